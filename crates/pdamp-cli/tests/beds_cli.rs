//! `pdamp settle` and the bed warnings of `pdamp check` from the command line.

use std::path::PathBuf;
use std::process::Command;

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// The small cylinder is filled with its axis vertical and turned: `summary.json` gives the
/// clearance h of the bed as filled (D Eq. 8.1: container length − bed length along the axis)
/// beside the turned bed's statistics, and the bed files are written.
#[test]
fn settle_writes_the_bed_and_its_fill_clearance() {
    let out = std::env::temp_dir().join(format!("pdamp-cli-settle-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = pdamp()
        .args(["--threads", "2", "settle"])
        .arg(examples().join("damper_cylinder_small.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let fill = &s["bed_at_fill"];
    let h = fill["clearance_m"].as_f64().unwrap();
    let span = fill["bed_span_along_direction_m"].as_array().unwrap();
    let length = fill["container_length_along_direction_m"].as_f64().unwrap();
    assert!((length - 0.028).abs() < 1e-6, "inner length {length}");
    let bed_length = span[1].as_f64().unwrap() - span[0].as_f64().unwrap();
    assert!((h - (length - bed_length)).abs() < 1e-12);
    // 300 spheres of 2.5 mm in a 16 mm cylinder: a random packing leaves a few mm.
    assert!(h > 1e-3 && h < 1e-2, "h = {h}");
    // The volumetric h of D Eq. 8.1 (to the mean surface), larger than the gap to the highest
    // sphere by less than two diameters (a rough poured surface).
    let h_surface = fill["clearance_to_surface_m"].as_f64().unwrap();
    let height = fill["bed_height_m"].as_f64().unwrap();
    assert!((h_surface - (length - height)).abs() < 1e-12);
    assert!(
        h_surface > h && h_surface - h < 5e-3,
        "h to the surface {h_surface}, to the highest sphere {h}"
    );
    let bulk = s["bed"]["packing_fraction_bulk"].as_f64().unwrap();
    assert!((0.55..0.66).contains(&bulk), "bulk packing fraction {bulk}");
    for f in [
        "bed.pdbed",
        "bed.csv",
        "bed.data",
        "bed.vtp",
        "provenance.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// `pdamp check` warns about a crystal damper bed and a single packing; bad `--packings` is
/// refused naming the key.
#[test]
fn check_warns_about_crystal_beds() {
    let o = pdamp()
        .arg("check")
        .arg(examples().join("damper_shaken_box_tight.toml"))
        .output()
        .unwrap();
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("starts as a crystal") && err.contains("drop_down"),
        "{err}"
    );
    let o = pdamp()
        .arg("check")
        .arg(examples().join("damper_shaken_box.toml"))
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("crystal"));
    let out = std::env::temp_dir().join(format!("pdamp-cli-packings-{}", std::process::id()));
    let o = pdamp()
        .arg("run")
        .arg(examples().join("damper_cylinder_small.toml"))
        .args(["--packings", "0", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("damper.packings must be in 1..=1000"));
    assert!(!out.exists());
}

/// `pdamp check` on a file of another command names that command instead of a TOML key error.
#[test]
fn check_names_the_command_of_other_scenario_files() {
    for (file, command) in [
        ("couple_ch5_forced_u2mm.toml", "pdamp couple"),
        ("powder_cantilever_small.toml", "pdamp powder run"),
        ("structure_ch5_beam.toml", "pdamp structure modes"),
        ("study_ch5_layers.toml", "pdamp structure optimize-layers"),
    ] {
        let o = pdamp()
            .arg("check")
            .arg(examples().join(file))
            .output()
            .unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("is not a DEM scenario") && err.contains(command),
            "{file}: {err}"
        );
    }
}
