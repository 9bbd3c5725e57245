//! TEMPORARY stand-in (replaced by the real laws on merge): Hertz elastic only.
#![allow(missing_docs)]
use super::*;
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactModel { pub normal: NormalLaw, #[serde(default)] pub friction: FrictionLaw }
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case")]
pub enum NormalLaw { Hertz, HertzMindlin { restitution: f64 } }
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "law", rename_all = "kebab-case")]
pub enum FrictionLaw { #[default] Frictionless, Mindlin { friction_coefficient: f64 } }
impl ContactModel {
    pub fn validate(&self) -> Result<(), String> { Ok(()) }
    pub fn prepare(&mut self) {}
    pub fn evaluate(&self, p: &PairProps, k: &ContactKinematics, h: &mut ContactHistory) -> ContactForce {
        if k.overlap_m <= 0.0 { *h = ContactHistory::default(); return ContactForce::default(); }
        let kn = 4.0 / 3.0 * p.e_eff_pa * p.r_eff_m.sqrt();
        let d = k.overlap_m;
        ContactForce { normal_elastic_n: kn * d * d.sqrt(), normal_energy_j: 0.4 * kn * d * d * d.sqrt(), ..Default::default() }
    }
    pub fn max_interaction_gap_m(&self, _p: &PairProps) -> f64 { 0.0 }
    pub fn contact_time_estimate_s(&self, p: &PairProps, v: f64) -> f64 { 2.868 * (p.m_eff_kg.powi(2) / (v * p.r_eff_m * p.e_eff_pa.powi(2))).powf(0.2) }
    pub fn stiffness_estimate_n_m(&self, p: &PairProps, v: f64) -> f64 { let kn = 4.0 / 3.0 * p.e_eff_pa * p.r_eff_m.sqrt(); let dm = (1.25 * p.m_eff_kg * v * v / kn).powf(0.4); 1.5 * kn * dm.sqrt() }
}
