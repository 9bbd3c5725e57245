//! The CSV tables of the report: `designs.csv`, `dem.csv` and `fields.csv`.

use super::{describe, objective_names, per_mode_values, shown};
use crate::dem::DemVerification;
use crate::effective_fields::FieldEvaluation;
use crate::search::Candidate;
use crate::space::Space;
use std::fmt::Write as _;

/// `designs.csv`: verified designs by level-1 objective, then the screened ones by level 0.
/// With levels 2 and 3: the listed designs first (their order), each with the highest level
/// that ran on it and the ensembles' means and 95 % half-widths, then the other designs.
pub(super) fn designs_csv(
    space: &Space,
    cands: &[Candidate],
    listed: &[Candidate],
    fields: &[FieldEvaluation],
    dem: &[DemVerification],
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

/// `dem.csv`: one row per design and packing.
pub(super) fn dem_csv(dem: &[DemVerification]) -> String {
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

/// `fields.csv` of the design study: level 2's designs in its order.
pub(super) fn fields_csv(space: &Space, fields: &[FieldEvaluation]) -> String {
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
