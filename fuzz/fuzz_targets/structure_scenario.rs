//! cargo-fuzz target: the structure_scenario reader must never panic (`pdamp_structure::fuzz::structure_scenario`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_structure::fuzz::structure_scenario(data));
