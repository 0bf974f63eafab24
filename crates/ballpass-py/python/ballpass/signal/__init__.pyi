"""Type stubs of ``ballpass.signal`` (SciPy 1.17's signatures; results are
float64/complex128 arrays; ``fs`` in Hz gives Hz and unit²/Hz)."""

from typing import Any, Callable, Literal, Sequence

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.intp]
C128 = npt.NDArray[np.complex128]
Window = str | tuple[str] | npt.ArrayLike
Detrend = Literal["constant", "linear", False] | None
Interval = float | tuple[float | None, float | None] | None

class PeakPropertyWarning(RuntimeWarning): ...

def welch(x: npt.ArrayLike, fs: float = 1.0, window: Window = "hann_periodic",
          nperseg: int | None = None, noverlap: int | None = None, nfft: int | None = None,
          detrend: Detrend = "constant", return_onesided: bool = True,
          scaling: Literal["density", "spectrum"] = "density", axis: int = -1,
          average: Literal["mean", "median"] = "mean") -> tuple[F64, F64]:
    """(f Hz, Pxx unit²/Hz) by Welch's method."""
def csd(x: npt.ArrayLike, y: npt.ArrayLike, fs: float = 1.0, window: Window = "hann_periodic",
        nperseg: int | None = None, noverlap: int | None = None, nfft: int | None = None,
        detrend: Detrend = "constant", return_onesided: bool = True,
        scaling: Literal["density", "spectrum"] = "density", axis: int = -1,
        average: Literal["mean", "median"] = "mean") -> tuple[F64, C128]:
    """(f Hz, Pxy = conj(X) Y, unit_x·unit_y/Hz)."""
def coherence(x: npt.ArrayLike, y: npt.ArrayLike, fs: float = 1.0,
              window: Window = "hann_periodic", nperseg: int | None = None,
              noverlap: int | None = None, nfft: int | None = None,
              detrend: Detrend = "constant", axis: int = -1) -> tuple[F64, F64]:
    """(f Hz, |Pxy|²/(Pxx Pyy) in [0, 1])."""
def periodogram(x: npt.ArrayLike, fs: float = 1.0, window: Window = "boxcar",
                nfft: int | None = None, detrend: Detrend = "constant",
                return_onesided: bool = True,
                scaling: Literal["density", "spectrum"] = "density",
                axis: int = -1) -> tuple[F64, F64]:
    """(f Hz, Pxx unit²/Hz) from one windowed segment."""
def correlate(in1: npt.ArrayLike, in2: npt.ArrayLike,
              mode: Literal["full", "same", "valid"] = "full",
              method: Literal["auto", "fft", "direct"] = "auto") -> F64:
    """z[k] = sum_n in1[n + k] in2[n] (1-D, by FFT; 'direct' is NotImplemented)."""
def correlation_lags(in1_len: int, in2_len: int,
                     mode: Literal["full", "same", "valid"] = "full") -> I64:
    """Lags (samples) of correlate's output."""
def butter(N: int, Wn: float | Sequence[float], btype: str = "low", analog: bool = False,
           output: Literal["ba", "zpk", "sos"] = "ba", fs: float | None = None) -> Any:
    """Digital Butterworth filter; Wn in Hz with fs, else a fraction of Nyquist."""
def cheby1(N: int, rp: float, Wn: float | Sequence[float], btype: str = "low",
           analog: bool = False, output: Literal["ba", "zpk", "sos"] = "ba",
           fs: float | None = None) -> Any:
    """Digital Chebyshev type I filter with rp dB pass-band ripple."""
def sosfilt(sos: npt.ArrayLike, x: npt.ArrayLike, axis: int = -1,
            zi: npt.ArrayLike | None = None) -> F64 | tuple[F64, F64]:
    """Second-order sections, direct form II transposed; (y, zf) with zi."""
def sosfilt_zi(sos: npt.ArrayLike) -> F64:
    """Initial states for a unit step's steady state, shape (n_sections, 2)."""
def sosfiltfilt(sos: npt.ArrayLike, x: npt.ArrayLike, axis: int = -1,
                padtype: Literal["odd", "even", "constant"] | None = "odd",
                padlen: int | None = None) -> F64:
    """Zero-phase forward-backward filtering."""
def lfilter(b: npt.ArrayLike, a: npt.ArrayLike, x: npt.ArrayLike, axis: int = -1,
            zi: npt.ArrayLike | None = None) -> F64 | tuple[F64, F64]:
    """Transfer function b(z)/a(z), direct form II transposed; (y, zf) with zi."""
def detrend(data: npt.ArrayLike, axis: int = -1,
            type: Literal["linear", "l", "constant", "c"] = "linear",
            bp: int | npt.ArrayLike = 0, overwrite_data: bool = False) -> F64:
    """Removes the least-squares line or the mean."""
def decimate(x: npt.ArrayLike, q: int, n: int | None = None, ftype: str = "iir",
             axis: int = -1, zero_phase: bool = True) -> F64:
    """Chebyshev I anti-alias low-pass, then every q-th sample."""
def find_peaks(x: npt.ArrayLike, height: Interval = None, threshold: Interval = None,
               distance: float | None = None, prominence: Interval = None,
               width: Interval = None, wlen: float | None = None, rel_height: float = 0.5,
               plateau_size: Interval = None) -> tuple[I64, dict[str, npt.NDArray[Any]]]:
    """(peak indices, properties with SciPy's keys); widths in samples."""
def peak_prominences(x: npt.ArrayLike, peaks: npt.ArrayLike,
                     wlen: float | None = None) -> tuple[F64, I64, I64]:
    """(prominences, left_bases, right_bases)."""
def peak_widths(x: npt.ArrayLike, peaks: npt.ArrayLike, rel_height: float = 0.5,
                prominence_data: tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike] | None = None,
                wlen: float | None = None) -> tuple[F64, F64, F64, F64]:
    """(widths, width_heights, left_ips, right_ips), in samples."""
def freqs(b: npt.ArrayLike, a: npt.ArrayLike, worN: npt.ArrayLike = ...,
          plot: Callable[..., Any] | None = None) -> tuple[F64, C128]:
    """H(jw) at angular frequencies worN (rad/s; an int is NotImplemented)."""
def freqz(b: npt.ArrayLike, a: npt.ArrayLike = 1, worN: int | npt.ArrayLike | None = 512,
          whole: bool = False, plot: Callable[..., Any] | None = None, fs: float = ...,
          include_nyquist: bool = False) -> tuple[F64, C128]:
    """(w in the units of fs, H)."""
def freqz_sos(sos: npt.ArrayLike, worN: int | npt.ArrayLike | None = 512, whole: bool = False,
              fs: float = ...) -> tuple[F64, C128]:
    """(w in the units of fs, H) of second-order sections."""
def sosfreqz(sos: npt.ArrayLike, worN: int | npt.ArrayLike | None = 512, whole: bool = False,
             fs: float = ...) -> tuple[F64, C128]:
    """The former name of freqz_sos."""
def gradient(f: npt.ArrayLike, *varargs: float | npt.ArrayLike, axis: int | Sequence[int] | None = None,
             edge_order: Literal[1, 2] = 1) -> F64 | tuple[F64, ...]:
    """numpy.gradient: units of f per unit of the spacing."""
