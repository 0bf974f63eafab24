//! The replay design's guard checked in closed loop (session 12): each
//! bench compensated with the product's table (a fixed-point round refused,
//! and the rounds stopped, when the replay with its table gives a larger
//! velocity-error std than without a table; a correction of the
//! fundamental kept only when the replay's f_c component falls;
//! [`crate::model::compensate`]) and, where it differs, with the table
//! built without the guard (every round and correction taken, as before
//! session 12), both simulated in closed loop on the same bench.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::model::compensate::{design_again, Kept};
use crate::sim::feedforward::{Feedforward, FeedforwardKey};
use crate::sim::SimSettings;

use super::compensation::{
    check_table, closed_loop, simulate_and_compensate, Compensated, CompensationCheck,
};

/// One bench with the guarded and the unguarded table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GuardCheck {
    /// The product's (guarded) check.
    pub product: CompensationCheck,
    /// What the guard kept.
    pub kept: Option<Kept>,
    /// Largest amplitude of the fundamental of the fixed-point tables (the
    /// friction against travel and each round), N: of those kept by the
    /// guard, and of all four rounds.
    pub round_u1_max_n: (f64, f64),
    /// Amplitude of the final table's fundamental, N: guarded, unguarded.
    pub u1_n: (f64, f64),
    /// Replayed std with each table tried by the unguarded rounds (the
    /// friction against travel first), µm/s.
    pub round_std_um_s: Vec<f64>,
    /// Replayed std without a table, µm/s.
    pub bare_std_um_s: f64,
    /// The unguarded table, when it differs from the product's: simulated
    /// f_c component and std, predicted (replay) f_c component and std,
    /// µm/s.
    pub unguarded: Option<Unguarded>,
}

/// The unguarded table's figures on a bench.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Unguarded {
    /// f_c component simulated with it, µm/s.
    pub f_c_um_s: f64,
    /// Std simulated with it, µm/s.
    pub std_um_s: f64,
    /// The replay's std with it, µm/s.
    pub std_predicted_um_s: f64,
    /// The replay's f_c component with it, µm/s.
    pub f_c_replayed_um_s: f64,
    /// The f_c component after as it would have been given with it
    /// (low, figure, high), µm/s.
    pub f_c_predicted_um_s: [f64; 3],
}

/// Bench `s` with the guarded and, where it differs, the unguarded table.
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn guard_check(s: &SimSettings) -> Result<GuardCheck> {
    let Compensated {
        sim,
        pred,
        analysis: a,
        comp,
        ..
    } = simulate_and_compensate(s)?;
    let recs = std::slice::from_ref(&sim.recording);
    let product = check_table(s, &comp, &pred)?;
    let bad = |reason: String| Error::InvalidRecording {
        source_name: sim.recording.source_name(),
        reason,
    };
    let amp = |c: (f64, f64)| 2.0 * c.0.hypot(c.1);
    let u1 = |t: &[f64]| amp(crate::analysis::sync::coefficient(t, 1));
    let (round_u1_max_n, u1_n, round_std_um_s, bare_std_um_s, unguarded) =
        if let Some(k) = comp.design_kept {
            let d = design_again(&a, recs, &comp, false).map_err(bad)?;
            let max = |r: &[crate::model::compensate::replay::Step]| {
                r.iter().map(|x| amp(x.table_c1)).fold(0.0, f64::max)
            };
            let unguarded = if d.table == comp.force_n {
                None
            } else {
                let ff = Feedforward {
                    force_n: d.table.clone(),
                    key: FeedforwardKey::OpticalPassage,
                };
                let (f_c, std) = closed_loop(s, ff, &pred)?;
                Some(Unguarded {
                    f_c_um_s: f_c,
                    std_um_s: std,
                    std_predicted_um_s: d.after.std_um_s,
                    f_c_replayed_um_s: d.after.f_c_um_s,
                    f_c_predicted_um_s: crate::model::compensate::f_c_after_interval(
                        d.after.f_c_um_s,
                        d.f_c_model_error_um_s,
                        comp.prediction.std_before_um_s * 1e-3 / comp.velocity_mm_s,
                    ),
                })
            };
            (
                // The guarded rounds are the unguarded ones up to the first
                // refused (the same replays).
                (
                    max(&d.trace.rounds[..k.refused_round.unwrap_or(d.trace.rounds.len())]),
                    max(&d.trace.rounds),
                ),
                (u1(&comp.force_n), u1(&d.table)),
                d.trace.rounds.iter().map(|x| x.std_um_s).collect(),
                d.trace.bare.std_um_s,
                unguarded,
            )
        } else {
            (
                (f64::NAN, f64::NAN),
                (u1(&comp.force_n), f64::NAN),
                Vec::new(),
                f64::NAN,
                None,
            )
        };
    Ok(GuardCheck {
        product,
        kept: comp.design_kept,
        round_u1_max_n,
        u1_n,
        round_std_um_s,
        bare_std_um_s,
        unguarded,
    })
}
