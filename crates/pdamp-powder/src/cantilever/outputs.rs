//! The outputs of a run: tip.csv, envelope.csv, energy.csv, the tip plot and summary.json.

use std::path::Path;

use super::{CantileverError, CantileverResult, CantileverScenario, scenario_digest};
use crate::damping;

/// Writes tip.csv, envelope.csv, energy.csv, the tip plot and (last) summary.json into `dir`.
pub fn write_outputs(
    dir: &Path,
    sc: &CantileverScenario,
    r: &CantileverResult,
) -> Result<(), CantileverError> {
    create_dir(dir)?;
    let rows: Vec<[f64; 3]> = (0..r.time_s.len())
        .map(|i| [r.time_s[i], r.tip_m[i], r.iterations[i]])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("tip.csv"),
        &["time_s", "tip_displacement_m", "coupling_iterations"],
        rows,
    )?;
    let t_rel = sc.load.rise_s + sc.load.hold_s;
    let ext = damping::local_extrema(&r.time_s, &r.tip_m, t_rel);
    let env: Vec<[f64; 2]> = ext
        .iter()
        .map(|&i| [r.time_s[i], r.tip_m[i].abs()])
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("envelope.csv"),
        &["time_s", "peak_abs_displacement_m"],
        env.iter(),
    )?;
    let erows: Vec<[f64; 9]> = r
        .energy
        .iter()
        .map(|(t, e)| {
            [
                *t,
                e.structure_kinetic_j,
                e.structure_strain_j,
                e.particle_kinetic_j,
                e.particle_potential_j,
                e.contact_elastic_j,
                e.dissipated_j,
                e.load_work_j,
                e.balance_j,
            ]
        })
        .collect();
    pdamp_io::csv::write_csv_atomic(
        dir.join("energy.csv"),
        &[
            "time_s",
            "structure_kinetic_j",
            "structure_strain_j",
            "particle_kinetic_j",
            "particle_potential_j",
            "contact_elastic_j",
            "dissipated_j",
            "load_work_j",
            "balance_j",
        ],
        erows,
    )?;
    let ms: Vec<f64> = r.time_s.iter().map(|t| t * 1e3).collect();
    let mm: Vec<f64> = r.tip_m.iter().map(|x| x * 1e3).collect();
    let mut plot = pdamp_plot::LinePlot::new(
        pdamp_plot::Axis::linear("time (ms)"),
        pdamp_plot::Axis::linear("tip displacement x (mm)"),
    );
    plot.series.push(pdamp_plot::Series::new("", ms, mm));
    pdamp_plot::line_plot(dir.join("tip"), &plot)?;
    // last: a run directory with summary.json is complete (the study skips it)
    // the digest lets a study reuse this run only for the same scenario (study::run_study)
    let summary = serde_json::json!({
        "result": r,
        "scenario": sc,
        "scenario_digest": scenario_digest(sc)?,
    });
    let path = dir.join("summary.json");
    let json = serde_json::to_string_pretty(&summary).map_err(CantileverError::Encode)?;
    pdamp_io::atomic::write_atomic(&path, json.as_bytes())
        .map_err(|source| CantileverError::Write { path, source })?;
    Ok(())
}

/// Creates `dir` (and its parents).
pub(super) fn create_dir(dir: &Path) -> Result<(), CantileverError> {
    std::fs::create_dir_all(dir).map_err(|source| CantileverError::File {
        path: dir.to_path_buf(),
        source,
    })
}
