//! Shared set-ups of the GPU kernel tests.
#![allow(dead_code)]

use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::generate::{Region, random_insertion};
use pdamp_dem::walls::{BoxInside, Geometry};
use pdamp_dem::{BodyState, HarmonicTranslation, Material, Motion, RigidBody, Vec3, World};
use pdamp_gpu::GpuDevice;

/// The device the kernels run on: a GPU, or lavapipe on the CPU. Without any Vulkan adapter
/// the test is skipped with a message, unless `PDAMP_REQUIRE_GPU_TESTS=1` (set by the
/// project's test script, which installs lavapipe) makes that a failure.
pub fn device() -> Option<GpuDevice> {
    match GpuDevice::open() {
        Ok(d) => {
            eprintln!("GPU kernels on {}", d.name());
            Some(d)
        }
        Err(e) => {
            if std::env::var("PDAMP_REQUIRE_GPU_TESTS").is_ok_and(|v| v == "1") {
                panic!("PDAMP_REQUIRE_GPU_TESTS=1 but {e}");
            }
            eprintln!("skipped: {e}");
            None
        }
    }
}

/// Soft steel (E = 2 GPa), the shaken box's material.
pub fn soft_steel() -> Material {
    Material::new("steel", 7800.0, 2e9, 0.3)
}

/// LIGGGHTS' Hertz–Mindlin with tangential history.
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

/// `n` spheres of radius 1 mm inserted at random in a closed box `side` × `side` × 40 mm
/// (floor at z = 0) on body 0 at rest.
pub fn box_world(n: usize, side: f64, model: ContactModel, dt: f64, seed: u64) -> World {
    let h = 0.04;
    let mut w = World::new(vec![soft_steel()], model, dt);
    w.add_body(
        RigidBody::new("box", BodyState::at_rest(Vec3::zeros()), Motion::Fixed).with_wall(
            "container",
            Geometry::BoxInside(BoxInside::new(
                Vec3::new(0.0, 0.0, 0.5 * h),
                Vec3::new(0.5 * side, 0.5 * side, 0.5 * h),
            )),
            0,
        ),
    );
    let region = Region::Box {
        min_m: Vec3::new(-0.5 * side, -0.5 * side, 0.0),
        max_m: Vec3::new(0.5 * side, 0.5 * side, h),
    };
    let r = 1e-3;
    for x in random_insertion(&region, &vec![r; n], seed, 10_000, None).expect("insertion") {
        w.add_particle(x, r, 0);
    }
    w
}

/// The shaken box: `n` spheres dropped for `settle_steps` steps in the box at rest, then the
/// box moves as x = 2 mm sin(2π 20 Hz t) (velocity Verlet, dt = 2 µs, Hertz–Mindlin e = 0.6,
/// μ = 0.3), initialised and ready to step.
pub fn shaken_box(n: usize, settle_steps: usize, seed: u64) -> World {
    let side = 0.02 * (n as f64 / 1000.0).sqrt().max(1.0);
    let mut w = box_world(n, side, hertz_mindlin(0.6, 0.3), 2e-6, seed);
    w.initialize();
    for _ in 0..settle_steps {
        w.step();
    }
    w.bodies[0].motion = Motion::Prescribed(std::sync::Arc::new(HarmonicTranslation {
        direction: [1.0, 0.0, 0.0],
        amplitude_m: 0.002,
        frequency_hz: 20.0,
        phase_rad: 0.0,
    }));
    w.restart_clock();
    w.initialize();
    w
}

/// Largest distance between the particle centres of a CPU world and a GPU snapshot, m.
pub fn max_position_difference(w: &World, s: &pdamp_gpu::GpuSnapshot) -> f64 {
    w.particles
        .position
        .iter()
        .zip(&s.position)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max)
}
