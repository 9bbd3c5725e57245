//! The Slurm backend: the tasks of a sweep as `sbatch --array` jobs on the shared file system.
//!
//! Every array element runs `pdamp sweep task DIR --index I,J,…` for its share of tasks
//! ([`SlurmOptions::max_tasks_per_job`] at most, several when tasks are short); arrays hold at
//! most [`SlurmOptions::array_limit`] elements (the site's `MaxArraySize`, read from `scontrol
//! show config` when not given) and run at most [`SlurmOptions::throttle`] elements at once
//! (`%N`). Tasks that others need (the beds of the packings) go first, in their own array, and
//! the rest waits for it (`--dependency=afterok`, `--kill-on-invalid-dep=yes`). Elements are
//! `--requeue`d when preempted; whatever a task finished is stored, so a requeued or
//! resubmitted element skips it.

use crate::{SweepError, io_err};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Options of `pdamp sweep submit … --backend slurm` (names as sbatch's).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlurmOptions {
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` (wall-clock limit of one array element, Slurm's formats: `MM`, `HH:MM:SS`,
    /// `D-HH`).
    pub time: Option<String>,
    /// `--account`.
    pub account: Option<String>,
    /// `--qos`.
    pub qos: Option<String>,
    /// `--mem-per-cpu` (e.g. `2G`).
    pub mem_per_cpu: Option<String>,
    /// `--cpus-per-task`: threads of one element (`pdamp --threads`), ≥ 1.
    pub cpus_per_task: usize,
    /// Largest number of elements of one array (the site's `MaxArraySize`); `None`: from
    /// `scontrol show config`, else 1000.
    pub array_limit: Option<usize>,
    /// Largest number of sweep tasks one array element runs (≥ 1; more when tasks are short).
    pub max_tasks_per_job: usize,
    /// Elements of one array running at once (`--array=…%N`); `None`: no limit.
    pub throttle: Option<usize>,
    /// Further `#SBATCH` options, verbatim (e.g. `--constraint=skylake`).
    pub extra: Vec<String>,
    /// The pdamp executable on the compute nodes (default: this one, which must then be on the
    /// shared file system).
    pub pdamp: Option<PathBuf>,
}

impl SlurmOptions {
    /// Checks the numbers; the message names the option.
    pub fn validate(&self) -> Result<(), SweepError> {
        let bad = |m: &str| Err(SweepError::Options(m.to_string()));
        if self.cpus_per_task == 0 {
            return bad("--cpus-per-task must be at least 1");
        }
        if self.max_tasks_per_job == 0 {
            return bad("--max-tasks-per-job must be at least 1");
        }
        if self.array_limit == Some(0) {
            return bad("--array-limit must be at least 1");
        }
        if self.throttle == Some(0) {
            return bad("--throttle must be at least 1 (it is Slurm's %N)");
        }
        for (name, v) in [
            ("--partition", &self.partition),
            ("--time", &self.time),
            ("--account", &self.account),
            ("--qos", &self.qos),
            ("--mem-per-cpu", &self.mem_per_cpu),
        ] {
            if v.as_deref()
                .is_some_and(|s| s.is_empty() || s.contains(char::is_whitespace))
            {
                return Err(SweepError::Options(format!(
                    "{name} '{}' must be one word",
                    v.as_deref().unwrap_or_default()
                )));
            }
        }
        if let Some(e) = self
            .extra
            .iter()
            .find(|e| !e.starts_with('-') || e.contains('\n'))
        {
            return Err(SweepError::Options(format!(
                "--sbatch-arg '{e}' must be one sbatch option starting with '-'"
            )));
        }
        Ok(())
    }
}

/// Splits `tasks` into array elements of at most `max_tasks_per_job` tasks (in the order
/// given) and the elements into arrays of at most `array_limit` elements.
pub fn plan_arrays(
    tasks: &[usize],
    max_tasks_per_job: usize,
    array_limit: usize,
) -> Vec<Vec<Vec<usize>>> {
    let elements: Vec<Vec<usize>> = tasks
        .chunks(max_tasks_per_job.max(1))
        .map(|c| c.to_vec())
        .collect();
    elements
        .chunks(array_limit.max(1))
        .map(|c| c.to_vec())
        .collect()
}

/// Quotes `s` for bash (single quotes).
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The batch script of one array: `#SBATCH` options, the elements' task lists, and the
/// `pdamp sweep task` line.
pub fn array_script(
    dir: &Path,
    kind: &str,
    number: usize,
    elements: &[Vec<usize>],
    options: &SlurmOptions,
    pdamp: &Path,
    after: Option<&str>,
) -> String {
    let mut s = String::from("#!/bin/bash\n");
    s.push_str(&format!(
        "# written by `pdamp sweep submit`: array {number} of the {kind} sweep in {}\n",
        dir.display()
    ));
    let mut opt = |o: String| s.push_str(&format!("#SBATCH {o}\n"));
    opt(format!("--job-name=pdamp-{kind}-{number:03}"));
    let throttle = options.throttle.map_or(String::new(), |t| format!("%{t}"));
    opt(format!(
        "--array=0-{}{throttle}",
        elements.len().saturating_sub(1)
    ));
    opt("--ntasks=1".into());
    opt(format!("--cpus-per-task={}", options.cpus_per_task));
    opt(format!(
        "--output={}",
        dir.join("sweep/logs/%A_%a.out").display()
    ));
    opt("--open-mode=append".into());
    opt("--requeue".into());
    for (name, v) in [
        ("partition", &options.partition),
        ("time", &options.time),
        ("account", &options.account),
        ("qos", &options.qos),
        ("mem-per-cpu", &options.mem_per_cpu),
    ] {
        if let Some(v) = v {
            opt(format!("--{name}={v}"));
        }
    }
    if let Some(job) = after {
        opt(format!("--dependency=afterok:{job}"));
        opt("--kill-on-invalid-dep=yes".into());
    }
    for e in &options.extra {
        opt(e.clone());
    }
    s.push_str("set -euo pipefail\nTASKS=(\n");
    for e in elements {
        let list: Vec<String> = e.iter().map(|t| t.to_string()).collect();
        s.push_str(&format!("  {}\n", list.join(",")));
    }
    s.push_str(")\n");
    s.push_str(&format!(
        "exec {} --threads \"${{SLURM_CPUS_PER_TASK:-{}}}\" sweep task {} --index \"${{TASKS[$SLURM_ARRAY_TASK_ID]}}\"\n",
        quote(&pdamp.display().to_string()),
        options.cpus_per_task,
        quote(&dir.display().to_string())
    ));
    s
}

/// Runs a Slurm client command; a missing command or a refusal is a [`SweepError::Slurm`]
/// with what Slurm said.
fn slurm(program: &str, args: &[&str]) -> Result<String, SweepError> {
    let out = Command::new(program).args(args).output().map_err(|e| {
        SweepError::Slurm(if e.kind() == std::io::ErrorKind::NotFound {
            format!(
                "`{program}` is not on the PATH: the Slurm backend needs Slurm's client commands (sbatch, squeue, scontrol) on this machine — run the sweep on the cluster's login node, or use --backend local"
            )
        } else {
            format!("cannot run `{program}`: {e}")
        })
    })?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(SweepError::Slurm(format!(
            "`{program} {}` failed ({}): {}",
            args.join(" "),
            out.status,
            err.trim()
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// `MaxArraySize` of the cluster (`scontrol show config`); array indices must stay below it.
pub fn max_array_size() -> Option<usize> {
    let text = slurm("scontrol", &["show", "config"]).ok()?;
    text.lines().find_map(|l| {
        let (k, v) = l.split_once('=')?;
        (k.trim() == "MaxArraySize")
            .then(|| v.trim().parse::<usize>().ok())
            .flatten()
    })
}

/// The array limit in force: the option, else the cluster's `MaxArraySize` (indices run up to
/// `MaxArraySize − 1`), else 1000.
pub fn array_limit(options: &SlurmOptions) -> usize {
    options
        .array_limit
        .or_else(|| max_array_size().map(|m| m.saturating_sub(1).max(1)))
        .unwrap_or(1000)
}

/// An array written and, unless a dry run, submitted.
#[derive(Debug, Clone)]
pub struct PlannedArray {
    /// The batch script (absolute).
    pub script: PathBuf,
    /// Tasks of each element.
    pub elements: Vec<Vec<usize>>,
    /// Whether it waits for the first array (the tasks the others need).
    pub after_first: bool,
}

/// Writes the scripts of the arrays for `first` (tasks others need; may be empty) and `rest`
/// into `dir/sweep/slurm/`, numbered from `start_number`.
pub fn write_arrays(
    dir: &Path,
    kind: &str,
    first: &[usize],
    rest: &[usize],
    options: &SlurmOptions,
    pdamp: &Path,
    start_number: usize,
) -> Result<Vec<PlannedArray>, SweepError> {
    options.validate()?;
    let limit = array_limit(options);
    let folder = dir.join("sweep/slurm");
    std::fs::create_dir_all(&folder).map_err(io_err(&folder))?;
    let logs = dir.join("sweep/logs");
    std::fs::create_dir_all(&logs).map_err(io_err(&logs))?;
    let mut planned = Vec::new();
    let mut number = start_number;
    for (group, after_first) in [(first, false), (rest, !first.is_empty())] {
        // The tasks others need run one per element: they gate everything else.
        let per_job = if after_first || first.is_empty() {
            options.max_tasks_per_job
        } else {
            1
        };
        for elements in plan_arrays(group, per_job, limit) {
            let script = folder.join(format!("array_{number:03}.sh"));
            // The dependency is filled in at submission (`--dependency` on the command line).
            let text = array_script(dir, kind, number, &elements, options, pdamp, None);
            pdamp_io::atomic::write_atomic(&script, text.as_bytes()).map_err(io_err(&script))?;
            planned.push(PlannedArray {
                script,
                elements,
                after_first,
            });
            number += 1;
        }
    }
    Ok(planned)
}

/// Submits the planned arrays in order; those marked `after_first` wait for all arrays of the
/// first group. The first script is tried with `sbatch --test-only` before anything is
/// submitted, so a bad partition, account or time limit is refused with Slurm's message and
/// nothing queued. Returns the job ids.
pub fn submit_arrays(planned: &[PlannedArray]) -> Result<Vec<String>, SweepError> {
    let Some(first) = planned.first() else {
        return Ok(Vec::new());
    };
    let script = first.script.display().to_string();
    // --test-only prints its verdict on stderr and exits 0 when the job would run.
    slurm("sbatch", &["--test-only", &script]).map_err(|e| {
        SweepError::Slurm(format!(
            "Slurm refuses the sweep's jobs (nothing was submitted): {e}"
        ))
    })?;
    let mut ids: Vec<String> = Vec::new();
    let mut gate: Vec<String> = Vec::new();
    for p in planned {
        let script = p.script.display().to_string();
        let dep = (!gate.is_empty() && p.after_first)
            .then(|| format!("--dependency=afterok:{}", gate.join(":")));
        let mut args: Vec<&str> = vec!["--parsable"];
        if let Some(d) = &dep {
            args.push(d);
            args.push("--kill-on-invalid-dep=yes");
        }
        args.push(&script);
        let out = slurm("sbatch", &args).map_err(|e| {
            SweepError::Slurm(format!(
                "{e} (arrays submitted before this one: {}; `pdamp sweep status` follows them and `pdamp sweep resubmit` submits the rest)",
                if ids.is_empty() { "none".to_string() } else { ids.join(", ") }
            ))
        })?;
        let id = out.trim().split(';').next().unwrap_or("").to_string();
        if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
            return Err(SweepError::Slurm(format!(
                "sbatch answered '{}' instead of a job id",
                out.trim()
            )));
        }
        if !p.after_first {
            gate.push(id.clone());
        }
        ids.push(id);
    }
    Ok(ids)
}

/// State of an array element in Slurm's queue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QueueState {
    /// Waiting to start (or held, or waiting for its dependency).
    Pending,
    /// Running (or completing, or being requeued).
    Running,
}

/// The queued and running elements of the given array jobs: (array job id, element) → state,
/// from `squeue`. Elements Slurm no longer lists have ended (finished, failed or cancelled:
/// the store tells which).
pub fn queue(job_ids: &[String]) -> Result<HashMap<(String, usize), QueueState>, SweepError> {
    let mut out = HashMap::new();
    if job_ids.is_empty() {
        return Ok(out);
    }
    let list = job_ids.join(",");
    let text = slurm("squeue", &["-h", "-r", "-j", &list, "-o", "%F|%K|%T"]).or_else(|e| {
        // squeue refuses a list in which every job has left the queue long ago.
        if e.to_string().contains("Invalid job id") {
            Ok(String::new())
        } else {
            Err(e)
        }
    })?;
    for line in text.lines() {
        let mut f = line.split('|');
        let (Some(job), Some(element), Some(state)) = (f.next(), f.next(), f.next()) else {
            continue;
        };
        let Ok(element) = element.trim().parse::<usize>() else {
            continue;
        };
        let state = match state.trim() {
            "PENDING" | "REQUEUED" | "REQUEUE_HOLD" | "REQUEUE_FED" | "SUSPENDED" => {
                QueueState::Pending
            }
            "RUNNING" | "COMPLETING" | "CONFIGURING" | "RESIZING" | "SIGNALING" | "STAGE_OUT"
            | "STOPPED" => QueueState::Running,
            // Ended (completed, cancelled, failed, timed out, preempted …): the store tells.
            _ => continue,
        };
        out.insert((job.trim().to_string(), element), state);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_are_chunked_to_the_limit_and_the_tasks_per_job() {
        let tasks: Vec<usize> = (0..108).collect();
        // 108 points, one per element, limit 25: 5 arrays of 25, 25, 25, 25, 8.
        let a = plan_arrays(&tasks, 1, 25);
        assert_eq!(
            a.iter().map(|x| x.len()).collect::<Vec<_>>(),
            [25, 25, 25, 25, 8]
        );
        assert_eq!(a[4][7], vec![107]);
        // 4 tasks per element: 27 elements, limit 25: arrays of 25 and 2.
        let b = plan_arrays(&tasks, 4, 25);
        assert_eq!(b.iter().map(|x| x.len()).collect::<Vec<_>>(), [25, 2]);
        assert_eq!(b[0][0], vec![0, 1, 2, 3]);
        assert_eq!(b[1][1], vec![104, 105, 106, 107]);
        // Every task exactly once, in order.
        let flat: Vec<usize> = b.into_iter().flatten().flatten().collect();
        assert_eq!(flat, tasks);
        // 9 points, 2 per element: 5 elements, the last with one point.
        let c = plan_arrays(&tasks[..9], 2, 1000);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].len(), 5);
        assert_eq!(c[0][4], vec![8]);
    }

    #[test]
    fn the_script_holds_the_options_and_the_task_lists() {
        let o = SlurmOptions {
            partition: Some("compute".into()),
            time: Some("01:00:00".into()),
            cpus_per_task: 2,
            max_tasks_per_job: 2,
            throttle: Some(2),
            extra: vec!["--constraint=skylake".into()],
            ..Default::default()
        };
        o.validate().unwrap();
        let s = array_script(
            Path::new("/scratch/it's here"),
            "fields",
            3,
            &[vec![0, 1], vec![2]],
            &o,
            Path::new("/opt/pdamp/bin/pdamp"),
            None,
        );
        for line in [
            "#SBATCH --array=0-1%2",
            "#SBATCH --cpus-per-task=2",
            "#SBATCH --partition=compute",
            "#SBATCH --time=01:00:00",
            "#SBATCH --requeue",
            "#SBATCH --constraint=skylake",
            "#SBATCH --job-name=pdamp-fields-003",
            "  0,1\n  2\n",
            "exec '/opt/pdamp/bin/pdamp' --threads \"${SLURM_CPUS_PER_TASK:-2}\" sweep task '/scratch/it'\\''s here' --index",
        ] {
            assert!(s.contains(line), "missing {line:?} in\n{s}");
        }
        let bad = SlurmOptions {
            cpus_per_task: 1,
            max_tasks_per_job: 0,
            ..Default::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("--max-tasks-per-job")
        );
        let bad = SlurmOptions {
            cpus_per_task: 1,
            max_tasks_per_job: 1,
            partition: Some("two words".into()),
            ..Default::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("--partition")
        );
    }
}
