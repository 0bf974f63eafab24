//! The segment chain of a TDMS file: lead-ins, metadata (objects, raw data
//! indexes, properties), and where each channel's values lie in the raw
//! data (its runs). Read through a [`Bytes`] source: the file in memory,
//! or the file on disk read segment by segment, raw data skipped.

use std::borrow::Cow;
use std::collections::HashMap;

use crate::error::excerpt;

const LEAD_IN: usize = 28;
pub(super) const TOC_META: u32 = 1 << 1;
pub(super) const TOC_NEW_OBJ_LIST: u32 = 1 << 2;
pub(super) const TOC_RAW: u32 = 1 << 3;
pub(super) const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;
const NO_DATA: u32 = 0xFFFF_FFFF;
const SAME_AS_BEFORE: u32 = 0;
const DAQMX_FORMAT_CHANGING: u32 = 0x1269;
const DAQMX_DIGITAL_LINE: u32 = 0x126A;
pub(super) const TY_STRING: u32 = 0x20;
pub(super) const TY_DAQMX: u32 = 0xFFFF_FFFF;
/// Most DAQmx scalers of one channel (a channel has one or two).
const MAX_SCALERS: usize = 8;

pub(super) type R<T> = std::result::Result<T, String>;

/// Size of one value of a TDMS data type; `None` for strings and unknown types.
pub(super) fn item_size(ty: u32) -> Option<usize> {
    Some(match ty {
        1 | 5 | 0x21 => 1,
        2 | 6 => 2,
        3 | 7 | 9 | 0x19 => 4,
        4 | 8 | 10 | 0x1A | 0x08_000C => 8,
        11 | 0x1B | 0x44 | 0x10_000D => 16,
        _ => return None,
    })
}

pub(super) fn type_name(ty: u32) -> &'static str {
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

/// A bounds-checked cursor over a segment's metadata (`b`, which starts
/// at byte `base` of the file).
struct Cur<'a> {
    b: &'a [u8],
    base: usize,
    pos: usize,
    end: usize,
    big: bool,
}

impl<'a> Cur<'a> {
    fn take(&mut self, n: usize, what: &str) -> R<&'a [u8]> {
        if n > self.end - self.pos {
            return Err(format!(
                "{what} at byte {} needs {n} bytes, only {} remain in the segment",
                self.base + self.pos,
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
pub(super) enum Prop {
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
pub(super) struct Run {
    pub(super) offset: usize,
    pub(super) count: usize,
    pub(super) stride: usize,
    pub(super) reps: usize,
    pub(super) rep_stride: usize,
    pub(super) big: bool,
    /// Stored type (a DAQmx scaler's type mapped to the TDMS type code).
    pub(super) ty: u32,
}

/// A DAQmx scaler of a channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Scaler {
    ty: u32,
    buffer: usize,
    byte_offset: usize,
    scale_id: u32,
}

/// A channel's raw data index.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Index {
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
#[derive(Debug, Default, Clone)]
pub(super) struct Object {
    pub(super) group: String,
    pub(super) channel: Option<String>,
    pub(super) props: Vec<(String, Prop)>,
    /// Data type of the last raw data index.
    pub(super) ty: Option<u32>,
    /// Runs of the main data (or of each DAQmx scaler, by scale id).
    pub(super) runs: Vec<(u32, Run)>,
    pub(super) values: usize,
    pub(super) last_index: Option<Index>,
}

impl Object {
    pub(super) fn prop(&self, name: &str) -> Option<&Prop> {
        self.props
            .iter()
            .rev()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v)
    }
    pub(super) fn num(&self, name: &str) -> Option<f64> {
        match self.prop(name) {
            Some(Prop::Num(x)) => Some(*x),
            _ => None,
        }
    }
    pub(super) fn label(&self) -> String {
        match &self.channel {
            Some(c) => format!("{}/{}", self.group, c),
            None => self.group.clone(),
        }
    }
}

/// The objects of a file with their data runs.
pub(super) struct Tdms {
    pub(super) objects: Vec<Object>,
    pub(super) notes: Vec<String>,
}

/// Splits `/'Group'/'Channel'` into its names (`''` is a quote inside one).
pub(super) fn split_path(p: &str) -> R<Vec<String>> {
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

/// Where [`read`] gets a file's bytes: the whole file in memory, or the
/// file on disk (only lead-ins and metadata are read from it).
pub(super) trait Bytes {
    /// The file's length in bytes.
    fn size(&self) -> usize;
    /// Bytes `at..at + n` (within [`Bytes::size`]).
    fn get(&mut self, at: usize, n: usize) -> R<Cow<'_, [u8]>>;
}

impl Bytes for &[u8] {
    fn size(&self) -> usize {
        self.len()
    }
    fn get(&mut self, at: usize, n: usize) -> R<Cow<'_, [u8]>> {
        let whole: &[u8] = self;
        whole
            .get(at..at.saturating_add(n))
            .map(Cow::Borrowed)
            .ok_or_else(|| format!("bytes {at}..{} beyond the file", at.saturating_add(n)))
    }
}

/// Reads the segment chain of a file: its objects and where their values lie.
pub(super) fn read(b: &mut dyn Bytes) -> R<Tdms> {
    let size = b.size();
    let mut objects: Vec<Object> = Vec::new();
    let mut by_path: HashMap<String, usize> = HashMap::new();
    // The object list of the previous segment, with each object's index.
    let mut list: Vec<(usize, Option<Index>)> = Vec::new();
    let mut notes = Vec::new();
    let mut pos = 0;
    let mut k = 0;
    while pos < size {
        k += 1;
        if size - pos < LEAD_IN {
            notes.push(format!(
                "{} trailing byte(s) after the last segment ignored",
                size - pos
            ));
            break;
        }
        let mut lead = [0u8; LEAD_IN];
        lead.copy_from_slice(&b.get(pos, LEAD_IN)?);
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
        let avail = (size - start) as u64;
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
            let meta = b.get(start, meta_end - start)?;
            let mut c = Cur {
                b: &meta,
                base: start,
                pos: 0,
                end: meta_end - start,
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
