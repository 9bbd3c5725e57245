//! Deferred half kicks (`World::step_deferred`, `World::run_until_or_break_deferred`) give the
//! same state as plain steps, to the bit: the fused pass does the same arithmetic in the same
//! order, only in one pass over the particles instead of two.

mod common;
use common::*;
use pdamp_dem::{Integrator, World};
use std::ops::ControlFlow;

fn shaken(seed: u64) -> World {
    let mut w = box_world(
        800,
        1e-3,
        0.025,
        0.04,
        hertz_mindlin(0.6, 0.4),
        2e-6,
        false,
        seed,
    );
    shake(&mut w, [1.0, 0.0, 0.3], 2e-3, 60.0);
    w
}

/// 1 500 plain steps against 1 500 deferred ones (completed at the end), and a run to a time
/// that is not a whole number of steps (the last step shortened) against the deferred run
/// that stops every 97 steps to read the state: same bits on one and two threads.
#[test]
fn deferred_half_kicks_give_the_same_bits() {
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut a = shaken(3);
            let mut b = a.clone();
            for _ in 0..1500 {
                a.step();
                b.step_deferred();
                assert!(b.step_pending());
                // Positions, clock and body loads are current between deferred steps.
                assert_eq!(a.time_s.to_bits(), b.time_s.to_bits());
                assert_eq!(
                    a.particles.position[17][0].to_bits(),
                    b.particles.position[17][0].to_bits()
                );
                assert_eq!(
                    a.bodies[0].contact_force_n[0].to_bits(),
                    b.bodies[0].contact_force_n[0].to_bits()
                );
            }
            b.complete_step();
            assert!(!b.step_pending());
            assert_same_bits(&a, &b, "after 1 500 steps");
            assert!(a.counters.neighbor_builds > 2, "the list was rebuilt");

            let t_end = a.time_s + 1234.5 * a.dt_s;
            a.run_until(t_end, |_| {});
            let mut reads = 0;
            let reached = b.run_until_or_break_deferred(t_end, |w| {
                if w.counters.steps.is_multiple_of(97) {
                    w.complete_step();
                    reads += 1;
                    assert!(w.check_health().is_ok());
                }
                ControlFlow::Continue(())
            });
            assert!(reached && reads > 10);
            assert!(!b.step_pending());
            assert_same_bits(&a, &b, "after run_until");
        });
    }
}

/// Under Gear's step control nothing is deferred: `step_deferred` is `step`.
#[test]
fn gear_steps_are_never_deferred() {
    let mut a = shaken(5);
    a.integrator = Integrator::Gear(Default::default());
    let mut b = a.clone();
    for _ in 0..50 {
        a.step();
        b.step_deferred();
        assert!(!b.step_pending());
    }
    assert_same_bits(&a, &b, "Gear");
}
