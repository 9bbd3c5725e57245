//! One convention for every command (issue 32): `--out DIR` is required wherever a command
//! writes files; the input file is copied verbatim as `DIR/input.toml` (DEM scenario commands
//! add `scenario.toml`, the scenario as run with every default); results on stdout are one
//! pretty-printed JSON object; negative numbers are values (`--opt -1`), refused by the
//! option's own range check, not mistaken for an option.

use std::path::PathBuf;
use std::process::{Command, Output};

fn pdamp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-conv-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

#[test]
fn negative_numbers_reach_the_range_checks() {
    let base = [
        "impact",
        "--radius-m",
        "1e-3",
        "--youngs-modulus-pa",
        "2e11",
        "--poisson-ratio",
        "0.3",
        "--density-kg-m3",
        "7800",
    ];
    for v in [["--velocity-m-s", "-1"], ["--velocity-m-s", "-1e-3"]] {
        let o = pdamp(&[&base[..], &v[..]].concat());
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("--velocity-m-s must lie in (0, 1000] m/s, got -"),
            "{}",
            stderr(&o)
        );
    }
    // A comma list that starts with a negative number.
    let o = pdamp(&[
        "cor",
        "--sphere-radius-m",
        "1e-3",
        "--sphere",
        "s235",
        "--wall",
        "s235",
        "--velocities-m-s",
        "-1,2",
        "--out",
        "/nonexistent/never",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--velocities-m-s must all lie in (0, 1000] m/s"));
}

#[test]
fn every_writing_command_needs_out() {
    for args in [
        &[
            "cor",
            "--sphere-radius-m",
            "1e-3",
            "--sphere",
            "s235",
            "--wall",
            "s235",
            "--velocities-m-s",
            "1",
        ][..],
        &["run", "builtin:shaken-box"][..],
        &["structure", "modes", "x.toml"][..],
        &["couple", "x.toml"][..],
        &["powder", "run", "x.toml"][..],
        &["fields", "x.toml"][..],
        &["settle", "x.toml"][..],
    ] {
        let o = pdamp(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("--out <OUT>"),
            "{args:?}: {}",
            stderr(&o)
        );
    }
}

#[test]
fn input_copy_scenario_as_run_and_pretty_json() {
    let d = scratch("input");
    let ex = pdamp(&["example", "--particles", "100", "--duration-s", "0.002"]);
    let text = String::from_utf8(ex.stdout).unwrap();
    // The user's file, comments and all.
    let mine = format!("# my own comment\n{text}");
    let sc = d.join("my scenario.toml");
    std::fs::write(&sc, &mine).unwrap();
    for cmd in ["run", "settle"] {
        let out = d.join(cmd);
        let o = pdamp(&[cmd, sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{cmd}: {}", stderr(&o));
        assert_eq!(
            std::fs::read_to_string(out.join("input.toml")).unwrap(),
            mine,
            "{cmd}: input.toml is the file as given"
        );
        let as_run = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
        assert!(
            as_run.contains("vtk_format = \"binary\""),
            "{cmd}: defaults filled in"
        );
        // stdout: one pretty-printed JSON object.
        let stdout = String::from_utf8(o.stdout).unwrap();
        assert!(stdout.starts_with("{\n  \""), "{cmd}: {stdout}");
        serde_json::from_str::<serde_json::Value>(&stdout).unwrap();
        let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
        assert!(manifest.contains("\"input.toml\""), "{manifest}");
    }
    // A failed run that wrote nothing but the copy of its input leaves no directory.
    let bad = d.join("bad.toml");
    std::fs::write(
        &bad,
        mine.replace("[simulation]", "[simulation]\nbogus_key = 1"),
    )
    .unwrap();
    let out = d.join("bad_out");
    let o = pdamp(&["run", bad.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.exists());
    // bench too prints pretty JSON (scripts take the whole stdout).
    let o = pdamp(&["bench", "--particles", "100", "--steps", "5"]);
    let stdout = String::from_utf8(o.stdout).unwrap();
    assert!(stdout.starts_with("{\n  \""), "{stdout}");
    let _ = std::fs::remove_dir_all(&d);
}
