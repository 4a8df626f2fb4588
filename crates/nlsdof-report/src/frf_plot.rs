//! SVG plot of `nlsdof frf`: amplitude (zero-to-peak) vs frequency (Hz).
//!
//! Drawn by [`nlsdof_figure`] as SVG: text is written as `<text>` elements
//! that the viewer renders, so no system fonts are needed at run time, and
//! the legend sits in its own strip right of the plot.
//!
//! Contents, per input level (one colour each):
//! * all steady-state branches: `steady_states` on ~600 frequencies plus the
//!   fold frequencies; roots of equal rank (index in the amplitude-sorted
//!   list) are connected between consecutive samples with equal root count,
//!   and across a fold the two roots born/dying there are joined to the fold
//!   point. Stable segments solid, unstable dashed;
//! * the swept points as small circles and each jump as a vertical arrow;
//! * the backbone (undamped free-vibration frequency vs amplitude) dotted grey.

use crate::ReportError;
use nlsdof::harmonic_balance::branches::{trace_branches, BranchOptions, TracedBranch};
use nlsdof::{backbone, Formulation, LevelResponse, NormalisedModel, SweepDirection};
use nlsdof_figure::RGBColor;
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series, Style, GREY};
use std::f64::consts::PI;

/// Unstable branches and the backbone.
const UNSTABLE: Style = Style::DashPattern(2, 7, 5);
const BACKBONE: Style = Style::DashPattern(2, 2, 4);

/// Frequencies sampled for the branches (plus the folds).
const SAMPLES: usize = 600;
const WIDTH: u32 = 1100;
const HEIGHT: u32 = 640;
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

/// All steady-state branches of one level across `[f_min, f_max]` (Hz),
/// as (Hz, m) polylines.
pub fn branches(
    level: &LevelResponse,
    f_min: f64,
    f_max: f64,
) -> Result<Vec<TracedBranch>, ReportError> {
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

/// Display unit for amplitudes up to `max_m` metres: the one length unit
/// of every figure ([`figure::length_unit`]).
fn amplitude_unit(max_m: f64) -> (&'static str, f64) {
    figure::length_unit(max_m)
}

/// Tick label of value `v` on an axis spanning `span`.
fn tick_label(v: f64, span: f64) -> String {
    // Ticks are ~span/10 apart in steps of 1, 2 or 5.
    let decimals = (1.0 - span.log10().floor()).clamp(0.0, 10.0) as usize;
    format!("{v:.decimals$}")
}

/// Renders the SVG document (in memory; the caller writes it atomically).
pub fn render_frf(p: &FrfPlot) -> Result<String, ReportError> {
    Ok(figure::render(
        &p.title,
        &[frf_panel(p)?],
        1,
        WIDTH,
        HEIGHT,
    )?)
}

/// The same figure as SVG or PNG bytes.
pub fn render_frf_as(p: &FrfPlot, format: figure::Format) -> Result<Vec<u8>, ReportError> {
    Ok(figure::render_as(
        format,
        &p.title,
        &[frf_panel(p)?],
        1,
        WIDTH,
        HEIGHT,
    )?)
}

/// The figure's one panel: branches, swept points, jumps, backbone.
fn frf_panel(p: &FrfPlot) -> Result<Panel, ReportError> {
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
    let mut panel = Panel::new(
        "",
        "Frequency f [Hz]",
        &format!("Amplitude a [{unit}], zero-to-peak"),
    );
    panel.x_range = Some((p.f_min, p.f_max));
    panel.y_range = Some((0.0, y_top));
    panel.legend = Corner::Outside;
    panel.tick_format = tick_label;
    let scaled = |pts: &[(f64, f64)]| pts.iter().map(|&(f, a)| (f, a * scale)).collect();
    let mut backbone = Some("backbone");
    for run in backbone_runs(p, a_max * 1.08) {
        let mut s = Series::new(scaled(&run), GREY, BACKBONE);
        if let Some(l) = backbone.take() {
            s = s.label(l);
        }
        panel.series.push(s);
    }
    for (i, (l, lines)) in p.levels.iter().zip(&level_lines).enumerate() {
        let c = colour(i);
        let stuck = l.sweep.points.iter().filter(|pt| pt.sticking).count();
        let note = if stuck == 0 {
            ""
        } else if stuck == l.sweep.points.len() {
            "  (no motion)"
        } else {
            "  (no motion in part)"
        };
        panel
            .series
            .push(Series::new(vec![], c, Style::Line(3)).label(format!("γ = {}{note}", l.gamma)));
        for pl in lines {
            let style = if pl.stable { Style::Line(2) } else { UNSTABLE };
            panel.series.push(Series::new(scaled(&pl.points), c, style));
        }
        let marks = l
            .sweep
            .points
            .iter()
            .step_by(marker_step)
            .map(|pt| (pt.omega / (2.0 * PI), pt.amplitude * scale))
            .collect();
        panel.series.push(Series::new(marks, c, Style::Dots(2)));
        let jumps = l
            .sweep
            .jumps
            .iter()
            .flat_map(|j| {
                let f = j.omega / (2.0 * PI);
                [
                    (f, j.amplitude_before * scale),
                    (f, j.amplitude_after * scale),
                ]
            })
            .collect();
        panel.series.push(Series::new(jumps, c, Style::Arrow(2)));
    }
    let dir = p.direction.name();
    let swept = if marker_step > 1 {
        format!("swept points (sweep {dir}; 1 of every {marker_step} of {n_points})")
    } else {
        format!("swept points (sweep {dir})")
    };
    for (style, label) in [
        (Style::Line(2), "stable branch".to_string()),
        (UNSTABLE, "unstable branch".to_string()),
        (Style::Dots(2), swept),
        (Style::Arrow(2), "jump".to_string()),
    ] {
        panel
            .series
            .push(Series::new(vec![], RGBColor(0, 0, 0), style).label(label));
    }
    Ok(panel)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlsdof::Model;

    fn duffing() -> Model {
        Model::linear(1.0, 3947.84, 1.2566)
            .unwrap()
            .with_stiffness(1.2e7, 2.0)
            .unwrap()
    }

    fn level(model: &Model, gamma: f64, f_min: f64, f_max: f64, steps: usize) -> LevelResponse {
        let omegas: Vec<f64> = (0..steps)
            .map(|i| 2.0 * PI * (f_min + (f_max - f_min) * i as f64 / (steps - 1) as f64))
            .collect();
        let hb = Formulation::HarmonicBalance;
        nlsdof::level_responses(model, &[gamma], &omegas, SweepDirection::Up, hb)
            .unwrap()
            .remove(0)
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
pub fn check_svg_name(path: Option<&std::path::Path>) -> Result<(), ReportError> {
    crate::figure_file::check_figure("--plot", path, &[crate::figure_file::FigureFormat::Svg])
        .map(|_| ())
}
