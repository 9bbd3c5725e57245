//! The state of every task of a sweep: from its store (finished, failed, damaged) and, for
//! tasks submitted to Slurm, from the queue (running, pending).

use crate::slurm::QueueState;
use crate::{Submission, SweepError, SweepManifest};
use serde::Serialize;
use std::collections::HashMap;
use std::path::Path;

/// What the store holds for a task (decided by the sweep's kind, which can read its files).
#[derive(Debug, Clone, PartialEq)]
pub enum Stored {
    /// Finished: the result file is there and readable.
    Done,
    /// Failed: the error it left.
    Failed(String),
    /// A result file that cannot be read (damaged, foreign): why. Runs again when resubmitted.
    Corrupt(String),
    /// Nothing stored.
    Missing,
}

/// State of one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "state", content = "message", rename_all = "snake_case")]
pub enum TaskState {
    /// Finished and stored.
    Done,
    /// Failed; the message it stored.
    Failed(String),
    /// Its stored result is damaged: why.
    Corrupt(String),
    /// Running in Slurm.
    Running,
    /// Waiting in Slurm's queue.
    Pending,
    /// Not finished and not in the queue (never submitted, cancelled, killed, or its element
    /// ended without it): `resubmit` runs it.
    Missing,
}

impl TaskState {
    /// Short name (`done`, `failed`, …).
    pub fn name(&self) -> &'static str {
        match self {
            TaskState::Done => "done",
            TaskState::Failed(_) => "failed",
            TaskState::Corrupt(_) => "corrupt",
            TaskState::Running => "running",
            TaskState::Pending => "pending",
            TaskState::Missing => "missing",
        }
    }

    /// Whether a submission should (re)run it.
    pub fn wants_run(&self) -> bool {
        matches!(
            self,
            TaskState::Failed(_) | TaskState::Corrupt(_) | TaskState::Missing
        )
    }
}

/// Queue states of the tasks of all Slurm submissions (task → state); the latest submission
/// of a task wins. An error when `squeue` cannot be asked.
pub fn queued_tasks(submissions: &[Submission]) -> Result<HashMap<usize, QueueState>, SweepError> {
    let ids: Vec<String> = submissions
        .iter()
        .flat_map(|s| s.arrays.iter().map(|a| a.job_id.clone()))
        .collect();
    if ids.is_empty() {
        return Ok(HashMap::new());
    }
    let q = crate::slurm::queue(&ids)?;
    let mut out = HashMap::new();
    for s in submissions {
        for a in &s.arrays {
            for (e, tasks) in a.elements.iter().enumerate() {
                if let Some(state) = q.get(&(a.job_id.clone(), e)) {
                    for &t in tasks {
                        out.insert(t, *state);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// The state of every task: the store first (a finished task is done whatever the queue
/// says), then the queue.
pub fn task_states(
    manifest: &SweepManifest,
    stored: impl Fn(&crate::Task) -> Stored,
    queued: &HashMap<usize, QueueState>,
) -> Vec<TaskState> {
    manifest
        .tasks
        .iter()
        .map(|t| match (stored(t), queued.get(&t.index)) {
            (Stored::Done, _) => TaskState::Done,
            (_, Some(QueueState::Running)) => TaskState::Running,
            (_, Some(QueueState::Pending)) => TaskState::Pending,
            (Stored::Failed(e), None) => TaskState::Failed(e),
            (Stored::Corrupt(e), None) => TaskState::Corrupt(e),
            (Stored::Missing, None) => TaskState::Missing,
        })
        .collect()
}

/// Counts per state, in the order done, running, pending, failed, corrupt, missing.
pub fn counts(states: &[TaskState]) -> [(&'static str, usize); 6] {
    let n = |name: &str| states.iter().filter(|s| s.name() == name).count();
    [
        ("done", n("done")),
        ("running", n("running")),
        ("pending", n("pending")),
        ("failed", n("failed")),
        ("corrupt", n("corrupt")),
        ("missing", n("missing")),
    ]
}

/// A text progress bar of `width` characters: `#` done, `>` running, `.` the rest.
pub fn progress_bar(states: &[TaskState], width: usize) -> String {
    let total = states.len().max(1);
    let done = states.iter().filter(|s| **s == TaskState::Done).count();
    let running = states.iter().filter(|s| **s == TaskState::Running).count();
    let d = done * width / total;
    let r = ((done + running) * width / total).saturating_sub(d);
    format!(
        "[{}{}{}] {done}/{} done",
        "#".repeat(d),
        ">".repeat(r),
        ".".repeat(width.saturating_sub(d + r)),
        states.len()
    )
}

/// Human-readable status of the sweep in `dir`: the bar, the counts, and every task that is
/// not done or waiting with its state (and message).
pub fn render(dir: &Path, manifest: &SweepManifest, states: &[TaskState]) -> String {
    let mut s = format!(
        "sweep {} ({}, {} tasks: {})\n{}\n",
        dir.display(),
        manifest.kind,
        manifest.tasks.len(),
        manifest.title,
        progress_bar(states, 40)
    );
    let parts: Vec<String> = counts(states)
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(name, n)| format!("{n} {name}"))
        .collect();
    s.push_str(&parts.join(", "));
    s.push('\n');
    for (t, st) in manifest.tasks.iter().zip(states) {
        match st {
            TaskState::Failed(e) | TaskState::Corrupt(e) => s.push_str(&format!(
                "  task {} ({}): {}: {e}\n",
                t.index,
                t.label,
                st.name()
            )),
            TaskState::Running | TaskState::Missing => s.push_str(&format!(
                "  task {} ({}): {}\n",
                t.index,
                t.label,
                st.name()
            )),
            _ => {}
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SWEEP_FORMAT, Task};
    use std::path::PathBuf;

    fn manifest(n: usize) -> SweepManifest {
        SweepManifest {
            format: SWEEP_FORMAT,
            pdamp_version: "0".into(),
            kind: "fields".into(),
            title: "t".into(),
            scenario_source: PathBuf::from("/a.toml"),
            base_dir: PathBuf::from("/"),
            scenario_digest: "d".into(),
            parameters: serde_json::Value::Null,
            tasks: (0..n)
                .map(|i| Task {
                    index: i,
                    label: format!("p{i}"),
                    needs: vec![],
                    result: PathBuf::from(format!("r{i}")),
                    error: PathBuf::from(format!("e{i}")),
                })
                .collect(),
        }
    }

    #[test]
    fn the_store_wins_over_the_queue_and_the_queue_over_missing() {
        let m = manifest(5);
        let queued: HashMap<usize, QueueState> = [
            (0, QueueState::Running),
            (1, QueueState::Running),
            (2, QueueState::Pending),
        ]
        .into_iter()
        .collect();
        let stored = |t: &crate::Task| match t.index {
            0 => Stored::Done,
            3 => Stored::Failed("unstable".into()),
            4 => Stored::Corrupt("damaged".into()),
            _ => Stored::Missing,
        };
        let s = task_states(&m, stored, &queued);
        assert_eq!(
            s.iter().map(|x| x.name()).collect::<Vec<_>>(),
            ["done", "running", "pending", "failed", "corrupt"]
        );
        assert!(!s[0].wants_run() && !s[1].wants_run() && !s[2].wants_run());
        assert!(s[3].wants_run() && s[4].wants_run());
        assert_eq!(progress_bar(&s, 10), "[##>>......] 1/5 done");
        let text = render(Path::new("/d"), &m, &s);
        assert!(
            text.contains("1 done, 1 running, 1 pending, 1 failed, 1 corrupt"),
            "{text}"
        );
        assert!(text.contains("task 3 (p3): failed: unstable"), "{text}");
    }
}
