//! cargo-fuzz target: the fields_table reader must never panic (`pdamp_structure::fuzz::fields_table`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_structure::fuzz::fields_table(data));
