"""SciPy reference fixtures for ballpass-dsp's spectral kernels.

Area `spectral`: windows (get_window, periodic), detrend, correlate +
correlation_lags (with MATLAB-style normalisations computed in NumPy),
welch / csd / coherence / periodogram over many lengths and settings, and the
thesis' "zoom processing" (polyphase average of Welch spectra) implemented in
NumPy step by step.

Signals are stored once in `signals.json` (rounded to 1e-6 so that the JSON
stays small; SciPy runs on exactly the stored values) and referenced by name.
Every other fixture has a `kind` key that the Rust test dispatches on.
"""
import warnings

import numpy as np
import scipy.signal as sig

FS = 1000.0


def _signals():
    rng = np.random.default_rng(20240611)
    out = {}
    for n in [1, 2, 3, 7, 8, 16, 63, 100, 101, 255, 256, 257, 1000, 1001, 3000]:
        t = np.arange(n)
        a = rng.standard_normal(n) + 0.7 * np.sin(2 * np.pi * 0.0513 * t)
        b = 0.6 * np.roll(a, 5) + 0.8 * rng.standard_normal(n) + 0.3 * np.cos(2 * np.pi * 0.21 * t)
        out[f"a{n}"] = np.round(a, 6)
        out[f"b{n}"] = np.round(b, 6)
    t = np.arange(3000)
    # Large offset and trend: exercises the detrend options.
    out["trend3000"] = np.round(5.0 + 0.01 * t + rng.standard_normal(3000), 6)
    out["trend1001"] = out["trend3000"][:1001].copy()
    out["b900"] = out["b1000"][:900].copy()
    # 60 Hz hum plus a slow tone: what zoom processing aliases.
    tt = np.arange(3000) / FS
    out["hum3000"] = np.round(
        np.sin(2 * np.pi * 1.1096 * tt) + 0.5 * np.sin(2 * np.pi * 60 * tt) + 0.3 * rng.standard_normal(3000), 6)
    return out


def _settings(window="hann", nperseg=None, noverlap=None, nfft=None, detrend="constant",
              scaling="density", onesided=True, average="mean"):
    return dict(window=window, nperseg=nperseg, noverlap=noverlap, nfft=nfft, detrend=detrend,
                scaling=scaling, onesided=onesided, average=average)


def _scipy_kwargs(s):
    win = s["window"]
    if isinstance(win, list):
        win = np.asarray(win)
    kw = dict(window=win, nperseg=s["nperseg"], noverlap=s["noverlap"], nfft=s["nfft"],
              detrend=False if s["detrend"] == "none" else s["detrend"], scaling=s["scaling"],
              return_onesided=s["onesided"], average=s["average"])
    return kw


def _nseg(n, s):
    """Segments SciPy averages (nperseg shortened to n for named windows)."""
    nperseg = s["nperseg"] if s["nperseg"] is not None else 256
    if not isinstance(s["window"], list):
        nperseg = min(nperseg, n)
    noverlap = s["noverlap"] if s["noverlap"] is not None else nperseg // 2
    return (n - noverlap) // (nperseg - noverlap)


def generate(write):
    with warnings.catch_warnings():
        # SciPy warns when it shortens nperseg to the signal length; the
        # fixtures exercise exactly that on purpose.
        warnings.filterwarnings("ignore", message="nperseg = .* is greater than signal length")
        warnings.filterwarnings("ignore", message="nperseg=.* is greater than signal length")
        _generate(write)


def _generate(write):
    S = _signals()
    write("signals", S)

    # --- windows -----------------------------------------------------------
    for name in ["hann", "hamming", "boxcar"]:
        for n in [1, 2, 3, 4, 5, 16, 255, 256]:
            write(f"window_{name}_{n}", dict(kind="window", window=name, n=n,
                                             values=sig.get_window(name, n)))

    # --- detrend -----------------------------------------------------------
    for xname in ["a1", "a2", "a3", "a16", "a101", "trend1001"]:
        for typ in ["linear", "constant"]:
            write(f"detrend_{typ}_{xname}", dict(kind="detrend", x=xname, type=typ,
                                                 out=sig.detrend(S[xname], type=typ)))

    # --- correlate ---------------------------------------------------------
    pairs = [("a1", "b1"), ("a2", "b3"), ("a7", "b8"), ("a16", "b16"), ("a63", "b100"),
             ("a256", "b255"), ("a1001", "b1001"), ("b8", "a3"),
             ("a1000", "b900")]
    for xn, yn in pairs:
        x, y = S[xn], S[yn]
        z_direct = np.correlate(x, y, "full")
        # scipy.signal.correlate(method='fft') agrees with the direct sum to
        # rounding; the direct sum is the sharper reference.
        assert np.allclose(sig.correlate(x, y, mode="full", method="fft"), z_direct, rtol=0, atol=1e-9)
        lags = sig.correlation_lags(len(x), len(y), mode="full")
        out = dict(kind="correlate", x=xn, y=yn, lags=lags, direct=z_direct)
        small = max(len(x), len(y)) <= 256
        if small:
            out["coeff"] = z_direct / np.sqrt(np.sum(x * x) * np.sum(y * y))
        if small and len(x) == len(y):
            n = len(x)
            out["biased"] = z_direct / n
            out["unbiased"] = z_direct / (n - np.abs(lags))
        write(f"correlate_{xn}_{yn}", out)

    # --- welch / csd / coherence --------------------------------------------
    rng = np.random.default_rng(7)
    custom64 = np.round(0.5 + rng.random(64), 6).tolist()
    cases = []
    for n in [1, 2, 3, 7, 8, 100, 101, 255, 256, 257, 1000, 1001]:
        cases.append((f"a{n}", f"b{n}", _settings()))  # defaults (nperseg clamps below 256)
    cases += [
        ("a3000", "b3000", _settings(nperseg=64)),
        ("a3000", "b3000", _settings(nperseg=63)),
        ("a1001", "b1001", _settings(nperseg=100, noverlap=0)),
        ("a1001", "b1001", _settings(nperseg=100, noverlap=99)),
        ("a1001", "b1001", _settings(nperseg=100, noverlap=10, nfft=128)),
        ("a1001", "b1001", _settings(nperseg=101, noverlap=30, nfft=131)),
        ("trend3000", "a3000", _settings(nperseg=128, detrend="none")),
        ("trend3000", "a3000", _settings(nperseg=128, detrend="linear")),
        ("trend3000", "a3000", _settings(nperseg=128, detrend="constant")),
        ("a1000", "b1000", _settings(nperseg=100, scaling="spectrum")),
        ("a1000", "b1000", _settings(nperseg=100, onesided=False)),
        ("a1001", "b1001", _settings(nperseg=101, onesided=False, scaling="spectrum")),
        ("a1000", "b1000", _settings(nperseg=100, average="median")),   # 19 segments
        ("a1001", "b1001", _settings(nperseg=200, noverlap=100, average="median")),  # 9
        ("a1000", "b1000", _settings(nperseg=250, noverlap=0, average="median")),  # 4 (even)
        ("a1000", "b1000", _settings(nperseg=100, average="median", onesided=False)),
        ("a1000", "b1000", _settings(window="hamming", nperseg=100)),
        ("a1001", "b1001", _settings(window="boxcar", nperseg=77, noverlap=20)),
        ("a1000", "b1000", _settings(window=custom64, nperseg=64, noverlap=16)),
        ("a100", "b100", _settings(nperseg=256, nfft=300)),  # clamps to 100, pads to 300
        ("a3000", "b3000", _settings(nperseg=1000, nfft=1024, detrend="linear", average="median")),
        ("a1000", "b900", _settings(nperseg=128)),  # csd zero-pads the shorter y
    ]
    for i, (xn, yn, s) in enumerate(cases):
        x, y = S[xn], S[yn]
        kw = _scipy_kwargs(s)
        base = dict(x=xn, y=yn, fs=FS, settings=s)
        if len(x) == len(y):
            f, p = sig.welch(x, FS, **kw)
            write(f"welch_{i:02}", dict(kind="welch", **base, freq=f, pxx=p, n_segments=_nseg(len(x), s)))
        f, p = sig.csd(x, y, FS, **kw)
        write(f"csd_{i:02}", dict(kind="csd", **base, freq=f, pxy=p.astype(complex),
                                  n_segments=_nseg(max(len(x), len(y)), s)))
        if len(x) == len(y) and s["average"] == "mean" and s["onesided"]:
            ckw = {k: kw[k] for k in ["window", "nperseg", "noverlap", "nfft", "detrend"]}
            with np.errstate(invalid="ignore"):
                f, c = sig.coherence(x, y, FS, **ckw)
            if np.isnan(c).any():
                continue  # one-sample signals: 0/0 (NaN is checked in the Rust unit tests)
            write(f"coherence_{i:02}", dict(kind="coherence", **base, freq=f, cxy=c,
                                            n_segments=_nseg(len(x), s)))

    # --- periodogram ---------------------------------------------------------
    pcases = [
        ("a1", dict()), ("a2", dict()), ("a7", dict()), ("a100", dict()), ("a101", dict()),
        ("a100", dict(nfft=128)), ("a101", dict(nfft=64)), ("a101", dict(nfft=101)),
        ("a100", dict(window="hann")), ("a101", dict(window="hamming", scaling="spectrum")),
        ("a100", dict(onesided=False)), ("a101", dict(onesided=False, nfft=150)),
        ("trend1001", dict(detrend="linear")), ("trend1001", dict(detrend="none", nfft=999)),
        ("a16", dict(window=np.round(np.linspace(0.2, 1.0, 16), 6).tolist())),
    ]
    for i, (xn, over) in enumerate(pcases):
        s = dict(window="boxcar", nfft=None, detrend="constant", scaling="density", onesided=True)
        s.update(over)
        win = np.asarray(s["window"]) if isinstance(s["window"], list) else s["window"]
        f, p = sig.periodogram(S[xn], FS, window=win, nfft=s["nfft"],
                               detrend=False if s["detrend"] == "none" else s["detrend"],
                               return_onesided=s["onesided"], scaling=s["scaling"])
        write(f"periodogram_{i:02}", dict(kind="periodogram", x=xn, fs=FS, settings=s, freq=f, pxx=p))

    # --- zoom processing (thesis Fig. 61), NumPy step by step -----------------
    zcases = [("hum3000", "a3000", 20, _settings(nperseg=64)),
              ("hum3000", "a3000", 7, _settings(nperseg=128, detrend="linear")),
              ("a1001", "b1001", 3, _settings(nperseg=100, average="median")),
              ("a1000", "b1000", 1, _settings(nperseg=100))]
    for i, (xn, yn, m, s) in enumerate(zcases):
        x, y = S[xn], S[yn]
        kw = _scipy_kwargs(s)
        L = len(x) // m
        fs_b = FS / m
        px, pxy = [], []
        for k in range(m):
            xb = x[k::m][:L]   # x_k[j] = x[m j + k]
            yb = y[k::m][:L]
            f, p = sig.welch(xb, fs_b, **kw)
            px.append(p)
            f, p = sig.csd(xb, yb, fs_b, **kw)
            pxy.append(p)
        write(f"zoom_{i:02}", dict(kind="zoom", x=xn, y=yn, fs=FS, decimation=m, settings=s, freq=f,
                                   pxx=np.mean(px, axis=0), pxy=np.mean(pxy, axis=0).astype(complex),
                                   n_segments=_nseg(L, s)))
