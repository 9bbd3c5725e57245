//! The cantilever study of paper Sect. 2.4: a 20 × 20 × 132 mm³ beam (clamped bottom face,
//! z = 0) with an 18 × 18 × 110 mm³ cavity starting 2 mm above the clamp (1 mm walls), filled
//! with powder at packing density ϕ, bent by a surface load q on the face x = 0 (q = 0.1 N/mm²,
//! resultant 264 N) ramped over 5 ms, held 1 ms and released; the tip displacement (top centre
//! point, x) decays freely. Scenario files: `examples/powder_cantilever_*.toml`, keys in
//! `docs/powder.md`.
//!
//! [`run_in_dir`] checkpoints a run (preparation and coupled run) into `DIR/checkpoint.bin`
//! and continues it with `resume`; the outputs then equal those of an uninterrupted run byte
//! for byte (wall times aside), see docs/reliability.md.

mod beam;
mod checkpoint;
mod cost;
mod outputs;
mod run;
mod validate;

use std::path::PathBuf;

use pdamp_io::checkpoint as ck;
pub use pdamp_scenario::run::RunOptions;
use serde::{Deserialize, Serialize};

pub use self::beam::{build_structure, cavity_interface, empty_beam_modes, timoshenko_reference};
pub use self::checkpoint::{
    CHECKPOINT_KIND, decode_preparation, inspect_checkpoint, scenario_digest,
};
pub use self::cost::CostEstimate;
pub use self::outputs::write_outputs;
pub use self::run::{run, run_in_dir};
use crate::couple::{CoupleError, CoupledEnergy, CouplingSettings};
use crate::damping::TableOneRatios;
use crate::error::ParameterError;
use crate::fe::gen_alpha::DynamicsError;
use crate::fe::{Aabb, BoxMeshDivisions, HexMesh, Kinematics, MassKind, Rayleigh, SvkMaterial};
use crate::health::HealthError;
use crate::law::PowderLaw;
use crate::prep::{PrepError, PrepReport, PrepSettings};
use crate::psd::LogNormal;
use crate::vtk::SnapshotError;
use pdamp_fem::EigenError;

fn d_len() -> f64 {
    0.132
}
fn d_width() -> f64 {
    0.020
}
fn d_wall() -> f64 {
    0.001
}
fn d_cav_len() -> f64 {
    0.110
}
fn d_cav_off() -> f64 {
    0.002
}
fn d_rho_inf() -> f64 {
    0.8
}
fn d_mass() -> MassKind {
    MassKind::Consistent
}

/// The beam (paper Sect. 2.4, Table A.3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSpec {
    /// Beam length \[m\] (0.132).
    #[serde(default = "d_len")]
    pub length_m: f64,
    /// Outer width of the square section \[m\] (0.020).
    #[serde(default = "d_width")]
    pub width_m: f64,
    /// Wall thickness around the cavity \[m\] (0.001).
    #[serde(default = "d_wall")]
    pub wall_thickness_m: f64,
    /// Cavity length \[m\] (0.110).
    #[serde(default = "d_cav_len")]
    pub cavity_length_m: f64,
    /// Distance of the cavity from the clamped face \[m\] (0.002).
    #[serde(default = "d_cav_off")]
    pub cavity_offset_m: f64,
    /// Material (Table A.3: 175 GPa, 0.27, 8000 kg/m³).
    #[serde(default = "d_mat")]
    pub material: SvkMaterial,
    /// Element size in the walls \[m\].
    pub wall_element_m: f64,
    /// Element size across the cavity \[m\].
    pub core_element_m: f64,
    /// Element size along the beam \[m\].
    pub length_element_m: f64,
    /// Mass matrix (`consistent` or `lumped`).
    #[serde(default = "d_mass")]
    pub mass: MassKind,
    /// Spectral radius ρ∞ of generalized-α (Table A.3: 0.8).
    #[serde(default = "d_rho_inf")]
    pub rho_inf: f64,
    /// Optional Rayleigh damping (off by default).
    #[serde(default)]
    pub rayleigh: Rayleigh,
    /// Finite (Saint Venant–Kirchhoff, the paper's model; default) or small deformation
    /// (`"linear"`: internal force K₀d, one solve per structure step).
    #[serde(default)]
    pub kinematics: Kinematics,
}

fn d_mat() -> SvkMaterial {
    SvkMaterial::STEEL_316L
}

impl BeamSpec {
    /// Cavity box \[m\].
    pub fn cavity(&self) -> Aabb {
        let t = self.wall_thickness_m;
        Aabb {
            min: [t, t, self.cavity_offset_m],
            max: [
                self.width_m - t,
                self.width_m - t,
                self.cavity_offset_m + self.cavity_length_m,
            ],
        }
    }
    /// The hex8 mesh.
    pub fn mesh(&self) -> HexMesh {
        HexMesh::box_with_cavity(
            [self.width_m, self.width_m, self.length_m],
            Some(self.cavity()),
            BoxMeshDivisions {
                wall_element_m: self.wall_element_m,
                core_element_m: self.core_element_m,
                length_element_m: self.length_element_m,
            },
        )
    }
    /// Element and node counts of [`BeamSpec::mesh`] (upper bounds, as f64 so that absurd
    /// sizes do not overflow), computed without building the mesh.
    pub fn mesh_size(&self) -> (f64, f64) {
        let div = |len: f64, h: f64| (len / h).round().max(1.0);
        let t = self.wall_thickness_m;
        let across =
            div(t, self.wall_element_m) * 2.0 + div(self.width_m - 2.0 * t, self.core_element_m);
        let top = self.length_m - self.cavity_offset_m - self.cavity_length_m;
        let along = div(self.cavity_offset_m, self.wall_element_m)
            + div(self.cavity_length_m, self.length_element_m)
            + div(top, self.length_element_m.min(self.core_element_m));
        (
            across * across * along,
            (across + 1.0) * (across + 1.0) * (along + 1.0),
        )
    }
}

/// Longest accepted beam dimension \[m\].
pub const MAX_LENGTH_M: f64 = 100.0;
/// Most structural elements a scenario may ask for.
pub const MAX_ELEMENTS: usize = 1_000_000;
/// Most particles a scenario may ask for.
pub const MAX_PARTICLES: usize = 10_000_000;
/// Most time steps (preparation or coupled run).
pub const MAX_STEPS: f64 = 1e8;
/// Most samples of tip.csv.
pub const MAX_SAMPLES: f64 = 1e7;
/// Most ParaView frames of a run (`run.vtk_interval_s`), as for DEM scenarios.
pub const MAX_VTK_FRAMES: f64 = 20_000.0;

/// The surface load on the face x = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// Pressure q \[Pa\] (0.1 N/mm² = 1e5 Pa), pushing in +x.
    pub pressure_pa: f64,
    /// Linear rise time \[s\] (5e-3).
    pub rise_s: f64,
    /// Hold time \[s\] (1e-3), then released.
    pub hold_s: f64,
}

fn d_ref_d50() -> f64 {
    1e-3
}
fn d_density() -> f64 {
    8000.0
}

/// The powder (paper Table A.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PowderSpec {
    /// Size distribution; cut-offs default to Table A.2 scaled to `d50_m`.
    pub d50_m: f64,
    /// σ of ln D (0.2707).
    #[serde(default = "d_sigma")]
    pub sigma: f64,
    /// Particle density [kg/m³] (8000).
    #[serde(default = "d_density")]
    pub density_kg_m3: f64,
    /// Contact law at the reference size `reference_d50_m` (Table A.2 values for 1 mm).
    pub law: PowderLaw,
    /// Size the law parameters refer to \[m\]; with f = d50_m / reference_d50_m the stiffness is
    /// scaled k' = f k and the surface energy γ' = f² γ (coarse-graining, Sect. 2.4/3.6).
    #[serde(default = "d_ref_d50")]
    pub reference_d50_m: f64,
    /// Preparation.
    pub prep: PrepSettings,
}

fn d_sigma() -> f64 {
    0.2707
}

impl PowderSpec {
    /// Size distribution.
    pub fn psd(&self) -> LogNormal {
        LogNormal {
            sigma: self.sigma,
            ..LogNormal::paper(self.d50_m)
        }
    }
    /// Law after coarse-graining.
    pub fn scaled_law(&self) -> PowderLaw {
        self.law.coarse_grained(self.d50_m / self.reference_d50_m)
    }
    /// Preparation settings of the simulated particles: a preparation surface energy is given
    /// like `law.surface_energy_j_m2` (for `reference_d50_m`) and coarse-grained the same way.
    pub fn scaled_prep(&self) -> PrepSettings {
        let f = self.d50_m / self.reference_d50_m;
        PrepSettings {
            surface_energy_j_m2: self.prep.surface_energy_j_m2.map(|g| g * f * f),
            ..self.prep
        }
    }
}

fn d_grav() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

/// Run control.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Simulated time after preparation \[s\] (paper: 0.03).
    pub duration_s: f64,
    /// Time step of DEM and FE \[s\] (paper: 2.5e-6 for D50 = 1 mm).
    pub time_step_s: f64,
    /// Gravity [m/s²] in beam coordinates (clamp at z = 0): [0,0,-9.81] upright (default),
    /// [0,0,9.81] upside down, [-9.81,0,0] horizontal with gravity along the excitation.
    #[serde(default = "d_grav")]
    pub gravity_m_s2: [f64; 3],
    /// Coupling settings (ε of eq. 16 = 1e-3).
    #[serde(default)]
    pub coupling: CouplingSettings,
    /// Sampling interval of tip.csv \[s\] (0 = every step).
    #[serde(default)]
    pub output_interval_s: f64,
    /// Interval of the ParaView frames (particles and deformed structure,
    /// `particles.pvd`) \[s\]; 0 = none. Default 1 ms.
    #[serde(default = "d_vtk_interval")]
    pub vtk_interval_s: f64,
}

fn d_vtk_interval() -> f64 {
    1e-3
}

/// Errors of the cantilever scenario and its runs. Texts starting with
/// [`pdamp_io::checkpoint::INTERRUPTED`] are runs stopped on request
/// ([`CantileverError::Interrupted`]).
#[derive(Debug, thiserror::Error)]
pub enum CantileverError {
    /// A key of the scenario is out of range (also `--checkpoint-interval-s`).
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The scenario exceeds a size limit ([`MAX_PARTICLES`], [`MAX_STEPS`]).
    #[error("{keys}: {estimate}; {limit}")]
    TooLarge {
        /// The keys that set the size.
        keys: &'static str,
        /// What the scenario would cost.
        estimate: CostEstimate,
        /// The limit exceeded and the fix.
        limit: String,
    },
    /// The time step is too long for the stiffest contact of the powder.
    #[error(
        "run.time_step_s = {time_step_s:.3e} s is {ratio:.2} of the shortest contact time {contact_time_s:.3e} s (particles of {diameter_m:.3e} m, k = {stiffness_n_m:.4e} N/m after coarse-graining); velocity Verlet needs less than {max_ratio}: use at most {:.3e} s (1/10 of the contact time)",
        0.1 * .contact_time_s
    )]
    TimeStep {
        /// `run.time_step_s` \[s\].
        time_step_s: f64,
        /// Its ratio to the contact time.
        ratio: f64,
        /// Shortest contact time \[s\].
        contact_time_s: f64,
        /// Diameter of the smallest particles \[m\].
        diameter_m: f64,
        /// Normal stiffness after coarse-graining (N/m).
        stiffness_n_m: f64,
        /// Largest allowed ratio ([`crate::health::MAX_STEP_RATIO`]).
        max_ratio: f64,
    },
    /// The scenario's TOML does not parse.
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// The scenario cannot be written as TOML for its digest.
    #[error("scenario: {0}")]
    Digest(#[source] toml::ser::Error),
    /// A checkpoint could not be written, read or decoded (pdamp-io).
    #[error(transparent)]
    Checkpoint(#[from] pdamp_io::checkpoint::CheckpointError),
    /// The run was stopped on request after its checkpoint was written.
    #[error("{0}")]
    Interrupted(ck::Interrupted),
    /// The preparation stopped without a checkpoint to continue from.
    #[error("preparation stopped")]
    PreparationStopped,
    /// A checkpoint holds no preparation ([`decode_preparation`]).
    #[error("not a preparation")]
    NotPreparation,
    /// A saved preparation is inconsistent.
    #[error(transparent)]
    Preparation(#[from] PrepError),
    /// Neither a prepared powder nor a checkpoint to start the coupled run from (a defect).
    #[error("internal: neither a prepared powder nor a checkpoint")]
    NoStart,
    /// The structure's time integration failed.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// The coupled step (or building the coupled system) failed.
    #[error(transparent)]
    Couple(#[from] CoupleError),
    /// A health check of the preparation or the coupled run failed.
    #[error(transparent)]
    Health(#[from] Box<HealthError>),
    /// The modal analysis failed.
    #[error(transparent)]
    Modes(#[from] EigenError),
    /// A ParaView frame could not be written.
    #[error(transparent)]
    Snapshot(#[from] SnapshotError),
    /// A CSV output could not be written.
    #[error(transparent)]
    Csv(#[from] pdamp_io::csv::CsvError),
    /// A plot could not be written.
    #[error(transparent)]
    Plot(#[from] pdamp_plot::PlotError),
    /// A file or folder could not be read or created.
    #[error("{path}: {source}")]
    File {
        /// The file or folder.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A JSON file (the summary of a finished run) could not be decoded.
    #[error("{path}: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// The decoding error.
        source: serde_json::Error,
    },
    /// The summary could not be encoded as JSON.
    #[error("{0}")]
    Encode(#[source] serde_json::Error),
    /// An output file could not be written.
    #[error("{source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// A cantilever scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CantileverScenario {
    /// Beam.
    pub beam: BeamSpec,
    /// Load.
    pub load: LoadSpec,
    /// Powder; absent = empty beam.
    pub powder: Option<PowderSpec>,
    /// Run.
    pub run: RunSpec,
}

impl CantileverScenario {
    /// Parses and validates TOML; errors name the key.
    pub fn from_toml(text: &str) -> Result<Self, CantileverError> {
        let s: Self = toml::from_str(text)?;
        s.validate()?;
        Ok(s)
    }

    /// Checks that every number is finite and in its physical range, and that the run fits
    /// the size limits ([`MAX_PARTICLES`], [`MAX_ELEMENTS`], [`MAX_STEPS`], [`MAX_SAMPLES`];
    /// the message carries the [`CostEstimate`]); nothing is allocated before. The error
    /// names the key, the value and the fix.
    pub fn validate(&self) -> Result<(), CantileverError> {
        self.beam.validate()?;
        self.validate_load_and_run()?;
        self.validate_powder()?;
        self.validate_cost()
    }
}

/// Time series and results of a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CantileverResult {
    /// Sample times \[s\].
    #[serde(skip)]
    pub time_s: Vec<f64>,
    /// Tip displacement in x \[m\].
    #[serde(skip)]
    pub tip_m: Vec<f64>,
    /// Coupling iterations of the sampled steps.
    #[serde(skip)]
    pub iterations: Vec<f64>,
    /// Energy samples.
    #[serde(skip)]
    pub energy: Vec<(f64, CoupledEnergy)>,
    /// Table-1 damping ratios.
    pub damping: TableOneRatios,
    /// Largest tip displacement before release \[m\].
    pub max_tip_before_release_m: f64,
    /// Preparation report (None for an empty beam).
    pub prep: Option<PrepReport>,
    /// Particles.
    pub particles: usize,
    /// Structural dofs / elements.
    pub structure_dofs: usize,
    /// Elements.
    pub elements: usize,
    /// Interface dofs $n^{ps}_{dof}$.
    pub interface_dofs: usize,
    /// Steps.
    pub steps: u64,
    /// Mean fixed-point iterations per step.
    pub mean_iterations: f64,
    /// Largest iteration count of a step.
    pub max_iterations: usize,
    /// Wall time of the coupled run (without preparation) \[s\].
    pub wall_time_s: f64,
    /// Mass of the structure and of the powder \[kg\].
    pub structure_mass_kg: f64,
    /// Powder mass \[kg\].
    pub powder_mass_kg: f64,
    /// Largest |balance − balance(0)| / max stored energy over the run.
    pub energy_closure: f64,
    /// Wall time of the coupled steps by partition (particles, structure, coupling) in this
    /// process (a resumed run counts from the resume).
    #[serde(default)]
    pub coupled_step_wall_time_s: crate::couple::StepTiming,
}
