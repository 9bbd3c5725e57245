//! Linear 8-node hexahedron (3 translational dof per node), isotropic linear elasticity,
//! 2 × 2 × 2 Gauss integration, consistent mass. Optionally with the nine incompatible bending
//! modes of Wilson/Taylor (shape functions $1-\xi^2$, $1-\eta^2$, $1-\zeta^2$ per direction,
//! derivatives taken with the centre Jacobian, condensed statically), which removes the shear
//! locking of the plain element in bending [Taylor, Beresford & Wilson 1976].
//!
//! Node order: $(\xi,\eta,\zeta)$ = (−,−,−), (+,−,−), (+,+,−), (−,+,−), (−,−,+), (+,−,+),
//! (+,+,+), (−,+,+).

use super::FeError;
use crate::solid::hex8::{CORNERS, shape};
use nalgebra::{DMatrix, Matrix3, SMatrix, Vector3};

/// 24 × 24 element matrix.
pub type Mat24 = SMatrix<f64, 24, 24>;

/// Isotropic material of a solid element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidMaterial {
    /// Young's modulus, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
    /// Density, kg/m³.
    pub density_kg_m3: f64,
}

fn elasticity(mat: &SolidMaterial) -> SMatrix<f64, 6, 6> {
    let (e, nu) = (mat.youngs_modulus_pa, mat.poisson_ratio);
    let c = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mut d = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            d[(i, j)] = c * if i == j { 1.0 - nu } else { nu };
        }
        d[(i + 3, i + 3)] = c * (1.0 - 2.0 * nu) / 2.0;
    }
    d
}

fn jacobian(x: &[[f64; 3]; 8], dn: &[[f64; 3]; 8]) -> Matrix3<f64> {
    // J[i][j] = ∂x_j/∂ξ_i
    let mut j = Matrix3::zeros();
    for a in 0..8 {
        for i in 0..3 {
            for k in 0..3 {
                j[(i, k)] += dn[a][i] * x[a][k];
            }
        }
    }
    j
}

/// Strain–displacement rows for one node/mode with global derivatives `g` (∂/∂x, ∂/∂y, ∂/∂z).
fn b_block(g: Vector3<f64>) -> SMatrix<f64, 6, 3> {
    let mut b = SMatrix::<f64, 6, 3>::zeros();
    b[(0, 0)] = g[0];
    b[(1, 1)] = g[1];
    b[(2, 2)] = g[2];
    b[(3, 0)] = g[1];
    b[(3, 1)] = g[0];
    b[(4, 1)] = g[2];
    b[(4, 2)] = g[1];
    b[(5, 0)] = g[2];
    b[(5, 2)] = g[0];
    b
}

/// Stiffness and consistent mass matrices of one element with node coordinates `x` (m).
///
/// # Errors
/// A non-positive Jacobian determinant (inverted or degenerate element).
pub fn matrices(
    x: &[[f64; 3]; 8],
    mat: &SolidMaterial,
    incompatible_modes: bool,
) -> Result<(Mat24, Mat24), FeError> {
    let d = elasticity(mat);
    let g = 1.0 / 3f64.sqrt();
    let mut k = Mat24::zeros();
    let mut m = Mat24::zeros();
    let mut k_ci = DMatrix::<f64>::zeros(24, 9);
    let mut k_ii = DMatrix::<f64>::zeros(9, 9);
    let (_, dn0) = shape([0.0; 3]);
    let j0 = jacobian(x, &dn0);
    let det0 = j0.determinant();
    let j0_inv = j0.try_inverse().ok_or(FeError::SingularCentreJacobian)?;
    for gp in CORNERS.iter() {
        let xi = [gp[0] * g, gp[1] * g, gp[2] * g];
        let (n, dn) = shape(xi);
        let j = jacobian(x, &dn);
        let det = j.determinant();
        if det <= 0.0 || !det.is_finite() {
            return Err(FeError::NonPositiveJacobian { determinant: det });
        }
        let j_inv = j.try_inverse().ok_or(FeError::SingularJacobian)?;
        let mut b = SMatrix::<f64, 6, 24>::zeros();
        for (a, dna) in dn.iter().enumerate() {
            let gl = j_inv * Vector3::from(*dna);
            b.fixed_view_mut::<6, 3>(0, 3 * a).copy_from(&b_block(gl));
        }
        k += b.transpose() * d * b * det;
        for a in 0..8 {
            for c in 0..8 {
                let v = mat.density_kg_m3 * n[a] * n[c] * det;
                for i in 0..3 {
                    m[(3 * a + i, 3 * c + i)] += v;
                }
            }
        }
        if incompatible_modes {
            // P_i = 1 − ξ_i², ∂P_i/∂ξ_i = −2ξ_i, mapped with J0 and scaled by det0/det.
            let mut bi = DMatrix::<f64>::zeros(6, 9);
            for mode in 0..3 {
                let mut dnat = Vector3::zeros();
                dnat[mode] = -2.0 * xi[mode];
                let gl = j0_inv * dnat * (det0 / det);
                let blk = b_block(gl);
                for r in 0..6 {
                    for c in 0..3 {
                        bi[(r, 3 * mode + c)] = blk[(r, c)];
                    }
                }
            }
            let bc = DMatrix::from_column_slice(6, 24, b.as_slice());
            let dd = DMatrix::from_column_slice(6, 6, d.as_slice());
            k_ci += bc.transpose() * &dd * &bi * det;
            k_ii += bi.transpose() * &dd * &bi * det;
        }
    }
    if incompatible_modes {
        let inv = k_ii
            .try_inverse()
            .ok_or(FeError::SingularIncompatibleModes)?;
        let corr = &k_ci * inv * k_ci.transpose();
        for r in 0..24 {
            for c in 0..24 {
                k[(r, c)] -= corr[(r, c)];
            }
        }
    }
    Ok((k, m))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brick(a: f64, b: f64, c: f64) -> [[f64; 3]; 8] {
        let mut x = [[0.0; 3]; 8];
        for (i, s) in CORNERS.iter().enumerate() {
            x[i] = [
                (s[0] + 1.0) * a / 2.0,
                (s[1] + 1.0) * b / 2.0,
                (s[2] + 1.0) * c / 2.0,
            ];
        }
        x
    }

    /// Patch-type checks: six rigid-body modes (zero energy), a uniform axial strain gives
    /// the uniaxial-stress energy, mass sums to ρV.
    #[test]
    fn rigid_modes_uniform_strain_and_mass() {
        for inc in [false, true] {
            let mat = SolidMaterial {
                youngs_modulus_pa: 210e9,
                poisson_ratio: 0.0,
                density_kg_m3: 7800.0,
            };
            let x = brick(0.3, 0.1, 0.2);
            let (k, m) = matrices(&x, &mat, inc).unwrap();
            let kf = faer::Mat::<f64>::from_fn(24, 24, |i, j| k[(i, j)]);
            let (ev, _) = crate::eigen::symmetric_evd(kf.as_ref()).unwrap();
            let kmax = ev[23];
            assert!(ev[5].abs() < 1e-9 * kmax && ev[6] > 1e-6 * kmax, "{ev:?}");
            // uniform ε_x = 1e-3 with ν = 0: energy ½ E ε² V
            let mut u = SMatrix::<f64, 24, 1>::zeros();
            for a in 0..8 {
                u[3 * a] = 1e-3 * x[a][0];
            }
            let energy = 0.5 * (u.transpose() * k * u)[(0, 0)];
            let exact = 0.5 * 210e9 * 1e-6 * 0.3 * 0.1 * 0.2;
            assert!((energy - exact).abs() < 1e-9 * exact, "{energy} {exact}");
            let mut t = SMatrix::<f64, 24, 1>::zeros();
            for a in 0..8 {
                t[3 * a + 1] = 1.0;
            }
            let mass = (t.transpose() * m * t)[(0, 0)];
            assert!((mass - 7800.0 * 0.006).abs() < 1e-9 * mass);
        }
    }
}
