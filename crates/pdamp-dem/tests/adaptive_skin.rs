//! An adaptive neighbour-list skin (`World::set_adaptive_skin`) changes how often the list is
//! built, not the contacts: a falling, bouncing bed of one force block (600 spheres) gives the
//! same bits as with the fixed skin (Hertz–Mindlin through the block kernel, and the powder's
//! linear spring with a Coulomb spring through the general pipeline; plane box and
//! triangle-mesh box; 1 and 2 threads), with far fewer builds. (With several blocks the pair
//! pass groups its sums by the listed pair count, so larger beds agree to round-off only.)

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::{AdaptiveSkin, World};

/// The powder's law of the DEM–FEM paper (P Table A.2): linear spring–dashpot, Coulomb spring.
fn linear_coulomb() -> ContactModel {
    ContactModel {
        normal: NormalLaw::Linear {
            stiffness_n_m: 5642.0,
            restitution: 0.4,
            clip_attractive: true,
        },
        friction: FrictionLaw::CoulombSpring {
            friction_coefficient: 0.4,
            stiffness_ratio: Some(0.7),
            damping_ratio: 1.0,
        },
        rolling: None,
        adhesion: None,
    }
}

/// 600 spheres of 1 mm radius scattered in a 30 mm × 30 mm × 120 mm box, thrown at up to
/// `v_m_s` and falling onto the floor.
fn falling(model: ContactModel, dt: f64, mesh: bool, v_m_s: f64) -> World {
    let mut w = box_world(600, 1e-3, 0.03, 0.12, model, dt, mesh, 11);
    randomize_velocities(&mut w, v_m_s, 5);
    w
}

#[test]
fn adaptive_skin_keeps_the_trajectory_and_saves_builds() {
    // (law, time step, mesh box, throw speed): with the fixed skin (0.2 mm) the list lasts
    // ≈ 10 steps at the start
    let cases = [
        (
            "Hertz–Mindlin, planes",
            hertz_mindlin(0.6, 0.4),
            2e-6,
            false,
            5.0,
        ),
        (
            "linear + Coulomb spring, mesh",
            linear_coulomb(),
            5e-6,
            true,
            2.0,
        ),
    ];
    for (name, model, dt, mesh, v) in cases {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut fixed = falling(model.clone(), dt, mesh, v);
                let mut adaptive = falling(model.clone(), dt, mesh, v);
                fixed.initialize();
                let skin = AdaptiveSkin {
                    steps: 40.0,
                    ..adaptive.default_adaptive_skin()
                };
                adaptive.set_adaptive_skin(Some(skin));
                adaptive.initialize();
                let steps = (0.06 / dt).round() as usize;
                for _ in 0..steps {
                    fixed.step();
                    adaptive.step();
                }
                let what = format!("{name}, {threads} thread(s)");
                // the bed has landed: contacts, wall work and dissipation are all exercised
                assert!(fixed.ledger.dissipated_j() > 0.0, "{what}");
                assert_same_bits(&fixed, &adaptive, &what);
                let (bf, ba) = (
                    fixed.counters.neighbor_builds,
                    adaptive.counters.neighbor_builds,
                );
                assert!(2 * ba < bf, "{what}: builds {ba} adaptive vs {bf} fixed");
                // back to rest: the adaptive skin returns to its smallest value
                assert!(adaptive.skin_m() >= skin.min_m && adaptive.skin_m() <= skin.max_m);
            });
        }
    }
}

#[test]
fn adaptive_skin_follows_the_fastest_particle_within_its_bounds() {
    let a = AdaptiveSkin {
        min_m: 1e-4,
        max_m: 4e-4,
        steps: 20.0,
    };
    // 2 v Δt n: 2 × 2 m/s × 2.5 µs × 20 = 2e-4 m
    assert!((a.skin_m(2.0, 2.5e-6) - 2e-4).abs() < 1e-18);
    assert_eq!(a.skin_m(0.0, 2.5e-6), 1e-4);
    assert_eq!(a.skin_m(100.0, 2.5e-6), 4e-4);
    assert_eq!(a.skin_m(f64::NAN, 2.5e-6), 1e-4);
    assert_eq!(a.skin_m(f64::INFINITY, 2.5e-6), 1e-4);
}
