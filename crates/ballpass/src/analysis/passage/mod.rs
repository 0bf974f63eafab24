//! Ball passages seen by the optical sensor (thesis §5, §6.3–6.4).
//!
//! Every ball passing the fibre tip reflects light back up the fibre: a pulse
//! in the photodetector voltage. [`detect_passages`] finds each pulse,
//! measures it, summarises the record and fits the two pulse-train models of
//! §6.3 (Gaussian Eq. 6.24 and rectangular Eq. 6.22, as corrected in docs/methods.md §5).
//!
//! # Method
//!
//! The pulses are measured against the record's own mean pulse (the
//! *template*), not one by one on the raw signal: where pulses overlap (a
//! FWHM of 0.3 τ_c and more), the width at half prominence of the sum is not
//! the width of a pulse, and a width read on one noisy pulse is biased by
//! its noise.
//!
//! ```text
//! noise σ        = MAD(x[n+L] − x[n]) / (0.67449 √2)        (L ≪ pulse width)
//! seeds          = find_peaks of x − (running 10th percentile), smoothed by τ_c/100,
//!                  above the threshold for that smoothing, ≥ 0.7 τ_c apart
//! blocks         = means of q samples, q = ⌊seed FWHM / 24⌋ (white noise σ/√q;
//!                  the pulse widens by 0.04 % at most)
//! repeat until the pulses found stop changing:
//!   least squares   blocks = spline baseline (knots τ_c apart) + Σ_k a_k h((n − c_k)/s_k)
//!                            [− κ ∫ blocks dt]                                (lsq.rs)
//!   each pulse      a_k, c_k, s_k (and a local offset) fitted against h with the
//!                   neighbours' modelled pulses removed
//!   search          matched filter of the restored, baseline-removed signal with h,
//!                   threshold from the false-detection rate               (scan.rs)
//! τ_p(k)         = s_k × FWHM(h)                 (full width at half maximum of the
//!                                                  pulse alone; CONVENTIONS.md's width
//!                                                  at half prominence of an isolated pulse)
//! σ_pulse        = τ_p / (2 √(2 ln 2))
//! time           = c_k + s_k × midpoint of h's half-maximum crossings
//! τ_c(k)         = time(k+1) − time(k);  spacing(k) = v τ_c(k) / 2
//! ```
//!
//! - **Overlap.** The template is the least-squares solution with every
//!   pulse's neighbours in the model, so the tails that overlap are shared
//!   out, not added to the pulse; each pulse's width is then fitted with its
//!   neighbours' modelled pulses subtracted. The baseline is a cubic spline
//!   with knots one period apart, blind to the ball-pass frequency and its
//!   harmonics (its spectrum is `sinc⁴(f τ_c)`), so it cannot take the
//!   train's shape.
//! - **Noise.** A width fitted by least squares is unbiased to first order
//!   in the noise; the template averages all pulses.
//! - **Record ends.** A pulse within two half widths of the record's start
//!   or end is cut: it is counted and timed when its centre is inside the
//!   record (`edge: true`), and left out of the widths (`width_used: false`).
//! - **Detection.** The threshold is set on the noise of the signal
//!   searched (the matched filter's output, measured on the model's
//!   residual), for [`PassageSettings::false_detections_per_record`]
//!   expected false detections per record in white Gaussian noise (Rice's
//!   formula, `scan.rs`), and at least [`PassageSettings::min_snr`].
//!   Passages of both polarities are searched together, strongest first,
//!   at least 0.7 τ_c apart, so the valley between two wide pulses is
//!   never taken for an inverted pulse.
//! - **AC coupling.** A first-order high-pass of time constant `T` gives
//!   `y' = x' − y/T`, so `x = y + (1/T) ∫ y dt`: the template of the
//!   restored signal is that of the blocks plus `κ = 1/T` times that of
//!   their running integral. A pulse of light starts and ends at the level
//!   around it, so `κ` is the rate at which the restored template ends
//!   where it starts (its last three grid points against its first three,
//!   with the neighbours' tails taken out, re-estimated on every
//!   least-squares pass); a step smaller than 0.5 % of the pulse or three
//!   standard errors is no coupling. The step is the AC coupling's
//!   signature whatever the pulse's shape (a dip after the pulse is not: a
//!   skewed pulse's long tail hides it). A coupling is kept only if the
//!   light level it restores is one a photodetector could have seen: the
//!   coupling takes the light's running mean out, so the record's mean,
//!   integrated back, may ramp the restored level by the light's own drift
//!   and at most the pulses' mean, not by `duration / T` times the
//!   record's DC level (the step that wide pulses' tails leave on a
//!   DC-coupled record reads as a slow coupling, and fails this).
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
//! - [`ConditionKind::BaselineDrift`]: the fitted baseline wanders over the
//!   record by more than 20 % of the median pulse and 5 block noises
//!   (thesis Figs. 32, 36).
//! - [`ConditionKind::AcCoupling`]: an AC coupling was found (and undone)
//!   whose dip per pulse (pulse area over `T`) is at least 2 % of the pulse
//!   (thesis Fig. 38).
//! - [`ConditionKind::InvertedPulses`]: pulses pointing down, the signature of
//!   interference with a coherent source (thesis Fig. 32, §5.2).
//! - [`ConditionKind::MissedPassages`]: gaps longer than 1.6 τ_c (their
//!   median); or, when the velocity and geometry predict the period, every
//!   gap within a quarter of a whole number of predicted periods, some of
//!   two or more (longer than one ball spacing can make) and not all the
//!   same number (a few passages found far apart have no median period;
//!   a train uniformly `n` periods apart is left to the period mismatch).
//! - [`ConditionKind::PeriodMismatch`]: measured `τ_c` far from the prediction.
//! - [`ConditionKind::WidthsWithheld`]: the baseline bends under the pulses
//!   by more than 15 % of a pulse (median over the pulses): a drift as fast
//!   as the pulses, which a width cannot be told from; or the widths
//!   disagree from pulse to pulse beyond their noise so much that their
//!   mean's standard error is over 2 % (a drift at the pulses' scale that
//!   the baseline does not follow, so does not bend with). No width is
//!   reported (`tau_p_s` is NaN, no passage has `width_used`); counts and
//!   times are kept (`withhold.rs`).
//!
//! How often each is right on benches it was never tuned on is measured by
//! [`crate::validate::passages`].

use serde::{Deserialize, Serialize};

use crate::analysis::train_fit;
use crate::bearing::check_velocity;
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};
use crate::stats::MeanStd;

mod conditions;
mod coupling;
mod edges;
mod fits;
mod gaps;
mod lsq;
mod measure;
mod overlap;
mod pulse_fit;
mod scan;
mod settings;
mod signal;
mod template;
#[cfg(test)]
mod tests;
mod train_stats;
mod withhold;

pub use overlap::PulseOverlap;
pub use settings::PassageSettings;
use signal::{gaussian_smooth, median, noise_sigma, rms_difference_sigma, running_percentile};
pub(crate) use train_stats::TrainStats;
use withhold::Withheld;

/// `2√(2 ln 2)`: width at half maximum of a Gaussian over its sigma.
const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949_3;

/// One ball passing the fibre.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Passage {
    /// 0-based number of the passage in the record.
    pub index: usize,
    /// Centre: midpoint of the two half-maximum crossings of the fitted
    /// pulse, s.
    pub time_s: f64,
    /// Maximum of the fitted pulse, s.
    pub peak_time_s: f64,
    /// +1 for a pulse up, −1 for an inverted pulse (interference).
    pub polarity: i8,
    /// Time to the next passage `τ_c`, s (`None` for the last).
    pub tau_c_s: Option<f64>,
    /// Full width at half maximum `τ_p` of this pulse alone (the
    /// neighbours' overlap removed), s.
    pub tau_p_s: f64,
    /// Gaussian sigma `τ_p / (2√(2 ln 2))`, s.
    pub sigma_s: f64,
    /// Pulse amplitude above the baseline (peak of the fitted pulse), V.
    pub amplitude_v: f64,
    /// Height above the baseline, V (the amplitude, kept for the reports).
    pub height_v: f64,
    /// `τ_p / τ_c` with this passage's `τ_c`.
    pub tau_p_over_tau_c: Option<f64>,
    /// Ball spacing implied `v τ_c / 2`, mm (when the velocity is known).
    pub spacing_mm: Option<f64>,
    /// The pulse is cut by the record's start or end (within two half
    /// widths of its peak): counted and timed, its width not used.
    #[serde(default)]
    pub edge: bool,
    /// Its width entered `tau_p_s` and the other width statistics.
    #[serde(default)]
    pub width_used: bool,
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
    /// The baseline bends under the pulses, or the widths scatter beyond
    /// noise, too much for the widths to be measured: they are withheld.
    WidthsWithheld,
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
            ConditionKind::WidthsWithheld => "widths_withheld",
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
    /// Robust noise standard deviation per sample, V.
    pub noise_v: f64,
    /// Smallest amplitude a whole pulse needs to be detected, V
    /// (`threshold_sigma` times `detection_noise_v`).
    pub prominence_threshold_v: f64,
    /// Noise of the signal searched: standard deviation of a pulse
    /// amplitude estimated by the matched filter, V.
    #[serde(default)]
    pub detection_noise_v: f64,
    /// Detection threshold, in standard deviations of the searched signal's noise.
    #[serde(default)]
    pub threshold_sigma: f64,
    /// False detections per record the threshold allows in white Gaussian noise.
    #[serde(default)]
    pub false_detections_per_record: f64,
    /// AC-coupling time constant found and undone before measuring, s
    /// (`None`: none found, or restoration off).
    #[serde(default)]
    pub ac_time_constant_s: Option<f64>,
    /// Full width at half maximum of the record's mean pulse (the template), s.
    #[serde(default)]
    pub template_fwhm_s: f64,
    /// Median, over the passages whose width is measured, of how far the
    /// baseline bends under a pulse, in pulse heights (`None` when no
    /// passage's width is measured); above 0.15 the widths are withheld
    /// ([`ConditionKind::WidthsWithheld`]).
    #[serde(default)]
    pub baseline_bend: Option<f64>,
    /// Standard error of the mean width, relative, from the widths'
    /// scatter over the passages beyond what each fit's noise explains
    /// (`None` with fewer than three widths measured); above 0.02 the
    /// widths are withheld ([`ConditionKind::WidthsWithheld`]).
    #[serde(default)]
    pub width_scatter_se: Option<f64>,
    /// How much the pulses overlap and how far low that can leave the
    /// widths (`None` when the mean pulse gives no answer).
    #[serde(default)]
    pub overlap: Option<PulseOverlap>,
    /// Passages found (both polarities).
    pub count: usize,
    /// Of which inverted.
    pub count_inverted: usize,
    /// The passages, in time order.
    pub passages: Vec<Passage>,
    /// `τ_c` between consecutive passages, s.
    pub tau_c_s: MeanStd,
    /// `τ_p`, full width at half maximum of each pulse alone, s (the
    /// passages with `width_used`).
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
    /// Baseline under the pulses, one value per sample, V, as the recorded
    /// signal shows it (AC coupling included): a pulse's top is at baseline
    /// plus its height. Kept for plots, not serialised.
    #[serde(skip)]
    pub baseline_v: Vec<f64>,
}

/// Smallest prominence of the strongest pulses that guide the period in
/// the velocity-free mode, in noise standard deviations (lag-1 noise,
/// 2-sample smoothing).
const GUIDE_SNR: f64 = 6.0;

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
            let thr = (GUIDE_SNR * sigma1).max(1e-12 * x_range);
            let c = scan::keep_strong(scan::candidates(&y0, None, thr, None, None)?, 0.5);
            if c.idx.len() < 3 {
                return Err(no_passages(format!(
                    "found {} pulse(s) above {:.3e} V ({GUIDE_SNR} noise sigma) without a velocity to guide the search; give the tracking velocity",
                    c.idx.len(),
                    thr,
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
    if (n as f64) < tau_samples {
        return Err(no_passages(format!(
            "the record lasts {:.3} s, shorter than one of its ball-pass periods ({:.3} s each): it cannot hold two passages",
            n as f64 / fs,
            tau_guide
        )));
    }

    // Noise, a first baseline and the seeds.
    let window = (settings.baseline_periods * tau_samples).round() as usize;
    let y0: Vec<f64> = {
        let baseline0 = running_percentile(x, window, settings.baseline_percentile);
        x.iter().zip(&baseline0).map(|(a, b)| a - b).collect()
    };
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
    let alpha = settings.false_detections_per_record;
    let seeds = scan::seeds(
        &y0,
        sigma,
        settings.baseline_percentile,
        tau_samples,
        alpha,
        settings.min_snr,
    )?;
    let Some(half_widths) = seeds.half_widths() else {
        let largest = y0.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        return Err(no_passages(format!(
            "no pulse stands out of the noise: largest excursion {largest:.3e} V, noise sigma {sigma:.3e} V"
        )));
    };
    // Record-length buffers are freed as soon as they are used (a long
    // record's passages are found beside few other buffers).
    drop(y0);
    let m = measure::measure(x, fs, tau_samples, &seeds, half_widths, sigma, settings)
        .map_err(no_passages)?;

    // Passages, in samples of the record.
    let q = m.q as f64;
    let nd = m.baseline.len();
    let to_sample = |b: f64| b * q + 0.5 * (q - 1.0);
    let t_of = |i: f64| rec.meta.start_time_s + i / fs;
    let hw_l = m.shape.peak_u - m.shape.left_u;
    let hw_r = m.shape.right_u - m.shape.peak_u;
    let fwhm_s = m.shape.fwhm() * q / fs;
    let kept: Vec<&pulse_fit::PulseFit> = m
        .fits
        .iter()
        .filter(|f| {
            let mid = to_sample(f.pulse.c + f.pulse.s * m.shape.mid_u());
            (0.0..=(n - 1) as f64).contains(&mid)
        })
        .collect();
    if kept.len() < 2 {
        return Err(no_passages(format!(
            "only {} pulse above the threshold ({:.1} noise sigma of the matched filter); at least two passages are needed to measure a period",
            kept.len(),
            m.z
        )));
    }
    let times: Vec<f64> = kept
        .iter()
        .map(|f| t_of(to_sample(f.pulse.c + f.pulse.s * m.shape.mid_u())))
        .collect();
    let mut passages: Vec<Passage> = kept
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let p = f.pulse;
            let tau_c = times.get(k + 1).map(|t| t - times[k]);
            let tau_p = p.s * fwhm_s;
            let first = p.c + p.s * (m.shape.peak_u - 2.0 * hw_l);
            let last = p.c + p.s * (m.shape.peak_u + 2.0 * hw_r);
            let edge = first < 0.0 || last > (nd - 1) as f64;
            Passage {
                index: k,
                time_s: times[k],
                peak_time_s: t_of(to_sample(p.c + p.s * m.shape.peak_u)),
                polarity: if p.a < 0.0 { -1 } else { 1 },
                tau_c_s: tau_c,
                tau_p_s: tau_p,
                sigma_s: tau_p / FWHM_PER_SIGMA,
                amplitude_v: p.a.abs(),
                height_v: p.a.abs(),
                tau_p_over_tau_c: tau_c.map(|t| tau_p / t),
                spacing_mm: match (tau_c, velocity) {
                    (Some(t), Some(v)) => Some(v * t / 2.0),
                    _ => None,
                },
                edge,
                width_used: !edge && f.ok,
            }
        })
        .collect();
    let inverted = passages.iter().filter(|p| p.polarity < 0).count();
    let bends: Vec<Option<f64>> = kept
        .iter()
        .map(|f| withhold::baseline_bend(&m.baseline, &f.pulse, &m.shape))
        .collect();
    let used: Vec<(f64, f64)> = kept
        .iter()
        .zip(&passages)
        .filter(|(_, p)| p.width_used)
        .map(|(f, _)| (f.pulse.s, f.s_se))
        .collect();
    let width_scatter_se = withhold::scatter_se(&used);
    let (baseline_bend, widths_withheld) =
        withhold::withhold(&mut passages, &bends, width_scatter_se);

    let TrainStats {
        tau_c_all,
        regular,
        med_tau,
        tau_c: tau_c_stats,
        tau_p: tau_p_stats,
        sigma: sigma_stats,
        tau_p_over_tau_c: ratio_stats,
        amplitude: amp_stats,
    } = TrainStats::of(&passages)
        .ok_or_else(|| no_passages("no period between passages".into()))?;
    let f_c = 1.0 / tau_c_stats.mean;
    let amps: Vec<f64> = passages.iter().map(|p| p.amplitude_v).collect();
    let med_amp = median(&amps);

    // The template's area (peak 1), s: the dip an AC coupling of rate κ
    // leaves after each pulse is κ × area, in pulse heights.
    let area_s = m.template.h.iter().sum::<f64>() * m.template.dx * q / fs;
    let ac = (m.kappa > 0.0).then(|| (1.0 / m.kappa, m.kappa * area_s));
    let f_c_predicted = predicted.as_ref().map(|p| p.f_c_hz);
    let conditions = conditions::conditions(&conditions::Inputs {
        passages: &passages,
        tau_c_all: &tau_c_all,
        med_tau,
        baseline: &m.baseline,
        blocks_per_period: tau_samples / q,
        med_amp,
        block_noise: sigma / q.sqrt(),
        ac,
        f_c,
        f_c_predicted,
        tau_single_max: predicted.as_ref().map(|p| 1.0 / p.f_single_spacing_low_hz),
        withheld_bend: baseline_bend.filter(|_| widths_withheld == Some(Withheld::Bend)),
        withheld_scatter_se: width_scatter_se
            .filter(|_| widths_withheld == Some(Withheld::Scatter)),
    });
    // Overlap of pulses one median period apart (the template's units are
    // blocks, its stretch the pulses' mean).
    let overlap = PulseOverlap::of(&m.template, &m.shape, med_tau * fs / q);
    let rel_err = f_c_predicted.map(|p| (f_c - p) / p);

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

    // The restored signal without its baseline, per sample (the fits' data),
    // and the baseline as the recorded signal shows it (for the plots).
    let positions: Vec<f64> = (0..n).map(|i| (i as f64 - 0.5 * (q - 1.0)) / q).collect();
    let base = m.splines.eval_at(&m.beta, &positions);
    drop(positions);
    let integral = if m.kappa > 0.0 {
        signal::running_integral(x, 1.0 / fs)
    } else {
        Vec::new()
    };
    let restored = |i: usize| x[i] + integral.get(i).map_or(0.0, |v| m.kappa * v);
    let baseline_v: Vec<f64> = (0..n)
        .map(|i| base[i] - integral.get(i).map_or(0.0, |v| m.kappa * v))
        .collect();

    let fits = if settings.fit_pulses >= 2 && inverted == 0 {
        let y: Vec<f64> = (0..n).map(|i| restored(i) - base[i]).collect();
        Some(fits::fit_trains(
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
        prominence_threshold_v: m.z * m.amplitude_noise,
        detection_noise_v: m.amplitude_noise,
        threshold_sigma: m.z,
        false_detections_per_record: alpha,
        ac_time_constant_s: ac.map(|a| a.0),
        template_fwhm_s: fwhm_s,
        baseline_bend,
        width_scatter_se,
        overlap,
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
        baseline_v,
    })
}
