//! [`Welch::spectra`]: the auto- and cross-spectra of several signals from
//! one set of segment FFTs.

use rustfft::num_complex::Complex64;

use super::{check_fs, mirror, Average, Engine, Welch, WelchSettings};
use crate::error::{check_signal_set, Result};

/// Auto- and cross-spectra of several equal-length signals, from one set of
/// segment FFTs (see [`Welch::spectra`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralSet {
    /// Bin frequencies in Hz (`rfftfreq` or `fftfreq` order).
    pub freq_hz: Vec<f64>,
    /// The power spectral density of each signal, in input order.
    pub auto: Vec<Vec<f64>>,
    /// The cross spectral density of each requested pair `(i, j)`,
    /// `conj(X_i) X_j` averaged, in the order of the pairs.
    pub cross: Vec<Vec<Complex64>>,
    /// Number of segments averaged.
    pub n_segments: usize,
}

impl Welch {
    /// The PSD of every signal and the CSD of every pair `(i, j)` of
    /// `signals` (indices into it): [`Welch::psd`] of each signal and
    /// [`Welch::csd`] of each pair, but with each segment of each signal
    /// transformed once (one real FFT) instead of once per spectrum it
    /// enters: three signals and their three pairs take 3 real FFTs per
    /// segment instead of the equivalent of 9. The single-spectrum calls
    /// pack segments into complex FFTs differently, so the results agree
    /// with them to rounding (`spectra_set_equals_psd_and_csd` bounds the
    /// difference at 1e-13 of each series' peak), and with median
    /// averaging (computed by them) exactly. SciPy has no such call; its
    /// `welch` and `csd` are matched.
    ///
    /// # Errors
    /// As [`Welch::psd`] for every signal; [`crate::DspError::LengthMismatch`] if
    /// the signals' lengths differ; [`crate::DspError::InvalidSetting`] for a pair
    /// index out of range.
    pub fn spectra(
        &mut self,
        signals: &[&[f64]],
        pairs: &[(usize, usize)],
        fs_hz: f64,
    ) -> Result<SpectralSet> {
        check_fs(fs_hz)?;
        let n = check_signal_set(signals, pairs, "signals (spectra)")?;
        if self.settings.average == Average::Median {
            // Medians need every segment's value; the single-spectrum
            // paths keep them. Same results, three times the FFTs.
            let mut auto = Vec::with_capacity(signals.len());
            let mut freq_hz = Vec::new();
            let mut n_segments = 0;
            for x in signals {
                let p = self.psd(x, fs_hz)?;
                (freq_hz, n_segments) = (p.freq_hz, p.n_segments);
                auto.push(p.pxx);
            }
            let cross = pairs
                .iter()
                .map(|&(i, j)| self.csd(signals[i], signals[j], fs_hz).map(|c| c.pxy))
                .collect::<Result<_>>()?;
            return Ok(SpectralSet {
                freq_hz,
                auto,
                cross,
                n_segments,
            });
        }
        let s = self.settings.clone();
        Ok(match self.engine_for(n)? {
            Some(mut e) => e.set(signals, pairs, fs_hz, &s),
            None => self.engine.set(signals, pairs, fs_hz, &s),
        })
    }
}

impl Engine {
    /// [`Welch::spectra`] with mean averaging (inputs validated): one real
    /// FFT per signal and segment ([`Engine::segment_fft`]), then the
    /// products, sums and scalings of the single-spectrum paths.
    pub(super) fn set(
        &mut self,
        signals: &[&[f64]],
        pairs: &[(usize, usize)],
        fs_hz: f64,
        s: &WelchSettings,
    ) -> SpectralSet {
        let nseg = self.n_segments(signals[0].len());
        let step = self.nperseg - self.noverlap;
        let nb = self.n_bins();
        let mut specs = vec![vec![Complex64::new(0.0, 0.0); nb]; signals.len()];
        let mut auto = vec![vec![0.0; nb]; signals.len()];
        let mut cross = vec![vec![Complex64::new(0.0, 0.0); nb]; pairs.len()];
        for seg in 0..nseg {
            for (x, spec) in signals.iter().zip(specs.iter_mut()) {
                self.segment_fft(x, seg * step, s.detrend, false);
                spec.copy_from_slice(&self.spec_x);
            }
            for (acc, spec) in auto.iter_mut().zip(&specs) {
                acc.iter_mut()
                    .zip(spec)
                    .for_each(|(a, c)| *a += c.norm_sqr());
            }
            for (acc, &(i, j)) in cross.iter_mut().zip(pairs) {
                // conj(a) * b, written as in `Engine::cross`.
                for ((s, a), b) in acc.iter_mut().zip(&specs[i]).zip(&specs[j]) {
                    s.re += a.re * b.re + a.im * b.im;
                    s.im += a.re * b.im - a.im * b.re;
                }
            }
        }
        let fac = self.bin_factors(fs_hz, s.scaling, s.onesided);
        let inv = 1.0 / nseg as f64;
        let auto = auto
            .into_iter()
            .map(|acc| {
                let p: Vec<f64> = acc.iter().zip(&fac).map(|(a, f)| a * f * inv).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, self.nfft, |v| v)
                }
            })
            .collect();
        let cross = cross
            .into_iter()
            .map(|acc| {
                let p: Vec<Complex64> = acc.iter().zip(&fac).map(|(a, f)| a * (f * inv)).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, self.nfft, |v| v.conj())
                }
            })
            .collect();
        SpectralSet {
            freq_hz: self.freqs(fs_hz, s.onesided),
            auto,
            cross,
            n_segments: nseg,
        }
    }
}
