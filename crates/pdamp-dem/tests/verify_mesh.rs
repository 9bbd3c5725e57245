//! Triangle-mesh walls against the analytic box: identical trajectories through face, edge and
//! corner hits, no force jump across shared edges, and the same packing height.

mod common;
use common::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::{Vec3, World};

fn model() -> ContactModel {
    ContactModel {
        normal: NormalLaw::Gonthier {
            restitution: 0.7,
            min_impact_velocity_m_s: 1e-3,
        },
        friction: FrictionLaw::Mindlin {
            friction_coefficient: 0.3,
        },
        rolling: None,
        adhesion: None,
    }
}

fn few_particles(mesh: bool) -> World {
    let r = 2e-3;
    let mut w = box_world(0, r, 0.04, 0.04, model(), 2e-6, mesh, 1);
    // Aimed at a face, a concave edge, a corner and the floor diagonal; far apart from each other.
    let starts = [
        (Vec3::new(0.0, 0.0, 0.02), Vec3::new(0.0, 0.0, -0.8)),
        (Vec3::new(0.012, -0.012, 0.03), Vec3::new(0.5, 0.0, -0.3)),
        (Vec3::new(-0.012, 0.012, 0.012), Vec3::new(-0.6, 0.6, -0.6)),
        (Vec3::new(0.012, 0.012, 0.02), Vec3::new(0.3, 0.3, 0.0)),
    ];
    for (x, v) in starts {
        let i = w.add_particle(x, r, 0);
        w.particles.velocity[i] = v;
    }
    w
}

#[test]
fn mesh_box_trajectories_match_analytic_box() {
    let mut a = few_particles(false);
    let mut b = few_particles(true);
    let mut worst: f64 = 0.0;
    let mut wall_hits = 0usize;
    let mut multi_hits = 0usize;
    for _ in 0..100_000 {
        a.step();
        b.step();
        wall_hits += a.num_pw_contacts();
        multi_hits += (0..a.particles.len())
            .filter(|&i| a.num_wall_contacts_of(i) >= 2)
            .count();
        assert_eq!(a.num_pw_contacts(), b.num_pw_contacts());
        for i in 0..a.particles.len() {
            worst = worst.max((a.particles.position[i] - b.particles.position[i]).norm());
        }
    }
    eprintln!(
        "mesh vs analytic box: largest position difference {worst:.3e} m over {wall_hits} contact-steps \
         ({multi_hits} with two or more walls touched: edge/corner hits)"
    );
    assert!(wall_hits > 500 && multi_hits > 20);
    assert!(worst < 1e-9, "trajectories differ by {worst:.3e} m");
}

#[test]
fn settled_bed_height_mesh_vs_analytic() {
    let heights: Vec<f64> = [false, true]
        .iter()
        .map(|&mesh| {
            let mut w = box_world(
                400,
                1e-3,
                0.02,
                0.04,
                hertz_mindlin(0.5, 0.3),
                2e-6,
                mesh,
                9,
            );
            w.run_until(0.15, |_| {});
            bed_height(&w)
        })
        .collect();
    eprintln!(
        "bed height analytic {:.5e} m, mesh {:.5e} m",
        heights[0], heights[1]
    );
    assert!((heights[1] / heights[0] - 1.0).abs() < 0.01);
}
