#!/usr/bin/env python3
"""Write the MAT-file test fixtures of crates/ballpass/tests/data/ (committed).

Pinned numpy/scipy (tools/requirements.txt). Every file holds 200 samples at
1 kHz of the same deterministic signals, so tests can compare loaders:

    time_s[i]      = i / 1000
    friction_N[i]  = 2 + 0.5 sin(2 pi 5 t)
    position_mm[i] = 9 t                      (ControlDesk file: encoder counts
                                               of 1e-4 mm, int32)
    optical_V[i]   = 0.25 + 0.125 cos(2 pi 20 t)

Files:
    plain_v5.mat            plain double column vectors, no compression
    plain_v7.mat            the same, zlib-compressed (MATLAB -v7 default),
                            with MATLAB's header text
    controldesk.mat         dSPACE ControlDesk layout: rec.X.Data (time),
                            rec.Y(i).Name/.Data/.Unit channels (row vectors)
    matrix.mat              friction_N is a 200x2 matrix (not a vector)
    truncated.mat           plain_v5.mat cut to 60 % of its bytes
    truncated_v7.mat        plain_v7.mat cut to 60 % of its bytes
    garbage.mat             a valid header followed by random bytes
    csv_renamed.mat         a CSV text file named .mat
    v73_header.mat          the first bytes of a MATLAB v7.3 (HDF5) file:
                            the 512-byte text header and the HDF5 signature
Usage: python3 tools/make_mat_fixtures.py
"""
import io
import os

import numpy as np
import scipy
import scipy.io

OUT = os.path.join(os.path.dirname(__file__), "..", "crates", "ballpass", "tests", "data")
N, FS = 200, 1000.0


def signals():
    t = np.arange(N) / FS
    return {
        "time_s": t,
        "friction_N": 2 + 0.5 * np.sin(2 * np.pi * 5 * t),
        "position_mm": 9 * t,
        "optical_V": 0.25 + 0.125 * np.cos(2 * np.pi * 20 * t),
    }


def col(v):
    return np.asarray(v, dtype=np.float64).reshape(-1, 1)


def savemat_bytes(d, compress):
    b = io.BytesIO()
    scipy.io.savemat(b, d, format="5", do_compression=compress, oned_as="column")
    return b.getvalue()


def fixed_header(data, matlab_style=False):
    """Replaces scipy's "Created on" time stamp so that the fixtures are
    reproducible; matlab_style writes MATLAB's own header text instead
    ("MAT-file, Platform: ..." padded with spaces; scipy omits the comma)."""
    if matlab_style:
        text = b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created on: Mon Mar 14 10:00:00 2011"
        text = text.ljust(116, b" ")
    else:
        text = b"MATLAB 5.0 MAT-file Platform: posix, Created on: Mon Mar 14 10:00:00 2011"
        text = text.ljust(116, b"\x00")
    return text + data[116:]


def write(name, data):
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)


def main():
    os.makedirs(OUT, exist_ok=True)
    s = signals()
    plain = fixed_header(savemat_bytes({k: col(v) for k, v in s.items()}, False))
    comp = fixed_header(savemat_bytes({k: col(v) for k, v in s.items()}, True), matlab_style=True)
    write("plain_v5.mat", plain)
    write("plain_v7.mat", comp)

    # ControlDesk: one struct named after the recording; X is the time base,
    # Y a 1xK struct array of signals with a block-path Name.
    row = lambda v: np.asarray(v).reshape(1, -1)
    counts = np.round(s["position_mm"] / 1e-4).astype(np.int32)
    y = np.zeros((1, 3), dtype=[("Name", "O"), ("Type", "O"), ("Data", "O"), ("Unit", "O"), ("XIndex", "O")])
    for i, (name, data, unit) in enumerate([
        ("Model Root/Load cell/Force", row(s["friction_N"]), "N"),
        ("Model Root/Encoder/Counts", row(counts), "counts"),
        ("Model Root/Photodetector/Voltage", row(s["optical_V"]), "V"),
    ]):
        y[0, i] = (name, "Signal", data, unit, 1.0)
    rec = {
        "X": {"Name": "Time", "Type": "Time", "Data": row(s["time_s"]), "Unit": "s"},
        "Y": y,
        "Description": {"General": {"DateTime": "2011-03-14 10:00:00"}},
        "RTProgram": {"Name": "bench.sdf"},
    }
    write("controldesk.mat", fixed_header(savemat_bytes({"rec_9mm_s": rec}, True)))

    m = {k: col(v) for k, v in s.items()}
    m["friction_N"] = np.hstack([col(s["friction_N"]), col(s["friction_N"])])
    write("matrix.mat", fixed_header(savemat_bytes(m, False)))

    write("truncated.mat", plain[: int(len(plain) * 0.6)])
    write("truncated_v7.mat", comp[: int(len(comp) * 0.6)])
    rng = np.random.default_rng(12345)
    write("garbage.mat", plain[:128] + rng.integers(0, 256, 4000, dtype=np.uint8).tobytes())

    lines = ["time_s,friction_N,position_mm,optical_V"]
    lines += [",".join(repr(float(s[k][i])) for k in s) for i in range(N)]
    write("csv_renamed.mat", ("\n".join(lines) + "\n").encode())

    hdr = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Mar 14 10:00:00 2011 HDF5 schema 1.00 ."
    hdr = hdr.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
    write("v73_header.mat", hdr.ljust(512, b"\x00") + b"\x89HDF\r\n\x1a\n" + b"\x00" * 504)
    print(f"wrote fixtures to {os.path.normpath(OUT)} with scipy {scipy.__version__}, numpy {np.__version__}")


if __name__ == "__main__":
    main()
