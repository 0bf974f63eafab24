//! Near stall taken apart (session 13): why the product's table misses
//! the goal on some benches whose velocity-error std is over 15 % of the
//! velocity. Each such bench is run in closed loop with the product's
//! table, with the fundamental of its fixed-point table alone (corrected
//! as the table is), with the table built on the simulated stage's gains
//! (the identification left out: is it the stage model?), and without a
//! table; beside each, what the replay predicted for it. The replay's
//! error at f_c without a table (records against replay, `E_0`) and with
//! the product's table (closed loop against replay, `E_T`) are given as
//! complex fundamentals, so their sizes and phases can be compared.

use serde::Serialize;

use crate::analysis::sync::coefficient;
use crate::analysis::AnalyzeSettings;
use crate::error::{Error, Result};
use crate::model::compensate::{design_again, designed, Kept};
use crate::model::stage::PdLoop;
use crate::sim::feedforward::{Feedforward, FeedforwardKey};
use crate::sim::{simulate, SimSettings};

use super::compensation::{check_table, CompensationCheck};
use super::compensation_fc::C1;
use super::compensation_stall::{run, Run};

/// Velocity-error std over the velocity above which a bench is taken
/// apart (below, only the product's check is made).
pub const TAKEN_APART_ABOVE: f64 = 0.15;

/// One table's figures on a bench.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Alternative {
    /// Closed loop with it.
    pub run: Run,
    /// The replay's f_c component with it, µm/s.
    pub replay_f_c_um_s: f64,
    /// The replay's std with it, µm/s.
    pub replay_std_um_s: f64,
    /// Amplitude of the table's fundamental, N.
    pub u1_n: f64,
}

/// One bench taken apart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NearStall {
    /// The product's check.
    pub product: CompensationCheck,
    /// What the guard kept.
    pub kept: Option<Kept>,
    /// Velocity-error std over the velocity, without a table.
    pub std_over_v: f64,
    /// The rest, when the bench is over [`TAKEN_APART_ABOVE`] and the
    /// table came from the replay.
    pub apart: Option<Apart>,
}

/// A near-stall bench taken apart (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Apart {
    /// Without a table, closed loop (the bench itself).
    pub none: Run,
    /// The replay without a table: f_c component and std, µm/s.
    pub replay_bare: (f64, f64),
    /// The product's table.
    pub product: Alternative,
    /// The fundamental of the fixed-point table alone, corrected.
    pub fundamental_only: Option<Alternative>,
    /// The product's design on the simulated stage's gains.
    pub true_gains: Alternative,
    /// The friction against travel (the first table): the replay's std.
    pub travel_replay_std_um_s: f64,
    /// Records' fundamental minus the bare replay's, µm/s (`E_0`).
    pub e_0: C1,
    /// Closed loop's fundamental with the product's table minus the
    /// replay's with it, µm/s (`E_T`).
    pub e_t: C1,
    /// `G_vf(jω_c)` of the stage used over the simulated one's.
    pub g_ratio: C1,
}

/// Bench `s` taken apart (module docs).
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn near_stall_check(s: &SimSettings) -> Result<NearStall> {
    let sim = simulate(s)?;
    let pred = s.geometry.predict(s.velocity_mm_s, 5)?;
    let gains = PdLoop::from_products(s.stage.mass_kg, s.stage.kkp_n_per_m, s.stage.kkd_n_s_per_m)?;
    let recs = std::slice::from_ref(&sim.recording);
    let a = crate::analysis::analyze(recs, &pred, &AnalyzeSettings::default())?;
    let (comp, design) = designed(&a, recs, Some(gains))?;
    let product = check_table(s, &comp, &pred)?;
    let std_over_v = comp.prediction.std_before_um_s * 1e-3 / s.velocity_mm_s;
    let out = |apart| NearStall {
        product: product.clone(),
        kept: comp.design_kept,
        std_over_v,
        apart,
    };
    if design.is_none() || std_over_v <= TAKEN_APART_ABOVE {
        return Ok(out(None));
    }
    let d = design_again(&a, recs, &comp, true).map_err(|reason| Error::InvalidRecording {
        source_name: sim.recording.source_name(),
        reason,
    })?;
    let amp = |c: C1| 2.0 * c.0.hypot(c.1);
    let ff = |t: &[f64]| {
        Some(Feedforward {
            force_n: t.to_vec(),
            key: FeedforwardKey::OpticalPassage,
        })
    };
    let (none, _) = run(s, None, &pred)?;
    let (prod_run, prod_mean) = run(s, ff(&comp.force_n), &pred)?;
    let fundamental_only = match &d.trace.fundamental_only {
        Some(c) => Some(Alternative {
            run: run(s, ff(&c.table), &pred)?.0,
            replay_f_c_um_s: c.after.f_c_um_s,
            replay_std_um_s: c.after.std_um_s,
            u1_n: amp(coefficient(&c.table, 1)),
        }),
        None => None,
    };
    let mut a2 = a.clone();
    if let Some(st) = a2.stage.as_mut() {
        st.identified = false;
    }
    let (comp2, d2) = designed(&a2, recs, Some(gains))?;
    let true_gains = Alternative {
        run: run(s, ff(&comp2.force_n), &pred)?.0,
        replay_f_c_um_s: d2.as_ref().map_or(f64::NAN, |d| d.after.f_c_um_s),
        replay_std_um_s: comp2.prediction.std_after_um_s,
        u1_n: amp(coefficient(&comp2.force_n, 1)),
    };
    let bare = coefficient(&d.trace.bare.waveform_um_s, 1);
    let measured = d.trace.measured_v1.unwrap_or((f64::NAN, f64::NAN));
    let truth = coefficient(&prod_mean, 1);
    let replayed = coefficient(&d.after.waveform_um_s, 1);
    let w_c = std::f64::consts::TAU * comp.prediction.f_c_hz;
    let g = comp.stage.g_vf(w_c) / gains.g_vf(w_c);
    let bad = |reason: &str| Error::InvalidRecording {
        source_name: sim.recording.source_name(),
        reason: reason.into(),
    };
    Ok(out(Some(Apart {
        none,
        replay_bare: (d.trace.bare.f_c_um_s, d.trace.bare.std_um_s),
        product: Alternative {
            run: prod_run,
            replay_f_c_um_s: d.after.f_c_um_s,
            replay_std_um_s: d.after.std_um_s,
            u1_n: amp(coefficient(&comp.force_n, 1)),
        },
        fundamental_only,
        true_gains,
        travel_replay_std_um_s: d
            .trace
            .rounds
            .first()
            .ok_or_else(|| bad("no round in the design"))?
            .std_um_s,
        e_0: (measured.0 - bare.0, measured.1 - bare.1),
        e_t: (truth.0 - replayed.0, truth.1 - replayed.1),
        g_ratio: (g.re, g.im),
    })))
}
