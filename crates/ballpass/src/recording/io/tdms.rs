//! NI TDMS files (LabVIEW, DAQmx, npTDMS): our own reader, bounded by the file.
//!
//! A TDMS file is a chain of segments: a 28-byte lead-in (`TDSm`, table of
//! contents, version, offsets), metadata (objects `/'Group'/'Channel'` with their
//! raw data index and properties) and raw data, written in chunks. Objects
//! and their raw data indexes carry over from segment to segment unless a
//! segment replaces them.
//!
//! Read: every segment layout (new or carried-over object lists, several
//! chunks per segment, an unfinished last segment), contiguous and
//! interleaved raw data, big-endian segments, and DAQmx raw data with
//! format-changing scalers; channels of integer, float, boolean and
//! timestamp type. NI scaling properties (`NI_Scale[k]_...`: linear,
//! polynomial and DAQmx scalers, chained as NI defines) are applied as
//! npTDMS applies them. The time base is `wf_increment` (the rate, stated)
//! and `wf_start_offset` of the channels used; channels whose `wf_start_time`
//! differ by half a sample or more are refused.
//!
//! Why not the `tdms-rs` crate: it allocates buffers of any size a length
//! field claims (a 4 GB path length aborts the process), reads only the
//! first chunk of a segment (later chunks are silently lost) and neither
//! interleaved nor DAQmx data; a reader that checks every length against
//! the file is shorter than the pre-validation it would need.
//!
//! Bounds: every length and count is checked against the bytes that remain
//! before anything is allocated from it; the data of a channel is kept as a
//! few runs per segment (offset, count, stride, repetitions), so a segment
//! of a million tiny chunks costs no more than one of a single chunk.

use std::collections::HashMap;
use std::path::Path;

use super::names::{self, Candidate};
use super::{LoadOptions, Locator, RawColumn, RawTable};
use crate::error::{excerpt, Error, Result};

const LEAD_IN: usize = 28;
const TOC_META: u32 = 1 << 1;
const TOC_NEW_OBJ_LIST: u32 = 1 << 2;
const TOC_RAW: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;
const NO_DATA: u32 = 0xFFFF_FFFF;
const SAME_AS_BEFORE: u32 = 0;
const DAQMX_FORMAT_CHANGING: u32 = 0x1269;
const DAQMX_DIGITAL_LINE: u32 = 0x126A;
const TY_STRING: u32 = 0x20;
const TY_DAQMX: u32 = 0xFFFF_FFFF;
/// Most DAQmx scalers of one channel (a channel has one or two).
const MAX_SCALERS: usize = 8;

type R<T> = std::result::Result<T, String>;

/// Size of one value of a TDMS data type; `None` for strings and unknown types.
fn item_size(ty: u32) -> Option<usize> {
    Some(match ty {
        1 | 5 | 0x21 => 1,
        2 | 6 => 2,
        3 | 7 | 9 | 0x19 => 4,
        4 | 8 | 10 | 0x1A | 0x08_000C => 8,
        11 | 0x1B | 0x44 | 0x10_000D => 16,
        _ => return None,
    })
}

fn type_name(ty: u32) -> &'static str {
    match ty {
        1 => "int8",
        2 => "int16",
        3 => "int32",
        4 => "int64",
        5 => "uint8",
        6 => "uint16",
        7 => "uint32",
        8 => "uint64",
        9 | 0x19 => "single",
        10 | 0x1A => "double",
        11 | 0x1B => "extended",
        0x20 => "string",
        0x21 => "boolean",
        0x44 => "timestamp",
        0x08_000C | 0x10_000D => "complex",
        TY_DAQMX => "DAQmx raw",
        _ => "unknown",
    }
}

/// A bounds-checked cursor over the file.
struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
    end: usize,
    big: bool,
}

impl<'a> Cur<'a> {
    fn take(&mut self, n: usize, what: &str) -> R<&'a [u8]> {
        if n > self.end - self.pos {
            return Err(format!(
                "{what} at byte {} needs {n} bytes, only {} remain in the segment",
                self.pos,
                self.end - self.pos
            ));
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> R<u32> {
        let a: [u8; 4] = self.take(4, what)?.try_into().map_err(|_| "short read")?;
        Ok(if self.big {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        })
    }
    fn u64(&mut self, what: &str) -> R<u64> {
        let a: [u8; 8] = self.take(8, what)?.try_into().map_err(|_| "short read")?;
        Ok(if self.big {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        })
    }
    fn string(&mut self, what: &str) -> R<String> {
        let n = self.u32(what)? as usize;
        Ok(String::from_utf8_lossy(self.take(n, what)?).into_owned())
    }
    fn left(&self) -> usize {
        self.end - self.pos
    }
}

/// A property value.
#[derive(Debug, Clone, PartialEq)]
enum Prop {
    Num(f64),
    Text(String),
    /// Seconds since 1904-01-01 UTC and the fraction in units of 2^-64 s.
    Time(i64, u64),
    Other,
}

fn read_prop(c: &mut Cur<'_>) -> R<Prop> {
    let ty = c.u32("property type")?;
    fn num<'a>(c: &mut Cur<'a>, n: usize) -> R<&'a [u8]> {
        c.take(n, "property value")
    }
    let big = c.big;
    macro_rules! int {
        ($t:ty, $n:expr) => {{
            let a: [u8; $n] = num(c, $n)?.try_into().map_err(|_| "short read")?;
            Prop::Num(if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            } as f64)
        }};
    }
    Ok(match ty {
        1 => int!(i8, 1),
        2 => int!(i16, 2),
        3 => int!(i32, 4),
        4 => int!(i64, 8),
        5 => int!(u8, 1),
        6 => int!(u16, 2),
        7 => int!(u32, 4),
        8 => int!(u64, 8),
        9 | 0x19 => int!(f32, 4),
        10 | 0x1A => int!(f64, 8),
        0x21 => Prop::Num(f64::from(num(c, 1)?[0] != 0)),
        TY_STRING => Prop::Text(c.string("property text")?),
        0x44 => {
            let (a, b) = (c.u64("timestamp")?, c.u64("timestamp")?);
            if big {
                Prop::Time(a as i64, b)
            } else {
                Prop::Time(b as i64, a)
            }
        }
        other => match item_size(other) {
            Some(n) => {
                num(c, n)?;
                Prop::Other
            }
            None => return Err(format!("property of unknown type {other:#x}")),
        },
    })
}

/// How a channel's values are laid out in one segment: `reps` blocks of
/// `count` values `stride` bytes apart, block `k` starting at `offset + k
/// rep_stride`.
#[derive(Debug, Clone, Copy)]
struct Run {
    offset: usize,
    count: usize,
    stride: usize,
    reps: usize,
    rep_stride: usize,
    big: bool,
    /// Stored type (a DAQmx scaler's type mapped to the TDMS type code).
    ty: u32,
}

/// A DAQmx scaler of a channel.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Scaler {
    ty: u32,
    buffer: usize,
    byte_offset: usize,
    scale_id: u32,
}

/// A channel's raw data index.
#[derive(Debug, Clone, PartialEq)]
enum Index {
    Plain {
        ty: u32,
        count: u64,
        bytes: u64,
    },
    Daqmx {
        count: u64,
        scalers: Vec<Scaler>,
        widths: Vec<usize>,
    },
}

/// What the file says about one object.
#[derive(Debug, Default)]
struct Object {
    group: String,
    channel: Option<String>,
    props: Vec<(String, Prop)>,
    /// Data type of the last raw data index.
    ty: Option<u32>,
    /// Runs of the main data (or of each DAQmx scaler, by scale id).
    runs: Vec<(u32, Run)>,
    values: usize,
    last_index: Option<Index>,
}

impl Object {
    fn prop(&self, name: &str) -> Option<&Prop> {
        self.props
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v)
    }
    fn num(&self, name: &str) -> Option<f64> {
        match self.prop(name) {
            Some(Prop::Num(x)) => Some(*x),
            _ => None,
        }
    }
    fn label(&self) -> String {
        match &self.channel {
            Some(c) => format!("{}/{}", self.group, c),
            None => self.group.clone(),
        }
    }
}

/// The objects of a file with their data runs.
struct Tdms {
    objects: Vec<Object>,
    notes: Vec<String>,
}

/// Splits `/'Group'/'Channel'` into its names (`''` is a quote inside one).
fn split_path(p: &str) -> R<Vec<String>> {
    if p == "/" {
        return Ok(Vec::new());
    }
    let mut parts = Vec::new();
    let mut rest = p;
    while !rest.is_empty() {
        rest = rest
            .strip_prefix("/'")
            .ok_or_else(|| format!("object path '{}' is not /'name'/...", excerpt(p)))?;
        let mut name = String::new();
        loop {
            let q = rest
                .find('\'')
                .ok_or_else(|| format!("object path '{}' has an unclosed quote", excerpt(p)))?;
            name.push_str(&rest[..q]);
            rest = &rest[q + 1..];
            if let Some(r) = rest.strip_prefix('\'') {
                name.push('\'');
                rest = r;
            } else {
                break;
            }
        }
        parts.push(name);
    }
    Ok(parts)
}

fn read(b: &[u8]) -> R<Tdms> {
    let mut objects: Vec<Object> = Vec::new();
    let mut by_path: HashMap<String, usize> = HashMap::new();
    // The object list of the previous segment, with each object's index.
    let mut list: Vec<(usize, Option<Index>)> = Vec::new();
    let mut notes = Vec::new();
    let mut pos = 0;
    let mut k = 0;
    while pos < b.len() {
        k += 1;
        if b.len() - pos < LEAD_IN {
            notes.push(format!(
                "{} trailing byte(s) after the last segment ignored",
                b.len() - pos
            ));
            break;
        }
        let lead = &b[pos..pos + LEAD_IN];
        if &lead[..4] != b"TDSm" {
            return Err(format!(
                "segment {k} at byte {pos} does not start with 'TDSm'{}",
                if k == 1 { " (not a TDMS file)" } else { "" }
            ));
        }
        // The table of contents is little-endian; the version and offsets
        // follow the segment's byte order (as npTDMS reads them).
        let toc = u32::from_le_bytes([lead[4], lead[5], lead[6], lead[7]]);
        let big = toc & TOC_BIG_ENDIAN != 0;
        let w64 = |at: usize| {
            let a: [u8; 8] = lead[at..at + 8].try_into().unwrap_or([0; 8]);
            if big {
                u64::from_be_bytes(a)
            } else {
                u64::from_le_bytes(a)
            }
        };
        let next = w64(12);
        let raw_off = w64(20);
        let start = pos + LEAD_IN;
        let avail = (b.len() - start) as u64;
        let unfinished = next == u64::MAX;
        let seg_len = if unfinished {
            avail
        } else if next > avail {
            notes.push(format!(
                "segment {k} is cut short: {avail} of its {next} bytes are in the file"
            ));
            avail
        } else {
            next
        };
        if raw_off > seg_len {
            return Err(format!(
                "segment {k} at byte {pos}: metadata of {raw_off} bytes in a segment of {seg_len}"
            ));
        }
        let meta_end = start + raw_off as usize;
        let seg_end = start + seg_len as usize;
        if toc & TOC_META != 0 {
            let mut c = Cur {
                b,
                pos: start,
                end: meta_end,
                big,
            };
            let what = |s: &str| format!("segment {k}: {s}");
            if toc & TOC_NEW_OBJ_LIST != 0 {
                list.clear();
            }
            let n = c.u32("object count").map_err(|r| what(&r))? as usize;
            if n > c.left() / 8 {
                return Err(what(&format!("{n} objects claimed in {} bytes", c.left())));
            }
            for _ in 0..n {
                let path = c.string("object path").map_err(|r| what(&r))?;
                let raw_index = c.u32("raw data index").map_err(|r| what(&r))?;
                let id = match by_path.get(&path) {
                    Some(&id) => id,
                    None => {
                        let parts = split_path(&path).map_err(|r| what(&r))?;
                        let id = objects.len();
                        objects.push(Object {
                            group: parts.first().cloned().unwrap_or_else(|| "/".into()),
                            channel: parts.get(1).cloned(),
                            ..Object::default()
                        });
                        by_path.insert(path.clone(), id);
                        id
                    }
                };
                let index = match raw_index {
                    NO_DATA => None,
                    SAME_AS_BEFORE => Some(objects[id].last_index.clone().ok_or_else(|| {
                        what(&format!(
                            "'{}' reuses a raw data index it never had",
                            excerpt(&objects[id].label())
                        ))
                    })?),
                    DAQMX_FORMAT_CHANGING => Some(daqmx_index(&mut c).map_err(|r| what(&r))?),
                    DAQMX_DIGITAL_LINE => {
                        return Err(what("DAQmx digital line data is not supported"))
                    }
                    len => Some(plain_index(&mut c, len).map_err(|r| what(&r))?),
                };
                if let Some(Index::Plain { ty, .. }) = &index {
                    objects[id].ty = Some(*ty);
                }
                if let Some(Index::Daqmx { .. }) = &index {
                    objects[id].ty = Some(TY_DAQMX);
                }
                if index.is_some() {
                    objects[id].last_index = index.clone();
                }
                let nprops = c.u32("property count").map_err(|r| what(&r))? as usize;
                if nprops > c.left() / 8 {
                    return Err(what(&format!(
                        "{nprops} properties claimed in {} bytes",
                        c.left()
                    )));
                }
                for _ in 0..nprops {
                    let name = c.string("property name").map_err(|r| what(&r))?;
                    let v = read_prop(&mut c).map_err(|r| what(&r))?;
                    objects[id].props.push((name, v));
                }
                match list.iter_mut().find(|(o, _)| *o == id) {
                    Some(entry) => entry.1 = index,
                    None => list.push((id, index)),
                }
            }
        }
        if toc & (TOC_RAW | TOC_DAQMX) != 0 && seg_end > meta_end {
            layout_raw(
                &mut objects,
                &list,
                meta_end,
                seg_end,
                toc,
                big,
                k,
                &mut notes,
            )?;
        }
        if unfinished {
            break;
        }
        pos = seg_end;
    }
    Ok(Tdms { objects, notes })
}

fn plain_index(c: &mut Cur<'_>, len: u32) -> R<Index> {
    let start = c.pos;
    let len = len as usize;
    if len < 16 || len > c.left() + 4 {
        return Err(format!("raw data index of {len} bytes"));
    }
    let ty = c.u32("data type")?;
    let dim = c.u32("array dimension")?;
    if dim != 1 {
        return Err(format!("array dimension {dim}; TDMS data has dimension 1"));
    }
    let count = c.u64("value count")?;
    let bytes = if ty == TY_STRING {
        c.u64("string data size")?
    } else {
        let size = item_size(ty).ok_or_else(|| format!("data of unknown type {ty:#x}"))?;
        count
            .checked_mul(size as u64)
            .ok_or_else(|| format!("{count} values overflow"))?
    };
    // Skip what this index holds beyond what we read (its length counts
    // the 4-byte length field itself).
    let used = c.pos - start;
    if len - 4 > used {
        c.take(len - 4 - used, "raw data index")?;
    }
    Ok(Index::Plain { ty, count, bytes })
}

fn daqmx_index(c: &mut Cur<'_>) -> R<Index> {
    let _ty = c.u32("DAQmx data type")?;
    let dim = c.u32("array dimension")?;
    if dim != 1 {
        return Err(format!("DAQmx array dimension {dim}; expected 1"));
    }
    let count = c.u64("DAQmx value count")?;
    let n = c.u32("DAQmx scaler count")? as usize;
    if n > MAX_SCALERS || n > c.left() / 20 {
        return Err(format!(
            "{n} DAQmx scalers for one channel (at most {MAX_SCALERS} are read)"
        ));
    }
    let mut scalers = Vec::with_capacity(n);
    for _ in 0..n {
        let code = c.u32("scaler type")?;
        let ty = match code {
            0 => 5,
            1 => 1,
            2 => 6,
            3 => 2,
            4 => 7,
            5 => 3,
            6 => 8,
            7 => 4,
            8 => 9,
            9 => 10,
            other => return Err(format!("DAQmx scaler of type {other}")),
        };
        let buffer = c.u32("raw buffer index")? as usize;
        let byte_offset = c.u32("byte offset")? as usize;
        let _bitmap = c.u32("sample format")?;
        let scale_id = c.u32("scale id")?;
        scalers.push(Scaler {
            ty,
            buffer,
            byte_offset,
            scale_id,
        });
    }
    let nw = c.u32("raw data width count")? as usize;
    if nw > c.left() / 4 {
        return Err(format!(
            "{nw} raw data widths claimed in {} bytes",
            c.left()
        ));
    }
    let widths = (0..nw)
        .map(|_| c.u32("raw data width").map(|w| w as usize))
        .collect::<R<Vec<_>>>()?;
    for s in &scalers {
        let w = widths.get(s.buffer).ok_or_else(|| {
            format!(
                "a scaler of buffer {} but {} buffer(s)",
                s.buffer,
                widths.len()
            )
        })?;
        let size = item_size(s.ty).unwrap_or(8);
        if s.byte_offset.checked_add(size).is_none_or(|e| e > *w) {
            return Err(format!(
                "a scaler at byte {} of a {w}-byte raw data width",
                s.byte_offset
            ));
        }
    }
    Ok(Index::Daqmx {
        count,
        scalers,
        widths,
    })
}

/// Records where the raw data of segment `k` puts each object's values.
#[allow(clippy::too_many_arguments)]
fn layout_raw(
    objects: &mut [Object],
    list: &[(usize, Option<Index>)],
    start: usize,
    end: usize,
    toc: u32,
    big: bool,
    k: usize,
    notes: &mut Vec<String>,
) -> R<()> {
    let with_data: Vec<(usize, &Index)> = list
        .iter()
        .filter_map(|(id, ix)| ix.as_ref().map(|ix| (*id, ix)))
        .filter(|(_, ix)| match ix {
            Index::Plain { count, .. } | Index::Daqmx { count, .. } => *count > 0,
        })
        .collect();
    if with_data.is_empty() {
        return Ok(());
    }
    let raw = (end - start) as u64;
    let too_big = || format!("segment {k}: a chunk larger than the file");
    let daqmx = with_data
        .iter()
        .any(|(_, ix)| matches!(ix, Index::Daqmx { .. }));
    if daqmx {
        // Buffers: (values, width), as npTDMS computes them.
        let mut dims: Vec<(u64, usize)> = Vec::new();
        for (_, ix) in &with_data {
            let Index::Daqmx {
                count,
                scalers,
                widths,
            } = ix
            else {
                return Err(format!("segment {k}: DAQmx and other data mixed"));
            };
            if dims.is_empty() {
                dims = widths.iter().map(|&w| (0, w)).collect();
            } else if dims.iter().map(|d| d.1).ne(widths.iter().copied()) {
                return Err(format!(
                    "segment {k}: DAQmx raw data widths differ between channels"
                ));
            }
            for s in scalers {
                dims[s.buffer].0 = dims[s.buffer].0.max(*count);
            }
        }
        let mut chunk = 0u64;
        for &(n, w) in &dims {
            chunk = n
                .checked_mul(w as u64)
                .and_then(|x| x.checked_add(chunk))
                .ok_or_else(too_big)?;
        }
        if chunk == 0 || chunk > raw {
            return Err(format!(
                "segment {k}: DAQmx chunks of {chunk} bytes in {raw} bytes of data"
            ));
        }
        let reps = (raw / chunk) as usize;
        if raw % chunk != 0 {
            notes.push(format!(
                "segment {k}: an incomplete last chunk of {} bytes ignored",
                raw % chunk
            ));
        }
        let mut buf_start = Vec::with_capacity(dims.len());
        let mut acc = 0usize;
        for &(n, w) in &dims {
            buf_start.push(acc);
            acc += n as usize * w;
        }
        for (id, ix) in &with_data {
            let Index::Daqmx { scalers, count, .. } = ix else {
                continue;
            };
            for s in scalers {
                let run = Run {
                    offset: start + buf_start[s.buffer] + s.byte_offset,
                    count: *count as usize,
                    stride: dims[s.buffer].1,
                    reps,
                    rep_stride: chunk as usize,
                    big,
                    ty: s.ty,
                };
                objects[*id].runs.push((s.scale_id, run));
            }
            objects[*id].values += *count as usize * reps;
        }
        return Ok(());
    }
    let interleaved = toc & TOC_INTERLEAVED != 0;
    let mut chunk = 0u64;
    let mut row = 0usize;
    for (_, ix) in &with_data {
        let Index::Plain { bytes, ty, count } = ix else {
            continue;
        };
        chunk = chunk.checked_add(*bytes).ok_or_else(too_big)?;
        if interleaved {
            row += item_size(*ty)
                .ok_or_else(|| format!("segment {k}: interleaved {} data", type_name(*ty)))?;
            let first = with_data.iter().find_map(|(_, ix)| match ix {
                Index::Plain { count, .. } => Some(*count),
                Index::Daqmx { .. } => None,
            });
            if first != Some(*count) {
                return Err(format!(
                    "segment {k}: interleaved channels with different value counts"
                ));
            }
        }
    }
    if chunk == 0 || chunk > raw {
        return Err(format!(
            "segment {k}: chunks of {chunk} bytes in {raw} bytes of data (truncated?)"
        ));
    }
    let reps = (raw / chunk) as usize;
    if raw % chunk != 0 {
        notes.push(format!(
            "segment {k}: an incomplete last chunk of {} bytes ignored",
            raw % chunk
        ));
    }
    let mut offset = start;
    for (id, ix) in &with_data {
        let Index::Plain { ty, count, bytes } = ix else {
            continue;
        };
        let size = item_size(*ty).unwrap_or(1);
        let run = Run {
            offset,
            count: *count as usize,
            stride: if interleaved { row } else { size },
            reps,
            rep_stride: chunk as usize,
            big,
            ty: *ty,
        };
        offset += if interleaved { size } else { *bytes as usize };
        objects[*id].runs.push((0, run));
        objects[*id].values += *count as usize * reps;
    }
    Ok(())
}

/// Decodes the values of one run (`ty` a numeric TDMS type).
fn decode(b: &[u8], run: &Run, out: &mut Vec<f64>, t0: &mut Option<(i64, u64)>) -> R<()> {
    if run.count == 0 || run.reps == 0 {
        return Ok(());
    }
    let size =
        item_size(run.ty).ok_or_else(|| format!("{} data is not numeric", type_name(run.ty)))?;
    // The last byte the run reads must be in the file: checked once, so the
    // loops below index within bounds.
    (run.reps - 1)
        .checked_mul(run.rep_stride)
        .and_then(|x| x.checked_add((run.count - 1).checked_mul(run.stride)?))
        .and_then(|x| x.checked_add(run.offset)?.checked_add(size))
        .filter(|&end| end <= b.len())
        .ok_or_else(|| format!("data beyond the end of the file (from byte {})", run.offset))?;
    let big = run.big;
    macro_rules! each {
        ($n:expr, $f:expr) => {{
            // FnMut for time stamps (they keep the first one).
            #[allow(unused_mut)]
            let mut f = $f;
            for r in 0..run.reps {
                let base = run.offset + r * run.rep_stride;
                if run.stride == $n {
                    // Contiguous: whole values back to back.
                    out.extend(
                        b[base..base + run.count * $n]
                            .chunks_exact($n)
                            .map(|w| f(<[u8; $n]>::try_from(w).unwrap_or([0; $n]))),
                    );
                } else {
                    out.extend((0..run.count).map(|i| {
                        let at = base + i * run.stride;
                        f(<[u8; $n]>::try_from(&b[at..at + $n]).unwrap_or([0; $n]))
                    }));
                }
            }
        }};
    }
    macro_rules! num {
        ($t:ty, $n:expr) => {
            each!($n, |a: [u8; $n]| {
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            })
        };
    }
    match run.ty {
        1 => num!(i8, 1),
        2 => num!(i16, 2),
        3 => num!(i32, 4),
        4 => num!(i64, 8),
        5 => num!(u8, 1),
        6 => num!(u16, 2),
        7 => num!(u32, 4),
        8 => num!(u64, 8),
        9 | 0x19 => num!(f32, 4),
        10 | 0x1A => num!(f64, 8),
        0x21 => each!(1, |a: [u8; 1]| f64::from(a[0] != 0)),
        0x44 => each!(16, |a: [u8; 16]| {
            let w = |k: usize| -> [u8; 8] { a[k..k + 8].try_into().unwrap_or([0; 8]) };
            let (frac, secs) = if big {
                (u64::from_be_bytes(w(8)), i64::from_be_bytes(w(0)))
            } else {
                (u64::from_le_bytes(w(0)), i64::from_le_bytes(w(8)))
            };
            // Seconds from the first time stamp, exactly where f64 allows.
            let (s0, f0) = *t0.get_or_insert((secs, frac));
            (secs.wrapping_sub(s0)) as f64
                + (frac as f64 - f0 as f64) / 18_446_744_073_709_551_616.0
        }),
        other => return Err(format!("{} data is not numeric", type_name(other))),
    }
    Ok(())
}

/// The values of a channel, scaled as its NI scaling properties say.
fn values(b: &[u8], o: &Object) -> R<Vec<f64>> {
    let total = o.values;
    if total > b.len() {
        return Err(format!(
            "claims {total} values in a file of {} bytes",
            b.len()
        ));
    }
    let scaling = Scaling::of(o)?;
    let mut t0 = None;
    let daqmx = o.ty == Some(TY_DAQMX);
    if !daqmx {
        let mut raw = Vec::with_capacity(total);
        for (_, run) in &o.runs {
            decode(b, run, &mut raw, &mut t0)?;
        }
        return match scaling {
            None => Ok(raw),
            Some(s) => s.apply(&raw, &HashMap::new()),
        };
    }
    // DAQmx: one series per scale id.
    let mut series: HashMap<u32, Vec<f64>> = HashMap::new();
    for (id, run) in &o.runs {
        let v = series.entry(*id).or_default();
        decode(b, run, v, &mut t0)?;
    }
    match scaling {
        Some(s) => s.apply(&[], &series),
        None => match series.len() {
            1 => Ok(series.into_values().next().unwrap_or_default()),
            n => Err(format!(
                "DAQmx data with {n} scalers and no scaling properties"
            )),
        },
    }
}

/// NI scaling: a chain of scales, the last one applied (see npTDMS).
struct Scaling {
    scales: Vec<Scale>,
}

enum Scale {
    Linear {
        slope: f64,
        intercept: f64,
        input: u32,
    },
    Polynomial {
        coeffs: Vec<f64>,
        input: u32,
    },
    Daqmx(u32),
    NoOp(u32),
}

const RAW_INPUT: u32 = 0xFFFF_FFFF;

impl Scaling {
    fn of(o: &Object) -> R<Option<Scaling>> {
        let n = match o.num("NI_Number_Of_Scales") {
            Some(n) => n as usize,
            None => {
                let max = o
                    .props
                    .iter()
                    .filter_map(|(k, _)| {
                        k.strip_prefix("NI_Scale[")?
                            .strip_suffix("]_Scale_Type")?
                            .parse::<usize>()
                            .ok()
                    })
                    .max();
                match max {
                    Some(m) => m + 1,
                    None => return Ok(None),
                }
            }
        };
        if n == 0 {
            return Ok(None);
        }
        if matches!(o.prop("NI_Scaling_Status"), Some(Prop::Text(s)) if s == "scaled") {
            return Ok(None);
        }
        if n > 64 {
            return Err(format!("{n} NI scales"));
        }
        let num = |k: String| o.num(&k);
        let mut scales = Vec::with_capacity(n);
        for i in 0..n {
            let ty = match o.prop(&format!("NI_Scale[{i}]_Scale_Type")) {
                Some(Prop::Text(t)) => t.clone(),
                Some(_) => return Err(format!("NI_Scale[{i}]_Scale_Type is not text")),
                None => {
                    scales.push(Scale::Daqmx(i as u32));
                    continue;
                }
            };
            let input = |name: &str| {
                num(format!("NI_Scale[{i}]_{name}_Input_Source")).map_or(RAW_INPUT, |x| x as u32)
            };
            let need =
                |k: String| num(k.clone()).ok_or_else(|| format!("scaling property {k} missing"));
            scales.push(match ty.as_str() {
                "Linear" => Scale::Linear {
                    slope: need(format!("NI_Scale[{i}]_Linear_Slope"))?,
                    intercept: need(format!("NI_Scale[{i}]_Linear_Y_Intercept"))?,
                    input: input("Linear"),
                },
                "Polynomial" => {
                    let m = num(format!("NI_Scale[{i}]_Polynomial_Coefficients_Size"))
                        .map_or(4, |m| m as usize);
                    if m > 64 {
                        return Err(format!("a polynomial scale of {m} coefficients"));
                    }
                    Scale::Polynomial {
                        coeffs: (0..m)
                            .map(|j| need(format!("NI_Scale[{i}]_Polynomial_Coefficients[{j}]")))
                            .collect::<R<_>>()?,
                        input: input("Polynomial"),
                    }
                }
                "AdvancedAPI" => Scale::NoOp(input("AdvancedAPI")),
                other => {
                    return Err(format!(
                        "NI scaling '{}' is not supported (linear, polynomial and DAQmx \
                         scalers are); give the channel's scale instead",
                        excerpt(other)
                    ))
                }
            });
        }
        Ok(Some(Scaling { scales }))
    }

    fn apply(&self, raw: &[f64], scalers: &HashMap<u32, Vec<f64>>) -> R<Vec<f64>> {
        self.compute(self.scales.len() as u32 - 1, raw, scalers, 0)
    }

    fn compute(
        &self,
        i: u32,
        raw: &[f64],
        scalers: &HashMap<u32, Vec<f64>>,
        depth: usize,
    ) -> R<Vec<f64>> {
        if depth > self.scales.len() {
            return Err("NI scales refer to each other in a loop".into());
        }
        if i == RAW_INPUT {
            if raw.is_empty() && !scalers.is_empty() {
                return Err("an NI scale reads raw data of DAQmx scalers".into());
            }
            return Ok(raw.to_vec());
        }
        let scale = self
            .scales
            .get(i as usize)
            .ok_or_else(|| format!("NI scale {i} does not exist"))?;
        Ok(match scale {
            Scale::Daqmx(id) => scalers
                .get(id)
                .cloned()
                .ok_or_else(|| format!("no DAQmx scaler with scale id {id}"))?,
            Scale::NoOp(input) => self.compute(*input, raw, scalers, depth + 1)?,
            Scale::Linear {
                slope,
                intercept,
                input,
            } => self
                .compute(*input, raw, scalers, depth + 1)?
                .into_iter()
                .map(|x| x * slope + intercept)
                .collect(),
            Scale::Polynomial { coeffs, input } => self
                .compute(*input, raw, scalers, depth + 1)?
                .into_iter()
                .map(|x| {
                    // numpy's polyval (Horner from the highest coefficient).
                    let mut y = coeffs.last().copied().unwrap_or(0.0);
                    for c in coeffs.iter().rev().skip(1) {
                        y = c + y * x;
                    }
                    if coeffs.is_empty() {
                        0.0
                    } else {
                        y
                    }
                })
                .collect(),
        })
    }
}

fn format_err(path: &Path, reason: impl Into<String>) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        reason: reason.into(),
    }
}

fn open(path: &Path, bytes: &[u8]) -> Result<Tdms> {
    if !bytes.starts_with(b"TDSm") {
        return Err(format_err(
            path,
            if bytes.is_empty() {
                "file is empty; expected an NI TDMS file".to_string()
            } else {
                "not an NI TDMS file (it does not start with 'TDSm')".to_string()
            },
        ));
    }
    read(bytes).map_err(|r| format_err(path, format!("damaged TDMS file: {r}")))
}

/// The groups that hold channels, in file order.
fn groups(t: &Tdms) -> Vec<String> {
    let mut g: Vec<String> = Vec::new();
    for o in t.objects.iter().filter(|o| o.channel.is_some()) {
        if !g.contains(&o.group) {
            g.push(o.group.clone());
        }
    }
    g
}

/// The groups of a file for a message: `'Run 1' (3 channels), ...`.
fn list_groups(t: &Tdms) -> String {
    let g: Vec<String> = groups(t)
        .iter()
        .map(|g| {
            let n = t
                .objects
                .iter()
                .filter(|o| o.channel.is_some() && &o.group == g)
                .count();
            format!(
                "'{}' ({n} channel{})",
                excerpt(g),
                if n == 1 { "" } else { "s" }
            )
        })
        .collect();
    if g.is_empty() {
        "no group with channels".into()
    } else {
        g.join(", ")
    }
}

/// The group `record` names (its name ignoring case).
///
/// # Errors
/// The reason, listing the file's groups, when none has that name.
fn group_of(t: &Tdms, record: &str) -> R<String> {
    let want = record.trim();
    groups(t)
        .into_iter()
        .find(|g| g.eq_ignore_ascii_case(want))
        .ok_or_else(|| {
            format!(
                "no group '{}' (FILE#GROUP names one run); the file holds {}",
                excerpt(want),
                list_groups(t)
            )
        })
}

/// The channels of a TDMS file by name (`Group/Channel`, or `Channel` alone),
/// only those of `group` when given.
fn candidates(t: &Tdms, group: Option<&str>) -> (Vec<usize>, Vec<Candidate>) {
    let ids: Vec<usize> = (0..t.objects.len())
        .filter(|&i| t.objects[i].channel.is_some())
        .filter(|&i| group.is_none_or(|g| t.objects[i].group == g))
        .collect();
    let cands = ids
        .iter()
        .map(|&i| {
            let o = &t.objects[i];
            Candidate {
                full: o.label(),
                short: o.channel.clone(),
            }
        })
        .collect();
    (ids, cands)
}

/// Parses a TDMS file held in memory into raw columns.
pub(crate) fn parse(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<RawTable> {
    let t = open(path, bytes)?;
    let err = |r: String| format_err(path, r);
    let group = opts
        .record
        .as_deref()
        .map(|r| group_of(&t, r))
        .transpose()
        .map_err(err)?;
    let (ids, cands) = candidates(&t, group.as_deref());
    let has = || names::list(&cands.iter().map(|c| c.full.clone()).collect::<Vec<_>>());
    let column = |i: usize| -> Result<RawColumn> {
        let o = &t.objects[i];
        let values =
            values(bytes, o).map_err(|r| err(format!("channel '{}': {r}", excerpt(&o.label()))))?;
        let unit = match o.prop("unit_string") {
            Some(Prop::Text(u)) if !u.trim().is_empty() => Some((
                u.trim().to_string(),
                format!("unit_string of '{}'", excerpt(&o.label())),
            )),
            _ => None,
        };
        Ok(RawColumn {
            name: excerpt(&o.label()),
            values,
            resolution: 0.0,
            unit,
        })
    };
    let mut channels = Vec::new();
    let mut used = Vec::new();
    let all = groups(&t);
    let several = group.is_none() && all.len() > 1;
    let mapped =
        names::map_channels(&cands, opts, ", as Group/Channel or Channel").map_err(|r| {
            if several {
                // One run per group, as LabVIEW writes them: say how to pick one.
                let file = path
                    .file_name()
                    .map_or(String::new(), |f| f.to_string_lossy().into_owned());
                err(format!(
                    "{r}; the file holds several groups (runs?): {}; name one as FILE#GROUP \
                     (e.g. '{}#{}')",
                    list_groups(&t),
                    excerpt(&file),
                    excerpt(&all[0])
                ))
            } else {
                err(r)
            }
        })?;
    for (c, k) in mapped {
        used.push(ids[k]);
        channels.push((c, column(ids[k])?));
    }
    let time_name = opts
        .time
        .clone()
        .unwrap_or_else(|| super::csv::TIME_COLUMN.into());
    let time = if opts.ignore_time {
        None
    } else {
        match names::find(&cands, &time_name).map_err(err)? {
            Some(k) => Some(column(ids[k])?),
            None if opts.time.is_some() => {
                return Err(err(format!(
                    "no channel '{}' for time; the file has: {}",
                    excerpt(&time_name),
                    has()
                )))
            }
            None => None,
        }
    };
    // The waveform timing of the channels used.
    let mut stated_rate = None;
    let mut start_time_s = None;
    let mut first_start: Option<(String, (i64, u64), f64)> = None;
    for &i in &used {
        let o = &t.objects[i];
        let Some(inc) = o.num("wf_increment") else {
            continue;
        };
        if !(inc.is_finite() && inc > 0.0) {
            return Err(err(format!(
                "channel '{}': wf_increment {inc}; expected a positive number of seconds",
                excerpt(&o.label())
            )));
        }
        let fs = rate_of_increment(inc);
        match &stated_rate {
            None => stated_rate = Some((fs, format!("wf_increment of '{}'", excerpt(&o.label())))),
            Some((f0, from)) if (f0 - fs).abs() > 1e-12 * f0 => {
                return Err(err(format!(
                    "channel '{}' is sampled at {fs} Hz (wf_increment), but {from} says {f0} Hz",
                    excerpt(&o.label())
                )))
            }
            Some(_) => {}
        }
        start_time_s.get_or_insert(o.num("wf_start_offset").unwrap_or(0.0));
        if let Some(Prop::Time(s, f)) = o.prop("wf_start_time") {
            match &first_start {
                None => first_start = Some((o.label(), (*s, *f), fs)),
                Some((other, (s0, f0), fs0)) => {
                    let dt =
                        (s - s0) as f64 + (*f as f64 - *f0 as f64) / 18_446_744_073_709_551_616.0;
                    if dt.abs() * fs0 >= 0.5 {
                        return Err(err(format!(
                            "channels '{}' and '{}' start {dt} s apart (wf_start_time); \
                             they are not one recording",
                            excerpt(other),
                            excerpt(&o.label())
                        )));
                    }
                }
            }
        }
    }
    Ok(RawTable {
        time,
        channels,
        locator: Locator::Samples,
        stated_rate,
        start_time_s,
        notes: t.notes,
        ..RawTable::default()
    })
}

/// `1 / increment`, as the decimal with the fewest digits whose reciprocal
/// is the same double (a `wf_increment` written as `1 / 1000` gives 1000).
fn rate_of_increment(inc: f64) -> f64 {
    let raw = 1.0 / inc;
    for digits in 1..=17 {
        if let Ok(c) = format!("{:.*e}", digits - 1, raw).parse::<f64>() {
            if 1.0 / c == inc {
                return c;
            }
        }
    }
    raw
}

/// What a TDMS file holds, for `inspect`: groups and channels.
pub(crate) fn contents(
    path: &Path,
    bytes: &[u8],
    record: Option<&str>,
    limit: usize,
) -> Result<Vec<(String, String)>> {
    let t = open(path, bytes)?;
    let group = record
        .map(|r| group_of(&t, r))
        .transpose()
        .map_err(|r| format_err(path, r))?;
    let mut out = Vec::new();
    let shown = t
        .objects
        .iter()
        .filter(|o| group.as_ref().is_none_or(|g| &o.group == g));
    for o in shown.take(limit) {
        let desc = match &o.channel {
            None => {
                let n = t
                    .objects
                    .iter()
                    .filter(|c| c.channel.is_some() && c.group == o.group)
                    .count();
                if o.group == "/" {
                    format!("file properties: {}", o.props.len())
                } else {
                    format!("group of {n} channel(s)")
                }
            }
            Some(_) => {
                let mut d = format!(
                    "channel, {}, {} values",
                    o.ty.map_or("no data", type_name),
                    o.values
                );
                if let Some(inc) = o.num("wf_increment") {
                    d.push_str(&format!(
                        ", wf_increment {inc} s ({} Hz)",
                        rate_of_increment(inc)
                    ));
                }
                if let Some(Prop::Text(u)) = o.prop("unit_string") {
                    d.push_str(&format!(", unit {}", excerpt(u)));
                }
                d
            }
        };
        out.push((excerpt(&o.label()), desc));
    }
    for n in &t.notes {
        out.push(("note".into(), n.clone()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn object_paths_split_with_quotes() {
        assert_eq!(split_path("/").unwrap(), Vec::<String>::new());
        assert_eq!(split_path("/'G'").unwrap(), vec!["G"]);
        assert_eq!(
            split_path("/'Group 1'/'it''s/a name'").unwrap(),
            vec!["Group 1", "it's/a name"]
        );
        assert!(split_path("/G").is_err());
        assert!(split_path("/'G").is_err());
    }

    #[test]
    fn rates_snap_to_the_decimal_of_the_increment() {
        assert_eq!(rate_of_increment(1.0 / 1000.0), 1000.0);
        assert_eq!(rate_of_increment(0.001), 1000.0);
        assert_eq!(rate_of_increment(1.0 / 2048.0), 2048.0);
        assert_eq!(rate_of_increment(1.0 / 25600.0), 25600.0);
    }
}
