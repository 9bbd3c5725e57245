//! The resonance sweep of level 3 for the forced objectives (min_frf_peak,
//! max_resonance_damping): each objective mode's resonance is measured by a slow linear sine
//! sweep through it under the study's harmonic force, the time-domain approach of
//! D Sect. 3.3.2, on the structure reduced to that mode (as level 1's steady-state FRF,
//! D Eq. 3.44, sees it). The peak of the output point's response gives the resonance peak and,
//! by D Eq. 3.47, the damping ratio at resonance.
//!
//! A sweep passes the resonance in finite time, so its peak lies below the steady-state peak.
//! The plan therefore sets the sweep's rate with the formula model of the same design: it runs
//! the formula dampers through the planned sweep and slows it down (halving the rate) until
//! the sweep's peak is within [`SWEEP_PEAK_TOLERANCE`] of the formula model's steady-state
//! peak. The remaining difference (the sweep's bias) is reported beside the DEM result. The
//! band is ±[`BAND_HALF_WIDTH_ZETAS`]·ζ·f around the expected resonance, i.e. ±4 half-power
//! half-widths.

use crate::DesignError;
use crate::fidelity::{FrfResonance, single_mode};
use crate::spec::HarmonicLoad;
use crate::study::DesignStudy;
use pdamp_structure::forced::{self, PeakDamping, Sweep, SweepLaw, SweepSpec};
use pdamp_structure::free::{CoupledDamper, TimeHistory};
use pdamp_structure::modal::ModalStructure;
use serde::Serialize;

/// Largest relative difference between the formula model's sweep peak and its steady-state
/// peak that a sweep plan accepts.
pub const SWEEP_PEAK_TOLERANCE: f64 = 0.02;

/// Half-width of the swept band in units of ζ·f_c (the half-power half-width of a resonance
/// is ζ·f_c).
pub const BAND_HALF_WIDTH_ZETAS: f64 = 4.0;

/// Smallest rate parameter η = ṙ/(ζ f_c)² the plan tries (ṙ the sweep rate in Hz/s); at the
/// default η = 1 the sweep is already slow (about 8 time constants inside the half-power band).
pub const SLOWEST_RATE_PARAMETER: f64 = 1.0 / 16.0;

/// Samples per period of the highest swept frequency (the peak is refined by a parabola).
pub const SAMPLES_PER_PERIOD: f64 = 40.0;

/// The sweep of one mode's resonance.
#[derive(Debug, Clone)]
pub struct SweepPlan {
    /// The structure reduced to the mode (its only mode, index 0).
    pub structure: ModalStructure,
    /// The sweep: force, points, time step of the formula model's run.
    pub spec: SweepSpec,
    /// What the plan was made for and what it measured with the formula model.
    pub summary: SweepSummary,
}

/// A sweep plan as the report shows it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SweepSummary {
    /// Expected resonance frequency (the band's centre), Hz.
    pub centre_hz: f64,
    /// Damping ratio the rate is set for.
    pub damping_ratio: f64,
    /// First frequency, Hz.
    pub start_hz: f64,
    /// Last frequency, Hz.
    pub end_hz: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Rate parameter η = ṙ/(ζ f_c)².
    pub rate_parameter: f64,
    /// The formula model's steady-state resonance peak at the output point, m.
    pub steady_peak_m: f64,
    /// The formula model's peak on this sweep, m.
    pub formula_sweep_peak_m: f64,
}

impl SweepSummary {
    /// The sweep's bias on the formula model: sweep peak / steady-state peak − 1.
    pub fn formula_sweep_bias(&self) -> f64 {
        self.formula_sweep_peak_m / self.steady_peak_m - 1.0
    }

    /// Whether `frequency_hz` lies in the middle 60 % of the band (a peak closer to an end may
    /// be the band's edge rather than the resonance).
    pub fn well_inside(&self, frequency_hz: f64) -> bool {
        let (lo, hi) = (
            self.start_hz.min(self.end_hz),
            self.start_hz.max(self.end_hz),
        );
        let margin = 0.2 * (hi - lo);
        frequency_hz > lo + margin && frequency_hz < hi - margin
    }
}

impl SweepPlan {
    /// D Eq. 3.47 on a sweep history of this plan at the output point.
    pub fn peak_of(&self, hist: &TimeHistory) -> Option<PeakDamping> {
        let s = &self.structure;
        let phi_ex = s.point(&self.spec.excitation_point).ok()?[0];
        let phi_out = s.point(&self.spec.output_point).ok()?[0];
        forced::peak_damping(
            hist,
            &self.spec.sweep,
            self.spec.force_amplitude_n,
            phi_ex,
            phi_out,
            s.modes[0].omega_rad_s(),
            None,
        )
    }
}

/// Where a sweep looks for a resonance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepTarget {
    /// Expected resonance frequency, Hz.
    pub centre_hz: f64,
    /// Damping ratio the band is sized for (±[`BAND_HALF_WIDTH_ZETAS`]·ζ·f_c).
    pub band_damping_ratio: f64,
    /// Damping ratio the rate is set for (η·(ζ f_c)² Hz/s).
    pub rate_damping_ratio: f64,
}

/// The [`SweepPlan`] of mode `k` (0-based) of the study's structure for `target`, slowed until
/// the formula `dampers` meet their `steady` resonance within [`SWEEP_PEAK_TOLERANCE`] (or the
/// slowest rate is reached; the bias is then reported).
///
/// # Errors
/// A study without a harmonic load, unknown points, a non-positive damping ratio or centre.
pub fn sweep_plan(
    study: &DesignStudy,
    structure: &ModalStructure,
    dampers: &[CoupledDamper],
    k: usize,
    steady: &FrfResonance,
    target: SweepTarget,
) -> Result<SweepPlan, DesignError> {
    let load = study
        .load
        .as_ref()
        .ok_or_else(|| DesignError::Solver("a forced objective without a harmonic load".into()))?;
    if !(target.centre_hz > 0.0
        && target.band_damping_ratio > 0.0
        && target.rate_damping_ratio > 0.0)
    {
        return Err(DesignError::Solver(format!(
            "mode {}: no resonance sweep for {target:?}",
            k + 1
        )));
    }
    plan_single_mode(
        single_mode(structure, k),
        dampers,
        load,
        &study.free.output_point,
        steady.peak_m,
        target,
    )
}

/// [`sweep_plan`] on a structure of one mode: `load` at its point, the response at
/// `output_point`, `steady_peak_m` the formula dampers' steady-state peak there.
///
/// # Errors
/// Unknown points.
pub fn plan_single_mode(
    single: ModalStructure,
    dampers: &[CoupledDamper],
    load: &HarmonicLoad,
    output_point: &str,
    steady_peak_m: f64,
    target: SweepTarget,
) -> Result<SweepPlan, DesignError> {
    let centre_hz = target.centre_hz;
    let half = (BAND_HALF_WIDTH_ZETAS * target.band_damping_ratio).clamp(0.005, 0.5) * centre_hz;
    let (start, end) = (centre_hz - half, centre_hz + half);
    let zf = target.rate_damping_ratio * centre_hz;
    let mut eta = 1.0;
    let mut previous_peak: Option<f64> = None;
    loop {
        let sweep = Sweep {
            start_hz: start,
            end_hz: end,
            duration_s: 2.0 * half / (eta * zf * zf),
            law: SweepLaw::Linear,
        };
        let spec = SweepSpec {
            sweep,
            force_amplitude_n: load.force_n,
            excitation_point: load.excitation_point.clone(),
            output_point: output_point.to_string(),
            time_step_s: 1.0 / (SAMPLES_PER_PERIOD * 2.0 * end),
            sample_every: 1,
        };
        let hist = forced::run_sweep(&single, dampers, &spec).map_err(DesignError::from)?;
        let mut plan = SweepPlan {
            structure: single.clone(),
            spec,
            summary: SweepSummary {
                centre_hz,
                damping_ratio: target.rate_damping_ratio,
                start_hz: start,
                end_hz: end,
                duration_s: sweep.duration_s,
                rate_parameter: eta,
                steady_peak_m,
                formula_sweep_peak_m: f64::NAN,
            },
        };
        let peak = plan.peak_of(&hist).map_or(0.0, |p| p.max_amplitude_m);
        plan.summary.formula_sweep_peak_m = peak;
        // a sweep twice as slow that changes the peak by less than a quarter of the tolerance
        // has converged in the rate: what is left of the bias is not the sweep's speed (a
        // nonlinear FRF whose steady-state branch a sweep from below does not reach)
        let rate_converged = previous_peak
            .is_some_and(|p| (peak - p).abs() <= 0.25 * SWEEP_PEAK_TOLERANCE * peak.abs());
        if plan.summary.formula_sweep_bias().abs() <= SWEEP_PEAK_TOLERANCE
            || rate_converged
            || eta <= SLOWEST_RATE_PARAMETER
        {
            return Ok(plan);
        }
        previous_peak = Some(peak);
        eta *= 0.5;
    }
}

/// Why a sweep is made again after the first packing: the DEM bed damps clearly less than the
/// plan's ζ (its sweep would be too fast for the narrower peak), or its peak lies near the
/// band's edge. `None`: the plan stands.
pub fn replan_reason(s: &SweepSummary, dem: &PeakDamping) -> Option<String> {
    if dem.damping_ratio < 0.7 * s.damping_ratio {
        Some(format!(
            "the DEM's ζ {:.4} is below 0.7 × the planned {:.4}",
            dem.damping_ratio, s.damping_ratio
        ))
    } else if !s.well_inside(dem.resonance_frequency_hz) {
        Some(format!(
            "the DEM's peak at {:.3} Hz lies near the edge of {:.3}–{:.3} Hz",
            dem.resonance_frequency_hz, s.start_hz, s.end_hz
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear oscillator (m = 1.5 kg, k = 1848 N/m, ζ = 0.02, no damper): the plan's sweep
    /// meets the closed-form peak F/(2ζk√(1−ζ²)) within the tolerance, at the frequency
    /// f_n√(1−2ζ²) within 0.4 of the half-power half-width ζ f_n (an up-sweep's peak lags by
    /// about one time constant 1/(ζω): measured +0.26 ζ f_n at η = 1), and D Eq. 3.47 returns
    /// ζ within 3 %. The plan sweeps ±4 ζ f_n in about 8/(η ζ f_n) s.
    #[test]
    fn a_planned_sweep_meets_the_closed_form_resonance_of_a_linear_oscillator() {
        let (m, k, zeta) = (1.5_f64, 1848.0_f64, 0.02_f64);
        let c = 2.0 * zeta * (k * m).sqrt();
        let s = ModalStructure::single_mode(m, k, c);
        let point = s.points[0].name.clone();
        let f = 3.0;
        let fn_hz = (k / m).sqrt() / std::f64::consts::TAU;
        let exact = f / (2.0 * zeta * k * (1.0 - zeta * zeta).sqrt());
        let load = HarmonicLoad {
            force_n: f,
            excitation_point: point.clone(),
        };
        let plan = plan_single_mode(
            s.clone(),
            &[],
            &load,
            &point,
            exact,
            SweepTarget {
                centre_hz: fn_hz,
                band_damping_ratio: zeta,
                rate_damping_ratio: zeta,
            },
        )
        .unwrap();
        let sm = plan.summary;
        assert!(
            sm.formula_sweep_bias().abs() <= SWEEP_PEAK_TOLERANCE,
            "{sm:?}"
        );
        assert!((sm.end_hz - sm.start_hz - 8.0 * zeta * fn_hz).abs() < 1e-9 * fn_hz);
        let t = 8.0 / (sm.rate_parameter * zeta * fn_hz);
        assert!((sm.duration_s / t - 1.0).abs() < 1e-9, "{sm:?}");
        // the plan's own sweep, run again, gives the frequency and ζ of Eq. 3.47
        let hist = forced::run_sweep(&plan.structure, &[], &plan.spec).unwrap();
        let pk = plan.peak_of(&hist).unwrap();
        let f_peak = fn_hz * (1.0 - 2.0 * zeta * zeta).sqrt();
        assert!(
            (pk.resonance_frequency_hz - f_peak).abs() < 0.4 * zeta * fn_hz,
            "{pk:?} vs {f_peak}"
        );
        assert!((pk.damping_ratio / zeta - 1.0).abs() < 0.03, "{pk:?}");
        assert!(replan_reason(&sm, &pk).is_none());
        // a bed that damps half as much, or peaks at the band's edge, is swept again
        let weak = PeakDamping {
            damping_ratio: 0.5 * zeta,
            ..pk
        };
        assert!(replan_reason(&sm, &weak).unwrap().contains("below"));
        let edge = PeakDamping {
            resonance_frequency_hz: sm.end_hz - 0.1 * (sm.end_hz - sm.start_hz),
            ..pk
        };
        assert!(replan_reason(&sm, &edge).unwrap().contains("edge"));
    }
}
