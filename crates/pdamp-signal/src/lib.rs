//! Signal analysis: harmonic amplitudes, complex power method, decay and FRF evaluation.
//!
//! Conventions: `f64`, SI units, and complex amplitudes in the form
//! `x(t) = Re(X̂ e^{iΩt})`, `Ω = 2πf` (see [`harmonic`]). Equation references
//! "[D Eq. x]" point to the reference dissertation on the particle damper
//! design toolchain.
//!
//! - [`harmonic`]: exact single-bin DFT over whole cycles, one-sided spectrum.
//! - [`mod@complex_power`]: dissipated energy, (effective) loss factor and
//!   effective particle mass [D Eqs. 3.12–3.17].
//! - [`decay`]: peaks, logarithmic decrement, exponential fit,
//!   amplitude-dependent damping.
//! - [`frf`]: stepped-sine FRF, Welch H1 estimator, half-power damping.
//!
//! ```
//! use std::f64::consts::TAU;
//! use pdamp_signal::complex_power_from_time_series;
//!
//! // Container moved as x = X sin(Ωt) [D Eq. 3.8] with a viscous damper c
//! // inside a container of mass m_con: F = m_con·a + c·v.
//! let (f_hz, dt_s, x_m, c, m_con_kg, m_bed_kg) = (2.0, 1e-3, 0.01, 5.0, 0.3, 0.5);
//! let w = TAU * f_hz;
//! let t: Vec<f64> = (0..1000).map(|k| k as f64 * dt_s).collect();
//! let v: Vec<f64> = t.iter().map(|t| x_m * w * (w * t).cos()).collect();
//! let force: Vec<f64> = t
//!     .iter()
//!     .zip(&v)
//!     .map(|(t, v)| -m_con_kg * x_m * w * w * (w * t).sin() + c * v)
//!     .collect();
//! let r = complex_power_from_time_series(&force, &v, 0.0, dt_s, f_hz, m_bed_kg, m_con_kg)?;
//! // Ẽ = π c Ω X² per cycle, η̄ = c/(m_bed Ω).
//! assert!((r.dissipated_energy_per_cycle_j - std::f64::consts::PI * c * w * x_m * x_m).abs() < 1e-12);
//! assert!((r.effective_loss_factor - c / (m_bed_kg * w)).abs() < 1e-12);
//! # Ok::<(), pdamp_signal::SignalError>(())
//! ```

#![forbid(unsafe_code)]
pub mod complex_power;
pub mod decay;
pub mod error;
pub mod frf;
pub mod harmonic;

pub use complex_power::{ComplexPowerResult, complex_power, complex_power_from_time_series};
pub use error::{Result, SignalError};
pub use harmonic::{CycleRule, HarmonicAmplitude, Spectrum, harmonic_amplitude, spectrum};
pub use num_complex::Complex64;
