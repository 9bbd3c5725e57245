//! Materials of particles and walls and the effective pair properties of a contact
//! (Hertz theory, [D Eq. 2.71, 2.72, 2.81]).

use serde::{Deserialize, Serialize};

/// Elastic and inertial properties of one material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Name used to refer to the material in scenarios.
    pub name: String,
    /// Mass density ρ in kg/m³.
    pub density_kg_m3: f64,
    /// Young's modulus E in Pa.
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν (dimensionless, −1 < ν < 0.5).
    pub poisson_ratio: f64,
}

impl Material {
    /// Creates a material from its properties.
    pub fn new(name: &str, density_kg_m3: f64, youngs_modulus_pa: f64, poisson_ratio: f64) -> Self {
        Self {
            name: name.to_string(),
            density_kg_m3,
            youngs_modulus_pa,
            poisson_ratio,
        }
    }

    /// Structural steel (ρ = 7 850 kg/m³, E = 210 GPa, ν = 0.3).
    pub fn steel() -> Self {
        Self::new("steel", 7850.0, 210e9, 0.3)
    }

    /// Checks ranges; returns a message naming the offending field.
    pub fn validate(&self) -> Result<(), crate::ParameterError> {
        if !(self.density_kg_m3.is_finite() && self.density_kg_m3 > 0.0) {
            return Err(crate::ParameterError::invalid(
                "density_kg_m3",
                format!(
                    "density_kg_m3 must be > 0, got {} (material '{}')",
                    self.density_kg_m3, self.name
                ),
            ));
        }
        if !(self.youngs_modulus_pa.is_finite() && self.youngs_modulus_pa > 0.0) {
            return Err(crate::ParameterError::invalid(
                "youngs_modulus_pa",
                format!(
                    "youngs_modulus_pa must be > 0, got {} (material '{}')",
                    self.youngs_modulus_pa, self.name
                ),
            ));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(crate::ParameterError::invalid(
                "poisson_ratio",
                format!(
                    "poisson_ratio must lie in (-1, 0.5), got {} (material '{}')",
                    self.poisson_ratio, self.name
                ),
            ));
        }
        Ok(())
    }
}

/// Effective Young's modulus $1/\bar E = (1-\nu_1^2)/E_1 + (1-\nu_2^2)/E_2$ [D Eq. 2.71], in Pa.
pub fn effective_modulus(a: &Material, b: &Material) -> f64 {
    1.0 / ((1.0 - a.poisson_ratio.powi(2)) / a.youngs_modulus_pa
        + (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus_pa)
}

/// Effective shear modulus $1/\bar G = 2(2-\nu_1)(1+\nu_1)/E_1 + 2(2-\nu_2)(1+\nu_2)/E_2$
/// (Mindlin; as used by LIGGGHTS' Hertz/history model), in Pa.
pub fn effective_shear_modulus(a: &Material, b: &Material) -> f64 {
    let c = |m: &Material| {
        2.0 * (2.0 - m.poisson_ratio) * (1.0 + m.poisson_ratio) / m.youngs_modulus_pa
    };
    1.0 / (c(a) + c(b))
}

/// Effective radius $1/\bar R = 1/r_1 + 1/r_2$ [D Eq. 2.72], in m. `r2 = f64::INFINITY` for planes.
pub fn effective_radius(r1: f64, r2: f64) -> f64 {
    if r2.is_infinite() {
        r1
    } else {
        1.0 / (1.0 / r1 + 1.0 / r2)
    }
}

/// Effective mass $1/\bar M = 1/M_1 + 1/M_2$ [D Eq. 2.81], in kg. `m2 = f64::INFINITY` for walls.
pub fn effective_mass(m1: f64, m2: f64) -> f64 {
    if m2.is_infinite() {
        m1
    } else {
        m1 * m2 / (m1 + m2)
    }
}
