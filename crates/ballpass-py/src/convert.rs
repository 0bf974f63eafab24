//! Conversions between the library's serde values and Python objects.
//!
//! Results cross as their serde JSON value ([`to_py`]), so a Python result's
//! `to_dict()` is by construction what the command-line tool writes as JSON
//! (NaN and infinities are `None`, as serde_json writes them `null`).
//! Tables of serde rows cross as columns ([`columns`]). Settings come in as
//! JSON text merged onto the library's defaults ([`settings`]), so every
//! field of a settings struct is reachable by its serde name.

use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

use crate::errors;

/// A serde JSON value as a Python object: `None`, `bool`, `int`, `float`,
/// `str`, `list` and `dict` (keys in the struct's field order).
pub fn to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => {
            if let Some(i) = n.as_i64() {
                i.into_pyobject(py)?.into_any()
            } else if let Some(u) = n.as_u64() {
                u.into_pyobject(py)?.into_any()
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any()
            }
        }
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let list = PyList::empty(py);
            for x in a {
                list.append(to_py(py, x)?)?;
            }
            list.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A serializable value as its JSON value.
pub fn json_value<T: Serialize>(v: &T) -> PyResult<Value> {
    serde_json::to_value(v).map_err(|e| errors::value(format!("cannot serialise: {e}")))
}

/// A serializable value as the Python object of its JSON value.
pub fn serialize<'py, T: Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    to_py(py, &json_value(v)?)
}

/// Serde rows (CSV table rows) as `{column: numpy array or list}`, in the
/// rows' field order: numbers become float64 arrays (`None` as NaN), whole
/// numbers without gaps int64 arrays, anything else a list. An empty table
/// has no columns.
pub fn columns<'py, T: Serialize>(py: Python<'py>, rows: &[T]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    let Value::Array(rows) = json_value(&rows)? else {
        return Ok(out);
    };
    let Some(Value::Object(first)) = rows.first() else {
        return Ok(out);
    };
    for key in first.keys() {
        let cells: Vec<&Value> = rows
            .iter()
            .map(|r| r.get(key).unwrap_or(&Value::Null))
            .collect();
        out.set_item(key, column(py, &cells)?)?;
    }
    Ok(out)
}

/// One column as the most specific array type that holds it.
fn column<'py>(py: Python<'py>, cells: &[&Value]) -> PyResult<Bound<'py, PyAny>> {
    let numeric = cells.iter().all(|c| c.is_number() || c.is_null());
    let whole = cells.iter().all(|c| c.is_i64() || c.is_u64());
    if whole {
        let v: Vec<i64> = cells
            .iter()
            .map(|c| c.as_i64().unwrap_or(i64::MAX))
            .collect();
        return Ok(v.into_pyarray(py).into_any());
    }
    if numeric {
        let v: Vec<f64> = cells
            .iter()
            .map(|c| c.as_f64().unwrap_or(f64::NAN))
            .collect();
        return Ok(v.into_pyarray(py).into_any());
    }
    let list = PyList::empty(py);
    for c in cells {
        list.append(to_py(py, c)?)?;
    }
    Ok(list.into_any())
}

/// A float vector as a numpy array (no copy).
pub fn array<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    v.into_pyarray(py)
}

/// `base` with every key of `over` replaced, objects merged key by key.
fn merge(base: &mut Value, over: Value) {
    match (base, over) {
        (Value::Object(b), Value::Object(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(slot) if slot.is_object() && v.is_object() => merge(slot, v),
                    _ => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (slot, v) => *slot = v,
    }
}

/// `defaults` with the JSON object `overrides` merged onto it (nested
/// objects key by key), read back as `T`. `what` names the settings in the
/// error, which says which field is unknown or has the wrong type.
pub fn settings<T: Serialize + DeserializeOwned>(
    defaults: &T,
    overrides: Option<&str>,
    what: &str,
) -> PyResult<T> {
    let Some(text) = overrides else {
        return serde_json::from_value(json_value(defaults)?)
            .map_err(|e| errors::value(format!("{what}: {e}")));
    };
    let over: Value =
        serde_json::from_str(text).map_err(|e| errors::value(format!("{what}: {e}")))?;
    if !over.is_object() {
        return Err(errors::value(format!(
            "{what}: expected a dict of settings, got {over}"
        )));
    }
    let mut base = json_value(defaults)?;
    merge(&mut base, over);
    serde_json::from_value(base).map_err(|e| errors::value(format!("invalid {what}: {e}")))
}
