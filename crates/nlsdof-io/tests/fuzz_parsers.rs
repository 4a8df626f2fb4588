//! Parser fuzzing (issue 11, item 12): structured mutations of valid files
//! for every parser of nlsdof-io — model TOML, fit CSV, phase-resonance CSV,
//! beam txt, Polytec ASCII (time histories and swept-sine FRF exports),
//! signal CSV, MAT v5, bounds TOML, FRF CSV and the column tables of
//! `fit-time` and `decay` (CSV, tab, LabVIEW .lvm, Polytec ASCII; issue 30:
//! every error message of that reader must also be one printable line).
//!
//! Each input is a valid seed file with 1 to 4 stacked mutations: numbers
//! replaced by edge values (NaN, inf, 1e308, subnormals, huge integers,
//! empty, words), lines deleted, duplicated, swapped or spliced from another
//! seed, separators changed, truncation, inserted bytes (invalid UTF-8, NUL,
//! CR, quotes, BOM), bit flips; for MAT files also tag sizes and types
//! overwritten with edge integers, and mutated elements re-compressed so the
//! mutation reaches the inflated data. No input may panic, take longer than
//! 1 s, or make the parser hold more than 1 GiB (a counting allocator
//! refuses — and so aborts the run on — any allocation beyond that).
//!
//! `fuzz_parsers_ci` runs 10,000 inputs per parser (part of the normal
//! test suite); `fuzz_parsers_million` (ignored; run with
//! `cargo test --release -p nlsdof-io --test fuzz_parsers -- --ignored --nocapture`)
//! runs 1,000,000 per parser. `NLSDOF_FUZZ_N` overrides the count,
//! `NLSDOF_FUZZ_SEED` the seed.

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

// ------------------------------------------------------------ allocator

const MEMORY_LIMIT: usize = 1 << 30;
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

struct Counting;

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        if now > MEMORY_LIMIT {
            CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
            return std::ptr::null_mut(); // aborts: "memory allocation of N bytes failed"
        }
        PEAK.fetch_max(now, Ordering::Relaxed);
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
            PEAK.fetch_max(now, Ordering::Relaxed);
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

// ------------------------------------------------------------------ rng

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        // xorshift64*
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

// ------------------------------------------------------------ mutations

const MAX_INPUT: usize = 1 << 16;

const VALUES: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "-3",
    "-3.0001",
    "NaN",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "Infinity",
    "+inf",
    "1e308",
    "1.8e308",
    "-1e308",
    "1e-320",
    "4.9e-324",
    "-4.9e-324",
    "1e999",
    "1e-999",
    "99999999999999999999999",
    "18446744073709551616",
    "-9223372036854775809",
    "0x10",
    "0b1",
    "1_000",
    "1,5",
    "0,00524991",
    "",
    " ",
    "\"1\"",
    "'1'",
    "1e",
    "e5",
    ".",
    "-",
    "+5",
    "١٢",
    "1.0.0",
    "up",
    "down",
    "UP",
    "both",
    "level",
    "gamma",
    "f_hz",
    "amplitude",
    "phase_deg",
    "sweep",
    "weight",
    "t",
    "time",
    "accel",
    "#",
    "\u{feff}",
    "true",
    "false",
    "[",
    "]",
    "{",
    "}",
    "=",
    "= 1",
    "[nonlinear_stiffness]",
    "[nonlinear_damping]",
    "coefficient = 1e300",
    "exponent = -3",
    "exponent = nan",
    "exponent = inf",
    "mass = 0",
    "mass = -1",
    "mass = inf",
    "stiffness = 1e-320",
    "damping = -0.0",
    "alpha = [1, 2]",
    "beta = [2, 1]",
    "rho = [nan, 1]",
    "x = [[1,2],[3]]",
    "a.b.c = 1",
    "\"key\" = 1",
    "[[t]]",
    "Source File Name:",
    "Signal:",
    "Time\tTime Signal",
    "[ s ]\t[ N ]",
    "X-Data [Hz]",
    "\t",
    ";",
    ",",
    ",,",
    "\r",
    "\0",
    "\u{0}\u{1}\u{7f}",
    "ÿ",
    "\u{2028}",
    "𝟙",
];

/// Text mutations (line/field aware).
fn mutate_text(rng: &mut Rng, input: &[u8], seeds: &[Vec<u8>]) -> Vec<u8> {
    let mut out = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        out = match rng.below(14) {
            0 | 1 | 2 => replace_token(rng, &out),
            3 => edit_lines(rng, &out, |rng, lines| {
                if !lines.is_empty() {
                    let k = rng.below(lines.len());
                    lines.remove(k);
                }
            }),
            4 => edit_lines(rng, &out, |rng, lines| {
                if !lines.is_empty() {
                    let k = rng.below(lines.len());
                    let most = if rng.below(8) == 0 { 200 } else { 3 };
                    let n = 1 + rng.below(most);
                    let l = lines[k].clone();
                    for _ in 0..n {
                        lines.insert(k, l.clone());
                    }
                }
            }),
            5 => edit_lines(rng, &out, |rng, lines| {
                if lines.len() > 1 {
                    let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
                    lines.swap(a, b);
                }
            }),
            6 => {
                // splice a line of another seed
                let other = rng.pick(seeds).clone();
                let ol: Vec<&[u8]> = other.split(|&b| b == b'\n').collect();
                let line = ol[rng.below(ol.len())].to_vec();
                edit_lines(rng, &out, move |rng, lines| {
                    let k = rng.below(lines.len() + 1);
                    lines.insert(k, line.clone());
                })
            }
            7 => {
                let seps: [&[u8]; 5] = [b",", b";", b"\t", b" ", b",,"];
                let (from, to) = (*rng.pick(&seps), *rng.pick(&seps));
                replace_all(&out, from, to)
            }
            8 => {
                let k = rng.below(out.len() + 1);
                out[..k].to_vec()
            }
            9 => {
                let ins: [&[u8]; 9] = [
                    b"\xff",
                    b"\xc3",
                    b"\0",
                    b"\r",
                    b"\"",
                    b"\xef\xbb\xbf",
                    b"\n",
                    b"\r\n",
                    b"#",
                ];
                let k = rng.below(out.len() + 1);
                let mut v = out[..k].to_vec();
                let s: &[u8] = *rng.pick(&ins[..]);
                v.extend_from_slice(s);
                v.extend_from_slice(&out[k..]);
                v
            }
            10 => {
                if !out.is_empty() {
                    let k = rng.below(out.len());
                    out[k] ^= 1 << rng.below(8);
                }
                out
            }
            11 => {
                let a = rng.below(out.len() + 1);
                let b = (a + rng.below(64)).min(out.len());
                let mut v = out[..a].to_vec();
                v.extend_from_slice(&out[b..]);
                v
            }
            12 => replace_all(&out, b"\n", if rng.below(2) == 0 { b"\r\n" } else { b"\r" }),
            _ => {
                // a digit replaced by another
                let digits: Vec<usize> = (0..out.len())
                    .filter(|&i| out[i].is_ascii_digit())
                    .collect();
                if !digits.is_empty() {
                    let k = *rng.pick(&digits);
                    out[k] = b'0' + rng.below(10) as u8;
                }
                out
            }
        };
        out.truncate(MAX_INPUT);
    }
    out
}

fn replace_all(v: &[u8], from: &[u8], to: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(v.len());
    let mut i = 0;
    while i < v.len() {
        if v[i..].starts_with(from) {
            out.extend_from_slice(to);
            i += from.len();
        } else {
            out.push(v[i]);
            i += 1;
        }
    }
    out
}

fn edit_lines(rng: &mut Rng, v: &[u8], f: impl FnOnce(&mut Rng, &mut Vec<Vec<u8>>)) -> Vec<u8> {
    let mut lines: Vec<Vec<u8>> = v.split(|&b| b == b'\n').map(|l| l.to_vec()).collect();
    f(rng, &mut lines);
    lines.join(&b'\n')
}

/// Replaces one token (a run of number-like characters, or a word) by an
/// edge value.
fn replace_token(rng: &mut Rng, v: &[u8]) -> Vec<u8> {
    let is_tok = |b: u8| b.is_ascii_alphanumeric() || matches!(b, b'.' | b'-' | b'+' | b'_');
    let starts: Vec<usize> = (0..v.len())
        .filter(|&i| is_tok(v[i]) && (i == 0 || !is_tok(v[i - 1])))
        .collect();
    let value = rng.pick(VALUES).as_bytes();
    if starts.is_empty() {
        let mut out = v.to_vec();
        out.extend_from_slice(value);
        return out;
    }
    let a = *rng.pick(&starts);
    let mut b = a;
    while b < v.len() && is_tok(v[b]) {
        b += 1;
    }
    let mut out = v[..a].to_vec();
    if rng.below(16) == 0 {
        // a very long token
        for _ in 0..1 + rng.below(400) {
            out.extend_from_slice(value);
            out.push(b'9');
        }
    } else {
        out.extend_from_slice(value);
    }
    out.extend_from_slice(&v[b..]);
    out
}

// ------------------------------------------------------------------ MAT

fn mat_header(big_endian: bool) -> Vec<u8> {
    let mut out = vec![b' '; 116];
    out[..20].copy_from_slice(b"MATLAB 5.0 MAT-file,");
    out.extend([0u8; 8]);
    if big_endian {
        out.extend(0x0100u16.to_be_bytes());
        out.extend(*b"MI");
    } else {
        out.extend(0x0100u16.to_le_bytes());
        out.extend(*b"IM");
    }
    out
}

fn u32b(v: u32, be: bool) -> [u8; 4] {
    if be {
        v.to_be_bytes()
    } else {
        v.to_le_bytes()
    }
}

/// A miMATRIX element: class, dims, name, real data stored as `ty`.
fn mat_matrix(name: &str, dims: &[i32], data: &[f64], ty: u32, complex: bool, be: bool) -> Vec<u8> {
    let pad = |v: &mut Vec<u8>| {
        while v.len() % 8 != 0 {
            v.push(0);
        }
    };
    let mut p = Vec::new();
    p.extend(u32b(6, be));
    p.extend(u32b(8, be));
    p.extend(u32b(6 | if complex { 0x0800 } else { 0 }, be));
    p.extend(u32b(0, be));
    p.extend(u32b(5, be));
    p.extend(u32b(4 * dims.len() as u32, be));
    for &d in dims {
        p.extend(u32b(d as u32, be));
    }
    pad(&mut p);
    if name.len() <= 4 && !name.is_empty() {
        // small data element
        p.extend(u32b(((name.len() as u32) << 16) | 1, be));
        let mut n = name.as_bytes().to_vec();
        n.resize(4, 0);
        p.extend(n);
    } else {
        p.extend(u32b(1, be));
        p.extend(u32b(name.len() as u32, be));
        p.extend(name.as_bytes());
        pad(&mut p);
    }
    for _ in 0..if complex { 2 } else { 1 } {
        let bytes: Vec<u8> = match ty {
            9 => data
                .iter()
                .flat_map(|v| if be { v.to_be_bytes() } else { v.to_le_bytes() })
                .collect(),
            7 => data
                .iter()
                .flat_map(|&v| {
                    if be {
                        (v as f32).to_be_bytes()
                    } else {
                        (v as f32).to_le_bytes()
                    }
                })
                .collect(),
            2 => data.iter().map(|&v| v as u8).collect(),
            _ => data
                .iter()
                .flat_map(|&v| {
                    if be {
                        (v as i16).to_be_bytes()
                    } else {
                        (v as i16).to_le_bytes()
                    }
                })
                .collect(),
        };
        let ty = if matches!(ty, 9 | 7 | 2) { ty } else { 3 };
        p.extend(u32b(ty, be));
        p.extend(u32b(bytes.len() as u32, be));
        p.extend(bytes);
        pad(&mut p);
    }
    let mut out = Vec::new();
    out.extend(u32b(14, be));
    out.extend(u32b(p.len() as u32, be));
    out.extend(p);
    out
}

fn compress(el: &[u8], be: bool) -> Vec<u8> {
    use std::io::Write;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(el).unwrap();
    let c = z.finish().unwrap();
    let mut out = Vec::new();
    out.extend(u32b(15, be));
    out.extend(u32b(c.len() as u32, be));
    out.extend(c);
    out
}

/// Valid MAT seeds: (file, its elements uncompressed, endianness).
fn mat_seeds() -> Vec<(Vec<u8>, Vec<Vec<u8>>, bool)> {
    let x: Vec<f64> = (0..40).map(|k| (k as f64 * 0.3).sin()).collect();
    let t: Vec<f64> = (0..40).map(|k| k as f64 * 0.01).collect();
    let tx: Vec<f64> = t.iter().chain(&x).copied().collect();
    let mut seeds = Vec::new();
    for be in [false, true] {
        let sets: Vec<Vec<Vec<u8>>> = vec![
            vec![
                mat_matrix("accel", &[40, 1], &x, 9, false, be),
                mat_matrix("fs", &[1, 1], &[100.0], 9, false, be),
            ],
            vec![
                mat_matrix("u", &[1, 40], &x, 7, false, be),
                mat_matrix("t", &[1, 40], &t, 9, false, be),
            ],
            vec![mat_matrix("rec", &[40, 2], &tx, 9, false, be)],
            vec![
                mat_matrix("a", &[2, 40], &tx, 3, false, be),
                mat_matrix("z", &[1, 40], &x, 9, true, be),
            ],
            vec![
                mat_matrix("gamma", &[40, 1], &x, 2, false, be),
                mat_matrix("fs", &[1, 1], &[50.0], 2, false, be),
            ],
        ];
        for els in sets {
            for compressed in [false, true] {
                let mut f = mat_header(be);
                for e in &els {
                    if compressed {
                        f.extend(compress(e, be));
                    } else {
                        f.extend(e);
                    }
                }
                seeds.push((f, els.clone(), be));
            }
        }
    }
    seeds
}

const EDGE_U32: &[u32] = &[
    0,
    1,
    2,
    3,
    4,
    5,
    6,
    7,
    8,
    9,
    12,
    13,
    14,
    15,
    16,
    17,
    24,
    0x7f,
    0xff,
    0x800,
    0xffff,
    0x1_0000,
    0x0004_0001,
    0x7fff_ffff,
    0x8000_0000,
    0xffff_fff8,
    0xffff_ffff,
];

fn mutate_mat(rng: &mut Rng, seeds: &[(Vec<u8>, Vec<Vec<u8>>, bool)]) -> Vec<u8> {
    let (file, els, be) = rng.pick(seeds);
    let be = *be;
    let mut out = if rng.below(3) == 0 {
        // structure-aware: mutate an element, then (maybe) compress it
        let mut f = mat_header(be);
        for e in els {
            let mut e = e.clone();
            if rng.below(2) == 0 {
                e = mutate_bytes(rng, &e, be);
            }
            if rng.below(2) == 0 {
                f.extend(compress(&e, be));
            } else {
                f.extend(e);
            }
        }
        f
    } else {
        file.clone()
    };
    for _ in 0..1 + rng.below(3) {
        out = mutate_bytes(rng, &out, be);
        out.truncate(MAX_INPUT);
    }
    out
}

fn mutate_bytes(rng: &mut Rng, v: &[u8], be: bool) -> Vec<u8> {
    let mut out = v.to_vec();
    match rng.below(7) {
        0 | 1 | 2 => {
            // an aligned u32 (tag, size, flags, dims) set to an edge value
            if out.len() >= 4 {
                let k = rng.below(out.len() / 4) * 4;
                let val = *rng.pick(EDGE_U32);
                out[k..k + 4].copy_from_slice(&u32b(val, be));
            }
        }
        3 => {
            let k = rng.below(out.len() + 1);
            out.truncate(k);
        }
        4 => {
            if !out.is_empty() {
                let k = rng.below(out.len());
                out[k] ^= 1 << rng.below(8);
            }
        }
        5 => {
            let k = rng.below(out.len() + 1);
            let n = 1 + rng.below(16);
            let ins: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            out.splice(k..k, ins);
        }
        _ => {
            let a = rng.below(out.len() + 1);
            let b = (a + rng.below(64)).min(out.len());
            out.drain(a..b);
        }
    }
    out
}

// ---------------------------------------------------------------- seeds

fn repo() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

fn read_head(rel: &str, lines: usize) -> Option<Vec<u8>> {
    let p = repo().join(rel);
    let bytes = std::fs::read(p).ok()?;
    let mut n = 0;
    let end = bytes
        .iter()
        .position(|&b| {
            n += usize::from(b == b'\n');
            n >= lines
        })
        .map(|e| e + 1)
        .unwrap_or(bytes.len());
    Some(bytes[..end].to_vec())
}

fn fit_csv_seeds() -> Vec<Vec<u8>> {
    let mut a = String::from("level,gamma,f_hz,amplitude,phase_deg,sweep,weight\n");
    let mut b = String::from("# comment\nlevel,gamma,f_hz,amplitude\n");
    for (l, g) in [("low", 0.1), ("high", 0.25)] {
        for i in 0..12 {
            let f = 8.5 + 0.3 * i as f64;
            let amp = g * 1e-3 / (1.0 + (f - 10.0f64).powi(2));
            a += &format!("{l},{g},{f},{amp:e},{},up,1\n", 10.0 * i as f64);
            b += &format!("{l},{g},{f},{amp}\n");
        }
        for i in 0..6 {
            let f = 12.0 - 0.5 * i as f64;
            a += &format!("{l},{g},{f},{:e},90,down,0.5\n", g * 1e-4);
        }
    }
    vec![a.into_bytes(), b.into_bytes()]
}

fn pr_seeds() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = [
        "examples/har-wing-table8.csv",
        "examples/har-wing-loaded-table8.csv",
    ]
    .iter()
    .filter_map(|p| read_head(p, 200))
    .collect();
    v.push(b"gamma,f_hz,amplitude,level,weight\n0.4,5.4,0.01,a,1\n0.8,5.38,0.02,b,1\n1.2,5.36,0.03,c,2\n".to_vec());
    v
}

fn beam_seeds() -> Vec<Vec<u8>> {
    let mut v = Vec::new();
    let d = "../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C/frf_0.04g.txt";
    if let Some(b) = read_head(d, 80) {
        v.push(b);
    }
    let mut s = String::from(
        "X-Data [Hz]\tLaser (M - Filtered) [m/s]\tPhase [Deg]\tLaser (M - Filtered) [m/s]\tPhase [Deg]\t\r\n\t002: [06-25-24 12:56]\t\t003: [06-25-24 13:04]\t\r\n",
    );
    for i in 0..40 {
        let f = 31.0 + 0.002 * i as f64;
        s += &format!(
            "{:>12}\t{:>12}\t{}\t{:>12}\t{}\r\n",
            format!("{f}").replace('.', ","),
            format!("{:.8}", 0.005 + 1e-5 * i as f64).replace('.', ","),
            format!("{:.1}", 74.3 - 0.1 * i as f64).replace('.', ","),
            format!("{:.8}", 0.006 + 1e-5 * i as f64).replace('.', ","),
            format!("{:.1}", 71.3 + 0.1 * i as f64).replace('.', ","),
        );
    }
    v.push(s.clone().into_bytes());
    // one run only
    let one: String = s
        .lines()
        .map(|l| l.split('\t').take(3).collect::<Vec<_>>().join("\t") + "\r\n")
        .collect();
    v.push(one.into_bytes());
    v
}

fn polytec_time_seeds() -> Vec<Vec<u8>> {
    let mut v = Vec::new();
    for f in ["mec-t1-force.txt", "mec-t1-velocity.txt"] {
        let p =
            format!("../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_impact/{f}");
        if let Some(b) = read_head(&p, 60) {
            v.push(b);
        }
    }
    let mut s = String::from(
        "Source File Name:\tt3\r\nPoint Index:\t1\t[x = 0.03\ty = 0.02\tz = -1.23]\r\nComponent:\tRoot\r\nSignal:\tTime - Ref1 Force - Samples\r\n\r\nTime\tTime Signal\r\n[ s ]\t[ N ]\r\n",
    );
    for k in 0..50 {
        s += &format!("{}\t{}\r\n", k as f64 * 1e-4, (k as f64 * 0.2).sin() * 40.0);
    }
    v.push(s.into_bytes());
    let mut c = String::from("t,force,vel\n");
    for k in 0..50 {
        c += &format!(
            "{},{},{}\n",
            k as f64 * 1e-3,
            (k as f64 * 0.2).sin(),
            (k as f64 * 0.2).cos()
        );
    }
    v.push(c.into_bytes());
    v.push(b"ch1 ch2\n1 2\n3 4\n5 6\n7 8\n".to_vec());
    v
}

fn signal_csv_seeds() -> Vec<Vec<u8>> {
    let mut a = String::from("t,accel\n");
    let mut b = String::new();
    let mut c = String::from("# one column\naccel\n");
    for k in 0..60 {
        let t = k as f64 * 0.01;
        a += &format!("{t},{}\n", (t * 30.0).sin());
        b += &format!("{t},{}\n", (t * 30.0).cos());
        c += &format!("{}\n", (t * 10.0).sin());
    }
    vec![a.into_bytes(), b.into_bytes(), c.into_bytes()]
}

fn model_seeds() -> Vec<Vec<u8>> {
    let mut v: Vec<Vec<u8>> = [
        "examples/har-wing.toml",
        "examples/har-wing-integer.toml",
        "examples/har-wing-loaded.toml",
        "examples/duffing-strong.toml",
        "examples/coulomb.toml",
    ]
    .iter()
    .filter_map(|p| read_head(p, 400))
    .collect();
    v.push(b"mass = 1\nstiffness = 3947.84\ndamping = 1.2566\n[nonlinear_stiffness]\ncoefficient = 4e7\nexponent = 2\n[nonlinear_damping]\ncoefficient = 0.1\nexponent = 1\n".to_vec());
    v
}

fn bounds_seeds() -> Vec<Vec<u8>> {
    vec![
        b"alpha = [100.0, 10000.0]\ndelta = [0.0, 10]\nbeta = [1e3, 1e9]\nrho = [0.5, 4.0]\n"
            .to_vec(),
        b"# bounds\nkappa = [0, 5]\neta = [-0.9, 3]\ngain = [0.5, 2]\n".to_vec(),
    ]
}

fn column_table_seeds() -> Vec<Vec<u8>> {
    vec![
        b"\"V1\",\"V2\",\n0.0057756,0.0093978,\n0.0066102,0.012971,\n-0.001,0.002,\n".to_vec(),
        b"u;y\n1;2\n3;4\n5;6\n".to_vec(),
        b"t\tu\ty\n0\t1\t2\n0.1\t3\t4\n0.2\t5\t6\n".to_vec(),
        b"LabVIEW Measurement\t\nWriter_Version\t2\n***End_of_Header***\t\n\nChannels\t2\n***End_of_Header***\t\nX_Value\tV1\tV2\tComment\n0\t1\t2\n0.001\t3\t4\n".to_vec(),
        b"Source File Name:\tt3\r\nSignal:\tTime\r\n\r\nTime\tV1\tV2\r\n[ s ]\t[ V ]\t[ V ]\r\n0\t1.5\t2\r\n0.0001\t2.5\t3\r\n".to_vec(),
        b"# comment\n0,1\n2,3\n4,5\n".to_vec(),
    ]
}

fn frf_csv_seeds() -> Vec<Vec<u8>> {
    let mut a = String::from("f_hz,re,im\n");
    let mut b = String::from("f_hz,mag,phase_deg\n");
    let mut c = String::new();
    for i in 0..40 {
        let f = 8.0 + 0.1 * i as f64;
        let w = 2.0 * std::f64::consts::PI * f;
        let (re, im) = (3947.84 - w * w, 2.5 * w);
        let n = re * re + im * im;
        a += &format!("{f},{},{}\n", re / n, -im / n);
        b += &format!("{f},{},{}\n", 1.0 / n.sqrt(), -(im.atan2(re)).to_degrees());
        c += &format!("{f},{}\n", 1.0 / n.sqrt());
    }
    vec![a.into_bytes(), b.into_bytes(), c.into_bytes()]
}

// -------------------------------------------------------------- parsers

type Parse = Box<dyn Fn(&[u8])>;

fn text(b: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(b)
}

fn parsers() -> Vec<(&'static str, Vec<Vec<u8>>, Parse)> {
    use nlsdof_io::*;
    let p = Path::new("fuzz");
    let fit_spec_data = {
        let seed = &fit_csv_seeds()[0];
        stepped_sine_data::parse_csv(&text(seed), p, &Default::default()).expect("valid fit seed")
    };
    vec![
        (
            "model TOML",
            model_seeds(),
            Box::new(move |b: &[u8]| {
                let _ = model_file::parse_model(&text(b), p);
            }),
        ),
        (
            "fit CSV",
            fit_csv_seeds(),
            Box::new(move |b: &[u8]| {
                for opts in [
                    Default::default(),
                    stepped_sine_data::ReadOptions {
                        gamma_in_g: true,
                        peak_to_peak: true,
                        ..Default::default()
                    },
                ] {
                    let _ = stepped_sine_data::parse_csv(&text(b), p, &opts);
                }
            }),
        ),
        (
            "phase-resonance CSV",
            pr_seeds(),
            Box::new(move |b: &[u8]| {
                let _ = phase_resonance_data::parse_csv(&text(b), p, &Default::default());
            }),
        ),
        (
            "beam txt",
            beam_seeds(),
            Box::new(move |b: &[u8]| {
                use stepped_sine_data::Runs;
                let t: String = b.iter().map(|&c| c as char).collect();
                for runs in [Runs::Up, Runs::Down, Runs::Both] {
                    let _ = stepped_sine_data::parse_beam_file(&t, p, 0.04, runs);
                }
                let _ = frf_file::parse_polytec_sweep(b, p);
            }),
        ),
        (
            "Polytec ASCII / time histories",
            polytec_time_seeds(),
            Box::new(move |b: &[u8]| {
                let _ = frf_file::parse_time_history(&text(b), p, None);
                let _ = frf_file::parse_time_history(&text(b), p, Some(1e4));
            }),
        ),
        (
            "signal CSV",
            signal_csv_seeds(),
            Box::new(move |b: &[u8]| {
                let _ = signal_file::parse_csv(b, p, None);
                let _ = signal_file::parse_csv(b, p, Some(100.0));
            }),
        ),
        (
            "MAT v5",
            Vec::new(), // generated by mutate_mat
            Box::new(move |b: &[u8]| {
                let _ = signal_file::parse_mat(b, p, None, None);
                let _ = signal_file::parse_mat(b, p, Some(100.0), Some("accel"));
            }),
        ),
        (
            "bounds TOML",
            bounds_seeds(),
            Box::new(move |b: &[u8]| {
                if let Ok(bounds) = bounds_file::parse_bounds(&text(b), p) {
                    let mut spec = nlsdof::identification::FitSpec::new(
                        nlsdof::identification::models::ModelKind::Generalised,
                        &fit_spec_data,
                    );
                    for (name, lo, hi) in bounds {
                        let _ = spec.set_bounds(&name, lo, hi);
                    }
                }
            }),
        ),
        (
            "column table (fit-time, decay)",
            column_table_seeds(),
            Box::new(move |b: &[u8]| {
                for wanted in [&["V1", "V2"][..], &["0", "1"][..], &["u", "y"][..]] {
                    if let Err(e) = table_file::parse_columns(b, p, wanted) {
                        let m = e.to_string();
                        assert!(
                            !m.chars().any(|c| c.is_control() || c == '\u{fffd}'),
                            "not one printable line: {m:?}"
                        );
                    }
                }
            }),
        ),
        (
            "FRF CSV",
            frf_csv_seeds(),
            Box::new(move |b: &[u8]| {
                let _ = frf_file::parse_frf_csv(&text(b), p);
            }),
        ),
    ]
}

// -------------------------------------------------------------- driver

struct Stats {
    inputs: u64,
    seconds: f64,
    slowest: Duration,
    peak_bytes: usize,
}

fn run(name: &str, seeds: &[Vec<u8>], parse: &dyn Fn(&[u8]), n: u64, seed: u64) -> Stats {
    let mut rng = Rng(seed ^ 0x9e37_79b9_7f4a_7c15 ^ name.len() as u64 * 0x1000_0001);
    let mats = if seeds.is_empty() {
        mat_seeds()
    } else {
        Vec::new()
    };
    let trace = std::env::var_os("NLSDOF_FUZZ_TRACE").is_some();
    let t0 = Instant::now();
    let mut slowest = Duration::ZERO;
    let mut peak_bytes = 0usize;
    for i in 0..n {
        let input = if mats.is_empty() {
            let s = rng.pick(seeds);
            // every 64th input is a seed unchanged (the valid path)
            if i % 64 == 0 {
                s.clone()
            } else {
                mutate_text(&mut rng, s, seeds)
            }
        } else if i % 64 == 0 {
            rng.pick(&mats).0.clone()
        } else {
            mutate_mat(&mut rng, &mats)
        };
        if trace {
            eprintln!("{name} #{i}: {:?}", String::from_utf8_lossy(&input));
        }
        let base = CURRENT.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        let start = Instant::now();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parse(&input)));
        let dt = start.elapsed();
        let used = PEAK.load(Ordering::Relaxed).saturating_sub(base);
        peak_bytes = peak_bytes.max(used);
        if r.is_err() {
            let dir = repo().join("target/fuzz-failures");
            let _ = std::fs::create_dir_all(&dir);
            let f = dir.join(format!(
                "{}-{i}.bin",
                name.replace(|c: char| !c.is_alphanumeric(), "_")
            ));
            let _ = std::fs::write(&f, &input);
            panic!(
                "{name}: input #{i} panicked (saved to {}): {:?}",
                f.display(),
                String::from_utf8_lossy(&input)
            );
        }
        assert!(
            dt < Duration::from_secs(1),
            "{name}: input #{i} took {dt:?}: {:?}",
            String::from_utf8_lossy(&input)
        );
        slowest = slowest.max(dt);
    }
    Stats {
        inputs: n,
        seconds: t0.elapsed().as_secs_f64(),
        slowest,
        peak_bytes,
    }
}

fn fuzz_all(default_n: u64) {
    let n = std::env::var("NLSDOF_FUZZ_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default_n);
    let seed = std::env::var("NLSDOF_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5eed_2026);
    println!("| parser | inputs | time (s) | slowest input (ms) | peak extra memory (KiB) |");
    println!("|---|---:|---:|---:|---:|");
    for (name, seeds, parse) in parsers() {
        if name != "MAT v5" {
            assert!(!seeds.is_empty(), "{name}: no seeds");
        }
        let s = run(name, &seeds, &*parse, n, seed);
        println!(
            "| {name} | {} | {:.1} | {:.3} | {} |",
            s.inputs,
            s.seconds,
            s.slowest.as_secs_f64() * 1e3,
            s.peak_bytes / 1024
        );
        assert!(s.peak_bytes < MEMORY_LIMIT);
    }
}

/// The seeds themselves parse (so the mutations start from valid files).
#[test]
fn seeds_are_valid() {
    use nlsdof_io::*;
    let p = Path::new("seed");
    for s in model_seeds() {
        model_file::parse_model(&text(&s), p).unwrap();
    }
    for s in fit_csv_seeds() {
        stepped_sine_data::parse_csv(&text(&s), p, &Default::default()).unwrap();
    }
    for s in pr_seeds() {
        phase_resonance_data::parse_csv(&text(&s), p, &Default::default()).unwrap();
    }
    for s in beam_seeds() {
        let t: String = s.iter().map(|&c| c as char).collect();
        stepped_sine_data::parse_beam_file(&t, p, 0.04, stepped_sine_data::Runs::Up).unwrap();
    }
    for s in polytec_time_seeds() {
        frf_file::parse_time_history(&text(&s), p, Some(1e3)).ok();
    }
    for s in signal_csv_seeds() {
        signal_file::parse_csv(&s[..], p, Some(100.0))
            .or_else(|_| signal_file::parse_csv(&s[..], p, None))
            .unwrap();
    }
    for (f, _, _) in mat_seeds() {
        nlsdof_io::mat5::parse(&f).unwrap();
    }
    for s in bounds_seeds() {
        bounds_file::parse_bounds(&text(&s), p).unwrap();
    }
    for s in frf_csv_seeds() {
        frf_file::parse_frf_csv(&text(&s), p).unwrap();
    }
    for s in column_table_seeds() {
        table_file::parse_columns(&s, p, &["0", "1"]).unwrap();
    }
}

#[test]
fn fuzz_parsers_ci() {
    fuzz_all(10_000);
}

#[test]
#[ignore = "1,000,000 inputs per parser: minutes; run once with --ignored --nocapture"]
fn fuzz_parsers_million() {
    fuzz_all(1_000_000);
}
