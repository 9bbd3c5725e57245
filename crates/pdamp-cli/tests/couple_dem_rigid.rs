//! `pdamp couple` with a rigid-body full-DEM container (`dofs = "translation+rotation"`):
//! examples/couple_ch8_dem_rigid_small.toml shortened to 0.1 s runs, writes its outputs and
//! decays; a wrong key combination is refused with a message naming the key.

use std::path::{Path, PathBuf};
use std::process::Command;

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-rigid-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The example with absolute paths to its structure and damper files, `edit` applied.
fn write_scenario(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let ex = examples();
    let text = std::fs::read_to_string(ex.join("couple_ch8_dem_rigid_small.toml"))
        .unwrap()
        .replace(
            "structure_file = \"structure_ch8_beam1_end.toml\"",
            &format!(
                "structure_file = {:?}",
                ex.join("structure_ch8_beam1_end.toml")
            ),
        )
        .replace(
            "scenario = \"couple_ch8_cube40_damper.toml\"",
            &format!("scenario = {:?}", ex.join("couple_ch8_cube40_damper.toml")),
        );
    assert!(text.contains("examples/structure_ch8_beam1_end.toml"));
    assert!(text.contains("examples/couple_ch8_cube40_damper.toml"));
    assert!(text.contains("dofs = \"translation+rotation\""));
    let p = dir.join("couple.toml");
    std::fs::write(&p, edit(text)).unwrap();
    p
}

fn couple(scn: &Path, out: &Path) -> std::process::Output {
    pdamp()
        .args(["--threads", "1", "couple"])
        .arg(scn)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn couple_dem_translation_rotation_example_runs_and_decays() {
    let dir = scratch("run");
    let scn = write_scenario(&dir, |t| t.replace("duration_s = 0.3", "duration_s = 0.1"));
    assert!(
        std::fs::read_to_string(&scn)
            .unwrap()
            .contains("duration_s = 0.1")
    );
    let out = dir.join("out");
    let o = couple(&scn, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["decay.csv", "damping.csv", "summary.json"] {
        assert!(out.join(f).exists(), "{f} written");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["approach"], "1 (full DEM)");
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let x0 = num(&s["initial_amplitude_m"]);
    let x_end = num(&s["final_peak_amplitude_m"]);
    let z_max = num(&s["max_damping_ratio"]);
    let z1 = num(&s["first_cycle"]["damping_ratio"]);
    let f1 = num(&s["first_cycle"]["frequency_hz"]);
    eprintln!("X0 {x0}, X_end {x_end}, ζ first {z1}, ζ max {z_max}, f {f1} Hz");
    assert_eq!(x0, 5e-4);
    // 0.1 s of mode 1 (54.2 Hz bare): about 5 cycles, damped by the bed but not stopped.
    assert!(num(&s["cycles"]) >= 3.0, "{s}");
    assert!(x_end.is_finite() && x_end > 0.0 && x_end < x0, "{s}");
    // The bare beam has ζ1 = 3.2e-4; the bed adds damping, a damping ratio of 0.2 would be
    // unphysical for 165 g of spheres on a 6.7 kg beam.
    assert!(z1.is_finite() && z1 > 3.2e-4 && z1 < 0.2, "{s}");
    assert!(z_max.is_finite() && z_max >= z1 && z_max < 0.2, "{s}");
    // The moving container mass lowers the frequency slightly below the bare 54.2 Hz.
    assert!(f1 > 45.0 && f1 < 54.3, "{s}");
    // The decay history is finite throughout.
    let decay = std::fs::read_to_string(out.join("decay.csv")).unwrap();
    let rows: Vec<&str> = decay.lines().skip(1).collect();
    assert!(rows.len() > 100);
    assert!(rows.iter().all(|l| {
        l.split(',')
            .all(|v| v.parse::<f64>().is_ok_and(f64::is_finite))
    }));
    // The bed in ParaView (issue 32): frames every output.vtk_interval_s = 0.05 s of the damper
    // scenario, particles and container together, read back by VTK where it is installed.
    let pvd = std::fs::read_to_string(out.join("particles.pvd")).unwrap();
    for t in ["0", "0.05", "0.1"] {
        assert!(
            pvd.contains(&format!(
                "timestep=\"{t}\" group=\"\" part=\"0\" file=\"vtk/particles_"
            )),
            "frame at {t} s: {pvd}"
        );
    }
    assert_eq!(pvd.matches("<DataSet").count() % 3, 0, "{pvd}");
    for f in pvd.split("file=\"").skip(1) {
        let f = &f[..f.find('"').unwrap()];
        assert!(out.join(f).is_file(), "{f} listed but missing");
    }
    if let Ok(py) = std::env::var("PDAMP_TEST_PYTHON") {
        let o = Command::new(py)
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/check_vtk.py"))
            .arg(out.join("particles.pvd"))
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let read: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let frames = read[0]["frames"].as_array().unwrap();
        assert_eq!(frames.len(), 3);
        let n = frames[0]["parts"][0]["points"].as_u64().unwrap();
        assert!(n > 0);
        for f in frames {
            let parts = f["parts"].as_array().unwrap();
            assert_eq!(parts[0]["points"].as_u64(), Some(n), "{f}");
            assert!(
                parts[1..].iter().all(|w| w["polys"].as_u64() > Some(0)),
                "{f}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn couple_dem_rotation_points_need_translation_rotation() {
    let dir = scratch("bad");
    let scn = write_scenario(&dir, |t| {
        t.replace("dofs = \"translation+rotation\"", "dofs = \"translation\"")
    });
    let out = dir.join("out");
    let o = couple(&scn, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("dampers[0].rotation_points: only with dofs = \"translation+rotation\""),
        "{err}"
    );
    assert!(!out.exists(), "no output directory on bad input");
    let _ = std::fs::remove_dir_all(&dir);
}
