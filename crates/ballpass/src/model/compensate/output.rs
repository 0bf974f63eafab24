//! The compensation's files: `compensation.json` and its tables
//! (`compensation_phase.csv`, `compensation_rail.csv`), for the one-shot
//! table and the second round alike.

use serde::Serialize;

use super::Compensation;
use crate::error::{Error, Result};

/// One of the compensation's tables, as its CSV file holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationTable {
    /// First column's name (`phase`, `position_mm`).
    pub index_name: &'static str,
    /// First column.
    pub index: Vec<f64>,
    /// The other columns, named with their units.
    pub columns: Vec<(String, Vec<f64>)>,
}

impl CompensationTable {
    fn write(&self, path: &std::path::Path) -> Result<()> {
        crate::analysis::export::write_csv(
            path,
            &crate::analysis::export::Table {
                index_name: self.index_name,
                index: &self.index,
                columns: self.columns.clone(),
            },
        )
    }
}

impl Compensation {
    /// Phase of each bin, periods after phase 0 (`j / B`).
    fn phases(&self) -> Vec<f64> {
        (0..self.bins)
            .map(|j| j as f64 / self.bins as f64)
            .collect()
    }

    /// The table against phase, `compensation_phase.csv`: `phase`,
    /// `force_n`, `velocity_error_after_um_s`.
    pub fn phase_table(&self) -> CompensationTable {
        CompensationTable {
            index_name: "phase",
            index: self.phases(),
            columns: vec![
                ("force_n".into(), self.force_n.clone()),
                (
                    "velocity_error_after_um_s".into(),
                    self.prediction.waveform_after_um_s.clone(),
                ),
            ],
        }
    }

    /// The table against rail position, `compensation_rail.csv`
    /// (`position_mm`, `force_n`), when the passages lock to the rail.
    pub fn rail_table(&self) -> Option<CompensationTable> {
        self.rail.as_ref().map(|r| CompensationTable {
            index_name: "position_mm",
            index: self
                .phases()
                .iter()
                .map(|p| r.x0_mm + p * r.pitch_mm)
                .collect(),
            columns: vec![("force_n".into(), self.force_n.clone())],
        })
    }

    /// Writes `compensation.json`, `compensation_phase.csv`
    /// ([`Compensation::phase_table`]) and, with a rail table,
    /// `compensation_rail.csv` ([`Compensation::rail_table`]) into `dir`.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file or folder.
    pub fn write(&self, dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>> {
        write_outputs(dir, self, self.phase_table(), self.rail_table())
    }

    /// The table as the simulator's feedforward, keyed on the passages.
    pub fn feedforward(&self) -> crate::sim::feedforward::Feedforward {
        crate::sim::feedforward::Feedforward {
            force_n: self.force_n.clone(),
            key: crate::sim::feedforward::FeedforwardKey::OpticalPassage,
        }
    }
}

/// Writes `json` as `compensation.json`, `phase` as
/// `compensation_phase.csv` and `rail` (when given) as
/// `compensation_rail.csv` into `dir` (created if missing); returns their
/// paths.
///
/// # Errors
/// [`Error::Io`] naming the file or folder.
pub(super) fn write_outputs<T: Serialize>(
    dir: &std::path::Path,
    json: &T,
    phase: CompensationTable,
    rail: Option<CompensationTable>,
) -> Result<Vec<std::path::PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut out = vec![
        dir.join("compensation.json"),
        dir.join("compensation_phase.csv"),
    ];
    crate::fsutil::write_json_pretty(&out[0], json)?;
    phase.write(&out[1])?;
    if let Some(t) = rail {
        let path = dir.join("compensation_rail.csv");
        t.write(&path)?;
        out.push(path);
    }
    Ok(out)
}
