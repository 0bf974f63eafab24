//! The one error type of `ballpass-dsp`.

/// Result alias used by every kernel in this crate.
pub type Result<T> = std::result::Result<T, DspError>;

/// What was wrong with the input or the settings given to a kernel.
///
/// Every variant names the argument it is about, so that a caller can turn it
/// into a message for a person ("channel friction_N: ...").
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DspError {
    /// An input that must hold samples holds none.
    #[error("{what} is empty")]
    Empty {
        /// Which argument.
        what: &'static str,
    },
    /// An input holds a NaN or an infinity.
    #[error("{what} holds a non-finite value ({value}) at index {index}")]
    NonFinite {
        /// Which argument.
        what: &'static str,
        /// Index of the first bad sample.
        index: usize,
        /// The value found there.
        value: f64,
    },
    /// Two inputs that must have equal lengths do not.
    #[error("{what}: lengths differ (expected {expected}, found {found})")]
    LengthMismatch {
        /// Which arguments.
        what: &'static str,
        /// Length of the first.
        expected: usize,
        /// Length of the second.
        found: usize,
    },
    /// An input is too short for the operation.
    #[error("{what} is too short: needs at least {needed} samples, has {found}")]
    TooShort {
        /// Which argument.
        what: &'static str,
        /// Minimum length.
        needed: usize,
        /// Actual length.
        found: usize,
    },
    /// A setting is out of its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidSetting {
        /// Name of the setting, as in the settings struct.
        name: &'static str,
        /// What is wrong, with the value.
        reason: String,
    },
    /// A numerical procedure did not converge or became singular.
    #[error("{what} failed: {reason}")]
    Numerical {
        /// Which procedure.
        what: &'static str,
        /// Why.
        reason: String,
    },
}

/// Checks that `x` is non-empty and finite.
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`].
pub fn check_finite(what: &'static str, x: &[f64]) -> Result<()> {
    if x.is_empty() {
        return Err(DspError::Empty { what });
    }
    match first_non_finite(x) {
        Some(index) => Err(DspError::NonFinite {
            what,
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}

/// Index of the first NaN or infinity in `x`.
///
/// Fast path: a branch-free OR of "exponent all ones" (NaN or inf) over
/// blocks vectorises, so kernels can afford to check every call.
pub(crate) fn first_non_finite(x: &[f64]) -> Option<usize> {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    if x.chunks(1024).all(|c| {
        c.iter()
            .fold(0u64, |bad, v| bad | u64::from(v.to_bits() & EXP == EXP))
            == 0
    }) {
        return None;
    }
    x.iter().position(|v| !v.is_finite())
}

/// Returns an [`DspError::InvalidSetting`] built from a name and a message.
pub fn invalid(name: &'static str, reason: impl Into<String>) -> DspError {
    DspError::InvalidSetting {
        name,
        reason: reason.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_finite_names_first_bad_sample() {
        let err = check_finite("x", &[1.0, f64::NAN, f64::INFINITY]).unwrap_err();
        assert!(matches!(err, DspError::NonFinite { index: 1, .. }));
        assert_eq!(
            check_finite("x", &[]).unwrap_err(),
            DspError::Empty { what: "x" }
        );
        assert!(check_finite("x", &[0.0, -1.0]).is_ok());
    }
}
