#!/usr/bin/env python3
"""The SciPy script a user would write for `ballpass analyze` on a long record.

The steps of tools/reference_analyze.py (gradient, Butterworth sosfiltfilt,
linear detrend, the six correlations, full-range and unfiltered Welch/CSD/
coherence, decimate + high-resolution Welch), on one CSV record, with the
correlations written only within the same lag window as ballpass
(`--max-lag`, s): SciPy's `correlate(method='fft')` has no lag window, so
the script computes every lag and slices, as a SciPy user would.

It prints one JSON line: wall seconds of the whole run (CSV read to the
four CSV files written). Peak memory is measured from outside
(`/usr/bin/time -v`, see crates/ballpass-cli/benches/long_record.rs).

Usage:
  python3 tools/bench_scipy_long.py REC.csv --velocity 9 --max-lag 90 --out DIR
Pinned versions: tools/requirements.txt.
"""
import argparse
import json
import pathlib
import sys
import time

import numpy as np
from scipy import signal

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import reference_analyze as ref  # noqa: E402


def load_csv(path):
    """The four columns by their header names; fs from the time span."""
    with open(path) as f:
        header = f.readline().strip().lower().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    cols = {name: data[:, i] for i, name in enumerate(header)}
    t = cols["time_s"]
    fs = float(f"{(len(t) - 1) / (t[-1] - t[0]):.12g}")
    return fs, cols["friction_n"], cols["position_mm"], cols["optical_v"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rec")
    ap.add_argument("--velocity", type=float, required=True)
    ap.add_argument("--max-lag", type=float, required=True, help="lag window, s")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    t0 = time.perf_counter()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    fs, fr, pos, opt = load_csv(a.rec)
    args = argparse.Namespace(
        velocity=a.velocity, lowpass=20.0, order=5, detrend="linear", corr_norm="coeff",
        nperseg=4096, noverlap=None, q=None, nperseg_hr=None, noverlap_hr=None, zoom=None,
        trim=0.0, d_avg=4.0 + 2.0 / 36.0)
    _, corr, full, hires, unfiltered = ref.analyze(fs, fr, pos, opt, args)
    del fr, pos, opt
    lag = int(round(a.max_lag * fs))
    zero = len(corr["lag_s"]) // 2
    window = {k: v[max(zero - lag, 0):zero + lag + 1] for k, v in corr.items()}
    ref.write_csv(out / "correlations.csv", ref.correlation_table(window, "coeff"))
    ref.write_csv(out / "spectra.csv", ref.spectrum_table(full))
    ref.write_csv(out / "spectra_hires.csv", ref.spectrum_table(hires))
    ref.write_csv(out / "spectra_unfiltered.csv", ref.spectrum_table(unfiltered))
    print(json.dumps({"seconds": time.perf_counter() - t0, "fs_hz": fs}))


if __name__ == "__main__":
    main()
