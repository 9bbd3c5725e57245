//! Bad input through the CLI: non-zero exit status, a message naming file, key, line and fix,
//! and no output directory created.

use std::process::Command;

/// A JSON output file of a run.
fn read_json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

#[test]
fn bad_scenario_exits_nonzero_and_writes_nothing() {
    let dir = std::env::temp_dir().join(format!("pdamp-cli-err-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ex = pdamp()
        .args(["example", "--particles", "50", "--duration-s", "0.01"])
        .output()
        .unwrap();
    let text = String::from_utf8(ex.stdout)
        .unwrap()
        .replace("poisson_ratio = 0.3", "poisson_ratio = 0.7");
    let scn = dir.join("bad.toml");
    std::fs::write(&scn, &text).unwrap();
    let line = text[..text.find("poisson_ratio = 0.7").unwrap()]
        .matches('\n')
        .count()
        + 1;
    for cmd in ["run", "fields", "check"] {
        let out = dir.join(format!("out_{cmd}"));
        let mut c = pdamp();
        c.arg(cmd).arg(&scn);
        if cmd != "check" {
            c.arg("--out").arg(&out);
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{cmd}: {err}");
        assert!(err.contains("bad.toml"), "{cmd}: {err}");
        assert!(
            err.contains(&format!(
                "line {line}, column 1: materials[0].poisson_ratio"
            )),
            "{cmd}: {err}"
        );
        assert!(err.contains("(-1, 0.5)"), "{cmd}: {err}");
        assert!(!out.exists(), "{cmd}: no output directory on bad input");
    }
    let o = pdamp()
        .args(["run", "no_such.toml", "--out"])
        .arg(dir.join("x"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot read scenario 'no_such.toml'"));
    assert!(!dir.join("x").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn blow_up_is_diagnosed_and_outputs_are_kept() {
    let dir = std::env::temp_dir().join(format!("pdamp-cli-blowup-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ex = pdamp()
        .args(["example", "--particles", "200", "--duration-s", "0.05"])
        .output()
        .unwrap();
    // A time step near the contact time passes the (relaxed) check but cannot resolve impacts.
    let text = String::from_utf8(ex.stdout)
        .unwrap()
        .replace("max_time_step_ratio = 0.1", "max_time_step_ratio = 1.0")
        .replace("time_step_s = 0.000002", "time_step_s = 0.000035")
        .replace(
            "initial_velocity_m_s = [\n    0.0,\n    0.0,\n    0.0,\n]",
            "initial_velocity_m_s = [0.0, 0.0, -20.0]",
        );
    assert!(text.contains("time_step_s = 0.000035") && text.contains("-20.0"));
    let scn = dir.join("blowup.toml");
    std::fs::write(&scn, &text).unwrap();
    let out = dir.join("out");
    let o = pdamp()
        .args(["--threads", "1", "run"])
        .arg(&scn)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("numerical failure at t = "), "{err}");
    assert!(err.contains("particle "), "{err}");
    assert!(err.contains("time step"), "{err}");
    assert!(out.join("failure.json").exists(), "diagnosis kept");
    assert!(out.join("scenario.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn outputs_carry_version_scenario_and_seed() {
    let dir = std::env::temp_dir().join(format!("pdamp-cli-prov-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ex = pdamp()
        .args(["example", "--particles", "30", "--duration-s", "0.002"])
        .output()
        .unwrap();
    let scn = dir.join("s.toml");
    std::fs::write(&scn, ex.stdout).unwrap();
    let out = dir.join("out");
    let o = pdamp()
        .arg("run")
        .arg(&scn)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let prov = read_json(&out.join("provenance.json"));
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(prov["pdamp_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(prov["seed"], 1);
    assert_eq!(summary["seed"], 1);
    assert_eq!(prov["scenario_digest"], summary["scenario_digest"]);
    assert_eq!(prov["scenario_digest"].as_str().unwrap().len(), 16);
    assert!(
        prov["command"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a == "run")
    );
    // The canonical scenario copy reproduces the run.
    let copy = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    assert!(copy.contains("seed = 1"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Commands without a DEM scenario (structure, cor) also write `provenance.json`, with the
/// input file copied verbatim and its digest.
#[test]
fn other_commands_carry_provenance() {
    let dir = std::env::temp_dir().join(format!("pdamp-cli-prov2-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let structure = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/structure_cantilever_small.toml"
    );
    let out = dir.join("modes");
    let o = pdamp()
        .args(["structure", "modes", structure, "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let prov = read_json(&out.join("provenance.json"));
    assert_eq!(prov["pdamp_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(prov["scenario_digest"].as_str().unwrap().len(), 16);
    assert_eq!(
        std::fs::read_to_string(out.join("input.toml")).unwrap(),
        std::fs::read_to_string(structure).unwrap()
    );
    let out = dir.join("cor");
    let o = pdamp()
        .args([
            "cor",
            "--sphere-radius-m",
            "0.005",
            "--sphere",
            "s235",
            "--wall",
            "s235",
            "--velocities-m-s",
            "0.5,1",
            "--model",
            "hertz",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let prov = read_json(&out.join("provenance.json"));
    assert!(
        prov["command"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a == "cor")
    );
    assert!(!out.join("input.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pdamp run` on a damper scenario takes the excitation point from the command line.
#[test]
fn damper_point_from_the_command_line() {
    let dir = std::env::temp_dir().join(format!("pdamp-cli-point-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let ex = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    // Not a damper scenario: refused before any output.
    let o = pdamp()
        .arg("run")
        .arg(ex.join("shaken_box.toml"))
        .args(["--frequency-hz", "50"])
        .arg("--out")
        .arg(dir.join("a"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("need a scenario with a [damper] section"));
    assert!(!dir.join("a").exists());
    // Two amplitude measures at once: a usage error.
    let o = pdamp()
        .arg("run")
        .arg(ex.join("damper_cylinder_small.toml"))
        .args(["--amplitude-m", "1e-3", "--intensity", "5"])
        .arg("--out")
        .arg(dir.join("b"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Out of range: the message names the key.
    let o = pdamp()
        .arg("run")
        .arg(ex.join("damper_cylinder_small.toml"))
        .arg("--frequency-hz=-5")
        .arg("--out")
        .arg(dir.join("c"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("damper.frequency_hz must be > 0"), "{err}");
    assert!(!dir.join("c").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pdamp fields --device gpu` on a scenario the GPU kernels cannot run (a mesh container) is
/// refused before any bed is prepared or anything written, naming the wall; `pdamp check` says
/// the same in its report. Needs no GPU: the check runs on the host.
#[test]
fn gpu_fields_refuse_unsupported_scenarios_up_front() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scn = root.join("examples/damper_ch8_single_cross.toml");
    let out = std::env::temp_dir().join(format!("pdamp-cli-gpu-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = pdamp()
        .args(["fields"])
        .arg(&scn)
        .arg("--out")
        .arg(&out)
        .args(["--device", "gpu"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("triangle-mesh wall")
            && err.contains("'cross'")
            && err.contains("--device gpu"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
    let o = pdamp().arg("check").arg(&scn).output().unwrap();
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        report["gpu_backend"]
            .as_str()
            .unwrap()
            .starts_with("not supported: a triangle-mesh wall")
    );
    let o = pdamp()
        .arg("check")
        .arg(root.join("examples/damper_cylinder_small.toml"))
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        report["gpu_backend"]
            .as_str()
            .unwrap()
            .starts_with("supported")
    );
}
