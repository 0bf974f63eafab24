//! The models of `ballpass model`: each returns the command's JSON as a
//! dict and its CSV tables as `{column: array}`, from
//! `ballpass::model::tables`.

use ballpass::model::stage::PdLoop;
use ballpass::model::tables::{
    pulses_tables, signals_tables, stage_tables, PulsesTableSettings, SignalsTableSettings,
    StageTableSettings,
};
use ballpass::model::{RatioKind, SinusoidModel};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert;
use crate::errors;

type Tables<'py> = (Bound<'py, PyAny>, Bound<'py, PyDict>);

/// `ballpass.model.signals`: `model` and `settings` are merged onto the
/// defaults of `SinusoidModel` and `SignalsTableSettings`.
#[pyfunction]
#[pyo3(signature = (model=None, settings=None))]
fn model_signals<'py>(
    py: Python<'py>,
    model: Option<&str>,
    settings: Option<&str>,
) -> PyResult<Tables<'py>> {
    let m: SinusoidModel = convert::settings(&SinusoidModel::default(), model, "model")?;
    let s: SignalsTableSettings =
        convert::settings(&SignalsTableSettings::default(), settings, "table settings")?;
    let t = signals_tables(&m, &s).map_err(errors::domain)?;
    let tables = PyDict::new(py);
    tables.set_item("correlations", convert::columns(py, &t.correlations)?)?;
    tables.set_item("spectral_lines", convert::columns(py, &t.spectral_lines)?)?;
    Ok((convert::serialize(py, &t)?, tables))
}

/// `ballpass.model.pulses`: `settings` merged onto `PulsesTableSettings`.
#[pyfunction]
#[pyo3(signature = (settings=None))]
fn model_pulses<'py>(py: Python<'py>, settings: Option<&str>) -> PyResult<Tables<'py>> {
    let s: PulsesTableSettings =
        convert::settings(&PulsesTableSettings::default(), settings, "pulse settings")?;
    let t = py.detach(|| pulses_tables(&s)).map_err(errors::domain)?;
    let tables = PyDict::new(py);
    tables.set_item(
        "gaussian_coefficients",
        convert::columns(py, &t.gaussian_coefficients)?,
    )?;
    tables.set_item(
        "rectangular_coefficients",
        convert::columns(py, &t.rectangular_coefficients)?,
    )?;
    tables.set_item("trains", convert::columns(py, &t.trains)?)?;
    Ok((convert::serialize(py, &t)?, tables))
}

/// The PD loop of `ballpass model stage`: from gains (`kp`, `kd`, with
/// `motor_constant`, default 1) or from `natural_frequency_hz` and `damping`.
fn pd_loop(
    mass_kg: f64,
    motor_constant: Option<f64>,
    kp: Option<f64>,
    kd: Option<f64>,
    natural_frequency_hz: Option<f64>,
    damping: Option<f64>,
) -> PyResult<PdLoop> {
    match (kp, kd, natural_frequency_hz, damping) {
        (Some(kp), Some(kd), None, None) => {
            PdLoop::from_gains(mass_kg, motor_constant.unwrap_or(1.0), kp, kd)
        }
        (None, None, Some(f), Some(z)) => PdLoop::from_natural(mass_kg, f, z),
        _ => return Err(errors::value(
            "a PD stage needs either kp and kd (with motor_constant) or natural_frequency_hz and damping",
        )),
    }
    .map_err(errors::domain)
}

/// `ballpass.model.stage`: `settings` merged onto `StageTableSettings`.
#[pyfunction]
#[pyo3(signature = (mass_kg, motor_constant=None, kp=None, kd=None, natural_frequency_hz=None, damping=None, settings=None))]
#[allow(clippy::too_many_arguments)]
fn model_stage<'py>(
    py: Python<'py>,
    mass_kg: f64,
    motor_constant: Option<f64>,
    kp: Option<f64>,
    kd: Option<f64>,
    natural_frequency_hz: Option<f64>,
    damping: Option<f64>,
    settings: Option<&str>,
) -> PyResult<Tables<'py>> {
    let stage = pd_loop(
        mass_kg,
        motor_constant,
        kp,
        kd,
        natural_frequency_hz,
        damping,
    )?;
    let s: StageTableSettings =
        convert::settings(&StageTableSettings::default(), settings, "stage settings")?;
    let t = py
        .detach(|| stage_tables(&stage, &s))
        .map_err(errors::domain)?;
    let tables = PyDict::new(py);
    tables.set_item("bode", convert::columns(py, &t.bode)?)?;
    tables.set_item("difference", convert::columns(py, &t.difference)?)?;
    if let Some(r) = &t.response {
        tables.set_item("harmonics", convert::columns(py, &r.harmonics)?)?;
        tables.set_item(
            "velocity_response",
            convert::columns(py, &t.velocity_rows())?,
        )?;
    }
    Ok((convert::serialize(py, &t)?, tables))
}

/// The Gaussian `σ / τ_c` of a pulse-width ratio of kind `"sigma"` or
/// `"fwhm"` (width at half maximum over τ_c).
#[pyfunction]
fn sigma_ratio(ratio: f64, kind: &str) -> PyResult<f64> {
    let k: RatioKind = serde_json::from_value(serde_json::Value::String(kind.into()))
        .map_err(|e| errors::value(format!("invalid ratio_kind {kind:?}: {e}")))?;
    Ok(k.sigma_ratio(ratio))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(model_signals, m)?)?;
    m.add_function(wrap_pyfunction!(model_pulses, m)?)?;
    m.add_function(wrap_pyfunction!(model_stage, m)?)?;
    m.add_function(wrap_pyfunction!(sigma_ratio, m)?)?;
    Ok(())
}
