//! `nlsdof decay` end to end: a simulated Duffing free decay (CSV with a
//! time column) and the bad-input contract.

mod common;

use common::{fails, json, write};
use nlsdof::identification::time_domain::{simulate_output, TimeModel};
use nlsdof::simulation::State;
use nlsdof::NormalisedModel;
use std::fmt::Write as _;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

#[test]
fn duffing_decay_backbone_json_and_figure() {
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
    let x = simulate_output(&tm, &vec![0.0; 20_000], fs, State { x: 1.0, v: 0.0 }).unwrap();
    let mut s = String::from("t,x\n");
    for (k, v) in x.iter().enumerate() {
        writeln!(s, "{},{v:e}", k as f64 / fs).unwrap();
    }
    let f = write(dir.path(), "decay.csv", &s);
    let fig = dir.path().join("decay.svg");
    let v = json(&[
        "decay",
        "--input",
        f.to_str().unwrap(),
        "--column",
        "x",
        "--t-start",
        "0",
        "--json",
        "--plot",
        fig.to_str().unwrap(),
    ]);
    let bb = v["backbone"].as_array().unwrap();
    assert!(bb.len() >= 10, "{v}");
    for p in bb {
        let a = p["amplitude"].as_f64().unwrap();
        let f = p["f_hz"].as_f64().unwrap();
        let want = (tm.model.alpha + 0.75 * tm.model.beta * a * a).sqrt() / TWO_PI;
        assert!((f - want).abs() < 2e-3 * want, "{a}: {f} vs {want}");
    }
    assert!(v["envelope_error"].as_f64().unwrap() < 0.02, "{v}");
    assert!(std::fs::read_to_string(&fig).unwrap().contains("<svg"));
}

#[test]
fn bad_input_one_line_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = String::from("t,x\n");
    for k in 0..5000 {
        let t = k as f64 / 1000.0;
        writeln!(s, "{t},{}", (TWO_PI * 37.0 * t).sin()).unwrap();
    }
    let sine = write(dir.path(), "sine.csv", &s);
    let p = sine.to_str().unwrap();
    let fig = dir.path().join("f.svg");
    let fg = fig.to_str().unwrap();
    fails(
        &["decay", "--input", p, "--column", "x", "--plot", fg],
        "no decay",
        &fig,
    );
    fails(
        &[
            "decay", "--input", p, "--column", "x", "--band", "30:700", "--plot", fg,
        ],
        "Nyquist",
        &fig,
    );
    fails(
        &["decay", "--input", p, "--column", "y", "--plot", fg],
        "no column \"y\"",
        &fig,
    );
    let uneven = write(
        dir.path(),
        "u.csv",
        "t,x\n0,1\n0.001,0.5\n0.003,0.2\n0.004,0.1\n",
    );
    fails(
        &[
            "decay",
            "--input",
            uneven.to_str().unwrap(),
            "--column",
            "x",
            "--plot",
            fg,
        ],
        "not uniform",
        &fig,
    );
}

/// The clamped beam's impact records (Polytec ASCII, velocity in m/s) as a
/// check on a nearly linear decay: the backbone of the first test of each
/// set stays within 1 % of its mean frequency, near the beam's first mode
/// (measured 2026-11-23: 139.68–140.57 Hz without the magnet, 130.29–130.52
/// Hz with it; docs/decay.md). The second no-magnet test, struck harder
/// (0.28 m/s), hardens by 3.7 % and is not asserted here.
#[test]
fn beam_impact_decays_are_nearly_linear() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/clamped-beam-duffing-catarinaluz");
    if !root.is_dir() {
        eprintln!("SKIPPED: beam data directory {} is absent", root.display());
        return;
    }
    for (file, lo, hi) in [
        ("cc_beam_no_magnet_impact/mec-t1-velocity.txt", 135.0, 145.0),
        ("cc_beam_magnet_impact/mag-t1-velocity.txt", 125.0, 135.0),
    ] {
        let f = root.join(file);
        let v = json(&[
            "decay",
            "--input",
            f.to_str().unwrap(),
            "--column",
            "Time Signal",
            "--json",
        ]);
        let bb = v["backbone"].as_array().unwrap();
        assert!(bb.len() >= 10, "{file}: {v}");
        let fr: Vec<f64> = bb.iter().map(|p| p["f_hz"].as_f64().unwrap()).collect();
        let mean = fr.iter().sum::<f64>() / fr.len() as f64;
        assert!(lo < mean && mean < hi, "{file}: mean {mean} Hz");
        for &x in &fr {
            assert!((x / mean - 1.0).abs() < 1e-2, "{file}: {x} vs mean {mean}");
        }
    }
}
