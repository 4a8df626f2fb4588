//! Time-domain identification: free decay (Hilbert backbone, damping
//! curve, averaged power-law fit) and the output-error fit of Eq 32 to a
//! recorded input and output, as `nlsdof decay` and `nlsdof fit-time`.

use crate::arrays::{f64_array, values};
use crate::convert::{to_py, value_error};
use nlsdof::identification::decay::{analyse, DecayOptions};
use nlsdof::identification::time_domain::{
    check_ranges, fit_time_domain, predict_with, InputInterpolation, Prediction, SampleRange,
    TimeFitOptions, TimeRecord,
};
use nlsdof::identification::ModelKind;
use pyo3::prelude::*;
use std::time::Instant;

/// Free-decay identification of the record `x` sampled at `fs` Hz (as
/// `nlsdof decay --json`): Hilbert envelope and instantaneous frequency,
/// the backbone f(a) and the decay rate against amplitude in `bins` bins,
/// the averaged power-law fits of stiffness and damping with 95 %
/// intervals, and the envelope error of the fitted model's free decay.
/// `t_start` (s from the first sample) and `band` (Hz, Hz) default to what
/// the record shows. Returns the document (dict).
///
/// >>> import numpy as np, nlsdof
/// >>> t = np.arange(20000) / 1000.0; wn = 2 * np.pi * 20
/// >>> x = np.exp(-0.01 * wn * t) * np.cos(wn * np.sqrt(1 - 1e-4) * t)  # f_n 20 Hz, zeta 0.01
/// >>> r = nlsdof.decay(x, fs=1000.0)
/// >>> r["adequate"], round(r["damping_fit"]["parameters"][0]["value"], 2)  # delta = 2 zeta omega_n, 1/s
/// (True, 2.52)
#[pyfunction]
#[pyo3(signature = (x, fs, t_start=None, band=None, bins=30))]
pub fn decay<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    fs: f64,
    t_start: Option<f64>,
    band: Option<Vec<f64>>,
    bins: usize,
) -> PyResult<Bound<'py, PyAny>> {
    if bins < 4 {
        return Err(value_error(format!("bins {bins}: give at least 4")));
    }
    let t0 = Instant::now();
    let a = f64_array(x, "x")?;
    let x = values(&a);
    let band = crate::convert::pair(band, "band")?;
    let mut opts = DecayOptions {
        t_start,
        band,
        bins,
        ..DecayOptions::default()
    };
    let t_an = Instant::now();
    // Ctrl-C stops it (KeyboardInterrupt): the analysis polls the flag
    // between FFT blocks, amplitude bins and pieces of the model's decay
    let r = crate::interrupt::run(py, None, "decay", |cancel, _| {
        opts.cancel = cancel;
        analyse(&x, fs, &opts)
    })?
    .map_err(value_error)?;
    let analyse_s = t_an.elapsed().as_secs_f64();
    let rec = nlsdof_report::decay::DecayRecord {
        input: "",
        column: "x",
        fs,
        t0: 0.0,
    };
    let doc = nlsdof_report::decay::decay_json(&rec, &r, analyse_s, t0.elapsed().as_secs_f64());
    let out = to_py(py, &doc)?;
    // beyond the CLI's document: the curves behind it, as numpy arrays
    // (time from the first sample, s; the Hilbert envelope and the fitted
    // model's envelope over the analysed decay, in x's unit)
    let d = out.cast::<pyo3::types::PyDict>()?;
    let t: Vec<f64> = (r.start..r.end).map(|k| k as f64 / fs).collect();
    d.set_item("t", numpy::PyArray1::from_vec(py, t))?;
    d.set_item(
        "envelope",
        numpy::PyArray1::from_vec(py, r.amplitude.clone()),
    )?;
    d.set_item(
        "model_envelope",
        numpy::PyArray1::from_vec(py, r.model_amplitude.clone()),
    )?;
    // the model envelope's first samples are the Hilbert edge transient of
    // its simulation (left out of the figures), and the fitted backbone and
    // damping curves of the CLI's figure
    d.set_item(
        "model_envelope_edge",
        nlsdof_report::decay::model_edge_samples(&r, fs),
    )?;
    let (ca, cf, cr) = nlsdof_report::decay::fitted_curves(&r);
    let curves = pyo3::types::PyDict::new(py);
    curves.set_item("amplitude", numpy::PyArray1::from_vec(py, ca))?;
    curves.set_item("f_hz", numpy::PyArray1::from_vec(py, cf))?;
    curves.set_item("decay_rate", numpy::PyArray1::from_vec(py, cr))?;
    d.set_item("fitted_curves", curves)?;
    crate::document::report(out, "decay")
}

/// Output-error fit of the power-law ODE (Eq 32) to the input `u`
/// (m/s^2) and output `y` (m) sampled at `fs` Hz, on the half-open sample
/// range `fit_range` (default: all), with exact RK4 sensitivities and an
/// equation-error start (as `nlsdof fit-time --json`). Each of `tests`
/// (ranges) is predicted from its first samples. `model`: as `fit`, without
/// coulomb. `input_interpolation` ("cubic", "linear" or "zoh") is the
/// input between samples (part of the model); `substeps` fixes the RK4
/// steps per sample (default: chosen so that the integration error is at
/// most 1 % of the RMS output error; the document's "integration" says
/// which). `fix` holds model parameters at values instead of fitting them
/// (`{"delta": 0.0}`, as `fit-time --fix delta=0`; names alpha ...
/// output_offset). Returns the document (dict): parameters, intervals, RMS
/// errors.
///
/// >>> import numpy as np, nlsdof
/// >>> u = np.random.default_rng(0).standard_normal(1000)
/// >>> y, _ = nlsdof.Model(1.0, (2 * np.pi * 5) ** 2, 2.0).simulate(u, fs=200.0)
/// >>> r = nlsdof.fit_time(u, y, 200.0, model="linear")
/// >>> r["converged"], round(r["parameters"]["alpha"], 1), round(r["parameters"]["delta"], 3)
/// (True, 987.0, 2.0)
#[pyfunction]
#[pyo3(signature = (u, y, fs, model="duffing", fit_range=None, tests=None, starts=1, seed=1, max_iterations=400, input_interpolation="cubic", substeps=None, progress=None, fix=None))]
#[allow(clippy::too_many_arguments)]
pub fn fit_time<'py>(
    py: Python<'py>,
    u: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    fs: f64,
    model: &str,
    fit_range: Option<Vec<usize>>,
    tests: Option<Vec<Vec<usize>>>,
    starts: usize,
    seed: u64,
    max_iterations: usize,
    input_interpolation: &str,
    substeps: Option<usize>,
    progress: Option<&Bound<'py, PyAny>>,
    fix: Option<std::collections::BTreeMap<String, f64>>,
) -> PyResult<Bound<'py, PyAny>> {
    let t0 = Instant::now();
    // as `fit-time --fix NAME=VALUE`
    let mut fixed = Vec::new();
    for (name, v) in fix.unwrap_or_default() {
        let p = nlsdof::identification::time_domain::fixable_parameter(&name).ok_or_else(|| {
            value_error(format!(
                "fix {name:?}: not a parameter of fit_time (alpha, delta, beta, rho, kappa, eta, gain, input_offset, output_offset)"
            ))
        })?;
        fixed.push((p, v));
    }
    let interpolation = InputInterpolation::parse(input_interpolation).ok_or_else(|| {
        value_error(format!(
            "input_interpolation {input_interpolation:?} is not an interpolation: cubic, linear or zoh"
        ))
    })?;
    let kind = ModelKind::parse(model)
        .filter(|k| *k != ModelKind::Coulomb)
        .ok_or_else(|| {
            value_error(format!(
                "model {model:?} is not allowed: linear, duffing, generalised, quadratic, duffing-quadratic, duffing-generalised, generalised-damping or generalised-stiffness (coulomb: the sensitivity equations are singular at v = 0)"
            ))
        })?;
    if starts == 0 || max_iterations == 0 {
        return Err(value_error("starts and max_iterations must be at least 1"));
    }
    let (ua, ya) = (f64_array(u, "u")?, f64_array(y, "y")?);
    let (u, y) = (values(&ua), values(&ya));
    let rec = TimeRecord::new(&u, &y, fs).map_err(value_error)?;
    let range = match crate::convert::pair(fit_range, "fit_range")? {
        Some((a, b)) => SampleRange::new(a, b),
        None => SampleRange::new(0, u.len()),
    };
    let tests: Vec<SampleRange> = tests
        .unwrap_or_default()
        .into_iter()
        .enumerate()
        .map(|(i, t)| {
            let (a, b) =
                crate::convert::pair(Some(t), &format!("tests[{i}]"))?.expect("a pair was given");
            Ok(SampleRange::new(a, b))
        })
        .collect::<PyResult<_>>()?;
    if tests.is_empty() {
        check_ranges(u.len(), range, None).map_err(value_error)?;
    }
    for t in &tests {
        check_ranges(u.len(), range, Some(*t)).map_err(value_error)?;
    }
    let mut opts = TimeFitOptions {
        starts,
        seed,
        interpolation,
        substeps,
        fixed,
        ..TimeFitOptions::default()
    };
    opts.lm.max_iterations = max_iterations;
    opts.lm.max_evaluations = 3 * max_iterations;
    let t_fit = Instant::now();
    // Ctrl-C stops it (KeyboardInterrupt); progress= sees the fit, then
    // each test range's prediction
    let (fit, preds) = crate::interrupt::run(py, progress, kind.name(), |cancel, rep| {
        opts.lm.cancel = cancel;
        rep.stage("output-error fit", 1);
        let fit = fit_time_domain(&rec, range, kind, &opts)?;
        rep.step();
        let tm = fit.model();
        rep.stage("predictions", tests.len());
        let preds = tests
            .iter()
            .map(|t| {
                cancel.check()?;
                let p = predict_with(&rec, *t, &tm, &fit.discretisation);
                rep.step();
                p
            })
            .collect::<Result<Vec<Prediction>, _>>()?;
        Ok::<_, nlsdof::identification::time_domain::TimeFitError>((fit, preds))
    })?
    .map_err(value_error)?;
    let run = nlsdof_report::time_fit::TimeFitRun {
        input: "",
        kind,
        fs,
        samples: u.len(),
        range,
        fit: &fit,
        predictions: &preds,
        fit_s: t_fit.elapsed().as_secs_f64(),
    };
    let out = to_py(
        py,
        &nlsdof_report::time_fit::json(&run, t0.elapsed().as_secs_f64()),
    )?;
    // beyond the CLI's document: the model output over the estimation range
    // and each test range (the CLI's --predict), as numpy arrays
    let d = out.cast::<pyo3::types::PyDict>()?;
    d.get_item("estimation")?
        .map(|e| {
            e.set_item(
                "y_model",
                numpy::PyArray1::from_vec(py, fit.y_model.clone()),
            )
        })
        .transpose()?;
    if let Some(tests) = d.get_item("tests")? {
        for (entry, p) in tests.try_iter()?.zip(&preds) {
            entry?.set_item("y_model", numpy::PyArray1::from_vec(py, p.y_model.clone()))?;
        }
    }
    crate::document::report(out, "fit_time")
}
