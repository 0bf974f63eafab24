//! Hand-built MAT-files: a small level-5 element writer and the hostile
//! structures of issue 18 (deep nesting, huge dimensions, compressed
//! streams inside compressed streams, length fields that lie).

use std::io::Write;

const MI_INT8: u32 = 1;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

/// A tagged element (little-endian, padded to 8 bytes).
pub fn element(ty: u32, data: &[u8]) -> Vec<u8> {
    let mut e = Vec::with_capacity(8 + data.len() + 7);
    e.extend_from_slice(&ty.to_le_bytes());
    e.extend_from_slice(&(data.len() as u32).to_le_bytes());
    e.extend_from_slice(data);
    while e.len() % 8 != 0 {
        e.push(0);
    }
    e
}

/// A `miMATRIX` of `class` with `dims`, `name` and class-specific `contents`.
pub fn matrix(class: u8, flags: u8, dims: &[i32], name: &str, contents: &[u8]) -> Vec<u8> {
    let mut body = Vec::new();
    let mut f = [0u8; 8];
    f[0] = class;
    f[1] = flags;
    body.extend(element(MI_UINT32, &f));
    let d: Vec<u8> = dims.iter().flat_map(|x| x.to_le_bytes()).collect();
    body.extend(element(MI_INT32, &d));
    body.extend(element(MI_INT8, name.as_bytes()));
    body.extend_from_slice(contents);
    element(MI_MATRIX, &body)
}

/// A double column vector named `name`.
pub fn double_vector(name: &str, values: &[f64]) -> Vec<u8> {
    let data: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
    matrix(
        6,
        0,
        &[values.len() as i32, 1],
        name,
        &element(MI_DOUBLE, &data),
    )
}

/// A 1x1 cell holding `inner` (a `miMATRIX`).
pub fn cell(name: &str, inner: &[u8]) -> Vec<u8> {
    matrix(1, 0, &[1, 1], name, inner)
}

/// Field name length (8, as a small element) and the names, NUL-padded.
fn field_names(names: &[&str]) -> Vec<u8> {
    let mut c = Vec::new();
    c.extend_from_slice(&(MI_INT32 | (4 << 16)).to_le_bytes());
    c.extend_from_slice(&8i32.to_le_bytes());
    let mut all = Vec::new();
    for n in names {
        let mut b = n.as_bytes().to_vec();
        b.resize(8, 0);
        all.extend(b);
    }
    c.extend(element(MI_INT8, &all));
    c
}

/// A 1x1 struct with one field `f` holding `inner`.
pub fn struct1(name: &str, inner: &[u8]) -> Vec<u8> {
    let mut c = field_names(&["f"]);
    c.extend_from_slice(inner);
    matrix(2, 0, &[1, 1], name, &c)
}

/// A 1x1 object of class `cls` with one field `f` holding `inner`.
pub fn object1(name: &str, cls: &str, inner: &[u8]) -> Vec<u8> {
    let mut c = element(MI_INT8, cls.as_bytes());
    c.extend(field_names(&["f"]));
    c.extend_from_slice(inner);
    matrix(3, 0, &[1, 1], name, &c)
}

/// `inner` as a `miCOMPRESSED` element (zlib).
pub fn compressed(inner: &[u8]) -> Vec<u8> {
    let mut enc = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    // Writing to a Vec cannot fail.
    let _ = enc.write_all(inner);
    let z = enc.finish().unwrap_or_default();
    let mut e = Vec::with_capacity(8 + z.len());
    e.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
    e.extend_from_slice(&(z.len() as u32).to_le_bytes());
    e.extend(z);
    e
}

/// A level-5 file: MATLAB's header and the variables.
pub fn file(vars: &[Vec<u8>]) -> Vec<u8> {
    let mut text = b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created by: ballpass-fuzz".to_vec();
    text.resize(116, b' ');
    let mut f = text;
    f.extend_from_slice(&[0; 8]);
    f.extend_from_slice(&0x0100u16.to_le_bytes());
    f.extend_from_slice(b"IM");
    for v in vars {
        f.extend_from_slice(v);
    }
    f
}

/// `depth` nested 1x1 cells around a small vector (issue 18 item 1).
pub fn nested_cells(depth: usize) -> Vec<u8> {
    let mut v = double_vector("", &[1.0, 2.0]);
    for _ in 0..depth {
        v = cell("", &v);
    }
    rename_top(&mut v, "c");
    file(&[v])
}

/// `depth` nested 1x1 structs (issue 18 item 2).
pub fn nested_structs(depth: usize) -> Vec<u8> {
    let mut v = double_vector("", &[1.0, 2.0]);
    for _ in 0..depth {
        v = struct1("", &v);
    }
    rename_top(&mut v, "s");
    file(&[v])
}

/// `depth` nested 1x1 objects (issue 18 item 2).
pub fn nested_objects(depth: usize) -> Vec<u8> {
    let mut v = double_vector("", &[1.0, 2.0]);
    for _ in 0..depth {
        v = object1("", "widget", &v);
    }
    rename_top(&mut v, "o");
    file(&[v])
}

/// A compressed variable whose stream holds another compressed element
/// (`levels` deep), the innermost a vector of `n` zeros (issue 18 item 3).
pub fn nested_zlib(levels: usize, n: usize) -> Vec<u8> {
    let mut v = double_vector("z", &vec![0.0; n]);
    for _ in 0..levels {
        v = compressed(&v);
    }
    file(&[v])
}

/// A variable whose name element claims `claim` bytes (issue 18 item 3).
pub fn lying_name_length(claim: u32) -> Vec<u8> {
    let mut v = double_vector("friction_N", &[1.0; 16]);
    // The name tag is the third sub-element: after the 8-byte matrix tag,
    // 16 bytes of flags and 16 of dimensions.
    let at = 8 + 16 + 16 + 4;
    v[at..at + 4].copy_from_slice(&claim.to_le_bytes());
    file(&[v])
}

/// A double array whose dimensions claim `rows x cols` elements.
pub fn lying_dims(rows: i32, cols: i32, class: u8) -> Vec<u8> {
    let data: Vec<u8> = [1.0f64; 4].iter().flat_map(|x| x.to_le_bytes()).collect();
    let contents = match class {
        // cells / structs: one child only
        1 => double_vector("", &[1.0]),
        2 => {
            let mut c = field_names(&["f"]);
            c.extend(double_vector("", &[1.0]));
            c
        }
        _ => element(MI_DOUBLE, &data),
    };
    file(&[matrix(class, 0, &[rows, cols], "x", &contents)])
}

/// A struct array of `rows x cols` elements and no fields (it holds
/// nothing, whatever its size).
pub fn fieldless_struct(rows: i32, cols: i32) -> Vec<u8> {
    file(&[matrix(2, 0, &[rows, cols], "s", &field_names(&[]))])
}

/// A char array with no characters whose dimensions claim `rows x 0`.
pub fn empty_text(rows: i32) -> Vec<u8> {
    file(&[matrix(4, 0, &[rows, 0], "c", &element(MI_UINT16, &[]))])
}

fn rename_top(v: &mut Vec<u8>, name: &str) {
    // The outermost matrix's name is empty: rebuild its name element.
    let name_at = 8 + 16 + 16;
    let old_tag = u32::from_le_bytes([v[name_at], v[name_at + 1], v[name_at + 2], v[name_at + 3]]);
    if old_tag != MI_INT8 || v[name_at + 4..name_at + 8] != [0, 0, 0, 0] {
        return;
    }
    let mut out = v[..name_at].to_vec();
    out.extend(element(MI_INT8, name.as_bytes()));
    out.extend_from_slice(&v[name_at + 8..]);
    let body = (out.len() - 8) as u32;
    out[4..8].copy_from_slice(&body.to_le_bytes());
    *v = out;
}

/// The structured stress files: nesting of every kind at depths around the
/// limit and far beyond it, compressed streams inside compressed streams,
/// length and dimension fields that lie, wide structs, and valid files of
/// the same shapes. Deterministic; built once (nesting 2048 deep is big).
pub fn stress_corpus() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    for depth in [2usize, 8, 20, 22, 31, 32, 33, 64, 512, 2048] {
        out.push(nested_cells(depth));
        out.push(nested_structs(depth));
        out.push(nested_objects(depth));
        let inner = nested_cells(depth);
        out.push(file(&[compressed(&inner[128..])]));
    }
    for levels in 1..=3 {
        for n in [16, 1 << 12, 1 << 16] {
            out.push(nested_zlib(levels, n));
        }
    }
    for claim in [8, 64, 1 << 20, u32::MAX, u32::MAX - 7] {
        out.push(lying_name_length(claim));
    }
    for (rows, cols) in [
        (1, 1),
        (2, 4),
        (1 << 16, 1 << 16),
        (i32::MAX, i32::MAX),
        (-1, 4),
    ] {
        for class in [1u8, 2, 4, 5, 6, 9, 15, 17, 99] {
            out.push(lying_dims(rows, cols, class));
        }
    }
    for (rows, cols) in [(0, 0), (1, 1), (i32::MAX, 2), (1 << 20, 1 << 10)] {
        out.push(fieldless_struct(rows, cols));
    }
    for rows in [0, 2, 1 << 20, i32::MAX] {
        out.push(empty_text(rows));
    }
    for n in [1usize, 100, 5000] {
        let names: Vec<String> = (0..n).map(|i| format!("f{i:06}")).collect();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let mut c = field_names(&refs);
        for _ in 0..n {
            c.extend(double_vector("", &[1.0]));
        }
        out.push(file(&[matrix(2, 0, &[1, 1], "wide", &c)]));
    }
    // Valid recordings of the shapes the loaders expect.
    let v: Vec<f64> = (0..64).map(|i| i as f64).collect();
    let t: Vec<f64> = v.iter().map(|x| x / 1000.0).collect();
    out.push(file(&[
        compressed(&double_vector("time_s", &t)),
        double_vector("friction_N", &v),
        compressed(&double_vector("optical_V", &v)),
    ]));
    let mut c = field_names(&["gs", "sr"]);
    c.extend(double_vector("", &v));
    c.extend(double_vector("", &[1000.0]));
    out.push(file(&[compressed(&matrix(2, 0, &[1, 1], "bearing", &c))]));
    out
}
