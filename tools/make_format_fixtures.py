#!/usr/bin/env python3
"""Write the TDMS, MF4, MATLAB v7.3 and MATLAB struct fixtures of
crates/ballpass/tests/data/ (committed), each with the format's own writer,
and beside each one FILE.expected.csv: what the format's own reader reads
back (npTDMS, asammdf, h5py, scipy.io), printed with repr so that it
round-trips to the same doubles. The Rust tests read both and compare bits.

Pinned versions: tools/requirements-formats.txt. Every file holds 200
samples at 1 kHz of the signals of tools/make_mat_fixtures.py:

    time_s[i]      = i / 1000
    friction_N[i]  = 2 + 0.5 sin(2 pi 5 t)
    position_mm[i] = 9 t
    optical_V[i]   = 0.25 + 0.125 cos(2 pi 20 t)

TDMS (npTDMS writes the first two, tdms_timed and tdms_stamps; the others are laid out byte by byte
here, as LabVIEW and DAQmx write them, and checked by reading them back
with npTDMS):
    tdms_plain.tdms        group 'Measurements', float64 channels in two
                           segments, wf_increment/wf_start_offset/wf_start_time,
                           unit_string
    tdms_scaled.tdms       groups 'Bench 1' and 'Bench 2', int16 counts with
                           NI linear scaling (Force, Position) and a polynomial
                           (Voltage); 'Voltage' is in both groups
    tdms_interleaved.tdms  interleaved float64 data, two chunks per segment
    tdms_bigendian.tdms    a big-endian segment
    tdms_daqmx.tdms        DAQmx raw data: one int16 buffer of 3 scalers,
                           NI polynomial scales on each channel
    tdms_timed.tdms        a time channel and no waveform timing: float64 s
    tdms_stamps.tdms       the same with TDMS timestamps
    tdms_runs.tdms         three runs in one file, one group each ('Run 1',
                           'Run 2', 'Run 3'), as LabVIEW logs a run per
                           group: the same channel names in every group,
                           run k at 9 k mm/s with 200 - 20 (k - 1) samples,
                           each run written in two segments and the runs'
                           segments interleaved; one expected file per run,
                           tdms_runs.tdms.run<k>.expected.csv
MF4 (asammdf):
    mf4_plain.mf4          one channel group, time master, units
    mf4_compressed.mf4     the same saved with transposed deflate (DZ blocks)
    mf4_invalid.mf4        float64 friction with 3 samples marked invalid
    mf4_two_rates.mf4      friction at 1 kHz and optical at 500 Hz
    mf4_blocks.mf4         (function mf4_blocks) 5000 samples at 1 kHz
                           written in 9 appends of uneven sizes and saved
                           in data blocks of about 1000 bytes (a data list
                           of 81 DT blocks); friction int16 counts
                           with a linear conversion and 5 samples marked
                           invalid, position float32, optical uint8 with a
                           linear conversion (records of 15 bytes)
    mf4_blocks_dz.mf4      the same saved with transposed deflate (DZ blocks)
    mf4_analyze.mf4        (function mf4_analyze) the record of
                           tests/fixtures/analyze/input.csv (1600 samples
                           at 200 Hz) as float64 channels with their time
                           master, in data blocks of about 4 kB
MATLAB v7.3 (h5py, in MATLAB's layout: 512-byte text header, MATLAB_class):
    v73_plain.mat          plain double vectors (one of them gzip-chunked)
    v73_controldesk.mat    the ControlDesk layout of controldesk.mat: a struct
                           rec with X (1x1 struct) and Y (1x3 struct array of
                           object references into #refs#)
    v73_struct.mat         bearing.gs (vector), bearing.sr (scalar), a cell
    v73_chunked.mat        2000 samples (not 200) in many chunks, for reading
                           in ranges: friction deflate+shuffle in chunks of
                           300, position a MATLAB row vector (HDF5 shape
                           (n, 1)) in deflate chunks of 128, optical int16
                           counts in plain chunks of 77, time contiguous
    v73_analyze.mat        the analysis fixture tests/fixtures/analyze/input.csv
                           (8 s at 200 Hz) as v7.3, friction in deflate chunks
                           of 100: the command line's streamed-versus-whole test
MATLAB level 5 structs (scipy.io.savemat):
    struct_v5.mat          bearing.gs, bearing.sr, nested.inner.data, a cell

Usage: python3 tools/make_format_fixtures.py [FUNCTION ...]
(all fixtures, or only those of the functions named, e.g. tdms_runs)
"""
import datetime
import io
import os
import struct
import sys

import asammdf
import h5py
import nptdms
import numpy as np
import scipy
import scipy.io
from asammdf import MDF, Signal
from asammdf.blocks.v4_blocks import FileHistory
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "ballpass", "tests", "data")
N, FS = 200, 1000.0
START = datetime.datetime(2011, 3, 14, 10, 0, 0)


def signals():
    t = np.arange(N) / FS
    return {
        "time_s": t,
        "friction_N": 2 + 0.5 * np.sin(2 * np.pi * 5 * t),
        "position_mm": 9 * t,
        "optical_V": 0.25 + 0.125 * np.cos(2 * np.pi * 20 * t),
    }


def path(name):
    return os.path.join(OUT, name)


def expected(name, columns):
    """FILE.expected.csv: the reference reader's values, repr-printed."""
    names = list(columns)
    n = len(columns[names[0]])
    lines = [",".join(names)]
    for i in range(n):
        lines.append(",".join(repr(float(columns[k][i])) for k in names))
    with open(path(name + ".expected.csv"), "w") as f:
        f.write("\n".join(lines) + "\n")


# ---------------------------------------------------------------- TDMS


def tdms_time(ch):
    return ch.time_track()


def tdms_plain(s):
    name = "tdms_plain.tdms"
    props = lambda unit: {
        "wf_increment": 1.0 / FS,
        "wf_start_offset": 0.0,
        "wf_start_time": np.datetime64("2011-03-14T10:00:00.000000"),
        "unit_string": unit,
    }
    with TdmsWriter(path(name)) as w:
        for half in (slice(0, N // 2), slice(N // 2, N)):
            w.write_segment([
                RootObject({"title": "ballpass fixture"}),
                GroupObject("Measurements"),
                ChannelObject("Measurements", "friction_N", s["friction_N"][half], props("N")),
                ChannelObject("Measurements", "position_mm", s["position_mm"][half], props("mm")),
                ChannelObject("Measurements", "optical_V", s["optical_V"][half], props("V")),
            ])
    f = TdmsFile.read(path(name))
    g = f["Measurements"]
    expected(name, {
        "time_s": tdms_time(g["friction_N"]),
        "friction_N": g["friction_N"][:],
        "position_mm": g["position_mm"][:],
        "optical_V": g["optical_V"][:],
    })


def tdms_timed(s):
    """A time channel and no waveform timing, as LabVIEW's measurement-file
    writer logs, in two segments: tdms_timed.tdms has float64 seconds from
    3.25 s ('time_s'), tdms_stamps.tdms TDMS timestamps 1 ms apart from
    START ('time_s'); one group 'Log' each."""
    t = 3.25 + np.arange(N) / FS
    stamps = np.datetime64(START) + np.arange(N) * np.timedelta64(1, "ms")
    for name, time in (("tdms_timed.tdms", t), ("tdms_stamps.tdms", stamps)):
        with TdmsWriter(path(name)) as w:
            for half in (slice(0, N // 2), slice(N // 2, N)):
                w.write_segment([
                    RootObject({"title": "ballpass fixture"}),
                    GroupObject("Log"),
                    ChannelObject("Log", "time_s", time[half]),
                    ChannelObject("Log", "friction_N", s["friction_N"][half], {"unit_string": "N"}),
                    ChannelObject("Log", "position_mm", s["position_mm"][half],
                                  {"unit_string": "mm"}),
                    ChannelObject("Log", "optical_V", s["optical_V"][half], {"unit_string": "V"}),
                ])
        g = TdmsFile.read(path(name))["Log"]
        cols = ("time_s",) if time is t else ()
        expected(name, {c: g[c][:] for c in cols + ("friction_N", "position_mm", "optical_V")})


def tdms_runs(s):
    name = "tdms_runs.tdms"
    props = lambda unit, k: {
        "wf_increment": 1.0 / FS,
        "wf_start_offset": 0.0,
        "wf_start_time": np.datetime64(f"2011-03-14T1{k}:00:00.000000"),
        "unit_string": unit,
    }
    runs = {}
    for k in (1, 2, 3):
        n = N - 20 * (k - 1)
        t = np.arange(n) / FS
        runs[k] = {
            "friction_N": 2 + 0.5 * k * np.sin(2 * np.pi * 5 * k * t),
            "position_mm": 9 * k * t + k,
            "optical_V": 0.25 + 0.125 * np.cos(2 * np.pi * 20 * t + k),
        }
    with TdmsWriter(path(name)) as w:
        w.write_segment([RootObject({"title": "ballpass fixture: one run per group"})])
        for part in (0, 1):
            for k, r in runs.items():
                n = len(r["friction_N"])
                half = slice(0, n // 2) if part == 0 else slice(n // 2, n)
                g = f"Run {k}"
                w.write_segment([
                    GroupObject(g, {"velocity_mm_s": 9.0 * k}),
                    *[
                        ChannelObject(g, c, r[c][half], props(u, k))
                        for c, u in (("friction_N", "N"), ("position_mm", "mm"), ("optical_V", "V"))
                    ],
                ])
    f = TdmsFile.read(path(name))
    for k in runs:
        g = f[f"Run {k}"]
        expected(f"{name}.run{k}", {
            "time_s": tdms_time(g["friction_N"]),
            "friction_N": g["friction_N"][:],
            "position_mm": g["position_mm"][:],
            "optical_V": g["optical_V"][:],
        })


def tdms_scaled(s):
    name = "tdms_scaled.tdms"
    wf = {"wf_increment": 1.0 / FS, "wf_start_offset": 0.0}

    def linear(slope, intercept, unit):
        return {
            **wf,
            "NI_Number_Of_Scales": np.int32(1),
            "NI_Scale[0]_Scale_Type": "Linear",
            "NI_Scale[0]_Linear_Slope": slope,
            "NI_Scale[0]_Linear_Y_Intercept": intercept,
            "NI_Scale[0]_Linear_Input_Source": np.uint32(0xFFFFFFFF),
            "unit_string": unit,
        }

    poly = {
        **wf,
        "NI_Number_Of_Scales": np.int32(1),
        "NI_Scale[0]_Scale_Type": "Polynomial",
        "NI_Scale[0]_Polynomial_Coefficients_Size": np.int32(3),
        "NI_Scale[0]_Polynomial_Coefficients[0]": 0.25,
        "NI_Scale[0]_Polynomial_Coefficients[1]": 1e-4,
        "NI_Scale[0]_Polynomial_Coefficients[2]": 1e-9,
        "NI_Scale[0]_Polynomial_Input_Source": np.uint32(0xFFFFFFFF),
        "unit_string": "V",
    }
    force = np.round((s["friction_N"] - 2.0) / 1e-4).astype(np.int16)
    counts = np.round(s["position_mm"] / 1e-3).astype(np.int16)
    volts = np.round((s["optical_V"] - 0.25) / 1e-4).astype(np.int16)
    with TdmsWriter(path(name)) as w:
        w.write_segment([
            RootObject(),
            GroupObject("Bench 1"),
            ChannelObject("Bench 1", "Force", force, linear(1e-4, 2.0, "N")),
            ChannelObject("Bench 1", "Position", counts, linear(1e-3, 0.0, "mm")),
            ChannelObject("Bench 1", "Voltage", volts, poly),
            GroupObject("Bench 2"),
            ChannelObject("Bench 2", "Voltage", volts, poly),
        ])
    f = TdmsFile.read(path(name))
    g = f["Bench 1"]
    expected(name, {
        "time_s": tdms_time(g["Force"]),
        "friction_N": g["Force"][:],
        "position_mm": g["Position"][:],
        "optical_V": g["Voltage"][:],
    })


def tdms_string(b, endian):
    return struct.pack(endian + "I", len(b)) + b


def tdms_segment(objects, raw, toc, endian="<", chunks=1):
    """One segment: lead-in (tag, little-endian table of contents, then the
    version and offsets in the segment's byte order), metadata, raw data."""
    meta = struct.pack(endian + "I", len(objects))
    for obj_path, index, props in objects:
        meta += tdms_string(obj_path.encode(), endian) + index
        meta += struct.pack(endian + "I", len(props))
        for key, code, value in props:
            meta += tdms_string(key.encode(), endian) + struct.pack(endian + "I", code) + value
    lead = b"TDSm" + struct.pack("<I", toc) + struct.pack(endian + "IQQ", 4713, len(meta) + len(raw), len(meta))
    return lead + meta + raw


def plain_index(code, count, endian):
    return struct.pack(endian + "IIIQ", 20, code, 1, count)


def f64_prop(key, x, endian):
    return (key, 10, struct.pack(endian + "d", x))


def tdms_interleaved(s):
    """Interleaved float64 data, two chunks of 100 samples in one segment."""
    name = "tdms_interleaved.tdms"
    chans = ["friction_N", "position_mm", "optical_V"]
    toc = (1 << 1) | (1 << 2) | (1 << 3) | (1 << 5)
    objects = [("/", struct.pack("<I", 0xFFFFFFFF), []), ("/'Run'", struct.pack("<I", 0xFFFFFFFF), [])]
    for c in chans:
        objects.append((f"/'Run'/'{c}'", plain_index(10, N // 2, "<"),
                        [f64_prop("wf_increment", 1.0 / FS, "<"), f64_prop("wf_start_offset", 0.0, "<")]))
    raw = b"".join(struct.pack("<ddd", *(s[c][i] for c in chans)) for i in range(N))
    with open(path(name), "wb") as f:
        f.write(tdms_segment(objects, raw, toc))
    f = TdmsFile.read(path(name))
    g = f["Run"]
    for c in chans:
        assert np.array_equal(g[c][:], s[c]), c
    expected(name, {"time_s": tdms_time(g["friction_N"]), **{c: g[c][:] for c in chans}})


def tdms_bigendian(s):
    name = "tdms_bigendian.tdms"
    chans = ["friction_N", "optical_V"]
    toc = (1 << 1) | (1 << 2) | (1 << 3) | (1 << 6)
    objects = [("/'Run'", struct.pack(">I", 0xFFFFFFFF), [])]
    for c in chans:
        objects.append((f"/'Run'/'{c}'", plain_index(10, N, ">"),
                        [f64_prop("wf_increment", 1.0 / FS, ">"), f64_prop("wf_start_offset", 0.0, ">")]))
    raw = b"".join(struct.pack(">%dd" % N, *s[c]) for c in chans)
    with open(path(name), "wb") as f:
        f.write(tdms_segment(objects, raw, toc, endian=">"))
    f = TdmsFile.read(path(name))
    g = f["Run"]
    for c in chans:
        assert np.array_equal(g[c][:], s[c]), c
    expected(name, {"time_s": tdms_time(g["friction_N"]), **{c: g[c][:] for c in chans}})


def tdms_daqmx(s):
    """DAQmx raw data: one buffer of 6-byte rows (3 int16 scalers), each
    channel a polynomial NI scale of its scaler (scale 0 = the DAQmx scaler,
    scale 1 = polynomial of scale 0)."""
    name = "tdms_daqmx.tdms"
    chans = [("friction_N", 2.0, 1e-4), ("position_mm", 0.0, 1e-3), ("optical_V", 0.25, 1e-4)]
    raw16 = {
        "friction_N": np.round((s["friction_N"] - 2.0) / 1e-4).astype(np.int16),
        "position_mm": np.round(s["position_mm"] / 1e-3).astype(np.int16),
        "optical_V": np.round((s["optical_V"] - 0.25) / 1e-4).astype(np.int16),
    }
    toc = (1 << 1) | (1 << 2) | (1 << 3) | (1 << 5) | (1 << 7)
    objects = [("/'Dev1'", struct.pack("<I", 0xFFFFFFFF), [])]
    for k, (c, offset, gain) in enumerate(chans):
        index = struct.pack("<IIIQI", 0x1269, 0xFFFFFFFF, 1, N, 1)
        # scaler: DAQmx type 3 (int16), raw buffer 0, byte offset 2k, bitmap 0, scale id 0
        index += struct.pack("<IIIII", 3, 0, 2 * k, 0, 0)
        index += struct.pack("<II", 1, 6)
        props = [
            ("NI_Number_Of_Scales", 3, struct.pack("<i", 2)),
            ("NI_Scale[1]_Scale_Type", 0x20, tdms_string(b"Polynomial", "<")),
            ("NI_Scale[1]_Polynomial_Coefficients_Size", 3, struct.pack("<i", 2)),
            f64_prop("NI_Scale[1]_Polynomial_Coefficients[0]", offset, "<"),
            f64_prop("NI_Scale[1]_Polynomial_Coefficients[1]", gain, "<"),
            ("NI_Scale[1]_Polynomial_Input_Source", 7, struct.pack("<I", 0)),
            f64_prop("wf_increment", 1.0 / FS, "<"),
            f64_prop("wf_start_offset", 0.0, "<"),
        ]
        objects.append((f"/'Dev1'/'{c}'", index, props))
    raw = b"".join(struct.pack("<hhh", *(raw16[c][i] for c, _, _ in chans)) for i in range(N))
    with open(path(name), "wb") as f:
        f.write(tdms_segment(objects, raw, toc))
    f = TdmsFile.read(path(name))
    g = f["Dev1"]
    cols = {c: g[c][:] for c, _, _ in chans}
    for c, offset, gain in chans:
        assert np.allclose(cols[c], offset + gain * raw16[c]), c
    expected(name, {"time_s": tdms_time(g["friction_N"]), **cols})


# ---------------------------------------------------------------- MF4


def mdf_save(mdf, name, compression=0):
    """Saves with fixed times (start and file history), so that the bytes
    are the same on every run."""
    mdf.header.start_time = START
    fh = FileHistory()
    fh.abs_time = int(START.replace(tzinfo=datetime.timezone.utc).timestamp()) * 10**9
    fh.comment = "<FHcomment><TX>ballpass fixture</TX><tool_id>make_format_fixtures.py</tool_id></FHcomment>"
    mdf._mdf.file_history = [fh]
    mdf.save(path(name), overwrite=True, compression=compression, add_history_block=False)


def mf4_fixtures(s):
    t = s["time_s"]
    sigs = lambda: [
        Signal(s["friction_N"], t, name="friction_N", unit="N"),
        Signal(s["position_mm"], t, name="position_mm", unit="mm"),
        Signal(s["optical_V"], t, name="optical_V", unit="V"),
    ]
    for name, comp in [("mf4_plain.mf4", 0), ("mf4_compressed.mf4", 2)]:
        mdf = MDF(version="4.10")
        mdf.append(sigs(), acq_name="bench", comment="ballpass fixture")
        mdf_save(mdf, name, comp)
        with MDF(path(name)) as back:
            cols = {c: back.get(c).samples for c in ["friction_N", "position_mm", "optical_V"]}
            expected(name, {"time_s": back.get("friction_N").timestamps, **cols})

    name = "mf4_invalid.mf4"
    invalid = np.zeros(N, dtype=bool)
    invalid[[50, 51, 120]] = True
    mdf = MDF(version="4.10")
    mdf.append([Signal(s["friction_N"], t, name="friction_N", unit="N", invalidation_bits=invalid),
                Signal(s["optical_V"], t, name="optical_V", unit="V")], acq_name="bench")
    mdf_save(mdf, name)
    with MDF(path(name)) as back:
        # Kept with their invalidation bits (by default asammdf drops them).
        f = back.get("friction_N", ignore_invalidation_bits=True)
        vals = np.where(np.asarray(f.invalidation_bits), np.nan, f.samples)
        assert np.isnan(vals).sum() == 3
        expected(name, {"time_s": f.timestamps, "friction_N": vals, "optical_V": back.get("optical_V").samples})

    name = "mf4_two_rates.mf4"
    mdf = MDF(version="4.10")
    mdf.append([Signal(s["friction_N"], t, name="friction_N", unit="N")], acq_name="fast")
    mdf.append([Signal(s["optical_V"][::2], t[::2], name="optical_V", unit="V")], acq_name="slow")
    mdf_save(mdf, name)


def mf4_blocks(s):
    """Several data blocks and odd records, for the streamed reader."""
    n = 5000
    t = np.arange(n) / FS
    counts = np.round(2000 * np.sin(2 * np.pi * 5 * t)).astype(np.int16)
    pos = (9 * t).astype(np.float32)
    opt = np.round(100 + 80 * np.cos(2 * np.pi * 20 * t)).astype(np.uint8)
    invalid = np.zeros(n, dtype=bool)
    invalid[[7, 1999, 2000, 2001, 4990]] = True
    cuts = [0, 1, 17, 600, 601, 1999, 2500, 3333, 4800, n]
    for name, comp in [("mf4_blocks.mf4", 0), ("mf4_blocks_dz.mf4", 2)]:
        mdf = MDF(version="4.10")
        # Data blocks of at most about 1000 bytes (62 records): a data list.
        mdf.configure(write_fragment_size=1000)
        for a, b in zip(cuts[:-1], cuts[1:]):
            sl = slice(a, b)
            sigs = [
                Signal(counts[sl], t[sl], name="friction_N", unit="N", invalidation_bits=invalid[sl],
                       conversion={"a": 0.00025, "b": 2.0}),
                Signal(pos[sl], t[sl], name="position_mm", unit="mm"),
                Signal(opt[sl], t[sl], name="optical_V", unit="V",
                       conversion={"a": 1.0 / 640, "b": 0.1}),
            ]
            if a == 0:
                mdf.append(sigs, acq_name="bench", comment="ballpass fixture")
            else:
                mdf.extend(0, [(t[sl], None)] + [(x.samples, x.invalidation_bits) for x in sigs])
        mdf_save(mdf, name, comp)
        with MDF(path(name)) as back:
            f = back.get("friction_N", ignore_invalidation_bits=True)
            vals = np.where(np.asarray(f.invalidation_bits), np.nan, f.samples)
            assert np.isnan(vals).sum() == 5
            assert len(vals) == n
            expected(name, {"time_s": f.timestamps, "friction_N": vals,
                            "position_mm": back.get("position_mm").samples.astype(np.float64),
                            "optical_V": back.get("optical_V").samples})


def mf4_analyze(s):
    """The analysis fixture as an MF4 file: `analyze --stream on` and
    `--stream off` compared on it (crates/ballpass-cli/tests/analyze.rs)."""
    src = os.path.join(OUT, "..", "fixtures", "analyze", "input.csv")
    cols = np.genfromtxt(src, delimiter=",", names=True)
    t = cols["time_s"]
    name = "mf4_analyze.mf4"
    mdf = MDF(version="4.10")
    mdf.configure(write_fragment_size=4096)
    mdf.append([Signal(cols[c], t, name=c, unit=u)
                for c, u in [("friction_N", "N"), ("position_mm", "mm"), ("optical_V", "V")]],
               acq_name="bench", comment="ballpass analysis fixture")
    mdf_save(mdf, name)
    with MDF(path(name)) as back:
        for c in ["friction_N", "position_mm", "optical_V"]:
            assert np.array_equal(back.get(c).samples, cols[c]), c
            assert np.array_equal(back.get(c).timestamps, t), c


# ---------------------------------------------------------------- MATLAB v7.3

MATLAB_73_HEADER = (
    b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Mar 14 10:00:00 2011 HDF5 schema 1.00 ."
).ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"


def h5_file(name):
    return h5py.File(path(name), "w", userblock_size=512, libver="earliest", track_order=False)


def matlab_header(name):
    with open(path(name), "r+b") as f:
        f.write(MATLAB_73_HEADER.ljust(512, b"\x00"))


def mat_double(parent, key, values, **kw):
    """A MATLAB column vector: HDF5 shape (1, n), MATLAB dims n x 1."""
    d = parent.create_dataset(key, data=np.asarray(values, dtype=np.float64).reshape(1, -1), **kw)
    d.attrs["MATLAB_class"] = np.bytes_("double")
    return d


def mat_char(parent, key, text):
    d = parent.create_dataset(key, data=np.frombuffer(text.encode("utf-16-le"), dtype=np.uint16).reshape(-1, 1))
    d.attrs["MATLAB_class"] = np.bytes_("char")
    d.attrs["MATLAB_int_decode"] = np.int32(2)
    return d


def mat_struct(parent, key):
    g = parent.create_group(key)
    g.attrs["MATLAB_class"] = np.bytes_("struct")
    return g


def v73_fixtures(s):
    name = "v73_plain.mat"
    with h5_file(name) as f:
        for k, v in s.items():
            mat_double(f, k, v, **({"chunks": (1, 64), "compression": "gzip"} if k == "optical_V" else {}))
    matlab_header(name)
    with h5py.File(path(name), "r") as f:
        expected(name, {k: f[k][()].ravel() for k in s})

    name = "v73_controldesk.mat"
    counts = np.round(s["position_mm"] / 1e-4).astype(np.int32)
    with h5_file(name) as f:
        refs = f.create_group("#refs#")
        rec = mat_struct(f, "rec_9mm_s")
        x = mat_struct(rec, "X")
        mat_double(x, "Data", s["time_s"])
        mat_char(x, "Name", "Time")
        y = mat_struct(rec, "Y")
        names, datas, units = [], [], []
        for i, (label, data, unit) in enumerate([
            ("Model Root/Load cell/Force", s["friction_N"], "N"),
            ("Model Root/Encoder/Counts", counts, "counts"),
            ("Model Root/Photodetector/Voltage", s["optical_V"], "V"),
        ]):
            names.append(mat_char(refs, f"n{i}", label).ref)
            if data.dtype == np.int32:
                d = refs.create_dataset(f"d{i}", data=data.reshape(1, -1))
                d.attrs["MATLAB_class"] = np.bytes_("int32")
            else:
                d = mat_double(refs, f"d{i}", data)
            datas.append(d.ref)
            units.append(mat_char(refs, f"u{i}", unit).ref)
        for field, r in [("Name", names), ("Data", datas), ("Unit", units)]:
            y.create_dataset(field, data=np.array(r, dtype=h5py.ref_dtype).reshape(3, 1))
    matlab_header(name)
    with h5py.File(path(name), "r") as f:
        y = f["rec_9mm_s/Y"]
        data = [f[r][()].ravel() for r in y["Data"][:, 0]]
        expected(name, {
            "time_s": f["rec_9mm_s/X/Data"][()].ravel(),
            "friction_N": data[0],
            "position_mm": data[1] * 1e-4,
            "optical_V": data[2],
        })

    name = "v73_struct.mat"
    with h5_file(name) as f:
        refs = f.create_group("#refs#")
        b = mat_struct(f, "bearing")
        mat_double(b, "gs", s["friction_N"], chunks=(1, 50), compression="gzip")
        sr = b.create_dataset("sr", data=np.array([[FS]]))
        sr.attrs["MATLAB_class"] = np.bytes_("double")
        c0 = mat_double(refs, "c0", s["optical_V"])
        c1 = mat_char(refs, "c1", "label")
        cell = f.create_dataset("signals", data=np.array([[c0.ref], [c1.ref]], dtype=h5py.ref_dtype))
        cell.attrs["MATLAB_class"] = np.bytes_("cell")
    matlab_header(name)
    with h5py.File(path(name), "r") as f:
        expected(name, {
            "friction_N": f["bearing/gs"][()].ravel(),
            "optical_V": f[f["signals"][0, 0]][()].ravel(),
        })


def v73_chunked(s):
    n = 2000
    t = np.arange(n) / FS
    name = "v73_chunked.mat"
    optical = np.round((0.25 + 0.125 * np.cos(2 * np.pi * 20 * t)) * 1000).astype(np.int16)
    with h5_file(name) as f:
        mat_double(f, "time_s", t)
        mat_double(f, "friction_N", 2 + 0.5 * np.sin(2 * np.pi * 5 * t),
                   chunks=(1, 300), compression="gzip", shuffle=True)
        p = f.create_dataset("position_mm", data=(9 * t).reshape(-1, 1), chunks=(128, 1), compression="gzip")
        p.attrs["MATLAB_class"] = np.bytes_("double")
        o = f.create_dataset("optical_V", data=optical.reshape(1, -1), chunks=(1, 77))
        o.attrs["MATLAB_class"] = np.bytes_("int16")
    matlab_header(name)
    with h5py.File(path(name), "r") as f:
        assert f["friction_N"].chunks == (1, 300) and f["optical_V"].chunks == (1, 77)
        expected(name, {k: f[k][()].ravel().astype(np.float64) for k in s})


def v73_analyze(s):
    src = os.path.join(OUT, "..", "fixtures", "analyze", "input.csv")
    cols = np.genfromtxt(src, delimiter=",", names=True, dtype=np.float64)
    name = "v73_analyze.mat"
    with h5_file(name) as f:
        for k in cols.dtype.names:
            kw = {"chunks": (1, 100), "compression": "gzip"} if k == "friction_N" else {}
            mat_double(f, k, cols[k], **kw)
    matlab_header(name)
    with h5py.File(path(name), "r") as f:
        for k in cols.dtype.names:
            assert np.array_equal(f[k][()].ravel(), cols[k])


# ---------------------------------------------------------------- MATLAB level 5 structs


def struct_v5(s):
    name = "struct_v5.mat"
    col = lambda v: np.asarray(v, dtype=np.float64).reshape(-1, 1)
    cell = np.empty((1, 2), dtype=object)
    cell[0, 0] = col(s["optical_V"])
    cell[0, 1] = "label"
    data = {
        "bearing": {"gs": col(s["friction_N"]), "sr": FS, "load": 25.0, "rate": 1797.0},
        "nested": {"inner": {"data": col(s["position_mm"])}},
        "signals": cell,
    }
    b = io.BytesIO()
    scipy.io.savemat(b, data, format="5", do_compression=True, oned_as="column")
    raw = b.getvalue()
    text = b"MATLAB 5.0 MAT-file Platform: posix, Created on: Mon Mar 14 10:00:00 2011".ljust(116, b"\x00")
    with open(path(name), "wb") as f:
        f.write(text + raw[116:])
    m = scipy.io.loadmat(path(name))
    expected(name, {
        "friction_N": m["bearing"]["gs"][0, 0].ravel(),
        "position_mm": m["nested"]["inner"][0, 0]["data"][0, 0].ravel(),
        "optical_V": m["signals"][0, 0].ravel(),
    })


def main():
    os.makedirs(OUT, exist_ok=True)
    s = signals()
    every = [tdms_plain, tdms_scaled, tdms_runs, tdms_timed, tdms_interleaved, tdms_bigendian,
             tdms_daqmx, mf4_fixtures, mf4_blocks, mf4_analyze, v73_fixtures, struct_v5,
             v73_chunked, v73_analyze]
    wanted = sys.argv[1:]
    unknown = [w for w in wanted if w not in {f.__name__ for f in every}]
    if unknown:
        sys.exit(f"unknown fixture function(s) {unknown}; known: {[f.__name__ for f in every]}")
    for f in every:
        if not wanted or f.__name__ in wanted:
            f(s)
    print(
        f"wrote format fixtures to {os.path.normpath(OUT)} with npTDMS {nptdms.__version__}, "
        f"asammdf {asammdf.__version__}, h5py {h5py.__version__}, scipy {scipy.__version__}, "
        f"numpy {np.__version__}"
    )


if __name__ == "__main__":
    main()
