//! A model file is a complete artefact (issue 25): `fit --out` holds the
//! forcing gain (`[signal] input_gain`) and the provenance, `frf --at` on the
//! data reproduces the fit's model curves bit for bit, and every
//! steady-state command applies the `[signal]` table or refuses it in one
//! line naming the key, writing nothing.

mod common;
use common::{nlsdof, ok};
use nlsdof::{ForcedResponse, Formulation, NormalisedModel, SweepDirection};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
/// The structure sees this multiple of the recorded level.
const TRUE_GAIN: f64 = 1.6;

/// Duffing + quadratic damping (f_n = 10 Hz), 3 levels, up and down sweeps
/// with jumps, recorded levels `gamma / TRUE_GAIN`; 0.5 % deterministic
/// amplitude noise so that the fit is not exact.
fn write_data(dir: &Path) -> PathBuf {
    let wn = TWO_PI * 10.0;
    let m = NormalisedModel {
        alpha: wn * wn,
        delta: 0.01 * wn,
        beta: 4.0e6,
        rho: 2.0,
        kappa: 0.02,
        eta: 1.0,
    };
    let freqs: Vec<f64> = (0..60).map(|i| 8.0 + 6.0 * i as f64 / 59.0).collect();
    let omegas: Vec<f64> = freqs.iter().map(|f| TWO_PI * f).collect();
    let mut s = String::from("level,gamma,f_hz,amplitude,sweep\n");
    let mut k = 0u32;
    for (l, g) in [("low", 0.05), ("mid", 0.12), ("high", 0.25)] {
        let r = ForcedResponse::from_normalised(&m, TRUE_GAIN * g, Formulation::HarmonicBalance)
            .unwrap();
        for dir in [SweepDirection::Up, SweepDirection::Down] {
            let mut pts = r.sweep(&omegas, dir).unwrap().points;
            if dir == SweepDirection::Down {
                pts.reverse();
            }
            for (f, p) in freqs.iter().zip(&pts) {
                k += 1;
                let noise = 1.0 + 0.005 * ((k as f64 * 1.618).fract() - 0.5);
                writeln!(s, "{l},{g},{f},{:e},{}", p.amplitude * noise, dir.name()).unwrap();
            }
        }
    }
    let path = dir.join("data.csv");
    std::fs::write(&path, s).unwrap();
    path
}

/// CSV rows as maps.
fn rows(text: &str) -> Vec<BTreeMap<String, String>> {
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

fn num(r: &BTreeMap<String, String>, k: &str) -> f64 {
    r[k].parse().unwrap_or_else(|_| panic!("{k} = {}", r[k]))
}

#[test]
fn fit_out_then_frf_at_the_data_reproduces_the_fit_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let data = write_data(dir.path());
    let (model, predict) = (dir.path().join("m.toml"), dir.path().join("p.csv"));
    let o = nlsdof()
        .args([
            "fit",
            data.to_str().unwrap(),
            "--model",
            "duffing-quadratic",
            "--free",
            "gain",
        ])
        .arg("--out")
        .arg(&model)
        .arg("--predict")
        .arg(&predict)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // the file holds the gain and the provenance as data
    let doc = nlsdof_io::model_file::read_document(&model).unwrap();
    let gain = doc.signal.expect("a [signal] table").input_gain;
    assert!((gain - TRUE_GAIN).abs() < 0.05, "gain {gain}");
    eprintln!("fitted gain {gain}");
    let prov = doc.provenance.expect("a [provenance] table");
    assert_eq!(prov.tool.as_deref(), Some("nlsdof fit"));
    assert_eq!(prov.model.as_deref(), Some("duffing-quadratic"));
    assert_eq!(prov.data.as_deref(), data.to_str());
    assert!(prov.cost.unwrap() > 0.0);

    let predicted = rows(&std::fs::read_to_string(&predict).unwrap());
    assert_eq!(predicted.len(), 360);
    // frf at the data's levels, frequencies and directions, from the file
    for at in [&data, &predict] {
        let o = nlsdof()
            .args(["frf", "--model", model.to_str().unwrap(), "--csv", "--at"])
            .arg(at)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let swept = rows(&String::from_utf8(o.stdout).unwrap());
        assert_eq!(swept.len(), predicted.len());
        // frf lists each level in sweep order, --predict by increasing frequency
        let mut matched = 0;
        for chunk in swept.chunks(60).zip(predicted.chunks(60)) {
            let (mut s, p) = (chunk.0.to_vec(), chunk.1);
            if s[0]["sweep"] == "down" {
                s.reverse();
            }
            for (a, b) in s.iter().zip(p) {
                assert_eq!(num(a, "gamma"), num(b, "gamma"), "levels as recorded");
                assert_eq!(num(a, "f_hz"), num(b, "f_hz"));
                assert_eq!(
                    num(a, "amplitude").to_bits(),
                    num(b, "model_amplitude").to_bits(),
                    "{a:?} vs {b:?}"
                );
                assert_eq!(num(a, "phase_deg"), num(b, "model_phase_deg"));
                matched += 1;
            }
        }
        assert_eq!(matched, 360);
    }
}

/// A plain model and the same model with `[signal] input_gain = 2`.
fn write_models(dir: &Path) -> (PathBuf, PathBuf) {
    let base = "mass = 0.5\nstiffness = 2000.0\ndamping = 0.3\n[nonlinear_stiffness]\ncoefficient = 4.0e7\nexponent = 2.0\n";
    let (plain, gained) = (dir.join("plain.toml"), dir.join("gained.toml"));
    std::fs::write(&plain, base).unwrap();
    std::fs::write(&gained, format!("{base}[signal]\ninput_gain = 2.0\n")).unwrap();
    (plain, gained)
}

#[test]
fn steady_state_commands_apply_the_input_gain() {
    let dir = tempfile::tempdir().unwrap();
    let (plain, gained) = write_models(dir.path());
    let (p, g) = (plain.to_str().unwrap(), gained.to_str().unwrap());
    // roots: the gained model at gamma equals the plain one at 2 gamma
    let roots = |m: &str, gamma: &str| -> serde_json::Value {
        serde_json::from_str(&ok(&[
            "roots", "--model", m, "--gamma", gamma, "--f-hz", "10.5", "--json",
        ]))
        .unwrap()
    };
    let (a, b) = (roots(g, "0.4"), roots(p, "0.8"));
    assert_eq!(a["roots"], b["roots"]);
    assert_eq!(a["gamma"], 0.4, "the level as given");
    assert_eq!(a["input_gain"], 2.0);
    assert_eq!(b["input_gain"], 1.0);
    let text = ok(&["roots", "--model", g, "--gamma", "0.4", "--f-hz", "10.5"]);
    assert!(text.contains("input_gain = 2"), "{text}");
    // frf: the same curves, the levels as given
    let frf = |m: &str, gamma: &str| {
        rows(&ok(&[
            "frf", "--model", m, "--gamma", gamma, "--f-min", "8", "--f-max", "14", "--steps",
            "40", "--csv",
        ]))
    };
    let (a, b) = (frf(g, "0.4"), frf(p, "0.8"));
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x["amplitude"], y["amplitude"]);
        assert_eq!(num(x, "gamma"), 0.4);
    }
    // multi-harmonic balance too
    let mhb = |m: &str, gamma: &str| -> serde_json::Value {
        serde_json::from_str(&ok(&[
            "frf",
            "--model",
            m,
            "--gamma",
            gamma,
            "--f-min",
            "8",
            "--f-max",
            "14",
            "--steps",
            "20",
            "--harmonics",
            "3",
            "--json",
        ]))
        .unwrap()
    };
    let (a, b) = (mhb(g, "0.4"), mhb(p, "0.8"));
    assert_eq!(a["levels"][0]["points"], b["levels"][0]["points"]);
    assert_eq!(a["levels"][0]["gamma"], 0.4);
}

#[test]
fn a_table_a_command_cannot_apply_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let base = "mass = 0.5\nstiffness = 2000.0\ndamping = 0.3\n[nonlinear_stiffness]\ncoefficient = 4.0e7\nexponent = 2.0\n";
    let cases = [
        (
            "offset.toml",
            "[signal]\ninput_gain = 2.0\ninput_offset = 0.01\n",
            "input_offset",
        ),
        (
            "negative.toml",
            "[signal]\ninput_gain = -2.0\n",
            "input_gain",
        ),
        (
            "nan.toml",
            "[signal]\ninput_gain = nan\n",
            "signal.input_gain",
        ),
        (
            "cost.toml",
            "[provenance]\ncost = -3.0\n",
            "provenance.cost",
        ),
    ];
    for (name, table, key) in cases {
        let m = dir.path().join(name);
        std::fs::write(&m, format!("{base}{table}")).unwrap();
        let m = m.to_str().unwrap();
        let plot = dir.path().join(format!("{name}.svg"));
        let runs: Vec<Vec<&str>> = vec![
            vec!["roots", "--model", m, "--gamma", "0.4", "--f-hz", "10"],
            vec![
                "frf",
                "--model",
                m,
                "--gamma",
                "0.4",
                "--f-min",
                "8",
                "--f-max",
                "12",
                "--steps",
                "10",
                "--plot",
                plot.to_str().unwrap(),
            ],
            vec!["hb-error", "--model", m, "--gamma", "0.4"],
        ];
        for args in runs {
            let o = nlsdof().args(&args).output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert!(err.contains(key), "{args:?}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{err}");
            assert!(o.stdout.is_empty());
            assert!(!plot.exists());
        }
    }
}
