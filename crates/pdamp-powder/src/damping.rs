//! Damping ratios from a free decay as defined for paper Table 1: the logarithmic decrement
//! $\delta = \frac1n\ln\frac{x(t)}{x(t+nT)}$ between local minima and
//! $\zeta = 1/\sqrt{1+(2\pi/\delta)^2}$; ζ1 from the first to the second local minimum, ζ2 from
//! the second to the third, ζ̄5 from the first to the sixth (n = 5). Minima are taken after the
//! release of the load; amplitudes are |x| at the minima.

/// Damping ratio from a logarithmic decrement.
pub fn zeta_from_decrement(delta: f64) -> f64 {
    1.0 / (1.0 + (2.0 * std::f64::consts::PI / delta).powi(2)).sqrt()
}

/// Indices of strict local minima (x[i-1] > x\[i\] ≤ x[i+1]) with t ≥ `t_start`.
pub fn local_minima(t: &[f64], x: &[f64], t_start: f64) -> Vec<usize> {
    // series of different lengths (a damaged tip.csv): the common part
    (1..x.len().min(t.len()).saturating_sub(1))
        .filter(|&i| t[i] >= t_start && x[i - 1] > x[i] && x[i] <= x[i + 1])
        .collect()
}

/// Indices of local extrema of x (maxima and minima) with t ≥ `t_start`: the peaks whose
/// absolute values form the outer envelope (paper Fig. 2b).
pub fn local_extrema(t: &[f64], x: &[f64], t_start: f64) -> Vec<usize> {
    (1..x.len().min(t.len()).saturating_sub(1))
        .filter(|&i| {
            t[i] >= t_start
                && ((x[i - 1] > x[i] && x[i] <= x[i + 1]) || (x[i - 1] < x[i] && x[i] >= x[i + 1]))
        })
        .collect()
}

/// Table-1 damping ratios.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TableOneRatios {
    /// ζ1 (first → second minimum); `None` if fewer than two minima.
    pub zeta_1: Option<f64>,
    /// ζ2 (second → third minimum).
    pub zeta_2: Option<f64>,
    /// ζ̄5 (first → sixth minimum, n = 5).
    pub zeta_5: Option<f64>,
    /// Mean period between the minima used \[s\].
    pub period_s: Option<f64>,
}

/// Computes the Table-1 ratios of the signal `x(t)` after `t_release`.
pub fn table_one(t: &[f64], x: &[f64], t_release: f64) -> TableOneRatios {
    let m = local_minima(t, x, t_release);
    let amp = |k: usize| x[m[k]].abs();
    let z = |a: usize, b: usize| -> Option<f64> {
        (m.len() > b && amp(b) > 0.0)
            .then(|| zeta_from_decrement((amp(a) / amp(b)).ln() / (b - a) as f64))
    };
    TableOneRatios {
        zeta_1: z(0, 1),
        zeta_2: z(1, 2),
        zeta_5: z(0, 5),
        period_s: (m.len() > 1).then(|| (t[m[m.len() - 1]] - t[m[0]]) / (m.len() - 1) as f64),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_of_different_lengths_and_nan_do_not_panic() {
        let t = [0.0, 1.0, 2.0];
        let x = [1.0, -1.0, 1.0, -1.0, f64::NAN, 2.0];
        assert_eq!(local_minima(&t, &x, 0.0), vec![1]);
        let r = table_one(&x, &t, 0.0);
        assert!(r.zeta_1.is_none());
    }

    #[test]
    fn recovers_zeta_of_a_damped_oscillator() {
        let (zeta, f): (f64, f64) = (0.05, 700.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let t: Vec<f64> = (0..30000).map(|i| i as f64 * 1e-6).collect();
        let x: Vec<f64> = t
            .iter()
            .map(|&t| (-zeta * w * t).exp() * (wd * t).cos())
            .collect();
        let r = table_one(&t, &x, 0.0);
        // minima of e^{-ζωt}cos(ω_d t) are spaced by T_d; sampling at 1 µs limits accuracy to ~1e-3
        for z in [r.zeta_1, r.zeta_2, r.zeta_5] {
            assert!((z.unwrap() - zeta).abs() < 1e-3, "{z:?}");
        }
    }
}
