//! The two newcomer examples of docs/examples.md ("New examples"): a damper in an STL container
//! (`examples/stl_cylinder_damper.toml` with `examples/stl_cylinder_r8_l24_mm.stl`) and a
//! polydisperse bed (`examples/polydisperse_box_damper.toml`). For each, `pdamp check` succeeds
//! without a crystal warning and its JSON reports the particles (and, for the polydisperse bed,
//! radii inside the file's range that span it), and a reduced damper point (3 cycles, 1 dropped,
//! a copy of the scenario in a temporary folder) writes `summary.json` whose energy ledger
//! closes against the complex power to the tolerance stated in docs/examples.md:
//! |energy_closure_relative| < 1e-3 (measured: 5e-5 and 1.2e-4). Each command runs on one
//! thread (the two tests run side by side); both together take ≈ 15 s on 2 cores.

use pdamp_dem::generate::SizeDistribution;
use pdamp_dem::math::Vec3;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Closure of the energy balance of a damper point that the examples must meet.
const CLOSURE_TOLERANCE: f64 = 1e-3;

fn pdamp() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_pdamp"));
    c.args(["--threads", "1"]);
    c
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-newcomer-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `pdamp check FILE`: succeeds, prints JSON on stdout, no crystal warning on stderr.
fn check(file: &Path) -> serde_json::Value {
    let o = pdamp().arg("check").arg(file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "check {}: {err}", file.display());
    assert!(!err.contains("crystal"), "crystal warning: {err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let warnings = v["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .all(|w| !w.as_str().unwrap().contains("crystal")),
        "{warnings:?}"
    );
    v
}

/// Copies `file` into `dir` with `[damper] cycles = 3, transient_cycles = 1` (the lines
/// `from_cycles`/`from_transient` replaced; each must be in the file exactly once).
fn reduced_copy(file: &Path, dir: &Path, from_cycles: &str, from_transient: &str) -> PathBuf {
    let text = std::fs::read_to_string(file).unwrap();
    for line in [from_cycles, from_transient] {
        assert_eq!(
            text.lines().filter(|l| *l == line).count(),
            1,
            "{line} in {}",
            file.display()
        );
    }
    let text = text
        .lines()
        .map(|l| {
            if l == from_cycles {
                "cycles = 3"
            } else if l == from_transient {
                "transient_cycles = 1"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let copy = dir.join(file.file_name().unwrap());
    std::fs::write(&copy, text).unwrap();
    copy
}

/// `pdamp run SCENARIO --out DIR` and the checks on its `summary.json`.
fn run_point(scenario: &Path, out: &Path, particles: u64) -> serde_json::Value {
    let o = pdamp()
        .arg("run")
        .arg(scenario)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "run {}: {}",
        scenario.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["particles"].as_u64(), Some(particles));
    assert_eq!(s["cycles_evaluated"].as_u64(), Some(2));
    let closure = s["point"]["energy_closure_relative"].as_f64().unwrap();
    assert!(
        closure.abs() < CLOSURE_TOLERANCE,
        "energy closure {closure} (tolerance {CLOSURE_TOLERANCE})"
    );
    let eta = s["effective_loss_factor"].as_f64().unwrap();
    let mass = s["effective_mass_ratio"].as_f64().unwrap();
    assert!(eta.is_finite() && eta >= 0.0, "η̄ = {eta}");
    assert!(mass.is_finite() && mass >= 0.0, "m̄/m = {mass}");
    s
}

#[test]
fn stl_container_example_checks_and_runs() {
    let stl = examples().join("stl_cylinder_r8_l24_mm.stl");
    let toml = examples().join("stl_cylinder_damper.toml");

    // The mesh: closed, small, and with `scale = 0.001, flip_normals = true` (as the scenario
    // says) its particle region is the inside of the cylinder R = 8 mm, L = 24 mm along x.
    let mut mesh = pdamp_io::stl::read_stl(&stl).unwrap();
    assert!(mesh.is_closed());
    assert_eq!(mesh.num_triangles(), 128);
    mesh = mesh.transformed(0.001, Vec3::new(0.0, 0.0, 0.0)).unwrap();
    mesh.flip_normals();
    assert!(mesh.in_particle_region(&Vec3::new(0.012, 0.0, 0.0)));
    assert!(mesh.in_particle_region(&Vec3::new(0.001, 0.0, -0.007)));
    assert!(!mesh.in_particle_region(&Vec3::new(0.012, 0.0, 0.0085)));
    assert!(!mesh.in_particle_region(&Vec3::new(0.0245, 0.0, 0.0)));

    let v = check(&toml);
    assert_eq!(v["particles"].as_u64(), Some(150));
    assert!(v["gpu_backend"].as_str().unwrap().contains("triangle-mesh"));
    assert!(
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .all(|w| !w.as_str().unwrap().contains("not closed"))
    );
    assert_eq!(
        v["estimate_for"],
        "pdamp fields (every point of the [fields] grid)"
    );

    // The same container with one facet missing: `pdamp check` warns, naming the wall.
    let open_dir = temp_dir("open_stl");
    let text = std::fs::read_to_string(&stl).unwrap();
    let k = text.find("facet normal").unwrap();
    let end = text[k..].find("endfacet").unwrap() + k + "endfacet".len();
    std::fs::write(
        open_dir.join("stl_cylinder_r8_l24_mm.stl"),
        format!("{}{}", &text[..k], &text[end..]),
    )
    .unwrap();
    std::fs::copy(&toml, open_dir.join("damper.toml")).unwrap();
    let v = check(&open_dir.join("damper.toml"));
    let w: Vec<&str> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    assert!(
        w.iter()
            .any(|w| w.contains("the mesh is not closed") && w.contains("wall '")),
        "{w:?}"
    );
    let _ = std::fs::remove_dir_all(&open_dir);

    let dir = temp_dir("stl");
    std::fs::copy(&stl, dir.join("stl_cylinder_r8_l24_mm.stl")).unwrap();
    let copy = reduced_copy(&toml, &dir, "cycles = 8", "transient_cycles = 3");
    let s = run_point(&copy, &dir.join("point"), 150);
    // The dropped bed lies inside the mesh: bottom above −R, top below +R.
    let bottom = s["bed"]["bed_bottom_m"].as_f64().unwrap();
    let surface = s["bed"]["bed_surface_m"].as_f64().unwrap();
    assert!(bottom > -0.008 && surface < 0.008 && bottom < surface);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn polydisperse_example_checks_and_runs() {
    let toml = examples().join("polydisperse_box_damper.toml");
    let sc = pdamp_scenario::schema::Scenario::load(&toml).unwrap();
    assert_eq!(sc.particles.len(), 1);
    let (lo, hi) = match sc.particles[0].size {
        SizeDistribution::Uniform {
            min_radius_m,
            max_radius_m,
        } => (min_radius_m, max_radius_m),
        ref other => panic!("expected a uniform size distribution, got {other:?}"),
    };
    assert_eq!((lo, hi), (0.75e-3, 1.5e-3));

    let v = check(&toml);
    assert_eq!(v["particles"].as_u64(), Some(250));
    let rmin = v["min_radius_m"].as_f64().unwrap();
    let rmax = v["max_radius_m"].as_f64().unwrap();
    // Inside the file's range and spanning it: 250 uniform samples leave gaps of ≈ 0.4 % of
    // the range at either end.
    assert!(rmin >= lo && rmax <= hi, "radii {rmin}–{rmax}");
    assert!(
        rmax - rmin > 0.95 * (hi - lo),
        "radii {rmin}–{rmax} do not span {lo}–{hi}"
    );

    let dir = temp_dir("poly");
    let copy = reduced_copy(&toml, &dir, "cycles = 6", "transient_cycles = 2");
    let s = run_point(&copy, &dir.join("point"), 250);
    let d = s["bed"]["mean_diameter_m"].as_f64().unwrap();
    assert!(d > 2.0 * lo && d < 2.0 * hi, "mean diameter {d}");
    // Shaken vertically with a clearance above the bed (docs/examples.md: h ≈ 16 mm).
    let h = s["bed"]["clearance_m"].as_f64().unwrap();
    assert!(h > 0.01 && h < 0.02, "clearance {h}");
    let _ = std::fs::remove_dir_all(&dir);
}
