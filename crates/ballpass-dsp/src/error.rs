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
#[inline(always)]
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
/// Fast path: [`all_finite`] over blocks, compiled for the widest vectors
/// the CPU has ([`crate::simd::widest`]), so kernels can afford to check
/// every call.
#[inline(always)]
pub(crate) fn first_non_finite(x: &[f64]) -> Option<usize> {
    if crate::simd::widest(|| x.chunks(1024).all(all_finite)) {
        return None;
    }
    x.iter().position(|v| !v.is_finite())
}

/// Accumulators of [`all_finite`].
const FINITE_ACC: usize = 32;

/// Whether every sample of `x` is finite, branch-free:
///
/// ```text
/// sum_i 0 * x[i] = 0     iff every x[i] is finite (0 * inf, 0 * NaN = NaN)
/// ```
///
/// summed in [`FINITE_ACC`] independent accumulators so that the loop
/// vectorises (about twice as fast as testing the exponent bits on the
/// SSE2 baseline, which lacks 64-bit integer compares) into several
/// independent chains of vector additions (4 with AVX-512: one chain
/// would be bound by the addition's latency).
#[inline(always)]
pub(crate) fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; FINITE_ACC];
    let mut blocks = x.chunks_exact(FINITE_ACC);
    for b in &mut blocks {
        for (a, v) in acc.iter_mut().zip(b) {
            *a += 0.0 * v;
        }
    }
    for (a, v) in acc.iter_mut().zip(blocks.remainder()) {
        *a += 0.0 * v;
    }
    // Each accumulator is +-0 or NaN: test them all at once rather than
    // summing them in one dependent chain.
    acc.iter().fold(true, |ok, &a| ok & (a == 0.0))
}

/// Checks a set of signals and the index pairs into it that a multi-signal
/// kernel ([`crate::Correlator::correlate_pairs`], [`crate::Welch::spectra`])
/// takes: at least one signal, each non-empty and finite, all of one length,
/// every pair index in range. Returns the common length.
///
/// # Errors
/// [`DspError::Empty`]/[`DspError::NonFinite`] for a signal,
/// [`DspError::LengthMismatch`] (naming `kernel`) for unequal lengths,
/// [`DspError::InvalidSetting`] for a pair index out of range.
pub(crate) fn check_signal_set(
    signals: &[&[f64]],
    pairs: &[(usize, usize)],
    kernel: &'static str,
) -> Result<usize> {
    let Some(first) = signals.first() else {
        return Err(DspError::Empty { what: "signals" });
    };
    let n = first.len();
    for s in signals {
        check_finite("signal", s)?;
        if s.len() != n {
            return Err(DspError::LengthMismatch {
                what: kernel,
                expected: n,
                found: s.len(),
            });
        }
    }
    if let Some(&(a, b)) = pairs
        .iter()
        .find(|&&(a, b)| a >= signals.len() || b >= signals.len())
    {
        return Err(invalid(
            "pairs",
            format!(
                "pair ({a}, {b}) names a signal beyond the {} given",
                signals.len()
            ),
        ));
    }
    Ok(n)
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

    #[test]
    fn all_finite_sees_every_position() {
        let ok: Vec<f64> = (0..37).map(|i| -1e300 * i as f64 - 0.0).collect();
        assert!(all_finite(&ok) && all_finite(&[]) && all_finite(&[-0.0, f64::MAX]));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for i in 0..ok.len() {
                let mut x = ok.clone();
                x[i] = bad;
                assert!(!all_finite(&x), "{bad} at {i}");
                assert_eq!(first_non_finite(&x), Some(i));
            }
        }
        // Across the 1024-sample blocks and the accumulators' remainders.
        let long: Vec<f64> = (0..3001).map(|i| i as f64 - 1500.5).collect();
        assert_eq!(first_non_finite(&long), None);
        for i in [0, 31, 32, 1023, 1024, 1025, 2047, 2999, 3000] {
            let mut x = long.clone();
            x[i] = f64::NAN;
            assert_eq!(first_non_finite(&x), Some(i), "NaN at {i}");
            assert!(!all_finite(&x));
        }
    }
}
