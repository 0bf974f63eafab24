//! A MATLAB v7.3 record as a [`RecordSource`]: its vectors read in ranges,
//! as many times as the streamed analysis needs, never held whole.
//!
//! [`open`] opens the HDF5 file on disk, reading only its metadata (the
//! variable tree of the whole-file reader, numeric data left unread), and
//! finds the channels as the whole-file reader does (`super::parse_file`:
//! plain variables, ControlDesk layouts, struct fields by path, a scalar
//! rate field), reading only the first block of each channel and of the
//! time. A time variable is then scanned in ranges (its steps checked as
//! `timebase::Steps` checks a column read in pieces, which gives the rate
//! of the whole column to the bit). The first block is finished as the
//! whole file is, which gives the channels, metadata and any error of
//! units or options.
//!
//! Each [`RecordSource::pass`] reads every channel in ranges of
//! [`BLOCK_SAMPLES`] through `hdf5-reader`'s hyperslab reads (contiguous,
//! compact and chunked datasets, deflate and shuffle filters), converts
//! them by the whole-file reader's own function (`H5Data::numbers_in`)
//! and finishes each block the same way, so every sample equals the
//! whole-file read to the bit.
//!
//! Declined (read whole, the reason said): a level-5 file (`-v6`/`-v7`),
//! a gap policy that fills or splits, a time variable whose steps are not
//! uniform (the whole-file reader reports or fills its gaps), a rate given
//! beside a time variable, vectors of different lengths (the whole-file
//! reader's error), a vector stored in chunks larger than
//! [`MAX_CHUNK_BYTES`] (each range would inflate a whole chunk again).
//!
//! A chunked vector's chunk index is checked whole at [`open`], as the
//! whole-file reader checks it (a range read sees only its own chunks);
//! `hdf5-reader` lists chunks only with their data, so this inflates each
//! chunk once more (found by the fuzz harness: a damaged index entry
//! outside every range read was refused whole and read streamed).

use std::fmt;
use std::io::Read;
use std::path::Path;

use super::tree::Data;
use super::v73::{H5Data, V73File};
use super::{format_err, is_v73, parse_file, File, Role};
use crate::error::{excerpt, Result};
use crate::recording::io::scanned::{
    first_block, piece_options, scanned_getters, stream_request, Scanned,
};
use crate::recording::io::{finish, timebase, LoadOptions, RawColumn};
use crate::recording::stream::{io_error, Block, RecordSource};
use crate::recording::{Channel, Metadata, Recording};

/// Samples per block handed to the analysis (and per range read).
pub const BLOCK_SAMPLES: usize = 1 << 18;

/// Largest chunk of a chunked vector read in ranges: 16 MiB, two million
/// doubles (MATLAB and h5py chunk far smaller).
pub const MAX_CHUNK_BYTES: usize = 16 << 20;

/// The chunk cache: a chunk of each of three channels and the time at the
/// largest chunk taken, so a chunk that straddles blocks is inflated once.
const CACHE_BYTES: usize = 4 * MAX_CHUNK_BYTES;

/// One channel: where it is read and its column as the file names it.
struct Lane {
    channel: Channel,
    data: H5Data,
    /// The column without values (name, unit).
    column: RawColumn,
}

/// A MATLAB v7.3 record read in ranges ([`open`]).
pub struct MatSource {
    scan: Scanned,
    /// Samples per block.
    block: usize,
    lanes: Vec<Lane>,
}

impl fmt::Debug for MatSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MatSource")
            .field("scan", &self.scan)
            .finish_non_exhaustive()
    }
}

/// Opens `path` (a MATLAB v7.3 file) for streaming: `Ok(Err(why))` when it
/// is read whole instead (module docs).
///
/// # Errors
/// [`Error::Io`](crate::Error::Io) when the file cannot be read; what the whole-file reader
/// says of a damaged file, a variable not found or bad options.
pub fn open(path: &Path, opts: &LoadOptions) -> Result<std::result::Result<MatSource, String>> {
    open_sized(path, opts, BLOCK_SAMPLES)
}

/// The first bytes of `path`, up to where a v7.3 file's HDF5 signature is.
fn head(path: &Path) -> Result<Vec<u8>> {
    let mut head = Vec::with_capacity(520);
    std::fs::File::open(path)
        .and_then(|f| f.take(520).read_to_end(&mut head))
        .map_err(|e| io_error(path, e))?;
    Ok(head)
}

/// [`open`] with the block size given (the tests use small ones).
pub(crate) fn open_sized(
    path: &Path,
    opts: &LoadOptions,
    block: usize,
) -> Result<std::result::Result<MatSource, String>> {
    let (file_path, opts) = match stream_request(path, opts)? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let opts = opts.as_ref();
    let block = block.max(Recording::MIN_SAMPLES);
    let size = std::fs::metadata(&file_path)
        .map_err(|e| io_error(&file_path, e))?
        .len();
    if !is_v73(&head(&file_path)?) {
        return Ok(Err(
            "only MATLAB v7.3 (HDF5) MAT-files are streamed; a level-5 file (-v6, -v7) is not"
                .into(),
        ));
    }
    let tree = V73File::open_path(&file_path, CACHE_BYTES)
        .map_err(|r| format_err(&file_path, format!("MATLAB v7.3 (HDF5) MAT-file: {r}")))?;
    let file = File::V73(tree);
    // The channels and time found as the whole-file reader finds them,
    // each read only for its first block.
    let mut found: Vec<(Role, H5Data, usize)> = Vec::new();
    let parsed = parse_file(
        &file_path,
        &file,
        opts,
        &mut |file, n, role| match (role, &n.data) {
            (Role::Rate, _) => file.numbers(n),
            (Role::Channel(_) | Role::Time, Data::H5(d)) => {
                let len = d.len()?;
                found.push((role, (**d).clone(), len));
                d.numbers_in(Some((0, first_block(len, block))))
            }
            (_, Data::V5(_)) => Err("level-5 data in a v7.3 file".into()),
        },
    );
    let len = found.first().map_or(0, |f| f.2);
    if found.iter().any(|f| f.2 != len) {
        // The whole-file reader's error, with the whole lengths.
        return Ok(Err(
            "its channels and time hold different numbers of values".into(),
        ));
    }
    let table = parsed?;
    let name_of = |role: Role| match role {
        Role::Channel(c) => table
            .channels
            .iter()
            .find(|(k, _)| *k == c)
            .map_or_else(String::new, |(_, col)| col.name.clone()),
        _ => table
            .time
            .as_ref()
            .map_or_else(String::new, |t| t.name.clone()),
    };
    for (role, d, _) in &found {
        if let Some(bytes) = d.chunk_bytes().filter(|&b| b > MAX_CHUNK_BYTES) {
            return Ok(Err(format!(
                "'{}' is stored in chunks of {:.0} MB, too large to read in pieces",
                name_of(*role),
                bytes as f64 / 1e6
            )));
        }
        // A damaged entry of the chunk index outside every range read
        // would go unseen: the whole-file reader's error instead.
        d.check_chunk_index().map_err(|r| {
            format_err(
                &file_path,
                format!("variable '{}' cannot be read: {r}", name_of(*role)),
            )
        })?;
    }
    let time = if opts.ignore_time {
        None
    } else {
        table.time.as_ref()
    };
    let base = match time {
        None => None,
        Some(t) => {
            if opts.fs_hz.is_some() || table.stated_rate.is_some() {
                return Ok(Err(format!(
                    "a rate is given beside its time '{}', which is checked against the whole \
                     column",
                    t.name
                )));
            }
            let Some((_, d, _)) = found.iter().find(|f| f.0 == Role::Time) else {
                return Ok(Err("its time is not a v7.3 dataset".into()));
            };
            let k = finish::time_unit(&file_path, &table, opts)?.seconds();
            let mut steps = timebase::Steps::default();
            let mut at = 0;
            while at < len && !steps.broken {
                let to = (at + block).min(len);
                let v = d.numbers_in(Some((at, to))).map_err(|r| {
                    format_err(
                        &file_path,
                        format!("variable '{}' cannot be read: {r}", t.name),
                    )
                })?;
                steps.extend(v.into_iter().map(|x| x * k));
                at = to;
            }
            match steps.uniform(t.resolution * k, opts.time_step_tolerance) {
                Some(base) => Some(base),
                None => {
                    return Ok(Err(format!(
                        "its time '{}' is not uniform (gaps and steps are checked on the whole \
                         column)",
                        excerpt(&t.name)
                    )))
                }
            }
        }
    };
    let lanes: Vec<Lane> = table
        .channels
        .iter()
        .filter_map(|(c, col)| {
            let (_, d, _) = found.iter().find(|f| f.0 == Role::Channel(*c))?;
            Some(Lane {
                channel: *c,
                data: d.clone(),
                column: RawColumn {
                    values: Vec::new(),
                    ..col.clone()
                },
            })
        })
        .collect();
    // The first block, finished as the whole file is: the channels and
    // metadata of the record, and any error of units or options.
    let first_opts = LoadOptions {
        velocity_mm_s: None,
        ..opts.clone()
    };
    let rec = finish::finish(&file_path, table, &first_opts)?
        .into_iter()
        .next()
        .ok_or_else(|| format_err(&file_path, "no samples"))?;
    let fs_hz = base.as_ref().map_or(rec.fs_hz(), |b| b.fs_hz);
    let mut meta = rec.meta.clone();
    meta.velocity_mm_s = opts.velocity_mm_s;
    Ok(Ok(MatSource {
        scan: Scanned {
            path: file_path,
            size,
            piece_opts: LoadOptions {
                fs_from: None,
                ..piece_options(opts, fs_hz)
            },
            start_time_s: meta.start_time_s,
            fs_hz,
            len,
            channels: rec.channels(),
            meta,
        },
        block,
        lanes,
    }))
}

impl MatSource {
    /// The file read.
    pub fn path(&self) -> &Path {
        self.scan.path()
    }
}

impl RecordSource for MatSource {
    scanned_getters!();

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        self.scan.unchanged()?;
        let (scan, lanes) = (&self.scan, &self.lanes);
        scan.blocks(
            self.block,
            &mut |at, n| {
                lanes
                    .iter()
                    .map(|lane| {
                        let values = lane.data.numbers_in(Some((at, at + n))).map_err(|r| {
                            format_err(
                                &scan.path,
                                format!("variable '{}' cannot be read: {r}", lane.column.name),
                            )
                        })?;
                        Ok((
                            lane.channel,
                            RawColumn {
                                values,
                                ..lane.column.clone()
                            },
                        ))
                    })
                    .collect()
            },
            f,
        )
    }
}

/// Fuzzing's check that a v7.3 file read in ranges ([`open`], blocks of 16
/// samples, so a fuzzed input's chunks are crossed many times) gives what
/// the whole-file reader gives (see
/// [`crate::recording::stream::check_agrees`]).
pub fn check_stream_agrees(path: &Path) -> std::result::Result<(), String> {
    let opts = LoadOptions::default();
    let whole = crate::recording::io::load(path, &opts);
    let opened = open_sized(path, &opts, 16).map(std::result::Result::ok);
    crate::recording::stream::check_agrees(opened, whole)
}

#[cfg(test)]
#[path = "stream_tests.rs"]
mod tests;
