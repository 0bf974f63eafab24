//! `welch`, `csd`, `coherence`, `periodogram`, `correlate` and `correlation_lags`.

use ballpass_dsp as dsp;
use ballpass_dsp::{
    Average, DetrendType, PeriodogramSettings, Scaling, Welch, WelchSettings, Window,
};
use numpy::{Complex64, IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use super::{map_pairs, map_rows, rows, slice1, stack, Arr1, Arr2};
use crate::errors;

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

pub(super) fn detrend_type(s: &str) -> PyResult<DetrendType> {
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
pub(super) fn welch<'py>(
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
pub(super) fn csd<'py>(
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
pub(super) fn coherence<'py>(
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
pub(super) fn periodogram<'py>(
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
pub(super) fn correlate<'py>(
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
pub(super) fn correlation_lags(py: Python<'_>, nx: usize, ny: usize) -> Bound<'_, PyArray1<i64>> {
    dsp::correlation_lags(nx, ny).into_pyarray(py)
}
