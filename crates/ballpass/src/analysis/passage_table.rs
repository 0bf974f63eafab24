//! What `ballpass passage` writes: `passages.csv` (one row per passage of
//! every record) and `passage.json` (schema `ballpass.passage/1`: every
//! record's [`PassageAnalysis`] and the records that failed).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::passage::PassageAnalysis;
use crate::error::Result;
use crate::fsutil::{write_csv_rows, write_json_pretty};
use crate::recording::segment::Window;

/// Schema tag of `passage.json`.
pub const PASSAGE_SCHEMA: &str = "ballpass.passage/1";

/// One passage of one record: a row of `passages.csv`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassageRow {
    /// The record's source.
    pub record: String,
    /// 0-based number of the passage in the record.
    pub index: usize,
    /// Centre of the pulse, s.
    pub time_s: f64,
    /// Sample of the extreme value, s.
    pub peak_time_s: f64,
    /// +1 for a pulse up, −1 for an inverted pulse.
    pub polarity: i8,
    /// Time to the next passage, s.
    pub tau_c_s: Option<f64>,
    /// Width at half prominence, s.
    pub tau_p_s: f64,
    /// Gaussian sigma, s.
    pub sigma_s: f64,
    /// `τ_p / τ_c`.
    pub tau_p_over_tau_c: Option<f64>,
    /// Prominence, V.
    pub amplitude_v: f64,
    /// Height above the running baseline, V.
    pub height_v: f64,
    /// Ball spacing implied, mm.
    pub spacing_mm: Option<f64>,
}

/// A record whose passages could not be measured, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassageFailure {
    /// The record (file name as given).
    pub record: String,
    /// The one-line reason.
    pub error: String,
}

/// Everything `ballpass passage` writes; serialises as `passage.json`.
#[derive(Debug, Clone, Serialize)]
pub struct PassageOutput {
    /// [`PASSAGE_SCHEMA`].
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// Bearing name used for the predictions.
    pub bearing: String,
    /// The time window of every record, when one was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<Window>,
    /// The records measured, in the order given.
    pub records: Vec<PassageAnalysis>,
    /// The records that failed.
    pub failed: Vec<PassageFailure>,
    /// Warnings of the checks before the analysis (dead channels left out,
    /// a forced velocity).
    pub warnings: Vec<String>,
}

impl PassageOutput {
    /// Wraps the measured records and the failures (no window, no
    /// warnings; set those fields when there are some).
    pub fn new(
        bearing: impl Into<String>,
        records: Vec<PassageAnalysis>,
        failed: Vec<PassageFailure>,
    ) -> Self {
        Self {
            schema: PASSAGE_SCHEMA,
            version: crate::VERSION,
            bearing: bearing.into(),
            window: None,
            records,
            failed,
            warnings: Vec::new(),
        }
    }

    /// The rows of `passages.csv`: every passage of every record, in order.
    pub fn rows(&self) -> Vec<PassageRow> {
        self.records.iter().flat_map(passage_rows).collect()
    }

    /// Writes `passages.csv` and `passage.json` into `dir` (which must
    /// exist), each atomically; returns their paths.
    ///
    /// # Errors
    /// [`crate::Error::Io`] naming the file.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let paths = [dir.join("passages.csv"), dir.join("passage.json")];
        write_csv_rows(&paths[0], &self.rows())?;
        write_json_pretty(&paths[1], self)?;
        Ok(paths.to_vec())
    }
}

/// The rows of `passages.csv` for one record.
pub fn passage_rows(r: &PassageAnalysis) -> Vec<PassageRow> {
    r.passages
        .iter()
        .map(|p| PassageRow {
            record: r.source.clone(),
            index: p.index,
            time_s: p.time_s,
            peak_time_s: p.peak_time_s,
            polarity: p.polarity,
            tau_c_s: p.tau_c_s,
            tau_p_s: p.tau_p_s,
            sigma_s: p.sigma_s,
            tau_p_over_tau_c: p.tau_p_over_tau_c,
            amplitude_v: p.amplitude_v,
            height_v: p.height_v,
            spacing_mm: p.spacing_mm,
        })
        .collect()
}

/// One record measured as `ballpass passage` measures it: the record as the
/// checks left it, its passages, and the checks' warnings and notes.
#[derive(Debug, Clone)]
pub struct CheckedPassages {
    /// The record after the checks (dead channels left out).
    pub recording: crate::recording::Recording,
    /// Its passages.
    pub passages: PassageAnalysis,
    /// Warnings of the checks (a forced velocity, a dead channel).
    pub warnings: Vec<String>,
    /// Notes of the checks (the velocity measured from the encoder).
    pub notes: Vec<String>,
}

/// The checks before the analysis, then the passages of one record, as
/// `ballpass passage` runs them: with a velocity (`stated`: the caller's
/// explicit one, else the file's or profile's) or an encoder, the velocity
/// is checked against the encoder (or measured from it when none is
/// stated) by [`super::preflight::check`]; with neither, only the dead
/// channels are left out. `explicit` is the velocity the caller gave
/// itself, which guides the detection; a measured velocity guides it too.
///
/// # Errors
/// The checks' errors (a velocity the encoder contradicts without
/// `force_velocity`, a ball-pass frequency above Nyquist, no live
/// channel) and [`super::passage::detect_passages`]'.
pub fn checked_passages(
    rec: crate::recording::Recording,
    stated: Option<f64>,
    explicit: Option<f64>,
    settings: &super::passage::PassageSettings,
    geometry: &crate::bearing::Geometry,
    pre: &super::preflight::PreflightSettings,
) -> Result<CheckedPassages> {
    use super::preflight::{check, check_channels, VelocitySource};
    let no_encoder = rec.channel(crate::recording::Channel::Position).is_none();
    let (recording, velocity, measured, warnings, notes) = if stated.is_none() && no_encoder {
        let c = check_channels(vec![rec], pre)?;
        let rec = c.recordings.into_iter().next().expect("one in, one out");
        (rec, None, false, c.warnings, Vec::new())
    } else {
        let c = check(vec![rec], stated, geometry, pre)?;
        let measured = c.velocity_source == VelocitySource::Measured;
        let rec = c.recordings.into_iter().next().expect("one in, one out");
        (rec, Some(c.velocity_mm_s), measured, c.warnings, c.notes)
    };
    let s = super::passage::PassageSettings {
        velocity_mm_s: if measured { velocity } else { explicit },
        ..settings.clone()
    };
    let mut passages = super::passage::detect_passages(&recording, &s)?;
    if measured {
        passages.velocity_source = "measured from the encoder".into();
    }
    Ok(CheckedPassages {
        recording,
        passages,
        warnings,
        notes,
    })
}
