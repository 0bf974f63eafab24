//! Long text recordings read from the file in pieces.
//!
//! The whole-file reader holds the file's bytes and the parsed columns at
//! once: for a two-hour record at 1 kHz that is 440 MB of text beside
//! 290 MB of numbers. A file of at least [`STREAM_BYTES`] is read here
//! instead: the header from its first [`HEAD_BYTES`], then the rows in
//! pieces of [`PIECE_BYTES`] cut at line ends, each parsed by the fast
//! path ([`super::fast::plain_rows`]) and appended to the columns; only one
//! piece of text is held at a time.
//!
//! Anything the fast path does not take (quotes, comments, blank lines,
//! `\r\n`, a bad or missing cell, a header it cannot place in the head)
//! returns `None`, and the caller reads the file whole with the general
//! reader, which gives the same values or the precise error with its line.
//! So the pieces change how much memory a plain file needs, never what is
//! read from it.

use std::io::Read;
use std::path::Path;

use super::fast::plain_rows;
use super::{layout, table, Dialect, Plan, Rows};
use crate::error::{Error, Result};
use crate::recording::io::{Format, LoadOptions, RawTable};
use crate::recording::Recording;

/// Files at least this long are read in pieces.
pub(crate) const STREAM_BYTES: u64 = 64 << 20;

/// Bytes read for the header (four times what the header search covers,
/// so the units row and the decimal-comma sniff see what they would in the
/// whole file).
pub(super) const HEAD_BYTES: usize = 4 << 20;

/// Bytes of text per piece.
pub(super) const PIECE_BYTES: usize = 16 << 20;

/// The raw table of a text recording of at least [`STREAM_BYTES`], read in
/// pieces; `Ok(None)` for a shorter file or one the pieces cannot take (see
/// the module docs).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read.
pub(crate) fn parse_streamed(
    path: &Path,
    format: Format,
    opts: &LoadOptions,
) -> Result<Option<RawTable>> {
    parse_in_pieces(path, format, opts, STREAM_BYTES, HEAD_BYTES, PIECE_BYTES)
}

/// [`parse_streamed`] with its sizes given (the tests use small ones).
fn parse_in_pieces(
    path: &Path,
    format: Format,
    opts: &LoadOptions,
    stream_bytes: u64,
    head_bytes: usize,
    piece_bytes: usize,
) -> Result<Option<RawTable>> {
    let mut rows: Option<Rows> = None;
    let size = std::fs::metadata(path)
        .map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?
        .len();
    if size < stream_bytes {
        return Ok(None);
    }
    let sizes = (head_bytes, piece_bytes);
    let got = for_each_piece(path, format, opts, sizes, &mut |_, plan, r, bytes| {
        let all = rows.get_or_insert_with(|| {
            // Room for the file's rows at the first piece's bytes per
            // row, and 2 % more.
            let mut all = Rows::with_capacity(plan, 0);
            if !r.lines.is_empty() {
                let per_row = bytes as f64 / r.lines.len() as f64;
                reserve(
                    &mut all,
                    (size as f64 / per_row * 1.02) as usize,
                    plan.time.is_some(),
                );
            }
            all
        });
        append(all, r);
        Ok(())
    })?;
    let Some((header, plan)) = got else {
        return Ok(None);
    };
    let mut rows = rows.unwrap_or_else(|| Rows::with_capacity(&plan, 0));
    // The room reserved from the first piece's rows is an estimate (2 %
    // over, more when the first rows are shorter): give back the rest.
    for c in &mut rows.channels {
        c.shrink_to_fit();
    }
    table(path, &header, &plan, rows, opts).map(Some)
}

/// Reads a text recording in pieces of `piece_bytes` (the header from its
/// first `head_bytes`), handing each piece's rows (and the piece's size in
/// bytes) to `each`, a piece of fewer than `Recording::MIN_SAMPLES` rows
/// joined to its neighbour; the header and plan, or `None` when the fast path
/// does not take the file (module docs).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; the first error of `each`.
pub(super) fn for_each_piece(
    path: &Path,
    format: Format,
    opts: &LoadOptions,
    (head_bytes, piece_bytes): (usize, usize),
    each: &mut dyn FnMut(&super::Header, &Plan, Rows, usize) -> Result<()>,
) -> Result<Option<(super::Header, Plan)>> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut buf = vec![0u8; head_bytes];
    let got = read_full(&mut file, &mut buf).map_err(io)?;
    buf.truncate(got);
    let Some(last_nl) = buf.iter().rposition(|&b| b == b'\n') else {
        return Ok(None);
    };
    let head = &buf[..=last_nl];
    let Ok(lay) = layout(path, head, format, opts) else {
        return Ok(None);
    };
    if lay.quoted_head || lay.body.is_empty() {
        return Ok(None);
    }
    let Ok(plan) = Plan::new(path, &lay.header, opts) else {
        return Ok(None);
    };
    let header = lay.header.clone();
    let ncols = header.columns.len();
    let d = Dialect {
        delimiter: header.delimiter,
        decimal_comma: header.decimal_comma,
    };
    let mut line = lay.body_line;
    // The first piece is the head's body; `carry` the text after its last
    // line end.
    let body_at = head.len() - lay.body.len();
    let mut piece: Vec<u8> = buf[body_at..=last_nl].to_vec();
    let mut carry: Vec<u8> = buf[last_nl + 1..].to_vec();
    drop(buf);
    let mut eof = got < head_bytes;
    // The rows read but not yet handed on (one piece behind), so that a
    // piece of fewer than `Recording::MIN_SAMPLES` rows (the file's last,
    // or any when lines are long) joins its neighbour: every piece handed
    // on can be finished as a recording unless the whole body is shorter.
    let mut pending: Option<(Rows, usize)> = None;
    loop {
        if !piece.is_empty() {
            let Some(r) = plain_rows(&piece, line, ncols, &plan, d, 0) else {
                return Ok(None);
            };
            line += r.lines.len() as u64;
            pending = match pending.take() {
                None => Some((r, piece.len())),
                Some((mut p, bytes)) => {
                    if p.lines.len() < Recording::MIN_SAMPLES
                        || r.lines.len() < Recording::MIN_SAMPLES
                    {
                        append(&mut p, r);
                        Some((p, bytes + piece.len()))
                    } else {
                        each(&header, &plan, p, bytes)?;
                        Some((r, piece.len()))
                    }
                }
            };
        }
        if eof && carry.is_empty() {
            break;
        }
        // The next piece: the carried partial line, then up to PIECE_BYTES
        // more, cut after the last line end (all of it at the end of file).
        piece.clear();
        piece.append(&mut carry);
        let start = piece.len();
        piece.resize(start + piece_bytes, 0);
        let got = read_full(&mut file, &mut piece[start..]).map_err(io)?;
        piece.truncate(start + got);
        eof = got < piece_bytes;
        if !eof {
            match piece.iter().rposition(|&b| b == b'\n') {
                Some(p) => carry.extend_from_slice(&piece[p + 1..]),
                None => return Ok(None),
            }
            let keep = piece.len() - carry.len();
            piece.truncate(keep);
        }
    }
    if let Some((p, bytes)) = pending {
        each(&header, &plan, p, bytes)?;
    }
    Ok(Some((header, plan)))
}

/// Room for `n` rows in every column used.
fn reserve(rows: &mut Rows, n: usize, has_time: bool) {
    rows.lines.reserve(n);
    if has_time {
        rows.time.reserve(n);
    }
    for c in &mut rows.channels {
        c.reserve(n);
    }
}

/// Appends the rows of one piece.
fn append(rows: &mut Rows, r: Rows) {
    rows.time.extend_from_slice(&r.time);
    for (c, rc) in rows.channels.iter_mut().zip(&r.channels) {
        c.extend_from_slice(rc);
    }
    rows.lines.extend_from_slice(&r.lines);
    rows.time_decimals = rows.time_decimals.max(r.time_decimals);
}

/// Reads until `buf` is full or the file ends; the bytes read.
fn read_full(file: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match file.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::io::parse;

    /// A scratch folder of its own per test (they run in parallel).
    fn scratch(test: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("ballpass-stream-{test}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn body(rows: usize) -> String {
        let mut t = String::from("time_s,friction_N,position_mm,optical_V\n");
        for i in 0..rows {
            let x = i as f64 * 1e-3;
            t.push_str(&format!(
                "{x},{},{},{}\n",
                (x * 7.3).sin() * 1.25,
                -0.2 + 9.0 * x,
                (x * 1.1).cos()
            ));
        }
        t
    }

    /// Read in pieces of a few kB (many piece boundaries, a head holding
    /// the header and part of the body) the table is the whole-file
    /// reader's, value for value and line for line.
    #[test]
    fn pieces_read_what_the_whole_file_reader_reads() {
        let dir = scratch("pieces");
        let opts = LoadOptions::default();
        for (name, text) in [
            ("plain.csv", body(20_000)),
            ("no_final_newline.csv", body(5_000).trim_end().to_string()),
            ("units.csv", body(3_000).replacen("\n", "\ns,N,mm,V\n", 1)),
        ] {
            let p = write(&dir, name, &text);
            let whole = parse(&p, text.as_bytes(), &opts).unwrap();
            for piece in [4096, 5000, 1 << 16] {
                let got = parse_in_pieces(&p, Format::Csv, &opts, 0, 3000, piece)
                    .unwrap()
                    .expect("a plain file is read in pieces");
                // Debug prints every f64 in its shortest round-trip form, so
                // equal text is equal bits.
                assert_eq!(
                    format!("{got:?}"),
                    format!("{whole:?}"),
                    "{name} piece {piece}"
                );
            }
            std::fs::remove_file(&p).unwrap();
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What the fast path does not take goes back to the whole-file reader.
    #[test]
    fn files_the_pieces_do_not_take_are_declined() {
        let dir = scratch("declined");
        let opts = LoadOptions::default();
        let base = body(2_000);
        for (name, text) in [
            ("short.csv", base.clone()),
            ("comment.csv", base.replacen("\n0.5,", "\n# note\n0.5,", 1)),
            ("bad.csv", base.replacen("\n0.5,", "\n0.5,x", 1)),
            ("crlf.csv", base.replace('\n', "\r\n")),
        ] {
            let p = write(&dir, name, &text);
            let min = if name == "short.csv" { 1 << 30 } else { 0 };
            let got = parse_in_pieces(&p, Format::Csv, &opts, min, 3000, 4096).unwrap();
            assert!(got.is_none(), "{name} should be declined");
            std::fs::remove_file(&p).unwrap();
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
