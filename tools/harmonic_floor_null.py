"""A simplified replica of the friction harmonic test on white noise, to
locate why its p-values err on the safe side (docs/verdicts.md, "Session
21 (lead)").

    python tools/harmonic_floor_null.py

Not the product's test: a flat white spectrum, SciPy's Welch (Hann, 50 %
overlap, 256-sample segments), the three bins around a predicted line
tested, and a straight line in ln f fitted to the ln PSD of five floor bins
on each side (the product fits ~9 bins, a line or a quadratic, over a
window set by f_c). As in the product (analysis/harmonics.rs):

    ratio  T = max over the tested bins of PSD / exp(fit - E[ln chi2_nu/nu])
    p      = E_eps[ 1 - F(T e^eps)^3 ],  F the CDF of chi2_nu/nu,
             eps ~ N(0, s2),  s2 = (psi' + m2) h c + m2,  c = 1.944

with three treatments of the floor's error: `misfit` (m2 = max(0, s^2 -
psi'), the product's), `no misfit` (m2 = 0), `exact` (s2 = 0). `gap`
leaves that many bins out between the tested bins and the floor bins on
each side (the product leaves none: the floor starts next to the tested
bins). The true spectrum is flat, so every p-value here is a null one.
Seeded (38 000 003); Monte Carlo, 20 000 tests per row (standard error
about 0.07 points at 1 %). Needs numpy and scipy (tools/requirements.txt).
"""

import numpy as np
from scipy.signal import welch
from scipy.special import digamma, polygamma
from scipy.stats import chi2

N = 256
C = 1.944  # 1 + 2 (4/9 + 1/36): Hann's neighbour inflation, as in the product
SIDE = 5  # floor bins on each side
GH_X, GH_W = np.polynomial.hermite_e.hermegauss(40)
GH_W = GH_W / GH_W.sum()


def run(rng, k, reps, gap):
    x = rng.standard_normal((reps, N * (k + 1) // 2))
    f, p = welch(x, nperseg=N, noverlap=N // 2, window="hann", axis=-1)
    band = p[:, 20:110] / p[:, 20:110].mean()
    nu = 2.0 / band.var()
    vchi = polygamma(1, nu / 2)
    mu = digamma(nu / 2) - np.log(nu / 2)
    out = {"misfit": [], "no misfit": [], "exact": []}
    for i0 in range(30, 100, 16):
        fb = np.r_[i0 - 1 - gap - SIDE : i0 - 1 - gap, i0 + 2 + gap : i0 + 2 + gap + SIDE]
        tb = np.array([i0 - 1, i0, i0 + 1])
        xf = np.c_[np.ones(len(fb)), np.log(f[fb] / f[i0])]
        inv = np.linalg.inv(xf.T @ xf)
        y = np.log(p[:, fb])
        beta = y @ xf @ inv
        s2 = ((y - beta @ xf.T) ** 2).sum(1) / (len(fb) - 2)
        xt = np.c_[np.ones(3), np.log(f[tb] / f[i0])]
        yhat = beta @ xt.T
        lev = np.einsum("ij,jk,ik->i", xt, inv, xt)
        ratio = p[:, tb] / np.exp(yhat - mu)
        t = ratio.max(1)
        h = lev[ratio.argmax(1)]
        m2 = np.maximum(0.0, s2 - vchi)
        for name, var in (
            ("misfit", (vchi + m2) * h * C + m2),
            ("no misfit", vchi * h * C),
            ("exact", 0.0 * h),
        ):
            eps = np.sqrt(var)[:, None] * GH_X[None, :]
            cdf = chi2.cdf(nu * t[:, None] * np.exp(eps), nu)
            out[name].append(((1.0 - cdf**3) * GH_W[None, :]).sum(1))
    return nu, {k: np.concatenate(v) for k, v in out.items()}


def main():
    rng = np.random.default_rng(38_000_003)
    print("gap | segments | nu | floor error | p <= 0.01 | p <= 0.05 | p <= 0.5")
    for gap in (0, 1, 2):
        for k in (3, 11, 45):
            nu, res = run(rng, k, 4000, gap)
            for name, pv in res.items():
                print(
                    f"{gap} | {k} | {nu:.1f} | {name} | {100 * np.mean(pv <= 0.01):.2f} % |"
                    f" {100 * np.mean(pv <= 0.05):.2f} % | {100 * np.mean(pv <= 0.5):.1f} %"
                )


if __name__ == "__main__":
    main()
