//! The repeated particle–wall pass of a coupling iteration (P Algorithm 1, issue 26): a step
//! whose deformable walls are first moved to a wrong guess and then, after any number of
//! repetitions, to the true surface gives the step taken with the true surface from the start
//! — the same contacts, spring histories and energies, forces to round-off — and the ledger
//! still closes.

mod common;
use common::*;
use pdamp_dem::wall_repeat::WallRepeatError;
use pdamp_dem::walls::Geometry;
use pdamp_dem::{BodyState, Motion, RigidBody, Vec3, World};

const SIDE: f64 = 0.06;

/// Two layers of 3 × 3 spheres resting on a membrane patch; friction and damping on, so that
/// every contact carries tangential history.
fn membrane_world(repeatable: bool) -> World {
    let r = 2e-3;
    let mut w = World::new(vec![soft_steel()], hertz_mindlin(0.6, 0.4), 1e-6);
    w.gravity_m_s2 = Vec3::new(0.0, 0.0, -9.81);
    w.add_body(
        RigidBody::new("membrane", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "patch",
            Geometry::Mesh(patch(SIDE, 8)),
            0,
        ),
    );
    for k in 0..2 {
        for j in 0..3 {
            for i in 0..3 {
                let s = 2.2 * r;
                w.add_particle(
                    Vec3::new(
                        s * (i as f64 - 1.0) + 1e-4 * k as f64,
                        s * (j as f64 - 1.0),
                        r + 2e-4 + s * k as f64,
                    ),
                    r,
                    0,
                );
            }
        }
    }
    w.set_wall_pass_repeatable(repeatable);
    w.initialize();
    w
}

/// The membrane's first mode shape at amplitude `amp` (m), written into `out`.
fn surface(flat: &[Vec3], amp: f64, out: &mut Vec<Vec3>) {
    let pi = std::f64::consts::PI;
    out.clear();
    out.extend(
        flat.iter()
            .map(|p| p + Vec3::z() * (amp * (pi * p.x / SIDE).cos() * (pi * p.y / SIDE).cos())),
    );
}

#[test]
fn repeated_wall_pass_equals_the_step_with_the_final_walls() {
    let flat = patch(SIDE, 8).vertices().to_vec();
    let (amp, f) = (0.08e-3, 60.0); // A ω² ≈ 11 m/s²: the spheres lift off and land again
    let omega = 2.0 * std::f64::consts::PI * f;
    let mut direct = membrane_world(false);
    let mut coupled = membrane_world(true);
    let (mut truth, mut guess) = (Vec::new(), Vec::new());
    let (mut worst_x, mut worst_f, mut worst_load, mut repeats) = (0.0f64, 0.0f64, 0.0f64, 0);
    let (mut max_closure, mut contact_steps) = (0.0f64, 0usize);
    let (mut nodal_a, mut nodal_b, mut nodal_guess) = (Vec::new(), Vec::new(), Vec::new());
    let mut guess_differs = 0;
    for k in 0..20_000 {
        let t1 = direct.time_s + direct.dt_s;
        surface(&flat, amp * (omega * t1).sin(), &mut truth);
        direct.move_wall_vertices(0, 0, &truth).unwrap();
        direct.step_deferred();
        // The coupled world first sees a guess 30 % off (and on every third step a second,
        // 10 % off), then the truth.
        surface(&flat, 1.3 * amp * (omega * t1).sin(), &mut guess);
        coupled.move_wall_vertices(0, 0, &guess).unwrap();
        coupled.step_deferred();
        coupled.wall_nodal_forces(0, 0, &mut nodal_guess).unwrap();
        if k % 3 == 0 {
            surface(&flat, 0.9 * amp * (omega * t1).sin(), &mut guess);
            coupled.move_wall_vertices_again(0, 0, &guess).unwrap();
            coupled.repeat_wall_pass().unwrap();
            repeats += 1;
        }
        coupled.move_wall_vertices_again(0, 0, &truth).unwrap();
        coupled.repeat_wall_pass().unwrap();
        repeats += 1;
        direct.wall_nodal_forces(0, 0, &mut nodal_a).unwrap();
        coupled.wall_nodal_forces(0, 0, &mut nodal_b).unwrap();
        let scale = direct.particles.mass[0] * 9.81;
        if nodal_guess
            .iter()
            .zip(&nodal_b)
            .any(|(g, b)| (g - b).norm() > 1e-3 * scale)
        {
            guess_differs += 1;
        }
        for (a, b) in nodal_a.iter().zip(&nodal_b) {
            worst_f = worst_f.max((a - b).norm() / scale);
        }
        worst_load =
            worst_load.max((direct.body_load(0).0 - coupled.body_load(0).0).norm() / scale);
        direct.complete_step();
        coupled.complete_step();
        assert_eq!(
            direct.num_pw_contacts(),
            coupled.num_pw_contacts(),
            "step {k}"
        );
        contact_steps += direct.num_pw_contacts();
        for (a, b) in direct
            .particles
            .position
            .iter()
            .zip(&coupled.particles.position)
        {
            worst_x = worst_x.max((a - b).norm());
        }
        if k % 100 == 0 {
            let l = coupled.ledger;
            max_closure = max_closure.max(l.closure_error_j().abs() / l.turnover_j().max(1e-300));
        }
    }
    let (a, b) = (direct.ledger, coupled.ledger);
    eprintln!(
        "repeated wall passes: {repeats} over 20 000 steps, {contact_steps} contact-steps; largest \
         position difference {worst_x:.3e} m, nodal force {worst_f:.3e} m g, body load \
         {worst_load:.3e} m g; the guess changed the nodal forces in {guess_differs} steps; wall work {:.9e} vs {:.9e} J, wall dissipation {:.9e} vs {:.9e} J; \
         ledger closes to {max_closure:.3e}",
        a.wall_work_j,
        b.wall_work_j,
        a.dissipated_normal_pw_j + a.dissipated_tangential_pw_j,
        b.dissipated_normal_pw_j + b.dissipated_tangential_pw_j,
    );
    assert!(contact_steps > 40_000, "{contact_steps}");
    assert!(
        guess_differs > 5_000,
        "the guesses must change the wall forces: {guess_differs} steps"
    );
    assert!(a.dissipated_tangential_pw_j > 0.0, "friction must act");
    // The same arithmetic in the same order: equal to the bit.
    assert!(worst_x == 0.0, "positions differ by {worst_x:.3e} m");
    assert!(worst_f == 0.0, "nodal forces differ by {worst_f:.3e} m g");
    assert!(
        worst_load == 0.0,
        "body loads differ by {worst_load:.3e} m g"
    );
    assert_eq!(a, b, "ledgers differ");
    assert!(
        max_closure < 1e-4,
        "ledger closes only to {max_closure:.3e}"
    );
}

#[test]
fn a_wall_pass_is_repeated_only_inside_a_pending_step() {
    let mut w = membrane_world(false);
    w.step_deferred();
    assert_eq!(w.repeat_wall_pass(), Err(WallRepeatError::NotRepeatable));
    let mut w = membrane_world(true);
    assert_eq!(w.repeat_wall_pass(), Err(WallRepeatError::NoPendingStep));
    w.step_deferred();
    assert_eq!(w.repeat_wall_pass(), Ok(()));
    w.complete_step();
    assert_eq!(w.repeat_wall_pass(), Err(WallRepeatError::NoPendingStep));
    // A move can be replaced only after a move.
    let flat = patch(SIDE, 8).vertices().to_vec();
    assert!(w.move_wall_vertices_again(0, 0, &flat).is_err());
}
