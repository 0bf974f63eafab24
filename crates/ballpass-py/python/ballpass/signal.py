"""SciPy-compatible signal processing, computed by ballpass' Rust kernels.

Swap ``from scipy import signal`` for ``from ballpass import signal`` and the
functions below take the same arguments, defaults and return values as in
SciPy 1.17, give the same numbers (to 1e-9 relative or better on the
project's SciPy fixtures, tested), and raise SciPy's exceptions for SciPy's
bad inputs. ``gradient`` is ``numpy.gradient``.

Where ballpass differs, it says so loudly, never with a different answer:

* an option ballpass does not implement (another window, ``method='direct'``,
  ``ftype='fir'``, ``analog=True``, per-sample ``find_peaks`` bounds, ...)
  raises ``NotImplementedError`` naming it;
* complex input raises ``NotImplementedError``; NaN or infinite samples raise
  ``ValueError`` (SciPy would return NaN);
* results are float64 (complex128) whatever the input dtype: lists, ints and
  float32 are cast to float64 first (SciPy keeps float32 as float32, and
  ``correlate`` of integers is integer there).

Windows: ``'hann'`` (SciPy's default ``'hann_periodic'``), ``'hamming'``,
``'boxcar'`` and their aliases, all periodic (DFT-even) as ``get_window``
makes them, or an array of window values.

Units: ``fs`` in Hz gives frequencies in Hz and densities in unit²/Hz, as in
SciPy; lags are in samples.

The computation runs with the GIL released, in the calling thread.
"""

from __future__ import annotations

import math
import operator
import warnings

import numpy as np

from . import _native
from ._arrays import from_rows, normalize_axis, real_float64, to_rows

__all__ = [
    "welch",
    "csd",
    "coherence",
    "periodogram",
    "correlate",
    "correlation_lags",
    "butter",
    "cheby1",
    "sosfilt",
    "sosfilt_zi",
    "sosfiltfilt",
    "lfilter",
    "detrend",
    "decimate",
    "find_peaks",
    "peak_prominences",
    "peak_widths",
    "freqs",
    "freqz",
    "sosfreqz",
    "freqz_sos",
    "gradient",
    "PeakPropertyWarning",
]


class PeakPropertyWarning(RuntimeWarning):
    """A peak has a prominence or width of 0 (``scipy.signal.PeakPropertyWarning``)."""

# ---------------------------------------------------------------- windows

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


# ---------------------------------------------------------------- filter design

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


# ---------------------------------------------------------------- peaks


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


# ---------------------------------------------------------------- responses


def _coefficients(c, name):
    c = np.atleast_1d(np.asarray(c))
    if np.iscomplexobj(c):
        raise NotImplementedError(
            f"complex {name} is not supported by ballpass.signal"
        )
    c = np.asarray(c, dtype=np.float64)
    if c.ndim != 1:
        raise NotImplementedError(
            f"{name} of shape {c.shape}: ballpass.signal takes one filter (1-D coefficients)"
        )
    return np.ascontiguousarray(c)


def freqs(b, a, worN=200, plot=None):
    """Frequency response ``H(j w)`` of the analog filter ``b(s) / a(s)``
    (``scipy.signal.freqs``) at the angular frequencies ``worN`` (rad/s):
    ``(w, h)``. A number of points (SciPy picks the frequencies from the
    poles and zeros) raises NotImplementedError: give the frequencies."""
    if plot is not None:
        raise NotImplementedError("plot=: ballpass.signal does not plot")
    if worN is None or isinstance(worN, (int, np.integer)):
        raise NotImplementedError(
            f"freqs(worN={worN!r}): ballpass.signal evaluates at the angular frequencies "
            "you give; pass worN as an array of rad/s"
        )
    b, a = _coefficients(b, "b"), _coefficients(a, "a")
    w = np.atleast_1d(real_float64(worN, "worN"))
    return w, _native.freqs(b, a, np.ascontiguousarray(w))


def _fs(fs):
    if fs is None:
        raise ValueError("Sampling frequency can not be none.")
    if not np.isscalar(fs):
        raise ValueError("Sampling frequency fs must be a single scalar.")
    return float(fs)


def _grid(worN, whole, fs, include_nyquist):
    """SciPy's frequency grid: (frequencies returned, same in fs units)."""
    if worN is None:
        worN = 512
    if isinstance(worN, (int, np.integer)) and not isinstance(worN, bool):
        n = operator.index(worN)
        if n < 0:
            raise ValueError(f"worN must be nonnegative, got {n}")
        last = 2 * np.pi if whole else np.pi
        w = np.linspace(0, last, n, endpoint=include_nyquist and not whole)
        return w * (fs / (2 * np.pi))
    if isinstance(worN, complex):
        worN = worN.real
    w = np.atleast_1d(real_float64(worN, "worN"))
    w = 2 * np.pi * w / fs
    return w * (fs / (2 * np.pi))


def freqz(b, a=1, worN=512, whole=False, plot=None, fs=2 * np.pi, include_nyquist=False):
    """Frequency response of the digital filter ``b(z) / a(z)``
    (``scipy.signal.freqz``): ``(w, h)``, ``w`` in the units of ``fs``
    (rad/sample by default, Hz with ``fs`` in Hz)."""
    if plot is not None:
        raise NotImplementedError("plot=: ballpass.signal does not plot")
    b, a = _coefficients(b, "b"), _coefficients(a, "a")
    fs = _fs(fs)
    w = _grid(worN, whole, fs, include_nyquist)
    if b.size == 0:
        return w, np.zeros(w.shape, dtype=complex)
    return w, _native.freqz(b, a, np.ascontiguousarray(w), fs)


def freqz_sos(sos, worN=512, whole=False, fs=2 * np.pi):
    """Frequency response of second-order sections, the product of the
    sections' (``scipy.signal.freqz_sos``): ``(w, h)`` as :func:`freqz`."""
    fs = _fs(fs)
    sos = _sos(sos)
    if sos.shape[0] == 0:
        raise ValueError("Cannot compute frequencies with no sections")
    w = _grid(worN, whole, fs, False)
    return w, _native.sosfreqz(sos, np.ascontiguousarray(w), fs)


def sosfreqz(sos, worN=512, whole=False, fs=2 * np.pi):
    """``scipy.signal.sosfreqz``, the former name of :func:`freqz_sos`."""
    return freqz_sos(sos, worN=worN, whole=whole, fs=fs)


# ---------------------------------------------------------------- gradient


def gradient(f, *varargs, axis=None, edge_order=1):
    """``numpy.gradient``: second-order central differences inside and
    one-sided differences (``edge_order`` 1 or 2) at the ends, along each
    axis (or ``axis``). ``varargs``: one scalar step for all axes, or one
    per axis (a scalar step or the sample coordinates). Units: those of
    ``f`` per unit of the spacing (mm and s give mm/s)."""
    if (type(f) is np.ndarray and f.ndim == 1 and f.dtype == np.float64
            and axis in (None, 0, -1) and edge_order in (1, 2)
            and (not varargs or (len(varargs) == 1
                                 and (type(varargs[0]) in (float, int) or np.ndim(varargs[0]) == 0)))):
        # The common call, numpy.gradient(f, dt) of one signal: straight to
        # the kernel (it checks the length and the samples).
        if f.shape[0] < edge_order + 1:
            raise ValueError(
                "Shape of array too small to calculate a numerical gradient, "
                "at least (edge_order + 1) elements are required."
            )
        h = float(varargs[0]) if varargs else 1.0
        return _native.gradient1(f if f.flags.c_contiguous else np.ascontiguousarray(f), h,
                                 edge_order)
    f = real_float64(f, "f")
    n = f.ndim
    if axis is None:
        axes = tuple(range(n))
    else:
        axes = tuple(normalize_axis(a, n) for a in np.atleast_1d(axis))
        if len(set(axes)) != len(axes):
            raise ValueError("duplicate value in 'axis'")
    spacing = []
    if len(varargs) == 0:
        spacing = [1.0] * len(axes)
    elif len(varargs) == 1 and np.ndim(varargs[0]) == 0:
        spacing = [varargs[0]] * len(axes)
    elif len(varargs) == len(axes):
        for ax, d in zip(axes, varargs):
            d = np.asarray(d)
            if d.ndim == 0:
                spacing.append(d)
                continue
            if d.ndim != 1:
                raise ValueError("distances must be either scalars or 1d")
            if len(d) != f.shape[ax]:
                raise ValueError(
                    "when 1d, distances must match the length of the corresponding dimension"
                )
            spacing.append(real_float64(d, "coordinates"))
    else:
        raise TypeError("invalid number of arguments")
    if edge_order > 2:
        raise ValueError("'edge_order' greater than 2 not supported")
    out = []
    for ax, d in zip(axes, spacing):
        if f.shape[ax] < edge_order + 1:
            raise ValueError(
                "Shape of array too small to calculate a numerical gradient, "
                "at least (edge_order + 1) elements are required."
            )
        rows, outer = to_rows(f, ax)
        if np.ndim(d) == 0:
            g = _native.gradient(rows, float(d), None, int(edge_order))
        else:
            g = _native.gradient(rows, 1.0, np.ascontiguousarray(d), int(edge_order))
        out.append(from_rows(g, outer, ax, n))
    return out[0] if len(axes) == 1 else tuple(out)
