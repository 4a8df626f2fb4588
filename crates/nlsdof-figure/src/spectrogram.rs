//! PNG figures of STFT spectrograms (paper Fig 8): a 2-D heat map and a
//! 3-D waterfall, panels side by side (e.g. measurement and model).
//!
//! A spectrogram of the paper's record has ~10^6–10^7 cells, far too many
//! for SVG, so these are bitmaps: plotters draws axes and text into an
//! in-memory RGB buffer (`BitMapBackend::with_buffer`; text rasterised by
//! ab_glyph from DejaVu Sans embedded in the binary, no system fonts), the
//! cells are painted into the same buffer aggregated to pixels (**maximum**
//! of the bins falling in a pixel, so a narrow peak never disappears), and
//! the buffer is PNG-encoded (`image` crate) and returned; the caller
//! writes it (the CLI atomically: the file appears complete or not at all).
//!
//! * Heat map: time [s] across, frequency [Hz] up, colour = level in dB
//!   (`20 log10` of an amplitude spectrogram, `10 log10` of a PSD; the
//!   scale is shared by all panels and spans [`DYNAMIC_RANGE_DB`] below the
//!   largest value), with a colour bar. Each segment is a column of width
//!   one hop centred on its segment centre.
//! * Waterfall: one trace per segment (the spectrum, linear scale shared by
//!   the panels) on a frequency axis, stacked in depth along a time axis,
//!   drawn back to front with hidden-line removal.

use crate::FigureError;
use nlsdof::signal_processing::stft::{Scaling, Spectrogram};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Colour scale span of the heat map, dB below the maximum.
pub const DYNAMIC_RANGE_DB: f64 = 80.0;
const PANEL_W: u32 = 620;
const PANEL_H: u32 = 560;
const TITLE_H: u32 = 44;
const BAR_W: u32 = 130;
const FONT: &str = "sans-serif";

fn init_font() {
    crate::fonts::register();
}

fn draw_err<E: std::fmt::Display>(e: E) -> FigureError {
    FigureError::Draw {
        figure: "the spectrogram figure",
        detail: e.to_string(),
    }
}

/// White background and the centred figure title (`w` pixels wide);
/// returns the area below the title.
fn titled<'a>(
    root: &DrawingArea<BitMapBackend<'a>, Shift>,
    title: &str,
    w: u32,
) -> Result<DrawingArea<BitMapBackend<'a>, Shift>, FigureError> {
    root.fill(&WHITE).map_err(draw_err)?;
    let (top, body) = root.split_vertically(TITLE_H);
    top.draw(&Text::new(
        title.to_string(),
        ((w / 2) as i32, (TITLE_H / 2) as i32),
        (FONT, 22)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))
    .map_err(draw_err)?;
    Ok(body)
}

/// Viridis (matplotlib), 9 anchors, linear interpolation; `u` in [0, 1].
pub fn viridis(u: f64) -> [u8; 3] {
    const A: [[f64; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [71.0, 44.0, 122.0],
        [59.0, 81.0, 139.0],
        [44.0, 113.0, 142.0],
        [33.0, 144.0, 141.0],
        [39.0, 173.0, 129.0],
        [92.0, 200.0, 99.0],
        [170.0, 220.0, 50.0],
        [253.0, 231.0, 37.0],
    ];
    let u = if u.is_finite() {
        u.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = u * 8.0;
    let i = (x.floor() as usize).min(7);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for j in 0..3 {
        c[j] = (A[i][j] + f * (A[i + 1][j] - A[i][j])).round() as u8;
    }
    c
}

/// The bins shown: `f_range` (clipped to the grid) or all.
fn band(s: &Spectrogram, f_range: Option<(f64, f64)>) -> (f64, f64, std::ops::Range<usize>) {
    let f_last = s.frequencies.last().copied().unwrap_or(0.0);
    let (lo, hi) = match f_range {
        Some((a, b)) => (a.max(0.0), b.min(f_last).max(a.max(0.0))),
        None => (s.frequencies.first().copied().unwrap_or(0.0), f_last),
    };
    let r = s.band(lo, hi);
    // a single bin (or a degenerate range) still gets an axis of one bin width
    let df = match s.frequencies.as_slice() {
        [a, b, ..] => b - a,
        _ => 1.0,
    };
    (lo, if hi > lo { hi } else { lo + df }, r)
}

fn check_panels(
    panels: &[(&str, &Spectrogram)],
    f_range: Option<(f64, f64)>,
) -> Result<(), FigureError> {
    if panels.is_empty() {
        return Err(FigureError::NoSpectrogram);
    }
    if let Some((a, b)) = f_range {
        if !(a.is_finite() && b.is_finite() && a < b) {
            return Err(FigureError::BadFrequencyRange { min: a, max: b });
        }
    }
    for (label, s) in panels {
        if s.n_time == 0 || s.n_freq == 0 || s.magnitude.len() != s.n_time * s.n_freq {
            return Err(FigureError::MalformedSpectrogram {
                label: label.to_string(),
                n_time: s.n_time,
                n_freq: s.n_freq,
                values: s.magnitude.len(),
            });
        }
        let (_, _, r) = band(s, f_range);
        if r.is_empty() {
            let (a, b) = f_range.unwrap_or((0.0, 0.0));
            return Err(FigureError::NoBinInRange {
                label: label.to_string(),
                min: a,
                max: b,
                first: s.frequencies[0],
                last: s.frequencies[s.n_freq - 1],
            });
        }
    }
    Ok(())
}

/// Time extent of the cells: segment centres ± half a hop.
fn time_extent(s: &Spectrogram) -> (f64, f64, f64) {
    let t0 = s.times[0];
    let hop = if s.n_time > 1 {
        s.times[1] - s.times[0]
    } else {
        2.0 * t0.abs().max(1e-9)
    };
    (t0 - hop / 2.0, s.times[s.n_time - 1] + hop / 2.0, hop)
}

/// "Nice" tick values (1, 2, 5 × 10^k) covering [lo, hi], about `n` of them.
fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if hi.is_nan() || lo.is_nan() || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / n.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut v = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while v <= hi + step * 1e-9 {
        out.push(if v.abs() < step * 1e-9 { 0.0 } else { v });
        v += step;
    }
    out
}

fn fmt_tick(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    format!("{v:.decimals$}")
}

/// Shortest plain decimal form (up to 6 decimals): 100.0 -> "100", 5.25 -> "5.25".
fn fmt_auto(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

fn db_label(s: Scaling) -> &'static str {
    match s {
        Scaling::Amplitude => "level, 20 log10(amplitude) [dB]",
        Scaling::Psd => "level, 10 log10(PSD) [dB]",
    }
}

/// PNG bytes of an RGB8 buffer `w × h`.
pub fn encode_png(buf: &[u8], w: u32, h: u32) -> Result<Vec<u8>, FigureError> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(buf, w, h, image::ColorType::Rgb8)
        .map_err(|e| FigureError::Encode(e.to_string()))?;
    Ok(out)
}

/// The heat-map figure as PNG bytes.
pub fn heatmap_png(
    panels: &[(&str, &Spectrogram)],
    f_range: Option<(f64, f64)>,
    title: &str,
) -> Result<Vec<u8>, FigureError> {
    check_panels(panels, f_range)?;
    init_font();
    let scaling = panels[0].1.scaling;
    // shared colour scale
    let mut vmax = 0.0f64;
    for (_, s) in panels {
        let (_, _, r) = band(s, f_range);
        for t in 0..s.n_time {
            vmax = s.row(t)[r.clone()].iter().fold(vmax, |m, &v| m.max(v));
        }
    }
    let db_hi = if vmax > 0.0 {
        scaling.to_db(vmax).ceil()
    } else {
        0.0
    };
    let db_lo = db_hi - DYNAMIC_RANGE_DB;
    let np = panels.len() as u32;
    let (w, h) = (PANEL_W * np + BAR_W, PANEL_H + TITLE_H);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    // pass 1: axes, labels, title (plotters); remember the plot rectangles
    let mut rects = Vec::new();
    let bar_rect;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let body = titled(&root, title, w)?;
        let (maps, bar) = body.split_horizontally(PANEL_W * np);
        for ((label, s), area) in panels.iter().zip(maps.split_evenly((1, panels.len()))) {
            let (lo, hi, _) = band(s, f_range);
            let (t_lo, t_hi, _) = time_extent(s);
            let mut chart = ChartBuilder::on(&area)
                .caption(*label, (FONT, 18))
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(66)
                .build_cartesian_2d(t_lo..t_hi, lo..hi)
                .map_err(draw_err)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc("time [s]")
                .y_desc("frequency [Hz]")
                .x_label_formatter(&|v| fmt_auto(*v))
                .y_label_formatter(&|v| fmt_auto(*v))
                .label_style((FONT, 14))
                .axis_desc_style((FONT, 15))
                .draw()
                .map_err(draw_err)?;
            rects.push(chart.plotting_area().get_pixel_range());
        }
        let mut cb = ChartBuilder::on(&bar)
            .margin_top(12 + 24)
            .margin_bottom(12 + 44)
            .margin_right(12)
            .y_label_area_size(0)
            .right_y_label_area_size(64)
            .build_cartesian_2d(0.0..1.0, db_lo..db_hi)
            .map_err(draw_err)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(db_label(scaling))
            .y_label_formatter(&|v| fmt_auto(*v))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 13))
            .draw()
            .map_err(draw_err)?;
        bar_rect = cb.plotting_area().get_pixel_range();
        root.present().map_err(draw_err)?;
    }
    // pass 2: paint the cells into the plot rectangles (inside the axis lines)
    let put = |buf: &mut [u8], x: i32, y: i32, c: [u8; 3]| {
        let i = ((y as u32 * w + x as u32) * 3) as usize;
        buf[i..i + 3].copy_from_slice(&c);
    };
    let colour = |v: f64| {
        let db = if v > 0.0 {
            scaling.to_db(v)
        } else {
            f64::NEG_INFINITY
        };
        viridis((db - db_lo) / DYNAMIC_RANGE_DB)
    };
    for ((_, s), (xr, yr)) in panels.iter().zip(&rects) {
        let (lo, hi, r) = band(s, f_range);
        let (t_lo, t_hi, hop) = time_extent(s);
        let (x0, x1) = (xr.start + 1, xr.end - 1);
        let (y0, y1) = (yr.start + 1, yr.end - 1);
        if x1 <= x0 || y1 <= y0 {
            continue;
        }
        let nx = (x1 - x0) as usize;
        let ny = (y1 - y0) as usize;
        let df = if s.n_freq > 1 {
            s.frequencies[1] - s.frequencies[0]
        } else {
            1.0
        };
        let f_first = s.frequencies[0];
        // per pixel row: the bin range it covers (at least the nearest bin)
        let rows: Vec<(usize, usize)> = (0..ny)
            .map(|py| {
                // py = 0 is the top (hi)
                let fa = hi - (py as f64 + 1.0) / ny as f64 * (hi - lo);
                let fb = hi - py as f64 / ny as f64 * (hi - lo);
                let ka = ((fa - f_first) / df).ceil().max(r.start as f64) as usize;
                let kb = (((fb - f_first) / df).floor().min((r.end - 1) as f64)).max(0.0) as usize;
                if ka <= kb {
                    (ka, kb + 1)
                } else {
                    let fc = 0.5 * (fa + fb);
                    let k = ((fc - f_first) / df)
                        .round()
                        .clamp(r.start as f64, (r.end - 1) as f64)
                        as usize;
                    (k, k + 1)
                }
            })
            .collect();
        // per segment: the column of pixel values (max over bins)
        let cols: Vec<Vec<[u8; 3]>> = (0..s.n_time)
            .map(|t| {
                let row = s.row(t);
                rows.iter()
                    .map(|&(a, b)| colour(row[a..b].iter().fold(0.0f64, |m, &v| m.max(v))))
                    .collect()
            })
            .collect();
        for px in 0..nx {
            let tc = t_lo + (px as f64 + 0.5) / nx as f64 * (t_hi - t_lo);
            let seg = ((tc - s.times[0]) / hop)
                .round()
                .clamp(0.0, (s.n_time - 1) as f64) as usize;
            for (py, &c) in cols[seg].iter().enumerate() {
                put(&mut buf, x0 + px as i32, y0 + py as i32, c);
            }
        }
    }
    let (xr, yr) = bar_rect;
    let (x0, x1, y0, y1) = (xr.start + 1, xr.end - 1, yr.start + 1, yr.end - 1);
    for py in y0..y1.max(y0) {
        let u = 1.0 - (py - y0) as f64 / ((y1 - y0).max(1) - 1).max(1) as f64;
        let c = viridis(u);
        for px in x0..x1.max(x0) {
            put(&mut buf, px, py, c);
        }
    }
    encode_png(&buf, w, h)
}

/// The waterfall figure as PNG bytes.
pub fn waterfall_png(
    panels: &[(&str, &Spectrogram)],
    f_range: Option<(f64, f64)>,
    title: &str,
) -> Result<Vec<u8>, FigureError> {
    check_panels(panels, f_range)?;
    init_font();
    let mut vmax = 0.0f64;
    for (_, s) in panels {
        let (_, _, r) = band(s, f_range);
        for t in 0..s.n_time {
            vmax = s.row(t)[r.clone()].iter().fold(vmax, |m, &v| m.max(v));
        }
    }
    if vmax.is_nan() || vmax <= 0.0 {
        vmax = 1.0;
    }
    let np = panels.len() as u32;
    let (w, h) = (PANEL_W * np, PANEL_H + TITLE_H);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let body = titled(&root, title, w)?;
        for ((label, s), area) in panels.iter().zip(body.split_evenly((1, panels.len()))) {
            draw_waterfall(&area, label, s, f_range, vmax).map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    encode_png(&buf, w, h)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

fn draw_waterfall(
    area: &Area<'_>,
    label: &str,
    s: &Spectrogram,
    f_range: Option<(f64, f64)>,
    vmax: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let (pw, ph) = area.dim_in_pixel();
    let (pw, ph) = (pw as f64, ph as f64);
    let (lo, hi, r) = band(s, f_range);
    let (t_first, t_last) = (s.times[0], s.times[s.n_time - 1]);
    // geometry (pixels): front baseline from (ax, ay), length fw; depth
    // vector (dx, -dy) spans the time axis; amplitude height ah.
    let ax = 78.0;
    let ay = ph - 70.0;
    let fw = pw * 0.62;
    let (dx, dy) = (pw * 0.20, ph * 0.36);
    let ah = ph * 0.45;
    let tn = |t: f64| {
        if t_last > t_first {
            (t - t_first) / (t_last - t_first)
        } else {
            0.0
        }
    };
    let proj = |fnorm: f64, tnorm: f64, anorm: f64| -> (i32, i32) {
        (
            (ax + fnorm * fw + tnorm * dx).round() as i32,
            (ay - tnorm * dy - anorm * ah).round() as i32,
        )
    };
    let text = |size: u32| (FONT, size).into_font().color(&BLACK);
    let grey = RGBColor(150, 150, 150);
    area.draw(&Text::new(
        label.to_string(),
        ((pw / 2.0) as i32, 8),
        text(18).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    // floor outline (left and back edges)
    let floor = vec![
        proj(0.0, 0.0, 0.0),
        proj(0.0, 1.0, 0.0),
        proj(1.0, 1.0, 0.0),
    ];
    area.draw(&PathElement::new(floor, grey.stroke_width(1)))?;
    let a_ticks = nice_ticks(0.0, vmax, 4);
    let a_step = if a_ticks.len() > 1 {
        a_ticks[1] - a_ticks[0]
    } else {
        vmax
    };
    // traces, back to front, each filled white below (hidden-line removal)
    let ncol = fw.round().max(2.0) as usize;
    let df = s
        .frequencies
        .get(1)
        .map(|f| f - s.frequencies[0])
        .unwrap_or(1.0);
    let f_first = s.frequencies[0];
    let cols: Vec<(usize, usize)> = (0..ncol)
        .map(|c| {
            let fa = lo + c as f64 / ncol as f64 * (hi - lo);
            let fb = lo + (c as f64 + 1.0) / ncol as f64 * (hi - lo);
            let ka = ((fa - f_first) / df).ceil().max(r.start as f64) as usize;
            let kb = (((fb - f_first) / df).floor().min((r.end - 1) as f64)).max(0.0) as usize;
            if ka <= kb {
                (ka, kb + 1)
            } else {
                let k = ((0.5 * (fa + fb) - f_first) / df)
                    .round()
                    .clamp(r.start as f64, (r.end - 1) as f64) as usize;
                (k, k + 1)
            }
        })
        .collect();
    for t in (0..s.n_time).rev() {
        let row = s.row(t);
        let tnorm = tn(s.times[t]);
        let pts: Vec<(i32, i32)> = cols
            .iter()
            .enumerate()
            .map(|(c, &(a, b))| {
                let v = row[a..b].iter().fold(0.0f64, |m, &v| m.max(v));
                proj((c as f64 + 0.5) / ncol as f64, tnorm, (v / vmax).min(1.0))
            })
            .collect();
        let mut poly = pts.clone();
        poly.push(proj(1.0, tnorm, 0.0));
        poly.push(proj(0.0, tnorm, 0.0));
        area.draw(&Polygon::new(poly, WHITE.filled()))?;
        let [r8, g8, b8] = viridis(0.85 * (1.0 - tnorm));
        area.draw(&PathElement::new(pts, RGBColor(r8, g8, b8).stroke_width(1)))?;
    }
    // front axes: frequency along the front baseline, time along the right edge
    area.draw(&PathElement::new(
        vec![
            proj(0.0, 0.0, 0.0),
            proj(1.0, 0.0, 0.0),
            proj(1.0, 1.0, 0.0),
        ],
        BLACK.stroke_width(1),
    ))?;
    let f_ticks = nice_ticks(lo, hi, 5);
    let f_step = if f_ticks.len() > 1 {
        f_ticks[1] - f_ticks[0]
    } else {
        1.0
    };
    for &f in &f_ticks {
        let (x, y) = proj((f - lo) / (hi - lo).max(f64::MIN_POSITIVE), 0.0, 0.0);
        area.draw(&PathElement::new(
            vec![(x, y), (x, y + 5)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            fmt_tick(f, f_step),
            (x, y + 8),
            text(13).pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
    }
    let (fx, fy) = proj(0.5, 0.0, 0.0);
    area.draw(&Text::new(
        "frequency [Hz]",
        (fx, fy + 30),
        text(15).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    let t_ticks = nice_ticks(t_first, t_last, 5);
    let t_step = if t_ticks.len() > 1 {
        t_ticks[1] - t_ticks[0]
    } else {
        1.0
    };
    for &t in &t_ticks {
        let (x, y) = proj(1.0, tn(t), 0.0);
        area.draw(&PathElement::new(
            vec![(x, y), (x + 6, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            fmt_tick(t, t_step),
            (x + 9, y),
            text(13).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    let (tx, ty) = proj(1.0, 0.5, 0.0);
    area.draw(&Text::new(
        "time [s]",
        (tx + 28, ty + 22),
        text(15).pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    // amplitude axis on the front-left vertical edge (reads the first
    // segment's trace directly; later traces stand on their own baselines)
    area.draw(&PathElement::new(
        vec![proj(0.0, 0.0, 0.0), proj(0.0, 0.0, 1.0)],
        BLACK.stroke_width(1),
    ))?;
    for &a in &a_ticks {
        let (x, y) = proj(0.0, 0.0, a / vmax);
        area.draw(&PathElement::new(
            vec![(x - 5, y), (x, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            format_amplitude(a, a_step),
            (x - 8, y),
            text(13).pos(Pos::new(HPos::Right, VPos::Center)),
        ))?;
    }
    let (vx, vy) = proj(0.0, 0.0, 1.0);
    area.draw(&Text::new(
        match s.scaling {
            Scaling::Amplitude => "amplitude (0-peak, signal unit)",
            Scaling::Psd => "PSD [unit^2/Hz]",
        },
        (vx - 40, vy - 14),
        text(14).pos(Pos::new(HPos::Left, VPos::Bottom)),
    ))?;
    Ok(())
}

fn format_amplitude(a: f64, step: f64) -> String {
    if a == 0.0 {
        return "0".into();
    }
    let mag = step.abs().log10().floor();
    if (-3.0..4.0).contains(&mag) {
        fmt_tick(a, step)
    } else {
        let m = a.abs().log10().floor().min(mag + 2.0);
        let digits = (m - mag).max(0.0) as usize;
        format!("{:.*e}", digits, a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_and_colours() {
        assert_eq!(
            nice_ticks(0.0, 1.0, 5),
            vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
        );
        let t = nice_ticks(5.3, 5.5, 4);
        assert!(t.len() >= 3 && t[0] >= 5.3 && *t.last().unwrap() <= 5.5 + 1e-12);
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(f64::NAN), [68, 1, 84]);
        assert_eq!(format_amplitude(2e-5, 1e-5), "2e-5");
    }
}
