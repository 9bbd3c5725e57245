//! A solid cuboid (`box_outside`) inside a container acts as an inner structure
//! [D Sect. 8.1.4]: a sphere dropped on it comes to rest on its top face, one dropped beside it
//! falls past it to the container floor.

use pdamp_scenario::schema::Scenario;

const TOML: &str = r#"
title = "plate inside a box"
[simulation]
duration_s = 0.0
time_step_s = 2e-6
gravity_m_s2 = [0.0, 0.0, -9.81]
[[materials]]
name = "steel"
density_kg_m3 = 7800.0
youngs_modulus_pa = 2e9
poisson_ratio = 0.3
[contact]
normal = { law = "hertz-mindlin", restitution = 0.3 }
friction = { law = "mindlin", friction_coefficient = 0.3 }
[[bodies]]
name = "container"
[[bodies.walls]]
name = "box"
material = "steel"
geometry = { type = "box_inside", center_m = [0.0, 0.0, 0.02], half_extents_m = [0.02, 0.02, 0.02] }
[[bodies.walls]]
name = "plate"
material = "steel"
geometry = { type = "box_outside", center_m = [-0.01, 0.0, 0.01], half_extents_m = [0.008, 0.015, 0.0025] }
[[particles]]
material = "steel"
count = 1
size = { type = "monodisperse", radius_m = 1e-3 }
placement = { method = "grid", region = { type = "box", min_m = [-0.011, -0.001, 0.025], max_m = [-0.009, 0.001, 0.027] } }
[[particles]]
material = "steel"
count = 1
size = { type = "monodisperse", radius_m = 1e-3 }
placement = { method = "grid", region = { type = "box", min_m = [0.009, -0.001, 0.025], max_m = [0.011, 0.001, 0.027] } }
"#;

#[test]
fn sphere_rests_on_solid_cuboid() {
    let sc = Scenario::from_toml(TOML).expect("parse");
    sc.validate().expect("valid");
    let mut w = sc.build_world(std::path::Path::new(".")).expect("world");
    w.run_until(0.15, |_| {});
    let r = 1e-3;
    let on_plate = w.particles.position[0].z;
    let on_floor = w.particles.position[1].z;
    let top = 0.01 + 0.0025;
    eprintln!(
        "on plate z = {on_plate:.6e} (top + r = {:.6e}), on floor z = {on_floor:.6e}",
        top + r
    );
    assert!((on_plate - (top + r)).abs() < 0.02 * r, "{on_plate}");
    assert!((on_floor - r).abs() < 0.02 * r, "{on_floor}");
    assert!(
        w.ledger.kinetic_j < 1e-9,
        "not at rest: {}",
        w.ledger.kinetic_j
    );
}
