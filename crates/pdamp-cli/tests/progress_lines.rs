//! Progress in logs (issue 32): without a terminal (stderr piped, as under nohup or a batch
//! system) every long command prints progress lines — elapsed time, phase, percentage, ETA —
//! at every change of phase and every `PDAMP_PROGRESS_INTERVAL_S`; `--quiet` prints none.

use std::path::PathBuf;
use std::process::{Command, Stdio};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-progress-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs pdamp with stderr piped and progress lines every 0.05 s; returns stderr.
fn stderr_of(args: &[&str], quiet: bool) -> String {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pdamp"));
    if quiet {
        c.arg("--quiet");
    }
    let o = c
        .args(args)
        .env("PDAMP_PROGRESS_INTERVAL_S", "0.05")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{args:?}: {err}");
    err
}

/// Lines `[    t s] phase  p %…` of `phase`.
fn lines<'a>(err: &'a str, phase: &str) -> Vec<&'a str> {
    err.lines()
        .filter(|l| l.starts_with('[') && l.contains(" s] ") && l.contains(phase))
        .filter(|l| l.contains(" %"))
        .collect()
}

const DAMPER: &str = r#"title = "progress"

[simulation]
duration_s = 0.0
time_step_s = 2e-6
seed = 5

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

[[bodies.walls]]
name = "container"
material = "steel"
geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }

[[particles]]
material = "steel"
count = 20
size = { type = "monodisperse", radius_m = 0.001 }
placement = { method = "random", region = { type = "box", min_m = [-0.009, -0.009, 0.001], max_m = [0.009, 0.009, 0.019] } }

[settle]
max_duration_s = 0.01

[damper]
container_body = "box"
container_mass_kg = 0.05
direction = [1.0, 0.0, 0.0]
frequency_hz = 30.0
amplitude_m = 0.002
cycles = 4
transient_cycles = 1

[fields]
frequencies_hz = [30.0, 40.0]
amplitudes_m = [0.002]
"#;

#[test]
fn run_fields_cor_and_settle_print_progress_lines_without_a_terminal() {
    let d = scratch("all");
    let scn = d.join("damper.toml");
    std::fs::write(&scn, DAMPER).unwrap();
    let s = scn.to_str().unwrap();
    // A plain run (the shaken box, 300 spheres, 50 ms): settling, then the run up to 100 %.
    let ex = Command::new(env!("CARGO_BIN_EXE_pdamp"))
        .args(["example", "--particles", "300", "--duration-s", "0.05"])
        .output()
        .unwrap();
    let plain = d.join("plain.toml");
    std::fs::write(&plain, ex.stdout).unwrap();
    let o = d.join("run");
    let err = stderr_of(
        &["run", plain.to_str().unwrap(), "--out", o.to_str().unwrap()],
        false,
    );
    assert!(!lines(&err, "settling").is_empty(), "{err}");
    let running = lines(&err, "running");
    assert!(running.len() >= 2, "{err}");
    assert!(running.last().unwrap().contains("100.0 %"), "{err}");
    assert!(err.contains("eta"), "an estimate of the time left: {err}");
    // The energy ledger as a picture, with its labels.
    let svg = std::fs::read_to_string(o.join("energy.svg")).unwrap();
    for label in [
        "energy ledger",
        "time (s)",
        "energy (J)",
        "dissipated",
        "balance residual",
    ] {
        assert!(svg.contains(label), "energy.svg lacks {label}");
    }
    assert!(std::fs::metadata(o.join("energy.png")).unwrap().len() > 1000);
    // One particles.pvd opens the particles and the container together (parts of a frame).
    let pvd = std::fs::read_to_string(o.join("particles.pvd")).unwrap();
    assert!(
        pvd.contains(r#"part="1" file="vtk/wall_0_0_000000.vtp""#),
        "{pvd}"
    );
    for f in pvd.split("file=\"").skip(1) {
        let f = &f[..f.find('"').unwrap()];
        assert!(o.join(f).is_file(), "{f} listed but missing");
    }
    // A damper point.
    let err = stderr_of(
        &["run", s, "--out", d.join("point").to_str().unwrap()],
        false,
    );
    assert!(!lines(&err, "running").is_empty(), "{err}");
    // A field: the points counted.
    let err = stderr_of(
        &["fields", s, "--out", d.join("fields").to_str().unwrap()],
        false,
    );
    assert!(
        lines(&err, "points").iter().any(|l| l.contains("2/2")),
        "{err}"
    );
    // Settling a bed.
    let err = stderr_of(
        &["settle", s, "--out", d.join("bed").to_str().unwrap()],
        false,
    );
    assert!(!lines(&err, "settl").is_empty(), "{err}");
    // Restitution: the impacts counted.
    let err = stderr_of(
        &[
            "cor",
            "--sphere-radius-m",
            "1e-3",
            "--sphere",
            "s235",
            "--wall",
            "s235",
            "--velocities-m-s",
            "0.5,1,2",
            "--model",
            "hertz",
            "--out",
            d.join("cor").to_str().unwrap(),
        ],
        false,
    );
    assert!(
        lines(&err, "impacts").iter().any(|l| l.contains("3/3")),
        "{err}"
    );
    // A powder run (the tiny cantilever): preparation and the coupled run.
    let tiny = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../pdamp-powder/tests/data/tiny_cantilever.toml");
    let err = stderr_of(
        &[
            "powder",
            "run",
            tiny.to_str().unwrap(),
            "--out",
            d.join("powder").to_str().unwrap(),
        ],
        false,
    );
    let coupled = lines(&err, "coupled run");
    assert!(!coupled.is_empty(), "{err}");
    assert!(coupled.last().unwrap().contains("100.0 %"), "{err}");
    // --quiet: no progress at all.
    let err = stderr_of(
        &["run", s, "--out", d.join("quiet").to_str().unwrap()],
        true,
    );
    assert!(lines(&err, "").is_empty(), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `pdamp completions bash|zsh|fish` prints a completion script naming the commands.
#[test]
fn completion_scripts_for_three_shells() {
    for shell in ["bash", "zsh", "fish"] {
        let o = Command::new(env!("CARGO_BIN_EXE_pdamp"))
            .args(["completions", shell])
            .output()
            .unwrap();
        assert!(o.status.success(), "{shell}");
        let text = String::from_utf8_lossy(&o.stdout);
        for cmd in ["run", "fields", "settle", "couple", "powder", "overwrite"] {
            assert!(text.contains(cmd), "{shell} script lacks {cmd}");
        }
    }
}
