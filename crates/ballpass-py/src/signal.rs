//! The kernels behind `ballpass.signal`: `ballpass-dsp` on numpy arrays.
//!
//! Arguments arrive resolved and checked the way SciPy checks them (the
//! Python module does that, so its exceptions are SciPy's); signals arrive
//! as C-contiguous float64 arrays, several signals as the rows of a 2-D
//! array (the Python module moves `axis` last and flattens the others). The
//! rows are borrowed, not copied, and processed with the GIL released.

use ballpass_dsp as dsp;
use ballpass_dsp::{
    Average, DetrendType, FiltFiltSettings, FilterBand, PadLen, PadType, PeriodogramSettings,
    Scaling, Sos, Spacing, Welch, WelchSettings, Window,
};
use numpy::ndarray::{Array2, Array3};
use numpy::{
    Complex64, IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2,
    PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors;

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

fn window(w: &Bound<'_, PyAny>) -> PyResult<Window> {
    if let Ok(name) = w.extract::<String>() {
        return match name.as_str() {
            "hann" => Ok(Window::Hann),
            "hamming" => Ok(Window::Hamming),
            "boxcar" => Ok(Window::Boxcar),
            other => Err(errors::value(format!("unknown window {other:?}"))),
        };
    }
    let a: PyReadonlyArray1<'_, f64> = w.extract()?;
    Ok(Window::Custom(a.as_array().to_vec()))
}

fn detrend_type(s: &str) -> PyResult<DetrendType> {
    match s {
        "constant" => Ok(DetrendType::Constant),
        "linear" => Ok(DetrendType::Linear),
        "none" => Ok(DetrendType::None),
        other => Err(errors::value(format!("unknown detrend {other:?}"))),
    }
}

fn scaling(s: &str) -> PyResult<Scaling> {
    match s {
        "density" => Ok(Scaling::Density),
        "spectrum" => Ok(Scaling::Spectrum),
        other => Err(errors::value(format!("Unknown scaling: {other:?}"))),
    }
}

fn average(s: &str) -> PyResult<Average> {
    match s {
        "mean" => Ok(Average::Mean),
        "median" => Ok(Average::Median),
        other => Err(errors::value(format!(
            "average must be \"median\" or \"mean\", got {other}"
        ))),
    }
}

#[allow(clippy::too_many_arguments)]
fn welch_settings(
    win: &Bound<'_, PyAny>,
    nperseg: usize,
    noverlap: usize,
    nfft: usize,
    detrend: &str,
    scale: &str,
    onesided: bool,
    avg: &str,
) -> PyResult<WelchSettings> {
    Ok(WelchSettings {
        window: window(win)?,
        nperseg,
        noverlap: Some(noverlap),
        nfft: Some(nfft),
        detrend: detrend_type(detrend)?,
        scaling: scaling(scale)?,
        onesided,
        average: average(avg)?,
    })
}

/// `scipy.signal.welch` on each row: (freq, pxx rows).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn welch<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    fs: f64,
    window: &Bound<'py, PyAny>,
    nperseg: usize,
    noverlap: usize,
    nfft: usize,
    detrend: &str,
    scaling: &str,
    onesided: bool,
    average: &str,
) -> PyResult<(Arr1<'py>, Arr2<'py>)> {
    let s = welch_settings(
        window, nperseg, noverlap, nfft, detrend, scaling, onesided, average,
    )?;
    let (xs, m, n) = rows(&x)?;
    let mut w = Welch::new(s).map_err(errors::dsp)?;
    let mut freq = Vec::new();
    let (flat, width) = map_rows(py, xs, m, n, |r| {
        let p = w.psd(r, fs)?;
        freq = p.freq_hz;
        Ok(p.pxx)
    })?;
    Ok((freq.into_pyarray(py), stack(py, flat, m, width)?))
}

/// `scipy.signal.csd` on each pair of rows: (freq, complex pxy rows).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn csd<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    y: PyReadonlyArray2<'py, f64>,
    fs: f64,
    window: &Bound<'py, PyAny>,
    nperseg: usize,
    noverlap: usize,
    nfft: usize,
    detrend: &str,
    scaling: &str,
    onesided: bool,
    average: &str,
) -> PyResult<(Arr1<'py>, Bound<'py, PyArray2<Complex64>>)> {
    let s = welch_settings(
        window, nperseg, noverlap, nfft, detrend, scaling, onesided, average,
    )?;
    let mut w = Welch::new(s).map_err(errors::dsp)?;
    map_pairs(py, &x, &y, |x, y| {
        let c = w.csd(x, y, fs)?;
        let pxy = c.pxy.iter().map(|z| Complex64::new(z.re, z.im)).collect();
        Ok((c.freq_hz, pxy))
    })
}

/// `scipy.signal.coherence` on each pair of rows: (freq, cxy rows).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn coherence<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    y: PyReadonlyArray2<'py, f64>,
    fs: f64,
    window: &Bound<'py, PyAny>,
    nperseg: usize,
    noverlap: usize,
    nfft: usize,
    detrend: &str,
) -> PyResult<(Arr1<'py>, Arr2<'py>)> {
    let s = welch_settings(
        window, nperseg, noverlap, nfft, detrend, "density", true, "mean",
    )?;
    let mut w = Welch::new(s).map_err(errors::dsp)?;
    map_pairs(py, &x, &y, |x, y| {
        let c = w.coherence(x, y, fs)?;
        Ok((c.freq_hz, c.cxy))
    })
}

/// `scipy.signal.periodogram` on each row (`nfft` already resolved:
/// `None` is the row length).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn periodogram<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    fs: f64,
    window: &Bound<'py, PyAny>,
    nfft: Option<usize>,
    detrend: &str,
    scaling: &str,
    onesided: bool,
) -> PyResult<(Arr1<'py>, Arr2<'py>)> {
    let s = PeriodogramSettings {
        window: self::window(window)?,
        nfft,
        detrend: detrend_type(detrend)?,
        scaling: self::scaling(scaling)?,
        onesided,
    };
    let (xs, m, n) = rows(&x)?;
    let mut freq = Vec::new();
    let (flat, width) = map_rows(py, xs, m, n, |r| {
        let p = dsp::periodogram(r, fs, &s)?;
        freq = p.freq_hz;
        Ok(p.pxx)
    })?;
    Ok((freq.into_pyarray(py), stack(py, flat, m, width)?))
}

/// `scipy.signal.correlate(x, y, mode='full')` of two 1-D arrays.
#[pyfunction]
fn correlate<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    y: PyReadonlyArray1<'py, f64>,
) -> PyResult<Arr1<'py>> {
    let (xs, ys) = (slice1(&x)?, slice1(&y)?);
    let values = py
        .detach(|| {
            CORRELATOR.with_borrow_mut(|(c, out)| {
                c.correlate_into(xs, ys, out)?;
                Ok(std::mem::take(&mut out.values))
            })
        })
        .map_err(errors::dsp)?;
    Ok(values.into_pyarray(py))
}

thread_local! {
    /// Each thread's correlator and its last lags: its FFT buffers (three
    /// spectra of `len / 2` bins, the scratch) and the lag vector are made
    /// once per signal length instead of zeroed anew on every call. A
    /// cache only: every call computes from its own arguments.
    static CORRELATOR: std::cell::RefCell<(dsp::Correlator, dsp::Correlation)> =
        std::cell::RefCell::new((
            dsp::Correlator::new(dsp::CorrelateSettings {
                normalization: dsp::Normalization::None,
            }),
            dsp::Correlation {
                lags: Vec::new(),
                values: Vec::new(),
            },
        ));
}

/// `scipy.signal.correlation_lags(nx, ny, mode='full')`.
#[pyfunction]
fn correlation_lags(py: Python<'_>, nx: usize, ny: usize) -> Bound<'_, PyArray1<i64>> {
    dsp::correlation_lags(nx, ny).into_pyarray(py)
}

fn slice1<'a>(a: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|e| errors::value(format!("expected a contiguous array: {e}")))
}

fn band(btype: &str, wn: &[f64]) -> PyResult<FilterBand> {
    match (btype, wn) {
        ("lowpass", [c]) => Ok(FilterBand::LowPass { cutoff_hz: *c }),
        ("highpass", [c]) => Ok(FilterBand::HighPass { cutoff_hz: *c }),
        ("bandpass", [lo, hi]) => Ok(FilterBand::BandPass {
            low_hz: *lo,
            high_hz: *hi,
        }),
        ("bandstop", [lo, hi]) => Ok(FilterBand::BandStop {
            low_hz: *lo,
            high_hz: *hi,
        }),
        _ => Err(errors::value(format!(
            "{btype} needs {} critical frequencies, got {}",
            if btype.starts_with("band") { 2 } else { 1 },
            wn.len()
        ))),
    }
}

/// A designed filter: `(sos, zeros, poles, gain)`.
type Design<'py> = (Arr2<'py>, CArr1<'py>, CArr1<'py>, f64);

fn design<'py>(py: Python<'py>, zpk: dsp::Zpk) -> PyResult<Design<'py>> {
    let sos = dsp::zpk2sos(&zpk).map_err(errors::dsp)?;
    let c = |v: &[dsp::Complex64]| -> Vec<Complex64> {
        v.iter().map(|z| Complex64::new(z.re, z.im)).collect()
    };
    Ok((
        sos_array(py, &sos)?,
        c(&zpk.zeros).into_pyarray(py),
        c(&zpk.poles).into_pyarray(py),
        zpk.gain,
    ))
}

fn sos_array<'py>(py: Python<'py>, sos: &Sos) -> PyResult<Arr2<'py>> {
    let flat: Vec<f64> = sos.sections().iter().flatten().copied().collect();
    stack(py, flat, sos.n_sections(), 6)
}

/// `scipy.signal.butter(order, wn, btype, fs=fs)`: sections, zeros, poles, gain.
#[pyfunction]
fn butter<'py>(
    py: Python<'py>,
    order: usize,
    wn: Vec<f64>,
    btype: &str,
    fs: f64,
) -> PyResult<Design<'py>> {
    let zpk = dsp::butter_zpk(order, band(btype, &wn)?, fs).map_err(errors::dsp)?;
    design(py, zpk)
}

/// `scipy.signal.cheby1(order, rp, wn, btype, fs=fs)`: sections, zeros, poles, gain.
#[pyfunction]
fn cheby1<'py>(
    py: Python<'py>,
    order: usize,
    rp: f64,
    wn: Vec<f64>,
    btype: &str,
    fs: f64,
) -> PyResult<Design<'py>> {
    let zpk = dsp::cheby1_zpk(order, rp, band(btype, &wn)?, fs).map_err(errors::dsp)?;
    design(py, zpk)
}

fn sos_from(a: &PyReadonlyArray2<'_, f64>) -> PyResult<Sos> {
    if a.shape()[1] != 6 {
        return Err(errors::value("sos array must be shape (n_sections, 6)"));
    }
    let (s, m, _) = rows(a)?;
    if (0..m).any(|i| s[6 * i + 3] != 1.0) {
        return Err(errors::value("sos[:, 3] should be all ones"));
    }
    let sections = (0..m)
        .map(|i| {
            let mut r = [0.0; 6];
            r.copy_from_slice(&s[6 * i..6 * i + 6]);
            r
        })
        .collect();
    Sos::new(sections).map_err(errors::dsp)
}

/// `scipy.signal.sosfilt` on each row; with `zi` of shape `(rows,
/// n_sections, 2)` the final states too.
#[pyfunction]
#[pyo3(signature = (sos, x, zi=None))]
fn sosfilt<'py>(
    py: Python<'py>,
    sos: PyReadonlyArray2<'py, f64>,
    x: PyReadonlyArray2<'py, f64>,
    zi: Option<PyReadonlyArray3<'py, f64>>,
) -> PyResult<(Arr2<'py>, Option<Bound<'py, PyArray3<f64>>>)> {
    let sos = sos_from(&sos)?;
    let (xs, m, n) = rows(&x)?;
    let ns = sos.n_sections();
    let Some(zi) = zi else {
        let (flat, width) = map_rows(py, xs, m, n, |r| dsp::sosfilt_fast(&sos, r))?;
        return Ok((stack(py, flat, m, width)?, None));
    };
    if zi.shape() != [m, ns, 2] {
        return Err(errors::value(format!(
            "zi must have shape ({m}, {ns}, 2) for {m} signals and {ns} sections, got {:?}",
            zi.shape()
        )));
    }
    let zs = zi
        .as_slice()
        .map_err(|e| errors::value(format!("expected a contiguous zi: {e}")))?;
    let (y, zf) = py
        .detach(|| -> dsp::Result<_> {
            let (mut y, mut zf) = (Vec::with_capacity(m * n), Vec::with_capacity(m * ns * 2));
            for i in 0..m {
                let z0: Vec<[f64; 2]> = (0..ns)
                    .map(|s| [zs[(i * ns + s) * 2], zs[(i * ns + s) * 2 + 1]])
                    .collect();
                let o = dsp::sosfilt_fast_with_state(&sos, &xs[i * n..(i + 1) * n], &z0)?;
                y.extend_from_slice(&o.y);
                zf.extend(o.zf.iter().flatten());
            }
            Ok((y, zf))
        })
        .map_err(errors::dsp)?;
    let zf = Array3::from_shape_vec((m, ns, 2), zf)
        .map_err(errors::value)?
        .into_pyarray(py);
    Ok((stack(py, y, m, n)?, Some(zf)))
}

/// `scipy.signal.sosfilt_zi(sos)`.
#[pyfunction]
fn sosfilt_zi<'py>(py: Python<'py>, sos: PyReadonlyArray2<'py, f64>) -> PyResult<Arr2<'py>> {
    let sos = sos_from(&sos)?;
    let zi = dsp::sosfilt_zi(&sos).map_err(errors::dsp)?;
    let n = zi.len();
    stack(py, zi.into_iter().flatten().collect(), n, 2)
}

/// `scipy.signal.sosfiltfilt(sos, x, padtype, padlen)` on each row.
#[pyfunction]
#[pyo3(signature = (sos, x, padtype, padlen=None))]
fn sosfiltfilt<'py>(
    py: Python<'py>,
    sos: PyReadonlyArray2<'py, f64>,
    x: PyReadonlyArray2<'py, f64>,
    padtype: &str,
    padlen: Option<usize>,
) -> PyResult<Arr2<'py>> {
    let sos = sos_from(&sos)?;
    let pad_type = match padtype {
        "odd" => PadType::Odd,
        "even" => PadType::Even,
        "constant" => PadType::Constant,
        "none" => PadType::None,
        other => return Err(errors::value(format!("Unknown padding type {other:?}"))),
    };
    let pad_len = padlen.map_or(PadLen::Auto, PadLen::Samples);
    let f = dsp::ZeroPhaseFilter::new(sos, FiltFiltSettings { pad_type, pad_len })
        .map_err(errors::dsp)?;
    let (xs, m, n) = rows(&x)?;
    let (flat, width) = map_rows(py, xs, m, n, |r| f.apply(r))?;
    stack(py, flat, m, width)
}

/// `scipy.signal.lfilter(b, a, x)` on each row (long rows of a
/// well-conditioned filter split into chunks run side by side,
/// `ballpass_dsp::lfilter_fast`: SciPy's numbers to ~1e-10, not its
/// rounding); with `zi` of shape `(rows, K)` the final states too (SciPy's
/// loop: the final state needs the whole run).
#[pyfunction]
#[pyo3(signature = (b, a, x, zi=None))]
fn lfilter<'py>(
    py: Python<'py>,
    b: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    x: PyReadonlyArray2<'py, f64>,
    zi: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<(Arr2<'py>, Option<Arr2<'py>>)> {
    let (b, a) = (slice1(&b)?, slice1(&a)?);
    let (xs, m, n) = rows(&x)?;
    let Some(zi) = zi else {
        let (flat, width) = map_rows(py, xs, m, n, |r| dsp::lfilter_fast(b, a, r))?;
        return Ok((stack(py, flat, m, width)?, None));
    };
    let (zs, mz, k) = rows(&zi)?;
    if mz != m {
        return Err(errors::value(format!("zi has {mz} rows, x has {m}")));
    }
    let (y, zf) = py
        .detach(|| -> dsp::Result<_> {
            let (mut y, mut zf) = (Vec::with_capacity(m * n), Vec::with_capacity(m * k));
            for i in 0..m {
                let o = dsp::lfilter_with_state(
                    b,
                    a,
                    &xs[i * n..(i + 1) * n],
                    &zs[i * k..(i + 1) * k],
                )?;
                y.extend_from_slice(&o.y);
                zf.extend_from_slice(&o.zf);
            }
            Ok((y, zf))
        })
        .map_err(errors::dsp)?;
    Ok((stack(py, y, m, n)?, Some(stack(py, zf, m, k)?)))
}

/// `lfilter(b, a, x)` of one 1-D signal from rest: the common call, its
/// output made straight from the kernel's (no rows to stack).
#[pyfunction]
fn lfilter1<'py>(
    py: Python<'py>,
    b: PyReadonlyArray1<'py, f64>,
    a: PyReadonlyArray1<'py, f64>,
    x: PyReadonlyArray1<'py, f64>,
) -> PyResult<Arr1<'py>> {
    let (b, a, x) = (slice1(&b)?, slice1(&a)?, slice1(&x)?);
    let y = py
        .detach(|| dsp::lfilter_fast(b, a, x))
        .map_err(errors::dsp)?;
    Ok(y.into_pyarray(py))
}

/// `scipy.signal.detrend(x, type=type)` on each row.
#[pyfunction]
fn detrend<'py>(py: Python<'py>, x: PyReadonlyArray2<'py, f64>, kind: &str) -> PyResult<Arr2<'py>> {
    let kind = detrend_type(kind)?;
    let (xs, m, n) = rows(&x)?;
    let (flat, width) = map_rows(py, xs, m, n, |r| dsp::detrend(r, kind))?;
    stack(py, flat, m, width)
}

/// `scipy.signal.decimate(x, q, n, ftype='iir', zero_phase)` on each row.
#[pyfunction]
fn decimate<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    q: usize,
    order: usize,
    zero_phase: bool,
) -> PyResult<Arr2<'py>> {
    let d = dsp::Decimator::new(dsp::DecimateSettings {
        q,
        order,
        zero_phase,
    })
    .map_err(errors::dsp)?;
    let (xs, m, n) = rows(&x)?;
    let (flat, width) = map_rows(py, xs, m, n, |r| d.apply(r))?;
    stack(py, flat, m, width)
}

type Interval = Option<(Option<f64>, Option<f64>)>;

fn bound(b: Interval) -> Option<dsp::Bound> {
    b.map(|(min, max)| dsp::Bound { min, max })
}

fn indices<'py>(py: Python<'py>, v: &[usize]) -> Bound<'py, PyArray1<i64>> {
    v.iter()
        .map(|&i| i as i64)
        .collect::<Vec<_>>()
        .into_pyarray(py)
}

/// `scipy.signal.find_peaks`: (peaks, properties) with SciPy's keys, in
/// SciPy's order.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (x, height, threshold, distance, prominence, width, wlen, rel_height, plateau_size))]
fn find_peaks<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    height: Interval,
    threshold: Interval,
    distance: Option<f64>,
    prominence: Interval,
    width: Interval,
    wlen: Option<f64>,
    rel_height: f64,
    plateau_size: Interval,
) -> PyResult<(Bound<'py, PyArray1<i64>>, Bound<'py, PyDict>)> {
    let settings = dsp::FindPeaksSettings {
        height: bound(height),
        threshold: bound(threshold),
        distance,
        prominence: bound(prominence),
        width: bound(width),
        wlen,
        rel_height,
        plateau_size: bound(plateau_size),
    };
    let xs = slice1(&x)?;
    let p = py
        .detach(|| dsp::find_peaks(xs, &settings))
        .map_err(errors::dsp)?;
    let props = PyDict::new(py);
    let q = p.properties;
    let f = |v: Option<Vec<f64>>| v.map(|v| v.into_pyarray(py));
    let i = |v: Option<Vec<usize>>| v.map(|v| indices(py, &v));
    for (k, v) in [
        ("plateau_sizes", i(q.plateau_sizes)),
        ("left_edges", i(q.left_edges)),
        ("right_edges", i(q.right_edges)),
    ] {
        if let Some(v) = v {
            props.set_item(k, v)?;
        }
    }
    for (k, v) in [
        ("peak_heights", f(q.peak_heights)),
        ("left_thresholds", f(q.left_thresholds)),
        ("right_thresholds", f(q.right_thresholds)),
        ("prominences", f(q.prominences)),
    ] {
        if let Some(v) = v {
            props.set_item(k, v)?;
        }
    }
    for (k, v) in [
        ("left_bases", i(q.left_bases)),
        ("right_bases", i(q.right_bases)),
    ] {
        if let Some(v) = v {
            props.set_item(k, v)?;
        }
    }
    for (k, v) in [
        ("widths", f(q.widths)),
        ("width_heights", f(q.width_heights)),
        ("left_ips", f(q.left_ips)),
        ("right_ips", f(q.right_ips)),
    ] {
        if let Some(v) = v {
            props.set_item(k, v)?;
        }
    }
    Ok((indices(py, &p.indices), props))
}

fn peak_list(p: &PyReadonlyArray1<'_, i64>, n: usize) -> PyResult<Vec<usize>> {
    p.as_array()
        .iter()
        .map(|&i| {
            usize::try_from(i)
                .ok()
                .filter(|&u| u < n)
                .ok_or_else(|| errors::value(format!("peak {i} is not a valid index for `x`")))
        })
        .collect()
}

/// `scipy.signal.peak_prominences`: (prominences, left_bases, right_bases).
#[pyfunction]
#[pyo3(signature = (x, peaks, wlen=None))]
fn peak_prominences<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    peaks: PyReadonlyArray1<'py, i64>,
    wlen: Option<f64>,
) -> PyResult<(Arr1<'py>, IArr1<'py>, IArr1<'py>)> {
    let xs = slice1(&x)?;
    let pk = peak_list(&peaks, xs.len())?;
    let p = py
        .detach(|| dsp::peak_prominences(xs, &pk, wlen))
        .map_err(errors::dsp)?;
    Ok((
        p.prominences.into_pyarray(py),
        indices(py, &p.left_bases),
        indices(py, &p.right_bases),
    ))
}

type ProminenceData<'py> = (
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray1<'py, i64>,
);

/// `scipy.signal.peak_widths`: (widths, width_heights, left_ips, right_ips).
#[pyfunction]
#[pyo3(signature = (x, peaks, rel_height, prominence_data=None, wlen=None))]
fn peak_widths<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    peaks: PyReadonlyArray1<'py, i64>,
    rel_height: f64,
    prominence_data: Option<ProminenceData<'py>>,
    wlen: Option<f64>,
) -> PyResult<(Arr1<'py>, Arr1<'py>, Arr1<'py>, Arr1<'py>)> {
    let xs = slice1(&x)?;
    let pk = peak_list(&peaks, xs.len())?;
    let base = |a: &PyReadonlyArray1<'_, i64>| -> PyResult<Vec<usize>> {
        a.as_array()
            .iter()
            .map(|&i| {
                usize::try_from(i).map_err(|_| {
                    errors::value(format!(
                        "prominence data is invalid: base {i} is not a valid index"
                    ))
                })
            })
            .collect()
    };
    let prom = match &prominence_data {
        Some((p, l, r)) => Some(dsp::Prominences {
            prominences: p.as_array().to_vec(),
            left_bases: base(l)?,
            right_bases: base(r)?,
        }),
        None => None,
    };
    let w = py
        .detach(|| match &prom {
            Some(p) => dsp::peak_widths_with_prominences(xs, &pk, rel_height, p),
            None => dsp::peak_widths(xs, &pk, &dsp::PeakWidthsSettings { rel_height, wlen }),
        })
        .map_err(errors::dsp)?;
    Ok((
        w.widths.into_pyarray(py),
        w.width_heights.into_pyarray(py),
        w.left_ips.into_pyarray(py),
        w.right_ips.into_pyarray(py),
    ))
}

/// A response as a numpy array: `ballpass_dsp::Complex64` is numpy's
/// complex128 element (both `num_complex::Complex<f64>`), so the vector
/// becomes the array without a copy.
fn complex(py: Python<'_>, h: Vec<dsp::Complex64>) -> CArr1<'_> {
    h.into_pyarray(py)
}

/// `scipy.signal.freqs(b, a, worN=w)`: `H(j w)`.
#[pyfunction]
fn freqs<'py>(
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
fn freqz<'py>(
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

/// `scipy.signal.freqz_sos(sos, worN=f, fs=fs)`: `H` at frequencies `f`.
#[pyfunction]
fn sosfreqz<'py>(
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
fn gradient<'py>(
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
fn gradient1<'py>(
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

/// Samples below which a one-pass kernel keeps the GIL.
const SMALL_WORK: usize = 4096;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(welch, m)?)?;
    m.add_function(wrap_pyfunction!(csd, m)?)?;
    m.add_function(wrap_pyfunction!(coherence, m)?)?;
    m.add_function(wrap_pyfunction!(periodogram, m)?)?;
    m.add_function(wrap_pyfunction!(correlate, m)?)?;
    m.add_function(wrap_pyfunction!(correlation_lags, m)?)?;
    m.add_function(wrap_pyfunction!(butter, m)?)?;
    m.add_function(wrap_pyfunction!(cheby1, m)?)?;
    m.add_function(wrap_pyfunction!(sosfilt, m)?)?;
    m.add_function(wrap_pyfunction!(sosfilt_zi, m)?)?;
    m.add_function(wrap_pyfunction!(sosfiltfilt, m)?)?;
    m.add_function(wrap_pyfunction!(lfilter, m)?)?;
    m.add_function(wrap_pyfunction!(lfilter1, m)?)?;
    m.add_function(wrap_pyfunction!(detrend, m)?)?;
    m.add_function(wrap_pyfunction!(decimate, m)?)?;
    m.add_function(wrap_pyfunction!(find_peaks, m)?)?;
    m.add_function(wrap_pyfunction!(peak_prominences, m)?)?;
    m.add_function(wrap_pyfunction!(peak_widths, m)?)?;
    m.add_function(wrap_pyfunction!(freqs, m)?)?;
    m.add_function(wrap_pyfunction!(freqz, m)?)?;
    m.add_function(wrap_pyfunction!(sosfreqz, m)?)?;
    m.add_function(wrap_pyfunction!(gradient, m)?)?;
    m.add_function(wrap_pyfunction!(gradient1, m)?)?;
    Ok(())
}
