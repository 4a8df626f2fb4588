//! Reproduces the jump-weighted beam fits of docs/identification.md
//! (clamped-clamped beam, cc_beam_no_magnet_24C, up-sweeps, free gain):
//!
//! ```text
//! cargo run --release -p nlsdof-studies --example beam_jumps -- \
//!     MODEL LAMBDA STARTS DECIMATE [GAIN_MAX RHO_MAX ETA_MIN BETA_BOUND_FACTOR]
//! ```
//!
//! LAMBDA = 0 fits Eq 31 alone; DECIMATE keeps every n-th step (plus the
//! peak). Prints the parameters, the Eq 31 cost and the predicted vs
//! measured jump-down frequencies per level. With the environment variable
//! `MINIMAX` set, runs the minimax check instead ([`minimax`]).
use nlsdof::identification::models::*;
use nlsdof::identification::*;
const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map(String::as_str).unwrap_or("duffing");
    let weight: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let starts: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let decimate: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(4);
    let dir = std::path::Path::new(
        "/work/shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C",
    );
    let full =
        nlsdof_io::stepped_sine_data::read_beam_dir(dir, nlsdof_io::stepped_sine_data::Runs::Up)
            .unwrap();
    let mut data = full.clone();
    for c in data.curves.iter_mut() {
        let keep: Vec<usize> = (0..c.omegas.len())
            .filter(|i| i % decimate == 0)
            .chain(std::iter::once(c.peak_index()))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        c.omegas = keep.iter().map(|&i| c.omegas[i]).collect();
        c.amplitudes = keep.iter().map(|&i| c.amplitudes[i]).collect();
        c.weights = keep.iter().map(|&i| c.weights[i]).collect();
        c.phases = None;
    }
    let kind: ModelKind = match model {
        "duffing" => ModelKind::Duffing,
        "generalised" => ModelKind::Generalised,
        "generalised-stiffness" => ModelKind::GeneralisedStiffness,
        "duffing-quadratic" => ModelKind::DuffingQuadratic,
        "duffing-generalised" => ModelKind::DuffingGeneralised,
        _ => panic!("model"),
    };
    let mut spec = FitSpec::new(kind, &data);
    spec.free("gain").unwrap();
    if let Some(g) = args.get(5).and_then(|s| s.parse::<f64>().ok()) {
        spec.set_bounds("gain", 0.1, g).unwrap();
    }
    if let Some(g) = args.get(6).and_then(|s| s.parse::<f64>().ok()) {
        spec.set_bounds("rho", 0.0, g).unwrap();
    }
    if let Some(g) = args.get(8).and_then(|s| s.parse::<f64>().ok()) {
        let (lo, hi) = spec.bounds[BETA];
        spec.set_bounds("beta", lo, hi * g).unwrap();
    }
    if let Some(g) = args.get(7).and_then(|s| s.parse::<f64>().ok()) {
        if spec.status[ETA] == Status::Free {
            spec.set_bounds("eta", g, 8.0).unwrap();
        }
    }
    if std::env::var_os("MINIMAX").is_some() {
        minimax(&data, &full, &spec, weight);
        return;
    }
    let t0 = std::time::Instant::now();
    let opts = FitOptions {
        starts,
        ..FitOptions::default()
    };
    let res = if weight > 0.0 {
        fit_with_jumps(&data, &spec, &opts, weight, &|| {}).unwrap()
    } else {
        fit(&data, &spec, &opts, &|| {}).unwrap()
    };
    let jumps = predicted_jumps(&full, &res.theta).unwrap();
    println!(
        "{model} w={weight} starts={starts} ({:?}, {} it {}): theta {:?} eq31 cost {:e}",
        t0.elapsed(),
        res.iterations,
        res.termination,
        res.theta,
        res.cost
    );
    let full_cost = nlsdof::identification::jumps::eq31_cost(&full, &res.theta).unwrap();
    println!("full-data Eq31 cost {full_cost:e}");
    let mut worst = 0.0f64;
    for (c, pj) in full.curves.iter().zip(&jumps) {
        let meas = c.measured_jump(2.0).expect("measured jump") / TWO_PI;
        match pj {
            Some(p) => {
                let pred = p / TWO_PI;
                let d = 100.0 * (pred - meas) / meas;
                worst = worst.max(d.abs());
                println!("| {} | {meas:.2} | {pred:.2} | {d:+.2} |", c.level);
            }
            None => {
                worst = f64::INFINITY;
                println!("| {} | {meas:.2} | none |", c.level);
            }
        }
    }
    println!("worst {worst:.2} %");
}

/// Minimax check (`beam_jumps minimax MODEL LAMBDA`): iteratively
/// reweighted jump residuals (Lawson's algorithm, whose fixed point is the
/// minimax fit of the jump errors), each pass a local LM fit from the
/// previous optimum. Prints the worst predicted jump error per pass.
pub fn minimax(data: &Dataset, full: &Dataset, spec: &FitSpec, lambda: f64) {
    use nlsdof::identification::jumps::WithJumps;
    use nlsdof::identification::levenberg_marquardt::{minimise, LmOptions};
    use nlsdof::identification::objective::Problem;
    let problem = Problem::new(data, spec).unwrap();
    let mut wj = WithJumps::new(problem, lambda);
    let base: Vec<f64> = wj.targets.iter().map(|t| t.scale).collect();
    let (lo, hi) = wj.problem.u_bounds();
    let mut u = wj.problem.u_of(&spec.start);
    let mut w = vec![1.0; base.len()];
    for pass in 0..15 {
        let r = minimise(&wj, &u, &lo, &hi, &LmOptions::default()).unwrap();
        u = r.u;
        let th = wj.problem.theta(&u);
        let errs = wj.relative_errors(&th);
        let jumps = predicted_jumps(full, &th).unwrap();
        let worst = full
            .curves
            .iter()
            .zip(&jumps)
            .map(|(c, p)| {
                let m = c.measured_jump(2.0).unwrap();
                p.map(|p| (p / m - 1.0).abs() * 100.0)
                    .unwrap_or(f64::INFINITY)
            })
            .fold(0.0, f64::max);
        println!(
            "pass {pass}: worst {worst:.2} %  errors {:?}  theta {th:?}",
            errs.iter()
                .map(|e| e.map(|e| (e * 1e4).round() / 1e2))
                .collect::<Vec<_>>()
        );
        // Lawson's update: w ← w |e| / Σ w|e| (converges to the Chebyshev fit)
        let we: Vec<f64> = w
            .iter()
            .zip(&errs)
            .map(|(w, e)| w * e.map(f64::abs).unwrap_or(1.0))
            .collect();
        let sum: f64 = we.iter().sum();
        for (k, t) in wj.targets.iter_mut().enumerate() {
            w[k] = (we[k] / sum * w.len() as f64).max(1e-6);
            t.scale = base[k] * w[k].sqrt();
        }
    }
}
