//! Public configuration of a contact law ([`ContactModel`]) and its dispatch.
//!
//! A [`ContactModel`] combines one [`NormalLaw`], one [`FrictionLaw`], an optional
//! [`RollingResistance`] and an optional [`DmtAdhesion`]. [`ContactModel::evaluate`] is the hot
//! path called once per contact and step; it allocates nothing and never panics.
//!
//! **Caching.** Gonthier's damping parameter $\bar d(\varepsilon)$ [D Eq. 2.79] is the only
//! precomputed quantity. Caching is *transparent*: the first evaluation of a restitution on a
//! thread solves eq. 2.79 once and memoises it in a small per-thread table keyed by the exact
//! value of ε, so `evaluate` never solves it again. [`ContactModel::prepare`] exists for callers
//! that want to warm that table up front; calling it is optional.

use super::{ContactForce, ContactHistory, ContactKinematics, PairProps};
use super::{hertz, normal};
use crate::ParameterError;
use crate::math::Vec3;
use serde::{Deserialize, Serialize};

pub(crate) fn default_min_impact_velocity() -> f64 {
    1e-3
}

fn default_damping_ratio() -> f64 {
    1.0
}

/// Complete contact law of one pair of materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactModel {
    /// Normal force law.
    pub normal: NormalLaw,
    /// Tangential (friction) force law; frictionless by default.
    #[serde(default)]
    pub friction: FrictionLaw,
    /// Optional rolling-resistance torque.
    #[serde(default)]
    pub rolling: Option<RollingResistance>,
    /// Optional DMT (van der Waals) adhesion, acting also across small gaps.
    #[serde(default)]
    pub adhesion: Option<DmtAdhesion>,
}

/// Normal contact force laws. Every law returns its conservative part (used for the stored
/// contact energy) separately from its dissipative part.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum NormalLaw {
    /// Elastic Hertz law $F_n = k_n \delta^{3/2}$, $k_n = \tfrac43\bar E\sqrt{\bar R}$
    /// [D Eq. 2.69, 2.70]; no dissipation.
    Hertz,
    /// Gonthier's law $F_n = k_n \delta^{3/2}\,(1 + \bar d\,\dot\delta/(\varepsilon\dot\delta_0))$
    /// [D Eq. 2.78] with $\bar d(\varepsilon)$ from [D Eq. 2.79]. Reproduces the restitution ε
    /// exactly for any impact velocity. The total force is clipped at zero (it cannot turn
    /// attractive; for this law that happens only for separation faster than $\varepsilon\dot\delta_0$).
    Gonthier {
        /// Coefficient of restitution ε in (0, 1].
        restitution: f64,
        /// Lower bound for the stored impact velocity $\dot\delta_0$ in m/s (contacts that start
        /// at rest), default 1e-3 m/s.
        #[serde(default = "default_min_impact_velocity")]
        min_impact_velocity_m_s: f64,
    },
    /// Gonthier's law [D Eq. 2.78, 2.79] with a velocity-dependent coefficient of restitution
    /// $\varepsilon(\dot\delta_0)$ given as a table over the impact velocity (as measured or from
    /// FE impact simulations [D Chap. 4]; [D Tab. 8.1] "velocity dependent"): each contact uses
    /// ε of its own impact velocity, linearly interpolated and held constant outside the table.
    GonthierTable {
        /// Impact velocities of the table, m/s (strictly increasing, > 0).
        impact_velocities_m_s: Vec<f64>,
        /// Coefficients of restitution at those velocities, each in (0, 1].
        restitutions: Vec<f64>,
        /// Lower bound for the stored impact velocity $\dot\delta_0$ in m/s, default 1e-3 m/s.
        #[serde(default = "default_min_impact_velocity")]
        min_impact_velocity_m_s: f64,
    },
    /// Lankarani–Nikravesh law
    /// $F_n = k_n \delta^{3/2}\,(1 + \tfrac34 (1-\varepsilon^2)\,\dot\delta/\dot\delta_0)$ [D Eq. 2.77],
    /// accurate for ε ≳ 0.8. Total force clipped at zero.
    LankaraniNikravesh {
        /// Coefficient of restitution ε in (0, 1].
        restitution: f64,
        /// Lower bound for the stored impact velocity $\dot\delta_0$ in m/s, default 1e-3 m/s.
        #[serde(default = "default_min_impact_velocity")]
        min_impact_velocity_m_s: f64,
    },
    /// Linear spring–dashpot $F_n = k_N\delta + d_N\dot\delta$ with
    /// $d_N = 2|\ln e|\sqrt{k_N \bar M/(\ln^2 e + \pi^2)}$ [P Eq. (2)–(4)]; reproduces e exactly
    /// when not clipped (e = 1: an elastic spring).
    Linear {
        /// Spring stiffness $k_N$ in N/m.
        stiffness_n_m: f64,
        /// Coefficient of restitution e in (0, 1].
        restitution: f64,
        /// Clip the total normal force at zero (as [P Eq. (2)] does); default false.
        #[serde(default)]
        clip_attractive: bool,
    },
    /// The normal part of LIGGGHTS' `hertz` model: $F_n = \tfrac43\bar E a\,\delta + \gamma_n\dot\delta$,
    /// $a = \sqrt{\bar R\delta}$, $\gamma_n = -2\sqrt{5/6}\,\beta\sqrt{2\bar E a\,\bar M}$,
    /// $\beta = \ln e/\sqrt{\ln^2 e + \pi^2}$.
    HertzMindlin {
        /// Coefficient of restitution e in (0, 1].
        restitution: f64,
        /// Clip the total normal force at zero (LIGGGHTS `limitForce`); default false.
        #[serde(default)]
        clip_attractive: bool,
    },
}

/// Tangential force laws.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum FrictionLaw {
    /// No tangential force.
    #[default]
    Frictionless,
    /// Regularised sliding friction
    /// $\mathbf f^t = -\mu F_n \mathbf t \tanh(\eta \|\mathbf v^t\|)$ [D Eq. 2.85] (Andersson),
    /// with $F_n \ge 0$ the contact normal force (elastic + dissipative, adhesion excluded).
    RegularizedSliding {
        /// Coefficient of friction μ ≥ 0.
        friction_coefficient: f64,
        /// Smoothing parameter η in s/m (> 0).
        regularization_s_m: f64,
    },
    /// Coulomb-limited tangential spring–dashpot with return mapping [P Eq. (5)]:
    /// trial $\mathbf f = -k_t\boldsymbol\xi - d_t \mathbf v^t$, sliding at $\mu F_n$.
    CoulombSpring {
        /// Coefficient of friction μ ≥ 0.
        friction_coefficient: f64,
        /// $k_t$ as a multiple of the tangent normal stiffness ($k_N$ for the linear law,
        /// $dF_{el}/d\delta = 2\bar E\sqrt{\bar R\delta}$ for Hertz-type laws); default
        /// $(1-\nu)/(1-\nu/2)$ with ν = [`PairProps::poisson_mean`].
        #[serde(default)]
        stiffness_ratio: Option<f64>,
        /// $d_t$ as a multiple of the current normal damping coefficient; default 1 ($d_T = d_N$).
        #[serde(default = "default_damping_ratio")]
        damping_ratio: f64,
    },
    /// LIGGGHTS' `tangential history` model: $k_t = 8\bar G a$,
    /// $\gamma_t = -2\sqrt{5/6}\,\beta\sqrt{k_t \bar M}$ with β from the normal law's restitution.
    Mindlin {
        /// Coefficient of friction μ ≥ 0.
        friction_coefficient: f64,
    },
}

/// Constant-torque rolling resistance
/// $\boldsymbol\tau = -\mu_r \bar R\,|F_n|\,\hat{\boldsymbol\omega}$ with
/// $\hat{\boldsymbol\omega} = \frac{\boldsymbol\omega_{rel}}{|\boldsymbol\omega_{rel}|}\tanh(|\boldsymbol\omega_{rel}|\,t_r)$,
/// where $\boldsymbol\omega_{rel} = \boldsymbol\omega_i - \boldsymbol\omega_j$, $F_n \ge 0$ is the
/// contact normal force and $t_r$ = `regularization_s` smooths the sign change at
/// $\omega_{rel} = 0$ (cf. the tanh regularisation of [D Eq. 2.85]). The torque acts on *i*; the
/// partner receives the opposite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RollingResistance {
    /// Rolling-resistance coefficient $\mu_r$ ≥ 0 (dimensionless, lever arm $\mu_r\bar R$).
    pub coefficient: f64,
    /// Regularisation time $t_r$ in s (> 0).
    pub regularization_s: f64,
}

/// DMT van der Waals adhesion [P Eq. (6), (7)]: attractive force of magnitude
/// $F_{S0} = 4\pi\gamma\bar R$ for gaps $g \le g_0$ (including all overlaps),
/// $A\bar R/(6g^2)$ for $g_0 < g < g^*$ and 0 beyond $g^* = g_0/\sqrt{c}$, where
/// $g_0 = \sqrt{A\bar R/(6F_{S0})}$ and c is `cutoff_ratio`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DmtAdhesion {
    /// Surface energy γ in J/m² (≥ 0).
    pub surface_energy_j_m2: f64,
    /// Hamaker constant A in J (> 0).
    pub hamaker_constant_j: f64,
    /// Relative force level $c_{FS0}$ in (0, 1] at the cut-off gap $g^*$.
    pub cutoff_ratio: f64,
}

/// Piecewise-linear interpolation in a table `(x, y)` with increasing `x`, constant outside.
pub(crate) fn interpolate_clamped(x: &[f64], y: &[f64], v: f64) -> f64 {
    if v <= x[0] {
        return y[0];
    }
    let n = x.len();
    if v >= x[n - 1] {
        return y[n - 1];
    }
    let k = x.partition_point(|&xi| xi <= v); // x[k-1] <= v < x[k]
    let t = (v - x[k - 1]) / (x[k] - x[k - 1]);
    y[k - 1] + t * (y[k] - y[k - 1])
}

fn check(ok: bool, field: &str, range: &str, value: f64) -> Result<(), ParameterError> {
    ParameterError::check(ok, field, range, value)
}

impl NormalLaw {
    /// Coefficient of restitution the law is parametrised with (1 for [`NormalLaw::Hertz`]; for
    /// [`NormalLaw::GonthierTable`] the value at 1 m/s).
    pub fn restitution(&self) -> f64 {
        match *self {
            NormalLaw::Hertz => 1.0,
            NormalLaw::GonthierTable { .. } => self.restitution_at(1.0),
            NormalLaw::Gonthier { restitution, .. }
            | NormalLaw::LankaraniNikravesh { restitution, .. }
            | NormalLaw::Linear { restitution, .. }
            | NormalLaw::HertzMindlin { restitution, .. } => restitution,
        }
    }

    /// Coefficient of restitution at impact velocity `v` (m/s): the table value for
    /// [`NormalLaw::GonthierTable`] (linear interpolation, constant outside), else the constant.
    pub fn restitution_at(&self, v: f64) -> f64 {
        match self {
            NormalLaw::GonthierTable {
                impact_velocities_m_s: x,
                restitutions: y,
                ..
            } => interpolate_clamped(x, y, v),
            _ => self.restitution(),
        }
    }

    /// Lower bound applied to the stored impact velocity $\dot\delta_0$, m/s (1e-3 m/s for laws
    /// without the parameter).
    pub fn min_impact_velocity_m_s(&self) -> f64 {
        match *self {
            NormalLaw::Gonthier {
                min_impact_velocity_m_s,
                ..
            }
            | NormalLaw::GonthierTable {
                min_impact_velocity_m_s,
                ..
            }
            | NormalLaw::LankaraniNikravesh {
                min_impact_velocity_m_s,
                ..
            } => min_impact_velocity_m_s,
            _ => default_min_impact_velocity(),
        }
    }

    /// Whether the damping is scaled by the stored impact velocity (Gonthier, Lankarani–Nikravesh).
    pub fn scales_with_impact_velocity(&self) -> bool {
        matches!(
            self,
            NormalLaw::Gonthier { .. }
                | NormalLaw::GonthierTable { .. }
                | NormalLaw::LankaraniNikravesh { .. }
        )
    }

    /// Whether the law follows Hertz' $\delta^{3/2}$ elasticity (all but [`NormalLaw::Linear`]).
    pub fn is_hertz_type(&self) -> bool {
        !matches!(self, NormalLaw::Linear { .. })
    }

    fn validate(&self) -> Result<(), ParameterError> {
        if let NormalLaw::GonthierTable {
            impact_velocities_m_s: x,
            restitutions: y,
            min_impact_velocity_m_s,
        } = self
        {
            if x.is_empty() || x.len() != y.len() {
                return Err(ParameterError::invalid(
                    "normal.impact_velocities_m_s",
                    format!(
                        "normal.impact_velocities_m_s ({} values) and normal.restitutions ({} values) must be non-empty and of equal length",
                        x.len(),
                        y.len()
                    ),
                ));
            }
            for (k, v) in x.iter().enumerate() {
                check(
                    v.is_finite() && *v > 0.0 && (k == 0 || *v > x[k - 1]),
                    &format!("normal.impact_velocities_m_s[{k}]"),
                    "be > 0 and strictly increasing",
                    *v,
                )?;
            }
            for (k, e) in y.iter().enumerate() {
                check(
                    *e > 0.0 && *e <= 1.0,
                    &format!("normal.restitutions[{k}]"),
                    "lie in (0, 1]",
                    *e,
                )?;
            }
            return check(
                *min_impact_velocity_m_s > 0.0 && min_impact_velocity_m_s.is_finite(),
                "normal.min_impact_velocity_m_s",
                "be > 0",
                *min_impact_velocity_m_s,
            );
        }
        match *self {
            NormalLaw::Hertz | NormalLaw::GonthierTable { .. } => Ok(()),
            NormalLaw::Gonthier {
                restitution,
                min_impact_velocity_m_s,
            }
            | NormalLaw::LankaraniNikravesh {
                restitution,
                min_impact_velocity_m_s,
            } => {
                check(
                    restitution > 0.0 && restitution <= 1.0,
                    "normal.restitution",
                    "lie in (0, 1]",
                    restitution,
                )?;
                check(
                    min_impact_velocity_m_s > 0.0 && min_impact_velocity_m_s.is_finite(),
                    "normal.min_impact_velocity_m_s",
                    "be > 0",
                    min_impact_velocity_m_s,
                )
            }
            NormalLaw::Linear {
                stiffness_n_m,
                restitution,
                ..
            } => {
                check(
                    stiffness_n_m > 0.0 && stiffness_n_m.is_finite(),
                    "normal.stiffness_n_m",
                    "be > 0",
                    stiffness_n_m,
                )?;
                check(
                    restitution > 0.0 && restitution <= 1.0,
                    "normal.restitution",
                    "lie in (0, 1] (1: no damping)",
                    restitution,
                )
            }
            NormalLaw::HertzMindlin { restitution, .. } => check(
                restitution > 0.0 && restitution <= 1.0,
                "normal.restitution",
                "lie in (0, 1]",
                restitution,
            ),
        }
    }
}

impl FrictionLaw {
    fn validate(&self) -> Result<(), ParameterError> {
        let mu_ok = |mu: f64| {
            check(
                mu >= 0.0 && mu.is_finite(),
                "friction.friction_coefficient",
                "be >= 0",
                mu,
            )
        };
        match *self {
            FrictionLaw::Frictionless => Ok(()),
            FrictionLaw::RegularizedSliding {
                friction_coefficient,
                regularization_s_m,
            } => {
                mu_ok(friction_coefficient)?;
                check(
                    regularization_s_m > 0.0 && regularization_s_m.is_finite(),
                    "friction.regularization_s_m",
                    "be > 0",
                    regularization_s_m,
                )
            }
            FrictionLaw::CoulombSpring {
                friction_coefficient,
                stiffness_ratio,
                damping_ratio,
            } => {
                mu_ok(friction_coefficient)?;
                if let Some(r) = stiffness_ratio {
                    check(
                        r > 0.0 && r.is_finite(),
                        "friction.stiffness_ratio",
                        "be > 0",
                        r,
                    )?;
                }
                check(
                    damping_ratio >= 0.0 && damping_ratio.is_finite(),
                    "friction.damping_ratio",
                    "be >= 0",
                    damping_ratio,
                )
            }
            FrictionLaw::Mindlin {
                friction_coefficient,
            } => mu_ok(friction_coefficient),
        }
    }
}

impl ContactModel {
    /// Checks parameter ranges; the error message names the offending field, e.g.
    /// `normal.restitution must lie in (0, 1], got 1.3`.
    pub fn validate(&self) -> Result<(), ParameterError> {
        self.normal.validate()?;
        self.friction.validate()?;
        if let Some(r) = &self.rolling {
            check(
                r.coefficient >= 0.0 && r.coefficient.is_finite(),
                "rolling.coefficient",
                "be >= 0",
                r.coefficient,
            )?;
            check(
                r.regularization_s > 0.0 && r.regularization_s.is_finite(),
                "rolling.regularization_s",
                "be > 0",
                r.regularization_s,
            )?;
        }
        if let Some(a) = &self.adhesion {
            check(
                a.surface_energy_j_m2 >= 0.0 && a.surface_energy_j_m2.is_finite(),
                "adhesion.surface_energy_j_m2",
                "be >= 0",
                a.surface_energy_j_m2,
            )?;
            check(
                a.hamaker_constant_j > 0.0 && a.hamaker_constant_j.is_finite(),
                "adhesion.hamaker_constant_j",
                "be > 0",
                a.hamaker_constant_j,
            )?;
            check(
                a.cutoff_ratio > 0.0 && a.cutoff_ratio <= 1.0,
                "adhesion.cutoff_ratio",
                "lie in (0, 1]",
                a.cutoff_ratio,
            )?;
        }
        Ok(())
    }

    /// Optional warm-up: fills the calling thread's memo of Gonthier's $\bar d(\varepsilon)$
    /// [D Eq. 2.79]. Caching is transparent (see the module docs), so calling this is never
    /// required for correctness; it only moves the one-off solve out of the first contact.
    pub fn prepare(&mut self) {
        if let NormalLaw::Gonthier { restitution, .. } = self.normal {
            let _ = normal::gonthier_damping_cached(restitution);
        }
    }

    /// Force of one contact on particle *i* (see the module docs of [`crate::contact`] for the
    /// sign conventions). For `overlap_m > 0` the normal, friction and rolling laws act and the
    /// history is updated (the impact velocity $\dot\delta_0 = \max(\dot\delta, v_{\min})$ is stored
    /// at first touch); for `overlap_m ≤ 0` the history is reset and only adhesion acts.
    #[inline]
    pub fn evaluate(
        &self,
        p: &PairProps,
        k: &ContactKinematics,
        h: &mut ContactHistory,
    ) -> ContactForce {
        if let (
            NormalLaw::HertzMindlin {
                restitution,
                clip_attractive,
            },
            FrictionLaw::Mindlin {
                friction_coefficient,
            },
            None,
            None,
        ) = (&self.normal, &self.friction, &self.rolling, &self.adhesion)
        {
            return hertz_mindlin_history(
                *restitution,
                *clip_attractive,
                *friction_coefficient,
                p,
                k,
                h,
            );
        }
        self.evaluate_general(p, k, h)
    }

    /// [`ContactModel::evaluate`] without the one-pass shortcut for the LIGGGHTS law pair
    /// (kept callable so that tests can check that both give the same numbers).
    #[inline]
    pub(crate) fn evaluate_general(
        &self,
        p: &PairProps,
        k: &ContactKinematics,
        h: &mut ContactHistory,
    ) -> ContactForce {
        let mut f = ContactForce::default();
        let delta = k.overlap_m;
        if delta > 0.0 {
            if h.impact_velocity_m_s == 0.0 {
                h.impact_velocity_m_s = k
                    .overlap_rate_m_s
                    .max(self.normal.min_impact_velocity_m_s());
            }
            let mut n = self
                .normal
                .response(p, delta, k.overlap_rate_m_s, h.impact_velocity_m_s);
            // Explicit-step stability cap of the impact-velocity-scaled dashpots (Gonthier,
            // Lankarani–Nikravesh): their coefficient ∝ F_el/δ̇₀ grows without bound for contacts
            // that formed at rest and are then loaded hard. A dashpot with c·Δt/M̄ > 2 makes any
            // explicit step diverge, so c is limited to M̄/Δt (only such enduring contacts reach it;
            // impact tests are unaffected).
            if k.dt_s > 0.0 && self.normal.scales_with_impact_velocity() {
                let c_max = p.m_eff_kg / k.dt_s;
                if n.damping_n_s_m > c_max {
                    n.damping_n_s_m = c_max;
                    n.dissipative_n = (c_max * k.overlap_rate_m_s).max(-n.elastic_n);
                }
            }
            f.normal_elastic_n = n.elastic_n;
            f.normal_dissipative_n = n.dissipative_n;
            f.normal_energy_j = n.energy_j;
            let (ft, et) = self.friction.force(&self.normal, p, k, &n, h);
            f.tangential_n = ft;
            f.tangential_energy_j = et;
            if let Some(r) = &self.rolling {
                f.rolling_torque_nm = r.torque(p, k, n.elastic_n + n.dissipative_n);
            }
        } else {
            *h = ContactHistory::default();
        }
        if let Some(a) = &self.adhesion {
            let (force, potential) = a.force_and_potential(p, delta);
            f.normal_elastic_n -= force;
            f.normal_energy_j += potential;
        }
        f
    }

    /// Largest gap in m at which the law still produces a force: 0 without adhesion, the DMT
    /// cut-off $g^*$ [P Eq. (7)] with it. The pipeline calls [`ContactModel::evaluate`] for gaps in
    /// $(-g^*, 0]$ as well.
    pub fn max_interaction_gap_m(&self, p: &PairProps) -> f64 {
        self.adhesion.as_ref().map_or(0.0, |a| a.cutoff_gap_m(p))
    }

    /// Duration of a head-on contact at `impact_velocity_m_s`, for time-step checks: Hertz'
    /// $t_e$ [D Eq. 4.8] for Hertz-type laws (elastic estimate; velocity bounded below by the law's
    /// minimum impact velocity), $\pi/\sqrt{k_N/\bar M\,(1-\zeta^2)}$ with
    /// $\zeta = |\ln e|/\sqrt{\ln^2 e+\pi^2}$ for the linear law.
    pub fn contact_time_estimate_s(&self, p: &PairProps, impact_velocity_m_s: f64) -> f64 {
        match self.normal {
            NormalLaw::Linear {
                stiffness_n_m,
                restitution,
                ..
            } => {
                let l = restitution.ln();
                let zeta2 = l * l / (l * l + std::f64::consts::PI * std::f64::consts::PI);
                std::f64::consts::PI / (stiffness_n_m / p.m_eff_kg * (1.0 - zeta2)).sqrt()
            }
            _ => {
                let v = impact_velocity_m_s
                    .abs()
                    .max(self.normal.min_impact_velocity_m_s());
                hertz::hertz_contact_time(p.e_eff_pa, p.r_eff_m, p.m_eff_kg, v)
            }
        }
    }

    /// Linearised normal stiffness in N/m: for Hertz-type laws the tangent stiffness
    /// $\tfrac32 k_n\sqrt{\delta_{\max}}$ at the maximum overlap of an impact at
    /// `impact_velocity_m_s` [D Eq. 2.80], for the linear law $k_N$. With
    /// $\omega_{con} = \sqrt{k/m}$ [D Eq. 2.83] it gives $\Delta t_{\max} = \pi/\omega_{con}$
    /// [D Tab. 2.3].
    pub fn stiffness_estimate_n_m(&self, p: &PairProps, impact_velocity_m_s: f64) -> f64 {
        match self.normal {
            NormalLaw::Linear { stiffness_n_m, .. } => stiffness_n_m,
            _ => {
                let v = impact_velocity_m_s
                    .abs()
                    .max(self.normal.min_impact_velocity_m_s());
                let kn = hertz::hertz_stiffness(p.e_eff_pa, p.r_eff_m);
                1.5 * kn * hertz::hertz_max_overlap(kn, p.m_eff_kg, v).sqrt()
            }
        }
    }
}

impl ContactModel {
    /// For LIGGGHTS' `hertz` + `tangential history` without rolling resistance or adhesion:
    /// the damping factor $-2\sqrt{5/6}\,\beta(e)$, the friction coefficient and whether the
    /// normal force is clipped at zero; `None` for every other model.
    pub(crate) fn hertz_mindlin_constants(&self) -> Option<(f64, f64, bool)> {
        match (&self.normal, &self.friction, &self.rolling, &self.adhesion) {
            (
                NormalLaw::HertzMindlin {
                    restitution,
                    clip_attractive,
                },
                FrictionLaw::Mindlin {
                    friction_coefficient,
                },
                None,
                None,
            ) => Some((
                -2.0 * (5.0_f64 / 6.0).sqrt() * normal::liggghts_beta(*restitution),
                *friction_coefficient,
                *clip_attractive,
            )),
            _ => None,
        }
    }
}

/// LIGGGHTS' `hertz` + `tangential history` in one pass (the same numbers as the general path of
/// [`ContactModel::evaluate`] for [`NormalLaw::HertzMindlin`] with [`FrictionLaw::Mindlin`] and
/// no rolling resistance or adhesion; see `docs` of those laws and the LIGGGHTS reference). This
/// is the law of most benchmark and comparison runs, so it is kept free of dispatch and of
/// repeated logarithms.
#[inline]
fn hertz_mindlin_history(
    restitution: f64,
    clip_attractive: bool,
    mu: f64,
    p: &PairProps,
    k: &ContactKinematics,
    h: &mut ContactHistory,
) -> ContactForce {
    let delta = k.overlap_m;
    if delta <= 0.0 {
        *h = ContactHistory::default();
        return ContactForce::default();
    }
    if h.impact_velocity_m_s == 0.0 {
        h.impact_velocity_m_s = k.overlap_rate_m_s.max(default_min_impact_velocity());
    }
    let damping = -2.0 * (5.0_f64 / 6.0).sqrt() * normal::liggghts_beta(restitution);
    // Normal: a = √(R δ), S_n = 2 E a, k_n = 4/3 E a, γ_n = −2 √(5/6) β √(S_n m*).
    let a = (p.r_eff_m * delta).sqrt();
    let sn = 2.0 * p.e_eff_pa * a;
    let kn = 4.0 / 3.0 * p.e_eff_pa * a;
    let gamma_n = damping * (sn * p.m_eff_kg).sqrt();
    let elastic = kn * delta;
    let mut dissipative = gamma_n * k.overlap_rate_m_s;
    if clip_attractive {
        dissipative = dissipative.max(-elastic);
    }
    // Tangential: ξ += v_t Δt projected on the tangent plane; Coulomb cut-off at μ|F_n|.
    let nrm = k.normal;
    let vt = crate::math::tangential_part(&k.tangential_velocity_m_s, &nrm);
    let kt = 8.0 * p.g_eff_pa * a;
    let gamma_t = damping * (kt * p.m_eff_kg).sqrt();
    let mut xi = h.spring_m + vt * k.dt_s;
    xi -= nrm * xi.dot(&nrm);
    let shear_len = xi.norm();
    let ft_shear = kt * shear_len;
    let ft_friction = mu * (elastic + dissipative).abs();
    let ft = if ft_shear > ft_friction {
        if shear_len != 0.0 {
            let f = -kt * xi * (ft_friction / ft_shear);
            xi = -f / kt;
            f
        } else {
            Vec3::zeros()
        }
    } else {
        -kt * xi - gamma_t * vt
    };
    h.spring_m = xi;
    ContactForce {
        normal_elastic_n: elastic,
        normal_dissipative_n: dissipative,
        tangential_n: ft,
        rolling_torque_nm: Vec3::zeros(),
        normal_energy_j: 0.4 * kn * delta * delta,
        tangential_energy_j: 0.5 * kt * xi.norm_squared(),
    }
}
