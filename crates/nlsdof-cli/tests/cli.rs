//! End-to-end tests of the `nlsdof` binary: JSON/CSV shapes and values of
//! `equiv`, `roots`, `frf`, the SVG plot, and the error contract (exit code
//! 2, exactly one stderr line, no output file).

mod common;
use common::{example, fails, json, ok, write};

use serde_json::Value;
use std::f64::consts::PI;

// ---------------------------------------------------------------- equiv

#[test]
fn equiv_json_duffing() {
    let v = json(&["equiv", "--mu", "2", "--json"]);
    assert!((v["g"].as_f64().unwrap() - 0.75).abs() < 1e-15, "{v}");
    assert_eq!(v["mu"].as_f64().unwrap(), 2.0);
    assert!((v["closed_form"].as_f64().unwrap() - 0.75).abs() < 1e-15);
    assert_eq!(v["closed_form_formula"], "Eq 17 even");
    assert!(v["name"].as_str().unwrap().contains("Duffing"));
}

#[test]
fn equiv_json_special_and_non_integer() {
    let v = json(&["equiv", "--mu", "-1", "--json"]);
    assert!((v["g"].as_f64().unwrap() - 4.0 / PI).abs() < 1e-15);
    assert_eq!(v["closed_form_formula"], "Eq 25 odd");
    assert!(v["name"].as_str().unwrap().contains("Coulomb"));
    let v = json(&["equiv", "--mu", "1", "--json"]);
    assert!((v["g"].as_f64().unwrap() - 8.0 / (3.0 * PI)).abs() < 1e-15);
    assert!(v["name"].as_str().unwrap().contains("quadratic"));
    let v = json(&["equiv", "--mu", "0", "--json"]);
    assert!((v["g"].as_f64().unwrap() - 1.0).abs() < 1e-15);
    assert!(v["name"].as_str().unwrap().contains("linear"));
    let v = json(&["equiv", "--mu", "4.0022", "--json"]);
    assert!(v["closed_form"].is_null() && v["name"].is_null());
    assert_eq!(v["integer"], false);
    let g = v["g"].as_f64().unwrap();
    assert!(g > 0.62 && g < 0.63, "{g}");
}

#[test]
fn equiv_text() {
    let out = ok(&["equiv", "--mu", "3"]);
    assert!(out.contains("g(mu) = 0.679"), "{out}");
    assert!(out.contains("Eq 25 odd"), "{out}");
}

// ---------------------------------------------------------------- roots

#[test]
fn roots_linear_model_equals_receptance() {
    let dir = tempfile::tempdir().unwrap();
    let (m, k, c) = (2.0_f64, 800.0_f64, 1.5_f64);
    let model = write(
        dir.path(),
        "linear.toml",
        &format!("mass = {m:?}\nstiffness = {k:?}\ndamping = {c:?}\n"),
    );
    let wn = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let gamma = 0.7;
    for f in [0.5, 2.0, 3.1, wn / (2.0 * PI), 4.6, 10.0, 40.0] {
        let v = json(&[
            "roots",
            "--model",
            model.to_str().unwrap(),
            "--gamma",
            &gamma.to_string(),
            "--f-hz",
            &format!("{f:?}"),
            "--json",
        ]);
        let roots = v["roots"].as_array().unwrap();
        assert_eq!(roots.len(), 1, "f = {f}: {v}");
        let w = 2.0 * PI * f;
        let h = gamma / ((wn * wn - w * w).powi(2) + (2.0 * zeta * wn * w).powi(2)).sqrt();
        let a = roots[0]["amplitude"].as_f64().unwrap();
        assert!(((a - h) / h).abs() < 1e-12, "f = {f}: {a} vs {h}");
        let phase = (2.0 * zeta * wn * w).atan2(wn * wn - w * w).to_degrees();
        let p = roots[0]["phase_deg"].as_f64().unwrap();
        assert!((p - phase).abs() < 1e-9, "f = {f}: phase {p} vs {phase}");
        assert_eq!(roots[0]["stable"], true);
        assert!(v["no_motion"].is_null());
    }
}

#[test]
fn roots_duffing_three_sorted_with_middle_unstable() {
    let m = example("duffing-strong.toml");
    let v = json(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2",
        "--f-hz",
        "12.5",
        "--json",
    ]);
    let roots = v["roots"].as_array().unwrap();
    assert_eq!(roots.len(), 3, "{v}");
    let amps: Vec<f64> = roots
        .iter()
        .map(|r| r["amplitude"].as_f64().unwrap())
        .collect();
    assert!(amps[0] < amps[1] && amps[1] < amps[2], "{amps:?}");
    let stable: Vec<bool> = roots
        .iter()
        .map(|r| r["stable"].as_bool().unwrap())
        .collect();
    assert_eq!(stable, [true, false, true]);
    for r in roots {
        let p = r["phase_deg"].as_f64().unwrap();
        assert!((0.0..=180.0).contains(&p));
    }
    let text = ok(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2",
        "--f-hz",
        "12.5",
    ]);
    assert!(
        text.contains("3 steady states") && text.contains("unstable"),
        "{text}"
    );
    // --formulation modulation is accepted and also finds the three states
    let v = json(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2",
        "--f-hz",
        "12.5",
        "--formulation",
        "modulation",
        "--json",
    ]);
    assert_eq!(v["formulation"], "modulation");
    assert_eq!(v["roots"].as_array().unwrap().len(), 3, "{v}");
}

#[test]
fn roots_coulomb_sticking_is_explicit() {
    let m = example("coulomb.toml");
    let v = json(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2",
        "--f-hz",
        "5",
        "--json",
    ]);
    assert_eq!(v["roots"].as_array().unwrap().len(), 0);
    assert_eq!(v["no_motion"], "sticking");
    assert!(
        (v["friction_accel"].as_f64().unwrap() - 8.0 / PI).abs() < 1e-12,
        "{v}"
    );
    assert!((v["input_accel"].as_f64().unwrap() - 2.0).abs() < 1e-15);
    let text = ok(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2",
        "--f-hz",
        "5",
    ]);
    assert!(
        text.contains("Coulomb friction sticks: 4 c_f/pi = 2.54648 N >= m gamma = 2 N"),
        "{text}"
    );
    // above the sticking level it moves
    let v = json(&[
        "roots",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "3",
        "--f-hz",
        "5",
        "--json",
    ]);
    assert_eq!(v["roots"].as_array().unwrap().len(), 1);
    assert!(v["no_motion"].is_null());
}

// ---------------------------------------------------------------- frf

fn duffing_frf(sweep: &str) -> Value {
    let m = example("duffing-strong.toml");
    json(&[
        "frf",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "0.5,1,2",
        "--f-min",
        "8",
        "--f-max",
        "16",
        "--steps",
        "200",
        "--sweep",
        sweep,
        "--json",
    ])
}

#[test]
fn frf_duffing_hysteresis_one_jump_each_way() {
    let up = duffing_frf("up");
    let down = duffing_frf("down");
    let (lu, ld) = (
        up["levels"].as_array().unwrap(),
        down["levels"].as_array().unwrap(),
    );
    assert_eq!(lu.len(), 3);
    assert_eq!(ld.len(), 3);
    for (u, d) in lu.iter().zip(ld) {
        assert_eq!(u["sweep"], "up");
        assert_eq!(d["sweep"], "down");
        let ju = u["jumps"].as_array().unwrap();
        let jd = d["jumps"].as_array().unwrap();
        assert_eq!(ju.len(), 1, "up: {ju:?}");
        assert_eq!(jd.len(), 1, "down: {jd:?}");
        let (fu, fd) = (
            ju[0]["f_hz"].as_f64().unwrap(),
            jd[0]["f_hz"].as_f64().unwrap(),
        );
        assert!(
            fd < fu - 0.05,
            "down jump {fd} Hz should be below up jump {fu} Hz"
        );
        assert!(
            fu > 8.5 && fu < 15.5 && fd > 8.5 && fd < 15.5,
            "jumps inside the band: {fu} {fd}"
        );
        // sweeping up the amplitude drops, sweeping down it rises
        assert!(
            ju[0]["amplitude_after"].as_f64().unwrap()
                < ju[0]["amplitude_before"].as_f64().unwrap()
        );
        assert!(
            jd[0]["amplitude_after"].as_f64().unwrap()
                > jd[0]["amplitude_before"].as_f64().unwrap()
        );
        // both jumps sit on folds, which do not depend on the direction
        let folds: Vec<f64> = u["folds_hz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f.as_f64().unwrap())
            .collect();
        assert_eq!(folds.len(), 2, "{folds:?}");
        assert_eq!(u["folds_hz"], d["folds_hz"]);
        assert!(
            folds.iter().any(|f| (f - fu).abs() < 1e-9)
                && folds.iter().any(|f| (f - fd).abs() < 1e-9)
        );
        let pq = &u["phase_quadrature"];
        assert!(
            pq["f_hz"].as_f64().unwrap() > 10.0 && pq["amplitude"].as_f64().unwrap() > 0.0,
            "{pq}"
        );
    }
    // higher level, later jump
    let f = |l: &Value| l["jumps"][0]["f_hz"].as_f64().unwrap();
    assert!(f(&lu[0]) < f(&lu[1]) && f(&lu[1]) < f(&lu[2]));
}

#[test]
fn frf_json_points_in_sweep_order_linear_grid() {
    for sweep in ["up", "down"] {
        let v = duffing_frf(sweep);
        for l in v["levels"].as_array().unwrap() {
            let pts = l["points"].as_array().unwrap();
            assert_eq!(pts.len(), 200);
            let f: Vec<f64> = pts.iter().map(|p| p["f_hz"].as_f64().unwrap()).collect();
            let (first, last) = if sweep == "up" {
                (8.0, 16.0)
            } else {
                (16.0, 8.0)
            };
            assert!(
                (f[0] - first).abs() < 1e-12 && (f[199] - last).abs() < 1e-12,
                "{sweep}: {} {}",
                f[0],
                f[199]
            );
            for w in f.windows(2) {
                let step = (w[1] - w[0]).abs();
                assert!((step - 8.0 / 199.0).abs() < 1e-9, "{sweep}: step {step}");
                assert_eq!(w[1] > w[0], sweep == "up");
            }
            for p in pts {
                assert!(p["amplitude"].as_f64().unwrap() > 0.0);
                let ph = p["phase_deg"].as_f64().unwrap();
                assert!((0.0..=180.0).contains(&ph));
                assert_eq!(p["stable"], true);
                assert_eq!(p["sticking"], false);
            }
        }
    }
}

#[test]
fn frf_csv_header_and_rows() {
    let m = example("duffing-strong.toml");
    let out = ok(&[
        "frf",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "0.5,1,2",
        "--f-min",
        "8",
        "--f-max",
        "16",
        "--steps",
        "37",
        "--csv",
    ]);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[0],
        "level,gamma,f_hz,amplitude,phase_deg,sweep,stable,sticking"
    );
    assert_eq!(lines.len(), 1 + 3 * 37);
    for (i, line) in lines[1..].iter().enumerate() {
        let all: Vec<&str> = line.split(',').collect();
        assert_eq!(all.len(), 8, "{line}");
        assert_eq!(&all[5..], &["up", "true", "false"], "{line}");
        let cols: Vec<f64> = all[..5].iter().map(|c| c.parse().unwrap()).collect();
        assert_eq!(cols[0] as usize, i / 37 + 1);
        assert_eq!(cols[1], [0.5, 1.0, 2.0][i / 37]);
        assert!(cols[2] >= 8.0 && cols[2] <= 16.0 && cols[3] > 0.0);
    }
}

#[test]
fn frf_coulomb_sticking_points() {
    let m = example("coulomb.toml");
    let v = json(&[
        "frf",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "2,5",
        "--f-min",
        "3",
        "--f-max",
        "7",
        "--steps",
        "20",
        "--json",
    ]);
    let levels = v["levels"].as_array().unwrap();
    assert!(levels[0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .all(|p| p["sticking"] == true && p["amplitude"] == 0.0));
    assert!(levels[0]["phase_quadrature"].is_null());
    assert!(levels[1]["points"]
        .as_array()
        .unwrap()
        .iter()
        .all(|p| p["sticking"] == false));
}

#[test]
fn frf_text_summary() {
    let m = example("duffing-strong.toml");
    let out = ok(&[
        "frf",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "1,2",
        "--f-min",
        "8",
        "--f-max",
        "16",
        "--steps",
        "50",
    ]);
    for want in [
        "level 1: gamma = 1 m/s^2 zero-to-peak",
        "level 2",
        "peak (swept)",
        "jump",
        "fold",
        "phase quadrature",
        "Hz",
    ] {
        assert!(out.contains(want), "missing {want:?} in\n{out}");
    }
}

#[test]
fn frf_plot_svg() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("duffing.svg");
    let m = example("duffing-strong.toml");
    let out = ok(&[
        "frf",
        "--model",
        m.to_str().unwrap(),
        "--gamma",
        "0.5,1,2",
        "--f-min",
        "8",
        "--f-max",
        "16",
        "--steps",
        "60",
        "--sweep",
        "down",
        "--json",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    serde_json::from_str::<Value>(&out).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg") && text.trim_end().ends_with("</svg>"));
    for want in [
        "Frequency f [Hz]",
        "Amplitude a [mm], zero-to-peak",
        "γ = 0.5",
        "γ = 2",
        "backbone",
        "unstable branch",
        "sweep down",
    ] {
        assert!(text.contains(want), "SVG lacks {want:?}");
    }
    // only the plot: no temporary left behind
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn help_teaches_model_units_and_examples() {
    for verb in ["equiv", "roots", "frf"] {
        let out = ok(&[verb, "--help"]);
        assert!(out.contains("EXAMPLE"), "{verb}: {out}");
        assert!(
            out.contains(&format!("nlsdof {verb} --")),
            "{verb} help lacks an example command"
        );
    }
    for verb in ["roots", "frf"] {
        let out = ok(&[verb, "--help"]);
        for want in [
            "m x'' + c x' + k x",
            "zero-to-peak",
            "m/s^2",
            "Hz",
            "lag of x behind the input",
            "90",
        ] {
            assert!(out.contains(want), "{verb} help lacks {want:?}");
        }
    }
    let out = ok(&["--help"]);
    assert!(out.contains("zero-to-peak") && out.contains("EXAMPLES"));
}

// ---------------------------------------------------------------- errors

#[test]
fn errors_are_one_line_exit_2_and_leave_no_file() {
    let models = tempfile::tempdir().unwrap();
    let outs = tempfile::tempdir().unwrap();
    let good = example("duffing-strong.toml");
    let good = good.to_str().unwrap();
    let bad_toml = write(
        models.path(),
        "bad.toml",
        "mass = 1.0\nstiffness = [1.0\ndamping = 0.0\n",
    );
    let neg_mass = write(
        models.path(),
        "neg.toml",
        "mass = -1.0\nstiffness = 1.0\ndamping = 0.0\n",
    );
    let low_exp = write(
        models.path(),
        "exp.toml",
        "mass = 1.0\nstiffness = 1.0\ndamping = 0.0\n[nonlinear_stiffness]\ncoefficient = 1.0\nexponent = -3.5\n",
    );
    let missing = models.path().join("missing.toml");
    let plot = outs.path().join("p.svg");
    let plot = plot.to_str().unwrap();
    let frf = |model: &str, gamma: &str, f0: &str, f1: &str, steps: &str| -> Vec<String> {
        [
            "frf", "--model", model, "--gamma", gamma, "--f-min", f0, "--f-max", f1, "--steps",
            steps, "--plot", plot,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            frf(missing.to_str().unwrap(), "1", "8", "16", "10"),
            "missing.toml",
        ),
        (
            frf(bad_toml.to_str().unwrap(), "1", "8", "16", "10"),
            "bad.toml",
        ),
        (
            frf(neg_mass.to_str().unwrap(), "1", "8", "16", "10"),
            "mass = -1",
        ),
        (frf(low_exp.to_str().unwrap(), "1", "8", "16", "10"), "-3.5"),
        (frf(good, "NaN", "8", "16", "10"), "NaN"),
        (frf(good, "1,nan", "8", "16", "10"), "NaN"),
        (frf(good, "0", "8", "16", "10"), "--gamma 0"),
        (frf(good, "1,-2", "8", "16", "10"), "--gamma -2"),
        (frf(good, "1,x", "8", "16", "10"), "'x'"),
        (frf(good, "1", "16", "8", "10"), "--f-min 16"),
        (frf(good, "1", "8", "8", "10"), "--f-min 8"),
        (frf(good, "1", "0", "8", "10"), "--f-min 0"),
        (frf(good, "1", "-1", "8", "10"), "--f-min -1"),
        (frf(good, "1", "8", "inf", "10"), "--f-max inf"),
        (frf(good, "1", "8", "16", "1"), "--steps 1"),
        (frf(good, "1", "8", "16", "0"), "--steps 0"),
        (frf(good, "1", "8", "16", "-5"), "-5"),
        (
            frf(good, "1", "8", "8.00000000000001", "50"),
            "--steps 50 is too many",
        ),
    ];
    for (args, want) in &cases {
        let a: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
        fails(&a, want, outs.path());
    }
    let base = [
        "frf", "--model", good, "--gamma", "1", "--f-min", "8", "--f-max", "16", "--steps", "10",
        "--plot", plot,
    ];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        base.iter().copied().chain(extra.iter().copied()).collect()
    };
    fails(&with(&["--sweep", "sideways"]), "sideways", outs.path());
    fails(&with(&["--formulation", "exact"]), "exact", outs.path());
    fails(&with(&["--json", "--csv"]), "--csv", outs.path());
    // unwritable plot path: nothing created anywhere
    fails(
        &[
            "frf",
            "--model",
            good,
            "--gamma",
            "1",
            "--f-min",
            "8",
            "--f-max",
            "16",
            "--steps",
            "10",
            "--plot",
            outs.path().join("no/such/dir/p.svg").to_str().unwrap(),
        ],
        "p.svg",
        outs.path(),
    );
    // roots and equiv
    fails(
        &[
            "roots",
            "--model",
            neg_mass.to_str().unwrap(),
            "--gamma",
            "1",
            "--f-hz",
            "10",
        ],
        "mass",
        outs.path(),
    );
    fails(
        &[
            "roots",
            "--model",
            missing.to_str().unwrap(),
            "--gamma",
            "1",
            "--f-hz",
            "10",
        ],
        "missing.toml",
        outs.path(),
    );
    fails(
        &["roots", "--model", good, "--gamma", "NaN", "--f-hz", "10"],
        "NaN",
        outs.path(),
    );
    fails(
        &["roots", "--model", good, "--gamma", "-1", "--f-hz", "10"],
        "--gamma -1",
        outs.path(),
    );
    fails(
        &["roots", "--model", good, "--gamma", "1", "--f-hz", "0"],
        "--f-hz 0",
        outs.path(),
    );
    fails(
        &["roots", "--model", good, "--gamma", "1"],
        "--f-hz",
        outs.path(),
    );
    fails(&["equiv", "--mu", "-3"], "--mu -3", outs.path());
    fails(&["equiv", "--mu", "-4.5"], "--mu -4.5", outs.path());
    fails(&["equiv", "--mu", "NaN"], "NaN", outs.path());
    fails(&["equiv", "--mu", "two"], "two", outs.path());
}
