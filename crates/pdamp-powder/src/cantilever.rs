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

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

use pdamp_io::checkpoint::{self as ck, CheckpointHeader, CheckpointTimer};
pub use pdamp_io::run::RunOptions;
use serde::{Deserialize, Serialize};

use crate::bed::PowderBed;
use crate::couple::{
    CoupleError, Coupled, CoupledEnergy, CoupledState, CouplingSettings, Interface,
};
use crate::damping::{self, TableOneRatios};
use crate::error::ParameterError;
use crate::fe::gen_alpha::DynamicsError;
use crate::fe::sparse::SolverError;
use crate::fe::{
    self, Aabb, BoxMeshDivisions, Dynamics, GenAlpha, HexMesh, LoadRamp, MassKind, Rayleigh,
    Structure, SurfaceLoad, SvkMaterial,
};
use crate::health::HealthError;
use crate::law::PowderLaw;
use crate::prep::{PrepError, PrepReport, PrepSettings, Preparation};
use crate::psd::LogNormal;
use crate::vtk::SnapshotError;

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
    fn validate(&self) -> Result<(), ParameterError> {
        let len = |v: f64, k: &str| {
            if v > 0.0 && v <= MAX_LENGTH_M {
                Ok(())
            } else {
                Err(ParameterError::out_of_range(
                    format!("beam.{k}"),
                    v,
                    format!("must be a finite length in (0, {MAX_LENGTH_M}] m"),
                ))
            }
        };
        len(self.length_m, "length_m")?;
        len(self.width_m, "width_m")?;
        len(self.wall_thickness_m, "wall_thickness_m")?;
        len(self.cavity_length_m, "cavity_length_m")?;
        len(self.wall_element_m, "wall_element_m")?;
        len(self.core_element_m, "core_element_m")?;
        len(self.length_element_m, "length_element_m")?;
        let m = &self.material;
        if !(m.youngs_modulus_pa > 0.0 && m.youngs_modulus_pa <= 1e13) {
            return Err(ParameterError::out_of_range(
                "beam.material.youngs_modulus_pa",
                m.youngs_modulus_pa,
                "must be a finite modulus in (0, 1e13] Pa (Table A.3: 175e9)",
            ));
        }
        if !(m.density_kg_m3 > 0.0 && m.density_kg_m3 <= 1e5) {
            return Err(ParameterError::out_of_range(
                "beam.material.density_kg_m3",
                m.density_kg_m3,
                "must be in (0, 1e5] kg/m³ (Table A.3: 8000)",
            ));
        }
        if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return Err(ParameterError::out_of_range(
                "beam.material.poisson_ratio",
                m.poisson_ratio,
                "must be in (-1, 0.5)",
            ));
        }
        if 2.0 * self.wall_thickness_m >= self.width_m {
            return Err(ParameterError::invalid(
                "beam.wall_thickness_m",
                "must be less than half of width_m",
            ));
        }
        if !(self.cavity_offset_m > 0.0
            && self.cavity_offset_m + self.cavity_length_m < self.length_m)
        {
            return Err(ParameterError::out_of_range(
                "beam.cavity_offset_m",
                self.cavity_offset_m,
                "cavity must lie strictly inside the beam (0 < offset, offset + cavity_length_m < length_m)",
            ));
        }
        if !(0.0..=1.0).contains(&self.rho_inf) {
            return Err(ParameterError::out_of_range(
                "beam.rho_inf",
                self.rho_inf,
                "must be in [0, 1]",
            ));
        }
        for (k, v) in [
            ("mass_coeff_per_s", self.rayleigh.mass_coeff_per_s),
            ("stiffness_coeff_s", self.rayleigh.stiffness_coeff_s),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(ParameterError::out_of_range(
                    format!("beam.rayleigh.{k}"),
                    v,
                    "must be finite and ≥ 0",
                ));
            }
        }
        let (elements, nodes) = self.mesh_size();
        if elements > MAX_ELEMENTS as f64 {
            return Err(ParameterError::invalid(
                "beam.wall_element_m / core_element_m / length_element_m",
                format!(
                    "the mesh would have ≈ {elements:.3e} elements and {nodes:.3e} nodes (≈ {:.1} GB for the element data and matrices, before the factorization's fill-in), more than {MAX_ELEMENTS}; use larger element sizes",
                    elements * BYTES_PER_ELEMENT / 1e9
                ),
            ));
        }
        Ok(())
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
/// Memory per structural element, estimated (Gauss data, mass and stiffness matrices) [B].
const BYTES_PER_ELEMENT: f64 = 10e3;
/// Memory per particle, estimated (state, pair list, wall contacts, checkpoint copy) [B].
const BYTES_PER_PARTICLE: f64 = 2e3;
/// CPU time per particle and step, measured on the paper runs (≈ 1/3 of 56–140 ms per step
/// for 32 000 particles) [s].
const CPU_S_PER_PARTICLE_STEP: f64 = 1e-6;
/// CPU time per structural dof and coupled step (≈ 2/3 of a step for 19 008 dofs) [s].
const CPU_S_PER_DOF_STEP: f64 = 3e-6;

/// What a scenario will cost, estimated before anything is allocated
/// ([`CantileverScenario::estimate`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CostEstimate {
    /// Particles (mean particle volume of the truncated distribution).
    pub particles: f64,
    /// Structural elements (upper bound).
    pub elements: f64,
    /// Structural dofs (upper bound).
    pub dofs: f64,
    /// Coupled steps.
    pub steps: f64,
    /// Preparation steps (upper bound: settling and relaxation limits).
    pub prep_steps: f64,
    /// Memory \[B\].
    pub memory_bytes: f64,
    /// CPU time \[s\] (one core).
    pub cpu_s: f64,
}

impl std::fmt::Display for CostEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "≈ {:.3e} particles, {:.3e} elements, {:.3e} coupled steps and ≤ {:.3e} preparation steps: ≈ {:.2} GB of memory and ≈ {:.1} h of one core",
            self.particles,
            self.elements,
            self.steps,
            self.prep_steps,
            self.memory_bytes / 1e9,
            self.cpu_s / 3600.0
        )
    }
}

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
    Solver(#[from] SolverError),
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

    /// `[load]` and `[run]` (time step, gravity, output, coupling).
    fn validate_load_and_run(&self) -> Result<(), CantileverError> {
        let (l, r) = (&self.load, &self.run);
        let e = self.beam.material.youngs_modulus_pa;
        if !(l.pressure_pa.is_finite() && l.pressure_pa.abs() <= 1e-3 * e) {
            return Err(ParameterError::out_of_range(
                "load.pressure_pa",
                l.pressure_pa,
                format!(
                    "must be finite with |q| ≤ 1e-3 of beam.material.youngs_modulus_pa ({:.3e} Pa; larger loads bend the beam beyond the elastic range)",
                    1e-3 * e
                ),
            )
            .into());
        }
        if !(l.rise_s > 0.0 && l.rise_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "load.rise_s",
                l.rise_s,
                "must be in (0, 1000] s",
            )
            .into());
        }
        if !(l.hold_s >= 0.0 && l.hold_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "load.hold_s",
                l.hold_s,
                "must be in [0, 1000] s",
            )
            .into());
        }
        if !(r.duration_s > 0.0 && r.duration_s <= 1e3) {
            return Err(ParameterError::out_of_range(
                "run.duration_s",
                r.duration_s,
                "must be in (0, 1000] s",
            )
            .into());
        }
        if !(r.time_step_s > 0.0 && r.time_step_s < r.duration_s) {
            return Err(ParameterError::out_of_range(
                "run.time_step_s",
                r.time_step_s,
                "must be positive and below duration_s",
            )
            .into());
        }
        let g = r.gravity_m_s2;
        if !(g.iter().all(|x| x.is_finite()) && g.iter().map(|x| x * x).sum::<f64>() <= 1e6) {
            return Err(ParameterError::invalid(
                "run.gravity_m_s2",
                format!("must be finite with |g| ≤ 1000 m/s², got {g:?}"),
            )
            .into());
        }
        if !(r.output_interval_s >= 0.0 && r.output_interval_s <= r.duration_s) {
            return Err(ParameterError::out_of_range(
                "run.output_interval_s",
                r.output_interval_s,
                "must be in [0, duration_s] (0 = every step)",
            )
            .into());
        }
        if !(r.vtk_interval_s >= 0.0 && r.vtk_interval_s.is_finite()) {
            return Err(ParameterError::out_of_range(
                "run.vtk_interval_s",
                r.vtk_interval_s,
                "must be finite and >= 0 (seconds between ParaView frames, 0 = none)",
            )
            .into());
        }
        let c = &r.coupling;
        if !(c.tolerance > 0.0 && c.tolerance.is_finite()) {
            return Err(ParameterError::out_of_range(
                "run.coupling.tolerance",
                c.tolerance,
                "must be finite and positive (eq. 16: 1e-3 m/s)",
            )
            .into());
        }
        if !(1..=10_000).contains(&c.max_iterations) {
            return Err(ParameterError::invalid(
                "run.coupling.max_iterations",
                format!("must be in [1, 10000], got {}", c.max_iterations),
            )
            .into());
        }
        if !(c.initial_relaxation > 0.0 && c.initial_relaxation <= 2.0) {
            return Err(ParameterError::out_of_range(
                "run.coupling.initial_relaxation",
                c.initial_relaxation,
                "must be in (0, 2]",
            )
            .into());
        }
        Ok(())
    }

    /// `[powder]`: law, size distribution, density, preparation, fit in the cavity.
    fn validate_powder(&self) -> Result<(), CantileverError> {
        if let Some(p) = &self.powder {
            p.law.validate("powder.law.")?;
            p.psd().validate("powder.")?;
            if !(p.density_kg_m3 > 0.0 && p.density_kg_m3 <= 1e5) {
                return Err(ParameterError::out_of_range(
                    "powder.density_kg_m3",
                    p.density_kg_m3,
                    "must be in (0, 1e5] kg/m³",
                )
                .into());
            }
            let f = p.d50_m / p.reference_d50_m;
            if !(p.reference_d50_m > 0.0 && (1e-3..=1e3).contains(&f)) {
                return Err(ParameterError::out_of_range(
                    "powder.reference_d50_m",
                    p.reference_d50_m,
                    "must be positive with d50_m / reference_d50_m in [1e-3, 1e3]",
                )
                .into());
            }
            let s = &p.prep;
            if !(s.packing_density > 0.0 && s.packing_density < 0.74) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.packing_density",
                    s.packing_density,
                    "must be in (0, 0.74)",
                )
                .into());
            }
            if !(s.settling_gravity_factor >= 1.0 && s.settling_gravity_factor <= 1e4) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.settling_gravity_factor",
                    s.settling_gravity_factor,
                    "must be in [1, 1e4]",
                )
                .into());
            }
            if !(s.plate_speed_m_s > 0.0 && s.plate_speed_m_s <= 100.0) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.plate_speed_m_s",
                    s.plate_speed_m_s,
                    "must be in (0, 100] m/s",
                )
                .into());
            }
            if !(s.relax_time_s >= 0.0 && s.relax_time_s <= 1e3) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.relax_time_s",
                    s.relax_time_s,
                    "must be in [0, 1000] s",
                )
                .into());
            }
            if !(s.max_settling_time_s > 0.0 && s.max_settling_time_s <= 1e3) {
                return Err(ParameterError::out_of_range(
                    "powder.prep.max_settling_time_s",
                    s.max_settling_time_s,
                    "must be in (0, 1000] s",
                )
                .into());
            }
            let gap = self.beam.width_m - 2.0 * self.beam.wall_thickness_m;
            if p.psd().d_max_m * 1.02 > gap.min(self.beam.cavity_length_m) {
                return Err(ParameterError::invalid(
                    "powder.d50_m",
                    format!(
                        "the largest particles ({:.3e} m) do not fit the cavity ({gap:.3e} m across); use a smaller d50_m",
                        p.psd().d_max_m
                    ),
                )
                .into());
            }
        }
        Ok(())
    }

    /// Particles, steps, samples and frames within the limits, and the time step against the stiffest contact.
    fn validate_cost(&self) -> Result<(), CantileverError> {
        let r = &self.run;
        let est = self.estimate();
        if est.particles > MAX_PARTICLES as f64 {
            return Err(CantileverError::TooLarge {
                keys: "powder.d50_m / powder.prep.packing_density",
                estimate: est,
                limit: format!(
                    "more than {MAX_PARTICLES} particles; use a larger d50_m (coarse-graining with reference_d50_m)"
                ),
            });
        }
        if est.steps > MAX_STEPS {
            return Err(CantileverError::TooLarge {
                keys: "run.duration_s / run.time_step_s",
                estimate: est,
                limit: format!(
                    "more than {MAX_STEPS:e} steps; shorten duration_s or lengthen time_step_s"
                ),
            });
        }
        if est.prep_steps > MAX_STEPS {
            return Err(CantileverError::TooLarge {
                keys: "powder.prep.max_settling_time_s / relax_time_s",
                estimate: est,
                limit: format!(
                    "more than {MAX_STEPS:e} preparation steps at run.time_step_s; shorten them"
                ),
            });
        }
        if let Some(p) = &self.powder {
            // the stiffest contact: two of the smallest particles, coarse-grained stiffness
            let law = p.scaled_law();
            let dmin = p.psd().d_min_m;
            let m = p.density_kg_m3 * std::f64::consts::PI / 6.0 * dmin.powi(3);
            let tc = std::f64::consts::PI * (0.5 * m / law.normal_stiffness_n_m).sqrt();
            let ratio = r.time_step_s / tc;
            if !(ratio <= crate::health::MAX_STEP_RATIO) {
                return Err(CantileverError::TimeStep {
                    time_step_s: r.time_step_s,
                    ratio,
                    contact_time_s: tc,
                    diameter_m: dmin,
                    stiffness_n_m: law.normal_stiffness_n_m,
                    max_ratio: crate::health::MAX_STEP_RATIO,
                });
            }
        }
        let every = (r.output_interval_s / r.time_step_s).round().max(1.0);
        if est.steps / every > MAX_SAMPLES {
            return Err(ParameterError::invalid(
                "run.output_interval_s",
                format!(
                    "{:.3e} samples of tip.csv, more than {MAX_SAMPLES:e}; use a larger output_interval_s",
                    est.steps / every
                ),
            )
            .into());
        }
        if r.vtk_interval_s > 0.0 && r.duration_s / r.vtk_interval_s > MAX_VTK_FRAMES {
            return Err(ParameterError::invalid(
                "run.vtk_interval_s",
                format!(
                    "{:.3e} ParaView frames over duration_s = {} s, more than {MAX_VTK_FRAMES}; use a larger interval (or 0 for none)",
                    r.duration_s / r.vtk_interval_s,
                    r.duration_s
                ),
            )
            .into());
        }
        Ok(())
    }

    /// Work and memory of the scenario, estimated without allocating anything (f64 so that
    /// absurd inputs do not overflow).
    pub fn estimate(&self) -> CostEstimate {
        let (elements, nodes) = self.beam.mesh_size();
        let dt = self.run.time_step_s;
        let steps = (self.run.duration_s / dt).round();
        let (particles, prep_steps) = match &self.powder {
            Some(p) => {
                let n =
                    p.prep.packing_density * self.beam.cavity().volume() / p.psd().mean_volume_m3();
                let s = &p.prep;
                // settling ≤ max_settling_time_s, relaxation ≤ relax + max_settling, holding;
                // compression: the bed top is at most the cavity's length above the top
                let comp = self.beam.cavity_length_m / (s.plate_speed_m_s * dt);
                (
                    n,
                    (2.0 * s.max_settling_time_s + 2.0 * s.relax_time_s) / dt + comp,
                )
            }
            None => (0.0, 0.0),
        };
        let dofs = 3.0 * nodes;
        CostEstimate {
            particles,
            elements,
            dofs,
            steps,
            prep_steps,
            memory_bytes: elements * BYTES_PER_ELEMENT + particles * BYTES_PER_PARTICLE,
            cpu_s: steps * (particles * CPU_S_PER_PARTICLE_STEP + dofs * CPU_S_PER_DOF_STEP)
                + prep_steps * particles * CPU_S_PER_PARTICLE_STEP,
        }
    }
}

/// Builds the structure of the scenario: mesh, clamp (z = 0), pressure on x = 0, gravity.
pub fn build_structure(beam: &BeamSpec, load: &LoadSpec, gravity: [f64; 3]) -> (Structure, usize) {
    let mesh = beam.mesh();
    let tol = 1e-9;
    let clamped = mesh.nodes_on_plane(2, 0.0, tol);
    let faces = mesh.boundary_faces();
    let loaded = HexMesh::faces_on_plane(&faces, &mesh.nodes, 0, 0.0, tol);
    let tip = mesh.nearest_node([0.5 * beam.width_m, 0.5 * beam.width_m, beam.length_m]);
    let mut s = Structure::new(mesh, beam.material, &clamped, beam.mass, gravity);
    s.loads.push(SurfaceLoad {
        faces: loaded,
        traction_pa: [load.pressure_pa, 0.0, 0.0],
        ramp: LoadRamp {
            rise_s: load.rise_s,
            hold_s: load.hold_s,
        },
    });
    (s, tip)
}

/// Interface faces: boundary faces with all nodes on the cavity box surface.
pub fn cavity_interface(s: &Structure, cavity: &Aabb) -> Interface {
    let tol = 1e-9;
    let faces = s
        .mesh
        .boundary_faces()
        .into_iter()
        .filter(|f| {
            f.nodes
                .iter()
                .all(|&n| cavity.contains(s.mesh.nodes[n], tol))
        })
        .collect();
    Interface::new(faces)
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

/// Kind tag of `pdamp powder run` checkpoints (`-2`: the coupled run's particles are a
/// pdamp-dem world; `-3`: the structure state says which precision its tangent factor has;
/// checkpoints of earlier layouts are refused by name).
pub const CHECKPOINT_KIND: &str = "powder-run-3";

/// Digest identifying a scenario in checkpoints (FNV-1a 64 of its canonical TOML).
pub fn scenario_digest(sc: &CantileverScenario) -> Result<String, CantileverError> {
    let text = toml::to_string(sc).map_err(CantileverError::Digest)?;
    Ok(ck::digest(text.as_bytes()))
}

/// What a checkpoint holds: the preparation in progress, or the coupled run in progress
/// (which starts with the prepared powder), or nothing once the outputs are written.
#[derive(Serialize, Deserialize)]
enum Phase {
    Preparing(Box<Preparation>),
    Running(Box<RunState>),
    Finished,
}

/// The coupled run after step `step`: the complete dynamic state and the results so far.
#[derive(Serialize, Deserialize)]
struct RunState {
    step: u64,
    coupled: CoupledState,
    prep: Option<PrepReport>,
    time_s: Vec<f64>,
    tip_m: Vec<f64>,
    iterations: Vec<f64>,
    energy: Vec<(f64, CoupledEnergy)>,
    max_tip_before_release_m: f64,
    wall_time_s: f64,
}

/// Where and how often a run checkpoints.
struct Checkpointing {
    path: PathBuf,
    header: CheckpointHeader,
    interval_s: f64,
}

impl Checkpointing {
    fn save(&self, phase: &Phase) -> Result<(), CantileverError> {
        ck::save(&self.path, &self.header, phase).map_err(CantileverError::from)
    }
    fn interrupted(&self, time_s: f64) -> CantileverError {
        CantileverError::Interrupted(ck::Interrupted {
            time_s,
            path: self.path.clone(),
        })
    }
}

/// Decodes a `pdamp powder run` checkpoint of any scenario and returns its phase and
/// simulated time \[s\] (for inspection and fuzzing; never panics).
pub fn inspect_checkpoint(bytes: &[u8]) -> Result<(&'static str, f64), CantileverError> {
    let phase = ck::decode::<Phase>(bytes, CHECKPOINT_KIND, None).map_err(CantileverError::from)?;
    Ok(match phase {
        Phase::Preparing(p) => ("preparing", p.time_s()),
        Phase::Running(r) => ("running", r.coupled.dynamics.t),
        Phase::Finished => ("finished", f64::NAN),
    })
}

/// Decodes a `pdamp powder run` checkpoint of any scenario that holds a preparation in
/// progress and checks its consistency (for fuzzing; never panics).
pub fn decode_preparation(bytes: &[u8]) -> Result<Preparation, CantileverError> {
    let phase = ck::decode::<Phase>(bytes, CHECKPOINT_KIND, None).map_err(CantileverError::from)?;
    match phase {
        Phase::Preparing(p) => {
            p.check_consistency()?;
            Ok(*p)
        }
        _ => Err(CantileverError::NotPreparation),
    }
}

/// Runs the scenario (preparation + coupled run) without files. `progress(stage, fraction)`.
pub fn run(
    sc: &CantileverScenario,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    sc.validate()?;
    run_core(sc, None, None, None, progress)
}

/// Runs the scenario and writes its outputs ([`write_outputs`]) into `dir`, checkpointing
/// into `DIR/checkpoint.bin` every `options.checkpoint_interval_s` of wall-clock time, once
/// the preparation is finished (unless the interval is 0) and on a stop request
/// ([`pdamp_io::checkpoint::request_stop`], the CLI's Ctrl-C/SIGTERM), which ends the run with
/// an error starting with [`pdamp_io::checkpoint::INTERRUPTED`]. With `options.resume` the run
/// continues from the checkpoint (a checkpoint of another scenario is refused) and the
/// outputs equal those of an uninterrupted run byte for byte, wall times aside; resuming a
/// finished run returns its summary.
pub fn run_in_dir(
    sc: &CantileverScenario,
    dir: &Path,
    options: RunOptions,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    sc.validate()?;
    if !(options.checkpoint_interval_s >= 0.0 && options.checkpoint_interval_s.is_finite()) {
        return Err(ParameterError::out_of_range(
            "--checkpoint-interval-s",
            options.checkpoint_interval_s,
            "must be finite and ≥ 0 (0 = only on Ctrl-C)",
        )
        .into());
    }
    let digest = scenario_digest(sc)?;
    let c = Checkpointing {
        path: dir.join(ck::CHECKPOINT_FILE),
        header: CheckpointHeader::new(CHECKPOINT_KIND, &digest),
        interval_s: options.checkpoint_interval_s,
    };
    let resumed: Option<Phase> = if options.resume {
        ck::load(&c.path, CHECKPOINT_KIND, &digest).map_err(CantileverError::from)?
    } else {
        None
    };
    if let Some(Phase::Finished) = resumed {
        let path = dir.join("summary.json");
        let text = std::fs::read_to_string(&path).map_err(|source| CantileverError::File {
            path: path.clone(),
            source,
        })?;
        let json = |source| CantileverError::Json {
            path: path.clone(),
            source,
        };
        let js: serde_json::Value = serde_json::from_str(&text).map_err(json)?;
        return serde_json::from_value(js["result"].clone()).map_err(json);
    }
    create_dir(dir)?;
    let r = run_core(sc, Some(&c), resumed, Some(dir), progress)?;
    write_outputs(dir, sc, &r)?;
    c.save(&Phase::Finished)?;
    Ok(r)
}

/// The run; with `vtk_dir` the ParaView frames of [`crate::vtk::PowderSnapshots`] go there.
fn run_core(
    sc: &CantileverScenario,
    ckp: Option<&Checkpointing>,
    resumed: Option<Phase>,
    vtk_dir: Option<&Path>,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<CantileverResult, CantileverError> {
    let (mut s, tip) = build_structure(&sc.beam, &sc.load, sc.run.gravity_m_s2);
    let dt = sc.run.time_step_s;
    let cavity = sc.beam.cavity();
    let _stoppable = ckp.map(|_| ck::StoppableSection::enter());
    let mut timer = CheckpointTimer::new(ckp.map_or(0.0, |c| c.interval_s));
    let (mut preparing, mut running) = (None, None);
    match resumed {
        Some(Phase::Preparing(p)) => {
            p.check_consistency()?;
            preparing = Some(*p);
        }
        Some(Phase::Running(r)) => running = Some(*r),
        Some(Phase::Finished) | None => {}
    }
    // preparation (fresh, continued, or done before the checkpoint)
    let prepared = match (&running, &sc.powder) {
        (Some(_), _) => None,
        (None, Some(p)) => {
            let mut pr = preparing.take().unwrap_or_else(|| {
                Preparation::new(
                    cavity,
                    &p.psd(),
                    p.scaled_law(),
                    p.density_kg_m3,
                    dt,
                    &p.prep,
                )
            });
            let mut err = None;
            let flow = pr.run(progress, &mut |pr| {
                let Some(c) = ckp else {
                    return ControlFlow::Continue(());
                };
                let stop = ck::stop_requested();
                if stop || timer.due() {
                    if let Err(e) = c.save(&Phase::Preparing(Box::new(pr.snapshot()))) {
                        err = Some(e);
                        return ControlFlow::Break(());
                    }
                    if stop {
                        return ControlFlow::Break(());
                    }
                }
                ControlFlow::Continue(())
            });
            let flow = flow?;
            if let Some(e) = err {
                return Err(e);
            }
            if flow.is_break() {
                let c = ckp.ok_or(CantileverError::PreparationStopped)?;
                return Err(c.interrupted(pr.time_s()));
            }
            let (pw, rep) = pr.finish();
            Some((pw, Some(rep)))
        }
        (None, None) => Some((
            PowderBed::at_rest(PowderLaw::PAPER, &[], &[], 8000.0, [0.0; 3], dt),
            None,
        )),
    };
    let n = s.n_dof();
    let dynamics = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(sc.beam.rho_inf),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        sc.beam.rayleigh,
    )?;
    let interface = cavity_interface(&s, &cavity);
    let structure_mass = s.total_mass();
    let elements = s.mesh.elements.len();
    let nsteps = (sc.run.duration_s / dt).round() as u64;
    let result = |c: &Coupled, prep: Option<PrepReport>| CantileverResult {
        time_s: vec![0.0],
        tip_m: vec![0.0],
        iterations: vec![0.0],
        energy: vec![(0.0, c.energy())],
        damping: TableOneRatios::default(),
        max_tip_before_release_m: 0.0,
        prep,
        particles: c.particles(),
        structure_dofs: c.structure.n_dof(),
        elements,
        interface_dofs: c.interface.n_dof(),
        steps: nsteps,
        mean_iterations: 0.0,
        max_iterations: 0,
        wall_time_s: 0.0,
        structure_mass_kg: structure_mass,
        powder_mass_kg: c.particle_mass_kg(),
        energy_closure: 0.0,
        coupled_step_wall_time_s: Default::default(),
    };
    let (mut c, mut res, first) = match (running, prepared) {
        (Some(st), _) => {
            let mut c = Coupled::from_state(s, dynamics, interface, sc.run.coupling, st.coupled)?;
            c.container = sc.powder.is_some().then_some(cavity);
            let res = CantileverResult {
                time_s: st.time_s,
                tip_m: st.tip_m,
                iterations: st.iterations,
                energy: st.energy,
                max_tip_before_release_m: st.max_tip_before_release_m,
                wall_time_s: st.wall_time_s,
                ..result(&c, st.prep)
            };
            (c, res, st.step + 1)
        }
        (None, Some((mut powder, prep))) => {
            powder.world.gravity_m_s2 = pdamp_dem::Vec3::from(sc.run.gravity_m_s2);
            let mut c = Coupled::new(s, dynamics, powder, interface, sc.run.coupling)?;
            c.container = sc.powder.is_some().then_some(cavity);
            let res = result(&c, prep);
            (c, res, 1)
        }
        (None, None) => return Err(CantileverError::NoStart),
    };
    let wall_before = res.wall_time_s;
    let clock = Instant::now();
    let wall = |clock: &Instant| wall_before + clock.elapsed().as_secs_f64();
    let state = |c: &Coupled, res: &CantileverResult, step: u64, wall_time_s: f64| {
        Phase::Running(Box::new(RunState {
            step,
            coupled: c.save_state(),
            prep: res.prep.clone(),
            time_s: res.time_s.clone(),
            tip_m: res.tip_m.clone(),
            iterations: res.iterations.clone(),
            energy: res.energy.clone(),
            max_tip_before_release_m: res.max_tip_before_release_m,
            wall_time_s,
        }))
    };
    // the prepared powder is checkpointed at once (preparation can take long)
    if let Some(cp) = ckp
        && first == 1
        && sc.powder.is_some()
        && cp.interval_s > 0.0
    {
        cp.save(&state(&c, &res, 0, wall(&clock)))?;
    }
    let mut snapshots = match vtk_dir {
        Some(d) if sc.run.vtk_interval_s > 0.0 => {
            let every = ((sc.run.vtk_interval_s / dt).round() as u64).max(1);
            Some(crate::vtk::PowderSnapshots::new(
                d,
                every,
                dt,
                &c.structure.mesh,
            ))
        }
        _ => None,
    };
    if let Some(s) = snapshots.as_mut() {
        if first > 1 {
            s.resume_after(first - 1)?;
        } else {
            s.on_step(0, &c)?;
        }
    }
    let every = ((sc.run.output_interval_s / dt).round() as u64).max(1);
    let e_every = (nsteps / 2000).max(1);
    let t_release = sc.load.rise_s + sc.load.hold_s;
    for q in first..=nsteps {
        let it = c.step()?;
        let t = c.dynamics.t;
        let x = c.dynamics.d[3 * tip];
        if t <= t_release {
            res.max_tip_before_release_m = res.max_tip_before_release_m.max(x.abs());
        }
        if q % every == 0 {
            res.time_s.push(t);
            res.tip_m.push(x);
            res.iterations.push(it as f64);
        }
        if q % e_every == 0 || q == 1 {
            let e = c.energy();
            res.energy.push((t, e));
            check_energy_health(&c, &res.energy)?;
        }
        if let Some(s) = snapshots.as_mut() {
            s.on_step(q, &c)?;
        }
        if q % 200 == 0 {
            progress("coupled run", q as f64 / nsteps as f64);
        }
        if let Some(cp) = ckp {
            let stop = ck::stop_requested();
            if stop || timer.due() {
                cp.save(&state(&c, &res, q, wall(&clock)))?;
                if stop {
                    return Err(cp.interrupted(t));
                }
            }
        }
    }
    res.wall_time_s = wall(&clock);
    res.coupled_step_wall_time_s = c.timing;
    res.mean_iterations = c.total_iterations as f64 / c.steps.max(1) as f64;
    res.max_iterations = c.max_iterations_seen;
    res.damping = damping::table_one(&res.time_s, &res.tip_m, t_release);
    let b0 = res.energy[1.min(res.energy.len() - 1)].1.balance_j; // after step 1: wall springs known
    let emax = res
        .energy
        .iter()
        .map(|(_, e)| {
            e.structure_kinetic_j
                + e.structure_strain_j
                + e.particle_kinetic_j
                + e.contact_elastic_j
        })
        .fold(1e-300, f64::max);
    res.energy_closure = res
        .energy
        .iter()
        .skip(1)
        .map(|(_, e)| (e.balance_j - b0).abs())
        .fold(0.0, f64::max)
        / emax;
    Ok(res)
}

/// The energy health check of the coupled run ([`crate::health::check_energy`]): the
/// cumulative dissipation must not be negative beyond a tenth of the largest energy so far,
/// and the balance must not grow by more than half of it (from its value after step 1, when
/// the wall springs are known).
fn check_energy_health(
    c: &Coupled,
    energy: &[(f64, CoupledEnergy)],
) -> Result<(), Box<HealthError>> {
    let Some((_, e)) = energy.last() else {
        return Ok(());
    };
    let b0 = energy[1.min(energy.len() - 1)].1.balance_j;
    let scale = energy
        .iter()
        .map(|(_, e)| {
            e.structure_kinetic_j
                + e.structure_strain_j
                + e.particle_kinetic_j
                + e.contact_elastic_j
        })
        .chain(std::iter::once(e.load_work_j.abs()))
        .fold(0.0, f64::max);
    crate::health::check_energy(e.dissipated_j, e.balance_j - b0, scale).map_err(|s| {
        Box::new(HealthError::of_world(
            c.world.time_s,
            "coupled run",
            s,
            &c.world,
            &c.law,
        ))
    })
}

/// Writes tip.csv, envelope.csv, energy.csv, the tip plot and (last) summary.json into `dir`.
pub fn write_outputs(
    dir: &Path,
    sc: &CantileverScenario,
    r: &CantileverResult,
) -> Result<(), CantileverError> {
    create_dir(dir)?;
    let rows: Vec<[f64; 3]> = (0..r.time_s.len())
        .map(|i| [r.time_s[i], r.tip_m[i], r.iterations[i]])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("tip.csv"),
        &["time_s", "tip_displacement_m", "coupling_iterations"],
        rows,
    )?;
    let t_rel = sc.load.rise_s + sc.load.hold_s;
    let ext = damping::local_extrema(&r.time_s, &r.tip_m, t_rel);
    let env: Vec<[f64; 2]> = ext
        .iter()
        .map(|&i| [r.time_s[i], r.tip_m[i].abs()])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("envelope.csv"),
        &["time_s", "peak_abs_displacement_m"],
        env.iter(),
    )?;
    let erows: Vec<[f64; 9]> = r
        .energy
        .iter()
        .map(|(t, e)| {
            [
                *t,
                e.structure_kinetic_j,
                e.structure_strain_j,
                e.particle_kinetic_j,
                e.particle_potential_j,
                e.contact_elastic_j,
                e.dissipated_j,
                e.load_work_j,
                e.balance_j,
            ]
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("energy.csv"),
        &[
            "time_s",
            "structure_kinetic_j",
            "structure_strain_j",
            "particle_kinetic_j",
            "particle_potential_j",
            "contact_elastic_j",
            "dissipated_j",
            "load_work_j",
            "balance_j",
        ],
        erows,
    )?;
    let ms: Vec<f64> = r.time_s.iter().map(|t| t * 1e3).collect();
    let mm: Vec<f64> = r.tip_m.iter().map(|x| x * 1e3).collect();
    let mut plot = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("tip displacement x (mm)"),
    );
    plot.series.push(pdamp_plot::Series::new("", ms, mm));
    pdamp_plot::line_plot(dir.join("tip"), &plot)?;
    // last: a run directory with summary.json is complete (the study skips it)
    // the digest lets a study reuse this run only for the same scenario (study::run_study)
    let summary = serde_json::json!({
        "result": r,
        "scenario": sc,
        "scenario_digest": scenario_digest(sc)?,
    });
    let path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).map_err(CantileverError::Encode)?;
    pdamp_io::atomic::write_atomic(&path, json.as_bytes())
        .map_err(|source| CantileverError::Write { path, source })?;
    Ok(())
}

/// Creates `dir` (and its parents).
fn create_dir(dir: &Path) -> Result<(), CantileverError> {
    std::fs::create_dir_all(dir).map_err(|source| CantileverError::File {
        path: dir.to_path_buf(),
        source,
    })
}

/// First bending frequencies \[Hz\] of the empty beam (no powder), `count` lowest modes.
pub fn empty_beam_modes(beam: &BeamSpec, count: usize) -> Result<Vec<f64>, SolverError> {
    let (s, _) = build_structure(
        beam,
        &LoadSpec {
            pressure_pa: 0.0,
            rise_s: 1.0,
            hold_s: 0.0,
        },
        [0.0; 3],
    );
    fe::modes::lowest_modes(&s, count, 300).map(|(f, _)| f)
}

/// First bending frequency of the empty beam from piecewise Timoshenko theory (solid bottom,
/// hollow cavity part, solid top) \[Hz\].
pub fn timoshenko_reference(beam: &BeamSpec) -> f64 {
    use crate::fe::beam_theory::{Segment, timoshenko_f1};
    let inner = beam.width_m - 2.0 * beam.wall_thickness_m;
    let segs = [
        Segment {
            length_m: beam.cavity_offset_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
        Segment {
            length_m: beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: inner,
        },
        Segment {
            length_m: beam.length_m - beam.cavity_offset_m - beam.cavity_length_m,
            outer_m: beam.width_m,
            inner_m: 0.0,
        },
    ];
    let m = beam.material;
    timoshenko_f1(
        &segs,
        m.youngs_modulus_pa,
        m.poisson_ratio,
        m.density_kg_m3,
        1320,
        &[],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoint_inspection_and_damage() {
        let dir = std::env::temp_dir().join(format!("pdamp-powder-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(ck::CHECKPOINT_FILE);
        let cavity = Aabb {
            min: [0.0; 3],
            max: [0.006, 0.006, 0.012],
        };
        let s = PrepSettings::default();
        let mut pr = Preparation::new(
            cavity,
            &LogNormal::paper(2e-3),
            PowderLaw::PAPER.coarse_grained(2.0),
            8000.0,
            5e-6,
            &s,
        );
        let mut k = 0;
        let _ = pr.run(&mut |_, _| {}, &mut |_| {
            k += 1;
            if k == 50 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        let header = CheckpointHeader::new(CHECKPOINT_KIND, "digest");
        ck::save(&path, &header, &Phase::Preparing(Box::new(pr.snapshot()))).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let (phase, t) = inspect_checkpoint(&bytes).unwrap();
        assert_eq!(phase, "preparing");
        assert!((t - 50.0 * 5e-6).abs() < 1e-15, "{t}");
        // another scenario, another kind, damage and truncation are refused with a message
        let e = ck::load::<Phase>(&path, CHECKPOINT_KIND, "other")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("different scenario"), "{e}");
        let e = ck::load::<Phase>(&path, "run", "digest")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("not 'run'"), "{e}");
        let mut bad = bytes.clone();
        bad[bytes.len() / 2] ^= 1;
        assert!(
            inspect_checkpoint(&bad)
                .unwrap_err()
                .to_string()
                .contains("damaged")
        );
        assert!(inspect_checkpoint(&bytes[..bytes.len() - 100]).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
