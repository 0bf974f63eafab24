"""Fixtures for ballpass_dsp::lsq: scipy.optimize.least_squares(method='lm')
(MINPACK lmder with the analytic Jacobian) on noisy curve fits.

Each fixture: {"model", "t", "y", "x0", "params", "cost", "covariance"} where
covariance = inv(JᵀJ) · 2·cost / (m - n) at SciPy's solution (row-major).
Models (the Rust test implements the same formulas):
  exp_decay:  a·exp(-k·t) + c                          params [a, k, c]
  gaussians:  b + sum_j a_j·exp(-0.5·((t - c_j)/s_j)²)  params [b, a_0, c_0, s_0, a_1, ...]
"""
import numpy as np
from scipy.optimize import least_squares


def exp_decay(p, t):
    a, k, c = p
    e = np.exp(-k * t)
    return a * e + c, np.stack([e, -a * t * e, np.ones_like(t)], axis=1)


def gaussians(p, t):
    y = np.full_like(t, p[0])
    jac = np.zeros((t.size, p.size))
    jac[:, 0] = 1.0
    for j in range((p.size - 1) // 3):
        a, c, s = p[1 + 3 * j: 4 + 3 * j]
        u = (t - c) / s
        g = np.exp(-0.5 * u * u)
        y += a * g
        jac[:, 1 + 3 * j] = g
        jac[:, 2 + 3 * j] = a * g * u / s
        jac[:, 3 + 3 * j] = a * g * u * u / s
    return y, jac


MODELS = {"exp_decay": exp_decay, "gaussians": gaussians}


def fit(write, name, model, t, truth, x0, noise, rng):
    f = MODELS[model]
    y = f(np.asarray(truth, float), t)[0] + noise * rng.standard_normal(t.size)
    res = least_squares(lambda p: f(p, t)[0] - y, np.asarray(x0, float),
                        jac=lambda p: f(p, t)[1], method="lm",
                        ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=10000)
    assert res.success, (name, res.message)
    j = f(res.x, t)[1]
    m, n = j.shape
    cov = np.linalg.inv(j.T @ j) * 2 * res.cost / (m - n)
    write(name, {"model": model, "t": t, "y": y, "x0": x0, "truth": truth,
                 "params": res.x, "cost": res.cost, "covariance": cov.ravel(),
                 "scipy_status": res.status, "scipy_nfev": res.nfev})


def generate(write):
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 10.0, 60)
    fit(write, "exp_decay_noisy", "exp_decay", t, [2.5, 0.7, 0.3], [1.0, 1.0, 0.0], 0.02, rng)
    fit(write, "exp_decay_very_noisy", "exp_decay", t, [2.5, 0.7, 0.3], [1.0, 0.3, 1.0], 0.3, rng)
    t = np.linspace(0.0, 10.0, 101)
    fit(write, "gaussian_noisy", "gaussians", t, [0.5, 3.0, 4.2, 0.8], [0.0, 2.0, 4.0, 1.0], 0.05, rng)
    # Three overlapping pulses, 1 kHz for 1 s.
    t = np.arange(1000) / 1000.0
    truth = [0.1, 1.0, 0.30, 0.012, 0.8, 0.33, 0.015, 1.2, 0.60, 0.010]
    x0 = [0.0, 0.8, 0.305, 0.010, 1.0, 0.325, 0.012, 1.0, 0.598, 0.012]
    fit(write, "three_gaussians_noisy", "gaussians", t, truth, x0, 0.05, rng)
    # A pulse train like the optical sensor: 8 pulses, 25 parameters, 2 s.
    t = np.arange(2000) / 1000.0
    truth, x0 = [0.1], [0.05]
    for j in range(8):
        c = 0.12 + 0.24 * j + 0.01 * rng.standard_normal()
        truth += [1.0 + 0.1 * rng.standard_normal(), c, 0.012 + 0.001 * rng.standard_normal()]
        x0 += [1.0, round(c, 2), 0.01]
    fit(write, "pulse_train_noisy", "gaussians", t, truth, x0, 0.05, rng)
