//! Free-decay evaluation: peak detection, logarithmic decrement, exponential
//! fit and amplitude-dependent damping.
//!
//! For a linear oscillator `x = X e^{−ζω t} cos(ω_d t)` with
//! `ω_d = ω √(1−ζ²)`, successive maxima are exactly one damped period
//! `T_d = 2π/ω_d` apart and their ratio is exactly `e^{ζω T_d}`, so the
//! logarithmic decrement `δ = ζω T_d = 2πζ/√(1−ζ²)` and
//! `ζ = δ/√(4π² + δ²)` hold without approximation. Particle dampers are
//! nonlinear; [`amplitude_dependent_damping`] therefore reports an
//! equivalent ζ per pair of peaks against the amplitude.

use std::f64::consts::TAU;

use serde::Serialize;

use crate::error::{Result, SignalError, check_finite, check_finite_scalar, check_positive};

/// A local maximum with parabolically interpolated time and value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Peak {
    /// Index of the sample that is the discrete maximum.
    pub index: usize,
    /// Interpolated peak time.
    pub time_s: f64,
    /// Interpolated peak value (unit of the signal).
    pub value: f64,
}

/// Options for [`find_peaks`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakOptions {
    /// Minimum time between accepted peaks: among peaks closer than this the
    /// larger one wins (processed in order of decreasing value). For noisy
    /// decays choose about 0.6–0.9 of the expected period.
    pub min_separation_s: f64,
    /// Peaks with a (discrete) value `≤ min_value` are ignored, e.g. a
    /// multiple of the noise level. The default, 0, keeps positive maxima.
    pub min_value: f64,
    /// Half width `w` (in samples) of the least-squares parabola fitted
    /// through samples `k−w ..= k+w` around each discrete maximum `k`. The
    /// default, 1, is the exact three-point parabola; for noisy signals use a
    /// larger `w` (about 1/10 of the period in samples) to average the noise.
    pub fit_half_width_samples: usize,
}

impl Default for PeakOptions {
    fn default() -> Self {
        Self {
            min_separation_s: 0.0,
            min_value: 0.0,
            fit_half_width_samples: 1,
        }
    }
}

/// Finds the local maxima of `samples` (at `t0_s + k·dt_s`), refined by a
/// parabola (see [`PeakOptions::fit_half_width_samples`]), in time order.
///
/// A sample `k` is a candidate if `x[k−1] < x[k] ≥ x[k+1]` and
/// `x[k] > min_value`; candidates closer than `min_separation_s` to a larger
/// accepted peak are dropped. The end samples are never peaks. If the fitted
/// parabola is not concave or its vertex lies outside the fit window, the
/// discrete maximum is returned unrefined.
pub fn find_peaks(
    samples: &[f64],
    t0_s: f64,
    dt_s: f64,
    options: &PeakOptions,
) -> Result<Vec<Peak>> {
    check_finite_scalar("t0_s", t0_s)?;
    check_positive("dt_s", dt_s)?;
    check_finite("samples", samples)?;
    if !(options.min_separation_s >= 0.0 && options.min_separation_s.is_finite()) {
        return Err(SignalError::InvalidArgument {
            name: "min_separation_s",
            value: options.min_separation_s,
            reason: "must be finite and >= 0",
        });
    }
    if options.fit_half_width_samples == 0 {
        return Err(SignalError::InvalidArgument {
            name: "fit_half_width_samples",
            value: 0.0,
            reason: "must be >= 1",
        });
    }
    if options.min_value.is_nan() {
        return Err(SignalError::InvalidArgument {
            name: "min_value",
            value: options.min_value,
            reason: "must not be NaN",
        });
    }
    let mut candidates: Vec<usize> = (1..samples.len().saturating_sub(1))
        .filter(|&k| {
            samples[k - 1] < samples[k]
                && samples[k] >= samples[k + 1]
                && samples[k] > options.min_value
        })
        .collect();
    if options.min_separation_s > 0.0 && candidates.len() > 1 {
        let min_sep = options.min_separation_s / dt_s;
        let mut by_height = candidates.clone();
        by_height.sort_by(|&a, &b| samples[b].total_cmp(&samples[a]).then(a.cmp(&b)));
        let mut accepted: Vec<usize> = Vec::new();
        for k in by_height {
            if accepted
                .iter()
                .all(|&a| (a as f64 - k as f64).abs() >= min_sep)
            {
                accepted.push(k);
            }
        }
        accepted.sort_unstable();
        candidates = accepted;
    }
    let w = options.fit_half_width_samples;
    Ok(candidates
        .into_iter()
        .map(|k| {
            let (p, value) = refine_peak(samples, k, w);
            Peak {
                index: k,
                time_s: t0_s + (k as f64 + p) * dt_s,
                value,
            }
        })
        .collect())
}

/// Vertex `(offset in samples, value)` of the least-squares parabola through
/// `samples[k−w ..= k+w]` (clipped to the record); `(0, x[k])` if degenerate.
fn refine_peak(samples: &[f64], k: usize, w: usize) -> (f64, f64) {
    let lo = k.saturating_sub(w);
    let hi = (k + w).min(samples.len() - 1);
    // Normal equations for y ≈ a + b u + c u², u = j − k.
    let mut s = [0.0_f64; 5];
    let mut r = [0.0_f64; 3];
    for (j, &y) in samples.iter().enumerate().take(hi + 1).skip(lo) {
        let u = j as f64 - k as f64;
        let mut up = 1.0;
        for (i, si) in s.iter_mut().enumerate() {
            *si += up;
            if i < 3 {
                r[i] += up * y;
            }
            up *= u;
        }
    }
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(m);
    let unrefined = (0.0, samples[k]);
    if d == 0.0 || !d.is_finite() {
        return unrefined;
    }
    // Cramer's rule.
    let solve = |col: usize| {
        let mut mc = m;
        for (row, &ri) in mc.iter_mut().zip(&r) {
            row[col] = ri;
        }
        det3(mc) / d
    };
    let (a, b, c) = (solve(0), solve(1), solve(2));
    if c.is_nan() || c >= 0.0 {
        return unrefined;
    }
    let p = -b / (2.0 * c);
    if p.is_nan() || p.abs() > w as f64 {
        return unrefined;
    }
    (p, a + b * p + c * p * p)
}

/// `ζ = δ/√(4π² + δ²)` from the logarithmic decrement `δ` (exact for a linear oscillator).
pub fn damping_ratio_from_log_decrement(log_decrement: f64) -> f64 {
    log_decrement / (TAU * TAU + log_decrement * log_decrement).sqrt()
}

/// `δ = 2πζ/√(1−ζ²)` from the damping ratio `ζ < 1`.
pub fn log_decrement_from_damping_ratio(damping_ratio: f64) -> f64 {
    TAU * damping_ratio / (1.0 - damping_ratio * damping_ratio).sqrt()
}

/// Result of the logarithmic-decrement evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LogDecrement {
    /// Number of periods `n` between the first and last peak.
    pub n_periods: usize,
    /// `δ = (1/n) ln(x_0/x_n)`.
    pub log_decrement: f64,
    /// `ζ = δ/√(4π² + δ²)`.
    pub damping_ratio: f64,
    /// Damped frequency `f_d = n/(t_n − t_0)` from the peak spacing.
    pub damped_frequency_hz: f64,
    /// Undamped frequency `f_d/√(1−ζ²)`.
    pub undamped_frequency_hz: f64,
}

fn check_peaks(peaks: &[Peak], needed: usize) -> Result<()> {
    if peaks.len() < needed {
        return Err(SignalError::TooFew {
            what: "peaks",
            needed,
            got: peaks.len(),
        });
    }
    if let Some(index) = peaks
        .iter()
        .position(|p| !(p.value > 0.0 && p.value.is_finite()))
    {
        return Err(SignalError::InvalidArgument {
            name: "peaks",
            value: peaks[index].value,
            reason: "peak values must be finite and > 0",
        });
    }
    if peaks
        .windows(2)
        .any(|w| w[1].time_s.partial_cmp(&w[0].time_s) != Some(std::cmp::Ordering::Greater))
    {
        return Err(SignalError::Degenerate {
            reason: "peak times must be strictly increasing",
        });
    }
    Ok(())
}

/// Logarithmic decrement `δ = (1/n) ln(x_0/x_n)` between the first and the
/// last of `peaks` (successive maxima, one period apart), with damping ratio
/// and frequencies from the mean peak spacing. Needs ≥ 2 positive peaks.
pub fn log_decrement(peaks: &[Peak]) -> Result<LogDecrement> {
    check_peaks(peaks, 2)?;
    let n = peaks.len() - 1;
    let (first, last) = (peaks[0], peaks[n]);
    let delta = (first.value / last.value).ln() / n as f64;
    let zeta = damping_ratio_from_log_decrement(delta);
    let f_d = n as f64 / (last.time_s - first.time_s);
    Ok(LogDecrement {
        n_periods: n,
        log_decrement: delta,
        damping_ratio: zeta,
        damped_frequency_hz: f_d,
        undamped_frequency_hz: f_d / (1.0 - zeta * zeta).sqrt(),
    })
}

/// Least-squares fit of a free decay to its peaks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DecayFit {
    /// Decay rate `σ = ζω` from the slope of `ln x_i` versus `t_i`.
    pub decay_rate_1_per_s: f64,
    /// Damped frequency from the slope of `t_i` versus peak number `i`.
    pub damped_frequency_hz: f64,
    /// Undamped frequency `√(ω_d² + σ²)/(2π)`.
    pub undamped_frequency_hz: f64,
    /// Damping ratio `ζ = σ/√(ω_d² + σ²)`.
    pub damping_ratio: f64,
    /// Envelope amplitude at `t = 0`, `exp(intercept)` (unit of the signal).
    pub amplitude_at_t0: f64,
    /// Coefficient of determination of the `ln x_i` versus `t_i` fit.
    pub r_squared: f64,
}

/// Straight-line least squares `y ≈ a + b·x`; returns `(a, b, r²)`.
fn linear_fit(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(y) {
        let (dx, dy) = (xi - mx, yi - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let b = sxy / sxx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    (my - b * mx, b, r2)
}

/// Fits `ln x_i = ln X − σ t_i` (least squares over all `peaks`) and
/// `t_i = t_0 + i·T_d` (peak number `i`, assuming successive maxima one
/// period apart), giving `ζ = σ/√(ω_d² + σ²)` and `ω = √(ω_d² + σ²)`.
/// Less sensitive to noise on single peaks than [`log_decrement`]; assumes
/// viscous (exponential) decay. Needs ≥ 3 positive peaks.
pub fn fit_exponential_decay(peaks: &[Peak]) -> Result<DecayFit> {
    check_peaks(peaks, 3)?;
    let t: Vec<f64> = peaks.iter().map(|p| p.time_s).collect();
    let ln_x: Vec<f64> = peaks.iter().map(|p| p.value.ln()).collect();
    let idx: Vec<f64> = (0..peaks.len()).map(|i| i as f64).collect();
    let (a, b, r_squared) = linear_fit(&t, &ln_x);
    let (_, period_s, _) = linear_fit(&idx, &t);
    let sigma = -b;
    let omega_d = TAU / period_s;
    let omega = (omega_d * omega_d + sigma * sigma).sqrt();
    Ok(DecayFit {
        decay_rate_1_per_s: sigma,
        damped_frequency_hz: omega_d / TAU,
        undamped_frequency_hz: omega / TAU,
        damping_ratio: sigma / omega,
        amplitude_at_t0: a.exp(),
        r_squared,
    })
}

/// Equivalent damping of one pair of peaks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AmplitudeDamping {
    /// Mid time of the pair, `(t_i + t_{i+s})/2`.
    pub time_s: f64,
    /// Geometric-mean amplitude `√(x_i x_{i+s})` (unit of the signal).
    pub amplitude: f64,
    /// Logarithmic decrement per period, `ln(x_i/x_{i+s})/s`.
    pub log_decrement: f64,
    /// Equivalent damping ratio `δ/√(4π² + δ²)`.
    pub damping_ratio: f64,
    /// Damped frequency `s/(t_{i+s} − t_i)`.
    pub damped_frequency_hz: f64,
}

/// Amplitude-dependent damping: for each pair of peaks `span_periods` apart
/// (`span_periods = 1`: successive peaks) the equivalent ζ, frequency and
/// amplitude. A linear oscillator gives a constant ζ; a particle damper (or
/// dry friction) gives ζ varying with amplitude. Larger `span_periods`
/// averages noise at the cost of amplitude resolution.
pub fn amplitude_dependent_damping(
    peaks: &[Peak],
    span_periods: usize,
) -> Result<Vec<AmplitudeDamping>> {
    if span_periods == 0 {
        return Err(SignalError::InvalidArgument {
            name: "span_periods",
            value: 0.0,
            reason: "must be >= 1",
        });
    }
    check_peaks(peaks, span_periods + 1)?;
    let s = span_periods as f64;
    Ok(peaks
        .iter()
        .zip(&peaks[span_periods..])
        .map(|(a, b)| {
            let delta = (a.value / b.value).ln() / s;
            AmplitudeDamping {
                time_s: 0.5 * (a.time_s + b.time_s),
                amplitude: (a.value * b.value).sqrt(),
                log_decrement: delta,
                damping_ratio: damping_ratio_from_log_decrement(delta),
                damped_frequency_hz: s / (b.time_s - a.time_s),
            }
        })
        .collect())
}
