//! A second round on the machine (session 14): the table corrected from
//! records taken **with it applied**.
//!
//! Near stall, what the replay gets wrong is how the *compensated* stage
//! sticks, and records taken without a table cannot show it
//! (docs/methods.md §14). Records taken with the table applied do: their
//! velocity error is what the table leaves. The second round moves the
//! table's fundamental by the change that cancels the f_c component left
//! if the stage answers a change of the table's fundamental as the linear
//! loop does (session 10 found it does, stuck or not, within 0.26–0.43 of
//! the 0.40 a linear stage gives per learning step of 0.6):
//!
//! ```text
//! U_1 ← U_1 − R_1 / G_vf(jω_c)
//! ```
//!
//! `R_1` the fundamental of the synchronous average of the records'
//! velocity error (with the table), `ω_c` its ball-pass frequency and
//! `G_vf` the stage the first table was designed with. The higher
//! harmonics stay the table's (learning them raised the std near stall,
//! session 10).

use crate::analysis::{Analysis, Signal};
use crate::model::stage::PdLoop;

/// The f_c component left by the second round over the one in the records
/// taken with the first table, as simulated in closed loop: 10th, 50th and
/// 90th percentiles, for a velocity-error std (before any table) up to
/// [`super::STALL_FRACTION`] of the velocity, up to
/// [`super::SEVERE_STALL_FRACTION`], and above. Measured on design seeds
/// 20 000 000 (`cargo bench -p ballpass --bench compensate -- --second`,
/// the 56 second rounds of draws 0–26 and 60–91 finished when it was
/// frozen): 32 up to 15 % (good bearings and mildly sticking ones), 15
/// between 15 and 57 %, 9 above (docs/methods.md §14). The
/// figure given is the median, the interval from the 10th to the 90th
/// percentile is meant to hold 80 % of second rounds.
pub const SECOND_OVER_FIRST: [[f64; 3]; 3] = [
    [0.007, 0.021, 0.54],
    [0.016, 0.038, 0.16],
    [0.025, 0.052, 0.10],
];

/// The corrected table and what it is predicted to leave.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SecondRound {
    /// The corrected table, N per bin (the applied table with its
    /// fundamental moved).
    pub force_n: Vec<f64>,
    /// Amplitude of the change of the table's fundamental, N.
    pub change_n: f64,
    /// f_c component of the velocity error in the records taken with the
    /// applied table, µm/s.
    pub f_c_with_table_um_s: f64,
    /// Low-passed velocity-error std in those records, µm/s.
    pub std_with_table_um_s: f64,
    /// f_c component predicted after the second round, µm/s, and its
    /// 10–90 % interval ([`SECOND_OVER_FIRST`]).
    pub f_c_after_um_s: [f64; 3],
    /// Std predicted after the second round, µm/s: the records' (the
    /// fundamental's change leaves it within a few per cent near stall).
    pub std_after_um_s: f64,
}

/// The second round: `applied` the table (N per bin, keyed as
/// [`super::Compensation::force_n`]) the records of `a` were taken with,
/// `stage` the stage it was designed with, `stall` the velocity-error std
/// over the velocity before any table (the class of
/// [`SECOND_OVER_FIRST`]).
///
/// # Errors
/// A table of fewer than 4 bins or all zeros (a table withheld: records
/// without a table say nothing about the compensated stage), or records
/// without a synchronous average of the velocity error.
pub fn second_round(
    applied: &[f64],
    stage: &PdLoop,
    a: &Analysis,
    stall: f64,
) -> Result<SecondRound, String> {
    if applied.len() < 4 {
        return Err(format!(
            "the applied table has {} bins, at least 4 are needed",
            applied.len()
        ));
    }
    if applied.iter().all(|&u| u == 0.0) {
        return Err(
            "the applied table is all zeros (a table withheld): records taken \
                    without a table say nothing of the compensated stage"
                .into(),
        );
    }
    let sync = a
        .sync
        .as_ref()
        .ok_or("no synchronous average of the records taken with the table")?;
    let w = sync
        .waveform(Signal::VelocityError)
        .ok_or("no velocity error in the synchronous average of the records")?;
    let w_c = std::f64::consts::TAU / sync.period_s.mean;
    if !w_c.is_finite() || w_c <= 0.0 {
        return Err("no ball-pass period in the records taken with the table".into());
    }
    let mut force_n = applied.to_vec();
    super::replay::correct_fundamental(&mut force_n, &w.mean, stage, w_c);
    let d: Vec<f64> = force_n.iter().zip(applied).map(|(a, b)| a - b).collect();
    let c = crate::analysis::sync::coefficient(&d, 1);
    let std_with = a
        .velocity_error
        .as_ref()
        .map_or(f64::NAN, |v| v.lowpassed_std_um_s);
    let row = if stall <= super::STALL_FRACTION {
        0
    } else if stall <= super::SEVERE_STALL_FRACTION {
        1
    } else {
        2
    };
    Ok(SecondRound {
        force_n,
        change_n: 2.0 * c.0.hypot(c.1),
        f_c_with_table_um_s: w.fundamental_amplitude,
        std_with_table_um_s: std_with,
        f_c_after_um_s: SECOND_OVER_FIRST[row].map(|k| k * w.fundamental_amplitude),
        std_after_um_s: std_with,
    })
}
