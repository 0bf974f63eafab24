#!/usr/bin/env python3
"""Time SciPy on the work of crates/ballpass-dsp/benches/filters.rs.

Best of several timeit repeats, one core, per call in microseconds.
Usage: python3 tools/bench_scipy_filters.py
"""
import timeit

import numpy as np
import scipy
from scipy import signal


def best_us(stmt, env, number, repeat=7):
    return min(timeit.repeat(stmt, globals=env, number=number, repeat=repeat)) / number * 1e6


def main():
    n = 30_000
    rng = np.random.default_rng(0)
    x = rng.uniform(-0.5, 0.5, n) + np.sin(2 * np.pi * 1.1 * np.arange(n) / 1000.0)
    sos = signal.butter(5, 20.0, fs=1000.0, output="sos")
    env = {"signal": signal, "x": x, "sos": sos}
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    rows = [
        ("butter(5, 20 Hz, fs 1 kHz) design", "signal.butter(5, 20.0, fs=1000.0, output='sos')", 200),
        ("sosfiltfilt butter5 20 Hz, 30k samples", "signal.sosfiltfilt(sos, x)", 50),
        ("decimate q=20, 30k samples", "signal.decimate(x, 20)", 50),
    ]
    for name, stmt, number in rows:
        print(f"{name:45s} {best_us(stmt, env, number):10.1f} us")


if __name__ == "__main__":
    main()
