//! Normal force laws: Hertz [D Eq. 2.69], Lankarani–Nikravesh [D Eq. 2.77], Gonthier
//! [D Eq. 2.78, 2.79], linear spring–dashpot [P Eq. (2)–(4)] and the normal part of LIGGGHTS'
//! Hertz–Mindlin model.

use super::hertz::{gonthier_damping, hertz_stiffness};
use super::{NormalLaw, PairProps};
use std::cell::Cell;

/// Normal response of a law at one overlap $\delta > 0$ (adhesion not included).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct NormalResponse {
    /// Conservative force, N (+ repulsive).
    pub elastic_n: f64,
    /// Dissipative force, N, after any clipping of the total force.
    pub dissipative_n: f64,
    /// Stored energy of the conservative force, J.
    pub energy_j: f64,
    /// Tangent stiffness $dF_{el}/d\delta$ in N/m (reference for tangential stiffness).
    pub tangent_stiffness_n_m: f64,
    /// Current normal damping coefficient $\partial F_{dis}/\partial\dot\delta$ in N·s/m.
    pub damping_n_s_m: f64,
}

/// $\beta = \ln e / \sqrt{\ln^2 e + \pi^2}$ (LIGGGHTS; ≤ 0). The last value per thread is
/// remembered, so the logarithm is not taken again for every contact of the same law.
#[inline]
pub(crate) fn liggghts_beta(restitution: f64) -> f64 {
    thread_local! {
        static LAST: std::cell::Cell<(u64, f64)> = const { std::cell::Cell::new((u64::MAX, 0.0)) };
    }
    LAST.with(|c| {
        let (key, beta) = c.get();
        if key == restitution.to_bits() {
            return beta;
        }
        let l = restitution.ln();
        let beta = l / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt();
        c.set((restitution.to_bits(), beta));
        beta
    })
}

/// Linear dashpot coefficient $d_N = 2|\ln e|\sqrt{k_N \bar M/(\ln^2 e + \pi^2)}$ [P Eq. (4)].
#[inline]
pub(crate) fn linear_damping(stiffness_n_m: f64, m_eff_kg: f64, restitution: f64) -> f64 {
    let l = restitution.ln();
    2.0 * l.abs()
        * (stiffness_n_m * m_eff_kg / (l * l + std::f64::consts::PI * std::f64::consts::PI)).sqrt()
}

const MEMO_SLOTS: usize = 32;

thread_local! {
    /// Direct-mapped memo (restitution bits → $\bar d/\varepsilon$) of Gonthier's damping.
    static GONTHIER_MEMO: [Cell<(u64, f64)>; MEMO_SLOTS] =
        const { [const { Cell::new((u64::MAX, f64::NAN)) }; MEMO_SLOTS] };
}

/// $\bar d(\varepsilon)/\varepsilon$ [D Eq. 2.79], memoised per thread so that the hot path solves
/// eq. 2.79 only once per restitution value and thread.
#[inline]
pub(crate) fn gonthier_damping_cached(restitution: f64) -> f64 {
    let bits = restitution.to_bits();
    let slot = (bits.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 59) as usize % MEMO_SLOTS;
    GONTHIER_MEMO.with(|memo| {
        let cell = &memo[slot];
        let (key, value) = cell.get();
        if key == bits {
            value
        } else {
            let value = gonthier_damping(restitution) / restitution;
            cell.set((bits, value));
            value
        }
    })
}

/// Nodes of the dense table of $\bar d(\varepsilon)/\varepsilon$ used for velocity-dependent
/// restitution (ε = k / N).
const DENSE_NODES: usize = 4096;

/// $\bar d(\varepsilon)/\varepsilon$ [D Eq. 2.79] for any ε in (0, 1]: linear interpolation in a
/// table of 4 096 exact solutions (built once per process; relative error < 1e-4 for ε ≥ 0.05),
/// exact solve below ε = 1/4 096.
#[inline]
pub(crate) fn gonthier_damping_over_restitution_dense(e: f64) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    let t = TABLE.get_or_init(|| {
        (1..=DENSE_NODES)
            .map(|k| {
                let e = k as f64 / DENSE_NODES as f64;
                gonthier_damping(e) / e
            })
            .collect()
    });
    let s = e * DENSE_NODES as f64;
    if s < 1.0 {
        return gonthier_damping(e) / e;
    }
    let k = (s.floor() as usize).min(DENSE_NODES - 1); // node k ↔ ε = k/N, stored at k-1
    let f = s - k as f64;
    let (lo, hi) = (t[k - 1], t[k]);
    lo + f * (hi - lo)
}

impl NormalLaw {
    /// Normal response at overlap `delta > 0`, overlap rate `rate` (> 0 approaching) and stored
    /// impact velocity `v0 > 0`.
    #[inline]
    pub(crate) fn response(&self, p: &PairProps, delta: f64, rate: f64, v0: f64) -> NormalResponse {
        let sqrt_delta = delta.sqrt();
        match *self {
            NormalLaw::Linear {
                stiffness_n_m: k,
                restitution,
                clip_attractive,
            } => {
                let d = linear_damping(k, p.m_eff_kg, restitution);
                let elastic = k * delta;
                let mut dissipative = d * rate;
                if clip_attractive {
                    dissipative = dissipative.max(-elastic);
                }
                NormalResponse {
                    elastic_n: elastic,
                    dissipative_n: dissipative,
                    energy_j: 0.5 * k * delta * delta,
                    tangent_stiffness_n_m: k,
                    damping_n_s_m: d,
                }
            }
            NormalLaw::HertzMindlin {
                restitution,
                clip_attractive,
            } => {
                // LIGGGHTS normal_model_hertz: a = √(R δ), S_n = 2 E a, k_n = 4/3 E a,
                // γ_n = −2 √(5/6) β √(S_n m*), F = k_n δ − γ_n v_n with v_n = −δ̇.
                let a = (p.r_eff_m * delta).sqrt();
                let sn = 2.0 * p.e_eff_pa * a;
                let kn = 4.0 / 3.0 * p.e_eff_pa * a;
                let gamma_n = -2.0
                    * (5.0_f64 / 6.0).sqrt()
                    * liggghts_beta(restitution)
                    * (sn * p.m_eff_kg).sqrt();
                let elastic = kn * delta;
                let mut dissipative = gamma_n * rate;
                if clip_attractive {
                    dissipative = dissipative.max(-elastic);
                }
                NormalResponse {
                    elastic_n: elastic,
                    dissipative_n: dissipative,
                    energy_j: 0.4 * kn * delta * delta,
                    tangent_stiffness_n_m: sn,
                    damping_n_s_m: gamma_n,
                }
            }
            _ => {
                let kn = hertz_stiffness(p.e_eff_pa, p.r_eff_m);
                let elastic = kn * delta * sqrt_delta;
                // Damping coefficient c with F_dis = c δ̇ (Hertz: 0).
                let c = match self {
                    NormalLaw::Gonthier { restitution, .. } => {
                        elastic * gonthier_damping_cached(*restitution) / v0
                    }
                    NormalLaw::GonthierTable {
                        impact_velocities_m_s: x,
                        restitutions: y,
                        ..
                    } => {
                        let e = super::model::interpolate_clamped(x, y, v0);
                        elastic * gonthier_damping_over_restitution_dense(e) / v0
                    }
                    NormalLaw::LankaraniNikravesh { restitution, .. } => {
                        elastic * 0.75 * (1.0 - restitution * restitution) / v0
                    }
                    _ => 0.0,
                };
                NormalResponse {
                    elastic_n: elastic,
                    // Clipped so that the total force never turns attractive.
                    dissipative_n: (c * rate).max(-elastic),
                    energy_j: 0.4 * kn * delta * delta * sqrt_delta,
                    tangent_stiffness_n_m: 1.5 * kn * sqrt_delta,
                    damping_n_s_m: c,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_table_matches_exact_solution() {
        let mut worst: f64 = 0.0;
        for i in 0..=997 {
            let e = 0.05 + 0.95 * i as f64 / 997.0;
            let exact = gonthier_damping(e) / e;
            let dense = gonthier_damping_over_restitution_dense(e);
            worst = worst.max((dense / exact - 1.0).abs());
        }
        // Linear interpolation with spacing 1/4096: O(h²) error, largest at small ε.
        assert!(
            worst < 1e-4,
            "dense d̄/ε table: worst relative error {worst:e}"
        );
    }

    #[test]
    fn memo_returns_the_solution_for_many_restitutions() {
        for i in 1..=100 {
            let e = i as f64 / 100.0;
            let direct = gonthier_damping(e) / e;
            assert_eq!(gonthier_damping_cached(e), direct);
            assert_eq!(gonthier_damping_cached(e), direct, "second (memoised) call");
        }
    }
}
