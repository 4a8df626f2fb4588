//! Universal files (dataset 58) through the CLI: `linear-id` and
//! `frf-estimate` read them as the same data given as CSV (identical
//! results), `fit` reads a stepped-sine FRF set as the long CSV it was made
//! from (identical parameters), `frf --uff` and `simulate --out X.uff`
//! write what the library reader reads back as the CSV output, and the
//! refusals (no level, abscissa not a frequency, complex where a real
//! function is needed) are one line, exit 2, no output file.

mod common;

use common::{example, fails, json, ok};
use nlsdof_io::uff58::{
    read, write_ascii_file, write_binary_file, Abscissa, AxisInfo, Uff58Data, Uff58Dataset,
};
use std::f64::consts::PI;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A lightly damped SDoF receptance to base acceleration, m/(m/s^2), at
/// 200 frequencies from 5 to 15 Hz (f_n 10 Hz, zeta 0.02).
fn sdof_frf() -> Uff58Dataset {
    let (wn, zeta) = (2.0 * PI * 10.0, 0.02);
    let f: Vec<f64> = (0..200).map(|k| 5.0 + 0.05 * k as f64).collect();
    let h = f
        .iter()
        .map(|&f| {
            let w = 2.0 * PI * f;
            let (re, im) = (wn * wn - w * w, 2.0 * zeta * wn * w);
            let d = re * re + im * im;
            (re / d, -im / d)
        })
        .collect();
    let mut d = Uff58Dataset::frf(
        Abscissa::Even {
            start: 5.0,
            step: 0.05,
        },
        h,
    );
    d.header.id1 = "receptance 1+Z/base".into();
    d.header.ordinate_axis = AxisInfo::new(8, "Displacement", "m");
    d.header.denominator_axis = AxisInfo::new(12, "Acceleration", "m/s^2");
    d
}

/// A real coherence dataset over the same frequencies.
fn coherence() -> Uff58Dataset {
    let mut d = Uff58Dataset::frf(
        Abscissa::Even {
            start: 5.0,
            step: 0.05,
        },
        vec![],
    );
    d.header.function_type = 6;
    d.header.id1 = "coherence".into();
    d.data = Uff58Data::Real(vec![0.99; 200]);
    d
}

#[test]
fn linear_id_reads_a_uff_frf_as_the_same_csv() {
    let dir = tempfile::tempdir().unwrap();
    let uff = dir.path().join("h.uff");
    write_ascii_file(&uff, &[coherence(), sdof_frf()]).unwrap();
    // the CSV holds the values exactly as the library reads them back
    let back = read(&uff).unwrap();
    let Uff58Data::Complex(h) = &back[1].dataset.data else {
        panic!("complex")
    };
    let csv = dir.path().join("h.csv");
    nlsdof_io::frf_file::write_frf_csv(&csv, &back[1].dataset.abscissa_values(), h, None).unwrap();
    let from_csv = json(&["linear-id", s(&csv), "--poles", "1", "--json"]);
    // default: the file's only FRF (function type 4); by index; by ID-line text
    for extra in [&[][..], &["--dataset", "1"][..], &["--dataset", "1+Z"][..]] {
        let mut args = vec!["linear-id", s(&uff), "--poles", "1", "--json"];
        args.extend_from_slice(extra);
        assert_eq!(json(&args), from_csv, "{extra:?}");
    }
    let fnat = from_csv["sdof"]["f_n_hz"].as_f64().unwrap();
    assert!((fnat - 10.0).abs() < 1e-6, "{fnat}");

    // refusals: a real function, a time abscissa, --dataset on a CSV
    let out = dir.path().join("model.toml");
    let e = fails(
        &["linear-id", s(&uff), "--dataset", "0", "--out", s(&out)],
        "dataset 0 (\"coherence\") is real (coherence): an FRF is a complex function",
        &out,
    );
    assert!(e.contains("h.uff"), "{e}");
    let mut timed = sdof_frf();
    timed.header.abscissa_axis = AxisInfo::new(17, "Time", "s");
    let bad = dir.path().join("t.uff");
    write_ascii_file(&bad, &[timed]).unwrap();
    fails(
        &["linear-id", s(&bad), "--out", s(&out)],
        "the abscissa is time (specific data type 17, units 's'), not a frequency in Hz",
        &out,
    );
    fails(
        &["linear-id", s(&csv), "--dataset", "1", "--out", s(&out)],
        "chooses a dataset of a universal file",
        &out,
    );
    fails(
        &["linear-id", s(&uff), "--dataset", "7", "--out", s(&out)],
        "no dataset matches '7' (datasets: 0: coherence, real 'coherence'; 1: frequency response function, complex",
        &out,
    );
}

#[test]
fn frf_estimate_reads_uff_time_responses_as_the_same_csv() {
    let dir = tempfile::tempdir().unwrap();
    let n: usize = 4096;
    let force: Vec<f64> = (0..n)
        .map(|k| ((k as f64 * 0.731).sin() * 1e6).round() / 1e6 + ((k * k) % 17) as f64 * 0.01)
        .collect();
    // a moving average of the force as the response
    let resp: Vec<f64> = (0..n)
        .map(|k| {
            let lo = k.saturating_sub(3_usize);
            force[lo..=k].iter().sum::<f64>() / 4.0
        })
        .collect();
    let mut sets = Vec::new();
    for (name, v) in [("force", &force), ("response", &resp)] {
        let mut d = Uff58Dataset::time_response(0.0, 1.0 / 1000.0, v.clone());
        d.header.id1 = name.into();
        sets.push(d);
    }
    let mut complex = sdof_frf();
    complex.header.id1 = "an FRF".into();
    sets.push(complex);
    let uff = dir.path().join("th.uff");
    write_ascii_file(&uff, &sets).unwrap();
    let back = read(&uff).unwrap();
    let Abscissa::Even { step, .. } = back[0].dataset.abscissa else {
        panic!("even")
    };
    let col = |i: usize| match &back[i].dataset.data {
        Uff58Data::Real(v) => v.clone(),
        _ => panic!("real"),
    };
    let (x, y) = (col(0), col(1));
    let mut text = String::from("force,response\n");
    for (a, b) in x.iter().zip(&y) {
        text += &format!("{a:?},{b:?}\n");
    }
    let csv = common::write(dir.path(), "th.csv", &text);
    let fs = format!("{:?}", 1.0 / step);
    let out_csv = dir.path().join("from_csv.csv");
    ok(&[
        "frf-estimate",
        "--input",
        s(&csv),
        "--fs",
        &fs,
        "--segment",
        "512",
        "--out",
        s(&out_csv),
    ]);
    // default channels 1 and 2 (dataset indices 0 and 1), or by ID-line text
    for (i, extra) in [
        &[][..],
        &["--input-channel", "force", "--output-channel", "resp"][..],
    ]
    .iter()
    .enumerate()
    {
        let out_uff = dir.path().join(format!("from_uff{i}.csv"));
        let mut args = vec!["frf-estimate", "--input", s(&uff), "--segment", "512"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", s(&out_uff)]);
        ok(&args);
        assert_eq!(
            std::fs::read_to_string(&out_uff).unwrap(),
            std::fs::read_to_string(&out_csv).unwrap(),
            "{extra:?}"
        );
    }
    // complex where a real function is needed; --fs contradicting the file
    let out = dir.path().join("h.csv");
    fails(
        &["frf-estimate", "--input", s(&uff), "--output-channel", "3", "--out", s(&out)],
        "channel 3 (\"an FRF\") is complex (frequency response function): a time history is a real function",
        &out,
    );
    fails(
        &[
            "frf-estimate",
            "--input",
            s(&uff),
            "--fs",
            "1000",
            "--out",
            s(&out),
        ],
        "--fs 1000 would contradict it",
        &out,
    );
}

/// Rows of `nlsdof frf --csv`: (level, gamma, f_hz, amplitude, phase_deg, sweep).
fn frf_rows(csv: &str) -> Vec<(String, f64, f64, f64, f64, String)> {
    csv.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let n = |i: usize| c[i].parse::<f64>().unwrap();
            (c[0].to_string(), n(1), n(2), n(3), n(4), c[5].to_string())
        })
        .collect()
}

/// The stepped-sine set of `rows` as one FRF dataset per (level, sweep):
/// response kind 0 displacement, 1 velocity, 2 acceleration over the base
/// acceleration; the level and sweep in ID line 2 when `tokens`.
fn stepped_sine_uff(
    rows: &[(String, f64, f64, f64, f64, String)],
    kind: u32,
    tokens: bool,
) -> Vec<Uff58Dataset> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.0.clone(), r.5.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.iter()
        .map(|(level, sweep)| {
            let pts: Vec<_> = rows
                .iter()
                .filter(|r| &r.0 == level && &r.5 == sweep)
                .collect();
            let gamma = pts[0].1;
            let f: Vec<f64> = pts.iter().map(|r| r.2).collect();
            let h = pts
                .iter()
                .map(|r| {
                    // X = a e^{-j phi}; H = X (j Omega)^kind / gamma
                    let (w, phi) = (2.0 * PI * r.2, r.4.to_radians());
                    let (mut re, mut im) = (r.3 * phi.cos() / gamma, -r.3 * phi.sin() / gamma);
                    for _ in 0..kind {
                        (re, im) = (-im * w, re * w);
                    }
                    (re, im)
                })
                .collect();
            let mut d = Uff58Dataset::frf(Abscissa::Uneven(f), h);
            d.header.id1 = format!("level {level} {sweep}");
            if tokens {
                d.header.id2 = format!("gamma={gamma:?} sweep={sweep} level={level}");
            }
            let (t, label, units) = match kind {
                0 => (8, "Displacement", "m"),
                1 => (11, "Velocity", "m/s"),
                _ => (12, "Acceleration", "m/s^2"),
            };
            d.header.ordinate_axis = AxisInfo::new(t, label, units);
            d.header.denominator_axis = AxisInfo::new(12, "Acceleration", "m/s^2");
            d
        })
        .collect()
}

fn parameters(v: &serde_json::Value) -> Vec<(String, f64)> {
    v["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            (
                p["name"].as_str().unwrap().to_string(),
                p["value"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn fit_reads_a_uff_stepped_sine_set_as_its_csv() {
    let dir = tempfile::tempdir().unwrap();
    let model = example("duffing-strong.toml");
    let sweep = |dir: &str| {
        ok(&[
            "frf",
            "--model",
            s(&model),
            "--gamma",
            "0.5,1",
            "--f-min",
            "8",
            "--f-max",
            "16",
            "--steps",
            "41",
            "--sweep",
            dir,
            "--csv",
        ])
    };
    let up = sweep("up");
    let down = sweep("down");
    let text = format!("{up}{}", down.split_once('\n').unwrap().1);
    let csv = common::write(dir.path(), "set.csv", &text);
    let rows = frf_rows(&text);
    assert_eq!(rows.len(), 4 * 41);
    let base = ["--model", "duffing", "--json"];
    let from_csv = parameters(&json(&[&["fit", s(&csv)][..], &base[..]].concat()));
    let names: Vec<&str> = from_csv.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(names, ["alpha", "delta", "beta", "rho", "gain"]);
    let same = |p: &[(String, f64)], what: &str| {
        for ((n1, v1), (n2, v2)) in p.iter().zip(&from_csv) {
            assert_eq!(n1, n2);
            assert!(
                (v1 - v2).abs() <= 1e-9 * v2.abs(),
                "{what}: {n1} {v1} vs {v2} (CSV)"
            );
        }
    };
    // receptance with gamma/sweep/level tokens (binary 58b: bit-exact data)
    let p = dir.path().join("set.uff");
    write_binary_file(&p, &stepped_sine_uff(&rows, 0, true)).unwrap();
    same(
        &parameters(&json(&[&["fit", s(&p)][..], &base[..]].concat())),
        "receptance",
    );
    // accelerance without tokens: levels from --level-gamma, sweeps from the ID line
    let mut sets = stepped_sine_uff(&rows, 2, false);
    for d in &mut sets {
        d.header.id2 = format!(
            "sweep={}",
            if d.header.id1.ends_with("down") {
                "down"
            } else {
                "up"
            }
        );
    }
    let q = dir.path().join("acc.uff");
    write_binary_file(&q, &sets).unwrap();
    let v = json(
        &[
            &["fit", s(&q), "--level-gamma", "0.5,1,0.5,1"][..],
            &base[..],
        ]
        .concat(),
    );
    same(&parameters(&v), "accelerance");
    // velocity over acceleration, level as the z-axis value (m/s^2)
    let mut sets = stepped_sine_uff(&rows, 1, true);
    for d in &mut sets {
        let g: f64 = d.header.id2[6..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        d.header.id2 = d.header.id2.replace(&format!("gamma={g:?} "), "");
        d.header.z_axis = AxisInfo::new(12, "Level", "m/s^2");
        d.header.z_axis_value = g;
    }
    let r = dir.path().join("vel.uff");
    write_binary_file(&r, &sets).unwrap();
    same(
        &parameters(&json(&[&["fit", s(&r)][..], &base[..]].concat())),
        "mobility",
    );

    // refusals
    let out = dir.path().join("fitted.toml");
    let fit_out = |file: &Path| {
        vec![
            "fit".to_string(),
            s(file).to_string(),
            "--out".into(),
            s(&out).into(),
        ]
    };
    let args = |v: Vec<String>, extra: &[&str]| {
        let mut v = v;
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let run = |v: Vec<String>, want: &str| {
        let a: Vec<&str> = v.iter().map(|x| x.as_str()).collect();
        fails(&a, want, &out)
    };
    run(
        fit_out(&q),
        "dataset 0 (\"level 1 up\") states no level: give gamma=VALUE (m/s^2)",
    );
    run(
        args(fit_out(&q), &["--level-gamma", "0.5,1"]),
        "--level-gamma gives 2 level(s) but the file holds 4 FRF dataset(s)",
    );
    run(
        args(fit_out(&p), &["--velocity"]),
        "--velocity applies to CSV data",
    );
    run(
        args(fit_out(&csv), &["--level-gamma", "1"]),
        "--level-gamma gives the levels of a universal file",
    );
    let mut timed = stepped_sine_uff(&rows, 0, true);
    timed[1].header.abscissa_axis = AxisInfo::new(17, "Time", "s");
    let t = dir.path().join("time.uff");
    write_binary_file(&t, &timed).unwrap();
    run(
        fit_out(&t),
        "dataset 1 (\"level 2 up\"): the abscissa is time",
    );
    let mut forced = stepped_sine_uff(&rows, 2, true);
    forced[0].header.denominator_axis = AxisInfo::new(13, "Force", "N");
    let f = dir.path().join("force.uff");
    write_binary_file(&f, &forced).unwrap();
    run(fit_out(&f), "the ordinate denominator (record 10) is force (N): fit needs the response per input (base) acceleration");
    let mut g_units = stepped_sine_uff(&rows, 2, true);
    g_units[0].header.ordinate_axis = AxisInfo::new(12, "Acceleration", "g");
    let g = dir.path().join("g.uff");
    write_binary_file(&g, &g_units).unwrap();
    run(fit_out(&g), "units 'g' are not SI");
    // a file of time responses only
    let th = dir.path().join("th.uff");
    write_ascii_file(
        &th,
        &[Uff58Dataset::time_response(0.0, 0.01, vec![1.0, 2.0])],
    )
    .unwrap();
    run(fit_out(&th), "no complex FRF or transmissibility (function type 4 or 5) among the datasets (0: time response, real 'NONE')");
}

#[test]
fn frf_uff_reads_back_as_its_csv() {
    let dir = tempfile::tempdir().unwrap();
    let model = example("duffing-strong.toml");
    let uff = dir.path().join("curves.uff");
    let common_args = [
        "frf",
        "--model",
        s(&model),
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
    ];
    let csv = ok(&[&common_args[..], &["--csv"]].concat());
    let text = ok(&[&common_args[..], &["--uff", s(&uff)]].concat());
    assert!(text.contains("universal file written to"), "{text}");
    let rows = frf_rows(&csv);
    let back = read(&uff).unwrap();
    assert_eq!(back.len(), 3);
    for (i, f) in back.iter().enumerate() {
        let h = &f.dataset.header;
        let level = (i + 1).to_string();
        let mut pts: Vec<_> = rows.iter().filter(|r| r.0 == level).collect();
        pts.sort_by(|a, b| a.2.total_cmp(&b.2)); // the file holds increasing frequencies
        let gamma = pts[0].1;
        assert_eq!(h.function_type, 4);
        assert_eq!(h.id2, format!("gamma={gamma} sweep=down level={level}"));
        assert_eq!(
            (
                h.ordinate_axis.specific_data_type,
                h.ordinate_axis.units.as_str()
            ),
            (8, "m")
        );
        assert_eq!(
            (
                h.denominator_axis.specific_data_type,
                h.denominator_axis.units.as_str()
            ),
            (12, "m/s^2")
        );
        assert_eq!(h.z_axis_value, gamma);
        let x = f.dataset.abscissa_values();
        let Uff58Data::Complex(v) = &f.dataset.data else {
            panic!("complex")
        };
        assert_eq!(v.len(), pts.len());
        for ((r, &fx), &(re, im)) in pts.iter().zip(&x).zip(v) {
            // E13.5 abscissa: 7 significant digits; E20.12 values: 5e-13
            assert!((fx - r.2).abs() <= 5e-7 * r.2, "{fx} vs {}", r.2);
            let a = re.hypot(im) * gamma;
            assert!((a - r.3).abs() <= 1e-12 * r.3, "{a} vs {}", r.3);
            let phase = (-im.atan2(re)).to_degrees();
            assert!((phase - r.4).abs() <= 1e-9, "{phase} vs {}", r.4);
        }
    }
    // and fit reads it (levels and sweeps from the tokens)
    let v = json(&["fit", s(&uff), "--model", "duffing", "--json"]);
    assert_eq!(
        v["levels"].as_array().map(|l| l.len()),
        Some(3),
        "{}",
        v["levels"]
    );
    // refused before anything is written
    fails(
        &[
            &common_args[..],
            &[
                "--harmonics",
                "2",
                "--uff",
                s(&uff.with_file_name("h2.uff")),
            ],
        ]
        .concat(),
        "--uff writes first-order curves",
        &uff.with_file_name("h2.uff"),
    );
}

#[test]
fn simulate_writes_uff_time_responses() {
    let dir = tempfile::tempdir().unwrap();
    let chirp = dir.path().join("chirp.csv");
    ok(&[
        "signal",
        "chirp",
        "--amplitude",
        "0.25",
        "--f0",
        "4.5",
        "--f1",
        "6",
        "--duration",
        "4",
        "--fs",
        "1000",
        "--out",
        s(&chirp),
    ]);
    let model = example("har-wing.toml");
    let csv = dir.path().join("r.csv");
    let uff = dir.path().join("r.uff");
    let base = [
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&chirp),
        "--decimate",
        "2",
    ];
    ok(&[&base[..], &["--out", s(&csv)]].concat());
    ok(&[&base[..], &["--out", s(&uff)]].concat());
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let back = read(&uff).unwrap();
    let names: Vec<&str> = back.iter().map(|f| f.dataset.header.id1.as_str()).collect();
    assert_eq!(names, ["accel", "x", "v"]);
    let units: Vec<&str> = back
        .iter()
        .map(|f| f.dataset.header.ordinate_axis.units.as_str())
        .collect();
    assert_eq!(units, ["m/s^2", "m", "m/s"]);
    for (c, f) in back.iter().enumerate() {
        assert_eq!(f.dataset.header.function_type, 1);
        let Abscissa::Even { start, step } = f.dataset.abscissa else {
            panic!("even")
        };
        assert_eq!((start, step), (0.0, 0.002));
        let Uff58Data::Real(v) = &f.dataset.data else {
            panic!("real")
        };
        assert_eq!(v.len(), rows.len());
        for (k, (r, &y)) in rows.iter().zip(v).enumerate() {
            assert!((r[0] - k as f64 * 0.002).abs() < 1e-12);
            assert!(
                (y - r[c + 1]).abs() <= 5e-13 * r[c + 1].abs(),
                "{c} {k}: {y} vs {}",
                r[c + 1]
            );
        }
    }
    // simulate reads the written acceleration back as its input (--var by ID line)
    let again = dir.path().join("again.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&uff),
        "--var",
        "accel",
        "--out",
        s(&again),
    ]);
    // a complex function is not an input signal
    let frf = dir.path().join("frf.uff");
    write_ascii_file(&frf, &[sdof_frf()]).unwrap();
    let out = dir.path().join("none.uff");
    fails(
        &[
            "simulate",
            "--model",
            s(&model),
            "--input",
            s(&frf),
            "--out",
            s(&out),
        ],
        "is complex",
        &out,
    );
}
