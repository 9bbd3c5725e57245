//! Damper-position study (D Sect. 8.2.3, Fig. 8.27) on a pinned–pinned steel beam with a
//! constant-η̄ damper (approach 3): the added damping vanishes at a node of a mode (mode 2 at
//! midspan: < 1e-6 of its maximum) and is largest at the antinodes (mode 1 at midspan, mode 2
//! at a quarter span, within one element); at midspan the slope of mode 1 is zero.

use pdamp_structure::position_study::{PositionResult, PositionStudySpec, position_study};
use pdamp_structure::scenario::CoupleScenario;

const SCENARIO: &str = r#"
[structure]
n_modes = 3
[structure.beam]
length_m = 1.0
elements = 40
youngs_modulus_pa = 210e9
poisson_ratio = 0.3
density_kg_m3 = 7850.0
width_m = 0.02
height_m = 0.01
timoshenko = false
supports = [{ position_m = 0.0, kind = "pinned" }, { position_m = 1.0, kind = "pinned" }]
[structure.damping]
ratio = 0.001
[[structure.points]]
name = "damper"
position_m = 0.5
[[structure.points]]
name = "excitation"
position_m = 0.1

[[dampers]]
model = "constant"
point = "damper"
bed_mass_kg = 0.05
effective_loss_factor = 0.5
effective_mass_ratio = 0.8

[analysis]
kind = "steady_state"
start_hz = 10.0
end_hz = 30.0
force_amplitude_n = 1.0
excitation_point = "excitation"
output_point = "damper"
"#;

#[test]
fn node_gives_no_added_damping_antinode_the_most() {
    let scn: CoupleScenario = toml::from_str(SCENARIO).unwrap();
    let structure = scn.structure.clone().unwrap();
    let spec = PositionStudySpec {
        positions_m: None,
        start_m: Some(0.0),
        end_m: Some(1.0),
        count: Some(41),
        move_mass_at_m: None,
    };
    let res = position_study(&scn, &structure, std::path::Path::new("."), &spec).unwrap();
    assert_eq!(res.len(), 41 * 3);
    let mode = |k: usize| -> Vec<_> { res.iter().filter(|r| r.mode == k).collect() };
    let argmax = |v: &[&PositionResult]| {
        v.iter()
            .max_by(|a, b| a.added_damping_ratio.total_cmp(&b.added_damping_ratio))
            .map(|r| (r.position_m, r.added_damping_ratio))
            .unwrap()
    };
    fn at<'a>(v: &[&'a PositionResult], x: f64) -> &'a PositionResult {
        v.iter().find(|r| (r.position_m - x).abs() < 1e-9).unwrap()
    }
    let (m1, m2) = (mode(1), mode(2));
    let (x1, z1) = argmax(&m1);
    let (x2, z2) = argmax(&m2);
    let mid2 = at(&m2, 0.5);
    println!(
        "mode 1: max added ζ {z1:.5} at {x1} m (slope there {:.2e}); mode 2: max {z2:.5} at {x2} m, at midspan {:.2e} (φ = {:.2e})",
        at(&m1, 0.5).slope_rad_per_m_sqrt_kg,
        mid2.added_damping_ratio,
        mid2.phi_damper_per_sqrt_kg
    );
    assert!((x1 - 0.5).abs() <= 0.025);
    assert!((x2 - 0.25).abs() <= 0.025 || (x2 - 0.75).abs() <= 0.025);
    assert!(mid2.added_damping_ratio.abs() < 1e-6 * z2);
    assert!(at(&m1, 0.5).slope_rad_per_m_sqrt_kg.abs() < 1e-9);
    // at the supports (nodes of every mode) nothing is added
    assert!(at(&m1, 0.0).added_damping_ratio.abs() < 1e-9);
    assert!(z1 > 0.0 && z2 > 0.0);
}
