#!/usr/bin/env python3
"""Time SciPy on the work of crates/ballpass-dsp/benches/peaks.rs.

Signal: 30 000 samples at 1 kHz of a noisy Gaussian pulse train (optical
ball-pass sensor), generated with the same splitmix64 stream as the Rust
bench: pulse every 0.2 s +- 10 ms, amplitude 1 +- 0.1, sigma 12 ms, baseline
0.1, Gaussian noise sd 0.05 (Box-Muller).
Work: find_peaks(x, distance=100, prominence=0.3), then
peak_widths(x, peaks, rel_height=0.5) (which recomputes the prominences).

Usage: python3 tools/bench_scipy_peaks.py   (one core: OMP/MKL threads do not matter here)
"""
import math
import timeit

import numpy as np
import scipy
from scipy.signal import find_peaks, peak_widths

MASK = (1 << 64) - 1


class SplitMix64:
    def __init__(self, seed):
        self.s = seed & MASK

    def next_f64(self):
        self.s = (self.s + 0x9E3779B97F4A7C15) & MASK
        z = self.s
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
        z ^= z >> 31
        return (z >> 11) * 2.0**-53


def pulse_train(n=30_000, fs_hz=1000.0, seed=42):
    rng = SplitMix64(seed)
    t = np.arange(n) / fs_hz
    x = np.full(n, 0.1)
    c = 0.1
    while c < t[-1]:
        a = 1.0 + 0.2 * (rng.next_f64() - 0.5)
        x += a * np.exp(-0.5 * ((t - c) / 0.012) ** 2)
        c += 0.2 + 0.02 * (rng.next_f64() - 0.5)
    noise = np.empty(n)
    for i in range(n):
        u1 = 1.0 - rng.next_f64()
        u2 = rng.next_f64()
        noise[i] = math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)
    return x + 0.05 * noise


def work(x):
    peaks, _ = find_peaks(x, distance=100, prominence=0.3)
    return peaks, peak_widths(x, peaks, rel_height=0.5)


def main():
    x = pulse_train()
    peaks, (w, *_) = work(x)
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    print(f"{peaks.size} peaks, mean width {w.mean():.4f} samples")
    for name, fn in (("find_peaks(distance, prominence) + peak_widths", lambda: work(x)),
                     ("find_peaks(distance, prominence)",
                      lambda: find_peaks(x, distance=100, prominence=0.3))):
        t = timeit.Timer(fn)
        n, _ = t.autorange()
        best = min(t.repeat(repeat=7, number=n)) / n
        print(f"{name}: {best * 1e6:.1f} us per call (best of 7 x {n})")


if __name__ == "__main__":
    main()
