//! Running a scenario to files: settling, the main run, `energy.csv`, VTK snapshots with a
//! `.pvd` series, and `summary.json`.

pub use crate::error::RunError;
pub use crate::provenance::{referenced_files_digest, scenario_content_digest, scenario_digest};
use crate::schema::Scenario;
use pdamp_dem::WorldState;
use pdamp_dem::bed_statistics::{BedStatistics, bed_statistics};
use pdamp_dem::time_loop::{CancelToken, LoopControl, LoopEnd, LoopEvent};
use pdamp_dem::{Vec3, World};
use pdamp_io::checkpoint::CheckpointError;
use pdamp_io::csv::CsvWriter;
use pdamp_io::vtk::{PvdSeries, VtkEncoding};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;
use std::path::Path;

mod settle;
mod snapshots;
pub use settle::{settle, settle_after_turn, settle_or_break, settle_with, settle_with_or_break};
pub use snapshots::{
    SnapshotSeries, snapshot_files, wall_surface, write_snapshot, write_snapshot_with,
};

/// Column names of `energy.csv` (SI units in every name).
pub const ENERGY_COLUMNS: [&str; 11] = [
    "time_s",
    "kinetic_j",
    "potential_j",
    "elastic_j",
    "wall_work_j",
    "dissipated_normal_j",
    "dissipated_tangential_j",
    "dissipated_normal_pp_j",
    "dissipated_normal_pw_j",
    "dissipated_tangential_pp_j",
    "dissipated_tangential_pw_j",
];

/// What a run reports in `summary.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSummary {
    /// pdamp version that produced the file.
    pub pdamp_version: String,
    /// Scenario title.
    pub title: String,
    /// Digest of the scenario (FNV-1a 64 of the canonical TOML written as `scenario.toml`).
    pub scenario_digest: String,
    /// Worker threads used.
    pub threads: usize,
    /// Random seed.
    pub seed: u64,
    /// Number of particles.
    pub particles: usize,
    /// Simulated time of the main run, s.
    pub simulated_time_s: f64,
    /// Settling time before the main run, s.
    pub settling_time_s: f64,
    /// Accepted time steps (main run).
    pub steps: u64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Particle time steps per wall-clock second.
    pub particle_steps_per_s: f64,
    /// Final energy ledger.
    pub energy: pdamp_dem::EnergyLedger,
    /// Total dissipated energy, J.
    pub dissipated_j: f64,
    /// Balance residual W_wall − (ΔE_kin + ΔE_pot + ΔE_el + D), J.
    pub energy_closure_error_j: f64,
    /// Residual relative to the wall work (or to the largest energy term).
    pub energy_closure_relative: f64,
    /// Largest particle–particle overlap relative to the smaller radius at the end.
    pub max_relative_overlap: f64,
    /// Mean particle–particle and particle–wall contacts at the end.
    pub contacts_pp: usize,
    /// Particle–wall contacts at the end.
    pub contacts_pw: usize,
    /// Height of the bed: twice the mean particle height above the lowest particle bottom, m.
    pub bed_height_m: f64,
    /// Statistics of the bed at the start of the main run (after settling): packing fraction,
    /// coordination number, surface height ([`pdamp_dem::bed_statistics`]); also in
    /// `bed_statistics.json`.
    pub bed: Option<BedStatistics>,
}

/// File of the bed statistics at the start of a run's main phase.
pub const BED_STATISTICS_FILE: &str = "bed_statistics.json";

/// Twice the mean height of the particle centres above the lowest particle bottom, measured
/// against gravity: a robust packing-height measure, m.
pub fn bed_height_m(world: &World) -> f64 {
    let p = &world.particles;
    if p.is_empty() {
        return 0.0;
    }
    let up = -world.gravity_m_s2;
    let up = if up.norm() > 0.0 {
        up.normalize()
    } else {
        Vec3::z()
    };
    let lo = (0..p.len())
        .map(|i| up.dot(&p.position[i]) - p.radius[i])
        .fold(f64::INFINITY, f64::min);
    let mean = (0..p.len())
        .map(|i| up.dot(&p.position[i]) - lo)
        .sum::<f64>()
        / p.len() as f64;
    2.0 * mean
}

/// One row of `energy.csv` ([`ENERGY_COLUMNS`]): the time and the world's energy ledger, J.
pub fn ledger_row(w: &World) -> Vec<f64> {
    let l = &w.ledger;
    vec![
        w.time_s,
        l.kinetic_j,
        l.potential_j,
        l.elastic_j,
        l.wall_work_j,
        l.dissipated_normal_j(),
        l.dissipated_tangential_j(),
        l.dissipated_normal_pp_j,
        l.dissipated_normal_pw_j,
        l.dissipated_tangential_pp_j,
        l.dissipated_tangential_pw_j,
    ]
}

/// How `run_scenario` checkpoints and stops.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Wall-clock seconds between checkpoints (≤ 0: none, except on a stop request).
    pub checkpoint_interval_s: f64,
    /// Continue from `DIR/checkpoint.bin` if there is one.
    pub resume: bool,
    /// Cancelling it makes the run write a checkpoint and return an "interrupted" error.
    pub cancel: CancelToken,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            checkpoint_interval_s: 60.0,
            resume: false,
            cancel: CancelToken::new(),
        }
    }
}

impl RunOptions {
    /// Checkpoints every `checkpoint_interval_s`, continuing a checkpoint with `resume`, never
    /// cancelled.
    pub fn new(checkpoint_interval_s: f64, resume: bool) -> Self {
        Self {
            checkpoint_interval_s,
            resume,
            cancel: CancelToken::new(),
        }
    }

    /// The same options stopped by `cancel`.
    pub fn cancelled_by(self, cancel: &CancelToken) -> Self {
        Self {
            cancel: cancel.clone(),
            ..self
        }
    }

    /// The checkpoint cadence and stop request of a run with these options.
    pub fn control(&self) -> LoopControl {
        LoopControl::new(&self.cancel, self.checkpoint_interval_s)
    }
}

/// Phase a run checkpoint was taken in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
enum RunPhase {
    Settling,
    Running,
    Finished,
}

/// Everything `run_scenario` needs to continue: the DEM state and the output streams.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct RunCheckpoint {
    phase: RunPhase,
    world: Option<WorldState>,
    settle_time_s: f64,
    energy_csv_bytes: u64,
    energy_rows: usize,
    next_energy_s: f64,
    next_vtk_s: f64,
    snapshot: usize,
    pvd: Vec<(f64, String)>,
    steps_at_start: u64,
    wall_time_s: f64,
}

impl RunCheckpoint {
    fn settling(world: &World, wall_time_s: f64) -> Self {
        Self {
            phase: RunPhase::Settling,
            world: Some(world.save_state()),
            settle_time_s: 0.0,
            energy_csv_bytes: 0,
            energy_rows: 0,
            next_energy_s: 0.0,
            next_vtk_s: 0.0,
            snapshot: 0,
            pvd: Vec::new(),
            steps_at_start: 0,
            wall_time_s,
        }
    }
}

/// Decodes a `run` checkpoint file of any scenario and returns its simulated time, s (for
/// inspection and fuzzing; never panics).
pub fn inspect_run_checkpoint(bytes: &[u8]) -> Result<f64, CheckpointError> {
    let c: RunCheckpoint = pdamp_io::checkpoint::decode(bytes, RUN_KIND, None)?;
    Ok(c.world.map_or(0.0, |w| w.time_s()))
}

/// Steps between numerical health checks ([`World::check_health`]).
pub const HEALTH_CHECK_STEPS: u64 = 500;

/// Writes `failure.json` next to the outputs written so far and returns the error.
fn report_failure(
    out_dir: &Path,
    phase: &'static str,
    h: &pdamp_dem::health::HealthError,
) -> RunError {
    let json = serde_json::json!({
        "pdamp_version": env!("CARGO_PKG_VERSION"),
        "phase": phase,
        "time_s": h.time_s,
        "particle": h.particle,
        "position_m": h.position_m,
        "message": h.message,
    });
    let _ = std::fs::create_dir_all(out_dir);
    let _ = pdamp_io::atomic::write_atomic(
        out_dir.join("failure.json"),
        serde_json::to_string_pretty(&json)
            .unwrap_or_default()
            .as_bytes(),
    );
    RunError::Failed {
        health: h.clone(),
        phase,
        out_dir: out_dir.to_path_buf(),
    }
}

/// Kind tag of `run` checkpoints.
const RUN_KIND: &str = "run";

/// Runs `scenario` (paths relative to `base_dir`) and writes all outputs into `out_dir`.
/// `progress(phase, fraction)` is called regularly. Checkpoints every
/// `options.checkpoint_interval_s` of wall-clock time and when `options.cancel` is cancelled,
/// which ends the run with [`RunError::Interrupted`]. With `options.resume`, continues from the
/// last checkpoint; the outputs then equal those of an uninterrupted run (timing fields aside).
pub fn run_scenario(
    scenario: &Scenario,
    base_dir: &Path,
    out_dir: &Path,
    options: RunOptions,
    mut progress: impl FnMut(&str, f64),
) -> Result<RunSummary, RunError> {
    use pdamp_io::checkpoint::{self as ck, CheckpointHeader};
    let mut world = scenario.build_world_cancellable(base_dir, &options.cancel)?;
    let digest = scenario_content_digest(scenario, base_dir);
    let ck_path = out_dir.join(ck::CHECKPOINT_FILE);
    let header = CheckpointHeader::new(RUN_KIND, &digest);
    let resumed: Option<RunCheckpoint> = if options.resume {
        ck::load(&ck_path, RUN_KIND, &digest)?
    } else {
        None
    };
    if let Some(c) = &resumed
        && c.phase == RunPhase::Finished
    {
        return finished_summary(out_dir);
    }
    crate::provenance::write(scenario, out_dir).map_err(RunError::output)?;
    let start = std::time::Instant::now();
    let wall_before = resumed.as_ref().map_or(0.0, |c| c.wall_time_s);
    let wall = |start: &std::time::Instant| wall_before + start.elapsed().as_secs_f64();
    let mut control = options.control();
    let interrupted = |t: f64| {
        RunError::Interrupted(ck::Interrupted {
            time_s: t,
            path: ck_path.clone(),
        })
    };
    let main_gravity = Vec3::from(scenario.simulation.gravity_m_s2);
    let _armed = options.cancel.arm();
    let mut health: Option<pdamp_dem::health::HealthError> = None;

    // Settling (fresh, or resumed in the middle of it).
    let mut state = restore_resumed(&mut world, resumed, main_gravity)?;
    let settle_t = match (&state, &scenario.settle) {
        (Some(c), _) => c.settle_time_s,
        (None, Some(spec)) => settle_phase(
            &mut world,
            spec,
            main_gravity,
            &mut progress,
            &mut control,
            (&ck_path, &header),
            &|| wall(&start),
            out_dir,
        )?,
        (None, None) => 0.0,
    };

    // Main run: outputs opened fresh or continued at the checkpoint.
    let vtk_dir = out_dir.join("vtk");
    let vtk_every = scenario.output.vtk_interval_s;
    let vtk_encoding: VtkEncoding = scenario.output.vtk_format.into();
    let e_every = scenario.output.energy_interval_s;
    let csvio = RunError::output;
    let MainOutputs {
        mut csv,
        mut series,
        mut snap,
        next_energy_s: mut next_e,
        next_vtk_s: mut next_v,
        steps_at_start: steps0,
    } = open_outputs(state.take(), &mut world, scenario, out_dir, vtk_encoding)?;
    let t_end = scenario.simulation.duration_s;
    // Half kicks deferred (`World::step_deferred`: same results, one pass over the particles
    // less per step); the state is completed wherever it is read.
    let end = world.run_controlled(t_end, true, &mut control, |w, event| {
        if event == LoopEvent::Checkpoint {
            let bytes = csv.sync().map_err(csvio)?;
            let c = RunCheckpoint {
                phase: RunPhase::Running,
                world: Some(w.save_state()),
                settle_time_s: settle_t,
                energy_csv_bytes: bytes,
                energy_rows: csv.rows(),
                next_energy_s: next_e,
                next_vtk_s: next_v,
                snapshot: snap,
                pvd: series.as_ref().map_or(Vec::new(), |s| s.entries().to_vec()),
                steps_at_start: steps0,
                wall_time_s: wall(&start),
            };
            ck::save(&ck_path, &header, &c)?;
            return Ok(ControlFlow::Continue(()));
        }
        if w.counters.steps.is_multiple_of(HEALTH_CHECK_STEPS) {
            w.complete_step();
            if let Err(e) = w.check_health() {
                health = Some(e);
                return Ok(ControlFlow::Break(()));
            }
        }
        if w.time_s >= next_e - 1e-12 {
            w.complete_step();
            csv.write_row(&ledger_row(w)).map_err(RunError::output)?;
            next_e += e_every;
            progress("running", w.time_s / t_end);
        }
        if let Some(s) = series.as_mut()
            && w.time_s >= next_v - 1e-12
        {
            w.complete_step();
            write_frame(w, &vtk_dir, snap, vtk_encoding, s)?;
            snap += 1;
            next_v += vtk_every;
        }
        Ok::<_, RunError>(ControlFlow::Continue(()))
    })?;
    if let Some(h) = health {
        csv.sync().map_err(csvio)?;
        return Err(report_failure(out_dir, "running", &h));
    }
    if end == LoopEnd::Cancelled {
        return Err(interrupted(world.time_s));
    }
    csv.sync().map_err(csvio)?;
    let wall_s = wall(&start);
    let steps = world.counters.steps - steps0;
    let summary = run_summary(scenario, &world, &digest, settle_t, steps, wall_s, out_dir);
    write_finished(&summary, &world, out_dir, (&ck_path, &header), wall_s)?;
    Ok(summary)
}

/// The settling before the main run ([`settle_with_or_break`]) under the health check, with
/// checkpoints when `control` has one due or is cancelled. Returns the settling time, s.
#[allow(clippy::too_many_arguments)]
fn settle_phase(
    world: &mut World,
    spec: &crate::schema::SettleSpec,
    main_gravity: Vec3,
    progress: &mut dyn FnMut(&str, f64),
    control: &mut LoopControl,
    (ck_path, header): (&Path, &pdamp_io::checkpoint::CheckpointHeader),
    wall: &dyn Fn() -> f64,
    out_dir: &Path,
) -> Result<f64, RunError> {
    use pdamp_io::checkpoint as ck;
    let mut health = None;
    let mut err = None;
    let max = spec.max_duration_s;
    let r = settle_with_or_break(world, spec, main_gravity, |w| {
        progress("settling", w.time_s / max);
        if let Err(e) = w.check_health() {
            health = Some(e);
            return ControlFlow::Break(());
        }
        control
            .checkpoint_or_stop(|| ck::save(ck_path, header, &RunCheckpoint::settling(w, wall())))
            .unwrap_or_else(|e| {
                err = Some(e);
                ControlFlow::Break(())
            })
    });
    if let Some(e) = err {
        return Err(e.into());
    }
    if let Some(h) = health.take() {
        return Err(report_failure(out_dir, "settling", &h));
    }
    r.ok_or_else(|| {
        RunError::Interrupted(ck::Interrupted {
            time_s: world.time_s,
            path: ck_path.to_path_buf(),
        })
    })
}

/// The summary of a run that had finished (resumed after its end).
fn finished_summary(out_dir: &Path) -> Result<RunSummary, RunError> {
    let text = std::fs::read_to_string(out_dir.join("summary.json")).map_err(RunError::output)?;
    serde_json::from_str(&text).map_err(RunError::Summary)
}

/// Writes `summary.json` and the checkpoint that marks the run finished.
fn write_finished(
    summary: &RunSummary,
    world: &World,
    out_dir: &Path,
    (ck_path, header): (&Path, &pdamp_io::checkpoint::CheckpointHeader),
    wall_s: f64,
) -> Result<(), RunError> {
    let json = serde_json::to_string_pretty(summary)?;
    pdamp_io::atomic::write_atomic(out_dir.join("summary.json"), json.as_bytes())
        .map_err(RunError::output)?;
    let done = RunCheckpoint {
        phase: RunPhase::Finished,
        world: None,
        ..RunCheckpoint::settling(world, wall_s)
    };
    pdamp_io::checkpoint::save(ck_path, header, &done)?;
    Ok(())
}

/// Puts the state of checkpoint `resumed` back into `world`: a checkpoint of the main run is
/// returned (its outputs continue), one of the settling is consumed (the run gravity set again).
fn restore_resumed(
    world: &mut World,
    resumed: Option<RunCheckpoint>,
    main_gravity: Vec3,
) -> Result<Option<RunCheckpoint>, RunError> {
    Ok(match resumed {
        Some(mut c) if c.phase == RunPhase::Running => {
            world.restore_state(c.world.take().ok_or(RunError::NoState)?)?;
            Some(c)
        }
        Some(mut c) => {
            world.restore_state(c.world.take().ok_or(RunError::NoState)?)?;
            world.gravity_m_s2 = main_gravity;
            None
        }
        None => None,
    })
}

/// The outputs of the main run and where it stands ([`open_outputs`]).
struct MainOutputs {
    csv: EnergyCsv,
    series: Option<PvdSeries>,
    /// Index of the next VTK frame.
    snap: usize,
    /// Time of the next energy row, s.
    next_energy_s: f64,
    /// Time of the next VTK frame, s.
    next_vtk_s: f64,
    /// Step count when the main run started.
    steps_at_start: u64,
}

/// The outputs of the main run: continued at the checkpoint `resumed` (files cut back to it),
/// or opened afresh after initialising `world`. Returns the writers, the next frame, the next
/// energy and VTK times, and the step count at the start of the main run.
fn open_outputs(
    resumed: Option<RunCheckpoint>,
    world: &mut World,
    scenario: &Scenario,
    out_dir: &Path,
    vtk_encoding: VtkEncoding,
) -> Result<MainOutputs, RunError> {
    let csvio = RunError::output;
    let vtk_dir = out_dir.join("vtk");
    let pvd_path = out_dir.join("particles.pvd");
    let vtk_every = scenario.output.vtk_interval_s;
    let e_every = scenario.output.energy_interval_s;
    Ok(match resumed {
        Some(c) => {
            let csv = CsvWriter::resume(
                out_dir.join("energy.csv"),
                &ENERGY_COLUMNS,
                c.energy_csv_bytes,
                c.energy_rows,
            )
            .map_err(csvio)?;
            let series = resume_series(vtk_every > 0.0, &vtk_dir, &pvd_path, c.pvd)?;
            MainOutputs {
                csv,
                series,
                snap: c.snapshot,
                next_energy_s: c.next_energy_s,
                next_vtk_s: c.next_vtk_s,
                steps_at_start: c.steps_at_start,
            }
        }
        None => {
            world.initialize();
            let (csv, series, snap) =
                open_fresh_outputs(world, scenario, out_dir, &pvd_path, vtk_encoding)?;
            MainOutputs {
                csv,
                series,
                snap,
                next_energy_s: e_every,
                next_vtk_s: vtk_every,
                steps_at_start: world.counters.steps,
            }
        }
    })
}

/// The ParaView series of a resumed run (its VTK directory made again if missing), or none
/// without VTK output.
fn resume_series(
    vtk: bool,
    vtk_dir: &Path,
    pvd_path: &Path,
    entries: Vec<(f64, String)>,
) -> Result<Option<PvdSeries>, RunError> {
    if !vtk {
        return Ok(None);
    }
    std::fs::create_dir_all(vtk_dir).map_err(RunError::output)?;
    Ok(Some(PvdSeries::resume(pvd_path, entries)?))
}

/// Writes snapshot `snap` of `w` and adds it to the series.
fn write_frame(
    w: &World,
    vtk_dir: &Path,
    snap: usize,
    encoding: VtkEncoding,
    series: &mut PvdSeries,
) -> Result<(), RunError> {
    write_snapshot_with(w, vtk_dir, snap, encoding).map_err(RunError::output)?;
    series
        .add_frame(w.time_s, &snapshot_files(w, snap))
        .map_err(RunError::output)
}

/// `summary.json` of a finished run: counts, timings, the ledger and its closure, overlaps,
/// contacts and the bed statistics written at the start of the main run.
fn run_summary(
    scenario: &Scenario,
    world: &World,
    digest: &str,
    settle_t: f64,
    steps: u64,
    wall_s: f64,
    out_dir: &Path,
) -> RunSummary {
    let l = world.ledger;
    let scale = l.turnover_j().max(1e-300);
    RunSummary {
        pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
        title: scenario.title.clone(),
        scenario_digest: digest.to_string(),
        seed: scenario.simulation.seed,
        threads: rayon::current_num_threads(),
        particles: world.particles.len(),
        simulated_time_s: world.time_s,
        settling_time_s: settle_t,
        steps,
        wall_time_s: wall_s,
        particle_steps_per_s: steps as f64 * world.particles.len() as f64 / wall_s.max(1e-12),
        energy: l,
        dissipated_j: l.dissipated_j(),
        energy_closure_error_j: l.closure_error_j(),
        energy_closure_relative: l.closure_error_j() / scale,
        max_relative_overlap: world.max_relative_overlap(),
        contacts_pp: world.num_pp_contacts(),
        contacts_pw: world.num_pw_contacts(),
        bed_height_m: bed_height_m(world),
        bed: std::fs::read_to_string(out_dir.join(BED_STATISTICS_FILE))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok()),
    }
}

/// The writer of `energy.csv`.
type EnergyCsv = CsvWriter<std::io::BufWriter<std::fs::File>>;

/// The outputs of a main run started afresh: the bed statistics it starts from (measured once;
/// a resumed run reads them back), `energy.csv` with its first row and, with VTK output, the
/// series with its first frame. Returns the writers and the next frame's index.
fn open_fresh_outputs(
    world: &World,
    scenario: &Scenario,
    out_dir: &Path,
    pvd_path: &Path,
    vtk_encoding: VtkEncoding,
) -> Result<(EnergyCsv, Option<PvdSeries>, usize), RunError> {
    let io = RunError::output;
    let csvio = RunError::output;
    let vtk_dir = out_dir.join("vtk");
    let vtk_every = scenario.output.vtk_interval_s;
    // The bed the main run starts from (measured once; a resumed run reads it back).
    let stats = bed_statistics(world, crate::schema::excitation_direction(scenario));
    let json = serde_json::to_string_pretty(&stats)?;
    pdamp_io::atomic::write_atomic(out_dir.join(BED_STATISTICS_FILE), json.as_bytes())
        .map_err(io)?;
    let mut series = if vtk_every > 0.0 {
        std::fs::create_dir_all(&vtk_dir).map_err(io)?;
        Some(PvdSeries::new(pvd_path))
    } else {
        None
    };
    let mut csv = CsvWriter::create(out_dir.join("energy.csv"), &ENERGY_COLUMNS).map_err(csvio)?;
    csv.write_row(&ledger_row(world)).map_err(csvio)?;
    let mut snap = 0usize;
    if let Some(s) = series.as_mut() {
        write_snapshot_with(world, &vtk_dir, snap, vtk_encoding)?;
        s.add_frame(world.time_s, &snapshot_files(world, snap))?;
        snap += 1;
    }
    Ok((csv, series, snap))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 31: the digest of a scenario covers the content of the files it reads, so a
    /// checkpoint is not continued with another mesh behind the same path.
    #[test]
    fn content_digest_follows_the_mesh_bytes() {
        let dir = std::env::temp_dir().join(format!("pdamp-digest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut sc = crate::examples::shaken_box(10, 0.01);
        sc.bodies[0].walls[0].geometry = crate::schema::GeometrySpec::Stl(crate::schema::StlSpec {
            path: "box.stl".into(),
            scale: 1.0,
            translation_m: [0.0; 3],
            flip_normals: false,
        });
        std::fs::write(dir.join("box.stl"), "solid a\nendsolid a\n").unwrap();
        let a = scenario_content_digest(&sc, &dir);
        assert_eq!(a, scenario_content_digest(&sc, &dir));
        std::fs::write(dir.join("box.stl"), "solid b\nendsolid b\n").unwrap();
        let b = scenario_content_digest(&sc, &dir);
        assert_ne!(a, b, "same path, other bytes: another digest");
        assert_eq!(scenario_digest(&sc), scenario_digest(&sc));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
