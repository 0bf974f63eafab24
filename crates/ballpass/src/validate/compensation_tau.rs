//! The load cell's τ and the compensation (session 15): on a bench, the
//! replay's agreement with the records for each candidate τ
//! ([`crate::model::compensate::tau`]), beside the simulated τ and the one
//! the analysis fitted.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::model::compensate::tau::{scan, TauCandidate};
use crate::model::compensate::SEVERE_STALL_FRACTION;
use crate::sim::SimSettings;

use super::compensation::{simulate_and_compensate, Compensated};

/// One bench's scan.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TauScan {
    /// The simulated load cell's τ, s (`None`: DC coupled).
    pub true_tau_s: Option<f64>,
    /// The τ the analysis undid (`None`: none).
    pub analysis_tau_s: Option<f64>,
    /// Velocity-error std over the velocity, without a table.
    pub std_over_v: f64,
    /// The τ the rule chose (`None`: the friction as recorded).
    pub chosen_tau_s: Option<f64>,
    /// The friction as recorded, then each of `TAU_GRID_S`.
    pub candidates: Vec<TauCandidate>,
}

/// The scan of bench `s` through the stage the product's table used.
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn tau_scan(s: &SimSettings) -> Result<TauScan> {
    let Compensated {
        sim,
        analysis: a,
        comp,
        ..
    } = simulate_and_compensate(s)?;
    let recs = std::slice::from_ref(&sim.recording);
    let std_over_v = comp.prediction.std_before_um_s * 1e-3 / s.velocity_mm_s;
    let taus = crate::model::compensate::tau::candidates();
    let sc = scan(
        &a,
        recs,
        &comp.stage,
        std_over_v <= SEVERE_STALL_FRACTION,
        &taus,
    )
    .map_err(|reason| Error::InvalidRecording {
        source_name: sim.recording.source_name(),
        reason,
    })?;
    Ok(TauScan {
        chosen_tau_s: crate::model::compensate::tau::choose(&sc).flatten(),
        candidates: sc.candidates,
        true_tau_s: s.load_cell.time_constant_s,
        analysis_tau_s: a.load_cell.first().and_then(|d| d.tau_s),
        std_over_v,
    })
}
