//! Level 3: coupled DEM (approach 1, D Sect. 3.3) on the best designs, with an ensemble of
//! independently dropped beds per design and the 95 % confidence interval of the objective.
//!
//! For every design a damper scenario is written (a box of the design's inner dimensions built
//! from one-sided planes, two-sided shelves between horizontal layers, the study's particle
//! material with its Young's modulus, Poisson's ratio, restitution (Gonthier law) and
//! friction, the container material of `[verification]`), and a coupling scenario with the
//! study's structure and free analysis and that damper as `model = "dem"`. Each packing has its
//! own seed: the drop-down inserts the particles at random and lets them fall in rounds — a
//! horizontal layer is filled under gravity along −x (it collects against a wall, as the
//! rolling layers of D Sect. 5.1 do once they roll) and then turned to −z; a vertical bed falls
//! under −z. The run is `pdamp couple` itself ([`pdamp_structure::report::run_couple`]), so
//! every output of a coupled DEM run (decay.csv, damping.csv, the energy exchange, ParaView
//! frames) lies in `dem/design_N/packing_K/out/`.

use crate::DesignError;
use crate::fidelity::DecayPlan;
use crate::resonance_sweep::{SweepPlan, SweepTarget};
use crate::space::{Design, Space};
use crate::study::{Direction, ObjectiveSpec};
use pdamp_dem::contact::hertz::hertz_contact_time;
use pdamp_design::ensemble::EnsembleStat;
use pdamp_structure::forced;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One design's coupled-DEM result.
#[derive(Debug, Clone, Serialize)]
pub struct DemVerification {
    /// The design's rank among the verified designs (1-based).
    pub rank: usize,
    /// The objective's value: `stroke_m` (min_stroke, smaller is better) or
    /// `mean_damping_ratio` (max_damping: ζ averaged over the amplitude grid and the modes,
    /// larger is better).
    pub objective: &'static str,
    /// The objective of every packing.
    pub values: Vec<f64>,
    /// Mean, spread and 95 % confidence interval of the objective over the packings.
    pub stat: EnsembleStat,
    /// The level-1 (formulas, time simulation) value of the same design.
    pub time_simulation: f64,
    /// max_damping: each mode's ζ̄ over the packings and ζ(X) on the amplitude grid.
    pub modes: Vec<DemModeDamping>,
    /// min_frf_peak, max_resonance_damping: each mode's resonance from the DEM sweeps.
    pub resonances: Vec<DemResonance>,
    /// DEM time step used, s.
    pub time_step_s: f64,
    /// Factor applied to the particles' Young's modulus.
    pub youngs_modulus_scale: f64,
    /// Particles of the beds (all containers).
    pub particles: usize,
    /// Coupled runs made (packings, × modes for max_damping).
    pub runs: usize,
    /// Estimated cost before the runs: particles × DEM steps of all runs.
    pub estimated_particle_steps: f64,
    /// Largest energy closure of the runs (bed ledger and coupling, relative to the energy
    /// dissipated; `pdamp couple`'s `energy_exchange`).
    pub energy_closure: f64,
    /// Wall time of all packings, s.
    pub wall_s: f64,
    /// Where the runs are (relative to the output directory).
    pub dir: String,
}

impl DemVerification {
    /// Whether a larger objective is better (damping) or a smaller one (stroke, peak).
    pub fn larger_is_better(&self) -> bool {
        matches!(
            self.objective,
            "mean_damping_ratio" | "mean_resonance_damping_ratio"
        )
    }
}

impl DemResonance {
    /// Level 1's peak relative to the bare peak on the same sweep as the DEM (the formula
    /// dampers run through the plan's sweep).
    pub fn formula_sweep_relative_peak(&self) -> f64 {
        self.time_simulation.0 * (1.0 + self.sweep.formula_sweep_bias())
    }
}

/// One mode's resonance from the coupled-DEM sweeps of a design (forced objectives,
/// [`crate::resonance_sweep`]).
#[derive(Debug, Clone, Serialize)]
pub struct DemResonance {
    /// Mode number (1-based).
    pub mode: usize,
    /// Peak at the output point relative to the bare structure's, per packing.
    pub relative_peak: Vec<f64>,
    /// Its ensemble statistics.
    pub relative_peak_stat: EnsembleStat,
    /// ζ at resonance (D Eq. 3.47) per packing.
    pub damping_ratio: Vec<f64>,
    /// Its ensemble statistics.
    pub damping_ratio_stat: EnsembleStat,
    /// Frequency of the peak per packing, Hz.
    pub resonance_frequency_hz: Vec<f64>,
    /// Level 1 (steady-state FRF of the formula dampers, D Eq. 3.44): relative peak, ζ,
    /// frequency of the peak (Hz).
    pub time_simulation: (f64, f64, f64),
    /// The sweep the packings ran.
    pub sweep: crate::resonance_sweep::SweepSummary,
    /// Why the sweep was planned again after the first packing, if it was.
    pub replanned: Option<String>,
}

/// One mode's damping from the coupled-DEM decays of a design (max_damping).
#[derive(Debug, Clone, Serialize)]
pub struct DemModeDamping {
    /// Mode number (1-based).
    pub mode: usize,
    /// ζ averaged over the amplitude grid, per packing.
    pub damping_ratio: Vec<f64>,
    /// Its ensemble statistics.
    pub stat: EnsembleStat,
    /// The level-1 value of the same design.
    pub time_simulation: f64,
    /// ζ(X) over the packings on the amplitude grid: (X in m, statistics).
    pub curve: Vec<(f64, EnsembleStat)>,
    /// Smallest and largest cycle amplitude the decays reached (the grid outside it takes the
    /// nearest cycle's ζ), m.
    pub covered_amplitude_m: (f64, f64),
}

/// Largest relative particle velocity expected in the study: twice the damper point's
/// initial velocity amplitude X₀ω, plus a margin, m/s.
pub fn check_velocity_m_s(space: &Space, d: &Design) -> f64 {
    let a = space.peak_acceleration_m_s2(d);
    let k = space.study.free.mode;
    let w = space.structure(d.choice).modes[k].omega_rad_s();
    2.0 * a / w + 0.2
}

/// The DEM time step: `[verification] time_step_s` or 0.08 of the shorter Hertz contact time,
/// particle–particle or particle–container wall, at the check velocity (D Eq. 4.8; pdamp refuses
/// steps above 0.1 of the shortest contact).
pub fn time_step_s(space: &Space, d: &Design) -> f64 {
    time_step_at_s(space, d, check_velocity_m_s(space, d))
}

/// [`time_step_s`] for a largest relative impact velocity `velocity_m_s`.
pub fn time_step_at_s(space: &Space, d: &Design, velocity_m_s: f64) -> f64 {
    let v = &space.study.file.verification;
    if let Some(dt) = v.time_step_s {
        return dt;
    }
    let g = space.geometry(d.choice);
    let m = &space.study.file.materials[d.choice.material];
    let e = m.youngs_modulus_pa * v.youngs_modulus_scale;
    let compliance = (1.0 - m.poisson_ratio * m.poisson_ratio) / e;
    // two particles: E* = 1/(2(1−ν²)/E), R* = r/2, m* = m/2
    let pair = hertz_contact_time(
        1.0 / (2.0 * compliance),
        0.5 * g.radius_m,
        0.5 * g.particle_mass_kg,
        velocity_m_s,
    );
    // a particle on the container wall (flat, at rest): R* = r, m* = m — shorter than the pair's
    // where the wall is much stiffer than softened particles
    let c = &v.container;
    let wall = hertz_contact_time(
        1.0 / (compliance + (1.0 - c.poisson_ratio * c.poisson_ratio) / c.youngs_modulus_pa),
        g.radius_m,
        g.particle_mass_kg,
        velocity_m_s,
    );
    0.08 * pair.min(wall)
}

fn plane(
    s: &mut String,
    name: &str,
    material: &str,
    point: [f64; 3],
    normal: [f64; 3],
    two_sided: bool,
) {
    let _ = writeln!(
        s,
        "[[bodies.walls]]\nname = \"{name}\"\nmaterial = \"{material}\"\ngeometry = {{ type = \
         \"plane\", point_m = [{:e}, {:e}, {:e}], normal = [{}, {}, {}], two_sided = {two_sided} \
         }}\n",
        point[0], point[1], point[2], normal[0], normal[1], normal[2]
    );
}

/// The six walls of a box container, x ∈ [−a/2, a/2], y ∈ [−b/2, b/2], z ∈ [0, c], as one-sided
/// planes facing inwards; the two walls normal to the excitation (x for a horizontal
/// container, z for a vertical one) of material `impacted`, the others of the container's.
fn box_walls(s: &mut String, a: f64, b: f64, c: f64, vertical: bool, impacted: &str) {
    let (xm, zm) = if vertical {
        ("container", impacted)
    } else {
        (impacted, "container")
    };
    plane(
        s,
        "wall_x-",
        xm,
        [-a / 2.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        false,
    );
    plane(
        s,
        "wall_x+",
        xm,
        [a / 2.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        false,
    );
    plane(
        s,
        "wall_y-",
        "container",
        [0.0, -b / 2.0, 0.0],
        [0.0, 1.0, 0.0],
        false,
    );
    plane(
        s,
        "wall_y+",
        "container",
        [0.0, b / 2.0, 0.0],
        [0.0, -1.0, 0.0],
        false,
    );
    plane(s, "floor", zm, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], false);
    plane(s, "lid", zm, [0.0, 0.0, c], [0.0, 0.0, -1.0], false);
}

/// The damper scenario of a design (TOML), for packing seed `seed`.
pub fn damper_scenario(space: &Space, d: &Design, seed: u64) -> String {
    let st = space.study;
    let f = &st.file;
    let v = &f.verification;
    let g = space.geometry(d.choice);
    let m = &f.materials[d.choice.material];
    let dt = time_step_s(space, d);
    let vcheck = check_velocity_m_s(space, d);
    let k = st.free.mode;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Coupled-DEM verification of a design of {} (pdamp design):\n# {}\n\
         title = \"pdamp design verification\"\n\n[simulation]\nduration_s = 0.0\n\
         time_step_s = {dt:e}\ngravity_m_s2 = [0.0, 0.0, -9.81]\nseed = {seed}\n\
         check_impact_velocity_m_s = {vcheck}\n",
        st.path.display(),
        crate::report::describe(space, d)
    );
    let _ = writeln!(
        s,
        "[[materials]]\nname = \"particle\"\ndensity_kg_m3 = {}\nyoungs_modulus_pa = {:e}\n\
         poisson_ratio = {}\n\n[[materials]]\nname = \"container\"\ndensity_kg_m3 = {}\n\
         youngs_modulus_pa = {:e}\npoisson_ratio = {}\n",
        m.density_kg_m3,
        m.youngs_modulus_pa * v.youngs_modulus_scale,
        m.poisson_ratio,
        v.container.density_kg_m3,
        v.container.youngs_modulus_pa,
        v.container.poisson_ratio
    );
    let _ = writeln!(
        s,
        "[contact]\nnormal = {{ law = \"gonthier\", restitution = {}, min_impact_velocity_m_s = \
         0.05 }}\nfriction = {{ law = \"regularized-sliding\", friction_coefficient = {}, \
         regularization_s_m = 1000.0 }}\n\n[[contact.pairs]]\nmaterials = [\"particle\", \
         \"container\"]\nnormal = {{ law = \"gonthier\", restitution = {}, \
         min_impact_velocity_m_s = 0.05 }}\nfriction = {{ law = \"regularized-sliding\", \
         friction_coefficient = {}, regularization_s_m = 1000.0 }}\n",
        m.restitution, m.friction, m.wall_restitution, m.friction
    );
    let coating = st.coating(d.choice.coating);
    let impacted = if let Some(c) = coating {
        let _ = writeln!(
            s,
            "# end walls coated with {}: a half-space of its modulus (D Eq. 8.3–8.11)\n\
             [[materials]]\nname = \"coating\"\ndensity_kg_m3 = {}\nyoungs_modulus_pa = {:e}\n\
             poisson_ratio = {}\n\n[[contact.pairs]]\nmaterials = [\"particle\", \"coating\"]\n\
             normal = {{ law = \"gonthier\", restitution = {}, min_impact_velocity_m_s = 0.05 }}\n\
             friction = {{ law = \"regularized-sliding\", friction_coefficient = {}, \
             regularization_s_m = 1000.0 }}\n",
            c.name,
            c.density_kg_m3,
            c.youngs_modulus_pa,
            c.poisson_ratio,
            c.restitution,
            m.friction
        );
        "coating"
    } else {
        "container"
    };
    let _ = writeln!(s, "[[bodies]]\nname = \"container\"\n");
    let (l, w) = (g.length_m, f.damper.container_width_m);
    let direction;
    let mut groups: Vec<(usize, [f64; 3], [f64; 3])> = Vec::new();
    let settle_gravity;
    match space.location(d.choice).direction {
        Direction::Horizontal => {
            let h = match f.damper.container_height_m {
                Some(height) => height / d.particles.len() as f64,
                None => v.layer_height_m.unwrap_or(2.2 * g.radius_m),
            };
            let top = h * d.particles.len() as f64;
            box_walls(&mut s, l, w, top, false, impacted);
            for i in 1..d.particles.len() {
                plane(
                    &mut s,
                    &format!("shelf_{i}"),
                    "container",
                    [0.0, 0.0, i as f64 * h],
                    [0.0, 0.0, 1.0],
                    true,
                );
            }
            for (i, &n) in d.particles.iter().enumerate() {
                if n > 0 {
                    groups.push((
                        n,
                        [-l / 2.0, -w / 2.0, i as f64 * h],
                        [l / 2.0, w / 2.0, (i + 1) as f64 * h],
                    ));
                }
            }
            direction = [1.0, 0.0, 0.0];
            settle_gravity = Some([-9.81, 0.0, 0.0]);
        }
        Direction::Vertical => {
            let depth = f.damper.container_depth_m.unwrap_or(w);
            box_walls(&mut s, w, depth, l, true, impacted);
            groups.push((
                d.particles[0],
                [-w / 2.0, -depth / 2.0, 0.0],
                [w / 2.0, depth / 2.0, l],
            ));
            direction = [0.0, 0.0, 1.0];
            settle_gravity = None;
        }
    }
    for (n, lo, hi) in groups {
        let _ = writeln!(
            s,
            "[[particles]]\nmaterial = \"particle\"\ncount = {n}\nsize = {{ type = \
             \"monodisperse\", radius_m = {:e} }}\nplacement = {{ method = \"drop_down\", region \
             = {{ type = \"box\", min_m = [{:e}, {:e}, {:e}], max_m = [{:e}, {:e}, {:e}] }} }}\n",
            g.radius_m, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
        );
    }
    let _ = writeln!(
        s,
        "[settle]\nmax_duration_s = 1.0\nkinetic_energy_per_particle_j = 1e-9{}\n",
        settle_gravity.map_or(String::new(), |g| format!(
            "\ngravity_m_s2 = [{}, {}, {}]\nturn_max_duration_s = 0.5",
            g[0], g[1], g[2]
        ))
    );
    let freq = space.structure(d.choice).modes[k].frequency_hz;
    let _ = writeln!(
        s,
        "[damper]\ncontainer_body = \"container\"\ncontainer_mass_kg = 0.0\ndirection = [{}, {}, \
         {}]\nfrequency_hz = {freq}\namplitude_m = {:e}\ncycles = 2\ntransient_cycles = 1",
        direction[0],
        direction[1],
        direction[2],
        st.free.initial_displacement_m.abs().max(1e-6)
    );
    s
}

/// The damper scenario file of container `j` (0-based) of a design's run: `damper.toml`, then
/// `damper_2.toml`, … beside the coupling scenario.
fn damper_file(j: usize) -> String {
    if j == 0 {
        "damper.toml".into()
    } else {
        format!("damper_{}.toml", j + 1)
    }
}

/// The drop seed of container `j` of the packing with seed `seed`: the packing's own for the
/// first container, independent ones for the others (never another packing's).
fn container_seed(seed: u64, j: usize) -> u64 {
    if j == 0 {
        seed
    } else {
        seed ^ (j as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
    }
}

/// Replaces a coupling scenario's dampers by the design's DEM beds, one per container at its
/// point ([`damper_file`] beside it).
fn set_dem_damper(space: &Space, d: &Design, table: &mut toml::Table) {
    let dampers = space
        .location(d.choice)
        .points
        .iter()
        .enumerate()
        .map(|(j, point)| {
            let mut damper = toml::Table::new();
            damper.insert("model".into(), toml::Value::String("dem".into()));
            damper.insert("point".into(), toml::Value::String(point.clone()));
            damper.insert("scenario".into(), toml::Value::String(damper_file(j)));
            toml::Value::Table(damper)
        })
        .collect();
    table.insert("dampers".into(), toml::Value::Array(dampers));
}

/// Sampling interval (DEM steps) for about 4000 samples of a decay of `duration_s`.
fn sample_every(space: &Space, d: &Design, duration_s: f64) -> i64 {
    ((duration_s / time_step_s(space, d)) / 4000.0)
        .floor()
        .max(1.0) as i64
}

/// The coupling scenario of a design's DEM run (TOML): the study's structure and free analysis
/// (duration = the evaluation time) with the DEM damper at the design's point.
pub fn couple_scenario(
    space: &Space,
    d: &Design,
    evaluate_at_s: f64,
) -> Result<String, DesignError> {
    let mut table = crate::report::scenario_table(space, d)?;
    set_dem_damper(space, d, &mut table);
    if let Some(toml::Value::Table(a)) = table.get_mut("analysis") {
        a.insert("duration_s".into(), toml::Value::Float(evaluate_at_s));
        a.insert(
            "sample_every".into(),
            toml::Value::Integer(sample_every(space, d, evaluate_at_s)),
        );
    }
    toml::to_string(&table).map_err(|e| DesignError::Solver(e.to_string()))
}

/// The study's coupling scenario with the structure replaced by `s` written inline as
/// `[structure.modal]` (a structure reduced to one mode) and the DEM damper at the design's
/// point; the caller sets `[analysis]`.
fn single_mode_table(
    space: &Space,
    d: &Design,
    s: &pdamp_structure::modal::ModalStructure,
) -> Result<toml::Table, DesignError> {
    let mut table = crate::report::scenario_table(space, d)?;
    table.remove("structure_file");
    let points: Vec<toml::Value> = s
        .points
        .iter()
        .map(|p| {
            let mut t = toml::Table::new();
            t.insert("name".into(), toml::Value::String(p.name.clone()));
            t.insert(
                "shape".into(),
                toml::Value::Array(p.shape.iter().map(|&v| toml::Value::Float(v)).collect()),
            );
            toml::Value::Table(t)
        })
        .collect();
    let floats = |v: Vec<f64>| toml::Value::Array(v.into_iter().map(toml::Value::Float).collect());
    let mut modal = toml::Table::new();
    modal.insert(
        "frequencies_hz".into(),
        floats(s.modes.iter().map(|m| m.frequency_hz).collect()),
    );
    modal.insert(
        "damping_ratios".into(),
        floats(s.modes.iter().map(|m| m.damping_ratio).collect()),
    );
    modal.insert("points".into(), toml::Value::Array(points));
    let mut structure = toml::Table::new();
    structure.insert("n_modes".into(), toml::Value::Integer(1));
    structure.insert("modal".into(), toml::Value::Table(modal));
    table.insert("structure".into(), toml::Value::Table(structure));
    set_dem_damper(space, d, &mut table);
    Ok(table)
}

/// The coupling scenario of a design's damping decay in one mode (max_damping, TOML): the
/// [`DecayPlan`]'s single-mode structure written inline as `[structure.modal]`, its free
/// analysis over `duration_s`, and the DEM damper at the design's point.
pub fn decay_scenario(
    space: &Space,
    d: &Design,
    plan: &DecayPlan,
    duration_s: f64,
) -> Result<String, DesignError> {
    let mut table = single_mode_table(space, d, &plan.structure)?;
    let f = &plan.spec;
    let every = sample_every(space, d, duration_s);
    let analysis: toml::Table = toml::from_str(&format!(
        "kind = \"free\"\nduration_s = {duration_s:e}\ntime_step_s = {:e}\nmode = 1\n\
         initial_point = \"{}\"\ninitial_displacement_m = {:e}\noutput_point = \"{}\"\n\
         sample_every = {every}\n",
        f.time_step_s, f.initial_point, f.initial_displacement_m, f.output_point
    ))
    .map_err(|e| DesignError::Solver(e.to_string()))?;
    table.insert("analysis".into(), toml::Value::Table(analysis));
    toml::to_string(&table).map_err(|e| DesignError::Solver(e.to_string()))
}

/// The coupling scenario of a design's resonance sweep in one mode (forced objectives, TOML):
/// the [`SweepPlan`]'s single-mode structure inline, its sweep (`kind = "sweep"`, sampled
/// [`crate::resonance_sweep::SAMPLES_PER_PERIOD`] times per period of the highest frequency
/// at the DEM step) and the DEM damper at the design's point.
pub fn sweep_scenario(space: &Space, d: &Design, plan: &SweepPlan) -> Result<String, DesignError> {
    let mut table = single_mode_table(space, d, &plan.structure)?;
    let s = &plan.spec;
    let top = s.sweep.start_hz.max(s.sweep.end_hz);
    let every = ((1.0 / (crate::resonance_sweep::SAMPLES_PER_PERIOD * top)) / time_step_s(space, d))
        .floor()
        .max(1.0) as i64;
    let analysis: toml::Table = toml::from_str(&format!(
        "kind = \"sweep\"\nstart_hz = {:e}\nend_hz = {:e}\nduration_s = {:e}\n\
         law = \"linear\"\nforce_amplitude_n = {:e}\nexcitation_point = \"{}\"\n\
         output_point = \"{}\"\ntime_step_s = {:e}\nsample_every = {every}\nmode = 1\n",
        s.sweep.start_hz,
        s.sweep.end_hz,
        s.sweep.duration_s,
        s.force_amplitude_n,
        s.excitation_point,
        s.output_point,
        s.time_step_s
    ))
    .map_err(|e| DesignError::Solver(e.to_string()))?;
    table.insert("analysis".into(), toml::Value::Table(analysis));
    toml::to_string(&table).map_err(|e| DesignError::Solver(e.to_string()))
}

/// How much longer than the formulas' decay a DEM decay runs: a DEM bed that damps less than
/// the formulas predict still reaches (most of) the bottom of the amplitude range.
pub const DEM_DECAY_MARGIN: f64 = 1.25;

/// One coupled DEM run of a packing: writes the damper scenario of every container (each its
/// own drop) and the coupling scenario to `dir`, runs
/// `pdamp couple` into `dir/out` and returns the history at the output point (`history`:
/// `decay.csv` of a free analysis, `response.csv` of a sweep) and the run's energy closure
/// (the larger of the bed ledger's and the coupling's, from `summary.json`).
fn run_one(
    space: &Space,
    d: &Design,
    dir: &Path,
    seed: u64,
    couple: &str,
    history: &str,
) -> Result<(pdamp_structure::free::TimeHistory, f64), DesignError> {
    std::fs::create_dir_all(dir).map_err(|e| DesignError::output(dir, e))?;
    for j in 0..space.location(d.choice).points.len() {
        let dscn = dir.join(damper_file(j));
        let text = damper_scenario(space, d, container_seed(seed, j));
        pdamp_io::atomic::write_atomic(&dscn, text.as_bytes())
            .map_err(|e| DesignError::output(&dscn, e))?;
    }
    let cscn = dir.join("couple.toml");
    pdamp_io::atomic::write_atomic(&cscn, couple.as_bytes())
        .map_err(|e| DesignError::output(&cscn, e))?;
    let run_out = dir.join("out");
    let _ = std::fs::remove_dir_all(&run_out);
    pdamp_structure::report::run_couple(
        &cscn,
        &run_out,
        pdamp_io::run::RunOptions {
            checkpoint_interval_s: 0.0,
            resume: false,
        },
        &mut |_| {},
    )
    .map_err(|error| DesignError::StructureFile {
        path: cscn.clone(),
        error: Box::new(error),
    })?;
    let sp = run_out.join("summary.json");
    let summary: serde_json::Value = std::fs::read_to_string(&sp)
        .map_err(|e| DesignError::output(&sp, e))
        .and_then(|t| serde_json::from_str(&t).map_err(|e| DesignError::output(&sp, e)))?;
    let e = &summary["energy_exchange"];
    let closure = ["bed_ledger_closure", "coupling_closure"]
        .iter()
        .map(|k| e[*k].as_f64().unwrap_or(f64::NAN))
        .fold(0.0_f64, |a, b| if b.is_nan() { f64::NAN } else { a.max(b) });
    Ok((read_decay(&run_out.join(history))?, closure))
}

/// Runs the coupled DEM of `d` on `[verification] packings` beds in `out/dem/design_RANK` and
/// returns the objective of each: the stroke at the evaluation time (min_stroke), or ζ(X) of
/// every mode from a free decay over the amplitude range (max_damping, one run per mode and
/// packing, [`DecayPlan`] × [`DEM_DECAY_MARGIN`]), or each mode's resonance from a sine sweep
/// (min_frf_peak, max_resonance_damping, [`crate::resonance_sweep`]). `level1` is the design's time-simulation
/// evaluation (compared in the result). The cost (particles × steps) is reported through
/// `progress` before the first run.
///
/// # Errors
/// Input, DEM and output errors (the message names the packing's directory).
pub fn verify_design(
    space: &Space,
    d: &Design,
    rank: usize,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<DemVerification, DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rel = PathBuf::from(format!("dem/design_{rank}"));
    let started = std::time::Instant::now();
    let dt = time_step_s(space, d);
    // every container carries the design's bed
    let particles: usize =
        d.particles.iter().sum::<usize>() * space.location(d.choice).points.len();
    let mut result = DemVerification {
        rank,
        objective: "stroke_m",
        values: Vec::new(),
        stat: EnsembleStat::of(&[]),
        time_simulation: level1.stroke_m.unwrap_or(f64::NAN),
        modes: Vec::new(),
        resonances: Vec::new(),
        time_step_s: dt,
        youngs_modulus_scale: v.youngs_modulus_scale,
        particles,
        runs: 0,
        estimated_particle_steps: 0.0,
        energy_closure: 0.0,
        wall_s: 0.0,
        dir: rel.display().to_string(),
    };
    match &st.file.objective {
        ObjectiveSpec::MinStroke { evaluate_at_s } => {
            let k = st.free.mode;
            let period = 1.0 / space.structure(d.choice).modes[k].frequency_hz;
            result.estimated_particle_steps = announce(
                progress,
                &result,
                v.packings,
                v.packings as f64 * evaluate_at_s,
            );
            let couple = couple_scenario(space, d, *evaluate_at_s)?;
            for p in 0..v.packings {
                progress(&format!(
                    "design {rank}, packing {}/{}: coupled DEM",
                    p + 1,
                    v.packings
                ));
                let dir = out.join(&rel).join(format!("packing_{}", p + 1));
                let (hist, closure) =
                    run_one(space, d, &dir, seed(space, p), &couple, "decay.csv")?;
                result.runs += 1;
                result.energy_closure = result.energy_closure.max(closure);
                result.values.push(pdamp_structure::study::stroke_at(
                    &hist,
                    *evaluate_at_s,
                    1.1 * period,
                ));
            }
        }
        ObjectiveSpec::MaxDamping { .. } => {
            damping_decays(space, d, level1, out, &mut result, progress)?;
        }
        ObjectiveSpec::MinFrfPeak { .. } | ObjectiveSpec::MaxResonanceDamping { .. } => {
            resonance_sweeps(space, d, level1, out, &mut result, progress)?;
        }
    }
    result.stat = EnsembleStat::of(&result.values);
    result.wall_s = started.elapsed().as_secs_f64();
    Ok(result)
}

/// The cost of a verification in particle-steps (settling excluded), reported through
/// `progress` before the runs.
fn announce(
    progress: &mut dyn FnMut(&str),
    r: &DemVerification,
    runs: usize,
    simulated_s: f64,
) -> f64 {
    let ps = r.particles as f64 * simulated_s / r.time_step_s;
    progress(&format!(
        "design {}: coupled DEM, {runs} runs of {} particles, {simulated_s:.3} s simulated at \
         dt = {:.2e} s: {ps:.2e} particle-steps (≈ {:.0} min at 5e6 particle-steps/s; bed \
         preparation extra)",
        r.rank,
        r.particles,
        r.time_step_s,
        ps / 5e6 / 60.0
    ));
    ps
}

pub(crate) fn seed(space: &Space, packing: usize) -> u64 {
    pdamp_io::prepare::packing_seed(space.study.file.search.seed, packing)
}

/// max_damping: one free decay per packing and mode ([`DecayPlan`] × [`DEM_DECAY_MARGIN`]),
/// ζ(X) per cycle, averaged over the amplitude grid; fills `result`'s values and modes.
fn damping_decays(
    space: &Space,
    d: &Design,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    result: &mut DemVerification,
    progress: &mut dyn FnMut(&str),
) -> Result<(), DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rank = result.rank;
    let rel = PathBuf::from(&result.dir);
    let ObjectiveSpec::MaxDamping {
        modes,
        amplitude_min_m,
        amplitude_max_m,
        amplitudes,
    } = &st.file.objective
    else {
        return Err(DesignError::Solver(
            "damping decays: a max_damping objective".into(),
        ));
    };
    result.objective = "mean_damping_ratio";
    result.time_simulation = -level1.cost;
    let dampers = space.coupled_dampers(d)?;
    let structure = space.structure(d.choice);
    let plans = modes
        .iter()
        .map(|&m| {
            crate::fidelity::damping_decay_plan(
                st,
                structure,
                &dampers,
                m - 1,
                *amplitude_min_m,
                *amplitude_max_m,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let simulated: f64 = plans
        .iter()
        .map(|p| DEM_DECAY_MARGIN * p.spec.duration_s)
        .sum();
    result.estimated_particle_steps = announce(
        progress,
        result,
        v.packings * plans.len(),
        v.packings as f64 * simulated,
    );
    let grid = crate::fidelity::amplitude_grid(*amplitude_min_m, *amplitude_max_m, *amplitudes);
    let mut per_mode: Vec<Vec<Vec<(f64, f64)>>> = vec![Vec::new(); plans.len()];
    for p in 0..v.packings {
        for (i, (plan, &m)) in plans.iter().zip(modes).enumerate() {
            progress(&format!(
                "design {rank}, packing {}/{}, mode {m}: coupled DEM decay",
                p + 1,
                v.packings
            ));
            let dir = out
                .join(&rel)
                .join(format!("packing_{}", p + 1))
                .join(format!("mode_{m}"));
            let duration = DEM_DECAY_MARGIN * plan.spec.duration_s;
            let couple = decay_scenario(space, d, plan, duration)?;
            let (hist, closure) = run_one(space, d, &dir, seed(space, p), &couple, "decay.csv")?;
            result.runs += 1;
            result.energy_closure = result.energy_closure.max(closure);
            per_mode[i].push(crate::fidelity::damping_curve_of(&hist, plan.period_s)?);
        }
    }
    let mean_of = |curve: &[(f64, f64)]| {
        grid.iter()
            .map(|&x| crate::fidelity::curve_at(curve, x))
            .sum::<f64>()
            / grid.len() as f64
    };
    for (i, &m) in modes.iter().enumerate() {
        let curves = &per_mode[i];
        let zeta: Vec<f64> = curves.iter().map(|c| mean_of(c)).collect();
        let covered = curves
            .iter()
            .flatten()
            .fold((f64::INFINITY, 0.0_f64), |a, c| {
                (a.0.min(c.0), a.1.max(c.0))
            });
        let curve = grid
            .iter()
            .map(|&x| {
                let z: Vec<f64> = curves
                    .iter()
                    .map(|c| crate::fidelity::curve_at(c, x))
                    .collect();
                (x, EnsembleStat::of(&z))
            })
            .collect();
        result.modes.push(DemModeDamping {
            mode: m,
            stat: EnsembleStat::of(&zeta),
            damping_ratio: zeta,
            time_simulation: level1
                .damping_ratio_per_mode
                .get(i)
                .copied()
                .unwrap_or(f64::NAN),
            curve,
            covered_amplitude_m: covered,
        });
    }
    result.values = (0..v.packings)
        .map(|p| {
            result.modes.iter().map(|m| m.damping_ratio[p]).sum::<f64>() / result.modes.len() as f64
        })
        .collect();
    Ok(())
}

/// min_frf_peak, max_resonance_damping: per mode a [`SweepPlan`] at level 1's resonance
/// (frequency and ζ of the steady-state FRF); one coupled-DEM sweep per packing and mode. After
/// the first packing a mode's sweep is planned again once, around the DEM's peak and for the
/// smaller ζ, if [`crate::resonance_sweep::replan_reason`] says so, and that packing runs
/// again. Fills `result`'s values (mean relative peak or mean ζ over the modes) and resonances.
fn resonance_sweeps(
    space: &Space,
    d: &Design,
    level1: &crate::fidelity::Evaluation,
    out: &Path,
    result: &mut DemVerification,
    progress: &mut dyn FnMut(&str),
) -> Result<(), DesignError> {
    let st = space.study;
    let v = &st.file.verification;
    let rank = result.rank;
    let rel = PathBuf::from(&result.dir);
    let (ObjectiveSpec::MinFrfPeak {
        modes,
        frequencies,
        band,
    }
    | ObjectiveSpec::MaxResonanceDamping {
        modes,
        frequencies,
        band,
    }) = &st.file.objective
    else {
        return Err(DesignError::Solver(
            "resonance sweeps: a forced objective".into(),
        ));
    };
    let peak_objective = matches!(st.file.objective, ObjectiveSpec::MinFrfPeak { .. });
    result.objective = if peak_objective {
        "relative_peak"
    } else {
        "mean_resonance_damping_ratio"
    };
    result.time_simulation = if peak_objective {
        level1.cost
    } else {
        -level1.cost
    };
    let dampers = space.coupled_dampers(d)?;
    let structure = space.structure(d.choice);
    let mut plans = Vec::new();
    let mut level1_modes = Vec::new();
    for &m in modes {
        let k = m - 1;
        let steady =
            crate::fidelity::frf_resonance(st, structure, &dampers, k, *frequencies, *band)?;
        let zeta = crate::fidelity::resonance_damping_ratio(st, structure, k, steady.modal_peak)?;
        let bare = crate::fidelity::bare_peak_m(st, k)?;
        level1_modes.push((steady, zeta, bare));
        plans.push(crate::resonance_sweep::sweep_plan(
            st,
            structure,
            &dampers,
            k,
            &steady,
            SweepTarget {
                centre_hz: steady.frequency_hz,
                band_damping_ratio: zeta,
                rate_damping_ratio: zeta,
            },
        )?);
    }
    let simulated: f64 = plans.iter().map(|p| p.summary.duration_s).sum();
    result.estimated_particle_steps = announce(
        progress,
        result,
        v.packings * plans.len(),
        v.packings as f64 * simulated,
    );
    let mut peaks: Vec<Vec<forced::PeakDamping>> = vec![Vec::new(); plans.len()];
    let mut replanned: Vec<Option<String>> = vec![None; plans.len()];
    for p in 0..v.packings {
        for (i, &m) in modes.iter().enumerate() {
            let dir = out
                .join(&rel)
                .join(format!("packing_{}", p + 1))
                .join(format!("mode_{m}"));
            loop {
                let plan = &plans[i];
                progress(&format!(
                    "design {rank}, packing {}/{}, mode {m}: coupled DEM sweep {:.3}–{:.3} Hz \
                     in {:.1} s",
                    p + 1,
                    v.packings,
                    plan.summary.start_hz,
                    plan.summary.end_hz,
                    plan.summary.duration_s
                ));
                let couple = sweep_scenario(space, d, plan)?;
                let (hist, closure) =
                    run_one(space, d, &dir, seed(space, p), &couple, "response.csv")?;
                let pk = plan.peak_of(&hist).ok_or_else(|| {
                    DesignError::Solver(format!(
                        "{}: the sweep's response has no peak",
                        dir.display()
                    ))
                })?;
                let why = crate::resonance_sweep::replan_reason(&plan.summary, &pk);
                if let Some(why) = why.filter(|_| p == 0 && replanned[i].is_none()) {
                    progress(&format!(
                        "design {rank}, mode {m}: sweep planned again: {why}"
                    ));
                    let (steady, zeta, _) = level1_modes[i];
                    let k = m - 1;
                    plans[i] = crate::resonance_sweep::sweep_plan(
                        st,
                        structure,
                        &dampers,
                        k,
                        &steady,
                        SweepTarget {
                            centre_hz: pk.resonance_frequency_hz,
                            band_damping_ratio: zeta.max(pk.damping_ratio),
                            rate_damping_ratio: zeta.min(pk.damping_ratio),
                        },
                    )?;
                    replanned[i] = Some(why);
                    continue;
                }
                result.runs += 1;
                result.energy_closure = result.energy_closure.max(closure);
                peaks[i].push(pk);
                break;
            }
        }
    }
    for (i, &m) in modes.iter().enumerate() {
        let (steady, zeta, bare) = level1_modes[i];
        let rel_peak: Vec<f64> = peaks[i].iter().map(|p| p.max_amplitude_m / bare).collect();
        let zetas: Vec<f64> = peaks[i].iter().map(|p| p.damping_ratio).collect();
        result.resonances.push(DemResonance {
            mode: m,
            relative_peak_stat: EnsembleStat::of(&rel_peak),
            relative_peak: rel_peak,
            damping_ratio_stat: EnsembleStat::of(&zetas),
            damping_ratio: zetas,
            resonance_frequency_hz: peaks[i].iter().map(|p| p.resonance_frequency_hz).collect(),
            time_simulation: (steady.peak_m / bare, zeta, steady.frequency_hz),
            sweep: plans[i].summary,
            replanned: replanned[i].take(),
        });
    }
    let n = modes.len() as f64;
    result.values = (0..v.packings)
        .map(|p| {
            result
                .resonances
                .iter()
                .map(|r| {
                    if peak_objective {
                        r.relative_peak[p]
                    } else {
                        r.damping_ratio[p]
                    }
                })
                .sum::<f64>()
                / n
        })
        .collect();
    Ok(())
}

/// Reads `decay.csv` or `response.csv` (time_s, displacement_m, …) of a coupled run.
fn read_decay(path: &Path) -> Result<pdamp_structure::free::TimeHistory, DesignError> {
    let text = std::fs::read_to_string(path).map_err(|e| DesignError::output(path, e))?;
    let mut h = pdamp_structure::free::TimeHistory::default();
    for line in text.lines().skip(1) {
        let mut it = line.split(',');
        let t = it.next().and_then(|x| x.parse::<f64>().ok());
        let x = it.next().and_then(|x| x.parse::<f64>().ok());
        if let (Some(t), Some(x)) = (t, x) {
            h.time_s.push(t);
            h.displacement_m.push(x);
        }
    }
    Ok(h)
}
