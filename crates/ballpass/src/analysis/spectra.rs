//! Step 4: full-range and high-resolution spectra.
//!
//! # Spectra
//! Full range: `welch`/`csd` of the step-2 signals (window, `nperseg`
//! capped at `N`, `noverlap` default `nperseg/2`, per-segment mean removal,
//! density), coherence `|Pxy|^2 / (Pxx Pyy)` from the same estimates (what
//! `scipy.signal.coherence` computes).
//!
//! High resolution (default): `x_d = decimate(x, q)` (Chebyshev I, order 8,
//! 0.05 dB, cut at `0.8 fs/(2q)`, zero phase) with `q = floor(fs / (2.5
//! f_lp))` (without low-pass: `f_lp` replaced by `2 (K+1) f_c`), so the cut
//! sits at or above the low-pass; Welch at `fs/q` with
//! `nperseg = min(smooth(6 (fs/q) / f_c), N_d)`, where `smooth(x)` is the
//! smallest even `2^a 3^b 5^c >= x`: 6 to 6.75 bins per `f_c`.
//! Six is what the floor beside each line needs: the floor is fitted on
//! the bins of `[0.4, 2.5] f_c` (for `k = 1`) that are more than 1.5 bins
//! from every harmonic, at least five of them, and at 4–5 bins per `f_c`
//! (what a power of two of four periods gave on a third of the records)
//! only three are left and no line could be tested. A resolution coarser
//! than `f_c/4` is a warning, coarser than `f_c/2` an error. The thesis'
//! zoom ([`HiresMethod::PolyphaseZoom`]) averages the branch spectra instead.
//!
//! The tests for lines at `f_c` and its harmonics are in [`super::harmonics`].

use ballpass_dsp::{
    polyphase_average_csd, polyphase_average_psd, Complex64, DecimateSettings, Decimator, Welch,
    WelchSettings,
};
use serde::Serialize;

use super::correlation::pairs_for;
use super::preprocess::Prepared;
use super::{pair_name, AnalyzeSettings, HiresMethod, Signal};
use crate::error::{Error, Result};
use crate::stats::welch_dof;

/// Parameters of one spectrum estimate, as resolved on the records.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SpectrumInfo {
    /// `welch`, `decimate+welch`, or `polyphase_zoom` (thesis method).
    pub method: String,
    /// Sampling rate the Welch estimate runs at, Hz.
    pub fs_hz: f64,
    /// Decimation factor (`q`, or `M` for the zoom; 1 for full range).
    pub decimation: usize,
    /// Samples per segment.
    pub nperseg: usize,
    /// Overlap, samples.
    pub noverlap: usize,
    /// Segments averaged per record (per branch for the zoom).
    pub n_segments: usize,
    /// Records averaged.
    pub n_records: usize,
    /// Bin spacing `fs / nperseg`, Hz.
    pub resolution_hz: f64,
    /// Equivalent chi-square degrees of freedom of one bin (all records).
    pub dof: f64,
    /// Window name.
    pub window: String,
    /// Chi-square confidence band of the auto-spectra at
    /// `band_confidence` (see [`super::confidence`]); `None` without
    /// degrees of freedom.
    pub band: Option<super::confidence::PsdBand>,
    /// Coherence two independent signals exceed with the probability the
    /// coherence table tests at (see [`super::confidence`]); `None` with
    /// fewer than two equivalent segments.
    pub coherence_threshold: Option<f64>,
}

/// Auto- and cross-spectra and coherence of one record or of the average.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Spectra {
    /// Parameters.
    pub info: SpectrumInfo,
    /// Bin frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Auto-spectra (one-sided density, unit²/Hz).
    pub auto: Vec<(Signal, Vec<f64>)>,
    /// Cross spectra `conj(X) Y` and coherence of the cross pairs.
    pub cross: Vec<CrossSpectrum>,
}

/// One cross pair's spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSpectrum {
    /// `x` of `conj(X) Y`.
    pub x: Signal,
    /// `y` of `conj(X) Y`.
    pub y: Signal,
    /// Cross spectral density.
    pub pxy: Vec<Complex64>,
    /// Magnitude-squared coherence.
    pub coherence: Vec<f64>,
}

impl Spectra {
    /// The auto-spectrum of a signal, if present.
    pub fn auto_of(&self, s: Signal) -> Option<&[f64]> {
        self.auto
            .iter()
            .find(|(k, _)| *k == s)
            .map(|(_, v)| v.as_slice())
    }

    /// The cross spectrum of a pair, if present.
    pub fn cross_of(&self, x: Signal, y: Signal) -> Option<&CrossSpectrum> {
        self.cross.iter().find(|c| c.x == x && c.y == y)
    }

    /// Index of the bin nearest `f_hz`.
    pub fn nearest_bin(&self, f_hz: f64) -> Option<usize> {
        let df = self.freq_hz.get(1)? - self.freq_hz[0];
        let i = (f_hz / df).round();
        (i >= 0.0 && (i as usize) < self.freq_hz.len()).then_some(i as usize)
    }

    /// Recomputes every coherence from the (averaged) auto and cross spectra.
    pub(crate) fn refresh_coherence(&mut self) {
        for c in &mut self.cross {
            let px = &self
                .auto
                .iter()
                .find(|(k, _)| *k == c.x)
                .expect("x present")
                .1;
            let py = &self
                .auto
                .iter()
                .find(|(k, _)| *k == c.y)
                .expect("y present")
                .1;
            c.coherence = c
                .pxy
                .iter()
                .zip(px.iter().zip(py))
                .map(|(p, (a, b))| p.norm_sqr() / a / b)
                .collect();
        }
    }
}

/// The resolved high-resolution plan for one record length.
#[derive(Debug, Clone)]
pub(crate) struct HiresPlan {
    pub q: usize,
    pub fs_hz: f64,
    pub nperseg: usize,
    pub noverlap: usize,
    pub decimator: Option<Decimator>,
    pub zoom: bool,
}

/// The high-resolution segment in ball-pass periods (module docs).
const HIRES_PERIODS: f64 = 6.0;

/// Smallest even `2^a 3^b 5^c >= x` (x > 0): a length the FFT handles at
/// the speed of a power of two.
fn next_smooth(x: f64) -> usize {
    let mut best = usize::MAX;
    let mut p2 = 2usize;
    loop {
        let mut p3 = p2;
        loop {
            let mut n = p3;
            while (n as f64) < x {
                n *= 5;
            }
            best = best.min(n);
            if (p3 as f64) >= x {
                break;
            }
            p3 *= 3;
        }
        if (p2 as f64) >= x {
            break;
        }
        p2 *= 2;
    }
    best
}

/// Resolves `q`, the segment length and the decimator; warns or errors when
/// `f_c` cannot be resolved.
pub(crate) fn plan_hires(
    settings: &AnalyzeSettings,
    fs_hz: f64,
    n: usize,
    f_c_hz: f64,
    warnings: &mut Vec<String>,
) -> Result<HiresPlan> {
    let (q, zoom) = match settings.hires {
        HiresMethod::PolyphaseZoom { m } => (m, true),
        HiresMethod::Decimate => {
            let band = settings
                .lowpass_hz
                .unwrap_or(2.0 * (settings.harmonics + 1) as f64 * f_c_hz);
            let q = settings
                .hires_q
                .unwrap_or_else(|| ((fs_hz / (2.5 * band)).floor() as usize).max(1));
            (q, false)
        }
    };
    let nd = if zoom { n / q } else { n.div_ceil(q) };
    let fs_d = fs_hz / q as f64;
    let auto_nperseg = next_smooth(HIRES_PERIODS * fs_d / f_c_hz);
    let nperseg = settings.hires_nperseg.unwrap_or(auto_nperseg).min(nd);
    if nperseg < 2 {
        return Err(Error::setting(
            "hires",
            format!("decimation by {q} leaves {nd} samples; too few for a spectrum"),
        ));
    }
    let noverlap = settings.hires_noverlap.unwrap_or(nperseg / 2);
    if noverlap >= nperseg {
        return Err(Error::setting(
            "noverlap-hr",
            format!("must be less than the high-resolution segment ({nperseg}), got {noverlap}"),
        ));
    }
    let res = fs_d / nperseg as f64;
    if res > f_c_hz / 2.0 {
        return Err(Error::setting(
            "hires",
            format!(
                "resolution {res:.4} Hz (fs/q = {fs_d} Hz, {nperseg}-sample segments) is coarser \
                 than f_c/2 = {:.4} Hz: cannot resolve f_c; record longer or lower --lowpass",
                f_c_hz / 2.0
            ),
        ));
    }
    if res > f_c_hz / 4.0 {
        warnings.push(format!(
            "high-resolution spectrum: resolution {res:.4} Hz is coarser than f_c/4 = {:.4} Hz \
             ({nperseg}-sample segments at {fs_d} Hz); harmonics and floors are approximate",
            f_c_hz / 4.0
        ));
    }
    let decimator = if zoom || q < 2 {
        None
    } else {
        Some(
            Decimator::new(DecimateSettings {
                q,
                ..DecimateSettings::default()
            })
            .map_err(|e| Error::dsp("high-resolution decimator", e))?,
        )
    };
    Ok(HiresPlan {
        q,
        fs_hz: fs_d,
        nperseg,
        noverlap,
        decimator,
        zoom,
    })
}

/// Welch settings for a segment length.
pub(crate) fn welch_settings(
    settings: &AnalyzeSettings,
    nperseg: usize,
    noverlap: usize,
) -> WelchSettings {
    WelchSettings {
        window: settings.window.to_dsp(),
        nperseg,
        noverlap: Some(noverlap),
        ..WelchSettings::default()
    }
}

fn info(
    method: &str,
    settings: &AnalyzeSettings,
    fs_hz: f64,
    decimation: usize,
    nperseg: usize,
    noverlap: usize,
    n_segments: usize,
) -> Result<SpectrumInfo> {
    let w = settings
        .window
        .to_dsp()
        .values(nperseg)
        .map_err(|e| Error::dsp("window", e))?;
    Ok(SpectrumInfo {
        method: method.into(),
        fs_hz,
        decimation,
        nperseg,
        noverlap,
        n_segments,
        n_records: 1,
        resolution_hz: fs_hz / nperseg as f64,
        dof: welch_dof(&w, nperseg - noverlap, n_segments),
        window: settings.window.to_dsp().name().into(),
        band: None,
        coherence_threshold: None,
    })
}

/// Cross pairs and their indices into the signals.
pub(crate) type CrossPairs = (Vec<(Signal, Signal)>, Vec<(usize, usize)>);

/// The cross pairs of the signals `present` (in order) and their indices
/// into it.
pub(crate) fn cross_pairs(present: &[Signal]) -> CrossPairs {
    let index = |s: Signal| present.iter().position(|&k| k == s).expect("present");
    let pairs: Vec<(Signal, Signal)> = pairs_for(present)
        .into_iter()
        .filter(|(x, y)| x != y)
        .collect();
    let idx = pairs.iter().map(|&(x, y)| (index(x), index(y))).collect();
    (pairs, idx)
}

/// The [`Spectra`] (no info, no coherence yet) of a Welch set computed for
/// the signals `present` and their [`cross_pairs`].
pub(crate) fn of_set(present: &[Signal], set: ballpass_dsp::SpectralSet) -> Spectra {
    let (pairs, _) = cross_pairs(present);
    let auto = present.iter().copied().zip(set.auto).collect();
    let cross = pairs
        .iter()
        .zip(set.cross)
        .map(|(&(x, y), pxy)| CrossSpectrum {
            x,
            y,
            pxy,
            coherence: Vec::new(),
        })
        .collect();
    Spectra {
        info: SpectrumInfo::default(),
        freq_hz: set.freq_hz,
        auto,
        cross,
    }
}

/// Fills in the parameters of `s` and its coherence.
#[allow(clippy::too_many_arguments)]
pub(crate) fn complete(
    s: &mut Spectra,
    method: &str,
    settings: &AnalyzeSettings,
    fs_hz: f64,
    decimation: usize,
    nperseg: usize,
    noverlap: usize,
    n_segments: usize,
) -> Result<()> {
    s.info = info(
        method, settings, fs_hz, decimation, nperseg, noverlap, n_segments,
    )?;
    s.refresh_coherence();
    Ok(())
}

/// Welch auto/cross spectra of equal-length signals (shared by full and
/// decimated).
fn welch_all<S: AsRef<[f64]>>(
    signals: &[(Signal, S)],
    fs_hz: f64,
    welch: &mut Welch,
) -> Result<(Spectra, usize)> {
    let present: Vec<Signal> = signals.iter().map(|(s, _)| *s).collect();
    let (_, idx) = cross_pairs(&present);
    let xs: Vec<&[f64]> = signals.iter().map(|(_, x)| x.as_ref()).collect();
    // One FFT per signal and segment for all the auto and cross spectra;
    // the same numbers as `psd` per signal and `csd` per pair.
    let set = welch.spectra(&xs, &idx, fs_hz).map_err(|e| {
        Error::dsp(
            format!(
                "Welch spectra of {}",
                present
                    .iter()
                    .map(|s| s.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            e,
        )
    })?;
    let nseg = set.n_segments;
    Ok((of_set(&present, set), nseg))
}

/// Full-range spectra of one prepared record.
pub(crate) fn full(p: &Prepared, settings: &AnalyzeSettings) -> Result<Spectra> {
    full_of(&p.signals, p.fs_hz, p.n, settings)
}

/// The full-range Welch segment and overlap for a record of `n` samples:
/// the settings' segment capped at the record, half of it by default.
///
/// # Errors
/// [`Error::InvalidSetting`] when the overlap is not below the segment.
pub(crate) fn full_segments(settings: &AnalyzeSettings, n: usize) -> Result<(usize, usize)> {
    let nperseg = settings.nperseg.min(n);
    let noverlap = settings.noverlap.unwrap_or(nperseg / 2);
    if noverlap >= nperseg {
        return Err(Error::setting(
            "noverlap",
            format!("must be less than the segment length ({nperseg} after capping at the record), got {noverlap}"),
        ));
    }
    Ok((nperseg, noverlap))
}

/// Full-range spectra of equal-length signals of `n` samples at `fs_hz`
/// (the step-2 signals, or the unfiltered ones).
pub(crate) fn full_of<S: AsRef<[f64]>>(
    signals: &[(Signal, S)],
    fs_hz: f64,
    n: usize,
    settings: &AnalyzeSettings,
) -> Result<Spectra> {
    let (nperseg, noverlap) = full_segments(settings, n)?;
    let mut welch = Welch::new(welch_settings(settings, nperseg, noverlap))
        .map_err(|e| Error::dsp("Welch settings", e))?;
    let (mut s, nseg) = welch_all(signals, fs_hz, &mut welch)?;
    complete(&mut s, "welch", settings, fs_hz, 1, nperseg, noverlap, nseg)?;
    Ok(s)
}

/// High-resolution spectra of one prepared record.
pub(crate) fn hires(p: &Prepared, settings: &AnalyzeSettings, plan: &HiresPlan) -> Result<Spectra> {
    let ws = welch_settings(settings, plan.nperseg, plan.noverlap);
    if plan.zoom {
        let m = plan.q;
        let mut auto = Vec::new();
        let mut freq = Vec::new();
        let mut nseg = 0;
        for (s, x) in &p.signals {
            let r = polyphase_average_psd(x, p.fs_hz, m, &ws)
                .map_err(|e| Error::dsp(format!("zoom PSD of {}", s.name()), e))?;
            freq = r.freq_hz;
            nseg = r.n_segments;
            auto.push((*s, r.pxx));
        }
        let present: Vec<Signal> = p.signals.iter().map(|(s, _)| *s).collect();
        let mut cross = Vec::new();
        for (x, y) in pairs_for(&present).into_iter().filter(|(x, y)| x != y) {
            let c = polyphase_average_csd(
                p.signal(x).expect("present"),
                p.signal(y).expect("present"),
                p.fs_hz,
                m,
                &ws,
            )
            .map_err(|e| Error::dsp(format!("zoom cross spectrum {}", pair_name(x, y)), e))?;
            cross.push(CrossSpectrum {
                x,
                y,
                pxy: c.pxy,
                coherence: Vec::new(),
            });
        }
        let mut s = Spectra {
            info: info(
                "polyphase_zoom",
                settings,
                plan.fs_hz,
                m,
                plan.nperseg,
                plan.noverlap,
                nseg,
            )?,
            freq_hz: freq,
            auto,
            cross,
        };
        s.refresh_coherence();
        return Ok(s);
    }
    let decimated: Vec<(Signal, Vec<f64>)> = match &plan.decimator {
        Some(d) => p
            .signals
            .iter()
            .map(|(s, x)| {
                d.apply(x)
                    .map(|y| (*s, y))
                    .map_err(|e| Error::dsp(format!("decimation of {}", s.name()), e))
            })
            .collect::<Result<_>>()?,
        None => p.signals.clone(),
    };
    let mut welch = Welch::new(ws).map_err(|e| Error::dsp("Welch settings", e))?;
    let (mut s, nseg) = welch_all(&decimated, plan.fs_hz, &mut welch)?;
    complete(
        &mut s,
        "decimate+welch",
        settings,
        plan.fs_hz,
        plan.q,
        plan.nperseg,
        plan.noverlap,
        nseg,
    )?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_rules() {
        let s = AnalyzeSettings::default();
        let mut w = Vec::new();
        // 1 kHz, 20 Hz low-pass, 9 mm/s: q = 20, 6 periods at 50 Hz are
        // 270.4 samples: 288 = 2^5 3^2, 0.174 Hz, 6.4 bins per f_c.
        let p = plan_hires(&s, 1000.0, 30_000, 1.10959, &mut w).unwrap();
        assert_eq!((p.q, p.nperseg, p.noverlap), (20, 288, 144));
        assert!(w.is_empty());
        // 4 s of data at 1 mm/s cannot resolve 0.123 Hz.
        let e = plan_hires(&s, 1000.0, 4000, 0.123288, &mut w)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot resolve f_c"), "{e}");
    }

    /// Every f_c of the domain (0.1–5 Hz at 1 kHz, long records) gets 6 to
    /// 6.75 bins per f_c, the room the floor beside `k = 1` needs (module
    /// docs); four periods to a power of two gave 4 to 8 and fails here.
    #[test]
    fn every_f_c_gets_six_bins() {
        let s = AnalyzeSettings::default();
        for i in 0..400 {
            let f_c = 0.1 * 50f64.powf(i as f64 / 399.0);
            let mut w = Vec::new();
            let p = plan_hires(&s, 1000.0, 10_000_000, f_c, &mut w).unwrap();
            let bins = p.nperseg as f64 * f_c / p.fs_hz;
            assert!((6.0..=6.75).contains(&bins), "f_c {f_c}: {bins} bins");
            assert!(w.is_empty(), "f_c {f_c}: {w:?}");
        }
    }

    /// The smallest even 5-smooth length at or above x, against a brute
    /// force search; every f_c gets 6 to 6.75 bins per f_c above 100
    /// samples (even 5-smooth numbers lie within 12.5 % of each other
    /// there: 128 to 144 is the widest gap).
    #[test]
    fn smooth_segment_lengths() {
        let smooth = |n: usize| {
            let mut m = n;
            for p in [2, 3, 5] {
                while m % p == 0 {
                    m /= p;
                }
            }
            m == 1 && n % 2 == 0
        };
        for x in 1..5000usize {
            let want = (x..).find(|&n| smooth(n)).unwrap();
            assert_eq!(next_smooth(x as f64), want, "{x}");
            assert_eq!(next_smooth(x as f64 - 0.5), want, "{x} - 0.5");
        }
        for i in 0..2000 {
            let x = 100.0 * (1.0f64 + 0.01 * i as f64);
            let r = next_smooth(x) as f64 / x;
            assert!((1.0..=1.125).contains(&r), "{x} -> {r}");
        }
    }
}
