//! The table of input classes in docs/reliability.md: every class below is
//! run against the `nlsdof` binary, its outcome is classified (clean error:
//! exit 2, one stderr line `nlsdof: error: ...` naming the problem, nothing
//! on stdout, no file written or left behind, no number longer than 17
//! characters; or success with the expected output), and the generated
//! markdown table must equal the one in the document. Regenerate the
//! document's table with `NLSDOF_BLESS=1 cargo test --release -p nlsdof-cli
//! --test reliability_table`.

mod common;
use common::example;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// How a class is run and what it must do.
#[derive(Clone, Copy)]
enum Want {
    /// Clean error whose line contains the text.
    Error(&'static str),
    /// Success; stdout contains the text.
    Ok(&'static str),
    /// Success writing nothing to stdout checked.
    OkQuiet,
}

/// Standard output of the run.
#[derive(Clone, Copy, PartialEq)]
enum Out {
    Captured,
    DevFull,
    /// Reader closes the pipe at once (like `| head -0`).
    ClosedPipe,
}

struct Class {
    item: &'static str,
    class: &'static str,
    /// Arguments; `{d}` is the scratch folder, `{ex}` the examples folder.
    args: &'static str,
    out: Out,
    want: Want,
}

const FRF: &str =
    "frf --model {ex}/duffing-strong.toml --gamma 0.5,1 --f-min 8 --f-max 12 --steps 40";

fn classes() -> Vec<Class> {
    use Out::*;
    use Want::*;
    let c = |item, class, args, out, want| Class {
        item,
        class,
        args,
        out,
        want,
    };
    vec![
        c("1", "device node as output (`--plot /dev/null`)", "{FRF} --plot /dev/null", Captured, OkQuiet),
        c("1", "full device as output (`--plot /dev/full`)", "{FRF} --plot /dev/full", Captured, Error("No space left")),
        c("1", "FIFO as output", "{FRF} --plot {d}/fifo", Captured, Error("is a FIFO")),
        c("2", "directory as `frf --plot`", "{FRF} --plot {d}/DIR", Captured, Error("is a directory")),
        c("2", "directory as `signal --out`", "signal sine --out {d}/DIR --freq 5 --amplitude 1 --fs 100 --duration 1", Captured, Error("is a directory")),
        c("2", "directory as `spectrogram --csv`", "spectrogram --input {d}/sig.csv --csv {d}/DIR", Captured, Error("is a directory")),
        c("2", "directory as `frf-estimate --out`", "frf-estimate --input {d}/th_ok.csv --input-channel force --output-channel vel --out {d}/DIR", Captured, Error("is a directory")),
        c("2", "output folder missing", "{FRF} --plot {d}/nowhere/p.svg", Captured, Error("No such file")),
        c("3", "`stepped-sine --out o.csv --details o.csv`", "stepped-sine --model {ex}/duffing-strong.toml --gamma 1 --f-min 8 --f-max 12 --steps 3 --out {d}/o.csv --details {d}/o.csv", Captured, Error("two outputs")),
        c("3", "`fit --out f.svg --plot f.svg`", "fit {d}/data.csv --model duffing --starts 2 --out {d}/f.svg --plot {d}/f.svg", Captured, Error("two outputs")),
        c("3", "`fit --out f.toml --plot DIR`", "fit {d}/data.csv --model duffing --starts 2 --out {d}/f.toml --plot {d}/DIR", Captured, Error("is a directory")),
        c("3", "`linear-id --out l.toml --plot DIR` (existing l.toml kept)", "linear-id {d}/frf.csv --out {d}/l.toml --plot {d}/DIR", Captured, Error("is a directory")),
        c("4", "closed pipe on stdout (the reader exits at once)", "frf --model {ex}/duffing-strong.toml --gamma 0.5,1,2 --f-min 8 --f-max 12 --steps 20000 --csv --plot {d}/p.svg", ClosedPipe, OkQuiet),
        c("4", "stdout on /dev/full", "{FRF} --csv --plot {d}/p.svg", DevFull, Error("No space left")),
        c("5", "`stepped-sine --steps 1000000000`", "stepped-sine --model {ex}/duffing-strong.toml --gamma 1 --f-min 8 --f-max 12 --steps 1000000000 --out {d}/o.csv", Captured, Error("need 2 to 1000000")),
        c("5", "`stepped-sine --samples-per-cycle 1000000000`", "stepped-sine --model {ex}/duffing-strong.toml --gamma 1 --f-min 8 --f-max 12 --steps 3 --samples-per-cycle 1000000000 --out {d}/o.csv", Captured, Error("must be <= 100000")),
        c("5", "`signal stepped-sine --steps 1000000000 --dwell-cycles 1`", "signal stepped-sine --out {d}/o.csv --amplitude 1 --fs 100 --f-min 1 --f-max 2 --steps 1000000000 --dwell-cycles 1", Captured, Error("need 2 to 1000000")),
        c("5", "`spectrogram --nfft 100000000000`", "spectrogram --input {d}/sig.csv --nfft 100000000000", Captured, Error("at most 16777216")),
        c("5", "MAT file inflating to 300 MB", "simulate --model {ex}/duffing-strong.toml --input {d}/bomb.mat --fs 100 --out {d}/o.csv", Captured, Error("inflates to more than 268435456")),
        c("6", "`roots` with k_r = 1e300", "roots --model {d}/kr.toml --gamma 1 --f-hz 10 --json", Captured, Ok("1.1006424162982074e-100")),
        c("6", "`frf-estimate` with an all-zero input channel", "frf-estimate --input {d}/th.csv --input-channel force --output-channel vel --out {d}/h.csv", Captured, Error("no power")),
        c("6", "undamped linear model at exact resonance", "frf --model {d}/und.toml --gamma 1 --f-min 9 --f-max 11 --steps 3 --json", Captured, Ok("\"sticking\":false,\"unbounded\":true")),
        c("7", "UTF-8 byte-order mark in fit data", "fit {d}/bom.csv --model duffing --starts 2", Captured, Ok("alpha")),
        c("7", "UTF-8 byte-order mark in an FRF CSV (`linear-id`)", "linear-id {d}/bomfrf.csv", Captured, Ok("f_n")),
        c("7", "truncated MAT file", "simulate --model {ex}/duffing-strong.toml --input {d}/cut.mat --fs 100 --out {d}/o.csv", Captured, Error("truncated or corrupt")),
        c("7", "MAT v7.3 (HDF5) file", "simulate --model {ex}/duffing-strong.toml --input {d}/v73.mat --fs 100 --out {d}/o.csv", Captured, Error("MAT v7.3 (HDF5)")),
        c("7", "MAT v4 file", "simulate --model {ex}/duffing-strong.toml --input {d}/v4.mat --fs 100 --out {d}/o.csv", Captured, Error("MAT v4")),
        c("8", "`roots --gamma 1e308`", "roots --model {ex}/duffing-strong.toml --gamma 1e308 --f-hz 12.5", Captured, Error("overflow")),
        c("8", "`stepped-sine --f-min -1e300`", "stepped-sine --model {ex}/duffing-strong.toml --gamma 1 --f-min -1e300 --f-max 1 --steps 3 --out {d}/o.csv", Captured, Error("-1e300")),
        c("9", "`fit --frequency-weight NaN` without `--phase-resonance`", "fit {d}/data.csv --model duffing --frequency-weight NaN", Captured, Error("--phase-resonance")),
        c("9", "`linear-id --max-iterations 0`", "linear-id {d}/frf.csv --max-iterations 0", Captured, Error("--max-iterations 0")),
        c("9", "data row with an extra field", "fit {d}/extra.csv --model duffing --starts 2", Captured, Error("7 fields")),
        c("9", "`frf --plot p.pdf`", "{FRF} --plot {d}/p.pdf", Captured, Error("file name ending in .svg or .png")),
        c("-", "missing input file", "fit {d}/absent.csv --model duffing", Captured, Error("cannot read")),
        c("-", "model with mass = nan", "roots --model {d}/nanmass.toml --gamma 1 --f-hz 10", Captured, Error("mass")),
        c("-", "empty signal CSV", "spectrogram --input {d}/empty.csv --fs 100", Captured, Error("no samples")),
        c("-", "non-numeric field in fit data", "fit {d}/word.csv --model duffing", Captured, Error("is not a number")),
    ]
}

// ----------------------------------------------------------------- setup

fn w(d: &Path, name: &str, bytes: impl AsRef<[u8]>) {
    std::fs::write(d.join(name), bytes).unwrap();
}

fn mat_header() -> Vec<u8> {
    let mut out = vec![b' '; 116];
    out[..20].copy_from_slice(b"MATLAB 5.0 MAT-file,");
    out.extend([0u8; 8]);
    out.extend(0x0100u16.to_le_bytes());
    out.extend(*b"IM");
    out
}

fn setup(d: &Path) {
    std::fs::create_dir(d.join("DIR")).unwrap();
    let _ = Command::new("mkfifo").arg(d.join("fifo")).status();
    let frf = common::ok(&[
        "frf",
        "--model",
        example("duffing-strong.toml").to_str().unwrap(),
        "--gamma",
        "0.5,1",
        "--f-min",
        "8",
        "--f-max",
        "12",
        "--steps",
        "15",
        "--csv",
    ]);
    let data: String = frf
        .lines()
        .map(|l| l.split(',').take(6).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    w(d, "data.csv", &data);
    w(d, "bom.csv", format!("\u{feff}{data}"));
    w(d, "extra.csv", data.replacen(",up\n", ",up,7\n", 1));
    w(
        d,
        "word.csv",
        data.replacen(",up\n", ",up\n1,0.5,8.5,abc,3,up\n", 1),
    );
    let (wn, z) = (2.0 * std::f64::consts::PI * 10.0, 0.02);
    let mut t = String::from("f_hz,re,im\n");
    for i in 0..300 {
        let f = 6.0 + 8.0 * i as f64 / 299.0;
        let om = 2.0 * std::f64::consts::PI * f;
        let (re, im) = (wn * wn - om * om, 2.0 * z * wn * om);
        let n = re * re + im * im;
        t += &format!("{f:?},{:?},{:?}\n", re / n, -im / n);
    }
    w(d, "frf.csv", &t);
    w(d, "bomfrf.csv", format!("\u{feff}{t}"));
    w(d, "l.toml", "# the user's file\n");
    let mut th = String::from("t,force,vel\n");
    for k in 0..8192 {
        let tk = k as f64 / 1000.0;
        th += &format!(
            "{tk},0,{}\n",
            (2.0 * std::f64::consts::PI * 37.0 * tk).sin()
        );
    }
    w(d, "th.csv", &th);
    let mut th = String::from("t,force,vel\n");
    for k in 0..8192 {
        let tk = k as f64 / 1000.0;
        let u = (2.0 * std::f64::consts::PI * 37.0 * tk).sin();
        th += &format!("{tk},{u},{}\n", 0.5 * u);
    }
    w(d, "th_ok.csv", &th);
    let mut sig = String::from("t,accel\n");
    for k in 0..800 {
        let tk = k as f64 / 200.0;
        sig += &format!("{tk},{}\n", (2.0 * std::f64::consts::PI * 5.0 * tk).sin());
    }
    w(d, "sig.csv", &sig);
    w(d, "empty.csv", "");
    w(d, "kr.toml", "mass = 1\nstiffness = 3947.84\ndamping = 1.2566\n[nonlinear_stiffness]\ncoefficient = 1e300\nexponent = 2\n");
    w(
        d,
        "und.toml",
        "mass = 1\nstiffness = 3947.8417604357433\ndamping = 0\n",
    );
    w(
        d,
        "nanmass.toml",
        "mass = nan\nstiffness = 3947.84\ndamping = 1.2566\n",
    );
    // MAT files
    {
        use std::io::Write;
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..300 {
            z.write_all(&zeros).unwrap();
        }
        let c = z.finish().unwrap();
        let mut f = mat_header();
        f.extend(15u32.to_le_bytes());
        f.extend((c.len() as u32).to_le_bytes());
        f.extend(c);
        w(d, "bomb.mat", f);
    }
    {
        let x: Vec<f64> = (0..200).map(|k| (k as f64 * 0.1).sin()).collect();
        let mut p = Vec::new();
        for v in [6u32, 8, 6, 0, 5, 8] {
            p.extend(v.to_le_bytes());
        }
        p.extend(200i32.to_le_bytes());
        p.extend(1i32.to_le_bytes());
        p.extend(((5u32) << 16 | 1).to_le_bytes());
        p.extend(b"accel\0\0\0");
        p.extend(9u32.to_le_bytes());
        p.extend(1600u32.to_le_bytes());
        for v in &x {
            p.extend(v.to_le_bytes());
        }
        let mut f = mat_header();
        f.extend(14u32.to_le_bytes());
        f.extend((p.len() as u32).to_le_bytes());
        f.extend(&p);
        w(d, "cut.mat", &f[..f.len() / 2]);
        let mut h5 = vec![b' '; 512];
        h5[..19].copy_from_slice(b"MATLAB 7.3 MAT-file");
        h5.extend(b"\x89HDF\r\n\x1a\n");
        w(d, "v73.mat", h5);
        let mut v4 = Vec::new();
        for v in [0u32, 200, 1, 0, 6] {
            v4.extend(v.to_le_bytes());
        }
        v4.extend(b"accel\0");
        for v in &x {
            v4.extend(v.to_le_bytes());
        }
        w(d, "v4.mat", v4);
    }
}

// ------------------------------------------------------------------- run

fn listing(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut v = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(p) = stack.pop() {
        for e in std::fs::read_dir(&p).unwrap() {
            let e = e.unwrap();
            let ft = e.file_type().unwrap();
            if ft.is_dir() {
                stack.push(e.path());
                v.push((e.path(), Vec::new()));
            } else if ft.is_file() {
                v.push((e.path(), std::fs::read(e.path()).unwrap()));
            } else {
                v.push((e.path(), b"special".to_vec()));
            }
        }
    }
    v.sort();
    v
}

fn longest_number(s: &str) -> usize {
    s.split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// Runs one class; returns its outcome as a table cell.
fn outcome(c: &Class, d: &Path) -> String {
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let line = c
        .args
        .replace("{FRF}", FRF)
        .replace("{d}", d.to_str().unwrap())
        .replace("{ex}", ex.to_str().unwrap());
    let args: Vec<&str> = line.split_whitespace().collect();
    let before = listing(d);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_nlsdof"));
    cmd.args(&args).current_dir(d).stderr(Stdio::piped());
    let (code, stdout, stderr) = match c.out {
        Out::Captured => {
            let o = cmd.stdout(Stdio::piped()).output().unwrap();
            (o.status.code(), o.stdout, o.stderr)
        }
        Out::DevFull => {
            let full = std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap();
            let o = cmd.stdout(full).output().unwrap();
            (o.status.code(), Vec::new(), o.stderr)
        }
        Out::ClosedPipe => {
            let mut child = cmd.stdout(Stdio::piped()).spawn().unwrap();
            drop(child.stdout.take());
            let o = child.wait_with_output().unwrap();
            (o.status.code(), Vec::new(), o.stderr)
        }
    };
    let after = listing(d);
    let stderr = String::from_utf8_lossy(&stderr).into_owned();
    let stdout = String::from_utf8_lossy(&stdout).into_owned();
    let unchanged = before == after;
    let mut problems = Vec::new();
    let cell = match c.want {
        Want::Error(want) => {
            if code != Some(2) {
                problems.push(format!("exit {code:?}"));
            }
            if stderr.trim_end().lines().count() != 1 || !stderr.starts_with("nlsdof: error: ") {
                problems.push("not one `nlsdof: error:` line".into());
            }
            if !stderr.contains(want) {
                problems.push(format!("message lacks `{want}`"));
            }
            if !stdout.is_empty() {
                problems.push("stdout not empty".into());
            }
            if !unchanged {
                problems.push("files changed".into());
            }
            if longest_number(&stderr) > 17 {
                problems.push("long number".into());
            }
            format!("clean error: “…{want}…”")
        }
        Want::Ok(want) => {
            if code != Some(0) {
                problems.push(format!("exit {code:?}: {}", stderr.trim()));
            }
            if !stdout.contains(want) {
                problems.push(format!("output lacks `{want}`"));
            }
            format!("ok: prints `{want}`")
        }
        Want::OkQuiet => {
            let quiet_exit = matches!(code, Some(0) | Some(141));
            if !quiet_exit {
                problems.push(format!("exit {code:?}"));
            }
            if !stderr.is_empty() {
                problems.push(format!("stderr: {}", stderr.trim()));
            }
            if c.out == Out::ClosedPipe {
                if !unchanged {
                    problems.push("files changed".into());
                }
                "quiet end (exit 141), no file".to_string()
            } else {
                "ok (written through, device kept)".to_string()
            }
        }
    };
    if problems.is_empty() {
        cell
    } else {
        format!("FAILED: {}", problems.join("; "))
    }
}

const START: &str =
    "<!-- reliability-table:start (generated by crates/nlsdof-cli/tests/reliability_table.rs) -->";
const END: &str = "<!-- reliability-table:end -->";

#[cfg(target_os = "linux")]
#[test]
fn reliability_table_matches_docs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    let mut table = String::from("| item | input class | command | outcome |\n|---|---|---|---|\n");
    for c in classes() {
        let out = outcome(&c, d);
        let shown = c
            .args
            .replace("{FRF}", "frf … ")
            .replace("{d}/", "")
            .replace("{ex}/", "");
        let shown = shown.replace("frf …  ", "frf … ");
        let shown = if shown.len() > 90 {
            format!(
                "{}…",
                &shown[..shown
                    .char_indices()
                    .take_while(|(i, _)| *i < 88)
                    .last()
                    .map(|(i, c)| i + c.len_utf8())
                    .unwrap_or(0)]
            )
        } else {
            shown
        };
        let redirect = match c.out {
            Out::Captured => "",
            Out::DevFull => " > /dev/full",
            Out::ClosedPipe => " \\| head -0",
        };
        table += &format!(
            "| {} | {} | `{}{}` | {} |\n",
            c.item,
            c.class,
            shown.trim(),
            redirect,
            out
        );
    }
    let doc_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/reliability.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap_or_default();
    let (head, tail) = match (doc.find(START), doc.find(END)) {
        (Some(a), Some(b)) if b > a => (doc[..a].to_string(), doc[b + END.len()..].to_string()),
        _ => (doc.clone(), String::from("\n")),
    };
    let generated = format!("{head}{START}\n{table}{END}{tail}");
    if std::env::var_os("NLSDOF_BLESS").is_some() {
        std::fs::write(&doc_path, &generated).unwrap();
        return;
    }
    assert!(!table.contains("FAILED"), "some classes failed:\n{table}");
    assert_eq!(
        doc, generated,
        "docs/reliability.md is out of date; regenerate with NLSDOF_BLESS=1 (table:\n{table})"
    );
}
