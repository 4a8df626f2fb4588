//! End-to-end tests of `nlsdof simulate`, `nlsdof stepped-sine` and
//! `nlsdof signal`: output shapes and values against closed forms, the
//! error contract (exit code 2, one stderr line naming the offending value,
//! no output file) and Ctrl-C leaving no partial file.

mod common;
use common::{fails, ok, write};

use serde_json::Value;
use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

/// Linear model: m = 1 kg, k = (2π·2 Hz)² N/m, c = 0.4 N s/m.
fn linear_model(dir: &Path) -> PathBuf {
    write(
        dir,
        "lin.toml",
        &format!(
            "mass = 1.0\nstiffness = {}\ndamping = 0.4\n",
            (TAU * 2.0).powi(2)
        ),
    )
}

fn read_csv(p: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|f| f.parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// `signal sine` → `simulate` (both RK4 modes and Dormand–Prince) →
/// `t,accel,x,v` equal to the closed-form response of the linear model
/// (including the transient from rest) to 1e-6.
#[test]
fn simulate_linear_sine_matches_closed_form() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let input = d.path().join("sine.csv");
    let (a, f, fs) = (0.8, 1.9, 1024.0);
    ok(&[
        "signal",
        "sine",
        "--amplitude",
        "0.8",
        "--freq",
        "1.9",
        "--duration",
        "10",
        "--fs",
        "1024",
        "--out",
        input.to_str().unwrap(),
    ]);
    let (h, rows) = read_csv(&input);
    assert_eq!(h, ["t", "accel"]);
    assert_eq!(rows.len(), 10 * 1024 + 1);
    // closed form of x'' + δx' + αx = A sin Ωt from rest
    let (alpha, delta, w) = ((TAU * 2.0f64).powi(2), 0.4, TAU * f);
    let (re, im) = (alpha - w * w, delta * w);
    let den = re * re + im * im;
    let (hr, hi) = (re / den, -im / den);
    let xp = |t: f64| a * (hr * (w * t).sin() + hi * (w * t).cos());
    let vp = |t: f64| a * w * (hr * (w * t).cos() - hi * (w * t).sin());
    let sg = 0.5 * delta;
    let wd = (alpha - sg * sg).sqrt();
    let (c1, c2) = (-xp(0.0), (-vp(0.0) - sg * xp(0.0)) / wd);
    let exact = |t: f64| xp(t) + (-sg * t).exp() * (c1 * (wd * t).cos() + c2 * (wd * t).sin());
    for extra in [
        vec![],
        vec!["--samples-per-step", "1"],
        vec!["--method", "dopri"],
    ] {
        let out = d.path().join("resp.csv");
        let mut args = vec![
            "simulate",
            "--model",
            model.to_str().unwrap(),
            "--input",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(extra.iter().copied());
        let text = ok(&args);
        assert!(text.contains("simulated 10241 samples"), "{text}");
        let (h, rows) = read_csv(&out);
        assert_eq!(h, ["t", "accel", "x", "v"]);
        assert_eq!(rows.len(), 10241);
        let scale = rows.iter().map(|r| exact(r[0]).abs()).fold(0.0, f64::max);
        let err = rows
            .iter()
            .map(|r| (r[2] - exact(r[0])).abs())
            .fold(0.0, f64::max)
            / scale;
        // samples-per-step 1 reads the sine as piecewise linear: O(h²) input error
        let tol = if extra.first() == Some(&"--samples-per-step") || extra.get(1) == Some(&"dopri")
        {
            2e-5
        } else {
            1e-6
        };
        assert!(err < tol, "{extra:?}: relative error {err:e}");
        assert!(
            (rows[5][0] - 5.0 / fs).abs() < 1e-15
                && (rows[5][1] - a * (w * 5.0 / fs).sin()).abs() < 1e-12
        );
    }
}

/// `--json` summary, decimation, `--base` (input sign flipped), a one-column
/// input with `--fs`, and a non-uniform time column (RK4 one step per sample).
#[test]
fn simulate_options_and_json() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let col: String = (0..2001)
        .map(|k| format!("{}\n", (k as f64 * 0.01).sin()))
        .collect();
    let input = write(d.path(), "one.csv", &col);
    let out = d.path().join("o.csv");
    let v: Value = serde_json::from_str(&ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        input.to_str().unwrap(),
        "--fs",
        "200",
        "--decimate",
        "10",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]))
    .unwrap();
    assert_eq!(v["samples"], 2001);
    assert_eq!(v["outputs"], 201);
    assert_eq!(v["method"], "rk4");
    // issue 11: default on uniform sampling is RK4 with h = 1/(2 fs) and
    // cubic input between the samples (two steps per sample)
    assert_eq!(v["samples_per_step"], 0.5);
    assert_eq!(v["input_interpolation"], "cubic");
    assert_eq!(v["sampling"]["fs_hz"], 200.0);
    let (_, rows) = read_csv(&out);
    assert_eq!(rows.len(), 201);
    assert!((rows[200][0] - 10.0).abs() < 1e-12);
    let out2 = d.path().join("b.csv");
    ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        input.to_str().unwrap(),
        "--fs",
        "200",
        "--decimate",
        "10",
        "--base",
        "--out",
        out2.to_str().unwrap(),
    ]);
    let (_, neg) = read_csv(&out2);
    for (p, q) in rows.iter().zip(&neg) {
        assert!((p[2] + q[2]).abs() < 1e-15 && (p[1] + q[1]).abs() < 1e-15);
    }
    // non-uniform time column
    let txt: String = (0..400)
        .map(|k| {
            let t = k as f64 * 0.01 + if k % 2 == 1 { 0.003 } else { 0.0 };
            format!("{t},{}\n", t.sin())
        })
        .collect();
    let nu = write(d.path(), "nu.csv", &format!("t,accel\n{txt}"));
    let v: Value = serde_json::from_str(&ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        nu.to_str().unwrap(),
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]))
    .unwrap();
    assert_eq!(v["sampling"]["uniform"], false);
    assert_eq!(v["samples_per_step"], 1);
}

/// MAT v5 input: an n×2 [t accel] double matrix.
#[test]
fn simulate_reads_mat_files() {
    fn pad(b: &mut Vec<u8>) {
        while b.len() % 8 != 0 {
            b.push(0);
        }
    }
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let n = 500usize;
    let mut data: Vec<f64> = (0..n).map(|k| k as f64 / 100.0).collect();
    data.extend((0..n).map(|k| (k as f64 / 100.0 * 7.0).sin()));
    let mut el = vec![];
    for (ty, bytes) in [
        (6u32, [6u32.to_le_bytes(), 0u32.to_le_bytes()].concat()),
        (5, [(n as i32).to_le_bytes(), 2i32.to_le_bytes()].concat()),
    ] {
        el.extend_from_slice(&ty.to_le_bytes());
        el.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        el.extend_from_slice(&bytes);
    }
    el.extend_from_slice(&1u32.to_le_bytes());
    el.extend_from_slice(&3u32.to_le_bytes());
    el.extend_from_slice(b"rec");
    pad(&mut el);
    el.extend_from_slice(&9u32.to_le_bytes());
    el.extend_from_slice(&((8 * data.len()) as u32).to_le_bytes());
    for v in &data {
        el.extend_from_slice(&v.to_le_bytes());
    }
    let mut file = vec![b' '; 116];
    file[..10].copy_from_slice(b"MATLAB 5.0");
    file.extend_from_slice(&[0u8; 8]);
    file.extend_from_slice(&0x0100u16.to_le_bytes());
    file.extend_from_slice(b"IM");
    file.extend_from_slice(&14u32.to_le_bytes());
    file.extend_from_slice(&(el.len() as u32).to_le_bytes());
    file.extend_from_slice(&el);
    let mat = d.path().join("rec.mat");
    std::fs::write(&mat, file).unwrap();
    let out = d.path().join("m.csv");
    let csv_in = d.path().join("rec.csv");
    std::fs::write(
        &csv_in,
        (0..n)
            .map(|k| format!("{},{}\n", data[k], data[n + k]))
            .collect::<String>(),
    )
    .unwrap();
    let out2 = d.path().join("c.csv");
    ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        mat.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&[
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--input",
        csv_in.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read_to_string(&out).unwrap(),
        std::fs::read_to_string(&out2).unwrap()
    );
}

/// Bad input → exit 2, one line naming the problem and value, no output.
#[test]
fn simulate_rejects_bad_input_without_output() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let m = model.to_str().unwrap();
    let out = d.path().join("never.csv");
    let o = out.to_str().unwrap();
    let nan = write(
        d.path(),
        "nan.csv",
        "t,accel\n0,1\n0.01,2\n0.02,NaN\n0.03,1\n",
    );
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            nan.to_str().unwrap(),
            "--out",
            o,
        ],
        "line 4: input sample 2 = NaN is not a finite number",
        &out,
    );
    let mono = write(d.path(), "mono.csv", "0,1\n0.01,2\n0.005,3\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            mono.to_str().unwrap(),
            "--out",
            o,
        ],
        "t[2] = 0.005 s follows 0.01 s",
        &out,
    );
    let one = write(d.path(), "one.csv", "1\n2\n3\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            one.to_str().unwrap(),
            "--fs",
            "0",
            "--out",
            o,
        ],
        "fs = 0 Hz must be finite and > 0",
        &out,
    );
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            one.to_str().unwrap(),
            "--fs",
            "-2048",
            "--out",
            o,
        ],
        "fs = -2048 Hz",
        &out,
    );
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            one.to_str().unwrap(),
            "--out",
            o,
        ],
        "needs the sampling frequency (--fs HZ)",
        &out,
    );
    let empty = write(d.path(), "empty.csv", "");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            empty.to_str().unwrap(),
            "--fs",
            "100",
            "--out",
            o,
        ],
        "no samples (empty file)",
        &out,
    );
    let header_only = write(d.path(), "h.csv", "t,accel\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            header_only.to_str().unwrap(),
            "--out",
            o,
        ],
        "no samples",
        &out,
    );
    let cols = write(d.path(), "cols.csv", "0,1,2\n1,2,3\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            cols.to_str().unwrap(),
            "--out",
            o,
        ],
        "found 3 column(s)",
        &out,
    );
    let ragged = write(d.path(), "rag.csv", "0,1\n1,2\n2\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            ragged.to_str().unwrap(),
            "--out",
            o,
        ],
        "line 3",
        &out,
    );
    let text = write(d.path(), "txt.csv", "0,1\n1,abc\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            text.to_str().unwrap(),
            "--out",
            o,
        ],
        "\"abc\" is not a number",
        &out,
    );
    let good = write(d.path(), "good.csv", "0,1\n1,2\n");
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            good.to_str().unwrap(),
            "--fs",
            "10",
            "--out",
            o,
        ],
        "would contradict it",
        &out,
    );
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            d.path().join("missing.csv").to_str().unwrap(),
            "--out",
            o,
        ],
        "cannot read",
        &out,
    );
    fails(
        &[
            "simulate",
            "--model",
            m,
            "--input",
            good.to_str().unwrap(),
            "--samples-per-step",
            "3",
            "--out",
            o,
        ],
        "samples per step = 3",
        &out,
    );
    // a diverging (softening) model: error, not a file of infinities
    let soft = write(d.path(), "soft.toml", "mass = 1.0\nstiffness = 1.0\ndamping = 0.0\n[nonlinear_stiffness]\ncoefficient = -1.0\nexponent = 2.0\n");
    let push = write(
        d.path(),
        "push.csv",
        &(0..400)
            .map(|k| format!("{},5\n", k as f64 * 0.1))
            .collect::<String>(),
    );
    fails(
        &[
            "simulate",
            "--model",
            soft.to_str().unwrap(),
            "--input",
            push.to_str().unwrap(),
            "--out",
            o,
        ],
        "diverges",
        &out,
    );
}

/// Ctrl-C during a long run: exit 130 and neither the output nor its
/// temporary file remains.
#[test]
fn ctrl_c_leaves_no_partial_output() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let big: String = (0..3_000_000)
        .map(|k| if k % 2 == 0 { "0.5\n" } else { "-0.25\n" })
        .collect();
    let input = write(d.path(), "big.csv", &big);
    let out = d.path().join("out.csv");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_nlsdof"))
        .args([
            "simulate",
            "--model",
            model.to_str().unwrap(),
            "--input",
            input.to_str().unwrap(),
            "--fs",
            "2048",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // wait until the hidden temporary output exists, then interrupt
    let t0 = std::time::Instant::now();
    let partial = || {
        std::fs::read_dir(d.path()).unwrap().any(|e| {
            e.unwrap()
                .file_name()
                .to_string_lossy()
                .ends_with(".partial")
        })
    };
    while !partial() && t0.elapsed().as_secs() < 60 {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let sent = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    if status.success() {
        // finished before the signal arrived: then the file must be complete
        let (_, rows) = read_csv(&out);
        assert_eq!(rows.len(), 3_000_000);
        eprintln!("warning: run finished before Ctrl-C could be delivered");
        return;
    }
    assert_eq!(status.code(), Some(130));
    assert!(!out.exists(), "output exists after Ctrl-C");
    assert!(!partial(), "temporary file left after Ctrl-C");
}

/// The rig through the CLI: the fitting CSV format, details and history
/// files, both sweep directions; amplitudes of a linear model equal the
/// closed form.
#[test]
fn stepped_sine_cli_writes_the_fitting_format() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let out = d.path().join("rig.csv");
    let det = d.path().join("det.csv");
    let hist = d.path().join("hist.csv");
    let v: Value = serde_json::from_str(&ok(&[
        "stepped-sine",
        "--model",
        model.to_str().unwrap(),
        "--gamma",
        "0.5,1",
        "--f-min",
        "1.8",
        "--f-max",
        "2.2",
        "--steps",
        "9",
        "--sweep",
        "both",
        "--out",
        out.to_str().unwrap(),
        "--details",
        det.to_str().unwrap(),
        "--history",
        hist.to_str().unwrap(),
        "--history-decimate",
        "64",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["levels"].as_array().unwrap().len(), 4);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "level,gamma,f_hz,amplitude,phase_deg,sweep"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 9 * 2);
    let alpha = (TAU * 2.0f64).powi(2);
    for r in &rows {
        let (level, gamma, f, amp, ph) = (
            r[0],
            r[1].parse::<f64>().unwrap(),
            r[2].parse::<f64>().unwrap(),
            r[3].parse::<f64>().unwrap(),
            r[4].parse::<f64>().unwrap(),
        );
        assert!(level == "1" || level == "2", "level {level}");
        assert!(r[5] == "up" || r[5] == "down");
        let w = TAU * f;
        let exact = gamma / (alpha - w * w).hypot(0.4 * w);
        assert!(
            (amp - exact).abs() < 3e-4 * exact,
            "f {f}: {amp} vs {exact}"
        );
        let phase = (0.4 * w).atan2(alpha - w * w).to_degrees();
        assert!((ph - phase).abs() < 0.05 && (0.0..=180.0).contains(&ph));
    }
    assert_eq!(rows[0][2], "1.8");
    assert_eq!(rows[9 * 2][2], "2.2"); // first 'down' row of level 1
    let dt = std::fs::read_to_string(&det).unwrap();
    assert!(dt.starts_with("level,gamma,f_hz,amplitude,phase_deg,sweep,peak_to_peak,harmonic2,harmonic3,cycles,settled,residual\n"));
    assert!(dt
        .lines()
        .skip(1)
        .all(|l| l.split(',').nth(10) == Some("true")));
    let ht = std::fs::read_to_string(&hist).unwrap();
    assert!(ht.starts_with("level,gamma,sweep,t,accel,x,v\n") && ht.lines().count() > 100);
}

#[test]
fn stepped_sine_cli_rejects_bad_arguments() {
    let d = tempfile::tempdir().unwrap();
    let model = linear_model(d.path());
    let m = model.to_str().unwrap();
    let out = d.path().join("rig.csv");
    let o = out.to_str().unwrap();
    fails(
        &[
            "stepped-sine",
            "--model",
            m,
            "--gamma",
            "1,-2",
            "--f-min",
            "1",
            "--f-max",
            "2",
            "--steps",
            "5",
            "--out",
            o,
        ],
        "'-2'",
        &out,
    );
    fails(
        &[
            "stepped-sine",
            "--model",
            m,
            "--gamma",
            "1",
            "--f-min",
            "2",
            "--f-max",
            "1",
            "--steps",
            "5",
            "--out",
            o,
        ],
        "need 0 < f-min < f-max",
        &out,
    );
    fails(
        &[
            "stepped-sine",
            "--model",
            m,
            "--gamma",
            "1",
            "--f-min",
            "1",
            "--f-max",
            "2",
            "--steps",
            "1",
            "--out",
            o,
        ],
        "--steps 1",
        &out,
    );
    fails(
        &[
            "stepped-sine",
            "--model",
            m,
            "--gamma",
            "1",
            "--f-min",
            "1",
            "--f-max",
            "2",
            "--steps",
            "3",
            "--samples-per-cycle",
            "4",
            "--out",
            o,
        ],
        "samples per cycle = 4",
        &out,
    );
}

/// `signal chirp` (linear with the paper's rate, and logarithmic) and
/// `signal stepped-sine`: sample counts, frequencies from zero crossings.
#[test]
fn signal_generators() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("c.csv");
    ok(&[
        "signal",
        "chirp",
        "--amplitude",
        "0.25",
        "--f0",
        "4.5",
        "--rate",
        "0.005",
        "--f1",
        "6",
        "--fs",
        "64",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (_, rows) = read_csv(&out);
    assert_eq!(rows.len(), 300 * 64 + 1);
    assert!(rows.iter().all(|r| r[1].abs() <= 0.25 + 1e-12));
    // instantaneous frequency near t = 200 s from zero crossings over 2 s
    let zc = rows
        .windows(2)
        .filter(|w| w[0][0] >= 199.0 && w[1][0] <= 201.0 && (w[0][1] > 0.0) != (w[1][1] > 0.0))
        .count();
    let f_mid = 4.5 + 0.005 * 200.0;
    assert!(
        (zc as f64 / 4.0 - f_mid).abs() < 0.3,
        "{zc} crossings in 2 s vs {f_mid} Hz"
    );
    ok(&[
        "signal",
        "chirp",
        "--kind",
        "log",
        "--amplitude",
        "1",
        "--f0",
        "1",
        "--f1",
        "8",
        "--duration",
        "3",
        "--fs",
        "200",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(read_csv(&out).1.len(), 601);
    ok(&[
        "signal",
        "stepped-sine",
        "--amplitude",
        "1",
        "--f-min",
        "2",
        "--f-max",
        "3",
        "--steps",
        "3",
        "--dwell-cycles",
        "4",
        "--fs",
        "1000",
        "--out",
        out.to_str().unwrap(),
    ]);
    let dur = 4.0 / 2.0 + 4.0 / 2.5 + 4.0 / 3.0;
    assert_eq!(
        read_csv(&out).1.len(),
        (dur * 1000.0f64).floor() as usize + 1
    );
    let bad = d.path().join("bad.csv");
    fails(
        &[
            "signal",
            "sine",
            "--amplitude",
            "1",
            "--freq",
            "0",
            "--duration",
            "1",
            "--fs",
            "100",
            "--out",
            bad.to_str().unwrap(),
        ],
        "--freq 0",
        &bad,
    );
    fails(
        &[
            "signal",
            "sine",
            "--amplitude",
            "1",
            "--freq",
            "1",
            "--duration",
            "1",
            "--fs",
            "-1",
            "--out",
            bad.to_str().unwrap(),
        ],
        "--fs -1",
        &bad,
    );
    fails(
        &[
            "signal",
            "chirp",
            "--amplitude",
            "1",
            "--f0",
            "1",
            "--fs",
            "100",
            "--out",
            bad.to_str().unwrap(),
        ],
        "two of --f1, --rate, --duration",
        &bad,
    );
    fails(
        &[
            "signal",
            "stepped-sine",
            "--amplitude",
            "1",
            "--f-min",
            "1",
            "--f-max",
            "2",
            "--steps",
            "3",
            "--fs",
            "100",
            "--out",
            bad.to_str().unwrap(),
        ],
        "--dwell-cycles",
        &bad,
    );
}
