//! Multi-harmonic sweeps (`nlsdof frf --harmonics H`,
//! [`nlsdof::multi_harmonic`]): JSON, CSV and text with every harmonic's
//! amplitude (m) and phase (deg), and the SVG of the first harmonic and of
//! the higher-harmonic content.

use crate::steady_state::{jumps_text, model_summary, sweep_name};
use crate::ReportError;
use nlsdof::multi_harmonic::{
    harmonic_amplitude, harmonic_phase, max_abs_displacement, LevelSweep,
};
use nlsdof::{Model, SweepDirection};
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// What a multi-harmonic sweep was asked for, as its reports state it.
#[derive(Debug, Clone, Copy)]
pub struct HarmonicSweepRequest<'a> {
    /// The model's name (its file).
    pub model_name: &'a str,
    pub direction: SweepDirection,
    pub steps: usize,
    pub harmonics: usize,
}

fn hz(omega: f64) -> f64 {
    omega / (2.0 * PI)
}

fn harmonics_json(q: &[f64]) -> Vec<Value> {
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

/// The JSON document of `frf --harmonics H --json`.
pub fn sweep_json(args: &HarmonicSweepRequest, model: &Model, levels: &[LevelSweep]) -> Value {
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
                "sweep": sweep_name(args.direction),
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
        "model": args.model_name,
        "f_n_hz": hz(model.omega_n()),
        "zeta": model.zeta(),
        "formulation": "hb",
        "harmonics": args.harmonics,
        "units": {"gamma": "m/s^2 zero-to-peak", "amplitude": "m zero-to-peak (first harmonic)", "f_hz": "Hz", "phase_deg": "deg lag of the harmonic behind the input (harmonic k: A_k cos(k Omega t - phi_k))", "max_abs_x": "m"},
        "levels": lv,
    });
    out
}

/// The CSV of `frf --harmonics H --csv`: the first-order columns, then
/// every harmonic's amplitude and phase and `max_abs_x`.
pub fn sweep_csv(args: &HarmonicSweepRequest, levels: &[LevelSweep]) -> String {
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
                sweep_name(args.direction),
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

/// The text report of `frf --harmonics H`.
pub fn sweep_text(
    args: &HarmonicSweepRequest,
    model: &Model,
    levels: &[LevelSweep],
    f_min: f64,
    f_max: f64,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "model {}: {}", args.model_name, model_summary(model));
    let _ = writeln!(
        s,
        "stepped-sine sweep {}, {} .. {} Hz, {} steps; harmonic balance with H = {} harmonics (constant and even terms included), pseudo-arclength continuation, Hill stability",
        sweep_name(args.direction),
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
/// SVG: first-harmonic amplitude against frequency per level, and the
/// higher-harmonic content.
pub fn sweep_svg(
    title: &str,
    levels: &[LevelSweep],
    f_min: f64,
    f_max: f64,
) -> Result<String, ReportError> {
    let bytes = sweep_figure(title, levels, f_min, f_max, figure::Format::Svg)?;
    Ok(String::from_utf8(bytes).expect("SVG is text"))
}

/// [`sweep_svg`]'s figure as SVG or PNG bytes.
pub fn sweep_figure(
    title: &str,
    levels: &[LevelSweep],
    f_min: f64,
    f_max: f64,
    format: figure::Format,
) -> Result<Vec<u8>, ReportError> {
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
    let (unit, scale) = figure::length_unit(a_max);
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
    Ok(figure::render_as(
        format,
        title,
        &[amp, content],
        1,
        1100,
        430,
    )?)
}
