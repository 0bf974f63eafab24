//! The parser of one level-5 variable: walks a `miMATRIX` element (numeric,
//! char, logical, sparse, cell, struct and object arrays, nested at most
//! [`MAX_DEPTH`] levels) into a [`Value`], checking every length against
//! its container before anything is allocated from it.

use super::*;

/// Why a variable cannot be read, and where in it (innermost step first).
pub(super) struct PErr {
    reason: String,
    path: Vec<String>,
}

impl From<String> for PErr {
    fn from(reason: String) -> Self {
        Self {
            reason,
            path: Vec::new(),
        }
    }
}

impl PErr {
    /// `variable 'x' at x.f{2}: reason`, the path bounded.
    pub(super) fn message(&self, name: &str) -> String {
        let at = if self.path.is_empty() {
            String::new()
        } else {
            let p: String = self.path.iter().rev().map(String::as_str).collect();
            format!(
                " at {}",
                crate::error::excerpt_within(&format!("{name}{p}"), 100)
            )
        };
        format!("variable '{}'{at}: {}", excerpt(name), self.reason)
    }
}

/// Walks the contents of one variable.
pub(super) struct Parser<'b> {
    pub(super) e: Endian,
    pub(super) b: &'b [u8],
    pub(super) var: usize,
}

impl Parser<'_> {
    /// The value of a `miMATRIX` whose header is `h` and whose data ends at `end`.
    pub(super) fn contents(&self, h: MatrixHead, end: usize, depth: usize) -> Result<Value, PErr> {
        let n =
            count(&h.dims).ok_or_else(|| format!("dimensions {} overflow", dims_text(&h.dims)))?;
        let room = end.saturating_sub(h.rest);
        match h.class {
            1 => {
                // Each cell is an element of at least 8 bytes.
                self.deeper(depth)?;
                if n > room / 8 {
                    return Err(format!(
                        "cell {} claims {n} cells; its {room} bytes hold at most {}",
                        dims_text(&h.dims),
                        room / 8
                    )
                    .into());
                }
                let mut items = Vec::with_capacity(n);
                let mut pos = h.rest;
                for k in 0..n {
                    let (v, next) = self.child(pos, end, depth + 1, || format!("{{{}}}", k + 1))?;
                    items.push(v);
                    pos = next;
                }
                Ok(Value::Cell {
                    dims: h.dims,
                    items,
                })
            }
            2 | 3 => {
                self.deeper(depth)?;
                let mut pos = h.rest;
                let mut object_class = None;
                if h.class == 3 {
                    let t = tag(self.e, self.b, pos, end, "object class name")?;
                    object_class = Some(String::from_utf8_lossy(&self.b[t.data]).into_owned());
                    pos = t.next;
                }
                let len_tag = tag(self.e, self.b, pos, end, "field name length")?;
                if len_tag.ty != MI_INT32 || len_tag.data.len() != 4 {
                    return Err(PErr::from(
                        "field name length is not one miINT32".to_string(),
                    ));
                }
                let len = self.e.u32(self.b, len_tag.data.start) as usize;
                let names_tag = tag(self.e, self.b, len_tag.next, end, "field names")?;
                let names_len = names_tag.data.len();
                if len == 0 && names_len > 0 || len > 0 && names_len % len != 0 {
                    return Err(format!(
                        "field names of {names_len} bytes are not a multiple of their length {len}"
                    )
                    .into());
                }
                let nfields = names_len.checked_div(len).unwrap_or(0);
                let fields: Vec<String> = (0..nfields)
                    .map(|f| {
                        let raw = &self.b[names_tag.data.start + f * len..][..len];
                        let raw = raw.split(|&c| c == 0).next().unwrap_or(raw);
                        String::from_utf8_lossy(raw).into_owned()
                    })
                    .collect();
                let slots = n.saturating_mul(nfields);
                let room = end.saturating_sub(names_tag.next);
                if slots > room / 8 {
                    return Err(format!(
                        "struct {} with {nfields} fields claims {slots} values; its {room} bytes \
                         hold at most {}",
                        dims_text(&h.dims),
                        room / 8
                    )
                    .into());
                }
                // A struct without fields holds nothing whatever its size:
                // no elements are made for it (its dimensions are kept).
                let n_elems = if nfields == 0 { 0 } else { n };
                let mut elems = Vec::with_capacity(n_elems);
                let mut pos = names_tag.next;
                for k in 0..n_elems {
                    let mut elem = Vec::with_capacity(nfields);
                    for name in &fields {
                        let (v, next) = self.child(pos, end, depth + 1, || {
                            if n == 1 {
                                format!(".{name}")
                            } else {
                                format!("({}).{name}", k + 1)
                            }
                        })?;
                        elem.push(v);
                        pos = next;
                    }
                    elems.push(elem);
                }
                let s = Struct {
                    dims: h.dims,
                    fields,
                    elems,
                };
                Ok(match object_class {
                    None => Value::Struct(s),
                    Some(class) => Value::Other {
                        class,
                        dims: s.dims,
                        why: "a MATLAB object",
                    },
                })
            }
            4 => {
                let t = tag(self.e, self.b, h.rest, end, "characters")?;
                let bytes = &self.b[t.data.clone()];
                let chars: Vec<char> = match t.ty {
                    MI_UTF8 => String::from_utf8_lossy(bytes).chars().collect(),
                    MI_INT8 | MI_UINT8 => bytes.iter().map(|&c| char::from(c)).collect(),
                    MI_UTF16 | MI_UINT16 | MI_INT16 => {
                        let units: Vec<u16> = bytes
                            .chunks_exact(2)
                            .map(|w| {
                                if self.e.little {
                                    u16::from_le_bytes([w[0], w[1]])
                                } else {
                                    u16::from_be_bytes([w[0], w[1]])
                                }
                            })
                            .collect();
                        char::decode_utf16(units)
                            .map(|c| c.unwrap_or('\u{fffd}'))
                            .collect()
                    }
                    MI_UTF32 | MI_UINT32 | MI_INT32 => bytes
                        .chunks_exact(4)
                        .map(|w| char::from_u32(self.e.u32(w, 0)).unwrap_or('\u{fffd}'))
                        .collect(),
                    other => return Err(format!("characters stored as type {other}").into()),
                };
                Ok(Value::Text(text_rows(&chars, &h.dims)))
            }
            5 => Ok(Value::Other {
                class: "sparse".into(),
                dims: h.dims,
                why: "sparse; expected a full numeric vector",
            }),
            6..=15 => {
                let t = tag(self.e, self.b, h.rest, end, "real part")?;
                let size = type_size(t.ty).ok_or_else(|| {
                    format!("numbers stored as type {}, which is not numeric", t.ty)
                })?;
                if t.ty == MI_UTF8 || t.ty == MI_UTF16 || t.ty == MI_UTF32 {
                    return Err(format!("numbers stored as text type {}", t.ty).into());
                }
                if n.checked_mul(size) != Some(t.data.len()) {
                    return Err(format!(
                        "{} {} needs {n} values but holds {} bytes of {size}-byte values",
                        class_name(h.class),
                        dims_text(&h.dims),
                        t.data.len()
                    )
                    .into());
                }
                if h.complex {
                    return Ok(Value::Other {
                        class: class_name(h.class).into(),
                        dims: h.dims,
                        why: "complex; expected real numbers",
                    });
                }
                Ok(Value::Numeric(Numeric {
                    dims: h.dims,
                    class: if h.logical {
                        "logical"
                    } else {
                        class_name(h.class)
                    },
                    data: Data::V5(Span {
                        var: self.var,
                        start: t.data.start,
                        len: t.data.len(),
                        ty: t.ty,
                    }),
                }))
            }
            16 => Ok(Value::Other {
                class: "function_handle".into(),
                dims: Vec::new(),
                why: "a function handle",
            }),
            17 => Ok(Value::Other {
                class: if h.name.is_empty() {
                    "opaque".into()
                } else {
                    "opaque object".into()
                },
                dims: Vec::new(),
                why: "a MATLAB object (string, table, ...); save plain arrays",
            }),
            other => Err(format!("unknown array class {other}").into()),
        }
    }

    fn deeper(&self, depth: usize) -> Result<(), String> {
        if depth >= MAX_DEPTH {
            return Err(format!(
                "structs and cells nested more than {MAX_DEPTH} levels deep"
            ));
        }
        Ok(())
    }

    /// The `miMATRIX` child at `pos` and where the next one starts.
    fn child(
        &self,
        pos: usize,
        end: usize,
        depth: usize,
        step: impl Fn() -> String,
    ) -> Result<(Value, usize), PErr> {
        let at = |e: PErr| PErr {
            path: {
                let mut p = e.path;
                p.push(step());
                p
            },
            reason: e.reason,
        };
        let t = tag(self.e, self.b, pos, end, "element").map_err(|r| at(r.into()))?;
        if t.ty == MI_COMPRESSED {
            return Err(at(
                "compressed data inside a variable; MAT-files compress whole variables only"
                    .to_string()
                    .into(),
            ));
        }
        if t.ty != MI_MATRIX {
            return Err(at(format!(
                "element of type {}; expected an array (14)",
                t.ty
            )
            .into()));
        }
        if t.data.is_empty() {
            return Ok((empty(), t.next));
        }
        let h = matrix_head(self.e, self.b, t.data.start, t.data.end).map_err(|r| at(r.into()))?;
        let v = self.contents(h, t.data.end, depth).map_err(at)?;
        Ok((v, t.next))
    }
}

/// A char array (column-major) as rows of text joined by newlines.
pub(super) fn text_rows(chars: &[char], dims: &[usize]) -> String {
    let rows = dims.first().copied().unwrap_or(1).max(1);
    // An empty array makes no rows whatever its dimensions claim (2^31 rows
    // of nothing once reserved 51 GB); otherwise rows <= chars, and the text
    // is built in one string of about the characters' size.
    if rows == 1 || chars.is_empty() || chars.len() % rows != 0 {
        return chars.iter().collect();
    }
    let cols = chars.len() / rows;
    let mut out = String::with_capacity(chars.len() + rows);
    for r in 0..rows {
        if r > 0 {
            out.push('\n');
        }
        out.extend((0..cols).map(|c| chars[c * rows + r]));
    }
    out
}
