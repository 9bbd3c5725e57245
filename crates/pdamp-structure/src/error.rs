//! Typed errors of pdamp-structure (issue 30): [`StructureError`] for the scenario, the
//! structure models, the couplings and the reports; the finite elements have
//! [`crate::fe::FeError`], the sparse solver [`crate::sparse::SparseError`], the readers
//! [`crate::matrix_market::MatrixMarketError`] and the time integration
//! [`crate::integrate::IntegrationError`], all convertible into [`StructureError`].

use crate::fe::FeError;
use crate::integrate::IntegrationError;
use crate::matrix_market::MatrixMarketError;
use crate::sparse::SparseError;
use std::path::{Path, PathBuf};

/// What went wrong in the structural level. The text of every variant is the message the
/// library printed before the errors were typed.
#[derive(Debug, thiserror::Error)]
pub enum StructureError {
    /// A key (or a named part of the model) is missing, out of range or inconsistent:
    /// `key: message`.
    #[error("{key}: {message}")]
    Invalid {
        /// The key path (`dampers[0].point`) or the part of the model (`mode 2`).
        key: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A key violates a rule stated as a sentence about it: `key message` (the message starts
    /// with `must`, `is`, `needs`, …).
    #[error("{key} {message}")]
    Rule {
        /// The key path.
        key: String,
        /// The rest of the sentence.
        message: String,
    },
    /// A number of the input is not finite.
    #[error("{key} must be a finite number {expected}, got {value}")]
    NotFinite {
        /// The key path.
        key: String,
        /// The wanted range (`in (0, 1e4] m`), possibly empty.
        expected: String,
        /// The value given.
        value: f64,
    },
    /// A number of the input is out of its range.
    #[error("{key} must be {expected}, got {value:e}")]
    OutOfRange {
        /// The key path.
        key: String,
        /// The wanted range (`in (0, 1e4] m`).
        expected: String,
        /// The value given.
        value: f64,
    },
    /// A count of the input is out of its range.
    #[error("{key} must be an integer in [{lo}, {hi}], got {value}")]
    Count {
        /// The key path.
        key: String,
        /// The value given.
        value: usize,
        /// Smallest allowed value.
        lo: usize,
        /// Largest allowed value.
        hi: usize,
    },
    /// A position along the beam lies outside it.
    #[error(
        "{key} = {value} m lies outside the beam [0, {length_m}] m (structure.beam.length_m = \
         {length_m}); positions are measured from the beam's start, give one in [0, \
         {length_m}] m"
    )]
    OffBeam {
        /// The key path.
        key: String,
        /// The position given, m.
        value: f64,
        /// The beam's length, m.
        length_m: f64,
    },
    /// Values that are inconsistent together; the message names the keys involved.
    #[error("{0}")]
    Inconsistent(String),
    /// The point of a powder-friction damper is a node of the analysed mode.
    #[error("powder_friction: point '{point}' is a node of mode {mode} (φ/X undefined)")]
    NodeOfMode {
        /// The damper's point.
        point: String,
        /// The mode (1-based).
        mode: usize,
    },
    /// No point of the structure has this name.
    #[error("no structure point named '{name}' (known: {known:?})")]
    UnknownPoint {
        /// The name asked for.
        name: String,
        /// The names of the structure's points.
        known: Vec<String>,
    },
    /// The model is too large for the dense eigen solver.
    #[error(
        "{dofs} dof: the dense modal solver is limited to {max} dof (use solver = \"sparse\" or \
         \"auto\")"
    )]
    DenseLimit {
        /// Active dofs of the model.
        dofs: usize,
        /// The dense solver's limit.
        max: usize,
    },
    /// A numerical method failed (singular factor, no convergence, empty model, …).
    #[error("{0}")]
    Numerical(String),
    /// An error with the context it happened in (`DEM bed 1 at 'tip'`, a file name, a key).
    #[error("{context}: {error}")]
    Context {
        /// Where it happened.
        context: String,
        /// The error.
        error: Box<StructureError>,
    },
    /// A file could not be read.
    #[error("{}: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// A TOML file does not parse or does not fit the schema.
    #[error("{}: {error}", path.display())]
    Toml {
        /// The file.
        path: PathBuf,
        /// The TOML parser's error (key, line and column).
        error: toml::de::Error,
    },
    /// A Matrix Market or dof-map file of `structure.matrix_market.<key>` is unreadable or
    /// malformed.
    #[error("structure.matrix_market.{key}{}: {error}", quoted(path.as_deref()))]
    MatrixMarketFile {
        /// `stiffness`, `mass` or `dof_map`.
        key: &'static str,
        /// The file, when the error is not an I/O error (which names it already).
        path: Option<PathBuf>,
        /// The reader's error.
        error: MatrixMarketError,
    },
    /// The integration settings of a coupled DEM run are invalid (its time step is the damper
    /// scenario's).
    #[error("{error} (the time step is the damper scenario's)")]
    DemTimeStep {
        /// The settings error.
        error: IntegrationError,
    },
    /// The load of a DEM bed on the structure became non-finite.
    #[error(
        "numerical failure at t = {time_s:e} s: the load of DEM bed {bed} ('{point}') on the \
         structure became non-finite (bed kinetic energy {kinetic_j:e} J); likely cause: the \
         damper scenario's time step {time_step_s:e} s against its contact stiffness (check it \
         with `pdamp check`)"
    )]
    BedLoadNonFinite {
        /// Time, s.
        time_s: f64,
        /// The bed (1-based).
        bed: usize,
        /// The bed's structure point.
        point: String,
        /// The bed's kinetic energy, J.
        kinetic_j: f64,
        /// The damper scenario's time step, s.
        time_step_s: f64,
    },
    /// A run stopped on request after its checkpoint was written.
    #[error("{0}")]
    Interrupted(pdamp_io::checkpoint::Interrupted),
    /// A located error of a scenario or structure file (line and column of the key).
    #[error("{0}")]
    Scenario(pdamp_scenario::schema::ScenarioError),
    /// A Matrix Market reader error or a check of K and M.
    #[error(transparent)]
    MatrixMarket(#[from] MatrixMarketError),
    /// A finite-element model error.
    #[error(transparent)]
    Fe(#[from] FeError),
    /// A sparse solver error.
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// An integration setting or a numerical failure of the time integration.
    #[error(transparent)]
    Integration(#[from] IntegrationError),
    /// A CSV file could not be parsed or written.
    #[error("{0}")]
    Csv(pdamp_io::csv::CsvError),
    /// A plot could not be written.
    #[error("{0}")]
    Plot(pdamp_plot::PlotError),
    /// An I/O error (creating the output folder, writing a file).
    #[error("{0}")]
    Io(std::io::Error),
    /// A JSON value could not be written.
    #[error("{0}")]
    Json(serde_json::Error),
    /// A checkpoint cannot be written or read back (pdamp-io).
    #[error(transparent)]
    Checkpoint(#[from] pdamp_io::checkpoint::CheckpointError),
    /// The VTK frames of a coupled run cannot be written (pdamp-io; boxed: a run error carries
    /// a whole health report).
    #[error(transparent)]
    Snapshots(Box<pdamp_scenario::run::RunError>),
    /// A checkpoint's world state does not fit the scenario's bed (pdamp-dem).
    #[error(transparent)]
    State(#[from] pdamp_dem::state::StateError),
    /// A damper's bed cannot be made (pdamp-design).
    #[error(transparent)]
    Design(Box<pdamp_design::DesignError>),
    /// A signal-processing error (peak search).
    #[error("{0}")]
    Signal(pdamp_signal::SignalError),
}

fn quoted(path: Option<&Path>) -> String {
    match path {
        Some(p) => format!(" '{}'", p.display()),
        None => String::new(),
    }
}

impl From<pdamp_scenario::run::RunError> for StructureError {
    fn from(e: pdamp_scenario::run::RunError) -> Self {
        StructureError::Snapshots(Box::new(e))
    }
}

impl StructureError {
    /// [`StructureError::Invalid`]: `key: message`.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        StructureError::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }

    /// [`StructureError::Rule`]: `key message`.
    pub fn rule(key: impl Into<String>, message: impl Into<String>) -> Self {
        StructureError::Rule {
            key: key.into(),
            message: message.into(),
        }
    }

    /// [`StructureError::Inconsistent`].
    pub fn inconsistent(message: impl Into<String>) -> Self {
        StructureError::Inconsistent(message.into())
    }

    /// [`StructureError::Numerical`].
    pub fn numerical(message: impl Into<String>) -> Self {
        StructureError::Numerical(message.into())
    }

    /// This error within `context`: `context: self`.
    pub fn context(self, context: impl Into<String>) -> Self {
        StructureError::Context {
            context: context.into(),
            error: Box::new(self),
        }
    }

    /// [`StructureError::Read`].
    pub fn read(path: &Path, source: std::io::Error) -> Self {
        StructureError::Read {
            path: path.to_path_buf(),
            error: source,
        }
    }

    /// [`StructureError::Toml`].
    pub fn toml(path: &Path, source: toml::de::Error) -> Self {
        StructureError::Toml {
            path: path.to_path_buf(),
            error: source,
        }
    }

    /// This error located in the scenario or structure file `path` (its text `text`, when
    /// read): [`StructureError::Scenario`] with the line and column of the key the message
    /// starts with.
    pub fn located(self, path: &Path, text: Option<&str>) -> Self {
        pdamp_scenario::schema::ScenarioError::invalid(path, text, self.to_string()).into()
    }
}

// Errors of other crates are kept as values, not as `source()`: every message above already
// contains the wrapped error's text, and a chain printed by `anyhow`'s `{:#}` (the CLI) would
// repeat it.
macro_rules! wrap {
    ($($variant:ident($ty:ty)),* $(,)?) => {
        $(impl From<$ty> for StructureError {
            fn from(e: $ty) -> Self {
                StructureError::$variant(e)
            }
        })*
    };
}

wrap!(
    Scenario(pdamp_scenario::schema::ScenarioError),
    Csv(pdamp_io::csv::CsvError),
    Plot(pdamp_plot::PlotError),
    Io(std::io::Error),
    Json(serde_json::Error),
    Signal(pdamp_signal::SignalError),
);
