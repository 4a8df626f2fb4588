//! Speed of `identification::inspect` (target: ≤ 50 ms for a beam set of
//! 12 curves × 1024 points): the clamped-clamped beam's 6 levels with both
//! runs (skipped when ../shared is absent), and a synthetic set of the same
//! size (exact HB sweeps, 6 levels × up and down × 1024 steps, phases).
//! Figures: docs/inspect.md, "Speed".

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{criterion_group, criterion_main, Criterion};
use nlsdof::identification::inspect::{inspect, InspectOptions};
use nlsdof::identification::*;
use nlsdof::SweepDirection;
use std::time::Duration;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn synthetic() -> Dataset {
    let wn = TWO_PI * 145.0;
    let (rho, eta, a_ref) = (2.0f64, 1.0f64, 1e-3f64);
    let beta = 0.3 * wn * wn / (nlsdof::power_law::g_unchecked(rho) * a_ref.powf(rho));
    let kappa = 0.5 * 0.004 * wn / (nlsdof::power_law::g_unchecked(eta) * (wn * a_ref).powf(eta));
    let th = Parameters::from([wn * wn, 0.004 * wn, beta, rho, kappa, eta, 1.0]);
    let gammas: Vec<f64> = (0..6).map(|l| 0.4 + 0.2 * l as f64).collect();
    support::fixtures::hb_sweeps(
        &th,
        &gammas,
        (120.0, 230.0),
        1024,
        &[SweepDirection::Up, SweepDirection::Down],
        Some((1.0, 0.0)),
    )
}

/// Minimal reader of the beam files, both runs (the core has no I/O crate;
/// the parsing of nlsdof-io's `read_beam_dir`: decimal commas, velocity
/// amplitudes of the up and the down run).
fn read_beam(dir: &std::path::Path) -> Result<Dataset, ()> {
    let mut recs = Vec::new();
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .map_err(|_| ())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "txt"))
        .collect();
    names.sort();
    for p in names {
        let stem = p.file_stem().ok_or(())?.to_string_lossy().to_string();
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
            if f.len() < 5 {
                continue;
            }
            let w = TWO_PI * f[0];
            for (col, dir) in [(1, SweepDirection::Up), (3, SweepDirection::Down)] {
                recs.push(Record {
                    level: stem.clone(),
                    gamma: lvl * 9.80665,
                    omega: w,
                    amplitude: f[col] / w,
                    phase: Some(f[col + 1].to_radians()),
                    direction: dir,
                    weight: 1.0,
                });
            }
        }
    }
    Dataset::from_records(&recs).map_err(|_| ())
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("inspect");
    g.sample_size(30).measurement_time(Duration::from_secs(10));
    let opts = InspectOptions::default();
    let beam = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C");
    if let Ok(d) = read_beam(&beam) {
        assert_eq!(d.curves.len(), 12);
        g.bench_function("beam_24C_12x1024", |b| {
            b.iter(|| inspect(&d, &opts).unwrap())
        });
    }
    let d = synthetic();
    g.bench_function("synthetic_12x1024", |b| {
        b.iter(|| inspect(&d, &opts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
