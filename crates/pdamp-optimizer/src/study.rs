//! The design-study file of `pdamp design STUDY.toml --out DIR`: the structure (through a
//! coupling scenario), the objective, the design space of the damper, the materials, the
//! constraints and the search settings. Every key carries its unit; [`DesignStudy::load`]
//! checks them all and names the key of the first problem.
//!
//! ```toml
//! scenario = "couple_ch5_free_formulas.toml"  # structure + [analysis] kind = "free"
//!                                              # (its dampers are ignored)
//! [objective]
//! kind = "min_stroke"          # or "max_damping" (modes, amplitude range)
//! evaluate_at_s = 4.0
//!
//! [damper]
//! direction = "horizontal"     # rolling/bouncing layers (D Eq. 5.1–5.14, 6.12) | "vertical" (D Eq. 7.1–7.19)
//! points = ["damper"]          # candidate structure points
//! container_lengths_m = [0.12] # inner length along the excitation
//! container_width_m = 0.04     # inner width across it
//! layers = 3                   # separate layers (horizontal)
//! particle_radii_m = [0.005]
//!
//! [[materials]]
//! name = "steel"
//! density_kg_m3 = 7900.0
//!
//! [constraints]
//! max_bed_mass_kg = 0.6
//! ```

use crate::DesignError;
use pdamp_structure::free::FreeVibrationSpec;
use pdamp_structure::modal::ModalStructure;
use pdamp_structure::scenario::{CoupleScenario, PointSpec, StructureSpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What the optimiser minimises or maximises.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObjectiveSpec {
    /// Minimise the amplitude after time T: the largest |x| at the scenario's output point over
    /// the last period before `evaluate_at_s` of the scenario's free decay (the criterion of
    /// D Sect. 5.2.1 and 7.2.3).
    MinStroke {
        /// Evaluation time T, s (≤ the scenario's `analysis.duration_s`).
        evaluate_at_s: f64,
    },
    /// Maximise the damping ratio of the chosen modes, averaged over the amplitude range of
    /// the scenario's output point (log-spaced amplitudes, equal weights for every mode).
    MaxDamping {
        /// Modes (1-based).
        modes: Vec<usize>,
        /// Smallest amplitude of the range at the output point, m.
        amplitude_min_m: f64,
        /// Largest amplitude of the range at the output point, m.
        amplitude_max_m: f64,
        /// Amplitudes of the range (log-spaced, ≥ 2).
        #[serde(default = "default_amplitudes")]
        amplitudes: usize,
    },
    /// Minimise the resonance peaks of the chosen modes at the scenario's output point under
    /// its harmonic force (`[analysis] kind = "steady_state"`: force, excitation and output
    /// points), each relative to the bare structure's peak, averaged over the modes.
    MinFrfPeak {
        /// Modes (1-based).
        modes: Vec<usize>,
        /// Frequencies of the steady-state FRF around each resonance (level 1).
        #[serde(default = "default_frf_points")]
        frequencies: usize,
        /// Half-width of that band relative to the damped resonance frequency.
        #[serde(default = "default_frf_band")]
        band: f64,
    },
    /// Maximise the damping ratio at resonance of the chosen modes under the scenario's
    /// harmonic force (`steady_state` scenario), averaged over the modes: level 0 the
    /// equilibrium ζ of D Fig. 3.7 / Eq. 3.49 (the measure of `pdamp structure
    /// damper-positions`), level 1 ζ from the steady-state FRF's peak by D Eq. 3.47.
    MaxResonanceDamping {
        /// Modes (1-based).
        modes: Vec<usize>,
        /// Frequencies of the steady-state FRF around each resonance (level 1).
        #[serde(default = "default_frf_points")]
        frequencies: usize,
        /// Half-width of that band relative to the damped resonance frequency.
        #[serde(default = "default_frf_band")]
        band: f64,
    },
}

impl ObjectiveSpec {
    /// Whether the objective needs a `steady_state` scenario (a harmonic force).
    pub fn is_forced(&self) -> bool {
        matches!(
            self,
            ObjectiveSpec::MinFrfPeak { .. } | ObjectiveSpec::MaxResonanceDamping { .. }
        )
    }
}

fn default_frf_points() -> usize {
    121
}
fn default_frf_band() -> f64 {
    0.15
}

/// The harmonic load of a `steady_state` scenario (min_frf_peak).
#[derive(Debug, Clone, PartialEq)]
pub struct HarmonicLoad {
    /// Force amplitude F, N.
    pub force_n: f64,
    /// Excitation point.
    pub excitation_point: String,
}

fn default_amplitudes() -> usize {
    12
}

/// Excitation direction of the damper, i.e. which formula family models it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Horizontal: separate layers that roll (A < g, D Eq. 5.1–5.14) or bounce (A ≥ g,
    /// D Eq. 6.12), one layer per shelf of the container.
    Horizontal,
    /// Vertical: the bed as one block, single/double collect-and-collide (D Eq. 7.1–7.19).
    Vertical,
}

/// The design space of one container.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DamperSpace {
    /// Excitation direction.
    pub direction: Direction,
    /// Candidate structure points (names of `[[structure.points]]` or the single-mode point).
    #[serde(default)]
    pub points: Vec<String>,
    /// Candidate positions along a `[structure.beam]`, m: a damper point placed there (the FE
    /// snaps it to the nearest node), in the dof of `position_dof`.
    #[serde(default)]
    pub positions_m: Vec<f64>,
    /// Dof of the damper point at `positions_m` (default: the dof of the scenario's output
    /// point).
    #[serde(default)]
    pub position_dof: Option<String>,
    /// Position of a `[structure.beam]` point mass (the container) that moves with the damper
    /// to each of `positions_m`, m.
    #[serde(default)]
    pub move_mass_at_m: Option<f64>,
    /// Candidate inner container lengths along the excitation L, m (D Eq. 5.1/7.4).
    pub container_lengths_m: Vec<f64>,
    /// Inner width across the excitation, m (particles across: ⌊W/2r⌋).
    pub container_width_m: f64,
    /// Vertical containers: the second horizontal dimension, m (default: the width).
    #[serde(default)]
    pub container_depth_m: Option<f64>,
    /// Horizontal containers: number of separate layers (shelves), each filled independently.
    #[serde(default = "one")]
    pub layers: usize,
    /// Candidate particle radii r, m.
    pub particle_radii_m: Vec<f64>,
    /// Increment of the particle number of a layer (default: one row across the width for
    /// horizontal layers, one level of the cross-section for vertical beds).
    #[serde(default)]
    pub particle_count_step: Option<usize>,
}

fn one() -> usize {
    1
}

/// A particle material of the table. The formulas see only the density; the coupled-DEM
/// verification uses the rest (defaults: steel S235 of D Tab. 5.1, constant restitution as in
/// examples/damper_ch5_small.toml).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Name (in designs.csv and the scenario files).
    pub name: String,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
    /// Young's modulus, Pa (DEM).
    #[serde(default = "default_youngs")]
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (DEM).
    #[serde(default = "default_poisson")]
    pub poisson_ratio: f64,
    /// Coefficient of restitution particle–particle (DEM, Gonthier law).
    #[serde(default = "default_restitution")]
    pub restitution: f64,
    /// Coefficient of restitution particle–container wall (DEM).
    #[serde(default = "default_wall_restitution")]
    pub wall_restitution: f64,
    /// Coefficient of friction, particle–particle and particle–wall (DEM).
    #[serde(default = "default_friction")]
    pub friction: f64,
}

fn default_youngs() -> f64 {
    208e9
}
fn default_poisson() -> f64 {
    0.3
}
fn default_restitution() -> f64 {
    0.6
}
fn default_wall_restitution() -> f64 {
    0.9
}
fn default_friction() -> f64 {
    0.1
}

/// The container wall material of the coupled-DEM verification (default: PVC of D Tab. 5.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallMaterialSpec {
    /// Name.
    #[serde(default = "default_wall_name")]
    pub name: String,
    /// Density, kg/m³.
    #[serde(default = "default_wall_density")]
    pub density_kg_m3: f64,
    /// Young's modulus, Pa.
    #[serde(default = "default_wall_youngs")]
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio.
    #[serde(default = "default_wall_poisson")]
    pub poisson_ratio: f64,
}

fn default_wall_name() -> String {
    "PVC".into()
}
fn default_wall_density() -> f64 {
    1400.0
}
fn default_wall_youngs() -> f64 {
    3e9
}
fn default_wall_poisson() -> f64 {
    0.38
}

impl Default for WallMaterialSpec {
    fn default() -> Self {
        WallMaterialSpec {
            name: default_wall_name(),
            density_kg_m3: default_wall_density(),
            youngs_modulus_pa: default_wall_youngs(),
            poisson_ratio: default_wall_poisson(),
        }
    }
}

/// `[verification]`: the coupled-DEM level (approach 1) on the best designs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VerificationSpec {
    /// Best designs (by the time simulation) verified with coupled DEM; 0: none.
    #[serde(default)]
    pub dem_designs: usize,
    /// Independently dropped beds per design (≥ 2 for a 95 % confidence interval; D uses
    /// drop-down beds throughout).
    #[serde(default = "default_packings")]
    pub packings: usize,
    /// Factor on the particles' Young's modulus (< 1 softens: a longer time step, shorter runs;
    /// reported beside every DEM value).
    #[serde(default = "one_f64")]
    pub youngs_modulus_scale: f64,
    /// Height of one layer (shelf) of a horizontal container, m (default 2.2 r).
    #[serde(default)]
    pub layer_height_m: Option<f64>,
    /// DEM time step, s (default: 0.08 of the Hertz contact time of two particles at the
    /// largest relative velocity, D Eq. 4.8).
    #[serde(default)]
    pub time_step_s: Option<f64>,
    /// Container wall material.
    #[serde(default)]
    pub container: WallMaterialSpec,
}

fn default_packings() -> usize {
    3
}
fn one_f64() -> f64 {
    1.0
}

impl Default for VerificationSpec {
    fn default() -> Self {
        VerificationSpec {
            dem_designs: 0,
            packings: default_packings(),
            youngs_modulus_scale: 1.0,
            layer_height_m: None,
            time_step_s: None,
            container: WallMaterialSpec::default(),
        }
    }
}

/// Constraints on a design.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Constraints {
    /// Largest particle bed mass, kg (the mass the structure can spare; the container's own
    /// mass belongs to the structure model).
    #[serde(default)]
    pub max_bed_mass_kg: Option<f64>,
    /// Smallest clearance h of a filled layer/bed, m (manufacturing, noise).
    #[serde(default)]
    pub min_clearance_m: Option<f64>,
}

/// How the design space is searched.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Screening {
    /// Enumerate when the space has at most `max_enumerated` designs, swarm otherwise.
    #[default]
    Auto,
    /// Screen every design of the space with the envelope model.
    Enumerate,
    /// Particle-swarm search (argmin) over the fill fractions of every categorical choice.
    Swarm,
}

/// `[search]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchSpec {
    /// Screening strategy of the envelope fidelity.
    #[serde(default)]
    pub screening: Screening,
    /// Largest space that `auto` enumerates.
    #[serde(default = "default_max_enumerated")]
    pub max_enumerated: usize,
    /// Time simulations (fidelity 1) spent on the screened designs; default: 10 % of the
    /// screened designs, at least 2 and at most 60.
    #[serde(default)]
    pub verifications: Option<usize>,
    /// Designs listed in report.md and written as scenario files.
    #[serde(default = "default_top")]
    pub top: usize,
    /// Detuning of the robustness check (structure frequencies × (1 ± d)).
    #[serde(default = "default_detuning")]
    pub detuning: f64,
    /// Seed of the swarm.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Swarm particles per categorical choice.
    #[serde(default = "default_swarm_particles")]
    pub swarm_particles: usize,
    /// Swarm iterations per categorical choice.
    #[serde(default = "default_swarm_iterations")]
    pub swarm_iterations: u64,
}

fn default_max_enumerated() -> usize {
    200_000
}
fn default_top() -> usize {
    5
}
fn default_detuning() -> f64 {
    0.1
}
fn default_seed() -> u64 {
    1
}
fn default_swarm_particles() -> usize {
    24
}
fn default_swarm_iterations() -> u64 {
    40
}

impl Default for SearchSpec {
    fn default() -> Self {
        SearchSpec {
            screening: Screening::Auto,
            max_enumerated: default_max_enumerated(),
            verifications: None,
            top: default_top(),
            detuning: default_detuning(),
            seed: default_seed(),
            swarm_particles: default_swarm_particles(),
            swarm_iterations: default_swarm_iterations(),
        }
    }
}

/// A design-study file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignStudyFile {
    /// Coupling scenario (relative to the study file): the structure and a free analysis
    /// (initial condition, time step, output point); its dampers are ignored.
    pub scenario: PathBuf,
    /// The objective.
    pub objective: ObjectiveSpec,
    /// The damper's design space.
    pub damper: DamperSpace,
    /// Particle materials (default: steel, 7900 kg/m³).
    #[serde(default = "default_materials")]
    pub materials: Vec<MaterialSpec>,
    /// Constraints.
    #[serde(default)]
    pub constraints: Constraints,
    /// Search settings.
    #[serde(default)]
    pub search: SearchSpec,
    /// Coupled-DEM verification of the best designs.
    #[serde(default)]
    pub verification: VerificationSpec,
}

fn default_materials() -> Vec<MaterialSpec> {
    vec![MaterialSpec {
        name: "steel".into(),
        density_kg_m3: 7900.0,
        youngs_modulus_pa: default_youngs(),
        poisson_ratio: default_poisson(),
        restitution: default_restitution(),
        wall_restitution: default_wall_restitution(),
        friction: default_friction(),
    }]
}

/// A candidate damper location: a named point of the structure, or a position along a beam
/// (with its own structure: the point added, the container mass moved).
#[derive(Debug, Clone)]
pub struct Location {
    /// How reports name it (`'damper'`, `x = 1.760 m`).
    pub label: String,
    /// The structure point the damper sits at.
    pub point: String,
    /// The reduced structure with the damper there.
    pub structure: ModalStructure,
    /// The structure spec when it differs from the scenario's (positions along a beam): the
    /// scenario files of a design carry it inline.
    pub spec: Option<StructureSpec>,
}

/// Name of the damper point placed at `damper.positions_m`.
pub const POSITION_POINT: &str = "design_damper";

/// A loaded and checked study: the file, the reduced structure and the free-vibration settings.
#[derive(Debug, Clone)]
pub struct DesignStudy {
    /// The study file as read.
    pub file: DesignStudyFile,
    /// Where it was read from.
    pub path: PathBuf,
    /// The scenario's path (resolved).
    pub scenario_path: PathBuf,
    /// The structure, modally reduced.
    pub structure: ModalStructure,
    /// The scenario's free analysis (for a `steady_state` scenario: its output point, a
    /// placeholder for the rest).
    pub free: FreeVibrationSpec,
    /// The harmonic load of a `steady_state` scenario.
    pub load: Option<HarmonicLoad>,
    /// The scenario's structure source for the scenario files written for verified designs:
    /// the structure file (absolute) or `None` when the structure is inline in the scenario.
    pub structure_file: Option<PathBuf>,
    /// The candidate locations: `damper.points`, then `damper.positions_m`.
    pub locations: Vec<Location>,
}

/// Largest particle count of one layer or bed (guards the enumeration against absurd inputs).
pub const MAX_PARTICLES: usize = 10_000_000;

impl DesignStudy {
    /// Reads the study file, its scenario and its structure, and checks every key.
    ///
    /// # Errors
    /// [`DesignError::Load`] for unreadable or malformed files, [`DesignError::Input`] naming the
    /// key for out-of-range values.
    pub fn load(path: &Path) -> Result<Self, DesignError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| DesignError::Load(format!("{}: {e}", path.display())))?;
        let file: DesignStudyFile = toml::from_str(&text)
            .map_err(|e| DesignError::Load(format!("{}: {e}", path.display())))?;
        let base = path.parent().unwrap_or(Path::new("."));
        let scenario_path = if file.scenario.is_absolute() {
            file.scenario.clone()
        } else {
            base.join(&file.scenario)
        };
        let (scn, spec) = CoupleScenario::load(&scenario_path).map_err(DesignError::Load)?;
        let structure = spec
            .build(scenario_path.parent().unwrap_or(Path::new(".")))
            .map_err(|m| {
                DesignError::Load(pdamp_structure::scenario::locate(
                    &scn.structure_source(&scenario_path),
                    m,
                ))
            })?
            .modal;
        let load = match &scn.analysis {
            pdamp_structure::scenario::AnalysisSpec::SteadyState {
                force_amplitude_n,
                base_amplitude_m,
                excitation_point,
                ..
            } => Some(HarmonicLoad {
                force_n: pdamp_structure::scenario::ForceSpec {
                    force_amplitude_n: *force_amplitude_n,
                    base_amplitude_m: *base_amplitude_m,
                }
                .force_n(&spec)
                .map_err(|m| DesignError::Load(format!("{}: {m}", scenario_path.display())))?,
                excitation_point: excitation_point.clone(),
            }),
            _ => None,
        };
        let free = match (&scn.analysis, scn.analysis.free_vibration_spec()) {
            (_, Some(f)) => f,
            (pdamp_structure::scenario::AnalysisSpec::SteadyState { output_point, .. }, None) => {
                FreeVibrationSpec {
                    duration_s: 1.0,
                    time_step_s: 1e-3,
                    mode: 0,
                    initial_point: output_point.clone(),
                    initial_displacement_m: 0.0,
                    initial_velocity_m_s: 0.0,
                    scale_initial_by_bed_mass: false,
                    output_point: output_point.clone(),
                    update: pdamp_structure::free::UpdateRule::ZeroCrossing,
                    sample_every: 1,
                }
            }
            _ => {
                return Err(DesignError::Load(format!(
                    "{}: the design study's scenario needs [analysis] kind = \"free\" (initial \
                     condition, time step and output point of a decay) or kind = \
                     \"steady_state\" (force, excitation and output point; objective \
                     min_frf_peak)",
                    scenario_path.display()
                )));
            }
        };
        let structure_file = scn
            .structure_file
            .as_ref()
            .map(|_| scn.structure_source(&scenario_path))
            .map(|p| std::fs::canonicalize(&p).unwrap_or(p));
        let mut study = DesignStudy {
            file,
            path: path.to_path_buf(),
            scenario_path,
            structure,
            free,
            load,
            structure_file,
            locations: Vec::new(),
        };
        study.validate()?;
        study.locations = study.locations(&spec)?;
        Ok(study)
    }

    /// The candidate locations: the named points on the scenario's structure, and for every
    /// position along the beam the structure rebuilt with the damper point there (and the
    /// container mass moved, `damper.move_mass_at_m`).
    fn locations(&self, spec: &StructureSpec) -> Result<Vec<Location>, DesignError> {
        let d = &self.file.damper;
        let mut out: Vec<Location> = d
            .points
            .iter()
            .map(|p| Location {
                label: format!("'{p}'"),
                point: p.clone(),
                structure: self.structure.clone(),
                spec: None,
            })
            .collect();
        if d.positions_m.is_empty() {
            return Ok(out);
        }
        let Some(beam) = &spec.beam else {
            return Err(self.input(
                "damper.positions_m",
                "positions along a beam need a [structure.beam] structure; name points instead",
            ));
        };
        let dof = match &d.position_dof {
            Some(dof) => dof.clone(),
            None => spec
                .points
                .iter()
                .find(|p| p.name == self.free.output_point)
                .map_or_else(|| "uy".to_string(), |p| p.dof.clone()),
        };
        let moved = match d.move_mass_at_m {
            Some(x) => Some(
                beam.masses
                    .iter()
                    .position(|m| (m.position_m - x).abs() < 1e-9)
                    .ok_or_else(|| {
                        self.input(
                            "damper.move_mass_at_m",
                            format!("no [structure.beam] mass at {x} m"),
                        )
                    })?,
            ),
            None => None,
        };
        let base = self.scenario_path.parent().unwrap_or(Path::new("."));
        for (i, &x) in d.positions_m.iter().enumerate() {
            let key = format!("damper.positions_m[{i}]");
            pdamp_structure::scenario::on_beam(&key, x, beam.length_m)
                .map_err(|m| self.input(&key, m))?;
            let mut st = spec.clone();
            st.points.retain(|p| p.name != POSITION_POINT);
            st.points.push(PointSpec {
                name: POSITION_POINT.into(),
                position_m: Some(x),
                node: None,
                dof: dof.clone(),
            });
            if let (Some(m), Some(b)) = (moved, st.beam.as_mut()) {
                b.masses[m].position_m = x;
            }
            let structure = st
                .build(base)
                .map_err(|m| {
                    self.input(
                        &key,
                        format!("building the beam with the damper at {x} m: {m}"),
                    )
                })?
                .modal;
            out.push(Location {
                label: format!("x = {x:.3} m"),
                point: POSITION_POINT.into(),
                structure,
                spec: Some(st),
            });
        }
        Ok(out)
    }

    fn input(&self, key: impl Into<String>, message: impl Into<String>) -> DesignError {
        DesignError::Input {
            path: self.path.clone(),
            key: key.into(),
            message: message.into(),
        }
    }

    fn positive(&self, key: &str, v: f64, hi: f64) -> Result<(), DesignError> {
        if v.is_finite() && v > 0.0 && v <= hi {
            Ok(())
        } else {
            Err(self.input(
                key,
                format!("must be a finite number in (0, {hi:e}], got {v}"),
            ))
        }
    }

    fn check_modes(&self, modes: &[usize]) -> Result<(), DesignError> {
        if modes.is_empty() {
            return Err(self.input("objective.modes", "give at least one mode (1-based)"));
        }
        for (i, &m) in modes.iter().enumerate() {
            if m == 0 || m > self.structure.modes.len() {
                return Err(self.input(
                    format!("objective.modes[{i}]"),
                    format!(
                        "mode {m} does not exist: the structure has modes 1 … {}",
                        self.structure.modes.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Checks every key against the structure and the scenario.
    ///
    /// # Errors
    /// [`DesignError::Input`] naming the first bad key.
    pub fn validate(&self) -> Result<(), DesignError> {
        let f = &self.file;
        let d = &f.damper;
        let forced = f.objective.is_forced();
        if forced != self.load.is_some() {
            return Err(self.input(
                "objective.kind",
                if forced {
                    "min_frf_peak and max_resonance_damping need a scenario with [analysis] kind = \
                     \"steady_state\" (the force)"
                } else {
                    "min_stroke and max_damping need a scenario with [analysis] kind = \"free\"; \
                     a steady_state scenario goes with kind = \"min_frf_peak\" or \
                     \"max_resonance_damping\""
                },
            ));
        }
        match &f.objective {
            ObjectiveSpec::MinFrfPeak {
                modes,
                frequencies,
                band,
            }
            | ObjectiveSpec::MaxResonanceDamping {
                modes,
                frequencies,
                band,
            } => {
                self.check_modes(modes)?;
                if !(11..=100_000).contains(frequencies) {
                    return Err(self.input(
                        "objective.frequencies",
                        format!("must be in [11, 100000], got {frequencies}"),
                    ));
                }
                if !(band.is_finite() && *band > 0.0 && *band < 0.9) {
                    return Err(self.input(
                        "objective.band",
                        format!("must lie in (0, 0.9), got {band}"),
                    ));
                }
                if let Some(l) = &self.load {
                    if let Err(m) = self.structure.point(&l.excitation_point) {
                        return Err(self.input("scenario analysis.excitation_point", m));
                    }
                    self.positive("scenario analysis force", l.force_n.abs(), 1e12)?;
                }
            }
            ObjectiveSpec::MinStroke { evaluate_at_s } => {
                self.positive("objective.evaluate_at_s", *evaluate_at_s, 1e6)?;
                if *evaluate_at_s > self.free.duration_s {
                    return Err(self.input(
                        "objective.evaluate_at_s",
                        format!(
                            "{evaluate_at_s} s lies beyond the scenario's analysis.duration_s = {} s",
                            self.free.duration_s
                        ),
                    ));
                }
            }
            ObjectiveSpec::MaxDamping {
                modes,
                amplitude_min_m,
                amplitude_max_m,
                amplitudes,
            } => {
                self.check_modes(modes)?;
                self.positive("objective.amplitude_min_m", *amplitude_min_m, 10.0)?;
                self.positive("objective.amplitude_max_m", *amplitude_max_m, 10.0)?;
                if amplitude_min_m >= amplitude_max_m {
                    return Err(self.input(
                        "objective.amplitude_max_m",
                        format!("must exceed amplitude_min_m = {amplitude_min_m} m"),
                    ));
                }
                if !(2..=1000).contains(amplitudes) {
                    return Err(self.input(
                        "objective.amplitudes",
                        format!("must be in [2, 1000], got {amplitudes}"),
                    ));
                }
            }
        }
        if d.points.is_empty() && d.positions_m.is_empty() {
            return Err(self.input(
                "damper.points",
                "give at least one structure point (or positions_m along a beam)",
            ));
        }
        if d.points.len() + d.positions_m.len() > 10_000 {
            return Err(self.input("damper.positions_m", "at most 10 000 candidate locations"));
        }
        for (i, p) in d.points.iter().enumerate() {
            if let Err(m) = self.structure.point(p) {
                return Err(self.input(format!("damper.points[{i}]"), m));
            }
        }
        let output = self.structure.point(&self.free.output_point);
        if let Err(m) = output {
            return Err(self.input("scenario analysis.output_point", m));
        }
        if d.container_lengths_m.is_empty() {
            return Err(self.input("damper.container_lengths_m", "give at least one length"));
        }
        for (i, &l) in d.container_lengths_m.iter().enumerate() {
            self.positive(&format!("damper.container_lengths_m[{i}]"), l, 100.0)?;
        }
        self.positive("damper.container_width_m", d.container_width_m, 100.0)?;
        if let Some(w) = d.container_depth_m {
            self.positive("damper.container_depth_m", w, 100.0)?;
        }
        if d.layers == 0 || d.layers > 12 {
            return Err(self.input(
                "damper.layers",
                format!("must be in [1, 12], got {}", d.layers),
            ));
        }
        if d.direction == crate::study::Direction::Vertical && d.layers != 1 {
            return Err(self.input(
                "damper.layers",
                "a vertical bed is one block (D Sect. 7.1.1): use layers = 1",
            ));
        }
        if d.particle_radii_m.is_empty() {
            return Err(self.input("damper.particle_radii_m", "give at least one radius"));
        }
        let min_len = d
            .container_lengths_m
            .iter()
            .cloned()
            .fold(f64::MAX, f64::min);
        for (i, &r) in d.particle_radii_m.iter().enumerate() {
            self.positive(&format!("damper.particle_radii_m[{i}]"), r, 1.0)?;
            if 2.0 * r > d.container_width_m.min(min_len) {
                return Err(self.input(
                    format!("damper.particle_radii_m[{i}]"),
                    format!(
                        "a sphere of {r} m radius does not fit the container (width {} m, \
                         shortest length {min_len} m)",
                        d.container_width_m
                    ),
                ));
            }
        }
        if d.particle_count_step == Some(0) {
            return Err(self.input("damper.particle_count_step", "must be ≥ 1"));
        }
        if f.materials.is_empty() {
            return Err(self.input("materials", "give at least one [[materials]] entry"));
        }
        for (i, m) in f.materials.iter().enumerate() {
            self.positive(
                &format!("materials[{i}].density_kg_m3"),
                m.density_kg_m3,
                1e5,
            )?;
            if m.name.trim().is_empty() {
                return Err(self.input(format!("materials[{i}].name"), "must not be empty"));
            }
        }
        if let Some(m) = f.constraints.max_bed_mass_kg {
            self.positive("constraints.max_bed_mass_kg", m, 1e6)?;
        }
        if let Some(h) = f.constraints.min_clearance_m
            && !(h.is_finite() && h >= 0.0)
        {
            return Err(self.input(
                "constraints.min_clearance_m",
                format!("must be a finite number ≥ 0, got {h}"),
            ));
        }
        let v = &f.verification;
        if v.dem_designs > 20 {
            return Err(self.input(
                "verification.dem_designs",
                format!("must be in [0, 20], got {}", v.dem_designs),
            ));
        }
        if v.dem_designs > 0 && !matches!(f.objective, ObjectiveSpec::MinStroke { .. }) {
            return Err(self.input(
                "verification.dem_designs",
                "the coupled-DEM verification is built for kind = \"min_stroke\" only (a DEM \
                 decay per mode and amplitude range is not built yet): set 0",
            ));
        }
        if v.dem_designs > f.search.top {
            return Err(self.input(
                "verification.dem_designs",
                format!("must not exceed search.top = {}", f.search.top),
            ));
        }
        if !(1..=100).contains(&v.packings) {
            return Err(self.input(
                "verification.packings",
                format!("must be in [1, 100], got {}", v.packings),
            ));
        }
        self.positive(
            "verification.youngs_modulus_scale",
            v.youngs_modulus_scale,
            1.0,
        )?;
        if let Some(h) = v.layer_height_m {
            self.positive("verification.layer_height_m", h, 10.0)?;
            let rmax = d.particle_radii_m.iter().cloned().fold(0.0, f64::max);
            if h < 2.0 * rmax {
                return Err(self.input(
                    "verification.layer_height_m",
                    format!(
                        "{h} m is below the largest particle diameter {} m",
                        2.0 * rmax
                    ),
                ));
            }
        }
        if let Some(dt) = v.time_step_s {
            self.positive("verification.time_step_s", dt, 1e-2)?;
        }
        self.positive(
            "verification.container.density_kg_m3",
            v.container.density_kg_m3,
            1e5,
        )?;
        self.positive(
            "verification.container.youngs_modulus_pa",
            v.container.youngs_modulus_pa,
            1e13,
        )?;
        if !(v.container.poisson_ratio > 0.0 && v.container.poisson_ratio <= 0.5) {
            return Err(self.input(
                "verification.container.poisson_ratio",
                format!("must lie in (0, 0.5], got {}", v.container.poisson_ratio),
            ));
        }
        let s = &f.search;
        if s.verifications == Some(0) {
            return Err(self.input("search.verifications", "must be ≥ 1"));
        }
        if s.top == 0 || s.top > 100 {
            return Err(self.input("search.top", format!("must be in [1, 100], got {}", s.top)));
        }
        if !(s.detuning.is_finite() && (0.0..0.5).contains(&s.detuning)) {
            return Err(self.input(
                "search.detuning",
                format!("must be in [0, 0.5), got {}", s.detuning),
            ));
        }
        if s.swarm_particles < 2 || s.swarm_particles > 10_000 {
            return Err(self.input(
                "search.swarm_particles",
                format!("must be in [2, 10000], got {}", s.swarm_particles),
            ));
        }
        if s.swarm_iterations == 0 || s.swarm_iterations > 100_000 {
            return Err(self.input(
                "search.swarm_iterations",
                format!("must be in [1, 100000], got {}", s.swarm_iterations),
            ));
        }
        Ok(())
    }
}
