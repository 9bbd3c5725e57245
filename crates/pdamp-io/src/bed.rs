//! pdamp's native bed file (`*.pdbed`), written by `pdamp settle` and read by
//! `placement = { method = "file", path = "….pdbed" }`.
//!
//! # Format
//! The checkpoint framing of [`crate::checkpoint`]: the 8 bytes `PDAMPCK\0`, a bincode record
//! (fixed-width little-endian integers) of the header (format number, pdamp version, digest of
//! the scenario that made the bed, kind `bed`) and of a [`BedFile`], then the 16 hex digits of the
//! FNV-1a digest of everything before them. The [`BedFile`] holds
//! * the bed ([`pdamp_dem::Bed`]: material names, centres, radii, material indices,
//!   velocities and spins — everything another code needs, also exported to CSV and LAMMPS
//!   data files beside it by `pdamp settle`),
//! * its statistics ([`pdamp_dem::bed_statistics::BedStatistics`]),
//! * what the drop-down did (rounds, simulated time), if it was one,
//! * the full dynamic state of the world at the end of settling ([`pdamp_dem::WorldState`]:
//!   contact history, neighbour list, forces), so that a run starting from the bed in the same
//!   container continues bit for bit as if it had settled the bed itself.
//!
//! A damaged or foreign file is refused with the reason (magic, digest, format, kind).

use crate::checkpoint::{self, CheckpointError, CheckpointHeader};
use pdamp_dem::bed_statistics::BedStatistics;
use pdamp_dem::drop_down::DropDownReport;
use pdamp_dem::{Bed, WorldState};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Kind tag of bed files in the checkpoint header.
pub const BED_KIND: &str = "bed";

/// Contents of a native bed file (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BedFile {
    /// The particles.
    pub bed: Bed,
    /// Statistics of the settled bed.
    pub statistics: Option<BedStatistics>,
    /// What the drop-down did, if the bed was dropped.
    pub drop_down: Option<DropDownReport>,
    /// Settling time after the drop-down, s.
    pub settling_time_s: f64,
    /// The world's dynamic state for an exact continuation.
    pub state: Option<WorldState>,
}

/// Why a native bed file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum BedFileError {
    /// The file cannot be read.
    #[error("cannot read bed '{}': {cause}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Cause.
        cause: std::io::Error,
    },
    /// The file was read but is refused.
    #[error("bed '{}': {cause}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// Why.
        cause: Box<BedFileError>,
    },
    /// No bed-file magic at the start.
    #[error("not a pdamp bed file")]
    NotBedFile,
    /// Damaged, of another format version or of another kind.
    #[error(transparent)]
    Framing(CheckpointError),
    /// The bed's columns are inconsistent.
    #[error(transparent)]
    Bed(#[from] pdamp_dem::bed::BedError),
}

/// Writes `file` to `path` atomically; `scenario_digest` names the scenario that made it.
pub fn save_bed(path: &Path, file: &BedFile, scenario_digest: &str) -> Result<(), CheckpointError> {
    checkpoint::save(
        path,
        &CheckpointHeader::new(BED_KIND, scenario_digest),
        file,
    )
}

/// Reads a native bed file; the message says why a file is refused.
pub fn load_bed(path: &Path) -> Result<BedFile, BedFileError> {
    let bytes = std::fs::read(path).map_err(|e| BedFileError::Read {
        path: path.to_path_buf(),
        cause: e,
    })?;
    decode_bed(&bytes).map_err(|e| BedFileError::InFile {
        path: path.to_path_buf(),
        cause: Box::new(e),
    })
}

/// Decodes the bytes of a native bed file (never panics, bounded allocation).
pub fn decode_bed(bytes: &[u8]) -> Result<BedFile, BedFileError> {
    let f: BedFile = checkpoint::decode(bytes, BED_KIND, None).map_err(|e| match e {
        CheckpointError::NotCheckpoint => BedFileError::NotBedFile,
        e => BedFileError::Framing(e),
    })?;
    f.bed.validate()?;
    Ok(f)
}
