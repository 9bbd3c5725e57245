//! Approach 1 plumbing: a heavy sphere clamped (preloaded elastic Hertz contacts, no gravity)
//! in a box carried by a single-mode structure must act as a rigidly added mass, i.e. the free
//! vibration runs at $f = f_0\sqrt{M/(M+m_p)}$ with the structural damping ratio only
//! (elastic contacts dissipate nothing). Checks the displacement transfer structure → container,
//! the force transfer container → structure and their sign.

use pdamp_dem::walls::BoxInside;
use pdamp_dem::{
    BodyState, ContactModel, Geometry, Material, Motion, NormalLaw, RigidBody, Vec3, World,
};
use pdamp_design::Damper;
use pdamp_structure::dem::{DemCoupling, run_dem_free};
use pdamp_structure::free::{self, FreeVibrationSpec, UpdateRule};
use pdamp_structure::modal::ModalStructure;
use std::f64::consts::{PI, TAU};

#[test]
fn clamped_particle_is_an_added_mass() {
    let (damper, m_p) = clamped(0.02);
    let (mass, f0, zeta) = (1.0, 5.0, 0.01);
    let k = mass * (TAU * f0).powi(2);
    let s = ModalStructure::single_mode(mass, k, 2.0 * zeta * (k * mass).sqrt());
    let spec = FreeVibrationSpec {
        duration_s: 2.0,
        time_step_s: 5e-5,
        mode: 0,
        initial_point: "damper".into(),
        initial_displacement_m: 0.01,
        initial_velocity_m_s: 0.0,
        output_point: "damper".into(),
        update: UpdateRule::Never,
        sample_every: 1,
        scale_initial_by_bed_mass: false,
    };
    let h = run_dem_free(
        &s,
        &damper,
        "damper",
        &spec,
        &DemCoupling::default(),
        &mut |_| {},
        None,
    )
    .unwrap();
    let peaks = free::decay_peaks(&h, 0.1).unwrap();
    let cyc = free::damping_per_cycle(&peaks);
    let f_exp = f0 * (mass / (mass + m_p)).sqrt();
    // ζ with the added mass: D/(2√(K(M+m)))
    let z_exp = zeta * (mass / (mass + m_p)).sqrt();
    let f_mean = cyc.iter().map(|c| c.frequency_hz).sum::<f64>() / cyc.len() as f64;
    let z_mean = cyc.iter().map(|c| c.damping_ratio).sum::<f64>() / cyc.len() as f64;
    println!(
        "m_p = {m_p:.4} kg: f = {f_mean:.4} Hz (expected {f_exp:.4}, bare {f0}), ζ = {z_mean:.5} (expected {z_exp:.5})"
    );
    assert!(cyc.len() >= 6);
    assert!((f_mean - f_exp).abs() / f_exp < 0.005);
    assert!((z_mean - z_exp).abs() / z_exp < 0.05);
}

/// A sphere of radius `r` clamped in a box with 0.1 mm preload on each of the six faces
/// (elastic Hertz contacts, no gravity): a rigidly added mass. Returns the damper and the
/// sphere's mass.
fn clamped(r: f64) -> (Damper, f64) {
    let rho = 7850.0;
    let soft = Material::new("soft", rho, 1e8, 0.3);
    let model = ContactModel {
        normal: NormalLaw::Hertz,
        friction: Default::default(),
        rolling: None,
        adhesion: None,
    };
    let mut w = World::new(vec![soft], model, 5e-5);
    w.gravity_m_s2 = Vec3::zeros();
    w.add_particle(Vec3::zeros(), r, 0);
    let h = r - 1e-4;
    let body = RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
        "box",
        Geometry::BoxInside(BoxInside::new(Vec3::zeros(), Vec3::new(h, h, h))),
        0,
    );
    w.add_body(body);
    (
        Damper::from_world(w, 0, Vec3::new(1.0, 0.0, 0.0), 0.0, 1, 0),
        rho * 4.0 / 3.0 * PI * r.powi(3),
    )
}

/// Several DEM beds in one coupled run (one per container): two clamped spheres at two points
/// of one mode (φ = 1 and 0.6, unit modal mass, no structural damping) add the modal mass
/// m₁φ₁² + m₂φ₂², so the mode runs at f₀/√(1 + m₁φ₁² + m₂φ₂²) (0.5 %), and the structure's
/// and the beds' energies sum to a constant (elastic contacts; 1e-4 of the initial energy).
/// A second bed at a node of the mode (φ = 0) leaves the single-bed run unchanged bit for bit.
#[test]
fn two_beds_add_their_modal_masses() {
    use pdamp_structure::dem::{DemBed, run_dem_free_beds};
    use pdamp_structure::modal::{ModalPoint, Mode};
    let (f0, x0) = (5.0, 0.01);
    let s = ModalStructure {
        modes: vec![Mode {
            frequency_hz: f0,
            damping_ratio: 0.0,
        }],
        points: [("a", 1.0), ("b", 0.6), ("node", 0.0)]
            .iter()
            .map(|(n, v)| ModalPoint {
                name: n.to_string(),
                shape: vec![*v],
            })
            .collect(),
    };
    let spec = FreeVibrationSpec {
        duration_s: 2.0,
        time_step_s: 5e-5,
        mode: 0,
        initial_point: "a".into(),
        initial_displacement_m: x0,
        initial_velocity_m_s: 0.0,
        output_point: "a".into(),
        update: UpdateRule::Never,
        sample_every: 1,
        scale_initial_by_bed_mass: false,
    };
    let ((d1, m1), (d2, m2)) = (clamped(0.02), clamped(0.015));
    let o = DemCoupling::default();
    let bed = |damper, point| DemBed {
        damper,
        point,
        coupling: &o,
    };
    let (h, e) = run_dem_free_beds(
        &s,
        &[bed(&d1, "a"), bed(&d2, "b")],
        &spec,
        &mut |_| {},
        None,
    )
    .unwrap();
    let cyc = free::damping_per_cycle(&free::decay_peaks(&h, 0.1).unwrap());
    let f_mean = cyc.iter().map(|c| c.frequency_hz).sum::<f64>() / cyc.len() as f64;
    let f_exp = f0 / (1.0 + m1 + m2 * 0.36).sqrt();
    assert!(cyc.len() >= 6);
    assert!((f_mean / f_exp - 1.0).abs() < 0.005, "{f_mean} vs {f_exp}");
    let e0 = 0.5 * (TAU * f0).powi(2) * x0 * x0;
    let drift = e.structure_energy_change_j + e.bed_energy_change_j;
    assert!(drift.abs() < 1e-4 * e0, "{e:?} against {e0} J");
    // a bed at a node: the single-bed run, bit for bit
    let (one, _) = run_dem_free_beds(&s, &[bed(&d1, "a")], &spec, &mut |_| {}, None).unwrap();
    let (two, _) = run_dem_free_beds(
        &s,
        &[bed(&d1, "a"), bed(&d2, "node")],
        &spec,
        &mut |_| {},
        None,
    )
    .unwrap();
    assert_eq!(one.displacement_m, two.displacement_m);
    // beds that do not share a time step are refused, naming the bed
    let (mut d3, _) = clamped(0.01);
    d3.time_step_s *= 0.5;
    let err = run_dem_free_beds(
        &s,
        &[bed(&d1, "a"), bed(&d3, "b")],
        &spec,
        &mut |_| {},
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("DEM bed 2 at 'b'"), "{err}");
}
