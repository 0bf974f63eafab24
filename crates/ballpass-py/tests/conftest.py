"""Shared helpers of the pytest suite of the Python package.

The comparisons against SciPy use the project's fixture inputs (the JSON
files of crates/ballpass-dsp/tests/fixtures, written by
tools/gen_scipy_fixtures.py) and call SciPy itself on them, so every
argument goes through both libraries' Python layers.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
FIXTURES = ROOT / "crates" / "ballpass-dsp" / "tests" / "fixtures"

# Tolerance against SciPy: 1e-9 relative (the bar). Elementwise
# where every element is computed to full relative precision (spectra,
# widths, designs), relative to the array's largest magnitude where the
# rounding error scales with it instead (recursive filters, FFT
# correlation: a sample near zero carries the absolute error of the large
# ones, on both sides).
RTOL = 1e-9


def fixture(area: str, name: str) -> dict:
    return json.loads((FIXTURES / area / f"{name}.json").read_text())


def fixtures(area: str, prefix: str) -> list[tuple[str, dict]]:
    files = sorted((FIXTURES / area).glob(f"{prefix}*.json"))
    assert files, f"no {prefix}* fixtures in {area}"
    return [(f.stem, json.loads(f.read_text())) for f in files]


def _arrays(a, b):
    a = np.asarray(a)
    b = np.asarray(b)
    assert a.shape == b.shape, f"shape {a.shape} vs SciPy's {b.shape}"
    return a, b


def assert_close(ours, theirs, rtol: float = RTOL, what: str = ""):
    """Elementwise |a - b| <= rtol |b|, with a floor of 1e-12 max|b| for
    elements far below the array's scale."""
    a, b = _arrays(ours, theirs)
    if b.size == 0:
        return
    assert np.array_equal(np.isnan(a), np.isnan(b)), f"{what}: NaN positions differ"
    m = ~np.isnan(b)
    scale = np.max(np.abs(b[m])) if m.any() else 0.0
    floor = max(1e-12 * scale, np.finfo(float).tiny)
    err = np.max(np.abs(a[m] - b[m]) / np.maximum(np.abs(b[m]), floor)) if m.any() else 0.0
    assert err <= rtol, f"{what}: max relative error {err:.3e} > {rtol:.0e}"


def assert_close_norm(ours, theirs, rtol: float = RTOL, what: str = ""):
    """max |a - b| <= rtol max |b| (norm-wise)."""
    a, b = _arrays(ours, theirs)
    if b.size == 0:
        return
    scale = np.max(np.abs(b))
    err = np.max(np.abs(a - b)) / scale if scale > 0 else np.max(np.abs(a - b))
    assert err <= rtol, f"{what}: norm-wise relative error {err:.3e} > {rtol:.0e}"


def ballpass_bin() -> pathlib.Path:
    """The `ballpass` binary the CLI comparisons run: $BALLPASS_BIN, else
    the workspace's release or debug build."""
    env = os.environ.get("BALLPASS_BIN")
    candidates = [pathlib.Path(env)] if env else [
        ROOT / "target" / "release" / "ballpass",
        ROOT / "target" / "debug" / "ballpass",
    ]
    found = [c for c in candidates if c.is_file()]
    if not found:
        pytest.fail(
            "no ballpass binary: build it (cargo build -p ballpass-cli) or set BALLPASS_BIN"
        )
    return max(found, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def cli():
    """Runs the ballpass binary; returns its stdout (fails on a non-zero exit)."""
    exe = ballpass_bin()

    def run(*args, cwd=None):
        r = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, cwd=cwd)
        assert r.returncode == 0, f"ballpass {' '.join(map(str, args))}: {r.stderr}"
        return r.stdout

    return run


@pytest.fixture()
def tmp(tmp_path):
    yield tmp_path
    shutil.rmtree(tmp_path, ignore_errors=True)
