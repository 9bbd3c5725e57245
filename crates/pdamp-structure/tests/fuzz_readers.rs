//! CI mutation fuzzing of the Matrix Market and fields.csv readers (seed corpora in
//! `fuzz/corpus/`, engine [`pdamp_io::fuzz::mutation_fuzz`]); `PDAMP_FUZZ_SECONDS` sets the
//! time per reader (default 2 s).

use std::path::PathBuf;

#[test]
fn structural_readers_never_panic_on_mutated_input() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus");
    let failures = pdamp_io::fuzz::fuzz_all(
        &pdamp_structure::fuzz::TARGETS,
        &root,
        pdamp_io::fuzz::seconds_from_env(),
        0xfeed_0000,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Regression of the first fuzz finding: a dof-map line holding only separators.
#[test]
fn dof_map_line_of_separators_is_skipped() {
    let m =
        pdamp_structure::matrix_market::parse_dof_map("1 10 ux\n,\n , ,\n2 11 uy\n", 2).unwrap();
    assert_eq!(m.rows.len(), 2);
}
