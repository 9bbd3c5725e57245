//! Ensembles of independently prepared beds: a damper in a chaotic regime gives a different
//! η̄ for every packing, so a design number is the ensemble mean with its spread and its 95 %
//! confidence interval, mean ± t₀.₉₇₅,K−1 · s/√K (Student's t, s the sample standard deviation).

use serde::{Deserialize, Serialize};

/// Two-sided 95 % quantiles t₀.₉₇₅ of Student's t for 1…30 degrees of freedom.
const T975: [f64; 30] = [
    12.706_204_7,
    4.302_652_7,
    3.182_446_3,
    2.776_445_1,
    2.570_581_8,
    2.446_911_9,
    2.364_624_3,
    2.306_004_1,
    2.262_157_2,
    2.228_138_9,
    2.200_985_2,
    2.178_812_8,
    2.160_368_7,
    2.144_786_7,
    2.131_449_5,
    2.119_905_3,
    2.109_815_6,
    2.100_922_0,
    2.093_024_1,
    2.085_963_4,
    2.079_613_8,
    2.073_873_1,
    2.068_657_6,
    2.063_898_6,
    2.059_538_6,
    2.055_529_4,
    2.051_830_5,
    2.048_407_1,
    2.045_229_6,
    2.042_272_5,
];

/// t₀.₉₇₅ of Student's t with `dof` degrees of freedom (table to 30, then the Cornish–Fisher
/// expansion about the normal quantile, error < 1e-5); NaN for 0.
pub fn student_t_975(dof: usize) -> f64 {
    match dof {
        0 => f64::NAN,
        1..=30 => T975[dof - 1],
        _ => {
            let z: f64 = 1.959_963_984_540_054;
            let n = dof as f64;
            let g1 = (z.powi(3) + z) / 4.0;
            let g2 = (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0;
            let g3 = (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0;
            z + g1 / n + g2 / (n * n) + g3 / (n * n * n)
        }
    }
}

/// Mean, spread and 95 % confidence interval of one quantity over an ensemble.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnsembleStat {
    /// Members with a finite value.
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1); NaN for one member.
    pub std: f64,
    /// Half-width of the 95 % confidence interval of the mean, t₀.₉₇₅ s/√n; NaN for one member.
    pub ci95_half_width: f64,
    /// Lower end of the 95 % confidence interval.
    pub ci95_low: f64,
    /// Upper end of the 95 % confidence interval.
    pub ci95_high: f64,
}

impl EnsembleStat {
    /// Statistics of the finite values of `v` (non-finite ones, e.g. failed runs, are left out
    /// and show in `count`).
    pub fn of(v: &[f64]) -> Self {
        let x: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let n = x.len();
        let mean = if n > 0 {
            x.iter().sum::<f64>() / n as f64
        } else {
            f64::NAN
        };
        let std = if n > 1 {
            (x.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            f64::NAN
        };
        let half = student_t_975(n.saturating_sub(1)) * std / (n as f64).sqrt();
        Self {
            count: n,
            mean,
            std,
            ci95_half_width: half,
            ci95_low: mean - half,
            ci95_high: mean + half,
        }
    }

    /// Whether `value` lies inside the 95 % confidence interval.
    pub fn contains(&self, value: f64) -> bool {
        value >= self.ci95_low && value <= self.ci95_high
    }
}

/// The mean over packings of every quantity of a point (failed members, NaN, left out): the
/// ensemble's point for `fields.csv` and the maps. Counters are averaged and rounded.
pub fn mean_point(members: &[crate::damper::PointResult]) -> crate::damper::PointResult {
    use crate::damper::PointResult;
    let m = |f: fn(&PointResult) -> f64| {
        EnsembleStat::of(&members.iter().map(f).collect::<Vec<_>>()).mean
    };
    let first = &members[0];
    PointResult {
        frequency_hz: first.frequency_hz,
        amplitude_m: first.amplitude_m,
        acceleration_m_s2: first.acceleration_m_s2,
        intensity: first.intensity,
        velocity_amplitude_m_s: first.velocity_amplitude_m_s,
        dissipated_energy_per_cycle_j: m(|p| p.dissipated_energy_per_cycle_j),
        loss_factor: m(|p| p.loss_factor),
        effective_loss_factor: m(|p| p.effective_loss_factor),
        effective_mass_ratio: m(|p| p.effective_mass_ratio),
        effective_moving_mass_re_kg: m(|p| p.effective_moving_mass_re_kg),
        effective_moving_mass_im_kg: m(|p| p.effective_moving_mass_im_kg),
        ledger_dissipated_per_cycle_j: m(|p| p.ledger_dissipated_per_cycle_j),
        ledger_wall_work_per_cycle_j: m(|p| p.ledger_wall_work_per_cycle_j),
        share_normal_pp: m(|p| p.share_normal_pp),
        share_normal_pw: m(|p| p.share_normal_pw),
        share_tangential_pp: m(|p| p.share_tangential_pp),
        share_tangential_pw: m(|p| p.share_tangential_pw),
        energy_closure_relative: m(|p| p.energy_closure_relative),
        cycles_evaluated: m(|p| p.cycles_evaluated as f64).round() as u32,
        converged: members
            .iter()
            .map(|p| p.converged)
            .try_fold(true, |all, c| c.map(|c| all && c)),
        time_step_s: first.time_step_s,
        steps: m(|p| p.steps as f64).round() as u64,
        wall_time_s: m(|p| p.wall_time_s),
    }
}

/// Extra columns of an ensemble's `fields.csv` (after [`crate::fields::FIELD_COLUMNS`], which
/// then hold the means).
pub const ENSEMBLE_COLUMNS: [&str; 7] = [
    "packings",
    "effective_loss_factor_std",
    "effective_loss_factor_ci95_half_width",
    "effective_mass_ratio_std",
    "effective_mass_ratio_ci95_half_width",
    "dissipated_energy_per_cycle_j_std",
    "dissipated_energy_per_cycle_j_ci95_half_width",
];

/// The [`ENSEMBLE_COLUMNS`] of one point over its packings.
pub fn ensemble_row(members: &[crate::damper::PointResult]) -> Vec<f64> {
    let st = |f: fn(&crate::damper::PointResult) -> f64| {
        EnsembleStat::of(&members.iter().map(f).collect::<Vec<_>>())
    };
    let (e, m, d) = (
        st(|p| p.effective_loss_factor),
        st(|p| p.effective_mass_ratio),
        st(|p| p.dissipated_energy_per_cycle_j),
    );
    vec![
        e.count as f64,
        e.std,
        e.ci95_half_width,
        m.std,
        m.ci95_half_width,
        d.std,
        d.ci95_half_width,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn student_t_quantiles() {
        // Reference values of t_0.975 (e.g. Abramowitz & Stegun Table 26.10).
        assert!((student_t_975(1) - 12.706).abs() < 1e-3);
        assert!((student_t_975(4) - 2.776).abs() < 1e-3);
        assert!((student_t_975(7) - 2.365).abs() < 1e-3);
        assert!((student_t_975(40) - 2.021).abs() < 1e-3);
        assert!((student_t_975(60) - 2.000).abs() < 1e-3);
        assert!((student_t_975(120) - 1.980).abs() < 1e-3);
        // Continuous at the end of the table and towards the normal quantile.
        assert!((student_t_975(31) - 2.0395).abs() < 2e-4);
        assert!((student_t_975(100_000) - 1.95996).abs() < 1e-4);
        assert!(student_t_975(0).is_nan());
    }

    #[test]
    fn ensemble_stat_closed_form() {
        // 1, 2, 3, 4: mean 2.5, s = sqrt(5/3), half-width t(3) s / 2.
        let s = EnsembleStat::of(&[1.0, 2.0, 3.0, 4.0, f64::NAN]);
        assert_eq!(s.count, 4);
        assert!((s.mean - 2.5).abs() < 1e-15);
        assert!((s.std - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((s.ci95_half_width - 3.182_446_3 * (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-12);
        assert!(s.contains(2.5) && !s.contains(10.0));
        let one = EnsembleStat::of(&[0.3]);
        assert_eq!(one.mean, 0.3);
        assert!(one.std.is_nan() && one.ci95_half_width.is_nan());
    }
}
