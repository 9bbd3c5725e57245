//! Energy conservation and the energy ledger.

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::{HarmonicTranslation, Motion, Vec3};
use std::sync::Arc;

/// An elastic (ε = 1, μ = 0) gas of 1 000 particles in a closed box keeps its total energy
/// (kinetic + elastic) within 1e-4 relative over 100 000 velocity-Verlet steps.
#[test]
fn elastic_gas_conserves_energy() {
    let model = ContactModel {
        normal: NormalLaw::Hertz,
        friction: FrictionLaw::Frictionless,
        rolling: None,
        adhesion: None,
    };
    let r = 1e-3;
    let mut w = box_world(1000, r, 0.04, 0.04, model, 1e-6, false, 3);
    w.gravity_m_s2 = Vec3::zeros();
    randomize_velocities(&mut w, 0.5, 4);
    // Contact time at 1 m/s is about 38 µs: 1 µs resolves every contact with > 35 steps.
    assert!(w.min_contact_time_s(1.0) > 30.0 * w.dt_s);
    w.initialize();
    let e0 = w.ledger.total_mechanical_j();
    let mut worst: f64 = 0.0;
    for s in 0..100_000 {
        w.step();
        if s % 100 == 0 {
            worst = worst.max((w.ledger.total_mechanical_j() / e0 - 1.0).abs());
        }
    }
    worst = worst.max((w.ledger.total_mechanical_j() / e0 - 1.0).abs());
    eprintln!(
        "elastic gas: largest relative energy error {worst:.2e}, contacts built {}",
        w.counters.neighbor_builds
    );
    assert!(worst < 1e-4, "relative energy error {worst:.3e}");
    // The ledger sees no dissipation beyond integration noise.
    assert!(w.ledger.dissipated_j().abs() < 1e-4 * e0);
}

/// The ledger of a dissipative shaken bed closes:
/// wall work = ΔE_kin + ΔE_pot + ΔE_el + dissipated, within 1e-3 of the wall work.
#[test]
fn shaken_bed_ledger_closes() {
    let r = 1e-3;
    let mut w = tight_box_world(400, r, 0.02, 0.03, hertz_mindlin(0.6, 0.3), 2e-6);
    // settle briefly with the box at rest
    w.run_until(0.02, |_| {});
    w.bodies[0].motion = Motion::Prescribed(Arc::new(HarmonicTranslation {
        direction: [1.0, 0.0, 0.2],
        amplitude_m: 0.002,
        frequency_hz: 20.0,
        phase_rad: 0.0,
    }));
    w.restart_clock();
    w.run_until(0.1, |_| {});
    let l = w.ledger;
    eprintln!(
        "shaken bed ledger: {l:?}\nclosure error {:.3e} J of wall work {:.3e} J",
        l.closure_error_j(),
        l.wall_work_j
    );
    assert!(l.wall_work_j > 0.0);
    assert!(l.dissipated_normal_pp_j > 0.0 && l.dissipated_normal_pw_j > 0.0);
    assert!(l.dissipated_tangential_pp_j > 0.0 && l.dissipated_tangential_pw_j > 0.0);
    assert!(
        l.closure_error_j().abs() < 1e-3 * l.wall_work_j,
        "closure {:.3e} vs wall work {:.3e}",
        l.closure_error_j(),
        l.wall_work_j
    );
}
