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
/// Its `cancel` token is the run's stop request (fresh for every call, so a stopped run leaves
/// nothing behind for the next).
#[derive(Default)]
pub(crate) struct Progress {
    latest: Mutex<Option<(String, f64)>>,
    /// Cancelled on Ctrl-C or an exception of the callback; the work hands it to the library.
    pub(crate) cancel: pdamp_dem::time_loop::CancelToken,
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

/// An error of library work run from Python: any library error, kept as its text, which
/// becomes the message of the `RuntimeError` raised in Python. Every error that prints itself
/// converts into it, so the work can use `?` on the errors of all pdamp crates.
#[derive(Debug)]
pub(crate) struct LibraryError {
    /// The library's message.
    message: String,
}

impl<E: std::fmt::Display> From<E> for LibraryError {
    fn from(e: E) -> Self {
        Self {
            message: e.to_string(),
        }
    }
}

impl From<LibraryError> for PyErr {
    fn from(e: LibraryError) -> PyErr {
        PyRuntimeError::new_err(e.message)
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
/// (KeyboardInterrupt), or an exception raised by the callback, cancels the run's token
/// ([`Progress::cancel`], which the work hands to the library), waits for the run to stop at its
/// next check and raises the exception; the next call gets a fresh token.
pub(crate) fn detached<T: Send>(
    py: Python<'_>,
    pool: &rayon::ThreadPool,
    callback: Option<&Bound<'_, PyAny>>,
    f: impl FnOnce(&Progress) -> Result<T, LibraryError> + Send,
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
                    progress.cancel.cancel();
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
        return Err(e);
    }
    if let Some(cb) = callback {
        // The last word: the run's final state (or 100 % of its last phase).
        if let Some((phase, fraction)) = progress.take() {
            cb.call1((phase, fraction))?;
        }
    }
    match r {
        Ok(r) => r.map_err(PyErr::from),
        Err(_) => Err(PyRuntimeError::new_err("the simulation panicked")),
    }
}

/// Runs a short piece of work (a few steps of a [`crate::world::PyWorld`]) on `pool` with the
/// GIL released but without a watcher thread, then checks Python's signals: the cost of a call
/// stays at a few microseconds, and a Python loop around it stays interruptible.
pub(crate) fn detached_short<T: Send>(
    py: Python<'_>,
    pool: &rayon::ThreadPool,
    f: impl FnOnce() -> Result<T, LibraryError> + Send,
) -> PyResult<T> {
    let r = py.detach(|| pool.install(f));
    py.check_signals()?;
    r.map_err(PyErr::from)
}

/// The threads of a [`crate::world::PyWorld`]. Where it can, the Python thread that builds the
/// world becomes worker 0 of its pool (rayon's `use_current_thread`; one such pool per process,
/// shared by the worlds of that thread and thread count): a step called from Python then runs
/// on the calling thread without handing work to a sleeping worker and waiting for it to come
/// back (≈ 20 µs per call on a 2-core machine, 15 % of a 2 000-sphere step), and Ctrl-C and
/// progress are served from inside the loop. Calls from other threads use a pool of the
/// world's own.
pub(crate) struct WorldPool {
    caller: Option<(std::thread::ThreadId, std::sync::Arc<rayon::ThreadPool>)>,
    threads: Option<usize>,
    own: std::sync::OnceLock<rayon::ThreadPool>,
}

/// The pool whose worker 0 is a Python thread (see [`WorldPool`]).
type CallerPool = (
    std::thread::ThreadId,
    usize,
    std::sync::Arc<rayon::ThreadPool>,
);
static CALLER_POOL: Mutex<Option<CallerPool>> = Mutex::new(None);

impl WorldPool {
    /// The pool for a world built on this thread with `threads` workers (all cores: `None`).
    pub(crate) fn new(threads: Option<usize>) -> Self {
        let n = threads.filter(|&n| n > 0).unwrap_or_else(|| {
            std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
        });
        let me = std::thread::current().id();
        let mut caller = None;
        if let Ok(mut g) = CALLER_POOL.lock() {
            match &*g {
                Some((id, k, p)) if *id == me && *k == n => caller = Some((me, p.clone())),
                Some(_) => {}
                None => {
                    if let Ok(p) = rayon::ThreadPoolBuilder::new()
                        .num_threads(n)
                        .use_current_thread()
                        .build()
                    {
                        let p = std::sync::Arc::new(p);
                        *g = Some((me, n, p.clone()));
                        caller = Some((me, p));
                    }
                }
            }
        }
        Self {
            caller,
            threads: Some(n),
            own: std::sync::OnceLock::new(),
        }
    }

    /// The caller pool, when called from its thread.
    fn on_caller(&self) -> Option<&rayon::ThreadPool> {
        self.caller
            .as_ref()
            .filter(|(id, _)| *id == std::thread::current().id())
            .map(|(_, p)| p.as_ref())
    }

    fn own(&self) -> PyResult<&rayon::ThreadPool> {
        if let Some(p) = self.own.get() {
            return Ok(p);
        }
        let p = pool(self.threads)?;
        Ok(self.own.get_or_init(|| p))
    }

    /// Runs world work with the GIL released. `work` gets `poll(phase, fraction)`, to be called
    /// regularly (every step is fine: it costs a clock read); it returns true when the work must
    /// stop (Ctrl-C, or an exception from `callback`), which is then raised. After a successful
    /// run `callback(final_phase, 1.0)` is called. `short` work (a few steps) from a thread
    /// without a caller pool runs without a watcher thread.
    pub(crate) fn run<T: Send>(
        &self,
        py: Python<'_>,
        callback: Option<&Bound<'_, PyAny>>,
        final_phase: &str,
        short: bool,
        work: impl FnOnce(&mut dyn FnMut(&str, f64) -> bool) -> Result<T, LibraryError> + Send,
    ) -> PyResult<T> {
        let r = if let Some(pool) = self.on_caller() {
            let cb: Option<Py<PyAny>> = callback.map(|c| c.clone().unbind());
            let mut raised: Option<PyErr> = None;
            let mut last = std::time::Instant::now();
            let r = py.detach(|| {
                pool.install(|| {
                    let mut poll = |phase: &str, fraction: f64| -> bool {
                        if raised.is_some() {
                            return true;
                        }
                        if last.elapsed() < POLL {
                            return false;
                        }
                        last = std::time::Instant::now();
                        Python::attach(|py| {
                            let delivered = match &cb {
                                Some(c) => c.call1(py, (phase, fraction)).map(|_| ()),
                                None => Ok(()),
                            };
                            if let Err(e) = delivered.and_then(|()| py.check_signals()) {
                                raised = Some(e);
                            }
                        });
                        raised.is_some()
                    };
                    work(&mut poll)
                })
            });
            if let Some(e) = raised {
                return Err(e);
            }
            py.check_signals()?;
            r.map_err(PyErr::from)
        } else if short && callback.is_none() {
            let pool = self.own()?;
            detached_short(py, pool, || {
                // (Nothing watches a short run: Ctrl-C is seen right after it.)
                work(&mut |_, _| false)
            })
        } else {
            let pool = self.own()?;
            detached(py, pool, callback, |p: &Progress| {
                work(&mut |phase, f| {
                    p.set(phase, f);
                    p.cancel.is_cancelled()
                })
            })
        }?;
        if let Some(cb) = callback {
            cb.call1((final_phase, 1.0))?;
        }
        Ok(r)
    }
}
