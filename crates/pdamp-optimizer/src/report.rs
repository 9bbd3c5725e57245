//! What `pdamp design` writes: `designs.csv` (ranked, both fidelity levels), `summary.json`,
//! `report.md` (for an engineer to hand on), `decay.png/svg` (min_stroke: the best designs'
//! decays against the bare structure) or `damping.png/svg` (max_damping: ζ(X) of the best
//! designs), `robustness.csv` (the best design detuned by ±d in frequency, and its ζ(X)) and
//! `scenarios/design_N.toml`, a ready-to-run `pdamp couple` scenario for every listed design.
//! Every file is written atomically.

use crate::DesignError;
use crate::effective_fields::FieldEvaluation;
use crate::fidelity::{amplitude_grid, curve_at, simulated_damping_curve, time_evaluation};
use crate::search::{Candidate, SearchOutcome, spearman};
use crate::space::{Design, Space};
use crate::study::{Direction, ObjectiveSpec};
use pdamp_io::atomic::write_atomic;
use pdamp_plot::{Axis, LinePlot, Series, line_plot};
use pdamp_structure::modal::ModalStructure;
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

fn write(out: &Path, name: &str, text: &str) -> Result<(), DesignError> {
    let p = out.join(name);
    write_atomic(&p, text.as_bytes()).map_err(|e| DesignError::output(p, e))
}

/// One-line description of a design, e.g. `3 layers 32/40/40 × steel r = 5 mm, L = 120 mm at 'damper'`.
pub fn describe(space: &Space, d: &Design) -> String {
    let f = &space.study.file;
    let g = space.geometry(d.choice);
    let counts: Vec<String> = d.particles.iter().map(|n| n.to_string()).collect();
    let what = match space.location(d.choice).direction {
        Direction::Horizontal
            if f.damper.container_height_m.is_some() && d.particles.len() == 1 =>
        {
            format!("horizontal bed of {}", counts[0])
        }
        Direction::Horizontal => format!("{} layer(s) {}", d.particles.len(), counts.join("/")),
        Direction::Vertical => format!("vertical bed of {}", counts.join("/")),
    };
    let n = space.location(d.choice).points.len();
    let what = if n > 1 {
        format!("{n} containers, each a {what}")
    } else {
        what
    };
    let coating = &f.damper.coatings[d.choice.coating];
    format!(
        "{what} × {} r = {:.3} mm (n_max = {}), L = {:.1} mm{} at {}",
        f.materials[d.choice.material].name,
        g.radius_m * 1e3,
        g.capacity,
        g.length_m * 1e3,
        if coating == crate::spec::NO_COATING {
            String::new()
        } else {
            format!(", end walls coated with {coating}")
        },
        space.location(d.choice).label
    )
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
fn per_mode_values<'a>(space: &Space, e: &'a crate::fidelity::Evaluation) -> &'a [f64] {
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

/// `designs.csv`: verified designs by level-1 objective, then the screened ones by level 0.
/// With levels 2 and 3: the listed designs first (their order), each with the highest level
/// that ran on it and the ensembles' means and 95 % half-widths, then the other designs.
fn designs_csv(
    space: &Space,
    cands: &[Candidate],
    listed: &[Candidate],
    fields: &[FieldEvaluation],
    dem: &[crate::dem::DemVerification],
) -> String {
    let layers = space.study.file.damper.layers;
    let (per_mode, obj) = objective_names(space);
    let mut h = vec![
        "rank".to_string(),
        "fidelity".into(),
        "point".into(),
        "material".into(),
        "coating".into(),
        "particle_radius_m".into(),
        "container_length_m".into(),
        "particles_max_per_layer".into(),
    ];
    h.extend((1..=layers).map(|i| format!("particles_layer_{i}")));
    h.extend((1..=layers).map(|i| format!("clearance_layer_{i}_m")));
    h.push("bed_mass_kg".into());
    h.push(format!("{obj}_envelope"));
    h.push(format!("{obj}_time_simulation"));
    for m in &per_mode {
        h.push(format!("{m}_envelope"));
        h.push(format!("{m}_time_simulation"));
    }
    h.push("verified_as".into());
    for level in ["effective_fields", "coupled_dem"] {
        h.push(format!("{obj}_{level}_mean"));
        h.push(format!("{obj}_{level}_ci95_half_width"));
    }
    let mut s = h.join(",") + "\n";
    let f = &space.study.file;
    let rows = listed
        .iter()
        .enumerate()
        .map(|(i, c)| (c, Some(i + 1)))
        .chain(
            cands
                .iter()
                .filter(|c| !listed.iter().any(|l| l.design == c.design))
                .map(|c| (c, None)),
        );
    for (i, (c, listed_rank)) in rows.enumerate() {
        let g = space.geometry(c.design.choice);
        let field = fields
            .iter()
            .find(|e| e.design == c.design && e.failure.is_none());
        let coupled = listed_rank.and_then(|r| dem.iter().find(|d| d.rank == r));
        let mut row = vec![
            (i + 1).to_string(),
            if coupled.is_some() {
                "coupled_dem".into()
            } else if field.is_some() {
                "effective_fields".into()
            } else if c.time.is_some() {
                "formulas_time".into()
            } else {
                "envelope".into()
            },
            space.location(c.design.choice).label.replace(',', ";"),
            f.materials[c.design.choice.material].name.clone(),
            f.damper.coatings[c.design.choice.coating].clone(),
            format!("{:e}", g.radius_m),
            format!("{:e}", g.length_m),
            g.capacity.to_string(),
        ];
        row.extend(c.design.particles.iter().map(|n| n.to_string()));
        row.extend(
            c.design
                .particles
                .iter()
                .map(|&n| format!("{:e}", g.clearance_m(n))),
        );
        row.push(format!("{:e}", space.bed_mass_kg(&c.design)));
        row.push(format!("{:e}", shown(space, c.envelope.cost)));
        row.push(
            c.time
                .as_ref()
                .map_or(String::new(), |t| format!("{:e}", shown(space, t.cost))),
        );
        for k in 0..per_mode.len() {
            row.push(format!("{:e}", per_mode_values(space, &c.envelope)[k]));
            row.push(c.time.as_ref().map_or(String::new(), |t| {
                format!("{:e}", per_mode_values(space, t)[k])
            }));
        }
        row.push(c.verified_as.map_or(String::new(), |v| (v + 1).to_string()));
        for st in [field.map(|e| e.stat), coupled.map(|d| d.stat)] {
            match st {
                Some(st) => {
                    row.push(format!("{:e}", st.mean));
                    row.push(format!("{:e}", st.ci95_half_width));
                }
                None => row.extend([String::new(), String::new()]),
            }
        }
        s += &(row.join(",") + "\n");
    }
    s
}

/// A ready-to-run `pdamp couple` scenario of a design: the study's scenario with its dampers
/// replaced (the structure file referenced by its absolute path).
/// The study's coupling scenario as a table, with the structure of the design's location: the
/// structure file by its absolute path, or inline (`[structure]`) for a position along a beam.
pub fn scenario_table(space: &Space, d: &Design) -> Result<toml::Table, DesignError> {
    let st = space.study;
    let text = std::fs::read_to_string(&st.scenario_path)
        .map_err(|e| DesignError::Load(format!("{}: {e}", st.scenario_path.display())))?;
    let mut table: toml::Table = toml::from_str(&text)
        .map_err(|e| DesignError::Load(format!("{}: {e}", st.scenario_path.display())))?;
    match &space.location(d.choice).spec {
        Some(spec) => {
            table.remove("structure_file");
            table.insert(
                "structure".into(),
                toml::Value::try_from(spec)
                    .map_err(|e| DesignError::Solver(format!("serialising the structure: {e}")))?,
            );
        }
        None => {
            if let Some(p) = &st.structure_file {
                table.insert(
                    "structure_file".into(),
                    toml::Value::String(p.display().to_string()),
                );
            }
        }
    }
    Ok(table)
}

fn scenario_toml(space: &Space, d: &Design, rank: usize) -> Result<String, DesignError> {
    let st = space.study;
    let mut table = scenario_table(space, d)?;
    let dampers = toml::Value::try_from(space.damper_specs(d))
        .map_err(|e| DesignError::Solver(format!("serialising the dampers: {e}")))?;
    table.insert("dampers".into(), dampers);
    let body = toml::to_string(&table)
        .map_err(|e| DesignError::Solver(format!("serialising the scenario: {e}")))?;
    Ok(format!(
        "# Design {rank} of the design study {} (pdamp design):\n# {}\n# bed mass {:.4} kg; \
         analytical dampers (approach 3) as verified by the time simulation.\n#\n#   pdamp \
         couple scenarios/design_{rank}.toml --out out/design_{rank}\n{body}",
        st.path.display(),
        describe(space, d),
        space.bed_mass_kg(d)
    ))
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
    let fields = if f.verification.field_designs > 0 {
        let level1: Vec<(&Design, &crate::fidelity::Evaluation)> = verified
            .iter()
            .map(|c| (&c.design, c.time.as_ref().expect("verified")))
            .collect();
        crate::effective_fields::run_level(space, &level1, out, progress)?
    } else {
        Vec::new()
    };
    let fields_wall_s = fields_started.elapsed().as_secs_f64();
    let listed = listed_candidates(space, &verified, &fields);
    let top: Vec<&Candidate> = listed.iter().collect();
    let field_of = |d: &Design| {
        fields
            .iter()
            .find(|e| &e.design == d && e.failure.is_none())
    };
    for (i, c) in top.iter().enumerate() {
        let text = match field_of(&c.design) {
            Some(e) => fields_scenario_toml(space, e, out, i + 1)?,
            None => scenario_toml(space, &c.design, i + 1)?,
        };
        write(out, &format!("scenarios/design_{}.toml", i + 1), &text)?;
    }
    if !fields.is_empty() {
        write(out, "fields.csv", &fields_csv(space, &fields))?;
    }
    // the bare structure on both levels
    let (bare_time, bare_hist) = time_evaluation(st, &st.structure, &[])?;
    // level 0 against level 1 on the verified designs
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
    // robustness of the best listed design (level 2's best where it ran): detuned ±d on level 1
    let robust = &top[0].design;
    let dampers = space.coupled_dampers(robust)?;
    let best_structure = space.structure(robust.choice);
    let d = f.search.detuning;
    let mut rob = String::from("case,frequency_scale,objective_time_simulation\n");
    let mut detune = Vec::new();
    for (case, s) in [("minus", 1.0 - d), ("nominal", 1.0), ("plus", 1.0 + d)] {
        let (e, _) = time_evaluation(st, &detuned(best_structure, s), &dampers)?;
        let _ = writeln!(rob, "{case},{s},{:e}", shown(space, e.cost));
        detune.push(json!({"case": case, "frequency_scale": s, "objective": shown(space, e.cost)}));
    }
    write(out, "robustness.csv", &rob)?;
    let (mut plot, mut plots) = level1_damping_curves(space, &verified, out)?;
    if let Some(bh) = &bare_hist {
        let mut p = LinePlot::new(
            Axis::linear("time t (s)"),
            Axis::linear("displacement at the output point x (mm)"),
        );
        let mm = |v: &[f64]| v.iter().map(|x| x * 1e3).collect::<Vec<f64>>();
        p.series.push(Series::new(
            "bare structure",
            bh.time_s.clone(),
            mm(&bh.displacement_m),
        ));
        for (i, c) in verified.iter().take(3).enumerate() {
            let dm = space.coupled_dampers(&c.design)?;
            if let (_, Some(h)) = time_evaluation(st, space.structure(c.design.choice), &dm)? {
                p.series.push(Series::new(
                    format!("design {}", i + 1),
                    h.time_s.clone(),
                    mm(&h.displacement_m),
                ));
            }
        }
        match line_plot(out.join("decay"), &p) {
            Ok(_) => plots.push("decay.png"),
            Err(e) => eprintln!("note: no decay.png: {e}"),
        }
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
    let list: Vec<Value> = top
        .iter()
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
                } else if field_of(&c.design).is_some() {
                    "effective_fields"
                } else {
                    "formulas_time"
                },
                "effective_fields": field_of(&c.design),
                "coupled_dem": dem.iter().find(|d| d.rank == i + 1),
                "scenario": format!("scenarios/design_{}.toml", i + 1),
            })
        })
        .collect();
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
        "fidelity_agreement": {
            "verified_designs": verified.len(),
            "spearman_envelope_vs_time": rho,
            "mean_relative_difference_envelope_vs_time": mean_rel,
            "screening_rank_of_best": screening_rank_of_best,
        },
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

/// Forced objectives: the steady-state FRF at the output point (D Eq. 3.44) of the bare
/// structure and of the three best verified designs around every objective mode
/// (`frf.csv`: `mode,frequency_hz,bare_m,design_1_m,…`), and in `frf.png` also the coupled-DEM
/// sweeps of the first packing of every verified design (its `frf.csv` × the force). Returns
/// whether the plot was written.
fn frf_plots(
    space: &Space,
    verified: &[&Candidate],
    dem: &[crate::dem::DemVerification],
    out: &Path,
) -> Result<bool, DesignError> {
    let st = space.study;
    let (ObjectiveSpec::MinFrfPeak { modes, band, .. }
    | ObjectiveSpec::MaxResonanceDamping { modes, band, .. }) = &st.file.objective
    else {
        return Ok(false);
    };
    let force = st.load.as_ref().map_or(0.0, |l| l.force_n);
    let top: Vec<&&Candidate> = verified.iter().take(3).collect();
    let mut csv = String::from("mode,frequency_hz,bare_m");
    for i in 0..top.len() {
        let _ = write!(csv, ",design_{}_m", i + 1);
    }
    csv.push('\n');
    let mut plot = LinePlot::new(
        Axis::linear("frequency f (Hz)"),
        Axis::log("amplitude at the output point x (m)"),
    );
    for &m in modes {
        let k = m - 1;
        let fk = st.structure.modes[k].frequency_hz;
        // the bed's mass lowers the resonance: the band reaches further down than up
        let (lo, hi) = (fk * (1.0 - 2.0 * band).max(0.05), fk * (1.0 + band));
        let freqs: Vec<f64> = (0..400)
            .map(|i| lo + (hi - lo) * i as f64 / 399.0)
            .collect();
        let mut columns = vec![crate::fidelity::steady_frf_at_output(
            st,
            &st.structure,
            &[],
            k,
            &freqs,
        )?];
        for c in &top {
            let dm = space.coupled_dampers(&c.design)?;
            columns.push(crate::fidelity::steady_frf_at_output(
                st,
                space.structure(c.design.choice),
                &dm,
                k,
                &freqs,
            )?);
        }
        for (i, f) in freqs.iter().enumerate() {
            let _ = write!(csv, "{m},{f:e}");
            for col in &columns {
                let _ = write!(csv, ",{:e}", col[i]);
            }
            csv.push('\n');
        }
        for (j, col) in columns.into_iter().enumerate() {
            let label = if j == 0 {
                format!("mode {m}, bare structure")
            } else {
                format!("mode {m}, design {j} (formulas)")
            };
            plot.series.push(Series::new(label, freqs.clone(), col));
        }
        for d in dem {
            let path = out
                .join(&d.dir)
                .join("packing_1")
                .join(format!("mode_{m}"))
                .join("out")
                .join("frf.csv");
            if let Ok(text) = std::fs::read_to_string(&path) {
                let (fs, xs): (Vec<f64>, Vec<f64>) = text
                    .lines()
                    .skip(1)
                    .filter_map(|l| {
                        let mut it = l.split(',');
                        let f = it.next()?.parse::<f64>().ok()?;
                        let h = it.next()?.parse::<f64>().ok()?;
                        Some((f, h * force))
                    })
                    .unzip();
                if !fs.is_empty() {
                    plot.series.push(Series::new(
                        format!("mode {m}, design {}, coupled DEM sweep (packing 1)", d.rank),
                        fs,
                        xs,
                    ));
                }
            }
        }
    }
    write(out, "frf.csv", &csv)?;
    match line_plot(out.join("frf"), &plot) {
        Ok(_) => Ok(true),
        Err(e) => {
            eprintln!("note: no frf.png: {e}");
            Ok(false)
        }
    }
}

/// ζ(X) of the three best verified designs from level 1 (`damping_curve.csv` for the best,
/// `damping.png` for all three): over the objective's amplitude range (max_damping) or from
/// the release amplitude down to half the best stroke (min_stroke). Returns the plot (level 3
/// adds its curves) and the plots written.
fn level1_damping_curves(
    space: &Space,
    verified: &[&Candidate],
    out: &Path,
) -> Result<(LinePlot, Vec<&'static str>), DesignError> {
    let st = space.study;
    let f = &st.file;
    let best = verified[0];
    let (curve_modes, lo, hi) = match &f.objective {
        ObjectiveSpec::MinStroke { .. } => {
            let out_phi = st
                .structure
                .point(&st.free.output_point)
                .map_err(DesignError::from)?;
            let init_phi = st
                .structure
                .point(&st.free.initial_point)
                .map_err(DesignError::from)?;
            let k = st.free.mode;
            let x0 = (st.free.initial_displacement_m * out_phi[k] / init_phi[k]).abs();
            let x1 = best
                .time
                .as_ref()
                .and_then(|t| t.stroke_m)
                .unwrap_or(x0 / 10.0);
            (vec![k + 1], (0.5 * x1).max(x0 * 1e-3), x0)
        }
        ObjectiveSpec::MaxDamping {
            modes,
            amplitude_min_m,
            amplitude_max_m,
            ..
        } => (modes.clone(), *amplitude_min_m, *amplitude_max_m),
        ObjectiveSpec::MinFrfPeak { .. } | ObjectiveSpec::MaxResonanceDamping { .. } => {
            (Vec::new(), 0.0, 0.0)
        }
    };
    let mut curve_csv =
        String::from("mode,amplitude_m,damping_ratio_time_simulation,damping_ratio_bare\n");
    let mut plot = LinePlot::new(
        Axis::log("amplitude at the output point X (m)"),
        Axis::linear("damping ratio ζ (-)"),
    );
    for &m in &curve_modes {
        let grid = amplitude_grid(lo, hi, 16);
        for (label, c) in verified.iter().take(3).enumerate() {
            let dm = space.coupled_dampers(&c.design)?;
            let curve =
                simulated_damping_curve(st, space.structure(c.design.choice), &dm, m - 1, lo, hi)?;
            let ys: Vec<f64> = grid.iter().map(|&x| curve_at(&curve, x)).collect();
            if label == 0 {
                let zb = st.structure.modes[m - 1].damping_ratio;
                for (x, y) in grid.iter().zip(&ys) {
                    let _ = writeln!(curve_csv, "{m},{x:e},{y:e},{zb:e}");
                }
            }
            plot.series.push(Series::new(
                format!("mode {m}, design {}", label + 1),
                grid.clone(),
                ys,
            ));
        }
    }
    let mut plots = Vec::new();
    if !curve_modes.is_empty() {
        write(out, "damping_curve.csv", &curve_csv)?;
        match line_plot(out.join("damping"), &plot) {
            Ok(_) => plots.push("damping.png"),
            Err(e) => eprintln!("note: no damping.png: {e}"),
        }
    }
    Ok((plot, plots))
}

/// Level 3 of [`write_outputs`]: coupled DEM of the best designs (every container its own
/// dropped bed in one run), `dem.csv`, for max_damping `dem_damping_curve.csv` and the DEM
/// curves in `damping.png`, for the forced objectives `dem_resonance.csv`.
fn dem_level(
    space: &Space,
    top: &[&Candidate],
    out: &Path,
    plot: &mut LinePlot,
    plots: &mut Vec<&'static str>,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<crate::dem::DemVerification>, DesignError> {
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

/// `dem.csv`: one row per design and packing.
fn dem_csv(dem: &[crate::dem::DemVerification]) -> String {
    let obj = dem[0].objective;
    let mut csv = format!(
        "rank,packing,{obj}_coupled_dem,{obj}_time_simulation,particles,time_step_s,youngs_modulus_scale\n"
    );
    for d in dem {
        for (p, s) in d.values.iter().enumerate() {
            let _ = writeln!(
                csv,
                "{},{},{s:e},{:e},{},{:e},{}",
                d.rank,
                p + 1,
                d.time_simulation,
                d.particles,
                d.time_step_s,
                d.youngs_modulus_scale
            );
        }
    }
    csv
}

/// The best design under coupled DEM (largest mean ζ or smallest mean stroke).
fn best_by_dem(dem: &[crate::dem::DemVerification]) -> Option<&crate::dem::DemVerification> {
    let sign = |d: &crate::dem::DemVerification| {
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

/// The coupled-DEM section of `report.md`: the ensembles against the formulas, the energy
/// closure, ζ per mode (max_damping) and the DEM best.
fn dem_section(
    f: &crate::study::DesignStudyFile,
    dem: &[crate::dem::DemVerification],
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
fn resonance_table(dem: &[crate::dem::DemVerification]) -> String {
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

fn report_md(
    space: &Space,
    o: &SearchOutcome,
    s: &Value,
    top: &[&Candidate],
    fields: &[FieldEvaluation],
    dem: &[crate::dem::DemVerification],
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
    let objective = match &f.objective {
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
    };
    let _ = writeln!(r, "**Objective**: {objective}.\n");
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
    if !fields.is_empty() {
        r.push_str(&fields_section(space, fields));
        let _ = writeln!(r);
    }
    if !dem.is_empty() {
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
    r
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

/// The scenario of a design confirmed by its effective fields: its damper at every container
/// point as `model = "fields"` (approach 2) with the fields of every mode merged into
/// `scenarios/design_N_fields.csv` (ensemble means, one frequency per mode).
fn fields_scenario_toml(
    space: &Space,
    e: &FieldEvaluation,
    out: &Path,
    rank: usize,
) -> Result<String, DesignError> {
    let d = &e.design;
    let mut header = String::new();
    let mut rows: Vec<(f64, String)> = Vec::new();
    for m in &e.fields {
        let p = m.dir.join("fields.csv");
        let text = std::fs::read_to_string(&p).map_err(|err| DesignError::output(&p, err))?;
        let mut lines = text
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with('#'));
        if let Some(h) = lines.next() {
            header = h.to_string();
        }
        rows.extend(lines.map(|l| (m.frequency_hz, l.to_string())));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let csv_name = format!("design_{rank}_fields.csv");
    let mut csv = header + "\n";
    for (_, r) in &rows {
        csv += r;
        csv.push('\n');
    }
    write(out, &format!("scenarios/{csv_name}"), &csv)?;
    let bed = space.bed_mass_kg(d) / space.location(d.choice).points.len() as f64;
    let dampers: Vec<pdamp_structure::scenario::DamperSpec> = space
        .location(d.choice)
        .points
        .iter()
        .map(|p| pdamp_structure::scenario::DamperSpec::Fields {
            point: p.clone(),
            path: csv_name.clone().into(),
            bed_mass_kg: bed,
        })
        .collect();
    let mut table = scenario_table(space, d)?;
    table.insert(
        "dampers".into(),
        toml::Value::try_from(dampers)
            .map_err(|err| DesignError::Solver(format!("serialising the dampers: {err}")))?,
    );
    let body = toml::to_string(&table)
        .map_err(|err| DesignError::Solver(format!("serialising the scenario: {err}")))?;
    Ok(format!(
        "# Design {rank} of the design study {} (pdamp design):\n# {}\n# bed mass {:.4} kg; \
         effective fields (approach 2) of the DEM bed, {} packing(s), in {csv_name} (the mean \
         over the packings; each field at one mode's frequency).\n#\n#   pdamp couple \
         scenarios/design_{rank}.toml --out out/design_{rank}\n{body}",
        space.study.path.display(),
        describe(space, d),
        space.bed_mass_kg(d),
        e.stat.count
    ))
}

/// `fields.csv` of the design study: level 2's designs in its order.
fn fields_csv(space: &Space, fields: &[FieldEvaluation]) -> String {
    let obj = fields[0].objective;
    let (per_mode, _) = objective_names(space);
    let mut s = format!(
        "rank,level1_rank,coating,design,{obj}_effective_fields_mean,\
         {obj}_effective_fields_ci95_half_width,packings,{obj}_time_simulation"
    );
    for m in &per_mode {
        let _ = write!(
            s,
            ",{m}_effective_fields_mean,{m}_effective_fields_ci95_half_width"
        );
    }
    s += ",field_points,field_points_reused,time_step_s,wall_s\n";
    for (i, e) in fields.iter().enumerate() {
        let _ = write!(
            s,
            "{},{},{},{},{:e},{:e},{},{:e}",
            i + 1,
            e.level1_rank,
            e.coating,
            describe(space, &e.design).replace(',', ";"),
            e.stat.mean,
            e.stat.ci95_half_width,
            e.stat.count,
            e.time_simulation
        );
        for m in &e.per_mode {
            let _ = write!(s, ",{:e},{:e}", m.mean, m.ci95_half_width);
        }
        let _ = writeln!(
            s,
            ",{},{},{:e},{:.1}",
            e.fields.iter().map(|m| m.points).sum::<usize>(),
            e.fields.iter().map(|m| m.reused_points).sum::<usize>(),
            e.time_step_s,
            e.wall_s
        );
    }
    s
}

/// The effective-field section of `report.md`.
fn fields_section(space: &Space, fields: &[FieldEvaluation]) -> String {
    let f = &space.study.file;
    let v = &f.verification;
    let mut r = String::new();
    let _ = writeln!(r, "## Effective fields (approach 2)\n");
    let _ = writeln!(
        r,
        "The {} best time-simulated design(s), each with {} coating(s) ({}), as DEM beds in \
         their containers: η̄ and m̄/m_bed (D Eq. 3.13–3.17) at every objective mode's frequency \
         over {} log-spaced amplitudes of the damper point, {} cycles ({} dropped), on {} \
         dropped bed(s); the structure then simulated with each mode coupled to its field \
         (bilinear interpolation), once per bed's field.{} Fields stored in `{}` (reused on \
         every rerun).\n",
        v.field_designs,
        f.damper.coatings.len(),
        f.damper.coatings.join(", "),
        v.field_amplitudes,
        v.field_cycles,
        v.field_transient_cycles,
        v.packings,
        if v.youngs_modulus_scale < 1.0 {
            format!(
                " **Softened**: particle Young's modulus × {} (not the reference fidelity).",
                v.youngs_modulus_scale
            )
        } else {
            String::new()
        },
        fields
            .first()
            .and_then(|e| e.fields.first())
            .and_then(|m| m.dir.parent().and_then(|p| p.parent()))
            .map_or(String::new(), |p| p.display().to_string())
    );
    let (unit, scale) = if matches!(f.objective, ObjectiveSpec::MinStroke { .. }) {
        (" mm", 1e3)
    } else {
        ("", 1.0)
    };
    let _ = writeln!(
        r,
        "| rank | level-1 rank | coating | {obj} (formulas, time simulation) | {obj} (effective \
         fields, mean ± 95 % CI) | fields − formulas | η̄ on the grid | field points (reused) \
         | wall time |\n|---|---|---|---|---|---|---|---|---|",
        obj = fields[0].objective
    );
    for (i, e) in fields.iter().enumerate() {
        if let Some(why) = &e.failure {
            let _ = writeln!(
                r,
                "| {} | {} | {} | {:.4}{unit} | **no field**: {} | – | – | – | {:.0} s |",
                i + 1,
                e.level1_rank,
                e.coating,
                e.time_simulation * scale,
                why.replace('|', "/"),
                e.wall_s
            );
            continue;
        }
        let eta = e.fields.iter().fold((f64::INFINITY, 0.0_f64), |a, m| {
            (
                a.0.min(m.loss_factor_range.0),
                a.1.max(m.loss_factor_range.1),
            )
        });
        let _ = writeln!(
            r,
            "| {} | {} | {} | {:.4}{unit} | {:.4} ± {:.4}{unit} | {:+.1} % | {:.3}–{:.3} | {} ({}) \
             | {:.0} s |",
            i + 1,
            e.level1_rank,
            e.coating,
            e.time_simulation * scale,
            e.stat.mean * scale,
            e.stat.ci95_half_width * scale,
            100.0 * (e.stat.mean / e.time_simulation - 1.0),
            eta.0,
            eta.1,
            e.fields.iter().map(|m| m.points).sum::<usize>(),
            e.fields.iter().map(|m| m.reused_points).sum::<usize>(),
            e.wall_s
        );
    }
    // level 1 against level 2 on the uncoated designs
    let plain: Vec<&FieldEvaluation> = fields
        .iter()
        .filter(|e| e.design.choice.coating == 0 && e.failure.is_none())
        .collect();
    let a: Vec<f64> = plain.iter().map(|e| e.time_simulation).collect();
    let b: Vec<f64> = plain.iter().map(|e| e.stat.mean).collect();
    let best1 = plain
        .iter()
        .min_by_key(|e| e.level1_rank)
        .map(|e| e.level1_rank);
    let best2 = fields.iter().find(|e| e.failure.is_none());
    let _ = writeln!(
        r,
        "\nFormulas against fields on the {} design(s) without coating: Spearman rank \
         correlation {}; the time simulation's best (level-1 rank {}) is {} under the fields.",
        plain.len(),
        spearman(&a, &b).map_or("– (fewer than 3 designs)".to_string(), |x| format!(
            "{x:.2}"
        )),
        best1.map_or("–".into(), |x| x.to_string()),
        match (best1, best2) {
            (Some(b1), Some(b2)) if b2.level1_rank == b1 && b2.design.choice.coating == 0 =>
                "also the best".to_string(),
            (Some(b1), Some(b2)) if b2.level1_rank == b1 => format!(
                "also the best filling, and best with coating {}",
                b2.coating
            ),
            (_, Some(b2)) => format!(
                "not the best: level 2 prefers level-1 rank {} with coating {}",
                b2.level1_rank, b2.coating
            ),
            _ => "–".into(),
        }
    );
    if let Some(b) = best2 {
        let overlapping: Vec<String> = fields
            .iter()
            .enumerate()
            .filter(|(_, e)| {
                !std::ptr::eq(*e, b)
                    && e.failure.is_none()
                    && e.stat.ci95_low <= b.stat.ci95_high
                    && e.stat.ci95_high >= b.stat.ci95_low
            })
            .map(|(i, _)| (i + 1).to_string())
            .collect();
        if b.stat.count > 1 && !overlapping.is_empty() {
            let _ = writeln!(
                r,
                "\nThe 95 % intervals of field rank(s) {} overlap the best's: more packings \
                 decide.",
                overlapping.join(", ")
            );
        }
    }
    if f.damper.coatings.len() > 1 || f.damper.coatings[0] != crate::spec::NO_COATING {
        let _ = writeln!(r, "\n{}", coating_rule(space, fields));
    }
    let _ = writeln!(
        r,
        "\nEach field has one frequency, the mode's with the container on the structure; the \
         bed's effective mass lowers the coupled frequency by a few per cent, which the field \
         does not resolve, and outside the amplitude grid its edge values hold."
    );
    r
}

/// D's coated-wall design rule (Eq. 8.11 with Eq. 8.5, n_line = ⌊L/2r⌋, ν_w of the coating)
/// at the field frequencies, beside the coatings of the study.
fn coating_rule(space: &Space, fields: &[FieldEvaluation]) -> String {
    let f = &space.study.file;
    let mut r = String::from(
        "D's coated-wall rule (Eq. 8.11 + 8.5: the wall modulus at which the bed's compression \
         of the coating is the optimal stroke at Γ = 1, n_line particles in a row along the \
         excitation):",
    );
    let mut seen = Vec::new();
    for e in fields.iter().filter(|e| e.design.choice.coating == 0) {
        let g = space.geometry(e.design.choice);
        let m = &f.materials[e.design.choice.material];
        let n_line = (g.length_m / (2.0 * g.radius_m)).floor().max(1.0);
        let nu_w = f.coatings.first().map_or(0.49, |c| c.poisson_ratio);
        for fld in &e.fields {
            let key = (e.level1_rank, fld.mode);
            if seen.contains(&key) {
                continue;
            }
            seen.push(key);
            let dsg = pdamp_structure::design::coated_wall_design(
                &pdamp_structure::design::CoatedWallInput {
                    design_frequency_hz: fld.frequency_hz,
                    particle_radius_m: g.radius_m,
                    particle_density_kg_m3: m.density_kg_m3,
                    particle_youngs_modulus_pa: m.youngs_modulus_pa,
                    particle_poisson_ratio: m.poisson_ratio,
                    particles_per_line: n_line,
                    wall_poisson_ratio: nu_w,
                },
            );
            let _ = write!(
                r,
                " level-1 rank {} mode {} at {:.1} Hz: E_w ≈ {:.3} MPa (n_line = {n_line});",
                e.level1_rank,
                fld.mode,
                fld.frequency_hz,
                dsg.wall_modulus_pa * 1e-6
            );
        }
    }
    let table: Vec<String> = f
        .coatings
        .iter()
        .map(|c| format!("{} {:.3} MPa", c.name, c.youngs_modulus_pa * 1e-6))
        .collect();
    let _ = write!(r, " the coatings of the study: {}.", table.join(", "));
    r
}
