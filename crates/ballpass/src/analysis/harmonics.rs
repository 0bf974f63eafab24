//! Step 5: harmonics and their significance.
//!
//! Is there a line at `k f_c`?
//!
//! A bin of a Welch estimate of noise with spectrum `S(f)` is distributed as
//! `S(f) χ²_ν / ν`, with `ν` the equivalent degrees of freedom of the
//! overlapping windowed segments (Percival & Walden Eq. 292b; Hann at 50 %
//! gives ~1.89 per segment; `R` averaged repeats multiply it by `R`). The
//! test at `f = k f_c`:
//!
//! ```text
//! floor window  k = 1: [f/2.5, 2.5 f];  k ≥ 2: [f − 1.5 f_c, f + 1.5 f_c]
//!               minus the bins within ±1.5 bins of every harmonic j f_c and the
//!               two lowest bins (DC leakage)
//! floor fit     ln PSD = polynomial in ln f (quadratic with ≥ 12 bins, else a line)
//! floor S(f)    exp(fit(ln f) − E[ln χ²_ν/ν]),  E[ln χ²_ν/ν] = ψ(ν/2) − ln(ν/2)
//! statistic     T = max over the tested bins of PSD / S   (the two bins around a
//!               measured f, the nearest ±1 around a predicted one)
//! p-value       P(max_i (χ²_ν,i/ν) e^{−ε} > T),  ε ~ N(0, σ²)
//! σ²            (ψ'(ν/2) + m²) h c + m²:  the fit's prediction variance (h its
//!               leverage at f, c the variance inflation of neighbouring
//!               bins' correlation, 1 + 2 Σ ρ_j, ρ_j = |Σ w² e^{−2πijn/N}|² / (Σ w²)²,
//!               4/9 and 1/36 for Hann), plus m² = max(0, s² − ψ'(ν/2)), the
//!               residual variance of the fit beyond what χ² noise gives
//!               (a spectrum rougher than the model)
//! ```
//!
//! The floor follows a sloping spectrum (a load cell's drift, roughness, a
//! resonance nearby) instead of assuming it flat, and the statistic carries
//! the floor's own uncertainty, so the false-alarm rate of one test is its
//! nominal `α = 1 − confidence` at any record length (the harmonic tests of
//! `ballpass validate` measure it). A signal "shows f_c" when any of its
//! harmonics `k = 1..K` is significant after the Holm correction over the
//! `K` tests at `α`: a family-wise false-alarm rate of `α` per signal and
//! record. The largest of the tested bins is compared, so a line between
//! bins is not missed; neighbours of a strong line (leakage) are excluded
//! from no floor but the line's own ±1.5 bins, which errs towards "not
//! significant".
//!
//! Coherence at `k f_c`: the largest of the three bins nearest `k f_c`,
//! significant above the level at which the three bins' null tails add up
//! to `a = 1 − confidence^(1/3)`; each bin's tail is the larger of noise in
//! both channels and the exact tail of a line in one channel beside noise,
//! at the line's offset from the bin: noise passes a row with probability
//! at most `a` whether neither, one or both channels carry a line
//! ([`super::confidence`] module docs).

use rayon::prelude::*;
use serde::Serialize;

use super::spectra::Spectra;
use super::{pair_name, AnalyzeSettings, Signal};
use crate::stats::{digamma, gamma_p_many, gamma_p_with, parabolic_peak, trigamma};

/// The spectrum at one frequency against its local floor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HarmonicValue {
    /// Frequency examined, Hz.
    pub f_hz: f64,
    /// Frequency of the bin holding the largest ratio to the floor, Hz.
    pub bin_f_hz: f64,
    /// PSD in that bin, unit²/Hz.
    pub psd: f64,
    /// Local noise floor there (mean-equivalent), unit²/Hz.
    pub floor: Option<f64>,
    /// Bins the floor was fitted on.
    pub floor_bins: usize,
    /// `10 log10(psd / floor)`, dB.
    pub ratio_db: Option<f64>,
    /// Ratio a single test at `1 − confidence` needs, dB.
    pub threshold_db: Option<f64>,
    /// Probability of a ratio this large from noise alone (module docs).
    pub p_value: Option<f64>,
    /// `p_value < 1 − confidence` (one test, before the family correction).
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
    /// At `k f_c` measured (from another signal than this one).
    pub measured: Option<HarmonicValue>,
    /// Which value the claim rests on: `measured` when there is one, else
    /// `predicted`.
    pub tested: Option<String>,
    /// Whether the line stands above the floor after the Holm correction
    /// over the signal's `K` harmonics (family-wise `1 − confidence`).
    pub significant: Option<bool>,
}

impl HarmonicRow {
    /// The value the claim rests on.
    pub fn value(&self) -> Option<&HarmonicValue> {
        match self.tested.as_deref() {
            Some("measured") => self.measured.as_ref(),
            Some(_) => self.predicted.as_ref(),
            None => None,
        }
    }
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
    /// Level noise exceeds in any of the three bins with probability at
    /// most `1 − confidence^(1/3)` (module docs; `None` with fewer than two
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

/// What the harmonic test needs of one spectrum: its degrees of freedom
/// and the variance inflation of neighbouring bins' correlation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TestContext {
    nu: f64,
    inflation: f64,
    alpha: f64,
    /// `ln Γ(ν/2)`, for the χ² CDFs.
    ln_gamma_half_nu: f64,
    /// The threshold without the floor's uncertainty for 1, 2, 3 tested
    /// bins ([`TestContext::base`]).
    bases: [f64; 3],
}

impl TestContext {
    pub(crate) fn new(s: &Spectra, settings: &AnalyzeSettings) -> Option<TestContext> {
        let nu = s.info.dof;
        if nu.is_nan() || nu <= 0.0 {
            return None;
        }
        let w = settings.window.to_dsp().values(s.info.nperseg).ok()?;
        let n = w.len() as f64;
        let e: f64 = w.iter().map(|v| v * v).sum();
        let rho = |j: f64| {
            let (mut re, mut im) = (0.0, 0.0);
            for (i, v) in w.iter().enumerate() {
                let a = std::f64::consts::TAU * j * i as f64 / n;
                re += v * v * a.cos();
                im -= v * v * a.sin();
            }
            (re * re + im * im) / (e * e)
        };
        let inflation = 1.0 + 2.0 * (rho(1.0) + rho(2.0) + rho(3.0));
        let alpha = 1.0 - settings.confidence;
        Some(TestContext {
            nu,
            inflation,
            alpha,
            ln_gamma_half_nu: crate::stats::ln_gamma(0.5 * nu),
            bases: [1, 2, 3].map(|n_b| Self::base_of(alpha, nu, n_b)),
        })
    }

    /// The threshold of the largest of `n_b` bins' `χ²_ν/ν` without the
    /// floor's uncertainty.
    fn base_of(alpha: f64, nu: f64, n_b: usize) -> f64 {
        crate::stats::chi2_ppf((1.0 - alpha).powf(1.0 / n_b as f64), nu) / nu
    }

    /// [`TestContext::base_of`] for this spectrum (made once per context for
    /// the 1 to 3 bins a test takes).
    fn base(&self, n_b: usize) -> f64 {
        match n_b {
            1..=3 => self.bases[n_b - 1],
            _ => Self::base_of(self.alpha, self.nu, n_b),
        }
    }

    /// `P(max of n_b bins' χ²_ν/ν · e^{−ε} > t)`, `ε ~ N(0, var)`, the
    /// expectation over `ε` by 24-point Gauss–Hermite quadrature.
    fn tail(&self, t: f64, n_b: usize, var: f64) -> f64 {
        // chi2_cdf(ν x, ν)^n_b, ln Γ(ν/2) made once.
        let (a, lg) = (0.5 * self.nu, self.ln_gamma_half_nu);
        let sd = var.max(0.0).sqrt();
        if sd < 1e-9 {
            return 1.0 - gamma_p_with(a, lg, 0.5 * (self.nu * t)).powi(n_b as i32);
        }
        // The 24 nodes' CDFs side by side (the same bits as one by one).
        let xs: [f64; 24] = std::array::from_fn(|i| 0.5 * (self.nu * (t * (sd * GH_X[i]).exp())));
        let cdf = gamma_p_many(a, lg, &xs);
        let e: f64 = cdf
            .iter()
            .zip(GH_W)
            .map(|(p, w)| w * p.powi(n_b as i32))
            .sum();
        (1.0 - e).clamp(0.0, 1.0)
    }

    /// The `t` with `tail(t) = alpha`: bisection in `ln t` between the
    /// thresholds without the floor's uncertainty and with ±6 of its σ, to
    /// 0.1 % (the threshold is reported, not tested against).
    fn threshold(&self, n_b: usize, var: f64) -> f64 {
        let base = self.base(n_b);
        let sd = var.max(0.0).sqrt();
        let (mut lo, mut hi) = (base.ln() - 0.1, base.ln() + 6.0 * sd + 0.1);
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            if self.tail(mid.exp(), n_b, var) > self.alpha {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).exp()
    }
}

/// Nodes and weights of 24-point Gauss–Hermite quadrature for the standard
/// normal density (`numpy.polynomial.hermite_e.hermegauss(24)`, weights
/// divided by `√(2π)`; they sum to 1).
const GH_X: [f64; 24] = [
    -8.507803519195257,
    -7.437890666021663,
    -6.541675005098634,
    -5.732747175251201,
    -4.97804137463912,
    -4.260383605019905,
    -3.56930676407356,
    -2.8977286432233136,
    -2.2404678516917524,
    -1.5934804298164202,
    -0.953421922932109,
    -0.31737009662945237,
    0.31737009662945237,
    0.953421922932109,
    1.5934804298164202,
    2.2404678516917524,
    2.8977286432233136,
    3.56930676407356,
    4.260383605019905,
    4.97804137463912,
    5.732747175251201,
    6.541675005098634,
    7.437890666021663,
    8.507803519195257,
];
const GH_W: [f64; 24] = [
    9.39019368904204e-17,
    3.7149741527624003e-13,
    1.7186649279648716e-10,
    2.26746167348065e-08,
    1.2176597454425883e-06,
    3.2095005652746016e-05,
    0.00046471871877939644,
    0.003976608929181307,
    0.021126344408967556,
    0.07206936401717823,
    0.1614595128670001,
    0.2408701155466404,
    0.2408701155466404,
    0.1614595128670001,
    0.07206936401717823,
    0.021126344408967556,
    0.003976608929181307,
    0.00046471871877939644,
    3.2095005652746016e-05,
    1.2176597454425883e-06,
    2.26746167348065e-08,
    1.7186649279648716e-10,
    3.7149741527624003e-13,
    9.39019368904204e-17,
];

/// A least-squares polynomial in `u = (x − centre) / scale`.
struct PolyFit {
    centre: f64,
    scale: f64,
    coef: Vec<f64>,
    /// `(UᵀU)⁻¹` of the design.
    inv: [[f64; 3]; 3],
}

/// Least-squares polynomial (degree 1 or 2) of `y` on `x`, by the normal
/// equations on centred and scaled `x` (a few dozen points; well
/// conditioned once centred and scaled).
fn poly_fit(x: &[f64], y: &[f64], degree: usize) -> Option<PolyFit> {
    let m = x.len() as f64;
    let xc = x.iter().sum::<f64>() / m;
    let sc = x
        .iter()
        .map(|v| (v - xc).abs())
        .fold(0.0, f64::max)
        .max(1e-12);
    let p = degree + 1;
    let mut ata = [[0.0; 3]; 3];
    let mut aty = [0.0; 3];
    for (xi, yi) in x.iter().zip(y) {
        let u = (xi - xc) / sc;
        let row = [1.0, u, u * u];
        for a in 0..p {
            aty[a] += row[a] * yi;
            for b in 0..p {
                ata[a][b] += row[a] * row[b];
            }
        }
    }
    let inv = invert(&ata, p)?;
    let coef: Vec<f64> = (0..p)
        .map(|a| (0..p).map(|b| inv[a][b] * aty[b]).sum())
        .collect();
    Some(PolyFit {
        centre: xc,
        scale: sc,
        coef,
        inv,
    })
}

/// Inverse of the leading `p x p` block (Gauss–Jordan with pivoting).
fn invert(a: &[[f64; 3]; 3], p: usize) -> Option<[[f64; 3]; 3]> {
    let mut m = *a;
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate().take(p) {
        row[i] = 1.0;
    }
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[piv][c].abs() < 1e-12 {
            return None;
        }
        m.swap(c, piv);
        inv.swap(c, piv);
        let d = m[c][c];
        for k in 0..p {
            m[c][k] /= d;
            inv[c][k] /= d;
        }
        for r in 0..p {
            if r != c {
                let f = m[r][c];
                for k in 0..p {
                    m[r][k] -= f * m[c][k];
                    inv[r][k] -= f * inv[c][k];
                }
            }
        }
    }
    Some(inv)
}

/// The PSD at `f_hz` against its floor (module docs). `accurate`: `f_hz`
/// is measured (test the two bins around it), else predicted (the nearest
/// ±1).
pub(crate) fn harmonic_value(
    s: &Spectra,
    psd: &[f64],
    f_hz: f64,
    f_c_hz: f64,
    accurate: bool,
    ctx: Option<TestContext>,
) -> Option<HarmonicValue> {
    let df = s.info.resolution_hz;
    let i = s.nearest_bin(f_hz)?;
    if i < 2 || i + 2 >= psd.len() {
        return None;
    }
    let tested: Vec<usize> = if accurate {
        let lo = (f_hz / df).floor() as usize;
        if (f_hz / df - lo as f64).abs() < 1e-9 {
            vec![lo]
        } else {
            vec![lo, lo + 1]
        }
    } else {
        vec![i - 1, i, i + 1]
    };
    let near_harmonic = |j: usize| {
        let f = j as f64 * df;
        let h = (f / f_c_hz).round();
        h >= 1.0 && (f - h * f_c_hz).abs() <= 1.5 * df
    };
    let (lo_f, hi_f) = if f_hz < 2.5 * f_c_hz {
        (f_hz / 2.5, f_hz * 2.5)
    } else {
        (f_hz - 1.5 * f_c_hz, f_hz + 1.5 * f_c_hz)
    };
    let lo = ((lo_f / df).ceil() as usize).max(2);
    let hi = ((hi_f / df).floor() as usize).min(psd.len() - 2);
    let bins: Vec<usize> = (lo..=hi)
        .filter(|&j| !near_harmonic(j) && !tested.contains(&j) && psd[j] > 0.0)
        .collect();
    let value_at = |j: usize, floor: Option<f64>| HarmonicValue {
        f_hz,
        bin_f_hz: s.freq_hz[j],
        psd: psd[j],
        floor,
        floor_bins: bins.len(),
        ratio_db: None,
        threshold_db: None,
        p_value: None,
        significant: None,
    };
    let fallback = || {
        let j = *tested
            .iter()
            .max_by(|&&a, &&b| psd[a].total_cmp(&psd[b]))
            .expect("tested bins");
        value_at(j, None)
    };
    let Some(ctx) = ctx else {
        return Some(fallback());
    };
    if bins.len() < 5 {
        return Some(fallback());
    }
    let x: Vec<f64> = bins.iter().map(|&j| s.freq_hz[j].ln()).collect();
    let y: Vec<f64> = bins.iter().map(|&j| psd[j].ln()).collect();
    let degree = if bins.len() >= 12 { 2 } else { 1 };
    let Some(PolyFit {
        centre: xc,
        scale: sc,
        coef,
        inv,
    }) = poly_fit(&x, &y, degree)
    else {
        return Some(fallback());
    };
    let eval = |xv: f64| {
        let u = (xv - xc) / sc;
        let row = [1.0, u, u * u];
        let yhat: f64 = coef.iter().zip(row).map(|(c, r)| c * r).sum();
        let mut lev = 0.0;
        for a in 0..coef.len() {
            for b in 0..coef.len() {
                lev += row[a] * inv[a][b] * row[b];
            }
        }
        (yhat, lev)
    };
    let rss: f64 = x
        .iter()
        .zip(&y)
        .map(|(xi, yi)| (yi - eval(*xi).0).powi(2))
        .sum();
    let dof_res = bins.len() as f64 - coef.len() as f64;
    let s2 = rss / dof_res.max(1.0);
    let v_chi = trigamma(0.5 * ctx.nu);
    let misfit = (s2 - v_chi).max(0.0);
    let mu = digamma(0.5 * ctx.nu) - (0.5 * ctx.nu).ln();
    // The largest ratio over the tested bins.
    let (j, ratio, lev) = tested
        .iter()
        .map(|&j| {
            let (yhat, lev) = eval(s.freq_hz[j].ln());
            (j, psd[j] / (yhat - mu).exp(), lev)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("tested bins");
    let var = (v_chi + misfit) * lev * ctx.inflation + misfit;
    let p = ctx.tail(ratio, tested.len(), var);
    let thr = ctx.threshold(tested.len(), var);
    let floor = psd[j] / ratio;
    Some(HarmonicValue {
        ratio_db: Some(10.0 * ratio.log10()),
        threshold_db: Some(10.0 * thr.log10()),
        p_value: Some(p),
        significant: Some(p < ctx.alpha),
        ..value_at(j, Some(floor))
    })
}

/// Harmonic table for every auto-spectrum. `f_meas`: the measured `f_c`
/// and the signal it was measured from (a signal's own measurement is not
/// used to test it: that would pick the frequency from the data tested).
pub(crate) fn harmonics(
    s: &Spectra,
    f_pred: f64,
    f_meas: Option<(f64, Signal)>,
    settings: &AnalyzeSettings,
) -> Vec<HarmonicRow> {
    harmonics_reusing(s, f_pred, f_meas, settings, &[])
}

/// [`harmonics`], taking each row's test at the prediction from `known`
/// where it holds that signal and harmonic: rows [`harmonics`] made of the
/// same spectra, prediction and settings (the test is deterministic, so
/// the values are the very ones it would compute again).
pub(crate) fn harmonics_reusing(
    s: &Spectra,
    f_pred: f64,
    f_meas: Option<(f64, Signal)>,
    settings: &AnalyzeSettings,
    known: &[HarmonicRow],
) -> Vec<HarmonicRow> {
    let ctx = TestContext::new(s, settings);
    let alpha = 1.0 - settings.confidence;
    // Every (signal, k) test is independent of the others: all run in
    // parallel (rayon), collected in order, then corrected per signal.
    let per_signal: Vec<Vec<HarmonicRow>> = s
        .auto
        .par_iter()
        .map(|(sig, psd)| {
            let meas = f_meas.filter(|(_, from)| from != sig).map(|(f, _)| f);
            let mut mine: Vec<HarmonicRow> = (1..=settings.harmonics)
                .into_par_iter()
                .map(|k| {
                    let kf = k as f64;
                    let predicted = match known.iter().find(|r| r.signal == *sig && r.k == k) {
                        Some(r) => r.predicted.clone(),
                        None => harmonic_value(s, psd, kf * f_pred, f_pred, false, ctx),
                    };
                    let measured = meas.and_then(|f| harmonic_value(s, psd, kf * f, f, true, ctx));
                    let tested = if measured.is_some() {
                        Some("measured".to_string())
                    } else if predicted.is_some() {
                        Some("predicted".to_string())
                    } else {
                        None
                    };
                    HarmonicRow {
                        signal: *sig,
                        k,
                        predicted,
                        measured,
                        tested,
                        significant: None,
                    }
                })
                .collect();
            holm(&mut mine, alpha);
            mine
        })
        .collect();
    per_signal.into_iter().flatten().collect()
}

/// Holm's step-down correction over one signal's harmonics: sorted by
/// p-value, the `i`-th smallest (from 0) is significant while every
/// smaller one was and `p ≤ α / (m − i)`.
fn holm(rows: &mut [HarmonicRow], alpha: f64) {
    let mut order: Vec<(usize, f64)> = rows
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.value().and_then(|v| v.p_value).map(|p| (i, p)))
        .collect();
    let m = order.len();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut still = true;
    for (rank, (i, p)) in order.into_iter().enumerate() {
        still = still && p <= alpha / (m - rank) as f64;
        rows[i].significant = Some(still);
    }
}

/// Coherence rows for every cross pair and harmonic (module docs).
pub(crate) fn coherence_rows(
    s: &Spectra,
    f_c: f64,
    settings: &AnalyzeSettings,
) -> Vec<CoherenceRow> {
    let w = settings.window.to_dsp().values(s.info.nperseg).ok();
    let df = s.info.resolution_hz;
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
            // The row's level depends on where the line falls between the
            // three bins (module docs of `confidence`).
            let threshold = w.as_ref().and_then(|w| {
                super::confidence::coherence_row_level(
                    &s.info,
                    w,
                    (f - s.freq_hz[i]) / df,
                    settings.confidence,
                )
            });
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
    use crate::analysis::spectra::SpectrumInfo;
    use crate::sim::rng::Rng;

    /// A one-sided spectrum on a 0.1 Hz grid with `f_c` = 1 Hz: `shape(f)`
    /// times independent `χ²_ν / ν` bins, plus `line` at the harmonics.
    fn synthetic(rng: &mut Rng, nu: f64, shape: impl Fn(f64) -> f64, line: f64) -> Spectra {
        let (n, df) = (200, 0.1);
        let k = (nu / 2.0).round() as usize; // ν = 2k: a sum of k exponentials.
        let psd: Vec<f64> = (0..n)
            .map(|i| {
                let f = i as f64 * df;
                let chi: f64 = (0..k).map(|_| rng.exponential()).sum::<f64>() / k as f64;
                let l = if i % 10 == 0 && i > 0 { line } else { 0.0 };
                shape(f.max(df)) * (chi + l)
            })
            .collect();
        Spectra {
            info: SpectrumInfo {
                resolution_hz: df,
                dof: 2.0 * k as f64,
                nperseg: 256,
                ..Default::default()
            },
            freq_hz: (0..n).map(|i| i as f64 * df).collect(),
            auto: vec![(Signal::Optical, psd)],
            cross: vec![],
        }
    }

    #[test]
    fn a_line_is_significant() {
        let s = AnalyzeSettings::default();
        let mut rng = Rng::new(3);
        let rows = harmonics(&synthetic(&mut rng, 40.0, |_| 1.0, 30.0), 1.0, None, &s);
        assert_eq!(rows.len(), 5);
        for r in &rows {
            assert_eq!(r.significant, Some(true), "{r:?}");
            // 31 over a floor of ~1: about 15 dB.
            assert!(
                r.predicted.as_ref().unwrap().ratio_db.unwrap() > 12.0,
                "{r:?}"
            );
        }
    }

    /// Noise alone, flat or falling as 1/f² or 1/f⁴ (a drifting load cell's
    /// leakage), few or many degrees of freedom: the family-wise rate of
    /// "shows f_c" stays at its nominal 1 % (1000 spectra each; the
    /// binomial 99.9 % upper bound for a true 1 % is 2.1 %; independent bins
    /// are the best case for the floor fit, the simulator benches of
    /// `ballpass validate` check correlated ones).
    #[test]
    fn noise_alone_claims_at_the_nominal_rate_on_any_slope() {
        let s = AnalyzeSettings::default();
        for (name, nu) in [("few", 4.0), ("many", 400.0)] {
            for (slope, shape) in [
                ("flat", &(|_f: f64| 1.0) as &dyn Fn(f64) -> f64),
                ("1/f^2", &|f: f64| 1.0 / (f * f)),
                ("1/f^4", &|f: f64| 1.0 / (f * f * f * f)),
            ] {
                let mut rng = Rng::new(17);
                let trials = 1000;
                let claims = (0..trials)
                    .filter(|_| {
                        harmonics(&synthetic(&mut rng, nu, shape, 0.0), 1.0, None, &s)
                            .iter()
                            .any(|r| r.significant == Some(true))
                    })
                    .count();
                let rate = claims as f64 / trials as f64;
                assert!(rate < 0.021, "{name} dof, {slope}: {rate}");
            }
        }
    }

    /// Seeded records of one coherence-row case: friction noise (plus
    /// `ripple` times the optical line when not zero) against an optical
    /// channel with a line of amplitude `line` (none: noise in both) over
    /// noise `noise`; Hann segments of 64 samples at 50 %, 12 per record,
    /// `f_c` in bins (1 Hz). Returns rows significant on this
    /// rule, on session 17's (the middle bin's Carter level at `a/3` with
    /// the line's count) and on the rule before it (one bin at Welch's
    /// `ν/2` and `a`), and rows tested.
    fn coherence_case(
        seed: u64,
        records: usize,
        line: f64,
        noise: f64,
        ripple: f64,
        f_c: f64,
    ) -> [usize; 4] {
        use crate::analysis::confidence::{
            coherence_level, coherence_row_rate, coherence_segments,
        };
        use crate::analysis::spectra::full_of;
        use crate::analysis::WindowKind;
        let settings = AnalyzeSettings {
            nperseg: 64,
            noverlap: None,
            window: WindowKind::Hann,
            harmonics: 5,
            ..AnalyzeSettings::default()
        };
        let (n, fs) = (13 * 32, 64.0);
        let a = coherence_row_rate(settings.confidence);
        let w = settings.window.to_dsp().values(64).unwrap();
        let mut rng = Rng::new(seed);
        let mut out = [0usize; 4];
        for _ in 0..records {
            let ph = std::f64::consts::TAU * rng.uniform();
            let l: Vec<f64> = (0..n)
                .map(|t| (std::f64::consts::TAU * f_c * t as f64 / fs + ph).cos())
                .collect();
            let x: Vec<f64> = l.iter().map(|v| line * v + noise * rng.normal()).collect();
            let y: Vec<f64> = l.iter().map(|v| ripple * v + rng.normal()).collect();
            let s = full_of(
                &[(Signal::Friction, y), (Signal::Optical, x)],
                fs,
                n,
                &settings,
            )
            .unwrap();
            assert_eq!(s.info.n_segments, 12);
            let before = coherence_level(s.info.dof, a).unwrap();
            for r in coherence_rows(&s, f_c, &settings) {
                let i = s.nearest_bin(r.f_hz).unwrap();
                let d = (r.f_hz - s.freq_hz[i]) / s.info.resolution_hz;
                let n17 = coherence_segments(&s.info, &w, d);
                let s17 = coherence_level(2.0 * n17, a / 3.0).unwrap();
                out[0] += usize::from(r.significant == Some(true));
                out[1] += usize::from(r.coherence > s17);
                out[2] += usize::from(r.coherence > before);
                out[3] += 1;
            }
        }
        out
    }

    /// The null a coherence row faces: a line in one channel (the optical
    /// pulses), strong or about as strong as the noise in its bin, and
    /// noise in the other (friction without ripple), or noise in both.
    /// `f_c` 2.37 bins, so that the five harmonics sit 0.37, −0.26, 0.11,
    /// 0.48 and −0.15 bin off the grid; 2 000 records of each, five rows
    /// each: the rows called significant must stay within the exact
    /// binomial 99.9 % bound of the nominal `1 − 0.99^(1/3)` per row (53 of
    /// 10 000). This rule: 24 (strong line), 27 (weak line) and 29 (noise);
    /// session 17's rule 16, 14 and 19 (never more: its level is never
    /// lower); the rule before it 74, 92 and 93, over the bound.
    #[test]
    fn coherence_rows_keep_their_false_alarm_rate() {
        for (name, line, noise) in [
            ("strong line", 3.0, 0.3),
            ("weak line", 0.3, 1.0),
            ("noise", 0.0, 1.0),
        ] {
            let [hits, s17, before, rows] =
                coherence_case(30_000_001, 2000, line, noise, 0.0, 2.37);
            assert_eq!(rows, 10_000);
            eprintln!("{name}: {hits} rows significant, session 17's rule {s17}, before {before}");
            // P(Binomial(10 000, a) ≤ 53) ≥ 0.999 (scipy.stats.binom.ppf(0.999, 10 000, a) = 53).
            assert!(hits <= 53, "{name}: {hits} of {rows} rows significant");
            // Never fewer than session 17's rule: its level is never lower.
            assert!(hits >= s17, "{name}: {hits} vs {s17}");
            assert!(before > 53, "rule before: {before} of {rows}");
        }
    }

    /// A ripple in friction coherent with the optical line at `f_c`, 0.06
    /// bin off the grid (where session 17's level was most conservative),
    /// weak enough that session 17's rule misses most rows: this rule finds
    /// every row that one finds and more than 1.25 times as many (400
    /// records: 157 rows against 95; the 1 600 rows at k ≥ 2 are null).
    #[test]
    fn coherence_rows_find_a_weak_ripple_more_often() {
        let [hits, s17, _, rows] = coherence_case(30_100_001, 400, 3.0, 0.3, 0.25, 2.06);
        eprintln!("weak ripple: {hits} of {rows} rows significant, session 17's rule {s17}");
        assert!(hits >= s17);
        assert!(4 * hits > 5 * s17, "{hits} vs {s17} of {rows}");
    }
}
