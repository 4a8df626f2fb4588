//! `fit --landscape FILE`: the exponent landscape as JSON (the grid) or as
//! an SVG/PNG heat map of `log10(cost / cost_min)` over `(rho, eta)`, with
//! the grid minima (white rings) and the fitted exponents (red cross).

use crate::ReportError;
use nlsdof::identification::models::{ETA, RHO};
use nlsdof::identification::Identification;
use plotters::coord::Shift;
use plotters::prelude::*;
use serde_json::json;
use std::path::Path;

/// Output format, from the file name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Json,
    Svg,
    Png,
}

/// The format asked for by `path`'s extension.
pub fn kind_of(path: &Path) -> Result<Kind, ReportError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("json") => Ok(Kind::Json),
        Some("svg") => Ok(Kind::Svg),
        Some("png") => Ok(Kind::Png),
        _ => Err(ReportError::Invalid(format!(
            "--landscape {}: the name must end in .json, .svg or .png",
            path.display()
        ))),
    }
}

fn draw_err<E: std::fmt::Display>(e: E) -> ReportError {
    ReportError::Invalid(format!("cannot draw the landscape figure: {e}"))
}

const W: u32 = 820;
const H: u32 = 640;

/// The file's bytes.
pub fn render(id: &Identification, kind: Kind) -> Result<Vec<u8>, ReportError> {
    let l = &id.landscape;
    match kind {
        Kind::Json => {
            let nr = l.rho.len();
            let rows: Vec<Vec<Option<f64>>> = (0..l.eta.len())
                .map(|j| {
                    (0..nr)
                        .map(|i| Some(l.at(i, j)).filter(|c| c.is_finite()))
                        .collect()
                })
                .collect();
            let v = json!({
                "description": "equation-error cost profiled over the exponents (coefficients optimised at each node); cost[j][i] at (rho[i], eta[j]); null = node not solvable",
                "rho": l.rho, "eta": l.eta, "cost": rows, "with_phase": l.with_phase,
                "minima": l.minima.iter().map(|&(i, j)| json!({"rho": l.rho[i], "eta": l.eta[j], "cost": l.at(i, j)})).collect::<Vec<_>>(),
                "fitted": {"rho": id.fit.theta[RHO], "eta": id.fit.theta[ETA]},
            });
            Ok(serde_json::to_vec_pretty(&v).expect("json"))
        }
        Kind::Svg => {
            nlsdof_figure::fonts::register();
            let mut s = String::new();
            {
                let root = SVGBackend::with_string(&mut s, (W, H)).into_drawing_area();
                draw(&root, id)?;
                root.present().map_err(draw_err)?;
            }
            Ok(s.into_bytes())
        }
        Kind::Png => {
            nlsdof_figure::fonts::register();
            let mut buf = vec![255u8; (W * H * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut buf, (W, H)).into_drawing_area();
                draw(&root, id)?;
                root.present().map_err(draw_err)?;
            }
            Ok(nlsdof_figure::encode_png(&buf, W, H)?)
        }
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    id: &Identification,
) -> Result<(), ReportError> {
    let l = &id.landscape;
    root.fill(&WHITE).map_err(draw_err)?;
    let (nr, ne) = (l.rho.len(), l.eta.len());
    let cmin = l
        .cost
        .iter()
        .filter(|c| c.is_finite() && **c > 0.0)
        .fold(f64::INFINITY, |m, &c| m.min(c));
    let val = |c: f64| {
        if c.is_finite() && cmin.is_finite() {
            (c / cmin).max(1.0).log10()
        } else {
            f64::NAN
        }
    };
    let vmax = l
        .cost
        .iter()
        .map(|&c| val(c))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let half = |v: &[f64], k: usize| -> (f64, f64) {
        if v.len() == 1 {
            (v[0] - 0.5, v[0] + 0.5)
        } else {
            let d = (v[v.len() - 1] - v[0]) / (v.len() - 1) as f64;
            (v[k] - d / 2.0, v[k] + d / 2.0)
        }
    };
    let (x0, _) = half(&l.rho, 0);
    let (_, x1) = half(&l.rho, nr - 1);
    let (y0, _) = half(&l.eta, 0);
    let (_, y1) = half(&l.eta, ne - 1);
    let (main, bar) = root.split_horizontally(W - 110);
    let mut chart = ChartBuilder::on(&main)
        .caption(
            format!(
                "Exponent landscape: log10(cost / min), equation error{}",
                if l.with_phase { " with phase" } else { "" }
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(54)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("rho (stiffness exponent)")
        .y_desc("eta (damping exponent)")
        .draw()
        .map_err(draw_err)?;
    let mut cells = Vec::with_capacity(nr * ne);
    for j in 0..ne {
        for i in 0..nr {
            let v = val(l.at(i, j));
            let colour = if v.is_finite() {
                let c = nlsdof_figure::viridis(1.0 - v / vmax);
                RGBColor(c[0], c[1], c[2])
            } else {
                RGBColor(200, 200, 200)
            };
            let (a, b) = half(&l.rho, i);
            let (c, d) = half(&l.eta, j);
            cells.push(Rectangle::new([(a, c), (b, d)], colour.filled()));
        }
    }
    chart.draw_series(cells).map_err(draw_err)?;
    chart
        .draw_series(
            l.minima
                .iter()
                .map(|&(i, j)| Circle::new((l.rho[i], l.eta[j]), 6, WHITE.stroke_width(2))),
        )
        .map_err(draw_err)?
        .label("grid minima")
        .legend(|(x, y)| Circle::new((x, y), 5, BLACK.stroke_width(2)));
    chart
        .draw_series(std::iter::once(Cross::new(
            (id.fit.theta[RHO], id.fit.theta[ETA]),
            8,
            RED.stroke_width(3),
        )))
        .map_err(draw_err)?
        .label("fitted (output error)")
        .legend(|(x, y)| Cross::new((x, y), 5, RED.stroke_width(2)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)?;
    // colour bar
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(40)
        .margin_bottom(56)
        .margin_right(8)
        .y_label_area_size(46)
        .build_cartesian_2d(0.0..1.0, 0.0..vmax)
        .map_err(draw_err)?;
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc("log10(cost/min)")
        .draw()
        .map_err(draw_err)?;
    let steps = 64;
    cb.draw_series((0..steps).map(|k| {
        let a = vmax * k as f64 / steps as f64;
        let b = vmax * (k + 1) as f64 / steps as f64;
        let c = nlsdof_figure::viridis(1.0 - (a + b) / (2.0 * vmax));
        Rectangle::new([(0.0, a), (1.0, b)], RGBColor(c[0], c[1], c[2]).filled())
    }))
    .map_err(draw_err)?;
    Ok(())
}
