//! Speed of the staged identification (issue 10 targets, criterion):
//! equation-error stage on 5 levels × 200 points (≤ 1 ms), a 64 × 64
//! exponent landscape (≤ 0.5 s on 2 cores), the default fit of a beam set
//! (≤ 2 s; skipped when ../shared is absent) and of 1,000,000 data rows
//! (≤ 10 s). Figures: docs/identification.md, "Speed". Each fit starts with
//! an empty sweep memo (`recent_sweeps::forget`): a first fit is measured.

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{criterion_group, criterion_main, Criterion};
use nlsdof::identification::equation_error::{solve_magnitude, solve_phase, Prepared, Terms};
use nlsdof::identification::landscape::{landscape, Axis, LandscapePhase};
use nlsdof::identification::models::*;
use nlsdof::identification::objective::FitSpec;
use nlsdof::identification::*;
use nlsdof::SweepDirection;
use std::time::Duration;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn truth() -> Parameters {
    let wn = TWO_PI * 10.0;
    let rho: f64 = 2.6;
    let eta: f64 = 1.7;
    let a_ref: f64 = 0.01;
    let beta = 0.08 * wn * wn / (nlsdof::power_law::g_unchecked(rho) * a_ref.powf(rho));
    let kappa = 0.8 * 0.02 * wn / (nlsdof::power_law::g_unchecked(eta) * (wn * a_ref).powf(eta));
    Parameters::from([wn * wn, 0.02 * wn, beta, rho, kappa, eta, 1.0])
}

/// `levels` × `steps` exact-HB up-sweep points over 8–13 Hz, with phases.
fn data(theta: &Parameters, levels: usize, steps: usize) -> Dataset {
    let gammas: Vec<f64> = (0..levels)
        .map(|l| 0.05 + 0.35 * l as f64 / (levels.max(2) - 1) as f64)
        .collect();
    support::fixtures::hb_sweeps(
        theta,
        &gammas,
        (8.0, 13.0),
        steps,
        &[SweepDirection::Up],
        Some((1.0, 0.0)),
    )
}

fn bench(c: &mut Criterion) {
    let th = truth();
    let d = data(&th, 5, 200);
    let spec = FitSpec::new(ModelKind::Generalised, &d);
    let prep = Prepared::new(&d, spec.scales).unwrap();
    let terms = Terms {
        stiffness: true,
        damping: true,
        gain: None,
    };
    let mut g = c.benchmark_group("identify");
    g.sample_size(20).measurement_time(Duration::from_secs(5));
    g.bench_function("equation_error_phase_5x200", |b| {
        b.iter(|| solve_phase(&prep, terms, 2.6, 1.7, None, 0.0).unwrap())
    });
    g.bench_function("equation_error_magnitude_5x200", |b| {
        b.iter(|| solve_magnitude(&prep, terms, 2.6, 1.7, None).unwrap())
    });
    let rho = Axis {
        min: 0.0,
        max: 10.0,
        n: 64,
    };
    let eta = Axis {
        min: -1.0,
        max: 8.0,
        n: 64,
    };
    g.bench_function("landscape_64x64_phase_5x200", |b| {
        b.iter(|| {
            landscape(
                &prep,
                terms,
                rho,
                eta,
                LandscapePhase::Detect { delay: 0.0 },
            )
            .unwrap()
        })
    });
    g.bench_function("landscape_64x64_magnitude_5x200", |b| {
        b.iter(|| landscape(&prep, terms, rho, eta, LandscapePhase::Ignore).unwrap())
    });
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function("default_fit_generalised_5x200", |b| {
        b.iter(|| {
            recent_sweeps::forget();
            identify(&d, &FitPlan::new(ModelKind::Generalised), &|_| {}).unwrap()
        })
    });
    // the clamped-clamped beam (real data), if the shared data are present
    let beam = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C");
    if let Ok(d) = read_beam(&beam) {
        for kind in [ModelKind::Duffing, ModelKind::Generalised] {
            g.bench_function(format!("default_fit_beam_24C_{kind}"), |b| {
                b.iter(|| {
                    recent_sweeps::forget();
                    identify(&d, &FitPlan::new(kind), &|_| {}).unwrap()
                })
            });
        }
    }
    // 1,000,000 rows: 10 levels x 100,000 steps
    let big = data(&th, 10, 100_000);
    g.sample_size(10).measurement_time(Duration::from_secs(60));
    g.bench_function("default_fit_generalised_1e6_rows", |b| {
        b.iter(|| {
            recent_sweeps::forget();
            identify(&big, &FitPlan::new(ModelKind::Generalised), &|_| {}).unwrap()
        })
    });
    g.finish();
}

/// Minimal reader of the beam files (the core has no I/O crate; the same
/// parsing as nlsdof-io's `read_beam_dir`: decimal commas, up-run columns).
fn read_beam(dir: &std::path::Path) -> Result<Dataset, ()> {
    let mut recs = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .map_err(|_| ())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    names.sort();
    for p in names {
        let stem = p.file_stem().unwrap().to_string_lossy().to_string();
        let lvl: f64 = stem
            .trim_start_matches("frf_")
            .trim_end_matches('g')
            .parse()
            .map_err(|_| ())?;
        let text = std::fs::read_to_string(&p).map_err(|_| ())?;
        for line in text.lines().skip(2) {
            let f: Vec<f64> = line
                .split('\t')
                .filter_map(|s| s.trim().replace(',', ".").parse().ok())
                .collect();
            if f.len() < 3 {
                continue;
            }
            let w = TWO_PI * f[0];
            recs.push(Record {
                level: stem.clone(),
                gamma: lvl * 9.80665,
                omega: w,
                amplitude: f[1] / w,
                phase: Some(f[2].to_radians()),
                direction: SweepDirection::Up,
                weight: 1.0,
            });
        }
    }
    Dataset::from_records(&recs).map_err(|_| ())
}

criterion_group!(benches, bench);
criterion_main!(benches);
