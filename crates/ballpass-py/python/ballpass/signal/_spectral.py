"""Windows, spectra (``welch``, ``csd``, ``coherence``, ``periodogram``) and
``correlate`` / ``correlation_lags`` of ``ballpass.signal``."""

from __future__ import annotations

import operator
import warnings

import numpy as np

from .. import _native
from .._arrays import from_rows, normalize_axis, real_float64, to_rows


_WINDOWS = {
    "hann": "hann",
    "han": "hann",
    "hamming": "hamming",
    "hamm": "hamming",
    "ham": "hamming",
    "boxcar": "boxcar",
    "box": "boxcar",
    "ones": "boxcar",
    "rect": "boxcar",
    "rectangular": "boxcar",
}

# Windows SciPy's get_window knows but ballpass does not compute.
_SCIPY_ONLY_WINDOWS = {
    "barthann", "brthan", "bth", "bartlett", "bart", "brt", "blackman", "black",
    "blk", "blackmanharris", "blackharr", "bkh", "bohman", "bman", "bmn",
    "chebwin", "cheb", "cosine", "halfcosine", "dpss", "exponential", "poisson",
    "flattop", "flat", "flt", "gaussian", "gauss", "gss", "general cosine",
    "general_cosine", "general gaussian", "general_gaussian", "general gauss",
    "general_gauss", "ggs", "general hamming", "general_hamming", "kaiser", "ksr",
    "kaiser bessel derived", "kaiser_bessel_derived", "kbd", "lanczos", "sinc",
    "nuttall", "nutl", "nut", "parzen", "parz", "par", "taylor", "taylorwin",
    "triangle", "triang", "tri", "tukey", "tuk",
}

_SUPPORTED_WINDOWS = "'hann', 'hamming', 'boxcar' (and their aliases) or an array of values"


def _window(window):
    """A window as the Rust kernels take it: a name or a float64 array."""
    if isinstance(window, tuple):
        if len(window) == 1 and isinstance(window[0], str):
            window = window[0]
        else:
            raise NotImplementedError(
                f"window={window!r}: windows with parameters are not supported by "
                f"ballpass.signal; use {_SUPPORTED_WINDOWS}"
            )
    if isinstance(window, str):
        name = window.lower()
        periodic = True
        if name.endswith("_periodic"):
            name = name[: -len("_periodic")]
        elif name.endswith("_symmetric"):
            name = name[: -len("_symmetric")]
            periodic = False
        if name in _WINDOWS:
            kind = _WINDOWS[name]
            if not periodic and kind != "boxcar":
                raise NotImplementedError(
                    f"window={window!r}: symmetric windows are not supported by "
                    "ballpass.signal (spectral estimates use the periodic form)"
                )
            return kind
        if name in _SCIPY_ONLY_WINDOWS:
            raise NotImplementedError(
                f"window={window!r} is not supported by ballpass.signal; use {_SUPPORTED_WINDOWS}"
            )
        raise ValueError(f"Invalid window name {window!r} in parameter {window=}!")
    if np.ndim(window) == 0:
        raise NotImplementedError(
            f"window={window!r} (a Kaiser beta) is not supported by ballpass.signal; "
            f"use {_SUPPORTED_WINDOWS}"
        )
    return real_float64(window, "window")


def _detrend_name(detrend):
    if detrend is False or detrend is None:
        return "none"
    if detrend in ("constant", "linear"):
        return detrend
    if callable(detrend):
        raise NotImplementedError(
            "detrend=<function>: only 'constant', 'linear' or False are supported by ballpass.signal"
        )
    raise ValueError(f"Unknown detrend type {detrend!r}; expected 'constant', 'linear' or False")


# ---------------------------------------------------------------- spectra


def _segments(window, nperseg, noverlap, nfft, n):
    """SciPy's csd argument triage: (window, nperseg, noverlap, nfft)."""
    if isinstance(window, (str, tuple)):
        win = _window(window)
        nperseg = int(nperseg) if nperseg is not None else 256
        if nperseg < 1:
            raise ValueError(f"Parameter {nperseg=} is not a positive integer!")
        if n < nperseg:
            warnings.warn(
                f"{nperseg=} is greater than signal length max(len(x), len(y)) = {n}, "
                f"using nperseg = {n}",
                stacklevel=4,
            )
            nperseg = n
    else:
        win = _window(window)
        if win.ndim != 1:
            raise ValueError("window must be 1-D")
        if nperseg is None:
            nperseg = len(win)
        if nperseg != len(win):
            raise ValueError(f"{nperseg=} does not equal {len(win)=}")
    nfft = int(nfft) if nfft is not None else nperseg
    if nfft < nperseg:
        raise ValueError(f"{nfft=} must be greater than or equal to {nperseg=}!")
    noverlap = int(noverlap) if noverlap is not None else nperseg // 2
    if noverlap >= nperseg:
        raise ValueError(f"{noverlap=} must be less than {nperseg=}!")
    return win, int(nperseg), noverlap, nfft


def _check_scaling_average(scaling, average, n, nperseg, noverlap):
    if scaling not in ("spectrum", "density"):
        raise ValueError(
            f"Parameter {scaling=} not in {{'spectrum': 'magnitude', 'density': 'psd'}}!"
        )
    if average not in ("mean", "median"):
        # SciPy only looks at `average` when there is more than one segment.
        if (n - noverlap) // (nperseg - noverlap) > 1:
            raise ValueError(f"Parameter {average=} must be 'median' or 'mean'!")
        average = "mean"
    return average


def _spectral(x, y, fs, window, nperseg, noverlap, nfft, detrend, return_onesided,
              scaling, axis, average):
    """csd (y given) or welch (y None) along `axis`, as SciPy 1.17 does them."""
    x = real_float64(x, "x")
    same = y is None
    if not same:
        y = real_float64(y, "y")
    axis = int(axis)
    if x.ndim == 0 or (not same and y.ndim == 0):
        raise ValueError("x and y must be at least 1-D")
    ax = normalize_axis(axis, x.ndim)
    if same:
        if x.size == 0:
            return np.empty(x.shape), np.empty(x.shape)
        n = x.shape[ax]
    else:
        ay = normalize_axis(axis, y.ndim)
        x_outer = list(np.moveaxis(x, ax, -1).shape[:-1])
        y_outer = list(np.moveaxis(y, ay, -1).shape[:-1])
        try:
            outer = np.broadcast_shapes(tuple(x_outer), tuple(y_outer))
        except ValueError as e:
            raise ValueError("x and y cannot be broadcast together.") from e
        if x.size == 0 or y.size == 0:
            out_shape = outer + (min(x.shape[ax], y.shape[ay]),)
            empty = np.moveaxis(np.empty(out_shape), -1, axis)
            return empty, empty
        n = max(x.shape[ax], y.shape[ay])
    win, nperseg, noverlap, nfft = _segments(window, nperseg, noverlap, nfft, n)
    detrend = _detrend_name(detrend)
    average = _check_scaling_average(scaling, average, n, nperseg, noverlap)
    if same:
        rows, outer = to_rows(x, ax)
        f, p = _native.welch(rows, float(fs), win, nperseg, noverlap, nfft, detrend,
                             scaling, bool(return_onesided), average)
        return f, from_rows(p, outer, ax, x.ndim)
    xm = np.moveaxis(x, ax, -1)
    ym = np.moveaxis(y, ay, -1)
    xb = np.broadcast_to(xm, outer + xm.shape[-1:])
    yb = np.broadcast_to(ym, outer + ym.shape[-1:])
    xr = np.ascontiguousarray(xb.reshape(-1, xb.shape[-1]))
    yr = np.ascontiguousarray(yb.reshape(-1, yb.shape[-1]))
    f, p = _native.csd(xr, yr, float(fs), win, nperseg, noverlap, nfft, detrend,
                       scaling, bool(return_onesided), average)
    ndim = len(outer) + 1
    return f, from_rows(p, outer, axis if axis >= 0 else axis + ndim, ndim)


def welch(x, fs=1.0, window="hann_periodic", nperseg=None, noverlap=None, nfft=None,
          detrend="constant", return_onesided=True, scaling="density", axis=-1,
          average="mean"):
    """Power spectral density by Welch's method (``scipy.signal.welch``).

    Segments of ``nperseg`` samples (default 256, at most the signal length)
    overlapping by ``noverlap`` (default half), each detrended and windowed
    (periodic Hann by default), ``|FFT|²`` averaged (``'mean'`` or
    ``'median'``). Returns ``(f, Pxx)``: frequencies in Hz (the units of
    ``fs``) and the density in unit²/Hz (``scaling='density'``) or the power
    spectrum in unit² (``'spectrum'``).
    """
    return _spectral(x, None, fs, window, nperseg, noverlap, nfft, detrend,
                     return_onesided, scaling, axis, average)


def csd(x, y, fs=1.0, window="hann_periodic", nperseg=None, noverlap=None, nfft=None,
        detrend="constant", return_onesided=True, scaling="density", axis=-1,
        average="mean"):
    """Cross spectral density ``Pxy = conj(X) Y`` by Welch's method
    (``scipy.signal.csd``); the shorter signal is zero-padded.

    Returns ``(f, Pxy)``: Hz and complex unit_x·unit_y/Hz. If y is x delayed
    by d samples, ``angle(Pxy) = -2 pi f d / fs``.
    """
    if y is x:
        f, p = welch(x, fs, window, nperseg, noverlap, nfft, detrend, return_onesided,
                     scaling, axis, average)
        return f, p
    return _spectral(x, y, fs, window, nperseg, noverlap, nfft, detrend,
                     return_onesided, scaling, axis, average)


def coherence(x, y, fs=1.0, window="hann_periodic", nperseg=None, noverlap=None,
              nfft=None, detrend="constant", axis=-1):
    """Magnitude-squared coherence ``|Pxy|² / (Pxx Pyy)``
    (``scipy.signal.coherence``): ``(f, Cxy)``, Hz and values in [0, 1]."""
    x = real_float64(x, "x")
    y = real_float64(y, "y")
    if x.ndim == 0 or y.ndim == 0:
        raise ValueError("x and y must be at least 1-D")
    if x.size == 0 or y.size == 0:
        return _spectral(x, y, fs, window, nperseg, noverlap, nfft, detrend, True,
                         "density", axis, "mean")
    ax, ay = normalize_axis(axis, x.ndim), normalize_axis(axis, y.ndim)
    if x.shape[ax] != y.shape[ay]:
        raise NotImplementedError(
            "coherence of x and y of different lengths is not supported by ballpass.signal"
        )
    n = x.shape[ax]
    win, nperseg, noverlap, nfft = _segments(window, nperseg, noverlap, nfft, n)
    detrend = _detrend_name(detrend)
    xm, ym = np.moveaxis(x, ax, -1), np.moveaxis(y, ay, -1)
    try:
        outer = np.broadcast_shapes(xm.shape[:-1], ym.shape[:-1])
    except ValueError as e:
        raise ValueError("x and y cannot be broadcast together.") from e
    xr = np.ascontiguousarray(np.broadcast_to(xm, outer + (n,)).reshape(-1, n))
    yr = np.ascontiguousarray(np.broadcast_to(ym, outer + (n,)).reshape(-1, n))
    f, c = _native.coherence(xr, yr, float(fs), win, nperseg, noverlap, nfft, detrend)
    ndim = len(outer) + 1
    return f, from_rows(c, outer, axis if axis >= 0 else axis + ndim, ndim)


def periodogram(x, fs=1.0, window="boxcar", nfft=None, detrend="constant",
                return_onesided=True, scaling="density", axis=-1):
    """Power spectral density from one windowed segment
    (``scipy.signal.periodogram``): ``(f, Pxx)`` in Hz and unit²/Hz."""
    x = real_float64(x, "x")
    if x.size == 0:
        return np.empty(x.shape), np.empty(x.shape)
    if x.ndim == 0:
        raise ValueError("x must be at least 1-D")
    if window is None:
        window = "boxcar"
    ax = normalize_axis(axis, x.ndim)
    n = x.shape[ax]
    nperseg = n if nfft is None or nfft >= n else int(nfft)
    win = _window(window)
    if isinstance(win, np.ndarray) and win.size != nperseg:
        raise ValueError(
            "the size of the window must be the same size of the input on the specified axis"
        )
    if nfft is not None and int(nfft) < 1:
        raise ValueError(f"Parameter nperseg={int(nfft)} is not a positive integer!")
    if scaling not in ("spectrum", "density"):
        raise ValueError(
            f"Parameter {scaling=} not in {{'spectrum': 'magnitude', 'density': 'psd'}}!"
        )
    detrend = _detrend_name(detrend)
    rows, outer = to_rows(x, ax)
    f, p = _native.periodogram(rows, float(fs), win, None if nfft is None else int(nfft),
                               detrend, scaling, bool(return_onesided))
    return f, from_rows(p, outer, ax, x.ndim)


# ---------------------------------------------------------------- correlation


def _centered(full, newlen):
    start = (len(full) - newlen) // 2
    return full[start:start + newlen]


def correlate(in1, in2, mode="full", method="auto"):
    """Cross-correlation ``z[k] = sum_n in1[n + k] in2[n]`` of two 1-D arrays
    (``scipy.signal.correlate``), by FFT. ``mode``: ``'full'`` (lags
    ``-(len(in2)-1) .. len(in1)-1``, see ``correlation_lags``), ``'same'``
    or ``'valid'``. Unnormalised; equal to MATLAB ``xcorr(in1, in2)``."""
    if mode not in ("full", "same", "valid"):
        raise ValueError("Acceptable mode flags are 'valid', 'same', or 'full'.")
    if method not in ("auto", "fft", "direct"):
        raise ValueError("Acceptable method flags are 'auto', 'direct', or 'fft'.")
    if method == "direct":
        raise NotImplementedError(
            "method='direct': ballpass.signal correlates by FFT; use method='fft' or 'auto'"
        )
    a = real_float64(in1, "in1")
    b = real_float64(in2, "in2")
    if a.ndim != b.ndim:
        raise ValueError("in1 and in2 should have the same dimensionality")
    if a.ndim != 1:
        raise NotImplementedError(
            f"correlate of {a.ndim}-D arrays is not supported by ballpass.signal (1-D only)"
        )
    if a.size == 0:
        raise ValueError("in1 cannot be empty")
    if b.size == 0:
        raise ValueError("in2 cannot be empty")
    full = _native.correlate(np.ascontiguousarray(a), np.ascontiguousarray(b))
    if mode == "full":
        return full
    if mode == "same":
        return _centered(full, len(a)).copy()
    return _centered(full, abs(len(a) - len(b)) + 1).copy()


def correlation_lags(in1_len, in2_len, mode="full"):
    """Lags (samples) of ``correlate(in1, in2, mode)``
    (``scipy.signal.correlation_lags``)."""
    if mode == "full" and type(in1_len) is int and type(in2_len) is int and in1_len > 0 \
            and in2_len > 0:
        # The common call: straight to the kernel, which writes the range.
        return _native.correlation_lags(in1_len, in2_len)
    if mode not in ("full", "same", "valid"):
        raise ValueError(f"Mode {mode} is invalid")
    n1, n2 = operator.index(in1_len), operator.index(in2_len)
    if mode == "valid":
        bound = n1 - n2
        return np.arange(bound + 1) if bound >= 0 else np.arange(bound, 1)
    if n1 <= 0 or n2 <= 0:
        lags = np.arange(-n2 + 1, n1)
    else:
        lags = _native.correlation_lags(n1, n2)
    if mode == "full":
        return lags
    mid = lags.size // 2
    bound = n1 // 2
    if n1 % 2 == 0:
        return lags[mid - bound:mid + bound]
    return lags[mid - bound:mid + bound + 1]
