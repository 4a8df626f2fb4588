//! Speed of the time-domain output-error fit (criterion): the Duffing fit
//! (6 model parameters + the initial state = 8 free) of the Silverbox
//! estimation data, 65,062 samples (issue 26: ≤ 2 s on 2 cores), the
//! generalised fit (rho, eta free: 11 free; issue 26: ≤ 10 s); also one
//! simulation with sensitivities of that range. Skipped when
//! `../shared/data/silverbox` (or `SILVERBOX_DIR`) is absent.
//! Figures: docs/silverbox.md.

use criterion::{criterion_group, criterion_main, Criterion};
use nlsdof::identification::time_domain::{
    fit_time_domain, output_and_sensitivities, SampleRange, TimeFitOptions, TimeRecord,
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
    let rec = TimeRecord::new(&u, &y, fs).unwrap();
    let range = SampleRange::new(40650, 105712);
    let mut g = c.benchmark_group("time_domain");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("silverbox_duffing_fit_65062", |b| {
        b.iter(|| {
            let f = fit_time_domain(&rec, range, ModelKind::Duffing, &TimeFitOptions::default())
                .unwrap();
            assert!(f.termination.converged());
            f.rms
        })
    });
    // issue 26: the generalised fit (rho, eta free: 11 free) in at most 10 s
    g.bench_function("silverbox_generalised_fit_65062", |b| {
        b.iter(|| {
            let f = fit_time_domain(
                &rec,
                range,
                ModelKind::Generalised,
                &TimeFitOptions::default(),
            )
            .unwrap();
            assert!(f.termination.converged());
            f.rms
        })
    });
    let theta = {
        let f =
            fit_time_domain(&rec, range, ModelKind::Duffing, &TimeFitOptions::default()).unwrap();
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

/// `decay` on 29,000 samples (a simulated Duffing free decay at 1 kHz, the
/// size of the FRID record; target ≤ 50 ms), start found from the data.
fn bench_decay(c: &mut Criterion) {
    use nlsdof::identification::decay::{analyse, DecayOptions};
    use nlsdof::identification::time_domain::{simulate_output, TimeModel};
    use nlsdof::simulation::State;
    let wn = 2.0 * std::f64::consts::PI * 37.0;
    let tm = TimeModel {
        model: nlsdof::NormalisedModel {
            alpha: wn * wn,
            delta: 2.0 * 0.003 * wn,
            beta: 0.1 * wn * wn / 0.75,
            rho: 2.0,
            kappa: 0.0,
            eta: 0.0,
        },
        gain: 0.0,
        input_offset: 0.0,
        output_offset: 0.0,
    };
    let fs = 1000.0;
    let mut x = vec![0.0; 2000];
    x.extend(simulate_output(&tm, &vec![0.0; 27_000], fs, State { x: 1.0, v: 0.0 }).unwrap());
    for (k, v) in x.iter_mut().enumerate().take(2000) {
        *v = (wn * k as f64 / fs).sin();
    }
    let mut g = c.benchmark_group("decay");
    g.sample_size(20);
    g.bench_function("decay_29000", |b| {
        b.iter(|| {
            analyse(&x, fs, &DecayOptions::default())
                .unwrap()
                .envelope_error
        })
    });
    g.finish();
}

criterion_group!(benches, bench, bench_decay);
criterion_main!(benches);
