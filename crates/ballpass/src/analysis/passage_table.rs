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
