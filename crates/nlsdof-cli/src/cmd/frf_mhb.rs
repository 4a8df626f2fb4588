//! `nlsdof frf --harmonics H` (H ≥ 2): the stepped-sine curves by
//! multi-harmonic balance (constant and even harmonics included) with
//! pseudo-arclength continuation and Hill stability
//! ([`nlsdof::multi_harmonic`]). Output formats extend those of `frf`:
//! every point carries its harmonics and `max_abs_x`.

use super::roots::jumps_text;
use crate::error::CliError;
use nlsdof::multi_harmonic::{
    harmonic_amplitude, harmonic_phase, level_sweeps, max_abs_displacement, LevelSweep,
    MAX_HARMONICS,
};
use nlsdof::{Model, SweepDirection};
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style};
use serde_json::json;
use std::f64::consts::PI;
use std::fmt::Write as _;

/// Largest `--harmonics` accepted on the command line.
pub const CLI_MAX_HARMONICS: usize = if MAX_HARMONICS < 64 {
    MAX_HARMONICS
} else {
    64
};

/// Refuses a model without any damping: its forced response has no steady
/// state at resonance (the amplitude is unbounded) and every periodic
/// solution is only neutrally stable, so neither continuation nor Hill's
/// method has a defined answer.
pub fn check_damped(model: &Model, flag: &str) -> Result<(), CliError> {
    let c_e = model
        .nonlinear_damping
        .map(|d| d.coefficient)
        .unwrap_or(0.0);
    if model.damping == 0.0 && c_e == 0.0 {
        return Err(CliError::Usage(format!(
            "{flag}: the model has no damping (c = 0 and no c_e term): at resonance there is no forced steady state and every periodic solution is only neutrally stable; give c > 0 or a damping term"
        )));
    }
    Ok(())
}

/// What `frf --harmonics H` was asked for (the parsed `frf` arguments).
pub struct Request<'a> {
    /// The model file, as named.
    pub model: &'a std::path::Path,
    pub sweep: SweepDirection,
    pub steps: usize,
    pub harmonics: usize,
    pub json: bool,
    pub csv: bool,
    pub plot: Option<&'a std::path::Path>,
}

fn sweep_name(d: SweepDirection) -> &'static str {
    match d {
        SweepDirection::Up => "up",
        SweepDirection::Down => "down",
    }
}

/// Checks `--harmonics`.
pub fn check_harmonics(h: usize) -> Result<usize, CliError> {
    if h == 0 || h > CLI_MAX_HARMONICS {
        return Err(CliError::Usage(format!(
            "--harmonics {h} is not allowed: need an integer from 1 (exact first-order balance) to {CLI_MAX_HARMONICS}"
        )));
    }
    Ok(h)
}

fn hz(omega: f64) -> f64 {
    omega / (2.0 * PI)
}

fn harmonics_json(q: &[f64]) -> Vec<serde_json::Value> {
    let h = (q.len() - 1) / 2;
    (0..=h)
        .map(|k| {
            json!({
                "order": k,
                "amplitude": harmonic_amplitude(q, k),
                "phase_deg": harmonic_phase(q, k).to_degrees(),
            })
        })
        .collect()
}

/// Higher-harmonic content `√(Σ_{k≠1} A_k²) / A₁`.
fn distortion(q: &[f64]) -> f64 {
    let h = (q.len() - 1) / 2;
    let a1 = harmonic_amplitude(q, 1);
    let s: f64 = (0..=h)
        .filter(|&k| k != 1)
        .map(|k| harmonic_amplitude(q, k).powi(2))
        .sum();
    s.sqrt() / a1
}

pub fn run(
    args: &Request,
    model: &Model,
    gammas: &[f64],
    omegas: &[f64],
    f_min: f64,
    f_max: f64,
) -> Result<(), CliError> {
    let h = args.harmonics;
    check_damped(model, "--harmonics")?;
    let levels = level_sweeps(model, gammas, omegas, args.sweep, h)?;
    for (i, l) in levels.iter().enumerate() {
        if let Some(w) = &l.sweep.warning {
            eprintln!(
                "nlsdof: warning: level {} (gamma = {}): continuation stopped early, partial curve up to {:.6} Hz: {w}",
                i + 1,
                l.gamma,
                l.sweep.points.last().map(|p| hz(p.omega)).unwrap_or(f64::NAN)
            );
        }
    }
    let mut text = if args.json {
        json_output(args, model, &levels)
    } else if args.csv {
        csv_output(args, &levels)
    } else {
        text_output(args, model, &levels, f_min, f_max)
    };
    if let Some(path) = args.plot {
        let title = format!(
            "{} - harmonic balance, H = {h}, sweep {}",
            args.model
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            sweep_name(args.sweep)
        );
        let svg = render(&title, &levels, f_min, f_max)?;
        nlsdof_io::atomic::write_atomic(path, svg.as_bytes())?;
        if !args.json && !args.csv {
            let _ = writeln!(text, "\nplot written to {}", path.display());
        }
    }
    print!("{text}");
    Ok(())
}

fn json_output(args: &Request, model: &Model, levels: &[LevelSweep]) -> String {
    let lv: Vec<_> = levels
        .iter()
        .map(|l| {
            let points: Vec<_> = l
                .sweep
                .points
                .iter()
                .map(|p| {
                    let q = &p.coefficients;
                    json!({
                        "f_hz": hz(p.omega),
                        "amplitude": harmonic_amplitude(q, 1),
                        "phase_deg": harmonic_phase(q, 1).to_degrees(),
                        "stable": p.stable,
                        "sticking": false,
                        "max_abs_x": max_abs_displacement(q),
                        "harmonics": harmonics_json(q),
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
            json!({
                "gamma": l.gamma,
                "sweep": sweep_name(args.sweep),
                "points": points,
                "jumps": jumps,
                "folds_hz": l.sweep.folds.iter().map(|f| hz(f.0)).collect::<Vec<_>>(),
                "fold_amplitudes": l.sweep.folds.iter().map(|f| f.1).collect::<Vec<_>>(),
                "samples_per_period": l.sweep.samples,
                "regularisation_check": l.regularisation.map(|(w, c)| json!({"f_hz": hz(w), "relative_change_eps_over_4": c})),
                "warning": l.sweep.warning.as_ref().map(|w| w.to_string()),
            })
        })
        .collect();
    let out = json!({
        "model": args.model.display().to_string(),
        "f_n_hz": hz(model.omega_n()),
        "zeta": model.zeta(),
        "formulation": "hb",
        "harmonics": args.harmonics,
        "units": {"gamma": "m/s^2 zero-to-peak", "amplitude": "m zero-to-peak (first harmonic)", "f_hz": "Hz", "phase_deg": "deg lag of the harmonic behind the input (harmonic k: A_k cos(k Omega t - phi_k))", "max_abs_x": "m"},
        "levels": lv,
    });
    format!("{out}\n")
}

fn csv_output(args: &Request, levels: &[LevelSweep]) -> String {
    let h = args.harmonics;
    let mut s =
        String::from("level,gamma,f_hz,amplitude,phase_deg,sweep,stable,sticking,max_abs_x");
    for k in 0..=h {
        let _ = write!(s, ",a{k}");
    }
    s.push('\n');
    for (i, l) in levels.iter().enumerate() {
        for p in &l.sweep.points {
            let q = &p.coefficients;
            let _ = write!(
                s,
                "{},{},{},{},{},{},{},false,{}",
                i + 1,
                l.gamma,
                hz(p.omega),
                harmonic_amplitude(q, 1),
                harmonic_phase(q, 1).to_degrees(),
                sweep_name(args.sweep),
                p.stable,
                max_abs_displacement(q)
            );
            for k in 0..=h {
                let _ = write!(s, ",{}", harmonic_amplitude(q, k));
            }
            s.push('\n');
        }
    }
    s
}

fn text_output(
    args: &Request,
    model: &Model,
    levels: &[LevelSweep],
    f_min: f64,
    f_max: f64,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model {}: {}",
        args.model.display(),
        super::roots::model_summary(model)
    );
    let _ = writeln!(
        s,
        "stepped-sine sweep {}, {} .. {} Hz, {} steps; harmonic balance with H = {} harmonics (constant and even terms included), pseudo-arclength continuation, Hill stability",
        sweep_name(args.sweep),
        f_min,
        f_max,
        args.steps,
        args.harmonics
    );
    let _ = writeln!(
        s,
        "amplitudes zero-to-peak in m (first harmonic unless stated); phase = lag of x behind the input, deg"
    );
    for (i, l) in levels.iter().enumerate() {
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "level {}: gamma = {} m/s^2 zero-to-peak ({} m/s^2 peak-to-peak), {} samples per period",
            i + 1,
            l.gamma,
            2.0 * l.gamma,
            l.sweep.samples
        );
        if let Some(p) = l.sweep.points.iter().max_by(|a, b| {
            harmonic_amplitude(&a.coefficients, 1)
                .total_cmp(&harmonic_amplitude(&b.coefficients, 1))
        }) {
            let q = &p.coefficients;
            let _ = writeln!(
                s,
                "  peak (swept)       {:.6e} m at {:.6} Hz, phase lag {:.2} deg, max|x| {:.6e} m",
                harmonic_amplitude(q, 1),
                hz(p.omega),
                harmonic_phase(q, 1).to_degrees(),
                max_abs_displacement(q)
            );
        }
        if let Some(p) = l
            .sweep
            .points
            .iter()
            .max_by(|a, b| distortion(&a.coefficients).total_cmp(&distortion(&b.coefficients)))
        {
            let q = &p.coefficients;
            let k_max = (0..=args.harmonics)
                .filter(|&k| k != 1)
                .max_by(|&a, &b| harmonic_amplitude(q, a).total_cmp(&harmonic_amplitude(q, b)))
                .unwrap_or(0);
            let _ = writeln!(
                s,
                "  harmonic content   largest at {:.6} Hz: sqrt(sum A_k^2, k != 1)/A_1 = {:.3e}, mostly harmonic {k_max} ({:.3e} m)",
                hz(p.omega),
                distortion(q),
                harmonic_amplitude(q, k_max)
            );
        }
        let unstable = l.sweep.points.iter().filter(|p| !p.stable).count();
        if unstable > 0 {
            let _ = writeln!(
                s,
                "  no stable state    at {unstable} steps (followed state unstable)"
            );
        }
        jumps_text(&mut s, &l.sweep.jumps);
        if l.sweep.folds.is_empty() {
            let _ = writeln!(s, "  folds              none on the branch");
        }
        for f in &l.sweep.folds {
            let _ = writeln!(
                s,
                "  fold               at {:.6} Hz, amplitude {:.6e} m",
                hz(f.0),
                f.1
            );
        }
        if let Some((w, c)) = l.regularisation {
            let f = hz(w);
            let _ = writeln!(
                s,
                "  regularisation     friction/negative exponent smoothed; at the peak ({f:.6} Hz) eps -> eps/4 changes A_1 by {c:.2e} (relative)"
            );
        }
        if let Some(w) = &l.sweep.warning {
            let _ = writeln!(s, "  warning            partial curve: {w}");
        }
    }
    s
}

/// Two panels: first-harmonic amplitude (branch line, swept markers,
/// dashed max|x|) and the harmonic content `A_k / A₁` (log scale) of the
/// swept points.
fn render(title: &str, levels: &[LevelSweep], f_min: f64, f_max: f64) -> Result<String, CliError> {
    let mut a_max: f64 = 0.0;
    for l in levels {
        for p in &l.sweep.branch {
            a_max = a_max.max(p.amplitude(1));
        }
        for p in &l.sweep.points {
            a_max = a_max.max(max_abs_displacement(&p.coefficients));
        }
    }
    if !(a_max > 0.0 && a_max.is_finite()) {
        a_max = 1e-3;
    }
    let (unit, scale) = if a_max < 1e-3 {
        ("µm", 1e6)
    } else {
        ("mm", 1e3)
    };
    let mut amp = Panel::new(
        "First harmonic",
        "Frequency f [Hz]",
        &format!("First harmonic A1 [{unit}]; dashed: max|x|"),
    );
    amp.x_range = Some((f_min, f_max));
    amp.y_range = Some((0.0, a_max * 1.08 * scale));
    amp.legend = Corner::Outside;
    for (i, l) in levels.iter().enumerate() {
        let c = colour(i);
        let branch = l
            .sweep
            .branch
            .iter()
            .filter(|p| hz(p.omega) >= f_min && hz(p.omega) <= f_max)
            .map(|p| (hz(p.omega), p.amplitude(1) * scale))
            .collect();
        amp.series
            .push(Series::new(branch, c, Style::Line(2)).label(format!("γ = {}", l.gamma)));
        let max_x = l
            .sweep
            .points
            .iter()
            .map(|p| (hz(p.omega), max_abs_displacement(&p.coefficients) * scale))
            .collect();
        amp.series
            .push(Series::new(max_x, c, Style::DashPattern(1, 5, 4)));
        let step = l.sweep.points.len().div_ceil(100).max(1);
        let marks = |stable: bool| {
            l.sweep
                .points
                .iter()
                .step_by(step)
                .filter(|p| p.stable == stable)
                .map(|p| (hz(p.omega), harmonic_amplitude(&p.coefficients, 1) * scale))
                .collect::<Vec<_>>()
        };
        amp.series
            .push(Series::new(marks(true), c, Style::Filled(2)));
        amp.series
            .push(Series::new(marks(false), c, Style::Dots(3)));
    }
    // harmonic content A_k / A_1
    let h = levels
        .first()
        .and_then(|l| l.sweep.points.first())
        .map(|p| (p.coefficients.len() - 1) / 2)
        .unwrap_or(1);
    let mut lo: f64 = -1.0;
    let mut content = Panel::new(
        "Harmonic content",
        "Frequency f [Hz]",
        "A_k / A_1, swept points",
    );
    content.log_y = true;
    content.legend = Corner::Outside;
    let mut labelled = std::collections::HashSet::new();
    for (i, l) in levels.iter().enumerate() {
        for k in (0..=h).filter(|&k| k != 1).take(6) {
            let pts: Vec<(f64, f64)> = l
                .sweep
                .points
                .iter()
                .filter_map(|p| {
                    let r = harmonic_amplitude(&p.coefficients, k)
                        / harmonic_amplitude(&p.coefficients, 1);
                    (r > 1e-12).then(|| (hz(p.omega), r))
                })
                .collect();
            for &(_, v) in &pts {
                lo = lo.min(v.log10());
            }
            if pts.is_empty() {
                continue;
            }
            let style = match k {
                0 => Style::DashPattern(1, 2, 3),
                2 => Style::DashPattern(1, 8, 3),
                3 => Style::Line(2),
                _ => Style::DashPattern(1, 4, 2),
            };
            let mut s = Series::new(pts, colour(i), style);
            if labelled.insert(k) {
                s = s.label(format!("k = {k}"));
            }
            content.series.push(s);
        }
    }
    content.x_range = Some((f_min, f_max));
    content.y_range = Some((10f64.powf(lo.floor().max(-12.0)), 10f64.powf(0.5)));
    Ok(figure::render(title, &[amp, content], 1, 1100, 430)?)
}
