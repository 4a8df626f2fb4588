//! `nlsdof demo` end to end: the report folder is complete, the summary's
//! numbers agree with the built-in truth, and the same seed gives the same
//! tables. Uses `--quick` (about 7 s per run in release on 2 cores).

use assert_cmd::Command;
use serde_json::Value;
use std::path::Path;

fn run_demo(out: &Path, seed: u64) -> Value {
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["demo", "--quick", "--json", "--seed"])
        .arg(seed.to_string())
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "demo failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("stdout is the JSON summary")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn fit<'a>(cfg: &'a Value, id: &str) -> &'a Value {
    cfg["fits"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["id"] == id)
        .unwrap_or_else(|| panic!("fit {id} missing"))
}

/// report.md without its timings block (the only run-dependent part).
fn report_without_timings(dir: &Path) -> String {
    let s = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let a = s.find("<!-- timings").expect("timings block start");
    let b = s.find("<!-- /timings -->").expect("timings block end");
    format!("{}{}", &s[..a], &s[b..])
}

#[test]
fn demo_quick_report_is_complete_sane_and_deterministic() {
    let tmp = tempfile::tempdir().unwrap();
    let r1 = tmp.path().join("r1");
    let summary = run_demo(&r1, 3);

    // --- the folder: report, summary, every figure and table, non-empty
    let report = std::fs::read_to_string(r1.join("report.md")).unwrap();
    assert!(report.len() > 5000, "report.md is too short");
    let on_disk: Value =
        serde_json::from_str(&std::fs::read_to_string(r1.join("summary.json")).unwrap()).unwrap();
    assert_eq!(on_disk, summary, "summary.json equals the --json output");
    let figures: Vec<&str> = summary["figures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for want in [
        "fig2_stepped_sine_data.svg",
        "fig4_linear_frf.svg",
        "fig5_classic.svg",
        "fig6_duffing_generalised.svg",
        "fig7_generalised.svg",
        "fig8c_time_envelope.svg",
        "fig9_rms_per_level.svg",
    ] {
        assert!(figures.contains(&want), "{want} not listed");
    }
    // Fig 8: heat map and waterfall for levels 1, 3, 5 of both configurations
    assert_eq!(figures.iter().filter(|f| f.ends_with(".png")).count(), 12);
    for name in &figures {
        let bytes = std::fs::read(r1.join(name)).unwrap();
        assert!(bytes.len() > 1000, "{name} is (nearly) empty");
        if name.ends_with(".svg") {
            let s = String::from_utf8(bytes).unwrap();
            assert!(
                s.starts_with("<svg") && s.trim_end().ends_with("</svg>"),
                "{name}"
            );
        } else {
            assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{name} is not a PNG");
        }
        assert!(
            report.contains(&format!("]({name})")),
            "report.md does not show {name}"
        );
    }
    for t in summary["tables"].as_array().unwrap() {
        let p = r1.join(t.as_str().unwrap());
        assert!(std::fs::metadata(&p).unwrap().len() > 20, "{}", p.display());
    }
    assert!(r1.join("tables/timings.csv").exists());
    // no staging folder left next to the report
    let leftovers: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "r1")
        .collect();
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");

    // --- the numbers against the built-in truth
    let configs = summary["configurations"].as_array().unwrap();
    assert_eq!(configs.len(), 2);
    for c in configs {
        let name = c["name"].as_str().unwrap();
        // the rig settled everywhere
        for l in c["rig"]["levels"].as_array().unwrap() {
            assert_eq!(l["unsettled"], 0, "{name}: unsettled rig steps");
        }
        // linear identification: f_n within 0.01 %; zeta biased high by the
        // nonlinear damping the chirp still excites (about +1 %), within 3 %
        let lin = &c["linear_id"];
        assert!(f(&lin["f_n_error_percent"]).abs() < 0.01, "{name}: {lin}");
        let dz = f(&lin["zeta_error_percent"]);
        assert!(dz > 0.0 && dz < 3.0, "{name}: zeta error {dz} %");

        let truth_cost = f(&c["rig"]["truth_cost"]);
        // the truth is a feasible point of the all-free generalised model:
        // its optimum cannot be (noticeably) worse
        let free = fit(c, "g-free");
        assert!(
            f(&free["cost"]) <= 1.001 * truth_cost,
            "{name}: g-free cost {} > truth {truth_cost}",
            free["cost"]
        );
        // ... and its 95 % intervals contain the truth more often than not
        let params = free["parameters"].as_array().unwrap();
        let covered = params
            .iter()
            .filter(|p| {
                let ci = p["ci95"].as_array().unwrap();
                let t = f(&p["truth"]);
                f(&ci[0]) <= t && t <= f(&ci[1])
            })
            .count();
        assert_eq!(params.len(), 6);
        assert!(covered >= 4, "{name}: truth inside {covered}/6 intervals");
        // exponents recovered to a few tenths
        for (pn, tn) in [("rho", "rho"), ("eta", "eta")] {
            let p = params.iter().find(|p| p["name"] == pn).unwrap();
            let t = f(&c["truth"][tn]);
            assert!(
                (f(&p["value"]) - t).abs() < 0.5,
                "{name}: {pn} = {}",
                p["value"]
            );
        }
        // with the (slightly biased) identified linear part fixed, the
        // generalised fit stays near the noise floor ...
        let g_real = fit(c, "g-real");
        assert!(
            f(&g_real["cost"]) < 1.5 * truth_cost,
            "{name}: {}",
            g_real["cost"]
        );
        // ... while the classic model is clearly inadequate, and the criteria say so
        let classic = fit(c, "classic");
        assert!(
            f(&classic["cost"]) > 10.0 * truth_cost,
            "{name}: classic fits too well?"
        );
        assert!(f(&g_real["aic"]) < f(&classic["aic"]));
        // Table 5 cases a and b (fitted to two levels, judged on all five)
        // cannot beat the classic least-squares fit to all levels
        for id in ["classic-a", "classic-b"] {
            assert!(
                f(&fit(c, id)["cost"]) >= f(&classic["cost"]) * 0.999,
                "{name}: {id}"
            );
        }
        assert!(f(&g_real["bic"]) < f(&classic["bic"]));
        // integer exponents: the generalised pair is the rounded real one +- radius
        let g_int = fit(c, "g-int");
        assert!(g_int["integer_pairs"].as_array().unwrap().len() == 9);
        // phase quadrature: measured vs true model within 2 % (noise, 2 mHz steps)
        for p in c["rig"]["phase_quadrature_truth"].as_array().unwrap() {
            let (a, am) = (f(&p["model_amplitude"]), f(&p["measured_amplitude"]));
            assert!(((a - am) / am).abs() < 0.02, "{name}: {p}");
        }
        // spectrograms: the fitted model matches where there is signal
        for t in c["time_frequency"].as_array().unwrap() {
            let robust = f(&t["robust_max_relative_percent"]);
            assert!(robust > 0.0 && robust < 10.0, "{name}: {t}");
            // Eq 33 as printed is dominated by near-empty bins
            if let Some(raw) = t["eq33_max_relative_percent"].as_f64() {
                assert!(raw >= robust);
            }
        }
    }

    // --- same seed, same tables
    let r2 = tmp.path().join("r2");
    let mut again = run_demo(&r2, 3);
    let mut first = summary.clone();
    for v in [&mut first, &mut again] {
        v.as_object_mut().unwrap().remove("timings_s");
    }
    assert_eq!(first, again, "summary differs between runs with one seed");
    let mut tables: Vec<String> = std::fs::read_dir(r1.join("tables"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "timings.csv")
        .collect();
    tables.sort();
    assert!(tables.len() >= 8, "{tables:?}");
    for t in &tables {
        assert_eq!(
            std::fs::read_to_string(r1.join("tables").join(t)).unwrap(),
            std::fs::read_to_string(r2.join("tables").join(t)).unwrap(),
            "table {t} differs"
        );
    }
    assert_eq!(report_without_timings(&r1), report_without_timings(&r2));

    // --- an existing non-empty folder is refused without --force, untouched
    let before = std::fs::read(r1.join("report.md")).unwrap();
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["demo", "--quick", "--out"])
        .arg(&r1)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not empty") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert_eq!(std::fs::read(r1.join("report.md")).unwrap(), before);
}

#[test]
fn demo_rejects_bad_options_with_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    for args in [
        vec!["--noise", "0.9"],
        vec!["--starts", "0"],
        vec!["--integer-radius", "9"],
    ] {
        let o = Command::cargo_bin("nlsdof")
            .unwrap()
            .arg("demo")
            .args(&args)
            .arg("--out")
            .arg(tmp.path().join("x"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.starts_with("nlsdof: error:"), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(!tmp.path().join("x").exists());
    }
    // a file where the folder should go
    let file = tmp.path().join("file");
    std::fs::write(&file, "x").unwrap();
    let o = Command::cargo_bin("nlsdof")
        .unwrap()
        .args(["demo", "--out"])
        .arg(&file)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}
