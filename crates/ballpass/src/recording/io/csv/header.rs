//! Where a text recording's header is, and how its rows are written: the
//! preamble skipped, the header line, the units row, the delimiter and the
//! decimal separator (the rules in the module docs of [`super`]).

use std::path::Path;

use super::*;

/// Reads the header of a text recording (for `inspect` and error hints).
///
/// # Errors
/// As `super::load` for an empty or binary file or a malformed first row.
pub fn read_header(
    path: &Path,
    bytes: &[u8],
    format: Format,
    opts: &LoadOptions,
) -> Result<Header> {
    layout(path, bytes, format, opts).map(|l| l.header)
}

/// Finds the header, the units row and the body; detects the delimiter and
/// the decimal separator.
pub(super) fn layout<'a>(
    path: &Path,
    bytes: &'a [u8],
    format: Format,
    opts: &LoadOptions,
) -> Result<Layout<'a>> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    check_text(path, bytes)?;
    let given = opts.delimiter.or((format == Format::Tsv).then_some(b'\t'));
    let (start, line_offset, preamble) = find_header(bytes, opts, given);
    let text = &bytes[start..];
    let delimiter = given.unwrap_or_else(|| sniff_delimiter(text));
    let mut rdr = reader(text, delimiter);
    let mut record = ::csv::ByteRecord::new();
    let base = line_offset + 1;
    if !rdr
        .read_byte_record(&mut record)
        .map_err(|e| csv_error(path, e, base))?
    {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "no header row (the file holds only comments or blank lines); expected \
                     a header such as time_s,friction_N,position_mm,optical_V"
                .into(),
        });
    }
    let columns: Vec<String> = record
        .iter()
        .map(|f| String::from_utf8_lossy(f.trim_ascii()).into_owned())
        .collect();
    let line = record.position().map(|p| p.line()).unwrap_or(1) + line_offset;
    let after = rdr.position().clone();
    let mut body_start = start + after.byte() as usize;
    let mut body_line = after.line() + line_offset;
    let mut quoted_head = bytes[..body_start].contains(&b'"');
    let mut header = Header {
        columns,
        delimiter,
        line,
        preamble,
        units: None,
        decimal_comma: false,
    };
    let plan = Plan::new(path, &header, opts)?;
    let used: Vec<usize> = plan
        .time
        .into_iter()
        .chain(plan.channels.iter().map(|&(_, i)| i))
        .collect();
    // A units row: every used cell is text, none a number.
    let mut rows = reader(&bytes[body_start..], delimiter);
    if rows.read_byte_record(&mut record).unwrap_or(false) && record.len() == header.columns.len() {
        let cells: Vec<&[u8]> = used.iter().map(|&i| record[i].trim_ascii()).collect();
        let numeric = |c: &[u8]| number(c, false).is_ok() || number(c, true).is_ok();
        if cells.iter().any(|c| !c.is_empty())
            && cells.iter().all(|c| c.is_empty() || !numeric(c))
            && cells.iter().all(|c| c.len() <= 32)
        {
            let units_line = record.position().map(|p| p.line()).unwrap_or(1) + body_line - 1;
            let units = record
                .iter()
                .map(|f| {
                    String::from_utf8_lossy(f.trim_ascii())
                        .trim_matches(|c| c == '[' || c == ']' || c == '(' || c == ')')
                        .trim()
                        .to_string()
                })
                .collect();
            header.units = Some((units, units_line));
            let p = rows.position();
            body_line += p.line() - 1;
            body_start += p.byte() as usize;
            quoted_head = bytes[..body_start].contains(&b'"');
        }
    }
    header.decimal_comma = match opts.decimal_comma {
        Some(d) => d,
        None => delimiter != b',' && sniff_decimal_comma(&bytes[body_start..], delimiter, &used),
    };
    Ok(Layout {
        header,
        body: &bytes[body_start..],
        body_line,
        quoted_head,
    })
}

/// Where the header line starts, the lines before it, and the metadata
/// lines among those (see the module doc).
fn find_header(bytes: &[u8], opts: &LoadOptions, given: Option<u8>) -> (usize, u64, Vec<String>) {
    let mut wanted: Vec<String> = Channel::ALL
        .iter()
        .map(|&c| {
            opts.source(c)
                .name
                .clone()
                .unwrap_or_else(|| c.column_name().to_string())
        })
        .collect();
    wanted.push(opts.time.clone().unwrap_or_else(|| TIME_COLUMN.into()));
    let names_wanted = |line: &[u8]| {
        let d = given.unwrap_or_else(|| sniff_delimiter(line));
        line.split(|&b| b == d).any(|cell| {
            let cell = String::from_utf8_lossy(cell.trim_ascii());
            let cell = cell.trim_matches('"').trim();
            wanted.iter().any(|w| w.trim().eq_ignore_ascii_case(cell)) || is_time_name(cell)
        })
    };
    // Start and number of each line looked at that is not blank or a comment.
    let mut candidates: Vec<(usize, u64)> = Vec::new();
    let mut pos = 0;
    let mut line_no = 0u64;
    let mut found = None;
    while pos < bytes.len() && (line_no as usize) <= MAX_PREAMBLE_LINES && pos <= MAX_PREAMBLE_BYTES
    {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |e| pos + e + 1);
        let line = bytes[pos..end].trim_ascii();
        if !line.is_empty() && !line.starts_with(b"#") {
            let skipped = opts.skip_lines.is_some_and(|k| (line_no as usize) < k);
            if !skipped && (opts.skip_lines.is_some() || names_wanted(line)) {
                found = Some((pos, line_no));
                break;
            }
            candidates.push((pos, line_no));
        }
        pos = end;
        line_no += 1;
    }
    let (start, line) = match (found, opts.skip_lines) {
        (Some(f), _) => f,
        // Nothing names a wanted column: the first line is the header (its
        // error then lists what it has).
        (None, None) => candidates.first().copied().unwrap_or((pos, line_no)),
        (None, Some(_)) => (pos.min(bytes.len()), line_no),
    };
    let preamble = candidates
        .iter()
        .filter(|&&(p, _)| p < start)
        .map(|&(p, _)| {
            let end = bytes[p..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(bytes.len(), |e| p + e);
            excerpt_bytes(bytes[p..end].trim_ascii())
        })
        .collect();
    (start, line, preamble)
}

/// `time`, `t`, `zeit` or `timestamp` with a time unit (`time_ms`, `t [s]`).
pub(super) fn is_time_name(cell: &str) -> bool {
    let Some(unit) = units::unit_of_name(cell) else {
        return false;
    };
    let word: String = cell
        .chars()
        .take_while(|c| c.is_alphabetic())
        .collect::<String>()
        .to_lowercase();
    TimeUnit::parse(unit).is_some() && matches!(word.as_str(), "time" | "t" | "zeit" | "timestamp")
}

/// Whether the first rows' used cells write numbers with `,` and never `.`.
fn sniff_decimal_comma(body: &[u8], delimiter: u8, used: &[usize]) -> bool {
    let mut rdr = reader(body, delimiter);
    let mut record = ::csv::ByteRecord::new();
    let (mut comma, mut dot) = (false, false);
    for _ in 0..SNIFF_ROWS {
        if !rdr.read_byte_record(&mut record).unwrap_or(false) {
            break;
        }
        for &i in used {
            if let Some(cell) = record.get(i) {
                let mantissa = cell
                    .split(|&b| b == b'e' || b == b'E')
                    .next()
                    .unwrap_or(cell);
                comma |= mantissa.contains(&b',');
                dot |= mantissa.contains(&b'.');
            }
        }
    }
    comma && !dot
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
    if let Some(f) = Format::sniff(head) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: format!(
                "this is a {} file, not text: name it .{} or read it as format {}",
                match f {
                    Format::Tdms => "TDMS",
                    Format::Mf4 => "MDF 4",
                    _ => "MATLAB MAT-",
                }
                .trim_end_matches('-'),
                f.name(),
                f.name()
            ),
        });
    }
    if head.contains(&0) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "binary file, not delimited text; expected a CSV/TSV header row".into(),
        });
    }
    Ok(())
}

/// The most frequent of `,` `;` tab in the header line (`,` when none).
pub(super) fn sniff_delimiter(bytes: &[u8]) -> u8 {
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
