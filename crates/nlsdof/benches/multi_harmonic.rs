//! `cargo bench -p nlsdof --bench multi_harmonic`: pseudo-arclength
//! continuation of the strong Duffing oscillator (examples/duffing-strong.toml,
//! γ = 2 m/s²) over 8–16 Hz with ≥ 500 points and both folds located.
//! Issue 14 targets: H = 9 ≤ 20 ms, H = 1 ≤ 2 ms. Also: one Hill stability
//! evaluation at H = 9.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nlsdof::multi_harmonic::*;
use nlsdof::*;
use std::f64::consts::PI;

fn duffing() -> NormalisedModel {
    Model::linear(1.0, 3947.84, 1.2566)
        .unwrap()
        .with_stiffness(1.2e7, 2.0)
        .unwrap()
        .normalised()
        .unwrap()
}

fn run(h: usize, stability: bool) -> (usize, usize) {
    let br = continue_in_omega(
        &duffing(),
        2.0,
        h,
        2.0 * PI * 8.0,
        2.0 * PI * 16.0,
        HarmonicSettings::default(),
        &ContinuationOptions {
            stability,
            ..ContinuationOptions::default()
        },
    )
    .unwrap();
    assert!(br.warning.is_none());
    assert!(br.points.len() >= 500 && br.limit_points.len() == 2);
    (br.points.len(), br.limit_points.len())
}

fn bench(c: &mut Criterion) {
    let (n9, _) = run(9, false);
    let (n1, _) = run(1, false);
    eprintln!("points: H=9 {n9}, H=1 {n1}");
    c.bench_function(
        "mhb continuation duffing 8-16 Hz H=9 (>=500 pts, 2 folds)",
        |b| b.iter(|| run(black_box(9), false)),
    );
    c.bench_function(
        "mhb continuation duffing 8-16 Hz H=1 (>=500 pts, 2 folds)",
        |b| b.iter(|| run(black_box(1), false)),
    );
    c.bench_function(
        "mhb continuation duffing 8-16 Hz H=9 with Hill stability",
        |b| b.iter(|| run(black_box(9), true)),
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
