//! Every DEM scenario in `examples/` (a file with a `[simulation]` table) loads, validates and
//! builds its world in check mode (`Scenario::load_and_build`, what `pdamp check` runs), so a
//! shipped example never fails on a key or a placement a change made wrong; and every damper
//! example starts from a drop-down bed unless its comment says why it keeps a crystal.

use pdamp_scenario::schema::{PlacementMethod, Scenario};
use std::path::PathBuf;

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

#[test]
fn every_dem_example_checks() {
    let mut checked = 0;
    let mut failures = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(examples())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    entries.sort();
    for path in entries {
        let text = std::fs::read_to_string(&path).unwrap();
        let Ok(table) = text.parse::<toml::Table>() else {
            failures.push(format!("{}: not TOML", path.display()));
            continue;
        };
        if !table.contains_key("simulation") {
            continue; // structure, couple, powder and study files: their own commands
        }
        checked += 1;
        match Scenario::load_and_build(&path) {
            Err(e) => failures.push(format!("{}: {e}", path.display())),
            Ok((s, _)) => {
                let crystal = s.particles.iter().any(|g| {
                    matches!(
                        g.placement.method,
                        PlacementMethod::Grid | PlacementMethod::Tight
                    )
                });
                let says_why = ["Kept a crystal", "Kept crystals", "crystal counterpart"]
                    .iter()
                    .any(|w| text.contains(w));
                if s.damper.is_some() && crystal && !says_why {
                    failures.push(format!(
                        "{}: a damper with a crystal bed that does not say why (\"Kept a crystal …\")",
                        path.display()
                    ));
                }
            }
        }
    }
    assert!(checked >= 40, "only {checked} DEM examples found");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
