//! Typed errors of the design optimiser.

use std::path::PathBuf;

/// What went wrong in a design study.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// A key of the study file is missing, out of range or inconsistent; `key` is its dotted
    /// path in the file (e.g. `damper.particle_radii_m[1]`).
    #[error("{path}: {key}: {message}")]
    Input {
        /// The study file.
        path: PathBuf,
        /// Dotted key.
        key: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// The study file or its scenario cannot be read or parsed.
    #[error("{0}")]
    Load(String),
    /// The structure or a solver refused a design (unknown point, unstable step, …).
    #[error("{0}")]
    Solver(String),
    /// The structure level refused a design or its input.
    #[error(transparent)]
    Structure(Box<pdamp_structure::StructureError>),
    /// The structure level refused the scenario file `path` (or a run of it).
    #[error("{}: {error}", path.display())]
    StructureFile {
        /// The scenario file.
        path: PathBuf,
        /// The structure level's error (its text is in the message, so it is no `source()`).
        error: Box<pdamp_structure::StructureError>,
    },
    /// No design satisfies the constraints.
    #[error("no design satisfies the constraints: {0}")]
    Empty(String),
    /// Writing the results failed (nothing partial is left: every file is written atomically).
    #[error("writing {path}: {message}")]
    Output {
        /// The file.
        path: PathBuf,
        /// The cause.
        message: String,
    },
}

impl From<pdamp_structure::StructureError> for DesignError {
    fn from(e: pdamp_structure::StructureError) -> Self {
        DesignError::Structure(Box::new(e))
    }
}

impl DesignError {
    pub(crate) fn output(path: impl Into<PathBuf>, e: impl std::fmt::Display) -> Self {
        DesignError::Output {
            path: path.into(),
            message: e.to_string(),
        }
    }
}
