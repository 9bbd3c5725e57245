//! Running library work from Python: on a rayon pool with the GIL released, Ctrl-C (a
//! notebook's stop button) turned into a clean stop, and progress handed to a Python callback
//! from the calling thread (the workers never take the GIL).

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::Mutex;
use std::time::Duration;

/// How often the calling thread wakes to look for signals and progress.
const POLL: Duration = Duration::from_millis(50);

/// Progress of a run as the library reports it (`phase`, fraction done in [0, 1]); the workers
/// write it, the calling thread hands the latest value to the Python callback.
#[derive(Default)]
pub(crate) struct Progress {
    latest: Mutex<Option<(String, f64)>>,
}

impl Progress {
    /// Records the latest phase and fraction (cheap; called from the simulation).
    pub(crate) fn set(&self, phase: &str, fraction: f64) {
        if let Ok(mut l) = self.latest.lock() {
            match l.as_mut() {
                Some((p, f)) if p == phase => *f = fraction,
                _ => *l = Some((phase.to_string(), fraction)),
            }
        }
    }

    fn take(&self) -> Option<(String, f64)> {
        self.latest.lock().ok().and_then(|mut l| l.take())
    }
}

/// A rayon pool of `threads` workers (all cores when `None` or 0).
pub(crate) fn pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// Runs `f` on `pool` with the GIL released; an error of the library becomes a
/// `RuntimeError`. The calling thread wakes every 50 ms (or when `f` ends): it hands the
/// latest progress to `callback(phase, fraction)` and checks Python's signals. Ctrl-C
/// (KeyboardInterrupt), or an exception raised by the callback, asks the run to stop at its next
/// check ([`pdamp_io::checkpoint::request_stop`]), waits for it and raises the exception; the
/// stop request is withdrawn afterwards, so the next run starts normally.
pub(crate) fn detached<T: Send>(
    py: Python<'_>,
    pool: &rayon::ThreadPool,
    callback: Option<&Bound<'_, PyAny>>,
    f: impl FnOnce(&Progress) -> Result<T, String> + Send,
) -> PyResult<T> {
    let progress = Progress::default();
    let mut raised: Option<PyErr> = None;
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    let rx = Mutex::new(rx);
    let r = std::thread::scope(|s| {
        let progress = &progress;
        let run = s.spawn(move || {
            let r = pool.install(|| f(progress));
            let _ = tx.send(());
            r
        });
        loop {
            let done = py.detach(|| rx.lock().is_ok_and(|r| r.recv_timeout(POLL).is_ok()));
            if raised.is_none() {
                let delivered = match (callback, progress.take()) {
                    (Some(cb), Some((phase, fraction))) => cb.call1((phase, fraction)).map(|_| ()),
                    _ => Ok(()),
                };
                if let Err(e) = delivered.and_then(|()| py.check_signals()) {
                    pdamp_io::checkpoint::request_stop();
                    raised = Some(e);
                }
            }
            if done || run.is_finished() {
                break;
            }
        }
        run.join()
    });
    if let Some(e) = raised {
        pdamp_io::checkpoint::clear_stop();
        return Err(e);
    }
    if let Some(cb) = callback {
        // The last word: the run's final state (or 100 % of its last phase).
        if let Some((phase, fraction)) = progress.take() {
            cb.call1((phase, fraction))?;
        }
    }
    match r {
        Ok(r) => r.map_err(PyRuntimeError::new_err),
        Err(_) => Err(PyRuntimeError::new_err("the simulation panicked")),
    }
}

/// Runs a short piece of work (a few steps of a [`crate::world::PyWorld`]) on `pool` with the
/// GIL released but without a watcher thread, then checks Python's signals: the cost of a call
/// stays at a few microseconds, and a Python loop around it stays interruptible.
pub(crate) fn detached_short<T: Send>(
    py: Python<'_>,
    pool: &rayon::ThreadPool,
    f: impl FnOnce() -> Result<T, String> + Send,
) -> PyResult<T> {
    let r = py.detach(|| pool.install(f));
    py.check_signals()?;
    r.map_err(PyRuntimeError::new_err)
}
