//! The fast path of the text reader: the common file read without the
//! general CSV reader.
//!
//! It handles no quote anywhere, lines ended by `\n` or `\r\n`, every row
//! with as many fields as the header and every used cell a finite number;
//! it returns `None` as soon as anything else is met, and the caller then
//! reads the file with the general reader, which gives the same values for
//! such files and the precise error (or gap) for the others. Blank lines and
//! `#` lines are skipped as that reader does. The two are checked against
//! each other in the tests here and by the fuzz harness
//! ([`super::check_fast_path_agrees`]).

use super::{decimals, number, Plan, Rows};

/// Bodies at least this long are parsed in two halves in parallel.
pub(super) const PARALLEL_BYTES: usize = 1 << 18;

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

/// How the rows are written.
#[derive(Debug, Clone, Copy)]
pub(super) struct Dialect {
    /// Field delimiter.
    pub delimiter: u8,
    /// `,` is the decimal separator.
    pub decimal_comma: bool,
}

/// The rows of `text` (the body after the header and any units row; its
/// first line is file line `first_line`), or `None` for anything the fast
/// path does not handle.
///
/// A plain body (no `\r`, no `#`, no blank line before the end) is parsed
/// as two halves split at a line end, in parallel; the halves' rows are
/// then joined, so the result is the same as one pass.
pub(super) fn fast_rows(
    text: &[u8],
    first_line: u64,
    ncols: usize,
    plan: &Plan,
    d: Dialect,
    n_est: usize,
) -> Option<Rows> {
    // Which used value each field feeds: time, channel k, or nothing.
    let role = roles(ncols, plan, d)?;
    let mid = text.len() / 2;
    let split = (text.len() >= PARALLEL_BYTES)
        .then(|| text[mid..].iter().position(|&b| b == b'\n'))
        .flatten()
        .map(|p| mid + p + 1)
        .filter(|&s| s < text.len());
    let whole = || rows_of(text, first_line, &role, d, plan, n_est).map(|(rows, _)| rows);
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
        || rows_of(&text[..split], first_line, &role, d, plan, n_est),
        || rows_of(&text[split..], 0, &role, d, plan, n_est / 2 + 1),
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

/// The rows of `text` when every line is a plain row ended by `\n` (no
/// blank, comment or `\r\n` line; the last may lack its `\n`); `None`
/// otherwise. One piece of a long file ([`super::stream`]).
pub(super) fn plain_rows(
    text: &[u8],
    first_line: u64,
    ncols: usize,
    plan: &Plan,
    d: Dialect,
    n_est: usize,
) -> Option<Rows> {
    let role = roles(ncols, plan, d)?;
    match rows_of(text, first_line, &role, d, plan, n_est)? {
        (rows, true) => Some(rows),
        (_, false) => None,
    }
}

/// What each field feeds, or `None` for a delimiter the fast path does not
/// handle.
fn roles(ncols: usize, plan: &Plan, d: Dialect) -> Option<Vec<Role>> {
    let delimiter = d.delimiter;
    if delimiter == b'\r' || delimiter == b'\n' || delimiter == b'#' || !delimiter.is_ascii() {
        return None;
    }
    let mut role = vec![Role::Unused; ncols];
    if let Some(ti) = plan.time {
        role[ti] = Role::Time;
    }
    for (k, &(_, idx)) in plan.channels.iter().enumerate() {
        role[idx] = Role::Channel(k);
    }
    Some(role)
}

/// The rows of `text` (whole lines; its first line is file line
/// `first_line`) and whether every line was a row ended by `\n` (no blank,
/// comment or `\r\n` line); `None` for anything it does not handle. One
/// pass: the cells are parsed where they start, and each row must end where
/// its last cell does.
fn rows_of(
    text: &[u8],
    first_line: u64,
    role: &[Role],
    d: Dialect,
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
        let used = parse_row(&text[pos..], role, d, &mut rows)?;
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
fn parse_row(text: &[u8], role: &[Role], d: Dialect, rows: &mut Rows) -> Option<usize> {
    let delimiter = d.delimiter;
    let is_end = |b: u8| b == b'\n' || b == b'\r';
    let field_len = |from: usize| {
        text[from..]
            .iter()
            .position(|&b| b == delimiter || is_end(b))
            .unwrap_or(text.len() - from)
    };
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
            let len = field_len(i);
            if !plain_text(&text[i..i + len]) {
                return None;
            }
            i += len;
            continue;
        }
        let (x, dec) = if d.decimal_comma {
            // The whole field, as the general reader sees it.
            let len = field_len(i);
            let cell = &text[i..i + len];
            if !plain_text(cell) {
                return None;
            }
            i += len;
            number(cell.trim_ascii(), true).ok()?
        } else {
            // Cells are trimmed of white space, as the general path does.
            let blank = |b: u8| b != delimiter && b.is_ascii_whitespace() && !is_end(b);
            i += text[i..].iter().take_while(|&&b| blank(b)).count();
            let (x, used) = fast_float2::parse_partial::<f64, _>(&text[i..]).ok()?;
            let cell = &text[i..i + used];
            i += used;
            i += text[i..].iter().take_while(|&&b| blank(b)).count();
            (x, decimals(cell))
        };
        if !x.is_finite() {
            return None;
        }
        match r {
            Role::Time => {
                rows.time.push(x);
                rows.time_decimals = rows.time_decimals.max(dec);
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
