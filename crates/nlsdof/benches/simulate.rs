//! Simulation benchmark (custom harness; `cargo bench -p nlsdof --bench simulate`).
//!
//! The paper's longest record: 8 752 000 samples at 2048 Hz (71 min), which
//! it had to subsample to 64 Hz and still took > 40 min per simulation in
//! MATLAB (§4.1). The input here has the same length and rate: a
//! phase-continuous stepped sine over 5.3–5.5 Hz (200 steps, 0.62 m/s²
//! zero-to-peak, the paper's level 2) plus 2 % broadband noise, like a
//! recorded shaker acceleration. Reported:
//!
//! 1. RK4 time for the whole record with the wing model (Tables 3 + 7):
//!    real exponents (powf) and integer exponents (ρ = 4, η = 3:
//!    multiplications only), two and one samples per step; the
//!    Dormand–Prince reference on a 2^20-sample slice.
//! 2. scipy `solve_ivp` RK45 on the first 2^16 samples
//!    (`scripts/bench_scipy_simulate.py`, if python3 with numpy/scipy is
//!    available) and the per-sample speed ratio.
//! 3. The 5-level × 200-step virtual stepped-sine test of the wing.
//!
//! `NLSDOF_BENCH=memory` runs only the full simulation once into x and v
//! arrays (for `/usr/bin/time -v` peak-memory measurements) and prints the
//! array sizes. Timings are best of several runs; output arrays are
//! allocated once and reused (first-touch page faults excluded; the
//! memory run reports them separately).

#[path = "../tests/support/mod.rs"]
mod support;

use nlsdof::excitation::{Dwell, Excitation, SampledInput, SteppedSine};
use nlsdof::simulation::{simulate, simulate_into, Method, Options};
use nlsdof::stepped_sine::{run_levels, RigOptions};
use nlsdof::{NormalisedModel, SweepDirection};
use std::f64::consts::TAU;
use std::time::Instant;

const N: usize = 8_752_000;
const FS: f64 = 2048.0;

fn wing(integer: bool) -> NormalisedModel {
    let (rho, eta) = if integer {
        (4.0, 3.0)
    } else {
        (4.00220, 3.03099)
    };
    support::fixtures::wing_with_exponents(rho, eta)
        .normalised()
        .unwrap()
}

fn input() -> Vec<f64> {
    let omegas: Vec<f64> = (0..200).map(|k| TAU * (5.3 + 0.001 * k as f64)).collect();
    let dwell = N as f64 / FS / 200.0;
    let s = SteppedSine::new(0.62, omegas, Dwell::Seconds(dwell)).unwrap();
    let mut state: u64 = 0x2545F4914F6CDD1D;
    (0..N)
        .map(|k| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let noise = ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
            s.accel(k as f64 / FS) + 0.02 * 0.62 * noise
        })
        .collect()
}

fn best_of<F: FnMut() -> f64>(runs: usize, mut f: F) -> f64 {
    (0..runs).map(|_| f()).fold(f64::INFINITY, f64::min)
}

fn main() {
    let mode = std::env::var("NLSDOF_BENCH").unwrap_or_default();
    let t = Instant::now();
    let u = input();
    let gen_s = t.elapsed().as_secs_f64();
    let inp = SampledInput::uniform(&u, FS, 0.0).unwrap();
    let real = wing(false);
    let int = wing(true);
    let mb = |n: usize| n as f64 * 8.0 / 1e6;

    if mode == "memory" {
        let (mut x, mut v) = (Vec::new(), Vec::new());
        let t = Instant::now();
        let s = simulate_into(&real, &inp, &Options::default(), &mut x, &mut v).unwrap();
        println!(
            "memory run: {} samples in {:.3} s (incl. first touch of the output arrays); input {:.1} MB + output x,v {:.1} MB = {:.1} MB of arrays; final x {:e}",
            s.samples,
            t.elapsed().as_secs_f64(),
            mb(u.len()),
            mb(x.len() + v.len()),
            mb(u.len() + x.len() + v.len()),
            s.final_state.x
        );
        return;
    }

    println!(
        "input: {N} samples at {FS} Hz ({:.1} min), generated in {gen_s:.2} s",
        N as f64 / FS / 60.0
    );
    let (mut x, mut v) = (Vec::with_capacity(N), Vec::with_capacity(N));
    // touch the output pages once
    simulate_into(&int, &inp, &Options::default(), &mut x, &mut v).unwrap();
    let mut results = vec![];
    for (name, model, sps) in [
        ("wing real exponents, RK4 2 samples/step", &real, 2usize),
        ("wing integer exponents, RK4 2 samples/step", &int, 2),
        ("wing real exponents, RK4 1 sample/step", &real, 1),
        ("wing integer exponents, RK4 1 sample/step", &int, 1),
    ] {
        let opts = Options {
            method: Method::Rk4 {
                samples_per_step: sps,
            },
            ..Default::default()
        };
        let secs = best_of(3, || {
            let t = Instant::now();
            simulate_into(model, &inp, &opts, &mut x, &mut v).unwrap();
            t.elapsed().as_secs_f64()
        });
        println!(
            "{name:48} {secs:.3} s  ({:.1} ns/sample)",
            secs / N as f64 * 1e9
        );
        results.push((name, secs));
    }
    // streaming without storing anything
    let secs = best_of(3, || {
        let t = Instant::now();
        let mut acc = 0.0;
        simulate(&real, &inp, &Options::default(), |s| acc += s.x).unwrap();
        std::hint::black_box(acc);
        t.elapsed().as_secs_f64()
    });
    println!(
        "{:48} {secs:.3} s",
        "wing real, RK4 x2, streaming (no arrays)"
    );
    let slice = 1 << 20;
    let part = SampledInput::uniform(&u[..slice], FS, 0.0).unwrap();
    let t = Instant::now();
    let s = simulate_into(
        &real,
        &part,
        &Options {
            method: Method::reference(),
            ..Default::default()
        },
        &mut x,
        &mut v,
    )
    .unwrap();
    let dp = t.elapsed().as_secs_f64();
    println!(
        "{:48} {dp:.3} s for 2^20 samples ({:.1} ns/sample, {} RHS, {} rejected)",
        "wing real, Dormand-Prince rtol 1e-10",
        dp / slice as f64 * 1e9,
        s.rhs_evaluations,
        s.rejected_steps
    );

    // scipy comparison on the first 2^16 samples
    let ours_per_sample = results[0].1 / N as f64;
    let n16 = 1 << 16;
    let dir = std::env::temp_dir().join(format!("nlsdof-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let uin = dir.join("u.f64");
    let xref = dir.join("x.f64");
    std::fs::write(
        &uin,
        u[..n16]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    let p16 = SampledInput::uniform(&u[..n16], FS, 0.0).unwrap();
    simulate_into(
        &real,
        &p16,
        &Options {
            method: Method::reference(),
            ..Default::default()
        },
        &mut x,
        &mut v,
    )
    .unwrap();
    std::fs::write(
        &xref,
        x.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>(),
    )
    .unwrap();
    simulate_into(&real, &p16, &Options::default(), &mut x, &mut v).unwrap();
    let mut xr = vec![];
    simulate(
        &real,
        &p16,
        &Options {
            method: Method::reference(),
            ..Default::default()
        },
        |s| xr.push(s.x),
    )
    .unwrap();
    let scale = xr.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let rk4_err = x
        .iter()
        .zip(&xr)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale;
    println!(
        "RK4 x2 vs Dormand-Prince on the 2^16 slice: relative max error {rk4_err:.2e} (input read as smooth vs piecewise linear between samples)"
    );
    simulate_into(
        &real,
        &p16,
        &Options {
            method: Method::Rk4 {
                samples_per_step: 1,
            },
            ..Default::default()
        },
        &mut x,
        &mut v,
    )
    .unwrap();
    let rk4_1_err = x
        .iter()
        .zip(&xr)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / scale;
    println!("RK4 x1 vs Dormand-Prince on the 2^16 slice: relative max error {rk4_1_err:.2e} (same piecewise-linear input)");
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scripts/bench_scipy_simulate.py"
    );
    let model_arg = "0.26699,306.7878,0.1164,85000,4.0022,0.01591,3.03099";
    for (rtol, atol) in [("1e-3", "1e-6"), ("1e-8", "1e-11")] {
        let out = std::process::Command::new("python3")
            .args([
                script,
                "--input",
                uin.to_str().unwrap(),
                "--fs",
                "2048",
                "--model",
                model_arg,
            ])
            .args([
                "--rtol",
                rtol,
                "--atol",
                atol,
                "--reference",
                xref.to_str().unwrap(),
            ])
            .output();
        match out {
            Ok(o) if o.status.success() => {
                let text = String::from_utf8_lossy(&o.stdout);
                let per = text
                    .split("\"per_sample_s\": ")
                    .nth(1)
                    .and_then(|s| s.split([',', '}']).next())
                    .and_then(|s| s.trim().parse::<f64>().ok());
                match per {
                    Some(p) => println!(
                        "scipy solve_ivp RK45 rtol {rtol}: {:.2} us/sample vs ours {:.1} ns/sample: ratio {:.0}x   {}",
                        p * 1e6,
                        ours_per_sample * 1e9,
                        p / ours_per_sample,
                        text.trim()
                    ),
                    None => println!("scipy: unexpected output {text}"),
                }
            }
            Ok(o) => println!(
                "scipy comparison skipped: {}",
                String::from_utf8_lossy(&o.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            ),
            Err(e) => println!("scipy comparison skipped: python3 not runnable ({e})"),
        }
    }
    let _ = std::fs::remove_dir_all(&dir);

    // the paper's stepped-sine test, simulated
    let omegas: Vec<f64> = (0..200).map(|k| TAU * (5.3 + 0.001 * k as f64)).collect();
    let gammas = [0.41, 0.62, 0.81, 1.00, 1.23];
    let mut cycles = 0;
    let rig = best_of(2, || {
        let t = Instant::now();
        let r = run_levels(
            &real,
            &gammas,
            &omegas,
            SweepDirection::Up,
            &RigOptions::default(),
            &|| {},
        )
        .unwrap();
        cycles = r
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.cycles))
            .sum::<usize>();
        t.elapsed().as_secs_f64()
    });
    println!(
        "virtual stepped sine, wing, 5 levels x 200 steps: {rig:.3} s ({cycles} cycles x 64 RK4 steps, {} threads)",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    );
}
