//! cargo-fuzz target: the lammps_data reader must never panic (`pdamp_io::fuzz::lammps_data`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_io::fuzz::lammps_data(data));
