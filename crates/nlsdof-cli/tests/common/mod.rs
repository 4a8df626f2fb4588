//! Helpers shared by the end-to-end tests of the `nlsdof` binary: running
//! it, reading its JSON, and the error contract every verb follows (exit
//! code 2, exactly one stderr line `nlsdof: error: ...`, nothing on stdout,
//! no output file or temporary left behind).
#![allow(dead_code)] // each test binary uses a different subset

use assert_cmd::Command;
use serde_json::Value;
use std::path::{Path, PathBuf};

pub fn nlsdof() -> Command {
    Command::new(env!("CARGO_BIN_EXE_nlsdof"))
}

/// A file of the repository's `examples/` folder.
pub fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// A beam set of `../shared/data/clamped-beam-duffing-catarinaluz` beside
/// the repository; `None` (and a SKIPPED line) when the shared data are
/// absent.
pub fn beam_dir(set: &str) -> Option<PathBuf> {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/clamped-beam-duffing-catarinaluz")
        .join(set);
    if d.is_dir() {
        Some(d)
    } else {
        eprintln!("SKIPPED: beam data directory {} is absent", d.display());
        None
    }
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs a command that must succeed; returns stdout.
pub fn ok(args: &[&str]) -> String {
    let out = nlsdof().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "nlsdof {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must succeed and print JSON; returns it parsed.
pub fn json(args: &[&str]) -> Value {
    let text = ok(args);
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"))
}

/// Runs a command that must fail: exit code 2, exactly one stderr line
/// starting `nlsdof: error: `, nothing on stdout. Returns the stderr line.
pub fn fails_one_line(args: &[&str]) -> String {
    let out = nlsdof().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "nlsdof {args:?}: expected exit 2, got {:?}; stderr: {err}",
        out.status.code()
    );
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "nlsdof {args:?}: expected one stderr line, got: {err}"
    );
    assert!(err.starts_with("nlsdof: error: "), "{err}");
    assert!(
        out.stdout.is_empty(),
        "nlsdof {args:?}: stdout not empty: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    err
}

fn listing(dir: &Path) -> Vec<std::ffi::OsString> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    v.sort();
    v
}

/// [`fails_one_line`], the line mentions `want`, and nothing was written:
/// `out` is the output folder, or the output file (which must not exist
/// afterwards); its folder holds the same files afterwards as before (no
/// output, no temporary).
pub fn fails(args: &[&str], want: &str, out: &Path) -> String {
    let dir = if out.is_dir() {
        out
    } else {
        out.parent().unwrap()
    };
    let before = listing(dir);
    let err = fails_one_line(args);
    assert!(
        err.contains(want),
        "nlsdof {args:?}: stderr {err:?} does not mention {want:?}"
    );
    if !out.is_dir() {
        assert!(!out.exists(), "output file {} was written", out.display());
    }
    assert_eq!(before, listing(dir), "nlsdof {args:?}: files left behind");
    err
}
