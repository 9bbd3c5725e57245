//! cargo-fuzz target: the scenario reader must never panic (`pdamp_io::fuzz::scenario`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::scenario(data));
