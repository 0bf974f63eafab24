"""The package as shipped: stubs that match the runtime, the notebook-style
example of the docs runs, and the version is the library's."""

from __future__ import annotations

import ast
import pathlib
import subprocess
import sys

import ballpass
from ballpass import _native, signal

from conftest import ROOT

PKG = pathlib.Path(ballpass.__file__).parent


def _stub_names(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text())
    return {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}


def test_stubs_name_what_exists_and_cover_the_public_api():
    for stub, mod in ((PKG / "_native.pyi", _native), (PKG / "signal" / "__init__.pyi", signal)):
        names = _stub_names(stub)
        missing = sorted(n for n in names if not hasattr(mod, n))
        assert not missing, f"{stub.name} declares {missing}, which {mod.__name__} lacks"
    assert set(signal.__all__) <= _stub_names(PKG / "signal" / "__init__.pyi")
    public = {n for n in dir(_native) if not n.startswith("_")}
    assert public <= _stub_names(PKG / "_native.pyi"), public - _stub_names(PKG / "_native.pyi")
    assert (PKG / "py.typed").exists()


def test_every_public_function_has_a_docstring():
    for name in ballpass.__all__:
        obj = getattr(ballpass, name)
        assert (obj.__doc__ or "").strip(), name
    for name in signal.__all__:
        assert (getattr(signal, name).__doc__ or "").strip(), name


def test_version_is_the_librarys():
    cargo = (ROOT / "Cargo.toml").read_text()
    assert f'version = "{ballpass.__version__}"' in cargo


def test_notebook_example_runs_and_plots(tmp_path):
    out = tmp_path / "analysis.png"
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "notebook_analysis.py"), str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "ball-pass frequency found" in r.stdout, r.stdout
    assert out.stat().st_size > 10_000
