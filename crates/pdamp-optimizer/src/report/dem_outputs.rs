//! Level 3's outputs: the coupled-DEM runs of the best designs and their CSV files.

use super::csv::dem_csv;
use super::write;
use crate::DesignError;
use crate::dem::DemVerification;
use crate::search::Candidate;
use crate::space::Space;
use pdamp_plot::{LinePlot, Series, line_plot};
use std::fmt::Write as _;
use std::path::Path;

/// Level 3 of [`super::write_outputs`]: coupled DEM of the best designs (every container its own
/// dropped bed in one run), `dem.csv`, for max_damping `dem_damping_curve.csv` and the DEM
/// curves in `damping.png`, for the forced objectives `dem_resonance.csv`.
pub(super) fn dem_level(
    space: &Space,
    top: &[&Candidate],
    out: &Path,
    plot: &mut LinePlot,
    plots: &mut Vec<&'static str>,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<DemVerification>, DesignError> {
    let f = &space.study.file;
    let mut dem = Vec::new();
    for (i, c) in top.iter().take(f.verification.dem_designs).enumerate() {
        let level1 = c.time.as_ref().expect("verified");
        dem.push(crate::dem::verify_design(
            space,
            &c.design,
            i + 1,
            level1,
            out,
            progress,
        )?);
    }
    if !dem.is_empty() {
        write(out, "dem.csv", &dem_csv(&dem))?;
    }
    if dem.iter().any(|d| !d.resonances.is_empty()) {
        let mut csv = String::from(
            "rank,mode,packing,relative_peak_coupled_dem,damping_ratio_coupled_dem,resonance_frequency_hz_coupled_dem,relative_peak_time_simulation,damping_ratio_time_simulation,resonance_frequency_hz_time_simulation\n",
        );
        for d in &dem {
            for m in &d.resonances {
                for p in 0..m.relative_peak.len() {
                    let _ = writeln!(
                        csv,
                        "{},{},{},{:e},{:e},{:e},{:e},{:e},{:e}",
                        d.rank,
                        m.mode,
                        p + 1,
                        m.relative_peak[p],
                        m.damping_ratio[p],
                        m.resonance_frequency_hz[p],
                        m.time_simulation.0,
                        m.time_simulation.1,
                        m.time_simulation.2
                    );
                }
            }
        }
        write(out, "dem_resonance.csv", &csv)?;
    }
    if dem.iter().any(|d| !d.modes.is_empty()) {
        let mut csv = String::from(
            "rank,mode,amplitude_m,damping_ratio_coupled_dem_mean,damping_ratio_coupled_dem_ci95_half_width,packings\n",
        );
        for d in &dem {
            for m in &d.modes {
                for (x, z) in &m.curve {
                    let _ = writeln!(
                        csv,
                        "{},{},{x:e},{:e},{:e},{}",
                        d.rank, m.mode, z.mean, z.ci95_half_width, z.count
                    );
                }
                plot.series.push(Series::new(
                    format!("mode {}, design {}, coupled DEM", m.mode, d.rank),
                    m.curve.iter().map(|c| c.0).collect(),
                    m.curve.iter().map(|c| c.1.mean).collect(),
                ));
            }
        }
        write(out, "dem_damping_curve.csv", &csv)?;
        match line_plot(out.join("damping"), plot) {
            Ok(_) => {
                if !plots.contains(&"damping.png") {
                    plots.push("damping.png");
                }
            }
            Err(e) => eprintln!("note: no damping.png: {e}"),
        }
    }
    Ok(dem)
}

/// The best design under coupled DEM (largest mean ζ or smallest mean stroke).
pub(super) fn best_by_dem(dem: &[DemVerification]) -> Option<&DemVerification> {
    let sign = |d: &DemVerification| {
        if d.larger_is_better() {
            -d.stat.mean
        } else {
            d.stat.mean
        }
    };
    dem.iter()
        .filter(|d| d.stat.mean.is_finite())
        .min_by(|a, b| sign(a).total_cmp(&sign(b)))
}
