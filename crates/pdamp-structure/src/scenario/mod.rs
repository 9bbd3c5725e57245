//! TOML input of `pdamp structure modes` and `pdamp couple` (see docs/structure.md). SI units
//! in every key name; unknown keys are errors.
//!
//! This module holds the schema (the structs the TOML maps to) and loading; the other concepts
//! live in submodules: `build` (the structure built and reduced to modes), `damper_model`
//! (a damper entry turned into its DEM kinematics or equivalent model) and `validate` (range
//! checks of every key, with the limits).

mod build;
mod damper_model;
#[cfg(test)]
mod tests;
mod validate;

pub use validate::{
    MAX_DENSITY_KG_M3, MAX_DISPLACEMENT_M, MAX_DURATION_S, MAX_ELEMENTS, MAX_FORCE_N,
    MAX_FREQUENCY_HZ, MAX_LENGTH_M, MAX_MASS_KG, MAX_MODES, MAX_MODULUS_PA, MAX_POINTS,
    MAX_SEGMENTS, locate, locate_error, on_beam,
};

use crate::StructureError;
use crate::forced::SweepLaw;
use crate::free::UpdateRule;
use crate::modal::{ModalPoint, ModalStructure};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A structure file: `[structure]` with one model section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureFile {
    /// The structure.
    pub structure: StructureSpec,
}

/// The structure model and its reduction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    /// Number of modes kept (FE and Matrix Market models).
    #[serde(default = "default_modes")]
    pub n_modes: usize,
    /// Modes below this frequency (rigid-body modes) are dropped, Hz.
    #[serde(default = "default_min_frequency")]
    pub min_frequency_hz: f64,
    /// Eigen solver of FE and Matrix Market models: `auto` (dense up to
    /// [`crate::sparse::AUTO_SPARSE_ABOVE_DOF`] active dof, sparse above), `dense` or `sparse`
    /// (faer Krylov–Schur on the shift-inverted pencil, [`crate::sparse`]).
    #[serde(default)]
    pub solver: EigenSolver,
    /// Single mode in damper coordinates [D Eq. 3.27/3.36].
    #[serde(default)]
    pub single_mode: Option<SingleModeSpec>,
    /// Direct modal input.
    #[serde(default)]
    pub modal: Option<ModalSpec>,
    /// Built-in straight beam.
    #[serde(default)]
    pub beam: Option<BeamSpec>,
    /// Imported matrices.
    #[serde(default)]
    pub matrix_market: Option<MatrixMarketSpec>,
    /// Structural damping (FE and Matrix Market models).
    #[serde(default)]
    pub damping: Option<DampingSpec>,
    /// Named points (FE and Matrix Market models).
    #[serde(default)]
    pub points: Vec<PointSpec>,
}

/// Eigen solver selection (`[structure] solver`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EigenSolver {
    /// Dense up to [`crate::sparse::AUTO_SPARSE_ABOVE_DOF`] dof, sparse above.
    #[default]
    Auto,
    /// Dense Cholesky + symmetric eigen solver ([`crate::modal::lowest_modes`]).
    Dense,
    /// Sparse shift-invert Krylov–Schur ([`crate::sparse::lowest_modes_sparse`]).
    Sparse,
}

/// Dense solver limit (memory n² and time n³).
pub const DENSE_MAX_DOF: usize = 4000;

fn default_modes() -> usize {
    4
}
fn default_min_frequency() -> f64 {
    1e-3
}

/// `[structure.single_mode]`: $M\ddot x + D\dot x + Kx = f$ at the damper [D Eq. 3.36].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SingleModeSpec {
    /// M, kg.
    pub mass_kg: f64,
    /// K, N/m.
    pub stiffness_n_m: f64,
    /// D, N·s/m.
    #[serde(default)]
    pub damping_n_s_m: f64,
}

/// `[structure.modal]`: eigenfrequencies, damping ratios and mass-normalised shape values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModalSpec {
    /// f_k, Hz.
    pub frequencies_hz: Vec<f64>,
    /// ζ_k (one per mode).
    pub damping_ratios: Vec<f64>,
    /// Points with their φ^(k) values (1/√kg).
    pub points: Vec<ModalPoint>,
}

/// Structural damping of FE/imported models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DampingSpec {
    /// Same ζ for all modes.
    #[serde(default)]
    pub ratio: Option<f64>,
    /// ζ per mode.
    #[serde(default)]
    pub ratios: Option<Vec<f64>>,
    /// Rayleigh α (mass-proportional), 1/s.
    #[serde(default)]
    pub rayleigh_alpha_1_s: Option<f64>,
    /// Rayleigh β (stiffness-proportional), s.
    #[serde(default)]
    pub rayleigh_beta_s: Option<f64>,
}

/// `[structure.beam]`: a straight beam along x with planar (x–y) or 3D motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSpec {
    /// Length, m.
    pub length_m: f64,
    /// Number of elements.
    pub elements: usize,
    /// E, Pa.
    pub youngs_modulus_pa: f64,
    /// ν.
    pub poisson_ratio: f64,
    /// ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Cross-section area, m² (or give width_m/height_m).
    #[serde(default)]
    pub area_m2: Option<f64>,
    /// Second moment for bending in x–y (deflection along y), m⁴.
    #[serde(default)]
    pub second_moment_m4: Option<f64>,
    /// Second moment for bending in x–z, m⁴ (default: as second_moment_m4).
    #[serde(default)]
    pub second_moment_z_m4: Option<f64>,
    /// Torsion constant, m⁴ (default: sum of the second moments).
    #[serde(default)]
    pub torsion_constant_m4: Option<f64>,
    /// Rectangle width (z extent), m.
    #[serde(default)]
    pub width_m: Option<f64>,
    /// Rectangle height (y extent, bending direction), m.
    #[serde(default)]
    pub height_m: Option<f64>,
    /// Timoshenko elements (κ = 5/6).
    #[serde(default = "yes")]
    pub timoshenko: bool,
    /// Only in-plane (x–y) motion: uz, θx, θy fixed everywhere.
    #[serde(default = "yes")]
    pub planar: bool,
    /// Supports.
    #[serde(default)]
    pub supports: Vec<SupportSpec>,
    /// Lumped masses.
    #[serde(default)]
    pub masses: Vec<MassSpec>,
}

fn yes() -> bool {
    true
}

/// Support kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SupportKind {
    /// All six dof fixed.
    Clamped,
    /// Translations fixed.
    Pinned,
    /// Transverse spring (y) of `stiffness_n_m`.
    Spring,
}

/// A support at a position along the beam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportSpec {
    /// Position along the beam, m.
    pub position_m: f64,
    /// Kind.
    pub kind: SupportKind,
    /// Spring stiffness, N/m (kind = "spring").
    #[serde(default)]
    pub stiffness_n_m: f64,
}

/// A lumped mass on the beam.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MassSpec {
    /// Position along the beam, m.
    pub position_m: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Rotary inertia about z, kg·m².
    #[serde(default)]
    pub rotary_inertia_kg_m2: f64,
    /// Offset of the mass centre from the beam axis along y, m (rigid attachment).
    #[serde(default)]
    pub offset_y_m: f64,
}

/// `[structure.matrix_market]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixMarketSpec {
    /// Stiffness matrix file.
    pub stiffness: PathBuf,
    /// Mass matrix file.
    pub mass: PathBuf,
    /// Dof map file (`row node dof`).
    pub dof_map: PathBuf,
}

/// A named point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointSpec {
    /// Name.
    pub name: String,
    /// Position along the beam, m (built-in beam).
    #[serde(default)]
    pub position_m: Option<f64>,
    /// Node id (Matrix Market model).
    #[serde(default)]
    pub node: Option<i64>,
    /// Direction dof: `uy` (default), `uz`, `ux`, …
    #[serde(default = "default_dof")]
    pub dof: String,
}

fn default_dof() -> String {
    "uy".into()
}

/// Result of building a structure.
#[derive(Debug, Clone)]
pub struct BuiltStructure {
    /// The reduced structure.
    pub modal: ModalStructure,
    /// Total mass of an FE model, kg.
    pub total_mass_kg: Option<f64>,
    /// Active dof of an FE/imported model.
    pub dof_count: Option<usize>,
    /// Eigen solver used ("dense", "sparse"; `None` for modal/single-mode input).
    pub solver: Option<&'static str>,
}

fn resolve(base: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    }
}

/// Loads and validates a structure file ([`StructureSpec::validate`]).
///
/// # Errors
/// I/O and TOML errors; invalid values with the file, the key's line and column and the fix.
pub fn load_structure(path: &Path) -> Result<StructureFile, StructureError> {
    let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
    let f: StructureFile = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
    f.structure
        .validate()
        .map_err(|m| m.located(path, Some(&text)))?;
    Ok(f)
}

/// A `pdamp couple` scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoupleScenario {
    /// Structure file (relative to the scenario), or give `[structure]` inline.
    #[serde(default)]
    pub structure_file: Option<PathBuf>,
    /// Inline structure.
    #[serde(default)]
    pub structure: Option<StructureSpec>,
    /// Dampers.
    #[serde(default)]
    pub dampers: Vec<DamperSpec>,
    /// The analysis.
    pub analysis: AnalysisSpec,
}

/// A damper model at a structure point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum DamperSpec {
    /// Viscous reference: Ẽ = πcΩX², constant mass.
    Viscous {
        /// Structure point.
        point: String,
        /// c, N·s/m.
        damping_n_s_m: f64,
        /// Coupled mass, kg.
        #[serde(default)]
        mass_kg: f64,
    },
    /// Approach 2: effective field from fields.csv.
    Fields {
        /// Structure point.
        point: String,
        /// fields.csv (relative to the scenario).
        path: PathBuf,
        /// Bed mass m_bed, kg.
        bed_mass_kg: f64,
    },
    /// Approach 3: rolling/scattered layers (D Eq. 5.1–5.14).
    Rolling {
        /// Structure point.
        point: String,
        /// Layers.
        layers: Vec<RollingLayerSpec>,
        /// Smoothing of the X_opt jump (logistic width in ln X).
        #[serde(default)]
        smoothing_log_width: Option<f64>,
    },
    /// Approach 3: combined horizontal rolling/bouncing model (D Eq. 6.12).
    Horizontal {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// h_rol, m.
        rolling_clearance_m: f64,
        /// h_bou, m.
        bouncing_clearance_m: f64,
        /// m̄/m_bed for A ≥ g.
        #[serde(default = "one")]
        bouncing_mass_ratio: f64,
    },
    /// Approach 3: vertical single/double collect-and-collide bed (D Eq. 7.1–7.19).
    Vertical {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// Clearance h to the top wall, m (or give `container_length_m`, `particles`,
        /// `max_particles` for Eq. 7.4).
        #[serde(default)]
        clearance_m: Option<f64>,
        /// Inner container length L along the excitation, m (Eq. 7.4).
        #[serde(default)]
        container_length_m: Option<f64>,
        /// Particle number n_p (Eq. 7.4).
        #[serde(default)]
        particles: Option<f64>,
        /// n_p^max (Eq. 7.4).
        #[serde(default)]
        max_particles: Option<f64>,
    },
    /// Fixed η̄ and m̄/m_bed.
    Constant {
        /// Structure point.
        point: String,
        /// Bed mass, kg.
        bed_mass_kg: f64,
        /// η̄.
        effective_loss_factor: f64,
        /// m̄/m_bed.
        effective_mass_ratio: f64,
    },
    /// Approach 3: powder-filled cavity, sliding-friction work under pure shear or bending
    /// (paper Sect. 4, eq. 17–26; [`crate::formulas::PowderFrictionDamper`]).
    PowderFriction {
        /// Structure point (X is its amplitude).
        point: String,
        /// `shear` (eq. 20) or `bending` (eq. 26).
        mechanism: crate::formulas::FrictionMechanism,
        /// Cavity length l, m.
        cavity_length_m: f64,
        /// Cavity width b, m (bending).
        #[serde(default)]
        cavity_width_m: Option<f64>,
        /// Coefficient of friction μ.
        friction: f64,
        /// Wall normal force F_N,y (shear) / F_N,x (bending), N.
        wall_normal_force_n: f64,
        /// κ = φ/X, rad/m; or give `angle_points`.
        #[serde(default)]
        angle_per_displacement_rad_m: Option<f64>,
        /// Points giving φ from the analysed mode: bending `[θ_start, θ_end]`
        /// (φ = (θ_end − θ_start)/2), shear `[u_start, θ_start, u_end, θ_end]`
        /// (φ = (u_end − u_start)/l − (θ_start + θ_end)/2).
        #[serde(default)]
        angle_points: Option<Vec<String>>,
        /// Powder mass, kg.
        bed_mass_kg: f64,
        /// m̄ added at the point, kg (the powder mass itself belongs to the structure).
        #[serde(default)]
        effective_mass_kg: f64,
    },
    /// Approach 1: full DEM damper from a damper scenario (`[damper]` section).
    Dem {
        /// Structure point.
        point: String,
        /// Damper scenario (relative to this scenario).
        scenario: PathBuf,
        /// Subtract the static bed weight.
        #[serde(default = "yes")]
        compensate_static_weight: bool,
        /// Container dof that follow the structure: `"1d"` (along the damper's direction at
        /// `point`), `"translation"` or `"translation+rotation"` (rigid body, D Eq. 3.21–3.26).
        #[serde(default)]
        dofs: DemDofs,
        /// Rigid-body modes: structure points of u_x, u_y, u_z of the damper node in the
        /// DEM frame (`""` = that dof is not moved); `point` must be one of them.
        #[serde(default)]
        translation_points: Option<Vec<String>>,
        /// `"translation+rotation"`: points of θ_x, θ_y, θ_z (rad), `""` = not rotated.
        #[serde(default)]
        rotation_points: Option<Vec<String>>,
        /// Attachment point (rotation centre, torque reference) in the damper scenario's
        /// frame, m; default: the container's reference position.
        #[serde(default)]
        attachment_point_m: Option<[f64; 3]>,
    },
}

/// Container dof of a DEM damper (approach 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DemDofs {
    /// Translation along the damper's direction only.
    #[default]
    #[serde(rename = "1d")]
    OneDimensional,
    /// Three translations.
    #[serde(rename = "translation")]
    Translation,
    /// Three translations and three small rotations.
    #[serde(rename = "translation+rotation")]
    TranslationRotation,
}

fn one() -> f64 {
    1.0
}

fn default_overlap() -> f64 {
    0.3
}

/// One layer of a rolling damper: give `clearance_m` or `container_length_m` with
/// `particles` and `particles_per_layer` (Eq. 5.1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RollingLayerSpec {
    /// Bed mass of the layer, kg.
    pub bed_mass_kg: f64,
    /// Clearance h_rol, m.
    #[serde(default)]
    pub clearance_m: Option<f64>,
    /// Container length L, m.
    #[serde(default)]
    pub container_length_m: Option<f64>,
    /// n_p.
    #[serde(default)]
    pub particles: Option<f64>,
    /// n_p^max.
    #[serde(default)]
    pub particles_per_layer: Option<f64>,
}

impl DamperSpec {
    /// Structure point of the damper.
    pub fn point(&self) -> &str {
        match self {
            DamperSpec::Viscous { point, .. }
            | DamperSpec::Fields { point, .. }
            | DamperSpec::Rolling { point, .. }
            | DamperSpec::Horizontal { point, .. }
            | DamperSpec::Vertical { point, .. }
            | DamperSpec::Constant { point, .. }
            | DamperSpec::PowderFriction { point, .. }
            | DamperSpec::Dem { point, .. } => point,
        }
    }
}

/// Excitation force: a force amplitude, or a base amplitude U of a single-mode structure
/// (R' = UK, D Sect. 5.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// F, N.
    #[serde(default)]
    pub force_amplitude_n: Option<f64>,
    /// U, m (single_mode structures: F = U K).
    #[serde(default)]
    pub base_amplitude_m: Option<f64>,
}

/// The analysis of a `pdamp couple` scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum AnalysisSpec {
    /// Free vibration from an initial condition [D Sect. 3.3.1].
    Free {
        /// Simulated time, s.
        duration_s: f64,
        /// Time step, s (DEM dampers use their scenario's step).
        time_step_s: f64,
        /// Mode carrying the initial condition (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
        /// Point of the initial condition.
        initial_point: String,
        /// Initial displacement, m.
        initial_displacement_m: f64,
        /// Initial velocity, m/s.
        #[serde(default)]
        initial_velocity_m_s: f64,
        /// Scale the initial displacement (and velocity) by $1 + m_{bed}/M$ [D Eq. 5.19]: the
        /// excitation that starts the decay gives the structure the same peak acceleration with
        /// and without particles, so the amplitude grows with the added bed mass ($M$: the modal
        /// mass of `mode` at `initial_point`, $m_{bed}$: the dampers' particle mass). For the
        /// Flexor of D Sect. 5.2.1 (78 mm without particles).
        #[serde(default)]
        scale_initial_by_bed_mass: bool,
        /// Output point.
        output_point: String,
        /// Update rule for approaches 2/3.
        #[serde(default)]
        update: UpdateRule,
        /// Peaks between which ζ per cycle is evaluated (`damping.csv`): `positive` (default,
        /// D Sect. 5.1.2) or `negative` (D Sect. 7.2, vertical dampers released downwards).
        #[serde(default)]
        decay_peaks: crate::free::DecayPeaks,
        /// Store every n-th step.
        #[serde(default = "one_usize")]
        sample_every: usize,
    },
    /// Sine sweep in the time domain [D Sect. 3.3.2].
    Sweep {
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
        /// Duration, s.
        duration_s: f64,
        /// Linear or logarithmic.
        #[serde(default)]
        law: SweepLaw,
        /// Force amplitude F, N.
        #[serde(default)]
        force_amplitude_n: Option<f64>,
        /// Base amplitude U of a single-mode structure (F = U K), m.
        #[serde(default)]
        base_amplitude_m: Option<f64>,
        /// Excitation point.
        excitation_point: String,
        /// Output point.
        output_point: String,
        /// Time step, s.
        time_step_s: f64,
        /// Store every n-th step.
        #[serde(default = "one_usize")]
        sample_every: usize,
        /// Cycles per FRF window.
        #[serde(default = "four")]
        window_cycles: usize,
        /// Mode analysed by Eq. 3.47 (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
        /// Split the sweep into this many overlapping segments, each started from rest, FRFs
        /// combined by peak hold (frequency-domain approach, D Sect. 3.3.2); 1 = one sweep.
        #[serde(default = "one_usize")]
        segments: usize,
        /// Overlap of neighbouring segments as a fraction of the segment width (half of it is
        /// the cut-off start-up transient).
        #[serde(default = "default_overlap")]
        segment_overlap: f64,
    },
    /// Steady-state FRF of approaches 2/3 by the iteration of D Fig. 3.7 / Eq. 3.44, one mode.
    SteadyState {
        /// Start frequency, Hz.
        start_hz: f64,
        /// End frequency, Hz.
        end_hz: f64,
        /// Number of frequencies.
        #[serde(default = "thousand")]
        points: usize,
        /// Force amplitude F, N.
        #[serde(default)]
        force_amplitude_n: Option<f64>,
        /// Base amplitude U of a single-mode structure (F = U K), m.
        #[serde(default)]
        base_amplitude_m: Option<f64>,
        /// Excitation point.
        excitation_point: String,
        /// Output point.
        output_point: String,
        /// Mode (1-based).
        #[serde(default = "one_usize")]
        mode: usize,
    },
}

impl AnalysisSpec {
    /// The peaks a free decay's ζ per cycle is taken between (positive for the other kinds).
    pub fn decay_peaks(&self) -> crate::free::DecayPeaks {
        match self {
            AnalysisSpec::Free { decay_peaks, .. } => *decay_peaks,
            _ => crate::free::DecayPeaks::Positive,
        }
    }

    /// The free-vibration settings of a `kind = "free"` analysis (`None` for the others);
    /// `mode` becomes 0-based.
    pub fn free_vibration_spec(&self) -> Option<crate::free::FreeVibrationSpec> {
        match self {
            AnalysisSpec::Free {
                duration_s,
                time_step_s,
                mode,
                initial_point,
                initial_displacement_m,
                initial_velocity_m_s,
                scale_initial_by_bed_mass,
                output_point,
                update,
                sample_every,
                ..
            } => Some(crate::free::FreeVibrationSpec {
                duration_s: *duration_s,
                time_step_s: *time_step_s,
                mode: mode.saturating_sub(1),
                initial_point: initial_point.clone(),
                initial_displacement_m: *initial_displacement_m,
                initial_velocity_m_s: *initial_velocity_m_s,
                output_point: output_point.clone(),
                update: *update,
                sample_every: *sample_every,
                scale_initial_by_bed_mass: *scale_initial_by_bed_mass,
            }),
            _ => None,
        }
    }
}

fn one_usize() -> usize {
    1
}
fn four() -> usize {
    4
}
fn thousand() -> usize {
    1000
}

impl ForceSpec {
    /// The force amplitude, N (needs the single-mode stiffness for `base_amplitude_m`).
    ///
    /// # Errors
    /// Not exactly one of the two amplitudes; a base amplitude without a single-mode structure.
    pub fn force_n(&self, structure: &StructureSpec) -> Result<f64, StructureError> {
        match (self.force_amplitude_n, self.base_amplitude_m) {
            (Some(f), None) => Ok(f),
            (None, Some(u)) => structure
                .single_mode
                .map(|s| u * s.stiffness_n_m)
                .ok_or_else(|| {
                    StructureError::rule(
                        "base_amplitude_m",
                        "needs a single_mode structure (R' = U K)",
                    )
                }),
            _ => Err(StructureError::inconsistent(
                "give exactly one of force_amplitude_n and base_amplitude_m",
            )),
        }
    }
}

impl CoupleScenario {
    /// Loads a scenario; returns it with the structure spec resolved.
    ///
    /// # Errors
    /// I/O, TOML, missing structure.
    pub fn load(path: &Path) -> Result<(Self, StructureSpec), StructureError> {
        let text = std::fs::read_to_string(path).map_err(|e| StructureError::read(path, e))?;
        let s: CoupleScenario = toml::from_str(&text).map_err(|e| StructureError::toml(path, e))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let located = |m: StructureError| m.located(path, Some(&text));
        let structure = match (&s.structure, &s.structure_file) {
            (Some(st), None) => {
                st.validate().map_err(located)?;
                st.clone()
            }
            (None, Some(f)) => load_structure(&resolve(base, f))?.structure,
            _ => {
                return Err(located(StructureError::invalid(
                    "structure_file",
                    "give exactly one of structure_file and [structure]",
                )));
            }
        };
        s.validate(&structure).map_err(located)?;
        Ok((s, structure))
    }

    /// The file that holds the scenario's structure (`structure_file` resolved, or the scenario
    /// `path` itself), for locating structure errors.
    pub fn structure_source(&self, path: &Path) -> PathBuf {
        match &self.structure_file {
            Some(f) => resolve(path.parent().unwrap_or(Path::new(".")), f),
            None => path.to_path_buf(),
        }
    }
}
