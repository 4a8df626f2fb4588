//! Identification speed: local fit of the generalised model to 5 levels ×
//! 200 steps (target ≤ 20 ms) and a 256-start global search (target ≤ 2 s
//! on 2 cores; GlobalSearch-style: 256 trial points scored, local runs from
//! the best, see `identification::global`). Synthetic noise-free data from
//! the exact harmonic balance. Figures: docs/identification.md, "Speed".

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{criterion_group, criterion_main, Criterion};
use nlsdof::identification::models::*;
use nlsdof::identification::*;
use nlsdof::SweepDirection;
use std::time::Duration;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// 5 levels × 200 exact-HB up-sweep points over 8–13 Hz.
fn data(theta: &Parameters) -> Dataset {
    let gammas = [0.05, 0.1, 0.2, 0.3, 0.4];
    support::fixtures::hb_sweeps(
        theta,
        &gammas,
        (8.0, 13.0),
        200,
        &[SweepDirection::Up],
        None,
    )
}

fn truth() -> Parameters {
    let wn = TWO_PI * 10.0;
    let rho: f64 = 2.6;
    let eta: f64 = 1.7;
    let a_ref: f64 = 0.01;
    let beta = 0.08 * wn * wn / (nlsdof::power_law::g_unchecked(rho) * a_ref.powf(rho));
    let kappa = 0.8 * 0.02 * wn / (nlsdof::power_law::g_unchecked(eta) * (wn * a_ref).powf(eta));
    Parameters::from([wn * wn, 0.02 * wn, beta, rho, kappa, eta, 1.0])
}

fn bench(c: &mut Criterion) {
    let th = truth();
    let d = data(&th);
    let mut spec = FitSpec::new(ModelKind::Generalised, &d);
    let mut start = th;
    start[ALPHA] *= 1.01;
    for j in [DELTA, BETA, KAPPA] {
        start[j] *= 1.05;
    }
    start[RHO] += 0.1;
    start[ETA] -= 0.1;
    spec.start = start;
    let mut g = c.benchmark_group("fit");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("local_generalised_5x200", |b| {
        b.iter(|| fit(&d, &spec, &FitOptions::default(), &|| {}).unwrap())
    });
    let gspec = FitSpec::new(ModelKind::Generalised, &d);
    g.bench_function("global_generalised_5x200_256_starts", |b| {
        b.iter(|| {
            fit(
                &d,
                &gspec,
                &FitOptions {
                    starts: 256,
                    seed: 1,
                    ..FitOptions::default()
                },
                &|| {},
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
