#!/usr/bin/env python3
"""Time SciPy on the work of crates/ballpass-dsp/benches/spectral.rs.

A 30 000-sample record at 1 kHz (a 1.1096 Hz tone plus uniform noise from
the same LCG as the Rust bench): full-lag cross-correlation
(scipy.signal.correlate(method='fft') + correlation_lags), autocorrelation,
welch and csd with nperseg=4096 (other settings default). Best of several
timeit repeats, one core (set OMP/MKL threads to 1 before running if needed).

Usage: python3 tools/bench_scipy_spectral.py
"""
import os
import timeit

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy  # noqa: E402
import scipy.signal as sig  # noqa: E402

N = 30_000
FS = 1000.0
MASK = (1 << 64) - 1


def record(seed):
    s = seed
    noise = np.empty(N)
    for i in range(N):
        s = (s * 6364136223846793005 + 1442695040888963407) & MASK
        noise[i] = ((s >> 11) / float(1 << 53)) * 2.0 - 1.0
    return np.sin(2 * np.pi * 1.1096 * np.arange(N) / FS) + noise


def best(stmt, number):
    t = timeit.Timer(stmt).repeat(repeat=7, number=number)
    return min(t) / number


def main():
    x, y = record(1), record(2)
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    cases = {
        "correlate_full_30000": (lambda: (sig.correlate(x, y, mode="full", method="fft"),
                                          sig.correlation_lags(N, N, mode="full")), 50),
        "autocorrelate_full_30000": (lambda: (sig.correlate(x, x, mode="full", method="fft"),
                                              sig.correlation_lags(N, N, mode="full")), 50),
        "welch_30000_nperseg4096": (lambda: sig.welch(x, FS, nperseg=4096), 50),
        "csd_30000_nperseg4096": (lambda: sig.csd(x, y, FS, nperseg=4096), 50),
    }
    for name, (fn, number) in cases.items():
        print(f"{name:28s} {best(fn, number) * 1e6:10.1f} us")


if __name__ == "__main__":
    main()
