//! Complex amplitudes of uniformly sampled signals.
//!
//! Convention used throughout the crate: a harmonic signal is written as
//!
//! ```text
//! x(t) = Re( X̂ · e^{iΩt} ),   Ω = 2π f,
//! ```
//!
//! so that `X̂ = |X̂| e^{iφ}` describes `x(t) = |X̂| cos(Ωt + φ)`. For samples
//! `x_k` at `t_k = t0 + k·dt` the single-bin DFT estimate is
//!
//! ```text
//! X̂ = (2/N) Σ_k x_k e^{−iΩ t_k},
//! ```
//!
//! which is the complex amplitude "obtained by the FFT" of [D Eq. 3.12] and
//! [D Eq. 3.15]. It is exact (no leakage from a DC offset or from other
//! harmonics of `f`) when the `N` samples span a whole number of cycles.
//! Time enters through the absolute sample times `t_k`, so phases refer to
//! `t = 0`, not to the first sample.

use std::f64::consts::{PI, TAU};

use num_complex::Complex64;
use rustfft::FftPlanner;

use crate::error::{Result, SignalError, check_finite, check_finite_scalar, check_positive};

/// Absolute tolerance, in samples, for a window of whole cycles to count as an
/// integer number of samples under [`CycleRule::Exact`].
pub const WHOLE_CYCLE_TOLERANCE_SAMPLES: f64 = 1e-6;

/// How the analysis window of whole cycles is chosen from a record.
///
/// In both cases the window is the **last** `n_samples` samples of the record
/// (leading samples are dropped, because transients sit at the start of a
/// record); the number of cycles is the largest admissible one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CycleRule {
    /// Use the largest number of whole cycles `c` for which `c/(f·dt)` is an
    /// integer within [`WHOLE_CYCLE_TOLERANCE_SAMPLES`]; fail with
    /// [`SignalError::NoWholeCycleWindow`] if there is none. Exact for pure
    /// harmonics of `f`.
    #[default]
    Exact,
    /// Use the largest number of whole cycles `c` with `round(c/(f·dt)) ≤ N`
    /// and round the sample count to the nearest integer. The window is then
    /// off by at most half a sample, giving a leakage error of order
    /// `1/n_samples`. Use for arbitrary `dt` (e.g. DEM output).
    Nearest,
}

/// The window of whole cycles used for a harmonic amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleWindow {
    /// Index of the first sample used (samples before it were trimmed).
    pub first_sample: usize,
    /// Number of samples used.
    pub n_samples: usize,
    /// Number of whole cycles of the analysis frequency in the window.
    pub n_cycles: usize,
    /// Samples per cycle, `1/(f·dt)`.
    pub samples_per_cycle: f64,
}

/// Complex amplitude of a signal at one frequency, with the window used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicAmplitude {
    /// Complex amplitude `X̂` (unit of the signal), `x(t) = Re(X̂ e^{iΩt})`.
    pub amplitude: Complex64,
    /// Analysis frequency.
    pub frequency_hz: f64,
    /// Whole-cycle window the DFT was taken over.
    pub window: CycleWindow,
}

impl HarmonicAmplitude {
    /// Magnitude `|X̂|` (unit of the signal).
    pub fn magnitude(&self) -> f64 {
        self.amplitude.norm()
    }

    /// Phase `arg X̂` in radians, in `(−π, π]`.
    pub fn phase_rad(&self) -> f64 {
        self.amplitude.arg()
    }
}

fn check_sampling(dt_s: f64, frequency_hz: f64) -> Result<()> {
    check_positive("dt_s", dt_s)?;
    check_positive("frequency_hz", frequency_hz)?;
    if frequency_hz * dt_s >= 0.5 {
        return Err(SignalError::InvalidArgument {
            name: "frequency_hz",
            value: frequency_hz,
            reason: "must be below the Nyquist frequency 1/(2·dt_s)",
        });
    }
    Ok(())
}

/// Chooses the window of whole cycles of `frequency_hz` in a record of
/// `n_samples` samples spaced `dt_s`, following `rule` (see [`CycleRule`]).
///
/// Errors: invalid `dt_s`/`frequency_hz` (non-positive, at or above Nyquist),
/// [`SignalError::LessThanOneCycle`] when the record is shorter than one
/// period, [`SignalError::NoWholeCycleWindow`] under [`CycleRule::Exact`].
pub fn whole_cycle_window(
    n_samples: usize,
    dt_s: f64,
    frequency_hz: f64,
    rule: CycleRule,
) -> Result<CycleWindow> {
    check_sampling(dt_s, frequency_hz)?;
    let f_dt = frequency_hz * dt_s;
    let samples_per_cycle = 1.0 / f_dt;
    let cycles_available = n_samples as f64 * f_dt;
    let too_short = || SignalError::LessThanOneCycle {
        frequency_hz,
        cycles_available,
    };
    // Largest candidate cycle count, allowing for rounding in `n·f·dt`.
    let c_max = (cycles_available + 1e-9).floor() as usize;
    if c_max == 0 {
        return Err(too_short());
    }
    let make = |c: usize, m: usize| CycleWindow {
        first_sample: n_samples - m,
        n_samples: m,
        n_cycles: c,
        samples_per_cycle,
    };
    match rule {
        CycleRule::Exact => {
            for c in (1..=c_max).rev() {
                let m_real = c as f64 / f_dt;
                let m = m_real.round();
                if (m_real - m).abs() <= WHOLE_CYCLE_TOLERANCE_SAMPLES && m as usize <= n_samples {
                    return Ok(make(c, m as usize));
                }
            }
            Err(SignalError::NoWholeCycleWindow {
                frequency_hz,
                samples_per_cycle,
            })
        }
        CycleRule::Nearest => {
            for c in (1..=c_max).rev() {
                let m = (c as f64 / f_dt).round() as usize;
                if m <= n_samples && m >= 2 {
                    return Ok(make(c, m));
                }
            }
            Err(too_short())
        }
    }
}

/// Single-bin DFT `(2/N) Σ x_k e^{−iΩ t_k}` over `samples[window]`, with the
/// phase reduced modulo one cycle before the trigonometric evaluation.
fn single_bin(
    samples: &[f64],
    t0_s: f64,
    dt_s: f64,
    frequency_hz: f64,
    w: &CycleWindow,
) -> Complex64 {
    let cycles_t0 = (frequency_hz * t0_s).rem_euclid(1.0);
    let f_dt = frequency_hz * dt_s;
    let mut sum = Complex64::new(0.0, 0.0);
    for (j, &x) in samples[w.first_sample..w.first_sample + w.n_samples]
        .iter()
        .enumerate()
    {
        let k = (w.first_sample + j) as f64;
        let cycles = cycles_t0 + (k * f_dt).fract();
        let (s, c) = (TAU * cycles).sin_cos();
        sum += Complex64::new(x * c, -x * s);
    }
    sum * (2.0 / w.n_samples as f64)
}

/// Complex amplitude `X̂ = (2/N) Σ x_k e^{−iΩ t_k}` of `samples` (taken at
/// `t_k = t0_s + k·dt_s`) at `frequency_hz`, over the largest window of whole
/// cycles at the end of the record that is an exact integer number of
/// samples ([`CycleRule::Exact`]).
///
/// Convention `x(t) = Re(X̂ e^{iΩt})`; the FFT amplitude of [D Eq. 3.12].
/// Errors: non-finite data, invalid `dt_s`/`frequency_hz`, fewer than one
/// cycle, no exact whole-cycle window (then use
/// [`harmonic_amplitude_with_rule`] with [`CycleRule::Nearest`]).
pub fn harmonic_amplitude(
    samples: &[f64],
    t0_s: f64,
    dt_s: f64,
    frequency_hz: f64,
) -> Result<HarmonicAmplitude> {
    harmonic_amplitude_with_rule(samples, t0_s, dt_s, frequency_hz, CycleRule::Exact)
}

/// As [`harmonic_amplitude`], with an explicit window rule.
pub fn harmonic_amplitude_with_rule(
    samples: &[f64],
    t0_s: f64,
    dt_s: f64,
    frequency_hz: f64,
    rule: CycleRule,
) -> Result<HarmonicAmplitude> {
    check_finite_scalar("t0_s", t0_s)?;
    check_finite("samples", samples)?;
    let window = whole_cycle_window(samples.len(), dt_s, frequency_hz, rule)?;
    let amplitude = single_bin(samples, t0_s, dt_s, frequency_hz, &window);
    Ok(HarmonicAmplitude {
        amplitude,
        frequency_hz,
        window,
    })
}

/// One-sided amplitude spectrum with the crate's complex-amplitude convention.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrum {
    /// Bin frequencies `j/(N·dt)`, `j = 0..=N/2`.
    pub frequencies_hz: Vec<f64>,
    /// Complex amplitudes `X̂_j` (unit of the signal), `x(t) ≈ Σ_j Re(X̂_j e^{iΩ_j t})`.
    pub amplitudes: Vec<Complex64>,
    /// Bin spacing `1/(N·dt)`.
    pub frequency_resolution_hz: f64,
}

impl Spectrum {
    /// Index of the bin nearest to `frequency_hz`, or `None` if the frequency
    /// is negative, non-finite or more than half a bin above the last bin.
    pub fn nearest_bin(&self, frequency_hz: f64) -> Option<usize> {
        if !frequency_hz.is_finite() || frequency_hz < 0.0 {
            return None;
        }
        let j = (frequency_hz / self.frequency_resolution_hz).round() as usize;
        (j < self.amplitudes.len()).then_some(j)
    }

    /// Complex amplitude of the bin nearest to `frequency_hz` (see [`Spectrum::nearest_bin`]).
    pub fn amplitude_at(&self, frequency_hz: f64) -> Option<Complex64> {
        self.nearest_bin(frequency_hz).map(|j| self.amplitudes[j])
    }

    /// Magnitudes `|X̂_j|` (unit of the signal).
    pub fn magnitudes(&self) -> Vec<f64> {
        self.amplitudes.iter().map(|a| a.norm()).collect()
    }
}

/// One-sided amplitude spectrum of `samples` (at `t_k = t0_s + k·dt_s`) via
/// rustfft: `X̂_j = (2/N) Σ_k x_k e^{−iΩ_j t_k}` for `0 < j < N/2`; the DC bin
/// (and, for even `N`, the Nyquist bin) use `1/N` instead of `2/N`, so the DC
/// bin is the mean. No window is applied: a component at `f` is exact when
/// the record holds whole cycles of `f` (`f` is then a bin frequency).
pub fn spectrum(samples: &[f64], t0_s: f64, dt_s: f64) -> Result<Spectrum> {
    check_finite_scalar("t0_s", t0_s)?;
    check_positive("dt_s", dt_s)?;
    check_finite("samples", samples)?;
    let n = samples.len();
    if n < 2 {
        return Err(SignalError::TooFew {
            what: "samples",
            needed: 2,
            got: n,
        });
    }
    let mut buf: Vec<Complex64> = samples.iter().map(|&x| Complex64::new(x, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let span_s = n as f64 * dt_s;
    let n_bins = n / 2 + 1;
    let mut frequencies_hz = Vec::with_capacity(n_bins);
    let mut amplitudes = Vec::with_capacity(n_bins);
    for (j, &b) in buf.iter().take(n_bins).enumerate() {
        let scale = if j == 0 || 2 * j == n { 1.0 } else { 2.0 } / n as f64;
        // Shift the time origin from the first sample to t = 0.
        let cycles = (j as f64 * t0_s / span_s).rem_euclid(1.0);
        let shift = Complex64::from_polar(1.0, -2.0 * PI * cycles);
        frequencies_hz.push(j as f64 / span_s);
        amplitudes.push(b * shift * scale);
    }
    Ok(Spectrum {
        frequencies_hz,
        amplitudes,
        frequency_resolution_hz: 1.0 / span_s,
    })
}
