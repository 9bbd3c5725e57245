//! The coupled-DEM section of `report.md`.

use super::dem_outputs::best_by_dem;
use crate::dem::DemVerification;
use crate::effective_fields::FieldEvaluation;
use crate::study::DesignStudyFile;
use std::fmt::Write as _;

/// The coupled-DEM section of `report.md`: the ensembles against the formulas, the energy
/// closure, ζ per mode (max_damping) and the DEM best.
pub(super) fn dem_section(
    f: &DesignStudyFile,
    dem: &[DemVerification],
    level2: &[Option<&FieldEvaluation>],
) -> String {
    let mut r = String::new();
    let _ = writeln!(r, "## Coupled DEM (approach 1)\n");
    let _ = writeln!(
        r,
        "Each design's damper as a DEM bed in its container, dropped {} times with \
         independent seeds, coupled to the structure (`pdamp couple`, runs in `dem/`).{}\n",
        f.verification.packings,
        if f.verification.youngs_modulus_scale < 1.0 {
            format!(
                " **Softened**: particle Young's modulus × {} (shorter runs; not the \
                 reference fidelity).",
                f.verification.youngs_modulus_scale
            )
        } else {
            String::new()
        }
    );
    let (unit, scale, name) = match dem[0].objective {
        "stroke_m" => (" mm", 1e3, "stroke"),
        "relative_peak" => ("", 1.0, "peak / bare peak"),
        "mean_resonance_damping_ratio" => ("", 1.0, "mean ζ at resonance"),
        _ => ("", 1.0, "mean ζ"),
    };
    let _ = writeln!(
        r,
        "| rank | {name} (formulas, time simulation) | {name} (coupled DEM, mean ± 95 % CI) \
         | packings | DEM − formulas | particles | time step | particle-steps (estimated) \
         | energy closure | wall time |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for d in dem {
        let _ = writeln!(
            r,
            "| {} | {:.4}{unit} | {:.4} ± {:.4}{unit} | {} | {:+.1} % | {} | {:.2e} s | \
             {:.2e} | {:.1e} | {:.0} s |",
            d.rank,
            d.time_simulation * scale,
            d.stat.mean * scale,
            d.stat.ci95_half_width * scale,
            d.stat.count,
            100.0 * (d.stat.mean / d.time_simulation - 1.0),
            d.particles,
            d.time_step_s,
            d.estimated_particle_steps,
            d.energy_closure,
            d.wall_s
        );
    }
    if level2.iter().any(|e| e.is_some()) {
        r.push_str(&against_fields_table(dem, level2, name, unit, scale));
    }
    let open: Vec<String> = dem
        .iter()
        .filter(|d| d.energy_closure.is_nan() || d.energy_closure > 1e-3)
        .map(|d| d.rank.to_string())
        .collect();
    let _ = writeln!(
        r,
        "\nEnergy closure: the bed's ledger (wall work = bed energy change + dissipation) \
         and the coupling (structure's work on the bed = walls' work), relative to the \
         energy dissipated, largest over each design's runs (`energy_exchange` in each \
         run's `summary.json`). {}",
        if open.is_empty() {
            "All ≤ 1e-3.".to_string()
        } else {
            format!(
                "**Above 1e-3 for design(s) {}**: refine `[verification] time_step_s`.",
                open.join(", ")
            )
        }
    );
    if dem.iter().any(|d| !d.modes.is_empty()) {
        r.push_str(&mode_damping_table(dem));
    }
    if dem.iter().any(|d| !d.resonances.is_empty()) {
        r.push_str(&resonance_table(dem));
    }
    if let Some(b) = best_by_dem(dem) {
        let overlapping: Vec<String> = dem
            .iter()
            .filter(|d| {
                d.rank != b.rank
                    && d.stat.ci95_low <= b.stat.ci95_high
                    && d.stat.ci95_high >= b.stat.ci95_low
            })
            .map(|d| d.rank.to_string())
            .collect();
        let _ = writeln!(
            r,
            "\nUnder coupled DEM the best of these is design {} ({name} {:.4}{unit}){}.",
            b.rank,
            b.stat.mean * scale,
            if overlapping.is_empty() {
                ", its 95 % interval clear of the others'".to_string()
            } else {
                format!(
                    "; the intervals of design(s) {} overlap it: more packings decide",
                    overlapping.join(", ")
                )
            }
        );
    }
    r
}

/// The per-mode resonances of the coupled-DEM sweeps (forced objectives) against level 1,
/// with each sweep's plan and its bias on the formula model.
fn resonance_table(dem: &[DemVerification]) -> String {
    let mut r = String::new();
    let _ = writeln!(
        r,
        "\nPer mode at resonance: a slow linear sine sweep of the structure reduced to the mode \
         under the study's force, with the DEM bed coupled (D Sect. 3.3.2); the largest \
         response gives the peak and ζ by D Eq. 3.47. The sweep's rate is set with the \
         formula dampers: slowed until their sweep peak lies within {:.0} % of their \
         steady-state peak, or until a sweep twice as slow moves it by less than a quarter of \
         that (the bias column). A bias that stays large is not the rate: the formulas' \
         steady-state FRF then has an upper branch that a sweep from below does not reach \
         (a jump), and the like-for-like comparison is the formulas' value on the same sweep.\n\n\
         | rank | mode | peak / bare (formulas, steady state) | peak / bare (formulas, same sweep) | \
         peak / bare (coupled DEM, mean ± 95 % CI) | ζ (formulas) | ζ (coupled DEM) | \
         f_peak formulas → DEM | sweep | bias of the sweep on the formulas |\n\
         |---|---|---|---|---|---|---|---|---|---|",
        100.0 * crate::resonance_sweep::SWEEP_PEAK_TOLERANCE
    );
    for d in dem {
        for m in &d.resonances {
            let f_dem = m.resonance_frequency_hz.iter().sum::<f64>()
                / m.resonance_frequency_hz.len().max(1) as f64;
            let _ = writeln!(
                r,
                "| {} | {} | {:.4} | {:.4} | {:.4} ± {:.4} | {:.4} | {:.4} ± {:.4} | {:.3} → \
                 {:.3} Hz | {:.3}–{:.3} Hz in {:.1} s (η = {}){} | {:+.2} % |",
                d.rank,
                m.mode,
                m.time_simulation.0,
                m.formula_sweep_relative_peak(),
                m.relative_peak_stat.mean,
                m.relative_peak_stat.ci95_half_width,
                m.time_simulation.1,
                m.damping_ratio_stat.mean,
                m.damping_ratio_stat.ci95_half_width,
                m.time_simulation.2,
                f_dem,
                m.sweep.start_hz,
                m.sweep.end_hz,
                m.sweep.duration_s,
                m.sweep.rate_parameter,
                m.replanned
                    .as_ref()
                    .map_or(String::new(), |w| format!(", planned again: {w}")),
                100.0 * m.sweep.formula_sweep_bias()
            );
        }
    }
    r
}

/// Each design's coupled-DEM ensemble against its effective fields (level 2), with whether
/// the 95 % intervals overlap.
fn against_fields_table(
    dem: &[DemVerification],
    level2: &[Option<&FieldEvaluation>],
    name: &str,
    unit: &str,
    scale: f64,
) -> String {
    let mut r = String::new();
    let _ = writeln!(
        r,
        "\nAgainst the effective fields (level 2, the same bed type, the structure simulated \
         with the fields):\n\n| rank | {name} (effective fields, mean ± 95 % CI) | {name} \
         (coupled DEM, mean ± 95 % CI) | DEM − fields | intervals overlap |\n|---|---|---|---|---|"
    );
    for (d, e) in dem.iter().zip(level2) {
        if let Some(e) = e {
            let _ = writeln!(
                r,
                "| {} | {:.4} ± {:.4}{unit} | {:.4} ± {:.4}{unit} | {:+.1} % | {} |",
                d.rank,
                e.stat.mean * scale,
                e.stat.ci95_half_width * scale,
                d.stat.mean * scale,
                d.stat.ci95_half_width * scale,
                100.0 * (d.stat.mean / e.stat.mean - 1.0),
                if d.stat.ci95_low <= e.stat.ci95_high && d.stat.ci95_high >= e.stat.ci95_low {
                    "yes"
                } else {
                    "no"
                }
            );
        }
    }
    r
}

/// max_damping: ζ̄ per mode from the DEM decays against the formulas (D Eq. 3.40/3.41 per
/// cycle) and the modes whose decays did not cover the amplitude range.
fn mode_damping_table(dem: &[DemVerification]) -> String {
    let mut r = String::new();
    let _ = writeln!(
        r,
        "\nPer mode: ζ̄ over the amplitude grid from free decays of the structure \
         reduced to that mode, released 10 % above the range (D Eq. 3.40/3.41 per \
         cycle, the same procedure as the time simulation).\n\n| rank | mode | ζ̄ \
         (formulas) | ζ̄ (coupled DEM, mean ± 95 % CI) | DEM − formulas | amplitudes \
         the decays covered |\n|---|---|---|---|---|---|"
    );
    for d in dem {
        for m in &d.modes {
            let _ = writeln!(
                r,
                "| {} | {} | {:.4} | {:.4} ± {:.4} | {:+.1} % | {:.3}–{:.3} mm |",
                d.rank,
                m.mode,
                m.time_simulation,
                m.stat.mean,
                m.stat.ci95_half_width,
                100.0 * (m.stat.mean / m.time_simulation - 1.0),
                m.covered_amplitude_m.0 * 1e3,
                m.covered_amplitude_m.1 * 1e3
            );
        }
    }
    let short: Vec<String> = dem
        .iter()
        .flat_map(|d| d.modes.iter().map(move |m| (d.rank, m)))
        .filter(|(_, m)| {
            let (lo, hi) = (m.curve[0].0, m.curve[m.curve.len() - 1].0);
            m.covered_amplitude_m.0 > 1.1 * lo || m.covered_amplitude_m.1 < hi / 1.1
        })
        .map(|(rank, m)| format!("design {rank} mode {}", m.mode))
        .collect();
    let _ = writeln!(
        r,
        "\nζ(X) of the DEM ensembles: `dem_damping_curve.csv` and the `coupled DEM` \
         curves of `damping.png`.{}",
        if short.is_empty() {
            String::new()
        } else {
            format!(
                " The decays of {} did not cover the whole amplitude range (first cycle \
                 below the top: the bed's first impacts; last cycle above the bottom: \
                 the bed damps less than the formulas predicted): outside the covered \
                 amplitudes the grid takes the nearest cycle's ζ.",
                short.join(", ")
            )
        }
    );
    r
}
