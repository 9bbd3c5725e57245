//! What the kernels can run: contact laws and walls as kernel table rows, and the check of a
//! world against them.

use crate::{GpuFeature, GpuUnsupported};
use pdamp_dem::contact::{ContactModel, FrictionLaw, NormalLaw, hertz::gonthier_damping};
use pdamp_dem::walls::Geometry;
use pdamp_dem::{Integrator, Motion, Vec3, World};

use super::LAW_F;

/// Parameters of one contact law for the kernels: `LAW_F` numbers and the kinds.
pub(super) fn law_row_with_table(
    model: &ContactModel,
    el: &pdamp_dem::interaction::PairElastic,
    tables: &mut Vec<f64>,
) -> Result<([f64; LAW_F], [u32; 4]), GpuFeature> {
    if let NormalLaw::GonthierTable {
        impact_velocities_m_s,
        restitutions,
        ..
    } = &model.normal
    {
        // A plain Gonthier row, then the kind, the table's place (relative to the tables,
        // made absolute when the tables are laid out) and its length.
        let plain = ContactModel {
            normal: NormalLaw::Gonthier {
                restitution: model.normal.restitution(),
                min_impact_velocity_m_s: model.normal.min_impact_velocity_m_s(),
            },
            ..model.clone()
        };
        let (mut f, mut u) = law_row(&plain, el)?;
        u[0] = 2;
        f[14] = tables.len() as f64;
        f[15] = impact_velocities_m_s.len() as f64;
        for (v, e) in impact_velocities_m_s.iter().zip(restitutions) {
            tables.extend([*v, *e]);
        }
        return Ok((f, u));
    }
    law_row(model, el)
}

fn law_row(
    model: &ContactModel,
    el: &pdamp_dem::interaction::PairElastic,
) -> Result<([f64; LAW_F], [u32; 4]), GpuFeature> {
    if model.rolling.is_some() {
        return Err(GpuFeature::RollingResistance);
    }
    if model.adhesion.is_some() {
        return Err(GpuFeature::Adhesion);
    }
    let mut f = [0.0; LAW_F];
    let mut u = [0u32; 4];
    f[0] = el.e_eff_pa;
    f[1] = el.g_eff_pa;
    f[2] = el.poisson_mean;
    let e = model.normal.restitution();
    f[3] = e;
    let l = e.ln();
    let beta = l / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt();
    f[4] = -2.0 * (5.0_f64 / 6.0).sqrt() * beta;
    f[9] = model.normal.min_impact_velocity_m_s();
    match model.normal {
        NormalLaw::Hertz => u[0] = 0,
        NormalLaw::Gonthier { restitution, .. } => {
            u[0] = 1;
            f[5] = gonthier_damping(restitution) / restitution;
        }
        NormalLaw::GonthierTable { .. } => unreachable!("handled by law_row_with_table"),
        NormalLaw::LankaraniNikravesh { restitution, .. } => {
            u[0] = 3;
            f[6] = 0.75 * (1.0 - restitution * restitution);
        }
        NormalLaw::Linear {
            stiffness_n_m,
            restitution,
            clip_attractive,
        } => {
            u[0] = 4;
            f[7] = stiffness_n_m;
            let l = restitution.ln();
            f[8] = 2.0 * l.abs() / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt();
            u[2] = clip_attractive as u32;
        }
        NormalLaw::HertzMindlin {
            clip_attractive, ..
        } => {
            u[0] = 5;
            u[2] = clip_attractive as u32;
        }
    }
    match model.friction {
        FrictionLaw::Frictionless => u[1] = 0,
        FrictionLaw::RegularizedSliding {
            friction_coefficient,
            regularization_s_m,
        } => {
            u[1] = 1;
            f[10] = friction_coefficient;
            f[11] = regularization_s_m;
        }
        FrictionLaw::CoulombSpring {
            friction_coefficient,
            stiffness_ratio,
            damping_ratio,
        } => {
            u[1] = 2;
            f[10] = friction_coefficient;
            let nu = el.poisson_mean;
            f[12] = stiffness_ratio.unwrap_or((1.0 - nu) / (1.0 - 0.5 * nu));
            f[13] = damping_ratio;
        }
        FrictionLaw::Mindlin {
            friction_coefficient,
        } => {
            u[1] = 3;
            f[10] = friction_coefficient;
        }
    }
    Ok((f, u))
}

/// Kernel description of one wall: kind, three rows of geometry, two-sided flag.
pub(super) fn wall_rows(g: &Geometry) -> Result<(u32, [[f64; 4]; 3], u32), GpuFeature> {
    let v = |a: &Vec3, w: f64| [a.x, a.y, a.z, w];
    Ok(match g {
        Geometry::Plane(p) => (
            0,
            [v(&p.point_m, 0.0), v(&p.normal, 0.0), [0.0; 4]],
            p.two_sided as u32,
        ),
        Geometry::BoxInside(b) => (
            1,
            [v(&b.center_m, 0.0), v(&b.half_extents_m, 0.0), [0.0; 4]],
            0,
        ),
        Geometry::CylinderInside(c) => (
            2,
            [
                v(&c.base_center_m, 0.0),
                v(&c.axis, 0.0),
                [c.radius_m, c.length_m, 0.0, 0.0],
            ],
            0,
        ),
        Geometry::CylinderOutside(_) => return Err(GpuFeature::CylinderOutside),
        Geometry::Mesh(_) => return Err(GpuFeature::MeshWall),
    })
}

/// Whether the GPU kernels can run `world` (integrator, walls, body motions, contact laws,
/// external forces); the error says what they lack, naming the wall, body or materials. Cheap:
/// call it before preparing a bed for the GPU.
pub fn check_world(world: &World) -> Result<(), GpuUnsupported> {
    if !matches!(world.integrator, Integrator::VelocityVerlet) {
        return Err(GpuUnsupported::Integrator);
    }
    if world
        .particles
        .external_force
        .iter()
        .any(|f| *f != Vec3::zeros())
    {
        return Err(GpuUnsupported::ExternalForces);
    }
    for b in &world.bodies {
        if matches!(b.motion, Motion::Driven) {
            return Err(GpuUnsupported::DrivenBody {
                body: b.name.clone(),
            });
        }
        for wall in &b.walls {
            wall_rows(&wall.geometry).map_err(|feature| GpuUnsupported::Wall {
                feature,
                wall: wall.name.clone(),
                body: b.name.clone(),
            })?;
        }
    }
    let n = world.interactions.num_materials();
    let mut tables = Vec::new();
    for a in 0..n {
        for b in 0..n {
            let (model, el) = world.interactions.get(a as u16, b as u16);
            law_row_with_table(model, el, &mut tables).map_err(|feature| {
                GpuUnsupported::ContactLaw {
                    feature,
                    material_a: world.materials[a].name.clone(),
                    material_b: world.materials[b].name.clone(),
                }
            })?;
        }
    }
    Ok(())
}
