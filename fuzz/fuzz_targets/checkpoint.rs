//! cargo-fuzz target: the checkpoint reader must never panic (`pdamp_scenario::fuzz::checkpoint`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_scenario::fuzz::checkpoint(data));
