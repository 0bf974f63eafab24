"""The domain API against the command line: the same input gives identical
numbers (the JSON files equal ``to_dict()``, the CSV tables equal the
result's tables, exactly), plus the Python-only behaviour: recordings from
arrays, errors, threads and the GIL."""

from __future__ import annotations

import csv
import json
import pickle
import subprocess
import threading
import time

import numpy as np
import pytest

import ballpass
from ballpass import signal as bs
from conftest import ballpass_bin


def read_json(path):
    return json.loads(path.read_text())


def read_csv(path):
    """{column: list of cells} with numbers as floats (NumPy's nan/inf)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    head, body = rows[0], rows[1:]
    cols = {}
    for i, name in enumerate(head):
        cells = [r[i] for r in body]
        try:
            cols[name] = np.array([float(c) if c != "" else np.nan for c in cells])
        except ValueError:
            cols[name] = cells
    return cols


def assert_table_equals_csv(table, path):
    want = read_csv(path)
    assert table.columns == list(want), f"{path.name}: columns"
    for k, v in want.items():
        got = table[k]
        if isinstance(v, list):
            assert [str(x) for x in got] == v, k
        else:
            got = np.asarray(got, dtype=np.float64)
            # Exact: both sides print/keep the shortest round-trip text of
            # the same f64 (NaN where the CSV has nan or an empty cell).
            assert np.array_equal(got, v, equal_nan=True), f"{path.name}:{k}"


@pytest.fixture(scope="module")
def recs(tmp_path_factory, cli):
    """Two simulated recordings written by the CLI, 9 mm/s, 20 s."""
    d = tmp_path_factory.mktemp("recs")
    for seed in (3, 4):
        cli("simulate", "-v", "9", "--seed", seed, "--duration", "20", "-o", d / f"r{seed}.csv")
    return d


def test_simulate_equals_the_cli(recs):
    rec, truth = ballpass.simulate(9.0, seed=3, duration_s=20)
    assert truth.to_dict() == read_json(recs / "r3.truth.json")
    loaded = ballpass.load(recs / "r3.csv")
    for ch in ("friction_n", "position_mm", "optical_v"):
        # The CSV holds shortest round-trip text: exact.
        assert np.array_equal(getattr(rec, ch), getattr(loaded, ch)), ch
    assert rec.fs_hz == loaded.fs_hz == 1000.0 and len(rec) == 20000


def test_load_reads_a_lab_dialect_as_the_cli(recs, cli, tmp):
    """A CSV as a lab's logger writes it (two metadata lines, a units row,
    decimal commas and semicolons, time in ms, one missing sample) reads
    with the command line's dialect options: the same samples as the
    canonical file, and `inspect` through the CLI agrees on the length."""
    rec = ballpass.load(recs / "r3.csv")
    n = 2000
    lines = ["logger: bench 2", "date: 2026-11-24",
             "t;friction;position;optical", "ms;N;mm;V"]
    for i in range(n):
        if i == 700:
            continue  # a dropped sample: a gap of one step
        cells = [repr(1000.0 * i / float(rec.fs_hz)), repr(float(rec.friction_n[i])),
                 repr(float(rec.position_mm[i])), repr(float(rec.optical_v[i]))]
        lines.append(";".join(c.replace(".", ",") for c in cells))
    f = tmp / "lab.csv"
    f.write_text("\n".join(lines) + "\n")
    opts = dict(delimiter="semicolon", decimal_comma=True, skip_lines=2, time_col="t",
                time_unit="ms", friction_col="friction", position_col="position",
                optical_col="optical", min_periods=0.1)
    with pytest.raises(ValueError, match="gap"):
        ballpass.load(f, **opts)
    got = ballpass.load(f, fill_gaps_s=0.0015, **opts)
    assert len(got) == n and got.fs_hz == rec.fs_hz
    keep = np.arange(n) != 700
    # decimal-comma text of the shortest round-trip repr: exact where read
    assert np.array_equal(got.friction_n[keep], rec.friction_n[:n][keep])
    assert np.array_equal(got.optical_v[keep], rec.optical_v[:n][keep])
    # the filled sample lies between its neighbours (linear fill)
    lo, hi = sorted((rec.position_mm[699], rec.position_mm[701]))
    assert lo <= got.position_mm[700] <= hi
    out = cli("inspect", f, "--delimiter", "semicolon", "--decimal-comma", "--skip-lines", "2",
              "--time-col", "t", "--time-unit", "ms", "--friction-col", "friction",
              "--position-col", "position", "--optical-col", "optical", "--fill-gaps", "0.0015",
              "--min-periods", "0.1")
    assert str(n) in out, out


def test_analyze_equals_the_cli(recs, cli, tmp):
    for files, flags, kw in (
        (["r3.csv"], [], {}),
        (["r3.csv", "r4.csv"], [], {}),
        (["r3.csv"], ["--lowpass", "15", "--nperseg", "2048", "--zoom", "8", "--detrend",
                      "constant", "--corr-norm", "biased"],
         {"lowpass_hz": 15.0, "nperseg": 2048, "hires": {"method": "polyphase_zoom", "m": 8},
          "detrend": "constant", "corr_norm": "biased"}),
    ):
        out = tmp / f"a{len(files)}{len(flags)}"
        cli("analyze", *[recs / f for f in files], "--velocity", "9", "--no-report", "--out", out,
            *flags)
        loaded = [ballpass.load(recs / f) for f in files]
        a = ballpass.analyze(loaded, velocity_mm_s=9.0, **kw)
        assert a.to_dict() == read_json(out / "analysis.json")
        assert_table_equals_csv(a.correlations, out / "correlations.csv")
        assert_table_equals_csv(a.spectra, out / "spectra.csv")
        assert_table_equals_csv(a.spectra_hires, out / "spectra_hires.csv")
        assert_table_equals_csv(a.spectra_unfiltered, out / "spectra_unfiltered.csv")
        # The position-domain PSDs and the synchronous average, when the
        # command line writes them (it does for these records: below).
        for name in ("spectra_position", "sync_average"):
            if (out / f"{name}.csv").exists():
                assert_table_equals_csv(getattr(a, name), out / f"{name}.csv")
            else:
                assert getattr(a, name) is None, name
        assert a.schema == "ballpass.analysis/2"
    # paths work too, and the attributes are the JSON's fields
    b = ballpass.analyze(recs / "r3.csv", velocity_mm_s=9.0)
    assert isinstance(b.spectra_position.psd_friction_n2_mm, np.ndarray)
    assert b.spectra_position.freq_per_mm.shape == b.spectra_position.psd_friction_n2_mm.shape
    assert b.sync_average.friction_mean_n.shape == b.sync_average.phase.shape == (b.sync.bins,)
    assert b.prediction.f_c_hz == pytest.approx(9.0 / (2 * (4 + 2 / 36)), rel=1e-12)
    assert isinstance(b.prediction.harmonics_hz, np.ndarray)
    assert b.verdict.text and b.correlations.lag_s.shape == (39999,)


def test_analyze_streams_a_file_as_the_cli(recs, cli, tmp):
    """`stream='on'` is `--stream on`: the record read block by block gives
    the command line's streamed analysis.json and tables; it needs a
    velocity and one file, and 'auto' reads a short file whole."""
    out = tmp / "streamed"
    cli("analyze", recs / "r3.csv", "--velocity", "9", "--stream", "on", "--no-report",
        "--out", out)
    with pytest.warns(ballpass.BallpassWarning, match="streamed"):
        a = ballpass.analyze(recs / "r3.csv", velocity_mm_s=9.0, stream="on")
    assert a.to_dict() == read_json(out / "analysis.json")
    assert a.to_dict()["stream"]["passes"] == 4
    assert_table_equals_csv(a.correlations, out / "correlations.csv")
    assert_table_equals_csv(a.spectra, out / "spectra.csv")
    assert_table_equals_csv(a.spectra_hires, out / "spectra_hires.csv")
    # Streamed records get the position-domain spectra and the synchronous
    # average too (docs/methods.md §15), as the command line writes them.
    assert_table_equals_csv(a.spectra_position, out / "spectra_position.csv")
    assert_table_equals_csv(a.sync_average, out / "sync_average.csv")
    whole = ballpass.analyze(recs / "r3.csv", velocity_mm_s=9.0)
    assert "stream" not in whole.to_dict()
    with pytest.raises(ValueError, match="velocity_mm_s"):
        ballpass.analyze(recs / "r3.csv", stream="on")
    with pytest.raises(ValueError, match="one record file"):
        ballpass.analyze([recs / "r3.csv", recs / "r4.csv"], velocity_mm_s=9.0, stream="on")
    with pytest.raises(ValueError, match="auto.*on.*off"):
        ballpass.analyze(recs / "r3.csv", velocity_mm_s=9.0, stream="sometimes")


def test_analyze_runs_the_command_lines_checks(recs, cli, tmp):
    """As `ballpass analyze`: a stated velocity that the encoder contradicts
    is an error unless forced (then a warning, and analysis.json equals the
    command line's), and without a stated velocity the encoder's is used."""
    rec = ballpass.load(recs / "r3.csv")
    with pytest.raises(ValueError, match="encoder"):
        ballpass.analyze(rec, velocity_mm_s=12.0)
    with pytest.warns(ballpass.BallpassWarning, match="as forced"):
        forced = ballpass.analyze(rec, velocity_mm_s=12.0, force_velocity=True)
    out = tmp / "forced"
    cli("analyze", recs / "r3.csv", "--velocity", "12", "--force-velocity", "--no-report",
        "--out", out)
    assert forced.to_dict() == read_json(out / "analysis.json")
    bare = ballpass.Recording(rec.fs_hz, friction_n=rec.friction_n, position_mm=rec.position_mm,
                              optical_v=rec.optical_v)
    measured = ballpass.analyze(bare)
    assert any("measured from the encoder" in n for n in measured.method_notes)
    # The simulated stage tracks 9 mm/s to far better than 1 %.
    assert measured.prediction.f_c_hz == pytest.approx(9.0 / (2 * (4 + 2 / 36)), rel=1e-2)


def _cli_error(*args) -> str:
    """Runs the ballpass binary expecting a failure; returns its stderr."""
    r = subprocess.run([str(ballpass_bin()), *map(str, args)], capture_output=True, text=True)
    assert r.returncode != 0, f"ballpass {' '.join(map(str, args))} succeeded"
    return r.stderr


def test_second_round_and_load_cell_equal_the_cli(recs, cli, tmp):
    """`compensate(..., applied=...)` is `ballpass compensate --applied`
    (the records taken with the table applied, here by `simulate
    --feedforward`), with the applied table given as a path, as the first
    round's result or as its dict; `load_cell` is `--load-cell-tau`; the
    bad arguments are refused."""
    stage = read_json(recs / "r3.truth.json")["settings"]["stage"]
    m, kp, kd = stage["mass_kg"], stage["kkp_n_per_m"], stage["kkd_n_s_per_m"]
    gains = ("--mass", m, "--kkp", kp, "--kkd", kd)
    c1 = tmp / "c1"
    cli("compensate", recs / "r3.csv", "--velocity", "9", *gains, "--load-cell-tau", "10",
        "--out", c1)
    first = ballpass.compensate(recs / "r3.csv", velocity_mm_s=9.0, mass_kg=m, kkp=kp, kkd=kd,
                                load_cell=10)
    assert first.to_dict() == read_json(c1 / "compensation.json")
    cli("simulate", "--settings", recs / "r3.truth.json", "--feedforward", c1 / "compensation.json",
        "--out", tmp / "with_table.csv")
    c2 = tmp / "c2"
    cli("compensate", tmp / "with_table.csv", "--velocity", "9", "--load-cell-tau", "10",
        "--applied", c1 / "compensation.json", "--out", c2)
    want = read_json(c2 / "compensation.json")
    assert want["schema"] == "ballpass.compensation-second/1"
    second = ballpass.compensate(tmp / "with_table.csv", velocity_mm_s=9.0, load_cell=10,
                                 applied=c1 / "compensation.json")
    assert second.to_dict() == want
    assert_table_equals_csv(second.table, c2 / "compensation_phase.csv")
    np.testing.assert_array_equal(second.applied_force_n, first.force_n)
    for applied in (first, first.to_dict()):
        again = ballpass.compensate(tmp / "with_table.csv", velocity_mm_s=9.0, load_cell=10,
                                    applied=applied)
        d = again.to_dict()
        assert d.pop("applied_from") == "<applied table>"
        assert d == {k: v for k, v in want.items() if k != "applied_from"}
    with pytest.raises(ValueError, match="applied table's"):
        ballpass.compensate(tmp / "with_table.csv", velocity_mm_s=9.0, applied=first,
                            mass_kg=m, kkp=kp, kkd=kd)
    with pytest.raises(TypeError, match="applied"):
        ballpass.compensate(tmp / "with_table.csv", velocity_mm_s=9.0, applied=3)
    with pytest.raises(ValueError, match="load_cell"):
        ballpass.compensate(recs / "r3.csv", velocity_mm_s=9.0, mass_kg=m, kkp=kp, kkd=kd,
                            load_cell="sometimes")
    (tmp / "bad.json").write_text('{"schema": "ballpass.analysis/1"}')
    stderr = _cli_error("compensate", tmp / "with_table.csv", "--velocity", "9",
                        "--applied", tmp / "bad.json", "--out", tmp / "z")
    with pytest.raises(ValueError) as e:
        ballpass.compensate(tmp / "with_table.csv", velocity_mm_s=9.0, applied=tmp / "bad.json")
    assert "bad.json" in str(e.value) and str(e.value) in stderr, (str(e.value), stderr)


def test_compensate_equals_the_cli(recs, cli, tmp):
    """`ballpass.compensate` is `ballpass compensate`: compensation.json and
    both tables exactly, one record and two repeats; the same errors (a
    stage the records do not identify and no gains, no optical sensor);
    the loop gains go together."""
    stage = read_json(recs / "r3.truth.json")["settings"]["stage"]
    m, kp, kd = stage["mass_kg"], stage["kkp_n_per_m"], stage["kkd_n_s_per_m"]
    for files in (["r3.csv"], ["r3.csv", "r4.csv"]):
        out = tmp / f"c{len(files)}"
        cli("compensate", *[recs / f for f in files], "--velocity", "9", "--mass", m,
            "--kkp", kp, "--kkd", kd, "--out", out)
        c = ballpass.compensate([recs / f for f in files], velocity_mm_s=9.0, mass_kg=m,
                                kkp=kp, kkd=kd)
        assert c.to_dict() == read_json(out / "compensation.json")
        assert_table_equals_csv(c.table, out / "compensation_phase.csv")
        if (out / "compensation_rail.csv").exists():
            assert_table_equals_csv(c.rail_table, out / "compensation_rail.csv")
        else:
            assert c.rail_table is None
        assert c.force_n.shape == (c.bins,) and c.prediction.f_c_after_um_s >= 0
    # These 20 s records do not identify the stage: without the gains both
    # refuse, with the same words.
    stderr = _cli_error("compensate", recs / "r3.csv", "--velocity", "9", "--out", tmp / "x")
    with pytest.raises(ValueError) as e:
        ballpass.compensate(recs / "r3.csv", velocity_mm_s=9.0)
    assert "identified" in str(e.value) and str(e.value) in stderr, (str(e.value), stderr)
    with pytest.raises(ValueError, match="together"):
        ballpass.compensate(recs / "r3.csv", velocity_mm_s=9.0, mass_kg=m)
    rec = ballpass.load(recs / "r3.csv")
    ballpass.Recording(rec.fs_hz, friction_n=rec.friction_n, position_mm=rec.position_mm,
                       velocity_mm_s=9.0).to_csv(tmp / "no_optical.csv")
    stderr = _cli_error("compensate", tmp / "no_optical.csv", "--velocity", "9", "--mass", m,
                        "--kkp", kp, "--kkd", kd, "--out", tmp / "y")
    with pytest.raises(ValueError) as e:
        ballpass.compensate(tmp / "no_optical.csv", velocity_mm_s=9.0, mass_kg=m, kkp=kp, kkd=kd)
    assert str(e.value) in stderr, (str(e.value), stderr)


def test_passages_equal_the_cli(recs, cli, tmp):
    cli("passage", recs / "r3.csv", recs / "r4.csv", "--velocity", "9", "--no-report",
        "--out", tmp)
    p = ballpass.passages([recs / "r3.csv", recs / "r4.csv"], velocity_mm_s=9.0)
    assert p.to_dict() == read_json(tmp / "passage.json")
    assert_table_equals_csv(p.table, tmp / "passages.csv")
    r = p.records[1]
    assert r.count == len(r.table.tau_p_s) and r.tau_c_s.mean > 0


def test_passages_take_a_window_and_run_the_checks(recs, cli, tmp):
    """As `ballpass passage --window T0:T1`: each record cut to the window
    (passage.json names it and equals the command line's); the checks of
    `analyze` run first: a velocity the encoder contradicts is an error
    unless forced (then a warning, and the JSON equals the command
    line's), and without one the encoder's guides the detection."""
    cli("passage", recs / "r3.csv", recs / "r4.csv", "--velocity", "9", "--window", "2.5:15",
        "--no-report", "--out", tmp / "w")
    p = ballpass.passages([recs / "r3.csv", recs / "r4.csv"], velocity_mm_s=9.0,
                          window=(2.5, 15))
    assert p.to_dict() == read_json(tmp / "w" / "passage.json")
    assert_table_equals_csv(p.table, tmp / "w" / "passages.csv")
    assert p.window.start_s == 2.5 and p.window.end_s == 15.0
    times = p.records[0].table.time_s
    assert times.min() >= 2.5 and times.max() < 15.0
    # an open end, and the window as the command line's text
    q = ballpass.passages(recs / "r3.csv", velocity_mm_s=9.0, window=(None, 10))
    assert q.to_dict() == ballpass.passages(recs / "r3.csv", velocity_mm_s=9.0,
                                            window=":10").to_dict()
    assert q.records[0].table.time_s.max() < 10.0
    with pytest.raises(ValueError, match="window"):
        ballpass.passages(recs / "r3.csv", velocity_mm_s=9.0, window=(5, 2))
    rec = ballpass.load(recs / "r3.csv")
    with pytest.raises(ValueError, match="encoder"):
        ballpass.passages(rec, velocity_mm_s=12.0)
    with pytest.warns(ballpass.BallpassWarning, match="as forced"):
        forced = ballpass.passages(rec, velocity_mm_s=12.0, force_velocity=True)
    cli("passage", recs / "r3.csv", "--velocity", "12", "--force-velocity", "--no-report",
        "--out", tmp / "f")
    assert forced.to_dict() == read_json(tmp / "f" / "passage.json")
    bare = ballpass.Recording(rec.fs_hz, friction_n=rec.friction_n, position_mm=rec.position_mm,
                              optical_v=rec.optical_v)
    measured = ballpass.passages(bare)
    assert measured.records[0].velocity_source == "measured from the encoder"


def test_predict_equals_the_cli(cli):
    out = json.loads(cli("predict", "-v", "1:3:0.5", "--harmonics", "3", "--json"))
    p = ballpass.predict([1.0, 1.5, 2.0, 2.5, 3.0], harmonics=3)
    assert p.to_dict() == out
    assert np.array_equal(p.table.f_c_hz, [q["f_c_hz"] for q in out["predictions"]])
    custom = json.loads(cli("predict", "-v", "9", "--balls", "30", "--json"))
    assert ballpass.predict(9, balls_in_race=30).to_dict() == custom


def test_models_equal_the_cli(cli, tmp):
    cases = [
        (["signals", "--f-c", "1.2", "--convention", "eq612", "--points", "51"],
         lambda: ballpass.model.signals(1.2, convention="eq612", points=51), "signals.json"),
        (["signals", "--velocity", "9"], lambda: ballpass.model.signals(velocity_mm_s=9),
         "signals.json"),
        (["pulses", "--velocity", "9", "--ratio", "0.3", "--ratio-kind", "fwhm", "--order", "7"],
         lambda: ballpass.model.pulses(0.3, ratio_kind="fwhm", velocity_mm_s=9, order=7),
         "pulses.json"),
        (["stage", "--mass", "5", "--kp", "2000", "--kd", "50"],
         lambda: ballpass.model.stage(5, kp=2000, kd=50), "stage.json"),
        (["stage", "--mass", "5", "--natural-frequency", "1.1", "--damping", "0.35",
          "--velocity", "9", "--period-points", "100"],
         lambda: ballpass.model.stage(5, natural_frequency_hz=1.1, damping=0.35,
                                      velocity_mm_s=9, period_points=100), "stage.json"),
    ]
    for i, (args, fn, json_name) in enumerate(cases):
        d = tmp / f"m{i}"
        cli("model", *args, "--no-report", "--out", d)
        m = fn()
        assert m.to_dict() == read_json(d / json_name), args
        for name, table in m.tables.items():
            assert_table_equals_csv(table, d / f"{name}.csv")


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    """A small campaign: a sweep of sr25w (5, 10, 20 mm/s) and a batch of
    four bearings at 20 mm/s, bearing3 sticking; 10 s records, 2 repeats."""
    d = tmp_path_factory.mktemp("fleet")
    rows = ["path,bearing,velocity_mm_s,repeat,condition"]
    seed = 100
    for v in (5, 10, 20):
        for r in (1, 2):
            seed += 1
            rec, _ = ballpass.simulate(v, seed=seed, duration_s=10)
            rec.to_csv(d / f"sweep_v{v}_r{r}.csv")
            rows.append(f"sweep_v{v}_r{r}.csv,sr25w,{v},{r},good")
    for b in (1, 2, 3, 4):
        cond = "sticking" if b == 3 else "good"
        for r in (1, 2):
            seed += 1
            rec, _ = ballpass.simulate(20, seed=seed, duration_s=10, condition=cond)
            rec.to_csv(d / f"b{b}_r{r}.csv")
            rows.append(f"b{b}_r{r}.csv,bearing{b},20,{r},{cond}")
    (d / "manifest.csv").write_text("\n".join(rows) + "\n")
    return d


def test_sweep_and_diagnose_equal_the_cli(fleet, cli, tmp):
    m = fleet / "manifest.csv"
    cli("sweep", m, "--no-report", "--out", tmp / "s")
    s = ballpass.sweep(m)
    assert s.to_dict() == read_json(tmp / "s" / "sweep.json")
    # every flag away from its default, so that a keyword lost on the way
    # to the library shows as a different diagnosis.json (settings included)
    cli("diagnose", m, "--no-report", "--out", tmp / "d", "--low-band", "30",
        "--spike-spreads", "7", "--bad-false-alarm", "1e-3")
    d = ballpass.diagnose(m, low_band_hz=30.0, spike_spreads=7.0, bad_false_alarm=1e-3,
                          threads=2)
    want = read_json(tmp / "d" / "diagnosis.json")
    assert d.to_dict() == want
    assert_table_equals_csv(d.friction_spectra, tmp / "d" / "friction_spectra.csv")
    verdicts = {b.bearing: b.verdict for b in d.result.bearings}
    assert verdicts["bearing3"] == "bad", verdicts


def test_campaigns_take_a_window_and_force_velocity(fleet, cli, tmp):
    """`sweep`, `diagnose` and the split diagnosis with `--window` and
    `--force-velocity` equal the command line's (settings included)."""
    m = fleet / "manifest.csv"
    cli("sweep", m, "--window", "1:9", "--force-velocity", "--no-report", "--out", tmp / "s")
    s = ballpass.sweep(m, window=(1, 9), force_velocity=True)
    assert s.to_dict() == read_json(tmp / "s" / "sweep.json")
    assert s.settings.window.start_s == 1.0 and s.settings.preflight.force_velocity
    cli("diagnose", m, "--window", "2:", "--no-report", "--out", tmp / "d")
    d = ballpass.diagnose(m, window=(2, None))
    assert d.to_dict() == read_json(tmp / "d" / "diagnosis.json")
    assert d.to_dict() != ballpass.diagnose(m).to_dict()
    entries = [e for e in ballpass.read_manifest(m).entries
               if e.velocity_mm_s == 20 and e.bearing != "sr25w"]
    parts = [ballpass.process_record(e.path, bearing=e.bearing, velocity_mm_s=e.velocity_mm_s,
                                     repeat=e.repeat, condition=e.condition, window=(2, None))
             for e in entries]
    split = ballpass.diagnose_records(parts, source=d.source, selection=d.selection,
                                      window=(2, None))
    for key in ("result", "record_results", "settings"):
        assert split.to_dict()[key] == d.to_dict()[key], key


def test_campaigns_segment_a_multi_speed_run_as_the_cli(cli, tmp):
    """``segment=True`` is ``--segment``: two simulated lab runs (42, 83 and
    125 mm/s forward and back in 25 s, velocities left empty) give a sweep
    and a diagnosis equal to the command line's, each plateau a record at
    its measured speed."""
    rows = ["path,bearing,velocity_mm_s,repeat"]
    for b in (1, 2):
        cli("simulate", "--multi-speed", "--duration", "25", "--seed", 40 + b,
            "-o", tmp / f"b{b}.csv")
        rows.append(f"b{b}.csv,b{b},,1")
    m = tmp / "manifest.csv"
    m.write_text("\n".join(rows) + "\n")
    cli("sweep", m, "--segment", "--only-bearing", "b1", "--no-report", "--out", tmp / "s")
    s = ballpass.sweep(m, segment=True, only_bearings=["b1"])
    assert s.to_dict() == read_json(tmp / "s" / "sweep.json")
    plateaus = [r["plateau"] for r in s.to_dict()["record_results"]]
    assert len(plateaus) == 6 and all(p is not None for p in plateaus)
    assert {p["direction"] for p in plateaus} == {"forward", "backward"}
    cli("diagnose", m, "--segment", "--no-report", "--out", tmp / "d")
    d = ballpass.diagnose(m, segment=True)
    assert d.to_dict() == read_json(tmp / "d" / "diagnosis.json")
    # without it, an empty velocity is a failed record that says how (the
    # sweep takes one bearing: one record)
    failed = ballpass.sweep(m).to_dict()["failed"]
    assert len(failed) == 1 and "--segment" in failed[0]["reason"], failed


def test_diagnosis_split_into_records_and_batch_equals_the_whole(fleet):
    """process_record on each record (anywhere, pickled in between) and
    diagnose_records on the lot give the diagnose verdicts."""
    flags = {"low_band_hz": 30.0, "spike_spreads": 7.0}
    whole = ballpass.diagnose(fleet / "manifest.csv", bad_false_alarm=1e-3, **flags)
    entries = ballpass.read_manifest(fleet / "manifest.csv").entries
    chosen = [e for e in entries if e.velocity_mm_s == 20 and e.bearing != "sr25w"]
    parts = [pickle.loads(pickle.dumps(
        ballpass.process_record(e.path, bearing=e.bearing, velocity_mm_s=e.velocity_mm_s,
                                repeat=e.repeat, condition=e.condition, **flags)))
        for e in chosen]
    # the per-period heights travel beside the JSON, which leaves them out
    for p in parts:
        st = p.to_dict()["sticking"]
        assert st is not None and "times_s" not in st and "heights_n" not in st
        assert len(p.sticking_heights_n) == st["periods"] > 10
    split = ballpass.diagnose_records(parts, source=whole.source, selection=whole.selection,
                                      bad_false_alarm=1e-3, **flags)
    assert split.to_dict()["result"] == whole.to_dict()["result"]
    assert split.to_dict()["record_results"] == whole.to_dict()["record_results"]
    assert split.to_dict()["settings"] == whole.to_dict()["settings"]
    # a result rebuilt without its heights is refused, not diagnosed on nothing
    bare = ballpass.RecordResult(parts[0].to_dict(), parts[0].friction_psd_freq_hz,
                                 parts[0].friction_psd)
    with pytest.raises(ValueError, match="sticking_heights_n has 0 values"):
        ballpass.diagnose_records([bare])
    with pytest.raises(ValueError, match="unknown field `spike_factor`"):
        ballpass.diagnose(fleet / "manifest.csv", settings={"spike_factor": 7.0})


# ---------------------------------------------------------------- Python-only


def test_recording_from_arrays_and_pickle():
    t = np.arange(5000) / 1000.0
    rec = ballpass.Recording(1000.0, friction_n=np.sin(t).astype(np.float32),
                             position_mm=(9.0 * t).tolist(), velocity_mm_s=9.0,
                             test_id="x")
    assert rec.channels == ["friction_N", "position_mm"] and rec.optical_v is None
    assert rec.friction_n.dtype == np.float64 and np.array_equal(rec.time_s, t)
    back = pickle.loads(pickle.dumps(rec))
    assert np.array_equal(back.position_mm, rec.position_mm) and back.test_id == "x"
    rec.velocity_mm_s = 8.0
    assert rec.velocity_mm_s == 8.0


def test_bad_input_is_a_clear_value_error(tmp):
    with pytest.raises(ValueError, match="friction_N.*sample 3"):
        ballpass.Recording(1000.0, friction_n=[0, 1, 2, np.nan] + [0] * 20)
    with pytest.raises(ValueError, match="position_mm.*has 10 samples"):
        ballpass.Recording(1000.0, friction_n=np.zeros(20), position_mm=np.zeros(10))
    with pytest.raises(ValueError, match="fs"):
        ballpass.Recording(-1.0, friction_n=np.zeros(20))
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        ballpass.load(tmp / "nope.csv")
    (tmp / "bad.csv").write_text("time_s,friction_N\n0,1\n0.001,x\n")
    with pytest.raises(ValueError, match=r"bad.csv:3"):
        ballpass.load(tmp / "bad.csv")
    rec, _ = ballpass.simulate(9.0, duration_s=10)
    with pytest.raises(ValueError, match="lowpas"):
        ballpass.analyze(rec, lowpas_hz=20)
    with pytest.raises(ValueError, match="nperseg"):
        ballpass.analyze(rec, nperseg=1)
    with pytest.raises(ValueError, match="unknown bearing"):
        ballpass.predict(9, bearing="nosuch")
    with pytest.raises(ValueError, match="velocity"):
        ballpass.predict(-1)
    with pytest.raises(TypeError):
        ballpass.load(tmp / "x.csv", colour="red")
    with pytest.raises(ValueError, match="threads"):
        ballpass.ThreadPool(0)


def test_threads_setting_gives_the_same_numbers():
    recs = [ballpass.simulate(9.0, seed=s, duration_s=10)[0] for s in (1, 2, 3)]
    base = ballpass.analyze(recs)
    with ballpass.threads(1) as pool:
        assert pool.threads == 1
        one = ballpass.analyze(recs)
    two = ballpass.analyze(recs, threads=2)
    assert base.to_dict() == one.to_dict() == two.to_dict()
    assert np.array_equal(base.spectra.psd_friction_n2_per_hz, two.spectra.psd_friction_n2_per_hz)


def test_the_gil_is_released_while_computing():
    """A Python thread keeps running while another is inside ballpass: the
    longest pause between its loop iterations stays far below the length of
    the native call (with the GIL held it would be the whole call). The call
    is long (16 M samples, some 0.1-0.5 s) so that an OS scheduling stall of
    a few tens of ms on a loaded machine stays far below half of it (with
    4 M samples a 32 ms stall under load 9 once failed it)."""
    x = np.random.default_rng(0).standard_normal(16_000_000)
    t0 = time.perf_counter()
    bs.welch(x, nperseg=4096)
    call = time.perf_counter() - t0
    done = threading.Event()

    def work():
        bs.welch(x, nperseg=4096)
        done.set()

    th = threading.Thread(target=work)
    stamps = []
    th.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
    th.join()
    gaps = np.diff(stamps) if len(stamps) > 1 else np.array([call])
    assert len(stamps) > 100 and gaps.max() < 0.5 * call, (len(stamps), gaps.max(), call)


def test_results_are_read_only_json_with_arrays():
    rec, _ = ballpass.simulate(9.0, duration_s=10)
    a = ballpass.analyze(rec)
    with pytest.raises(AttributeError):
        a.fs_hz = 1.0
    d = a.to_dict()
    d["fs_hz"] = 0
    assert a.fs_hz == 1000.0
    assert set(a.keys()) == set(d)
    assert json.loads(a.to_json()) == a.to_dict()
    assert a.correlations.to_pandas().shape[0] == 19999 if _has_pandas() else True


def _has_pandas():
    try:
        import pandas  # noqa: F401
    except ImportError:
        return False
    return True
