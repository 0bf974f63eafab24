//! MATLAB v7.3 MAT-files (`save -v7.3`, MATLAB's default for large data):
//! HDF5 containers read with the pure-Rust `hdf5-reader` crate.
//!
//! MATLAB's layout: a 512-byte text header (user block), then HDF5 with one
//! root member per variable, each carrying a `MATLAB_class` attribute.
//!
//! - numeric, logical and char arrays are datasets whose HDF5 shape is the
//!   MATLAB dimensions reversed (MATLAB is column-major); `MATLAB_empty`
//!   marks an empty array;
//! - a 1x1 struct is a group whose members are its fields;
//! - a struct array is a group whose fields are datasets of object
//!   references (without a `MATLAB_class`) into the `#refs#` group;
//! - a cell array is a dataset of object references with class `cell`.
//!
//! The tree is built into the same [`Value`] as a level-5 file's, with
//! numeric data read only when asked for. Bounds: [`super::v5::MAX_DEPTH`]
//! levels of nesting (references may form cycles), at most one value per 8
//! bytes of file, and reads limited to what the file can hold.

use std::cell::Cell;
use std::collections::HashMap;

use std::path::Path;
use std::sync::Arc;

use hdf5_reader::group::Group;
use hdf5_reader::storage::FileStorage;
use hdf5_reader::{Dataset, Datatype, Hdf5File, OpenOptions, SliceInfo, SliceInfoElem};

use super::tree::{count, Data, Numeric, Struct, Value};
use super::v5::MAX_DEPTH;
use crate::error::excerpt;
use crate::recording::io::contain::{contain, detail};

/// A numeric dataset of a v7.3 file, read on request (whole, or a range of
/// its values when streamed).
#[derive(Clone)]
pub(crate) struct H5Data {
    ds: Dataset,
}

/// A v7.3 file: its top-level variables, parsed.
pub(crate) struct V73File {
    /// Variables in file order (names starting with `#` are MATLAB's own).
    pub vars: Vec<(String, Value)>,
}

type R<T> = std::result::Result<T, String>;

fn h5<T>(what: &str, f: impl FnOnce() -> hdf5_reader::error::Result<T>) -> R<T> {
    match contain(f) {
        Some(Ok(v)) => Ok(v),
        Some(Err(e)) => Err(format!("{what}: {}", detail(&e))),
        None => Err(format!("{what}: the HDF5 structure could not be decoded")),
    }
}

impl V73File {
    /// Opens an HDF5 MAT-file held in memory and builds its variable tree.
    ///
    /// # Errors
    /// The reason, in words, for a damaged or unreadable file.
    pub fn open(bytes: &[u8]) -> R<Self> {
        Self::open_with(bytes.len(), 0, |options| {
            Hdf5File::from_bytes_with_options(bytes, options)
        })
    }

    /// Opens an HDF5 MAT-file on disk, reading only the parts asked for
    /// (the streamed reader's way), with a chunk cache of `cache_bytes`.
    ///
    /// # Errors
    /// As [`V73File::open`], and the file's read error.
    pub fn open_path(path: &Path, cache_bytes: usize) -> R<Self> {
        let storage = h5("cannot be opened", || FileStorage::open(path))?;
        let len = usize::try_from(hdf5_reader::storage::Storage::len(&storage))
            .map_err(|_| "file too large".to_string())?;
        Self::open_with(len, cache_bytes, |options| {
            Hdf5File::from_storage_with_options(Arc::new(storage), options)
        })
    }

    /// The tree of the HDF5 file of `len` bytes that `make` opens with the
    /// reader's bounds.
    fn open_with(
        len: usize,
        cache_bytes: usize,
        make: impl FnOnce(OpenOptions) -> hdf5_reader::error::Result<Hdf5File>,
    ) -> R<Self> {
        // Nothing read can exceed what the file holds, inflated at most 1032:1.
        let can_hold = len.saturating_mul(1032).saturating_add(1 << 20);
        let options = OpenOptions::default()
            .with_chunk_cache_bytes(cache_bytes)
            .with_max_read_bytes(can_hold)
            .with_max_chunk_bytes(can_hold.min(64 << 20))
            .with_max_object_header_bytes(len.clamp(4096, 64 << 20));
        let file = h5("not a readable HDF5 file", || make(options))?;
        let root = h5("no root group", || file.root_group())?;
        let mut b = Builder {
            budget: Cell::new(len / 8 + 64),
            refs: HashMap::new(),
            offset_size: contain(|| root.offset_size()).unwrap_or(8),
        };
        if let Ok(refs) = h5("#refs#", || root.group("#refs#")) {
            let (groups, datasets) = h5("#refs#", || refs.members())?;
            for g in groups {
                b.refs.insert(g.address(), Obj::Group(g));
            }
            for d in datasets {
                b.refs.insert(d.address(), Obj::Dataset(Box::new(d)));
            }
        }
        let (groups, datasets) = h5("root group", || root.members())?;
        let mut objs: Vec<(String, Obj)> = groups
            .into_iter()
            .map(|g| (g.name().to_string(), Obj::Group(g)))
            .chain(
                datasets
                    .into_iter()
                    .map(|d| (d.name().to_string(), Obj::Dataset(Box::new(d)))),
            )
            .filter(|(n, _)| !n.starts_with('#'))
            .collect();
        objs.sort_by(|a, b| a.0.cmp(&b.0));
        let mut vars = Vec::with_capacity(objs.len());
        for (name, obj) in objs {
            let v = b
                .value(&obj, 0)
                .map_err(|r| format!("variable '{}': {r}", excerpt(&name)))?;
            vars.push((name, v));
        }
        Ok(Self { vars })
    }
}

/// An HDF5 object: a group or a dataset.
enum Obj {
    Group(Group),
    Dataset(Box<Dataset>),
}

struct Builder {
    /// Values left to build (one per 8 bytes of file).
    budget: Cell<usize>,
    /// `#refs#` members by address.
    refs: HashMap<u64, Obj>,
    offset_size: u8,
}

fn class_of_attrs(attrs: &[hdf5_reader::Attribute]) -> Option<String> {
    attrs
        .iter()
        .find(|a| a.name == "MATLAB_class")
        .and_then(|a| contain(|| a.read_string()).and_then(Result::ok))
        .map(|s| s.trim_end_matches('\0').to_string())
}

fn has_attr(attrs: &[hdf5_reader::Attribute], name: &str) -> bool {
    attrs.iter().any(|a| a.name == name)
}

/// MATLAB dimensions from an HDF5 shape (reversed; a scalar is 1x1).
fn matlab_dims(shape: &[u64]) -> R<Vec<usize>> {
    let mut d: Vec<usize> = shape
        .iter()
        .rev()
        .map(|&x| usize::try_from(x).map_err(|_| format!("dimension {x} too large")))
        .collect::<R<_>>()?;
    while d.len() < 2 {
        d.push(1);
    }
    Ok(d)
}

fn static_class(class: &str) -> Option<&'static str> {
    Some(match class {
        "double" => "double",
        "single" => "single",
        "int8" => "int8",
        "uint8" => "uint8",
        "int16" => "int16",
        "uint16" => "uint16",
        "int32" => "int32",
        "uint32" => "uint32",
        "int64" => "int64",
        "uint64" => "uint64",
        "logical" => "logical",
        _ => return None,
    })
}

impl Builder {
    fn spend(&self) -> R<()> {
        let left = self.budget.get();
        if left == 0 {
            return Err("more values than the file can hold (references repeat?)".into());
        }
        self.budget.set(left - 1);
        Ok(())
    }

    fn value(&self, obj: &Obj, depth: usize) -> R<Value> {
        self.spend()?;
        if depth > MAX_DEPTH {
            return Err(format!(
                "structs and cells nested more than {MAX_DEPTH} levels deep"
            ));
        }
        match obj {
            Obj::Dataset(ds) => self.dataset(ds, depth),
            Obj::Group(g) => self.group(g, depth),
        }
    }

    fn dataset(&self, ds: &Dataset, depth: usize) -> R<Value> {
        let attrs = contain(|| ds.attributes()).unwrap_or_default();
        let class = class_of_attrs(&attrs).unwrap_or_default();
        let dims = matlab_dims(ds.shape())?;
        if has_attr(&attrs, "MATLAB_empty") {
            return Ok(Value::Other {
                class: if class.is_empty() {
                    "double".into()
                } else {
                    class
                },
                dims: vec![0, 0],
                why: "empty",
            });
        }
        if has_attr(&attrs, "MATLAB_object_decode") {
            return Ok(Value::Other {
                class,
                dims,
                why: "a MATLAB object (string, table, ...); save plain arrays",
            });
        }
        match class.as_str() {
            "cell" => {
                let items = self
                    .references(ds)?
                    .into_iter()
                    .map(|addr| self.deref(addr, depth + 1))
                    .collect::<R<Vec<_>>>()?;
                Ok(Value::Cell { dims, items })
            }
            "char" => {
                let n = count(&dims).ok_or("dimensions overflow")?;
                let units: Vec<u16> = match ds.dtype() {
                    Datatype::FixedPoint { size: 2, .. } => {
                        h5("characters", || ds.read_array::<u16>())?
                            .iter()
                            .copied()
                            .collect()
                    }
                    Datatype::FixedPoint { size: 1, .. } => {
                        h5("characters", || ds.read_array::<u8>())?
                            .iter()
                            .map(|&c| u16::from(c))
                            .collect()
                    }
                    other => return Err(format!("characters stored as {other:?}")),
                };
                if units.len() != n {
                    return Err(format!("{} characters for {n}", units.len()));
                }
                Ok(Value::Text(
                    char::decode_utf16(units)
                        .map(|c| c.unwrap_or('\u{fffd}'))
                        .collect(),
                ))
            }
            c => match (static_class(c), ds.dtype()) {
                (Some(class), Datatype::FixedPoint { .. } | Datatype::FloatingPoint { .. }) => {
                    Ok(Value::Numeric(Numeric {
                        dims,
                        class,
                        data: Data::H5(Box::new(H5Data { ds: ds.clone() })),
                    }))
                }
                (Some(class), Datatype::Compound { .. }) => Ok(Value::Other {
                    class: class.into(),
                    dims,
                    why: "complex; expected real numbers",
                }),
                (None, Datatype::FixedPoint { .. } | Datatype::FloatingPoint { .. })
                    if c.is_empty() =>
                {
                    // An HDF5 file not written by MATLAB: numbers without a class.
                    Ok(Value::Numeric(Numeric {
                        dims,
                        class: "double",
                        data: Data::H5(Box::new(H5Data { ds: ds.clone() })),
                    }))
                }
                _ => Ok(Value::Other {
                    class: if c.is_empty() {
                        "dataset".into()
                    } else {
                        c.into()
                    },
                    dims,
                    why: "not a numeric array",
                }),
            },
        }
    }

    fn group(&self, g: &Group, depth: usize) -> R<Value> {
        let attrs = h5("attributes", || g.attributes())?;
        let class = class_of_attrs(&attrs).unwrap_or_else(|| "struct".into());
        if has_attr(&attrs, "MATLAB_sparse") {
            return Ok(Value::Other {
                class: "sparse".into(),
                dims: Vec::new(),
                why: "sparse; expected a full numeric vector",
            });
        }
        if class != "struct" {
            return Ok(Value::Other {
                class,
                dims: Vec::new(),
                why: "a MATLAB object; save plain arrays",
            });
        }
        let (groups, datasets) = h5("struct fields", || g.members())?;
        let mut members: Vec<(String, Obj)> = groups
            .into_iter()
            .map(|x| (x.name().to_string(), Obj::Group(x)))
            .chain(
                datasets
                    .into_iter()
                    .map(|x| (x.name().to_string(), Obj::Dataset(Box::new(x)))),
            )
            .collect();
        // MATLAB's field order, when recorded.
        let order: Vec<String> = attrs
            .iter()
            .find(|a| a.name == "MATLAB_fields")
            .and_then(|a| contain(|| a.read_strings()).and_then(Result::ok))
            .unwrap_or_default();
        members.sort_by_key(|(n, _)| order.iter().position(|o| o == n).unwrap_or(usize::MAX));
        // A struct array: fields are reference datasets without a class.
        let array_dims = members.iter().find_map(|(_, o)| match o {
            Obj::Dataset(ds)
                if matches!(ds.dtype(), Datatype::Reference { .. })
                    && class_of_attrs(&contain(|| ds.attributes()).unwrap_or_default())
                        .is_none() =>
            {
                Some(ds.shape().to_vec())
            }
            _ => None,
        });
        let fields: Vec<String> = members.iter().map(|(n, _)| n.clone()).collect();
        match array_dims {
            None => {
                let mut elem = Vec::with_capacity(members.len());
                for (name, obj) in &members {
                    elem.push(
                        self.value(obj, depth + 1)
                            .map_err(|r| format!("field '{}': {r}", excerpt(name)))?,
                    );
                }
                Ok(Value::Struct(Struct {
                    dims: vec![1, 1],
                    fields,
                    elems: vec![elem],
                }))
            }
            Some(shape) => {
                let dims = matlab_dims(&shape)?;
                let n = count(&dims).ok_or("dimensions overflow")?;
                let mut columns = Vec::with_capacity(members.len());
                for (name, obj) in &members {
                    let Obj::Dataset(ds) = obj else {
                        return Err(format!(
                            "field '{}' of a struct array is a group; expected references",
                            excerpt(name)
                        ));
                    };
                    let refs = self.references(ds)?;
                    if refs.len() != n {
                        return Err(format!(
                            "field '{}' has {} elements, the struct array {n}",
                            excerpt(name),
                            refs.len()
                        ));
                    }
                    columns.push(refs);
                }
                let mut elems = Vec::with_capacity(n);
                for k in 0..n {
                    let mut elem = Vec::with_capacity(columns.len());
                    for (f, col) in columns.iter().enumerate() {
                        elem.push(self.deref(col[k], depth + 1).map_err(|r| {
                            format!("field '{}' of element {}: {r}", excerpt(&fields[f]), k + 1)
                        })?);
                    }
                    elems.push(elem);
                }
                Ok(Value::Struct(Struct {
                    dims,
                    fields,
                    elems,
                }))
            }
        }
    }

    /// The object addresses a reference dataset holds.
    fn references(&self, ds: &Dataset) -> R<Vec<u64>> {
        if !matches!(ds.dtype(), Datatype::Reference { .. }) {
            return Err(format!(
                "expected object references, found {:?}",
                ds.dtype()
            ));
        }
        let raw = h5("references", || ds.read_raw_bytes())?;
        if raw.len() / usize::from(self.offset_size.max(1)) > self.budget.get() {
            return Err("more references than the file can hold".into());
        }
        h5("references", || {
            hdf5_reader::reference::read_object_references(&raw, self.offset_size)
        })
    }

    fn deref(&self, addr: u64, depth: usize) -> R<Value> {
        let obj = self
            .refs
            .get(&addr)
            .ok_or_else(|| format!("a reference to {addr:#x}, which is not in #refs#"))?;
        self.value(obj, depth)
    }
}

impl H5Data {
    /// The numbers, as `f64`.
    ///
    /// # Errors
    /// The reason, for a damaged dataset or a non-numeric type.
    pub fn numbers(&self) -> R<Vec<f64>> {
        self.numbers_in(None)
    }

    /// How many numbers the dataset holds.
    pub fn len(&self) -> R<usize> {
        count(&matlab_dims(self.ds.shape())?).ok_or_else(|| "dimensions overflow".into())
    }

    /// Bytes of one chunk of the dataset when it is stored in chunks.
    pub fn chunk_bytes(&self) -> Option<usize> {
        let elem = match self.ds.dtype() {
            Datatype::FloatingPoint { size, .. } | Datatype::FixedPoint { size, .. } => {
                usize::from(*size)
            }
            _ => 8,
        };
        let chunks = contain(|| self.ds.chunks()).flatten()?;
        Some(chunks.iter().fold(elem, |a, &c| {
            a.saturating_mul(usize::try_from(c).unwrap_or(usize::MAX))
        }))
    }

    /// The whole-file read's checks of a chunked dataset's chunk index,
    /// which a read of a range makes only for the chunks in its range:
    /// every chunk inside the dataset, on the chunk grid, and listed once.
    /// Each chunk is inflated on the way (one at a time; `hdf5-reader`
    /// lists chunks only with their data).
    ///
    /// # Errors
    /// The reason, for a chunk out of place or a damaged index or chunk.
    pub fn check_chunk_index(&self) -> R<()> {
        let ds = &self.ds;
        let Some(grid) = contain(|| ds.chunks()).flatten() else {
            return Ok(());
        };
        let shape = ds.shape();
        let walked = contain(|| -> R<()> {
            let mut seen: Vec<Vec<u64>> = Vec::new();
            for chunk in ds.iter_chunks().map_err(|e| detail(&e))? {
                let chunk = chunk.map_err(|e| detail(&e))?;
                let at = chunk.offsets();
                let placed = at.len() == shape.len()
                    && grid.len() == shape.len()
                    && at
                        .iter()
                        .zip(shape)
                        .zip(&grid)
                        .all(|((&o, &n), &c)| o < n && c > 0 && o % u64::from(c) == 0);
                if !placed {
                    return Err(format!(
                        "a chunk at offsets {at:?} outside the dataset's {shape:?} in chunks of \
                         {grid:?}"
                    ));
                }
                seen.push(at.to_vec());
            }
            seen.sort_unstable();
            if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
                return Err(format!("two chunks at offsets {:?}", w[0]));
            }
            Ok(())
        });
        match walked {
            Some(r) => r.map_err(|r| format!("chunk index: {r}")),
            None => Err("chunk index: it could not be decoded".into()),
        }
    }

    /// Numbers `at.0..at.1` of a vector (every number for `None`), as
    /// `f64`: the same conversion whole or in ranges.
    ///
    /// # Errors
    /// The reason, for a damaged dataset, a non-numeric type, or a range
    /// of a dataset that is not a vector.
    pub fn numbers_in(&self, at: Option<(usize, usize)>) -> R<Vec<f64>> {
        let ds = &self.ds;
        let selection = match at {
            None => None,
            Some((from, to)) => {
                let shape = ds.shape();
                if shape.iter().filter(|&&d| d > 1).count() > 1 {
                    return Err("a range of a matrix; expected a vector".into());
                }
                Some(SliceInfo {
                    selections: shape
                        .iter()
                        .map(|&d| {
                            if d > 1 {
                                SliceInfoElem::Slice {
                                    start: from as u64,
                                    end: to as u64,
                                    step: 1,
                                }
                            } else {
                                SliceInfoElem::Slice {
                                    start: 0,
                                    end: d,
                                    step: 1,
                                }
                            }
                        })
                        .collect(),
                })
            }
        };
        let sel = selection.as_ref();
        // The array of the whole dataset or of the range.
        macro_rules! get {
            ($t:ty) => {
                match sel {
                    None => h5("reading data", || ds.read_array::<$t>())?,
                    Some(sel) => h5("reading data", || ds.read_slice::<$t>(sel))?,
                }
            };
        }
        macro_rules! read {
            ($t:ty) => {
                get!($t).iter().map(|&x| x as f64).collect()
            };
        }
        Ok(match ds.dtype() {
            Datatype::FloatingPoint { size: 8, .. } => {
                let a = get!(f64);
                if a.is_standard_layout() {
                    // A vector in memory order: the array's buffer as it is.
                    let n = a.len();
                    let (mut v, offset) = a.into_raw_vec_and_offset();
                    let k = offset.unwrap_or(0);
                    if k > 0 {
                        v.drain(..k.min(v.len()));
                    }
                    v.truncate(n);
                    v
                } else {
                    a.iter().copied().collect()
                }
            }
            Datatype::FloatingPoint { size: 4, .. } => read!(f32),
            Datatype::FixedPoint {
                size: 1,
                signed: true,
                ..
            } => read!(i8),
            Datatype::FixedPoint {
                size: 1,
                signed: false,
                ..
            } => read!(u8),
            Datatype::FixedPoint {
                size: 2,
                signed: true,
                ..
            } => read!(i16),
            Datatype::FixedPoint {
                size: 2,
                signed: false,
                ..
            } => read!(u16),
            Datatype::FixedPoint {
                size: 4,
                signed: true,
                ..
            } => read!(i32),
            Datatype::FixedPoint {
                size: 4,
                signed: false,
                ..
            } => read!(u32),
            // 64-bit integers above 2^53 round to the nearest double.
            Datatype::FixedPoint {
                size: 8,
                signed: true,
                ..
            } => read!(i64),
            Datatype::FixedPoint {
                size: 8,
                signed: false,
                ..
            } => read!(u64),
            other => return Err(format!("data of type {other:?} is not numeric")),
        })
    }
}
