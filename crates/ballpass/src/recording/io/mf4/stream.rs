//! An MF4 record as a [`RecordSource`]: its data read in pieces, as many
//! times as the streamed analysis needs, never held whole.
//!
//! [`open`] opens the file through a reader that reads only what it is
//! asked for (`falcon_mdf` over a file handle, not the file's bytes): the
//! blocks of metadata (data and channel groups, channels, conversions, the
//! list of data blocks), mapped onto the record's channels as the
//! whole-file reader maps them. It then reads the master time channel once,
//! in bounded windows, keeping its first and last stamps and its smallest
//! and largest step: the uniform-grid check of
//! `timebase::derive` when every step is
//! within the tolerance of the smallest, which gives the same rate to the
//! bit, and the check of a given rate against it. Each
//! [`RecordSource::pass`] reads the channels' records in bounded windows
//! (`falcon_mdf`'s aligned chunks: at most one data block inflated, or
//! 4 MB of an uncompressed one, plus one block of samples), decodes them
//! by the same code as the whole-file reader (the crate's conversions and
//! invalidation bits, then `values`) and finishes each
//! block as the whole-file reader finishes the file, so every sample
//! equals the whole-file read to the bit.
//!
//! Declined (read whole, the reason said): a time channel whose steps are
//! not all within the tolerance of the smallest (they are judged against
//! the median, which needs the whole column) or not increasing, a gap
//! policy that fills or splits, channels from several channel groups
//! (their time axes are compared whole), an unsorted data group (its
//! records are indexed whole when the file is opened), virtual,
//! variable-length or array channels (their values depend on more than a
//! window's records), and compressed data blocks that inflate past
//! [`MAX_INFLATED_BYTES`].

use std::path::Path;
use std::sync::Arc;

use falcon_mdf::blocks::ChannelType;
use falcon_mdf::io::reader::BufferedSource;
use falcon_mdf::stream::SignalsChunks;
use falcon_mdf::Mf4File;

use super::{check_magic, format_err, mdf, open_options, time_unit, values, Mapping, R};
use crate::error::{excerpt, shown_path, Error, Result};
use crate::recording::io::scanned::{
    first_block, piece_options, scanned_getters, stream_request, Scanned,
};
use crate::recording::io::timebase::{self, TimeError};
use crate::recording::io::{
    finish, name_record, LoadOptions, Locator, RawColumn, RawTable, TimeUnit,
};
use crate::recording::stream::{io_error, Block, RecordSource};
use crate::recording::{Channel, Metadata, Recording};

/// Samples per block handed to the analysis (and per window of records).
pub const BLOCK_SAMPLES: usize = 1 << 18;
/// Largest compressed data block streamed (it is inflated whole), bytes
/// inflated: 64 MiB, sixteen times what asammdf and CANape write.
pub const MAX_INFLATED_BYTES: u64 = 64 << 20;

/// An MF4 record read in pieces ([`open`]).
pub struct Mf4Source {
    scan: Scanned,
    /// The file's metadata and handle (boxed: it is large).
    file: Box<Mf4File>,
    /// Samples per block.
    block: usize,
    /// The file's channels read, distinct, in the order of `lanes`' firsts.
    read: Vec<falcon_mdf::Channel>,
    /// Each channel of the record, the index in `read` of the file's
    /// channel it is read from, and that column's name and unit.
    lanes: Vec<(Channel, usize, RawColumn)>,
}

impl std::fmt::Debug for Mf4Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mf4Source")
            .field("scan", &self.scan)
            .finish_non_exhaustive()
    }
}

/// Opens `path` (an MF4 file) for streaming: `Ok(Err(why))` when it is
/// read whole instead (module docs).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; what the whole-file reader
/// says of a damaged file, a channel not found, a bad time channel unit,
/// a given rate the time channel contradicts, or bad options.
pub fn open(path: &Path, opts: &LoadOptions) -> Result<std::result::Result<Mf4Source, String>> {
    open_sized(path, opts, BLOCK_SAMPLES)
}

/// The file opened for reads of what is asked for only, and its length.
fn open_file(path: &Path) -> Result<(Mf4File, u64)> {
    use std::io::Read;
    let mut head = Vec::with_capacity(8);
    std::fs::File::open(path)
        .and_then(|f| f.take(8).read_to_end(&mut head))
        .map_err(|e| io_error(path, e))?;
    check_magic(path, &head)?;
    let size = std::fs::metadata(path)
        .map_err(|e| io_error(path, e))?
        .len();
    let len = usize::try_from(size).map_err(|_| format_err(path, "file too large"))?;
    let source = BufferedSource::open(path).map_err(|e| format_err(path, e.to_string()))?;
    let file = mdf("damaged MDF file", || {
        Mf4File::from_source_with_options(Arc::new(source), open_options(len))
    })
    .map_err(|r| format_err(path, r))?;
    Ok((file, size))
}

/// What the time channel's scan found (its values in seconds).
struct Steps {
    n: usize,
    first: f64,
    last: f64,
    dmin: f64,
    dmax: f64,
    /// A value not finite, or a step not positive: the sample.
    broken: Option<usize>,
}

impl Steps {
    fn push(&mut self, v: f64) {
        if self.broken.is_some() {
            return;
        }
        if !v.is_finite() {
            self.broken = Some(self.n);
            return;
        }
        if self.n > 0 {
            let d = v - self.last;
            if d <= 0.0 {
                self.broken = Some(self.n);
                return;
            }
            self.dmin = self.dmin.min(d);
            self.dmax = self.dmax.max(d);
        } else {
            self.first = v;
        }
        self.last = v;
        self.n += 1;
    }
}

/// [`open`] with the block size given (the tests use small ones).
pub(crate) fn open_sized(
    path: &Path,
    opts: &LoadOptions,
    block: usize,
) -> Result<std::result::Result<Mf4Source, String>> {
    let (file_path, opts) = match stream_request(path, opts)? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let opts = opts.as_ref();
    let block = block.max(Recording::MIN_SAMPLES);
    let p = file_path.as_path();
    let (file, size) = open_file(p)?;
    let map = Mapping::new(p, &file, opts)?;
    if let Some(k) = map.other_groups().next() {
        return Ok(Err(format!(
            "channels '{}' and '{}' are in different channel groups, whose time axes are \
             compared whole",
            map.label(map.used[0].1),
            map.label(k)
        )));
    }
    let time_k = map.time_item(p, &file, opts)?;
    let first = map.first();
    let group = (first.dg, first.cg);
    if let Some(k) = time_k {
        let it = &map.items[k];
        if (it.dg, it.cg) != group {
            return Ok(Err(format!(
                "the time channel '{}' is in another channel group than the channels",
                map.label(k)
            )));
        }
    }
    let dg = &file.data_groups()[group.0];
    if dg.is_unsorted() {
        return Ok(Err(
            "its data group holds the records of several channel groups interleaved, which \
             are indexed whole"
                .into(),
        ));
    }
    if let Some(b) = dg.block_index().blocks().iter().find(|b| {
        (b.compression.is_some() || b.invalidation_block.is_some())
            && b.original_size > MAX_INFLATED_BYTES
    }) {
        return Ok(Err(format!(
            "a compressed data block of {} MB, which is inflated whole",
            b.original_size >> 20
        )));
    }
    // The file's channels read (distinct), and the time's.
    let mut read_k: Vec<usize> = Vec::new();
    let mut lanes = Vec::with_capacity(map.used.len());
    for &(c, k) in &map.used {
        let i = read_k.iter().position(|&j| j == k).unwrap_or_else(|| {
            read_k.push(k);
            read_k.len() - 1
        });
        lanes.push((c, i, map.column(&file, k, Vec::new())));
    }
    for k in read_k.iter().copied().chain(time_k) {
        let c = map.channel(&file, k);
        let plain = matches!(
            c.channel_type,
            ChannelType::FixedLength | ChannelType::Master
        );
        if !plain || c.array_shape.is_some() {
            return Ok(Err(format!(
                "channel '{}' is {}, whose values depend on more than a window of records",
                map.label(k),
                if plain {
                    "an array".to_string()
                } else {
                    format!("{:?}", c.channel_type)
                }
            )));
        }
    }
    let len = usize::try_from(dg.channel_groups[group.1].sample_count)
        .map_err(|_| format_err(p, "sample count beyond this machine's memory"))?;
    let read: Vec<falcon_mdf::Channel> = read_k
        .iter()
        .map(|&k| map.channel(&file, k).clone())
        .collect();
    // The time channel: its unit, its scan, the rate.
    let mut notes = Vec::new();
    let mut timed = None;
    if let Some(k) = time_k {
        let mut col = map.column(&file, k, Vec::new());
        let table = RawTable {
            time_unit: time_unit(p, &mut col, opts)?,
            ..RawTable::default()
        };
        let unit = finish::time_unit(p, &table, opts)?;
        if unit != TimeUnit::S {
            notes.push(format!("time '{}' read in {}", col.name, unit.symbol()));
        }
        let fail = |r: String| format_err(p, format!("channel '{}': {r}", col.name));
        let steps = scan_time(&file, map.channel(&file, k), unit, len).map_err(fail)?;
        if let Some(i) = steps.broken {
            return Ok(Err(format!(
                "its time channel '{}' does not increase by finite steps at sample {}",
                col.name,
                i + 1
            )));
        }
        let Some(base) = timebase::uniform(
            steps.first,
            steps.last,
            steps.n,
            (steps.dmin, steps.dmax),
            0.0,
            opts.time_step_tolerance,
        ) else {
            return Ok(Err(format!(
                "the steps of its time channel '{}' are not all within the tolerance of the \
                 smallest: they are judged against the median step, on the whole column",
                col.name
            )));
        };
        let fs = match opts.fs_hz {
            // The whole-file check: the span and the largest magnitude of an
            // increasing column are its ends'.
            Some(fs) => {
                timebase::check_given_rate(&[steps.first, steps.last], 0.0, fs, steps.n - 1)
                    .map_err(|e: TimeError| {
                        Error::setting(
                            "fs",
                            format!("{}: {} (time '{}')", shown_path(p), e.reason, col.name),
                        )
                    })?;
                fs
            }
            None => base.fs_hz,
        };
        timed = Some((fs, base.start_time_s));
    }
    // The first block, finished as the whole file is: the rate (without a
    // time channel), channels and metadata, and any error of units or
    // options.
    let first_opts = match timed {
        Some((fs, _)) => piece_options(opts, fs),
        None => LoadOptions {
            velocity_mm_s: None,
            ..opts.clone()
        },
    };
    let n = first_block(len, block);
    let mut chunks = Chunks::new(&file, &read, block, len).map_err(|r| format_err(p, r))?;
    let values = chunks.next(n).map_err(|r| format_err(p, r))?;
    let table = RawTable {
        channels: columns(&lanes, values),
        locator: Locator::Samples,
        start_time_s: timed.map(|(_, t0)| t0),
        ..RawTable::default()
    };
    drop(chunks);
    let rec = finish::finish(p, table, &first_opts)?
        .into_iter()
        .next()
        .ok_or_else(|| format_err(p, "no samples"))?;
    let mut meta = rec.meta.clone();
    notes.append(&mut meta.notes);
    meta.notes = notes;
    meta.velocity_mm_s = opts.velocity_mm_s;
    name_record(path, &mut meta, opts);
    let fs_hz = rec.fs_hz();
    Ok(Ok(Mf4Source {
        scan: Scanned {
            path: file_path.clone(),
            size,
            piece_opts: piece_options(opts, fs_hz),
            start_time_s: meta.start_time_s,
            fs_hz,
            len,
            channels: rec.channels(),
            meta,
        },
        file: Box::new(file),
        block,
        read,
        lanes,
    }))
}

/// Reads the time channel in windows: its steps, in seconds (each value
/// times the unit's seconds, as the whole-file reader scales it).
fn scan_time(file: &Mf4File, time: &falcon_mdf::Channel, unit: TimeUnit, len: usize) -> R<Steps> {
    let mut steps = Steps {
        n: 0,
        first: 0.0,
        last: 0.0,
        dmin: f64::INFINITY,
        dmax: f64::NEG_INFINITY,
        broken: None,
    };
    let k = unit.seconds();
    let mut chunks = Chunks::new(file, std::slice::from_ref(time), BLOCK_SAMPLES, len)?;
    let mut left = len;
    while left > 0 {
        let n = left.min(BLOCK_SAMPLES);
        for v in chunks.next(n)?.swap_remove(0) {
            steps.push(if unit == TimeUnit::S { v } else { v * k });
        }
        left -= n;
    }
    Ok(steps)
}

/// The channels of one group read together, a window of records at a
/// time, handed out in blocks of any size.
struct Chunks<'f> {
    it: SignalsChunks<'f>,
    /// Values decoded and not yet handed out, per channel.
    pending: Vec<Vec<f64>>,
    names: Vec<String>,
    /// Samples decoded so far, and the group's sample count.
    decoded: usize,
    len: usize,
}

impl<'f> Chunks<'f> {
    fn new(file: &'f Mf4File, chans: &[falcon_mdf::Channel], window: usize, len: usize) -> R<Self> {
        Ok(Chunks {
            it: mdf("reading", || file.signals_chunks(chans, window))?,
            pending: vec![Vec::new(); chans.len()],
            names: chans.iter().map(|c| excerpt(&c.name)).collect(),
            decoded: 0,
            len,
        })
    }

    /// The next `n` values of every channel.
    fn next(&mut self, n: usize) -> R<Vec<Vec<f64>>> {
        while self.pending.first().is_some_and(|p| p.len() < n) {
            let it = &mut self.it;
            let Some(signals) = mdf("reading", || it.next().transpose())? else {
                return Err(format!(
                    "channel '{}': {} values decoded of the {} its group declares (truncated \
                     or damaged data)",
                    self.names[0], self.decoded, self.len
                ));
            };
            if signals.len() != self.pending.len() {
                return Err("a window of records did not hold every channel".into());
            }
            let count = signals[0].len();
            for ((p, s), name) in self.pending.iter_mut().zip(&signals).zip(&self.names) {
                let v = values(s, count as u64).map_err(|r| format!("channel '{name}': {r}"))?;
                p.extend(v);
            }
            self.decoded += count;
        }
        Ok(self
            .pending
            .iter_mut()
            .map(|p| {
                let rest = p.split_off(n.min(p.len()));
                std::mem::replace(p, rest)
            })
            .collect())
    }
}

/// The record's raw columns from the values of the channels read.
fn columns(
    lanes: &[(Channel, usize, RawColumn)],
    values: Vec<Vec<f64>>,
) -> Vec<(Channel, RawColumn)> {
    let mut values: Vec<Option<Vec<f64>>> = values.into_iter().map(Some).collect();
    let uses = |i: usize| lanes.iter().filter(|(_, j, _)| *j == i).count();
    let mut seen = vec![0usize; values.len()];
    lanes
        .iter()
        .map(|(c, i, col)| {
            seen[*i] += 1;
            // Moved out by the last channel that reads it, else copied.
            let v = if seen[*i] == uses(*i) {
                values[*i].take().unwrap_or_default()
            } else {
                values[*i].clone().unwrap_or_default()
            };
            (
                *c,
                RawColumn {
                    values: v,
                    ..col.clone()
                },
            )
        })
        .collect()
}

impl Mf4Source {
    /// The file read.
    pub fn path(&self) -> &Path {
        self.scan.path()
    }
}

impl RecordSource for Mf4Source {
    scanned_getters!();

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        self.scan.unchanged()?;
        let scan = &self.scan;
        let mut chunks = Chunks::new(&self.file, &self.read, self.block, scan.len)
            .map_err(|r| format_err(&scan.path, r))?;
        let lanes = &self.lanes;
        scan.blocks(
            self.block,
            &mut |_, n| {
                let values = chunks.next(n).map_err(|r| format_err(&scan.path, r))?;
                Ok(columns(lanes, values))
            },
            f,
        )
    }
}

/// Fuzzing's check that an MF4 file read in pieces ([`open`], blocks of
/// 16 samples, so that a fuzzed input is cut many times) gives what the
/// whole-file reader gives (see [`crate::recording::stream::check_agrees`]).
pub fn check_stream_agrees(path: &Path) -> std::result::Result<(), String> {
    let opts = LoadOptions::default();
    let whole = crate::recording::io::load(path, &opts);
    let opened = open_sized(path, &opts, 16).map(std::result::Result::ok);
    crate::recording::stream::check_agrees(opened, whole)
}

#[cfg(test)]
#[path = "stream_tests.rs"]
mod tests;
