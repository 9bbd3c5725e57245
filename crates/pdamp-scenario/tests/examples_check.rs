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

/// The inner structures of D Sect. 8.1.4 ship as one closed mesh each
/// (`scripts/box_union_stl.py`, the union of the 5 mm × 5 mm bars, so that no surface is felt
/// twice where bars cross): closed, normals outwards (an obstacle), enclosing the bars' union —
/// single cross 2·(5·5·40) − 5·5·5 = 1875 mm³; triple cross three crosses plus the 26.2 mm axial
/// bar less its 2.5 + 5 + 2.5 mm inside the crosses: 3·1875 + 5·5·16.2 = 6030 mm³.
#[test]
fn inner_structure_meshes_are_closed_unions_of_the_bars() {
    for (file, wall, volume_mm3) in [
        ("damper_ch8_single_cross.toml", "cross", 1875.0),
        (
            "damper_ch8_tab83_triple_cross_softened.toml",
            "triple_cross",
            6030.0,
        ),
    ] {
        let (_, world) = Scenario::load_and_build(&examples().join(file)).unwrap();
        let mesh = world
            .bodies
            .iter()
            .flat_map(|b| &b.walls)
            .find(|w| w.name == wall)
            .map(|w| match &w.geometry {
                pdamp_dem::walls::Geometry::Mesh(m) => m,
                g => panic!("{file}: wall {wall} is {g:?}, not a mesh"),
            })
            .unwrap_or_else(|| panic!("{file}: no wall {wall}"));
        assert!(mesh.is_closed(), "{file}: {wall} is not closed");
        let v = mesh.enclosed_volume_m3() * 1e9;
        // STL stores single-precision coordinates: 13.1 mm is off by ≈ 5e-7 mm
        assert!((v / volume_mm3 - 1.0).abs() < 1e-7, "{file}: {v} mm³");
    }
}
