//! The f_c component after compensation taken apart (session 11): the
//! fundamentals (complex Fourier coefficients `c_1` of the synchronous
//! averages, µm/s; the amplitude is `2|c_1|`) of the velocity error as
//! recorded, as replayed without a table, as replayed with the table before
//! and after the fundamental's correction, and as simulated in closed loop
//! with both tables: where the replay's error at f_c comes from and whether
//! it stays the same with the table applied.

use serde::Serialize;

use crate::analysis::sync::coefficient;
use crate::analysis::Signal;
use crate::bearing::Prediction;
use crate::error::{Error, Result};
use crate::model::compensate::{design_again, StageSource};
use crate::model::stage::PdLoop;
use crate::sim::feedforward::{Feedforward, FeedforwardKey};
use crate::sim::SimSettings;
use crate::validate::compensation::{simulate_and_compensate, Compensated};

/// A fundamental, `c_1` (re, im), µm/s or N.
pub type C1 = (f64, f64);

/// One bench taken apart at f_c.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FcTrace {
    /// Commanded velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Velocity-error std over the velocity, without a table.
    pub std_over_v: f64,
    /// Where the stage came from.
    pub stage_source: StageSource,
    /// Natural frequency (Hz) and damping ratio of the stage used, and of
    /// the simulated one.
    pub stage_f_n_zeta: ((f64, f64), (f64, f64)),
    /// `G_vf(jω_c)` of the stage used over the simulated one's.
    pub g_ratio: C1,
    /// Std of the velocity error without a table, µm/s.
    pub std_before_um_s: f64,
    /// Records' velocity error.
    pub measured: C1,
    /// Replay without a table.
    pub replay_bare: C1,
    /// Replay with the fixed-point table.
    pub replay_fixed: C1,
    /// Replay with the corrected table.
    pub replay_final: C1,
    /// Closed loop with the fixed-point table.
    pub truth_fixed: C1,
    /// Closed loop with the corrected table.
    pub truth_final: C1,
    /// Std after, µm/s: closed loop with the fixed-point and the corrected
    /// table, and the replay's with the corrected one.
    pub std_after_um_s: (f64, f64, f64),
    /// Fundamentals of the fixed-point and corrected tables, N.
    pub table_fixed: C1,
    /// The same of the corrected table.
    pub table_final: C1,
    /// Periods averaged in the records' synchronous average.
    pub periods: usize,
    /// Half-width of the records' fundamental amplitude's band at the
    /// synchronous average's confidence, from its per-bin band (µm/s).
    pub measured_band_um_s: f64,
}

/// Takes bench `s` apart at f_c (module docs).
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn trace(s: &SimSettings) -> Result<FcTrace> {
    let Compensated {
        sim,
        pred,
        gains,
        analysis: a,
        comp,
        ..
    } = simulate_and_compensate(s)?;
    let recs = std::slice::from_ref(&sim.recording);
    let bad = |reason: String| Error::InvalidRecording {
        source_name: sim.recording.source_name(),
        reason,
    };
    let d = design_again(&a, recs, &comp, true).map_err(bad)?;
    let c = |w: &[f64]| coefficient(w, 1);
    let (truth_fixed, std_fixed) = run(s, &d.trace.fixed_point, &pred)?;
    let (truth_final, std_final) = run(s, &comp.force_n, &pred)?;
    let w_c = std::f64::consts::TAU * comp.prediction.f_c_hz;
    let g = comp.stage.g_vf(w_c) / gains.g_vf(w_c);
    let fz = |g: &PdLoop| (g.omega_n_rad_s() / std::f64::consts::TAU, g.damping_ratio());
    let sync = a.sync.as_ref();
    let w = sync.and_then(|y| y.waveform(Signal::VelocityError));
    Ok(FcTrace {
        velocity_mm_s: s.velocity_mm_s,
        std_over_v: comp.prediction.std_before_um_s * 1e-3 / s.velocity_mm_s,
        stage_source: comp.stage_source,
        stage_f_n_zeta: (fz(&comp.stage), fz(&gains)),
        g_ratio: (g.re, g.im),
        std_before_um_s: comp.prediction.std_before_um_s,
        measured: d.trace.measured_v1.unwrap_or((f64::NAN, f64::NAN)),
        replay_bare: c(&d.trace.bare.waveform_um_s),
        replay_fixed: c(&d.trace.fixed_point_after.waveform_um_s),
        replay_final: c(&d.after.waveform_um_s),
        truth_fixed,
        truth_final,
        std_after_um_s: (std_fixed, std_final, d.after.std_um_s),
        table_fixed: c(&d.trace.fixed_point),
        table_final: c(&d.table),
        periods: sync.map_or(0, |y| y.periods_used),
        measured_band_um_s: w.map_or(f64::NAN, |w| {
            let half: Vec<f64> = w
                .band_high
                .iter()
                .zip(&w.band_low)
                .map(|(h, l)| 0.5 * (h - l))
                .collect();
            fundamental_spread(&half)
        }),
    })
}

/// Rms of the band's half-widths per bin (µm/s) times `2/√B`: the same
/// for the fundamental's amplitude when the bins' errors are independent.
fn fundamental_spread(band: &[f64]) -> f64 {
    let b = band.len().max(1) as f64;
    let rms = (band.iter().map(|x| x * x).sum::<f64>() / b).sqrt();
    rms * 2.0 / b.sqrt()
}

/// Bench `s` with `table` applied, keyed on the passages: the fundamental
/// of its velocity error's synchronous average and its low-passed std.
fn run(s: &SimSettings, table: &[f64], pred: &Prediction) -> Result<(C1, f64)> {
    let ff = Feedforward {
        force_n: table.to_vec(),
        key: FeedforwardKey::OpticalPassage,
    };
    let (r, mean) = super::compensation_stall::run(s, Some(ff), pred)?;
    Ok((coefficient(&mean, 1), r.std_um_s))
}
