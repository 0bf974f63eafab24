#!/usr/bin/env python3
"""Write a long CSV record (time_s, friction_N, position_mm, optical_V) as an
ASAM MDF 4 file with asammdf, as a logger writes one: one channel group,
float64 channels on a float64 time master, data blocks of asammdf's 4 MB.

The CSV is read a million rows at a time and appended to the file as it
goes (asammdf keeps appended data in a temporary file), so that a 24-hour
record at 1 kHz (86.4 million rows, 5.3 GB of CSV) is converted in bounded
memory. Used by `cargo bench -p ballpass-cli --bench long_record -- --mf4`.

Environment: tools/requirements-formats.txt (asammdf 8.8.28, pandas, numpy).

Usage: python3 tools/write_long_mf4.py RECORD.csv OUT.mf4
"""
import sys

import numpy as np
import pandas as pd
from asammdf import MDF, Signal

CHANNELS = [("friction_N", "N"), ("position_mm", "mm"), ("optical_V", "V")]
ROWS = 1_000_000


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: write_long_mf4.py RECORD.csv OUT.mf4")
    src, out = sys.argv[1], sys.argv[2]
    mdf = MDF(version="4.10")
    n = 0
    for chunk in pd.read_csv(src, chunksize=ROWS, dtype=np.float64):
        t = chunk["time_s"].to_numpy()
        cols = [chunk[c].to_numpy() for c, _ in CHANNELS]
        if n == 0:
            mdf.append([Signal(v, t, name=c, unit=u) for v, (c, u) in zip(cols, CHANNELS)],
                       acq_name="bench", comment="ballpass long record")
        else:
            mdf.extend(0, [(t, None)] + [(v, None) for v in cols])
        n += len(t)
    mdf.save(out, overwrite=True, compression=0)
    mdf.close()
    print(f"wrote {out}: {n} samples")


if __name__ == "__main__":
    main()
