//! cargo-fuzz target: the abaqus reader must never panic (`pdamp_powder::fuzz::abaqus`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_powder::fuzz::abaqus(data));
