//! The Silverbox generalised fits (heavy: run with `--ignored --nocapture`;
//! need `../shared/data/silverbox` or `SILVERBOX_DIR`): the 9-parameter
//! generalised model and the same with δ held at 0 (8 parameters: α, β, ρ,
//! κ, η, gain and the two offsets). Prints the estimation RMS, the three
//! official test scores and the fitted parameters (docs/silverbox.md).

mod support;
use nlsdof::identification::time_domain::{
    fit_time_domain, predict_with, SampleRange, TimeFitOptions, TimeRecord, DELTA, TIME_PARAM_NAMES,
};
use nlsdof::identification::ModelKind;

fn silverbox() -> (Vec<f64>, Vec<f64>) {
    support::fixtures::silverbox_record()
}

fn run(label: &str, opts: &TimeFitOptions) {
    let (u, y) = silverbox();
    let rec = TimeRecord::new(&u, &y, 610.3515625).unwrap();
    let t = std::time::Instant::now();
    let f = fit_time_domain(
        &rec,
        SampleRange::new(40650, 105712),
        ModelKind::Generalised,
        opts,
    )
    .unwrap();
    let fit_s = t.elapsed().as_secs_f64();
    let scores: Vec<f64> = [(100, 40575), (100, 32100), (105712, 127400)]
        .iter()
        .map(|&(a, b)| {
            1000.0
                * predict_with(&rec, SampleRange::new(a, b), &f.model(), &f.discretisation)
                    .unwrap()
                    .rms
        })
        .collect();
    let se = |p: usize| {
        f.uncertainty.as_ref().and_then(|u| {
            u.names
                .iter()
                .position(|n| *n == TIME_PARAM_NAMES[p])
                .map(|k| u.std_errors[k])
        })
    };
    let params: Vec<String> = (0..9)
        .map(|p| match se(p) {
            Some(s) => format!("{} = {:.6} (se {s:.3e})", TIME_PARAM_NAMES[p], f.theta[p]),
            None => format!("{} = {:.6} (held)", TIME_PARAM_NAMES[p], f.theta[p]),
        })
        .collect();
    eprintln!(
        "Silverbox {label}: {} free (with x0, v0), estimation RMS {:.4} mV, scores [mV] {scores:.4?}, \
         {} ({} iterations of the last fit), {} substeps (integration error / output error {:.4}), fit {fit_s:.2} s\n  {}",
        f.free.len(),
        1000.0 * f.rms,
        f.termination,
        f.iterations,
        f.integration.substeps,
        f.integration.integration_error / f.integration.output_error,
        params.join(", ")
    );
    assert!(f.termination.converged());
    assert!(f.integration.met);
}

#[test]
#[ignore]
fn silverbox_generalised() {
    run("generalised", &TimeFitOptions::default());
}

#[test]
#[ignore]
fn silverbox_generalised_delta_held_at_zero() {
    run(
        "generalised, delta = 0",
        &TimeFitOptions {
            fixed: vec![(DELTA, 0.0)],
            ..TimeFitOptions::default()
        },
    );
}
