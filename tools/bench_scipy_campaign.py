#!/usr/bin/env python3
"""Time the campaign work of `ballpass sweep` + `ballpass diagnose` done the
NumPy/SciPy way: a loop over the manifest's files, each read once and put
through the same steps (pinned versions: tools/requirements.txt).

Per file: np.loadtxt; velocity error (np.gradient); 5th-order Butterworth
20 Hz sosfiltfilt + linear detrend of the three signals; the six full-lag
correlations (signal.correlate, fft) normalised; full-range welch/csd/coherence
(nperseg 4096); decimate(q=20) and hi-res welch/csd/coherence; ball passages
as ballpass detects them (`detect` of tools/bench_scipy_passage.py: robust
noise, running 10th-percentile baseline, Gaussian smoothing, find_peaks +
peak_widths on the pulses up and down; until session 3 this was a lighter
single find_peaks over a global percentile baseline, less work than ballpass
does); sticking spikes (find_peaks on friction minus its
block-median baseline). Then the per-velocity and per-bearing tables are
trivial in comparison and left out (that favours SciPy).

Usage: python3 tools/bench_scipy_campaign.py CAMPAIGN_DIR/manifest.csv [--ballpass BIN] [-n N]
Prints the total wall time, one core. With --ballpass (e.g.
target/release/ballpass), also times `BIN sweep` + `BIN diagnose` on the same
manifest (--no-report, best of N each, run before and after the SciPy loop so
that both see the same machine) and prints the ratio.

Session 2 figures (idle machine, load ~1, simulated campaign of 150 records):
sweep 0.31 s + diagnose 0.16 s = 0.48 s vs SciPy 7.73 s, 16.1x (earlier run:
0.49 s vs 7.54 s, 15.4x). On the session's final main (peaks and csd work
merged), three runs, load ~1.5: 0.46 / 0.50 / 0.48 s vs 8.74 / 8.80 / 8.30 s,
19.0x / 17.5x / 17.5x (the SciPy loop's own time varies by 15 % between runs).
"""
import argparse
import csv
import json
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy import signal

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import bench_scipy_passage as bp  # noqa: E402
import reference_analyze as ra  # noqa: E402


class Args:
    lowpass = 20.0
    order = 5
    detrend = "linear"
    corr_norm = "coeff"
    nperseg = 4096
    noverlap = None
    q = 20
    nperseg_hr = None
    noverlap_hr = None
    trim = 0.0
    zoom = None
    d_avg = 4.0 + 2.0 / 36.0


def one(path, velocity):
    fs, fr, pos, opt = ra.load_csv(path)
    a = Args()
    a.velocity = velocity
    f_c = velocity / (2 * a.d_avg)
    ra.analyze(fs, fr, pos, opt, a)
    tau = 1.0 / f_c
    # Ball passages as ballpass detects them (running-percentile baseline,
    # robust noise, Gaussian smoothing, pulses up and down).
    bp.detect(opt, fs, velocity)
    block = max(8, int(round(tau * fs / 2)))
    med = np.array([np.median(fr[i:i + block]) for i in range(0, len(fr), block)])
    centres = np.arange(len(med)) * block + (block - 1) / 2
    resid = fr - np.interp(np.arange(len(fr)), centres, med)
    level = 1.4826 * np.median(np.abs(resid - np.median(resid)))
    signal.find_peaks(resid, height=8 * level, distance=max(1, int(0.5 * tau * fs)))


def ballpass_best(binary, manifest, n):
    """Best wall time of `sweep` and of `diagnose` over n runs each."""
    best = {}
    with tempfile.TemporaryDirectory() as out:
        for _ in range(n):
            for cmd in ("sweep", "diagnose"):
                t0 = time.perf_counter()
                subprocess.run(
                    [binary, cmd, str(manifest), "--out", f"{out}/{cmd}", "--no-report"],
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                    check=True,
                )
                dt = time.perf_counter() - t0
                best[cmd] = min(best.get(cmd, dt), dt)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("manifest")
    ap.add_argument("--ballpass", help="ballpass binary to time beside SciPy")
    ap.add_argument("-n", type=int, default=5)
    a = ap.parse_args()
    manifest = pathlib.Path(a.manifest)
    rows = list(csv.DictReader(manifest.open()))
    before = ballpass_best(a.ballpass, manifest, a.n) if a.ballpass else None
    t0 = time.perf_counter()
    for r in rows:
        one(manifest.parent / r["path"], float(r["velocity_mm_s"]))
    dt = time.perf_counter() - t0
    result = {"records": len(rows), "scipy_campaign_s": dt}
    if a.ballpass:
        after = ballpass_best(a.ballpass, manifest, a.n)
        best = {k: min(before[k], after[k]) for k in before}
        total = best["sweep"] + best["diagnose"]
        result.update(
            {
                "ballpass_sweep_s": best["sweep"],
                "ballpass_diagnose_s": best["diagnose"],
                "ballpass_total_s": total,
                "speedup": dt / total,
            }
        )
    print(json.dumps(result))


if __name__ == "__main__":
    main()
