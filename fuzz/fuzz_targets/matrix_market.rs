//! cargo-fuzz target: the matrix_market reader must never panic (`pdamp_structure::fuzz::matrix_market`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_structure::fuzz::matrix_market(data));
