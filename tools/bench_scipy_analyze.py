#!/usr/bin/env python3
"""Speed of `ballpass analyze` against the SciPy reference, same record.

Times (best of N, wall clock):
  * the SciPy reference `tools/reference_analyze.py` in-process (CSV read to
    the four CSV files written), as its `--time` flag does;
  * the whole `ballpass analyze` process (start to exit, no report), N runs,
    interleaved with the reference runs so that both see the same machine load;
  * `ballpass analyze` with five copies of the record (repeats).

Usage: python3 tools/bench_scipy_analyze.py REC.csv --velocity 9 [--bin target/release/ballpass] [-n 7]
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import reference_analyze as ref  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rec")
    ap.add_argument("--velocity", type=float, required=True)
    ap.add_argument("--bin", default="target/release/ballpass")
    ap.add_argument("-n", type=int, default=7)
    a = ap.parse_args()
    tmp = pathlib.Path(tempfile.mkdtemp())
    five = []
    for i in range(5):
        p = tmp / f"rep{i}.csv"
        shutil.copy(a.rec, p)
        five.append(str(p))
    ref_args = ref_namespace(a.velocity, tmp / "ref")

    def scipy_once():
        fs, fr, pos, opt = ref.load_csv(a.rec)
        _, corr, full, hires, unfiltered = ref.analyze(fs, fr, pos, opt, ref_args)
        ref.write_csv(tmp / "ref" / "correlations.csv", ref.correlation_table(corr, ref_args.corr_norm))
        ref.write_csv(tmp / "ref" / "spectra.csv", ref.spectrum_table(full))
        ref.write_csv(tmp / "ref" / "spectra_hires.csv", ref.spectrum_table(hires))
        ref.write_csv(tmp / "ref" / "spectra_unfiltered.csv", ref.spectrum_table(unfiltered))

    def proc(recs):
        cmd = [a.bin, "analyze", *recs, "--velocity", str(a.velocity), "--no-report", "--out", str(tmp / "bp")]
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)

    (tmp / "ref").mkdir()
    best = {"scipy_in_process_s": 1e9, "ballpass_process_s": 1e9, "ballpass_process_5_repeats_s": 1e9}
    for _ in range(a.n):
        best["scipy_in_process_s"] = min(best["scipy_in_process_s"], timed(scipy_once))
        best["ballpass_process_s"] = min(best["ballpass_process_s"], timed(lambda: proc([a.rec])))
        best["ballpass_process_5_repeats_s"] = min(
            best["ballpass_process_5_repeats_s"], timed(lambda: proc(five)))
    best["speedup"] = best["scipy_in_process_s"] / best["ballpass_process_s"]
    best["repeats_ratio"] = best["ballpass_process_5_repeats_s"] / best["ballpass_process_s"]
    print(json.dumps(best, indent=1))
    shutil.rmtree(tmp)


def ref_namespace(velocity, out):
    return argparse.Namespace(
        velocity=velocity, out=str(out), lowpass=20.0, order=5, detrend="linear",
        corr_norm="coeff", nperseg=4096, noverlap=None, q=None, nperseg_hr=None,
        noverlap_hr=None, zoom=None, trim=0.0, d_avg=4.0 + 2.0 / 36.0)


def timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
