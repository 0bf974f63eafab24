//! The testbed simulator: recordings whose true answer is known.
//!
//! It is the built-in data source of `ballpass demo` and the test oracle of
//! every analysis. One call, [`simulate`], turns a [`SimSettings`] into a
//! [`Simulation`]: a [`Recording`] with the three bench channels and a
//! [`Truth`] (schema `ballpass.truth/1`) with the true passage times, the
//! realised `f_c` and `tau_c`, pulse widths, lags and every parameter.
//!
//! # Physics
//!
//! ```text
//! stage   m y'' = -K K_P y - K K_D y' - f - m r''      y = x - r, r = V t   (thesis Eqs. 6.1-6.6)
//! friction f = sat(x' / v_eps) [F_c + rough(x) + sum_j P g(s - e_j) + sum_j A_j g_stick(s - e_j)]
//! balls   s = (x - x_0) / 2  (balls advance at half the stage speed; passages at fixed s)
//! load cell  HP(tau) then 2nd-order Butterworth 400 Hz, sampled, + white noise
//! encoder    floor(x / 0.1 um) * 0.1 um
//! optical    DC + m(t) sum_j P_o,k g(s - e_j - offset), [AC coupling], Butterworth 400 Hz, + noise
//! ```
//!
//! - The stage is integrated exactly (zero-order-hold discretisation by a
//!   matrix exponential) at `oversample x fs` (20 kHz by default); friction
//!   and sensors are evaluated at that internal rate, pulses only within six
//!   sigmas of their centres.
//! - Friction opposes motion; the load cell reads `+f` (see [`stage`]).
//! - Ball gaps are a uniform random split of `d_ext`, re-drawn per recording,
//!   so passage intervals vary as docs/methods.md §1 describes while the long-run
//!   passage rate is exactly `v / (2 d_avg)`.
//! - Pulse widths are set as FWHM / `tau_c` ratios (the thesis' `tau_p /
//!   tau_c = 0.155`, width at half prominence) and are fixed lengths along
//!   the ball travel, so they scale with `1 / v` like the thesis' Fig. 52.
//! - `good` bearing: pulses of 0.2 N on a 3 N Coulomb level plus a random
//!   "roughness" force (an Ornstein–Uhlenbeck process along the rail, std
//!   0.2 N, correlation length 1.3 mm) that leaves the `f_c` line only 2–4
//!   times its neighbourhood in a 0.2 Hz-resolution Welch spectrum of the
//!   20 Hz low-passed friction (hard to see, thesis Fig. 63a) while
//!   averaged autocorrelations still rise at multiples of `tau_c` (Fig. 55).
//! - `sticking` bearing: in addition, 60 % of ball entries (at random) carry
//!   a narrow spike (FWHM 0.05 `tau_c`) whose peak is uniform up to
//!   `(10 - 1) F_c`, so the total friction reaches up to ten times the
//!   Coulomb level (thesis Fig. 66). Its low-frequency friction spectrum is
//!   about 100 times a good bearing's with clear peaks at `f_c` (Figs. 67-68).
//!
//! # Which numbers come from the thesis
//!
//! | quantity | value | source |
//! |---|---|---|
//! | SR25W geometry | d = 4 mm, d_ext = 2 mm, N_B = 36 | thesis §1, §3.1 |
//! | sampling, duration | 1 kHz, 30 s | thesis §7 |
//! | optical pulse width | FWHM = 0.155 tau_c | thesis §6.4 (Fig. 53) |
//! | optical lag behind friction | 0.39 s at 9 mm/s → sensor offset 1.755 mm | thesis §7.1 (docs/methods.md §8–9 for the sign) |
//! | anti-alias filters | 400 Hz (2nd-order Butterworth assumed) | thesis §5.3, §7 |
//! | encoder | 0.1 µm | thesis §4 |
//! | interference drift | period 5 s, pulses invert at crests | thesis §5.2 (Fig. 32) |
//! | sticking spikes | up to 10x the friction, at ball passages | thesis §8 (Fig. 66) |
//! | velocity-error std | peak near 9 mm/s at ~100 µm/s (calibration target) | thesis Fig. 29 (110 µm/s) |
//! | load-cell time constant | 10 s (spec >= 50 s; Fig. 54 decays faster) | thesis §3.3, §7 |
//!
//! Beyond the thesis' bench, every part can be set to stand for benches that
//! are not ours (the randomized validation draws them): pulse shapes other
//! than the Gaussian ([`shapes`]), a DC-coupled force sensor or any discharge
//! time constant, spike amplitudes in a given range (mild to severe
//! sticking), a slow wander of the optical DC level, any stage, rate,
//! duration and geometry.
//!
//! Assumptions (the thesis gives no number): the PD stage (natural frequency
//! at the 9 mm/s ball-pass frequency, damping 0.35, effective mass 240 kg —
//! see [`StageSettings`] for why), Coulomb level 3 N ("a few newtons"),
//! pulse amplitude 0.2 N, roughness 0.2 N over 1.3 mm, friction pulse width
//! equal to the optical one, sticking probability 0.6 and spike width
//! 0.05 tau_c, noise levels (load cell 0.02 N, photodetector 0.01 V), DC
//! level 1 V and pulse height 0.5 V with 5 % ball-to-ball spread, reference
//! acceleration 100 mm/s², AC-coupling time constant 1 s, drift amplitude
//! 0.5 V, and the Gaussian pulse shape of the friction.
//!
//! With the defaults the velocity-error std (as the analysis computes it,
//! `numpy.gradient` of the encoder position) averages about 50 µm/s at
//! 1 mm/s, 100 µm/s at 9–10 mm/s and 83 µm/s at 20 mm/s (5 seeds; see
//! `examples/sim_sweep.rs`).

use crate::error::{Error, Result};
use crate::recording::{Channels, Metadata, Recording};

pub mod balls;
pub mod campaign;
pub mod feedforward;
pub mod profile;
pub mod rng;
pub mod sensors;
pub mod settings;
pub mod shapes;
pub mod stage;
pub mod truth;

pub use profile::{PlateauTruth, ProfilePlateau, SpeedProfile};
pub use settings::{
    Condition, EncoderSettings, FrictionSettings, LoadCellSettings, MotionSettings,
    OpticalSettings, SimSettings, Start, MAX_SAMPLES,
};
pub use shapes::PulseShape;
pub use stage::{PdStage, StageSettings};
pub use truth::{truth_path, Simulation, Spike, Truth, TRUTH_SCHEMA};

use balls::Circuit;
use rng::Rng;
use sensors::{quantize, Butterworth2, HighPass1};
use shapes::{fundamental, PulseTrain};

/// Rail roughness: an Ornstein–Uhlenbeck process in rail position with
/// standard deviation `sigma` and correlation length `ell`, generated exactly
/// at knots `h = ell / ROUGHNESS_KNOTS_PER_LENGTH` apart (`r[i+1] = rho r[i] +
/// sigma sqrt(1 - rho^2) xi`, `rho = exp(-h / ell)`) and interpolated
/// linearly in between; knots are drawn lazily as the stage advances.
struct Roughness {
    sigma: f64,
    rho: f64,
    h_mm: f64,
    knots: Vec<f64>,
    rng: Rng,
}

/// Roughness knots per correlation length (linear interpolation between
/// them smooths only wavelengths far below the correlation length).
const ROUGHNESS_KNOTS_PER_LENGTH: f64 = 50.0;

impl Roughness {
    fn new(sigma: f64, ell_mm: f64, mut rng: Rng) -> Self {
        let h_mm = ell_mm / ROUGHNESS_KNOTS_PER_LENGTH;
        let first = sigma * rng.normal();
        Self {
            sigma,
            rho: (-h_mm / ell_mm).exp(),
            h_mm,
            knots: vec![first],
            rng,
        }
    }

    /// Value at `d_mm` of rail travel from the start (held at the first knot
    /// for negative travel).
    fn value(&mut self, d_mm: f64) -> f64 {
        if self.sigma == 0.0 {
            return 0.0;
        }
        let u = (d_mm / self.h_mm).max(0.0);
        let i = u.floor() as usize;
        let innov = self.sigma * (1.0 - self.rho * self.rho).sqrt();
        while self.knots.len() < i + 2 {
            let last = self.knots[self.knots.len() - 1];
            let next = self.rho * last + innov * self.rng.normal();
            self.knots.push(next);
        }
        let frac = u - i as f64;
        self.knots[i] + frac * (self.knots[i + 1] - self.knots[i])
    }
}

/// First forward crossings of fixed ball-travel positions, as times.
struct Crossings {
    centres_mm: Vec<f64>,
    next: usize,
    times_s: Vec<f64>,
    index: Vec<usize>,
}

impl Crossings {
    fn new(centres_mm: Vec<f64>, s0: f64) -> Self {
        let next = centres_mm.partition_point(|&c| c <= s0);
        Self {
            centres_mm,
            next,
            times_s: Vec::new(),
            index: Vec::new(),
        }
    }

    /// Records crossings in `(s0, s1]` during `[t0, t0 + dt)`, keeping those
    /// at or after `t_from`.
    fn advance(&mut self, s0: f64, s1: f64, t0: f64, dt: f64, t_from: Option<f64>) {
        if s1 <= s0 {
            return;
        }
        while self.next < self.centres_mm.len() && self.centres_mm[self.next] <= s1 {
            let c = self.centres_mm[self.next];
            if let Some(t_from) = t_from {
                let t = t0 + dt * (c - s0) / (s1 - s0);
                if t >= t_from {
                    self.times_s.push(t - t_from);
                    self.index.push(self.next);
                }
            }
            self.next += 1;
        }
    }
}

fn cmul(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn arg(z: (f64, f64)) -> f64 {
    z.1.atan2(z.0)
}

/// Wraps a lag into `(-tau/2, tau/2]`.
fn wrap_lag(lag: f64, tau: f64) -> f64 {
    let mut l = lag - tau * (lag / tau).round();
    if l <= -tau / 2.0 {
        l += tau;
    }
    l
}

/// `numpy.gradient` with unit spacing: central differences inside,
/// one-sided first differences at the ends.
fn gradient(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut g = vec![0.0; n];
    if n < 2 {
        return g;
    }
    g[0] = x[1] - x[0];
    g[n - 1] = x[n - 1] - x[n - 2];
    for i in 1..n - 1 {
        g[i] = (x[i + 1] - x[i - 1]) / 2.0;
    }
    g
}

fn std_dev(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt()
}

// Random streams: one per part, so options do not shift each other's draws.
const STREAM_BALLS: u64 = 1;
const STREAM_ROUGHNESS: u64 = 2;
const STREAM_STICK: u64 = 3;
const STREAM_LOAD_CELL_NOISE: u64 = 4;
const STREAM_OPTICAL_NOISE: u64 = 5;
const STREAM_OPTICAL_AMPLITUDE: u64 = 6;
const STREAM_INTERFERENCE: u64 = 7;
const STREAM_BASELINE_DRIFT: u64 = 8;

/// Simulates one bench recording.
///
/// See the module docs for the model. Outputs: `friction_N` (load cell,
/// `+` in the direction of motion), `position_mm` (encoder, quantised),
/// `optical_V` (photodetector); metadata velocity, bearing and test id.
///
/// ```
/// use ballpass::sim::{simulate, SimSettings};
/// let sim = simulate(&SimSettings { duration_s: 2.0, ..Default::default() })?;
/// assert_eq!(sim.recording.len(), 2000); // 2 s at 1 kHz
/// // SR25W at 9 mm/s: f_c = 9 / (2 * 4.05556) = 1.10959 Hz (docs/methods.md §1).
/// assert!((sim.truth.f_c_nominal_hz - 1.10959).abs() < 1e-5);
/// # Ok::<(), ballpass::Error>(())
/// ```
///
/// # Errors
/// [`Error::InvalidSetting`] for a setting out of range (see
/// [`SimSettings::validate`]), or when a `from_rest` stage never reaches the
/// trigger distance, or when the stage does not move forward on average.
pub fn simulate(settings: &SimSettings) -> Result<Simulation> {
    settings.validate()?;
    let s = settings;
    let g = &s.geometry;
    let profile = s.profile.as_ref();
    let v_mm_s = profile.map_or(s.velocity_mm_s, |p| p.first_velocity_mm_s().abs());
    let v_m_s = v_mm_s * 1e-3;
    let dt = 1.0 / (s.fs_hz * f64::from(s.oversample));
    let os = s.oversample as usize;
    let n_out = s.n_samples();
    let d_avg = g.d_avg_mm();
    let tau_c_nom = 2.0 * d_avg / v_mm_s;
    let fr = &s.friction;
    let opt = &s.optical;
    let m = s.stage.mass_kg;

    // Balls and their passages on the ball-travel axis s (mm).
    let mut rng_balls = Rng::stream(s.seed, STREAM_BALLS);
    let circuit = Circuit::draw(g, &mut rng_balls);
    let length = circuit.length_mm();
    let settle = s.settle_time_s();
    let trigger = s.trigger_distance_mm();
    let pre_est_s = match s.start {
        Start::Settled => settle,
        Start::FromRest => trigger / v_mm_s + v_mm_s / s.motion.acceleration_mm_s2,
    };
    let passages = match profile {
        None => {
            let travel_budget_mm = 1.2 * (v_mm_s * (pre_est_s + s.duration_s) + trigger) + 20.0;
            circuit.passages(-length - 10.0, travel_budget_mm / 2.0 + length)
        }
        Some(p) => {
            // Ball travel (x - x_init) / 2 over the run, with the margin of
            // the single-speed budget for the stage's lag and overshoot.
            let (lo, hi) = p.position_range_mm(settle, s.duration_s);
            let x_init = -p.first_velocity_mm_s() * settle;
            let margin = 0.2 * (hi - lo) + 20.0;
            circuit.passages(
                (lo - x_init - margin) / 2.0 - length - 10.0,
                (hi - x_init + margin) / 2.0 + length,
            )
        }
    };
    let entries: Vec<f64> = passages.iter().map(|p| p.travel_mm).collect();

    // Spatial pulse widths: FWHM ratio * tau_c * v/2 = ratio * d_avg.
    let mut friction_pulses = PulseTrain::new(
        entries.clone(),
        vec![fr.pulse_amplitude_n; entries.len()],
        fr.pulse_shape,
        fr.pulse_width_ratio * d_avg,
    );
    let mut rng_stick = Rng::stream(s.seed, STREAM_STICK);
    let stick_amps: Vec<f64> = entries
        .iter()
        .map(|_| {
            // Two draws per passage whatever the condition, so that the
            // sequence is stable.
            let hit = rng_stick.uniform() < fr.stick_probability;
            let u = rng_stick.uniform();
            if s.condition == Condition::Sticking && hit {
                match fr.stick_range_n {
                    Some([lo, hi]) => lo + (hi - lo) * u,
                    None => (fr.stick_max_ratio - 1.0) * fr.coulomb_n * u,
                }
            } else {
                0.0
            }
        })
        .collect();
    // Only the entries that carry a spike are evaluated.
    let (stick_centres, stick_nonzero): (Vec<f64>, Vec<f64>) = entries
        .iter()
        .zip(&stick_amps)
        .filter(|(_, &a)| a > 0.0)
        .map(|(&e, &a)| (e, a))
        .unzip();
    let mut stick_pulses = PulseTrain::new(
        stick_centres,
        stick_nonzero,
        PulseShape::Gaussian,
        fr.stick_width_ratio * d_avg,
    );
    let mut rng_amp = Rng::stream(s.seed, STREAM_OPTICAL_AMPLITUDE);
    let ball_amps: Vec<f64> = (0..g.balls_in_race)
        .map(|_| (opt.pulse_amplitude_v * (1.0 + opt.amplitude_jitter * rng_amp.normal())).max(0.0))
        .collect();
    let optical_centres: Vec<f64> = entries.iter().map(|e| e + opt.sensor_offset_mm).collect();
    let mut optical_pulses = PulseTrain::new(
        optical_centres.clone(),
        passages.iter().map(|p| ball_amps[p.ball]).collect(),
        opt.pulse_shape,
        opt.width_ratio * d_avg,
    );

    // Stage and reference.
    let mut stage = PdStage::new(&s.stage, dt)?;
    let a_ref = s.motion.acceleration_mm_s2 * 1e-3;
    let t_acc = v_m_s / a_ref;
    let (k_pre_settled, x_ref0) = match s.start {
        Start::Settled => {
            // Friction opposes the motion: the stage lags behind it.
            let sign = profile.map_or(1.0, |p| p.first_velocity_mm_s().signum());
            stage.set_state(-sign * s.stage.steady_offset_m(fr.coulomb_n), 0.0);
            let k = (settle / dt).ceil() as usize;
            (Some(k), -(k as f64) * dt * v_m_s)
        }
        Start::FromRest => (None, 0.0),
    };
    // Reference position and velocity at time t (from the simulation start);
    // t never decreases between calls.
    let mut sampler = profile.map(|p| p.sampler());
    let t_record = k_pre_settled.unwrap_or(0) as f64 * dt;
    let mut reference = |t: f64| -> (f64, f64) {
        if let Some(sm) = sampler.as_mut() {
            return sm.at(t - t_record);
        }
        match s.start {
            Start::Settled => (x_ref0 + v_m_s * t, v_m_s),
            Start::FromRest => {
                if t < t_acc {
                    (0.5 * a_ref * t * t, a_ref * t)
                } else {
                    (v_m_s * (t - 0.5 * t_acc), v_m_s)
                }
            }
        }
    };
    let max_pre_steps = match s.start {
        Start::Settled => k_pre_settled.unwrap_or(0),
        Start::FromRest => ((10.0 * pre_est_s + 100.0) / dt).ceil() as usize,
    };

    // Sensors.
    let mut lc_hp = s
        .load_cell
        .time_constant_s
        .map(|tau| HighPass1::new(tau, dt, 0.0));
    let mut lc_lp: Option<Butterworth2> = None;
    let mut opt_ac = HighPass1::new(opt.ac_time_constant_s, dt, opt.dc_v);
    let mut opt_lp: Option<Butterworth2> = None;
    let mut rng_interf = Rng::stream(s.seed, STREAM_INTERFERENCE);
    let interf_phase0 = std::f64::consts::TAU * rng_interf.uniform();
    let interf_w = std::f64::consts::TAU / opt.interference_period_s;
    let mut rng_drift = Rng::stream(s.seed, STREAM_BASELINE_DRIFT);
    let drift_phase = [
        std::f64::consts::TAU * rng_drift.uniform(),
        std::f64::consts::TAU * rng_drift.uniform(),
    ];
    let drift_w = std::f64::consts::TAU / opt.baseline_drift_period_s;
    let drift = |t: f64| {
        opt.baseline_drift_v
            * (0.6 * (drift_w * t + drift_phase[0]).sin()
                + 0.4 * (drift_w / 0.37 * t + drift_phase[1]).sin())
    };

    let mut roughness = Roughness::new(
        fr.roughness_n,
        fr.roughness_length_mm,
        Rng::stream(s.seed, STREAM_ROUGHNESS),
    );

    let (r0, _) = reference(0.0);
    let x_init = r0 + stage.deviation_m();
    let travel = |x: f64| (x - x_init) * 1e3 / 2.0;
    let mut friction_cross = Crossings::new(entries.clone(), 0.0);
    let mut optical_cross = Crossings::new(optical_centres, 0.0);
    let feedforward = s.feedforward.as_ref();

    let mut friction_out = Vec::with_capacity(n_out);
    let mut position_out = Vec::with_capacity(n_out);
    let mut optical_out = Vec::with_capacity(n_out);
    let mut ve_true = Vec::with_capacity(n_out);
    // The ball-pass pulse trains alone, as they fall in time (truth.rs,
    // `optical_lag_s`).
    let mut ripple_out = Vec::with_capacity(n_out);
    let mut pulses_out = Vec::with_capacity(n_out);
    let mut speed_sum = 0.0;
    let q_mm = s.encoder.resolution_um * 1e-3;
    let v_band_min = fr.zero_velocity_band_mm_s * 1e-3;

    let mut k_rec: Option<usize> = None;
    let mut k = 0usize;
    loop {
        let t = k as f64 * dt;
        let (r, rdot) = reference(t);
        let x = r + stage.deviation_m();
        let xdot = rdot + stage.velocity_error_m_s();
        if k_rec.is_none() {
            let triggered = match s.start {
                Start::Settled => Some(k) == k_pre_settled,
                Start::FromRest => (x - x_init) * 1e3 >= trigger,
            };
            if triggered {
                k_rec = Some(k);
            } else if k > max_pre_steps {
                return Err(Error::setting(
                    "trigger distance",
                    format!(
                        "the stage did not travel {trigger} mm within {:.0} s of starting from rest",
                        k as f64 * dt
                    ),
                ));
            }
        }
        let sample_index = k_rec.and_then(|kr| {
            let d = k - kr;
            (d % os == 0).then_some(d / os)
        });
        if sample_index == Some(n_out) {
            break;
        }

        // Friction at this step (held over it).
        let sb = travel(x);
        let ripple = friction_pulses.value(sb);
        let magnitude =
            (fr.coulomb_n + roughness.value((x - x_init) * 1e3) + ripple + stick_pulses.value(sb))
                .max(0.0);
        let v_eps = v_band_min.max(2.0 * magnitude * dt / m);
        let friction = magnitude * (xdot / v_eps).clamp(-1.0, 1.0);

        // Optical signal at this step.
        let pulses = optical_pulses.value(sb);
        let mut optical_in = if opt.interference_drift {
            let th = interf_w * t + interf_phase0;
            opt.dc_v + opt.interference_amplitude_v * th.sin() - th.sin() * pulses
        } else {
            opt.dc_v + pulses
        };
        if opt.baseline_drift_v > 0.0 {
            optical_in += drift(t);
        }

        // Sensors: high-pass has feedthrough, low-pass output is its state.
        let lc_hp_out = match lc_hp.as_mut() {
            Some(hp) => hp.step(friction),
            None => friction,
        };
        let lcl =
            lc_lp.get_or_insert_with(|| Butterworth2::new(s.load_cell.antialias_hz, dt, lc_hp_out));
        let opt_hp_out = if opt.ac_coupling {
            opt_ac.step(optical_in)
        } else {
            optical_in
        };
        let ol = opt_lp.get_or_insert_with(|| Butterworth2::new(opt.antialias_hz, dt, opt_hp_out));
        if sample_index.is_some() {
            friction_out.push(lcl.output());
            optical_out.push(ol.output());
            position_out.push(quantize(x * 1e3, q_mm));
            ve_true.push((xdot - if profile.is_some() { rdot } else { v_m_s }) * 1e3);
            speed_sum += xdot.abs() * 1e3;
            ripple_out.push(ripple);
            pulses_out.push(pulses);
        }
        lcl.step(lc_hp_out);
        ol.step(opt_hp_out);

        // Feedforward from the compensation table, at this step's phase.
        let u = feedforward.map_or(0.0, |ff| {
            use feedforward::FeedforwardKey;
            match ff.key {
                FeedforwardKey::OpticalPassage => match optical_cross.next {
                    0 => 0.0,
                    j => ff.force_at((sb - optical_cross.centres_mm[j - 1]) / d_avg),
                },
                FeedforwardKey::RailPosition { x0_mm, pitch_mm } => {
                    ff.force_at((x * 1e3 - x0_mm) / pitch_mm)
                }
            }
        });

        // Stage, with the step-average reference acceleration.
        let (_, rdot1) = reference(t + dt);
        stage.step(friction - u, (rdot1 - rdot) / dt);
        let (r1, _) = reference(t + dt);
        let x1 = r1 + stage.deviation_m();

        let t_from = k_rec.map(|kr| kr as f64 * dt);
        let s1 = travel(x1);
        friction_cross.advance(sb, s1, t, dt, t_from);
        optical_cross.advance(sb, s1, t, dt, t_from);
        k += 1;
    }
    let k_rec = k_rec.unwrap_or(0);
    let record_start_time_s = k_rec as f64 * dt;
    let t_last = (n_out - 1) as f64 / s.fs_hz;
    let keep = |c: &Crossings| -> (Vec<f64>, Vec<usize>) {
        c.times_s
            .iter()
            .zip(&c.index)
            .filter(|(&t, _)| t <= t_last)
            .map(|(&t, &j)| (t, j))
            .unzip()
    };
    let (optical_passage_times_s, opt_idx) = keep(&optical_cross);
    let (friction_pulse_times_s, fr_idx) = keep(&friction_cross);
    let sticking_spikes: Vec<Spike> = friction_pulse_times_s
        .iter()
        .zip(&fr_idx)
        .filter(|(_, &j)| stick_amps[j] > 0.0)
        .map(|(&t, &j)| Spike {
            time_s: t,
            amplitude_n: stick_amps[j],
        })
        .collect();

    // Measurement noise, sampled at fs.
    let mut rng_lc = Rng::stream(s.seed, STREAM_LOAD_CELL_NOISE);
    friction_out
        .iter_mut()
        .for_each(|y| *y += s.load_cell.noise_n * rng_lc.normal());
    let mut rng_on = Rng::stream(s.seed, STREAM_OPTICAL_NOISE);
    optical_out
        .iter_mut()
        .for_each(|y| *y += opt.noise_v * rng_on.normal());

    // Realised quantities.
    let mean_v = match profile {
        None => v_mm_s + ve_true.iter().sum::<f64>() / n_out as f64,
        Some(_) => speed_sum / n_out as f64,
    };
    if mean_v.is_nan() || mean_v <= 0.0 {
        return Err(Error::setting(
            "friction",
            format!(
                "the stage did not move forward on average ({mean_v:.3} mm/s); friction too high for the stage settings"
            ),
        ));
    }
    let f_c = mean_v / (2.0 * d_avg);
    let tau_c = 1.0 / f_c;
    let passage_rate_hz = match optical_passage_times_s.as_slice() {
        [first, .., last] if last > first => {
            Some((optical_passage_times_s.len() - 1) as f64 / (last - first))
        }
        _ => None,
    };
    let w = std::f64::consts::TAU * f_c;
    let lc_aa = Butterworth2::response(s.load_cell.antialias_hz, w);
    let lc_resp = match s.load_cell.time_constant_s {
        Some(tau) => cmul(HighPass1::response(tau, w), lc_aa),
        None => lc_aa,
    };
    // The phase each pulse shape adds to its train's fundamental (zero for
    // the symmetric pulses).
    let g_f = fundamental(fr.pulse_shape, fr.pulse_width_ratio * d_avg, d_avg);
    let g_o = fundamental(opt.pulse_shape, opt.width_ratio * d_avg, d_avg);
    let shape_phase = arg(g_o) - arg(g_f);
    let mut opt_resp = Butterworth2::response(opt.antialias_hz, w);
    if opt.ac_coupling {
        opt_resp = cmul(opt_resp, HighPass1::response(opt.ac_time_constant_s, w));
    }
    let gvf = s.stage.g_vf(w);
    let h_ve = (-gvf.0, -gvf.1);
    let optical_delay_s = opt.sensor_offset_mm / (mean_v / 2.0);
    // The phase the pulse trains' fundamentals show as they fall in time
    // (truth.rs, `optical_lag_s`); the pulses' geometric delay where the
    // record cannot tell it.
    let trains_phase = match profile {
        None => truth::fundamental_phase_difference(&ripple_out, &pulses_out, w / s.fs_hz),
        Some(_) => None,
    };
    let opt_phase_force =
        trains_phase.unwrap_or(-w * optical_delay_s + shape_phase) + arg(opt_resp) - arg(lc_aa);
    let opt_phase = opt_phase_force + arg(lc_aa) - arg(lc_resp);
    let optical_lag_s = wrap_lag(-opt_phase / w, tau_c);
    let optical_lag_force_s = wrap_lag(-opt_phase_force / w, tau_c);
    let ve_phase_force = arg(h_ve) - arg(lc_aa);
    let ve_phase = ve_phase_force + arg(lc_aa) - arg(lc_resp);
    let velocity_error_lag_s = wrap_lag(-ve_phase / w, tau_c);
    let velocity_error_lag_force_s = wrap_lag(-ve_phase_force / w, tau_c);
    let ve_meas: Vec<f64> = gradient(&position_out)
        .iter()
        .map(|d| d * s.fs_hz - v_mm_s)
        .collect();

    let plateaus = profile.map_or_else(Vec::new, |p| plateau_truth(p, &position_out, s));
    let truth = Truth {
        schema: TRUTH_SCHEMA.into(),
        version: crate::VERSION.into(),
        condition: s.condition,
        velocity_mm_s: v_mm_s,
        fs_hz: s.fs_hz,
        n_samples: n_out,
        record_start_time_s,
        d_avg_mm: d_avg,
        f_c_nominal_hz: 1.0 / tau_c_nom,
        tau_c_nominal_s: tau_c_nom,
        mean_velocity_mm_s: mean_v,
        f_c_hz: f_c,
        tau_c_s: tau_c,
        passage_rate_hz,
        ball_spacings_mm: circuit.spacings_mm.clone(),
        optical_passage_balls: opt_idx.iter().map(|&j| passages[j].ball).collect(),
        optical_passage_times_s,
        friction_pulse_balls: fr_idx.iter().map(|&j| passages[j].ball).collect(),
        friction_pulse_times_s,
        sticking_spikes,
        optical_pulse_fwhm_s: opt.width_ratio * tau_c,
        optical_pulse_sigma_s: sensors::sigma_from_fwhm(opt.width_ratio * tau_c),
        optical_pulse_fwhm_tau_c: opt.width_ratio,
        friction_pulse_fwhm_s: fr.pulse_width_ratio * tau_c,
        optical_delay_s,
        optical_lag_s,
        optical_lag_tau_c: optical_lag_s / tau_c,
        optical_phase_deg: -360.0 * optical_lag_s / tau_c,
        optical_lag_force_s,
        optical_lag_force_tau_c: optical_lag_force_s / tau_c,
        velocity_error_lag_force_s,
        velocity_error_lag_force_tau_c: velocity_error_lag_force_s / tau_c,
        load_cell_phase_deg: arg(lc_resp).to_degrees(),
        friction_fundamental_n: 2.0 * fr.pulse_amplitude_n * (g_f.0 * g_f.0 + g_f.1 * g_f.1).sqrt()
            / d_avg,
        velocity_error_lag_s,
        velocity_error_lag_tau_c: velocity_error_lag_s / tau_c,
        velocity_error_phase_deg: -360.0 * velocity_error_lag_s / tau_c,
        g_vf_gain_mm_s_per_n: (gvf.0 * gvf.0 + gvf.1 * gvf.1).sqrt() * 1e3,
        natural_frequency_hz: s.stage.omega_n_rad_s() / std::f64::consts::TAU,
        damping_ratio: s.stage.damping_ratio(),
        steady_offset_mm: s.stage.steady_offset_m(fr.coulomb_n) * 1e3,
        velocity_error_std_mm_s: std_dev(&ve_meas),
        velocity_error_true_std_mm_s: std_dev(&ve_true),
        interference_phase_rad: opt.interference_drift.then(|| {
            (interf_w * record_start_time_s + interf_phase0).rem_euclid(std::f64::consts::TAU)
        }),
        plateaus,
        settings: s.clone(),
    };

    let meta = Metadata {
        // A multi-speed run has no one velocity.
        velocity_mm_s: profile.is_none().then_some(v_mm_s),
        bearing: Some(s.bearing.clone()),
        test_id: Some(s.test_id.clone().unwrap_or_else(|| match profile {
            None => format!("sim-v{v_mm_s}-s{}", s.seed),
            Some(_) => format!("sim-profile-s{}", s.seed),
        })),
        source: None,
        start_time_s: 0.0,
        notes: Vec::new(),
    };
    let recording = Recording::new(
        s.fs_hz,
        Channels {
            friction_n: Some(friction_out),
            position_mm: Some(position_out),
            optical_v: Some(optical_out),
        },
        meta,
    )?;
    Ok(Simulation { recording, truth })
}

/// The truth of each plateau of a profile: commanded interval and velocity,
/// and the stage's mean velocity over it from the recorded encoder.
fn plateau_truth(p: &SpeedProfile, position: &[f64], s: &SimSettings) -> Vec<PlateauTruth> {
    let n = position.len();
    p.intervals(s.duration_s)
        .into_iter()
        .filter_map(|(a, b, v)| {
            let i0 = ((a * s.fs_hz).ceil() as usize).min(n);
            let i1 = ((b * s.fs_hz).ceil() as usize).min(n);
            (i1 > i0 + 1).then(|| PlateauTruth {
                start_s: a,
                end_s: b,
                velocity_mm_s: v,
                mean_velocity_mm_s: (position[i1 - 1] - position[i0]) * s.fs_hz
                    / (i1 - 1 - i0) as f64,
            })
        })
        .collect()
}

/// The tests' simulated record: the default bench at 9 mm/s for
/// `duration_s`, drawn from `seed`.
#[cfg(test)]
pub(crate) fn test_record(seed: u64, duration_s: f64) -> crate::recording::Recording {
    simulate(&SimSettings {
        velocity_mm_s: 9.0,
        duration_s,
        seed,
        ..Default::default()
    })
    .expect("simulates")
    .recording
}
