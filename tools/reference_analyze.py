#!/usr/bin/env python3
"""NumPy/SciPy reference of `ballpass analyze`'s numeric steps.

Two uses:
  * parity fixtures: the Rust tests compare every exported correlation and
    spectrum with what this script computes on the same recording (relative
    error <= 1e-9);
  * the speed baseline: `--time` runs the same steps in-process (CSV read to
    files written) and prints the best wall time, to put beside ballpass'.

Steps (the defaults of ballpass' AnalyzeSettings; each is a flag here too):
  0. trim: the first round(trim * fs) samples are dropped (velocity is
     differentiated on the whole record first, then cut)
  1. velocity = np.gradient(position_mm, 1/fs); velocity_error = velocity - V
  2. for friction, velocity_error, optical:
       y = sosfiltfilt(butter(order, lowpass, 'low', fs=fs, output='sos'), x)
       y = detrend(y, type=detrend)
  3. correlations: correlate(x, y, 'full') for the 3 autos and the pairs
     (friction, velocity_error), (friction, optical), (velocity_error, optical);
     lags = correlation_lags(N, N) / fs; normalisation biased / unbiased / coeff / none
  4. full-range spectra on the step-2 signals: welch/csd(nperseg, noverlap,
     window='hann', detrend='constant', scaling='density'), coherence
  4b. the same full-range spectra of the unfiltered signals (after step 1:
     trimmed, velocity error, no low-pass, no detrend; Welch still removes
     each segment's mean), as the thesis' Figs. 62 and 64
  5. high-resolution spectra: decimate(step-2 signal, q) (IIR, zero phase),
     then welch/csd/coherence at fs/q with nperseg_hr, where by default
     q = floor(fs / (2.5 lowpass)) and
     nperseg_hr = min(next_smooth(6 (fs/q) / f_c), len(decimated)) (six
     periods rounded up to the next even 2^a 3^b 5^c),
     f_c = V / (2 d_avg); or, with --zoom M, the thesis' polyphase average:
     mean over i < M of welch/csd(x[i::M][:N//M], fs/M), coherence
     |mean Pxy|^2 / (mean Pxx mean Pyy).

Column names carry their units, as ballpass writes them (lowercase unit
tokens: n = N, mm_s = mm/s, v = V, a digit for a power, per_ before a
divisor; no token = dimensionless): correlations.csv has lag_s and
r_<series>[_<unit>] (no unit when coeff-normalised), the spectra files
freq_hz, psd_<signal>_<unit2>_per_hz, csd_<pair>_re/_im_<unit>_per_hz and
coh_<pair>.

Usage:
  python3 tools/reference_analyze.py REC.csv --velocity 9 --out DIR [--time]
Pinned versions: tools/requirements.txt.
"""
import argparse
import json
import pathlib
import time

import numpy as np
from scipy import signal, stats

PAIRS = [
    ("friction", "friction"),
    ("velocity_error", "velocity_error"),
    ("optical", "optical"),
    ("friction", "velocity_error"),
    ("friction", "optical"),
    ("velocity_error", "optical"),
]


def series_name(a, b):
    return a if a == b else f"{a}__{b}"


UNIT = {"friction": "n", "velocity_error": "mm_s", "optical": "v"}
SQUARED = {"friction": "n2", "velocity_error": "mm2_s2", "optical": "v2"}


def product_unit(a, b):
    return SQUARED[a] if a == b else f"{UNIT[a]}_{UNIT[b]}"


def correlation_table(corr, norm):
    """correlations.csv columns: lag_s, r_<series>[_<unit of the product>]."""
    out = {"lag_s": corr["lag_s"]}
    for p, q in PAIRS:
        name = "r_" + series_name(p, q)
        if norm != "coeff":
            name += "_" + product_unit(p, q)
        out[name] = corr[series_name(p, q)]
    return out


def band_factors(length, nperseg, noverlap, confidence=0.95):
    """Chi-square band of a Welch PSD: factors [nu/chi2(1-a/2), nu/chi2(a/2)] for the
    bins between DC and Nyquist and for those two (half the dof), with nu the
    equivalent dof of K periodic-Hann segments (Percival & Walden 292b)."""
    step = nperseg - noverlap
    k = (length - nperseg) // step + 1
    w = signal.get_window("hann", nperseg)
    h = w / np.sqrt(np.sum(w * w))
    s = 0.0
    for j in range(1, k):
        if j * step >= nperseg:
            break
        s += (1 - j / k) * np.sum(h[j * step:] * h[: nperseg - j * step]) ** 2
    nu = 2 * k / (1 + 2 * s)
    a = 1 - confidence
    f = lambda v: (v / stats.chi2.ppf(1 - a / 2, v), v / stats.chi2.ppf(a / 2, v))
    return f(nu), f(nu / 2), nperseg


def spectrum_table(spec):
    """spectra*.csv columns: freq_hz, psd_*, then csd_*_re/_im and coh_* per pair,
    then the 95 % band of each psd."""
    out = {"freq_hz": spec["freq_hz"]}
    for p, q in PAIRS:
        if p == q:
            out[f"psd_{p}_{SQUARED[p]}_per_hz"] = spec[p]
    for p, q in PAIRS:
        if p != q:
            name, unit = series_name(p, q), product_unit(p, q)
            out[f"csd_{name}_re_{unit}_per_hz"] = spec[name + "_re"]
            out[f"csd_{name}_im_{unit}_per_hz"] = spec[name + "_im"]
            out[f"coh_{name}"] = spec[name + "_coh"]
    (lo, hi), (lo_e, hi_e), nperseg = spec["_band"]
    for p, q in PAIRS:
        if p == q:
            nb = len(spec[p])
            edge = np.zeros(nb, bool)
            edge[0] = True
            if nperseg % 2 == 0:
                edge[-1] = True
            out[f"psd_{p}_lower_{SQUARED[p]}_per_hz"] = spec[p] * np.where(edge, lo_e, lo)
            out[f"psd_{p}_upper_{SQUARED[p]}_per_hz"] = spec[p] * np.where(edge, hi_e, hi)
    return out


def load_csv(path):
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=1)
    header = pathlib.Path(path).read_text().split("\n", 1)[0].strip().lower().split(",")
    cols = {name: data[:, i] for i, name in enumerate(header)}
    t = cols["time_s"]
    # Rate from the whole span, snapped to 12 significant digits: a time
    # column printed from i / fs gives fs exactly, as ballpass' loader does
    # (recording/io/timebase.rs). 1 / median(diff(t)) would be off by ~1e-14
    # relative, which shifts the velocity error by V * 1e-14 (visible
    # without detrending).
    fs = (len(t) - 1) / (t[-1] - t[0])
    fs = float(f"{fs:.12g}")
    return fs, cols["friction_n"], cols["position_mm"], cols["optical_v"]


def normalise(z, n, how, x, y):
    if how == "none":
        return z
    if how == "biased":
        return z / n
    if how == "unbiased":
        lags = signal.correlation_lags(n, n)
        return z / (n - np.abs(lags))
    if how == "coeff":
        return z / np.sqrt(np.dot(x, x) * np.dot(y, y))
    raise ValueError(how)


def analyze(fs, friction, position, optical, a):
    trim = int(round(a.trim * fs))
    v = np.gradient(position, 1.0 / fs)[trim:]
    ve = v - a.velocity
    friction = friction[trim:]
    optical = optical[trim:]
    raw = {"friction": friction, "velocity_error": ve, "optical": optical}
    sos = signal.butter(a.order, a.lowpass, "low", fs=fs, output="sos")
    sig = {}
    for name, x in (("friction", friction), ("velocity_error", ve), ("optical", optical)):
        y = signal.sosfiltfilt(sos, x)
        if a.detrend != "none":
            y = signal.detrend(y, type=a.detrend)
        sig[name] = y
    n = len(friction)
    corr = {"lag_s": signal.correlation_lags(n, n) / fs}
    for p, q in PAIRS:
        z = signal.correlate(sig[p], sig[q], mode="full", method="fft")
        corr[series_name(p, q)] = normalise(z, n, a.corr_norm, sig[p], sig[q])

    def spectra(s, fs_, nperseg, noverlap):
        out = {}
        for p, q in PAIRS:
            if p == q:
                f, pxx = signal.welch(s[p], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                out["freq_hz"] = f
                out[p] = pxx
            else:
                f, pxy = signal.csd(s[p], s[q], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                _, cxy = signal.coherence(s[p], s[q], fs_, window="hann", nperseg=nperseg, noverlap=noverlap)
                name = series_name(p, q)
                out[name + "_re"] = pxy.real
                out[name + "_im"] = pxy.imag
                out[name + "_coh"] = cxy
        out["_band"] = band_factors(len(s["friction"]), nperseg, noverlap)
        return out

    nperseg = min(a.nperseg, n)
    noverlap = a.noverlap if a.noverlap is not None else nperseg // 2
    full = spectra(sig, fs, nperseg, noverlap)
    unfiltered = spectra(raw, fs, nperseg, noverlap)
    f_c = a.velocity / (2.0 * a.d_avg)
    if a.zoom:
        m = a.zoom
        nd = n // m
        nhr = min(a.nperseg_hr or next_smooth(6.0 * (fs / m) / f_c), nd)
        nov = a.noverlap_hr if a.noverlap_hr is not None else nhr // 2
        hires = zoom_spectra(sig, fs, m, nhr, nov)
    else:
        q = a.q or max(int(np.floor(fs / (2.5 * a.lowpass))), 1)
        dec = sig if q < 2 else {
            k: signal.decimate(x, q, ftype="iir", zero_phase=True) for k, x in sig.items()
        }
        nd = len(dec["friction"])
        nhr = min(a.nperseg_hr or next_smooth(6.0 * (fs / q) / f_c), nd)
        nov = a.noverlap_hr if a.noverlap_hr is not None else nhr // 2
        hires = spectra(dec, fs / q, nhr, nov)
    return sig, corr, full, hires, unfiltered


def next_smooth(x):
    """Smallest even n >= x whose only prime factors are 2, 3 and 5."""
    n = max(2, int(np.ceil(x)))
    while True:
        m = n
        for p in (2, 3, 5):
            while m % p == 0:
                m //= p
        if m == 1 and n % 2 == 0:
            return n
        n += 1


def zoom_spectra(sig, fs, m, nperseg, noverlap):
    """Thesis zoom processing: mean of the spectra of the M polyphase branches."""
    n = len(sig["friction"]) // m
    br = {k: [x[i::m][:n] for i in range(m)] for k, x in sig.items()}
    kw = dict(window="hann", nperseg=nperseg, noverlap=noverlap)
    out = {}
    auto = {}
    for p, q in PAIRS:
        if p == q:
            ps = [signal.welch(b, fs / m, **kw) for b in br[p]]
            out["freq_hz"] = ps[0][0]
            auto[p] = np.mean([b[1] for b in ps], axis=0)
            out[p] = auto[p]
    for p, q in PAIRS:
        if p != q:
            pxy = np.mean([signal.csd(bx, by, fs / m, **kw)[1] for bx, by in zip(br[p], br[q])], axis=0)
            name = series_name(p, q)
            out[name + "_re"] = pxy.real
            out[name + "_im"] = pxy.imag
            out[name + "_coh"] = np.abs(pxy) ** 2 / auto[p] / auto[q]
    # ballpass states the dof of one branch's Welch average (the branches
    # are not independent averages, docs/methods.md section 10).
    out["_band"] = band_factors(n, nperseg, noverlap)
    return out


def write_csv(path, table):
    keys = list(table.keys())
    cols = np.column_stack([table[k] for k in keys])
    np.savetxt(path, cols, delimiter=",", header=",".join(keys), comments="", fmt="%.17g")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("rec")
    ap.add_argument("--velocity", type=float, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--lowpass", type=float, default=20.0)
    ap.add_argument("--order", type=int, default=5)
    ap.add_argument("--detrend", default="linear", choices=["linear", "constant", "none"])
    ap.add_argument("--corr-norm", default="coeff", choices=["none", "biased", "unbiased", "coeff"])
    ap.add_argument("--nperseg", type=int, default=4096)
    ap.add_argument("--noverlap", type=int, default=None)
    ap.add_argument("--q", type=int, default=None, help="default floor(fs / (2.5 lowpass))")
    ap.add_argument("--nperseg-hr", type=int, default=None, help="default f_c/4 resolution")
    ap.add_argument("--noverlap-hr", type=int, default=None)
    ap.add_argument("--zoom", type=int, default=None, help="thesis polyphase zoom factor M")
    ap.add_argument("--trim", type=float, default=0.0)
    ap.add_argument("--d-avg", type=float, default=4.0 + 2.0 / 36.0, help="mm (SR25W)")
    ap.add_argument("--time", action="store_true")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)

    def once():
        fs, fr, pos, opt = load_csv(a.rec)
        _, corr, full, hires, unfiltered = analyze(fs, fr, pos, opt, a)
        write_csv(out / "correlations.csv", correlation_table(corr, a.corr_norm))
        write_csv(out / "spectra.csv", spectrum_table(full))
        write_csv(out / "spectra_hires.csv", spectrum_table(hires))
        write_csv(out / "spectra_unfiltered.csv", spectrum_table(unfiltered))

    if a.time:
        best = min(_timed(once) for _ in range(5))
        print(json.dumps({"reference_analyze_best_s": best}))
    else:
        once()


def _timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
