//! `nlsdof inspect` ([`nlsdof::identification::inspect`]): the text summary
//! (first line the verdict), the JSON document, and the one-page figure
//! (normalised curves; backbone with its power-law fit; damping against
//! velocity amplitude with its fit). SI units; frequencies in Hz.

use crate::figure_file::FigureFormat;
use crate::ReportError;
use nlsdof::identification::inspect::{Inspection, JumpKind, LawFit, PeakKind, ResonanceSource};
use nlsdof::identification::Dataset;
use nlsdof::SweepDirection;
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style, GREY};
use serde_json::{json, Value};
use std::fmt::Write as _;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The figure formats `inspect --plot` writes.
pub const PLOT_FORMATS: [FigureFormat; 2] = [FigureFormat::Svg, FigureFormat::Png];

/// The JSON document of `nlsdof inspect --json`: the [`Inspection`] as
/// serde writes it (SI units, rad/s and Hz side by side), with the data
/// source, the headline and the run time (s) on top.
pub fn inspect_json(source: &str, r: &Inspection, seconds: f64) -> Result<Value, ReportError> {
    let mut v = serde_json::to_value(r)
        .map_err(|e| ReportError::Invalid(format!("inspection not serialisable: {e}")))?;
    if let Value::Object(m) = &mut v {
        m.insert("source".into(), json!(source));
        m.insert("headline".into(), json!(r.recommendation.headline));
        m.insert("inspect_s".into(), json!(seconds));
    }
    Ok(v)
}

fn ci(f: &LawFit) -> String {
    match f.exponent_ci95 {
        Some([a, b]) => format!("{:.3}  95 % [{:.3}, {:.3}]", f.exponent, a, b),
        None => format!("{:.3}  (no interval)", f.exponent),
    }
}

/// A level or coefficient with four significant digits.
fn sig4(v: f64) -> String {
    let a = v.abs();
    if (0.01..1e4).contains(&a) {
        let d = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.d$}")
    } else {
        format!("{v:.3e}")
    }
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |x| format!("{x:.digits$}"))
}

/// The text summary of `nlsdof inspect`; its first line is the verdict.
pub fn inspect_text(source: &str, r: &Inspection) -> String {
    let mut s = String::new();
    let rec = &r.recommendation;
    let _ = writeln!(s, "{}", rec.headline);
    let _ = writeln!(
        s,
        "data: {source}: {} curves, {} levels; {}",
        r.curves.len(),
        r.levels.len(),
        r.phase.note
    );
    // per curve
    let _ = writeln!(s, "\nPER CURVE (peak refined by a parabola in (Omega^2, 1/a^2); a/gamma in s^2; noise relative to a)");
    let _ = writeln!(
        s,
        "  {:<8} {:<4} {:>10} {:>11} {:>11} {:<11} {:>10} {:>9} {:>8} {:<11} {:>7}  jump",
        "level",
        "dir",
        "gamma",
        "f_peak Hz",
        "a_peak m",
        "peak",
        "f_90 Hz",
        "zeta",
        "delta",
        "damping",
        "noise"
    );
    for c in &r.curves {
        let kind = match c.peak.kind {
            PeakKind::Refined => "refined",
            PeakKind::BeforeJump => "before-jump",
            PeakKind::AfterJump => "after-jump",
            PeakKind::BandEdge => "band-edge",
            PeakKind::Sampled => "sampled",
        };
        let jump = c.jump.as_ref().map_or("-".to_string(), |j| {
            format!(
                "{} {:.4} -> {:.4} Hz x{:.2}{}",
                if j.kind == JumpKind::Drop {
                    "drop"
                } else {
                    "rise"
                },
                j.f_before_hz,
                j.f_after_hz,
                j.ratio,
                match j.early {
                    Some(true) => " EARLY",
                    _ => "",
                }
            )
        });
        let _ = writeln!(
            s,
            "  {:<8} {:<4} {:>10} {:>11.5} {:>11.4e} {:<11} {:>10} {:>9} {:>8} {:<11} {:>7.4}  {}",
            c.level,
            c.direction.name(),
            sig4(c.gamma),
            c.peak.f_hz,
            c.peak.amplitude,
            kind,
            opt(c.quadrature.as_ref().map(|q| q.f_hz), 5),
            opt(c.damping.as_ref().map(|d| d.zeta), 5),
            opt(c.damping.as_ref().map(|d| d.delta), 4),
            c.damping.as_ref().map_or("-", |d| match d.method {
                nlsdof::identification::inspect::DampingMethod::HalfPower => "half-power",
                nlsdof::identification::inspect::DampingMethod::PhaseSlope => "phase-slope",
            }),
            c.noise_relative,
            jump
        );
    }
    for c in &r.curves {
        for n in &c.notes {
            let _ = writeln!(s, "  {} ({}): {n}", c.level, c.direction.name());
        }
    }
    // per level
    let _ = writeln!(s, "\nRESONANCE POINT PER LEVEL (delta_eq = gamma/(a_r Omega_r), the damping at resonance; V = Omega_r a_r)");
    let _ = writeln!(
        s,
        "  {:<8} {:<10} {:>11} {:>11} {:>11} {:>11} {:>10} {:>10} {:>5}",
        "level", "source", "f_r Hz", "f_bb Hz", "a_r m", "a_r/gamma", "V m/s", "delta_eq", "used"
    );
    for p in &r.levels {
        let _ = writeln!(
            s,
            "  {:<8} {:<10} {:>11.5} {:>11.5} {:>11.4e} {:>11.4e} {:>10.4e} {:>10.5} {:>5}",
            p.level,
            match p.source {
                ResonanceSource::Quadrature => "90 deg",
                ResonanceSource::Peak => "peak",
            },
            p.f_hz,
            p.omega_backbone / TWO_PI,
            p.amplitude,
            p.normalised,
            p.velocity,
            p.delta_eq,
            if p.used { "yes" } else { "no" }
        );
    }
    // homogeneity
    let _ = writeln!(
        s,
        "\nHOMOGENEITY (spread across levels in units of the noise; ~1 = linear within the noise)"
    );
    match &r.homogeneity {
        Some(h) => {
            let _ = writeln!(
                s,
                "  linearity index {:.2} (99.9 % point {:.2}): {}",
                h.index,
                h.threshold,
                if h.linear_within_noise {
                    "homogeneous within the noise"
                } else {
                    "the levels differ beyond the noise"
                }
            );
            let _ = writeln!(
                s,
                "  a_r/gamma {:.2}, Omega_r {:.2}, delta_eq {:.2} (each alone, 99.9 % point {:.2}); resonance moves {:.3} %, a_r/gamma {:.2} %, delta_eq {:.2} %",
                h.index_normalised_peak,
                h.index_frequency,
                h.index_damping,
                h.threshold_single,
                h.frequency_shift_percent,
                h.normalised_peak_change_percent,
                h.damping_change_percent
            );
        }
        None => {
            let _ = writeln!(s, "  homogeneity needs two levels or more");
        }
    }
    // laws
    let _ = writeln!(s, "\nSTIFFNESS LAW  Omega_r^2 - omega_0^2 = g(rho) beta a_r^rho  (first-order HB backbone, Eq 9/30)");
    let st = &r.stiffness;
    let _ = writeln!(
        s,
        "  {}{}",
        match (st.nonlinear, st.hardening) {
            (false, _) => "linear: the resonance does not move beyond the noise".to_string(),
            (true, Some(true)) => "hardening".into(),
            (true, Some(false)) => "softening".into(),
            (true, None) => "nonlinear (sign not determined)".into(),
        },
        st.chi2
            .map_or(String::new(), |c| format!(" (chi2 of Omega_r {c:.1})"))
    );
    match &st.fit {
        Some(f) => {
            let _ = writeln!(s, "  rho   = {}", ci(f));
            let _ = writeln!(
                s,
                "  beta  = {:.5e} 1/(s^2 m^rho) (mass-normalised k_r/m); f_0 = {} Hz; scatter {} x the noise, {} dof",
                f.coefficient,
                st.f0_hz.map_or("-".into(), |v| format!("{v:.5}")),
                opt(f.scatter, 2),
                f.dof
            );
            if let Some(n) = &f.interval_note {
                let _ = writeln!(s, "  {n}");
            }
        }
        None => {
            let _ = writeln!(s, "  no fit: {}", st.note.as_deref().unwrap_or("-"));
        }
    }
    let _ = writeln!(s, "\nDAMPING LAW  delta_eq - delta_0 = g(eta) kappa V^eta  (Eq 22/23 at resonance; Coulomb: eta = -1, Eq 27-28)");
    let dm = &r.damping;
    let _ = writeln!(
        s,
        "  {}{}",
        if dm.nonlinear {
            "nonlinear: the damping at resonance changes beyond the noise"
        } else {
            "linear: the damping at resonance does not change beyond the noise"
        },
        dm.chi2
            .map_or(String::new(), |c| format!(" (chi2 of delta_eq {c:.1})"))
    );
    match &dm.fit {
        Some(f) => {
            let _ = writeln!(s, "  eta     = {}", ci(f));
            let _ = writeln!(
                s,
                "  delta_0 = {:.5e} 1/s{}; kappa = {:.5e} (mass-normalised c_e/m, (s/m)^eta/s); scatter {} x the noise, {} dof",
                f.intercept,
                if f.intercept_held { " (at its bound 0)" } else { "" },
                f.coefficient,
                opt(f.scatter, 2),
                f.dof
            );
            if let Some(n) = &f.interval_note {
                let _ = writeln!(s, "  {n}");
            }
        }
        None => {
            let _ = writeln!(s, "  no fit: {}", dm.note.as_deref().unwrap_or("-"));
        }
    }
    // recommendation
    let _ = writeln!(
        s,
        "\nRECOMMENDATION  model family {}, stiffness {}, damping {}: nlsdof fit --model {}",
        match rec.family {
            nlsdof::identification::inspect::Family::Linear => "linear",
            nlsdof::identification::inspect::Family::DuffingLike => "Duffing-like",
            nlsdof::identification::inspect::Family::Generalised => "generalised",
        },
        rec.stiffness,
        rec.damping,
        rec.model
    );
    for e in &rec.evidence {
        let _ = writeln!(s, "  evidence: {e}");
    }
    if rec.pinned.is_empty() {
        let _ = writeln!(s, "  pinned: no exponent to +-0.25 at 95 %");
    } else {
        let _ = writeln!(s, "  pinned: {}", rec.pinned.join("; "));
    }
    if !rec.nonlinear_levels.is_empty() {
        let _ = writeln!(
            s,
            "  levels carrying the nonlinearity (beyond 3 sigma of the lowest level, or jumping): {}",
            rec.nonlinear_levels.join(", ")
        );
    }
    for n in &rec.notes {
        let _ = writeln!(s, "note: {n}");
    }
    for w in &rec.warnings {
        let _ = writeln!(s, "WARNING: {w}");
    }
    s
}

/// The one-page figure: normalised curves `a/γ` against frequency with the
/// resonance points; the backbone `f_r(a_r)` with its power-law fit; the
/// damping `δ_eq` against `V = Ω_r a_r` with its fit. SVG or PNG.
pub fn inspect_figure(
    data: &Dataset,
    r: &Inspection,
    format: FigureFormat,
) -> Result<Vec<u8>, ReportError> {
    let level_index = |name: &str| r.levels.iter().position(|p| p.level == name).unwrap_or(0);
    let mut curves = Panel::new(
        "normalised response a/gamma (lines), resonance points (dots)",
        "frequency [Hz]",
        "a/gamma [s^2]",
    );
    curves.legend = Corner::Outside;
    for c in &data.curves {
        let k = level_index(&c.level);
        let n = c.omegas.len();
        let stride = (n / 400).max(1);
        let pts: Vec<(f64, f64)> = (0..n)
            .step_by(stride)
            .map(|i| (c.omegas[i] / TWO_PI, c.amplitudes[i] / c.gamma))
            .collect();
        let (line, _) = nlsdof_figure::sweep_styles(c.direction == SweepDirection::Up, 1, 2);
        curves
            .series
            .push(Series::new(pts, colour(k), line).label(format!(
                "{} ({})",
                c.level,
                c.direction.name()
            )));
    }
    for (k, p) in r.levels.iter().enumerate() {
        curves.series.push(Series::new(
            vec![(p.f_hz, p.normalised)],
            colour(k),
            if p.used {
                Style::Filled(4)
            } else {
                Style::Dots(4)
            },
        ));
    }
    // backbone
    let amax = r.levels.iter().fold(0.0f64, |m, p| m.max(p.amplitude)) * 1.1;
    // one length unit from the data's magnitude, as every figure
    let (unit, scale) = nlsdof_figure::length_unit(amax / 1.1);
    let mut backbone = Panel::new(
        "backbone: resonance points (dots; hollow: left out), power-law fit (line)",
        "frequency [Hz]",
        &format!("amplitude a_r [{unit}]"),
    );
    backbone.legend = Corner::Outside;
    let mut pts_used = Vec::new();
    let mut pts_out = Vec::new();
    for p in &r.levels {
        let q = (p.omega_backbone / TWO_PI, p.amplitude * scale);
        if p.used {
            pts_used.push(q);
        } else {
            pts_out.push(q);
        }
    }
    backbone
        .series
        .push(Series::new(pts_used, colour(0), Style::Filled(4)).label("resonance points"));
    if !pts_out.is_empty() {
        backbone
            .series
            .push(Series::new(pts_out, colour(0), Style::Dots(4)).label("left out (early jump)"));
    }
    // a law is drawn only where the levels determine its exponent (an
    // exponent at the end of its range, fitted through the points, would
    // read as a result)
    if let Some(f) = r.stiffness.fit.as_ref().filter(|f| f.determined()) {
        let line: Vec<(f64, f64)> = (0..=120)
            .filter_map(|i| {
                let a = amax * i as f64 / 120.0;
                let w2 = f.at(a.max(1e-300));
                (w2 > 0.0 && w2.is_finite()).then(|| (w2.sqrt() / TWO_PI, a * scale))
            })
            .collect();
        backbone.series.push(
            Series::new(line, colour(1), Style::Line(2)).label(format!("rho = {:.3}", f.exponent)),
        );
    }
    if amax > 0.0 {
        backbone.y_range = Some((0.0, amax * scale));
    }
    // damping
    let vmax = r.levels.iter().fold(0.0f64, |m, p| m.max(p.velocity)) * 1.1;
    let vmin = r
        .levels
        .iter()
        .fold(f64::INFINITY, |m, p| m.min(p.velocity))
        * 0.9;
    let drawn = r.damping.fit.as_ref().is_some_and(|f| f.determined());
    let mut damping = Panel::new(
        if drawn {
            "damping at resonance: delta_eq = gamma/(a_r Omega_r) (dots), power-law fit (line)"
        } else {
            "damping at resonance: delta_eq = gamma/(a_r Omega_r) (dots); eta not determined by these levels"
        },
        "velocity amplitude V = Omega_r a_r [m/s]",
        "delta_eq [1/s]",
    );
    damping.legend = Corner::Outside;
    let dots = |used: bool| -> Vec<(f64, f64)> {
        r.levels
            .iter()
            .filter(|p| p.used == used)
            .map(|p| (p.velocity, p.delta_eq))
            .collect()
    };
    damping
        .series
        .push(Series::new(dots(true), colour(0), Style::Filled(4)).label("levels"));
    let out = dots(false);
    if !out.is_empty() {
        damping
            .series
            .push(Series::new(out, colour(0), Style::Dots(4)).label("left out (early jump)"));
    }
    if let Some(f) = r.damping.fit.as_ref().filter(|f| f.determined()) {
        if vmax > 0.0 && vmin.is_finite() && vmin > 0.0 {
            let line: Vec<(f64, f64)> = (0..=120)
                .map(|i| {
                    let v = vmin + (vmax - vmin) * i as f64 / 120.0;
                    (v, f.at(v))
                })
                .filter(|q| q.1.is_finite())
                .collect();
            damping.series.push(
                Series::new(line, colour(1), Style::Line(2))
                    .label(format!("eta = {:.3}", f.exponent)),
            );
            damping.series.push(
                Series::new(
                    vec![(vmin, f.intercept), (vmax, f.intercept)],
                    GREY,
                    Style::Dashed(1),
                )
                .label("delta_0"),
            );
        }
    }
    let (ymin, ymax) = r.levels.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.delta_eq), b.max(p.delta_eq))
    });
    if ymin.is_finite() && ymax > 0.0 {
        let lo = r
            .damping
            .fit
            .as_ref()
            .map_or(ymin, |f| f.intercept.min(ymin));
        let pad = 0.1 * (ymax - lo).max(0.05 * ymax);
        damping.y_range = Some(((lo - pad).max(0.0), ymax + pad));
    }
    let rec = &r.recommendation;
    let title = format!(
        "nlsdof inspect: stiffness {}, damping {} -> nlsdof fit --model {}",
        rec.stiffness, rec.damping, rec.model
    );
    let panels = [curves, backbone, damping];
    Ok(match format {
        FigureFormat::Png => figure::render_png(&title, &panels, 1, 1100, 400)?,
        _ => figure::render(&title, &panels, 1, 1100, 400)?.into_bytes(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlsdof::identification::inspect::{inspect, InspectOptions};
    use nlsdof::identification::Record;
    use nlsdof::SweepDirection;

    /// A linear SDoF's curves at three levels: the text's first line is the
    /// verdict, the JSON has the same headline and no NaN, and both figure
    /// formats render.
    #[test]
    fn text_json_and_figure_of_a_linear_set() {
        let (wn, zeta) = (TWO_PI * 10.0, 0.01);
        let mut recs = Vec::new();
        for (l, g) in [1.0, 2.0, 4.0].into_iter().enumerate() {
            for i in 0..200 {
                let w = wn * (0.9 + 0.2 * i as f64 / 199.0);
                let a = g / ((wn * wn - w * w).powi(2) + (2.0 * zeta * wn * w).powi(2)).sqrt();
                recs.push(Record {
                    level: format!("{l}"),
                    gamma: g,
                    omega: w,
                    amplitude: a,
                    phase: None,
                    direction: SweepDirection::Up,
                    weight: 1.0,
                });
            }
        }
        let data = Dataset::from_records(&recs).unwrap();
        let r = inspect(&data, &InspectOptions::default()).unwrap();
        let text = inspect_text("lin.csv", &r);
        assert_eq!(text.lines().next().unwrap(), r.recommendation.headline);
        assert!(text.starts_with("linear"), "{text}");
        assert!(text.contains("HOMOGENEITY") && text.contains("STIFFNESS LAW"));
        let v = inspect_json("lin.csv", &r, 0.0).unwrap();
        assert_eq!(v["headline"], json!(r.recommendation.headline));
        assert_eq!(v["curves"].as_array().unwrap().len(), 3);
        let svg = inspect_figure(&data, &r, FigureFormat::Svg).unwrap();
        assert!(svg.starts_with(b"<svg"));
        let png = inspect_figure(&data, &r, FigureFormat::Png).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
    }
}
