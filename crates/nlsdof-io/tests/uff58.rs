//! Universal File Format dataset 58 / 58b (`nlsdof_io::uff58`).
//!
//! * Oracle: every file of `tests/data/uff58` (written by pyuff 2.5.8, or
//!   by `generate.py` where pyuff cannot write the variant) is read and
//!   compared, header field by header field and value by value (bit for
//!   bit), with what pyuff reads (`FILE.json`).
//! * Round trips: binary 58b bit-exact; ASCII exact for values of up to 12
//!   significant digits, within 5e-13 otherwise, and a second write gives
//!   the same text.
//! * pyuff reads what we write: `NLSDOF_PYUFF_PYTHON=/path/to/python` (with
//!   pyuff 2.5.8 and numpy) runs `check_with_pyuff.py` on files written
//!   here; without it that test only says it was skipped.
//! * Errors, limits, lenient forms of real files.
//! * Fuzz: random bytes and mutated valid files (bit flips, truncations,
//!   changed counts and fields, spliced lines); no input may panic or make
//!   the parser allocate beyond a limit (a counting allocator aborts the
//!   run). `fuzz_ci` runs `NLSDOF_FUZZ_CASES` inputs (default 10,000, fixed
//!   seed); `fuzz_million` (ignored) runs 1,000,000:
//!   `cargo test --release -p nlsdof-io --test uff58 fuzz_million -- --ignored --nocapture`.

use nlsdof_io::uff58::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use serde_json::{Map, Value};
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

// ------------------------------------------------------------ allocator

/// No test input may make the parser hold more than this.
const MEMORY_LIMIT: usize = 512 << 20;
static CURRENT: AtomicUsize = AtomicUsize::new(0);

struct Counting;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        if now > MEMORY_LIMIT {
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut(); // aborts: "memory allocation of N bytes failed"
        }
        let p = System.alloc(layout);
        if p.is_null() {
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > layout.size() {
            let grow = new_size - layout.size();
            let now = CURRENT.fetch_add(grow, Ordering::Relaxed) + grow;
            if now > MEMORY_LIMIT {
                CURRENT.fetch_sub(grow, Ordering::Relaxed);
                return std::ptr::null_mut();
            }
            let p = System.realloc(ptr, layout, new_size);
            if p.is_null() {
                CURRENT.fetch_sub(grow, Ordering::Relaxed);
            }
            p
        } else {
            let p = System.realloc(ptr, layout, new_size);
            if !p.is_null() {
                CURRENT.fetch_sub(layout.size() - new_size, Ordering::Relaxed);
            }
            p
        }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

// ------------------------------------------------------------ helpers

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/uff58")
}

fn oracle_files() -> Vec<String> {
    let list = std::fs::read_to_string(data_dir().join("files.txt")).unwrap();
    let files: Vec<String> = list.lines().map(str::to_string).collect();
    assert!(files.len() >= 19, "{files:?}");
    files
}

fn json_of(name: &str) -> Value {
    let text = std::fs::read_to_string(data_dir().join(format!("{name}.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// A float as the JSON files hold it: the shortest round-trip decimal.
fn fv(v: f64) -> Value {
    Value::String(format!("{v:?}"))
}

fn parse_f(v: &Value) -> f64 {
    v.as_str()
        .and_then(|s| s.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("not a float string: {v}"))
}

/// Keys whose values are floats (compared bit for bit).
const FLOAT_KEYS: [&str; 5] = ["abscissa_min", "abscissa_inc", "z_axis_value", "x", "data"];

/// A function read here as pyuff 2.5.8's dict of it: the same keys, the
/// same value forms (floats as shortest round-trip strings).
fn pyuff_dict(f: &Uff58Function) -> Map<String, Value> {
    let (i, d, h) = (&f.info, &f.dataset, &f.dataset.header);
    let mut m = Map::new();
    let mut put = |k: &str, v: Value| {
        m.insert(k.to_string(), v);
    };
    put("type", 58.into());
    match i.encoding {
        Encoding::Ascii => put("binary", 0.into()),
        Encoding::Binary {
            big_endian,
            declared_bytes,
        } => {
            put("binary", 1.into());
            put("byte_ordering", (if big_endian { 2 } else { 1 }).into());
            put("fp_format", 2.into());
            put("n_ascii_lines", 11.into());
            put("n_bytes", declared_bytes.into());
        }
    }
    for (k, id) in [&h.id1, &h.id2, &h.id3, &h.id4, &h.id5].iter().enumerate() {
        put(&format!("id{}", k + 1), id.as_str().into());
    }
    put("func_type", h.function_type.into());
    put("func_id", h.function_id.into());
    put("ver_num", h.version.into());
    put("load_case_id", h.load_case.into());
    put("rsp_ent_name", h.response_entity.as_str().into());
    put("rsp_node", h.response_node.into());
    put("rsp_dir", h.response_direction.into());
    put("ref_ent_name", h.reference_entity.as_str().into());
    put("ref_node", h.reference_node.into());
    put("ref_dir", h.reference_direction.into());
    put("ord_data_type", i.ordinate_type.into());
    put("num_pts", i.points.into());
    put("abscissa_spacing", i.abscissa_spacing.into());
    put("abscissa_min", fv(i.abscissa_min));
    put("abscissa_inc", fv(i.abscissa_increment));
    put("z_axis_value", fv(h.z_axis_value));
    for (name, a) in [
        ("abscissa", &h.abscissa_axis),
        ("ordinate", &h.ordinate_axis),
        ("orddenom", &h.denominator_axis),
        ("z_axis", &h.z_axis),
    ] {
        put(
            &format!("{name}_spec_data_type"),
            a.specific_data_type.into(),
        );
        put(&format!("{name}_len_unit_exp"), a.length_exponent.into());
        put(&format!("{name}_force_unit_exp"), a.force_exponent.into());
        put(
            &format!("{name}_temp_unit_exp"),
            a.temperature_exponent.into(),
        );
        put(&format!("{name}_axis_lab"), a.label.as_str().into());
        put(&format!("{name}_axis_units_lab"), a.units.as_str().into());
    }
    put(
        "x",
        Value::Array(d.abscissa_values().into_iter().map(fv).collect()),
    );
    put(
        "data",
        match &d.data {
            Uff58Data::Real(y) => Value::Array(y.iter().map(|&v| fv(v)).collect()),
            Uff58Data::Complex(y) => Value::Array(
                y.iter()
                    .map(|&(re, im)| Value::Array(vec![fv(re), fv(im)]))
                    .collect(),
            ),
        },
    );
    m
}

fn same_floats(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Array(a), Value::Array(b)) => {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same_floats(x, y))
        }
        _ => parse_f(a).to_bits() == parse_f(b).to_bits(),
    }
}

/// Every key of pyuff's dict `want` is in `have` with the same value
/// (floats bit for bit), and `have` has no other key.
fn assert_same_dict(want: &Map<String, Value>, have: &Map<String, Value>, what: &str) {
    for (k, w) in want {
        let h = have
            .get(k)
            .unwrap_or_else(|| panic!("{what}: pyuff has {k}, not read here"));
        let ok = if FLOAT_KEYS.contains(&k.as_str()) {
            same_floats(w, h)
        } else {
            w == h
        };
        assert!(ok, "{what}: {k}: pyuff {w}, here {h}");
    }
    for k in have.keys() {
        assert!(want.contains_key(k), "{what}: {k} read here, not by pyuff");
    }
}

fn pth() -> &'static Path {
    Path::new("test.uff")
}

fn header_fields_equal(a: &Uff58Header, b: &Uff58Header) -> bool {
    a == b
}

// ------------------------------------------------------------ oracle

#[test]
fn every_oracle_file_reads_as_pyuff_reads_it() {
    let mut functions = 0;
    for name in oracle_files() {
        let doc = json_of(&name);
        assert_eq!(doc["pyuff"], "2.5.8");
        let path = data_dir().join(&name);
        let read = read(&path).unwrap_or_else(|e| panic!("{e}"));
        let sets = doc["sets"].as_array().unwrap();
        let ours: Vec<&Value> = sets.iter().filter(|s| s["type"] == 58).collect();
        assert_eq!(read.len(), ours.len(), "{name}");
        let mut k = 0;
        for (block, s) in sets.iter().enumerate() {
            if s["type"] != 58 {
                continue;
            }
            let f = &read[k];
            assert_eq!(f.info.index, k, "{name}");
            assert_eq!(f.info.block, block, "{name}: pyuff set number");
            let want = s.as_object().unwrap();
            assert_same_dict(want, &pyuff_dict(f), &format!("{name} set {block}"));
            k += 1;
            functions += 1;
        }
        // the set numbers of the other datasets
        let types: Vec<i64> = doc["set_types"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap())
            .collect();
        assert_eq!(types.len(), sets.len());
    }
    assert_eq!(functions, 23);
}

#[test]
fn headers_only_match_the_full_read() {
    for name in oracle_files() {
        let path = data_dir().join(&name);
        let full = read(&path).unwrap();
        let heads = read_headers(&path).unwrap();
        assert_eq!(full.len(), heads.len());
        for (f, h) in full.iter().zip(&heads) {
            assert_eq!(f.info, h.info, "{name}");
            assert!(header_fields_equal(&f.dataset.header, &h.header), "{name}");
        }
    }
}

#[test]
fn single_precision_values_are_as_stored() {
    for name in oracle_files() {
        let path = data_dir().join(&name);
        for f in read(&path).unwrap() {
            if f.info.precision != Precision::Single {
                continue;
            }
            let vals: Vec<f64> = match &f.dataset.data {
                Uff58Data::Real(y) => y.clone(),
                Uff58Data::Complex(y) => y.iter().flat_map(|&(a, b)| [a, b]).collect(),
            };
            match f.info.encoding {
                // binary: exact f32 values
                Encoding::Binary { .. } => {
                    for v in vals {
                        assert_eq!(v, v as f32 as f64, "{name}");
                    }
                }
                // ASCII: the decimal of the E13.5 field (6 digits), as pyuff
                Encoding::Ascii => {
                    for v in vals {
                        let s = format!("{v:.5e}");
                        assert_eq!(s.parse::<f64>().unwrap(), v, "{name}");
                    }
                }
            }
        }
    }
}

#[test]
fn functions_are_selected_by_index_and_header_fields() {
    let path = data_dir().join("multi.uff");
    let all = read(&path).unwrap();
    assert_eq!(all.len(), 5);
    let blocks: Vec<usize> = all.iter().map(|f| f.info.block).collect();
    assert_eq!(blocks, [2, 3, 4, 6, 7]);
    let sel = |s: Uff58Select| -> Vec<usize> {
        read_selected(&path, &s)
            .unwrap()
            .iter()
            .map(|f| f.info.index)
            .collect()
    };
    assert_eq!(
        sel(Uff58Select {
            index: Some(2),
            ..Default::default()
        }),
        [2]
    );
    assert_eq!(
        sel(Uff58Select {
            function_type: Some(4),
            ..Default::default()
        }),
        [1, 2]
    );
    assert_eq!(
        sel(Uff58Select {
            response_node: Some(2),
            response_direction: Some(3),
            ..Default::default()
        }),
        [1, 3]
    );
    assert_eq!(
        sel(Uff58Select {
            function_type: Some(4),
            reference_node: Some(1),
            reference_direction: Some(3),
            id1_contains: Some("3+Y".into()),
            ..Default::default()
        }),
        [2]
    );
    assert!(sel(Uff58Select {
        index: Some(9),
        ..Default::default()
    })
    .is_empty());
    let one = read_selected(
        &path,
        &Uff58Select {
            index: Some(2),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(one[0], all[2]);
    assert_eq!(
        all[2].dataset.header.function_type_name(),
        "frequency response function"
    );
    assert_eq!(function_type_name(5), "transmissibility");
    assert_eq!(specific_data_type_name(18), "frequency");

    // the data of a function not selected are not parsed
    let mut text = std::fs::read(&path).unwrap();
    let bad = b"  1.00000000000e+00";
    let at = text
        .windows(bad.len())
        .rposition(|w| w.ends_with(b"e+00") || w.ends_with(b"e-01"))
        .unwrap();
    text[at + 3] = b'x'; // in the last function (auto spectrum, uneven)
    assert!(parse(&text, &path).is_err());
    let s = Uff58Select {
        function_type: Some(4),
        ..Default::default()
    };
    assert_eq!(parse_selected(&text, &path, &s).unwrap().len(), 2);
    assert_eq!(parse_headers(&text, &path).unwrap().len(), 5);
}

// ------------------------------------------------------------ round trips

fn datasets_of(name: &str) -> Vec<Uff58Dataset> {
    read(&data_dir().join(name))
        .unwrap()
        .into_iter()
        .map(|f| f.dataset)
        .collect()
}

fn numbers(d: &Uff58Dataset) -> Vec<f64> {
    let mut v = match &d.abscissa {
        Abscissa::Even { start, step } => vec![*start, *step],
        Abscissa::Uneven(x) => x.clone(),
    };
    match &d.data {
        Uff58Data::Real(y) => v.extend(y),
        Uff58Data::Complex(y) => v.extend(y.iter().flat_map(|&(a, b)| [a, b])),
    }
    v
}

#[test]
fn oracle_functions_written_again_read_back_identically() {
    for name in oracle_files() {
        let ds = datasets_of(&name);
        // binary: bit for bit, header and all
        let bytes = write_binary(&ds).unwrap();
        let back: Vec<Uff58Dataset> = parse(&bytes, pth())
            .unwrap()
            .into_iter()
            .map(|f| f.dataset)
            .collect();
        assert_eq!(back.len(), ds.len());
        for (a, b) in ds.iter().zip(&back) {
            assert_eq!(a.header, b.header, "{name}");
            let (na, nb) = (numbers(a), numbers(b));
            assert_eq!(na.len(), nb.len());
            for (x, y) in na.iter().zip(&nb) {
                assert_eq!(x.to_bits(), y.to_bits(), "{name}");
            }
        }
        // ASCII: exact for what ASCII files held (at most 12 digits) and
        // the abscissa (E13.5 from pyuff), close for binary doubles
        let text = write_ascii(&ds).unwrap();
        let back = parse(text.as_bytes(), pth()).unwrap();
        for (a, b) in ds.iter().zip(&back) {
            let b = &b.dataset;
            assert_eq!(a.header, b.header, "{name}");
            assert_eq!(
                std::mem::discriminant(&a.abscissa),
                std::mem::discriminant(&b.abscissa)
            );
            let n_abscissa = match &a.abscissa {
                Abscissa::Even { .. } => 2,
                Abscissa::Uneven(_) => a.len(),
            };
            for (k, (x, y)) in numbers(a).iter().zip(&numbers(b)).enumerate() {
                if name.starts_with("ascii") || name.starts_with("crlf") {
                    assert_eq!(x.to_bits(), y.to_bits(), "{name}: {x} {y}");
                } else {
                    check_close(*x, *y, k < n_abscissa).unwrap();
                }
            }
        }
        // writing what was read gives the same text
        let again: Vec<Uff58Dataset> = back.into_iter().map(|f| f.dataset).collect();
        assert_eq!(write_ascii(&again).unwrap(), text, "{name}");
    }
}

/// Significant digits of the shortest decimal of `x`.
fn digits(x: f64) -> usize {
    let s = format!("{x:e}");
    let m = s.split('e').next().unwrap_or("");
    m.trim_start_matches('-')
        .chars()
        .filter(char::is_ascii_digit)
        .count()
}

/// `y` as read back from the ASCII field of `x`: exact when `x` has at
/// most 12 significant digits (5 in a 13-column field), else within the
/// digits that fit.
fn check_close(x: f64, y: f64, narrow: bool) -> Result<(), String> {
    let exact = if narrow { 5 } else { 12 };
    if digits(x) <= exact || x == y {
        return if x.to_bits() == y.to_bits() {
            Ok(())
        } else {
            Err(format!("{x:e} written inexactly: {y:e}"))
        };
    }
    let big = x.abs() >= 1e99 || x.abs() < 1e-99;
    let tol = match (narrow, big) {
        (false, false) => 5e-13,
        // next to f64::MAX the digits are cut, not rounded: twice the error
        (false, true) => 1e-11,
        (true, false) => 5e-6,
        (true, true) => 1e-4,
    };
    if (x - y).abs() <= tol * x.abs() || (x.abs() < 1e-300 && y.abs() < 1e-300) {
        Ok(())
    } else {
        Err(format!("{x:e} read back as {y:e} (tolerance {tol})"))
    }
}

fn finite() -> impl Strategy<Value = f64> {
    prop_oneof![
        any::<f64>().prop_filter("finite", |v| v.is_finite()),
        -1e3f64..1e3,
        Just(0.0),
        Just(-0.0),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(f64::MAX),
        Just(-f64::MAX),
        Just(0.1),
        Just(1.0 / 3.0),
    ]
}

fn dataset() -> impl Strategy<Value = Uff58Dataset> {
    (
        proptest::collection::vec((finite(), finite(), finite()), 0..40),
        any::<bool>(),
        any::<bool>(),
        (finite(), finite(), finite()),
        (
            0i32..28,
            -99999i64..99999,
            -6i32..=6,
            "[ -~]{0,10}",
            "[A-Za-z /^()0-9]{0,20}",
        ),
    )
        .prop_map(
            |(pts, complex, uneven, (start, step, z), (ft, node, dir, ent, units))| {
                let mut h = Uff58Header {
                    id1: format!("random {ft} {node}"),
                    function_type: ft,
                    response_node: node,
                    response_direction: dir,
                    reference_node: -node,
                    reference_direction: -dir,
                    response_entity: ent.trim().to_string(),
                    z_axis_value: z,
                    ..Uff58Header::default()
                };
                h.ordinate_axis.units = units.trim().to_string();
                if h.response_entity.is_empty() {
                    h.response_entity = "NONE".into();
                }
                if h.ordinate_axis.units.is_empty() {
                    h.ordinate_axis.units = "NONE".into();
                }
                let abscissa = if uneven {
                    Abscissa::Uneven(pts.iter().map(|p| p.0).collect())
                } else {
                    Abscissa::Even { start, step }
                };
                let data = if complex {
                    Uff58Data::Complex(pts.iter().map(|p| (p.1, p.2)).collect())
                } else {
                    Uff58Data::Real(pts.iter().map(|p| p.1).collect())
                };
                Uff58Dataset {
                    header: h,
                    abscissa,
                    data,
                }
            },
        )
}

fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        rng_algorithm: RngAlgorithm::ChaCha,
        ..Config::default()
    };
    TestRunner::new_with_rng(
        config,
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

#[test]
fn random_functions_round_trip() {
    runner(300, 1)
        .run(&proptest::collection::vec(dataset(), 1..4), |ds| {
            // binary: bit-exact data; record 7 keeps the abscissa in 13 columns
            let back = parse(&write_binary(&ds).unwrap(), pth()).unwrap();
            prop_assert_eq!(back.len(), ds.len());
            for (a, f) in ds.iter().zip(&back) {
                let b = &f.dataset;
                prop_assert_eq!(&a.header.id1, &b.header.id1);
                prop_assert_eq!(a.header.response_node, b.header.response_node);
                prop_assert_eq!(&a.header.response_entity, &b.header.response_entity);
                prop_assert_eq!(&a.header.ordinate_axis, &b.header.ordinate_axis);
                prop_assert_eq!(a.len(), b.len());
                let (na, nb) = (numbers(a), numbers(b));
                let skip = if matches!(a.abscissa, Abscissa::Even { .. }) {
                    2
                } else {
                    0
                };
                for (x, y) in na.iter().zip(&nb).skip(skip) {
                    prop_assert_eq!(x.to_bits(), y.to_bits());
                }
            }
            // ASCII: within the digits that fit, then stable
            let text = write_ascii(&ds).unwrap();
            let back = parse(text.as_bytes(), pth()).unwrap();
            for (a, f) in ds.iter().zip(&back) {
                let b = &f.dataset;
                prop_assert_eq!(a.header.function_type, b.header.function_type);
                let n_abscissa = match &a.abscissa {
                    Abscissa::Even { .. } => 2,
                    Abscissa::Uneven(_) => a.len(),
                };
                for (k, (x, y)) in numbers(a).iter().zip(&numbers(b)).enumerate() {
                    // record 7 and an uneven abscissa: 13 columns
                    if let Err(m) = check_close(*x, *y, k < n_abscissa) {
                        prop_assert!(false, "{}", m);
                    }
                }
            }
            let again: Vec<Uff58Dataset> = back.into_iter().map(|f| f.dataset).collect();
            prop_assert_eq!(write_ascii(&again).unwrap(), text);
            Ok(())
        })
        .unwrap();
}

#[test]
fn simulated_time_history_and_model_frf_files() {
    let dir = tempfile::tempdir().unwrap();
    let fs = 3000.0;
    let x: Vec<f64> = (0..300)
        .map(|k| (2.0 * std::f64::consts::PI * 37.0 * k as f64 / fs).sin() * 1e-3)
        .collect();
    let mut t = Uff58Dataset::time_response(0.0, 1.0 / fs, x.clone());
    t.header.id1 = "nlsdof simulate: x(t)".into();
    t.header.response_node = 1;
    t.header.response_direction = 3;
    t.header.ordinate_axis = AxisInfo::new(8, "Displacement", "m");
    let f: Vec<f64> = (0..50).map(|k| 5.0 + 0.25 * k as f64).collect();
    let h: Vec<(f64, f64)> = f
        .iter()
        .map(|&f| {
            let w = 2.0 * std::f64::consts::PI * f;
            let (k, m, c) = (4.0e4, 1.0, 2.0);
            let den = (k - m * w * w, c * w);
            let n = den.0 * den.0 + den.1 * den.1;
            (den.0 / n, -den.1 / n)
        })
        .collect();
    let mut m = Uff58Dataset::frf(Abscissa::Uneven(f.clone()), h.clone());
    m.header.id1 = "model FRF".into();
    m.header.ordinate_axis = AxisInfo::new(8, "Displacement", "m");
    m.header.denominator_axis = AxisInfo::new(13, "Force", "N");
    let ds = vec![t, m];
    let a = dir.path().join("out.uff");
    let b = dir.path().join("out_b.uff");
    write_ascii_file(&a, &ds).unwrap();
    write_binary_file(&b, &ds).unwrap();
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        2,
        "no temporary left"
    );
    for p in [&a, &b] {
        let r = read(p).unwrap();
        assert_eq!(r.len(), 2);
        assert_eq!(r[0].dataset.header, ds[0].header);
        assert_eq!(r[1].dataset.header, ds[1].header);
        assert_eq!(r[1].dataset.abscissa, Abscissa::Uneven(f.clone()));
        let Uff58Data::Real(y) = &r[0].dataset.data else {
            panic!()
        };
        let Uff58Data::Complex(hh) = &r[1].dataset.data else {
            panic!()
        };
        let exact = p == &b;
        for (u, v) in y.iter().zip(&x) {
            assert!(if exact {
                u == v
            } else {
                (u - v).abs() <= 5e-13 * v.abs()
            });
        }
        for (u, v) in hh.iter().zip(&h) {
            assert!(if exact {
                u == v
            } else {
                (u.0 - v.0).abs() <= 5e-13 * v.0.abs() && (u.1 - v.1).abs() <= 5e-13 * v.1.abs()
            });
        }
        // 1/3000 s does not fit record 7's 13 columns: 7 digits kept
        let Abscissa::Even { start, step } = r[0].dataset.abscissa else {
            panic!()
        };
        assert_eq!(start, 0.0);
        assert!((step - 1.0 / fs).abs() < 1e-7 / fs);
    }
    let text = std::fs::read_to_string(&a).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "    -1");
    assert_eq!(lines[1], "    58");
    assert_eq!(lines[7].len(), 80, "record 6: {:?}", lines[7]);
    assert_eq!(&lines[8][..30], "         4       300         1");
    assert_eq!(lines[8].len(), 69);
    assert_eq!(
        lines[9],
        format!("{:10}{:5}{:5}{:5} {:<20} {:<20}", 17, 0, 0, 0, "Time", "s")
    );
    assert!(lines[13].len() == 80 && lines[13].split_whitespace().count() == 4);
    // a failed write leaves nothing: a dataset the writer refuses
    let mut bad = ds.clone();
    bad[1].header.ordinate_axis.units = "m/s²".into();
    let c = dir.path().join("bad.uff");
    let e = write_ascii_file(&c, &bad).unwrap_err().to_string();
    assert!(
        e.contains("not printable ASCII") && e.contains("m/s^2"),
        "{e}"
    );
    assert!(!c.exists());
}

#[test]
fn the_writer_refuses_what_the_format_cannot_hold() {
    let ok = Uff58Dataset::time_response(0.0, 1e-3, vec![1.0, 2.0]);
    assert!(write_ascii(std::slice::from_ref(&ok)).is_ok());
    type Edit = Box<dyn Fn(&mut Uff58Dataset)>;
    let cases: Vec<(Edit, &str)> = vec![
        (Box::new(|d| d.header.id1 = "x".repeat(81)), "ID line 1"),
        (
            Box::new(|d| d.header.response_entity = "ELEVENCHARS".into()),
            "response entity",
        ),
        (
            Box::new(|d| d.header.abscissa_axis.label = "µ".into()),
            "printable ASCII",
        ),
        (
            Box::new(|d| d.header.response_direction = 7),
            "response direction",
        ),
        (
            Box::new(|d| d.header.response_node = 10_000_000_000),
            "response node",
        ),
        (
            Box::new(|d| d.header.function_type = 100_000),
            "function type",
        ),
        (
            Box::new(|d| d.data = Uff58Data::Real(vec![1.0, f64::NAN])),
            "data value 1",
        ),
        (
            Box::new(|d| d.abscissa = Abscissa::Uneven(vec![1.0])),
            "uneven abscissa",
        ),
        (
            Box::new(|d| {
                d.abscissa = Abscissa::Even {
                    start: 0.0,
                    step: f64::INFINITY,
                }
            }),
            "finite",
        ),
        (Box::new(|d| d.header.z_axis_value = f64::NAN), "z-axis"),
    ];
    for (edit, want) in cases {
        let mut d = ok.clone();
        edit(&mut d);
        let e = write_ascii(&[ok.clone(), d.clone()])
            .unwrap_err()
            .to_string();
        assert!(e.contains("index 1") && e.contains(want), "{e}");
        assert!(write_binary(&[d]).is_err());
    }
}

// ------------------------------------------------------------ lenient forms

fn simple_ascii() -> String {
    let mut d = Uff58Dataset::frf(
        Abscissa::Even {
            start: 1.0,
            step: 0.5,
        },
        vec![(1.0, -2.0), (3.0, 4.0), (-5.5, 6.25)],
    );
    d.header.id1 = "FRF".into();
    write_ascii(&[d]).unwrap()
}

fn replace_line(text: &str, k: usize, new: &str) -> String {
    let mut l: Vec<String> = text.lines().map(str::to_string).collect();
    l[k] = new.to_string();
    l.join("\n") + "\n"
}

#[test]
fn forms_found_in_real_files_are_read() {
    let base = parse(simple_ascii().as_bytes(), pth()).unwrap();
    let want = &base[0].dataset;
    let same = |text: &str| {
        let r = parse(text.as_bytes(), pth()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(r.len(), 1);
        assert_eq!(&r[0].dataset, want, "{text}");
    };
    let t = simple_ascii();
    // CRLF; Fortran D exponents; blank-separated numbers of other widths
    same(&t.replace('\n', "\r\n"));
    same(&replace_line(&t, 13, "  1.0D+00 -2.0D+00  3.0D+00  4.0D0"));
    same(&replace_line(&t, 13, "1 -2 3 4"));
    same(&replace_line(
        &t,
        8,
        "         6         3         1   1.0000000000000E+00   5.0000000000000E-01   0.0E+00",
    ));
    // blank lines between datasets, a stray -1, a trailing -1
    same(&format!("\n{t}\n    -1\n"));
    same(&format!("    -1\n{t}"));
    // another dataset (2411, ASCII) before it; an unknown binary one
    same(&format!(
        "    -1\n  2411\n         1         0         0        11\n    -1\n{t}"
    ));
    let mut bin = b"    -1\n  2414b     1     2           1           5     0     0           0           0\nascii line\n\x00\x01\n-1".to_vec();
    bin.extend(b"\n    -1\n");
    bin.extend(t.as_bytes());
    let r = parse(&bin, pth()).unwrap();
    assert_eq!(r[0].info.block, 1);
    // touching E13.5 fields (3-digit exponents) in the columns of the format
    let mut d = Uff58Dataset::time_response(0.0, 1.0, vec![0.0; 6]);
    d.header.id1 = "single".into();
    let t6 = write_ascii(&[d]).unwrap();
    let t6 = replace_line(
        &t6,
        8,
        "         2         6         1  0.00000E+00  1.00000E+00  0.00000E+00",
    );
    let fields = [
        "-1.23456E+100",
        "-2.34567E-100",
        "3.00000E+00",
        "4.00000E+00",
        "5.00000E+00",
        "6.0000E+000",
    ];
    let line: String = fields.iter().map(|f| format!("{f:>13}")).collect();
    let t6 = replace_line(&t6, 13, &line);
    let t6 = replace_line(&t6, 14, "    -1");
    let t6: String = t6.lines().take(15).map(|l| format!("{l}\n")).collect();
    let r = parse(t6.as_bytes(), pth()).unwrap_or_else(|e| panic!("{e}\n{t6}"));
    assert_eq!(
        r[0].dataset.data,
        Uff58Data::Real(vec![-1.23456e100, -2.34567e-100, 3.0, 4.0, 5.0, 6.0])
    );
    assert_eq!(r[0].info.precision, Precision::Single);
    // a Latin-1 units label (not UTF-8)
    let mut latin = simple_ascii().into_bytes();
    let at = latin.windows(5).position(|w| w == b"Hz   ").unwrap();
    latin[at..at + 3].copy_from_slice(b"\xb5s ");
    let r = parse(&latin, pth()).unwrap();
    assert_eq!(r[0].dataset.header.abscissa_axis.units, "µs");
}

/// A 58b file, little or big endian, with an uneven double abscissa
/// stored as 4-byte floats (Addendum B's "the abscissa is always real
/// single precision"), told apart by its declared byte count.
#[test]
fn binary_layouts_told_apart_by_the_declared_count() {
    let x = [1.5f32, 2.25, 4.0];
    let y = [(0.1f64, -0.2f64), (1e-300, 3.0), (-7.0, 8.5)];
    for big in [false, true] {
        let mut d = Uff58Dataset::frf(
            Abscissa::Uneven(x.iter().map(|&v| v as f64).collect()),
            y.to_vec(),
        );
        d.header.id1 = "f32 abscissa".into();
        let text = write_ascii(&[d.clone()]).unwrap();
        let head: Vec<&str> = text.lines().skip(2).take(11).collect();
        let mut bytes = format!(
            "    -1\n    58b{:6}{:6}{:12}{:12}{:6}{:6}{:12}{:12}\n",
            if big { 2 } else { 1 },
            2,
            11,
            3 * 20,
            0,
            0,
            0,
            0
        )
        .into_bytes();
        for l in head {
            bytes.extend(l.as_bytes());
            bytes.push(b'\n');
        }
        for (xv, (re, im)) in x.iter().zip(&y) {
            if big {
                bytes.extend(xv.to_be_bytes());
                bytes.extend(re.to_be_bytes());
                bytes.extend(im.to_be_bytes());
            } else {
                bytes.extend(xv.to_le_bytes());
                bytes.extend(re.to_le_bytes());
                bytes.extend(im.to_le_bytes());
            }
        }
        bytes.extend(b"    -1\n");
        let r = parse(&bytes, pth()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r[0].dataset, d);
        assert_eq!(
            r[0].info.encoding,
            Encoding::Binary {
                big_endian: big,
                declared_bytes: 60
            }
        );
    }
}

// ------------------------------------------------------------ errors

fn err_of(bytes: &[u8]) -> String {
    let e = parse(bytes, pth()).expect_err("must fail");
    let s = e.to_string();
    assert!(
        !s.chars().any(|c| c.is_control()),
        "control characters in {s:?}"
    );
    // converts to the crate's error
    let _ = nlsdof_io::IoError::from(e);
    s
}

#[test]
fn errors_name_the_line_dataset_record_and_text() {
    let t = simple_ascii();
    let e = err_of(replace_line(&t, 13, " 1.0E+00 -2.0E+00 3.0E+00 4.0Q+00").as_bytes());
    assert!(
        e.contains("test.uff: line 14: dataset 58 index 0 (block 0), record 12 (data values): '4.0Q+00' is not a number"),
        "{e}"
    );
    let two = format!("{t}{}", t.replace("FRF", "second"));
    let e = err_of(replace_line(&two, 24, "    7").as_bytes());
    assert!(
        e.contains("line 25: dataset 58 index 1 (block 1), record 7 (data form)"),
        "{e}"
    );
    let e = err_of(replace_line(&t, 7, "    4   abc").as_bytes());
    assert!(
        e.contains("record 6") && e.contains("field 2") && e.contains("'abc'"),
        "{e}"
    );
    let e = err_of(
        replace_line(
            &t,
            8,
            "         3         3         1  1.00000E+00  5.00000E-01  0.00000E+00",
        )
        .as_bytes(),
    );
    assert!(
        e.contains("ordinate data type") && e.contains("magnitude-phase"),
        "{e}"
    );
    // truncated: in the header, in the data
    let e = err_of(&t.as_bytes()[..t.find("Frequency").unwrap()]);
    assert!(e.contains("record 9") && e.contains("ends before"), "{e}");
    let cut = t.len() - 12;
    let e = err_of(&t.as_bytes()[..cut]);
    assert!(e.contains("no closing"), "{e}");
    let without_last = replace_line(&t, 14, "    -1");
    let e = err_of(
        without_last
            .lines()
            .take(15)
            .collect::<Vec<_>>()
            .join("\n")
            .as_bytes(),
    );
    assert!(
        e.contains("record 12") && e.contains("4 numbers") && e.contains("(6)"),
        "{e}"
    );
    // not a universal file
    let e = err_of(b"t,accel\n0,1\n");
    assert!(
        e.contains("not a universal file") && e.contains("'t,accel'"),
        "{e}"
    );
    let e = err_of(&[0x1f, 0x8b, 8, 0, 0, 0]);
    assert!(e.contains("gzip"), "{e}");
    assert!(err_of(b"").contains("empty"));
    assert!(err_of(b"    -1\n\x00\x01garbage\x07\n").contains("not a dataset number"));
    // binary: DEC floats, byte order 3
    let b = write_binary(&datasets_of("ascii_double_real_even_time.uff")).unwrap();
    let s = String::from_utf8_lossy(&b[..100]).to_string();
    let dec = s.replacen("     1     2          11", "     1     1          11", 1);
    let mut bd = b.clone();
    bd[..100].copy_from_slice(&dec.as_bytes()[..100]);
    assert!(err_of(&bd).contains("DEC VMS"));
    let mut bo = b.clone();
    bo[..100].copy_from_slice(&s.replacen("     1     2", "     3     2", 1).as_bytes()[..100]);
    assert!(err_of(&bo).contains("byte ordering 3"));
    // binary truncated: no raw bytes in the message
    let e = err_of(&b[..b.len() - 30]);
    assert!(e.contains("only") && e.contains("remain"), "{e}");
    // bytes after the data where the -1 should be: escaped
    let mut junk = b[..b.len() - 7].to_vec();
    junk.extend(b"\x00\x1b[31m\xff\xfe-1\n");
    let e = err_of(&junk);
    assert!(e.contains("closing"), "{e}");
}

#[test]
fn absurd_point_counts_are_refused_before_allocating() {
    let t = simple_ascii();
    for n in ["2000000000", "9999999999"] {
        let line = format!("         6{n:>10}         1  1.00000E+00  5.00000E-01  0.00000E+00");
        let e = err_of(replace_line(&t, 8, &line).as_bytes());
        assert!(e.contains("cannot hold them"), "{e}");
        // headers only: fine, nothing allocated for the data
        let h = parse_headers(replace_line(&t, 8, &line).as_bytes(), pth()).unwrap();
        assert_eq!(h[0].info.points, n.parse::<usize>().unwrap());
    }
    let b = write_binary(&datasets_of("ascii_double_complex_even_frf.uff")).unwrap();
    let s = String::from_utf8_lossy(&b).to_string();
    let line7 = s.lines().nth(8).unwrap().to_string();
    let huge = format!("{}{:>10}{}", &line7[..10], "9999999999", &line7[20..]);
    let b2 = String::from_utf8_lossy(&b).replacen(&line7, &huge, 1);
    // (lossy text is fine here: the failure comes before the data)
    let e = err_of(b2.as_bytes());
    assert!(
        e.contains("9999999999 points") && e.contains("remain"),
        "{e}"
    );
}

/// A data line of 40 million numbers for 3 points: refused without holding
/// them (the counting allocator would abort past 512 MiB).
#[test]
fn an_endless_data_line_is_not_held() {
    let t = simple_ascii();
    let mut long = String::with_capacity(80 << 20);
    for _ in 0..40_000_000 {
        long.push_str("1 ");
    }
    let e = err_of(replace_line(&t, 13, &long).as_bytes());
    assert!(e.contains("more numbers than record 7 declares"), "{e}");
    let e = err_of(replace_line(&t, 8, &long).as_bytes());
    assert!(e.contains("record 7"), "{e}");
}

// ------------------------------------------------------------ pyuff reads ours

/// A function as the JSON sidecar that `check_with_pyuff.py` compares
/// with pyuff's reading.
fn expectation(fs: &[Uff58Function]) -> Value {
    Value::Array(fs.iter().map(|f| Value::Object(pyuff_dict(f))).collect())
}

fn files_for_pyuff(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut all: Vec<Uff58Dataset> = Vec::new();
    for name in [
        "ascii_double_real_even_time.uff",
        "binary_double_complex_even_frf.uff",
        "ascii_double_complex_uneven_frf.uff",
        "binary_single_real_even_time_le.uff",
        "binary_double_real_uneven_coherence_be_lf.uff",
    ] {
        all.extend(datasets_of(name));
    }
    let mut t = Uff58Dataset::time_response(
        0.0,
        1.0 / 3000.0,
        (0..37).map(|k| (k as f64 * 0.7).sin() / 3.0).collect(),
    );
    t.header.id1 = "nlsdof simulate".into();
    t.header.ordinate_axis = AxisInfo::new(12, "Acceleration", "m/s^2");
    all.push(t);
    for (k, d) in all.iter().enumerate() {
        for binary in [false, true] {
            let p = dir.join(format!("f{k}_{}.uff", if binary { "b" } else { "a" }));
            let ds = std::slice::from_ref(d);
            if binary {
                write_binary_file(&p, ds).unwrap();
            } else {
                write_ascii_file(&p, ds).unwrap();
            }
            out.push(p);
        }
    }
    let p = dir.join("multi_a.uff");
    write_ascii_file(&p, &all).unwrap();
    out.push(p);
    let p = dir.join("multi_b.uff");
    write_binary_file(&p, &all).unwrap();
    out.push(p);
    for p in &out {
        let fs = read(p).unwrap();
        let json = serde_json::to_string_pretty(&expectation(&fs)).unwrap();
        std::fs::write(format!("{}.json", p.display()), json).unwrap();
    }
    out
}

#[test]
fn pyuff_reads_our_files_as_we_do() {
    let Ok(python) = std::env::var("NLSDOF_PYUFF_PYTHON") else {
        eprintln!("skipped: set NLSDOF_PYUFF_PYTHON to a python with pyuff 2.5.8 and numpy");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let files = files_for_pyuff(dir.path());
    let out = std::process::Command::new(python)
        .arg(data_dir().join("check_with_pyuff.py"))
        .args(&files)
        .output()
        .unwrap();
    let msg = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    eprintln!("{msg}");
    assert!(out.status.success(), "{msg}");
    assert!(msg.contains(&format!("{} files", files.len())), "{msg}");
}

// ------------------------------------------------------------ fuzz

#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(prop::sample::Index, u8),
    Truncate(prop::sample::Index),
    Insert(prop::sample::Index, Vec<u8>),
    Delete(prop::sample::Index, usize),
    /// A number of a header line (record `line` of a dataset) replaced.
    Number(prop::sample::Index, prop::sample::Index, &'static str),
    DuplicateLine(prop::sample::Index),
    DeleteLine(prop::sample::Index),
}

const EDGE: [&str; 14] = [
    "0",
    "-1",
    "1",
    "2",
    "9999999999",
    "2147483648",
    "-999999999",
    "1e308",
    "NaN",
    "",
    "abc",
    "58b",
    "    -1",
    "12345678901234567890",
];
const INSERTS: [&[u8]; 8] = [
    b"\n    -1\n",
    b"\n    58b     1     2          11        9999     0     0           0           0\n",
    b"\0",
    b"\r",
    b"\xff\xfe",
    b"\n",
    b"  151\n",
    b"E+999",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<prop::sample::Index>(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        any::<prop::sample::Index>().prop_map(Mutation::Truncate),
        (
            any::<prop::sample::Index>(),
            prop_oneof![
                proptest::collection::vec(any::<u8>(), 1..16),
                proptest::sample::select(INSERTS.to_vec()).prop_map(|s| s.to_vec()),
            ]
        )
            .prop_map(|(i, v)| Mutation::Insert(i, v)),
        (any::<prop::sample::Index>(), 1usize..200).prop_map(|(i, n)| Mutation::Delete(i, n)),
        (
            any::<prop::sample::Index>(),
            any::<prop::sample::Index>(),
            proptest::sample::select(EDGE.to_vec())
        )
            .prop_map(|(l, t, e)| Mutation::Number(l, t, e)),
        (
            any::<prop::sample::Index>(),
            any::<prop::sample::Index>(),
            proptest::sample::select(EDGE.to_vec())
        )
            .prop_map(|(l, t, e)| Mutation::Number(l, t, e)),
        any::<prop::sample::Index>().prop_map(Mutation::DuplicateLine),
        any::<prop::sample::Index>().prop_map(Mutation::DeleteLine),
    ]
}

/// Replaces a number of one of the first 13 lines of a dataset (its
/// header) by `with`: counts, types, spacing, byte counts, exponents.
fn replace_number(
    b: &[u8],
    line: prop::sample::Index,
    tok: prop::sample::Index,
    with: &str,
) -> Vec<u8> {
    // header lines: within 13 lines of a "-1"
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            b.iter()
                .enumerate()
                .filter(|(_, &c)| c == b'\n')
                .map(|(i, _)| i + 1),
        )
        .filter(|&s| s < b.len())
        .collect();
    let mut header = Vec::new();
    let mut since = usize::MAX;
    for &s in &starts {
        let end = b[s..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(b.len(), |e| s + e);
        let text = &b[s..end];
        if text.trim_ascii() == b"-1" {
            since = 0;
        } else if since < 13 {
            since += 1;
            header.push((s, end));
        }
    }
    if header.is_empty() {
        return b.to_vec();
    }
    let (s, e) = header[line.index(header.len())];
    let mut toks = Vec::new();
    let mut k = s;
    while k < e {
        if b[k].is_ascii_digit() || b[k] == b'-' || b[k] == b'.' {
            let st = k;
            while k < e && !b[k].is_ascii_whitespace() {
                k += 1;
            }
            toks.push((st, k));
        } else {
            k += 1;
        }
    }
    if toks.is_empty() {
        return b.to_vec();
    }
    let (ts, te) = toks[tok.index(toks.len())];
    let mut out = b[..ts].to_vec();
    out.extend(with.as_bytes());
    out.extend(&b[te..]);
    out
}

fn line_bounds(b: &[u8], i: prop::sample::Index) -> Option<(usize, usize)> {
    let starts: Vec<usize> = std::iter::once(0)
        .chain(
            b.iter()
                .enumerate()
                .filter(|(_, &c)| c == b'\n')
                .map(|(i, _)| i + 1),
        )
        .filter(|&s| s < b.len())
        .collect();
    if starts.is_empty() {
        return None;
    }
    let s = starts[i.index(starts.len())];
    let e = b[s..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |e| s + e + 1);
    Some((s, e))
}

fn apply(mut b: Vec<u8>, m: &Mutation) -> Vec<u8> {
    match m {
        Mutation::FlipBit(i, bit) if !b.is_empty() => {
            let k = i.index(b.len());
            b[k] ^= 1 << bit;
        }
        Mutation::Truncate(i) if !b.is_empty() => {
            b.truncate(i.index(b.len()));
        }
        Mutation::Insert(i, v) => {
            let k = i.index(b.len() + 1);
            b.splice(k..k, v.iter().copied());
        }
        Mutation::Delete(i, n) if !b.is_empty() => {
            let k = i.index(b.len());
            let e = (k + n).min(b.len());
            b.drain(k..e);
        }
        Mutation::Number(l, t, with) => b = replace_number(&b, *l, *t, with),
        Mutation::DuplicateLine(i) => {
            if let Some((s, e)) = line_bounds(&b, *i) {
                let l = b[s..e].to_vec();
                b.splice(s..s, l);
            }
        }
        Mutation::DeleteLine(i) => {
            if let Some((s, e)) = line_bounds(&b, *i) {
                b.drain(s..e);
            }
        }
        _ => {}
    }
    b
}

fn fuzz_seeds() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = oracle_files()
        .iter()
        .map(|n| std::fs::read(data_dir().join(n)).unwrap())
        .collect();
    let ds = datasets_of("multi.uff");
    seeds.push(write_ascii(&ds).unwrap().into_bytes());
    seeds.push(write_binary(&ds).unwrap());
    seeds.push(simple_ascii().into_bytes());
    seeds
}

fn fuzz(cases: u32) {
    let seeds = fuzz_seeds();
    let n = seeds.len();
    let input = prop_oneof![
        1 => proptest::collection::vec(any::<u8>(), 0..600).prop_map(|b| (None, b, vec![])),
        1 => (proptest::collection::vec(any::<u8>(), 0..300))
            .prop_map(|b| { let mut v = b"    -1\n    58\n".to_vec(); v.extend(b); (None, v, vec![]) }),
        8 => (0..n, proptest::collection::vec(mutation(), 1..5))
            .prop_map(|(s, m)| (Some(s), Vec::new(), m)),
    ];
    let start = std::time::Instant::now();
    let select = Uff58Select {
        function_type: Some(4),
        ..Default::default()
    };
    // outcomes: read, file error, block error, dataset error
    let counts: [AtomicUsize; 4] = Default::default();
    runner(cases, 11)
        .run(&input, |(seed, raw, muts)| {
            let bytes = match seed {
                Some(s) => muts.iter().fold(seeds[s].clone(), apply),
                None => raw,
            };
            let t = std::time::Instant::now();
            let r = parse(&bytes, pth());
            let kind = match &r {
                Ok(_) => 0,
                Err(Uff58Error::File { .. }) => 1,
                Err(Uff58Error::Block { .. }) => 2,
                _ => 3,
            };
            counts[kind].fetch_add(1, Ordering::Relaxed);
            match r {
                Ok(fs) => {
                    // what was read can be listed, and written if finite
                    let _ = write_ascii(&fs.iter().map(|f| f.dataset.clone()).collect::<Vec<_>>());
                }
                Err(e) => {
                    let s = e.to_string();
                    prop_assert!(!s.chars().any(|c| c.is_control()), "{:?}", s);
                    prop_assert!(s.len() < 1000, "{}", s);
                }
            }
            let _ = parse_headers(&bytes, pth());
            let _ = parse_selected(&bytes, pth(), &select);
            prop_assert!(t.elapsed().as_secs_f64() < 1.0);
            Ok(())
        })
        .unwrap();
    let c: Vec<usize> = counts.iter().map(|c| c.load(Ordering::Relaxed)).collect();
    eprintln!(
        "uff58 fuzz: {cases} inputs in {:.1} s: {} read, {} not a universal file, {} bad \
         between datasets, {} bad dataset 58",
        start.elapsed().as_secs_f64(),
        c[0],
        c[1],
        c[2],
        c[3]
    );
}

#[test]
fn fuzz_ci() {
    let cases = std::env::var("NLSDOF_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    fuzz(cases);
}

#[test]
#[ignore = "10^6 inputs; run in release with --ignored"]
fn fuzz_million() {
    fuzz(1_000_000);
}
