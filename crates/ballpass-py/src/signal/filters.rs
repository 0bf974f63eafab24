//! Filter design (`butter`, `cheby1`) and filtering (`sosfilt`, `sosfiltfilt`,
//! `lfilter`, `detrend`, `decimate`).

use ballpass_dsp as dsp;
use ballpass_dsp::{FiltFiltSettings, FilterBand, PadLen, PadType, Sos};
use numpy::ndarray::Array3;
use numpy::{
    Complex64, IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::spectral::detrend_type;
use super::{map_rows, rows, slice1, stack, Arr1, Arr2, CArr1};
use crate::errors;

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
pub(super) fn butter<'py>(
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
pub(super) fn cheby1<'py>(
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

pub(super) fn sos_from(a: &PyReadonlyArray2<'_, f64>) -> PyResult<Sos> {
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
pub(super) fn sosfilt<'py>(
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
pub(super) fn sosfilt_zi<'py>(
    py: Python<'py>,
    sos: PyReadonlyArray2<'py, f64>,
) -> PyResult<Arr2<'py>> {
    let sos = sos_from(&sos)?;
    let zi = dsp::sosfilt_zi(&sos).map_err(errors::dsp)?;
    let n = zi.len();
    stack(py, zi.into_iter().flatten().collect(), n, 2)
}

/// `scipy.signal.sosfiltfilt(sos, x, padtype, padlen)` on each row.
#[pyfunction]
#[pyo3(signature = (sos, x, padtype, padlen=None))]
pub(super) fn sosfiltfilt<'py>(
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
pub(super) fn lfilter<'py>(
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
pub(super) fn lfilter1<'py>(
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
pub(super) fn detrend<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    kind: &str,
) -> PyResult<Arr2<'py>> {
    let kind = detrend_type(kind)?;
    let (xs, m, n) = rows(&x)?;
    let (flat, width) = map_rows(py, xs, m, n, |r| dsp::detrend(r, kind))?;
    stack(py, flat, m, width)
}

/// `scipy.signal.decimate(x, q, n, ftype='iir', zero_phase)` on each row.
#[pyfunction]
pub(super) fn decimate<'py>(
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
