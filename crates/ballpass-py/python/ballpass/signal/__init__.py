"""SciPy-compatible signal processing, computed by ballpass' Rust kernels.

Swap ``from scipy import signal`` for ``from ballpass import signal`` and the
functions below take the same arguments, defaults and return values as in
SciPy 1.17, give the same numbers (to 1e-9 relative or better on the
project's SciPy fixtures, tested), and raise SciPy's exceptions for SciPy's
bad inputs. ``gradient`` is ``numpy.gradient``.

Where ballpass differs, it says so loudly, never with a different answer:

* an option ballpass does not implement (another window, ``method='direct'``,
  ``ftype='fir'``, ``analog=True``, per-sample ``find_peaks`` bounds, ...)
  raises ``NotImplementedError`` naming it;
* complex input raises ``NotImplementedError``; NaN or infinite samples raise
  ``ValueError`` (SciPy would return NaN);
* results are float64 (complex128) whatever the input dtype: lists, ints and
  float32 are cast to float64 first (SciPy keeps float32 as float32, and
  ``correlate`` of integers is integer there).

Windows: ``'hann'`` (SciPy's default ``'hann_periodic'``), ``'hamming'``,
``'boxcar'`` and their aliases, all periodic (DFT-even) as ``get_window``
makes them, or an array of window values.

Units: ``fs`` in Hz gives frequencies in Hz and densities in unit²/Hz, as in
SciPy; lags are in samples.

The computation runs with the GIL released, in the calling thread.
"""

from ._filters import (
    butter,
    cheby1,
    decimate,
    detrend,
    lfilter,
    sosfilt,
    sosfilt_zi,
    sosfiltfilt,
)
from ._peaks import PeakPropertyWarning, find_peaks, peak_prominences, peak_widths
from ._responses import freqs, freqz, freqz_sos, gradient, sosfreqz
from ._spectral import coherence, correlate, correlation_lags, csd, periodogram, welch

__all__ = [
    "welch",
    "csd",
    "coherence",
    "periodogram",
    "correlate",
    "correlation_lags",
    "butter",
    "cheby1",
    "sosfilt",
    "sosfilt_zi",
    "sosfiltfilt",
    "lfilter",
    "detrend",
    "decimate",
    "find_peaks",
    "peak_prominences",
    "peak_widths",
    "freqs",
    "freqz",
    "sosfreqz",
    "freqz_sos",
    "gradient",
    "PeakPropertyWarning",
]
