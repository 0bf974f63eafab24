//! Writing a recording as a level-5 MAT-file.

use std::io::Write;
use std::path::Path;

use crate::error::{Error, Result};
use crate::recording::Recording;

const TEXT_LEN: usize = 116;
const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MX_DOUBLE_CLASS: u32 = 6;

/// Writes a recording as a MAT-file (level 5, uncompressed, little-endian):
/// column vectors `time_s` (`start_time_s + i / fs_hz`) and the channels
/// present under their canonical names, all double. MATLAB, Octave, scipy
/// and `super::load` read it; `load` gives back the same bits.
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
