//! Welch auto- and cross-spectra of signals that arrive in pieces, in
//! memory that does not grow with their length.
//!
//! [`WelchStream`] holds less than one segment of each signal: as soon as
//! a segment is complete it is transformed, its products are added to the
//! sums, and the samples no later segment needs are dropped. The segments,
//! their order and every operation on them are those of
//! [`Welch::spectra`](crate::Welch::spectra) with mean averaging, so the
//! result equals it to the bit however the signals are cut into pieces.

use crate::error::{check_finite, invalid, DspError, Result};
use crate::spectral::{
    check_settings, geometry, mirror, Average, Engine, SpectralSet, WelchSettings,
};
use crate::Complex64;

/// [`Welch::spectra`](crate::Welch::spectra) (mean average) fed piece by
/// piece ([`WelchStream::push`]).
pub struct WelchStream {
    settings: WelchSettings,
    engine: Engine,
    pairs: Vec<(usize, usize)>,
    /// The samples of each signal from the next segment's start.
    bufs: Vec<Vec<f64>>,
    specs: Vec<Vec<Complex64>>,
    auto: Vec<Vec<f64>>,
    cross: Vec<Vec<Complex64>>,
    n_segments: usize,
}

impl std::fmt::Debug for WelchStream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WelchStream")
            .field("settings", &self.settings)
            .field("n_segments", &self.n_segments)
            .finish()
    }
}

impl WelchStream {
    /// A stream of `k` signals with the spectra of `pairs` (indices).
    /// `settings.nperseg` is used as given (the caller caps it at the
    /// signal length, as [`Welch`](crate::Welch) does for a short signal).
    ///
    /// # Errors
    /// As [`Welch::new`](crate::Welch::new);
    /// [`DspError::InvalidSetting`] for median averaging (it needs every
    /// segment's spectrum) or a pair index out of range.
    pub fn new(settings: WelchSettings, k: usize, pairs: &[(usize, usize)]) -> Result<WelchStream> {
        check_settings(&settings)?;
        if settings.average == Average::Median {
            return Err(invalid(
                "average",
                "a streamed Welch estimate averages by the mean (the median needs every segment)",
            ));
        }
        if let Some(&(a, b)) = pairs.iter().find(|&&(a, b)| a >= k || b >= k) {
            return Err(invalid(
                "pairs",
                format!("pair ({a}, {b}) is out of range for {k} signals"),
            ));
        }
        let (nperseg, noverlap, nfft) = geometry(&settings, settings.nperseg)?;
        let engine = Engine::new(&settings.window, nperseg, noverlap, nfft)?;
        let nb = engine.n_bins();
        let zero = Complex64::new(0.0, 0.0);
        Ok(WelchStream {
            settings,
            engine,
            pairs: pairs.to_vec(),
            bufs: vec![Vec::new(); k],
            specs: vec![vec![zero; nb]; k],
            auto: vec![vec![0.0; nb]; k],
            cross: vec![vec![zero; nb]; pairs.len()],
            n_segments: 0,
        })
    }

    /// Segments completed so far.
    pub fn n_segments(&self) -> usize {
        self.n_segments
    }

    /// Feeds the next samples of every signal (equal lengths).
    ///
    /// # Errors
    /// [`DspError::LengthMismatch`] for pieces of different lengths or a
    /// wrong number of them; [`DspError::NonFinite`] for a non-finite sample.
    pub fn push(&mut self, pieces: &[&[f64]]) -> Result<()> {
        let m = pieces.first().map_or(0, |p| p.len());
        if pieces.len() != self.bufs.len() || pieces.iter().any(|p| p.len() != m) {
            return Err(DspError::LengthMismatch {
                what: "pieces (WelchStream::push)",
                expected: self.bufs.len(),
                found: pieces.len(),
            });
        }
        let (nperseg, step) = (
            self.engine.nperseg,
            self.engine.nperseg - self.engine.noverlap,
        );
        let mut at = 0;
        while at < m {
            // Only as much as completes the next segment, so a buffer never
            // holds more than one segment.
            let need = nperseg - self.bufs[0].len();
            let to = (at + need).min(m);
            for (b, p) in self.bufs.iter_mut().zip(pieces) {
                check_finite("signal", &p[at..to])?;
                b.extend_from_slice(&p[at..to]);
            }
            at = to;
            if self.bufs[0].len() == nperseg {
                self.segment();
                for b in &mut self.bufs {
                    b.drain(..step);
                }
            }
        }
        Ok(())
    }

    /// Adds the segment at the start of the buffers, as
    /// `Engine::set` adds each of its segments.
    fn segment(&mut self) {
        let detrend = self.settings.detrend;
        for (x, spec) in self.bufs.iter().zip(self.specs.iter_mut()) {
            self.engine.segment_fft(x, 0, detrend, false);
            spec.copy_from_slice(&self.engine.spec_x);
        }
        for (acc, spec) in self.auto.iter_mut().zip(&self.specs) {
            acc.iter_mut()
                .zip(spec)
                .for_each(|(a, c)| *a += c.norm_sqr());
        }
        for (acc, &(i, j)) in self.cross.iter_mut().zip(&self.pairs) {
            for ((s, a), b) in acc.iter_mut().zip(&self.specs[i]).zip(&self.specs[j]) {
                s.re += a.re * b.re + a.im * b.im;
                s.im += a.re * b.im - a.im * b.re;
            }
        }
        self.n_segments += 1;
    }

    /// The spectra at sampling rate `fs_hz`.
    ///
    /// # Errors
    /// [`DspError::TooShort`] when no segment was completed;
    /// [`DspError::InvalidSetting`] for a bad `fs_hz`.
    pub fn finish(self, fs_hz: f64) -> Result<SpectralSet> {
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(invalid(
                "fs_hz",
                format!("must be finite and positive, got {fs_hz}"),
            ));
        }
        if self.n_segments == 0 {
            return Err(DspError::TooShort {
                what: "signals (one Welch segment)",
                needed: self.engine.nperseg,
                found: self.bufs.first().map_or(0, Vec::len),
            });
        }
        let s = &self.settings;
        let nfft = self.engine.nfft;
        let fac = self.engine.bin_factors(fs_hz, s.scaling, s.onesided);
        let inv = 1.0 / self.n_segments as f64;
        let auto = self
            .auto
            .into_iter()
            .map(|acc| {
                let p: Vec<f64> = acc.iter().zip(&fac).map(|(a, f)| a * f * inv).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, nfft, |v| v)
                }
            })
            .collect();
        let cross = self
            .cross
            .into_iter()
            .map(|acc| {
                let p: Vec<Complex64> = acc.iter().zip(&fac).map(|(a, f)| a * (f * inv)).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, nfft, |v| v.conj())
                }
            })
            .collect();
        Ok(SpectralSet {
            freq_hz: self.engine.freqs(fs_hz, s.onesided),
            auto,
            cross,
            n_segments: self.n_segments,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_noise::noise;
    use crate::Welch;

    #[test]
    fn pieces_give_the_whole_signal_spectra_to_the_bit() {
        let n = 10_000;
        let (x, y, z) = (noise(n, 1), noise(n, 2), noise(n, 3));
        let pairs = [(0, 1), (0, 2), (1, 2)];
        for (nperseg, noverlap, onesided) in [
            (256, None, true),
            (500, Some(100), true),
            (300, None, false),
        ] {
            let settings = WelchSettings {
                nperseg,
                noverlap,
                onesided,
                ..WelchSettings::default()
            };
            let whole = Welch::new(settings.clone())
                .unwrap()
                .spectra(&[&x, &y, &z], &pairs, 50.0)
                .unwrap();
            for piece in [1, 97, 1000, n] {
                let mut w = WelchStream::new(settings.clone(), 3, &pairs).unwrap();
                for ((a, b), c) in x.chunks(piece).zip(y.chunks(piece)).zip(z.chunks(piece)) {
                    w.push(&[a, b, c]).unwrap();
                }
                assert_eq!(w.finish(50.0).unwrap(), whole, "{nperseg} {piece}");
            }
        }
        let w = WelchStream::new(WelchSettings::default(), 1, &[]).unwrap();
        assert!(w.finish(1.0).is_err());
        let median = WelchSettings {
            average: Average::Median,
            ..WelchSettings::default()
        };
        assert!(WelchStream::new(median, 1, &[]).is_err());
    }
}
