"""ballpass: ball-pass disturbances of linear ball bearings, from Python.

The same computations as the ``ballpass`` command-line tool, on numpy arrays
and in one process:

* :class:`Recording` (from arrays, :func:`load` or :func:`simulate`) is the
  one way data enters an analysis;
* :func:`predict`, :func:`analyze`, :func:`passages`, :func:`sweep`,
  :func:`diagnose` and the models in :mod:`ballpass.model` return result
  objects whose ``to_dict()`` equals the command line's JSON for the same
  input, with numpy arrays for series and tables;
* :func:`process_record` and :func:`diagnose_records` split a diagnosis into
  per-record work and a batch step, for fleets on many machines
  (``examples/spark_fleet.py``);
* :mod:`ballpass.signal` is a drop-in for the SciPy functions ballpass
  matches.

Units are in the names (``fs_hz``, ``velocity_mm_s``, ``friction_n``). The
computation runs with the GIL released; parallel work (repeats, campaigns)
runs in the pool of :func:`threads` or ``threads=``, else in one thread per
core (``RAYON_NUM_THREADS`` sets that).
"""

from __future__ import annotations

import contextlib
import contextvars
import json
import os
import warnings
from typing import Iterable, Iterator, Sequence

import numpy as np

from . import _native
from ._native import Recording, ThreadPool
from ._results import RecordResult, Result, Table

__version__: str = _native.__version__

__all__ = [
    "Recording",
    "ThreadPool",
    "Result",
    "RecordResult",
    "Table",
    "BallpassWarning",
    "threads",
    "load",
    "simulate",
    "predict",
    "analyze",
    "passages",
    "compensate",
    "read_manifest",
    "select",
    "sweep",
    "diagnose",
    "process_record",
    "diagnose_records",
    "model",
    "signal",
]


class BallpassWarning(UserWarning):
    """What an analysis wants its user to know about the numbers (the
    command line prints these as ``warning: ...``)."""


# ---------------------------------------------------------------- threads

_POOL: contextvars.ContextVar[ThreadPool | None] = contextvars.ContextVar(
    "ballpass_pool", default=None
)


@contextlib.contextmanager
def threads(n: int | ThreadPool) -> Iterator[ThreadPool]:
    """Runs ballpass' parallel work inside the block in ``n`` worker threads
    (or the given pool), e.g. ``with ballpass.threads(1): ...`` in each of
    many worker processes so that they do not oversubscribe the machine.
    Context-local (threads and asyncio tasks each see their own setting);
    nothing global changes."""
    pool = n if isinstance(n, ThreadPool) else ThreadPool(int(n))
    token = _POOL.set(pool)
    try:
        yield pool
    finally:
        _POOL.reset(token)


def _pool(n):
    if n is None:
        return _POOL.get()
    if isinstance(n, ThreadPool):
        return n
    return ThreadPool(int(n))


# ---------------------------------------------------------------- helpers

_LOAD_KEYS = (
    "profile", "format", "delimiter", "fs_hz", "time_col", "ignore_time",
    "friction_col", "position_col", "optical_col", "friction_scale",
    "friction_offset", "position_scale", "position_offset", "optical_scale",
    "optical_offset", "velocity_mm_s", "test_id", "min_periods", "fs_from",
    "time_unit", "decimal_comma", "skip_lines", "fill_gaps_s", "bearing",
    "ball_diameter_mm", "free_space_mm", "balls_in_race",
)


def _load_json(options: dict) -> str | None:
    unknown = sorted(set(options) - set(_LOAD_KEYS))
    if unknown:
        raise TypeError(
            f"unexpected load option(s) {', '.join(unknown)}; expected any of {', '.join(_LOAD_KEYS)}"
        )
    given = {k: (os.fspath(v) if k == "profile" else v) for k, v in options.items() if v is not None}
    return json.dumps(given) if given else None


def _bearing_json(bearing, ball_diameter_mm, free_space_mm, balls_in_race) -> str | None:
    given = {
        k: v
        for k, v in (
            ("bearing", bearing),
            ("ball_diameter_mm", ball_diameter_mm),
            ("free_space_mm", free_space_mm),
            ("balls_in_race", balls_in_race),
        )
        if v is not None
    }
    return json.dumps(given) if given else None


def _settings_json(settings: dict | None, overrides: dict) -> str | None:
    merged = dict(settings or {})
    merged.update({k: v for k, v in overrides.items() if v is not None})
    return json.dumps(merged) if merged else None


def _window(window) -> str | None:
    """A time window as the command line's ``--window T0:T1``: ``(t0, t1)``
    in seconds on the records' time axis (``None`` leaves an end open), or
    that text itself."""
    if window is None or isinstance(window, str):
        return window
    try:
        t0, t1 = window
    except (TypeError, ValueError):
        raise ValueError(f"window: expected (t0, t1) in seconds or 'T0:T1', got {window!r}") from None
    ends = ["" if t is None else repr(float(t)) for t in (t0, t1)]
    return f"{ends[0]}:{ends[1]}"


def _warn(data: dict) -> None:
    for w in data.get("warnings", ()):
        warnings.warn(w, BallpassWarning, stacklevel=3)


def _records_table(items: list) -> Table:
    """The scalar numeric fields of a list of dicts as a table."""
    if not items:
        return Table({})
    keys = [
        k for k, v in items[0].items()
        if (isinstance(v, (int, float)) and not isinstance(v, bool)) or v is None
    ]
    cols = {}
    for k in keys:
        vals = [it.get(k) for it in items]
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) or v is None for v in vals):
            cols[k] = np.asarray([np.nan if v is None else v for v in vals], dtype=np.float64)
    return Table(cols)


def _as_recordings(recordings, load_options: dict) -> list[Recording]:
    if isinstance(recordings, (Recording, str, os.PathLike)):
        recordings = [recordings]
    out = []
    for r in recordings:
        out.append(r if isinstance(r, Recording) else load(r, **load_options))
    if not out:
        raise ValueError("no recordings given")
    return out


# ---------------------------------------------------------------- recordings


def load(path: str | os.PathLike, *, profile=None, format=None, delimiter=None,
         fs_hz=None, time_col=None, ignore_time=False, friction_col=None,
         position_col=None, optical_col=None, friction_scale=None,
         friction_offset=None, position_scale=None, position_offset=None,
         optical_scale=None, optical_offset=None, velocity_mm_s=None, test_id=None,
         min_periods=None, fs_from=None, time_unit=None, decimal_comma=False,
         skip_lines=None, fill_gaps_s=None, bearing=None,
         ball_diameter_mm=None, free_space_mm=None, balls_in_race=None) -> Recording:
    """Reads one recording file (CSV/TSV, MATLAB .mat v5/v7/v7.3, NI .tdms,
    MDF .mf4; ``FILE#GROUP`` names one run of a TDMS file) with the command
    line's mapping options: a bench ``profile`` (TOML) first, then these
    arguments. Columns ``time_s, friction_N, position_mm, optical_V`` by
    default; ``*_col`` names others, ``*_scale``/``*_offset`` convert raw
    numbers (value = raw * scale + offset, in N, mm, V); ``fs_hz`` is needed
    without a time column or ``fs_from`` (a MAT scalar or struct field
    holding the rate, e.g. ``'bearing.sr'``). CSV dialects as the command
    line's flags: ``time_unit`` (``'s'``, ``'ms'``, ``'us'``),
    ``decimal_comma``, ``skip_lines`` (metadata lines before the header);
    gaps (NaN, missing time stamps) are refused, naming their place, unless
    ``fill_gaps_s`` fills those up to that long (s, linear). Raises
    FileNotFoundError/OSError for a file that cannot be read, ValueError
    naming the line or channel for bad content."""
    opts = dict(
        profile=profile, format=format, delimiter=delimiter, fs_hz=fs_hz,
        time_col=time_col, ignore_time=ignore_time or None, friction_col=friction_col,
        position_col=position_col, optical_col=optical_col,
        friction_scale=friction_scale, friction_offset=friction_offset,
        position_scale=position_scale, position_offset=position_offset,
        optical_scale=optical_scale, optical_offset=optical_offset,
        velocity_mm_s=velocity_mm_s, test_id=test_id, min_periods=min_periods,
        fs_from=fs_from, time_unit=time_unit, decimal_comma=decimal_comma or None,
        skip_lines=skip_lines, fill_gaps_s=fill_gaps_s,
        bearing=bearing, ball_diameter_mm=ball_diameter_mm,
        free_space_mm=free_space_mm, balls_in_race=balls_in_race,
    )
    return _native.load(os.fspath(path), _load_json(opts))


def simulate(velocity_mm_s: float | None = None, *, bearing: str | None = None,
             condition: str | None = None, seed: int | None = None,
             settings: dict | None = None, **setting_overrides) -> tuple[Recording, Result]:
    """A bench recording from the built-in testbed simulator, with its
    ground truth: ``(recording, truth)``. ``truth.to_dict()`` equals the
    ``NAME.truth.json`` of ``ballpass simulate``. ``settings`` (and keyword
    arguments) set simulator fields by name, e.g. ``duration_s=10``,
    ``fs_hz=2000``, ``friction={"coulomb_n": 2.0}``; ``condition`` is
    ``'good'`` or ``'sticking'``; the same seed gives the same samples."""
    rec, truth = _native.simulate(
        _settings_json(settings, setting_overrides), velocity_mm_s, bearing, condition, seed
    )
    return rec, Result(truth, kind="Truth")


# ---------------------------------------------------------------- analyses


def predict(velocity_mm_s: float | Sequence[float], *, bearing: str | None = None,
            ball_diameter_mm: float | None = None, free_space_mm: float | None = None,
            balls_in_race: int | None = None, harmonics: int = 5) -> Result:
    """Ball-pass frequency ``f_c = v / (2 d_avg)`` (Hz), period ``tau_c_s``
    and band at one or more velocities (mm/s), for a catalog bearing
    (default ``sr25w``) or a custom geometry. ``to_dict()`` equals
    ``ballpass predict --json``; ``.table`` holds the predictions as
    columns."""
    vs = np.atleast_1d(np.asarray(velocity_mm_s, dtype=np.float64)).tolist()
    data = _native.predict(vs, int(harmonics),
                           _bearing_json(bearing, ball_diameter_mm, free_space_mm, balls_in_race))
    return Result(data, {"table": _records_table(data["predictions"])}, "Prediction")


def analyze(recordings, *, velocity_mm_s: float | None = None, bearing: str | None = None,
            ball_diameter_mm=None, free_space_mm=None, balls_in_race=None,
            force_velocity: bool = False, settings: dict | None = None, threads=None,
            stream: str = "auto", **setting_overrides) -> Result:
    """Correlations, spectra, measured period, phases and harmonics of one
    recording, or of several repeats at one velocity (averaged), as
    ``ballpass analyze``. ``recordings``: Recording objects or file paths.
    ``velocity_mm_s`` defaults to the recordings' own, else the encoder's.
    The command line's checks run first: dead channels are left out (with
    a warning), and a stated velocity that the encoder contradicts is an
    error unless ``force_velocity``. Settings are
    ``AnalyzeSettings`` fields by name (``lowpass_hz``, ``order``,
    ``detrend``, ``nperseg``, ``corr_norm``, ``harmonics``, ...), in
    ``settings`` or as keyword arguments.

    The setting ``window`` is the Welch window (the command line's
    ``--welch-window``); to analyse part of a record, slice it first.

    ``to_dict()`` equals ``analysis.json`` (schema ``ballpass.analysis/2``);
    the tables ``correlations`` (``lag_s`` then one column per series:
    ``r_friction__optical`` under ``corr_norm='coeff'``, else with the
    product's unit, ``r_friction__optical_n_v``), ``spectra``,
    ``spectra_hires`` and ``spectra_unfiltered`` (``freq_hz`` then PSDs
    such as ``psd_friction_n2_per_hz``, cross spectra ``csd_<pair>_re_<unit>``
    and ``csd_<pair>_im_<unit>``, coherence ``coh_<pair>``) equal the CSV
    files, and so do ``spectra_position`` (``freq_per_mm`` in cycles/mm,
    then the position-domain PSDs such as ``psd_friction_n2_mm`` in
    unit²·mm and their confidence bands; ``None`` without position-domain
    spectra) and ``sync_average`` (``phase`` in periods after the optical
    passage, then ``<signal>_mean_<unit>``, ``<signal>_band_low_<unit>``,
    ``<signal>_band_high_<unit>`` in N and µm/s; ``None`` without a
    synchronous average). The analysis' warnings are also issued as
    :class:`BallpassWarning`.

    ``stream`` is the command line's ``--stream``: one record *file* of
    1 GiB or more (``'auto'``), or any size (``'on'``), is read block by
    block in memory that does not grow with its length, if it is a plain
    CSV/TSV with a uniform time column, a TDMS, an MF4 or a MATLAB v7.3
    file; ``'off'`` always
    reads it whole. A streamed record needs a velocity (given or in the
    file); its passages are detected window by window (``to_dict()['stream']``
    says how), its synchronous average and position-domain spectra are the
    in-memory ones; ``'on'`` with anything that cannot stream is an error
    that says why."""
    load_opts = {"velocity_mm_s": velocity_mm_s, "bearing": bearing, "min_periods": 2.0}
    load_opts = {k: v for k, v in load_opts.items() if v is not None}
    settings_json = _settings_json(settings, setting_overrides)
    tables = None
    if stream != "off":
        if isinstance(recordings, (str, os.PathLike)):
            # The streamed record's geometry comes with its load options.
            stream_opts = dict(load_opts, ball_diameter_mm=ball_diameter_mm,
                               free_space_mm=free_space_mm, balls_in_race=balls_in_race)
            tables, why = _native.analyze_file(
                os.fspath(recordings), stream, _load_json(stream_opts), velocity_mm_s,
                settings_json, _pool(threads),
            )
            if why is not None:
                warnings.warn(why, BallpassWarning, stacklevel=2)
        elif stream == "on":
            raise ValueError("stream='on' takes one record file path (not Recording objects or a list)")
        elif stream != "auto":
            raise ValueError(f"stream: expected 'auto', 'on' or 'off', got {stream!r}")
    if tables is None:
        recs = _as_recordings(recordings, load_opts)
        tables = _native.analyze(
            recs, velocity_mm_s,
            _bearing_json(bearing, ball_diameter_mm, free_space_mm, balls_in_race),
            settings_json, _pool(threads), bool(force_velocity),
        )
    data, corr, spectra, hires, unfiltered, position, sync = tables
    _warn(data)
    return Result(
        data,
        {"correlations": Table(corr), "spectra": Table(spectra), "spectra_hires": Table(hires),
         "spectra_unfiltered": Table(unfiltered),
         "spectra_position": None if position is None else Table(position),
         "sync_average": None if sync is None else Table(sync)},
        "Analysis",
    )


def _load_cell_json(load_cell) -> str | None:
    """``load_cell`` as the library's setting: ``None`` (the default,
    ``auto``), ``'auto'``, ``'off'`` or a time constant in seconds."""
    if load_cell is None:
        return None
    if isinstance(load_cell, str):
        if load_cell not in ("auto", "off"):
            raise ValueError(f"load_cell: expected a time constant in seconds (> 0), 'auto' or 'off', got {load_cell!r}")
        return json.dumps(load_cell)
    if isinstance(load_cell, bool):
        raise ValueError(f"load_cell: expected a time constant in seconds (> 0), 'auto' or 'off', got {load_cell!r}")
    return json.dumps({"time_constant": float(load_cell)})


def compensate(recordings, *, velocity_mm_s: float | None = None, bearing: str | None = None,
               ball_diameter_mm=None, free_space_mm=None, balls_in_race=None,
               mass_kg: float | None = None, kkp: float | None = None, kkd: float | None = None,
               force_velocity: bool = False, load_cell=None, applied=None, threads=None) -> Result:
    """A feedforward compensation table (force in N against ball-pass
    phase, and against rail position in mm when the passages lock to the
    rail) from the synchronous average of recordings at one velocity, and
    the velocity error (µm/s) it is predicted to leave, as ``ballpass
    compensate``. The recordings need friction, encoder position and the
    optical sensor (Recording objects or file paths); the command line's
    checks run first, as for :func:`analyze`, with the default analysis
    settings. The stage is identified from the records; when that fails,
    give the loop as ``mass_kg`` (kg), ``kkp`` (K·K_P, N/m) and ``kkd``
    (K·K_D, N·s/m), all three.

    ``load_cell``: the quartz load cell's discharge time constant in
    seconds, ``'auto'`` (default) or ``'off'`` (a DC-coupled sensor), as
    ``--load-cell-tau``. With ``'auto'`` the time constant is the one with
    which the replay through the stage gives the records' velocity error
    best (``to_dict()['load_cell']`` says which and why); near stall the
    records do not decide it and a warning says so: there a known time
    constant makes the table better.

    ``applied``: a second round, as ``--applied``. The recordings were
    taken on the machine with that table applied; give its
    ``compensation.json`` as a path, or the result of an earlier
    :func:`compensate` (or its ``to_dict()``). The table's fundamental is
    corrected from what the recordings still show; the stage is the
    applied table's (``mass_kg``/``kkp``/``kkd`` are refused). The result
    is then a ``SecondCompensation``: ``to_dict()`` equals its
    ``compensation.json`` (``round`` holds the f_c component and std with
    the applied table, µm/s, and the predicted f_c component after, with
    its 10–90 % interval) and ``table`` its ``compensation_phase.csv``
    (``phase``, ``force_n``, ``applied_force_n``).

    Otherwise ``to_dict()`` equals ``compensation.json``; ``table`` equals
    ``compensation_phase.csv`` (``phase`` in periods after phase 0,
    ``force_n``, ``velocity_error_after_um_s``) and ``rail_table``
    ``compensation_rail.csv`` (``position_mm``, ``force_n``; ``None``
    without a rail table). The checks' warnings and the result's are
    issued as :class:`BallpassWarning`."""
    gains = (mass_kg, kkp, kkd)
    if all(g is None for g in gains):
        gains = None
    elif any(g is None for g in gains):
        raise ValueError("give mass_kg, kkp and kkd together")
    else:
        gains = tuple(float(g) for g in gains)
    load_opts = {"velocity_mm_s": velocity_mm_s, "bearing": bearing, "min_periods": 2.0}
    recs = _as_recordings(recordings, {k: v for k, v in load_opts.items() if v is not None})
    bearing_json = _bearing_json(bearing, ball_diameter_mm, free_space_mm, balls_in_race)
    load_cell_json = _load_cell_json(load_cell)
    if applied is not None:
        if gains is not None:
            raise ValueError("applied: the stage is the applied table's; do not give mass_kg, kkp and kkd")
        if isinstance(applied, Result):
            applied = applied.to_dict()
        if isinstance(applied, dict):
            path, text, name = None, json.dumps(applied), "<applied table>"
        elif isinstance(applied, (str, os.PathLike)):
            path, text, name = os.fspath(applied), None, os.fspath(applied)
        else:
            raise TypeError(f"applied: expected a compensation.json path, a dict or a compensate() result, got {type(applied).__name__}")
        data, phase, checks = _native.compensate_second(
            recs, name, path, text, velocity_mm_s, bearing_json, _pool(threads),
            bool(force_velocity), load_cell_json,
        )
        _warn({"warnings": checks})
        _warn(data)
        return Result(data, {"table": Table(phase)}, "SecondCompensation")
    data, phase, rail, checks = _native.compensate(
        recs, velocity_mm_s, bearing_json, gains, _pool(threads), bool(force_velocity),
        load_cell_json,
    )
    _warn({"warnings": checks})
    _warn(data)
    return Result(
        data,
        {"table": Table(phase), "rail_table": None if rail is None else Table(rail)},
        "Compensation",
    )


def passages(recordings, *, velocity_mm_s: float | None = None, bearing: str | None = None,
             ball_diameter_mm=None, free_space_mm=None, balls_in_race=None,
             window=None, force_velocity: bool = False,
             settings: dict | None = None, threads=None, **setting_overrides) -> Result:
    """Ball passages seen by the optical sensor, per recording, as
    ``ballpass passage``: periods ``tau_c_s``, widths at half prominence
    ``tau_p_s``, artefacts and pulse-train fits. Settings are
    ``PassageSettings`` fields (``min_snr``, ``fit_pulses``,
    ``rectangular_order``, ...). ``to_dict()`` equals ``passage.json``;
    ``.table`` equals ``passages.csv`` and each ``.records[i].table`` holds
    that record's rows. A recording that fails is listed in ``failed``;
    when all fail, the first failure is raised.

    ``window=(t0, t1)`` (s, on each record's time axis; ``None`` leaves an
    end open) measures only that part, as ``--window T0:T1``. The command
    line's checks run first, as for :func:`analyze`: dead channels are left
    out (with a warning), and a velocity (``velocity_mm_s`` or the
    recording's own) that the encoder contradicts is an error unless
    ``force_velocity``; without one, the encoder's is used."""
    load_opts = {"velocity_mm_s": velocity_mm_s, "bearing": bearing}
    recs = _as_recordings(recordings, {k: v for k, v in load_opts.items() if v is not None})
    over = dict(setting_overrides)
    if velocity_mm_s is not None:
        over["velocity_mm_s"] = velocity_mm_s
    data, tables = _native.passages(
        recs, _bearing_json(bearing, ball_diameter_mm, free_space_mm, balls_in_race),
        _settings_json(settings, over), _pool(threads), _window(window), bool(force_velocity),
    )
    _warn(data)
    per = [Table(t) for t in tables]
    whole = {}
    if per and per[0].columns:
        for c in per[0].columns:
            parts = [t[c] for t in per if c in t]
            whole[c] = (np.concatenate(parts) if isinstance(parts[0], np.ndarray)
                        else [v for p in parts for v in p])
    result = Result(data, {"table": Table(whole)}, "Passages")
    object.__getattribute__(result, "_cache")["records"] = [
        Result(r, {"table": t}, "PassageAnalysis") for r, t in zip(data["records"], per)
    ]
    return result


# ---------------------------------------------------------------- campaigns


def read_manifest(source: str | os.PathLike, *, pattern: str | None = None,
                  bearing: str | None = None, velocity_mm_s: float | None = None) -> Result:
    """A campaign's recordings: a manifest CSV (``path, bearing,
    velocity_mm_s, repeat[, condition, notes]``), or a folder with a
    file-name ``pattern`` (``'v{velocity}_r{repeat}.csv'``). ``.entries``
    lists them."""
    return Result(
        _native.manifest(os.fspath(source), pattern,
                         _load_json({"bearing": bearing, "velocity_mm_s": velocity_mm_s})),
        kind="Manifest",
    )


def select(source: str | os.PathLike, kind: str = "diagnose", *, pattern: str | None = None,
           only_bearings: Iterable[str] = (), only_velocities: Iterable[float] = (),
           bearing: str | None = None, velocity_mm_s: float | None = None) -> Result:
    """The records ``ballpass sweep`` (``kind='sweep'``) or ``ballpass
    diagnose`` (``'diagnose'``) would use from a manifest or folder:
    ``.entries`` and, in words, ``.notes`` (the outputs' ``selection``). By
    default the bearing recorded at the most velocities (sweep) or the
    velocity with the most bearings (diagnose); naming bearings or
    velocities replaces the default."""
    return Result(
        _native.selection(kind, os.fspath(source), pattern, list(only_bearings),
                          [float(v) for v in only_velocities],
                          _load_json({"bearing": bearing, "velocity_mm_s": velocity_mm_s})),
        kind="Selection",
    )


def _diagnosis_json(settings, low_band_hz, spike_spreads, bad_false_alarm):
    """``DiagnoseSettings`` as JSON: the keyword flags fill what ``settings``
    (any ``DiagnoseSettings`` field, ``sticking`` a dict of
    ``StickingSettings``) leaves unset."""
    d = dict(settings or {})
    d.setdefault("low_band_hz", float(low_band_hz))
    d.setdefault("bad_false_alarm", float(bad_false_alarm))
    sticking = dict(d.get("sticking") or {})
    sticking.setdefault("outlier_spreads", float(spike_spreads))
    d["sticking"] = sticking
    return json.dumps(d)


def sweep(source, *, pattern: str | None = None, only_bearings: Iterable[str] = (),
          only_velocities: Iterable[float] = (), lowpass_hz: float = 20.0,
          harmonics: int = 5, window=None, force_velocity: bool = False,
          segment: bool = False, threads=None, **load_options) -> Result:
    """A velocity sweep over a campaign, as ``ballpass sweep``: velocity-error
    trend, tau_c and tau_p against velocity, d_avg. ``source`` is a manifest
    CSV or a folder with ``pattern``; by default the bearing recorded at the
    most velocities. ``window=(t0, t1)`` (s) uses only that part of each
    record (``--window``); each record's velocity is checked against its
    encoder as :func:`analyze` does (``force_velocity``:
    ``--force-velocity``). ``segment=True`` (``--segment``) splits each file
    into its constant-velocity plateaus, each analysed at its own measured
    speed (manifest velocities may then be left empty); the plateau of each
    record is in its ``plateau``. ``to_dict()`` equals ``sweep.json``."""
    data, _ = _native.campaign(
        "sweep", os.fspath(source), pattern, list(only_bearings),
        [float(v) for v in only_velocities], float(lowpass_hz), int(harmonics), None,
        _load_json(load_options), _pool(threads), _window(window), bool(force_velocity),
        bool(segment),
    )
    return Result(data, kind="Sweep")


def diagnose(source, *, pattern: str | None = None, only_bearings: Iterable[str] = (),
             only_velocities: Iterable[float] = (), lowpass_hz: float = 20.0,
             harmonics: int = 5, low_band_hz: float = 25.0, spike_spreads: float = 8.0,
             bad_false_alarm: float = 1e-4, settings: dict | None = None, window=None,
             force_velocity: bool = False, segment: bool = False, threads=None,
             **load_options) -> Result:
    """A batch of bearings, as ``ballpass diagnose``: friction spectra,
    harmonics, the friction of each ball-pass period and a verdict per
    bearing (worst first in ``.result.bearings``). ``source`` is a manifest
    CSV or a folder with ``pattern``; by default the velocity with the most
    bearings. The keywords are the command line's flags: ``low_band_hz``
    (``--low-band``, Hz, evidence only), ``spike_spreads``
    (``--spike-spreads``: a period is a sticking spike when it rises this
    many spreads above the bearing's typical period) and ``bad_false_alarm``
    (``--bad-false-alarm``: false-alarm probability per good bearing of the
    spike count for "bad"); ``settings`` sets any ``DiagnoseSettings`` field
    (e.g. ``{"suspect_false_alarm": 0.01, "sticking": {"smoothing_periods":
    0.01}}``) and wins over the keywords. ``window=(t0, t1)`` (s),
    ``force_velocity`` and ``segment`` are ``--window``,
    ``--force-velocity`` and ``--segment``, as for :func:`sweep`. ``to_dict()`` equals ``diagnosis.json``;
    ``.friction_spectra`` is ``friction_spectra.csv`` (columns
    ``psd_friction_<bearing>_n2_per_hz``)."""
    data, spectra = _native.campaign(
        "diagnose", os.fspath(source), pattern, list(only_bearings),
        [float(v) for v in only_velocities], float(lowpass_hz), int(harmonics),
        _diagnosis_json(settings, low_band_hz, spike_spreads, bad_false_alarm),
        _load_json(load_options), _pool(threads), _window(window), bool(force_velocity),
        bool(segment),
    )
    return Result(data, {"friction_spectra": Table(spectra)}, "Diagnosis")


def process_record(path, *, bearing: str, velocity_mm_s: float, repeat: int = 1,
                   condition: str | None = None, lowpass_hz: float = 20.0, harmonics: int = 5,
                   low_band_hz: float = 25.0, spike_spreads: float = 8.0,
                   settings: dict | None = None, window=None, force_velocity: bool = False,
                   **load_options) -> RecordResult:
    """One record of a campaign, loaded and processed exactly as
    ``ballpass diagnose`` processes each record (analysis, passages, the
    friction of each ball-pass period, friction spectrum): the per-record
    half of :func:`diagnose`, for executors of a distributed engine. Give it
    the ``low_band_hz`` and ``spike_spreads`` the batch half gets, and the
    same ``window`` and ``force_velocity`` as :func:`diagnose_records`. The
    result pickles."""
    data, freq, psd, heights = _native.process_record(
        os.fspath(path), bearing, float(velocity_mm_s), int(repeat), condition,
        float(lowpass_hz), int(harmonics),
        _diagnosis_json(settings, low_band_hz, spike_spreads, 1e-4),
        _load_json(load_options), _window(window), bool(force_velocity),
    )
    return RecordResult(data, freq, psd, heights)


def diagnose_records(records: Iterable[RecordResult], *, failures: Iterable[tuple] = (),
                     source: str = "records", selection: Iterable[str] = (),
                     lowpass_hz: float = 20.0, harmonics: int = 5, low_band_hz: float = 25.0,
                     spike_spreads: float = 8.0, bad_false_alarm: float = 1e-4,
                     settings: dict | None = None, window=None,
                     force_velocity: bool = False) -> Result:
    """The batch half of :func:`diagnose`: verdicts from records processed
    by :func:`process_record` (anywhere), with the same thresholds.
    ``failures`` are ``(path, bearing, velocity_mm_s, repeat, reason)`` of
    records that could not be processed. Returns what :func:`diagnose`
    returns."""
    states = [r._state() for r in records]
    data, spectra = _native.diagnose_records(
        states, [tuple(f) for f in failures], str(source), list(selection),
        float(lowpass_hz), int(harmonics),
        _diagnosis_json(settings, low_band_hz, spike_spreads, bad_false_alarm),
        _window(window), bool(force_velocity),
    )
    return Result(data, {"friction_spectra": Table(spectra)}, "Diagnosis")


from . import model, signal  # noqa: E402  (they import from this package)
