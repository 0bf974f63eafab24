//! MATLAB MAT-files: level 5 (`-v6`/`-v7`, scipy's `savemat`, dSPACE
//! ControlDesk) and v7.3 (HDF5), read into the same tree of values.
//!
//! Where a channel comes from:
//!
//! - **plain variables**: numeric vectors named `time_s`, `friction_N`,
//!   `position_mm`, `optical_V` (ignoring case) or the names in
//!   [`LoadOptions`];
//! - **struct fields by path**: a name such as `bearing.gs`, `rec.Y(2).Data`
//!   or `c{3}` walks structs (`.field`, `(k)` for element `k` of a struct
//!   array) and cells (`{k}`); [`LoadOptions::fs_from`] names a scalar the
//!   same way (`bearing.sr`) to give the sampling rate;
//! - **ControlDesk**: a struct variable `rec` with `rec.X.Data` the time and
//!   `rec.Y(i).Name` / `.Data` the signals. A channel name matches a signal's
//!   whole `Name` (a block path such as `Model Root/Load cell/Force`) or its
//!   last `/`-separated part (`Force`) when only one signal has it.
//!
//! Plain variables and paths win when any of them matches a channel.
//!
//! Any real numeric class (double, single, integers, logical) is converted
//! to `f64`; a matrix that is not a vector, complex or sparse data, text or
//! an object is an error naming the variable and what it is.
//!
//! The level-5 parser is our own (`v5`): its time and memory are bounded
//! by the file (nesting depth, every length checked against its container,
//! compressed variables inflated only when used and never nested). v7.3
//! files are read with `hdf5-reader` (`v73`) with its panics contained.

use std::path::Path;

use super::names::{self, Candidate};
use super::{LoadOptions, Locator, RawColumn, RawTable};
use crate::error::{excerpt, Error, Result};
use crate::recording::Channel;

pub mod stream;
mod tree;
pub(crate) mod v5;
pub(crate) mod v73;
mod write;

pub use write::write_mat;

use tree::{leaves, parse_path, walk, Value};
use v5::V5File;
use v73::V73File;

const V73_MAGIC: &[u8] = b"MATLAB 7.3 MAT-file";
const HDF5_MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";

/// Most paths listed in a message or a listing.
const LIST_LIMIT: usize = 200;

fn format_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// A MAT-file of either kind.
enum File<'a> {
    V5(V5File<'a>),
    V73(V73File),
}

impl<'a> File<'a> {
    fn open(path: &Path, bytes: &'a [u8]) -> Result<Self> {
        if is_v73(bytes) {
            return V73File::open(bytes)
                .map(File::V73)
                .map_err(|r| format_err(path, format!("MATLAB v7.3 (HDF5) MAT-file: {r}")));
        }
        if !bytes.starts_with(v5::V5_MAGIC) {
            return Err(format_err(path, not_a_mat_file(bytes)));
        }
        V5File::open(bytes)
            .map(File::V5)
            .map_err(|r| format_err(path, r))
    }

    fn names(&self) -> Vec<&str> {
        match self {
            File::V5(f) => f.vars.iter().map(|v| v.name.as_str()).collect(),
            File::V73(f) => f.vars.iter().map(|(n, _)| n.as_str()).collect(),
        }
    }

    /// Whether variable `i` is a struct, without parsing it.
    fn is_struct(&self, i: usize) -> bool {
        match self {
            File::V5(f) => f.vars[i].class == 2,
            File::V73(f) => matches!(f.vars[i].1, Value::Struct(_)),
        }
    }

    /// Whether variable `i` is a numeric vector, without parsing it.
    fn is_numeric_vector(&self, i: usize) -> bool {
        match self {
            File::V5(f) => {
                let v = &f.vars[i];
                (6..=15).contains(&v.class)
                    && !v.complex
                    && v.dims.iter().filter(|&&d| d > 1).count() <= 1
            }
            File::V73(f) => f.vars[i].1.as_vector().is_some(),
        }
    }

    fn value(&self, i: usize) -> std::result::Result<&Value, String> {
        match self {
            File::V5(f) => f.value(i),
            File::V73(f) => Ok(&f.vars[i].1),
        }
    }

    fn numbers(&self, n: &tree::Numeric) -> std::result::Result<Vec<f64>, String> {
        match (&n.data, self) {
            (tree::Data::V5(span), File::V5(f)) => f.numbers(span),
            (tree::Data::H5(d), _) => d.numbers(),
            (tree::Data::V5(_), File::V73(_)) => Err("level-5 data in a v7.3 file".into()),
        }
    }
}

/// Whether a file starting with `head` (its first 520 bytes or more) is a
/// v7.3 (HDF5) MAT-file.
fn is_v73(head: &[u8]) -> bool {
    head.starts_with(V73_MAGIC)
        || head.get(512..520) == Some(HDF5_MAGIC)
        || head.starts_with(HDF5_MAGIC)
}

/// Why bytes that do not start like a level-5 MAT-file are not one.
fn not_a_mat_file(bytes: &[u8]) -> String {
    let head = &bytes[..bytes.len().min(256)];
    let texty = !head.is_empty()
        && head
            .iter()
            .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace() || b >= 0x80);
    if bytes.is_empty() {
        "file is empty; expected a MATLAB MAT-file".to_string()
    } else if bytes.starts_with(b"MATLAB") {
        "damaged MAT-file header (expected 'MATLAB 5.0 MAT-file' or 'MATLAB 7.3 MAT-file')"
            .to_string()
    } else if texty {
        let first = String::from_utf8_lossy(head);
        let first = first.lines().next().unwrap_or("").trim();
        format!(
            "not a MAT-file but text (starts with '{}'): it looks like a CSV file; \
             name it .csv or read it as format csv",
            excerpt(&first.chars().take(40).collect::<String>())
        )
    } else {
        "not a MATLAB MAT-file (no 'MATLAB 5.0 MAT-file' header)".to_string()
    }
}

/// Where a channel's numbers are: a value, its path for messages, and the
/// unit the file states for it.
struct Found<'v> {
    label: String,
    value: &'v Value,
    unit: Option<String>,
}

/// Parses a MAT-file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let file = File::open(path, bytes)?;
    parse_file(path, &file, opts, &mut |file, n, _| file.numbers(n))
}

/// What [`parse_file`] reads a vector for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Channel(Channel),
    Time,
    Rate,
}

/// How [`parse_file`] reads the numbers of a vector it found: all of them
/// ([`File::numbers`]), or, streamed, the first block of a channel or time.
type ReadNumbers<'r> =
    dyn FnMut(&File<'_>, &tree::Numeric, Role) -> std::result::Result<Vec<f64>, String> + 'r;

/// [`parse`] of an open file, its numbers read by `read`.
fn parse_file(
    path: &Path,
    file: &File<'_>,
    opts: &LoadOptions,
    read: &mut ReadNumbers<'_>,
) -> Result<RawTable> {
    let err = |r: String| format_err(path, r);
    let names = file.names();
    let wanted: Vec<String> = Channel::ALL
        .iter()
        .map(|&c| {
            opts.source(c)
                .name
                .clone()
                .unwrap_or_else(|| c.column_name().to_string())
        })
        .collect();

    // ControlDesk recordings: struct variables with fields X and Y.
    let mut controldesk = Vec::new();
    for i in 0..names.len() {
        if file.is_struct(i) {
            let v = file.value(i).map_err(err)?;
            if let Some(s) = v.as_struct() {
                if s.single().is_some() && s.field(0, "X").is_some() && s.field(0, "Y").is_some() {
                    controldesk.push(i);
                }
            }
        }
    }
    let mut plain_hit = false;
    for w in &wanted {
        if plain(file, w).map_err(err)?.is_some() {
            plain_hit = true;
        }
    }
    let layout = if plain_hit || controldesk.is_empty() {
        Layout::Plain
    } else if controldesk.len() > 1 {
        let list: Vec<String> = controldesk.iter().map(|&i| names[i].to_string()).collect();
        return Err(err(format!(
            "{} ControlDesk recordings in one file ({}); expected one",
            list.len(),
            names::list(&list)
        )));
    } else {
        let i = controldesk[0];
        Layout::ControlDesk(i, controldesk_signals(file, i).map_err(err)?)
    };
    let lookup = |want: &str| -> Result<Option<Found<'_>>> {
        match &layout {
            Layout::Plain => plain(file, want).map_err(err),
            Layout::ControlDesk(_, signals) => {
                let cands: Vec<Candidate> = signals
                    .iter()
                    .map(|s| Candidate::new(s.name.clone()))
                    .collect();
                match names::find(&cands, want).map_err(err)? {
                    Some(k) => Ok(Some(Found {
                        label: signals[k].label.clone(),
                        value: signals[k].data,
                        unit: signals[k].unit.clone(),
                    })),
                    None => plain(file, want).map_err(err),
                }
            }
        }
    };
    let what = match layout {
        Layout::Plain => "variable",
        Layout::ControlDesk(..) => "signal",
    };
    let has = || listing(file, &layout);

    let mut channels = Vec::new();
    for (k, &c) in Channel::ALL.iter().enumerate() {
        match lookup(&wanted[k])? {
            Some(f) => channels.push((c, column(file, &f, Role::Channel(c), read).map_err(err)?)),
            None if opts.source(c).name.is_some() => {
                return Err(err(format!(
                    "no {what} '{}' for {}; the file has: {}",
                    excerpt(&wanted[k]),
                    c.column_name(),
                    has()
                )))
            }
            None => {}
        }
    }
    if channels.is_empty() {
        return Err(err(format!(
            "no channel found; expected {what}s friction_N, position_mm or optical_V \
             (or mapped names, struct fields such as 'bearing.gs'); the file has: {}",
            has()
        )));
    }
    let n = channels[0].1.values.len();
    for (c, col) in &channels[1..] {
        if col.values.len() != n {
            return Err(err(format!(
                "'{}' ({}) has {} samples but '{}' has {n}",
                col.name,
                c.column_name(),
                col.values.len(),
                channels[0].1.name
            )));
        }
    }
    let time = if opts.ignore_time {
        None
    } else {
        match (&opts.time, &layout) {
            (Some(name), _) => Some(lookup(name)?.ok_or_else(|| {
                err(format!(
                    "no {what} '{}' for time; the file has: {}",
                    excerpt(name),
                    has()
                ))
            })?),
            (None, Layout::Plain) => lookup(super::csv::TIME_COLUMN)?,
            (None, Layout::ControlDesk(i, _)) => {
                let rec = file.value(*i).map_err(err)?;
                let x = rec
                    .as_struct()
                    .and_then(|s| s.field(0, "X"))
                    .and_then(Value::as_struct)
                    .and_then(|x| x.field(0, "Data"));
                let name = excerpt(names[*i]);
                let unit = rec
                    .as_struct()
                    .and_then(|s| s.field(0, "X"))
                    .and_then(Value::as_struct)
                    .and_then(|x| match x.field(0, "Unit") {
                        Some(Value::Text(t)) if !t.trim().is_empty() => Some(t.trim().to_string()),
                        _ => None,
                    });
                Some(Found {
                    unit,
                    label: format!("{name}.X.Data"),
                    value: x.ok_or_else(|| {
                        err(format!(
                            "ControlDesk recording '{name}' has no time vector {name}.X.Data"
                        ))
                    })?,
                })
            }
        }
    };
    // The time's unit: from its name (`time_ms`) or ControlDesk's X.Unit.
    let time_unit = time.as_ref().and_then(|f| {
        let (unit, from) = match &f.unit {
            Some(u) => (super::TimeUnit::parse(u), format!("Unit of '{}'", f.label)),
            None => (
                super::TimeUnit::of_name(&f.label),
                format!("the name '{}'", f.label),
            ),
        };
        unit.map(|u| (u, from))
    });
    let time = time
        .map(|f| column(file, &Found { unit: None, ..f }, Role::Time, read))
        .transpose()
        .map_err(err)?;
    let stated_rate = match &opts.fs_from {
        None => None,
        Some(name) => {
            let f = lookup(name)?.ok_or_else(|| {
                err(format!(
                    "no {what} '{}' for the sampling rate (fs_from); the file has: {}",
                    excerpt(name),
                    has()
                ))
            })?;
            let col = column(file, &f, Role::Rate, read).map_err(err)?;
            match col.values.as_slice() {
                [fs] => Some((*fs, format!("variable '{}'", f.label))),
                v => {
                    return Err(err(format!(
                        "'{}' for the sampling rate holds {} values; expected one number (Hz)",
                        f.label,
                        v.len()
                    )))
                }
            }
        }
    };
    Ok(RawTable {
        time,
        time_unit,
        channels,
        locator: Locator::Samples,
        stated_rate,
        ..RawTable::default()
    })
}

enum Layout<'v> {
    Plain,
    /// The recording's variable and its signals.
    ControlDesk(usize, Vec<Signal<'v>>),
}

/// A ControlDesk signal: `Y(k).Name`, `Y(k).Data` and `Y(k).Unit`.
struct Signal<'v> {
    name: String,
    label: String,
    data: &'v Value,
    unit: Option<String>,
}

fn controldesk_signals<'v>(
    file: &'v File<'_>,
    i: usize,
) -> std::result::Result<Vec<Signal<'v>>, String> {
    let rec = file.value(i)?;
    let name = excerpt(file.names()[i]);
    let Some(y) = rec
        .as_struct()
        .and_then(|s| s.field(0, "Y"))
        .and_then(Value::as_struct)
    else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for k in 0..y.elems.len() {
        let Some(data) = y.field(k, "Data") else {
            continue;
        };
        let full = match y.field(k, "Name") {
            Some(Value::Text(t)) => t.clone(),
            _ => String::new(),
        };
        let unit = match y.field(k, "Unit") {
            Some(Value::Text(t)) if !t.trim().is_empty() => Some(t.trim().to_string()),
            _ => None,
        };
        out.push(Signal {
            label: format!("{name}.Y({}).Data '{}'", k + 1, excerpt(&full)),
            name: full,
            data,
            unit,
        });
    }
    Ok(out)
}

/// A top-level variable named `want`, or the value at a path such as `bearing.gs`.
fn plain<'v>(file: &'v File<'_>, want: &str) -> std::result::Result<Option<Found<'v>>, String> {
    let names = file.names();
    let want = want.trim();
    if let Some(i) = names.iter().position(|n| n.eq_ignore_ascii_case(want)) {
        return Ok(Some(Found {
            label: excerpt(names[i]),
            value: file.value(i)?,
            unit: None,
        }));
    }
    let Some((head, steps)) = parse_path(want) else {
        return Ok(None);
    };
    if steps.is_empty() {
        return Ok(None);
    }
    let Some(i) = names.iter().position(|n| n.eq_ignore_ascii_case(&head)) else {
        return Ok(None);
    };
    let v = walk(file.value(i)?, &steps).map_err(|r| format!("'{}': {r}", excerpt(want)))?;
    Ok(Some(Found {
        label: excerpt(want),
        value: v,
        unit: None,
    }))
}

/// What the file holds that could be a channel, for messages.
fn listing(file: &File<'_>, layout: &Layout<'_>) -> String {
    let mut out: Vec<String> = Vec::new();
    if let Layout::ControlDesk(_, signals) = layout {
        out.extend(signals.iter().map(|s| s.name.clone()));
    }
    for (i, name) in file.names().iter().enumerate() {
        if file.is_numeric_vector(i) {
            out.push(name.to_string());
        } else if file.is_struct(i) {
            if let Ok(v) = file.value(i) {
                for (p, v) in leaves(name, v, LIST_LIMIT) {
                    if v.as_vector().is_some() {
                        out.push(p);
                    }
                }
            }
        }
        if out.len() >= LIST_LIMIT {
            break;
        }
    }
    if out.is_empty() {
        return "no numeric vectors".into();
    }
    names::list(&out)
}

/// Converts a found value to a column of `f64`.
fn column(
    file: &File<'_>,
    f: &Found<'_>,
    role: Role,
    read: &mut ReadNumbers<'_>,
) -> std::result::Result<RawColumn, String> {
    let bad = |what: String| format!("variable '{}' {what}", f.label);
    let n = match f.value {
        Value::Numeric(n) => n,
        Value::Text(_) => return Err(bad("is text; expected a numeric vector".into())),
        Value::Struct(s) => {
            return Err(bad(format!(
                "is a struct; name a field, as in '{}.{}'",
                f.label,
                s.fields.first().map(|s| excerpt(s)).unwrap_or_default()
            )))
        }
        Value::Cell { .. } => {
            return Err(bad(format!(
                "is a cell array; name a cell, as in '{}{{1}}'",
                f.label
            )))
        }
        Value::Other { class, why, .. } => {
            return Err(bad(format!("is {} ({why})", excerpt(class))))
        }
    };
    if f.value.as_vector().is_none() {
        return Err(bad(format!(
            "is a {} matrix; expected a vector (one row or one column)",
            tree::dims_text(&n.dims)
        )));
    }
    let values = read(file, n, role).map_err(|r| bad(format!("cannot be read: {r}")))?;
    Ok(RawColumn {
        name: f.label.clone(),
        values,
        resolution: 0.0,
        unit: f
            .unit
            .as_ref()
            .map(|u| (u.clone(), format!("Unit of '{}'", f.label))),
    })
}

/// One line per thing a MAT-file holds (path and what it is), at most
/// `limit` lines, for `inspect`.
pub(crate) fn contents(path: &Path, bytes: &[u8], limit: usize) -> Result<Vec<(String, String)>> {
    let file = File::open(path, bytes)?;
    let mut out = Vec::new();
    for (i, name) in file.names().iter().enumerate() {
        match file.value(i) {
            Ok(v) => {
                for (p, v) in leaves(name, v, limit.saturating_sub(out.len())) {
                    out.push((p, v.describe()));
                }
            }
            Err(r) => out.push((name.to_string(), format!("unreadable: {r}"))),
        }
        if out.len() >= limit {
            break;
        }
    }
    Ok(out)
}
