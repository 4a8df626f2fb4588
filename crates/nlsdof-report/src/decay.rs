//! Free-decay identification (`nlsdof decay`,
//! [`nlsdof::identification::decay`]): JSON, text and the SVG of the
//! record, its Hilbert envelope, the backbone and the damping curve.

use crate::ReportError;
use nlsdof::identification::decay::{DecayAnalysis, Fitted};
use plotters::prelude::*;
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
        "analyse_s": analyse_s,
        "total_s": total_s,
    })
}

/// The text report of `nlsdof decay`: the backbone table (amplitude,
/// frequency in Hz, decay rate in 1/s) and the fitted parameters.
pub fn decay_text(rec: &DecayRecord, r: &DecayAnalysis, analyse_s: f64) -> String {
    let (fs, t0) = (rec.fs, rec.t0);
    let mut s = String::new();
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
    let _ = writeln!(
        s,
        "envelope error of the fitted model's free decay: {:.4} % of the largest amplitude",
        100.0 * r.envelope_error
    );
    s
}

fn plot_err<E: std::fmt::Display>(e: E) -> ReportError {
    ReportError::Invalid(format!("cannot draw the plot: {e}"))
}

fn fitted_json(f: &Fitted) -> Value {
    let p: Vec<_> = (0..3)
        .map(|k| {
            json!({"name": f.names[k], "value": f.values[k], "lower": f.lower[k], "upper": f.upper[k]})
        })
        .collect();
    json!({"parameters": p, "rms": f.rms})
}

/// SVG of the record `x` (sampled at `fs` Hz from `t0` s) with the analysis.
pub fn decay_svg(x: &[f64], fs: f64, t0: f64, r: &DecayAnalysis) -> Result<String, ReportError> {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (1200, 800)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let (top, bottom) = root.split_vertically(400);
        let (bl, br) = bottom.split_horizontally(600);
        let blue = RGBColor(31, 119, 180);
        let red = RGBColor(214, 39, 40);
        let grey = RGBColor(150, 150, 150);
        let t = |k: usize| t0 + k as f64 / fs;
        let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let mut ch = ChartBuilder::on(&top)
            .caption(
                "record (grey), Hilbert envelope (blue), fitted model's envelope (red)",
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(t(0)..t(x.len() - 1), -1.1 * xmax..1.1 * xmax)
            .map_err(plot_err)?;
        ch.configure_mesh()
            .x_desc("t [s]")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(plot_err)?;
        let step = (x.len() / 20_000).max(1);
        ch.draw_series(LineSeries::new(
            (0..x.len()).step_by(step).map(|k| (t(k), x[k] - mean)),
            grey.stroke_width(1),
        ))
        .map_err(plot_err)?;
        ch.draw_series(LineSeries::new(
            r.amplitude
                .iter()
                .enumerate()
                .map(|(k, &a)| (t(r.start + k), a)),
            blue.stroke_width(2),
        ))
        .map_err(plot_err)?;
        ch.draw_series(LineSeries::new(
            r.model_amplitude
                .iter()
                .enumerate()
                .map(|(k, &a)| (t(r.start + k), a)),
            red.stroke_width(2),
        ))
        .map_err(plot_err)?;
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
        let curve = |a: f64| {
            let w2 = m.alpha + g(m.rho) * m.beta * a.powf(m.rho);
            w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
        };
        let mut ch = ChartBuilder::on(&bl)
            .caption(
                "backbone: points (Hilbert), line (fitted)",
                ("sans-serif", 16),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(f0 - pad..f1 + pad, 0.0..amax)
            .map_err(plot_err)?;
        ch.configure_mesh()
            .x_desc("f [Hz]")
            .y_desc("amplitude")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(plot_err)?;
        ch.draw_series(
            r.backbone
                .iter()
                .map(|p| Circle::new((p.f_hz, p.amplitude), 3, blue.filled())),
        )
        .map_err(plot_err)?;
        ch.draw_series(LineSeries::new(
            (0..=100).map(|i| {
                let a = amax * i as f64 / 100.0;
                (curve(a), a)
            }),
            red.stroke_width(2),
        ))
        .map_err(plot_err)?;
        let lmax = r.backbone.iter().fold(0.0f64, |mx, p| mx.max(p.decay_rate)) * 1.2;
        let lmin = r
            .backbone
            .iter()
            .fold(f64::INFINITY, |mn, p| mn.min(p.decay_rate))
            .min(0.0);
        let dm = r.damping.values;
        let rate = |a: f64| {
            let w = 2.0 * std::f64::consts::PI * curve(a);
            0.5 * (dm[0] + g(dm[2]) * dm[1] * (w * a).powf(dm[2]))
        };
        let mut ch = ChartBuilder::on(&br)
            .caption("damping curve: decay rate -d ln a/dt", ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..amax, lmin..lmax.max(1e-12))
            .map_err(plot_err)?;
        ch.configure_mesh()
            .x_desc("amplitude")
            .y_desc("lambda [1/s]")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(plot_err)?;
        ch.draw_series(
            r.backbone
                .iter()
                .map(|p| Circle::new((p.amplitude, p.decay_rate), 3, blue.filled())),
        )
        .map_err(plot_err)?;
        ch.draw_series(LineSeries::new(
            (1..=100).map(|i| {
                let a = amax * i as f64 / 100.0;
                (a, rate(a))
            }),
            red.stroke_width(2),
        ))
        .map_err(plot_err)?;
        root.present().map_err(plot_err)?;
    }
    Ok(s)
}
