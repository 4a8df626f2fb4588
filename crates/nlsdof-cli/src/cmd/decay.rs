//! `nlsdof decay`: free-decay identification (library:
//! `nlsdof::identification::decay`): Hilbert envelope and instantaneous
//! frequency, backbone, damping curve, averaged-equation fit, envelope
//! check, SVG figure.

use crate::error::CliError;
use nlsdof::identification::decay::{analyse, DecayAnalysis, DecayOptions, Fitted};
use nlsdof::identification::time_domain::uniform_fs;
use nlsdof_io::table_file::read_columns;
use plotters::prelude::*;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    about = "Free-decay identification: Hilbert backbone f(a), damping curve, averaged power-law fit, envelope check",
    after_long_help = DECAY_HELP
)]
pub struct Args {
    /// Record: LabVIEW .lvm text (two header blocks) or CSV with a header.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Response column (header name or 0-based index).
    #[arg(long, value_name = "NAME")]
    pub column: String,
    /// Time column (s; default X_Value, t or time if present).
    #[arg(long, value_name = "C")]
    pub time_column: Option<String>,
    /// Sampling frequency, Hz (instead of a time column).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Start of the free decay, s from the first sample (default: where the envelope leaves its maximum).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_start: Option<f64>,
    /// Band-pass around the mode F1:F2 in Hz (default: 0.5 to 1.5 x the spectral peak).
    #[arg(long, value_name = "F1:F2")]
    pub band: Option<String>,
    /// Amplitude bins of the backbone.
    #[arg(long, default_value_t = 30)]
    pub bins: usize,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// SVG figure: record with envelope, backbone, damping curve.
    #[arg(long, value_name = "FIG.svg")]
    pub plot: Option<PathBuf>,
}

const DECAY_HELP: &str = "METHOD:
  Analytic signal by FFT (zero-padded to >= 2N, band-pass with raised-cosine edges), the
  instantaneous amplitude a(t) = |z| and frequency f(t); the ends are trimmed by
  max(3 cycles, 2/bandwidth). Backbone f(a) and decay rate lambda(a) = -d ln a/dt per
  amplitude bin. The averaged power-law equations
      omega^2 = alpha + g(rho) beta a^rho
      da/dt  = -a (delta + g(eta) kappa (omega a)^eta) / 2
  are fitted (grid over the exponent + Levenberg-Marquardt, 95 % intervals), and the
  fitted model's simulated free decay from (a0, 0) is compared with the measured
  envelope (RMS error relative to the largest amplitude).

EXAMPLE:
  nlsdof decay --input ../shared/data/magnetomechanical-sdof-decay-frid/decay_f_42p05_ampl_2p0_0.lvm \\
      --column Strain_0 --t-start 12 --json --plot decay.svg";

fn plot_err<E: std::fmt::Display>(e: E) -> CliError {
    CliError::Usage(format!("cannot draw the plot: {e}"))
}

fn fitted_json(f: &Fitted) -> serde_json::Value {
    let p: Vec<_> = (0..3)
        .map(|k| {
            json!({"name": f.names[k], "value": f.values[k], "lower": f.lower[k], "upper": f.upper[k]})
        })
        .collect();
    json!({"parameters": p, "rms": f.rms})
}

fn svg(x: &[f64], fs: f64, t0: f64, r: &DecayAnalysis) -> Result<String, CliError> {
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

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    let band = match &a.band {
        None => None,
        Some(b) => {
            let bad = || CliError::Usage(format!("--band {b:?} is not F1:F2 in Hz (e.g. 30:50)"));
            let (x, y) = b.split_once(':').ok_or_else(bad)?;
            Some((
                x.trim().parse::<f64>().map_err(|_| bad())?,
                y.trim().parse::<f64>().map_err(|_| bad())?,
            ))
        }
    };
    if a.bins < 4 {
        return Err(CliError::Usage(format!(
            "--bins {}: give at least 4",
            a.bins
        )));
    }
    if let Some(p) = &a.plot {
        nlsdof_io::atomic::check_targets(&[("--plot", p)])?;
    }
    if let Some(fs) = a.fs {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(CliError::Usage(format!(
                "--fs {fs} must be a finite sampling frequency > 0 Hz"
            )));
        }
        if a.time_column.is_some() {
            return Err(CliError::Usage(
                "give either --fs or --time-column, not both".into(),
            ));
        }
    }
    let (x, fs, t0) = if let Some(fs) = a.fs {
        let t = read_columns(&a.input, &[a.column.as_str()])?;
        (t.columns.into_iter().next().unwrap_or_default(), fs, 0.0)
    } else {
        let tc: Vec<&str> = match &a.time_column {
            Some(c) => vec![c.as_str()],
            None => vec!["X_Value", "t", "time"],
        };
        let mut last_err = None;
        let mut got = None;
        for c in tc {
            match read_columns(&a.input, &[a.column.as_str(), c]) {
                Ok(t) => {
                    got = Some(t);
                    break;
                }
                Err(e) => {
                    // a missing response column is the error to report
                    if let Err(e2) = read_columns(&a.input, &[a.column.as_str()]) {
                        return Err(e2.into());
                    }
                    last_err = Some(e);
                }
            }
        }
        let Some(t) = got else {
            return Err(match (a.time_column.is_some(), last_err) {
                (true, Some(e)) => e.into(),
                _ => CliError::Usage(format!(
                    "{}: no time column (X_Value, t, time): give --time-column C or --fs HZ",
                    a.input.display()
                )),
            });
        };
        let mut cols = t.columns.into_iter();
        let x = cols.next().unwrap_or_default();
        let time = cols.next().unwrap_or_default();
        let fs = uniform_fs(&time, 1e-3).map_err(|e| {
            CliError::Usage(format!(
                "{}: column {:?}: {e}",
                a.input.display(),
                t.names[1]
            ))
        })?;
        (x, fs, time.first().copied().unwrap_or(0.0))
    };
    let opts = DecayOptions {
        t_start: a.t_start.map(|t| t - t0),
        band,
        bins: a.bins,
    };
    let t_an = Instant::now();
    let r = analyse(&x, fs, &opts)
        .map_err(|e| CliError::Usage(format!("{}: {e}", a.input.display())))?;
    let analyse_s = t_an.elapsed().as_secs_f64();
    if let Some(p) = &a.plot {
        nlsdof_io::atomic::write_atomic(p, svg(&x, fs, t0, &r)?.as_bytes())?;
    }
    if a.json {
        let v = json!({
            "input": a.input,
            "column": a.column,
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
            "total_s": t_start.elapsed().as_secs_f64(),
        });
        println!("{v}");
    } else {
        println!(
            "free decay of {} from t = {:.4} s to {:.4} s, band {:.3}:{:.3} Hz, {} backbone points ({:.1} ms)",
            a.column,
            t0 + r.start as f64 / fs,
            t0 + r.end as f64 / fs,
            r.band.0,
            r.band.1,
            r.backbone.len(),
            1e3 * analyse_s
        );
        println!("  amplitude          f [Hz]      decay rate [1/s]");
        for p in &r.backbone {
            println!(
                "  {:>14.6e}  {:>10.5}  {:>12.5}",
                p.amplitude, p.f_hz, p.decay_rate
            );
        }
        for f in [&r.stiffness, &r.damping] {
            for k in 0..3 {
                println!(
                    "  {:<6} {:>16.8e}  [{:.6e}, {:.6e}]",
                    f.names[k], f.values[k], f.lower[k], f.upper[k]
                );
            }
        }
        println!(
            "envelope error of the fitted model's free decay: {:.4} % of the largest amplitude",
            100.0 * r.envelope_error
        );
    }
    Ok(())
}
