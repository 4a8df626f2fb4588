//! `cargo bench -p nlsdof --bench vector_fitting`:
//! * fast relaxed vector fitting of a 1000-point FRF with 10 pole pairs
//!   (issue target: <= 10 ms), noise-free and with 1 % noise;
//! * H1/H2/coherence (Welch, 4096-point Hann segments, 50 % overlap) of
//!   1 M samples (issue target: <= 0.2 s).

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nlsdof::signal_processing::{welch_frf, WelchOptions};
use nlsdof::vector_fitting::{vector_fit, VfOptions, C64};
use std::f64::consts::PI;

fn ten_mode_frf(noise: f64) -> (Vec<f64>, Vec<C64>) {
    let w: Vec<f64> = (0..1000)
        .map(|i| 2.0 * PI * (5.0 + 110.0 * i as f64 / 999.0))
        .collect();
    let mut state = 12345u64;
    let mut u = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let h: Vec<C64> = w
        .iter()
        .map(|&w| {
            (0..10)
                .map(|i| {
                    let wn = 2.0 * PI * (10.0 * (i as f64 + 1.0) + 1.7 * (i as f64).sin());
                    let z = 0.005 + 0.0025 * i as f64;
                    let a = (1.0 + 0.3 * i as f64) * wn * wn / (4.0 * PI * PI);
                    C64::new(a, 0.0) / C64::new(wn * wn - w * w, 2.0 * z * wn * w)
                })
                .sum::<C64>()
        })
        .collect();
    let href = (h.iter().map(|z| z.norm_sqr()).sum::<f64>() / 1000.0).sqrt();
    let h = h
        .into_iter()
        .map(|z| z + C64::new(u(), u()) * (noise * href * 2.45))
        .collect();
    (w, h)
}

fn bench(c: &mut Criterion) {
    let opts = VfOptions {
        pole_pairs: 10,
        ..Default::default()
    };
    for (name, noise) in [
        ("vf_1000pts_10pairs", 0.0),
        ("vf_1000pts_10pairs_noise1pct", 0.01),
    ] {
        let (w, h) = ten_mode_frf(noise);
        let r = vector_fit(&w, &h, &opts).unwrap();
        eprintln!("{name}: {} iterations, {}", r.iterations, r.termination);
        c.bench_function(name, |b| {
            b.iter(|| vector_fit(black_box(&w), black_box(&h), &opts).unwrap())
        });
    }
    let n = 1 << 20;
    let mut s = 1u64;
    let x: Vec<f64> = (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        })
        .collect();
    let y: Vec<f64> = (0..n)
        .map(|i| {
            if i > 0 {
                0.5 * x[i] + 0.3 * x[i - 1]
            } else {
                0.0
            }
        })
        .collect();
    let wo = WelchOptions::default();
    let mut g = c.benchmark_group("welch");
    g.sample_size(10);
    g.bench_function("h1_h2_coherence_1M_samples", |b| {
        b.iter(|| welch_frf(1e4, black_box(&x), black_box(&y), &wo).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
