#!/usr/bin/env python3
"""How much a build changes `ballpass.analyze`'s outputs: the 16 simulated
records of the speed work (1, 4, 9, 15 mm/s; good and sticking; one and two
repeats, seeds 1-2), every output table and every number of `to_dict()`.

  python3 tools/analyze_output_diff.py dump OUT.pkl     (with one build installed)
  python3 tools/analyze_output_diff.py compare A.pkl B.pkl

`compare` prints, per output table (and for the JSON's numbers), the largest
relative difference |a - b| / max(|a|, |b|) over the 16 analyses (0 where
both are 0); for the tables also the largest difference relative to its
column's largest magnitude (an element near zero, a cross spectrum's
imaginary part at a bin where it changes sign, has a large relative
difference from a change at the column's rounding level); and whether every verdict, warning list and non-numeric field
is equal. Pinned versions: tools/requirements-py.txt.
"""
import pickle
import sys
import warnings

import numpy as np


def dump(path):
    import ballpass

    warnings.simplefilter("ignore")
    out = {}
    for v in (1.0, 4.0, 9.0, 15.0):
        for cond in ("good", "sticking"):
            for reps in (1, 2):
                recs = [ballpass.simulate(v, condition=cond, seed=s)[0] for s in range(1, reps + 1)]
                r = ballpass.analyze(recs if reps > 1 else recs[0])
                tables = {}
                for name in sorted(r.tables):
                    t = getattr(r, name)
                    tables[name] = None if t is None else {k: np.asarray(c) for k, c in t.to_dict().items()}
                out[f"{v}-{cond}-{reps}"] = (r.to_dict(), tables)
    with open(path, "wb") as f:
        pickle.dump(out, f)
    print(len(out), "analyses")


def flatten(d, prefix=""):
    """(path, value) of every leaf of a JSON-like tree."""
    if isinstance(d, dict):
        for k, v in d.items():
            yield from flatten(v, f"{prefix}.{k}")
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from flatten(v, f"{prefix}[{i}]")
    else:
        yield prefix, d


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    both = np.isfinite(a) & np.isfinite(b)
    if not np.array_equal(np.isfinite(a), np.isfinite(b)) or not np.array_equal(a[~both], b[~both]):
        return float("inf")
    scale = np.maximum(np.abs(a[both]), np.abs(b[both]))
    d = np.abs(a[both] - b[both])
    r = np.where(scale > 0, d / np.where(scale > 0, scale, 1.0), 0.0)
    return float(r.max()) if r.size else 0.0


def compare(pa, pb):
    a, b = (pickle.load(open(p, "rb")) for p in (pa, pb))
    worst = {}
    colscaled = {}
    other = []
    verdicts_equal = True
    for key in a:
        (da, ta), (db, tb) = a[key], b[key]
        if da["verdict"] != db["verdict"]:
            verdicts_equal = False
            print("VERDICT CHANGED", key, da["verdict"], db["verdict"])
        fa, fb = dict(flatten(da)), dict(flatten(db))
        if fa.keys() != fb.keys():
            other.append((key, "fields differ", sorted(set(fa) ^ set(fb))[:5]))
        for path in fa.keys() & fb.keys():
            x, y = fa[path], fb[path]
            if isinstance(x, (int, float)) and isinstance(y, (int, float)) and not isinstance(x, bool):
                r = rel(x, y)
                top = path.split("[")[0].split(".")[1]
                if r > worst.get(f"json:{top}", (0.0,))[0]:
                    worst[f"json:{top}"] = (r, key, path)
                worst.setdefault(f"json:{top}", (0.0, key, path))
            elif x != y:
                other.append((key, path, x, y))
        for name in ta:
            if (ta[name] is None) != (tb[name] is None):
                other.append((key, name, "present in one only"))
                continue
            if ta[name] is None:
                continue
            for col in ta[name]:
                x, y = ta[name][col], tb[name][col]
                if x.dtype == object or y.dtype == object:
                    if list(x) != list(y):
                        other.append((key, name, col))
                    continue
                r = rel(x, y) if x.shape == y.shape else float("inf")
                if r > worst.get(name, (0.0,))[0]:
                    worst[name] = (r, key, col)
                worst.setdefault(name, (0.0, key, col))
                if x.shape == y.shape and np.all(np.isfinite(x)) and np.all(np.isfinite(y)):
                    scale = max(np.abs(x).max(), np.abs(y).max(), 1e-300)
                    c = float(np.abs(x - y).max() / scale)
                    if c > colscaled.get(name, (0.0,))[0]:
                        colscaled[name] = (c, key, col)
                    colscaled.setdefault(name, (0.0, key, col))
    print(f"verdicts equal on all {len(a)} analyses: {verdicts_equal}")
    for name, (r, key, where) in sorted(worst.items()):
        print(f"{name:28s} max relative difference {r:.3e}  ({key}, {where})")
    for name, (r, key, where) in sorted(colscaled.items()):
        print(f"{name:28s} max difference / column's largest magnitude {r:.3e}  ({key}, {where})")
    print(f"non-numeric differences: {len(other)}")
    for o in other[:20]:
        print("  ", o)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "dump":
        dump(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
