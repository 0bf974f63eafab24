#!/usr/bin/env python3
"""A bearing fleet on Spark: `ballpass diagnose` scaled out.

    python examples/spark_fleet.py MANIFEST --out DIR [--master local[2]]
        [--low-band HZ] [--spike-spreads K] [--bad-false-alarm P]
        [--env-archive ballpass_env.tar.gz | --pack-wheel ballpass-*.whl]

1. The driver reads the manifest and selects the records as `ballpass
   diagnose` does (by default the velocity with the most bearings).
2. The executors analyse each record (`mapInPandas`): `ballpass.process_record`
   is exactly the per-record work of `ballpass diagnose` (analysis, optical
   passages, the friction of each ball-pass period, friction spectrum). The
   records table is written as Parquet (`DIR/records.parquet`: flat
   scalars, the full result as JSON, the friction spectrum and the
   per-period heights, which the diagnosis pools per bearing).
3. The diagnosis runs per batch (`groupBy(velocity).applyInPandas`):
   `ballpass.diagnose_records` ranks every bearing of the batch against the
   batch median, giving one row per bearing with its verdict and evidence
   (`DIR/diagnosis.parquet`, and the whole answer as `DIR/diagnosis.json`,
   equal to the command line's `diagnosis.json`).
4. The verdicts are printed, worst first, as `ballpass diagnose` prints them.

The verdicts equal `ballpass diagnose MANIFEST`'s (tested in
crates/ballpass-py/tests/test_spark.py).

Shipping ballpass: it is a native (compiled) package, which Spark's
`--py-files` cannot carry; Spark's documented way is a packed Python
environment shipped with `spark.archives` and used by the executors as
`PYSPARK_PYTHON=./environment/bin/python`. `--pack-wheel WHEEL` builds one
(a virtualenv with the wheel, numpy, pandas and pyarrow, packed by
venv-pack); `--env-archive` ships one built before. Without either the
executors use this interpreter (its own ballpass), which is fine for
`local[*]`.

Scaling: each record is independent, so step 2 scales with the executors'
cores until the file system is the limit; give each task one worker thread
(`--threads-per-task 1`, the default) so that executors x cores tasks do not
oversubscribe the machines. Step 3 moves each batch's record results (a few
kB each plus a 2049-bin spectrum and one height per ball-pass period) to one task and is small next to step 2.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import pandas as pd

import ballpass

# Flat columns of the records table (the full result is in `result_json`).
RECORD_SCALARS = [
    ("fs_hz", "double"),
    ("duration_s", "double"),
    ("f_c_predicted_hz", "double"),
    ("f_c_correlation_hz", "double"),
    ("f_c_passages_hz", "double"),
    ("passages", "long"),
    ("tau_c_s", "double"),
    ("tau_p_s", "double"),
    ("tau_ratio", "double"),
    ("velocity_error_std_um_s", "double"),
    ("friction_low_band_power_n2", "double"),
]
RECORDS_SCHEMA = ", ".join(
    ["order long", "path string", "bearing string", "velocity_mm_s double", "repeat int",
     "condition string", "error string"]
    + [f"{k} {t}" for k, t in RECORD_SCALARS]
    + ["sticking_periods long", "sticking_spikes long", "result_json string",
       "friction_psd_freq_hz binary", "friction_psd binary", "sticking_heights_n binary",
       "python_prefix string"]
)
BEARINGS_SCHEMA = ("velocity_mm_s double, rank long, bearing string, verdict string, "
                   "records long, evidence string, bearing_json string, diagnosis_json string")


def analyse_records(settings: dict, threads: int):
    """The mapInPandas function: each manifest row to a records-table row."""

    def run(batches):
        import ballpass as bp  # on the executor

        with bp.threads(threads):
            for pdf in batches:
                rows = []
                for e in pdf.itertuples(index=False):
                    row = {"order": int(e.order), "path": e.path, "bearing": e.bearing,
                           "velocity_mm_s": float(e.velocity_mm_s), "repeat": int(e.repeat),
                           "condition": e.condition, "error": None,
                           "python_prefix": sys.prefix}
                    try:
                        r = bp.process_record(e.path, bearing=e.bearing,
                                              velocity_mm_s=float(e.velocity_mm_s),
                                              repeat=int(e.repeat), condition=e.condition,
                                              **settings)
                    except (ValueError, OSError) as ex:
                        row["error"] = str(ex)
                        rows.append(row)
                        continue
                    d = r.to_dict()
                    for k, _ in RECORD_SCALARS:
                        row[k] = d.get(k)
                    st = d.get("sticking")
                    row["sticking_periods"] = None if st is None else st["periods"]
                    row["sticking_spikes"] = None if st is None else st["spikes"]
                    row["result_json"] = json.dumps(d)
                    # float64 bytes: Arrow and Parquet carry them as they are
                    row["friction_psd_freq_hz"] = r.friction_psd_freq_hz.astype("<f8").tobytes()
                    row["friction_psd"] = r.friction_psd.astype("<f8").tobytes()
                    row["sticking_heights_n"] = r.sticking_heights_n.astype("<f8").tobytes()
                    rows.append(row)
                yield pd.DataFrame(rows, columns=[c.split(" ")[0] for c in RECORDS_SCHEMA.split(", ")])

    return run


def diagnose_batch(source: str, notes: list[str], settings: dict):
    """The applyInPandas function: one batch's records to one row per bearing."""

    def run(pdf: pd.DataFrame) -> pd.DataFrame:
        import ballpass as bp  # on the executor

        pdf = pdf.sort_values("order")  # manifest order, as ballpass diagnose
        ok = pdf[pdf["error"].isna()]
        f64 = np.dtype("<f8")
        records = [bp.RecordResult(json.loads(j), np.frombuffer(f, f64), np.frombuffer(p, f64),
                                   np.frombuffer(h, f64))
                   for j, f, p, h in zip(ok["result_json"], ok["friction_psd_freq_hz"],
                                         ok["friction_psd"], ok["sticking_heights_n"])]
        failed = [(r.path, r.bearing, r.velocity_mm_s, r.repeat, r.error)
                  for r in pdf[pdf["error"].notna()].itertuples(index=False)]
        d = bp.diagnose_records(records, failures=failed, source=source, selection=notes,
                                **settings)
        whole = d.to_json(indent=None)
        out = []
        for i, b in enumerate(d.to_dict()["result"]["bearings"]):
            out.append({
                "velocity_mm_s": float(pdf["velocity_mm_s"].iloc[0]),
                "rank": b["rank"], "bearing": b["bearing"], "verdict": b["verdict"],
                "records": b["records"], "evidence": "; ".join(b["evidence"]),
                "bearing_json": json.dumps(b),
                # the batch's whole answer once, on its first row
                "diagnosis_json": whole if i == 0 else None,
            })
        return pd.DataFrame(out)

    return run


def pack_environment(wheel: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    """A venv-pack archive of a virtualenv holding `wheel` and what the
    executors' pandas UDFs need (numpy, pandas, pyarrow at this
    interpreter's versions)."""
    import pyarrow

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="ballpass-env-"))
    env = tmp / "env"
    subprocess.run([sys.executable, "-m", "venv", str(env)], check=True)
    pip = [str(env / "bin" / "python"), "-m", "pip", "install", "-q"]
    subprocess.run(pip + [str(wheel), f"numpy=={np.__version__}",
                          f"pandas=={pd.__version__}", f"pyarrow=={pyarrow.__version__}",
                          "venv-pack"], check=True)
    out.unlink(missing_ok=True)
    subprocess.run([str(env / "bin" / "venv-pack"), "-p", str(env), "-o", str(out), "-q",
                    "--compress-level", "1"], check=True)
    shutil.rmtree(tmp, ignore_errors=True)
    return out


def spark_session(master: str, archive: pathlib.Path | None, app: str = "ballpass-fleet"):
    from pyspark import SparkFiles
    from pyspark.sql import SparkSession

    if __name__ != "__main__":
        # Imported (tests, notebooks): ship this module's functions by value,
        # as Spark does for a script's, since executors cannot import it.
        from pyspark import cloudpickle

        cloudpickle.register_pickle_by_value(sys.modules[__name__])
    local = master.startswith("local")
    if archive is not None and not local:
        # Executors unpack the archive into their working directory.
        os.environ["PYSPARK_PYTHON"] = "./environment/bin/python"
    else:
        os.environ.setdefault("PYSPARK_PYTHON", sys.executable)
    os.environ.setdefault("PYSPARK_DRIVER_PYTHON", sys.executable)
    b = (SparkSession.builder.master(master).appName(app)
         .config("spark.ui.enabled", "false")
         .config("spark.ui.showConsoleProgress", "false")
         .config("spark.sql.shuffle.partitions", "4")
         .config("spark.sql.execution.arrow.maxRecordsPerBatch", "64"))
    if archive is not None:
        b = b.config("spark.archives", f"{archive}#environment")
    spark = b.getOrCreate()
    spark.sparkContext.setLogLevel("ERROR")
    if archive is not None and local:
        # local[*] runs the executor in the driver's process, whose working
        # directory is not where Spark unpacked the archive: point the
        # Python workers at the unpacked environment itself.
        spark.sparkContext.pythonExec = str(
            pathlib.Path(SparkFiles.getRootDirectory()) / "environment" / "bin" / "python")
    return spark


def run(manifest: pathlib.Path, out: pathlib.Path, *, master: str = "local[2]",
        archive: pathlib.Path | None = None, threads_per_task: int = 1,
        partitions: int | None = None, only_bearings=(), only_velocities=(),
        lowpass_hz: float = 20.0, harmonics: int = 5, low_band_hz: float = 25.0,
        spike_spreads: float = 8.0, bad_false_alarm: float = 1e-4,
        quiet: bool = False) -> dict:
    """Runs the pipeline; returns {"records", "seconds", "records_per_s",
    "bearings": [bearing rows]} and writes DIR/records.parquet,
    DIR/diagnosis.parquet and DIR/diagnosis.json."""
    out.mkdir(parents=True, exist_ok=True)
    sel = ballpass.select(manifest, "diagnose", only_bearings=only_bearings,
                          only_velocities=only_velocities)
    entries = sel.to_dict()["entries"]
    notes = sel.to_dict()["notes"]
    # ballpass diagnose's flags: the per-record ones, then the batch's too
    settings = {"lowpass_hz": lowpass_hz, "harmonics": harmonics,
                "low_band_hz": low_band_hz, "spike_spreads": spike_spreads}
    batch_settings = dict(settings, bad_false_alarm=bad_false_alarm)
    spark = spark_session(master, archive)
    try:
        t0 = time.perf_counter()
        pdf = pd.DataFrame([{
            "order": i, "path": str(pathlib.Path(e["path"]).resolve()), "bearing": e["bearing"],
            "velocity_mm_s": float(e["velocity_mm_s"]), "repeat": int(e["repeat"]),
            "condition": e["condition"]} for i, e in enumerate(entries)])
        df = spark.createDataFrame(pdf)
        n_parts = partitions or max(1, min(len(entries), 4 * spark.sparkContext.defaultParallelism))
        df = df.repartition(n_parts)
        records = df.mapInPandas(analyse_records(settings, threads_per_task), RECORDS_SCHEMA)
        records_path = out / "records.parquet"
        records.write.mode("overwrite").parquet(str(records_path))
        t_records = time.perf_counter() - t0
        stored = spark.read.parquet(str(records_path))
        bearings = (stored.groupBy("velocity_mm_s")
                    .applyInPandas(diagnose_batch(sel.source, notes, batch_settings), BEARINGS_SCHEMA))
        diag_path = out / "diagnosis.parquet"
        bearings.write.mode("overwrite").parquet(str(diag_path))
        rows = (spark.read.parquet(str(diag_path))
                .orderBy("velocity_mm_s", "rank").collect())
        seconds = time.perf_counter() - t0
    finally:
        spark.stop()
    batches = [json.loads(r["diagnosis_json"]) for r in rows if r["diagnosis_json"]]
    if len(batches) == 1:
        (out / "diagnosis.json").write_text(json.dumps(batches[0], indent=2) + "\n")
    result = {"records": len(entries), "seconds": seconds,
              "records_per_s": len(entries) / seconds, "records_stage_s": t_records,
              "bearings": [r.asDict() for r in rows], "diagnoses": batches}
    if not quiet:
        print(f"{len(entries)} records in {seconds:.2f} s on {master} "
              f"({result['records_per_s']:.1f} records/s; analysis and records table "
              f"{t_records:.2f} s, diagnosis {seconds - t_records:.2f} s)")
        for n in notes:
            print(f"  {n}")
        for r in rows:
            print(f"#{r['rank']} {r['bearing']:<12} {r['verdict']:<8} {r['evidence']}")
        print(f"wrote {out}/records.parquet, diagnosis.parquet, diagnosis.json")
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("manifest", type=pathlib.Path)
    ap.add_argument("--out", type=pathlib.Path, required=True)
    ap.add_argument("--master", default="local[2]")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--env-archive", type=pathlib.Path,
                   help="packed Python environment with ballpass (venv-pack / conda-pack)")
    g.add_argument("--pack-wheel", type=pathlib.Path,
                   help="build that environment from this ballpass wheel first")
    ap.add_argument("--threads-per-task", type=int, default=1)
    ap.add_argument("--partitions", type=int, default=None)
    ap.add_argument("--only-bearing", action="append", default=[])
    ap.add_argument("--only-velocity", action="append", type=float, default=[])
    ap.add_argument("--lowpass", type=float, default=20.0)
    ap.add_argument("--harmonics", type=int, default=5)
    ap.add_argument("--low-band", type=float, default=25.0, metavar="HZ")
    ap.add_argument("--spike-spreads", type=float, default=8.0, metavar="K")
    ap.add_argument("--bad-false-alarm", type=float, default=1e-4, metavar="P")
    a = ap.parse_args()
    archive = a.env_archive
    if a.pack_wheel is not None:
        archive = pack_environment(a.pack_wheel, a.out.with_suffix(".env.tar.gz"))
    run(a.manifest, a.out, master=a.master, archive=archive,
        threads_per_task=a.threads_per_task, partitions=a.partitions,
        only_bearings=a.only_bearing, only_velocities=a.only_velocity,
        lowpass_hz=a.lowpass, harmonics=a.harmonics, low_band_hz=a.low_band,
        spike_spreads=a.spike_spreads, bad_false_alarm=a.bad_false_alarm)


if __name__ == "__main__":
    main()
