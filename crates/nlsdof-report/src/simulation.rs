//! Time simulation of a recorded input (`nlsdof simulate`,
//! [`nlsdof::simulation`]): the JSON document and the one-line text
//! summary (samples, steps, integration-error estimate, max |x| in m).

use nlsdof::simulation::Summary;
use serde_json::{json, Value};

/// One simulation run, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct SimulationRun<'a> {
    /// The input record and the output file.
    pub input: &'a str,
    pub out: &'a str,
    pub summary: &'a Summary,
    /// Rows written.
    pub outputs: usize,
    /// Sampling frequency (Hz) of a uniformly sampled input.
    pub fs: Option<f64>,
    /// `"rk4"` or `"dopri"`.
    pub method: &'static str,
    /// Input samples per integration step (0.5: two RK4 steps per sample).
    pub samples_per_step: f64,
    /// How the input is taken between samples: `"cubic"`, `"linear"`,
    /// `"samples"`.
    pub interpolation: &'static str,
    /// Estimated integration error relative to max |x|, the samples it was
    /// checked on, and whether it is above the warning level.
    pub integration_error: Option<(f64, usize, bool)>,
    /// max |x|, m.
    pub max_abs_x: f64,
    /// Measured time to simulate and write, s.
    pub elapsed_s: f64,
}

/// `samples_per_step` as an integer when it is one (as the JSON always had).
fn per_step(v: f64) -> Value {
    if v.fract() == 0.0 && (0.0..1e15).contains(&v) {
        json!(v as u64)
    } else {
        json!(v)
    }
}

/// The JSON document of `nlsdof simulate --json`; `total_s` is the measured
/// run time (s).
pub fn json(run: &SimulationRun, total_s: f64) -> Value {
    let summary = run.summary;
    json!({
        "input": run.input,
        "out": run.out,
        "samples": summary.samples,
        "outputs": run.outputs,
        "sampling": match run.fs {
            Some(fs) => json!({"uniform": true, "fs_hz": fs}),
            None => json!({"uniform": false}),
        },
        "method": run.method,
        "samples_per_step": per_step(run.samples_per_step),
        "input_interpolation": run.interpolation,
        "integration_error": run.integration_error.map(|(e, n, warn)| json!({
            "estimate": e,
            "relative_to": "max |x|",
            "reference": "step doubling on the whole record: RK4, h = 1/(4 fs), cubic input, the difference scaled by 2^p/(2^p - 1) for the order p of the law (the error against the exact response to the input taken as cubic between samples)",
            "samples_checked": n,
            "warning": warn,
        })),
        "steps": summary.steps,
        "rejected_steps": summary.rejected_steps,
        "rhs_evaluations": summary.rhs_evaluations,
        "friction_events": summary.events,
        "final": {"t": summary.final_time, "x": summary.final_state.x, "v": summary.final_state.v},
        "max_abs_x": run.max_abs_x,
        "simulate_and_write_s": run.elapsed_s,
        "total_s": total_s,
    })
}

/// The one-line text summary of `nlsdof simulate`.
pub fn text(run: &SimulationRun) -> String {
    let summary = run.summary;
    let sps = if summary.samples_per_step > 0 {
        format!(
            ", {} sample(s)/step, {} input",
            per_step(run.samples_per_step),
            run.interpolation
        )
    } else {
        String::new()
    };
    let err = match run.integration_error {
        Some((e, _, _)) => format!("; estimated integration error {e:.1e} of max |x|"),
        None => String::new(),
    };
    format!(
        "simulated {} samples ({}{sps}, {} steps, {} RHS evaluations{}) in {:.3} s; max |x| = {:.6e} m{err}; wrote {} rows to {}\n",
        summary.samples,
        run.method,
        summary.steps,
        summary.rhs_evaluations,
        if summary.events > 0 {
            format!(", {} stick/slip events", summary.events)
        } else {
            String::new()
        },
        run.elapsed_s,
        run.max_abs_x,
        run.outputs,
        run.out
    )
}
