//! The ready-to-run scenarios of the listed designs (`scenarios/design_N.toml`).

use super::{describe, scenario_table, write};
use crate::DesignError;
use crate::effective_fields::FieldEvaluation;
use crate::space::{Design, Space};
use std::path::Path;

pub(super) fn scenario_toml(space: &Space, d: &Design, rank: usize) -> Result<String, DesignError> {
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

/// The scenario of a design confirmed by its effective fields: its damper at every container
/// point as `model = "fields"` (approach 2) with the fields of every mode merged into
/// `scenarios/design_N_fields.csv` (ensemble means, one frequency per mode).
pub(super) fn fields_scenario_toml(
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
