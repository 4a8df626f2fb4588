//! The real-data tables of docs/identification.md: the default fit
//! (`identify` with `FitPlan::new(model)`, i.e. `nlsdof fit --beam-dir DIR
//! --model MODEL` with no other flag) on the three beam sets, and the same
//! fit with every jump read as exact and as censored. Per level: the
//! measured and model jump, whether the measured sweep left its branch
//! early and by how many Hz, the RMS over the branch before the jump (as a
//! fraction of the peak), the peak error and the residual against the
//! noise; then a cross-validation (fit the lower half of the levels,
//! predict the upper half's jumps and peaks).
//!
//! ```text
//! cargo run --release -p nlsdof-studies --example real_data_tables -- [SHARED_DATA_DIR] [MODEL,..] [READING,..]
//! ```
use nlsdof::identification::models::*;
use nlsdof::identification::*;
use nlsdof::SweepDirection;
use nlsdof_io::stepped_sine_data::{read_beam_dir, Runs};
use std::fmt::Write;
use std::time::Instant;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn hz(w: f64) -> f64 {
    w / TWO_PI
}

fn opt(v: Option<f64>, p: usize) -> String {
    v.map_or("-".to_string(), |x| format!("{x:.p$}"))
}

/// The per-level table of a fit (its own curve reports).
fn table(id: &Identification, out: &mut String) {
    writeln!(out, "| level | jump meas. [Hz] | jump model [Hz] | diff [%] | left early by [Hz] | upper-branch RMS [% of peak] | peak meas. [mm] | peak model [mm] | diff [%] | residual / noise |").ok();
    writeln!(
        out,
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    )
    .ok();
    for (c, r) in id.data.curves.iter().zip(&id.curves) {
        let (mj, pj) = (r.measured_jump.map(hz), r.model_jump.map(hz));
        let d = match (mj, pj) {
            (Some(a), Some(b)) => format!("{:+.2}", 100.0 * (b / a - 1.0)),
            _ => "-".into(),
        };
        let peak = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
        writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {:.4} | {:.4} | {:+.1} | {:.1}{} |",
            c.level,
            opt(mj, 2),
            opt(pj, 2),
            d,
            opt(r.left_early_by.map(hz), 2),
            opt(r.upper_branch_rms.map(|v| 100.0 * v / peak), 1),
            1e3 * r.peak.0,
            1e3 * r.peak.1,
            100.0 * (r.peak.1 / r.peak.0 - 1.0),
            r.noise.ratio(),
            if id.adequacy.failing.contains(
                &id.curves
                    .iter()
                    .position(|x| std::ptr::eq(x, r))
                    .unwrap_or(usize::MAX)
            ) {
                " (does not fit)"
            } else {
                ""
            }
        )
        .ok();
    }
}

/// Cross-validation: the model of `fit` predicts the held-out `curves`
/// (jump-down frequency of the model's own sweep against the measured one,
/// `Curve::measured_jump`, and the peaks).
fn predict(curves: &Dataset, theta: &Parameters, out: &mut String) -> Option<f64> {
    let jumps = predicted_jumps(curves, theta).unwrap_or_default();
    let amps = objective::model_amplitudes(curves, theta).unwrap_or_default();
    writeln!(
        out,
        "| level | jump meas. [Hz] | jump predicted [Hz] | diff [%] | peak meas. [mm] | peak predicted [mm] | diff [%] |"
    )
    .ok();
    writeln!(out, "| --- | --- | --- | --- | --- | --- | --- |").ok();
    let mut worst = 0.0f64;
    let mut measured = 0;
    for (k, c) in curves.curves.iter().enumerate() {
        let mj = c.measured_jump(2.0).map(hz);
        let pj = jumps.get(k).copied().flatten().map(hz);
        measured += usize::from(mj.is_some());
        let d = match (mj, pj) {
            (Some(a), Some(b)) => {
                worst = worst.max((b / a - 1.0).abs());
                format!("{:+.2}", 100.0 * (b / a - 1.0))
            }
            (Some(_), None) => {
                worst = f64::INFINITY;
                "no jump predicted".into()
            }
            _ => "-".into(),
        };
        let am = amps.get(k).cloned().unwrap_or_default();
        let peak_m = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
        let peak_p = am.iter().fold(0.0f64, |m, &a| m.max(a));
        writeln!(
            out,
            "| {} | {} | {} | {} | {:.4} | {:.4} | {:+.1} |",
            c.level,
            opt(mj, 2),
            opt(pj, 2),
            d,
            1e3 * peak_m,
            1e3 * peak_p,
            100.0 * (peak_p / peak_m - 1.0)
        )
        .ok();
    }
    (measured > 0).then_some(worst)
}

/// The targets of issue 24 on a fit: the worst upper-branch RMS (fraction
/// of the peak), the largest distance (in steps) by which a measured jump
/// lies beyond the model's fold.
fn targets(id: &Identification) -> (f64, f64) {
    let mut rms = 0.0f64;
    let mut beyond = 0.0f64;
    for (c, r) in id.data.curves.iter().zip(&id.curves) {
        let peak = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
        if let Some(u) = r.upper_branch_rms {
            rms = rms.max(u / peak);
        }
        if let (Some(mj), Some(next)) = (r.measured_jump, r.measured_jump_next) {
            let step = (next - mj).abs();
            let fold = r.model_jump.unwrap_or(f64::NAN);
            // measured jump (the last step on the branch) beyond the fold,
            // in sweep order
            let over = match r.direction {
                SweepDirection::Up => mj - fold,
                SweepDirection::Down => fold - mj,
            };
            if over.is_finite() {
                beyond = beyond.max(over / step);
            }
        }
    }
    (rms, beyond)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let root = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "../shared/data/clamped-beam-duffing-catarinaluz".into());
    let models: Vec<ModelKind> = args
        .get(2)
        .map(|s| s.split(',').filter_map(ModelKind::parse).collect())
        .unwrap_or_else(|| vec![ModelKind::Duffing, ModelKind::Generalised]);
    let readings: Vec<(&str, ReadingChoice)> = args
        .get(3)
        .map(|s| {
            s.split(',')
                .filter_map(|r| match r {
                    "auto" => Some(("auto (default)", ReadingChoice::Auto)),
                    "exact" => Some(("exact", ReadingChoice::Exact)),
                    "censored" => Some(("censored", ReadingChoice::Censored)),
                    _ => None,
                })
                .collect()
        })
        .unwrap_or_else(|| vec![("auto (default)", ReadingChoice::Auto)]);
    let mut out = String::new();
    for set in [
        "cc_beam_no_magnet_24C",
        "cc_beam_magnet_24C",
        "cantilever_no_magnet",
    ] {
        let dir = std::path::Path::new(&root).join(set);
        let data = match read_beam_dir(&dir, Runs::Up) {
            Ok(d) => d,
            Err(e) => {
                eprintln!("{set}: {e}");
                continue;
            }
        };
        for &kind in &models {
            for &(rname, reading) in &readings {
                let plan = FitPlan::new(kind).with_reading(reading);
                let t = Instant::now();
                let id = identify(&data, &plan, &|_| {});
                let secs = t.elapsed().as_secs_f64();
                writeln!(
                    out,
                    "\n### {set}, {kind}, jumps read {rname} ({secs:.2} s)\n"
                )
                .ok();
                let id = match id {
                    Ok(id) => id,
                    Err(e) => {
                        writeln!(out, "error: {e}").ok();
                        continue;
                    }
                };
                let th = id.fit.theta;
                writeln!(
                    out,
                    "f_n = {:.2} Hz, zeta = {:.3e}, gain = {:.3} ({}), rho = {:.3}, eta = {:.3}, phase: {}; cost (Eq 31) {:.4e}, objective {:.4e}; {} curves censored; residual / noise {:.1}\n\n{}\n",
                    hz(th[ALPHA].sqrt()),
                    th[DELTA] / (2.0 * th[ALPHA].sqrt()),
                    th[GAIN],
                    match id.spec.status[GAIN] {
                        Status::Free => "free",
                        _ => "held",
                    },
                    th[RHO],
                    th[ETA],
                    id.phase
                        .map(|p| format!("{} {:+.1} deg", if p.sign > 0.0 { "lag" } else { "lead" }, p.offset.to_degrees()))
                        .unwrap_or_else(|| "-".into()),
                    id.fit.cost,
                    id.fit.objective,
                    id.spec.censored.iter().filter(|&&c| c).count(),
                    id.adequacy.ratio,
                    id.warning()
                        .unwrap_or_else(|| "no warning".into())
                        .replace('\n', " / "),
                )
                .ok();
                for n in id.fit.notes() {
                    writeln!(out, "note: {n}\n").ok();
                }
                table(&id, &mut out);
                let (rms, beyond) = targets(&id);
                if id.curves.iter().any(|c| c.measured_jump.is_some()) {
                    writeln!(
                        out,
                        "\nworst upper-branch RMS {:.1} % of the peak; measured jumps at most {:.2} steps beyond the model's fold",
                        100.0 * rms,
                        beyond
                    )
                    .ok();
                } else {
                    writeln!(out, "\nno measured jump: no upper branch to judge").ok();
                }
                // cross-validation: lower half of the levels -> upper half
                let n = data.curves.len();
                if n >= 2 {
                    let lower = Dataset {
                        curves: data.curves[..n / 2].to_vec(),
                    };
                    let upper = Dataset {
                        curves: id.data.curves[n / 2..].to_vec(),
                    };
                    let t = Instant::now();
                    match identify(&lower, &plan, &|_| {}) {
                        Ok(cv) => {
                            writeln!(
                                out,
                                "\nCross-validation: fitted on the lower {} level(s) ({:.2} s), predicted on the upper {}:\n",
                                n / 2,
                                t.elapsed().as_secs_f64(),
                                n - n / 2
                            )
                            .ok();
                            let worst = predict(&upper, &cv.fit.theta, &mut out);
                            writeln!(
                                out,
                                "\nworst cross-validated jump error {}",
                                match worst {
                                    None => "(no measured jump in the predicted levels)".into(),
                                    Some(w) if w.is_finite() => format!("{:.2} %", 100.0 * w),
                                    Some(_) => "(a level without a predicted jump)".into(),
                                }
                            )
                            .ok();
                        }
                        Err(e) => {
                            writeln!(out, "\ncross-validation fit failed: {e}").ok();
                        }
                    }
                }
            }
        }
    }
    print!("{out}");
}
