//! Anti-aliased downsampling, `scipy.signal.decimate` with its IIR filter.

use crate::error::{invalid, Result};
use crate::iir::{cheby1, FilterBand};
use crate::sos::{sosfilt, FiltFiltSettings, Sos, ZeroPhaseFilter};

/// Settings of [`Decimator`]; the default matches SciPy's
/// `decimate(x, q, ftype='iir', zero_phase=True)` with `q = 2`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DecimateSettings {
    /// Downsampling factor `q >= 2`: every `q`-th sample is kept.
    pub q: usize,
    /// Order of the Chebyshev I anti-alias filter (SciPy's `n`, default 8).
    pub order: usize,
    /// Filter forward and backward (`sosfiltfilt`, SciPy's default) instead
    /// of forward only (`sosfilt`).
    pub zero_phase: bool,
}

impl Default for DecimateSettings {
    fn default() -> Self {
        DecimateSettings {
            q: 2,
            order: 8,
            zero_phase: true,
        }
    }
}

/// A planned decimator: the anti-alias filter is designed once.
///
/// ```text
/// sos = cheby1(order, 0.05 dB, 0.8 / q)     (cutoff as a fraction of Nyquist)
/// y   = sosfiltfilt(sos, x)[::q]            (zero_phase; else sosfilt)
/// ```
///
/// The output has `ceil(len(x) / q)` samples, `y[k] = filtered[k q]`, as
/// SciPy's slicing `[::q]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Decimator {
    q: usize,
    zero_phase: bool,
    filter: ZeroPhaseFilter,
}

impl Decimator {
    /// Designs the anti-alias filter.
    ///
    /// # Errors
    /// [`crate::DspError::InvalidSetting`] if `q < 2` or `order == 0`.
    pub fn new(settings: DecimateSettings) -> Result<Decimator> {
        if settings.q < 2 {
            return Err(invalid(
                "q",
                format!("decimation factor must be at least 2, got {}", settings.q),
            ));
        }
        if settings.order == 0 {
            return Err(invalid("order", "must be at least 1, got 0"));
        }
        // SciPy: cheby1(n, 0.05, 0.8 / q, output='sos') with Wn relative to
        // Nyquist, i.e. fs = 2.
        let sos = cheby1(
            settings.order,
            0.05,
            FilterBand::LowPass {
                cutoff_hz: 0.8 / settings.q as f64,
            },
            2.0,
        )?;
        Ok(Decimator {
            q: settings.q,
            zero_phase: settings.zero_phase,
            filter: ZeroPhaseFilter::new(sos, FiltFiltSettings::default())?,
        })
    }

    /// The anti-alias filter.
    pub fn sos(&self) -> &Sos {
        self.filter.sos()
    }

    /// The planned zero-phase anti-alias filter (what [`Decimator::apply`]
    /// runs when zero-phase), for filtering a signal in pieces
    /// ([`crate::ZeroPhaseStream`]).
    pub fn zero_phase_filter(&self) -> Option<&ZeroPhaseFilter> {
        self.zero_phase.then_some(&self.filter)
    }

    /// The decimation factor `q`.
    pub fn q(&self) -> usize {
        self.q
    }

    /// Filters and downsamples `x`.
    ///
    /// # Errors
    /// [`crate::DspError::Empty`] / [`crate::DspError::NonFinite`] for a bad
    /// `x`; [`crate::DspError::TooShort`] if zero-phase and `x` is not longer
    /// than the filter's padlen (27 for the default order 8).
    pub fn apply(&self, x: &[f64]) -> Result<Vec<f64>> {
        // Both check `x`.
        let y = if self.zero_phase {
            self.filter.apply(x)?
        } else {
            sosfilt(self.filter.sos(), x)?
        };
        Ok(y.iter().step_by(self.q).copied().collect())
    }
}

/// `scipy.signal.decimate(x, q)` (IIR, zero phase): Chebyshev I low-pass at
/// `0.8 fs / (2q)`, forward-backward, then every `q`-th sample from the
/// first. See [`Decimator`] to design once and run many.
///
/// ```
/// let x: Vec<f64> = (0..200).map(|i| (i as f64 * 0.01).sin()).collect();
/// let y = ballpass_dsp::decimate(&x, 4).unwrap();
/// assert_eq!(y.len(), 50);
/// ```
///
/// # Errors
/// As [`Decimator::new`] and [`Decimator::apply`].
pub fn decimate(x: &[f64], q: usize) -> Result<Vec<f64>> {
    Decimator::new(DecimateSettings {
        q,
        ..DecimateSettings::default()
    })?
    .apply(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validates() {
        assert!(decimate(&[1.0; 100], 1).is_err());
        assert!(decimate(&[1.0; 100], 0).is_err());
        assert!(decimate(&[1.0; 27], 2).is_err());
        assert_eq!(decimate(&[1.0; 28], 2).unwrap().len(), 14);
        assert!(decimate(&[], 2).is_err());
    }
}
