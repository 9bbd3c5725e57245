//! Checkpoints of long runs: the complete dynamic state of the simulation plus the position of
//! every output stream, written atomically (temporary file + fsync + rename) as
//! `DIR/checkpoint.bin`. A run killed at any moment and resumed from its last checkpoint ends
//! with outputs identical to an uninterrupted run: the DEM state is restored bit for bit
//! ([`pdamp_dem::WorldState`]), `energy.csv` is cut back to the rows of the checkpoint, and VTK
//! frames after it are written again.
//!
//! Stopping on request: a loop whose `pdamp_dem::time_loop::CancelToken` is cancelled (by the
//! CLI's SIGINT/SIGTERM handler, a Python session) writes a checkpoint and returns
//! [`Interrupted`]. The wall-clock cadence is the engine's (`pdamp_dem::time_loop`).

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// File name of the checkpoint inside the output directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// Format version of the checkpoint file; bumped when the layout changes.
pub const CHECKPOINT_FORMAT: u32 = 4;

/// Error text prefix of a run stopped on request after its checkpoint was written.
pub const INTERRUPTED: &str = "interrupted";

/// A run stopped on request; its checkpoint is on disk.
#[derive(Debug, Clone, PartialEq)]
pub struct Interrupted {
    /// Simulated time of the checkpoint, s.
    pub time_s: f64,
    /// The checkpoint file.
    pub path: PathBuf,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{INTERRUPTED}: checkpoint at t = {:.6e} s written to {}; continue with --resume",
            self.time_s,
            self.path.display()
        )
    }
}

impl std::error::Error for Interrupted {}

/// 64-bit FNV-1a digest (stable across platforms and Rust versions), printed as 16 hex digits.
pub fn digest(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Header common to every checkpoint: which program and which scenario wrote it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckpointHeader {
    /// [`CHECKPOINT_FORMAT`] of the writer.
    pub format: u32,
    /// pdamp version of the writer.
    pub pdamp_version: String,
    /// Digest of the scenario (canonical TOML) the run belongs to.
    pub scenario_digest: String,
    /// Kind of run (`run`, `damper-point`, …).
    pub kind: String,
}

impl CheckpointHeader {
    /// Header for this build of pdamp.
    pub fn new(kind: &str, scenario_digest: &str) -> Self {
        Self {
            format: CHECKPOINT_FORMAT,
            pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
            scenario_digest: scenario_digest.to_string(),
            kind: kind.to_string(),
        }
    }
}

#[derive(Serialize)]
struct OutFile<'a, T> {
    header: &'a CheckpointHeader,
    body: &'a T,
}

#[derive(Deserialize)]
struct InFile<T> {
    header: CheckpointHeader,
    body: T,
}

const MAGIC: &[u8; 8] = b"PDAMPCK\0";

/// Why a checkpoint (or a bed file, which has the same framing) cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file cannot be read or written.
    #[error("checkpoint {}: {cause}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Cause.
        cause: std::io::Error,
    },
    /// The file was read but is refused.
    #[error("checkpoint {}: {cause}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// Why.
        cause: Box<CheckpointError>,
    },
    /// No checkpoint magic at the start (or too short).
    #[error("not a pdamp checkpoint")]
    NotCheckpoint,
    /// The trailing digest does not match the content.
    #[error("damaged (digest mismatch)")]
    Damaged,
    /// The header or body does not decode.
    #[error("unreadable ({0})")]
    Unreadable(String),
    /// Another file format version.
    #[error(
        "format {format} written by pdamp {pdamp_version}, this pdamp reads format {CHECKPOINT_FORMAT}"
    )]
    Format {
        /// The file's format.
        format: u32,
        /// The pdamp version that wrote it.
        pdamp_version: String,
    },
    /// Written by another kind of run.
    #[error("written by a '{found}' run, not '{expected}'")]
    Kind {
        /// Kind in the file.
        found: String,
        /// Kind expected.
        expected: String,
    },
    /// Written for another scenario (its digest differs).
    #[error(
        "written for a different scenario (the file changed since); start afresh without \
         --resume or use another --out directory"
    )]
    OtherScenario,
    /// The body does not encode.
    #[error("{0}")]
    Encode(String),
    /// A part does not encode ([`encode_part`]).
    #[error("checkpoint: {0}")]
    EncodePart(String),
    /// A part does not decode ([`decode_part`]).
    #[error("checkpoint: unreadable part ({0})")]
    UnreadablePart(String),
}

impl CheckpointError {
    /// `why` about the file `path`.
    pub fn in_file(path: &Path, why: CheckpointError) -> Self {
        Self::InFile {
            path: path.to_path_buf(),
            cause: Box::new(why),
        }
    }
}

/// Writes `body` with `header` to `path` atomically.
pub fn save<T: Serialize>(
    path: &Path,
    header: &CheckpointHeader,
    body: &T,
) -> Result<(), CheckpointError> {
    let mut bytes = MAGIC.to_vec();
    bincode::serialize_into(&mut bytes, &OutFile { header, body })
        .map_err(|e| CheckpointError::in_file(path, CheckpointError::Encode(e.to_string())))?;
    let sum = digest(&bytes);
    bytes.extend_from_slice(sum.as_bytes());
    crate::atomic::write_atomic(path, &bytes).map_err(|e| CheckpointError::Io {
        path: path.to_path_buf(),
        cause: e,
    })
}

/// Reads a checkpoint written by [`save`]; checks the magic, the trailing digest, the format,
/// the kind and the scenario digest, and says which one fails. `Ok(None)` if there is no file.
pub fn load<T: for<'de> Deserialize<'de>>(
    path: &Path,
    kind: &str,
    scenario_digest: &str,
) -> Result<Option<T>, CheckpointError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(CheckpointError::Io {
                path: path.to_path_buf(),
                cause: e,
            });
        }
    };
    decode(&bytes, kind, Some(scenario_digest))
        .map(Some)
        .map_err(|why| CheckpointError::in_file(path, why))
}

/// Checks only the framing of a checkpoint file — the magic and the trailing digest of
/// everything before it — without decoding the body: a quick test that a stored file is
/// complete and undamaged (a sweep's status over thousands of files).
pub fn verify_framing(bytes: &[u8]) -> Result<(), CheckpointError> {
    if bytes.len() < MAGIC.len() + 16 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(CheckpointError::NotCheckpoint);
    }
    let (data, sum) = bytes.split_at(bytes.len() - 16);
    if digest(data).as_bytes() != sum {
        return Err(CheckpointError::Damaged);
    }
    Ok(())
}

/// Decodes the bytes of a checkpoint file (see [`load`]; `scenario_digest = None` skips that
/// check). Never panics and never allocates more than the input length suggests, whatever the
/// bytes are.
pub fn decode<T: for<'de> Deserialize<'de>>(
    bytes: &[u8],
    kind: &str,
    scenario_digest: Option<&str>,
) -> Result<T, CheckpointError> {
    use bincode::Options;
    if bytes.len() < MAGIC.len() + 16 || &bytes[..MAGIC.len()] != MAGIC {
        return Err(CheckpointError::NotCheckpoint);
    }
    let (data, sum) = bytes.split_at(bytes.len() - 16);
    if digest(data).as_bytes() != sum {
        return Err(CheckpointError::Damaged);
    }
    let options = bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .with_limit(data.len() as u64);
    // The header first: a file of another format (another body layout) is named as such
    // instead of failing somewhere in its body.
    let header: CheckpointHeader = options
        .allow_trailing_bytes()
        .deserialize(&data[MAGIC.len()..])
        .map_err(|e| CheckpointError::Unreadable(e.to_string()))?;
    if header.format != CHECKPOINT_FORMAT {
        return Err(CheckpointError::Format {
            format: header.format,
            pdamp_version: header.pdamp_version,
        });
    }
    // The kind too (before the body, whose layout is the kind's).
    if header.kind != kind {
        return Err(CheckpointError::Kind {
            found: header.kind,
            expected: kind.to_string(),
        });
    }
    let f: InFile<T> = options
        .deserialize(&data[MAGIC.len()..])
        .map_err(|e| CheckpointError::Unreadable(e.to_string()))?;
    if scenario_digest.is_some_and(|d| d != f.header.scenario_digest) {
        return Err(CheckpointError::OtherScenario);
    }
    Ok(f.body)
}

/// Encodes a value exactly (bincode, fixed-width integers) for embedding in a checkpoint body,
/// e.g. the state of an observer behind a trait object.
pub fn encode_part<T: Serialize>(value: &T) -> Result<Vec<u8>, CheckpointError> {
    use bincode::Options;
    bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .serialize(value)
        .map_err(|e| CheckpointError::EncodePart(e.to_string()))
}

/// Decodes what [`encode_part`] wrote (never allocates more than the input suggests).
pub fn decode_part<T: for<'de> Deserialize<'de>>(bytes: &[u8]) -> Result<T, CheckpointError> {
    use bincode::Options;
    bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .with_limit(bytes.len() as u64)
        .deserialize(bytes)
        .map_err(|e| CheckpointError::UnreadablePart(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn save_load_round_trip_and_checks() {
        let dir = std::env::temp_dir().join(format!("pdamp-ck-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(CHECKPOINT_FILE);
        let h = CheckpointHeader::new("run", "abc");
        let body = (1.5f64, vec![1u32, 2, 3], String::from("x"));
        save(&p, &h, &body).unwrap();
        let back: (f64, Vec<u32>, String) = load(&p, "run", "abc").unwrap().unwrap();
        assert_eq!(back, body);
        let e = load::<(f64, Vec<u32>, String)>(&p, "run", "other")
            .unwrap_err()
            .to_string();
        assert!(e.contains("different scenario"), "{e}");
        let e = load::<(f64, Vec<u32>, String)>(&p, "fields", "abc")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not 'fields'"), "{e}");
        let mut bytes = std::fs::read(&p).unwrap();
        let k = bytes.len() / 2;
        bytes[k] ^= 0x55;
        std::fs::write(&p, &bytes).unwrap();
        let e = load::<(f64, Vec<u32>, String)>(&p, "run", "abc")
            .unwrap_err()
            .to_string();
        assert!(e.contains("damaged"), "{e}");
        std::fs::write(&p, b"garbage").unwrap();
        let e = load::<(f64, Vec<u32>, String)>(&p, "run", "abc")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a pdamp checkpoint"), "{e}");
        // A file of an older format whose body no longer parses is named by its format.
        let mut old = CheckpointHeader::new("run", "abc");
        old.format = CHECKPOINT_FORMAT - 1;
        save(&p, &old, &(7u8,)).unwrap();
        let e = load::<(f64, Vec<u32>, String)>(&p, "run", "abc")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!(
                "format {} written by pdamp",
                CHECKPOINT_FORMAT - 1
            )),
            "{e}"
        );
        assert!(
            load::<u8>(&dir.join("none.bin"), "run", "abc")
                .unwrap()
                .is_none()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn digest_is_fnv1a() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(digest(b""), "cbf29ce484222325");
        assert_eq!(digest(b"a"), "af63dc4c8601ec8c");
        assert_eq!(digest(b"foobar"), "85944171f73967e8");
    }
}
