//! Built-in scenarios: the shaken-box benchmark (DEM-core issue) used by `pdamp bench`, by the
//! default example and by tests.

use crate::schema::*;
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw};
use pdamp_dem::generate::{Region, SizeDistribution};
use pdamp_dem::walls::BoxInside;
use pdamp_dem::{HarmonicTranslation, Integrator, Material, Vec3};

/// Side length of the square base of the shaken box for `n` particles, m: 40 mm up to
/// n = 8 000 and 40·√(n/8 000) mm above, so the bed height stays about the same.
pub fn shaken_box_side_m(n: usize) -> f64 {
    0.040 * (n as f64 / 8000.0).sqrt().max(1.0)
}

/// The shaken-box benchmark: a closed box 40 mm high, `n` steel spheres of radius 1 mm
/// (ρ = 7 800 kg/m³, E softened to 2 GPa, ν = 0.3) in hexagonal close packing, Hertz–Mindlin
/// with restitution 0.6 and friction 0.3, settled under gravity, then the box moves as
/// x = X sin(2π f t) with f = 20 Hz and X = 2 mm for `duration_s`.
pub fn shaken_box(n: usize, duration_s: f64) -> Scenario {
    let side = shaken_box_side_m(n);
    let h = 0.040;
    Scenario {
        title: format!("shaken box, {n} spheres"),
        simulation: SimulationSpec {
            duration_s,
            time_step_s: 2e-6,
            integrator: Integrator::VelocityVerlet,
            gravity_m_s2: [0.0, 0.0, -9.81],
            seed: 1,
            skin_m: Some(0.2e-3),
            max_time_step_ratio: 0.1,
            check_impact_velocity_m_s: 1.0,
        },
        output: OutputSpec {
            energy_interval_s: 1e-3,
            vtk_interval_s: 0.05,
            vtk_format: Default::default(),
        },
        materials: vec![Material::new("steel", 7800.0, 2e9, 0.3)],
        contact: ContactSpec {
            default: ContactModel {
                normal: NormalLaw::HertzMindlin {
                    restitution: 0.6,
                    clip_attractive: false,
                },
                friction: FrictionLaw::Mindlin {
                    friction_coefficient: 0.3,
                },
                rolling: None,
                adhesion: None,
            },
            pairs: vec![],
        },
        bodies: vec![BodySpec {
            name: "box".into(),
            position_m: [0.0, 0.0, 0.0],
            motion: MotionSpec::Harmonic(HarmonicTranslation {
                direction: [1.0, 0.0, 0.0],
                amplitude_m: 0.002,
                frequency_hz: 20.0,
                phase_rad: 0.0,
            }),
            walls: vec![WallSpec {
                name: "container".into(),
                material: "steel".into(),
                geometry: GeometrySpec::BoxInside(BoxInside::new(
                    Vec3::new(0.0, 0.0, 0.5 * h),
                    Vec3::new(0.5 * side, 0.5 * side, 0.5 * h),
                )),
            }],
        }],
        particles: vec![ParticleGroupSpec {
            material: "steel".into(),
            count: Some(n),
            filling: None,
            size: SizeDistribution::Monodisperse { radius_m: 1e-3 },
            placement: PlacementSpec {
                gap_m: 2e-5,
                ..PlacementSpec::new(
                    PlacementMethod::Tight,
                    Region::Box {
                        min_m: Vec3::new(-0.5 * side, -0.5 * side, 0.0),
                        max_m: Vec3::new(0.5 * side, 0.5 * side, h),
                    },
                )
            },
            initial_velocity_m_s: [0.0; 3],
        }],
        settle: Some(SettleSpec {
            max_duration_s: 0.05,
            kinetic_energy_per_particle_j: 0.0,
            gravity_m_s2: None,
            turn_max_duration_s: None,
        }),
        damper: None,
        fields: None,
    }
}

/// The shaken box as a damper point [D Sect. 3.2]: the benchmark's bed of `n` spheres as a
/// drop-down ([`PlacementMethod::DropDown`], settled for up to 0.3 s), the box excited along x at
/// 20 Hz with X = 2 mm for 10 cycles (3 dropped), container mass 0.2 kg, on `packings`
/// independently prepared beds; no motion output (`examples/damper_shaken_box.toml` is the
/// commented file version with 8 000 spheres).
pub fn shaken_box_damper(n: usize, packings: usize) -> Scenario {
    let mut s = shaken_box(n, 0.0);
    s.title = format!("shaken box damper, {n} spheres, drop-down beds");
    let side = shaken_box_side_m(n);
    s.particles[0].placement = PlacementSpec::new(
        PlacementMethod::DropDown,
        Region::Box {
            min_m: Vec3::new(-0.5 * side, -0.5 * side, 0.0),
            max_m: Vec3::new(0.5 * side, 0.5 * side, 0.040),
        },
    );
    s.bodies[0].motion = MotionSpec::Fixed;
    s.settle = Some(SettleSpec {
        max_duration_s: 0.3,
        kinetic_energy_per_particle_j: 1e-11,
        gravity_m_s2: None,
        turn_max_duration_s: None,
    });
    s.damper = Some(DamperSpec {
        container_body: "box".into(),
        container_mass_kg: 0.2,
        direction: [1.0, 0.0, 0.0],
        frequency_hz: Some(20.0),
        amplitude_m: Some(2e-3),
        acceleration_m_s2: None,
        intensity: None,
        cycles: 10,
        transient_cycles: 3,
        convergence: None,
        motion_output: MotionOutputSpec {
            phases_per_cycle: 0,
            field_cells: 24,
            trajectory_particles: Vec::new(),
            vtk_frames_per_cycle: 0,
        },
        packings,
    });
    s
}
