//! Effective fields [D Sect. 3.2.2, 8.1.1]: the damper evaluated on a grid of excitation
//! frequencies × amplitudes, each point an independent simulation from the same settled bed,
//! run in parallel and resumable (every finished point is stored at once and never recomputed).

use crate::DesignError;
use crate::damper::{Damper, PointResult};
use pdamp_scenario::schema::{AmplitudeAxis, FieldsSpec};
use std::path::{Path, PathBuf};
use std::sync::{Condvar, Mutex};

/// Particles per thread below which a second thread inside one simulation does not pay (the
/// per-step synchronisation costs more than the split work saves).
pub const MIN_PARTICLES_PER_THREAD: usize = 2000;

/// How the points of a field share the threads.
///
/// Rule: a point starts whenever a thread is idle and gets `ceil(idle / waiting)` threads
/// (`waiting`: points not started yet, itself included), but at most one per
/// [`MIN_PARTICLES_PER_THREAD`] particles of the bed. So points run in parallel, one thread
/// each, as long as at least as many points wait as threads are idle; when fewer points wait
/// than threads are idle (a grid smaller than the machine, a resumed run with a few points
/// left, the last points of a grid started together) large beds share the idle threads evenly
/// and use them inside the simulation (the DEM's own parallel loops). A point keeps its threads
/// until it ends; threads freed while the last points run stay idle. Points start longest first
/// (most time steps at most: lowest frequency), so the tail consists of the short ones. Results
/// do not depend on the split (the DEM is deterministic for any thread count).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThreadSplit {
    /// Threads in all (default: the current rayon pool's, i.e. `pdamp --threads`).
    pub threads: usize,
    /// A simulation gets k threads only with at least k × this many particles.
    pub min_particles_per_thread: usize,
}

impl Default for ThreadSplit {
    fn default() -> Self {
        Self {
            threads: rayon::current_num_threads(),
            min_particles_per_thread: MIN_PARTICLES_PER_THREAD,
        }
    }
}

impl ThreadSplit {
    /// Threads for a point of a bed of `particles` that starts while `idle` threads are idle
    /// and `waiting` points (this one included) are not started yet (≥ 1).
    pub fn threads_for_point(&self, idle: usize, waiting: usize, particles: usize) -> usize {
        let share = idle.div_ceil(waiting.max(1));
        let by_size = particles / self.min_particles_per_thread.max(1);
        share.min(by_size).max(1)
    }
}

/// Runs `run(k, threads)` for every `k` of `order`, in that order of starting, with the threads
/// shared as [`ThreadSplit`] says; `run` gets a rayon pool of `threads` threads installed.
fn run_split<R: Send>(
    order: &[usize],
    split: ThreadSplit,
    particles: usize,
    run: impl Fn(usize) -> R + Sync,
) -> Vec<(usize, R)> {
    struct State {
        idle: usize,
        next: usize,
    }
    let threads = split.threads.max(1);
    let state = Mutex::new(State {
        idle: threads,
        next: 0,
    });
    let freed = Condvar::new();
    let results = Mutex::new(Vec::with_capacity(order.len()));
    std::thread::scope(|s| {
        for _ in 0..threads.min(order.len()) {
            s.spawn(|| {
                loop {
                    let (k, t) = {
                        let mut st = state.lock().unwrap_or_else(|e| e.into_inner());
                        while st.next < order.len() && st.idle == 0 {
                            st = freed.wait(st).unwrap_or_else(|e| e.into_inner());
                        }
                        if st.next >= order.len() {
                            return;
                        }
                        let t = split.threads_for_point(st.idle, order.len() - st.next, particles);
                        st.idle -= t.min(st.idle);
                        st.next += 1;
                        (order[st.next - 1], t)
                    };
                    let r = match rayon::ThreadPoolBuilder::new().num_threads(t).build() {
                        Ok(pool) => pool.install(|| run(k)),
                        Err(_) => run(k),
                    };
                    results
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push((k, r));
                    state.lock().unwrap_or_else(|e| e.into_inner()).idle += t;
                    freed.notify_all();
                }
            });
        }
    });
    let mut results = results.into_inner().unwrap_or_else(|e| e.into_inner());
    results.sort_by_key(|(k, _)| *k);
    results
}

/// Columns of `fields.csv`: the required columns first, then diagnostics.
pub const FIELD_COLUMNS: [&str; 19] = [
    "frequency_hz",
    "amplitude_m",
    "acceleration_m_s2",
    "intensity",
    "dissipated_energy_per_cycle_j",
    "loss_factor",
    "effective_loss_factor",
    "effective_mass_ratio",
    "effective_moving_mass_re_kg",
    "effective_moving_mass_im_kg",
    "ledger_dissipated_per_cycle_j",
    "share_normal_pp",
    "share_normal_pw",
    "share_tangential_pp",
    "share_tangential_pw",
    "energy_closure_relative",
    "cycles_evaluated",
    "converged",
    "wall_time_s",
];

/// The grid of an effective field.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldGrid {
    /// Frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Which amplitude measure the second axis holds.
    pub amplitude_axis: AmplitudeAxis,
    /// Values of the second axis (m, m/s² or Γ).
    pub amplitude_values: Vec<f64>,
    /// Frequency axis is logarithmic.
    pub frequency_log: bool,
    /// Amplitude axis is logarithmic.
    pub amplitude_log: bool,
}

impl FieldGrid {
    /// Grid from the scenario's `[fields]` section.
    pub fn from_spec(spec: &FieldsSpec) -> Result<Self, DesignError> {
        let (axis, a) = spec.amplitude_axis().ok_or(DesignError::AmplitudeAxis)?;
        Ok(Self {
            frequencies_hz: spec.frequencies_hz.values(),
            amplitude_axis: axis,
            amplitude_values: a.values(),
            frequency_log: spec.frequencies_hz.is_log(),
            amplitude_log: a.is_log(),
        })
    }

    /// All points (frequency index, amplitude index, f, X), frequency-major.
    pub fn points(&self) -> Vec<(usize, usize, f64, f64)> {
        let mut out = Vec::new();
        for (i, &f) in self.frequencies_hz.iter().enumerate() {
            for (j, &a) in self.amplitude_values.iter().enumerate() {
                out.push((i, j, f, FieldsSpec::displacement(self.amplitude_axis, f, a)));
            }
        }
        out
    }

    /// Axis title of the amplitude axis with its unit.
    pub fn amplitude_title(&self) -> &'static str {
        match self.amplitude_axis {
            AmplitudeAxis::Displacement => "amplitude X (m)",
            AmplitudeAxis::Acceleration => "acceleration A (m/s²)",
            AmplitudeAxis::Intensity => "intensity Γ = A/g (-)",
        }
    }
}

/// One row of `fields.csv` for a point.
pub fn field_row(r: &PointResult) -> Vec<f64> {
    vec![
        r.frequency_hz,
        r.amplitude_m,
        r.acceleration_m_s2,
        r.intensity,
        r.dissipated_energy_per_cycle_j,
        r.loss_factor,
        r.effective_loss_factor,
        r.effective_mass_ratio,
        r.effective_moving_mass_re_kg,
        r.effective_moving_mass_im_kg,
        r.ledger_dissipated_per_cycle_j,
        r.share_normal_pp,
        r.share_normal_pw,
        r.share_tangential_pp,
        r.share_tangential_pw,
        r.energy_closure_relative,
        r.cycles_evaluated as f64,
        match r.converged {
            Some(true) => 1.0,
            Some(false) => 0.0,
            None => f64::NAN,
        },
        r.wall_time_s,
    ]
}

/// File of the finished point (frequency index `i`, amplitude index `j`) of the field in `dir`:
/// `dir/points/fIII_aJJJ.json`, written atomically when the point ends.
pub fn point_path(dir: &Path, i: usize, j: usize) -> PathBuf {
    dir.join("points").join(format!("f{i:03}_a{j:03}.json"))
}

/// File with the error of a point that failed, next to its slot: `dir/points/fIII_aJJJ.error.txt`
/// (removed when the point later succeeds).
pub fn point_error_path(dir: &Path, i: usize, j: usize) -> PathBuf {
    dir.join("points")
        .join(format!("f{i:03}_a{j:03}.error.txt"))
}

/// What the store holds for one point of a field.
#[derive(Debug, Clone)]
pub enum StoredPoint {
    /// Finished: its result.
    Done(Box<PointResult>),
    /// Failed: the error it left next to its slot.
    Failed(String),
    /// A point file that cannot be read or belongs to another excitation (a damaged or foreign
    /// file): the reason. It is recomputed like a missing point.
    Corrupt(String),
    /// Nothing stored yet.
    Missing,
}

/// Reads what the store in `dir` holds for grid point (`i`, `j`) at frequency `f`, amplitude `x`.
pub fn stored_point(dir: &Path, i: usize, j: usize, f: f64, x: f64) -> StoredPoint {
    let path = point_path(dir, i, j);
    match std::fs::read_to_string(&path) {
        Ok(text) => match serde_json::from_str::<PointResult>(&text) {
            Ok(r) => {
                let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
                if same(r.frequency_hz, f) && same(r.amplitude_m, x) {
                    StoredPoint::Done(Box::new(r))
                } else {
                    StoredPoint::Corrupt(format!(
                        "{} holds f = {} Hz, X = {:e} m instead of f = {f} Hz, X = {x:e} m",
                        path.display(),
                        r.frequency_hz,
                        r.amplitude_m
                    ))
                }
            }
            Err(e) => StoredPoint::Corrupt(format!("{} is damaged: {e}", path.display())),
        },
        Err(_) => match std::fs::read_to_string(point_error_path(dir, i, j)) {
            Ok(e) => StoredPoint::Failed(e.trim().to_string()),
            Err(_) => StoredPoint::Missing,
        },
    }
}

/// A stored point is reused only if it belongs to the same excitation.
fn load_point(dir: &Path, i: usize, j: usize, f: f64, x: f64) -> Option<PointResult> {
    match stored_point(dir, i, j, f, x) {
        StoredPoint::Done(r) => Some(*r),
        _ => None,
    }
}

/// Stores the outcome of point (`i`, `j`) in `dir`: the result (and the error file of an
/// earlier failure removed), or the error next to its slot. Interruptions are not stored.
/// Returns the outcome, or an `output:` error when the store cannot be written.
pub fn store_point(
    dir: &Path,
    i: usize,
    j: usize,
    r: Result<PointResult, DesignError>,
) -> Result<PointResult, DesignError> {
    match r {
        Ok(r) => {
            let json = serde_json::to_string_pretty(&r)?;
            let path = point_path(dir, i, j);
            pdamp_io::atomic::write_atomic(&path, json.as_bytes())
                .map_err(DesignError::write(path))?;
            let _ = std::fs::remove_file(point_error_path(dir, i, j));
            Ok(r)
        }
        Err(e) if e.is_output() || e.is_interrupted() => Err(e),
        Err(e) => {
            let path = point_error_path(dir, i, j);
            pdamp_io::atomic::write_atomic(&path, e.to_string().as_bytes())
                .map_err(DesignError::write(path))?;
            Err(e)
        }
    }
}

/// Outcome of [`run_fields`].
#[derive(Debug, Clone)]
pub struct FieldsOutcome {
    /// All points in grid order (frequency-major).
    /// Failed points have NaN results (grey on the maps) and are listed in `failed`.
    pub points: Vec<PointResult>,
    /// Points taken from an earlier, interrupted run.
    pub reused: usize,
    /// Points that failed (e.g. an unstable simulation): frequency, amplitude and the message.
    /// They are not stored, so a rerun tries them again.
    pub failed: Vec<(f64, f64, String)>,
    /// Span of the settled bed along the excitation direction (see
    /// [`crate::damper::Damper::bed_span_along_direction_m`]), m.
    pub bed_span_along_direction_m: [f64; 2],
}

/// A point result with every evaluated quantity NaN (a failed point).
fn failed_point(f: f64, x: f64) -> PointResult {
    let w = 2.0 * std::f64::consts::PI * f;
    let a = x * w * w;
    PointResult {
        frequency_hz: f,
        amplitude_m: x,
        acceleration_m_s2: a,
        intensity: a / pdamp_scenario::schema::STANDARD_GRAVITY_M_S2,
        velocity_amplitude_m_s: x * w,
        dissipated_energy_per_cycle_j: f64::NAN,
        loss_factor: f64::NAN,
        effective_loss_factor: f64::NAN,
        effective_mass_ratio: f64::NAN,
        effective_moving_mass_re_kg: f64::NAN,
        effective_moving_mass_im_kg: f64::NAN,
        ledger_dissipated_per_cycle_j: f64::NAN,
        ledger_wall_work_per_cycle_j: f64::NAN,
        share_normal_pp: f64::NAN,
        share_normal_pw: f64::NAN,
        share_tangential_pp: f64::NAN,
        share_tangential_pw: f64::NAN,
        energy_closure_relative: f64::NAN,
        cycles_evaluated: 0,
        converged: None,
        time_step_s: f64::NAN,
        steps: 0,
        wall_time_s: f64::NAN,
    }
}

/// Runs all grid points not yet stored in `out_dir/points/`, in parallel, then writes
/// `out_dir/fields.csv`. `on_point(done, total)` is called after every finished point.
/// Threads are shared as [`ThreadSplit::default`] says.
pub fn run_fields(
    damper: &Damper,
    grid: &FieldGrid,
    out_dir: &Path,
    on_point: impl Fn(usize, usize) + Sync,
) -> Result<FieldsOutcome, DesignError> {
    run_fields_with(damper, grid, out_dir, ThreadSplit::default(), on_point)
}

/// Where the points of a field run.
#[derive(Debug, Clone, Copy)]
pub enum PointEngine<'a> {
    /// On the CPU engine, points in parallel with the threads split as given.
    Cpu(ThreadSplit),
    /// On the GPU backend: the pending points in batches of worlds advanced together (up to
    /// [`GPU_BATCH_PARTICLES`] particles a batch).
    #[cfg(feature = "gpu")]
    Gpu(&'a pdamp_gpu::GpuDevice),
    /// Nothing runs: the field is collected from its store (a sweep's `collect`). Points that
    /// failed come out as NaN rows with their stored error; a point still missing (not run
    /// yet, running, or its file damaged) is an error that names how many and which.
    Stored,
    #[doc(hidden)]
    _Lifetime(std::marker::PhantomData<&'a ()>),
}

/// Largest number of particles of one GPU batch of field points (about 19 GB of device memory
/// at today's 4.35 GB per million particles).
pub const GPU_BATCH_PARTICLES: usize = 4_000_000;

/// [`run_fields`] with an explicit split of the threads between and inside the points.
pub fn run_fields_with(
    damper: &Damper,
    grid: &FieldGrid,
    out_dir: &Path,
    split: ThreadSplit,
    on_point: impl Fn(usize, usize) + Sync,
) -> Result<FieldsOutcome, DesignError> {
    run_fields_on(damper, grid, out_dir, PointEngine::Cpu(split), on_point)
}

/// [`run_fields`] on the CPU engine or the GPU backend.
pub fn run_fields_on(
    damper: &Damper,
    grid: &FieldGrid,
    out_dir: &Path,
    engine: PointEngine<'_>,
    on_point: impl Fn(usize, usize) + Sync,
) -> Result<FieldsOutcome, DesignError> {
    let _armed = damper.cancel.arm();
    std::fs::create_dir_all(out_dir.join("points"))
        .map_err(DesignError::write(out_dir.join("points")))?;
    let points = grid.points();
    let total = points.len();
    let mut results: Vec<Option<PointResult>> = points
        .iter()
        .map(|&(i, j, f, x)| load_point(out_dir, i, j, f, x))
        .collect();
    let reused = results.iter().filter(|r| r.is_some()).count();
    let done = std::sync::atomic::AtomicUsize::new(reused);
    on_point(reused, total);
    let mut pending: Vec<usize> = (0..total).filter(|&k| results[k].is_none()).collect();
    // Longest points first (most steps at most: lowest frequency) so that the short ones make
    // the tail; a stable sort keeps the grid order among equals.
    let max_steps = |f: f64| damper.cycles as f64 * (1.0 / (f * damper.time_step_s)).ceil();
    pending.sort_by(|&a, &b| max_steps(points[b].2).total_cmp(&max_steps(points[a].2)));
    let particles = damper.settled.particles.len();
    let store = |k: usize, r: Result<PointResult, DesignError>| {
        let (i, j, _, _) = points[k];
        let stored = store_point(out_dir, i, j, r);
        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        on_point(n, total);
        stored
    };
    let fresh: Vec<(usize, Result<PointResult, DesignError>)> = match engine {
        PointEngine::Cpu(split) => run_split(&pending, split, particles, |k| {
            let (_, _, f, x) = points[k];
            store(k, damper.run_point(f, x, &mut ()))
        }),
        #[cfg(feature = "gpu")]
        PointEngine::Gpu(gpu) => {
            let per_batch = (GPU_BATCH_PARTICLES / particles.max(1)).max(1);
            let mut fresh = Vec::with_capacity(pending.len());
            for batch in pending.chunks(per_batch) {
                let jobs: Vec<(&Damper, f64, f64)> = batch
                    .iter()
                    .map(|&k| (damper, points[k].2, points[k].3))
                    .collect();
                match crate::gpu_points::run_points_gpu(gpu, &jobs) {
                    Ok(results) => {
                        for (&k, r) in batch.iter().zip(results) {
                            fresh.push((k, store(k, Ok(r))));
                        }
                    }
                    Err(e) => {
                        // The batch's error is every point's.
                        let e = std::sync::Arc::new(e);
                        for &k in batch {
                            fresh.push((k, store(k, Err(DesignError::Batch(e.clone())))));
                        }
                    }
                }
            }
            fresh
        }
        PointEngine::Stored => {
            let mut fresh = Vec::with_capacity(pending.len());
            let mut missing = Vec::new();
            for &k in &pending {
                let (i, j, f, x) = points[k];
                match stored_point(out_dir, i, j, f, x) {
                    StoredPoint::Failed(e) => fresh.push((k, Err(DesignError::StoredFailure(e)))),
                    StoredPoint::Corrupt(why) => missing.push(why),
                    StoredPoint::Missing | StoredPoint::Done(_) => {
                        missing.push(format!("f = {f} Hz, X = {x:.4e} m (f{i:03}_a{j:03})"))
                    }
                }
            }
            if !missing.is_empty() {
                let n = missing.len();
                missing.truncate(5);
                return Err(DesignError::NotFinished {
                    dir: out_dir.join("points"),
                    missing: n,
                    total,
                    shown: missing,
                });
            }
            fresh
        }
        PointEngine::_Lifetime(_) => Vec::new(),
    };
    let mut failed = Vec::new();
    let mut interrupted = 0;
    for (k, r) in fresh {
        match r {
            Ok(r) => results[k] = Some(r),
            Err(e) if e.is_output() => return Err(e),
            Err(e) if e.is_interrupted() => interrupted += 1,
            Err(e) => {
                let (_, _, f, x) = points[k];
                failed.push((f, x, e.to_string()));
                results[k] = Some(failed_point(f, x));
            }
        }
    }
    if interrupted > 0 {
        let finished = results.iter().filter(|r| r.is_some()).count();
        return Err(DesignError::FieldInterrupted {
            finished,
            total,
            interrupted,
            dir: out_dir.join("points"),
        });
    }
    let points: Vec<PointResult> = results.into_iter().map(|r| r.unwrap()).collect();
    write_fields_csv(&out_dir.join("fields.csv"), &points)?;
    let (lo, hi) = damper.bed_span_along_direction_m();
    Ok(FieldsOutcome {
        points,
        reused,
        failed,
        bed_span_along_direction_m: [lo, hi],
    })
}

/// Checkpoints inside the points of [`run_field_points`]: every `interval_s` of wall-clock
/// time and on SIGTERM (a cancelled or preempted Slurm task) the point in progress is saved
/// next to its slot (`points/fIII_aJJJ.ckpt`); the next run of the point continues from it and
/// gives the result of an uninterrupted run.
#[derive(Debug, Clone)]
pub struct PointCheckpoints {
    /// Digest of the packing's scenario and the files it reads
    /// ([`pdamp_scenario::run::scenario_content_digest`]): a checkpoint of another scenario is refused.
    pub scenario_digest: String,
    /// Wall-clock seconds between checkpoints (≤ 0: only on a stop request).
    pub interval_s: f64,
}

/// Checkpoint file of a point in progress (see [`PointCheckpoints`]).
pub fn point_checkpoint_path(dir: &Path, i: usize, j: usize) -> PathBuf {
    dir.join("points").join(format!("f{i:03}_a{j:03}.ckpt"))
}

/// Outcome of one point of [`run_field_points`]: `Ok(true)` computed now, `Ok(false)` found
/// finished in the store, `Err` the error of a failed point (stored next to its slot).
pub type PointRun = Result<bool, DesignError>;

/// Runs the grid points `indices` (positions in [`FieldGrid::points`], frequency-major) of the
/// field stored in `out_dir` that are not finished yet — a task of a sweep — with the threads
/// shared as `split` says, storing each point as it ends (its result, or its error next to its
/// slot) and telling `on_point(index, outcome)`. Returns, per index, `Ok(true)` when it ran,
/// `Ok(false)` when it was already finished, or the error of a failed point; an `output:`
/// error or an interruption ends the call.
pub fn run_field_points(
    damper: &Damper,
    grid: &FieldGrid,
    out_dir: &Path,
    indices: &[usize],
    split: ThreadSplit,
    checkpoints: Option<&PointCheckpoints>,
    on_point: impl Fn(usize, &Result<PointResult, DesignError>) + Sync,
) -> Result<Vec<(usize, PointRun)>, DesignError> {
    let _armed = damper.cancel.arm();
    std::fs::create_dir_all(out_dir.join("points"))
        .map_err(DesignError::write(out_dir.join("points")))?;
    let points = grid.points();
    if let Some(&k) = indices.iter().find(|&&k| k >= points.len()) {
        return Err(DesignError::NoGridPoint {
            index: k,
            points: points.len(),
        });
    }
    let mut out: Vec<(usize, PointRun)> = Vec::with_capacity(indices.len());
    let mut pending = Vec::new();
    for &k in indices {
        let (i, j, f, x) = points[k];
        if load_point(out_dir, i, j, f, x).is_some() {
            out.push((k, Ok(false)));
        } else {
            pending.push(k);
        }
    }
    let particles = damper.settled.particles.len();
    let ran = run_split(&pending, split, particles, |k| {
        let (i, j, f, x) = points[k];
        if damper.cancel.is_cancelled() {
            // Stopped (SIGTERM of a cancelled task): the points not started stay missing.
            return Err(DesignError::Interrupted);
        }
        let r = match checkpoints {
            None => damper.run_point(f, x, &mut ()),
            Some(c) => {
                let path = point_checkpoint_path(out_dir, i, j);
                let run = |resume: bool| {
                    damper.run_point_checkpointed(
                        f,
                        x,
                        &mut (),
                        Some(&crate::damper::PointCheckpointing {
                            resume,
                            path: path.clone(),
                            scenario_digest: c.scenario_digest.clone(),
                            interval_s: c.interval_s,
                        }),
                    )
                };
                let resume = path.is_file();
                let mut r = run(resume);
                // A checkpoint that cannot be continued (damaged, foreign) costs the point its
                // progress, not its result: it starts again.
                if resume
                    && let Err(e) = &r
                    && e.is_checkpoint()
                {
                    let _ = std::fs::remove_file(&path);
                    r = run(false);
                }
                if r.is_ok() {
                    let _ = std::fs::remove_file(&path);
                }
                r
            }
        };
        let r = store_point(out_dir, i, j, r);
        on_point(k, &r);
        r
    });
    for (k, r) in ran {
        match r {
            Ok(_) => out.push((k, Ok(true))),
            Err(e) if e.is_output() || e.is_interrupted() => return Err(e),
            Err(e) => out.push((k, Err(e))),
        }
    }
    out.sort_by_key(|(k, _)| *k);
    Ok(out)
}

/// Writes `fields.csv` atomically.
pub fn write_fields_csv(path: &Path, points: &[PointResult]) -> Result<(), DesignError> {
    pdamp_io::csv::write_csv_atomic(path, &FIELD_COLUMNS, points.iter().map(field_row))
        .map_err(DesignError::write_csv(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_split_rule() {
        let split = ThreadSplit {
            threads: 16,
            min_particles_per_thread: 2000,
        };
        // 9 large-bed points on 16 threads started together: shares 2,2,2,2,2,2,2,1,1.
        let (mut idle, mut got) = (16, Vec::new());
        for waiting in (1..=9).rev() {
            let t = split.threads_for_point(idle, waiting, 100_000);
            idle -= t;
            got.push(t);
        }
        assert_eq!(got, [2, 2, 2, 2, 2, 2, 2, 1, 1]);
        // Enough points: one thread each.
        assert_eq!(split.threads_for_point(16, 40, 100_000), 1);
        assert_eq!(split.threads_for_point(1, 3, 100_000), 1);
        // The last point of a grid alone on the machine takes all threads, a small bed not.
        assert_eq!(split.threads_for_point(16, 1, 100_000), 16);
        assert_eq!(split.threads_for_point(16, 1, 4500), 2);
        assert_eq!(split.threads_for_point(16, 1, 300), 1);
    }
}
