//! Documents handed to Python as `nlsdof._report.Report`: a `dict` (equal
//! to the CLI's `--json` document) that Jupyter shows as a table of
//! parameters with intervals, units and the status (`_repr_html_`).

use pyo3::prelude::*;

/// `doc` (a dict) as a `Report` of `kind` (the call that made it).
pub fn report<'py>(doc: Bound<'py, PyAny>, kind: &str) -> PyResult<Bound<'py, PyAny>> {
    let py = doc.py();
    py.import("nlsdof._report")?
        .getattr("Report")?
        .call1((doc, kind))
}
