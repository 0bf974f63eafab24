#!/usr/bin/env python3
"""Write a 30 s, 1 kHz recording (time plus three channels) in every format
ballpass reads, each with the format's own writer, and time the format's
own reader loading it: the reference figures for
crates/ballpass/benches/load.rs ("load <format> 30 s 1 kHz"), which reads the
same files from the same folder.

    python3 tools/bench_formats_load.py [DIR]      (default: target/format-bench)

Environment: tools/requirements-formats.txt. Each figure is the best of 7
runs of: open the file, read the time and the three channels into float64
arrays (what ballpass's loader does before its checks).
"""
import datetime
import os
import sys
import timeit

import asammdf
import h5py
import nptdms
import numpy as np
import scipy
import scipy.io
from asammdf import MDF, Signal
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

FS, N = 1000.0, 30_000
NAMES = ["friction_N", "position_mm", "optical_V"]


def signals():
    t = np.arange(N) / FS
    rng = np.random.default_rng(0)
    return {
        "time_s": t,
        "friction_N": 2.0 + 0.05 * np.sin(2 * np.pi * 1.10959 * t) + 0.01 * (rng.random(N) - 0.5),
        "position_mm": 9.0 * t + 1e-4 * (rng.random(N) - 0.5),
        "optical_V": 0.3 + 0.2 * (rng.random(N) - 0.5),
    }


def write_all(d, s):
    os.makedirs(d, exist_ok=True)
    p = lambda n: os.path.join(d, n)
    with open(p("rec.csv"), "w") as f:
        f.write("time_s,friction_N,position_mm,optical_V\n")
        for row in zip(*(s[k] for k in ["time_s"] + NAMES)):
            f.write(",".join(repr(float(x)) for x in row) + "\n")
    col = {k: v.reshape(-1, 1) for k, v in s.items()}
    scipy.io.savemat(p("rec_v5.mat"), col, format="5", do_compression=False)
    scipy.io.savemat(p("rec_v7.mat"), col, format="5", do_compression=True)
    with h5py.File(p("rec_v73.mat"), "w", userblock_size=512) as f:
        for k, v in s.items():
            ds = f.create_dataset(k, data=v.reshape(1, -1))
            ds.attrs["MATLAB_class"] = np.bytes_("double")
    with open(p("rec_v73.mat"), "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(116, b" ")
                + b"\x00" * 8 + b"\x00\x02IM")
    props = {"wf_increment": 1.0 / FS, "wf_start_offset": 0.0}
    with TdmsWriter(p("rec.tdms")) as w:
        w.write_segment([RootObject(), GroupObject("bench")] +
                        [ChannelObject("bench", k, s[k], props) for k in NAMES])
    mdf = MDF(version="4.10")
    mdf.append([Signal(s[k], s["time_s"], name=k) for k in NAMES], acq_name="bench")
    mdf.header.start_time = datetime.datetime(2011, 3, 14)
    mdf.save(p("rec.mf4"), overwrite=True)


def readers(d):
    p = lambda n: os.path.join(d, n)

    def csv():
        a = np.loadtxt(p("rec.csv"), delimiter=",", skiprows=1)
        return [a[:, i] for i in range(4)]

    def mat(name):
        def f():
            m = scipy.io.loadmat(p(name))
            return [m[k].ravel() for k in ["time_s"] + NAMES]
        return f

    def v73():
        with h5py.File(p("rec_v73.mat"), "r") as f:
            return [f[k][()].ravel() for k in ["time_s"] + NAMES]

    def tdms():
        f = TdmsFile.read(p("rec.tdms"))
        g = f["bench"]
        return [g[NAMES[0]].time_track()] + [g[k][:] for k in NAMES]

    def mf4():
        with MDF(p("rec.mf4")) as m:
            sigs = [m.get(k) for k in NAMES]
            return [sigs[0].timestamps] + [x.samples for x in sigs]

    return [
        ("csv", "numpy.loadtxt", csv),
        ("mat v5", "scipy.io.loadmat", mat("rec_v5.mat")),
        ("mat v7 (zlib)", "scipy.io.loadmat", mat("rec_v7.mat")),
        ("mat v7.3", "h5py", v73),
        ("tdms", "npTDMS", tdms),
        ("mf4", "asammdf", mf4),
    ]


def main():
    d = sys.argv[1] if len(sys.argv) > 1 else os.path.join("target", "format-bench")
    s = signals()
    write_all(d, s)
    print(f"files in {d}; numpy {np.__version__}, scipy {scipy.__version__}, h5py {h5py.__version__}, "
          f"npTDMS {nptdms.__version__}, asammdf {asammdf.__version__}")
    for fmt, who, f in readers(d):
        cols = f()
        assert all(len(c) == N for c in cols), fmt
        best = min(timeit.repeat(f, number=1, repeat=7))
        print(f"{fmt:14s} {who:18s} {best * 1e3:8.2f} ms")


if __name__ == "__main__":
    main()
