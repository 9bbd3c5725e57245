//! Errors of a scenario's inputs that name the key they come from: a value out of range
//! ([`pdamp_dem::ParameterError`]) or a file a key names that cannot be read or used. The
//! cause of a wrapped error is part of the message (not `source()`), so that a chain printer
//! (`anyhow`'s `{:#}`) shows it once. File-level
//! errors (which scenario file, which line) are [`crate::schema::ScenarioError`].

use pdamp_dem::ParameterError;
use std::path::PathBuf;

/// A boxed error of another kind (CSV, STL, bed format, packing, …) kept as the source.
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

/// An input of a scenario cannot be used; the message starts with the key.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// A value out of range or not fitting the others.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The TOML text does not parse or does not fit the schema (serde names key, line, column).
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// The file a key names cannot be read.
    #[error("{key}: cannot read '{}': {cause}", path.display())]
    Read {
        /// The key that names the file.
        key: String,
        /// The file.
        path: PathBuf,
        /// Cause.
        cause: std::io::Error,
    },
    /// The file a key names was read but cannot be used.
    #[error("{key}: '{}': {cause}", path.display())]
    File {
        /// The key that names the file.
        key: String,
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        cause: Source,
    },
    /// What a key describes cannot be built (a packing that does not fit, a bed that does not
    /// match its group, …).
    #[error("{key}: {cause}{hint}")]
    At {
        /// The key.
        key: String,
        /// Cause.
        cause: Source,
        /// How to fix it (empty, or starting with `; `).
        hint: String,
    },
}

impl InputError {
    /// [`InputError::At`].
    pub fn at(key: impl Into<String>, source: impl Into<Source>) -> Self {
        Self::At {
            key: key.into(),
            cause: source.into(),
            hint: String::new(),
        }
    }

    /// [`InputError::At`] with a hint how to fix it (`; enlarge the region, …`).
    pub fn at_with_hint(
        key: impl Into<String>,
        source: impl Into<Source>,
        hint: impl Into<String>,
    ) -> Self {
        Self::At {
            key: key.into(),
            cause: source.into(),
            hint: hint.into(),
        }
    }

    /// [`InputError::File`].
    pub fn file(
        key: impl Into<String>,
        path: impl Into<PathBuf>,
        source: impl Into<Source>,
    ) -> Self {
        Self::File {
            key: key.into(),
            path: path.into(),
            cause: source.into(),
        }
    }

    /// [`InputError::Read`].
    pub fn read(key: impl Into<String>, path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Read {
            key: key.into(),
            path: path.into(),
            cause: source,
        }
    }

    /// A message that starts with the key it is about ([`ParameterError::from_message`]).
    pub fn message(message: impl Into<String>) -> Self {
        Self::Parameter(ParameterError::from_message(message))
    }

    /// The key the error is about (empty for a TOML error, whose message has line and column).
    pub fn key(&self) -> &str {
        match self {
            Self::Parameter(e) => e.key(),
            Self::Toml(_) => "",
            Self::Read { key, .. } | Self::File { key, .. } | Self::At { key, .. } => key,
        }
    }
}

/// Why a run (or its settling) stopped without finishing; [`RunError::Interrupted`] is a stop
/// on request after the checkpoint was written.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario's world cannot be built.
    #[error(transparent)]
    Input(#[from] crate::InputError),
    /// A checkpoint cannot be written or read back.
    #[error(transparent)]
    Checkpoint(#[from] pdamp_io::checkpoint::CheckpointError),
    /// The checkpoint does not fit the scenario's world.
    #[error(transparent)]
    State(#[from] pdamp_dem::state::StateError),
    /// A checkpoint of a running phase without the world's state.
    #[error("checkpoint without state")]
    NoState,
    /// An output file cannot be written.
    #[error("output: {0}")]
    Output(crate::error::Source),
    /// A ParaView file or series cannot be written or continued.
    #[error(transparent)]
    Vtk(#[from] pdamp_io::vtk::VtkError),
    /// The summary of a finished run cannot be read back.
    #[error("summary.json: {0}")]
    Summary(serde_json::Error),
    /// A result does not serialise.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// Stopped on request; the checkpoint is on disk (the text starts with
    /// [`pdamp_io::checkpoint::INTERRUPTED`]).
    #[error(transparent)]
    Interrupted(#[from] pdamp_io::checkpoint::Interrupted),
    /// A health check failed; `failure.json` names the particle.
    #[error(
        "{health} (during {phase}; outputs written so far are kept in {}, see failure.json)",
        out_dir.display()
    )]
    Failed {
        /// What the check found.
        health: pdamp_dem::health::HealthError,
        /// `settling` or `running`.
        phase: &'static str,
        /// The output directory.
        out_dir: PathBuf,
    },
}

impl RunError {
    /// [`RunError::Output`].
    pub fn output(e: impl Into<crate::error::Source>) -> Self {
        Self::Output(e.into())
    }

    /// Whether the run was stopped on request with its checkpoint written.
    pub fn is_interrupted(&self) -> bool {
        matches!(self, Self::Interrupted(_))
    }
}
