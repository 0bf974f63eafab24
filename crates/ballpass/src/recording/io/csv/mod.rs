//! Delimited text (CSV, TSV) with a header row, in the dialects labs write.
//!
//! - The header is the first line that is neither blank nor a `#` comment,
//!   after [`LoadOptions::skip_lines`] lines when given; otherwise, when that
//!   line names no wanted column, the first of the next lines (at most
//!   [`MAX_PREAMBLE_LINES`] in all) that does: the lines before it are a
//!   logger's metadata. Later `#` lines and blank lines are skipped. A UTF-8
//!   byte-order mark (as Excel writes) is ignored.
//! - Column names match ignoring case and surrounding spaces: `time_s`,
//!   `friction_N`, `position_mm`, `optical_V`, or the names in
//!   [`LoadOptions`]. Without one named, the time column may also be a
//!   `time`/`t`/`zeit` column that states its unit (`time_ms`, `t [ms]`).
//!   Other columns are ignored.
//! - The delimiter is [`LoadOptions::delimiter`], a tab for [`Format::Tsv`],
//!   else whichever of `,` `;` tab occurs most in the header line.
//! - A decimal comma (`1,5`) is read when set, or detected in a `;`- or
//!   tab-separated file whose numbers use `,` and never `.`.
//! - A row under the header whose used cells are all text (`s`, `N`, `[mm]`)
//!   is a units row: the time column's unit scales the time (ms, µs), and a
//!   channel's unit is converted to N, mm or V (kN, µm, mV) or refused when
//!   ballpass does not know it and no scale is given. Units in the header
//!   names (`Force [kN]`, `time_ms`) count the same.
//! - Every row must have as many fields as the header; every cell of a used
//!   column must be a number. An empty cell, `NaN` or `inf` is a gap (see
//!   [`super::GapPolicy`]).
//!
//! Errors name the file, the 1-based line and the column.

use std::path::Path;

use super::{units, Format, LoadOptions, Locator, RawColumn, RawTable, TimeUnit};
use crate::error::{excerpt, excerpt_bytes, Error, Result};
use crate::recording::Channel;

pub mod blocks;
mod fast;
mod header;
mod stream;

use fast::{fast_rows, Dialect};
pub use header::read_header;
use header::{is_time_name, layout};
pub(crate) use stream::parse_streamed;

/// Canonical name of the time column.
pub const TIME_COLUMN: &str = "time_s";

/// Most lines searched for the header (and skipped before it).
pub const MAX_PREAMBLE_LINES: usize = 200;

/// Most bytes searched for the header.
const MAX_PREAMBLE_BYTES: usize = 1 << 20;

/// Rows sampled to detect a decimal comma.
const SNIFF_ROWS: usize = 100;

/// The header of a text file and how its rows are written.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// Column names as written (trimmed).
    pub columns: Vec<String>,
    /// Delimiter used.
    pub delimiter: u8,
    /// 1-based line of the header.
    pub line: u64,
    /// Lines before the header that are not blank or comments (metadata).
    pub preamble: Vec<String>,
    /// The units row under the header, if any, and its line.
    pub units: Option<(Vec<String>, u64)>,
    /// Numbers are written with a decimal comma.
    pub decimal_comma: bool,
}

/// A text file split into header and body.
struct Layout<'a> {
    header: Header,
    /// The body: rows after the header (and the units row).
    body: &'a [u8],
    /// File line of the body's first line, as the CSV reader counts.
    body_line: u64,
    /// A quote appears before the body (in the header or units row).
    quoted_head: bool,
}

/// Parses a text recording held in memory.
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    format: Format,
    opts: &LoadOptions,
) -> Result<RawTable> {
    let layout = layout(path, bytes, format, opts)?;
    let header = &layout.header;
    let plan = Plan::new(path, header, opts)?;
    let n_est = layout.body.len() / (header.columns.len() * 8 + 1);
    let d = Dialect {
        delimiter: header.delimiter,
        decimal_comma: header.decimal_comma,
    };
    let fast = if layout.quoted_head {
        None
    } else {
        fast_rows(
            layout.body,
            layout.body_line,
            header.columns.len(),
            &plan,
            d,
            n_est,
        )
    };
    let rows = match fast {
        Some(rows) => rows,
        None => reader_rows(path, &layout, &plan, n_est)?,
    };
    table(path, header, &plan, rows, opts)
}

/// The raw table of the rows read under `header`.
fn table(
    path: &Path,
    header: &Header,
    plan: &Plan,
    rows: Rows,
    opts: &LoadOptions,
) -> Result<RawTable> {
    let Rows {
        time: time_vals,
        channels: chan_vals,
        lines,
        time_decimals,
    } = rows;
    if lines.is_empty() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: format!(
                "header (line {}) but no data rows; expected one row of numbers per sample",
                header.line
            ),
        });
    }
    let unit_of = |idx: usize| -> Option<(String, String)> {
        let from_row = header.units.as_ref().and_then(|(u, line)| {
            let u = u.get(idx)?.trim();
            (!u.is_empty()).then(|| (u.to_string(), format!("units row, line {line}")))
        });
        from_row.or_else(|| {
            units::unit_of_name(&header.columns[idx]).map(|u| {
                (
                    u.to_string(),
                    format!("header '{}'", excerpt(&header.columns[idx])),
                )
            })
        })
    };
    let mut time_unit = None;
    let time = match plan.time {
        Some(ti) => {
            if let Some((u, from)) = unit_of(ti) {
                let unit = TimeUnit::parse(&u).ok_or_else(|| Error::Parse {
                    path: path.to_path_buf(),
                    line: header.line as usize,
                    column: Some(header.columns[ti].clone()),
                    reason: format!(
                        "time unit '{}' ({from}) is not s, ms or us; give the time unit",
                        excerpt(&u)
                    ),
                })?;
                time_unit = Some((unit, from));
            }
            Some(RawColumn {
                name: excerpt(&header.columns[ti]),
                values: time_vals,
                resolution: if time_decimals == i32::MIN {
                    0.0
                } else {
                    0.5 * 10f64.powi(-time_decimals.clamp(-300, 300))
                },
                unit: None,
            })
        }
        None => None,
    };
    let channels = plan
        .channels
        .iter()
        .zip(chan_vals)
        .map(|(&(c, idx), values)| {
            (
                c,
                RawColumn {
                    name: excerpt(&header.columns[idx]),
                    values,
                    resolution: 0.0,
                    unit: unit_of(idx),
                },
            )
        })
        .collect();
    let mut notes = Vec::new();
    if header.decimal_comma && opts.decimal_comma.is_none() {
        notes.push("read with a decimal comma (detected)".to_string());
    }
    if !header.preamble.is_empty() {
        notes.push(format!(
            "{} metadata line(s) before the header (line {}) skipped",
            header.preamble.len(),
            header.line
        ));
    }
    Ok(RawTable {
        time,
        time_unit,
        channels,
        locator: Locator::Lines(lines),
        notes,
        ..RawTable::default()
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

/// A CSV reader over `bytes` (rows only: no header, comments skipped).
fn reader(bytes: &[u8], delimiter: u8) -> ::csv::Reader<&[u8]> {
    ::csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .delimiter(delimiter)
        .from_reader(without_trailing_comment(bytes))
}

/// `bytes` without the `#` lines at its end that have no `\n` after them:
/// the CSV reader would take such a line for a row, where a `#` line
/// anywhere else is a comment. (A comment runs to `\n`; a last line ended
/// by a lone `\r` counts as unended.)
fn without_trailing_comment(mut bytes: &[u8]) -> &[u8] {
    while bytes.last().is_some_and(|&b| b != b'\n') {
        let end = bytes.len() - bytes.iter().rev().take_while(|&&b| b == b'\r').count();
        let start = bytes[..end]
            .iter()
            .rposition(|&b| b == b'\n' || b == b'\r')
            .map_or(0, |p| p + 1);
        if bytes.get(start) != Some(&b'#') {
            break;
        }
        bytes = &bytes[..start];
    }
    bytes
}

/// The rows read by the general CSV reader (quotes, lone `\r` line ends),
/// with the precise error for a bad row or cell.
fn reader_rows(path: &Path, layout: &Layout<'_>, plan: &Plan, n_est: usize) -> Result<Rows> {
    let header = &layout.header;
    let mut rdr = reader(layout.body, header.delimiter);
    let line_of = |rel: u64| rel + layout.body_line - 1;
    let mut record = ::csv::ByteRecord::new();
    let mut rows = Rows::with_capacity(plan, n_est);
    let ncols = header.columns.len();
    while rdr
        .read_byte_record(&mut record)
        .map_err(|e| csv_error(path, e, layout.body_line))?
    {
        let line = line_of(record.position().map(|p| p.line()).unwrap_or(1));
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
            let (x, dec) = number(cell, header.decimal_comma).map_err(|r| cell_err(ti, r))?;
            rows.time.push(x);
            rows.time_decimals = rows.time_decimals.max(dec);
        }
        for (k, &(_, idx)) in plan.channels.iter().enumerate() {
            let cell = record[idx].trim_ascii();
            let (x, _) = number(cell, header.decimal_comma).map_err(|r| cell_err(idx, r))?;
            rows.channels[k].push(x);
        }
        rows.lines.push(line);
    }
    Ok(rows)
}

fn csv_error(path: &Path, e: ::csv::Error, base_line: u64) -> Error {
    let line = e
        .position()
        .map(|p| (p.line() + base_line - 1) as usize)
        .unwrap_or(0);
    let reason = match e.kind() {
        ::csv::ErrorKind::Utf8 { .. } => "text that is not UTF-8".to_string(),
        ::csv::ErrorKind::Io(io) => io.to_string(),
        _ => crate::recording::io::contain::detail(&e),
    };
    Error::Parse {
        path: path.to_path_buf(),
        line,
        column: None,
        reason,
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
                "no column '{}' for {what}; the header has: {}",
                excerpt(name),
                super::names::list(&header.columns)
            ),
        };
        let time = match (&opts.time, opts.ignore_time) {
            (_, true) => None,
            (Some(name), false) => Some(find(name)?.ok_or_else(|| missing("time", name))?),
            (None, false) => match find(TIME_COLUMN)? {
                Some(i) => Some(i),
                None => header.columns.iter().position(|c| is_time_name(c)),
            },
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
                    super::names::list(&header.columns)
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
                        excerpt(&header.columns[idx])
                    ),
                ));
            }
        }
        Ok(Self { time, channels })
    }
}

/// Parses one trimmed cell: its value (NaN for an empty cell; `NaN` and
/// `inf` as written) and its printed decimals ([`decimals`]).
fn number(cell: &[u8], decimal_comma: bool) -> std::result::Result<(f64, i32), String> {
    if cell.is_empty() {
        return Ok((f64::NAN, i32::MIN));
    }
    let text = std::str::from_utf8(cell)
        .map_err(|_| format!("'{}' is not a number", excerpt_bytes(cell)))?;
    let replaced;
    let t = if decimal_comma && text.contains(',') {
        if text.contains('.') || text.matches(',').count() > 1 {
            return Err(format!(
                "'{}' is not a number (with a decimal comma, '.' and a second ',' are not allowed)",
                excerpt(text)
            ));
        }
        replaced = text.replacen(',', ".", 1);
        &replaced
    } else {
        text
    };
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok((x, decimals(t.as_bytes()))),
        Ok(x) => Ok((x, i32::MIN)),
        Err(_) => {
            let hint = if !decimal_comma && text.contains(',') {
                " (a decimal comma? set decimal comma to read '1,5' as 1.5)"
            } else {
                ""
            };
            Err(format!("'{}' is not a number{hint}", excerpt(text)))
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

/// What a text file holds, for `inspect`: its layout and one line per column.
pub(crate) fn contents(
    path: &Path,
    bytes: &[u8],
    format: Format,
    opts: &LoadOptions,
    limit: usize,
) -> Result<Vec<(String, String)>> {
    let l = layout(path, bytes, format, opts)?;
    let h = &l.header;
    let plan = Plan::new(path, h, opts).ok();
    let mut out = Vec::new();
    let delim = match h.delimiter {
        b'\t' => "tab".to_string(),
        d => format!("'{}'", char::from(d)),
    };
    out.push((
        format!("line {}", h.line),
        format!(
            "header of {} columns, delimiter {delim}{}{}",
            h.columns.len(),
            if h.decimal_comma {
                ", decimal comma"
            } else {
                ""
            },
            h.units
                .as_ref()
                .map(|(_, line)| format!(", units row at line {line}"))
                .unwrap_or_default()
        ),
    ));
    if let Some(first) = h.preamble.first() {
        out.push((
            format!("lines 1-{}", h.line - 1),
            format!("{} metadata line(s), the first: {first}", h.preamble.len()),
        ));
    }
    for (i, name) in h.columns.iter().enumerate().take(limit) {
        let unit = h
            .units
            .as_ref()
            .and_then(|(u, _)| u.get(i).filter(|u| !u.is_empty()).cloned())
            .or_else(|| units::unit_of_name(name).map(str::to_string));
        let used = plan.as_ref().and_then(|p| {
            if p.time == Some(i) {
                Some("time".to_string())
            } else {
                p.channels
                    .iter()
                    .find(|&&(_, j)| j == i)
                    .map(|(c, _)| c.column_name().to_string())
            }
        });
        out.push((
            excerpt(name),
            format!(
                "column {}{}{}",
                i + 1,
                unit.map(|u| format!(", unit {}", excerpt(&u)))
                    .unwrap_or_default(),
                used.map(|u| format!(", read as {u}")).unwrap_or_default()
            ),
        ));
    }
    Ok(out)
}

/// For the fuzz harness: whether the fast path, when it reads `bytes` at
/// all, reads exactly what the general reader reads (values bit for bit,
/// each row's line, time decimals). `Err` says how they differ.
///
/// # Errors
/// A description of the first difference.
#[doc(hidden)]
pub fn check_fast_path_agrees(bytes: &[u8]) -> std::result::Result<(), String> {
    let path = Path::new("fuzz.csv");
    let opts = LoadOptions::default();
    let Ok(l) = layout(path, bytes, Format::Csv, &opts) else {
        return Ok(());
    };
    let Ok(plan) = Plan::new(path, &l.header, &opts) else {
        return Ok(());
    };
    let d = Dialect {
        delimiter: l.header.delimiter,
        decimal_comma: l.header.decimal_comma,
    };
    if l.quoted_head {
        return Ok(());
    }
    let Some(fast) = fast_rows(l.body, l.body_line, l.header.columns.len(), &plan, d, 4) else {
        return Ok(());
    };
    let slow = reader_rows(path, &l, &plan, 4)
        .map_err(|e| format!("the fast path read it, the general reader failed: {e}"))?;
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    if fast.lines != slow.lines {
        return Err(format!(
            "lines differ: {:?} vs {:?}",
            fast.lines, slow.lines
        ));
    }
    if fast.time_decimals != slow.time_decimals {
        return Err("time decimals differ".into());
    }
    if bits(&fast.time) != bits(&slow.time) {
        return Err("time values differ".into());
    }
    for (a, b) in fast.channels.iter().zip(&slow.channels) {
        if bits(a) != bits(b) {
            return Err("channel values differ".into());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
