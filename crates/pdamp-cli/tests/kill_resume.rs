//! Kill-and-resume: `pdamp run` killed with SIGKILL at random moments (settling and main run)
//! and resumed with `--resume` ends with outputs identical to an uninterrupted run; SIGINT
//! writes a checkpoint and exits with status 130. Same thread count throughout (results are
//! also independent of it, see `determinism_across_thread_counts`). The same for `pdamp
//! couple` (full-DEM dampers) and `pdamp powder run`/`study` (the DEM–FEM runs, `powder_*`).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn pdamp() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pdamp"))
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp-kill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small shaken box: 250 particles, 10 ms settling + 30 ms shaking, VTK every 5 ms.
fn scenario(dir: &Path) -> PathBuf {
    let out = pdamp()
        .args(["example", "--particles", "250", "--duration-s", "0.03"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout)
        .unwrap()
        .replace("max_duration_s = 0.05", "max_duration_s = 0.01")
        .replace("vtk_interval_s = 0.05", "vtk_interval_s = 0.005");
    assert!(text.contains("max_duration_s = 0.01") && text.contains("vtk_interval_s = 0.005"));
    let p = dir.join("scenario.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn run(scn: &Path, out: &Path, threads: &str, extra: &[&str]) -> Command {
    let mut c = pdamp();
    c.args(["--threads", threads, "run"])
        .arg(scn)
        .arg("--out")
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

/// Every output file except the timing fields of summary.json and the checkpoint itself.
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let name = p.strip_prefix(dir).unwrap().to_string_lossy().to_string();
            // provenance.json and input.toml record the command, not its results (a study's
            // case directory has neither).
            // manifest.json records the command line too; .pdamp.lock is the directory's lock.
            if name == "checkpoint.bin"
                || name == "manifest.json"
                || name == ".pdamp.lock"
                || name == "provenance.json"
                || name == "input.toml"
                || name.contains(".tmp-")
            {
                continue;
            }
            let mut bytes = std::fs::read(&p).unwrap();
            if name == "summary.json" {
                let text = String::from_utf8(bytes).unwrap();
                bytes = text
                    .lines()
                    .filter(|l| !l.contains("wall_time_s") && !l.contains("particle_steps_per_s"))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .into_bytes();
            }
            files.push((name, bytes));
        }
    }
    files.sort();
    files
}

fn assert_same(a: &Path, b: &Path) {
    let (fa, fb) = (outputs(a), outputs(b));
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&fa), names(&fb), "same files");
    for ((n, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(
            x == y,
            "{n} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    assert!(fa.iter().any(|f| f.0 == "energy.csv") && fa.len() > 8);
}

/// xorshift64*: reproducible "random" kill times from the process id.
fn next(state: &mut u64) -> f64 {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
}

/// Waits `wait`, then (unless `any_time`) until the child has written a checkpoint newer than
/// `before`, then kills it with SIGKILL. Returns false when the child finished first.
fn kill_after_checkpoint(
    child: &mut std::process::Child,
    ckpt: &Path,
    before: Option<std::time::SystemTime>,
    wait: Duration,
    any_time: bool,
) -> bool {
    std::thread::sleep(wait);
    let stamp = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        if any_time || stamp(ckpt) != before || Instant::now() > deadline {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    true
}

fn checkpoint_stamp(p: &Path) -> Option<std::time::SystemTime> {
    std::fs::metadata(p).and_then(|m| m.modified()).ok()
}

#[test]
fn sigkill_at_random_moments_then_resume_gives_identical_outputs() {
    let dir = scratch("sigkill");
    let scn = scenario(&dir);
    let reference = dir.join("reference");
    let t0 = Instant::now();
    let st = run(&scn, &reference, "2", &[]).status().unwrap();
    assert!(st.success());
    let full = t0.elapsed().as_secs_f64();

    let out = dir.join("killed");
    let mut rng = 0x9e37_79b9_7f4a_7c15u64 ^ std::process::id() as u64;
    let mut kills = 0;
    let mut resumed_from_checkpoint = 0;
    let ckpt = out.join("checkpoint.bin");
    for attempt in 0..8 {
        let args: &[&str] = if attempt == 0 {
            &["--checkpoint-interval-s", "0.05"]
        } else {
            &["--checkpoint-interval-s", "0.05", "--resume"]
        };
        let before = checkpoint_stamp(&ckpt);
        let mut child = run(&scn, &out, "2", args).spawn().unwrap();
        // Kill at a random moment in the first 2–20 % of a full run's duration, but (after the
        // first attempt) not before this process has written a checkpoint of its own, so that
        // every attempt makes progress and the test does not depend on machine load.
        let wait = Duration::from_secs_f64(full * (0.02 + 0.18 * next(&mut rng)));
        if !kill_after_checkpoint(&mut child, &ckpt, before, wait, attempt == 0) {
            break;
        }
        kills += 1;
        if ckpt.exists() {
            resumed_from_checkpoint += 1;
        }
    }
    let st = run(&scn, &out, "2", &["--resume"]).status().unwrap();
    assert!(st.success());
    eprintln!(
        "{kills} SIGKILLs ({resumed_from_checkpoint} after a checkpoint existed); full run {full:.2} s"
    );
    assert!(kills >= 3, "the run was killed several times ({kills})");
    assert!(resumed_from_checkpoint >= 2);
    assert_same(&reference, &out);
    // Resuming a finished run changes nothing.
    let st = run(&scn, &out, "2", &["--resume"]).status().unwrap();
    assert!(st.success());
    assert_same(&reference, &out);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 31, severe defect 2: a rerun without `--resume` used to truncate `energy.csv` at once
/// while the old "finished" checkpoint stayed until the new run's first checkpoint; killed in
/// between, a following `--resume` printed the old summary and exited 0 with a fraction of the
/// energy rows. Now the rerun is refused, `--overwrite` removes the old checkpoint with the
/// other files, and `--resume` after a kill before the first checkpoint says there is nothing
/// to resume (status 1). Outputs cut behind the checkpoint's back are refused on `--resume`.
#[test]
fn rerun_over_results_is_refused_and_resume_never_reports_a_truncated_run() {
    let d = scratch("rerun");
    let scn = scenario(&d);
    let out = d.join("out");
    let st = run(&scn, &out, "2", &[]).status().unwrap();
    assert!(st.success());
    let energy = std::fs::read(out.join("energy.csv")).unwrap();
    // A plain rerun is refused and touches nothing.
    let o = run(&scn, &out, "2", &[]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("already holds the results") && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(std::fs::read(out.join("energy.csv")).unwrap(), energy);
    // --overwrite killed before its first checkpoint (interval 0: none until the end).
    let mut child = run(
        &scn,
        &out,
        "1",
        &["--overwrite", "--checkpoint-interval-s", "0"],
    )
    .spawn()
    .unwrap();
    let t0 = Instant::now();
    // The new run has taken the directory (manifest "running") and opened its energy.csv.
    let started = || {
        std::fs::read_to_string(out.join("manifest.json")).is_ok_and(|m| m.contains("running"))
            && out.join("energy.csv").exists()
    };
    while !started() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !out.join("checkpoint.bin").exists(),
        "the old run's checkpoint must be gone once the new run writes"
    );
    // Nothing to resume: said, and the run starts again (complete outputs, never the old
    // summary over a truncated energy.csv).
    let o = run(&scn, &out, "2", &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(err.contains("nothing to resume"), "{err}");
    assert_eq!(std::fs::read(out.join("energy.csv")).unwrap(), energy);
    // A directory with results of another command and no checkpoint is refused.
    std::fs::remove_file(out.join("checkpoint.bin")).unwrap();
    let o = run(&scn, &d.join("elsewhere"), "2", &[]).output().unwrap();
    assert!(o.status.success());
    let mut m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    m["command"] = serde_json::json!(["pdamp", "fields", "other.toml"]);
    std::fs::write(out.join("manifest.json"), m.to_string()).unwrap();
    let o = run(&scn, &out, "2", &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("nothing to resume"), "{err}");
    // --overwrite runs it again; a finished run resumes to its summary; the manifest lists
    // what the run wrote.
    let st = run(&scn, &out, "2", &["--overwrite"]).status().unwrap();
    assert!(st.success());
    let o = run(&scn, &out, "2", &["--resume"]).output().unwrap();
    assert!(o.status.success(), "a finished run resumes to its summary");
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["status"], "finished");
    assert!(
        manifest["files"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f == "energy.csv"),
        "{manifest}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn resume_refuses_outputs_that_do_not_match_the_checkpoint() {
    let d = scratch("mismatch");
    let scn = scenario(&d);
    // Long enough (3 s simulated) to be stopped in the main run.
    let text = std::fs::read_to_string(&scn).unwrap();
    let long = text.replace("duration_s = 0.03", "duration_s = 3.0");
    assert_ne!(long, text);
    std::fs::write(&scn, long).unwrap();
    let out = d.join("out");
    // SIGINT in the main run: a checkpoint with energy rows behind it.
    let mut child = run(&scn, &out, "1", &[])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while std::fs::metadata(out.join("energy.csv")).map_or(0, |m| m.len()) < 2000
        && t0.elapsed() < Duration::from_secs(120)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    sigint(child.id());
    let st = child.wait().unwrap();
    assert_eq!(st.code(), Some(130));
    // Same length, fewer rows: two rows merged into one line.
    let text = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    let cut = text.replacen("\n", " ", 2).replacen(' ', "\n", 1);
    assert_eq!(cut.len(), text.len());
    std::fs::write(out.join("energy.csv"), cut).unwrap();
    let o = run(&scn, &out, "1", &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("do not match the checkpoint"), "{err}");
    // A missing VTK frame listed in the checkpoint is refused too.
    std::fs::write(out.join("energy.csv"), &text).unwrap();
    let frame = std::fs::read_dir(out.join("vtk"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::remove_file(&frame).unwrap();
    let o = run(&scn, &out, "1", &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("missing"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// A small damper point (20 spheres in a shaken box, 8 cycles at 30 Hz) with velocity fields,
/// trajectories, VTK frames and two packings.
const DAMPER_POINT: &str = r#"title = "damper point resume"

[simulation]
duration_s = 0.0
time_step_s = 2e-6
seed = 5

[[materials]]
name = "steel"
density_kg_m3 = 7800.0
youngs_modulus_pa = 2e9
poisson_ratio = 0.3

[contact]
normal = { law = "hertz-mindlin", restitution = 0.6 }
friction = { law = "mindlin", friction_coefficient = 0.3 }

[[bodies]]
name = "box"

[[bodies.walls]]
name = "container"
material = "steel"
geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.01], half_extents_m = [0.01, 0.01, 0.01] }

[[particles]]
material = "steel"
count = 20
size = { type = "monodisperse", radius_m = 0.001 }
placement = { method = "random", region = { type = "box", min_m = [-0.009, -0.009, 0.001], max_m = [0.009, 0.009, 0.019] } }

[settle]
max_duration_s = 0.01

[damper]
container_body = "box"
container_mass_kg = 0.05
direction = [1.0, 0.0, 0.0]
frequency_hz = 30.0
amplitude_m = 0.002
cycles = 8
transient_cycles = 2
packings = 2
motion_output = { phases_per_cycle = 4, field_cells = 6, trajectory_particles = [0, 7], vtk_frames_per_cycle = 4 }
"#;

/// Issue 31 item 6: a damper point (`run` with [damper]) checkpoints and resumes like a plain
/// run: SIGKILL at random moments after a checkpoint, then SIGINT, then --resume, ends with
/// outputs identical to an uninterrupted run.
#[test]
fn damper_point_killed_and_resumed_gives_identical_outputs() {
    let d = scratch("damper");
    let scn = d.join("damper.toml");
    std::fs::write(&scn, DAMPER_POINT).unwrap();
    let reference = d.join("reference");
    let t0 = Instant::now();
    let o = run(&scn, &reference, "2", &[]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full = t0.elapsed();
    let out = d.join("interrupted");
    let ckpt = out.join("checkpoint.bin");
    let mut state = 0x9e37_79b9_7f4a_7c15 ^ u64::from(std::process::id());
    let mut kills = 0;
    let mut resume = false;
    for _ in 0..6 {
        let extra: &[&str] = if resume {
            &["--resume", "--checkpoint-interval-s", "0.05"]
        } else {
            &["--checkpoint-interval-s", "0.05"]
        };
        let mut child = run(&scn, &out, "2", extra).spawn().unwrap();
        let before = checkpoint_stamp(&ckpt);
        let wait = full.mul_f64(0.1 + 0.3 * next(&mut state));
        if !kill_after_checkpoint(&mut child, &ckpt, before, wait, false) {
            break;
        }
        kills += 1;
        resume = true;
    }
    let o = run(&scn, &out, "2", &["--resume"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        kills >= 1,
        "the point was never interrupted (it ran in {full:?})"
    );
    let files = outputs(&reference);
    let names: Vec<&str> = files.iter().map(|f| f.0.as_str()).collect();
    for f in [
        "summary.json",
        "velocity_fields.csv",
        "trajectories.csv",
        "particles.pvd",
    ] {
        assert!(names.contains(&f), "{f} missing in {names:?}");
    }
    let got: Vec<String> = outputs(&out).into_iter().map(|f| f.0).collect();
    assert_eq!(got, names, "files after {kills} kills");
    for ((n, x), (_, y)) in files.iter().zip(&outputs(&out)) {
        assert!(x == y, "{n} differs after {kills} kills");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Two runs into one directory at once: the second is refused while the first holds it (it
/// used to end with both exiting 0 and a mixed energy.csv); the first ends normally.
#[test]
fn a_second_run_into_a_busy_directory_is_refused() {
    let d = scratch("busy");
    let scn = scenario(&d);
    let text = std::fs::read_to_string(&scn).unwrap();
    std::fs::write(&scn, text.replace("duration_s = 0.03", "duration_s = 0.5")).unwrap();
    let out = d.join("out");
    let mut first = run(&scn, &out, "1", &[])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !out.join("manifest.json").exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let o = run(&scn, &out, "1", &["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("in use by another pdamp run")
            && err.contains(&format!("process {}", first.id())),
        "{err}"
    );
    sigint(first.id());
    assert_eq!(first.wait().unwrap().code(), Some(130));
    let _ = std::fs::remove_dir_all(&d);
}

/// An output name that is a symbolic link out of the directory is refused; its target is
/// left as it was (energy.csv used to be truncated through the link).
#[cfg(unix)]
#[test]
fn outputs_are_never_written_through_a_link() {
    let d = scratch("link");
    let scn = scenario(&d);
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // The VTK folder as a link to a folder of the user's.
    let target = d.join("precious");
    std::fs::create_dir_all(&target).unwrap();
    std::fs::write(target.join("notes.txt"), "keep me").unwrap();
    std::os::unix::fs::symlink(&target, out.join("vtk")).unwrap();
    let o = run(&scn, &out, "1", &[]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("symbolic link"), "{err}");
    assert_eq!(std::fs::read_dir(&target).unwrap().count(), 1);
    // A stale energy.csv linked out of the directory: --overwrite removes the link, not the
    // file it points to.
    std::fs::remove_file(out.join("vtk")).unwrap();
    let file = d.join("precious.csv");
    std::fs::write(&file, "keep me").unwrap();
    std::os::unix::fs::symlink(&file, out.join("energy.csv")).unwrap();
    let o = run(&scn, &out, "1", &["--overwrite"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    assert!(
        !std::fs::symlink_metadata(out.join("energy.csv"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Sends SIGINT to a process.
fn sigint(pid: u32) {
    let st = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
        .unwrap();
    assert!(st.success());
}

#[test]
fn sigint_writes_checkpoint_and_exits_130() {
    let dir = scratch("sigint");
    let scn = scenario(&dir);
    let reference = dir.join("reference");
    let t0 = Instant::now();
    assert!(run(&scn, &reference, "2", &[]).status().unwrap().success());
    let full = t0.elapsed().as_secs_f64();
    let out = dir.join("interrupted");
    let child = run(&scn, &out, "2", &["--checkpoint-interval-s", "0"])
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs_f64(full * 0.3));
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("continue with --resume"), "{err}");
    assert!(out.join("checkpoint.bin").exists());
    assert!(
        run(&scn, &out, "2", &["--resume"])
            .status()
            .unwrap()
            .success()
    );
    assert_same(&reference, &out);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn determinism_across_thread_counts() {
    let dir = scratch("threads");
    let scn = scenario(&dir);
    let (a, b, c) = (dir.join("t1"), dir.join("t2"), dir.join("t2again"));
    assert!(run(&scn, &a, "1", &[]).status().unwrap().success());
    assert!(run(&scn, &b, "2", &[]).status().unwrap().success());
    assert!(run(&scn, &c, "2", &[]).status().unwrap().success());
    assert_same(&b, &c);
    // Thread count is recorded in summary.json; everything else is identical.
    let strip = |d: &Path| {
        outputs(d)
            .into_iter()
            .map(|(n, b)| {
                let t = String::from_utf8_lossy(&b)
                    .lines()
                    .filter(|l| !l.contains("\"threads\""))
                    .collect::<Vec<_>>()
                    .join("\n");
                (n, t)
            })
            .collect::<Vec<_>>()
    };
    assert!(
        strip(&a) == strip(&b),
        "1 and 2 threads give identical outputs"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resume_refuses_a_changed_scenario() {
    let dir = scratch("changed");
    let scn = scenario(&dir);
    let out = dir.join("out");
    let child = run(&scn, &out, "2", &["--checkpoint-interval-s", "0"])
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    if o.status.success() {
        return; // finished before the signal: nothing to check
    }
    let text = std::fs::read_to_string(&scn)
        .unwrap()
        .replace("seed = 1", "seed = 2");
    std::fs::write(&scn, text).unwrap();
    let o = run(&scn, &out, "2", &["--resume"]).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("different scenario"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pdamp fields` stopped by SIGINT keeps its finished points; running it again computes only
/// the others, and the field equals an uninterrupted one (all columns but the wall time).
#[test]
fn fields_sigint_then_rerun_gives_the_same_field() {
    let dir = scratch("fields");
    let src =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/damper_cylinder_small.toml");
    let text = std::fs::read_to_string(src).unwrap();
    let text = text
        .replace("cycles = 8\ntransient_cycles = 3", "cycles = 4\ntransient_cycles = 1")
        .replace(
            "frequencies_hz = { from = 40.0, to = 160.0, count = 3, spacing = \"log\" }\nintensities = { from = 2.0, to = 20.0, count = 3, spacing = \"log\" }",
            "frequencies_hz = [150.0, 200.0, 250.0]\nintensities = [5.0, 10.0]",
        );
    assert!(text.contains("cycles = 4") && text.contains("[150.0, 200.0, 250.0]"));
    let scn = dir.join("fields.toml");
    std::fs::write(&scn, text).unwrap();
    let fields = |out: &Path| {
        let mut c = pdamp();
        c.args(["--threads", "2", "fields"])
            .arg(&scn)
            .arg("--out")
            .arg(out)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    let reference = dir.join("reference");
    assert!(fields(&reference).status().unwrap().success());
    let out = dir.join("stopped");
    let child = fields(&out).spawn().unwrap();
    let t0 = Instant::now();
    let count = || {
        std::fs::read_dir(out.join("points"))
            .map(|d| {
                d.filter(|e| {
                    e.as_ref()
                        .unwrap()
                        .path()
                        .extension()
                        .is_some_and(|x| x == "json")
                })
                .count()
            })
            .unwrap_or(0)
    };
    while count() < 2 && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    if o.status.success() {
        eprintln!("finished before the signal; nothing to resume");
    } else {
        assert_eq!(o.status.code(), Some(130), "{err}");
        assert!(err.contains("points are finished"), "{err}");
        assert!(!out.join("fields.csv").exists(), "no partial fields.csv");
        assert!(fields(&out).status().unwrap().success());
    }
    let table = |d: &Path| {
        std::fs::read_to_string(d.join("fields.csv"))
            .unwrap()
            .lines()
            .map(|l| l.rsplit_once(',').unwrap().0.to_string())
            .collect::<Vec<_>>()
    };
    let (a, b) = (table(&reference), table(&out));
    assert_eq!(a.len(), 7);
    assert_eq!(a, b, "same field apart from wall_time_s");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pdamp couple` with a full-DEM damper (approach 1) killed with SIGKILL and resumed ends
/// with the same decay, damping and summary as an uninterrupted run.
#[test]
fn couple_dem_sigkill_then_resume_gives_identical_outputs() {
    let dir = scratch("couple");
    let ex = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let text = std::fs::read_to_string(ex.join("couple_ch5_free_dem_small.toml"))
        .unwrap()
        .replace(
            "structure_file = \"structure_ch5_beam.toml\"",
            &format!("structure_file = {:?}", ex.join("structure_ch5_beam.toml")),
        )
        .replace(
            "scenario = \"damper_ch5_small.toml\"",
            &format!("scenario = {:?}", ex.join("damper_ch5_small.toml")),
        )
        .replace("duration_s = 4.0", "duration_s = 1.5");
    assert!(text.contains("duration_s = 1.5") && text.contains("examples/damper_ch5_small"));
    let scn = dir.join("couple.toml");
    std::fs::write(&scn, text).unwrap();
    let couple = |out: &Path, extra: &[&str]| {
        let mut c = pdamp();
        c.args(["--threads", "2", "couple"])
            .arg(&scn)
            .arg("--out")
            .arg(out)
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    let reference = dir.join("reference");
    let t0 = Instant::now();
    assert!(couple(&reference, &[]).status().unwrap().success());
    let full = t0.elapsed().as_secs_f64();
    let out = dir.join("killed");
    let mut rng = 0x1234_5678_9abc_def1u64 ^ std::process::id() as u64;
    let mut kills = 0;
    for attempt in 0..6 {
        let args: &[&str] = if attempt == 0 {
            &["--checkpoint-interval-s", "0.05"]
        } else {
            &["--checkpoint-interval-s", "0.05", "--resume"]
        };
        let ckpt = out.join("checkpoint.bin");
        let before = checkpoint_stamp(&ckpt);
        let mut child = couple(&out, args).spawn().unwrap();
        let wait = Duration::from_secs_f64(full * (0.1 + 0.15 * next(&mut rng)));
        if !kill_after_checkpoint(&mut child, &ckpt, before, wait, false) {
            break;
        }
        kills += 1;
    }
    assert!(couple(&out, &["--resume"]).status().unwrap().success());
    eprintln!("couple: {kills} SIGKILLs; full run {full:.2} s");
    assert!(kills >= 2, "killed several times ({kills})");
    for f in ["decay.csv", "damping.csv"] {
        assert!(
            std::fs::read(reference.join(f)).unwrap() == std::fs::read(out.join(f)).unwrap(),
            "{f} differs"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pdamp couple` with a segmented forced sweep and a full-DEM damper (frequency-domain
/// approach, 3 overlapping segments, peak hold) killed with SIGKILL after checkpoints (inside
/// segments and between them) and resumed ends with the same FRFs, response and summary as an
/// uninterrupted run, byte for byte.
#[test]
fn couple_dem_segmented_sweep_sigkill_then_resume_gives_identical_outputs() {
    let dir = scratch("couple-segments");
    let ex = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    // the ch5 DEM damper (36 spheres) on a 20 Hz single mode, 15 → 25 Hz in 0.9 s, 3 segments
    let text = format!(
        "[structure]\n[structure.single_mode]\nmass_kg = 1.058\nstiffness_n_m = 16707.0\n\
         damping_n_s_m = 1.3\n\n[[dampers]]\nmodel = \"dem\"\npoint = \"damper\"\nscenario = {:?}\n\n\
         [analysis]\nkind = \"sweep\"\nstart_hz = 15.0\nend_hz = 25.0\nduration_s = 0.9\n\
         force_amplitude_n = 5.0\nexcitation_point = \"excitation\"\noutput_point = \"output\"\n\
         time_step_s = 1e-4\nsample_every = 4\nwindow_cycles = 4\nsegments = 3\n",
        ex.join("damper_ch5_small.toml")
    );
    let scn = dir.join("couple.toml");
    std::fs::write(&scn, text).unwrap();
    let couple = |out: &Path, extra: &[&str]| {
        let mut c = pdamp();
        c.args(["--threads", "2", "couple"])
            .arg(&scn)
            .arg("--out")
            .arg(out)
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        c
    };
    let reference = dir.join("reference");
    let t0 = Instant::now();
    let r = couple(&reference, &[]).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let full = t0.elapsed().as_secs_f64();
    let out = dir.join("killed");
    let mut rng = 0x0bad_cafe_1234_5678u64 ^ std::process::id() as u64;
    let mut kills = 0;
    for attempt in 0..8 {
        let args: &[&str] = if attempt == 0 {
            &["--checkpoint-interval-s", "0.05"]
        } else {
            &["--checkpoint-interval-s", "0.05", "--resume"]
        };
        // wait for any new checkpoint: a segment's own or the finished-segments file
        let stamps = |d: &Path| -> Vec<Option<std::time::SystemTime>> {
            (0..3)
                .map(|i| checkpoint_stamp(&d.join(format!("checkpoint_segment_{i}.bin"))))
                .chain([checkpoint_stamp(&d.join("checkpoint.bin"))])
                .collect()
        };
        let before = stamps(&out);
        let mut child = couple(&out, args).spawn().unwrap();
        std::thread::sleep(Duration::from_secs_f64(
            full * (0.08 + 0.12 * next(&mut rng)),
        ));
        let deadline = Instant::now() + Duration::from_secs(120);
        let finished = loop {
            if child.try_wait().unwrap().is_some() {
                break true;
            }
            if stamps(&out) != before || Instant::now() > deadline {
                break false;
            }
            std::thread::sleep(Duration::from_millis(2));
        };
        if finished {
            break;
        }
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
        kills += 1;
    }
    let r = couple(&out, &["--resume"]).output().unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    eprintln!("couple segments: {kills} SIGKILLs; full run {full:.2} s");
    assert!(kills >= 2, "killed several times ({kills})");
    for f in ["frf.csv", "frf_segments.csv", "response.csv"] {
        assert!(
            std::fs::read(reference.join(f)).unwrap() == std::fs::read(out.join(f)).unwrap(),
            "{f} differs"
        );
    }
    let summary = |d: &Path| -> String {
        std::fs::read_to_string(d.join("summary.json"))
            .unwrap()
            .lines()
            .filter(|l| !l.contains("wall_time_s"))
            .collect()
    };
    assert_eq!(summary(&reference), summary(&out), "summary.json differs");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- `pdamp powder run` / `study` (DEM–FEM) ----

/// The reduced cantilever `examples/powder_cantilever_small.toml` shortened to 4 ms (load ramp
/// and hold 2.5 ms, then 1.5 ms of free decay): ≈ 540 particles, preparation (settling,
/// compression, relaxation) ≈ 3 s, 400 coupled steps ≈ 4 s on an idle machine.
fn powder_scenario(path: &Path, seed: u64) -> PathBuf {
    let src = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/powder_cantilever_small.toml");
    let text = std::fs::read_to_string(src)
        .unwrap()
        .replace("duration_s = 0.008", "duration_s = 0.004")
        .replace("seed = 1\n", &format!("seed = {seed}\n"));
    assert!(text.contains("duration_s = 0.004") && text.contains(&format!("seed = {seed}\n")));
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

fn powder(threads: &str, args: &[&str], scn: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = pdamp();
    c.args(["--threads", threads, "powder"])
        .args(args)
        .arg(scn)
        .args(["--out"])
        .arg(out)
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    c
}

/// The uninterrupted reference run (2 threads), shared by the powder tests: (scratch dir,
/// scenario, output dir, wall time of the run in s).
fn powder_reference() -> &'static (PathBuf, PathBuf, PathBuf, f64) {
    static REF: std::sync::OnceLock<(PathBuf, PathBuf, PathBuf, f64)> = std::sync::OnceLock::new();
    REF.get_or_init(|| {
        let dir = scratch("powder");
        let scn = powder_scenario(&dir.join("cantilever.toml"), 1);
        let out = dir.join("reference");
        let t0 = Instant::now();
        let o = powder("2", &["run"], &scn, &out, &[]).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (dir, scn, out, t0.elapsed().as_secs_f64())
    })
}

/// Removes the shared scratch dir once all three powder tests are done.
fn powder_test_done() {
    static DONE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    if DONE.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1 == 3 {
        let _ = std::fs::remove_dir_all(&powder_reference().0);
    }
}

/// All outputs of a powder run (tip.csv, envelope.csv, energy.csv, summary.json without its
/// wall times, tip.png/svg) are identical byte for byte.
fn assert_same_powder(a: &Path, b: &Path) {
    let (fa, fb) = (outputs(a), outputs(b));
    let names = |f: &[(String, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&fa), names(&fb), "same files");
    for f in [
        "tip.csv",
        "envelope.csv",
        "energy.csv",
        "summary.json",
        "tip.png",
    ] {
        assert!(names(&fa).iter().any(|n| n == f), "{f} missing");
    }
    for ((n, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(
            x == y,
            "{n} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// Sends SIGINT to `child` as soon as a line of its stderr contains `pattern`; returns the exit
/// code and the whole stderr.
fn sigint_on_line(mut child: std::process::Child, pattern: &str) -> (Option<i32>, String) {
    use std::io::BufRead;
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut all = String::new();
        for line in std::io::BufReader::new(stderr).lines() {
            let line = line.unwrap_or_default();
            let _ = tx.send(line.clone());
            all.push_str(&line);
            all.push('\n');
        }
        all
    });
    for line in rx.iter() {
        if line.contains(pattern) {
            let k = Command::new("kill")
                .args(["-INT", &child.id().to_string()])
                .status()
                .unwrap();
            assert!(k.success());
            break;
        }
    }
    let status = child.wait().unwrap();
    (status.code(), reader.join().unwrap())
}

/// `pdamp powder run` killed with SIGKILL at random moments (preparation and coupled run),
/// each time after it wrote a checkpoint of its own, and resumed: the outputs equal those of
/// the uninterrupted run byte for byte.
#[test]
fn powder_sigkill_at_random_moments_then_resume_gives_identical_outputs() {
    let (dir, scn, reference, full) = powder_reference();
    let full = *full;
    let out = dir.join("killed");
    let ckpt = out.join("checkpoint.bin");
    let mut rng = 0x5eed_0fd3_f3a1_u64 ^ std::process::id() as u64;
    let (mut kills, mut resumed_from_checkpoint) = (0, 0);
    let mut stages = Vec::new();
    for attempt in 0..8 {
        let args: &[&str] = if attempt == 0 {
            &["--checkpoint-interval-s", "0.05"]
        } else {
            &["--checkpoint-interval-s", "0.05", "--resume"]
        };
        let before = checkpoint_stamp(&ckpt);
        let mut child = powder("2", &["run"], scn, &out, args).spawn().unwrap();
        // as for `pdamp run`: a random moment, then (after the first attempt) not before this
        // process has written a checkpoint of its own
        let wait = Duration::from_secs_f64(full * (0.03 + 0.2 * next(&mut rng)));
        if !kill_after_checkpoint(&mut child, &ckpt, before, wait, attempt == 0) {
            break;
        }
        kills += 1;
        if ckpt.exists() {
            resumed_from_checkpoint += 1;
        }
        let mut err = String::new();
        let _ = std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err);
        let stage = err.lines().last().unwrap_or("(start)").to_string();
        stages.push(stage);
    }
    let o = powder("2", &["run"], scn, &out, &["--resume"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    eprintln!(
        "powder: {kills} SIGKILLs ({resumed_from_checkpoint} after a checkpoint existed), last progress lines {stages:?}; full run {full:.2} s"
    );
    assert!(kills >= 3, "the run was killed several times ({kills})");
    assert!(resumed_from_checkpoint >= 2);
    assert_same_powder(reference, &out);
    // resuming a finished run changes nothing
    let o = powder("2", &["run"], scn, &out, &["--resume"])
        .output()
        .unwrap();
    assert!(o.status.success());
    assert_same_powder(reference, &out);
    powder_test_done();
}

/// SIGINT during the preparation and during the coupled run writes a checkpoint and exits
/// with status 130; a checkpoint of another scenario is refused; resuming after the coupled-run
/// checkpoint does not redo the preparation and ends as the uninterrupted run.
#[test]
fn powder_sigint_then_resume_gives_identical_outputs_and_refuses_other_scenarios() {
    let (dir, scn, reference, _) = powder_reference();
    let out = dir.join("interrupted");
    let ckpt = out.join("checkpoint.bin");
    let run = |extra: &[&str]| powder("2", &["run"], scn, &out, extra);
    let (code, err) = sigint_on_line(
        run(&["--checkpoint-interval-s", "0"]).spawn().unwrap(),
        "settling",
    );
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("continue with --resume"), "{err}");
    assert!(ckpt.exists());
    // another scenario (seed 2) in the same directory: refused, checkpoint kept
    let other = powder_scenario(&dir.join("other.toml"), 2);
    let o = powder("2", &["run"], &other, &out, &["--resume"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("different scenario"), "{e}");
    assert!(!out.join("summary.json").exists());
    // continue the preparation, stop again in the coupled run
    let (code, err) = sigint_on_line(
        run(&["--resume", "--checkpoint-interval-s", "0"])
            .spawn()
            .unwrap(),
        "coupled run",
    );
    assert_eq!(code, Some(130), "{err}");
    let o = run(&["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        !err.contains("settling") && !err.contains("compressing"),
        "the preparation is not redone: {err}"
    );
    assert_same_powder(reference, &out);
    powder_test_done();
}

/// `pdamp powder study --resume` continues inside the interrupted run (not from its start).
/// The study runs on 1 thread throughout and is compared with the 2-thread reference: results
/// do not depend on the thread count either.
#[test]
fn powder_study_resumes_inside_the_interrupted_run_on_one_thread() {
    let (dir, scn, reference, _) = powder_reference();
    let out = dir.join("study");
    let study = |extra: &[&str]| {
        powder(
            "1",
            &[
                "study",
                "--parameter",
                "packing-density",
                "--values",
                "0.58",
            ],
            scn,
            &out,
            extra,
        )
    };
    let (code, err) = sigint_on_line(study(&[]).spawn().unwrap(), "coupled run");
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("continue with --resume"), "{err}");
    let o = study(&["--resume"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        !err.contains("settling"),
        "resumed inside the run, after its preparation: {err}"
    );
    // packing density 0.58 is the base scenario's: the run equals the reference
    assert_same_powder(reference, &out.join("packing_density_0.58"));
    // the table of a finished study is rebuilt from the run's files, equal to the first one
    let table = |path: &std::path::Path| {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap()
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        (header, rows)
    };
    let (header, first) = table(&out.join("table.csv"));
    for col in [
        "zeta_5",
        "period_s",
        "settled_packing_density",
        "compressed",
        "energy_closure",
    ] {
        assert!(header.iter().any(|h| h == col), "{col} missing: {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    assert_eq!(first.len(), 1);
    assert!([0.0, 1.0].contains(&first[0][col("compressed")]));
    assert!((first[0][col("packing_density")] - 0.58).abs() < 0.01);
    std::fs::remove_file(out.join("table.csv")).unwrap();
    let o = study(&[]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, again) = table(&out.join("table.csv"));
    for (a, b) in first[0].iter().zip(&again[0]) {
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(1e-12) || (a.is_nan() && b.is_nan()),
            "{:?} vs {:?}",
            first[0],
            again[0]
        );
    }
    powder_test_done();
}
