//! A suite of mistaken scenarios: each must be refused before any work starts, with a message
//! that names the file, the offending key with its line and column, and the fix.

use pdamp_scenario::schema::{Scenario, ScenarioError};
use std::path::PathBuf;

/// A small valid damper scenario; every case below changes one thing in it.
const BASE: &str = r#"title = "bad-scenario base"

[simulation]
duration_s = 0.01
time_step_s = 2e-6
seed = 3

[output]
energy_interval_s = 0.001
vtk_interval_s = 0.0

[[materials]]
name = "steel"
density_kg_m3 = 7800.0
youngs_modulus_pa = 2e9
poisson_ratio = 0.3

[[materials]]
name = "pvc"
density_kg_m3 = 1400.0
youngs_modulus_pa = 2e9
poisson_ratio = 0.35

[contact]
normal = { law = "hertz-mindlin", restitution = 0.6 }
friction = { law = "mindlin", friction_coefficient = 0.3 }

[[contact.pairs]]
materials = ["steel", "pvc"]
normal = { law = "hertz-mindlin", restitution = 0.5 }
friction = { law = "mindlin", friction_coefficient = 0.4 }

[[bodies]]
name = "box"
motion = { type = "harmonic", direction = [1.0, 0.0, 0.0], amplitude_m = 0.001, frequency_hz = 30.0 }

[[bodies.walls]]
name = "container"
material = "pvc"
geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }

[[particles]]
material = "steel"
count = 20
size = { type = "monodisperse", radius_m = 0.001 }
placement = { method = "grid", region = { type = "box", min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.02] } }

[settle]
max_duration_s = 0.005

[damper]
container_body = "box"
container_mass_kg = 0.05
direction = [1.0, 0.0, 0.0]
frequency_hz = 30.0
amplitude_m = 0.001
cycles = 8
transient_cycles = 3
"#;

struct Case {
    what: &'static str,
    from: &'static str,
    to: &'static str,
    /// Substrings the message must contain (key and fix).
    expect: &'static [&'static str],
    /// A substring of the line the error must point at (None: no location expected).
    line_of: Option<&'static str>,
}

const CASES: &[Case] = &[
    Case {
        what: "TOML syntax error",
        from: "duration_s = 0.01",
        to: "duration_s = 0.01 s",
        expect: &["TOML parse error", "duration_s = 0.01 s"],
        line_of: Some("duration_s = 0.01 s"),
    },
    Case {
        what: "misspelt key",
        from: "time_step_s = 2e-6",
        to: "timestep_s = 2e-6",
        expect: &["unknown field `timestep_s`", "time_step_s"],
        line_of: Some("timestep_s"),
    },
    Case {
        what: "unit missing from the key name",
        from: "duration_s = 0.01",
        to: "duration = 0.01",
        expect: &["unknown field `duration`", "duration_s"],
        line_of: Some("duration = 0.01"),
    },
    Case {
        what: "wrong unit in the key name",
        from: "size = { type = \"monodisperse\", radius_m = 0.001 }",
        to: "size = { type = \"monodisperse\", radius_mm = 1.0 }",
        expect: &["radius_mm", "radius_m"],
        line_of: Some("radius_mm"),
    },
    Case {
        what: "missing required key",
        from: "time_step_s = 2e-6\n",
        to: "",
        expect: &["missing field `time_step_s`"],
        line_of: Some("[simulation]"),
    },
    Case {
        what: "number given as a string",
        from: "duration_s = 0.01",
        to: "duration_s = \"0.01 s\"",
        expect: &["invalid type", "duration_s"],
        line_of: Some("duration_s = \"0.01 s\""),
    },
    Case {
        what: "unknown contact law",
        from: "normal = { law = \"hertz-mindlin\", restitution = 0.6 }",
        to: "normal = { law = \"hertz-mindlen\", restitution = 0.6 }",
        expect: &["hertz-mindlen", "hertz-mindlin"],
        line_of: Some("[contact]"),
    },
    Case {
        what: "negative duration",
        from: "duration_s = 0.01",
        to: "duration_s = -0.01",
        expect: &["simulation.duration_s", ">= 0"],
        line_of: Some("duration_s = -0.01"),
    },
    Case {
        what: "zero time step",
        from: "time_step_s = 2e-6",
        to: "time_step_s = 0.0",
        expect: &["simulation.time_step_s", "must be > 0", "pdamp check"],
        line_of: Some("time_step_s = 0.0"),
    },
    Case {
        what: "time step far above the contact time",
        from: "time_step_s = 2e-6",
        to: "time_step_s = 2e-4",
        expect: &[
            "simulation.time_step_s",
            "of the shortest contact time",
            "use at most",
        ],
        line_of: Some("time_step_s = 2e-4"),
    },
    Case {
        what: "time step in milliseconds by mistake (longer than the run)",
        from: "time_step_s = 2e-6",
        to: "time_step_s = 0.02",
        expect: &["exceeds simulation.duration_s", "check the units"],
        line_of: Some("time_step_s = 0.02"),
    },
    Case {
        what: "density zero",
        from: "density_kg_m3 = 7800.0",
        to: "density_kg_m3 = 0.0",
        expect: &["materials[0].density_kg_m3", "must be > 0", "steel"],
        line_of: Some("density_kg_m3 = 0.0"),
    },
    Case {
        what: "Young's modulus in GPa (negative sign typo)",
        from: "youngs_modulus_pa = 2e9\npoisson_ratio = 0.35",
        to: "youngs_modulus_pa = -2e9\npoisson_ratio = 0.35",
        expect: &["materials[1].youngs_modulus_pa", "must be > 0", "pvc"],
        line_of: Some("youngs_modulus_pa = -2e9"),
    },
    Case {
        what: "Poisson ratio 0.5",
        from: "poisson_ratio = 0.3",
        to: "poisson_ratio = 0.5",
        expect: &["materials[0].poisson_ratio", "(-1, 0.5)"],
        line_of: Some("poisson_ratio = 0.5"),
    },
    Case {
        what: "duplicate material name",
        from: "name = \"pvc\"",
        to: "name = \"steel\"",
        expect: &[
            "materials[1].name",
            "duplicate material name 'steel'",
            "own name",
        ],
        line_of: Some("name = \"steel\"\ndensity_kg_m3 = 1400.0"),
    },
    Case {
        what: "restitution above one",
        from: "restitution = 0.6",
        to: "restitution = 1.6",
        expect: &["contact.normal.restitution", "(0, 1]", "1.6"],
        line_of: Some("restitution = 1.6"),
    },
    Case {
        what: "negative friction coefficient",
        from: "friction_coefficient = 0.4",
        to: "friction_coefficient = -0.4",
        expect: &["contact.pairs[0].friction.friction_coefficient", ">= 0"],
        line_of: Some("friction_coefficient = -0.4"),
    },
    Case {
        what: "contact pair with an undefined material",
        from: "materials = [\"steel\", \"pvc\"]",
        to: "materials = [\"steel\", \"PVC\"]",
        expect: &[
            "contact.pairs[0].materials",
            "unknown material 'PVC'",
            "steel, pvc",
        ],
        line_of: Some("materials = [\"steel\", \"PVC\"]"),
    },
    Case {
        what: "wall made of an undefined material",
        from: "material = \"pvc\"",
        to: "material = \"aluminium\"",
        expect: &[
            "bodies[0].walls[0].material",
            "unknown material 'aluminium'",
        ],
        line_of: Some("material = \"aluminium\""),
    },
    Case {
        what: "particles of an undefined material",
        from: "material = \"steel\"\ncount = 20",
        to: "material = \"steal\"\ncount = 20",
        expect: &["particles[0].material", "unknown material 'steal'"],
        line_of: Some("material = \"steal\""),
    },
    Case {
        what: "harmonic motion with zero direction",
        from: "direction = [1.0, 0.0, 0.0], amplitude_m",
        to: "direction = [0.0, 0.0, 0.0], amplitude_m",
        expect: &["bodies[0].motion.direction", "non-zero"],
        line_of: Some("direction = [0.0, 0.0, 0.0], amplitude_m"),
    },
    Case {
        what: "negative radius",
        from: "radius_m = 0.001",
        to: "radius_m = -0.001",
        expect: &["particles[0].size.radius_m", "> 0"],
        line_of: Some("radius_m = -0.001"),
    },
    Case {
        what: "both count and filling",
        from: "count = 20",
        to: "count = 20\nfilling = { max_count = 40, ratio = 0.5 }",
        expect: &["particles[0].count", "exactly one of `count` and `filling`"],
        line_of: Some("count = 20"),
    },
    Case {
        what: "filling ratio above one",
        from: "count = 20",
        to: "filling = { max_count = 40, ratio = 1.5 }",
        expect: &["particles[0].filling.ratio", "(0, 1]"],
        line_of: Some("ratio = 1.5"),
    },
    Case {
        what: "more particles than the region holds",
        from: "count = 20",
        to: "count = 2000",
        expect: &[
            "particles[0].placement.region",
            "holds only",
            "enlarge the region",
        ],
        line_of: Some("region = {"),
    },
    Case {
        what: "placement region inverted",
        from: "min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.02]",
        to: "min_m = [0.01, -0.01, 0.0], max_m = [-0.01, 0.01, 0.02]",
        expect: &["particles[0].placement.region.min_m", "below max_m"],
        line_of: Some("min_m = [0.01"),
    },
    Case {
        what: "particles placed outside the container",
        from: "min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.02]",
        to: "min_m = [0.005, -0.01, 0.0], max_m = [0.03, 0.01, 0.02]",
        expect: &[
            "particles[0].placement.region",
            "wall 'container'",
            "inside the container",
        ],
        line_of: Some("region = {"),
    },
    Case {
        what: "two groups placed on top of each other",
        from: "[settle]",
        to: "[[particles]]\nmaterial = \"pvc\"\ncount = 5\nsize = { type = \"monodisperse\", radius_m = 0.001 }\nplacement = { method = \"grid\", region = { type = \"box\", min_m = [-0.01, -0.01, 0.0], max_m = [0.01, 0.01, 0.015] } }\n\n[settle]",
        expect: &[
            "particles[1].placement",
            "initial overlap",
            "make them disjoint",
        ],
        line_of: Some("0.015"),
    },
    Case {
        what: "damper refers to a missing body",
        from: "container_body = \"box\"",
        to: "container_body = \"cylinder\"",
        expect: &["damper.container_body", "no body named 'cylinder'", "box"],
        line_of: Some("container_body = \"cylinder\""),
    },
    Case {
        what: "amplitude given twice",
        from: "amplitude_m = 0.001\ncycles",
        to: "amplitude_m = 0.001\nintensity = 2.0\ncycles",
        expect: &[
            "damper:",
            "only one of amplitude_m, acceleration_m_s2, intensity",
        ],
        line_of: Some("[damper]"),
    },
    Case {
        what: "fewer cycles than transient cycles",
        from: "cycles = 8",
        to: "cycles = 3",
        expect: &[
            "damper.cycles",
            "must exceed damper.transient_cycles",
            "cycles = 18",
        ],
        line_of: Some("cycles = 3"),
    },
    Case {
        what: "convergence tolerance zero",
        from: "transient_cycles = 3\n",
        to: "transient_cycles = 3\nconvergence = { relative_tolerance = 0.0 }\n",
        expect: &[
            "damper.convergence.relative_tolerance",
            "must be in (0, 1)",
            "e.g. 0.02",
        ],
        line_of: Some("convergence = {"),
    },
    Case {
        what: "convergence with an unknown key",
        from: "transient_cycles = 3\n",
        to: "transient_cycles = 3\nconvergence = { relative_tolerance = 0.02, window = 2 }\n",
        expect: &["unknown field `window`", "window_cycles"],
        line_of: Some("convergence = {"),
    },
    Case {
        what: "convergence window not shorter than the minimum",
        from: "transient_cycles = 3\n",
        to: "transient_cycles = 3\nconvergence = { relative_tolerance = 0.02, min_evaluated_cycles = 3, window_cycles = 3 }\n",
        expect: &[
            "damper.convergence.min_evaluated_cycles (3) must exceed",
            "window_cycles (3)",
            "min_evaluated_cycles = 5",
        ],
        line_of: Some("convergence = {"),
    },
    Case {
        what: "convergence minimum beyond the maximum cycles",
        from: "transient_cycles = 3\n",
        to: "transient_cycles = 3\nconvergence = { relative_tolerance = 0.02, min_evaluated_cycles = 6 }\n",
        expect: &[
            "damper.convergence.min_evaluated_cycles (6)",
            "exceeds damper.cycles (8)",
            "at least 9",
        ],
        line_of: Some("convergence = {"),
    },
    Case {
        what: "fields grid without a damper",
        from: "[damper]\ncontainer_body = \"box\"\ncontainer_mass_kg = 0.05\ndirection = [1.0, 0.0, 0.0]\nfrequency_hz = 30.0\namplitude_m = 0.001\ncycles = 8\ntransient_cycles = 3\n",
        to: "[fields]\nfrequencies_hz = [20.0, 40.0]\nintensities = [1.0, 2.0]\n",
        expect: &["fields: a [damper] section is needed"],
        line_of: Some("[fields]"),
    },
    Case {
        what: "log range through zero",
        from: "[damper]",
        to: "[fields]\nfrequencies_hz = { from = 0.0, to = 100.0, count = 5, spacing = \"log\" }\nintensities = [1.0, 2.0]\n\n[damper]",
        expect: &["fields.frequencies_hz", "from > 0"],
        line_of: Some("frequencies_hz = {"),
    },
    Case {
        what: "energy output interval zero",
        from: "energy_interval_s = 0.001",
        to: "energy_interval_s = 0.0",
        expect: &["output.energy_interval_s", "> 0"],
        line_of: Some("energy_interval_s = 0.0"),
    },
    Case {
        what: "negative settling time",
        from: "max_duration_s = 0.005",
        to: "max_duration_s = -0.005",
        expect: &["settle.max_duration_s", ">= 0"],
        line_of: Some("max_duration_s = -0.005"),
    },
    Case {
        what: "two models for one material pair",
        from: "[[bodies]]",
        to: "[[contact.pairs]]\nmaterials = [\"pvc\", \"steel\"]\nnormal = { law = \"hertz-mindlin\", restitution = 0.5 }\nfriction = { law = \"mindlin\", friction_coefficient = 0.4 }\n\n[[bodies]]",
        expect: &[
            "contact.pairs[1].materials",
            "one [[contact.pairs]] entry per material pair",
        ],
        line_of: Some("materials = [\"pvc\", \"steel\"]"),
    },
    Case {
        what: "missing STL mesh file",
        from: "geometry = { type = \"box_inside\", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }",
        to: "geometry = { type = \"stl\", path = \"no_such_file.stl\", flip_normals = true }",
        expect: &["bodies[0].walls[0].geometry.path", "no_such_file.stl"],
        line_of: Some("no_such_file.stl"),
    },
    Case {
        what: "body without walls",
        from: "[[bodies.walls]]\nname = \"container\"\nmaterial = \"pvc\"\ngeometry = { type = \"box_inside\", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }\n",
        to: "walls = []\n",
        expect: &["bodies[0].walls", "has no walls"],
        line_of: Some("walls = []"),
    },
];

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-bad-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn line_of(text: &str, needle: &str) -> usize {
    let off = text
        .find(needle)
        .unwrap_or_else(|| panic!("marker {needle:?} not in the scenario"));
    text[..off].matches('\n').count() + 1
}

#[test]
fn base_scenario_is_valid() {
    let dir = scratch();
    let p = dir.join("base.toml");
    std::fs::write(&p, BASE).unwrap();
    let (_, world) = Scenario::load_and_build(&p).unwrap();
    assert_eq!(world.particles.len(), 20);
}

#[test]
fn every_mistake_gets_a_located_message_with_a_fix() {
    assert!(CASES.len() >= 20, "at least 20 distinct mistakes");
    let dir = scratch();
    let mut failures = Vec::new();
    for (k, c) in CASES.iter().enumerate() {
        assert!(
            BASE.contains(c.from),
            "case '{}': pattern not in base",
            c.what
        );
        let text = BASE.replacen(c.from, c.to, 1);
        let path = dir.join(format!("case_{k:02}.toml"));
        std::fs::write(&path, &text).unwrap();
        let err = match Scenario::load_and_build(&path) {
            Ok(_) => {
                failures.push(format!("case '{}': accepted", c.what));
                continue;
            }
            Err(e) => e,
        };
        let msg = err.to_string();
        eprintln!("[{}] {msg}\n", c.what);
        if !msg.contains(&format!("case_{k:02}.toml")) {
            failures.push(format!("case '{}': file not named: {msg}", c.what));
        }
        for e in c.expect {
            if !msg.contains(e) {
                failures.push(format!("case '{}': '{e}' missing in: {msg}", c.what));
            }
        }
        if let Some(marker) = c.line_of {
            let want = line_of(&text, marker);
            let got = match &err {
                ScenarioError::Invalid { line_col, .. } => line_col.map(|l| l.0),
                ScenarioError::Parse { message, .. } => message
                    .split("line ")
                    .nth(1)
                    .and_then(|r| r.split(|c: char| !c.is_ascii_digit()).next())
                    .and_then(|n| n.parse().ok()),
                ScenarioError::Read { .. } => None,
            };
            if got != Some(want) {
                failures.push(format!(
                    "case '{}': expected line {want}, got {got:?}: {msg}",
                    c.what
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn restitution_table_csv_is_read_relative_to_the_scenario() {
    let dir = scratch().join("table");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("cor.csv"),
        "velocity_m_s,restitution,contact_time_s,max_force_n\n0.1,0.9,1e-4,1\n1.0,0.6,1e-4,5\n",
    )
    .unwrap();
    let text = BASE.replace(
        "normal = { law = \"hertz-mindlin\", restitution = 0.5 }",
        "normal = { law = \"gonthier-table\", restitution_table_csv = \"cor.csv\" }",
    );
    let p = dir.join("s.toml");
    std::fs::write(&p, &text).unwrap();
    let (sc, _) = Scenario::load_and_build(&p).unwrap();
    let law = &sc.contact.pairs[0].model.normal;
    assert!((law.restitution_at(0.1) - 0.9).abs() < 1e-15);
    assert!((law.restitution_at(0.55) - 0.75).abs() < 1e-12);
    assert!(
        sc.to_toml().contains("impact_velocities_m_s"),
        "outputs are self-contained"
    );

    // A broken table: the message names the key, its line, the file and the row.
    std::fs::write(
        dir.join("cor.csv"),
        "velocity_m_s,restitution\n1.0,0.6\n0.1,0.9\n",
    )
    .unwrap();
    let err = Scenario::load_and_build(&p).unwrap_err().to_string();
    let line = line_of(&text, "restitution_table_csv");
    assert!(
        err.contains(&format!("line {line}"))
            && err.contains("contact.pairs[0].normal.restitution_table_csv")
            && err.contains("cor.csv")
            && err.contains("row 3"),
        "{err}"
    );
    std::fs::remove_file(dir.join("cor.csv")).unwrap();
    let err = Scenario::load_and_build(&p).unwrap_err().to_string();
    assert!(err.contains("cannot read"), "{err}");
}
