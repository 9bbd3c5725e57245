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

/// Why the crosses are one mesh: a sphere pressed onto the face of the single cross where its
/// two arms cross (x = 23.7 mm, y = z = 0) touches the union mesh once; as two `box_outside`
/// bars, each bar reports its own contact at the same point (twice the force). Beside the
/// crossing (y = 10 mm) both give one contact.
#[test]
fn the_union_mesh_of_a_cross_presents_the_crossing_once() {
    use pdamp_dem::Vec3;
    use pdamp_dem::walls::{Geometry, TriMesh};
    let (_, world) =
        Scenario::load_and_build(&examples().join("damper_ch8_single_cross.toml")).unwrap();
    let union = world
        .bodies
        .iter()
        .flat_map(|b| &b.walls)
        .find(|w| w.name == "cross")
        .map(|w| w.geometry.clone())
        .unwrap();
    let bar = |half: [f64; 3]| {
        let mut m = TriMesh::box_inside(Vec3::new(0.0262, 0.0, 0.0), Vec3::from(half));
        m.flip_normals();
        Geometry::Mesh(m)
    };
    let bars = [bar([0.0025, 0.02, 0.0025]), bar([0.0025, 0.0025, 0.02])];
    let r = 1.25e-3;
    for (y, bars_expected) in [(0.0, 2), (0.01, 1)] {
        // 10 µm into the face x = 26.2 − 2.5 mm
        let x = Vec3::new(0.0262 - 0.0025 - r + 1e-5, y, 0.0);
        let mut out = Vec::new();
        union.sphere_contacts(&x, r, 0.0, &mut out);
        assert_eq!(out.len(), 1, "union at y = {y}: {out:?}");
        assert!((out[0].overlap_m - 1e-5).abs() < 1e-9);
        out.clear();
        for b in &bars {
            b.sphere_contacts(&x, r, 0.0, &mut out);
        }
        assert_eq!(out.len(), bars_expected, "two bars at y = {y}: {out:?}");
    }
}
