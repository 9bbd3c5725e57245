//! Entry points for fuzzing the readers: each takes arbitrary bytes and must return (an error
//! or a value) without panicking, hanging or allocating beyond the input's size. They are
//! shared by the cargo-fuzz targets in `fuzz/` and the stable-Rust mutation test
//! `tests/fuzz_readers.rs` that runs in CI.

use std::io::Cursor;

/// STL, binary or ASCII ([`crate::stl::read_stl_from`]).
pub fn stl(bytes: &[u8]) {
    if let Ok(mesh) = crate::stl::read_stl_from(Cursor::new(bytes)) {
        let _ = mesh.bounding_box();
    }
}

/// Scenario TOML: parsing, validation and the error location lookup. Worlds are not built
/// (that would place as many particles as the input asks for).
pub fn scenario(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let base = std::path::Path::new("/nonexistent-pdamp-fuzz");
    match crate::scenario::Scenario::from_toml_in(&text, base) {
        Ok(s) => {
            if let Err(m) = s.validate() {
                let _ = crate::scenario::locate_key(&text, crate::scenario::leading_key_path(&m));
            } else {
                let _ = s.to_toml();
            }
        }
        Err(m) => {
            let _ = crate::scenario::locate_key(&text, crate::scenario::leading_key_path(&m));
        }
    }
}

/// Numeric CSV (`fields.csv`, `energy.csv`, …): [`crate::csv::parse_csv_f64`].
pub fn csv(bytes: &[u8]) {
    let _ = crate::csv::parse_csv_f64(&String::from_utf8_lossy(bytes));
}

/// Restitution tables: [`crate::restitution::parse_restitution_table`].
pub fn restitution_table(bytes: &[u8]) {
    let _ = crate::restitution::parse_restitution_table(&String::from_utf8_lossy(bytes));
}

/// Checkpoint files of `pdamp run` ([`crate::run::inspect_run_checkpoint`]).
pub fn checkpoint(bytes: &[u8]) {
    let _ = crate::run::inspect_run_checkpoint(bytes);
    // Again with a valid trailing digest, so that mutated payloads reach the decoder itself.
    if bytes.len() > 24 {
        let mut b = bytes[..bytes.len() - 16].to_vec();
        let sum = crate::checkpoint::digest(&b);
        b.extend_from_slice(sum.as_bytes());
        let _ = crate::run::inspect_run_checkpoint(&b);
    }
}

/// All readers by name (for the harnesses).
pub const TARGETS: [(&str, fn(&[u8])); 5] = [
    ("stl", stl),
    ("scenario", scenario),
    ("csv", csv),
    ("restitution_table", restitution_table),
    ("checkpoint", checkpoint),
];
