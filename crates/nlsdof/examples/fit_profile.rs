//! Profiling driver for the identification benchmarks (same problem as
//! `benches/fit.rs`): `cargo run --release --example fit_profile -- local|global N`.

use nlsdof::identification::models::*;
use nlsdof::identification::objective::model_amplitudes;
use nlsdof::identification::*;
use nlsdof::SweepDirection;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn data(theta: &[f64; N_PARAMS]) -> Dataset {
    let gammas = [0.05, 0.1, 0.2, 0.3, 0.4];
    let mut recs = Vec::new();
    for (l, &g) in gammas.iter().enumerate() {
        for i in 0..200 {
            let f = 8.0 + 5.0 * i as f64 / 199.0;
            recs.push(Record {
                level: format!("L{l}"),
                gamma: g,
                omega: TWO_PI * f,
                amplitude: 1.0,
                phase: None,
                direction: SweepDirection::Up,
                weight: 1.0,
            });
        }
    }
    let mut d = Dataset::from_records(&recs).unwrap();
    let amps = model_amplitudes(&d, theta).unwrap();
    for (c, a) in d.curves.iter_mut().zip(amps) {
        c.amplitudes = a;
    }
    d
}

fn truth() -> [f64; N_PARAMS] {
    let wn = TWO_PI * 10.0;
    let rho: f64 = 2.6;
    let eta: f64 = 1.7;
    let a_ref: f64 = 0.01;
    let beta = 0.08 * wn * wn / (nlsdof::power_law::g_unchecked(rho) * a_ref.powf(rho));
    let kappa = 0.8 * 0.02 * wn / (nlsdof::power_law::g_unchecked(eta) * (wn * a_ref).powf(eta));
    [wn * wn, 0.02 * wn, beta, rho, kappa, eta, 1.0]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map(String::as_str).unwrap_or("local");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let th = truth();
    let d = data(&th);
    let t0 = std::time::Instant::now();
    if mode == "local" {
        let mut spec = FitSpec::new(ModelKind::Generalised, &d);
        let mut start = th;
        start[ALPHA] *= 1.01;
        for j in [DELTA, BETA, KAPPA] {
            start[j] *= 1.05;
        }
        start[RHO] += 0.1;
        start[ETA] -= 0.1;
        spec.start = start;
        for _ in 0..n {
            let r = fit(&d, &spec, &FitOptions::default(), &|| {}).unwrap();
            eprintln!("{} it {} cost {:e}", r.termination, r.iterations, r.cost);
        }
    } else {
        let spec = FitSpec::new(ModelKind::Generalised, &d);
        let r = fit(
            &d,
            &spec,
            &FitOptions {
                starts: n,
                seed: 1,
                ..FitOptions::default()
            },
            &|| {},
        )
        .unwrap();
        eprintln!(
            "{} it {} cost {:e} minima {} theta {:?}",
            r.termination,
            r.iterations,
            r.cost,
            r.minima.len(),
            r.theta
        );
        for m in r.minima.iter().take(5) {
            eprintln!("  cost {:e} count {} {:?}", m.cost, m.count, m.theta);
        }
    }
    eprintln!("elapsed {:?}", t0.elapsed());
}
