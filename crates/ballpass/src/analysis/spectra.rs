//! Steps 4–5: full-range and high-resolution spectra, harmonics and their
//! significance.
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
//! `nperseg = min(next_pow2(4 (fs/q) / f_c), N_d)`. A resolution coarser
//! than `f_c/4` is a warning, coarser than `f_c/2` an error. The thesis'
//! zoom ([`HiresMethod::PolyphaseZoom`]) averages the branch spectra instead.
//!
//! # Harmonics (chosen here; the brief left the floor window open)
//! At `f = k f_c` (predicted, and measured when there is one):
//!
//! ```text
//! PSD(f)  = max over the bins within ±1 of the bin nearest f
//! floor   = median of the PSD over bins within ±1.5 f_c of f, excluding the
//!           bins within ±1 of every harmonic j f_c (j = 0, 1, 2, ...),
//!           converted to a mean: floor = median / (chi2_ppf(0.5, nu) / nu)
//! ratio   = 10 log10(PSD / floor) dB
//! signif. = PSD > floor * chi2_ppf(p, nu) / nu,   p = confidence^(1/3)
//! ```
//!
//! The window is three ball-pass intervals wide because at the default
//! resolution (`f_c/4 .. f_c/8`) the ±0.5 `f_c` window minus the line's
//! own bins leaves almost nothing. A noise-only Welch bin is distributed
//! as `S chi2_nu / nu` with `nu` the equivalent degrees of freedom of the
//! overlapping windowed segments (Percival & Walden Eq. 292b; Hann at 50 %
//! gives ~1.89 per segment); the exponent `1/3` is the Šidák correction
//! for taking the largest of three bins. Averaging `R` repeats multiplies
//! `nu` by `R`. Leakage of a strong line into its neighbours' skirts (±2
//! bins) can raise the floor: the test errs towards "not significant".
//!
//! Coherence at `k f_c`: the largest of the ±1 bins, significant above
//! `1 - a^(1/(n_d - 1))`, `a = 1 - confidence^(1/3)`, with `n_d = nu/2`
//! the equivalent number of independent segments.

use ballpass_dsp::{
    polyphase_average_csd, polyphase_average_psd, Complex64, DecimateSettings, Decimator, Welch,
    WelchSettings,
};
use serde::Serialize;

use super::correlation::pairs_for;
use super::preprocess::Prepared;
use super::{pair_name, AnalyzeSettings, HiresMethod, Signal};
use crate::error::{Error, Result};
use crate::stats::{chi2_ppf, median, parabolic_peak, welch_dof};

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

/// Next power of two `>= x` (x > 0).
fn next_pow2(x: f64) -> usize {
    let mut n = 1usize;
    while (n as f64) < x {
        n *= 2;
    }
    n
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
    let auto_nperseg = next_pow2(4.0 * fs_d / f_c_hz);
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
    })
}

/// Welch auto/cross spectra of equal-length signals (shared by full and
/// decimated).
fn welch_all(
    signals: &[(Signal, Vec<f64>)],
    fs_hz: f64,
    welch: &mut Welch,
) -> Result<(Spectra, usize)> {
    let present: Vec<Signal> = signals.iter().map(|(s, _)| *s).collect();
    let index = |s: Signal| present.iter().position(|&k| k == s).expect("present");
    let pairs: Vec<(Signal, Signal)> = pairs_for(&present)
        .into_iter()
        .filter(|(x, y)| x != y)
        .collect();
    let idx: Vec<(usize, usize)> = pairs.iter().map(|&(x, y)| (index(x), index(y))).collect();
    let xs: Vec<&[f64]> = signals.iter().map(|(_, x)| x.as_slice()).collect();
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
    Ok((
        Spectra {
            info: SpectrumInfo::default(),
            freq_hz: set.freq_hz,
            auto,
            cross,
        },
        set.n_segments,
    ))
}

/// Full-range spectra of one prepared record.
pub(crate) fn full(p: &Prepared, settings: &AnalyzeSettings) -> Result<Spectra> {
    full_of(&p.signals, p.fs_hz, p.n, settings)
}

/// Full-range spectra of equal-length signals of `n` samples at `fs_hz`
/// (the step-2 signals, or the unfiltered ones).
pub(crate) fn full_of(
    signals: &[(Signal, Vec<f64>)],
    fs_hz: f64,
    n: usize,
    settings: &AnalyzeSettings,
) -> Result<Spectra> {
    let nperseg = settings.nperseg.min(n);
    let noverlap = settings.noverlap.unwrap_or(nperseg / 2);
    if noverlap >= nperseg {
        return Err(Error::setting(
            "noverlap",
            format!("must be less than the segment length ({nperseg} after capping at the record), got {noverlap}"),
        ));
    }
    let mut welch = Welch::new(welch_settings(settings, nperseg, noverlap))
        .map_err(|e| Error::dsp("Welch settings", e))?;
    let (mut s, nseg) = welch_all(signals, fs_hz, &mut welch)?;
    s.info = info("welch", settings, fs_hz, 1, nperseg, noverlap, nseg)?;
    s.refresh_coherence();
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
    s.info = info(
        "decimate+welch",
        settings,
        plan.fs_hz,
        plan.q,
        plan.nperseg,
        plan.noverlap,
        nseg,
    )?;
    s.refresh_coherence();
    Ok(s)
}

/// The spectrum at one frequency against its local floor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HarmonicValue {
    /// Frequency examined, Hz.
    pub f_hz: f64,
    /// Frequency of the bin holding the maximum, Hz.
    pub bin_f_hz: f64,
    /// PSD, the largest of the ±1 bins, unit²/Hz.
    pub psd: f64,
    /// Local noise floor (mean-equivalent), unit²/Hz.
    pub floor: Option<f64>,
    /// Bins the floor's median was taken over.
    pub floor_bins: usize,
    /// `10 log10(psd / floor)`, dB.
    pub ratio_db: Option<f64>,
    /// Ratio the PSD must exceed at the stated confidence, dB.
    pub threshold_db: Option<f64>,
    /// Whether the PSD stands above the floor at the stated confidence.
    pub significant: Option<bool>,
}

/// One harmonic of one signal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HarmonicRow {
    /// Signal.
    pub signal: Signal,
    /// Harmonic number `k`.
    pub k: usize,
    /// At `k f_c` predicted.
    pub predicted: Option<HarmonicValue>,
    /// At `k f_c` measured.
    pub measured: Option<HarmonicValue>,
}

/// Coherence of one pair at one harmonic.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CoherenceRow {
    /// Pair name.
    pub pair: String,
    /// Harmonic number.
    pub k: usize,
    /// Frequency examined (measured `k f_c` when there is one), Hz.
    pub f_hz: f64,
    /// Coherence, largest of the ±1 bins.
    pub coherence: f64,
    /// Threshold at the stated confidence (`None` with fewer than two
    /// equivalent segments).
    pub threshold: Option<f64>,
    /// Whether the coherence exceeds the threshold.
    pub significant: Option<bool>,
}

/// Index and value of the largest of the bins within ±1 of `i`.
fn max_near(v: &[f64], i: usize) -> (usize, f64) {
    let lo = i.saturating_sub(1);
    let hi = (i + 1).min(v.len() - 1);
    (lo..=hi).fold((i, f64::NEG_INFINITY), |(bi, bv), j| {
        if v[j] > bv {
            (j, v[j])
        } else {
            (bi, bv)
        }
    })
}

/// Chi-square ratios for one spectrum's degrees of freedom.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Quantiles {
    /// `chi2_ppf(0.5, nu) / nu`: median of a noise bin over its mean.
    median_ratio: f64,
    /// `chi2_ppf(confidence^(1/3), nu) / nu`: the significance threshold.
    threshold_ratio: f64,
}

impl Quantiles {
    pub(crate) fn new(nu: f64, confidence: f64) -> Option<Quantiles> {
        (nu > 0.0).then(|| Quantiles {
            median_ratio: chi2_ppf(0.5, nu) / nu,
            threshold_ratio: chi2_ppf(confidence.powf(1.0 / 3.0), nu) / nu,
        })
    }
}

/// The PSD at `f_hz` against its floor (module docs).
pub(crate) fn harmonic_value(
    s: &Spectra,
    psd: &[f64],
    f_hz: f64,
    f_c_hz: f64,
    q: Option<Quantiles>,
) -> Option<HarmonicValue> {
    let i = s.nearest_bin(f_hz)?;
    if i == 0 || i + 1 >= psd.len() {
        return None;
    }
    let df = s.info.resolution_hz;
    let (bi, p) = max_near(psd, i);
    let lo = ((f_hz - 1.5 * f_c_hz) / df).ceil().max(1.0) as usize;
    let hi = (((f_hz + 1.5 * f_c_hz) / df).floor() as usize).min(psd.len() - 1);
    let near_harmonic = |j: usize| {
        let f = j as f64 * df;
        let h = (f / f_c_hz).round();
        (f - h * f_c_hz).abs() <= 1.5 * df
    };
    let bins: Vec<f64> = (lo..=hi)
        .filter(|&j| !near_harmonic(j))
        .map(|j| psd[j])
        .collect();
    let (floor, ratio, thr, sig) = match (median(&bins), q) {
        (Some(m), Some(q)) if bins.len() >= 3 && m > 0.0 => {
            let floor = m / q.median_ratio;
            let thr = q.threshold_ratio;
            let ratio = p / floor;
            (
                Some(floor),
                Some(10.0 * ratio.log10()),
                Some(10.0 * thr.log10()),
                Some(ratio > thr),
            )
        }
        _ => (None, None, None, None),
    };
    Some(HarmonicValue {
        f_hz,
        bin_f_hz: s.freq_hz[bi],
        psd: p,
        floor,
        floor_bins: bins.len(),
        ratio_db: ratio,
        threshold_db: thr,
        significant: sig,
    })
}

/// Harmonic table for every auto-spectrum.
pub(crate) fn harmonics(
    s: &Spectra,
    f_pred: f64,
    f_meas: Option<f64>,
    settings: &AnalyzeSettings,
) -> Vec<HarmonicRow> {
    let q = Quantiles::new(s.info.dof, settings.confidence);
    let mut rows = Vec::new();
    for (sig, psd) in &s.auto {
        for k in 1..=settings.harmonics {
            let kf = k as f64;
            rows.push(HarmonicRow {
                signal: *sig,
                k,
                predicted: harmonic_value(s, psd, kf * f_pred, f_pred, q),
                measured: f_meas.and_then(|f| harmonic_value(s, psd, kf * f, f, q)),
            });
        }
    }
    rows
}

/// Coherence rows for every cross pair and harmonic.
pub(crate) fn coherence_rows(
    s: &Spectra,
    f_c: f64,
    settings: &AnalyzeSettings,
) -> Vec<CoherenceRow> {
    let n_d = s.info.dof / 2.0;
    let a = 1.0 - settings.confidence.powf(1.0 / 3.0);
    let threshold = (n_d > 1.0).then(|| 1.0 - a.powf(1.0 / (n_d - 1.0)));
    let mut rows = Vec::new();
    for c in &s.cross {
        for k in 1..=settings.harmonics {
            let f = k as f64 * f_c;
            let Some(i) = s
                .nearest_bin(f)
                .filter(|&i| i > 0 && i + 1 < c.coherence.len())
            else {
                continue;
            };
            let (_, v) = max_near(&c.coherence, i);
            rows.push(CoherenceRow {
                pair: pair_name(c.x, c.y),
                k,
                f_hz: f,
                coherence: v,
                threshold,
                significant: threshold.map(|t| v > t),
            });
        }
    }
    rows
}

/// The largest PSD within ±25 % of `f_pred`, parabolically interpolated, Hz.
pub(crate) fn spectral_peak(s: &Spectra, psd: &[f64], f_pred: f64) -> Option<f64> {
    let df = s.info.resolution_hz;
    let lo = ((0.75 * f_pred / df).ceil() as usize).max(1);
    let hi = ((1.25 * f_pred / df).floor() as usize).min(psd.len().checked_sub(2)?);
    if lo > hi {
        return None;
    }
    let i = (lo..=hi).max_by(|&a, &b| psd[a].total_cmp(&psd[b]))?;
    let (d, _) = parabolic_peak(psd[i - 1], psd[i], psd[i + 1]);
    Some((i as f64 + d) * df)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn synthetic(noise_only: bool) -> Spectra {
        // Flat PSD of 1 with a line at bin 10 (f_c = 1 Hz, df = 0.1 Hz) and
        // its harmonics, plus a fixed pseudo-random ±20 % ripple.
        let n = 200;
        let df = 0.1;
        let psd: Vec<f64> = (0..n)
            .map(|i| {
                let ripple = 1.0 + 0.2 * (((i * 7919) % 13) as f64 / 6.0 - 1.0);
                let line = if !noise_only && i % 10 == 0 && i > 0 {
                    30.0
                } else {
                    0.0
                };
                ripple + line
            })
            .collect();
        Spectra {
            info: SpectrumInfo {
                resolution_hz: df,
                dof: 20.0,
                ..Default::default()
            },
            freq_hz: (0..n).map(|i| i as f64 * df).collect(),
            auto: vec![(Signal::Optical, psd)],
            cross: vec![],
        }
    }

    #[test]
    fn a_line_is_significant_and_flat_noise_is_not() {
        let s = AnalyzeSettings::default();
        let rows = harmonics(&synthetic(false), 1.0, None, &s);
        assert_eq!(rows.len(), 5);
        for r in &rows {
            let v = r.predicted.as_ref().unwrap();
            assert_eq!(v.significant, Some(true), "{r:?}");
            // 31 over a floor of ~1: about 15 dB.
            assert!(v.ratio_db.unwrap() > 12.0, "{r:?}");
        }
        let rows = harmonics(&synthetic(true), 1.0, None, &s);
        for r in &rows {
            let v = r.predicted.as_ref().unwrap();
            assert_eq!(v.significant, Some(false), "{r:?}");
        }
    }

    #[test]
    fn resolution_rules() {
        let s = AnalyzeSettings::default();
        let mut w = Vec::new();
        // 1 kHz, 20 Hz low-pass, 9 mm/s: q = 20, 256 samples, 0.195 Hz.
        let p = plan_hires(&s, 1000.0, 30_000, 1.10959, &mut w).unwrap();
        assert_eq!((p.q, p.nperseg, p.noverlap), (20, 256, 128));
        assert!(w.is_empty());
        // 4 s of data at 1 mm/s cannot resolve 0.123 Hz.
        let e = plan_hires(&s, 1000.0, 4000, 0.123288, &mut w)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cannot resolve f_c"), "{e}");
    }
}
