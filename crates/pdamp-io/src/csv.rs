//! Minimal numeric CSV: a buffered [`CsvWriter`] for time series (header of unit-suffixed column
//! names such as `time_s`, `energy_j`, rows of f64 written with shortest round-trip formatting)
//! and [`read_csv_f64`], a reader that never panics on malformed input.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Errors of CSV writing and reading. Line and column numbers are 1-based.
#[derive(Debug, thiserror::Error)]
pub enum CsvError {
    /// I/O failure on `path`.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// A column name is empty or contains a comma, quote or line break.
    #[error("invalid CSV column name {0:?}")]
    InvalidColumnName(String),
    /// A row does not have as many fields as the header.
    #[error("line {line}: expected {expected} fields, found {found}")]
    RowLength {
        /// Line number (1-based; for writers, the data row number + 1).
        line: usize,
        /// Number of columns in the header.
        expected: usize,
        /// Number of fields in the row.
        found: usize,
    },
    /// A field is not a number.
    #[error("line {line}, column {column}: cannot parse {text:?} as a number")]
    Parse {
        /// Line number (1-based).
        line: usize,
        /// Column number (1-based).
        column: usize,
        /// The offending field (trimmed, at most 64 characters).
        text: String,
    },
    /// The file has no header line.
    #[error("{0}: empty CSV file (no header)")]
    Empty(PathBuf),
}

/// Formats `x` so that it parses back to the identical f64: plain decimal for
/// 1e-4 ≤ |x| < 1e15 (and 0), scientific otherwise; `NaN`, `inf`, `-inf` for non-finite values.
pub fn format_f64(x: f64, out: &mut String) {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) || !x.is_finite() {
        let _ = write!(out, "{x}");
    } else {
        let _ = write!(out, "{x:e}");
    }
}

/// Writes a whole table (header + rows of f64) to `path` atomically (temporary file + rename),
/// so an interrupted run never leaves a half-written file.
pub fn write_csv_atomic<R: AsRef<[f64]>>(
    path: impl AsRef<Path>,
    header: &[&str],
    rows: impl IntoIterator<Item = R>,
) -> Result<(), CsvError> {
    let path = path.as_ref();
    let mut w = CsvWriter::new(Vec::new(), header)?;
    for row in rows {
        w.write_row(row.as_ref())?;
    }
    let bytes = w.into_inner()?;
    crate::atomic::write_atomic(path, &bytes).map_err(|source| CsvError::Io {
        path: path.into(),
        source,
    })
}

/// Buffered CSV writer for rows of f64 with a fixed header.
pub struct CsvWriter<W: Write> {
    out: W,
    columns: usize,
    rows: usize,
    bytes: u64,
    line: String,
    path: PathBuf,
}

impl CsvWriter<BufWriter<File>> {
    /// Creates (truncates) `path` and writes the header line.
    pub fn create(path: impl AsRef<Path>, header: &[&str]) -> Result<Self, CsvError> {
        let path = path.as_ref();
        let file = File::create(path).map_err(|source| CsvError::Io {
            path: path.into(),
            source,
        })?;
        let mut w = CsvWriter::new(BufWriter::new(file), header)?;
        w.path = path.into();
        Ok(w)
    }

    /// Reopens a file written by [`CsvWriter::create`] to append after a checkpoint: the file
    /// is cut back to `bytes` (the length [`CsvWriter::sync`] returned, with `rows` data rows);
    /// rows written after the checkpoint are dropped. Fails if the file is shorter than that
    /// or its header differs.
    pub fn resume(
        path: impl AsRef<Path>,
        header: &[&str],
        bytes: u64,
        rows: usize,
    ) -> Result<Self, CsvError> {
        use std::io::{Read, Seek, SeekFrom};
        let path = path.as_ref();
        let io = |source: io::Error| CsvError::Io {
            path: path.into(),
            source,
        };
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let head = header.join(",") + "\n";
        if len < bytes || bytes < head.len() as u64 {
            return Err(io(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("file has {len} bytes, the checkpoint expects at least {bytes}"),
            )));
        }
        let mut first = vec![0u8; head.len()];
        file.read_exact(&mut first).map_err(io)?;
        if first != head.as_bytes() {
            return Err(io(io::Error::new(
                io::ErrorKind::InvalidData,
                "header differs from the expected columns",
            )));
        }
        // The rows up to the checkpoint must be the checkpoint's rows (a file of the same
        // length from another run, or one cut and refilled, is not continued).
        file.seek(SeekFrom::Start(0)).map_err(io)?;
        let mut kept = Vec::new();
        (&mut file).take(bytes).read_to_end(&mut kept).map_err(io)?;
        let lines = kept.iter().filter(|&&b| b == b'\n').count();
        if lines != rows + 1 || kept.last() != Some(&b'\n') {
            return Err(io(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "the first {bytes} bytes hold {} rows, the checkpoint expects {rows}: the outputs do not match the checkpoint; rerun with --overwrite",
                    lines.saturating_sub(1)
                ),
            )));
        }
        file.set_len(bytes).map_err(io)?;
        file.seek(SeekFrom::End(0)).map_err(io)?;
        Ok(CsvWriter {
            out: BufWriter::new(file),
            columns: header.len(),
            rows,
            bytes,
            line: String::new(),
            path: path.into(),
        })
    }

    /// Flushes and syncs the rows to disk; returns the file length in bytes (for
    /// [`CsvWriter::resume`]).
    pub fn sync(&mut self) -> Result<u64, CsvError> {
        self.flush()?;
        let r = self.out.get_ref().sync_data();
        r.map_err(|e| self.io(e))?;
        Ok(self.bytes)
    }
}

impl<W: Write> CsvWriter<W> {
    /// Wraps `out` and writes the header line. Column names should carry their unit as a suffix
    /// (`time_s`, `force_n`); they must be non-empty and free of `,` `"` and line breaks.
    pub fn new(out: W, header: &[&str]) -> Result<Self, CsvError> {
        for name in header {
            if name.trim().is_empty() || name.contains([',', '"', '\n', '\r']) {
                return Err(CsvError::InvalidColumnName((*name).to_string()));
            }
        }
        let mut w = CsvWriter {
            out,
            columns: header.len(),
            rows: 0,
            bytes: 0,
            line: String::new(),
            path: PathBuf::new(),
        };
        let line = header.join(",") + "\n";
        w.out.write_all(line.as_bytes()).map_err(|e| w.io(e))?;
        w.bytes = line.len() as u64;
        Ok(w)
    }

    fn io(&self, source: io::Error) -> CsvError {
        CsvError::Io {
            path: self.path.clone(),
            source,
        }
    }

    /// Appends one row; its length must equal the header's.
    pub fn write_row(&mut self, values: &[f64]) -> Result<(), CsvError> {
        if values.len() != self.columns {
            return Err(CsvError::RowLength {
                line: self.rows + 2,
                expected: self.columns,
                found: values.len(),
            });
        }
        self.line.clear();
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            format_f64(v, &mut self.line);
        }
        self.line.push('\n');
        let r = self.out.write_all(self.line.as_bytes());
        r.map_err(|e| self.io(e))?;
        self.rows += 1;
        self.bytes += self.line.len() as u64;
        Ok(())
    }

    /// Number of data rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Flushes buffered rows to the underlying writer (call periodically for live monitoring).
    pub fn flush(&mut self) -> Result<(), CsvError> {
        let r = self.out.flush();
        r.map_err(|e| self.io(e))
    }

    /// Flushes and returns the underlying writer.
    pub fn into_inner(mut self) -> Result<W, CsvError> {
        self.flush()?;
        Ok(self.out)
    }
}

/// Reads a numeric CSV file: the header (column names, trimmed) and all data rows.
///
/// Blank lines and lines starting with `#` are skipped, `\r\n` line ends and spaces around
/// fields are accepted; `NaN`, `inf`, `-inf` parse. Never panics: malformed input gives a
/// [`CsvError`] naming the line and column.
pub fn read_csv_f64(path: impl AsRef<Path>) -> Result<(Vec<String>, Vec<Vec<f64>>), CsvError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| CsvError::Io {
        path: path.into(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| CsvError::Io {
        path: path.into(),
        source: io::Error::new(io::ErrorKind::InvalidData, format!("not UTF-8: {e}")),
    })?;
    parse_csv_f64(&text).map_err(|e| match e {
        CsvError::Empty(_) => CsvError::Empty(path.into()),
        other => other,
    })
}

/// As [`read_csv_f64`] on text in memory.
pub fn parse_csv_f64(text: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), CsvError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((_, head)) = lines.next() else {
        return Err(CsvError::Empty(PathBuf::new()));
    };
    let header: Vec<String> = head.split(',').map(|s| s.trim().to_string()).collect();
    let mut rows = Vec::new();
    for (line, l) in lines {
        let mut row = Vec::with_capacity(header.len());
        for (c, field) in l.split(',').enumerate() {
            let f = field.trim();
            let v = f.parse::<f64>().map_err(|_| CsvError::Parse {
                line,
                column: c + 1,
                text: f.chars().take(64).collect(),
            })?;
            row.push(v);
        }
        if row.len() != header.len() {
            return Err(CsvError::RowLength {
                line,
                expected: header.len(),
                found: row.len(),
            });
        }
        rows.push(row);
    }
    Ok((header, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roundtrip_full_precision() {
        let dir = std::env::temp_dir().join(format!("pdamp-io-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("series.csv");
        let rows = vec![
            vec![0.0, 1.0 / 3.0, -2.5e-300],
            vec![2.5e-6, 1e20, f64::NAN],
            vec![0.1 + 0.2, -1e-5, f64::INFINITY],
        ];
        let mut w = CsvWriter::create(&p, &["time_s", "energy_j", "force_n"]).unwrap();
        for r in &rows {
            w.write_row(r).unwrap();
        }
        w.flush().unwrap();
        assert_eq!(w.rows(), 3);
        assert!(matches!(
            w.write_row(&[1.0]),
            Err(CsvError::RowLength {
                expected: 3,
                found: 1,
                ..
            })
        ));
        drop(w);
        let (h, back) = read_csv_f64(&p).unwrap();
        assert_eq!(h, ["time_s", "energy_j", "force_n"]);
        for (a, b) in rows.iter().zip(&back) {
            for (x, y) in a.iter().zip(b) {
                assert!(
                    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                    "{x} vs {y}"
                );
            }
        }
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(
            text.starts_with("time_s,energy_j,force_n\n0,0.3333333333333333,-2.5e-300\n"),
            "{text}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn malformed_input_gives_errors_not_panics() {
        assert!(matches!(parse_csv_f64(""), Err(CsvError::Empty(_))));
        assert!(matches!(
            parse_csv_f64("\n# only comment\n"),
            Err(CsvError::Empty(_))
        ));
        let e = parse_csv_f64("a_s,b_m\n1,2\n3,x\n").unwrap_err();
        assert!(
            matches!(
                e,
                CsvError::Parse {
                    line: 3,
                    column: 2,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("line 3, column 2"), "{e}");
        let e = parse_csv_f64("a_s,b_m\r\n1,2,3\r\n").unwrap_err();
        assert!(
            matches!(
                e,
                CsvError::RowLength {
                    line: 2,
                    expected: 2,
                    found: 3
                }
            ),
            "{e}"
        );
        let e = parse_csv_f64("a_s,b_m\n1,\n").unwrap_err();
        assert!(
            matches!(
                e,
                CsvError::Parse {
                    line: 2,
                    column: 2,
                    ..
                }
            ),
            "{e}"
        );
        let (h, r) = parse_csv_f64("# c\n a_s , b_m \r\n\r\n 1 , -2e3 \r\n").unwrap();
        assert_eq!(h, ["a_s", "b_m"]);
        assert_eq!(r, vec![vec![1.0, -2000.0]]);
        // Garbage bytes and missing files.
        for junk in [
            "\u{0}\u{1},\u{2}\n\u{3}",
            ",,,\n,,,",
            "a\n\"1\"",
            "a\n1e99999",
            "a\n--1",
        ] {
            let _ = parse_csv_f64(junk);
        }
        assert!(matches!(
            read_csv_f64("/nonexistent/pdamp.csv"),
            Err(CsvError::Io { .. })
        ));
        assert!(CsvWriter::new(Vec::new(), &["a,b"]).is_err());
    }

    #[test]
    fn writer_into_vec() {
        let mut w = CsvWriter::new(Vec::new(), &["x_m"]).unwrap();
        w.write_row(&[1.5]).unwrap();
        let v = w.into_inner().unwrap();
        assert_eq!(String::from_utf8(v).unwrap(), "x_m\n1.5\n");
    }
}
