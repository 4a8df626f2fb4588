//! A value map on a rectangular grid: one coloured cell per node (viridis,
//! low values bright), a colour bar, white rings at marked nodes and a red
//! cross at one point. Used for the exponent landscape of `nlsdof fit`
//! (log10 of the equation-error cost over ρ and η).

use crate::{viridis, FigureError};
use plotters::coord::Shift;
use plotters::prelude::*;

/// What the map shows.
#[derive(Debug, Clone)]
pub struct GridMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Node coordinates, increasing and evenly spaced.
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    /// `values[j * x.len() + i]` at `(x[i], y[j])`, ≥ 0; NaN: no value
    /// (grey cell). 0 is the brightest colour.
    pub values: Vec<f64>,
    /// Label of the colour bar.
    pub value_label: String,
    /// Nodes ringed in white, and the legend entry of the rings.
    pub rings: Vec<(f64, f64)>,
    pub rings_label: String,
    /// A point marked with a red cross, and its legend entry.
    pub cross: Option<(f64, f64)>,
    pub cross_label: String,
}

const W: u32 = 820;
const H: u32 = 640;

fn draw_err<E: std::fmt::Display>(e: E) -> FigureError {
    FigureError::Draw {
        figure: "the grid map",
        detail: e.to_string(),
    }
}

/// The map as an SVG document.
pub fn grid_map_svg(map: &GridMap) -> Result<String, FigureError> {
    crate::fonts::register();
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (W, H)).into_drawing_area();
        draw(&root, map)?;
        root.present().map_err(draw_err)?;
    }
    Ok(s)
}

/// The same map as PNG bytes (drawn by the same code).
pub fn grid_map_png(map: &GridMap) -> Result<Vec<u8>, FigureError> {
    crate::fonts::register();
    let mut buf = vec![255u8; (W * H * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (W, H)).into_drawing_area();
        draw(&root, map)?;
        root.present().map_err(draw_err)?;
    }
    crate::encode_png(&buf, W, H)
}

/// The cell around node `k` of `v`.
fn half(v: &[f64], k: usize) -> (f64, f64) {
    if v.len() == 1 {
        (v[0] - 0.5, v[0] + 0.5)
    } else {
        let d = (v[v.len() - 1] - v[0]) / (v.len() - 1) as f64;
        (v[k] - d / 2.0, v[k] + d / 2.0)
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    map: &GridMap,
) -> Result<(), FigureError> {
    root.fill(&WHITE).map_err(draw_err)?;
    let (nx, ny) = (map.x.len(), map.y.len());
    if nx == 0 || ny == 0 || map.values.len() != nx * ny {
        return Err(FigureError::Draw {
            figure: "the grid map",
            detail: format!("{} values for a {nx} x {ny} grid", map.values.len()),
        });
    }
    let vmax = map
        .values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let (x0, _) = half(&map.x, 0);
    let (_, x1) = half(&map.x, nx - 1);
    let (y0, _) = half(&map.y, 0);
    let (_, y1) = half(&map.y, ny - 1);
    let (main, bar) = root.split_horizontally(W - 110);
    let mut chart = ChartBuilder::on(&main)
        .caption(&map.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(54)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(map.x_label.as_str())
        .y_desc(map.y_label.as_str())
        .draw()
        .map_err(draw_err)?;
    let mut cells = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let v = map.values[j * nx + i];
            let colour = if v.is_finite() {
                let c = viridis(1.0 - v / vmax);
                RGBColor(c[0], c[1], c[2])
            } else {
                RGBColor(200, 200, 200)
            };
            let (a, b) = half(&map.x, i);
            let (c, d) = half(&map.y, j);
            cells.push(Rectangle::new([(a, c), (b, d)], colour.filled()));
        }
    }
    chart.draw_series(cells).map_err(draw_err)?;
    chart
        .draw_series(
            map.rings
                .iter()
                .map(|&p| Circle::new(p, 6, WHITE.stroke_width(2))),
        )
        .map_err(draw_err)?
        .label(map.rings_label.as_str())
        .legend(|(x, y)| Circle::new((x, y), 5, BLACK.stroke_width(2)));
    if let Some(p) = map.cross {
        chart
            .draw_series(std::iter::once(Cross::new(p, 8, RED.stroke_width(3))))
            .map_err(draw_err)?
            .label(map.cross_label.as_str())
            .legend(|(x, y)| Cross::new((x, y), 5, RED.stroke_width(2)));
    }
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
        .y_desc(map.value_label.as_str())
        .draw()
        .map_err(draw_err)?;
    let steps = 64;
    cb.draw_series((0..steps).map(|k| {
        let a = vmax * k as f64 / steps as f64;
        let b = vmax * (k + 1) as f64 / steps as f64;
        let c = viridis(1.0 - (a + b) / (2.0 * vmax));
        Rectangle::new([(0.0, a), (1.0, b)], RGBColor(c[0], c[1], c[2]).filled())
    }))
    .map_err(draw_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_every_cell_and_refuses_a_wrong_size() {
        let map = GridMap {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x: vec![0.0, 1.0, 2.0],
            y: vec![0.0, 0.5],
            values: vec![0.0, 1.0, 2.0, f64::NAN, 0.5, 1.5],
            value_label: "v".into(),
            rings: vec![(0.0, 0.0)],
            rings_label: "minima".into(),
            cross: Some((1.0, 0.5)),
            cross_label: "fit".into(),
        };
        let svg = grid_map_svg(&map).unwrap();
        // 6 cells + 64 colour-bar steps + the legend box are rectangles
        assert!(svg.matches("<rect").count() >= 6 + 64, "{}", svg.len());
        // the legend names both markers in text elements
        let texts: Vec<&str> = svg.split("<text").skip(1).collect();
        assert!(texts.iter().any(|t| t.contains("minima")));
        assert!(texts.iter().any(|t| t.contains("fit")));
        assert!(grid_map_png(&map).unwrap().starts_with(b"\x89PNG"));
        let bad = GridMap {
            values: vec![0.0; 5],
            ..map
        };
        assert!(grid_map_svg(&bad).is_err());
    }
}
