//! Total-Lagrangian hex8 with the Saint Venant–Kirchhoff law (paper Sect. 2.2, eq. 8):
//! $\mathbf F = \mathbf I + \nabla_0\mathbf d$, $\mathbf E = \tfrac12(\mathbf F^\top\mathbf F-\mathbf I)$,
//! $\mathbf S = \lambda\,\mathrm{tr}\mathbf E\,\mathbf I + 2\mu\mathbf E$, strain energy
//! $\Psi = \tfrac\lambda2(\mathrm{tr}\mathbf E)^2 + \mu\,\mathbf E:\mathbf E$; internal force
//! $f_{aI} = \int F_{iJ}S_{JK}\,\partial_K N_a\,dV_0$; 2 × 2 × 2 Gauss points.

use rayon::prelude::*;

use super::hex8::element_gauss_points;
pub use super::hex8::{GaussPoint, shape};
use super::mesh::HexMesh;

/// Isotropic Saint Venant–Kirchhoff material.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SvkMaterial {
    /// Young's modulus \[Pa\] (paper Table A.3: 175 GPa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio (Table A.3: 0.27).
    pub poisson_ratio: f64,
    /// Reference density [kg/m³] (Table A.3: 8000).
    pub density_kg_m3: f64,
}

impl SvkMaterial {
    /// 316L as in paper Table A.3.
    pub const STEEL_316L: SvkMaterial = SvkMaterial {
        youngs_modulus_pa: 175e9,
        poisson_ratio: 0.27,
        density_kg_m3: 8000.0,
    };
    /// Lamé constants (λ, μ) \[Pa\].
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus_pa, self.poisson_ratio);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }
}

/// Gauss-point data of every element (8 points each).
///
/// # Panics
/// If an element is inverted or degenerate (det J ≤ 0).
pub fn precompute(mesh: &HexMesh) -> Vec<[GaussPoint; 8]> {
    mesh.elements
        .iter()
        .map(|el| element_gauss_points(&mesh.nodes, el))
        .collect()
}

/// Element volumes \[m³\].
pub fn element_volumes(mesh: &HexMesh) -> Vec<f64> {
    precompute(mesh)
        .iter()
        .map(|g| g.iter().map(|p| p.wdet).sum())
        .collect()
}

#[inline]
/// Displacement gradient $\mathbf H = \nabla_0\mathbf u$ ($\mathbf F = \mathbf I + \mathbf H$).
fn displacement_gradient(gp: &GaussPoint, u: &[[f64; 3]; 8]) -> [[f64; 3]; 3] {
    let mut f = [[0.0; 3]; 3];
    for a in 0..8 {
        for i in 0..3 {
            for k in 0..3 {
                f[i][k] += u[a][i] * gp.dn[a][k];
            }
        }
    }
    f
}

/// Green–Lagrange strain from $\mathbf H = \mathbf F - \mathbf I$ as
/// $\tfrac12(\mathbf H + \mathbf H^\top + \mathbf H^\top\mathbf H)$ (no cancellation of
/// $\mathbf F^\top\mathbf F - \mathbf I$ at small strains) and the PK2 stress.
#[inline]
fn green_pk2(f: &[[f64; 3]; 3], lam: f64, mu: f64) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let h = f;
    let mut e = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let hh = h[0][i] * h[0][j] + h[1][i] * h[1][j] + h[2][i] * h[2][j];
            e[i][j] = 0.5 * (h[i][j] + h[j][i] + hh);
        }
    }
    let tr = e[0][0] + e[1][1] + e[2][2];
    let mut s = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            s[i][j] = 2.0 * mu * e[i][j] + if i == j { lam * tr } else { 0.0 };
        }
    }
    (e, s)
}

/// Internal force (24 entries, node-major) and strain energy \[J\] of one element for nodal
/// displacements `u`.
#[inline]
pub fn element_force(
    gps: &[GaussPoint; 8],
    u: &[[f64; 3]; 8],
    lam: f64,
    mu: f64,
) -> ([f64; 24], f64) {
    let mut out = [0.0; 24];
    let mut w = 0.0;
    for gp in gps {
        let h = displacement_gradient(gp, u);
        let (e, s) = green_pk2(&h, lam, mu);
        let mut f = h;
        for (i, row) in f.iter_mut().enumerate() {
            row[i] += 1.0;
        }
        let tr = e[0][0] + e[1][1] + e[2][2];
        let ee: f64 = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| e[i][j] * e[i][j])
            .sum();
        w += (0.5 * lam * tr * tr + mu * ee) * gp.wdet;
        // P = F S (first Piola–Kirchhoff)
        let mut p = [[0.0; 3]; 3];
        for i in 0..3 {
            for k in 0..3 {
                p[i][k] = (f[i][0] * s[0][k] + f[i][1] * s[1][k] + f[i][2] * s[2][k]) * gp.wdet;
            }
        }
        for a in 0..8 {
            let d = gp.dn[a];
            for i in 0..3 {
                out[3 * a + i] += p[i][0] * d[0] + p[i][1] * d[1] + p[i][2] * d[2];
            }
        }
    }
    (out, w)
}

/// Tangent stiffness (24 × 24, row-major) of one element: material part
/// $\mathbf B^\top\mathbb C\mathbf B$ plus geometric part $(\nabla N_a\cdot\mathbf S\nabla N_b)\mathbf I$.
pub fn element_tangent(gps: &[GaussPoint; 8], u: &[[f64; 3]; 8], lam: f64, mu: f64) -> Vec<f64> {
    let mut k = vec![0.0; 576];
    for gp in gps {
        let h = displacement_gradient(gp, u);
        let (_, s) = green_pk2(&h, lam, mu);
        let mut f = h;
        for (i, row) in f.iter_mut().enumerate() {
            row[i] += 1.0;
        }
        // B (6 × 24) in Voigt order 11, 22, 33, 12, 23, 13 (engineering shear)
        let mut b = [[0.0; 24]; 6];
        for a in 0..8 {
            let d = gp.dn[a];
            for i in 0..3 {
                let c = 3 * a + i;
                b[0][c] = f[i][0] * d[0];
                b[1][c] = f[i][1] * d[1];
                b[2][c] = f[i][2] * d[2];
                b[3][c] = f[i][0] * d[1] + f[i][1] * d[0];
                b[4][c] = f[i][1] * d[2] + f[i][2] * d[1];
                b[5][c] = f[i][0] * d[2] + f[i][2] * d[0];
            }
        }
        // D B
        let mut db = [[0.0; 24]; 6];
        for c in 0..24 {
            let tr = b[0][c] + b[1][c] + b[2][c];
            for r in 0..3 {
                db[r][c] = lam * tr + 2.0 * mu * b[r][c];
            }
            for r in 3..6 {
                db[r][c] = mu * b[r][c];
            }
        }
        for r in 0..24 {
            for c in 0..24 {
                let mut v = 0.0;
                for q in 0..6 {
                    v += b[q][r] * db[q][c];
                }
                k[r * 24 + c] += v * gp.wdet;
            }
        }
        for a in 0..8 {
            for bb in 0..8 {
                let (da, db_) = (gp.dn[a], gp.dn[bb]);
                let mut g = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        g += da[i] * s[i][j] * db_[j];
                    }
                }
                g *= gp.wdet;
                for i in 0..3 {
                    k[(3 * a + i) * 24 + 3 * bb + i] += g;
                }
            }
        }
    }
    k
}

/// Consistent mass (8 × 8 scalar block, same for each direction) of one element \[kg\].
pub fn element_mass(gps: &[GaussPoint; 8], rho: f64) -> [[f64; 8]; 8] {
    let mut m = [[0.0; 8]; 8];
    for gp in gps {
        for a in 0..8 {
            for b in 0..8 {
                m[a][b] += rho * gp.n[a] * gp.n[b] * gp.wdet;
            }
        }
    }
    m
}

/// Assembled internal force vector (3 per node) and total strain energy \[J\]. Element forces are
/// computed in parallel and gathered in element order (deterministic for any thread count).
pub fn internal_force(
    mesh: &HexMesh,
    gps: &[[GaussPoint; 8]],
    d: &[f64],
    mat: &SvkMaterial,
    scratch: &mut Vec<[f64; 24]>,
    out: &mut [f64],
) -> f64 {
    let (lam, mu) = mat.lame();
    scratch.resize(mesh.elements.len(), [0.0; 24]);
    let energy: f64 = scratch
        .par_iter_mut()
        .with_min_len(256)
        .zip(mesh.elements.par_iter().zip(gps.par_iter()))
        .map(|(fe, (el, g))| {
            let mut u = [[0.0; 3]; 8];
            for a in 0..8 {
                u[a] = [d[3 * el[a]], d[3 * el[a] + 1], d[3 * el[a] + 2]];
            }
            let (f, w) = element_force(g, &u, lam, mu);
            *fe = f;
            w
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum();
    out.iter_mut().for_each(|x| *x = 0.0);
    for (el, fe) in mesh.elements.iter().zip(scratch.iter()) {
        for a in 0..8 {
            for i in 0..3 {
                out[3 * el[a] + i] += fe[3 * a + i];
            }
        }
    }
    energy
}
