//! MATLAB values as read from a MAT-file of either kind (level 5 or v7.3),
//! and paths into them (`bearing.gs`, `rec.Y(2).Data`, `c{3}`).
//!
//! Numeric data stays in the file until asked for ([`Data`]): a file is
//! listed and searched without converting arrays nobody uses.

use super::v5::Span;
use super::v73::H5Data;

/// One MATLAB value.
pub(crate) enum Value {
    /// A real numeric or logical array.
    Numeric(Numeric),
    /// A character array, as text (rows joined by newlines).
    Text(String),
    /// A struct array: `elems[k][f]` is field `f` of element `k`.
    Struct(Struct),
    /// A cell array.
    Cell {
        /// MATLAB dimensions.
        dims: Vec<usize>,
        /// Elements in MATLAB (column-major) order.
        items: Vec<Value>,
    },
    /// Something that holds no channel for us (complex, sparse, objects,
    /// function handles), with what it is.
    Other {
        /// MATLAB class name or a description.
        class: String,
        /// Dimensions, when known.
        dims: Vec<usize>,
        /// Why it cannot be a channel.
        why: &'static str,
    },
}

/// A real numeric array whose data is read on request.
pub(crate) struct Numeric {
    /// MATLAB dimensions.
    pub dims: Vec<usize>,
    /// MATLAB class (`double`, `int32`, `logical`, ...).
    pub class: &'static str,
    /// Where the values are.
    pub data: Data,
}

/// Where the values of a numeric array are.
pub(crate) enum Data {
    /// Bytes of a level-5 file.
    V5(Span),
    /// A dataset of a v7.3 (HDF5) file.
    H5(Box<H5Data>),
}

/// A struct array.
pub(crate) struct Struct {
    /// MATLAB dimensions.
    pub dims: Vec<usize>,
    /// Field names, in file order.
    pub fields: Vec<String>,
    /// `elems[k][f]`: field `f` of element `k` (column-major order).
    pub elems: Vec<Vec<Value>>,
}

impl Struct {
    /// Field `name` of element `k` (name matched exactly, then ignoring case).
    pub fn field(&self, k: usize, name: &str) -> Option<&Value> {
        let f = self.fields.iter().position(|f| f == name).or_else(|| {
            self.fields
                .iter()
                .position(|f| f.eq_ignore_ascii_case(name))
        })?;
        self.elems.get(k)?.get(f)
    }

    /// The only element of a 1x1 struct.
    pub fn single(&self) -> Option<&[Value]> {
        match self.elems.as_slice() {
            [one] => Some(one),
            _ => None,
        }
    }
}

/// MATLAB class names by level-5 class number.
pub(crate) fn class_name(class: u8) -> &'static str {
    match class {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        16 => "function_handle",
        17 => "opaque",
        _ => "unknown",
    }
}

/// `200x1`.
pub(crate) fn dims_text(dims: &[usize]) -> String {
    dims.iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join("x")
}

/// Number of elements of an array of these dimensions, `None` on overflow.
pub(crate) fn count(dims: &[usize]) -> Option<usize> {
    dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d))
}

impl Value {
    /// What the value is, for listings: `double 200x1`, `struct 1x1`.
    pub fn describe(&self) -> String {
        match self {
            Value::Numeric(n) => format!("{} {}", n.class, dims_text(&n.dims)),
            Value::Text(t) => format!("char '{}'", crate::error::excerpt(t)),
            Value::Struct(s) => format!("struct {}", dims_text(&s.dims)),
            Value::Cell { dims, .. } => format!("cell {}", dims_text(dims)),
            Value::Other { class, dims, why } if dims.is_empty() => format!("{class} ({why})"),
            Value::Other { class, dims, why } => {
                format!("{class} {} ({why})", dims_text(dims))
            }
        }
    }

    /// The numeric array, if this is a vector (one row or one column).
    pub fn as_vector(&self) -> Option<&Numeric> {
        match self {
            Value::Numeric(n) if n.dims.iter().filter(|&&d| d > 1).count() <= 1 => Some(n),
            _ => None,
        }
    }

    /// A 1x1 struct or a struct array of one element, as its struct.
    pub fn as_struct(&self) -> Option<&Struct> {
        match self {
            Value::Struct(s) => Some(s),
            _ => None,
        }
    }
}

/// One step of a path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Step {
    /// `.name`: a struct field.
    Field(String),
    /// `(k)`: element `k` (1-based) of a struct array.
    Index(usize),
    /// `{k}`: element `k` (1-based) of a cell array.
    Cell(usize),
}

/// Parses `name.field(2).other{3}` into the variable name and the steps;
/// `None` when it is not such a path (a plain name gives no steps).
pub(crate) fn parse_path(s: &str) -> Option<(String, Vec<Step>)> {
    let s = s.trim();
    // MATLAB names: letters, digits and underscores.
    let ident_end = |t: &str| {
        t.find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(t.len())
    };
    let head_len = ident_end(s);
    let head = &s[..head_len];
    if head.is_empty() {
        return None;
    }
    let mut steps = Vec::new();
    let mut rest = &s[head_len..];
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('.') {
            let n = ident_end(r);
            if n == 0 {
                return None;
            }
            steps.push(Step::Field(r[..n].to_string()));
            rest = &r[n..];
        } else {
            let (close, cell) = match rest.as_bytes()[0] {
                b'(' => (')', false),
                b'{' => ('}', true),
                _ => return None,
            };
            let end = rest.find(close)?;
            let k: usize = rest[1..end].trim().parse().ok().filter(|&k| k >= 1)?;
            steps.push(if cell { Step::Cell(k) } else { Step::Index(k) });
            rest = &rest[end + 1..];
        }
        if steps.len() > 64 {
            return None;
        }
    }
    Some((head.to_string(), steps))
}

/// Follows `steps` from `v`; `Err` says which step found nothing.
pub(crate) fn walk<'v>(v: &'v Value, steps: &[Step]) -> Result<&'v Value, String> {
    let mut cur = v;
    // The element of a struct array chosen by an `(k)` step.
    let mut chosen: Option<usize> = None;
    for step in steps {
        match (step, cur) {
            (Step::Field(name), Value::Struct(s)) => {
                let k = match (chosen.take(), s.elems.len()) {
                    (Some(k), _) => k,
                    (None, 1) => 0,
                    (None, n) => {
                        return Err(format!(
                            "a {} struct array ({n} elements) has no single '{}': name an \
                             element, as in (1).{}",
                            dims_text(&s.dims),
                            crate::error::excerpt(name),
                            crate::error::excerpt(name)
                        ))
                    }
                };
                cur = s.field(k, name).ok_or_else(|| {
                    format!(
                        "no field '{}' (fields: {})",
                        crate::error::excerpt(name),
                        list_names(&s.fields)
                    )
                })?;
            }
            (Step::Index(k), Value::Struct(s)) if chosen.is_none() => {
                if *k > s.elems.len() {
                    return Err(format!(
                        "index ({k}) beyond the {} elements of the struct array",
                        s.elems.len()
                    ));
                }
                chosen = Some(k - 1);
            }
            (Step::Cell(k), Value::Cell { items, .. }) => {
                cur = items
                    .get(k - 1)
                    .ok_or_else(|| format!("index {{{k}}} beyond the {} cells", items.len()))?;
            }
            (_, other) => {
                return Err(format!(
                    "cannot apply {} to a {}",
                    step_text(step),
                    other.describe()
                ))
            }
        }
    }
    if let Some(k) = chosen {
        return Err(format!(
            "({}) selects a struct, not numbers: name a field",
            k + 1
        ));
    }
    Ok(cur)
}

fn step_text(step: &Step) -> String {
    match step {
        Step::Field(f) => format!(".{}", crate::error::excerpt(f)),
        Step::Index(k) => format!("({k})"),
        Step::Cell(k) => format!("{{{k}}}"),
    }
}

fn list_names(names: &[String]) -> String {
    let shown: Vec<String> = names
        .iter()
        .take(20)
        .map(|n| crate::error::excerpt(n))
        .collect();
    let more = names.len().saturating_sub(shown.len());
    if more > 0 {
        format!("{}, and {more} more", shown.join(", "))
    } else if shown.is_empty() {
        "none".into()
    } else {
        shown.join(", ")
    }
}

/// Every value below `v` reachable by a path, with its path, depth first,
/// at most `limit` of them (a listing, never a workload).
pub(crate) fn leaves<'v>(name: &str, v: &'v Value, limit: usize) -> Vec<(String, &'v Value)> {
    let mut out = Vec::new();
    let mut stack: Vec<(String, &Value)> = vec![(name.to_string(), v)];
    while let Some((path, v)) = stack.pop() {
        if out.len() >= limit {
            break;
        }
        match v {
            Value::Struct(s) => {
                let single = s.elems.len() == 1;
                // Push in reverse so that the listing comes out in file order.
                for (k, elem) in s.elems.iter().enumerate().rev() {
                    for (f, value) in s.fields.iter().zip(elem).rev() {
                        let p = if single {
                            format!("{path}.{f}")
                        } else {
                            format!("{path}({}).{f}", k + 1)
                        };
                        stack.push((p, value));
                    }
                }
                out.push((path, v));
            }
            Value::Cell { items, .. } => {
                for (k, item) in items.iter().enumerate().rev() {
                    stack.push((format!("{path}{{{}}}", k + 1), item));
                }
                out.push((path, v));
            }
            _ => out.push((path, v)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_fields_indices_and_cells() {
        assert_eq!(
            parse_path("bearing.gs"),
            Some(("bearing".into(), vec![Step::Field("gs".into())]))
        );
        assert_eq!(
            parse_path("rec.Y(2).Data"),
            Some((
                "rec".into(),
                vec![
                    Step::Field("Y".into()),
                    Step::Index(2),
                    Step::Field("Data".into())
                ]
            ))
        );
        assert_eq!(parse_path("c{3}"), Some(("c".into(), vec![Step::Cell(3)])));
        assert_eq!(parse_path("x"), Some(("x".into(), vec![])));
        for bad in ["", ".a", "a.", "a(0)", "a(x)", "a(1", "a..b", "a)"] {
            assert_eq!(parse_path(bad), None, "{bad}");
        }
    }
}
