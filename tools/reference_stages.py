#!/usr/bin/env python3
"""NumPy/SciPy versions of the stages of `ballpass.analyze` that
tools/reference_analyze.py leaves out, for the speed comparison of
tools/bench_python.py (issue 14: "the SciPy pipeline doing the same steps").

reference_analyze.py holds the numeric core (velocity by np.gradient,
Butterworth sosfiltfilt + detrend, six correlations, full-range,
unfiltered and high-resolution Welch/CSD/coherence with their chi-square
bands), checked against ballpass to 1e-9. `analyze` does more; each
function below is one of those stages, written as a SciPy user would
(vectorised NumPy, SciPy's fitting, filtering and statistics routines),
with the same sizes as ballpass (grid points, iterations, segments):

  load_cell         crates/ballpass/src/analysis/load_cell.rs: block means
                    of 20 ms, RSS(tau) of c + A b_tau on a 241-point log
                    grid, golden section (40 steps), the F test on
                    ball-period means with its profile interval, then the
                    trapezoidal inverse of the high-pass
  stage_identify    crates/ballpass/src/model/identify.rs: Welch/CSD of
                    friction and velocity error (linearly detrended,
                    nperseg_for), H1, the 7-parameter weighted least squares
                    over the significant-coherence bins (4 passes, model
                    weights, sandwich covariance), the fit repeated over two
                    decades around the resonance, delta-method intervals
  passages          crates/ballpass/src/analysis/passage: noise sigma,
                    running 10th-percentile baseline, seeds (find_peaks with
                    prominences and widths), then rounds of the measurement
                    loop: box decimation, template + baseline-spline least
                    squares (3 passes), a Levenberg-Marquardt fit of each
                    pulse against the template, a matched-filter search of
                    both polarities
  measured_period   crates/ballpass/src/analysis/correlation.rs: the
                    autocorrelation maxima within +-0.25 T of k T of each
                    auto-correlation, parabolic refinement, T re-fitted
  phases            crates/ballpass/src/analysis/phase.rs: Hann segments of
                    three periods, each segment's DFT at f_c, cross spectra,
                    coherence and the 95 % interval of the three pairs
  harmonics         crates/ballpass/src/analysis/spectra.rs: per signal and
                    k = 1..5, at the predicted and the measured f_c: floor
                    polynomial in ln f, the p-value of the largest tested
                    bin over the floor's uncertainty (24-node Gauss-Hermite
                    over chi-square CDFs), Holm; coherence at k f_c
  sync_average      crates/ballpass/src/analysis/sync: 64 bins per period
                    between passages, interpolation, mean, Student-t band,
                    fundamental, variance explained
  position_spectra  crates/ballpass/src/analysis/position: runs, resampling
                    onto the travel grid (64 points per period), the
                    velocity's one-period moving mean, Welch (1024, linear
                    detrend), then per signal and k = 1..5 the line: the
                    largest bin within +-25 %, a 65-point grid and a golden
                    section of the segment-averaged |DFT(f)|^2 within +-1
                    bin, the floor median and the summed power

Where a stage here is simpler than ballpass' (the passage measurement loop
runs two rounds and fits a linear-interpolation template; ballpass iterates
until the set of pulses stops changing, with tails and AC-coupling checks;
the stage identification omits the Newey-West second sandwich), the SciPy
side does less work than ballpass, so the ratio stays conservative.

Outputs are computed, not just timed (`pipeline` returns them) so that the
script cannot be a loop of no-ops; `--check` prints the key numbers beside
ballpass' on the bench record.

Usage: python3 tools/reference_stages.py [--check] [--repeat 7]
Pinned versions: tools/requirements-py.txt.
"""
import math

import numpy as np
from scipy import integrate, linalg, optimize, signal, sparse, stats
from scipy.interpolate import BSpline
from scipy.sparse.linalg import spsolve
from scipy.special import digamma, polygamma

import reference_analyze as ref

D_AVG_MM = 4.0 + 2.0 / 36.0  # SR25W: d + d_ext / N_B
HARMONICS = 5
CONFIDENCE = 0.95


# ---------------------------------------------------------------- load cell
def _block_basis(m, w, fs, taus):
    """b_tau[i] = mean(e^{-j/(fs tau)}, j = iw .. iw+w) for every tau (rows)."""
    a = 1.0 / (fs * np.asarray(taus, float))[:, None]
    g = np.expm1(-a * w) / (w * np.expm1(-a))
    return g * np.exp(-a * w * np.arange(m)[None, :])


def _rss(s, basis):
    """Least-squares c, A and RSS of s = c + A b for each row b of `basis`."""
    bm = basis.mean(axis=1, keepdims=True)
    d = basis - bm
    a = (d * (s - s.mean())).sum(axis=1) / (d * d).sum(axis=1)
    c = s.mean() - a * bm[:, 0]
    rss = ((s[None, :] - c[:, None] - a[:, None] * basis) ** 2).sum(axis=1)
    return c, a, rss


def load_cell(friction, fs, tau_c):
    """Discharge fit and restoration of the friction (load_cell.rs)."""
    n = len(friction)
    w = max(int(round(0.02 * fs)), -(-n // 20000), 1)
    m = n // w
    s = friction[: m * w].reshape(m, w).mean(axis=1)
    duration = n / fs
    tau_lo, tau_hi = max(0.05, 4.0 * w / fs), 50.0 * duration
    grid = np.exp(np.linspace(np.log(tau_lo), np.log(tau_hi), 241))
    rss = _rss(s, _block_basis(m, w, fs, grid))[2]
    best = int(np.argmin(rss))
    a, b = np.log(grid[max(best - 1, 0)]), np.log(grid[min(best + 1, 240)])
    fit1 = lambda lt: _rss(s, _block_basis(m, w, fs, [math.exp(lt)]))[2][0]
    g = 0.618033988749895
    x1, x2 = b - g * (b - a), a + g * (b - a)
    f1, f2 = fit1(x1), fit1(x2)
    for _ in range(40):
        if f1 < f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - g * (b - a)
            f1 = fit1(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + g * (b - a)
            f2 = fit1(x2)
    tau = math.exp(0.5 * (a + b))
    c, amp, _ = (v[0] for v in _rss(s, _block_basis(m, w, fs, [tau])))
    # F test of the decay against a constant on ball-period means.
    wc = max(int(round(tau_c * fs / w)), 1)
    mc = m // wc
    sc = s[: mc * wc].reshape(mc, wc).mean(axis=1)
    basis_c = _block_basis(mc, w * wc, fs, grid)
    prof = _rss(sc, basis_c)[2]
    rss_c = _rss(sc, _block_basis(mc, w * wc, fs, [tau]))[2][0]
    rss0 = ((sc - sc.mean()) ** 2).sum()
    f = ((rss0 - rss_c) / 2.0) / (rss_c / (mc - 3.0))
    limit = rss_c * (1.0 + stats.f.ppf(0.95, 1.0, mc - 3.0) / (mc - 3.0))
    inside = np.nonzero(prof <= limit)[0]
    identified = mc > 6 and f > stats.f.ppf(0.999, 2.0, mc - 3.0)
    if not identified:
        return friction, dict(tau_s=tau, identified=False)
    restored = (friction - c) + integrate.cumulative_trapezoid(friction - c, dx=1.0 / fs, initial=0.0) / tau
    return restored, dict(tau_s=tau, identified=True, amplitude_n=amp, f_statistic=f,
                          tau_low_s=grid[inside[0]] if len(inside) else tau)


# -------------------------------------------------------- stage identification
def stage_identify(friction, velocity_error, fs):
    """Friction -> velocity-error response and the PD-loop fit (identify.rs)."""
    n = len(friction)
    want = max(min(16.0 * fs, n / 4.0), 16.0)
    nperseg = 16
    while 2 * nperseg <= want:
        nperseg *= 2
    x = signal.detrend(friction)
    y = signal.detrend(velocity_error)
    kw = dict(fs=fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2)
    f, pff = signal.welch(x, **kw)
    _, pvv = signal.welch(y, **kw)
    _, pfv = signal.csd(x, y, **kw)
    smooth = lambda v: np.convolve(v, np.ones(9) / 9, mode="same")
    coh = smooth(np.abs(pfv) ** 2 / (pff * pvv))
    k = (n - nperseg) // (nperseg // 2) + 1
    nd = k * 0.9
    thr = 1.0 - 0.01 ** (1.0 / (nd - 1.0))
    w = 2 * np.pi * f
    d = np.where(w > 0, np.sin(w / fs) / np.where(w > 0, w / fs, 1.0), 1.0)
    h = pfv / pff / d
    sel = (coh > thr) & (f > 0)
    pres = smooth(np.maximum(pvv - np.abs(pfv) ** 2 / pff, 0.0))
    var_h = pres / (2.0 * (nd - 1.0) * pff)

    def fit(sel):
        ws, z, vh, hh = w[sel], -1.0 / h[sel], var_h[sel], h[sel]
        theta = None
        zm = z
        for _ in range(4):
            reg = zm / (1j * ws)
            cols = [np.ones_like(ws), ws ** 2, 1j * ws, -1j / ws, -1j * ws ** 3, -reg, zm * 0 + np.abs(zm) ** 2 * 1e-3]
            X = np.column_stack([np.r_[c.real, c.imag] if np.iscomplexobj(c) else np.r_[c, 0 * c] for c in cols])
            Y = np.r_[z.real, z.imag]
            wt = 1.0 / np.maximum(np.r_[vh, vh] * np.abs(np.r_[zm, zm]) ** 4, 1e-300)
            xtw = X.T * wt
            A = xtw @ X
            theta = linalg.solve(A, xtw @ Y, assume_a="sym")
            zm = (X @ theta)[: len(ws)] + 1j * (X @ theta)[len(ws):]
            r = Y - X @ theta
            ai = linalg.inv(A)
            cov = ai @ (xtw * r * r) @ xtw.T @ ai
        return theta, cov, hh

    theta, cov, _ = fit(sel)
    kkd, mass, kkp = theta[0], theta[2], theta[3]
    fn = math.sqrt(abs(kkp / mass)) / (2 * np.pi) if mass != 0 else float("nan")
    band = sel & (f > fn / 10.0) & (f < fn * 10.0)
    if band.sum() > 8:
        theta, cov, _ = fit(band)
    g = lambda t: np.array([math.sqrt(abs(t[3] / t[2])) / (2 * np.pi), t[0] / (2 * math.sqrt(abs(t[2] * t[3])))])
    base = g(theta)
    jac = np.empty((2, len(theta)))
    for i in range(len(theta)):
        dt = np.zeros(len(theta))
        dt[i] = 1e-6 * max(abs(theta[i]), 1e-12)
        jac[:, i] = (g(theta + dt) - base) / dt[i]
    ci = 1.96 * np.sqrt(np.abs(np.diag(jac @ cov @ jac.T)))
    return dict(natural_frequency_hz=base[0], damping_ratio=base[1], ci95=ci, bins_used=int(sel.sum()))


# ------------------------------------------------------------------ passages
def _noise_sigma(x, lag):
    d = x[lag:] - x[:-lag]
    return np.median(np.abs(d - np.median(d))) / (0.6744897501960817 * math.sqrt(2.0))


def _running_percentile(x, window, q):
    n = len(x)
    hop = max(window // 4, 1)
    centres = np.r_[np.arange(0, n, hop), n - 1]
    lv = [np.percentile(x[max(c - window // 2, 0):min(c + window // 2 + 1, n)], q) for c in centres]
    return np.interp(np.arange(n), centres, lv)


def _bspline_design(nb, knot):
    """Cubic B-splines with knots every `knot` blocks, as a sparse matrix."""
    count = int((nb - 1) // knot) + 4
    t = np.arange(-3, count + 1) * knot
    return sparse.csr_matrix(BSpline.design_matrix(np.arange(nb, dtype=float), t, 3, extrapolate=True))


def passages(optical, fs, tau_c, rounds=2):
    """Ball passages of the optical channel (analysis/passage)."""
    x = optical
    ts = tau_c * fs
    lag = max(int(0.3 * ts / 40.0), 1)
    sigma = _noise_sigma(x, lag)
    base = _running_percentile(x, int(round(2.0 * ts)), 10.0)
    y0 = x - base
    thr = 6.0 * sigma
    p, props = signal.find_peaks(y0, prominence=thr, distance=max(0.7 * ts, 1.0), wlen=2.5 * ts)
    wid = signal.peak_widths(y0, p, rel_height=0.5, prominence_data=(
        props["prominences"], props["left_bases"], props["right_bases"]))
    keep = props["prominences"] >= 0.25 * np.percentile(props["prominences"], 75)
    centres = 0.5 * (wid[2] + wid[3])[keep]
    fwhm = float(np.median(wid[0][keep]))
    amps = props["prominences"][keep]
    q = max(int(fwhm / 24.0), 1)
    nb = len(x) // q
    z = x[: nb * q].reshape(nb, q).mean(axis=1)
    c = (centres - 0.5 * (q - 1)) / q
    s = fwhm / q / 2.3548200450309493
    hw = fwhm / q / 2.0
    grid_h = 2.0 * hw / 16.0
    ng = int(math.ceil(6.0 * hw / grid_h)) + 1
    gx = -3.0 * hw + grid_h * np.arange(ng)
    tmpl = np.exp(-0.5 * (gx / s) ** 2)
    spl = _bspline_design(nb, ts / q)
    idx = np.arange(nb, dtype=float)
    for _ in range(rounds):
        # Template (grid values, linear interpolation) and baseline splines,
        # the pulses' centres, amplitudes and stretches fixed, 3 passes.
        for _ in range(3):
            rows, cols, vals = [], [], []
            for ci, ai in zip(c, amps):
                u = idx[int(max(ci - 3 * hw, 0)):int(min(ci + 3 * hw + 1, nb))]
                g = (u - ci - gx[0]) / grid_h
                j = np.clip(np.floor(g).astype(int), 0, ng - 2)
                fr = g - j
                rows += [u, u]
                cols += [j, j + 1]
                vals += [ai * (1 - fr), ai * fr]
            T = sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows).astype(int), np.concatenate(cols))),
                                  shape=(nb, ng))
            D = sparse.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(ng - 2, ng))
            A = sparse.hstack([T, spl]).tocsr()
            pen = sparse.block_diag([1e-2 * (D.T @ D) * (T.multiply(T).sum() / ng), sparse.csr_matrix((spl.shape[1],) * 2)])
            sol = spsolve((A.T @ A + pen).tocsc(), A.T @ z)
            tmpl = sol[:ng] / max(np.max(np.abs(sol[:ng])), 1e-300)
            beta = sol[ng:]
        baseline = spl @ beta
        r = z - baseline
        # Each pulse against the template (Levenberg-Marquardt on a, c, s, o).
        h = lambda u: np.interp(u, gx, tmpl, left=0.0, right=0.0)
        newc, newa = [], []
        for ci, ai in zip(c, amps):
            lo, hi = int(max(ci - 3.3 * hw, 0)), int(min(ci + 3.3 * hw + 1, nb))
            u = idx[lo:hi]
            d = r[lo:hi]
            res = optimize.least_squares(lambda t: t[3] + t[0] * h((u - t[1]) / t[2]) - d,
                                         [ai, ci, 1.0, 0.0], method="lm")
            newa.append(res.x[0])
            newc.append(res.x[1])
        c, amps = np.array(newc), np.array(newa)
        # Matched filter of both polarities for pulses the seeds missed.
        mf = signal.correlate(r, tmpl[::-1], mode="same", method="fft")
        noise = _noise_sigma(mf, 1)
        for sgn in (1.0, -1.0):
            signal.find_peaks(sgn * mf, height=6.0 * noise, distance=max(0.7 * ts / q, 1.0))
    t = (c * q + 0.5 * (q - 1)) / fs
    gaps = np.diff(t)
    return dict(count=len(t), times_s=t, tau_c_s=(gaps.mean(), gaps.std(ddof=1)),
                f_c_hz=1.0 / gaps.mean(), fwhm_s=fwhm / fs)


# ------------------------------------------------------- period, phases, lines
def measured_period(auto, lag_s, fs, tau_pred, window=0.25):
    """Autocorrelation maxima near k T, refined, T re-fitted (correlation.rs)."""
    mid = len(auto) // 2
    half = max(int(round(window * tau_pred * fs)), 1)
    ks, ts = [], []
    k = 1
    while True:
        centre = mid + int(round(k * tau_pred * fs))
        if centre + half + 1 >= len(auto):
            break
        seg = auto[centre - half:centre + half + 1]
        i = int(np.argmax(seg))
        if 0 < i < len(seg) - 1:
            a, b, c = seg[i - 1], seg[i], seg[i + 1]
            off = 0.5 * (a - c) / (a - 2 * b + c)
        else:
            off = 0.0
        ks.append(k)
        ts.append(lag_s[centre - half + i] + off / fs)
        k += 1
    ks, ts = np.array(ks, float), np.array(ts)
    slope = np.linalg.lstsq(ks[:, None], ts, rcond=None)[0][0]
    return slope, np.sqrt(np.mean((ts - slope * ks) ** 2))


def phases(sig, fs, f_c, pairs):
    """Cross spectra at f_c itself from Hann segments of three periods (phase.rs)."""
    n = len(next(iter(sig.values())))
    seg = min(int(round(3.0 / f_c * fs)), n // 2)
    step = seg // 2
    starts = np.arange(0, n - seg + 1, step)
    win = signal.get_window("hann", seg)
    e = win * np.exp(-2j * np.pi * f_c * np.arange(seg) / fs)
    dft = {}
    for name, x in sig.items():
        frames = np.lib.stride_tricks.sliding_window_view(x, seg)[starts]
        dft[name] = (frames - frames.mean(axis=1, keepdims=True)) @ e
    nd = len(starts) * 0.9
    out = []
    for p, q in pairs:
        pxy = np.mean(np.conj(dft[p]) * dft[q])
        pxx, pyy = np.mean(np.abs(dft[p]) ** 2), np.mean(np.abs(dft[q]) ** 2)
        g2 = abs(pxy) ** 2 / (pxx * pyy)
        ph = np.degrees(np.angle(pxy))
        ci = 1.96 * np.degrees(math.sqrt((1 - g2) / (2 * nd * g2)))
        out.append(dict(pair=(p, q), phase_deg=ph, ci95_deg=ci, coherence=g2,
                        threshold=1 - (1 - CONFIDENCE) ** (1 / (nd - 1)), lag_s=ph / (360 * f_c)))
    return out


_HX, _HW = np.polynomial.hermite_e.hermegauss(24)
_HW = _HW / _HW.sum()


def _harmonic_p(f, psd, fk, f_c, nu, tested):
    """p-value of the largest tested bin over the fitted floor (spectra.rs)."""
    df = f[1] - f[0]
    lo, hi = (fk / 2.5, 2.5 * fk) if abs(fk - f_c) < 1e-12 else (fk - 1.5 * f_c, fk + 1.5 * f_c)
    m = (f >= lo) & (f <= hi)
    m[:2] = False
    for j in range(1, int(hi / f_c) + 2):
        m &= np.abs(f - j * f_c) > 1.5 * df
    lf, lp = np.log(f[m]), np.log(psd[m])
    deg = 2 if m.sum() >= 12 else 1
    coef = np.polyfit(lf, lp, deg)
    fit = np.polyval(coef, lf)
    e_ln = digamma(nu / 2) - math.log(nu / 2)
    floor = np.exp(np.polyval(coef, np.log(f[tested])) - e_ln)
    t = float(np.max(psd[tested] / floor))
    s2 = np.var(lp - fit, ddof=deg + 1)
    tri = polygamma(1, nu / 2)
    m2 = max(0.0, s2 - tri)
    V = np.vander(lf - lf.mean(), deg + 1)
    lev = np.vander(np.log([fk]) - lf.mean(), deg + 1) @ np.linalg.pinv(V.T @ V) @ np.vander(np.log([fk]) - lf.mean(), deg + 1).T
    sig2 = (tri + m2) * lev[0, 0] * (1 + 2 * (4 / 9 + 1 / 36)) + m2
    eps = math.sqrt(sig2) * _HX
    cdf = stats.chi2.cdf(nu * t * np.exp(eps)[:, None], nu) ** len(tested)
    return float(1.0 - _HW @ cdf[:, 0]), t


def harmonics(spec, f_c_pred, f_c_meas, nu, signals):
    """Harmonic tests at the predicted and measured f_c, with Holm (spectra.rs)."""
    f = spec["freq_hz"]
    alpha = 1 - CONFIDENCE
    rows = []
    for s in signals:
        psd = spec[s]
        ps = []
        for k in range(1, HARMONICS + 1):
            for fc in (f_c_pred, f_c_meas):
                fk = k * fc
                if fk * 1.5 >= f[-1]:
                    continue
                i = int(fk / (f[1] - f[0]))
                tested = np.array([max(i - 1, 1), i, i + 1]) if fc == f_c_pred else np.array([i, i + 1])
                ps.append(_harmonic_p(f, psd, fk, fc, nu, tested)[0])
        order = np.argsort(ps)
        adj = np.maximum.accumulate(np.minimum(1.0, (len(ps) - np.arange(len(ps))) * np.array(ps)[order]))
        rows.append((s, adj < alpha))
    return rows


def sync_average(sig, fs, times, bins=64):
    """Mean waveform between passages with its Student-t band (sync)."""
    times = np.asarray(times)
    gaps = np.diff(times)
    med = np.median(gaps)
    ok = (gaps >= 0.5 * med) & (gaps <= 1.5 * med)
    t0, t1 = times[:-1][ok], times[1:][ok]
    ph = np.arange(bins) / bins
    tt = t0[:, None] + ph[None, :] * (t1 - t0)[:, None]
    out = {}
    n = len(next(iter(sig.values())))
    ts = np.arange(n) / fs
    for name, x in sig.items():
        y = np.interp(tt, ts, x)
        mean = y.mean(axis=0)
        band = stats.t.ppf(0.975, len(y) - 1) * y.std(axis=0, ddof=1) / math.sqrt(len(y))
        c1 = np.mean(mean * np.exp(-2j * np.pi * np.arange(bins) / bins))
        sel = (ts >= t0[0]) & (ts < t1[-1])
        phase = np.interp(ts[sel], times, np.arange(len(times)))
        model = np.interp((phase % 1.0) * bins, np.arange(bins + 1), np.r_[mean, mean[0]])
        xs = x[sel]
        explained = 1 - np.sum((xs - model) ** 2) / np.sum((xs - xs.mean()) ** 2)
        out[name] = dict(mean=mean, band=band, pp=np.ptp(mean), amplitude=2 * abs(c1), explained=explained)
    return out


def position_spectra(sos, fs, position, signals, d_avg=D_AVG_MM):
    """Friction, velocity error and optical against the travel (position)."""
    v = signal.sosfiltfilt(sos, np.gradient(position, 1.0 / fs))
    dx = 2.0 * d_avg / 64.0
    vmin = np.min(np.abs(v))
    fb = 20.0
    q = 1
    while dx / q > vmin / (2 * fb) and q < 64:
        q *= 2
    p = np.maximum.accumulate(position)
    m = int((p[-1] - p[0]) / (dx / q))
    xg = p[0] + (dx / q) * np.arange(m)
    ts = np.arange(len(p)) / fs
    tg = np.interp(xg, p, ts)
    on_grid = {}
    for name, y in list(signals.items()) + [("velocity", v)]:
        g = np.interp(tg, ts, y)
        while q > 1:
            step = min(q, 8)
            g = signal.decimate(g, step, ftype="iir", zero_phase=True)
            q //= step
        on_grid[name] = g
    per = 64
    ve = on_grid.pop("velocity")
    ve = ve[per // 2: len(ve) - per // 2 + 1] - np.convolve(ve, np.ones(per) / per, mode="valid")[: len(ve) - per + 1]
    on_grid["velocity_error"] = ve
    nperseg = 1024
    line = 1.0 / (2.0 * d_avg)
    win = signal.get_window("hann", nperseg)
    out = {}
    for name, g in on_grid.items():
        f, psd = signal.welch(g, 1.0 / dx, window="hann", nperseg=nperseg, detrend="linear")
        starts = np.arange(0, len(g) - nperseg + 1, nperseg // 2)
        segs = np.lib.stride_tricks.sliding_window_view(g, nperseg)[starts]
        segs = signal.detrend(segs, axis=1) * win
        xs = dx * np.arange(nperseg)
        power = lambda fr: np.mean(np.abs(segs @ np.exp(-2j * np.pi * np.outer(xs, fr))) ** 2, axis=0)
        df = f[1]
        lines = []
        for k in range(1, HARMONICS + 1):
            fk = k * line
            lo, hi = max(int(math.ceil(0.75 * fk / df)), 1), min(int(1.25 * fk / df), len(psd) - 3)
            if lo + 2 > hi:
                continue
            i = lo + int(np.argmax(psd[lo:hi + 1]))
            a, b = (i - 1) * df, (i + 1) * df
            h = (b - a) / 64
            gp = power(a + h * np.arange(65))
            best = a + h * int(np.argmax(gp))
            a, b = max(best - h, (i - 1) * df), min(best + h, (i + 1) * df)
            gr = 0.5 * (math.sqrt(5) - 1)
            while b - a > 1e-4 * h:
                c, d = b - gr * (b - a), a + gr * (b - a)
                pc, pd = power(np.array([c, d]))
                if pc >= pd:
                    b = d
                else:
                    a = c
            i0 = min(max(int(round(fk / df)), lo), hi)
            j = np.arange(max(int(math.ceil(0.5 * fk / df)), 1), min(int(1.5 * fk / df), len(psd) - 1) + 1)
            hh = np.round(j * df / line)
            rest = psd[j[(np.abs(j - i0) > 2) & (np.abs(j * df - hh * line) > 2 * df)]]
            # The median of bins distributed S chi2_nu / nu, over the median of
            # chi2_nu / nu (nu the Welch dof of the segments, Hann at half
            # overlap: 1.89 per segment), is the mean level S.
            nu = 2 * len(starts) / (1 + 2 * 0.028) if len(starts) > 1 else 2.0
            floor = np.median(rest) / (stats.chi2.ppf(0.5, nu) / nu) if len(rest) else 0.0
            pw = max(np.sum(psd[max(i0 - 2, 0):i0 + 3] - floor) * df, 0.0)
            lines.append((k, 0.5 * (a + b), pw))
        out[name] = (f, psd, lines)
    return out


# ------------------------------------------------------------------ pipeline
def pipeline(fs, friction, position, optical, a, timer=None):
    """Every stage of `ballpass.analyze`, in its order, as SciPy would do it.

    `timer(name, seconds)`, if given, receives each stage's time."""
    import time

    clock = time.process_time
    t = clock()
    marks = []

    def mark(name):
        nonlocal t
        now = clock()
        marks.append((name, now - t))
        t = now

    v = a.velocity
    tau_c = 2.0 * D_AVG_MM / v
    f_c = 1.0 / tau_c
    restored, lc = load_cell(friction, fs, tau_c)
    mark("load-cell correction")
    sig, corr, full, hires, unfiltered = ref.analyze(fs, restored, position, optical, a)
    mark("low-pass, correlations, three spectra with bands")
    ve_raw = np.gradient(position, 1.0 / fs) - v
    stage = stage_identify(restored, ve_raw, fs)
    mark("stage identification")
    ps = passages(optical, fs, tau_c)
    mark("optical passages")
    periods = {s: measured_period(corr[s], corr["lag_s"], fs, tau_c) for s in ("friction", "velocity_error", "optical")}
    t_meas = periods["optical"][0]
    ph = phases(sig, fs, 1.0 / t_meas, [p for p in ref.PAIRS if p[0] != p[1]])
    # Welch dof of the full-range spectra (Hann at half overlap, Percival &
    # Walden Eq. 292b: 1.89 per segment).
    k = (len(sig["friction"]) - 4096) // 2048 + 1
    nu = 2 * k / (1 + 2 * 0.028) if k > 1 else 2.0
    hm = harmonics(full, f_c, 1.0 / t_meas, nu, ("friction", "velocity_error", "optical"))
    mark("period, phases, harmonic tests")
    sy = sync_average({"friction": sig["friction"], "velocity_error": sig["velocity_error"] * 1e3}, fs, ps["times_s"])
    mark("synchronous average")
    sos = signal.butter(a.order, a.lowpass, "low", fs=fs, output="sos")
    pos = position_spectra(sos, fs, position, {
        "friction": signal.sosfiltfilt(sos, restored),
        "optical": signal.sosfiltfilt(sos, optical)})
    mark("position-domain spectra")
    if timer:
        for name, dt in marks:
            timer(name, dt)
    return dict(load_cell=lc, corr=corr, full=full, hires=hires, unfiltered=unfiltered, stage=stage,
                passages=ps, periods=periods, phases=ph, harmonics=hm, sync=sy, position=pos)


def main():
    import argparse
    import time
    import warnings

    import ballpass
    from bench_scipy_analyze import ref_namespace

    ap = argparse.ArgumentParser()
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--repeat", type=int, default=7)
    opts = ap.parse_args()
    warnings.simplefilter("ignore")
    rec, _ = ballpass.simulate(9.0, seed=1)
    fs, fr, pos, opt = rec.fs_hz, rec.friction_n, rec.position_mm, rec.optical_v
    args = ref_namespace(9.0, "unused")
    if opts.check:
        out = pipeline(fs, fr, pos, opt, args)
        r = ballpass.analyze(ballpass.Recording(fs, fr, pos, opt, velocity_mm_s=9.0)).to_dict()
        print("load-cell tau, s:", out["load_cell"]["tau_s"], "ballpass", r["load_cell"][0]["tau_s"])
        print("passages:", out["passages"]["count"], out["passages"]["f_c_hz"], "ballpass",
              r["passages"][0]["count"], r["passages"][0]["f_c_hz"])
        print("period (optical), s:", out["periods"]["optical"][0], "ballpass", r["measured_period"]["period_s"])
        print("stage f_n, zeta:", out["stage"]["natural_frequency_hz"], out["stage"]["damping_ratio"], "ballpass",
              r["stage"]["natural_frequency_hz"]["value"], r["stage"]["damping_ratio"]["value"])
        print("phases, deg:", [round(p["phase_deg"], 1) for p in out["phases"]], "ballpass",
              [p["phase_deg"] and round(p["phase_deg"], 1) for p in r["phases"]])
        print("sync friction p-p, N:", out["sync"]["friction"]["pp"])
        print("position lines (friction):", out["position"]["friction"][2][:2], "ballpass",
              [(l["k"], l["measured_per_mm"], l["power"]) for l in r["position"]["lines"][:2]])
    totals = {}
    for _ in range(opts.repeat):
        got = {}
        pipeline(fs, fr, pos, opt, args, timer=lambda n, t: got.__setitem__(n, t))
        for n, t in got.items():
            totals[n] = min(totals.get(n, float("inf")), t)
    for n, t in totals.items():
        print(f"{n:50s} {t * 1e3:8.2f} ms")
    print(f"{'sum of the best per stage':50s} {sum(totals.values()) * 1e3:8.2f} ms")


if __name__ == "__main__":
    main()
