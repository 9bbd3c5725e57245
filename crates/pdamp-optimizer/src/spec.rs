//! The keys of a design-study file (`pdamp design STUDY.toml`): objective, damper space,
//! material table, constraints, search and verification settings, with their defaults.
//! Loading and checking them is [`crate::study`]'s job.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

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
    /// The damper's orientation at particular points, overriding `direction`: the container's
    /// length L always lies along the point's dof, and gravity lies along it (`vertical`, a dof
    /// along the vertical) or across it (`horizontal`). A structure whose point moves in several
    /// dofs is offered as several points (e.g. `tip_ux`, `tip_uz`), each with its orientation:
    /// the optimiser then chooses the orientation with the point. The containers of one
    /// multi-container set share an orientation (sets that mix are left out).
    #[serde(default)]
    pub point_directions: std::collections::BTreeMap<String, Direction>,
    /// Candidate positions along a `[structure.beam]`, m: a damper point placed there (the FE
    /// snaps it to the nearest node), in the dof of `position_dof`.
    #[serde(default)]
    pub positions_m: Vec<f64>,
    /// Numbers of identical containers to consider (default `[1]`): with n ≥ 2 every set of n
    /// different `points` carries one container each, all with the same design; their bed
    /// masses add (the constraints apply to the sum) and the formulas add their energies
    /// (D Eq. 3.39). Free-decay objectives only.
    #[serde(default = "one_container")]
    pub containers: Vec<usize>,
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
    /// Horizontal containers: inner height, m, shared by the layers. Each layer is then
    /// ⌊H/(layers·2r)⌋ particles high — with `layers = 1` a three-dimensional bed that fills the
    /// cross-section, as the cylinders and cubes of D Ch. 8, its clearance by D Eq. 8.1 and its
    /// optimal stroke X_opt = h/π (D Eq. 8.2, the bouncing of D Eq. 6.12). Default: one particle
    /// row per layer (the rolling layers of D Ch. 5/6).
    #[serde(default)]
    pub container_height_m: Option<f64>,
    /// Horizontal containers: number of separate layers (shelves), each filled independently.
    #[serde(default = "one")]
    pub layers: usize,
    /// Candidate particle radii r, m.
    pub particle_radii_m: Vec<f64>,
    /// Increment of the particle number of a layer (default: one row across the width for
    /// horizontal layers, one level of the cross-section for vertical beds).
    #[serde(default)]
    pub particle_count_step: Option<usize>,
    /// Candidate wall coatings of the two walls the bed impacts (those normal to the
    /// excitation), by name from `[[coatings]]`; `"none"` is the bare container wall (default
    /// `["none"]`). The formulas do not see a coating (D gives only the design rule Eq. 8.11,
    /// no motion-mode formula), so levels 0 and 1 rate the uncoated design and the effective
    /// fields (level 2) and the coupled DEM (level 3) tell the coatings apart.
    #[serde(default = "no_coating")]
    pub coatings: Vec<String>,
}

/// Name of the uncoated wall in `[damper] coatings`.
pub const NO_COATING: &str = "none";

fn no_coating() -> Vec<String> {
    vec![NO_COATING.into()]
}

/// A wall coating of the table (D Sect. 8.1.5): a soft layer on the walls the bed impacts,
/// modelled in DEM as a half-space of its modulus (Hertz contact of a sphere with a flat
/// coating, the idealisation of D's design formula Eq. 8.3–8.11; the finite thickness on the
/// container wall is not represented). `container_lengths_m` are the inner lengths between
/// the coatings' faces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoatingSpec {
    /// Name (in `[damper] coatings`, designs.csv and the scenario files).
    pub name: String,
    /// Young's modulus E_w, Pa (D Tab. 8.4: 0.27 / 0.72 / 1.4 MPa for TFC Type 13 / 1 / 2).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν_w (rubber ≈ 0.5; < 0.5 for the contact law).
    #[serde(default = "default_coating_poisson")]
    pub poisson_ratio: f64,
    /// Density, kg/m³.
    #[serde(default = "default_coating_density")]
    pub density_kg_m3: f64,
    /// Coefficient of restitution particle–coating (default 0.77, T2 of D L1917).
    #[serde(default = "default_coating_restitution")]
    pub restitution: f64,
}

fn default_coating_poisson() -> f64 {
    0.49
}
fn default_coating_density() -> f64 {
    1190.0
}
fn default_coating_restitution() -> f64 {
    0.77
}

fn one_container() -> Vec<usize> {
    vec![1]
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

/// `[verification]`: the effective fields (level 2, approach 2) and the coupled DEM (level 3,
/// approach 1) of the best designs.
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
    /// Best designs (by the time simulation) whose effective fields are computed (level 2,
    /// approach 2), each with every coating of `[damper] coatings`; 0: none.
    #[serde(default)]
    pub field_designs: usize,
    /// Amplitudes of a field (log-spaced over the amplitudes the damper point sees).
    #[serde(default = "default_field_amplitudes")]
    pub field_amplitudes: usize,
    /// Excitation cycles of a field point (the first `field_transient_cycles` dropped).
    #[serde(default = "default_field_cycles")]
    pub field_cycles: u32,
    /// Transient cycles of a field point.
    #[serde(default = "default_field_transient_cycles")]
    pub field_transient_cycles: u32,
    /// Where the fields are stored (relative to the study file; default `OUT/fields`): one
    /// folder per damper, named by the digest of its scenario, with the finished points of
    /// every packing (`pdamp fields`' store). A study run again, or another study with the
    /// same dampers, reuses every stored point.
    #[serde(default)]
    pub fields_store: Option<PathBuf>,
}

fn default_field_amplitudes() -> usize {
    5
}
fn default_field_cycles() -> u32 {
    10
}
fn default_field_transient_cycles() -> u32 {
    3
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
            field_designs: 0,
            field_amplitudes: default_field_amplitudes(),
            field_cycles: default_field_cycles(),
            field_transient_cycles: default_field_transient_cycles(),
            fields_store: None,
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
    /// Wall coatings (`[damper] coatings` picks from them).
    #[serde(default)]
    pub coatings: Vec<CoatingSpec>,
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
