//! Bed preparation as a scenario says: build the world (placing or dropping the particles,
//! [`Scenario::build_world_reporting`]), settle it (`[settle]`, with the "turn" of a container
//! filled under another gravity, D Sect. 8.1.1) and measure the bed
//! ([`pdamp_dem::bed_statistics`]). Used by `pdamp settle`, damper points, effective fields and
//! ensembles, so that every command makes its beds the same way.

use crate::InputError;
use crate::error::Source;
pub use crate::schema::excitation_direction;
use crate::schema::{Preparation, Scenario};
use pdamp_dem::bed_statistics::{BedStatistics, bed_statistics};
use pdamp_dem::drop_down::DropDownReport;
use pdamp_dem::time_loop::CancelToken;
use pdamp_dem::{Bed, Vec3, World};
use pdamp_io::bed::{BedFile, save_bed};
use pdamp_io::checkpoint::CheckpointError;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Why a bed cannot be prepared, saved or read back.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    /// The scenario's world cannot be built.
    #[error(transparent)]
    Input(#[from] InputError),
    /// A bed or prepared-bed file cannot be written, or is refused.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// A saved prepared bed cannot be used.
    #[error("prepared bed {}: {cause}", path.display())]
    Prepared {
        /// The file.
        path: PathBuf,
        /// Why.
        cause: Source,
    },
    /// An output file cannot be written.
    #[error("output: {0}")]
    Output(Source),
    /// The summary does not serialise.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

impl PrepareError {
    fn prepared(path: impl Into<PathBuf>, source: impl Into<Source>) -> Self {
        Self::Prepared {
            path: path.into(),
            cause: source.into(),
        }
    }
}

/// A settled bed in its world.
#[derive(Debug, Clone)]
pub struct PreparedBed {
    /// The world after settling (clock at zero, bodies at their reference poses).
    pub world: World,
    /// Settling time (both stages), s.
    pub settling_time_s: f64,
    /// What each drop-down group did.
    pub drop_down: Vec<DropDownReport>,
    /// Statistics of the bed as filled, before the container was "turned" (only for a fill under
    /// `settle.gravity_m_s2`): its clearance along the excitation is the h of D Eq. 8.1/8.2 — the
    /// gap the filled bed leaves to the cap —, which the turned bed no longer shows along the
    /// axis.
    pub fill_statistics: Option<BedStatistics>,
}

/// Seed of packing `k` of an ensemble: packing 0 is the scenario's own seed, the others are
/// spaced far apart so that the size draws and insertions of different packings and groups
/// never share a stream.
pub fn packing_seed(seed: u64, k: usize) -> u64 {
    seed.wrapping_add(1_000_003u64.wrapping_mul(k as u64))
}

/// The scenario with the seed of packing `k` ([`packing_seed`]).
pub fn scenario_for_packing(scenario: &Scenario, k: usize) -> Scenario {
    let mut s = scenario.clone();
    s.simulation.seed = packing_seed(scenario.simulation.seed, k);
    s
}

/// Builds and settles the bed of `scenario` (paths relative to `base_dir`);
/// `progress(phase, fraction)` follows the drop-down and the settling; a drop-down stops when
/// `cancel` is cancelled.
pub fn prepare_bed(
    scenario: &Scenario,
    base_dir: &Path,
    progress: &mut dyn FnMut(&str, f64),
    cancel: &CancelToken,
) -> Result<PreparedBed, PrepareError> {
    let (mut world, drop_down) =
        scenario.build_world_reporting(base_dir, Preparation::Full, progress, cancel)?;
    // A damper's bed is made in the container at rest (its excitation belongs to the points).
    if let Some(d) = &scenario.damper
        && let Some(b) = world.bodies.iter_mut().find(|b| b.name == d.container_body)
    {
        b.motion = pdamp_dem::Motion::Fixed;
    }
    let main_gravity = world.gravity_m_s2;
    let mut fill_statistics = None;
    let settling_time_s = match &scenario.settle {
        Some(s) => {
            let t = crate::run::settle_with(&mut world, s, |f| progress("settling", f));
            let turned = s
                .gravity_m_s2
                .is_some_and(|g| Vec3::from(g) != main_gravity);
            if turned {
                // Measured under the filling gravity (settle_with put the run's back).
                let mut filled = world.clone();
                filled.gravity_m_s2 = Vec3::from(s.gravity_m_s2.unwrap_or([0.0; 3]));
                fill_statistics = Some(bed_statistics(&filled, excitation_direction(scenario)));
            }
            t + if turned {
                crate::run::settle_after_turn(
                    &mut world,
                    s.turn_max_duration_s.unwrap_or(s.max_duration_s),
                    s.kinetic_energy_per_particle_j,
                    |f| progress("settling", f),
                )
            } else {
                0.0
            }
        }
        None => {
            world.initialize();
            0.0
        }
    };
    Ok(PreparedBed {
        world,
        settling_time_s,
        drop_down,
        fill_statistics,
    })
}

/// Kind tag of prepared-bed files ([`save_prepared`]).
pub const PREPARED_KIND: &str = "prepared-bed";

/// What [`save_prepared`] stores: the full dynamic state of the prepared world and what the
/// preparation did.
#[derive(Serialize, serde::Deserialize)]
struct PreparedFile {
    state: pdamp_dem::WorldState,
    settling_time_s: f64,
    drop_down: Vec<DropDownReport>,
    fill_statistics: Option<BedStatistics>,
}

/// Saves a prepared bed to `path` (atomic; the checkpoint framing of [`pdamp_io::checkpoint`],
/// kind [`PREPARED_KIND`], keyed by [`crate::provenance::scenario_content_digest`] of `scenario`),
/// so that another process — a task of a sweep on another node — continues from the same bits
/// with [`load_prepared`] instead of preparing the bed again.
pub fn save_prepared(
    path: &Path,
    prepared: &PreparedBed,
    scenario: &Scenario,
    base_dir: &Path,
) -> Result<(), CheckpointError> {
    let digest = crate::provenance::scenario_content_digest(scenario, base_dir);
    pdamp_io::checkpoint::save(
        path,
        &pdamp_io::checkpoint::CheckpointHeader::new(PREPARED_KIND, &digest),
        &PreparedFile {
            state: prepared.world.save_state(),
            settling_time_s: prepared.settling_time_s,
            drop_down: prepared.drop_down.clone(),
            fill_statistics: prepared.fill_statistics.clone(),
        },
    )
}

/// Reads a bed saved by [`save_prepared`] for `scenario` (paths relative to `base_dir`): the
/// world is built from the scenario's bodies and walls without its particles, then the saved
/// particles and their state are put in, so that it equals bit for bit the world
/// [`prepare_bed`] made. `Ok(None)` when there is no file; a file of another scenario (or a
/// changed mesh or table), another pdamp format or a damaged file is refused with the reason.
pub fn load_prepared(
    path: &Path,
    scenario: &Scenario,
    base_dir: &Path,
) -> Result<Option<PreparedBed>, PrepareError> {
    let digest = crate::provenance::scenario_content_digest(scenario, base_dir);
    let Some(f) = pdamp_io::checkpoint::load::<PreparedFile>(path, PREPARED_KIND, &digest)
        .map_err(|e| match e {
            CheckpointError::Io { path, cause } => PrepareError::prepared(path, cause),
            CheckpointError::InFile { path, cause } => PrepareError::prepared(path, *cause),
            e => PrepareError::Checkpoint(e),
        })?
    else {
        return Ok(None);
    };
    let mut world =
        scenario.build_world_with(base_dir, crate::schema::Preparation::Check, &mut |_, _| {})?;
    let why = |e: pdamp_dem::state::StateError| PrepareError::prepared(path, e);
    world.set_particles_of(&f.state).map_err(why)?;
    world.restore_state(f.state).map_err(why)?;
    if let Some(d) = &scenario.damper
        && let Some(b) = world.bodies.iter_mut().find(|b| b.name == d.container_body)
    {
        b.motion = pdamp_dem::Motion::Fixed;
    }
    Ok(Some(PreparedBed {
        world,
        settling_time_s: f.settling_time_s,
        drop_down: f.drop_down,
        fill_statistics: f.fill_statistics,
    }))
}

/// `summary.json` of `pdamp settle`.
#[derive(Debug, Clone, Serialize)]
pub struct SettleSummary {
    /// pdamp version.
    pub pdamp_version: String,
    /// Scenario title.
    pub title: String,
    /// Digest of the scenario.
    pub scenario_digest: String,
    /// Seed of this bed.
    pub seed: u64,
    /// Bed statistics.
    pub bed: BedStatistics,
    /// Statistics of the bed as filled, before the "turn" (fills under `settle.gravity_m_s2`).
    pub bed_at_fill: Option<BedStatistics>,
    /// What each drop-down group did.
    pub drop_down: Vec<DropDownReport>,
    /// Settling time, s.
    pub settling_time_s: f64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Files written (relative to the output directory).
    pub files: Vec<String>,
}

/// `pdamp settle`: prepares the bed of `scenario` and writes into `out` the native bed
/// `bed.pdbed` (exact continuation), `bed.csv` and `bed.data` (LAMMPS `atom_style sphere`, SI)
/// for other codes, `bed.vtp` (ParaView), `summary.json` with the statistics, and
/// `provenance.json`.
pub fn settle_scenario(
    scenario: &Scenario,
    base_dir: &Path,
    out: &Path,
    progress: &mut dyn FnMut(&str, f64),
    cancel: &CancelToken,
) -> Result<SettleSummary, PrepareError> {
    let start = std::time::Instant::now();
    let io = |e: std::io::Error| PrepareError::Output(e.into());
    let prepared = prepare_bed(scenario, base_dir, progress, cancel)?;
    let world = &prepared.world;
    crate::provenance::write(scenario, out).map_err(io)?;
    let stats = bed_statistics(world, excitation_direction(scenario));
    let digest = crate::provenance::scenario_digest(scenario);
    let bed = Bed::from_world(world);
    save_bed(
        &out.join("bed.pdbed"),
        &BedFile {
            bed: bed.clone(),
            statistics: Some(stats.clone()),
            drop_down: prepared.drop_down.first().cloned(),
            settling_time_s: prepared.settling_time_s,
            state: Some(world.save_state()),
        },
        &digest,
    )?;
    pdamp_io::atomic::write_atomic(
        out.join("bed.csv"),
        pdamp_io::bed_formats::write_bed_csv(&bed).as_bytes(),
    )
    .map_err(io)?;
    let densities: Vec<f64> = world.materials.iter().map(|m| m.density_kg_m3).collect();
    let p = &world.particles;
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (x, r) in p.position.iter().zip(&p.radius) {
        for k in 0..3 {
            lo[k] = lo[k].min(x[k] - r);
            hi[k] = hi[k].max(x[k] + r);
        }
    }
    pdamp_io::atomic::write_atomic(
        out.join("bed.data"),
        pdamp_io::bed_formats::write_lammps_data(&bed, &densities, (lo, hi)).as_bytes(),
    )
    .map_err(io)?;
    pdamp_io::vtk::write_particles_vtp(
        out.join("bed.vtp"),
        &p.position,
        &p.radius,
        &[
            (
                "velocity_m_s",
                pdamp_io::vtk::PointField::Vector(&p.velocity),
            ),
            (
                "material",
                pdamp_io::vtk::PointField::Int(
                    &p.material.iter().map(|&m| m as u32).collect::<Vec<_>>(),
                ),
            ),
        ],
    )
    .map_err(|e| PrepareError::Output(e.into()))?;
    let summary = SettleSummary {
        pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
        title: scenario.title.clone(),
        scenario_digest: digest,
        seed: scenario.simulation.seed,
        bed: stats,
        bed_at_fill: prepared.fill_statistics.clone(),
        drop_down: prepared.drop_down,
        settling_time_s: prepared.settling_time_s,
        wall_time_s: start.elapsed().as_secs_f64(),
        files: [
            "bed.pdbed",
            "bed.csv",
            "bed.data",
            "bed.vtp",
            "summary.json",
        ]
        .map(String::from)
        .to_vec(),
    };
    let json = serde_json::to_string_pretty(&summary)?;
    pdamp_io::atomic::write_atomic(out.join("summary.json"), json.as_bytes()).map_err(io)?;
    Ok(summary)
}
