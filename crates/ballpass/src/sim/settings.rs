//! Everything that defines a simulated recording ([`SimSettings`]) and the
//! range checks of every field.

use serde::{Deserialize, Serialize};

use super::profile::SpeedProfile;
use super::shapes::PulseShape;
use super::stage::StageSettings;
use crate::bearing::{self, check_velocity, Geometry};
use crate::error::{Error, Result};
use crate::recording::Recording;

/// Bearing condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Condition {
    /// Small periodic friction content, hard to see in a spectrum.
    #[default]
    Good,
    /// Sporadic large friction spikes at ball passages (thesis ch. 8).
    Sticking,
}

impl Condition {
    /// Lower-case name (`good`, `sticking`).
    pub fn name(self) -> &'static str {
        match self {
            Condition::Good => "good",
            Condition::Sticking => "sticking",
        }
    }
}

/// How the recording starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// Stage already tracking `V` in steady state; a settling time is
    /// simulated before the first sample so that pulses and roughness have
    /// driven the stage as they would in a long run.
    #[default]
    Settled,
    /// Stage starts at rest, the reference accelerates to `V`, and the
    /// recording triggers when the stage has travelled the trigger distance
    /// (thesis ch. 7).
    FromRest,
}

/// Motion profile and trigger.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MotionSettings {
    /// Reference acceleration from rest, mm/s² (assumption: 100).
    pub acceleration_mm_s2: f64,
    /// Stage travel that triggers the recording in `from_rest`, mm; `None`:
    /// `V² / (2 a) + V t_settle`.
    pub trigger_distance_mm: Option<f64>,
    /// Time allowed for transients, s; `None`: `10 / (zeta omega_n)` (e^-10).
    pub settle_time_s: Option<f64>,
}

impl Default for MotionSettings {
    fn default() -> Self {
        Self {
            acceleration_mm_s2: 100.0,
            trigger_distance_mm: None,
            settle_time_s: None,
        }
    }
}

/// Friction model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionSettings {
    /// Coulomb level `F_c`, N.
    pub coulomb_n: f64,
    /// Peak of the pulse of each ball entering the loaded zone, N.
    pub pulse_amplitude_n: f64,
    /// Friction pulse FWHM as a fraction of `tau_c`.
    pub pulse_width_ratio: f64,
    /// Shape of each ball's friction pulse (Gaussian by default).
    pub pulse_shape: PulseShape,
    /// Standard deviation of the roughness force, N.
    pub roughness_n: f64,
    /// Correlation length of the roughness along the rail (stage travel), mm.
    pub roughness_length_mm: f64,
    /// Probability that a ball entry carries a sticking spike (`sticking` only).
    pub stick_probability: f64,
    /// Largest total friction during a spike, as a multiple of `F_c`: spike
    /// peaks are uniform in `[0, (ratio - 1) F_c]` unless `stick_range_n` is set.
    pub stick_max_ratio: f64,
    /// Spike peaks uniform in `[lo, hi]` N instead (`None`: from `stick_max_ratio`).
    pub stick_range_n: Option<[f64; 2]>,
    /// Sticking spike FWHM as a fraction of `tau_c`.
    pub stick_width_ratio: f64,
    /// Regularisation of the Coulomb sign near zero velocity, mm/s (raised
    /// automatically where needed for stability at the internal step).
    pub zero_velocity_band_mm_s: f64,
}

impl Default for FrictionSettings {
    fn default() -> Self {
        Self {
            coulomb_n: 3.0,
            pulse_amplitude_n: 0.2,
            pulse_width_ratio: 0.155,
            pulse_shape: PulseShape::Gaussian,
            roughness_n: 0.2,
            roughness_length_mm: 1.3,
            stick_probability: 0.6,
            stick_max_ratio: 10.0,
            stick_range_n: None,
            stick_width_ratio: 0.05,
            zero_velocity_band_mm_s: 1e-3,
        }
    }
}

/// Quartz load cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadCellSettings {
    /// Discharge time constant of the first-order high-pass, s. The 208C01 is
    /// specified at >= 50 s, but thesis Fig. 54 decays within ~10 s; 10 s.
    /// `None`: a DC-coupled force sensor (no discharge).
    pub time_constant_s: Option<f64>,
    /// White noise on the recorded samples, N (std).
    pub noise_n: f64,
    /// Analog anti-alias low-pass cut-off, Hz.
    pub antialias_hz: f64,
}

impl Default for LoadCellSettings {
    fn default() -> Self {
        Self {
            time_constant_s: Some(10.0),
            noise_n: 0.02,
            antialias_hz: 400.0,
        }
    }
}

/// Linear encoder.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EncoderSettings {
    /// Resolution, µm (Renishaw RGH22 on the ABL20100: 0.1 µm).
    pub resolution_um: f64,
}

impl Default for EncoderSettings {
    fn default() -> Self {
        Self { resolution_um: 0.1 }
    }
}

/// Optical ball-pass sensor (photodetector).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OpticalSettings {
    /// DC level, V.
    pub dc_v: f64,
    /// Peak of a ball's pulse, V.
    pub pulse_amplitude_v: f64,
    /// Relative ball-to-ball variation of the pulse height (std).
    pub amplitude_jitter: f64,
    /// Pulse FWHM (width at half prominence) as a fraction of `tau_c` (thesis: 0.155).
    pub width_ratio: f64,
    /// Shape of each ball's pulse (Gaussian by default).
    pub pulse_shape: PulseShape,
    /// Distance from the loaded-zone entry to the sensor along the ball path, mm.
    /// Optical pulses lag friction pulses by `offset / (v / 2)`; 1.755 mm gives
    /// the thesis' 0.39 s at 9 mm/s (0.433 tau_c at every speed).
    pub sensor_offset_mm: f64,
    /// White noise on the recorded samples, V (std).
    pub noise_v: f64,
    /// Analog anti-alias low-pass cut-off, Hz.
    pub antialias_hz: f64,
    /// AC coupling (first-order high-pass) before the anti-alias filter (thesis Fig. 38).
    pub ac_coupling: bool,
    /// AC-coupling time constant, s.
    pub ac_time_constant_s: f64,
    /// Coherent-source interference drift (thesis Fig. 32): a slow sinusoid
    /// `A sin(theta)` added to the signal and pulses multiplied by `-sin(theta)`,
    /// so pulses point up in its troughs, invert at its crests and vanish at
    /// its mid-level.
    pub interference_drift: bool,
    /// Period of the interference drift, s (thesis: 5 s).
    pub interference_period_s: f64,
    /// Amplitude of the interference drift, V.
    pub interference_amplitude_v: f64,
    /// Slow wander of the DC level that leaves the pulses as they are (lamp
    /// ageing, temperature), peak, V: the sum of two sinusoids of random
    /// phase, periods `baseline_drift_period_s` and 0.37 of it, amplitudes
    /// 0.6 and 0.4 of this. 0: none.
    pub baseline_drift_v: f64,
    /// Period of the slower drift component, s.
    pub baseline_drift_period_s: f64,
}

impl Default for OpticalSettings {
    fn default() -> Self {
        Self {
            dc_v: 1.0,
            pulse_amplitude_v: 0.5,
            amplitude_jitter: 0.05,
            width_ratio: 0.155,
            pulse_shape: PulseShape::Gaussian,
            sensor_offset_mm: 1.755,
            noise_v: 0.01,
            antialias_hz: 400.0,
            ac_coupling: false,
            ac_time_constant_s: 1.0,
            interference_drift: false,
            interference_period_s: 5.0,
            interference_amplitude_v: 0.5,
            baseline_drift_v: 0.0,
            baseline_drift_period_s: 30.0,
        }
    }
}

/// Everything that defines a simulated recording. Same settings (seed
/// included), same samples, bit for bit, on one platform.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimSettings {
    /// Tracking velocity `V`, mm/s.
    pub velocity_mm_s: f64,
    /// Recorded duration, s.
    pub duration_s: f64,
    /// Sampling rate of the recording, Hz.
    pub fs_hz: f64,
    /// Internal steps per sample (internal rate = `oversample * fs`).
    pub oversample: u32,
    /// Seed of all random draws.
    pub seed: u64,
    /// Bearing name written to the metadata (catalog key or a campaign label).
    pub bearing: String,
    /// Ball-circuit geometry.
    pub geometry: Geometry,
    /// Test id written to the metadata; `None`: `sim-v{V}-s{seed}`.
    pub test_id: Option<String>,
    /// Bearing condition.
    pub condition: Condition,
    /// Settled or from rest.
    pub start: Start,
    /// Stage model.
    pub stage: StageSettings,
    /// Motion profile and trigger.
    pub motion: MotionSettings,
    /// Friction model.
    pub friction: FrictionSettings,
    /// Load cell.
    pub load_cell: LoadCellSettings,
    /// Encoder.
    pub encoder: EncoderSettings,
    /// Photodetector.
    pub optical: OpticalSettings,
    /// A multi-speed run instead of one velocity (see [`super::profile`]):
    /// the stage starts settled at the first plateau's velocity and
    /// `velocity_mm_s` is not used for the motion. `None` (the default,
    /// and absent from the JSON) for one constant velocity.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub profile: Option<SpeedProfile>,
    /// A compensation table the controller applies as feedforward force
    /// (see [`super::feedforward`]); `None` (the default, absent from the
    /// JSON): no feedforward.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedforward: Option<super::feedforward::Feedforward>,
}

impl Default for SimSettings {
    fn default() -> Self {
        Self {
            velocity_mm_s: 9.0,
            duration_s: 30.0,
            fs_hz: 1000.0,
            oversample: 20,
            seed: 0,
            bearing: "sr25w".into(),
            geometry: SR25W,
            test_id: None,
            condition: Condition::Good,
            start: Start::Settled,
            stage: StageSettings::default(),
            motion: MotionSettings::default(),
            friction: FrictionSettings::default(),
            load_cell: LoadCellSettings::default(),
            encoder: EncoderSettings::default(),
            optical: OpticalSettings::default(),
            profile: None,
            feedforward: None,
        }
    }
}

const SR25W: Geometry = Geometry {
    ball_diameter_mm: 4.0,
    free_space_mm: 2.0,
    balls_in_race: 36,
};

/// Most samples one recording may have (guards against a typo like `--fs 1e9`).
pub const MAX_SAMPLES: usize = 50_000_000;

fn positive(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            name,
            format!("must be a positive number, got {v}"),
        ))
    }
}

fn non_negative(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            name,
            format!("must be zero or a positive number, got {v}"),
        ))
    }
}

impl SimSettings {
    /// Settings for a catalog bearing at one velocity, other fields default.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an unknown bearing key.
    pub fn for_bearing(key: &str, velocity_mm_s: f64) -> Result<Self> {
        let entry = bearing::find(key)?;
        Ok(Self {
            velocity_mm_s,
            bearing: entry.key.into(),
            geometry: entry.geometry,
            ..Self::default()
        })
    }

    /// Number of recorded samples, `round(duration * fs)`.
    pub fn n_samples(&self) -> usize {
        (self.duration_s * self.fs_hz).round() as usize
    }

    /// Checks every field's range.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field and the value.
    pub fn validate(&self) -> Result<()> {
        check_velocity(self.velocity_mm_s)?;
        positive("duration", self.duration_s)?;
        positive("fs", self.fs_hz)?;
        if !(1..=1000).contains(&self.oversample) {
            return Err(Error::setting(
                "oversample",
                format!("must be 1 to 1000, got {}", self.oversample),
            ));
        }
        let n = self.duration_s * self.fs_hz;
        if n.round() < Recording::MIN_SAMPLES as f64 || n > MAX_SAMPLES as f64 {
            return Err(Error::setting(
                "duration",
                format!(
                    "{} s at {} Hz gives {n:.0} samples; expected {} to {MAX_SAMPLES}",
                    self.duration_s,
                    self.fs_hz,
                    Recording::MIN_SAMPLES
                ),
            ));
        }
        self.geometry.validate()?;
        self.stage.validate()?;
        let band = self.friction.zero_velocity_band_mm_s;
        if self.velocity_mm_s < 10.0 * band {
            return Err(Error::setting(
                "velocity",
                format!(
                    "{} mm/s is within 10x the friction's zero-velocity band ({band} mm/s); expected at least {}",
                    self.velocity_mm_s,
                    10.0 * band
                ),
            ));
        }
        let passages =
            self.velocity_mm_s * (self.duration_s + 100.0) / (2.0 * self.geometry.d_avg_mm());
        if passages > 1e7 {
            return Err(Error::setting(
                "velocity",
                format!(
                    "{} mm/s over {} s makes {passages:.0} ball passages; at most 1e7",
                    self.velocity_mm_s, self.duration_s
                ),
            ));
        }
        if let Some(f) = &self.feedforward {
            f.validate()?;
        }
        if let Some(p) = &self.profile {
            p.validate(10.0 * band)?;
            if self.start != Start::Settled {
                return Err(Error::setting(
                    "start",
                    "a speed profile starts settled at its first plateau; use start = settled",
                ));
            }
            let passages =
                p.max_speed_mm_s() * (self.duration_s + 100.0) / (2.0 * self.geometry.d_avg_mm());
            if passages > 1e7 {
                return Err(Error::setting(
                    "profile",
                    format!("makes up to {passages:.0} ball passages; at most 1e7"),
                ));
            }
        }
        positive("acceleration", self.motion.acceleration_mm_s2)?;
        if let Some(d) = self.motion.trigger_distance_mm {
            non_negative("trigger distance", d)?;
        }
        if let Some(t) = self.motion.settle_time_s {
            non_negative("settle time", t)?;
        }
        let f = &self.friction;
        non_negative("friction coulomb_n", f.coulomb_n)?;
        non_negative("friction pulse_amplitude_n", f.pulse_amplitude_n)?;
        positive("friction pulse_width_ratio", f.pulse_width_ratio)?;
        non_negative("friction roughness_n", f.roughness_n)?;
        positive("friction roughness_length_mm", f.roughness_length_mm)?;
        if !(0.0..=1.0).contains(&f.stick_probability) {
            return Err(Error::setting(
                "friction stick_probability",
                format!("must be between 0 and 1, got {}", f.stick_probability),
            ));
        }
        if !(f.stick_max_ratio.is_finite() && f.stick_max_ratio >= 1.0) {
            return Err(Error::setting(
                "friction stick_max_ratio",
                format!("must be at least 1, got {}", f.stick_max_ratio),
            ));
        }
        positive("friction stick_width_ratio", f.stick_width_ratio)?;
        if let Some([lo, hi]) = f.stick_range_n {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi >= lo) {
                return Err(Error::setting(
                    "friction stick_range_n",
                    format!("must be [lo, hi] with 0 <= lo <= hi, got [{lo}, {hi}]"),
                ));
            }
        }
        positive(
            "friction zero_velocity_band_mm_s",
            f.zero_velocity_band_mm_s,
        )?;
        if let Some(tau) = self.load_cell.time_constant_s {
            positive("load-cell time constant", tau)?;
        }
        non_negative("load-cell noise", self.load_cell.noise_n)?;
        positive("load-cell anti-alias cut-off", self.load_cell.antialias_hz)?;
        positive("encoder resolution", self.encoder.resolution_um)?;
        let o = &self.optical;
        for (name, v) in [
            ("optical dc_v", o.dc_v),
            ("optical pulse_amplitude_v", o.pulse_amplitude_v),
            ("optical sensor_offset_mm", o.sensor_offset_mm),
            (
                "optical interference_amplitude_v",
                o.interference_amplitude_v,
            ),
        ] {
            if !v.is_finite() {
                return Err(Error::setting(name, format!("must be finite, got {v}")));
            }
        }
        non_negative("optical amplitude_jitter", o.amplitude_jitter)?;
        positive("optical width_ratio", o.width_ratio)?;
        non_negative("optical noise_v", o.noise_v)?;
        positive("optical anti-alias cut-off", o.antialias_hz)?;
        positive("optical AC-coupling time constant", o.ac_time_constant_s)?;
        positive("optical interference period", o.interference_period_s)?;
        non_negative("optical baseline_drift_v", o.baseline_drift_v)?;
        positive("optical baseline drift period", o.baseline_drift_period_s)?;
        Ok(())
    }

    pub(super) fn settle_time_s(&self) -> f64 {
        self.motion
            .settle_time_s
            .unwrap_or_else(|| 10.0 / (self.stage.damping_ratio() * self.stage.omega_n_rad_s()))
    }

    pub(super) fn trigger_distance_mm(&self) -> f64 {
        self.motion.trigger_distance_mm.unwrap_or_else(|| {
            let v = self.velocity_mm_s;
            v * v / (2.0 * self.motion.acceleration_mm_s2) + v * self.settle_time_s()
        })
    }
}
