//! The figure layer of every command and of the demo: the palette, and
//! line figures as a grid of panels, each with its own axes and a
//! hand-laid legend, drawn by one code path to SVG ([`render`]) or PNG
//! ([`render_png`]). plotters' SVG backend writes `<text>` elements, so no
//! fonts are needed to view it; the legend is placed by hand because
//! plotters can only estimate text extents. Spectrogram heat maps and
//! waterfalls are in [`crate::heatmap_png`] and [`crate::waterfall_png`].

use crate::FigureError;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// One colour per input level or series: Tableau-10 without its grey, then
/// eleven colours chosen greedily for the largest CIELAB distance to all
/// before them (and to [`GREY`]), so that 20 curves stay distinct (smallest
/// pairwise distance ΔE76 ≈ 28, between purple and pink). The Python module
/// (`nlsdof.plot`) uses the same list.
pub const COLOURS: [RGBColor; 20] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 255),
    RGBColor(255, 34, 255),
    RGBColor(0, 51, 0),
    RGBColor(0, 17, 153),
    RGBColor(51, 34, 68),
    RGBColor(255, 0, 119),
    RGBColor(136, 102, 0),
    RGBColor(119, 187, 136),
    RGBColor(136, 0, 68),
    RGBColor(0, 119, 255),
    RGBColor(255, 136, 136),
];
/// Reference lines, backbones, measured points in the background.
pub const GREY: RGBColor = RGBColor(150, 150, 150);
/// Text-like dark lines.
pub const DARK: RGBColor = RGBColor(40, 40, 40);
/// Mesh lines of a chart (major, minor).
pub const MESH: (RGBColor, RGBColor) = (RGBColor(222, 222, 222), RGBColor(244, 244, 244));

/// The `i`-th colour of the palette (cycling after 20).
pub fn colour(i: usize) -> RGBColor {
    COLOURS[i % COLOURS.len()]
}

/// Dash patterns (pixels on, off) of the `i`-th cycle of the palette:
/// curve `i` is drawn in [`colour`]`(i)` with [`dash`]`(i)`, so that
/// curves 21 to 80 differ from curves 1 to 20 by their dash as well.
pub const DASHES: [Option<(u32, u32)>; 4] = [None, Some((9, 3)), Some((3, 3)), Some((12, 3))];

/// The line of curve `i` of width `w`: solid for the first 20 curves, then
/// the [`DASHES`] in turn.
pub fn dash(i: usize, w: u32) -> Style {
    match DASHES[(i / COLOURS.len()) % DASHES.len()] {
        None => Style::Line(w),
        Some((on, off)) => Style::DashPattern(w, on, off),
    }
}

/// Line and marker of a measured sweep direction, one convention in every
/// figure (and in `nlsdof.plot`): up-sweeps solid lines and filled dots,
/// down-sweeps dashed lines (7 on, 4 off) and hollow circles.
pub fn sweep_styles(up: bool, width: u32, radius: u32) -> (Style, Style) {
    if up {
        (Style::Line(width), Style::Filled(radius))
    } else {
        (Style::DashPattern(width, 7, 4), Style::Dots(radius + 1))
    }
}

/// One length unit for every figure of a run: the largest of m, mm, µm and
/// nm in which `peak_m` (metres) is at least 1, and its scale factor from
/// metres (`nlsdof.plot` chooses the same way).
pub fn length_unit(peak_m: f64) -> (&'static str, f64) {
    let peak = peak_m.abs();
    for (name, scale) in [("m", 1.0), ("mm", 1e3), ("µm", 1e6)] {
        if peak * scale >= 1.0 {
            return (name, scale);
        }
    }
    ("nm", 1e9)
}

/// The format of a figure file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Svg,
    Png,
}

/// [`render`] or [`render_png`], as the file's bytes.
pub fn render_as(
    format: Format,
    title: &str,
    panels: &[Panel],
    cols: usize,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, FigureError> {
    match format {
        Format::Svg => render(title, panels, cols, w, h).map(String::into_bytes),
        Format::Png => render_png(title, panels, cols, w, h),
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Style {
    /// Solid line of the given width.
    Line(u32),
    /// Dashed line of the given width.
    Dashed(u32),
    /// Dashed line: width, dash and gap lengths (pixels).
    DashPattern(u32, u32, u32),
    /// Hollow circles of the given radius.
    Dots(u32),
    /// Filled circles of the given radius.
    Filled(u32),
    /// Arrows of the given width, one from each even-indexed point to the
    /// next (e.g. a jump of a sweep), heads in pixels.
    Arrow(u32),
}

#[derive(Debug, Clone)]
pub struct Series {
    pub label: Option<String>,
    pub points: Vec<(f64, f64)>,
    pub colour: RGBColor,
    pub style: Style,
}

impl Series {
    pub fn new(points: Vec<(f64, f64)>, colour: RGBColor, style: Style) -> Self {
        Self {
            label: None,
            points,
            colour,
            style,
        }
    }
    pub fn label(mut self, l: impl Into<String>) -> Self {
        self.label = Some(l.into());
        self
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Corner {
    TopLeft,
    /// In a strip of [`LEGEND_W`] pixels right of the plot.
    Outside,
}

/// Width of the [`Corner::Outside`] legend strip before it is fitted to
/// the labels (the strip is as wide as the measured labels, at most half
/// the panel), pixels.
pub const LEGEND_W: u32 = 235;

#[derive(Debug, Clone)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    pub legend: Corner,
    /// Logarithmic y axis (values <= 0 are dropped).
    pub log_y: bool,
    /// Tick label of a value on a linear axis of the given span.
    pub tick_format: fn(f64, f64) -> String,
}

impl Panel {
    pub fn new(title: impl Into<String>, x_label: &str, y_label: &str) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            x_range: None,
            y_range: None,
            legend: Corner::TopLeft,
            log_y: false,
            tick_format: tick,
        }
    }
}

/// plotters lays text out with ab_glyph (enabled for the PNG figures), which
/// needs a registered font even for SVG output (`main` registers it too;
/// this keeps the module usable from tests).
fn ensure_font() {
    crate::fonts::register();
}

fn plot_err<E: std::fmt::Display>(e: E) -> FigureError {
    FigureError::Draw {
        figure: "a figure",
        detail: e.to_string(),
    }
}

/// Tick label with decimals suited to an axis spanning `span`.
pub(crate) fn tick(v: f64, span: f64) -> String {
    let decimals = (1.0 - span.abs().max(1e-300).log10().floor()).clamp(0.0, 8.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

fn auto_range(panel: &Panel) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in &panel.series {
        for &(x, y) in &s.points {
            if x.is_finite() && y.is_finite() {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    if x0.partial_cmp(&x1) != Some(std::cmp::Ordering::Less) {
        x0 = if x0.is_finite() { x0 - 1.0 } else { 0.0 };
        x1 = x0 + 2.0;
    }
    if y0.partial_cmp(&y1) != Some(std::cmp::Ordering::Less) {
        y0 = if y0.is_finite() { y0 - 1.0 } else { 0.0 };
        y1 = y0 + 2.0;
    }
    let pad = 0.05 * (y1 - y0);
    let x = panel.x_range.unwrap_or((x0, x1));
    let y = panel.y_range.unwrap_or((y0 - pad, y1 + pad));
    (x, y)
}

/// Renders `panels` in a grid of `cols` columns, each panel `w × h` pixels,
/// under a figure title. Returns the SVG document.
pub fn render(
    title: &str,
    panels: &[Panel],
    cols: usize,
    w: u32,
    h: u32,
) -> Result<String, FigureError> {
    ensure_font();
    let (width, height) = figure_size(panels, cols, w, h);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        draw_figure(&root, title, panels, cols)?;
    }
    Ok(svg)
}

/// The same figure as [`render`], as PNG bytes (drawn by the same code on
/// the bitmap backend).
pub fn render_png(
    title: &str,
    panels: &[Panel],
    cols: usize,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, FigureError> {
    ensure_font();
    let (width, height) = figure_size(panels, cols, w, h);
    let mut buf = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        draw_figure(&root, title, panels, cols)?;
    }
    crate::spectrogram::encode_png(&buf, width, height)
}

const TITLE_H: u32 = 40;

fn figure_size(panels: &[Panel], cols: usize, w: u32, h: u32) -> (u32, u32) {
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    (w * cols as u32, h * rows as u32 + TITLE_H)
}

fn draw_figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    panels: &[Panel],
    cols: usize,
) -> Result<(), FigureError> {
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    root.fill(&WHITE).map_err(plot_err)?;
    root.draw(&Text::new(
        title.to_string(),
        (16, 12),
        ("sans-serif", 21).into_font().color(&BLACK),
    ))
    .map_err(plot_err)?;
    let (_, body) = root.split_vertically(TITLE_H);
    let areas = body.split_evenly((rows, cols));
    // panels of one column share the widest outside legend strip, so that
    // their plot areas line up
    let mut strips = vec![0u32; cols];
    for (k, (panel, area)) in panels.iter().zip(areas.iter()).enumerate() {
        let entries: Vec<&Series> = panel.series.iter().filter(|s| s.label.is_some()).collect();
        if panel.legend == Corner::Outside && !entries.is_empty() {
            let w = legend_layout(area, &entries, panel.legend)?.strip_w;
            strips[k % cols] = strips[k % cols].max(w);
        }
    }
    for (k, (panel, area)) in panels.iter().zip(areas.iter()).enumerate() {
        draw_panel(root, area, panel, strips[k % cols])?;
    }
    root.present().map_err(plot_err)?;
    Ok(())
}

fn draw_panel<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
    min_strip: u32,
) -> Result<(), FigureError> {
    // the legend's entries and layout (measured with the embedded font)
    let entries: Vec<&Series> = panel.series.iter().filter(|s| s.label.is_some()).collect();
    let mut layout = legend_layout(area, &entries, panel.legend)?;
    layout.strip_w = layout.strip_w.max(min_strip);
    let (chart_area, legend_area) = if panel.legend == Corner::Outside && !entries.is_empty() {
        let (w, _) = area.dim_in_pixel();
        let (a, b) = area.split_horizontally(w.saturating_sub(layout.strip_w));
        (a, Some(b))
    } else {
        (area.clone(), None)
    };
    let area = &chart_area;
    // a log axis is drawn as log10 of the values with labels 10^v
    let logged;
    let panel = if panel.log_y {
        let mut p = panel.clone();
        for s in &mut p.series {
            s.points = s
                .points
                .iter()
                .filter(|q| q.1 > 0.0)
                .map(|&(x, y)| (x, y.log10()))
                .collect();
        }
        p.y_range = panel.y_range.map(|(a, b)| (a.log10(), b.log10()));
        logged = p;
        &logged
    } else {
        panel
    };
    let ((x0, x1), (y0, y1)) = auto_range(panel);
    let (xs, ys) = (x1 - x0, y1 - y0);
    let fmt = panel.tick_format;
    let x_fmt = |v: &f64| fmt(*v, xs);
    let log_y = panel.log_y;
    let y_fmt = move |v: &f64| {
        if log_y {
            let p = 10f64.powf(*v);
            let d = (1.0 - p.log10().floor()).clamp(0.0, 8.0) as usize;
            format!("{p:.d$}")
        } else {
            fmt(*v, ys)
        }
    };
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 17))
        .margin(10)
        .margin_right(18)
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .x_labels(8)
        .y_labels(7)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .axis_desc_style(("sans-serif", 15))
        .label_style(("sans-serif", 14))
        .bold_line_style(MESH.0)
        .light_line_style(MESH.1)
        // no axis lines or tick marks from plotters (they would be SVG
        // polylines, beside the data's): the plot area gets a frame below
        // and the grid carries the ticks
        .axis_style(TRANSPARENT)
        .draw()
        .map_err(plot_err)?;
    let (fx, fy) = chart.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(fx.start, fy.start), (fx.end, fy.end)],
        DARK.stroke_width(1),
    ))
    .map_err(plot_err)?;
    let inside = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && x >= x0 && x <= x1 && y >= y0 && y <= y1
    };
    for s in &panel.series {
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|(x, y)| (x, y.clamp(y0, y1)))
            .collect();
        // one point per pixel: repeated pixels make zero-length segments,
        // whose joins the bitmap backend draws as long spikes
        let mut last = None;
        let pts: Vec<(f64, f64)> = pts
            .into_iter()
            .filter(|p| {
                let px = chart.backend_coord(p);
                let keep = last != Some(px);
                last = Some(px);
                keep
            })
            .collect();
        match s.style {
            Style::Line(wd) => {
                chart
                    .draw_series(LineSeries::new(pts, s.colour.stroke_width(wd)))
                    .map_err(plot_err)?;
            }
            Style::Dashed(wd) => {
                chart
                    .draw_series(DashedLineSeries::new(pts, 6, 4, s.colour.stroke_width(wd)))
                    .map_err(plot_err)?;
            }
            Style::DashPattern(wd, on, off) => {
                chart
                    .draw_series(DashedLineSeries::new(
                        pts,
                        on.max(1),
                        off,
                        s.colour.stroke_width(wd),
                    ))
                    .map_err(plot_err)?;
            }
            Style::Dots(r) => {
                chart
                    .draw_series(
                        s.points
                            .iter()
                            .filter(|p| inside(p))
                            .map(|&p| Circle::new(p, r, s.colour.stroke_width(1))),
                    )
                    .map_err(plot_err)?;
            }
            Style::Filled(r) => {
                chart
                    .draw_series(
                        s.points
                            .iter()
                            .filter(|p| inside(p))
                            .map(|&p| Circle::new(p, r, s.colour.filled())),
                    )
                    .map_err(plot_err)?;
            }
            Style::Arrow(wd) => {
                for pair in s.points.chunks_exact(2) {
                    let from = chart.backend_coord(&pair[0]);
                    let to = chart.backend_coord(&pair[1]);
                    draw_arrow(root, from, to, s.colour, wd)?;
                }
            }
        }
    }
    // legend, by hand, in pixels
    if entries.is_empty() {
        return Ok(());
    }
    let (px0, py0) = chart.backend_coord(&(x0, y1));
    let LegendLayout {
        row,
        col_w,
        per_col,
        ..
    } = layout;
    let font = LEGEND_FONT;
    let n_cols = entries.len().div_ceil(per_col.max(1)) as i32;
    let box_w = col_w * n_cols;
    let box_h = row * entries.len().min(per_col) as i32 + 8;
    let (bx, by) = match (panel.legend, &legend_area) {
        (Corner::Outside, Some(la)) => {
            let (ox, oy) = la.get_base_pixel();
            let (_, lh) = la.dim_in_pixel();
            // level with the plot's top, moved up if it would run off
            (
                ox + 4,
                (py0 + 8).min(oy + lh as i32 - box_h - 2).max(oy + 2),
            )
        }
        _ => (px0 + 8, py0 + 8),
    };
    root.draw(&Rectangle::new(
        [(bx, by), (bx + box_w, by + box_h)],
        ShapeStyle::from(&WHITE.mix(0.85)).filled(),
    ))
    .map_err(plot_err)?;
    root.draw(&Rectangle::new(
        [(bx, by), (bx + box_w, by + box_h)],
        RGBColor(200, 200, 200).stroke_width(1),
    ))
    .map_err(plot_err)?;
    for (i, s) in entries.iter().enumerate() {
        let (c, r) = ((i / per_col) as i32, (i % per_col) as i32);
        let bx = bx + c * col_w;
        let y = by + 4 + row * r + row / 2;
        let (lx0, lx1) = (bx + 6, bx + 32);
        match s.style {
            // a solid swatch is a filled bar, so that the SVG's polylines
            // are the data's lines only (scripts count them)
            Style::Line(wd) => {
                let h = wd.max(2) as i32;
                root.draw(&Rectangle::new(
                    [(lx0, y - h / 2), (lx1, y - h / 2 + h)],
                    s.colour.filled(),
                ))
                .map_err(plot_err)?
            }
            Style::Dashed(wd) => root
                .draw(&DashedPathElement::new(
                    vec![(lx0, y), (lx1, y)],
                    6,
                    4,
                    s.colour.stroke_width(wd.max(2)),
                ))
                .map_err(plot_err)?,
            Style::DashPattern(wd, on, off) => root
                .draw(&DashedPathElement::new(
                    vec![(lx0, y), (lx1, y)],
                    on.max(1),
                    off,
                    s.colour.stroke_width(wd.max(1)),
                ))
                .map_err(plot_err)?,
            // marker swatches are polygons, so that the SVG's circles are
            // the data's points only (scripts count them)
            Style::Dots(r) => {
                let c = ((lx0 + lx1) / 2, y);
                let r = r.max(3) as f64;
                root.draw(&Polygon::new(octagon(c, r + 0.5), s.colour.filled()))
                    .map_err(plot_err)?;
                root.draw(&Polygon::new(octagon(c, r - 1.0), WHITE.filled()))
                    .map_err(plot_err)?
            }
            Style::Filled(r) => {
                let c = ((lx0 + lx1) / 2, y);
                root.draw(&Polygon::new(
                    octagon(c, r.max(3) as f64 + 0.5),
                    s.colour.filled(),
                ))
                .map_err(plot_err)?
            }
            Style::Arrow(wd) => {
                let x = (lx0 + lx1) / 2;
                draw_arrow(root, (x, y - row / 2), (x, y + row / 2), s.colour, wd)?
            }
        }
        root.draw(&Text::new(
            s.label.clone().unwrap_or_default(),
            (bx + 40, y - font / 2 - 1),
            ("sans-serif", font as u32).into_font().color(&BLACK),
        ))
        .map_err(plot_err)?;
    }
    Ok(())
}

/// Font size of legend entries as asked of plotters (which writes
/// `size / 1.24` px: 14 gives 11.3 px).
const LEGEND_FONT: i32 = 14;

/// Where a legend's entries go: rows of `row` pixels, columns of `col_w`
/// pixels with `per_col` entries each, in a strip `strip_w` pixels wide
/// ([`Corner::Outside`]).
#[derive(Debug, Clone, Copy)]
struct LegendLayout {
    row: i32,
    col_w: i32,
    per_col: usize,
    strip_w: u32,
}

/// Lays the legend out from the labels' measured widths: one column when
/// the entries fit the panel's height, more columns side by side otherwise;
/// an outside strip as wide as the columns (at most half the panel).
fn legend_layout<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    entries: &[&Series],
    corner: Corner,
) -> Result<LegendLayout, FigureError> {
    let row = 18;
    let font: TextStyle = ("sans-serif", LEGEND_FONT as u32).into();
    let mut text_w = 0;
    for s in entries {
        let l = s.label.as_deref().unwrap_or("");
        let w = area
            .estimate_text_size(l, &font)
            .map(|(w, _)| w as i32)
            // no font: the width of DejaVu Sans' average glyph at 12 px
            .unwrap_or(l.chars().count() as i32 * 7);
        text_w = text_w.max(w);
    }
    let col_w = 40 + text_w + 16;
    let (aw, ah) = area.dim_in_pixel();
    // the rows that fit between the plot's top and the panel's bottom
    let usable = (ah as i32 - 60).max(row);
    let per_col = ((usable - 8) / row).max(1) as usize;
    let n_cols = entries.len().div_ceil(per_col).max(1) as i32;
    let strip_w = match corner {
        Corner::Outside => ((col_w * n_cols + 16) as u32).min(aw / 2).max(60),
        Corner::TopLeft => 0,
    };
    Ok(LegendLayout {
        row,
        col_w,
        per_col,
        strip_w,
    })
}

/// The corners of a regular octagon of radius `r` around `c` (pixels).
fn octagon(c: (i32, i32), r: f64) -> Vec<(i32, i32)> {
    (0..8)
        .map(|k| {
            let t = std::f64::consts::PI * (k as f64 + 0.5) / 4.0;
            (
                c.0 + (r * t.cos()).round() as i32,
                c.1 + (r * t.sin()).round() as i32,
            )
        })
        .collect()
}

/// A vertical arrow in pixels (`from` and `to` share x), head at `to`.
fn draw_arrow<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    from: (i32, i32),
    to: (i32, i32),
    c: RGBColor,
    width: u32,
) -> Result<(), FigureError> {
    let dy = to.1 - from.1;
    let head = 9.min(dy.abs());
    let base = to.1 - dy.signum() * head;
    root.draw(&PathElement::new(
        vec![from, (to.0, base)],
        c.stroke_width(width),
    ))
    .map_err(plot_err)?;
    if head > 0 {
        root.draw(&Polygon::new(
            vec![(to.0 - 5, base), (to.0 + 5, base), to],
            c.filled(),
        ))
        .map_err(plot_err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks() {
        assert_eq!(tick(5.25, 0.2), "5.25");
        assert_eq!(tick(-0.0, 1.0), "0.0");
        assert_eq!(tick(12.0, 40.0), "12");
    }

    #[test]
    fn renders_panels_and_legend() {
        let mut p = Panel::new("a panel", "x [Hz]", "y [m]");
        p.series.push(
            Series::new(vec![(0.0, 1.0), (1.0, 2.0)], colour(0), Style::Line(2)).label("line"),
        );
        p.series
            .push(Series::new(vec![(0.5, 1.5)], colour(1), Style::Dots(2)).label("dots"));
        let svg = render("title", &[p.clone(), p.clone()], 2, 400, 300).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("a panel") && svg.contains("dots"));
        let png = render_png("title", &[p.clone(), p], 2, 400, 300).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
    }
}
