//! MATLAB MAT-files, level 5 (what MATLAB's `save -v7`/`-v6`, scipy's
//! `savemat` and dSPACE ControlDesk write).
//!
//! Two layouts are read:
//!
//! - **plain variables**: numeric vectors named `time_s`, `friction_N`,
//!   `position_mm`, `optical_V` (ignoring case) or the names in
//!   [`LoadOptions`];
//! - **ControlDesk**: a struct variable `rec` with `rec.X.Data` the time and
//!   `rec.Y(i).Name` / `.Data` / `.Unit` the signals. A channel name in
//!   [`LoadOptions`] matches a signal's whole `Name` (a block path such as
//!   `Model Root/Load cell/Force`) or its last `/`-separated part (`Force`).
//!
//! Plain variables win when any of them matches a channel.
//!
//! Any numeric class (double, single, integers, logical) is converted to
//! `f64`; a matrix that is not a vector, complex or sparse data, or text is
//! an error naming the variable.
//!
//! MATLAB v7.3 files are HDF5 containers, which no pure-Rust reader here
//! decodes: they are detected and refused with the advice to save with `-v7`.
//!
//! Parsing is done by the `matrw` crate. A malformed file could make a
//! third-party parser panic: every call into it runs under
//! [`std::panic::catch_unwind`], and a panic becomes [`Error::Format`]. Before
//! that, the top-level structure of the file (128-byte header, then tagged
//! elements whose sizes must fit in the file) is checked here, so that a
//! truncated file is reported as such.

use std::borrow::Cow;
use std::cell::Cell;
use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Once;

use matrw::{MatFile, MatVariable, MatlabType};

use super::{LoadOptions, Locator, RawColumn, RawTable};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};

const HEADER_LEN: usize = 128;
const TEXT_LEN: usize = 116;
const V5_MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";
const V73_MAGIC: &[u8] = b"MATLAB 7.3 MAT-file";
const HDF5_MAGIC: &[u8] = b"\x89HDF\r\n\x1a\n";
const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MX_DOUBLE_CLASS: u32 = 6;

fn format_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

/// Parses a MAT-file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let file = read_matfile(path, bytes)?;
    let vars: Vec<(&String, &MatVariable)> = file.iter().collect();
    let entries = plain_entries(&vars);
    let wanted: Vec<String> = Channel::ALL
        .iter()
        .map(|&c| {
            opts.source(c)
                .name
                .clone()
                .unwrap_or_else(|| c.column_name().to_string())
        })
        .collect();
    let plain_hit = wanted.iter().any(|w| find(&entries, w).is_some());
    let controldesk: Vec<(&String, &matrw::Structure)> = vars
        .iter()
        .filter_map(|&(name, v)| {
            as_struct(v)
                .filter(|s| s.get("X").is_some() && s.get("Y").is_some())
                .map(|s| (name, s))
        })
        .collect();
    let (entries, time_entry, layout) = if plain_hit || controldesk.is_empty() {
        let time = match (&opts.time, opts.ignore_time) {
            (_, true) => None,
            (Some(name), false) => Some(find(&entries, name).ok_or_else(|| {
                format_err(
                    path,
                    format!(
                        "no variable '{name}' for time; the file has: {}",
                        list(&entries)
                    ),
                )
            })?),
            (None, false) => find(&entries, super::csv::TIME_COLUMN),
        }
        .cloned();
        (entries, time, "variables")
    } else {
        if controldesk.len() > 1 {
            let names: Vec<&str> = controldesk.iter().map(|(n, _)| n.as_str()).collect();
            return Err(format_err(
                path,
                format!(
                    "{} ControlDesk recordings in one file ({}); expected one",
                    names.len(),
                    names.join(", ")
                ),
            ));
        }
        let (name, rec) = controldesk[0];
        let (entries, time) = controldesk_entries(path, name, rec)?;
        let time = match (&opts.time, opts.ignore_time) {
            (_, true) => None,
            (Some(t), false) => Some(find(&entries, t).cloned().ok_or_else(|| {
                format_err(
                    path,
                    format!(
                        "no signal '{t}' for time in ControlDesk recording '{name}'; \
                                 it has: {}",
                        list(&entries)
                    ),
                )
            })?),
            (None, false) => Some(time),
        };
        (entries, time, "signals")
    };

    let mut channels = Vec::new();
    for (k, &c) in Channel::ALL.iter().enumerate() {
        match find(&entries, &wanted[k]) {
            Some(e) => channels.push((c, column(path, e)?)),
            None if opts.source(c).name.is_some() => {
                return Err(format_err(
                    path,
                    format!(
                        "no {layout} '{}' for {}; the file has: {}",
                        wanted[k],
                        c.column_name(),
                        list(&entries)
                    ),
                ))
            }
            None => {}
        }
    }
    if channels.is_empty() {
        return Err(format_err(
            path,
            format!(
                "no channel found; expected {layout} friction_N, position_mm or optical_V \
                 (or mapped names); the file has: {}",
                list(&entries)
            ),
        ));
    }
    let n = channels[0].1.values.len();
    for (c, col) in &channels[1..] {
        if col.values.len() != n {
            return Err(format_err(
                path,
                format!(
                    "'{}' ({}) has {} samples but '{}' has {n}",
                    col.name,
                    c.column_name(),
                    col.values.len(),
                    channels[0].1.name
                ),
            ));
        }
    }
    let time = time_entry.map(|e| column(path, &e)).transpose()?;
    Ok(RawTable {
        time,
        channels,
        locator: Locator::Samples,
    })
}

/// A numeric array that may feed a channel, with the names it answers to.
#[derive(Clone)]
struct Entry<'a> {
    /// Path for messages (`friction_N`, `rec.Y(2).Data`).
    label: String,
    /// Names it matches, most specific first.
    names: Vec<String>,
    data: &'a MatVariable,
}

fn plain_entries<'a>(vars: &[(&'a String, &'a MatVariable)]) -> Vec<Entry<'a>> {
    vars.iter()
        .filter(|(_, v)| {
            matches!(
                v,
                MatVariable::NumericArray(_) | MatVariable::SparseArray(_)
            )
        })
        .map(|&(name, v)| Entry {
            label: name.clone(),
            names: vec![name.clone()],
            data: v,
        })
        .collect()
}

fn controldesk_entries<'a>(
    path: &Path,
    name: &str,
    rec: &'a matrw::Structure,
) -> Result<(Vec<Entry<'a>>, Entry<'a>)> {
    let x = rec.get("X").and_then(as_struct_or_first);
    let time_data = x.and_then(|x| x.get("Data")).ok_or_else(|| {
        format_err(
            path,
            format!("ControlDesk recording '{name}' has no time vector {name}.X.Data"),
        )
    })?;
    let time = Entry {
        label: format!("{name}.X.Data"),
        names: vec!["time".into()],
        data: time_data,
    };
    let signals: Vec<&matrw::Structure> = match rec.get("Y") {
        Some(MatVariable::StructureArray(a)) => a.value.iter().filter_map(as_struct).collect(),
        Some(MatVariable::Structure(s)) => vec![s],
        _ => Vec::new(),
    };
    let mut entries = Vec::new();
    for (i, s) in signals.into_iter().enumerate() {
        let Some(data) = s.get("Data") else { continue };
        let full = s.get("Name").and_then(string_of).unwrap_or_default();
        let mut names = vec![full.clone()];
        if let Some(last) = full.rsplit('/').next() {
            if last != full {
                names.push(last.trim().to_string());
            }
        }
        entries.push(Entry {
            label: format!("{name}.Y({}).Data '{full}'", i + 1),
            names,
            data,
        });
    }
    Ok((entries, time))
}

/// The entry whose name matches `want` (ignoring case): whole names first,
/// then short names; `None` when nothing or more than one short name matches.
fn find<'e, 'a>(entries: &'e [Entry<'a>], want: &str) -> Option<&'e Entry<'a>> {
    let want = want.trim();
    if let Some(e) = entries
        .iter()
        .find(|e| e.names[0].eq_ignore_ascii_case(want))
    {
        return Some(e);
    }
    let mut short = entries
        .iter()
        .filter(|e| e.names[1..].iter().any(|n| n.eq_ignore_ascii_case(want)));
    match (short.next(), short.next()) {
        (Some(e), None) => Some(e),
        _ => None,
    }
}

fn list(entries: &[Entry<'_>]) -> String {
    if entries.is_empty() {
        return "no numeric variables".into();
    }
    entries
        .iter()
        .map(|e| format!("'{}'", e.names[0]))
        .collect::<Vec<_>>()
        .join(", ")
}

fn as_struct(v: &MatVariable) -> Option<&matrw::Structure> {
    match v {
        MatVariable::Structure(s) => Some(s),
        MatVariable::StructureArray(a) if a.value.len() == 1 => as_struct(&a.value[0]),
        _ => None,
    }
}

fn as_struct_or_first(v: &MatVariable) -> Option<&matrw::Structure> {
    match v {
        MatVariable::StructureArray(a) => a.value.first().and_then(as_struct),
        _ => as_struct(v),
    }
}

fn string_of(v: &MatVariable) -> Option<String> {
    match v {
        MatVariable::NumericArray(a) => match &a.value {
            MatlabType::UTF8(c) | MatlabType::UTF16(c) => Some(c.iter().collect()),
            _ => None,
        },
        _ => None,
    }
}

/// Converts one entry to a column of `f64`.
fn column(path: &Path, e: &Entry<'_>) -> Result<RawColumn> {
    let bad = |what: &str| format_err(path, format!("variable '{}' {what}", e.label));
    let a = match e.data {
        MatVariable::NumericArray(a) => a,
        MatVariable::SparseArray(_) => {
            return Err(bad("is sparse; expected a full numeric vector"))
        }
        _ => return Err(bad("is not numeric; expected a numeric vector")),
    };
    if a.is_complex() {
        return Err(bad("is complex; expected real numbers"));
    }
    let long_dims = a.dim.iter().filter(|&&d| d > 1).count();
    if long_dims > 1 {
        let dims: Vec<String> = a.dim.iter().map(usize::to_string).collect();
        return Err(bad(&format!(
            "is a {} matrix; expected a vector (one row or one column)",
            dims.join("x")
        )));
    }
    fn conv<T: Copy + Into<f64>>(v: &[T]) -> Vec<f64> {
        v.iter().map(|&x| x.into()).collect()
    }
    let values = match &a.value {
        MatlabType::F64(v) => v.clone(),
        MatlabType::F32(v) => conv(v),
        MatlabType::I8(v) => conv(v),
        MatlabType::U8(v) => conv(v),
        MatlabType::I16(v) => conv(v),
        MatlabType::U16(v) => conv(v),
        MatlabType::I32(v) => conv(v),
        MatlabType::U32(v) => conv(v),
        // 64-bit integers above 2^53 round to the nearest double.
        MatlabType::I64(v) => v.iter().map(|&x| x as f64).collect(),
        MatlabType::U64(v) => v.iter().map(|&x| x as f64).collect(),
        MatlabType::BOOL(v) => v.iter().map(|&b| f64::from(u8::from(b))).collect(),
        MatlabType::UTF8(_) | MatlabType::UTF16(_) => {
            return Err(bad("is text; expected a numeric vector"))
        }
    };
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        return Err(bad(&format!(
            "sample {} is {}; expected a finite number",
            i + 1,
            values[i]
        )));
    }
    Ok(RawColumn {
        name: e.label.clone(),
        values,
        resolution: 0.0,
    })
}

/// Checks the container, then hands the bytes to `matrw` with panics contained.
fn read_matfile(path: &Path, bytes: &[u8]) -> Result<MatFile> {
    let bytes = prepare(path, bytes)?;
    match contain_panics(|| matrw::load_matfile_from_u8(&bytes)) {
        Ok(Ok(file)) => Ok(file),
        Ok(Err(e)) => Err(format_err(
            path,
            format!("malformed MAT-file: {}", one_line(&e.to_string())),
        )),
        Err(msg) => Err(format_err(
            path,
            format!(
                "malformed MAT-file (the MAT reader failed: {})",
                one_line(&msg)
            ),
        )),
    }
}

fn one_line(s: &str) -> String {
    let first = s
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    let mut out: String = first.chars().take(200).collect();
    if first.chars().count() > 200 {
        out.push('…');
    }
    out
}

/// Recognises the file, refuses what it is not, normalises scipy's header
/// text to MATLAB's (the parser wants `MAT-file, `), drops any subsystem
/// data, and checks that every top-level element fits in the file.
fn prepare<'a>(path: &Path, bytes: &'a [u8]) -> Result<Cow<'a, [u8]>> {
    if bytes.starts_with(V73_MAGIC)
        || bytes.get(512..520) == Some(HDF5_MAGIC)
        || bytes.starts_with(HDF5_MAGIC)
    {
        return Err(format_err(
            path,
            "MATLAB v7.3 (HDF5) MAT-files are not supported; save the recording \
             with save(..., '-v7') in MATLAB, or export it as CSV",
        ));
    }
    if !bytes.starts_with(V5_MAGIC) {
        let head = &bytes[..bytes.len().min(256)];
        let texty = !head.is_empty()
            && head
                .iter()
                .all(|&b| b.is_ascii_graphic() || b.is_ascii_whitespace() || b >= 0x80);
        let reason = if bytes.is_empty() {
            "file is empty; expected a MATLAB MAT-file".to_string()
        } else if bytes.starts_with(b"MATLAB") {
            "damaged MAT-file header (expected 'MATLAB 5.0 MAT-file')".to_string()
        } else if texty {
            let first = String::from_utf8_lossy(head);
            let first = first.lines().next().unwrap_or("").trim();
            format!(
                "not a MAT-file but text (starts with '{}'): it looks like a CSV file; \
                 name it .csv or read it as format csv",
                first.chars().take(40).collect::<String>()
            )
        } else {
            "not a MATLAB MAT-file (no 'MATLAB 5.0 MAT-file' header)".to_string()
        };
        return Err(format_err(path, reason));
    }
    if bytes.len() < HEADER_LEN {
        return Err(format_err(
            path,
            format!(
                "truncated MAT-file: {} bytes, shorter than the {HEADER_LEN}-byte header",
                bytes.len()
            ),
        ));
    }
    let little = match &bytes[126..128] {
        b"IM" => true,
        b"MI" => false,
        other => {
            return Err(format_err(
                path,
                format!(
                    "malformed MAT-file header: endian indicator {:?}, expected 'IM' or 'MI'",
                    String::from_utf8_lossy(other)
                ),
            ))
        }
    };
    let u32_at = |b: &[u8], at: usize| -> u32 {
        let w = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        if little {
            u32::from_le_bytes(w)
        } else {
            u32::from_be_bytes(w)
        }
    };
    // Subsystem data (MATLAB objects) follows the variables; it is not data for us.
    let sub = &bytes[116..124];
    let mut end = bytes.len();
    if sub.iter().any(|&b| b != 0 && b != b' ') {
        let w: [u8; 8] = sub.try_into().unwrap_or([0; 8]);
        let off = if little {
            u64::from_le_bytes(w)
        } else {
            u64::from_be_bytes(w)
        };
        if off as usize > HEADER_LEN && (off as usize) <= bytes.len() {
            end = off as usize;
        }
    }
    let mut pos = HEADER_LEN;
    let mut k = 0;
    while pos < end {
        k += 1;
        if end - pos < 8 {
            return Err(format_err(
                path,
                format!(
                    "truncated MAT-file: element {k} at byte {pos} has only {} of its 8 tag bytes",
                    end - pos
                ),
            ));
        }
        let first = u32_at(bytes, pos);
        let (ty, total) = if first >> 16 != 0 {
            (first & 0xffff, 8)
        } else {
            let n = u32_at(bytes, pos + 4) as usize;
            let padded = if first == MI_COMPRESSED {
                n
            } else {
                n.div_ceil(8) * 8
            };
            (first, 8 + padded)
        };
        if ty != MI_MATRIX && ty != MI_COMPRESSED {
            return Err(format_err(
                path,
                format!(
                    "malformed MAT-file: element {k} at byte {pos} has data type {ty}; \
                     expected a variable (14 or 15)"
                ),
            ));
        }
        if total > end - pos {
            return Err(format_err(
                path,
                format!(
                    "truncated MAT-file: variable {k} at byte {pos} needs {total} bytes \
                     but only {} remain",
                    end - pos
                ),
            ));
        }
        pos += total;
    }
    let needs_patch = !bytes[V5_MAGIC.len()..].starts_with(b", ");
    if !needs_patch && end == bytes.len() {
        return Ok(Cow::Borrowed(bytes));
    }
    let mut owned = bytes[..end].to_vec();
    if needs_patch {
        let mut text = b"MATLAB 5.0 MAT-file, ".to_vec();
        text.resize(TEXT_LEN, b' ');
        owned[..TEXT_LEN].copy_from_slice(&text);
    }
    Ok(Cow::Owned(owned))
}

thread_local! {
    static CONTAINED: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`, turning a panic into `Err(message)`. While `f` runs on this
/// thread, the panic message is not printed (other threads and other panics
/// keep the previous hook's behaviour).
fn contain_panics<T>(f: impl FnOnce() -> T) -> std::result::Result<T, String> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !CONTAINED.with(Cell::get) {
                previous(info);
            }
        }));
    });
    let was = CONTAINED.with(|c| c.replace(true));
    let r = catch_unwind(AssertUnwindSafe(f));
    CONTAINED.with(|c| c.set(was));
    r.map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into())
    })
}

/// Writes a recording as a MAT-file (level 5, uncompressed, little-endian):
/// column vectors `time_s` (`start_time_s + i / fs_hz`) and the channels
/// present under their canonical names, all double. MATLAB, Octave, scipy
/// and [`super::load`] read it; `load` gives back the same bits.
///
/// Written to a temporary file beside `path` and renamed into place.
///
/// # Errors
/// [`Error::Io`] when the file cannot be written; [`Error::InvalidRecording`]
/// for more than 2^28 samples (the 4 GiB element limit of level 5).
pub fn write_mat(rec: &Recording, path: &Path) -> Result<()> {
    let n = rec.len();
    if n > (1 << 28) {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!("{n} samples exceed what a level-5 MAT-file can hold (2^28)"),
        });
    }
    let time: Vec<f64> = (0..n).map(|i| rec.time_s(i)).collect();
    let mut vars: Vec<(&str, &[f64])> = vec![("time_s", &time)];
    for c in rec.channels() {
        if let Some(v) = rec.channel(c) {
            vars.push((c.column_name(), v));
        }
    }
    crate::fsutil::write_atomic_with(path, |w| {
        let mut text = format!(
            "MATLAB 5.0 MAT-file, Platform: ballpass {}, Created by: ballpass",
            crate::VERSION
        )
        .into_bytes();
        text.resize(TEXT_LEN, b' ');
        w.write_all(&text)?;
        w.write_all(&[0; 8])?;
        w.write_all(&0x0100u16.to_le_bytes())?;
        w.write_all(b"IM")?;
        for (name, data) in &vars {
            write_vector(w, name, data)?;
        }
        Ok(())
    })
}

fn write_vector(w: &mut impl Write, name: &str, data: &[f64]) -> std::io::Result<()> {
    let tag = |w: &mut dyn Write, ty: u32, n: usize| -> std::io::Result<()> {
        w.write_all(&ty.to_le_bytes())?;
        w.write_all(&(n as u32).to_le_bytes())
    };
    let name_padded = name.len().div_ceil(8) * 8;
    let body = 16 + 16 + (8 + name_padded) + (8 + data.len() * 8);
    tag(w, MI_MATRIX, body)?;
    tag(w, MI_UINT32, 8)?;
    w.write_all(&MX_DOUBLE_CLASS.to_le_bytes())?;
    w.write_all(&0u32.to_le_bytes())?;
    tag(w, MI_INT32, 8)?;
    w.write_all(&(data.len() as i32).to_le_bytes())?;
    w.write_all(&1i32.to_le_bytes())?;
    tag(w, MI_INT8, name.len())?;
    w.write_all(name.as_bytes())?;
    w.write_all(&vec![0u8; name_padded - name.len()])?;
    tag(w, MI_DOUBLE, data.len() * 8)?;
    let mut buf = Vec::with_capacity(data.len() * 8);
    for x in data {
        buf.extend_from_slice(&x.to_le_bytes());
    }
    w.write_all(&buf)
}
