//! Scenario files: a TOML description of a DEM run (materials, contact laws, walls on rigid
//! bodies, particle groups, time stepping, output). See `docs/scenario.md` for the schema.
//!
//! Loading validates everything up front; every error names the key that is wrong.

use crate::InputError;
use pdamp_dem::ParameterError;
use pdamp_dem::contact::ContactModel;
use pdamp_dem::generate::{
    Layering, Region, SizeDistribution, grid_packing, random_insertion_clear_of, tight_packing,
};
use pdamp_dem::walls::{BoxInside, CylinderInside, CylinderOutside, Geometry, Plane};
use pdamp_dem::{
    BodyState, HarmonicTranslation, Integrator, Material, Motion, RigidBody, Vec3, World,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Errors while reading or checking a scenario.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read scenario '{path}': {source}")]
    Read {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// TOML syntax or schema error (serde names key, line and column).
    #[error("scenario '{path}': {message}")]
    Parse {
        /// File.
        path: PathBuf,
        /// Message from the TOML parser.
        message: String,
    },
    /// A value is out of range or inconsistent.
    #[error("scenario '{path}'{}: {message}", at(*line_col))]
    Invalid {
        /// File.
        path: PathBuf,
        /// 1-based line and column of the offending key in the file, when it is there.
        line_col: Option<(usize, usize)>,
        /// What is wrong, which key (the message starts with its path, e.g.
        /// `particles[0].size.radius_m`) and how to fix it.
        message: String,
    },
}

fn at(line_col: Option<(usize, usize)>) -> String {
    match line_col {
        Some((l, c)) => format!(", line {l}, column {c}"),
        None => String::new(),
    }
}

impl ScenarioError {
    /// An [`ScenarioError::Invalid`] for `message` about `key` (its path, e.g.
    /// `particles[0].size.radius_m`) in the scenario file `path` whose text is `text`: the key is
    /// looked up in the text for its line and column (the deepest part of the path that is in
    /// the file).
    pub fn at_key(path: &Path, text: Option<&str>, key: &str, message: String) -> Self {
        let line_col = text.and_then(|t| locate_key(t, key));
        ScenarioError::Invalid {
            path: path.to_path_buf(),
            line_col,
            message,
        }
    }

    /// An [`ScenarioError::Invalid`] for `message` about the scenario file `path` whose text is
    /// `text`: the key path the message starts with is looked up in the text for its line and
    /// column (the deepest part of the path that is in the file).
    pub fn invalid(path: &Path, text: Option<&str>, message: impl Into<String>) -> Self {
        let message = message.into();
        let line_col = text.and_then(|t| locate_key(t, leading_key_path(&message)));
        ScenarioError::Invalid {
            path: path.to_path_buf(),
            line_col,
            message,
        }
    }
}

pub use pdamp_dem::error::leading_key_path;

/// 1-based line and column of key path `key` (`particles[0].size.radius_m`) in TOML `text`: of
/// the deepest prefix of the path present in the file (so a missing key points at its table).
/// `None` if the text does not parse or not even the first key is there.
pub fn locate_key(text: &str, key: &str) -> Option<(usize, usize)> {
    use toml::de::{DeTable, DeValue};
    let root = DeTable::parse(text).ok()?;
    let mut segments: Vec<(String, Vec<usize>)> = Vec::new();
    for part in key.split('.').filter(|p| !p.is_empty()) {
        let (name, rest) = part.split_once('[').unwrap_or((part, ""));
        let idx = rest
            .split('[')
            .filter_map(|i| i.trim_end_matches(']').parse().ok())
            .collect();
        segments.push((name.to_string(), idx));
    }
    let mut table = root.get_ref();
    let mut best: Option<std::ops::Range<usize>> = None;
    'outer: for (name, idx) in &segments {
        let Some((k, v)) = table
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == name.as_str())
        else {
            break;
        };
        best = Some(k.span());
        let mut value = v;
        for &i in idx {
            match value.get_ref() {
                DeValue::Array(a) if i < a.len() => {
                    value = &a[i];
                    best = Some(value.span());
                }
                _ => break 'outer,
            }
        }
        match value.get_ref() {
            DeValue::Table(t) => table = t,
            _ => break,
        }
    }
    let off = best?.start.min(text.len());
    let before = &text[..off];
    let line = before.matches('\n').count() + 1;
    let col = before.rfind('\n').map_or(off, |p| off - p - 1) + 1;
    Some((line, col))
}

/// A complete scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free text shown in outputs.
    #[serde(default)]
    pub title: String,
    /// Time stepping and global settings.
    pub simulation: SimulationSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
    /// Materials, referred to by name.
    pub materials: Vec<Material>,
    /// Contact models.
    pub contact: ContactSpec,
    /// Rigid bodies with their walls.
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Particle groups.
    #[serde(default)]
    pub particles: Vec<ParticleGroupSpec>,
    /// Optional settling (drop-down) phase before the main run.
    #[serde(default)]
    pub settle: Option<SettleSpec>,
    /// Single-damper evaluation: harmonic excitation of a container and the complex power
    /// method [D Sect. 3.2]. With it, `pdamp run` evaluates one point and `pdamp fields` a grid.
    #[serde(default)]
    pub damper: Option<DamperSpec>,
    /// Grid of excitation points for `pdamp fields` (needs `[damper]`).
    #[serde(default)]
    pub fields: Option<FieldsSpec>,
}

/// Standard gravity used for the excitation intensity Γ = A/g [D Eq. 3.11], m/s².
pub const STANDARD_GRAVITY_M_S2: f64 = 9.81;

/// A particle damper moved harmonically, $x_c = X \sin(\Omega t)$ along `direction`
/// [D Eq. 3.8–3.11].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DamperSpec {
    /// Name of the body that is the container (its `motion` is replaced by the excitation).
    pub container_body: String,
    /// Mass of the container m_con, kg (its inertia is part of the driving force).
    pub container_mass_kg: f64,
    /// Excitation direction (normalised on use).
    pub direction: [f64; 3],
    /// Excitation frequency f, Hz (for `pdamp run`; `pdamp fields` uses the grid).
    #[serde(default)]
    pub frequency_hz: Option<f64>,
    /// Displacement amplitude X, m (give exactly one of X, A or Γ).
    #[serde(default)]
    pub amplitude_m: Option<f64>,
    /// Acceleration amplitude A = XΩ², m/s².
    #[serde(default)]
    pub acceleration_m_s2: Option<f64>,
    /// Excitation intensity Γ = A/g (g = 9.81 m/s²).
    #[serde(default)]
    pub intensity: Option<f64>,
    /// Excitation cycles simulated in total.
    #[serde(default = "default_cycles")]
    pub cycles: u32,
    /// Leading cycles dropped as transient before the evaluation.
    #[serde(default = "default_transient_cycles")]
    pub transient_cycles: u32,
    /// Optional early stop of a point once its effective quantities have converged; `cycles`
    /// is then the maximum. Without it every point runs exactly `cycles` cycles.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub convergence: Option<ConvergenceSpec>,
    /// Motion-mode output of `pdamp run` (velocity fields, trajectories, VTK frames).
    #[serde(default)]
    pub motion_output: MotionOutputSpec,
    /// Independently prepared beds per point (an ensemble; packing k uses the seed
    /// `simulation.seed + 1 000 003 k`): results are reported as the mean with the standard
    /// deviation and the 95 % confidence interval over the packings.
    #[serde(default = "default_packings")]
    pub packings: usize,
}

fn default_packings() -> usize {
    1
}

/// Most packings of an ensemble.
pub const MAX_PACKINGS: usize = 1000;

/// Most values of one axis of a field grid.
pub const MAX_AXIS_VALUES: usize = 10_000;
/// Most excitation cycles of a damper point.
pub const MAX_DAMPER_CYCLES: u32 = 100_000;
/// Most phases per cycle of the velocity fields.
pub const MAX_PHASES_PER_CYCLE: u32 = 360;
/// Most cells of the velocity fields along an axis.
pub const MAX_FIELD_CELLS: u32 = 200;
/// Most VTK frames per cycle of a damper point.
pub const MAX_VTK_FRAMES_PER_CYCLE: u32 = 1000;
/// Most particles with a written trajectory.
pub const MAX_TRAJECTORIES: usize = 10_000;

fn default_cycles() -> u32 {
    20
}

/// Early stop of an excitation point [`DamperSpec::convergence`]: after the transient cycles,
/// the running estimates of η̄ and m̄_bed/m_bed over all evaluated cycles (complex power over the
/// whole cycles so far [D Eq. 3.12–3.17]) are taken at the end of every cycle. The point stops
/// once at least `min_evaluated_cycles` cycles are evaluated and the latest estimate differs from
/// each of the estimates of the last `window_cycles` cycles by at most
/// `relative_tolerance × max(|latest|, absolute_floor)`, for η̄ and for m̄_bed/m_bed.
/// η̄ = Ẽ/(π m_bed V²) is Ẽ in units of the bed's power scale, so the η̄ test is the test of the
/// dissipated energy per cycle Ẽ, with the floor `absolute_floor × π m_bed V²`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConvergenceSpec {
    /// Relative tolerance between successive running estimates (0 < tol < 1), e.g. 0.02.
    pub relative_tolerance: f64,
    /// Evaluated cycles (after `transient_cycles`) before a stop is considered (≥ window + 1).
    #[serde(default = "default_min_evaluated_cycles")]
    pub min_evaluated_cycles: u32,
    /// Number of preceding cycle-end estimates the latest one must agree with (≥ 1).
    #[serde(default = "default_window_cycles")]
    pub window_cycles: u32,
    /// Floor of the scale of η̄ and m̄_bed/m_bed (both in units of the bed mass): values below
    /// it are compared absolutely, to `relative_tolerance × absolute_floor` (≥ 0).
    #[serde(default = "default_absolute_floor")]
    pub absolute_floor: f64,
}

fn default_min_evaluated_cycles() -> u32 {
    4
}
fn default_window_cycles() -> u32 {
    2
}
fn default_absolute_floor() -> f64 {
    0.1
}
fn default_transient_cycles() -> u32 {
    5
}

/// What `pdamp run` records of the bed motion on a damper scenario [D Sect. 3.2.1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionOutputSpec {
    /// Phases per cycle at which phase-averaged velocity fields are taken (0 = none); phase k
    /// is Ωt = 2πk/n, so n = 4 gives x_c = 0, X, 0, −X.
    #[serde(default = "default_phases")]
    pub phases_per_cycle: u32,
    /// Cells of the velocity-field grid along the excitation direction (the other axis scales
    /// with the container's aspect ratio).
    #[serde(default = "default_field_cells")]
    pub field_cells: u32,
    /// Particle indices whose trajectories (container frame) are written.
    #[serde(default)]
    pub trajectory_particles: Vec<usize>,
    /// VTK frames per cycle over the last evaluated cycle (0 = none).
    #[serde(default = "default_vtk_frames")]
    pub vtk_frames_per_cycle: u32,
}

fn default_phases() -> u32 {
    4
}
fn default_field_cells() -> u32 {
    24
}
fn default_vtk_frames() -> u32 {
    16
}

impl Default for MotionOutputSpec {
    fn default() -> Self {
        Self {
            phases_per_cycle: default_phases(),
            field_cells: default_field_cells(),
            trajectory_particles: Vec::new(),
            vtk_frames_per_cycle: default_vtk_frames(),
        }
    }
}

impl DamperSpec {
    /// Displacement amplitude X at `frequency_hz` from whichever of X, A, Γ is given, m.
    pub fn amplitude_at(&self, frequency_hz: f64) -> Option<f64> {
        let w = 2.0 * std::f64::consts::PI * frequency_hz;
        match (self.amplitude_m, self.acceleration_m_s2, self.intensity) {
            (Some(x), None, None) => Some(x),
            (None, Some(a), None) => Some(a / (w * w)),
            (None, None, Some(g)) => Some(g * STANDARD_GRAVITY_M_S2 / (w * w)),
            _ => None,
        }
    }
}

/// Values along one axis of the effective-field grid: an explicit list or a range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum AxisSpec {
    /// Explicit values.
    List(Vec<f64>),
    /// `count` values from `from` to `to`, evenly spaced (`linear`) or geometrically (`log`).
    Range {
        /// First value.
        from: f64,
        /// Last value.
        to: f64,
        /// Number of values (≥ 1).
        count: usize,
        /// `linear` or `log`.
        #[serde(default)]
        spacing: Spacing,
    },
}

/// Spacing of a range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// Equal differences.
    #[default]
    Linear,
    /// Equal ratios.
    Log,
}

impl AxisSpec {
    /// The values.
    pub fn values(&self) -> Vec<f64> {
        match self {
            AxisSpec::List(v) => v.clone(),
            AxisSpec::Range {
                from,
                to,
                count,
                spacing,
            } => {
                let n = *count;
                if n == 1 {
                    return vec![*from];
                }
                (0..n)
                    .map(|k| {
                        let s = k as f64 / (n - 1) as f64;
                        match spacing {
                            Spacing::Linear => from + (to - from) * s,
                            Spacing::Log => from * (to / from).powf(s),
                        }
                    })
                    .collect()
            }
        }
    }

    /// True for a logarithmic range (or a list with constant ratios).
    pub fn is_log(&self) -> bool {
        match self {
            AxisSpec::Range { spacing, .. } => *spacing == Spacing::Log,
            AxisSpec::List(v) => {
                v.len() > 2
                    && v.iter().all(|x| *x > 0.0)
                    && v.windows(3).all(|w| {
                        let (a, b) = (w[1] / w[0], w[2] / w[1]);
                        (a / b - 1.0).abs() < 1e-6
                    })
                    && (v[1] / v[0] - 1.0).abs() > 1e-6
                    && {
                        let d = v[1] - v[0];
                        let d2 = v[2] - v[1];
                        (d / d2 - 1.0).abs() > 1e-6
                    }
            }
        }
    }

    fn validate(&self, key: &str) -> Result<(), ParameterError> {
        // The count first: `values` allocates it.
        if let AxisSpec::Range { count, .. } = self
            && *count > MAX_AXIS_VALUES
        {
            return Err(ParameterError::from_message(format!(
                "{key}.count must be at most {MAX_AXIS_VALUES}, got {count}"
            )));
        }
        let v = self.values();
        if v.is_empty() {
            return Err(ParameterError::from_message(format!("{key}: no values")));
        }
        if let AxisSpec::Range {
            from,
            to,
            spacing: Spacing::Log,
            ..
        } = self
            && !(*from > 0.0 && *to > 0.0)
        {
            return Err(ParameterError::from_message(format!(
                "{key}: a log range needs from > 0 and to > 0"
            )));
        }
        if v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(ParameterError::from_message(format!(
                "{key}: all values must be finite and > 0"
            )));
        }
        Ok(())
    }
}

/// Which amplitude measure the second grid axis gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum AmplitudeAxis {
    /// Displacement amplitude X, m.
    Displacement,
    /// Acceleration amplitude A, m/s².
    Acceleration,
    /// Intensity Γ = A/g.
    Intensity,
}

/// Grid of an effective field: frequencies × one amplitude measure [D Sect. 8.1.1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldsSpec {
    /// Excitation frequencies, Hz.
    pub frequencies_hz: AxisSpec,
    /// Displacement amplitudes X, m (give exactly one amplitude axis).
    #[serde(default)]
    pub amplitudes_m: Option<AxisSpec>,
    /// Acceleration amplitudes A, m/s².
    #[serde(default)]
    pub accelerations_m_s2: Option<AxisSpec>,
    /// Intensities Γ = A/g.
    #[serde(default)]
    pub intensities: Option<AxisSpec>,
}

impl FieldsSpec {
    /// The amplitude axis and its spec.
    pub fn amplitude_axis(&self) -> Option<(AmplitudeAxis, &AxisSpec)> {
        match (
            &self.amplitudes_m,
            &self.accelerations_m_s2,
            &self.intensities,
        ) {
            (Some(a), None, None) => Some((AmplitudeAxis::Displacement, a)),
            (None, Some(a), None) => Some((AmplitudeAxis::Acceleration, a)),
            (None, None, Some(a)) => Some((AmplitudeAxis::Intensity, a)),
            _ => None,
        }
    }

    /// Displacement amplitude X for frequency `f` and amplitude-axis value `a`, m.
    pub fn displacement(axis: AmplitudeAxis, f: f64, a: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * f;
        match axis {
            AmplitudeAxis::Displacement => a,
            AmplitudeAxis::Acceleration => a / (w * w),
            AmplitudeAxis::Intensity => a * STANDARD_GRAVITY_M_S2 / (w * w),
        }
    }
}

/// Global settings of the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Simulated duration of the main run (after settling), s.
    pub duration_s: f64,
    /// Time step, s (initial step for Gear).
    pub time_step_s: f64,
    /// Integrator: `{ scheme = "velocity-verlet" }` (default) or `{ scheme = "gear", ... }`.
    #[serde(default = "default_integrator")]
    pub integrator: Integrator,
    /// Gravitational acceleration vector, m/s².
    #[serde(default = "default_gravity")]
    pub gravity_m_s2: [f64; 3],
    /// Seed of all random choices.
    #[serde(default)]
    pub seed: u64,
    /// Verlet skin, m (default 0.2 × smallest radius).
    #[serde(default)]
    pub skin_m: Option<f64>,
    /// Largest allowed ratio time step / shortest contact time (default 0.1).
    #[serde(default = "default_dt_ratio")]
    pub max_time_step_ratio: f64,
    /// Impact velocity used to estimate the shortest contact time, m/s (default 1).
    #[serde(default = "default_check_velocity")]
    pub check_impact_velocity_m_s: f64,
}

fn default_integrator() -> Integrator {
    Integrator::VelocityVerlet
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}
fn default_dt_ratio() -> f64 {
    0.1
}
fn default_check_velocity() -> f64 {
    1.0
}

/// Output settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Interval of rows in `energy.csv`, s.
    #[serde(default = "default_energy_interval")]
    pub energy_interval_s: f64,
    /// Interval of VTK snapshots, s; 0 disables VTK.
    #[serde(default = "default_vtk_interval")]
    pub vtk_interval_s: f64,
    /// Data encoding of the VTK files: `"binary"` (zlib-compressed, appended; the default)
    /// or `"ascii"` (readable and diffable, ≈ 5 × larger).
    #[serde(default)]
    pub vtk_format: VtkFormat,
}

/// Data encoding of VTK output (`output.vtk_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VtkFormat {
    /// zlib-compressed raw binary appended to the file (ParaView's own default).
    #[default]
    Binary,
    /// Shortest round-trip decimal numbers.
    Ascii,
}

impl From<VtkFormat> for crate::vtk::VtkEncoding {
    fn from(f: VtkFormat) -> Self {
        match f {
            VtkFormat::Binary => crate::vtk::VtkEncoding::Binary,
            VtkFormat::Ascii => crate::vtk::VtkEncoding::Ascii,
        }
    }
}

fn default_energy_interval() -> f64 {
    1e-3
}
fn default_vtk_interval() -> f64 {
    0.05
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            energy_interval_s: default_energy_interval(),
            vtk_interval_s: default_vtk_interval(),
            vtk_format: VtkFormat::default(),
        }
    }
}

/// Contact models: a default for all pairs and overrides per material pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Model used for every pair without an override.
    #[serde(flatten)]
    pub default: ContactModel,
    /// Overrides for given material pairs.
    #[serde(default)]
    pub pairs: Vec<PairOverride>,
}

/// A contact model for one pair of materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairOverride {
    /// The two material names.
    pub materials: [String; 2],
    /// The model.
    #[serde(flatten)]
    pub model: ContactModel,
}

/// A rigid body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name.
    pub name: String,
    /// Reference position, m.
    #[serde(default)]
    pub position_m: [f64; 3],
    /// Motion: `{ type = "fixed" }` (default), `{ type = "harmonic", ... }`, `{ type = "driven" }`.
    #[serde(default)]
    pub motion: MotionSpec,
    /// Walls.
    pub walls: Vec<WallSpec>,
}

/// Motion of a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum MotionSpec {
    /// Does not move.
    #[default]
    Fixed,
    /// $x(t) = X \sin(2\pi f t + \varphi)$ along `direction`.
    Harmonic(HarmonicTranslation),
    /// Set from outside (structural coupling).
    Driven,
}

/// One wall of a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Name.
    pub name: String,
    /// Material name.
    pub material: String,
    /// Geometry in the body frame.
    pub geometry: GeometrySpec,
}

/// Geometry of a wall in the scenario file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum GeometrySpec {
    /// Infinite plane.
    Plane(Plane),
    /// Closed cuboid container.
    BoxInside(BoxInside),
    /// Closed cylindrical container.
    CylinderInside(CylinderInside),
    /// Solid rod.
    CylinderOutside(CylinderOutside),
    /// Solid cuboid (plates, bars, crosses inside a container [D Sect. 8.1.4]), axis-aligned in
    /// the body frame; a closed triangle mesh with outward normals.
    BoxOutside(BoxOutsideSpec),
    /// Triangle mesh from an STL file.
    Stl(StlSpec),
}

/// A solid cuboid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxOutsideSpec {
    /// Centre in the body frame, m.
    pub center_m: [f64; 3],
    /// Half edge lengths, m.
    pub half_extents_m: [f64; 3],
}

/// A triangle mesh read from STL.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StlSpec {
    /// Path, relative to the scenario file.
    pub path: PathBuf,
    /// Factor applied to the coordinates (e.g. 0.001 for millimetres).
    #[serde(default = "one")]
    pub scale: f64,
    /// Translation applied after scaling, m.
    #[serde(default)]
    pub translation_m: [f64; 3],
    /// Flip triangle normals (STL normals point out of the solid; a container's cavity needs
    /// them pointing into the particle region).
    #[serde(default)]
    pub flip_normals: bool,
}

fn one() -> f64 {
    1.0
}

/// A group of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleGroupSpec {
    /// Material name.
    pub material: String,
    /// Number of particles (or give `filling`).
    #[serde(default)]
    pub count: Option<usize>,
    /// Number of particles from a filling ratio or a clearance [D Eq. 8.1].
    #[serde(default)]
    pub filling: Option<FillingSpec>,
    /// Size distribution.
    pub size: SizeDistribution,
    /// Where the particles start.
    pub placement: PlacementSpec,
    /// Initial velocity, m/s.
    #[serde(default)]
    pub initial_velocity_m_s: [f64; 3],
}

/// Refuses an array of the file that is longer than the one it was read into (a vector
/// `[x, y, z, w]` read as `[x, y, z]`): walks the tables of both, `key` is the path so far.
fn check_array_lengths(
    original: &toml::Table,
    canonical: &toml::Table,
    key: &str,
) -> Result<(), ParameterError> {
    for (k, v) in original {
        let Some(c) = canonical.get(k) else { continue };
        let path = if key.is_empty() {
            k.clone()
        } else {
            format!("{key}.{k}")
        };
        check_value_lengths(v, c, &path)?;
    }
    Ok(())
}

fn check_value_lengths(v: &toml::Value, c: &toml::Value, path: &str) -> Result<(), ParameterError> {
    match (v, c) {
        (toml::Value::Table(a), toml::Value::Table(b)) => check_array_lengths(a, b, path),
        (toml::Value::Array(a), toml::Value::Array(b)) => {
            if a.len() != b.len() && a.iter().all(|x| x.is_float() || x.is_integer()) {
                return Err(ParameterError::from_message(format!(
                    "{path} has {} components, {} expected (e.g. [x, y, z])",
                    a.len(),
                    b.len()
                )));
            }
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                check_value_lengths(x, y, &format!("{path}[{k}]"))?;
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Particle number from the container's capacity $n_p^{max}$: either a filling ratio
/// $n_p/n_p^{max}$ or a clearance h to the lid, $n_p = n_p^{max}(1 - h/L)$ [D Eq. 8.1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FillingSpec {
    /// Particles that fill the container completely, $n_p^{max}$.
    pub max_count: usize,
    /// Filling ratio $n_p / n_p^{max}$ in (0, 1].
    #[serde(default)]
    pub ratio: Option<f64>,
    /// Clearance h between bed and lid, m.
    #[serde(default)]
    pub clearance_m: Option<f64>,
    /// Inner container length L along the excitation, m (with `clearance_m`).
    #[serde(default)]
    pub container_length_m: Option<f64>,
}

impl ParticleGroupSpec {
    /// Number of particles of the group from `count` or `filling`.
    pub fn resolved_count(&self) -> Result<usize, ParameterError> {
        match (&self.count, &self.filling) {
            (Some(n), None) => Ok(*n),
            (None, Some(f)) => {
                if f.max_count == 0 {
                    return Err(ParameterError::from_message(
                        "filling.max_count must be > 0",
                    ));
                }
                let ratio = match (f.ratio, f.clearance_m, f.container_length_m) {
                    (Some(r), None, None) => {
                        if !(r > 0.0 && r <= 1.0) {
                            return Err(ParameterError::from_message(format!(
                                "filling.ratio must be in (0, 1], got {r}"
                            )));
                        }
                        r
                    }
                    (None, Some(h), Some(l)) => {
                        if !(l > 0.0 && h >= 0.0 && h < l) {
                            return Err(ParameterError::from_message(format!(
                                "filling: need 0 <= clearance_m < container_length_m, got {h} and {l}"
                            )));
                        }
                        1.0 - h / l
                    }
                    _ => {
                        return Err(ParameterError::from_message(
                            "filling: give either ratio, or clearance_m together with container_length_m",
                        ));
                    }
                };
                Ok((ratio * f.max_count as f64).round() as usize)
            }
            _ => Err(ParameterError::from_message(
                "count: give exactly one of `count` and `filling` in the group",
            )),
        }
    }
}

/// Initial placement of a particle group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpec {
    /// `drop_down` (random insertion clear of every wall, falling in rounds under gravity: the
    /// dissertation's beds), `random` (random insertion clear of every wall, no fall), `grid`
    /// (simple cubic crystal), `tight` (hexagonal close-packed crystal) or `file` (a saved or
    /// imported bed).
    pub method: PlacementMethod,
    /// Region to fill (all methods but `file`), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Region>,
    /// Gap between neighbouring spheres (lattices), m.
    #[serde(default)]
    pub gap_m: f64,
    /// For `random`: height of insertion layers (layer by layer), m.
    #[serde(default)]
    pub layer_height_m: Option<f64>,
    /// For `file`: the bed file, relative to the scenario file: a native bed of `pdamp settle`
    /// (`*.pdbed`, exact continuation), a LAMMPS/LIGGGHTS data file of `write_data`
    /// (`*.data`, `*.lmp`; SI units, `atom_style sphere` or `granular`) or a CSV file
    /// (`*.csv`: `x_m,y_m,z_m,radius_m[,vx_m_s,…]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// For `file`: the format when the extension does not tell (`native`, `lammps`, `csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<BedFormat>,
    /// For `file` with a LAMMPS data file: material name of atom type 1, 2, … (default: every
    /// atom gets the group's material).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub type_materials: Vec<String>,
    /// For `drop_down`: most insertion rounds (default 200).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_rounds: Option<usize>,
    /// For `drop_down`: longest fall of a round, s (default 0.5 s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_round_duration_s: Option<f64>,
    /// For `drop_down`: a round's fall ends when the kinetic energy per particle is below this,
    /// J (default: 1 % of m g r of the mean particle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub round_kinetic_energy_per_particle_j: Option<f64>,
    /// For `drop_down`: fill with the lid open and close it afterwards (D L3085, L3093), for
    /// containers whose clearance to the lid is less than a diameter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_lid: Option<OpenLidSpec>,
    /// For `drop_down`: pour from an inlet over time instead of inserting in rounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inlet: Option<InletSpec>,
}

/// `placement.inlet` of a `drop_down` group ([`pdamp_dem::drop_down::Inlet`]): the particles
/// are inserted into `region` at `rate_per_s` with `velocity_m_s` while the world runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InletSpec {
    /// The inlet region inside the container, above the bed, m.
    pub region: Region,
    /// Particles per second of simulated time.
    pub rate_per_s: f64,
    /// Velocity of the inserted particles, m/s (default at rest).
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// `placement.open_lid` of a `drop_down` group: the walls that end at the region's top are
/// extended by `headroom_m` while the particles pour in; then the lid closes onto the bed at
/// `close_speed_m_s`, pushing with at most the bed's weight, while the container is tapped
/// along −g at `tap_frequency_hz` with Γ = `tap_intensity` where given
/// ([`pdamp_dem::drop_down::OpenLid`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpenLidSpec {
    /// How far the container is extended above its top while pouring, m.
    pub headroom_m: f64,
    /// Closing speed of the lid onto a bed that stands above the top, m/s (default 0.02).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub close_speed_m_s: Option<f64>,
    /// Longest closing before the preparation gives up, s (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_close_duration_s: Option<f64>,
    /// Tapping frequency while the lid closes, Hz (with `tap_intensity`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tap_frequency_hz: Option<f64>,
    /// Tapping acceleration amplitude over g, Γ (with `tap_frequency_hz`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tap_intensity: Option<f64>,
}

impl OpenLidSpec {
    /// Checks ranges; the message names the key under `key`.
    fn validate(&self, key: &str) -> Result<(), ParameterError> {
        let check = |name: &str, v: f64, hi: f64, unit: &str| {
            if v.is_finite() && v > 0.0 && v <= hi {
                Ok(())
            } else {
                Err(ParameterError::from_message(format!(
                    "{key}.open_lid.{name} must be in (0, {hi}] {unit}, got {v}"
                )))
            }
        };
        check("headroom_m", self.headroom_m, 100.0, "m")?;
        if let Some(v) = self.close_speed_m_s {
            check("close_speed_m_s", v, 100.0, "m/s")?;
        }
        if let Some(v) = self.max_close_duration_s {
            check("max_close_duration_s", v, 1e3, "s")?;
        }
        match (self.tap_frequency_hz, self.tap_intensity) {
            (Some(f), Some(i)) => {
                check("tap_frequency_hz", f, 1e5, "Hz")?;
                check("tap_intensity", i, 1e3, "(Γ = A/g)")
            }
            (None, None) => Ok(()),
            _ => Err(ParameterError::from_message(format!(
                "{key}.open_lid.tap_frequency_hz: give tap_frequency_hz and tap_intensity together (or neither)"
            ))),
        }
    }

    /// The drop-down's settings.
    pub fn to_open_lid(&self) -> pdamp_dem::drop_down::OpenLid {
        pdamp_dem::drop_down::OpenLid {
            headroom_m: self.headroom_m,
            close_speed_m_s: self.close_speed_m_s.unwrap_or(0.02),
            max_close_duration_s: self.max_close_duration_s.unwrap_or(2.0),
            tapping: match (self.tap_frequency_hz, self.tap_intensity) {
                (Some(frequency_hz), Some(intensity)) => Some(pdamp_dem::drop_down::Tapping {
                    frequency_hz,
                    intensity,
                }),
                _ => None,
            },
        }
    }
}

impl PlacementSpec {
    /// `method` in `region` with every other key at its default.
    pub fn new(method: PlacementMethod, region: Region) -> Self {
        Self {
            method,
            region: Some(region),
            gap_m: 0.0,
            layer_height_m: None,
            path: None,
            format: None,
            type_materials: Vec::new(),
            max_rounds: None,
            max_round_duration_s: None,
            round_kinetic_energy_per_particle_j: None,
            open_lid: None,
            inlet: None,
        }
    }
}

/// Placement method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlacementMethod {
    /// Simple cubic lattice (a crystal).
    Grid,
    /// Hexagonal close packing (a crystal).
    Tight,
    /// Random without overlap, clear of every wall; no fall.
    Random,
    /// Random insertion clear of every wall, falling in rounds under gravity
    /// ([`pdamp_dem::drop_down`], D Sect. 2.1, Fig. 2.2c/d).
    DropDown,
    /// A saved or imported bed ([`PlacementSpec::path`]).
    File,
}

/// Format of a bed file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BedFormat {
    /// pdamp's own bed file (`pdamp settle`), with the state for an exact continuation.
    Native,
    /// LAMMPS/LIGGGHTS data file (`write_data`).
    Lammps,
    /// Plain CSV.
    Csv,
}

impl BedFormat {
    /// The format `format` says, or the one of the path's extension.
    pub fn of(path: &Path, format: Option<BedFormat>) -> Result<BedFormat, ParameterError> {
        if let Some(f) = format {
            return Ok(f);
        }
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("pdbed") => Ok(BedFormat::Native),
            Some("data" | "lmp" | "lammps") => Ok(BedFormat::Lammps),
            Some("csv") => Ok(BedFormat::Csv),
            _ => Err(ParameterError::from_message(format!(
                "cannot tell the bed format of '{}' from its extension; name it *.pdbed, \
                 *.data or *.csv, or set placement.format = \"native\" | \"lammps\" | \"csv\"",
                path.display()
            ))),
        }
    }
}

/// Settling (drop-down) before the main run: the bodies stay at their reference pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettleSpec {
    /// Longest settling time, s.
    pub max_duration_s: f64,
    /// Settling ends early when the kinetic energy per particle falls below this, J.
    #[serde(default)]
    pub kinetic_energy_per_particle_j: f64,
    /// Gravity during settling, m/s² (default: `simulation.gravity_m_s2`). Lets a container be
    /// filled along one axis and then "turned", e.g. a cylinder filled with its axis vertical and
    /// excited with the axis horizontal [D Sect. 8.1.1].
    #[serde(default)]
    pub gravity_m_s2: Option<[f64; 3]>,
    /// Longest second settling stage after the "turn" to `simulation.gravity_m_s2`, s (only
    /// with `gravity_m_s2`; default `max_duration_s`). Used by damper runs and fields, whose
    /// steady state needs a bed at rest under the run gravity.
    #[serde(default)]
    pub turn_max_duration_s: Option<f64>,
}

impl Scenario {
    /// Reads and validates a scenario file.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        let s = Self::from_toml_in(&text, &base).map_err(|e| match e {
            InputError::Toml(e) => ScenarioError::Parse {
                path: path.to_path_buf(),
                message: e.to_string(),
            },
            e => ScenarioError::at_key(path, Some(&text), e.key(), e.to_string()),
        })?;
        s.validate()
            .map_err(|e| ScenarioError::at_key(path, Some(&text), e.key(), e.to_string()))?;
        // Vectors are read into fixed-size arrays, which ignore extra components: compare
        // every array of the file with the scenario as read.
        if let (Ok(original), Ok(canonical)) = (
            text.parse::<toml::Table>(),
            s.to_toml().parse::<toml::Table>(),
        ) {
            check_array_lengths(&original, &canonical, "")
                .map_err(|e| ScenarioError::at_key(path, Some(&text), e.key(), e.to_string()))?;
        }
        Ok(s)
    }

    /// Reads and validates a scenario file and builds its world (paths relative to the file):
    /// all checks run before any output is written, and every error names the file, the key
    /// with its line and column, and the fix. `drop_down` groups are checked for fit but not
    /// dropped ([`Preparation::Check`]): their particles sit at placeholder positions far from
    /// the container (right for counts, masses and the time-step check, not for a run).
    pub fn load_and_build(path: &Path) -> Result<(Self, World), ScenarioError> {
        let s = Self::load(path)?;
        // Work and memory before anything is allocated (one run or one damper point).
        crate::estimate::Estimate::of(&s, 1, rayon::current_num_threads())
            .check()
            .map_err(|e| {
                let text = std::fs::read_to_string(path).ok();
                ScenarioError::at_key(path, text.as_deref(), e.key(), e.to_string())
            })?;
        let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        let world = s
            .build_world_with(&base, Preparation::Check, &mut |_, _| {})
            .map_err(|e| {
                let text = std::fs::read_to_string(path).ok();
                ScenarioError::at_key(path, text.as_deref(), e.key(), e.to_string())
            })?;
        Ok((s, world))
    }

    /// Parses TOML text (no validation).
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Parses TOML text whose file lies in `base_dir`: restitution tables named by
    /// `restitution_table_csv` are read from CSV files relative to it
    /// ([`crate::restitution::inline_tables`]). No validation.
    pub fn from_toml_in(text: &str, base_dir: &Path) -> Result<Self, InputError> {
        if !text.contains(crate::restitution::TABLE_KEY) {
            return Ok(Self::from_toml(text)?);
        }
        let mut doc: toml::Table = toml::from_str(text)?;
        crate::restitution::inline_tables(&mut doc, base_dir)?;
        Ok(toml::Value::Table(doc).try_into()?)
    }

    /// Serialises to TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }

    /// Files the scenario reads besides itself (STL walls, bed files), as written in it
    /// (relative to the scenario file). Restitution tables are inlined by [`Self::to_toml`].
    pub fn referenced_files(&self) -> Vec<PathBuf> {
        let walls = self.bodies.iter().flat_map(|b| &b.walls);
        let stl = walls.filter_map(|w| match &w.geometry {
            GeometrySpec::Stl(s) => Some(s.path.clone()),
            _ => None,
        });
        let beds = self
            .particles
            .iter()
            .filter_map(|g| g.placement.path.clone());
        stl.chain(beds).collect()
    }

    /// Checks `damper.motion_output`: sizes that fit a cycle and the bed.
    fn validate_motion_output(&self, d: &DamperSpec) -> Result<(), ParameterError> {
        let m = &d.motion_output;
        if m.phases_per_cycle > MAX_PHASES_PER_CYCLE {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.phases_per_cycle must lie in 0..={MAX_PHASES_PER_CYCLE} (0 = no velocity fields), got {}; 4 gives the phases 0, 90, 180 and 270°",
                m.phases_per_cycle
            )));
        }
        if !(1..=MAX_FIELD_CELLS).contains(&m.field_cells) {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.field_cells must lie in 1..={MAX_FIELD_CELLS}, got {}; e.g. 12",
                m.field_cells
            )));
        }
        if m.vtk_frames_per_cycle > MAX_VTK_FRAMES_PER_CYCLE {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.vtk_frames_per_cycle must be at most {MAX_VTK_FRAMES_PER_CYCLE}, got {}; e.g. 8",
                m.vtk_frames_per_cycle
            )));
        }
        if let Some(f) = d.frequency_hz {
            let steps_per_cycle = 1.0 / (f * self.simulation.time_step_s);
            for (k, n) in [
                ("phases_per_cycle", m.phases_per_cycle),
                ("vtk_frames_per_cycle", m.vtk_frames_per_cycle),
            ] {
                if f64::from(n) > steps_per_cycle {
                    return Err(ParameterError::from_message(format!(
                        "damper.motion_output.{k} ({n}) exceeds the {steps_per_cycle:.0} time steps of a cycle at {f} Hz; use at most {}",
                        steps_per_cycle.floor().max(1.0)
                    )));
                }
            }
        }
        let n: Option<usize> = self
            .particles
            .iter()
            .map(|g| g.resolved_count().ok())
            .try_fold(0usize, |a, c| c.map(|c| a.saturating_add(c)))
            .filter(|_| {
                self.particles
                    .iter()
                    .all(|g| g.placement.method != PlacementMethod::File)
            });
        if let Some(n) = n
            && let Some(&i) = m.trajectory_particles.iter().find(|&&i| i >= n)
        {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.trajectory_particles: particle {i} does not exist (the bed has {n} particles, indices 0..={})",
                n.saturating_sub(1)
            )));
        }
        if m.trajectory_particles.len() > MAX_TRAJECTORIES {
            return Err(ParameterError::from_message(format!(
                "damper.motion_output.trajectory_particles lists {} particles, at most {MAX_TRAJECTORIES}",
                m.trajectory_particles.len()
            )));
        }
        Ok(())
    }

    /// Checks the placement of group `g` (keys as `particles[g].placement.…`).
    fn validate_placement(&self, g: usize, pl: &PlacementSpec) -> Result<(), ParameterError> {
        let key = format!("particles[{g}].placement");
        let is_file = pl.method == PlacementMethod::File;
        match (&pl.region, is_file) {
            (Some(r), false) => r
                .validate()
                .map_err(|e| e.under(&format!("{key}.region.")))?,
            (None, false) => {
                return Err(ParameterError::from_message(format!(
                    "{key}.region: missing; give the volume to fill, e.g. region = {{ type = \"box\", min_m = [..], max_m = [..] }}"
                )));
            }
            (Some(_), true) => {
                return Err(ParameterError::from_message(format!(
                    "{key}.region: a bed from a file has its own positions; remove region"
                )));
            }
            (None, true) => {}
        }
        if is_file && pl.path.is_none() {
            return Err(ParameterError::from_message(format!(
                "{key}.path: missing; method = \"file\" needs the bed file (from `pdamp settle`, LAMMPS write_data or CSV)"
            )));
        }
        if !is_file && (pl.path.is_some() || pl.format.is_some() || !pl.type_materials.is_empty()) {
            return Err(ParameterError::from_message(format!(
                "{key}.path: path, format and type_materials belong to method = \"file\""
            )));
        }
        if is_file && self.particles.len() > 1 {
            return Err(ParameterError::from_message(format!(
                "{key}.method: a bed file holds the whole bed; it must be the only [[particles]] group"
            )));
        }
        for m in &pl.type_materials {
            self.material_index(m, &format!("{key}.type_materials"))?;
        }
        let is_drop = pl.method == PlacementMethod::DropDown;
        if !is_drop
            && (pl.max_rounds.is_some()
                || pl.max_round_duration_s.is_some()
                || pl.round_kinetic_energy_per_particle_j.is_some()
                || pl.open_lid.is_some()
                || pl.inlet.is_some())
        {
            return Err(ParameterError::from_message(format!(
                "{key}.max_rounds: max_rounds, max_round_duration_s, round_kinetic_energy_per_particle_j, open_lid and inlet belong to method = \"drop_down\""
            )));
        }
        if let Some(i) = &pl.inlet {
            i.region
                .validate()
                .map_err(|e| e.under(&format!("{key}.inlet.region.")))?;
            if !(i.rate_per_s.is_finite() && i.rate_per_s > 0.0 && i.rate_per_s <= 1e9) {
                return Err(ParameterError::from_message(format!(
                    "{key}.inlet.rate_per_s must be in (0, 1e9] particles per second, got {}",
                    i.rate_per_s
                )));
            }
            if !i
                .velocity_m_s
                .iter()
                .all(|v| v.is_finite() && v.abs() <= 1e3)
            {
                return Err(ParameterError::from_message(format!(
                    "{key}.inlet.velocity_m_s must be finite and at most 1000 m/s, got {:?}",
                    i.velocity_m_s
                )));
            }
        }
        if let Some(l) = &pl.open_lid {
            l.validate(&key)?;
        }
        if pl.max_rounds == Some(0) {
            return Err(ParameterError::from_message(format!(
                "{key}.max_rounds must be >= 1"
            )));
        }
        if let Some(t) = pl.max_round_duration_s
            && !(t.is_finite() && t > 0.0 && t <= 1e3)
        {
            return Err(ParameterError::from_message(format!(
                "{key}.max_round_duration_s must be in (0, 1000] s, got {t}"
            )));
        }
        if let Some(e) = pl.round_kinetic_energy_per_particle_j
            && !(e.is_finite() && e >= 0.0)
        {
            return Err(ParameterError::from_message(format!(
                "{key}.round_kinetic_energy_per_particle_j must be finite and >= 0 (J), got {e}"
            )));
        }
        if is_drop && self.fill_gravity().norm() == 0.0 {
            return Err(ParameterError::from_message(format!(
                "{key}.method: drop_down lets the particles fall, but gravity is zero; set simulation.gravity_m_s2 or settle.gravity_m_s2, or use method = \"random\""
            )));
        }
        Ok(())
    }

    /// Gravity while the bed is made: `settle.gravity_m_s2` when given, else the run's, m/s².
    pub fn fill_gravity(&self) -> Vec3 {
        Vec3::from(
            self.settle
                .as_ref()
                .and_then(|s| s.gravity_m_s2)
                .unwrap_or(self.simulation.gravity_m_s2),
        )
    }

    /// Whether any group starts from a crystal (`grid` or `tight`): such a bed has another
    /// packing fraction and clearance than the dissertation's drop-down beds and moves as a
    /// block (a warning for damper scenarios).
    pub fn crystal_groups(&self) -> Vec<usize> {
        self.particles
            .iter()
            .enumerate()
            .filter(|(_, g)| {
                matches!(
                    g.placement.method,
                    PlacementMethod::Grid | PlacementMethod::Tight
                )
            })
            .map(|(i, _)| i)
            .collect()
    }

    fn material_index(&self, name: &str, key: &str) -> Result<u16, ParameterError> {
        self.materials
            .iter()
            .position(|m| m.name == name)
            .map(|i| i as u16)
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                ParameterError::invalid(
                    key,
                    format!(
                        "{key}: unknown material '{name}' (defined: {})",
                        known.join(", ")
                    ),
                )
            })
    }

    /// Checks ranges and references. Every message starts with the path of the offending key
    /// (`particles[0].size.radius_m …`, located by [`ScenarioError::invalid`]) and says how
    /// to fix it.
    pub fn validate(&self) -> Result<(), ParameterError> {
        self.validate_simulation_and_output()?;
        self.validate_materials_and_contact()?;
        self.validate_bodies()?;
        self.validate_damper()?;
        self.validate_fields()?;
        self.validate_settle_and_particles()
    }

    /// `[simulation]` and `[output]`.
    fn validate_simulation_and_output(&self) -> Result<(), ParameterError> {
        let s = &self.simulation;
        if !(s.duration_s.is_finite() && s.duration_s >= 0.0) {
            return Err(ParameterError::from_message(format!(
                "simulation.duration_s must be a finite time >= 0 in seconds, got {}",
                s.duration_s
            )));
        }
        if !finite_pos(s.time_step_s) {
            return Err(ParameterError::from_message(format!(
                "simulation.time_step_s must be > 0 (seconds), got {}; a safe value is about 1/20 \
                 of the contact time (`pdamp check` prints it)",
                s.time_step_s
            )));
        }
        if s.duration_s > 0.0 && s.time_step_s > s.duration_s {
            return Err(ParameterError::from_message(format!(
                "simulation.time_step_s ({}) exceeds simulation.duration_s ({}); check the units \
                 (both in seconds)",
                s.time_step_s, s.duration_s
            )));
        }
        if let Integrator::Gear(g) = &s.integrator {
            g.validate(s.time_step_s)
                .map_err(|e| e.under("simulation.integrator."))?;
        }
        if s.gravity_m_s2.iter().any(|g| !g.is_finite()) {
            return Err(ParameterError::from_message(format!(
                "simulation.gravity_m_s2 must be finite, got {:?}; e.g. [0.0, 0.0, -9.81]",
                s.gravity_m_s2
            )));
        }
        if let Some(skin) = s.skin_m
            && !finite_pos(skin)
        {
            return Err(ParameterError::from_message(format!(
                "simulation.skin_m must be > 0 (metres), got {skin}; leave it out for the default \
                 0.2 × smallest radius"
            )));
        }
        if !(s.max_time_step_ratio > 0.0 && s.max_time_step_ratio <= 1.0) {
            return Err(ParameterError::from_message(format!(
                "simulation.max_time_step_ratio must lie in (0, 1], got {}; 0.1 is the default",
                s.max_time_step_ratio
            )));
        }
        if !finite_pos(s.check_impact_velocity_m_s) {
            return Err(ParameterError::from_message(format!(
                "simulation.check_impact_velocity_m_s must be > 0 (m/s), got {}",
                s.check_impact_velocity_m_s
            )));
        }
        if !finite_pos(self.output.energy_interval_s) {
            return Err(ParameterError::from_message(format!(
                "output.energy_interval_s must be > 0 (seconds), got {}",
                self.output.energy_interval_s
            )));
        }
        if !(self.output.vtk_interval_s.is_finite() && self.output.vtk_interval_s >= 0.0) {
            return Err(ParameterError::from_message(format!(
                "output.vtk_interval_s must be >= 0 (seconds; 0 switches VTK off), got {}",
                self.output.vtk_interval_s
            )));
        }
        Ok(())
    }

    /// `[[materials]]` (unique names) and `[contact]` with its pairs.
    fn validate_materials_and_contact(&self) -> Result<(), ParameterError> {
        if self.materials.is_empty() {
            return Err(ParameterError::from_message(
                "materials: at least one material is needed; add a [[materials]] table with name, \
                 density_kg_m3, youngs_modulus_pa and poisson_ratio",
            ));
        }
        for (k, m) in self.materials.iter().enumerate() {
            m.validate()
                .map_err(|e| e.under(&format!("materials[{k}].")))?;
            if self.materials[..k].iter().any(|o| o.name == m.name) {
                return Err(ParameterError::from_message(format!(
                    "materials[{k}].name: duplicate material name '{}'; give every material its \
                     own name",
                    m.name
                )));
            }
        }
        self.contact
            .default
            .validate()
            .map_err(|e| e.under("contact."))?;
        for (k, p) in self.contact.pairs.iter().enumerate() {
            let key = format!("contact.pairs[{k}].materials");
            let a = self.material_index(&p.materials[0], &key)?;
            let b = self.material_index(&p.materials[1], &key)?;
            if self.contact.pairs[..k].iter().any(|o| {
                let (c, d) = (
                    self.material_index(&o.materials[0], "").unwrap_or(u16::MAX),
                    self.material_index(&o.materials[1], "").unwrap_or(u16::MAX),
                );
                (a, b) == (c, d) || (a, b) == (d, c)
            }) {
                return Err(ParameterError::from_message(format!(
                    "{key}: the pair {:?} has a contact model already; keep one [[contact.pairs]] \
                     entry per material pair",
                    p.materials
                )));
            }
            p.model
                .validate()
                .map_err(|e| e.under(&format!("contact.pairs[{k}].")))?;
        }
        Ok(())
    }

    /// `[[bodies]]`: unique names, motions, walls.
    fn validate_bodies(&self) -> Result<(), ParameterError> {
        for (b, body) in self.bodies.iter().enumerate() {
            if self.bodies[..b].iter().any(|o| o.name == body.name) {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].name: duplicate body name '{}'; give every body its own name",
                    body.name
                )));
            }
            if body.position_m.iter().any(|x| !x.is_finite()) {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].position_m must be finite"
                )));
            }
            if body.walls.is_empty() {
                return Err(ParameterError::from_message(format!(
                    "bodies[{b}].walls: body '{}' has no walls; add a [[bodies.walls]] table",
                    body.name
                )));
            }
            for (w, wall) in body.walls.iter().enumerate() {
                self.material_index(&wall.material, &format!("bodies[{b}].walls[{w}].material"))?;
            }
            if let MotionSpec::Harmonic(h) = &body.motion {
                if !Vec3::from(h.direction).norm().is_finite()
                    || Vec3::from(h.direction).norm() == 0.0
                {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.direction must be a finite non-zero vector, got {:?}; \
                         e.g. [1.0, 0.0, 0.0] for horizontal shaking",
                        h.direction
                    )));
                }
                if !finite_pos(h.frequency_hz) {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.frequency_hz must be > 0 (Hz), got {}",
                        h.frequency_hz
                    )));
                }
                if !(h.amplitude_m.is_finite() && h.amplitude_m >= 0.0 && h.amplitude_m <= 1.0) {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.amplitude_m must lie in [0, 1] m, got {}; check the unit",
                        h.amplitude_m
                    )));
                }
                if h.frequency_hz > 1e5 {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.frequency_hz must be at most 1e5 Hz, got {}",
                        h.frequency_hz
                    )));
                }
                if !h.phase_rad.is_finite() {
                    return Err(ParameterError::from_message(format!(
                        "bodies[{b}].motion.phase_rad must be finite (radians), got {}",
                        h.phase_rad
                    )));
                }
            }
        }
        Ok(())
    }

    /// `[damper]`: the container body, the excitation and the cycles.
    fn validate_damper(&self) -> Result<(), ParameterError> {
        if let Some(d) = &self.damper {
            if !self.bodies.iter().any(|b| b.name == d.container_body) {
                let known: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                return Err(ParameterError::from_message(format!(
                    "damper.container_body: no body named '{}'; use one of: {}",
                    d.container_body,
                    known.join(", ")
                )));
            }
            if !(1..=MAX_PACKINGS).contains(&d.packings) {
                return Err(ParameterError::from_message(format!(
                    "damper.packings must be in 1..={MAX_PACKINGS} (independently prepared beds), got {}",
                    d.packings
                )));
            }
            if !(d.container_mass_kg.is_finite()
                && d.container_mass_kg >= 0.0
                && d.container_mass_kg <= 1e6)
            {
                return Err(ParameterError::from_message(format!(
                    "damper.container_mass_kg must lie in [0, 1e6] kg, got {}; check the unit",
                    d.container_mass_kg
                )));
            }
            if Vec3::from(d.direction).norm() == 0.0 || !Vec3::from(d.direction).norm().is_finite()
            {
                return Err(ParameterError::from_message(format!(
                    "damper.direction must be a finite non-zero vector, got {:?}; e.g. [1.0, 0.0, 0.0]",
                    d.direction
                )));
            }
            let given = [
                d.amplitude_m.is_some(),
                d.acceleration_m_s2.is_some(),
                d.intensity.is_some(),
            ]
            .iter()
            .filter(|x| **x)
            .count();
            if given > 1 {
                return Err(ParameterError::from_message(
                    "damper: give only one of amplitude_m, acceleration_m_s2, intensity (they \
                     describe the same amplitude); delete the others",
                ));
            }
            if self.fields.is_none() && given == 0 {
                return Err(ParameterError::from_message(
                    "damper: give one of amplitude_m, acceleration_m_s2 or intensity (or a [fields] grid)",
                ));
            }
            for (k, v) in [
                ("amplitude_m", d.amplitude_m),
                ("acceleration_m_s2", d.acceleration_m_s2),
                ("intensity", d.intensity),
                ("frequency_hz", d.frequency_hz),
            ] {
                if let Some(v) = v
                    && !finite_pos(v)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.{k} must be > 0, got {v}"
                    )));
                }
            }
            if self.fields.is_none() && d.frequency_hz.is_none() {
                return Err(ParameterError::from_message(
                    "damper.frequency_hz is needed (or a [fields] grid)",
                ));
            }
            // Physical ranges (a finite but absurd number gives finite nonsense downstream).
            for (k, v, max, unit) in [
                ("amplitude_m", d.amplitude_m, 1.0, "m"),
                ("acceleration_m_s2", d.acceleration_m_s2, 1e6, "m/s²"),
                ("intensity", d.intensity, 1e5, "(A/g)"),
                ("frequency_hz", d.frequency_hz, 1e5, "Hz"),
            ] {
                if let Some(v) = v
                    && !(finite_pos(v) && v <= max)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.{k} must lie in (0, {max:e}] {unit}, got {v}; check the unit"
                    )));
                }
            }
            if d.cycles > MAX_DAMPER_CYCLES {
                return Err(ParameterError::from_message(format!(
                    "damper.cycles must be at most {MAX_DAMPER_CYCLES}, got {}; use [damper.convergence] to stop when the result has settled",
                    d.cycles
                )));
            }
            self.validate_motion_output(d)?;
            if d.cycles <= d.transient_cycles {
                return Err(ParameterError::from_message(format!(
                    "damper.cycles ({}) must exceed damper.transient_cycles ({}); e.g. cycles = {}",
                    d.cycles,
                    d.transient_cycles,
                    d.transient_cycles + 15
                )));
            }
            if let Some(c) = &d.convergence {
                if !(c.relative_tolerance.is_finite()
                    && c.relative_tolerance > 0.0
                    && c.relative_tolerance < 1.0)
                {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.relative_tolerance must be in (0, 1), got {}; e.g. 0.02",
                        c.relative_tolerance
                    )));
                }
                if c.window_cycles == 0 {
                    return Err(ParameterError::from_message(
                        "damper.convergence.window_cycles must be >= 1, got 0; e.g. 2",
                    ));
                }
                if c.min_evaluated_cycles <= c.window_cycles {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.min_evaluated_cycles ({}) must exceed \
                         damper.convergence.window_cycles ({}): the first estimate compared needs \
                         window_cycles earlier ones; e.g. min_evaluated_cycles = {}",
                        c.min_evaluated_cycles,
                        c.window_cycles,
                        c.window_cycles + 2
                    )));
                }
                if d.transient_cycles + c.min_evaluated_cycles > d.cycles {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.min_evaluated_cycles ({}) plus damper.transient_cycles \
                         ({}) exceeds damper.cycles ({}), the maximum; raise cycles to at least {}",
                        c.min_evaluated_cycles,
                        d.transient_cycles,
                        d.cycles,
                        d.transient_cycles + c.min_evaluated_cycles
                    )));
                }
                if !(c.absolute_floor.is_finite() && c.absolute_floor >= 0.0) {
                    return Err(ParameterError::from_message(format!(
                        "damper.convergence.absolute_floor must be >= 0 (in units of the bed mass), \
                         got {}; e.g. 0.1",
                        c.absolute_floor
                    )));
                }
            }
        }
        Ok(())
    }

    /// `[fields]`: a damper and exactly one amplitude axis.
    fn validate_fields(&self) -> Result<(), ParameterError> {
        if let Some(f) = &self.fields {
            if self.damper.is_none() {
                return Err(ParameterError::from_message(
                    "fields: a [damper] section is needed; add one with container_body, \
                     container_mass_kg and direction",
                ));
            }
            f.frequencies_hz.validate("fields.frequencies_hz")?;
            match f.amplitude_axis() {
                Some((AmplitudeAxis::Displacement, a)) => a.validate("fields.amplitudes_m")?,
                Some((AmplitudeAxis::Acceleration, a)) => {
                    a.validate("fields.accelerations_m_s2")?
                }
                Some((AmplitudeAxis::Intensity, a)) => a.validate("fields.intensities")?,
                None => {
                    return Err(ParameterError::from_message(
                        "fields: give exactly one of amplitudes_m, accelerations_m_s2, intensities",
                    ));
                }
            }
        }
        Ok(())
    }

    /// `[settle]` and every `[[particles]]` group.
    fn validate_settle_and_particles(&self) -> Result<(), ParameterError> {
        if let Some(st) = &self.settle {
            if !(st.max_duration_s.is_finite() && st.max_duration_s >= 0.0) {
                return Err(ParameterError::from_message(format!(
                    "settle.max_duration_s must be >= 0 (seconds), got {}",
                    st.max_duration_s
                )));
            }
            if !(st.kinetic_energy_per_particle_j.is_finite()
                && st.kinetic_energy_per_particle_j >= 0.0)
            {
                return Err(ParameterError::from_message(format!(
                    "settle.kinetic_energy_per_particle_j must be >= 0 (J), got {}",
                    st.kinetic_energy_per_particle_j
                )));
            }
            if let Some(t) = st.turn_max_duration_s
                && !(t.is_finite() && t >= 0.0)
            {
                return Err(ParameterError::from_message(format!(
                    "settle.turn_max_duration_s must be >= 0 (seconds), got {t}"
                )));
            }
            if let Some(g) = st.gravity_m_s2
                && g.iter().any(|x| !x.is_finite())
            {
                return Err(ParameterError::from_message(format!(
                    "settle.gravity_m_s2 must be finite, got {g:?}"
                )));
            }
        }
        if self.particles.is_empty() && (self.damper.is_some() || self.settle.is_some()) {
            return Err(ParameterError::from_message(
                "particles: no [[particles]] group; a damper or settling needs particles",
            ));
        }
        for (g, grp) in self.particles.iter().enumerate() {
            self.material_index(&grp.material, &format!("particles[{g}].material"))?;
            let n = grp
                .resolved_count()
                .map_err(|e| e.under(&format!("particles[{g}].")))?;
            if n == 0 {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].count: the group has no particles; give count >= 1 or remove it"
                )));
            }
            grp.size
                .validate()
                .map_err(|e| e.under(&format!("particles[{g}].size.")))?;
            self.validate_placement(g, &grp.placement)?;
            if !(grp.placement.gap_m.is_finite() && grp.placement.gap_m >= 0.0) {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].placement.gap_m must be >= 0 (metres), got {}",
                    grp.placement.gap_m
                )));
            }
            if grp.initial_velocity_m_s.iter().any(|v| !v.is_finite()) {
                return Err(ParameterError::from_message(format!(
                    "particles[{g}].initial_velocity_m_s must be finite"
                )));
            }
        }
        Ok(())
    }

    /// Builds the world: bodies, walls (STL paths relative to `base_dir`), particles placed
    /// and checked for overlaps, and the time step checked against the contact time. A
    /// `drop_down` group is dropped here (its falls are simulated: see
    /// [`Scenario::build_world_with`] for progress and a quick check without it).
    pub fn build_world(&self, base_dir: &Path) -> Result<World, InputError> {
        self.build_world_with(base_dir, Preparation::Full, &mut |_, _| {})
    }

    /// [`Scenario::build_world`] with `mode`: [`Preparation::Check`] checks a `drop_down` group
    /// for fit (its particles' volume against the region) without dropping it, so that the
    /// world lacks those particles; `progress(phase, fraction)` follows the drop-down.
    pub fn build_world_with(
        &self,
        base_dir: &Path,
        mode: Preparation,
        progress: &mut dyn FnMut(&str, f64),
    ) -> Result<World, InputError> {
        self.build_world_reporting(base_dir, mode, progress)
            .map(|(w, _)| w)
    }

    /// [`Scenario::build_world_with`], also returning what each drop-down did (one report per
    /// `drop_down` group, in group order).
    pub fn build_world_reporting(
        &self,
        base_dir: &Path,
        mode: Preparation,
        progress: &mut dyn FnMut(&str, f64),
    ) -> Result<(World, Vec<pdamp_dem::drop_down::DropDownReport>), InputError> {
        let mut reports = Vec::new();
        let mut world = self.world_with_bodies(base_dir)?;
        let up = -world.gravity_m_s2;
        let up = if up.norm() > 0.0 {
            up.normalize()
        } else {
            Vec3::z()
        };
        let mut group_of: Vec<usize> = Vec::new();
        let mut settled_bed = false;
        let mut bed_from_file = false;
        let mut bed_state = None;
        let mut placeholders: Vec<(u16, Vec<f64>)> = Vec::new();
        for (g, grp) in self.particles.iter().enumerate() {
            let mat = self.material_index(&grp.material, "particles")?;
            let count = grp
                .resolved_count()
                .map_err(|e| e.under(&format!("particles[{g}].")))?;
            let pl = &grp.placement;
            if pl.method == PlacementMethod::File {
                let path = base_dir.join(pl.path.as_ref().ok_or(ParameterError::invalid(
                    "placement.path",
                    "placement.path missing",
                ))?);
                let (bed, state) = self.read_bed_for_group(g, &path, pl, &grp.material)?;
                self.check_bed_against_group(g, &path, &bed, count, grp)?;
                for i in 0..bed.len() {
                    let m = self.material_index(
                        &bed.materials[bed.material[i] as usize],
                        &format!(
                            "particles[{g}].placement.path: particle {i} of {}",
                            path.display()
                        ),
                    )?;
                    let id = world.add_particle(bed.position_m[i], bed.radius_m[i], m);
                    world.particles.velocity[id] = bed.velocity_m_s[i];
                    world.particles.angular_velocity[id] = bed.angular_velocity_rad_s[i];
                    group_of.push(g);
                }
                settled_bed = true;
                bed_from_file = true;
                bed_state = state;
                continue;
            }
            let radii = grp
                .size
                .sample_n(count, self.simulation.seed.wrapping_add(g as u64));
            let region = pl.region.as_ref().ok_or(ParameterError::invalid(
                "placement.region",
                "placement.region missing",
            ))?;
            let seed = self.simulation.seed.wrapping_add(1000 + g as u64);
            let fix = |e: pdamp_dem::generate::PackingError| {
                InputError::at_with_hint(
                    format!("particles[{g}].placement.region"),
                    e,
                    "; enlarge the region, or lower the particle count, the radius or \
                     placement.gap_m",
                )
            };
            if pl.method == PlacementMethod::DropDown {
                if mode == Preparation::Check {
                    self.check_drop_down_fits(g, region, &radii)?;
                    placeholders.push((mat, radii));
                    continue;
                }
                let dropped =
                    self.drop_down_group(&world, g, mat, region, &radii, seed, progress)?;
                reports.push(dropped.report.clone());
                // Earlier groups settled further under this one.
                for (i, x) in dropped.earlier_position_m.iter().enumerate() {
                    world.particles.position[i] = *x;
                    world.particles.velocity[i] = dropped.earlier_velocity_m_s[i];
                    world.particles.angular_velocity[i] = dropped.earlier_angular_velocity_rad_s[i];
                }
                settled_bed = true;
                let r_max = radii.iter().cloned().fold(0.0, f64::max);
                let order = pdamp_dem::generate::layer_order(&dropped.position_m, 2.0 * r_max);
                for k in order {
                    let id = world.add_particle(dropped.position_m[k], radii[k], mat);
                    world.particles.velocity[id] = dropped.velocity_m_s[k];
                    world.particles.angular_velocity[id] = dropped.angular_velocity_rad_s[k];
                    group_of.push(g);
                }
                continue;
            }
            let pos = packed_positions(&world, pl, region, &radii, seed, &up).map_err(fix)?;
            // Number the group's particles by layers of cells (spatial neighbours close in
            // memory: the DEM's pair loop then finds its partners in cache).
            let r_max = radii.iter().cloned().fold(0.0, f64::max);
            let order = pdamp_dem::generate::layer_order(&pos, 2.0 * r_max);
            for (x, r) in order.iter().map(|&k| (&pos[k], &radii[k])) {
                let id = world.add_particle(*x, *r, mat);
                world.particles.velocity[id] = Vec3::from(grp.initial_velocity_m_s);
                group_of.push(g);
            }
        }
        // A dropped bed or one from a file is at rest with its contacts: it overlaps its
        // neighbours and the walls by its contact deformation (a few 1e-4 of the radius,
        // refused beyond 5 %). A bed dropped here was simulated under the health check: its
        // wall contacts are accepted to the health check's limit of that wall (a soft wall, a
        // coating, may be pressed in deeper: pdamp_dem::health::wall_overlap_limit).
        let tolerance = if settled_bed { 0.05 } else { 1e-9 };
        check_initial_overlaps(&world, &group_of, tolerance)?;
        check_inside_walls(
            &world,
            &group_of,
            self,
            tolerance,
            settled_bed && !bed_from_file,
        )?;
        add_placeholders(&mut world, placeholders);
        if let Some(state) = bed_state {
            // The saved state continues exactly when the bed was made in this container; a bed
            // from another scenario keeps the positions, velocities and spins set above.
            let _ = world.restore_state(state);
        }
        if let Some(skin) = self.simulation.skin_m {
            world.set_skin(skin);
        }
        self.check_time_step(&world)?;
        Ok((world, reports))
    }

    /// The world of the scenario without particles: materials, contact laws, gravity,
    /// integrator, and the bodies with their walls (STL paths relative to `base_dir`).
    fn world_with_bodies(&self, base_dir: &Path) -> Result<World, InputError> {
        let mut model = self.contact.default.clone();
        model.prepare();
        let mut world = World::new(self.materials.clone(), model, self.simulation.time_step_s);
        for p in &self.contact.pairs {
            let a = self.material_index(&p.materials[0], "contact.pairs")?;
            let b = self.material_index(&p.materials[1], "contact.pairs")?;
            world.set_contact_model(a, b, p.model.clone());
        }
        world.gravity_m_s2 = Vec3::from(self.simulation.gravity_m_s2);
        world.integrator = self.simulation.integrator.clone();
        for (bi, b) in self.bodies.iter().enumerate() {
            let motion = match &b.motion {
                MotionSpec::Fixed => Motion::Fixed,
                MotionSpec::Harmonic(h) => Motion::Prescribed(Arc::new(h.clone())),
                MotionSpec::Driven => Motion::Driven,
            };
            let mut body = RigidBody::new(
                &b.name,
                BodyState::at_rest(Vec3::from(b.position_m)),
                motion,
            );
            for (wi, w) in b.walls.iter().enumerate() {
                let mat = self.material_index(&w.material, "walls")?;
                let geometry = match &w.geometry {
                    GeometrySpec::Plane(g) => Geometry::Plane(g.clone()),
                    GeometrySpec::BoxInside(g) => Geometry::BoxInside(g.clone()),
                    GeometrySpec::CylinderInside(g) => Geometry::CylinderInside(g.clone()),
                    GeometrySpec::CylinderOutside(g) => Geometry::CylinderOutside(g.clone()),
                    GeometrySpec::BoxOutside(b) => {
                        if b.half_extents_m
                            .iter()
                            .any(|h| !(*h > 0.0 && h.is_finite()))
                        {
                            return Err(InputError::message(format!(
                                "bodies[{bi}].walls[{wi}].geometry.half_extents_m must be > 0, got {:?}",
                                b.half_extents_m
                            )));
                        }
                        let mut m = pdamp_dem::walls::TriMesh::box_inside(
                            Vec3::from(b.center_m),
                            Vec3::from(b.half_extents_m),
                        );
                        m.flip_normals();
                        Geometry::Mesh(m)
                    }
                    GeometrySpec::Stl(s) => {
                        let path = base_dir.join(&s.path);
                        let mut mesh = crate::stl::read_stl(&path).map_err(|e| {
                            InputError::at(format!("bodies[{bi}].walls[{wi}].geometry.path"), e)
                        })?;
                        mesh = mesh
                            .transformed(s.scale, Vec3::from(s.translation_m))
                            .map_err(|e| {
                                InputError::at(
                                    format!("bodies[{bi}].walls[{wi}].geometry.scale"),
                                    e,
                                )
                            })?;
                        if s.flip_normals {
                            mesh.flip_normals();
                        }
                        Geometry::Mesh(mesh)
                    }
                };
                body.walls.push(pdamp_dem::Wall {
                    geometry,
                    material: mat,
                    name: w.name.clone(),
                });
            }
            world.add_body(body);
        }
        Ok(world)
    }

    /// The time step against the shortest contact time of the built world (velocity Verlet).
    fn check_time_step(&self, world: &World) -> Result<(), InputError> {
        if !world.particles.is_empty() {
            let tc = world.min_contact_time_s(self.simulation.check_impact_velocity_m_s);
            let ratio = self.simulation.time_step_s / tc;
            if matches!(world.integrator, Integrator::VelocityVerlet)
                && ratio > self.simulation.max_time_step_ratio
            {
                return Err(InputError::message(format!(
                    "simulation.time_step_s = {:.3e} s is {:.2} of the shortest contact time {:.3e} s (impact at {} m/s); \
                     use at most {:.3e} s (max_time_step_ratio = {})",
                    self.simulation.time_step_s,
                    ratio,
                    tc,
                    self.simulation.check_impact_velocity_m_s,
                    self.simulation.max_time_step_ratio * tc,
                    self.simulation.max_time_step_ratio
                )));
            }
        }
        Ok(())
    }
}

/// How much of a bed [`Scenario::build_world_with`] prepares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preparation {
    /// Everything, drop-downs included.
    Full,
    /// Checks only: `drop_down` groups are checked for fit but not dropped (not in the world).
    Check,
}

/// Densest random packing a drop-down can reach (random close packing of equal spheres).
const RANDOM_CLOSE_PACKING: f64 = 0.64;

impl Scenario {
    /// Reads the bed file of group `g` in its format; the native format also gives the saved
    /// state.
    fn read_bed_for_group(
        &self,
        g: usize,
        path: &Path,
        pl: &PlacementSpec,
        material: &str,
    ) -> Result<(pdamp_dem::Bed, Option<pdamp_dem::WorldState>), InputError> {
        let key = format!("particles[{g}].placement.path");
        let format = BedFormat::of(path, pl.format).map_err(|e| InputError::at(&key, e))?;
        let read = || std::fs::read_to_string(path).map_err(|e| InputError::read(&key, path, e));
        let (bed, state) = match format {
            BedFormat::Native => {
                let f = crate::bed::load_bed(path).map_err(|e| InputError::at(&key, e))?;
                (f.bed, f.state)
            }
            BedFormat::Lammps => {
                let mut bed = crate::bed_formats::read_lammps_data(&read()?, &pl.type_materials)
                    .map_err(|e| InputError::file(&key, path, e))?;
                if pl.type_materials.is_empty() {
                    bed.materials = vec![material.to_string()];
                    bed.material.iter_mut().for_each(|m| *m = 0);
                }
                (bed, None)
            }
            BedFormat::Csv => (
                crate::bed_formats::read_bed_csv(&read()?, material)
                    .map_err(|e| InputError::file(&key, path, e))?,
                None,
            ),
        };
        bed.validate()
            .map_err(|e| InputError::file(&key, path, e))?;
        Ok((bed, state))
    }

    /// A bed must have the group's count and radii inside its size distribution.
    fn check_bed_against_group(
        &self,
        g: usize,
        path: &Path,
        bed: &pdamp_dem::Bed,
        count: usize,
        grp: &ParticleGroupSpec,
    ) -> Result<(), InputError> {
        if bed.len() != count {
            return Err(InputError::message(format!(
                "particles[{g}].count: the scenario asks for {count} particles, the bed '{}' has {}; set count = {}",
                path.display(),
                bed.len(),
                bed.len()
            )));
        }
        let (lo, hi) = (grp.size.min_radius_m(), grp.size.max_radius_m());
        if let Some(i) = bed
            .radius_m
            .iter()
            .position(|&r| r < lo * (1.0 - 1e-9) || r > hi * (1.0 + 1e-9))
        {
            return Err(InputError::message(format!(
                "particles[{g}].size: particle {i} of the bed '{}' has radius {:.6e} m, outside the group's size range [{lo:.6e}, {hi:.6e}] m; make the size match the bed",
                path.display(),
                bed.radius_m[i]
            )));
        }
        Ok(())
    }

    /// A drop-down cannot pack denser than random close packing: refuse a group whose solid
    /// volume exceeds 0.64 of the region's volume.
    fn check_drop_down_fits(
        &self,
        g: usize,
        region: &Region,
        radii: &[f64],
    ) -> Result<(), ParameterError> {
        let solid: f64 = radii
            .iter()
            .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
            .sum();
        let v = region.volume_m3();
        if solid > RANDOM_CLOSE_PACKING * v {
            return Err(ParameterError::from_message(format!(
                "particles[{g}].placement.region: the particles' volume {solid:.4e} m³ is {:.2} of the region's {v:.4e} m³, more than a random packing holds ({RANDOM_CLOSE_PACKING}); enlarge the region or lower the count",
                solid / v
            )));
        }
        Ok(())
    }

    /// Drops group `g` into `world` under the filling gravity ([`Scenario::fill_gravity`]).
    #[allow(clippy::too_many_arguments)]
    fn drop_down_group(
        &self,
        world: &World,
        g: usize,
        mat: u16,
        region: &Region,
        radii: &[f64],
        seed: u64,
        progress: &mut dyn FnMut(&str, f64),
    ) -> Result<pdamp_dem::drop_down::DroppedParticles, InputError> {
        self.check_drop_down_fits(g, region, radii)?;
        let pl = &self.particles[g].placement;
        let gravity = self.fill_gravity();
        let rho = world.materials[mat as usize].density_kg_m3;
        let r_mean = radii.iter().sum::<f64>() / radii.len().max(1) as f64;
        let m_mean = 4.0 / 3.0 * std::f64::consts::PI * rho * r_mean.powi(3);
        let spec = pdamp_dem::drop_down::DropDownSpec {
            region: region.clone(),
            max_attempts_per_particle: 1000,
            seed,
            kinetic_energy_per_particle_j: pl
                .round_kinetic_energy_per_particle_j
                .unwrap_or(0.01 * m_mean * gravity.norm() * r_mean),
            max_round_duration_s: pl.max_round_duration_s.unwrap_or(0.5),
            max_rounds: pl.max_rounds.unwrap_or(200),
            open_lid: pl.open_lid.as_ref().map(OpenLidSpec::to_open_lid),
            inlet: pl.inlet.as_ref().map(|i| pdamp_dem::drop_down::Inlet {
                region: i.region.clone(),
                rate_per_s: i.rate_per_s,
                velocity_m_s: Vec3::from(i.velocity_m_s),
            }),
        };
        let mut w = world.clone();
        w.gravity_m_s2 = gravity;
        let total = radii.len().max(1) as f64;
        pdamp_dem::drop_down::drop_down(&w, radii, mat, &spec, |_, placed| {
            progress("drop-down", placed as f64 / total);
            if crate::checkpoint::stop_requested() {
                std::ops::ControlFlow::Break(())
            } else {
                std::ops::ControlFlow::Continue(())
            }
        })
        .map_err(|e| InputError::at(format!("particles[{g}].placement"), e))
    }
}

/// Finite and positive.
fn finite_pos(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

/// Fails if two particles overlap by more than 1e-9 of the smaller radius at the start.
fn check_initial_overlaps(
    world: &World,
    group_of: &[usize],
    tolerance: f64,
) -> Result<(), ParameterError> {
    let p = &world.particles;
    let n = p.len();
    if n < 2 {
        return Ok(());
    }
    // Sort by x and sweep (O(n log n) for reasonable packings).
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| p.position[a].x.total_cmp(&p.position[b].x));
    let r_max = p.max_radius();
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if p.position[j].x - p.position[i].x > 2.0 * r_max {
                break;
            }
            let d = (p.position[i] - p.position[j]).norm();
            let ov = p.radius[i] + p.radius[j] - d;
            if ov > tolerance * p.radius[i].min(p.radius[j]) {
                let (i, j) = (i.min(j), i.max(j));
                let (gi, gj) = (group_of[i], group_of[j]);
                let fix = if gi != gj {
                    format!(
                        "the placement regions of particles[{gi}] and particles[{gj}] overlap; \
                         make them disjoint"
                    )
                } else {
                    "increase placement.gap_m or use another placement method".to_string()
                };
                return Err(ParameterError::from_message(format!(
                    "particles[{gj}].placement: initial overlap of {:.3e} m between particle {} at {:?} and particle {} at {:?}; {fix}",
                    ov,
                    i,
                    p.position[i].as_slice(),
                    j,
                    p.position[j].as_slice()
                )));
            }
        }
    }
    Ok(())
}

/// Fails if a particle starts overlapping a wall or outside a closed container (boxes and
/// cylinders report a particle outside as a deep overlap; open meshes cannot tell).
/// Particles overlapping a wall by more than `tolerance` of their radius are refused; with
/// `health_limits` (a bed dropped under the health check) each wall's health-check limit
/// applies instead.
fn check_inside_walls(
    world: &World,
    group_of: &[usize],
    sc: &Scenario,
    tolerance: f64,
    health_limits: bool,
) -> Result<(), InputError> {
    let p = &world.particles;
    let mut contacts = Vec::new();
    for (bi, b) in world.bodies.iter().enumerate() {
        let pose = pdamp_dem::BodyState::at_rest(Vec3::from(sc.bodies[bi].position_m));
        for (wi, w) in b.walls.iter().enumerate() {
            for (i, &g) in group_of.iter().enumerate() {
                contacts.clear();
                let x = pose.to_body(&p.position[i]);
                w.geometry
                    .sphere_contacts(&x, p.radius[i], 0.0, &mut contacts);
                let limit = if health_limits {
                    pdamp_dem::health::wall_overlap_limit(
                        &world.materials[p.material[i] as usize],
                        &world.materials[w.material as usize],
                    )
                } else {
                    tolerance
                };
                if let Some(c) = contacts.iter().find(|c| c.overlap_m > limit * p.radius[i]) {
                    let outside = c.overlap_m > p.radius[i];
                    return Err(InputError::message(format!(
                        "particles[{g}].placement.region: particle {i} at {:?} m {} wall '{}' of body '{}' (bodies[{bi}].walls[{wi}]) by {:.3e} m; \
                         keep the region inside the container, at least one radius ({:.3e} m) away from its walls",
                        p.position[i].as_slice(),
                        if outside { "lies outside" } else { "overlaps" },
                        w.name,
                        b.name,
                        c.overlap_m,
                        p.radius[i]
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Lattice or random positions of a group's particles in `region` (random ones clear of the
/// walls of `world`).
fn packed_positions(
    world: &World,
    pl: &PlacementSpec,
    region: &Region,
    radii: &[f64],
    seed: u64,
    up: &Vec3,
) -> Result<Vec<Vec3>, pdamp_dem::generate::PackingError> {
    let up = *up;
    match pl.method {
        PlacementMethod::Grid => grid_packing(region, radii, pl.gap_m, &up),
        PlacementMethod::Tight => tight_packing(region, radii, pl.gap_m, &up),
        _ => {
            let layering = pl.layer_height_m.map(|h| Layering {
                up,
                layer_height_m: h,
            });
            let scratch = std::cell::RefCell::new(Vec::new());
            let blocked = |x: &Vec3, r: f64| {
                world
                    .wall_overlap(x, r, &mut scratch.borrow_mut())
                    .is_some()
            };
            random_insertion_clear_of(region, radii, seed, 1000, layering.as_ref(), &blocked)
        }
    }
}

/// Check mode: the drop-down groups' particles far away in a row (for counts, masses and the
/// time-step check), not dropped.
fn add_placeholders(world: &mut World, placeholders: Vec<(u16, Vec<f64>)>) {
    let far = world
        .bodies
        .iter()
        .flat_map(|b| b.walls.iter().filter_map(|w| w.geometry.bounding_box()))
        .fold(1.0f64, |a, (lo, hi)| a.max(lo.amax()).max(hi.amax()));
    let pitch = 4.0
        * placeholders
            .iter()
            .flat_map(|(_, r)| r.iter())
            .fold(0.0f64, |a, &b| a.max(b));
    let mut x = 1e3 * far;
    for (mat, radii) in placeholders {
        for r in radii {
            world.add_particle(Vec3::new(x, 0.0, 0.0), r, mat);
            x += pitch;
        }
    }
}
