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
does); the per-record numbers of the analysis (`scalars`: measured period
from the autocorrelation peaks, phases from the correlations and the
cross-spectra, harmonics against their chi-square floors and coherence at
k f_c, velocity-error spread: ~0.7-1.1 ms of ~55 ms per record, added in
session 3); sticking spikes (find_peaks on friction minus its block-median
baseline). Then the per-velocity and per-bearing tables are trivial in
comparison and left out (that favours SciPy).

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

Session 3 (quiet machine, load ~1.2-1.7, this script with the faithful
passage detection and the per-record numbers): mid-session main 0.447 s
(sweep 0.292 + diagnose 0.154) vs SciPy 8.39 s, 18.8x; again 0.439 s vs
8.26 s, 18.8x. The session's final main (correlation energies once per
signal, spectra kept), five runs: 0.446 / 0.462 / 0.435 / 0.435 / 0.430 s
vs 8.76 / 9.35 / 8.87 / 8.77 / 8.62 s = 19.6x / 20.2x / 20.4x / 20.2x /
20.0x (median 20.2x). The same kind of binary against the session-2 script
(lighter SciPy work: one find_peaks for the passages, no per-record
numbers) measured 17.0x mid-session. Session-2 main against this script:
0.483 s (sweep 0.317 + diagnose 0.166) in the same minutes.
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
from scipy import signal, stats

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


def parabola(a, b, c):
    den = a - 2.0 * b + c
    return 0.0 if den == 0 else max(-0.5, min(0.5, 0.5 * (a - c) / den))


def period(r, zero, fs, tau):
    """Autocorrelation peaks near k T (window +-T/4, k T within half the
    record), parabolic refinement, T re-fitted through the origin."""
    t, ks, lags, k = tau, [], [], 1
    while k * t <= 0.5 * zero / fs:
        c, w = zero + int(round(k * t * fs)), int(round(0.25 * t * fs))
        lo, hi = max(c - w, zero + 1), min(c + w, len(r) - 2)
        if hi <= lo:
            break
        i = lo + int(np.argmax(r[lo:hi + 1]))
        if lo < i < hi and r[i] > 0:
            ks.append(k)
            lags.append((i - zero + parabola(r[i - 1], r[i], r[i + 1])) / fs)
            kk = np.array(ks, float)
            t = float(np.dot(kk, lags) / np.dot(kk, kk))
        k += 1
    return t if ks else None


def harmonic(f, psd, fk, f_c, med_ratio, thr_ratio):
    """PSD at fk (largest of the +-1 bins) against the median floor over
    +-1.5 f_c without the bins near any harmonic, chi-square scaled."""
    df = f[1] - f[0]
    i = int(round(fk / df))
    if i < 1 or i + 1 >= len(psd):
        return None
    p = psd[i - 1:i + 2].max()
    j = np.arange(max(int(np.ceil((fk - 1.5 * f_c) / df)), 1),
                  min(int(np.floor((fk + 1.5 * f_c) / df)), len(psd) - 1) + 1)
    fj = j * df
    keep = np.abs(fj - np.round(fj / f_c) * f_c) > 1.5 * df
    if keep.sum() < 3:
        return None
    floor = np.median(psd[j[keep]]) / med_ratio
    return 10 * np.log10(p / floor), p / floor > thr_ratio


def scalars(fs, sig, corr, hires, f_c, nperseg_hr, nd, velocity_error_raw):
    """The per-record numbers ballpass' analysis reports: measured period,
    phases (correlation and cross-spectrum), harmonics and coherence at
    k f_c with their chi-square thresholds, velocity-error spread."""
    n = len(sig["friction"])
    zero = n - 1
    tau = 1.0 / f_c
    periods = {s: period(corr[s], zero, fs, tau) for s in ("friction", "velocity_error", "optical")}
    t = next((p for p in periods.values() if p), tau)
    f_used = 1.0 / t
    h = int(round(0.5 * t * fs))
    for pair in ("friction__velocity_error", "friction__optical", "velocity_error__optical"):
        r = corr[pair][zero - h:zero + h + 1]
        i = int(np.argmax(r))
        d = parabola(r[i - 1], r[i], r[i + 1]) if 0 < i < len(r) - 1 else 0.0
        _ = 360.0 * ((i - h + d) / fs) / t
        k = int(round(f_used / (hires["freq_hz"][1] - hires["freq_hz"][0])))
        _ = np.angle(hires[pair + "_re"][k] + 1j * hires[pair + "_im"][k], deg=True)
    w = signal.get_window("hann", nperseg_hr)
    step = nperseg_hr - nperseg_hr // 2
    segs = (nd - nperseg_hr) // step + 1
    e = np.dot(w, w)
    sm = sum((1 - m / segs) * (np.dot(w[m * step:], w[:len(w) - m * step]) / e) ** 2
             for m in range(1, segs) if m * step < len(w))
    nu = 2 * segs / (1 + 2 * sm)
    med_ratio = stats.chi2.ppf(0.5, nu) / nu
    thr_ratio = stats.chi2.ppf(0.99 ** (1 / 3), nu) / nu
    f = hires["freq_hz"]
    df = f[1] - f[0]
    # As ballpass: a first pass at the predicted f_c, the spectral peak
    # within +-25 % of it, then the table at the predicted and measured f_c.
    for s in ("friction", "velocity_error", "optical"):
        for k in range(1, 6):
            harmonic(f, hires[s], k * f_c, f_c, med_ratio, thr_ratio)
        lo, hi = max(int(np.ceil(0.75 * f_c / df)), 1), min(int(np.floor(1.25 * f_c / df)), len(f) - 2)
        if lo <= hi:
            i = lo + int(np.argmax(hires[s][lo:hi + 1]))
            _ = (i + parabola(hires[s][i - 1], hires[s][i], hires[s][i + 1])) * df
    for s in ("friction", "velocity_error", "optical"):
        for k in range(1, 6):
            harmonic(f, hires[s], k * f_c, f_c, med_ratio, thr_ratio)
            harmonic(f, hires[s], k * f_used, f_used, med_ratio, thr_ratio)
    n_d = nu / 2
    thr = 1 - (1 - 0.99 ** (1 / 3)) ** (1 / (n_d - 1)) if n_d > 1 else np.inf
    for pair in ("friction__velocity_error", "friction__optical", "velocity_error__optical"):
        coh = hires[pair + "_coh"]
        for k in range(1, 6):
            i = int(round(k * f_used / df))
            if 0 < i < len(coh) - 1:
                _ = coh[i - 1:i + 2].max() > thr
    _ = (np.std(velocity_error_raw, ddof=1), np.std(sig["velocity_error"], ddof=1))


def one(path, velocity):
    fs, fr, pos, opt = ra.load_csv(path)
    a = Args()
    a.velocity = velocity
    f_c = velocity / (2 * a.d_avg)
    sig, corr, _, hires, _ = ra.analyze(fs, fr, pos, opt, a)
    nd = -(-len(sig["friction"]) // a.q)
    nperseg_hr = min(ra.next_smooth(6.0 * (fs / a.q) / f_c), nd)
    ve_raw = np.gradient(pos, 1.0 / fs) - velocity
    scalars(fs, sig, corr, hires, f_c, nperseg_hr, nd, ve_raw)
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
