//! Modal reduction [D Eq. 3.20–3.22] and the reduced structure [D Eq. 3.21, 3.23].
//!
//! The generalized eigenproblem $(K - \omega_k^2 M)\phi^{(k)} = 0$ is solved densely: with the
//! Cholesky factor $M = L L^T$ it becomes the standard symmetric problem
//! $L^{-1} K L^{-T} y = \omega^2 y$, $\phi = L^{-T} y$, which gives mass-normalised shapes
//! ($\Phi^T M \Phi = E$, $\Phi^T K \Phi = \Omega$), by faer's dense self-adjoint eigensolver
//! ([`pdamp_fem::dense_lowest_modes`]). Dense is adequate up to a few thousand dof.

use crate::StructureError;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The lowest modes of a generalized eigenproblem.
#[derive(Debug, Clone)]
pub struct ModalBasis {
    /// Angular eigenfrequencies ω_k, rad/s (ascending).
    pub omega_rad_s: Vec<f64>,
    /// Mass-normalised mode shapes Φ, one column per mode.
    pub shapes: DMatrix<f64>,
}

impl From<pdamp_fem::Modes> for ModalBasis {
    fn from(modes: pdamp_fem::Modes) -> Self {
        let s = &modes.shapes;
        ModalBasis {
            shapes: DMatrix::from_fn(s.nrows(), s.ncols(), |i, j| s[(i, j)]),
            omega_rad_s: modes.omega_rad_s,
        }
    }
}

/// Solves $(K - \omega^2 M)\phi = 0$ [D Eq. 3.20] for the lowest `n_modes` modes with
/// frequency ≥ `min_frequency_hz` (use a small positive value to drop rigid-body modes).
///
/// # Errors
/// Non-square or mismatched matrices, non-finite entries, or a mass matrix that is not
/// positive definite (a dof with stiffness but no mass).
pub fn lowest_modes(
    stiffness: &DMatrix<f64>,
    mass: &DMatrix<f64>,
    n_modes: usize,
    min_frequency_hz: f64,
) -> Result<ModalBasis, StructureError> {
    if stiffness.iter().chain(mass.iter()).any(|v| !v.is_finite()) {
        return Err(StructureError::numerical("K or M has non-finite entries"));
    }
    let faer_of =
        |a: &DMatrix<f64>| faer::Mat::<f64>::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)]);
    let modes = pdamp_fem::dense_lowest_modes(
        faer_of(stiffness).as_ref(),
        faer_of(mass).as_ref(),
        n_modes,
        min_frequency_hz,
    )
    .map_err(|e| StructureError::numerical(e.to_string()))?;
    Ok(ModalBasis::from(modes))
}

/// One mode of the reduced structure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// Undamped eigenfrequency f_k = ω_k/2π, Hz.
    pub frequency_hz: f64,
    /// Modal (structural) damping ratio ζ_k; the modal damping is $D_k = 2\zeta_k\omega_k$.
    pub damping_ratio: f64,
}

impl Mode {
    /// ω_k, rad/s.
    pub fn omega_rad_s(&self) -> f64 {
        TAU * self.frequency_hz
    }
}

/// Mass-normalised mode-shape values at a named point in a given direction
/// ($\phi_{ex}^{(k)}$, $\phi_{pd}^{(k)}$ of D Eq. 3.23), one value per mode, in 1/√kg.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModalPoint {
    /// Point name (excitation, damper, output, …).
    pub name: String,
    /// φ^(k) at the point, one per mode.
    pub shape: Vec<f64>,
}

/// The modally reduced structure $\ddot q + D\dot q + \Omega q = \Phi^T f$ [D Eq. 3.21] with
/// diagonal modal damping, evaluated at named points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModalStructure {
    /// The retained modes.
    pub modes: Vec<Mode>,
    /// Named points with their mode-shape values.
    pub points: Vec<ModalPoint>,
}

impl ModalStructure {
    /// A single mode in damper coordinates [D Eq. 3.27/3.28]: $M\ddot x + D\dot x + Kx = f$ at
    /// the point `"damper"` (φ = 1/√M, ω² = K/M, ζ = D/(2√(KM))). Points `"excitation"` and
    /// `"output"` coincide with it.
    pub fn single_mode(mass_kg: f64, stiffness_n_m: f64, damping_n_s_m: f64) -> Self {
        let phi = 1.0 / mass_kg.sqrt();
        let omega = (stiffness_n_m / mass_kg).sqrt();
        let pt = |name: &str| ModalPoint {
            name: name.into(),
            shape: vec![phi],
        };
        Self {
            modes: vec![Mode {
                frequency_hz: omega / TAU,
                damping_ratio: damping_n_s_m / (2.0 * (stiffness_n_m * mass_kg).sqrt()),
            }],
            points: vec![pt("damper"), pt("excitation"), pt("output")],
        }
    }

    /// Mode-shape values of a named point.
    ///
    /// # Errors
    /// Unknown point name.
    pub fn point(&self, name: &str) -> Result<&[f64], StructureError> {
        self.points
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.shape.as_slice())
            .ok_or_else(|| StructureError::UnknownPoint {
                name: name.to_string(),
                known: self.points.iter().map(|p| p.name.clone()).collect(),
            })
    }

    /// Rayleigh damping $D = \alpha M + \beta K$ in modal form:
    /// $\zeta_k = \alpha/(2\omega_k) + \beta\omega_k/2$.
    pub fn set_rayleigh(&mut self, alpha_1_s: f64, beta_s: f64) {
        for m in &mut self.modes {
            let w = m.omega_rad_s();
            m.damping_ratio = alpha_1_s / (2.0 * w) + beta_s * w / 2.0;
        }
    }

    /// Equivalent single-mode parameters of mode `k` in the coordinates of point `point`
    /// [D Eq. 3.27]: $M = 1/\phi^2$, $K = \omega_k^2/\phi^2$, $D = 2\zeta_k\omega_k/\phi^2$.
    pub fn equivalent_sdof(
        &self,
        k: usize,
        point: &str,
    ) -> Result<(f64, f64, f64), StructureError> {
        let phi = self.point(point)?[k];
        let m = &self.modes[k];
        let w = m.omega_rad_s();
        let mass = 1.0 / (phi * phi);
        Ok((mass, w * w * mass, 2.0 * m.damping_ratio * w * mass))
    }

    /// Checks sizes and values.
    pub fn validate(&self) -> Result<(), StructureError> {
        if self.modes.is_empty() {
            return Err(StructureError::rule("structure", "has no modes"));
        }
        for (k, m) in self.modes.iter().enumerate() {
            if !(m.frequency_hz.is_finite() && m.frequency_hz >= 0.0) {
                return Err(StructureError::invalid(
                    format!("mode {}", k + 1),
                    "frequency must be ≥ 0",
                ));
            }
            if !(m.damping_ratio.is_finite() && m.damping_ratio >= 0.0) {
                return Err(StructureError::invalid(
                    format!("mode {}", k + 1),
                    "damping ratio must be ≥ 0",
                ));
            }
        }
        for p in &self.points {
            if p.shape.len() != self.modes.len() {
                return Err(StructureError::rule(
                    format!("point '{}'", p.name),
                    format!(
                        "has {} mode-shape values for {} modes",
                        p.shape.len(),
                        self.modes.len()
                    ),
                ));
            }
            if p.shape.iter().any(|v| !v.is_finite()) {
                return Err(StructureError::invalid(
                    format!("point '{}'", p.name),
                    "non-finite mode-shape value",
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_dof_chain_matches_closed_form_and_is_mass_normalised() {
        // m1 = m2 = 1, k1 = k2 = 1 (ground–1–2): ω² = (3 ∓ √5)/2.
        let k = DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -1.0, 1.0]);
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
        let b = lowest_modes(&k, &m, 2, 0.0).unwrap();
        let w2: Vec<f64> = b.omega_rad_s.iter().map(|w| w * w).collect();
        assert!((w2[0] - (3.0 - 5f64.sqrt()) / 2.0).abs() < 1e-12);
        assert!((w2[1] - (3.0 + 5f64.sqrt()) / 2.0).abs() < 1e-12);
        let e = b.shapes.transpose() * &m * &b.shapes;
        assert!((e - DMatrix::identity(2, 2)).norm() < 1e-12);
    }

    #[test]
    fn non_positive_mass_is_an_error() {
        let k = DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -1.0, 1.0]);
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]);
        assert!(lowest_modes(&k, &m, 2, 0.0).is_err());
    }
}
