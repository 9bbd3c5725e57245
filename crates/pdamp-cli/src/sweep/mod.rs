//! `pdamp sweep …`, `pdamp fields --backend slurm` and `pdamp powder study|run --backend
//! slurm`: a grid of independent simulations as a sweep of tasks run here or as Slurm array
//! jobs, collected into exactly the outputs of the local command (see [`pdamp_sweep`] and
//! docs/cluster.md). Kinds:
//! * `fields` — an effective field with its packings: one task per packing's bed (prepared
//!   and saved once), one per grid point and packing (checkpointed inside the point);
//! * `powder-study`, `powder-ensemble` — one task per coupled DEM–FEM run (value and packing),
//!   checkpointed in its folder.

use anyhow::{Context, Result, bail};
use pdamp_design::FieldGrid;
use pdamp_design::report::BedSource;
use pdamp_scenario::schema::Scenario;
use pdamp_sweep::slurm::SlurmOptions;
use pdamp_sweep::status::{Stored, TaskState};
use pdamp_sweep::{SweepManifest, Task};
use std::path::{Path, PathBuf};

mod fields;
mod powder;

pub(crate) use fields::create;
use fields::{FIELDS_KIND, FieldTask, execute_field_tasks, field_tasks, stored_field};
use powder::{POWDER_ENSEMBLE_KIND, POWDER_STUDY_KIND, collect_powder};
pub(crate) use powder::{PowderSweep, create_powder};

/// Where the tasks of a sweep run.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Backend {
    /// Here, the tasks in parallel on this machine's threads (what `pdamp fields` does).
    Local,
    /// As Slurm array jobs (`sbatch --array`), each element running `pdamp sweep task`.
    Slurm,
}

/// How and where to submit (the Slurm options are sbatch's).
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct BackendArgs {
    /// Where the tasks run: `local` (this machine) or `slurm` (array jobs; run this on the
    /// cluster's login node, DIR on the shared file system).
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// Slurm partition (sbatch --partition).
    #[arg(long)]
    partition: Option<String>,
    /// Wall-clock limit of one array element (sbatch --time: MM, HH:MM:SS, D-HH).
    #[arg(long)]
    time: Option<String>,
    /// Slurm account to charge (sbatch --account).
    #[arg(long)]
    account: Option<String>,
    /// Quality of service (sbatch --qos).
    #[arg(long)]
    qos: Option<String>,
    /// Memory per CPU (sbatch --mem-per-cpu, e.g. 2G).
    #[arg(long)]
    mem_per_cpu: Option<String>,
    /// CPUs of one array element: the threads of its pdamp (sbatch --cpus-per-task).
    #[arg(long, default_value_t = 1)]
    cpus_per_task: usize,
    /// Most elements in one array (the site's MaxArraySize; default: from `scontrol show
    /// config`): more tasks are submitted as several arrays.
    #[arg(long)]
    array_limit: Option<usize>,
    /// Most sweep tasks (grid points) one array element runs, one after the other or in
    /// parallel on its CPUs: more than one when points are short.
    #[arg(long, default_value_t = 1)]
    max_tasks_per_job: usize,
    /// Elements of one array running at once (Slurm's `--array=…%N`).
    #[arg(long)]
    throttle: Option<usize>,
    /// A further sbatch option, verbatim (repeatable), e.g. `--sbatch-arg=--constraint=skylake`.
    #[arg(long = "sbatch-arg", allow_hyphen_values = true)]
    sbatch_arg: Vec<String>,
    /// The pdamp executable on the compute nodes (default: this one; it must be on the shared
    /// file system).
    #[arg(long)]
    pdamp: Option<PathBuf>,
    /// Write the batch scripts into DIR/sweep/slurm and print the plan; submit nothing.
    #[arg(long)]
    dry_run: bool,
}

impl BackendArgs {
    fn slurm_options(&self) -> SlurmOptions {
        SlurmOptions {
            partition: self.partition.clone(),
            time: self.time.clone(),
            account: self.account.clone(),
            qos: self.qos.clone(),
            mem_per_cpu: self.mem_per_cpu.clone(),
            cpus_per_task: self.cpus_per_task,
            array_limit: self.array_limit,
            max_tasks_per_job: self.max_tasks_per_job,
            throttle: self.throttle,
            extra: self.sbatch_arg.clone(),
            pdamp: self.pdamp.clone(),
        }
    }

    /// Whether a Slurm option was given (they mean nothing to the local backend).
    pub(crate) fn any_slurm_option(&self) -> bool {
        self.partition.is_some()
            || self.time.is_some()
            || self.account.is_some()
            || self.qos.is_some()
            || self.mem_per_cpu.is_some()
            || self.cpus_per_task != 1
            || self.array_limit.is_some()
            || self.max_tasks_per_job != 1
            || self.throttle.is_some()
            || !self.sbatch_arg.is_empty()
            || self.pdamp.is_some()
            || self.dry_run
    }
}

/// `pdamp sweep …`.
#[derive(clap::Subcommand)]
pub(crate) enum SweepCommand {
    /// Make the sweep of a scenario's [fields] grid (and its packings) in DIR without running
    /// anything: DIR/sweep.json lists the tasks.
    New {
        /// Scenario file (TOML) with [damper] and [fields].
        scenario: PathBuf,
        /// Sweep (output) directory.
        #[arg(long)]
        out: PathBuf,
    },
    /// Submit the tasks of DIR that are not finished (missing, failed, damaged), not those
    /// queued or running; default backend: slurm.
    Submit {
        /// Sweep directory.
        dir: PathBuf,
        #[command(flatten)]
        backend: BackendArgs,
    },
    /// Submit again only the tasks that are missing or failed (cancelled, killed, preempted
    /// past their requeue, or never submitted); finished ones are never recomputed.
    Resubmit {
        /// Sweep directory.
        dir: PathBuf,
        #[command(flatten)]
        backend: BackendArgs,
    },
    /// State of every task: done, running, pending (from squeue), failed (with its error),
    /// corrupt, missing.
    Status {
        /// Sweep directory.
        dir: PathBuf,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Build the outputs of a local run (fields.csv, maps, bed statistics) from the finished
    /// tasks; failed points become NaN rows with their message.
    Collect {
        /// Sweep directory.
        dir: PathBuf,
    },
    /// Run tasks of the sweep (what each Slurm array element runs).
    Task {
        /// Sweep directory.
        dir: PathBuf,
        /// Task indices (comma-separated; see DIR/sweep.json).
        #[arg(long, value_delimiter = ',', required = true)]
        index: Vec<usize>,
    },
}

/// Runs a `pdamp sweep` command.
pub(crate) fn dispatch(command: SweepCommand) -> Result<()> {
    match command {
        SweepCommand::New { scenario, out } => {
            let m = create(&scenario, &out)?;
            println!(
                "{}",
                serde_json::to_string_pretty(&serde_json::json!({
                    "sweep": out, "kind": m.kind, "tasks": m.tasks.len(),
                    "next": format!("pdamp sweep submit {} --backend slurm [--partition …]", out.display()),
                }))?
            );
            Ok(())
        }
        SweepCommand::Submit { dir, backend } | SweepCommand::Resubmit { dir, backend } => {
            submit(&dir, &backend)
        }
        SweepCommand::Status { dir, json } => status(&dir, json),
        SweepCommand::Collect { dir } => collect(&dir),
        SweepCommand::Task { dir, index } => run_tasks(&dir, &index),
    }
}

/// A sweep opened for work: its scenario (checked against the manifest's digest) and tasks.
enum Opened {
    Fields {
        sc: Box<Scenario>,
        tasks: Vec<FieldTask>,
        grid: FieldGrid,
        packings: usize,
    },
    Powder {
        base: Box<pdamp_powder::cantilever::CantileverScenario>,
        what: PowderSweep,
        runs: Vec<pdamp_powder::study::StudyRun>,
    },
}

/// Opens the sweep of manifest `m` in `dir`: reads its copy of the scenario and refuses when the
/// scenario or a file it reads changed since the sweep was made.
fn open(dir: &Path, m: &SweepManifest) -> Result<Opened> {
    let copy = dir.join(pdamp_sweep::SCENARIO_COPY);
    let text =
        std::fs::read_to_string(&copy).with_context(|| format!("reading {}", copy.display()))?;
    let changed = |digest: &str| {
        anyhow::anyhow!(
            "{}: the scenario or a file it reads (relative to {}) changed since the sweep was made (digest {} now, {} then); finished tasks would not match new ones — make a new sweep in another directory",
            dir.display(),
            m.base_dir.display(),
            digest,
            m.scenario_digest
        )
    };
    match m.kind.as_str() {
        FIELDS_KIND => {
            let sc = Scenario::from_toml_in(&text, &m.base_dir)
                .and_then(|s| s.validate().map(|_| s).map_err(Into::into))
                .map_err(|e| anyhow::anyhow!("{}: {e}", copy.display()))?;
            let digest = pdamp_scenario::run::scenario_content_digest(&sc, &m.base_dir);
            if digest != m.scenario_digest {
                return Err(changed(&digest));
            }
            let (tasks, grid, packings) = field_tasks(&sc)?;
            Ok(Opened::Fields {
                sc: Box::new(sc),
                tasks,
                grid,
                packings,
            })
        }
        POWDER_STUDY_KIND | POWDER_ENSEMBLE_KIND => {
            let base = pdamp_powder::cantilever::CantileverScenario::from_toml(&text)
                .map_err(|e| anyhow::anyhow!("{}: {e}", copy.display()))?;
            let digest =
                pdamp_powder::cantilever::scenario_digest(&base).map_err(anyhow::Error::msg)?;
            if digest != m.scenario_digest {
                return Err(changed(&digest));
            }
            let what: PowderSweep = serde_json::from_value(m.parameters.clone())
                .with_context(|| format!("{}: parameters", SweepManifest::path(dir).display()))?;
            let runs = what.runs(&base, dir)?;
            Ok(Opened::Powder {
                base: Box::new(base),
                what,
                runs,
            })
        }
        other => bail!(
            "{}: a sweep of kind '{other}', which this pdamp does not know",
            dir.display()
        ),
    }
}

pub(super) fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// Writes the sweep `manifest` of `scenario` into `out` (or opens the same sweep there); another
/// scenario's sweep is refused before anything in `out` is touched, and so is a directory that
/// another command's results or the command's inputs make unusable.
fn install(
    scenario: &Path,
    out: &Path,
    manifest: SweepManifest,
    inputs: &[PathBuf],
    outputs: &[&str],
) -> Result<SweepManifest> {
    if let Ok(existing) = SweepManifest::load(out)
        && (existing.scenario_digest != manifest.scenario_digest
            || existing.kind != manifest.kind
            || existing.parameters != manifest.parameters
            || existing.tasks != manifest.tasks)
    {
        return Err(pdamp_sweep::SweepError::OtherScenario {
            dir: out.to_path_buf(),
            existing: existing.scenario_source,
            existing_digest: existing.scenario_digest,
            new: manifest.scenario_source,
            new_digest: manifest.scenario_digest,
        }
        .into());
    }
    let inputs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
    let mut outputs = outputs.to_vec();
    outputs.extend(["sweep.json", "sweep"]);
    let dir = pdamp_io::output_dir::OutputDir::open(
        out,
        pdamp_io::output_dir::OutputMode::Continue,
        &outputs,
        &inputs,
    )?;
    let text = std::fs::read_to_string(scenario)?;
    let m = SweepManifest::create_or_open(out, manifest, &text)?;
    crate::outputs::copy_input(out, scenario)?;
    dir.close()?;
    Ok(m)
}

/// A task without a result: failed when it left an error file, else missing.
fn stored_error(dir: &Path, t: &Task) -> Stored {
    match std::fs::read_to_string(dir.join(&t.error)) {
        Ok(e) => Stored::Failed(e.trim().to_string()),
        Err(_) => Stored::Missing,
    }
}

impl Opened {
    /// What the store holds for task `t`.
    fn stored(&self, dir: &Path, t: &Task) -> Stored {
        match self {
            Opened::Fields {
                tasks,
                grid,
                packings,
                ..
            } => stored_field(dir, grid, *packings, tasks[t.index], t),
            Opened::Powder { runs, .. } => match runs[t.index].finished() {
                Ok(true) => Stored::Done,
                Ok(false) => stored_error(dir, t),
                Err(e) => Stored::Corrupt(e.to_string()),
            },
        }
    }
}

/// State of every task of the sweep in `dir` (the queue asked only when something was submitted
/// to Slurm).
/// Without `strict`, a queue that cannot be asked (no Slurm client on this machine) is a
/// warning and queued tasks show as missing; with it (before submitting) it is an error.
fn states(dir: &Path, strict: bool) -> Result<(SweepManifest, Opened, Vec<TaskState>)> {
    let m = SweepManifest::load(dir)?;
    let opened = open(dir, &m)?;
    let submissions = pdamp_sweep::load_submissions(dir)?;
    let queued = match pdamp_sweep::status::queued_tasks(&submissions) {
        Ok(q) => q,
        Err(e) if !strict => {
            eprintln!(
                "warning: cannot ask Slurm's queue ({e}); tasks queued or running there show as missing"
            );
            Default::default()
        }
        Err(e) => return Err(e.into()),
    };
    let st = pdamp_sweep::status::task_states(&m, |t| opened.stored(dir, t), &queued);
    Ok((m, opened, st))
}

fn status(dir: &Path, json: bool) -> Result<()> {
    let (m, _, st) = states(dir, false)?;
    if json {
        let counts: serde_json::Map<String, serde_json::Value> = pdamp_sweep::status::counts(&st)
            .iter()
            .map(|(k, n)| (k.to_string(), serde_json::json!(n)))
            .collect();
        let tasks: Vec<serde_json::Value> = m
            .tasks
            .iter()
            .zip(&st)
            .map(|(t, s)| {
                let mut v = serde_json::to_value(s).unwrap_or_default();
                v["index"] = serde_json::json!(t.index);
                v["label"] = serde_json::json!(t.label);
                v
            })
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "sweep": dir, "kind": m.kind, "tasks": m.tasks.len(), "counts": counts, "task_states": tasks,
            }))?
        );
    } else {
        print!("{}", pdamp_sweep::status::render(dir, &m, &st));
    }
    Ok(())
}

/// Submits the unfinished tasks of the sweep in `dir` to the chosen backend.
pub(crate) fn submit(dir: &Path, args: &BackendArgs) -> Result<()> {
    let backend = args.backend.unwrap_or(Backend::Slurm);
    let (m, _, st) = states(dir, true)?;
    let wanted: Vec<usize> = m
        .tasks
        .iter()
        .zip(&st)
        .filter(|(_, s)| s.wants_run())
        .map(|(t, _)| t.index)
        .collect();
    let busy = st
        .iter()
        .filter(|s| matches!(s, TaskState::Running | TaskState::Pending))
        .count();
    if backend == Backend::Local {
        if args.any_slurm_option() {
            bail!("the Slurm options (--partition, --time, --throttle, …) need --backend slurm");
        }
        if busy > 0 {
            bail!(
                "{busy} tasks of {} are queued or running in Slurm; wait for them (`pdamp sweep status`) or cancel them (scancel) before running the rest here",
                dir.display()
            );
        }
        let run = execute_tasks(dir, &wanted)?;
        for f in &run.failed {
            eprintln!("warning: {f}");
        }
        pdamp_sweep::record_submission(
            dir,
            pdamp_sweep::Submission {
                backend: "local".into(),
                time_unix_s: pdamp_sweep::now_unix_s(),
                arrays: vec![],
            },
        )?;
        return collect(dir);
    }
    if wanted.is_empty() {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "sweep": dir, "submitted_tasks": 0, "queued_or_running": busy,
                "next": format!("pdamp sweep collect {}", dir.display()),
            }))?
        );
        return Ok(());
    }
    let options = args.slurm_options();
    let pdamp = match &options.pdamp {
        Some(p) => p.clone(),
        None => std::env::current_exe().context("locating this pdamp executable")?,
    };
    let dir_abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    // Beds first (the points need them), then the points.
    let (first, rest): (Vec<usize>, Vec<usize>) = wanted
        .iter()
        .partition(|&&t| m.tasks.iter().any(|o| o.needs.contains(&t)));
    let number = pdamp_sweep::load_submissions(dir)?
        .iter()
        .map(|s| s.arrays.len())
        .sum();
    let planned = pdamp_sweep::slurm::write_arrays(
        &dir_abs, &m.kind, &first, &rest, &options, &pdamp, number,
    )?;
    let rel = |p: &Path| {
        p.strip_prefix(&dir_abs)
            .map(|r| r.to_path_buf())
            .unwrap_or(p.to_path_buf())
    };
    if args.dry_run {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "sweep": dir, "dry_run": true, "tasks": wanted.len(),
                "arrays": planned.iter().map(|p| serde_json::json!({
                    "script": rel(&p.script), "elements": p.elements.len(), "after_beds": p.after_first,
                })).collect::<Vec<_>>(),
            }))?
        );
        return Ok(());
    }
    let ids = pdamp_sweep::slurm::submit_arrays(&planned)?;
    pdamp_sweep::record_submission(
        dir,
        pdamp_sweep::Submission {
            backend: "slurm".into(),
            time_unix_s: pdamp_sweep::now_unix_s(),
            arrays: planned
                .iter()
                .zip(&ids)
                .map(|(p, id)| pdamp_sweep::SubmittedArray {
                    job_id: id.clone(),
                    script: rel(&p.script),
                    elements: p.elements.clone(),
                })
                .collect(),
        },
    )?;
    println!(
        "{}",
        serde_json::to_string_pretty(&serde_json::json!({
            "sweep": dir, "submitted_tasks": wanted.len(), "arrays": ids,
            "status": format!("pdamp sweep status {}", dir.display()),
            "collect": format!("pdamp sweep collect {}", dir.display()),
        }))?
    );
    Ok(())
}

/// Runs the tasks `indices` of the sweep in `dir` here: beds first, then the points packing by
/// packing on this process's threads. Each finished task is stored at once; a failed one
/// leaves its error next to its slot.
fn execute_tasks(dir: &Path, indices: &[usize]) -> Result<TasksRun> {
    let m = SweepManifest::load(dir)?;
    for &i in indices {
        m.task(dir, i)?;
    }
    match open(dir, &m)? {
        Opened::Fields {
            sc,
            tasks,
            grid,
            packings,
        } => execute_field_tasks(dir, &m, &sc, &tasks, &grid, packings, indices),
        Opened::Powder { runs, .. } => {
            let mut run = TasksRun {
                ran: 0,
                failed: Vec::new(),
            };
            // One run after the other, each on all threads of the task; checkpointed in its
            // folder, so a requeued or resubmitted task continues where it was stopped.
            for &i in indices {
                let task = &m.tasks[i];
                match runs[i].run(60.0, crate::cancel(), &mut |_, _| {}) {
                    Ok(ran) => {
                        run.ran += usize::from(ran);
                        let _ = std::fs::remove_file(dir.join(&task.error));
                    }
                    Err(e) if e.to_string().starts_with(pdamp_io::checkpoint::INTERRUPTED) => {
                        bail!("{e}")
                    }
                    Err(e) => {
                        let e = e.to_string();
                        if let Some(parent) = dir.join(&task.error).parent() {
                            std::fs::create_dir_all(parent)?;
                        }
                        pdamp_io::atomic::write_atomic(dir.join(&task.error), e.as_bytes())?;
                        run.failed.push(format!("task {i} ({}): {e}", task.label));
                    }
                }
            }
            Ok(run)
        }
    }
}

/// What [`execute_tasks`] did.
struct TasksRun {
    /// Points computed now (not those found finished).
    ran: usize,
    /// Failed tasks with their errors.
    failed: Vec<String>,
}

/// `pdamp sweep task`: runs the tasks, prints what happened, fails when one failed (so that a
/// Slurm array waiting for a bed is not started on a bed that failed).
fn run_tasks(dir: &Path, indices: &[usize]) -> Result<()> {
    let TasksRun { ran, failed } = execute_tasks(dir, indices)?;
    println!(
        "{}",
        serde_json::to_string_pretty(&serde_json::json!({
            "sweep": dir, "tasks": indices, "tasks_run": ran, "failed": failed,
        }))?
    );
    if !failed.is_empty() {
        bail!(
            "{} of {} tasks failed (their errors are stored next to their slots; `pdamp sweep status {}` lists them)",
            failed.len(),
            indices.len(),
            dir.display()
        );
    }
    Ok(())
}

/// Builds fields.csv, the maps and the bed statistics from the store of the sweep in `dir`.
pub(crate) fn collect(dir: &Path) -> Result<()> {
    let (m, opened, st) = states(dir, false)?;
    let open: Vec<String> = m
        .tasks
        .iter()
        .zip(&st)
        .filter(|(_, s)| !matches!(s, TaskState::Done | TaskState::Failed(_)))
        .map(|(t, s)| match s {
            TaskState::Corrupt(e) => format!("task {} ({}): corrupt: {e}", t.index, t.label),
            _ => format!("task {} ({}): {}", t.index, t.label, s.name()),
        })
        .collect();
    if !open.is_empty() {
        let counts: Vec<String> = pdamp_sweep::status::counts(&st)
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{n} {k}"))
            .collect();
        bail!(
            "{}: {} of {} tasks are not finished ({}): {}{}\n`pdamp sweep status {0}` shows every task; `pdamp sweep resubmit {0}` runs the missing ones",
            dir.display(),
            open.len(),
            m.tasks.len(),
            counts.join(", "),
            open.iter().take(5).cloned().collect::<Vec<_>>().join("; "),
            if open.len() > 5 { "; …" } else { "" }
        );
    }
    let sc = match opened {
        Opened::Fields { sc, .. } => sc,
        Opened::Powder { base, what, .. } => return collect_powder(dir, &base, &what),
    };
    let mut out_dir = pdamp_io::output_dir::OutputDir::open(
        dir,
        pdamp_io::output_dir::OutputMode::Continue,
        &crate::outputs::RUN_OUTPUTS,
        &[],
    )?;
    let start = std::time::Instant::now();
    let outcome = pdamp_design::report::run_fields_scenario_from(
        &sc,
        &m.base_dir,
        dir,
        pdamp_design::PointEngine::Stored,
        BedSource::Saved(dir),
        |_| {},
        |_, _| {},
        crate::cancel(),
    );
    out_dir.set_outcome(&outcome);
    out_dir.close()?;
    let outcome = outcome.map_err(|e| {
        anyhow::anyhow!(
            "{e}\n`pdamp sweep status {0}` shows every task; `pdamp sweep resubmit {0}` runs the missing ones",
            dir.display()
        )
    })?;
    for (f, x, e) in &outcome.failed {
        eprintln!("warning: point f = {f} Hz, X = {x:.4e} m failed (NaN in fields.csv): {e}");
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&serde_json::json!({
            "sweep": dir,
            "points": outcome.points.len(),
            "failed_points": outcome.failed.iter().map(|(f, x, e)| serde_json::json!({
                "frequency_hz": f, "amplitude_m": x, "error": e
            })).collect::<Vec<_>>(),
            "fields_csv": dir.join("fields.csv"),
            "wall_time_s": start.elapsed().as_secs_f64(),
        }))?
    );
    Ok(())
}
