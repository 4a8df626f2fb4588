//! Issue 30 (reliability, third round): each reproduction of the issue as a
//! test, by class. docs/reliability.md ("Third round") lists them.

mod common;
use common::{example, fails_one_line, ok, write};

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A free decay of a linear oscillator (f = 20 Hz, ζ = 1 %), t,x at 1 kHz.
fn decay_record(dir: &Path) -> PathBuf {
    let mut text = String::from("t,x\n");
    for k in 0..8000 {
        let t = k as f64 / 1000.0;
        let w = std::f64::consts::TAU * 20.0;
        writeln!(
            text,
            "{t},{:e}",
            1e-3 * (-0.01 * w * t).exp() * (w * t).cos()
        )
        .unwrap();
    }
    write(dir, "decay.csv", &text)
}

/// Inputs every verb of the loop test needs: a sine, its response, an FRF,
/// stepped-sine data, a free decay.
struct Inputs {
    sine: PathBuf,
    response: PathBuf,
    frf: PathBuf,
    data: PathBuf,
    decay: PathBuf,
}

/// A chirp (5 to 20 Hz, 20 s at 200 Hz) and the response of the Duffing
/// example to it: `(chirp.csv, response.csv)`.
fn chirp_response(dir: &Path) -> (PathBuf, PathBuf) {
    let model = example("duffing-strong.toml");
    let sine = dir.join("sine.csv");
    ok(&[
        "signal",
        "chirp",
        "--amplitude",
        "1",
        "--f0",
        "5",
        "--f1",
        "20",
        "--duration",
        "20",
        "--fs",
        "200",
        "--out",
        s(&sine),
    ]);
    let response = dir.join("response.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&sine),
        "--out",
        s(&response),
    ]);
    (sine, response)
}

fn inputs(dir: &Path) -> Inputs {
    let model = example("duffing-strong.toml");
    let (sine, response) = chirp_response(dir);
    let frf = dir.join("frf.csv");
    ok(&[
        "frf-estimate",
        "--input",
        s(&response),
        "--input-channel",
        "accel",
        "--output-channel",
        "x",
        "--segment",
        "512",
        "--out",
        s(&frf),
    ]);
    let data = dir.join("data.csv");
    let csv = ok(&[
        "frf",
        "--model",
        s(&model),
        "--gamma",
        "0.5,1",
        "--f-min",
        "8",
        "--f-max",
        "14",
        "--steps",
        "30",
        "--csv",
    ]);
    std::fs::write(&data, csv).unwrap();
    Inputs {
        sine,
        response,
        frf,
        data,
        decay: decay_record(dir),
    }
}

/// Class 2: an output path that is a symbolic link loop is refused by every
/// verb, in one line, and the links stay links (it was replaced by a regular
/// file, exit 0, in ten verbs).
#[cfg(unix)]
#[test]
fn a_symlink_loop_as_output_is_refused_by_every_verb() {
    let dir = tempfile::tempdir().unwrap();
    let i = inputs(dir.path());
    let model = example("duffing-strong.toml");
    let (l1, l2) = (dir.path().join("l1.svg"), dir.path().join("l2.svg"));
    std::os::unix::fs::symlink(&l2, &l1).unwrap();
    std::os::unix::fs::symlink(&l1, &l2).unwrap();
    let l = s(&l1);
    let runs: Vec<Vec<&str>> = vec![
        vec![
            "signal",
            "sine",
            "--amplitude",
            "1",
            "--freq",
            "10",
            "--fs",
            "100",
            "--duration",
            "1",
            "--out",
            l,
        ],
        vec![
            "frf",
            "--model",
            s(&model),
            "--gamma",
            "1",
            "--f-min",
            "8",
            "--f-max",
            "12",
            "--steps",
            "5",
            "--plot",
            l,
        ],
        vec![
            "simulate",
            "--model",
            s(&model),
            "--input",
            s(&i.sine),
            "--out",
            l,
        ],
        vec![
            "stepped-sine",
            "--model",
            s(&model),
            "--gamma",
            "1",
            "--f-min",
            "9",
            "--f-max",
            "10",
            "--steps",
            "2",
            "--out",
            l,
        ],
        vec!["fit", s(&i.data), "--model", "duffing", "--out", l],
        vec![
            "fit-time",
            "--input",
            s(&i.response),
            "--input-column",
            "accel",
            "--output-column",
            "x",
            "--out",
            l,
        ],
        vec![
            "decay",
            "--input",
            s(&i.decay),
            "--column",
            "x",
            "--plot",
            l,
        ],
        vec![
            "linear-id",
            s(&i.frf),
            "--input",
            "acceleration",
            "--output",
            "displacement",
            "--out",
            l,
        ],
        vec![
            "frf-estimate",
            "--input",
            s(&i.response),
            "--input-channel",
            "accel",
            "--output-channel",
            "x",
            "--segment",
            "512",
            "--out",
            l,
        ],
        vec![
            "spectrogram",
            "--input",
            s(&i.sine),
            "--column",
            "accel",
            "--csv",
            l,
        ],
    ];
    for args in &runs {
        let err = fails_one_line(args);
        assert!(err.contains("symbolic link loop"), "{args:?}: {err}");
        for link in [&l1, &l2] {
            assert!(
                std::fs::symlink_metadata(link)
                    .unwrap()
                    .file_type()
                    .is_symlink(),
                "{args:?} replaced {}",
                link.display()
            );
        }
    }
}

/// Class 3: `demo` that fails on standard output leaves no folder; `--out`
/// a loop is refused before any work; `--out` a link to a folder keeps the
/// link and fills the folder.
#[cfg(target_os = "linux")]
#[test]
fn demo_leaves_nothing_when_it_fails_and_keeps_a_linked_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_nlsdof"))
        .args(["demo", "--quick", "--json", "--out", s(&out)])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "one line, no progress lines: {err}"
    );
    assert!(!out.exists(), "the demo folder was left behind");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing left"
    );
    // a loop: refused at once
    let (l1, l2) = (dir.path().join("l1"), dir.path().join("l2"));
    std::os::unix::fs::symlink(&l2, &l1).unwrap();
    std::os::unix::fs::symlink(&l1, &l2).unwrap();
    let t = std::time::Instant::now();
    let err = fails_one_line(&["demo", "--quick", "--force", "--out", s(&l1)]);
    assert!(err.contains("does not resolve"), "{err}");
    assert!(t.elapsed().as_secs_f64() < 0.5, "refused before any work");
    // a link to a folder: the link stays, the folder gets the report
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let link = dir.path().join("link");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    ok(&["demo", "--quick", "--out", s(&link)]);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(real.join("report.md").exists());
}

/// Class 4: zeta of extreme but valid scalings (mass 1e-300 printed
/// `zeta = inf`, 1e300 `zeta = 0.000000`, JSON null).
#[test]
fn zeta_is_right_at_extreme_scalings() {
    let dir = tempfile::tempdir().unwrap();
    for m in ["1e-300", "1e300"] {
        let mass: f64 = m.parse().unwrap();
        let model = write(
            dir.path(),
            "m.toml",
            &format!(
                "mass = {m}\nstiffness = {:e}\ndamping = {:e}\n",
                mass * 3947.84,
                mass * 1.256_637
            ),
        );
        let v: serde_json::Value = serde_json::from_str(&ok(&[
            "frf",
            "--model",
            s(&model),
            "--gamma",
            "1",
            "--f-min",
            "9",
            "--f-max",
            "11",
            "--steps",
            "3",
            "--json",
        ]))
        .unwrap();
        let z = v["zeta"].as_f64().unwrap_or(f64::NAN);
        assert!((z - 0.01).abs() < 1e-6, "mass {m}: zeta {z}");
    }
}

/// Class 5: a figure name whose format the option cannot write is refused
/// in one line and nothing is written (`decay --plot d.png` wrote SVG into
/// d.png); one policy for every figure option.
#[test]
fn figure_names_follow_one_policy() {
    let dir = tempfile::tempdir().unwrap();
    let decay = decay_record(dir.path());
    let model = example("duffing-strong.toml");
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let (pdf, svg) = (p("d.pdf"), p("d.svg"));
    let runs: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "decay",
                "--input",
                s(&decay),
                "--column",
                "x",
                "--plot",
                &pdf,
            ],
            "written as SVG or PNG",
        ),
        (
            vec![
                "frf",
                "--model",
                s(&model),
                "--gamma",
                "1",
                "--f-min",
                "8",
                "--f-max",
                "12",
                "--steps",
                "5",
                "--plot",
                &pdf,
            ],
            "written as SVG or PNG",
        ),
        (
            vec![
                "spectrogram",
                "--input",
                s(&decay),
                "--column",
                "x",
                "--plot",
                &svg,
            ],
            "written as PNG",
        ),
        (
            vec![
                "spectrogram",
                "--input",
                s(&decay),
                "--column",
                "x",
                "--waterfall",
                &svg,
            ],
            "written as PNG",
        ),
    ];
    for (args, want) in runs {
        let err = fails_one_line(&args);
        assert!(err.contains(want), "{args:?}: {err}");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "{args:?} wrote a file"
        );
    }
}

/// Class 6: the column-table reader of `fit-time` and `decay` quoted a gzip
/// header, binary garbage or UTF-16 text raw. Now each is named for what it
/// is, in one printable line.
#[test]
fn binary_and_utf16_inputs_are_named_not_dumped() {
    let dir = tempfile::tempdir().unwrap();
    let utf16: Vec<u8> = "t,x\n0,1\n1,2\n".bytes().flat_map(|b| [b, 0]).collect();
    let mut garbage: Vec<u8> = (0..2000u32).map(|i| (i * 7919 % 251) as u8).collect();
    garbage[10] = 0;
    let mut mat = b"MATLAB 5.0 MAT-file, Platform: GLNXA64".to_vec();
    mat.extend([0u8; 100]);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "g.csv.gz",
            vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3, b'\n', 0, 7],
            "gzip",
        ),
        ("b.csv", garbage, "binary data"),
        ("u.csv", utf16, "UTF-16"),
        (
            "bom16.csv",
            [
                &[0xffu8, 0xfe][..],
                &"t".bytes().flat_map(|b| [b, 0]).collect::<Vec<u8>>(),
            ]
            .concat(),
            "UTF-16",
        ),
        ("m.mat", mat, "MAT-file"),
    ];
    for (name, bytes, want) in cases {
        let p = dir.path().join(name);
        std::fs::write(&p, &bytes).unwrap();
        for args in [
            vec!["decay", "--input", s(&p), "--column", "x", "--fs", "100"],
            vec![
                "fit-time",
                "--input",
                s(&p),
                "--input-column",
                "u",
                "--output-column",
                "y",
                "--fs",
                "100",
            ],
        ] {
            let err = fails_one_line(&args);
            assert!(err.contains(want), "{args:?}: {err}");
            assert!(
                !err.trim_end()
                    .chars()
                    .any(|c| c.is_control() || c == '\u{fffd}'),
                "{args:?}: raw bytes in {err:?}"
            );
        }
    }
    // text that is merely odd is quoted escaped and short
    let odd = write(
        dir.path(),
        "odd.csv",
        &format!("t,x\n0,1\n1,a\u{2028}{}\n2,3\n", "z".repeat(300)),
    );
    let err = fails_one_line(&["decay", "--input", s(&odd), "--column", "x"]);
    assert!(err.len() < 300 && err.contains("\\u{2028}"), "{err}");
}

/// Class 9: a closed standard output was swallowed (`equiv --mu 2 >&-`
/// exited 0 and printed nothing). It is an error before any work, as any
/// other standard-output failure, and no file is written.
#[cfg(target_os = "linux")]
#[test]
fn a_closed_stdout_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.csv");
    for args in [
        vec!["equiv", "--mu", "2"],
        vec![
            "signal",
            "sine",
            "--amplitude",
            "1",
            "--freq",
            "10",
            "--fs",
            "100",
            "--duration",
            "1",
            "--out",
            s(&out),
        ],
    ] {
        let o = std::process::Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" >&-")
            .arg(env!("CARGO_BIN_EXE_nlsdof"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("standard output") && err.contains("closed"),
            "{err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists());
    }
}

/// Class 7: unbounded work is refused up front with the limit and its reason
/// (nlsdof::limits), in one line and well under a second.
#[test]
fn unbounded_work_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let decay = decay_record(dir.path());
    let model = example("duffing-strong.toml");
    let mut pr = String::from("gamma,f_hz,amplitude\n");
    for i in 0..20_000 {
        writeln!(
            pr,
            "{},{},1e-3",
            1.0 + i as f64 * 1e-3,
            10.0 + i as f64 * 1e-4
        )
        .unwrap();
    }
    let pr = write(dir.path(), "pr.csv", &pr);
    let mut frf = String::from("f_hz,re,im\n");
    for i in 0..1_000_100 {
        writeln!(frf, "{},1e-4,1e-6", 1.0 + i as f64 * 1e-4).unwrap();
    }
    let frf = write(dir.path(), "frf.csv", &frf);
    let runs: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "decay",
                "--input",
                s(&decay),
                "--column",
                "x",
                "--bins",
                "1000000000",
            ],
            "amplitude bins",
        ),
        (
            vec![
                "frf",
                "--model",
                s(&model),
                "--gamma",
                "1",
                "--f-min",
                "8",
                "--f-max",
                "14",
                "--steps",
                "5000",
                "--harmonics",
                "64",
            ],
            "steps x levels x H^3",
        ),
        (
            vec!["fit", s(&pr), "--phase-resonance"],
            "phase-resonance points",
        ),
        (
            vec![
                "linear-id",
                s(&frf),
                "--input",
                "acceleration",
                "--output",
                "displacement",
            ],
            "FRF lines",
        ),
    ];
    for (args, want) in runs {
        let t = std::time::Instant::now();
        let err = fails_one_line(&args);
        assert!(
            err.contains(want) && err.contains("above the limit"),
            "{args:?}: {err}"
        );
        assert!(
            t.elapsed().as_secs_f64() < 5.0,
            "{args:?} took {:?}",
            t.elapsed()
        );
    }
}

/// Class 8: the multi-harmonic balance of the bundled Coulomb example failed
/// from 2 Hz ("Newton did not converge ... (residual/gamma NaN)"): the
/// continuation's first point now uses the damped Newton of `solve_at`.
/// And no NaN in any message (`hb-error --h-max 1`), no 300-digit numbers
/// (`--tol 1e-300`).
#[test]
fn multi_harmonic_coulomb_covers_the_example_band_and_messages_have_no_nan() {
    let model = example("coulomb.toml");
    let m = s(&model);
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "frf",
        "--model",
        m,
        "--gamma",
        "5",
        "--f-min",
        "2",
        "--f-max",
        "8",
        "--steps",
        "60",
        "--harmonics",
        "3",
        "--json",
    ]))
    .unwrap();
    let pts = v["levels"][0]["points"].as_array().unwrap();
    assert_eq!(pts.len(), 60);
    // the first-order sweep agrees at the resonance peak to the harmonics' size
    let first: serde_json::Value = serde_json::from_str(&ok(&[
        "frf", "--model", m, "--gamma", "5", "--f-min", "2", "--f-max", "8", "--steps", "60",
        "--json",
    ]))
    .unwrap();
    let peak = |v: &serde_json::Value| {
        v["levels"][0]["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["amplitude"].as_f64().unwrap())
            .fold(0.0f64, f64::max)
    };
    let (a3, a1) = (peak(&v), peak(&first));
    assert!(
        (a3 - a1).abs() < 1e-2 * a1,
        "H = 3 peak {a3} vs first order {a1}"
    );
    for args in [
        vec![
            "hb-error", "--model", m, "--gamma", "5", "--f-min", "2", "--f-max", "8", "--h-max",
            "5",
        ],
        vec!["hb-error", "--model", m, "--gamma", "5", "--h-max", "1"],
        vec![
            "hb-error",
            "--model",
            s(&example("duffing-strong.toml")),
            "--gamma",
            "1",
            "--h-max",
            "3",
            "--tol",
            "1e-300",
        ],
    ] {
        let o = common::nlsdof().args(&args).output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        for text in [&o.stdout, &o.stderr] {
            let t = String::from_utf8_lossy(text);
            assert!(!t.contains("NaN") && !t.contains("nan"), "{args:?}: {t}");
            assert!(
                t.lines().all(|l| l.len() < 400),
                "{args:?}: a very long line"
            );
        }
    }
}

/// Class 4: `decay` on a record that is not a free decay (a chirp response
/// after its resonance) printed nonsense with exit 0 and "envelope error NaN
/// %". Now the verdict is the first line and in JSON (`adequate: false`).
#[test]
fn decay_of_a_forced_response_says_so_first() {
    let dir = tempfile::tempdir().unwrap();
    let (_, resp) = chirp_response(dir.path());
    let text = ok(&["decay", "--input", s(&resp), "--column", "x"]);
    assert!(
        text.starts_with("WARNING: the fitted model's free decay misses"),
        "{text}"
    );
    assert!(!text.contains("NaN"), "{text}");
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "decay",
        "--input",
        s(&resp),
        "--column",
        "x",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["adequate"], false);
    // a true free decay is adequate and quiet
    let decay = decay_record(dir.path());
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "decay",
        "--input",
        s(&decay),
        "--column",
        "x",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["adequate"], true, "{v}");
    assert!(v["envelope_error"].as_f64().unwrap() < 0.05);
}
