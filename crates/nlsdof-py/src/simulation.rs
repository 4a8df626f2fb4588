//! `nlsdof.Simulation`, the result of `Model.simulate`: the trajectory and
//! the integration-error check of `nlsdof simulate` (issue 26).

use numpy::PyArray1;
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The result of `Model.simulate`: numpy `x` (m) and `v` (m/s) at every
/// input sample; `integration_error`, the estimated integration error
/// relative to max |x| (the CLI's JSON `integration_error.estimate`: step
/// doubling on the whole record, see `nlsdof simulate --help`), `None` when
/// `check=False`; `warning`, the text of the `RuntimeWarning` given when the
/// estimate is above 1e-3 (the CLI's warning, the same text), else `None`.
/// It unpacks as the pair `x, v = model.simulate(u, fs)`.
#[pyclass(frozen, name = "Simulation", module = "nlsdof")]
pub struct Simulation {
    #[pyo3(get)]
    x: Py<PyArray1<f64>>,
    #[pyo3(get)]
    v: Py<PyArray1<f64>>,
    #[pyo3(get)]
    integration_error: Option<f64>,
    #[pyo3(get)]
    warning: Option<String>,
    n: usize,
}

impl Simulation {
    pub(crate) fn new(
        n: usize,
        x: Py<PyArray1<f64>>,
        v: Py<PyArray1<f64>>,
        integration_error: Option<f64>,
        warning: Option<String>,
    ) -> Self {
        Self {
            n,
            x,
            v,
            integration_error,
            warning,
        }
    }
}

#[pymethods]
impl Simulation {
    fn __len__(&self) -> usize {
        2
    }

    /// `result[0]` is `x`, `result[1]` is `v` (as the pair it unpacks to).
    fn __getitem__(&self, py: Python<'_>, i: isize) -> PyResult<Py<PyArray1<f64>>> {
        match i {
            0 | -2 => Ok(self.x.clone_ref(py)),
            1 | -1 => Ok(self.v.clone_ref(py)),
            _ => Err(PyIndexError::new_err(
                "Simulation index out of range (x, v)",
            )),
        }
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        PyTuple::new(py, [self.x.clone_ref(py), self.v.clone_ref(py)])?
            .as_any()
            .try_iter()
            .map(|it| it.into_any())
    }

    fn __repr__(&self) -> String {
        let n = self.n;
        let e = match self.integration_error {
            Some(e) => format!("{e:.1e}"),
            None => "None".into(),
        };
        format!(
            "Simulation({n} samples, integration_error={e}{})",
            if self.warning.is_some() {
                ", warned"
            } else {
                ""
            }
        )
    }
}
