//! cargo-fuzz target: the restitution_table reader must never panic (`pdamp_io::fuzz::restitution_table`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::restitution_table(data));
