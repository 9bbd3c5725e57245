//! ParaView output read back by VTK itself (issue 32): `scripts/check_vtk.py` opens every file
//! of a run's `particles.pvd` with VTK's XML reader (the library ParaView is built on) and
//! reports points, cells and arrays. The files are compressed binary (appended raw, zlib).
//!
//! Needs a Python with the `vtk` package: `scripts/test.sh` makes one (`target/test-venv`) and
//! sets `PDAMP_TEST_PYTHON` and `PDAMP_REQUIRE_VTK_TESTS=1`; a bare `cargo test` without them
//! skips these tests with a note.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-paraview-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The Python that has VTK, or `None` (test skipped) when none is configured.
fn python() -> Option<String> {
    match std::env::var("PDAMP_TEST_PYTHON") {
        Ok(p) if !p.is_empty() => Some(p),
        _ => {
            assert!(
                std::env::var("PDAMP_REQUIRE_VTK_TESTS").as_deref() != Ok("1"),
                "PDAMP_REQUIRE_VTK_TESTS=1 but PDAMP_TEST_PYTHON is not set"
            );
            eprintln!(
                "skipped: set PDAMP_TEST_PYTHON to a Python with `vtk` (scripts/test.sh does)"
            );
            None
        }
    }
}

/// What VTK read from `files` (JSON of scripts/check_vtk.py).
fn vtk_read(py: &str, files: &[&Path]) -> Vec<Value> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/check_vtk.py");
    let o = Command::new(py).arg(script).args(files).output().unwrap();
    assert!(
        o.status.success(),
        "VTK failed: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice::<Vec<Value>>(&o.stdout).unwrap()
}

fn pdamp(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_pdamp"))
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A plain run's `particles.pvd` opens particles and container together, every frame, in
/// binary compressed form, with the values the run had.
#[test]
fn plain_run_pvd_opens_particles_and_walls_in_vtk() {
    let Some(py) = python() else { return };
    let d = scratch("plain");
    let ex = Command::new(env!("CARGO_BIN_EXE_pdamp"))
        .args(["example", "--particles", "300", "--duration-s", "0.05"])
        .output()
        .unwrap();
    let sc = d.join("plain.toml");
    std::fs::write(&sc, ex.stdout).unwrap();
    let out = d.join("run");
    pdamp(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let read = vtk_read(&py, &[&out.join("particles.pvd")]);
    let frames = read[0]["frames"].as_array().unwrap();
    // Snapshots every 50 ms over 50 ms: t = 0 and t = 0.05 s.
    let times: Vec<f64> = frames
        .iter()
        .map(|f| f["time_s"].as_f64().unwrap())
        .collect();
    assert_eq!(times, vec![0.0, 0.05]);
    for f in frames {
        let parts = f["parts"].as_array().unwrap();
        assert_eq!(parts.len(), 2, "particles and the box: {f}");
        let (p, w) = (&parts[0], &parts[1]);
        assert_eq!(p["part"], 0);
        assert_eq!(p["points"], 300);
        assert_eq!(p["verts"], 300);
        assert_eq!(p["compressed"], true);
        let r = &p["point_data"]["radius_m"]["range"];
        assert_eq!(r[0].as_f64(), Some(1e-3));
        assert_eq!(r[1].as_f64(), Some(1e-3));
        assert_eq!(p["point_data"]["velocity_m_s"]["components"], 3);
        for name in ["angular_velocity_rad_s", "speed_m_s", "material", "id"] {
            assert!(p["point_data"].get(name).is_some(), "{name} missing: {p}");
        }
        let ids = &p["point_data"]["id"]["range"];
        assert_eq!((ids[0].as_f64(), ids[1].as_f64()), (Some(0.0), Some(299.0)));
        // The box: 12 triangles enclosing every particle.
        assert_eq!(w["part"], 1);
        assert_eq!(w["polys"], 12);
        assert_eq!(w["compressed"], true);
        let (pb, wb) = (
            p["bounds"].as_array().unwrap(),
            w["bounds"].as_array().unwrap(),
        );
        for k in 0..3 {
            let (lo, hi) = (wb[2 * k].as_f64().unwrap(), wb[2 * k + 1].as_f64().unwrap());
            assert!(pb[2 * k].as_f64().unwrap() > lo && pb[2 * k + 1].as_f64().unwrap() < hi);
        }
    }
    // `pdamp settle`'s bed.vtp as well.
    let bed = d.join("bed");
    pdamp(&[
        "settle",
        sc.to_str().unwrap(),
        "--out",
        bed.to_str().unwrap(),
    ]);
    let read = vtk_read(&py, &[&bed.join("bed.vtp")]);
    assert_eq!(read[0]["points"], 300);
    assert_eq!(read[0]["compressed"], true);
    let _ = std::fs::remove_dir_all(&d);
}

/// `pdamp powder run` writes the powder and the deformed structure as frames of one
/// `particles.pvd`; VTK reads both, the structure with its displacement field.
#[test]
fn powder_run_pvd_has_particles_and_deformed_structure() {
    let Some(py) = python() else { return };
    let d = scratch("powder");
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../pdamp-powder/tests/data/tiny_cantilever.toml");
    let text = std::fs::read_to_string(src).unwrap();
    assert!(text.contains("output_interval_s = 1e-5"));
    let text = text.replace(
        "output_interval_s = 1e-5",
        "output_interval_s = 1e-5\nvtk_interval_s = 5e-4",
    );
    let sc = d.join("powder.toml");
    std::fs::write(&sc, text).unwrap();
    let out = d.join("out");
    pdamp(&[
        "powder",
        "run",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let particles = summary["result"]["particles"].as_u64().unwrap();
    assert!(particles > 0, "{summary}");
    let read = vtk_read(&py, &[&out.join("particles.pvd")]);
    let frames = read[0]["frames"].as_array().unwrap();
    let times: Vec<f64> = frames
        .iter()
        .map(|f| f["time_s"].as_f64().unwrap())
        .collect();
    assert_eq!(times, vec![0.0, 5e-4, 1e-3]);
    for f in frames {
        let parts = f["parts"].as_array().unwrap();
        assert_eq!(parts.len(), 2, "{f}");
        assert_eq!(parts[0]["points"].as_u64(), Some(particles));
        assert!(parts[0]["point_data"].get("radius_m").is_some());
        assert!(parts[1]["polys"].as_u64().unwrap() > 0);
        assert_eq!(parts[1]["point_data"]["displacement_m"]["components"], 3);
    }
    // At rest at t = 0; loaded later (the tip is pushed in the rise phase).
    let u = |k: usize| {
        frames[k]["parts"][1]["point_data"]["displacement_m"]["range"][1]
            .as_f64()
            .unwrap()
    };
    assert_eq!(u(0), 0.0);
    assert!(u(2) > 0.0, "{}", frames[2]);
    let _ = std::fs::remove_dir_all(&d);
}

/// A damper point's animation of the last cycle (`particles.pvd`): the bed and the container
/// as the parts of every frame, read by VTK.
#[test]
fn damper_point_animation_has_bed_and_container() {
    let Some(py) = python() else { return };
    let d = scratch("damper");
    let sc =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/damper_cylinder_small.toml");
    let out = d.join("point");
    pdamp(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let read = vtk_read(&py, &[&out.join("particles.pvd")]);
    let frames = read[0]["frames"].as_array().unwrap();
    assert!(frames.len() >= 8, "{} frames", frames.len());
    for f in frames {
        let parts = f["parts"].as_array().unwrap();
        assert_eq!(parts.len(), 2, "{f}");
        assert_eq!(parts[0]["points"], 300);
        assert_eq!(parts[0]["compressed"], true);
        assert!(parts[1]["polys"].as_u64().unwrap() > 0, "{f}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
