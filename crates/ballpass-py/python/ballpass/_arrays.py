"""Array plumbing shared by the Python modules: inputs as float64, an axis
moved last and the other axes flattened into rows, and back."""

from __future__ import annotations

import numpy as np


def real_float64(x, name: str = "x") -> np.ndarray:
    """`x` as a float64 array (lists, ints and float32 are cast); complex
    input is a NotImplementedError naming `name`."""
    a = np.asarray(x)
    if np.iscomplexobj(a):
        raise NotImplementedError(
            f"ballpass.signal takes real {name}; complex input is not supported"
        )
    if a.dtype == object:
        a = a.astype(np.float64)
    return np.asarray(a, dtype=np.float64)


def normalize_axis(axis, ndim: int) -> int:
    """`axis` as a non-negative index, with NumPy's AxisError when out of range."""
    axis = int(axis)
    if not -ndim <= axis < ndim:
        raise np.exceptions.AxisError(axis, ndim)
    return axis % ndim


def to_rows(a: np.ndarray, axis: int) -> tuple[np.ndarray, tuple[int, ...]]:
    """`a` with `axis` moved last and the other axes flattened: a C-contiguous
    2-D array of rows, and the shape of the other axes."""
    if axis == a.ndim - 1 and a.flags.c_contiguous:
        return a.reshape(-1, a.shape[-1]), a.shape[:-1]
    moved = np.moveaxis(a, axis, -1)
    outer = moved.shape[:-1]
    return np.ascontiguousarray(moved.reshape(-1, moved.shape[-1])), outer


def from_rows(rows: np.ndarray, outer: tuple[int, ...], axis: int, ndim: int) -> np.ndarray:
    """The inverse of `to_rows` for rows of any length: the row axis goes
    back to `axis` of an array of `ndim` dimensions."""
    out = rows.reshape(outer + rows.shape[-1:])
    if axis in (-1, ndim - 1):
        return out
    return np.moveaxis(out, -1, axis if axis >= 0 else axis + ndim)
