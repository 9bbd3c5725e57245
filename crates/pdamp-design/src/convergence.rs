//! Early stop of an excitation point on convergence (`[damper] convergence`).
//!
//! After the transient cycles the complex power method [D Eq. 3.12–3.17] is evaluated at the end
//! of every cycle over *all* evaluated cycles so far (the running mean of the per-cycle complex
//! force amplitudes: the single-bin DFT over whole cycles is additive). The point stops when the
//! latest running estimate agrees with each of the estimates at the ends of the previous
//! `window_cycles` cycles, for η̄ and for m̄_bed/m_bed:
//!
//! $|q_n - q_k| \le \mathrm{tol} \cdot \max(|q_n|, q_\mathrm{floor})$ for $k = n-w, \dots, n-1$.
//!
//! Comparing with every estimate in the window (a plateau), not only with the one a window
//! earlier, keeps a fluctuating sequence whose running mean happens to return to an earlier value
//! from stopping. A plateau over a few cycles can still occur by chance in a chaotic bed, so the
//! standard error of the mean must meet the same bound too: $s_q/\sqrt{n} \le \mathrm{tol}
//! \cdot \max(|q_n|, q_\mathrm{floor})$ with $s_q$ the sample standard deviation of the
//! single-cycle values of q (a periodic bed: $s_q \approx 0$, it stops at the minimum). η̄ = Ẽ/(π m_bed V²) is the dissipated energy per cycle Ẽ in units of the bed's
//! power scale, so the η̄ test is the Ẽ test; its floor keeps η̄ ≈ 0 (a stuck bed) from demanding
//! an impossible relative accuracy.

pub use pdamp_scenario::schema::ConvergenceSpec;

/// Running estimate after a number of evaluated cycles.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunningEstimate {
    /// Effective loss factor η̄ [D Eq. 3.15] (Ẽ per cycle / (π m_bed V²)).
    pub effective_loss_factor: f64,
    /// Effective particle mass ratio m̄_bed/m_bed [D Eq. 3.17].
    pub effective_mass_ratio: f64,
}

/// Whether the running estimates `history` (entry `k` over the first `k + 1` evaluated cycles)
/// with the single-cycle values `per_cycle` (entry `k` of cycle `k` alone) have converged by the
/// criterion `c` (see the module documentation).
pub fn has_converged(
    history: &[RunningEstimate],
    per_cycle: &[RunningEstimate],
    c: &ConvergenceSpec,
) -> bool {
    let n = history.len();
    let w = c.window_cycles as usize;
    if n < c.min_evaluated_cycles as usize || n <= w || w == 0 || per_cycle.len() != n {
        return false;
    }
    let standard_error = |q: fn(&RunningEstimate) -> f64| {
        let mean = per_cycle.iter().map(q).sum::<f64>() / n as f64;
        let var = per_cycle.iter().map(|e| (q(e) - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (var / n as f64).sqrt()
    };
    let last = history[n - 1];
    let close = |a: f64, b: f64| {
        a.is_finite()
            && b.is_finite()
            && (a - b).abs() <= c.relative_tolerance * a.abs().max(c.absolute_floor)
    };
    let bound = |a: f64| c.relative_tolerance * a.abs().max(c.absolute_floor);
    history[n - 1 - w..n - 1].iter().all(|e| {
        close(last.effective_loss_factor, e.effective_loss_factor)
            && close(last.effective_mass_ratio, e.effective_mass_ratio)
    }) && standard_error(|e| e.effective_loss_factor) <= bound(last.effective_loss_factor)
        && standard_error(|e| e.effective_mass_ratio) <= bound(last.effective_mass_ratio)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> ConvergenceSpec {
        ConvergenceSpec {
            relative_tolerance: 0.02,
            min_evaluated_cycles: 4,
            window_cycles: 2,
            absolute_floor: 0.1,
        }
    }

    /// Running means of per-cycle values (η̄_k, m_k).
    fn running(per_cycle: &[(f64, f64)]) -> Vec<RunningEstimate> {
        let (mut se, mut sm) = (0.0, 0.0);
        per_cycle
            .iter()
            .enumerate()
            .map(|(k, &(e, m))| {
                se += e;
                sm += m;
                RunningEstimate {
                    effective_loss_factor: se / (k + 1) as f64,
                    effective_mass_ratio: sm / (k + 1) as f64,
                }
            })
            .collect()
    }

    fn single(per_cycle: &[(f64, f64)]) -> Vec<RunningEstimate> {
        per_cycle
            .iter()
            .map(|&(e, m)| RunningEstimate {
                effective_loss_factor: e,
                effective_mass_ratio: m,
            })
            .collect()
    }

    /// First number of evaluated cycles at which the criterion stops, if any.
    fn stop_at(per_cycle: &[(f64, f64)], c: &ConvergenceSpec) -> Option<usize> {
        let h = running(per_cycle);
        let p = single(per_cycle);
        (1..=h.len()).find(|&n| has_converged(&h[..n], &p[..n], c))
    }

    #[test]
    fn steady_sequence_stops_at_min_cycles() {
        let seq = vec![(0.3, 0.7); 20];
        assert_eq!(stop_at(&seq, &spec()), Some(4));
    }

    /// A transient: η̄ per cycle rises from 0.05 to 0.4 and m̄/m falls from 1 to 0.5 with a time
    /// constant of 4 cycles (the bed breaking loose). The running means drift by more than 2 %
    /// per window as long as the transient lasts; the criterion must not stop within the 12
    /// cycles shown, although the per-cycle values have almost reached the plateau there.
    #[test]
    fn does_not_stop_during_a_transient() {
        let seq: Vec<(f64, f64)> = (0..12)
            .map(|k| {
                let g = (-(k as f64) / 4.0).exp();
                (0.4 - 0.35 * g, 0.5 + 0.5 * g)
            })
            .collect();
        assert_eq!(stop_at(&seq, &spec()), None);
        // A slow linear drift of 3 % per cycle of the per-cycle values is not a plateau either.
        let drift: Vec<(f64, f64)> = (0..30)
            .map(|k| (0.3 * (1.0 + 0.03 * k as f64), 0.7))
            .collect();
        assert_eq!(stop_at(&drift, &spec()), None);
    }

    /// An alternating sequence whose running mean returns exactly to its value one window
    /// earlier (cycles 2 and 4: mean 0.3) but jumps in between: comparing only with the estimate
    /// a window earlier would stop at cycle 4; the plateau test does not.
    #[test]
    fn does_not_stop_on_a_coincidental_return() {
        let seq = [(0.1, 0.7), (0.5, 0.7), (0.1, 0.7), (0.5, 0.7)];
        let h = running(&seq);
        assert!((h[3].effective_loss_factor - h[1].effective_loss_factor).abs() < 1e-15);
        assert!(!has_converged(&h, &single(&seq), &spec()));
    }

    /// Chaotic bed: per-cycle η̄ and m̄/m fluctuate by ±20 % around 0.3 and 0.6 (deterministic
    /// pseudo-random sequence, per-cycle standard deviation 11.5 %). The criterion stops only
    /// once the standard error of the mean is within the tolerance (n ≳ (0.115/0.02)² ≈ 33),
    /// and there the running mean is within a few tolerances of the long-run mean.
    #[test]
    fn fluctuating_sequence_stops_near_the_mean() {
        let mut state: u64 = 12345;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let seq: Vec<(f64, f64)> = (0..400)
            .map(|_| (0.3 * (1.0 + 0.2 * rnd()), 0.6 * (1.0 + 0.2 * rnd())))
            .collect();
        let n = stop_at(&seq, &spec()).expect("stops");
        let h = running(&seq[..n]);
        let last = h[n - 1];
        assert!(n >= 25, "a fluctuating sequence needs many cycles: {n}");
        assert!(
            (last.effective_loss_factor / 0.3 - 1.0).abs() < 0.05,
            "{n}: {last:?}"
        );
        assert!(
            (last.effective_mass_ratio / 0.6 - 1.0).abs() < 0.05,
            "{n}: {last:?}"
        );
    }

    /// η̄ ≈ 0 with round-off noise (a stuck bed) converges thanks to the floor; without a floor
    /// it would never stop.
    #[test]
    fn floor_lets_near_zero_loss_factor_converge() {
        let seq: Vec<(f64, f64)> = (0..10)
            .map(|k| (1e-5 * if k % 2 == 0 { 1.0 } else { -1.0 }, 1.0))
            .collect();
        assert_eq!(stop_at(&seq, &spec()), Some(4));
        let no_floor = ConvergenceSpec {
            absolute_floor: 0.0,
            ..spec()
        };
        assert_eq!(stop_at(&seq, &no_floor), None);
    }

    #[test]
    fn nan_never_converges() {
        let seq = vec![(f64::NAN, 0.7); 10];
        assert_eq!(stop_at(&seq, &spec()), None);
    }
}
