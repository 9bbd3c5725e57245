//! Progress of long commands, where the user looks: a bar on a terminal; elsewhere (`nohup`, a
//! batch job, a pipe) a line on stderr every few seconds and at every change of phase, with the
//! elapsed time, the phase, its percentage, the estimated time left and, for counted work, the
//! count — so the log of a background run is never silent; nothing with `--quiet`.
//!
//! The interval of the lines is `PDAMP_PROGRESS_INTERVAL_S` seconds (default 5).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

static QUIET: AtomicBool = AtomicBool::new(false);

/// `--quiet`: no progress at all.
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

struct State {
    phase: String,
    phase_start: Instant,
    last_line: Option<Instant>,
    fraction: f64,
}

/// The progress of one command (shareable between threads).
pub struct Progress {
    bar: Option<ProgressBar>,
    lines: bool,
    interval: Duration,
    start: Instant,
    state: Mutex<State>,
}

impl Progress {
    /// Progress on stderr: a bar on a terminal, lines otherwise, nothing with `--quiet`.
    pub fn new() -> Self {
        let quiet = QUIET.load(Ordering::Relaxed);
        let tty = std::io::stderr().is_terminal();
        let bar = (!quiet && tty).then(|| {
            let b = ProgressBar::new(1000);
            b.set_style(
                ProgressStyle::with_template(
                    "{msg:>9} [{elapsed_precise}] {wide_bar} {percent:>3}% eta {eta}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b
        });
        let interval = std::env::var("PDAMP_PROGRESS_INTERVAL_S")
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .filter(|s| s.is_finite() && *s >= 0.0)
            .unwrap_or(5.0);
        let now = Instant::now();
        Self {
            bar,
            lines: !quiet && !tty,
            interval: Duration::from_secs_f64(interval),
            start: now,
            state: Mutex::new(State {
                phase: String::new(),
                phase_start: now,
                last_line: None,
                fraction: 0.0,
            }),
        }
    }

    /// `fraction` (0–1) of `phase` is done.
    pub fn set(&self, phase: &str, fraction: f64) {
        self.update(phase, fraction, None);
    }

    /// `done` of `total` items of `phase` are done (e.g. the points of a field).
    pub fn count(&self, phase: &str, done: usize, total: usize) {
        let f = if total == 0 {
            1.0
        } else {
            done as f64 / total as f64
        };
        self.update(phase, f, Some((done, total)));
    }

    fn update(&self, phase: &str, fraction: f64, count: Option<(usize, usize)>) {
        let fraction = if fraction.is_finite() {
            fraction.clamp(0.0, 1.0)
        } else {
            0.0
        };
        if let Some(b) = &self.bar {
            b.set_message(phase.to_string());
            b.set_position((fraction * 1000.0) as u64);
        }
        if !self.lines {
            return;
        }
        let Ok(mut s) = self.state.lock() else { return };
        let now = Instant::now();
        let new_phase = s.phase != phase;
        if new_phase {
            s.phase = phase.to_string();
            s.phase_start = now;
        }
        s.fraction = fraction;
        let due = s
            .last_line
            .is_none_or(|t| now.duration_since(t) >= self.interval);
        let ends = fraction >= 1.0 && !new_phase;
        if !(new_phase || due || ends) {
            return;
        }
        s.last_line = Some(now);
        let in_phase = now.duration_since(s.phase_start).as_secs_f64();
        let eta = if fraction > 0.0 && fraction < 1.0 && in_phase > 0.0 {
            format!("  eta {}", human(in_phase * (1.0 - fraction) / fraction))
        } else {
            String::new()
        };
        let count = count.map_or(String::new(), |(d, t)| format!("  {d}/{t}"));
        eprintln!(
            "[{:>9.1} s] {phase} {:5.1} %{count}{eta}",
            now.duration_since(self.start).as_secs_f64(),
            100.0 * fraction
        );
    }

    /// Removes the bar (lines need no clean-up).
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

impl Default for Progress {
    fn default() -> Self {
        Self::new()
    }
}

/// A duration for people: `42 s`, `7.5 min`, `3.2 h`, `2.1 d`.
fn human(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else if s < 172_800.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} d", s / 86_400.0)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn durations_for_people() {
        assert_eq!(super::human(42.0), "42 s");
        assert_eq!(super::human(450.0), "7.5 min");
        assert_eq!(super::human(3.2 * 3600.0), "3.2 h");
        assert_eq!(super::human(2.1 * 86_400.0), "2.1 d");
    }
}
