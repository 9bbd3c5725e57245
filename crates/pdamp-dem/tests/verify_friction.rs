//! A sphere on an incline: rolling without slip below the slip angle, sliding above it
//! (tan θ > 7/2 μ for a solid sphere).

use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::walls::{Geometry, Plane};
use pdamp_dem::{BodyState, Material, Motion, RigidBody, Vec3, World};

const G: f64 = 9.81;

/// Acceleration along the incline (x after rotating gravity by θ about y), measured from the
/// velocity change between 20 ms and 120 ms.
fn incline_acceleration(theta_deg: f64, friction: FrictionLaw) -> (f64, f64) {
    let th = theta_deg.to_radians();
    let model = ContactModel {
        normal: NormalLaw::Gonthier {
            restitution: 0.5,
            min_impact_velocity_m_s: 1e-3,
        },
        friction,
        rolling: None,
        adhesion: None,
    };
    let r = 5e-3;
    let mut w = World::new(vec![Material::new("steel", 7800.0, 2e9, 0.3)], model, 2e-6);
    w.gravity_m_s2 = Vec3::new(G * th.sin(), 0.0, -G * th.cos());
    w.add_body(
        RigidBody::new("incline", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "plane",
            Geometry::Plane(Plane::new(Vec3::zeros(), Vec3::z(), false)),
            0,
        ),
    );
    w.add_particle(Vec3::new(0.0, 0.0, r), r, 0);
    w.run_until(0.02, |_| {});
    let (v0, w0) = (w.particles.velocity[0].x, w.particles.angular_velocity[0].y);
    let t0 = w.time_s;
    w.run_until(0.12, |_| {});
    let a = (w.particles.velocity[0].x - v0) / (w.time_s - t0);
    let alpha = (w.particles.angular_velocity[0].y - w0) / (w.time_s - t0);
    (a, alpha * r)
}

#[test]
fn rolling_without_slip_below_slip_angle() {
    for friction in [
        FrictionLaw::Mindlin {
            friction_coefficient: 0.3,
        },
        FrictionLaw::CoulombSpring {
            friction_coefficient: 0.3,
            stiffness_ratio: None,
            damping_ratio: 1.0,
        },
    ] {
        let (a, a_roll) = incline_acceleration(20.0, friction.clone());
        let expect = 5.0 / 7.0 * G * 20f64.to_radians().sin();
        eprintln!(
            "{friction:?}: a = {a:.5} m/s², 5/7 g sinθ = {expect:.5}, rolling a = {a_roll:.5}"
        );
        assert!(
            (a / expect - 1.0).abs() < 0.01,
            "{friction:?}: a = {a}, expected {expect}"
        );
        assert!(
            (a_roll / a - 1.0).abs() < 0.01,
            "no slip: ω̇ r = {a_roll} vs a = {a}"
        );
    }
}

#[test]
fn sliding_above_slip_angle() {
    let mu = 0.3;
    let th = 60f64.to_radians();
    let expect = G * (th.sin() - mu * th.cos());
    for friction in [
        FrictionLaw::Mindlin {
            friction_coefficient: mu,
        },
        FrictionLaw::CoulombSpring {
            friction_coefficient: mu,
            stiffness_ratio: None,
            damping_ratio: 1.0,
        },
        FrictionLaw::RegularizedSliding {
            friction_coefficient: mu,
            regularization_s_m: 1e4,
        },
    ] {
        let (a, _) = incline_acceleration(60.0, friction.clone());
        eprintln!("{friction:?}: a = {a:.5} m/s², g(sinθ − μ cosθ) = {expect:.5}");
        assert!(
            (a / expect - 1.0).abs() < 0.01,
            "{friction:?}: a = {a}, expected {expect}"
        );
    }
}
