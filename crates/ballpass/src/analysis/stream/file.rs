//! Whether a record file is analysed streamed, and the streamed analysis
//! with the velocity it needs: the one choice behind the command line's
//! `--stream` and Python's `stream=`.

use std::path::{Path, PathBuf};

use super::analyze_stream;
use crate::analysis::{Analysis, AnalyzeSettings};
use crate::bearing::Geometry;
use crate::error::{shown_path, Error, Result};
use crate::recording::io::csv::blocks::{self, CsvSource};
use crate::recording::io::mat::stream::{self as mat_stream, MatSource};
use crate::recording::io::mf4::stream::{self as mf4_stream, Mf4Source};
use crate::recording::io::tdms::stream::{self as tdms_stream, TdmsSource};
use crate::recording::io::{resolve, Format};
use crate::recording::stream::{Block, RecordSource};
use crate::recording::{Channel, LoadOptions, Metadata};

/// When to stream a record file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StreamMode {
    /// A file of [`STREAM_ABOVE_BYTES`] or more, when it can be streamed.
    #[default]
    Auto,
    /// Always: a file that cannot be streamed is an error.
    On,
    /// Never: the whole record in memory, with every output.
    Off,
}

impl StreamMode {
    /// `auto`, `on` or `off`.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming `name` for anything else.
    pub fn parse(name: &str, v: &str) -> Result<Self> {
        match v {
            "auto" => Ok(Self::Auto),
            "on" => Ok(Self::On),
            "off" => Ok(Self::Off),
            _ => Err(Error::setting(
                name,
                format!("expected `auto`, `on` or `off`, got `{v}`"),
            )),
        }
    }
}

/// Files at least this long are streamed under [`StreamMode::Auto`]:
/// 1 GiB, about 4.5 hours of three channels at 1 kHz as CSV, 12 hours as
/// float64 TDMS, 9 hours as float64 MF4 (with its time channel) or as
/// MATLAB v7.3 doubles with a time vector.
pub const STREAM_ABOVE_BYTES: u64 = 1 << 30;

/// How the front end names what the messages ask the user to give.
#[derive(Debug, Clone, Copy)]
pub struct Naming {
    /// The stream choice (`--stream`, `stream=`).
    pub stream: &'static str,
    /// The velocity (`--velocity`, `velocity_mm_s=`).
    pub velocity: &'static str,
}

/// A record file read in pieces: the sources [`choose`] streams.
#[derive(Debug)]
pub enum FileSource {
    /// A plain CSV/TSV file.
    Csv(CsvSource),
    /// An NI TDMS file (or one group of it).
    Tdms(TdmsSource),
    /// A MATLAB v7.3 (HDF5) MAT-file.
    Mat(MatSource),
    /// An ASAM MDF 4 file.
    Mf4(Mf4Source),
}

impl FileSource {
    /// The file read.
    pub fn path(&self) -> &Path {
        match self {
            FileSource::Csv(s) => s.path(),
            FileSource::Tdms(s) => s.path(),
            FileSource::Mat(s) => s.path(),
            FileSource::Mf4(s) => s.path(),
        }
    }

    fn inner(&mut self) -> &mut dyn RecordSource {
        match self {
            FileSource::Csv(s) => s,
            FileSource::Tdms(s) => s,
            FileSource::Mat(s) => s,
            FileSource::Mf4(s) => s,
        }
    }

    fn get(&self) -> &dyn RecordSource {
        match self {
            FileSource::Csv(s) => s,
            FileSource::Tdms(s) => s,
            FileSource::Mat(s) => s,
            FileSource::Mf4(s) => s,
        }
    }
}

impl RecordSource for FileSource {
    fn fs_hz(&self) -> f64 {
        self.get().fs_hz()
    }

    fn len(&self) -> usize {
        self.get().len()
    }

    fn channels(&self) -> Vec<Channel> {
        self.get().channels()
    }

    fn meta(&self) -> &Metadata {
        self.get().meta()
    }

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        self.inner().pass(f)
    }
}

/// What [`choose`] decided.
#[derive(Debug)]
pub enum Choice {
    /// Stream the record from this source.
    Stream(Box<FileSource>),
    /// Read the records whole; with a warning when a long file could not
    /// be streamed (it says why, and that memory grows with the record).
    Whole(Option<String>),
}

/// Decides how `files` are analysed under `mode`. `needs_whole` is why
/// the caller needs the record in memory (segmentation, a time window),
/// if it does.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::InvalidSetting`]
/// when `mode` is [`StreamMode::On`] and the files cannot be streamed,
/// saying why.
pub fn choose(
    files: &[PathBuf],
    opts: &LoadOptions,
    mode: StreamMode,
    needs_whole: Option<&str>,
    naming: Naming,
) -> Result<Choice> {
    if mode == StreamMode::Off {
        return Ok(Choice::Whole(None));
    }
    let [path] = files else {
        if mode == StreamMode::On {
            return Err(Error::setting(
                naming.stream,
                format!("`on` takes one record file ({} given)", files.len()),
            ));
        }
        return Ok(Choice::Whole(None));
    };
    // `FILE#GROUP` names a group of a TDMS file.
    let (file, file_opts) = resolve(path, opts)?;
    let size = std::fs::metadata(&file)
        .map_err(|source| Error::Io {
            path: file.clone(),
            source,
        })?
        .len();
    if mode == StreamMode::Auto && size < STREAM_ABOVE_BYTES {
        return Ok(Choice::Whole(None));
    }
    let src =
        match needs_whole {
            Some(why) => Err(why.to_string()),
            None => match file_opts.format.unwrap_or_else(|| Format::from_path(&file)) {
                Format::Csv | Format::Tsv => blocks::open(path, opts)?
                    .map(FileSource::Csv)
                    .ok_or_else(|| {
                        "only a plain CSV/TSV file (a uniform time column, no missing values, no \
                     given rate) is streamed"
                            .to_string()
                    }),
                Format::Tdms => tdms_stream::open(path, opts)?.map(FileSource::Tdms),
                Format::Mat => mat_stream::open(path, opts)?.map(FileSource::Mat),
                Format::Mf4 => mf4_stream::open(path, opts)?.map(FileSource::Mf4),
            },
        };
    let why = match src {
        Ok(src) => return Ok(Choice::Stream(Box::new(src))),
        Err(why) => why,
    };
    let shown = shown_path(path);
    if mode == StreamMode::On {
        return Err(Error::setting(
            naming.stream,
            format!("{shown} cannot be streamed: {why}"),
        ));
    }
    Ok(Choice::Whole(Some(format!(
        "{shown} is {:.1} GB and is read whole ({why}): it needs memory in proportion \
         (about 60 bytes per sample of three channels)",
        size as f64 / 1e9
    ))))
}

/// The streamed analysis of `src` at the velocity given, else the one the
/// file states, with a method note saying which; `progress` hears each
/// pass.
///
/// # Errors
/// [`Error::InvalidSetting`] naming the velocity when there is none
/// (measuring it from the encoder needs the record in memory); the
/// analysis' errors.
pub fn analyze_streamed(
    src: &mut FileSource,
    velocity_mm_s: Option<f64>,
    geometry: &Geometry,
    settings: &AnalyzeSettings,
    naming: Naming,
    progress: &mut dyn FnMut(&str),
) -> Result<Analysis> {
    let Some(v) = velocity_mm_s.or(src.meta().velocity_mm_s) else {
        return Err(Error::setting(
            naming.velocity,
            format!(
                "{} is streamed (too long to hold in memory): give {} (measuring it from the \
                 encoder needs the record in memory), or {} off to read it whole",
                shown_path(src.path()),
                naming.velocity,
                naming.stream
            ),
        ));
    };
    let prediction = geometry.predict(v, settings.harmonics)?;
    let mut analysis = analyze_stream(src, &prediction, settings, progress)?;
    analysis
        .method_notes
        .push(format!("velocity {v:.4} mm/s, stated"));
    Ok(analysis)
}
