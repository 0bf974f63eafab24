# %% [markdown]
# # A bench record in a notebook
#
# Load one recording, analyse it with ballpass and plot what it found: the
# signals, the friction × optical correlation with its lag, and the friction
# spectrum against the predicted ball-pass frequency `f_c = v / (2 d_avg)`.
# Each `# %%` block is one notebook cell (VS Code, Jupytext and Spyder run
# them as cells; `python examples/notebook_analysis.py OUT.png` runs the
# whole file and saves the figure).
#
# Install: `pip install ./crates/ballpass-py matplotlib` from the repository.

# %%
import sys
import tempfile
from pathlib import Path

import matplotlib

if __name__ == "__main__" and len(sys.argv) > 1:
    matplotlib.use("Agg")  # a script writing a PNG needs no display
import matplotlib.pyplot as plt
import numpy as np

import ballpass

# A recording as a lab has it: here the built-in bench simulator writes one
# (30 s at 1 kHz, THK SR25W at 9 mm/s); use your own file instead.
path = Path(tempfile.mkdtemp()) / "run_v9.csv"
sim, truth = ballpass.simulate(9.0, seed=7)
sim.to_csv(path)

rec = ballpass.load(path, velocity_mm_s=9.0)  # columns time_s, friction_N, position_mm, optical_V
rec

# %%
a = ballpass.analyze(rec)  # the analysis of `ballpass analyze`, on this process's arrays
print(a.verdict.text)
print(f"f_c predicted {a.prediction.f_c_hz:.4f} Hz, measured {a.measured_period.f_c_hz:.4f} Hz")
for ph in a.phases:
    print(" ", ph.words)

# %%
fig, ax = plt.subplots(3, 1, figsize=(8, 9), constrained_layout=True)
t = rec.time_s
ax[0].plot(t, rec.friction_n, lw=0.6, label="friction (N)")
ax[0].plot(t, rec.optical_v, lw=0.6, label="optical (V)")
ax[0].set_xlim(0, 5)
ax[0].set_xlabel("time (s)")
ax[0].legend(loc="upper right")

c = a.correlations  # columns of correlations.csv: lag_s, then one per series
ax[1].plot(c.lag_s, c.r_friction__optical, lw=0.8)
tau_c = a.prediction.tau_c_s
for k in range(-2, 3):
    ax[1].axvline(k * tau_c, color="0.8", lw=0.8)
ax[1].set_xlim(-2.5 * tau_c, 2.5 * tau_c)
ax[1].set_xlabel("lag (s)  [peak at -d: optical lags friction by d]")
ax[1].set_ylabel("R friction×optical (coeff)")

s = a.spectra_hires  # freq_hz, then PSDs and cross spectra
ax[2].semilogy(s.freq_hz, s.psd_friction_n2_per_hz, lw=0.8)
for f in a.prediction.harmonics_hz:
    ax[2].axvline(f, color="tab:red", lw=0.6, alpha=0.5)
ax[2].set_xlim(0, 6 * a.prediction.f_c_hz)
ax[2].set_xlabel("frequency (Hz); red: k·f_c predicted")
ax[2].set_ylabel("friction PSD (N²/Hz)")

# %%
# Everything the command line writes as analysis.json is there as a dict:
summary = a.to_dict()
sorted(summary)[:8], np.round(a.spectra.psd_friction_n2_per_hz.max(), 6)

# %%
if __name__ == "__main__" and len(sys.argv) > 1:
    fig.savefig(sys.argv[1], dpi=80)
