//! The virtual stepped-sine rig (`nlsdof stepped-sine`,
//! [`nlsdof::stepped_sine`]): the integration-error warning, the JSON
//! summary and the text summary of a run (peak per level and sweep).

use crate::steady_state::sweep_name as name;
use nlsdof::stepped_sine::{RigPoint, RigSweep, INTEGRATION_WARNING};
use serde_json::{json, Value};
use std::f64::consts::TAU;
use std::fmt::Write as _;

/// One rig run, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct RigRun<'a> {
    /// Each sweep with the index of its level.
    pub sweeps: &'a [(usize, RigSweep)],
    /// Frequency steps per sweep.
    pub steps: usize,
    /// Measured wall time of the simulation, s.
    pub wall_s: f64,
    /// The output file.
    pub out: &'a str,
}

impl RigRun<'_> {
    fn cycles(&self) -> usize {
        self.sweeps
            .iter()
            .flat_map(|(_, s)| s.points.iter().map(|p| p.cycles))
            .sum()
    }
    fn simulated(&self) -> f64 {
        self.sweeps.iter().map(|(_, s)| s.duration).sum()
    }
}

fn peak(s: &RigSweep) -> Option<&RigPoint> {
    s.points
        .iter()
        .max_by(|p, q| p.amplitude.total_cmp(&q.amplitude))
}

/// The largest estimated integration error over all steps (RK4 with N and
/// 2N steps per cycle, see [`nlsdof::stepped_sine`]), relative to the
/// amplitude, and a warning naming where it occurred when it exceeds
/// [`INTEGRATION_WARNING`]; `samples_per_cycle` is the N of the run.
pub fn integration_error(
    sweeps: &[(usize, RigSweep)],
    samples_per_cycle: usize,
) -> (f64, Option<String>) {
    let worst = sweeps
        .iter()
        .flat_map(|(_, s)| s.points.iter())
        .max_by(|p, q| p.integration_error.total_cmp(&q.integration_error));
    let error = worst.map_or(0.0, |p| p.integration_error);
    let warning = (error > INTEGRATION_WARNING).then(|| {
        format!(
            "the estimated integration error reaches {:.2e} of the amplitude (at {:.4} Hz): raise --samples-per-cycle (now {}; the error falls as its 4th power)",
            error,
            worst.map_or(0.0, |p| p.omega / TAU),
            samples_per_cycle
        )
    });
    (error, warning)
}

/// The JSON summary of `nlsdof stepped-sine --json`; `integration` is
/// [`integration_error`]'s result and `total_s` the measured run time (s).
pub fn json(run: &RigRun, integration: (f64, Option<String>), total_s: f64) -> Value {
    let levels: Vec<_> = run
        .sweeps
        .iter()
        .map(|(k, s)| {
            json!({
                "level": k + 1,
                "gamma": s.gamma,
                "sweep": name(s.direction),
                "peak": peak(s).map(|p| json!({"f_hz": p.omega / TAU, "amplitude": p.amplitude, "phase_deg": p.phase.to_degrees()})),
                "unsettled": s.points.iter().filter(|p| !p.settled).count(),
                "simulated_s": s.duration,
            })
        })
        .collect();
    json!({"out": run.out, "levels": levels, "steps": run.steps, "cycles": run.cycles(),
           "simulated_s": run.simulated(), "wall_s": run.wall_s, "total_s": total_s,
           "integration_error": {"estimate": integration.0, "warning": integration.1}})
}

/// The text summary of `nlsdof stepped-sine`.
pub fn text(run: &RigRun) -> String {
    let mut s = String::new();
    for (k, sw) in run.sweeps {
        if let Some(p) = peak(sw) {
            let _ = writeln!(
                s,
                "level {} (gamma {} m/s^2, sweep {}): peak {:.6e} m at {:.4} Hz, phase {:.2} deg",
                k + 1,
                sw.gamma,
                name(sw.direction),
                p.amplitude,
                p.omega / TAU,
                p.phase.to_degrees()
            );
        }
    }
    let _ = writeln!(
        s,
        "{} sweep(s) x {} steps: {} cycles = {:.1} s of simulated time in {:.3} s; wrote {}",
        run.sweeps.len(),
        run.steps,
        run.cycles(),
        run.simulated(),
        run.wall_s,
        run.out
    );
    s
}
