//! Matrix Market import end to end: the built-in cantilever's K and M written as Matrix Market
//! files with a dof map and read back through a `[structure.matrix_market]` section give the
//! same eigenfrequencies and tip mode-shape values as the built-in beam model.

use pdamp_structure::matrix_market::{format_dof_map, format_symmetric};
use pdamp_structure::scenario::StructureFile;
use std::path::Path;

const BEAM: &str = r#"
[structure]
n_modes = 4
min_frequency_hz = 0.0
[structure.beam]
length_m = 1.0
elements = 20
youngs_modulus_pa = 210e9
poisson_ratio = 0.3
density_kg_m3 = 7850.0
width_m = 0.02
height_m = 0.01
timoshenko = true
supports = [{ position_m = 0.0, kind = "clamped" }]
[[structure.points]]
name = "tip"
position_m = 1.0
"#;

#[test]
fn exported_matrices_round_trip_through_the_importer() {
    let spec: StructureFile = toml::from_str(BEAM).unwrap();
    let reference = spec.structure.build(Path::new(".")).unwrap().modal;
    let (fe, _) = spec.structure.beam.as_ref().unwrap().model().unwrap();
    let a = fe.assemble().unwrap();
    let dir = std::env::temp_dir().join(format!("pdamp-structure-mm-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("K.mtx"), format_symmetric(&a.stiffness, 0.0)).unwrap();
    std::fs::write(dir.join("M.mtx"), format_symmetric(&a.mass, 0.0)).unwrap();
    // node ids as an exporting program would number them (1-based)
    let rows: Vec<(i64, _)> = a.dofs.iter().map(|&(n, d)| (n as i64 + 1, d)).collect();
    std::fs::write(dir.join("dofs.txt"), format_dof_map(&rows)).unwrap();
    let imported: StructureFile = toml::from_str(
        r#"
[structure]
n_modes = 4
min_frequency_hz = 0.0
[structure.matrix_market]
stiffness = "K.mtx"
mass = "M.mtx"
dof_map = "dofs.txt"
[[structure.points]]
name = "tip"
node = 21
dof = "UY"
"#,
    )
    .unwrap();
    let s = imported.structure.build(&dir).unwrap().modal;
    for (k, (a, b)) in reference.modes.iter().zip(&s.modes).enumerate() {
        println!(
            "mode {}: beam {:.6} Hz, imported {:.6} Hz",
            k + 1,
            a.frequency_hz,
            b.frequency_hz
        );
        assert!((a.frequency_hz - b.frequency_hz).abs() < 1e-9 * a.frequency_hz);
        let (pa, pb) = (
            reference.point("tip").unwrap()[k],
            s.point("tip").unwrap()[k],
        );
        assert!((pa - pb).abs() < 1e-6 * pa.abs(), "{pa} {pb}");
    }
    // a point on a node that is not in the map is an error, not a panic
    let bad: StructureFile = toml::from_str(
        r#"
[structure.matrix_market]
stiffness = "K.mtx"
mass = "M.mtx"
dof_map = "dofs.txt"
[[structure.points]]
name = "x"
node = 999
"#,
    )
    .unwrap();
    assert!(bad.structure.build(&dir).is_err());
    std::fs::remove_dir_all(&dir).ok();
}

/// The user-style plate of `examples/structure_plate.toml`: the committed Matrix Market files
/// are the export of [`Plate::EXAMPLE`] (every entry to 1e-15 relative), and read through
/// `[structure.matrix_market]` they give the cantilever plate's frequencies: Leissa (NASA
/// SP-160, Table 4.51, CFFF square, ν = 0.3) λ = 3.492, 8.525, 21.43, 27.33 within 1.5 %; the
/// torsion mode has a node line through the free edge's middle (φ₂ there < 1e-9 of the corner's).
#[test]
fn example_plate_export_is_current_and_matches_leissa() {
    use pdamp_structure::fe::plate::Plate;
    use pdamp_structure::matrix_market::read_matrix_market;
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let a = Plate::EXAMPLE.assemble().unwrap();
    for (file, m) in [("K.mtx", &a.stiffness), ("M.mtx", &a.mass)] {
        let coo = read_matrix_market(&examples.join("plate").join(file)).unwrap();
        let d = coo.to_dense();
        assert_eq!(d.shape(), m.shape(), "{file}");
        let scale = m.amax();
        let diff = (&d - m).amax();
        assert!(
            diff <= 1e-15 * scale,
            "{file}: differs by {diff:e} (max {scale:e})"
        );
    }
    let (_, spec) =
        pdamp_structure::scenario::CoupleScenario::load(&examples.join("couple_plate_free.toml"))
            .unwrap();
    let s = spec.build(&examples).unwrap().modal;
    let leissa = [3.492, 8.525, 21.43, 27.33];
    for (k, l) in leissa.iter().enumerate() {
        let w = s.modes[k].omega_rad_s();
        let lambda = w / Plate::EXAMPLE.omega_of_lambda(1.0);
        println!("mode {}: λ = {lambda:.4} (Leissa {l})", k + 1);
        assert!(
            (lambda / l - 1.0).abs() < 0.015,
            "mode {}: {lambda} vs {l}",
            k + 1
        );
    }
    let corner = s.point("corner").unwrap();
    let middle = s.point("edge_middle").unwrap();
    assert!(middle[1].abs() < 1e-9 * corner[1].abs(), "{middle:?}");
}
