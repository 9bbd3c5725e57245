//! A design as the outputs name it: its one-line description and the study's coupling scenario
//! with the design's structure (shared by the report and the verification levels).

use crate::DesignError;
use crate::space::{Design, Space};
use crate::study::Direction;

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
