//! `report.md`, the report for an engineer to hand on.

use super::dem_section::dem_section;
use super::fields_section::fields_section;
use super::{describe, objective_names, shown};
use crate::dem::DemVerification;
use crate::effective_fields::FieldEvaluation;
use crate::search::{Candidate, SearchOutcome};
use crate::space::Space;
use crate::study::{DesignStudyFile, ObjectiveSpec};
use serde_json::Value;
use std::fmt::Write as _;

/// `report.md`: the study, the objective, the search, the best designs and every level's
/// comparison, then the robustness of the best design.
pub(super) fn report_md(
    space: &Space,
    o: &SearchOutcome,
    s: &Value,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
    dem: &[DemVerification],
) -> String {
    let st = space.study;
    let f = &st.file;
    let mut r = String::new();
    let _ = writeln!(r, "# Particle damper design: {}\n", st.path.display());
    let _ = writeln!(
        r,
        "Structure and decay: `{}` ({} modes; free analysis from {} m at '{}', output point '{}').\n",
        st.scenario_path.display(),
        st.structure.modes.len(),
        st.free.initial_displacement_m,
        st.free.initial_point,
        st.free.output_point
    );
    let objective = objective_text(space);
    let _ = writeln!(r, "**Objective**: {objective}.\n");
    search_paragraph(&mut r, o, s, fields, dem);
    best_designs_table(&mut r, space, s, top, fields);
    fidelity_section(&mut r, s);
    if !fields.is_empty() {
        r.push_str(&fields_section(space, fields));
        let _ = writeln!(r);
    }
    if !dem.is_empty() {
        dem_level_section(&mut r, f, top, fields, dem);
    }
    robustness_section(&mut r, space, s, fields);
    r
}

/// The objective in words, with the equations its levels use.
fn objective_text(space: &Space) -> String {
    let f = &space.study.file;
    match &f.objective {
        ObjectiveSpec::MinStroke { evaluate_at_s } => {
            format!("smallest stroke (largest |x| over the last period) at t = {evaluate_at_s} s")
        }
        ObjectiveSpec::MaxDamping {
            modes,
            amplitude_min_m,
            amplitude_max_m,
            ..
        } => format!(
            "largest mean damping ratio of mode(s) {modes:?} over X = {amplitude_min_m} … \
             {amplitude_max_m} m at the output point"
        ),
        ObjectiveSpec::MinFrfPeak { modes, band, .. } => format!(
            "smallest resonance peak(s) of mode(s) {modes:?} at the output point under the \
             scenario's harmonic force, relative to the bare structure's (level 0: the \
             equilibrium of D Fig. 3.7; level 1: the steady-state FRF, D Eq. 3.44, over ±{:.0} %)",
            band * 100.0
        ),
        ObjectiveSpec::MaxResonanceDamping { modes, band, .. } => format!(
            "largest damping ratio at resonance of mode(s) {modes:?} under the scenario's \
             harmonic force (level 0: the equilibrium ζ of D Fig. 3.7 / Eq. 3.49; level 1: ζ \
             from the steady-state FRF's peak, D Eq. 3.44/3.47, over ±{:.0} %)",
            band * 100.0
        ),
    }
}

/// The search paragraph: the space, the evaluations of every level and their wall times.
fn search_paragraph(
    r: &mut String,
    o: &SearchOutcome,
    s: &Value,
    fields: &[FieldEvaluation],
    dem: &[DemVerification],
) {
    let _ = writeln!(
        r,
        "**Search**: {:.0} designs in the space (before the constraints); {} envelope evaluations ({}), {} time \
         simulations; wall time {:.2} s screening + {:.2} s verification{}{}.\n",
        o.space_size,
        o.envelope_evaluations,
        o.screening,
        o.time_evaluations,
        o.screening_wall_s,
        o.verification_wall_s,
        if fields.is_empty() {
            String::new()
        } else {
            format!(
                " + {:.0} s effective fields ({} field points, {} reused from the store)",
                s["wall_time_s"]["effective_fields"]
                    .as_f64()
                    .unwrap_or(f64::NAN),
                s["effective_field_points"].as_u64().unwrap_or(0),
                s["effective_field_points_reused"].as_u64().unwrap_or(0)
            )
        },
        if dem.is_empty() {
            String::new()
        } else {
            format!(
                " + {:.0} s coupled DEM ({} runs)",
                dem.iter().map(|d| d.wall_s).sum::<f64>(),
                s["coupled_dem_runs"].as_u64().unwrap_or(0)
            )
        }
    );
}

/// The table of the best designs and the bare structure's objective.
fn best_designs_table(
    r: &mut String,
    space: &Space,
    s: &Value,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
) {
    let (_, obj) = objective_names(space);
    let _ = writeln!(r, "## Best designs\n");
    let _ = writeln!(
        r,
        "| rank | design | bed mass (kg) | {obj} (envelope) | {obj} (time simulation) | {obj} \
         (effective fields, mean ± 95 % CI) | scenario |"
    );
    let _ = writeln!(r, "|---|---|---|---|---|---|---|");
    for (i, c) in top.iter().enumerate() {
        let _ = writeln!(
            r,
            "| {} | {} | {:.4} | {:.4e} | {:.4e} | {} | `scenarios/design_{}.toml` |",
            i + 1,
            describe(space, &c.design),
            space.bed_mass_kg(&c.design),
            shown(space, c.envelope.cost),
            shown(space, c.time.as_ref().map_or(f64::NAN, |t| t.cost)),
            fields
                .iter()
                .find(|e| e.design == c.design)
                .map_or("–".to_string(), |e| format!(
                    "{:.4e} ± {:.1e}",
                    e.stat.mean, e.stat.ci95_half_width
                )),
            i + 1
        );
    }
    if !fields.is_empty() {
        let _ = writeln!(
            r,
            "\nThe designs with effective fields come first, in the fields' order; the others \
             follow in the time simulation's order."
        );
    }
    let bare = &s["bare_structure"][format!("{obj}_time_simulation")];
    let _ = writeln!(r, "\nBare structure: {obj} = {bare}.\n");
}

/// The fidelity section: the envelope against the time simulation and the formulas' limits.
fn fidelity_section(r: &mut String, s: &Value) {
    let a = &s["fidelity_agreement"];
    let _ = writeln!(r, "## Fidelity levels\n");
    let _ = writeln!(
        r,
        "Envelope (formulas' η̄, m̄ at the current amplitude, D Eq. 3.33/3.39/3.51) against the \
         time simulation (approach 3, D Sect. 3.3.1) on the {} verified designs: Spearman rank \
         correlation {}, mean relative difference {:.1} %; the best verified design ranked {} in \
         the screening.\n",
        a["verified_designs"],
        a["spearman_envelope_vs_time"],
        100.0
            * a["mean_relative_difference_envelope_vs_time"]
                .as_f64()
                .unwrap_or(0.0),
        a["screening_rank_of_best"]
    );
    let _ = writeln!(
        r,
        "Both levels use the analytical motion-mode formulas (approach 3); they inherit their \
         assumptions (D Ch. 5–7: rigid spheres, fully plastic collect-and-collide impacts, one \
         layer rolling as a block, a vertical bed as one block) and do not see a wall coating. \
         Effective fields (approach 2, `[verification] field_designs`) and coupled DEM \
         (approach 1, `dem_designs`) are the next levels.\n"
    );
}

/// The coupled-DEM section, each design beside its effective fields where level 2 ran.
fn dem_level_section(
    r: &mut String,
    f: &DesignStudyFile,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
    dem: &[DemVerification],
) {
    let level2: Vec<Option<&FieldEvaluation>> = dem
        .iter()
        .map(|d| {
            top.get(d.rank - 1).and_then(|c| {
                fields
                    .iter()
                    .find(|e| e.design == c.design && e.failure.is_none())
            })
        })
        .collect();
    r.push_str(&dem_section(f, dem, &level2));
    let _ = writeln!(r);
}

/// The robustness section (the best design detuned) and where the curves and FRFs are.
fn robustness_section(r: &mut String, space: &Space, s: &Value, fields: &[FieldEvaluation]) {
    let f = &space.study.file;
    let (_, obj) = objective_names(space);
    let _ = writeln!(r, "## Robustness of the best design\n");
    let _ = writeln!(
        r,
        "Design 1 with the structure's frequencies detuned, on the time simulation (the \
         formulas{}).\n",
        if fields.is_empty() {
            ""
        } else {
            ": a coating is not seen there"
        }
    );
    let _ = writeln!(
        r,
        "| structure frequencies | {obj} (time simulation) |\n|---|---|"
    );
    if let Some(rows) = s["robustness"]["best_design_objective"].as_array() {
        for row in rows {
            let _ = writeln!(
                r,
                "| × {:.2} | {:.4e} |",
                row["frequency_scale"].as_f64().unwrap_or(f64::NAN),
                row["objective"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    if f.objective.is_forced() {
        let _ = writeln!(
            r,
            "\nThe steady-state FRFs of the best designs against the bare structure (and the \
             coupled-DEM sweeps of level 3): `frf.csv`, `frf.png`."
        );
    } else {
        let _ = writeln!(
            r,
            "\nζ over the amplitude range: `damping_curve.csv`, `damping.png`{}.",
            if matches!(f.objective, ObjectiveSpec::MinStroke { .. }) {
                "; the decays against the bare structure: `decay.png`"
            } else {
                ""
            }
        );
    }
}
