//! The real-data tables of docs/identification.md: the default staged fit
//! (`identify` with `FitPlan::new(model)`, i.e. `nlsdof fit --beam-dir DIR
//! --model MODEL` with no other flag) on the three beam sets, per level the
//! measured and model jump-down frequency, peak amplitude and RMS, and a
//! cross-validation (fit the lower half of the levels, predict the upper).
//!
//! ```text
//! cargo run --release -p nlsdof-studies --example real_data_tables -- [SHARED_DATA_DIR] [MODEL,..]
//! ```
use nlsdof::identification::models::*;
use nlsdof::identification::*;
use nlsdof_io::stepped_sine_data::{read_beam_dir, Runs};
use std::time::Instant;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn hz(w: f64) -> f64 {
    w / TWO_PI
}

/// Model amplitudes of θ on `data` (phases as in `like`, converted).
fn judge(data: &Dataset, theta: &Parameters) -> (Vec<Vec<f64>>, Vec<Option<f64>>) {
    let amps = objective::model_amplitudes(data, theta).unwrap_or_default();
    let jumps = predicted_jumps(data, theta).unwrap_or_default();
    (amps, jumps)
}

fn table(data: &Dataset, theta: &Parameters, out: &mut String) {
    use std::fmt::Write;
    let (amps, jumps) = judge(data, theta);
    writeln!(out, "| level | jump meas. [Hz] | jump model [Hz] | diff [%] | peak meas. [mm] | peak model [mm] | diff [%] | RMS [mm] |").ok();
    writeln!(out, "| --- | --- | --- | --- | --- | --- | --- | --- |").ok();
    for (k, c) in data.curves.iter().enumerate() {
        let mj = c.measured_jump(2.0).map(hz);
        let pj = jumps.get(k).copied().flatten().map(hz);
        let am = amps.get(k).cloned().unwrap_or_default();
        let peak_m = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
        let peak_p = am.iter().fold(0.0f64, |m, &a| m.max(a));
        let rms = (c
            .amplitudes
            .iter()
            .zip(&am)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / c.amplitudes.len() as f64)
            .sqrt();
        let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
        let d = match (mj, pj) {
            (Some(a), Some(b)) => format!("{:+.2}", 100.0 * (b / a - 1.0)),
            _ => "-".into(),
        };
        writeln!(
            out,
            "| {} | {} | {} | {} | {:.4} | {:.4} | {:+.1} | {:.4} |",
            c.level,
            f(mj),
            f(pj),
            d,
            1e3 * peak_m,
            1e3 * peak_p,
            100.0 * (peak_p / peak_m - 1.0),
            1e3 * rms
        )
        .ok();
    }
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
    let mut out = String::new();
    use std::fmt::Write;
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
            let t = Instant::now();
            let id = identify(&data, &FitPlan::new(kind), &|_| {});
            let secs = t.elapsed().as_secs_f64();
            writeln!(out, "\n### {set}, {kind} (default fit, {secs:.2} s)\n").ok();
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
                "f_n = {:.2} Hz, zeta = {:.3e}, gain = {:.3} ({}), rho = {:.3}, eta = {:.3}, phase: {}, jump weight {}; {}\n",
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
                id.jump_weight,
                id.fit.warning().unwrap_or_else(|| "converged, no bound, identifiable".into())
            )
            .ok();
            table(&id.data, &th, &mut out);
            // cross-validation: lower half of the levels -> upper half
            let n = id.data.curves.len();
            if n >= 2 {
                let lower = Dataset {
                    curves: data.curves[..n / 2].to_vec(),
                };
                let upper_conv = Dataset {
                    curves: id.data.curves[n / 2..].to_vec(),
                };
                let t = Instant::now();
                match identify(&lower, &FitPlan::new(kind), &|_| {}) {
                    Ok(cv) => {
                        writeln!(
                            out,
                            "\nCross-validation: fitted on the lower {} level(s) ({:.2} s), predicted on the upper {}:\n",
                            n / 2,
                            t.elapsed().as_secs_f64(),
                            n - n / 2
                        )
                        .ok();
                        table(&upper_conv, &cv.fit.theta, &mut out);
                    }
                    Err(e) => {
                        writeln!(out, "\ncross-validation fit failed: {e}").ok();
                    }
                }
            }
        }
    }
    print!("{out}");
}
