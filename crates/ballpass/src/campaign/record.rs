//! What a campaign keeps of one record: every scalar the analyses produced
//! (one row of `records.csv`), plus the friction spectrum for diagnosis.

use serde::{Deserialize, Serialize};

use super::sticking::PassageHeights;

/// One record's results.
///
/// Reads back from its JSON (`Deserialize`) except the friction spectrum,
/// which the JSON leaves out and which comes back empty: a record's result
/// can travel between processes (the Python package's pickling, Spark
/// executors) with the spectrum sent beside it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RecordResult {
    /// Recording file.
    pub path: String,
    /// Bearing.
    pub bearing: String,
    /// Commanded velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Repeat number.
    pub repeat: u32,
    /// Condition from the manifest, when given.
    pub condition: Option<String>,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration analysed, s.
    pub duration_s: f64,
    /// Predicted ball-pass frequency, Hz.
    pub f_c_predicted_hz: f64,
    /// Ball-pass frequency from the autocorrelations, Hz.
    pub f_c_correlation_hz: Option<f64>,
    /// Ball passages counted by the optical sensor.
    pub passages: Option<usize>,
    /// Ball-pass frequency from the optical passages (1 / mean tau_c), Hz.
    pub f_c_passages_hz: Option<f64>,
    /// Mean ball-pass period from the passages, s.
    pub tau_c_s: Option<f64>,
    /// Standard deviation of the ball-pass period, s.
    pub tau_c_std_s: Option<f64>,
    /// Mean optical pulse width at half prominence, s.
    pub tau_p_s: Option<f64>,
    /// Standard deviation of the pulse width, s.
    pub tau_p_std_s: Option<f64>,
    /// Mean of tau_p / tau_c over the passages.
    pub tau_ratio: Option<f64>,
    /// Velocity-error standard deviation (raw, ddof 0), µm/s.
    pub velocity_error_std_um_s: Option<f64>,
    /// Velocity-error standard deviation after the low-pass, µm/s.
    pub velocity_error_lowpassed_std_um_s: Option<f64>,
    /// Phase of the optical signal relative to friction (correlation), degrees.
    pub phase_friction_optical_deg: Option<f64>,
    /// Phase of the velocity error relative to friction, degrees.
    pub phase_friction_velocity_error_deg: Option<f64>,
    /// Phase of the optical signal relative to the velocity error, degrees.
    pub phase_velocity_error_optical_deg: Option<f64>,
    /// Friction PSD over its local floor at k·f_c, k = 1..K, dB.
    pub friction_harmonic_ratio_db: Vec<Option<f64>>,
    /// Whether the friction PSD at k·f_c stands above its floor.
    pub friction_harmonic_significant: Vec<Option<bool>>,
    /// Friction power in the low band (0 to the diagnosis band edge), N².
    pub friction_low_band_power_n2: Option<f64>,
    /// Friction of each ball-pass period (sticking).
    pub sticking: Option<PassageHeights>,
    /// The friction's and velocity error's lines in the position domain
    /// (amplitude with its confidence interval, per harmonic), when the
    /// record has an encoder and enough travel in one direction.
    #[serde(default)]
    pub position_ripple: Vec<super::ripple::RippleLine>,
    /// Warnings of the analyses.
    pub warnings: Vec<String>,
    /// The plateau of a multi-speed run this record is (file, time range,
    /// measured velocity, direction); `None`: the whole file. Its
    /// `velocity_mm_s` above is then the mean speed of the plateaus pooled
    /// with it, and the record was analysed at the plateau's own speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plateau: Option<super::segments::PlateauSource>,
    /// Friction auto-spectrum (full range, after the analysis' low-pass and
    /// detrend): frequencies, Hz.
    #[serde(skip)]
    pub friction_psd_freq_hz: Vec<f64>,
    /// Friction auto-spectrum, N²/Hz.
    #[serde(skip)]
    pub friction_psd: Vec<f64>,
    /// The record's friction → velocity-error spectra, pooled by the sweep
    /// to identify the stage.
    #[serde(skip)]
    pub stage_spectra: Option<crate::model::identify::StageSpectra>,
}
