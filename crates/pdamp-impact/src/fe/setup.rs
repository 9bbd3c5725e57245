//! Building an FE impact model: Gauss-point geometry and lumped mass of the elements, the
//! contact slaves, the stable time step and the bodies.

use super::{Body, Gp};
use crate::constitutive::Kernel;
use crate::material::{Material, MaterialModel};
use crate::mesh::Mesh;

/// Geometry of all elements: Gauss points, B-bar rows (mean dilatation), lumped (row-sum)
/// nodal masses and the smallest characteristic length of the sphere's and the wall's
/// elements.
pub(super) struct ElementGeometry {
    pub(super) gps: Vec<Gp>,
    pub(super) bvbar: Vec<[f64; 8]>,
    pub(super) mass: Vec<f64>,
    pub(super) lmin_sphere: f64,
    pub(super) lmin_wall: f64,
}

/// Gauss-point geometry (2×2 points, weight 2πr·detJ), B-bar rows and lumped mass of every
/// element, and the characteristic lengths $L_e$ = area / longest diagonal; `wall_mat` gives
/// the density of the non-sphere elements.
pub(super) fn element_geometry(
    mesh: &Mesh,
    sphere: &Material,
    wall_mat: &Material,
) -> ElementGeometry {
    let n = mesh.r.len();
    let g = 1.0 / 3f64.sqrt();
    let pts = [(-g, -g), (g, -g), (g, g), (-g, g)];
    let mut gps = Vec::with_capacity(4 * mesh.elems.len());
    let mut bvbar = Vec::with_capacity(mesh.elems.len());
    let mut mass = vec![0.0; n];
    let mut lmin_sphere = f64::INFINITY;
    let mut lmin_wall = f64::INFINITY;
    for (e, q) in mesh.elems.iter().enumerate() {
        let in_sphere = mesh.sphere_elems.contains(&e);
        let rho = if in_sphere {
            sphere.density_kg_m3
        } else {
            wall_mat.density_kg_m3
        };
        let xr: [f64; 4] = std::array::from_fn(|a| mesh.r[q[a] as usize]);
        let xz: [f64; 4] = std::array::from_fn(|a| mesh.z[q[a] as usize]);
        let mut bv = [0.0; 8];
        let mut vol = 0.0;
        for &(xi, eta) in &pts {
            let nn = [
                0.25 * (1.0 - xi) * (1.0 - eta),
                0.25 * (1.0 + xi) * (1.0 - eta),
                0.25 * (1.0 + xi) * (1.0 + eta),
                0.25 * (1.0 - xi) * (1.0 + eta),
            ];
            let dxi = [
                -0.25 * (1.0 - eta),
                0.25 * (1.0 - eta),
                0.25 * (1.0 + eta),
                -0.25 * (1.0 + eta),
            ];
            let deta = [
                -0.25 * (1.0 - xi),
                -0.25 * (1.0 + xi),
                0.25 * (1.0 + xi),
                0.25 * (1.0 - xi),
            ];
            let (mut j11, mut j12, mut j21, mut j22, mut r) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for a in 0..4 {
                j11 += dxi[a] * xr[a];
                j12 += dxi[a] * xz[a];
                j21 += deta[a] * xr[a];
                j22 += deta[a] * xz[a];
                r += nn[a] * xr[a];
            }
            let det = j11 * j22 - j12 * j21;
            assert!(det > 0.0, "element {e} is inverted");
            let mut gp = Gp {
                dndr: [0.0; 4],
                dndz: [0.0; 4],
                nr: [0.0; 4],
                w: 2.0 * std::f64::consts::PI * r * det,
            };
            for a in 0..4 {
                gp.dndr[a] = (j22 * dxi[a] - j12 * deta[a]) / det;
                gp.dndz[a] = (-j21 * dxi[a] + j11 * deta[a]) / det;
                gp.nr[a] = nn[a] / r;
                mass[q[a] as usize] += rho * gp.w * nn[a];
                bv[2 * a] += gp.w * (gp.dndr[a] + gp.nr[a]);
                bv[2 * a + 1] += gp.w * gp.dndz[a];
            }
            vol += gp.w;
            gps.push(gp);
        }
        for b in &mut bv {
            *b /= vol;
        }
        bvbar.push(bv);
        // characteristic length: area / longest diagonal
        let area = 0.5 * ((xr[2] - xr[0]) * (xz[3] - xz[1]) - (xr[3] - xr[1]) * (xz[2] - xz[0]));
        let d1 = ((xr[2] - xr[0]).powi(2) + (xz[2] - xz[0]).powi(2)).sqrt();
        let d2 = ((xr[3] - xr[1]).powi(2) + (xz[3] - xz[1]).powi(2)).sqrt();
        let le = area / d1.max(d2);
        if in_sphere {
            lmin_sphere = lmin_sphere.min(le);
        } else {
            lmin_wall = lmin_wall.min(le);
        }
    }
    ElementGeometry {
        gps,
        bvbar,
        mass,
        lmin_sphere,
        lmin_wall,
    }
}

/// Contact slaves: the sphere's surface nodes up to z = 0.3 R, with their tributary annulus
/// areas π(r_h² − r_l²) (midpoints to the neighbouring surface nodes).
pub(super) fn contact_slaves(mesh: &Mesh, radius: f64) -> (Vec<u32>, Vec<f64>) {
    let surf = &mesh.sphere_surface;
    let mut slaves = Vec::new();
    let mut slave_area = Vec::new();
    for (k, &s) in surf.iter().enumerate() {
        if mesh.z[s as usize] > 0.3 * radius {
            break;
        }
        let r = mesh.r[s as usize];
        let rl = if k == 0 {
            0.0
        } else {
            0.5 * (r + mesh.r[surf[k - 1] as usize])
        };
        let rh = 0.5 * (r + mesh.r[surf[k + 1] as usize]);
        slaves.push(s);
        slave_area.push(std::f64::consts::PI * (rh * rh - rl * rl));
    }
    (slaves, slave_area)
}

/// Stable step of the elements, $\min_e L_e/c_p$ with the P-wave speed from the algorithmic
/// (critical) moduli at step `dt` (Prony materials); `wall` is `None` for a rigid plane.
pub(super) fn element_time_step(
    sphere: &Material,
    wall: Option<&Material>,
    lmin_sphere: f64,
    lmin_wall: f64,
    dt: f64,
) -> f64 {
    let cp = |mat: &Material, dt: f64| {
        let (k, g) = Kernel::critical_moduli(mat, dt);
        ((k + 4.0 / 3.0 * g) / mat.density_kg_m3).sqrt()
    };
    let mut dte = lmin_sphere / cp(sphere, dt);
    if let Some(wall_mat) = wall {
        dte = dte.min(lmin_wall / cp(wall_mat, dt));
    }
    dte
}

/// Stable step of the contact penalty springs, 2/ω_max with ω² = ε_N A (1/m_slave +
/// 1/m_wall node); `wall_surface` is `None` for a rigid plane.
pub(super) fn penalty_time_step(
    slaves: &[u32],
    slave_area: &[f64],
    penalty: f64,
    inv_m: &[f64],
    wall_surface: Option<&[u32]>,
) -> f64 {
    let mut w2 = 0.0f64;
    for (k, &s) in slaves.iter().enumerate() {
        let kk = penalty * slave_area[k];
        let mw = match wall_surface {
            None => 0.0,
            Some(ws) => inv_m[ws[k.min(ws.len() - 1)] as usize],
        };
        w2 = w2.max(kk * (inv_m[s as usize] + mw));
    }
    2.0 / w2.sqrt()
}

/// The bodies: the sphere and (unless `wall` is `None`, a rigid plane) the wall, each with
/// its material kernel at step `dt` and zeroed state at its Gauss points.
pub(super) fn build_bodies(
    mesh: &Mesh,
    sphere: &Material,
    wall: Option<&Material>,
    dt: f64,
) -> Vec<Body> {
    let mut bodies = Vec::new();
    let mut add_body = |mat: &Material, elems: std::ops::Range<usize>| {
        let kernel = Kernel::new(mat, dt);
        let n_state = kernel.n_state();
        let ngp = 4 * elems.len();
        bodies.push(Body {
            elems,
            n_state,
            state: vec![0.0; n_state * ngp],
            kernel,
            plastic: matches!(mat.model, MaterialModel::ViscoplasticJ2 { .. }),
            dissipated: 0.0,
        });
    };
    add_body(sphere, mesh.sphere_elems.clone());
    if let Some(wall_mat) = wall {
        add_body(wall_mat, mesh.wall_elems.clone());
    }
    bodies
}
