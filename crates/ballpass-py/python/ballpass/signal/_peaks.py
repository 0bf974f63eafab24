"""``find_peaks``, ``peak_prominences`` and ``peak_widths`` of ``ballpass.signal``."""

from __future__ import annotations

import math
import warnings

import numpy as np

from .. import _native
from .._arrays import real_float64



class PeakPropertyWarning(RuntimeWarning):
    """A peak has a prominence or width of 0 (``scipy.signal.PeakPropertyWarning``)."""


def _interval(value, name):
    """A find_peaks condition as (min, max) of floats or None."""
    if value is None:
        return None
    try:
        lo, hi = value
    except (TypeError, ValueError):
        lo, hi = value, None
    for v in (lo, hi):
        if isinstance(v, np.ndarray) and v.ndim > 0:
            raise NotImplementedError(
                f"{name}: per-sample (array) bounds are not supported by ballpass.signal"
            )
    return (None if lo is None else float(lo), None if hi is None else float(hi))


def _x1d(x):
    x = real_float64(x, "x")
    if x.ndim != 1:
        raise ValueError("`x` must be a 1-D array")
    return np.ascontiguousarray(x)


def _peaks(peaks):
    p = np.asarray(peaks)
    if p.size == 0:
        p = np.array([], dtype=np.intp)
    try:
        p = p.astype(np.intp, order="C", casting="safe", subok=False, copy=False)
    except TypeError as e:
        raise TypeError("cannot safely cast `peaks` to dtype('intp')") from e
    if p.ndim != 1:
        raise ValueError("`peaks` must be a 1-D array")
    return np.ascontiguousarray(p, dtype=np.int64)


def _wlen(wlen):
    if wlen is None:
        return None
    if not 1 < wlen:
        raise ValueError(f"`wlen` must be larger than 1, was {wlen}")
    return float(math.ceil(wlen)) if isinstance(wlen, float) else float(wlen)


def find_peaks(x, height=None, threshold=None, distance=None, prominence=None,
               width=None, wlen=None, rel_height=0.5, plateau_size=None):
    """Local maxima of a 1-D signal and their properties
    (``scipy.signal.find_peaks``): ``(peaks, properties)``, the indices and
    a dict with SciPy's keys (``peak_heights``, ``prominences``,
    ``left_bases``, ``widths``, ...). Bounds are a number (minimum) or a
    ``(min, max)`` pair; widths are in samples."""
    x = _x1d(x)
    if distance is not None and distance < 1:
        raise ValueError("`distance` must be greater or equal to 1")
    needs_prominence = prominence is not None or width is not None
    w = _wlen(wlen) if needs_prominence else None
    if width is not None and not rel_height >= 0:
        raise ValueError("`rel_height` must be greater or equal to 0.0")
    return _native.find_peaks(
        x,
        _interval(height, "height"),
        _interval(threshold, "threshold"),
        None if distance is None else float(distance),
        _interval(prominence, "prominence"),
        _interval(width, "width"),
        w,
        float(rel_height) if width is not None else 0.5,
        _interval(plateau_size, "plateau_size"),
    )


def peak_prominences(x, peaks, wlen=None):
    """Prominence of each peak and its bases (``scipy.signal.peak_prominences``):
    ``(prominences, left_bases, right_bases)``."""
    x = _x1d(x)
    p = _peaks(peaks)
    out = _native.peak_prominences(x, p, _wlen(wlen))
    if np.any(out[0] == 0):
        warnings.warn("some peaks have a prominence of 0", PeakPropertyWarning, stacklevel=2)
    return out


def peak_widths(x, peaks, rel_height=0.5, prominence_data=None, wlen=None):
    """Width of each peak at ``rel_height`` of its prominence below the peak
    (``scipy.signal.peak_widths``): ``(widths, width_heights, left_ips,
    right_ips)``, in samples."""
    x = _x1d(x)
    p = _peaks(peaks)
    if not rel_height >= 0:
        raise ValueError("`rel_height` must be greater or equal to 0.0")
    if prominence_data is None:
        out = _native.peak_widths(x, p, float(rel_height), None, _wlen(wlen))
    else:
        prom, lb, rb = prominence_data
        prom = np.ascontiguousarray(prom, dtype=np.float64)
        lb, rb = _peaks(lb), _peaks(rb)
        if not (prom.shape == lb.shape == rb.shape == p.shape):
            raise ValueError("arrays in `prominence_data` must have the same shape as `peaks`")
        out = _native.peak_widths(x, p, float(rel_height), (prom, lb, rb), None)
    if np.any(out[0] == 0):
        warnings.warn("some peaks have a width of 0", PeakPropertyWarning, stacklevel=2)
    return out
