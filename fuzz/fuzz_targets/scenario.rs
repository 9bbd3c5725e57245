//! cargo-fuzz target: the scenario reader must never panic (`pdamp_scenario::fuzz::scenario`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_scenario::fuzz::scenario(data));
