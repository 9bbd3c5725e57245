//! Fuzz entry points of the structural readers (see docs/reliability.md): each takes arbitrary
//! bytes and must return without panicking. Shared by `fuzz/` (cargo fuzz) and
//! `tests/fuzz_readers.rs` (CI).

/// Matrix Market coordinate file, optionally followed by a line `---` and a node/dof map.
pub fn matrix_market(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let (mtx, map) = match text.split_once("\n---\n") {
        Some((a, b)) => (a, Some(b)),
        None => (&*text, None),
    };
    if let Ok(m) = crate::matrix_market::parse_matrix_market(mtx) {
        if m.nrows * m.ncols <= 1 << 16 {
            let _ = m.to_dense();
        }
        if let Some(map) = map {
            let _ = crate::matrix_market::parse_dof_map(map, m.nrows);
        }
    }
}

/// `fields.csv` as read by the effective-field coupling (approach 2), then interpolated.
pub fn fields_table(bytes: &[u8]) {
    let Ok((header, rows)) = pdamp_io::csv::parse_csv_f64(&String::from_utf8_lossy(bytes)) else {
        return;
    };
    if let Ok(t) = crate::effective::FieldTable::from_rows(&header, &rows, 0.1) {
        for (f, x) in [
            (1.0, 1e-4),
            (100.0, 1e-3),
            (1e4, 1e-9),
            (0.0, 0.0),
            (f64::NAN, 1.0),
        ] {
            let _ = t.interpolate(f, x);
        }
    }
}

/// The readers by name.
pub const TARGETS: [pdamp_io::fuzz::Target; 2] = [
    ("matrix_market", matrix_market),
    ("fields_table", fields_table),
];
