"""Type stubs of the compiled module ``ballpass._native``.

The public API is the ``ballpass`` package; this module's functions take
resolved arguments (settings as JSON text) and are called by it. The two
classes are public: :class:`Recording` and :class:`ThreadPool`.
"""

import os
from typing import Any

import numpy as np
import numpy.typing as npt

__version__: str

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
C128 = npt.NDArray[np.complex128]

class Recording:
    """One bench recording: uniformly sampled channels and metadata.

    Built from arrays (any sequence of real numbers, cast to float64), by
    ``ballpass.load`` or by ``ballpass.simulate``; validated on the way in
    (positive rate, at least one channel, equal lengths, at least 16
    samples, finite values), else ``ValueError`` naming the channel and the
    sample.
    """

    def __init__(
        self,
        fs_hz: float,
        friction_n: npt.ArrayLike | None = None,
        position_mm: npt.ArrayLike | None = None,
        optical_v: npt.ArrayLike | None = None,
        *,
        velocity_mm_s: float | None = None,
        bearing: str | None = None,
        test_id: str | None = None,
        source: str | os.PathLike[str] | None = None,
        start_time_s: float = 0.0,
    ) -> None: ...
    @property
    def fs_hz(self) -> float:
        """Sampling rate, Hz."""
    @property
    def friction_n(self) -> F64 | None:
        """Friction force from the load cell, N (a copy)."""
    @property
    def position_mm(self) -> F64 | None:
        """Stage position from the encoder, mm (a copy)."""
    @property
    def optical_v(self) -> F64 | None:
        """Optical ball-pass sensor, V (a copy)."""
    @property
    def time_s(self) -> F64:
        """Sample times, s: ``start_time_s + i / fs_hz``."""
    @property
    def duration_s(self) -> float:
        """Duration ``len / fs_hz``, s."""
    @property
    def channels(self) -> list[str]:
        """Channels present: ``friction_N``, ``position_mm``, ``optical_V``."""
    @property
    def velocity_mm_s(self) -> float | None:
        """Commanded tracking velocity, mm/s, when known (settable)."""
    @velocity_mm_s.setter
    def velocity_mm_s(self, v: float | None) -> None: ...
    @property
    def bearing(self) -> str | None:
        """Bearing name, when known (settable)."""
    @bearing.setter
    def bearing(self, v: str | None) -> None: ...
    @property
    def test_id(self) -> str | None:
        """Test identifier, when known (settable)."""
    @test_id.setter
    def test_id(self, v: str | None) -> None: ...
    @property
    def source(self) -> str | None:
        """File the recording was read from."""
    @property
    def start_time_s(self) -> float:
        """Time of the first sample, s."""
    @property
    def name(self) -> str:
        """Name used in messages: source file, else test id, else ``recording``."""
    def __len__(self) -> int: ...
    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Writes canonical CSV (``time_s, friction_N, position_mm, optical_V``), atomically."""
    def to_mat(self, path: str | os.PathLike[str]) -> None:
        """Writes a MATLAB level-5 MAT-file, atomically."""

class ThreadPool:
    """A pool of ``threads`` worker threads for ballpass' parallel work
    (repeats, campaigns); use with ``ballpass.threads`` or ``threads=``."""

    def __init__(self, threads: int) -> None: ...
    @property
    def threads(self) -> int:
        """Number of worker threads."""

# ---- domain (called by the ballpass package) ----
def load(path: str, options: str | None = None) -> Recording: ...
def simulate(
    settings: str | None = None,
    velocity_mm_s: float | None = None,
    bearing: str | None = None,
    condition: str | None = None,
    seed: int | None = None,
) -> tuple[Recording, dict[str, Any]]: ...
def predict(velocities_mm_s: list[float], harmonics: int, bearing: str | None = None) -> dict[str, Any]: ...
def analyze(
    recordings: list[Recording],
    velocity_mm_s: float | None = None,
    bearing: str | None = None,
    settings: str | None = None,
    pool: ThreadPool | None = None,
    force_velocity: bool = False,
) -> tuple[dict[str, Any], dict[str, F64], dict[str, F64], dict[str, F64], dict[str, F64],
           dict[str, F64] | None, dict[str, F64] | None]: ...
def analyze_file(
    path: str,
    stream: str,
    load: str | None = None,
    velocity_mm_s: float | None = None,
    settings: str | None = None,
    pool: ThreadPool | None = None,
) -> tuple[tuple[dict[str, Any], dict[str, F64], dict[str, F64], dict[str, F64], dict[str, F64],
                 dict[str, F64] | None, dict[str, F64] | None] | None, str | None]: ...
def compensate(
    recordings: list[Recording],
    velocity_mm_s: float | None = None,
    bearing: str | None = None,
    gains: tuple[float, float, float] | None = None,
    pool: ThreadPool | None = None,
    force_velocity: bool = False,
    load_cell: str | None = None,
) -> tuple[dict[str, Any], dict[str, F64], dict[str, F64] | None, list[str]]: ...
def compensate_second(
    recordings: list[Recording],
    applied_name: str,
    applied_path: str | None = None,
    applied_json: str | None = None,
    velocity_mm_s: float | None = None,
    bearing: str | None = None,
    pool: ThreadPool | None = None,
    force_velocity: bool = False,
    load_cell: str | None = None,
) -> tuple[dict[str, Any], dict[str, F64], list[str]]: ...
def passages(
    recordings: list[Recording],
    bearing: str | None = None,
    settings: str | None = None,
    pool: ThreadPool | None = None,
    window: str | None = None,
    force_velocity: bool = False,
) -> tuple[dict[str, Any], list[dict[str, Any]]]: ...
def manifest(source: str, pattern: str | None = None, load: str | None = None) -> dict[str, Any]: ...
def selection(kind: str, source: str, pattern: str | None = None,
              only_bearings: list[str] = ..., only_velocities: list[float] = ...,
              load: str | None = None) -> dict[str, Any]: ...
def process_record(
    path: str,
    bearing: str,
    velocity_mm_s: float,
    repeat: int,
    condition: str | None = None,
    lowpass_hz: float = 20.0,
    harmonics: int = 5,
    diagnosis: str | None = None,
    load: str | None = None,
    window: str | None = None,
    force_velocity: bool = False,
) -> tuple[dict[str, Any], F64, F64, F64]: ...
def diagnose_records(
    records: list[tuple[str, F64, F64, F64]],
    failures: list[tuple[str, str, float, int, str]],
    source: str,
    selection: list[str],
    lowpass_hz: float = 20.0,
    harmonics: int = 5,
    diagnosis: str | None = None,
    window: str | None = None,
    force_velocity: bool = False,
) -> tuple[dict[str, Any], dict[str, F64]]: ...
def campaign(
    kind: str,
    source: str,
    pattern: str | None = None,
    only_bearings: list[str] = ...,
    only_velocities: list[float] = ...,
    lowpass_hz: float = 20.0,
    harmonics: int = 5,
    diagnosis: str | None = None,
    load: str | None = None,
    pool: ThreadPool | None = None,
    window: str | None = None,
    force_velocity: bool = False,
    segment: bool = False,
) -> tuple[dict[str, Any], dict[str, F64]]: ...
def model_signals(model: str | None = None, settings: str | None = None) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]: ...
def model_pulses(settings: str | None = None) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]: ...
def model_stage(
    mass_kg: float,
    motor_constant: float | None = None,
    kp: float | None = None,
    kd: float | None = None,
    natural_frequency_hz: float | None = None,
    damping: float | None = None,
    settings: str | None = None,
) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]: ...
def sigma_ratio(ratio: float, kind: str) -> float: ...

# ---- kernels (called by ballpass.signal; rows are C-contiguous 2-D) ----
def welch(x: F64, fs: float, window: str | F64, nperseg: int, noverlap: int, nfft: int,
          detrend: str, scaling: str, onesided: bool, average: str) -> tuple[F64, F64]: ...
def csd(x: F64, y: F64, fs: float, window: str | F64, nperseg: int, noverlap: int, nfft: int,
        detrend: str, scaling: str, onesided: bool, average: str) -> tuple[F64, C128]: ...
def coherence(x: F64, y: F64, fs: float, window: str | F64, nperseg: int, noverlap: int,
              nfft: int, detrend: str) -> tuple[F64, F64]: ...
def periodogram(x: F64, fs: float, window: str | F64, nfft: int | None, detrend: str,
                scaling: str, onesided: bool) -> tuple[F64, F64]: ...
def correlate(x: F64, y: F64) -> F64: ...
def correlation_lags(nx: int, ny: int) -> I64: ...
def butter(order: int, wn: list[float], btype: str, fs: float) -> tuple[F64, C128, C128, float]: ...
def cheby1(order: int, rp: float, wn: list[float], btype: str, fs: float) -> tuple[F64, C128, C128, float]: ...
def sosfilt(sos: F64, x: F64, zi: F64 | None = None) -> tuple[F64, F64 | None]: ...
def sosfilt_zi(sos: F64) -> F64: ...
def sosfiltfilt(sos: F64, x: F64, padtype: str, padlen: int | None = None) -> F64: ...
def lfilter(b: F64, a: F64, x: F64, zi: F64 | None = None) -> tuple[F64, F64 | None]: ...
def lfilter1(b: F64, a: F64, x: F64) -> F64: ...
def detrend(x: F64, kind: str) -> F64: ...
def decimate(x: F64, q: int, order: int, zero_phase: bool) -> F64: ...
def find_peaks(x: F64, height: tuple[float | None, float | None] | None,
               threshold: tuple[float | None, float | None] | None, distance: float | None,
               prominence: tuple[float | None, float | None] | None,
               width: tuple[float | None, float | None] | None, wlen: float | None,
               rel_height: float,
               plateau_size: tuple[float | None, float | None] | None) -> tuple[I64, dict[str, npt.NDArray[Any]]]: ...
def peak_prominences(x: F64, peaks: I64, wlen: float | None = None) -> tuple[F64, I64, I64]: ...
def peak_widths(x: F64, peaks: I64, rel_height: float,
                prominence_data: tuple[F64, I64, I64] | None = None,
                wlen: float | None = None) -> tuple[F64, F64, F64, F64]: ...
def freqs(b: F64, a: F64, w: F64) -> C128: ...
def freqz(b: F64, a: F64, f: F64, fs: float) -> C128: ...
def sosfreqz(sos: F64, f: F64, fs: float) -> C128: ...
def freqz_grid(b: F64, a: F64, f: F64, fs: float) -> tuple[F64, C128]: ...
def sosfreqz_grid(sos: F64, f: F64, fs: float) -> tuple[F64, C128]: ...
def gradient(f: F64, h: float, coords: F64 | None, edge_order: int) -> F64: ...
def gradient1(f: F64, h: float, edge_order: int) -> F64: ...
def gradient_plain(f: object, h: object) -> F64 | None: ...
