//! A record read block by block, any number of times: what the streamed
//! analysis ([`crate::analysis::stream`]) reads instead of a [`Recording`]
//! held whole.
//!
//! A [`RecordSource`] knows the record's rate, length and channels before
//! its samples are read (a file source scans the file once to know them)
//! and hands the samples over in consecutive [`Block`]s, from the start,
//! each time [`RecordSource::pass`] is called.

use std::path::Path;

use super::{Channel, Metadata, Recording};
use crate::error::{Error, Result};

/// Consecutive samples of every channel of a record (equal lengths).
#[derive(Debug, Clone, Copy, Default)]
pub struct Block<'a> {
    /// Friction, N.
    pub friction_n: Option<&'a [f64]>,
    /// Position, mm.
    pub position_mm: Option<&'a [f64]>,
    /// Optical sensor, V.
    pub optical_v: Option<&'a [f64]>,
}

impl<'a> Block<'a> {
    /// Every sample of `rec`, as one block.
    pub fn of(rec: &'a Recording) -> Self {
        Block {
            friction_n: rec.channel(Channel::Friction),
            position_mm: rec.channel(Channel::Position),
            optical_v: rec.channel(Channel::Optical),
        }
    }

    /// The block of one channel, if the record has it.
    pub fn channel(&self, c: Channel) -> Option<&'a [f64]> {
        match c {
            Channel::Friction => self.friction_n,
            Channel::Position => self.position_mm,
            Channel::Optical => self.optical_v,
        }
    }

    /// Samples in the block.
    pub fn len(&self) -> usize {
        Channel::ALL
            .iter()
            .find_map(|&c| self.channel(c))
            .map_or(0, <[f64]>::len)
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A record that can be read block by block from its start, repeatedly.
pub trait RecordSource {
    /// Sampling rate, Hz.
    fn fs_hz(&self) -> f64;
    /// Samples per channel.
    fn len(&self) -> usize;
    /// No samples.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Channels present, in canonical order.
    fn channels(&self) -> Vec<Channel>;
    /// The record's metadata (source, test id, velocity, ...).
    fn meta(&self) -> &Metadata;
    /// Reads the whole record from its start, handing `f` consecutive
    /// blocks that together hold every sample once.
    ///
    /// # Errors
    /// A read or format error of the source, or the first error of `f`.
    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()>;

    /// The name used in messages and outputs.
    fn source_name(&self) -> String {
        super::source_name(self.meta())
    }
}

/// A [`Recording`] in memory handed over in blocks of a chosen size: the
/// streamed analysis of a record that is loaded anyway, and the tests'
/// way to compare the streamed analysis with the in-memory one.
#[derive(Debug, Clone, Copy)]
pub struct RecordingSource<'a> {
    rec: &'a Recording,
    block: usize,
}

impl<'a> RecordingSource<'a> {
    /// `rec` in blocks of `block` samples (at least 1).
    pub fn new(rec: &'a Recording, block: usize) -> Self {
        RecordingSource {
            rec,
            block: block.max(1),
        }
    }
}

impl RecordSource for RecordingSource<'_> {
    fn fs_hz(&self) -> f64 {
        self.rec.fs_hz()
    }

    fn len(&self) -> usize {
        self.rec.len()
    }

    fn channels(&self) -> Vec<Channel> {
        self.rec.channels()
    }

    fn meta(&self) -> &Metadata {
        &self.rec.meta
    }

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        let n = self.rec.len();
        let mut at = 0;
        while at < n {
            let to = (at + self.block).min(n);
            let cut = |c: Channel| self.rec.channel(c).map(|x| &x[at..to]);
            f(Block {
                friction_n: cut(Channel::Friction),
                position_mm: cut(Channel::Position),
                optical_v: cut(Channel::Optical),
            })?;
            at = to;
        }
        Ok(())
    }
}

/// The I/O error of reading `path` (the stream sources' reads).
pub(crate) fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Errors unless the file at `path` is still `size` bytes long, as when a
/// stream source opened it: a source reads its file again on every pass,
/// and a file changed in between would give a record of two files.
pub(crate) fn check_unchanged(path: &Path, size: u64) -> Result<()> {
    let now = std::fs::metadata(path)
        .map_err(|e| io_error(path, e))?
        .len();
    if now == size {
        return Ok(());
    }
    Err(Error::Format {
        path: path.to_path_buf(),
        reason: format!("the file changed while it was read ({now} bytes, {size} when opened)"),
    })
}

/// The samples of one [`RecordSource::pass`], one series per channel of
/// [`Channel::ALL`] (empty for a channel the record lacks).
///
/// # Errors
/// The pass's error.
pub fn collect(src: &mut dyn RecordSource) -> Result<Vec<Vec<f64>>> {
    let mut got: Vec<Vec<f64>> = vec![Vec::new(); Channel::ALL.len()];
    src.pass(&mut |b| {
        for (g, c) in got.iter_mut().zip(Channel::ALL) {
            g.extend_from_slice(b.channel(c).unwrap_or(&[]));
        }
        Ok(())
    })?;
    Ok(got)
}

/// Fuzzing's check that a file read in pieces (`opened`: the source, or
/// `None` when the file is read whole instead) gives what the whole-file
/// reader gives (`whole`): the same rate, length, channels and samples to
/// the bit, or an error from both. `Err` describes a disagreement; a file
/// declined agrees by definition.
pub fn check_agrees<S: RecordSource>(
    opened: Result<Option<S>>,
    whole: Result<Recording>,
) -> std::result::Result<(), String> {
    let mut src = match opened {
        Ok(Some(src)) => src,
        Ok(None) => return Ok(()),
        Err(e) => {
            return match whole {
                Ok(_) => Err(format!(
                    "the scan refused what the whole-file reader read: {e}"
                )),
                Err(_) => Ok(()),
            }
        }
    };
    let got = collect(&mut src);
    let (got, whole) = match (got, whole) {
        (Err(_), Err(_)) => return Ok(()),
        (Ok(_), Err(e)) => return Err(format!("streamed, but the whole-file reader refused: {e}")),
        (Err(e), Ok(_)) => {
            return Err(format!(
                "the whole-file reader read what a pass refused: {e}"
            ))
        }
        (Ok(g), Ok(w)) => (g, w),
    };
    if src.fs_hz().to_bits() != whole.fs_hz().to_bits() || src.len() != whole.len() {
        return Err(format!(
            "rate or length differ: {} Hz, {} samples streamed; {} Hz, {} whole",
            src.fs_hz(),
            src.len(),
            whole.fs_hz(),
            whole.len()
        ));
    }
    if src.channels() != whole.channels() {
        return Err("channels differ".into());
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (g, c) in got.iter().zip(Channel::ALL) {
        if bits(g) != bits(whole.channel(c).unwrap_or(&[])) {
            return Err(format!("{} samples differ", c.column_name()));
        }
    }
    Ok(())
}

/// The stream sources' tests' check: `src` has `whole`'s rate, length,
/// channels and metadata, and (twice, pass after pass) every sample of it
/// to the bit.
#[cfg(test)]
pub(crate) fn assert_streams_as(src: &mut dyn RecordSource, whole: &Recording, label: &str) {
    assert_eq!(src.fs_hz().to_bits(), whole.fs_hz().to_bits(), "{label}");
    assert_eq!(src.len(), whole.len(), "{label}");
    assert_eq!(src.channels(), whole.channels(), "{label}");
    assert_eq!(src.meta(), &whole.meta, "{label}");
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for _ in 0..2 {
        let got = collect(src).unwrap();
        for (g, c) in got.iter().zip(Channel::ALL) {
            let w = whole.channel(c).unwrap_or(&[]);
            assert!(bits(g) == bits(w), "{label} {c:?}");
        }
    }
}
