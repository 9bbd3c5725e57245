//! The `fields` kind of sweep: an effective field with its packings — one task per packing's
//! bed (prepared and saved once), one per grid point and packing (checkpointed inside the
//! point).

use super::{TasksRun, absolute, install, stored_error};
use anyhow::{Context, Result, bail};
use pdamp_design::FieldGrid;
use pdamp_design::fields::{StoredPoint, stored_point};
use pdamp_design::report::{BedSource, field_damper, prepared_bed_path};
use pdamp_scenario::schema::Scenario;
use pdamp_sweep::status::Stored;
use pdamp_sweep::{SweepManifest, Task};
use std::path::{Path, PathBuf};

/// Kind name of effective-field sweeps.
pub(super) const FIELDS_KIND: &str = "fields";

/// Output directory of packing `k` of a field with `packings` packings.
fn packing_dir(dir: &Path, packings: usize, k: usize) -> PathBuf {
    if packings == 1 {
        dir.to_path_buf()
    } else {
        dir.join("packings").join(format!("packing_{k:03}"))
    }
}

/// A task of a field sweep: the bed of a packing, or a grid point of a packing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum FieldTask {
    Bed { packing: usize },
    Point { packing: usize, grid_index: usize },
}

/// Tasks of the field of `sc`: the beds first (tasks 0 … K−1), then packing by packing the
/// grid points in grid order.
pub(super) fn field_tasks(sc: &Scenario) -> Result<(Vec<FieldTask>, FieldGrid, usize)> {
    let spec = sc.fields.as_ref().context(
        "a sweep needs a scenario with [damper] and [fields] (an effective field); other grids run with their own commands",
    )?;
    if sc.damper.is_none() {
        bail!("a field sweep needs a [damper] section");
    }
    let grid = FieldGrid::from_spec(spec).map_err(anyhow::Error::msg)?;
    let packings = sc.damper.as_ref().map_or(1, |d| d.packings).max(1);
    let n = grid.points().len();
    let mut tasks: Vec<FieldTask> = (0..packings)
        .map(|k| FieldTask::Bed { packing: k })
        .collect();
    for k in 0..packings {
        tasks.extend((0..n).map(|g| FieldTask::Point {
            packing: k,
            grid_index: g,
        }));
    }
    Ok((tasks, grid, packings))
}

/// Label, the tasks it needs, and its result and error files (relative to the sweep directory)
/// of a task of a field sweep.
fn describe(
    grid: &FieldGrid,
    packings: usize,
    t: FieldTask,
) -> (String, Vec<usize>, PathBuf, PathBuf) {
    let root = Path::new("");
    match t {
        FieldTask::Bed { packing } => {
            let result = prepared_bed_path(root, packing);
            let error = result.with_extension("error.txt");
            (format!("bed of packing {packing}"), vec![], result, error)
        }
        FieldTask::Point {
            packing,
            grid_index,
        } => {
            let (i, j, f, x) = grid.points()[grid_index];
            let d = packing_dir(root, packings, packing);
            let amp = grid.amplitude_values[j];
            let label = format!(
                "{}f = {f} Hz, {} = {amp:.4e} (X = {x:.4e} m)",
                if packings > 1 {
                    format!("packing {packing}: ")
                } else {
                    String::new()
                },
                match grid.amplitude_axis {
                    pdamp_scenario::schema::AmplitudeAxis::Displacement => "X",
                    pdamp_scenario::schema::AmplitudeAxis::Acceleration => "A",
                    pdamp_scenario::schema::AmplitudeAxis::Intensity => "Γ",
                }
            );
            (
                label,
                vec![packing],
                pdamp_design::fields::point_path(&d, i, j),
                pdamp_design::fields::point_error_path(&d, i, j),
            )
        }
    }
}

/// Makes (or opens, when it is of the same scenario) the field sweep of `scenario` in `out`.
pub(crate) fn create(scenario: &Path, out: &Path) -> Result<SweepManifest> {
    let sc = Scenario::load(scenario)?;
    let (tasks, grid, packings) = field_tasks(&sc)?;
    let source = absolute(scenario);
    let base_dir = source.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    let manifest = SweepManifest {
        format: pdamp_sweep::SWEEP_FORMAT,
        pdamp_version: env!("CARGO_PKG_VERSION").to_string(),
        kind: FIELDS_KIND.into(),
        title: sc.title.clone(),
        scenario_source: source,
        scenario_digest: pdamp_scenario::run::scenario_content_digest(&sc, &base_dir),
        base_dir,
        parameters: serde_json::Value::Null,
        tasks: tasks
            .iter()
            .enumerate()
            .map(|(index, &t)| {
                let (label, needs, result, error) = describe(&grid, packings, t);
                Task {
                    index,
                    label,
                    needs,
                    result,
                    error,
                }
            })
            .collect(),
    };
    let inputs = crate::outputs::scenario_inputs(scenario, &sc);
    install(
        scenario,
        out,
        manifest,
        &inputs,
        &crate::outputs::RUN_OUTPUTS,
    )
}

/// What the store holds for a task of a field sweep.
pub(super) fn stored_field(
    dir: &Path,
    grid: &FieldGrid,
    packings: usize,
    ft: FieldTask,
    t: &Task,
) -> Stored {
    match ft {
        FieldTask::Bed { .. } => match std::fs::read(dir.join(&t.result)) {
            Ok(bytes) => match pdamp_io::checkpoint::verify_framing(&bytes) {
                Ok(()) => Stored::Done,
                Err(e) => Stored::Corrupt(format!("{}: {e}", t.result.display())),
            },
            Err(_) => stored_error(dir, t),
        },
        FieldTask::Point {
            packing,
            grid_index,
        } => {
            let (i, j, f, x) = grid.points()[grid_index];
            match stored_point(&packing_dir(dir, packings, packing), i, j, f, x) {
                StoredPoint::Done(_) => Stored::Done,
                StoredPoint::Failed(e) => Stored::Failed(e),
                StoredPoint::Corrupt(e) => Stored::Corrupt(e),
                StoredPoint::Missing => Stored::Missing,
            }
        }
    }
}

/// [`execute_tasks`] of a field sweep.
pub(super) fn execute_field_tasks(
    dir: &Path,
    m: &SweepManifest,
    sc: &Scenario,
    tasks: &[FieldTask],
    grid: &FieldGrid,
    packings: usize,
    indices: &[usize],
) -> Result<TasksRun> {
    let mut failed: Vec<String> = Vec::new();
    let mut ran = 0usize;
    // The beds asked for, then those the points need.
    let mut beds: Vec<usize> = indices
        .iter()
        .map(|&i| match tasks[i] {
            FieldTask::Bed { packing } | FieldTask::Point { packing, .. } => packing,
        })
        .collect();
    beds.sort_unstable();
    beds.dedup();
    for k in beds {
        let bed_task = &m.tasks[k];
        let bed_file = dir.join(&bed_task.result);
        if let Ok(bytes) = std::fs::read(&bed_file)
            && let Err(e) = pdamp_io::checkpoint::verify_framing(&bytes)
        {
            eprintln!(
                "warning: {} is damaged ({e}); preparing the bed of packing {k} again",
                bed_file.display()
            );
            let _ = std::fs::remove_file(&bed_file);
        }
        let damper = field_damper(sc, &m.base_dir, k, BedSource::Saved(dir), |_| {})
            .map(|d| d.cancelled_by(crate::cancel()));
        let points: Vec<usize> = indices
            .iter()
            .filter_map(|&i| match tasks[i] {
                FieldTask::Point {
                    packing,
                    grid_index,
                } if packing == k => Some(grid_index),
                _ => None,
            })
            .collect();
        let damper = match damper {
            Ok(d) => {
                let _ = std::fs::remove_file(dir.join(&bed_task.error));
                d
            }
            Err(e) if e.is_output() => bail!("{e}"),
            Err(e) => {
                let msg = format!("the bed of packing {k} could not be prepared: {e}");
                pdamp_io::atomic::write_atomic(dir.join(&bed_task.error), msg.as_bytes())?;
                failed.push(format!("task {k} ({}): {msg}", bed_task.label));
                continue;
            }
        };
        if points.is_empty() {
            continue;
        }
        let out = packing_dir(dir, packings, k);
        let start = std::time::Instant::now();
        let results = pdamp_design::fields::run_field_points(
            &damper,
            grid,
            &out,
            &points,
            pdamp_design::ThreadSplit::default(),
            Some(&pdamp_design::fields::PointCheckpoints {
                scenario_digest: pdamp_scenario::run::scenario_content_digest(
                    &pdamp_scenario::prepare::scenario_for_packing(sc, k),
                    &m.base_dir,
                ),
                interval_s: 60.0,
            }),
            |g, r| {
                let (_, _, f, x) = grid.points()[g];
                eprintln!(
                    "[{:.0} s] packing {k}: point f = {f} Hz, X = {x:.4e} m {}",
                    start.elapsed().as_secs_f64(),
                    match r {
                        Ok(_) => "finished".to_string(),
                        Err(e) => format!("failed: {e}"),
                    }
                )
            },
        )
        .map_err(anyhow::Error::msg)?;
        for (g, r) in results {
            match r {
                Ok(true) => ran += 1,
                Ok(false) => {}
                Err(e) => {
                    let t = tasks
                        .iter()
                        .position(|&t| {
                            t == FieldTask::Point {
                                packing: k,
                                grid_index: g,
                            }
                        })
                        .unwrap_or(0);
                    failed.push(format!("task {t} ({}): {e}", m.tasks[t].label));
                }
            }
        }
    }
    Ok(TasksRun { ran, failed })
}
