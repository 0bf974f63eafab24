"""Result objects: the library's serde output as attributes, series as numpy
arrays, tables as columns.

A result holds the JSON value the command-line tool writes for the same
work (``to_dict()`` returns it, equal to the file), so its fields follow the
library's result structs without a list of them here: every key of the JSON
is an attribute, numeric lists are numpy arrays, nested objects are
results again. Tables (the CSV files: correlations, spectra, passages, ...)
are :class:`Table` objects of numpy columns.
"""

from __future__ import annotations

import copy
import json
from typing import Any, Iterator, Mapping

import numpy as np


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _wrap(value):
    """A JSON value as users get it: dicts as Result, numeric lists (None as
    NaN) as numpy arrays, lists of dicts as lists of Result."""
    if isinstance(value, dict):
        return Result(value)
    if isinstance(value, list) and value:
        if all(_is_number(v) or v is None for v in value) and any(_is_number(v) for v in value):
            if all(isinstance(v, int) and not isinstance(v, bool) for v in value):
                return np.asarray(value, dtype=np.int64)
            return np.asarray([np.nan if v is None else v for v in value], dtype=np.float64)
        return [_wrap(v) for v in value]
    return value


class Table(Mapping[str, Any]):
    """Named columns of equal length (numpy arrays; text columns as lists),
    in the CSV file's order. ``t["col"]`` or ``t.col``; ``to_pandas()``."""

    __slots__ = ("_cols",)

    def __init__(self, columns: Mapping[str, Any]):
        object.__setattr__(self, "_cols", dict(columns))

    def __getitem__(self, key: str):
        return self._cols[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._cols)

    def __len__(self) -> int:
        return len(self._cols)

    def __getattr__(self, name: str):
        try:
            return self._cols[name]
        except KeyError:
            raise AttributeError(
                f"table has no column {name!r}; columns: {', '.join(self._cols)}"
            ) from None

    def __dir__(self):
        return list(super().__dir__()) + list(self._cols)

    @property
    def columns(self) -> list[str]:
        """Column names, in order."""
        return list(self._cols)

    @property
    def rows(self) -> int:
        """Number of rows."""
        first = next(iter(self._cols.values()), None)
        return 0 if first is None else len(first)

    def to_dict(self) -> dict[str, list]:
        """The columns as lists."""
        return {k: (v.tolist() if isinstance(v, np.ndarray) else list(v)) for k, v in self._cols.items()}

    def to_pandas(self):
        """The table as a pandas DataFrame (needs pandas)."""
        import pandas as pd

        return pd.DataFrame(self._cols)

    def __repr__(self) -> str:
        return f"Table({self.rows} rows: {', '.join(self._cols)})"


class Result:
    """A ballpass result: every key of its JSON is an attribute (numeric
    lists as numpy arrays, objects as results), ``to_dict()`` is the JSON
    value itself (what the command line writes), and tables are attributes
    too (listed in ``tables``)."""

    __slots__ = ("_data", "_tables", "_cache", "_kind")

    def __init__(self, data: dict, tables: Mapping[str, Table] | None = None, kind: str | None = None):
        object.__setattr__(self, "_data", data)
        object.__setattr__(self, "_tables", dict(tables or {}))
        object.__setattr__(self, "_cache", {})
        object.__setattr__(self, "_kind", kind)

    def __getattr__(self, name: str):
        tables = object.__getattribute__(self, "_tables")
        if name in tables:
            return tables[name]
        data = object.__getattribute__(self, "_data")
        if name not in data:
            raise AttributeError(
                f"{type(self).__name__} has no field {name!r}; fields: {', '.join(data)}"
            )
        cache = object.__getattribute__(self, "_cache")
        if name not in cache:
            cache[name] = _wrap(data[name])
        return cache[name]

    def __setattr__(self, name, value):
        raise AttributeError("ballpass results are read-only; copy to_dict() to change one")

    def __getitem__(self, key: str):
        return self.__getattr__(key)

    def __contains__(self, key: str) -> bool:
        return key in self._data or key in self._tables

    def __dir__(self):
        return list(super().__dir__()) + list(self._data) + list(self._tables)

    def keys(self) -> list[str]:
        """The JSON's keys."""
        return list(self._data)

    @property
    def tables(self) -> dict[str, Table]:
        """The result's tables (the CSV files), by name."""
        return dict(self._tables)

    def to_dict(self) -> dict:
        """The result as the command line's JSON (a deep copy)."""
        return copy.deepcopy(self._data)

    def to_json(self, indent: int | None = 2) -> str:
        """The JSON text (as the command line writes it, NaN as null)."""
        return json.dumps(self._data, indent=indent, ensure_ascii=False)

    def __eq__(self, other):
        if isinstance(other, Result):
            return self._data == other._data
        return NotImplemented

    __hash__ = None

    def __repr__(self) -> str:
        kind = self._kind or type(self).__name__
        shown = []
        for k, v in self._data.items():
            if isinstance(v, (str, int, float, bool)) or v is None:
                shown.append(f"{k}={v!r}")
            if len(shown) == 6:
                break
        more = [k for k in self._data if not isinstance(self._data[k], (str, int, float, bool)) and self._data[k] is not None]
        tail = f", ... ({len(self._data)} fields" + (f"; tables {', '.join(self._tables)}" if self._tables else "") + ")"
        if not more and len(shown) == len(self._data):
            tail = ""
        return f"{kind}({', '.join(shown)}{tail})"


class RecordResult(Result):
    """One campaign record's result (a row of ``records.csv``, an entry of a
    campaign JSON's ``record_results``) with its friction spectrum
    (``friction_psd_freq_hz`` in Hz, ``friction_psd`` in N²/Hz) and the
    friction height of each ball-pass period (``sticking_heights_n``, N; the
    diagnosis pools them per bearing, the JSON leaves them out). Picklable:
    it travels between processes (Spark executors) whole; a result rebuilt
    from its parts needs all four."""

    __slots__ = ()

    def __init__(self, data: dict, freq_hz: np.ndarray, psd: np.ndarray,
                 sticking_heights_n: np.ndarray | None = None):
        heights = np.zeros(0) if sticking_heights_n is None else sticking_heights_n
        super().__init__(
            data,
            {"friction_psd_freq_hz": np.asarray(freq_hz), "friction_psd": np.asarray(psd),
             "sticking_heights_n": np.asarray(heights, dtype=np.float64)},
            "RecordResult",
        )

    def _state(self):
        return (json.dumps(self._data), self._tables["friction_psd_freq_hz"],
                self._tables["friction_psd"], self._tables["sticking_heights_n"])

    def __reduce__(self):
        return (_record_from_state, self._state())


def _record_from_state(text: str, freq_hz, psd, heights=None) -> RecordResult:
    return RecordResult(json.loads(text), np.asarray(freq_hz), np.asarray(psd),
                        None if heights is None else np.asarray(heights))
