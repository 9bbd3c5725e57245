//! Elastic–perfectly-plastic restitution of Thornton (1997), "Coefficient of restitution for
//! collinear collisions of elastic–perfectly plastic spheres", J. Appl. Mech. 64, 383–386.
//!
//! Hertz contact until the maximum contact pressure reaches the limiting pressure $p_y$; beyond,
//! the pressure is capped at $p_y$ (loading) and unloading is Hertzian with an enlarged radius.
//! The yield velocity is
//! $$V_y = \sqrt{\pi^4/40}\,\Big(\frac{p_y^5}{\bar E^4\rho}\Big)^{1/2} \approx 1.56\Big(\frac{p_y^5}{\bar E^4\rho}\Big)^{1/2}$$
//! (sphere on a wall, Thornton 1997) and for $V_i > V_y$
//! $$e = \Big(\frac{6\sqrt3}{5}\Big)^{1/2}\Big[1 - \frac16\Big(\frac{V_y}{V_i}\Big)^2\Big]^{1/2}
//! \Big[\frac{V_y/V_i}{V_y/V_i + 2\sqrt{6/5 - \tfrac15 (V_y/V_i)^2}}\Big]^{1/4},$$
//! $e = 1$ below. With the effective mass and radius the same holds for two spheres:
//! $\rho$ is then $3\bar M/(4\pi\bar R^3)$.

use crate::hertz::HertzPair;

/// Factor of Johnson (1985): first yield under a Hertz contact when $p_0 = 1.6\,\sigma_y$
/// (ν ≈ 0.3). Used as the default limiting pressure $p_y = 1.6\,\sigma_y$ of the softer body.
pub const FIRST_YIELD_PRESSURE_FACTOR: f64 = 1.6;

/// Yield velocity $V_y$ (m/s) of the pair for limiting contact pressure `p_y` (Pa):
/// the impact velocity at which the Hertz pressure $p_0$ [`HertzPair::max_pressure`] reaches $p_y$.
pub fn yield_velocity(pair: &HertzPair, p_y: f64) -> f64 {
    // p0 ∝ √δ_max ∝ v^{2/5}: p0(v) = p0(1 m/s) v^{2/5}
    let p1 = pair.max_pressure(1.0);
    (p_y / p1).powf(2.5)
}

/// Thornton's restitution for impact velocity `v` given the yield velocity `v_y` (both m/s).
pub fn restitution(v: f64, v_y: f64) -> f64 {
    if v <= v_y {
        return 1.0;
    }
    let x = v_y / v;
    (6.0 * 3f64.sqrt() / 5.0).sqrt()
        * (1.0 - x * x / 6.0).sqrt()
        * (x / (x + 2.0 * (1.2 - 0.2 * x * x).sqrt())).powf(0.25)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hertz::{effective_modulus, sphere_mass};

    /// $V_y$ from the pressure condition equals the closed form $1.56\sqrt{p_y^5/(\bar E^4\rho)}$.
    #[test]
    fn yield_velocity_closed_form() {
        let r = 0.015;
        let rho = 7800.0;
        let pair = HertzPair {
            e_eff: effective_modulus(208e9, 0.3, 208e9, 0.3),
            r_eff: r,
            m_eff: sphere_mass(r, rho),
        };
        let p_y = 1.6 * 230e6;
        let vy = yield_velocity(&pair, p_y);
        let closed = (std::f64::consts::PI.powi(4) / 40.0).sqrt()
            * (p_y.powi(5) / (pair.e_eff.powi(4) * rho)).sqrt();
        assert!((vy / closed - 1.0).abs() < 1e-9, "{vy} vs {closed}");
        assert!((closed / (p_y.powi(5) / (pair.e_eff.powi(4) * rho)).sqrt() - 1.56).abs() < 1e-3);
    }

    /// e = 1 at V = V_y (continuous), decreasing, and $e \to 1.185\,(V_y/V)^{1/4}$ for $V \gg V_y$.
    #[test]
    fn limits() {
        assert!((restitution(1.0, 1.0) - 1.0).abs() < 1e-12);
        let mut last = 1.0;
        for k in 1..50 {
            let e = restitution(1.0 + k as f64, 1.0);
            assert!(e < last);
            last = e;
        }
        let x: f64 = 1e-6;
        let asym = (6.0 * 3f64.sqrt() / 5.0).sqrt() * (x / (2.0 * 1.2f64.sqrt())).powf(0.25);
        assert!((restitution(1.0 / x, 1.0) / asym - 1.0).abs() < 1e-5);
    }
}
