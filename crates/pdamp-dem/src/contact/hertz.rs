//! Analytic results of Hertz impact theory and Gonthier's damping parameter.
//!
//! These closed forms serve three purposes: the contact laws use them (stiffness, $\bar d$),
//! the pipeline uses them for time-step and neighbour-skin estimates (contact time, maximum
//! overlap), and the tests use them as the reference the integrated impacts must reproduce.
//! All quantities are SI; "effective" quantities are those of [D Eq. 2.71, 2.72, 2.81].

/// Hertz normal stiffness $k_n = \tfrac43 \bar E \sqrt{\bar R}$ [D Eq. 2.70], in N/m^{3/2},
/// so that the elastic force is $F_n = k_n \delta^{3/2}$ [D Eq. 2.69].
#[inline]
pub fn hertz_stiffness(e_eff_pa: f64, r_eff_m: f64) -> f64 {
    4.0 / 3.0 * e_eff_pa * r_eff_m.sqrt()
}

/// Maximum overlap of an elastic Hertz impact
/// $\delta_{\max} = \left(\frac{5 \bar M \dot\delta_0^2}{4 k_n}\right)^{2/5}$ [D Eq. 2.80], in m.
///
/// `k_n` is the Hertz stiffness of [`hertz_stiffness`], `m_eff_kg` the effective mass
/// [D Eq. 2.81] and `v0_m_s` the normal impact velocity $\dot\delta_0$.
#[inline]
pub fn hertz_max_overlap(k_n: f64, m_eff_kg: f64, v0_m_s: f64) -> f64 {
    (5.0 * m_eff_kg * v0_m_s * v0_m_s / (4.0 * k_n)).powf(0.4)
}

/// Duration of an elastic Hertz impact
/// $t_e = 2.868 \left(\frac{\bar M^2}{v \bar R \bar E^2}\right)^{1/5}$ [D Eq. 4.8], in s.
///
/// (The exact Hertz value is $2.9432\,\delta_{\max}/v$; eq. 4.8 agrees with it to 4 digits.)
#[inline]
pub fn hertz_contact_time(e_eff_pa: f64, r_eff_m: f64, m_eff_kg: f64, v0_m_s: f64) -> f64 {
    2.868 * (m_eff_kg * m_eff_kg / (v0_m_s * r_eff_m * e_eff_pa * e_eff_pa)).powf(0.2)
}

/// Peak force of an elastic Hertz impact $F_{\max} = k_n \delta_{\max}^{3/2}$
/// ([D Eq. 2.69] evaluated at the maximum overlap of [D Eq. 2.80]), in N.
#[inline]
pub fn hertz_max_force(k_n: f64, m_eff_kg: f64, v0_m_s: f64) -> f64 {
    k_n * hertz_max_overlap(k_n, m_eff_kg, v0_m_s).powf(1.5)
}

/// $f(\bar d)/\bar d^2$ with $f(\bar d) = \ln(1+\bar d/\varepsilon) - \ln(1-\bar d) - \bar d(1+1/\varepsilon)$,
/// the logarithm of [D Eq. 2.79] with its trivial root $\bar d = 0$ divided out. Evaluated by its
/// power series for small $\bar d/\varepsilon$ (to avoid cancellation) and directly otherwise.
fn gonthier_reduced_residual(d: f64, e: f64) -> f64 {
    let x = d / e;
    if x < 0.05 {
        // f = Σ_{k≥2} [(-1)^{k+1} x^k + d^k] / k  ⇒  f/d² = Σ_{k≥2} d^{k-2} [(-1)^{k+1} e^{-k} + 1] / k.
        // The k = 2 coefficient (1 − 1/ε²)/2 is formed as (ε−1)(ε+1)/(2ε²) to keep it accurate
        // for ε → 1.
        let mut sum = (e - 1.0) * (e + 1.0) / (2.0 * e * e);
        let mut dk = 1.0; // d^{k-2}
        let mut xk = 1.0 / (e * e); // e^{-k}
        let mut sign = 1.0; // (-1)^{k+1} for k = 3
        for k in 3..40 {
            dk *= d;
            xk /= e;
            sum += dk * (sign * xk + 1.0) / k as f64;
            sign = -sign;
        }
        sum
    } else {
        ((x).ln_1p() - (-d).ln_1p() - d * (1.0 + 1.0 / e)) / (d * d)
    }
}

/// Gonthier's nonlinear damping parameter $\bar d(\varepsilon)$, the nontrivial root of
/// $\frac{1 + \bar d/\varepsilon}{1 - \bar d} = e^{\bar d (1 + 1/\varepsilon)}$ [D Eq. 2.79].
///
/// Valid for $\varepsilon \in (0, 1]$ with $\bar d(1) = 0$ and $\bar d \to 1$ for $\varepsilon \to 0$
/// (for $\varepsilon \lesssim 0.03$ the root lies closer to 1 than one ulp and the largest double
/// below 1 is returned). Returns NaN for $\varepsilon \notin (0, 1]$. Solved by bisection on the
/// reduced residual $f(\bar d)/\bar d^2$ (which is negative at $0^+$ and tends to $+\infty$ at $1^-$)
/// down to machine precision; costs a few µs, so callers cache the result.
pub fn gonthier_damping(restitution: f64) -> f64 {
    let e = restitution;
    if !(e > 0.0 && e <= 1.0) {
        return f64::NAN;
    }
    if e == 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if gonthier_reduced_residual(mid, e) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    // `hi` is the smallest double with a non-negative residual; when the root is closer to 1
    // than an ulp, `hi` is 1.0 itself and `lo` the largest double below it.
    if hi < 1.0 { 0.5 * (lo + hi) } else { lo }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Residual of [D Eq. 2.79] written as LHS/RHS − 1.
    fn eq_2_79_residual(d: f64, e: f64) -> f64 {
        (1.0 + d / e) / (1.0 - d) / (d * (1.0 + 1.0 / e)).exp() - 1.0
    }

    #[test]
    fn gonthier_damping_solves_eq_2_79() {
        assert_eq!(gonthier_damping(1.0), 0.0);
        assert!(gonthier_damping(0.0).is_nan());
        assert!(gonthier_damping(1.2).is_nan());
        assert!(gonthier_damping(f64::NAN).is_nan());
        let mut prev = 1.0;
        for i in 0..=400 {
            let e = 0.02 + 0.98 * i as f64 / 400.0;
            let d = gonthier_damping(e);
            assert!(d <= prev, "d̄ must decrease with ε");
            prev = d;
            if e == 1.0 {
                continue;
            }
            assert!(d > 0.0 && d < 1.0, "d̄({e}) = {d} outside (0, 1)");
            if e >= 0.15 {
                // 1 − d̄ > 1e-3 here, so the residual can be evaluated to ~1e-13.
                let r = eq_2_79_residual(d, e);
                assert!(r.abs() < 1e-12, "residual of eq 2.79 at ε = {e}: {r:e}");
            } else {
                // For small ε, 1 − d̄ is tiny and the residual is limited by the spacing of doubles
                // near 1: check that d̄ is the best double, i.e. the residual changes sign across it.
                let below = gonthier_reduced_residual(d - f64::EPSILON, e);
                let above = gonthier_reduced_residual(
                    (d + f64::EPSILON / 2.0).min(1.0 - f64::EPSILON / 2.0),
                    e,
                );
                assert!(
                    below < 0.0 && (above >= 0.0 || d == 1.0 - f64::EPSILON / 2.0),
                    "ε = {e}: d̄ = {d}"
                );
            }
        }
        // Near ε = 1 the root behaves like 1.5 (1 − ε).
        for s in [1e-4, 1e-7, 1e-10] {
            let e = 1.0 - s;
            let s = 1.0 - e; // the exactly representable distance to 1
            let d = gonthier_damping(e);
            assert!(
                (d / (1.5 * s) - 1.0).abs() < 2.0 * s + 1e-12,
                "d̄(1 − {s}) = {d}"
            );
        }
        // Very small ε: d̄ → 1 (rounded), never ≥ 1.
        let d = gonthier_damping(0.01);
        assert!(d < 1.0 && d > 1.0 - 1e-15);
    }

    #[test]
    fn gonthier_damping_known_values() {
        // Reference roots computed independently with 50-digit arithmetic (mpmath bisection of
        // eq 2.79); the integrated Gonthier impacts in `contact::tests` cross-check them
        // dynamically (the restitution comes out as ε).
        let cases = [
            (0.1, 0.999_815_939_749_566_8),
            (0.2, 0.983_833_343_158_157_3),
            (0.5, 0.716_375_266_635_687_5),
            (0.8, 0.298_516_962_692_042_9),
            (0.95, 0.074_980_275_023_044_54),
        ];
        for (e, expected) in cases {
            let d = gonthier_damping(e);
            assert!(
                (d - expected).abs() < 1e-13,
                "d̄({e}) = {d:.17}, expected {expected}"
            );
        }
    }

    #[test]
    fn published_steel_sphere_on_steel_wall() {
        // 30 mm diameter steel sphere (E = 210 GPa, ν = 0.3, ρ = 7850) at 1 m/s on a steel wall.
        let r = 0.015;
        let m = 7850.0 * 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
        let e_eff = 1.0 / (2.0 * (1.0 - 0.09) / 210e9);
        let t = hertz_contact_time(e_eff, r, m, 1.0);
        let k = hertz_stiffness(e_eff, r);
        let f = hertz_max_force(k, m, 1.0);
        // Eq 4.8 gives 103.66 µs and eq 2.69/2.80 give 3938.6 N; the quoted 103.8 µs / 3909 N
        // are within 0.14 % / 0.76 % of these.
        assert!((t - 103.656e-6).abs() < 0.002e-6, "t_e = {t:e}");
        assert!((f - 3938.57).abs() < 0.01, "F_max = {f}");
        assert!((t / 103.8e-6 - 1.0).abs() < 0.002, "t_e vs quoted 103.8 µs");
        assert!((f / 3909.0 - 1.0).abs() < 0.008, "F_max vs quoted 3909 N");
        // Exact Hertz duration 2.9432 δ_max / v agrees with eq 4.8 to 1e-4.
        let exact = 2.9432 * hertz_max_overlap(k, m, 1.0);
        assert!((t / exact - 1.0).abs() < 1e-4);
    }
}
