//! Linear identification of an SDoF from a measured FRF (`nlsdof
//! linear-id`, paper §2.3, Table 3): JSON, text, the model file of the
//! linear part and the SVG of |H|, phase and the Nyquist plot.

use crate::ReportError;
use nlsdof::vector_fitting::InputKind;
use nlsdof::vector_fitting::{
    mobility, CircleFit, MassSource, OutputKind, SdofIdentification, SdofLinear, C64,
};
use nlsdof::Model;
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// The linear part as an `nlsdof fit --fix` value.
fn fix_argument(alpha: f64, delta: f64, mass: Option<f64>) -> String {
    let mut s = format!("alpha={alpha:?},delta={delta:?}");
    if let Some(m) = mass {
        s += &format!(",m={m:?}");
    }
    s
}

fn source_name(s: MassSource) -> &'static str {
    match s {
        MassSource::Residue => "residue",
        MassSource::Given => "given",
        MassSource::Unidentified => "not identifiable",
    }
}

fn c(z: C64) -> serde_json::Value {
    json!([z.re, z.im])
}

/// α = k/m (1/s²), δ = c/m (1/s), the mass (kg) if known and where it
/// came from.
fn linear_part(l: &SdofLinear) -> (f64, f64, Option<f64>, MassSource) {
    (l.alpha, l.delta, l.mass, l.mass_source)
}

/// The JSON document of `linear-id --json`: the vector fit (order history,
/// poles, residues), the SDoF linear part (α = k/m in 1/s², δ = c/m in 1/s,
/// and m, k, c when the mass is known), the half-power and circle-fit
/// estimates. `f_hz` are the frequencies (Hz) of the points used.
pub fn json(id: &SdofIdentification, f_hz: &[f64]) -> Value {
    let (alpha, delta, mass, source) = linear_part(&id.sdof);
    let fit = id.fit.as_ref().map(|f| {
        json!({
            "pole_pairs": id.modes.len(),
            "order": f.order(),
            "iterations": f.iterations,
            "termination": f.termination.to_string(),
            "rms_history": f.rms_history,
            "rms_error": f.rms_error,
            "relative_rms_error": f.relative_rms_error,
            "constant": f.constant,
            "proportional": f.proportional,
            "auto_order_history": id.auto_history.iter().map(|(n, r)| json!({"pole_pairs": n, "rms_error": r})).collect::<Vec<_>>(),
            "real_poles": f.terms.iter().filter(|t| !t.is_pair()).map(|t| json!({"pole": t.pole.re, "residue": t.residue.re})).collect::<Vec<_>>(),
        })
    });
    let modes: Vec<_> = id
        .modes
        .iter()
        .map(|m| json!({"f_n_hz": m.frequency_hz, "zeta": m.zeta, "pole": c(m.pole), "residue": c(m.residue), "peak": m.peak}))
        .collect();
    let lp = id.linear.as_ref().map(|l| {
        json!({"mode": id.chosen.map(|i| i + 1), "gain": c(l.gain), "complexity_deg": l.complexity.to_degrees(), "residue_mass": l.residue_mass})
    });
    let hp = match &id.half_power {
        Ok(h) => {
            json!({"f_n_hz": h.omega_n / (2.0 * PI), "zeta": h.zeta, "f_low_hz": h.omega_low / (2.0 * PI), "f_high_hz": h.omega_high / (2.0 * PI)})
        }
        Err(e) => json!({"error": e.to_string()}),
    };
    let cf = match circle_result(id) {
        Ok(c) => {
            json!({"f_n_hz": c.omega_n / (2.0 * PI), "zeta": c.zeta, "diameter": 2.0 * c.radius, "points": c.points, "relative_residual": c.relative_residual})
        }
        Err(e) => json!({"error": e}),
    };
    let out = json!({
        "points": f_hz.len(),
        "vector_fitting": fit,
        "modes": modes,
        "sdof": {
            "alpha": alpha, "delta": delta,
            "f_n_hz": alpha.sqrt() / (2.0 * PI), "zeta": delta / (2.0 * alpha.sqrt()),
            "mass": mass, "stiffness": mass.map(|m| m * alpha), "damping": mass.map(|m| m * delta),
            "mass_source": source_name(source),
            "fix_argument": fix_argument(alpha, delta, mass),
            "from_vector_fitting": lp,
        },
        "half_power": hp,
        "circle_fit": cf,
    });
    out
}

/// The text report of `linear-id`; `source` names the FRF file.
pub fn text(id: &SdofIdentification, f_hz: &[f64], source_file: &str) -> String {
    let (alpha, delta, mass, source) = linear_part(&id.sdof);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "FRF {}: {} points, {:.6} .. {:.6} Hz",
        source_file,
        f_hz.len(),
        f_hz[0],
        f_hz[f_hz.len() - 1]
    );
    if let Some(f) = &id.fit {
        if !id.auto_history.is_empty() {
            let h: Vec<String> = id
                .auto_history
                .iter()
                .map(|(n, r)| format!("{n}:{r:.3e}"))
                .collect();
            let _ = writeln!(
                s,
                "model order (pole pairs: RMS error): {}  -> {} pair(s)",
                h.join("  "),
                id.modes.len()
            );
        }
        let _ = writeln!(
            s,
            "vector fitting: {} pole(s), {} iteration(s), {}",
            f.order(),
            f.iterations,
            f.termination
        );
        let h: Vec<String> = f.rms_history.iter().map(|r| format!("{r:.3e}")).collect();
        let _ = writeln!(s, "  RMS error per iteration: {}", h.join(" "));
        let _ = writeln!(
            s,
            "  final RMS error {:.4e} ({:.3e} of the RMS FRF)",
            f.rms_error, f.relative_rms_error
        );
        let _ = writeln!(
            s,
            "   #     f_n [Hz]         zeta       residue (rad/s units)"
        );
        for (i, m) in id.modes.iter().enumerate() {
            let mark = if Some(i) == id.chosen { "*" } else { " " };
            let _ = writeln!(
                s,
                "{mark}{:>3} {:>12.6} {:>12.6e}   {:+.6e} {:+.6e}j",
                i + 1,
                m.frequency_hz,
                m.zeta,
                m.residue.re,
                m.residue.im
            );
        }
        for t in f.terms.iter().filter(|t| !t.is_pair()) {
            let _ = writeln!(
                s,
                "  real pole {:.6e} rad/s, residue {:.6e}",
                t.pole.re, t.residue.re
            );
        }
    } else {
        let _ = writeln!(
            s,
            "amplitude-only FRF: vector fitting needs the phase; using the half-power estimate"
        );
    }
    let wn = alpha.sqrt();
    let _ = writeln!(
        s,
        "SDoF linear part{}:",
        id.chosen
            .map(|i| format!(" (mode {})", i + 1))
            .unwrap_or_default()
    );
    let _ = writeln!(
        s,
        "  f_n = {:.6} Hz, zeta = {:.6e}",
        wn / (2.0 * PI),
        delta / (2.0 * wn)
    );
    let _ = writeln!(
        s,
        "  alpha = k/m = {alpha:.6e} 1/s^2, delta = c/m = {delta:.6e} 1/s"
    );
    match mass {
        Some(m) => {
            let _ = writeln!(
                s,
                "  m = {m:.6e} kg ({}), k = {:.6e} N/m, c = {:.6e} N s/m",
                source_name(source),
                m * alpha,
                m * delta
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  m, k, c: mass not identifiable from a base-acceleration FRF (give --mass)"
            );
        }
    }
    let _ = writeln!(
        s,
        "  for `nlsdof fit`: --fix {}",
        fix_argument(alpha, delta, mass)
    );
    if let Some(l) = &id.linear {
        let _ = writeln!(
            s,
            "  modal gain G = {:.6e} {:+.6e}j (complexity {:.2} deg)",
            l.gain.re,
            l.gain.im,
            l.complexity.to_degrees()
        );
    }
    match &id.half_power {
        Ok(h) => {
            let _ = writeln!(
                s,
                "half-power: f_n = {:.6} Hz, zeta = {:.6e} (mobility, band {:.6} .. {:.6} Hz)",
                h.omega_n / (2.0 * PI),
                h.zeta,
                h.omega_low / (2.0 * PI),
                h.omega_high / (2.0 * PI)
            );
        }
        Err(e) => {
            let _ = writeln!(s, "half-power: n/a ({e})");
        }
    }
    match circle_result(id) {
        Ok(c) => {
            let _ = writeln!(s, "circle fit: f_n = {:.6} Hz, zeta = {:.6e} ({} points, residual {:.2e} of the radius)", c.omega_n / (2.0 * PI), c.zeta, c.points, c.relative_residual);
        }
        Err(e) => {
            let _ = writeln!(s, "circle fit: n/a ({e})");
        }
    }
    s
}

/// The model file of the identified linear part (TOML with a header that
/// says where the mass came from); `source_file` names the FRF file.
pub fn model_file_text(id: &SdofIdentification, source_file: &str) -> Result<String, ReportError> {
    let (alpha, delta, mass, source) = linear_part(&id.sdof);
    let m = mass.unwrap_or(1.0);
    let model = Model::linear(m, m * alpha, m * delta)?;
    let mut s = format!(
        "# Linear part identified by `nlsdof linear-id` from {source_file}\n# alpha = k/m = {alpha:?} 1/s^2, delta = c/m = {delta:?} 1/s\n"
    );
    s += match source {
        MassSource::Residue => "# mass from the residue of the force-input FRF (modal mass at the measurement point)\n",
        MassSource::Given => "# mass given with --mass\n",
        MassSource::Unidentified => {
            "# mass NOT identifiable from a base-acceleration FRF: m = 1 kg placeholder, so stiffness = k/m and\n# damping = c/m; every response to a base acceleration depends only on these ratios.\n"
        }
    };
    s += &nlsdof_io::model_file::model_to_toml(&model);
    s += &nlsdof_io::model_file::provenance_to_toml(&nlsdof_io::model_file::Provenance {
        tool: Some("nlsdof linear-id".into()),
        version: Some(env!("CARGO_PKG_VERSION").into()),
        data: Some(source_file.to_string()),
        model: Some("linear".into()),
        ..Default::default()
    });
    Ok(s)
}

/// The circle fit, or why there is none.
fn circle_result(id: &SdofIdentification) -> Result<&CircleFit, String> {
    match &id.circle {
        Some(Ok(c)) => Ok(c),
        Some(Err(e)) => Err(e.to_string()),
        None => Err("needs the phase (complex FRF)".into()),
    }
}

/// The unit of an FRF from `input` to `output` (SI, as the values are
/// used): `m/N`, `(m/s)/N`, `m/(m/s²)`, ...
pub fn frf_unit(input: InputKind, output: OutputKind) -> String {
    let out = match output {
        OutputKind::Displacement => "m",
        OutputKind::Velocity => "(m/s)",
        OutputKind::Acceleration => "(m/s²)",
    };
    let inp = match input {
        InputKind::Force => "N",
        InputKind::Acceleration => "(m/s²)",
    };
    format!("{out}/{inp}")
}

/// SVG: |H| (log) and phase vs frequency, measured points and fitted curve;
/// Nyquist plot of the mobility with the fitted model and the circle fit
/// (units of a displacement-per-base-acceleration FRF unless
/// [`figure_as`] is told the quantities).
pub fn svg(
    id: &SdofIdentification,
    f_hz: &[f64],
    output: OutputKind,
) -> Result<String, ReportError> {
    let bytes = figure_as(
        id,
        f_hz,
        InputKind::Acceleration,
        output,
        figure::Format::Svg,
    )?;
    Ok(String::from_utf8(bytes).expect("SVG is text"))
}

/// The figure of `linear-id --plot` (SVG or PNG): |H| (log, in the FRF's
/// unit from `input` to `output`) and phase vs frequency, measured points
/// and fitted curve; Nyquist plot of the mobility (velocity per input)
/// with the fitted model and the circle fit.
pub fn figure_as(
    id: &SdofIdentification,
    f_hz: &[f64],
    input: InputKind,
    output: OutputKind,
    format: figure::Format,
) -> Result<Vec<u8>, ReportError> {
    let unit = frf_unit(input, output);
    let mob_unit = frf_unit(input, OutputKind::Velocity);
    if f_hz.is_empty() {
        return Err(ReportError::Invalid("no FRF point to plot".into()));
    }
    let (blue, red, green) = (colour(0), colour(1), colour(2));
    let (f0, f1) = (f_hz[0], f_hz[f_hz.len() - 1]);
    let (f0, f1) = if f1 > f0 {
        (f0, f1)
    } else {
        (f0 - 0.5, f0 + 0.5)
    };
    let nf = 800;
    let fit_curve: Vec<(f64, C64)> = match &id.fit {
        Some(fit) => (0..=nf)
            .map(|i| f0 + (f1 - f0) * i as f64 / nf as f64)
            .map(|f| (f, fit.eval(2.0 * PI * f)))
            .collect(),
        None => vec![],
    };
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let mut mags: Vec<f64> = id.magnitude.iter().copied().filter(|&v| pos(v)).collect();
    mags.extend(fit_curve.iter().map(|p| p.1.norm()).filter(|&v| pos(v)));
    let lo = mags.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = mags.iter().copied().fold(0.0, f64::max);
    let (lo, hi) = if lo < hi {
        (lo / 1.5, hi * 1.5)
    } else {
        (1e-12, 1.0)
    };
    let mut mag = Panel::new(
        "Measured (points) and fitted (line) FRF",
        "frequency f [Hz]",
        &format!("|H| [{unit}]"),
    );
    mag.legend = Corner::Outside;
    mag.log_y = true;
    mag.x_range = Some((f0, f1));
    mag.y_range = Some((lo, hi));
    mag.series.push(
        Series::new(
            f_hz.iter()
                .copied()
                .zip(id.magnitude.iter().copied())
                .collect(),
            blue,
            Style::Dots(2),
        )
        .label("measured"),
    );
    let mut phase = Panel::new("Phase", "frequency f [Hz]", "phase of H [deg]");
    phase.x_range = Some((f0, f1));
    phase.y_range = Some((-180.0, 180.0));
    if let Some(h) = &id.values {
        phase.series.push(Series::new(
            f_hz.iter()
                .zip(h)
                .map(|(&f, z)| (f, z.arg().to_degrees()))
                .collect(),
            blue,
            Style::Dots(2),
        ));
    }
    if !fit_curve.is_empty() {
        mag.series.push(
            Series::new(
                fit_curve
                    .iter()
                    .map(|&(f, z)| (f, z.norm().max(lo)))
                    .collect(),
                red,
                Style::Line(2),
            )
            .label("vector fit"),
        );
        phase.series.push(Series::new(
            fit_curve
                .iter()
                .map(|&(f, z)| (f, z.arg().to_degrees()))
                .collect(),
            red,
            Style::Filled(1),
        ));
    }
    // Nyquist of the mobility.
    let mob = |w: f64, z: C64| mobility(w, z, output);
    let meas: Vec<C64> = match &id.values {
        Some(h) => id.omega.iter().zip(h).map(|(&w, &z)| mob(w, z)).collect(),
        None => vec![],
    };
    let fitted: Vec<C64> = fit_curve
        .iter()
        .map(|&(f, z)| mob(2.0 * PI * f, z))
        .collect();
    let mut circle: Vec<C64> = vec![];
    if let Some(Ok(c)) = &id.circle {
        circle = (0..=200)
            .map(|i| c.center + C64::from_polar(c.radius, 2.0 * PI * i as f64 / 200.0))
            .collect();
    }
    let ext = meas
        .iter()
        .chain(&fitted)
        .chain(&circle)
        .map(|z| z.re.abs().max(z.im.abs()))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let ext = if ext > 0.0 { ext * 1.1 } else { 1.0 };
    let mut nyquist = Panel::new(
        "Nyquist plot of the mobility",
        &format!("Re Y [{mob_unit}]"),
        &format!("Im Y [{mob_unit}]"),
    );
    nyquist.legend = Corner::Outside;
    nyquist.x_range = Some((-ext, ext));
    nyquist.y_range = Some((-ext, ext));
    let pts = |v: &[C64]| v.iter().map(|z| (z.re, z.im)).collect::<Vec<_>>();
    nyquist
        .series
        .push(Series::new(pts(&meas), blue, Style::Dots(2)).label("data"));
    if !fitted.is_empty() {
        nyquist
            .series
            .push(Series::new(pts(&fitted), red, Style::Line(2)).label("fit"));
    }
    if !circle.is_empty() {
        nyquist
            .series
            .push(Series::new(pts(&circle), green, Style::Line(1)).label("circle fit"));
    }
    Ok(figure::render_as(
        format,
        "Linear identification",
        &[mag, phase, nyquist],
        2,
        620,
        460,
    )?)
}
