//! Gear PC5 with the step-size controller of [D Sect. 2.5.2]:
//! - free flight is integrated exactly (a parabola is a polynomial of the predictor) and the
//!   controller grows the step to Δt_max;
//! - a sphere dropped on a floor rebounds with Gonthier's restitution [D Eq. 2.78/2.79] using the
//!   established parameters of [D Tab. 2.3];
//! - a bed of 1 000 particles settles to the packing height that velocity Verlet gives, and its
//!   energy balance closes.

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::walls::{Geometry, Plane};
use pdamp_dem::{BodyState, GearParams, Integrator, Material, Motion, RigidBody, Vec3, World};

fn gonthier(e: f64, mu: f64) -> ContactModel {
    ContactModel {
        normal: NormalLaw::Gonthier {
            restitution: e,
            min_impact_velocity_m_s: 1e-2,
        },
        friction: if mu > 0.0 {
            FrictionLaw::RegularizedSliding {
                friction_coefficient: mu,
                regularization_s_m: 1000.0,
            }
        } else {
            FrictionLaw::Frictionless
        },
        rolling: None,
        adhesion: None,
    }
}

fn floor_world(model: ContactModel, z0: f64, v0: Vec3) -> World {
    let mut w = World::new(
        vec![Material::new("steel", 7850.0, 210e9, 0.3)],
        model,
        1e-6,
    );
    w.add_body(
        RigidBody::new("floor", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "floor",
            Geometry::Plane(Plane::new(Vec3::zeros(), Vec3::z(), false)),
            0,
        ),
    );
    let i = w.add_particle(Vec3::new(0.0, 0.0, z0), 5e-3, 0);
    w.particles.velocity[i] = v0;
    w.integrator = Integrator::Gear(GearParams::default());
    w
}

/// Free flight: x(t) = x0 + v0 t + g t²/2 reproduced to round-off; the step grows to Δt_max.
#[test]
fn free_flight_is_exact_and_step_grows() {
    let v0 = Vec3::new(0.3, -0.2, 2.0);
    let z0 = 0.5;
    let mut w = floor_world(gonthier(0.8, 0.0), z0, v0);
    w.run_until(0.02, |_| {});
    let t = w.time_s;
    let expect = Vec3::new(0.0, 0.0, z0) + v0 * t + w.gravity_m_s2 * (0.5 * t * t);
    let err = (w.particles.position[0] - expect).norm();
    eprintln!(
        "free flight: t {t:.6} s, steps {}, rejected {}, final dt {:.3e} s, position error {err:.3e} m",
        w.counters.steps, w.counters.rejected_steps, w.dt_s
    );
    assert!(err < 1e-12, "position error {err:e} m");
    assert_eq!(w.counters.rejected_steps, 0);
    let dt_max = w.gear_default_dt_max_s();
    assert!(
        (w.dt_s / dt_max - 1.0).abs() < 1e-12,
        "step {:e} s did not grow to Δt_max {dt_max:e} s",
        w.dt_s
    );
}

/// Drop on a floor: rebound speed / impact speed equals Gonthier's ε within 0.5 %, with the
/// default tolerances of [D Tab. 2.3].
#[test]
fn bounce_restitution_matches_gonthier() {
    for e in [0.5, 0.8, 0.95] {
        let v_in = 1.0;
        let r = 5e-3;
        let mut w = floor_world(gonthier(e, 0.0), r + 1e-4, Vec3::new(0.0, 0.0, -v_in));
        let mut v_out: f64 = 0.0;
        let mut touched = false;
        w.run_until(5e-3, |w| {
            let z = w.particles.position[0].z;
            if z < r {
                touched = true;
            }
            if touched && z > r && v_out == 0.0 {
                v_out = w.particles.velocity[0].z;
            }
        });
        // Gravity acts over the 0.1 mm approach and the contact (~1e-4 s): < 0.2 % of v_in.
        let approach_v = (v_in * v_in + 2.0 * 9.81 * 1e-4).sqrt();
        let measured = v_out / approach_v;
        eprintln!(
            "ε = {e}: measured {measured:.5}, steps {}, rejected {}, evaluations {}",
            w.counters.steps, w.counters.rejected_steps, w.counters.force_evaluations
        );
        assert!(touched && v_out > 0.0, "no rebound for ε = {e}");
        assert!(
            (measured / e - 1.0).abs() < 5e-3,
            "ε = {e}: measured restitution {measured}"
        );
    }
}

/// Must-show of the DEM core issue: 1 000 particles stacked in a close packing with 2 % gaps drop
/// and settle in a box; Gear (step control, [D Tab. 2.3] parameters except τ = 1e-3) and
/// velocity Verlet reach the same packing height within 1 %.
#[test]
fn gear_and_verlet_settle_1000_particles_to_same_height() {
    let mut heights = Vec::new();
    for gear in [false, true] {
        let model = gonthier(0.5, 0.3);
        let mut w = tight_box_world(1000, 1e-3, 0.016, 0.04, model.clone(), 1e-5);
        w.materials[0].youngs_modulus_pa = 2e7;
        w.interactions = pdamp_dem::interaction::InteractionTable::new(&w.materials, model);
        if gear {
            w.integrator = Integrator::Gear(GearParams {
                tolerance_abs: 1e-3,
                tolerance_rel: 1e-3,
                ..Default::default()
            });
        }
        let h0 = bed_height(&w);
        w.run_until(0.1, |_| {});
        eprintln!(
            "gear={gear}: steps {}, rejected {}, force evaluations {}, height {:.6e} m (initial {h0:.6e} m), \
             KE {:.3e} J, dissipated {:.4e} J",
            w.counters.steps,
            w.counters.rejected_steps,
            w.counters.force_evaluations,
            bed_height(&w),
            w.ledger.kinetic_j,
            w.ledger.dissipated_j()
        );
        assert!(
            w.ledger.kinetic_j < 1e-3 * w.ledger.dissipated_j(),
            "bed not settled"
        );
        // Verlet's contact work uses the step's mean velocity and closes to round-off level;
        // Gear evaluates the contact power with end-of-step velocities before the last correction,
        // which leaves a balance error of the order of its tolerance.
        let closure = w.ledger.closure_error_j().abs() / w.ledger.dissipated_j();
        eprintln!("closure error / dissipated {closure:.2e}");
        let limit = if gear { 2e-2 } else { 1e-3 };
        assert!(closure < limit, "energy closure {closure:e}");
        heights.push(bed_height(&w));
    }
    assert!(
        (heights[1] / heights[0] - 1.0).abs() < 0.01,
        "heights {heights:?}"
    );
}
