//! Output of damper runs: `summary.json` with the effective quantities, velocity fields,
//! trajectories, VTK animation of the last cycle and plots.

use crate::DesignError;
use crate::damper::{Damper, POINT_KIND, PointCheckpoint, PointCheckpointing, PointResult};
use crate::ensemble::EnsembleStat;
use crate::fields::{FieldGrid, FieldsOutcome};
use crate::motion::MotionRecorder;
use pdamp_dem::bed_statistics::BedStatistics;
use pdamp_dem::time_loop::CancelToken;
use pdamp_io::checkpoint as ck;
use pdamp_scenario::schema::Scenario;
use serde::Serialize;
use std::path::Path;

/// `summary.json` of `pdamp run` on a damper scenario.
#[derive(Debug, Clone, Serialize)]
pub struct DamperRunSummary {
    /// pdamp version.
    pub pdamp_version: String,
    /// Scenario title.
    pub title: String,
    /// Digest of the scenario (see `provenance.json`).
    pub scenario_digest: String,
    /// Random seed.
    pub seed: u64,
    /// Number of particles.
    pub particles: usize,
    /// Bed mass m_bed, kg.
    pub bed_mass_kg: f64,
    /// Container mass m_con, kg.
    pub container_mass_kg: f64,
    /// Settling time, s.
    pub settling_time_s: f64,
    /// Span of the settled bed along the excitation direction, from the container's reference
    /// position, [lowest, highest], m (with the inner walls: the clearance h).
    pub bed_span_along_direction_m: [f64; 2],
    /// Excitation frequency, Hz.
    pub frequency_hz: f64,
    /// Displacement amplitude X, m.
    pub amplitude_m: f64,
    /// Acceleration amplitude A, m/s².
    pub acceleration_m_s2: f64,
    /// Intensity Γ.
    pub intensity: f64,
    /// Dissipated energy per cycle Ẽ [D Eq. 3.13], J.
    pub dissipated_energy_per_cycle_j: f64,
    /// Loss factor η [D Eq. 3.14].
    pub loss_factor: f64,
    /// Effective loss factor η̄ [D Eq. 3.15].
    pub effective_loss_factor: f64,
    /// Effective particle mass ratio m̄_bed/m_bed [D Eq. 3.17].
    pub effective_mass_ratio: f64,
    /// Cycles evaluated (after the transient); fewer than `cycles − transient_cycles` when the
    /// point stopped early on convergence.
    pub cycles_evaluated: u32,
    /// Whether `[damper] convergence` was met (`null`: no criterion given).
    pub converged: Option<bool>,
    /// Statistics of the settled bed of packing 0 (packing fraction, coordination number,
    /// clearance h along the excitation).
    pub bed: BedStatistics,
    /// Statistics of packing 0's bed as filled, before the "turn" (fills under
    /// `settle.gravity_m_s2`): its `clearance_m` is D's h (Eq. 8.1/8.2).
    pub bed_at_fill: Option<BedStatistics>,
    /// Independently prepared beds the point ran on (`[damper] packings`). With more than one,
    /// the top-level Ẽ, η, η̄ and m̄_bed/m_bed are the ensemble means and `ensemble` holds their
    /// spread and 95 % confidence intervals; `point`, `bed` and the motion outputs are packing 0's.
    pub packings: usize,
    /// Ensemble statistics (with more than one packing).
    pub ensemble: Option<EnsembleSummary>,
    /// Everything else of the point (ledger cross-check, dissipation shares, timing).
    pub point: PointResult,
}

/// One member of an ensemble.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct PackingResult {
    /// Packing index k.
    pub packing: usize,
    /// Seed of its bed.
    pub seed: u64,
    /// Dissipated energy per cycle Ẽ, J.
    pub dissipated_energy_per_cycle_j: f64,
    /// Loss factor η.
    pub loss_factor: f64,
    /// Effective loss factor η̄.
    pub effective_loss_factor: f64,
    /// Effective mass ratio m̄_bed/m_bed.
    pub effective_mass_ratio: f64,
    /// Energy balance residual relative to the wall work.
    pub energy_closure_relative: f64,
    /// Packing fraction of the settled bed.
    pub packing_fraction: f64,
    /// Clearance h along the excitation, m.
    pub clearance_m: f64,
    /// Error of a failed member (its values are NaN and left out of the statistics).
    pub error: Option<String>,
}

/// Mean, spread and 95 % confidence interval over the packings of a point.
#[derive(Debug, Clone, Serialize)]
pub struct EnsembleSummary {
    /// Dissipated energy per cycle Ẽ, J.
    pub dissipated_energy_per_cycle_j: EnsembleStat,
    /// Loss factor η.
    pub loss_factor: EnsembleStat,
    /// Effective loss factor η̄.
    pub effective_loss_factor: EnsembleStat,
    /// Effective mass ratio m̄_bed/m_bed.
    pub effective_mass_ratio: EnsembleStat,
    /// Packing fraction of the beds.
    pub packing_fraction: EnsembleStat,
    /// Clearance h of the beds, m.
    pub clearance_m: EnsembleStat,
    /// Every member.
    pub members: Vec<PackingResult>,
}

impl EnsembleSummary {
    /// Statistics over `members` (failed ones left out).
    pub fn of(members: Vec<PackingResult>) -> Self {
        let st = |f: fn(&PackingResult) -> f64| {
            EnsembleStat::of(&members.iter().map(f).collect::<Vec<_>>())
        };
        Self {
            dissipated_energy_per_cycle_j: st(|m| m.dissipated_energy_per_cycle_j),
            loss_factor: st(|m| m.loss_factor),
            effective_loss_factor: st(|m| m.effective_loss_factor),
            effective_mass_ratio: st(|m| m.effective_mass_ratio),
            packing_fraction: st(|m| m.packing_fraction),
            clearance_m: st(|m| m.clearance_m),
            members,
        }
    }
}

/// Member `k` of an ensemble from its point and bed.
fn packing_result(
    k: usize,
    seed: u64,
    r: Result<(PointResult, BedStatistics, Option<f64>), DesignError>,
) -> PackingResult {
    match r {
        Ok((p, b, clearance)) => PackingResult {
            packing: k,
            seed,
            dissipated_energy_per_cycle_j: p.dissipated_energy_per_cycle_j,
            loss_factor: p.loss_factor,
            effective_loss_factor: p.effective_loss_factor,
            effective_mass_ratio: p.effective_mass_ratio,
            energy_closure_relative: p.energy_closure_relative,
            packing_fraction: b.packing_fraction,
            clearance_m: clearance.unwrap_or(f64::NAN),
            error: None,
        },
        Err(e) => PackingResult {
            packing: k,
            seed,
            dissipated_energy_per_cycle_j: f64::NAN,
            loss_factor: f64::NAN,
            effective_loss_factor: f64::NAN,
            effective_mass_ratio: f64::NAN,
            energy_closure_relative: f64::NAN,
            packing_fraction: f64::NAN,
            clearance_m: f64::NAN,
            error: Some(e.to_string()),
        },
    }
}

/// Runs the point (f, X) of `sc` on packings `1..packings` (packing 0 is the caller's), in
/// parallel, each on its own freshly prepared bed; writes `out/packings/packing_KKK.json`
/// (with `reuse`, those already there for the same seed are taken instead of run again).
pub fn run_other_packings(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    (frequency_hz, amplitude_m): (f64, f64),
    packings: usize,
    reuse: bool,
    on_done: &(dyn Fn(usize) + Sync),
) -> Result<Vec<PackingResult>, DesignError> {
    use rayon::prelude::*;
    if packings <= 1 {
        return Ok(Vec::new());
    }
    let dir = out.join("packings");
    std::fs::create_dir_all(&dir).map_err(DesignError::write(&dir))?;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let members: Vec<Result<PackingResult, DesignError>> = (1..packings)
        .into_par_iter()
        .map(|k| {
            let sk = pdamp_scenario::prepare::scenario_for_packing(sc, k);
            // A resumed run reuses the packings finished before (same scenario: the
            // checkpoint's digest was checked; same seed).
            if reuse
                && let Ok(text) = std::fs::read_to_string(dir.join(format!("packing_{k:03}.json")))
                && let Ok(m) = serde_json::from_str::<PackingResult>(&text)
                && m.seed == sk.simulation.seed
                && m.error.is_none()
            {
                on_done(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                return Ok(m);
            }
            let r = Damper::from_scenario(&sk, base_dir, |_| {}).and_then(|d| {
                let p = d.run_point(frequency_hz, amplitude_m, &mut ())?;
                Ok((p, d.bed_statistics(), d.clearance_m()))
            });
            let r = match r {
                Err(e) if e.is_output() || e.is_interrupted() => return Err(e),
                r => r,
            };
            let m = packing_result(k, sk.simulation.seed, r);
            let json = serde_json::to_string_pretty(&m)?;
            let path = dir.join(format!("packing_{k:03}.json"));
            pdamp_io::atomic::write_atomic(&path, json.as_bytes())
                .map_err(DesignError::write(path))?;
            on_done(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            Ok(m)
        })
        .collect();
    members.into_iter().collect()
}

/// Runs the single excitation point of a damper scenario and writes `summary.json`,
/// `velocity_fields.csv`, `trajectories.csv`, `force_displacement.csv` (bed force, driving
/// force and container motion over all cycles, [`MotionRecorder::force_displacement`]),
/// `particles.pvd` + `vtk/` and plots (velocity fields, trajectories, `force_time`,
/// `hysteresis`) into `out`.
pub fn run_damper_scenario(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    progress: impl FnMut(&str, f64),
) -> Result<DamperRunSummary, DesignError> {
    let options = pdamp_scenario::run::RunOptions::new(0.0, false);
    run_damper_scenario_with(sc, base_dir, out, options, progress)
}

/// The `summary.json` text of a damper run in `out` whose checkpoint says it finished (for the
/// same scenario and files), `None` when there is no such checkpoint: a resumed finished run
/// only reprints its summary.
pub fn finished_damper_summary(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
) -> Result<Option<String>, DesignError> {
    let digest = pdamp_scenario::run::scenario_content_digest(sc, base_dir);
    match ck::load::<PointCheckpoint>(&out.join(ck::CHECKPOINT_FILE), POINT_KIND, &digest)
        .map_err(DesignError::from)?
    {
        Some(PointCheckpoint::Finished) => std::fs::read_to_string(out.join("summary.json"))
            .map(Some)
            .map_err(|source| DesignError::ReadSummary {
                path: out.join("summary.json"),
                source,
            }),
        _ => Ok(None),
    }
}

/// [`run_damper_scenario`] with checkpoints (`DIR/checkpoint.bin` every
/// `options.checkpoint_interval_s` of wall-clock time and on Ctrl-C/SIGTERM, see
/// [`crate::damper::PointCheckpointing`]) and `options.resume`: the point continues where it
/// stopped (the bed is prepared again, deterministically), finished packings of an ensemble
/// are reused, and the outputs equal those of an uninterrupted run (timing fields aside); see
/// [`finished_damper_summary`] for a finished run.
pub fn run_damper_scenario_with(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    options: pdamp_scenario::run::RunOptions,
    mut progress: impl FnMut(&str, f64),
) -> Result<DamperRunSummary, DesignError> {
    let digest = pdamp_scenario::run::scenario_content_digest(sc, base_dir);
    let checkpointing = PointCheckpointing::in_dir(out, &digest, &options);
    let ck_path = checkpointing.path.clone();
    let _armed = options.cancel.arm();
    let spec = sc.damper.as_ref().ok_or(DesignError::NoDamperSection)?;
    let f = spec.frequency_hz.ok_or(DesignError::NoFrequency)?;
    let x = spec.amplitude_at(f).ok_or(DesignError::NoAmplitude)?;
    pdamp_scenario::provenance::write(sc, out).map_err(DesignError::write(out))?;
    let damper = Damper::from_scenario_cancellable(
        sc,
        base_dir,
        |p| progress("settling", p),
        &options.cancel,
    )?;
    let omega = 2.0 * std::f64::consts::PI * f;
    let steps_per_cycle = (1.0 / (f * damper.time_step_s)).ceil();
    let mo = &spec.motion_output;
    let mut rec = MotionRecorder::new(
        &damper,
        f,
        x * omega,
        mo.phases_per_cycle,
        mo.field_cells,
        mo.trajectory_particles.clone(),
        steps_per_cycle,
    );
    if mo.vtk_frames_per_cycle > 0 {
        let dir = out.join("vtk");
        std::fs::create_dir_all(&dir).map_err(DesignError::write(&dir))?;
        rec.vtk = Some((dir, mo.vtk_frames_per_cycle));
    }
    let cycles = damper.cycles;
    let mut wrapped = ProgressObserver {
        inner: &mut rec,
        progress: &mut progress,
        cycles,
        last: u32::MAX,
    };
    let p = damper.run_point_checkpointed(f, x, &mut wrapped, Some(&checkpointing))?;
    if let Some(e) = &rec.error {
        return Err(DesignError::VtkFrames(e.clone()));
    }
    if !rec.vtk_frames.is_empty() {
        // Particles and the container (every wall with a surface) as the parts of each frame.
        let pvd_path = out.join("particles.pvd");
        let mut pvd = pdamp_io::vtk::PvdSeries::new(pvd_path.clone());
        for (idx, (t, _)) in rec.vtk_frames.iter().enumerate() {
            pvd.add_frame(
                *t,
                &pdamp_scenario::run::snapshot_files(&damper.settled, idx),
            )
            .map_err(|source| DesignError::Pvd {
                path: pvd_path.clone(),
                source,
            })?;
        }
    }
    write_velocity_fields(&rec, &out.join("velocity_fields.csv"))?;
    if !rec.trajectories.is_empty() {
        pdamp_io::csv::write_csv_atomic(
            out.join("trajectories.csv"),
            &["particle", "time_s", "x_m", "y_m", "z_m"],
            &rec.trajectories,
        )
        .map_err(DesignError::write_csv(out.join("trajectories.csv")))?;
    }
    crate::plots::velocity_field_plots(&rec, out)?;
    crate::plots::trajectory_plot(&rec, out)?;
    pdamp_io::csv::write_csv_atomic(
        out.join("force_displacement.csv"),
        &crate::motion::FORCE_DISPLACEMENT_COLUMNS,
        &rec.force_displacement,
    )
    .map_err(DesignError::write_csv(out.join("force_displacement.csv")))?;
    crate::plots::force_displacement_plots(&rec, damper.transient_cycles, &p, out)?;
    let bed = damper.bed_statistics();
    let packings = spec.packings;
    let ensemble = if packings > 1 {
        progress("packings", 0.0);
        let mut members = vec![packing_result(
            0,
            sc.simulation.seed,
            Ok((p.clone(), bed.clone(), damper.clearance_m())),
        )];
        members.extend(run_other_packings(
            sc,
            base_dir,
            out,
            (f, x),
            packings,
            options.resume,
            &|_| {},
        )?);
        Some(EnsembleSummary::of(members))
    } else {
        None
    };
    let mean_or = |v: f64, pick: fn(&EnsembleSummary) -> &EnsembleStat| {
        ensemble.as_ref().map_or(v, |e| pick(e).mean)
    };
    let summary = DamperRunSummary {
        pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
        title: sc.title.clone(),
        scenario_digest: pdamp_scenario::run::scenario_digest(sc),
        seed: sc.simulation.seed,
        particles: damper.settled.particles.len(),
        bed_mass_kg: damper.bed_mass_kg,
        container_mass_kg: damper.container_mass_kg,
        settling_time_s: damper.settling_time_s,
        bed_span_along_direction_m: {
            let (lo, hi) = damper.bed_span_along_direction_m();
            [lo, hi]
        },
        frequency_hz: f,
        amplitude_m: x,
        acceleration_m_s2: p.acceleration_m_s2,
        intensity: p.intensity,
        dissipated_energy_per_cycle_j: mean_or(p.dissipated_energy_per_cycle_j, |e| {
            &e.dissipated_energy_per_cycle_j
        }),
        loss_factor: mean_or(p.loss_factor, |e| &e.loss_factor),
        effective_loss_factor: mean_or(p.effective_loss_factor, |e| &e.effective_loss_factor),
        effective_mass_ratio: mean_or(p.effective_mass_ratio, |e| &e.effective_mass_ratio),
        cycles_evaluated: p.cycles_evaluated,
        converged: p.converged,
        bed,
        bed_at_fill: damper.fill_statistics.clone(),
        packings,
        ensemble,
        point: p,
    };
    let json = serde_json::to_string_pretty(&summary)?;
    pdamp_io::atomic::write_atomic(out.join("summary.json"), json.as_bytes())
        .map_err(DesignError::write(out.join("summary.json")))?;
    ck::save(
        &ck_path,
        &ck::CheckpointHeader::new(POINT_KIND, &digest),
        &PointCheckpoint::Finished,
    )
    .map_err(DesignError::from)?;
    Ok(summary)
}

struct ProgressObserver<'a, P: FnMut(&str, f64)> {
    inner: &'a mut MotionRecorder,
    progress: &'a mut P,
    cycles: u32,
    last: u32,
}

impl<P: FnMut(&str, f64)> crate::damper::PointObserver for ProgressObserver<'_, P> {
    fn on_step(&mut self, w: &pdamp_dem::World, cycle: u32, phase: f64, d: &Damper) {
        self.inner.on_step(w, cycle, phase, d);
        let pct = ((cycle as f64 + phase / (2.0 * std::f64::consts::PI)) / self.cycles as f64
            * 1000.0) as u32;
        if pct != self.last {
            self.last = pct;
            (self.progress)("running", pct as f64 / 1000.0);
        }
    }

    fn reads_particles(&self) -> bool {
        self.inner.reads_particles()
    }

    fn save_state(&self) -> Result<Vec<u8>, DesignError> {
        self.inner.save_state()
    }

    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), DesignError> {
        self.inner.restore_state(bytes)
    }
}

/// Writes the phase-averaged velocity fields: one row per phase and occupied cell.
pub fn write_velocity_fields(rec: &MotionRecorder, path: &Path) -> Result<(), DesignError> {
    let rows = rec.fields.iter().flat_map(|f| {
        (0..f.count.len())
            .filter(|&c| f.count[c] > 0)
            .map(move |c| {
                let [x, y] = rec.cell_center(c);
                let n = f.count[c] as f64;
                [
                    f.phase_rad,
                    x,
                    y,
                    f.speed_sum[c] / n,
                    f.vel_sum[c][0] / n,
                    f.vel_sum[c][1] / n,
                    n,
                ]
            })
    });
    pdamp_io::csv::write_csv_atomic(
        path,
        &[
            "phase_rad",
            "x_m",
            "y_m",
            "speed_over_v",
            "vx_over_v",
            "vy_over_v",
            "samples",
        ],
        rows,
    )
    .map_err(DesignError::write_csv(path))
}

/// `pdamp fields`: settles the damper once, runs the grid (resumable) and writes `fields.csv`
/// and the maps.
pub fn run_fields_scenario(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    settle_progress: impl FnMut(f64),
    on_point: impl Fn(usize, usize) + Sync,
) -> Result<FieldsOutcome, DesignError> {
    let engine = crate::fields::PointEngine::Cpu(crate::fields::ThreadSplit::default());
    let cancel = CancelToken::new();
    run_fields_scenario_on(
        sc,
        base_dir,
        out,
        engine,
        settle_progress,
        on_point,
        &cancel,
    )
}

/// [`run_fields_scenario`] with the points on the CPU engine or the GPU backend (the beds are
/// prepared on the CPU either way); its points stop when `cancel` is cancelled.
pub fn run_fields_scenario_on(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    engine: crate::fields::PointEngine<'_>,
    settle_progress: impl FnMut(f64),
    on_point: impl Fn(usize, usize) + Sync,
    cancel: &CancelToken,
) -> Result<FieldsOutcome, DesignError> {
    run_fields_scenario_from(
        sc,
        base_dir,
        out,
        engine,
        BedSource::Prepare,
        settle_progress,
        on_point,
        cancel,
    )
}

/// Where the beds of a field's packings come from.
#[derive(Debug, Clone, Copy)]
pub enum BedSource<'a> {
    /// Prepared here (drop-down, settling) as the scenario says.
    Prepare,
    /// Read from [`prepared_bed_path`] in the given directory where a process saved it, else
    /// prepared here and saved there for the others: every task of a sweep, on whatever node,
    /// starts from the same bits and no bed is prepared twice.
    Saved(&'a Path),
}

/// File of the saved bed of packing `k` of a field or sweep in `dir`:
/// `dir/beds/packing_KKK.pdprep` ([`pdamp_scenario::prepare::save_prepared`]).
pub fn prepared_bed_path(dir: &Path, k: usize) -> std::path::PathBuf {
    dir.join("beds").join(format!("packing_{k:03}.pdprep"))
}

/// The damper of packing `k` of the field of `sc` (packing 0: the scenario's own seed; see
/// [`pdamp_scenario::prepare::scenario_for_packing`]), its bed taken from `beds`.
pub fn field_damper(
    sc: &Scenario,
    base_dir: &Path,
    k: usize,
    beds: BedSource<'_>,
    progress: impl FnMut(f64),
) -> Result<Damper, DesignError> {
    let sk = pdamp_scenario::prepare::scenario_for_packing(sc, k);
    let BedSource::Saved(dir) = beds else {
        return Damper::from_scenario(&sk, base_dir, progress);
    };
    let path = prepared_bed_path(dir, k);
    if let Some(prepared) =
        pdamp_scenario::prepare::load_prepared(&path, &sk, base_dir).map_err(DesignError::from)?
    {
        return Damper::from_prepared(&sk, prepared);
    }
    let mut progress = progress;
    let prepared = pdamp_scenario::prepare::prepare_bed(
        &sk,
        base_dir,
        &mut |_, f| progress(f),
        &pdamp_dem::time_loop::CancelToken::new(),
    )
    .map_err(DesignError::from)?;
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(DesignError::write(parent))?;
    }
    pdamp_scenario::prepare::save_prepared(&path, &prepared, &sk, base_dir)
        .map_err(DesignError::IoOutput)?;
    Damper::from_prepared(&sk, prepared)
}

/// [`run_fields_scenario_on`] with the beds from `beds` (a sweep's collect step reads the
/// beds its tasks saved and, with [`crate::fields::PointEngine::Stored`], only its store).
#[allow(clippy::too_many_arguments)]
pub fn run_fields_scenario_from(
    sc: &Scenario,
    base_dir: &Path,
    out: &Path,
    engine: crate::fields::PointEngine<'_>,
    beds: BedSource<'_>,
    mut settle_progress: impl FnMut(f64),
    on_point: impl Fn(usize, usize) + Sync,
    cancel: &CancelToken,
) -> Result<FieldsOutcome, DesignError> {
    let spec = sc.fields.as_ref().ok_or(DesignError::NoFieldsSection)?;
    let grid = FieldGrid::from_spec(spec)?;
    pdamp_scenario::provenance::write(sc, out).map_err(DesignError::write(out))?;
    // Stored points are reused only for the same physics: everything but the grid itself and
    // the single-point excitation must match.
    let mut physics = sc.clone();
    physics.fields = None;
    if let Some(d) = physics.damper.as_mut() {
        d.frequency_hz = None;
        d.amplitude_m = None;
        d.acceleration_m_s2 = None;
        d.intensity = None;
        d.motion_output = Default::default();
    }
    // The content of meshes and bed files counts, not only their paths.
    let fingerprint =
        physics.to_toml() + &pdamp_scenario::run::referenced_files_digest(sc, base_dir);
    let fp_path = out.join("points").join("scenario_physics.toml");
    std::fs::create_dir_all(out.join("points")).map_err(DesignError::write(out.join("points")))?;
    match std::fs::read_to_string(&fp_path) {
        Ok(old) if old != fingerprint => {
            return Err(DesignError::OtherScenario {
                out: out.to_path_buf(),
                fingerprint: fp_path,
            });
        }
        Ok(_) => {}
        Err(_) => {
            pdamp_io::atomic::write_atomic(&fp_path, fingerprint.as_bytes())
                .map_err(DesignError::write(&fp_path))?;
        }
    }
    let packings = sc.damper.as_ref().map_or(1, |d| d.packings);
    if packings == 1 {
        let damper =
            field_damper(sc, base_dir, 0, beds, &mut settle_progress)?.cancelled_by(cancel);
        let bed = damper.bed_statistics();
        write_bed_statistics(
            out,
            &serde_json::json!({ "bed": bed, "bed_at_fill": damper.fill_statistics }),
        )?;
        let outcome = crate::fields::run_fields_on(&damper, &grid, out, engine, on_point)?;
        crate::plots::field_maps_with(&grid, &outcome.points, out, damper.clearance_m())?;
        return Ok(outcome);
    }
    // An ensemble: every packing's field in packings/packing_KKK/ (resumable like a single
    // field), then the means, spreads and confidence intervals in fields.csv and the maps.
    let mut fields: Vec<FieldsOutcome> = Vec::with_capacity(packings);
    let mut clearances = Vec::with_capacity(packings);
    let total = grid.points().len() * packings;
    for k in 0..packings {
        let damper = field_damper(sc, base_dir, k, beds, |f| {
            settle_progress((k as f64 + f) / packings as f64)
        })?
        .cancelled_by(cancel);
        let dir = out.join("packings").join(format!("packing_{k:03}"));
        std::fs::create_dir_all(&dir).map_err(DesignError::write(&dir))?;
        let bed = damper.bed_statistics();
        write_bed_statistics(
            &dir,
            &serde_json::json!({ "bed": bed, "bed_at_fill": damper.fill_statistics }),
        )?;
        clearances.push(damper.clearance_m().unwrap_or(f64::NAN));
        let done_before = k * grid.points().len();
        let o = crate::fields::run_fields_on(&damper, &grid, &dir, engine, |d, _| {
            on_point(done_before + d, total)
        })?;
        fields.push(o);
    }
    let n = grid.points().len();
    let members =
        |i: usize| -> Vec<PointResult> { fields.iter().map(|o| o.points[i].clone()).collect() };
    let means: Vec<PointResult> = (0..n)
        .map(|i| crate::ensemble::mean_point(&members(i)))
        .collect();
    let mut columns: Vec<&str> = crate::fields::FIELD_COLUMNS.to_vec();
    columns.extend(crate::ensemble::ENSEMBLE_COLUMNS);
    let rows: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let mut r = crate::fields::field_row(&means[i]);
            r.extend(crate::ensemble::ensemble_row(&members(i)));
            r
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(out.join("fields.csv"), &columns, rows.iter().cloned())
        .map_err(DesignError::write_csv(out.join("fields.csv")))?;
    let h = EnsembleStat::of(&clearances);
    write_bed_statistics(
        out,
        &serde_json::json!({ "clearance_m": h, "packings": packings }),
    )?;
    crate::plots::field_maps_with(&grid, &means, out, Some(h.mean))?;
    let half: Vec<f64> = rows
        .iter()
        .map(|r| r[crate::fields::FIELD_COLUMNS.len() + 2])
        .collect();
    crate::plots::value_map(
        &grid,
        &half,
        out,
        "effective_loss_factor_ci95_half_width",
        &format!("95 % confidence half-width of η̄ over {packings} packings"),
        "±Δη̄ (-)",
    )?;
    Ok(FieldsOutcome {
        points: means,
        reused: fields.iter().map(|o| o.reused).sum(),
        failed: fields.into_iter().flat_map(|o| o.failed).collect(),
        bed_span_along_direction_m: [f64::NAN; 2],
    })
}

/// Writes the bed statistics of a field (`bed_statistics.json`: packing fraction, coordination
/// number, clearance h used for the X_opt = h/π line of the maps).
fn write_bed_statistics(dir: &Path, stats: &impl Serialize) -> Result<(), DesignError> {
    let json = serde_json::to_string_pretty(stats)?;
    let path = dir.join("bed_statistics.json");
    pdamp_io::atomic::write_atomic(&path, json.as_bytes()).map_err(DesignError::write(path))
}
