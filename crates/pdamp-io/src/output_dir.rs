//! The output directory of a command (`--out DIR`): one owner at a time, nothing lost.
//!
//! [`OutputDir::open`] is called by every command that writes a directory, before it writes
//! anything, and
//! * takes an **exclusive lock** (`DIR/.pdamp.lock`, an OS file lock released when the process
//!   ends, also when it is killed): a second run into the same directory is refused, naming the
//!   process that holds it;
//! * refuses a directory that holds the **results of an earlier run** unless the command
//!   continues them (`--resume`, or a resumable command such as `fields`) or is told to replace
//!   them (`--overwrite`, which removes exactly the files the previous run wrote — stale VTK
//!   frames, checkpoints, `failure.json` and temporary files included — and nothing else);
//! * refuses to write **through a symbolic link** (an output name in `DIR` that is a link would
//!   send the output, or its truncation, out of `DIR`);
//! * refuses to **overwrite an input** (`pdamp run DIR/scenario.toml --out DIR` would replace
//!   the user's file by the canonical copy);
//! * keeps a **manifest** (`DIR/manifest.json`): the command, its status (`running`,
//!   `finished`, `failed`, `interrupted`) and, once it ends, every file it wrote. While a run
//!   is in progress (or after it was killed) the manifest lists the entries that were in `DIR`
//!   before it started, so `--overwrite` can still tell the run's files from the user's.

use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Name of the lock file inside an output directory.
pub const LOCK_FILE: &str = ".pdamp.lock";
/// Name of the manifest inside an output directory.
pub const MANIFEST_FILE: &str = "manifest.json";
/// The verbatim copy of the input file every command writes into its output directory.
pub const INPUT_COPY_FILE: &str = "input.toml";

/// Output files of earlier pdamp versions (without a manifest) that mark a directory as
/// holding results.
const RESULT_MARKERS: [&str; 8] = [
    "summary.json",
    "checkpoint.bin",
    "energy.csv",
    "fields.csv",
    "provenance.json",
    "failure.json",
    "particles.pvd",
    "bed.pdbed",
];

/// How a command treats what an earlier run left in its output directory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputMode {
    /// A new run: the directory must not hold results of an earlier run.
    Fresh,
    /// Continue the earlier run (`--resume`, or a command that reuses finished work such as
    /// `fields`): its files are kept.
    Continue,
    /// Replace the earlier run (`--overwrite`): its files are removed first.
    Overwrite,
}

/// Final state of a run, recorded in the manifest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    /// In progress, or killed (the manifest was never completed).
    Running,
    /// Ended with all its outputs written.
    Finished,
    /// Ended with an error (outputs written so far are kept).
    Failed,
    /// Stopped by Ctrl-C/SIGTERM after writing a checkpoint.
    Interrupted,
}

/// `DIR/manifest.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// pdamp version of the run.
    pub pdamp_version: String,
    /// Command line of the run.
    pub command: Vec<String>,
    /// State of the run.
    pub status: RunStatus,
    /// Entries of `DIR` (relative paths) that existed before the run started and are not its
    /// own (the user's files; kept by `--overwrite`).
    pub preexisting: Vec<String>,
    /// Files the run wrote (relative paths), filled in when it ends.
    pub files: Vec<String>,
}

/// Why an output directory cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum OutputDirError {
    /// An I/O error on a named path.
    #[error("output directory: {path}: {source}")]
    Io {
        /// Path of the failing operation.
        path: PathBuf,
        /// Underlying error.
        source: io::Error,
    },
    /// Another process writes into the directory.
    #[error(
        "output directory {dir} is in use by another pdamp run ({holder}); wait for it to end or choose another --out"
    )]
    Locked {
        /// The directory.
        dir: PathBuf,
        /// Who holds the lock (process id, as far as known).
        holder: String,
    },
    /// The directory holds results of an earlier run.
    #[error(
        "output directory {dir} already holds the results of an earlier run ({what}); use --resume to continue it, --overwrite to replace it, or choose another --out"
    )]
    HasResults {
        /// The directory.
        dir: PathBuf,
        /// What was found.
        what: String,
    },
    /// An output name is a symbolic link.
    #[error(
        "{path} is a symbolic link; pdamp never writes through links out of the output directory: remove the link or choose another --out"
    )]
    Symlink {
        /// The link.
        path: PathBuf,
    },
    /// An output would replace an input file.
    #[error(
        "the output {output} would overwrite the input {input}; choose an --out directory that does not hold the command's inputs"
    )]
    WouldOverwriteInput {
        /// The output file.
        output: PathBuf,
        /// The input it would replace.
        input: PathBuf,
    },
    /// `--resume` but there is nothing to continue.
    #[error("{0}")]
    NothingToResume(String),
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> OutputDirError + '_ {
    move |source| OutputDirError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// An output directory held by this process (see the module documentation). The lock is
/// released and the manifest completed when it is dropped.
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
    /// Whether `open` created the directory (a failed command that wrote nothing removes it).
    created: bool,
    lock: Option<File>,
    manifest: Manifest,
    status: RunStatus,
}

impl OutputDir {
    /// Opens (creating it if needed) and locks `path` for a command that writes the files and
    /// folders named in `outputs` (relative names; used to detect symbolic links and inputs
    /// that would be overwritten) and reads the files `inputs`.
    pub fn open(
        path: &Path,
        mode: OutputMode,
        outputs: &[&str],
        inputs: &[&Path],
    ) -> Result<Self, OutputDirError> {
        if let Ok(m) = fs::symlink_metadata(path)
            && !m.is_dir()
            && !m.file_type().is_symlink()
        {
            return Err(OutputDirError::Io {
                path: path.to_path_buf(),
                source: io::Error::new(
                    io::ErrorKind::AlreadyExists,
                    "exists and is not a directory; --out names a directory",
                ),
            });
        }
        let created = !path.exists();
        fs::create_dir_all(path).map_err(io_err(path))?;
        let lock = match Self::lock(path) {
            Ok(l) => l,
            Err(e) => {
                if created {
                    let _ = fs::remove_file(path.join(LOCK_FILE));
                    let _ = fs::remove_dir(path);
                }
                return Err(e);
            }
        };
        // Inputs that an output would replace.
        for name in outputs.iter().copied().chain([MANIFEST_FILE]) {
            let out = path.join(name);
            if let Ok(out_c) = fs::canonicalize(&out) {
                for input in inputs {
                    if fs::canonicalize(input).is_ok_and(|c| c == out_c) {
                        return Err(OutputDirError::WouldOverwriteInput {
                            output: out,
                            input: input.to_path_buf(),
                        });
                    }
                }
            }
        }
        let old = read_manifest(path);
        match mode {
            OutputMode::Fresh => {
                if let Some(m) = &old {
                    return Err(OutputDirError::HasResults {
                        dir: path.to_path_buf(),
                        what: format!(
                            "{} by `{}`, status {:?}",
                            MANIFEST_FILE,
                            m.command
                                .iter()
                                .skip(1)
                                .cloned()
                                .collect::<Vec<_>>()
                                .join(" "),
                            m.status
                        )
                        .to_lowercase(),
                    });
                }
                let found: Vec<&str> = RESULT_MARKERS
                    .iter()
                    .copied()
                    .filter(|n| fs::symlink_metadata(path.join(n)).is_ok())
                    .collect();
                if !found.is_empty() {
                    return Err(OutputDirError::HasResults {
                        dir: path.to_path_buf(),
                        what: found.join(", "),
                    });
                }
            }
            OutputMode::Overwrite => remove_previous_run(path, old.as_ref())?,
            OutputMode::Continue => {}
        }
        remove_temporaries(path)?;
        // No output through a link (checked after the removals: a link may have been a
        // previous run's output name, e.g. a user's replacement of energy.csv).
        for name in outputs.iter().copied().chain([MANIFEST_FILE]) {
            let p = path.join(name);
            if fs::symlink_metadata(&p).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(OutputDirError::Symlink { path: p });
            }
        }
        let preexisting = match (&old, mode) {
            // A continued run keeps the earlier run's idea of the user's files.
            (Some(m), OutputMode::Continue) => m.preexisting.clone(),
            _ => list_entries(path)?,
        };
        let manifest = Manifest {
            pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
            command: std::env::args().collect(),
            status: RunStatus::Running,
            preexisting,
            files: Vec::new(),
        };
        let dir = Self {
            path: path.to_path_buf(),
            created,
            lock: Some(lock),
            manifest,
            status: RunStatus::Failed,
        };
        dir.write_manifest()?;
        Ok(dir)
    }

    /// Takes the directory's lock; the holder's process id is written into the lock file.
    fn lock(path: &Path) -> Result<File, OutputDirError> {
        let lock_path = path.join(LOCK_FILE);
        if fs::symlink_metadata(&lock_path).is_ok_and(|m| m.file_type().is_symlink()) {
            return Err(OutputDirError::Symlink { path: lock_path });
        }
        let mut f = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&lock_path)
            .map_err(io_err(&lock_path))?;
        match f.try_lock() {
            Ok(()) => {}
            Err(fs::TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = f.read_to_string(&mut holder);
                let holder = match holder.trim() {
                    "" => "process unknown".to_string(),
                    pid => format!("process {pid}"),
                };
                return Err(OutputDirError::Locked {
                    dir: path.to_path_buf(),
                    holder,
                });
            }
            Err(fs::TryLockError::Error(e)) => return Err(io_err(&lock_path)(e)),
        }
        let _ = f.set_len(0);
        let _ = f.rewind();
        let _ = write!(f, "{}", std::process::id());
        let _ = f.flush();
        Ok(f)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records how the run ends (written into the manifest when `self` is dropped; the
    /// default is [`RunStatus::Failed`]).
    pub fn set_status(&mut self, status: RunStatus) {
        self.status = status;
    }

    /// Records the end of a command from its result: finished, interrupted (an error starting
    /// with [`crate::checkpoint::INTERRUPTED`]) or failed.
    pub fn set_outcome<T, E: std::fmt::Display>(&mut self, result: &Result<T, E>) {
        self.status = match result {
            Ok(_) => RunStatus::Finished,
            Err(e) if e.to_string().starts_with(crate::checkpoint::INTERRUPTED) => {
                RunStatus::Interrupted
            }
            Err(_) => RunStatus::Failed,
        };
    }

    fn write_manifest(&self) -> Result<(), OutputDirError> {
        let p = self.path.join(MANIFEST_FILE);
        let json =
            serde_json::to_string_pretty(&self.manifest).map_err(|e| OutputDirError::Io {
                path: p.clone(),
                source: io::Error::other(e),
            })?;
        crate::atomic::write_atomic(&p, json.as_bytes()).map_err(io_err(&p))
    }

    /// Completes the manifest (status and the files written) and releases the lock.
    pub fn close(mut self) -> Result<(), OutputDirError> {
        self.complete()
    }

    fn complete(&mut self) -> Result<(), OutputDirError> {
        if self.lock.is_none() {
            return Ok(());
        }
        let before: BTreeSet<&String> = self.manifest.preexisting.iter().collect();
        let files: Vec<String> = list_files(&self.path)?
            .into_iter()
            .filter(|f| !before.contains(f) && f != MANIFEST_FILE)
            .collect();
        // A command that failed before writing anything (a copy of its input is no result)
        // leaves no directory it created.
        if self.status == RunStatus::Failed
            && self.created
            && files.iter().all(|f| f == INPUT_COPY_FILE)
        {
            let _ = fs::remove_file(self.path.join(INPUT_COPY_FILE));
            self.lock = None;
            let _ = fs::remove_file(self.path.join(MANIFEST_FILE));
            let _ = fs::remove_file(self.path.join(LOCK_FILE));
            let _ = fs::remove_dir(&self.path);
            return Ok(());
        }
        self.manifest.files = files;
        self.manifest.status = self.status;
        let r = self.write_manifest();
        self.lock = None;
        r
    }
}

impl Drop for OutputDir {
    fn drop(&mut self) {
        let _ = self.complete();
    }
}

/// Reads `dir/manifest.json` if there is a readable one.
pub fn read_manifest(dir: &Path) -> Option<Manifest> {
    let text = fs::read_to_string(dir.join(MANIFEST_FILE)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Top-level entries of `dir` (names), without the lock and the manifest.
fn list_entries(dir: &Path) -> Result<Vec<String>, OutputDirError> {
    let mut v = Vec::new();
    for e in fs::read_dir(dir).map_err(io_err(dir))? {
        let e = e.map_err(io_err(dir))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name != LOCK_FILE && name != MANIFEST_FILE {
            v.push(name);
        }
    }
    v.sort();
    Ok(v)
}

/// Every file below `dir` (relative paths with `/`), links not followed, without the lock.
/// Entries of a folder listed as a whole in a manifest (`vtk`) appear file by file.
fn list_files(dir: &Path) -> Result<Vec<String>, OutputDirError> {
    fn walk(root: &Path, rel: &str, out: &mut Vec<String>) -> Result<(), OutputDirError> {
        let here = if rel.is_empty() {
            root.to_path_buf()
        } else {
            root.join(rel)
        };
        for e in fs::read_dir(&here).map_err(io_err(&here))? {
            let e = e.map_err(io_err(&here))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let r = if rel.is_empty() {
                name.clone()
            } else {
                format!("{rel}/{name}")
            };
            if r == LOCK_FILE {
                continue;
            }
            let ft = e.file_type().map_err(io_err(&e.path()))?;
            if ft.is_dir() {
                walk(root, &r, out)?;
            } else {
                out.push(r);
            }
        }
        Ok(())
    }
    let mut v = Vec::new();
    walk(dir, "", &mut v)?;
    v.sort();
    Ok(v)
}

/// `--overwrite`: removes what the previous run wrote. With a completed manifest: exactly its
/// files (folders left empty by that are removed too); with a manifest of a run that never
/// ended: every entry that was not in the directory before that run started; without a
/// manifest (an earlier pdamp version): the known result files and folders.
fn remove_previous_run(dir: &Path, old: Option<&Manifest>) -> Result<(), OutputDirError> {
    let rm = |p: &Path| -> Result<(), OutputDirError> {
        match fs::symlink_metadata(p) {
            Ok(m) if m.is_dir() => fs::remove_dir_all(p).map_err(io_err(p)),
            Ok(_) => fs::remove_file(p).map_err(io_err(p)),
            Err(_) => Ok(()),
        }
    };
    match old {
        Some(m) if m.status != RunStatus::Running => {
            let mut dirs = BTreeSet::new();
            for f in &m.files {
                // Never leave the directory through a stored name.
                if f.split('/').any(|c| c == ".." || c.is_empty()) || Path::new(f).is_absolute() {
                    continue;
                }
                rm(&dir.join(f))?;
                let mut parent = Path::new(f).parent();
                while let Some(p) = parent.filter(|p| !p.as_os_str().is_empty()) {
                    dirs.insert(p.to_path_buf());
                    parent = p.parent();
                }
            }
            // Deepest first; only folders the removals left empty.
            for d in dirs.iter().rev() {
                let _ = fs::remove_dir(dir.join(d));
            }
        }
        Some(m) => {
            let keep: BTreeSet<&String> = m.preexisting.iter().collect();
            for name in list_entries(dir)? {
                if !keep.contains(&name) {
                    rm(&dir.join(&name))?;
                }
            }
        }
        None => {
            for name in RESULT_MARKERS.iter().chain(&[
                "vtk",
                "points",
                "packings",
                "scenario.toml",
                "input.toml",
            ]) {
                rm(&dir.join(name))?;
            }
        }
    }
    rm(&dir.join(MANIFEST_FILE))
}

/// Removes temporary files (`*.tmp-<pid>-<n>`, see [`crate::atomic`]) left below `dir` by a
/// killed process (the caller holds the directory's lock, so none is in use).
fn remove_temporaries(dir: &Path) -> Result<(), OutputDirError> {
    for f in list_files(dir)? {
        let name = f.rsplit('/').next().unwrap_or(&f);
        if is_temporary(name) {
            let p = dir.join(&f);
            fs::remove_file(&p).map_err(io_err(&p))?;
        }
    }
    Ok(())
}

/// Whether `name` is a temporary file of an atomic writer: `<name>.tmp-<pid>-<n>`
/// ([`crate::atomic`]) or `.<name>.<pid>-<n>.tmp.<ext>` (the plots of `pdamp-plot`).
fn is_temporary(name: &str) -> bool {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
    if let Some(rest) = name.strip_prefix('.')
        && let Some(i) = rest.rfind(".tmp.")
        && let Some(j) = rest[..i].rfind('.')
        && let Some((pid, n)) = rest[j + 1..i].split_once('-')
        && digits(pid)
        && digits(n)
    {
        return true;
    }
    let Some(i) = name.rfind(".tmp-") else {
        return false;
    };
    let mut parts = name[i + 5..].split('-');
    matches!(
        (parts.next(), parts.next(), parts.next()),
        (Some(a), Some(b), None)
            if !a.is_empty() && !b.is_empty()
                && a.bytes().all(|c| c.is_ascii_digit())
                && b.bytes().all(|c| c.is_ascii_digit())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pdamp-outdir-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn fresh_run_refuses_results_and_overwrite_removes_exactly_the_runs_files() {
        let d = tmp("fresh");
        fs::create_dir_all(&d).unwrap();
        fs::write(d.join("notes.txt"), "mine").unwrap();
        let mut o = OutputDir::open(&d, OutputMode::Fresh, &["energy.csv", "vtk"], &[]).unwrap();
        fs::create_dir_all(d.join("vtk")).unwrap();
        fs::write(d.join("vtk/frame_0000.vtu"), "x").unwrap();
        fs::write(d.join("energy.csv"), "a\n").unwrap();
        o.set_status(RunStatus::Finished);
        o.close().unwrap();
        let m = read_manifest(&d).unwrap();
        assert_eq!(m.status, RunStatus::Finished);
        assert_eq!(m.files, vec!["energy.csv", "vtk/frame_0000.vtu"]);
        assert_eq!(m.preexisting, vec!["notes.txt"]);
        let e = OutputDir::open(&d, OutputMode::Fresh, &["energy.csv"], &[]).unwrap_err();
        assert!(e.to_string().contains("--overwrite"), "{e}");
        // A stale temporary file and a frame of the old run go; the user's file stays.
        fs::write(d.join("summary.json.tmp-123-4"), "x").unwrap();
        let o = OutputDir::open(&d, OutputMode::Overwrite, &["energy.csv"], &[]).unwrap();
        assert!(!d.join("vtk").exists() && !d.join("energy.csv").exists());
        assert!(!d.join("summary.json.tmp-123-4").exists());
        assert_eq!(fs::read_to_string(d.join("notes.txt")).unwrap(), "mine");
        drop(o);
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn a_second_holder_is_refused_and_links_and_inputs_are_protected() {
        let d = tmp("lock");
        fs::create_dir_all(&d).unwrap();
        let o = OutputDir::open(&d, OutputMode::Fresh, &["energy.csv"], &[]).unwrap();
        let e = OutputDir::open(&d, OutputMode::Continue, &["energy.csv"], &[]).unwrap_err();
        assert!(matches!(e, OutputDirError::Locked { .. }), "{e}");
        assert!(
            e.to_string().contains(&std::process::id().to_string()),
            "{e}"
        );
        drop(o);
        #[cfg(unix)]
        {
            let target = tmp("lock-target");
            fs::write(&target, "keep").unwrap();
            std::os::unix::fs::symlink(&target, d.join("energy.csv")).unwrap();
            let e = OutputDir::open(&d, OutputMode::Continue, &["energy.csv"], &[]).unwrap_err();
            assert!(matches!(e, OutputDirError::Symlink { .. }), "{e}");
            assert_eq!(fs::read_to_string(&target).unwrap(), "keep");
            fs::remove_file(d.join("energy.csv")).unwrap();
            let _ = fs::remove_file(&target);
        }
        fs::write(d.join("scenario.toml"), "user's").unwrap();
        let input = d.join("scenario.toml");
        let e =
            OutputDir::open(&d, OutputMode::Continue, &["scenario.toml"], &[&input]).unwrap_err();
        assert!(
            matches!(e, OutputDirError::WouldOverwriteInput { .. }),
            "{e}"
        );
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn a_failed_command_that_wrote_nothing_leaves_no_directory() {
        let d = tmp("failed");
        let o = OutputDir::open(&d, OutputMode::Fresh, &["energy.csv"], &[]).unwrap();
        drop(o); // status Failed by default
        assert!(!d.exists());
        // One that wrote something keeps it, with the manifest.
        let o = OutputDir::open(&d, OutputMode::Fresh, &["energy.csv"], &[]).unwrap();
        fs::write(d.join("energy.csv"), "t\n").unwrap();
        drop(o);
        assert_eq!(read_manifest(&d).unwrap().status, RunStatus::Failed);
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn temporary_names() {
        assert!(is_temporary("energy.csv.tmp-12-0"));
        assert!(!is_temporary("energy.csv"));
        assert!(!is_temporary("a.tmp-12"));
        assert!(!is_temporary("a.tmp-x-1"));
        assert!(is_temporary(".velocity_field_phase2.png.14789-5.tmp.png"));
        assert!(!is_temporary(".hidden.png"));
    }
}
