//! Issue 31 ("Reliability past the scenario file") for the structural level: every test here
//! failed (accepted the input, panicked or gave no location) before the fix. Each asserts that
//! the input is refused with a message naming the file/key, the line and the fix.

use pdamp_structure::effective::{EffectiveDamper, EffectiveState, FieldTable};
use pdamp_structure::free::{CoupledDamper, FreeVibrationSpec, UpdateRule, run_free_vibration};
use pdamp_structure::integrate::{IntegrationError, validate_settings};
use pdamp_structure::matrix_market::{
    MatrixMarketError, check_structural_pair, parse_dof_map, parse_matrix_market,
};
use pdamp_structure::modal::ModalStructure;
use pdamp_structure::scenario::{CoupleScenario, load_structure};
use std::path::{Path, PathBuf};

/// A fresh directory for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-structure-rel-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn has_all(msg: impl std::fmt::Display, parts: &[&str]) {
    let msg = msg.to_string();
    for p in parts {
        assert!(msg.contains(p), "message lacks {p:?}: {msg}");
    }
}

const SYM: &str = "%%MatrixMarket matrix coordinate real symmetric\n";
const GEN: &str = "%%MatrixMarket matrix coordinate real general\n";

fn mm_err(text: &str) -> MatrixMarketError {
    parse_matrix_market(text).expect_err(text)
}

// ---------------------------------------------------------------- 1. Matrix Market input

#[test]
fn mm_non_finite_entry_is_refused_with_its_line() {
    let e = mm_err(&format!("{SYM}% c\n2 2 2\n1 1 1.0\n2 2 inf\n"));
    assert_eq!(e.to_string(), "line 5: value 'inf' is not finite");
}

#[test]
fn mm_bad_entry_reports_its_real_line_not_line_1() {
    let e = mm_err(&format!("{SYM}% a\n% b\n\n3 3 2\n1 1 1.0\n% c\n3 x 1.0\n"));
    has_all(e.to_string(), &["line 8", "column index 'x'"]);
}

#[test]
fn mm_duplicate_entry_is_refused_naming_both_lines() {
    let e = mm_err(&format!("{GEN}2 2 3\n1 1 1.0\n2 2 1.0\n1 1 2.0\n"));
    has_all(
        e.to_string(),
        &[
            "line 5",
            "entry (1, 1) is given twice",
            "also on line 3",
            "give every",
        ],
    );
    let e = mm_err(&format!("{SYM}2 2 3\n2 1 1.0\n2 2 1.0\n2 1 2.0\n"));
    has_all(e.to_string(), &["line 5", "given twice", "line 3"]);
}

#[test]
fn mm_symmetric_file_storing_both_triangles_is_refused() {
    let e = mm_err(&format!(
        "{SYM}2 2 4\n1 1 2.0\n2 1 -1.0\n1 2 -1.0\n2 2 2.0\n"
    ));
    has_all(
        e.to_string(),
        &[
            "line 5",
            "(1, 2)",
            "also stored as (2, 1) on line 4",
            "one triangle only",
        ],
    );
}

#[test]
fn mm_absurd_size_lines_are_refused_before_allocating() {
    for (text, want) in [
        (
            format!("{GEN}100000000000 100000000000 1\n1 1 1\n"),
            "exceeds",
        ),
        (
            format!("{GEN}200000 200000 150000000\n1 1 1\n"),
            "can hold at most",
        ),
        (
            format!("{GEN}200000 200000 250000000\n1 1 1\n"),
            "more than the 200000000",
        ),
    ] {
        let t = std::time::Instant::now();
        let e = mm_err(&text).to_string();
        has_all(&e, &["line 2", want]);
        assert!(t.elapsed().as_secs_f64() < 0.5, "took {:?}", t.elapsed());
    }
}

fn coo(text: &str) -> pdamp_structure::matrix_market::CooMatrix {
    parse_matrix_market(text).unwrap()
}

#[test]
fn mm_non_symmetric_general_matrix_is_refused() {
    let k = coo(&format!(
        "{GEN}2 2 4\n1 1 2.0\n1 2 -1.0\n2 1 -1.5\n2 2 2.0\n"
    ));
    let m = coo(&format!("{SYM}2 2 2\n1 1 1.0\n2 2 1.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap_err();
    has_all(
        &e,
        &[
            "stiffness 'K.mtx', line 4",
            "a(1, 2) = -1e0 but a(2, 1) = -1.5e0",
            "line 5",
            "symmetric",
        ],
    );
    // within 1e-9·max|a| is accepted
    let k = coo(&format!(
        "{GEN}2 2 4\n1 1 2.0\n1 2 -1.0\n2 1 -1.0000000001\n2 2 2.0\n"
    ));
    check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap();
    // an entry whose mirror is missing
    let k = coo(&format!("{GEN}2 2 3\n1 1 2.0\n1 2 -1.0\n2 2 2.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap_err();
    has_all(&e, &["line 4", "not stored"]);
}

#[test]
fn mm_mass_that_is_not_positive_definite_is_refused() {
    let k = coo(&format!("{SYM}3 3 3\n1 1 1.0\n2 2 1.0\n3 3 1.0\n"));
    let map = parse_dof_map("1 7 UX\n2 7 UY\n3 8 ROTZ\n", 3).unwrap();
    // a massless rotation
    let m = coo(&format!("{SYM}3 3 2\n1 1 1.0\n2 2 1.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", Some(&map)).unwrap_err();
    has_all(
        &e,
        &[
            "mass 'M.mtx'",
            "m(3, 3)",
            "row 3 (node 8 Rz)",
            "not stored",
            "positive definite",
            "give every dof mass",
        ],
    );
    // a 2×2 minor that is negative
    let m = coo(&format!("{SYM}3 3 4\n1 1 1.0\n2 1 2.0\n2 2 1.0\n3 3 1.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", Some(&map)).unwrap_err();
    has_all(&e, &["mass 'M.mtx', line 4", "not positive definite"]);
    // every minor positive, but indefinite: only the factorization sees it
    let m = coo(&format!(
        "{SYM}3 3 6\n1 1 1.0\n2 1 0.9\n3 1 0.9\n2 2 1.0\n3 2 -0.9\n3 3 1.0\n"
    ));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", Some(&map)).unwrap_err();
    has_all(
        &e,
        &[
            "mass 'M.mtx'",
            "not positive definite",
            "Cholesky factorization",
        ],
    );
}

#[test]
fn mm_stiffness_that_is_not_positive_semi_definite_is_refused() {
    let m = coo(&format!("{SYM}3 3 3\n1 1 1.0\n2 2 1.0\n3 3 1.0\n"));
    let k = coo(&format!("{SYM}3 3 3\n1 1 1.0\n2 2 -5.0\n3 3 1.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap_err();
    has_all(
        &e,
        &[
            "stiffness 'K.mtx'",
            "k(2, 2)",
            "line 4",
            "positive semi-definite",
        ],
    );
    let k = coo(&format!("{SYM}3 3 4\n1 1 1.0\n2 1 3.0\n2 2 1.0\n3 3 1.0\n"));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap_err();
    has_all(
        &e,
        &["stiffness 'K.mtx', line 4", "not positive semi-definite"],
    );
    let k = coo(&format!(
        "{SYM}3 3 6\n1 1 1.0\n2 1 0.9\n3 1 0.9\n2 2 1.0\n3 2 -0.9\n3 3 1.0\n"
    ));
    let e = check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap_err();
    has_all(
        &e,
        &["stiffness 'K.mtx'", "an eigenvalue of (K, M) lies below"],
    );
    // a free spring chain (rigid-body mode, K only semi-definite) is accepted
    let k = coo(&format!("{SYM}2 2 3\n1 1 1.0\n2 1 -1.0\n2 2 1.0\n"));
    let m = coo(&format!("{SYM}2 2 2\n1 1 1.0\n2 2 1.0\n"));
    check_structural_pair(&k, "K.mtx", &m, "M.mtx", None).unwrap();
}

#[test]
fn dof_map_with_a_node_dof_twice_is_refused_naming_both_lines() {
    let e = parse_dof_map("# row node dof\n1 17 UX\n2 17 UY\n3 17 UX\n", 3).unwrap_err();
    has_all(
        e.to_string(),
        &["line 4", "node 17 dof Ux", "row 3", "row 1 on line 2"],
    );
}

/// Writes a Matrix Market structure (K, M, dof map) and a structure file whose point is on
/// `node`; returns the structure file.
fn mm_structure(d: &Path, k: &str, m: &str, node: i64) -> PathBuf {
    std::fs::write(d.join("K.mtx"), k).unwrap();
    std::fs::write(d.join("M.mtx"), m).unwrap();
    std::fs::write(d.join("dofs.txt"), "1 1 UY\n2 2 UY\n").unwrap();
    let f = d.join("structure.toml");
    std::fs::write(
        &f,
        format!(
            "[structure]\nn_modes = 2\n\n[structure.matrix_market]\nstiffness = \"K.mtx\"\n\
             mass = \"M.mtx\"\ndof_map = \"dofs.txt\"\n\n[[structure.points]]\nname = \"a\"\n\
             node = 1\n\n[[structure.points]]\nname = \"b\"\nnode = {node}\n"
        ),
    )
    .unwrap();
    f
}

const K2: &str =
    "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2e4\n2 1 -1e4\n2 2 1e4\n";
const M2: &str = "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0\n2 2 1.0\n";

#[test]
fn unknown_node_names_the_key_and_its_real_line() {
    let d = dir("node");
    let f = mm_structure(&d, K2, M2, 99);
    let out = d.join("out");
    let e = pdamp_structure::report::run_modes(&f, &out).unwrap_err();
    has_all(
        &e,
        &[
            "structure.toml",
            "line 15",
            "structure.points[1].node",
            "node 99",
            "dof map",
            "give a node",
        ],
    );
    assert!(!out.exists(), "no output directory for a refused input");
    // the valid file runs
    let f = mm_structure(&d, K2, M2, 2);
    pdamp_structure::report::run_modes(&f, &out).unwrap();
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn non_symmetric_stiffness_file_is_refused_when_building_a_structure() {
    let d = dir("asym");
    let k = "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 2e4\n1 2 -1e4\n2 1 -3e4\n2 2 1e4\n";
    let f = mm_structure(&d, k, M2, 2);
    let e = pdamp_structure::report::run_modes(&f, &d.join("out")).unwrap_err();
    has_all(
        &e,
        &["structure.matrix_market", "K.mtx', line 4", "symmetric"],
    );
    let f = mm_structure(
        &d,
        K2,
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 1 1.0\n",
        2,
    );
    let e = pdamp_structure::report::run_modes(&f, &d.join("out")).unwrap_err();
    has_all(&e, &["M.mtx", "m(2, 2)", "node 2 Uy", "positive definite"]);
    std::fs::remove_dir_all(&d).ok();
}

// ---------------------------------------------------------------- 2. structure scenario numbers

const BEAM: &str = r#"[structure]
n_modes = 2

[structure.beam]
length_m = 1.0
elements = 10
youngs_modulus_pa = 210e9
poisson_ratio = 0.3
density_kg_m3 = 7850.0
width_m = 0.02
height_m = 0.01
supports = [{ position_m = 0.0, kind = "clamped" }, { position_m = 1.0, kind = "pinned" }]

[[structure.points]]
name = "p"
position_m = 0.5
"#;

fn structure_error(d: &Path, text: &str) -> String {
    let f = d.join("s.toml");
    std::fs::write(&f, text).unwrap();
    load_structure(&f).map(|_| ()).unwrap_err().to_string()
}

#[test]
fn support_outside_the_beam_is_refused_not_snapped() {
    let d = dir("support");
    load_structure(&{
        std::fs::write(d.join("ok.toml"), BEAM).unwrap();
        d.join("ok.toml")
    })
    .unwrap();
    let e = structure_error(
        &d,
        &BEAM.replace("position_m = 1.0, kind", "position_m = 1.2, kind"),
    );
    has_all(
        &e,
        &[
            "s.toml",
            "line 12",
            "structure.beam.supports[1].position_m = 1.2 m lies outside the beam [0, 1] m",
            "length_m = 1",
            "give one in [0, 1] m",
        ],
    );
    let e = structure_error(&d, &BEAM.replace("position_m = 0.5", "position_m = -0.1"));
    has_all(
        &e,
        &[
            "line 16",
            "structure.points[0].position_m = -0.1 m lies outside",
        ],
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn structure_numbers_are_refused_with_key_and_line() {
    let d = dir("numbers");
    for (from, to, want) in [
        (
            "length_m = 1.0",
            "length_m = nan",
            "structure.beam.length_m must be a finite number",
        ),
        (
            "length_m = 1.0",
            "length_m = 1e9",
            "structure.beam.length_m must be in (0, 1e4] m",
        ),
        (
            "elements = 10",
            "elements = 2000000",
            "structure.beam.elements must be an integer in [1, 1000000]",
        ),
        (
            "youngs_modulus_pa = 210e9",
            "youngs_modulus_pa = -1.0",
            "structure.beam.youngs_modulus_pa",
        ),
        (
            "poisson_ratio = 0.3",
            "poisson_ratio = 0.7",
            "structure.beam.poisson_ratio must be in (-1, 0.5)",
        ),
        (
            "density_kg_m3 = 7850.0",
            "density_kg_m3 = inf",
            "structure.beam.density_kg_m3 must be a finite number",
        ),
        ("width_m = 0.02", "width_m = 0.0", "structure.beam.width_m"),
        (
            "n_modes = 2",
            "n_modes = 0",
            "structure.n_modes must be an integer in [1, 1000]",
        ),
    ] {
        let text = BEAM.replace(from, to);
        let line = text
            .lines()
            .position(|l| l.starts_with(to.split(' ').next().unwrap()))
            .unwrap()
            + 1;
        let e = structure_error(&d, &text);
        has_all(&e, &[want, &format!("line {line}, column 1")]);
    }
    let e = structure_error(&d, &format!("{BEAM}\n[structure.damping]\nratio = 1.5\n"));
    has_all(
        &e,
        &["structure.damping.ratio must be in [0, 1e0]", "line 19"],
    );
    let e = structure_error(
        &d,
        "[structure]\n[structure.single_mode]\nmass_kg = 1e300\nstiffness_n_m = 1.0\n",
    );
    has_all(&e, &["structure.single_mode.mass_kg", "line 3"]);
    let e = structure_error(
        &d,
        "[structure]\n[structure.modal]\nfrequencies_hz = [10.0, -3.0]\ndamping_ratios = [0.01, 0.01]\npoints = []\n",
    );
    has_all(&e, &["structure.modal.frequencies_hz[1]", "line 3"]);
    std::fs::remove_dir_all(&d).ok();
}

const COUPLE: &str = r#"[structure]
[structure.single_mode]
mass_kg = 2.0
stiffness_n_m = 8.0e4

[[dampers]]
model = "constant"
point = "damper"
bed_mass_kg = 0.2
effective_loss_factor = 0.5
effective_mass_ratio = 0.7

[analysis]
kind = "free"
duration_s = 1.0
time_step_s = 1e-3
initial_point = "damper"
initial_displacement_m = 0.01
output_point = "damper"
"#;

#[test]
fn couple_scenario_numbers_are_refused_with_key_and_line() {
    let d = dir("couple");
    let f = d.join("c.toml");
    std::fs::write(&f, COUPLE).unwrap();
    CoupleScenario::load(&f).unwrap();
    for (from, to, want, line) in [
        (
            "duration_s = 1.0",
            "duration_s = inf",
            "analysis.duration_s must be a finite number",
            15,
        ),
        (
            "time_step_s = 1e-3",
            "time_step_s = 0.0",
            "analysis.time_step_s must be in (0, 1e0]",
            16,
        ),
        (
            "time_step_s = 1e-3",
            "time_step_s = 1e-12",
            "more than the 1e9 accepted",
            16,
        ),
        (
            "initial_displacement_m = 0.01",
            "initial_displacement_m = nan",
            "analysis.initial_displacement_m",
            18,
        ),
        (
            "initial_displacement_m = 0.01",
            "initial_displacement_m = 0.0",
            "starts at rest",
            18,
        ),
        (
            "bed_mass_kg = 0.2",
            "bed_mass_kg = 1e300",
            "dampers[0].bed_mass_kg must be in (0, 1e9] kg",
            9,
        ),
        (
            "effective_loss_factor = 0.5",
            "effective_loss_factor = -0.1",
            "dampers[0].effective_loss_factor",
            10,
        ),
        (
            "kind = \"free\"",
            "kind = \"free\"\nmode = 3",
            "analysis.mode must be an integer in [1, 1]",
            15,
        ),
    ] {
        std::fs::write(&f, COUPLE.replace(from, to)).unwrap();
        let e = CoupleScenario::load(&f).unwrap_err();
        has_all(&e, &["c.toml", want, &format!("line {line}")]);
    }
    let sweep = COUPLE.replace(
        "kind = \"free\"\nduration_s = 1.0\ntime_step_s = 1e-3\ninitial_point = \"damper\"\ninitial_displacement_m = 0.01\noutput_point = \"damper\"\n",
        "kind = \"sweep\"\nstart_hz = 10.0\nend_hz = 100.0\nduration_s = 2.0\nforce_amplitude_n = 1.0\nexcitation_point = \"damper\"\noutput_point = \"damper\"\ntime_step_s = 1e-3\nsegment_overlap = 0.3\n",
    );
    for (from, to, want) in [
        (
            "time_step_s = 1e-3",
            "time_step_s = 4e-3",
            "use at most 1.25e-3 s",
        ),
        ("start_hz = 10.0", "start_hz = -1.0", "analysis.start_hz"),
        (
            "force_amplitude_n = 1.0",
            "force_amplitude_n = nan",
            "analysis.force_amplitude_n",
        ),
        (
            "segment_overlap = 0.3",
            "segment_overlap = 1.5",
            "analysis.segment_overlap must be in [0, 1)",
        ),
    ] {
        std::fs::write(&f, sweep.replace(from, to)).unwrap();
        let e = CoupleScenario::load(&f).unwrap_err();
        has_all(&e, &["c.toml", want, "line "]);
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn damper_positions_outside_the_beam_are_refused() {
    let d = dir("positions");
    std::fs::write(
        d.join("c.toml"),
        format!(
            "{}\n[[dampers]]\nmodel = \"constant\"\npoint = \"p\"\nbed_mass_kg = 0.1\n\
             effective_loss_factor = 0.5\neffective_mass_ratio = 0.5\n\n[analysis]\n\
             kind = \"steady_state\"\nstart_hz = 1.0\nend_hz = 100.0\nforce_amplitude_n = 1.0\n\
             excitation_point = \"p\"\noutput_point = \"p\"\n",
            BEAM
        ),
    )
    .unwrap();
    std::fs::write(
        d.join("study.toml"),
        "scenario = \"c.toml\"\n[study]\npositions_m = [0.2, 0.5, 3.0]\n",
    )
    .unwrap();
    let e = pdamp_structure::position_study::run_position_study_file(
        &d.join("study.toml"),
        &d.join("out"),
    )
    .unwrap_err();
    has_all(
        &e,
        &[
            "study.toml",
            "line 3",
            "study.positions_m[2] = 3 m lies outside the beam [0, 1] m",
        ],
    );
    std::fs::remove_dir_all(&d).ok();
}

// ---------------------------------------------------------------- 3. effective-field tables

const FIELDS: &str = "# effective field\nfrequency_hz,amplitude_m,effective_loss_factor,effective_mass_ratio\n\
10,1e-4,0.5,0.8\n10,1e-3,0.6,0.7\n\n20,1e-4,nan,nan\n20,1e-3,0.4,0.6\n";

#[test]
fn fields_table_refuses_negative_and_non_finite_values_with_line() {
    let t = FieldTable::parse(FIELDS, 0.1).unwrap();
    assert_eq!(t.frequencies_hz, vec![10.0, 20.0]); // the NaN (failed) point is skipped
    for (from, to, want) in [
        (
            "10,1e-3,0.6,0.7",
            "10,1e-3,-0.6,0.7",
            "line 4: column effective_loss_factor gives η̄ = -6e-1",
        ),
        (
            "10,1e-3,0.6,0.7",
            "10,1e-3,0.6,-0.7",
            "line 4: column effective_mass_ratio = -7e-1",
        ),
        (
            "20,1e-3,0.4,0.6",
            "20,1e-3,inf,0.6",
            "line 7: column effective_loss_factor gives η̄ = inf",
        ),
        (
            "20,1e-3,0.4,0.6",
            "20,inf,0.4,0.6",
            "line 7: column amplitude_m = inf",
        ),
        (
            "20,1e-3,0.4,0.6",
            "nan,1e-3,0.4,0.6",
            "line 7: column frequency_hz = NaN",
        ),
        (
            "20,1e-3,0.4,0.6",
            "20,1e-3,0.4,1e400",
            "line 7: column effective_mass_ratio = inf",
        ),
    ] {
        let e = FieldTable::parse(&FIELDS.replace(from, to), 0.1).unwrap_err();
        has_all(&e, &[want, "fields.csv"]);
    }
    // round-off below zero is read as 0
    let t = FieldTable::parse(&FIELDS.replace("0.6,0.7", "-1e-9,0.7"), 0.1).unwrap();
    assert_eq!(t.columns[0].effective_loss_factor[1], 0.0);
    // through the file reader, with the path
    let d = dir("fields");
    std::fs::write(d.join("fields.csv"), FIELDS.replace("0.6,0.7", "-0.6,0.7")).unwrap();
    let e = FieldTable::read(&d.join("fields.csv"), 0.1).unwrap_err();
    has_all(&e, &["fields.csv: fields.csv line 4"]);
    std::fs::remove_dir_all(&d).ok();
}

// ---------------------------------------------------------------- 4. integrator health

fn free_spec(dt: f64) -> FreeVibrationSpec {
    FreeVibrationSpec {
        duration_s: 1.0,
        time_step_s: dt,
        mode: 0,
        initial_point: "damper".into(),
        initial_displacement_m: 0.01,
        initial_velocity_m_s: 0.0,
        output_point: "damper".into(),
        update: UpdateRule::ZeroCrossing,
        sample_every: 1,
        scale_initial_by_bed_mass: false,
    }
}

#[test]
fn integrator_settings_are_validated_before_running() {
    let s = ModalStructure::single_mode(1.0, 1e4, 0.0);
    for (dt, dur, every, want) in [
        (f64::NAN, 1.0, 1, "time_step_s = NaN"),
        (0.0, 1.0, 1, "time_step_s = 0e0"),
        (2.0, 1.0, 1, "longer than the duration"),
        (1e-3, f64::INFINITY, 1, "duration_s = inf"),
        (1e-12, 10.0, 1, "more than the 1e9 accepted"),
        (1e-3, 1.0, 0, "sample_every"),
        (1e-8, 1.0, 1, "samples would be stored"),
    ] {
        let e = validate_settings(&s, dt, dur, every, false).unwrap_err();
        assert!(matches!(e, IntegrationError::Settings { .. }));
        has_all(e.to_string(), &[want]);
    }
    // the explicit scheme of the DEM coupling: ω Δt < 2
    let w = (1e4f64).sqrt();
    let e = validate_settings(&s, 2.5 / w, 10.0, 1, true).unwrap_err();
    has_all(
        e.to_string(),
        &["ω_max Δt = 2.500 ≥ 2", "mode 1", "T_min/π"],
    );
    validate_settings(&s, 1.5 / w, 10.0, 1, true).unwrap();
    // and the driver refuses a NaN step instead of running
    let e = run_free_vibration(&s, &[], &free_spec(f64::NAN)).unwrap_err();
    has_all(&e, &["time_step_s"]);
}

/// A damper model that puts energy in: negative dissipated energy (or NaN mass).
#[derive(Debug)]
struct Bad {
    energy_sign: f64,
    mass_kg: f64,
}

impl EffectiveDamper for Bad {
    fn evaluate(&self, amplitude_m: f64, omega_rad_s: f64) -> EffectiveState {
        EffectiveState {
            effective_mass_kg: self.mass_kg,
            dissipated_energy_per_cycle_j: self.energy_sign
                * std::f64::consts::PI
                * 5.0
                * omega_rad_s
                * amplitude_m
                * amplitude_m,
        }
    }
    fn bed_mass_kg(&self) -> f64 {
        0.1
    }
}

#[test]
fn energy_created_by_a_damper_stops_the_run_with_a_diagnosis() {
    let s = ModalStructure::single_mode(1.0, 1e4, 0.0);
    let damper = |energy_sign, mass_kg| {
        vec![CoupledDamper {
            point: "damper".into(),
            model: Box::new(Bad {
                energy_sign,
                mass_kg,
            }),
        }]
    };
    // a healthy (dissipative) model runs
    run_free_vibration(&s, &damper(1.0, 0.05), &free_spec(1e-4)).unwrap();
    let e = run_free_vibration(&s, &damper(-1.0, 0.05), &free_spec(1e-4)).unwrap_err();
    has_all(
        &e,
        &[
            "numerical failure at t = ",
            "mode 1",
            "negative dissipation",
            "likely cause",
            "negative or non-finite effective mass or damping",
            "d̄ = -5e0",
        ],
    );
    let e = run_free_vibration(&s, &damper(1.0, f64::NAN), &free_spec(1e-4)).unwrap_err();
    has_all(
        &e,
        &[
            "numerical failure at t = ",
            "non-finite",
            "mode 1",
            "likely cause",
        ],
    );
}

#[test]
fn healthy_runs_report_non_negative_dissipation() {
    use nalgebra::DVector;
    use pdamp_structure::integrate::ModalIntegrator;
    let s = ModalStructure::single_mode(2.0, 800.0, 3.0);
    let mut it = ModalIntegrator::new(&s, 1e-3);
    it.q[0] = 0.1;
    it.make_consistent(&DVector::zeros(1));
    let e0 = it.energy_j();
    for k in 0..5000 {
        it.step(&DVector::from_element(1, (k as f64 * 0.02).sin()));
        it.check_health(&s, k % 100 == 0).unwrap();
    }
    let d = it.dissipated_j();
    assert!(d > 0.0 && d < e0 + it.work_j().abs() + 1.0, "{d}");
}
