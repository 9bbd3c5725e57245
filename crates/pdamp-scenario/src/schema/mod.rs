//! Scenario files: a TOML description of a DEM run (materials, contact laws, walls on rigid
//! bodies, particle groups, time stepping, output). See `docs/scenario.md` for the schema.
//!
//! Loading validates everything up front; every error names the key that is wrong.

use crate::InputError;
use pdamp_dem::ParameterError;
use pdamp_dem::contact::ContactModel;
use pdamp_dem::walls::{BoxInside, CylinderInside, CylinderOutside, Plane};
use pdamp_dem::{HarmonicTranslation, Integrator, Material, Vec3, World};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

mod build;
pub mod estimate;
mod particles;
mod validate;
pub use build::Preparation;
pub use particles::{
    BedFormat, FillingSpec, InletSpec, OpenLidSpec, ParticleGroupSpec, PlacementMethod,
    PlacementSpec,
};
use validate::check_array_lengths;

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

/// Gravity of the excitation intensity Γ = A/g [D Eq. 3.11], m/s² (a physical constant: it lives
/// in `pdamp_dem::math`).
pub use pdamp_dem::math::STANDARD_GRAVITY_M_S2;

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

impl From<VtkFormat> for pdamp_io::vtk::VtkEncoding {
    fn from(f: VtkFormat) -> Self {
        match f {
            VtkFormat::Binary => pdamp_io::vtk::VtkEncoding::Binary,
            VtkFormat::Ascii => pdamp_io::vtk::VtkEncoding::Ascii,
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
        estimate::Estimate::of(&s, 1, rayon::current_num_threads())
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
        if !text.contains(pdamp_io::restitution::TABLE_KEY) {
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
}

/// The excitation direction of a damper scenario (for the clearance), if it has one.
pub fn excitation_direction(scenario: &Scenario) -> Option<Vec3> {
    scenario.damper.as_ref().map(|d| Vec3::from(d.direction))
}
