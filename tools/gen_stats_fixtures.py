#!/usr/bin/env python3
"""Write the SciPy reference values the ballpass statistics tests compare against.

Pinned: numpy and scipy versions in tools/requirements.txt (the script refuses
to run on others, so the fixtures never drift silently).

Writes crates/ballpass/tests/fixtures/stats/chi2_ppf.json: rows
[nu, p, scipy.stats.chi2.ppf(p, nu)] over the degrees of freedom a Welch
average produces (non-integer equivalent dof from overlapping windows, from a
single periodogram's 2 up to long averages over repeats) and the tail
probabilities of 80-99.9 % confidence bands (alpha/2 and 1 - alpha/2) and of
the harmonic tests. Floats are written with repr(), which round-trips exactly.

Usage: python3 tools/gen_stats_fixtures.py
"""
import json
import pathlib
import sys

import numpy as np
import scipy
from scipy import stats

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "crates" / "ballpass" / "tests" / "fixtures" / "stats"


def check_pins():
    for line in (ROOT / "tools" / "requirements.txt").read_text().splitlines():
        if "==" in line:
            k, v = line.strip().split("==")
            have = {"numpy": np.__version__, "scipy": scipy.__version__}.get(k)
            if have != v:
                sys.exit(f"{k} {have} installed, {v} pinned: pip install -r tools/requirements.txt")


def main():
    check_pins()
    nus = [0.5, 1.0, 1.5, 2.0, 3.0, 3.7, 5.0, 7.58, 10.0, 18.95, 28.53, 47.3, 100.0, 189.5,
           400.0, 1000.0, 3790.0]
    ps = [1e-4, 0.0005, 0.005, 0.025, 0.05, 0.1, 0.5, 0.9, 0.95, 0.975, 0.995, 0.9995, 0.9999]
    rows = [[nu, p, float(stats.chi2.ppf(p, nu))] for nu in nus for p in ps]
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "chi2_ppf.json"
    path.write_text(json.dumps({"scipy": scipy.__version__, "rows": rows}, separators=(",", ":")) + "\n")
    print(f"{len(rows)} rows in {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
