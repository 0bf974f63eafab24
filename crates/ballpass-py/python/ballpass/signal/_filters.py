"""Filter design (``butter``, ``cheby1``) and filtering (``sosfilt``,
``sosfiltfilt``, ``lfilter``, ``detrend``, ``decimate``) of ``ballpass.signal``."""

from __future__ import annotations

import math
import operator

import numpy as np

from .. import _native
from .._arrays import from_rows, normalize_axis, real_float64, to_rows


_BANDS = {
    "band": "bandpass", "bandpass": "bandpass", "pass": "bandpass", "bp": "bandpass",
    "bs": "bandstop", "bandstop": "bandstop", "bands": "bandstop", "stop": "bandstop",
    "l": "lowpass", "low": "lowpass", "lowpass": "lowpass", "lp": "lowpass",
    "high": "highpass", "highpass": "highpass", "h": "highpass", "hp": "highpass",
}


def _poly(roots):
    """numpy.poly of a root array (real when the roots are conjugate pairs)."""
    return np.atleast_1d(np.poly(roots))


def _iir(order, rp, Wn, btype, analog, output, fs, kind):
    """SciPy's iirfilter argument handling around the Rust design."""
    if analog:
        raise NotImplementedError(
            "analog=True: ballpass.signal designs digital filters only"
        )
    Wn = np.asarray(Wn, dtype=np.float64)
    if fs is not None:
        if not np.isscalar(fs):
            raise ValueError("Sampling frequency fs must be a single scalar.")
        fs = float(fs)
        Wn = Wn / (fs / 2)
    btype, output = btype.lower(), output.lower()
    if np.any(Wn <= 0):
        raise ValueError("filter critical frequencies must be greater than 0")
    if Wn.size > 1 and not Wn.reshape(-1)[0] < Wn.reshape(-1)[1]:
        raise ValueError("Wn[0] must be less than Wn[1]")
    if btype not in _BANDS:
        raise ValueError(f"'{btype}' is an invalid bandtype for filter.")
    btype = _BANDS[btype]
    if output not in ("ba", "zpk", "sos"):
        raise ValueError(f"'{output}' is not a valid output form.")
    if rp is not None and rp < 0:
        raise ValueError("passband ripple (rp) must be positive")
    if abs(int(order)) != order:
        raise ValueError("Filter order must be a nonnegative integer")
    order = int(order)
    if np.any(Wn <= 0) or np.any(Wn >= 1):
        if fs is not None:
            raise ValueError(
                "Digital filter critical frequencies must be 0 < Wn < fs/2 "
                f"(fs={fs} -> fs/2={fs / 2})"
            )
        raise ValueError("Digital filter critical frequencies must be 0 < Wn < 1")
    wn = [float(v) for v in Wn.reshape(-1)]
    if btype in ("lowpass", "highpass") and len(wn) != 1:
        raise ValueError("Must specify a single critical frequency Wn for lowpass or highpass filter")
    if btype in ("bandpass", "bandstop") and len(wn) != 2:
        raise ValueError(
            "Wn must specify start and stop frequencies for bandpass or bandstop filter"
        )
    if order == 0:
        # The trivial filter of an order-0 prototype: gain 1 (Butterworth)
        # or 10^(-rp/20) (Chebyshev I), no poles or zeros.
        k = 1.0 if rp is None else 10 ** (-rp / 20)
        z = p = np.array([], dtype=complex)
        sos = np.array([[k, 0.0, 0.0, 1.0, 0.0, 0.0]])
    elif kind == "butter":
        sos, z, p, k = _native.butter(order, wn, btype, 2.0)
    else:
        sos, z, p, k = _native.cheby1(order, float(rp), wn, btype, 2.0)
    if output == "sos":
        return sos
    if output == "zpk":
        return z, p, k
    return k * _poly(z), _poly(p)


def butter(N, Wn, btype="low", analog=False, output="ba", fs=None):
    """Digital Butterworth filter (``scipy.signal.butter``).

    ``Wn`` is the -3 dB frequency: in Hz with ``fs``, else a fraction of
    Nyquist. ``output='sos'`` (second-order sections, recommended),
    ``'zpk'`` or ``'ba'`` (transfer function, from the same zeros and poles).
    """
    return _iir(N, None, Wn, btype, analog, output, fs, "butter")


def cheby1(N, rp, Wn, btype="low", analog=False, output="ba", fs=None):
    """Digital Chebyshev type I filter with ``rp`` dB pass-band ripple
    (``scipy.signal.cheby1``); arguments as :func:`butter`."""
    return _iir(N, rp, Wn, btype, analog, output, fs, "cheby1")


# ---------------------------------------------------------------- filtering


def _sos(sos):
    sos = np.asarray(sos)
    if np.iscomplexobj(sos):
        raise NotImplementedError("complex filter coefficients are not supported by ballpass.signal")
    sos = np.atleast_2d(np.asarray(sos, dtype=np.float64))
    if sos.ndim != 2:
        raise ValueError("sos array must be 2D")
    if sos.shape[1] != 6:
        raise ValueError("sos array must be shape (n_sections, 6)")
    if not np.all(sos[:, 3] == 1):
        raise ValueError("sos[:, 3] should be all ones")
    return np.ascontiguousarray(sos)


def _x(x):
    x = real_float64(x, "x")
    if x.ndim == 0:
        raise ValueError("x must be at least 1-D")
    return x


def sosfilt(sos, x, axis=-1, zi=None):
    """Filters ``x`` along ``axis`` with second-order sections
    (``scipy.signal.sosfilt``, direct form II transposed). With ``zi`` (shape
    ``(n_sections, ..., 2, ...)``) returns ``(y, zf)``."""
    if (zi is None and type(x) is np.ndarray and x.ndim == 1 and x.dtype == np.float64
            and x.flags.c_contiguous and axis in (-1, 0) and type(sos) is np.ndarray
            and sos.dtype == np.float64 and sos.ndim == 2 and sos.shape[1] == 6
            and sos.flags.c_contiguous):
        # The common call, sosfilt(sos, x) of one float64 signal: straight
        # to the kernel, which checks the sections (a0 = 1, SciPy's message)
        # and the samples.
        y, _ = _native.sosfilt(sos, x.reshape(1, -1))
        return y.reshape(-1)
    x = _x(x)
    sos = _sos(sos)
    ns = sos.shape[0]
    ax = normalize_axis(axis, x.ndim)
    zi_shape = list(x.shape)
    zi_shape[ax] = 2
    zi_shape = tuple([ns] + zi_shape)
    if zi is not None:
        zi = real_float64(zi, "zi")
        if zi.shape != zi_shape:
            raise ValueError(
                f"Invalid zi shape. With axis={axis!r}, an input with shape {x.shape!r}, "
                f"and an sos array with {ns} sections, zi must have shape {zi_shape!r}, "
                f"got {zi.shape!r}."
            )
    rows, outer = to_rows(x, ax)
    if zi is None:
        y, _ = _native.sosfilt(sos, rows)
        return from_rows(y, outer, ax, x.ndim)
    # zi: (ns, ..., 2 at axis+1, ...) -> (rows, ns, 2)
    zm = np.moveaxis(zi, (0, ax + 1), (-2, -1))
    zm_shape = zm.shape
    zr = np.ascontiguousarray(zm.reshape(-1, ns, 2))
    y, zf = _native.sosfilt(sos, rows, zr)
    zf = np.moveaxis(zf.reshape(zm_shape), (-2, -1), (0, ax + 1))
    return from_rows(y, outer, ax, x.ndim), zf


def sosfilt_zi(sos):
    """Initial state of each section for a unit step's steady state
    (``scipy.signal.sosfilt_zi``); multiply by ``x[0]``."""
    sos = np.asarray(sos)
    if sos.ndim != 2 or sos.shape[1] != 6:
        raise ValueError("sos must be shape (n_sections, 6)")
    return _native.sosfilt_zi(_sos(sos))


def sosfiltfilt(sos, x, axis=-1, padtype="odd", padlen=None):
    """Zero-phase forward-backward filtering with second-order sections
    (``scipy.signal.sosfiltfilt``): ``padtype`` ``'odd'``, ``'even'``,
    ``'constant'`` or None; ``padlen`` default
    ``3 (2 n_sections + 1 - min(#b2 == 0, #a2 == 0))``."""
    sos = _sos(sos)
    x = _x(x)
    if padtype not in ("even", "odd", "constant", None):
        raise ValueError(
            f"Unknown value '{padtype}' given to padtype. "
            "padtype must be 'even', 'odd', 'constant', or None."
        )
    ax = normalize_axis(axis, x.ndim)
    ntaps = 2 * sos.shape[0] + 1 - min(int((sos[:, 2] == 0).sum()), int((sos[:, 5] == 0).sum()))
    edge = 0 if padtype is None else (3 * ntaps if padlen is None else int(padlen))
    if x.shape[ax] <= edge:
        raise ValueError(
            f"The length of the input vector x must be greater than padlen, which is {edge}."
        )
    rows, outer = to_rows(x, ax)
    y = _native.sosfiltfilt(sos, rows, "none" if padtype is None else padtype,
                            None if padlen is None else int(padlen))
    return from_rows(y, outer, ax, x.ndim)


def lfilter(b, a, x, axis=-1, zi=None):
    """Filters ``x`` with the transfer function ``b(z) / a(z)``
    (``scipy.signal.lfilter``, direct form II transposed). With ``zi``
    (``x``'s shape with ``axis`` of length ``max(len(a), len(b)) - 1``)
    returns ``(y, zf)``. Without ``zi``, a long signal (2 048 samples or
    more) through a filter whose recurrence does not amplify rounding much
    is cut into 8 chunks filtered side by side, each corrected by the
    free response of the state it inherits: SciPy's numbers to ~1e-10 of
    the output's scale, not its rounding, several times faster."""
    if (zi is None and type(x) is np.ndarray and type(b) is np.ndarray and type(a) is np.ndarray
            and x.ndim == 1 and b.ndim == 1 and a.ndim == 1 and axis in (-1, 0)
            and x.dtype == np.float64 and b.dtype == np.float64 and a.dtype == np.float64
            and x.size > 0 and b.size > 0 and a.size > 0 and a[0] != 0
            and x.flags.c_contiguous and b.flags.c_contiguous and a.flags.c_contiguous):
        # The common call, one float64 signal from rest: straight to the
        # kernel (it checks the samples; the checks below all pass).
        return _native.lfilter1(b, a, x)
    b = np.atleast_1d(np.asarray(b))
    a = np.atleast_1d(np.asarray(a))
    if not (b.ndim == 1 and b.size > 0):
        raise ValueError(f"Parameter b is not a non-empty 1d array, since {b.shape=}!")
    if not (a.ndim == 1 and a.size > 0):
        raise ValueError(f"Parameter a is not a non-empty 1d array, since {a.shape=}!")
    b, a = real_float64(b, "b"), real_float64(a, "a")
    x = _x(x)
    if len(a) > 1 and a[0] == 0:
        raise ValueError("BUG: filter coefficient a[0] == 0 not supported yet")
    ax = normalize_axis(axis, x.ndim)
    k = max(len(a), len(b)) - 1
    if zi is not None:
        zi = real_float64(zi, "zi")
        want = list(x.shape)
        want[ax] = k
        if zi.shape != tuple(want):
            raise ValueError(
                f"Unexpected shape for zi: expected {tuple(want)}, found {zi.shape}."
            )
    if x.shape[ax] == 0:
        y = np.empty(x.shape)
        return y if zi is None else (y, zi.copy())
    rows, outer = to_rows(x, ax)
    if zi is None:
        y, _ = _native.lfilter(b, a, rows)
        return from_rows(y, outer, ax, x.ndim)
    zr, _ = to_rows(zi, ax)
    y, zf = _native.lfilter(b, a, rows, zr)
    return from_rows(y, outer, ax, x.ndim), from_rows(zf, outer, ax, x.ndim)


def detrend(data, axis=-1, type="linear", bp=0, overwrite_data=False):
    """Removes the least-squares line (``type='linear'``) or the mean
    (``'constant'``) along ``axis`` (``scipy.signal.detrend``). Breakpoints
    ``bp`` other than the ends raise NotImplementedError."""
    if type not in ("linear", "l", "constant", "c"):
        raise ValueError("Trend type must be 'linear' or 'constant'.")
    x = real_float64(data, "data")
    if x.ndim == 0:
        raise ValueError("data must be at least 1-D")
    ax = normalize_axis(axis, x.ndim)
    n = x.shape[ax]
    kind = "linear" if type in ("linear", "l") else "constant"
    if kind == "linear":
        bps = np.unique(np.concatenate(np.atleast_1d(0, np.asarray(bp), n)))
        if np.any(bps > n):
            raise ValueError("Breakpoints must be less than length of data along given axis.")
        if len(bps) > 2:
            raise NotImplementedError(
                f"bp={bp!r}: piecewise detrending between breakpoints is not supported "
                "by ballpass.signal"
            )
    if x.size == 0:
        if kind == "constant":
            return x.copy()
        raise ValueError("cannot detrend an empty array linearly")
    rows, outer = to_rows(x, ax)
    return from_rows(_native.detrend(rows, kind), outer, ax, x.ndim)


def decimate(x, q, n=None, ftype="iir", axis=-1, zero_phase=True):
    """Downsamples by ``q`` after an order-``n`` (default 8) Chebyshev I
    anti-alias low-pass at ``0.8 fs / (2 q)`` (``scipy.signal.decimate``
    with ``ftype='iir'``), forward-backward when ``zero_phase``."""
    x = real_float64(x, "x")
    q = operator.index(q)
    if n is not None:
        n = operator.index(n)
    if isinstance(ftype, str):
        if ftype == "fir":
            raise NotImplementedError(
                "ftype='fir': ballpass.signal decimates with the IIR (Chebyshev I) filter only"
            )
        if ftype != "iir":
            raise ValueError("invalid ftype")
    else:
        raise NotImplementedError(
            "ftype=<dlti>: ballpass.signal decimates with its Chebyshev I filter only"
        )
    order = 8 if n is None else n
    if q == 1:
        sos = cheby1(order, 0.05, 0.8, output="sos")
        return sosfiltfilt(sos, x, axis=axis) if zero_phase else sosfilt(sos, x, axis=axis)
    if q < 1:
        raise ValueError(f"the downsampling factor q must be a positive integer, got {q}")
    if x.ndim == 0:
        raise ValueError("x must be at least 1-D")
    ax = normalize_axis(axis, x.ndim)
    if zero_phase:
        edge = 3 * (2 * math.ceil(order / 2) + 1 - (0 if order % 2 == 0 else 1))
        if x.shape[ax] <= edge:
            raise ValueError(
                f"The length of the input vector x must be greater than padlen, which is {edge}."
            )
    rows, outer = to_rows(x, ax)
    y = _native.decimate(rows, q, order, bool(zero_phase))
    return from_rows(y, outer, ax, x.ndim)
