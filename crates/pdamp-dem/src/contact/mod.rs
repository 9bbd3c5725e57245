//! Contact laws: normal force, friction, rolling resistance and adhesion of one contact.
//!
//! A contact law only computes forces from the contact kinematics and its own history; it never
//! does energy bookkeeping (the pipeline integrates work and subtracts the stored elastic energy the
//! law reports). The same laws serve particle–particle and particle–wall contacts: for a wall the
//! pipeline passes $\bar R = r$ (or the cylinder rule of [D Eq. 2.74/2.75]) and $\bar M = m$.
//!
//! Sign conventions: `normal` points from the partner towards particle *i*; the overlap
//! $\delta > 0$ means penetration and $\dot\delta > 0$ approach; all forces returned act on *i*.

use crate::math::Vec3;
use serde::{Deserialize, Serialize};

mod adhesion;
mod coarse_grain;
mod friction;
pub mod hertz;
mod model;
mod normal;
#[cfg(test)]
mod tests;

pub use model::*;

/// Constant properties of one contact pair (effective quantities of Hertz theory).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairProps {
    /// Effective Young's modulus $\bar E$ [D Eq. 2.71], Pa.
    pub e_eff_pa: f64,
    /// Effective shear modulus $\bar G$ (Mindlin), Pa.
    pub g_eff_pa: f64,
    /// Mean Poisson's ratio of the two materials (for default tangential stiffness ratios).
    pub poisson_mean: f64,
    /// Effective radius $\bar R$ [D Eq. 2.72], m.
    pub r_eff_m: f64,
    /// Effective mass $\bar M$ [D Eq. 2.81], kg.
    pub m_eff_kg: f64,
}

/// Kinematics of one contact at the current state, computed by the pipeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactKinematics {
    /// Overlap $\delta = r_i + r_j - |x_i - x_j|$ in m; negative values are a gap (only passed
    /// to laws with an adhesion range).
    pub overlap_m: f64,
    /// Overlap rate $\dot\delta$ in m/s, positive while the partners approach.
    pub overlap_rate_m_s: f64,
    /// Unit normal pointing from the partner towards particle *i*.
    pub normal: Vec3,
    /// Tangential relative velocity of *i* with respect to the partner at the contact point
    /// (perpendicular to `normal`), m/s [D Eq. 2.15].
    pub tangential_velocity_m_s: Vec3,
    /// Relative angular velocity $\omega_i - \omega_j$ in rad/s (rolling resistance).
    pub relative_angular_velocity_rad_s: Vec3,
    /// Time step in s, used to integrate history variables.
    pub dt_s: f64,
}

/// Memory of one contact that survives neighbour-list rebuilds.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ContactHistory {
    /// Tangential spring elongation $\xi$ in m (spring–dashpot friction laws).
    pub spring_m: Vec3,
    /// Overlap rate at first touch $\dot\delta_0$ in m/s (Gonthier, Lankarani–Nikravesh);
    /// 0 while the partners have not touched yet.
    pub impact_velocity_m_s: f64,
}

/// Forces of one contact on particle *i*, split as the energy ledger needs them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    /// Conservative part of the normal force along `normal` in N (repulsive > 0), adhesion included.
    pub normal_elastic_n: f64,
    /// Dissipative (damping) part of the normal force along `normal` in N.
    pub normal_dissipative_n: f64,
    /// Tangential (friction) force on *i* in N, perpendicular to `normal`.
    pub tangential_n: Vec3,
    /// Rolling-resistance torque on *i* in N·m (the partner receives the opposite).
    pub rolling_torque_nm: Vec3,
    /// Elastic energy stored in the normal direction at this state, J (Hertz $\tfrac25 k_n\delta^{5/2}$
    /// [D Eq. 2.82], linear $\tfrac12 k\delta^2$, plus the adhesion potential).
    pub normal_energy_j: f64,
    /// Elastic energy stored in the tangential spring, J.
    pub tangential_energy_j: f64,
}

impl ContactForce {
    /// Total normal force along the normal, N.
    #[inline]
    pub fn normal_total_n(&self) -> f64 {
        self.normal_elastic_n + self.normal_dissipative_n
    }
}
