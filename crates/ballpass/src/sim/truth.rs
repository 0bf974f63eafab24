//! What is true about a simulated recording: the truth file `NAME.truth.json`.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::profile::PlateauTruth;
use super::settings::{Condition, SimSettings};
use crate::error::Result;
use crate::recording::Recording;

/// Schema tag of the truth file.
pub const TRUTH_SCHEMA: &str = "ballpass.truth/1";

/// A simulated recording and what is true about it.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The recording (friction_N, position_mm, optical_V).
    pub recording: Recording,
    /// The truth.
    pub truth: Truth,
}

/// One sticking spike.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spike {
    /// Time of the spike's centre (the ball's loaded-zone entry), s from the first sample.
    pub time_s: f64,
    /// Peak added to the friction, N.
    pub amplitude_n: f64,
}

/// What is true about a simulated recording (schema `ballpass.truth/1`).
///
/// Times are seconds from the first sample. Lags are of the fundamental at
/// the realised `f_c`, between the *recorded* channels (sensor filters
/// included), wrapped into `(-tau_c/2, tau_c/2]`; a positive lag means the
/// signal lags the friction force, and the phase is `-360 lag / tau_c`
/// degrees (docs/methods.md §8 convention). The `*_force_*` lags are the same
/// against the friction *force* itself, without the load cell's discharge
/// high-pass (what an analysis that restores the load cell's DC measures).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// `ballpass.truth/1`.
    pub schema: String,
    /// ballpass version that produced it.
    pub version: String,
    /// Bearing condition.
    pub condition: Condition,
    /// Commanded velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Number of samples per channel.
    pub n_samples: usize,
    /// Simulated time before the first sample (settling or acceleration), s.
    pub record_start_time_s: f64,
    /// Mean ball spacing `d_avg`, mm.
    pub d_avg_mm: f64,
    /// Predicted ball-pass frequency `V / (2 d_avg)`, Hz.
    pub f_c_nominal_hz: f64,
    /// Predicted ball-pass period, s.
    pub tau_c_nominal_s: f64,
    /// Mean stage velocity over the recording, mm/s.
    pub mean_velocity_mm_s: f64,
    /// Realised long-run ball-pass frequency `mean velocity / (2 d_avg)`, Hz.
    pub f_c_hz: f64,
    /// Realised ball-pass period `1 / f_c_hz`, s.
    pub tau_c_s: f64,
    /// Mean optical passage rate in the recording, `(n - 1) / (t_last - t_first)`, Hz
    /// (`None` with fewer than two passages). Varies about `f_c` with the spacings.
    pub passage_rate_hz: Option<f64>,
    /// Centre-to-centre spacings of the circuit, ball `k` to `k + 1`, mm.
    pub ball_spacings_mm: Vec<f64>,
    /// Times the ball centres pass the optical sensor, s.
    pub optical_passage_times_s: Vec<f64>,
    /// Which ball made each optical passage.
    pub optical_passage_balls: Vec<usize>,
    /// Times the ball centres enter the loaded zone (friction pulse centres), s.
    pub friction_pulse_times_s: Vec<f64>,
    /// Which ball made each friction pulse.
    pub friction_pulse_balls: Vec<usize>,
    /// Sticking spikes in the recording (empty for a good bearing).
    pub sticking_spikes: Vec<Spike>,
    /// Optical pulse width at half prominence (FWHM), s.
    pub optical_pulse_fwhm_s: f64,
    /// Optical pulse Gaussian sigma, s.
    pub optical_pulse_sigma_s: f64,
    /// Optical pulse FWHM / tau_c.
    pub optical_pulse_fwhm_tau_c: f64,
    /// Friction pulse FWHM, s.
    pub friction_pulse_fwhm_s: f64,
    /// Delay of the optical pulses after the friction pulses, `offset / (v/2)`, s (not wrapped).
    pub optical_delay_s: f64,
    /// Lag of the optical channel behind the friction channel, s. Since
    /// session 17 it rests on the fundamentals of the two pulse trains as
    /// the simulator generated them in time (Hann-windowed DFT at `f_c`,
    /// records of ten periods or more; `fundamental_phase_difference`),
    /// not on `optical_delay_s` and the pulse shapes alone: both trains are
    /// fixed in the travel, so a velocity ripple locked to the ball
    /// passages (the stage answering the friction ripple, strongest when
    /// `f_c` or `2 f_c` is near its resonance) moves them in time by the
    /// stage's position ripple at their instants, and the recorded channels
    /// show that. At one speed only; with a speed profile, or fewer than ten
    /// periods, the geometric delay at the mean speed.
    pub optical_lag_s: f64,
    /// Same, in units of tau_c.
    pub optical_lag_tau_c: f64,
    /// Phase of the optical channel relative to friction, degrees.
    pub optical_phase_deg: f64,
    /// Lag of the optical channel behind the friction force (no load-cell
    /// high-pass), s.
    pub optical_lag_force_s: f64,
    /// Same, in units of tau_c.
    pub optical_lag_force_tau_c: f64,
    /// Lag of the velocity error behind the friction force, s.
    pub velocity_error_lag_force_s: f64,
    /// Same, in units of tau_c.
    pub velocity_error_lag_force_tau_c: f64,
    /// Phase the load cell adds at f_c (high-pass and anti-alias), degrees.
    pub load_cell_phase_deg: f64,
    /// Amplitude (peak) of the f_c component of the regular friction ripple
    /// (the balls' pulses, without roughness or sticking), N.
    pub friction_fundamental_n: f64,
    /// Lag of the velocity error (from the position channel) behind the friction channel, s.
    pub velocity_error_lag_s: f64,
    /// Same, in units of tau_c.
    pub velocity_error_lag_tau_c: f64,
    /// Phase of the velocity error relative to friction, degrees.
    pub velocity_error_phase_deg: f64,
    /// `|G_vf(j 2 pi f_c)|`, velocity error per unit friction at f_c, (mm/s)/N.
    pub g_vf_gain_mm_s_per_n: f64,
    /// Stage natural frequency `sqrt(K K_P / m) / 2 pi`, Hz.
    pub natural_frequency_hz: f64,
    /// Stage damping ratio.
    pub damping_ratio: f64,
    /// Steady lag of the stage behind the reference, `F_c / (K K_P)`, mm.
    pub steady_offset_mm: f64,
    /// Std of the velocity error as the analysis computes it (`numpy.gradient`
    /// of the encoder position, minus V), mm/s.
    pub velocity_error_std_mm_s: f64,
    /// Std of the true (unquantised) velocity error at the sample instants, mm/s.
    pub velocity_error_true_std_mm_s: f64,
    /// Phase of the interference drift at the first sample, rad (when enabled).
    pub interference_phase_rad: Option<f64>,
    /// With a speed profile: each plateau's commanded interval and velocity
    /// and the stage's mean velocity over it (absent otherwise). The
    /// single-speed fields above then refer to the first plateau's speed,
    /// `mean_velocity_mm_s` is the mean speed over the record, and the
    /// passage times are first forward crossings only.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plateaus: Vec<PlateauTruth>,
    /// All parameters.
    pub settings: SimSettings,
}

impl Truth {
    /// Writes the truth as pretty-printed JSON, atomically (temporary file
    /// beside `path`, then rename).
    ///
    /// # Errors
    /// [`crate::Error::Io`] naming the file.
    pub fn write_json(&self, path: &Path) -> Result<()> {
        crate::fsutil::write_atomic_with(path, |w| {
            serde_json::to_writer_pretty(&mut *w, self).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        })
    }
}

/// `arg O(ω) − arg F(ω)` (radians, unwrapped to `(−π, π]`), with `F`
/// and `O` the Hann-windowed DFTs at `w_per_sample` (radians per sample) of
/// the mean-removed friction ripple and optical pulse train as the
/// simulator generated them in time; `None` with fewer than ten periods in
/// the record (the window's leakage from DC and the harmonics is then no
/// longer negligible) or a train without a fundamental.
pub(crate) fn fundamental_phase_difference(
    friction: &[f64],
    optical: &[f64],
    w_per_sample: f64,
) -> Option<f64> {
    let n = friction.len().min(optical.len());
    if n < 2 || (n as f64) * w_per_sample < 10.0 * std::f64::consts::TAU {
        return None;
    }
    let dft = |x: &[f64]| {
        let m = x[..n].iter().sum::<f64>() / n as f64;
        let (mut re, mut im, mut e) = (0.0, 0.0, 0.0);
        for (i, v) in x[..n].iter().enumerate() {
            let h = 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos();
            let a = w_per_sample * i as f64;
            let d = h * (v - m);
            re += d * a.cos();
            im -= d * a.sin();
            e += d * d;
        }
        (re, im, e)
    };
    let (fr, fi, fe) = dft(friction);
    let (or, oi, oe) = dft(optical);
    // A fundamental of at least 1e-6 of the train's windowed energy.
    let has = |re: f64, im: f64, e: f64| e > 0.0 && re * re + im * im > 1e-12 * e * n as f64;
    if !has(fr, fi, fe) || !has(or, oi, oe) {
        return None;
    }
    let d = oi.atan2(or) - fi.atan2(fr);
    let tau = std::f64::consts::TAU;
    Some(d - tau * ((d + std::f64::consts::PI) / tau).floor())
}

/// The truth file that belongs beside a recording: `rec.csv` → `rec.truth.json`.
pub fn truth_path(recording_path: &Path) -> PathBuf {
    recording_path.with_extension("truth.json")
}

#[cfg(test)]
mod tests {
    use super::fundamental_phase_difference;

    /// Two sinusoids 12.3 periods long, the second 0.7 rad behind, over
    /// offsets and harmonics of their own: the phase difference within
    /// 1e-3 rad (the Hann window's leakage from DC and 2 f at 12 periods is
    /// below 1e-4); too short a record gives `None`.
    #[test]
    fn the_fundamental_phase_difference_of_two_trains() {
        let (n, w) = (4000usize, std::f64::consts::TAU * 12.3 / 4000.0);
        let f: Vec<f64> = (0..n)
            .map(|i| 3.0 + (w * i as f64 + 0.2).cos() + 0.5 * (2.0 * w * i as f64).cos())
            .collect();
        let o: Vec<f64> = (0..n)
            .map(|i| {
                1.0 + 2.0 * (w * i as f64 + 0.2 - 0.7).cos() + 0.3 * (3.0 * w * i as f64).sin()
            })
            .collect();
        let d = fundamental_phase_difference(&f, &o, w).unwrap();
        assert!((d + 0.7).abs() < 1e-3, "{d}");
        assert_eq!(
            fundamental_phase_difference(&f[..3000], &o[..3000], w),
            None
        );
        assert_eq!(fundamental_phase_difference(&vec![1.0; n], &o, w), None);
    }
}
