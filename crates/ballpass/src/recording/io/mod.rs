//! Reading and writing recording files: CSV/TSV text and MATLAB `.mat`.
//!
//! Every loader produces the same [`Recording`] through one validation path
//! ([`LoadOptions`] says which columns or variables hold which channel, with
//! what scale and offset, and how the sampling rate is known):
//!
//! - a time column (`time_s`, or the one named by [`LoadOptions::time`]) must
//!   increase by a uniform step; the sampling rate is derived from it
//!   (see [`timebase`]), and an [`LoadOptions::fs_hz`] given as well must agree;
//! - without a time column, [`LoadOptions::fs_hz`] is required;
//! - every cell must be a finite number, every channel as long as the others,
//!   and, when velocity and bearing are known, the recording must span at
//!   least [`LoadOptions::min_periods`] ball-pass periods.
//!
//! [`write_csv`] writes the canonical CSV and [`write_mat`] a level-5 MAT-file;
//! [`load`] reads either back bit for bit.

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{Channel, Channels, Metadata, Recording};
use crate::bearing::Geometry;
use crate::error::{Error, Result};

pub mod csv;
pub mod mat;
pub mod timebase;

pub use mat::write_mat;

/// File formats a recording can be read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum Format {
    /// Delimited text with a header row; the delimiter is detected
    /// (`,` `;` or tab) unless [`LoadOptions::delimiter`] is set.
    Csv,
    /// Tab-separated text with a header row.
    Tsv,
    /// MATLAB MAT-file, level 5 (`-v6`/`-v7`).
    Mat,
}

impl Format {
    /// The format a file name implies: `.mat` → MAT, `.tsv`/`.tab` → TSV,
    /// anything else → CSV (the delimiter is then detected from the header).
    pub fn from_path(path: &Path) -> Format {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("mat") => Format::Mat,
            Some("tsv" | "tab") => Format::Tsv,
            _ => Format::Csv,
        }
    }
}

/// Where one channel comes from in a file, and how to convert it to its unit.
///
/// ```text
/// value [unit] = raw * scale + offset
/// ```
///
/// e.g. encoder counts at 0.1 µm per count: `scale = 1e-4` → mm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChannelSource {
    /// Column (CSV) or variable / signal name (MAT), matched ignoring case.
    /// `None`: the canonical name (`friction_N`, `position_mm`, `optical_V`).
    pub name: Option<String>,
    /// Multiplier applied to the raw numbers.
    pub scale: f64,
    /// Added after scaling, in the channel's unit.
    pub offset: f64,
}

impl Default for ChannelSource {
    fn default() -> Self {
        Self {
            name: None,
            scale: 1.0,
            offset: 0.0,
        }
    }
}

impl ChannelSource {
    fn is_identity(&self) -> bool {
        self.scale == 1.0 && self.offset == 0.0
    }

    fn check(&self, channel: Channel) -> Result<()> {
        if !(self.scale.is_finite() && self.scale != 0.0) {
            return Err(Error::setting(
                format!("{} scale", channel.short_name()),
                format!("must be a finite non-zero number, got {}", self.scale),
            ));
        }
        if !self.offset.is_finite() {
            return Err(Error::setting(
                format!("{} offset", channel.short_name()),
                format!("must be a finite number, got {}", self.offset),
            ));
        }
        Ok(())
    }
}

/// How to read a recording file: which columns hold what, scales, sampling
/// rate, and the metadata the file itself does not carry.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// File format; `None`: from the file name (see [`Format::from_path`]),
    /// and a file whose contents say otherwise is an error that says so.
    pub format: Option<Format>,
    /// Field delimiter of a text file; `None`: detected from the header line.
    pub delimiter: Option<u8>,
    /// Sampling rate, Hz. Required when the file has no time column; checked
    /// against the time column when it has one.
    pub fs_hz: Option<f64>,
    /// Name of the time column / variable, s. `None`: `time_s` if present
    /// (ControlDesk's `X.Data` in a ControlDesk MAT-file).
    pub time: Option<String>,
    /// Ignore any time column and use [`LoadOptions::fs_hz`] alone.
    pub ignore_time: bool,
    /// Friction force channel, N.
    pub friction: ChannelSource,
    /// Stage position channel, mm.
    pub position: ChannelSource,
    /// Optical sensor channel, V.
    pub optical: ChannelSource,
    /// Largest deviation of one time step from the median step, relative to
    /// the step (the printed time's rounding is allowed on top, see [`timebase`]).
    pub time_step_tolerance: f64,
    /// Tracking velocity, mm/s, recorded in the metadata.
    pub velocity_mm_s: Option<f64>,
    /// Bearing name, recorded in the metadata.
    pub bearing: Option<String>,
    /// Bearing geometry used to check that the recording spans enough
    /// ball-pass periods (only when the velocity is known too).
    pub geometry: Option<Geometry>,
    /// Fewest ball-pass periods `tau_c` a recording must span.
    pub min_periods: f64,
    /// Test identifier; `None`: the file stem.
    pub test_id: Option<String>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            format: None,
            delimiter: None,
            fs_hz: None,
            time: None,
            ignore_time: false,
            friction: ChannelSource::default(),
            position: ChannelSource::default(),
            optical: ChannelSource::default(),
            time_step_tolerance: timebase::DEFAULT_STEP_TOLERANCE,
            velocity_mm_s: None,
            bearing: None,
            geometry: None,
            min_periods: 3.0,
            test_id: None,
        }
    }
}

impl LoadOptions {
    /// The source of one channel.
    pub fn source(&self, c: Channel) -> &ChannelSource {
        match c {
            Channel::Friction => &self.friction,
            Channel::Position => &self.position,
            Channel::Optical => &self.optical,
        }
    }

    /// Mutable access to the source of one channel.
    pub fn source_mut(&mut self, c: Channel) -> &mut ChannelSource {
        match c {
            Channel::Friction => &mut self.friction,
            Channel::Position => &mut self.position,
            Channel::Optical => &mut self.optical,
        }
    }

    /// Checks the ranges of the settings (scales, rate, velocity, tolerances).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        for c in Channel::ALL {
            self.source(c).check(c)?;
        }
        if let Some(fs) = self.fs_hz {
            if !(fs.is_finite() && fs > 0.0) {
                return Err(Error::setting(
                    "fs",
                    format!("must be a positive number of Hz, got {fs}"),
                ));
            }
        }
        if self.ignore_time && self.fs_hz.is_none() {
            return Err(Error::setting(
                "fs",
                "the time column is ignored, so the sampling rate must be given",
            ));
        }
        if let Some(v) = self.velocity_mm_s {
            crate::bearing::check_velocity(v)?;
        }
        if let Some(g) = &self.geometry {
            g.validate()?;
        }
        if !(self.time_step_tolerance.is_finite()
            && self.time_step_tolerance > 0.0
            && self.time_step_tolerance < 0.5)
        {
            return Err(Error::setting(
                "time step tolerance",
                format!(
                    "must be between 0 and 0.5 (relative to the step), got {}",
                    self.time_step_tolerance
                ),
            ));
        }
        if !(self.min_periods.is_finite() && self.min_periods >= 0.0) {
            return Err(Error::setting(
                "min_periods",
                format!("must be zero or positive, got {}", self.min_periods),
            ));
        }
        Ok(())
    }
}

/// Loads one recording file.
///
/// The format comes from [`LoadOptions::format`] or the file name; a file whose
/// contents contradict its name (a CSV renamed `.mat`, a MAT-file named `.csv`)
/// is an error that says what it looks like.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Parse`] naming file,
/// line and column for a bad cell, a ragged row or a bad time step;
/// [`Error::Format`] for an empty, truncated or mislabelled file;
/// [`Error::InvalidSetting`] for bad options; [`Error::InvalidRecording`] for a
/// recording that spans too few ball-pass periods.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Recording> {
    opts.validate()?;
    let format = opts.format.unwrap_or_else(|| Format::from_path(path));
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let table = match format {
        Format::Csv | Format::Tsv => csv::parse(path, &bytes, format, opts)?,
        Format::Mat => mat::parse(path, &bytes, opts)?,
    };
    finish(path, table, opts)
}

/// Numbers read from a file, before validation.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawTable {
    /// The time column, if any.
    pub time: Option<RawColumn>,
    /// Channel columns found, unscaled.
    pub channels: Vec<(Channel, RawColumn)>,
    /// How to name sample `i` in messages.
    pub locator: Locator,
}

/// One column as read.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawColumn {
    /// Name in the file.
    pub name: String,
    /// Values.
    pub values: Vec<f64>,
    /// Half a unit of the last printed digit (text files), 0 for binary.
    pub resolution: f64,
}

/// Names sample `i` of a table in error messages.
#[derive(Debug, Clone, Default)]
pub(crate) enum Locator {
    /// Text file: the 1-based line of each data row.
    Lines(Vec<u64>),
    /// Binary file: 1-based sample number within a variable.
    #[default]
    Samples,
}

impl Locator {
    fn error(&self, path: &Path, i: usize, column: &str, reason: String) -> Error {
        match self {
            Locator::Lines(lines) => Error::Parse {
                path: path.to_path_buf(),
                line: lines.get(i).copied().unwrap_or(0) as usize,
                column: Some(column.to_string()),
                reason,
            },
            Locator::Samples => Error::Format {
                path: path.to_path_buf(),
                reason: format!("variable '{column}', sample {}: {reason}", i + 1),
            },
        }
    }
}

/// Validates a raw table and builds the recording.
pub(crate) fn finish(path: &Path, table: RawTable, opts: &LoadOptions) -> Result<Recording> {
    let n = table
        .channels
        .first()
        .map(|(_, c)| c.values.len())
        .unwrap_or(0);
    let time = if opts.ignore_time { None } else { table.time };
    let (fs_hz, start_time_s) = match &time {
        Some(t) => {
            if t.values.len() != n {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    reason: format!(
                        "time '{}' has {} samples but the channels have {n}",
                        t.name,
                        t.values.len()
                    ),
                });
            }
            let base = timebase::derive(&t.values, t.resolution, opts.time_step_tolerance)
                .map_err(|e| table.locator.error(path, e.index, &t.name, e.reason))?;
            let fs = match opts.fs_hz {
                Some(fs) => {
                    timebase::check_given_rate(&t.values, t.resolution, fs).map_err(|e| {
                        Error::setting(
                            "fs",
                            format!("{}: {} (time '{}')", path.display(), e.reason, t.name),
                        )
                    })?;
                    fs
                }
                None => base.fs_hz,
            };
            (fs, base.start_time_s)
        }
        None => match opts.fs_hz {
            Some(fs) => (fs, 0.0),
            None => {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    reason: format!(
                        "no time column ('{}') and no sampling rate given (fs): one is needed",
                        opts.time.as_deref().unwrap_or("time_s")
                    ),
                })
            }
        },
    };
    let mut channels = Channels::default();
    for (c, col) in table.channels {
        let src = opts.source(c);
        let mut v = col.values;
        if !src.is_identity() {
            for x in &mut v {
                *x = *x * src.scale + src.offset;
            }
        }
        match c {
            Channel::Friction => channels.friction_n = Some(v),
            Channel::Position => channels.position_mm = Some(v),
            Channel::Optical => channels.optical_v = Some(v),
        }
    }
    let meta = Metadata {
        velocity_mm_s: opts.velocity_mm_s,
        bearing: opts.bearing.clone(),
        test_id: opts
            .test_id
            .clone()
            .or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned())),
        source: Some(path.to_path_buf()),
        start_time_s,
    };
    let rec = Recording::new(fs_hz, channels, meta)?;
    check_periods(&rec, opts)?;
    Ok(rec)
}

/// With velocity and geometry known, the recording must span `min_periods` periods.
fn check_periods(rec: &Recording, opts: &LoadOptions) -> Result<()> {
    let (Some(v), Some(g)) = (opts.velocity_mm_s, opts.geometry) else {
        return Ok(());
    };
    let tau_c_s = 1.0 / (v / (2.0 * g.d_avg_mm()));
    let periods = rec.duration_s() / tau_c_s;
    if periods < opts.min_periods {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!(
                "{:.4} s of data spans {periods:.2} ball-pass periods at {v} mm/s \
                 (tau_c = {tau_c_s:.4} s); at least {} needed (min_periods)",
                rec.duration_s(),
                opts.min_periods
            ),
        });
    }
    Ok(())
}

/// Writes a recording as canonical CSV: header `time_s` followed by the
/// channels present (`friction_N`, `position_mm`, `optical_V`), `,`-separated,
/// one row per sample, numbers in the shortest form that reads back to the
/// same `f64` bits.
///
/// The time column is `start_time_s + i / fs_hz`, which [`load`] turns back
/// into the same rate whenever it has at most 15 significant digits (any real
/// bench rate) and into the nearest double of it otherwise.
///
/// The file is written atomically ([`crate::fsutil::write_atomic_with`]), so a
/// reader never sees half a file under `path`.
///
/// # Errors
/// [`Error::Io`] naming the file when it cannot be written.
pub fn write_csv(rec: &Recording, path: &Path) -> Result<()> {
    crate::fsutil::write_atomic_with(path, |w| write_csv_to(rec, w))
}

/// Writes the canonical CSV of [`write_csv`] to any writer.
///
/// # Errors
/// The writer's error.
pub fn write_csv_to<W: Write>(rec: &Recording, w: &mut W) -> std::io::Result<()> {
    let channels: Vec<&[f64]> = rec
        .channels()
        .into_iter()
        .filter_map(|c| rec.channel(c))
        .collect();
    w.write_all(b"time_s")?;
    for c in rec.channels() {
        w.write_all(b",")?;
        w.write_all(c.column_name().as_bytes())?;
    }
    w.write_all(b"\n")?;
    let mut buf = zmij::Buffer::new();
    for i in 0..rec.len() {
        w.write_all(buf.format_finite(rec.time_s(i)).as_bytes())?;
        for ch in &channels {
            w.write_all(b",")?;
            w.write_all(buf.format_finite(ch[i]).as_bytes())?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests;
