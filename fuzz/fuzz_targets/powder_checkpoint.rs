//! cargo-fuzz target: the powder_checkpoint reader must never panic (`pdamp_powder::fuzz::powder_checkpoint`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| pdamp_powder::fuzz::powder_checkpoint(data));
