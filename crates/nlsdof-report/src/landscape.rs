//! `fit --landscape FILE`: the exponent landscape as JSON (the grid) or as
//! an SVG/PNG heat map of `log10(cost / cost_min)` over `(rho, eta)`, with
//! the grid minima (white rings) and the fitted exponents (red cross).

use crate::ReportError;
use nlsdof::identification::models::{ETA, RHO};
use nlsdof::identification::Identification;
use nlsdof_figure::{
    self as figure, colour, grid_map_png, grid_map_svg, Corner, GridMap, Panel, Series, Style,
};
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
    use crate::figure_file::{figure_format, FigureFormat as F};
    Ok(
        match figure_format("--landscape", path, &[F::Json, F::Svg, F::Png])? {
            F::Json => Kind::Json,
            F::Svg => Kind::Svg,
            F::Png => Kind::Png,
        },
    )
}

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
        Kind::Svg | Kind::Png => {
            let (nr, ne) = (l.rho.len(), l.eta.len());
            let format = if kind == Kind::Png {
                figure::Format::Png
            } else {
                figure::Format::Svg
            };
            if nr > 1 && ne > 1 {
                Ok(match format {
                    figure::Format::Svg => grid_map_svg(&map(id))?.into_bytes(),
                    figure::Format::Png => grid_map_png(&map(id))?,
                })
            } else if nr * ne > 1 {
                profile_figure(id, format)
            } else {
                Err(ReportError::Invalid(format!(
                    "--landscape: the {} fit has no free exponent, so its landscape is a single node (rho {}, eta {}) and there is nothing to draw; write FILE.json for its cost, or free an exponent",
                    id.fit.kind,
                    crate::num(l.rho.first().copied().unwrap_or(f64::NAN)),
                    crate::num(l.eta.first().copied().unwrap_or(f64::NAN)),
                )))
            }
        }
    }
}

/// A landscape with one free exponent (the other axis a single node): the
/// profile `log10(cost / min)` against that exponent, the grid minima
/// ringed and the fitted exponent marked by a vertical line.
fn profile_figure(id: &Identification, format: figure::Format) -> Result<Vec<u8>, ReportError> {
    let l = &id.landscape;
    let along_rho = l.rho.len() > 1;
    let (xs, name, fitted) = if along_rho {
        (&l.rho, "rho (stiffness exponent)", id.fit.theta[RHO])
    } else {
        (&l.eta, "eta (damping exponent)", id.fit.theta[ETA])
    };
    let cost = |k: usize| if along_rho { l.at(k, 0) } else { l.at(0, k) };
    let cmin = (0..xs.len())
        .map(cost)
        .filter(|c| c.is_finite() && *c > 0.0)
        .fold(f64::INFINITY, f64::min);
    let val = |c: f64| (c.is_finite() && cmin.is_finite()).then(|| (c / cmin).max(1.0).log10());
    let pts: Vec<(f64, f64)> = (0..xs.len())
        .filter_map(|k| val(cost(k)).map(|v| (xs[k], v)))
        .collect();
    let top = pts.iter().fold(0.0f64, |m, p| m.max(p.1)).max(0.1);
    let mut p = Panel::new(
        format!(
            "Exponent profile: log10(cost / min), equation error{}",
            if l.with_phase { " with phase" } else { "" }
        ),
        name,
        "log10(cost / min)",
    );
    p.legend = Corner::Outside;
    p.y_range = Some((-0.05 * top, 1.08 * top));
    p.series.push(
        Series::new(pts, colour(0), Style::Line(2)).label("landscape (coefficients optimised)"),
    );
    let minima: Vec<(f64, f64)> = l
        .minima
        .iter()
        .filter_map(|&(i, j)| {
            let k = if along_rho { i } else { j };
            val(l.at(i, j)).map(|v| (xs[k], v))
        })
        .collect();
    p.series
        .push(Series::new(minima, colour(0), Style::Dots(5)).label("grid minima"));
    p.series.push(
        Series::new(
            vec![(fitted, -0.05 * top), (fitted, 1.08 * top)],
            colour(1),
            Style::DashPattern(2, 7, 4),
        )
        .label("fitted (output error)"),
    );
    Ok(figure::render_as(
        format,
        "Exponent landscape",
        &[p],
        1,
        1000,
        560,
    )?)
}

/// The heat map of `log10(cost / cost_min)` over `(rho, eta)`, with the
/// grid minima ringed and the fitted exponents crossed.
fn map(id: &Identification) -> GridMap {
    let l = &id.landscape;
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
    let mut values = Vec::with_capacity(nr * ne);
    for j in 0..ne {
        for i in 0..nr {
            values.push(val(l.at(i, j)));
        }
    }
    GridMap {
        title: format!(
            "Exponent landscape: log10(cost / min), equation error{}",
            if l.with_phase { " with phase" } else { "" }
        ),
        x_label: "rho (stiffness exponent)".into(),
        y_label: "eta (damping exponent)".into(),
        x: l.rho.clone(),
        y: l.eta.clone(),
        values,
        value_label: "log10(cost/min)".into(),
        rings: l
            .minima
            .iter()
            .map(|&(i, j)| (l.rho[i], l.eta[j]))
            .collect(),
        rings_label: "grid minima".into(),
        cross: Some((id.fit.theta[RHO], id.fit.theta[ETA])),
        cross_label: "fitted (output error)".into(),
    }
}
