//! Delimited text (CSV, TSV) with a header row.
//!
//! - The first line that is neither blank nor a `#` comment is the header;
//!   later `#` lines and blank lines are skipped. A UTF-8 byte-order mark
//!   (as Excel writes) is ignored.
//! - Column names match ignoring case and surrounding spaces: `time_s`,
//!   `friction_N`, `position_mm`, `optical_V`, or the names in
//!   [`LoadOptions`]. Other columns are ignored.
//! - The delimiter is [`LoadOptions::delimiter`], a tab for [`Format::Tsv`],
//!   else whichever of `,` `;` tab occurs most in the header line.
//! - Every row must have as many fields as the header, and every cell of a
//!   used column must be a finite number (`1.5`, `-2e-3`, `inf` is rejected).
//!
//! Errors name the file, the 1-based line and the column.

use std::path::Path;

use super::{Format, LoadOptions, Locator, RawColumn, RawTable};
use crate::error::{Error, Result};
use crate::recording::Channel;

/// Canonical name of the time column.
pub const TIME_COLUMN: &str = "time_s";

/// The header and first data rows of a text file, for `inspect` and messages.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Column names as written (trimmed).
    pub columns: Vec<String>,
    /// Delimiter used.
    pub delimiter: u8,
    /// 1-based line of the header.
    pub line: u64,
}

/// Parses a text recording held in memory.
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    format: Format,
    opts: &LoadOptions,
) -> Result<RawTable> {
    let (mut rdr, header) = open(path, bytes, format, opts.delimiter)?;
    let plan = Plan::new(path, &header, opts)?;

    let n_est = bytes.len() / (header.columns.len() * 8 + 1);
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let Rows {
        time: time_vals,
        channels: chan_vals,
        lines,
        time_decimals,
    } = match fast_rows(body, rdr.position(), &header, &plan, n_est) {
        Some(rows) => rows,
        None => reader_rows(path, &mut rdr, &header, &plan, n_est)?,
    };
    if lines.is_empty() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: format!(
                "header (line {}) but no data rows; expected one row of numbers per sample",
                header.line
            ),
        });
    }
    let time = plan.time.map(|ti| RawColumn {
        name: header.columns[ti].clone(),
        values: time_vals,
        resolution: if time_decimals == i32::MIN {
            0.0
        } else {
            0.5 * 10f64.powi(-time_decimals.clamp(-300, 300))
        },
    });
    let channels = plan
        .channels
        .iter()
        .zip(chan_vals)
        .map(|(&(c, idx), values)| {
            (
                c,
                RawColumn {
                    name: header.columns[idx].clone(),
                    values,
                    resolution: 0.0,
                },
            )
        })
        .collect();
    Ok(RawTable {
        time,
        channels,
        locator: Locator::Lines(lines),
    })
}

/// The values of the used columns, row by row, with each row's 1-based line.
struct Rows {
    time: Vec<f64>,
    channels: Vec<Vec<f64>>,
    lines: Vec<u64>,
    time_decimals: i32,
}

impl Rows {
    fn with_capacity(plan: &Plan, n: usize) -> Self {
        Self {
            time: Vec::with_capacity(if plan.time.is_some() { n } else { 0 }),
            channels: plan
                .channels
                .iter()
                .map(|_| Vec::with_capacity(n))
                .collect(),
            lines: Vec::with_capacity(n),
            time_decimals: i32::MIN,
        }
    }
}

/// The rows read by the general CSV reader (quotes, lone `\r` line ends),
/// with the precise error for a bad row or cell.
fn reader_rows(
    path: &Path,
    rdr: &mut ::csv::Reader<&[u8]>,
    header: &Header,
    plan: &Plan,
    n_est: usize,
) -> Result<Rows> {
    let delimiter = header.delimiter;
    let mut record = ::csv::ByteRecord::new();
    let csv_err = |e: ::csv::Error| csv_error(path, e);
    let mut rows = Rows::with_capacity(plan, n_est);
    let ncols = header.columns.len();
    while rdr.read_byte_record(&mut record).map_err(csv_err)? {
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        if record.len() != ncols {
            return Err(Error::Parse {
                path: path.to_path_buf(),
                line: line as usize,
                column: None,
                reason: format!(
                    "{} field(s), but the header (line {}) has {ncols}; rows must all \
                     have as many fields as the header",
                    record.len(),
                    header.line
                ),
            });
        }
        let cell_err = |idx: usize, reason: String| Error::Parse {
            path: path.to_path_buf(),
            line: line as usize,
            column: Some(header.columns[idx].clone()),
            reason,
        };
        if let Some(ti) = plan.time {
            let cell = record[ti].trim_ascii();
            rows.time
                .push(parse_number(cell, delimiter).map_err(|r| cell_err(ti, r))?);
            rows.time_decimals = rows.time_decimals.max(decimals(cell));
        }
        for (k, &(_, idx)) in plan.channels.iter().enumerate() {
            let cell = record[idx].trim_ascii();
            rows.channels[k].push(parse_number(cell, delimiter).map_err(|r| cell_err(idx, r))?);
        }
        rows.lines.push(line);
    }
    Ok(rows)
}

/// The rows of the common file, read without the general CSV reader: no
/// quote anywhere, lines ended by `\n` or `\r\n`, every row with as many
/// fields as the header and every used cell a finite number. `None` as soon
/// as anything else is met: the caller then reads the file with the general
/// reader, which gives the same values for such files and the precise error
/// for bad ones. Blank lines and `#` lines are skipped as that reader does.
///
/// A plain body (no `\r`, no `#`, no blank line before the end) is parsed
/// as two halves split at a line end, in parallel; the halves' rows are
/// then joined, so the result is the same as one pass.
fn fast_rows(
    body: &[u8],
    after_header: &::csv::Position,
    header: &Header,
    plan: &Plan,
    n_est: usize,
) -> Option<Rows> {
    let ncols = header.columns.len();
    let delimiter = header.delimiter;
    if delimiter == b'\r' || delimiter == b'\n' || delimiter == b'#' || !delimiter.is_ascii() {
        return None;
    }
    // Which used value each field feeds: time, channel k, or nothing.
    let mut role = vec![Role::Unused; ncols];
    if let Some(ti) = plan.time {
        role[ti] = Role::Time;
    }
    for (k, &(_, idx)) in plan.channels.iter().enumerate() {
        role[idx] = Role::Channel(k);
    }
    let start = usize::try_from(after_header.byte()).ok()?;
    let text = body.get(start..)?;
    // No quote anywhere (the body's are looked for by `rows_of`, in the
    // only bytes it does not parse as numbers).
    if body[..start].contains(&b'"') {
        return None;
    }
    let first_line = after_header.line();
    let mid = text.len() / 2;
    let split = (text.len() >= PARALLEL_BYTES)
        .then(|| text[mid..].iter().position(|&b| b == b'\n'))
        .flatten()
        .map(|p| mid + p + 1)
        .filter(|&s| s < text.len());
    let whole = || rows_of(text, first_line, &role, delimiter, plan, n_est).map(|(rows, _)| rows);
    let Some(split) = split else {
        return whole();
    };
    // The halves in parallel, the second numbered from 0; when both are
    // plain (no blank, comment or `\r\n` line) every row's line is its
    // own, so the second half's numbers are shifted by the first half's
    // rows. Otherwise the text is read again in one pass.
    // The first half's vectors have room for the whole, so that the join
    // below does not move them.
    let (a, b) = rayon::join(
        || rows_of(&text[..split], first_line, &role, delimiter, plan, n_est),
        || rows_of(&text[split..], 0, &role, delimiter, plan, n_est / 2 + 1),
    );
    let ((mut a, a_plain), (b, b_plain)) = (a?, b?);
    if !(a_plain && b_plain) {
        return whole();
    }
    let offset = first_line + a.lines.len() as u64;
    a.time.extend_from_slice(&b.time);
    for (c, bc) in a.channels.iter_mut().zip(&b.channels) {
        c.extend_from_slice(bc);
    }
    a.lines.extend(b.lines.iter().map(|l| l + offset));
    a.time_decimals = a.time_decimals.max(b.time_decimals);
    Some(a)
}

/// Bodies at least this long are parsed in two halves in parallel.
const PARALLEL_BYTES: usize = 1 << 18;

/// What one field of a row feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// A column the recording does not use.
    Unused,
    /// The time column.
    Time,
    /// Channel `k` of the plan.
    Channel(usize),
}

/// The rows of `text` (whole lines; its first line is file line
/// `first_line`) as [`fast_rows`] reads them, and whether every line was a
/// row ended by `\n` (no blank, comment or `\r\n` line); `None` for
/// anything it does not handle. One pass: the cells are parsed where they
/// start, and each row must end where its last cell does.
fn rows_of(
    text: &[u8],
    first_line: u64,
    role: &[Role],
    delimiter: u8,
    plan: &Plan,
    n_est: usize,
) -> Option<(Rows, bool)> {
    let mut rows = Rows::with_capacity(plan, n_est);
    let mut plain = true;
    // Line numbers as the general reader gives them: a row's line is the
    // reader's line count where the previous record (or the header) ended,
    // i.e. after its `\n`, or before it when the record ended with `\r\n`.
    let mut row_line = first_line;
    let mut this_line = first_line;
    let mut pos = 0;
    while pos < text.len() {
        match text[pos] {
            // A blank line (`\n` or `\r\n`).
            b'\n' => {
                pos += 1;
                this_line += 1;
                plain = false;
                continue;
            }
            b'\r' if text.get(pos + 1) == Some(&b'\n') => {
                pos += 2;
                this_line += 1;
                plain = false;
                continue;
            }
            b'#' => {
                plain = false;
                let end = text[pos..].iter().position(|&b| b == b'\n');
                let line = &text[pos..end.map_or(text.len(), |e| pos + e)];
                if line.strip_suffix(b"\r").unwrap_or(line).contains(&b'\r') || !plain_text(line) {
                    return None;
                }
                pos = end.map_or(text.len(), |e| pos + e + 1);
                this_line += 1;
                continue;
            }
            _ => {}
        }
        let used = parse_row(&text[pos..], role, delimiter, &mut rows)?;
        pos += used;
        // The row ends at `\n`, `\r\n` or the end of the text.
        let crlf = match text.get(pos) {
            None => false,
            Some(b'\n') => {
                pos += 1;
                false
            }
            Some(b'\r') if text.get(pos + 1) == Some(&b'\n') => {
                pos += 2;
                plain = false;
                true
            }
            Some(_) => return None,
        };
        rows.lines.push(row_line);
        row_line = if crlf { this_line } else { this_line + 1 };
        this_line += 1;
    }
    Some((rows, plain))
}

/// Parses the used cells of the row starting `text` into `rows` and returns
/// the bytes it took, up to (not including) the line end; `None` unless the
/// row has exactly `role.len()` fields and every used cell is a finite
/// number.
fn parse_row(text: &[u8], role: &[Role], delimiter: u8, rows: &mut Rows) -> Option<usize> {
    let is_end = |b: u8| b == b'\n' || b == b'\r';
    let mut i = 0;
    for (k, &r) in role.iter().enumerate() {
        if k > 0 {
            // The previous field ended at a delimiter.
            if text.get(i) != Some(&delimiter) {
                return None;
            }
            i += 1;
        }
        if r == Role::Unused {
            let len = text[i..]
                .iter()
                .position(|&b| b == delimiter || is_end(b))
                .unwrap_or(text.len() - i);
            if !plain_text(&text[i..i + len]) {
                return None;
            }
            i += len;
            continue;
        }
        // Cells are trimmed of white space, as the general path does.
        let blank = |b: u8| b != delimiter && b.is_ascii_whitespace() && !is_end(b);
        i += text[i..].iter().take_while(|&&b| blank(b)).count();
        let (x, used) = fast_float2::parse_partial::<f64, _>(&text[i..]).ok()?;
        if !x.is_finite() {
            return None;
        }
        let cell = &text[i..i + used];
        i += used;
        i += text[i..].iter().take_while(|&&b| blank(b)).count();
        match r {
            Role::Time => {
                rows.time.push(x);
                rows.time_decimals = rows.time_decimals.max(decimals(cell));
            }
            Role::Channel(c) => rows.channels[c].push(x),
            Role::Unused => {}
        }
    }
    Some(i)
}

/// Whether bytes that [`rows_of`] skips (a comment line, an unused field)
/// are text without a quote. A quote has a CSV meaning the fast path does
/// not implement; bytes that are not UTF-8 are left to the general reader
/// too (it decodes only the cells it uses, so the result is the same; the
/// fast path only declines). Everything else `rows_of` accepts (numbers,
/// white space, delimiters, line ends) is ASCII by construction, so these
/// checks stand for a check of the whole body.
fn plain_text(skipped: &[u8]) -> bool {
    !skipped.contains(&b'"') && std::str::from_utf8(skipped).is_ok()
}

/// Reads the header of a text recording (for `inspect` and error hints).
///
/// # Errors
/// As [`super::load`] for an empty or binary file or a malformed first row.
pub fn read_header(
    path: &Path,
    bytes: &[u8],
    format: Format,
    delimiter: Option<u8>,
) -> Result<Header> {
    open(path, bytes, format, delimiter).map(|(_, h)| h)
}

/// Checks that `bytes` is text, picks the delimiter, and reads the header row.
fn open<'a>(
    path: &Path,
    bytes: &'a [u8],
    format: Format,
    delimiter: Option<u8>,
) -> Result<(::csv::Reader<&'a [u8]>, Header)> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    check_text(path, bytes)?;
    let delimiter = delimiter.unwrap_or_else(|| match format {
        Format::Tsv => b'\t',
        _ => sniff_delimiter(bytes),
    });
    let mut rdr = ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .delimiter(delimiter)
        .from_reader(bytes);
    let mut record = ::csv::ByteRecord::new();
    if !rdr
        .read_byte_record(&mut record)
        .map_err(|e| csv_error(path, e))?
    {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "no header row (the file holds only comments or blank lines); expected \
                     a header such as time_s,friction_N,position_mm,optical_V"
                .into(),
        });
    }
    let header = Header {
        columns: record
            .iter()
            .map(|f| String::from_utf8_lossy(f.trim_ascii()).into_owned())
            .collect(),
        delimiter,
        line: record.position().map(|p| p.line()).unwrap_or(1),
    };
    Ok((rdr, header))
}

fn csv_error(path: &Path, e: ::csv::Error) -> Error {
    let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
    Error::Parse {
        path: path.to_path_buf(),
        line,
        column: None,
        reason: e.to_string(),
    }
}

/// Which header column feeds what.
struct Plan {
    time: Option<usize>,
    channels: Vec<(Channel, usize)>,
}

impl Plan {
    fn new(path: &Path, header: &Header, opts: &LoadOptions) -> Result<Self> {
        let find = |name: &str| -> Result<Option<usize>> {
            let mut hits = header
                .columns
                .iter()
                .enumerate()
                .filter(|(_, c)| c.eq_ignore_ascii_case(name.trim()))
                .map(|(i, _)| i);
            let first = hits.next();
            if first.is_some() && hits.next().is_some() {
                return Err(Error::Parse {
                    path: path.to_path_buf(),
                    line: header.line as usize,
                    column: Some(name.to_string()),
                    reason: "column name appears more than once in the header".into(),
                });
            }
            Ok(first)
        };
        let missing = |what: &str, name: &str| Error::Parse {
            path: path.to_path_buf(),
            line: header.line as usize,
            column: None,
            reason: format!(
                "no column '{name}' for {what}; the header has: {}",
                header.columns.join(", ")
            ),
        };
        let time = match (&opts.time, opts.ignore_time) {
            (_, true) => None,
            (Some(name), false) => Some(find(name)?.ok_or_else(|| missing("time", name))?),
            (None, false) => find(TIME_COLUMN)?,
        };
        let mut channels = Vec::new();
        for c in Channel::ALL {
            match &opts.source(c).name {
                Some(name) => {
                    let idx = find(name)?.ok_or_else(|| missing(c.column_name(), name))?;
                    channels.push((c, idx));
                }
                None => {
                    if let Some(idx) = find(c.column_name())? {
                        channels.push((c, idx));
                    }
                }
            }
        }
        if channels.is_empty() {
            return Err(Error::Parse {
                path: path.to_path_buf(),
                line: header.line as usize,
                column: None,
                reason: format!(
                    "no channel column found; expected friction_N, position_mm or optical_V \
                     (or a mapped name); the header has: {}",
                    header.columns.join(", ")
                ),
            });
        }
        for (k, &(c, idx)) in channels.iter().enumerate() {
            let clash = channels[..k]
                .iter()
                .find(|&&(_, j)| j == idx)
                .map(|&(o, _)| o.column_name())
                .or_else(|| (time == Some(idx)).then_some("time"));
            if let Some(other) = clash {
                return Err(Error::setting(
                    format!("{} column", c.short_name()),
                    format!(
                        "column '{}' is already used for {other}",
                        header.columns[idx]
                    ),
                ));
            }
        }
        Ok(Self { time, channels })
    }
}

/// Rejects binary files early, saying what they look like.
fn check_text(path: &Path, bytes: &[u8]) -> Result<()> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "file is empty; expected a header row such as \
                     time_s,friction_N,position_mm,optical_V and rows of numbers"
                .into(),
        });
    }
    let head = &bytes[..bytes.len().min(4096)];
    if head.starts_with(b"MATLAB") {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "this is a MATLAB MAT-file, not text: name it .mat or read it as format mat"
                .into(),
        });
    }
    if head.starts_with(b"\x89HDF\r\n\x1a\n") || head.contains(&0) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "binary file, not delimited text; expected a CSV/TSV header row".into(),
        });
    }
    Ok(())
}

/// The most frequent of `,` `;` tab in the header line (`,` when none).
fn sniff_delimiter(bytes: &[u8]) -> u8 {
    let header = bytes
        .split(|&b| b == b'\n')
        .map(<[u8]>::trim_ascii)
        .find(|l| !l.is_empty() && !l.starts_with(b"#"))
        .unwrap_or(b"");
    let count = |d: u8| header.iter().filter(|&&b| b == d).count();
    [b',', b'\t', b';']
        .into_iter()
        .max_by_key(|&d| (count(d), d == b','))
        .filter(|&d| count(d) > 0)
        .unwrap_or(b',')
}

/// Parses one cell as a finite `f64`.
fn parse_number(cell: &[u8], delimiter: u8) -> std::result::Result<f64, String> {
    if cell.is_empty() {
        return Err("empty cell; expected a number".into());
    }
    let text = std::str::from_utf8(cell)
        .map_err(|_| format!("'{}' is not a number", String::from_utf8_lossy(cell)))?;
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(format!("'{text}' is not a finite number")),
        Err(_) => {
            let hint = if delimiter != b',' && text.contains(',') {
                " (decimal commas are not supported: use '.' as decimal point)"
            } else {
                ""
            };
            Err(format!("'{text}' is not a number{hint}"))
        }
    }
}

/// Digits after the decimal point of a printed number, minus its exponent
/// (`0.0125` → 4, `1.25e-2` → 4, `12` → 0, `1e3` → -3).
fn decimals(cell: &[u8]) -> i32 {
    // One pass (it runs on every time cell): the point, then an exponent.
    let mut point = None;
    for (i, &b) in cell.iter().enumerate() {
        match b {
            b'.' => point = Some(i),
            b'e' | b'E' => {
                let exp = std::str::from_utf8(&cell[i + 1..])
                    .ok()
                    .and_then(|s| s.parse::<i32>().ok())
                    .unwrap_or(0);
                let frac = point.map_or(0, |p| (i - p - 1) as i32);
                return frac.saturating_sub(exp);
            }
            _ => {}
        }
    }
    point.map_or(0, |p| (cell.len() - p - 1) as i32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows of `text` by the fast path (`None` if it declines) and by the
    /// general reader.
    fn both(text: &str) -> (Option<Rows>, Rows) {
        let path = Path::new("t.csv");
        let bytes = text.as_bytes();
        let opts = LoadOptions::default();
        let (mut rdr, header) = open(path, bytes, Format::Csv, None).unwrap();
        let plan = Plan::new(path, &header, &opts).unwrap();
        let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        let fast = fast_rows(body, &rdr.position().clone(), &header, &plan, 4);
        let slow = reader_rows(path, &mut rdr, &header, &plan, 4).unwrap();
        (fast, slow)
    }

    /// The fast path reads exactly what the general reader reads (values
    /// bit for bit, each row's line, time decimals) on files with comments,
    /// blank lines, CRLF, a BOM, padding, unused columns, `;` and tab
    /// delimiters, and no final newline.
    #[test]
    fn fast_rows_agree_with_the_csv_reader() {
        let texts = [
            "time_s,friction_N,optical_V\n0.0,1.5,2\n0.001,-2e-3,3.25\n",
            "# note\n\n time_s , friction_N\r\n0.000, 1\r\n\r\n# mid\r\n0.001 ,2\r\n0.002,3",
            "\u{FEFF}time_s;friction_N;x\n0;1;a\n1;2;b\n",
            "time_s\tposition_mm\toptical_V\n0\t0.1\t1\n\n\n1\t0.2\t1e3\n",
            "friction_N,unused\n1,\n",
            "time_s,friction_N\n0,1\n# c\n\n1,2\n#\n2,3",
        ];
        for t in texts {
            let (fast, slow) = both(t);
            let fast = fast.unwrap_or_else(|| panic!("fast path declined {t:?} {:?}", slow.lines));
            assert_eq!(fast.lines, slow.lines, "{t:?}");
            assert_eq!(fast.time_decimals, slow.time_decimals, "{t:?}");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast.time), bits(&slow.time), "{t:?}");
            assert_eq!(fast.channels.len(), slow.channels.len());
            for (a, b) in fast.channels.iter().zip(&slow.channels) {
                assert_eq!(bits(a), bits(b), "{t:?}");
            }
        }
    }

    /// A body long enough to be parsed in two halves gives the same rows,
    /// values and line numbers as the general reader; with a comment or a
    /// `\r\n` it is parsed in one pass, with the same result.
    #[test]
    fn long_bodies_parsed_in_halves_agree_with_the_csv_reader() {
        let mut body = String::new();
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for i in 0..20_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            let v = (u - 0.5) * 10f64.powi((i % 13) - 6);
            body.push_str(&format!("{},{v},{:e},x{i}, {}\n", i as f64 / 1000.0, u, -u));
        }
        let head = "time_s,friction_N,position_mm,note,optical_V\n";
        let plain = format!("{head}{body}");
        assert!(plain.len() >= 2 * PARALLEL_BYTES);
        let crlf = plain.replace('\n', "\r\n");
        let commented = format!("{head}# a comment\n{body}");
        for t in [&plain, &crlf, &commented] {
            let (fast, slow) = both(t);
            let fast = fast.expect("fast path read it");
            assert_eq!(fast.lines.len(), 20_000);
            assert_eq!(fast.lines, slow.lines);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast.time), bits(&slow.time));
            assert_eq!(fast.time_decimals, slow.time_decimals);
            for (a, b) in fast.channels.iter().zip(&slow.channels) {
                assert_eq!(bits(a), bits(b));
            }
        }
        // A bad cell in the second half sends the file to the general reader.
        let bad = plain.replacen(",x19990,", ",x19990,,", 1);
        let path = Path::new("t.csv");
        let (rdr, header) = open(path, bad.as_bytes(), Format::Csv, None).unwrap();
        let plan = Plan::new(path, &header, &LoadOptions::default()).unwrap();
        assert!(fast_rows(bad.as_bytes(), rdr.position(), &header, &plan, 4).is_none());
    }

    /// Quotes, lone `\r` line ends, ragged rows and bad cells are left to
    /// the general reader (which reads or reports them).
    #[test]
    fn fast_rows_decline_what_they_do_not_handle() {
        let path = Path::new("t.csv");
        for t in [
            "time_s,friction_N\n0,\"1\"\n",
            "time_s,friction_N\r0,1\r1,2\r",
            "time_s,friction_N\n0,1,2\n",
            "time_s,friction_N\n0\n",
            "time_s,friction_N\n0,1\n1,inf\n",
            "time_s,friction_N\n0,1\n1,x\n",
            "time_s,friction_N\n0,1\n1,\n",
            // Quotes where no number is parsed: a comment, an unused field.
            "time_s,friction_N\n# a \"quoted\" note\n0,1\n",
            "time_s,friction_N,note\n0,1,\"a, b\"\n",
            "\"time_s\",friction_N\n0,1\n",
        ] {
            let (rdr, header) = open(path, t.as_bytes(), Format::Csv, None).unwrap();
            let plan = Plan::new(path, &header, &LoadOptions::default()).unwrap();
            assert!(
                fast_rows(t.as_bytes(), rdr.position(), &header, &plan, 4).is_none(),
                "{t:?}"
            );
        }
    }

    /// Bytes that are not text, where no number is parsed (a comment, an
    /// unused field), send the file to the general reader too.
    #[test]
    fn fast_rows_decline_bytes_that_are_not_text() {
        let path = Path::new("t.csv");
        for t in [
            &b"time_s,friction_N,note\n0,1,ok\n1,2,\xFF\n"[..],
            &b"time_s,friction_N\n0,1\n# \xC3\n1,2\n"[..],
        ] {
            let (rdr, header) = open(path, t, Format::Csv, None).unwrap();
            let plan = Plan::new(path, &header, &LoadOptions::default()).unwrap();
            assert!(
                fast_rows(t, rdr.position(), &header, &plan, 4).is_none(),
                "{t:?}"
            );
        }
        // The same files as text are read.
        for t in [
            &b"time_s,friction_N,note\n0,1,ok\n1,2,\xC3\xA9\n"[..],
            &b"time_s,friction_N\n0,1\n# \xC3\xA9\n1,2\n"[..],
        ] {
            let (rdr, header) = open(path, t, Format::Csv, None).unwrap();
            let plan = Plan::new(path, &header, &LoadOptions::default()).unwrap();
            assert!(fast_rows(t, rdr.position(), &header, &plan, 4).is_some());
        }
    }

    #[test]
    fn decimals_count_printed_precision() {
        assert_eq!(decimals(b"0.0125"), 4);
        assert_eq!(decimals(b"1.25e-2"), 4);
        assert_eq!(decimals(b"12"), 0);
        assert_eq!(decimals(b"1e3"), -3);
        assert_eq!(decimals(b"-3.5E+1"), 0);
        assert_eq!(decimals(b"5."), 0);
        assert_eq!(decimals(b".25"), 2);
        assert_eq!(decimals(b"2.5e"), 1);
    }

    #[test]
    fn delimiter_is_sniffed_from_the_header_line() {
        assert_eq!(sniff_delimiter(b"# c,o,m\na\tb\tc\n1\t2\t3\n"), b'\t');
        assert_eq!(sniff_delimiter(b"a;b;c\n1,5;2;3\n"), b';');
        assert_eq!(sniff_delimiter(b"a,b\n"), b',');
        assert_eq!(sniff_delimiter(b"a\n1\n"), b',');
    }
}
