//! Steady states and stepped-sine sweeps of first-order harmonic balance
//! (`nlsdof roots`, `nlsdof frf`; paper Eq 12–30): JSON, CSV and text.
//! Amplitudes are zero-to-peak in m, levels γ zero-to-peak in m/s²,
//! frequencies in Hz, phases in degrees of lag of x behind the input.

use nlsdof::{Formulation, LevelResponse, Model, NoMotion, RootSet, SweepDirection};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

fn hz(omega: f64) -> f64 {
    omega / (2.0 * PI)
}

/// The short name of a formulation, as `--formulation` spells it.
pub fn formulation_name(f: Formulation) -> &'static str {
    match f {
        Formulation::HarmonicBalance => "hb",
        Formulation::Modulation => "modulation",
    }
}

/// One line on what a formulation is.
pub fn formulation_description(f: Formulation) -> &'static str {
    match f {
        Formulation::HarmonicBalance => "exact first-order harmonic balance",
        Formulation::Modulation => "near-resonance form, paper Eq 30",
    }
}

/// `"up"` or `"down"`.
pub fn sweep_name(d: SweepDirection) -> &'static str {
    d.name()
}

/// What a sweep was asked for, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct SweepRequest<'a> {
    /// The model's name (its file).
    pub model_name: &'a str,
    pub direction: SweepDirection,
    pub formulation: Formulation,
    pub steps: usize,
    /// Band, Hz.
    pub f_min: f64,
    pub f_max: f64,
    /// The data file whose levels, frequencies and sweep directions were
    /// swept (`nlsdof frf --at`), instead of one grid and direction.
    pub at: Option<&'a str>,
}

/// Six significant digits, without trailing zeros.
fn round6(v: f64) -> String {
    let s = format!("{v:.5e}");
    s.parse::<f64>().map(crate::num).unwrap_or(s)
}

/// The JSON document of `nlsdof roots --json`: every steady state at one
/// level `gamma` (m/s²) and frequency `f_hz`, or why there is no motion.
pub fn roots_json(
    model_name: &str,
    model: &Model,
    f_hz: f64,
    gamma: f64,
    formulation: Formulation,
    set: &RootSet,
) -> Value {
    let roots: Vec<_> = set
        .roots
        .iter()
        .map(|r| json!({"amplitude": r.amplitude, "phase_deg": r.phase.to_degrees(), "stable": r.stable}))
        .collect();
    let mut out = json!({
        "model": model_name,
        "f_hz": f_hz,
        "gamma": gamma,
        "formulation": formulation_name(formulation),
        "roots": roots,
        "no_motion": Value::Null,
    });
    match set.no_motion {
        None => {}
        Some(NoMotion::Sticking {
            friction_accel,
            input_accel,
        }) => {
            out["no_motion"] = json!("sticking");
            out["friction_accel"] = json!(friction_accel);
            out["input_accel"] = json!(input_accel);
            out["friction_force_n"] = json!(friction_accel * model.mass);
            out["input_force_n"] = json!(input_accel * model.mass);
        }
        Some(NoMotion::NoRoot) => out["no_motion"] = json!("no_root"),
        Some(NoMotion::Unbounded) => out["no_motion"] = json!("unbounded"),
    }
    out
}

/// The text report of `nlsdof roots`.
pub fn roots_text(
    model_name: &str,
    model: &Model,
    f_hz: f64,
    gamma: f64,
    formulation: Formulation,
    set: &RootSet,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model {model_name}: {}", model_summary(model));
    let _ = writeln!(
        s,
        "gamma = {} m/s^2 zero-to-peak, f = {} Hz, formulation: {} ({})",
        crate::num(gamma),
        crate::num(f_hz),
        formulation_name(formulation),
        formulation_description(formulation)
    );
    match set.no_motion {
        Some(NoMotion::Sticking {
            friction_accel,
            input_accel,
        }) => {
            let _ = writeln!(s, "no steady motion: the mass sticks");
            let _ = writeln!(
                s,
                "Coulomb friction sticks: 4 c_f/pi = {} N >= m gamma = {} N",
                round6(friction_accel * model.mass),
                round6(input_accel * model.mass)
            );
        }
        Some(NoMotion::NoRoot) => {
            let _ = writeln!(
                s,
                "no steady motion: the harmonic-balance equation has no positive root"
            );
        }
        Some(NoMotion::Unbounded) => {
            let _ = writeln!(s, "no finite steady state: nothing balances the input at any amplitude, so the response grows without bound (no damping at resonance)");
        }
        None => {
            let n = set.roots.len();
            let _ = writeln!(s, "{n} steady state{}:", if n == 1 { "" } else { "s" });
            let _ = writeln!(
                s,
                "  {:>2}  {:>14}  {:>15}  stability",
                "#", "amplitude [m]", "phase lag [deg]"
            );
            for (i, r) in set.roots.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "  {:>2}  {:>14.6e}  {:>15.4}  {}",
                    i + 1,
                    r.amplitude,
                    r.phase.to_degrees(),
                    if r.stable { "stable" } else { "unstable" }
                );
            }
        }
    }
    s
}

/// Linear natural frequency (Hz) and damping ratio, for report headers.
pub fn model_summary(model: &Model) -> String {
    format!(
        "f_n = {:.6} Hz, zeta = {:.6} (linear part)",
        model.omega_n() / (2.0 * PI),
        model.zeta()
    )
}

/// The summary lines of a sweep's jumps (shared by the first-order and
/// multi-harmonic `frf` text output).
pub fn jumps_text(s: &mut String, jumps: &[nlsdof::Jump]) {
    if jumps.is_empty() {
        let _ = writeln!(s, "  jumps              none");
    }
    for j in jumps {
        let _ = writeln!(
            s,
            "  jump               at {:.6} Hz: {:.6e} m -> {:.6e} m ({})",
            hz(j.omega),
            j.amplitude_before,
            j.amplitude_after,
            if j.amplitude_after > j.amplitude_before {
                "up"
            } else {
                "down"
            }
        );
    }
}

/// The JSON document of `nlsdof frf --json` (first order: the harmonics
/// list holds orders 0 and 1 only).
pub fn sweep_json(req: &SweepRequest, model: &Model, levels: &[LevelResponse]) -> Value {
    let lv: Vec<_> = levels
        .iter()
        .map(|l| {
            let points: Vec<_> = l
                .sweep
                .points
                .iter()
                .map(|p| {
                    // no finite steady state: no amplitude, no phase
                    let num = |v: f64| (!p.unbounded).then_some(v);
                    json!({
                        "f_hz": hz(p.omega),
                        "amplitude": num(p.amplitude),
                        "phase_deg": num(p.phase.to_degrees()),
                        "stable": p.stable,
                        "sticking": p.sticking,
                        "unbounded": p.unbounded,
                        // first order: x = a cos(Ωt − φ), no other harmonic
                        "harmonics": [
                            {"order": 0, "amplitude": num(0.0), "phase_deg": num(0.0)},
                            {"order": 1, "amplitude": num(p.amplitude), "phase_deg": num(p.phase.to_degrees())},
                        ],
                        "max_abs_x": num(p.amplitude),
                    })
                })
                .collect();
            let jumps: Vec<_> = l
                .sweep
                .jumps
                .iter()
                .map(|j| {
                    json!({
                        "f_hz": hz(j.omega),
                        "amplitude_before": j.amplitude_before,
                        "amplitude_after": j.amplitude_after,
                    })
                })
                .collect();
            let folds: Vec<f64> = l.sweep.folds.iter().map(|f| hz(f.omega)).collect();
            let fold_amps: Vec<f64> = l.sweep.folds.iter().map(|f| f.amplitude).collect();
            json!({
                "gamma": l.gamma,
                "sweep": sweep_name(l.sweep.direction),
                "points": points,
                "jumps": jumps,
                "folds_hz": folds,
                "fold_amplitudes": fold_amps,
                "phase_quadrature": l.phase_quadrature.map(|q| json!({"f_hz": hz(q.omega), "amplitude": q.amplitude})),
            })
        })
        .collect();
    json!({
        "model": req.model_name,
        "f_n_hz": hz(model.omega_n()),
        "zeta": model.zeta(),
        "formulation": formulation_name(req.formulation),
        "harmonics": 1,
        "units": {"gamma": "m/s^2 zero-to-peak", "amplitude": "m zero-to-peak", "f_hz": "Hz", "phase_deg": "deg lag of x behind input"},
        "levels": lv,
    })
}

/// CSV rows; the first five columns are the contract, `sweep` matches the
/// stepped-sine data format read by the fitting commands, `stable` and
/// `sticking` flag each point. A sticking point (no steady motion) has
/// amplitude 0 and an empty phase (there is no phase to report); a point
/// without a finite steady state (undamped resonance) has both empty.
pub fn sweep_csv(levels: &[LevelResponse]) -> String {
    let mut s = String::from("level,gamma,f_hz,amplitude,phase_deg,sweep,stable,sticking\n");
    for (i, l) in levels.iter().enumerate() {
        let sweep = sweep_name(l.sweep.direction);
        for p in &l.sweep.points {
            let phase = if p.sticking || p.unbounded {
                String::new()
            } else {
                format!("{}", p.phase.to_degrees())
            };
            let amplitude = if p.unbounded {
                String::new()
            } else {
                format!("{}", p.amplitude)
            };
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{}",
                i + 1,
                l.gamma,
                hz(p.omega),
                amplitude,
                phase,
                sweep,
                p.stable,
                p.sticking
            );
        }
    }
    s
}

/// The text report of `nlsdof frf`: per level the swept peak, sticking and
/// unbounded steps, jumps, folds and the phase-quadrature point.
pub fn sweep_text(req: &SweepRequest, model: &Model, levels: &[LevelResponse]) -> String {
    let (f_min, f_max) = (req.f_min, req.f_max);
    let mut s = String::new();
    let _ = writeln!(s, "model {}: {}", req.model_name, model_summary(model));
    match req.at {
        None => {
            let _ = writeln!(
                s,
                "stepped-sine sweep {}, {} .. {} Hz, {} steps; formulation {} ({})",
                sweep_name(req.direction),
                f_min,
                f_max,
                req.steps,
                formulation_name(req.formulation),
                formulation_description(req.formulation)
            );
        }
        Some(data) => {
            let _ = writeln!(
                s,
                "stepped-sine sweeps at the levels, frequencies and sweep directions of {data} ({f_min} .. {f_max} Hz), each starting on the state nearest its measured first amplitude; formulation {} ({})",
                formulation_name(req.formulation),
                formulation_description(req.formulation)
            );
        }
    }
    let _ = writeln!(
        s,
        "amplitudes zero-to-peak in m; phase = lag of x behind the input, deg"
    );
    for (i, l) in levels.iter().enumerate() {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "level {}: gamma = {} m/s^2 zero-to-peak ({} m/s^2 peak-to-peak){}",
            i + 1,
            l.gamma,
            2.0 * l.gamma,
            if req.at.is_some() {
                format!(", sweep {}", sweep_name(l.sweep.direction))
            } else {
                String::new()
            }
        );
        let peak = l
            .sweep
            .points
            .iter()
            .filter(|p| !p.sticking && !p.unbounded)
            .max_by(|a, b| a.amplitude.total_cmp(&b.amplitude));
        match peak {
            Some(p) => {
                let _ = writeln!(
                    s,
                    "  peak (swept)       {:.6e} m at {:.6} Hz, phase lag {:.2} deg",
                    p.amplitude,
                    hz(p.omega),
                    p.phase.to_degrees()
                );
            }
            None => {
                let _ = writeln!(s, "  peak (swept)       none: no motion at any step");
            }
        }
        let sticking = l.sweep.points.iter().filter(|p| p.sticking).count();
        if let Some(first) = l.sweep.points.iter().find(|p| p.sticking) {
            let why = match l
                .response
                .steady_states(first.omega)
                .ok()
                .and_then(|r| r.no_motion)
            {
                Some(NoMotion::Sticking { .. }) => "Coulomb friction sticks",
                _ => "no steady-state root",
            };
            let _ = writeln!(
                s,
                "  no motion          at {} of {} steps ({why})",
                sticking,
                l.sweep.points.len()
            );
        }
        let unbounded = l.sweep.points.iter().filter(|p| p.unbounded).count();
        if let Some(first) = l.sweep.points.iter().find(|p| p.unbounded) {
            let _ = writeln!(
                s,
                "  no finite state    at {unbounded} of {} steps (first {:.6} Hz): the response grows without bound (no damping at resonance)",
                l.sweep.points.len(),
                hz(first.omega)
            );
        }
        let unstable = l
            .sweep
            .points
            .iter()
            .filter(|p| !p.sticking && !p.unbounded && !p.stable)
            .count();
        if unstable > 0 {
            let _ = writeln!(
                s,
                "  no stable state    at {unstable} steps (followed state unstable)"
            );
        }
        jumps_text(&mut s, &l.sweep.jumps);
        if l.sweep.folds.is_empty() {
            let _ = writeln!(s, "  folds              none in the band");
        }
        for f in &l.sweep.folds {
            let _ = writeln!(
                s,
                "  fold               at {:.6} Hz, amplitude {:.6e} m",
                hz(f.omega),
                f.amplitude
            );
        }
        match l.phase_quadrature {
            Some(q) => {
                let _ = writeln!(
                    s,
                    "  phase quadrature   {:.6} Hz, amplitude {:.6e} m{}",
                    hz(q.omega),
                    q.amplitude,
                    if hz(q.omega) < f_min || hz(q.omega) > f_max {
                        " (outside the band)"
                    } else {
                        ""
                    }
                );
            }
            None => {
                let _ = writeln!(s, "  phase quadrature   none");
            }
        }
    }
    s
}
