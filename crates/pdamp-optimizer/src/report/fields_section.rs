//! The effective-field section of `report.md`.

use crate::effective_fields::FieldEvaluation;
use crate::search::spearman;
use crate::space::Space;
use crate::study::ObjectiveSpec;
use std::fmt::Write as _;

/// The effective-field section of `report.md`.
pub(super) fn fields_section(space: &Space, fields: &[FieldEvaluation]) -> String {
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
    r.push_str(&formulas_against_fields(fields));
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

/// Level 1 against level 2 on the uncoated designs (Spearman rank correlation, whether the
/// time simulation's best stays the best) and the designs whose intervals overlap the best's.
fn formulas_against_fields(fields: &[FieldEvaluation]) -> String {
    let mut r = String::new();
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
    r
}
