//! Stage 6: figures, tables (markdown + CSV), `summary.json` and `report.md`.

mod markdown;
mod table;

use crate::ReportError;
use nlsdof::demo::spectra::PLOT_BAND;
use nlsdof::demo::{
    noise_model, Demo, FitEntry, Linear, CHIRP_F0, CHIRP_F1, FS_RECORD, F_MAX, F_MIN, LEVELS_PP,
    SPECTROGRAM_LEVELS,
};
use nlsdof::identification::models::{ALPHA, BETA, DELTA, ETA, GAIN, KAPPA, RHO};
use nlsdof::identification::{Parameter, PhaseQuadratureRow, Status, N_PARAMS, PARAM_NAMES};
use nlsdof_figure::{colour, render, Corner, Panel, Series, Style, DARK, GREY};
use nlsdof_io::atomic::write_atomic;
use serde_json::{json, Value};
use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;
pub use table::{sig, Table};

fn hz(w: f64) -> f64 {
    w / TAU
}

fn pct(v: Option<f64>) -> String {
    v.map(|x| format!("{x:+.3}")).unwrap_or_else(|| "-".into())
}

/// Everything produced by [`write_all`], kept for [`finish`].
pub struct Written {
    pub summary: Value,
    pub tables: Vec<Table>,
    pub figures: Vec<(String, String)>,
}

fn fig_path(dir: &Path, name: &str) -> std::path::PathBuf {
    dir.join(name)
}

fn write_svg(dir: &Path, name: &str, svg: String) -> Result<(), ReportError> {
    write_atomic(&fig_path(dir, name), svg.as_bytes())?;
    Ok(())
}

/// The length unit of every figure of the run, chosen once from the largest
/// measured amplitude ([`nlsdof_figure::length_unit`]): name and scale
/// from metres.
#[derive(Clone, Copy)]
struct Length(&'static str, f64);

impl Length {
    fn of(demo: &Demo) -> Self {
        let peak = demo
            .runs
            .iter()
            .filter_map(|r| r.measured.as_ref())
            .flat_map(|m| m.data.curves.iter().flat_map(|c| c.amplitudes.iter()))
            .map(|a| a.abs())
            .filter(|a| a.is_finite())
            .fold(0.0f64, f64::max);
        let (name, scale) = nlsdof_figure::length_unit(peak);
        Length(name, scale)
    }

    fn amplitude_label(self) -> String {
        format!("amplitude a [{}], zero-to-peak", self.0)
    }
}

const F_LABEL: &str = "frequency f [Hz]";

fn level_label(i: usize) -> String {
    format!(
        "γ = {:.2} m/s² (P-P {:.2})",
        0.5 * LEVELS_PP[i],
        LEVELS_PP[i]
    )
}

/// Fig 2: the "measured" stepped-sine curves.
fn fig2(demo: &Demo, dir: &Path, len: Length) -> Result<(), ReportError> {
    let mut panels = Vec::new();
    for run in &demo.runs {
        let m = run.measured.as_ref().expect("ran");
        let mut amp = Panel::new(
            format!("{}: amplitude (rig + noise)", run.cfg.title),
            F_LABEL,
            &len.amplitude_label(),
        );
        let mut ph = Panel::new(
            format!("{}: phase lag of x behind the input", run.cfg.title),
            F_LABEL,
            "phase lag [deg]",
        );
        for (i, c) in m.data.curves.iter().enumerate() {
            let pts: Vec<(f64, f64)> = c
                .omegas
                .iter()
                .zip(&c.amplitudes)
                .map(|(&w, &a)| (hz(w), len.1 * a))
                .collect();
            amp.series
                .push(Series::new(pts.clone(), colour(i), Style::Line(1)).label(level_label(i)));
            amp.series.push(Series::new(pts, colour(i), Style::Dots(1)));
            if let Some(p) = &c.phases {
                let pp: Vec<(f64, f64)> = c
                    .omegas
                    .iter()
                    .zip(p)
                    .map(|(&w, &v)| (hz(w), v.to_degrees()))
                    .collect();
                ph.series
                    .push(Series::new(pp, colour(i), Style::Line(1)).label(level_label(i)));
            }
        }
        let pq: Vec<(f64, f64)> = m
            .truth_pq
            .iter()
            .map(|r| (hz(r.measured_omega), len.1 * r.measured_amplitude))
            .collect();
        amp.series.push(
            Series::new(pq, RGBA_BLACK, Style::Filled(4)).label("phase quadrature (90° crossing)"),
        );
        amp.x_range = Some((F_MIN, F_MAX));
        amp.y_range = Some((0.0, max_y(&amp) * 1.08));
        amp.legend = Corner::Outside;
        ph.series.push(
            Series::new(vec![(F_MIN, 90.0), (F_MAX, 90.0)], GREY, Style::Dashed(1)).label("90°"),
        );
        ph.x_range = Some((F_MIN, F_MAX));
        ph.y_range = Some((0.0, 180.0));
        ph.legend = Corner::Outside;
        panels.push(amp);
        panels.push(ph);
    }
    let svg = render(
        "Fig 2 analogue: virtual stepped-sine test (sweep up, 5 levels, measurement noise)",
        &panels,
        2,
        800,
        430,
    )?;
    write_svg(dir, "fig2_stepped_sine_data.svg", svg)
}

const RGBA_BLACK: nlsdof_figure::RGBColor = nlsdof_figure::RGBColor(0, 0, 0);

fn max_y(p: &Panel) -> f64 {
    p.series
        .iter()
        .flat_map(|s| s.points.iter().map(|q| q.1))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-12)
}

/// Fig 4: the chirp's H1 and its vector fit.
fn fig4(demo: &Demo, dir: &Path) -> Result<(), ReportError> {
    let mut panels = Vec::new();
    for run in &demo.runs {
        let l = run.linear.as_ref().expect("ran");
        let truth = run.cfg.truth;
        let (a_true, d_true) = (truth.stiffness / truth.mass, truth.damping / truth.mass);
        let h_true = |w: f64| {
            nlsdof::vector_fitting::C64::new(1.0, 0.0)
                / nlsdof::vector_fitting::C64::new(a_true - w * w, d_true * w)
        };
        let db = |z: nlsdof::vector_fitting::C64| 20.0 * z.norm().log10();
        let ph = |z: nlsdof::vector_fitting::C64| -z.arg().to_degrees();
        let fine: Vec<f64> = (0..=600)
            .map(|i| CHIRP_F0 + (CHIRP_F1 - CHIRP_F0) * i as f64 / 600.0)
            .collect();
        let mut mag = Panel::new(
            format!(
                "{}: |H| = |X/Γ| (chirp 0.25 m/s², H1 of the record)",
                run.cfg.title
            ),
            F_LABEL,
            "|H| [dB re 1 m/(m/s²)]",
        );
        let mut phase = Panel::new(
            format!("{}: phase lag of H", run.cfg.title),
            F_LABEL,
            "phase lag [deg]",
        );
        let meas: Vec<(f64, f64)> = l
            .f_hz
            .iter()
            .zip(&l.h1)
            .map(|(&f, &h)| (f, db(h)))
            .collect();
        let meas_p: Vec<(f64, f64)> = l
            .f_hz
            .iter()
            .zip(&l.h1)
            .map(|(&f, &h)| (f, ph(h)))
            .collect();
        let fitc: Vec<(f64, f64)> = fine.iter().map(|&f| (f, db(l.fit.eval(TAU * f)))).collect();
        let fitp: Vec<(f64, f64)> = fine.iter().map(|&f| (f, ph(l.fit.eval(TAU * f)))).collect();
        let tr: Vec<(f64, f64)> = fine.iter().map(|&f| (f, db(h_true(TAU * f)))).collect();
        let trp: Vec<(f64, f64)> = fine.iter().map(|&f| (f, ph(h_true(TAU * f)))).collect();
        mag.series
            .push(Series::new(meas, GREY, Style::Dots(2)).label("H1 (noisy chirp, whole record)"));
        mag.series
            .push(Series::new(fitc, colour(0), Style::Line(2)).label(format!(
                "vector fit: f_n = {:.4} Hz, ζ = {:.3} %",
                l.part.mode.frequency_hz,
                100.0 * l.part.mode.zeta
            )));
        mag.series
            .push(Series::new(tr, colour(1), Style::Dashed(2)).label("true linear part (Table 3)"));
        phase
            .series
            .push(Series::new(meas_p, GREY, Style::Dots(2)).label("H1"));
        phase
            .series
            .push(Series::new(fitp, colour(0), Style::Line(2)).label("vector fit"));
        phase
            .series
            .push(Series::new(trp, colour(1), Style::Dashed(2)).label("true linear part"));
        mag.x_range = Some((CHIRP_F0, CHIRP_F1));
        phase.x_range = Some((CHIRP_F0, CHIRP_F1));
        phase.y_range = Some((0.0, 180.0));
        phase.legend = Corner::TopLeft;
        panels.push(mag);
        panels.push(phase);
    }
    let svg = render(
        "Fig 4 analogue: linear identification from a 4.5 → 6 Hz chirp (+0.005 Hz/s) at 0.25 m/s²: H1 of the whole record and fast relaxed vector fitting",
        &panels,
        2,
        640,
        430,
    )?;
    write_svg(dir, "fig4_linear_frf.svg", svg)
}

/// Data (dots) and the fitted model's branch-following sweep (lines).
fn fit_panel(run: &nlsdof::demo::ConfigRun, f: &FitEntry, len: Length) -> Panel {
    let m = run.measured.as_ref().expect("ran");
    let mut p = Panel::new(
        format!("{}: {}", run.cfg.title, f.label),
        F_LABEL,
        &len.amplitude_label(),
    );
    let mut off = 0;
    for (i, c) in m.data.curves.iter().enumerate() {
        let n = c.omegas.len();
        let data: Vec<(f64, f64)> = c
            .omegas
            .iter()
            .zip(&c.amplitudes)
            .map(|(&w, &a)| (hz(w), len.1 * a))
            .collect();
        let model: Vec<(f64, f64)> = c
            .omegas
            .iter()
            .zip(&f.result.model_amplitudes[off..off + n])
            .map(|(&w, &a)| (hz(w), len.1 * a))
            .collect();
        p.series.push(Series::new(data, colour(i), Style::Dots(2)));
        p.series
            .push(Series::new(model, colour(i), Style::Line(2)).label(level_label(i)));
        off += n;
    }
    let mut extra = vec![
        Series::new(vec![], DARK, Style::Dots(2)).label("data (rig + noise)"),
        Series::new(vec![], DARK, Style::Line(2))
            .label(format!("model, cost {:.3e}", f.result.cost)),
    ];
    p.series.append(&mut extra);
    p.x_range = Some((F_MIN, F_MAX));
    p.legend = Corner::Outside;
    p
}

fn fit_figure(
    demo: &Demo,
    dir: &Path,
    ids: &[&str],
    name: &str,
    title: &str,
    len: Length,
) -> Result<(), ReportError> {
    // common y range over the figure so the panels compare at a glance
    let mut panels = Vec::new();
    for id in ids {
        for run in &demo.runs {
            let f = run.fits.iter().find(|f| f.id == *id).expect("fit ran");
            panels.push(fit_panel(run, f, len));
        }
    }
    let top = panels.iter().map(max_y).fold(0.0, f64::max) * 1.08;
    for p in &mut panels {
        p.y_range = Some((0.0, top));
    }
    let svg = render(title, &panels, demo.runs.len(), 800, 430)?;
    write_svg(dir, name, svg)
}

fn short(f: &FitEntry) -> &'static str {
    match f.id {
        "classic" => "classic (ρ = 2, η = 1)",
        "classic-a" => "classic, fitted to levels 1-2",
        "classic-b" => "classic, fitted to levels 4-5",
        "dg-int" => "Duffing + gen. damping, integer η",
        "dg-real" => "Duffing + gen. damping, real η",
        "g-int" => "generalised, integer ρ, η",
        "g-real" => "generalised, real ρ, η",
        "g-free" => "generalised, linear part free",
        _ => f.label,
    }
}

/// RMS residual per level of every model, with the noise level.
fn fig_rms(demo: &Demo, dir: &Path, len: Length) -> Result<(), ReportError> {
    let mut panels = Vec::new();
    for run in &demo.runs {
        let m = run.measured.as_ref().expect("ran");
        let mut p = Panel::new(
            format!("{}: RMS residual per level", run.cfg.title),
            "input level γ [m/s²], zero-to-peak",
            &format!("RMS of (a_model − a_meas) [{}], log scale", len.0),
        );
        for (i, f) in run.fits.iter().enumerate() {
            let pts: Vec<(f64, f64)> = f
                .result
                .levels
                .iter()
                .map(|l| (l.gamma, len.1 * l.rms))
                .collect();
            p.series
                .push(Series::new(pts.clone(), colour(i), Style::Line(2)).label(short(f)));
            p.series.push(Series::new(pts, colour(i), Style::Filled(3)));
        }
        // the noise's own RMS per level (what a perfect model leaves)
        let mut off = 0;
        let mut noise = Vec::new();
        for (c, sw) in m.data.curves.iter().zip(&m.sweeps) {
            let n = c.omegas.len();
            let s2: f64 = c
                .amplitudes
                .iter()
                .zip(&sw.points)
                .map(|(a, p)| (a - p.amplitude).powi(2))
                .sum();
            noise.push((c.gamma, len.1 * (s2 / n as f64).sqrt()));
            off += n;
        }
        let _ = off;
        p.series
            .push(Series::new(noise, DARK, Style::Dashed(2)).label("measurement noise (RMS)"));
        let lo = p
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|q| q.1))
            .filter(|v| *v > 0.0)
            .fold(f64::INFINITY, f64::min);
        p.y_range = Some((lo * 0.8, max_y(&p) * 1.25));
        p.log_y = true;
        p.x_range = Some((0.35, 1.3));
        p.legend = Corner::Outside;
        panels.push(p);
    }
    let svg = render(
        "Residuals: RMS of the Eq 31 misfit per input level for each model (the dashed line is the injected noise)",
        &panels,
        2,
        860,
        430,
    )?;
    write_svg(dir, "fig9_rms_per_level.svg", svg)
}

/// Per-step peak |x| of the full-length time simulation.
fn fig_time(demo: &Demo, dir: &Path, len: Length) -> Result<(), ReportError> {
    let mut panels = Vec::new();
    for run in &demo.runs {
        let mut p = Panel::new(
            format!("{}: stepped-sine time simulation", run.cfg.title),
            "step frequency f [Hz]",
            &format!("peak |x| over each dwell's 2nd half [{}]", len.0),
        );
        for tl in &run.time {
            if !SPECTROGRAM_LEVELS.contains(&tl.level) {
                continue;
            }
            let meas: Vec<(f64, f64)> = tl.envelope.iter().map(|e| (e.0, len.1 * e.1)).collect();
            let model: Vec<(f64, f64)> = tl.envelope.iter().map(|e| (e.0, len.1 * e.2)).collect();
            p.series.push(
                Series::new(meas, colour(tl.level), Style::Dots(2))
                    .label(format!("measured, {}", level_label(tl.level))),
            );
            p.series.push(
                Series::new(model, colour(tl.level), Style::Line(2))
                    .label("fitted model (integer ρ, η)"),
            );
        }
        p.x_range = Some((F_MIN, F_MAX));
        p.y_range = Some((0.0, max_y(&p) * 1.08));
        p.legend = Corner::Outside;
        panels.push(p);
    }
    let svg = render(
        "Time domain: recorded (true model + noise) vs fitted generalised integer model, levels 1, 3, 5",
        &panels,
        2,
        800,
        430,
    )?;
    write_svg(dir, "fig8c_time_envelope.svg", svg)
}

/// PNG spectrograms (heat map and waterfall), measured beside model.
fn fig8_png(demo: &Demo, dir: &Path) -> Result<Vec<String>, ReportError> {
    let mut names = Vec::new();
    for run in &demo.runs {
        for ls in &run.spectra {
            let Some((sm, sn)) = &ls.plot else { continue };
            let base = format!("fig8_{}_level{}", run.cfg.key, ls.level + 1);
            let title = format!(
                "{}, level {} (γ = {:.2} m/s² 0-pk): Eq 33 {:.1} %, robust (≥ 1 % of max) {:.2} %",
                run.cfg.title,
                ls.level + 1,
                0.5 * LEVELS_PP[ls.level],
                ls.diff.max_relative_percent,
                ls.diff.robust_max_relative_percent
            );
            let pair = [("recorded (true + noise)", sm), ("fitted model", sn)];
            let heat = format!("{base}_heatmap.png");
            let water = format!("{base}_waterfall.png");
            if png_heatmap(&dir.join(&heat), &pair, Some(PLOT_BAND), &title)? {
                names.push(heat);
            }
            if png_waterfall(&dir.join(&water), &pair, Some(PLOT_BAND), &title)? {
                names.push(water);
            }
        }
    }
    Ok(names)
}

fn png_heatmap(
    path: &Path,
    pair: &[(&str, &nlsdof::signal_processing::stft::Spectrogram)],
    band: Option<(f64, f64)>,
    title: &str,
) -> Result<bool, ReportError> {
    nlsdof_io::atomic::write_atomic(path, &nlsdof_figure::heatmap_png(pair, band, title)?)?;
    Ok(true)
}

fn png_waterfall(
    path: &Path,
    pair: &[(&str, &nlsdof::signal_processing::stft::Spectrogram)],
    band: Option<(f64, f64)>,
    title: &str,
) -> Result<bool, ReportError> {
    nlsdof_io::atomic::write_atomic(path, &nlsdof_figure::waterfall_png(pair, band, title)?)?;
    Ok(true)
}

fn phys(j: usize, v: f64, m: f64) -> f64 {
    if Parameter::ALL[j].mass_scaled() {
        v * m
    } else {
        v
    }
}

fn exps(f: &FitEntry) -> &'static str {
    if f.kind == nlsdof::identification::ModelKind::DuffingQuadratic {
        "fixed (2, 1)"
    } else if f.integer {
        "integer"
    } else {
        "real"
    }
}

fn pq_max(rows: &[PhaseQuadratureRow]) -> (f64, f64) {
    rows.iter().fold((0.0f64, 0.0f64), |(fa, ff), r| {
        let (df, da) = r.differences_percent();
        (
            fa.max(da.map_or(f64::NAN, f64::abs)),
            ff.max(df.map_or(f64::NAN, f64::abs)),
        )
    })
}

pub fn build_tables(demo: &Demo) -> Vec<Table> {
    let mut tables = Vec::new();
    // truth
    let mut t = Table::new(
        "truth",
        &[
            "configuration",
            "m [kg]",
            "k [N/m]",
            "c [N s/m]",
            "k_r [N/m^(rho+1)]",
            "rho",
            "c_e [N (s/m)^(eta+1)]",
            "eta",
            "f_n [Hz]",
            "zeta [%]",
        ],
    );
    for run in &demo.runs {
        let m = &run.cfg.truth;
        let ks = m.nonlinear_stiffness.expect("truth has it");
        let cd = m.nonlinear_damping.expect("truth has it");
        t.push(vec![
            run.cfg.key.into(),
            sig(m.mass, 5),
            sig(m.stiffness, 7),
            sig(m.damping, 4),
            sig(ks.coefficient, 5),
            sig(ks.exponent, 6),
            sig(cd.coefficient, 4),
            sig(cd.exponent, 6),
            format!("{:.5}", m.omega_n() / TAU),
            format!("{:.4}", 100.0 * m.zeta()),
        ]);
    }
    tables.push(t);
    // rig
    let mut t = Table::new(
        "rig",
        &[
            "configuration",
            "level",
            "gamma P-P [m/s^2]",
            "gamma 0-pk [m/s^2]",
            "steps",
            "unsettled steps",
            "simulated test time [s]",
            "mean dwell [s]",
            "peak a measured [m]",
            "at f [Hz]",
        ],
    );
    for run in &demo.runs {
        let m = run.measured.as_ref().expect("ran");
        for (i, (c, sw)) in m.data.curves.iter().zip(&m.sweeps).enumerate() {
            let k = c.peak_index();
            t.push(vec![
                run.cfg.key.into(),
                format!("{}", i + 1),
                format!("{:.2}", LEVELS_PP[i]),
                format!("{:.3}", c.gamma),
                format!("{}", sw.points.len()),
                format!("{}", sw.points.iter().filter(|p| !p.settled).count()),
                format!("{:.1}", sw.duration),
                format!("{:.2}", m.mean_dwell(i)),
                sig(c.amplitudes[k], 5),
                format!("{:.4}", hz(c.omegas[k])),
            ]);
        }
    }
    tables.push(t);
    // linear identification
    let mut t = Table::new(
        "linear_id",
        &[
            "configuration",
            "f_n true [Hz]",
            "f_n VF [Hz]",
            "diff f_n [%]",
            "zeta true [%]",
            "zeta VF [%]",
            "diff zeta [%]",
            "k = m alpha [N/m] (m known)",
            "c = m delta [N s/m]",
            "f_n half-power [Hz]",
            "zeta half-power [%]",
            "VF rel. RMS error",
            "record [samples]",
            "f_n, zeta with Hann Welch (3 x 50 %) [Hz, %]",
        ],
    );
    for run in &demo.runs {
        let l = run.linear.as_ref().expect("ran");
        let tm = &run.cfg.truth;
        let (fnt, zt) = (tm.omega_n() / TAU, tm.zeta());
        let (fi, zi) = (l.part.mode.frequency_hz, l.part.mode.zeta);
        t.push(vec![
            run.cfg.key.into(),
            format!("{fnt:.5}"),
            format!("{fi:.5}"),
            format!("{:+.4}", 100.0 * (fi - fnt) / fnt),
            format!("{:.4}", 100.0 * zt),
            format!("{:.4}", 100.0 * zi),
            format!("{:+.2}", 100.0 * (zi - zt) / zt),
            sig(l.part.stiffness.unwrap_or(f64::NAN), 7),
            sig(l.part.damping.unwrap_or(f64::NAN), 4),
            l.half_power
                .as_ref()
                .map(|h| format!("{:.5}", hz(h.omega_n)))
                .unwrap_or_else(|| "-".into()),
            l.half_power
                .as_ref()
                .map(|h| format!("{:.4}", 100.0 * h.zeta))
                .unwrap_or_else(|| "-".into()),
            format!("{:.2e}", l.fit.relative_rms_error),
            format!("{}", l.samples),
            l.hann
                .as_ref()
                .map(|(p, n, len)| {
                    format!(
                        "{:.5}, {:.4} ({:+.2} %) [{n} x {len}]",
                        p.mode.frequency_hz,
                        100.0 * p.mode.zeta,
                        100.0 * (p.mode.zeta - zt) / zt
                    )
                })
                .unwrap_or_else(|| "-".into()),
        ]);
    }
    tables.push(t);
    // comparison
    let mut t = Table::new(
        "fits",
        &[
            "configuration",
            "model",
            "paper",
            "exponents",
            "linear part",
            "free p",
            "cost (Eq 31) [s^4]",
            "RMS a/gamma [s^2]",
            "AIC",
            "BIC",
            "max |diff a_PQ| [%]",
            "max |diff f_PQ| [%]",
            "distinct minima",
        ],
    );
    for run in &demo.runs {
        let m = run.measured.as_ref().expect("ran");
        let n = m.data.len() as f64;
        let (ta, tf) = pq_max(&m.truth_pq);
        t.push(vec![
            run.cfg.key.into(),
            "true model (reference)".into(),
            "-".into(),
            "real".into(),
            "true".into(),
            "0".into(),
            format!("{:.4e}", m.truth_cost),
            format!("{:.4e}", (m.truth_cost / n).sqrt()),
            format!("{:.1}", n * (m.truth_cost / n).ln()),
            format!("{:.1}", n * (m.truth_cost / n).ln()),
            format!("{ta:.3}"),
            format!("{tf:.4}"),
            "-".into(),
        ]);
        for f in &run.fits {
            let r = &f.result;
            let (da, df) = pq_max(&f.pq);
            t.push(vec![
                run.cfg.key.into(),
                f.label.into(),
                f.paper.into(),
                exps(f).into(),
                match f.linear {
                    Linear::Fixed => "fixed (stage 2)".into(),
                    Linear::Free => "free".into(),
                },
                format!("{}", r.n_free),
                format!("{:.4e}", r.cost),
                format!("{:.4e}", r.rms_normalised()),
                format!("{:.1}", r.aic()),
                format!("{:.1}", r.bic()),
                format!("{da:.3}"),
                format!("{df:.4}"),
                if f.integer {
                    format!("{} pairs", f.integer_table.len())
                } else {
                    format!("{}", r.minima.len())
                },
            ]);
        }
    }
    tables.push(t);
    // parameters
    let mut t = Table::new(
        "parameters",
        &[
            "configuration",
            "model",
            "parameter",
            "unit",
            "status",
            "value",
            "95 % interval",
            "truth",
            "truth inside interval",
        ],
    );
    for run in &demo.runs {
        let mass = run.cfg.truth.mass;
        for f in &run.fits {
            let r = &f.result;
            for j in 0..N_PARAMS {
                if r.status[j] == Status::Absent || j == GAIN {
                    continue;
                }
                let unc = r
                    .uncertainty
                    .as_ref()
                    .and_then(|u| u.index(PARAM_NAMES[j]).map(|k| (u.lower[k], u.upper[k])));
                // the truth is comparable when the model has the true exponent structure
                let comparable = match j {
                    ALPHA | DELTA => true,
                    BETA => r.status[RHO] == Status::Free,
                    KAPPA => r.status[ETA] == Status::Free,
                    RHO | ETA => r.status[j] == Status::Free,
                    _ => false,
                };
                let truth = phys(j, run.truth_theta[j], mass);
                let inside = match (comparable, unc) {
                    (true, Some((lo, hi))) => {
                        let (lo, hi) = (phys(j, lo, mass), phys(j, hi, mass));
                        if truth >= lo && truth <= hi {
                            "yes"
                        } else {
                            "no"
                        }
                        .to_string()
                    }
                    _ => "-".into(),
                };
                t.push(vec![
                    run.cfg.key.into(),
                    f.id.into(),
                    Parameter::ALL[j].info().physical_name.into(),
                    Parameter::ALL[j].info().physical_unit.into(),
                    match r.status[j] {
                        Status::Free => "free".into(),
                        Status::Fixed(_) => "fixed".into(),
                        Status::Absent => "absent".into(),
                    },
                    sig(phys(j, r.theta[j], mass), 6),
                    unc.map(|(lo, hi)| {
                        format!(
                            "[{}, {}]",
                            sig(phys(j, lo, mass), 6),
                            sig(phys(j, hi, mass), 6)
                        )
                    })
                    .unwrap_or_else(|| "-".into()),
                    if comparable {
                        sig(truth, 6)
                    } else {
                        "-".into()
                    },
                    inside,
                ]);
            }
        }
    }
    tables.push(t);
    // integer search
    let mut t = Table::new(
        "integer_search",
        &["configuration", "model", "rho", "eta", "cost (Eq 31) [s^4]"],
    );
    for run in &demo.runs {
        for f in run.fits.iter().filter(|f| f.integer) {
            for (r, e, c) in &f.integer_table {
                t.push(vec![
                    run.cfg.key.into(),
                    f.id.into(),
                    r.map(|v| v.to_string())
                        .unwrap_or_else(|| "2 (fixed)".into()),
                    e.map(|v| v.to_string()).unwrap_or_else(|| "-".into()),
                    match c {
                        Ok(c) => format!("{c:.4e}"),
                        Err(e) => format!("error: {e}"),
                    },
                ]);
            }
        }
    }
    tables.push(t);
    // Table 8
    let mut t = Table::new(
        "phase_quadrature",
        &[
            "configuration",
            "gamma P-P [m/s^2]",
            "a_PQ measured [m]",
            "f_PQ measured [Hz]",
            "a_PQ true model [m]",
            "f_PQ true model [Hz]",
            "a_PQ real [m]",
            "diff a [%]",
            "f_PQ real [Hz]",
            "diff f [%]",
            "a_PQ integer [m]",
            "diff a [%]",
            "f_PQ integer [Hz]",
            "diff f [%]",
        ],
    );
    for run in &demo.runs {
        let m = run.measured.as_ref().expect("ran");
        let gr = &run.fits.iter().find(|f| f.id == "g-real").expect("ran").pq;
        let gi = &run.fits.iter().find(|f| f.id == "g-int").expect("ran").pq;
        for (i, ((tr, r), ig)) in m.truth_pq.iter().zip(gr).zip(gi).enumerate() {
            let (dfr, dar) = r.differences_percent();
            let (dfi, dai) = ig.differences_percent();
            let o = |v: Option<f64>, n: usize| v.map(|x| sig(x, n)).unwrap_or_else(|| "-".into());
            t.push(vec![
                run.cfg.key.into(),
                format!("{:.2}", LEVELS_PP[i]),
                sig(tr.measured_amplitude, 5),
                format!(
                    "{:.4}{}",
                    hz(tr.measured_omega),
                    if tr.measured_from == "peak" {
                        " (peak)"
                    } else {
                        ""
                    }
                ),
                o(tr.model_amplitude, 5),
                tr.model_omega
                    .map(|w| format!("{:.4}", hz(w)))
                    .unwrap_or_else(|| "-".into()),
                o(r.model_amplitude, 5),
                pct(dar),
                r.model_omega
                    .map(|w| format!("{:.4}", hz(w)))
                    .unwrap_or_else(|| "-".into()),
                pct(dfr),
                o(ig.model_amplitude, 5),
                pct(dai),
                ig.model_omega
                    .map(|w| format!("{:.4}", hz(w)))
                    .unwrap_or_else(|| "-".into()),
                pct(dfi),
            ]);
        }
    }
    tables.push(t);
    // Eq 33
    let mut t = Table::new(
        "spectrogram_eq33",
        &[
            "configuration",
            "level",
            "gamma P-P [m/s^2]",
            "dwell per step [s]",
            "record [s]",
            "samples (64 Hz)",
            "STFT L",
            "segments",
            "bin width [Hz]",
            "Eq 33 max [%]",
            "at t [s]",
            "at f [Hz]",
            "robust max (>= 1 % of peak) [%]",
            "at f [Hz]",
            "global L2 diff [%]",
            "time-domain rel. RMS error [%]",
        ],
    );
    for run in &demo.runs {
        for (tl, ls) in run.time.iter().zip(&run.spectra) {
            let d = &ls.diff;
            t.push(vec![
                run.cfg.key.into(),
                format!("{}", tl.level + 1),
                format!("{:.2}", LEVELS_PP[tl.level]),
                format!("{:.2}", tl.dwell_s),
                format!("{:.1}", tl.duration_s),
                format!("{}", tl.samples),
                format!("{}", ls.segment_len),
                format!("{}", ls.n_time),
                format!("{:.5}", ls.resolution_hz),
                sig(d.max_relative_percent, 4),
                format!("{:.0}", d.at_time),
                format!("{:.3}", d.at_frequency),
                sig(d.robust_max_relative_percent, 4),
                format!("{:.3}", d.robust_at_frequency),
                sig(d.global_relative_percent, 4),
                sig(100.0 * tl.relative_rms_error, 4),
            ]);
        }
    }
    tables.push(t);
    tables
}

fn fit_json(run: &nlsdof::demo::ConfigRun, f: &FitEntry) -> Value {
    let r = &f.result;
    let mass = run.cfg.truth.mass;
    let params: Vec<Value> = (0..N_PARAMS)
        .filter(|&j| r.status[j] != Status::Absent && j != GAIN)
        .map(|j| {
            let unc = r.uncertainty.as_ref().and_then(|u| {
                u.index(PARAM_NAMES[j]).map(|k| (u.lower[k], u.upper[k], u.std_errors[k]))
            });
            let comparable = match j {
                ALPHA | DELTA => true,
                BETA => r.status[RHO] == Status::Free,
                KAPPA => r.status[ETA] == Status::Free,
                RHO | ETA => r.status[j] == Status::Free,
                _ => false,
            };
            json!({
                "name": PARAM_NAMES[j],
                "status": match r.status[j] { Status::Free => "free", Status::Fixed(_) => "fixed", Status::Absent => "absent" },
                "value": r.theta[j],
                "std_error": unc.map(|u| u.2),
                "ci95": unc.map(|u| [u.0, u.1]),
                "truth": comparable.then_some(run.truth_theta[j]),
                "physical": {"name": Parameter::ALL[j].info().physical_name, "unit": Parameter::ALL[j].info().physical_unit, "value": phys(j, r.theta[j], mass),
                             "ci95": unc.map(|u| [phys(j, u.0, mass), phys(j, u.1, mass)]),
                             "truth": comparable.then_some(phys(j, run.truth_theta[j], mass))},
            })
        })
        .collect();
    let pq: Vec<Value> =
        f.pq.iter()
            .map(|p| {
                let (df, da) = p.differences_percent();
                json!({"level": p.level, "gamma": p.gamma, "measured_f_hz": hz(p.measured_omega),
                   "measured_amplitude": p.measured_amplitude, "measured_from": p.measured_from,
                   "model_f_hz": p.model_omega.map(hz), "model_amplitude": p.model_amplitude,
                   "diff_f_percent": df, "diff_amplitude_percent": da})
            })
            .collect();
    json!({
        "id": f.id, "label": f.label, "paper": f.paper, "model": f.kind.name(),
        "exponents": exps(f),
        "linear_part": match f.linear { Linear::Fixed => "fixed", Linear::Free => "free" },
        "cost": r.cost, "rms_normalised": r.rms_normalised(), "aic": r.aic(), "bic": r.bic(),
        "points": r.n_points, "free_parameters": r.n_free,
        "termination": r.termination.name(), "iterations": r.iterations,
        "distinct_minima": r.minima.len(),
        "theta": r.theta.to_array(),
        "parameters": params,
        "levels": r.levels.iter().map(|l| json!({"level": l.level, "gamma": l.gamma, "rms": l.rms, "rms_normalised": l.rms_normalised})).collect::<Vec<_>>(),
        "integer_pairs": f.integer_table.iter().map(|(r, e, c)| json!({"rho": r, "eta": e,
            "cost": c.as_ref().ok(), "error": c.as_ref().err()})).collect::<Vec<_>>(),
        "phase_quadrature": pq,
    })
}

fn summary_json(demo: &Demo) -> Value {
    let s = &demo.settings;
    let configs: Vec<Value> = demo
        .runs
        .iter()
        .map(|run| {
            let tm = &run.cfg.truth;
            let m = run.measured.as_ref().expect("ran");
            let l = run.linear.as_ref().expect("ran");
            let ks = tm.nonlinear_stiffness.expect("truth");
            let cd = tm.nonlinear_damping.expect("truth");
            let (fnt, zt) = (tm.omega_n() / TAU, tm.zeta());
            json!({
                "name": run.cfg.key,
                "truth": {"m": tm.mass, "k": tm.stiffness, "c": tm.damping,
                          "k_r": ks.coefficient, "rho": ks.exponent, "c_e": cd.coefficient, "eta": cd.exponent,
                          "f_n_hz": fnt, "zeta": zt, "theta": run.truth_theta.to_array()},
                "rig": {
                    "levels": m.sweeps.iter().enumerate().map(|(i, sw)| json!({
                        "gamma_pp": LEVELS_PP[i], "gamma": sw.gamma, "steps": sw.points.len(),
                        "unsettled": sw.points.iter().filter(|p| !p.settled).count(),
                        "simulated_s": sw.duration, "mean_dwell_s": m.mean_dwell(i)})).collect::<Vec<_>>(),
                    "noise_rms_normalised": m.noise_rms_normalised,
                    "truth_cost": m.truth_cost,
                    "truth_rms_normalised": (m.truth_cost / m.data.len() as f64).sqrt(),
                    "phase_quadrature_truth": m.truth_pq.iter().map(|p| json!({
                        "level": p.level, "measured_f_hz": hz(p.measured_omega), "measured_amplitude": p.measured_amplitude,
                        "measured_from": p.measured_from,
                        "model_f_hz": p.model_omega.map(hz), "model_amplitude": p.model_amplitude})).collect::<Vec<_>>(),
                },
                "linear_id": {
                    "f_n_hz": l.part.mode.frequency_hz, "zeta": l.part.mode.zeta,
                    "alpha": l.part.alpha, "delta": l.part.delta,
                    "k": l.part.stiffness, "c": l.part.damping, "mass_given": tm.mass,
                    "truth_f_n_hz": fnt, "truth_zeta": zt,
                    "f_n_error_percent": 100.0 * (l.part.mode.frequency_hz - fnt) / fnt,
                    "zeta_error_percent": 100.0 * (l.part.mode.zeta - zt) / zt,
                    "vf_relative_rms_error": l.fit.relative_rms_error,
                    "vf_iterations": l.fit.iterations,
                    "vf_termination": l.fit.termination.to_string(),
                    "half_power": l.half_power.as_ref().map(|h| json!({"f_n_hz": hz(h.omega_n), "zeta": h.zeta})),
                    "welch": {"segments": l.averages, "segment_len": l.segment, "window": "rectangular", "samples": l.samples, "fs_hz": FS_RECORD},
                    "hann_welch_comparison": l.hann.as_ref().map(|(p, n, len)| json!({"f_n_hz": p.mode.frequency_hz, "zeta": p.mode.zeta, "segments": n, "segment_len": len})),
                },
                "fits": run.fits.iter().map(|f| fit_json(run, f)).collect::<Vec<_>>(),
                "time_frequency": run.time.iter().zip(&run.spectra).map(|(tl, ls)| json!({
                    "level": tl.level + 1, "gamma": tl.gamma, "dwell_s": tl.dwell_s, "duration_s": tl.duration_s,
                    "samples": tl.samples, "stft_segment_len": ls.segment_len, "stft_segments": ls.n_time, "stft_bins": ls.n_freq,
                    "bin_width_hz": ls.resolution_hz,
                    "eq33_max_relative_percent": finite_or_null(ls.diff.max_relative_percent),
                    "eq33_at_time_s": ls.diff.at_time, "eq33_at_frequency_hz": ls.diff.at_frequency,
                    "robust_max_relative_percent": finite_or_null(ls.diff.robust_max_relative_percent),
                    "robust_at_frequency_hz": ls.diff.robust_at_frequency,
                    "floor_fraction": ls.diff.floor_fraction,
                    "bins_compared": ls.diff.bins_compared, "bins_total": ls.diff.bins_total,
                    "global_relative_percent": ls.diff.global_relative_percent,
                    "time_relative_rms_error": tl.relative_rms_error,
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    json!({
        "command": "nlsdof demo",
        "seed": s.seed, "quick": s.quick, "starts": s.starts, "steps": s.steps,
        "integer_radius": s.integer_radius,
        "units": {"gamma": "m/s^2 zero-to-peak", "amplitude": "m zero-to-peak", "frequency": "Hz",
                  "cost": "s^4 (sum of (a/gamma)^2 residuals)", "theta": "mass-normalised: alpha 1/s^2, delta 1/s, beta 1/(m^rho s^2), kappa (s/m)^eta / s, rho, eta, gain"},
        "noise_model": noise_model(s.noise_rel),
        "levels_pp": LEVELS_PP,
        "band_hz": [F_MIN, F_MAX],
        "configurations": configs,
    })
}

fn finite_or_null(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// Writes the figures, tables and a provisional summary; returns what [`finish`] needs.
/// The exponent landscape of the unloaded wing's generalised fit with the
/// linear part free (`g-free`): where the equation-error minima are and
/// where the output error ended. `false` if that fit is absent.
fn fig_landscape(demo: &Demo, dir: &Path) -> Result<bool, ReportError> {
    let Some(id) = demo
        .runs
        .first()
        .and_then(|r| r.fits.iter().find(|f| f.id == "g-free"))
        .and_then(|f| f.identification.as_ref())
    else {
        return Ok(false);
    };
    let svg = crate::landscape::render(id, crate::landscape::Kind::Svg)?;
    write_svg(
        dir,
        "fig10_landscape.svg",
        String::from_utf8_lossy(&svg).into_owned(),
    )?;
    Ok(true)
}

/// Number of times [`write_all`] calls its `step` callback.
pub const WRITE_STEPS: u64 = 8;

/// Writes the figures (SVG, PNG) and the tables (CSV) of the report into
/// `dir`, calling `step` [`WRITE_STEPS`] times as it goes (for a progress
/// bar).
pub fn write_all(demo: &Demo, dir: &Path, step: &dyn Fn()) -> Result<Written, ReportError> {
    let len = Length::of(demo);
    fig2(demo, dir, len)?;
    step();
    fig4(demo, dir)?;
    step();
    fit_figure(
        demo,
        dir,
        &["classic-a", "classic-b", "classic"],
        "fig5_classic.svg",
        "Fig 5 analogue: classic model (Duffing + quadratic damping), fitted to (top) levels 1-2, (middle) levels 4-5, (bottom) all levels — dots: data, lines: model",
        len,
    )?;
    step();
    fit_figure(
        demo,
        dir,
        &["dg-int", "dg-real"],
        "fig6_duffing_generalised.svg",
        "Fig 6 analogue: Duffing stiffness + generalised damping, (top) integer η, (bottom) real η",
        len,
    )?;
    step();
    fit_figure(
        demo,
        dir,
        &["g-int", "g-real"],
        "fig7_generalised.svg",
        "Fig 7 analogue: generalised stiffness and damping, (top) integer ρ, η, (bottom) real ρ, η",
        len,
    )?;
    step();
    fig_rms(demo, dir, len)?;
    fig_time(demo, dir, len)?;
    let landscape = fig_landscape(demo, dir)?;
    step();
    let pngs = fig8_png(demo, dir)?;
    step();
    let tables = build_tables(demo);
    for t in &tables {
        write_atomic(
            &dir.join("tables").join(format!("{}.csv", t.name)),
            t.csv().as_bytes(),
        )?;
    }
    step();
    let mut figures: Vec<(String, String)> = vec![
        ("fig2_stepped_sine_data.svg".into(), "Fig 2".into()),
        ("fig4_linear_frf.svg".into(), "Fig 4".into()),
        ("fig5_classic.svg".into(), "Fig 5".into()),
        ("fig6_duffing_generalised.svg".into(), "Fig 6".into()),
        ("fig7_generalised.svg".into(), "Fig 7".into()),
        ("fig9_rms_per_level.svg".into(), "residuals".into()),
        ("fig8c_time_envelope.svg".into(), "time".into()),
    ];
    if landscape {
        figures.push(("fig10_landscape.svg".into(), "landscape".into()));
    }
    figures.extend(pngs.into_iter().map(|p| (p, "Fig 8".into())));
    Ok(Written {
        summary: summary_json(demo),
        tables,
        figures,
    })
}

/// Adds the timings, writes `summary.json`, `tables/timings.csv` and `report.md`.
pub fn finish(demo: &Demo, dir: &Path, w: Written, total: f64) -> Result<Value, ReportError> {
    let mut summary = w.summary;
    let timings: serde_json::Map<String, Value> = demo
        .timings
        .iter()
        .map(|(k, v)| (k.clone(), json!(v)))
        .chain(std::iter::once(("total".to_string(), json!(total))))
        .collect();
    summary["timings_s"] = Value::Object(timings);
    summary["figures"] = json!(w.figures.iter().map(|f| f.0.clone()).collect::<Vec<_>>());
    summary["tables"] = json!(w
        .tables
        .iter()
        .map(|t| format!("tables/{}.csv", t.name))
        .collect::<Vec<_>>());
    let mut tt = Table::new("timings", &["stage", "wall time [s]"]);
    for (k, v) in &demo.timings {
        tt.push(vec![k.clone(), format!("{v:.2}")]);
        if k == "nonlinear fits" {
            for run in &demo.runs {
                for f in &run.fits {
                    tt.push(vec![
                        format!("- fit {} / {}", run.cfg.key, f.id),
                        format!("{:.2}", f.seconds),
                    ]);
                }
            }
        }
    }
    tt.push(vec![
        "total (incl. start-up and folder handling)".into(),
        format!("{total:.2}"),
    ]);
    write_atomic(&dir.join("tables").join("timings.csv"), tt.csv().as_bytes())?;
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .expect("json")
            .as_bytes(),
    )?;
    let md = markdown::report_md(demo, &w.tables, &w.figures, &tt);
    write_atomic(&dir.join("report.md"), md.as_bytes())?;
    Ok(summary)
}

/// A few lines on stdout (without --json): the key numbers of each configuration.
pub fn text_summary(demo: &Demo, out: &Path) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "report: {}", out.join("report.md").display());
    for run in &demo.runs {
        let (Some(m), Some(l)) = (run.measured.as_ref(), run.linear.as_ref()) else {
            continue;
        };
        let tm = &run.cfg.truth;
        let _ = writeln!(
            s,
            "{}: linear id f_n = {:.5} Hz (true {:.5}), zeta = {:.4} % (true {:.4} %)",
            run.cfg.key,
            l.part.mode.frequency_hz,
            tm.omega_n() / TAU,
            100.0 * l.part.mode.zeta,
            100.0 * tm.zeta()
        );
        let _ = writeln!(
            s,
            "  Eq 31 cost / true model's (1 = as good as the truth): {}",
            run.fits
                .iter()
                .map(|f| format!("{} {:.2}", f.id, f.result.cost / m.truth_cost))
                .collect::<Vec<_>>()
                .join(", ")
        );
        if let Some(best) = run
            .fits
            .iter()
            .min_by(|a, b| a.result.aic().total_cmp(&b.result.aic()))
        {
            let _ = writeln!(s, "  lowest AIC: {} ({})", best.id, best.label);
        }
        let robust = run
            .spectra
            .iter()
            .map(|x| x.diff.robust_max_relative_percent)
            .fold(0.0f64, f64::max);
        let raw = run
            .spectra
            .iter()
            .map(|x| x.diff.max_relative_percent)
            .fold(0.0f64, f64::max);
        let _ = writeln!(
            s,
            "  spectrograms, worst level: Eq 33 {} %, robust (>= 1 % of peak) {:.2} %",
            sig(raw, 4),
            robust
        );
    }
    s
}
