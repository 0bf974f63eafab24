//! Frequency responses (`freqs`, `freqz`, `sosfreqz`) and numpy's `gradient`.

use ballpass_dsp as dsp;
use ballpass_dsp::Spacing;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyFloat;

use super::filters::sos_from;
use super::{map_rows, rows, slice1, stack, Arr1, Arr2, CArr1, SMALL_WORK};
use crate::errors;

/// A response as a numpy array: `ballpass_dsp::Complex64` is numpy's
/// complex128 element (both `num_complex::Complex<f64>`), so the vector
/// becomes the array without a copy.
fn complex(py: Python<'_>, h: Vec<dsp::Complex64>) -> CArr1<'_> {
    h.into_pyarray(py)
}

/// `scipy.signal.freqs(b, a, worN=w)`: `H(j w)`.
#[pyfunction]
pub(super) fn freqs<'py>(
    py: Python<'py>,
    b: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    w: PyReadonlyArray1<'py, f64>,
) -> PyResult<CArr1<'py>> {
    let (b, a, w) = (slice1(&b)?, slice1(&a)?, slice1(&w)?);
    let h = py
        .detach(|| dsp::freqs_values(b, a, w))
        .map_err(errors::dsp)?;
    Ok(complex(py, h))
}

/// `scipy.signal.freqz(b, a, worN=f, fs=fs)`: `H` at frequencies `f`.
#[pyfunction]
pub(super) fn freqz<'py>(
    py: Python<'py>,
    b: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    fs: f64,
) -> PyResult<CArr1<'py>> {
    let (b, a, f) = (slice1(&b)?, slice1(&a)?, slice1(&f)?);
    let h = py
        .detach(|| dsp::freqz_values(b, a, f, fs))
        .map_err(errors::dsp)?;
    Ok(complex(py, h))
}

/// The frequencies SciPy's `freqz` / `freqz_sos` return for an array
/// `worN` in the units of `fs`: `2 pi f / fs` (the rad/sample values it
/// evaluates at) converted back, `(2 pi f / fs) (fs / (2 pi))`, with
/// NumPy's operations in NumPy's order (one pass here instead of three
/// array passes in Python).
fn scipy_grid(f: &[f64], fs: f64) -> Vec<f64> {
    let two_pi = 2.0 * std::f64::consts::PI;
    let back = fs / two_pi;
    f.iter().map(|&v| two_pi * v / fs * back).collect()
}

/// `scipy.signal.freqz(b, a, worN=f, fs=fs)` for an array `f` in the units
/// of `fs`: `(w, H)`, `w` as SciPy returns it (as [`scipy_grid`], made
/// with the response by [`dsp::freqz_values_scipy_grid`]) and `H` at `f`.
#[pyfunction]
pub(super) fn freqz_grid<'py>(
    py: Python<'py>,
    b: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    fs: f64,
) -> PyResult<(Arr1<'py>, CArr1<'py>)> {
    let (b, a, f) = (slice1(&b)?, slice1(&a)?, slice1(&f)?);
    let (w, h) = py
        .detach(|| dsp::freqz_values_scipy_grid(b, a, f, fs))
        .map_err(errors::dsp)?;
    Ok((w.into_pyarray(py), complex(py, h)))
}

/// `scipy.signal.freqz_sos(sos, worN=f, fs=fs)` for an array `f`: `(w, H)`
/// as [`freqz_grid`].
#[pyfunction]
pub(super) fn sosfreqz_grid<'py>(
    py: Python<'py>,
    sos: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    fs: f64,
) -> PyResult<(Arr1<'py>, CArr1<'py>)> {
    let sos = sos_from(&sos)?;
    let f = slice1(&f)?;
    let (w, h) = py
        .detach(|| dsp::sosfreqz_values(&sos, f, fs).map(|h| (scipy_grid(f, fs), h)))
        .map_err(errors::dsp)?;
    Ok((w.into_pyarray(py), complex(py, h)))
}

/// `scipy.signal.freqz_sos(sos, worN=f, fs=fs)`: `H` at frequencies `f`.
#[pyfunction]
pub(super) fn sosfreqz<'py>(
    py: Python<'py>,
    sos: PyReadonlyArray2<'py, f64>,
    f: PyReadonlyArray1<'py, f64>,
    fs: f64,
) -> PyResult<CArr1<'py>> {
    let sos = sos_from(&sos)?;
    let f = slice1(&f)?;
    let h = py
        .detach(|| dsp::sosfreqz_values(&sos, f, fs))
        .map_err(errors::dsp)?;
    Ok(complex(py, h))
}

/// `numpy.gradient` along each row, with a uniform step `h` or sample
/// coordinates `coords`.
#[pyfunction]
#[pyo3(signature = (f, h, coords, edge_order))]
pub(super) fn gradient<'py>(
    py: Python<'py>,
    f: PyReadonlyArray2<'py, f64>,
    h: f64,
    coords: Option<PyReadonlyArray1<'py, f64>>,
    edge_order: usize,
) -> PyResult<Arr2<'py>> {
    let edge = match edge_order {
        1 => dsp::EdgeOrder::First,
        2 => dsp::EdgeOrder::Second,
        _ => return Err(errors::value("'edge_order' greater than 2 not supported")),
    };
    let c = match &coords {
        Some(c) => Some(slice1(c)?),
        None => None,
    };
    let spacing = match c {
        Some(c) => Spacing::Coordinates(c),
        None => Spacing::Uniform(h),
    };
    let (xs, m, n) = rows(&f)?;
    let (flat, width) = map_rows(py, xs, m, n, |r| {
        dsp::gradient_with_edge_order(r, spacing, edge)
    })?;
    stack(py, flat, m, width)
}

/// `numpy.gradient(f, h, edge_order=edge_order)` of one 1-D signal with a
/// uniform step: the common call, without the rows' plumbing. A short
/// signal is differentiated without releasing the GIL (a few microseconds
/// of work, less than the release and the wait to take it back).
#[pyfunction]
pub(super) fn gradient1<'py>(
    py: Python<'py>,
    f: PyReadonlyArray1<'py, f64>,
    h: f64,
    edge_order: usize,
) -> PyResult<Arr1<'py>> {
    let edge = match edge_order {
        1 => dsp::EdgeOrder::First,
        2 => dsp::EdgeOrder::Second,
        _ => return Err(errors::value("'edge_order' greater than 2 not supported")),
    };
    let f = slice1(&f)?;
    let run = || dsp::gradient_with_edge_order(f, Spacing::Uniform(h), edge);
    let g = if f.len() <= SMALL_WORK {
        run()
    } else {
        py.detach(run)
    }
    .map_err(errors::dsp)?;
    Ok(g.into_pyarray(py))
}

/// `numpy.gradient(f, h)` with its checks made here instead of in Python
/// (about 0.4 us less per call than `gradient1` behind the Python checks):
/// `f` a C-contiguous 1-D float64 array of at least two samples and `h` a
/// Python float, else `None` and the caller takes the general path (which
/// converts the arguments or raises NumPy's errors).
#[pyfunction]
pub(super) fn gradient_plain<'py>(
    py: Python<'py>,
    f: &Bound<'py, PyAny>,
    h: &Bound<'py, PyAny>,
) -> PyResult<Option<Arr1<'py>>> {
    let (Ok(f), Ok(h)) = (f.cast::<PyArray1<f64>>(), h.cast_exact::<PyFloat>()) else {
        return Ok(None);
    };
    let Ok(f) = f.try_readonly() else {
        return Ok(None);
    };
    let h = h.value();
    let f = match f.as_slice() {
        Ok(f) if f.len() >= 2 => f,
        _ => return Ok(None),
    };
    let run = || dsp::gradient_with_edge_order(f, Spacing::Uniform(h), dsp::EdgeOrder::First);
    let g = if f.len() <= SMALL_WORK {
        run()
    } else {
        py.detach(run)
    }
    .map_err(errors::dsp)?;
    Ok(Some(g.into_pyarray(py)))
}
