//! Thin rectangular plates in bending: the Kirchhoff plate on a structured mesh of ACM
//! rectangles (Adini–Clough–Melosh, 12 dofs: $w$, $\theta_x = \partial w/\partial y$,
//! $\theta_y = -\partial w/\partial x$ per corner; Zienkiewicz & Taylor, The Finite Element
//! Method, Vol. 2, Sect. 4.4). The element passes the patch test and converges to the
//! Kirchhoff solution; it is what a user's FE program would export as a shell model's
//! out-of-plane part. pdamp reads plates as Matrix Market K and M
//! ([`crate::matrix_market`]); this module writes such a pair for examples and tests
//! (`cargo run -p pdamp-structure --example export_plate`), checked against Leissa's
//! cantilever-plate frequencies.
//!
//! Stiffness $K_e = \int B^T D B\,dA$ with the curvatures
//! $\kappa = (w_{,xx}, w_{,yy}, 2w_{,xy})$ and $D = \frac{Eh^3}{12(1-\nu^2)}
//! \begin{pmatrix}1&\nu&0\\ \nu&1&0\\ 0&0&(1-\nu)/2\end{pmatrix}$; consistent mass
//! $M_e = \rho h\int N^T N\,dA$ (rotary inertia neglected, thin plate). Both by 4 × 4 Gauss
//! points (exact for the element's polynomials).

use super::{Assembled, Dof, FeError};
use nalgebra::{DMatrix, SMatrix};

/// A rectangular Kirchhoff plate `[0, length] × [0, width]` in the x–y plane, deflecting
/// along z, clamped along the edge x = 0 (a cantilever plate) or free.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plate {
    /// Length along x, m.
    pub length_m: f64,
    /// Width along y, m.
    pub width_m: f64,
    /// Thickness h, m.
    pub thickness_m: f64,
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
    /// Density ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Elements along x.
    pub elements_x: usize,
    /// Elements along y.
    pub elements_y: usize,
    /// Clamp the edge x = 0 (all three dofs of its nodes removed).
    pub clamped_at_x0: bool,
}

/// Monomials ξ^p η^q of the ACM element, (p, q).
const TERMS: [(i32, i32); 12] = [
    (0, 0),
    (1, 0),
    (0, 1),
    (2, 0),
    (1, 1),
    (0, 2),
    (3, 0),
    (2, 1),
    (1, 2),
    (0, 3),
    (3, 1),
    (1, 3),
];

/// ∂^(dx+dy)/∂ξ^dx∂η^dy of ξ^p η^q at (ξ, η).
fn monomial(p: i32, q: i32, dx: i32, dy: i32, xi: f64, eta: f64) -> f64 {
    let fall = |n: i32, d: i32| -> f64 { (0..d).map(|k| (n - k) as f64).product() };
    if dx > p || dy > q {
        return 0.0;
    }
    fall(p, dx) * fall(q, dy) * xi.powi(p - dx) * eta.powi(q - dy)
}

/// Row vector of the 12 monomials' derivative (dx, dy) at (ξ, η).
fn basis(dx: i32, dy: i32, xi: f64, eta: f64) -> SMatrix<f64, 1, 12> {
    SMatrix::<f64, 1, 12>::from_fn(|_, j| monomial(TERMS[j].0, TERMS[j].1, dx, dy, xi, eta))
}

/// 4-point Gauss–Legendre on [0, 1]: (points, weights).
fn gauss4() -> ([f64; 4], [f64; 4]) {
    let a = (3.0 / 7.0 - 2.0 / 7.0 * (6.0_f64 / 5.0).sqrt()).sqrt();
    let b = (3.0 / 7.0 + 2.0 / 7.0 * (6.0_f64 / 5.0).sqrt()).sqrt();
    let wa = (18.0 + 30.0_f64.sqrt()) / 36.0;
    let wb = (18.0 - 30.0_f64.sqrt()) / 36.0;
    let x = [-b, -a, a, b].map(|t| 0.5 * (t + 1.0));
    (x, [wb / 2.0, wa / 2.0, wa / 2.0, wb / 2.0])
}

/// Corner order of the element (ξ, η): (0,0), (1,0), (1,1), (0,1).
const CORNERS: [(f64, f64); 4] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];

impl Plate {
    /// The plate of `examples/structure_plate.toml`: steel 250 × 250 × 3 mm (E = 210 GPa,
    /// ν = 0.3, ρ = 7850 kg/m³), clamped along x = 0, 12 × 12 elements.
    pub const EXAMPLE: Plate = Plate {
        length_m: 0.25,
        width_m: 0.25,
        thickness_m: 0.003,
        youngs_modulus_pa: 210e9,
        poisson_ratio: 0.3,
        density_kg_m3: 7850.0,
        elements_x: 12,
        elements_y: 12,
        clamped_at_x0: true,
    };

    /// Flexural rigidity $D = Eh^3/(12(1-\nu^2))$, N·m.
    pub fn flexural_rigidity_n_m(&self) -> f64 {
        self.youngs_modulus_pa * self.thickness_m.powi(3)
            / (12.0 * (1.0 - self.poisson_ratio * self.poisson_ratio))
    }

    /// Angular frequency of a frequency parameter $\lambda = \omega a^2\sqrt{\rho h/D}$
    /// (Leissa's normalisation with a = the length along x), rad/s.
    pub fn omega_of_lambda(&self, lambda: f64) -> f64 {
        lambda / self.length_m.powi(2)
            * (self.flexural_rigidity_n_m() / (self.density_kg_m3 * self.thickness_m)).sqrt()
    }

    /// Node id (0-based) of grid node (i along x, j along y).
    pub fn node(&self, i: usize, j: usize) -> usize {
        j * (self.elements_x + 1) + i
    }

    /// Element stiffness and mass (12 × 12, dofs per corner w, θx, θy).
    fn element(&self) -> (SMatrix<f64, 12, 12>, SMatrix<f64, 12, 12>) {
        let a = self.length_m / self.elements_x as f64;
        let b = self.width_m / self.elements_y as f64;
        // C: the corner dofs of each monomial; N = P C⁻¹
        let mut c = SMatrix::<f64, 12, 12>::zeros();
        for (n, &(xi, eta)) in CORNERS.iter().enumerate() {
            c.set_row(3 * n, &basis(0, 0, xi, eta));
            c.set_row(3 * n + 1, &(basis(0, 1, xi, eta) / b));
            c.set_row(3 * n + 2, &(-basis(1, 0, xi, eta) / a));
        }
        let ci = c.try_inverse().expect("the ACM corner matrix is regular");
        let dr = self.flexural_rigidity_n_m();
        let nu = self.poisson_ratio;
        let d = nalgebra::Matrix3::new(
            dr,
            nu * dr,
            0.0,
            nu * dr,
            dr,
            0.0,
            0.0,
            0.0,
            0.5 * (1.0 - nu) * dr,
        );
        let rho_h = self.density_kg_m3 * self.thickness_m;
        let (x, w) = gauss4();
        let mut k = SMatrix::<f64, 12, 12>::zeros();
        let mut m = SMatrix::<f64, 12, 12>::zeros();
        for (xi, wx) in x.iter().zip(&w) {
            for (eta, wy) in x.iter().zip(&w) {
                let mut bm = SMatrix::<f64, 3, 12>::zeros();
                bm.set_row(0, &(basis(2, 0, *xi, *eta) / (a * a)));
                bm.set_row(1, &(basis(0, 2, *xi, *eta) / (b * b)));
                bm.set_row(2, &(basis(1, 1, *xi, *eta) * (2.0 / (a * b))));
                let bm = bm * ci;
                let n = basis(0, 0, *xi, *eta) * ci;
                let da = wx * wy * a * b;
                k += bm.transpose() * d * bm * da;
                m += n.transpose() * n * (rho_h * da);
            }
        }
        (k, m)
    }

    /// Assembles K and M on the active dofs (rows: (node, UZ | ROTX | ROTY)).
    ///
    /// # Errors
    /// Non-positive sizes, properties or element counts (named).
    pub fn assemble(&self) -> Result<Assembled, FeError> {
        for (key, v) in [
            ("length_m", self.length_m),
            ("width_m", self.width_m),
            ("thickness_m", self.thickness_m),
            ("youngs_modulus_pa", self.youngs_modulus_pa),
            ("density_kg_m3", self.density_kg_m3),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(FeError::Plate {
                    key,
                    message: format!("must be a positive number, got {v}"),
                });
            }
        }
        if !(0.0..0.5).contains(&self.poisson_ratio) {
            return Err(FeError::Plate {
                key: "poisson_ratio",
                message: format!("must be in [0, 0.5), got {}", self.poisson_ratio),
            });
        }
        if self.elements_x == 0 || self.elements_y == 0 {
            return Err(FeError::Plate {
                key: "elements_x, elements_y",
                message: "at least one element each".into(),
            });
        }
        let (ke, me) = self.element();
        let (nx, ny) = (self.elements_x, self.elements_y);
        let nodes = (nx + 1) * (ny + 1);
        let order = [Dof::Uz, Dof::Rx, Dof::Ry];
        let mut row = vec![usize::MAX; 3 * nodes];
        let mut dofs = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                if self.clamped_at_x0 && i == 0 {
                    continue;
                }
                let n = self.node(i, j);
                for (l, &dof) in order.iter().enumerate() {
                    row[3 * n + l] = dofs.len();
                    dofs.push((n, dof));
                }
            }
        }
        let na = dofs.len();
        let mut k = DMatrix::<f64>::zeros(na, na);
        let mut m = DMatrix::<f64>::zeros(na, na);
        for ej in 0..ny {
            for ei in 0..nx {
                let corner = [
                    self.node(ei, ej),
                    self.node(ei + 1, ej),
                    self.node(ei + 1, ej + 1),
                    self.node(ei, ej + 1),
                ];
                let g: Vec<usize> = corner
                    .iter()
                    .flat_map(|&n| (0..3).map(move |l| 3 * n + l))
                    .map(|d| row[d])
                    .collect();
                for (p, &r) in g.iter().enumerate() {
                    if r == usize::MAX {
                        continue;
                    }
                    for (q, &c) in g.iter().enumerate() {
                        if c != usize::MAX {
                            k[(r, c)] += ke[(p, q)];
                            m[(r, c)] += me[(p, q)];
                        }
                    }
                }
            }
        }
        Ok(Assembled {
            stiffness: k,
            mass: m,
            dofs,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example plate on an n × n mesh, clamped or free.
    fn plate(n: usize, clamped: bool) -> Plate {
        Plate {
            elements_x: n,
            elements_y: n,
            clamped_at_x0: clamped,
            ..Plate::EXAMPLE
        }
    }

    /// Total mass: every rigid translation w = 1 gives uᵀMu = ρhA (1e-12).
    #[test]
    fn mass_of_a_rigid_translation_is_the_plate_mass() {
        let p = plate(4, false);
        let a = p.assemble().unwrap();
        let u: Vec<f64> = a
            .dofs
            .iter()
            .map(|d| if d.1 == Dof::Uz { 1.0 } else { 0.0 })
            .collect();
        let u = nalgebra::DVector::from_vec(u);
        let mass = (u.transpose() * &a.mass * &u)[(0, 0)];
        let exact = 7850.0 * 0.003 * 0.25 * 0.25;
        assert!((mass / exact - 1.0).abs() < 1e-12, "{mass} vs {exact}");
        // rigid translation and rigid rotation store no strain energy
        let ku = &a.stiffness * &u;
        assert!(ku.amax() < 1e-9 * a.stiffness.amax(), "{}", ku.amax());
    }

    /// Constant curvature w = x²/2 (θy = −x) is reproduced exactly (patch test): the strain
    /// energy of a free plate is D A / 2 · 1 (1e-10).
    #[test]
    fn constant_curvature_patch_gives_the_exact_energy() {
        let p = plate(3, false);
        let a = p.assemble().unwrap();
        let h = 0.25 / 3.0;
        let u: Vec<f64> = a
            .dofs
            .iter()
            .map(|&(n, d)| {
                let x = (n % 4) as f64 * h;
                match d {
                    Dof::Uz => 0.5 * x * x,
                    Dof::Ry => -x,
                    _ => 0.0,
                }
            })
            .collect();
        let u = nalgebra::DVector::from_vec(u);
        let e = 0.5 * (u.transpose() * &a.stiffness * &u)[(0, 0)];
        let exact = 0.5 * p.flexural_rigidity_n_m() * 0.25 * 0.25;
        assert!((e / exact - 1.0).abs() < 1e-10, "{e} vs {exact}");
    }

    /// Eigenfrequency parameters λ = ωa²√(ρh/D) of a K, M pair (dense, for tests).
    fn lambdas(p: &Plate, a: &Assembled, count: usize) -> Vec<f64> {
        let f =
            |m: &DMatrix<f64>| faer::Mat::<f64>::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)]);
        let modes = crate::eigen::dense_lowest_modes(
            f(&a.stiffness).as_ref(),
            f(&a.mass).as_ref(),
            count,
            0.0,
        )
        .unwrap();
        modes
            .omega_rad_s
            .iter()
            .map(|&w| w / p.omega_of_lambda(1.0))
            .collect()
    }

    /// The cantilever (CFFF) square plate, ν = 0.3: Leissa, Vibration of Plates (NASA SP-160,
    /// 1969), Table 4.51: λ = 3.492, 8.525, 21.43, 27.33, 31.11 (Ritz upper bounds). The
    /// 12 × 12 ACM mesh is within 1.5 % of each and converged (6 × 6 → 12 × 12 moves λ by
    /// less than 0.5 %).
    #[test]
    fn cantilever_square_plate_matches_leissa() {
        let leissa = [3.492, 8.525, 21.43, 27.33, 31.11];
        let coarse = lambdas(&plate(6, true), &plate(6, true).assemble().unwrap(), 5);
        let fine = lambdas(&plate(12, true), &plate(12, true).assemble().unwrap(), 5);
        for k in 0..5 {
            let (ec, ef) = (coarse[k] / leissa[k] - 1.0, fine[k] / leissa[k] - 1.0);
            println!(
                "mode {}: λ 6×6 {:.4}, 12×12 {:.4}, Leissa {} ({:+.2} %)",
                k + 1,
                coarse[k],
                fine[k],
                leissa[k],
                100.0 * ef
            );
            assert!(
                ef.abs() < 0.015,
                "mode {}: {} vs {}",
                k + 1,
                fine[k],
                leissa[k]
            );
            // mesh-converged: halving the element size moves λ by less than 0.5 %
            assert!((ef - ec).abs() < 0.005, "mode {}: not converged", k + 1);
        }
    }
}
