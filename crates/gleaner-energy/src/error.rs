use thiserror::Error;

/// Invalid arguments to the energy model. Each message carries the offending value.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EnergyError {
    /// A model parameter outside its valid range (the message names the parameter, its unit
    /// and the range it must lie in).
    #[error("invalid {name}: {value} (expected {expected})")]
    InvalidParameter {
        /// Parameter name, with its unit.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// A search interval that is empty or not finite.
    #[error("invalid search interval [{lo}, {hi}]: need finite lo < hi")]
    InvalidInterval {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// Two inputs that must have the same length do not.
    #[error("length mismatch: {what} ({left} vs {right})")]
    LengthMismatch {
        /// What is being compared.
        what: &'static str,
        /// Length of the first input.
        left: usize,
        /// Length of the second input.
        right: usize,
    },
}

/// Checks that `value` is finite and > 0.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, EnergyError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(EnergyError::InvalidParameter {
            name,
            value,
            expected: "a finite number > 0",
        })
    }
}

/// Checks that `value` is finite and >= 0.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, EnergyError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(EnergyError::InvalidParameter {
            name,
            value,
            expected: "a finite number >= 0",
        })
    }
}

/// Checks that `value` is finite (any sign).
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64, EnergyError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EnergyError::InvalidParameter {
            name,
            value,
            expected: "a finite number",
        })
    }
}
