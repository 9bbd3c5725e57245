//! cargo-fuzz target: the native bed reader must never panic (`pdamp_io::fuzz::bed_native`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::bed_native(data));
