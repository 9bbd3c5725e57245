use super::*;

#[test]
fn unknown_keys_are_rejected() {
    let bad =
        "[structure]\n[structure.single_mode]\nmass_kg = 1.0\nstiffness_n_m = 1.0\nmass = 3\n";
    assert!(toml::from_str::<StructureFile>(bad).is_err());
    let good = "[structure]\n[structure.single_mode]\nmass_kg = 1.0\nstiffness_n_m = 1.0\n";
    let s: StructureFile = toml::from_str(good).unwrap();
    assert!(s.structure.build(Path::new(".")).is_ok());
}
