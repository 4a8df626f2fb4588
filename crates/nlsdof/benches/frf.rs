//! `cargo bench -p nlsdof --bench frf`: 5 levels × 200 steps of a stepped-sine
//! FRF with branch following (issue target: ≤ 0.1 ms for the wing).

#[path = "../tests/support/mod.rs"]
mod support;
use support::fixtures::wing;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nlsdof::*;
use std::f64::consts::PI;

fn duffing() -> Model {
    let wn = 2.0 * PI * 10.0;
    Model::linear(1.0, wn * wn, 2.0 * 0.01 * wn)
        .unwrap()
        .with_stiffness(4.0e7, 2.0)
        .unwrap()
}

fn frf(model: &Model, gammas: &[f64], f0: f64, f1: f64, dir: SweepDirection) -> usize {
    let omegas: Vec<f64> = (0..200)
        .map(|i| 2.0 * PI * (f0 + (f1 - f0) * i as f64 / 199.0))
        .collect();
    let mut n = 0;
    for &g in gammas {
        let r = ForcedResponse::new(model, g, Formulation::HarmonicBalance).unwrap();
        let s = r.sweep(&omegas, dir).unwrap();
        n += s.points.len() + s.jumps.len();
    }
    n
}

fn bench(c: &mut Criterion) {
    let wing = wing();
    let wing_levels = [0.41, 0.62, 0.81, 1.00, 1.23];
    c.bench_function("frf wing 5x200 sweep up (real exponents)", |b| {
        b.iter(|| frf(black_box(&wing), &wing_levels, 5.2, 5.6, SweepDirection::Up))
    });
    let omegas: Vec<f64> = (0..200)
        .map(|i| 2.0 * PI * (5.2 + 0.4 * i as f64 / 199.0))
        .collect();
    // sweep_levels: the sweeps in parallel; level_responses: the same with
    // each level's phase-quadrature point, what the Python
    // `Model.sweep(gamma=[5 levels], f_hz=200 points)` runs (the reference
    // of its call-overhead figure)
    type Levels =
        fn(&Model, &[f64], &[f64], SweepDirection, Formulation) -> Result<usize, SolveError>;
    let runs: [(&str, Levels); 2] = [
        (
            "frf wing 5x200 sweep up, levels in parallel (sweep_levels)",
            |m, g, w, d, f| sweep_levels(m, g, w, d, f).map(|v| v.len()),
        ),
        (
            "frf wing 5x200 level_responses (the Python sweep's computation)",
            |m, g, w, d, f| level_responses(m, g, w, d, f).map(|v| v.len()),
        ),
    ];
    for (name, run) in runs {
        c.bench_function(name, |b| {
            b.iter(|| {
                run(
                    black_box(&wing),
                    &wing_levels,
                    &omegas,
                    SweepDirection::Up,
                    Formulation::HarmonicBalance,
                )
                .unwrap()
            })
        });
    }
    let duff = duffing();
    let duff_levels = [0.25, 0.5, 1.0, 1.5, 2.0];
    c.bench_function("frf strong duffing 5x200 sweep up (jumps)", |b| {
        b.iter(|| {
            frf(
                black_box(&duff),
                &duff_levels,
                8.0,
                22.0,
                SweepDirection::Up,
            )
        })
    });
    c.bench_function("frf strong duffing 5x200 sweep down (jumps)", |b| {
        b.iter(|| {
            frf(
                black_box(&duff),
                &duff_levels,
                8.0,
                22.0,
                SweepDirection::Down,
            )
        })
    });
    let r = ForcedResponse::new(&duff, 1.0, Formulation::HarmonicBalance).unwrap();
    c.bench_function("steady_states duffing, 3 roots", |b| {
        b.iter(|| r.steady_states(black_box(2.0 * PI * 14.0)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3)).warm_up_time(std::time::Duration::from_secs(1));
    targets = bench
}
criterion_main!(benches);
