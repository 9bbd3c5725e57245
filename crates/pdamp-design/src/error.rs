//! Typed errors of the design level (issue 30): damper points, effective fields, their outputs
//! and plots.
//!
//! Three kinds of errors steer the runs: an `output:` error (a file that cannot be written)
//! ends a field at once, an interruption (Ctrl-C/SIGTERM) leaves the unfinished points to the
//! next run, and every other error fails only its point ([`DesignError::is_output`],
//! [`DesignError::is_interrupted`]).

use pdamp_io::checkpoint::INTERRUPTED;
use std::path::PathBuf;
use std::sync::Arc;

/// What can go wrong at the design level; the variants name the scenario key, file, excitation
/// point, packing or plot they come from.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// The scenario has no `[damper]` section.
    #[error("scenario has no [damper] section")]
    NoDamperSection,
    /// The scenario has no `[fields]` section.
    #[error("scenario has no [fields] section")]
    NoFieldsSection,
    /// `damper.container_body` names no body of the scenario.
    #[error("damper.container_body: no body '{body}'")]
    NoContainerBody {
        /// The name given.
        body: String,
    },
    /// `pdamp run` of a damper scenario needs `damper.frequency_hz`.
    #[error("damper.frequency_hz is needed for `pdamp run`")]
    NoFrequency,
    /// The damper's single point has no (or more than one) amplitude.
    #[error("damper: give one of amplitude_m, acceleration_m_s2, intensity")]
    NoAmplitude,
    /// The `[fields]` section has no or more than one amplitude axis.
    #[error("fields: give exactly one amplitude axis")]
    AmplitudeAxis,
    /// A checkpoint to resume holds a point that is finished already.
    #[error("checkpoint {}: the point is finished already", path.display())]
    CheckpointFinished {
        /// The checkpoint file.
        path: PathBuf,
    },
    /// A checkpoint to resume belongs to another excitation point.
    #[error("checkpoint: written for f = {frequency_hz} Hz, X = {amplitude_m} m, not this point")]
    CheckpointOtherPoint {
        /// Frequency of the checkpoint's point, Hz.
        frequency_hz: f64,
        /// Displacement amplitude of the checkpoint's point, m.
        amplitude_m: f64,
    },
    /// The velocity-field grid of a checkpoint's motion recorder differs from the scenario's.
    #[error("checkpoint: the velocity-field grid differs from the scenario's")]
    CheckpointFieldGrid,
    /// The health check of the DEM world failed during a point.
    #[error("f = {frequency_hz} Hz, X = {amplitude_m:.4e} m, cycle {cycle}: {source}")]
    Health {
        /// Excitation frequency, Hz.
        frequency_hz: f64,
        /// Displacement amplitude, m.
        amplitude_m: f64,
        /// Cycle in progress (from 1).
        cycle: u32,
        /// The diagnosis.
        #[source]
        source: pdamp_dem::health::HealthError,
    },
    /// The kinetic energy of the bed became non-finite during a point.
    #[error(
        "f = {frequency_hz} Hz, X = {amplitude_m:.4e} m: the simulation became unstable in cycle {cycle} \
         (non-finite kinetic energy). Reduce simulation.time_step_s, or for the Gonthier and \
         Lankarani–Nikravesh laws raise min_impact_velocity_m_s: enduring contacts created at rest \
         get a damping coefficient ∝ 1/min_impact_velocity_m_s that a fixed explicit step cannot follow"
    )]
    Unstable {
        /// Excitation frequency, Hz.
        frequency_hz: f64,
        /// Displacement amplitude, m.
        amplitude_m: f64,
        /// Cycle in progress (from 1).
        cycle: u32,
    },
    /// A point was stopped by Ctrl-C/SIGTERM (its checkpoint, if any, is written).
    #[error(
        "{INTERRUPTED}: point f = {frequency_hz} Hz, X = {amplitude_m:.4e} m stopped in cycle {cycle}"
    )]
    PointInterrupted {
        /// Excitation frequency, Hz.
        frequency_hz: f64,
        /// Displacement amplitude, m.
        amplitude_m: f64,
        /// Cycle in progress (from 1).
        cycle: u32,
    },
    /// A point of a sweep task was not started because a stop was requested.
    #[error("{INTERRUPTED}")]
    Interrupted,
    /// A field was interrupted: the finished points are stored.
    #[error(
        "{INTERRUPTED}: {finished} of {total} points are finished and stored in {}; run the same \
         command again to compute the other {interrupted}",
        dir.display()
    )]
    FieldInterrupted {
        /// Points finished (stored).
        finished: usize,
        /// Points of the grid.
        total: usize,
        /// Points interrupted.
        interrupted: usize,
        /// The store (`points/`).
        dir: PathBuf,
    },
    /// The complex power of a point could not be evaluated.
    #[error("complex power at f = {frequency_hz} Hz, X = {amplitude_m} m: {source}")]
    ComplexPower {
        /// Excitation frequency, Hz.
        frequency_hz: f64,
        /// Displacement amplitude, m.
        amplitude_m: f64,
        /// The cause.
        #[source]
        source: pdamp_signal::SignalError,
    },
    /// Collecting a field from its store: some points are not finished.
    #[error(
        "{}: {missing} of {total} points are not finished: {}{}",
        dir.display(),
        shown.join("; "),
        if *missing > shown.len() { "; …" } else { "" }
    )]
    NotFinished {
        /// The store (`points/`).
        dir: PathBuf,
        /// Points not finished.
        missing: usize,
        /// Points of the grid.
        total: usize,
        /// The first few of them (point and slot, or why its file is unusable).
        shown: Vec<String>,
    },
    /// A point of a sweep task is not on the grid.
    #[error("grid point {index} does not exist: the grid has {points} points")]
    NoGridPoint {
        /// The index asked for.
        index: usize,
        /// Points of the grid.
        points: usize,
    },
    /// A field's output directory holds the points of another scenario.
    #[error(
        "{}: holds points of a different scenario (see {}); use another --out or delete its points/ folder",
        out.display(),
        fingerprint.display()
    )]
    OtherScenario {
        /// The output directory.
        out: PathBuf,
        /// The file with the physics of the stored points.
        fingerprint: PathBuf,
    },
    /// The error a failed point left in its store (`fIII_aJJJ.error.txt`).
    #[error("{0}")]
    StoredFailure(String),
    /// GPU points: the dampers of one batch have different cycle counts.
    #[error(
        "GPU points: point {point} has {cycles}/{transient_cycles} cycles/transient cycles, point 0 {cycles0}/{transient_cycles0}; one batch runs one cycle count"
    )]
    GpuCycles {
        /// Index of the point in the batch.
        point: usize,
        /// Its cycles.
        cycles: u32,
        /// Its transient cycles.
        transient_cycles: u32,
        /// Cycles of point 0.
        cycles0: u32,
        /// Transient cycles of point 0.
        transient_cycles0: u32,
    },
    /// An excitation point with a non-positive or non-finite frequency or amplitude.
    #[error("excitation point f = {frequency_hz} Hz, X = {amplitude_m} m is not valid")]
    InvalidPoint {
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Displacement amplitude, m.
        amplitude_m: f64,
    },
    /// The GPU backend failed.
    #[cfg(feature = "gpu")]
    #[error(transparent)]
    Gpu(#[from] pdamp_gpu::GpuError),
    /// The GPU backend failed while a batch of points ran.
    #[cfg(feature = "gpu")]
    #[error("GPU batch of {points} points, cycle {cycle}: {source}")]
    GpuRun {
        /// Points of the batch.
        points: usize,
        /// Cycle in progress (from 1).
        cycle: u32,
        /// The cause.
        #[source]
        source: pdamp_gpu::GpuError,
    },
    /// A GPU point without evaluated cycles.
    #[error("point {point}: no evaluated cycles")]
    NoEvaluatedCycles {
        /// Index of the point in the batch.
        point: usize,
    },
    /// The error of a whole GPU batch, shared by each of its points.
    #[error(transparent)]
    Batch(Arc<DesignError>),
    /// An output file or directory cannot be written.
    #[error("output: {source}")]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A CSV output cannot be written.
    #[error("output: {source}")]
    WriteCsv {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: pdamp_io::csv::CsvError,
    },
    /// `summary.json` of a finished run cannot be read.
    #[error("output: {}: {source}", path.display())]
    ReadSummary {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A VTK frame of the motion recorder could not be written (the first such error).
    #[error("output: {0}")]
    VtkFrames(String),
    /// The series file `particles.pvd` cannot be written.
    #[error("{source}")]
    Pvd {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: pdamp_io::vtk::VtkError,
    },
    /// A result cannot be serialised to JSON.
    #[error("{0}")]
    Json(#[from] serde_json::Error),
    /// A plot cannot be drawn or written.
    #[error("plot: {source}")]
    Plot {
        /// The file stem of the plot.
        stem: PathBuf,
        /// The cause.
        #[source]
        source: pdamp_plot::PlotError,
    },
    /// The bed cannot be prepared or a prepared bed read back.
    #[error(transparent)]
    Prepare(#[from] pdamp_scenario::prepare::PrepareError),
    /// A point's checkpoint cannot be written or read back.
    #[error(transparent)]
    Checkpoint(#[from] pdamp_io::checkpoint::CheckpointError),
    /// A prepared bed cannot be saved.
    #[error("output: {0}")]
    IoOutput(pdamp_io::checkpoint::CheckpointError),
    /// A checkpoint's world state does not fit the scenario.
    #[error(transparent)]
    State(#[from] pdamp_dem::state::StateError),
}

impl DesignError {
    /// The text of a stored failure (a point's error read back from its file, known only by
    /// its text).
    fn foreign_text(&self) -> Option<&str> {
        match self {
            DesignError::StoredFailure(s) => Some(s),
            _ => None,
        }
    }

    /// An `output:` error: a file or directory that cannot be written (or read back). It ends a
    /// field or ensemble at once and is never stored as the error of a point.
    pub fn is_output(&self) -> bool {
        match self {
            DesignError::Write { .. }
            | DesignError::WriteCsv { .. }
            | DesignError::ReadSummary { .. }
            | DesignError::VtkFrames(_)
            | DesignError::IoOutput(_)
            | DesignError::Prepare(pdamp_scenario::prepare::PrepareError::Output(_)) => true,
            DesignError::Batch(e) => e.is_output(),
            e => e.foreign_text().is_some_and(|s| s.starts_with("output:")),
        }
    }

    /// An interruption (Ctrl-C/SIGTERM, see [`pdamp_io::checkpoint::INTERRUPTED`]): the run
    /// can be continued; it is never stored as the error of a point.
    pub fn is_interrupted(&self) -> bool {
        match self {
            DesignError::PointInterrupted { .. }
            | DesignError::Interrupted
            | DesignError::FieldInterrupted { .. } => true,
            DesignError::Batch(e) => e.is_interrupted(),
            DesignError::Prepare(e) => e.to_string().starts_with(INTERRUPTED),
            e => e.foreign_text().is_some_and(|s| s.starts_with(INTERRUPTED)),
        }
    }

    /// An error of a point's checkpoint (unreadable, foreign, finished, or a state that does
    /// not fit): the point can start again without it.
    pub fn is_checkpoint(&self) -> bool {
        match self {
            DesignError::CheckpointFinished { .. }
            | DesignError::CheckpointOtherPoint { .. }
            | DesignError::CheckpointFieldGrid
            | DesignError::Checkpoint(_)
            | DesignError::State(_) => true,
            DesignError::Batch(e) => e.is_checkpoint(),
            e => e
                .foreign_text()
                .is_some_and(|s| s.starts_with("checkpoint")),
        }
    }

    pub(crate) fn write(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| DesignError::Write { path, source }
    }

    pub(crate) fn write_csv(
        path: impl Into<PathBuf>,
    ) -> impl FnOnce(pdamp_io::csv::CsvError) -> Self {
        let path = path.into();
        move |source| DesignError::WriteCsv { path, source }
    }

    pub(crate) fn plot(stem: impl Into<PathBuf>) -> impl FnOnce(pdamp_plot::PlotError) -> Self {
        let stem = stem.into();
        move |source| DesignError::Plot { stem, source }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texts_are_those_of_the_string_errors() {
        let e = DesignError::PointInterrupted {
            frequency_hz: 20.0,
            amplitude_m: 1e-3,
            cycle: 3,
        };
        assert_eq!(
            e.to_string(),
            "interrupted: point f = 20 Hz, X = 1.0000e-3 m stopped in cycle 3"
        );
        assert!(e.is_interrupted() && !e.is_output());
        let e = DesignError::FieldInterrupted {
            finished: 4,
            total: 9,
            interrupted: 2,
            dir: PathBuf::from("out/points"),
        };
        assert_eq!(
            e.to_string(),
            "interrupted: 4 of 9 points are finished and stored in out/points; run the same \
             command again to compute the other 2"
        );
        assert_eq!(DesignError::Interrupted.to_string(), "interrupted");
        let shown: Vec<String> = (0..5).map(|k| format!("p{k}")).collect();
        let e = DesignError::NotFinished {
            dir: PathBuf::from("d/points"),
            missing: 7,
            total: 9,
            shown: shown.clone(),
        };
        assert_eq!(
            e.to_string(),
            "d/points: 7 of 9 points are not finished: p0; p1; p2; p3; p4; …"
        );
        let e = DesignError::NotFinished {
            dir: PathBuf::from("d/points"),
            missing: 5,
            total: 9,
            shown,
        };
        assert_eq!(
            e.to_string(),
            "d/points: 5 of 9 points are not finished: p0; p1; p2; p3; p4"
        );
        let e = DesignError::Write {
            path: PathBuf::from("x"),
            source: std::io::Error::other("disk full"),
        };
        assert_eq!(e.to_string(), "output: disk full");
        assert!(e.is_output() && !e.is_interrupted());
        let e = DesignError::OtherScenario {
            out: PathBuf::from("o"),
            fingerprint: PathBuf::from("o/points/scenario_physics.toml"),
        };
        assert_eq!(
            e.to_string(),
            "o: holds points of a different scenario (see o/points/scenario_physics.toml); use \
             another --out or delete its points/ folder"
        );
        let e = DesignError::CheckpointFinished {
            path: PathBuf::from("c.bin"),
        };
        assert_eq!(
            e.to_string(),
            "checkpoint c.bin: the point is finished already"
        );
        assert!(e.is_checkpoint());
    }

    #[test]
    fn wrapped_texts_keep_their_kind() {
        use pdamp_scenario::prepare::PrepareError;
        let no_space = std::io::Error::other("no space");
        let e = DesignError::Prepare(PrepareError::Output(no_space.into()));
        assert!(e.is_output() && !e.is_checkpoint());
        assert_eq!(e.to_string(), "output: no space");
        let e = DesignError::State(pdamp_dem::state::StateError::ParticleCount {
            checkpoint: 3,
            scenario: 4,
        });
        assert!(e.is_checkpoint() && !e.is_output());
        assert_eq!(
            e.to_string(),
            "checkpoint has 3 particles, the scenario builds 4"
        );
        let e = DesignError::Checkpoint(pdamp_io::checkpoint::CheckpointError::Damaged);
        assert!(e.is_checkpoint() && !e.is_interrupted());
        let bad = pdamp_scenario::InputError::message("scenario.x: bad key");
        assert!(!DesignError::Prepare(PrepareError::Input(bad)).is_output());
        let shared = DesignError::Batch(Arc::new(DesignError::Interrupted));
        assert!(shared.is_interrupted());
        assert_eq!(shared.to_string(), "interrupted");
        assert_eq!(
            DesignError::NoDamperSection.to_string(),
            "scenario has no [damper] section"
        );
    }
}
