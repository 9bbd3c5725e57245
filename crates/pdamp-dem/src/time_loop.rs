//! The time loop every driver runs on: a plain run, a damper point, a structure coupled to
//! DEM beds, the DEM–FEM coupling of a powder cavity, and the preparations before them (drop-down,
//! settling). It owns what they all need besides the physics of a step:
//! * **cancellation** — a [`CancelToken`] handed in by the caller (the CLI's Ctrl-C/SIGTERM
//!   handler, a Python session, a test); no process-wide flag;
//! * **checkpoints** — a wall-clock [`CheckpointTimer`]; [`LoopControl::poll`] says after each
//!   step whether to write one and whether to stop after it;
//! * the loop itself — [`run`] steps a [`LoopEvent`] handler until it says
//!   [`Flow::Finished`], writes checkpoints when due and stops on cancellation after one.
//!
//! A [`World`](crate::World) steps through [`World::run_controlled`](crate::World::run_controlled),
//! which is [`run`] with the world's shortened last step and deferred half kicks.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// A request to stop, shared between whoever asks (a signal handler, another thread) and the
/// loops that honour it. Cloning shares the request; a new token is never cancelled.
///
/// Loops that can stop cleanly (write a checkpoint, then return an "interrupted" error)
/// [`arm`](CancelToken::arm) the token while they run, so that a signal handler can tell a
/// clean stop from one that has to end the process ([`CancelToken::is_armed`]).
#[derive(Debug, Clone, Default)]
pub struct CancelToken(Arc<CancelState>);

#[derive(Debug, Default)]
struct CancelState {
    requested: AtomicBool,
    armed: AtomicUsize,
}

impl CancelToken {
    /// A token nobody has cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the loops holding this token to write a checkpoint and stop (async-signal-safe:
    /// one atomic store).
    pub fn cancel(&self) {
        self.0.requested.store(true, Ordering::SeqCst);
    }

    /// True once [`CancelToken::cancel`] was called (and not [`reset`](CancelToken::reset)).
    pub fn is_cancelled(&self) -> bool {
        self.0.requested.load(Ordering::Relaxed)
    }

    /// Withdraws a request once the stopped run has returned, so that the next run with the
    /// same token (a Python session after Ctrl-C) is not stopped at once.
    pub fn reset(&self) {
        self.0.requested.store(false, Ordering::SeqCst);
    }

    /// Marks a loop that stops cleanly on [`CancelToken::cancel`] as running, until the
    /// returned guard is dropped.
    pub fn arm(&self) -> Armed {
        self.0.armed.fetch_add(1, Ordering::SeqCst);
        Armed(self.clone())
    }

    /// True while a loop holding this token would stop cleanly on a request.
    pub fn is_armed(&self) -> bool {
        self.0.armed.load(Ordering::SeqCst) > 0
    }
}

/// Two tokens are equal when they share one request (clones of each other).
impl PartialEq for CancelToken {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// While alive, a loop that stops cleanly holds the token ([`CancelToken::arm`]).
#[derive(Debug)]
#[must_use = "the loop is armed only while the guard lives"]
pub struct Armed(CancelToken);

impl Drop for Armed {
    fn drop(&mut self) {
        self.0.0.armed.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Wall-clock cadence of checkpoints: due every `interval_s` seconds (looked at every 64th
/// call, so that a loop may ask after every step).
#[derive(Debug, Clone)]
pub struct CheckpointTimer {
    interval: std::time::Duration,
    last: std::time::Instant,
    calls: u32,
}

impl CheckpointTimer {
    /// A timer firing every `interval_s` seconds of wall-clock time (≤ 0: never).
    pub fn new(interval_s: f64) -> Self {
        Self {
            // (An interval beyond what a Duration holds, infinity included, means never.)
            interval: if interval_s > 0.0 && interval_s < 1e15 {
                std::time::Duration::from_secs_f64(interval_s)
            } else {
                std::time::Duration::MAX
            },
            last: std::time::Instant::now(),
            calls: 0,
        }
    }

    /// True if a checkpoint is due now (then the timer restarts).
    pub fn due(&mut self) -> bool {
        self.calls = self.calls.wrapping_add(1);
        if !self.calls.is_multiple_of(64) || self.interval == std::time::Duration::MAX {
            return false;
        }
        if self.last.elapsed() >= self.interval {
            self.last = std::time::Instant::now();
            true
        } else {
            false
        }
    }
}

/// What a loop does after a step ([`LoopControl::poll`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Poll {
    /// Go on.
    Continue,
    /// Write a checkpoint, then go on.
    Checkpoint,
    /// Cancelled: write a checkpoint (where the loop keeps them), then stop.
    Stop,
}

/// Cancellation and checkpoint cadence of one run: the token it honours and its timer.
#[derive(Debug, Clone)]
pub struct LoopControl {
    /// The stop request the run honours.
    pub cancel: CancelToken,
    /// When the next checkpoint is due.
    pub timer: CheckpointTimer,
}

impl LoopControl {
    /// Checkpoints every `checkpoint_interval_s` of wall-clock time (≤ 0: only on a stop
    /// request), stopping on `cancel`.
    pub fn new(cancel: &CancelToken, checkpoint_interval_s: f64) -> Self {
        Self {
            cancel: cancel.clone(),
            timer: CheckpointTimer::new(checkpoint_interval_s),
        }
    }

    /// After a step: stop (after a checkpoint) on a request, or write a checkpoint when due.
    pub fn poll(&mut self) -> Poll {
        if self.cancel.is_cancelled() {
            Poll::Stop
        } else if self.timer.due() {
            Poll::Checkpoint
        } else {
            Poll::Continue
        }
    }

    /// The checkpoint protocol of a loop body in one call: on a due checkpoint or a stop
    /// request calls `save`; returns `Break` when the loop must stop (cancelled).
    pub fn checkpoint_or_stop<E>(
        &mut self,
        save: impl FnOnce() -> Result<(), E>,
    ) -> Result<std::ops::ControlFlow<()>, E> {
        match self.poll() {
            Poll::Continue => Ok(std::ops::ControlFlow::Continue(())),
            Poll::Checkpoint => save().map(|()| std::ops::ControlFlow::Continue(())),
            Poll::Stop => save().map(|()| std::ops::ControlFlow::Break(())),
        }
    }
}

/// What [`run`] asks of its handler.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopEvent {
    /// Take one step (and observe it).
    Step,
    /// Write a checkpoint of the state after the last step.
    Checkpoint,
}

/// The handler's answer to [`LoopEvent::Step`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Step on.
    Continue,
    /// The run reached its end.
    Finished,
    /// An observer ended the run early (e.g. converged).
    Break,
}

/// How [`run`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopEnd {
    /// The handler said [`Flow::Finished`].
    Finished,
    /// The handler said [`Flow::Break`].
    Broken,
    /// Cancelled; the checkpoint after the last step was written.
    Cancelled,
}

/// The time loop: asks `on` for a [`LoopEvent::Step`] until it answers
/// [`Flow::Finished`] or [`Flow::Break`]; after every step that goes on, asks
/// `control` ([`LoopControl::poll`]) and has `on` write a [`LoopEvent::Checkpoint`] when one is
/// due or the run is cancelled, stopping after it in the latter case. The first error of `on`
/// ends the loop. (`on` answers a `Checkpoint` event with `Flow::Continue`.)
pub fn run<E>(
    control: &mut LoopControl,
    mut on: impl FnMut(LoopEvent) -> Result<Flow, E>,
) -> Result<LoopEnd, E> {
    loop {
        match on(LoopEvent::Step)? {
            Flow::Continue => {}
            Flow::Finished => return Ok(LoopEnd::Finished),
            Flow::Break => return Ok(LoopEnd::Broken),
        }
        match control.poll() {
            Poll::Continue => {}
            Poll::Checkpoint => {
                on(LoopEvent::Checkpoint)?;
            }
            Poll::Stop => {
                on(LoopEvent::Checkpoint)?;
                return Ok(LoopEnd::Cancelled);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A counter stepped to 10 with a checkpoint record.
    fn count_to_ten(control: &mut LoopControl, cancel_at: Option<u32>) -> (LoopEnd, u32, Vec<u32>) {
        let (mut n, mut saved) = (0u32, Vec::new());
        let token = control.cancel.clone();
        let end = run::<()>(control, |ev| match ev {
            LoopEvent::Step => {
                n += 1;
                if Some(n) == cancel_at {
                    token.cancel();
                }
                Ok(if n == 10 {
                    Flow::Finished
                } else {
                    Flow::Continue
                })
            }
            LoopEvent::Checkpoint => {
                saved.push(n);
                Ok(Flow::Continue)
            }
        })
        .unwrap();
        (end, n, saved)
    }

    #[test]
    fn a_loop_runs_to_its_end_without_checkpoints_when_none_are_due() {
        let mut c = LoopControl::new(&CancelToken::new(), 0.0);
        assert_eq!(count_to_ten(&mut c, None), (LoopEnd::Finished, 10, vec![]));
    }

    #[test]
    fn cancelling_writes_one_checkpoint_after_the_step_and_stops() {
        let token = CancelToken::new();
        let mut c = LoopControl::new(&token, 0.0);
        assert_eq!(
            count_to_ten(&mut c, Some(4)),
            (LoopEnd::Cancelled, 4, vec![4])
        );
        assert!(token.is_cancelled());
        token.reset();
        assert!(!token.is_cancelled());
        // A clone shares the request.
        let other = token.clone();
        other.cancel();
        assert!(token.is_cancelled());
    }

    #[test]
    fn a_checkpoint_is_written_when_the_timer_is_due() {
        let mut c = LoopControl::new(&CancelToken::new(), 1e-9);
        std::thread::sleep(std::time::Duration::from_millis(2));
        let (end, n, saved) = count_to_ten(&mut c, None);
        assert_eq!((end, n), (LoopEnd::Finished, 10));
        assert!(saved.is_empty(), "the timer looks only at every 64th call");
        let mut timer = CheckpointTimer::new(1e-9);
        std::thread::sleep(std::time::Duration::from_millis(2));
        let due: Vec<bool> = (0..64).map(|_| timer.due()).collect();
        assert_eq!(due.iter().filter(|d| **d).count(), 1);
        assert!(due[63]);
        let mut never = CheckpointTimer::new(0.0);
        assert!((0..256).all(|_| !never.due()));
    }

    #[test]
    fn arming_is_counted_per_loop() {
        let token = CancelToken::new();
        assert!(!token.is_armed());
        let a = token.arm();
        let b = token.clone().arm();
        drop(a);
        assert!(token.is_armed());
        drop(b);
        assert!(!token.is_armed());
    }

    #[test]
    fn checkpoint_or_stop_saves_and_breaks_only_when_cancelled() {
        let token = CancelToken::new();
        let mut c = LoopControl::new(&token, 0.0);
        let mut saves = 0;
        let f = c.checkpoint_or_stop::<()>(|| {
            saves += 1;
            Ok(())
        });
        assert_eq!((f, saves), (Ok(std::ops::ControlFlow::Continue(())), 0));
        token.cancel();
        let f = c.checkpoint_or_stop::<()>(|| {
            saves += 1;
            Ok(())
        });
        assert_eq!((f, saves), (Ok(std::ops::ControlFlow::Break(())), 1));
        let f = c.checkpoint_or_stop(|| Err("disk full"));
        assert_eq!(f, Err("disk full"));
    }
}
