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

    /// Jupyter: samples, peak displacement (m) and velocity (m/s), the
    /// integration-error estimate and the status (ok / warning).
    fn _repr_html_(&self, py: Python<'_>) -> PyResult<String> {
        use numpy::PyArrayMethods;
        let peak = |a: &Py<PyArray1<f64>>| -> PyResult<f64> {
            let r = a.bind(py).readonly();
            Ok(r.as_array().iter().fold(0.0_f64, |m, v| m.max(v.abs())))
        };
        let (px, pv) = (peak(&self.x)?, peak(&self.v)?);
        let err = match self.integration_error {
            Some(e) => format!("{e:.3e}"),
            None => "not checked".into(),
        };
        let status = match &self.warning {
            Some(w) => format!(
                "<b>WARNING:</b> {}",
                w.replace('&', "&amp;")
                    .replace('<', "&lt;")
                    .replace('>', "&gt;")
            ),
            None => "ok".into(),
        };
        Ok(format!(
            "<div><b>nlsdof Simulation</b> &mdash; {status}<table>\
             <tr><th>quantity</th><th>value</th><th>unit</th></tr>\
             <tr><td>samples</td><td>{}</td><td>-</td></tr>\
             <tr><td>max |x|</td><td>{px:.6e}</td><td>m</td></tr>\
             <tr><td>max |v|</td><td>{pv:.6e}</td><td>m/s</td></tr>\
             <tr><td>integration error (relative to max |x|)</td><td>{err}</td><td>-</td></tr>\
             </table></div>",
            self.n
        ))
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
