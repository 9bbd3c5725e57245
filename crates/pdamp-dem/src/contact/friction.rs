//! Tangential force laws (regularised sliding [D Eq. 2.85], Coulomb spring–dashpot with return
//! mapping [P Eq. (5)], LIGGGHTS' tangential history model) and rolling resistance.

use super::normal::{NormalResponse, liggghts_beta};
use super::{
    ContactHistory, ContactKinematics, FrictionLaw, NormalLaw, PairProps, RollingResistance,
};
use crate::math::{Vec3, tangential_part};

impl FrictionLaw {
    /// Tangential force on *i* and the energy stored in the tangential spring, for a contact with
    /// overlap > 0 whose normal response is `n`. Updates the spring elongation in `h`.
    ///
    /// * `RegularizedSliding`: $-\mu F_n \hat{\mathbf v}^t\tanh(\eta|\mathbf v^t|)$ with
    ///   $F_n = \max(F_{el}+F_{dis}, 0)$ (adhesion excluded); no history (spring kept at 0).
    /// * `CoulombSpring`: the old spring is rotated into the current tangent plane (length kept),
    ///   $\boldsymbol\xi \mathrel{+}= \mathbf v^t\Delta t$, trial $\mathbf f = -k_t\boldsymbol\xi - d_t\mathbf v^t$;
    ///   if $|\mathbf f| > \mu F_n$ the force is scaled to $\mu F_n$ and the spring is mapped back to
    ///   $\boldsymbol\xi = -(\mathbf f + d_t\mathbf v^t)/k_t$. The force never exceeds $\mu F_n$.
    /// * `Mindlin` (LIGGGHTS `tangential history`): $\boldsymbol\xi \mathrel{+}= \mathbf v^t\Delta t$, then
    ///   projected onto the tangent plane (length not rescaled); if $k_t|\boldsymbol\xi| \le \mu|F_n|$
    ///   the force is $-k_t\boldsymbol\xi - \gamma_t\mathbf v^t$ (the damping may exceed the Coulomb
    ///   limit while sticking, as in LIGGGHTS), otherwise $-\mu|F_n|\boldsymbol\xi/|\boldsymbol\xi|$ and
    ///   $\boldsymbol\xi = -\mathbf f/k_t$.
    #[inline]
    pub(crate) fn force(
        &self,
        normal: &NormalLaw,
        p: &PairProps,
        k: &ContactKinematics,
        n: &NormalResponse,
        h: &mut ContactHistory,
    ) -> (Vec3, f64) {
        let fn_total = n.elastic_n + n.dissipative_n;
        let nrm = k.normal;
        let vt = tangential_part(&k.tangential_velocity_m_s, &nrm);
        match *self {
            FrictionLaw::Frictionless => (Vec3::zeros(), 0.0),
            FrictionLaw::RegularizedSliding {
                friction_coefficient: mu,
                regularization_s_m: eta,
            } => {
                let speed = vt.norm();
                let f = if speed > 0.0 {
                    vt * (-mu * fn_total.max(0.0) * (eta * speed).tanh() / speed)
                } else {
                    Vec3::zeros()
                };
                (f, 0.0)
            }
            FrictionLaw::CoulombSpring {
                friction_coefficient: mu,
                stiffness_ratio,
                damping_ratio,
            } => {
                let nu = p.poisson_mean;
                let ratio = stiffness_ratio.unwrap_or((1.0 - nu) / (1.0 - 0.5 * nu));
                let kt = ratio * n.tangent_stiffness_n_m;
                let dt_coeff = damping_ratio * n.damping_n_s_m;
                // Rotate the old spring into the current tangent plane, keeping its length.
                let old_len = h.spring_m.norm();
                let mut xi = tangential_part(&h.spring_m, &nrm);
                let proj_len = xi.norm();
                if proj_len > 0.0 {
                    xi *= old_len / proj_len;
                }
                xi += vt * k.dt_s;
                let mut f = -kt * xi - dt_coeff * vt;
                let limit = mu * fn_total.max(0.0);
                let f_len = f.norm();
                if f_len > limit {
                    // Return mapping onto the Coulomb cone.
                    f *= limit / f_len;
                    xi = if kt > 0.0 {
                        -(f + dt_coeff * vt) / kt
                    } else {
                        Vec3::zeros()
                    };
                }
                h.spring_m = xi;
                (f, 0.5 * kt * xi.norm_squared())
            }
            FrictionLaw::Mindlin {
                friction_coefficient: mu,
            } => {
                let a = (p.r_eff_m * k.overlap_m).sqrt();
                let kt = 8.0 * p.g_eff_pa * a;
                let gamma_t = -2.0
                    * (5.0_f64 / 6.0).sqrt()
                    * liggghts_beta(normal.restitution())
                    * (kt * p.m_eff_kg).sqrt();
                let mut xi = h.spring_m + vt * k.dt_s;
                xi -= nrm * xi.dot(&nrm);
                let shear_len = xi.norm();
                let ft_shear = kt * shear_len;
                let ft_friction = mu * fn_total.abs();
                let f = if ft_shear > ft_friction {
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
                (f, 0.5 * kt * xi.norm_squared())
            }
        }
    }
}

impl RollingResistance {
    /// Rolling-resistance torque on *i*,
    /// $-\mu_r\bar R\,\max(F_n,0)\,\frac{\boldsymbol\omega_{rel}}{|\boldsymbol\omega_{rel}|}\tanh(|\boldsymbol\omega_{rel}|t_r)$;
    /// its magnitude never exceeds $\mu_r\bar R F_n$.
    #[inline]
    pub(crate) fn torque(&self, p: &PairProps, k: &ContactKinematics, normal_force_n: f64) -> Vec3 {
        let w = k.relative_angular_velocity_rad_s;
        let speed = w.norm();
        if speed > 0.0 {
            w * (-self.coefficient
                * p.r_eff_m
                * normal_force_n.max(0.0)
                * (speed * self.regularization_s).tanh()
                / speed)
        } else {
            Vec3::zeros()
        }
    }
}
