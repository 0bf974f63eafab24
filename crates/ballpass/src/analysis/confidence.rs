//! Confidence on spectra: chi-square intervals of the Welch PSDs and the
//! significance level of the coherence.
//!
//! # PSD bands
//!
//! A bin of a Welch estimate `P̂(f)` of Gaussian noise whose spectrum
//! `S(f)` is smooth over the window's bandwidth is distributed as
//! `S(f) χ²_ν / ν`, with `ν` the equivalent degrees of freedom of the
//! average of `K` overlapping windowed segments (Welch 1967; Percival &
//! Walden 1993, Eq. 292b; [`crate::stats::welch_dof`]):
//!
//! ```text
//! h      = w / sqrt(sum w²)
//! ρ(j)   = (sum_t h[t] h[t + j·step])²          (window overlap correlation)
//! ν      = 2K / (1 + 2 sum_{j=1}^{K-1} (1 − j/K) ρ(j))
//! band   = [ν P̂ / χ²_ν(1 − α/2),  ν P̂ / χ²_ν(α/2)],   α = 1 − confidence
//! ```
//!
//! `R` averaged records multiply `ν` by `R`. The DC and Nyquist bins are
//! real-valued (χ²_1 per segment) and carry `ν/2`. Rectangular segments
//! without overlap give `ν = 2K`; periodic Hann at 50 % has `ρ(1) = 1/36`
//! and `ρ(j ≥ 2) = 0`, so `ν = 2K / (1 + (K−1)/(18K))` (→ `1.895 K`).
//!
//! MATLAB's `pwelch(..., 'ConfidenceLevel', p)` gives the same interval
//! form but with `ν = 2K` (its `chi2conf(p, K)`), whatever the window and
//! overlap; for Hann at 50 % its band is therefore slightly too narrow (ν
//! about 5 % too large). ballpass accounts for the overlap.
//!
//! # Coherence significance
//!
//! For two independent Gaussian signals and `n` independent segments the
//! magnitude-squared coherence estimate has `P(C > c) = (1 − c)^(n−1)`
//! (Carter 1987, Eq. 39), so the level that noise exceeds with probability
//! `a` is `1 − a^(1/(n−1))`. Overlapping segments are not independent, and
//! how many independent ones they are worth depends on what the two
//! channels hold:
//!
//! - noise in both: the cross spectrum's noise is a product of the two
//!   channels' noises, shared between segments by `c(m)²` (the window's
//!   overlap correlation squared): Welch's `n = ν/2`;
//! - a line in one channel (the optical pulses always have one at `k f_c`;
//!   friction without ripple has none) and noise in the other: the noise
//!   enters the cross spectrum linearly, shared by `c(m)` itself, turned
//!   against the line's phasor by the offset `δ` (bins) between the line and
//!   the bin: `n = K / (1 + 2 Σ (1 − m/K) c(m) cos(2π m δ · step / nperseg))`
//!   (`super::phase::line_segments_turned`); Hann at 50 % gives `0.75 K`
//!   on the line's bin, `K` half a bin off, `1.5 K` a bin off.
//!
//! A bin is counted as the smaller of the two (`R` averaged records
//! multiply both by `R`; [`coherence_segments`]). Carter's law at such a
//! count is only an approximation for the line case, heavier than the truth
//! on the line's bin at few segments (seven times at three segments), so a
//! coherence row is tested on exact tails instead: a row at `k f_c` takes
//! the largest of the three bins nearest `k f_c` and is significant above
//! the `c` at which the three bins' tails add up to `a`
//! ([`coherence_row_level`]), each bin's tail the larger of
//!
//! - noise in both: Carter's `(1 − c)^(ν/2 − 1)`;
//! - a line in one channel: the exact tail of `|uᴴY|²/(YᴴY)` for the noise
//!   channel's correlated segment DFTs `Y` and the line's phasors `u`, at
//!   the bin's offset from the line (`line_tail`: one positive eigenvalue
//!   of a quadratic form, found with a banded Cholesky factor); above 512
//!   segments per record Carter's at the line's count, which it approaches.
//!
//! Noise exceeds the row's level with probability at most `a` whichever
//! null holds (the larger tail per bin, the sum over bins). The analysis
//! tests three pairs at each harmonic, so each row at `a = 1 −
//! confidence^(1/3)` (Šidák): at most `1 − confidence` for the three pairs
//! at one harmonic together, `a` (0.33 % at 99 %) per row. Seeded
//! simulations of the null with the estimator's own segmenting (Hann, 50 %,
//! 3–150 segments, a line in one channel 0–0.5 bin from the grid, strong or
//! about as strong as the noise in its bin, or noise in both) gave
//! 0.13–0.31 % per row at a = 0.33 %; session 17's rule (the middle bin's
//! Carter level at `a/3`) gave 0.02–0.31 %, and one bin's level at `ν/2`
//! 0.6–1.1 % (two to three times its nominal rate).
//!
//! The coherence figure draws the level of a row whose line falls on a bin
//! (the highest in our checks); rows between bins have lower levels, each
//! stated in its row
//! (`coherence` in `analysis.json`).

use serde::Serialize;

use super::export::{product_token, psd_column};
use super::spectra::SpectrumInfo;
use super::{AnalyzeSettings, Signal, Spectra};
use crate::stats::chi2_ppf;
use std::f64::consts::TAU;

mod line_tail;
#[cfg(test)]
mod reference;

/// A PSD's confidence band as multipliers of the estimate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PsdBand {
    /// Two-sided confidence of the band (0.95 = 95 %).
    pub confidence: f64,
    /// Equivalent degrees of freedom the band rests on (bins between DC and
    /// Nyquist; those two carry half).
    pub dof: f64,
    /// Lower bound over the estimate, `ν / χ²_ν(1 − α/2)`.
    pub lower_factor: f64,
    /// Upper bound over the estimate, `ν / χ²_ν(α/2)`.
    pub upper_factor: f64,
}

/// Multipliers `[ν / χ²_ν(1 − α/2), ν / χ²_ν(α/2)]` of a chi-square
/// confidence interval at `confidence` for an estimate with `nu` degrees of
/// freedom; `None` unless `nu > 0` and `0 < confidence < 1`.
///
/// ```
/// use ballpass::analysis::confidence::psd_band_factors;
/// // 20 dof at 95 %: scipy.stats.chi2.ppf([0.975, 0.025], 20) = 34.170, 9.591.
/// let [lo, hi] = psd_band_factors(20.0, 0.95).unwrap();
/// assert!((lo - 20.0 / 34.16960690283833).abs() < 1e-12);
/// assert!((hi - 20.0 / 9.590777392264867).abs() < 1e-12);
/// ```
pub fn psd_band_factors(nu: f64, confidence: f64) -> Option<[f64; 2]> {
    if !(nu > 0.0 && nu.is_finite() && confidence > 0.0 && confidence < 1.0) {
        return None;
    }
    let alpha = 1.0 - confidence;
    Some([
        nu / chi2_ppf(1.0 - alpha / 2.0, nu),
        nu / chi2_ppf(alpha / 2.0, nu),
    ])
}

/// The band of a spectrum with `nu` equivalent degrees of freedom.
pub fn psd_band(nu: f64, confidence: f64) -> Option<PsdBand> {
    let [lower_factor, upper_factor] = psd_band_factors(nu, confidence)?;
    Some(PsdBand {
        confidence,
        dof: nu,
        lower_factor,
        upper_factor,
    })
}

/// Coherence that two independent signals exceed with probability `a`
/// when estimated from `nu` equivalent degrees of freedom (`nu/2`
/// equivalent segments): `1 − a^(1/(nu/2 − 1))`; `None` with fewer than
/// two equivalent segments (the coherence is then 1 by construction).
pub fn coherence_level(nu: f64, a: f64) -> Option<f64> {
    carter_level(nu / 2.0, a)
}

/// `1 − a^(1/(n − 1))` for `n` equivalent independent segments; `None`
/// unless `n > 1` and `0 < a < 1`.
fn carter_level(n: f64, a: f64) -> Option<f64> {
    (n > 1.0 && a > 0.0 && a < 1.0).then(|| 1.0 - a.powf(1.0 / (n - 1.0)))
}

/// Equivalent independent segments of the coherence in a bin `offset_bins`
/// from a line at `k f_c` (module docs): the smaller of Welch's `ν/2` and
/// the count for a line in one channel; `w` is the window of
/// `info.nperseg` samples.
pub fn coherence_segments(info: &SpectrumInfo, w: &[f64], offset_bins: f64) -> f64 {
    let n_power = 0.5 * info.dof;
    let Some(step) = info.nperseg.checked_sub(info.noverlap).filter(|&s| s > 0) else {
        return n_power;
    };
    let theta = std::f64::consts::TAU * offset_bins * step as f64 / info.nperseg as f64;
    let n_line = info.n_records.max(1) as f64
        * super::phase::line_segments_turned(w, step, info.n_segments, theta);
    n_power.min(n_line)
}

/// The level a coherence row at `offset_bins` (the line's offset from the
/// bin nearest it, `|δ| ≤ ½`) tests against (module docs): the `c` at which
/// the three bins' null tails sum to `a = 1 − confidence^(1/3)`, each bin's
/// tail the larger of the noise-in-both one (Carter at Welch's `ν/2`) and
/// the exact one of a line in one channel (`line_tail`; Carter
/// at the line's equivalent count beyond
/// 512 segments per record). `None` with `ν/2 ≤ 1` or
/// without a window of `info.nperseg` samples.
pub fn coherence_row_level(
    info: &SpectrumInfo,
    w: &[f64],
    offset_bins: f64,
    confidence: f64,
) -> Option<f64> {
    let a = coherence_row_rate(confidence);
    let n_power = 0.5 * info.dof;
    if !(n_power > 1.0 && a > 0.0 && a < 1.0 && w.len() == info.nperseg) {
        return None;
    }
    let step = info.nperseg.checked_sub(info.noverlap).filter(|&s| s > 0);
    let k = info.n_segments.max(1);
    let r = info.n_records.max(1);
    let corr = step.map(|st| line_tail::overlap_correlations(w, st, k));
    let turn = |d: f64| step.map_or(0.0, |st| TAU * d * st as f64 / info.nperseg as f64);
    let exact = k <= line_tail::EXACT_MAX_SEGMENTS;
    // Per bin: the line's equivalent count and its exact tail (which keeps
    // its last root to start the next level's search from).
    let mut bins: Vec<(f64, Option<line_tail::LineTail>)> =
        [offset_bins + 1.0, offset_bins, offset_bins - 1.0]
            .iter()
            .map(|&d| {
                let n_line = match step {
                    Some(st) => r as f64 * super::phase::line_segments_turned(w, st, k, turn(d)),
                    None => n_power,
                };
                let exact = corr
                    .as_ref()
                    .filter(|_| exact)
                    .map(|corr| line_tail::LineTail::new(corr, k, r, turn(d)));
                (n_line, exact)
            })
            .collect();
    // The three bins' tails summed at x = ln(1 − c).
    let tail = |x: f64| -> f64 {
        let c = -x.exp_m1();
        bins.iter_mut()
            .map(|(n_line, exact)| {
                let noise = ((n_power - 1.0) * x).exp();
                let line = match exact {
                    Some(t) => t.tail(c).unwrap_or_else(|| ((*n_line - 1.0) * x).exp()),
                    None => ((n_line.max(1.0) - 1.0) * x).exp(),
                };
                noise.max(line)
            })
            .sum()
    };
    level_of_tail(tail, a, n_power)
}

/// The level `c` at which a falling tail reaches `a`: solves
/// `ln tail(x) = ln a` for `x = ln(1 − c) < 0` (the tail falls from 3 at
/// `x = 0`; Carter's tails are straight lines in `x`, the exact ones nearly
/// so) by bracketing from `ln a / (n_power − 1)`, then Illinois false
/// position on `ln tail`. `None` when no bracket is found.
pub(super) fn level_of_tail(mut tail: impl FnMut(f64) -> f64, a: f64, n_power: f64) -> Option<f64> {
    let mut phi = |x: f64| tail(x).ln() - a.ln();
    let (mut hi, mut f_hi) = (0.0, phi(0.0));
    let mut lo = a.ln() / (n_power - 1.0);
    let mut f_lo = phi(lo);
    while f_lo > 0.0 {
        (hi, f_hi) = (lo, f_lo);
        lo *= 2.0;
        f_lo = phi(lo);
        if lo < -1e4 {
            return None;
        }
    }
    let mut side = 0i8;
    for _ in 0..100 {
        let x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let f = phi(x);
        if f.abs() < 1e-12 || (hi - lo).abs() < 1e-14 * lo.abs() {
            lo = x;
            break;
        }
        if f > 0.0 {
            (hi, f_hi) = (x, f);
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        } else {
            (lo, f_lo) = (x, f);
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        }
    }
    Some(-lo.exp_m1())
}

/// The nominal false-alarm rate of one coherence row, `1 − confidence^(1/3)`
/// (module docs).
pub fn coherence_row_rate(confidence: f64) -> f64 {
    1.0 - confidence.powf(1.0 / 3.0)
}

/// Fills in a spectrum's band and coherence level once its `dof` is final
/// (after the repeats are averaged); the level drawn is a row's with the
/// line on a bin (module docs).
pub(crate) fn finish(s: &mut Spectra, settings: &AnalyzeSettings) {
    s.info.band = psd_band(s.info.dof, settings.band_confidence);
    s.info.coherence_threshold = settings
        .window
        .to_dsp()
        .values(s.info.nperseg)
        .ok()
        .and_then(|w| coherence_row_level(&s.info, &w, 0.0, settings.confidence));
}

/// Band multipliers of bin `i` of `n` (DC and an even-`nperseg` Nyquist
/// bin carry half the degrees of freedom).
fn factors_for_bin(s: &Spectra, band: &PsdBand, i: usize, n: usize) -> [f64; 2] {
    let edge = i == 0 || (s.info.nperseg % 2 == 0 && i + 1 == n);
    if edge {
        psd_band_factors(band.dof / 2.0, band.confidence).unwrap_or([f64::NAN; 2])
    } else {
        [band.lower_factor, band.upper_factor]
    }
}

/// The lower and upper band of one auto-spectrum, bin by bin; `None`
/// without a band.
pub fn band_of(s: &Spectra, psd: &[f64]) -> Option<[Vec<f64>; 2]> {
    let band = s.info.band?;
    let n = psd.len();
    let (mut lo, mut hi) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for (i, p) in psd.iter().enumerate() {
        let [a, b] = factors_for_bin(s, &band, i, n);
        lo.push(a * p);
        hi.push(b * p);
    }
    Some([lo, hi])
}

/// Column names of a signal's band: `psd_friction_lower_n2_per_hz`,
/// `psd_friction_upper_n2_per_hz`.
pub fn band_columns_of(sig: Signal) -> [String; 2] {
    let unit = product_token(sig, sig);
    debug_assert!(psd_column(sig).ends_with(&format!("_{unit}_per_hz")));
    [
        format!("psd_{}_lower_{unit}_per_hz", sig.name()),
        format!("psd_{}_upper_{unit}_per_hz", sig.name()),
    ]
}

/// The band columns of every auto-spectrum (appended after the spectra's
/// other columns in the CSV exports).
pub fn band_columns(s: &Spectra) -> Vec<(String, Vec<f64>)> {
    let mut out = Vec::new();
    for (sig, psd) in &s.auto {
        if let Some([lo, hi]) = band_of(s, psd) {
            let [nl, nh] = band_columns_of(*sig);
            out.push((nl, lo));
            out.push((nh, hi));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::welch_dof;

    /// A periodic Hann window (the child modules' tests use it too).
    pub(super) fn hann(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos())
            .collect()
    }

    /// Analytic equivalent degrees of freedom. Rectangular segments without
    /// overlap are independent: 2K exactly. Rectangular at 50 %: the
    /// normalised overlap at one step is 1/2, so ρ(1) = 1/4 and ρ(j ≥ 2) = 0
    /// (no overlap): ν = 2K / (1 + (1 − 1/K)/2). Periodic Hann at 50 %:
    /// Σ h[t] h[t + N/2] = 1/6 (Σ w[t] w[t+N/2] = N/16 over Σ w² = 3N/8),
    /// ρ(1) = 1/36: ν = 2K / (1 + (1 − 1/K)/18), → 1.895 K.
    #[test]
    fn edof_known_cases() {
        let n = 512;
        let boxcar = vec![1.0; n];
        let w = hann(n);
        for k in [1usize, 2, 3, 7, 10, 100] {
            let kf = k as f64;
            // Tolerance: the overlap sums are exact rationals up to the
            // rounding of 512 products, 1e-12 relative.
            let close = |got: f64, want: f64| (got - want).abs() < 1e-12 * want;
            assert!(close(welch_dof(&boxcar, n, k), 2.0 * kf), "boxcar K={k}");
            let want = 2.0 * kf / (1.0 + (1.0 - 1.0 / kf) / 2.0);
            assert!(
                close(welch_dof(&boxcar, n / 2, k), want),
                "boxcar 50 % K={k}"
            );
            let want = 2.0 * kf / (1.0 + (1.0 - 1.0 / kf) / 18.0);
            let got = welch_dof(&w, n / 2, k);
            assert!(close(got, want), "Hann 50 % K={k}: {got} vs {want}");
        }
    }

    #[test]
    fn band_factors_edges() {
        assert!(psd_band_factors(0.0, 0.95).is_none());
        assert!(psd_band_factors(10.0, 1.0).is_none());
        let [lo, hi] = psd_band_factors(2.0, 0.95).unwrap();
        // χ²_2 is exponential: quantiles −2 ln(1 − p), so the factors are
        // 1/−ln(0.025) and 1/−ln(0.975): exact to rounding.
        assert!((lo - 1.0 / -(0.025f64).ln()).abs() < 1e-12);
        assert!((hi - 1.0 / -(0.975f64).ln()).abs() < 1e-10);
    }

    #[test]
    fn coherence_level_is_carters() {
        // n = 10 segments, a = 0.05: 1 − 0.05^(1/9).
        let c = coherence_level(20.0, 0.05).unwrap();
        assert!((c - (1.0 - 0.05f64.powf(1.0 / 9.0))).abs() < 1e-15);
        assert!(coherence_level(2.0, 0.05).is_none());
    }

    /// Seeded Monte-Carlo coverage: Welch (Hann, 256-sample segments, 50 %
    /// overlap, 15 segments: ν = 28.5) of white noise and of AR(1) noise
    /// `x[n] = 0.6 x[n−1] + e[n]` (true one-sided PSD
    /// `2 σ² / (fs |1 − 0.6 e^{−2πif/fs}|²)`); the 95 % band must cover the
    /// true PSD in 95 % of bins. Every 3rd bin of each of 400 records is
    /// scored (Hann bins 3 apart share no window overlap in frequency beyond
    /// ρ = 1/36², so they are nearly independent): 400 × 42 = 16 800
    /// scores, and the exact 99.9 % binomial interval of the observed rate
    /// must hold 0.95 (its half-width is about ±0.0055).
    #[test]
    fn bands_cover_the_true_psd_at_their_level() {
        use crate::sim::rng::Rng;
        use crate::stats::binomial_interval;
        use ballpass_dsp::{Welch, WelchSettings, Window};
        let (nperseg, k) = (256usize, 15usize);
        let n = nperseg / 2 * (k + 1);
        let fs = 100.0;
        let mut welch = Welch::new(WelchSettings {
            window: Window::Hann,
            nperseg,
            ..WelchSettings::default()
        })
        .unwrap();
        let nu = welch_dof(&hann(nperseg), nperseg / 2, k);
        let [lo_f, hi_f] = psd_band_factors(nu, 0.95).unwrap();
        for (name, phi) in [("white", 0.0), ("AR(1) 0.6", 0.6)] {
            let mut rng = Rng::new(20_251_124);
            let (mut hits, mut total) = (0usize, 0usize);
            for _ in 0..400 {
                let mut prev = 0.0;
                // Burn-in of 200 samples for the AR(1) start-up.
                let x: Vec<f64> = (0..n + 200)
                    .map(|_| {
                        prev = phi * prev + rng.normal();
                        prev
                    })
                    .skip(200)
                    .collect();
                let p = welch.psd(&x, fs).unwrap();
                assert_eq!(p.n_segments, k);
                for i in (3..p.freq_hz.len() - 3).step_by(3) {
                    let th = std::f64::consts::TAU * p.freq_hz[i] / fs;
                    let d = (1.0 - phi * th.cos()).powi(2) + (phi * th.sin()).powi(2);
                    let truth = 2.0 / (fs * d);
                    total += 1;
                    if lo_f * p.pxx[i] <= truth && truth <= hi_f * p.pxx[i] {
                        hits += 1;
                    }
                }
            }
            let [a, b] = binomial_interval(hits, total, 0.999);
            assert!(
                a <= 0.95 && 0.95 <= b,
                "{name}: coverage {hits}/{total} = {:.4}, 99.9 % interval [{a:.4}, {b:.4}]",
                hits as f64 / total as f64
            );
        }
    }

    /// The row level against an independent root: SciPy's `brentq` on the
    /// same sum of three tails, each the larger of Carter's at `ν/2` and
    /// the eigenvalue product of a line in one channel (NumPy
    /// `linalg.solve`/`slogdet` on the dense matrices), periodic Hann 64 at
    /// 50 %. Both roots are solved to ~1e-12; 1e-9 absolute is loose.
    #[test]
    fn coherence_row_level_matches_a_scipy_root() {
        let w = hann(64);
        for (k, d, want) in [
            (3usize, 0.0, 0.9736355937284047),
            (12, 0.0, 0.505862958583905),
            (12, 0.3, 0.4911374464089439),
            (12, -0.5, 0.479306473503266),
            (40, 0.2, 0.1801207129456115),
            (150, 0.0, 0.05246646762367738),
        ] {
            let info = SpectrumInfo {
                nperseg: 64,
                noverlap: 32,
                n_segments: k,
                n_records: 1,
                dof: welch_dof(&w, 32, k),
                ..Default::default()
            };
            let got = coherence_row_level(&info, &w, d, 0.99).unwrap();
            assert!((got - want).abs() < 1e-9, "K={k} δ={d}: {got} vs {want}");
        }
    }

    /// The row level of session 20 (each bin's tail with a kept root and
    /// the factor's fixed row, `line_tail::LineTail`) against session 19's
    /// (kept in `reference`) over windows, overlaps, segment counts from 2
    /// to past `EXACT_MAX_SEGMENTS`, 1 to 3 records, offsets and two
    /// confidences. Tolerance: 1e-12 relative (the roots are solved to
    /// ~1e-12 in ln tail) plus the level's own rounding in both: a bin's
    /// tail is known to `(n − 1) ε/(c(1 − c))` relative (`line_tail`'s
    /// test), its logarithm falls by `(n − 1)/(1 − c)` per unit of `c`, so
    /// the level is known to `ε/c` absolute, `ε/c²` relative; 8 times that.
    #[test]
    fn coherence_row_level_equals_session_19s() {
        let boxcar = vec![1.0; 64];
        let w = hann(64);
        let mut worst = 0.0f64;
        let mut ks: Vec<usize> = (2..=24).collect();
        ks.extend([31, 58, 100, 150, 301, 512, 513, 700]);
        for (name, win, noverlap) in [
            ("hann 50 %", &w, 32usize),
            ("hann 75 %", &w, 48),
            ("hann 25 %", &w, 16),
            ("boxcar 50 %", &boxcar, 32),
            ("hann, no overlap", &w, 0),
        ] {
            for &k in &ks {
                for r in [1usize, 3] {
                    let info = SpectrumInfo {
                        nperseg: 64,
                        noverlap,
                        n_segments: k,
                        n_records: r,
                        dof: r as f64 * welch_dof(win, 64 - noverlap, k),
                        ..Default::default()
                    };
                    for d in [0.0, 0.13, -0.37, 0.5] {
                        for conf in [0.99, 0.95] {
                            let got = coherence_row_level(&info, win, d, conf);
                            let want = reference::coherence_row_level(&info, win, d, conf);
                            match (got, want) {
                                (Some(g), Some(h)) => {
                                    let err = (g - h).abs() / h;
                                    let tol = 1e-12 + 8.0 * f64::EPSILON / (h * h);
                                    worst = worst.max(err / tol);
                                    assert!(
                                        err <= tol,
                                        "{name} K={k} R={r} δ={d} {conf}: {g} vs {h}"
                                    );
                                }
                                (None, None) => {}
                                _ => panic!("{name} K={k} R={r} δ={d}: {got:?} vs {want:?}"),
                            }
                        }
                    }
                }
            }
        }
        eprintln!("row level: worst difference over its tolerance {worst:.3}");
    }
}
