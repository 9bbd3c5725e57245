//! Import of stiffness and mass matrices in Matrix Market coordinate format (as exported by
//! ANSYS `HBMAT`/`*SMAT` or Abaqus `*MATRIX GENERATE` after conversion) with a node/dof map.
//!
//! Supported: `%%MatrixMarket matrix coordinate real|integer general|symmetric`, 1-based
//! indices, `%` comments. For `symmetric` files only one triangle is stored and mirrored.
//! Refused with the line of the offending entry: non-finite values, an entry given twice
//! (duplicate (i, j)), a `symmetric` file that stores both triangles (a_ij and a_ji), and a
//! size line announcing more than [`MAX_DIMENSION`] rows or columns, more than
//! [`MAX_ENTRIES`] entries or more entries than the file's bytes can hold (checked before
//! anything is allocated). [`check_structural_pair`] adds the checks of a structural K and M:
//! symmetry of `general` files, M positive definite, K positive semi-definite where this is
//! cheap to see.
//!
//! The dof map is a text file with one line per matrix row: `row node dof` (whitespace or
//! comma separated; `row` 1-based; `dof` one of `UX UY UZ ROTX ROTY ROTZ`, also `RX…`, `U1…`,
//! `1`–`6`). Lines starting with `#`, `%` or `!` and a header line whose first field is not a
//! number are skipped; a (node, dof) given for two rows is refused with both lines. Every reader
//! returns an error on malformed input and never panics.

use crate::linear::Dof;
use nalgebra::DMatrix;
use std::path::Path;

/// Errors of the Matrix Market and dof-map readers.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MatrixMarketError {
    /// Bad or unsupported banner line.
    #[error("line {line}: {reason}")]
    Header {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A malformed entry.
    #[error("line {line}: {reason}")]
    Entry {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file is inconsistent as a whole.
    #[error("{0}")]
    Structure(String),
    /// Reading the file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error text.
        message: String,
    },
    /// K and M of [`check_structural_pair`] are not square or differ in size.
    #[error(
        "stiffness '{k_file}' is {k_rows}×{k_cols}, mass '{m_file}' is {m_rows}×{m_cols}: both \
         must be square and of one size"
    )]
    PairSizes {
        /// The stiffness file.
        k_file: String,
        /// Rows of K.
        k_rows: usize,
        /// Columns of K.
        k_cols: usize,
        /// The mass file.
        m_file: String,
        /// Rows of M.
        m_rows: usize,
        /// Columns of M.
        m_cols: usize,
    },
    /// An entry of K or M violates a structural check ([`check_structural_pair`]).
    #[error("{matrix} '{file}', line {line}: {message}")]
    PairEntry {
        /// `stiffness` or `mass`.
        matrix: &'static str,
        /// The file.
        file: String,
        /// 1-based line of the entry in the file.
        line: usize,
        /// What is wrong and the fix.
        message: String,
    },
    /// K or M as a whole violates a structural check ([`check_structural_pair`]).
    #[error("{matrix} '{file}': {message}")]
    PairMatrix {
        /// `stiffness` or `mass`.
        matrix: &'static str,
        /// The file.
        file: String,
        /// What is wrong and the fix.
        message: String,
    },
    /// A sparse matrix of the checks could not be built.
    #[error(transparent)]
    Sparse(#[from] crate::sparse::SparseError),
}

/// A sparse matrix as triplets (0-based).
#[derive(Debug, Clone, PartialEq)]
pub struct CooMatrix {
    /// Rows.
    pub nrows: usize,
    /// Columns.
    pub ncols: usize,
    /// (row, column, value), 0-based, symmetric files already mirrored.
    pub entries: Vec<(usize, usize, f64)>,
    /// 1-based line in the file of every entry (a mirrored entry carries its original's line);
    /// empty for matrices not read from a file.
    pub lines: Vec<usize>,
}

impl CooMatrix {
    /// Dense copy (duplicates summed).
    pub fn to_dense(&self) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.nrows, self.ncols);
        for &(i, j, v) in &self.entries {
            m[(i, j)] += v;
        }
        m
    }

    /// Line of entry `k` in its file (0 when unknown).
    fn line_of(&self, k: usize) -> usize {
        self.lines.get(k).copied().unwrap_or(0)
    }

    /// Largest |a_ij|.
    pub fn max_abs(&self) -> f64 {
        self.entries.iter().map(|e| e.2.abs()).fold(0.0, f64::max)
    }

    /// Summed diagonal of a square matrix.
    pub fn diagonal(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.nrows.min(self.ncols)];
        for &(i, j, v) in &self.entries {
            if i == j && i < d.len() {
                d[i] += v;
            }
        }
        d
    }

    /// The first pair (k, l) of entries with |a_ij − a_ji| > `rel_tol`·max|a| (entry k at
    /// (i, j), l its mirror or `None` where a_ji is not stored), with a_ij and a_ji.
    pub fn asymmetry(&self, rel_tol: f64) -> Option<(usize, Option<usize>, f64, f64)> {
        let tol = rel_tol * self.max_abs();
        let mut idx: Vec<usize> = (0..self.entries.len()).collect();
        idx.sort_by_key(|&k| (self.entries[k].0, self.entries[k].1));
        let find = |i: usize, j: usize| {
            idx.binary_search_by_key(&(i, j), |&k| (self.entries[k].0, self.entries[k].1))
                .ok()
                .map(|p| idx[p])
        };
        for (k, &(i, j, v)) in self.entries.iter().enumerate() {
            if i == j {
                continue;
            }
            let (l, w) = match find(j, i) {
                Some(l) => (Some(l), self.entries[l].2),
                None => (None, 0.0),
            };
            if (v - w).abs() > tol {
                return Some((k, l, v, w));
            }
        }
        None
    }
}

/// Largest dimension accepted (the dense modal solver is the limit anyway).
pub const MAX_DIMENSION: usize = 200_000;

/// Largest number of stored entries a size line may announce (2e8: 3.2 GB of triplets).
pub const MAX_ENTRIES: usize = 200_000_000;

/// Shortest possible entry line (`1 1 0` and a newline), bytes: a size line announcing more
/// entries than the file's length allows is refused before allocating.
const MIN_ENTRY_BYTES: usize = 6;

/// Relative tolerance of the symmetry check of `general` files: |a_ij − a_ji| ≤ 1e-9·max|a|.
pub const SYMMETRY_TOLERANCE: f64 = 1e-9;

/// The banner line `%%MatrixMarket matrix coordinate real|integer|double general|symmetric`;
/// returns whether the file is symmetric.
fn parse_banner(text: &str) -> Result<bool, MatrixMarketError> {
    let banner = text.lines().next().ok_or(MatrixMarketError::Header {
        line: 1,
        reason: "empty file".into(),
    })?;
    let tok: Vec<String> = banner
        .split_whitespace()
        .map(|s| s.to_ascii_lowercase())
        .collect();
    let head = |reason: &str| MatrixMarketError::Header {
        line: 1,
        reason: reason.into(),
    };
    if tok.len() != 5 || tok[0] != "%%matrixmarket" {
        return Err(head(
            "expected '%%MatrixMarket matrix coordinate real general|symmetric'",
        ));
    }
    if tok[1] != "matrix" {
        return Err(head("only 'matrix' objects are supported"));
    }
    if tok[2] != "coordinate" {
        return Err(head(
            "only the 'coordinate' format is supported (not 'array')",
        ));
    }
    if tok[3] != "real" && tok[3] != "integer" && tok[3] != "double" {
        return Err(head("only real or integer fields are supported"));
    }
    Ok(match tok[4].as_str() {
        "general" => false,
        "symmetric" => true,
        _ => return Err(head("symmetry must be 'general' or 'symmetric'")),
    })
}

/// The size line `rows cols entries` (`l`, split into `f`, on line `line`): dimensions and
/// entry count within the limits and what a file of `text_len` bytes can hold.
fn parse_size_line(
    line: usize,
    l: &str,
    f: &[&str],
    symmetric: bool,
    text_len: usize,
) -> Result<(usize, usize, usize), MatrixMarketError> {
    let bad = |reason: String| MatrixMarketError::Entry { line, reason };
    if f.len() != 3 {
        return Err(bad(format!(
            "size line needs 'rows cols entries', got '{l}'"
        )));
    }
    let p = |s: &str| {
        s.parse::<usize>()
            .map_err(|_| bad(format!("'{s}' is not a non-negative integer")))
    };
    let (r, c, n) = (p(f[0])?, p(f[1])?, p(f[2])?);
    if r > MAX_DIMENSION || c > MAX_DIMENSION {
        return Err(bad(format!("dimension {r}×{c} exceeds {MAX_DIMENSION}")));
    }
    if symmetric && r != c {
        return Err(bad(format!("symmetric matrix must be square, got {r}×{c}")));
    }
    if n > r.saturating_mul(c) {
        return Err(bad(format!("{n} entries cannot fit a {r}×{c} matrix")));
    }
    if n > MAX_ENTRIES {
        return Err(bad(format!(
            "{n} entries announced, more than the {MAX_ENTRIES} accepted"
        )));
    }
    if n > text_len / MIN_ENTRY_BYTES + 1 {
        return Err(bad(format!(
            "{n} entries announced, but the file ({} bytes) can hold at most {} \
             (truncated file or wrong size line)",
            text_len,
            text_len / MIN_ENTRY_BYTES + 1
        )));
    }
    Ok((r, c, n))
}

/// The stored entries checked against the size line's count `n` (the mirrored copies of a
/// symmetric file left out) and for positions given twice: duplicates, or both triangles of
/// a symmetric file.
fn check_stored_entries(
    entries: &[(usize, usize, f64)],
    lines: &[usize],
    symmetric: bool,
    n: usize,
) -> Result<(), MatrixMarketError> {
    // Stored entries (the mirrored copies of a symmetric file left out), keyed by position
    // (a symmetric file's by its lower-triangle position): equal keys are duplicates or both
    // triangles of a symmetric file.
    let mut stored: Vec<((usize, usize), usize)> = Vec::with_capacity(n);
    let mut k = 0;
    while k < entries.len() {
        let (i, j, _) = entries[k];
        let key = if symmetric {
            (i.max(j), i.min(j))
        } else {
            (i, j)
        };
        stored.push((key, k));
        k += if symmetric && i != j { 2 } else { 1 };
    }
    if stored.len() != n {
        return Err(MatrixMarketError::Structure(format!(
            "size line announces {n} entries, file has {}",
            stored.len()
        )));
    }
    stored.sort_unstable();
    for w in stored.windows(2) {
        if w[0].0 != w[1].0 {
            continue;
        }
        let (a, b) = (w[0].1.min(w[1].1), w[0].1.max(w[1].1));
        let (ea, eb) = (entries[a], entries[b]);
        let reason = if (ea.0, ea.1) == (eb.0, eb.1) {
            format!(
                "entry ({}, {}) is given twice (also on line {}): duplicate entries are not \
                 summed; give every (row, column) once",
                eb.0 + 1,
                eb.1 + 1,
                lines[a]
            )
        } else {
            format!(
                "entry ({}, {}) of a symmetric file is also stored as ({}, {}) on line {}: a \
                 'symmetric' file stores one triangle only; drop the other triangle or declare \
                 the file 'general'",
                eb.0 + 1,
                eb.1 + 1,
                ea.0 + 1,
                ea.1 + 1,
                lines[a]
            )
        };
        return Err(MatrixMarketError::Entry {
            line: lines[b],
            reason,
        });
    }
    Ok(())
}

/// Parses Matrix Market coordinate text.
///
/// # Errors
/// Every malformed banner, size line or entry, out-of-range indices, wrong entry counts,
/// non-finite values.
pub fn parse_matrix_market(text: &str) -> Result<CooMatrix, MatrixMarketError> {
    let symmetric = parse_banner(text)?;
    let mut size: Option<(usize, usize, usize)> = None;
    let mut entries = Vec::new();
    let mut lines = Vec::new();
    for (i, raw) in text.lines().enumerate().skip(1) {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('%') {
            continue;
        }
        let f: Vec<&str> = l.split_whitespace().collect();
        let bad = |reason: String| MatrixMarketError::Entry { line, reason };
        match size {
            None => {
                let (r, c, n) = parse_size_line(line, l, &f, symmetric, text.len())?;
                size = Some((r, c, n));
                entries.reserve(n * if symmetric { 2 } else { 1 });
                lines.reserve(n * if symmetric { 2 } else { 1 });
            }
            Some((r, c, _)) => {
                if f.len() != 3 {
                    return Err(bad(format!("entry needs 'row col value', got '{l}'")));
                }
                let idx = |s: &str, max: usize, what: &str| -> Result<usize, MatrixMarketError> {
                    let v = s
                        .parse::<usize>()
                        .map_err(|_| bad(format!("{what} index '{s}' is not an integer")))?;
                    if v == 0 || v > max {
                        return Err(bad(format!("{what} index {v} outside 1..={max}")));
                    }
                    Ok(v - 1)
                };
                let (ri, ci) = (idx(f[0], r, "row")?, idx(f[1], c, "column")?);
                let v: f64 = f[2]
                    .parse()
                    .map_err(|_| bad(format!("value '{}' is not a number", f[2])))?;
                if !v.is_finite() {
                    return Err(bad(format!("value '{}' is not finite", f[2])));
                }
                if entries.len() >= 2 * MAX_ENTRIES {
                    return Err(bad(format!("more than {MAX_ENTRIES} entries")));
                }
                entries.push((ri, ci, v));
                lines.push(line);
                if symmetric && ri != ci {
                    entries.push((ci, ri, v));
                    lines.push(line);
                }
            }
        }
    }
    let (nrows, ncols, n) =
        size.ok_or(MatrixMarketError::Structure("no size line found".into()))?;
    check_stored_entries(&entries, &lines, symmetric, n)?;
    Ok(CooMatrix {
        nrows,
        ncols,
        entries,
        lines,
    })
}

/// Reads a Matrix Market file.
///
/// # Errors
/// I/O errors and everything [`parse_matrix_market`] rejects.
pub fn read_matrix_market(path: &Path) -> Result<CooMatrix, MatrixMarketError> {
    let text = std::fs::read_to_string(path).map_err(|e| MatrixMarketError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    parse_matrix_market(&text)
}

/// Node and dof of every matrix row.
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    /// (node id as in the exporting program, dof) per row (0-based row index).
    pub rows: Vec<(i64, Dof)>,
}

impl DofMap {
    /// Row of a (node, dof).
    pub fn row(&self, node: i64, dof: Dof) -> Option<usize> {
        self.rows.iter().position(|&r| r == (node, dof))
    }
}

/// Parses a dof map for a matrix of dimension `n`.
///
/// # Errors
/// Malformed lines, rows out of range, duplicate or missing rows.
pub fn parse_dof_map(text: &str, n: usize) -> Result<DofMap, MatrixMarketError> {
    if n > MAX_DIMENSION {
        return Err(MatrixMarketError::Structure(format!(
            "dof map for {n} rows: more than the {MAX_DIMENSION} accepted"
        )));
    }
    let mut rows: Vec<Option<(i64, Dof)>> = vec![None; n];
    let mut seen: std::collections::HashMap<(i64, Dof), (usize, usize)> =
        std::collections::HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') || l.starts_with('%') || l.starts_with('!') {
            continue;
        }
        let f: Vec<&str> = l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        let Some(first) = f.first() else {
            continue; // only separators (found by fuzzing: a line "," used to panic)
        };
        if first.parse::<i64>().is_err() && first.parse::<f64>().is_err() {
            continue; // header line such as "Matrix Eqn  Node  DOF"
        }
        let bad = |reason: String| MatrixMarketError::Entry { line, reason };
        if f.len() != 3 {
            return Err(bad(format!("dof map line needs 'row node dof', got '{l}'")));
        }
        let r: usize = f[0]
            .parse()
            .map_err(|_| bad(format!("row '{}' is not an integer", f[0])))?;
        if r == 0 || r > n {
            return Err(bad(format!("row {r} outside 1..={n}")));
        }
        let node: i64 = f[1]
            .parse()
            .map_err(|_| bad(format!("node '{}' is not an integer", f[1])))?;
        let dof = Dof::parse(f[2]).ok_or_else(|| bad(format!("unknown dof '{}'", f[2])))?;
        if rows[r - 1].is_some() {
            return Err(bad(format!("row {r} mapped twice")));
        }
        if let Some((r0, l0)) = seen.insert((node, dof), (r, line)) {
            return Err(bad(format!(
                "node {node} dof {dof:?} is mapped to row {r} and already to row {r0} on line \
                 {l0}: every (node, dof) must belong to one matrix row"
            )));
        }
        rows[r - 1] = Some((node, dof));
    }
    let missing: Vec<usize> = rows
        .iter()
        .enumerate()
        .filter(|(_, r)| r.is_none())
        .map(|(i, _)| i + 1)
        .take(5)
        .collect();
    if !missing.is_empty() {
        return Err(MatrixMarketError::Structure(format!(
            "dof map has no entry for rows {missing:?}…"
        )));
    }
    Ok(DofMap {
        rows: rows.into_iter().flatten().collect(),
    })
}

/// Reads a dof map file for a matrix of dimension `n`.
///
/// # Errors
/// I/O errors and everything [`parse_dof_map`] rejects.
pub fn read_dof_map(path: &Path, n: usize) -> Result<DofMap, MatrixMarketError> {
    let text = std::fs::read_to_string(path).map_err(|e| MatrixMarketError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    parse_dof_map(&text, n)
}

/// Names row `i` (0-based) for messages: `row i+1 (node N UY)` with a dof map.
fn row_name(i: usize, map: Option<&DofMap>) -> String {
    match map.and_then(|m| m.rows.get(i)) {
        Some((node, dof)) => format!("row {} (node {node} {dof:?})", i + 1),
        None => format!("row {}", i + 1),
    }
}

/// Where entry `k` of `a` is: `line L` or `not stored`.
fn entry_at(a: &CooMatrix, k: Option<usize>) -> String {
    match k.map(|k| a.line_of(k)) {
        Some(0) | None => "not stored".into(),
        Some(l) => format!("line {l}"),
    }
}

/// Checks an imported structural stiffness `k` (file `k_file`) and mass `m` (file `m_file`)
/// before the eigen solver sees them: both square of one size, symmetric within
/// [`SYMMETRY_TOLERANCE`] (a `general` file may hold anything), M positive definite (positive
/// diagonal, every 2×2 principal minor positive, and an LDLᵀ factorization with positive
/// pivots), K positive semi-definite as far as cheaply visible (non-negative diagonal,
/// k_ij² ≤ k_ii k_jj, and no eigenvalue of (K, M) below −1e-8·max k_ii/m_ii: the Sturm count
/// of K + σM). `map` (the dof map, when read) names the node and dof of a bad row.
///
/// # Errors
/// A message naming the file, the entry (row, column, line) and the fix.
pub fn check_structural_pair(
    k: &CooMatrix,
    k_file: &str,
    m: &CooMatrix,
    m_file: &str,
    map: Option<&DofMap>,
) -> Result<(), MatrixMarketError> {
    if k.nrows != k.ncols || m.nrows != m.ncols || k.nrows != m.nrows {
        return Err(MatrixMarketError::PairSizes {
            k_file: k_file.to_string(),
            k_rows: k.nrows,
            k_cols: k.ncols,
            m_file: m_file.to_string(),
            m_rows: m.nrows,
            m_cols: m.ncols,
        });
    }
    let n = k.nrows;
    for (a, file, what) in [(k, k_file, "stiffness"), (m, m_file, "mass")] {
        if let Some((e, l, v, w)) = a.asymmetry(SYMMETRY_TOLERANCE) {
            let (i, j, _) = a.entries[e];
            return Err(MatrixMarketError::PairEntry {
                matrix: what,
                file: file.to_string(),
                line: a.line_of(e),
                message: format!(
                    "a({}, {}) = {v:e} but a({}, {}) = {w:e} ({}): a structural matrix must be \
                     symmetric (|a_ij − a_ji| ≤ {SYMMETRY_TOLERANCE:e}·max|a| = {:e}); export the \
                     symmetric matrix (or one triangle as 'symmetric')",
                    i + 1,
                    j + 1,
                    j + 1,
                    i + 1,
                    entry_at(a, l),
                    SYMMETRY_TOLERANCE * a.max_abs()
                ),
            });
        }
    }
    let (kd, md) = (k.diagonal(), m.diagonal());
    let diag_line =
        |a: &CooMatrix, i: usize| entry_at(a, a.entries.iter().position(|e| e.0 == i && e.1 == i));
    for i in 0..n {
        if md[i] <= 0.0 {
            return Err(MatrixMarketError::PairMatrix {
                matrix: "mass",
                file: m_file.to_string(),
                message: format!(
                    "diagonal entry m({0}, {0}) of {1} is {2:e} ({3}): the mass matrix must be \
                     positive definite; give every dof mass (rotary inertia for rotations) or \
                     remove the dof from the export",
                    i + 1,
                    row_name(i, map),
                    md[i],
                    diag_line(m, i)
                ),
            });
        }
        if kd[i] < 0.0 {
            return Err(MatrixMarketError::PairMatrix {
                matrix: "stiffness",
                file: k_file.to_string(),
                message: format!(
                    "diagonal entry k({0}, {0}) of {1} is {2:e} ({3}): the stiffness matrix must \
                     be positive semi-definite (wrong sign or a stress-stiffened export?)",
                    i + 1,
                    row_name(i, map),
                    kd[i],
                    diag_line(k, i)
                ),
            });
        }
    }
    for (a, d, file, what, strict) in [
        (m, &md, m_file, "mass", true),
        (k, &kd, k_file, "stiffness", false),
    ] {
        for (e, &(i, j, v)) in a.entries.iter().enumerate() {
            let bound = d[i] * d[j];
            let bad = if strict {
                v * v >= bound * (1.0 - 1e-12)
            } else {
                v * v > bound * (1.0 + 1e-9) + f64::MIN_POSITIVE
            };
            if i != j && bad {
                return Err(MatrixMarketError::PairEntry {
                    matrix: what,
                    file: file.to_string(),
                    line: a.line_of(e),
                    message: format!(
                        "a({}, {}) = {v:e} exceeds √(a_ii·a_jj) = {:e} ({} and {}): the {what} \
                         matrix is not positive {}definite",
                        i + 1,
                        j + 1,
                        bound.sqrt(),
                        row_name(i, map),
                        row_name(j, map),
                        if strict { "" } else { "semi-" }
                    ),
                });
            }
        }
    }
    let sparse = |a: &CooMatrix| crate::sparse::SymmetricCsr::from_triplets(n, &a.entries, false);
    let ms = sparse(m)?;
    if !crate::factor::is_positive_definite(&ms) {
        return Err(MatrixMarketError::PairMatrix {
            matrix: "mass",
            file: m_file.to_string(),
            message: "the mass matrix is not positive definite (its Cholesky factorization has \
                      a non-positive pivot): a dof without mass or a wrong sign; give every dof \
                      mass or remove it from the export"
                .to_string(),
        });
    }
    let ratio = kd.iter().zip(&md).map(|(a, b)| a / b).fold(0.0, f64::max);
    if ratio > 0.0 && ratio.is_finite() {
        // K + σM is positive definite exactly when every eigenvalue of (K, M) exceeds −σ
        let sigma = 1e-8 * ratio;
        if !crate::factor::is_positive_definite(&sparse(k)?.shifted(-sigma, &ms)) {
            return Err(MatrixMarketError::PairMatrix {
                matrix: "stiffness",
                file: k_file.to_string(),
                message: format!(
                    "the stiffness matrix is not positive semi-definite: an eigenvalue of \
                     (K, M) lies below −{sigma:e} (1/s²) (the Cholesky factorization of \
                     K + {sigma:e}·M has a non-positive pivot); check the sign of the export and \
                     that K holds no stress-stiffening or follower terms"
                ),
            });
        }
    }
    Ok(())
}

/// Matrix Market text (`coordinate real symmetric`, lower triangle, 17 significant digits) of a
/// symmetric matrix; entries with |a_ij| ≤ `drop_below` are omitted.
pub fn format_symmetric(m: &DMatrix<f64>, drop_below: f64) -> String {
    let mut entries = Vec::new();
    for j in 0..m.ncols() {
        for i in j..m.nrows() {
            let v = m[(i, j)];
            if v.abs() > drop_below {
                entries.push(format!("{} {} {:.17e}", i + 1, j + 1, v));
            }
        }
    }
    format!(
        "%%MatrixMarket matrix coordinate real symmetric\n% written by pdamp-structure\n{} {} {}\n{}\n",
        m.nrows(),
        m.ncols(),
        entries.len(),
        entries.join("\n")
    )
}

/// Dof map text (`row node dof`, 1-based rows, ANSYS dof names) for rows given as
/// (node id, dof).
pub fn format_dof_map(rows: &[(i64, Dof)]) -> String {
    let name = |d: Dof| match d {
        Dof::Ux => "UX",
        Dof::Uy => "UY",
        Dof::Uz => "UZ",
        Dof::Rx => "ROTX",
        Dof::Ry => "ROTY",
        Dof::Rz => "ROTZ",
    };
    let mut s = String::from("# row node dof\n");
    for (i, (n, d)) in rows.iter().enumerate() {
        s.push_str(&format!("{} {} {}\n", i + 1, n, name(*d)));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: &str = "%%MatrixMarket matrix coordinate real symmetric\n% comment\n2 2 3\n1 1 2.0\n2 1 -1\n2 2 1.0\n";

    #[test]
    fn symmetric_file_is_mirrored() {
        let m = parse_matrix_market(K).unwrap().to_dense();
        assert_eq!(m, DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -1.0, 1.0]));
    }

    #[test]
    fn malformed_inputs_are_errors_not_panics() {
        let bad = [
            "",
            "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n",
            "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n",
            "%%MatrixMarket matrix coordinate real skew-symmetric\n1 1 0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n3 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n0 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 abc\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 nan\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0\n2 2 1.0\n",
            "%%MatrixMarket matrix coordinate real symmetric\n2 3 1\n1 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n-2 2 1\n1 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n99999999999 2 1\n1 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 5\n1 1 1.0\n",
            "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1\n",
            "garbage",
        ];
        for b in bad {
            assert!(parse_matrix_market(b).is_err(), "accepted: {b:?}");
        }
    }

    #[test]
    fn dof_map_parsing() {
        let m = parse_dof_map("Matrix Eqn Node DOF\n1 17 UX\n2, 17, ROTZ\n", 2).unwrap();
        assert_eq!(m.rows, vec![(17, Dof::Ux), (17, Dof::Rz)]);
        for bad in [
            "1 17 UX\n",
            "1 17 UQ\n2 1 UX\n",
            "1 17 UX\n1 18 UX\n",
            "3 1 UX\n",
            "1 x UX\n2 1 UY\n",
            "1 1\n",
        ] {
            assert!(parse_dof_map(bad, 2).is_err(), "accepted: {bad:?}");
        }
    }
}
