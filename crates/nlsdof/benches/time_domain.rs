//! Speed of the time-domain output-error fit (issue 15 target, criterion):
//! the Duffing fit (6 model parameters + the initial state = 8 free) of the
//! Silverbox estimation data, 65,062 samples, ≤ 10 s on 2 cores; also one
//! simulation with sensitivities of that range. Skipped when
//! `../shared/data/silverbox` (or `SILVERBOX_DIR`) is absent.
//! Figures: docs/silverbox.md.

use criterion::{criterion_group, criterion_main, Criterion};
use nlsdof::identification::time_domain::{
    fit, output_and_sensitivities, Record, SampleRange, TimeFitOptions,
};
use nlsdof::identification::ModelKind;
use std::path::PathBuf;
use std::time::Duration;

/// V1, V2 of SNLS80mV.csv (header `"V1","V2",`, trailing comma).
fn silverbox() -> Option<(Vec<f64>, Vec<f64>)> {
    let dir = std::env::var_os("SILVERBOX_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/silverbox")
        });
    let text = std::fs::read_to_string(dir.join("SNLS80mV.csv")).ok()?;
    let (mut u, mut y) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        let mut f = line.split(',');
        u.push(f.next()?.trim().parse().ok()?);
        y.push(f.next()?.trim().parse().ok()?);
    }
    Some((u, y))
}

fn bench(c: &mut Criterion) {
    let Some((u, y)) = silverbox() else {
        eprintln!("time_domain bench: Silverbox data not found, skipped");
        return;
    };
    let fs = 610.3515625;
    let rec = Record::new(&u, &y, fs).unwrap();
    let range = SampleRange::new(40650, 105712);
    let mut g = c.benchmark_group("time_domain");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("silverbox_duffing_fit_65062", |b| {
        b.iter(|| {
            let f = fit(&rec, range, ModelKind::Duffing, &TimeFitOptions::default()).unwrap();
            assert!(f.termination.converged());
            f.rms
        })
    });
    let theta = {
        let f = fit(&rec, range, ModelKind::Duffing, &TimeFitOptions::default()).unwrap();
        f.theta
    };
    g.bench_function("silverbox_sensitivities_65062", |b| {
        b.iter(|| {
            output_and_sensitivities(&theta, &u[40650..105712], fs)
                .unwrap()
                .0[0]
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
