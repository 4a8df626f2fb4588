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

const W: u32 = 860;
const H: u32 = 680;
/// Height of the legend strip under the map, pixels.
const LEGEND_H: u32 = 36;

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
    if nx * ny < 2 {
        return Err(FigureError::Draw {
            figure: "the grid map",
            detail: "a single node has nothing to map (draw it as a value, or a 1-D profile)"
                .into(),
        });
    }
    let vmax = map
        .values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    // a flat map (every value 0) still gets a readable colour bar
    let vmax = if vmax > 1e-9 { vmax } else { 1.0 };
    let (x0, _) = half(&map.x, 0);
    let (_, x1) = half(&map.x, nx - 1);
    let (y0, _) = half(&map.y, 0);
    let (_, y1) = half(&map.y, ny - 1);
    let (upper, legend) = root.split_vertically(H - LEGEND_H);
    let (main, bar) = upper.split_horizontally(W - 120);
    let mut chart = ChartBuilder::on(&main)
        .caption(&map.title, ("sans-serif", 19))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(62)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(draw_err)?;
    let (xs, ys) = (x1 - x0, y1 - y0);
    let x_fmt = |v: &f64| crate::panel::tick(*v, xs);
    let y_fmt = |v: &f64| crate::panel::tick(*v, ys);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(map.x_label.as_str())
        .y_desc(map.y_label.as_str())
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 15))
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
        .map_err(draw_err)?;
    if let Some(p) = map.cross {
        chart
            .draw_series(std::iter::once(Cross::new(p, 8, RED.stroke_width(3))))
            .map_err(draw_err)?;
    }
    // the map's frame (as the line figures' plot areas have)
    let (fx, fy) = chart.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(fx.start, fy.start), (fx.end, fy.end)],
        crate::DARK.stroke_width(1),
    ))
    .map_err(draw_err)?;
    // the legend, in its strip under the map (off the cells)
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    let (lx, ly) = legend.get_base_pixel();
    let y = ly + LEGEND_H as i32 / 2;
    let mut x = lx + 80;
    let entries: [(Option<&str>, bool); 2] = [
        (Some(map.rings_label.as_str()), true),
        (map.cross.map(|_| map.cross_label.as_str()), false),
    ];
    for (label, ring) in entries {
        let Some(label) = label else { continue };
        if ring {
            root.draw(&Circle::new((x, y), 6, BLACK.stroke_width(2)))
                .map_err(draw_err)?;
        } else {
            root.draw(&Cross::new((x, y), 6, RED.stroke_width(3)))
                .map_err(draw_err)?;
        }
        root.draw(&Text::new(
            label.to_string(),
            (x + 14, y),
            font.pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Left,
                plotters::style::text_anchor::VPos::Center,
            )),
        ))
        .map_err(draw_err)?;
        let (w, _) = root.estimate_text_size(label, &font).unwrap_or((200, 13));
        x += 14 + w as i32 + 40;
    }
    // colour bar
    let mut cb = ChartBuilder::on(&bar)
        .margin_top(44)
        .margin_bottom(60)
        .margin_right(10)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..1.0, 0.0..vmax)
        .map_err(draw_err)?;
    let cb_fmt = |v: &f64| crate::panel::tick(*v, vmax);
    cb.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(map.value_label.as_str())
        .y_labels(8)
        .y_label_formatter(&cb_fmt)
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 15))
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
    let (fx, fy) = cb.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(fx.start, fy.start), (fx.end, fy.end)],
        crate::DARK.stroke_width(1),
    ))
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
