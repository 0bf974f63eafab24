//! What the fixed-rate stream sources (MATLAB v7.3, MF4, TDMS) know once
//! their scan is done, and the block loop every pass of theirs runs: read
//! a block of each channel, finish it as the whole-file reader finishes a
//! file, hand it over.

use std::path::{Path, PathBuf};

use super::{finish, LoadOptions, Locator, RawColumn, RawTable};
use crate::error::Result;
use crate::recording::stream::{check_unchanged, Block};
use crate::recording::{Channel, Metadata, Recording};

/// A scanned file: where it is, the record's rate, length, channels and
/// metadata, and how each block is finished.
#[derive(Debug, Clone)]
pub(crate) struct Scanned {
    pub(crate) path: PathBuf,
    /// The file's length when it was opened.
    pub(crate) size: u64,
    /// The options each block is finished with ([`piece_options`]).
    pub(crate) piece_opts: LoadOptions,
    /// Time of the first sample, s.
    pub(crate) start_time_s: f64,
    pub(crate) fs_hz: f64,
    pub(crate) len: usize,
    pub(crate) channels: Vec<Channel>,
    pub(crate) meta: Metadata,
}

impl Scanned {
    /// Errors unless the file is as long as when it was opened
    /// ([`check_unchanged`]); a pass calls it before reading.
    pub(crate) fn unchanged(&self) -> Result<()> {
        check_unchanged(&self.path, self.size)
    }

    /// Reads the record from its start in blocks of `block` samples (the
    /// last one taking what would be left shorter than a recording):
    /// `read(at, n)` gives the raw columns of samples `at..at + n`, which
    /// are finished with [`Self::piece_opts`] and handed to `f`.
    pub(crate) fn blocks(
        &self,
        block: usize,
        read: &mut dyn FnMut(usize, usize) -> Result<Vec<(Channel, RawColumn)>>,
        f: &mut dyn FnMut(Block<'_>) -> Result<()>,
    ) -> Result<()> {
        let mut at = 0;
        while at < self.len {
            let n = first_block(self.len - at, block);
            let table = RawTable {
                channels: read(at, n)?,
                locator: Locator::SamplesFrom(at),
                start_time_s: Some(self.start_time_s + at as f64 / self.fs_hz),
                ..RawTable::default()
            };
            for rec in finish::finish(&self.path, table, &self.piece_opts)? {
                f(Block::of(&rec))?;
            }
            at += n;
        }
        Ok(())
    }

    /// The file read.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }
}

/// Samples in the block starting at 0 of a record of `len`: `block`, or
/// all when what would be left is shorter than a recording.
pub(crate) fn first_block(len: usize, block: usize) -> usize {
    if len.saturating_sub(block) < Recording::MIN_SAMPLES {
        len
    } else {
        block
    }
}

/// The options a piece is finished with: the record's rate given, its
/// time column (checked by the scan) not read again, no period check (the
/// whole record's is the analysis').
pub(crate) fn piece_options(opts: &LoadOptions, fs_hz: f64) -> LoadOptions {
    LoadOptions {
        fs_hz: Some(fs_hz),
        ignore_time: true,
        velocity_mm_s: None,
        ..opts.clone()
    }
}

/// The four [`crate::recording::stream::RecordSource`] getters of a
/// source whose [`Scanned`] is its field `scan`.
macro_rules! scanned_getters {
    () => {
        fn fs_hz(&self) -> f64 {
            self.scan.fs_hz
        }

        fn len(&self) -> usize {
            self.scan.len
        }

        fn channels(&self) -> Vec<Channel> {
            self.scan.channels.clone()
        }

        fn meta(&self) -> &Metadata {
            &self.scan.meta
        }
    };
}
pub(crate) use scanned_getters;

/// What every fixed-rate stream source checks first: the options valid,
/// the path resolved (a `FILE#GROUP` or the like split off), and no gap
/// policy that fills or splits (that needs the record whole). `Ok(Err(why))`
/// when the file is to be read whole instead.
///
/// # Errors
/// The options' and the path's errors.
#[allow(clippy::type_complexity)]
pub(crate) fn stream_request<'a>(
    path: &Path,
    opts: &'a LoadOptions,
) -> Result<std::result::Result<(PathBuf, std::borrow::Cow<'a, LoadOptions>), String>> {
    opts.validate()?;
    let (file_path, opts) = super::resolve(path, opts)?;
    if !opts.gaps.refuses() {
        return Ok(Err(
            "filling or splitting at gaps needs the record in memory".into(),
        ));
    }
    Ok(Ok((file_path, opts)))
}
