#!/usr/bin/env python3
"""Time SciPy/NumPy on the work of crates/ballpass/benches/passage.rs.

Record: the simulator's default 30 s record at 9 mm/s, seed 0 (1 kHz, 33
passages), written by

    ballpass simulate -v 9 --seed 0 -o rec.csv

Work, as ballpass::analysis::passage::detect_passages with the SR25W
prediction (tau_c = 2 d_avg / v):
  1. noise sigma = MAD of lag-L differences / (0.67449 sqrt 2)
  2. running 10th-percentile baseline over 2 tau_c (evaluated every window/4,
     linear in between), y = x - baseline
  3. Gaussian smoothing (sigma tau_c/200 samples), find_peaks on y and -y with
     prominence >= 6 sigma, distance 0.7 tau_c, wlen 2.5 tau_c; peak_widths at
     rel_height 0.5; keep prominences >= 0.25 x p75
  4. least_squares (method='lm', analytic Jacobian) of the Gaussian train
     (S, t0, tau_c, sigma, one amplitude per pulse) over the whole record and
     of the rectangular train of order 20 (S, P, t_s, tau_c, r), at most 150
     samples per period.

The drift / AC-coupling condition checks are left out (they are a few
vector operations). Prints the time of detection alone and with the fits,
and the fit results to compare with `ballpass passage`.

Usage: python3 tools/bench_scipy_passage.py rec.csv
"""
import math
import sys
import timeit

import numpy as np
import scipy
from scipy.ndimage import gaussian_filter1d
from scipy.optimize import least_squares
from scipy.signal import find_peaks, peak_widths

FWHM_PER_SIGMA = 2.0 * math.sqrt(2.0 * math.log(2.0))
D_AVG_MM = 4.0 + 2.0 / 36.0  # SR25W: d + d_ext / N_B


def running_percentile(x, window, q):
    n = len(x)
    hop = max(window // 4, 1)
    centres = list(range(0, n, hop))
    if centres[-1] != n - 1:
        centres.append(n - 1)
    levels = [np.percentile(x[max(c - window // 2, 0):min(c + window // 2 + 1, n)], q)
              for c in centres]
    return np.interp(np.arange(n), centres, levels)


def detect(x, fs, v):
    tau = 2.0 * D_AVG_MM / v
    ts = tau * fs
    lag = max(int(0.3 * ts / 40.0), 1)
    d = x[lag:] - x[:-lag]
    sigma = np.median(np.abs(d - np.median(d))) / (0.6744897501960817 * math.sqrt(2.0))
    base = running_percentile(x, int(round(2.0 * ts)), 10.0)
    y = x - base
    ys = gaussian_filter1d(y, max(0.005 * ts, 1.0), mode="mirror", truncate=4.0)
    thr = 6.0 * sigma
    out = []
    for s in (ys, -ys):
        p, props = find_peaks(s, prominence=thr, distance=max(0.7 * ts, 1.0), wlen=2.5 * ts)
        # The prominences find_peaks just computed, as ballpass passes them.
        w = peak_widths(s, p, rel_height=0.5, prominence_data=(
            props["prominences"], props["left_bases"], props["right_bases"]))
        out.append((p, props["prominences"], w))
    p75 = max(np.percentile(o[1], 75) if len(o[1]) else 0.0 for o in out)
    p, prom, w = out[0]
    keep = prom >= max(thr, 0.25 * p75)
    centres = 0.5 * (w[2][keep] + w[3][keep]) / fs
    return y, centres, w[0][keep] / fs, prom[keep], tau


def gauss_fun(th, t, d):
    s, t0, tau, sig = th[:4]
    amps = th[4:]
    j = np.arange(len(amps))
    u = (t[:, None] - t0 - j[None, :] * tau) / sig
    return s + (np.exp(-0.5 * u * u) * amps).sum(axis=1) - d


def gauss_jac(th, t, d):
    s, t0, tau, sig = th[:4]
    amps = th[4:]
    j = np.arange(len(amps))
    u = (t[:, None] - t0 - j[None, :] * tau) / sig
    e = np.exp(-0.5 * u * u)
    g = amps * e * u / sig
    jac = np.empty((len(t), len(th)))
    jac[:, 0] = 1.0
    jac[:, 1] = g.sum(axis=1)
    jac[:, 2] = (g * j).sum(axis=1)
    jac[:, 3] = (g * u).sum(axis=1)
    jac[:, 4:] = e
    return jac


def rect_fun(th, t, d, order=20):
    s, p, ts, tau, r = th
    n = np.arange(1, order + 1)
    phi = np.pi * (2.0 * (t - ts) / tau + r)
    series = (2.0 * p / (n * np.pi) * np.sin(n * np.pi * r) * np.cos(np.outer(phi, n))).sum(axis=1)
    return s + p * r + series - d


def rect_jac(th, t, d, order=20):
    s, p, ts, tau, r = th
    n = np.arange(1, order + 1)
    phi = np.pi * (2.0 * (t - ts) / tau + r)
    c = np.cos(np.outer(phi, n))
    sn = np.sin(np.outer(phi, n))
    sr, cr = np.sin(n * np.pi * r), np.cos(n * np.pi * r)
    a = -2.0 * p / np.pi * (sr * sn).sum(axis=1)
    jac = np.empty((len(t), 5))
    jac[:, 0] = 1.0
    jac[:, 1] = r + 2.0 / np.pi * (sr * c / n).sum(axis=1)
    jac[:, 2] = -2.0 * np.pi * a / tau
    jac[:, 3] = -2.0 * np.pi * (t - ts) * a / tau**2
    jac[:, 4] = p + 2.0 * p * (cr * c).sum(axis=1) + np.pi * a
    return jac


def fits(y, fs, centres, widths, prom, tau_guide):
    tau0 = np.median(np.diff(centres))
    lo = max(centres[0] - 0.5 * tau0, 0.0)
    hi = min(centres[-1] + 0.5 * tau0, len(y) / fs)
    stride = max(int(tau0 * fs / 150.0), 1)
    idx = np.arange(int(math.ceil(lo * fs)), min(int(hi * fs), len(y) - 1) + 1, stride)
    t, d = idx / fs, y[idx]
    sig0 = np.median(widths) / FWHM_PER_SIGMA
    g = least_squares(gauss_fun, np.r_[0.0, centres[0], tau0, sig0, prom], jac=gauss_jac,
                      args=(t, d), method="lm")
    r0 = min(max(np.median(widths) / tau0, 0.01), 0.9)
    r = least_squares(rect_fun, [0.0, np.median(prom), centres[0] - tau0 * (1 - r0 / 2), tau0, r0],
                      jac=rect_jac, args=(t, d), method="lm")
    ss_tot = ((d - d.mean()) ** 2).sum()
    return g, r, 1.0 - (g.fun**2).sum() / ss_tot, 1.0 - (r.fun**2).sum() / ss_tot


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    data = np.genfromtxt(sys.argv[1], delimiter=",", names=True)
    x = np.asarray(data["optical_V"], dtype=float)
    fs = 1.0 / (data["time_s"][1] - data["time_s"][0])
    v = 9.0
    y, centres, widths, prom, tau = detect(x, fs, v)
    g, r, g_r2, r_r2 = fits(y, fs, centres, widths, prom, tau)
    print(f"numpy {np.__version__}, scipy {scipy.__version__}")
    print(f"{len(centres)} passages, tau_c {np.diff(centres).mean():.5f} s, "
          f"tau_p {widths.mean():.5f} s (smoothed widths, not deconvolved)")
    print(f"Gaussian fit: tau_c {g.x[2]:.5f} s, sigma {g.x[3]:.5f} s, R2 {g_r2:.4f}, nfev {g.nfev}")
    print(f"rectangular fit: tau_c {r.x[3]:.5f} s, r {r.x[4]:.4f}, R2 {r_r2:.4f}, nfev {r.nfev}")
    def full():
        y, c, w, p, tau = detect(x, fs, v)
        return fits(y, fs, c, w, p, tau)

    for name, fn in [("detect", lambda: detect(x, fs, v)), ("detect_and_fit_whole_record", full)]:
        reps = 5
        best = min(timeit.repeat(fn, number=1, repeat=reps))
        print(f"{name}: best of {reps} {best * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
