"""Two premises of the friction harmonic test, checked on white noise with
SciPy's Welch (Hann, 50 % overlap): how strongly neighbouring bins of a
Welch PSD and of its logarithm are correlated, and whether the tail of the
largest of three neighbouring bins is that of three independent ones when
the floor is known (docs/verdicts.md, "Session 21 (lead)").

    python tools/welch_neighbour_null.py

Seeded (38 000 001, 38 000 002); Monte Carlo, so figures move in the third
decimal between seeds. Needs numpy and scipy (tools/requirements.txt).
"""

import numpy as np
from scipy.signal import welch
from scipy.stats import chi2

N = 256  # segment length; bins 20..110 are far from DC and Nyquist


def corr(a, lag):
    x = a[:, :-lag] - a[:, :-lag].mean(0)
    y = a[:, lag:] - a[:, lag:].mean(0)
    return (x * y).mean() / np.sqrt((x * x).mean() * (y * y).mean())


def spectra(rng, k, reps):
    """Welch PSDs of `reps` white-noise records of `k` half-overlapping
    segments, bins 20..110, scaled to a true level of 1."""
    x = rng.standard_normal((reps, N * (k + 1) // 2))
    _, p = welch(x, nperseg=N, noverlap=N // 2, window="hann", axis=-1)
    p = p[:, 20:110]
    return p / p.mean()


def main():
    rng = np.random.default_rng(38_000_001)
    print("neighbour correlation, PSD and ln PSD; c = 1 + 2 (rho1 + rho2)")
    for k in (1, 3, 11, 45):
        p = spectra(rng, k, 4000)
        nu = 2.0 / p.var()
        lp = np.log(p)
        r1, r2, l1, l2 = corr(p, 1), corr(p, 2), corr(lp, 1), corr(lp, 2)
        print(
            f"segments {k:2d} nu {nu:5.1f}: PSD {r1:.3f} {r2:.3f} c {1 + 2 * (r1 + r2):.3f}"
            f" | ln PSD {l1:.3f} {l2:.3f} c {1 + 2 * (l1 + l2):.3f}"
        )
    rng = np.random.default_rng(38_000_002)
    print("largest of three neighbouring bins, true floor, independent-bin threshold")
    for k in (3, 11, 45):
        p = spectra(rng, k, 6000)
        nu = 2.0 / p.var()
        top = p[:, :90].reshape(p.shape[0], 30, 3).max(-1).ravel()
        for a in (0.05, 0.01, 0.002):
            q = 1.0 - (1.0 - a) ** (1.0 / 3.0)
            thr = chi2.isf(q, nu) / nu
            print(f"segments {k:2d} nu {nu:5.1f} nominal {a:.3f}: observed {np.mean(top > thr):.4f}")


if __name__ == "__main__":
    main()
