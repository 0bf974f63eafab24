//! The analysis of thesis chapters 4 and 7 as one function, [`analyze`]:
//! velocity error, low-pass and detrend, correlations with the measured
//! period and phases, full-range and high-resolution spectra, harmonics with
//! their significance, and the average of repeated tests.
//!
//! # Steps (defaults = the thesis' processing, [`AnalyzeSettings::default`])
//!
//! 1. [`preprocess`]: `v = numpy.gradient(position, 1/fs)` (Eq. 4.1 inside),
//!    `v_e = v - V`; the first `trim_start_s` seconds dropped.
//! 2. 5th-order Butterworth low-pass at 20 Hz, forward-backward
//!    (`sosfiltfilt`), then linear detrend, on friction, `v_e` and optical.
//! 3. [`correlation`]: the three autocorrelations and the cross-correlations
//!    friction×v_e, friction×optical, v_e×optical, Eq. 7.1
//!    (`R_xy[m] = sum_n x[n+m] y[n]`: a peak at lag `-d` means y lags x by
//!    `d`), coefficient-normalised by default. The measured period comes from
//!    the autocorrelation peaks near `k tau_c`, the phases from the
//!    cross-correlation peak within half a period of zero lag.
//! 4. [`spectra`]: full-range Welch (Hann, 4096 samples capped at `N`, half
//!    overlap) auto- and cross-spectra and coherence of the step-2 signals,
//!    and a high-resolution spectrum: `decimate` by
//!    `q = floor(fs / (2.5 f_lp))` (Chebyshev anti-alias at `0.8 fs/(2q)`,
//!    at or above the low-pass) then Welch with
//!    `nperseg = min(smooth(6 (fs/q) / f_c), N/q)` (six periods, rounded up to an even
//!    `2^a 3^b 5^c`); or, with
//!    [`HiresMethod::PolyphaseZoom`], the thesis' zoom processing (docs/methods.md §10).
//! 5. Harmonics `k f_c` (predicted and measured): PSD, local noise floor,
//!    ratio, chi-square significance; coherence with its threshold.
//! 6. [`repeats`]: several records at one velocity are analysed alone, then
//!    their correlations and spectra are averaged (thesis §7) and analysed
//!    again; per-record scalars are kept with their mean and spread.
//!
//! Decisions where the brief left room are recorded in the docs of each
//! step and in [`Analysis::method_notes`], which `analysis.json` carries.
//!
//! The optical ball passages are found by [`passage::detect_passages`].

use ballpass_dsp::{DetrendType, Normalization, Window};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bearing::Prediction;
use crate::error::{Error, Result};
use crate::recording::Recording;

pub mod confidence;
pub mod correlation;
pub mod export;
pub mod harmonics;
pub mod load_cell;
pub mod passage;
pub mod passage_table;
pub mod phase;
pub mod position;
pub mod preflight;
pub mod preprocess;
pub mod repeats;
pub mod spectra;
pub mod stream;
pub mod sync;
mod train_fit;

pub use correlation::{CorrelationWindow, Correlations, MeasuredPeriod, SignalPeriod};
pub use export::{write_outputs, OutputPaths};
pub use harmonics::{CoherenceRow, HarmonicRow, HarmonicValue};
pub use passage::{detect_passages, PassageAnalysis, PassageSettings};
pub use passage_table::{PassageFailure, PassageOutput, PassageRow};
pub use phase::Phase;
pub use preprocess::{Prepared, VelocityErrorStats};
pub use repeats::{RecordScalars, Repeats, Spread};
pub use spectra::{Spectra, SpectrumInfo};

/// Schema tag of `analysis.json`.
pub const SCHEMA: &str = "ballpass.analysis/2";

/// One of the three analysed signals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Signal {
    /// Friction force, N.
    Friction,
    /// Velocity error `v - V`, mm/s.
    VelocityError,
    /// Optical sensor, V.
    Optical,
}

impl Signal {
    /// The three signals in canonical (column) order.
    pub const ALL: [Signal; 3] = [Signal::Friction, Signal::VelocityError, Signal::Optical];

    /// Column name (`friction`, `velocity_error`, `optical`).
    pub fn name(self) -> &'static str {
        match self {
            Signal::Friction => "friction",
            Signal::VelocityError => "velocity_error",
            Signal::Optical => "optical",
        }
    }

    /// Words for summaries (`friction`, `velocity error`, `optical`).
    pub fn words(self) -> &'static str {
        match self {
            Signal::Friction => "friction",
            Signal::VelocityError => "velocity error",
            Signal::Optical => "optical",
        }
    }

    /// Unit of the signal.
    pub fn unit(self) -> &'static str {
        match self {
            Signal::Friction => "N",
            Signal::VelocityError => "mm/s",
            Signal::Optical => "V",
        }
    }
}

/// The three cross pairs `(x, y)` in canonical order; Eq. 7.1 `R_xy`.
pub const CROSS_PAIRS: [(Signal, Signal); 3] = [
    (Signal::Friction, Signal::VelocityError),
    (Signal::Friction, Signal::Optical),
    (Signal::VelocityError, Signal::Optical),
];

/// Column name of a pair: `x` for an autocorrelation, `x__y` otherwise.
pub fn pair_name(x: Signal, y: Signal) -> String {
    if x == y {
        x.name().to_string()
    } else {
        format!("{}__{}", x.name(), y.name())
    }
}

/// Trend removed after the low-pass (step 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Detrend {
    /// Least-squares line (thesis, default).
    #[default]
    Linear,
    /// Mean.
    Constant,
    /// Nothing.
    None,
}

impl Detrend {
    pub(crate) fn to_dsp(self) -> DetrendType {
        match self {
            Detrend::Linear => DetrendType::Linear,
            Detrend::Constant => DetrendType::Constant,
            Detrend::None => DetrendType::None,
        }
    }
}

/// Normalisation of the correlations (see [`ballpass_dsp::Normalization`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CorrNorm {
    /// Divide by `N`.
    Biased,
    /// Divide by `N - |m|`.
    Unbiased,
    /// Divide by `sqrt(R_xx[0] R_yy[0])` (autocorrelations are 1 at zero lag).
    #[default]
    Coeff,
    /// Raw sums.
    None,
}

impl CorrNorm {
    pub(crate) fn to_dsp(self) -> Normalization {
        match self {
            CorrNorm::Biased => Normalization::Biased,
            CorrNorm::Unbiased => Normalization::Unbiased,
            CorrNorm::Coeff => Normalization::Coeff,
            CorrNorm::None => Normalization::None,
        }
    }
}

/// Welch segment window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WindowKind {
    /// Periodic Hann (SciPy's default).
    #[default]
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular.
    Boxcar,
}

impl WindowKind {
    pub(crate) fn to_dsp(self) -> Window {
        match self {
            WindowKind::Hann => Window::Hann,
            WindowKind::Hamming => Window::Hamming,
            WindowKind::Boxcar => Window::Boxcar,
        }
    }
}

/// How the high-resolution low-band spectrum is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "method")]
pub enum HiresMethod {
    /// Anti-alias filter and decimate once (`scipy.signal.decimate`, IIR,
    /// zero phase), then Welch at `fs / q` (default; what the thesis meant).
    #[default]
    Decimate,
    /// The thesis' zoom processing (Fig. 61): mean of the Welch spectra of
    /// the `m` polyphase branches `x[m k + i]`, no anti-alias filter.
    /// Aliases and gains no averages (docs/methods.md §10); for reproduction only.
    PolyphaseZoom {
        /// Decimation factor `M`.
        m: usize,
    },
}

/// Every setting of [`analyze`]; `Default` is the thesis' processing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AnalyzeSettings {
    /// Seconds dropped at the start of each record (start transient).
    pub trim_start_s: f64,
    /// Butterworth low-pass cutoff, Hz (`None`: no low-pass). Default 20.
    pub lowpass_hz: Option<f64>,
    /// Butterworth order. Default 5.
    pub order: usize,
    /// Trend removed after the low-pass. Default linear.
    pub detrend: Detrend,
    /// Correlation normalisation. Default coeff.
    pub corr_norm: CorrNorm,
    /// Full-range Welch segment length (capped at the record length). Default 4096.
    pub nperseg: usize,
    /// Full-range Welch overlap (`None`: half the segment).
    pub noverlap: Option<usize>,
    /// Welch window (full and high-resolution). Default Hann.
    pub window: WindowKind,
    /// High-resolution method.
    pub hires: HiresMethod,
    /// Decimation factor of the high-resolution spectrum (`None`:
    /// `floor(fs / (2.5 f_lp))`, see [`spectra`]).
    pub hires_q: Option<usize>,
    /// High-resolution segment length (`None`: shortest power of two giving
    /// `f_c / 4` resolution, capped at the decimated length).
    pub hires_nperseg: Option<usize>,
    /// High-resolution overlap (`None`: half the segment).
    pub hires_noverlap: Option<usize>,
    /// Harmonics `k = 1..=K` examined. Default 5.
    pub harmonics: usize,
    /// Confidence of the significance tests. Default 0.99.
    pub confidence: f64,
    /// Two-sided confidence of the PSD bands exported and drawn with every
    /// auto-spectrum (chi-square with Welch's equivalent degrees of
    /// freedom, [`confidence`]). Default 0.95 (MATLAB `pwelch`'s usual level).
    pub band_confidence: f64,
    /// Half-width of the autocorrelation peak windows around `k tau_c`, in
    /// periods. Default 0.25.
    pub period_window: f64,
    /// Most autocorrelation peaks used for the period (`None`: all up to
    /// half the record, where half the samples still overlap).
    pub max_period_peaks: Option<usize>,
    /// Largest disagreement between the correlation and cross-spectrum
    /// phases before a warning, degrees. Default 20.
    pub phase_tolerance_deg: f64,
    /// Encoder resolution for the quantisation floor of the velocity error,
    /// µm. Default 0.1 (Renishaw RGH22).
    pub encoder_resolution_um: f64,
    /// Load-cell DC restoration (see [`load_cell`]). Default: estimate the
    /// discharge from each record and undo it where identified.
    pub load_cell: load_cell::LoadCellCorrection,
    /// Lags the correlations are computed and exported for (see
    /// [`MaxLag`]). Default: [`MaxLag::Auto`].
    pub max_lag: MaxLag,
}

/// The lag window of the correlations: `-L ..= L`.
///
/// A record of `N` samples has lags out to `N - 1`, but the period and the
/// phases only use the peaks within a few hundred ball periods of zero lag,
/// and on an hour-long record the full range is millions of lags per series
/// (gigabytes of memory and of `correlations.csv`). Within the window the
/// values are those of the whole-record correlation (same sums, same
/// normalisation with the whole `N`), computed block by block
/// ([`ballpass_dsp::correlate_pairs_window`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaxLag {
    /// [`MaxLag::AUTO_PERIODS`] predicted ball periods, and never less
    /// than [`MaxLag::AUTO_MIN_S`] (so records up to a minute keep every
    /// lag); the full range when the record is shorter.
    #[default]
    Auto,
    /// Lags out to this many seconds (the full range when the record is
    /// shorter).
    Seconds(f64),
    /// Every lag, `-(N-1) ..= N-1`.
    Full,
}

impl MaxLag {
    /// Ball periods in the [`MaxLag::Auto`] window.
    pub const AUTO_PERIODS: f64 = 100.0;
    /// Shortest [`MaxLag::Auto`] window, s.
    pub const AUTO_MIN_S: f64 = 60.0;

    /// The largest lag `L` in samples for a record of `n` samples at
    /// `fs_hz` with predicted period `tau_c_s`: at most `n - 1`.
    pub fn samples(self, n: usize, fs_hz: f64, tau_c_s: f64) -> usize {
        let full = n.saturating_sub(1);
        let seconds = match self {
            MaxLag::Full => return full,
            MaxLag::Auto => (Self::AUTO_PERIODS * tau_c_s).max(Self::AUTO_MIN_S),
            MaxLag::Seconds(s) => s,
        };
        let l = (seconds * fs_hz).round();
        if l >= full as f64 {
            full
        } else {
            l as usize
        }
    }
}

impl Default for AnalyzeSettings {
    fn default() -> Self {
        Self {
            trim_start_s: 0.0,
            lowpass_hz: Some(20.0),
            order: 5,
            detrend: Detrend::Linear,
            corr_norm: CorrNorm::Coeff,
            nperseg: 4096,
            noverlap: None,
            window: WindowKind::Hann,
            hires: HiresMethod::Decimate,
            hires_q: None,
            hires_nperseg: None,
            hires_noverlap: None,
            harmonics: 5,
            confidence: 0.99,
            band_confidence: 0.95,
            period_window: 0.25,
            max_period_peaks: None,
            phase_tolerance_deg: 20.0,
            encoder_resolution_um: 0.1,
            load_cell: load_cell::LoadCellCorrection::Auto,
            max_lag: MaxLag::Auto,
        }
    }
}

impl AnalyzeSettings {
    /// Checks the ranges that do not depend on a recording.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the flag.
    pub fn validate(&self) -> Result<()> {
        if !(self.trim_start_s.is_finite() && self.trim_start_s >= 0.0) {
            return Err(Error::setting(
                "trim",
                format!(
                    "must be zero or a positive number of s, got {}",
                    self.trim_start_s
                ),
            ));
        }
        if self.nperseg < 2 {
            return Err(Error::setting(
                "nperseg",
                format!("must be at least 2, got {}", self.nperseg),
            ));
        }
        if let Some(o) = self.noverlap {
            if o >= self.nperseg {
                return Err(Error::setting(
                    "noverlap",
                    format!("must be less than nperseg ({}), got {o}", self.nperseg),
                ));
            }
        }
        if !(1..=100).contains(&self.harmonics) {
            return Err(Error::setting(
                "harmonics",
                format!("must be between 1 and 100, got {}", self.harmonics),
            ));
        }
        if !(self.confidence > 0.5 && self.confidence < 1.0) {
            return Err(Error::setting(
                "confidence",
                format!(
                    "must be between 0.5 and 1 (exclusive), got {}",
                    self.confidence
                ),
            ));
        }
        if !(self.band_confidence > 0.0 && self.band_confidence < 1.0) {
            return Err(Error::setting(
                "band confidence",
                format!(
                    "must be between 0 and 1 (exclusive), got {}",
                    self.band_confidence
                ),
            ));
        }
        if !(self.period_window > 0.0 && self.period_window < 0.5) {
            return Err(Error::setting(
                "period window",
                format!(
                    "must be between 0 and 0.5 periods, got {}",
                    self.period_window
                ),
            ));
        }
        if self.max_period_peaks == Some(0) {
            return Err(Error::setting("max period peaks", "must be at least 1"));
        }
        if !(self.phase_tolerance_deg > 0.0 && self.phase_tolerance_deg <= 180.0) {
            return Err(Error::setting(
                "phase tolerance",
                format!(
                    "must be in (0, 180] degrees, got {}",
                    self.phase_tolerance_deg
                ),
            ));
        }
        if !(self.encoder_resolution_um.is_finite() && self.encoder_resolution_um > 0.0) {
            return Err(Error::setting(
                "encoder resolution",
                format!(
                    "must be a positive number of µm, got {}",
                    self.encoder_resolution_um
                ),
            ));
        }
        self.load_cell.validate()?;
        if let MaxLag::Seconds(s) = self.max_lag {
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::setting(
                    "max-lag",
                    format!("must be a positive number of s or 'full', got {s}"),
                ));
            }
        }
        if self.hires_q == Some(0) {
            return Err(Error::setting(
                "hires q",
                "decimation factor must be at least 1",
            ));
        }
        if let HiresMethod::PolyphaseZoom { m } = self.hires {
            if m < 2 {
                return Err(Error::setting(
                    "zoom",
                    format!("decimation factor M must be at least 2, got {m}"),
                ));
            }
        }
        if self.hires_nperseg.is_some_and(|n| n < 2) {
            return Err(Error::setting("nperseg-hr", "must be at least 2"));
        }
        Ok(())
    }
}

/// What one input record was.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputInfo {
    /// File or test name.
    pub source: String,
    /// Test id, when known.
    pub test_id: Option<String>,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Samples in the record as loaded.
    pub samples: usize,
    /// Duration as loaded, s.
    pub duration_s: f64,
    /// Channels present (`friction_N`, ...).
    pub channels: Vec<String>,
}

/// A series that could not be computed, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Absent {
    /// Series name (`optical`, `friction__optical`, ...).
    pub name: String,
    /// Why it is absent.
    pub reason: String,
}

/// Which signals and pairs the analysis has.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeriesInfo {
    /// Signals analysed.
    pub signals: Vec<Signal>,
    /// Correlation/spectrum series present, in column order.
    pub present: Vec<String>,
    /// Series absent, with the reason.
    pub absent: Vec<Absent>,
}

/// The conclusion in a few fields and one sentence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// Predicted ball-pass frequency, Hz.
    pub f_c_predicted_hz: f64,
    /// Measured ball-pass frequency (from the preferred autocorrelation), Hz.
    pub f_c_measured_hz: Option<f64>,
    /// `(measured - predicted) / predicted`, %.
    pub f_c_deviation_percent: Option<f64>,
    /// Signals whose spectrum at `f_c` stands above the local floor at the
    /// stated confidence.
    pub signals_showing_f_c: Vec<Signal>,
    /// Harmonics `k` at which the friction spectrum stands above its floor.
    pub friction_harmonics_flagged: Vec<usize>,
    /// One-sentence summary.
    pub text: String,
}

/// Everything [`analyze`] finds. Serialises as `analysis.json`; the
/// correlation and spectrum tables are exported as CSV by [`export`].
#[derive(Debug, Clone, Serialize)]
pub struct Analysis {
    /// Schema tag, [`SCHEMA`].
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// The records analysed.
    pub inputs: Vec<InputInfo>,
    /// The settings used.
    pub settings: AnalyzeSettings,
    /// How the settings resolved on these records and the choices the
    /// brief left open.
    pub method_notes: Vec<String>,
    /// Samples per record analysed (after trim and common truncation).
    pub samples_analysed: usize,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration analysed per record, s.
    pub duration_analysed_s: f64,
    /// Predicted ball-pass periods in the analysed duration.
    pub periods_in_record: f64,
    /// The bearing's prediction at the commanded velocity.
    pub prediction: Prediction,
    /// Series present and absent.
    pub series: SeriesInfo,
    /// Full-range spectrum parameters.
    pub spectrum_full: SpectrumInfo,
    /// High-resolution spectrum parameters.
    pub spectrum_hires: SpectrumInfo,
    /// Parameters of the full-range spectrum of the unfiltered signals.
    pub spectrum_unfiltered: SpectrumInfo,
    /// The lags the correlations hold (and `correlations.csv` exports).
    pub correlation_window: CorrelationWindow,
    /// Period measured from the autocorrelations.
    pub measured_period: MeasuredPeriod,
    /// Phases of the cross pairs.
    pub phases: Vec<Phase>,
    /// Auto-spectrum at the harmonics.
    pub harmonics: Vec<HarmonicRow>,
    /// Coherence at the harmonics.
    pub coherence: Vec<CoherenceRow>,
    /// Velocity-error statistics: of the record, or for repeats the mean
    /// over the records of each record's statistics (see
    /// [`VelocityErrorStats::mean_of`]; every record's own value is in
    /// [`Analysis::repeats`]).
    pub velocity_error: Option<VelocityErrorStats>,
    /// What was done about each record's load-cell discharge (records with
    /// a friction channel, in input order).
    pub load_cell: Vec<load_cell::DcRestoration>,
    /// The stage identified from the friction → velocity-error response of
    /// the records pooled (`None` without friction and position channels).
    pub stage: Option<crate::model::identify::StageIdentification>,
    /// The pooled spectra behind [`Analysis::stage`], for pooling further
    /// (a campaign pools them over its records).
    #[serde(skip)]
    pub stage_spectra: Option<crate::model::identify::StageSpectra>,
    /// Per-record results and spread, when more than one record was given.
    pub repeats: Option<Repeats>,
    /// Conclusion.
    pub verdict: Verdict,
    /// Ball passages of each record (optical sensor), in brief; the full
    /// table with fits is `ballpass passage`.
    pub passages: Vec<PassageSummary>,
    /// Synchronous average of friction and velocity error over the
    /// ball-pass period ([`sync`]; `None` when none could be made, see the
    /// warnings, or for a campaign's records), exported as `sync_average.csv`.
    pub sync: Option<sync::SyncAverage>,
    /// Everything the user should know about the numbers.
    pub warnings: Vec<String>,
    /// Correlations (averaged over repeats), exported as `correlations.csv`.
    #[serde(skip)]
    pub correlations: Correlations,
    /// Full-range spectra, exported as `spectra.csv`.
    #[serde(skip)]
    pub spectra: Spectra,
    /// High-resolution spectra, exported as `spectra_hires.csv`.
    #[serde(skip)]
    pub spectra_hires: Spectra,
    /// Full-range spectra of the signals before the low-pass and detrend
    /// (thesis Figs. 62 and 64: the white-noise floor above the band of
    /// interest), exported as `spectra_unfiltered.csv`. Welch still removes
    /// each segment's mean.
    #[serde(skip)]
    pub spectra_unfiltered: Spectra,
    /// Friction and velocity-error spectra against the travel, in
    /// cycles/mm (`None` without a position channel, or when no run of one
    /// direction is long enough; see the warnings). Its table is
    /// `spectra_position.csv`.
    pub position: Option<position::PositionSpectra>,
    /// How the record was streamed (absent: analysed in memory, see
    /// [`stream`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stream: Option<stream::StreamInfo>,
}

/// Runs the whole analysis on one record or several repeats at the same
/// velocity.
///
/// `prediction` carries the commanded velocity `V` (for the velocity
/// error) and the predicted `f_c`, `tau_c`.
///
/// # Errors
/// [`Error::InvalidSetting`] for bad settings (a cutoff at or above
/// Nyquist, a zero velocity, settings that cannot resolve `f_c`),
/// [`Error::InvalidRecording`] for no records, records of different rates,
/// or fewer than two predicted periods after the trim;
/// [`Error::MissingChannel`] when no analysable signal is present.
pub fn analyze(
    recs: &[Recording],
    prediction: &Prediction,
    settings: &AnalyzeSettings,
) -> Result<Analysis> {
    repeats::run(recs, prediction, settings, true, None)
}

/// [`analyze`] without the passage summaries ([`Analysis::passages`] is
/// left empty): for callers that detect the passages themselves with their
/// own settings (the campaigns), so the detection is not done twice.
pub(crate) fn analyze_without_passages(
    recs: &[Recording],
    prediction: &Prediction,
    settings: &AnalyzeSettings,
    restored: Option<Vec<Restored<'_>>>,
) -> Result<Analysis> {
    repeats::run(recs, prediction, settings, false, restored)
}

/// The stage as identified, or identified again without the check of the
/// encoder's quantisation where that check refused it and the friction
/// shows no harmonic above its floor (`verdict`): the staircase an
/// undithered encoder makes of the velocity error biases the fit through
/// the friction's ball-pass lines, and leaves broadband friction's
/// response unbiased (`model::identify::FrictionLines`).
pub fn stage_for_lines(
    stage: Option<crate::model::identify::StageIdentification>,
    spectra: Option<&crate::model::identify::StageSpectra>,
    verdict: &Verdict,
) -> Option<crate::model::identify::StageIdentification> {
    use crate::model::identify::{identify_with, FrictionLines};
    match (stage, spectra) {
        (Some(id), Some(sp))
            if !id.identified
                && verdict.friction_harmonics_flagged.is_empty()
                && sp.encoder.is_some_and(|e| e.undithered()) =>
        {
            Some(identify_with(sp, FrictionLines::NotShown))
        }
        (stage, _) => stage,
    }
}

/// One record's friction after the load-cell correction, and what was done
/// (`None` for a record without friction).
pub(crate) type Restored<'a> = Option<(std::borrow::Cow<'a, [f64]>, load_cell::DcRestoration)>;

/// The ball passages of one record in brief (part of `analysis.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassageSummary {
    /// Record name.
    pub source: String,
    /// Passages found; `None` when detection failed (see `note`).
    pub count: Option<usize>,
    /// Ball-pass frequency from the passages `1 / mean tau_c`, Hz.
    pub f_c_hz: Option<f64>,
    /// Mean and sample std of the period between passages, s.
    pub tau_c_s: Option<crate::stats::MeanStd>,
    /// Mean and sample std of the width at half prominence, s.
    pub tau_p_s: Option<crate::stats::MeanStd>,
    /// Mean and sample std of `tau_p / tau_c` (thesis: 0.155).
    pub tau_p_over_tau_c: Option<crate::stats::MeanStd>,
    /// Sensor conditions found (drift, AC coupling, inverted pulses, ...).
    pub conditions: Vec<String>,
    /// Why there is no summary (no optical channel, no pulses), if so.
    pub note: Option<String>,
}

impl PassageSummary {
    /// The summary of record `source`'s detected passages `p`.
    pub(crate) fn of(source: String, p: &passage::PassageAnalysis) -> Self {
        PassageSummary {
            source,
            count: Some(p.count),
            f_c_hz: Some(p.f_c_measured_hz).filter(|f| f.is_finite()),
            tau_c_s: Some(p.tau_c_s),
            tau_p_s: Some(p.tau_p_s),
            tau_p_over_tau_c: Some(p.tau_p_over_tau_c),
            conditions: p.conditions.iter().map(|c| c.message.clone()).collect(),
            note: None,
        }
    }

    /// No summary of record `source`, with why.
    pub(crate) fn without(source: String, note: String) -> Self {
        PassageSummary {
            source,
            count: None,
            f_c_hz: None,
            tau_c_s: None,
            tau_p_s: None,
            tau_p_over_tau_c: None,
            conditions: Vec::new(),
            note: Some(note),
        }
    }
}

/// A record's passage times (s, on its own clock), or why there are none.
pub(crate) type PassageTimes = std::result::Result<Vec<f64>, String>;

/// Detects the passages of each record (no pulse-train fits) with the
/// prediction's velocity guiding the period; failures become notes. The
/// passage times go with each summary (for the synchronous average).
fn passage_summaries(recs: &[Recording], pred: &Prediction) -> Vec<(PassageSummary, PassageTimes)> {
    let settings = PassageSettings {
        velocity_mm_s: Some(pred.velocity_mm_s),
        fit_pulses: 0,
        ..PassageSettings::default()
    };
    recs.par_iter()
        .map(|r| {
            let empty = |note: String| PassageSummary::without(r.source_name(), note);
            if r.channel(crate::recording::Channel::Optical).is_none() {
                return (
                    empty("no optical channel".into()),
                    Err("no optical channel".into()),
                );
            }
            match detect_passages(r, &settings) {
                Ok(p) => (
                    PassageSummary::of(r.source_name(), &p),
                    Ok(p.passages.iter().map(|q| q.time_s).collect()),
                ),
                Err(e) => (empty(e.to_string()), Err(e.to_string())),
            }
        })
        .collect()
}
