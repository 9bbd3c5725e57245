//! Errors of parameter validation shared by the powder law, the size distribution and the
//! cantilever scenario: every error names the key (with its section prefix, e.g.
//! `powder.law.friction`).

/// A parameter outside its range or otherwise invalid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParameterError {
    /// A number outside its range.
    #[error("{key}: {expected}, got {value}")]
    OutOfRange {
        /// The key, with its section prefix.
        key: String,
        /// The value given.
        value: f64,
        /// The allowed range (`must be in (0, 1]`, …).
        expected: String,
    },
    /// Any other invalid value or combination of values.
    #[error("{key}: {message}")]
    Invalid {
        /// The key (or keys), with the section prefix.
        key: String,
        /// What is wrong and how to fix it.
        message: String,
    },
}

impl ParameterError {
    /// [`ParameterError::OutOfRange`].
    pub fn out_of_range(key: impl Into<String>, value: f64, expected: impl Into<String>) -> Self {
        Self::OutOfRange {
            key: key.into(),
            value,
            expected: expected.into(),
        }
    }

    /// [`ParameterError::Invalid`].
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }
}
