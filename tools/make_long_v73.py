#!/usr/bin/env python3
"""Write a long MATLAB v7.3 record for the long-record bench
(crates/ballpass-cli/benches/long_record.rs --mat73) with h5py, in
MATLAB's layout (512-byte text header, MATLAB_class attributes, each
channel a double column vector: HDF5 shape (1, n)).

    python3 tools/make_long_v73.py RAW_DIR OUT.mat [--deflate]

RAW_DIR holds time_s.f64, friction_N.f64, position_mm.f64 and
optical_V.f64: little-endian doubles, one file per variable (the bench
writes them from the simulated record). They are copied in slices of a
million values through a memory map, so this script's memory stays flat
whatever the length. Without --deflate the datasets are contiguous (h5py's
default); with it they are chunked by 65536 values and deflated at level 4
with shuffle, as MATLAB's `save -v7.3` compresses by default.

Pinned versions: tools/requirements-formats.txt (h5py, numpy).
"""
import os
import sys

import h5py
import numpy as np

HEADER = (
    b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Mar 14 10:00:00 2011 HDF5 schema 1.00 ."
).ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02" + b"IM"
NAMES = ["time_s", "friction_N", "position_mm", "optical_V"]
SLICE = 1 << 20


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    deflate = "--deflate" in sys.argv[1:]
    if len(args) != 2:
        sys.exit(__doc__)
    raw_dir, out = args
    kw = {"chunks": (1, 65536), "compression": "gzip", "compression_opts": 4, "shuffle": True} if deflate else {}
    with h5py.File(out, "w", userblock_size=512, libver="earliest") as f:
        for name in NAMES:
            src = np.memmap(os.path.join(raw_dir, name + ".f64"), dtype="<f8", mode="r")
            n = src.shape[0]
            d = f.create_dataset(name, shape=(1, n), dtype="<f8", **kw)
            d.attrs["MATLAB_class"] = np.bytes_("double")
            for a in range(0, n, SLICE):
                d[0, a:a + SLICE] = src[a:a + SLICE]
            del src
    with open(out, "r+b") as f:
        f.write(HEADER.ljust(512, b"\x00"))


if __name__ == "__main__":
    main()
