//! SVG plot of `nlsdof frf`: amplitude (zero-to-peak) vs frequency (Hz).
//!
//! Drawn with `plotters` using only its SVG backend (no bitmap backend, no
//! `ttf`/font-kit): the SVG backend writes text as `<text>` elements that the
//! viewer renders, so no system fonts are needed at run time; plotters only
//! estimates text extents for layout, which is why the legend is laid out by
//! hand in its own panel on the right instead of plotters' legend box.
//!
//! Contents, per input level (one colour each):
//! * all steady-state branches: `steady_states` on ~600 frequencies plus the
//!   fold frequencies; roots of equal rank (index in the amplitude-sorted
//!   list) are connected between consecutive samples with equal root count,
//!   and across a fold the two roots born/dying there are joined to the fold
//!   point. Stable segments solid, unstable dashed;
//! * the swept points as small circles and each jump as a vertical arrow;
//! * the backbone (undamped free-vibration frequency vs amplitude) dotted grey.

use crate::error::CliError;
use crate::figure::{colour, GREY, MESH};
use nlsdof::harmonic_balance::branches::{trace_branches, BranchOptions, TracedBranch};
use nlsdof::{backbone, Formulation, LevelResponse, NormalisedModel, SweepDirection};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::f64::consts::PI;

/// Frequencies sampled for the branches (plus the folds).
const SAMPLES: usize = 600;
const WIDTH: u32 = 1100;
const HEIGHT: u32 = 640;
const LEGEND_WIDTH: u32 = 250;
/// Largest number of swept-point markers drawn per level.
const MAX_MARKERS: usize = 100;

/// Everything the plot needs.
pub struct FrfPlot<'a> {
    pub title: String,
    pub model: NormalisedModel,
    pub formulation: Formulation,
    pub direction: SweepDirection,
    /// Band, Hz.
    pub f_min: f64,
    pub f_max: f64,
    pub levels: &'a [LevelResponse],
}

fn plot_err<E: std::fmt::Display>(e: E) -> CliError {
    CliError::Usage(format!("cannot draw the plot: {e}"))
}

/// All steady-state branches of one level across `[f_min, f_max]` (Hz),
/// as (Hz, m) polylines.
pub fn branches(
    level: &LevelResponse,
    f_min: f64,
    f_max: f64,
) -> Result<Vec<TracedBranch>, CliError> {
    let opts = BranchOptions {
        samples: SAMPLES,
        radians_per_unit: 2.0 * PI,
    };
    Ok(trace_branches(
        &level.response,
        &level.sweep.folds,
        f_min,
        f_max,
        &opts,
    )?)
}

/// Backbone as runs of (Hz, m) inside the band, clipped at its edges.
fn backbone_runs(p: &FrfPlot, a_max: f64) -> Vec<Vec<(f64, f64)>> {
    const N: usize = 400;
    let mut runs: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    let inside = |f: f64| f >= p.f_min && f <= p.f_max;
    for i in 0..=N {
        let a = a_max * i as f64 / N as f64;
        let Some(w) = backbone(&p.model, a, p.formulation) else {
            if current.len() > 1 {
                runs.push(std::mem::take(&mut current));
            }
            current.clear();
            prev = None;
            continue;
        };
        let pt = (w / (2.0 * PI), a);
        if let Some(q) = prev {
            // Crossing a band edge: add the interpolated edge point.
            for edge in [p.f_min, p.f_max] {
                if (q.0 - edge) * (pt.0 - edge) < 0.0 {
                    let t = (edge - q.0) / (pt.0 - q.0);
                    let e = (edge, q.1 + t * (pt.1 - q.1));
                    if inside(q.0) {
                        current.push(e);
                        if current.len() > 1 {
                            runs.push(std::mem::take(&mut current));
                        }
                        current.clear();
                    } else {
                        current.push(e);
                    }
                }
            }
        }
        if inside(pt.0) {
            current.push(pt);
        }
        prev = Some(pt);
    }
    if current.len() > 1 {
        runs.push(current);
    }
    runs
}

/// Display unit for amplitudes up to `max_m` metres.
fn amplitude_unit(max_m: f64) -> (&'static str, f64) {
    if max_m >= 0.5 {
        ("m", 1.0)
    } else if max_m >= 0.5e-3 {
        ("mm", 1e3)
    } else {
        ("µm", 1e6)
    }
}

/// Tick label of value `v` on an axis spanning `span`.
fn tick_label(v: f64, span: f64) -> String {
    // Ticks are ~span/10 apart in steps of 1, 2 or 5.
    let decimals = (1.0 - span.log10().floor()).clamp(0.0, 10.0) as usize;
    format!("{v:.decimals$}")
}

/// Renders the SVG document (in memory; the caller writes it atomically).
pub fn render_frf(p: &FrfPlot) -> Result<String, CliError> {
    crate::fonts::register();
    let mut level_lines: Vec<Vec<TracedBranch>> = Vec::with_capacity(p.levels.len());
    let mut a_max: f64 = 0.0;
    for l in p.levels {
        let lines = branches(l, p.f_min, p.f_max)?;
        for pl in &lines {
            for &(_, a) in &pl.points {
                if a.is_finite() {
                    a_max = a_max.max(a);
                }
            }
        }
        for pt in &l.sweep.points {
            a_max = a_max.max(pt.amplitude);
        }
        for j in &l.sweep.jumps {
            a_max = a_max.max(j.amplitude_before).max(j.amplitude_after);
        }
        level_lines.push(lines);
    }
    if !(a_max > 0.0 && a_max.is_finite()) {
        a_max = 1e-3;
    }
    let (unit, scale) = amplitude_unit(a_max);
    // At most ~MAX_MARKERS markers per level, so they do not bury the curves.
    let n_points = p
        .levels
        .iter()
        .map(|l| l.sweep.points.len())
        .max()
        .unwrap_or(0);
    let marker_step = n_points.div_ceil(MAX_MARKERS).max(1);
    let y_top = a_max * 1.08 * scale;
    let backbone = backbone_runs(p, a_max * 1.08);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let (left, right) = root.split_horizontally(WIDTH - LEGEND_WIDTH);
        let x_span = p.f_max - p.f_min;
        let x_fmt = |v: &f64| tick_label(*v, x_span);
        let y_fmt = |v: &f64| tick_label(*v, y_top);
        let mut chart = ChartBuilder::on(&left)
            .caption(&p.title, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(78)
            .build_cartesian_2d(p.f_min..p.f_max, 0.0..y_top)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("Frequency f [Hz]")
            .y_desc(format!("Amplitude a [{unit}], zero-to-peak"))
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .axis_desc_style(("sans-serif", 15))
            .label_style(("sans-serif", 13))
            .bold_line_style(MESH.0)
            .light_line_style(MESH.1)
            .draw()
            .map_err(plot_err)?;

        for run in &backbone {
            chart
                .draw_series(DashedLineSeries::new(
                    run.iter().map(|&(f, a)| (f, a * scale)),
                    2,
                    4,
                    GREY.stroke_width(2),
                ))
                .map_err(plot_err)?;
        }
        for (i, (l, lines)) in p.levels.iter().zip(&level_lines).enumerate() {
            let c = colour(i);
            for pl in lines {
                let pts = pl.points.iter().map(|&(f, a)| (f, a * scale));
                if pl.stable {
                    chart
                        .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                        .map_err(plot_err)?;
                } else {
                    chart
                        .draw_series(DashedLineSeries::new(pts, 7, 5, c.stroke_width(2)))
                        .map_err(plot_err)?;
                }
            }
            chart
                .draw_series(l.sweep.points.iter().step_by(marker_step).map(|pt| {
                    Circle::new(
                        (pt.omega / (2.0 * PI), pt.amplitude * scale),
                        2,
                        c.stroke_width(1),
                    )
                }))
                .map_err(plot_err)?;
        }
        // Jump arrows, drawn in pixels so the heads keep their shape.
        for (i, l) in p.levels.iter().enumerate() {
            let c = colour(i);
            for j in &l.sweep.jumps {
                let f = j.omega / (2.0 * PI);
                let from = chart.backend_coord(&(f, j.amplitude_before * scale));
                let to = chart.backend_coord(&(f, j.amplitude_after * scale));
                draw_arrow(&root, from, to, c)?;
            }
        }

        // Legend panel.
        let text = |s: &str, x: i32, y: i32, size: u32| -> Result<(), CliError> {
            right
                .draw(&Text::new(
                    s.to_string(),
                    (x, y),
                    ("sans-serif", size).into_font().color(&BLACK),
                ))
                .map_err(plot_err)
        };
        let mut y = 40;
        text("Input level γ", 12, y, 15)?;
        y += 8;
        text("(m/s², zero-to-peak)", 12, y + 12, 12)?;
        y += 34;
        // Rows shrink when there are many levels, so the legend fits.
        let n_levels = p.levels.len().max(1) as i32;
        let row = ((HEIGHT as i32 - y - 190) / n_levels).clamp(9, 22);
        let font = (row - 6).clamp(7, 14) as u32;
        for (i, l) in p.levels.iter().enumerate() {
            let c = colour(i);
            right
                .draw(&PathElement::new(vec![(14, y), (44, y)], c.stroke_width(3)))
                .map_err(plot_err)?;
            let stuck = l.sweep.points.iter().filter(|pt| pt.sticking).count();
            let note = if stuck == 0 {
                ""
            } else if stuck == l.sweep.points.len() {
                "  (no motion)"
            } else {
                "  (no motion in part)"
            };
            text(
                &format!("γ = {}{note}", l.gamma),
                54,
                y - font as i32 / 2 - 1,
                font,
            )?;
            y += row;
        }
        y += 14;
        right
            .draw(&PathElement::new(
                vec![(14, y), (44, y)],
                BLACK.stroke_width(2),
            ))
            .map_err(plot_err)?;
        text("stable branch", 54, y - 8, 13)?;
        y += 22;
        right
            .draw(&DashedPathElement::new(
                vec![(14, y), (44, y)],
                7,
                5,
                BLACK.stroke_width(2),
            ))
            .map_err(plot_err)?;
        text("unstable branch", 54, y - 8, 13)?;
        y += 22;
        right
            .draw(&DashedPathElement::new(
                vec![(14, y), (44, y)],
                2,
                4,
                GREY.stroke_width(2),
            ))
            .map_err(plot_err)?;
        text("backbone", 54, y - 8, 13)?;
        y += 22;
        right
            .draw(&Circle::new((29, y), 2, BLACK.stroke_width(1)))
            .map_err(plot_err)?;
        let dir = match p.direction {
            SweepDirection::Up => "up",
            SweepDirection::Down => "down",
        };
        text(&format!("swept points (sweep {dir})"), 54, y - 8, 13)?;
        if marker_step > 1 {
            y += 16;
            text(
                &format!("(1 of every {marker_step} of {n_points} points)"),
                54,
                y - 8,
                12,
            )?;
        }
        y += 30;
        let (ox, oy) = right.get_base_pixel();
        draw_arrow(&root, (ox + 29, oy + y - 12), (ox + 29, oy + y + 10), BLACK)?;
        text("jump", 54, y - 8, 13)?;
        root.present().map_err(plot_err)?;
    }
    Ok(svg)
}

fn draw_arrow<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    from: (i32, i32),
    to: (i32, i32),
    c: RGBColor,
) -> Result<(), CliError> {
    let dy = to.1 - from.1;
    let len = dy.abs();
    let head = 9.min(len);
    let dir = dy.signum();
    let base = to.1 - dir * head;
    root.draw(&PathElement::new(
        vec![from, (to.0, base)],
        c.stroke_width(2),
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
    use nlsdof::{ForcedResponse, Model};

    fn duffing() -> Model {
        Model::linear(1.0, 3947.84, 1.2566)
            .unwrap()
            .with_stiffness(1.2e7, 2.0)
            .unwrap()
    }

    fn level(model: &Model, gamma: f64, f_min: f64, f_max: f64, steps: usize) -> LevelResponse {
        let response = ForcedResponse::new(model, gamma, Formulation::HarmonicBalance).unwrap();
        let omegas: Vec<f64> = (0..steps)
            .map(|i| 2.0 * PI * (f_min + (f_max - f_min) * i as f64 / (steps - 1) as f64))
            .collect();
        let sweep = response.sweep(&omegas, SweepDirection::Up).unwrap();
        let phase_quadrature = response.phase_quadrature().unwrap();
        LevelResponse {
            gamma,
            response,
            sweep,
            phase_quadrature,
        }
    }

    #[test]
    fn backbone_is_clipped_to_the_band() {
        let model = duffing();
        let l = level(&model, 2.0, 8.0, 12.0, 10);
        let levels = [l];
        let p = FrfPlot {
            title: "t".into(),
            model: model.normalised().unwrap(),
            formulation: Formulation::HarmonicBalance,
            direction: SweepDirection::Up,
            f_min: 8.0,
            f_max: 12.0,
            levels: &levels,
        };
        let runs = backbone_runs(&p, 0.02);
        assert_eq!(runs.len(), 1);
        let run = &runs[0];
        assert!((run[0].0 - model.omega_n() / (2.0 * PI)).abs() < 1e-9 && run[0].1 == 0.0);
        let last = run.last().unwrap();
        assert!(
            (last.0 - 12.0).abs() < 1e-12,
            "ends on the band edge: {last:?}"
        );
        assert!(run.iter().all(|&(f, _)| (8.0..=12.0).contains(&f)));
    }

    #[test]
    fn svg_has_axes_legend_and_arrows() {
        let model = duffing();
        let levels = [
            level(&model, 1.0, 8.0, 16.0, 40),
            level(&model, 2.0, 8.0, 16.0, 40),
        ];
        let p = FrfPlot {
            title: "duffing".into(),
            model: model.normalised().unwrap(),
            formulation: Formulation::HarmonicBalance,
            direction: SweepDirection::Up,
            f_min: 8.0,
            f_max: 16.0,
            levels: &levels,
        };
        let svg = render_frf(&p).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for want in [
            "Frequency f [Hz]",
            "Amplitude a [mm], zero-to-peak",
            "γ = 1",
            "γ = 2",
            "jump",
            "backbone",
        ] {
            assert!(svg.contains(want), "missing {want}");
        }
        // two jump arrows + the legend arrow, each with a filled head
        assert!(svg.matches("<polygon").count() >= 3);
    }

    #[test]
    fn amplitude_units() {
        assert_eq!(amplitude_unit(0.02), ("mm", 1e3));
        assert_eq!(amplitude_unit(2.0), ("m", 1.0));
        assert_eq!(amplitude_unit(2e-5), ("µm", 1e6));
        assert_eq!(tick_label(5.25, 0.4), "5.25");
        assert_eq!(tick_label(12.0, 8.0), "12.0");
        assert_eq!(tick_label(20.0, 25.0), "20");
    }
}

/// `--plot` of the SVG plots: a name asking for another format (`.png`,
/// `.pdf`, ...) is refused instead of getting SVG content under it.
pub fn check_svg_name(path: Option<&std::path::Path>) -> Result<(), CliError> {
    let Some(path) = path else { return Ok(()) };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    const OTHER: [&str; 12] = [
        "png", "jpg", "jpeg", "gif", "bmp", "pdf", "eps", "ps", "tif", "tiff", "webp", "html",
    ];
    if OTHER.contains(&ext.as_str()) {
        return Err(CliError::Usage(format!(
            "--plot {}: this plot is written as SVG only; give a .svg file name (PNG figures: nlsdof spectrogram --plot)",
            path.display()
        )));
    }
    Ok(())
}
