//! cargo-fuzz target: the gmsh reader must never panic (`pdamp_powder::fuzz::gmsh`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_powder::fuzz::gmsh(data));
