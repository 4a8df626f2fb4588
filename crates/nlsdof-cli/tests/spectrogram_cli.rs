//! End-to-end tests of `nlsdof spectrogram`: JSON summary against closed
//! forms (a tone of known amplitude at a bin frequency; a model 1 % too
//! large), PNG and CSV outputs, and the error contract (exit code 2, one
//! stderr line naming the offending value, no output file at all).

use assert_cmd::Command;
use serde_json::Value;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

fn nlsdof() -> Command {
    Command::new(env!("CARGO_BIN_EXE_nlsdof"))
}

fn ok(args: &[&str]) -> String {
    let out = nlsdof().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "nlsdof {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn listing(dir: &Path) -> Vec<std::ffi::OsString> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    v.sort();
    v
}

/// Must fail with exit code 2 and one stderr line containing `want`,
/// leaving the directory `dir` exactly as it was.
fn fails(args: &[&str], want: &str, dir: &Path) {
    let before = listing(dir);
    let o = nlsdof().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(2),
        "nlsdof {args:?}: expected exit 2, got {:?}; stderr: {err}",
        o.status.code()
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one stderr line: {err}");
    assert!(
        err.contains(want),
        "stderr {err:?} does not mention {want:?}"
    );
    assert_eq!(before, listing(dir), "files written or left behind");
}

/// CSV `t,accel,x` at 100 Hz, 3000 samples: accel a 3 Hz sine, x a 7 Hz
/// sine of amplitude `amp` (7 Hz is bin 14 of L = 200 → 0.5 Hz bins).
fn write_record(dir: &Path, name: &str, amp: f64) -> PathBuf {
    let mut s = String::from("t,accel,x\n");
    for n in 0..3000 {
        let t = n as f64 / 100.0;
        s.push_str(&format!(
            "{t},{},{}\n",
            0.5 * (TAU * 3.0 * t).sin(),
            amp * (TAU * 7.0 * t + 0.4).sin()
        ));
    }
    let p = dir.join(name);
    std::fs::write(&p, s).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn json_summary_pngs_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let meas = write_record(dir.path(), "meas.csv", 0.002);
    let model = write_record(dir.path(), "model.csv", 0.00202);
    let heat = dir.path().join("heat.png");
    let fall = dir.path().join("fall.png");
    let csv = dir.path().join("spec.csv");
    let out = ok(&[
        "spectrogram",
        "--input",
        s(&meas),
        "--column",
        "x",
        "--compare",
        s(&model),
        "--fmin",
        "2",
        "--fmax",
        "12",
        "--plot",
        s(&heat),
        "--waterfall",
        s(&fall),
        "--csv",
        s(&csv),
        "--json",
    ]);
    let v: Value = serde_json::from_str(out.trim()).unwrap();
    let st = &v["stft"];
    assert_eq!(st["segment_len"], 200);
    assert_eq!(st["noverlap"], 100);
    assert_eq!(st["segments"], 29);
    assert_eq!(st["window"], "hamming");
    assert_eq!(st["symmetry"], "symmetric");
    assert_eq!(st["scaling"], "amplitude");
    assert_eq!(v["fs_hz"], 100.0);
    // the tone: 7 Hz, amplitude 0.002 (to the window's mirror leakage)
    assert_eq!(v["peak"]["frequency_hz"], 7.0);
    let peak = v["peak"]["value"].as_f64().unwrap();
    assert!((peak - 0.002).abs() < 2e-3 * 0.002, "{peak}");
    // band 2..12 Hz: bins 4..=24
    assert_eq!(v["band_bins"], 21);
    let c = &v["compare"];
    let robust = c["robust_max_relative_percent"].as_f64().unwrap();
    assert!((robust - 1.0).abs() < 1e-6, "{robust}");
    assert!((c["robust_at_frequency_hz"].as_f64().unwrap() - 7.0).abs() < 1.01);
    assert_eq!(c["bins_total"], 29 * 21);
    assert!(c["bins_compared"].as_u64().unwrap() > 0);
    assert!((c["global_relative_percent"].as_f64().unwrap() - 1.0).abs() < 1e-6);
    for p in [&heat, &fall] {
        let bytes = std::fs::read(p).unwrap();
        assert!(
            bytes.len() > 10_000,
            "{} is {} bytes",
            p.display(),
            bytes.len()
        );
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,f_hz,s,s_compare,rel_diff_percent"
    );
    assert_eq!(lines.count(), 29 * 21);
    // nothing else (no temporaries) in the directory
    assert_eq!(listing(dir.path()).len(), 5);
}

#[test]
fn text_summary_one_column_with_fs_and_psd() {
    let dir = tempfile::tempdir().unwrap();
    let mut body = String::new();
    for n in 0..1500 {
        body.push_str(&format!("{}\n", (TAU * 10.0 * n as f64 / 100.0).sin()));
    }
    let p = dir.path().join("one.csv");
    std::fs::write(&p, body).unwrap();
    let out = ok(&[
        "spectrogram",
        "--input",
        s(&p),
        "--fs",
        "100",
        "--window",
        "hann",
        "--periodic",
        "--scaling",
        "psd",
    ]);
    assert!(out.contains("L = 100"), "{out}");
    assert!(out.contains("29 segments"), "{out}");
    assert!(out.contains("f = 10.0000 Hz"), "{out}");
    assert!(!out.contains("Eq 33"), "{out}");
}

#[test]
fn bad_input_exits_2_with_one_line_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let meas = write_record(d, "meas.csv", 0.002);
    let png = d.join("out.png");
    let csv = d.join("out.csv");
    // a non-finite sample on data line 10
    let text = std::fs::read_to_string(&meas).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[10] = "0.09,0.1,NaN".into();
    let bad = lines.join("\n");
    let badp = d.join("bad.csv");
    std::fs::write(&badp, bad).unwrap();
    fails(
        &[
            "spectrogram",
            "--input",
            s(&badp),
            "--column",
            "x",
            "--plot",
            s(&png),
        ],
        "NaN",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--column",
            "y",
            "--plot",
            s(&png),
        ],
        "\"y\"",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--overlap",
            "1",
            "--csv",
            s(&csv),
        ],
        "--overlap 1",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--floor",
            "2",
            "--csv",
            s(&csv),
        ],
        "--floor 2",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--segments",
            "2000",
            "--csv",
            s(&csv),
        ],
        "L = 1",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--fmin",
            "9",
            "--fmax",
            "3",
            "--csv",
            s(&csv),
        ],
        "--fmin 9",
        d,
    );
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--window",
            "kaiser",
            "--csv",
            s(&csv),
        ],
        "kaiser",
        d,
    );
    // comparison records of different length
    let short = d.join("short.csv");
    let t = std::fs::read_to_string(&meas).unwrap();
    std::fs::write(&short, t.lines().take(2000).collect::<Vec<_>>().join("\n")).unwrap();
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--column",
            "x",
            "--compare",
            s(&short),
            "--csv",
            s(&csv),
            "--plot",
            s(&png),
        ],
        "same length",
        d,
    );
    // the last output cannot be created: none of the outputs may appear
    let nowhere = d.join("no-such-dir").join("fig.png");
    fails(
        &[
            "spectrogram",
            "--input",
            s(&meas),
            "--column",
            "x",
            "--csv",
            s(&csv),
            "--plot",
            s(&png),
            "--waterfall",
            s(&nowhere),
        ],
        "no-such-dir",
        d,
    );
    // missing input file
    fails(
        &[
            "spectrogram",
            "--input",
            s(&d.join("missing.csv")),
            "--csv",
            s(&csv),
        ],
        "missing.csv",
        d,
    );
}

#[test]
fn help_explains_eq33_and_scaling() {
    let out = ok(&["spectrogram", "--help"]);
    for want in [
        "Eq 33",
        "robust",
        "20 log10",
        "--floor",
        "amplitude",
        "unit^2/Hz",
    ] {
        assert!(out.contains(want), "--help lacks {want:?}");
    }
}
