#!/usr/bin/env python3
"""Time numpy's text loaders on the file shape of crates/ballpass/benches/load.rs.

30 s at 1 kHz, columns time_s, friction_N, position_mm, optical_V, every number
at full (repr) precision: the same work as `ballpass::recording::load` (parse
and keep the numbers; ballpass also checks the time column, which is not
counted here). Usage: python3 tools/bench_scipy_load.py
"""
import os
import tempfile
import timeit

import numpy as np


def make(path):
    fs, n = 1000.0, 30_000
    t = np.arange(n) / fs
    rng = np.random.default_rng(0)
    friction = 2.0 + 0.05 * np.sin(2 * np.pi * 1.10959 * t) + 0.01 * (rng.random(n) - 0.5)
    position = 9.0 * t + 1e-4 * (rng.random(n) - 0.5)
    optical = 0.3 + 0.2 * (rng.random(n) - 0.5)
    with open(path, "w") as f:
        f.write("time_s,friction_N,position_mm,optical_V\n")
        for row in zip(t, friction, position, optical):
            f.write(",".join(repr(float(x)) for x in row) + "\n")


def main():
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "thesis_30s_1kHz.csv")
        make(path)
        size = os.path.getsize(path)
        for name, fn in [
            ("np.loadtxt", lambda: np.loadtxt(path, delimiter=",", skiprows=1)),
            ("np.genfromtxt", lambda: np.genfromtxt(path, delimiter=",", names=True)),
        ]:
            reps = 5
            best = min(timeit.repeat(fn, number=1, repeat=reps))
            print(f"{name:14s} {best * 1e3:8.2f} ms  (best of {reps}, {size / 1e6:.2f} MB, numpy {np.__version__})")


if __name__ == "__main__":
    main()
