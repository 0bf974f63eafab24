//! Writing an [`Analysis`]: `analysis.json`, `correlations.csv`,
//! `spectra.csv`, `spectra_hires.csv`, `spectra_unfiltered.csv` and, with
//! position-domain spectra, `spectra_position.csv` (`freq_per_mm` in
//! cycles/mm, `psd_friction_n2_mm`, `psd_velocity_error_mm3_s2`, one-sided
//! densities per cycle/mm, and their `_lower_`/`_upper_` bands), each
//! written atomically by [`crate::fsutil::write_atomic_with`] (a reader never
//! sees half a file; no `fsync`, see [`crate::fsutil`]).
//!
//! CSV layout: one header row, `,`-separated, numbers in the shortest form
//! that reads back to the same `f64` (`nan`/`inf`/`-inf` for non-finite
//! values, as NumPy writes them). Every column name ends in its unit
//! (`docs/user-guide.md`, "Units in names"): lowercase tokens joined by `_`
//! (`n` newton, `v` volt, `mm_s` mm/s, `hz`, `s`), a digit for a power
//! (`n2` = N², `mm2_s2` = (mm/s)²), `per_` before a divisor; a name without
//! a unit token is dimensionless.
//!
//! - `correlations.csv`: `lag_s`, then `r_<series>` for `friction`,
//!   `velocity_error`, `optical`, `friction__velocity_error`,
//!   `friction__optical`, `velocity_error__optical` (absent series are left
//!   out), with the unit of the normalisation: none for `coeff`
//!   (`r_friction`), the product of the signals' units otherwise
//!   (`r_friction_n2`, `r_friction__optical_n_v`).
//! - `spectra.csv`, `spectra_hires.csv`, `spectra_unfiltered.csv`:
//!   `freq_hz`, the auto-spectra `psd_<signal>_<unit²>_per_hz`
//!   (`psd_friction_n2_per_hz`), then per cross pair
//!   `csd_<pair>_re_<unit>_per_hz`, `csd_<pair>_im_<unit>_per_hz` and the
//!   coherence `coh_<pair>`, then per auto-spectrum its confidence band
//!   `psd_<signal>_lower_<unit²>_per_hz`, `psd_<signal>_upper_<unit²>_per_hz`
//!   (level and degrees of freedom in `analysis.json`, `spectrum_*.band`).
//! - `sync_average.csv` (when the analysis has a synchronous average,
//!   [`super::sync`]): `phase` (fraction of the ball-pass period after phase
//!   0), then `friction_mean_n`, `friction_band_low_n`,
//!   `friction_band_high_n`, `velocity_error_mean_um_s`,
//!   `velocity_error_band_low_um_s`, `velocity_error_band_high_um_s`.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{pair_name, Analysis, CorrNorm, Correlations, Signal, Spectra};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic_with;

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
    /// `spectra_unfiltered.csv`.
    pub spectra_unfiltered: PathBuf,
    /// `spectra_position.csv`, when there are position-domain spectra.
    pub spectra_position: Option<PathBuf>,
    /// `sync_average.csv`, when the analysis has a synchronous average.
    pub sync: Option<PathBuf>,
}

/// Unit token of a signal in column names (`n`, `mm_s`, `v`).
pub fn unit_token(s: Signal) -> &'static str {
    match s {
        Signal::Friction => "n",
        Signal::VelocityError => "mm_s",
        Signal::Optical => "v",
    }
}

/// Unit token of the product of two signals: `n2`, `mm2_s2`, `v2` for a
/// signal with itself, `n_mm_s`, `n_v`, `mm_s_v` for a pair.
pub fn product_token(x: Signal, y: Signal) -> String {
    if x != y {
        return format!("{}_{}", unit_token(x), unit_token(y));
    }
    match x {
        Signal::Friction => "n2".into(),
        Signal::VelocityError => "mm2_s2".into(),
        Signal::Optical => "v2".into(),
    }
}

/// Column name of a correlation series under a normalisation:
/// `r_<series>` (dimensionless for `coeff`), else with the unit of the
/// product (`r_friction_n2`).
pub fn correlation_column(x: Signal, y: Signal, norm: CorrNorm) -> String {
    match norm {
        CorrNorm::Coeff => format!("r_{}", pair_name(x, y)),
        _ => format!("r_{}_{}", pair_name(x, y), product_token(x, y)),
    }
}

/// A table of named columns over one index column.
pub(crate) struct Table<'a> {
    pub index_name: &'a str,
    pub index: &'a [f64],
    pub columns: Vec<(String, Vec<f64>)>,
}

/// Columns of `correlations.csv` (without `lag_s`), for correlations
/// normalised by `norm`.
pub fn correlation_columns(c: &Correlations, norm: CorrNorm) -> Vec<(String, &[f64])> {
    c.series
        .iter()
        .map(|((x, y), v)| (correlation_column(*x, *y, norm), v.as_slice()))
        .collect()
}

/// Column name of an auto-spectrum: `psd_friction_n2_per_hz`.
pub fn psd_column(s: Signal) -> String {
    format!("psd_{}_{}_per_hz", s.name(), product_token(s, s))
}

/// Columns of `spectra.csv` / `spectra_hires.csv` /
/// `spectra_unfiltered.csv` (without `freq_hz`).
pub fn spectrum_columns(s: &Spectra) -> Vec<(String, Vec<f64>)> {
    let mut cols: Vec<(String, Vec<f64>)> = s
        .auto
        .iter()
        .map(|(k, v)| (psd_column(*k), v.clone()))
        .collect();
    for c in &s.cross {
        let name = pair_name(c.x, c.y);
        let unit = product_token(c.x, c.y);
        cols.push((
            format!("csd_{name}_re_{unit}_per_hz"),
            c.pxy.iter().map(|z| z.re).collect(),
        ));
        cols.push((
            format!("csd_{name}_im_{unit}_per_hz"),
            c.pxy.iter().map(|z| z.im).collect(),
        ));
        cols.push((format!("coh_{name}"), c.coherence.clone()));
    }
    cols.extend(super::confidence::band_columns(s));
    cols
}

/// Longest text of one number: zmij's longest f64 form is 24 bytes
/// (`-1.2345678901234567e-308`).
const SLOT: usize = 32;

/// Writes the text of `v` at `out[*pos..]` (which has at least [`SLOT`]
/// bytes) and advances `pos`.
fn put_num(out: &mut [u8], pos: &mut usize, buf: &mut zmij::Buffer, v: f64) {
    let s: &[u8] = if v.is_finite() {
        buf.format_finite(v).as_bytes()
    } else if v.is_nan() {
        b"nan"
    } else if v > 0.0 {
        b"inf"
    } else {
        b"-inf"
    };
    copy_short(&mut out[*pos..*pos + SLOT], s);
    *pos += s.len();
}

/// Copies `s` (at most [`SLOT`] bytes) to the start of `dst` with two
/// fixed-size, possibly overlapping block copies, which compile to a few
/// register moves; a `copy_from_slice` of a variable length calls `memcpy`,
/// which cost as much as formatting the number.
fn copy_short(dst: &mut [u8], s: &[u8]) {
    fn two<const K: usize>(dst: &mut [u8], s: &[u8]) {
        let n = s.len();
        let head: [u8; K] = s[..K].try_into().expect("K bytes");
        let tail: [u8; K] = s[n - K..].try_into().expect("K bytes");
        dst[..K].copy_from_slice(&head);
        dst[n - K..n].copy_from_slice(&tail);
    }
    match s.len() {
        16..=32 => two::<16>(dst, s),
        8..=15 => two::<8>(dst, s),
        4..=7 => two::<4>(dst, s),
        n => dst[..n].iter_mut().zip(s).for_each(|(d, &b)| *d = b),
    }
}

/// Rows formatted per write: small enough that the one reused buffer
/// (about 240 kB for 7 columns) stays in cache and costs no page faults.
const CHUNK_ROWS: usize = 1024;

/// Formats rows `start..end` of the table into `out` (cleared first).
fn format_rows(
    out: &mut Vec<u8>,
    index: &[f64],
    cols: &[(String, &[f64])],
    start: usize,
    end: usize,
) {
    // Each number takes at most SLOT bytes plus a separator.
    out.resize((end - start) * (cols.len() + 1) * (SLOT + 1) + SLOT, 0);
    let mut buf = zmij::Buffer::new();
    let mut pos = 0;
    for i in start..end {
        put_num(out, &mut pos, &mut buf, index[i]);
        for (_, col) in cols {
            out[pos] = b',';
            pos += 1;
            put_num(out, &mut pos, &mut buf, col[i]);
        }
        out[pos] = b'\n';
        pos += 1;
    }
    out.truncate(pos);
}

/// Writes the header, then the rows in chunks of [`CHUNK_ROWS`]: the
/// chunks of one round are formatted in parallel (one buffer per worker
/// thread of the rayon pool) while a writer thread writes the previous
/// round, in order, so the text is the same as a sequential pass; the
/// round's buffers go back to the formatter for reuse.
fn write_table<W: Write + Send>(
    w: &mut W,
    index_name: &str,
    index: &[f64],
    cols: &[(String, &[f64])],
) -> std::io::Result<()> {
    use rayon::prelude::*;
    use std::sync::mpsc;
    let mut head = index_name.to_string();
    for (name, _) in cols {
        head.push(',');
        head.push_str(name);
    }
    head.push('\n');
    w.write_all(head.as_bytes())?;
    let n = index.len();
    let chunks = n.div_ceil(CHUNK_ROWS);
    let workers = rayon::current_num_threads().clamp(1, chunks.max(1));
    std::thread::scope(|scope| {
        let (to_writer, rounds) = mpsc::sync_channel::<Vec<Vec<u8>>>(1);
        let (give_back, returned) = mpsc::channel::<Vec<Vec<u8>>>();
        let writer = scope.spawn(move || -> std::io::Result<()> {
            for bufs in rounds {
                for out in &bufs {
                    w.write_all(out)?;
                }
                // The formatter may have finished; then the buffers just drop.
                let _ = give_back.send(bufs);
            }
            Ok(())
        });
        for round in (0..chunks).step_by(workers) {
            let in_round = workers.min(chunks - round);
            let mut bufs = returned
                .try_recv()
                .unwrap_or_else(|_| vec![Vec::new(); workers]);
            bufs.truncate(in_round);
            let fill = |(k, out): (usize, &mut Vec<u8>)| {
                let start = (round + k) * CHUNK_ROWS;
                format_rows(out, index, cols, start, (start + CHUNK_ROWS).min(n));
            };
            if in_round > 1 {
                bufs.par_iter_mut().enumerate().for_each(fill);
            } else {
                bufs.iter_mut().enumerate().for_each(fill);
            }
            if to_writer.send(bufs).is_err() {
                // The writer stopped on an error, which join reports.
                break;
            }
        }
        drop(to_writer);
        writer
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })
}

/// Writes a table as CSV atomically.
pub(crate) fn write_csv(path: &Path, t: &Table<'_>) -> Result<()> {
    let cols: Vec<(String, &[f64])> = t
        .columns
        .iter()
        .map(|(n, v)| (n.clone(), v.as_slice()))
        .collect();
    write_atomic_with(path, |w| write_table(w, t.index_name, t.index, &cols))
}

/// Writes `correlations.csv` to `path`; `norm` is the normalisation the
/// correlations were computed with (it sets the columns' unit).
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_correlations(path: &Path, c: &Correlations, norm: CorrNorm) -> Result<()> {
    let cols = correlation_columns(c, norm);
    write_atomic_with(path, |w| write_table(w, "lag_s", &c.lag_s, &cols))
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

/// Writes `analysis.json` and the four CSV files into `dir` (created if
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
        spectra_unfiltered: dir.join("spectra_unfiltered.csv"),
        spectra_position: a
            .position
            .as_ref()
            .map(|_| dir.join("spectra_position.csv")),
        sync: a.sync.as_ref().map(|_| dir.join("sync_average.csv")),
    };
    // The large correlations.csv beside the four small files.
    let (corr, rest) = rayon::join(
        || write_correlations(&paths.correlations, &a.correlations, a.settings.corr_norm),
        || {
            write_spectra(&paths.spectra, &a.spectra)?;
            write_spectra(&paths.spectra_hires, &a.spectra_hires)?;
            write_spectra(&paths.spectra_unfiltered, &a.spectra_unfiltered)?;
            if let (Some(path), Some(p)) = (&paths.spectra_position, &a.position) {
                write_csv(
                    path,
                    &Table {
                        index_name: "freq_per_mm",
                        index: &p.freq_per_mm,
                        columns: super::position::position_columns(p),
                    },
                )?;
            }
            if let (Some(s), Some(p)) = (&a.sync, &paths.sync) {
                s.write_csv(p)?;
            }
            write_atomic_with(&paths.json, |w| {
                serde_json::to_writer_pretty(&mut *w, a).map_err(std::io::Error::other)?;
                w.write_all(b"\n")
            })
        },
    );
    corr?;
    rest?;
    Ok(paths)
}

#[cfg(test)]
mod tests {
    #[test]
    fn copy_short_copies_every_length() {
        let src: Vec<u8> = (1..=32).collect();
        for n in 0..=32 {
            let mut dst = [0u8; super::SLOT];
            super::copy_short(&mut dst, &src[..n]);
            assert_eq!(&dst[..n], &src[..n], "{n}");
            assert!(dst[n..].iter().all(|&b| b == 0), "{n}");
        }
    }

    use super::*;

    /// Every column name carries the unit of its numbers; the coefficient
    /// normalisation is dimensionless and says so by having none.
    #[test]
    fn column_names_carry_their_units() {
        use Signal::*;
        assert_eq!(psd_column(Friction), "psd_friction_n2_per_hz");
        assert_eq!(
            psd_column(VelocityError),
            "psd_velocity_error_mm2_s2_per_hz"
        );
        assert_eq!(psd_column(Optical), "psd_optical_v2_per_hz");
        assert_eq!(
            correlation_column(Friction, Optical, CorrNorm::Biased),
            "r_friction__optical_n_v"
        );
        assert_eq!(
            correlation_column(VelocityError, VelocityError, CorrNorm::None),
            "r_velocity_error_mm2_s2"
        );
        assert_eq!(
            correlation_column(Friction, VelocityError, CorrNorm::Coeff),
            "r_friction__velocity_error"
        );
    }

    fn table(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let index: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3 - 3.0).collect();
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() / 3.0).collect();
        let mut b: Vec<f64> = (0..n).map(|i| 1e-300 * i as f64 - 7e5).collect();
        b[n / 2] = f64::NAN;
        b[n / 3] = f64::NEG_INFINITY;
        (index, a, b)
    }

    /// The pipelined, parallel writer gives exactly the text of a plain
    /// row-by-row pass (header, order, every number) for tables shorter
    /// than one chunk, of a few rounds, and with a partial last chunk.
    #[test]
    fn table_text_equals_a_sequential_pass() {
        for n in [1, 5, CHUNK_ROWS, 3 * CHUNK_ROWS + 17] {
            let (index, a, b) = table(n);
            let cols = vec![
                ("a".to_string(), a.as_slice()),
                ("b".to_string(), b.as_slice()),
            ];
            let mut got = Vec::new();
            write_table(&mut got, "x", &index, &cols).unwrap();
            let mut want = String::from("x,a,b\n");
            let text = |v: f64| {
                if v.is_nan() {
                    "nan".to_string()
                } else if v.is_infinite() {
                    if v > 0.0 { "inf" } else { "-inf" }.to_string()
                } else {
                    zmij::Buffer::new().format_finite(v).to_string()
                }
            };
            for i in 0..n {
                want.push_str(&format!(
                    "{},{},{}\n",
                    text(index[i]),
                    text(a[i]),
                    text(b[i])
                ));
            }
            assert_eq!(String::from_utf8(got).unwrap(), want, "{n} rows");
        }
    }

    /// A writer that fails part-way: the error comes back (no panic, no hang).
    #[test]
    fn a_failing_writer_is_an_error() {
        struct Failing(usize);
        impl Write for Failing {
            fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
                if self.0 < buf.len() {
                    return Err(std::io::Error::other("disk full"));
                }
                self.0 -= buf.len();
                Ok(buf.len())
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let (index, a, b) = table(5 * CHUNK_ROWS);
        let cols = vec![
            ("a".to_string(), a.as_slice()),
            ("b".to_string(), b.as_slice()),
        ];
        let err = write_table(&mut Failing(100_000), "x", &index, &cols).unwrap_err();
        assert_eq!(err.to_string(), "disk full");
    }
}
