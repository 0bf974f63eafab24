//! A record read block by block, any number of times: what the streamed
//! analysis ([`crate::analysis::stream`]) reads instead of a [`Recording`]
//! held whole.
//!
//! A [`RecordSource`] knows the record's rate, length and channels before
//! its samples are read (a file source scans the file once to know them)
//! and hands the samples over in consecutive [`Block`]s, from the start,
//! each time [`RecordSource::pass`] is called.

use super::{Channel, Metadata, Recording};
use crate::error::Result;

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
