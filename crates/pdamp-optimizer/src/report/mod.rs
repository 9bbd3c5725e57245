//! What `pdamp design` writes: `designs.csv` (ranked, both fidelity levels), `summary.json`,
//! `report.md` (for an engineer to hand on), `decay.png/svg` (min_stroke: the best designs'
//! decays against the bare structure) or `damping.png/svg` (max_damping: ζ(X) of the best
//! designs), `robustness.csv` (the best design detuned by ±d in frequency, and its ζ(X)) and
//! `scenarios/design_N.toml`, a ready-to-run `pdamp couple` scenario for every listed design.
//! Every file is written atomically.

mod csv;
mod dem_outputs;
mod dem_section;
mod fields_section;
mod markdown;
mod plots;
mod scenarios;

use crate::DesignError;
use crate::dem::DemVerification;
use crate::effective_fields::FieldEvaluation;
use crate::fidelity::{Evaluation, time_evaluation};
use crate::search::{Candidate, SearchOutcome, spearman};
use crate::space::{Design, Space};
use crate::study::ObjectiveSpec;
use csv::{designs_csv, fields_csv};
use dem_outputs::{best_by_dem, dem_level};
use markdown::report_md;
use pdamp_io::atomic::write_atomic;
use pdamp_structure::modal::ModalStructure;
use plots::{decay_plot, frf_plots, level1_damping_curves};
use scenarios::{fields_scenario_toml, scenario_toml};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

pub use crate::design_scenario::{describe, scenario_table};

fn write(out: &Path, name: &str, text: &str) -> Result<(), DesignError> {
    let p = out.join(name);
    write_atomic(&p, text.as_bytes()).map_err(|e| DesignError::output(p, e))
}

fn objective_names(space: &Space) -> (Vec<String>, &'static str) {
    match &space.study.file.objective {
        ObjectiveSpec::MinStroke { .. } => (Vec::new(), "stroke_m"),
        ObjectiveSpec::MaxDamping { modes, .. } => (
            modes
                .iter()
                .map(|m| format!("mean_damping_ratio_mode_{m}"))
                .collect(),
            "mean_damping_ratio",
        ),
        ObjectiveSpec::MinFrfPeak { modes, .. } => (
            modes.iter().map(|m| format!("peak_mode_{m}_m")).collect(),
            "relative_peak",
        ),
        ObjectiveSpec::MaxResonanceDamping { modes, .. } => (
            modes
                .iter()
                .map(|m| format!("resonance_damping_ratio_mode_{m}"))
                .collect(),
            "mean_resonance_damping_ratio",
        ),
    }
}

/// The per-mode values behind the objective: mean ζ (max_damping) or peak amplitudes
/// (min_frf_peak).
fn per_mode_values<'a>(space: &Space, e: &'a Evaluation) -> &'a [f64] {
    match space.study.file.objective {
        ObjectiveSpec::MinFrfPeak { .. } => &e.peak_amplitude_per_mode_m,
        _ => &e.damping_ratio_per_mode,
    }
}

/// The objective as a user reads it: the stroke (m) or the mean ζ.
fn shown(space: &Space, cost: f64) -> f64 {
    match space.study.file.objective {
        ObjectiveSpec::MinStroke { .. } | ObjectiveSpec::MinFrfPeak { .. } => cost,
        ObjectiveSpec::MaxDamping { .. } | ObjectiveSpec::MaxResonanceDamping { .. } => -cost,
    }
}

/// Structure with every frequency scaled (a stiffer or softer structure: detuning).
pub fn detuned(structure: &ModalStructure, scale: f64) -> ModalStructure {
    let mut s = structure.clone();
    for m in &mut s.modes {
        m.frequency_hz *= scale;
    }
    s
}

/// Writes every output and returns the summary.
///
/// # Errors
/// Solver and output errors.
pub fn write_outputs(
    space: &Space,
    outcome: &SearchOutcome,
    out: &Path,
    wall_s: f64,
    progress: &mut dyn FnMut(&str),
) -> Result<Value, DesignError> {
    let started = std::time::Instant::now();
    let st = space.study;
    let f = &st.file;
    std::fs::create_dir_all(out.join("scenarios")).map_err(|e| DesignError::output(out, e))?;
    let cands = &outcome.candidates;
    let verified: Vec<&Candidate> = cands.iter().filter(|c| c.time.is_some()).collect();
    let best = verified[0];
    // level 2: effective fields of the best time-simulated designs, with every coating
    let fields_started = std::time::Instant::now();
    let fields = effective_field_level(space, &verified, out, progress)?;
    let fields_wall_s = fields_started.elapsed().as_secs_f64();
    let listed = listed_candidates(space, &verified, &fields);
    let top: Vec<&Candidate> = listed.iter().collect();
    write_scenarios(space, &top, &fields, out)?;
    // the bare structure on both levels
    let (bare_time, bare_hist) = time_evaluation(st, &st.structure, &[])?;
    let agreement = fidelity_agreement(cands, &verified, best);
    // robustness of the best listed design (level 2's best where it ran): detuned ±d on level 1
    let d = f.search.detuning;
    let detune = write_robustness(space, &top[0].design, out)?;
    let (mut plot, mut plots) = level1_damping_curves(space, &verified, out)?;
    if let Some(bh) = &bare_hist
        && decay_plot(space, &verified, bh, out)?
    {
        plots.push("decay.png");
    }
    // level 3: coupled DEM on the best designs, an ensemble of dropped beds each
    let dem = dem_level(space, &top, out, &mut plot, &mut plots, progress)?;
    if f.objective.is_forced() && frf_plots(space, &verified, &dem, out)? {
        plots.push("frf.png");
    }
    write(
        out,
        "designs.csv",
        &designs_csv(space, cands, &listed, &fields, &dem),
    )?;
    let (_, obj) = objective_names(space);
    let list = listed_json(space, &top, &fields, &dem);
    let summary = json!({
        "study": st.path.display().to_string(),
        "objective": f.objective,
        "space_size": outcome.space_size,
        "screening": outcome.screening,
        "envelope_evaluations": outcome.envelope_evaluations,
        "time_evaluations": outcome.time_evaluations,
        "best": list.first(),
        "top": list,
        "bare_structure": {format!("{obj}_time_simulation"): shown(space, bare_time.cost),
            "damping_ratio_per_mode_time_simulation": bare_time.damping_ratio_per_mode},
        "fidelity_agreement": agreement,
        "robustness": {"detuning": d, "best_design_objective": detune},
        "effective_fields": fields,
        "effective_field_points": fields.iter().flat_map(|e| e.fields.iter().map(|m| m.points)).sum::<usize>(),
        "effective_field_points_reused": fields.iter().flat_map(|e| e.fields.iter().map(|m| m.reused_points)).sum::<usize>(),
        "coupled_dem": dem,
        "coupled_dem_runs": dem.iter().map(|d| d.runs).sum::<usize>(),
        "best_by_coupled_dem": best_by_dem(&dem)
            .map(|d| json!({"rank": d.rank, "objective": d.objective, "mean": d.stat.mean,
                "ci95_half_width": d.stat.ci95_half_width})),
        "wall_time_s": {"screening": outcome.screening_wall_s,
            "verification": outcome.verification_wall_s,
            "effective_fields": fields_wall_s,
            "coupled_dem": dem.iter().map(|d| d.wall_s).sum::<f64>().abs(), // an empty sum is −0
            "total": wall_s + started.elapsed().as_secs_f64()},
        "plots": plots,
    });
    write(
        out,
        "report.md",
        &report_md(space, outcome, &summary, &top, &fields, &dem),
    )?;
    write(
        out,
        "summary.json",
        &serde_json::to_string_pretty(&summary).map_err(|e| DesignError::output(out, e))?,
    )?;
    Ok(summary)
}

/// Level 2 of [`write_outputs`]: the effective fields of the best time-simulated designs, with
/// every coating (none without `[verification] field_designs`).
fn effective_field_level(
    space: &Space,
    verified: &[&Candidate],
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<FieldEvaluation>, DesignError> {
    if space.study.file.verification.field_designs > 0 {
        let level1: Vec<(&Design, &Evaluation)> = verified
            .iter()
            .map(|c| (&c.design, c.time.as_ref().expect("verified")))
            .collect();
        crate::effective_fields::run_level(space, &level1, out, progress)
    } else {
        Ok(Vec::new())
    }
}

/// A design's effective-field evaluation, if level 2 ran on it and succeeded.
fn field_of<'a>(fields: &'a [FieldEvaluation], d: &Design) -> Option<&'a FieldEvaluation> {
    fields
        .iter()
        .find(|e| &e.design == d && e.failure.is_none())
}

/// `scenarios/design_N.toml` of every listed design (with its effective fields where level 2
/// confirmed it) and `fields.csv`.
fn write_scenarios(
    space: &Space,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
    out: &Path,
) -> Result<(), DesignError> {
    for (i, c) in top.iter().enumerate() {
        let text = match field_of(fields, &c.design) {
            Some(e) => fields_scenario_toml(space, e, out, i + 1)?,
            None => scenario_toml(space, &c.design, i + 1)?,
        };
        write(out, &format!("scenarios/design_{}.toml", i + 1), &text)?;
    }
    if !fields.is_empty() {
        write(out, "fields.csv", &fields_csv(space, fields))?;
    }
    Ok(())
}

/// Level 0 against level 1 on the verified designs: Spearman rank correlation, mean relative
/// difference and the screening rank of the best verified design (`fidelity_agreement`).
fn fidelity_agreement(cands: &[Candidate], verified: &[&Candidate], best: &Candidate) -> Value {
    let e0: Vec<f64> = verified.iter().map(|c| c.envelope.cost).collect();
    let e1: Vec<f64> = verified
        .iter()
        .map(|c| c.time.as_ref().expect("verified").cost)
        .collect();
    let rho = spearman(&e0, &e1);
    let rel: Vec<f64> = e0
        .iter()
        .zip(&e1)
        .filter(|(_, b)| **b != 0.0)
        .map(|(a, b)| (a / b - 1.0).abs())
        .collect();
    let mean_rel = rel.iter().sum::<f64>() / rel.len().max(1) as f64;
    let screening_rank_of_best = cands
        .iter()
        .filter(|c| c.design != best.design)
        .filter(|c| c.envelope.cost < best.envelope.cost)
        .count()
        + 1;
    json!({
        "verified_designs": verified.len(),
        "spearman_envelope_vs_time": rho,
        "mean_relative_difference_envelope_vs_time": mean_rel,
        "screening_rank_of_best": screening_rank_of_best,
    })
}

/// `robustness.csv`: the design `robust` with the structure detuned by ±d in frequency on
/// level 1; returns the cases for the summary.
fn write_robustness(space: &Space, robust: &Design, out: &Path) -> Result<Vec<Value>, DesignError> {
    let st = space.study;
    let dampers = space.coupled_dampers(robust)?;
    let best_structure = space.structure(robust.choice);
    let d = st.file.search.detuning;
    let mut rob = String::from("case,frequency_scale,objective_time_simulation\n");
    let mut detune = Vec::new();
    for (case, s) in [("minus", 1.0 - d), ("nominal", 1.0), ("plus", 1.0 + d)] {
        let (e, _) = time_evaluation(st, &detuned(best_structure, s), &dampers)?;
        let _ = writeln!(rob, "{case},{s},{:e}", shown(space, e.cost));
        detune.push(json!({"case": case, "frequency_scale": s, "objective": shown(space, e.cost)}));
    }
    write(out, "robustness.csv", &rob)?;
    Ok(detune)
}

/// The listed designs as the summary gives them (`top`), each with the level that confirmed it.
fn listed_json(
    space: &Space,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
    dem: &[DemVerification],
) -> Vec<Value> {
    let f = &space.study.file;
    let (_, obj) = objective_names(space);
    top.iter()
        .enumerate()
        .map(|(i, c)| {
            json!({
                "rank": i + 1,
                "design": describe(space, &c.design),
                "location": space.location(c.design.choice).label,
                "material": f.materials[c.design.choice.material].name,
                "particle_radius_m": space.geometry(c.design.choice).radius_m,
                "container_length_m": space.geometry(c.design.choice).length_m,
                "particles_per_layer": c.design.particles,
                "bed_mass_kg": space.bed_mass_kg(&c.design),
                format!("{obj}_envelope"): shown(space, c.envelope.cost),
                format!("{obj}_time_simulation"): c.time.as_ref().map(|t| shown(space, t.cost)),
                "damping_ratio_per_mode_time_simulation": c.time.as_ref().map(|t| t.damping_ratio_per_mode.clone()),
                "peak_amplitude_per_mode_m_time_simulation": c.time.as_ref().map(|t| t.peak_amplitude_per_mode_m.clone()),
                "coating": f.damper.coatings[c.design.choice.coating],
                "confirmed_by": if dem.iter().any(|d| d.rank == i + 1) {
                    "coupled_dem"
                } else if field_of(fields, &c.design).is_some() {
                    "effective_fields"
                } else {
                    "formulas_time"
                },
                "effective_fields": field_of(fields, &c.design),
                "coupled_dem": dem.iter().find(|d| d.rank == i + 1),
                "scenario": format!("scenarios/design_{}.toml", i + 1),
            })
        })
        .collect()
}

/// The listed designs: with level 2, its designs in its order (every coating), then the other
/// time-simulated designs in level-1 order, up to `search.top` in all (level 2's all listed);
/// without level 2 the best `search.top` time-simulated designs.
fn listed_candidates(
    space: &Space,
    verified: &[&Candidate],
    fields: &[FieldEvaluation],
) -> Vec<Candidate> {
    let top = space.study.file.search.top;
    let mut list: Vec<Candidate> = Vec::new();
    for e in fields.iter().filter(|e| e.failure.is_none()) {
        let mut plain = e.design.clone();
        plain.choice.coating = 0;
        if let Some(c) = verified.iter().find(|c| c.design == plain) {
            let mut c = (*c).clone();
            c.design = e.design.clone();
            list.push(c);
        }
    }
    for c in verified {
        if list.len() >= top.max(fields.iter().filter(|e| e.failure.is_none()).count()) {
            break;
        }
        if !list.iter().any(|l| l.design == c.design) {
            list.push((*c).clone());
        }
    }
    list
}
