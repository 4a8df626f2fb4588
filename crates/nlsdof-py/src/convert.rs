//! Errors and documents: library errors as `ValueError`, JSON documents
//! (`serde_json::Value`) as Python dicts and lists.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;

/// A library error as a `ValueError` with the CLI's one-line message.
pub fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(nlsdof_report::compact_numbers(&e.to_string()))
}

/// A JSON document as Python objects (`null` -> `None`, numbers -> `int`
/// or `float`, arrays -> `list`, objects -> `dict` in key order).
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
            let l = PyList::empty(py);
            for x in a {
                l.append(to_py(py, x)?)?;
            }
            l.into_any()
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

/// A sweep direction from `"up"` or `"down"`.
pub fn direction(s: &str) -> PyResult<nlsdof::SweepDirection> {
    match s.to_ascii_lowercase().as_str() {
        "up" => Ok(nlsdof::SweepDirection::Up),
        "down" => Ok(nlsdof::SweepDirection::Down),
        _ => Err(value_error(format!(
            "direction {s:?} is not allowed: use \"up\" or \"down\""
        ))),
    }
}

/// A formulation from `"hb"` (exact first-order harmonic balance) or
/// `"modulation"` (the paper's Eq 30).
pub fn formulation(s: &str) -> PyResult<nlsdof::Formulation> {
    match s.to_ascii_lowercase().as_str() {
        "hb" => Ok(nlsdof::Formulation::HarmonicBalance),
        "modulation" => Ok(nlsdof::Formulation::Modulation),
        _ => Err(value_error(format!(
            "formulation {s:?} is not allowed: use \"hb\" or \"modulation\""
        ))),
    }
}

/// A pair `(a, b)` from any sequence of two values (tuple, list, numpy
/// array), naming the argument when it has another length.
pub fn pair<T: Copy>(v: Option<Vec<T>>, name: &str) -> PyResult<Option<(T, T)>> {
    match v {
        None => Ok(None),
        Some(v) if v.len() == 2 => Ok(Some((v[0], v[1]))),
        Some(v) => Err(value_error(format!(
            "{name} must be a pair of two values, got {}",
            v.len()
        ))),
    }
}
