//! Sweeps: grids of independent simulations (the points of an effective field, the packings of
//! an ensemble) run as tasks, here or on a cluster, and collected into the outputs of a local
//! run.
//!
//! A sweep is a directory — the output directory of the command it belongs to — holding
//! * the manifest `sweep.json` ([`SweepManifest`]): what kind of sweep, the scenario (a copy in
//!   `sweep/scenario.toml` and the digest of its content and of every file it reads) and the
//!   list of tasks, each with the file it leaves when finished and the file of its error;
//! * the store of finished tasks: one file per task, written atomically when the task ends
//!   (for a field: `points/fIII_aJJJ.json`, as a local `pdamp fields` run writes), so a killed
//!   or preempted task loses nothing that was finished and a task that runs again skips what is
//!   stored; a task that fails writes its error next to its slot;
//! * `sweep/submissions.json` ([`Submission`]): what was submitted where (Slurm array jobs
//!   and which tasks each array element runs), for [`status`] and resubmission;
//! * `sweep/slurm/*.sh` and `sweep/logs/` of the Slurm backend ([`slurm`]).
//!
//! The crate knows nothing of the physics: the command that owns a sweep kind builds the task
//! list, runs a task and collects; this crate keeps the directory, plans and submits the
//! Slurm arrays and tells the state of every task.

#![forbid(unsafe_code)]

pub mod slurm;
pub mod status;

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Format number of `sweep.json`.
pub const SWEEP_FORMAT: u32 = 1;
/// File name of the manifest in a sweep directory.
pub const MANIFEST_FILE: &str = "sweep.json";
/// Folder of the sweep's own files in a sweep directory.
pub const SWEEP_FOLDER: &str = "sweep";
/// The scenario as the sweep runs it (a copy made when the sweep was created).
pub const SCENARIO_COPY: &str = "sweep/scenario.toml";
/// Record of the submissions.
pub const SUBMISSIONS_FILE: &str = "sweep/submissions.json";

/// Errors of the sweep layer. Messages name the directory, file or task.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file of the sweep cannot be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// `sweep.json` or `submissions.json` is damaged or of another format.
    #[error("{path}: {why}")]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Why.
        why: String,
    },
    /// The directory is not a sweep.
    #[error(
        "{0}: not a sweep directory (no sweep.json); make one with `pdamp fields SCENARIO --out DIR --backend slurm` or `pdamp sweep new SCENARIO --out DIR`"
    )]
    NotASweep(PathBuf),
    /// The directory is a sweep of another scenario.
    #[error(
        "{dir}: holds a sweep of another scenario ({existing}, digest {existing_digest}), not of {new} (digest {new_digest}); use another --out directory or delete this one"
    )]
    OtherScenario {
        /// The sweep directory.
        dir: PathBuf,
        /// The scenario of the sweep in it.
        existing: PathBuf,
        /// Its digest.
        existing_digest: String,
        /// The scenario given now.
        new: PathBuf,
        /// Its digest.
        new_digest: String,
    },
    /// A task index outside the sweep.
    #[error("task {index} does not exist: the sweep in {dir} has {count} tasks (0 … {})", count.saturating_sub(1))]
    NoSuchTask {
        /// The sweep directory.
        dir: PathBuf,
        /// The index asked for.
        index: usize,
        /// Number of tasks.
        count: usize,
    },
    /// Slurm refused or is missing.
    #[error("{0}")]
    Slurm(String),
    /// Bad options.
    #[error("{0}")]
    Options(String),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> SweepError + '_ {
    move |source| SweepError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// One task of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Task {
    /// Position in the manifest's task list (what `pdamp sweep task DIR --index I` runs).
    pub index: usize,
    /// What it computes, for people (e.g. `bed of packing 0`, `f = 40 Hz, Γ = 1`).
    pub label: String,
    /// Tasks whose results it reads (a point needs its packing's bed); a task runs them itself
    /// when they are not finished, so an order is a saving, not a condition.
    pub needs: Vec<usize>,
    /// Its result file, relative to the sweep directory.
    pub result: PathBuf,
    /// Its error file (written when it fails), relative to the sweep directory.
    pub error: PathBuf,
}

/// The manifest of a sweep (`sweep.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepManifest {
    /// [`SWEEP_FORMAT`] of the writer.
    pub format: u32,
    /// pdamp version of the writer.
    pub pdamp_version: String,
    /// Kind of sweep (`fields`).
    pub kind: String,
    /// Title of the scenario.
    pub title: String,
    /// The scenario file the sweep was made from (absolute).
    pub scenario_source: PathBuf,
    /// Directory against which the scenario's relative paths (meshes, tables, beds) resolve
    /// (absolute; on a cluster it must be on the shared file system).
    pub base_dir: PathBuf,
    /// Digest of the scenario and of the content of every file it reads: a task refuses to run
    /// when they changed since the sweep was made.
    pub scenario_digest: String,
    /// What the kind needs besides the scenario to rebuild its tasks (a study's parameter,
    /// values and packings); `null` for a field.
    #[serde(default)]
    pub parameters: serde_json::Value,
    /// The tasks.
    pub tasks: Vec<Task>,
}

impl SweepManifest {
    /// Path of the manifest in `dir`.
    pub fn path(dir: &Path) -> PathBuf {
        dir.join(MANIFEST_FILE)
    }

    /// Reads the manifest of the sweep in `dir`.
    pub fn load(dir: &Path) -> Result<Self, SweepError> {
        let path = Self::path(dir);
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(SweepError::NotASweep(dir.to_path_buf()));
            }
            Err(e) => return Err(io_err(&path)(e)),
        };
        let m: SweepManifest = serde_json::from_str(&text).map_err(|e| SweepError::Damaged {
            path: path.clone(),
            why: format!("unreadable ({e})"),
        })?;
        if m.format != SWEEP_FORMAT {
            return Err(SweepError::Damaged {
                path,
                why: format!(
                    "sweep format {} (pdamp {}), this pdamp reads format {SWEEP_FORMAT}",
                    m.format, m.pdamp_version
                ),
            });
        }
        if let Some((k, t)) = m.tasks.iter().enumerate().find(|(k, t)| t.index != *k) {
            return Err(SweepError::Damaged {
                path,
                why: format!("task {k} has index {}", t.index),
            });
        }
        Ok(m)
    }

    /// Creates the sweep in `dir` (manifest and the scenario copy), or opens the one there when
    /// it is of the same scenario (same digest and kind); a sweep of another scenario is
    /// refused ([`SweepError::OtherScenario`]) and nothing in `dir` changes.
    pub fn create_or_open(
        dir: &Path,
        manifest: SweepManifest,
        scenario_text: &str,
    ) -> Result<Self, SweepError> {
        match Self::load(dir) {
            Ok(existing) => {
                if existing.scenario_digest != manifest.scenario_digest
                    || existing.kind != manifest.kind
                    || existing.parameters != manifest.parameters
                    || existing.tasks != manifest.tasks
                {
                    return Err(SweepError::OtherScenario {
                        dir: dir.to_path_buf(),
                        existing: existing.scenario_source,
                        existing_digest: existing.scenario_digest,
                        new: manifest.scenario_source,
                        new_digest: manifest.scenario_digest,
                    });
                }
                Ok(existing)
            }
            Err(SweepError::NotASweep(_)) => {
                let folder = dir.join(SWEEP_FOLDER);
                std::fs::create_dir_all(&folder).map_err(io_err(&folder))?;
                let copy = dir.join(SCENARIO_COPY);
                pdamp_io::atomic::write_atomic(&copy, scenario_text.as_bytes())
                    .map_err(io_err(&copy))?;
                let path = Self::path(dir);
                let json = serde_json::to_string_pretty(&manifest).expect("manifest serialises");
                pdamp_io::atomic::write_atomic(&path, json.as_bytes()).map_err(io_err(&path))?;
                Ok(manifest)
            }
            Err(e) => Err(e),
        }
    }

    /// The task `index`, or [`SweepError::NoSuchTask`].
    pub fn task(&self, dir: &Path, index: usize) -> Result<&Task, SweepError> {
        self.tasks.get(index).ok_or(SweepError::NoSuchTask {
            dir: dir.to_path_buf(),
            index,
            count: self.tasks.len(),
        })
    }
}

/// One submission of tasks to a backend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    /// `slurm` or `local`.
    pub backend: String,
    /// When (seconds since the Unix epoch).
    pub time_unix_s: u64,
    /// The Slurm array jobs (empty for the local backend).
    pub arrays: Vec<SubmittedArray>,
}

/// One Slurm array job of a submission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubmittedArray {
    /// Slurm's job id of the array.
    pub job_id: String,
    /// The batch script, relative to the sweep directory.
    pub script: PathBuf,
    /// The sweep tasks of every array element (element `e` runs `elements[e]`).
    pub elements: Vec<Vec<usize>>,
}

/// Reads the submissions made so far (none: an empty list).
pub fn load_submissions(dir: &Path) -> Result<Vec<Submission>, SweepError> {
    let path = dir.join(SUBMISSIONS_FILE);
    match std::fs::read_to_string(&path) {
        Ok(t) => serde_json::from_str(&t).map_err(|e| SweepError::Damaged {
            path,
            why: format!("unreadable ({e})"),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        Err(e) => Err(io_err(&path)(e)),
    }
}

/// Appends a submission to the record (atomic rewrite).
pub fn record_submission(dir: &Path, submission: Submission) -> Result<(), SweepError> {
    let mut all = load_submissions(dir)?;
    all.push(submission);
    let path = dir.join(SUBMISSIONS_FILE);
    let json = serde_json::to_string_pretty(&all).expect("submissions serialise");
    pdamp_io::atomic::write_atomic(&path, json.as_bytes()).map_err(io_err(&path))
}

/// Seconds since the Unix epoch, now.
pub fn now_unix_s() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}
