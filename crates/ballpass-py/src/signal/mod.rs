//! The kernels behind `ballpass.signal`: `ballpass-dsp` on numpy arrays.
//!
//! Arguments arrive resolved and checked the way SciPy checks them (the
//! Python module does that, so its exceptions are SciPy's); signals arrive
//! as C-contiguous float64 arrays, several signals as the rows of a 2-D
//! array (the Python module moves `axis` last and flattens the others). The
//! rows are borrowed, not copied, and processed with the GIL released.

use ballpass_dsp as dsp;
use numpy::ndarray::Array2;
use numpy::{
    Complex64, IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use crate::errors;

mod filters;
mod peaks;
mod response;
mod spectral;

type Arr1<'py> = Bound<'py, PyArray1<f64>>;
type Arr2<'py> = Bound<'py, PyArray2<f64>>;
type CArr1<'py> = Bound<'py, PyArray1<Complex64>>;
type IArr1<'py> = Bound<'py, PyArray1<i64>>;

/// The rows of a C-contiguous 2-D array: (slice, rows, row length).
fn rows<'a>(a: &'a PyReadonlyArray2<'_, f64>) -> PyResult<(&'a [f64], usize, usize)> {
    let (m, n) = (a.shape()[0], a.shape()[1]);
    let s = a
        .as_slice()
        .map_err(|e| errors::value(format!("expected a C-contiguous array: {e}")))?;
    Ok((s, m, n))
}

/// Each row of `x` (length `n`) through `f`; the results, all of one
/// length, stacked as a `(rows, len)` array.
fn map_rows<T: Copy + Send>(
    py: Python<'_>,
    x: &[f64],
    m: usize,
    n: usize,
    mut f: impl FnMut(&[f64]) -> dsp::Result<Vec<T>> + Send,
) -> PyResult<(Vec<T>, usize)> {
    py.detach(|| {
        if m == 1 {
            // One signal: its result is the output buffer, no copy.
            let r = f(&x[..n])?;
            let width = r.len();
            return Ok((r, width));
        }
        let mut out = Vec::new();
        let mut width = 0;
        for i in 0..m {
            let r = f(&x[i * n..(i + 1) * n])?;
            width = r.len();
            out.extend_from_slice(&r);
        }
        Ok((out, width))
    })
    .map_err(errors::dsp)
}

fn stack<'py, T: numpy::Element>(
    py: Python<'py>,
    flat: Vec<T>,
    m: usize,
    width: usize,
) -> PyResult<Bound<'py, PyArray2<T>>> {
    Ok(Array2::from_shape_vec((m, width), flat)
        .map_err(errors::value)?
        .into_pyarray(py))
}

/// Each pair of rows of `x` and `y` (the same number of rows, any row
/// lengths) through `f`, which returns the frequencies and one row of
/// results: the frequencies and the rows stacked.
fn map_pairs<'py, T: Copy + Send + numpy::Element>(
    py: Python<'py>,
    x: &PyReadonlyArray2<'py, f64>,
    y: &PyReadonlyArray2<'py, f64>,
    mut f: impl FnMut(&[f64], &[f64]) -> dsp::Result<(Vec<f64>, Vec<T>)> + Send,
) -> PyResult<(Arr1<'py>, Bound<'py, PyArray2<T>>)> {
    let (xs, m, nx) = rows(x)?;
    let (ys, my, ny) = rows(y)?;
    if m != my {
        return Err(errors::value(format!("x has {m} rows, y has {my}")));
    }
    let (freq, flat, width) = py
        .detach(|| -> dsp::Result<_> {
            let (mut freq, mut flat, mut width) = (Vec::new(), Vec::new(), 0);
            for i in 0..m {
                let (fr, row) = f(&xs[i * nx..(i + 1) * nx], &ys[i * ny..(i + 1) * ny])?;
                width = row.len();
                flat.extend_from_slice(&row);
                freq = fr;
            }
            Ok((freq, flat, width))
        })
        .map_err(errors::dsp)?;
    Ok((freq.into_pyarray(py), stack(py, flat, m, width)?))
}

fn slice1<'a>(a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|e| errors::value(format!("expected a contiguous array: {e}")))
}

/// Samples below which a one-pass kernel keeps the GIL.
const SMALL_WORK: usize = 4096;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(spectral::welch, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::csd, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::coherence, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::periodogram, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::correlate, m)?)?;
    m.add_function(wrap_pyfunction!(spectral::correlation_lags, m)?)?;
    m.add_function(wrap_pyfunction!(filters::butter, m)?)?;
    m.add_function(wrap_pyfunction!(filters::cheby1, m)?)?;
    m.add_function(wrap_pyfunction!(filters::sosfilt, m)?)?;
    m.add_function(wrap_pyfunction!(filters::sosfilt_zi, m)?)?;
    m.add_function(wrap_pyfunction!(filters::sosfiltfilt, m)?)?;
    m.add_function(wrap_pyfunction!(filters::lfilter, m)?)?;
    m.add_function(wrap_pyfunction!(filters::lfilter1, m)?)?;
    m.add_function(wrap_pyfunction!(filters::detrend, m)?)?;
    m.add_function(wrap_pyfunction!(filters::decimate, m)?)?;
    m.add_function(wrap_pyfunction!(peaks::find_peaks, m)?)?;
    m.add_function(wrap_pyfunction!(peaks::peak_prominences, m)?)?;
    m.add_function(wrap_pyfunction!(peaks::peak_widths, m)?)?;
    m.add_function(wrap_pyfunction!(response::freqs, m)?)?;
    m.add_function(wrap_pyfunction!(response::freqz, m)?)?;
    m.add_function(wrap_pyfunction!(response::sosfreqz, m)?)?;
    m.add_function(wrap_pyfunction!(response::freqz_grid, m)?)?;
    m.add_function(wrap_pyfunction!(response::sosfreqz_grid, m)?)?;
    m.add_function(wrap_pyfunction!(response::gradient, m)?)?;
    m.add_function(wrap_pyfunction!(response::gradient1, m)?)?;
    m.add_function(wrap_pyfunction!(response::gradient_plain, m)?)?;
    Ok(())
}
