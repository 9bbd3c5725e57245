//! cargo-fuzz target: the bed_csv reader must never panic (`pdamp_io::fuzz::bed_csv`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::bed_csv(data));
