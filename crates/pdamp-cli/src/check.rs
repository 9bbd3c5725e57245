//! `pdamp check`: a scenario (or a design study, or another kind of input) loaded, validated
//! and built without running it.

use anyhow::{Result, anyhow, bail};

/// Warnings about a scenario that runs but is unlikely to be what the user wants.
fn scenario_warnings(
    sc: &pdamp_scenario::schema::Scenario,
    world: &pdamp_dem::World,
) -> Vec<String> {
    let mut w = Vec::new();
    for b in &world.bodies {
        for wall in &b.walls {
            if let pdamp_dem::walls::Geometry::Mesh(m) = &wall.geometry
                && !m.is_closed()
            {
                w.push(format!(
                    "body '{}', wall '{}': the mesh is not closed (some edge is not shared by exactly two \
                     triangles running along it in opposite directions): particles can leave a container \
                     through the gap; close the mesh if it is meant to hold the bed",
                    b.name, wall.name
                ));
            }
        }
    }
    if sc.damper.is_some() {
        for g in sc.crystal_groups() {
            w.push(format!(
                "particles[{g}].placement.method: a damper bed that starts as a crystal (grid/tight) has another packing \
                 fraction and clearance than a poured bed and moves as a block; the dissertation's beds are drop-downs: \
                 use method = \"drop_down\" (with [settle]) for results to compare with it"
            ));
        }
        if sc.damper.as_ref().is_some_and(|d| d.packings == 1) {
            w.push(
                "damper.packings = 1: one bed is one sample of a chaotic system; set packings >= 3 (or --packings) \
                 for a mean with a 95 % confidence interval"
                    .into(),
            );
        }
    }
    w
}

/// For a TOML file that is not a DEM scenario (no `[simulation]`), the command that reads it.
fn other_scenario_kind(path: &std::path::Path) -> Option<&'static str> {
    let table = std::fs::read_to_string(path)
        .ok()?
        .parse::<toml::Table>()
        .ok()?;
    if table.contains_key("simulation") {
        return None;
    }
    let has = |k: &str| table.contains_key(k);
    Some(
        if has("beam") && has("powder") || has("beam") && has("run") {
            "a powder cantilever scenario: run it with `pdamp powder run FILE --out DIR` (docs/powder.md)"
        } else if has("dampers") || has("analysis") {
            "a structure-with-dampers scenario: run it with `pdamp couple FILE --out DIR` (docs/structure.md)"
        } else if has("study") {
            "a layer study: run it with `pdamp structure optimize-layers FILE --out DIR` (docs/structure.md)"
        } else if has("structure") {
            "a structure: see its modes with `pdamp structure modes FILE --out DIR` (docs/structure.md)"
        } else {
            return None;
        },
    )
}

/// `pdamp check` of a design study (`scenario`, `[objective]`, `[damper]`): every key checked
/// by the optimiser's loader, then the size of the space and the work it implies.
fn check_design_study(path: &std::path::Path) -> Option<Result<()>> {
    let table = std::fs::read_to_string(path)
        .ok()?
        .parse::<toml::Table>()
        .ok()?;
    if !(table.contains_key("objective") && table.contains_key("damper")) {
        return None;
    }
    Some((|| {
        let study = pdamp_optimizer::DesignStudy::load(path).map_err(|e| anyhow!(e))?;
        let space = pdamp_optimizer::Space::new(&study);
        let size = space.size();
        let s = &study.file.search;
        let enumerate = match s.screening {
            pdamp_optimizer::study::Screening::Enumerate => true,
            pdamp_optimizer::study::Screening::Swarm => false,
            pdamp_optimizer::study::Screening::Auto => size <= s.max_enumerated as f64,
        };
        let screened = if enumerate {
            format!("all {size:.0} designs screened with the envelope model")
        } else {
            format!(
                "{size:.3e} designs: a particle swarm over {} categorical choice(s), ≤ {} envelope \
                 evaluations each",
                space.choices().len(),
                s.swarm_particles as u64 * (s.swarm_iterations + 1)
            )
        };
        let verify = s.verifications.map_or_else(
            || "10 % of the screened designs (2 … 60)".to_string(),
            |v| v.to_string(),
        );
        let v = &study.file.verification;
        let dem = if v.dem_designs == 0 {
            String::new()
        } else {
            let per_design = match &study.file.objective {
                pdamp_optimizer::study::ObjectiveSpec::MaxDamping { modes, .. } => modes.len(),
                _ => 1,
            };
            format!(
                "; coupled DEM: {} runs ({} designs × {} packings{}), each one's cost \
                 (particles × steps) printed before it starts{}",
                v.dem_designs * v.packings * per_design,
                v.dem_designs,
                v.packings,
                if per_design > 1 {
                    format!(" × {per_design} modes")
                } else {
                    String::new()
                },
                if v.youngs_modulus_scale < 1.0 {
                    format!(", softened × {}", v.youngs_modulus_scale)
                } else {
                    String::new()
                }
            )
        };
        let fields = if v.field_designs == 0 {
            String::new()
        } else {
            let modes = match &study.file.objective {
                pdamp_optimizer::study::ObjectiveSpec::MinStroke { .. } => 1,
                pdamp_optimizer::study::ObjectiveSpec::MaxDamping { modes, .. }
                | pdamp_optimizer::study::ObjectiveSpec::MinFrfPeak { modes, .. }
                | pdamp_optimizer::study::ObjectiveSpec::MaxResonanceDamping { modes, .. } => {
                    modes.len()
                }
            };
            let designs = v.field_designs * study.file.damper.coatings.len();
            format!(
                "; effective fields: {designs} designs ({} × {} coating(s)) × {modes} mode(s) × \
                 {} amplitudes × {} packings = {} DEM field points of {} cycles (stored points \
                 are reused)",
                v.field_designs,
                study.file.damper.coatings.len(),
                v.field_amplitudes,
                v.packings,
                designs * modes * v.field_amplitudes * v.packings,
                v.field_cycles
            )
        };
        println!(
            "{}: a design study, OK — {screened}; time simulations: {verify}{fields}{dem}; run \
             it with `pdamp design FILE --out DIR` (docs/design.md)",
            path.display()
        );
        Ok(())
    })())
}

pub(crate) fn cmd_check(scenario: &std::path::Path) -> Result<()> {
    if let Some(r) = check_design_study(scenario) {
        return r;
    }
    if let Some(kind) = other_scenario_kind(scenario) {
        bail!(
            "{} is not a DEM scenario (it has no [simulation] table) but {kind}; `pdamp check` \
             checks DEM scenarios (beds, dampers, plain runs)",
            scenario.display()
        );
    }
    let (sc, world) = pdamp_scenario::schema::Scenario::load_and_build(scenario)?;
    let p = &world.particles;
    let bed_mass: f64 = p.mass.iter().sum();
    let (rmin, rmax) = p
        .radius
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &r| (a.min(r), b.max(r)));
    let tc = world.min_contact_time_s(sc.simulation.check_impact_velocity_m_s);
    let mut report = serde_json::json!({
        "scenario": scenario,
        "title": sc.title,
        "particles": p.len(),
        "bed_mass_kg": bed_mass,
        "min_radius_m": rmin,
        "max_radius_m": rmax,
        "bodies": world.bodies.iter().map(|b| b.name.clone()).collect::<Vec<_>>(),
        "time_step_s": sc.simulation.time_step_s,
        "shortest_contact_time_s": tc,
        "time_step_over_contact_time": sc.simulation.time_step_s / tc,
        "estimate": pdamp_scenario::estimate::Estimate::of(
            &sc,
            sc.fields
                .as_ref()
                .and_then(|f| pdamp_design::FieldGrid::from_spec(f).ok())
                .map_or(1, |g| g.frequencies_hz.len() * g.amplitude_values.len()),
            rayon::current_num_threads(),
        ),
        "estimate_for": if sc.fields.is_some() {
            "pdamp fields (every point of the [fields] grid)"
        } else {
            "pdamp run"
        },
        "warnings": scenario_warnings(&sc, &world),
    });
    #[cfg(feature = "gpu")]
    {
        report["gpu_backend"] = match pdamp_gpu::check_world(&world) {
            Ok(()) => serde_json::json!("supported (pdamp fields --device gpu)"),
            Err(e) => serde_json::json!(format!("not supported: {e}")),
        };
    }
    for w in scenario_warnings(&sc, &world) {
        eprintln!("warning: {w}");
    }
    if let Some(d) = &sc.damper {
        report["damper"] = serde_json::json!({
            "container_body": d.container_body,
            "container_mass_kg": d.container_mass_kg,
            "frequency_hz": d.frequency_hz,
            "amplitude_m": d.frequency_hz.and_then(|f| d.amplitude_at(f)),
            "cycles": d.cycles,
            "transient_cycles": d.transient_cycles,
        });
    }
    if let Some(f) = &sc.fields {
        let g = pdamp_design::FieldGrid::from_spec(f).map_err(anyhow::Error::msg)?;
        report["fields"] = serde_json::json!({
            "frequencies_hz": g.frequencies_hz,
            "amplitude_axis": format!("{:?}", g.amplitude_axis),
            "amplitude_values": g.amplitude_values,
            "points": g.frequencies_hz.len() * g.amplitude_values.len(),
        });
    }
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
