"""ballpass.signal against SciPy 1.17 on the project's fixture inputs.

Every function is called the way a notebook calls SciPy (same positional and
keyword arguments) on the inputs of the SciPy fixtures that the Rust kernels
are tested on, and compared with SciPy's own answer computed here, to 1e-9
relative (see conftest.py for the two ways "relative" is measured).
"""

from __future__ import annotations

import importlib.util
import warnings

import numpy as np
import pytest
import scipy
from scipy import signal as ss

from ballpass import signal as bs

from conftest import ROOT, assert_close, assert_close_norm, fixture, fixtures


def test_scipy_is_the_pinned_version():
    # The comparisons mean "equals SciPy 1.17"; another SciPy would make them
    # compare against something else.
    assert scipy.__version__.startswith("1.17"), scipy.__version__


S = fixture("spectral", "signals")


def sig(name):
    return np.asarray(S[name], dtype=np.float64)


def scipy_window(w):
    return np.asarray(w) if isinstance(w, list) else w


def spectral_kwargs(s):
    return dict(
        window=scipy_window(s["window"]), nperseg=s["nperseg"], noverlap=s["noverlap"],
        nfft=s["nfft"], detrend=False if s["detrend"] == "none" else s["detrend"],
        scaling=s["scaling"], return_onesided=s["onesided"], average=s["average"],
    )


def both(fn, *args, **kw):
    """(ballpass, scipy) results of the same call, SciPy's warnings silenced
    (both warn the same way; see test_welch_warns_like_scipy)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return getattr(bs, fn)(*args, **kw), getattr(ss, fn)(*args, **kw)


# ---------------------------------------------------------------- spectra


@pytest.mark.parametrize("name,case", fixtures("spectral", "welch_"))
def test_welch(name, case):
    (f, p), (fs_, ps) = both("welch", sig(case["x"]), case["fs"], **spectral_kwargs(case["settings"]))
    assert_close(f, fs_, what=f"{name} f")
    assert_close(p, ps, what=f"{name} Pxx")


@pytest.mark.parametrize("name,case", fixtures("spectral", "csd_"))
def test_csd(name, case):
    (f, p), (fs_, ps) = both("csd", sig(case["x"]), sig(case["y"]), case["fs"],
                             **spectral_kwargs(case["settings"]))
    assert_close(f, fs_, what=f"{name} f")
    assert p.dtype == np.complex128
    assert_close(p.real, ps.real, what=f"{name} re")
    assert_close(p.imag, ps.imag, what=f"{name} im")


@pytest.mark.parametrize("name,case", fixtures("spectral", "coherence_"))
def test_coherence(name, case):
    kw = spectral_kwargs(case["settings"])
    kw = {k: kw[k] for k in ("window", "nperseg", "noverlap", "nfft", "detrend")}
    x, y = sig(case["x"]), sig(case["y"])
    (f, c), (fs_, cs) = both("coherence", x, y, case["fs"], **kw)
    assert_close(f, fs_)
    # Bins where Pxx or Pyy is rounding residue (the DC bin after each
    # segment's mean is removed, with a boxcar window) hold a ratio of
    # residues on both sides: compared only where both spectra have power
    # above 1e-20 of their peak, as in crates/ballpass-dsp/tests/spectral.rs.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pxx = ss.welch(x, case["fs"], **kw)[1]
        pyy = ss.welch(y, case["fs"], **kw)[1]
    live = (pxx > 1e-20 * pxx.max()) & (pyy > 1e-20 * pyy.max())
    assert_close(c[live], cs[live], what=name)


@pytest.mark.parametrize("name,case", fixtures("spectral", "periodogram_"))
def test_periodogram(name, case):
    s = case["settings"]
    kw = dict(window=scipy_window(s["window"]), nfft=s["nfft"],
              detrend=False if s["detrend"] == "none" else s["detrend"],
              return_onesided=s["onesided"], scaling=s["scaling"])
    (f, p), (fs_, ps) = both("periodogram", sig(case["x"]), case["fs"], **kw)
    assert_close(f, fs_)
    assert_close(p, ps, what=name)


def test_spectra_along_an_axis_of_a_2d_array():
    x = np.stack([sig("a1000"), sig("b1000"), sig("trend1001")[:1000]])
    y = np.stack([sig("b1000"), sig("a1000"), sig("a1000")])
    for axis, xx, yy in ((-1, x, y), (0, x.T, y.T), (1, x, y)):
        (f, p), (_, ps) = both("welch", xx, 1000.0, nperseg=128, axis=axis)
        assert p.shape == ps.shape
        assert_close(p, ps)
        (f, p), (_, ps) = both("csd", xx, yy, 1000.0, nperseg=100, axis=axis)
        assert p.shape == ps.shape
        assert_close(p.real, ps.real)
        (f, c), (_, cs) = both("coherence", xx, yy, 1000.0, nperseg=100, axis=axis)
        assert_close(c, cs)
        (f, p), (_, ps) = both("periodogram", xx, 1000.0, axis=axis)
        assert_close(p, ps)
    # one y broadcast against three x
    (f, p), (_, ps) = both("csd", x, y[0], 1000.0, nperseg=64)
    assert p.shape == ps.shape == (3, 33)
    assert_close(p.real, ps.real)


def test_welch_warns_like_scipy():
    x = sig("a100")
    with pytest.warns(UserWarning, match="nperseg=256 is greater than signal length"):
        bs.welch(x)


def test_inputs_scipy_accepts():
    x = sig("a1000")
    for variant in (x.tolist(), x.astype(np.float32), np.round(100 * x).astype(np.int64)):
        f, p = bs.welch(variant, 100.0, nperseg=100)
        want = ss.welch(np.asarray(variant, dtype=np.float64), 100.0, nperseg=100)[1]
        assert p.dtype == np.float64
        assert_close(p, want)
        if not isinstance(variant, list):  # SciPy 1.17's welch fails on a list
            # SciPy keeps float32 as float32: its answer is compared with
            # ballpass' float64 one at float32's precision.
            ps = ss.welch(variant, 100.0, nperseg=100)[1]
            assert_close(p, ps, rtol=1e-5 if variant.dtype == np.float32 else 1e-9)
    for fn, args in (("sosfiltfilt", (ss.butter(3, 0.1, output="sos"),)), ("detrend", ()),
                     ("decimate", ()), ("gradient", ())):
        extra = (4,) if fn == "decimate" else ()
        ours = getattr(bs, fn)(*args, x.tolist(), *extra)
        theirs = (np.gradient if fn == "gradient" else getattr(ss, fn))(*args, x, *extra)
        assert_close_norm(ours, theirs, what=f"{fn} of a list")
    for window in ("hann", "hann_periodic", "han", "hamming", "ham", "boxcar", "rect", ("hann",)):
        (f, p), (_, ps) = both("welch", x, nperseg=100, window=window)
        assert_close(p, ps, what=str(window))


# ---------------------------------------------------------------- correlation


@pytest.mark.parametrize("name,case", fixtures("spectral", "correlate_"))
def test_correlate_and_lags(name, case):
    x, y = sig(case["x"]), sig(case["y"])
    for mode in ("full", "same", "valid"):
        z, zs = both("correlate", x, y, mode=mode)
        assert_close_norm(z, zs, what=f"{name} {mode}")
        lags = bs.correlation_lags(len(x), len(y), mode=mode)
        want = ss.correlation_lags(len(x), len(y), mode=mode)
        assert lags.dtype.kind == "i" and np.array_equal(lags, want), mode
        assert len(lags) == len(z)


# ---------------------------------------------------------------- detrend


@pytest.mark.parametrize("name,case", fixtures("spectral", "detrend_"))
def test_detrend(name, case):
    x = sig(case["x"])
    for t in (case["type"], case["type"][0]):
        y, ys = both("detrend", x, type=t)
        # Removing a trend leaves residuals far below the data's scale: the
        # rounding is relative to the data (norm-wise on the input scale).
        assert np.max(np.abs(y - ys)) <= 1e-9 * max(np.max(np.abs(x)), 1e-300), name
    m = np.stack([x, x[::-1]]) if x.size > 1 else np.stack([x, x])
    for axis, arr in ((-1, m), (0, m.T)):
        y, ys = both("detrend", arr, axis=axis, type=case["type"])
        assert np.max(np.abs(y - ys)) <= 1e-9 * max(np.max(np.abs(arr)), 1e-300)


# ---------------------------------------------------------------- filters

FILTERS = fixture("filters", "design")["cases"]


@pytest.mark.parametrize("i", range(len(FILTERS)))
def test_butter_and_cheby1(i):
    c = FILTERS[i]
    wn = c["wn"][0] if len(c["wn"]) == 1 else c["wn"]
    args = (c["order"], wn) if c["kind"] == "butter" else (c["order"], c["rp"], wn)
    for output in ("sos", "zpk", "ba"):
        ours, theirs = both(c["kind"], *args, btype=c["btype"], output=output, fs=c["fs"])
        if output == "sos":
            assert_close(ours, theirs, what="sos")
        elif output == "zpk":
            for a, b in zip(ours[:2], theirs[:2]):
                assert_close(np.sort_complex(a).real, np.sort_complex(b).real, what="z/p re")
                assert_close(np.sort_complex(a).imag, np.sort_complex(b).imag, what="z/p im")
            assert_close(ours[2], theirs[2])
        else:
            # Polynomial coefficients from the same roots: norm-wise, as
            # the expansion cancels (1e-9 of the largest coefficient).
            for a, b in zip(ours, theirs):
                assert a.dtype == b.dtype
                assert_close_norm(a, b, what="ba")
    # normalised frequencies (no fs) give the same filter
    if c["fs"] == 2.0:
        ours, theirs = both(c["kind"], *args, btype=c["btype"], output="sos")
        assert_close(ours, theirs)


def test_butter_defaults_and_order_zero():
    (b, a), (bs_, as_) = both("butter", 4, 0.2)
    assert_close_norm(b, bs_)
    assert_close_norm(a, as_)
    for kind, args in (("butter", (0, 0.2)), ("cheby1", (0, 1.0, 0.2))):
        for output in ("sos", "ba"):
            ours, theirs = both(kind, *args, output=output)
            for o, t in zip(ours, theirs):
                assert_close(o, t)


SOSFILT = fixture("filters", "sosfilt")["cases"]


@pytest.mark.parametrize("i", range(len(SOSFILT)))
def test_sosfilt_zi_and_sosfiltfilt(i):
    c = SOSFILT[i]
    sos, x = np.asarray(c["sos"]), np.asarray(c["x"])
    y, ys = both("sosfilt", sos, x)
    assert_close_norm(y, ys)
    zi_in = np.asarray(c["zi_in"])
    (y, zf), (ys, zfs) = both("sosfilt", sos, x, zi=zi_in)
    assert_close_norm(y, ys)
    assert_close_norm(zf, zfs)
    z, zs = both("sosfilt_zi", sos)
    assert_close(z, zs)
    for padtype in ("odd", "even", "constant", None):
        y, ys = both("sosfiltfilt", sos, x, padtype=padtype)
        assert_close_norm(y, ys, what=str(padtype))
    y, ys = both("sosfiltfilt", sos, x, padlen=7)
    assert_close_norm(y, ys)


def test_filters_along_an_axis_with_state():
    sos = ss.butter(4, 0.1, output="sos")
    rng = np.random.default_rng(3)
    x = rng.standard_normal((3, 200))
    for axis, arr in ((-1, x), (0, x.T)):
        y, ys = both("sosfilt", sos, arr, axis=axis)
        assert_close_norm(y, ys)
        zi_shape = list(arr.shape)
        zi_shape[axis] = 2
        zi = rng.standard_normal([sos.shape[0]] + zi_shape)
        (y, zf), (ys, zfs) = both("sosfilt", sos, arr, axis=axis, zi=zi)
        assert_close_norm(y, ys)
        assert_close_norm(zf, zfs)
        y, ys = both("sosfiltfilt", sos, arr, axis=axis)
        assert_close_norm(y, ys)
        y, ys = both("decimate", arr, 4, axis=axis)
        assert_close_norm(y, ys)
        b, a = ss.butter(3, 0.2)
        y, ys = both("lfilter", b, a, arr, axis=axis)
        assert_close_norm(y, ys)
        zl = list(arr.shape)
        zl[axis] = 3
        zi = rng.standard_normal(zl)
        (y, zf), (ys, zfs) = both("lfilter", b, a, arr, axis=axis, zi=zi)
        assert_close_norm(y, ys)
        assert_close_norm(zf, zfs)


DECIMATE = fixture("filters", "decimate")["cases"]


@pytest.mark.parametrize("i", range(len(DECIMATE)))
def test_decimate(i):
    c = DECIMATE[i]
    x = np.asarray(c["x"])
    kw = {"n": c["n"]} if "n" in c else {}
    y, ys = both("decimate", x, c["q"], **kw)
    assert_close_norm(y, ys)
    y, ys = both("decimate", x, c["q"], zero_phase=False, **kw)
    assert_close_norm(y, ys)


def _lcg_signal():
    spec = importlib.util.spec_from_file_location(
        "filters_fixtures", ROOT / "tools" / "scipy_fixtures" / "filters.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.lcg_signal


def test_long_signals():
    lcg = _lcg_signal()
    for c in fixture("filters", "long")["cases"]:
        x = lcg(c["n"], c["seed"])
        if c["kind"] == "sosfiltfilt":
            y, ys = both("sosfiltfilt", np.asarray(c["sos"]), x)
        else:
            y, ys = both("decimate", x, c["q"])
        assert_close_norm(y, ys, what=f"{c['kind']} {c['n']}")


LFILTER = fixture("filters", "lfilter")["cases"]


@pytest.mark.parametrize("i", range(len(LFILTER)))
def test_lfilter(i):
    c = LFILTER[i]
    b, a, x = c["b"], c["a"], np.asarray(c["x"])
    y, ys = both("lfilter", b, a, x)
    assert_close_norm(y, ys)
    (y, zf), (ys, zfs) = both("lfilter", b, a, x, zi=np.asarray(c["zi_in"]))
    assert_close_norm(y, ys)
    assert_close_norm(zf, zfs)


def test_lfilter_long_signals_in_chunks():
    # Long signals run in chunks side by side (ballpass_dsp::lfilter_fast)
    # when the filter's recurrence amplifies rounding little; the others
    # run SciPy's loop. Either way SciPy's numbers to 1e-9 norm-wise
    # (the chunked path is built for ~1e-10). Designs in b, a form from
    # order 1 to 8, cutoffs 2-300 Hz at 1 kHz, with and without a
    # remainder of the 8 chunks; 2-D along both axes.
    rng = np.random.default_rng(7)
    for n in (2048, 2051, 30_000):
        x = rng.uniform(-0.5, 0.5, n) + np.sin(2 * np.pi * 1.1 * np.arange(n) / 1000.0) + 3.0
        for order in range(1, 9):
            for fc in (2.0, 20.0, 50.0, 300.0):
                b, a = ss.butter(order, fc, fs=1000.0)
                y, ys = both("lfilter", b, a, x)
                assert_close_norm(y, ys, what=f"butter({order}, {fc}) n={n}")
        b, a = ss.cheby1(4, 0.5, 40.0, fs=1000.0)
        y, ys = both("lfilter", b, a, x)
        assert_close_norm(y, ys, what=f"cheby1 n={n}")
    b, a = ss.butter(5, 20.0, fs=1000.0)
    x2 = rng.standard_normal((3, 4000))
    for axis, arr in ((-1, x2), (0, x2.T.copy())):
        y, ys = both("lfilter", b, a, arr, axis=axis)
        assert_close_norm(y, ys, what=f"2-D axis {axis}")


# ---------------------------------------------------------------- responses


def test_freqs_freqz_sosfreqz():
    r = fixture("filters", "response")
    for c in r["analog"]:
        (w, h), (ws, hs) = both("freqs", c["b"], c["a"], worN=np.asarray(c["w"]))
        assert_close(w, ws)
        assert_close(h.real, hs.real)
        assert_close(h.imag, hs.imag)
    sos, f = np.asarray(r["sos"]), np.asarray(r["f"])
    for fn, args in (("sosfreqz", (sos,)), ("freqz_sos", (sos,)), ("freqz", (r["b"], r["a"]))):
        for kw in ({"worN": f, "fs": 1000.0}, {}, {"worN": 100, "whole": True},
                   {"worN": 64, "fs": 250.0}):
            (w, h), (ws, hs) = both(fn, *args, **kw)
            assert_close(w, ws)
            # The response spans many decades (stop band): norm-wise.
            assert_close_norm(h, hs, what=f"{fn} {kw}")
    (w, h), (ws, hs) = both("freqz", r["b"], r["a"], worN=33, include_nyquist=True)
    assert_close(w, ws)
    assert_close_norm(h, hs)


# ---------------------------------------------------------------- gradient


def test_gradient():
    for c in fixture("filters", "gradient")["cases"]:
        f = np.asarray(c["f"])
        step = np.asarray(c["x"]) if "x" in c else c["h"]
        for edge in (1, 2) if len(f) >= 3 else (1,):
            g = bs.gradient(f, step, edge_order=edge)
            gs = np.gradient(f, step, edge_order=edge)
            assert_close_norm(g, gs)
    m = np.random.default_rng(5).standard_normal((4, 7))
    for args, kw in (((), {}), ((0.5,), {}), ((2.0, np.cumsum(np.arange(1, 8.0))), {}),
                     ((), {"axis": 1}), ((0.1,), {"axis": 0, "edge_order": 2})):
        ours, theirs = bs.gradient(m, *args, **kw), np.gradient(m, *args, **kw)
        if isinstance(theirs, (list, tuple)):
            assert isinstance(ours, type(theirs)) and len(ours) == len(theirs)
            for o, t in zip(ours, theirs):
                assert_close_norm(o, t)
        else:
            assert_close_norm(ours, theirs)
    assert_close_norm(bs.gradient([1, 4, 9, 16]), np.gradient([1, 4, 9, 16]))


# ---------------------------------------------------------------- peaks

PEAK_FIXTURES = fixtures("peaks", "")


def scipy_peak_kwargs(s):
    kw = {k: (tuple(v) if isinstance(v, list) else v) for k, v in s.items()}
    return kw


@pytest.mark.parametrize("name,case", PEAK_FIXTURES)
def test_find_peaks_prominences_widths(name, case):
    x = np.asarray(case["x"], dtype=np.float64)
    for c in case["find_peaks"]:
        kw = scipy_peak_kwargs(c["settings"])
        (p, props), (ps, propss) = both("find_peaks", x, **kw)
        assert np.array_equal(p, ps), (name, kw)
        assert list(props) == list(propss), (name, kw)
        for k in propss:
            assert props[k].dtype.kind == propss[k].dtype.kind, k
            assert_close(props[k], propss[k], what=f"{name} {kw} {k}")
    for c in case["prominences"]:
        ours, theirs = both("peak_prominences", x, np.asarray(c["peaks"], dtype=np.intp),
                            wlen=c["wlen"])
        for o, t in zip(ours, theirs):
            assert_close(o, t, what=name)
    for c in case["widths"]:
        peaks = np.asarray(c["peaks"], dtype=np.intp)
        ours, theirs = both("peak_widths", x, peaks, rel_height=c["rel_height"], wlen=c["wlen"])
        for o, t in zip(ours, theirs):
            assert_close(o, t, what=name)
        if peaks.size and c["wlen"] is None:
            prom = ss.peak_prominences(x, peaks)
            ours, theirs = both("peak_widths", x, peaks, rel_height=c["rel_height"],
                                prominence_data=prom)
            for o, t in zip(ours, theirs):
                assert_close(o, t, what=name)


# ---------------------------------------------------------------- exceptions

X = np.sin(np.arange(300) / 7.0)
SOS = ss.butter(4, 0.1, output="sos")
BAD = [
    # the Raises sections of SciPy's docs
    ("peak_prominences", (X, [400]), {}),
    ("peak_prominences", (X, [-1]), {}),
    ("peak_widths", (X, [10], 0.5, (np.array([1.0]), np.array([20]), np.array([30]))), {}),
    ("peak_widths", (X, [10, 20], 0.5, (np.array([1.0]), np.array([0]), np.array([30]))), {}),
    # bad arguments the parameter docs describe
    ("peak_prominences", (X, [1.5]), {}),
    ("peak_prominences", (X, [10]), {"wlen": 1}),
    ("peak_widths", (X, [10]), {"rel_height": -0.5}),
    ("find_peaks", (X,), {"distance": 0.5}),
    ("find_peaks", (np.ones((3, 3)),), {}),
    ("find_peaks", (X,), {"prominence": 1, "wlen": 0.5}),
    ("welch", (X,), {"nperseg": 64, "noverlap": 64}),
    ("welch", (X,), {"nperseg": 64, "nfft": 32}),
    ("welch", (X,), {"nperseg": 0}),
    ("welch", (X,), {"scaling": "power"}),
    ("welch", (X,), {"nperseg": 64, "average": "mode"}),
    ("welch", (X,), {"window": "nosuchwindow"}),
    ("welch", (X,), {"window": np.ones(50), "nperseg": 64}),
    ("csd", (np.ones((2, 300)), np.ones((3, 300))), {}),
    ("periodogram", (X,), {"window": np.ones(10)}),
    ("correlate", (X, X), {"mode": "middle"}),
    ("correlate", (X, X), {"method": "slow"}),
    ("correlation_lags", (5, 3), {"mode": "middle"}),
    ("butter", (4, 1.2), {"output": "sos"}),
    ("butter", (4, 600.0), {"fs": 1000.0, "output": "sos"}),
    ("butter", (4, 0.0), {"output": "sos"}),
    ("butter", (4, [0.3, 0.2]), {"btype": "bandpass", "output": "sos"}),
    ("butter", (4, 0.2), {"btype": "bandpass", "output": "sos"}),
    ("butter", (4, 0.2), {"btype": "notch"}),
    ("butter", (4, 0.2), {"output": "tf"}),
    ("butter", (-2, 0.2), {}),
    ("butter", (2.5, 0.2), {}),
    ("cheby1", (4, -1.0, 0.2), {"output": "sos"}),
    ("sosfilt", (SOS[:, :5], X), {}),
    ("sosfilt", (np.array([[1.0, 0, 0, 2.0, 0, 0]]), X), {}),
    ("sosfilt", (SOS, X), {"zi": np.zeros((3, 2))}),
    ("sosfilt", (SOS, 3.0), {}),
    ("sosfilt_zi", (SOS[:, :4],), {}),
    ("sosfiltfilt", (SOS, X[:15]), {}),
    ("sosfiltfilt", (SOS, X), {"padtype": "mirror"}),
    ("sosfiltfilt", (SOS, X), {"padlen": 300}),
    ("lfilter", ([], [1.0], X), {}),
    ("lfilter", ([1.0], [0.0, 1.0], X), {}),
    ("lfilter", ([1.0, 2.0], [1.0, 0.5], X), {"zi": np.zeros(3)}),
    ("detrend", (X,), {"type": "quadratic"}),
    ("detrend", (X,), {"bp": 400}),
    ("decimate", (X, 2.5), {}),
    ("decimate", (X, 2), {"ftype": "cheby"}),
    ("decimate", (X[:20], 2), {}),
    ("decimate", (X, 2), {"n": 2.5}),
    ("freqz", ([1.0], [1.0]), {"worN": -3}),
    ("freqz", ([1.0], [1.0]), {"fs": None}),
    ("freqz_sos", (np.zeros((0, 6)),), {}),
    ("gradient", (np.ones(1),), {}),
    ("gradient", (np.ones(5), 1.0, 2.0), {}),
    ("gradient", (np.ones(5), np.ones(4)), {}),
    ("gradient", (np.ones(5),), {"edge_order": 3}),
]


@pytest.mark.parametrize("fn,args,kw", BAD, ids=[f"{b[0]}-{i}" for i, b in enumerate(BAD)])
def test_bad_input_raises_what_scipy_raises(fn, args, kw):
    ref = np.gradient if fn == "gradient" else getattr(ss, fn)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(Exception) as theirs:
            ref(*args, **kw)
        with pytest.raises(Exception) as ours:
            getattr(bs, fn)(*args, **kw)
    assert type(ours.value) is type(theirs.value), (
        f"ballpass raised {type(ours.value).__name__}: {ours.value}; "
        f"SciPy {type(theirs.value).__name__}: {theirs.value}")
    assert str(ours.value), "an exception without a message"


UNSUPPORTED = [
    ("welch", (X,), {"window": ("kaiser", 8.0)}, "kaiser"),
    ("welch", (X,), {"window": "blackman"}, "blackman"),
    ("welch", (X,), {"window": "hann_symmetric"}, "symmetric"),
    ("welch", (X,), {"detrend": lambda s: s}, "detrend"),
    ("welch", (X + 1j,), {}, "complex"),
    ("coherence", (X, X[:200]), {}, "different lengths"),
    ("correlate", (X, X), {"method": "direct"}, "direct"),
    ("correlate", (np.ones((3, 3)), np.ones((2, 2))), {}, "1-D"),
    ("butter", (4, 0.2), {"analog": True}, "analog"),
    ("decimate", (X, 2), {"ftype": "fir"}, "fir"),
    ("find_peaks", (X,), {"height": np.zeros(300)}, "height"),
    ("freqs", ([1.0], [1.0, 1.0]), {}, "worN"),
    ("freqz", ([1.0], [1.0, 0.5]), {"plot": print}, "plot"),
    ("freqz", (np.ones((2, 3)),), {}, "b"),
    ("detrend", (X,), {"bp": [100, 200]}, "bp"),
]


@pytest.mark.parametrize("fn,args,kw,named", UNSUPPORTED,
                         ids=[f"{u[0]}-{u[3]}" for u in UNSUPPORTED])
def test_unsupported_options_are_named_never_answered_differently(fn, args, kw, named):
    with pytest.raises(NotImplementedError, match=named):
        getattr(bs, fn)(*args, **kw)


def test_non_finite_samples_are_a_value_error_naming_the_index():
    x = X.copy()
    x[17] = np.nan
    for fn, args in (("welch", (x,)), ("sosfiltfilt", (SOS, x)), ("find_peaks", (x,)),
                     ("correlate", (x, X)), ("gradient", (x,)), ("detrend", (x,))):
        with pytest.raises(ValueError, match="17"):
            getattr(bs, fn)(*args)


def test_zero_prominence_and_width_warn_like_scipy():
    x = np.array([0.0, 1.0, 1.0, 0.0, 2.0, 0.0])
    with pytest.warns(bs.PeakPropertyWarning, match="prominence of 0"):
        bs.peak_prominences(x, [0])
    with pytest.warns(bs.PeakPropertyWarning, match="width of 0"):
        bs.peak_widths(x, [0])
