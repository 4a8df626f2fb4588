//! `nlsdof fit-time` end to end on a synthetic Silverbox-like record
//! (header `"V1","V2",` with a trailing comma), the model file read back by
//! `nlsdof simulate`, and the bad-input contract.

mod common;

#[path = "../../nlsdof/tests/support/fixtures.rs"]
#[allow(dead_code)]
mod fixtures;
use common::{fails, json, ok, write};
use fixtures::Rng;
use nlsdof::identification::time_domain::{simulate_output, TimeModel};
use nlsdof::simulation::State;
use nlsdof::NormalisedModel;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const FS: f64 = 200.0;
const N: usize = 3000;

fn truth() -> TimeModel {
    TimeModel {
        model: NormalisedModel {
            alpha: 1000.0,
            delta: 3.0,
            beta: 2000.0,
            rho: 2.0,
            kappa: 0.0,
            eta: 0.0,
        },
        gain: 100.0,
        input_offset: 0.05,
        output_offset: 0.01,
    }
}

/// Silverbox-style CSV of an exact Duffing record (random-phase multisine).
fn write_record(dir: &Path) -> PathBuf {
    let mut rng = Rng(11);
    let lines: Vec<(f64, f64)> = (1..=30)
        .map(|k| (0.5 * k as f64, std::f64::consts::TAU * rng.uniform()))
        .collect();
    let amp = (2.0 / 30.0f64).sqrt();
    let u: Vec<f64> = (0..N)
        .map(|i| {
            let t = i as f64 / FS;
            lines
                .iter()
                .map(|(f, p)| amp * (std::f64::consts::TAU * f * t + p).sin())
                .sum()
        })
        .collect();
    let y = simulate_output(&truth(), &u, FS, State { x: 0.0, v: 0.0 }).unwrap();
    let mut s = String::from("\"V1\",\"V2\",\n");
    for (a, b) in u.iter().zip(&y) {
        writeln!(s, "{a:e},{b:e},").unwrap();
    }
    s.push('\n');
    write(dir, "rec.csv", &s)
}

#[test]
fn fits_predicts_and_simulate_reproduces_the_prediction() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_record(dir.path());
    let pred = dir.path().join("pred.csv");
    let model = dir.path().join("model.toml");
    let r = rec.to_str().unwrap();
    let v = json(&[
        "fit-time",
        "--input",
        r,
        "--input-column",
        "V1",
        "--output-column",
        "V2",
        "--fs",
        "200",
        "--range",
        "0:2000",
        "--model",
        "duffing",
        "--test",
        "2000:3000",
        "--predict",
        pred.to_str().unwrap(),
        "--out",
        model.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(v["converged"], true, "{v}");
    let t = truth();
    for (name, want) in [
        ("alpha", t.model.alpha),
        ("delta", t.model.delta),
        ("beta", t.model.beta),
        ("gain", t.gain),
        ("input_offset", t.input_offset),
        ("output_offset", t.output_offset),
    ] {
        let got = v["parameters"][name].as_f64().unwrap();
        // the CSV holds 6 significant digits
        assert!(
            (got - want).abs() <= 1e-3 * want.abs(),
            "{name}: {got} vs {want}"
        );
    }
    let test = &v["tests"][0];
    assert!(test["rms"].as_f64().unwrap() < 1e-4, "{test}");
    let x0 = test["initial"]["x0"].as_f64().unwrap();
    let v0 = test["initial"]["v0"].as_f64().unwrap();
    let text = std::fs::read_to_string(&pred).unwrap();
    assert!(text.starts_with("t,u,y_measured,y_model\n"), "{text:.80}");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 1000);
    assert!((rows[0][0] - 2000.0 / FS).abs() < 1e-12);
    let m = std::fs::read_to_string(&model).unwrap();
    assert!(m.contains("[signal]"), "{m}");
    // simulate reproduces y_model from the model file and the initial state
    let sim = dir.path().join("sim.csv");
    ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        pred.to_str().unwrap(),
        "--x0",
        &format!("{x0:e}"),
        "--v0",
        &format!("{v0:e}"),
        "--out",
        sim.to_str().unwrap(),
    ]);
    let s = std::fs::read_to_string(&sim).unwrap();
    assert!(s.starts_with("t,accel,x,v,y\n"), "{s:.80}");
    let scale = rows.iter().fold(0.0f64, |a, r| a.max(r[3].abs()));
    let err = s
        .lines()
        .skip(1)
        .zip(&rows)
        .map(|(l, r)| {
            let y: f64 = l.split(',').nth(4).unwrap().parse().unwrap();
            (y - r[3]).abs()
        })
        .fold(0.0, f64::max);
    assert!(err < 1e-9 * scale, "simulate vs prediction: {err:e}");
}

/// `--fix name=value` holds a parameter: held at its true value the others
/// are still recovered, the held value is in the document and the model
/// file, and it is not among the free parameters.
#[test]
fn fix_holds_a_parameter_at_its_value() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_record(dir.path());
    let model = dir.path().join("model.toml");
    let t = truth();
    let held = format!("gain={}", t.gain * 1.5);
    let run = |fix: &str| {
        json(&[
            "fit-time",
            "--input",
            rec.to_str().unwrap(),
            "--input-column",
            "V1",
            "--output-column",
            "V2",
            "--fs",
            "200",
            "--range",
            "0:2000",
            "--model",
            "duffing",
            "--fix",
            fix,
            "--out",
            model.to_str().unwrap(),
            "--json",
        ])
    };
    let v = run("delta=3");
    assert_eq!(v["parameters"]["delta"].as_f64(), Some(3.0), "{v}");
    for (name, want) in [
        ("alpha", t.model.alpha),
        ("beta", t.model.beta),
        ("gain", t.gain),
    ] {
        let got = v["parameters"][name].as_f64().unwrap();
        assert!((got - want).abs() <= 1e-3 * want, "{name}: {got} vs {want}");
    }
    assert!(
        !v["free"].to_string().contains("\"delta\""),
        "{}",
        v["free"]
    );
    // held away from the truth: the gain stays where it is held, the
    // others move to compensate and the fit is worse
    let w = run(&held);
    assert_eq!(w["parameters"]["gain"].as_f64(), Some(1.5 * t.gain), "{w}");
    let rms = |d: &serde_json::Value| d["estimation"]["rms"].as_f64().unwrap();
    assert!(rms(&w) > 10.0 * rms(&v), "{} vs {}", rms(&w), rms(&v));
    let m = std::fs::read_to_string(&model).unwrap();
    assert!(m.contains(&format!("input_gain = {}", 1.5 * t.gain)), "{m}");
}

#[test]
fn bad_input_one_line_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let rec = write_record(dir.path());
    let r = rec.to_str().unwrap();
    let out = dir.path().join("m.toml");
    let o = out.to_str().unwrap();
    let base = |range: &str, test: &str, extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = [
            "fit-time",
            "--input",
            r,
            "--input-column",
            "V1",
            "--output-column",
            "V2",
            "--fs",
            "200",
            "--range",
            range,
            "--model",
            "duffing",
            "--out",
            o,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        if !test.is_empty() {
            v.push("--test".into());
            v.push(test.into());
        }
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |args: Vec<String>, want: &str| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        fails(&a, want, &out);
    };
    run(
        base("0:5000", "", &[]),
        "outside the record of 3000 samples",
    );
    run(base("0:2000", "1500:3000", &[]), "overlap");
    run(base("0:2000", "2000:4000", &[]), "outside the record");
    run(base("2000:1000", "", &[]), "empty or reversed");
    let mut a = base("0:2000", "", &[]);
    a[8] = "0".into();
    run(a, "--fs 0");
    let mut a = base("0:2000", "", &[]);
    a[12] = "nope".into();
    run(a, "not a model");
    run(base("a:b", "", &[]), "is not a range");
    run(
        base("0:2000", "", &["--fix", "zeta=1"]),
        "--fix zeta: not a parameter",
    );
    run(base("0:2000", "", &["--fix", "delta"]), "is not name=value");
    run(
        base("0:2000", "", &["--fix", "delta=x"]),
        "'x' is not a number",
    );
    run(
        base("0:2000", "", &["--fix", "delta=1,delta=2"]),
        "given twice",
    );
    run(
        base("0:2000", "", &["--fix", "delta=-1"]),
        "inside its bounds",
    );
    let mut a = base("0:2000", "2000:2500", &["--test", "2500:3000"]);
    a.push("--predict".into());
    a.push(dir.path().join("p.csv").to_str().unwrap().into());
    run(a, "exactly one --test");
    let mut a = base("0:2000", "", &[]);
    a[4] = "V7".into();
    run(a, "no column \"V7\"");
    // a time column that is not uniform
    let t = write(
        dir.path(),
        "t.csv",
        "t,u,y\n0,1,2\n0.1,1,2\n0.2,1,2\n0.35,1,2\n",
    );
    fails(
        &[
            "fit-time",
            "--input",
            t.to_str().unwrap(),
            "--input-column",
            "u",
            "--output-column",
            "y",
            "--time-column",
            "t",
            "--range",
            "0:3",
            "--model",
            "linear",
            "--out",
            o,
        ],
        "not uniform",
        &out,
    );
}
