//! Randomized benches: a [`Domain`] of bench parameters, and the concrete
//! [`Bench`] drawn from it, which turns into simulator settings for each
//! bearing of a fleet.
//!
//! The default domain is the one the verdicts are validated over (issue
//! "verdicts that hold on any bench"):
//!
//! | part | range |
//! |---|---|
//! | velocity | 1–20 mm/s |
//! | sampling rate | 500, 1000, 2000, 2500, 5000 Hz |
//! | duration | 10–120 s per record (longer in the record-length scenarios) |
//! | geometry | ball 2–8 mm, 20–60 balls, free space 0.05–0.5 of a ball per circuit |
//! | Coulomb level | 1.5–6 N |
//! | good-bearing ripple | 0–10 % of the Coulomb level; shape Gaussian, raised cosine, skewed, rectangular or a continuous ripple; FWHM 0.05–0.3 τc |
//! | rail roughness | 0–5 % of the Coulomb level, correlation length 0.5–3 mm |
//! | friction noise | 0.002–0.05 N (log-uniform) |
//! | load cell | DC coupled (20 %) or discharge τ 0.3–100 s (log-uniform); 0.5–20 s of motion before the record |
//! | stage | f_n 1–50 Hz (log-uniform), ζ 0.1–1.0, mass 10–300 kg (log-uniform) |
//! | optical pulses | FWHM 0.05–0.45 τc, SNR 5–50 (log-uniform), Gaussian, raised cosine or skewed |
//! | optical sensor | AC coupled (50 %, τ 0.5–10 s), baseline drift (30 %, up to the pulse height), coherent-light interference (10 %) |
//! | sticking | severity 0 (mild) to 1 (severe), see [`Sticking`] |
//!
//! Within a fleet every bearing shares the bench; a good bearing's ripple,
//! roughness and Coulomb level vary by ±30 %, ±30 % and ±15 % around the
//! bench's (bearings of one batch differ a little).

use serde::{Deserialize, Serialize};

use crate::bearing::Geometry;
use crate::error::{Error, Result};
use crate::sim::rng::Rng;
use crate::sim::{
    Condition, FrictionSettings, LoadCellSettings, MotionSettings, OpticalSettings, PulseShape,
    SimSettings, StageSettings, Start,
};

/// A closed range `[lo, hi]` drawn uniformly, or log-uniformly. In JSON
/// an object `{"lo": .., "hi": .., "log": false}` or a single number (a
/// fixed value).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "RangeRepr")]
pub struct Range {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Draw uniformly in `log` (both ends positive).
    #[serde(default)]
    pub log: bool,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RangeRepr {
    Fixed(f64),
    Range {
        lo: f64,
        hi: f64,
        #[serde(default)]
        log: bool,
    },
}

impl From<RangeRepr> for Range {
    fn from(r: RangeRepr) -> Self {
        match r {
            RangeRepr::Fixed(v) => Range::fixed(v),
            RangeRepr::Range { lo, hi, log } => Range { lo, hi, log },
        }
    }
}

impl Range {
    /// A uniform range.
    pub const fn lin(lo: f64, hi: f64) -> Self {
        Self { lo, hi, log: false }
    }

    /// A log-uniform range.
    pub const fn log(lo: f64, hi: f64) -> Self {
        Self { lo, hi, log: true }
    }

    /// A single value.
    pub const fn fixed(v: f64) -> Self {
        Self::lin(v, v)
    }

    /// One draw.
    pub fn draw(&self, rng: &mut Rng) -> f64 {
        let u = rng.uniform();
        if self.log && self.lo > 0.0 && self.hi > 0.0 {
            (self.lo.ln() + u * (self.hi.ln() - self.lo.ln())).exp()
        } else {
            self.lo + u * (self.hi - self.lo)
        }
    }
}

/// The bench parameters validation draws from (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Domain {
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: Range,
    /// Sampling rates to choose from, Hz.
    pub fs_hz: Vec<f64>,
    /// Duration of each record, s.
    pub duration_s: Range,
    /// Ball diameter, mm.
    pub ball_diameter_mm: Range,
    /// Balls in the circuit.
    pub balls_in_race: Range,
    /// Free space of the circuit, in ball diameters.
    pub free_space_per_ball: Range,
    /// Coulomb friction level, N.
    pub coulomb_n: Range,
    /// Good-bearing ripple (pulse peak), fraction of the Coulomb level.
    pub ripple_fraction: Range,
    /// Friction pulse FWHM, fraction of tau_c.
    pub friction_pulse_width_ratio: Range,
    /// Friction pulse shapes to choose from.
    pub friction_shapes: Vec<PulseShape>,
    /// Rail roughness std, fraction of the Coulomb level.
    pub roughness_fraction: Range,
    /// Roughness correlation length, mm.
    pub roughness_length_mm: Range,
    /// Load-cell noise std, N.
    pub friction_noise_n: Range,
    /// Probability that the force sensor is DC coupled (no discharge).
    pub load_cell_dc_probability: f64,
    /// Load-cell discharge time constant, s.
    pub load_cell_tau_s: Range,
    /// Motion before the first sample (discharge already under way), s.
    pub pre_record_s: Range,
    /// Stage natural frequency, Hz.
    pub stage_f_n_hz: Range,
    /// Stage damping ratio.
    pub stage_zeta: Range,
    /// Stage moving mass, kg.
    pub stage_mass_kg: Range,
    /// Optical pulse FWHM, fraction of tau_c.
    pub optical_width_ratio: Range,
    /// Optical pulse shapes to choose from.
    pub optical_shapes: Vec<PulseShape>,
    /// Optical pulse height, V.
    pub optical_pulse_v: Range,
    /// Optical pulse height over the noise std.
    pub optical_snr: Range,
    /// Probability of AC coupling.
    pub ac_probability: f64,
    /// AC-coupling time constant, s.
    pub ac_tau_s: Range,
    /// Probability of a baseline drift.
    pub drift_probability: f64,
    /// Drift amplitude, in pulse heights.
    pub drift_fraction: Range,
    /// Drift period, s.
    pub drift_period_s: Range,
    /// Probability of coherent-light interference (pulses fade and invert).
    pub interference_probability: f64,
    /// Sticking severity, 0 (mild) to 1 (severe).
    pub sticking_severity: Range,
}

impl Default for Domain {
    fn default() -> Self {
        Self {
            velocity_mm_s: Range::lin(1.0, 20.0),
            fs_hz: vec![500.0, 1000.0, 2000.0, 2500.0, 5000.0],
            duration_s: Range::log(10.0, 120.0),
            ball_diameter_mm: Range::lin(2.0, 8.0),
            balls_in_race: Range::lin(20.0, 60.0),
            free_space_per_ball: Range::lin(0.05, 0.5),
            coulomb_n: Range::lin(1.5, 6.0),
            ripple_fraction: Range::lin(0.0, 0.10),
            friction_pulse_width_ratio: Range::lin(0.05, 0.3),
            friction_shapes: PulseShape::ALL.to_vec(),
            roughness_fraction: Range::lin(0.0, 0.05),
            roughness_length_mm: Range::log(0.5, 3.0),
            friction_noise_n: Range::log(0.002, 0.05),
            load_cell_dc_probability: 0.2,
            load_cell_tau_s: Range::log(0.3, 100.0),
            pre_record_s: Range::lin(0.5, 20.0),
            stage_f_n_hz: Range::log(1.0, 50.0),
            stage_zeta: Range::lin(0.1, 1.0),
            stage_mass_kg: Range::log(10.0, 300.0),
            optical_width_ratio: Range::lin(0.05, 0.45),
            optical_shapes: vec![
                PulseShape::Gaussian,
                PulseShape::RaisedCosine,
                PulseShape::Skewed,
            ],
            optical_pulse_v: Range::log(0.1, 2.0),
            optical_snr: Range::log(5.0, 50.0),
            ac_probability: 0.5,
            ac_tau_s: Range::log(0.5, 10.0),
            drift_probability: 0.3,
            drift_fraction: Range::lin(0.0, 1.0),
            drift_period_s: Range::log(5.0, 60.0),
            interference_probability: 0.1,
            sticking_severity: Range::lin(0.0, 1.0),
        }
    }
}

/// How a sticking bearing sticks (thesis ch. 8): sporadic spikes of random
/// height at ball entries.
///
/// Severity `s` in `[0, 1]`: a fraction `0.1 + 0.5 s` of the passages carry
/// a spike whose peak is uniform in `[2 (1 − s) A, 3 A + s (9 F_c − 3 A)]`,
/// with `A = max(ripple, 0.02 F_c)` the good bearing's ripple (at least 2 %
/// of the Coulomb level, so that a bench without ripple still has spikes).
/// `s = 0` is "mild" (spikes 2–3 times the ripple on 10 % of the passages),
/// `s = 1` the simulator's default sticking bearing (up to ten times the
/// friction on 60 % of the passages, thesis Fig. 66).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sticking {
    /// Severity, 0 (mild) to 1 (severe).
    pub severity: f64,
    /// Fraction of passages with a spike.
    pub probability: f64,
    /// Spike peaks, N: uniform in this range.
    pub range_n: [f64; 2],
    /// Spike FWHM, fraction of tau_c.
    pub width_ratio: f64,
}

impl Sticking {
    /// The sticking of `severity` for a bearing of ripple `ripple_n` and
    /// Coulomb level `coulomb_n`.
    pub fn of(severity: f64, ripple_n: f64, coulomb_n: f64, width_ratio: f64) -> Self {
        let s = severity.clamp(0.0, 1.0);
        let a = ripple_n.max(0.02 * coulomb_n);
        Self {
            severity: s,
            probability: 0.1 + 0.5 * s,
            range_n: [
                2.0 * (1.0 - s) * a,
                3.0 * a + s * (9.0 * coulomb_n - 3.0 * a),
            ],
            width_ratio,
        }
    }
}

/// One drawn bench: every parameter concrete.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bench {
    /// Seed the bench was drawn with.
    pub seed: u64,
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration of each record, s.
    pub duration_s: f64,
    /// Bearing geometry.
    pub geometry: Geometry,
    /// Friction model of a good bearing (ripple, shape, roughness, Coulomb level).
    pub friction: FrictionSettings,
    /// Load cell.
    pub load_cell: LoadCellSettings,
    /// Motion before the first sample, s.
    pub pre_record_s: f64,
    /// Stage.
    pub stage: StageSettings,
    /// Optical sensor.
    pub optical: OpticalSettings,
    /// Sticking severity used when a bearing of this bench sticks.
    pub sticking_severity: f64,
}

fn pick<T: Copy>(v: &[T], rng: &mut Rng) -> T {
    let i = ((rng.uniform() * v.len() as f64) as usize).min(v.len() - 1);
    v[i]
}

impl Domain {
    /// Checks the domain: every range ordered and finite (positive when
    /// log-uniform), rates positive, probabilities in [0, 1], shape lists
    /// not empty, and a bench drawn from it a valid simulator setting.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the key.
    pub fn validate(&self) -> Result<()> {
        let ranges = [
            ("velocity_mm_s", self.velocity_mm_s),
            ("duration_s", self.duration_s),
            ("ball_diameter_mm", self.ball_diameter_mm),
            ("balls_in_race", self.balls_in_race),
            ("free_space_per_ball", self.free_space_per_ball),
            ("coulomb_n", self.coulomb_n),
            ("ripple_fraction", self.ripple_fraction),
            (
                "friction_pulse_width_ratio",
                self.friction_pulse_width_ratio,
            ),
            ("roughness_fraction", self.roughness_fraction),
            ("roughness_length_mm", self.roughness_length_mm),
            ("friction_noise_n", self.friction_noise_n),
            ("load_cell_tau_s", self.load_cell_tau_s),
            ("pre_record_s", self.pre_record_s),
            ("stage_f_n_hz", self.stage_f_n_hz),
            ("stage_zeta", self.stage_zeta),
            ("stage_mass_kg", self.stage_mass_kg),
            ("optical_width_ratio", self.optical_width_ratio),
            ("optical_pulse_v", self.optical_pulse_v),
            ("optical_snr", self.optical_snr),
            ("ac_tau_s", self.ac_tau_s),
            ("drift_fraction", self.drift_fraction),
            ("drift_period_s", self.drift_period_s),
            ("sticking_severity", self.sticking_severity),
        ];
        for (name, r) in ranges {
            if !(r.lo.is_finite() && r.hi.is_finite() && r.lo <= r.hi) || (r.log && r.lo <= 0.0) {
                return Err(Error::setting(
                    format!("domain {name}"),
                    format!(
                        "must be a finite range with lo ≤ hi (lo > 0 when log), got [{}, {}]",
                        r.lo, r.hi
                    ),
                ));
            }
        }
        if self.fs_hz.is_empty() || self.fs_hz.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
            return Err(Error::setting(
                "domain fs_hz",
                "must list positive sampling rates",
            ));
        }
        if self.friction_shapes.is_empty() || self.optical_shapes.is_empty() {
            return Err(Error::setting(
                "domain shapes",
                "friction_shapes and optical_shapes must not be empty",
            ));
        }
        for (name, p) in [
            ("load_cell_dc_probability", self.load_cell_dc_probability),
            ("ac_probability", self.ac_probability),
            ("drift_probability", self.drift_probability),
            ("interference_probability", self.interference_probability),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(Error::setting(
                    format!("domain {name}"),
                    format!("must be a probability in [0, 1], got {p}"),
                ));
            }
        }
        let b = self.draw(0);
        b.settings(&b.bearing(0, true), 0).validate()
    }

    /// Draws one bench (deterministic in `seed`).
    pub fn draw(&self, seed: u64) -> Bench {
        let mut r = Rng::new(seed);
        let velocity_mm_s = self.velocity_mm_s.draw(&mut r);
        let fs_hz = pick(&self.fs_hz, &mut r);
        let duration_s = self.duration_s.draw(&mut r);
        let d = self.ball_diameter_mm.draw(&mut r);
        let n_b = self.balls_in_race.draw(&mut r).round().max(2.0) as u32;
        let geometry = Geometry {
            ball_diameter_mm: d,
            free_space_mm: self.free_space_per_ball.draw(&mut r) * d,
            balls_in_race: n_b,
        };
        let coulomb = self.coulomb_n.draw(&mut r);
        let friction = FrictionSettings {
            coulomb_n: coulomb,
            pulse_amplitude_n: self.ripple_fraction.draw(&mut r) * coulomb,
            pulse_width_ratio: self.friction_pulse_width_ratio.draw(&mut r),
            pulse_shape: pick(&self.friction_shapes, &mut r),
            roughness_n: self.roughness_fraction.draw(&mut r) * coulomb,
            roughness_length_mm: self.roughness_length_mm.draw(&mut r),
            stick_probability: 0.0,
            stick_range_n: None,
            ..FrictionSettings::default()
        };
        let dc = r.uniform() < self.load_cell_dc_probability;
        let tau = self.load_cell_tau_s.draw(&mut r);
        let load_cell = LoadCellSettings {
            time_constant_s: (!dc).then_some(tau),
            noise_n: self.friction_noise_n.draw(&mut r),
            ..LoadCellSettings::default()
        };
        let pre_record_s = self.pre_record_s.draw(&mut r);
        let f_n = self.stage_f_n_hz.draw(&mut r);
        let zeta = self.stage_zeta.draw(&mut r);
        let mass = self.stage_mass_kg.draw(&mut r);
        let wn = std::f64::consts::TAU * f_n;
        let stage = StageSettings {
            mass_kg: mass,
            kkp_n_per_m: mass * wn * wn,
            kkd_n_s_per_m: 2.0 * zeta * mass * wn,
        };
        let pulse_v = self.optical_pulse_v.draw(&mut r);
        let snr = self.optical_snr.draw(&mut r);
        let ac = r.uniform() < self.ac_probability;
        let ac_tau = self.ac_tau_s.draw(&mut r);
        let drift = r.uniform() < self.drift_probability;
        let drift_v = self.drift_fraction.draw(&mut r) * pulse_v;
        let drift_period = self.drift_period_s.draw(&mut r);
        let interference = r.uniform() < self.interference_probability;
        let optical = OpticalSettings {
            pulse_amplitude_v: pulse_v,
            width_ratio: self.optical_width_ratio.draw(&mut r),
            pulse_shape: pick(&self.optical_shapes, &mut r),
            noise_v: pulse_v / snr,
            ac_coupling: ac,
            ac_time_constant_s: ac_tau,
            baseline_drift_v: if drift { drift_v } else { 0.0 },
            baseline_drift_period_s: drift_period,
            interference_drift: interference,
            interference_amplitude_v: pulse_v,
            ..OpticalSettings::default()
        };
        Bench {
            seed,
            velocity_mm_s,
            fs_hz,
            duration_s,
            geometry,
            friction,
            load_cell,
            pre_record_s,
            stage,
            optical,
            sticking_severity: self.sticking_severity.draw(&mut r),
        }
    }
}

/// One bearing of a fleet on a bench: its own small departures from the
/// bench's friction, and whether (and how) it sticks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BearingDraw {
    /// Ripple factor relative to the bench (0.7–1.3).
    pub ripple_factor: f64,
    /// Roughness factor (0.7–1.3).
    pub roughness_factor: f64,
    /// Coulomb-level factor (0.85–1.15).
    pub coulomb_factor: f64,
    /// The sticking, for a sticking bearing.
    pub sticking: Option<Sticking>,
}

impl Bench {
    /// Draws bearing `index` of a fleet on this bench; `sticks` makes it a
    /// sticking bearing of the bench's severity.
    pub fn bearing(&self, index: u64, sticks: bool) -> BearingDraw {
        let mut r = Rng::stream(self.seed, 1000 + index);
        let ripple_factor = 0.7 + 0.6 * r.uniform();
        let roughness_factor = 0.7 + 0.6 * r.uniform();
        let coulomb_factor = 0.85 + 0.3 * r.uniform();
        let width = 0.02 + 0.08 * r.uniform();
        let sticking = sticks.then(|| {
            Sticking::of(
                self.sticking_severity,
                self.friction.pulse_amplitude_n * ripple_factor,
                self.friction.coulomb_n * coulomb_factor,
                width,
            )
        });
        BearingDraw {
            ripple_factor,
            roughness_factor,
            coulomb_factor,
            sticking,
        }
    }

    /// The simulator settings of one record of `bearing`, seed `seed`.
    pub fn settings(&self, bearing: &BearingDraw, seed: u64) -> SimSettings {
        let mut friction = self.friction;
        friction.pulse_amplitude_n *= bearing.ripple_factor;
        friction.roughness_n *= bearing.roughness_factor;
        friction.coulomb_n *= bearing.coulomb_factor;
        let condition = match bearing.sticking {
            Some(s) => {
                friction.stick_probability = s.probability;
                friction.stick_range_n = Some(s.range_n);
                friction.stick_width_ratio = s.width_ratio;
                Condition::Sticking
            }
            None => Condition::Good,
        };
        // About 20 kHz inside, whatever the sampling rate.
        let oversample = ((20_000.0 / self.fs_hz).round() as u32).max(1);
        SimSettings {
            velocity_mm_s: self.velocity_mm_s,
            duration_s: self.duration_s,
            fs_hz: self.fs_hz,
            oversample,
            seed,
            bearing: "validation".into(),
            geometry: self.geometry,
            test_id: None,
            condition,
            start: Start::Settled,
            stage: self.stage,
            motion: MotionSettings {
                settle_time_s: Some(self.pre_record_s),
                ..MotionSettings::default()
            },
            friction,
            load_cell: self.load_cell,
            encoder: Default::default(),
            optical: self.optical,
            profile: None,
            feedforward: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::simulate;

    /// Every bench the default domain draws is one the simulator accepts,
    /// and draws are reproducible.
    #[test]
    fn drawn_benches_simulate() {
        let d = Domain {
            duration_s: Range::fixed(10.0),
            ..Domain::default()
        };
        for seed in 0..40 {
            let b = d.draw(seed);
            assert_eq!(b, d.draw(seed));
            for (i, sticks) in [(0, false), (1, true)] {
                let bd = b.bearing(i, sticks);
                let s = b.settings(&bd, seed * 10 + i);
                let sim = simulate(&s).unwrap_or_else(|e| panic!("seed {seed}: {e}\n{b:#?}"));
                assert_eq!(sim.truth.condition == Condition::Sticking, sticks);
            }
        }
    }

    /// Mild sticking is 2–3 ripples on 10 % of passages; severe is the
    /// simulator's default sticking bearing.
    #[test]
    fn sticking_severity_ends() {
        let mild = Sticking::of(0.0, 0.3, 3.0, 0.05);
        assert_eq!(
            (mild.probability, mild.range_n),
            (0.1, [0.6, 0.8999999999999999])
        );
        let severe = Sticking::of(1.0, 0.3, 3.0, 0.05);
        assert!((severe.probability - 0.6).abs() < 1e-12);
        assert_eq!(severe.range_n[0], 0.0);
        assert!((severe.range_n[1] - 27.0).abs() < 1e-12);
        // No ripple: spikes of 2-3 times 2 % of the Coulomb level.
        let s = Sticking::of(0.0, 0.0, 3.0, 0.05);
        assert!((s.range_n[0] - 0.12).abs() < 1e-12 && (s.range_n[1] - 0.18).abs() < 1e-12);
    }
}
