//! The scenarios of a design's coupled-DEM runs: the damper scenario of every container (a box
//! of one-sided planes, shelves between horizontal layers, the materials and contact laws, the
//! drop) and the coupling scenarios of a decay or a resonance sweep.

use super::{check_velocity_m_s, time_step_s};
use crate::DesignError;
use crate::design_scenario::{describe, scenario_table};
use crate::fidelity::DecayPlan;
use crate::resonance_sweep::{SAMPLES_PER_PERIOD, SweepPlan};
use crate::space::{Design, Space};
use crate::spec::{CoatingSpec, MaterialSpec, VerificationSpec};
use crate::study::Direction;
use std::fmt::Write as _;

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
    let f = &space.study.file;
    let m = &f.materials[d.choice.material];
    let mut s = String::new();
    write_simulation_section(&mut s, space, d, seed);
    write_material_sections(&mut s, m, &f.verification);
    write_contact_section(&mut s, m);
    let impacted = match space.study.coating(d.choice.coating) {
        Some(c) => write_coating_section(&mut s, c, m),
        None => "container",
    };
    let _ = writeln!(s, "[[bodies]]\nname = \"container\"\n");
    let bed = match space.location(d.choice).direction {
        Direction::Horizontal => write_horizontal_container(&mut s, space, d, impacted),
        Direction::Vertical => write_vertical_container(&mut s, space, d, impacted),
    };
    let radius_m = space.geometry(d.choice).radius_m;
    for (n, lo, hi) in bed.groups {
        write_particle_group(&mut s, radius_m, n, lo, hi);
    }
    write_settle_section(&mut s, bed.settle_gravity);
    write_damper_section(&mut s, space, d, bed.direction);
    s
}

/// The header comment and `[simulation]`: the DEM time step ([`time_step_s`]), gravity along
/// −z, the packing's seed and the check velocity ([`check_velocity_m_s`]).
fn write_simulation_section(s: &mut String, space: &Space, d: &Design, seed: u64) {
    let st = space.study;
    let dt = time_step_s(space, d);
    let vcheck = check_velocity_m_s(space, d);
    let _ = writeln!(
        s,
        "# Coupled-DEM verification of a design of {} (pdamp design):\n# {}\n\
         title = \"pdamp design verification\"\n\n[simulation]\nduration_s = 0.0\n\
         time_step_s = {dt:e}\ngravity_m_s2 = [0.0, 0.0, -9.81]\nseed = {seed}\n\
         check_impact_velocity_m_s = {vcheck}\n",
        st.path.display(),
        describe(space, d)
    );
}

/// `[[materials]]` of the particles (Young's modulus × `[verification] youngs_modulus_scale`)
/// and of the container (`[verification]`'s material).
fn write_material_sections(s: &mut String, m: &MaterialSpec, v: &VerificationSpec) {
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
}

/// `[contact]`: Gonthier normal law and regularized sliding friction between particles, and
/// the particle–container pair with the wall restitution.
fn write_contact_section(s: &mut String, m: &MaterialSpec) {
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
}

/// The coating of the end walls as a material (a half-space of its modulus, D Eq. 8.3–8.11)
/// and its contact pair with the particles; returns the impacted walls' material name.
fn write_coating_section(s: &mut String, c: &CoatingSpec, m: &MaterialSpec) -> &'static str {
    let _ = writeln!(
        s,
        "# end walls coated with {}: a half-space of its modulus (D Eq. 8.3–8.11)\n\
         [[materials]]\nname = \"coating\"\ndensity_kg_m3 = {}\nyoungs_modulus_pa = {:e}\n\
         poisson_ratio = {}\n\n[[contact.pairs]]\nmaterials = [\"particle\", \"coating\"]\n\
         normal = {{ law = \"gonthier\", restitution = {}, min_impact_velocity_m_s = 0.05 }}\n\
         friction = {{ law = \"regularized-sliding\", friction_coefficient = {}, \
         regularization_s_m = 1000.0 }}\n",
        c.name, c.density_kg_m3, c.youngs_modulus_pa, c.poisson_ratio, c.restitution, m.friction
    );
    "coating"
}

/// How a container's bed is dropped and excited: the particle groups (count, lower and upper
/// corner of the drop region, m), the excitation direction and the gravity of the settling
/// turn (none for a vertical bed).
struct BedLayout {
    groups: Vec<(usize, [f64; 3], [f64; 3])>,
    direction: [f64; 3],
    settle_gravity: Option<[f64; 3]>,
}

/// A horizontal container: the box walls with two-sided shelves between the layers, each
/// layer filled under gravity along −x.
fn write_horizontal_container(
    s: &mut String,
    space: &Space,
    d: &Design,
    impacted: &str,
) -> BedLayout {
    let f = &space.study.file;
    let v = &f.verification;
    let g = space.geometry(d.choice);
    let (l, w) = (g.length_m, f.damper.container_width_m);
    let mut groups: Vec<(usize, [f64; 3], [f64; 3])> = Vec::new();
    let h = match f.damper.container_height_m {
        Some(height) => height / d.particles.len() as f64,
        None => v.layer_height_m.unwrap_or(2.2 * g.radius_m),
    };
    let top = h * d.particles.len() as f64;
    box_walls(s, l, w, top, false, impacted);
    for i in 1..d.particles.len() {
        plane(
            s,
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
    BedLayout {
        groups,
        direction: [1.0, 0.0, 0.0],
        settle_gravity: Some([-9.81, 0.0, 0.0]),
    }
}

/// A vertical container: the box walls (the container length along z) and one bed falling
/// under −z.
fn write_vertical_container(
    s: &mut String,
    space: &Space,
    d: &Design,
    impacted: &str,
) -> BedLayout {
    let f = &space.study.file;
    let g = space.geometry(d.choice);
    let (l, w) = (g.length_m, f.damper.container_width_m);
    let mut groups: Vec<(usize, [f64; 3], [f64; 3])> = Vec::new();
    let depth = f.damper.container_depth_m.unwrap_or(w);
    box_walls(s, w, depth, l, true, impacted);
    groups.push((
        d.particles[0],
        [-w / 2.0, -depth / 2.0, 0.0],
        [w / 2.0, depth / 2.0, l],
    ));
    BedLayout {
        groups,
        direction: [0.0, 0.0, 1.0],
        settle_gravity: None,
    }
}

/// `[[particles]]`: `n` monodisperse particles of radius `radius_m` dropped into the box
/// `lo`…`hi`.
fn write_particle_group(s: &mut String, radius_m: f64, n: usize, lo: [f64; 3], hi: [f64; 3]) {
    let _ = writeln!(
        s,
        "[[particles]]\nmaterial = \"particle\"\ncount = {n}\nsize = {{ type = \
         \"monodisperse\", radius_m = {:e} }}\nplacement = {{ method = \"drop_down\", region = \
         {{ type = \"box\", min_m = [{:e}, {:e}, {:e}], max_m = [{:e}, \
         {:e}, {:e}] }} }}\n",
        radius_m, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
}

/// `[settle]`: the drop's settling, with the turn's gravity of a horizontal bed.
fn write_settle_section(s: &mut String, settle_gravity: Option<[f64; 3]>) {
    let _ = writeln!(
        s,
        "[settle]\nmax_duration_s = 1.0\nkinetic_energy_per_particle_j = 1e-9{}\n",
        settle_gravity.map_or(String::new(), |g| format!(
            "\ngravity_m_s2 = [{}, {}, {}]\nturn_max_duration_s = 0.5",
            g[0], g[1], g[2]
        ))
    );
}

/// `[damper]`: the container excited along `direction` at the free analysis mode's frequency
/// with the release amplitude.
fn write_damper_section(s: &mut String, space: &Space, d: &Design, direction: [f64; 3]) {
    let st = space.study;
    let k = st.free.mode;
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
}

/// The damper scenario file of container `j` (0-based) of a design's run: `damper.toml`, then
/// `damper_2.toml`, … beside the coupling scenario.
pub(super) fn damper_file(j: usize) -> String {
    if j == 0 {
        "damper.toml".into()
    } else {
        format!("damper_{}.toml", j + 1)
    }
}

/// The drop seed of container `j` of the packing with seed `seed`: the packing's own for the
/// first container, independent ones for the others (never another packing's).
pub(super) fn container_seed(seed: u64, j: usize) -> u64 {
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
    let mut table = scenario_table(space, d)?;
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
    let mut table = scenario_table(space, d)?;
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
    let every = ((1.0 / (SAMPLES_PER_PERIOD * top)) / time_step_s(space, d))
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
