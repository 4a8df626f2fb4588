//! `nlsdof.inspect`: what stepped-sine data say before any fit, the
//! document of `nlsdof inspect --json` (issue 29).

use crate::convert::{to_py, value_error};
use crate::fit::dataset;
use nlsdof::identification::inspect::{inspect as inspect_data, InspectOptions, PhaseUse};
use pyo3::prelude::*;

/// Model-free characterisation of stepped-sine data (the CLI's `nlsdof
/// inspect --json`, same keys and numbers): per level the resonance, the 90°
/// point, the damping and the jumps; the homogeneity of the levels against
/// their noise; the stiffness law `Ω_r² − ω_0² = g(ρ) β a_r^ρ` and the damping
/// law `δ_eq − δ_0 = g(η) κ (Ω_r a_r)^η` read from the resonance points, with
/// 95 % intervals; and the model to fit (`headline`, `recommendation`).
///
/// `data`: a `SteppedSineData` (e.g. from `read_beam_dir`) or anything
/// `fit` takes. `phase`: "auto" (detect the convention, the default) or
/// "ignore". `min_jump_ratio`: the smallest step-to-step amplitude ratio
/// read as a jump (> 1, default 1.2, as the CLI). SI units (m, m/s², Hz and
/// rad/s side by side). Raises ValueError on data it cannot inspect.
///
/// >>> import nlsdof  # doctest: +SKIP
/// >>> r = nlsdof.inspect(nlsdof.read_beam_dir("cc_beam_no_magnet_24C"))  # doctest: +SKIP
/// >>> r["headline"]  # doctest: +SKIP
#[pyfunction]
#[pyo3(signature = (data, phase="auto", min_jump_ratio=1.2))]
pub fn inspect<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    phase: &str,
    min_jump_ratio: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let (data, source) = dataset(data)?;
    let phase = match phase {
        "auto" => PhaseUse::Auto,
        "ignore" => PhaseUse::Ignore,
        other => {
            return Err(value_error(format!(
                "phase = '{other}': expected 'auto' or 'ignore'"
            )))
        }
    };
    let opts = InspectOptions {
        phase,
        min_jump_ratio,
    };
    let t = std::time::Instant::now();
    let r = py
        .detach(|| inspect_data(&data, &opts))
        .map_err(value_error)?;
    let doc = nlsdof_report::inspect::inspect_json(
        source.as_deref().unwrap_or("data"),
        &r,
        t.elapsed().as_secs_f64(),
    )
    .map_err(value_error)?;
    crate::document::report(to_py(py, &doc)?, "inspect")
}
