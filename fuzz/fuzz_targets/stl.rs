//! cargo-fuzz target: the stl reader must never panic (`pdamp_io::fuzz::stl`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::stl(data));
