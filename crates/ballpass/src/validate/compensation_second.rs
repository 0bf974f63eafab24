//! The second round checked in closed loop (session 14): each bench is
//! compensated with the product's table, simulated with it (the records
//! of the second round), the table corrected from those records
//! ([`crate::model::compensate::second::second_round`]) and simulated
//! again with the corrected table.

use serde::Serialize;

use crate::analysis::{analyze, AnalyzeSettings};
use crate::error::{Error, Result};
use crate::model::compensate::second::second_round;
use crate::sim::feedforward::{Feedforward, FeedforwardKey};
use crate::sim::{simulate, SimSettings};

use super::compensation::{closed_loop, table_for_with, CompensationCheck};

/// One bench's two rounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SecondRoundCheck {
    /// The first round (the product's table; its closed loop is the
    /// second round's records).
    pub first: CompensationCheck,
    /// Velocity-error std over the velocity, without a table.
    pub std_over_v: f64,
    /// The second round, or why there is none (a table withheld).
    pub second: std::result::Result<SecondRun, String>,
}

/// The corrected table in closed loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SecondRun {
    /// f_c component with it, simulated, µm/s.
    pub f_c_after_um_s: f64,
    /// Low-passed velocity-error std with it, simulated, µm/s.
    pub std_after_um_s: f64,
    /// f_c component predicted (10 %, figure, 90 %), µm/s.
    pub f_c_predicted_um_s: [f64; 3],
    /// Std predicted, µm/s.
    pub std_predicted_um_s: f64,
    /// Amplitude of the change of the table's fundamental, N.
    pub change_n: f64,
}

/// Bench `s` in two rounds (module docs).
///
/// # Errors
/// The simulator's, the analysis' and the compensation's errors.
pub fn second_round_check(s: &SimSettings) -> Result<SecondRoundCheck> {
    second_round_check_with(s, &AnalyzeSettings::default())
}

/// [`second_round_check`] with the first round's records analysed with
/// `settings` (e.g. the load cell's τ given; session 15). The second
/// round's records are analysed as the product does.
///
/// # Errors
/// As [`second_round_check`].
pub fn second_round_check_with(
    s: &SimSettings,
    settings: &AnalyzeSettings,
) -> Result<SecondRoundCheck> {
    let (comp, pred) = table_for_with(s, settings)?;
    let mut s1 = s.clone();
    s1.feedforward = Some(comp.feedforward());
    let sim1 = simulate(&s1)?;
    let a1 = analyze(
        std::slice::from_ref(&sim1.recording),
        &pred,
        &AnalyzeSettings::default(),
    )?;
    let first = super::compensation::check_from_run(s, &comp, &a1, &sim1.recording)?;
    let std_over_v = comp.prediction.std_before_um_s * 1e-3 / s.velocity_mm_s;
    let second = match second_round(&comp.force_n, &comp.stage, &a1, std_over_v) {
        Ok(r) => {
            let ff = Feedforward {
                force_n: r.force_n.clone(),
                key: FeedforwardKey::OpticalPassage,
            };
            let (f_c, std) = closed_loop(s, ff, &pred)?;
            Ok(SecondRun {
                f_c_after_um_s: f_c,
                std_after_um_s: std,
                f_c_predicted_um_s: r.f_c_after_um_s,
                std_predicted_um_s: r.std_after_um_s,
                change_n: r.change_n,
            })
        }
        Err(e) if comp.table_refused.is_some() => Err(e),
        Err(reason) => {
            return Err(Error::InvalidRecording {
                source_name: sim1.recording.source_name(),
                reason,
            })
        }
    };
    Ok(SecondRoundCheck {
        first,
        std_over_v,
        second,
    })
}
