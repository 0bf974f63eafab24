"""Frequency responses (``freqs``, ``freqz``, ``sosfreqz``) and numpy's
``gradient`` of ``ballpass.signal``."""

from __future__ import annotations

import operator

import numpy as np

from .. import _native
from .._arrays import from_rows, normalize_axis, real_float64, to_rows
from ._filters import _sos



_F64 = np.dtype(np.float64)


def _plain(*arrays):
    """Whether every argument is a 1-D C-contiguous float64 ndarray (not a
    subclass): what the slow path's conversions would return unchanged, so
    that the common call goes straight to the kernel (about 2.5 us less per
    call)."""
    for x in arrays:
        if not (type(x) is np.ndarray and x.dtype is _F64 and x.ndim == 1
                and x.flags.c_contiguous):
            return False
    return True


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
    if plot is None and _plain(b, a, worN):
        # The common call: the conversions below would return these arrays.
        return worN, _native.freqs(b, a, worN)
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
    f = _given(worN)
    w = 2 * np.pi * f / fs
    return w * (fs / (2 * np.pi))


def _given(worN):
    """An array `worN` (frequencies in the units of fs) as float64."""
    if isinstance(worN, complex):
        worN = worN.real
    return np.ascontiguousarray(np.atleast_1d(real_float64(worN, "worN")))


def _counted(worN):
    """Whether `worN` is a number of points (SciPy's grid), not frequencies."""
    return worN is None or (isinstance(worN, (int, np.integer)) and not isinstance(worN, bool))


def freqz(b, a=1, worN=512, whole=False, plot=None, fs=2 * np.pi, include_nyquist=False):
    """Frequency response of the digital filter ``b(z) / a(z)``
    (``scipy.signal.freqz``): ``(w, h)``, ``w`` in the units of ``fs``
    (rad/sample by default, Hz with ``fs`` in Hz)."""
    if plot is None and type(fs) is float and _plain(b, a, worN) and b.size > 0:
        # The common call (frequencies given as an array, fs a float): the
        # conversions below would return these arguments unchanged.
        return _native.freqz_grid(b, a, worN, fs)
    if plot is not None:
        raise NotImplementedError("plot=: ballpass.signal does not plot")
    b, a = _coefficients(b, "b"), _coefficients(a, "a")
    fs = _fs(fs)
    if b.size > 0 and not _counted(worN):
        # Frequencies given: SciPy's returned grid and H at them in one call.
        return _native.freqz_grid(b, a, _given(worN), fs)
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
    if not _counted(worN):
        return _native.sosfreqz_grid(sos, _given(worN), fs)
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
    if type(f) is np.ndarray and axis is None and edge_order == 1 and len(varargs) == 1:
        # numpy.gradient(f, dt) of one float64 signal: the native side
        # checks the array and the step (None: anything else).
        g = _native.gradient_plain(f, varargs[0])
        if g is not None:
            return g
    if (type(f) is np.ndarray and f.ndim == 1 and f.dtype is _F64
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
