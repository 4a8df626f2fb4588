//! End-to-end tests of `frf --harmonics` and `hb-error` (issue 14).

mod common;
use common::{example, fails_one_line, json, write};

fn duffing() -> String {
    example("duffing-strong.toml").display().to_string()
}

#[test]
fn frf_harmonics_json_has_harmonics_and_max_abs_x() {
    let m = duffing();
    let v = json(&[
        "frf",
        "--model",
        &m,
        "--gamma",
        "2",
        "--f-min",
        "8",
        "--f-max",
        "16",
        "--steps",
        "41",
        "--harmonics",
        "5",
        "--json",
    ]);
    assert_eq!(v["harmonics"], 5);
    let lv = &v["levels"][0];
    let pts = lv["points"].as_array().unwrap();
    assert_eq!(pts.len(), 41);
    for p in pts {
        let h = p["harmonics"].as_array().unwrap();
        assert_eq!(h.len(), 6);
        for (k, e) in h.iter().enumerate() {
            assert_eq!(e["order"], k);
        }
        // "amplitude" is the first harmonic's
        assert_eq!(p["amplitude"], h[1]["amplitude"]);
        let a1 = p["amplitude"].as_f64().unwrap();
        let mx = p["max_abs_x"].as_f64().unwrap();
        assert!(mx >= 0.99 * a1 && mx.is_finite());
    }
    // hardening: one jump down on the up-sweep, two folds
    assert_eq!(lv["jumps"].as_array().unwrap().len(), 1);
    assert_eq!(lv["folds_hz"].as_array().unwrap().len(), 2);
    // H = 1 (default) points carry the same fields: orders 0 and 1
    let v1 = json(&[
        "frf", "--model", &m, "--gamma", "2", "--f-min", "8", "--f-max", "16", "--steps", "5",
        "--json",
    ]);
    let p = &v1["levels"][0]["points"][0];
    assert_eq!(p["harmonics"].as_array().unwrap().len(), 2);
    assert_eq!(p["max_abs_x"], p["amplitude"]);
}

#[test]
fn harmonics_bad_values_and_undamped_model_are_one_line_errors() {
    let m = duffing();
    let base = [
        "frf", "--model", &m, "--gamma", "2", "--f-min", "8", "--f-max", "16", "--steps", "5",
    ];
    for h in ["0", "65"] {
        let mut a = base.to_vec();
        a.extend(["--harmonics", h]);
        let e = fails_one_line(&a);
        assert!(e.contains("--harmonics"), "{e}");
    }
    let mut a = base.to_vec();
    a.extend(["--harmonics", "3", "--formulation", "modulation"]);
    fails_one_line(&a);
    let dir = tempfile::tempdir().unwrap();
    let und = write(
        dir.path(),
        "und.toml",
        "mass = 1.0\nstiffness = 3947.84\ndamping = 0.0\n",
    );
    let und = und.display().to_string();
    let e = fails_one_line(&[
        "frf",
        "--model",
        &und,
        "--gamma",
        "1",
        "--f-min",
        "8",
        "--f-max",
        "12",
        "--steps",
        "5",
        "--harmonics",
        "3",
    ]);
    assert!(e.contains("no damping"), "{e}");
    let e = fails_one_line(&["hb-error", "--model", &und, "--gamma", "1"]);
    assert!(e.contains("no damping"), "{e}");
}

#[test]
fn hb_error_converges_and_first_order_error_is_reported() {
    let m = duffing();
    let v = json(&[
        "hb-error", "--model", &m, "--gamma", "2", "--f-min", "8", "--f-max", "16", "--json",
    ]);
    let lv = &v["levels"][0];
    assert_eq!(lv["converged"], true);
    let rows = lv["rows"].as_array().unwrap();
    assert_eq!(rows[0]["harmonics"], 1);
    let e1 = rows[0]["peak_amplitude_error"].as_f64().unwrap();
    assert!(e1 > 1e-3, "{e1}");
    let last = rows.last().unwrap();
    assert_eq!(last["peak_amplitude_error"].as_f64().unwrap(), 0.0);
    assert_eq!(last["harmonics"], lv["reference_harmonics"]);
}

#[test]
fn coulomb_harmonics_reports_the_regularisation_check() {
    let m = example("coulomb.toml").display().to_string();
    let v = json(&[
        "frf",
        "--model",
        &m,
        "--gamma",
        "10",
        "--f-min",
        "3",
        "--f-max",
        "4",
        "--steps",
        "5",
        "--harmonics",
        "5",
        "--json",
    ]);
    let lv = &v["levels"][0];
    let chk = lv["regularisation_check"]["relative_change_eps_over_4"]
        .as_f64()
        .unwrap();
    assert!(chk < 1e-4, "{chk}");
    assert_eq!(lv["points"].as_array().unwrap().len(), 5);
    // smooth models have no regularisation
    let d = json(&[
        "frf",
        "--model",
        &duffing(),
        "--gamma",
        "1",
        "--f-min",
        "8",
        "--f-max",
        "9",
        "--steps",
        "3",
        "--harmonics",
        "3",
        "--json",
    ]);
    assert!(d["levels"][0]["regularisation_check"].is_null());
}
