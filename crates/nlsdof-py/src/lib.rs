//! Python bindings of nlsdof: the module `nlsdof` (this crate's extension
//! `nlsdof._nlsdof`, re-exported by `python/nlsdof/__init__.py`).
//!
//! A thin layer over the library: each function converts its arguments,
//! calls one library entry point with the GIL released, and converts the
//! result. The documents (`to_dict()`) are those of the CLI's `--json`,
//! built by `nlsdof-report`, so both give the same keys and numbers. Every
//! library error becomes a `ValueError` carrying the CLI's one-line message.

mod arrays;
mod convert;
mod document;
mod fit;
mod inspect;
mod interrupt;
mod model;
mod readers;
mod signal;
mod simulation;
mod time;
mod uff;
mod workflows;

use pyo3::prelude::*;

/// The shape factor of the equivalent coefficients (paper Eq 12/24):
/// `g(mu) = 2 Gamma((3+mu)/2) / (sqrt(pi) Gamma(2+mu/2))`, for `mu > -3`
/// (`g(0) = 1`, `g(2) = 3/4`, `g(-1) = 4/pi`).
///
/// >>> import nlsdof
/// >>> round(nlsdof.g(0.0), 12), nlsdof.g(2.0)
/// (1.0, 0.75)
#[pyfunction]
fn g(mu: f64) -> PyResult<f64> {
    nlsdof::power_law::g(mu).map_err(convert::value_error)
}

#[pymodule]
fn _nlsdof(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(g, m)?)?;
    m.add_class::<model::Model>()?;
    m.add_class::<model::SteadyState>()?;
    m.add_class::<model::Jump>()?;
    m.add_class::<model::Sweep>()?;
    m.add_class::<model::HarmonicSweep>()?;
    m.add_class::<model::RigSweep>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<fit::SteppedSineData>()?;
    m.add_class::<fit::FitResult>()?;
    m.add_function(wrap_pyfunction!(fit::read_stepped_sine, m)?)?;
    m.add_function(wrap_pyfunction!(fit::read_beam_dir, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_class::<signal::Spectrogram>()?;
    m.add_function(wrap_pyfunction!(signal::linear_id, m)?)?;
    m.add_function(wrap_pyfunction!(signal::spectrogram, m)?)?;
    m.add_function(wrap_pyfunction!(signal::compare_spectrograms, m)?)?;
    m.add_function(wrap_pyfunction!(time::decay, m)?)?;
    m.add_function(wrap_pyfunction!(time::fit_time, m)?)?;
    m.add_function(wrap_pyfunction!(inspect::inspect, m)?)?;
    m.add_function(wrap_pyfunction!(uff::read_uff, m)?)?;
    m.add_function(wrap_pyfunction!(uff::write_uff, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_lvm, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_polytec, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_polytec_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(readers::read_mat, m)?)?;
    m.add_function(wrap_pyfunction!(workflows::frf_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(workflows::compare, m)?)?;
    m.add_function(wrap_pyfunction!(workflows::signal, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
