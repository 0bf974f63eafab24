//! `find_peaks`, `peak_prominences` and `peak_widths`.

use ballpass_dsp as dsp;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::{slice1, Arr1, IArr1};
use crate::errors;

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
pub(super) fn find_peaks<'py>(
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
pub(super) fn peak_prominences<'py>(
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
pub(super) fn peak_widths<'py>(
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
