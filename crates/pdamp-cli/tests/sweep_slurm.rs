//! Sweeps (issue 27): an effective field as tasks run here or as Slurm array jobs through a
//! real Slurm (`scripts/slurm-local.sh`, started by `scripts/test.sh`; no mock of sbatch), and
//! collected into exactly the outputs of a local `pdamp fields` run.
//!
//! The Slurm tests need a cluster: with `PDAMP_REQUIRE_SLURM_TESTS=1` (set by scripts/test.sh
//! once its local cluster is up) they must run; without it and without `sbatch` they are
//! skipped with a note.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn ok(o: &Output) -> Value {
    assert!(
        o.status.success(),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap_or(Value::Null)
}

fn failed(o: &Output) -> String {
    assert!(
        !o.status.success(),
        "should fail; stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Whether a Slurm cluster answers; panics where scripts/test.sh promised one.
fn slurm() -> bool {
    let up = Command::new("sinfo")
        .args(["-h", "-o", "%t"])
        .output()
        .is_ok_and(|o| o.status.success() && !o.stdout.is_empty());
    if !up {
        assert!(
            std::env::var("PDAMP_REQUIRE_SLURM_TESTS").is_err(),
            "PDAMP_REQUIRE_SLURM_TESTS is set but no Slurm cluster answers (SLURM_CONF = {:?})",
            std::env::var("SLURM_CONF")
        );
        eprintln!(
            "note: no Slurm cluster (start one with `eval \"$(bash scripts/slurm-local.sh start)\"`): Slurm sweep test skipped"
        );
    }
    up
}

fn status(dir: &Path) -> Value {
    ok(&pdamp()
        .args(["sweep", "status", "--json"])
        .arg(dir)
        .output()
        .unwrap())
}

fn count(s: &Value, state: &str) -> u64 {
    s["counts"][state].as_u64().unwrap()
}

/// Waits until nothing of the sweep is queued or running (at most 15 min).
fn wait_idle(dir: &Path) -> Value {
    let start = Instant::now();
    loop {
        let s = status(dir);
        if count(&s, "running") + count(&s, "pending") == 0 {
            return s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(900),
            "sweep in {} not finished after 15 min: {s}",
            dir.display()
        );
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// fields.csv of two runs: equal in every column but the timing.
fn assert_same_fields(a: &Path, b: &Path) {
    let read = |d: &Path| {
        let text = std::fs::read_to_string(d.join("fields.csv")).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|s| s.to_string())
            .collect();
        let rows: Vec<Vec<String>> = lines
            .map(|l| l.split(',').map(|s| s.to_string()).collect())
            .collect();
        (header, rows)
    };
    let (ha, ra) = read(a);
    let (hb, rb) = read(b);
    assert_eq!(ha, hb);
    assert_eq!(ra.len(), 9);
    assert_eq!(ra.len(), rb.len());
    let timing = ha.iter().position(|c| c == "wall_time_s").unwrap();
    for (x, y) in ra.iter().zip(&rb) {
        for (k, (u, v)) in x.iter().zip(y).enumerate() {
            if k != timing {
                assert_eq!(u, v, "column {} differs: {x:?} vs {y:?}", ha[k]);
            }
        }
    }
    for map in ["effective_loss_factor.png", "effective_mass_ratio.svg"] {
        assert_eq!(
            std::fs::read(a.join(map)).unwrap(),
            std::fs::read(b.join(map)).unwrap(),
            "{map} differs"
        );
    }
}

/// Must-show 1 and 2: the 3 × 3 field of damper_cylinder_small as Slurm arrays (%2 throttle,
/// 2 points per element) collects to the local run's fields.csv and maps; an element cancelled
/// with scancel mid-run shows as missing, `resubmit` runs only the missing points, and the
/// collected result is again identical.
#[test]
fn a_field_through_slurm_equals_the_local_run_also_after_scancel_and_resubmit() {
    if !slurm() {
        return;
    }
    let scenario = examples().join("damper_cylinder_small.toml");
    let local = temp("local");
    ok(&pdamp()
        .args(["--quiet", "fields"])
        .arg(&scenario)
        .arg("--out")
        .arg(&local)
        .output()
        .unwrap());

    // Through Slurm: one array for the bed, one of 5 elements (2 points each, the last 1).
    let swept = temp("slurm");
    let v = ok(&pdamp()
        .arg("fields")
        .arg(&scenario)
        .arg("--out")
        .arg(&swept)
        .args([
            "--backend",
            "slurm",
            "--throttle",
            "2",
            "--max-tasks-per-job",
            "2",
        ])
        .output()
        .unwrap());
    assert_eq!(v["submitted_tasks"], 10);
    assert_eq!(v["arrays"].as_array().unwrap().len(), 2);
    let script = std::fs::read_to_string(swept.join("sweep/slurm/array_001.sh")).unwrap();
    assert!(script.contains("#SBATCH --array=0-4%2"), "{script}");
    let s = wait_idle(&swept);
    assert_eq!(count(&s, "done"), 10, "{s}");
    let c = ok(&pdamp()
        .args(["sweep", "collect"])
        .arg(&swept)
        .output()
        .unwrap());
    assert_eq!(c["points"], 9);
    assert_same_fields(&local, &swept);

    // Cancel the first point element as soon as it runs.
    let cancelled = temp("cancel");
    let v = ok(&pdamp()
        .arg("fields")
        .arg(&scenario)
        .arg("--out")
        .arg(&cancelled)
        .args([
            "--backend",
            "slurm",
            "--throttle",
            "1",
            "--max-tasks-per-job",
            "3",
        ])
        .output()
        .unwrap());
    let points_job = v["arrays"][1].as_str().unwrap().to_string();
    let element = format!("{points_job}_0");
    let start = Instant::now();
    loop {
        let q = Command::new("squeue")
            .args(["-h", "-r", "-j", &points_job, "-o", "%K|%T"])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&q.stdout)
            .lines()
            .any(|l| l.trim() == "0|RUNNING")
        {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "element {element} never ran"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let running = status(&cancelled);
    assert!(count(&running, "running") >= 1, "{running}");
    // Into its first point (≈ 2 s each): SIGTERM saves the point in progress.
    std::thread::sleep(Duration::from_millis(1000));
    let o = Command::new("scancel").arg(&element).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = wait_idle(&cancelled);
    let checkpoints = |d: &Path| -> Vec<PathBuf> {
        std::fs::read_dir(d.join("points"))
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "ckpt"))
            .collect()
    };
    // The point in progress was checkpointed (when the signal came after it started; it is
    // continued from there by the resubmission and gives the same numbers).
    eprintln!(
        "points saved in progress by scancel: {:?}",
        checkpoints(&cancelled)
    );
    let missing = count(&s, "missing");
    assert!(
        (1..=3).contains(&missing),
        "the cancelled element's unfinished points are missing: {s}"
    );
    assert_eq!(
        count(&s, "failed"),
        0,
        "an interruption is not a failure: {s}"
    );
    assert_eq!(count(&s, "done"), 10 - missing);
    // The text status names them.
    let text = pdamp()
        .args(["sweep", "status"])
        .arg(&cancelled)
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&text.stdout).contains(": missing"));
    // Finished points are kept: their files are not touched by the resubmission.
    let finished: Vec<(PathBuf, std::time::SystemTime)> =
        std::fs::read_dir(cancelled.join("points"))
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .map(|p| {
                (
                    p.clone(),
                    std::fs::metadata(&p).unwrap().modified().unwrap(),
                )
            })
            .collect();
    let v = ok(&pdamp()
        .args(["sweep", "resubmit"])
        .arg(&cancelled)
        .output()
        .unwrap());
    assert_eq!(v["submitted_tasks"].as_u64().unwrap(), missing, "{v}");
    let s = wait_idle(&cancelled);
    assert_eq!(count(&s, "done"), 10, "{s}");
    assert!(
        checkpoints(&cancelled).is_empty(),
        "a finished point leaves no checkpoint"
    );
    for (p, t) in finished {
        assert_eq!(
            std::fs::metadata(&p).unwrap().modified().unwrap(),
            t,
            "{}",
            p.display()
        );
    }
    ok(&pdamp()
        .args(["sweep", "collect"])
        .arg(&cancelled)
        .output()
        .unwrap());
    assert_same_fields(&local, &cancelled);
    for d in [local, swept, cancelled] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A 1 × 2 variant of the small cylinder (fast), written next to the examples' tables.
fn tiny_scenario(dir: &Path, seed: u64) -> PathBuf {
    let text = std::fs::read_to_string(examples().join("damper_cylinder_small.toml"))
        .unwrap()
        .replace(
            "frequencies_hz = { from = 40.0, to = 160.0, count = 3, spacing = \"log\" }",
            "frequencies_hz = [160.0]",
        )
        .replace(
            "intensities = { from = 2.0, to = 20.0, count = 3, spacing = \"log\" }",
            "intensities = [5.0, 20.0]",
        )
        .replace("seed = 1", &format!("seed = {seed}"));
    assert!(text.contains("frequencies_hz = [160.0]"));
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join(format!("tiny_{seed}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Must-show 4 without a cluster: the local backend, a store with a damaged task file
/// (status names it, collect refuses naming it, resubmit recomputes only it), a sweep
/// directory of another scenario, no Slurm on the PATH, bad options.
#[test]
fn local_backend_damaged_store_other_scenario_and_no_slurm_are_clear() {
    let work = temp("bad");
    let scenario = tiny_scenario(&work, 1);
    let dir = work.join("sweep");
    ok(&pdamp()
        .args(["sweep", "new"])
        .arg(&scenario)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap());
    let s = status(&dir);
    assert_eq!(s["tasks"], 3);
    assert_eq!(count(&s, "missing"), 3);
    // Collect before anything ran: refused, naming the points.
    let e = failed(
        &pdamp()
            .args(["sweep", "collect"])
            .arg(&dir)
            .output()
            .unwrap(),
    );
    assert!(e.contains("3 of 3 tasks are not finished"), "{e}");
    assert!(e.contains("pdamp sweep resubmit"), "{e}");
    // The local backend runs the tasks here and collects.
    let v = ok(&pdamp()
        .args(["--quiet", "sweep", "submit"])
        .arg(&dir)
        .args(["--backend", "local"])
        .output()
        .unwrap());
    assert_eq!(v["points"], 2, "{v}");
    assert_eq!(count(&status(&dir), "done"), 3);
    let csv = std::fs::read_to_string(dir.join("fields.csv")).unwrap();
    // A damaged point file: named by status and collect, recomputed alone by resubmit.
    let damaged = dir.join("points/f000_a001.json");
    let kept = dir.join("points/f000_a000.json");
    let kept_before = std::fs::read(&kept).unwrap();
    std::fs::write(&damaged, b"{\"frequency_hz\": 1").unwrap();
    let s = status(&dir);
    assert_eq!(count(&s, "corrupt"), 1, "{s}");
    let e = failed(
        &pdamp()
            .args(["sweep", "collect"])
            .arg(&dir)
            .output()
            .unwrap(),
    );
    assert!(e.contains("f000_a001.json is damaged"), "{e}");
    let v = ok(&pdamp()
        .args(["--quiet", "sweep", "resubmit"])
        .arg(&dir)
        .args(["--backend", "local"])
        .output()
        .unwrap());
    assert_eq!(v["points"], 2);
    assert_eq!(std::fs::read(&kept).unwrap(), kept_before);
    let again = std::fs::read_to_string(dir.join("fields.csv")).unwrap();
    let strip = |t: &str| -> Vec<String> {
        t.lines()
            .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string())
            .collect()
    };
    assert_eq!(strip(&csv), strip(&again), "wall_time_s is the last column");
    // A point that failed (its error stored next to its slot, as a task writes it): status
    // shows the message, collect gives its NaN row and names it, resubmit runs it again.
    let point = dir.join("points/f000_a000.json");
    let result = std::fs::read(&point).unwrap();
    std::fs::remove_file(&point).unwrap();
    std::fs::write(
        dir.join("points/f000_a000.error.txt"),
        "unstable: particle 7 left the container",
    )
    .unwrap();
    let s = status(&dir);
    assert_eq!(count(&s, "failed"), 1, "{s}");
    assert!(
        s.to_string().contains("particle 7 left the container"),
        "{s}"
    );
    let o = pdamp()
        .args(["sweep", "collect"])
        .arg(&dir)
        .output()
        .unwrap();
    let v = ok(&o);
    assert_eq!(v["failed_points"].as_array().unwrap().len(), 1, "{v}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("particle 7 left the container"));
    let nan_row = std::fs::read_to_string(dir.join("fields.csv")).unwrap();
    let row = nan_row.lines().nth(1).unwrap();
    assert!(row.starts_with("160,") && row.contains("NaN"), "{row}");
    let v = ok(&pdamp()
        .args(["--quiet", "sweep", "resubmit"])
        .arg(&dir)
        .args(["--backend", "local"])
        .output()
        .unwrap());
    assert!(v["failed_points"].as_array().unwrap().is_empty(), "{v}");
    assert!(!dir.join("points/f000_a000.error.txt").exists());
    let without_time = |b: &[u8]| {
        let mut v: Value = serde_json::from_slice(b).unwrap();
        v["wall_time_s"] = Value::Null;
        v
    };
    assert_eq!(
        without_time(&std::fs::read(&point).unwrap()),
        without_time(&result)
    );
    // A damaged bed file: status says so; a task prepares the bed again.
    let bed = dir.join("beds/packing_000.pdprep");
    let mut bytes = std::fs::read(&bed).unwrap();
    let n = bytes.len();
    bytes[n / 3] ^= 1;
    std::fs::write(&bed, &bytes).unwrap();
    let s = status(&dir);
    assert_eq!(count(&s, "corrupt"), 1, "{s}");
    ok(&pdamp()
        .args(["--quiet", "sweep", "task"])
        .arg(&dir)
        .args(["--index", "0"])
        .output()
        .unwrap());
    assert_eq!(count(&status(&dir), "done"), 3);

    // Another scenario into the same directory: refused, nothing changed.
    let other = tiny_scenario(&work, 2);
    let manifest = std::fs::read(dir.join("sweep.json")).unwrap();
    for args in [vec!["sweep", "new"], vec!["fields", "--backend", "slurm"]] {
        let e = failed(
            &pdamp()
                .args(&args)
                .arg(&other)
                .arg("--out")
                .arg(&dir)
                .output()
                .unwrap(),
        );
        assert!(e.contains("holds a sweep of another scenario"), "{e}");
    }
    assert_eq!(std::fs::read(dir.join("sweep.json")).unwrap(), manifest);
    // The scenario's file edited after the sweep was made: tasks refuse.
    let copy = dir.join("sweep/scenario.toml");
    let original = std::fs::read_to_string(&copy).unwrap();
    std::fs::write(&copy, original.replace("seed = 1", "seed = 3")).unwrap();
    let e = failed(
        &pdamp()
            .args(["sweep", "task"])
            .arg(&dir)
            .args(["--index", "1"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("changed since the sweep was made"), "{e}");
    std::fs::write(&copy, original).unwrap();
    // A task index outside the sweep.
    let e = failed(
        &pdamp()
            .args(["sweep", "task"])
            .arg(&dir)
            .args(["--index", "7"])
            .output()
            .unwrap(),
    );
    assert!(
        e.contains("task 7 does not exist") && e.contains("3 tasks"),
        "{e}"
    );
    // Not a sweep.
    let e = failed(
        &pdamp()
            .args(["sweep", "status"])
            .arg(&work)
            .output()
            .unwrap(),
    );
    assert!(e.contains("not a sweep directory"), "{e}");

    // No Slurm on the PATH: a clear message, nothing lost. (The damaged point is redone
    // first so that there is something to submit.)
    std::fs::write(&damaged, b"x").unwrap();
    let e = failed(
        &pdamp()
            .args(["sweep", "submit"])
            .arg(&dir)
            .env("PATH", "/nonexistent")
            .output()
            .unwrap(),
    );
    assert!(e.contains("`sbatch` is not on the PATH"), "{e}");
    assert!(kept.is_file() && dir.join("beds/packing_000.pdprep").is_file());
    // Options that need Slurm, and bad numbers.
    let e = failed(
        &pdamp()
            .args(["sweep", "submit"])
            .arg(&dir)
            .args(["--backend", "local", "--partition", "x"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("need --backend slurm"), "{e}");
    let e = failed(
        &pdamp()
            .args(["sweep", "submit"])
            .arg(&dir)
            .args(["--max-tasks-per-job", "0", "--dry-run"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("--max-tasks-per-job must be at least 1"), "{e}");
    // A dry run plans without Slurm: 108-style chunking is a unit test of pdamp-sweep; here
    // the plan of the one missing point and its scripts.
    let v = ok(&pdamp()
        .args(["sweep", "submit"])
        .arg(&dir)
        .args(["--dry-run", "--array-limit", "25"])
        .env("PATH", "/nonexistent")
        .output()
        .unwrap());
    assert_eq!(v["tasks"], 1, "{v}");
    let _ = std::fs::remove_dir_all(&work);
}

/// Must-show 3 and 4 with a cluster: 108 tasks with `--array-limit 25` become 5 arrays (and with
/// 4 tasks per job 2), submitted on hold and cancelled; an unknown partition is refused by
/// Slurm before anything is queued.
#[test]
fn arrays_are_chunked_and_an_unknown_partition_is_refused_by_slurm() {
    if !slurm() {
        return;
    }
    let work = temp("chunk");
    // A 12 × 9 grid of the tiny scenario: 1 bed + 108 points.
    let text = std::fs::read_to_string(tiny_scenario(&work, 1))
        .unwrap()
        .replace(
            "frequencies_hz = [160.0]",
            "frequencies_hz = { from = 40.0, to = 1000.0, count = 12, spacing = \"log\" }",
        )
        .replace(
            "intensities = [5.0, 20.0]",
            "intensities = { from = 1.0, to = 40.0, count = 9, spacing = \"log\" }",
        );
    let scenario = work.join("grid.toml");
    std::fs::write(&scenario, text).unwrap();
    let dir = work.join("sweep");
    ok(&pdamp()
        .args(["sweep", "new"])
        .arg(&scenario)
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap());
    let e = failed(
        &pdamp()
            .args(["sweep", "submit"])
            .arg(&dir)
            .args(["--partition", "no_such_partition"])
            .output()
            .unwrap(),
    );
    assert!(
        e.contains("nothing was submitted") && e.to_lowercase().contains("partition"),
        "{e}"
    );
    assert!(!dir.join(pdamp_sweep_submissions()).exists());
    for (per_job, arrays) in [("1", 1 + 5), ("4", 1 + 2)] {
        let v = ok(&pdamp()
            .args(["sweep", "submit"])
            .arg(&dir)
            .args(["--array-limit", "25", "--max-tasks-per-job", per_job])
            .args(["--sbatch-arg=--hold"])
            .output()
            .unwrap());
        let ids: Vec<String> = v["arrays"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap().to_string())
            .collect();
        assert_eq!(ids.len(), arrays, "{v}");
        // Held in the queue: every task pending.
        let s = status(&dir);
        assert_eq!(count(&s, "pending"), 109, "{s}");
        let o = Command::new("scancel").args(&ids).output().unwrap();
        assert!(o.status.success());
        // Cancelled: missing again (Slurm may list them for a moment).
        let s = wait_idle(&dir);
        assert_eq!(count(&s, "missing"), 109, "{s}");
    }
    let last = std::fs::read_to_string(dir.join("sweep/slurm/array_008.sh")).unwrap();
    assert!(last.contains("#SBATCH --array=0-1\n"), "{last}");
    assert!(
        last.contains("  101,102,103,104\n  105,106,107,108\n"),
        "{last}"
    );
    let _ = std::fs::remove_dir_all(&work);
}

fn pdamp_sweep_submissions() -> &'static str {
    "sweep/submissions.json"
}

/// The powder study as a sweep (one task per value and packing, each checkpointed in its
/// folder): through Slurm it collects to the table and ensemble statistics of the local
/// `pdamp powder study` (timing columns aside).
#[test]
fn a_powder_study_through_slurm_equals_the_local_run() {
    if !slurm() {
        return;
    }
    let scenario = examples().join("powder_cantilever_small.toml");
    let args = [
        "--parameter",
        "friction",
        "--values",
        "0.3",
        "--packings",
        "2",
    ];
    let local = temp("powder-local");
    ok(&pdamp()
        .args(["--quiet", "powder", "study"])
        .arg(&scenario)
        .args(args)
        .arg("--out")
        .arg(&local)
        .output()
        .unwrap());
    let swept = temp("powder-slurm");
    let v = ok(&pdamp()
        .args(["powder", "study"])
        .arg(&scenario)
        .args(args)
        .arg("--out")
        .arg(&swept)
        .args(["--backend", "slurm", "--cpus-per-task", "1"])
        .output()
        .unwrap());
    assert_eq!(v["submitted_tasks"], 2, "{v}");
    let s = wait_idle(&swept);
    assert_eq!(count(&s, "done"), 2, "{s}");
    ok(&pdamp()
        .args(["sweep", "collect"])
        .arg(&swept)
        .output()
        .unwrap());
    let table = |d: &Path| -> Vec<String> {
        std::fs::read_to_string(d.join("table.csv"))
            .unwrap()
            .lines()
            .map(|l| {
                let cols: Vec<&str> = l.split(',').collect();
                // the last three columns are wall times
                cols[..cols.len() - 3].join(",")
            })
            .collect()
    };
    assert_eq!(table(&local), table(&swept));
    assert_eq!(table(&local).len(), 3);
    assert_eq!(
        std::fs::read_to_string(local.join("ensemble.csv")).unwrap(),
        std::fs::read_to_string(swept.join("ensemble.csv")).unwrap()
    );
    // --resume/--overwrite and a single run are refused with the reason.
    let e = failed(
        &pdamp()
            .args(["powder", "run"])
            .arg(&scenario)
            .arg("--out")
            .arg(temp("powder-single"))
            .args(["--backend", "slurm"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("give --packings K"), "{e}");
    for d in [local, swept] {
        let _ = std::fs::remove_dir_all(d);
    }
}
