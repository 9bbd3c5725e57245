//! Settling a bed before a run: under the run gravity, or filled under another gravity and
//! then "turned" (D Sect. 8.1.1), with the bodies held.

use pdamp_dem::{Motion, Vec3, World};
use std::ops::ControlFlow;

/// Lets settling run with all bodies held at their reference pose, then restarts the clock at
/// zero (bodies get their motion back). Ends early below `ke_per_particle_j`.
pub fn settle(
    world: &mut World,
    max_duration_s: f64,
    ke_per_particle_j: f64,
    mut tick: impl FnMut(f64),
) -> f64 {
    settle_or_break(world, max_duration_s, ke_per_particle_j, |w| {
        tick(w.time_s / max_duration_s);
        ControlFlow::Continue(())
    })
    .unwrap_or(max_duration_s)
}

/// Holds every body that is not driven (settling happens in a container at rest); returns
/// their motions for [`release_bodies`].
fn hold_bodies(world: &mut World) -> Vec<Motion> {
    let motions = world.bodies.iter().map(|b| b.motion.clone()).collect();
    for b in world.bodies.iter_mut() {
        if !matches!(b.motion, Motion::Driven) {
            b.motion = Motion::Fixed;
        }
    }
    motions
}

/// Gives the bodies back the motions [`hold_bodies`] took.
fn release_bodies(world: &mut World, motions: Vec<Motion>) {
    for (b, m) in world.bodies.iter_mut().zip(motions) {
        b.motion = m;
    }
}

/// Settling as in [`settle`], with `hook` called every 200 steps; when it returns `Break` the
/// loop stops at once (bodies get their motion back, the clock is not restarted) and the result
/// is `None`. The check of the kinetic energy uses the step counter, so a settling resumed from
/// a checkpoint ends at the same step as an uninterrupted one.
pub fn settle_or_break(
    world: &mut World,
    max_duration_s: f64,
    ke_per_particle_j: f64,
    mut hook: impl FnMut(&World) -> ControlFlow<()>,
) -> Option<f64> {
    let motions = hold_bodies(world);
    let n = world.particles.len().max(1) as f64;
    let check_every = 200u64;
    let mut stopped = false;
    while world.time_s < max_duration_s {
        world.step();
        if world.counters.steps.is_multiple_of(check_every) {
            if world.ledger.kinetic_j / n < ke_per_particle_j {
                break;
            }
            if hook(world).is_break() {
                stopped = true;
                break;
            }
        }
    }
    let t = world.time_s;
    release_bodies(world, motions);
    if stopped {
        return None;
    }
    world.restart_clock();
    Some(t)
}

/// Second settling stage after the container was "turned" (filled under one gravity, run under
/// another, D Sect. 8.1.1: filled with the axis vertical, then turned by 90°): steps under the
/// world's gravity with the bodies held until the kinetic energy per particle has risen above
/// `ke_per_particle_j` and fallen below it again (the bed slumped and came to rest), or for
/// `max_duration_s`. Restarts the clock and returns the time taken, s.
///
/// Without it the slump happens during the excitation: at 1 kHz the 16 evaluated cycles of a
/// 50 mm bed last 16 ms, less than its fall time, and the ledger then books the released
/// potential energy as dissipation (250 × the cycle's wall work on the baseline cylinder).
pub fn settle_after_turn(
    world: &mut World,
    max_duration_s: f64,
    ke_per_particle_j: f64,
    mut tick: impl FnMut(f64),
) -> f64 {
    let motions = hold_bodies(world);
    let n = world.particles.len().max(1) as f64;
    let t0 = world.time_s;
    let mut risen = false;
    while world.time_s - t0 < max_duration_s {
        world.step();
        if world.counters.steps.is_multiple_of(200) {
            let ke = world.ledger.kinetic_j / n;
            if ke >= ke_per_particle_j {
                risen = true;
            } else if risen {
                break;
            }
            tick((world.time_s - t0) / max_duration_s);
        }
    }
    let t = world.time_s - t0;
    release_bodies(world, motions);
    world.restart_clock();
    t
}

/// Settles `world` as `spec` says (with its own gravity if given) and restarts the clock.
pub fn settle_with(
    world: &mut World,
    spec: &crate::schema::SettleSpec,
    mut tick: impl FnMut(f64),
) -> f64 {
    let g = world.gravity_m_s2;
    let max = spec.max_duration_s;
    settle_with_or_break(world, spec, g, |w| {
        tick(w.time_s / max);
        ControlFlow::Continue(())
    })
    .unwrap_or(max)
}

/// [`settle_with`] with a hook as in [`settle_or_break`]; `main_gravity_m_s2` is put back
/// after settling (needed when resuming: the restored world carries the settling gravity).
pub fn settle_with_or_break(
    world: &mut World,
    spec: &crate::schema::SettleSpec,
    main_gravity_m_s2: Vec3,
    hook: impl FnMut(&World) -> ControlFlow<()>,
) -> Option<f64> {
    if let Some(gs) = spec.gravity_m_s2 {
        world.gravity_m_s2 = Vec3::from(gs);
    }
    let t = settle_or_break(
        world,
        spec.max_duration_s,
        spec.kinetic_energy_per_particle_j,
        hook,
    )?;
    if world.gravity_m_s2 != main_gravity_m_s2 {
        world.gravity_m_s2 = main_gravity_m_s2;
        world.restart_clock();
    }
    Some(t)
}
