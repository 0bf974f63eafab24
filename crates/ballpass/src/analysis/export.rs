//! Writing an [`Analysis`]: `analysis.json`, `correlations.csv`,
//! `spectra.csv`, `spectra_hires.csv`, each to a temporary file renamed into
//! place (a reader never sees half a file).
//!
//! CSV layout: one header row, `,`-separated, numbers in the shortest form
//! that reads back to the same `f64` (`nan`/`inf`/`-inf` for non-finite
//! values, as NumPy writes them).
//!
//! - `correlations.csv`: `lag_s`, then `friction`, `velocity_error`,
//!   `optical`, `friction__velocity_error`, `friction__optical`,
//!   `velocity_error__optical` (absent series are left out).
//! - `spectra.csv`, `spectra_hires.csv`: `freq_hz`, the auto-spectra by
//!   signal name, then per cross pair `<pair>_re`, `<pair>_im`, `<pair>_coh`.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{pair_name, Analysis, Correlations, Spectra};
use crate::error::{Error, Result};
use crate::recording::io::write_atomic;

/// Where [`write_outputs`] put the files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputPaths {
    /// `analysis.json`.
    pub json: PathBuf,
    /// `correlations.csv`.
    pub correlations: PathBuf,
    /// `spectra.csv`.
    pub spectra: PathBuf,
    /// `spectra_hires.csv`.
    pub spectra_hires: PathBuf,
}

/// A table of named columns over one index column.
pub(crate) struct Table<'a> {
    pub index_name: &'a str,
    pub index: &'a [f64],
    pub columns: Vec<(String, Vec<f64>)>,
}

/// Columns of `correlations.csv`.
pub fn correlation_columns(c: &Correlations) -> Vec<(String, &[f64])> {
    c.series
        .iter()
        .map(|((x, y), v)| (pair_name(*x, *y), v.as_slice()))
        .collect()
}

/// Columns of `spectra.csv` / `spectra_hires.csv` (without `freq_hz`).
pub fn spectrum_columns(s: &Spectra) -> Vec<(String, Vec<f64>)> {
    let mut cols: Vec<(String, Vec<f64>)> = s
        .auto
        .iter()
        .map(|(k, v)| (k.name().to_string(), v.clone()))
        .collect();
    for c in &s.cross {
        let name = pair_name(c.x, c.y);
        cols.push((format!("{name}_re"), c.pxy.iter().map(|z| z.re).collect()));
        cols.push((format!("{name}_im"), c.pxy.iter().map(|z| z.im).collect()));
        cols.push((format!("{name}_coh"), c.coherence.clone()));
    }
    cols
}

fn write_num<W: Write>(w: &mut W, buf: &mut zmij::Buffer, v: f64) -> std::io::Result<()> {
    if v.is_finite() {
        w.write_all(buf.format_finite(v).as_bytes())
    } else if v.is_nan() {
        w.write_all(b"nan")
    } else if v > 0.0 {
        w.write_all(b"inf")
    } else {
        w.write_all(b"-inf")
    }
}

fn write_table<W: Write>(
    w: &mut W,
    index_name: &str,
    index: &[f64],
    cols: &[(String, &[f64])],
) -> std::io::Result<()> {
    w.write_all(index_name.as_bytes())?;
    for (name, _) in cols {
        w.write_all(b",")?;
        w.write_all(name.as_bytes())?;
    }
    w.write_all(b"\n")?;
    let mut buf = zmij::Buffer::new();
    for (i, x) in index.iter().enumerate() {
        write_num(w, &mut buf, *x)?;
        for (_, c) in cols {
            w.write_all(b",")?;
            write_num(w, &mut buf, c[i])?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Writes a table as CSV atomically.
pub(crate) fn write_csv(path: &Path, t: &Table<'_>) -> Result<()> {
    let cols: Vec<(String, &[f64])> = t
        .columns
        .iter()
        .map(|(n, v)| (n.clone(), v.as_slice()))
        .collect();
    write_atomic(path, |w| write_table(w, t.index_name, t.index, &cols))
}

/// Writes `correlations.csv` to `path`.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_correlations(path: &Path, c: &Correlations) -> Result<()> {
    let cols = correlation_columns(c);
    write_atomic(path, |w| write_table(w, "lag_s", &c.lag_s, &cols))
}

/// Writes a spectra table (`spectra.csv` layout) to `path`.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_spectra(path: &Path, s: &Spectra) -> Result<()> {
    write_csv(
        path,
        &Table {
            index_name: "freq_hz",
            index: &s.freq_hz,
            columns: spectrum_columns(s),
        },
    )
}

/// Writes `analysis.json` and the three CSV files into `dir` (created if
/// needed).
///
/// # Errors
/// [`Error::Io`] naming the folder or file that could not be written.
pub fn write_outputs(a: &Analysis, dir: &Path) -> Result<OutputPaths> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let paths = OutputPaths {
        json: dir.join("analysis.json"),
        correlations: dir.join("correlations.csv"),
        spectra: dir.join("spectra.csv"),
        spectra_hires: dir.join("spectra_hires.csv"),
    };
    write_correlations(&paths.correlations, &a.correlations)?;
    write_spectra(&paths.spectra, &a.spectra)?;
    write_spectra(&paths.spectra_hires, &a.spectra_hires)?;
    write_atomic(&paths.json, |w| {
        serde_json::to_writer_pretty(&mut *w, a).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })?;
    Ok(paths)
}
