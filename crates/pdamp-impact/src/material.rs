//! Materials of the impact models [D Sect. 4.1].
//!
//! - linear elastic (Hooke [D Eq. 4.1]);
//! - J2 elastic–viscoplastic with piecewise-linear isotropic hardening $\sigma_y(\bar\epsilon_{pl})$
//!   and Perzyna rate dependence $\sigma_d = \beta\sigma_y$, $\beta = 1 + (\dot{\bar\epsilon}_{pl}/\zeta)^\lambda$
//!   [D Eq. 4.2, Tab. 4.1];
//! - linear viscoelastic (generalised Maxwell): Prony series on the shear modulus
//!   $g_R(t) = 1 - \sum g_i(1-e^{-t/\tau_i})$ [D Eq. 4.3–4.5], long-term $E$, ν given
//!   [D Eq. 4.7, L1711].
//!
//! Built-ins: [`Material::s235`], [`Material::al6060`], [`Material::saa9579`]. Further materials
//! come from a TOML file ([`MaterialSet::from_toml_str`]).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Errors of material definitions.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// A parameter is out of range.
    #[error("material {name}: {msg}")]
    Invalid {
        /// Material name.
        name: String,
        /// What is wrong.
        msg: String,
    },
    /// The TOML text does not parse.
    #[error("material file: {0}")]
    Toml(String),
    /// No material of that name.
    #[error("unknown material {0:?} (built-ins: s235, al6060, saa9579)")]
    Unknown(String),
}

/// Constitutive model of a [`Material`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum MaterialModel {
    /// Linear elastic.
    Elastic,
    /// J2 plasticity with piecewise-linear isotropic hardening and Perzyna overstress
    /// [D Eq. 4.2].
    ViscoplasticJ2 {
        /// Quasi-static yield curve as `[equivalent plastic strain, yield stress in Pa]` points
        /// (strain increasing from 0; constant after the last point).
        hardening_pa: Vec<[f64; 2]>,
        /// Perzyna viscosity parameter ζ in 1/s [D Tab. 4.1] (none = rate independent).
        #[serde(default)]
        perzyna_zeta_1_s: Option<f64>,
        /// Perzyna exponent λ [D Tab. 4.1].
        #[serde(default = "one")]
        perzyna_lambda: f64,
    },
    /// Linear viscoelastic Prony series on the shear modulus [D Eq. 4.5]; the given Young's
    /// modulus and Poisson ratio are the long-term values [D L1711]. The bulk modulus is the
    /// long-term one and does not relax unless `bulk_relaxes` (then K follows the same series).
    ViscoelasticProny {
        /// `[g_i, tau_i in s]` pairs [D Tab. 4.2].
        prony: Vec<[f64; 2]>,
        /// Let the bulk modulus relax with the same series (constant ν) instead of staying at
        /// its long-term value.
        #[serde(default)]
        bulk_relaxes: bool,
    },
}

fn one() -> f64 {
    1.0
}

/// A material: elastic constants, density and constitutive model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (built-in key or TOML table name).
    #[serde(default)]
    pub name: String,
    /// Young's modulus E, Pa (long-term for Prony materials).
    pub youngs_modulus_pa: f64,
    /// Poisson ratio ν (long-term for Prony materials).
    pub poisson_ratio: f64,
    /// Density ρ, kg/m³.
    pub density_kg_m3: f64,
    /// Kuwabara–Kono dissipation constant A in s for the analytical viscoelastic model (metals:
    /// 0; Prony materials derive theirs from the series).
    #[serde(default)]
    pub kk_dissipation_time_s: Option<f64>,
    /// Constitutive model.
    #[serde(flatten)]
    pub model: MaterialModel,
}

/// Quasi-static yield curve of S235 used here (equivalent plastic strain, Pa). D Fig. 4.1 gives
/// it only as a figure (data of \[SeifriedEtAl10\]); D Tab. 4.1 gives σ_y = 230 MPa. The later
/// points are our assumption for a mild structural steel (UTS ≈ 450–500 MPa): see docs/cor.md.
pub const S235_HARDENING_PA: [[f64; 2]; 6] = [
    [0.0, 230e6],
    [0.01, 245e6],
    [0.05, 330e6],
    [0.10, 390e6],
    [0.20, 450e6],
    [0.50, 520e6],
];

/// Quasi-static yield curve of Al6060 used here (equivalent plastic strain, Pa): σ_y = 205 MPa
/// [D Tab. 4.1] with the flat hardening D describes for aluminium ("lower slope at high strains",
/// D L1850); later points assumed, see docs/cor.md.
pub const AL6060_HARDENING_PA: [[f64; 2]; 6] = [
    [0.0, 205e6],
    [0.01, 215e6],
    [0.05, 232e6],
    [0.10, 242e6],
    [0.20, 252e6],
    [0.50, 262e6],
];

/// Prony series of the SAA9579-52 elastomer, `[g_i, τ_i in s]` [D Tab. 4.2].
pub const SAA9579_PRONY: [[f64; 2]; 22] = [
    [0.0358414, 5.4e-15],
    [0.0325413, 9.2e-14],
    [0.0323402, 1.59e-12],
    [0.034239, 2.61e-11],
    [0.0465026, 3.78e-10],
    [0.0762799, 3.31e-9],
    [0.109384, 1.83e-8],
    [0.0135877, 5.48e-8],
    [0.142179, 1.12e-7],
    [0.141801, 4.73e-7],
    [0.11387, 1.7e-6],
    [0.0846797, 6.33e-6],
    [0.0517678, 2.75e-5],
    [0.0279107, 0.000163],
    [0.0127789, 0.00149],
    [0.00707692, 0.0226],
    [0.0056339, 0.57],
    [0.00538153, 21.7],
    [0.00542548, 700.0],
    [0.00510943, 23500.0],
    [0.00398299, 805000.0],
    [0.00947423, 4.36e7],
];

impl Material {
    /// Steel S235: E = 208 GPa, ν = 0.3, ρ = 7800 kg/m³, σ_y = 230 MPa, ζ = 305 1/s, λ = 0.403
    /// [D Tab. 4.1]; hardening [`S235_HARDENING_PA`].
    pub fn s235() -> Self {
        Self {
            name: "s235".into(),
            youngs_modulus_pa: 208e9,
            poisson_ratio: 0.3,
            density_kg_m3: 7800.0,
            kk_dissipation_time_s: None,
            model: MaterialModel::ViscoplasticJ2 {
                hardening_pa: S235_HARDENING_PA.to_vec(),
                perzyna_zeta_1_s: Some(305.0),
                perzyna_lambda: 0.403,
            },
        }
    }

    /// Aluminium Al6060: E = 67.7 GPa, ν = 0.33, ρ = 2702 kg/m³, σ_y = 205 MPa, ζ = 5548 1/s,
    /// λ = 1 [D Tab. 4.1]; hardening [`AL6060_HARDENING_PA`].
    pub fn al6060() -> Self {
        Self {
            name: "al6060".into(),
            youngs_modulus_pa: 67.7e9,
            poisson_ratio: 0.33,
            density_kg_m3: 2702.0,
            kk_dissipation_time_s: None,
            model: MaterialModel::ViscoplasticJ2 {
                hardening_pa: AL6060_HARDENING_PA.to_vec(),
                perzyna_zeta_1_s: Some(5548.0),
                perzyna_lambda: 1.0,
            },
        }
    }

    /// Elastomer SAA9579-52: long-term E = 54.97 MPa, ν = 0.4477 [D L1711], ρ = 1180 kg/m³
    /// [D Tab. 4.3], Prony series [`SAA9579_PRONY`] [D Tab. 4.2].
    pub fn saa9579() -> Self {
        Self {
            name: "saa9579".into(),
            youngs_modulus_pa: 54.97e6,
            poisson_ratio: 0.4477,
            density_kg_m3: 1180.0,
            kk_dissipation_time_s: None,
            model: MaterialModel::ViscoelasticProny {
                prony: SAA9579_PRONY.to_vec(),
                bulk_relaxes: false,
            },
        }
    }

    /// Linear elastic material.
    pub fn elastic(name: &str, e: f64, nu: f64, rho: f64) -> Self {
        Self {
            name: name.into(),
            youngs_modulus_pa: e,
            poisson_ratio: nu,
            density_kg_m3: rho,
            kk_dissipation_time_s: None,
            model: MaterialModel::Elastic,
        }
    }

    /// The same material made linear elastic (same E, ν, ρ).
    pub fn as_elastic(&self) -> Self {
        let mut m = self.clone();
        m.model = MaterialModel::Elastic;
        m
    }

    /// Built-in material by name.
    pub fn builtin(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "s235" => Some(Self::s235()),
            "al6060" => Some(Self::al6060()),
            "saa9579" | "saa" => Some(Self::saa9579()),
            _ => None,
        }
    }

    /// Long-term shear modulus $G = E/(2(1+\nu))$, Pa.
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
    }

    /// Long-term bulk modulus $K = E/(3(1-2\nu))$, Pa.
    pub fn bulk_modulus(&self) -> f64 {
        self.youngs_modulus_pa / (3.0 * (1.0 - 2.0 * self.poisson_ratio))
    }

    /// Instantaneous shear modulus $G_0 = G_\infty/(1-\sum g_i)$ [D Eq. 4.7] (G for others).
    pub fn instantaneous_shear_modulus(&self) -> f64 {
        match &self.model {
            MaterialModel::ViscoelasticProny { prony, .. } => {
                self.shear_modulus() / (1.0 - prony.iter().map(|p| p[0]).sum::<f64>())
            }
            _ => self.shear_modulus(),
        }
    }

    /// Initial (quasi-static) yield stress, Pa (infinite for non-plastic materials).
    pub fn initial_yield_stress(&self) -> f64 {
        match &self.model {
            MaterialModel::ViscoplasticJ2 { hardening_pa, .. } => hardening_pa[0][1],
            _ => f64::INFINITY,
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`MaterialError::Invalid`] naming the offending parameter.
    pub fn validate(&self) -> Result<(), MaterialError> {
        let bad = |msg: String| {
            Err(MaterialError::Invalid {
                name: self.name.clone(),
                msg,
            })
        };
        if !(self.youngs_modulus_pa > 0.0 && self.youngs_modulus_pa.is_finite()) {
            return bad(format!(
                "youngs_modulus_pa must be > 0, got {}",
                self.youngs_modulus_pa
            ));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return bad(format!(
                "poisson_ratio must lie in (-1, 0.5), got {}",
                self.poisson_ratio
            ));
        }
        if !(self.density_kg_m3 > 0.0 && self.density_kg_m3.is_finite()) {
            return bad(format!(
                "density_kg_m3 must be > 0, got {}",
                self.density_kg_m3
            ));
        }
        match &self.model {
            MaterialModel::Elastic => {}
            MaterialModel::ViscoplasticJ2 {
                hardening_pa,
                perzyna_zeta_1_s,
                perzyna_lambda,
            } => {
                if hardening_pa.is_empty() || hardening_pa[0][0] != 0.0 {
                    return bad("hardening_pa must start at plastic strain 0".into());
                }
                for w in hardening_pa.windows(2) {
                    if w[1][0] <= w[0][0] || w[1][1] < w[0][1] {
                        return bad(
                            "hardening_pa strains must increase and stresses not decrease".into(),
                        );
                    }
                }
                if hardening_pa[0][1] <= 0.0 {
                    return bad("initial yield stress must be > 0".into());
                }
                if let Some(z) = perzyna_zeta_1_s
                    && (z.is_nan() || *z <= 0.0)
                {
                    return bad(format!("perzyna_zeta_1_s must be > 0, got {z}"));
                }
                if perzyna_lambda.is_nan() || *perzyna_lambda <= 0.0 {
                    return bad(format!("perzyna_lambda must be > 0, got {perzyna_lambda}"));
                }
            }
            MaterialModel::ViscoelasticProny { prony, .. } => {
                let s: f64 = prony.iter().map(|p| p[0]).sum();
                if prony.iter().any(|p| !(p[0] > 0.0 && p[1] > 0.0)) || s >= 1.0 {
                    return bad(format!(
                        "prony terms need g_i > 0, tau_i > 0 and sum g_i < 1 (sum = {s})"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Built-in materials plus those of a TOML file:
///
/// ```toml
/// [materials.my_steel]
/// youngs_modulus_pa = 210e9
/// poisson_ratio = 0.3
/// density_kg_m3 = 7850.0
/// model = "viscoplastic-j2"            # or "elastic", "viscoelastic-prony"
/// hardening_pa = [[0.0, 300e6], [0.1, 400e6]]
/// perzyna_zeta_1_s = 305.0
/// perzyna_lambda = 0.403
/// ```
#[derive(Debug, Clone, Default)]
pub struct MaterialSet {
    /// Materials by name (file materials override built-ins of the same name).
    pub materials: BTreeMap<String, Material>,
}

#[derive(Deserialize)]
struct MaterialFile {
    #[serde(default)]
    materials: BTreeMap<String, Material>,
}

impl MaterialSet {
    /// The built-in materials.
    pub fn builtins() -> Self {
        let mut materials = BTreeMap::new();
        for m in [Material::s235(), Material::al6060(), Material::saa9579()] {
            materials.insert(m.name.clone(), m);
        }
        Self { materials }
    }

    /// Built-ins plus the `[materials.NAME]` tables of a TOML text.
    ///
    /// # Errors
    /// TOML syntax errors and invalid parameters.
    pub fn from_toml_str(text: &str) -> Result<Self, MaterialError> {
        let file: MaterialFile =
            toml::from_str(text).map_err(|e| MaterialError::Toml(e.to_string()))?;
        let mut set = Self::builtins();
        for (name, mut m) in file.materials {
            m.name = name.clone();
            m.validate()?;
            set.materials.insert(name.to_ascii_lowercase(), m);
        }
        Ok(set)
    }

    /// Material by (case-insensitive) name.
    ///
    /// # Errors
    /// [`MaterialError::Unknown`].
    pub fn get(&self, name: &str) -> Result<Material, MaterialError> {
        self.materials
            .get(&name.to_ascii_lowercase())
            .cloned()
            .ok_or_else(|| MaterialError::Unknown(name.into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_valid() {
        for m in MaterialSet::builtins().materials.values() {
            m.validate().unwrap();
        }
        // D L1711: G_inf = E/(2(1+nu)) = 18.985 MPa; G_0 = G_inf/(1 - sum g_i) ≈ 8.58 GPa
        let saa = Material::saa9579();
        assert!((saa.shear_modulus() / 18.985e6 - 1.0).abs() < 1e-4);
        let g0 = saa.instantaneous_shear_modulus();
        assert!((g0 / 8.58e9 - 1.0).abs() < 2e-3, "G0 = {g0}");
    }

    #[test]
    fn toml_materials() {
        let text = r#"
[materials.soft]
youngs_modulus_pa = 1e9
poisson_ratio = 0.3
density_kg_m3 = 1000.0
model = "elastic"

[materials.ss]
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
density_kg_m3 = 7900.0
model = "viscoplastic-j2"
hardening_pa = [[0.0, 300e6], [0.1, 400e6]]
perzyna_zeta_1_s = 100.0
perzyna_lambda = 0.5
"#;
        let set = MaterialSet::from_toml_str(text).unwrap();
        assert_eq!(set.get("soft").unwrap().model, MaterialModel::Elastic);
        assert!(matches!(
            set.get("SS").unwrap().model,
            MaterialModel::ViscoplasticJ2 { .. }
        ));
        assert!(set.get("s235").is_ok());
        assert!(set.get("nope").is_err());
        assert!(MaterialSet::from_toml_str("[materials.x]\nyoungs_modulus_pa = -1.0\npoisson_ratio = 0.3\ndensity_kg_m3 = 1.0\nmodel = \"elastic\"").is_err());
    }
}
