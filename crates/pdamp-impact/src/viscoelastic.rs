//! Viscoelastic Hertz impact after Kuwabara & Kono (1987) and Brilliantov et al. (1996):
//! $$F = k_n\big(\delta^{3/2} + A\sqrt\delta\,\dot\delta\big),\quad F \ge 0$$
//! (Brilliantov et al. 1996, eq. 13 form; the 3/2 of Kuwabara–Kono is absorbed in A),
//! with the dissipative time constant $A$ (s). The restitution is obtained by integrating
//! $\bar M\ddot\delta = -F$ (RK4); for small $A$ it follows Ramírez et al. (1999)
//! $\varepsilon = 1 - C_1 A\rho^{2/5}v^{1/5} + C_2 A^2\rho^{4/5}v^{2/5}$, $\rho = k_n/\bar M$,
//! $C_1 = 1.15344$, $C_2 = 0.79826$.
//!
//! For a Prony-series material [D Eq. 4.5, 4.6] the parameters are taken at the impact's own
//! time scale: $\bar E$ from the storage modulus $G'(\omega)$ and $A = \tan\phi(\omega)/\omega$
//! with $\omega = \pi/t_c$ ([`prony_kk_parameters`]; an equivalent Kelvin–Voigt body).

use crate::hertz::HertzPair;

/// $C_1$ of Ramírez et al. (1999).
pub const C1: f64 = 1.15344;
/// $C_2$ of Ramírez et al. (1999).
pub const C2: f64 = 0.79826;

/// Result of a Kuwabara–Kono impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KkImpact {
    /// Coefficient of restitution.
    pub restitution: f64,
    /// Contact time (force > 0), s.
    pub contact_time_s: f64,
    /// Maximum force, N.
    pub max_force_n: f64,
}

/// Integrates the Kuwabara–Kono impact at velocity `v` (m/s) with dissipation constant `a_s` (s).
pub fn kk_impact(pair: &HertzPair, a_s: f64, v: f64) -> KkImpact {
    let k = pair.k_n();
    let m = pair.m_eff;
    let steps = 20_000usize;
    let dt = pair.contact_time(v) / steps as f64;
    let force = |d: f64, dd: f64| {
        if d <= 0.0 {
            0.0
        } else {
            (k * (d.powf(1.5) + a_s * d.sqrt() * dd)).max(0.0)
        }
    };
    let (mut t, mut d, mut dd) = (0.0f64, 0.0f64, v);
    let mut fmax = 0.0f64;
    for _ in 0..(100 * steps) {
        let f = |d: f64, dd: f64| (dd, -force(d, dd) / m);
        let k1 = f(d, dd);
        let k2 = f(d + 0.5 * dt * k1.0, dd + 0.5 * dt * k1.1);
        let k3 = f(d + 0.5 * dt * k2.0, dd + 0.5 * dt * k2.1);
        let k4 = f(d + dt * k3.0, dd + dt * k3.1);
        d += dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
        dd += dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        t += dt;
        let fnow = force(d, dd);
        fmax = fmax.max(fnow);
        if t > 10.0 * dt && (d <= 0.0 || (fnow == 0.0 && dd < 0.0)) {
            break;
        }
    }
    KkImpact {
        restitution: -dd / v,
        contact_time_s: t,
        max_force_n: fmax,
    }
}

/// Ramírez et al. (1999) second-order series for ε (valid for small $A\rho^{2/5}v^{1/5}$).
pub fn restitution_series(pair: &HertzPair, a_s: f64, v: f64) -> f64 {
    let x = a_s * (pair.k_n() / pair.m_eff).powf(0.4) * v.powf(0.2);
    1.0 - C1 * x + C2 * x * x
}

/// Storage and loss shear moduli $(G', G'')$ of a Prony series at angular frequency `omega`
/// [D Eq. 4.5, 4.6]: $G' = G_0[g_\infty + \sum g_i\omega^2\tau_i^2/(1+\omega^2\tau_i^2)]$,
/// $G'' = G_0\sum g_i\omega\tau_i/(1+\omega^2\tau_i^2)$, $g_\infty = 1-\sum g_i$ [D Eq. 4.7].
pub fn prony_complex_modulus(g0: f64, prony: &[[f64; 2]], omega: f64) -> (f64, f64) {
    let g_inf = 1.0 - prony.iter().map(|p| p[0]).sum::<f64>();
    let mut gs = g_inf;
    let mut gl = 0.0;
    for &[g, tau] in prony {
        let wt = omega * tau;
        gs += g * wt * wt / (1.0 + wt * wt);
        gl += g * wt / (1.0 + wt * wt);
    }
    (g0 * gs, g0 * gl)
}

/// Normalised relaxation function $g_R(t) = 1 - \sum g_i(1 - e^{-t/\tau_i})$ [D Eq. 4.5].
pub fn prony_relaxation(prony: &[[f64; 2]], t: f64) -> f64 {
    1.0 - prony
        .iter()
        .map(|&[g, tau]| g * (1.0 - (-t / tau).exp()))
        .sum::<f64>()
}

/// Kuwabara–Kono parameters of a Prony material pair at the impact time scale: returns the
/// Hertz pair with $\bar E$ from the storage modulus at $\omega = \pi/t_c$ and $A = \tan\phi/\omega$
/// (fixed point over $t_c$, [D Eq. 4.8]). `e_of_g(G)` maps a shear modulus of the Prony body to its
/// Young's modulus; `other_compliance` is $(1-\nu^2)/E$ of the partner (0 if rigid).
pub fn prony_kk_parameters(
    base: &HertzPair,
    g0: f64,
    prony: &[[f64; 2]],
    nu: f64,
    other_compliance: f64,
    v: f64,
) -> (HertzPair, f64) {
    let mut pair = *base;
    let mut a_s = 0.0;
    for _ in 0..50 {
        let omega = std::f64::consts::PI / pair.contact_time(v);
        let (gs, gl) = prony_complex_modulus(g0, prony, omega);
        let e = 2.0 * gs * (1.0 + nu);
        pair.e_eff = 1.0 / ((1.0 - nu * nu) / e + other_compliance);
        a_s = gl / gs / omega;
    }
    (pair, a_s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hertz::{effective_modulus, sphere_mass};

    fn pair() -> HertzPair {
        HertzPair {
            e_eff: effective_modulus(208e9, 0.3, 208e9, 0.3),
            r_eff: 0.015,
            m_eff: sphere_mass(0.015, 7800.0),
        }
    }

    /// Without dissipation the impact is elastic (ε = 1 within 1e-6) with the Hertz contact time.
    #[test]
    fn elastic_limit() {
        let p = pair();
        let r = kk_impact(&p, 0.0, 1.0);
        assert!((r.restitution - 1.0).abs() < 1e-6, "{}", r.restitution);
        assert!((r.contact_time_s / p.contact_time(1.0) - 1.0).abs() < 2e-3);
    }

    /// Small dissipation: ε agrees with Ramírez et al. (1999) to second order (|Δε| < 2e-4 for
    /// $A\rho^{2/5}v^{1/5}$ = 0.02, 0.05).
    #[test]
    fn matches_series() {
        let p = pair();
        let scale = (p.k_n() / p.m_eff).powf(0.4);
        for x in [0.02, 0.05] {
            let a = x / scale;
            let e = kk_impact(&p, a, 1.0).restitution;
            let s = restitution_series(&p, a, 1.0);
            assert!(
                (e - s).abs() < 2e-4 * (x / 0.02) * (x / 0.02),
                "x = {x}: {e} vs {s}"
            );
        }
    }

    /// Prony relaxation [D Eq. 4.5] and complex modulus limits: $G'(\omega\to0) = G_\infty$
    /// [D Eq. 4.7], $G'(\omega\to\infty) = G_0$.
    #[test]
    fn prony_limits() {
        let prony = [[0.3, 1e-3], [0.5, 1e-1]];
        assert!((prony_relaxation(&prony, 0.0) - 1.0).abs() < 1e-15);
        assert!((prony_relaxation(&prony, 1e9) - 0.2).abs() < 1e-12);
        let t = 2e-3;
        let exact = 1.0 - 0.3 * (1.0 - (-2.0f64).exp()) - 0.5 * (1.0 - (-0.02f64).exp());
        assert!((prony_relaxation(&prony, t) - exact).abs() < 1e-15);
        let (gs0, gl0) = prony_complex_modulus(1.0, &prony, 1e-9);
        assert!((gs0 - 0.2).abs() < 1e-9 && gl0 < 1e-6);
        let (gs1, _) = prony_complex_modulus(1.0, &prony, 1e12);
        assert!((gs1 - 1.0).abs() < 1e-6);
    }
}
