//! cargo-fuzz target: the dof_map reader must never panic (`pdamp_structure::fuzz::dof_map`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_structure::fuzz::dof_map(data));
