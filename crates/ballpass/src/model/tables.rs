//! The tables of `ballpass model`: the sinusoid model signals, the pulse
//! trains and the PD stage evaluated on grids, ready to plot or to export.
//!
//! Each of [`signals_tables`], [`pulses_tables`] and [`stage_tables`] returns
//! one struct that serialises as the command's JSON file (`signals.json`,
//! `pulses.json`, `stage.json`; schema tags `ballpass.model.*/1`) and holds
//! its CSV tables as rows (`#[serde(skip)]`, written by `write`). The
//! command-line tool and the Python package are glue over these functions,
//! so both give the same numbers.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::pulse_train::{sigma_ratio_from_fwhm_ratio, GaussianTrain, RectangularTrain};
use super::signals::{LagConvention, ModelSignal, SinusoidModel};
use super::stage::{
    difference_responses, velocity_response, BodeRow, DifferenceRow, FrequencyAxis, HarmonicRow,
    LoopFeatures, PdLoop, VelocityResponse, VelocityResponseSettings,
};
use crate::error::{Error, Result};
use crate::fsutil::{write_csv_rows as write_rows, write_json_pretty as write_pretty_json};

// ---------------------------------------------------------------- signals

/// Grid and convention of [`signals_tables`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SignalsTableSettings {
    /// Lags run from `−periods·τ_c` to `+periods·τ_c`. Default 2.
    pub periods: f64,
    /// Number of lags in the correlation table (2 to 1 000 000). Default 401.
    pub points: usize,
    /// Lag convention of the correlation table and the peaks. Default Eq. 7.1.
    pub convention: LagConvention,
}

impl Default for SignalsTableSettings {
    fn default() -> Self {
        Self {
            periods: 2.0,
            points: 401,
            convention: LagConvention::Eq71,
        }
    }
}

/// One lag of the analytic correlations (`correlations.csv`); each column
/// carries the unit of its product (friction N, velocity error mm/s,
/// optical V).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CorrelationRow {
    /// Lag, s.
    pub tau_s: f64,
    /// `R_FF`, N² (column `r_ff_n2`).
    #[serde(rename = "r_ff_n2")]
    pub r_ff: f64,
    /// `R_vv` of the velocity error, (mm/s)² (column `r_veve_mm2_s2`).
    #[serde(rename = "r_veve_mm2_s2")]
    pub r_veve: f64,
    /// `R_SS`, V² (column `r_ss_v2`).
    #[serde(rename = "r_ss_v2")]
    pub r_ss: f64,
    /// `R_Fv`, N·mm/s (column `r_fve_n_mm_s`).
    #[serde(rename = "r_fve_n_mm_s")]
    pub r_fve: f64,
    /// `R_FS`, N·V (column `r_fs_n_v`).
    #[serde(rename = "r_fs_n_v")]
    pub r_fs: f64,
    /// `R_Sv`, V·mm/s (column `r_sve_v_mm_s`).
    #[serde(rename = "r_sve_v_mm_s")]
    pub r_sve: f64,
}

/// One Dirac line of a model cross spectrum (`spectral_lines.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpectralLineRow {
    /// Pair, `x_y` in symbols (`F_ve`, ...).
    pub pair: String,
    /// Angular frequency of the line, rad/s.
    pub omega_rad_s: f64,
    /// Frequency of the line, Hz.
    pub f_hz: f64,
    /// Real part of the line weight.
    pub weight_re: f64,
    /// Imaginary part of the line weight.
    pub weight_im: f64,
}

/// The correlation peak nearest zero lag of one pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeakRow {
    /// Pair, `x_y` in symbols.
    pub pair: String,
    /// Symbols of x and y, for sentences ("ve leads F by ...").
    #[serde(skip)]
    pub names: (&'static str, &'static str),
    /// Lag of the peak, s, in the table's convention.
    pub tau_phi_s: f64,
    /// Phase `360 τ_φ / τ_c`, degrees.
    pub phase_deg: f64,
    /// How long y lags x, s (negative: y leads).
    pub y_lags_x_s: f64,
}

/// Everything `ballpass model signals` writes; serialises as `signals.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SignalsTables {
    /// `ballpass.model.signals/1`.
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// The model evaluated.
    pub model: SinusoidModel,
    /// Lag convention of the correlations and peaks.
    pub convention: LagConvention,
    /// The convention in words.
    pub convention_note: &'static str,
    /// What the spectral line weights are.
    pub spectra_note: &'static str,
    /// Correlation peaks nearest zero lag, one per pair that has one.
    pub peaks: Vec<PeakRow>,
    /// Dirac lines of the six spectra.
    pub spectral_lines: Vec<SpectralLineRow>,
    /// The correlations on the lag grid (`correlations.csv`).
    #[serde(skip)]
    pub correlations: Vec<CorrelationRow>,
}

impl SignalsTables {
    /// Writes `correlations.csv`, `spectral_lines.csv` and `signals.json`
    /// into `dir` (which must exist), each atomically; returns their paths.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let paths = [
            dir.join("correlations.csv"),
            dir.join("spectral_lines.csv"),
            dir.join("signals.json"),
        ];
        write_rows(&paths[0], &self.correlations)?;
        write_rows(&paths[1], &self.spectral_lines)?;
        write_pretty_json(&paths[2], self)?;
        Ok(paths.to_vec())
    }
}

/// The analytic correlations, spectral lines and correlation peaks of the
/// sinusoid model (thesis §6.2, Eqs. 6.10–6.17 as corrected), on
/// `settings.points` lags from `−P τ_c` to `+P τ_c`.
///
/// # Errors
/// [`Error::InvalidSetting`] for a bad model (see
/// [`SinusoidModel::validate`]) or a grid outside `periods > 0`, 2 to
/// 1 000 000 points.
pub fn signals_tables(
    model: &SinusoidModel,
    settings: &SignalsTableSettings,
) -> Result<SignalsTables> {
    model.validate()?;
    let (periods, points) = (settings.periods, settings.points);
    if !(periods.is_finite() && periods > 0.0 && (2..=1_000_000).contains(&points)) {
        return Err(Error::setting(
            "periods/points",
            "need periods > 0 and 2 to 1000000 points",
        ));
    }
    let conv = settings.convention;
    use ModelSignal::{Friction as F, Optical as S, VelocityError as V};
    let span = periods * model.tau_c_s();
    let correlations = (0..points)
        .map(|i| {
            let tau = -span + 2.0 * span * i as f64 / (points - 1) as f64;
            let r = |x, y| model.correlation(x, y, tau, conv);
            CorrelationRow {
                tau_s: tau,
                r_ff: r(F, F),
                r_veve: r(V, V),
                r_ss: r(S, S),
                r_fve: r(F, V),
                r_fs: r(F, S),
                r_sve: r(S, V),
            }
        })
        .collect();
    let name = |x: ModelSignal, y: ModelSignal| format!("{}_{}", x.symbol(), y.symbol());
    let mut spectral_lines = Vec::new();
    let mut peaks = Vec::new();
    for (x, y) in [(F, F), (V, V), (S, S), (F, V), (F, S), (S, V)] {
        for l in model.cross_spectrum(x, y) {
            spectral_lines.push(SpectralLineRow {
                pair: name(x, y),
                omega_rad_s: l.omega_rad_s,
                f_hz: l.omega_rad_s / (2.0 * PI),
                weight_re: l.weight_re,
                weight_im: l.weight_im,
            });
        }
        if let Some(p) = model.correlation_peak(x, y, conv) {
            peaks.push(PeakRow {
                pair: name(x, y),
                names: (x.symbol(), y.symbol()),
                tau_phi_s: p.tau_phi_s,
                phase_deg: p.phase_deg,
                y_lags_x_s: p.y_lags_x_s,
            });
        }
    }
    Ok(SignalsTables {
        schema: "ballpass.model.signals/1",
        version: crate::VERSION,
        model: *model,
        convention: conv,
        convention_note: match conv {
            LagConvention::Eq71 => "R_xy(tau) = <x(t+tau) y(t)> (thesis Eq. 7.1, scipy correlate); a peak at -d means y lags x by d",
            LagConvention::Eq612 => "R_xy(tau) = <x(t) y(t+tau)> (thesis Eq. 6.12); a peak at +d means y lags x by d",
        },
        spectra_note: "Dirac line weights of the unitary Fourier transform of the Eq. 6.12 correlation (conj(X)*Y, as scipy csd), with the signs of Eq. 6.17 corrected (docs/methods.md §4)",
        peaks,
        spectral_lines,
        correlations,
    })
}

// ---------------------------------------------------------------- pulses

/// What a pulse-width ratio measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RatioKind {
    /// Gaussian sigma over τ_c (the r of thesis Eq. 6.23, corrected).
    #[default]
    Sigma,
    /// Width at half maximum over τ_c (the τ_p that `ballpass passage` measures).
    Fwhm,
}

impl RatioKind {
    /// The Gaussian `σ / τ_c` of a ratio of this kind.
    pub fn sigma_ratio(self, ratio: f64) -> f64 {
        match self {
            RatioKind::Sigma => ratio,
            RatioKind::Fwhm => sigma_ratio_from_fwhm_ratio(ratio),
        }
    }
}

/// Settings of [`pulses_tables`]; `Default` is the thesis' r = 0.155.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PulsesTableSettings {
    /// Ball-pass frequency, Hz (`None`: τ_c = 1 s, a normalised period).
    pub f_c_hz: Option<f64>,
    /// Pulse width ratio (see `ratio_kind`). Default 0.155.
    pub ratio: f64,
    /// Whether `ratio` is σ/τ_c or width-at-half-maximum/τ_c. The
    /// rectangle's duty ratio is `ratio` as given, whatever its kind: the
    /// thesis compares both trains at the same r.
    pub ratio_kind: RatioKind,
    /// Pulse height P (any unit; coefficients scale with it). Default 1.
    pub amplitude: f64,
    /// Base level S. Default 0.
    pub dc: f64,
    /// Gaussian coefficients C_0..C_N listed. Default 10.
    pub harmonics: usize,
    /// Order N of the rectangular Fourier series. Default 20 (thesis Fig. 47).
    pub order: usize,
    /// Periods of the trains synthesised. Default 2.
    pub periods: usize,
    /// Samples per period of the synthesised trains. Default 500.
    pub points: usize,
}

impl Default for PulsesTableSettings {
    fn default() -> Self {
        Self {
            f_c_hz: None,
            ratio: 0.155,
            ratio_kind: RatioKind::Sigma,
            amplitude: 1.0,
            dc: 0.0,
            harmonics: 10,
            order: 20,
            periods: 2,
            points: 500,
        }
    }
}

/// One Gaussian Fourier coefficient (`gaussian_coefficients.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GaussianRow {
    /// Harmonic number n.
    pub n: usize,
    /// `n` (the line's frequency over f_c).
    pub f_over_f_c: f64,
    /// `Re C_n`.
    pub c_re: f64,
    /// `Im C_n`.
    pub c_im: f64,
    /// `|C_n|`.
    pub c_abs: f64,
    /// `|C_n| / |P|` (0 for P = 0).
    pub c_over_p: f64,
    /// The coefficient as the thesis printed it, over P.
    pub thesis_printed_c_over_p: f64,
}

/// One rectangular Fourier coefficient (`rectangular_coefficients.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RectRow {
    /// Harmonic number n (0: `a_0`).
    pub n: usize,
    /// `a_n`.
    pub a_n: f64,
    /// `b_n`.
    pub b_n: f64,
}

/// One sample of the synthesised trains (`trains.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrainRow {
    /// Time, s.
    pub t_s: f64,
    /// Gaussian train.
    pub gaussian: f64,
    /// Its Fourier series, order `gaussian_series_order`.
    pub gaussian_series: f64,
    /// Rectangular train.
    pub rectangular: f64,
    /// Its Fourier series, order `rectangular_order`.
    pub rectangular_series: f64,
}

/// Everything `ballpass model pulses` writes; serialises as `pulses.json`.
#[derive(Debug, Clone, Serialize)]
pub struct PulsesTables {
    /// `ballpass.model.pulses/1`.
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// Period, s.
    pub tau_c_s: f64,
    /// The ratio as given.
    pub ratio: f64,
    /// What the ratio measures.
    pub ratio_kind: RatioKind,
    /// The Gaussian train.
    pub gaussian: GaussianTrain,
    /// Its width at half maximum, s.
    pub gaussian_fwhm_s: f64,
    /// Order of the Gaussian series synthesised (coefficients above 1e-16 C_0).
    pub gaussian_series_order: usize,
    /// The rectangular train.
    pub rectangular: RectangularTrain,
    /// Order N of its series.
    pub rectangular_order: usize,
    /// `a_0` of the rectangular series.
    pub rectangular_a0: f64,
    /// Gibbs overshoot of the order-N series, fraction of the jump.
    pub rectangular_gibbs_overshoot_fraction: f64,
    /// RMS of the Gaussian series' error over the synthesised samples.
    pub fit_rms_gaussian_series: f64,
    /// RMS of the rectangular series' error over the synthesised samples.
    pub fit_rms_rectangular_series: f64,
    /// `gaussian_coefficients.csv`.
    #[serde(skip)]
    pub gaussian_coefficients: Vec<GaussianRow>,
    /// `rectangular_coefficients.csv`.
    #[serde(skip)]
    pub rectangular_coefficients: Vec<RectRow>,
    /// `trains.csv`.
    #[serde(skip)]
    pub trains: Vec<TrainRow>,
}

impl PulsesTables {
    /// The Gaussian `σ / τ_c`.
    pub fn sigma_ratio(&self) -> f64 {
        self.gaussian.sigma_ratio
    }

    /// Writes `gaussian_coefficients.csv`, `rectangular_coefficients.csv`,
    /// `trains.csv` and `pulses.json` into `dir` (which must exist).
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let paths = [
            dir.join("gaussian_coefficients.csv"),
            dir.join("rectangular_coefficients.csv"),
            dir.join("trains.csv"),
            dir.join("pulses.json"),
        ];
        write_rows(&paths[0], &self.gaussian_coefficients)?;
        write_rows(&paths[1], &self.rectangular_coefficients)?;
        write_rows(&paths[2], &self.trains)?;
        write_pretty_json(&paths[3], self)?;
        Ok(paths.to_vec())
    }
}

/// Gaussian and rectangular pulse trains (thesis §6.3, as corrected): their
/// Fourier coefficients and `periods` periods synthesised from the trains
/// and from their series.
///
/// # Errors
/// [`Error::InvalidSetting`] for a ratio outside (0, 1), a non-finite
/// level, a bad `f_c_hz`, `order` outside 1 to 100 000, more than 100 000
/// harmonics, periods outside 1 to 1000, or points outside 2 to 1 000 000.
pub fn pulses_tables(s: &PulsesTableSettings) -> Result<PulsesTables> {
    let tau_c = match s.f_c_hz {
        None => 1.0,
        Some(f) if f.is_finite() && f > 0.0 => 1.0 / f,
        Some(f) => {
            return Err(Error::setting(
                "f_c",
                format!("must be a positive number of Hz, got {f}"),
            ))
        }
    };
    let sigma_ratio = s.ratio_kind.sigma_ratio(s.ratio);
    let g = GaussianTrain::new(tau_c, sigma_ratio, s.amplitude, s.dc, 0.0)?;
    let r = RectangularTrain::new(tau_c, s.ratio, s.amplitude, s.dc)?;
    if s.order == 0 || s.order > 100_000 {
        return Err(Error::setting(
            "order",
            format!("must be 1 to 100000, got {}", s.order),
        ));
    }
    if s.harmonics > 100_000
        || s.periods == 0
        || s.periods > 1000
        || !(2..=1_000_000).contains(&s.points)
    {
        return Err(Error::setting(
            "harmonics/periods/points",
            "need harmonics ≤ 100000, 1 to 1000 periods, 2 to 1000000 points per period",
        ));
    }
    let gaussian_coefficients: Vec<GaussianRow> = (0..=s.harmonics)
        .map(|n| {
            let c = g.coefficient(n as i64);
            GaussianRow {
                n,
                f_over_f_c: n as f64,
                c_re: c.re,
                c_im: c.im,
                c_abs: c.norm(),
                c_over_p: if s.amplitude != 0.0 {
                    c.norm() / s.amplitude.abs()
                } else {
                    0.0
                },
                thesis_printed_c_over_p: g.thesis_printed_coefficient(n as i64),
            }
        })
        .collect();
    let coef = r.coefficients(s.order);
    let mut rectangular_coefficients = vec![RectRow {
        n: 0,
        a_n: coef.a0,
        b_n: 0.0,
    }];
    rectangular_coefficients.extend((1..=s.order).map(|n| RectRow {
        n,
        a_n: coef.a[n - 1],
        b_n: coef.b[n - 1],
    }));
    let gorder = g.order_for(1e-16).max(1);
    let trains: Vec<TrainRow> = (0..s.periods * s.points)
        .map(|i| {
            let t = tau_c * i as f64 / s.points as f64;
            TrainRow {
                t_s: t,
                gaussian: g.value(t),
                gaussian_series: g.partial_sum(t, gorder),
                rectangular: r.value(t),
                rectangular_series: r.partial_sum(t, s.order),
            }
        })
        .collect();
    let rms = |f: &dyn Fn(&TrainRow) -> f64| {
        (trains.iter().map(|x| f(x).powi(2)).sum::<f64>() / trains.len() as f64).sqrt()
    };
    let gibbs = r.gibbs_overshoot(s.order)?;
    Ok(PulsesTables {
        schema: "ballpass.model.pulses/1",
        version: crate::VERSION,
        tau_c_s: tau_c,
        ratio: s.ratio,
        ratio_kind: s.ratio_kind,
        gaussian: g,
        gaussian_fwhm_s: g.fwhm_s(),
        gaussian_series_order: gorder,
        rectangular: r,
        rectangular_order: s.order,
        rectangular_a0: coef.a0,
        rectangular_gibbs_overshoot_fraction: gibbs,
        fit_rms_gaussian_series: rms(&|x| x.gaussian_series - x.gaussian),
        fit_rms_rectangular_series: rms(&|x| x.rectangular_series - x.rectangular),
        gaussian_coefficients,
        rectangular_coefficients,
        trains,
    })
}

// ---------------------------------------------------------------- stage

/// Settings of [`stage_tables`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StageTableSettings {
    /// The Bode table's log-spaced axis (default 0.01 Hz to 1 kHz, 500 points).
    pub axis: FrequencyAxis,
    /// Sampling rate of the differentiator comparison (thesis Fig. 28), Hz.
    /// Default 1000.
    pub difference_fs_hz: f64,
    /// Ball-pass frequency, Hz: with it, the velocity response to a
    /// Gaussian friction train is computed.
    pub f_c_hz: Option<f64>,
    /// Gaussian `σ / τ_c` of the friction pulses. Default 0.155.
    pub sigma_ratio: f64,
    /// Height P of the friction pulses, N. Default 1.
    pub friction_amplitude_n: f64,
    /// Harmonics and samples of the velocity response.
    pub velocity: VelocityResponseSettings,
}

impl Default for StageTableSettings {
    fn default() -> Self {
        Self {
            axis: FrequencyAxis::default(),
            difference_fs_hz: 1000.0,
            f_c_hz: None,
            sigma_ratio: 0.155,
            friction_amplitude_n: 1.0,
            velocity: VelocityResponseSettings::default(),
        }
    }
}

/// One sample of the velocity response (`velocity_response.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VelocityRow {
    /// Time, s.
    pub t_s: f64,
    /// Friction train, N.
    pub friction_n: f64,
    /// Velocity deviation, mm/s.
    pub velocity_mm_s: f64,
    /// Position deviation, µm.
    pub position_um: f64,
    /// The thesis' magnitude-only sum, mm/s.
    pub velocity_magnitude_only_mm_s: f64,
}

/// The velocity response in brief (part of `stage.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VelocitySummary {
    /// Ball-pass frequency, Hz.
    pub f_c_hz: f64,
    /// The friction pulse train.
    pub friction: GaussianTrain,
    /// Harmonics of friction and velocity.
    pub harmonics: Vec<HarmonicRow>,
    /// Velocity peak to peak, mm/s.
    pub velocity_peak_to_peak_mm_s: f64,
    /// Error of the thesis' magnitude-only sum, fraction of the peak.
    pub magnitude_only_error_of_peak: f64,
}

/// Everything `ballpass model stage` writes; serialises as `stage.json`.
#[derive(Debug, Clone, Serialize)]
pub struct StageTables {
    /// `ballpass.model.stage/1`.
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// The loop.
    pub stage: PdLoop,
    /// Its peaks and corners.
    pub features: LoopFeatures,
    /// Units of the tables.
    pub units_note: &'static str,
    /// The velocity response, when a ball-pass frequency was given.
    pub velocity_response: Option<VelocitySummary>,
    /// `bode.csv`.
    #[serde(skip)]
    pub bode: Vec<BodeRow>,
    /// `difference.csv`.
    #[serde(skip)]
    pub difference: Vec<DifferenceRow>,
    /// The full velocity response (`harmonics.csv`, `velocity_response.csv`).
    #[serde(skip)]
    pub response: Option<VelocityResponse>,
}

impl StageTables {
    /// The rows of `velocity_response.csv` (empty without a response).
    pub fn velocity_rows(&self) -> Vec<VelocityRow> {
        let Some(r) = &self.response else {
            return Vec::new();
        };
        (0..r.time_s.len())
            .map(|i| VelocityRow {
                t_s: r.time_s[i],
                friction_n: r.friction_n[i],
                velocity_mm_s: r.velocity_mm_s[i],
                position_um: r.position_um[i],
                velocity_magnitude_only_mm_s: r.velocity_magnitude_only_mm_s[i],
            })
            .collect()
    }

    /// Writes `bode.csv`, `difference.csv`, with a response
    /// `harmonics.csv` and `velocity_response.csv`, then `stage.json` into
    /// `dir` (which must exist); returns their paths in that order.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut paths = vec![dir.join("bode.csv"), dir.join("difference.csv")];
        write_rows(&paths[0], &self.bode)?;
        write_rows(&paths[1], &self.difference)?;
        if let Some(r) = &self.response {
            let (h, v) = (dir.join("harmonics.csv"), dir.join("velocity_response.csv"));
            write_rows(&h, &r.harmonics)?;
            write_rows(&v, &self.velocity_rows())?;
            paths.extend([h, v]);
        }
        let json = dir.join("stage.json");
        write_pretty_json(&json, self)?;
        paths.push(json);
        Ok(paths)
    }
}

/// The PD stage of thesis §6.1 on grids: Bode table of `G_xr`, `G_xf`,
/// `G_vf`, the differentiator comparison, and (with `f_c_hz`) one period of
/// the velocity under a Gaussian friction pulse train centred at `τ_c / 2`.
///
/// # Errors
/// [`Error::InvalidSetting`] for a bad axis, differentiator rate, `f_c`,
/// pulse ratio or response settings.
pub fn stage_tables(stage: &PdLoop, s: &StageTableSettings) -> Result<StageTables> {
    let features = stage.features();
    let bode = stage.bode(&s.axis)?;
    let difference = difference_responses(s.difference_fs_hz, 500)?;
    let response = match s.f_c_hz {
        Some(f) => {
            if !(f.is_finite() && f > 0.0) {
                return Err(Error::setting(
                    "f_c",
                    format!("must be a positive number of Hz, got {f}"),
                ));
            }
            let tc = 1.0 / f;
            let friction =
                GaussianTrain::new(tc, s.sigma_ratio, s.friction_amplitude_n, 0.0, 0.5 * tc)?;
            Some((friction, velocity_response(stage, &friction, &s.velocity)?))
        }
        None => None,
    };
    Ok(StageTables {
        schema: "ballpass.model.stage/1",
        version: crate::VERSION,
        stage: *stage,
        features,
        units_note: "SI: G_xf in m/N (dB re 1 m/N), G_vf in (m/s)/N (dB re 1 (m/s)/N); velocity response in mm/s, position in um",
        velocity_response: response.as_ref().map(|(friction, r)| VelocitySummary {
            f_c_hz: r.f_c_hz,
            friction: *friction,
            harmonics: r.harmonics.clone(),
            velocity_peak_to_peak_mm_s: r.velocity_peak_to_peak_mm_s,
            magnitude_only_error_of_peak: r.magnitude_only_error_of_peak,
        }),
        bode,
        difference,
        response: response.map(|(_, r)| r),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Eq. 7.1 friction × velocity-error correlation of unit sinusoids
    /// is `+½ sin ω_c τ` (docs/methods.md §4 with the Eq. 7.1 mirror); rounding only.
    #[test]
    fn signals_table_holds_the_analytic_correlation() {
        let t =
            signals_tables(&SinusoidModel::default(), &SignalsTableSettings::default()).unwrap();
        assert_eq!(t.correlations.len(), 401);
        assert_eq!(t.correlations[0].tau_s, -2.0);
        for r in &t.correlations {
            assert!((r.r_fve - 0.5 * (2.0 * PI * r.tau_s).sin()).abs() < 1e-12);
        }
        assert_eq!(t.peaks.len(), 6);
        let bad = SignalsTableSettings {
            points: 1,
            ..Default::default()
        };
        assert!(signals_tables(&SinusoidModel::default(), &bad).is_err());
    }

    /// docs/methods.md §6: |C_1| / P = √(2π) r exp(−2π² r²) = 0.24180 at r = 0.155.
    #[test]
    fn pulses_table_has_the_corrected_coefficients() {
        let t = pulses_tables(&PulsesTableSettings::default()).unwrap();
        assert!((t.gaussian_coefficients[1].c_over_p - 0.24180).abs() < 5e-6);
        assert_eq!(t.rectangular_coefficients.len(), 21);
        assert_eq!(t.trains.len(), 1000);
        let bad = PulsesTableSettings {
            order: 0,
            ..Default::default()
        };
        assert!(pulses_tables(&bad)
            .unwrap_err()
            .to_string()
            .contains("order"));
    }

    /// Without f_c there is no velocity response and no response table.
    #[test]
    fn stage_tables_response_only_with_f_c() {
        let stage = PdLoop::from_natural(5.0, 1.1, 0.35).unwrap();
        let t = stage_tables(&stage, &StageTableSettings::default()).unwrap();
        assert!(t.velocity_response.is_none() && t.velocity_rows().is_empty());
        assert_eq!(t.bode.len(), 500);
        let with = StageTableSettings {
            f_c_hz: Some(1.1),
            ..Default::default()
        };
        let t = stage_tables(&stage, &with).unwrap();
        assert_eq!(t.velocity_rows().len(), 1000);
    }
}
