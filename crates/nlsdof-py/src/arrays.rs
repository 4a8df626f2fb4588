//! numpy arguments: any array-like of numbers becomes a one-dimensional
//! float64 array; a contiguous float64 array is read in place (no copy).

use crate::convert::value_error;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use std::borrow::Cow;

/// `obj` as a one-dimensional float64 array: taken as it is when it is one,
/// else converted by `numpy.asarray(obj, dtype=float64)` (ints, lists,
/// float32, ...). `name` names the argument in errors.
pub fn f64_array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<PyReadonlyArray1<'py, f64>> {
    if let Ok(a) = obj.extract::<PyReadonlyArray1<'py, f64>>() {
        return Ok(a);
    }
    let np = obj.py().import("numpy")?;
    let conv = np
        .call_method1("asarray", (obj, "float64"))
        .map_err(|e| value_error(format!("{name}: not an array of real numbers ({e})")))?;
    let ndim: usize = conv.getattr("ndim")?.extract()?;
    if ndim != 1 {
        let shape: Vec<usize> = conv.getattr("shape")?.extract()?;
        return Err(value_error(format!(
            "{name} must be one-dimensional, got shape {shape:?}"
        )));
    }
    conv.extract::<PyReadonlyArray1<'py, f64>>()
        .map_err(|e| value_error(format!("{name}: {e}")))
}

/// The values of `a`: borrowed when contiguous, else copied once.
pub fn values<'a>(a: &'a PyReadonlyArray1<'_, f64>) -> Cow<'a, [f64]> {
    match a.as_slice() {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
    }
}
