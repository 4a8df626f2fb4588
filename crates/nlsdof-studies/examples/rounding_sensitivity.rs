//! How far the default fit of a beam set moves when its data move by a
//! rounding error: every amplitude multiplied by `1 + k·1e-15`, k = 0…5 (a
//! thousand times below the vibrometer's resolution), each fitted with the
//! default plan (`nlsdof fit --beam-dir DIR --model MODEL`). Prints, per k,
//! the objective, ρ, η, the gain, the worst upper-branch RMS (% of the peak,
//! over the points before each measured jump), the curves read as censored,
//! and whether the self-check says the model fits. The numbers of
//! docs/identification.md ("These fits move with rounding").
//!
//! ```text
//! cargo run --release -p nlsdof-studies --example rounding_sensitivity -- [BEAM_DIR] [MODEL]
//! ```
use nlsdof::identification::*;
use nlsdof_io::stepped_sine_data::{read_beam_dir, Runs};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = args.get(1).cloned().unwrap_or_else(|| {
        "../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C".into()
    });
    let kind = args
        .get(2)
        .and_then(|s| ModelKind::parse(s))
        .unwrap_or(ModelKind::Generalised);
    let data = match read_beam_dir(std::path::Path::new(&dir), Runs::Up) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{dir}: {e}");
            std::process::exit(1);
        }
    };
    println!("{dir}, {kind}, default fit; amplitudes x (1 + k 1e-15)\n");
    println!("| k | objective | rho | eta | gain | worst upper-branch RMS [% of peak] | censored | adequate | time [s] |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for k in 0..=5 {
        let mut d = data.clone();
        for c in &mut d.curves {
            for a in &mut c.amplitudes {
                *a *= 1.0 + k as f64 * 1e-15;
            }
        }
        let t = Instant::now();
        let id = match identify(&d, &FitPlan::new(kind), &|_| {}) {
            Ok(id) => id,
            Err(e) => {
                println!("| {k} | error: {e} | | | | | | | |");
                continue;
            }
        };
        let secs = t.elapsed().as_secs_f64();
        let worst = id
            .data
            .curves
            .iter()
            .zip(&id.curves)
            .filter_map(|(c, r)| {
                let peak = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
                r.upper_branch_rms.map(|u| 100.0 * u / peak)
            })
            .fold(f64::NAN, f64::max);
        let th = &id.fit.theta;
        println!(
            "| {k} | {:.3e} | {:.3} | {:.3} | {:.3} | {:.1} | {} of {} | {} | {secs:.2} |",
            id.fit.objective,
            th.rho,
            th.eta,
            th.gain,
            worst,
            id.spec.censored.iter().filter(|&&c| c).count(),
            id.spec.censored.len(),
            id.adequacy.adequate,
        );
    }
}
