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

use std::path::Path;

use crate::analysis::sync::SyncKey;
use crate::analysis::{analyze, Analysis, AnalyzeSettings, Signal};
use crate::bearing::Prediction;
use crate::error::{Error, Result};
use crate::model::stage::PdLoop;
use crate::recording::Recording;

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
) -> std::result::Result<SecondRound, String> {
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

/// Schema tag of the `compensation.json` a second round writes.
pub const SECOND_SCHEMA: &str = "ballpass.compensation-second/1";

/// The table a machine ran with, read back from the `compensation.json`
/// that gave it (a first round's or a second round's): what
/// [`second_round`] needs of it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AppliedTable {
    /// The file it was read from.
    pub source: String,
    /// Force per bin, N (bin `j` at phase `j / B` after the optical passage).
    pub force_n: Vec<f64>,
    /// The stage the table was designed with.
    pub stage: PdLoop,
    /// Velocity the table was made at, mm/s.
    pub velocity_mm_s: f64,
    /// Low-passed velocity-error std before any table, µm/s (the first
    /// round's records; carried on by later rounds).
    pub std_before_um_s: f64,
}

/// What [`AppliedTable::read`] takes of either schema.
#[derive(serde::Deserialize)]
struct AppliedFile {
    schema: String,
    force_n: Vec<f64>,
    stage: PdLoop,
    velocity_mm_s: f64,
    #[serde(default)]
    prediction: Option<BeforeStd>,
    #[serde(default)]
    std_before_um_s: Option<f64>,
}

#[derive(serde::Deserialize)]
struct BeforeStd {
    std_before_um_s: f64,
}

impl AppliedTable {
    /// Reads the `compensation.json` of `ballpass compensate` (first or
    /// second round).
    ///
    /// # Errors
    /// [`Error::Io`] when unreadable; as [`AppliedTable::parse`] otherwise.
    pub fn read(path: &Path) -> Result<AppliedTable> {
        let text = crate::fsutil::read_text(path, "compensation.json is JSON text")?;
        Self::parse(path, &text)
    }

    /// The table of `text`, the content of a `compensation.json` named
    /// `path` in errors.
    ///
    /// # Errors
    /// [`Error::Format`] naming `path` when it is not such a file, has no
    /// table, or its table or velocity is not finite.
    pub fn parse(path: &Path, text: &str) -> Result<AppliedTable> {
        let bad = |reason: String| Error::Format {
            path: path.to_path_buf(),
            reason,
        };
        let f: AppliedFile = serde_json::from_str(text).map_err(|e| {
            bad(format!(
                "not the compensation.json of `ballpass compensate` ({e})"
            ))
        })?;
        if f.schema != super::SCHEMA && f.schema != SECOND_SCHEMA {
            return Err(bad(format!(
                "schema {:?}, expected {:?} or {:?}",
                f.schema,
                super::SCHEMA,
                SECOND_SCHEMA
            )));
        }
        let std_before_um_s = f
            .std_before_um_s
            .or(f.prediction.map(|p| p.std_before_um_s))
            .ok_or_else(|| bad("no velocity-error std before the table".into()))?;
        if f.force_n.iter().any(|u| !u.is_finite()) {
            return Err(bad("force_n holds a value that is not finite".into()));
        }
        if !(f.velocity_mm_s.is_finite() && f.velocity_mm_s > 0.0) {
            return Err(bad(format!(
                "velocity_mm_s {} is not a positive speed",
                f.velocity_mm_s
            )));
        }
        Ok(AppliedTable {
            source: path.display().to_string(),
            force_n: f.force_n,
            stage: f.stage,
            velocity_mm_s: f.velocity_mm_s,
            std_before_um_s,
        })
    }

    /// The table as the simulator applies it: keyed on the optical
    /// passages, as `ballpass compensate` makes it.
    pub fn feedforward(&self) -> crate::sim::feedforward::Feedforward {
        crate::sim::feedforward::Feedforward {
            force_n: self.force_n.clone(),
            key: crate::sim::feedforward::FeedforwardKey::OpticalPassage,
        }
    }
}

/// `compensation.json` of a second round: the corrected table, the table
/// the records were taken with and what the correction is predicted to
/// leave.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SecondCompensation {
    /// [`SECOND_SCHEMA`].
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// Records used: taken with the applied table.
    pub sources: Vec<String>,
    /// The `compensation.json` of the applied table.
    pub applied_from: String,
    /// Velocity of the records, mm/s.
    pub velocity_mm_s: f64,
    /// Phase 0 in words.
    pub phase_reference: String,
    /// Bins per period.
    pub bins: usize,
    /// Spacing of the table in phase, periods (`1 / B`).
    pub phase_spacing: f64,
    /// Mean period of the records' average, s.
    pub period_s: f64,
    /// Periods averaged.
    pub periods_used: usize,
    /// The corrected table, N per bin, along the motion.
    pub force_n: Vec<f64>,
    /// The table the records were taken with, N per bin.
    pub applied_force_n: Vec<f64>,
    /// The stage the applied table was designed with (used again).
    pub stage: PdLoop,
    /// Low-passed velocity-error std before any table, µm/s (carried from
    /// the applied table's file; it picks the row of [`SECOND_OVER_FIRST`]).
    pub std_before_um_s: f64,
    /// The correction and its prediction.
    pub round: SecondRound,
    /// Warnings: the analysis' and, first, the checks of this round.
    pub warnings: Vec<String>,
}

/// The second round of the records `recs`, taken with `applied` on the
/// machine: analysed with `settings` at `pred`, then [`second_round`].
///
/// # Errors
/// The analysis' errors; [`Error::InvalidRecording`] when there is no
/// synchronous average keyed on optical passages, or when
/// [`second_round`] refuses (a withheld table, too few bins).
pub fn second_from_records(
    recs: &[Recording],
    pred: &Prediction,
    settings: &AnalyzeSettings,
    applied: &AppliedTable,
) -> Result<SecondCompensation> {
    let a = analyze(recs, pred, settings)?;
    let names = a
        .inputs
        .iter()
        .map(|i| i.source.clone())
        .collect::<Vec<_>>();
    let bad = |reason: String| Error::InvalidRecording {
        source_name: names.join(", "),
        reason,
    };
    let sync = a
        .sync
        .as_ref()
        .ok_or_else(|| bad("a second round needs the synchronous average".into()))?;
    if sync.key != SyncKey::OpticalPassage {
        return Err(bad(
            "a second round needs optical ball passages (the table is keyed on them); the \
             average was keyed on the encoder"
                .into(),
        ));
    }
    let stall = applied.std_before_um_s * 1e-3 / applied.velocity_mm_s;
    let round = second_round(&applied.force_n, &applied.stage, &a, stall).map_err(bad)?;
    let mut warnings = Vec::new();
    let v = a.prediction.velocity_mm_s;
    if (v / applied.velocity_mm_s - 1.0).abs() > VELOCITY_MATCH {
        warnings.push(format!(
            "the applied table was made at {:.4} mm/s and these records run at {v:.4} mm/s: \
             the correction assumes the same stage response at both",
            applied.velocity_mm_s
        ));
    }
    if stall > super::STALL_FRACTION {
        warnings.push(format!(
            "near stall before any table (velocity-error std {:.0} % of the velocity): the \
             prediction after this round is the spread of simulated second rounds there \
             (docs/methods.md §14), not a replay",
            100.0 * stall
        ));
    }
    warnings.extend(a.warnings.iter().cloned());
    let bins = round.force_n.len();
    Ok(SecondCompensation {
        schema: SECOND_SCHEMA,
        version: crate::VERSION,
        sources: names,
        applied_from: applied.source.clone(),
        velocity_mm_s: v,
        phase_reference: "the optical passage (the sensor's pulse peak), as the applied table"
            .into(),
        bins,
        phase_spacing: 1.0 / bins as f64,
        period_s: sync.period_s.mean,
        periods_used: sync.periods_used,
        force_n: round.force_n.clone(),
        applied_force_n: applied.force_n.clone(),
        stage: applied.stage,
        std_before_um_s: applied.std_before_um_s,
        round,
        warnings,
    })
}

/// Relative difference of the records' velocity from the applied table's
/// above which a second round warns: the stage's response at the new
/// ball-pass frequency is not the one the table met (2 %, twice the
/// f_c accuracy the analysis states).
pub const VELOCITY_MATCH: f64 = 0.02;

impl SecondCompensation {
    /// The corrected table against phase, `compensation_phase.csv`:
    /// `phase`, `force_n`, `applied_force_n`.
    pub fn phase_table(&self) -> super::CompensationTable {
        super::CompensationTable {
            index_name: "phase",
            index: (0..self.bins)
                .map(|j| j as f64 / self.bins as f64)
                .collect(),
            columns: vec![
                ("force_n".into(), self.force_n.clone()),
                ("applied_force_n".into(), self.applied_force_n.clone()),
            ],
        }
    }

    /// Writes `compensation.json` and `compensation_phase.csv` into `dir`
    /// (created if missing), each atomically; returns their paths.
    ///
    /// # Errors
    /// [`Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<std::path::PathBuf>> {
        super::write_outputs(dir, self, self.phase_table(), None)
    }
}
