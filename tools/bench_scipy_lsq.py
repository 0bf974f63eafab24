#!/usr/bin/env python3
"""Time SciPy on the work of crates/ballpass-dsp/benches/lsq.rs.

A Gaussian pulse-train fit: 30 000 samples at 1 kHz, 26 pulses of
(amplitude, centre, sigma) on a baseline (79 parameters), uniform noise,
the same LCG stream and perturbed start as the Rust bench. SciPy's
least_squares(method='lm') with an analytic (dense) Jacobian; best of a few
fits, one core.

Usage: python3 tools/bench_scipy_lsq.py
"""
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy.optimize import least_squares  # noqa: E402

N = 30_000
FS = 1000.0
PULSES = 26
MASK = (1 << 64) - 1


class Lcg:
    def __init__(self, seed):
        self.s = seed

    def next(self):
        self.s = (self.s * 6364136223846793005 + 1442695040888963407) & MASK
        return (self.s >> 11) / float(1 << 53) - 0.5


T = np.arange(N) / FS


def model(p):
    y = np.full(N, p[0])
    for a, c, s in p[1:].reshape(-1, 3):
        u = (T - c) / s
        y += a * np.exp(-0.5 * u * u)
    return y


def jac(p, y):
    j = np.zeros((N, p.size))
    j[:, 0] = 1.0
    for k, (a, c, s) in enumerate(p[1:].reshape(-1, 3)):
        u = (T - c) / s
        e = np.exp(-0.5 * u * u)
        j[:, 1 + 3 * k] = e
        j[:, 2 + 3 * k] = a * e * u / s
        j[:, 3 + 3 * k] = a * e * u * u / s
    return j


def problem():
    rng = Lcg(2024)
    truth = [0.1]
    for k in range(PULSES):
        c = 0.6 + 1.15 * k + 0.02 * rng.next()
        a = 1.0 + 0.2 * rng.next()
        s = 0.03 + 0.01 * rng.next()
        truth += [a, c, s]
    truth = np.array(truth)
    noise = np.array([0.05 * rng.next() for _ in range(N)])
    y = noise + model(truth)
    start = truth.copy()
    start[0] = 0.0
    start[1::3] *= 0.8
    start[2::3] += 0.01
    start[3::3] *= 1.25
    return y, truth, start


def main():
    y, truth, start = problem()
    fit = lambda: least_squares(lambda p: model(p) - y, start, jac=lambda p: jac(p, y),
                                method="lm")
    res = fit()
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    print(f"{start.size} parameters, nfev {res.nfev}, njev {res.njev}, "
          f"rms {np.sqrt(np.mean(res.fun ** 2)):.4f}, "
          f"worst parameter error {np.max(np.abs(res.x - truth)):.2e}")
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        fit()
        best = min(best, time.perf_counter() - t0)
    print(f"pulse-train fit, 79 parameters, 30k samples: {best * 1e3:.1f} ms (best of 5)")


if __name__ == "__main__":
    main()
