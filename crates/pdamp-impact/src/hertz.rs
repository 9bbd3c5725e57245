//! Elastic Hertz impact of a sphere on a half-space or on a second sphere.
//!
//! Effective quantities [D Eq. 2.71, 2.72, 2.81], stiffness $k_n = \tfrac43\bar E\sqrt{\bar R}$
//! [D Eq. 2.70], maximum overlap $\delta_{max} = (5\bar M v^2/(4k_n))^{2/5}$ [D Eq. 2.80], contact
//! time $t_e = 2.868\,(\bar M^2/(v\bar R\bar E^2))^{1/5}$ [D Eq. 4.8] and the force history from the
//! Hertz equation of motion $\bar M\ddot\delta = -k_n\delta^{3/2}$.

/// Effective modulus $1/\bar E = (1-\nu_1^2)/E_1 + (1-\nu_2^2)/E_2$ [D Eq. 2.71], in Pa.
/// A rigid partner is `e2 = f64::INFINITY`.
pub fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    let c2 = if e2.is_finite() {
        (1.0 - nu2 * nu2) / e2
    } else {
        0.0
    };
    1.0 / ((1.0 - nu1 * nu1) / e1 + c2)
}

/// Harmonic mean $1/\bar X = 1/x_1 + 1/x_2$ (radius [D Eq. 2.72], mass [D Eq. 2.81]); an infinite
/// partner (plane, fixed wall) gives $x_1$.
pub fn effective(x1: f64, x2: f64) -> f64 {
    if x2.is_finite() {
        1.0 / (1.0 / x1 + 1.0 / x2)
    } else {
        x1
    }
}

/// Sphere mass $\tfrac43\pi r^3\rho$, kg.
pub fn sphere_mass(radius_m: f64, density_kg_m3: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * radius_m.powi(3) * density_kg_m3
}

/// Effective Hertz contact pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HertzPair {
    /// Effective modulus $\bar E$, Pa.
    pub e_eff: f64,
    /// Effective radius $\bar R$, m.
    pub r_eff: f64,
    /// Effective mass $\bar M$, kg.
    pub m_eff: f64,
}

impl HertzPair {
    /// Stiffness $k_n = \tfrac43\bar E\sqrt{\bar R}$ [D Eq. 2.70], N/m^{3/2}.
    pub fn k_n(&self) -> f64 {
        4.0 / 3.0 * self.e_eff * self.r_eff.sqrt()
    }

    /// Maximum overlap $\delta_{max} = (5\bar M v^2/(4k_n))^{2/5}$ [D Eq. 2.80], m.
    pub fn max_overlap(&self, v: f64) -> f64 {
        (5.0 * self.m_eff * v * v / (4.0 * self.k_n())).powf(0.4)
    }

    /// Maximum force $k_n\delta_{max}^{3/2}$, N.
    pub fn max_force(&self, v: f64) -> f64 {
        self.k_n() * self.max_overlap(v).powf(1.5)
    }

    /// Contact radius at maximum overlap $a = \sqrt{\bar R\delta_{max}}$, m.
    pub fn max_contact_radius(&self, v: f64) -> f64 {
        (self.r_eff * self.max_overlap(v)).sqrt()
    }

    /// Maximum Hertz pressure $p_0 = 2\bar E a/(\pi\bar R)$, Pa.
    pub fn max_pressure(&self, v: f64) -> f64 {
        2.0 * self.e_eff * self.max_contact_radius(v) / (std::f64::consts::PI * self.r_eff)
    }

    /// Contact time $t_e = 2.868\,(\bar M^2/(v\bar R\bar E^2))^{1/5}$ [D Eq. 4.8], s.
    pub fn contact_time(&self, v: f64) -> f64 {
        2.868 * (self.m_eff * self.m_eff / (v * self.r_eff * self.e_eff * self.e_eff)).powf(0.2)
    }

    /// Force history of the Hertz impact: integrates $\bar M\ddot\delta = -k_n\delta^{3/2}$
    /// (RK4, `steps` steps over the contact) and returns `(t_s, force_n)` samples from first
    /// touch to separation; the last sample is at $\delta = 0$.
    pub fn force_history(&self, v: f64, steps: usize) -> Vec<(f64, f64)> {
        let k = self.k_n();
        let m = self.m_eff;
        let dt = self.contact_time(v) / steps.max(8) as f64;
        let acc = |d: f64| -k * d.max(0.0).powf(1.5) / m;
        let (mut t, mut d, mut dd) = (0.0, 0.0, v);
        let mut out = vec![(0.0, 0.0)];
        loop {
            let k1 = (dd, acc(d));
            let k2 = (dd + 0.5 * dt * k1.1, acc(d + 0.5 * dt * k1.0));
            let k3 = (dd + 0.5 * dt * k2.1, acc(d + 0.5 * dt * k2.0));
            let k4 = (dd + dt * k3.1, acc(d + dt * k3.0));
            let dn = d + dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            let ddn = dd + dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            if dn <= 0.0 {
                // linear interpolation of the separation instant
                let s = d / (d - dn);
                out.push((t + s * dt, 0.0));
                return out;
            }
            t += dt;
            d = dn;
            dd = ddn;
            out.push((t, k * d.powf(1.5)));
            if out.len() > 100 * steps.max(8) {
                return out;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel_wall() -> HertzPair {
        let r = 0.015;
        HertzPair {
            e_eff: effective_modulus(208e9, 0.3, 208e9, 0.3),
            r_eff: r,
            m_eff: sphere_mass(r, 7800.0),
        }
    }

    /// 30 mm steel sphere on a steel wall at 1 m/s: t_e ≈ 104 µs, F_max ≈ 3.9 kN [D Eq. 4.8, 2.80]
    /// (the dissertation's FE gives 101 µs, D L1859).
    #[test]
    fn steel_on_steel_values() {
        let h = steel_wall();
        let te = h.contact_time(1.0);
        assert!((te - 103.8e-6).abs() < 0.5e-6, "t_e = {te}");
        let f = h.max_force(1.0);
        assert!((f - 3909.0).abs() < 20.0, "F = {f}");
    }

    /// The ODE's contact time agrees with the closed form [D Eq. 4.8] (2.868 vs the exact
    /// 2.8665…: 0.1 %), and its peak force with $k_n\delta_{max}^{3/2}$.
    #[test]
    fn force_history_matches_closed_form() {
        let h = steel_wall();
        for v in [0.01, 1.0, 3.0] {
            let hist = h.force_history(v, 4000);
            let tc = hist.last().unwrap().0;
            let rel = (tc / h.contact_time(v) - 1.0).abs();
            assert!(rel < 2e-3, "v = {v}: t_c = {tc}, rel = {rel}");
            let fmax = hist.iter().map(|p| p.1).fold(0.0, f64::max);
            assert!((fmax / h.max_force(v) - 1.0).abs() < 1e-5);
        }
    }
}
