//! Issue 28, items 2 and 3: one reader layer for every verb (CSV, LabVIEW
//! .lvm, Polytec ASCII, MAT v5, universal files, told apart by content),
//! binary files named and never echoed, and hints for likely unit and
//! format mistakes on the first line.

mod common;

use common::{example, fails_one_line, json, nlsdof, ok, write};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// A LabVIEW measurement file as LabVIEW writes it (two header blocks,
/// tab separated, CRLF, a trailing empty Comment column): X_Value from 0 at
/// `fs`, and the named channels.
fn lvm(dir: &Path, name: &str, fs: f64, channels: &[(&str, &[f64])]) -> PathBuf {
    let mut s = String::from("LabVIEW Measurement\t\r\nWriter_Version\t2\r\nReader_Version\t2\r\nSeparator\tTab\r\nDecimal_Separator\t.\r\nMulti_Headings\tNo\r\nX_Columns\tOne\r\n***End_of_Header***\t\r\n\t\r\n");
    write!(s, "Channels\t{}\t\r\n", channels.len()).unwrap();
    write!(s, "Delta_X\t{}\t\r\n", 1.0 / fs).unwrap();
    s.push_str("***End_of_Header***\t\t\t\r\nX_Value");
    for (n, _) in channels {
        write!(s, "\t{n}").unwrap();
    }
    s.push_str("\tComment\r\n");
    for k in 0..channels[0].1.len() {
        write!(s, "{:.6}", k as f64 / fs).unwrap();
        for (_, v) in channels {
            write!(s, "\t{:e}", v[k]).unwrap();
        }
        s.push_str("\t\r\n");
    }
    write(dir, name, &s)
}

/// The one stderr line of a failing run, checked to hold no byte that is
/// not printable text.
fn clean_error(args: &[&str]) -> String {
    let out = nlsdof().args(args).output().unwrap();
    assert!(
        !out.stderr
            .iter()
            .any(|&b| b == 0 || (b < 0x20 && b != b'\n')),
        "control bytes in stderr: {:?}",
        out.stderr
    );
    fails_one_line(args)
}

#[test]
fn lvm_is_read_by_every_time_history_verb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fs = 200.0;
    let n = 2000;
    let u: Vec<f64> = (0..n)
        .map(|k| 0.4 * (TWO_PI * 5.3 * k as f64 / fs).sin())
        .collect();
    let y: Vec<f64> = (0..n)
        .map(|k| 1e-3 * (TWO_PI * 5.3 * k as f64 / fs).cos())
        .collect();
    let f = lvm(d, "rec.lvm", fs, &[("Voltage", &u), ("Strain_0", &y)]);
    let fp = f.to_str().unwrap();
    // spectrogram: was "no column named Strain_0 (columns: labview measurement)"
    let v = json(&[
        "spectrogram",
        "--input",
        fp,
        "--column",
        "Strain_0",
        "--json",
    ]);
    assert!((v["fs_hz"].as_f64().unwrap() - fs).abs() < 1e-9, "{v}");
    assert_eq!(v["samples"].as_u64(), Some(n as u64), "{v}");
    // simulate: was "line 2: Writer_Version is not a number"
    let sim = d.join("sim.csv");
    let sp = sim.to_str().unwrap();
    ok(&[
        "simulate",
        "--model",
        example("har-wing.toml").to_str().unwrap(),
        "--input",
        fp,
        "--var",
        "Voltage",
        "--out",
        sp,
    ]);
    let text = std::fs::read_to_string(&sim).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows.len(), n + 1);
    // the LVM's X_Value sets the time: sample 10 at 10/fs, accel = u[10]
    let r10: Vec<f64> = rows[11].split(',').map(|x| x.parse().unwrap()).collect();
    assert!((r10[0] - 10.0 / fs).abs() < 1e-12, "{}", rows[11]);
    assert!((r10[1] - u[10]).abs() <= 1e-6 * u[10].abs(), "{}", rows[11]);
    // frf-estimate: was "line 2: Writer_Version is not a number"
    let h = d.join("h.csv");
    let v = json(&[
        "frf-estimate",
        "--input",
        fp,
        "--input-channel",
        "Voltage",
        "--output-channel",
        "Strain_0",
        "--out",
        h.to_str().unwrap(),
        "--json",
    ]);
    assert!(h.exists(), "{v}");
    // by channel number from 1 (the columns after X_Value)
    let h2 = d.join("h2.csv");
    ok(&[
        "frf-estimate",
        "--input",
        fp,
        "--input-channel",
        "1",
        "--output-channel",
        "2",
        "--out",
        h2.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read_to_string(&h).unwrap(),
        std::fs::read_to_string(&h2).unwrap()
    );
    // fit-time: X_Value is the time column without --fs / --time-column
    let x: Vec<f64> = rows[1..]
        .iter()
        .map(|r| r.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    let g = lvm(d, "io.lvm", fs, &[("Voltage", &u), ("x", &x)]);
    let v = json(&[
        "fit-time",
        "--input",
        g.to_str().unwrap(),
        "--input-column",
        "Voltage",
        "--output-column",
        "x",
        "--model",
        "linear",
        "--json",
    ]);
    assert!((v["fs_hz"].as_f64().unwrap() - fs).abs() < 1e-9, "{v}");
}

/// Minimal MAT v5 file: uncompressed real double column vectors.
fn mat(dir: &Path, name: &str, vars: &[(&str, &[f64])]) -> PathBuf {
    fn pad(b: &mut Vec<u8>) {
        while b.len() % 8 != 0 {
            b.push(0);
        }
    }
    fn tag(b: &mut Vec<u8>, ty: u32, len: usize) {
        b.extend_from_slice(&ty.to_le_bytes());
        b.extend_from_slice(&(len as u32).to_le_bytes());
    }
    let mut out = vec![b' '; 116];
    out[..19].copy_from_slice(b"MATLAB 5.0 MAT-file");
    out.extend_from_slice(&[0u8; 8]);
    out.extend_from_slice(&0x0100u16.to_le_bytes());
    out.extend_from_slice(b"IM");
    for (n, data) in vars {
        let mut el = vec![];
        tag(&mut el, 6, 8);
        el.extend_from_slice(&6u32.to_le_bytes());
        el.extend_from_slice(&0u32.to_le_bytes());
        tag(&mut el, 5, 8);
        el.extend_from_slice(&(data.len() as i32).to_le_bytes());
        el.extend_from_slice(&1i32.to_le_bytes());
        tag(&mut el, 1, n.len());
        el.extend_from_slice(n.as_bytes());
        pad(&mut el);
        tag(&mut el, 9, 8 * data.len());
        for v in data.iter() {
            el.extend_from_slice(&v.to_le_bytes());
        }
        pad(&mut el);
        tag(&mut out, 14, el.len());
        out.extend_from_slice(&el);
    }
    let p = dir.join(name);
    std::fs::write(&p, out).unwrap();
    p
}

#[test]
fn mat_files_are_read_by_variable_name_and_never_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fs = 500.0;
    let t: Vec<f64> = (0..5000).map(|k| k as f64 / fs).collect();
    let x: Vec<f64> = t
        .iter()
        .map(|t| (-0.8 * t).exp() * (TWO_PI * 20.0 * t).cos())
        .collect();
    let m = mat(d, "decay.mat", &[("t", &t), ("x", &x)]);
    let mp = m.to_str().unwrap();
    // read (the time vector t gives fs), not refused
    let v = json(&["decay", "--input", mp, "--column", "x", "--json"]);
    assert!((v["fs_hz"].as_f64().unwrap() - fs).abs() < 1e-9, "{v}");
    // an unknown variable: one clean line naming the format and the fix
    let e = clean_error(&["decay", "--input", mp, "--column", "V2", "--fs", "500"]);
    assert!(e.contains("MAT-file") && e.contains("--column"), "{e}");
    assert!(
        e.contains("x[") && e.contains("t["),
        "lists the variables: {e}"
    );
    // the same content under a .csv name is still a MAT-file
    let c = d.join("decay.csv");
    std::fs::copy(&m, &c).unwrap();
    let v = json(&[
        "decay",
        "--input",
        c.to_str().unwrap(),
        "--column",
        "x",
        "--json",
    ]);
    assert!((v["fs_hz"].as_f64().unwrap() - fs).abs() < 1e-9, "{v}");
    // the Silverbox file of the issue (when the shared data are present)
    let sb =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/silverbox/SNLS80mV.mat");
    if sb.exists() {
        let e = clean_error(&["decay", "--input", sb.to_str().unwrap(), "--column", "V2"]);
        assert!(e.len() < 300 && e.contains("--fs"), "{e}");
    }
}

#[test]
fn binary_files_are_named_by_every_verb_and_never_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut gz = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 3];
    gz.extend((0..2000u32).map(|i| (i * 7919 % 251) as u8));
    let f = d.join("rec.csv");
    std::fs::write(&f, &gz).unwrap();
    let fp = f.to_str().unwrap();
    let model = example("har-wing.toml");
    let mp = model.to_str().unwrap();
    let out = d.join("o.csv");
    let op = out.to_str().unwrap();
    for args in [
        vec!["decay", "--input", fp, "--column", "x"],
        vec!["spectrogram", "--input", fp, "--column", "x"],
        vec!["spectrogram", "--input", fp, "--fs", "100"],
        vec!["simulate", "--model", mp, "--input", fp, "--out", op],
        vec!["frf-estimate", "--input", fp, "--out", op],
        vec![
            "fit-time",
            "--input",
            fp,
            "--input-column",
            "u",
            "--output-column",
            "y",
            "--fs",
            "10",
        ],
        vec!["fit", fp, "--model", "duffing"],
        vec!["inspect", fp],
        vec!["linear-id", fp],
    ] {
        let e = clean_error(&args);
        assert!(e.contains("gzip"), "{args:?}: {e}");
        assert!(e.len() < 400, "{args:?}: {e}");
        assert!(!out.exists());
    }
}

/// A stepped-sine table as a European spreadsheet saves it: semicolons,
/// decimal commas, a Latin-1 comment.
#[test]
fn semicolon_decimal_comma_and_latin1_tables_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ss = d.join("ss.csv");
    ok(&[
        "stepped-sine",
        "--model",
        example("har-wing.toml").to_str().unwrap(),
        "--gamma",
        "0.41,0.82",
        "--f-min",
        "5",
        "--f-max",
        "6",
        "--steps",
        "12",
        "--out",
        ss.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&ss).unwrap();
    let mut euro: Vec<u8> = b"# Pr\xfcfstand, Amplitude in m\n".to_vec();
    euro.extend(text.replace(',', ";").replace('.', ",").bytes());
    let e = d.join("euro.csv");
    std::fs::write(&e, &euro).unwrap();
    let strip = |mut v: serde_json::Value| {
        let m = v.as_object_mut().unwrap();
        m.remove("source");
        m.remove("inspect_s");
        v
    };
    let a = strip(json(&["inspect", ss.to_str().unwrap(), "--json"]));
    let b = strip(json(&["inspect", e.to_str().unwrap(), "--json"]));
    assert_eq!(a, b);
    // a separator that is not read: the missing column names it first
    let bar = write(d, "bar.csv", &text.replace(',', "|"));
    let err = clean_error(&["inspect", bar.to_str().unwrap()]);
    assert!(
        err.contains("missing column 'level'") && err.contains("bars"),
        "{err}"
    );
}

/// Amplitudes in mm: the first line says so, and does not call the levels
/// g (the free gain stops at its bound 10, within 3 % of 9.81).
#[test]
fn amplitudes_in_mm_are_named_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ss = d.join("ss.csv");
    ok(&[
        "stepped-sine",
        "--model",
        example("har-wing.toml").to_str().unwrap(),
        "--gamma",
        "0.41,0.82,1.23",
        "--f-min",
        "5",
        "--f-max",
        "6.5",
        "--steps",
        "25",
        "--out",
        ss.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&ss).unwrap();
    let mut mm = String::new();
    for (k, line) in text.lines().enumerate() {
        if k == 0 {
            mm.push_str(line);
        } else {
            let mut f: Vec<String> = line.split(',').map(str::to_string).collect();
            f[3] = format!("{:e}", f[3].parse::<f64>().unwrap() * 1000.0);
            mm.push_str(&f.join(","));
        }
        mm.push('\n');
    }
    let p = write(d, "mm.csv", &mm);
    let out = nlsdof()
        .args(["fit", p.to_str().unwrap(), "--model", "generalised"])
        .output()
        .unwrap();
    let all =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    // the report's first line (stdout) is the hint
    let first = String::from_utf8_lossy(&out.stdout)
        .lines()
        .next()
        .unwrap_or("")
        .to_string();
    assert!(
        first.starts_with("HINT") && first.contains("in mm"),
        "{all}"
    );
    assert!(!all.contains("in g;"), "{all}");
}
