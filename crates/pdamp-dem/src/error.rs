//! Typed errors of the engine's inputs: parameters of contact laws, materials, size
//! distributions, regions, walls and integrators. Each names the key it is about; the
//! message is what the user sees (the CLI prefixes the scenario path and line).

/// A parameter of the engine is out of range or does not fit the others.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParameterError {
    /// A number outside its allowed range, e.g. `normal.restitution must lie in (0, 1], got 1.3`.
    #[error("{key} must {requirement}, got {value}")]
    OutOfRange {
        /// The key, e.g. `friction.friction_coefficient` or `radius_m`.
        key: String,
        /// What the value must satisfy, phrased after "must", e.g. `be > 0`.
        requirement: String,
        /// The value given.
        value: f64,
    },
    /// Values that do not fit together or a value outside its range with a hint how to fix it;
    /// `message` is the whole sentence and starts with (or names) `key`.
    #[error("{message}")]
    Invalid {
        /// The key the message is about.
        key: String,
        /// The whole message.
        message: String,
    },
}

impl ParameterError {
    /// `key must requirement, got value`.
    pub fn out_of_range(
        key: impl Into<String>,
        requirement: impl Into<String>,
        value: f64,
    ) -> Self {
        Self::OutOfRange {
            key: key.into(),
            requirement: requirement.into(),
            value,
        }
    }

    /// A message about `key` that is not a plain range check.
    pub fn invalid(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Invalid {
            key: key.into(),
            message: message.into(),
        }
    }

    /// A message that starts with the key it is about (`a.b[2].c must be > 0`): the key is
    /// taken from it ([`leading_key_path`]).
    pub fn from_message(message: impl Into<String>) -> Self {
        let message = message.into();
        Self::Invalid {
            key: leading_key_path(&message).to_string(),
            message,
        }
    }

    /// The same error for a key under the table `prefix` (which ends with its separator, e.g.
    /// `contact.` or `materials[2].`): key and message get the prefix.
    pub fn under(self, prefix: &str) -> Self {
        match self {
            Self::OutOfRange {
                key,
                requirement,
                value,
            } => Self::OutOfRange {
                key: format!("{prefix}{key}"),
                requirement,
                value,
            },
            Self::Invalid { key, message } => Self::Invalid {
                key: format!("{prefix}{key}"),
                message: format!("{prefix}{message}"),
            },
        }
    }

    /// The key the error is about.
    pub fn key(&self) -> &str {
        match self {
            Self::OutOfRange { key, .. } | Self::Invalid { key, .. } => key,
        }
    }

    /// `Ok(())` when `ok`, otherwise [`ParameterError::OutOfRange`].
    pub fn check(ok: bool, key: &str, requirement: &str, value: f64) -> Result<(), Self> {
        if ok {
            Ok(())
        } else {
            Err(Self::out_of_range(key, requirement, value))
        }
    }
}

/// The key path a validation message starts with: `a.b[2].c` of `a.b[2].c must be > 0`.
pub fn leading_key_path(message: &str) -> &str {
    let end = message
        .find(|c: char| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '[' | ']' | '-')))
        .unwrap_or(message.len());
    message[..end].trim_end_matches('.')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_of_a_message_is_its_leading_path() {
        let e = ParameterError::from_message("particles[2].size.radius_m must be > 0, got -1");
        assert_eq!(e.key(), "particles[2].size.radius_m");
        assert_eq!(
            e.to_string(),
            "particles[2].size.radius_m must be > 0, got -1"
        );
        let e = ParameterError::out_of_range("rolling.coefficient", "be >= 0", -0.5);
        assert_eq!(e.to_string(), "rolling.coefficient must be >= 0, got -0.5");
        assert_eq!(e.key(), "rolling.coefficient");
        assert_eq!(leading_key_path("simulation.dt_s. must"), "simulation.dt_s");
        let e = e.under("contact.");
        assert_eq!(e.key(), "contact.rolling.coefficient");
        assert_eq!(
            e.to_string(),
            "contact.rolling.coefficient must be >= 0, got -0.5"
        );
        let e = ParameterError::invalid("axis", "axis must be non-zero").under("walls[1].");
        assert_eq!(e.key(), "walls[1].axis");
        assert_eq!(e.to_string(), "walls[1].axis must be non-zero");
    }
}
