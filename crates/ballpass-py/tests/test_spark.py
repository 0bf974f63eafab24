"""examples/spark_fleet.py on Spark local[2]: the same verdicts (the whole
diagnosis.json) as `ballpass diagnose` on the same
manifest.

Needs PySpark (tests requirements) and a JVM: skipped, saying so, only when
no JVM can be found (no `java` on PATH and no JAVA_HOME); .ci/run installs
one where the machine has none. With BALLPASS_WHEEL set (CI), ballpass is
shipped to the executors the way Spark ships native packages: a venv-pack
archive of a virtualenv holding that wheel, unpacked by Spark
(`spark.archives`); the test checks the executors ran its interpreter.
"""

from __future__ import annotations

import importlib.util
import json
import os
import pathlib
import shutil
import sys

import pytest

from conftest import ROOT


def _example(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # importable by name (Spark pickles it by value)
    spec.loader.exec_module(mod)
    return mod


def _have_jvm() -> bool:
    home = os.environ.get("JAVA_HOME")
    return shutil.which("java") is not None or bool(home and (pathlib.Path(home) / "bin" / "java").exists())


pytestmark = pytest.mark.skipif(
    not _have_jvm(), reason="no JVM (java not on PATH, JAVA_HOME unset): Spark cannot start"
)


def test_spark_fleet_gives_the_cli_verdicts(tmp_path, cli):
    import pyspark  # noqa: F401  (a test requirement: fail, not skip, without it)

    make_fleet = _example("make_fleet").make_fleet
    spark_fleet = _example("spark_fleet")
    # A sweep bearing recorded at other velocities too, then the batch: the
    # default selection leaves the sweep bearing out, as the CLI does.
    fleet = tmp_path / "fleet"
    manifest = make_fleet(fleet, bearings=5, repeats=3, duration_s=10.0, sticky=4, fmt="mat")
    extra = make_fleet(tmp_path / "sweep", bearings=1, repeats=2, velocity_mm_s=9.0,
                       duration_s=12.0, sticky=0, fmt="csv", seed=500)
    rows = manifest.read_text().splitlines()
    for line in extra.read_text().splitlines()[1:]:
        path, _, v, r, c = line.split(",")
        rows.append(f"../sweep/{path},bearing001,{v},{r},{c}")
    manifest.write_text("\n".join(rows) + "\n")

    # non-default flags: they must reach both halves on the executors
    cli("diagnose", manifest, "--no-report", "--out", tmp_path / "cli",
        "--spike-spreads", "7", "--bad-false-alarm", "1e-3")
    want = json.loads((tmp_path / "cli" / "diagnosis.json").read_text())

    archive = None
    wheel = os.environ.get("BALLPASS_WHEEL")
    if wheel:
        archive = spark_fleet.pack_environment(pathlib.Path(wheel), tmp_path / "env.tar.gz")
    got = spark_fleet.run(manifest, tmp_path / "spark", master="local[2]", archive=archive,
                          spike_spreads=7.0, bad_false_alarm=1e-3, quiet=True)

    # bearing001 is also recorded at 9 mm/s: left out of the batch (12 records)
    assert got["records"] == want["records"] == 12
    assert any("left out bearing001" in n for n in want["selection"]), want["selection"]
    assert len(got["diagnoses"]) == 1
    diagnosis = got["diagnoses"][0]
    assert diagnosis == want
    verdicts = [(b["rank"], b["bearing"], b["verdict"]) for b in got["bearings"]]
    assert verdicts == [(b["rank"], b["bearing"], b["verdict"])
                        for b in want["result"]["bearings"]]
    assert ("bearing004" in [b for _, b, v in verdicts if v == "bad"]), verdicts

    import pyarrow.parquet as pq

    records = pq.read_table(tmp_path / "spark" / "records.parquet").to_pandas()
    assert len(records) == 12 and records["error"].isna().all()
    if archive is not None:
        # The executors ran the shipped environment's interpreter.
        assert all("environment" in p for p in records["python_prefix"]), set(records["python_prefix"])
