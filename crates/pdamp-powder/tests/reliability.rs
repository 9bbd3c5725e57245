//! Issue 31 ("reliability past the scenario file") for `pdamp-powder`: studies refuse run
//! directories of another scenario, every scenario number is validated (finite, physical
//! range, size limits with a cost estimate), the Gmsh/Abaqus readers refuse bad meshes with the
//! real line, and the health checks stop the DEM and the coupled run with a typed error naming
//! the particle, the time and the likely cause — never a panic.

use std::path::PathBuf;

use pdamp_powder::cantilever::{self, CantileverScenario, RunOptions};
use pdamp_powder::study::StudyError;

fn tiny_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/tiny_cantilever.toml"
    ))
    .unwrap()
}

fn tiny() -> CantileverScenario {
    CantileverScenario::from_toml(&tiny_text()).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-powder-rel-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn tiny_scenario_runs() {
    let t = std::time::Instant::now();
    let r = cantilever::run(&tiny(), &mut |_, _| {}).unwrap();
    eprintln!(
        "{} particles, {} dofs, {:.2} s, prep {:?}",
        r.particles,
        r.structure_dofs,
        t.elapsed().as_secs_f64(),
        r.prep
    );
}

// ---------------------------------------------------------------- defect 1: study reuse

fn study(sc: &CantileverScenario, out: &std::path::Path) -> Result<Vec<f64>, StudyError> {
    pdamp_powder::study::run_study(
        sc,
        pdamp_powder::study::StudyParameter::PackingDensity,
        &[0.45],
        out,
        RunOptions::new(0.0, false),
        &mut |_, _| {},
    )
    .map(|rows| rows.iter().map(|r| r.energy_closure).collect())
}

/// Before the fix, the second study silently reused the results of the first scenario (and
/// `input.toml` showed the new one).
#[test]
fn study_refuses_results_of_another_scenario_and_reuses_its_own() {
    let out = tmp("study");
    let sc = tiny();
    study(&sc, &out).unwrap();
    let run_dir = out.join("packing_density_0.45");
    let summary = std::fs::read(run_dir.join("summary.json")).unwrap();
    let js: serde_json::Value = serde_json::from_slice(&summary).unwrap();
    let digest = cantilever::scenario_digest(
        &pdamp_powder::study::StudyParameter::PackingDensity
            .apply(&sc, 0.45)
            .unwrap(),
    )
    .unwrap();
    assert_eq!(js["scenario_digest"].as_str(), Some(digest.as_str()));
    // the same scenario: reused (nothing recomputed: the summary is untouched)
    study(&sc, &out).unwrap();
    assert_eq!(
        std::fs::read(run_dir.join("summary.json")).unwrap(),
        summary
    );
    // a changed scenario (another friction): refused before anything runs, results kept
    let mut other = sc.clone();
    other.powder.as_mut().unwrap().law.friction = 0.2;
    let e = study(&other, &out).unwrap_err().to_string();
    assert!(e.contains(&run_dir.display().to_string()), "{e}");
    assert!(
        e.contains("holds results of a different scenario (digest "),
        "{e}"
    );
    assert!(
        e.contains(&format!(
            " vs {}",
            cantilever::scenario_digest(
                &pdamp_powder::study::StudyParameter::PackingDensity
                    .apply(&other, 0.45)
                    .unwrap()
            )
            .unwrap()
        )),
        "{e}"
    );
    assert!(e.contains("use another --out or remove it"), "{e}");
    assert_eq!(
        std::fs::read(run_dir.join("summary.json")).unwrap(),
        summary
    );
    // a summary written before the digest field: the stored scenario decides
    let mut old = js.clone();
    old.as_object_mut().unwrap().remove("scenario_digest");
    std::fs::write(
        run_dir.join("summary.json"),
        serde_json::to_vec_pretty(&old).unwrap(),
    )
    .unwrap();
    study(&sc, &out).unwrap();
    let e = study(&other, &out).unwrap_err().to_string();
    assert!(e.contains("holds results of a different scenario"), "{e}");
    // an interrupted run of another scenario (its checkpoint) is refused as well
    let _ = std::fs::remove_file(run_dir.join("summary.json"));
    let e = study(&other, &out).unwrap_err().to_string();
    assert!(
        e.contains("holds an interrupted run of a different scenario"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn study_values_are_validated_before_any_run() {
    let out = tmp("values");
    let sc = tiny();
    use pdamp_powder::study::StudyParameter as P;
    for (p, v, want) in [
        (P::PackingDensity, f64::NAN, "finite"),
        (P::Friction, f64::INFINITY, "finite"),
        (P::Orientation, 0.5, "orientation values"),
        (P::StiffnessFactor, -1.0, "stiffness factor"),
        (P::D50, 0.0, "d50_m"),
        (P::PackingDensity, 0.9, "powder.prep.packing_density"),
        (P::Restitution, 2.0, "powder.law.restitution"),
    ] {
        let e = pdamp_powder::study::run_study(
            &sc,
            p,
            &[0.45, v],
            &out,
            RunOptions::new(0.0, false),
            &mut |_, _| {},
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("--values") && e.contains(want), "{v}: {e}");
        assert!(
            !out.exists(),
            "nothing may be written before the values are checked"
        );
    }
}

#[test]
fn infinite_checkpoint_interval_is_refused_before_writing() {
    let out = tmp("interval");
    let e = cantilever::run_in_dir(
        &tiny(),
        &out,
        RunOptions::new(f64::INFINITY, false),
        &mut |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("--checkpoint-interval-s"), "{e}");
    assert!(!out.exists());
}

// ---------------------------------------------------------------- defect 2: numbers

/// Replaces `key = …` in `section` of the tiny scenario.
fn with(section: &str, key: &str, value: &str) -> String {
    let mut out = String::new();
    let mut cur = String::new();
    let mut done = false;
    for line in tiny_text().lines() {
        let t = line.trim();
        if t.starts_with('[') {
            cur = t.trim_matches(|c| c == '[' || c == ']').to_string();
        }
        if cur == section && t.split('=').next().map(str::trim) == Some(key) {
            out.push_str(&format!("{key} = {value}\n"));
            done = true;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    assert!(done, "{section}.{key} not in the tiny scenario");
    out
}

#[test]
fn every_number_is_validated_with_its_key() {
    let cases: &[(&str, &str, &str, &str)] = &[
        ("beam", "length_m", "nan", "beam.length_m"),
        ("beam", "width_m", "inf", "beam.width_m"),
        ("beam", "cavity_offset_m", "nan", "beam.cavity_offset_m"),
        ("beam", "rho_inf", "nan", "beam.rho_inf"),
        (
            "beam.material",
            "youngs_modulus_pa",
            "inf",
            "beam.material.youngs_modulus_pa",
        ),
        (
            "beam.material",
            "density_kg_m3",
            "nan",
            "beam.material.density_kg_m3",
        ),
        (
            "beam.material",
            "poisson_ratio",
            "-1.0",
            "beam.material.poisson_ratio",
        ),
        (
            "beam.rayleigh",
            "mass_coeff_per_s",
            "nan",
            "beam.rayleigh.mass_coeff_per_s",
        ),
        (
            "beam.rayleigh",
            "stiffness_coeff_s",
            "inf",
            "beam.rayleigh.stiffness_coeff_s",
        ),
        // the 5e287 m tip displacement
        ("load", "pressure_pa", "1e300", "load.pressure_pa"),
        ("load", "pressure_pa", "nan", "load.pressure_pa"),
        ("load", "rise_s", "inf", "load.rise_s"),
        ("load", "hold_s", "nan", "load.hold_s"),
        ("run", "duration_s", "inf", "run.duration_s"),
        ("run", "time_step_s", "nan", "run.time_step_s"),
        ("run", "gravity_m_s2", "[nan, 0.0, 0.0]", "run.gravity_m_s2"),
        ("run", "gravity_m_s2", "[1e6, 0.0, 0.0]", "run.gravity_m_s2"),
        ("run", "output_interval_s", "-1.0", "run.output_interval_s"),
        ("run.coupling", "tolerance", "inf", "run.coupling.tolerance"),
        (
            "run.coupling",
            "initial_relaxation",
            "nan",
            "run.coupling.initial_relaxation",
        ),
        (
            "run.coupling",
            "max_iterations",
            "0",
            "run.coupling.max_iterations",
        ),
        ("powder", "d50_m", "nan", "powder.d50_m"),
        ("powder", "sigma", "1e300", "powder.sigma"),
        ("powder", "density_kg_m3", "inf", "powder.density_kg_m3"),
        (
            "powder",
            "reference_d50_m",
            "1e-300",
            "powder.reference_d50_m",
        ),
        (
            "powder.law",
            "normal_stiffness_n_m",
            "inf",
            "powder.law.normal_stiffness_n_m",
        ),
        ("powder.law", "friction", "nan", "powder.law.friction"),
        (
            "powder.law",
            "surface_energy_j_m2",
            "inf",
            "powder.law.surface_energy_j_m2",
        ),
        ("powder.law", "hamaker_j", "inf", "powder.law.hamaker_j"),
        (
            "powder.law",
            "poisson_ratio",
            "nan",
            "powder.law.poisson_ratio",
        ),
        (
            "powder.prep",
            "packing_density",
            "nan",
            "powder.prep.packing_density",
        ),
        (
            "powder.prep",
            "settling_gravity_factor",
            "inf",
            "powder.prep.settling_gravity_factor",
        ),
        (
            "powder.prep",
            "plate_speed_m_s",
            "inf",
            "powder.prep.plate_speed_m_s",
        ),
        (
            "powder.prep",
            "relax_time_s",
            "nan",
            "powder.prep.relax_time_s",
        ),
        (
            "powder.prep",
            "max_settling_time_s",
            "inf",
            "powder.prep.max_settling_time_s",
        ),
        // a time step above the contact time (the powder would explode)
        (
            "run",
            "time_step_s",
            "1e-4",
            "run.time_step_s = 1.000e-4 s is",
        ),
    ];
    for (section, key, value, want) in cases {
        let e = CantileverScenario::from_toml(&with(section, key, value))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(want) || e.contains(want),
            "{section}.{key} = {value}: {e}"
        );
    }
}

/// The optional preparation keys (absent from the tiny scenario) are checked like the law's.
#[test]
fn preparation_friction_and_surface_energy_are_validated_with_their_keys() {
    for (key, value) in [
        ("friction", "-0.1"),
        ("friction", "nan"),
        ("surface_energy_j_m2", "inf"),
        ("surface_energy_j_m2", "-1.0"),
    ] {
        let text = tiny_text().replace(
            "[powder.prep]\n",
            &format!("[powder.prep]\n{key} = {value}\n"),
        );
        assert!(
            text.contains(&format!("{key} = {value}")),
            "no [powder.prep] section"
        );
        let e = CantileverScenario::from_toml(&text)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("powder.prep.{key}")),
            "powder.prep.{key} = {value}: {e}"
        );
    }
    let ok = tiny_text().replace(
        "[powder.prep]\n",
        "[powder.prep]\nfriction = 1.0\nsurface_energy_j_m2 = 2.0\n",
    );
    let sc = CantileverScenario::from_toml(&ok).unwrap();
    let p = sc.powder.unwrap();
    assert_eq!(p.prep.friction, Some(1.0));
    // coarse-grained like the law's surface energy: γ' = f² γ
    let f = p.d50_m / p.reference_d50_m;
    assert_eq!(p.scaled_prep().surface_energy_j_m2, Some(2.0 * f * f));
}

#[test]
fn sizes_are_bounded_with_a_cost_estimate() {
    // elements: 1 µm walls
    let e = CantileverScenario::from_toml(&with("beam", "wall_element_m", "1e-7"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("beam.wall_element_m") && e.contains("elements") && e.contains("GB"),
        "{e}"
    );
    // particles: 10 µm powder in the cavity (coarse-graining keeps the time step valid)
    let text =
        with("powder", "d50_m", "1e-5").replace("reference_d50_m = 1e-3", "reference_d50_m = 1e-5");
    let e = CantileverScenario::from_toml(&text)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particles") && e.contains("GB") && e.contains("of one core"),
        "{e}"
    );
    // steps: 1000 s at 5 µs
    let e = CantileverScenario::from_toml(&with("run", "duration_s", "1000.0"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("run.duration_s") && e.contains("steps") && e.contains("h of one core"),
        "{e}"
    );
    // ParaView frames: one per µs of a 1 s run
    let text = with("run", "duration_s", "1.0").replace(
        "output_interval_s = 1e-5",
        "output_interval_s = 1e-5\nvtk_interval_s = 1e-6",
    );
    let e = CantileverScenario::from_toml(&text)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("run.vtk_interval_s") && e.contains("frames"),
        "{e}"
    );
    let est = tiny().estimate();
    assert!((20.0..100.0).contains(&est.particles), "{est:?}");
    assert!(est.steps == 200.0, "{est:?}");
}

// ---------------------------------------------------------------- defect 3: mesh readers

use pdamp_powder::fe::{MeshError, read_abaqus_inp, read_gmsh};

const HEX_NODES: &str = "1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n";

fn gmsh22(nodes: &str, n: usize, elements: &str) -> String {
    format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{n}\n{nodes}$EndNodes\n$Elements\n1\n{elements}\n$EndElements\n"
    )
}

#[test]
fn gmsh_reader_refuses_bad_meshes_with_the_real_line() {
    let good = gmsh22(HEX_NODES, 8, "7 5 2 0 1 1 2 3 4 5 6 7 8");
    assert_eq!(read_gmsh(&good, 1.0).unwrap().elements.len(), 1);
    // unknown node 99 in the element on line 17 (was always "line 1")
    let e = read_gmsh(&gmsh22(HEX_NODES, 8, "7 5 2 0 1 1 2 3 4 5 6 7 99"), 1.0).unwrap_err();
    assert_eq!(
        e,
        MeshError::UnknownNode {
            line: 17,
            element: 7,
            node: 99
        }
    );
    assert!(
        e.to_string()
            .starts_with("line 17: element 7 references unknown node 99"),
        "{e}"
    );
    // non-finite coordinate of node 3 on line 8
    let e = read_gmsh(
        &gmsh22(
            &HEX_NODES.replace("3 1 1 0", "3 1 nan 0"),
            8,
            "7 5 2 0 1 1 2 3 4 5 6 7 8",
        ),
        1.0,
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("line 8: node 3: coordinate y is not finite"),
        "{e}"
    );
    let e = read_gmsh(
        &gmsh22(
            &HEX_NODES.replace("3 1 1 0", "3 1 1 inf"),
            8,
            "7 5 2 0 1 1 2 3 4 5 6 7 8",
        ),
        1.0,
    )
    .unwrap_err();
    assert!(e.to_string().contains("coordinate z is not finite"), "{e}");
    // inverted (bottom and top faces swapped) and degenerate (a collapsed corner) elements
    let e = read_gmsh(&gmsh22(HEX_NODES, 8, "7 5 2 0 1 5 6 7 8 1 2 3 4"), 1.0).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::BadElement {
                line: 17,
                element: 7,
                kind: "inverted",
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("reorder its nodes"), "{e}");
    let e = read_gmsh(&gmsh22(HEX_NODES, 8, "7 5 2 0 1 1 2 3 4 5 6 7 7"), 1.0).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::BadElement {
                kind: "degenerate",
                ..
            }
        ),
        "{e}"
    );
    // duplicate node id
    let e = read_gmsh(
        &gmsh22(
            &format!("{HEX_NODES}3 5 5 5\n"),
            9,
            "7 5 2 0 1 1 2 3 4 5 6 7 8",
        ),
        1.0,
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .contains("node 3 is defined twice (first on line 8)"),
        "{e}"
    );
    // negative tag count (an overflow before)
    let e = read_gmsh(
        &gmsh22(HEX_NODES, 8, "7 5 -9223372036854775807 0 1 1 2 3 4 5 6 7 8"),
        1.0,
    )
    .unwrap_err();
    assert!(e.to_string().starts_with("line 17:"), "{e}");
    // a bad scale
    assert_eq!(
        read_gmsh(&good, f64::NAN).unwrap_err().to_string(),
        "scale: must be finite and positive, got NaN"
    );
}

#[test]
fn gmsh_announced_sizes_are_bounded_by_the_file() {
    // the 91-byte file announcing 1e11 nodes exhausted the memory
    let tiny = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 100000000000 1 100000000000\n2 1 0 100000000000\n";
    let t = std::time::Instant::now();
    let e = read_gmsh(tiny, 1.0).unwrap_err();
    assert!(t.elapsed().as_secs_f64() < 1.0);
    assert!(
        matches!(
            e,
            MeshError::AnnouncedSize {
                line: 6,
                announced: 100_000_000_000,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("announces 100000000000 nodes in the block, but only 0 lines follow"),
        "{e}"
    );
    for text in [
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n100000000000\n1 0 0 0\n",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n18446744073709551\n",
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n1 9000000000000000000 1 1\n2 1 3 9000000000000000000\n",
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n1 1 1 1\n2 1 5 -5\n",
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n99999999999 1 1 1\n",
    ] {
        let t = std::time::Instant::now();
        let e = read_gmsh(text, 1.0).unwrap_err();
        assert!(t.elapsed().as_secs_f64() < 1.0, "{text}");
        let m = e.to_string();
        assert!(m.contains("announces") || m.contains("negative"), "{m}");
    }
}

#[test]
fn abaqus_reader_refuses_bad_meshes_with_the_real_line() {
    let nodes = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n";
    let inp = |el: &str| format!("** test\n{nodes}*ELEMENT, TYPE=C3D8, ELSET=E\n{el}\n");
    assert_eq!(
        read_abaqus_inp(&inp("4, 1, 2, 3, 4, 5, 6, 7, 8"), 1.0)
            .unwrap()
            .elements
            .len(),
        1
    );
    // continued over two lines
    assert_eq!(
        read_abaqus_inp(&inp("4, 1, 2, 3, 4,\n5, 6, 7, 8"), 1.0)
            .unwrap()
            .elements
            .len(),
        1
    );
    let e = read_abaqus_inp(&inp("4, 1, 2, 3, 4, 5, 6, 7, 42"), 1.0).unwrap_err();
    assert_eq!(
        e,
        MeshError::UnknownNode {
            line: 12,
            element: 4,
            node: 42
        }
    );
    let e = read_abaqus_inp(&inp("4, 5, 6, 7, 8, 1, 2, 3, 4"), 1.0).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::BadElement {
                line: 12,
                element: 4,
                kind: "inverted",
                ..
            }
        ),
        "{e}"
    );
    let e = read_abaqus_inp(&inp("4, 1, 2, 3, 4, 5, 6, 7, 8, 9"), 1.0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("line 12: element 4: C3D8 needs an id and 8 nodes"),
        "{e}"
    );
    let e = read_abaqus_inp(&inp("4, 1, 2, 3"), 1.0).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("line 12: element 4: C3D8 needs an id and 8 nodes, got 3"),
        "{e}"
    );
    let e = read_abaqus_inp(
        &inp("4, 1, 2, 3, 4, 5, 6, 7, 8").replace("7, 1, 1, 1", "7, 1, 1e999, 1"),
        1.0,
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("line 9: node 7: coordinate y is not finite"),
        "{e}"
    );
}

// ---------------------------------------------------------------- defect 4: health checks

use pdamp_powder::bed::PowderBed;
use pdamp_powder::couple::{CoupleError, Coupled};
use pdamp_powder::fe::{Dynamics, GenAlpha};
use pdamp_powder::health::Symptom;
use pdamp_powder::law::PowderLaw;

/// The tiny beam with `pos` particles (r = 1 mm) in its cavity, not yet stepped.
fn coupled(pos: Vec<[f64; 3]>) -> Coupled {
    let sc = tiny();
    let (mut s, _) = cantilever::build_structure(&sc.beam, &sc.load, sc.run.gravity_m_s2);
    let n = s.n_dof();
    let dt = sc.run.time_step_s;
    let dy = Dynamics::new(
        &mut s,
        GenAlpha::from_rho_inf(0.8),
        dt,
        vec![0.0; n],
        vec![0.0; n],
        sc.beam.rayleigh,
    )
    .unwrap();
    let interface = cantilever::cavity_interface(&s, &sc.beam.cavity());
    let radius = vec![1e-3; pos.len()];
    let powder = PowderBed::at_rest(
        PowderLaw::PAPER.coarse_grained(2.0),
        &pos,
        &radius,
        8000.0,
        sc.run.gravity_m_s2,
        dt,
    );
    let mut c = Coupled::new(s, dy, powder, interface, sc.run.coupling).unwrap();
    c.container = Some(sc.beam.cavity());
    c
}

fn grid() -> Vec<[f64; 3]> {
    (0..8)
        .map(|i| {
            [
                0.0035 + 0.003 * (i % 2) as f64,
                0.0035 + 0.003 * ((i / 2) % 2) as f64,
                0.005 + 0.003 * (i / 4) as f64,
            ]
        })
        .collect()
}

fn health(e: CoupleError) -> pdamp_powder::health::HealthError {
    match e {
        CoupleError::Health(h) => *h,
        other => panic!("expected a health error, got {other}"),
    }
}

#[test]
fn coupled_run_stops_on_non_finite_particles_naming_particle_time_and_cause() {
    let mut c = coupled(grid());
    for _ in 0..3 {
        c.step().unwrap();
    }
    c.world.particles.velocity[5] = pdamp_dem::Vec3::new(f64::NAN, 0.0, 0.0);
    let h = health(c.step().unwrap_err());
    assert!(
        matches!(
            h.symptom,
            Symptom::NonFiniteParticle {
                particle: 5,
                quantity: "position",
                ..
            }
        ),
        "{h}"
    );
    let m = h.to_string();
    assert!(
        m.starts_with(
            "numerical failure at t = 2.000000e-5 s (coupled run): particle 5: non-finite position"
        ),
        "{m}"
    );
    // evidence: a small step ratio, so the time step is not blamed
    assert!(h.evidence.step_ratio() < 0.1, "{:?}", h.evidence);
    assert!(
        m.contains("likely cause: not the time step (time step ratio 0.0"),
        "{m}"
    );
}

#[test]
fn coupled_run_stops_when_a_particle_leaves_the_cavity() {
    let mut pos = grid();
    pos[2] = [0.0035, 0.0035, 0.040]; // above the beam (cavity top at 22 mm)
    let mut c = coupled(pos);
    let h = health(c.step().unwrap_err());
    assert!(
        matches!(h.symptom, Symptom::Escaped { particle: 2, .. }),
        "{h}"
    );
    assert!(
        h.to_string()
            .contains("particle 2 at [3.5000e-3, 3.5000e-3, 4.0000e-2] m left the closed cavity"),
        "{h}"
    );
    assert!(
        h.cause
            .starts_with("a particle passed through a cavity wall"),
        "{}",
        h.cause
    );
}

#[test]
fn coupled_run_stops_on_a_runaway_overlap() {
    let mut pos = grid();
    pos[1] = [pos[0][0] + 0.6e-3, pos[0][1], pos[0][2]]; // overlap 1.4 mm of 2 mm
    let mut c = coupled(pos);
    // the pair list is built by the first force pass; the check runs every 100 steps
    let mut err = None;
    for _ in 0..=100 {
        if let Err(e) = c.step() {
            err = Some(e);
            break;
        }
    }
    let h = health(err.expect("the overlap must be caught"));
    assert!(
        matches!(h.symptom, Symptom::Overlap { particle: 0, partner: 1, relative } if relative > 0.5),
        "{h}"
    );
    assert!(
        h.cause.starts_with("the contacts are too soft"),
        "{}",
        h.cause
    );
    assert!(h.to_string().contains("likely cause"), "{h}");
}

#[test]
fn energy_check_and_cause_follow_the_evidence() {
    use pdamp_powder::health::{Evidence, check_energy};
    assert!(check_energy(1.0, 0.0, 10.0).is_ok());
    assert!(matches!(
        check_energy(-2.0, 0.0, 10.0),
        Err(Symptom::NegativeDissipation { .. })
    ));
    assert!(matches!(
        check_energy(1.0, 6.0, 10.0),
        Err(Symptom::EnergyCreated { .. })
    ));
    assert!(matches!(
        check_energy(f64::NAN, 0.0, 10.0),
        Err(Symptom::NegativeDissipation { .. })
    ));
    let ev = |ratio: f64, overlap: f64| Evidence {
        time_step_s: ratio * 1e-4,
        contact_time_s: 1e-4,
        max_relative_overlap: overlap,
        dissipated_j: -1.0,
    };
    let s = Symptom::NegativeDissipation {
        dissipated_j: -1.0,
        scale_j: 1.0,
    };
    assert!(
        ev(0.9, 0.0)
            .likely_cause(&s)
            .starts_with("the time step 9.000e-5 s is 0.90 of the shortest contact time")
    );
    assert!(
        ev(0.05, 0.8)
            .likely_cause(&s)
            .starts_with("the contacts are too soft")
    );
    assert!(ev(0.05, 0.1).likely_cause(&s).starts_with(
        "energy created at the particle–wall interface (time step ratio 0.05 is fine"
    ));
}

#[test]
fn preparation_with_a_too_large_time_step_stops_blaming_the_time_step() {
    use pdamp_powder::fe::Aabb;
    use pdamp_powder::prep::{PrepSettings, prepare};
    use pdamp_powder::psd::LogNormal;
    let cavity = Aabb {
        min: [0.0; 3],
        max: [0.01, 0.01, 0.02],
    };
    let law = PowderLaw::PAPER.coarse_grained(3.0);
    // contact time ≈ 1e-4 s: a 1e-4 s step is unstable (scenario validation refuses it)
    let Err(e) = prepare(
        cavity,
        &LogNormal::paper(3e-3),
        law,
        8000.0,
        1.5e-4,
        &PrepSettings {
            packing_density: 0.45,
            max_settling_time_s: 0.5,
            ..PrepSettings::default()
        },
        &mut |_, _| {},
    ) else {
        panic!("the unstable preparation must fail");
    };
    let m = e.to_string();
    assert!(m.starts_with("numerical failure at t = "), "{m}");
    assert!(
        m.contains("(preparation: settling)") && m.contains("particle"),
        "{m}"
    );
    assert!(
        m.contains("likely cause: the time step 1.500e-4 s is"),
        "{m}"
    );
}

#[test]
fn neighbor_list_survives_non_finite_positions() {
    // the engine's neighbour list (pdamp-dem), as the powder runs use it
    use pdamp_dem::Vec3;
    let mut nl = pdamp_dem::neighbor::NeighborList::new(1e-4);
    let pos = vec![
        Vec3::zeros(),
        Vec3::new(f64::INFINITY, 0.0, 0.0),
        Vec3::repeat(f64::NAN),
        Vec3::new(1e-3, 0.0, 0.0),
        Vec3::repeat(-f64::INFINITY),
    ];
    nl.rebuild(&pos, &[1e-3; 5]);
    assert_eq!(nl.num_pairs(), 1, "only the finite pair 0–3");
    assert_eq!((nl.first[0], nl.second[0]), (0, 3));
}

/// A particle pressed out of the cavity during the plate compression is blamed on the bed
/// resisting the plate (a too loose or too stiff bed for the packing density asked), not on
/// the load or the time step of the coupled run.
#[test]
fn particle_pressed_out_by_the_plate_names_the_preparation_keys() {
    use pdamp_powder::health::{COMPRESSION_STAGE, HealthError, Symptom};
    let law = PowderLaw::PAPER;
    let w = pdamp_powder::bed::powder_world(&law, 8000.0, [0.0, 0.0, -9.81], 2.5e-6);
    let escaped = Symptom::Escaped {
        particle: 3,
        position: [0.0; 3],
        distance_m: 5e-6,
    };
    let e = HealthError::of_world(0.26, COMPRESSION_STAGE, escaped.clone(), &w, &law);
    assert!(
        e.cause.starts_with("the bed resists the plate")
            && e.cause.contains("powder.prep.packing_density")
            && e.cause.contains("powder.prep.friction"),
        "{}",
        e.cause
    );
    let e = HealthError::of_world(0.01, "coupled run", escaped, &w, &law);
    assert!(
        e.cause
            .starts_with("a particle passed through a cavity wall"),
        "{}",
        e.cause
    );
}
