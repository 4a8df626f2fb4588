//! The stepped-sine fit (`nlsdof fit`, `nlsdof compare`, paper §4 Eq 31):
//! its JSON document, its text report, its model file and its SVG of data
//! against model.

use crate::ReportError;
use nlsdof::identification::models::{ALPHA, BETA, DELTA, GAIN};
use nlsdof::identification::phase_resonance::PrFitResult;
use nlsdof::identification::profile::OutputErrorProfile;
use nlsdof::identification::search::{IntegerPair, SignTrial};
use nlsdof::identification::uncertainty::Uncertainty;
use nlsdof::identification::{
    phase_quadrature_table, predicted_jumps, Dataset, FitResult, Identification, Minimum, Sign,
    Status, N_PARAMS, PARAM_NAMES,
};
use nlsdof::identification::{Parameter, Parameters};
use nlsdof::{Model, SweepDirection};
use nlsdof_figure::{self as figure, colour, Corner, Panel, Series};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;

fn hz(w: f64) -> f64 {
    w / (2.0 * PI)
}

fn status_name(s: Status) -> &'static str {
    match s {
        Status::Absent => "absent",
        Status::Fixed(_) => "fixed",
        Status::Free => "free",
    }
}

/// SVG of a sweep fit ([`fit_figure`] in SVG).
pub fn fit_svg(data: &Dataset, res: &FitResult) -> Result<String, ReportError> {
    let bytes = fit_figure(data, res, figure::Format::Svg)?;
    Ok(String::from_utf8(bytes).expect("SVG is text"))
}

/// The figure of a sweep fit (`fit --plot`, SVG or PNG): measured
/// amplitudes (markers, every point up to 300 per curve) and the model's
/// branch-following amplitudes at the same steps (one line per curve), one
/// colour per level ([`figure::colour`], 20 distinct), up-sweeps solid with
/// filled dots and down-sweeps dashed with hollow circles
/// ([`figure::sweep_styles`]); zero-to-peak amplitude in one length unit
/// chosen from the data ([`figure::length_unit`]) against Hz.
pub fn fit_figure(
    data: &Dataset,
    res: &FitResult,
    format: figure::Format,
) -> Result<Vec<u8>, ReportError> {
    let top = data
        .curves
        .iter()
        .flat_map(|c| c.amplitudes.iter())
        .chain(&res.model_amplitudes)
        .fold(0.0f64, |m, &a| if a.is_finite() { m.max(a) } else { m });
    let (unit, scale) = figure::length_unit(top);
    let mut panel = Panel::new(
        format!(
            "nlsdof fit: {} (markers: data, lines: model), cost {:.4e}",
            res.kind, res.cost
        ),
        "frequency f [Hz]",
        &format!("amplitude a [{unit}], zero-to-peak"),
    );
    panel.legend = Corner::Outside;
    if top > 0.0 {
        panel.y_range = Some((0.0, 1.05 * top * scale));
    }
    // one colour per level, in the order the levels first appear
    let mut levels: Vec<&str> = Vec::new();
    let (mut any_up, mut any_down) = (false, false);
    let mut off = 0;
    for c in &data.curves {
        let i = match levels.iter().position(|l| *l == c.level.as_str()) {
            Some(i) => i,
            None => {
                levels.push(c.level.as_str());
                levels.len() - 1
            }
        };
        let n = c.omegas.len();
        let f: Vec<f64> = c.omegas.iter().map(|&w| hz(w)).collect();
        let model = (0..n).map(|k| (f[k], res.model_amplitudes[off + k] * scale));
        let stride = (n / 300).max(1);
        let measured = (0..n)
            .step_by(stride)
            .map(|k| (f[k], c.amplitudes[k] * scale));
        let up = c.direction == SweepDirection::Up;
        any_up |= up;
        any_down |= !up;
        let (line, marker) = figure::sweep_styles(up, 2, 2);
        let dir = if up { "up" } else { "down" };
        panel.series.push(
            Series::new(model.collect(), colour(i), line).label(format!("{} {dir}", c.level)),
        );
        panel
            .series
            .push(Series::new(measured.collect(), colour(i), marker));
        off += n;
    }
    for (present, up, dir) in [(any_up, true, "up"), (any_down, false, "down")] {
        if present {
            let (line, marker) = figure::sweep_styles(up, 2, 2);
            panel
                .series
                .push(Series::new(vec![], figure::DARK, line).label(format!("model, sweep {dir}")));
            panel.series.push(
                Series::new(vec![], figure::DARK, marker).label(format!("data, sweep {dir}")),
            );
        }
    }
    Ok(figure::render_as(
        format,
        "Stepped-sine fit",
        &[panel],
        1,
        1100,
        600,
    )?)
}

/// The JSON document of a staged fit ([`nlsdof::identification::identify()`]):
/// `nlsdof fit --json` and the Python `FitResult.to_dict()`. The fit's
/// document ([`result_json`]) with the jump weight and the stages
/// ([`identification_json`]).
pub fn identification_document(
    id: &Identification,
    mass: Option<f64>,
) -> Result<Value, ReportError> {
    let mut v = result_json(&id.data, &id.fit, mass)?;
    v["warning"] = json!(id.warning());
    // a likely unit mistake (levels in g, amplitudes in mm), also the
    // warning's first line
    v["unit_hint"] = json!(id.unit_hint());
    v["notes"] = json!(id.fit.notes());
    v["adequacy"] = adequacy_json(id);
    v["levels"] = Value::Array(curves_json(id));
    v["jump_weight"] = json!(id.jump_weight);
    if !id.sign_trials.is_empty() {
        if let Some(t) = sign_trials_json(&id.sign_trials) {
            v["sign_auto"] = t;
        }
    }
    v["identification"] = identification_json(id);
    Ok(v)
}

/// The self-check against the noise as JSON: `adequate`, the residual in
/// units of the noise over all points, the curves that do not fit, the
/// thresholds and what was tried.
pub fn adequacy_json(id: &Identification) -> Value {
    use nlsdof::identification::identify::{ADEQUACY_ALL, ADEQUACY_CURVE, ADEQUACY_PEAKS};
    let a = &id.adequacy;
    json!({
        "adequate": a.adequate,
        "residual_over_noise": a.ratio,
        "peak_residual_over_noise": a.peak_ratio,
        "amplitude_residual_over_noise": a.split.map(|s| s.ratios().0),
        "phase_residual_over_noise": a.split.map(|s| s.ratios().1),
        "failing_levels": a.failing.iter().map(|&i| {
            let c = &id.curves[i];
            json!({"level": c.level, "sweep": c.direction.name(), "residual_over_noise": c.noise.ratio()})
        }).collect::<Vec<_>>(),
        "message": id.adequacy_message(),
        "thresholds": {"curve_mean_z2": ADEQUACY_CURVE, "all_mean_z2": ADEQUACY_ALL, "peaks_mean_z2": ADEQUACY_PEAKS,
                       "note": "z = residual / local noise (estimated from the fit's residuals by pseudo-residuals); a curve does not fit when mean z^2 exceeds curve_mean_z2, the data when the mean over all points exceeds all_mean_z2 or the mean over the resonance peaks (points at least half their curve's peak) exceeds peaks_mean_z2 (there against the noise the peaks' own pseudo-residuals support, where they reject the estimate at their chi^2 0.1 % point); residual_over_noise and peak_residual_over_noise are sqrt(mean z^2); with phases, amplitude_residual_over_noise and phase_residual_over_noise are the same over the amplitude residuals (with the jump penalties) and over the phase residuals apart (null without phases)"},
        "escalation": a.escalation,
        "late_folds": a.late_folds.iter().map(|&(i, r)| {
            let c = &id.curves[i];
            json!({"level": c.level, "sweep": c.direction.name(),
                   "left_early_by_hz": c.left_early_by.map(hz),
                   "model_sweep_residual_over_noise": r})
        }).collect::<Vec<_>>(),
        "needs_early_jumps": a.needs_early_jumps.map(|r| json!({
            "note": "the fit fits the noise only with the jumps of these curves read as censored (the sweep left its branch before the model's fold); read exactly it does not",
            "exact_residual_over_noise": r,
            "censored": id.curves.iter().filter(|c| c.reading == nlsdof::identification::output_error::JumpReading::Censored)
                .map(|c| json!({"level": c.level, "sweep": c.direction.name()})).collect::<Vec<_>>(),
        })),
    })
}

/// Per-curve JSON of a staged fit: RMS, jump reading, measured and model
/// jump, whether the sweep left its branch early and by how much, the
/// residual against the noise, the upper-branch RMS and the peaks.
pub fn curves_json(id: &Identification) -> Vec<Value> {
    id.fit
        .levels
        .iter()
        .zip(&id.curves)
        .map(|(l, c)| {
            json!({
                "level": l.level, "gamma": l.gamma, "sweep": l.direction.name(),
                "points": l.points, "rms": l.rms, "rms_normalised": l.rms_normalised,
                "jump_reading": c.reading.name(),
                "measured_jump_f_hz": c.measured_jump.map(hz),
                "measured_jump_next_f_hz": c.measured_jump_next.map(hz),
                "model_jump_f_hz": c.model_jump.map(hz),
                "left_early": c.left_early_by.is_some(),
                "left_early_by_hz": c.left_early_by.map(hz),
                "residual_over_noise": c.noise.ratio(),
                "amplitude_residual_over_noise": c.noise.split.map(|s| s.ratios().0),
                "phase_residual_over_noise": c.noise.split.map(|s| s.ratios().1),
                "noise_rms": c.noise.noise_rms,
                "upper_branch_rms": c.upper_branch_rms,
                "peak_measured": c.peak.0, "peak_model": c.peak.1,
            })
        })
        .collect()
}

/// The text report of a staged fit: the first lines say whether the model
/// fits the noise and whether the fit is to be trusted (nothing when it
/// is), then results worth a line (natural bounds, vanished terms), the
/// fit, the per-level table and the stages that led to it.
pub fn identification_report(
    id: &Identification,
    mass: Option<f64>,
) -> Result<String, ReportError> {
    identification_report_with(id, mass, &[], crate::intervals::IntervalView::One)
}

/// [`identification_report`] with the output-error `profiles` computed
/// (`fit --profile`) and the intervals of `view` ([`crate::intervals`]):
/// one 95 % interval per parameter in the table, labelled with its method,
/// or also every other interval with what it leaves out.
pub fn identification_report_with(
    id: &Identification,
    mass: Option<f64>,
    profiles: &[OutputErrorProfile],
    view: crate::intervals::IntervalView,
) -> Result<String, ReportError> {
    let mut s = String::new();
    if let Some(w) = id.warning() {
        writeln!(s, "{w}").ok();
    }
    for n in id.fit.notes() {
        writeln!(s, "note: {n}").ok();
    }
    if !id.sign_trials.is_empty() {
        let chosen = if id.fit.theta[BETA] < 0.0 {
            Sign::Softening
        } else {
            Sign::Hardening
        };
        s.push_str(&sign_trials_text(&id.sign_trials, chosen));
    }
    let chosen = crate::intervals::chosen(&id.fit, profiles);
    result_text_body(&mut s, &id.data, &id.fit, mass, Some(&chosen))?;
    s.push_str(&crate::intervals::default_text(id, profiles));
    if view == crate::intervals::IntervalView::All {
        s.push_str(&crate::intervals::all_text(id, profiles));
    }
    s.push_str(&curves_text(id));
    s.push_str(&pq_text(&id.data, &id.fit)?);
    minima_text(&mut s, &id.fit.minima, &id.fit.status);
    s.push('\n');
    s.push_str(&identification_text(id));
    Ok(s)
}

/// `--integer`: every integer node of the landscape (equation-error cost)
/// with the output-error objective of the nodes that were fitted.
pub fn integer_nodes_json(id: &Identification) -> Value {
    let l = &id.landscape;
    let mut rows = Vec::new();
    for (j, &eta) in l.eta.iter().enumerate() {
        for (i, &rho) in l.rho.iter().enumerate() {
            let fitted = id
                .candidates
                .iter()
                .find(|c| c.rho == rho && c.eta == eta)
                .and_then(|c| c.oe.as_ref().ok().copied());
            rows.push(json!({"rho": rho, "eta": eta, "ee_cost": l.at(i, j), "objective": fitted}));
        }
    }
    Value::Array(rows)
}

/// `--integer` table as text: the fitted nodes first (lowest objective
/// first), then the equation-error cost of the others.
pub fn integer_nodes_text(id: &Identification) -> String {
    let mut s = String::new();
    let mut fitted: Vec<_> = id
        .candidates
        .iter()
        .filter_map(|c| c.oe.as_ref().ok().map(|o| (c.rho, c.eta, c.ee_cost, *o)))
        .collect();
    fitted.sort_by(|a, b| a.3.total_cmp(&b.3));
    writeln!(
        s,
        "\ninteger exponents: {} nodes in the landscape, {} fitted by output error",
        id.landscape.rho.len() * id.landscape.eta.len(),
        fitted.len()
    )
    .ok();
    writeln!(
        s,
        "  {:>5} {:>5} {:>14} {:>14}",
        "rho", "eta", "ee cost", "objective"
    )
    .ok();
    for (r, e, ee, o) in &fitted {
        writeln!(s, "  {r:>5} {e:>5} {ee:>14.6e} {o:>14.6e}").ok();
    }
    s
}

/// The per-level table of a staged fit (text).
pub fn curves_text(id: &Identification) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "\nper level: {:<10} {:>5} {:>8} {:>12} {:>13} {:>13} {:>12} {:>10} {:>12} {:>12} {:>12}",
        "level",
        "sweep",
        "reading",
        "RMS [m]",
        "jump meas[Hz]",
        "jump model",
        "early by[Hz]",
        "res/noise",
        "upper RMS",
        "peak meas",
        "peak model"
    )
    .ok();
    let f = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    for (l, c) in id.fit.levels.iter().zip(&id.curves) {
        writeln!(
            s,
            "           {:<10} {:>5} {:>8} {:>12.4e} {:>13} {:>13} {:>12} {:>10.2} {:>12} {:>12.4e} {:>12.4e}",
            l.level,
            l.direction.name(),
            c.reading.name(),
            l.rms,
            f(c.measured_jump.map(hz), 3),
            f(c.model_jump.map(hz), 3),
            f(c.left_early_by.map(hz), 3),
            c.noise.ratio(),
            c.upper_branch_rms.map_or("-".to_string(), |v| format!("{v:.4e}")),
            c.peak.0,
            c.peak.1,
        )
        .ok();
    }
    s
}

/// JSON of output-error profile intervals (`fit --profile`): name ->
/// {estimate, ci95 [lower, upper] (null: open), fits, points [[value,
/// statistic], ...]}.
pub fn profiles_json(profiles: &[OutputErrorProfile]) -> Value {
    let mut m = serde_json::Map::new();
    for p in profiles {
        m.insert(
            p.parameter.info().name.to_string(),
            json!({"estimate": p.estimate, "ci95": [p.lower, p.upper], "fits": p.fits,
                   "start": p.start, "refused": p.refusal(),
                   "points": p.points.iter().map(|&(v, s)| [v, s]).collect::<Vec<_>>(),
                   "note": "(P - P*)/sigma^2 <= 3.84, P the output-error objective with the exponent held; null = open (bound or step limit)"}),
        );
    }
    Value::Object(m)
}

/// Text lines of output-error profile intervals (`fit --profile`).
pub fn profiles_text(profiles: &[OutputErrorProfile]) -> String {
    let mut s = String::new();
    let f = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
    for p in profiles {
        writeln!(
            s,
            "profile 95 % interval (output error) {}: [{}, {}] around {:.4} ({} local fits)",
            p.parameter.info().name,
            f(p.lower),
            f(p.upper),
            p.estimate,
            p.fits
        )
        .ok();
    }
    s
}

/// JSON of the stages of [`nlsdof::identification::identify()`] (equation error, landscape,
/// phase convention, gain decision, candidates).
pub fn identification_json(id: &Identification) -> Value {
    let l = &id.landscape;
    let minima: Vec<Value> = l
        .minima
        .iter()
        .take(20)
        .map(|&(i, j)| json!({"rho": l.rho[i], "eta": l.eta[j], "cost": l.at(i, j)}))
        .collect();
    let prof = |p: Option<nlsdof::identification::landscape::ProfileInterval>| {
        p.map(|p| json!([p.lower, p.upper]))
    };
    json!({
        "equation_error": {"theta": id.equation_error.theta.to_array(), "cost": id.equation_error.cost,
                            "residuals": id.equation_error.n_residuals},
        "landscape": {"rho": [l.rho.first(), l.rho.last(), l.rho.len()],
                      "eta": [l.eta.first(), l.eta.last(), l.eta.len()],
                      "with_phase": l.with_phase, "minima": minima},
        "profile_ci95": {"rho": prof(id.rho_profile), "eta": prof(id.eta_profile),
                         "note": "profile likelihood of the equation-error cost over the landscape grid; null bound = open at the grid edge"},
        "phase_convention": id.phase.map(|p| json!({
            "sign": if p.sign > 0.0 { "lag" } else { "lead" },
            "offset_deg": p.offset.to_degrees(), "delay_s": p.delay})),
        "gain_test": id.gain_test.map(|g| json!({"equation_error_gain": g.gain, "equation_error_f": g.f_statistic, "freed": g.freed,
            "output_error": g.output_error.map(|o| json!({"held_objective": o.held, "free_objective": o.free, "free_gain": o.gain,
                "f_statistic": o.f_statistic, "at_bound": o.at_bound})),
            "note": "the equation-error test (biased by errors in variables) only chooses the starts; the output-error F test decides: freed when F > 10.83"})),
        "jump_weight": id.jump_weight,
        "candidates": id.candidates.iter().map(|c| json!({
            "rho": c.rho, "eta": c.eta, "ee_cost": c.ee_cost, "sign": c.sign.name(), "gain_held": c.gain,
            "objective": c.oe.as_ref().ok(), "error": c.oe.as_ref().err()})).collect::<Vec<_>>(),
    })
}

/// Text lines of the stages of [`nlsdof::identification::identify()`].
pub fn identification_text(id: &Identification) -> String {
    let mut s = String::new();
    let l = &id.landscape;
    // (the screen freed the gain: the nodes raced with it free and held)
    let held = id.candidates.iter().filter(|c| c.gain.is_some()).count();
    let both = if held > 0 && held < id.candidates.len() {
        format!(" ({held} of them with the gain held at 1, beside the free-gain race)")
    } else {
        String::new()
    };
    writeln!(
        s,
        "stages: equation error ({}) -> landscape {}x{} (rho {:.3}..{:.3}, eta {:.3}..{:.3}), {} grid minima -> output error from the best {}{both}",
        if l.with_phase { "amplitude and phase" } else { "amplitude" },
        l.rho.len(),
        l.eta.len(),
        l.rho[0],
        l.rho[l.rho.len() - 1],
        l.eta[0],
        l.eta[l.eta.len() - 1],
        l.minima.len(),
        id.candidates.len()
    )
    .ok();
    if let Some(p) = id.phase {
        writeln!(
            s,
            "phase convention: {} {:+.2} deg{} (measured phase = {}displacement lag + offset)",
            if p.sign > 0.0 { "lag" } else { "lead" },
            p.offset.to_degrees(),
            if p.delay != 0.0 {
                format!(" + delay {:.3e} s", p.delay)
            } else {
                String::new()
            },
            if p.sign > 0.0 { "" } else { "-" }
        )
        .ok();
    }
    if let Some(g) = id.gain_test {
        let t = nlsdof::identification::identify::GAIN_F_THRESHOLD;
        match g.output_error {
            // the decision first, then its reason (issue 28: "held at 1
            // (..., F = 1.392e4, freed when F > 10.83)" read as a
            // contradiction when the estimate was outside the bounds)
            Some(o) => writeln!(
                s,
                "gain: {} (output error: free gain {:.4}, F = {:.3e} {} {t}{}; equation-error screen {:.4}, F = {:.3e})",
                if g.freed {
                    "free: freeing it lowers the output error significantly"
                } else {
                    "held at 1: freeing it does not lower the output error significantly"
                },
                o.gain,
                o.f_statistic,
                if o.f_statistic > t { ">" } else { "<=" },
                if o.at_bound { "; the free gain sits at its bound" } else { "" },
                g.gain,
                g.f_statistic,
            ),
            None => {
                let (lo, hi) = id.spec.bounds[nlsdof::identification::models::GAIN];
                let outside = !(g.gain > lo && g.gain < hi);
                if !g.freed && g.f_statistic > t && outside {
                    // significant, but the estimate lies outside the
                    // bounds: that is why it is held, and a unit mistake
                    // is the likely cause
                    writeln!(
                        s,
                        "gain: held at 1 because the equation-error estimate {:.4} lies outside the gain's bounds [{lo}, {hi}] (F = {:.3e} > {t} would free it otherwise): check the units of the levels (g instead of m/s^2? --gamma-in-g) and amplitudes (mm instead of m?)",
                        g.gain, g.f_statistic,
                    )
                } else {
                    writeln!(
                        s,
                        "gain: {} (equation-error gain {:.4}, F = {:.3e} {} {t})",
                        if g.freed {
                            "free: freeing it lowers the equation error significantly"
                        } else {
                            "held at 1: freeing it does not lower the equation error significantly"
                        },
                        g.gain,
                        g.f_statistic,
                        if g.f_statistic > t { ">" } else { "<=" },
                    )
                }
            }
        }
        .ok();
    }
    let censored = id.spec.censored.iter().filter(|&&c| c).count();
    writeln!(
        s,
        "jumps: weight {} ({} of {} curves read as censored: the sweep may leave its branch before the fold)",
        id.jump_weight,
        censored,
        id.data.curves.len()
    )
    .ok();
    // (the equation-error profile intervals are in the `--intervals all`
    // section, crate::intervals, with what they leave out)
    s
}

/// The `--out` model file of a fit: a header (model, cost, a note when the
/// fit is not trustworthy, the mass convention), the physical model for
/// `mass` (1 kg when not given), the forcing gain as `[signal] input_gain`
/// (the model sees `gain * gamma`: `nlsdof frf --model` and Python
/// `Model.sweep` apply it, so the file reproduces the fit's curves) and the
/// `[provenance]` table (`data`: the data as the user named it).
pub fn model_file_text(
    res: &FitResult,
    mass: Option<f64>,
    data: Option<&str>,
) -> Result<String, ReportError> {
    let model = physical(res, mass.unwrap_or(1.0))?;
    let mut text = format!(
        "# fitted by `nlsdof fit`, model {}, cost {:.6e}{}\n",
        res.kind,
        res.cost,
        match res.misfit {
            Some(r) =>
                format!(" (DOES NOT FIT its data: residual {r:.1}x the noise; see the fit report)"),
            None if res.warning().is_some() => {
                " (NOT CONVERGED or not identifiable: see the fit report)".to_string()
            }
            None => String::new(),
        },
    );
    if mass.is_none() {
        text.push_str("# no mass given: m = 1 kg, all values are per unit mass\n");
    }
    text.push_str(&nlsdof_io::model_file::model_to_toml(&model));
    text.push_str(&nlsdof_io::model_file::forcing_gain_to_toml(
        res.theta[GAIN],
    ));
    text.push_str(&nlsdof_io::model_file::provenance_to_toml(&provenance(
        res, data,
    )));
    Ok(text)
}

/// The `[provenance]` of a fit's model file (`data`: as the user named it).
pub fn provenance(res: &FitResult, data: Option<&str>) -> nlsdof_io::model_file::Provenance {
    nlsdof_io::model_file::Provenance {
        tool: Some("nlsdof fit".into()),
        version: Some(env!("CARGO_PKG_VERSION").into()),
        data: data.map(str::to_string),
        model: Some(res.kind.to_string()),
        objective: Some(
            "Eq 31: sum of squared amplitude residuals of the model's own sweeps (m^2, weighted)"
                .into(),
        ),
        cost: Some(res.cost),
        converged: Some(res.converged),
        range: None,
        ..Default::default()
    }
}

/// One measured point with the fit's model there (a row of `--predict`).
#[derive(Debug, Clone, PartialEq)]
pub struct PredictedPoint<'a> {
    pub level: &'a str,
    /// Measured level γ, m/s² zero-to-peak.
    pub gamma: f64,
    pub f_hz: f64,
    /// Measured amplitude, m zero-to-peak.
    pub amplitude: f64,
    pub sweep: &'static str,
    /// The model amplitude the fit compared (Eq 31: the model's own sweep).
    pub model_amplitude: f64,
    /// The model's phase lag there, deg.
    pub model_phase_deg: f64,
    /// Measured phase lag, deg, where the data have phases.
    pub phase_deg: Option<f64>,
}

/// Every measured point with the fit's model amplitude and phase there: the
/// fit's own model curves (Eq 31: each curve's model sweep at `gain * gamma`,
/// starting on the state nearest the measured first amplitude). Curves in
/// data order, points by increasing frequency. `--predict` and Python's
/// `FitResult.fitted_curves()`.
pub fn predicted_points(id: &Identification) -> Result<Vec<PredictedPoint<'_>>, ReportError> {
    let res = &id.fit;
    let response = nlsdof::identification::objective::model_response(&id.data, &res.theta)?;
    let mut out = Vec::with_capacity(res.model_amplitudes.len());
    let mut off = 0;
    for (c, model) in id.data.curves.iter().zip(&response) {
        for (k, (&w, &a)) in c.omegas.iter().zip(&c.amplitudes).enumerate() {
            out.push(PredictedPoint {
                level: &c.level,
                gamma: c.gamma,
                f_hz: hz(w),
                amplitude: a,
                sweep: c.direction.name(),
                // the amplitude the fit compared (bit for bit); its phase from the same sweep
                model_amplitude: res.model_amplitudes[off + k],
                model_phase_deg: model[k].1.to_degrees(),
                phase_deg: c.phases.as_ref().map(|p| p[k].to_degrees()),
            });
        }
        off += c.omegas.len();
    }
    Ok(out)
}

/// The `--predict` CSV of a fit: [`predicted_points`] as columns
/// `level,gamma,f_hz,amplitude,sweep,model_amplitude,model_phase_deg`, plus
/// `phase_deg` when the data have phases; SI, zero-to-peak, numbers written
/// to round-trip exactly. The file is itself a stepped-sine data file
/// (`nlsdof fit`, `nlsdof frf --at` read it).
pub fn predict_csv(id: &Identification) -> Result<String, ReportError> {
    let points = predicted_points(id)?;
    let with_phase = points.iter().any(|p| p.phase_deg.is_some());
    let mut s = String::from("level,gamma,f_hz,amplitude,sweep,model_amplitude,model_phase_deg");
    if with_phase {
        s.push_str(",phase_deg");
    }
    s.push('\n');
    let quote = |t: &str| {
        if t.contains([',', '"', '\n', '\r']) {
            format!("\"{}\"", t.replace('"', "\"\""))
        } else {
            t.to_string()
        }
    };
    for p in &points {
        write!(
            s,
            "{},{:?},{:?},{:?},{},{:?},{:?}",
            quote(p.level),
            p.gamma,
            p.f_hz,
            p.amplitude,
            p.sweep,
            p.model_amplitude,
            p.model_phase_deg
        )
        .ok();
        if with_phase {
            match p.phase_deg {
                Some(v) => write!(s, ",{v:?}").ok(),
                None => write!(s, ",").ok(),
            };
        }
        s.push('\n');
    }
    Ok(s)
}

/// Physical model for mass `m` (β, κ scaled; gain is not part of it).
pub fn physical(res: &FitResult, m: f64) -> Result<Model, ReportError> {
    Ok(res.model().to_physical(m)?)
}

/// The parameter block of a fit's JSON, one object per parameter present:
/// name, status, value, standard error and 95 % interval (when `unc` is
/// given), and the physical value for mass `mass` (1 kg when not given).
pub fn parameters_json(
    theta: &Parameters,
    status: &[Status; N_PARAMS],
    unc: Option<&Uncertainty>,
    mass: Option<f64>,
) -> Vec<Value> {
    let m = mass.unwrap_or(1.0);
    let mut params = Vec::new();
    for j in 0..N_PARAMS {
        if status[j] == Status::Absent {
            continue;
        }
        let unc = unc.and_then(|u| u.index(PARAM_NAMES[j]).map(|k| (u, k)));
        let info = Parameter::ALL[j].info();
        let phys = |v: f64| {
            if Parameter::ALL[j].mass_scaled() {
                v * m
            } else {
                v
            }
        };
        params.push(json!({
            "name": PARAM_NAMES[j],
            "status": status_name(status[j]),
            "value": theta[j],
            "std_error": unc.map(|(u, k)| u.std_errors[k]),
            "ci95": unc.map(|(u, k)| [u.lower[k], u.upper[k]]),
            "physical": { "name": info.physical_name, "unit": info.physical_unit, "value": phys(theta[j]),
                          "ci95": unc.map(|(u, k)| [phys(u.lower[k]), phys(u.upper[k])]) },
        }));
    }
    params
}

/// The distinct local minima of a fit as JSON: cost, starts that found it,
/// termination, θ.
pub fn minima_json(minima: &[Minimum]) -> Value {
    Value::Array(
        minima
            .iter()
            .map(|m| json!({"cost": m.cost, "count": m.count, "termination": m.termination.name(), "theta": m.theta.to_array()}))
            .collect(),
    )
}

/// The distinct local minima of a multistart (up to 20), one line each
/// with the free parameters; nothing when there was a single start.
fn minima_text(s: &mut String, minima: &[Minimum], status: &[Status; N_PARAMS]) {
    if !(minima.len() > 1 || minima.first().map_or(false, |m| m.count > 1)) {
        return;
    }
    writeln!(s, "\ndistinct local minima ({}):", minima.len()).ok();
    for (i, mm) in minima.iter().enumerate().take(20) {
        let free: Vec<String> = (0..N_PARAMS)
            .filter(|&j| status[j] == Status::Free)
            .map(|j| format!("{}={:.5e}", PARAM_NAMES[j], mm.theta[j]))
            .collect();
        writeln!(
            s,
            "  #{:<3} cost {:.6e}  starts {:>4}  {}  {}",
            i + 1,
            mm.cost,
            mm.count,
            mm.termination,
            free.join(" ")
        )
        .ok();
    }
}

/// JSON of one fit.
pub fn result_json(
    data: &Dataset,
    res: &FitResult,
    mass: Option<f64>,
) -> Result<Value, ReportError> {
    let valid = res.intervals_valid();
    let params = parameters_json(
        &res.theta,
        &res.status,
        res.uncertainty.as_ref().filter(|_| valid),
        mass,
    );
    let jumps = predicted_jumps(data, &res.theta)?;
    let levels: Vec<Value> = res
        .levels
        .iter()
        .zip(data.curves.iter().zip(&jumps))
        .map(|(l, (c, pj))| {
            json!({
                "level": l.level, "gamma": l.gamma,
                "sweep": if l.direction == SweepDirection::Up { "up" } else { "down" },
                "points": l.points, "rms": l.rms, "rms_normalised": l.rms_normalised,
                "measured_jump_f_hz": c.measured_jump(2.0).map(hz),
                "model_jump_f_hz": pj.map(hz),
            })
        })
        .collect();
    let pq: Vec<Value> = phase_quadrature_table(data, &res.theta)?
        .iter()
        .map(|r| {
            let (df, da) = r.differences_percent();
            json!({
                "level": r.level, "gamma": r.gamma, "measured_from": r.measured_from,
                "measured_f_hz": hz(r.measured_omega), "measured_amplitude": r.measured_amplitude,
                "model_f_hz": r.model_omega.map(hz), "model_amplitude": r.model_amplitude,
                "diff_f_percent": df, "diff_amplitude_percent": da,
            })
        })
        .collect();
    let minima = minima_json(&res.minima);
    let stiffness_sign = (res.status[BETA] != Status::Absent).then(|| {
        if res.theta[BETA] < 0.0 {
            "softening"
        } else {
            "hardening"
        }
    });
    Ok(json!({
        "model": res.kind.name(),
        "stiffness_sign": stiffness_sign,
        "converged": res.converged,
        "at_bounds": res.at_bounds,
        "unidentifiable": res.unidentifiable,
        "intervals_valid": valid,
        // the model does not fit its noise: the residual over the noise the
        // first line quotes (null when it fits); intervals are then not valid
        "misfit": res.misfit,
        "warning": res.warning(),
        "notes": res.notes(),
        "ridges": res.ridges.iter().map(|r| json!({"parameters": [r.first, r.second], "correlation": r.correlation, "remedy": r.remedy()})).collect::<Vec<_>>(),
        "crossings": res.crossings.iter().map(|c| json!({"parameter": c.name, "bound": c.bound})).collect::<Vec<_>>(),
        "natural_bounds": res.natural.iter().map(|n| json!({"parameter": n.name, "value": n.value, "meaning": n.meaning})).collect::<Vec<_>>(),
        "inactive": res.inactive.iter().map(|i| json!({"exponent": i.exponent, "coefficient": i.coefficient, "held_at": i.held_at})).collect::<Vec<_>>(),
        "objective": res.objective,
        "phase_cost": res.phase_cost,
        "parameters": params,
        "parameter_order": PARAM_NAMES,
        "theta": res.theta.to_array(),
        "mass": mass,
        "mass_note": if mass.is_none() { Some("no mass given: physical values are per unit mass (m = 1 kg)") } else { None },
        "cost": res.cost,
        "rms_normalised": res.rms_normalised(),
        "aic": res.aic(), "bic": res.bic(),
        "points": res.n_points, "free_parameters": res.n_free,
        "termination": res.termination.name(),
        "iterations": res.iterations,
        "correlation": res.uncertainty.as_ref().filter(|_| valid).map(|u| json!({"names": u.names, "matrix": u.correlation})),
        "minima": minima,
        "levels": levels,
        "phase_quadrature": pq,
    }))
}

/// The parameter block shared by the sweep and phase-resonance fit reports:
/// a note when no mass is given, one line per parameter (status, value,
/// standard error, 95 % interval, physical value) and `f_n`, `zeta`.
pub fn parameter_table_text(
    s: &mut String,
    theta: &Parameters,
    status: &[Status; N_PARAMS],
    unc: Option<&Uncertainty>,
    mass: Option<f64>,
) {
    parameter_rows(s, theta, status, unc, mass, None)
}

/// [`parameter_table_text`]; with `chosen`, the interval column holds the
/// one interval reported per parameter and names its method
/// ([`crate::intervals::chosen`]).
fn parameter_rows(
    s: &mut String,
    theta: &Parameters,
    status: &[Status; N_PARAMS],
    unc: Option<&Uncertainty>,
    mass: Option<f64>,
    chosen: Option<&[Option<crate::intervals::Interval>; N_PARAMS]>,
) {
    let m = mass.unwrap_or(1.0);
    if mass.is_none() {
        writeln!(
            s,
            "note: no mass given (--mass); physical values are per unit mass (m = 1 kg)"
        )
        .ok();
    }
    let (head, width) = match chosen {
        None => ("95 % interval", 33),
        Some(_) => ("95 % interval (method)", 54),
    };
    writeln!(
        s,
        "{:<6} {:>7} {:>15} {:>12} {:>width$}   {}",
        "param", "status", "value", "std error", head, "physical"
    )
    .ok();
    for j in 0..N_PARAMS {
        if status[j] == Status::Absent {
            continue;
        }
        let u_k = unc.and_then(|u| u.index(PARAM_NAMES[j]).map(|k| (u, k)));
        let (se, mut ci) = match u_k {
            Some((u, k)) => (
                format!("{:.4e}", u.std_errors[k]),
                format!("[{:.6e}, {:.6e}]", u.lower[k], u.upper[k]),
            ),
            None => ("-".into(), "-".into()),
        };
        if let Some(c) = chosen {
            ci = c[j].map_or("-".into(), |i| format!("{} {}", i.bounds_text(), i.method));
        }
        let phys = if Parameter::ALL[j].mass_scaled() {
            theta[j] * m
        } else {
            theta[j]
        };
        writeln!(
            s,
            "{:<6} {:>7} {:>15.8e} {:>12} {:>width$}   {} = {:.8e} {}",
            PARAM_NAMES[j],
            status_name(status[j]),
            theta[j],
            se,
            ci,
            Parameter::ALL[j].info().physical_name,
            phys,
            Parameter::ALL[j].info().physical_unit
        )
        .ok();
    }
    let wn = theta[ALPHA].sqrt();
    writeln!(
        s,
        "f_n = {:.6} Hz, zeta = {:.6e}",
        hz(wn),
        theta[DELTA] / (2.0 * wn)
    )
    .ok();
}

/// Human-readable report of one fit.
pub fn result_text(
    data: &Dataset,
    res: &FitResult,
    mass: Option<f64>,
) -> Result<String, ReportError> {
    let mut s = String::new();
    if let Some(w) = res.warning() {
        writeln!(s, "{w}").ok();
    }
    for n in res.notes() {
        writeln!(s, "note: {n}").ok();
    }
    result_text_body(&mut s, data, res, mass, None)?;
    let jumps = predicted_jumps(data, &res.theta)?;
    writeln!(
        s,
        "\nper level: {:<10} {:>10} {:>5} {:>12} {:>14} {:>14} {:>14}",
        "level", "gamma", "sweep", "RMS [m]", "RMS a/gamma", "jump meas [Hz]", "jump model [Hz]"
    )
    .ok();
    for (l, (c, pj)) in res.levels.iter().zip(data.curves.iter().zip(&jumps)) {
        let f = |v: Option<f64>| {
            v.map(|w| format!("{:.3}", hz(w)))
                .unwrap_or_else(|| "-".into())
        };
        writeln!(
            s,
            "           {:<10} {:>10.5} {:>5} {:>12.4e} {:>14.4e} {:>14} {:>14}",
            l.level,
            l.gamma,
            l.direction.name(),
            l.rms,
            l.rms_normalised,
            f(c.measured_jump(2.0)),
            f(*pj)
        )
        .ok();
    }
    s.push_str(&pq_text(data, res)?);
    minima_text(&mut s, &res.minima, &res.status);
    Ok(s)
}

/// The cost line, termination and parameter table of a fit.
fn result_text_body(
    s: &mut String,
    data: &Dataset,
    res: &FitResult,
    mass: Option<f64>,
    chosen: Option<&[Option<crate::intervals::Interval>; N_PARAMS]>,
) -> Result<(), ReportError> {
    let _ = data;
    if res.objective != res.cost {
        writeln!(s, "model {}: cost (Eq 31, the model's own sweep) = {:.6e}, objective (measured branch, jump penalties) = {:.6e}, RMS (a/gamma) = {:.6e} s^2, {} points, {} free parameters", res.kind, res.cost, res.objective, (res.objective / res.n_points as f64).sqrt(), res.n_points, res.n_free).ok();
    } else {
        writeln!(s, "model {}: cost (Eq 31) = {:.6e}, RMS (a/gamma) = {:.6e} s^2, {} points, {} free parameters", res.kind, res.cost, res.rms_normalised(), res.n_points, res.n_free).ok();
    }
    writeln!(
        s,
        "termination: {} after {} iterations",
        res.termination, res.iterations
    )
    .ok();
    parameter_rows(
        s,
        &res.theta,
        &res.status,
        res.uncertainty.as_ref().filter(|_| res.intervals_valid()),
        mass,
        chosen,
    );
    if let Some(r) = res.misfit {
        writeln!(
            s,
            "intervals: not shown (the model does not fit its noise, residual {r:.1}x: an interval would describe the noise, not the misfit; see the first line)"
        )
        .ok();
    } else if res.uncertainty.is_some() && !res.intervals_valid() {
        writeln!(
            s,
            "intervals: not shown (the fit is not trustworthy, see the first line)"
        )
        .ok();
    } else if res.uncertainty.is_none() {
        writeln!(s, "intervals: not available (J^T J singular at the optimum: some parameter is not identifiable from these data)").ok();
    }
    Ok(())
}

/// Phase-quadrature table (Table 8 analogue) as text.
pub fn pq_text(data: &Dataset, res: &FitResult) -> Result<String, ReportError> {
    let mut s = String::new();
    writeln!(s, "\nphase quadrature (model) vs measured ({}): {:<10} {:>12} {:>12} {:>9} {:>12} {:>12} {:>9}", res.kind, "level", "f_meas [Hz]", "f_model", "diff %", "a_meas [m]", "a_model", "diff %").ok();
    for r in phase_quadrature_table(data, &res.theta)? {
        let (df, da) = r.differences_percent();
        let o =
            |v: Option<f64>, p: usize| v.map(|x| format!("{x:.p$}")).unwrap_or_else(|| "-".into());
        writeln!(
            s,
            "  ({:<5})  {:<10} {:>12.4} {:>12} {:>9} {:>12.5e} {:>12} {:>9}",
            r.measured_from,
            r.level,
            hz(r.measured_omega),
            o(r.model_omega.map(hz), 4),
            o(df, 2),
            r.measured_amplitude,
            r.model_amplitude
                .map(|a| format!("{a:.5e}"))
                .unwrap_or_else(|| "-".into()),
            o(da, 2)
        )
        .ok();
    }
    Ok(s)
}

/// JSON of an integer search's pairs (`--integer`).
pub fn integer_pairs_json(pairs: &[IntegerPair]) -> Value {
    Value::Array(
        pairs
            .iter()
            .map(|p| match &p.outcome {
                Ok((cost, t)) => {
                    json!({"rho": p.rho, "eta": p.eta, "cost": cost, "termination": t.name()})
                }
                Err(e) => json!({"rho": p.rho, "eta": p.eta, "error": e}),
            })
            .collect(),
    )
}

/// Text of an integer search's pairs (`--integer`).
pub fn integer_pairs_text(pairs: &[IntegerPair]) -> String {
    let mut s = String::from("\ninteger exponent pairs (rho, eta): cost\n");
    let show = |v: Option<i64>| v.map_or_else(|| "null".to_string(), |v| v.to_string());
    for p in pairs {
        let outcome = match &p.outcome {
            Ok((cost, _)) => format!("{cost:.6e}"),
            Err(e) => Value::String(e.clone()).to_string(),
        };
        writeln!(s, "  ({}, {}): {outcome}", show(p.rho), show(p.eta)).ok();
    }
    s
}

/// JSON of one phase-resonance fit (same parameter block as sweep fits).
pub fn pr_json(res: &PrFitResult, mass: Option<f64>, frequency_weight: f64) -> Value {
    let params = parameters_json(&res.theta, &res.status, res.uncertainty.as_ref(), mass);
    let pq: Vec<Value> = res
        .rows
        .iter()
        .map(|r| {
            let (df, da) = r.differences_percent();
            json!({
                "level": r.level, "gamma": r.gamma, "measured_from": "phase-resonance data",
                "measured_f_hz": hz(r.measured_omega), "measured_amplitude": r.measured_amplitude,
                "model_f_hz": hz(r.model_omega), "model_amplitude": r.model_amplitude,
                "diff_f_percent": df, "diff_amplitude_percent": da,
            })
        })
        .collect();
    let minima = minima_json(&res.minima);
    json!({
        "data": "phase-resonance",
        "model": res.kind.name(),
        "stiffness_sign": res.stiffness_sign.name(),
        "parameters": params,
        "parameter_order": PARAM_NAMES,
        "theta": res.theta.to_array(),
        "mass": mass,
        "mass_note": if mass.is_none() { Some("no mass given: physical values are per unit mass (m = 1 kg)") } else { None },
        "cost": res.cost,
        "rms": res.rms(),
        "frequency_weight": frequency_weight,
        "frequency_scale": res.frequency_scale,
        "aic": res.aic(), "bic": res.bic(),
        "points": res.n_points, "residuals": 2 * res.n_points, "free_parameters": res.n_free,
        "termination": res.termination.name(),
        "iterations": res.iterations,
        "correlation": res.uncertainty.as_ref().map(|u| json!({"names": u.names, "matrix": u.correlation})),
        "minima": minima,
        "phase_quadrature": pq,
    })
}

/// The measured-vs-model table of a phase-resonance fit.
pub fn pr_table_text(res: &PrFitResult) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "\nphase resonance ({}): {:<10} {:>10} {:>12} {:>12} {:>9} {:>12} {:>12} {:>9}",
        res.kind,
        "level",
        "gamma",
        "f_meas [Hz]",
        "f_model",
        "diff %",
        "a_meas [m]",
        "a_model",
        "diff %"
    )
    .ok();
    for r in &res.rows {
        let (df, da) = r.differences_percent();
        writeln!(
            s,
            "  {:<10} {:>10.5} {:>12.5} {:>12.5} {:>9.3} {:>12.5e} {:>12.5e} {:>9.3}",
            r.level,
            r.gamma,
            hz(r.measured_omega),
            hz(r.model_omega),
            df,
            r.measured_amplitude,
            r.model_amplitude,
            da
        )
        .ok();
    }
    s
}

/// Human-readable report of one phase-resonance fit.
pub fn pr_text(res: &PrFitResult, mass: Option<f64>, frequency_weight: f64) -> String {
    let mut s = String::new();
    writeln!(
        s,
        "model {} from phase-resonance points: cost = {:.6e}, RMS = {:.6e} s^2, {} levels ({} residuals), {} free parameters",
        res.kind,
        res.cost,
        res.rms(),
        res.n_points,
        2 * res.n_points,
        res.n_free
    )
    .ok();
    writeln!(
        s,
        "frequency weight w_f = {frequency_weight} (W = {:.6e} s^2); stiffness sign: {}",
        res.frequency_scale,
        res.stiffness_sign.name()
    )
    .ok();
    writeln!(
        s,
        "termination: {} after {} iterations",
        res.termination, res.iterations
    )
    .ok();
    parameter_table_text(
        &mut s,
        &res.theta,
        &res.status,
        res.uncertainty.as_ref(),
        mass,
    );
    if res.uncertainty.is_none() {
        writeln!(
            s,
            "intervals: not available (no residual degrees of freedom: 2 x levels = free parameters)"
        )
        .ok();
    }
    s.push_str(&pr_table_text(res));
    minima_text(&mut s, &res.minima, &res.status);
    s
}

/// JSON of the `--sign auto` trials (`None` if only one sign was fitted).
pub fn sign_trials_json(t: &[SignTrial]) -> Option<Value> {
    (t.len() > 1).then(|| {
        Value::Array(
            t.iter()
                .map(|t| match &t.cost {
                    Ok(c) => json!({"sign": t.sign.name(), "cost": c}),
                    Err(e) => json!({"sign": t.sign.name(), "error": e}),
                })
                .collect(),
        )
    })
}

/// Text of the `--sign auto` trials (empty if only one sign was fitted).
pub fn sign_trials_text(t: &[SignTrial], chosen: Sign) -> String {
    if t.len() < 2 {
        return String::new();
    }
    let mut s = format!("--sign auto: kept {}; ", chosen.name());
    let parts: Vec<String> = t
        .iter()
        .map(|t| match &t.cost {
            Ok(c) => format!("{} cost {c:.6e}", t.sign.name()),
            Err(e) => format!("{} failed ({e})", t.sign.name()),
        })
        .collect();
    s.push_str(&parts.join(", "));
    s.push('\n');
    s
}
