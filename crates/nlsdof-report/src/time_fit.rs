//! The time-domain output-error fit (`nlsdof fit-time`, paper Eq 32,
//! [`nlsdof::identification::time_domain`]): parameters at bounds, the
//! convergence warning, the JSON document and the text report.

use nlsdof::identification::time_domain::{
    Prediction, SampleRange, TimeFit, INIT_WINDOW, MAX_EXPONENT, TIME_PARAM_NAMES,
};
use nlsdof::identification::ModelKind;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// One time-domain fit with its validation, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct TimeFitRun<'a> {
    /// The record's file.
    pub input: &'a str,
    pub kind: ModelKind,
    /// Sampling frequency, Hz.
    pub fs: f64,
    /// Samples in the record.
    pub samples: usize,
    /// The estimation range.
    pub range: SampleRange,
    pub fit: &'a TimeFit,
    /// The predictions on the test ranges.
    pub predictions: &'a [Prediction],
    /// Measured fit time, s.
    pub fit_s: f64,
}

/// The free parameters that ended on a bound (their intervals mean
/// nothing): δ or κ at 0, ρ or η at 0 or [`MAX_EXPONENT`].
pub fn at_bounds(fit: &TimeFit) -> Vec<&'static str> {
    fit.free
        .iter()
        .filter(|&&p| {
            let v = fit.theta[p];
            match TIME_PARAM_NAMES[p] {
                "delta" | "kappa" => v == 0.0,
                "rho" | "eta" => v == 0.0 || v == MAX_EXPONENT,
                _ => false,
            }
        })
        .map(|&p| TIME_PARAM_NAMES[p])
        .collect()
}

/// Why the fit is not to be trusted, if it is not: not converged, or
/// J'J singular (no intervals).
pub fn warning(fit: &TimeFit) -> Option<String> {
    let ic = &fit.integration;
    if !fit.termination.converged() {
        Some(format!("the fit did not converge ({})", fit.termination))
    } else if !ic.met {
        Some(format!(
            "the integration error {:.3e} (RMS change when the {} RK4 substeps per sample are doubled) is above {} of the RMS output error {:.3e}: the parameters partly describe the integrator{}",
            ic.integration_error,
            ic.substeps,
            ic.tolerance,
            ic.output_error,
            if ic.automatic { "" } else { "; omit --substeps to choose them automatically" }
        ))
    } else if fit.uncertainty.is_none() {
        Some("J'J is singular at the optimum: a parameter is not identifiable, no intervals".into())
    } else {
        None
    }
}

/// The JSON document of `nlsdof fit-time --json`; `total_s` is the measured
/// run time (s).
pub fn json(run: &TimeFitRun, total_s: f64) -> Value {
    let fit = run.fit;
    let params: serde_json::Map<String, Value> = TIME_PARAM_NAMES
        .iter()
        .zip(fit.theta.iter())
        .map(|(n, v)| (n.to_string(), json!(v)))
        .collect();
    let intervals: Vec<_> = fit
        .uncertainty
        .as_ref()
        .map(|u| {
            (0..u.names.len())
                .map(|k| {
                    json!({"name": u.names[k], "value": u.values[k], "std_error": u.std_errors[k],
                           "lower": u.lower[k], "upper": u.upper[k]})
                })
                .collect()
        })
        .unwrap_or_default();
    json!({
        "input": run.input,
        "model": run.kind.name(),
        "fs_hz": run.fs,
        "samples": run.samples,
        "parameters": params,
        "free": fit.free.iter().map(|&p| TIME_PARAM_NAMES[p]).collect::<Vec<_>>(),
        "intervals_95": intervals,
        "converged": fit.termination.converged(),
        "termination": fit.termination.name(),
        "iterations": fit.iterations,
        "warning": warning(fit),
        "at_bounds": at_bounds(fit),
        "estimation": {
            "range": [run.range.start, run.range.end],
            "rms": fit.rms,
            "start_rms": fit.start_rms,
        },
        "integration": {
            "input_interpolation": fit.discretisation.interpolation.name(),
            "substeps": fit.integration.substeps,
            "step_s": fit.integration.step,
            "automatic": fit.integration.automatic,
            "integration_error": fit.integration.integration_error,
            "output_error": fit.integration.output_error,
            "ratio": fit.integration.integration_error / fit.integration.output_error,
            "tolerance": fit.integration.tolerance,
            "met": fit.integration.met,
            "fits": fit.integration.refits,
        },
        "tests": run.predictions.iter().map(|p| json!({
            "range": [p.range.start, p.range.end],
            "rms": p.rms,
            "score_x1000": 1000.0 * p.rms,
            "init_window": INIT_WINDOW,
            "initial": {"x0": p.initial.x, "v0": p.initial.v},
        })).collect::<Vec<_>>(),
        "fit_s": run.fit_s,
        "total_s": total_s,
    })
}

/// The text report of `nlsdof fit-time`.
pub fn text(run: &TimeFitRun) -> String {
    let (fit, range) = (run.fit, run.range);
    let mut s = String::new();
    if let Some(w) = warning(fit) {
        let _ = writeln!(s, "WARNING: {w}");
    }
    let at_bounds = at_bounds(fit);
    if !at_bounds.is_empty() {
        let _ = writeln!(
            s,
            "note: at a bound (its interval is not meaningful): {}",
            at_bounds.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "fit-time {} on {} samples {}:{} at {} Hz: RMS output error {:.6e} (equation-error start {:.6e}), {} ({} iterations) in {:.2} s",
        run.kind,
        range.len(),
        range.start,
        range.end,
        run.fs,
        fit.rms,
        fit.start_rms,
        fit.termination,
        fit.iterations,
        run.fit_s
    );
    let ic = &fit.integration;
    let _ = writeln!(
        s,
        "  integration: RK4, {} substeps per sample (h = {:.4e} s, {}), {} input; integration error {:.3e} = {:.2} % of the RMS output error ({}; target {} %)",
        ic.substeps,
        ic.step,
        if ic.automatic { "chosen" } else { "fixed" },
        fit.discretisation.interpolation,
        ic.integration_error,
        100.0 * ic.integration_error / ic.output_error,
        if ic.met { "met" } else { "NOT met" },
        100.0 * ic.tolerance
    );
    let _ = writeln!(s, "  parameter        value                 95 % interval");
    for (k, name) in TIME_PARAM_NAMES.iter().enumerate() {
        let free = fit.free.contains(&k);
        let iv = match (free, fit.uncertainty.as_ref()) {
            (true, Some(u)) => {
                let i = u.names.iter().position(|n| n == name).unwrap_or(0);
                format!("[{:.6e}, {:.6e}]", u.lower[i], u.upper[i])
            }
            (true, None) => "-".into(),
            (false, _) => "fixed".into(),
        };
        let _ = writeln!(s, "  {name:<14} {:>22.12e}  {iv}", fit.theta[k]);
    }
    for p in run.predictions {
        let _ = writeln!(
            s,
            "test {}:{}: RMS error of y[{INIT_WINDOW}:] {:.6e} (x1000 = {:.4}); initial state x0 = {:e}, v0 = {:e}",
            p.range.start,
            p.range.end,
            p.rms,
            1000.0 * p.rms,
            p.initial.x,
            p.initial.v
        );
    }
    s
}
