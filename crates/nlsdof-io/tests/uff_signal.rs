//! Universal files as recorded signals (`read_signal`: `simulate --input`,
//! `spectrogram`): a time response written by the UFF writer reads back as
//! the signal it holds, with its sampling from record 7; complex functions,
//! an ambiguous choice and a contradicting `--fs` are refused by name.

use nlsdof_io::signal_file::{read_signal, SignalGrid};
use nlsdof_io::uff58::{write_ascii_file, Uff58Dataset};
use std::path::Path;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/uff58")
        .join(name)
}

#[test]
fn a_time_response_reads_as_its_signal() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("accel.uff");
    // values of at most 12 significant digits: exact through ASCII 58
    let values: Vec<f64> = (0..500)
        .map(|k| ((k as f64 * 0.37).sin() * 1e6).round() / 1e6)
        .collect();
    let mut ds = Uff58Dataset::time_response(0.5, 1.0 / 1024.0, values.clone());
    ds.header.id1 = "base acceleration".into();
    write_ascii_file(&path, &[ds]).unwrap();
    let s = read_signal(&path, None, None).unwrap();
    assert_eq!(s.values, values);
    match s.grid {
        SignalGrid::Uniform { t0, fs } => {
            assert_eq!(t0, 0.5);
            assert!((fs - 1024.0).abs() < 1e-9, "{fs}");
        }
        g => panic!("{g:?}"),
    }
    // chosen by index or by ID-line text: the same signal
    assert_eq!(read_signal(&path, None, Some("0")).unwrap(), s);
    assert_eq!(read_signal(&path, None, Some("base accel")).unwrap(), s);
    // --fs contradicts the file's sampling
    let e = read_signal(&path, Some(100.0), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--fs 100"), "{e}");
    let e = read_signal(&path, None, Some("7")).unwrap_err().to_string();
    assert!(
        e.contains("no dataset matches '7'") && e.contains("0: time response"),
        "{e}"
    );
}

#[test]
fn the_oracle_time_files_read_as_signals() {
    for name in [
        "ascii_double_real_even_time.uff",
        "binary_double_real_even_time.uff",
    ] {
        let s = read_signal(&data(name), None, None).unwrap();
        assert!(s.len() > 2, "{name}");
        assert!(matches!(s.grid, SignalGrid::Uniform { .. }), "{name}");
    }
}

#[test]
fn complex_functions_are_not_signals() {
    let e = read_signal(&data("ascii_double_complex_even_frf.uff"), None, Some("0"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("dataset 0 is complex"), "{e}");
}
