//! Error type shared by all analysis functions of this crate.

use thiserror::Error;

/// Errors returned by the signal-analysis functions.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SignalError {
    /// A sample or parameter array contains NaN or an infinity.
    #[error("non-finite value in `{name}` at index {index}")]
    NonFinite {
        /// Name of the offending argument.
        name: &'static str,
        /// Index of the first non-finite element.
        index: usize,
    },
    /// A scalar argument is out of its valid range (or not finite).
    #[error("invalid argument `{name}` = {value}: {reason}")]
    InvalidArgument {
        /// Name of the offending argument.
        name: &'static str,
        /// The value that was passed.
        value: f64,
        /// Why it was rejected.
        reason: &'static str,
    },
    /// Too few samples, peaks or points for the requested analysis.
    #[error("too few {what}: at least {needed} required, got {got}")]
    TooFew {
        /// What is counted (samples, peaks, points, ...).
        what: &'static str,
        /// Minimum number required.
        needed: usize,
        /// Number supplied.
        got: usize,
    },
    /// Two arrays that must have equal length do not.
    #[error("length mismatch: `{left}` has {left_len} elements, `{right}` has {right_len}")]
    LengthMismatch {
        /// Name of the first array.
        left: &'static str,
        /// Length of the first array.
        left_len: usize,
        /// Name of the second array.
        right: &'static str,
        /// Length of the second array.
        right_len: usize,
    },
    /// The record is shorter than one period of the analysis frequency.
    #[error(
        "record covers only {cycles_available} cycles of {frequency_hz} Hz; at least one whole cycle is required"
    )]
    LessThanOneCycle {
        /// Analysis frequency.
        frequency_hz: f64,
        /// Number of (fractional) cycles contained in the record.
        cycles_available: f64,
    },
    /// No number of whole cycles maps onto an integer number of samples.
    #[error(
        "no window of whole cycles of {frequency_hz} Hz fits an integer number of samples \
         ({samples_per_cycle} samples per cycle); use `CycleRule::Nearest`"
    )]
    NoWholeCycleWindow {
        /// Analysis frequency.
        frequency_hz: f64,
        /// Samples per cycle, `1/(f·dt)`.
        samples_per_cycle: f64,
    },
    /// The data are degenerate for the requested quantity (e.g. zero velocity amplitude).
    #[error("degenerate data: {reason}")]
    Degenerate {
        /// Description of the degeneracy.
        reason: &'static str,
    },
    /// The −3 dB level is not crossed on one side of the resonance peak.
    #[error(
        "half-power crossing not found on the {side} side of the peak at {peak_frequency_hz} Hz"
    )]
    HalfPowerCrossingNotFound {
        /// `"lower"` or `"upper"`.
        side: &'static str,
        /// Frequency of the picked peak.
        peak_frequency_hz: f64,
    },
}

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, SignalError>;

/// Fails with [`SignalError::NonFinite`] at the first non-finite element.
pub(crate) fn check_finite(name: &'static str, data: &[f64]) -> Result<()> {
    match data.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(SignalError::NonFinite { name, index }),
        None => Ok(()),
    }
}

/// Fails unless `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SignalError::InvalidArgument {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}

/// Fails unless `value` is finite.
pub(crate) fn check_finite_scalar(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SignalError::InvalidArgument {
            name,
            value,
            reason: "must be finite",
        })
    }
}

/// Fails unless both slices have the same length.
pub(crate) fn check_same_len(
    left: &'static str,
    left_len: usize,
    right: &'static str,
    right_len: usize,
) -> Result<()> {
    if left_len == right_len {
        Ok(())
    } else {
        Err(SignalError::LengthMismatch {
            left,
            left_len,
            right,
            right_len,
        })
    }
}
