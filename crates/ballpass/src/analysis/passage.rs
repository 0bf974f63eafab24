//! Ball passages seen by the optical sensor (thesis §5, §6.3–6.4).
//!
//! Every ball passing the fibre tip reflects light back up the fibre: a pulse
//! in the photodetector voltage. [`detect_passages`] finds each pulse,
//! measures it, summarises the record and fits the two pulse-train models of
//! §6.3 (Gaussian Eq. 6.24 and rectangular Eq. 6.22, as corrected in docs/methods.md §5).
//!
//! # Method
//!
//! ```text
//! noise σ      = MAD(x[n+L] − x[n]) / (0.67449 √2)          (L ≪ pulse width; robust to pulses and drift)
//! baseline b   = running 10th percentile over ~2 τ_c          (follows drift; the pulses sit above it)
//! y            = x − b
//! passages     = find_peaks(y, prominence ≥ max(k σ, ρ · p75), distance ≥ 0.7 τ_c, wlen = 2.5 τ_c)
//! τ_p          = peak_widths(y, rel_height = 0.5)             (width at half prominence, CONVENTIONS.md)
//! σ_pulse      = τ_p / (2 √(2 ln 2))
//! time         = midpoint of the two half-prominence crossings
//! τ_c(k)       = time(k+1) − time(k);  spacing(k) = v τ_c(k) / 2
//! ```
//!
//! Pulse-train fits ([`TrainFits`]) use [`ballpass_dsp::least_squares`]
//! (Levenberg–Marquardt) with analytic Jacobians: the Gaussian train's is
//! sparse, each sample depending on the nearby pulses' amplitudes and on
//! `S, t0, τ_c, σ`. They cover the whole record up to
//! [`PassageSettings::fit_pulses`] passages, at most 150 samples per period.
//!
//! The ball-pass period `τ_c` used for the window lengths comes from the
//! velocity and geometry when the velocity is known (`f_c = v / (2 d_avg)`),
//! and otherwise from the median spacing of the strongest pulses.
//!
//! # Conditions reported
//!
//! - [`ConditionKind::BaselineDrift`]: the level between the pulses, taken
//!   at the same places of every regular gap, differs from gap to gap by more
//!   than 10 % of the median pulse and 5 σ (thesis Figs. 32, 36).
//! - [`ConditionKind::AcCoupling`]: the level after each pulse is lower than
//!   before it, beyond what the running baseline's slope explains, by a
//!   median of more than 2 % of the pulse, in at least 70 % of the pulses and
//!   consistently (Student's t of the mean dip > 3, which a drifting level
//!   does not give): a high-pass (AC coupling) compensating the slow pulse
//!   (thesis Fig. 38). Tuned on the simulator: its 1 s coupling gives 3.5 %
//!   at 20 mm/s and 33 % at 1 mm/s; a clean record gives ±0.5 %.
//! - [`ConditionKind::InvertedPulses`]: pulses pointing down, the signature of
//!   interference with a coherent source (thesis Fig. 32, §5.2).
//! - [`ConditionKind::MissedPassages`]: gaps longer than 1.6 τ_c.
//! - [`ConditionKind::PeriodMismatch`]: measured `τ_c` far from the prediction.

use serde::{Deserialize, Serialize};

use ballpass_dsp::{
    find_peaks, peak_widths_with_prominences, Bound, FindPeaksSettings, Prominences,
};

use crate::analysis::train_fit;
use crate::bearing::{check_velocity, Geometry};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};
use crate::stats::{from_order_key, order_key, percentile_of_keys, MeanStd};

/// Most samples per ball-pass period used by the pulse-train fits.
const FIT_SAMPLES_PER_PERIOD: f64 = 150.0;

/// `2√(2 ln 2)`: width at half maximum of a Gaussian over its sigma.
const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949_3;

/// Settings of [`detect_passages`]; the defaults suit the thesis' bench.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageSettings {
    /// Tracking velocity, mm/s; `None`: the recording's metadata, else the
    /// velocity-free mode (period from the pulses themselves).
    pub velocity_mm_s: Option<f64>,
    /// Bearing geometry for predictions; `None`: no predicted `f_c`, no
    /// spacing limits (a velocity alone then only converts periods to spacings).
    pub geometry: Option<Geometry>,
    /// Smallest prominence, in noise standard deviations.
    pub min_snr: f64,
    /// Smallest prominence relative to the 75th percentile of the prominences.
    pub min_relative_prominence: f64,
    /// Smallest distance between passages, in predicted periods.
    pub min_distance_periods: f64,
    /// Length of the running-percentile baseline, in periods.
    pub baseline_periods: f64,
    /// Percentile of the running baseline, 0–100.
    pub baseline_percentile: f64,
    /// Most passages in the pulse-train fits, counted from the start of the
    /// record; 0: no fits. The default, 200, fits a whole 30 s record at any
    /// velocity up to 48 mm/s (the fit's dense Jacobian grows as the square
    /// of this number: 200 pulses is 30 000 samples × 204 parameters, 49 MB).
    pub fit_pulses: usize,
    /// Order N of the rectangular Fourier series fitted (thesis Fig. 47: 20).
    pub rectangular_order: usize,
}

impl Default for PassageSettings {
    fn default() -> Self {
        Self {
            velocity_mm_s: None,
            geometry: None,
            min_snr: 6.0,
            min_relative_prominence: 0.25,
            min_distance_periods: 0.7,
            baseline_periods: 2.0,
            baseline_percentile: 10.0,
            fit_pulses: 200,
            rectangular_order: 20,
        }
    }
}

impl PassageSettings {
    fn validate(&self) -> Result<()> {
        if let Some(v) = self.velocity_mm_s {
            check_velocity(v)?;
        }
        if let Some(g) = &self.geometry {
            g.validate()?;
        }
        let pos = |name: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::setting(
                    name,
                    format!("must be a positive number, got {v}"),
                ))
            }
        };
        pos("min_snr", self.min_snr)?;
        pos("min_distance_periods", self.min_distance_periods)?;
        pos("baseline_periods", self.baseline_periods)?;
        if !(0.0..1.0).contains(&self.min_relative_prominence) {
            return Err(Error::setting(
                "min_relative_prominence",
                format!("must be in [0, 1), got {}", self.min_relative_prominence),
            ));
        }
        if !(0.0..=100.0).contains(&self.baseline_percentile) {
            return Err(Error::setting(
                "baseline_percentile",
                format!("must be in [0, 100], got {}", self.baseline_percentile),
            ));
        }
        if self.rectangular_order == 0 || self.rectangular_order > 10_000 {
            return Err(Error::setting(
                "rectangular_order",
                format!("must be 1 to 10000, got {}", self.rectangular_order),
            ));
        }
        Ok(())
    }
}

/// One ball passing the fibre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Passage {
    /// 0-based number of the passage in the record.
    pub index: usize,
    /// Centre: midpoint of the two half-prominence crossings, s.
    pub time_s: f64,
    /// Sample of the extreme value, s.
    pub peak_time_s: f64,
    /// +1 for a pulse up, −1 for an inverted pulse (interference).
    pub polarity: i8,
    /// Time to the next passage `τ_c`, s (`None` for the last).
    pub tau_c_s: Option<f64>,
    /// Width at half prominence `τ_p`, s.
    pub tau_p_s: f64,
    /// Gaussian sigma `τ_p / (2√(2 ln 2))`, s.
    pub sigma_s: f64,
    /// Prominence (pulse amplitude), V.
    pub amplitude_v: f64,
    /// Height above the running baseline, V.
    pub height_v: f64,
    /// `τ_p / τ_c` with this passage's `τ_c`.
    pub tau_p_over_tau_c: Option<f64>,
    /// Ball spacing implied `v τ_c / 2`, mm (when the velocity is known).
    pub spacing_mm: Option<f64>,
}

/// Spread of the ball spacings against what the free space allows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpacingSpread {
    /// Smallest spacing `v τ_c / 2`, mm.
    pub min_mm: f64,
    /// Largest spacing, mm.
    pub max_mm: f64,
    /// Standard deviation of the spacings, mm.
    pub std_mm: f64,
    /// Smallest possible spacing: touching balls, `d`, mm.
    pub limit_min_mm: f64,
    /// Largest possible spacing: all free space in one gap, `d + d_ext`, mm.
    pub limit_max_mm: f64,
    /// `(max − min) / d_ext`: how much of the free space the spread uses.
    pub spread_over_free_space: f64,
    /// Spacings outside `[d, d + d_ext]` by more than the timing resolution.
    pub outside_limits: usize,
}

/// What kind of problem a record shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ConditionKind {
    /// The DC level under the pulses drifts.
    BaselineDrift,
    /// Undershoots after the pulses: the signal was AC coupled.
    AcCoupling,
    /// Some pulses point down: interference of a coherent source.
    InvertedPulses,
    /// Gaps where one or more passages seem to be missing.
    MissedPassages,
    /// The measured period is far from the predicted one.
    PeriodMismatch,
}

impl ConditionKind {
    /// Short name, as in the JSON (`baseline_drift`, ...).
    pub fn name(self) -> &'static str {
        match self {
            ConditionKind::BaselineDrift => "baseline_drift",
            ConditionKind::AcCoupling => "ac_coupling",
            ConditionKind::InvertedPulses => "inverted_pulses",
            ConditionKind::MissedPassages => "missed_passages",
            ConditionKind::PeriodMismatch => "period_mismatch",
        }
    }
}

/// A condition found in a record, what it means and what to do about it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Condition {
    /// Which condition.
    pub kind: ConditionKind,
    /// The measure that triggered it (see `message` for its meaning).
    pub measure: f64,
    /// What was found, with numbers.
    pub message: String,
    /// What the user should do (the thesis' own fixes).
    pub advice: String,
}

/// Goodness of fit of a model to the optical signal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitQuality {
    /// Root-mean-square residual, V.
    pub rms_residual_v: f64,
    /// `rms_residual / median pulse amplitude`.
    pub rms_over_amplitude: f64,
    /// Coefficient of determination `1 − SS_res / SS_tot`.
    pub r_squared: f64,
    /// Samples fitted.
    pub samples: usize,
    /// Levenberg–Marquardt iterations.
    pub iterations: usize,
    /// Whether the solver converged.
    pub converged: bool,
}

/// The Gaussian pulse train of Eq. 6.24 fitted to the record's pulses.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaussianTrainFit {
    /// Base level `S`, V (of the baseline-removed signal).
    pub dc_v: f64,
    /// Centre of the first fitted pulse `t_0`, s.
    pub t0_s: f64,
    /// Period `τ_c`, s.
    pub tau_c_s: f64,
    /// Sigma of every pulse, s.
    pub sigma_s: f64,
    /// Width at half maximum `2√(2 ln 2) σ`, s.
    pub tau_p_s: f64,
    /// Per-pulse amplitudes `P_n`, V.
    pub amplitudes_v: Vec<f64>,
    /// How well it fits.
    pub quality: FitQuality,
}

/// The rectangular pulse train of order N (Eq. 6.22 as corrected in docs/methods.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RectangularTrainFit {
    /// Base level `S`, V.
    pub dc_v: f64,
    /// Pulse height `P`, V.
    pub amplitude_v: f64,
    /// Start of the period whose pulse is the first fitted one, s.
    pub t_start_s: f64,
    /// Period `τ_c`, s.
    pub tau_c_s: f64,
    /// Pulse width `τ_p`, s.
    pub tau_p_s: f64,
    /// Duty ratio `r = τ_p / τ_c`.
    pub ratio: f64,
    /// Order of the series.
    pub order: usize,
    /// How well it fits.
    pub quality: FitQuality,
}

/// Both fits over the same stretch of signal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainFits {
    /// Start of the stretch fitted, s.
    pub from_s: f64,
    /// End of the stretch fitted, s.
    pub to_s: f64,
    /// Passages in the stretch.
    pub pulses: usize,
    /// The Gaussian train (Eq. 6.24).
    pub gaussian: Option<GaussianTrainFit>,
    /// The rectangular train (Eq. 6.22 corrected).
    pub rectangular: Option<RectangularTrainFit>,
    /// `"gaussian"` or `"rectangular"`: the lower rms residual.
    pub better: Option<String>,
    /// Why a fit is missing, when one is.
    pub notes: Vec<String>,
}

impl GaussianTrainFit {
    /// The fitted train at `t_s`, V (baseline-removed signal):
    /// `S + Σ_j P_j exp(−(t − t0 − j τ_c)² / (2σ²))`.
    pub fn value(&self, t_s: f64) -> f64 {
        let mut th = vec![self.dc_v, self.t0_s, self.tau_c_s, self.sigma_s];
        th.extend_from_slice(&self.amplitudes_v);
        train_fit::gaussian_value(&th, t_s)
    }
}

impl RectangularTrainFit {
    /// The fitted series at `t_s`, V (baseline-removed signal):
    /// `S + P r + Σ_{n=1}^{N} (2P / nπ) sin(nπ r) cos(nπ (2 (t − t_s) / τ_c + r))`.
    pub fn value(&self, t_s: f64) -> f64 {
        train_fit::rectangular_value(
            &[
                self.dc_v,
                self.amplitude_v,
                self.t_start_s,
                self.tau_c_s,
                self.ratio,
            ],
            self.order,
            t_s,
        )
    }
}

/// Passages of one record and their summary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageAnalysis {
    /// File or test the record came from.
    pub source: String,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Velocity used, mm/s.
    pub velocity_mm_s: Option<f64>,
    /// Where the velocity came from: `settings`, `metadata` or `none`.
    pub velocity_source: String,
    /// Period used for the windows, s, and where it came from.
    pub tau_c_guide_s: f64,
    /// `prediction` or `pulses` (velocity-free mode).
    pub tau_c_guide_source: String,
    /// Robust noise standard deviation, V.
    pub noise_v: f64,
    /// Prominence threshold applied, V.
    pub prominence_threshold_v: f64,
    /// Passages found (both polarities).
    pub count: usize,
    /// Of which inverted.
    pub count_inverted: usize,
    /// The passages, in time order.
    pub passages: Vec<Passage>,
    /// `τ_c` between consecutive passages, s.
    pub tau_c_s: MeanStd,
    /// `τ_p`, width at half prominence, s.
    pub tau_p_s: MeanStd,
    /// Gaussian sigma, s.
    pub sigma_s: MeanStd,
    /// `τ_p / τ_c` per passage (thesis §6.4: 0.155).
    pub tau_p_over_tau_c: MeanStd,
    /// Pulse amplitude (prominence), V.
    pub amplitude_v: MeanStd,
    /// Measured ball-pass frequency `1 / mean τ_c`, Hz.
    pub f_c_measured_hz: f64,
    /// Predicted `v / (2 d_avg)`, Hz.
    pub f_c_predicted_hz: Option<f64>,
    /// `(measured − predicted) / predicted`.
    pub f_c_relative_error: Option<f64>,
    /// Mean ball spacing implied `v · mean τ_c / 2`, mm.
    pub d_avg_implied_mm: Option<f64>,
    /// Catalog `d_avg = d + d_ext / N_B`, mm.
    pub d_avg_catalog_mm: Option<f64>,
    /// Spread of spacings against the free-space limits.
    pub spacing: Option<SpacingSpread>,
    /// Conditions found (empty when the record is clean).
    pub conditions: Vec<Condition>,
    /// Pulse-train fits.
    pub fits: Option<TrainFits>,
    /// The settings used.
    pub settings: PassageSettings,
    /// Running baseline under the pulses, one value per sample, V: the fits
    /// and the pulse heights are of `optical − baseline`. Kept for plots,
    /// not serialised.
    #[serde(skip)]
    pub baseline_v: Vec<f64>,
}

/// Robust noise standard deviation from lag-`lag` differences:
/// `MAD(x[n+lag] − x[n]) / (0.67449 √2)`.
fn noise_sigma(x: &[f64], lag: usize) -> f64 {
    let lag = lag.max(1);
    if x.len() <= lag + 1 {
        return 0.0;
    }
    let mut keys: Vec<i64> = x
        .windows(lag + 1)
        .map(|w| order_key(w[lag] - w[0]))
        .collect();
    let med = percentile_of_keys(&mut keys, 50.0);
    for k in keys.iter_mut() {
        *k = order_key((from_order_key(*k) - med).abs());
    }
    percentile_of_keys(&mut keys, 50.0) / (0.674_489_750_196_081_7 * std::f64::consts::SQRT_2)
}

/// Non-robust fallback of [`noise_sigma`]: `rms(x[n+lag] − x[n]) / √2`.
fn rms_difference_sigma(x: &[f64], lag: usize) -> f64 {
    let lag = lag.max(1);
    if x.len() <= lag {
        return 0.0;
    }
    let m = (x.len() - lag) as f64;
    (x.windows(lag + 1)
        .map(|w| (w[lag] - w[0]).powi(2))
        .sum::<f64>()
        / m
        / 2.0)
        .sqrt()
}

fn median(v: &[f64]) -> f64 {
    percentile(v, 50.0)
}

/// Linear-interpolated percentile (numpy's default) of `v`.
fn percentile(v: &[f64], q: f64) -> f64 {
    let mut keys: Vec<i64> = v.iter().map(|&x| order_key(x)).collect();
    percentile_of_keys(&mut keys, q)
}

/// Running percentile over `window` samples, evaluated every `window / 4`
/// samples and linearly interpolated between.
fn running_percentile(x: &[f64], window: usize, q: f64) -> Vec<f64> {
    let n = x.len();
    let window = window.clamp(3, n.max(3));
    let hop = (window / 4).max(1);
    let mut centres: Vec<usize> = (0..n).step_by(hop).collect();
    if *centres.last().unwrap_or(&0) != n - 1 {
        centres.push(n - 1);
    }
    let mut keys = Vec::with_capacity(window);
    let levels: Vec<f64> = centres
        .iter()
        .map(|&c| {
            let lo = c.saturating_sub(window / 2);
            let hi = (c + window / 2 + 1).min(n);
            keys.clear();
            keys.extend(x[lo..hi].iter().map(|&v| order_key(v)));
            percentile_of_keys(&mut keys, q)
        })
        .collect();
    let mut out = vec![0.0; n];
    for w in 0..centres.len().saturating_sub(1) {
        let (c0, c1) = (centres[w], centres[w + 1]);
        for (i, o) in out.iter_mut().enumerate().take(c1 + 1).skip(c0) {
            let f = (i - c0) as f64 / (c1 - c0) as f64;
            *o = levels[w] + f * (levels[w + 1] - levels[w]);
        }
    }
    if centres.len() == 1 {
        out.fill(levels[0]);
    }
    out
}

struct Candidates {
    idx: Vec<usize>,
    prominence: Vec<f64>,
    width: Vec<f64>,
    left_ip: Vec<f64>,
    right_ip: Vec<f64>,
}

fn dsp(context: &str, e: ballpass_dsp::DspError) -> Error {
    Error::dsp(context.to_string(), e)
}

fn candidates(
    y: &[f64],
    threshold: f64,
    distance: Option<f64>,
    wlen: Option<f64>,
) -> Result<Candidates> {
    let peaks = find_peaks(
        y,
        &FindPeaksSettings {
            prominence: Some(Bound::at_least(threshold)),
            distance,
            wlen,
            ..Default::default()
        },
    )
    .map_err(|e| dsp("optical_V: find_peaks", e))?;
    // The widths at half prominence from the prominences find_peaks just
    // computed with the same `wlen` (what `peak_widths(y, peaks, 0.5, wlen)`
    // would compute again).
    let p = peaks.properties;
    let prominences = Prominences {
        prominences: p.prominences.unwrap_or_default(),
        left_bases: p.left_bases.unwrap_or_default(),
        right_bases: p.right_bases.unwrap_or_default(),
    };
    let w = peak_widths_with_prominences(y, &peaks.indices, 0.5, &prominences)
        .map_err(|e| dsp("optical_V: peak_widths", e))?;
    Ok(Candidates {
        prominence: prominences.prominences,
        idx: peaks.indices,
        width: w.widths,
        left_ip: w.left_ips,
        right_ip: w.right_ips,
    })
}

/// Keeps the candidates whose prominence is at least `rel` × the 75th
/// percentile of all.
fn keep_strong(c: Candidates, rel: f64) -> Candidates {
    if c.idx.is_empty() {
        return c;
    }
    let p75 = percentile(&c.prominence, 75.0);
    let keep: Vec<bool> = c.prominence.iter().map(|&v| v >= rel * p75).collect();
    let f = |v: Vec<f64>| -> Vec<f64> {
        v.into_iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(x, _)| x)
            .collect()
    };
    Candidates {
        idx: c
            .idx
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect(),
        prominence: f(c.prominence),
        width: f(c.width),
        left_ip: f(c.left_ip),
        right_ip: f(c.right_ip),
    }
}

/// Finds every ball passage in the optical channel of `rec`, measures it,
/// summarises the record, reports artefacts and fits the pulse-train models.
///
/// # Errors
/// [`Error::MissingChannel`] when the record has no optical channel;
/// [`Error::InvalidSetting`] for bad settings; [`Error::NoPassages`] when the
/// channel holds fewer than two pulses above the threshold (with the largest
/// bump found and the threshold in the message).
pub fn detect_passages(rec: &Recording, settings: &PassageSettings) -> Result<PassageAnalysis> {
    settings.validate()?;
    let x = rec.require(Channel::Optical, "ball-passage detection")?;
    let fs = rec.fs_hz();
    let n = x.len();
    let source = rec.source_name();
    let (velocity, velocity_source) = match (settings.velocity_mm_s, rec.meta.velocity_mm_s) {
        (Some(v), _) => (Some(v), "settings"),
        (None, Some(v)) => {
            check_velocity(v)?;
            (Some(v), "metadata")
        }
        (None, None) => (None, "none"),
    };
    let predicted = match (velocity, &settings.geometry) {
        (Some(v), Some(g)) => Some(g.predict(v, 1)?),
        _ => None,
    };
    let no_passages = |reason: String| Error::NoPassages {
        source_name: source.clone(),
        reason,
    };
    let x_range = x.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - x.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    if x_range <= 0.0 {
        return Err(no_passages("the optical signal is constant".into()));
    }

    // Period guide: predicted, else from the strongest pulses.
    let (tau_guide, guide_source) = match &predicted {
        Some(p) => (p.tau_c_s, "prediction"),
        None => {
            let mean = x.iter().sum::<f64>() / n as f64;
            let y0: Vec<f64> = x.iter().map(|v| v - mean).collect();
            let y0 = gaussian_smooth(&y0, 2.0);
            // Noise at a lag of 1 sample; refined below once the width is known.
            let sigma1 = noise_sigma(x, 1);
            let thr = (settings.min_snr * sigma1).max(1e-12 * x_range);
            let c = keep_strong(candidates(&y0, thr, None, None)?, 0.5);
            if c.idx.len() < 3 {
                return Err(no_passages(format!(
                    "found {} pulse(s) above {:.3e} V ({} noise sigma) without a velocity to guide the search; give the tracking velocity",
                    c.idx.len(),
                    thr,
                    settings.min_snr
                )));
            }
            let gaps: Vec<f64> = c
                .idx
                .windows(2)
                .map(|w| (w[1] - w[0]) as f64 / fs)
                .collect();
            (median(&gaps), "pulses")
        }
    };
    let tau_samples = tau_guide * fs;
    if tau_samples < 8.0 {
        return Err(Error::setting(
            "sampling rate",
            format!("{source}: a ball-pass period of {tau_guide:.4} s is only {tau_samples:.1} samples at {fs} Hz; need at least 8"),
        ));
    }
    if (n as f64) < 2.0 * tau_samples {
        return Err(no_passages(format!(
            "the record lasts {:.3} s, less than two ball-pass periods ({:.3} s each)",
            n as f64 / fs,
            tau_guide
        )));
    }

    // Baseline and noise.
    let window = (settings.baseline_periods * tau_samples).round() as usize;
    let baseline = running_percentile(x, window, settings.baseline_percentile);
    let y: Vec<f64> = x.iter().zip(&baseline).map(|(a, b)| a - b).collect();
    // A lag of ~1/40 of the expected pulse width keeps the pulses out of the
    // differences while catching noise that is not white sample to sample.
    let lag = ((0.3 * tau_samples) / 40.0).floor().max(1.0) as usize;
    let mut sigma = noise_sigma(x, lag);
    if sigma == 0.0 {
        // A quantised or synthetic signal can have a zero MAD; fall back to
        // the plain rms of the differences at lag 1 and at `lag`.
        sigma = [1, lag]
            .iter()
            .map(|&l| rms_difference_sigma(x, l))
            .fold(0.0, f64::max);
    }
    let floor = settings.min_snr * sigma;
    let threshold0 = floor.max(1e-9 * x_range);
    let distance = (settings.min_distance_periods * tau_samples).max(1.0);
    let wlen = Some((2.5 * tau_samples).max(3.0));

    // Detect and measure on a lightly smoothed copy: a Gaussian kernel of
    // σ_k = τ_c/200 cuts white noise several-fold (no noise spike reaches the
    // threshold, and noise does not bias the half-prominence crossings) while
    // widening a pulse by a known amount, undone below.
    let sigma_k = (0.005 * tau_samples).max(1.0);
    let ys = gaussian_smooth(&y, sigma_k);
    let up = candidates(&ys, threshold0, Some(distance), wlen)?;
    let neg: Vec<f64> = ys.iter().map(|v| -v).collect();
    let down = candidates(&neg, threshold0, Some(distance), wlen)?;
    // Reference pulse size: the 75th percentile of the larger family.
    let p75 = |c: &Candidates| {
        if c.prominence.is_empty() {
            0.0
        } else {
            percentile(&c.prominence, 75.0)
        }
    };
    let (p_up, p_down) = (p75(&up), p75(&down));
    let threshold = threshold0.max(settings.min_relative_prominence * p_up.max(p_down));
    let up = keep_strong_abs(up, threshold);
    let down = keep_strong_abs(down, threshold);
    if up.idx.is_empty() && down.idx.is_empty() {
        let largest = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        return Err(no_passages(format!(
            "no pulse stands out of the noise: largest excursion {largest:.3e} V, noise sigma {sigma:.3e} V, threshold {threshold:.3e} V ({} sigma)",
            settings.min_snr
        )));
    }

    // Upward pulses are passages. Downward ones are inverted passages only
    // when they stand apart from every upward pulse (an AC-coupling dip
    // follows its pulse closely) and are about as narrow as the pulses.
    let w_up = if up.width.is_empty() {
        f64::NAN
    } else {
        median(&up.width)
    };
    let mut events: Vec<(usize, i8, f64, f64, f64, f64)> = Vec::new(); // idx, pol, prom, width, lip, rip
    for i in 0..up.idx.len() {
        events.push((
            up.idx[i],
            1,
            up.prominence[i],
            up.width[i],
            up.left_ip[i],
            up.right_ip[i],
        ));
    }
    let mut inverted = 0;
    for i in 0..down.idx.len() {
        let d = down.idx[i];
        let far = up
            .idx
            .iter()
            .all(|&u| (u as f64 - d as f64).abs() >= 0.5 * tau_samples);
        let narrow =
            !w_up.is_finite() || (down.width[i] <= 2.5 * w_up && down.width[i] >= 0.3 * w_up);
        if far && narrow {
            events.push((
                d,
                -1,
                down.prominence[i],
                down.width[i],
                down.left_ip[i],
                down.right_ip[i],
            ));
            inverted += 1;
        }
    }
    events.sort_by_key(|e| e.0);
    if events.len() < 2 {
        return Err(no_passages(format!(
            "only {} pulse above {threshold:.3e} V ({:.1} noise sigma); at least two passages are needed to measure a period",
            events.len(),
            threshold / sigma.max(f64::MIN_POSITIVE)
        )));
    }

    let t_of = |i: f64| rec.meta.start_time_s + i / fs;
    let times: Vec<f64> = events.iter().map(|e| t_of(0.5 * (e.4 + e.5))).collect();
    let passages: Vec<Passage> = events
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let tau_c = times.get(k + 1).map(|t| t - times[k]);
            // Undo the smoothing: for a Gaussian pulse σ_m² = σ² + σ_k², and
            // the peak drops by σ/σ_m.
            let sig_m = e.3 / FWHM_PER_SIGMA;
            let sig = (sig_m * sig_m - sigma_k * sigma_k)
                .max(0.25 * sig_m * sig_m)
                .sqrt();
            let tau_p = sig * FWHM_PER_SIGMA / fs;
            let gain = sig_m / sig;
            Passage {
                index: k,
                time_s: times[k],
                peak_time_s: t_of(e.0 as f64),
                polarity: e.1,
                tau_c_s: tau_c,
                tau_p_s: tau_p,
                sigma_s: tau_p / FWHM_PER_SIGMA,
                amplitude_v: e.2 * gain,
                height_v: ys[e.0].abs() * gain,
                tau_p_over_tau_c: tau_c.map(|t| tau_p / t),
                spacing_mm: match (tau_c, velocity) {
                    (Some(t), Some(v)) => Some(v * t / 2.0),
                    _ => None,
                },
            }
        })
        .collect();

    let col = |f: &dyn Fn(&Passage) -> Option<f64>| -> Vec<f64> {
        passages.iter().filter_map(f).collect()
    };
    let tau_c_all = col(&|p| p.tau_c_s);
    let tau_c_stats =
        MeanStd::of(&tau_c_all).ok_or_else(|| no_passages("no period between passages".into()))?;
    let tau_p_stats = MeanStd::of(&col(&|p| Some(p.tau_p_s))).unwrap_or(tau_c_stats);
    let sigma_stats = MeanStd::of(&col(&|p| Some(p.sigma_s))).unwrap_or(tau_c_stats);
    let ratio_stats = MeanStd::of(&col(&|p| p.tau_p_over_tau_c)).unwrap_or(tau_c_stats);
    let amp_stats = MeanStd::of(&col(&|p| Some(p.amplitude_v))).unwrap_or(tau_c_stats);
    // Missed passages make a period twice as long; measure f_c on the
    // periods that are not gaps.
    let med_tau = median(&tau_c_all);
    let regular: Vec<f64> = tau_c_all
        .iter()
        .copied()
        .filter(|t| *t < 1.6 * med_tau)
        .collect();
    let tau_c_stats = MeanStd::of(&regular).unwrap_or(tau_c_stats);
    let f_c = 1.0 / tau_c_stats.mean;

    let mut conditions = Vec::new();
    let amps: Vec<f64> = passages.iter().map(|p| p.amplitude_v).collect();
    let med_amp = median(&amps);

    // Baseline drift: the level between the pulses, taken at the same places
    // of every regular gap (mid and late in the stretch free of pulses), varies
    // from gap to gap. A response locked to the pulses (AC-coupling recovery,
    // pulse tails) repeats in every gap and cancels; a drift does not. Works
    // for drifts slower or faster than the ball-pass period.
    let widths_all: Vec<f64> = events.iter().map(|e| e.3).collect();
    let fwhm_samples = median(&widths_all);
    let centres: Vec<f64> = events.iter().map(|e| 0.5 * (e.4 + e.5)).collect();
    let mut levels: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for w in centres.windows(2) {
        if w[1] - w[0] >= 1.6 * med_tau * fs {
            continue;
        }
        let margin = 1.2 * fwhm_samples;
        let (a, b) = (w[0] + margin, w[1] - margin);
        if b - a < 6.0 {
            continue;
        }
        let h = (0.04 * tau_samples).min((b - a) / 12.0).max(1.0);
        for (slot, q) in levels.iter_mut().zip([0.5, 5.0 / 6.0]) {
            let c = a + q * (b - a);
            let (lo, hi) = (
                (c - h).round() as usize,
                ((c + h).round() as usize).min(n - 1),
            );
            let seg = &x[lo..=hi];
            slot.push(seg.iter().sum::<f64>() / seg.len() as f64);
        }
    }
    if levels[0].len() >= 2 {
        let range = levels
            .iter()
            .map(|l| {
                l.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
                    - l.iter().fold(f64::INFINITY, |a, &b| a.min(b))
            })
            .fold(0.0, f64::max);
        if range > 0.1 * med_amp && range > 5.0 * sigma {
            conditions.push(Condition {
                kind: ConditionKind::BaselineDrift,
                measure: range / med_amp,
                message: format!(
                    "the level between the pulses wanders by {range:.3e} V ({:.0}% of the median pulse) from one gap to another",
                    100.0 * range / med_amp
                ),
                advice: "pulses were measured against a running baseline, so counts and widths hold; a wandering level with a laser source is the strain-dependent interference of thesis §5.2 (Figs. 32, 36): use an incoherent source (LED, thesis §5.3) and keep the fibre still".into(),
            });
        }
    }

    // AC coupling: level just after each upward pulse lower than just before,
    // beyond the baseline's own slope there.
    let mut asym = Vec::new();
    for (k, e) in events.iter().enumerate() {
        if e.1 != 1 {
            continue;
        }
        let c = 0.5 * (e.4 + e.5);
        let w = e.3.max(2.0);
        let mean_over = |a: f64, b: f64| -> Option<f64> {
            let (a, b) = (a.round(), b.round());
            if a < 0.0 || b as usize >= n || b <= a {
                return None;
            }
            let s = &x[a as usize..=b as usize];
            Some(s.iter().sum::<f64>() / s.len() as f64)
        };
        let (Some(l), Some(r)) = (
            mean_over(c - 1.5 * w, c - 1.0 * w),
            mean_over(c + 1.0 * w, c + 1.5 * w),
        ) else {
            continue;
        };
        let bl = baseline[((c - 1.25 * w).round() as usize).min(n - 1)];
        let br = baseline[((c + 1.25 * w).round() as usize).min(n - 1)];
        let _ = k;
        asym.push(((l - r) - (bl - br)) / e.2);
    }
    if asym.len() >= 3 {
        let positive = asym.iter().filter(|a| **a > 0.0).count() as f64 / asym.len() as f64;
        let med = median(&asym);
        // Consistency: AC coupling gives every pulse the same dip; a level
        // that drifts across the pulses gives dips and rises at random.
        // Student's t of the mean dip must exceed 3.
        let t_stat = MeanStd::of(&asym).map_or(0.0, |s| {
            if s.std > 0.0 {
                s.mean / (s.std / (s.n as f64).sqrt())
            } else {
                f64::INFINITY * s.mean.signum()
            }
        });
        if med > 0.02 && positive >= 0.7 && t_stat > 3.0 {
            conditions.push(Condition {
                kind: ConditionKind::AcCoupling,
                measure: med,
                message: format!(
                    "the signal after each pulse sits {:.0}% of the pulse height below the level before it ({:.0}% of the pulses): the photodetector was AC coupled and the coupling compensates the slow pulse (thesis Fig. 38)",
                    100.0 * med,
                    100.0 * positive
                ),
                advice: "record the photodetector DC coupled (thesis Fig. 39): AC coupling distorts the pulse profile, so the widths tau_p and the fits of this record are biased, and passage times come early by about sigma^2 / T (pulse sigma, coupling time constant T) when the pulses are not short against T".into(),
            });
        }
    }

    if inverted > 0 {
        conditions.push(Condition {
            kind: ConditionKind::InvertedPulses,
            measure: inverted as f64 / events.len() as f64,
            message: format!(
                "{inverted} of {} passages are inverted pulses: interference between the incident and reflected light of a coherent source (thesis Fig. 32)",
                events.len()
            ),
            advice: "use an incoherent light source (LED, thesis §5.3) or multimode fibre; AC coupling does not cure it. Amplitudes of this record are not comparable between passages; inverted passages are counted and timed, polarity −1".into(),
        });
    }

    let gaps = tau_c_all.iter().filter(|t| **t >= 1.6 * med_tau).count();
    if gaps > 0 {
        let missing: f64 = tau_c_all
            .iter()
            .filter(|t| **t >= 1.6 * med_tau)
            .map(|t| (t / med_tau).round() - 1.0)
            .sum();
        conditions.push(Condition {
            kind: ConditionKind::MissedPassages,
            measure: missing,
            message: format!(
                "{gaps} gap(s) of 1.6 periods or more: about {missing:.0} passage(s) too weak to detect"
            ),
            advice: "weak passages fall below the threshold: lower min_snr only if the noise allows; fading pulses with a laser source are the interference of thesis Fig. 32 (use an LED)".into(),
        });
    }

    let f_c_predicted = predicted.as_ref().map(|p| p.f_c_hz);
    let rel_err = f_c_predicted.map(|p| (f_c - p) / p);
    if let (Some(e), Some(p)) = (rel_err, f_c_predicted) {
        if e.abs() > 0.2 {
            conditions.push(Condition {
                kind: ConditionKind::PeriodMismatch,
                measure: e,
                message: format!(
                    "measured f_c = {f_c:.4} Hz is {:+.0}% from the predicted {p:.4} Hz",
                    100.0 * e
                ),
                advice: "check the tracking velocity and the bearing geometry given; passages closer than 0.7 predicted periods are merged".into(),
            });
        }
    }

    let d_avg_implied = velocity.map(|v| v * tau_c_stats.mean / 2.0);
    let spacing = match (velocity, &settings.geometry) {
        (Some(v), Some(g)) => {
            let s: Vec<f64> = regular.iter().map(|t| v * t / 2.0).collect();
            MeanStd::of(&s).map(|ms| {
                let min = s.iter().fold(f64::INFINITY, |a, &b| a.min(b));
                let max = s.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
                let (lo, hi) = (g.ball_diameter_mm, g.ball_diameter_mm + g.free_space_mm);
                // One sample of timing error at each end of a period.
                let tol = v / fs;
                SpacingSpread {
                    min_mm: min,
                    max_mm: max,
                    std_mm: ms.std,
                    limit_min_mm: lo,
                    limit_max_mm: hi,
                    spread_over_free_space: if g.free_space_mm > 0.0 {
                        (max - min) / g.free_space_mm
                    } else {
                        f64::INFINITY
                    },
                    outside_limits: s
                        .iter()
                        .filter(|d| **d < lo - tol || **d > hi + tol)
                        .count(),
                }
            })
        }
        _ => None,
    };

    let fits = if settings.fit_pulses >= 2 && inverted == 0 {
        Some(fit_trains(
            &y,
            fs,
            rec.meta.start_time_s,
            &passages,
            settings,
            med_amp,
        ))
    } else {
        None
    };

    Ok(PassageAnalysis {
        source,
        fs_hz: fs,
        duration_s: rec.duration_s(),
        velocity_mm_s: velocity,
        velocity_source: velocity_source.into(),
        tau_c_guide_s: tau_guide,
        tau_c_guide_source: guide_source.into(),
        noise_v: sigma,
        prominence_threshold_v: threshold,
        count: passages.len(),
        count_inverted: inverted,
        tau_c_s: tau_c_stats,
        tau_p_s: tau_p_stats,
        sigma_s: sigma_stats,
        tau_p_over_tau_c: ratio_stats,
        amplitude_v: amp_stats,
        f_c_measured_hz: f_c,
        f_c_predicted_hz: f_c_predicted,
        f_c_relative_error: rel_err,
        d_avg_implied_mm: d_avg_implied,
        d_avg_catalog_mm: settings.geometry.as_ref().map(|g| g.d_avg_mm()),
        spacing,
        conditions,
        fits,
        passages,
        settings: settings.clone(),
        baseline_v: baseline,
    })
}

/// Kernels longer than this many taps are applied by FFT (the same sums,
/// rounded differently; `gaussian_smooth_equals_the_plain_sum` bounds the
/// difference at 1e-13 for unit-scale noise), shorter ones directly.
const FFT_TAPS: usize = 64;

/// The unit-area Gaussian of `sigma` samples truncated at 4σ (and to fit a
/// signal of `n` samples): its half-length and its `2 half + 1` taps.
fn gaussian_kernel(sigma: f64, n: usize) -> (usize, Vec<f64>) {
    let half = ((4.0 * sigma).ceil() as usize).min(n.saturating_sub(1));
    let mut k: Vec<f64> = (0..=2 * half)
        .map(|i| {
            let u = (i as f64 - half as f64) / sigma;
            (-0.5 * u * u).exp()
        })
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    (half, k)
}

/// Convolution with a unit-area Gaussian of `sigma` samples (truncated at
/// 4σ), with the signal mirrored at both ends.
fn gaussian_smooth(x: &[f64], sigma: f64) -> Vec<f64> {
    let n = x.len();
    let (half, k) = gaussian_kernel(sigma, n);
    let at = |i: isize| -> f64 {
        let n = n as isize;
        let j = if i < 0 {
            -i
        } else if i >= n {
            2 * (n - 1) - i
        } else {
            i
        };
        x[j.clamp(0, n - 1) as usize]
    };
    let edge = |i: usize| -> f64 {
        k.iter()
            .enumerate()
            .map(|(j, w)| w * at(i as isize + j as isize - half as isize))
            .sum()
    };
    if k.len() > FFT_TAPS && n > k.len() {
        // A long kernel (slow tracking: σ_k = τ_c/200 is 40 samples at
        // 1 mm/s and 1 kHz, 325 taps) by FFT: the mirrored signal
        // correlated with the symmetric kernel, whose lag `i` is output `i`.
        let padded: Vec<f64> = (0..n + 2 * half)
            .map(|m| at(m as isize - half as isize))
            .collect();
        if let Ok(c) = ballpass_dsp::correlate(&padded, &k, ballpass_dsp::Normalization::None) {
            return c.values[k.len() - 1..k.len() - 1 + n].to_vec();
        }
    }
    // Where the kernel lies inside the signal, outputs `lo..hi` are the
    // plain sums of `w_j x_(i-half+j)` in the order of `j` (the value `edge`
    // gives), computed side by side with the CPU's vectors.
    let lo = half.min(n);
    let hi = n.saturating_sub(half).max(lo);
    let mut out: Vec<f64> = Vec::with_capacity(n);
    out.extend((0..lo).map(edge));
    if hi > lo {
        // The slice holds `hi - lo + 2 half >= k.len()` samples, neither
        // empty: `correlate_valid` has nothing to reject.
        out.extend(
            ballpass_dsp::correlate_valid(&x[lo - half..hi + half], &k)
                .expect("the kernel fits inside the slice"),
        );
    }
    out.extend((hi..n).map(edge));
    out
}

fn keep_strong_abs(c: Candidates, threshold: f64) -> Candidates {
    let keep: Vec<bool> = c.prominence.iter().map(|&p| p >= threshold).collect();
    let f = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect()
    };
    Candidates {
        idx: c
            .idx
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(x, _)| *x)
            .collect(),
        prominence: f(&c.prominence),
        width: f(&c.width),
        left_ip: f(&c.left_ip),
        right_ip: f(&c.right_ip),
    }
}

fn quality(
    resid: &[f64],
    data: &[f64],
    med_amp: f64,
    iterations: usize,
    converged: bool,
) -> FitQuality {
    let m = data.len().max(1) as f64;
    let mean = data.iter().sum::<f64>() / m;
    let ss_tot: f64 = data.iter().map(|v| (v - mean).powi(2)).sum();
    let ss_res: f64 = resid.iter().map(|v| v * v).sum();
    let rms = (ss_res / m).sqrt();
    FitQuality {
        rms_residual_v: rms,
        rms_over_amplitude: rms / med_amp,
        r_squared: if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else {
            0.0
        },
        samples: data.len(),
        iterations,
        converged,
    }
}

/// Fits the Gaussian (Eq. 6.24) and rectangular (Eq. 6.22 corrected) trains
/// to the first `fit_pulses` passages of the baseline-removed signal (the
/// whole record when it has no more).
fn fit_trains(
    y: &[f64],
    fs: f64,
    t_start: f64,
    passages: &[Passage],
    settings: &PassageSettings,
    med_amp: f64,
) -> TrainFits {
    let k = settings.fit_pulses.min(passages.len());
    let used = &passages[..k];
    let tau0 = {
        let t: Vec<f64> = used
            .iter()
            .filter_map(|p| p.tau_c_s)
            .take(k.saturating_sub(1))
            .collect();
        if t.is_empty() {
            passages[1].time_s - passages[0].time_s
        } else {
            median(&t)
        }
    };
    let from = (used[0].time_s - 0.5 * tau0).max(t_start);
    let to = (used[k - 1].time_s + 0.5 * tau0).min(t_start + y.len() as f64 / fs);
    let i0 = ((from - t_start) * fs).ceil().max(0.0) as usize;
    let i1 = (((to - t_start) * fs).floor() as usize).min(y.len() - 1);
    // At most FIT_SAMPLES_PER_PERIOD samples per period keeps the fit cheap;
    // the pulses (FWHM ≈ 0.155 τ_c) are still sampled ~20 times at half height.
    let stride = ((tau0 * fs / FIT_SAMPLES_PER_PERIOD).floor() as usize).max(1);
    let idx: Vec<usize> = (i0..=i1).step_by(stride).collect();
    let t: Vec<f64> = idx.iter().map(|&i| t_start + i as f64 / fs).collect();
    let d: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
    let m = t.len();
    let mut fits = TrainFits {
        from_s: from,
        to_s: to,
        pulses: k,
        gaussian: None,
        rectangular: None,
        better: None,
        notes: Vec::new(),
    };
    if m < 8 + k {
        fits.notes.push(format!(
            "only {m} samples between {from:.3} s and {to:.3} s for {k} pulses: no fit"
        ));
        return fits;
    }
    let widths: Vec<f64> = used.iter().map(|p| p.tau_p_s).collect();
    let tau_p0 = median(&widths);
    let sigma0 = tau_p0 / FWHM_PER_SIGMA;

    // Gaussian: θ = [S, t0, τ, σ, P_0 .. P_{k−1}], started from the
    // detections (first centre, median period and width, each prominence).
    let mut th0 = vec![0.0, used[0].time_s, tau0, sigma0];
    th0.extend(used.iter().map(|p| p.amplitude_v));
    match train_fit::fit_gaussian(&t, &d, &th0) {
        Ok(g) => {
            let sig = g.params[3].abs();
            fits.gaussian = Some(GaussianTrainFit {
                dc_v: g.params[0],
                t0_s: g.params[1],
                tau_c_s: g.params[2],
                sigma_s: sig,
                tau_p_s: FWHM_PER_SIGMA * sig,
                amplitudes_v: g.params[train_fit::G_AMP0..].to_vec(),
                quality: quality(&g.residuals, &d, med_amp, g.iterations, g.converged),
            });
        }
        Err(e) => fits.notes.push(format!("Gaussian train fit failed: {e}")),
    }

    // Rectangular, order N: θ = [S, P, t_s, τ, r]; the pulse occupies
    // [t_s + τ − rτ, t_s + τ) of each period (Eq. 6.18).
    let order = settings.rectangular_order;
    let r0 = (tau_p0 / tau0).clamp(0.01, 0.9);
    // Centre of the first pulse at t_s + τ(1 − r/2).
    let ts0 = used[0].time_s - tau0 * (1.0 - r0 / 2.0);
    match train_fit::fit_rectangular(&t, &d, &[0.0, med_amp, ts0, tau0, r0], order) {
        Ok(rf) => {
            fits.rectangular = Some(RectangularTrainFit {
                dc_v: rf.params[0],
                amplitude_v: rf.params[1],
                t_start_s: rf.params[2],
                tau_c_s: rf.params[3],
                tau_p_s: rf.params[4] * rf.params[3],
                ratio: rf.params[4],
                order,
                quality: quality(&rf.residuals, &d, med_amp, rf.iterations, rf.converged),
            });
        }
        Err(e) => fits
            .notes
            .push(format!("rectangular train fit failed: {e}")),
    }
    if let (Some(a), Some(b)) = (&fits.gaussian, &fits.rectangular) {
        fits.better = Some(
            if a.quality.rms_residual_v <= b.quality.rms_residual_v {
                "gaussian"
            } else {
                "rectangular"
            }
            .into(),
        );
    }
    fits
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bearing::lookup;
    use crate::recording::{Channels, Metadata};

    /// The blocked Gaussian smoothing equals the plain per-sample sum (the
    /// previous implementation, kept here as the reference) bit for bit, for
    /// signals shorter than, as long as and much longer than the kernel;
    /// long kernels (by FFT) equal it to rounding.
    #[test]
    fn gaussian_smooth_equals_the_plain_sum() {
        fn plain(x: &[f64], sigma: f64) -> Vec<f64> {
            let n = x.len();
            let (half, k) = gaussian_kernel(sigma, n);
            let at = |i: isize| -> f64 {
                let n = n as isize;
                let j = if i < 0 {
                    -i
                } else if i >= n {
                    2 * (n - 1) - i
                } else {
                    i
                };
                x[j.clamp(0, n - 1) as usize]
            };
            (0..n)
                .map(|i| {
                    k.iter()
                        .enumerate()
                        .map(|(j, w)| w * at(i as isize + j as isize - half as isize))
                        .sum()
                })
                .collect()
        }
        let mut rng = Rng(5);
        for (n, sigma) in [
            (1_usize, 2.0),
            (5, 2.0),
            (17, 2.0),
            (18, 2.0),
            (40, 7.5),
            (3001, 2.0),
            (3001, 7.5),
            (3001, 23.7),
            (30_000, 40.5),
        ] {
            let x: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            let got = gaussian_smooth(&x, sigma);
            let want = plain(&x, sigma);
            let taps = gaussian_kernel(sigma, n).1.len();
            if taps > FFT_TAPS && n > taps {
                // By FFT: the same sums, rounded differently. The outputs are
                // O(0.1) for unit noise; 1e-13 absolute is ~1000 ulp of them.
                let err = got
                    .iter()
                    .zip(&want)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                assert!(err < 1e-13, "n {n}, sigma {sigma}: {err:e}");
            } else {
                let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&got), bits(&want), "n {n}, sigma {sigma}");
            }
        }
    }

    /// A small deterministic generator (SplitMix64 + Box–Muller) so the tests
    /// need no dependency and are reproducible.
    struct Rng(u64);
    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn uniform(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let u1 = self.uniform().max(1e-300);
            let u2 = self.uniform();
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
    }

    struct Synth {
        fs: f64,
        velocity: f64,
        duration_s: f64,
        /// FWHM / τ_c of the pulses.
        fwhm_ratio: f64,
        amplitude: f64,
        noise: f64,
        /// Relative spacing jitter (uniform ±).
        jitter: f64,
        drift_amp: f64,
        drift_period_s: f64,
        /// High-pass time constant, s (0: DC coupled).
        ac_tau_s: f64,
        /// Interference: pulses multiplied by cos(2π t / period) (0: none).
        interference_period_s: f64,
        seed: u64,
    }

    impl Default for Synth {
        fn default() -> Self {
            Self {
                fs: 1000.0,
                velocity: 10.0,
                duration_s: 30.0,
                fwhm_ratio: 0.155,
                amplitude: 0.5,
                noise: 0.01,
                jitter: 0.0,
                drift_amp: 0.0,
                drift_period_s: 20.0,
                ac_tau_s: 0.0,
                interference_period_s: 0.0,
                seed: 7,
            }
        }
    }

    /// Returns the recording and the true passage times.
    fn synth(s: &Synth) -> (Recording, Vec<f64>) {
        let g = lookup("sr25w").unwrap().geometry;
        let tau_c = 2.0 * g.d_avg_mm() / s.velocity;
        let mut rng = Rng(s.seed);
        let mut times = Vec::new();
        let mut t = 0.37 * tau_c;
        while t < s.duration_s - 0.3 * tau_c {
            times.push(t);
            t += tau_c * (1.0 + s.jitter * (2.0 * rng.uniform() - 1.0));
        }
        let n = (s.duration_s * s.fs) as usize;
        let sigma = s.fwhm_ratio * tau_c / FWHM_PER_SIGMA;
        let mut x: Vec<f64> = (0..n)
            .map(|i| {
                let ti = i as f64 / s.fs;
                let mut v = 1.0;
                let mut pulses = 0.0;
                for &c in &times {
                    let u = (ti - c) / sigma;
                    if u.abs() < 10.0 {
                        pulses += (-0.5 * u * u).exp();
                    }
                }
                let gain = if s.interference_period_s > 0.0 {
                    (2.0 * std::f64::consts::PI * ti / s.interference_period_s).cos()
                } else {
                    1.0
                };
                v += s.amplitude * gain * pulses;
                v += s.drift_amp * (2.0 * std::f64::consts::PI * ti / s.drift_period_s).sin();
                if s.interference_period_s > 0.0 {
                    v += 0.3 * (2.0 * std::f64::consts::PI * ti / s.interference_period_s).cos();
                }
                v + s.noise * rng.normal()
            })
            .collect();
        if s.ac_tau_s > 0.0 {
            // First-order RC high-pass, exact for the sampled input held
            // between samples: y[n] = α (y[n−1] + x[n] − x[n−1]).
            let a = s.ac_tau_s / (s.ac_tau_s + 1.0 / s.fs);
            let mut prev_x = x[0];
            let mut prev_y = 0.0;
            for v in x.iter_mut() {
                let yv = a * (prev_y + *v - prev_x);
                prev_x = *v;
                prev_y = yv;
                *v = yv;
            }
        }
        let rec = Recording::new(
            s.fs,
            Channels {
                optical_v: Some(x),
                ..Default::default()
            },
            Metadata {
                velocity_mm_s: Some(s.velocity),
                test_id: Some("synthetic".into()),
                ..Default::default()
            },
        )
        .unwrap();
        (rec, times)
    }

    fn settings() -> PassageSettings {
        PassageSettings {
            geometry: Some(lookup("sr25w").unwrap().geometry),
            ..Default::default()
        }
    }

    fn kinds(a: &PassageAnalysis) -> Vec<ConditionKind> {
        a.conditions.iter().map(|c| c.kind).collect()
    }

    /// Every true passage matched by exactly one detection within a tenth of a period.
    fn assert_all_found(a: &PassageAnalysis, truth: &[f64], tau_c: f64) {
        assert_eq!(a.count, truth.len(), "count: {:?}", kinds(a));
        for (p, t) in a.passages.iter().zip(truth) {
            assert!(
                (p.time_s - t).abs() < 0.1 * tau_c,
                "passage at {} vs {t}",
                p.time_s
            );
        }
    }

    #[test]
    fn clean_records_at_1_to_20_mm_s_are_measured_within_spec() {
        let g = lookup("sr25w").unwrap().geometry;
        for v in [1.0, 2.0, 5.0, 9.0, 14.0, 20.0] {
            let tau_c = 2.0 * g.d_avg_mm() / v;
            let s = Synth {
                velocity: v,
                duration_s: (12.0 * tau_c).max(20.0),
                seed: v as u64,
                ..Default::default()
            };
            let (rec, truth) = synth(&s);
            let a = detect_passages(&rec, &settings()).unwrap();
            assert_all_found(&a, &truth, tau_c);
            // Issue targets: τ_c within 0.5 %, τ_p/τ_c within 3 %.
            assert!(
                (a.tau_c_s.mean / tau_c - 1.0).abs() < 0.005,
                "v = {v}: {}",
                a.tau_c_s.mean
            );
            assert!(
                (a.tau_p_over_tau_c.mean / 0.155 - 1.0).abs() < 0.03,
                "v = {v}: {}",
                a.tau_p_over_tau_c.mean
            );
            assert!(a.conditions.is_empty(), "v = {v}: {:?}", a.conditions);
            assert_eq!(a.velocity_source, "metadata");
            // d_avg implied matches the catalog to the τ_c accuracy.
            assert!((a.d_avg_implied_mm.unwrap() / g.d_avg_mm() - 1.0).abs() < 0.005);
        }
    }

    #[test]
    fn noisy_jittered_record_finds_every_passage_and_spacing_limits() {
        let s = Synth {
            noise: 0.05,
            jitter: 0.2,
            seed: 11,
            ..Default::default()
        };
        let (rec, truth) = synth(&s);
        let tau_c = 2.0 * 4.05556 / 10.0;
        let a = detect_passages(&rec, &settings()).unwrap();
        assert_all_found(&a, &truth, tau_c);
        let sp = a.spacing.unwrap();
        // Jitter ±20 % of 4.056 mm spans 3.24–4.87 mm: some below d = 4 mm.
        assert!(sp.min_mm < 4.0 && sp.outside_limits > 0);
        assert_eq!((sp.limit_min_mm, sp.limit_max_mm), (4.0, 6.0));
        // Artefacts that were not simulated are not reported.
        for k in [
            ConditionKind::BaselineDrift,
            ConditionKind::AcCoupling,
            ConditionKind::InvertedPulses,
        ] {
            assert!(!kinds(&a).contains(&k), "{:?}", a.conditions);
        }
    }

    #[test]
    fn drift_is_reported_and_does_not_break_detection() {
        let s = Synth {
            drift_amp: 0.4,
            drift_period_s: 25.0,
            ..Default::default()
        };
        let (rec, truth) = synth(&s);
        let a = detect_passages(&rec, &settings()).unwrap();
        assert_all_found(&a, &truth, 0.811);
        assert!(
            kinds(&a).contains(&ConditionKind::BaselineDrift),
            "{:?}",
            a.conditions
        );
        assert!(!kinds(&a).contains(&ConditionKind::AcCoupling));
        assert!((a.tau_c_s.mean / 0.811111 - 1.0).abs() < 0.005);
    }

    #[test]
    fn ac_coupling_dips_are_reported() {
        // Thesis Fig. 38: slow pulses (0.5–1 mm/s) through an AC coupling.
        let s = Synth {
            velocity: 1.0,
            duration_s: 100.0,
            ac_tau_s: 5.0,
            ..Default::default()
        };
        let (rec, truth) = synth(&s);
        let a = detect_passages(&rec, &settings()).unwrap();
        assert_all_found(&a, &truth, 8.111);
        assert!(
            kinds(&a).contains(&ConditionKind::AcCoupling),
            "{:?}",
            a.conditions
        );
        assert!(!kinds(&a).contains(&ConditionKind::InvertedPulses));
        let c = a
            .conditions
            .iter()
            .find(|c| c.kind == ConditionKind::AcCoupling)
            .unwrap();
        assert!(c.advice.contains("DC coupled"));
    }

    #[test]
    fn inverted_pulses_are_reported_as_interference() {
        // Thesis Fig. 32: pulses inverted on the crests of a 5 s interference fringe.
        let s = Synth {
            velocity: 20.0,
            duration_s: 20.0,
            interference_period_s: 5.0,
            ..Default::default()
        };
        let (rec, _) = synth(&s);
        let a = detect_passages(&rec, &settings()).unwrap();
        assert!(
            kinds(&a).contains(&ConditionKind::InvertedPulses),
            "{:?}",
            a.conditions
        );
        assert!(a.count_inverted > 5);
        let c = a
            .conditions
            .iter()
            .find(|c| c.kind == ConditionKind::InvertedPulses)
            .unwrap();
        assert!(c.advice.contains("incoherent"));
    }

    #[test]
    fn velocity_free_mode_finds_the_period_from_the_pulses() {
        let (mut rec, truth) = synth(&Synth::default());
        rec.meta.velocity_mm_s = None;
        let a = detect_passages(&rec, &PassageSettings::default()).unwrap();
        assert_eq!(a.tau_c_guide_source, "pulses");
        assert_all_found(&a, &truth, 0.811);
        assert!(
            a.f_c_predicted_hz.is_none() && a.spacing.is_none() && a.d_avg_implied_mm.is_none()
        );
    }

    #[test]
    fn gaussian_fit_beats_rectangular_on_gaussian_pulses() {
        let (rec, _) = synth(&Synth::default());
        let a = detect_passages(&rec, &settings()).unwrap();
        let f = a.fits.unwrap();
        // The default fits the whole record's train (37 pulses here).
        assert_eq!(f.pulses, a.count);
        assert!(f.notes.is_empty(), "{:?}", f.notes);
        let g = f.gaussian.unwrap();
        let r = f.rectangular.unwrap();
        assert_eq!(f.better.as_deref(), Some("gaussian"));
        // Noise 0.01 on pulses of 0.5: a correct model leaves ~2 % of the amplitude.
        assert!(g.quality.rms_over_amplitude < 0.03, "{:?}", g.quality);
        assert!(r.quality.rms_over_amplitude > g.quality.rms_over_amplitude);
        assert!((g.tau_c_s / 0.811111 - 1.0).abs() < 0.005);
        assert!((g.tau_p_s / (0.155 * 0.811111) - 1.0).abs() < 0.03);
        assert!(g.amplitudes_v.iter().all(|p| (p - 0.5).abs() < 0.05));
    }

    #[test]
    fn no_optical_channel_or_no_pulses_is_a_clear_error() {
        let rec = Recording::new(
            1000.0,
            Channels {
                friction_n: Some(vec![0.0; 5000]),
                ..Default::default()
            },
            Metadata::default(),
        )
        .unwrap();
        let e = detect_passages(&rec, &settings()).unwrap_err().to_string();
        assert!(e.contains("optical_V is missing"), "{e}");
        let mut rng = Rng(3);
        let noise: Vec<f64> = (0..20000).map(|_| 0.01 * rng.normal()).collect();
        let rec = Recording::new(
            1000.0,
            Channels {
                optical_v: Some(noise),
                ..Default::default()
            },
            Metadata {
                velocity_mm_s: Some(10.0),
                ..Default::default()
            },
        )
        .unwrap();
        let e = detect_passages(&rec, &settings()).unwrap_err();
        assert!(matches!(e, Error::NoPassages { .. }), "{e}");
        assert!(e.to_string().contains("no ball passages"), "{e}");
    }

    #[test]
    fn helpers_are_right() {
        let v = vec![3.0, 1.0, 2.0, 4.0];
        // numpy.percentile([1,2,3,4], 25) = 1.75
        assert!((percentile(&v, 25.0) - 1.75).abs() < 1e-15);
        let mut rng = Rng(5);
        let x: Vec<f64> = (0..100_000).map(|_| 2.0 * rng.normal()).collect();
        // MAD estimate of σ = 2 from 1e5 samples: standard error ≈ 1.1 %.
        assert!((noise_sigma(&x, 1) / 2.0 - 1.0).abs() < 0.03);
        let b = running_percentile(&[5.0; 100], 20, 10.0);
        assert!(b.iter().all(|v| *v == 5.0));
    }
}
