//! `compensate`: what `ballpass compensate` computes, on recordings already
//! in memory (glue over [`ballpass::model::compensate`]).

use ballpass::analysis::load_cell::LoadCellCorrection;
use ballpass::analysis::AnalyzeSettings;
use ballpass::model::compensate::second::{second_from_records, AppliedTable};
use ballpass::model::compensate::{compensate as compensation, CompensationTable};
use ballpass::model::stage::PdLoop;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::analysis::{checked_run, table};
use crate::errors;
use crate::pool::ThreadPool;
use crate::recording::PyRecording;

fn columns<'py>(py: Python<'py>, t: CompensationTable) -> PyResult<Bound<'py, PyDict>> {
    table(py, t.index_name, &t.index, t.columns)
}

/// `ballpass.compensate`: the feedforward compensation table of recordings
/// at one velocity and its predicted benefit, as `ballpass compensate`:
/// the command line's checks first (their warnings returned apart, as the
/// command line prints them apart from `compensation.json`), the default
/// analysis settings, the stage identified from the records or, when that
/// fails, the loop `gains = (mass kg, K·K_P N/m, K·K_D N·s/m)`. Returns
/// `(compensation.json as a dict, compensation_phase.csv's columns,
/// compensation_rail.csv's columns or None, the checks' warnings)`.
/// The analysis settings of `compensate`: the defaults, with the load
/// cell's correction when `load_cell` (JSON of `LoadCellCorrection`:
/// `"auto"`, `"off"` or `{"time_constant": s}`) is given.
fn settings_with(load_cell: Option<&str>) -> PyResult<AnalyzeSettings> {
    let mut settings = AnalyzeSettings::default();
    if let Some(j) = load_cell {
        let c: LoadCellCorrection = serde_json::from_str(j).map_err(|e| {
            pyo3::exceptions::PyValueError::new_err(format!(
                "load_cell: expected a time constant in seconds (> 0), 'auto' or 'off' ({e})"
            ))
        })?;
        c.validate().map_err(errors::domain)?;
        settings.load_cell = c;
    }
    Ok(settings)
}

#[pyfunction]
#[pyo3(signature = (recordings, velocity_mm_s=None, bearing=None, gains=None, pool=None, force_velocity=false, load_cell=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn compensate<'py>(
    py: Python<'py>,
    recordings: Vec<PyRef<'py, PyRecording>>,
    velocity_mm_s: Option<f64>,
    bearing: Option<&str>,
    gains: Option<(f64, f64, f64)>,
    pool: Option<Bound<'py, ThreadPool>>,
    force_velocity: bool,
    load_cell: Option<&str>,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    Option<Bound<'py, PyDict>>,
    Vec<String>,
)> {
    let settings = settings_with(load_cell)?;
    let gains = gains
        .map(|(m, kp, kd)| PdLoop::from_products(m, kp, kd))
        .transpose()
        .map_err(errors::domain)?;
    let (comp, checks) = checked_run(
        py,
        &recordings,
        velocity_mm_s,
        bearing,
        pool.as_ref(),
        force_velocity,
        settings.harmonics,
        |recs, prediction| compensation(recs, prediction, &settings, gains),
    )?;
    let rail = comp.rail_table().map(|t| columns(py, t)).transpose()?;
    Ok((
        crate::convert::serialize(py, &comp)?,
        columns(py, comp.phase_table())?,
        rail,
        checks.warnings,
    ))
}

/// `ballpass.compensate(..., applied=...)`: the second round, as
/// `ballpass compensate --applied`: the records were taken with the table
/// of `applied` (a compensation.json: read from `applied_path`, or its text
/// `applied_json`, named `applied_name` in errors). Returns
/// `(compensation.json as a dict, compensation_phase.csv's columns, the
/// checks' warnings)`.
#[pyfunction]
#[pyo3(signature = (recordings, applied_name, applied_path=None, applied_json=None, velocity_mm_s=None, bearing=None, pool=None, force_velocity=false, load_cell=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn compensate_second<'py>(
    py: Python<'py>,
    recordings: Vec<PyRef<'py, PyRecording>>,
    applied_name: &str,
    applied_path: Option<std::path::PathBuf>,
    applied_json: Option<&str>,
    velocity_mm_s: Option<f64>,
    bearing: Option<&str>,
    pool: Option<Bound<'py, ThreadPool>>,
    force_velocity: bool,
    load_cell: Option<&str>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>, Vec<String>)> {
    let settings = settings_with(load_cell)?;
    let applied = match (applied_path, applied_json) {
        (Some(p), None) => AppliedTable::read(&p),
        (None, Some(j)) => AppliedTable::parse(std::path::Path::new(applied_name), j),
        _ => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "applied: give the compensation.json as a path or as its dict, one of them",
            ))
        }
    }
    .map_err(errors::domain)?;
    let (second, checks) = checked_run(
        py,
        &recordings,
        velocity_mm_s,
        bearing,
        pool.as_ref(),
        force_velocity,
        settings.harmonics,
        |recs, prediction| second_from_records(recs, prediction, &settings, &applied),
    )?;
    Ok((
        crate::convert::serialize(py, &second)?,
        columns(py, second.phase_table())?,
        checks.warnings,
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(compensate, m)?)?;
    m.add_function(wrap_pyfunction!(compensate_second, m)?)?;
    Ok(())
}
