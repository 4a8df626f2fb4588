//! Peak memory of `decay` and `fit-time` on long records (issue 30, class
//! 10: on 1e7 rows `decay` peaked at 2.1 GB and `fit-time` at 850 MB, more
//! than three times the numbers read). The peak is the child's `VmHWM`
//! (Linux), polled from `/proc` while it runs: the high-water mark only
//! grows, so the last reading misses at most the final 2 ms.
#![cfg(target_os = "linux")]

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

const BIN: &str = env!("CARGO_BIN_EXE_nlsdof");
const MB: u64 = 1_000_000;

/// A free decay `time,accel` of `rows` samples at 10 kHz: 37 Hz, falling
/// by e^-5 over the record (as the 1e7-row probe).
fn write_decay(path: &Path, rows: usize) {
    let fs = 10_000.0;
    let rate = 5.0 / (rows as f64 / fs);
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(w, "time,accel").unwrap();
    for k in 0..rows {
        let t = k as f64 / fs;
        let x = (-rate * t).exp() * (2.0 * std::f64::consts::PI * 37.0 * t).sin();
        writeln!(w, "{t:.6},{x:.9e}").unwrap();
    }
    w.flush().unwrap();
}

/// Runs `nlsdof args` to the end: its peak resident memory in bytes, after
/// checking that it succeeded.
fn peak_memory(args: &[&str]) -> u64 {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let mut peak_kb = 0u64;
    let exit = loop {
        // a zombie's status has no VmHWM line: then the last reading stands
        if let Ok(s) = std::fs::read_to_string(&status) {
            let hwm = s
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok());
            peak_kb = peak_kb.max(hwm.unwrap_or(0));
        }
        if let Some(exit) = child.try_wait().unwrap() {
            break exit;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert!(exit.success(), "nlsdof {args:?}: {exit}: {err}");
    assert!(peak_kb > 0, "no VmHWM read for nlsdof {args:?}");
    peak_kb * 1024
}

/// `decay` and `fit-time` on `rows` rows: the peaks, and the numeric data
/// (two columns of f64).
fn peaks(rows: usize) -> (u64, u64, u64) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("decay.csv");
    write_decay(&input, rows);
    let input = input.to_str().unwrap();
    let decay = peak_memory(&["decay", "--input", input, "--column", "accel", "--json"]);
    // a short fit: the reading path is what is measured
    let fit_time = peak_memory(&[
        "fit-time",
        "--input",
        input,
        "--input-column",
        "time",
        "--output-column",
        "accel",
        "--fs",
        "10000",
        "--range",
        "0:2000",
        "--model",
        "linear",
        "--max-iterations",
        "1",
        "--json",
    ]);
    (decay, fit_time, rows as u64 * 2 * 8)
}

/// 1e6 rows (16 MB of numbers), a few seconds in release mode. `decay`'s
/// analytic signal has a working set that does not grow with the record:
/// at 10 kHz and a 37 Hz mode one FFT of 2^21 points (buffer, scratch,
/// forward and inverse twiddles: 4 x 2^21 x 16 bytes = 134 MB); that and
/// the program itself (about 10 MB) are allowed on top of 3x the data.
/// Measured: decay 223 MB before the fix, 177 MB after; fit-time 51 MB
/// before (the whole file, then the columns), 25 MB after.
#[test]
fn decay_and_fit_time_memory_stays_near_the_data_1e6_rows() {
    let (decay, fit_time, data) = peaks(1_000_000);
    let fixed = 4 * (1 << 21) * 16 + 26 * MB;
    assert!(
        decay <= 3 * data + fixed,
        "decay peaked at {} MB for {} MB of data",
        decay / MB,
        data / MB
    );
    assert!(
        fit_time <= 2 * data + 4 * MB,
        "fit-time peaked at {} MB for {} MB of data",
        fit_time / MB,
        data / MB
    );
}

/// The probe, 1e7 rows (160 MB of numbers, a 240 MB file): at most
/// about 3x the data, 500 MB (before the fix: 2,237 MB and 411 MB; after:
/// 462 MB and 169 MB).
/// Ignored by default (about 20 s in release mode): run with
/// `cargo test --release -p nlsdof-cli --test memory_cli -- --ignored`.
#[test]
#[ignore = "1e7 rows: about 20 s"]
fn decay_and_fit_time_memory_stays_near_the_data_1e7_rows() {
    let (decay, fit_time, data) = peaks(10_000_000);
    assert!(
        decay <= 500 * MB,
        "decay peaked at {} MB for {} MB of data",
        decay / MB,
        data / MB
    );
    assert!(
        fit_time <= 2 * data,
        "fit-time peaked at {} MB for {} MB of data",
        fit_time / MB,
        data / MB
    );
}
