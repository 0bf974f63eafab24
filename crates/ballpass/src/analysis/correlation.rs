//! Step 3: the six correlations, the measured period and the phases.
//!
//! Convention (thesis Eq. 7.1, SciPy `correlate`, MATLAB `xcorr`):
//!
//! ```text
//! R_xy[m] = sum_n x[n + m] y[n],   lag tau = m / fs
//! ```
//!
//! If `y` is `x` delayed by `d` seconds, `R_xy` peaks at `tau = -d`: a peak
//! at negative lag means **y lags x**.
//!
//! # Measured period
//! For each autocorrelation: the maximum within `±w tau` (w =
//! [`AnalyzeSettings::period_window`], 0.25) around `k T` for `k = 1, 2, ...`
//! while `k T` is within half the record (so at least half the samples
//! overlap), refined by a 3-point parabola; a maximum on the window's edge
//! or not above zero is not a peak and is skipped. `T` starts at the
//! predicted `tau_c` and is re-fitted after each peak (so the windows follow
//! a realised rate a few percent off the prediction; the brief centred them
//! on `k tau_c` alone). The period is the least-squares slope through the
//! origin, `T = sum k L_k / sum k^2`.
//!
//! # Phase
//! See [`super::phase`].

use ballpass_dsp::{CorrelateSettings, Correlator};
use serde::Serialize;

use super::preprocess::Prepared;
use super::{pair_name, AnalyzeSettings, Signal, CROSS_PAIRS};
use crate::error::{Error, Result};
use crate::stats::parabolic_peak;

/// The correlations of one record or the average of repeats.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Correlations {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Samples per record correlated, `N`.
    pub samples: usize,
    /// Lags, samples: `-L ..= L`, with `L = N - 1` for the full range (see
    /// [`super::MaxLag`]).
    pub lags: Vec<i64>,
    /// Lags, s: `lags / fs`.
    pub lag_s: Vec<f64>,
    /// Series present, `(x, y)` with `x == y` for an autocorrelation, in
    /// column order (autos, then the cross pairs).
    pub series: Vec<((Signal, Signal), Vec<f64>)>,
}

impl Correlations {
    /// The series `R_xy`, if present.
    pub fn get(&self, x: Signal, y: Signal) -> Option<&[f64]> {
        self.series
            .iter()
            .find(|(k, _)| *k == (x, y))
            .map(|(_, v)| v.as_slice())
    }

    /// Column names in order.
    pub fn names(&self) -> Vec<String> {
        self.series
            .iter()
            .map(|((x, y), _)| pair_name(*x, *y))
            .collect()
    }

    /// Index of lag zero.
    pub fn zero_index(&self) -> usize {
        self.lags.iter().position(|&m| m == 0).unwrap_or(0)
    }

    /// Largest lag held, samples (`L`).
    pub fn max_lag_samples(&self) -> usize {
        self.lags.last().map_or(0, |&m| m.unsigned_abs() as usize)
    }

    /// Whether every lag of the record is held (`L = N - 1`).
    pub fn is_full_range(&self) -> bool {
        self.max_lag_samples() + 1 >= self.samples
    }
}

/// The lag window of the correlations, as `analysis.json` states it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CorrelationWindow {
    /// The setting (`auto`, `full` or `{"seconds": s}`).
    pub setting: super::MaxLag,
    /// Largest lag held, s (`L / fs`).
    pub max_lag_s: f64,
    /// Largest lag held, samples (`L`).
    pub max_lag_samples: usize,
    /// Predicted ball periods within the window (`L / fs / tau_c`).
    pub max_lag_periods: f64,
    /// Whether the window is the record's full range (`L = N - 1`).
    pub full_range: bool,
}

impl CorrelationWindow {
    /// The window `corr` holds, for the predicted period `tau_c_s`.
    pub fn of(corr: &Correlations, setting: super::MaxLag, tau_c_s: f64) -> Self {
        let l = corr.max_lag_samples();
        let s = l as f64 / corr.fs_hz;
        CorrelationWindow {
            setting,
            max_lag_s: s,
            max_lag_samples: l,
            max_lag_periods: s / tau_c_s,
            full_range: corr.is_full_range(),
        }
    }
}

/// The `(x, y)` pairs present for the given signals, in column order.
pub(crate) fn pairs_for(signals: &[Signal]) -> Vec<(Signal, Signal)> {
    let mut out: Vec<(Signal, Signal)> = signals.iter().map(|&s| (s, s)).collect();
    out.extend(
        CROSS_PAIRS
            .iter()
            .filter(|(x, y)| signals.contains(x) && signals.contains(y)),
    );
    out
}

/// The six (or fewer) correlations of one prepared record over lags
/// `-max_lag ..= max_lag` samples; each signal is transformed once. The full
/// range (`max_lag >= N - 1`) is one whole-record transform; a shorter window
/// is computed block by block ([`ballpass_dsp::correlate_pairs_window`]).
pub(crate) fn compute(
    p: &Prepared,
    correlator: &mut Correlator,
    settings: &AnalyzeSettings,
    max_lag: usize,
) -> Result<Correlations> {
    debug_assert_eq!(
        correlator.settings(),
        &CorrelateSettings {
            normalization: settings.corr_norm.to_dsp()
        }
    );
    let signals: Vec<Signal> = p.signals.iter().map(|(s, _)| *s).collect();
    let pairs = pairs_for(&signals);
    let idx = |s: Signal| signals.iter().position(|&k| k == s).expect("present");
    let index_pairs: Vec<(usize, usize)> = pairs.iter().map(|&(x, y)| (idx(x), idx(y))).collect();
    let inputs: Vec<&[f64]> = p.signals.iter().map(|(_, v)| v.as_slice()).collect();
    let n = inputs.first().map_or(0, |s| s.len());
    let mut out = if max_lag + 1 >= n {
        correlator.correlate_pairs(&inputs, &index_pairs)
    } else {
        ballpass_dsp::correlate_pairs_window(
            &inputs,
            &index_pairs,
            max_lag,
            settings.corr_norm.to_dsp(),
        )
    }
    .map_err(|e| Error::dsp("correlations", e))?;
    // Every series has the same lags; keep the first one's.
    let lags = out
        .first_mut()
        .map(|c| std::mem::take(&mut c.lags))
        .unwrap_or_default();
    let lag_s = lags.iter().map(|&m| m as f64 / p.fs_hz).collect();
    Ok(Correlations {
        fs_hz: p.fs_hz,
        samples: n,
        lags,
        lag_s,
        series: pairs
            .into_iter()
            .zip(out.into_iter().map(|c| c.values))
            .collect(),
    })
}

/// One autocorrelation peak used for the period.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodPeak {
    /// Multiple `k` of the period.
    pub k: usize,
    /// Refined lag of the peak, s.
    pub lag_s: f64,
    /// Correlation at the peak (interpolated).
    pub value: f64,
}

/// The period one autocorrelation shows.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignalPeriod {
    /// Signal.
    pub signal: Signal,
    /// Fitted period `T`, s (`None`: no peak found).
    pub period_s: Option<f64>,
    /// `1 / T`, Hz.
    pub f_c_hz: Option<f64>,
    /// RMS of `L_k - k T` over the peaks, s.
    pub residual_rms_s: Option<f64>,
    /// Mean correlation value of the peaks used.
    pub mean_peak_value: Option<f64>,
    /// Windows examined (`k = 1..=k_max`).
    pub windows: usize,
    /// Peaks found and used.
    pub peaks: Vec<PeriodPeak>,
}

/// The measured period: each signal's own, and the one retained.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeasuredPeriod {
    /// Signal whose autocorrelation gives the retained period.
    pub from_signal: Option<Signal>,
    /// Why that signal.
    pub choice: String,
    /// Retained period, s.
    pub period_s: Option<f64>,
    /// Retained ball-pass frequency `1 / T`, Hz.
    pub f_c_hz: Option<f64>,
    /// Spectral cross-check: the high-resolution peak near the predicted
    /// `f_c` of the same signal, parabolically interpolated, Hz.
    pub f_c_spectral_hz: Option<f64>,
    /// Every signal's own period.
    pub per_signal: Vec<SignalPeriod>,
}

/// Period of one autocorrelation (see the module docs).
pub(crate) fn signal_period(
    corr: &Correlations,
    signal: Signal,
    tau_pred_s: f64,
    settings: &AnalyzeSettings,
) -> Option<SignalPeriod> {
    let r = corr.get(signal, signal)?;
    let fs = corr.fs_hz;
    let zero = corr.zero_index();
    let half_record_s = (corr.samples as f64 / 2.0) / fs;
    let mut k_max = ((half_record_s / tau_pred_s).floor() as usize).max(1);
    if !corr.is_full_range() {
        // Only the windows that fit in the lag window.
        let in_window = corr.max_lag_samples() as f64 / fs / tau_pred_s - settings.period_window;
        k_max = k_max.min((in_window.floor().max(1.0)) as usize);
    }
    if let Some(m) = settings.max_period_peaks {
        k_max = k_max.min(m);
    }
    let mut peaks = Vec::new();
    let mut t_est = tau_pred_s;
    let half_w = ((settings.period_window * tau_pred_s * fs).round() as usize).max(1);
    for k in 1..=k_max {
        let centre = zero as f64 + k as f64 * t_est * fs;
        let c = centre.round() as isize;
        let lo = (c - half_w as isize).max(zero as isize + 1) as usize;
        let hi = ((c + half_w as isize) as usize).min(r.len() - 2);
        if lo >= hi {
            continue;
        }
        let (i, _) =
            r[lo..=hi]
                .iter()
                .enumerate()
                .fold((0, f64::NEG_INFINITY), |(bi, bv), (j, &v)| {
                    if v > bv {
                        (j, v)
                    } else {
                        (bi, bv)
                    }
                });
        let i = lo + i;
        if i == lo || i == hi || r[i] <= 0.0 {
            continue;
        }
        let (d, v) = parabolic_peak(r[i - 1], r[i], r[i + 1]);
        let lag = (i as f64 + d - zero as f64) / fs;
        peaks.push(PeriodPeak {
            k,
            lag_s: lag,
            value: v,
        });
        t_est = fit(&peaks);
    }
    if peaks.is_empty() {
        return Some(SignalPeriod {
            signal,
            period_s: None,
            f_c_hz: None,
            residual_rms_s: None,
            mean_peak_value: None,
            windows: k_max,
            peaks,
        });
    }
    let t = fit(&peaks);
    let res = (peaks
        .iter()
        .map(|p| (p.lag_s - p.k as f64 * t).powi(2))
        .sum::<f64>()
        / peaks.len() as f64)
        .sqrt();
    let mean_v = peaks.iter().map(|p| p.value).sum::<f64>() / peaks.len() as f64;
    Some(SignalPeriod {
        signal,
        period_s: Some(t),
        f_c_hz: Some(1.0 / t),
        residual_rms_s: Some(res),
        mean_peak_value: Some(mean_v),
        windows: k_max,
        peaks,
    })
}

/// Least-squares slope through the origin of `lag_k = k T`.
fn fit(peaks: &[PeriodPeak]) -> f64 {
    let num: f64 = peaks.iter().map(|p| p.k as f64 * p.lag_s).sum();
    let den: f64 = peaks.iter().map(|p| (p.k * p.k) as f64).sum();
    num / den
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Gaussian pulse train with period `t` s, delayed by `delay` s.
    fn pulses(n: usize, fs: f64, t: f64, delay: f64) -> Vec<f64> {
        let sigma = 0.155 * t / 2.3548;
        (0..n)
            .map(|i| {
                let time = i as f64 / fs - delay;
                let ph = time.rem_euclid(t);
                let d = ph.min(t - ph);
                (-0.5 * (d / sigma).powi(2)).exp()
            })
            .map(|v| v - 0.3)
            .collect()
    }

    fn corr_of(x: &[f64], y: &[f64], fs: f64) -> Correlations {
        let mut c = Correlator::new(CorrelateSettings {
            normalization: ballpass_dsp::Normalization::Coeff,
        });
        let r = c
            .correlate_pairs(&[x, y], &[(0, 0), (1, 1), (0, 1)])
            .unwrap();
        let lags = r[0].lags.clone();
        Correlations {
            fs_hz: fs,
            samples: x.len(),
            lag_s: lags.iter().map(|&m| m as f64 / fs).collect(),
            lags,
            series: vec![
                ((Signal::Friction, Signal::Friction), r[0].values.clone()),
                ((Signal::Optical, Signal::Optical), r[1].values.clone()),
                ((Signal::Friction, Signal::Optical), r[2].values.clone()),
            ],
        }
    }

    #[test]
    fn period_and_lag_of_a_delayed_pulse_train() {
        let fs = 1000.0;
        let t = 0.9123;
        let x = pulses(20_000, fs, t, 0.0);
        let y = pulses(20_000, fs, t, 0.39);
        let c = corr_of(&x, &y, fs);
        // Predicted 2 % off the true period: the windows must still find it.
        let p = signal_period(&c, Signal::Optical, t * 1.02, &AnalyzeSettings::default()).unwrap();
        let got = p.period_s.unwrap();
        // Parabolic refinement of a smooth peak sampled at 1 ms, averaged
        // over ~10 peaks: well below 0.1 ms.
        assert!((got - t).abs() < 1e-4, "period {got} vs {t}");
        let ph =
            crate::analysis::phase::correlation_peak(&c, Signal::Friction, Signal::Optical, got)
                .unwrap();
        // y = x delayed by 0.39 s: peak at -0.39 s (Eq. 7.1), within 1 ms.
        assert!(
            (ph.correlation_lag_s + 0.39).abs() < 1e-3,
            "lag {}",
            ph.correlation_lag_s
        );
        assert!(
            (ph.correlation_phase_deg - crate::analysis::phase::wrap_deg(-360.0 * 0.39 / t)).abs()
                < 0.5
        );
    }
}
