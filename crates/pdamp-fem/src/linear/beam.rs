//! 3D two-node beam element (12 dof: $u, v, w, \theta_x, \theta_y, \theta_z$ per node) with
//! Euler–Bernoulli or Timoshenko bending stiffness and the consistent (cubic Hermite) mass matrix
//! [Przemieniecki 1968, ch. 5 and 11].
//!
//! Local axes: $x$ along the element from node 1 to node 2; the section's local $y$ axis lies in
//! the plane spanned by $x$ and the orientation vector; $z = x \times y$. Bending in the local
//! $x$–$y$ plane (deflection $v$) uses $I_z$, bending in $x$–$z$ (deflection $w$) uses $I_y$.

use super::FeError;
use nalgebra::{Matrix3, SMatrix, Vector3};
use serde::{Deserialize, Serialize};

/// 12 × 12 element matrix.
pub type Mat12 = SMatrix<f64, 12, 12>;

/// Cross-section and material of a beam element (SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSection {
    /// Young's modulus E, Pa.
    pub youngs_modulus_pa: f64,
    /// Shear modulus G, Pa.
    pub shear_modulus_pa: f64,
    /// Density ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Cross-sectional area A, m².
    pub area_m2: f64,
    /// Second moment of area about the local y axis (bending in x–z), m⁴.
    pub iy_m4: f64,
    /// Second moment of area about the local z axis (bending in x–y), m⁴.
    pub iz_m4: f64,
    /// Torsion constant J, m⁴.
    pub torsion_constant_m4: f64,
    /// Timoshenko shear coefficient κ (5/6 for rectangles); `None` gives Euler–Bernoulli.
    #[serde(default)]
    pub shear_coefficient: Option<f64>,
}

impl BeamSection {
    /// Rectangular solid section `width_m` (local z extent) × `height_m` (local y extent):
    /// $I_z = b h^3/12$, $I_y = h b^3/12$, Saint-Venant $J \approx \beta\, a b^3$ with the
    /// series approximation $\beta = \tfrac13 - 0.21\tfrac{b}{a}(1 - \tfrac{b^4}{12a^4})$ (a ≥ b).
    pub fn rectangle(
        width_m: f64,
        height_m: f64,
        youngs_modulus_pa: f64,
        poisson_ratio: f64,
        density_kg_m3: f64,
        timoshenko: bool,
    ) -> Self {
        let (a, b) = if width_m >= height_m {
            (width_m, height_m)
        } else {
            (height_m, width_m)
        };
        let r = b / a;
        let beta = 1.0 / 3.0 - 0.21 * r * (1.0 - r.powi(4) / 12.0);
        Self {
            youngs_modulus_pa,
            shear_modulus_pa: youngs_modulus_pa / (2.0 * (1.0 + poisson_ratio)),
            density_kg_m3,
            area_m2: width_m * height_m,
            iy_m4: height_m * width_m.powi(3) / 12.0,
            iz_m4: width_m * height_m.powi(3) / 12.0,
            torsion_constant_m4: beta * a * b.powi(3),
            shear_coefficient: timoshenko.then_some(5.0 / 6.0),
        }
    }

    /// Checks that all properties are finite and positive.
    pub fn validate(&self) -> Result<(), FeError> {
        let fields = [
            ("youngs_modulus_pa", self.youngs_modulus_pa),
            ("shear_modulus_pa", self.shear_modulus_pa),
            ("density_kg_m3", self.density_kg_m3),
            ("area_m2", self.area_m2),
            ("iy_m4", self.iy_m4),
            ("iz_m4", self.iz_m4),
            ("torsion_constant_m4", self.torsion_constant_m4),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(FeError::Section { name, value: v });
            }
        }
        if let Some(k) = self.shear_coefficient
            && !(k.is_finite() && k > 0.0)
        {
            return Err(FeError::ShearCoefficient { value: k });
        }
        Ok(())
    }
}

/// Rotation matrix whose rows are the local axes (x, y, z) in global coordinates.
///
/// # Errors
/// Zero length or an orientation vector parallel to the element axis.
pub fn local_axes(
    x1: [f64; 3],
    x2: [f64; 3],
    orientation: [f64; 3],
) -> Result<Matrix3<f64>, FeError> {
    let d = Vector3::from(x2) - Vector3::from(x1);
    let l = d.norm();
    if !(l > 0.0 && l.is_finite()) {
        return Err(FeError::ZeroLength);
    }
    let ex = d / l;
    let v = Vector3::from(orientation);
    let ez = ex.cross(&v);
    if ez.norm() < 1e-9 * v.norm().max(1e-300) {
        return Err(FeError::ParallelOrientation { orientation });
    }
    let ez = ez.normalize();
    let ey = ez.cross(&ex);
    Ok(Matrix3::from_rows(&[
        ex.transpose(),
        ey.transpose(),
        ez.transpose(),
    ]))
}

/// Element stiffness matrix in local coordinates. With a shear coefficient κ the bending blocks
/// carry the Timoshenko shear parameter $\Phi = 12 E I / (\kappa G A L^2)$.
pub fn local_stiffness(s: &BeamSection, l: f64) -> Mat12 {
    let mut k = Mat12::zeros();
    let e = s.youngs_modulus_pa;
    let ea = e * s.area_m2 / l;
    let gj = s.shear_modulus_pa * s.torsion_constant_m4 / l;
    let phi = |i: f64| match s.shear_coefficient {
        Some(kappa) => 12.0 * e * i / (kappa * s.shear_modulus_pa * s.area_m2 * l * l),
        None => 0.0,
    };
    let mut put = |i: usize, j: usize, v: f64| {
        k[(i, j)] += v;
        if i != j {
            k[(j, i)] += v;
        }
    };
    // Axial (0, 6) and torsion (3, 9).
    put(0, 0, ea);
    put(6, 6, ea);
    put(0, 6, -ea);
    put(3, 3, gj);
    put(9, 9, gj);
    put(3, 9, -gj);
    // Bending in x–y: v (1, 7), θz (5, 11), I_z.
    let p = phi(s.iz_m4);
    let c = e * s.iz_m4 / (l.powi(3) * (1.0 + p));
    put(1, 1, 12.0 * c);
    put(7, 7, 12.0 * c);
    put(1, 7, -12.0 * c);
    put(1, 5, 6.0 * l * c);
    put(1, 11, 6.0 * l * c);
    put(7, 5, -6.0 * l * c);
    put(7, 11, -6.0 * l * c);
    put(5, 5, (4.0 + p) * l * l * c);
    put(11, 11, (4.0 + p) * l * l * c);
    put(5, 11, (2.0 - p) * l * l * c);
    // Bending in x–z: w (2, 8), θy (4, 10), I_y; θy = −dw/dx flips the coupling signs.
    let p = phi(s.iy_m4);
    let c = e * s.iy_m4 / (l.powi(3) * (1.0 + p));
    put(2, 2, 12.0 * c);
    put(8, 8, 12.0 * c);
    put(2, 8, -12.0 * c);
    put(2, 4, -6.0 * l * c);
    put(2, 10, -6.0 * l * c);
    put(8, 4, 6.0 * l * c);
    put(8, 10, 6.0 * l * c);
    put(4, 4, (4.0 + p) * l * l * c);
    put(10, 10, (4.0 + p) * l * l * c);
    put(4, 10, (2.0 - p) * l * l * c);
    k
}

/// Consistent mass matrix in local coordinates: linear axial/torsion interpolation and cubic
/// Hermite bending interpolation (Euler–Bernoulli consistent mass, also used with Timoshenko
/// stiffness; the rotary-inertia and shear corrections of the mass are of order
/// $(r_g/L_{el})^2$ and negligible for the slender beams modelled here).
pub fn local_mass(s: &BeamSection, l: f64) -> Mat12 {
    let mut m = Mat12::zeros();
    let rho_a_l = s.density_kg_m3 * s.area_m2 * l;
    let ip = s.density_kg_m3 * (s.iy_m4 + s.iz_m4) * l;
    let mut put = |i: usize, j: usize, v: f64| {
        m[(i, j)] += v;
        if i != j {
            m[(j, i)] += v;
        }
    };
    put(0, 0, rho_a_l / 3.0);
    put(6, 6, rho_a_l / 3.0);
    put(0, 6, rho_a_l / 6.0);
    put(3, 3, ip / 3.0);
    put(9, 9, ip / 3.0);
    put(3, 9, ip / 6.0);
    let c = rho_a_l / 420.0;
    // x–y plane: v (1, 7), θz (5, 11).
    put(1, 1, 156.0 * c);
    put(7, 7, 156.0 * c);
    put(1, 7, 54.0 * c);
    put(1, 5, 22.0 * l * c);
    put(1, 11, -13.0 * l * c);
    put(7, 5, 13.0 * l * c);
    put(7, 11, -22.0 * l * c);
    put(5, 5, 4.0 * l * l * c);
    put(11, 11, 4.0 * l * l * c);
    put(5, 11, -3.0 * l * l * c);
    // x–z plane: w (2, 8), θy (4, 10), opposite coupling signs.
    put(2, 2, 156.0 * c);
    put(8, 8, 156.0 * c);
    put(2, 8, 54.0 * c);
    put(2, 4, -22.0 * l * c);
    put(2, 10, 13.0 * l * c);
    put(8, 4, -13.0 * l * c);
    put(8, 10, 22.0 * l * c);
    put(4, 4, 4.0 * l * l * c);
    put(10, 10, 4.0 * l * l * c);
    put(4, 10, -3.0 * l * l * c);
    m
}

/// Global stiffness and mass matrices $T^T K_l T$, $T^T M_l T$ of one element.
pub fn global_matrices(
    s: &BeamSection,
    x1: [f64; 3],
    x2: [f64; 3],
    orientation: [f64; 3],
) -> Result<(Mat12, Mat12), FeError> {
    let r = local_axes(x1, x2, orientation)?;
    let l = (Vector3::from(x2) - Vector3::from(x1)).norm();
    let mut t = Mat12::zeros();
    for b in 0..4 {
        t.fixed_view_mut::<3, 3>(3 * b, 3 * b).copy_from(&r);
    }
    let k = t.transpose() * local_stiffness(s, l) * t;
    let m = t.transpose() * local_mass(s, l) * t;
    Ok((k, m))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_body_motions_are_stress_free_and_mass_is_conserved() {
        let s = BeamSection::rectangle(0.08, 0.002, 200e9, 0.3, 7850.0, true);
        let (k, m) =
            global_matrices(&s, [0.1, 0.2, 0.3], [0.4, -0.1, 0.5], [0.0, 0.0, 1.0]).unwrap();
        let a = [0.3, -0.2, 0.7];
        let p1 = Vector3::new(0.1, 0.2, 0.3);
        let p2 = Vector3::new(0.4, -0.1, 0.5);
        let w = Vector3::new(0.2, 0.5, -0.1);
        // translation + small rotation: u = a + w × x, θ = w
        let mut u = nalgebra::SVector::<f64, 12>::zeros();
        for (n, p) in [p1, p2].iter().enumerate() {
            let d = Vector3::from(a) + w.cross(p);
            for i in 0..3 {
                u[6 * n + i] = d[i];
                u[6 * n + 3 + i] = w[i];
            }
        }
        let f = k * u;
        assert!(f.norm() < 1e-6 * k.norm() * u.norm(), "{}", f.norm());
        // Total mass from a unit translation: uᵀ M u = ρ A L.
        let mut t = nalgebra::SVector::<f64, 12>::zeros();
        t[0] = 1.0;
        t[6] = 1.0;
        let l = (p2 - p1).norm();
        let mass = (t.transpose() * m * t)[(0, 0)];
        assert!((mass - s.density_kg_m3 * s.area_m2 * l).abs() < 1e-12 * mass);
    }
}
