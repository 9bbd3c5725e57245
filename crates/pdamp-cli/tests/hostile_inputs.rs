//! The hostile-input corpus (issue 31): bad numbers in every section, broken meshes, beds and
//! tables, absurd sizes and command-line options, output directories that are files, links or
//! inputs. Every case runs the real `pdamp` binary under a memory limit and a time limit and
//! must be refused cleanly: exit status 1 (2 for options the parser refuses), a message that
//! names the key or option, no panic, no abort, no hang, and no output directory left behind
//! where the case says so.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small valid shaken-box scenario (plain run); cases replace one line of it.
const PLAIN: &str = r#"title = "hostile base"

[simulation]
duration_s = 0.002
time_step_s = 2e-6
gravity_m_s2 = [0.0, 0.0, -9.81]
seed = 1

[output]
energy_interval_s = 0.001
vtk_interval_s = 0.0

[[materials]]
name = "steel"
density_kg_m3 = 7800.0
youngs_modulus_pa = 2e9
poisson_ratio = 0.3

[contact]
normal = { law = "hertz-mindlin", restitution = 0.6 }
friction = { law = "mindlin", friction_coefficient = 0.3 }

[[bodies]]
name = "box"
motion = { type = "harmonic", direction = [1.0, 0.0, 0.0], amplitude_m = 0.001, frequency_hz = 30.0, phase_rad = 0.0 }

[[bodies.walls]]
name = "container"
material = "steel"
geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }

[[particles]]
material = "steel"
count = 20
size = { type = "monodisperse", radius_m = 0.001 }
placement = { method = "grid", region = { type = "box", min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.02] } }

[settle]
max_duration_s = 0.001
"#;

/// [`PLAIN`] as a damper point.
fn damper() -> String {
    PLAIN.to_string()
        + r#"
[damper]
container_body = "box"
container_mass_kg = 0.05
direction = [1.0, 0.0, 0.0]
frequency_hz = 30.0
amplitude_m = 0.001
cycles = 3
transient_cycles = 1
"#
}

/// [`PLAIN`] with the container replaced by the STL file `box.stl`.
fn with_stl() -> String {
    PLAIN.replace(
        r#"geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }"#,
        r#"geometry = { type = "stl", path = "box.stl" }"#,
    )
}

/// ASCII STL of the 20 mm box container (normals into the cavity) centred at z = 0.01 m;
/// `reverse` flips the vertex order of facet `k`, `drop` leaves facet `k` out, `twice`
/// repeats it.
fn box_stl(reverse: Option<usize>, drop: Option<usize>, twice: Option<usize>) -> String {
    let (lo, hi) = ([-0.011, -0.011, -0.001], [0.011, 0.011, 0.021]);
    let c = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    // Quads with outward orientation (counter-clockwise seen from outside), split in two.
    let quads = [
        [0, 2, 3, 1], // z-
        [4, 5, 7, 6], // z+
        [0, 1, 5, 4], // y-
        [2, 6, 7, 3], // y+
        [0, 4, 6, 2], // x-
        [1, 3, 7, 5], // x+
    ];
    let mut tris = Vec::new();
    for q in quads {
        // Inward normals for a container: reverse the outward order.
        tris.push([q[0], q[2], q[1]]);
        tris.push([q[0], q[3], q[2]]);
    }
    let mut s = String::from("solid box\n");
    for (k, t) in tris.iter().enumerate() {
        if drop == Some(k) {
            continue;
        }
        let t = if reverse == Some(k) {
            [t[0], t[2], t[1]]
        } else {
            *t
        };
        let times = if twice == Some(k) { 2 } else { 1 };
        for _ in 0..times {
            s.push_str(" facet normal 0 0 0\n  outer loop\n");
            for v in t {
                let p = c(v);
                s.push_str(&format!("   vertex {} {} {}\n", p[0], p[1], p[2]));
            }
            s.push_str("  endloop\n endfacet\n");
        }
    }
    s.push_str("endsolid box\n");
    s
}

/// One hostile input.
struct Case {
    name: String,
    /// Arguments; `{dir}` is the case's scratch folder.
    args: Vec<String>,
    /// Files written into the scratch folder first.
    files: Vec<(String, String)>,
    /// Expected exit status.
    code: i32,
    /// Substrings the error message must contain.
    expect: Vec<String>,
    /// `--out` folder that must not exist afterwards (refused before any output).
    no_out: bool,
}

fn case(name: &str, args: &[&str], files: Vec<(&str, String)>, code: i32, expect: &[&str]) -> Case {
    Case {
        name: name.to_string(),
        args: args.iter().map(|s| s.to_string()).collect(),
        files: files.into_iter().map(|(n, t)| (n.to_string(), t)).collect(),
        code,
        expect: expect.iter().map(|s| s.to_string()).collect(),
        no_out: false,
    }
}

/// `check` and `run` of a scenario whose line `from` is replaced by `to`: refused with a
/// message containing `expect`, and `run` leaves no output directory.
fn scenario_cases(out: &mut Vec<Case>, base: &str, tag: &str, from: &str, to: &str, expect: &str) {
    assert!(base.contains(from), "{tag}: base lacks {from}");
    let text = base.replacen(from, to, 1);
    for cmd in ["check", "run"] {
        let mut args = vec![cmd, "{dir}/s.toml"];
        if cmd == "run" {
            args.extend(["--out", "{dir}/out"]);
        }
        let mut c = case(
            &format!("{cmd}: {tag}"),
            &args,
            vec![("s.toml", text.clone())],
            1,
            &[expect],
        );
        c.no_out = cmd == "run";
        out.push(c);
    }
}

fn corpus() -> Vec<Case> {
    let mut v = Vec::new();
    let p = PLAIN;
    let d = damper();
    // Numbers of every section: non-finite, negative, zero, absurd.
    for (tag, from, to, expect) in [
        (
            "time step NaN",
            "time_step_s = 2e-6",
            "time_step_s = nan",
            "time_step_s",
        ),
        (
            "time step inf",
            "time_step_s = 2e-6",
            "time_step_s = inf",
            "time_step_s",
        ),
        (
            "time step negative",
            "time_step_s = 2e-6",
            "time_step_s = -2e-6",
            "time_step_s",
        ),
        (
            "time step zero",
            "time_step_s = 2e-6",
            "time_step_s = 0.0",
            "time_step_s",
        ),
        (
            "time step above contact time",
            "time_step_s = 2e-6",
            "time_step_s = 1e-3",
            "time_step_s",
        ),
        (
            "duration NaN",
            "duration_s = 0.002",
            "duration_s = nan",
            "duration_s",
        ),
        (
            "duration negative",
            "duration_s = 0.002",
            "duration_s = -1.0",
            "duration_s",
        ),
        (
            "duration inf",
            "duration_s = 0.002",
            "duration_s = inf",
            "duration_s",
        ),
        (
            "duration of centuries",
            "duration_s = 0.002",
            "duration_s = 1e9",
            "energy_interval_s",
        ),
        (
            "gravity NaN",
            "gravity_m_s2 = [0.0, 0.0, -9.81]",
            "gravity_m_s2 = [0.0, 0.0, nan]",
            "gravity_m_s2",
        ),
        (
            "gravity with four components",
            "gravity_m_s2 = [0.0, 0.0, -9.81]",
            "gravity_m_s2 = [0.0, 0.0, -9.81, 1.0]",
            "gravity_m_s2",
        ),
        (
            "gravity with two components",
            "gravity_m_s2 = [0.0, 0.0, -9.81]",
            "gravity_m_s2 = [0.0, -9.81]",
            "gravity_m_s2",
        ),
        (
            "gravity as a string",
            "gravity_m_s2 = [0.0, 0.0, -9.81]",
            "gravity_m_s2 = \"down\"",
            "gravity_m_s2",
        ),
        (
            "energy interval NaN",
            "energy_interval_s = 0.001",
            "energy_interval_s = nan",
            "energy_interval_s",
        ),
        (
            "energy interval tiny",
            "energy_interval_s = 0.001",
            "energy_interval_s = 1e-15",
            "energy_interval_s",
        ),
        (
            "vtk interval one step",
            "vtk_interval_s = 0.0",
            "vtk_interval_s = 2e-9",
            "vtk_interval_s",
        ),
        (
            "vtk interval negative",
            "vtk_interval_s = 0.0",
            "vtk_interval_s = -1.0",
            "vtk_interval_s",
        ),
        (
            "density NaN",
            "density_kg_m3 = 7800.0",
            "density_kg_m3 = nan",
            "density_kg_m3",
        ),
        (
            "density zero",
            "density_kg_m3 = 7800.0",
            "density_kg_m3 = 0.0",
            "density_kg_m3",
        ),
        (
            "density negative",
            "density_kg_m3 = 7800.0",
            "density_kg_m3 = -7800.0",
            "density_kg_m3",
        ),
        (
            "Young's modulus inf",
            "youngs_modulus_pa = 2e9",
            "youngs_modulus_pa = inf",
            "youngs_modulus_pa",
        ),
        (
            "Young's modulus zero",
            "youngs_modulus_pa = 2e9",
            "youngs_modulus_pa = 0.0",
            "youngs_modulus_pa",
        ),
        (
            "Poisson 0.7",
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.7",
            "poisson_ratio",
        ),
        (
            "Poisson NaN",
            "poisson_ratio = 0.3",
            "poisson_ratio = nan",
            "poisson_ratio",
        ),
        (
            "restitution 1.5",
            "restitution = 0.6",
            "restitution = 1.5",
            "restitution",
        ),
        (
            "restitution NaN",
            "restitution = 0.6",
            "restitution = nan",
            "restitution",
        ),
        (
            "friction negative",
            "friction_coefficient = 0.3",
            "friction_coefficient = -0.3",
            "friction_coefficient",
        ),
        (
            "friction NaN",
            "friction_coefficient = 0.3",
            "friction_coefficient = nan",
            "friction_coefficient",
        ),
        (
            "motion amplitude NaN",
            "amplitude_m = 0.001, frequency_hz = 30.0",
            "amplitude_m = nan, frequency_hz = 30.0",
            "amplitude_m",
        ),
        (
            "motion amplitude 10 m",
            "amplitude_m = 0.001, frequency_hz = 30.0",
            "amplitude_m = 10.0, frequency_hz = 30.0",
            "amplitude_m",
        ),
        (
            "motion frequency inf",
            "frequency_hz = 30.0, phase_rad",
            "frequency_hz = inf, phase_rad",
            "frequency_hz",
        ),
        (
            "motion frequency 1e9",
            "frequency_hz = 30.0, phase_rad",
            "frequency_hz = 1e9, phase_rad",
            "frequency_hz",
        ),
        (
            "motion phase NaN",
            "phase_rad = 0.0",
            "phase_rad = nan",
            "phase_rad",
        ),
        (
            "motion direction zero",
            "direction = [1.0, 0.0, 0.0], amplitude_m",
            "direction = [0.0, 0.0, 0.0], amplitude_m",
            "direction",
        ),
        (
            "box extents NaN",
            "half_extents_m = [0.01, 0.01, 0.01]",
            "half_extents_m = [nan, 0.01, 0.01]",
            "half_extents_m",
        ),
        (
            "box extents negative",
            "half_extents_m = [0.01, 0.01, 0.01]",
            "half_extents_m = [-0.01, 0.01, 0.01]",
            "half_extents_m",
        ),
        (
            "box extents zero",
            "half_extents_m = [0.01, 0.01, 0.01]",
            "half_extents_m = [0.0, 0.01, 0.01]",
            "half_extents_m",
        ),
        (
            "box centre inf",
            "center_m = [0.0, 0.0, 0.01]",
            "center_m = [0.0, 0.0, inf]",
            "center_m",
        ),
        ("particle count zero", "count = 20", "count = 0", "count"),
        (
            "a trillion particles",
            "count = 20",
            "count = 1000000000000",
            "particles",
        ),
        (
            "radius NaN",
            "radius_m = 0.001",
            "radius_m = nan",
            "radius_m",
        ),
        (
            "radius zero",
            "radius_m = 0.001",
            "radius_m = 0.0",
            "radius_m",
        ),
        (
            "radius negative",
            "radius_m = 0.001",
            "radius_m = -0.001",
            "radius_m",
        ),
        (
            "radius larger than the box",
            "radius_m = 0.001",
            "radius_m = 0.5",
            "the radius",
        ),
        (
            "region NaN",
            "min_m = [-0.01, -0.01, 0.0]",
            "min_m = [nan, -0.01, 0.0]",
            "min_m",
        ),
        (
            "region inverted",
            "max_m = [0.01, 0.01, 0.02]",
            "max_m = [-0.02, 0.01, 0.02]",
            "region",
        ),
        (
            "settle NaN",
            "max_duration_s = 0.001",
            "max_duration_s = nan",
            "max_duration_s",
        ),
        (
            "settle negative",
            "max_duration_s = 0.001",
            "max_duration_s = -1.0",
            "max_duration_s",
        ),
        (
            "unknown key",
            "seed = 1",
            "seed = 1\nduration = 3.0",
            "duration",
        ),
        ("wrong type", "seed = 1", "seed = \"one\"", "seed"),
        ("TOML syntax", "seed = 1", "seed = = 1", "line"),
        (
            "unknown material",
            "material = \"steel\"\ncount",
            "material = \"gold\"\ncount",
            "gold",
        ),
        (
            "unknown law",
            "law = \"hertz-mindlin\"",
            "law = \"hooke\"",
            "hooke",
        ),
    ] {
        scenario_cases(&mut v, p, tag, from, to, expect);
    }
    // Integrator settings (Gear).
    for (tag, gear, expect) in [
        (
            "Gear safety factor NaN",
            "safety_factor = nan",
            "safety_factor",
        ),
        (
            "Gear safety factor 2",
            "safety_factor = 2.0",
            "safety_factor",
        ),
        (
            "Gear safety factor negative",
            "safety_factor = -0.9",
            "safety_factor",
        ),
        (
            "Gear no corrections",
            "max_corrections = 0",
            "max_corrections",
        ),
        (
            "Gear a billion corrections",
            "max_corrections = 1000000000",
            "max_corrections",
        ),
        ("Gear dt_min zero", "dt_min_s = 0.0", "dt_min_s"),
        ("Gear dt_min above the step", "dt_min_s = 1.0", "dt_min_s"),
        ("Gear dt_max below the step", "dt_max_s = 1e-12", "dt_max_s"),
        ("Gear tolerance NaN", "tolerance_abs = nan", "tolerance_abs"),
        (
            "Gear relative tolerance 2",
            "tolerance_rel = 2.0",
            "tolerance_rel",
        ),
    ] {
        let defaults = [
            ("dt_min_s", "1e-16"),
            ("tolerance_abs", "1e-6"),
            ("tolerance_rel", "1e-6"),
            ("max_corrections", "10"),
            ("safety_factor", "0.9"),
        ];
        let mut keys: Vec<String> = defaults
            .iter()
            .filter(|(k, _)| !gear.starts_with(k))
            .map(|(k, x)| format!("{k} = {x}"))
            .collect();
        keys.push(gear.to_string());
        let to = format!(
            "seed = 1\nintegrator = {{ scheme = \"gear\", {} }}",
            keys.join(", ")
        );
        scenario_cases(&mut v, p, tag, "seed = 1", &to, expect);
    }
    // The damper section.
    for (tag, from, to, expect) in [
        (
            "container mass 1e300",
            "container_mass_kg = 0.05",
            "container_mass_kg = 1e300",
            "container_mass_kg",
        ),
        (
            "container mass NaN",
            "container_mass_kg = 0.05",
            "container_mass_kg = nan",
            "container_mass_kg",
        ),
        (
            "damper frequency 1e9",
            "frequency_hz = 30.0\namplitude_m",
            "frequency_hz = 1e9\namplitude_m",
            "frequency_hz",
        ),
        (
            "damper amplitude 5 m",
            "amplitude_m = 0.001\ncycles",
            "amplitude_m = 5.0\ncycles",
            "amplitude_m",
        ),
        (
            "damper amplitude NaN",
            "amplitude_m = 0.001\ncycles",
            "amplitude_m = nan\ncycles",
            "amplitude_m",
        ),
        (
            "a billion cycles",
            "cycles = 3\n",
            "cycles = 1000000000\n",
            "cycles",
        ),
        (
            "transient longer than the run",
            "transient_cycles = 1",
            "transient_cycles = 5",
            "transient_cycles",
        ),
        (
            "no packings",
            "transient_cycles = 1",
            "transient_cycles = 1\npackings = 0",
            "packings",
        ),
        (
            "a million VTK frames per cycle",
            "transient_cycles = 1",
            "transient_cycles = 1\nmotion_output = { vtk_frames_per_cycle = 1000000 }",
            "vtk_frames_per_cycle",
        ),
        (
            "trajectory of a particle that does not exist",
            "transient_cycles = 1",
            "transient_cycles = 1\nmotion_output = { trajectory_particles = [99999] }",
            "trajectory_particles",
        ),
        (
            "a million phases",
            "transient_cycles = 1",
            "transient_cycles = 1\nmotion_output = { phases_per_cycle = 1000000 }",
            "phases_per_cycle",
        ),
        (
            "no field cells",
            "transient_cycles = 1",
            "transient_cycles = 1\nmotion_output = { field_cells = 0 }",
            "field_cells",
        ),
        (
            "direction NaN",
            "direction = [1.0, 0.0, 0.0]\nfrequency_hz",
            "direction = [nan, 0.0, 0.0]\nfrequency_hz",
            "direction",
        ),
        (
            "unknown container",
            "container_body = \"box\"",
            "container_body = \"cup\"",
            "container_body",
        ),
    ] {
        scenario_cases(&mut v, &d, tag, from, to, expect);
    }
    // Meshes.
    let stl = with_stl();
    for (tag, mesh, expect) in [
        (
            "STL with one reversed facet",
            box_stl(Some(3), None, None),
            "oriented against",
        ),
        (
            "STL with a repeated facet",
            box_stl(None, None, Some(5)),
            "repeats triangle",
        ),
        ("empty STL", String::new(), "STL"),
        ("STL of garbage", "\u{1}\u{2}garbage".repeat(40), "STL"),
        (
            "STL with a NaN vertex",
            box_stl(None, None, None).replacen("vertex -0.011", "vertex nan", 1),
            "finite",
        ),
    ] {
        for cmd in ["check", "run"] {
            let mut args = vec![cmd, "{dir}/s.toml"];
            if cmd == "run" {
                args.extend(["--out", "{dir}/out"]);
            }
            let mut c = case(
                &format!("{cmd}: {tag}"),
                &args,
                vec![("s.toml", stl.clone()), ("box.stl", mesh.clone())],
                1,
                &[expect],
            );
            c.no_out = cmd == "run";
            v.push(c);
        }
    }
    // An open mesh (one bottom facet missing) lets the bed fall out: the run stops, naming the
    // particle and the open mesh, instead of ending with exit 0.
    let mut c = case(
        "run: STL container with a hole",
        &["run", "{dir}/s.toml", "--out", "{dir}/out"],
        vec![
            (
                "s.toml",
                stl.replace("duration_s = 0.002", "duration_s = 0.08")
                    .replace("energy_interval_s = 0.001", "energy_interval_s = 0.01"),
            ),
            ("box.stl", box_stl(None, Some(0), None)),
        ],
        1,
        &["has left its container", "not closed", "failure.json"],
    );
    c.no_out = false;
    v.push(c);
    v.push(case(
        "check: missing STL",
        &["check", "{dir}/s.toml"],
        vec![("s.toml", stl.clone())],
        1,
        &["box.stl"],
    ));
    // Bed files.
    let bed = |name: &str, count: usize| {
        PLAIN.replace("count = 20", &format!("count = {count}")).replace(
            r#"placement = { method = "grid", region = { type = "box", min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.02] } }"#,
            &format!(r#"placement = {{ method = "file", path = "{name}" }}"#),
        )
    };
    for (tag, file, count, content, expect) in [
        (
            "bed CSV with NaN",
            "bed.csv",
            1,
            "x_m,y_m,z_m,radius_m\nnan,0,0.01,0.001\n".to_string(),
            "bed.csv",
        ),
        (
            "bed CSV of garbage",
            "bed.csv",
            1,
            "\u{0}\u{0}\u{ff}".to_string(),
            "bed.csv",
        ),
        (
            "bed CSV outside the box",
            "bed.csv",
            1,
            "x_m,y_m,z_m,radius_m\n5.0,0,0.01,0.001\n".to_string(),
            "outside",
        ),
        (
            "bed CSV overlapping",
            "bed.csv",
            2,
            "x_m,y_m,z_m,radius_m\n0,0,0.01,0.001\n0,0,0.01,0.001\n".to_string(),
            "overlap",
        ),
        (
            "bed CSV count mismatch",
            "bed.csv",
            20,
            "x_m,y_m,z_m,radius_m\n0,0,0.01,0.001\n".to_string(),
            "count = 1",
        ),
        (
            "LAMMPS data announcing 1e11 atoms",
            "bed.data",
            1,
            "LAMMPS data\n\n100000000000 atoms\n1 atom types\n".to_string(),
            "bed.data",
        ),
        (
            "native bed of garbage",
            "bed.pdbed",
            1,
            "not a bed".to_string(),
            "bed.pdbed",
        ),
    ] {
        v.push(case(
            &format!("check: {tag}"),
            &["check", "{dir}/s.toml"],
            vec![("s.toml", bed(file, count)), (file, content)],
            1,
            &[expect],
        ));
    }
    v.push(case(
        "check: missing bed file",
        &["check", "{dir}/s.toml"],
        vec![("s.toml", bed("none.csv", 20))],
        1,
        &["none.csv"],
    ));
    // Command-line options.
    let ok = vec![("s.toml", PLAIN.to_string())];
    let run = |extra: &[&str]| {
        let mut a = vec!["run", "{dir}/s.toml", "--out", "{dir}/out"];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    for (tag, args, code, expect) in [
        (
            "checkpoint interval inf",
            run(&["--checkpoint-interval-s", "inf"]),
            1,
            "--checkpoint-interval-s",
        ),
        (
            "checkpoint interval NaN",
            run(&["--checkpoint-interval-s", "nan"]),
            1,
            "--checkpoint-interval-s",
        ),
        (
            "checkpoint interval negative",
            run(&["--checkpoint-interval-s=-5"]),
            1,
            "--checkpoint-interval-s",
        ),
        (
            "resume and overwrite",
            run(&["--resume", "--overwrite"]),
            2,
            "--overwrite",
        ),
        (
            "threads zero",
            [vec!["--threads".to_string(), "0".into()], run(&[])].concat(),
            1,
            "--threads",
        ),
        (
            "a million threads",
            [vec!["--threads".to_string(), "1000000".into()], run(&[])].concat(),
            1,
            "--threads",
        ),
        (
            "threads not a number",
            [vec!["--threads".to_string(), "many".into()], run(&[])].concat(),
            2,
            "--threads",
        ),
        (
            "damper frequency on a plain run",
            run(&["--frequency-hz", "20"]),
            1,
            "[damper]",
        ),
        (
            "missing scenario",
            vec![
                "run".into(),
                "{dir}/none.toml".into(),
                "--out".into(),
                "{dir}/out".into(),
            ],
            1,
            "none.toml",
        ),
    ] {
        let mut c = case(&format!("run: {tag}"), &[], ok.clone(), code, &[expect]);
        c.args = args;
        c.no_out = true;
        v.push(c);
    }
    for (tag, args, code, expect) in [
        (
            "bench no particles",
            vec!["bench", "--particles", "0", "--steps", "1"],
            1,
            "--particles",
        ),
        (
            "bench ten billion particles",
            vec!["bench", "--particles", "10000000000", "--steps", "1"],
            1,
            "particles",
        ),
        (
            "bench no steps",
            vec!["bench", "--particles", "100", "--steps", "0"],
            1,
            "--steps",
        ),
        (
            "bench batch without GPU",
            vec!["bench", "--batch", "4"],
            1,
            "--batch",
        ),
        (
            "impact radius NaN",
            vec![
                "impact",
                "--radius-m",
                "nan",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1",
            ],
            1,
            "--radius-m",
        ),
        (
            "impact radius 1e6 m",
            vec![
                "impact",
                "--radius-m",
                "1e6",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1",
            ],
            1,
            "--radius-m",
        ),
        (
            "impact velocity negative",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s=-1",
            ],
            1,
            "--velocity-m-s",
        ),
        (
            "impact velocity 1e300",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1e300",
            ],
            1,
            "--velocity-m-s",
        ),
        (
            "impact restitution 2",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1",
                "--law",
                "gonthier",
                "--restitution",
                "2",
            ],
            1,
            "--restitution",
        ),
        (
            "impact stiffness NaN",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1",
                "--law",
                "linear",
                "--stiffness-n-m",
                "nan",
            ],
            1,
            "--stiffness-n-m",
        ),
        (
            "impact modulus inf",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "inf",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "7800",
                "--velocity-m-s",
                "1",
            ],
            1,
            "youngs_modulus_pa",
        ),
        (
            "impact density zero",
            vec![
                "impact",
                "--radius-m",
                "1e-3",
                "--youngs-modulus-pa",
                "2e11",
                "--poisson-ratio",
                "0.3",
                "--density-kg-m3",
                "0",
                "--velocity-m-s",
                "1",
            ],
            1,
            "density_kg_m3",
        ),
        (
            "cor repeat zero",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1",
                "--model",
                "hertz",
                "--repeat",
                "0",
                "--out",
                "{dir}/out",
            ],
            1,
            "--repeat",
        ),
        (
            "cor repeat a billion",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1",
                "--model",
                "hertz",
                "--repeat",
                "1000000000",
                "--out",
                "{dir}/out",
            ],
            1,
            "--repeat",
        ),
        (
            "cor velocity NaN",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1,nan",
                "--model",
                "hertz",
                "--out",
                "{dir}/out",
            ],
            1,
            "--velocities-m-s",
        ),
        (
            "cor velocity 1e300",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1e300",
                "--model",
                "hertz",
                "--out",
                "{dir}/out",
            ],
            1,
            "--velocities-m-s",
        ),
        (
            "cor radius 1 km",
            vec![
                "cor",
                "--sphere-radius-m",
                "1000",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1",
                "--model",
                "hertz",
                "--out",
                "{dir}/out",
            ],
            1,
            "--sphere-radius-m",
        ),
        (
            "cor unknown material",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "unobtainium",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1",
                "--model",
                "hertz",
                "--out",
                "{dir}/out",
            ],
            1,
            "unobtainium",
        ),
        (
            "cor Thornton factor NaN",
            vec![
                "cor",
                "--sphere-radius-m",
                "1e-3",
                "--sphere",
                "s235",
                "--wall",
                "s235",
                "--velocities-m-s",
                "1",
                "--model",
                "thornton",
                "--thornton-pressure-factor",
                "nan",
                "--out",
                "{dir}/out",
            ],
            1,
            "--thornton-pressure-factor",
        ),
        (
            "example with no particles",
            vec!["example", "--particles", "0"],
            1,
            "--particles",
        ),
        (
            "example with a NaN duration",
            vec!["example", "--duration-s", "nan"],
            1,
            "--duration-s",
        ),
    ] {
        let mut c = case(tag, &args, Vec::new(), code, &[expect]);
        c.no_out = true;
        v.push(c);
    }
    v.push(case(
        "bench --settled over a file of the user",
        &[
            "bench",
            "--particles",
            "100",
            "--steps",
            "1",
            "--settled",
            "{dir}/notes.txt",
        ],
        vec![("notes.txt", "my notes".to_string())],
        1,
        &["not a settled bed"],
    ));
    // Output directories that are files, hold links or are the input's folder.
    v.push(case(
        "run: --out is a file",
        &["run", "{dir}/s.toml", "--out", "{dir}/s.toml"],
        ok.clone(),
        1,
        &["not a directory"],
    ));
    v.push(case(
        "run: scenario inside --out would be overwritten",
        &["run", "{dir}/scenario.toml", "--out", "{dir}"],
        vec![("scenario.toml", PLAIN.to_string())],
        1,
        &["would overwrite the input"],
    ));
    v.push(case(
        "run: --out holds results of another run",
        &["run", "{dir}/s.toml", "--out", "{dir}/out"],
        vec![
            ("s.toml", PLAIN.to_string()),
            ("out/summary.json", "{}".to_string()),
        ],
        1,
        &["already holds the results", "--overwrite"],
    ));
    v.push(case(
        "run: --resume over results without a checkpoint",
        &["run", "{dir}/s.toml", "--out", "{dir}/out", "--resume"],
        vec![
            ("s.toml", PLAIN.to_string()),
            ("out/energy.csv", "t\n".to_string()),
        ],
        1,
        &["nothing to resume"],
    ));
    v.push(case(
        "run: --resume with a damaged checkpoint",
        &["run", "{dir}/s.toml", "--out", "{dir}/out", "--resume"],
        vec![
            ("s.toml", PLAIN.to_string()),
            ("out/checkpoint.bin", "PDAMPCKP garbage".to_string()),
        ],
        1,
        &["checkpoint"],
    ));
    v.push(case(
        "run: --resume of a damper point with another scenario's checkpoint",
        &["run", "{dir}/s.toml", "--out", "{dir}/out", "--resume"],
        vec![
            ("s.toml", damper()),
            (
                "out/checkpoint.bin",
                "PDAMPCK\u{0}0123456789abcdef0123456789".to_string(),
            ),
        ],
        1,
        &["checkpoint"],
    ));
    v.push(case(
        "fields: a scenario without [fields]",
        &["fields", "{dir}/s.toml", "--out", "{dir}/out"],
        vec![("s.toml", damper())],
        1,
        &["[fields]"],
    ));
    v.push(case(
        "fields: a grid of a billion points",
        &["fields", "{dir}/s.toml", "--out", "{dir}/out"],
        vec![(
            "s.toml",
            damper()
                + "\n[fields]\nfrequencies_hz = { from = 0.01, to = 0.02, count = 1000 }\namplitudes_m = { from = 1e-4, to = 1e-3, count = 1000 }\n",
        )],
        1,
        &["1000000 points", "memory"],
    ));
    v.push(case(
        "fields: an axis of 1e11 values (found by the fuzzer: allocation abort)",
        &["check", "{dir}/s.toml"],
        vec![(
            "s.toml",
            damper()
                + "\n[fields]\nfrequencies_hz = { from = 10.0, to = 50.0, count = 100000000000 }\namplitudes_m = [1e-3]\n",
        )],
        1,
        &["fields.frequencies_hz.count"],
    ));
    // A VTK frame per time step of a damper point (50 steps per cycle at 10 kHz).
    scenario_cases(
        &mut v,
        &damper().replace(
            "frequency_hz = 30.0\namplitude_m",
            "frequency_hz = 10000.0\namplitude_m",
        ),
        "a VTK frame per step",
        "transient_cycles = 1",
        "transient_cycles = 1\nmotion_output = { vtk_frames_per_cycle = 999 }",
        "vtk_frames_per_cycle",
    );
    structure_and_powder_cases(&mut v);
    v
}

/// A small beam structure (`pdamp structure modes`).
const BEAM: &str = r#"[structure]
n_modes = 3
min_frequency_hz = 1.0

[structure.beam]
length_m = 1.8
elements = 30
youngs_modulus_pa = 68e9
poisson_ratio = 0.34
density_kg_m3 = 2700.0
area_m2 = 1138e-6
second_moment_m4 = 166000e-12
timoshenko = true
planar = true
masses = [{ position_m = 0.04, mass_kg = 1.0 }]

[[structure.points]]
name = "damper"
position_m = 0.9
"#;

/// The structure and DEM–FEM commands: bad numbers, meshes and matrices, sizes.
fn structure_and_powder_cases(v: &mut Vec<Case>) {
    let modes = ["structure", "modes", "{dir}/s.toml", "--out", "{dir}/out"];
    for (tag, from, to, expect) in [
        (
            "beam length NaN",
            "length_m = 1.8",
            "length_m = nan",
            "length_m",
        ),
        (
            "beam length negative",
            "length_m = 1.8",
            "length_m = -1.8",
            "length_m",
        ),
        ("no elements", "elements = 30", "elements = 0", "elements"),
        (
            "a billion elements",
            "elements = 30",
            "elements = 1000000000",
            "elements",
        ),
        (
            "Young's modulus inf",
            "youngs_modulus_pa = 68e9",
            "youngs_modulus_pa = inf",
            "youngs_modulus_pa",
        ),
        (
            "density zero",
            "density_kg_m3 = 2700.0",
            "density_kg_m3 = 0.0",
            "density_kg_m3",
        ),
        ("area NaN", "area_m2 = 1138e-6", "area_m2 = nan", "area_m2"),
        (
            "point outside the beam",
            "position_m = 0.9",
            "position_m = 7.0",
            "position_m",
        ),
        (
            "mass outside the beam",
            "position_m = 0.04, mass_kg",
            "position_m = -1.0, mass_kg",
            "position_m",
        ),
        (
            "negative point mass",
            "mass_kg = 1.0",
            "mass_kg = -1.0",
            "mass_kg",
        ),
        ("no modes", "n_modes = 3", "n_modes = 0", "n_modes"),
        (
            "a million modes",
            "n_modes = 3",
            "n_modes = 1000000",
            "n_modes",
        ),
    ] {
        assert!(BEAM.contains(from), "{tag}");
        let mut c = case(
            &format!("structure modes: {tag}"),
            &modes,
            vec![("s.toml", BEAM.replacen(from, to, 1))],
            1,
            &[expect],
        );
        c.no_out = true;
        v.push(c);
    }
    // Matrix Market structures.
    let mm = |k: &str, m: &str| {
        vec![
            (
                "s.toml",
                "[structure]\nn_modes = 1\nmin_frequency_hz = 0.0\n\n[structure.matrix_market]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\ndof_map = \"dofs.txt\"\n\n[[structure.points]]\nname = \"tip\"\nnode = 2\ndof = \"UY\"\n"
                    .to_string(),
            ),
            ("dofs.txt", "1 1 UY\n2 2 UY\n".to_string()),
            ("K.mtx", k.to_string()),
            ("M.mtx", m.to_string()),
        ]
    };
    let head = "%%MatrixMarket matrix coordinate real symmetric\n";
    let good_m = format!("{head}2 2 2\n1 1 1.0\n2 2 1.0\n");
    for (tag, k, m, expect) in [
        (
            "stiffness with NaN",
            format!("{head}2 2 2\n1 1 nan\n2 2 1.0\n"),
            good_m.clone(),
            "K.mtx",
        ),
        (
            "stiffness announcing 1e11 rows",
            format!("{head}100000000000 100000000000 1\n1 1 1.0\n"),
            good_m.clone(),
            "K.mtx",
        ),
        (
            "stiffness with a duplicate entry",
            format!("{head}2 2 3\n1 1 1.0\n1 1 1.0\n2 2 1.0\n"),
            good_m.clone(),
            "K.mtx",
        ),
        (
            "mass not positive definite",
            format!("{head}2 2 2\n1 1 1.0\n2 2 1.0\n"),
            format!("{head}2 2 2\n1 1 -1.0\n2 2 1.0\n"),
            "M.mtx",
        ),
        (
            "stiffness of garbage",
            "\u{0}\u{1}garbage".to_string(),
            good_m.clone(),
            "K.mtx",
        ),
        (
            "missing mass file",
            format!("{head}2 2 2\n1 1 1.0\n2 2 1.0\n"),
            String::new(),
            "M.mtx",
        ),
    ] {
        let mut files = mm(&k, &m);
        if m.is_empty() {
            files.pop();
        }
        let mut c = case(
            &format!("structure modes: {tag}"),
            &modes,
            files,
            1,
            &[expect],
        );
        c.no_out = true;
        v.push(c);
    }
    // DEM–FEM (powder) scenarios.
    let tiny = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../pdamp-powder/tests/data/tiny_cantilever.toml"),
    )
    .unwrap();
    let prun = ["powder", "run", "{dir}/s.toml", "--out", "{dir}/out"];
    for (tag, from, to, expect) in [
        (
            "pressure 1e300",
            "pressure_pa = 1e5",
            "pressure_pa = 1e300",
            "pressure_pa",
        ),
        (
            "pressure NaN",
            "pressure_pa = 1e5",
            "pressure_pa = nan",
            "pressure_pa",
        ),
        ("D50 NaN", "d50_m = 3e-3", "d50_m = nan", "d50_m"),
        (
            "D50 of a micrometre (1e11 particles)",
            "d50_m = 3e-3",
            "d50_m = 1e-7",
            "d50_m",
        ),
        ("sigma 50", "sigma = 0.2707", "sigma = 50.0", "sigma"),
        (
            "stiffness inf",
            "normal_stiffness_n_m = 5642.0",
            "normal_stiffness_n_m = inf",
            "normal_stiffness_n_m",
        ),
        (
            "restitution 2",
            "restitution = 0.4",
            "restitution = 2.0",
            "restitution",
        ),
        (
            "packing density 0.9",
            "packing_density = 0.45",
            "packing_density = 0.9",
            "packing_density",
        ),
        (
            "time step NaN",
            "time_step_s = 5e-6",
            "time_step_s = nan",
            "time_step_s",
        ),
        (
            "time step 1 s",
            "time_step_s = 5e-6",
            "time_step_s = 1.0",
            "time_step_s",
        ),
        (
            "duration of a year",
            "duration_s = 1e-3",
            "duration_s = 3e7",
            "duration_s",
        ),
        (
            "wall element zero",
            "wall_element_m = 0.001",
            "wall_element_m = 0.0",
            "wall_element_m",
        ),
        (
            "beam modulus NaN",
            "youngs_modulus_pa = 175e9",
            "youngs_modulus_pa = nan",
            "youngs_modulus_pa",
        ),
    ] {
        assert!(tiny.contains(from), "{tag}");
        let mut c = case(
            &format!("powder run: {tag}"),
            &prun,
            vec![("s.toml", tiny.replacen(from, to, 1))],
            1,
            &[expect],
        );
        c.no_out = true;
        v.push(c);
    }
    let mut c = case(
        "powder run: checkpoint interval inf",
        &[
            "powder",
            "run",
            "{dir}/s.toml",
            "--out",
            "{dir}/out",
            "--checkpoint-interval-s",
            "inf",
        ],
        vec![("s.toml", tiny.clone())],
        1,
        &["--checkpoint-interval-s"],
    );
    c.no_out = true;
    v.push(c);
    let mut c = case(
        "powder study: NaN value",
        &[
            "powder",
            "study",
            "{dir}/s.toml",
            "--parameter",
            "friction",
            "--values",
            "0.1,nan",
            "--out",
            "{dir}/out",
        ],
        vec![("s.toml", tiny.clone())],
        1,
        &["NaN"],
    );
    c.no_out = true;
    v.push(c);
    v.push(case(
        "powder run: --out holds results of another run",
        &["powder", "run", "{dir}/s.toml", "--out", "{dir}/out"],
        vec![("s.toml", tiny), ("out/summary.json", "{}".to_string())],
        1,
        &["already holds the results"],
    ));
}

/// Runs one case under a 2 GB address-space limit and a time limit; returns the problems.
fn run_case(c: &Case, root: &Path, k: usize) -> Vec<String> {
    let dir = root.join(format!("c{k:03}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in &c.files {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    let args: Vec<String> = c
        .args
        .iter()
        .map(|a| a.replace("{dir}", &dir.to_string_lossy()))
        .collect();
    let quoted: Vec<String> = args.iter().map(|a| format!("'{a}'")).collect();
    // PDAMP_HOSTILE_BIN runs the corpus against another build (e.g. an older release, to count
    // the defects it had).
    let bin = std::env::var("PDAMP_HOSTILE_BIN")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_pdamp").to_string());
    let script = format!("ulimit -v 4000000; exec '{bin}' {}", quoted.join(" "));
    let start = Instant::now();
    let mut child = Command::new("sh")
        .args(["-c", &script])
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let limit = Duration::from_secs(60);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut err = String::new();
    use std::io::Read;
    let _ = child.stderr.take().unwrap().read_to_string(&mut err);
    let mut problems = Vec::new();
    let Some(status) = status else {
        return vec![format!("{}: hangs (> {limit:?})", c.name)];
    };
    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
        problems.push(format!("{}: panics: {err}", c.name));
    }
    if status.code() != Some(c.code) {
        problems.push(format!(
            "{}: exit status {:?} (expected {}): {err}",
            c.name,
            status.code(),
            c.code
        ));
    }
    for e in &c.expect {
        if !err.contains(e.as_str()) {
            problems.push(format!("{}: message lacks '{e}': {err}", c.name));
        }
    }
    if c.no_out && dir.join("out").exists() && !c.files.iter().any(|(n, _)| n.starts_with("out/")) {
        problems.push(format!("{}: left an output directory", c.name));
    }
    problems
}

#[test]
fn every_hostile_input_is_refused_cleanly() {
    let cases = corpus();
    assert!(cases.len() >= 100, "{} cases", cases.len());
    let root: PathBuf = std::env::temp_dir().join(format!("pdamp-hostile-{}", std::process::id()));
    let start = Instant::now();
    let problems: Vec<String> = cases
        .iter()
        .enumerate()
        .flat_map(|(k, c)| run_case(c, &root, k))
        .collect();
    eprintln!(
        "{} hostile inputs in {:.1} s, {} problems",
        cases.len(),
        start.elapsed().as_secs_f64(),
        problems.len()
    );
    let _ = std::fs::remove_dir_all(&root);
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
}
