//! A TDMS record as a [`RecordSource`]: its raw data read in pieces, as
//! many times as the streamed analysis needs, never held whole.
//!
//! [`open`] reads the file's segment lead-ins and metadata once, seeking
//! past the raw data (`segments::read` on the file), and keeps what the
//! whole-file reader keeps: each channel's runs (where its values lie).
//! It then finishes the first block of the record as the whole-file reader
//! finishes the file (the `Plan` of channels and timing, units, scales,
//! the rate stated or given), which gives the rate, channels and metadata.
//! Each [`RecordSource::pass`] reads every channel's runs through a window
//! of the file of bounded size, decodes and scales them by the same
//! functions as the whole-file reader and finishes each block the same
//! way, so every sample equals the whole-file read to the bit.
//!
//! A time channel is scanned in pieces at the open: every stamp finite,
//! every step positive, and the grid uniform within the tolerance of the
//! smallest step, which gives the same rate and start as the whole
//! column's check, to the bit. Declined (read whole, the reason said): a
//! time channel that needs more (gaps, jitter beyond that tolerance, a
//! rate stated or given beside it, which is checked against the whole
//! column), a gap policy that fills or splits,
//! channels of different lengths (the whole-file reader's error), DAQmx
//! scalers of different lengths.
//!

use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::segments::{Bytes, Object, Run, R, TY_DAQMX};
use super::values::{check_run, decode, scaled, scaling, Scaling};
use super::{channel_err, column, format_err, plan};
use crate::error::excerpt;
use crate::error::Result;
use crate::recording::io::scanned::{
    first_block, piece_options, scanned_getters, stream_request, Scanned,
};
use crate::recording::io::{
    finish, name_record, timebase, LoadOptions, Locator, RawTable, TimeUnit,
};
use crate::recording::stream::{io_error, Block, RecordSource};
use crate::recording::{Channel, Metadata, Recording};

/// Samples per block handed to the analysis.
pub const BLOCK_SAMPLES: usize = 1 << 18;
/// Bytes of the file read at once for one channel.
pub const WINDOW_BYTES: usize = 16 << 20;

/// A TDMS record read in pieces ([`open`]).
#[derive(Debug)]
pub struct TdmsSource {
    scan: Scanned,
    /// Samples per block, bytes per read window.
    sizes: (usize, usize),
    /// Each channel and the object it is read from.
    lanes: Vec<(Channel, Object)>,
}

/// Opens `path` (a TDMS file, or `FILE#GROUP`) for streaming: `Ok(Err(why))`
/// when it is read whole instead (module docs).
///
/// # Errors
/// [`Error::Io`](crate::Error::Io) when the file cannot be read; what the whole-file reader
/// says of a damaged file, a channel not found or bad options.
pub fn open(path: &Path, opts: &LoadOptions) -> Result<std::result::Result<TdmsSource, String>> {
    open_sized(path, opts, (BLOCK_SAMPLES, WINDOW_BYTES))
}

/// The file on disk as [`Bytes`] for the scan.
struct OnDisk<'a> {
    file: &'a mut File,
    size: usize,
    buf: Vec<u8>,
}

impl Bytes for OnDisk<'_> {
    fn size(&self) -> usize {
        self.size
    }
    fn get(&mut self, at: usize, n: usize) -> R<std::borrow::Cow<'_, [u8]>> {
        if at.checked_add(n).is_none_or(|e| e > self.size) {
            return Err(format!("bytes {at}..+{n} beyond the file"));
        }
        self.buf.resize(n, 0);
        read_at(self.file, at, &mut self.buf)?;
        Ok(std::borrow::Cow::Borrowed(&self.buf))
    }
}

fn read_at(file: &mut File, at: usize, buf: &mut [u8]) -> R<()> {
    file.seek(SeekFrom::Start(at as u64))
        .and_then(|_| file.read_exact(buf))
        .map_err(|e| format!("reading {} bytes at byte {at}: {e}", buf.len()))
}

/// [`open`] with the block and window sizes given (the tests use small ones).
pub(crate) fn open_sized(
    path: &Path,
    opts: &LoadOptions,
    sizes: (usize, usize),
) -> Result<std::result::Result<TdmsSource, String>> {
    let (file_path, opts) = match stream_request(path, opts)? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let opts = opts.as_ref();
    let sizes = (sizes.0.max(Recording::MIN_SAMPLES), sizes.1.max(64));
    let mut file = File::open(&file_path).map_err(|e| io_error(&file_path, e))?;
    let size = file.metadata().map_err(|e| io_error(&file_path, e))?.len();
    let size = usize::try_from(size).map_err(|_| format_err(&file_path, "file too large"))?;
    let t = super::read(
        &file_path,
        &mut OnDisk {
            file: &mut file,
            size,
            buf: Vec::new(),
        },
    )?;
    let plan = plan(&file_path, &t, opts)?;
    let mut lanes = Vec::with_capacity(plan.channels.len());
    for &(c, i) in &plan.channels {
        let o = t.objects[i].clone();
        let fail = |r: String| channel_err(&file_path, &o, &r);
        let s = scaling(&o, size).map_err(fail)?;
        for (_, run) in &o.runs {
            check_run(run, size).map_err(fail)?;
        }
        if o.ty == Some(TY_DAQMX) {
            let mut counts: HashMap<u32, usize> = HashMap::new();
            for (id, run) in &o.runs {
                *counts.entry(*id).or_default() += run.count * run.reps;
            }
            if counts.values().any(|&n| n != o.values) {
                return Ok(Err(format!(
                    "the DAQmx scalers of '{}' hold different numbers of values",
                    crate::error::excerpt(&o.label())
                )));
            }
            if s.is_none() && counts.len() != 1 {
                // The whole-file reader's error.
                return Err(fail(format!(
                    "DAQmx data with {} scalers and no scaling properties",
                    counts.len()
                )));
            }
        }
        lanes.push((c, o));
    }
    let len = lanes.first().map_or(0, |(_, o)| o.values);
    if lanes.iter().any(|(_, o)| o.values != len) {
        return Ok(Err("its channels hold different numbers of values".into()));
    }
    // A time channel: its steps scanned in pieces.
    let timed = match plan.time {
        None => None,
        Some(i) => {
            let o = &t.objects[i];
            let why = |what: &str| {
                Ok(Err(format!(
                    "its time channel ('{}') {what}, which is checked on the whole column",
                    crate::error::excerpt(&o.label())
                )))
            };
            if plan.stated_rate.is_some() || opts.fs_hz.is_some() {
                return why("comes with a rate stated or given");
            }
            if o.values != len {
                return why("holds a different number of values from the channels");
            }
            match scan_time(&file_path, &mut file, o, sizes, size, opts) {
                Some(base) => Some(base),
                None => {
                    return why(
                        "does not step uniformly within the tolerance from its smallest step \
                         (a gap, jitter or a bad stamp)",
                    )
                }
            }
        }
    };
    // The first block, finished as the whole file is: the rate, channels
    // and metadata of the record, and any error of units or options.
    let first_opts = LoadOptions {
        velocity_mm_s: None,
        // The rate the time channel's scan found (its steps checked).
        fs_hz: timed.as_ref().map_or(opts.fs_hz, |b| Some(b.0.fs_hz)),
        ..opts.clone()
    };
    let first = first_block(len, sizes.0);
    let mut readers = readers(&file_path, &lanes, (sizes.1, size))?;
    let columns = read_block(&file_path, &mut file, &lanes, &mut readers, first)?;
    let table = RawTable {
        channels: columns,
        locator: Locator::Samples,
        stated_rate: plan.stated_rate,
        start_time_s: plan.start_time_s,
        notes: t.notes,
        ..RawTable::default()
    };
    let rec = finish::finish(&file_path, table, &first_opts)?
        .into_iter()
        .next()
        .ok_or_else(|| format_err(&file_path, "no samples"))?;
    let mut meta = rec.meta.clone();
    meta.velocity_mm_s = opts.velocity_mm_s;
    if let Some((base, note)) = &timed {
        // As the whole-file reader places a record with a time column.
        meta.start_time_s = base.start_time_s;
        meta.notes.extend(note.clone());
    }
    name_record(path, &mut meta, opts);
    Ok(Ok(TdmsSource {
        scan: Scanned {
            path: file_path,
            size: size as u64,
            piece_opts: piece_options(opts, rec.fs_hz()),
            start_time_s: meta.start_time_s,
            fs_hz: rec.fs_hz(),
            len,
            channels: rec.channels(),
            meta,
        },
        sizes,
        lanes,
    }))
}

/// The time channel `o` scanned in pieces of `block` values through a
/// window of `cap` bytes: its steps as the whole-file reader checks them
/// (every stamp finite, every step positive, the grid uniform within the
/// tolerance of the smallest step: [`timebase::uniform`], which gives the
/// rate and start [`timebase::derive`] gives the whole column, to the
/// bit), with the note the whole-file reader adds for a unit other than
/// seconds. `None` for anything else (the whole-file reader then reads it
/// and reports or repairs what it finds).
fn scan_time(
    path: &Path,
    file: &mut File,
    o: &Object,
    (block, cap): (usize, usize),
    size: usize,
    opts: &LoadOptions,
) -> Option<(timebase::Timebase, Option<String>)> {
    // One lane of the readers' kind; its channel label is not used here.
    let lane = [(Channel::Position, o.clone())];
    let mut rd = readers(path, &lane, (cap, size)).ok()?;
    // TDMS states no time unit: the option's, else seconds.
    let unit = finish::time_unit(path, &RawTable::default(), opts).ok()?;
    let k = unit.seconds();
    let mut steps = timebase::Steps::default();
    let mut at = 0;
    while at < o.values && !steps.broken {
        let take = block.min(o.values - at);
        let mut col = read_block(path, file, &lane, &mut rd, take).ok()?;
        let (_, col) = col.pop()?;
        if unit == TimeUnit::S {
            steps.extend(col.values);
        } else {
            steps.extend(col.values.into_iter().map(|v| v * k));
        }
        at += take;
    }
    if steps.n < 2 {
        return None;
    }
    let base = steps.uniform(0.0, opts.time_step_tolerance)?;
    let note = (unit != TimeUnit::S)
        .then(|| format!("time '{}' read in {}", excerpt(&o.label()), unit.symbol()));
    Some((base, note))
}

/// Where one series (a channel's values, or a DAQmx scaler's) is read.
struct Series {
    id: u32,
    runs: Vec<Run>,
    /// Run, repetition and value within it of the next value.
    at: (usize, usize, usize),
    /// Bytes of the file from `window.0`.
    window: (usize, Vec<u8>),
    cap: usize,
    /// The file's length.
    size: usize,
}

impl Series {
    /// Appends the next `n` values to `out`.
    fn next(
        &mut self,
        file: &mut File,
        n: usize,
        out: &mut Vec<f64>,
        t0: &mut Option<(i64, u64)>,
    ) -> R<()> {
        let mut need = n;
        while need > 0 {
            let (r, rep, i) = self.at;
            let run = *self
                .runs
                .get(r)
                .ok_or("fewer values in the file than its indexes count")?;
            if run.count == 0 || run.reps == 0 {
                self.at = (r + 1, 0, 0);
                continue;
            }
            let size = check_run(&run, usize::MAX)?;
            // Values whose bytes fit the window (at least one).
            let fit = (self.cap.saturating_sub(size) / run.stride.max(1)).saturating_add(1);
            let take = need.min(run.count - i).min(fit);
            let from = run.offset + rep * run.rep_stride + i * run.stride;
            let span = (take - 1) * run.stride + size;
            let (w0, w) = &self.window;
            if from < *w0 || from + span > w0 + w.len() {
                let len = self.cap.min(self.size.saturating_sub(from));
                self.window.0 = from;
                self.window.1.resize(len.max(span), 0);
                read_at(file, from, &mut self.window.1)?;
            }
            let piece = Run {
                offset: from - self.window.0,
                count: take,
                reps: 1,
                rep_stride: 0,
                ..run
            };
            decode(&self.window.1, &piece, out, t0)?;
            need -= take;
            self.at = if i + take < run.count {
                (r, rep, i + take)
            } else if rep + 1 < run.reps {
                (r, rep + 1, 0)
            } else {
                (r + 1, 0, 0)
            };
        }
        Ok(())
    }
}

/// What reads one channel: its series, scaling and first time stamp.
struct Reader {
    series: Vec<Series>,
    scaling: Option<Scaling>,
    daqmx: bool,
    t0: Option<(i64, u64)>,
}

fn readers(
    path: &Path,
    lanes: &[(Channel, Object)],
    (cap, size): (usize, usize),
) -> Result<Vec<Reader>> {
    lanes
        .iter()
        .map(|(_, o)| {
            let mut series: Vec<Series> = Vec::new();
            for &(id, run) in &o.runs {
                match series.iter_mut().find(|s| s.id == id) {
                    Some(s) => s.runs.push(run),
                    None => series.push(Series {
                        id,
                        runs: vec![run],
                        at: (0, 0, 0),
                        window: (0, Vec::new()),
                        cap,
                        size,
                    }),
                }
            }
            Ok(Reader {
                series,
                // Checked at the scan: the same scaling every pass.
                scaling: scaling(o, size).map_err(|r| channel_err(path, o, &r))?,
                daqmx: o.ty == Some(TY_DAQMX),
                t0: None,
            })
        })
        .collect()
}

/// The next `n` values of every channel as raw columns (scaled by NI
/// scaling, as the whole-file reader's columns are).
fn read_block(
    path: &Path,
    file: &mut File,
    lanes: &[(Channel, Object)],
    readers: &mut [Reader],
    n: usize,
) -> Result<Vec<(Channel, crate::recording::io::RawColumn)>> {
    let mut out = Vec::with_capacity(lanes.len());
    for ((c, o), rd) in lanes.iter().zip(readers.iter_mut()) {
        let fail = |r: String| channel_err(path, o, &r);
        let mut raw = Vec::new();
        let mut series = HashMap::new();
        for s in &mut rd.series {
            let mut v = Vec::with_capacity(n);
            s.next(file, n, &mut v, &mut rd.t0).map_err(fail)?;
            if rd.daqmx {
                series.insert(s.id, v);
            } else {
                raw.extend(v);
            }
        }
        let values = scaled(rd.scaling.as_ref(), rd.daqmx, raw, series).map_err(fail)?;
        out.push((*c, column(o, values)));
    }
    Ok(out)
}

impl TdmsSource {
    /// The file read.
    pub fn path(&self) -> &Path {
        self.scan.path()
    }
}

impl RecordSource for TdmsSource {
    scanned_getters!();

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        self.scan.unchanged()?;
        let (scan, lanes) = (&self.scan, &self.lanes);
        let path = scan.path();
        let mut file = File::open(path).map_err(|e| io_error(path, e))?;
        let window = (self.sizes.1, scan.size as usize);
        let mut readers = readers(path, lanes, window)?;
        scan.blocks(
            self.sizes.0,
            &mut |_, n| read_block(path, &mut file, lanes, &mut readers, n),
            f,
        )
    }
}

/// Fuzzing's check that a TDMS file read in pieces ([`open`], blocks of 16
/// samples through windows of 64 bytes, so a fuzzed input is cut many
/// times) gives what the whole-file reader gives (see
/// [`crate::recording::stream::check_agrees`]).
pub fn check_stream_agrees(path: &Path) -> std::result::Result<(), String> {
    let opts = LoadOptions::default();
    let whole = crate::recording::io::load(path, &opts);
    let opened = open_sized(path, &opts, (16, 64)).map(std::result::Result::ok);
    crate::recording::stream::check_agrees(opened, whole)
}

#[cfg(test)]
#[path = "stream_tests.rs"]
mod tests;
