"""Fixtures for ballpass_dsp::peaks: scipy.signal.find_peaks, peak_prominences
and peak_widths on many signals and settings.

One fixture per signal: {"x", "find_peaks": [case...], "prominences": [...],
"widths": [...]}. A find_peaks case stores its settings as
{"height": [min, max], ..., "distance": d, "wlen": w, "rel_height": r}
(null = open end; a missing key = criterion off) and SciPy's outputs.

Ties in the distance criterion: SciPy ranks peaks with NumPy's default
argsort, whose order of equal heights is not stable and differs between CPUs.
ballpass ranks equal heights by position (argsort kind="stable"). A case whose
outcome depends on that order is left out here (printed) and covered by a unit
test in peaks.rs instead.
"""
import warnings

import numpy as np
from scipy.signal import find_peaks, peak_prominences, peak_widths
from scipy.signal._peak_finding_utils import _select_by_peak_distance

CRITERIA = ("height", "threshold", "prominence", "width", "plateau_size")


def signals():
    rng = np.random.default_rng(20240611)
    out = {}
    for n in range(0, 6):
        out[f"tiny_{n}"] = rng.standard_normal(n)
    for n in (6, 7, 50, 51, 200, 201, 600, 601):
        out[f"noise_{n}"] = rng.standard_normal(n)
    # Integer levels: plateaus and exactly equal values everywhere.
    for n in (40, 301):
        out[f"levels_{n}"] = rng.integers(0, 4, n).astype(float)
    # Plateaus of sizes 1..6, also touching both edges.
    p = [3.0, 3.0, 1.0, 2.0, 0.0, 4.0, 4.0, 1.0, 5.0, 5.0, 5.0, 0.0, 2.0, 2.0, 2.0, 2.0, 1.0]
    p += [6.0] * 5 + [0.0, 1.0] + [3.0] * 6 + [2.0, 7.0, 7.0]
    out["plateaus"] = np.array(p)
    out["plateaus_negative"] = -10.0 + 0.5 * np.array(p[::-1])
    out["constant"] = np.full(20, 1.5)
    out["negative_noise"] = -100.0 + 0.01 * rng.standard_normal(500)
    # Optical-sensor-like pulse trains at 1 kHz: Gaussian pulses every
    # ~0.2 s with jitter, amplitude spread, baseline drift and noise.
    for name, n, noise in (("pulses_clean", 1500, 0.0), ("pulses_noisy", 1600, 0.05),
                           ("pulses_very_noisy", 1201, 0.2)):
        t = np.arange(n) / 1000.0
        x = 0.1 + 0.05 * np.sin(2 * np.pi * 0.3 * t)
        c = 0.05
        while c < t[-1]:
            a = 1.0 + 0.1 * rng.standard_normal()
            x += a * np.exp(-0.5 * ((t - c) / 0.012) ** 2)
            c += 0.2 + 0.01 * rng.standard_normal()
        out[name] = x + noise * rng.standard_normal(n)
    return out


def settings_list():
    s = [{}]
    s += [{"height": [0.5, None]}, {"height": [0.2, 1.0]}, {"height": [None, 0.5]},
          {"height": [None, None]}]
    s += [{"threshold": [0.1, None]}, {"threshold": [0.05, 0.5]}, {"threshold": [None, None]}]
    s += [{"distance": d} for d in (1, 2.5, 10, 50, 150)]
    s += [{"prominence": [0.5, None]}, {"prominence": [0.2, 2.0]}, {"prominence": [None, None]}]
    s += [{"prominence": [0.3, None], "wlen": w} for w in (2, 5, 20.5, 101, 10**9)]
    s += [{"width": [3, None]}, {"width": [2, 20]}]
    s += [{"width": [None, None], "rel_height": r} for r in (0.0, 0.25, 0.5, 1.0)]
    s += [{"width": [None, None], "wlen": 31, "rel_height": 1.0}]
    s += [{"plateau_size": v} for v in ([1, None], [2, None], [None, None], [2, 3])]
    s += [{"distance": 100, "prominence": [0.3, None]},
          {"height": [0.0, None], "threshold": [None, None], "distance": 3,
           "prominence": [0.1, None], "width": [1, 50], "rel_height": 0.5},
          {"height": [None, None], "threshold": [None, None], "distance": 1,
           "prominence": [None, None], "width": [None, None], "plateau_size": [None, None],
           "wlen": 50, "rel_height": 0.25},
          {"plateau_size": [1, 4], "height": [-9.0, None], "distance": 4,
           "width": [None, None], "rel_height": 1.0}]
    return s


def scipy_kwargs(s):
    kw = {k: tuple(v) for k, v in s.items() if k in CRITERIA}
    for k in ("distance", "wlen", "rel_height"):
        if k in s:
            kw[k] = s[k]
    return kw


def distance_tie_sensitive(x, s):
    """Whether the distance step's result depends on the order of ties."""
    if "distance" not in s:
        return False
    before = {k: v for k, v in scipy_kwargs(s).items()
              if k in ("height", "threshold", "plateau_size")}
    peaks, _ = find_peaks(x, **before)
    pr = x[peaks]
    scipy_keep = _select_by_peak_distance(peaks, pr, float(s["distance"]))
    d = int(np.ceil(s["distance"]))
    keep = np.ones(peaks.size, dtype=bool)
    for j in np.argsort(pr, kind="stable")[::-1]:
        if not keep[j]:
            continue
        k = j - 1
        while k >= 0 and peaks[j] - peaks[k] < d:
            keep[k] = False
            k -= 1
        k = j + 1
        while k < peaks.size and peaks[k] - peaks[j] < d:
            keep[k] = False
            k += 1
    return not np.array_equal(keep, scipy_keep)


def generate(write):
    warnings.simplefilter("ignore")  # PeakPropertyWarning for zero prominences/widths
    for name, x in signals().items():
        x = np.asarray(x, dtype=float)
        cases = []
        big = x.size > 300
        for s in settings_list():
            if big and s.get("width") == [None, None] and len(s) <= 3 \
                    and s.get("rel_height") != 0.5:
                continue  # the direct peak_widths cases cover these; keeps fixtures small
            if distance_tie_sensitive(x, s):
                print(f"  skip {name} {s}: distance outcome depends on the order of ties")
                continue
            peaks, props = find_peaks(x, **scipy_kwargs(s))
            cases.append({"settings": s, "peaks": peaks, "properties": props})
        local, _ = find_peaks(x)
        queries = [local]
        if x.size:
            # Non-maxima, edges, unsorted and repeated indices.
            queries.append(np.array([x.size - 1, 0, x.size // 2, x.size // 2]))
        proms, widths = [], []
        # Fewer combinations on long signals to keep the fixtures small.
        wlens = (None, 3.1, 41) if big else (None, 2, 3, 3.1, 8, 41, 10**9)
        width_args = ((None, 0.5), (None, 1.0), (9, 0.25)) if big else \
            [(w, r) for w in (None, 9) for r in (0.0, 0.25, 0.5, 1.0, 2.0)]
        for q in queries:
            for wlen in wlens:
                pr, lb, rb = peak_prominences(x, q, wlen=wlen)
                proms.append({"peaks": q, "wlen": wlen, "prominences": pr,
                              "left_bases": lb, "right_bases": rb})
            for wlen, rel in width_args:
                w, wh, li, ri = peak_widths(x, q, rel_height=rel, wlen=wlen)
                widths.append({"peaks": q, "wlen": wlen, "rel_height": rel, "widths": w,
                               "width_heights": wh, "left_ips": li, "right_ips": ri})
        write(name, {"x": x, "find_peaks": cases, "prominences": proms, "widths": widths})
