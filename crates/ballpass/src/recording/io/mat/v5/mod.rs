//! MATLAB level-5 MAT-files (`save -v6`/`-v7`, scipy's `savemat`, dSPACE
//! ControlDesk): a parser whose time and memory are bounded by the file.
//!
//! A file is a 128-byte header followed by tagged elements; each variable is
//! a `miMATRIX` element, or a `miCOMPRESSED` element holding one `miMATRIX`
//! as a zlib stream. What keeps a hostile file from becoming a workload:
//!
//! - every length field must fit inside its container before anything is
//!   allocated from it (an array of `n` cells or fields needs at least `8 n`
//!   bytes, a numeric array exactly `count x size` bytes);
//! - structs, cells and objects nest at most [`MAX_DEPTH`] levels (a MATLAB
//!   variable needs a handful), so recursion is shallow;
//! - a compressed variable is inflated only when it is used (its name and
//!   class are read from the first bytes of the stream), to at most what its
//!   declared size says and what its compressed bytes can hold (zlib expands
//!   at most 1032:1), and a compressed stream inside another is an error;
//! - each element is parsed once: time is linear in the bytes.

use std::cell::OnceCell;

use flate2::{Decompress, FlushDecompress, Status};

use super::tree::{class_name, count, dims_text, Data, Numeric, Struct, Value};
use crate::error::excerpt;

mod parse;
use parse::Parser;

/// Deepest nesting of structs, cells and objects read.
pub(crate) const MAX_DEPTH: usize = 32;
/// Largest expansion of a zlib stream (deflate's limit is about 1032:1).
const MAX_RATIO: usize = 1032;

const HEADER_LEN: usize = 128;
pub(crate) const V5_MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;
const MI_UTF16: u32 = 17;
const MI_UTF32: u32 = 18;

/// Where the values of a numeric array are in a level-5 file.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Span {
    /// Top-level variable whose bytes hold it.
    var: usize,
    /// Offset in those bytes.
    start: usize,
    /// Length in bytes.
    len: usize,
    /// Stored data type (`miDOUBLE`, `miUINT8`, ...).
    ty: u32,
}

/// A top-level variable: what its header says, and its element.
pub(crate) struct TopVar {
    /// Variable name.
    pub name: String,
    /// MATLAB class number.
    pub class: u8,
    /// Dimensions.
    pub dims: Vec<usize>,
    /// Complex flag.
    pub complex: bool,
    /// Element data in the file (after the tag).
    start: usize,
    end: usize,
    /// `Some(declared uncompressed size)` for a `miCOMPRESSED` element.
    compressed: Option<usize>,
}

/// A parsed level-5 file; variables are parsed when asked for.
pub(crate) struct V5File<'a> {
    bytes: &'a [u8],
    little: bool,
    /// Top-level variables in file order.
    pub vars: Vec<TopVar>,
    inflated: Vec<OnceCell<Vec<u8>>>,
    values: Vec<OnceCell<Value>>,
}

#[derive(Clone, Copy)]
struct Endian {
    little: bool,
}

impl Endian {
    fn u32(self, b: &[u8], at: usize) -> u32 {
        let w = [b[at], b[at + 1], b[at + 2], b[at + 3]];
        if self.little {
            u32::from_le_bytes(w)
        } else {
            u32::from_be_bytes(w)
        }
    }
}

/// One tagged element: its type, data range and where the next one starts.
struct Tag {
    ty: u32,
    data: std::ops::Range<usize>,
    next: usize,
}

/// Reads the tag at `pos` of `b[..end]`.
fn tag(e: Endian, b: &[u8], pos: usize, end: usize, what: &str) -> Result<Tag, String> {
    if end < pos || end - pos < 8 {
        return Err(format!(
            "{what}: an element tag needs 8 bytes, {} remain",
            end.saturating_sub(pos)
        ));
    }
    let first = e.u32(b, pos);
    // Small data element: the size is in the upper half of the first word.
    let small = first >> 16;
    if small != 0 {
        let ty = first & 0xffff;
        let n = small as usize;
        if n > 4 {
            return Err(format!(
                "{what}: a small element claims {n} bytes (at most 4)"
            ));
        }
        return Ok(Tag {
            ty,
            data: pos + 4..pos + 4 + n,
            next: pos + 8,
        });
    }
    let n = e.u32(b, pos + 4) as usize;
    let avail = end - pos - 8;
    if n > avail {
        return Err(format!(
            "{what}: element of type {first} claims {n} bytes, only {avail} remain"
        ));
    }
    let padded = if first == MI_COMPRESSED {
        n
    } else {
        n.div_ceil(8) * 8
    };
    Ok(Tag {
        ty: first,
        data: pos + 8..pos + 8 + n,
        next: (pos + 8).saturating_add(padded).min(end),
    })
}

/// Size in bytes of one value of a numeric data type.
fn type_size(ty: u32) -> Option<usize> {
    Some(match ty {
        MI_INT8 | MI_UINT8 | MI_UTF8 => 1,
        MI_INT16 | MI_UINT16 | MI_UTF16 => 2,
        MI_INT32 | MI_UINT32 | MI_SINGLE | MI_UTF32 => 4,
        MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
        _ => return None,
    })
}

/// What the header of a `miMATRIX` says before its contents.
struct MatrixHead {
    class: u8,
    complex: bool,
    logical: bool,
    dims: Vec<usize>,
    name: String,
    /// Where the class-specific contents start.
    rest: usize,
}

/// Reads array flags, dimensions and name of the `miMATRIX` data `b[start..end]`.
fn matrix_head(e: Endian, b: &[u8], start: usize, end: usize) -> Result<MatrixHead, String> {
    let flags = tag(e, b, start, end, "array flags")?;
    if flags.ty != MI_UINT32 || flags.data.len() != 8 {
        return Err(format!(
            "array flags have type {} and {} bytes; expected miUINT32 of 8 bytes",
            flags.ty,
            flags.data.len()
        ));
    }
    let w = e.u32(b, flags.data.start);
    let class = (w & 0xff) as u8;
    let complex = w & 0x0800 != 0;
    let logical = w & 0x0200 != 0;
    if class == 16 || class == 17 {
        // Function handles and opaque objects (strings, tables, ...) have
        // their own layout; they are listed, never read.
        return Ok(MatrixHead {
            class,
            complex,
            logical,
            dims: Vec::new(),
            name: opaque_name(e, b, flags.next, end),
            rest: end,
        });
    }
    let dims_tag = tag(e, b, flags.next, end, "dimensions")?;
    if dims_tag.ty != MI_INT32 || dims_tag.data.len() % 4 != 0 || dims_tag.data.is_empty() {
        return Err(format!(
            "dimensions have type {} and {} bytes; expected miINT32 values",
            dims_tag.ty,
            dims_tag.data.len()
        ));
    }
    let ndims = dims_tag.data.len() / 4;
    if ndims > 64 {
        return Err(format!("{ndims} dimensions (at most 64 are read)"));
    }
    let mut dims = Vec::with_capacity(ndims);
    for k in 0..ndims {
        let d = e.u32(b, dims_tag.data.start + 4 * k) as i32;
        if d < 0 {
            return Err(format!("negative dimension {d}"));
        }
        dims.push(d as usize);
    }
    let name_tag = tag(e, b, dims_tag.next, end, "array name")?;
    if name_tag.ty != MI_INT8 && name_tag.ty != MI_UINT8 && name_tag.ty != MI_UTF8 {
        return Err(format!(
            "array name has type {}; expected miINT8 text",
            name_tag.ty
        ));
    }
    let name = String::from_utf8_lossy(&b[name_tag.data.clone()]).into_owned();
    Ok(MatrixHead {
        class,
        complex,
        logical,
        dims,
        name,
        rest: name_tag.next,
    })
}

/// The name of an opaque object, when its first element is readable.
fn opaque_name(e: Endian, b: &[u8], pos: usize, end: usize) -> String {
    tag(e, b, pos, end, "name")
        .ok()
        .filter(|t| t.ty == MI_INT8)
        .map(|t| String::from_utf8_lossy(&b[t.data]).into_owned())
        .unwrap_or_default()
}

impl<'a> V5File<'a> {
    /// Reads the header and the list of variables (names, classes and
    /// dimensions; compressed variables are inflated only as far as their
    /// header).
    ///
    /// # Errors
    /// The reason, in words, when the file is not a readable level-5 MAT-file.
    pub fn open(bytes: &'a [u8]) -> Result<Self, String> {
        if bytes.len() < HEADER_LEN {
            return Err(format!(
                "truncated MAT-file: {} bytes, shorter than the {HEADER_LEN}-byte header",
                bytes.len()
            ));
        }
        let little = match &bytes[126..128] {
            b"IM" => true,
            b"MI" => false,
            other => {
                return Err(format!(
                    "malformed MAT-file header: endian indicator '{}', expected 'IM' or 'MI'",
                    crate::error::excerpt_bytes(other)
                ))
            }
        };
        let e = Endian { little };
        // Subsystem data (MATLAB objects) follows the variables; it is not data for us.
        let mut end = bytes.len();
        let sub = &bytes[116..124];
        if sub.iter().any(|&b| b != 0 && b != b' ') {
            let w: [u8; 8] = sub.try_into().unwrap_or([0; 8]);
            let off = if little {
                u64::from_le_bytes(w)
            } else {
                u64::from_be_bytes(w)
            };
            if off > HEADER_LEN as u64 && off <= bytes.len() as u64 {
                end = off as usize;
            }
        }
        let mut vars = Vec::new();
        let mut pos = HEADER_LEN;
        while pos < end {
            let k = vars.len() + 1;
            if end - pos >= 4 {
                let ty = e.u32(bytes, pos);
                if ty != MI_MATRIX && ty != MI_COMPRESSED {
                    return Err(format!(
                        "malformed MAT-file: element {k} at byte {pos} has data type {ty}; \
                         expected a variable (14 or 15)"
                    ));
                }
            }
            let t = tag(e, bytes, pos, end, &format!("variable {k} at byte {pos}"))
                .map_err(|r| format!("truncated MAT-file (or a damaged length field): {r}"))?;
            let var = match t.ty {
                MI_MATRIX => {
                    let head = if t.data.is_empty() {
                        None
                    } else {
                        Some(
                            matrix_head(e, bytes, t.data.start, t.data.end)
                                .map_err(|r| format!("variable {k} at byte {pos}: {r}"))?,
                        )
                    };
                    top_var(head, t.data.start, t.data.end, None)
                }
                MI_COMPRESSED => {
                    let declared = peek_declared(e, &bytes[t.data.clone()])
                        .map_err(|r| format!("compressed variable {k} at byte {pos}: {r}"))?;
                    let head = peek_head(e, &bytes[t.data.clone()], declared)
                        .map_err(|r| format!("compressed variable {k} at byte {pos}: {r}"))?;
                    top_var(head, t.data.start, t.data.end, Some(declared))
                }
                other => {
                    return Err(format!(
                        "malformed MAT-file: element {k} at byte {pos} has data type {other}; \
                         expected a variable (14 or 15)"
                    ))
                }
            };
            vars.push(var);
            pos = t.next;
        }
        let n = vars.len();
        Ok(Self {
            bytes,
            little,
            vars,
            inflated: (0..n).map(|_| OnceCell::new()).collect(),
            values: (0..n).map(|_| OnceCell::new()).collect(),
        })
    }

    fn endian(&self) -> Endian {
        Endian {
            little: self.little,
        }
    }

    /// The `miMATRIX` data of variable `i` (inflated when compressed).
    fn matrix_bytes(&self, i: usize) -> Result<(&[u8], usize, usize), String> {
        let v = &self.vars[i];
        match v.compressed {
            None => Ok((self.bytes, v.start, v.end)),
            Some(declared) => {
                let data = match self.inflated[i].get() {
                    Some(d) => d,
                    None => {
                        let d = inflate(&self.bytes[v.start..v.end], 8 + declared)?;
                        let _ = self.inflated[i].set(d);
                        self.inflated[i].get().ok_or("inflated data lost")?
                    }
                };
                Ok((data, 8, 8 + declared))
            }
        }
    }

    /// Variable `i`, parsed (once) down to its numeric arrays.
    ///
    /// # Errors
    /// The reason, naming the variable.
    pub fn value(&self, i: usize) -> Result<&Value, String> {
        if let Some(v) = self.values[i].get() {
            return Ok(v);
        }
        let name = excerpt(&self.vars[i].name);
        let (b, start, end) = self
            .matrix_bytes(i)
            .map_err(|r| format!("variable '{name}': {r}"))?;
        let value = if start == end {
            empty()
        } else {
            let head = matrix_head(self.endian(), b, start, end)
                .map_err(|r| format!("variable '{name}': {r}"))?;
            Parser {
                e: self.endian(),
                b,
                var: i,
            }
            .contents(head, end, 0)
            .map_err(|e| e.message(&self.vars[i].name))?
        };
        let _ = self.values[i].set(value);
        self.values[i]
            .get()
            .ok_or_else(|| "parsed value lost".to_string())
    }

    /// The numbers of a numeric array of this file, as `f64`.
    ///
    /// # Errors
    /// When the span is not in the file (an internal error) or the type is
    /// not numeric.
    pub fn numbers(&self, s: &Span) -> Result<Vec<f64>, String> {
        let (b, _, _) = self.matrix_bytes(s.var)?;
        let bytes = b
            .get(s.start..s.start + s.len)
            .ok_or("array data outside its variable")?;
        convert(self.little, s.ty, bytes)
    }
}

fn top_var(
    head: Option<MatrixHead>,
    start: usize,
    end: usize,
    compressed: Option<usize>,
) -> TopVar {
    match head {
        Some(h) => TopVar {
            name: h.name,
            class: h.class,
            dims: h.dims,
            complex: h.complex,
            start,
            end,
            compressed,
        },
        None => TopVar {
            name: String::new(),
            class: 6,
            dims: vec![0, 0],
            complex: false,
            start,
            end,
            compressed,
        },
    }
}

fn empty() -> Value {
    Value::Other {
        class: "double".into(),
        dims: vec![0, 0],
        why: "empty",
    }
}

/// The uncompressed size a `miCOMPRESSED` stream declares for its `miMATRIX`
/// (its first 8 inflated bytes), refusing a stream that holds anything else.
fn peek_declared(e: Endian, z: &[u8]) -> Result<usize, String> {
    let head = inflate_prefix(z, 8)?;
    if head.len() < 8 {
        return Err("zlib stream ends before the variable's tag".into());
    }
    let ty = e.u32(&head, 0);
    if ty == MI_COMPRESSED {
        return Err("a compressed stream inside a compressed stream; MAT-files hold none".into());
    }
    if ty != MI_MATRIX {
        return Err(format!(
            "the stream holds an element of type {ty}; expected a variable (14)"
        ));
    }
    let n = e.u32(&head, 4) as usize;
    let can_hold = z.len().saturating_mul(MAX_RATIO).saturating_add(64);
    if n > can_hold {
        return Err(format!(
            "it claims {n} bytes uncompressed, more than its {} compressed bytes can hold",
            z.len()
        ));
    }
    Ok(n)
}

/// Name, class and dimensions of a compressed variable, from the first
/// inflated bytes (more only when its header is unusually long).
fn peek_head(e: Endian, z: &[u8], declared: usize) -> Result<Option<MatrixHead>, String> {
    if declared == 0 {
        return Ok(None);
    }
    let mut want = (8 + declared).min(1024);
    loop {
        let head = inflate_prefix(z, want)?;
        let end = head.len().min(8 + declared);
        match matrix_head(e, &head, 8, end) {
            Ok(h) => return Ok(Some(h)),
            Err(r) if end >= 8 + declared || head.len() < want => return Err(r),
            Err(_) => want = (want * 8).min(8 + declared).min(1 << 20),
        }
        if want >= 1 << 20 {
            let head = inflate_prefix(z, want)?;
            let end = head.len().min(8 + declared);
            return matrix_head(e, &head, 8, end).map(Some);
        }
    }
}

/// The first `n` bytes of a zlib stream (fewer if it ends first).
fn inflate_prefix(z: &[u8], n: usize) -> Result<Vec<u8>, String> {
    let mut d = Decompress::new(true);
    let mut out = Vec::with_capacity(n);
    loop {
        let before_in = d.total_in();
        let before_out = d.total_out();
        let status = d
            .decompress_vec(&z[d.total_in() as usize..], &mut out, FlushDecompress::None)
            .map_err(|e| format!("corrupt zlib stream ({e})"))?;
        if out.len() >= n || matches!(status, Status::StreamEnd) {
            return Ok(out);
        }
        if d.total_in() == before_in && d.total_out() == before_out {
            // No progress: the input ended inside the stream.
            return Ok(out);
        }
    }
}

/// Inflates a whole `miCOMPRESSED` stream into exactly `want` bytes (the
/// variable's tag and data), growing the buffer as data arrives; never more
/// than what the compressed bytes can hold.
fn inflate(z: &[u8], want: usize) -> Result<Vec<u8>, String> {
    let bound = want.min(z.len().saturating_mul(MAX_RATIO).saturating_add(64));
    let mut d = Decompress::new(true);
    let mut out: Vec<u8> = Vec::new();
    out.try_reserve_exact(bound.min(z.len().saturating_mul(4).saturating_add(4096)))
        .map_err(|_| format!("cannot allocate {bound} bytes"))?;
    loop {
        if out.len() == out.capacity() {
            let more = out.capacity().max(4096).min(bound - out.len());
            out.try_reserve_exact(more)
                .map_err(|_| format!("cannot allocate {} bytes", out.len() + more))?;
        }
        let before_in = d.total_in();
        let before_out = d.total_out();
        let status = d
            .decompress_vec(&z[d.total_in() as usize..], &mut out, FlushDecompress::None)
            .map_err(|e| format!("corrupt zlib stream ({e})"))?;
        if out.len() >= bound {
            out.truncate(bound);
            break;
        }
        if matches!(status, Status::StreamEnd)
            || (d.total_in() == before_in && d.total_out() == before_out)
        {
            break;
        }
    }
    if out.len() < want {
        return Err(format!(
            "the zlib stream ends after {} of the {want} bytes its variable declares \
             (truncated or corrupt)",
            out.len()
        ));
    }
    Ok(out)
}

/// Converts stored numbers to `f64`.
fn convert(little: bool, ty: u32, b: &[u8]) -> Result<Vec<f64>, String> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {
            b.chunks_exact($n)
                .map(|w| {
                    let a: [u8; $n] = w.try_into().unwrap_or([0; $n]);
                    let x = if little {
                        <$t>::from_le_bytes(a)
                    } else {
                        <$t>::from_be_bytes(a)
                    };
                    // 64-bit integers above 2^53 round to the nearest double.
                    x as f64
                })
                .collect()
        };
    }
    Ok(match ty {
        MI_DOUBLE => conv!(f64, 8),
        MI_SINGLE => conv!(f32, 4),
        MI_INT8 => conv!(i8, 1),
        MI_UINT8 => conv!(u8, 1),
        MI_INT16 => conv!(i16, 2),
        MI_UINT16 => conv!(u16, 2),
        MI_INT32 => conv!(i32, 4),
        MI_UINT32 => conv!(u32, 4),
        MI_INT64 => conv!(i64, 8),
        MI_UINT64 => conv!(u64, 8),
        other => return Err(format!("data type {other} is not numeric")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use parse::text_rows;

    #[test]
    fn text_rows_reads_column_major_char_matrices() {
        // ['ab'; 'cd'] is stored a, c, b, d.
        assert_eq!(text_rows(&['a', 'c', 'b', 'd'], &[2, 2]), "ab\ncd");
        assert_eq!(text_rows(&['x', 'y'], &[1, 2]), "xy");
        // No characters: no rows, whatever the dimensions say.
        assert_eq!(text_rows(&[], &[i32::MAX as usize, 0]), "");
    }

    #[test]
    fn inflate_is_bounded_by_the_declared_size_and_the_stream() {
        use std::io::Write;
        let mut enc = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        enc.write_all(&[7u8; 10_000]).unwrap();
        let z = enc.finish().unwrap();
        assert_eq!(inflate(&z, 10_000).unwrap().len(), 10_000);
        // Asked for less: stops there.
        assert_eq!(inflate(&z, 100).unwrap().len(), 100);
        // Asked for more than the stream holds: an error, no huge buffer.
        let e = inflate(&z, 1 << 40).unwrap_err();
        assert!(e.contains("ends after 10000"), "{e}");
        // A truncated stream.
        assert!(inflate(&z[..z.len() / 2], 10_000).is_err());
    }
}
