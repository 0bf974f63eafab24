#!/usr/bin/env python3
"""Speed of the Python package against SciPy, in one Python process on the
same arrays (call overhead included on both sides).

1. ``ballpass.analyze`` on one 30 s three-channel record (1 kHz, simulated at
   9 mm/s) against the SciPy pipeline doing the same steps:
   ``tools/reference_stages.py``'s ``pipeline`` = the load-cell correction,
   ``tools/reference_analyze.py``'s numeric core (gradient, Butterworth
   sosfiltfilt + detrend of three channels, six full correlations, Welch
   auto/cross spectra and coherence with their chi-square bands, decimate +
   high-resolution spectra, the unfiltered spectra), the stage
   identification, the optical passages, the measured period, phases and
   harmonic tests, the synchronous average and the position-domain spectra
   (each stage is listed there with the ballpass module it mirrors). The
   numeric core alone is timed too (``analyze, numeric core only``: the
   figure earlier releases compared against). The ballpass side starts from
   the numpy arrays (it builds the Recording inside the timing).
   ``--stages`` also prints the SciPy pipeline's time per stage.
2. Each ``ballpass.signal`` function on 30 000 samples against the same
   ``scipy.signal`` (``numpy.gradient``) call.

Timing: best of ``--repeat`` timeit repeats (each a loop sized to ~0.2 s),
the two sides interleaved so that both see the same machine load; one
thread for SciPy (the script sets ``OPENBLAS_NUM_THREADS=1`` unless the
environment sets it: NumPy's BLAS would otherwise run workers whose
busy-waiting ``--cpu`` counts as SciPy's time) and ballpass in its
default pool (analyze parallelises over channels; the signal kernels run
in the calling thread).

Usage: python3 tools/bench_python.py [--repeat 7] [--json out.json] [--cpu]
[--threads N] (``--threads 1``, or ``RAYON_NUM_THREADS=1`` in the
environment, times analyze on one core, as SciPy runs; ``--threads N``
passes a ``ballpass.ThreadPool(N)`` made once, outside the timing; without
either, analyze runs in rayon's default pool, one thread per core. The
first line says which. ``--cpu`` times the process's CPU time instead of the wall
clock: on a loaded machine the wall clock mostly measures the waits for
a core, which CPU time leaves out.) Pinned versions:
tools/requirements-py.txt.
"""
import argparse
import json
import os
import pathlib
import sys
import time
import timeit
import warnings

# SciPy on one thread, as ballpass with RAYON_NUM_THREADS=1: NumPy's BLAS
# (OpenBLAS in the wheels) otherwise starts a worker per core, and with
# `--cpu` their busy-waiting is counted as SciPy's time (on this 2-core
# machine it doubled the pipeline's CPU time: 146 against 78 ms). Set
# before NumPy loads; a value in the environment is kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import scipy  # noqa: E402
from scipy import signal as ss  # noqa: E402

import ballpass  # noqa: E402
from ballpass import signal as bs  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import reference_analyze as ref  # noqa: E402
import reference_stages as stages  # noqa: E402
from bench_scipy_analyze import ref_namespace  # noqa: E402


TIMER = time.perf_counter


def best(stmt, repeat):
    """Best time per call, s: timeit with a loop of ~0.2 s."""
    t = timeit.Timer(stmt, timer=TIMER)
    n, _ = t.autorange()
    return min(t.repeat(repeat=repeat, number=max(1, n))) / max(1, n)


def pair(ours, theirs, repeat):
    """Best per-call times of both, interleaved repeat by repeat."""
    to, tt = timeit.Timer(ours, timer=TIMER), timeit.Timer(theirs, timer=TIMER)
    no = max(1, to.autorange()[0])
    nt = max(1, tt.autorange()[0])
    bo = bt = float("inf")
    for _ in range(repeat):
        bo = min(bo, to.timeit(no) / no)
        bt = min(bt, tt.timeit(nt) / nt)
    return bo, bt


def analyze_case(repeat, pool=None):
    """(ballpass, SciPy's whole pipeline, SciPy's numeric core) per call, s;
    ballpass in `pool` (a ThreadPool; None: the default pool)."""
    rec, _ = ballpass.simulate(9.0, seed=1)  # 30 s at 1 kHz, three channels
    fs = rec.fs_hz
    fr, pos, opt = rec.friction_n, rec.position_mm, rec.optical_v
    args = ref_namespace(9.0, "unused")

    def ours():
        r = ballpass.Recording(fs, fr, pos, opt, velocity_mm_s=9.0)
        return ballpass.analyze(r, threads=pool)

    def theirs():
        return stages.pipeline(fs, fr, pos, opt, args)

    def core():
        return ref.analyze(fs, fr, pos, opt, args)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t_bp, t_sp = pair(ours, theirs, repeat)
        t_core = best(core, repeat)
        return t_bp, t_sp, t_core


def scipy_stages(repeat):
    """Best CPU time of each stage of the SciPy pipeline, s."""
    rec, _ = ballpass.simulate(9.0, seed=1)
    args = ref_namespace(9.0, "unused")
    got = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(repeat):
            stages.pipeline(rec.fs_hz, rec.friction_n, rec.position_mm, rec.optical_v, args,
                            timer=lambda n, t: got.__setitem__(n, min(got.get(n, float("inf")), t)))
    return got


def kernel_cases():
    n = 30_000
    rng = np.random.default_rng(0)
    x = rng.uniform(-0.5, 0.5, n) + np.sin(2 * np.pi * 1.1 * np.arange(n) / 1000.0)
    y = np.roll(x, 25) + 0.3 * rng.standard_normal(n)
    sos = ss.butter(5, 20.0, fs=1000.0, output="sos")
    b, a = ss.butter(5, 20.0, fs=1000.0)
    pulses = np.zeros(n)
    pulses[::200] = 1.0
    pulses = np.convolve(pulses, np.exp(-0.5 * (np.arange(-60, 61) / 12.0) ** 2), "same")
    pulses += 0.02 * rng.standard_normal(n)
    peaks, _ = ss.find_peaks(pulses, prominence=0.5)
    f = np.linspace(0, 500, n)
    w = np.logspace(-2, 3, n)
    return [
        ("welch (nperseg 4096)", lambda m: m.welch(x, 1000.0, nperseg=4096)),
        ("welch (default 256)", lambda m: m.welch(x, 1000.0)),
        ("csd (nperseg 4096)", lambda m: m.csd(x, y, 1000.0, nperseg=4096)),
        ("coherence (nperseg 4096)", lambda m: m.coherence(x, y, 1000.0, nperseg=4096)),
        ("periodogram", lambda m: m.periodogram(x, 1000.0)),
        ("correlate (full)", lambda m: m.correlate(x, y)),
        ("correlation_lags", lambda m: m.correlation_lags(n, n)),
        ("butter(5, 20 Hz, sos)", lambda m: m.butter(5, 20.0, fs=1000.0, output="sos")),
        ("cheby1(8, 0.05, 0.04, sos)", lambda m: m.cheby1(8, 0.05, 0.04, output="sos")),
        ("sosfilt (butter 5)", lambda m: m.sosfilt(sos, x)),
        ("sosfilt_zi (butter 5)", lambda m: m.sosfilt_zi(sos)),
        ("sosfiltfilt (butter 5)", lambda m: m.sosfiltfilt(sos, x)),
        ("lfilter (butter 5, ba)", lambda m: m.lfilter(b, a, x)),
        ("detrend linear", lambda m: m.detrend(x)),
        ("decimate q=20", lambda m: m.decimate(x, 20)),
        ("find_peaks (prominence, width)", lambda m: m.find_peaks(pulses, prominence=0.5, width=1)),
        ("peak_prominences", lambda m: m.peak_prominences(pulses, peaks)),
        ("peak_widths", lambda m: m.peak_widths(pulses, peaks)),
        ("freqs (30k frequencies)", lambda m: m.freqs(b, a, worN=w)),
        ("freqz (30k frequencies)", lambda m: m.freqz(b, a, worN=f, fs=1000.0)),
        ("sosfreqz (30k frequencies)", lambda m: m.sosfreqz(sos, worN=f, fs=1000.0)),
        ("freqz_sos (30k frequencies)", lambda m: m.freqz_sos(sos, worN=f, fs=1000.0)),
        ("gradient", lambda m: (np if m is ss else m).gradient(x, 0.001)),
    ]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json", default=None)
    ap.add_argument("--cpu", action="store_true", help="time CPU, not the wall clock")
    ap.add_argument("--stages", action="store_true", help="the SciPy pipeline's CPU time per stage")
    ap.add_argument("--threads", type=int, default=None,
                    help="analyze in a ThreadPool of this many threads (default: rayon's default pool)")
    a = ap.parse_args()
    global TIMER
    if a.cpu:
        TIMER = time.process_time
    print(f"ballpass {ballpass.__version__}, scipy {scipy.__version__}, numpy {np.__version__}, "
          f"{'CPU time' if a.cpu else 'wall time'}, "
          f"OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}, "
          f"RAYON_NUM_THREADS={os.environ.get('RAYON_NUM_THREADS', 'unset')}")
    pool = None if a.threads is None else ballpass.ThreadPool(a.threads)
    if pool is not None:
        threads = f"{a.threads} (ThreadPool)"
    elif "RAYON_NUM_THREADS" in os.environ:
        threads = f"{os.environ['RAYON_NUM_THREADS']} (RAYON_NUM_THREADS, default pool)"
    else:
        threads = f"{len(os.sched_getaffinity(0))} (default pool, one per core)"
    print(f"analyze threads: {threads}; SciPy: one thread")
    out = {"analyze_threads": threads}
    t_bp, t_sp, t_core = analyze_case(a.repeat, pool)
    out["analyze_30s"] = {"ballpass_s": t_bp, "scipy_s": t_sp, "speedup": t_sp / t_bp,
                          "scipy_numeric_core_s": t_core}
    print(f"{'analyze, one 30 s 3-channel record':38s} ballpass {t_bp * 1e3:9.2f} ms   "
          f"scipy {t_sp * 1e3:9.2f} ms   {t_sp / t_bp:6.1f}x")
    print(f"{'analyze, numeric core only':38s} ballpass {t_bp * 1e3:9.2f} ms   "
          f"scipy {t_core * 1e3:9.2f} ms   {t_core / t_bp:6.1f}x")
    if a.stages:
        per = scipy_stages(a.repeat)
        out["scipy_stages_s"] = per
        for name, t in per.items():
            print(f"  scipy stage: {name:50s} {t * 1e3:8.2f} ms (CPU)")
    for name, call in kernel_cases():
        t_bp, t_sp = pair(lambda: call(bs), lambda: call(ss), a.repeat)
        out[name] = {"ballpass_us": t_bp * 1e6, "scipy_us": t_sp * 1e6, "speedup": t_sp / t_bp}
        print(f"{name:38s} ballpass {t_bp * 1e6:9.1f} us   scipy {t_sp * 1e6:9.1f} us   "
              f"{t_sp / t_bp:6.1f}x")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
