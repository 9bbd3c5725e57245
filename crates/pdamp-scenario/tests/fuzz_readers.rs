//! Stable-Rust mutation fuzzing of the scenario and run-checkpoint readers, run in CI: the seed corpora in `fuzz/corpus/`
//! (shared with the cargo-fuzz targets, see docs/reliability.md) plus random byte flips,
//! truncations, splices and insertions of interesting tokens
//! ([`pdamp_io::fuzz::mutation_fuzz`]), for a fixed time per reader. A panic, or an input
//! taking more than 5 s, fails the test and prints the input.
//!
//! Time per reader: `PDAMP_FUZZ_SECONDS` (default 2 s).

use std::path::PathBuf;

#[test]
fn readers_never_panic_on_mutated_input() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus");
    let failures = pdamp_io::fuzz::fuzz_all(
        &pdamp_scenario::fuzz::TARGETS,
        &root,
        pdamp_io::fuzz::seconds_from_env(),
        0x5eed_1234_abcd_0002,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
