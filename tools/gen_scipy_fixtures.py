#!/usr/bin/env python3
"""Write the SciPy reference fixtures that the ballpass-dsp tests compare against.

Pinned: numpy and scipy versions in tools/requirements.txt (checked below, the
script refuses to run on others so that fixtures never drift silently).

Each module tools/scipy_fixtures/<area>.py defines `generate(write)`, where
`write(name, obj)` stores `obj` as crates/ballpass-dsp/tests/fixtures/<area>/<name>.json.
Floats are written with repr(), which round-trips exactly; complex arrays are
stored as two lists `<key>_re` and `<key>_im`.

Usage: python3 tools/gen_scipy_fixtures.py [AREA ...]
"""
import importlib.util
import json
import pathlib
import sys

import numpy as np
import scipy

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "crates" / "ballpass-dsp" / "tests" / "fixtures"


def pinned():
    pins = {}
    for line in (ROOT / "tools" / "requirements.txt").read_text().splitlines():
        if "==" in line:
            k, v = line.strip().split("==")
            pins[k] = v
    return pins


def to_jsonable(obj):
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            if isinstance(v, np.ndarray) and np.iscomplexobj(v):
                out[k + "_re"] = to_jsonable(v.real)
                out[k + "_im"] = to_jsonable(v.imag)
            else:
                out[k] = to_jsonable(v)
        return out
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, complex):
        raise TypeError("store complex values as separate _re/_im arrays")
    return obj


def main(argv):
    pins = pinned()
    have = {"numpy": np.__version__, "scipy": scipy.__version__}
    for k, v in pins.items():
        if have.get(k) != v:
            sys.exit(f"{k} {have.get(k)} installed, {v} pinned: pip install -r tools/requirements.txt")
    areas = sorted(p.stem for p in (ROOT / "tools" / "scipy_fixtures").glob("*.py") if not p.stem.startswith("_"))
    wanted = argv[1:] or areas
    for area in wanted:
        spec = importlib.util.spec_from_file_location(area, ROOT / "tools" / "scipy_fixtures" / f"{area}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        outdir = OUT / area
        outdir.mkdir(parents=True, exist_ok=True)
        count = 0

        def write(name, obj, _outdir=outdir):
            nonlocal count
            path = _outdir / f"{name}.json"
            path.write_text(json.dumps(to_jsonable(obj), separators=(",", ":")) + "\n")
            count += 1

        mod.generate(write)
        print(f"{area}: {count} fixtures in {outdir.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv)
