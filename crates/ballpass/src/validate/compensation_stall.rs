//! Near-stall benches taken apart (session 10): how long the stage is
//! stuck with and without the product's table, and the best table a
//! controller could learn on the simulator itself (an oracle: iterative
//! learning on the very bench, same balls, spikes and noise), against which
//! the product's table and the goal (f_c component −80 %, std down) are
//! judged.
//!
//! ```text
//! learning   U_k ← U_k − γ R_k / G_vf(j k ω_c)     k = 1 … K
//! ```
//!
//! `R_k` the Fourier coefficients of the closed-loop run's synchronous
//! average of the velocity error (the very figure the goal is stated on),
//! `U_k` the table's, `G_vf` the simulated stage's (the truth, not the
//! identified one), `γ` = [`LEARNING_GAIN`]. With `K = 1` only the table's
//! fundamental is learnt (the best the f_c component can get); with `K` =
//! [`LEARNED_HARMONICS`] the shape too.

use serde::Serialize;

use crate::analysis::sync::coefficient;
use crate::analysis::{analyze, AnalyzeSettings, Signal};
use crate::bearing::Prediction;
use crate::error::{Error, Result};
use crate::model::compensate::compensate;
use crate::model::stage::PdLoop;
use crate::sim::feedforward::{Feedforward, FeedforwardKey};
use crate::sim::{simulate, SimSettings};

/// Gain of each learning step (below 1: the time-keyed average and the
/// travel-keyed table differ near stall, so a full step overshoots).
pub const LEARNING_GAIN: f64 = 0.6;

/// Harmonics the full learning adjusts.
pub const LEARNED_HARMONICS: usize = 12;

/// Learning steps of each oracle.
pub const LEARNING_STEPS: usize = 6;

/// Speed below which the stage counts as stuck, fraction of the commanded
/// velocity (on the encoder over [`STUCK_WINDOW_S`]).
pub const STUCK_SPEED_FRACTION: f64 = 0.1;

/// Window of the encoder speed for the stuck fraction, s (0.1 µm encoder
/// steps: 10 µm/s resolution, 1 % of 1 mm/s).
pub const STUCK_WINDOW_S: f64 = 0.01;

/// One closed-loop run's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Run {
    /// f_c component of the velocity error (fundamental of its synchronous
    /// average), µm/s.
    pub f_c_um_s: f64,
    /// Std of the low-passed velocity error, µm/s.
    pub std_um_s: f64,
    /// Fraction of the time the stage is stuck ([`STUCK_SPEED_FRACTION`]).
    pub stuck_fraction: f64,
    /// Fraction of the ball-pass periods in which the stage sticks at
    /// least once.
    pub periods_stuck: f64,
    /// Rms of the synchronous average over the low-passed std (how much
    /// of the velocity error is periodic in the ball-pass phase).
    pub periodic_share: f64,
}

/// One near-stall bench taken apart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StallDiagnosis {
    /// Commanded velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Velocity-error std over the velocity, without a table.
    pub std_over_v: f64,
    /// Without a table.
    pub none: Run,
    /// With the product's table.
    pub product: Run,
    /// The product's prediction: f_c component and std after, µm/s.
    pub predicted_um_s: (f64, f64),
    /// With the synchronous-average table (`force_sync_n`).
    pub sync_table: Run,
    /// With the table learnt on its fundamental only, each step.
    pub learnt_fundamental: Vec<Run>,
    /// With the table learnt on [`LEARNED_HARMONICS`] harmonics, each step.
    pub learnt_shape: Vec<Run>,
    /// Distance of tables' fundamentals from the one learnt (its last
    /// step), over the learnt one's: the product's, the
    /// synchronous-average table's, and `−V_1 / G_vf(jω_c)` (`V_1` the
    /// record's velocity error without a table, `G_vf` of the stage the
    /// product used).
    pub fundamental_miss: (f64, f64, f64),
    /// Amplitude of the learnt table's fundamental, N.
    pub learnt_fundamental_n: f64,
}

/// Takes bench `s` apart (module docs) when its velocity-error std is at
/// least `min_std_over_v` of the velocity (else `None`).
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn diagnose_stall(s: &SimSettings, min_std_over_v: f64) -> Result<Option<StallDiagnosis>> {
    let pred = s.geometry.predict(s.velocity_mm_s, 5)?;
    let gains = PdLoop::from_products(s.stage.mass_kg, s.stage.kkp_n_per_m, s.stage.kkd_n_s_per_m)?;
    let (none, mean0) = run(s, None, &pred)?;
    if none.std_um_s * 1e-3 / s.velocity_mm_s < min_std_over_v {
        return Ok(None);
    }
    let sim = simulate(s)?;
    let comp = compensate(
        std::slice::from_ref(&sim.recording),
        &pred,
        &AnalyzeSettings::default(),
        Some(gains),
    )?;
    let key = FeedforwardKey::OpticalPassage;
    let ff = |force_n: Vec<f64>| Feedforward { force_n, key };
    let (product, mean) = run(s, Some(ff(comp.force_n.clone())), &pred)?;
    let (sync_table, _) = run(s, Some(ff(comp.force_sync_n.clone())), &pred)?;
    let w_c = std::f64::consts::TAU * comp.prediction.f_c_hz;
    let mut learnt = [Vec::new(), Vec::new()];
    let mut tables = Vec::new();
    for (harmonics, out) in [1, LEARNED_HARMONICS].into_iter().zip(&mut learnt) {
        let (mut table, mut r) = (comp.force_n.clone(), mean.clone());
        for _ in 0..LEARNING_STEPS {
            learn(&mut table, &r, &gains, w_c, harmonics);
            let (x, m) = run(s, Some(ff(table.clone())), &pred)?;
            out.push(x);
            r = m;
        }
        tables.push(table);
    }
    let [learnt_fundamental, learnt_shape] = learnt;
    let c = |t: &[f64]| {
        let (re, im) = coefficient(t, 1);
        rustfft::num_complex::Complex64::new(re, im)
    };
    let star = c(&tables[0]);
    let (v1re, v1im) = coefficient(&mean0, 1);
    let inverse = -rustfft::num_complex::Complex64::new(v1re, v1im) / (comp.stage.g_vf(w_c) * 1e6);
    let miss = |u: rustfft::num_complex::Complex64| (u - star).norm() / star.norm();
    Ok(Some(StallDiagnosis {
        velocity_mm_s: s.velocity_mm_s,
        std_over_v: none.std_um_s * 1e-3 / s.velocity_mm_s,
        none,
        product,
        predicted_um_s: (
            comp.prediction.f_c_after_um_s,
            comp.prediction.std_after_um_s,
        ),
        sync_table,
        learnt_fundamental,
        learnt_shape,
        fundamental_miss: (
            miss(c(&comp.force_n)),
            miss(c(&comp.force_sync_n)),
            miss(inverse),
        ),
        learnt_fundamental_n: 2.0 * star.norm(),
    }))
}

/// One learning step on `table` from the run's synchronous average `r`
/// (µm/s), harmonics 1 … `harmonics` (module docs).
fn learn(table: &mut [f64], r: &[f64], stage: &PdLoop, w_c: f64, harmonics: usize) {
    let b = table.len();
    for k in 1..=harmonics.min(b / 2 - 1).min(r.len() / 2 - 1) {
        let rk = coefficient(r, k);
        // µm/s per N.
        let g = stage.g_vf(k as f64 * w_c) * 1e6;
        let d = rustfft::num_complex::Complex64::new(rk.0, rk.1) / g * (-LEARNING_GAIN);
        for (j, u) in table.iter_mut().enumerate() {
            let th = std::f64::consts::TAU * (k * j) as f64 / b as f64;
            *u += 2.0 * (d.re * th.cos() - d.im * th.sin());
        }
    }
}

/// Bench `s` with `ff` applied (none: as it is): its figures and the
/// synchronous average of its velocity error, µm/s.
pub(crate) fn run(
    s: &SimSettings,
    ff: Option<Feedforward>,
    pred: &Prediction,
) -> Result<(Run, Vec<f64>)> {
    let mut s1 = s.clone();
    s1.feedforward = ff;
    let sim = simulate(&s1)?;
    let rec = &sim.recording;
    let a = analyze(std::slice::from_ref(rec), pred, &AnalyzeSettings::default())?;
    let w = a
        .sync
        .as_ref()
        .and_then(|y| y.waveform(Signal::VelocityError))
        .ok_or_else(|| Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: "no synchronous average of the run".into(),
        })?;
    let std = a
        .velocity_error
        .as_ref()
        .map_or(f64::NAN, |v| v.lowpassed_std_um_s);
    let x = rec
        .channel(crate::recording::Channel::Position)
        .unwrap_or(&[]);
    let fs = rec.fs_hz();
    let n = ((STUCK_WINDOW_S * fs).round() as usize).max(1);
    let stuck: Vec<bool> = x
        .windows(n + 1)
        .map(|w| (w[n] - w[0]).abs() * fs / (n as f64) < STUCK_SPEED_FRACTION * s.velocity_mm_s)
        .collect();
    let stuck_fraction = stuck.iter().filter(|&&b| b).count() as f64 / stuck.len().max(1) as f64;
    let keys: Vec<usize> = sim
        .truth
        .optical_passage_times_s
        .iter()
        .map(|t| (t * fs).round() as usize)
        .collect();
    let periods: Vec<bool> = keys
        .windows(2)
        .filter(|k| k[1] <= stuck.len())
        .map(|k| stuck[k[0]..k[1]].iter().any(|&b| b))
        .collect();
    let rms = (w.mean.iter().map(|v| v * v).sum::<f64>() / w.mean.len() as f64
        - (w.mean.iter().sum::<f64>() / w.mean.len() as f64).powi(2))
    .max(0.0)
    .sqrt();
    Ok((
        Run {
            f_c_um_s: w.fundamental_amplitude,
            std_um_s: std,
            stuck_fraction,
            periods_stuck: periods.iter().filter(|&&b| b).count() as f64
                / periods.len().max(1) as f64,
            periodic_share: rms / std,
        },
        w.mean.clone(),
    ))
}
