//! Import of stiffness and mass matrices in Matrix Market coordinate format (as exported by
//! ANSYS `HBMAT`/`*SMAT` or Abaqus `*MATRIX GENERATE` after conversion) with a node/dof map.
//!
//! Supported: `%%MatrixMarket matrix coordinate real|integer general|symmetric`, 1-based
//! indices, `%` comments. For `symmetric` files only one triangle is stored and mirrored;
//! entries given twice are summed (as the format prescribes for assembled contributions).
//!
//! The dof map is a text file with one line per matrix row: `row node dof` (whitespace or
//! comma separated; `row` 1-based; `dof` one of `UX UY UZ ROTX ROTY ROTZ`, also `RX…`, `U1…`,
//! `1`–`6`). Lines starting with `#`, `%` or `!` and a header line whose first field is not a
//! number are skipped. Every reader returns an error on malformed input and never panics.

use crate::fe::Dof;
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
}

/// Largest dimension accepted (the dense modal solver is the limit anyway).
pub const MAX_DIMENSION: usize = 200_000;

/// Parses Matrix Market coordinate text.
///
/// # Errors
/// Every malformed banner, size line or entry, out-of-range indices, wrong entry counts,
/// non-finite values.
pub fn parse_matrix_market(text: &str) -> Result<CooMatrix, MatrixMarketError> {
    let mut lines = text.lines().enumerate();
    let (_, banner) = lines.next().ok_or(MatrixMarketError::Header {
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
    let symmetric = match tok[4].as_str() {
        "general" => false,
        "symmetric" => true,
        _ => return Err(head("symmetry must be 'general' or 'symmetric'")),
    };
    let mut size: Option<(usize, usize, usize)> = None;
    let mut entries = Vec::new();
    for (i, raw) in lines {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('%') {
            continue;
        }
        let f: Vec<&str> = l.split_whitespace().collect();
        let bad = |reason: String| MatrixMarketError::Entry { line, reason };
        match size {
            None => {
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
                size = Some((r, c, n));
                entries.reserve(n.min(10_000_000) * if symmetric { 2 } else { 1 });
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
                entries.push((ri, ci, v));
                if symmetric && ri != ci {
                    entries.push((ci, ri, v));
                }
            }
        }
    }
    let (nrows, ncols, n) =
        size.ok_or(MatrixMarketError::Structure("no size line found".into()))?;
    let stored = if symmetric {
        entries.iter().filter(|e| e.0 >= e.1).count()
    } else {
        entries.len()
    };
    if stored != n {
        return Err(MatrixMarketError::Structure(format!(
            "size line announces {n} entries, file has {stored}"
        )));
    }
    Ok(CooMatrix {
        nrows,
        ncols,
        entries,
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
    let mut rows: Vec<Option<(i64, Dof)>> = vec![None; n];
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
