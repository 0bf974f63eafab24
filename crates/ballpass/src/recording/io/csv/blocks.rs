//! A long text recording as a [`RecordSource`]: read in pieces, as many
//! times as the streamed analysis needs, never held whole.
//!
//! [`open`] scans the file once: its header, its rows in pieces (the fast
//! path of `super::stream`), the time column's steps (the uniform-grid
//! check of [`timebase::derive`], from the first and last stamps and the
//! smallest and largest step, which gives the same rate to the bit), and
//! that every channel value is finite. Each [`RecordSource::pass`] then
//! reads the pieces again and makes each one a recording exactly as the
//! whole-file reader makes the file one (`finish`: units, scales and
//! offsets, range checks, errors naming the line), at the scanned rate.
//!
//! A file the scan does not take — anything the fast path declines, a
//! time column with gaps or uneven steps, a missing value, no time column,
//! a given or stated rate, a record name — gives `None`: it is read whole,
//! where it is reported, filled or split as the options say.
//!

use std::path::{Path, PathBuf};

use super::stream::{for_each_piece, HEAD_BYTES, PIECE_BYTES};
use super::{table, Header, Plan};
use crate::error::{Error, Result};
use crate::recording::io::scanned::piece_options;
use crate::recording::io::{finish, timebase, Format, LoadOptions};
use crate::recording::stream::{Block, RecordSource};
use crate::recording::{Channel, Metadata};

/// A text recording read in pieces ([`open`]).
#[derive(Debug)]
pub struct CsvSource {
    path: PathBuf,
    format: Format,
    /// The options each piece is finished with: the scanned rate given,
    /// the time column already checked.
    piece_opts: LoadOptions,
    header: Header,
    sizes: (usize, usize),
    fs_hz: f64,
    len: usize,
    channels: Vec<Channel>,
    meta: Metadata,
}

/// Opens `path` for streaming when it is a plain CSV/TSV the scan takes
/// (module docs); `Ok(None)` otherwise.
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; a unit or option error of
/// the first piece, as the whole-file reader reports it.
pub fn open(path: &Path, opts: &LoadOptions) -> Result<Option<CsvSource>> {
    open_sized(path, opts, (HEAD_BYTES, PIECE_BYTES))
}

/// [`open`] with the head and piece sizes given (the tests use small ones).
pub(crate) fn open_sized(
    path: &Path,
    opts: &LoadOptions,
    sizes: (usize, usize),
) -> Result<Option<CsvSource>> {
    let format = opts.format.unwrap_or_else(|| Format::from_path(path));
    let plain_options = opts.fs_hz.is_none()
        && opts.fs_from.is_none()
        && !opts.ignore_time
        && opts.record.is_none()
        && opts.gaps.refuses();
    if !matches!(format, Format::Csv | Format::Tsv) || !plain_options {
        return Ok(None);
    }
    let mut steps = timebase::Steps::default();
    let mut resolution = f64::INFINITY;
    let mut finite = true;
    let mut first_piece: Option<(Vec<Channel>, Metadata)> = None;
    let mut has_time = true;
    let got = for_each_piece(path, format, opts, sizes, &mut |header, plan, rows, _| {
        if !finite || steps.broken {
            return Ok(());
        }
        finite &= rows
            .channels
            .iter()
            .all(|c| c.iter().all(|v| v.is_finite()));
        let t = table(path, header, plan, rows, opts)?;
        let Some(time) = &t.time else {
            has_time = false;
            return Ok(());
        };
        let k = finish::time_unit(path, &t, opts)?.seconds();
        resolution = resolution.min(time.resolution * k);
        steps.extend(time.values.iter().map(|&raw| raw * k));
        if first_piece.is_none() {
            // The channels and metadata as the whole-file reader gives them.
            let recs = finish::finish(path, t, &piece_options(opts, 1.0))?;
            if let Some(r) = recs.first() {
                first_piece = Some((r.channels(), r.meta.clone()));
            }
        }
        Ok(())
    })?;
    let (Some((header, _)), true, true, false, Some((channels, mut meta))) =
        (got, finite, has_time, steps.broken, first_piece)
    else {
        return Ok(None);
    };
    let Some(base) = steps.uniform(
        if resolution.is_finite() {
            resolution
        } else {
            0.0
        },
        opts.time_step_tolerance,
    ) else {
        return Ok(None);
    };
    meta.start_time_s = base.start_time_s;
    Ok(Some(CsvSource {
        path: path.to_path_buf(),
        format,
        piece_opts: piece_options(opts, base.fs_hz),
        header,
        sizes,
        fs_hz: base.fs_hz,
        len: steps.n,
        channels,
        meta,
    }))
}

impl CsvSource {
    /// The file read.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl RecordSource for CsvSource {
    fn fs_hz(&self) -> f64 {
        self.fs_hz
    }

    fn len(&self) -> usize {
        self.len
    }

    fn channels(&self) -> Vec<Channel> {
        self.channels.clone()
    }

    fn meta(&self) -> &Metadata {
        &self.meta
    }

    fn pass(&mut self, f: &mut dyn FnMut(Block<'_>) -> Result<()>) -> Result<()> {
        let path = self.path.clone();
        let opts = &self.piece_opts;
        let header = &self.header;
        let got = for_each_piece(
            &path,
            self.format,
            opts,
            self.sizes,
            &mut |_, plan: &Plan, rows, _| {
                if rows.lines.is_empty() {
                    return Ok(());
                }
                let t = table(&path, header, plan, rows, opts)?;
                for rec in finish::finish(&path, t, opts)? {
                    f(Block::of(&rec))?;
                }
                Ok(())
            },
        )?;
        if got.is_none() {
            return Err(Error::Format {
                path: path.clone(),
                reason: "the file changed while it was read (a piece no longer parses)".into(),
            });
        }
        Ok(())
    }
}

/// Fuzzing's check that a text file read in pieces ([`open`], with pieces
/// of 1 kB so that a fuzzed input is cut several times, after a head of
/// 4 kB, the whole-file reader's window for telling binary files) gives
/// what the whole-file reader gives: the same rate, length, channels and
/// samples to the bit, or an error from both. `Err` describes a
/// disagreement. A file [`open`] declines is the whole-file reader's alone
/// and agrees by definition.
pub fn check_stream_agrees(path: &Path) -> std::result::Result<(), String> {
    let opts = LoadOptions::default();
    let whole = crate::recording::io::load(path, &opts);
    crate::recording::stream::check_agrees(open_sized(path, &opts, (4096, 1024)), whole)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::io::{load, write_csv};
    use crate::recording::Recording;

    fn scratch(test: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("ballpass-blocks-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn record() -> Recording {
        crate::sim::simulate(&crate::sim::SimSettings {
            velocity_mm_s: 9.0,
            duration_s: 6.0,
            seed: 4,
            ..Default::default()
        })
        .unwrap()
        .recording
    }

    /// Read in pieces of a few kB, the blocks hold the whole-file reader's
    /// samples to the bit, at its rate.
    #[test]
    fn blocks_hold_what_the_whole_file_reader_reads() {
        let dir = scratch("same");
        let p = dir.join("rec.csv");
        write_csv(&record(), &p).unwrap();
        let opts = LoadOptions::default();
        let whole = load(&p, &opts).unwrap();
        let mut src = open_sized(&p, &opts, (3000, 4096))
            .unwrap()
            .expect("streams");
        assert_eq!((src.fs_hz(), src.len()), (whole.fs_hz(), whole.len()));
        assert_eq!(src.channels(), whole.channels());
        assert_eq!(src.meta().source, whole.meta.source);
        for _ in 0..2 {
            let mut got: Vec<Vec<f64>> = vec![Vec::new(); 3];
            let mut blocks = 0;
            src.pass(&mut |b| {
                for (g, c) in got.iter_mut().zip(Channel::ALL) {
                    g.extend_from_slice(b.channel(c).unwrap());
                }
                blocks += 1;
                Ok(())
            })
            .unwrap();
            assert!(blocks > 10);
            for (g, c) in got.iter().zip(Channel::ALL) {
                assert_eq!(g.as_slice(), whole.channel(c).unwrap(), "{c:?}");
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Pieces of a few rows each (fewer than a recording's minimum; in
    /// real files the last piece can be that short) join their
    /// neighbours: the file still streams, equal to the whole-file read.
    #[test]
    fn pieces_shorter_than_a_recording_join_their_neighbours() {
        let dir = scratch("short");
        let p = dir.join("rec.csv");
        write_csv(&record(), &p).unwrap();
        let opts = LoadOptions::default();
        let whole = load(&p, &opts).unwrap();
        let mut src = open_sized(&p, &opts, (3000, 100))
            .unwrap()
            .expect("streams");
        let mut got = Vec::new();
        src.pass(&mut |b| {
            assert!(b.channel(Channel::Friction).unwrap().len() >= Recording::MIN_SAMPLES);
            got.extend_from_slice(b.channel(Channel::Friction).unwrap());
            Ok(())
        })
        .unwrap();
        assert_eq!(got.as_slice(), whole.channel(Channel::Friction).unwrap());
        // The fuzz harness's check on the same file.
        assert_eq!(check_stream_agrees(&p), Ok(()));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A missing value or a gap in time goes to the whole-file reader.
    #[test]
    fn files_the_scan_does_not_take_are_declined() {
        let dir = scratch("declined");
        let p = dir.join("rec.csv");
        write_csv(&record(), &p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let opts = LoadOptions::default();
        let nan = {
            let mut l = lines.clone();
            let row = l[3000].replacen(',', ",nan,", 1);
            let cells: Vec<&str> = row.split(',').collect();
            let fixed = format!("{},{},{},{}", cells[0], cells[1], cells[3], cells[4]);
            l[3000] = &fixed;
            l.join("\n")
        };
        let gap = {
            let mut l = lines.clone();
            l.remove(2500);
            l.join("\n")
        };
        for (name, t) in [("nan.csv", nan), ("gap.csv", gap)] {
            let q = dir.join(name);
            std::fs::write(&q, t).unwrap();
            assert!(
                open_sized(&q, &opts, (3000, 4096)).unwrap().is_none(),
                "{name}"
            );
        }
        let given = LoadOptions {
            fs_hz: Some(1000.0),
            ..LoadOptions::default()
        };
        assert!(open_sized(&p, &given, (3000, 4096)).unwrap().is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
