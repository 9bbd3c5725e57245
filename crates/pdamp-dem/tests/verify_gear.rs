//! Gear PC5 with step control [D Sect. 2.5.2] and velocity Verlet settle a bed of 1 000
//! particles to the same packing height.

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::{GearParams, Integrator};

#[test]
fn gear_and_verlet_settle_to_same_height() {
    let model = ContactModel {
        normal: NormalLaw::Gonthier {
            restitution: 0.5,
            min_impact_velocity_m_s: 1e-2,
        },
        friction: FrictionLaw::RegularizedSliding {
            friction_coefficient: 0.3,
            regularization_s_m: 1000.0,
        },
        rolling: None,
        adhesion: None,
    };
    let mut heights = Vec::new();
    for gear in [false, true] {
        let mut w = box_world(1000, 1e-3, 0.02, 0.06, model.clone(), 2e-6, false, 5);
        // softer particles keep the test fast
        w.materials[0].youngs_modulus_pa = 2e7;
        w.interactions = pdamp_dem::interaction::InteractionTable::new(&w.materials, model.clone());
        w.dt_s = 1e-5;
        if gear {
            w.integrator = Integrator::Gear(GearParams {
                tolerance_abs: 1e-3,
                tolerance_rel: 1e-3,
                ..Default::default()
            });
        }
        w.run_until(0.3, |_| {});
        eprintln!(
            "gear={gear}: steps {}, rejected {}, force evaluations {}, height {:.5e} m, KE {:.3e} J",
            w.counters.steps,
            w.counters.rejected_steps,
            w.counters.force_evaluations,
            bed_height(&w),
            w.ledger.kinetic_j
        );
        heights.push(bed_height(&w));
    }
    assert!(
        (heights[1] / heights[0] - 1.0).abs() < 0.01,
        "heights {heights:?}"
    );
}
