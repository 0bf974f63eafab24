#!/usr/bin/env python3
"""NumPy/SciPy reference of `ballpass analyze`'s numeric steps.

Two uses:
  * parity fixtures: the Rust tests compare every exported correlation and
    spectrum with what this script computes on the same recording (relative
    error <= 1e-9);
  * the speed baseline: `--time` runs the same steps in-process (CSV read to
    files written) and prints the best wall time, to put beside ballpass'.

Steps (the defaults of ballpass' AnalyzeSettings; each is a flag here too):
  1. velocity = np.gradient(position_mm, 1/fs); velocity_error = velocity - V
  2. for friction, velocity_error, optical:
       y = sosfiltfilt(butter(order, lowpass, 'low', fs=fs, output='sos'), x)
       y = detrend(y, type=detrend)
  3. correlations: correlate(x, y, 'full') for the 3 autos and the pairs
     (friction, velocity_error), (friction, optical), (velocity_error, optical);
     lags = correlation_lags(N, N) / fs; normalisation biased / unbiased / coeff / none
  4. full-range spectra on the step-2 signals: welch/csd(nperseg, noverlap,
     window='hann', detrend='constant', scaling='density'), coherence
  5. high-resolution spectra: decimate(step-2 signal, q) (IIR, zero phase),
     then welch/csd/coherence at fs/q with nperseg_hr.

Usage:
  python3 tools/reference_analyze.py REC.csv --velocity 9 --out DIR [--time]
Pinned versions: tools/requirements.txt.
"""
import argparse
import json
import pathlib
import time

import numpy as np
from scipy import signal

PAIRS = [
    ("friction", "friction"),
    ("velocity_error", "velocity_error"),
    ("optical", "optical"),
    ("friction", "velocity_error"),
    ("friction", "optical"),
    ("velocity_error", "optical"),
]


def series_name(a, b):
    return a if a == b else f"{a}__{b}"


def load_csv(path):
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=1)
    header = pathlib.Path(path).read_text().split("\n", 1)[0].strip().lower().split(",")
    cols = {name: data[:, i] for i, name in enumerate(header)}
    t = cols["time_s"]
    fs = 1.0 / np.median(np.diff(t))
    return fs, cols["friction_n"], cols["position_mm"], cols["optical_v"]


def normalise(z, n, how, x, y):
    if how == "none":
        return z
    if how == "biased":
        return z / n
    if how == "unbiased":
        lags = signal.correlation_lags(n, n)
        return z / (n - np.abs(lags))
    if how == "coeff":
        return z / np.sqrt(np.dot(x, x) * np.dot(y, y))
    raise ValueError(how)


def analyze(fs, friction, position, optical, a):
    v = np.gradient(position, 1.0 / fs)
    ve = v - a.velocity
    sos = signal.butter(a.order, a.lowpass, "low", fs=fs, output="sos")
    sig = {}
    for name, x in (("friction", friction), ("velocity_error", ve), ("optical", optical)):
        y = signal.sosfiltfilt(sos, x)
        if a.detrend != "none":
            y = signal.detrend(y, type=a.detrend)
        sig[name] = y
    n = len(friction)
    corr = {"lag_s": signal.correlation_lags(n, n) / fs}
    for p, q in PAIRS:
        z = signal.correlate(sig[p], sig[q], mode="full", method="fft")
        corr[series_name(p, q)] = normalise(z, n, a.corr_norm, sig[p], sig[q])

    def spectra(s, fs_, nperseg, noverlap):
        out = {}
        for p, q in PAIRS:
            if p == q:
                f, pxx = signal.welch(s[p], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                out["freq_hz"] = f
                out[p] = pxx
            else:
                f, pxy = signal.csd(s[p], s[q], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                _, cxy = signal.coherence(s[p], s[q], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                name = series_name(p, q)
                out[name + "_re"] = pxy.real
                out[name + "_im"] = pxy.imag
                out[name + "_coh"] = cxy
        return out

    nperseg = min(a.nperseg, n)
    noverlap = a.noverlap if a.noverlap is not None else nperseg // 2
    full = spectra(sig, fs, nperseg, noverlap)
    dec = {k: signal.decimate(x, a.q, ftype="iir", zero_phase=True) for k, x in sig.items()}
    nd = len(dec["friction"])
    nhr = min(a.nperseg_hr, nd)
    hires = spectra(dec, fs / a.q, nhr, nhr // 2)
    return sig, corr, full, hires


def write_csv(path, table):
    keys = list(table.keys())
    cols = np.column_stack([table[k] for k in keys])
    np.savetxt(path, cols, delimiter=",", header=",".join(keys), comments="", fmt="%.17g")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rec")
    ap.add_argument("--velocity", type=float, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--lowpass", type=float, default=20.0)
    ap.add_argument("--order", type=int, default=5)
    ap.add_argument("--detrend", default="linear", choices=["linear", "constant", "none"])
    ap.add_argument("--corr-norm", default="coeff", choices=["none", "biased", "unbiased", "coeff"])
    ap.add_argument("--nperseg", type=int, default=4096)
    ap.add_argument("--noverlap", type=int, default=None)
    ap.add_argument("--q", type=int, default=20)
    ap.add_argument("--nperseg-hr", type=int, default=256)
    ap.add_argument("--time", action="store_true")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    def once():
        fs, fr, pos, opt = load_csv(a.rec)
        _, corr, full, hires = analyze(fs, fr, pos, opt, a)
        write_csv(out / "correlations.csv", corr)
        write_csv(out / "spectra.csv", full)
        write_csv(out / "spectra_hires.csv", hires)

    if a.time:
        best = min(_timed(once) for _ in range(5))
        print(json.dumps({"reference_analyze_best_s": best}))
    else:
        once()


def _timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
