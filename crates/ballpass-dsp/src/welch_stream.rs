//! Welch auto- and cross-spectra of signals that arrive in pieces, in
//! memory that does not grow with their length.
//!
//! [`WelchStream`] holds less than one segment of each signal: as soon as
//! a segment is complete it is transformed, its products are added to the
//! sums, and the samples no later segment needs are dropped. The segments,
//! their order and every operation on them are those of
//! [`Welch::spectra`](crate::Welch::spectra) with mean averaging, so the
//! result equals it to the bit however the signals are cut into pieces.
//!
//! [`WelchStream::with_groups`] also sums the same segment transforms into
//! groups (segment `j` into group `j mod G`): the parts of the estimate
//! that a delete-a-group jackknife leaves out one at a time, at the price
//! of a few additions per segment instead of a second transform.

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
    groups: Option<Groups>,
}

/// The raw sums of [`WelchStream::with_groups`]: per group, per signal
/// (pair), the first `bins` bins.
struct Groups {
    bins: usize,
    auto: Vec<Vec<Vec<f64>>>,
    cross: Vec<Vec<Vec<Complex64>>>,
    segments: Vec<usize>,
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
            groups: None,
        })
    }

    /// The same stream, also summing the segments into `groups` groups
    /// (segment `j`, counted from 0, into group `j mod groups`) over the
    /// first `bins` bins, the lowest non-negative frequencies (fewer if a
    /// one-sided spectrum has fewer):
    /// [`WelchStream::finish_with_groups`] returns them.
    ///
    /// # Errors
    /// [`DspError::InvalidSetting`] for `groups == 0` or after the first
    /// sample was pushed.
    pub fn with_groups(mut self, groups: usize, bins: usize) -> Result<WelchStream> {
        if groups == 0 {
            return Err(invalid("groups", "must be at least 1"));
        }
        if self.n_segments > 0 || self.bufs.iter().any(|b| !b.is_empty()) {
            return Err(invalid("groups", "must be set before the first sample"));
        }
        let bins = bins.min(self.engine.n_bins());
        let zero = Complex64::new(0.0, 0.0);
        self.groups = Some(Groups {
            bins,
            auto: vec![vec![vec![0.0; bins]; self.auto.len()]; groups],
            cross: vec![vec![vec![zero; bins]; self.cross.len()]; groups],
            segments: vec![0; groups],
        });
        Ok(self)
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
        if let Some(g) = &mut self.groups {
            let k = self.n_segments % g.segments.len();
            let bins = g.bins;
            for (acc, spec) in g.auto[k].iter_mut().zip(&self.specs) {
                acc.iter_mut()
                    .zip(&spec[..bins])
                    .for_each(|(a, c)| *a += c.norm_sqr());
            }
            for (acc, &(i, j)) in g.cross[k].iter_mut().zip(&self.pairs) {
                for ((s, a), b) in acc.iter_mut().zip(&self.specs[i]).zip(&self.specs[j]) {
                    s.re += a.re * b.re + a.im * b.im;
                    s.im += a.re * b.im - a.im * b.re;
                }
            }
            g.segments[k] += 1;
        }
        self.n_segments += 1;
    }

    /// The spectra at sampling rate `fs_hz`.
    ///
    /// # Errors
    /// [`DspError::TooShort`] when no segment was completed;
    /// [`DspError::InvalidSetting`] for a bad `fs_hz`.
    pub fn finish(self, fs_hz: f64) -> Result<SpectralSet> {
        self.finish_with_groups(fs_hz).map(|(set, _)| set)
    }

    /// The spectra at sampling rate `fs_hz` and, after
    /// [`WelchStream::with_groups`], each group's part of them: its
    /// segments' sum scaled as the estimate is (over every segment of the
    /// stream, so the parts add up to the estimate, to rounding), on its
    /// first group bins, the lowest non-negative frequencies (`freq_hz`
    /// those bins' frequencies, `n_segments` the group's segments). Empty
    /// without groups.
    ///
    /// # Errors
    /// As [`WelchStream::finish`].
    pub fn finish_with_groups(self, fs_hz: f64) -> Result<(SpectralSet, Vec<SpectralSet>)> {
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
        let groups = self.groups.map_or_else(Vec::new, |g| {
            let freq: Vec<f64> = self.engine.freqs(fs_hz, s.onesided)[..g.bins].to_vec();
            let scale_auto = |acc: Vec<f64>| -> Vec<f64> {
                acc.iter().zip(&fac).map(|(a, f)| a * f * inv).collect()
            };
            let scale_cross = |acc: Vec<Complex64>| -> Vec<Complex64> {
                acc.iter().zip(&fac).map(|(a, f)| a * (f * inv)).collect()
            };
            g.auto
                .into_iter()
                .zip(g.cross)
                .zip(g.segments)
                .map(|((auto, cross), n_segments)| SpectralSet {
                    freq_hz: freq.clone(),
                    auto: auto.into_iter().map(scale_auto).collect(),
                    cross: cross.into_iter().map(scale_cross).collect(),
                    n_segments,
                })
                .collect()
        });
        let set = SpectralSet {
            freq_hz: self.engine.freqs(fs_hz, s.onesided),
            auto,
            cross,
            n_segments: self.n_segments,
        };
        Ok((set, groups))
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
    /// The groups are the same segments summed apart: in pieces or whole
    /// they are equal to the bit, the estimate is unchanged by them, and
    /// they add up to it (to rounding: 1e-13 of the bin's value, sums of
    /// about 40 terms).
    #[test]
    fn groups_add_up_to_the_estimate_and_leave_it_unchanged() {
        let n = 10_000;
        let (x, y) = (noise(n, 4), noise(n, 5));
        let settings = WelchSettings {
            nperseg: 500,
            ..WelchSettings::default()
        };
        let plain = Welch::new(settings.clone())
            .unwrap()
            .spectra(&[&x, &y], &[(0, 1)], 50.0)
            .unwrap();
        let run = |piece: usize| {
            let mut w = WelchStream::new(settings.clone(), 2, &[(0, 1)])
                .unwrap()
                .with_groups(3, 40)
                .unwrap();
            for (a, b) in x.chunks(piece).zip(y.chunks(piece)) {
                w.push(&[a, b]).unwrap();
            }
            w.finish_with_groups(50.0).unwrap()
        };
        let (set, groups) = run(n);
        assert_eq!(set, plain);
        assert_eq!(run(97), (set.clone(), groups.clone()));
        // 39 segments: 13 in each group.
        assert_eq!(
            groups.iter().map(|g| g.n_segments).collect::<Vec<_>>(),
            [13; 3]
        );
        for k in 0..40 {
            assert_eq!(groups[0].freq_hz[k], set.freq_hz[k]);
            for s in 0..2 {
                let sum: f64 = groups.iter().map(|g| g.auto[s][k]).sum();
                assert!(
                    (sum - set.auto[s][k]).abs() <= 1e-13 * set.auto[s][k],
                    "{s} {k}"
                );
            }
            let sum: Complex64 = groups.iter().map(|g| g.cross[0][k]).sum();
            assert!(
                (sum - set.cross[0][k]).norm() <= 1e-13 * set.cross[0][k].norm(),
                "{k}"
            );
        }
        let started = {
            let mut w = WelchStream::new(settings.clone(), 2, &[(0, 1)]).unwrap();
            w.push(&[&x[..10], &y[..10]]).unwrap();
            w
        };
        assert!(started.with_groups(3, 40).is_err());
        let w = WelchStream::new(settings, 2, &[(0, 1)]).unwrap();
        assert!(w.with_groups(0, 40).is_err());
    }
}
