#!/usr/bin/env python3
"""Parity fixtures for `ballpass analyze` (crates/ballpass/tests/analyze_parity.rs).

Writes a small synthetic recording (8 s at 200 Hz, 18 mm/s, SR25W: Gaussian
pulse trains in friction and optical, a ripple and 0.1 um quantisation in the
position, seeded noise) to crates/ballpass/tests/fixtures/analyze/input.csv,
then runs tools/reference_analyze.py on it for each variant below and keeps
its CSV outputs (printed with 13 significant digits, enough for the 1e-9
comparison) under <variant>/. `settings.json` records each variant's flags.

Usage: python3 tools/gen_analyze_fixtures.py   (pinned versions: tools/requirements.txt)
"""
import json
import pathlib
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
OUT = ROOT / "crates/ballpass/tests/fixtures/analyze"
FS = 200.0
DURATION = 8.0
V = 18.0
D_AVG = 4.0 + 2.0 / 36.0

VARIANTS = {
    # Defaults (nperseg 4096 is capped at the 1600 samples).
    "default": [],
    # Every step-2/3/4 setting changed, and a trim.
    "settings": [
        "--lowpass", "15", "--order", "4", "--detrend", "constant",
        "--corr-norm", "unbiased", "--nperseg", "512", "--noverlap", "128",
        "--trim", "0.5", "--nperseg-hr", "64", "--noverlap-hr", "16",
    ],
    # The thesis' zoom processing for the high-resolution spectrum.
    "zoom": ["--zoom", "4", "--corr-norm", "biased", "--detrend", "none", "--nperseg-hr", "128"],
}


def gaussian_train(t, period, delay, fwhm_ratio=0.155):
    sigma = fwhm_ratio * period / (2.0 * np.sqrt(2.0 * np.log(2.0)))
    ph = np.mod(t - delay, period)
    d = np.minimum(ph, period - ph)
    return np.exp(-0.5 * (d / sigma) ** 2)


def record():
    rng = np.random.default_rng(20240611)
    n = int(DURATION * FS)
    t = np.arange(n) / FS
    tau = 2.0 * D_AVG / V
    friction = 3.0 + 0.3 * gaussian_train(t, tau, 0.1) + 0.05 * rng.standard_normal(n)
    optical = 1.0 + 0.5 * gaussian_train(t, tau, 0.1 + 0.2) + 0.02 * rng.standard_normal(n)
    ripple_mm = 0.5e-3 * np.sin(2 * np.pi * t / tau)
    position = np.floor((V * t + ripple_mm) / 1e-4) * 1e-4
    return t, friction, position, optical


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    t, fr, pos, opt = record()
    inp = OUT / "input.csv"
    with open(inp, "w") as f:
        f.write("time_s,friction_N,position_mm,optical_V\n")
        for row in zip(t, fr, pos, opt):
            f.write(",".join(repr(float(v)) for v in row) + "\n")
    settings = {}
    for name, flags in VARIANTS.items():
        d = OUT / name
        d.mkdir(exist_ok=True)
        cmd = [sys.executable, str(ROOT / "tools/reference_analyze.py"), str(inp),
               "--velocity", repr(V), "--out", str(d)] + flags
        subprocess.run(cmd, check=True)
        for csv in d.glob("*.csv"):
            data = np.loadtxt(csv, delimiter=",", skiprows=1)
            header = csv.read_text().split("\n", 1)[0]
            np.savetxt(csv, data, delimiter=",", header=header, comments="", fmt="%.13g")
        settings[name] = flags
    (OUT / "settings.json").write_text(json.dumps(
        {"velocity_mm_s": V, "fs_hz": FS, "variants": settings}, indent=1) + "\n")


if __name__ == "__main__":
    main()
