//! Deformable mesh walls (issue 26): a mesh whose vertices are moved as a rigid translation
//! behaves like the rigid mesh on a moving body; the nodal forces handed back balance the
//! particles' momentum change; a vibrating membrane patch under elastic contacts keeps the
//! energy ledger closed.

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::walls::{Geometry, TriMesh};
use pdamp_dem::{BodyState, Motion, RigidBody, Vec3, World};

fn elastic() -> ContactModel {
    ContactModel {
        normal: NormalLaw::Hertz,
        friction: FrictionLaw::Frictionless,
        rolling: None,
        adhesion: None,
    }
}

/// 1. A sphere resting on a patch that is shaken as a rigid body, and the same patch with its
///    vertices moved by the same translation every step: the same trajectory to 1e-12 m.
#[test]
fn rigidly_translated_vertices_equal_a_moving_rigid_mesh() {
    let (x, f) = (0.2e-3, 20.0); // A = 3.2 m/s² < g: the sphere stays on the patch, rolls and slides
    let dir = Vec3::new(1.0, 0.0, 0.3).normalize();
    let omega = 2.0 * std::f64::consts::PI * f;
    let phase = 0.5 * std::f64::consts::PI; // at rest at t = 0 in both worlds
    let u = |t: f64| dir * (x * (omega * t + phase).sin());
    let r = 3e-3;
    let make = |motion: Motion, mesh: TriMesh| {
        let mut w = World::new(vec![soft_steel()], hertz_mindlin(0.6, 0.3), 2e-6);
        w.gravity_m_s2 = Vec3::new(0.0, 0.0, -9.81);
        w.add_body(
            RigidBody::new("table", BodyState::at_rest(Vec3::zeros()), motion).with_wall(
                "patch",
                Geometry::Mesh(mesh),
                0,
            ),
        );
        w.add_particle(Vec3::new(0.001, 0.002, r + x), r, 0);
        w.initialize();
        w
    };
    let reference = patch(0.05, 4).vertices().to_vec();
    let faces = patch(0.05, 4).faces().to_vec();
    let shifted = |t: f64| reference.iter().map(|p| p + u(t)).collect::<Vec<_>>();
    let harmonic = pdamp_dem::HarmonicTranslation {
        direction: [dir.x, dir.y, dir.z],
        amplitude_m: x,
        frequency_hz: f,
        phase_rad: phase,
    };
    let mut rigid = make(
        Motion::Prescribed(std::sync::Arc::new(harmonic)),
        patch(0.05, 4),
    );
    let mut soft = make(
        Motion::Fixed,
        TriMesh::from_indexed(shifted(0.0), faces).unwrap(),
    );
    let (mut worst, mut contact_steps) = (0.0f64, 0usize);
    for _ in 0..50_000 {
        let t1 = soft.time_s + soft.dt_s;
        soft.move_wall_vertices(0, 0, &shifted(t1)).unwrap();
        soft.step();
        rigid.step();
        contact_steps += rigid.num_pw_contacts();
        assert_eq!(rigid.num_pw_contacts(), soft.num_pw_contacts());
        worst = worst.max((rigid.particles.position[0] - soft.particles.position[0]).norm());
        worst = worst.max(1e-3 * (rigid.particles.velocity[0] - soft.particles.velocity[0]).norm());
    }
    let (a, b) = (rigid.ledger, soft.ledger);
    let moved = (rigid.particles.position[0] - Vec3::new(0.001, 0.002, r)).norm();
    eprintln!(
        "deformed as a rigid translation: largest difference {worst:.3e} m (velocity × 1 ms) over \
         {contact_steps} contact-steps, sphere moved {moved:.3e} m; wall work {:.9e} vs {:.9e} J, \
         tangential dissipation {:.6e} J",
        a.wall_work_j, b.wall_work_j, a.dissipated_tangential_pw_j
    );
    assert!(contact_steps > 35_000, "{contact_steps}");
    assert!(
        a.dissipated_tangential_pw_j > 1e-8,
        "the sphere must slide on the moving patch (friction at work)"
    );
    assert!(worst < 1e-12, "trajectories differ by {worst:.3e} m");
    assert!((a.wall_work_j - b.wall_work_j).abs() <= 1e-9 * a.wall_work_j.abs());
}

/// Spheres on a grid above the patch (`layers` layers of 3 × 3, radius `r`, gap 0.2 r).
fn spheres_above(w: &mut World, r: f64, layers: usize, z0: f64) {
    for k in 0..layers {
        for j in 0..3 {
            for i in 0..3 {
                let s = 2.2 * r;
                w.add_particle(
                    Vec3::new(
                        s * (i as f64 - 1.0),
                        s * (j as f64 - 1.0),
                        z0 + s * k as f64,
                    ),
                    r,
                    0,
                );
            }
        }
    }
}

/// 2. A patch pushed into a cluster of spheres (no gravity, friction on): the nodal forces it
///    gets back, integrated over the steps as velocity Verlet integrates the particles, equal
///    the particles' momentum change to round-off.
#[test]
fn nodal_forces_balance_the_particles_momentum_change() {
    let r = 2e-3;
    let mut w = World::new(vec![soft_steel()], hertz_mindlin(0.5, 0.3), 1e-6);
    w.gravity_m_s2 = Vec3::zeros();
    w.add_body(
        RigidBody::new("piston", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "patch",
            Geometry::Mesh(patch(0.04, 6)),
            0,
        ),
    );
    spheres_above(&mut w, r, 2, r + 1e-4);
    w.initialize();
    let momentum = |w: &World| -> Vec3 {
        (0..w.particles.len())
            .map(|i| w.particles.velocity[i] * w.particles.mass[i])
            .sum()
    };
    let p0 = momentum(&w);
    let mut nodal = Vec::new();
    let total = |w: &World, nodal: &mut Vec<Vec3>| -> Vec3 {
        w.wall_nodal_forces(0, 0, nodal).unwrap();
        nodal.iter().sum()
    };
    let mut w_prev = total(&w, &mut nodal);
    let mut impulse = Vec3::zeros();
    let v_piston = 0.5; // m/s upwards
    let mut vertices = patch(0.04, 6).vertices().to_vec();
    for _ in 0..4_000 {
        for p in vertices.iter_mut() {
            p.z += v_piston * w.dt_s;
        }
        w.move_wall_vertices(0, 0, &vertices).unwrap();
        w.step();
        let w_now = total(&w, &mut nodal);
        // the particles feel −(force on the wall); velocity Verlet averages the step's two ends
        impulse -= (w_prev + w_now) * (0.5 * w.dt_s);
        w_prev = w_now;
    }
    let dp = momentum(&w) - p0;
    let err = (dp - impulse).norm();
    eprintln!(
        "piston: momentum change {:.9e} N·s (z), nodal impulse {:.9e} N·s, difference {err:.3e}; \
         {} wall contacts at the end",
        dp.z,
        impulse.z,
        w.num_pw_contacts()
    );
    assert!(
        dp.z > 1e-4,
        "the piston must push the spheres: Δp_z = {:.3e}",
        dp.z
    );
    assert!(
        err <= 1e-9 * dp.norm(),
        "Δp {dp:?} vs nodal impulse {impulse:?}"
    );
    // The loads sit on the vertices under the spheres: none on the patch's rim.
    w.wall_nodal_forces(0, 0, &mut nodal).unwrap();
    let rim: f64 = vertices
        .iter()
        .zip(&nodal)
        .filter(|(p, _)| p.x.abs() > 0.019 || p.y.abs() > 0.019)
        .map(|(_, f)| f.norm())
        .sum();
    assert_eq!(rim, 0.0);
}

/// 3. A membrane patch vibrating in its first mode shape under bouncing spheres, every contact
///    elastic (Hertz, frictionless): the energy ledger — wall work against kinetic, potential
///    and elastic energy — closes to 1e-4 of the energy turned over.
#[test]
fn vibrating_membrane_conserves_energy_with_elastic_contacts() {
    let r = 2e-3;
    let side = 0.06;
    let mut w = World::new(vec![soft_steel()], elastic(), 1e-6);
    w.gravity_m_s2 = Vec3::new(0.0, 0.0, -9.81);
    w.add_body(
        RigidBody::new("membrane", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "patch",
            Geometry::Mesh(patch(side, 8)),
            0,
        ),
    );
    spheres_above(&mut w, r, 2, r + 2e-4);
    w.initialize();
    let flat = patch(side, 8).vertices().to_vec();
    let (amp, f) = (0.4e-3, 60.0); // A ω² ≈ 57 m/s²: the spheres fly
    let omega = 2.0 * std::f64::consts::PI * f;
    let pi = std::f64::consts::PI;
    let shape = |p: &Vec3| (pi * p.x / side).cos() * (pi * p.y / side).cos();
    let mut max_closure = 0.0f64;
    let mut moved = Vec::with_capacity(flat.len());
    for k in 0..60_000 {
        let t1 = w.time_s + w.dt_s;
        moved.clear();
        moved.extend(
            flat.iter()
                .map(|p| p + Vec3::z() * (amp * (omega * t1).sin() * shape(p))),
        );
        w.move_wall_vertices(0, 0, &moved).unwrap();
        w.step();
        if k % 100 == 0 {
            let l = w.ledger;
            max_closure = max_closure.max(l.closure_error_j().abs() / l.turnover_j().max(1e-300));
        }
    }
    let l = w.ledger;
    eprintln!(
        "membrane: wall work {:.6e} J, kinetic {:.6e} J, dissipated {:.3e} J, closure {:.3e} J, \
         largest relative closure {max_closure:.3e}; {} wall contacts now",
        l.wall_work_j,
        l.kinetic_j,
        l.dissipated_j(),
        l.closure_error_j(),
        w.num_pw_contacts()
    );
    assert!(
        l.wall_work_j.abs() > 1e-6,
        "the membrane must do work on the spheres"
    );
    // Elastic contacts dissipate nothing; what the ledger books there is the step's change of
    // the surface velocity between the previous and the current contact point (the rotating-
    // wall term of the work integral), a round-off-sized share.
    assert!(
        l.dissipated_j().abs() <= 1e-5 * l.wall_work_j.abs(),
        "{}",
        l.dissipated_j()
    );
    assert!(
        max_closure <= 1e-4,
        "ledger closes only to {max_closure:.3e}"
    );
}
