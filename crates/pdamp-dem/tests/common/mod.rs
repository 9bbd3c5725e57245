//! Shared set-ups of the verification tests.
#![allow(dead_code)]

use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::generate::{Region, random_insertion, tight_packing};
use pdamp_dem::walls::{BoxInside, Geometry, TriMesh};
use pdamp_dem::{BodyState, Material, Motion, RigidBody, Vec3, World};
use rand::{RngExt, SeedableRng};

/// Shakes the box (body 0) of `w` harmonically along `direction` (velocity Verlet) and
/// initialises the world.
pub fn shake(w: &mut World, direction: [f64; 3], amplitude_m: f64, frequency_hz: f64) {
    w.integrator = pdamp_dem::Integrator::VelocityVerlet;
    w.bodies[0].motion = Motion::Prescribed(std::sync::Arc::new(pdamp_dem::HarmonicTranslation {
        direction,
        amplitude_m,
        frequency_hz,
        phase_rad: 0.0,
    }));
    w.initialize();
}

/// Soft steel-like material used in the bulk tests.
pub fn soft_steel() -> Material {
    Material::new("steel", 7800.0, 2e9, 0.3)
}

/// A world with particles of radius `r` randomly inserted in a closed box of `side` × `side` ×
/// `height` (the box's floor at z = 0), with the given container geometry (analytic or mesh).
#[allow(clippy::too_many_arguments)]
pub fn box_world(
    n: usize,
    r: f64,
    side: f64,
    height: f64,
    model: ContactModel,
    dt: f64,
    mesh: bool,
    seed: u64,
) -> World {
    let mut w = World::new(vec![soft_steel()], model, dt);
    let c = Vec3::new(0.0, 0.0, 0.5 * height);
    let h = Vec3::new(0.5 * side, 0.5 * side, 0.5 * height);
    let geometry = if mesh {
        Geometry::Mesh(TriMesh::box_inside(c, h))
    } else {
        Geometry::BoxInside(BoxInside::new(c, h))
    };
    w.add_body(
        RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed)
            .with_wall("box", geometry, 0),
    );
    let region = Region::Box {
        min_m: Vec3::new(-0.5 * side, -0.5 * side, 0.0),
        max_m: Vec3::new(0.5 * side, 0.5 * side, height),
    };
    let radii = vec![r; n];
    let pos = random_insertion(&region, &radii, seed, 10_000, None).expect("insertion");
    for x in pos {
        w.add_particle(x, r, 0);
    }
    w
}

/// Random velocities of magnitude up to `vmax` (deterministic).
pub fn randomize_velocities(w: &mut World, vmax: f64, seed: u64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for v in w.particles.velocity.iter_mut() {
        *v = Vec3::new(
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
        ) * (2.0 * vmax);
    }
}

/// Hertz–Mindlin with friction, the LIGGGHTS-style default model.
pub fn hertz_mindlin(e: f64, mu: f64) -> ContactModel {
    ContactModel {
        normal: NormalLaw::HertzMindlin {
            restitution: e,
            clip_attractive: false,
        },
        friction: FrictionLaw::Mindlin {
            friction_coefficient: mu,
        },
        rolling: None,
        adhesion: None,
    }
}

/// Particles in hexagonal close packing in a box region above the floor.
pub fn tight_box_world(
    n: usize,
    r: f64,
    side: f64,
    height: f64,
    model: ContactModel,
    dt: f64,
) -> World {
    let mut w = World::new(vec![soft_steel()], model, dt);
    let c = Vec3::new(0.0, 0.0, 0.5 * height);
    let h = Vec3::new(0.5 * side, 0.5 * side, 0.5 * height);
    w.add_body(
        RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "box",
            Geometry::BoxInside(BoxInside::new(c, h)),
            0,
        ),
    );
    let region = Region::Box {
        min_m: Vec3::new(-0.5 * side, -0.5 * side, 0.0),
        max_m: Vec3::new(0.5 * side, 0.5 * side, height),
    };
    let pos = tight_packing(&region, &vec![r; n], 0.02 * r, &Vec3::z()).expect("packing");
    for x in pos {
        w.add_particle(x, r, 0);
    }
    w
}

/// Twice the mean centre height above the floor (z = 0): the packing height measure, m.
pub fn bed_height(w: &World) -> f64 {
    let p = &w.particles;
    2.0 * p.position.iter().map(|x| x.z).sum::<f64>() / p.len() as f64
}

/// A flat square patch of side `side` at z = 0, `n` × `n` cells of two triangles, normals +z.
pub fn patch(side: f64, n: usize) -> TriMesh {
    let mut v = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            v.push(Vec3::new(
                side * (i as f64 / n as f64 - 0.5),
                side * (j as f64 / n as f64 - 0.5),
                0.0,
            ));
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh::from_indexed(v, f).unwrap()
}

/// Asserts that two worlds hold the same bits: time, positions, velocities, spins, forces,
/// torques and the energy ledger.
pub fn assert_same_bits(a: &World, b: &World, what: &str) {
    let (p, q) = (&a.particles, &b.particles);
    assert_eq!(a.time_s.to_bits(), b.time_s.to_bits(), "{what}: time");
    let fields = [
        ("x", &p.position, &q.position),
        ("v", &p.velocity, &q.velocity),
        ("ω", &p.angular_velocity, &q.angular_velocity),
        ("F", &p.force, &q.force),
        ("T", &p.torque, &q.torque),
    ];
    for (name, u, w) in fields {
        for i in 0..p.len() {
            for k in 0..3 {
                assert_eq!(u[i][k].to_bits(), w[i][k].to_bits(), "{what}: {name}[{i}]");
            }
        }
    }
    let (l, m) = (&a.ledger, &b.ledger);
    for (x, y, name) in [
        (l.kinetic_j, m.kinetic_j, "kinetic"),
        (l.potential_j, m.potential_j, "potential"),
        (l.elastic_j, m.elastic_j, "elastic"),
        (l.wall_work_j, m.wall_work_j, "wall work"),
        (l.dissipated_j(), m.dissipated_j(), "dissipated"),
    ] {
        assert_eq!(x.to_bits(), y.to_bits(), "{what}: ledger {name} {x} vs {y}");
    }
}
