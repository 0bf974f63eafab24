//! Reading and writing recording files: CSV/TSV text, MATLAB `.mat` (level 5
//! and v7.3), NI TDMS and ASAM MDF 4.
//!
//! Every loader produces the same [`Recording`] through one validation path
//! ([`LoadOptions`] says which columns, variables or channels hold which
//! channel, with what scale and offset, and how the sampling rate is known):
//!
//! - a time column (`time_s`, or the one named by [`LoadOptions::time`]; an
//!   MF4 master channel) must increase by a uniform step; the sampling rate
//!   is derived from it (see [`timebase`]), and an [`LoadOptions::fs_hz`]
//!   given as well must agree. A rate the file states (TDMS `wf_increment`,
//!   a MAT variable named by [`LoadOptions::fs_from`]) counts as given;
//! - without a time column or a stated rate, [`LoadOptions::fs_hz`] is required;
//! - every channel must be as long as the others; a sample without a finite
//!   value or a time stamp missing from the grid is a gap, refused unless
//!   [`LoadOptions::gaps`] says to fill or split (see [`GapPolicy`]); a
//!   value beyond ±[`Recording::MAX_ABS`] is refused;
//! - when velocity and bearing are known, the recording must span at least
//!   [`LoadOptions::min_periods`] ball-pass periods.
//!
//! Errors are one line and name the file and the line and column (text) or
//! the variable/channel and sample (binary formats). Loaders bound their
//! time and memory by what the file can really hold, and contain any
//! failure of a third-party parser as such an error (see `contain`).
//!
//! [`write_csv`] writes the canonical CSV and [`write_mat`] a level-5 MAT-file;
//! [`load`] reads either back bit for bit.

use std::io::Write;
use std::path::Path;

use super::{Channel, Recording};
use crate::error::{Error, Result};

pub(crate) mod contain;
pub mod csv;
mod finish;
pub mod mat;
pub mod mf4;
pub(crate) mod names;
mod options;
pub(crate) mod scanned;
pub mod tdms;
pub mod timebase;
pub(crate) mod units;

pub use finish::{prepare_for_inspection, Gap, GapCause, Prepared};
pub use mat::write_mat;
pub use options::{
    ChannelSource, Format, GapPolicy, LoadOptions, LoadOverrides, SourceOverride, TimeUnit,
};

/// Loads one recording file.
///
/// The format comes from [`LoadOptions::format`] or the file name; a file whose
/// contents contradict its name (a CSV renamed `.mat`, a MAT-file named `.csv`)
/// is an error that says what it looks like.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Parse`] naming file,
/// line and column for a bad cell, a ragged row or a bad time step;
/// [`Error::Format`] for an empty, truncated, damaged or mislabelled file;
/// [`Error::InvalidSetting`] for bad options; [`Error::InvalidRecording`] for a
/// recording that spans too few ball-pass periods, or that the gap policy
/// splits into several pieces (use [`load_all`] for those).
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Recording> {
    opts.validate()?;
    let (file, opts) = resolve(path, opts)?;
    if let Some(pieces) = load_streamed(&file, &opts)? {
        return one_piece(path, named(path, pieces, &opts));
    }
    let bytes = read(&file)?;
    one_piece(
        path,
        named(path, load_all_bytes(&file, &bytes, &opts)?, &opts),
    )
}

/// A path `FILE#NAME` names record `NAME` of `FILE` (a TDMS group): the
/// file and the options with [`LoadOptions::record`] set. A path that is a
/// file as it stands is that file, `#` and all.
///
/// # Errors
/// [`Error::Format`] naming the file when it is not of a format that holds
/// several records (TDMS), or when the name is empty.
pub(crate) fn resolve<'a>(
    path: &Path,
    opts: &'a LoadOptions,
) -> Result<(std::path::PathBuf, std::borrow::Cow<'a, LoadOptions>)> {
    use std::borrow::Cow;
    let split = path
        .to_str()
        .filter(|_| !path.exists())
        .and_then(|s| s.rsplit_once('#'))
        .filter(|(f, name)| !name.contains('/') && Path::new(f).is_file());
    let Some((file, name)) = split else {
        if let Some(r) = &opts.record {
            check_holds_records(path, opts, r)?;
        }
        return Ok((path.to_path_buf(), Cow::Borrowed(opts)));
    };
    let file = std::path::PathBuf::from(file);
    if name.trim().is_empty() {
        return Err(Error::Format {
            path: file,
            reason: "'#' with no record name after it; give FILE#GROUP".into(),
        });
    }
    check_holds_records(&file, opts, name)?;
    Ok((
        file,
        Cow::Owned(LoadOptions {
            record: Some(name.to_string()),
            ..opts.clone()
        }),
    ))
}

/// Only TDMS files hold several records here.
fn check_holds_records(file: &Path, opts: &LoadOptions, name: &str) -> Result<()> {
    let format = opts.format.unwrap_or_else(|| Format::from_path(file));
    if format == Format::Tdms {
        return Ok(());
    }
    Err(Error::Format {
        path: file.to_path_buf(),
        reason: format!(
            "'#{}' names a record inside the file, but only TDMS files (one group per run) \
             hold several records; this file is read as {}",
            crate::error::excerpt(name),
            format.name()
        ),
    })
}

/// The recordings of `FILE#NAME` named after it (source and test id), so
/// that records of one file are told apart in every output.
fn named(path: &Path, mut recs: Vec<Recording>, opts: &LoadOptions) -> Vec<Recording> {
    for r in &mut recs {
        name_record(path, &mut r.meta, opts);
    }
    recs
}

/// The metadata of a record of `FILE#NAME` named after it (see [`named`]).
pub(crate) fn name_record(path: &Path, meta: &mut super::Metadata, opts: &LoadOptions) {
    let Some(name) = &opts.record else {
        return;
    };
    meta.source = Some(path.to_path_buf());
    if opts.test_id.is_none() {
        meta.test_id = meta.test_id.take().map(|t| format!("{t}#{name}"));
    }
}

/// A long text file read in pieces (`csv::parse_streamed`), when it is one.
fn load_streamed(path: &Path, opts: &LoadOptions) -> Result<Option<Vec<Recording>>> {
    let format = opts.format.unwrap_or_else(|| Format::from_path(path));
    if !matches!(format, Format::Csv | Format::Tsv) {
        return Ok(None);
    }
    match csv::parse_streamed(path, format, opts)? {
        Some(table) => finish::finish(path, table, opts).map(Some),
        None => Ok(None),
    }
}

/// Loads one recording file that [`GapPolicy::split`] may cut into several
/// recordings at its gaps (one when it has none).
///
/// # Errors
/// As [`load`].
pub fn load_all(path: &Path, opts: &LoadOptions) -> Result<Vec<Recording>> {
    opts.validate()?;
    let (file, opts) = resolve(path, opts)?;
    if let Some(pieces) = load_streamed(&file, &opts)? {
        return Ok(named(path, pieces, &opts));
    }
    let bytes = read(&file)?;
    Ok(named(path, load_all_bytes(&file, &bytes, &opts)?, &opts))
}

/// [`load`] of a file already in memory; `path` names it in messages and
/// gives the format when none is set.
///
/// # Errors
/// As [`load`].
pub fn load_bytes(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<Recording> {
    one_piece(path, load_all_bytes(path, bytes, opts)?)
}

/// The one recording of a file, or the error for a file split at its gaps.
fn one_piece(path: &Path, mut pieces: Vec<Recording>) -> Result<Recording> {
    match pieces.len() {
        1 => Ok(pieces.remove(0)),
        n => Err(Error::InvalidRecording {
            source_name: crate::error::shown_path(path),
            reason: format!(
                "split at its gaps into {n} pieces, and one recording per file is expected here"
            ),
        }),
    }
}

/// [`load_all`] of a file already in memory.
///
/// # Errors
/// As [`load`].
pub fn load_all_bytes(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<Vec<Recording>> {
    opts.validate()?;
    let table = parse(path, bytes, opts)?;
    finish::finish(path, table, opts)
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The raw table of a file in memory, by its format.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let format = opts.format.unwrap_or_else(|| Format::from_path(path));
    if let Some(r) = &opts.record {
        check_holds_records(path, opts, r)?;
    }
    match format {
        Format::Csv | Format::Tsv => csv::parse(path, bytes, format, opts),
        Format::Mat => mat::parse(path, bytes, opts),
        Format::Tdms => tdms::parse(path, bytes, opts),
        Format::Mf4 => mf4::parse(path, bytes, opts),
    }
}

/// What a file holds, one line per item (a variable, struct field, group or
/// channel with what it is), for `inspect`: the names to give as channel
/// sources. At most `limit` items.
///
/// # Errors
/// As [`load`] for a file that cannot be read at all.
pub fn contents(path: &Path, opts: &LoadOptions, limit: usize) -> Result<Vec<(String, String)>> {
    let (file, opts) = resolve(path, opts)?;
    let bytes = read(&file)?;
    contents_of_bytes(&file, &bytes, &opts, limit)
}

/// [`contents`] of a file in memory.
///
/// # Errors
/// As [`load`] for a file that cannot be read at all.
pub fn contents_of_bytes(
    path: &Path,
    bytes: &[u8],
    opts: &LoadOptions,
    limit: usize,
) -> Result<Vec<(String, String)>> {
    let format = opts.format.unwrap_or_else(|| Format::from_path(path));
    match format {
        Format::Csv | Format::Tsv => csv::contents(path, bytes, format, opts, limit),
        Format::Mat => mat::contents(path, bytes, limit),
        Format::Tdms => tdms::contents(path, bytes, opts.record.as_deref(), limit),
        Format::Mf4 => mf4::contents(path, bytes, limit),
    }
}

/// Numbers read from a file, before validation.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawTable {
    /// The time column, if any.
    pub time: Option<RawColumn>,
    /// Unit of the time column the file states, with where it says so.
    pub time_unit: Option<(TimeUnit, String)>,
    /// Channel columns found, unscaled.
    pub channels: Vec<(Channel, RawColumn)>,
    /// How to name sample `i` in messages.
    pub locator: Locator,
    /// A sampling rate the file states, Hz, and where it says so.
    pub stated_rate: Option<(f64, String)>,
    /// Time of the first sample the file states, s, when it has no time column.
    pub start_time_s: Option<f64>,
    /// How the file was read, when that changed numbers (units converted).
    pub notes: Vec<String>,
}

/// One column as read.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawColumn {
    /// Name in the file (escaped for messages).
    pub name: String,
    /// Values.
    pub values: Vec<f64>,
    /// Half a unit of the last printed digit (text files), 0 for binary.
    pub resolution: f64,
    /// The unit the file states for it, with where it says so.
    pub unit: Option<(String, String)>,
}

/// Names sample `i` of a table in error messages.
#[derive(Debug, Clone, Default)]
pub(crate) enum Locator {
    /// Text file: the 1-based line of each data row.
    Lines(Vec<u64>),
    /// Binary file: 1-based sample number within a variable.
    #[default]
    Samples,
    /// A piece of a binary file read in pieces: its sample `i` is sample
    /// `i + offset` of the variable.
    SamplesFrom(usize),
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
            Locator::Samples | Locator::SamplesFrom(_) => Error::Format {
                path: path.to_path_buf(),
                reason: format!("'{column}', {}: {reason}", self.place(i)),
            },
        }
    }

    /// Where sample `i` is, in words (`line 57`, `sample 57`).
    fn place(&self, i: usize) -> String {
        match self {
            Locator::Lines(lines) => format!("line {}", lines.get(i).copied().unwrap_or(0)),
            Locator::Samples => format!("sample {}", i + 1),
            Locator::SamplesFrom(offset) => format!("sample {}", offset + i + 1),
        }
    }
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
