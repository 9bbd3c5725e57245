//! Drop-down beds [D Sect. 2.1, Fig. 2.2c/d]: random insertion clear of every wall and inner
//! structure, falling in rounds, settling; the bed's statistics; saved beds that continue a run
//! bit for bit; LAMMPS data files in and out.

use pdamp_dem::bed_statistics::bed_statistics;
use pdamp_dem::{Vec3, World};
use pdamp_scenario::prepare::{PreparedBed, prepare_bed, settle_scenario};
use pdamp_scenario::schema::Scenario;
use std::path::Path;
use std::sync::OnceLock;

const MATERIALS: &str = r#"
[[materials]]
name = "steel"
density_kg_m3 = 7800.0
youngs_modulus_pa = 1e8
poisson_ratio = 0.3
[contact]
normal = { law = "hertz-mindlin", restitution = 0.5 }
friction = { law = "mindlin", friction_coefficient = 0.3 }
"#;

/// 1 000 spheres (r = 1.75 mm, softened steel, μ = 0.3) dropped into a 40 mm cube.
fn cube(placement: &str, settle: bool) -> String {
    format!(
        r#"
title = "1000 spheres in a 40 mm cube"
[simulation]
duration_s = 0.02
time_step_s = 1e-5
gravity_m_s2 = [0.0, 0.0, -9.81]
seed = 1
{MATERIALS}
[[bodies]]
name = "container"
[[bodies.walls]]
name = "box"
material = "steel"
geometry = {{ type = "box_inside", center_m = [0.0, 0.0, 0.02], half_extents_m = [0.02, 0.02, 0.02] }}
[[particles]]
material = "steel"
count = 1000
size = {{ type = "monodisperse", radius_m = 1.75e-3 }}
placement = {placement}
{}
"#,
        if settle {
            "[settle]\nmax_duration_s = 1.0\nkinetic_energy_per_particle_j = 1e-10"
        } else {
            ""
        }
    )
}

const CUBE_DROP: &str = r#"{ method = "drop_down", region = { type = "box", min_m = [-0.02, -0.02, 0.0], max_m = [0.02, 0.02, 0.04] } }"#;

/// 1 000 spheres (r = 1.5 mm) in a cylinder (R = 20 mm, 60 mm high) around an inner rod
/// (`cylinder_outside`, r = 6 mm) on its axis.
fn cylinder_with_rod(method: &str) -> String {
    format!(
        r#"
title = "1000 spheres around a rod"
[simulation]
duration_s = 0.0
time_step_s = 1e-5
gravity_m_s2 = [0.0, 0.0, -9.81]
seed = 3
{MATERIALS}
[[bodies]]
name = "container"
[[bodies.walls]]
name = "can"
material = "steel"
geometry = {{ type = "cylinder_inside", base_center_m = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius_m = 0.02, length_m = 0.06 }}
[[bodies.walls]]
name = "rod"
material = "steel"
geometry = {{ type = "cylinder_outside", base_center_m = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius_m = 0.006, length_m = 0.06, capped = false }}
[[particles]]
material = "steel"
count = 1000
size = {{ type = "monodisperse", radius_m = 1.5e-3 }}
placement = {{ method = "{method}", region = {{ type = "cylinder", base_center_m = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius_m = 0.02, length_m = 0.06 }} }}
[settle]
max_duration_s = 1.0
kinetic_energy_per_particle_j = 1e-10
"#
    )
}

fn prepared_cube() -> &'static PreparedBed {
    static BED: OnceLock<PreparedBed> = OnceLock::new();
    BED.get_or_init(|| {
        let sc = Scenario::from_toml(&cube(CUBE_DROP, true)).expect("parse");
        sc.validate().expect("valid");
        prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()).expect("drop-down")
    })
}

/// Largest overlap of a particle with another or with a wall, relative to its radius.
fn max_overlaps(w: &World) -> (f64, f64) {
    let p = &w.particles;
    let mut pp = 0.0f64;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let ov = p.radius[i] + p.radius[j] - (p.position[i] - p.position[j]).norm();
            pp = pp.max(ov / p.radius[i].min(p.radius[j]));
        }
    }
    let mut pw = 0.0f64;
    let mut scratch = Vec::new();
    for i in 0..p.len() {
        if let Some((_, _, o)) = w.wall_overlap(&p.position[i], p.radius[i], &mut scratch) {
            pw = pw.max(o / p.radius[i]);
        }
    }
    (pp, pw)
}

/// Must-show 1 (cube): a random packing, not a crystal — bulk packing fraction in the random
/// loose/close range 0.58–0.64 and coordination number 4–7; contacts only by their deformation.
#[test]
fn drop_down_in_cube_is_a_random_packing() {
    let bed = prepared_cube();
    let s = bed_statistics(&bed.world, Some(Vec3::z()));
    eprintln!("cube: {s:#?}\ndrop-down: {:?}", bed.drop_down);
    assert_eq!(s.particles, 1000);
    assert!(
        (0.58..=0.64).contains(&s.packing_fraction_bulk),
        "bulk packing fraction {}",
        s.packing_fraction_bulk
    );
    // The free volume up to the surface includes the looser layers at the walls.
    assert!(s.packing_fraction < s.packing_fraction_bulk && s.packing_fraction > 0.45);
    assert!(
        (4.0..=7.0).contains(&s.mean_coordination_number),
        "Z = {}",
        s.mean_coordination_number
    );
    // Clearance to the lid: 40 mm − bed span, the bed span being its height from the floor.
    let h = s.clearance_m.unwrap();
    let span = s.bed_span_along_direction_m.unwrap();
    assert!((s.container_length_along_direction_m.unwrap() - 0.04).abs() < 1e-6);
    assert!((h - (0.04 - (span[1] - span[0]))).abs() < 1e-12 && h > 0.01);
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");
    assert!(
        bed.drop_down[0].inserted_per_round.len() >= 2,
        "{:?}",
        bed.drop_down
    );
}

/// Must-show 1 (cylinder with an inner rod): the insertion never puts a sphere into or across
/// the rod or the can, and the settled bed is a random packing around the rod.
#[test]
fn drop_down_around_inner_rod() {
    // The insertion itself (`random`: the same wall-aware insertion without the fall): no
    // overlap at all.
    let sc = Scenario::from_toml(&cylinder_with_rod("random")).expect("parse");
    let w = sc.build_world(Path::new(".")).expect("random insertion");
    let (pp, pw) = max_overlaps(&w);
    assert!(pp <= 1e-12 && pw <= 1e-9, "initial overlaps {pp} {pw}");
    for (x, r) in w.particles.position.iter().zip(&w.particles.radius) {
        let rho = (x.x * x.x + x.y * x.y).sqrt();
        assert!(rho >= 0.006 + r - 1e-12 && rho <= 0.02 - r + 1e-12, "{x:?}");
    }
    // The drop-down.
    let sc = Scenario::from_toml(&cylinder_with_rod("drop_down")).expect("parse");
    let bed =
        prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()).expect("drop-down");
    let s = bed_statistics(&bed.world, None);
    eprintln!("cylinder with rod: {s:#?}");
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");
    for x in &bed.world.particles.position {
        assert!(
            (x.x * x.x + x.y * x.y).sqrt() > 0.006,
            "inside the rod: {x:?}"
        );
    }
    assert!(
        (0.58..=0.64).contains(&s.packing_fraction_bulk),
        "bulk packing fraction {}",
        s.packing_fraction_bulk
    );
    assert!((4.0..=7.0).contains(&s.mean_coordination_number));
    // The rod holds the bed's centroid: the clearance is measured along the free lines beside
    // it, the can's 60 mm.
    let s = bed_statistics(&bed.world, Some(Vec3::z()));
    let length = s.container_length_along_direction_m.unwrap();
    assert!((length - 0.06).abs() < 1e-9, "container length {length}");
    let h = s.clearance_to_surface_m.unwrap();
    assert!((h - (0.06 - s.bed_height_m)).abs() < 1e-9 && h > 0.0, "{h}");
}

/// A closed inner obstacle (`box_outside`, a closed mesh): no sphere starts inside it, also
/// none that would not touch its faces (the one-sided triangles alone cannot tell).
#[test]
fn random_insertion_avoids_closed_mesh_interior() {
    let toml = format!(
        r#"
[simulation]
duration_s = 0.0
time_step_s = 1e-5
{MATERIALS}
[[bodies]]
name = "container"
[[bodies.walls]]
name = "box"
material = "steel"
geometry = {{ type = "box_inside", center_m = [0.0, 0.0, 0.02], half_extents_m = [0.02, 0.02, 0.02] }}
[[bodies.walls]]
name = "block"
material = "steel"
geometry = {{ type = "box_outside", center_m = [0.0, 0.0, 0.02], half_extents_m = [0.012, 0.012, 0.012] }}
[[particles]]
material = "steel"
count = 400
size = {{ type = "monodisperse", radius_m = 1e-3 }}
placement = {{ method = "random", region = {{ type = "box", min_m = [-0.02, -0.02, 0.0], max_m = [0.02, 0.02, 0.04] }} }}
"#
    );
    let sc = Scenario::from_toml(&toml).expect("parse");
    let w = sc.build_world(Path::new(".")).expect("world");
    let mut near = 0;
    for (i, x) in w.particles.position.iter().enumerate() {
        // Distance of the centre from the block (0 inside it) must be at least the radius.
        let out = Vec3::from_fn(|k, _| ((x[k] - [0.0, 0.0, 0.02][k]).abs() - 0.012).max(0.0));
        assert!(
            out.norm() >= 1e-3 * (1.0 - 1e-9),
            "particle {i} at {x:?} starts in the block"
        );
        near += (out.norm() < 3e-3) as usize;
    }
    assert!(
        near > 20,
        "the insertion uses the space around the block ({near})"
    );
}

/// Must-show 2: a bed saved by `pdamp settle` and loaded by `placement.method = "file"`
/// continues bit for bit like the run that settled it (1 and 2 threads).
#[test]
fn saved_bed_continues_bit_for_bit() {
    let dir = tempdir("saved_bed");
    let sc = Scenario::from_toml(&cube(CUBE_DROP, true)).expect("parse");
    settle_scenario(
        &sc,
        Path::new("."),
        &dir,
        &mut |_, _| {},
        &Default::default(),
    )
    .expect("settle");
    let reference = prepared_cube();
    let file = format!(
        r#"{{ method = "file", path = "{}" }}"#,
        dir.join("bed.pdbed").display()
    );
    let loaded = Scenario::from_toml(&cube(&file, false)).expect("parse");
    loaded.validate().expect("valid");
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (a, b) = pool.install(|| {
            let mut a = reference.world.clone();
            let mut b = loaded.build_world(Path::new(".")).expect("bed from file");
            for _ in 0..500 {
                a.step();
                b.step();
            }
            (a, b)
        });
        let p = (&a.particles, &b.particles);
        assert_eq!(p.0.position, p.1.position, "{threads} threads");
        assert_eq!(p.0.velocity, p.1.velocity);
        assert_eq!(p.0.angular_velocity, p.1.angular_velocity);
        assert_eq!(a.ledger, b.ledger);
    }
}

/// Must-show 3: the LAMMPS data file that `pdamp settle` writes round-trips exactly and a bed
/// imported from it runs; the CSV beside it too.
#[test]
fn lammps_and_csv_beds_import_and_run() {
    let dir = tempdir("lammps_bed");
    let sc = Scenario::from_toml(&cube(CUBE_DROP, true)).expect("parse");
    settle_scenario(
        &sc,
        Path::new("."),
        &dir,
        &mut |_, _| {},
        &Default::default(),
    )
    .expect("settle");
    let text = std::fs::read_to_string(dir.join("bed.data")).unwrap();
    let names = vec!["steel".to_string()];
    let bed = pdamp_io::bed_formats::read_lammps_data(&text, &names).expect("read");
    let again =
        pdamp_io::bed_formats::write_lammps_data(&bed, &[7800.0], ([-0.02; 3], [0.02, 0.02, 0.04]));
    assert_eq!(
        pdamp_io::bed_formats::read_lammps_data(&again, &names).unwrap(),
        bed
    );
    let reference = &prepared_cube().world.particles;
    assert_eq!(bed.position_m, reference.position);
    assert_eq!(bed.velocity_m_s, reference.velocity);
    for (path, extra) in [
        ("bed.data", r#", type_materials = ["steel"]"#),
        ("bed.csv", ""),
    ] {
        let placement = format!(
            r#"{{ method = "file", path = "{}"{extra} }}"#,
            dir.join(path).display()
        );
        let imported = Scenario::from_toml(&cube(&placement, false)).expect("parse");
        imported.validate().expect("valid");
        let mut w = imported.build_world(Path::new(".")).expect(path);
        assert_eq!(w.particles.position, reference.position, "{path}");
        w.run_until(0.01, |_| {});
        w.check_health().expect("runs");
        // A settled bed stays at rest.
        assert!(
            w.ledger.kinetic_j / 1000.0 < 1e-8,
            "{path}: {}",
            w.ledger.kinetic_j
        );
    }
}

/// A bed that does not fit the scenario is refused, naming what differs.
#[test]
fn mismatched_bed_is_refused() {
    let dir = tempdir("bad_bed");
    let sc = Scenario::from_toml(&cube(CUBE_DROP, true)).expect("parse");
    settle_scenario(
        &sc,
        Path::new("."),
        &dir,
        &mut |_, _| {},
        &Default::default(),
    )
    .expect("settle");
    let file = format!(
        r#"{{ method = "file", path = "{}" }}"#,
        dir.join("bed.pdbed").display()
    );
    let wrong_count = cube(&file, false).replace("count = 1000", "count = 999");
    let e = Scenario::from_toml(&wrong_count)
        .unwrap()
        .build_world(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particles[0].count") && e.contains("has 1000"),
        "{e}"
    );
    let wrong_size = cube(&file, false).replace("radius_m = 1.75e-3", "radius_m = 1.5e-3");
    let e = Scenario::from_toml(&wrong_size)
        .unwrap()
        .build_world(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("particles[0].size") && e.contains("particle 0"),
        "{e}"
    );
    // A smaller container: the bed sticks out through a wall.
    let small = cube(&file, false).replace(
        "half_extents_m = [0.02, 0.02, 0.02]",
        "half_extents_m = [0.015, 0.02, 0.02]",
    );
    let e = Scenario::from_toml(&small)
        .unwrap()
        .build_world(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(e.contains("wall 'box'") && e.contains("particle"), "{e}");
    // Damaged file.
    let mut bytes = std::fs::read(dir.join("bed.pdbed")).unwrap();
    bytes[40] ^= 0xff;
    std::fs::write(dir.join("bed.pdbed"), &bytes).unwrap();
    let e = Scenario::from_toml(&cube(&file, false))
        .unwrap()
        .build_world(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(e.contains("damaged"), "{e}");
    // A drop-down that cannot fit.
    let full = cube(CUBE_DROP, true).replace("count = 1000", "count = 2500");
    let e = Scenario::from_toml(&full)
        .unwrap()
        .build_world(Path::new("."))
        .unwrap_err()
        .to_string();
    assert!(e.contains("more than a random packing holds"), "{e}");
}

fn tempdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("pdamp_test_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Two drop-down groups (a layer of large spheres, then small ones on top): the first group
/// settles further under the second, and the whole bed starts without overlap beyond contact.
#[test]
fn two_drop_down_groups_stack() {
    let two = cube(CUBE_DROP, true).replace(
        "[settle]",
        &format!(
            "[[particles]]\nmaterial = \"steel\"\ncount = 400\nsize = {{ type = \"monodisperse\", radius_m = 1.2e-3 }}\nplacement = {CUBE_DROP}\n[settle]"
        ),
    );
    let two = two.replace("count = 1000", "count = 300");
    let sc = Scenario::from_toml(&two).expect("parse");
    sc.validate().expect("valid");
    let bed = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default())
        .expect("two groups drop");
    assert_eq!(bed.world.particles.len(), 700);
    assert_eq!(bed.drop_down.len(), 2);
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");
    // The small spheres lie on the large ones on average.
    let p = &bed.world.particles;
    let mean_z = |r: f64| {
        let z: Vec<f64> = (0..p.len())
            .filter(|&i| p.radius[i] == r)
            .map(|i| p.position[i].z)
            .collect();
        z.iter().sum::<f64>() / z.len() as f64
    };
    assert!(
        mean_z(1.2e-3) > mean_z(1.75e-3),
        "{} {}",
        mean_z(1.2e-3),
        mean_z(1.75e-3)
    );
}

/// 58 spheres r = 5 mm in a 40 mm cube (D Sect. 8.1.1's cube: four diameters wide, n_max = 65,
/// clearance to the lid less than a diameter; μ = 0.1 as D Tab. 8.1), filled along −z.
fn cube58(placement: &str) -> String {
    cube(placement, true)
        .replace("count = 1000", "count = 58")
        .replace("radius_m = 1.75e-3", "radius_m = 5e-3")
        .replace("youngs_modulus_pa = 1e8", "youngs_modulus_pa = 1e9")
        .replace("friction_coefficient = 0.3", "friction_coefficient = 0.1")
}

/// Filling with the lid open (D L3085, L3093): the closed-container drop-down cannot fill D's
/// 58-sphere cube (each sphere must fit whole below the lid); poured into the container raised
/// by 20 mm, the bed stands above the real top, and closing the lid while tapping (50 Hz,
/// Γ = 2) presses it in. Every sphere ends inside the real cube, without overlap beyond contact
/// deformation, the lid closed, the bed a random packing (not the 4 × 4 × 4 lattice).
#[test]
fn open_lid_fills_a_cube_with_less_than_a_diameter_of_clearance() {
    let closed = Scenario::from_toml(&cube58(CUBE_DROP)).expect("parse");
    closed.validate().expect("valid");
    let Err(err) = prepare_bed(&closed, Path::new("."), &mut |_, _| {}, &Default::default()) else {
        panic!("the closed cube cannot be filled")
    };
    let err = err.to_string();
    assert!(err.contains("drop-down placed only"), "{err}");

    let open = format!(
        "{}, open_lid = {{ headroom_m = 0.02, tap_frequency_hz = 50.0, tap_intensity = 2.0 }} }}",
        CUBE_DROP.strip_suffix(" }").unwrap()
    );
    let sc = Scenario::from_toml(&cube58(&open)).expect("parse");
    sc.validate().expect("valid");
    let bed = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default())
        .expect("open-lid fill");
    let report = &bed.drop_down[0];
    eprintln!("open lid: {report:?}");
    let p = &bed.world.particles;
    assert_eq!(p.len(), 58);
    let above = report.bed_top_above_lid_m.expect("open lid reported");
    assert!(above > 0.0, "the poured bed stood above the top: {above}");
    assert!(report.lid_closing_time_s > 0.0);
    // Inside the real cube (the world has the container's own walls again).
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");
    let top = (0..p.len())
        .map(|i| p.position[i].z + p.radius[i])
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(top <= 0.04 + 1e-2 * 5e-3, "highest top {top}");
    // Not a lattice: the sphere heights do not fall on four levels.
    let levels = (0..p.len())
        .filter(|&i| {
            let z = (p.position[i].z - 5e-3) / 1e-2;
            (z - z.round()).abs() > 0.1
        })
        .count();
    assert!(levels > 10, "{levels} spheres off the lattice levels");
}

/// Open lid on a cylinder whose axis points down (its base disc is the lid), the bed below the
/// top after pouring: the lid closes at once; and the errors: a lid that is not a wall, and a
/// bed that cannot be pressed in without tapping.
#[test]
fn open_lid_cylinder_and_errors() {
    let can = |count: usize, open_lid: &str| {
        cylinder_with_rod("drop_down")
            .replace("count = 1000", &format!("count = {count}"))
            .replace(
                "base_center_m = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius_m = 0.02, length_m = 0.06 }}",
                "base_center_m = [0.0, 0.0, 0.06], axis = [0.0, 0.0, -1.0], radius_m = 0.02, length_m = 0.06 }",
            )
            .replace(
                "base_center_m = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius_m = 0.02, length_m = 0.06 } }",
                &format!("base_center_m = [0.0, 0.0, 0.06], axis = [0.0, 0.0, -1.0], radius_m = 0.02, length_m = 0.06 }}{open_lid} }}"),
            )
    };
    let text = can(300, ", open_lid = { headroom_m = 0.01 }");
    assert!(text.contains("open_lid"), "{text}");
    let sc = Scenario::from_toml(&text).expect("parse");
    sc.validate().expect("valid");
    let bed = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default())
        .expect("open-lid fill");
    let report = &bed.drop_down[0];
    assert!(report.bed_top_above_lid_m.unwrap() < 0.0, "{report:?}");
    assert_eq!(bed.world.particles.len(), 300);
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");

    // The region's top 15 mm below the can's, beyond the 10 mm headroom: no wall closes the
    // container there. (5 mm below, the can's top would be raised with the lid.)
    let low = can(300, ", open_lid = { headroom_m = 0.01 }").replace(
        "base_center_m = [0.0, 0.0, 0.06], axis = [0.0, 0.0, -1.0], radius_m = 0.02, length_m = 0.06 }, open_lid",
        "base_center_m = [0.0, 0.0, 0.045], axis = [0.0, 0.0, -1.0], radius_m = 0.02, length_m = 0.045 }, open_lid",
    );
    let sc = Scenario::from_toml(&low).expect("parse");
    let Err(err) = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()) else {
        panic!("no lid wall")
    };
    let err = err.to_string();
    assert!(err.contains("no wall ends at the region's top"), "{err}");

    // Too many spheres to press in without tapping in 20 ms.
    let full = can(
        3000,
        ", open_lid = { headroom_m = 0.03, max_close_duration_s = 0.02 }",
    );
    let sc = Scenario::from_toml(&full).expect("parse");
    let Err(err) = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()) else {
        panic!("the lid cannot close")
    };
    let err = err.to_string();
    assert!(
        err.contains("the lid is still") && err.contains("held up by particle"),
        "{err}"
    );

    // Keys belong to drop_down and are checked.
    let bad = can(
        300,
        ", open_lid = { headroom_m = 0.01, tap_intensity = 2.0 }",
    );
    let err = Scenario::from_toml(&bad).unwrap().validate().unwrap_err();
    assert!(
        err.to_string()
            .contains("tap_frequency_hz and tap_intensity together"),
        "{err}"
    );
}

/// Pouring from an inlet (D Fig. 2.2c): the 1 000 spheres enter through a 16 × 16 × 7 mm inlet
/// under the lid at 2 000 per second and pile up below it; all are in after 0.5–0.7 s (the rate,
/// then the heap under the inlet slows the last ones: 0.62 s), without overlap beyond contact,
/// as a random packing. An inlet the pile reaches is reported.
#[test]
fn pouring_from_an_inlet() {
    let inlet = format!(
        "{}, inlet = {{ region = {{ type = \"box\", min_m = [-0.008, -0.008, 0.032], max_m = [0.008, 0.008, 0.039] }}, rate_per_s = 2000.0, velocity_m_s = [0.0, 0.0, -0.3] }} }}",
        CUBE_DROP.strip_suffix(" }").unwrap()
    );
    let sc = Scenario::from_toml(&cube(&inlet, true)).expect("parse");
    sc.validate().expect("valid");
    let bed = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()).expect("pour");
    let report = &bed.drop_down[0];
    eprintln!("inlet: {report:?}");
    assert_eq!(bed.world.particles.len(), 1000);
    assert!(
        (0.4995..0.7).contains(&report.inlet_pour_time_s),
        "{}",
        report.inlet_pour_time_s
    );
    let (pp, pw) = max_overlaps(&bed.world);
    assert!(pp < 1e-2 && pw < 1e-2, "overlaps {pp} {pw}");
    let s = bed_statistics(&bed.world, Some(Vec3::z()));
    assert!(
        (0.55..=0.64).contains(&s.packing_fraction_bulk),
        "bulk packing fraction {}",
        s.packing_fraction_bulk
    );

    let low = inlet.replace(
        "0.032], max_m = [0.008, 0.008, 0.039]",
        "0.0], max_m = [0.008, 0.008, 0.006]",
    );
    let sc = Scenario::from_toml(&cube(&low, true)).expect("parse");
    let Err(err) = prepare_bed(&sc, Path::new("."), &mut |_, _| {}, &Default::default()) else {
        panic!("the pile blocks an inlet at the floor")
    };
    let err = err.to_string();
    assert!(
        err.contains("drop-down from the inlet placed only"),
        "{err}"
    );
    // The keys are checked.
    let bad = inlet.replace("rate_per_s = 2000.0", "rate_per_s = -1.0");
    let err = Scenario::from_toml(&cube(&bad, true))
        .unwrap()
        .validate()
        .unwrap_err();
    assert!(err.to_string().contains("inlet.rate_per_s"), "{err}");
}
