//! Fuzz entry points of the structural readers (see docs/reliability.md): each takes arbitrary
//! bytes and must return without panicking. Shared by `fuzz/` (cargo fuzz) and
//! `tests/fuzz_readers.rs` (CI).

/// Matrix Market coordinate file, optionally followed by a line `---` and a node/dof map; a
/// small square matrix is also run through the structural checks
/// ([`crate::matrix_market::check_structural_pair`]) as K and as M.
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
        let map = map.and_then(|map| crate::matrix_market::parse_dof_map(map, m.nrows).ok());
        if m.nrows == m.ncols && m.nrows <= 256 {
            let _ = crate::matrix_market::check_structural_pair(&m, "k", &m, "m", map.as_ref());
        }
    }
}

/// A node/dof map on its own (the first line may give the matrix dimension as `# rows N`,
/// otherwise the number of data lines is taken).
pub fn dof_map(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let n = text
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("# rows "))
        .and_then(|v| v.trim().parse::<usize>().ok())
        .unwrap_or_else(|| text.lines().count());
    let _ = crate::matrix_market::parse_dof_map(&text, n.min(1 << 16));
}

/// A structure file or a `pdamp couple` scenario (TOML): parsed, validated with the error
/// located in the text, and — when valid and a small model without files (single mode,
/// modal, a beam of at most 200 elements) — built.
pub fn structure_scenario(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let locate = |m: crate::StructureError| {
        let m = m.to_string();
        let _ =
            pdamp_scenario::schema::locate_key(&text, pdamp_scenario::schema::leading_key_path(&m));
    };
    let spec = if let Ok(f) = toml::from_str::<crate::scenario::StructureFile>(&text) {
        Some(f.structure)
    } else if let Ok(s) = toml::from_str::<crate::scenario::CoupleScenario>(&text) {
        if let Some(st) = &s.structure
            && let Err(m) = s.validate(st)
        {
            locate(m);
        }
        s.structure
    } else {
        None
    };
    let Some(spec) = spec else {
        return;
    };
    match spec.validate() {
        Err(m) => locate(m),
        Ok(()) => {
            let small = spec.matrix_market.is_none()
                && spec.beam.as_ref().is_none_or(|b| b.elements <= 200)
                && spec.n_modes <= 20;
            if small {
                let _ = spec.build(std::path::Path::new("/nonexistent"));
            }
        }
    }
}

/// `fields.csv` as read by the effective-field coupling (approach 2), then interpolated.
pub fn fields_table(bytes: &[u8]) {
    let Ok(t) = crate::effective::FieldTable::parse(&String::from_utf8_lossy(bytes), 0.1) else {
        return;
    };
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

/// The readers by name.
pub const TARGETS: [pdamp_io::fuzz::Target; 4] = [
    ("matrix_market", matrix_market),
    ("dof_map", dof_map),
    ("structure_scenario", structure_scenario),
    ("fields_table", fields_table),
];
