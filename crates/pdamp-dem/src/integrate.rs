//! Time integration schemes: velocity Verlet and Gear's fifth-order predictor–corrector with the
//! step-size controller of Meyer & Seifried [D Sect. 2.5, Eq. 2.95–2.106, Tab. 2.2/2.3]: their parameters, the Gear
//! state and the per-particle kernels. The steps themselves, applied to a world, are in
//! `world/step.rs`.

use crate::forces::{Kin, PpContact, WallSlot};
use crate::math::Vec3;
use serde::{Deserialize, Serialize};

/// Parameters of the Gear predictor–corrector with step control; defaults are [D Tab. 2.3].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GearParams {
    /// Smallest step $\Delta t_{min}$, s.
    pub dt_min_s: f64,
    /// Largest step $\Delta t_{max}$, s; `None` = $\pi / \max \omega_{con}$ [D Tab. 2.3, Eq. 2.83],
    /// see [`World::gear_default_dt_max_s`](crate::World::gear_default_dt_max_s).
    pub dt_max_s: Option<f64>,
    /// Absolute tolerance $\tau_{abs}$ on the acceleration correction, m/s².
    pub tolerance_abs: f64,
    /// Relative tolerance $\tau_{rel}$.
    pub tolerance_rel: f64,
    /// Maximum number of corrector steps $n^c_{max}$.
    pub max_corrections: u32,
    /// Safety factor $\kappa_s$ of the controller [D Eq. 2.105].
    pub safety_factor: f64,
}

impl Default for GearParams {
    fn default() -> Self {
        Self {
            dt_min_s: 1e-16,
            dt_max_s: None,
            tolerance_abs: 1e-6,
            tolerance_rel: 1e-6,
            max_corrections: 10,
            safety_factor: 0.9,
        }
    }
}

impl GearParams {
    /// Checks the controller settings against the initial step `dt_s` (errors start with the
    /// key, e.g. `safety_factor must …`): Δt_min ≤ Δt ≤ Δt_max, positive finite tolerances,
    /// 1 to 100 corrector steps and a safety factor κ_s in (0, 1] [D Eq. 2.105].
    pub fn validate(&self, dt_s: f64) -> Result<(), crate::ParameterError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.dt_min_s) || self.dt_min_s > dt_s {
            return Err(crate::ParameterError::invalid(
                "dt_min_s",
                format!(
                    "dt_min_s must be > 0 and at most the time step {dt_s:e} s, got {}; e.g. 1e-16",
                    self.dt_min_s
                ),
            ));
        }
        if let Some(m) = self.dt_max_s
            && (!pos(m) || m < dt_s)
        {
            return Err(crate::ParameterError::invalid(
                "dt_max_s",
                format!(
                    "dt_max_s must be finite and at least the time step {dt_s:e} s, got {m}; leave it out for π/ω_max [D Eq. 2.83]"
                ),
            ));
        }
        if !pos(self.tolerance_abs) {
            return Err(crate::ParameterError::invalid(
                "tolerance_abs",
                format!(
                    "tolerance_abs must be > 0 (m/s²), got {}; e.g. 1e-6",
                    self.tolerance_abs
                ),
            ));
        }
        if !(self.tolerance_rel.is_finite() && (0.0..1.0).contains(&self.tolerance_rel)) {
            return Err(crate::ParameterError::invalid(
                "tolerance_rel",
                format!(
                    "tolerance_rel must lie in [0, 1), got {}; e.g. 1e-6",
                    self.tolerance_rel
                ),
            ));
        }
        if !(1..=100).contains(&self.max_corrections) {
            return Err(crate::ParameterError::invalid(
                "max_corrections",
                format!(
                    "max_corrections must lie in 1..=100, got {}; e.g. 10",
                    self.max_corrections
                ),
            ));
        }
        if !(self.safety_factor.is_finite()
            && self.safety_factor > 0.0
            && self.safety_factor <= 1.0)
        {
            return Err(crate::ParameterError::invalid(
                "safety_factor",
                format!(
                    "safety_factor must lie in (0, 1], got {}; e.g. 0.9 [D Eq. 2.105]",
                    self.safety_factor
                ),
            ));
        }
        Ok(())
    }
}

/// Time integration scheme.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "scheme", rename_all = "kebab-case")]
pub enum Integrator {
    /// Velocity Verlet with a fixed step; forces at $t+\Delta t$ use the half-step velocities.
    VelocityVerlet,
    /// Gear predictor–corrector of order 5 with step control.
    Gear(GearParams),
}

/// Gear corrector coefficients for order p = 5 [D Tab. 2.2].
pub(crate) const GEAR5: [f64; 5] = [19.0 / 90.0, 3.0 / 4.0, 1.0, 1.0 / 2.0, 1.0 / 12.0];

/// Time derivatives kept by the Gear scheme for every particle: translation (x, ẋ, ẍ, x⃛, x⁗) and
/// rotation (θ, ω, ω̇, ω̈, ω⃛).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GearState {
    pub(crate) trans: Vec<[Vec3; 5]>,
    pub(crate) rot: Vec<[Vec3; 5]>,
    pub(crate) dt_max_s: f64,
    pub(crate) backup_pairs: Vec<PpContact>,
    pub(crate) backup_walls: Vec<Vec<WallSlot>>,
    pub(crate) pred_trans: Vec<[Vec3; 5]>,
    pub(crate) pred_rot: Vec<[Vec3; 5]>,
    /// Corrector steps used by the last accepted step.
    pub last_corrections: u32,
}

/// Half kick of one particle: $v \mathrel{+}= F\,h/m$, $\omega \mathrel{+}= T\,h/J$ (`h` = half the
/// step).
#[inline(always)]
pub(crate) fn half_kick(
    v: &mut Vec3,
    w: &mut Vec3,
    f: &Vec3,
    t: &Vec3,
    m: f64,
    inv_inertia: f64,
    h: f64,
) {
    *v += *f * (h / m);
    *w += *t * (h * inv_inertia);
}

/// Drift of one particle by `dt`, packed for the pair loop (`[x, y, z, r]`, [`Kin`]); returns
/// its squared displacement from `reference` (0 without one).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn drift_and_pack(
    x: &mut Vec3,
    v: &Vec3,
    w: &Vec3,
    m: f64,
    radius: f64,
    dt: f64,
    xr: &mut [f64; 4],
    kin: &mut Kin,
    reference: Option<&Vec3>,
) -> f64 {
    *x += *v * dt;
    *xr = [x.x, x.y, x.z, radius];
    *kin = Kin::new(v, m, w);
    reference.map_or(0.0, |r| (*x - *r).norm_squared())
}
