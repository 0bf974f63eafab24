"""Fixtures for crates/ballpass-dsp/tests/filters.rs (area `filters`).

butter / cheby1 (zpk and SOS), sosfilt, sosfilt_zi, sosfiltfilt, decimate,
numpy.gradient, freqs / bode, freqz_sos, lfilter / lfilter_zi.
Signals are drawn from a fixed seed so the fixtures are reproducible.
"""
import numpy as np
from scipy import signal


def _signal(rng, n):
    t = np.arange(n)
    return (np.sin(2 * np.pi * t / 37.0) + 0.3 * np.cos(2 * np.pi * t / 5.3)
            + 0.5 * rng.standard_normal(n) + 2.0)


def lcg_signal(n, seed):
    """Deterministic test signal that the Rust test rebuilds without a
    fixture of its own: a 64-bit LCG's uniform noise on two tones and an
    offset (filters.rs `lcg_signal`)."""
    mask = (1 << 64) - 1
    s = seed & mask
    u = np.empty(n)
    for i in range(n):
        s = (s * 6364136223846793005 + 1442695040888963407) & mask
        u[i] = (s >> 11) / float(1 << 53) - 0.5
    t = np.arange(n)
    return np.sin(2 * np.pi * t / 37.0) + 0.3 * np.cos(2 * np.pi * t / 5.3) + u + 2.0


def generate(write):
    rng = np.random.default_rng(20240611)

    # --- filter design: butter over orders, bands, sampling rates ---
    designs = []
    for fs in (1000.0, 2.0, 250.0):
        nyq = fs / 2
        for order in range(1, 9):
            designs.append(("butter", order, None, "lowpass", [0.04 * nyq], fs))
            designs.append(("butter", order, None, "lowpass", [0.6 * nyq], fs))
            designs.append(("butter", order, None, "highpass", [0.1 * nyq], fs))
            designs.append(("butter", order, None, "bandpass", [0.05 * nyq, 0.3 * nyq], fs))
            designs.append(("butter", order, None, "bandstop", [0.2 * nyq, 0.45 * nyq], fs))
    designs.append(("butter", 5, None, "lowpass", [20.0], 1000.0))
    for order in (1, 2, 4, 5, 8):
        for rp in (0.05, 1.0):
            designs.append(("cheby1", order, rp, "lowpass", [0.3], 2.0))
            designs.append(("cheby1", order, rp, "highpass", [0.3], 2.0))
            designs.append(("cheby1", order, rp, "bandpass", [0.2, 0.5], 2.0))
            designs.append(("cheby1", order, rp, "bandstop", [0.2, 0.5], 2.0))
    for q in range(2, 21):
        designs.append(("cheby1", 8, 0.05, "lowpass", [0.8 / q], 2.0))

    out = []
    for kind, order, rp, btype, wn, fs in designs:
        wn_arg = wn[0] if len(wn) == 1 else wn
        if kind == "butter":
            z, p, k = signal.butter(order, wn_arg, btype=btype, output="zpk", fs=fs)
            sos = signal.butter(order, wn_arg, btype=btype, output="sos", fs=fs)
        else:
            z, p, k = signal.cheby1(order, rp, wn_arg, btype=btype, output="zpk", fs=fs)
            sos = signal.cheby1(order, rp, wn_arg, btype=btype, output="sos", fs=fs)
        z = np.asarray(z, dtype=complex)
        p = np.asarray(p, dtype=complex)
        out.append({"kind": kind, "order": order, "rp": rp, "btype": btype, "wn": wn,
                    "fs": fs, "z_re": z.real, "z_im": z.imag, "p_re": p.real,
                    "p_im": p.imag, "k": float(k), "sos": sos})
    write("design", {"cases": out})

    # --- sosfilt / sosfilt_zi / sosfiltfilt on several filters and lengths ---
    cases = []
    filt_specs = [
        ("butter", 5, None, "lowpass", [20.0], 1000.0),
        ("butter", 1, None, "lowpass", [50.0], 1000.0),
        ("butter", 2, None, "highpass", [5.0], 100.0),
        ("butter", 3, None, "bandpass", [0.1, 0.4], 2.0),
        ("butter", 4, None, "bandstop", [0.2, 0.3], 2.0),
        ("butter", 8, None, "lowpass", [0.2], 2.0),
        ("cheby1", 8, 0.05, "lowpass", [0.8 / 3], 2.0),
    ]
    lengths = [19, 20, 64, 101, 400]
    for kind, order, rp, btype, wn, fs in filt_specs:
        wn_arg = wn[0] if len(wn) == 1 else wn
        if kind == "butter":
            sos = signal.butter(order, wn_arg, btype=btype, output="sos", fs=fs)
        else:
            sos = signal.cheby1(order, rp, wn_arg, btype=btype, output="sos", fs=fs)
        padlen = 3 * (2 * len(sos) + 1 - min((sos[:, 2] == 0).sum(), (sos[:, 5] == 0).sum()))
        for n in lengths:
            if n <= padlen or (n == 400 and order not in (5, 8)):
                continue
            x = _signal(rng, n)
            zi = signal.sosfilt_zi(sos)
            zi_in = rng.standard_normal(zi.shape)
            y_state, zf = signal.sosfilt(sos, x, zi=zi_in)
            case = {"kind": kind, "order": order, "rp": rp, "btype": btype, "wn": wn,
                    "fs": fs, "sos": sos, "x": x, "padlen": int(padlen),
                    "sosfilt": signal.sosfilt(sos, x), "zi": zi,
                    "zi_in": zi_in, "sosfilt_state_y": y_state, "sosfilt_state_zf": zf,
                    "sosfiltfilt": signal.sosfiltfilt(sos, x)}
            for padtype in ("even", "constant", None):
                key = "sosfiltfilt_" + str(padtype).lower()
                case[key] = signal.sosfiltfilt(sos, x, padtype=padtype)
            case["sosfiltfilt_padlen7"] = signal.sosfiltfilt(sos, x, padlen=7)
            cases.append(case)
    write("sosfilt", {"cases": cases})

    # --- decimate, q = 2..20, odd/even lengths ---
    cases = []
    for q in range(2, 21):
        for n in ((301, 640) if q in (2, 3, 7, 20) else (301,)):
            x = _signal(rng, n)
            c = {"q": q, "x": x, "y": signal.decimate(x, q)}
            if q in (2, 5, 20):
                c["y_fwd"] = signal.decimate(x, q, zero_phase=False)
            cases.append(c)
    x = _signal(rng, 500)
    cases.append({"q": 4, "n": 4, "x": x, "y": signal.decimate(x, 4, n=4)})
    write("decimate", {"cases": cases})

    # --- long signals: sosfiltfilt and decimate on records long enough for
    # the chunked (SIMD-lane) filter path; x is rebuilt in Rust from `seed` ---
    long_cases = []
    for seed, n, order, btype, wn in ((7, 8000, 5, "lowpass", 20.0),
                                      (8, 8000, 3, "highpass", 50.0)):
        sos = signal.butter(order, wn, btype=btype, fs=1000.0, output="sos")
        long_cases.append({"kind": "sosfiltfilt", "seed": seed, "n": n, "sos": sos,
                           "y": signal.sosfiltfilt(sos, lcg_signal(n, seed))})
    for seed, n, q in ((9, 30000, 20), (10, 12000, 4)):
        long_cases.append({"kind": "decimate", "seed": seed, "n": n, "q": q,
                           "y": signal.decimate(lcg_signal(n, seed), q)})
    write("long", {"cases": long_cases})

    # --- numpy.gradient ---
    cases = []
    for n in (2, 3, 4, 10, 101):
        f = rng.standard_normal(n) * 10
        for h in (1.0, 0.001, 0.37):
            c = {"f": f, "h": h, "g1": np.gradient(f, h)}
            if n >= 3:
                c["g2"] = np.gradient(f, h, edge_order=2)
            cases.append(c)
        x = np.cumsum(rng.uniform(0.1, 2.0, n))
        c = {"f": f, "x": x, "g1": np.gradient(f, x)}
        if n >= 3:
            c["g2"] = np.gradient(f, x, edge_order=2)
        cases.append(c)
    write("gradient", {"cases": cases})

    # --- freqs / bode / freqz_sos ---
    cases = []
    w = np.logspace(-2, 3, 60)
    systems = [
        ([1.0], [1.0, 1.0]),
        ([1.0, 0.0], [1.0, 0.5, 4.0]),
        ([2.0, 3.0, 1.0], [1.0, 0.2, 9.0, 0.1]),
        ([25.0 * 40.0, 25.0 * 900.0], [1.0, 25.0 * 40.0, 25.0 * 900.0]),
        ([1.0], [1.0, 2.6131259, 3.4142136, 2.6131259, 1.0]),
        ([0.5, 3.0], [2.0, 1.0, 7.0, 3.0]),
    ]
    for b, a in systems:
        ww, h = signal.freqs(b, a, worN=w)
        _, mag, phase = signal.bode((b, a), w=w)
        cases.append({"b": b, "a": a, "w": w, "h": h, "mag": mag, "phase": phase})
    sos = signal.butter(5, 20.0, fs=1000.0, output="sos")
    f = np.linspace(0.0, 500.0, 257)
    _, hz = signal.freqz_sos(sos, worN=f, fs=1000.0)
    b, a = signal.butter(3, 0.2)
    _, hba = signal.freqz(b, a, worN=f, fs=1000.0)
    write("response", {"analog": cases, "sos": sos, "f": f, "h_sos": hz,
                       "b": b, "a": a, "h_ba": hba})

    # --- lfilter / lfilter_zi ---
    cases = []
    specs = [
        ([0.5], [1.0, -0.5]),
        ([1.0, 2.0, 1.0], [1.0]),
        ([0.2, 0.3], [2.0]),
        ([0.1, 0.2, 0.1], [1.0, -1.2, 0.5]),
        ([1.0, -1.0], [1.0, -0.9, 0.2, 0.05]),
        ([0.3, 0.1, 0.0, 0.2], [4.0, 1.0]),
    ]
    b5, a5 = signal.butter(5, 0.1)
    specs.append((list(b5), list(a5)))
    for b, a in specs:
        n = max(len(a), len(b))
        for length in (1, 7, 200):
            x = _signal(rng, length)
            zi_in = rng.standard_normal(n - 1)
            y_state, zf = signal.lfilter(b, a, x, zi=zi_in)
            c = {"b": b, "a": a, "x": x, "y": signal.lfilter(b, a, x),
                 "zi_in": zi_in, "y_state": y_state, "zf": zf}
            if len(a) > 1 or len(b) > 1:
                c["zi"] = signal.lfilter_zi(b, a)
            cases.append(c)
    write("lfilter", {"cases": cases})
