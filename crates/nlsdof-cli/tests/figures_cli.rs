//! Every line figure of the CLI, rendered and read back (issue 27, item 7):
//! the SVG's text elements are parsed for their font size and position, and
//! checked to be readable (at least 10 px), off every plot area (the framed
//! rectangles) and inside the canvas (no clipped legend); the legend boxes
//! are inside the canvas; `--plot` writes PNG for a `.png` name; a
//! landscape with a single node is refused in one line before the fit.

mod common;

use common::{fails_one_line, json, nlsdof, ok, write};
use nlsdof::identification::time_domain::{simulate_output, TimeModel};
use nlsdof::simulation::State;
use nlsdof::{ForcedResponse, Formulation, NormalisedModel, SweepDirection};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// A text element: its box in pixels, font size and content.
#[derive(Debug)]
struct TextBox {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    size: f64,
    text: String,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

fn num(tag: &str, name: &str) -> f64 {
    attr(tag, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no number {name} in {tag}"))
}

/// The canvas size of an SVG document.
fn canvas(svg: &str) -> (f64, f64) {
    let tag = &svg[..svg.find('>').unwrap()];
    (num(tag, "width"), num(tag, "height"))
}

/// Every `<text>` of the document with the box it covers: the width is
/// estimated at 0.56 em per character (DejaVu Sans averages 0.52 em), the
/// anchor (`text-anchor`, and `dy` for the baseline) and a 270° rotation
/// (the y-axis labels) as plotters writes them.
fn texts(svg: &str) -> Vec<TextBox> {
    let mut out = Vec::new();
    for part in svg.split("<text").skip(1) {
        let end = part.find('>').unwrap();
        let tag = &part[..end];
        let text = part[end + 1..part.find("</text>").unwrap()]
            .trim()
            .replace("&apos;", "'")
            .replace("&quot;", "\"")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&");
        let (x, y, size) = (num(tag, "x"), num(tag, "y"), num(tag, "font-size"));
        let w = 0.56 * size * text.chars().count() as f64;
        let (a0, a1) = match attr(tag, "text-anchor").as_deref() {
            Some("middle") => (-w / 2.0, w / 2.0),
            Some("end") => (-w, 0.0),
            _ => (0.0, w),
        };
        let (b0, b1) = match attr(tag, "dy").as_deref() {
            Some("0.76em") => (0.0, size),
            Some("0.5ex") => (-size / 2.0, size / 2.0),
            Some("-0.5ex") => (-size, 0.0),
            _ => (-size, 0.0),
        };
        let b = if attr(tag, "transform").is_some_and(|t| t.starts_with("rotate(270")) {
            // local x runs up the page, local y to the right
            TextBox {
                x0: x + b0,
                x1: x + b1,
                y0: y - a1,
                y1: y - a0,
                size,
                text,
            }
        } else {
            TextBox {
                x0: x + a0,
                x1: x + a1,
                y0: y + b0,
                y1: y + b1,
                size,
                text,
            }
        };
        out.push(b);
    }
    out
}

/// Rectangles `[x0, y0, x1, y1]` with the given stroke and no fill.
fn frames(svg: &str, stroke: &str) -> Vec<[f64; 4]> {
    svg.split("<rect")
        .skip(1)
        .map(|p| &p[..p.find('>').unwrap()])
        .filter(|t| {
            attr(t, "fill").as_deref() == Some("none")
                && attr(t, "stroke").as_deref() == Some(stroke)
        })
        .map(|t| {
            let (x, y) = (num(t, "x"), num(t, "y"));
            [x, y, x + num(t, "width"), y + num(t, "height")]
        })
        .collect()
}

/// The checks of every figure; `name` for the messages.
fn check_figure(name: &str, svg: &str) {
    assert!(svg.starts_with("<svg"), "{name}: not SVG");
    let (w, h) = canvas(svg);
    let texts = texts(svg);
    assert!(!texts.is_empty(), "{name}: no text");
    let plots = frames(svg, "#282828");
    assert!(!plots.is_empty(), "{name}: no framed plot area");
    for t in &texts {
        assert!(
            t.size >= 10.0,
            "{name}: text {:?} is {} px (< 10)",
            t.text,
            t.size
        );
        assert!(
            t.x0 >= -0.5 && t.y0 >= -0.5 && t.x1 <= w + 0.5 && t.y1 <= h + 0.5,
            "{name}: text {:?} at [{:.0}, {:.0}, {:.0}, {:.0}] leaves the {w} x {h} canvas",
            t.text,
            t.x0,
            t.y0,
            t.x1,
            t.y1
        );
        for p in &plots {
            // inside by more than 1 px on both axes: on the plot
            let overlap_x = t.x1.min(p[2]) - t.x0.max(p[0]);
            let overlap_y = t.y1.min(p[3]) - t.y0.max(p[1]);
            assert!(
                overlap_x <= 1.0 || overlap_y <= 1.0,
                "{name}: text {:?} [{:.0}, {:.0}, {:.0}, {:.0}] overlaps the plot area {p:?}",
                t.text,
                t.x0,
                t.y0,
                t.x1,
                t.y1
            );
        }
    }
    for l in frames(svg, "#C8C8C8") {
        assert!(
            l[0] >= 0.0 && l[1] >= 0.0 && l[2] <= w && l[3] <= h,
            "{name}: legend box {l:?} clipped by the {w} x {h} canvas"
        );
        for p in &plots {
            let overlap_x = l[2].min(p[2]) - l[0].max(p[0]);
            let overlap_y = l[3].min(p[3]) - l[1].max(p[1]);
            assert!(
                overlap_x <= 1.0 || overlap_y <= 1.0,
                "{name}: legend box {l:?} sits on the plot area {p:?}"
            );
        }
    }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn is_png(p: &Path) -> bool {
    std::fs::read(p).is_ok_and(|b| b.starts_with(b"\x89PNG"))
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Long CSV of an exact Duffing model (f_n = 10 Hz): `levels` levels,
/// up-sweeps, and a down-sweep of the highest level.
fn duffing_csv(dir: &Path, levels: usize) -> PathBuf {
    let wn = TWO_PI * 10.0;
    let m = NormalisedModel {
        alpha: wn * wn,
        delta: 0.02 * wn,
        beta: 2.5e6,
        rho: 2.0,
        kappa: 0.0,
        eta: 0.0,
    };
    let freqs: Vec<f64> = (0..25).map(|i| 8.5 + 3.5 * i as f64 / 24.0).collect();
    let omegas: Vec<f64> = freqs.iter().map(|f| TWO_PI * f).collect();
    let mut s = String::from("level,gamma,f_hz,amplitude,sweep\n");
    let mut add = |k: usize, dir: SweepDirection| {
        let g = 0.05 + 0.2 * k as f64 / levels.max(2) as f64;
        let sw = ForcedResponse::from_normalised(&m, g, Formulation::HarmonicBalance)
            .unwrap()
            .sweep(&omegas, dir)
            .unwrap();
        let mut rows: Vec<_> = omegas.iter().zip(&sw.points).collect();
        if dir == SweepDirection::Down {
            // in the order measured
            rows.reverse();
        }
        for (w, p) in rows {
            let name = if dir == SweepDirection::Up {
                "up"
            } else {
                "down"
            };
            writeln!(s, "L{k},{g},{},{:e},{name}", w / TWO_PI, p.amplitude).unwrap();
        }
    };
    for k in 0..levels {
        add(k, SweepDirection::Up);
    }
    add(levels - 1, SweepDirection::Down);
    let path = dir.join("data.csv");
    std::fs::write(&path, s).unwrap();
    path
}

#[test]
fn fit_figure_svg_png_and_landscape() {
    let dir = tempfile::tempdir().unwrap();
    let csv = duffing_csv(dir.path(), 3);
    let svg = dir.path().join("fit.svg");
    let png = dir.path().join("fit.png");
    let land = dir.path().join("land.svg");
    ok(&["fit", s(&csv), "--model", "duffing", "--plot", s(&svg)]);
    let text = read(&svg);
    check_figure("fit --plot", &text);
    // one length unit from the data's magnitude (mm here), stated on the axis
    assert!(text.contains("amplitude a [mm], zero-to-peak"), "unit");
    // up and down sweeps are told apart in the legend
    assert!(text.contains("model, sweep up") && text.contains("model, sweep down"));
    ok(&["fit", s(&csv), "--model", "duffing", "--plot", s(&png)]);
    assert!(is_png(&png), "fit --plot x.png writes PNG");
    // a one-node landscape is refused before the fit, nothing written
    let e = fails_one_line(&[
        "fit",
        s(&csv),
        "--model",
        "duffing",
        "--landscape",
        s(&land),
    ]);
    assert!(e.contains("single node"), "{e}");
    assert!(!land.exists());
    // one free exponent: a 1-D profile
    ok(&[
        "fit",
        s(&csv),
        "--model",
        "generalised-stiffness",
        "--grid",
        "12",
        "--landscape",
        s(&land),
    ]);
    let text = read(&land);
    check_figure("fit --landscape (profile)", &text);
    assert!(text.contains("rho (stiffness exponent)"));
    // two free exponents: the map, legend under it, readable colour bar
    let map = dir.path().join("map.svg");
    ok(&[
        "fit",
        s(&csv),
        "--model",
        "generalised",
        "--grid",
        "8",
        "--landscape",
        s(&map),
    ]);
    let text = read(&map);
    check_figure("fit --landscape (map)", &text);
    let ticks: Vec<String> = texts(&text)
        .into_iter()
        .map(|t| t.text)
        .filter(|t| t.parse::<f64>().is_ok())
        .collect();
    let distinct: std::collections::BTreeSet<&String> = ticks.iter().collect();
    assert!(distinct.len() >= 6, "colour bar and axes ticks: {ticks:?}");
}

#[test]
fn frf_figure_with_twenty_levels_keeps_its_legend() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("frf.svg");
    let gammas: Vec<String> = (0..20)
        .map(|i| format!("{:.2}", 0.2 + 0.1 * i as f64))
        .collect();
    let model = common::example("har-wing.toml");
    ok(&[
        "frf",
        "--model",
        s(&model),
        "--gamma",
        &gammas.join(","),
        "--f-min",
        "5.2",
        "--f-max",
        "5.6",
        "--steps",
        "120",
        "--plot",
        s(&svg),
    ]);
    let text = read(&svg);
    check_figure("frf --plot", &text);
    for g in ["γ = 0.2", "γ = 2.1"] {
        assert!(text.contains(g), "{g}");
    }
    // 20 levels, 20 different colours on the legend's swatches
    let png = dir.path().join("frf.png");
    ok(&[
        "frf",
        "--model",
        s(&model),
        "--gamma",
        "0.5,1",
        "--f-min",
        "5.2",
        "--f-max",
        "5.6",
        "--steps",
        "60",
        "--plot",
        s(&png),
    ]);
    assert!(is_png(&png));
    let mh = dir.path().join("mh.svg");
    ok(&[
        "frf",
        "--model",
        s(&model),
        "--gamma",
        "0.5,1",
        "--f-min",
        "5.2",
        "--f-max",
        "5.6",
        "--steps",
        "41",
        "--harmonics",
        "3",
        "--plot",
        s(&mh),
    ]);
    check_figure("frf --harmonics --plot", &read(&mh));
}

#[test]
fn palette_has_twenty_distinct_colours() {
    use nlsdof_figure::{colour, COLOURS};
    assert!(COLOURS.len() >= 20);
    // CIE76 distance in Lab between every pair
    fn lab(c: nlsdof_figure::RGBColor) -> [f64; 3] {
        let f = |u: u8| {
            let u = u as f64 / 255.0;
            if u <= 0.04045 {
                u / 12.92
            } else {
                ((u + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (f(c.0), f(c.1), f(c.2));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let h = |t: f64| {
            if t > 0.008856 {
                t.cbrt()
            } else {
                7.787 * t + 16.0 / 116.0
            }
        };
        [
            116.0 * h(y) - 16.0,
            500.0 * (h(x) - h(y)),
            200.0 * (h(y) - h(z)),
        ]
    }
    for i in 0..20 {
        for j in 0..i {
            let (a, b) = (lab(colour(i)), lab(colour(j)));
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            assert!(d > 25.0, "colours {i} and {j}: ΔE {d:.1}");
        }
    }
}

#[test]
fn decay_and_linear_id_figures() {
    let dir = tempfile::tempdir().unwrap();
    let fs = 1000.0;
    let wn = TWO_PI * 10.0;
    let tm = TimeModel {
        model: NormalisedModel {
            alpha: wn * wn,
            delta: 2.0 * 0.005 * wn,
            beta: 0.2 * wn * wn / 0.75,
            rho: 2.0,
            kappa: 0.0,
            eta: 0.0,
        },
        gain: 0.0,
        input_offset: 0.0,
        output_offset: 0.0,
    };
    let x = simulate_output(&tm, &vec![0.0; 20_000], fs, State { x: 1e-3, v: 0.0 }).unwrap();
    let mut t = String::from("t,x_m\n");
    for (k, v) in x.iter().enumerate() {
        writeln!(t, "{},{v:e}", k as f64 / fs).unwrap();
    }
    let f = write(dir.path(), "decay.csv", &t);
    let svg = dir.path().join("decay.svg");
    json(&[
        "decay",
        "--input",
        s(&f),
        "--column",
        "x_m",
        "--unit",
        "m",
        "--t-start",
        "0",
        "--json",
        "--plot",
        s(&svg),
    ]);
    let text = read(&svg);
    check_figure("decay --plot", &text);
    // the axes name the column and its unit
    assert!(text.contains("x_m [m], mean removed"), "record axis");
    assert!(text.contains("amplitude of x_m [m]"), "amplitude axes");
    let png = dir.path().join("decay.png");
    ok(&[
        "decay",
        "--input",
        s(&f),
        "--column",
        "x_m",
        "--t-start",
        "0",
        "--plot",
        s(&png),
    ]);
    assert!(is_png(&png));
    // linear-id: |H| with its unit
    let (k, c, m) = (1.2e3, 0.6, 1.0);
    let mut frf = String::from("f_hz,re,im\n");
    for i in 0..400 {
        let f = 4.5 + 1.5 * i as f64 / 399.0;
        let w = TWO_PI * f;
        let den = (k / m - w * w, c / m * w);
        let n = den.0 * den.0 + den.1 * den.1;
        writeln!(frf, "{f:?},{:?},{:?}", den.0 / n, -den.1 / n).unwrap();
    }
    let frf = write(dir.path(), "frf.csv", &frf);
    let svg = dir.path().join("lin.svg");
    ok(&["linear-id", s(&frf), "--plot", s(&svg)]);
    let text = read(&svg);
    check_figure("linear-id --plot", &text);
    assert!(text.contains("|H| [m/(m/s²)]"), "|H| unit");
    let svg = dir.path().join("lin_force.svg");
    ok(&[
        "linear-id",
        s(&frf),
        "--input",
        "force",
        "--output",
        "velocity",
        "--plot",
        s(&svg),
    ]);
    assert!(read(&svg).contains("|H| [(m/s)/N]"));
    let png = dir.path().join("lin.png");
    ok(&["linear-id", s(&frf), "--plot", s(&png)]);
    assert!(is_png(&png));
}

#[test]
fn inspect_figure() {
    let dir = tempfile::tempdir().unwrap();
    let csv = duffing_csv(dir.path(), 4);
    let svg = dir.path().join("inspect.svg");
    let out = nlsdof()
        .args(["inspect", s(&csv), "--plot", s(&svg)])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    check_figure("inspect --plot", &read(&svg));
}
