//! `nlsdof fit` / `nlsdof compare` end to end on a synthetic data set.

mod common;

use assert_cmd::Command;
use nlsdof::{ForcedResponse, Formulation, NormalisedModel, SweepDirection};
use std::fmt::Write as _;
use std::path::Path;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Long CSV of an exact Duffing model (f_n = 10 Hz, ζ = 1 %), 2 levels, up-sweeps.
fn write_csv(dir: &Path) -> (std::path::PathBuf, NormalisedModel) {
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
    for (l, g) in [("low", 0.1), ("high", 0.25)] {
        let sw = ForcedResponse::from_normalised(&m, g, Formulation::HarmonicBalance)
            .unwrap()
            .sweep(&omegas, SweepDirection::Up)
            .unwrap();
        for (f, p) in freqs.iter().zip(&sw.points) {
            writeln!(s, "{l},{g},{f},{:e},up", p.amplitude).unwrap();
        }
    }
    let path = dir.join("data.csv");
    std::fs::write(&path, s).unwrap();
    (path, m)
}

#[test]
fn fit_json_and_out_file() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, truth) = write_csv(dir.path());
    let out = dir.path().join("fitted.toml");
    let svg = dir.path().join("fit.svg");
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "duffing",
            "--starts",
            "4",
            "--seed",
            "3",
            "--mass",
            "2",
            "--json",
            "--out",
        ])
        .arg(&out)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.starts_with("<svg") && svg_text.trim_end().ends_with("</svg>"));
    assert_eq!(
        svg_text.matches("<polyline").count(),
        2,
        "one model line per curve"
    );
    assert_eq!(svg_text.matches("<circle").count(), 50, "every data point");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["model"], "duffing");
    let theta: Vec<f64> = v["theta"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        ((theta[0] - truth.alpha) / truth.alpha).abs() < 1e-6,
        "{theta:?}"
    );
    assert!(
        ((theta[2] - truth.beta) / truth.beta).abs() < 1e-6,
        "{theta:?}"
    );
    assert!(v["cost"].as_f64().unwrap() < 1e-12);
    assert!(v["termination"].is_string());
    assert!(!v["minima"].as_array().unwrap().is_empty());
    assert_eq!(v["phase_quadrature"].as_array().unwrap().len(), 2);
    // physical parameters scale with the given mass
    let k = v["parameters"][0]["physical"]["value"].as_f64().unwrap();
    assert!(((k - 2.0 * truth.alpha) / k).abs() < 1e-6);
    let model = nlsdof_io::model_file::read_model(&out).unwrap();
    assert_eq!(model.mass, 2.0);
    assert!(((model.stiffness - 2.0 * truth.alpha) / model.stiffness).abs() < 1e-6);
}

#[test]
fn fit_errors_are_one_line_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "level,gamma,f_hz,amplitude\na,1,10,1e-3\na,1,11,-2e-3\na,1,12,1e-3\nb,2,10,1e-3\nb,2,11,1e-3\nb,2,12,1e-3\n").unwrap();
    let out = dir.path().join("never.toml");
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["fit", bad.to_str().unwrap(), "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("nlsdof: error:")
            && err.trim_end().lines().count() == 1
            && err.contains("-0.002"),
        "{err}"
    );
    assert!(!out.exists());
    let (csv, _) = write_csv(dir.path());
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["fit", csv.to_str().unwrap(), "--free", "m"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not identifiable"));
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["fit", csv.to_str().unwrap(), "--model", "nonsense"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    for (extra, want) in [
        (&["--jump-weight=-1"][..], "--jump-weight -1"),
        (&["--jump-weight", "NaN"][..], "--jump-weight NaN"),
        (
            &["--model", "duffing", "--integer"][..],
            "--integer: the duffing model has no free exponent",
        ),
    ] {
        let o = Command::cargo_bin("nlsdof")
            .unwrap()
            .args(["fit", csv.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.trim_end().lines().count() == 1 && err.contains(want),
            "{extra:?}: {err}"
        );
        assert!(!out.exists());
    }
}

/// `--jump-weight` and `--jump-reading` on data with a jump: the fit runs
/// and reports the weight (default 1) and each curve's reading, and on exact
/// data every setting finds the truth (Eq 31 cost at rounding level).
#[test]
fn jump_weight_option_runs_and_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    let run = |extra: &[&str]| -> serde_json::Value {
        let o = Command::cargo_bin("nlsdof")
            .unwrap()
            .args(["fit", csv.to_str().unwrap(), "--model", "duffing", "--json"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let plain = run(&[]);
    let weighted = run(&["--jump-weight", "10"]);
    let none = run(&["--jump-weight", "0"]);
    let censored = run(&["--jump-reading", "censored"]);
    assert_eq!(plain["jump_weight"], 1.0);
    assert_eq!(weighted["jump_weight"], 10.0);
    assert_eq!(none["jump_weight"], 0.0);
    for v in [&plain, &weighted, &none, &censored] {
        let c = v["cost"].as_f64().unwrap();
        assert!(c < 1e-20, "{c}");
    }
    for l in plain["levels"].as_array().unwrap() {
        assert_eq!(l["jump_reading"], "exact");
    }
    for l in censored["levels"].as_array().unwrap() {
        assert_eq!(l["jump_reading"], "censored");
    }
}

#[test]
fn integer_exponent_search_reports_pairs() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    let bounds = dir.path().join("bounds.toml");
    std::fs::write(&bounds, "rho = [1, 3]\n").unwrap();
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "generalised-stiffness",
            "--integer",
            "--starts",
            "2",
            "--json",
            "--bounds",
        ])
        .arg(&bounds)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let pairs = v["integer_pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 3);
    // the data are Duffing: rho = 2 wins
    assert_eq!(v["theta"][3].as_f64().unwrap(), 2.0);
}

#[test]
fn compare_tabulates_models() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "compare",
            csv.to_str().unwrap(),
            "--models",
            "linear,duffing",
            "--starts",
            "2",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let models = v["models"].as_array().unwrap();
    assert_eq!(models.len(), 2);
    // the true model fits better
    assert!(models[1]["cost"].as_f64().unwrap() < models[0]["cost"].as_f64().unwrap());
    assert!(models[1]["aic"].as_f64().unwrap() < models[0]["aic"].as_f64().unwrap());
}

/// The clamped-clamped beam (real data, up-sweeps, 6 levels 0.04–0.14 g):
/// Duffing with a free forcing gain, fitted to every 4th step (256 per
/// level, for test speed) with the jump-frequency residuals
/// (`fit_with_jumps`, λ = 100). Prints predicted vs measured jump-down
/// frequencies. NOTE: the issue asks for all jumps within 2 %; this is NOT
/// met. The measured jumps (148.1, 163.3, 182.6, 188.9, 209.8, 212.9 Hz)
/// alternate around any smooth trend (the real up-sweeps fall off the upper
/// branch early at 0.10 g and 0.14 g), and every first-order HB model tried
/// (Duffing, generalised stiffness, duffing-generalised, generalised; free
/// gain; λ from 30 to 10⁴; wider bounds) ends at a worst level error of
/// 2.2–2.8 %, and a minimax (Lawson) fit of the jump errors alone still
/// equioscillates at 2.14–2.19 % (docs/identification.md). This test
/// asserts the 2.5 % this fit meets (before the jump residuals: 9.05 %).
#[test]
fn clamped_beam_duffing_fit_predicts_jumps() {
    let Some(dir) = common::beam_dir("cc_beam_no_magnet_24C") else {
        return;
    };
    use nlsdof::identification::*;
    let full =
        nlsdof_io::stepped_sine_data::read_beam_dir(&dir, nlsdof_io::stepped_sine_data::Runs::Up)
            .unwrap();
    assert_eq!(full.levels().len(), 6);
    let mut data = full.clone();
    for c in data.curves.iter_mut() {
        let keep: Vec<usize> = (0..c.omegas.len())
            .filter(|i| i % 4 == 0)
            .chain(std::iter::once(c.peak_index()))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        c.omegas = keep.iter().map(|&i| c.omegas[i]).collect();
        c.amplitudes = keep.iter().map(|&i| c.amplitudes[i]).collect();
        c.weights = keep.iter().map(|&i| c.weights[i]).collect();
        c.phases = None;
    }
    let mut spec = FitSpec::new(ModelKind::Duffing, &data);
    spec.free("gain").unwrap();
    let t0 = std::time::Instant::now();
    let res = fit_with_jumps(
        &data,
        &spec,
        &FitOptions {
            starts: 1,
            ..FitOptions::default()
        },
        100.0,
        &|| {},
    )
    .unwrap();
    let elapsed = t0.elapsed();
    let jumps = predicted_jumps(&full, &res.theta).unwrap();
    let mut worst = 0.0f64;
    eprintln!(
        "beam duffing fit ({elapsed:?}, {}): theta {:?} cost {:e}",
        res.termination, res.theta, res.cost
    );
    eprintln!("| level | measured jump [Hz] | predicted jump [Hz] | diff % |");
    for (c, pj) in full.curves.iter().zip(&jumps) {
        let meas = c.measured_jump(2.0).expect("measured jump") / TWO_PI;
        let pred = pj.expect("model jumps") / TWO_PI;
        let d = 100.0 * (pred - meas) / meas;
        worst = worst.max(d.abs());
        eprintln!("| {} | {meas:.2} | {pred:.2} | {d:+.2} |", c.level);
    }
    assert!(worst < 2.5, "worst jump-frequency error {worst:.2} %");
}

/// The default staged fit (issue 10): stages and honest-convergence keys in
/// the JSON, the landscape as JSON, SVG and PNG, the phase columns used and
/// their convention detected, bad input one line and nothing written.
#[test]
fn staged_fit_reports_and_landscape() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, truth) = write_csv(dir.path());
    for (ext, magic) in [
        ("json", &b"{"[..]),
        ("svg", &b"<svg"[..]),
        ("png", &b"\x89PNG"[..]),
    ] {
        let land = dir.path().join(format!("land.{ext}"));
        let o = Command::cargo_bin("nlsdof")
            .unwrap()
            .args([
                "fit",
                csv.to_str().unwrap(),
                "--model",
                "generalised-stiffness",
                "--grid",
                "12x1",
                "--json",
                "--landscape",
            ])
            .arg(&land)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let bytes = std::fs::read(&land).unwrap();
        assert!(bytes.starts_with(magic), "{ext}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["converged"], true);
        assert!(v["at_bounds"].as_array().unwrap().is_empty());
        assert!(v["unidentifiable"].as_array().unwrap().is_empty());
        assert_eq!(v["intervals_valid"], true);
        let id = &v["identification"];
        assert!(id["equation_error"]["cost"].is_number());
        assert!(!id["landscape"]["minima"].as_array().unwrap().is_empty());
        // noise-free Duffing data: rho = 2 recovered
        assert!((v["theta"][3].as_f64().unwrap() - 2.0).abs() < 1e-5);
        assert!((v["theta"][0].as_f64().unwrap() / truth.alpha - 1.0).abs() < 1e-7);
        if ext == "json" {
            let g: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            assert_eq!(g["rho"].as_array().unwrap().len(), 12);
            assert_eq!(g["cost"].as_array().unwrap().len(), 1);
        }
    }
    // phase columns in a lead convention with a 90 degree offset: detected
    let text = std::fs::read_to_string(&csv).unwrap();
    let wn = TWO_PI * 10.0;
    let m = NormalisedModel {
        alpha: wn * wn,
        delta: 0.02 * wn,
        beta: 2.5e6,
        rho: 2.0,
        kappa: 0.0,
        eta: 0.0,
    };
    let mut s = String::from("level,gamma,f_hz,amplitude,sweep,phase_deg\n");
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (g, fhz): (f64, f64) = (f[1].parse().unwrap(), f[2].parse().unwrap());
        let r = ForcedResponse::from_normalised(&m, g, Formulation::HarmonicBalance).unwrap();
        let sw = r.sweep(&[TWO_PI * fhz], SweepDirection::Up).unwrap();
        let lead = 90.0 - sw.points[0].phase.to_degrees();
        writeln!(s, "{line},{lead}").unwrap();
    }
    let pcsv = dir.path().join("phase.csv");
    std::fs::write(&pcsv, s).unwrap();
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            pcsv.to_str().unwrap(),
            "--model",
            "duffing",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let pc = &v["identification"]["phase_convention"];
    assert_eq!(pc["sign"], "lead");
    assert!(
        (pc["offset_deg"].as_f64().unwrap() - 90.0).abs() < 1e-3,
        "{pc}"
    );
    assert!(v["phase_cost"].as_f64().unwrap() < 1e-12);
    // bad input: one line, exit 2, nothing written
    let out = dir.path().join("never.toml");
    for (args, needle) in [
        (vec!["--grid", "0"], "--grid"),
        (vec!["--grid", "5x0"], "--grid"),
        (vec!["--landscape", "x.txt"], ".json, .svg or .png"),
        (vec!["--phase-weight", "0"], "--phase-weight"),
        (
            vec!["--no-phase", "--phase-convention", "lag,0"],
            "conflicts",
        ),
        (vec!["--phase-convention", "sideways,0"], "lag or lead"),
    ] {
        let o = Command::cargo_bin("nlsdof")
            .unwrap()
            .args(["fit", pcsv.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.starts_with("nlsdof: error:") && err.contains(needle),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists());
    }
    // phase outside [-360, 360] degrees
    let bad = dir.path().join("badphase.csv");
    let mut t = std::fs::read_to_string(&pcsv).unwrap();
    let first_row_end = t.find('\n').unwrap() + 1;
    let row_end = first_row_end + t[first_row_end..].find('\n').unwrap();
    let row = t[first_row_end..row_end].to_string();
    let mut fields: Vec<String> = row.split(',').map(String::from).collect();
    *fields.last_mut().unwrap() = "400".into();
    t.replace_range(first_row_end..row_end, &fields.join(","));
    std::fs::write(&bad, t).unwrap();
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["fit", bad.to_str().unwrap(), "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("phase"), "{err}");
    assert!(!out.exists());
}

/// A fit that cannot reach the data (the stiffness exponent boxed away
/// from the truth) says so on its first lines — the model does not fit, a
/// parameter sits at its bound — and shows no intervals.
#[test]
fn unconverged_fit_says_so_first() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    // the stiffness exponent boxed in [7.5, 8] although the data are
    // Duffing (rho = 2): the fit ends at the bound
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "generalised-stiffness",
            "--grid",
            "1",
            "--bounds",
        ])
        .arg({
            let b = dir.path().join("b.toml");
            std::fs::write(&b, "rho = [7.5, 8]\n").unwrap();
            b
        })
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let mut lines = text.lines();
    let (first, second) = (lines.next().unwrap(), lines.next().unwrap());
    assert!(
        first.starts_with("WARNING: the model does not fit"),
        "{text}"
    );
    assert!(
        second.starts_with("WARNING:") && second.contains("at bounds: rho"),
        "{text}"
    );
    assert!(
        text.contains("intervals: not shown (the model does not fit its noise"),
        "{text}"
    );
}

/// A model that does not fit its noise has no valid intervals, whatever
/// else holds: the linear model on the Duffing data converges at no bound,
/// and its JSON says `intervals_valid: false` with the residual over the
/// noise under `misfit`; every parameter's reported interval is null.
#[test]
fn a_misfit_has_no_valid_intervals() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "linear",
            "--json",
            "--out",
        ])
        .arg(dir.path().join("model.toml"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["adequacy"]["adequate"], false, "{}", v["adequacy"]);
    let r = v["misfit"].as_f64().expect("misfit is a number");
    assert!(r > 2.5, "{r}");
    assert_eq!(v["intervals_valid"], false);
    for p in v["parameters"].as_array().unwrap() {
        assert!(p["interval"].is_null(), "{p}");
    }
    // the model file says so in its header, with the same number
    let file = std::fs::read_to_string(dir.path().join("model.toml")).unwrap();
    let head = file.lines().next().unwrap();
    assert!(
        head.contains(&format!(
            "DOES NOT FIT its data: residual {r:.1}x the noise"
        )),
        "{head}"
    );
}

/// The default fit (`fit --beam-dir DIR`, generalised, no other flag)
/// completes on each of the three real beam sets and says that the model
/// does not fit their noise (first-order HB with one power-law term each
/// leaves residuals 60-1300x the measurement noise there). A fold moved by
/// 1e-9 once took η from −1 to −1 + 2e-9 on the 24 °C set, where the
/// friction that held the mass at 120 Hz left an amplitude of 1e-300: the
/// solve overflowed and the error ended the whole fit (measured with a
/// variant of the late-fold pull that this build does not have); such a
/// move is now not taken.
#[test]
fn default_fits_of_the_beam_sets_complete_and_say_they_do_not_fit() {
    for set in [
        "cc_beam_no_magnet_24C",
        "cc_beam_magnet_24C",
        "cantilever_no_magnet",
    ] {
        let Some(dir) = common::beam_dir(set) else {
            return;
        };
        let v = common::json(&["fit", "--beam-dir", dir.to_str().unwrap(), "--json"]);
        assert_eq!(v["adequacy"]["adequate"], false, "{set}: {}", v["adequacy"]);
        let r = v["misfit"].as_f64().expect("misfit is a number");
        assert!(r > 10.0, "{set}: misfit {r}");
        assert_eq!(v["intervals_valid"], false, "{set}");
        // the beams' phases are fitted: the line and JSON say which part
        // does not fit, amplitudes or phases
        let a = &v["adequacy"];
        let amp = a["amplitude_residual_over_noise"].as_f64();
        let phase = a["phase_residual_over_noise"].as_f64();
        assert!(amp.is_some() && phase.is_some(), "{set}: {a}");
        let msg = a["message"].as_str().unwrap();
        assert!(
            msg.contains("(amplitudes ") && msg.contains("x, phases "),
            "{msg}"
        );
        for l in v["levels"].as_array().unwrap() {
            assert!(
                l["phase_residual_over_noise"].as_f64().is_some(),
                "{set}: {l}"
            );
        }
    }
}

/// `fit --profile`: output-error profile intervals of the free exponent,
/// around the estimate, on exact Duffing data (the truth ρ = 2 inside).
#[test]
fn profile_option_reports_output_error_intervals() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, _) = write_csv(dir.path());
    let run = |json: bool| {
        let mut c = Command::cargo_bin("nlsdof").unwrap();
        c.args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "generalised-stiffness",
            "--profile",
        ]);
        if json {
            c.arg("--json");
        }
        c.output().unwrap()
    };
    let o = run(true);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rho = &v["identification"]["profile_oe_ci95"]["rho"];
    let est = rho["estimate"].as_f64().unwrap();
    assert!((est - 2.0).abs() < 1e-3, "{est}");
    let ci = rho["ci95"].as_array().unwrap();
    // noise-free data: a narrow interval around the truth, where closed
    let (lo, hi) = (ci[0].as_f64(), ci[1].as_f64());
    assert!(lo.is_some() || hi.is_some(), "{rho}");
    if let Some(lo) = lo {
        assert!(lo <= est && est - lo < 0.1, "{lo}");
    }
    if let Some(hi) = hi {
        assert!(hi >= est && hi - est < 0.1, "{hi}");
    }
    assert!(rho["fits"].as_u64().unwrap() >= 2);
    assert!(rho["refused"].is_null(), "{rho}");
    // the one interval reported for rho is that profile, with its method;
    // alpha's is Wald, and ci95 keeps the Wald interval
    let params = v["parameters"].as_array().unwrap();
    let p = |n: &str| params.iter().find(|p| p["name"] == n).unwrap().clone();
    assert_eq!(p("rho")["interval"]["method"], "output-error profile");
    assert_eq!(p("rho")["interval"]["ci95"], rho["ci95"]);
    assert_eq!(p("alpha")["interval"]["method"], "Wald");
    assert_eq!(p("alpha")["interval"]["ci95"], p("alpha")["ci95"]);
    // the text report: one interval per parameter, named by its method
    let text = String::from_utf8_lossy(&run(false).stdout).into_owned();
    let row = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no {name} row in {text}"))
            .to_string()
    };
    assert!(row("rho").contains("] output-error profile"), "{text}");
    assert!(row("alpha").contains("] Wald"), "{text}");
    assert!(!text.contains("equation-error profile"), "{text}");
    // --intervals all: every method, each with what it leaves out
    let all = Command::cargo_bin("nlsdof")
        .unwrap()
        .args([
            "fit",
            csv.to_str().unwrap(),
            "--model",
            "generalised-stiffness",
        ])
        .args(["--profile", "--intervals", "all"])
        .output()
        .unwrap();
    let all = String::from_utf8_lossy(&all.stdout).into_owned();
    for m in [
        "Wald: linearised",
        "output-error profile: the objective",
        "equation-error profile: the branch-free",
    ] {
        assert!(all.contains(m), "{m} in {all}");
    }
    assert!(all.contains("leaves out"), "{all}");
}
