#!/usr/bin/env python3
"""Writes a simulated bearing fleet for `spark_fleet.py` and `ballpass
diagnose`: BEARINGS bearings x REPEATS records at one velocity (every
STICKY-th bearing sticking), each record a file from the built-in testbed
simulator, and `manifest.csv` listing them.

    python examples/make_fleet.py DIR --bearings 100 --repeats 10 \
        --duration 10 --format mat

Records are MATLAB .mat (compact, fast to read) or CSV; each has a seed of
its own (seed + index), so a fleet is reproducible file for file.
"""

from __future__ import annotations

import argparse
import pathlib

import ballpass


def make_fleet(out: pathlib.Path, bearings: int, repeats: int, *, velocity_mm_s: float = 20.0,
               duration_s: float = 10.0, sticky: int = 4, fmt: str = "mat", seed: int = 0,
               threads: int | None = None) -> pathlib.Path:
    """Writes the fleet into `out`; returns the manifest's path."""
    out.mkdir(parents=True, exist_ok=True)
    rows = ["path,bearing,velocity_mm_s,repeat,condition"]
    k = 0
    with ballpass.threads(threads or 1):
        for b in range(1, bearings + 1):
            condition = "sticking" if sticky and b % sticky == 0 else "good"
            for r in range(1, repeats + 1):
                rec, _ = ballpass.simulate(velocity_mm_s, condition=condition, seed=seed + k,
                                           duration_s=duration_s,
                                           test_id=f"bearing{b:03d}_r{r:02d}")
                k += 1
                name = f"bearing{b:03d}_r{r:02d}.{fmt}"
                (rec.to_mat if fmt == "mat" else rec.to_csv)(out / name)
                rows.append(f"{name},bearing{b:03d},{velocity_mm_s},{r},{condition}")
    manifest = out / "manifest.csv"
    manifest.write_text("\n".join(rows) + "\n")
    return manifest


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=pathlib.Path)
    ap.add_argument("--bearings", type=int, default=10)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--velocity", type=float, default=20.0, help="mm/s")
    ap.add_argument("--duration", type=float, default=10.0, help="s per record")
    ap.add_argument("--sticky", type=int, default=4, help="every N-th bearing sticks (0: none)")
    ap.add_argument("--format", choices=["mat", "csv"], default="mat")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    m = make_fleet(a.out, a.bearings, a.repeats, velocity_mm_s=a.velocity,
                   duration_s=a.duration, sticky=a.sticky, fmt=a.format, seed=a.seed)
    print(f"wrote {a.bearings * a.repeats} records and {m}")


if __name__ == "__main__":
    main()
