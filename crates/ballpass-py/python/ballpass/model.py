"""The signal and stage models of the thesis' chapter 6 (with its formulas
corrected), as ``ballpass model signals|pulses|stage``: each function returns
a result whose ``to_dict()`` equals the command's JSON file and whose tables
equal its CSV files.

The ball-pass frequency ``f_c_hz`` is given directly, or from a velocity
(mm/s) and a bearing (default ``sr25w``) as :func:`ballpass.predict` gives it.
"""

from __future__ import annotations

import json

from . import _native
from ._results import Result, Table

__all__ = ["signals", "pulses", "stage"]


def _f_c(f_c_hz, velocity_mm_s, bearing, what, required):
    if velocity_mm_s is not None:
        if f_c_hz is not None:
            raise ValueError(f"{what}: give f_c_hz or velocity_mm_s, not both")
        p = _native.predict([float(velocity_mm_s)], 1,
                            None if bearing is None else json.dumps({"bearing": bearing}))
        return p["predictions"][0]["f_c_hz"]
    if f_c_hz is None:
        if required:
            raise ValueError(
                f"{what} needs the ball-pass frequency: give velocity_mm_s (mm/s) or f_c_hz (Hz)"
            )
        return None
    f = float(f_c_hz)
    if not (f > 0 and f < float("inf")):
        raise ValueError(f"invalid f_c_hz: must be a positive number of Hz, got {f_c_hz}")
    return f


def _result(pair, kind):
    data, tables = pair
    return Result(data, {k: Table(v) for k, v in tables.items()}, kind)


def signals(f_c_hz: float | None = None, *, velocity_mm_s: float | None = None,
            bearing: str | None = None, friction_dc_n: float = 1.0,
            friction_amp_n: float = 1.0, velocity_amp_mm_s: float = 1.0,
            optical_dc_v: float = 1.0, optical_amp_v: float = 1.0,
            convention: str = "eq71", periods: float = 2.0, points: int = 401) -> Result:
    """The sinusoid model signals (thesis §6.2): friction ``F_c + a_f sin``,
    velocity error ``a_v cos``, optical ``S + a_s sin`` at f_c; their
    analytic correlations on ``points`` lags over ``±periods`` τ_c
    (``correlations`` table, convention ``'eq71'`` as scipy.signal.correlate
    or ``'eq612'``), spectral lines and correlation peaks. ``to_dict()``
    equals ``signals.json``."""
    f = _f_c(f_c_hz, velocity_mm_s, bearing, "model signals", True)
    model = dict(f_c_hz=f, friction_dc_n=friction_dc_n, friction_amp_n=friction_amp_n,
                 velocity_amp_mm_s=velocity_amp_mm_s, optical_dc_v=optical_dc_v,
                 optical_amp_v=optical_amp_v)
    settings = dict(periods=periods, points=points, convention=convention)
    return _result(_native.model_signals(json.dumps(model), json.dumps(settings)), "SignalsModel")


def pulses(ratio: float = 0.155, *, ratio_kind: str = "sigma", f_c_hz: float | None = None,
           velocity_mm_s: float | None = None, bearing: str | None = None,
           amplitude: float = 1.0, dc: float = 0.0, harmonics: int = 10, order: int = 20,
           periods: int = 2, points: int = 500) -> Result:
    """Gaussian and rectangular pulse trains (thesis §6.3): the Gaussian
    Fourier coefficients C_0..C_harmonics, the rectangular series of order
    ``order``, and ``periods`` periods synthesised with ``points`` samples
    each (tables ``gaussian_coefficients``, ``rectangular_coefficients``,
    ``trains``). ``ratio`` is σ/τ_c (``ratio_kind='sigma'``) or the width at
    half maximum over τ_c (``'fwhm'``); without a frequency τ_c = 1 s.
    ``to_dict()`` equals ``pulses.json``."""
    f = _f_c(f_c_hz, velocity_mm_s, bearing, "model pulses", False)
    settings = dict(f_c_hz=f, ratio=ratio, ratio_kind=ratio_kind, amplitude=amplitude, dc=dc,
                    harmonics=harmonics, order=order, periods=periods, points=points)
    return _result(_native.model_pulses(json.dumps(settings)), "PulsesModel")


def stage(mass_kg: float, *, motor_constant: float = 1.0, kp: float | None = None,
          kd: float | None = None, natural_frequency_hz: float | None = None,
          damping: float | None = None, f_min_hz: float = 0.01, f_max_hz: float = 1000.0,
          points: int = 500, difference_fs_hz: float = 1000.0, f_c_hz: float | None = None,
          velocity_mm_s: float | None = None, bearing: str | None = None,
          ratio: float = 0.155, ratio_kind: str = "sigma", friction_amplitude_n: float = 1.0,
          harmonics: int | None = None, period_points: int = 1000) -> Result:
    """The PD-controlled stage (thesis §6.1) of mass ``mass_kg`` (kg) from
    gains (``kp`` A/m, ``kd`` A·s/m, ``motor_constant`` N/A) or from
    ``natural_frequency_hz`` and ``damping``: Bode table of G_xr, G_xf, G_vf
    (``bode``, log-spaced ``f_min_hz``..``f_max_hz``), the differentiators
    at ``difference_fs_hz`` (``difference``), and with a ball-pass frequency
    the velocity under Gaussian friction pulses of height
    ``friction_amplitude_n`` N (``harmonics``, ``velocity_response``).
    ``to_dict()`` equals ``stage.json``."""
    f = _f_c(f_c_hz, velocity_mm_s, bearing, "model stage", False)
    settings = dict(
        axis=dict(f_min_hz=f_min_hz, f_max_hz=f_max_hz, points=points),
        difference_fs_hz=difference_fs_hz,
        f_c_hz=f,
        sigma_ratio=_native.sigma_ratio(float(ratio), ratio_kind),
        friction_amplitude_n=friction_amplitude_n,
        velocity=dict(harmonics=harmonics, points_per_period=period_points),
    )
    pair = _native.model_stage(float(mass_kg), motor_constant, kp, kd, natural_frequency_hz,
                               damping, json.dumps(settings))
    return _result(pair, "StageModel")
