//! Work and memory of a scenario, estimated before anything is allocated, and the limits a
//! run must stay within unless the user insists (`--force`).
//!
//! The figures are deliberately simple and stated with their basis, so that a user can check
//! them: memory ≈ [`BYTES_PER_PARTICLE`] per particle (measured: 1.45 kB per sphere of a settled
//! shaken box with its neighbour list and contacts, `pdamp bench` at 2·10⁴ and 2·10⁵ spheres),
//! time ≈ particle-steps / ([`PARTICLE_STEPS_PER_S_PER_THREAD`] × threads), outputs ≈ rows
//! and frames times their size.

use super::{PlacementMethod, Scenario};
use serde::Serialize;
use std::sync::atomic::{AtomicBool, Ordering};

/// Memory per particle, bytes (see the module documentation).
pub const BYTES_PER_PARTICLE: f64 = 1500.0;
/// Particle-steps per second and thread the estimate assumes (the CPU engine reaches 5–10·10⁶
/// on one core of the development machines).
pub const PARTICLE_STEPS_PER_S_PER_THREAD: f64 = 5e6;
/// Bytes per particle of one VTK frame (ASCII VTU).
pub const VTK_BYTES_PER_PARTICLE: f64 = 230.0;
/// Bytes of one row of `energy.csv`.
pub const ENERGY_ROW_BYTES: f64 = 250.0;
/// Most particles of one world (particle ids are 32-bit).
pub const MAX_PARTICLES: usize = u32::MAX as usize;
/// Most VTK frames of a run (without `--force`).
pub const MAX_VTK_FRAMES: f64 = 20_000.0;
/// Most rows of `energy.csv` (without `--force`).
pub const MAX_ENERGY_ROWS: f64 = 1e7;
/// Most bytes of output of a run (without `--force`).
pub const MAX_OUTPUT_BYTES: f64 = 50e9;
/// Longest estimated run time, s (without `--force`): 30 days.
pub const MAX_RUN_TIME_S: f64 = 30.0 * 86_400.0;

static FORCE: AtomicBool = AtomicBool::new(false);

/// Lets runs go beyond the soft limits (the command line's `--force`). Memory beyond what the
/// machine has in all, and more than [`MAX_PARTICLES`], are refused regardless.
pub fn set_force(force: bool) {
    FORCE.store(force, Ordering::Relaxed);
}

/// Whether `--force` was given.
pub fn forced() -> bool {
    FORCE.load(Ordering::Relaxed)
}

/// What a scenario will cost.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    /// Particles of one world (beds read from files count as 0 here: their size is bounded by
    /// the file).
    pub particles: usize,
    /// Memory of one world, bytes.
    pub memory_bytes: f64,
    /// Simulated time of the whole command, s (settling, run, every point and packing).
    pub simulated_time_s: f64,
    /// Time steps of the whole command.
    pub steps: f64,
    /// Particle-steps of the whole command.
    pub particle_steps: f64,
    /// Estimated wall-clock time on `threads` threads, s.
    pub wall_time_s: f64,
    /// Threads the estimate assumes.
    pub threads: usize,
    /// Rows of `energy.csv` (plain runs).
    pub energy_rows: f64,
    /// VTK frames (plain runs: over the run; damper points: over all points).
    pub vtk_frames: f64,
    /// Bytes of output, roughly.
    pub output_bytes: f64,
}

impl Estimate {
    /// The estimate of running `sc` once (a plain run or a damper point), or as a field of
    /// `points` points when `points > 1` (each with its packings), on `threads` threads.
    pub fn of(sc: &Scenario, points: usize, threads: usize) -> Self {
        let threads = threads.max(1);
        let particles = sc
            .particles
            .iter()
            .filter(|g| g.placement.method != PlacementMethod::File)
            .map(|g| g.resolved_count().unwrap_or(0))
            .fold(0usize, usize::saturating_add);
        let dt = sc.simulation.time_step_s;
        let settle = sc.settle.as_ref().map_or(0.0, |s| {
            s.max_duration_s + s.turn_max_duration_s.unwrap_or(0.0)
        });
        // Samples of the driving force, velocity and time kept over the evaluated cycles of
        // every point running at once (8 bytes each).
        let mut sample_bytes = 0.0;
        let (simulated, energy_rows, vtk_frames) = match &sc.damper {
            Some(d) => {
                // Mean period of the points: the single point's, or over the field's frequencies.
                let period = match (&sc.fields, d.frequency_hz) {
                    (Some(f), _) if points > 1 => {
                        let v = f.frequencies_hz.values();
                        v.iter().map(|f| 1.0 / f).sum::<f64>() / v.len().max(1) as f64
                    }
                    (_, Some(f)) => 1.0 / f,
                    (Some(_), None) => 1.0 / lowest_field_frequency(sc),
                    (None, None) => 1.0,
                };
                let longest =
                    1.0 / lowest_field_frequency(sc).min(d.frequency_hz.unwrap_or(f64::INFINITY));
                let evaluated = f64::from(d.cycles.saturating_sub(d.transient_cycles));
                let running = points.clamp(1, threads.max(1)) as f64;
                sample_bytes = 3.0 * 8.0 * evaluated * longest / dt * running;
                let point = f64::from(d.cycles) * period;
                let packings = d.packings.max(1) as f64;
                let n = points.max(1) as f64;
                // Only a single point (`pdamp run`) writes VTK frames; field points do not.
                let frames = if points > 1 {
                    0.0
                } else {
                    f64::from(d.motion_output.vtk_frames_per_cycle) * packings
                };
                (packings * (settle + n * point), 0.0, frames)
            }
            None => {
                let t = sc.simulation.duration_s;
                let rows = t / sc.output.energy_interval_s + 1.0;
                let frames = if sc.output.vtk_interval_s > 0.0 {
                    t / sc.output.vtk_interval_s + 1.0
                } else {
                    0.0
                };
                (settle + t, rows, frames)
            }
        };
        let steps = simulated / dt;
        let particle_steps = steps * particles as f64;
        Self {
            particles,
            memory_bytes: particles as f64 * BYTES_PER_PARTICLE + sample_bytes,
            simulated_time_s: simulated,
            steps,
            particle_steps,
            wall_time_s: particle_steps / (PARTICLE_STEPS_PER_S_PER_THREAD * threads as f64),
            threads,
            energy_rows,
            vtk_frames,
            output_bytes: energy_rows * ENERGY_ROW_BYTES
                + vtk_frames * particles as f64 * VTK_BYTES_PER_PARTICLE,
        }
    }

    /// Refuses what cannot or should not run: more particles than a world holds or memory
    /// beyond the machine (always), and without [`set_force`] also memory beyond what is
    /// available now, more than [`MAX_VTK_FRAMES`] frames, [`MAX_ENERGY_ROWS`] rows,
    /// [`MAX_OUTPUT_BYTES`] of output or [`MAX_RUN_TIME_S`] of estimated run time. The message
    /// gives the figures, the keys that set them and `--force`.
    pub fn check(&self) -> Result<(), pdamp_dem::ParameterError> {
        let gb = |b: f64| b / 1e9;
        if self.particles > MAX_PARTICLES {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "particles: {} particles exceed the {MAX_PARTICLES} a world can hold",
                self.particles
            )));
        }
        let (total, available) = memory_of_machine();
        if let Some(total) = total
            && self.memory_bytes > total
        {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "particles: the run needs about {:.1} GB of memory ({} particles × \
                 {BYTES_PER_PARTICLE} bytes, plus the force and velocity samples of the \
                 evaluated cycles of damper points); this process may use {:.1} GB in all. Use \
                 fewer or larger particles, or fewer cycles at low frequencies",
                gb(self.memory_bytes),
                self.particles,
                gb(total)
            )));
        }
        if forced() {
            return Ok(());
        }
        let force = "(--force runs it anyway)";
        if let Some(avail) = available
            && self.memory_bytes > 0.9 * avail
        {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "particles: the run needs about {:.1} GB of memory ({} particles, plus the \
                 samples of damper points), {:.1} GB are available now {force}",
                gb(self.memory_bytes),
                self.particles,
                gb(avail)
            )));
        }
        if self.vtk_frames > MAX_VTK_FRAMES {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "output: the run would write {:.0} VTK frames (limit {MAX_VTK_FRAMES}); raise \
                 output.vtk_interval_s (or lower damper.motion_output.vtk_frames_per_cycle) \
                 {force}",
                self.vtk_frames
            )));
        }
        if self.energy_rows > MAX_ENERGY_ROWS {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "output.energy_interval_s: the run would write {:.3e} rows of energy.csv (limit \
                 {MAX_ENERGY_ROWS:e}); raise output.energy_interval_s {force}",
                self.energy_rows
            )));
        }
        if self.output_bytes > MAX_OUTPUT_BYTES {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "output: the run would write about {:.1} GB (limit {:.0} GB); raise \
                 output.vtk_interval_s or output.energy_interval_s {force}",
                gb(self.output_bytes),
                gb(MAX_OUTPUT_BYTES)
            )));
        }
        if self.wall_time_s > MAX_RUN_TIME_S {
            return Err(pdamp_dem::ParameterError::from_message(format!(
                "simulation: {:.3e} particle-steps ({} particles, {:.3e} steps of {:.3e} s over \
                 {:.3e} s simulated) would take about {:.0} days on {} threads (estimate at \
                 {PARTICLE_STEPS_PER_S_PER_THREAD:e} particle-steps/s per thread); shorten \
                 simulation.duration_s or the damper cycles, or check the time step {force}",
                self.particle_steps,
                self.particles,
                self.steps,
                self.simulated_time_s / self.steps.max(1.0),
                self.simulated_time_s,
                self.wall_time_s / 86_400.0,
                self.threads
            )));
        }
        Ok(())
    }
}

/// Lowest frequency of the scenario's field grid (infinite without a grid).
fn lowest_field_frequency(sc: &Scenario) -> f64 {
    use super::AxisSpec;
    match sc.fields.as_ref().map(|f| &f.frequencies_hz) {
        Some(AxisSpec::List(v)) => v.iter().copied().fold(f64::INFINITY, f64::min),
        Some(AxisSpec::Range { from, to, .. }) => from.min(*to),
        None => f64::INFINITY,
    }
    .max(1e-3)
}

/// Total and available memory of the machine, bytes (Linux `/proc/meminfo`; `None` elsewhere).
pub fn memory_of_machine() -> (Option<f64>, Option<f64>) {
    let Ok(text) = std::fs::read_to_string("/proc/meminfo") else {
        return (None, None);
    };
    let field = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .map(|kb| kb * 1024.0)
    };
    let (total, available) = (field("MemTotal:"), field("MemAvailable:"));
    // A limit on the address space (`ulimit -v`, a batch system's memory limit) caps both.
    let limit = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("Max address space"))
                .and_then(|l| l.split_whitespace().nth(3))
                .and_then(|v| v.parse::<f64>().ok())
        });
    match limit {
        Some(l) => (
            Some(total.map_or(l, |t| t.min(l))),
            Some(available.map_or(l, |a| a.min(l))),
        ),
        None => (total, available),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_follow_the_scenario_and_limits_name_the_key() {
        let sc = crate::examples::shaken_box(2000, 0.5);
        let e = Estimate::of(&sc, 1, 2);
        assert_eq!(e.particles, 2000);
        let settle = sc.settle.as_ref().unwrap().max_duration_s;
        assert!((e.simulated_time_s - (0.5 + settle)).abs() < 1e-12);
        assert!((e.steps - e.simulated_time_s / sc.simulation.time_step_s).abs() < 1e-6);
        assert!((e.memory_bytes - 2000.0 * BYTES_PER_PARTICLE).abs() < 1e-9);
        e.check().unwrap();
        let mut many = sc.clone();
        many.output.vtk_interval_s = many.simulation.time_step_s;
        let err = Estimate::of(&many, 1, 2).check().unwrap_err().to_string();
        assert!(
            err.contains("VTK frames") && err.contains("output.vtk_interval_s"),
            "{err}"
        );
        let mut long = sc.clone();
        long.simulation.duration_s = 1e9;
        let err = Estimate::of(&long, 1, 2).check().unwrap_err().to_string();
        assert!(err.contains("--force"), "{err}");
    }
}
