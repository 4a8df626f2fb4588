//! Free-decay identification (`nlsdof decay`,
//! [`nlsdof::identification::decay`]): JSON, text and the SVG of the
//! record, its Hilbert envelope, the backbone and the damping curve.

use crate::ReportError;
use nlsdof::identification::decay::{DecayAnalysis, Fitted};
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style, GREY};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// Where the analysed record came from, as the reports state it.
#[derive(Debug, Clone, Copy)]
pub struct DecayRecord<'a> {
    /// The input file.
    pub input: &'a str,
    /// The response column.
    pub column: &'a str,
    /// Sampling frequency, Hz.
    pub fs: f64,
    /// Time of the first sample, s.
    pub t0: f64,
}

/// The JSON document of `nlsdof decay --json`; `analyse_s` and `total_s`
/// are the measured run times (s).
pub fn decay_json(rec: &DecayRecord, r: &DecayAnalysis, analyse_s: f64, total_s: f64) -> Value {
    let (fs, t0) = (rec.fs, rec.t0);
    json!({
        "input": rec.input,
        "column": rec.column,
        "fs_hz": fs,
        "band_hz": [r.band.0, r.band.1],
        "decay": {"t_start": t0 + r.start as f64 / fs, "t_end": t0 + r.end as f64 / fs},
        "backbone": r.backbone.iter().map(|p| json!({
            "amplitude": p.amplitude, "f_hz": p.f_hz, "decay_rate": p.decay_rate, "samples": p.samples,
        })).collect::<Vec<_>>(),
        "stiffness_fit": fitted_json(&r.stiffness),
        "damping_fit": fitted_json(&r.damping),
        "envelope_error": r.envelope_error,
        "rising_bins_dropped": r.rising_bins,
        "adequate": decay_adequate(r),
        "warnings": decay_warnings(r),
        "notes": decay_notes(r),
        "analyse_s": analyse_s,
        "total_s": total_s,
    })
}

/// The text report of `nlsdof decay`: the backbone table (amplitude,
/// frequency in Hz, decay rate in 1/s) and the fitted parameters.
pub fn decay_text(rec: &DecayRecord, r: &DecayAnalysis, analyse_s: f64) -> String {
    let (fs, t0) = (rec.fs, rec.t0);
    let mut s = String::new();
    if !decay_adequate(r) {
        // the verdict first, as `fit` does
        if let Some(w) = decay_warnings(r).first() {
            let _ = writeln!(s, "WARNING: {w}");
        }
    }
    let _ = writeln!(
        s,
        "free decay of {} from t = {:.4} s to {:.4} s, band {:.3}:{:.3} Hz, {} backbone points ({:.1} ms)",
        rec.column,
        t0 + r.start as f64 / fs,
        t0 + r.end as f64 / fs,
        r.band.0,
        r.band.1,
        r.backbone.len(),
        1e3 * analyse_s
    );
    let _ = writeln!(s, "  amplitude          f [Hz]      decay rate [1/s]");
    for p in &r.backbone {
        let _ = writeln!(
            s,
            "  {:>14.6e}  {:>10.5}  {:>12.5}",
            p.amplitude, p.f_hz, p.decay_rate
        );
    }
    for f in [&r.stiffness, &r.damping] {
        for k in 0..3 {
            let _ = writeln!(
                s,
                "  {:<6} {:>16.8e}  [{:.6e}, {:.6e}]",
                f.names[k], f.values[k], f.lower[k], f.upper[k]
            );
        }
    }
    match r.envelope_error {
        Some(e) => {
            let _ = writeln!(
                s,
                "envelope error of the fitted model's free decay: {:.4} % of the largest amplitude",
                100.0 * e
            );
        }
        None => {
            let _ = writeln!(
                s,
                "envelope error: not computed (the fitted model's free decay could not be simulated)"
            );
        }
    }
    for n in decay_notes(r) {
        let _ = writeln!(s, "note: {n}");
    }
    let skip = usize::from(!decay_adequate(r));
    for w in decay_warnings(r).iter().skip(skip) {
        let _ = writeln!(s, "WARNING: {w}");
    }
    s
}

/// Results worth stating that are not warnings: eta = -1 is Coulomb
/// friction (the bottom of the exponent range is a result, not a failure).
pub fn decay_notes(r: &DecayAnalysis) -> Vec<String> {
    let mut n = Vec::new();
    if decay_adequate(r)
        && r.damping.values[2] <= nlsdof::identification::decay::EXPONENT_RANGE.0 + 1e-9
        && !r.damping.at_bounds.contains(&"kappa")
    {
        n.push("eta = -1: Coulomb friction (dry friction force c_e = kappa m)".into());
    }
    if r.damping.at_bounds == ["delta"] {
        n.push("delta = 0: no linear damping is seen; the damping is all in the power law".into());
    }
    n
}

/// The fitted model's free decay must follow the measured envelope: an
/// RMS difference above this fraction of the largest amplitude means the
/// record is not a free decay of the model family (a forced response, a
/// record started before the excitation stopped). Measured: the magnet
/// beam's decays 2 %, the linear and Duffing oracles of the tests below
/// 1 %, a chirp response after its resonance 82 %.
pub const ENVELOPE_ADEQUATE: f64 = 0.10;

/// Whether the fitted model reproduces the measured envelope.
pub fn decay_adequate(r: &DecayAnalysis) -> bool {
    r.envelope_error.is_some_and(|e| e <= ENVELOPE_ADEQUATE)
}

/// What the reader of a decay analysis must know: parameters at a bound
/// (named), the natural bound eta = -1 as a result, dropped bins.
pub fn decay_warnings(r: &DecayAnalysis) -> Vec<String> {
    let mut w = Vec::new();
    match r.envelope_error {
        Some(e) if e > ENVELOPE_ADEQUATE => w.push(format!(
            "the fitted model's free decay misses the measured envelope by {:.0} % of its largest amplitude: this is not a free decay of the power-law model (a forced response? give --t-start where the excitation stops); the parameters do not describe the record",
            100.0 * e
        )),
        None => w.push(
            "the fitted model's free decay could not be simulated: the parameters are not checked against the record".into(),
        ),
        _ => {}
    }
    for f in [&r.stiffness, &r.damping] {
        // delta at 0 alone is a result (a note), not a doubt about the fit
        if !f.at_bounds.is_empty() && f.at_bounds != ["delta"] {
            w.push(format!(
                "{} at a bound of the fit ({}): {}",
                f.at_bounds.join(", "),
                if f.names[0] == "delta" {
                    "delta, kappa >= 0; eta in [-1, 10]"
                } else {
                    "rho in [-1, 10]"
                },
                if f.at_bounds.contains(&"kappa") {
                    "no nonlinear damping is seen, so eta is not identified"
                } else if f.at_bounds.contains(&"delta") {
                    "no linear damping is seen"
                } else {
                    "the exponent is not identified within the range; its interval is not valid"
                }
            ));
        }
    }
    if r.rising_bins > 0 {
        w.push(format!(
            "{} amplitude bin(s) where the envelope rose (noise at the tail) were dropped",
            r.rising_bins
        ));
    }
    w
}

fn fitted_json(f: &Fitted) -> Value {
    let p: Vec<_> = (0..3)
        .map(|k| {
            json!({"name": f.names[k], "value": f.values[k], "lower": f.lower[k], "upper": f.upper[k]})
        })
        .collect();
    json!({"parameters": p, "rms": f.rms, "at_bounds": f.at_bounds})
}

/// SVG of the record `x` (sampled at `fs` Hz from `t0` s) with the
/// analysis ([`decay_figure`] of a column named `x` in an unstated unit).
pub fn decay_svg(x: &[f64], fs: f64, t0: f64, r: &DecayAnalysis) -> Result<String, ReportError> {
    let bytes = decay_figure(x, fs, t0, r, "x", None, figure::Format::Svg)?;
    Ok(String::from_utf8(bytes).expect("SVG is text"))
}

/// The fitted model's curves of the figure's backbone and damping panels
/// on 101 amplitudes from 0 to 1.05 times the largest binned amplitude:
/// `(amplitude, f_hz, decay_rate)` with ω² = α + g(ρ) β a^ρ (Hz) and
/// λ = (δ + g(η) κ (ω a)^η) / 2 (1/s; non-finite at a = 0 for η < 0).
pub fn fitted_curves(r: &DecayAnalysis) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let amax = r.backbone.iter().fold(0.0f64, |m, p| m.max(p.amplitude)) * 1.05;
    let m = r.model();
    let g = nlsdof::power_law::g_unchecked;
    let dm = r.damping.values;
    let a: Vec<f64> = (0..=100).map(|i| amax * i as f64 / 100.0).collect();
    let f: Vec<f64> = a
        .iter()
        .map(|&a| {
            let w2 = m.alpha + g(m.rho) * m.beta * a.powf(m.rho);
            w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
        })
        .collect();
    let rate = a
        .iter()
        .zip(&f)
        .map(|(&a, &f)| {
            let w = 2.0 * std::f64::consts::PI * f;
            0.5 * (dm[0] + g(dm[2]) * dm[1] * (w * a).powf(dm[2]))
        })
        .collect();
    (a, f, rate)
}

/// Samples at the start of the fitted model's envelope left out of the
/// figure: the Hilbert transform's edge transient of the simulated decay
/// (the band-pass trim of the analysis, `max(3 cycles, 2/bandwidth)`, at
/// most a quarter of the decay; the envelope error skips them too).
pub fn model_edge_samples(r: &DecayAnalysis, fs: f64) -> usize {
    let (b0, b1) = r.band;
    let fc = 0.5 * (b0 + b1);
    let trim = ((3.0 / fc).max(2.0 / (b1 - b0)) * fs).ceil();
    let trim = if trim.is_finite() && trim > 0.0 {
        trim as usize
    } else {
        0
    };
    trim.min(r.model_amplitude.len() / 4)
}

/// The figure of `decay --plot` (SVG or PNG): the record `x` (sampled at
/// `fs` Hz from `t0` s; column `column`, in `unit` when known) with its
/// Hilbert envelope and the fitted model's envelope (from the end of the
/// Hilbert edge transient, [`model_edge_samples`]); the backbone f(a)
/// (points: Hilbert, line: fitted); the damping curve, decay rate
/// −d ln a/dt against amplitude. Every amplitude axis names the column and
/// its unit.
pub fn decay_figure(
    x: &[f64],
    fs: f64,
    t0: f64,
    r: &DecayAnalysis,
    column: &str,
    unit: Option<&str>,
    format: figure::Format,
) -> Result<Vec<u8>, ReportError> {
    let (blue, red) = (colour(0), colour(1));
    let unit = unit
        .filter(|u| !u.trim().is_empty())
        .unwrap_or("unit as recorded");
    let t = |k: usize| t0 + k as f64 / fs;
    let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
    let mut record = Panel::new(
        "record, Hilbert envelope and the fitted model's envelope",
        "time t [s]",
        &format!("{column} [{unit}], mean removed"),
    );
    record.legend = Corner::Outside;
    record.x_range = Some((t(0), t(x.len().saturating_sub(1))));
    record.y_range = Some((-1.1 * xmax, 1.1 * xmax));
    let step = (x.len() / 20_000).max(1);
    let envelope = |a: &[f64], from: usize| -> Vec<(f64, f64)> {
        a.iter()
            .enumerate()
            .skip(from)
            .map(|(k, &a)| (t(r.start + k), a))
            .collect()
    };
    let edge = model_edge_samples(r, fs);
    record.series = vec![
        Series::new(
            (0..x.len())
                .step_by(step)
                .map(|k| (t(k), x[k] - mean))
                .collect(),
            GREY,
            Style::Line(1),
        )
        .label("record"),
        Series::new(envelope(&r.amplitude, 0), blue, Style::Line(2)).label("Hilbert envelope"),
        Series::new(envelope(&r.model_amplitude, edge), red, Style::Line(2))
            .label("fitted model's envelope"),
    ];
    let amax = r.backbone.iter().fold(0.0f64, |m, p| m.max(p.amplitude)) * 1.05;
    let (f0, f1) = r
        .backbone
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.f_hz), b.max(p.f_hz))
        });
    let pad = 0.1 * (f1 - f0).max(1e-3 * f1);
    let m = r.model();
    let g = |mu: f64| nlsdof::power_law::g_unchecked(mu);
    // backbone of the fitted model, Hz: ω² = α + g(ρ) β a^ρ
    let curve = |a: f64| {
        let w2 = m.alpha + g(m.rho) * m.beta * a.powf(m.rho);
        w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
    };
    let amp_label = format!("amplitude of {column} [{unit}]");
    let mut backbone = Panel::new("backbone f(a)", "frequency f [Hz]", &amp_label);
    backbone.legend = Corner::Outside;
    backbone.x_range = Some((f0 - pad, f1 + pad));
    backbone.y_range = Some((0.0, amax));
    backbone.series = vec![
        Series::new(
            r.backbone.iter().map(|p| (p.f_hz, p.amplitude)).collect(),
            blue,
            Style::Filled(3),
        )
        .label("Hilbert, per bin"),
        Series::new(
            (0..=100)
                .map(|i| {
                    let a = amax * i as f64 / 100.0;
                    (curve(a), a)
                })
                .collect(),
            red,
            Style::Line(2),
        )
        .label("fitted"),
    ];
    let lmax = r.backbone.iter().fold(0.0f64, |mx, p| mx.max(p.decay_rate)) * 1.2;
    let lmin = r
        .backbone
        .iter()
        .fold(f64::INFINITY, |mn, p| mn.min(p.decay_rate))
        .min(0.0);
    let dm = r.damping.values;
    // decay rate of the fitted damping, 1/s: (δ + g(η) κ (ω a)^η) / 2
    let rate = |a: f64| {
        let w = 2.0 * std::f64::consts::PI * curve(a);
        0.5 * (dm[0] + g(dm[2]) * dm[1] * (w * a).powf(dm[2]))
    };
    let mut damping = Panel::new(
        "damping curve",
        &amp_label,
        "decay rate λ = -d ln a/dt [1/s]",
    );
    damping.legend = Corner::Outside;
    damping.x_range = Some((0.0, amax));
    damping.y_range = Some((lmin, lmax.max(1e-12)));
    damping.series = vec![
        Series::new(
            r.backbone
                .iter()
                .map(|p| (p.amplitude, p.decay_rate))
                .collect(),
            blue,
            Style::Filled(3),
        )
        .label("Hilbert, per bin"),
        Series::new(
            (1..=100)
                .map(|i| {
                    let a = amax * i as f64 / 100.0;
                    (a, rate(a))
                })
                .collect(),
            red,
            Style::Line(2),
        )
        .label("fitted"),
    ];
    Ok(figure::render_as(
        format,
        &format!("Free decay of {column}"),
        &[record, backbone, damping],
        1,
        1200,
        360,
    )?)
}
