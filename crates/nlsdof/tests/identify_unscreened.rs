//! The unscreened in-family suite of issue 24 (`support::synthetic::
//! unscreened_case`: single levels, backbone shifts up to 40 %, softening
//! with jumps, Coulomb, damping only, 120–300 steps, phase or not; nothing
//! rejected for being hard), fitted with the default plan.
//!
//! Every case is judged first by **optimum found**: the fit's Eq 31 cost
//! (the model's own sweeps, with the fitted gain) is at most 1.05× the
//! truth's on the same noisy data. The truth is a feasible point of every
//! fit, so this needs no identifiability argument. A miss must be
//! **flagged** (`converged: false` or the adequacy check failing); a flag
//! on a fit that found the optimum is a false alarm.
//!
//! `cargo test --release -p nlsdof --test identify_unscreened -- --ignored`
//! runs the 200 cases (targets: optimum found in at least 199, no miss
//! without a flag, false alarms at most 2 %, gain freed at most 5 %).

mod support;

use nlsdof::identification::models::*;
use nlsdof::identification::objective::evaluate;
use nlsdof::identification::{identify, FitPlan, ModelKind, Status};
use support::synthetic::{unscreened_case, Case};

struct Outcome {
    optimum: bool,
    flagged: bool,
    gain_freed: bool,
    line: String,
}

fn eq31(c: &Case, th: &nlsdof::identification::Parameters) -> f64 {
    evaluate(&c.data, th, false).map_or(f64::INFINITY, |e| e.cost())
}

fn run(c: &Case) -> Outcome {
    let plan = FitPlan::new(ModelKind::Generalised);
    let t0 = std::time::Instant::now();
    let id = match identify(&c.data, &plan, &|_| {}) {
        Ok(id) => id,
        Err(e) => {
            return Outcome {
                optimum: false,
                flagged: true,
                gain_freed: false,
                line: format!("{}: ERROR {e}", c.description),
            }
        }
    };
    let dt = t0.elapsed().as_secs_f64();
    let th = &id.fit.theta;
    let (cf, ct) = (eq31(c, th), eq31(c, &c.truth));
    let optimum = cf <= 1.05 * ct;
    let flagged = !id.fit.converged || !id.adequacy.adequate;
    let gain_freed = id.spec.status[GAIN] == Status::Free;
    let censored = id.spec.censored.iter().filter(|&&x| x).count();
    let line = format!(
        "{}: cost/truth {:8.3} {}{} | rho {:.3}/{:.3} eta {:.3}/{:.3} gain {:.4} | res/noise {:.2} (worst curve mean z2 {:.2}, peaks {:.2}){}{} | {:.2}s{}",
        c.description,
        cf / ct,
        if optimum { "opt" } else { "MISS" },
        if flagged { " FLAGGED" } else { "" },
        th[RHO],
        c.truth[RHO],
        th[ETA],
        c.truth[ETA],
        th[GAIN],
        id.adequacy.ratio,
        id.curves
            .iter()
            .map(|c| c.noise.mean_z2)
            .fold(0.0f64, f64::max),
        id.adequacy.peak_ratio,
        if censored > 0 {
            format!(", {censored} censored")
        } else {
            String::new()
        },
        id.warning().map(|w| format!(" | {}", w.replace('\n', " / "))).unwrap_or_default(),
        dt,
        if gain_freed { " GAIN FREED" } else { "" },
    ) + if id.adequacy.escalation.is_empty() {
        ""
    } else {
        " ESCALATED"
    };
    Outcome {
        optimum,
        flagged,
        gain_freed,
        line,
    }
}

struct Tally {
    n: usize,
    optimum: usize,
    missed: usize,
    false_alarms: usize,
    gain_freed: usize,
}

fn suite(seeds: std::ops::Range<u64>) -> Tally {
    use rayon::prelude::*;
    let cases: Vec<Case> = seeds.clone().into_par_iter().map(unscreened_case).collect();
    let out: Vec<Outcome> = cases.par_iter().map(run).collect();
    let mut t = Tally {
        n: out.len(),
        optimum: 0,
        missed: 0,
        false_alarms: 0,
        gain_freed: 0,
    };
    for o in &out {
        println!("{}", o.line);
        t.optimum += usize::from(o.optimum);
        t.missed += usize::from(!o.optimum && !o.flagged);
        t.false_alarms += usize::from(o.optimum && o.flagged);
        t.gain_freed += usize::from(o.gain_freed);
    }
    println!(
        "\nunscreened suite: optimum found {}/{}; misses without a flag {}; false alarms {}; gain freed {}",
        t.optimum, t.n, t.missed, t.false_alarms, t.gain_freed
    );
    for o in out.iter().filter(|o| !o.optimum || o.flagged) {
        println!("  {}", o.line);
    }
    t
}

/// The first 24 unscreened cases (CI): no miss without a flag, at most one
/// false alarm, the optimum found in at least 23.
#[test]
fn unscreened_suite_ci_subset() {
    let t = suite(0..24);
    assert_eq!(t.missed, 0, "misses without a flag");
    assert!(t.false_alarms <= 1, "{} false alarms", t.false_alarms);
    assert!(t.optimum >= 23, "optimum found in {} of {}", t.optimum, t.n);
    assert!(
        t.gain_freed <= 2,
        "gain freed in {} of {}",
        t.gain_freed,
        t.n
    );
}

/// The 200 cases: issue 24's targets.
#[test]
#[ignore = "200 cases: cargo test --release -p nlsdof --test identify_unscreened -- --ignored"]
fn unscreened_suite_full() {
    let t = suite(0..200);
    assert!(t.optimum >= 199, "optimum found in {} of 200", t.optimum);
    assert_eq!(t.missed, 0, "misses without a flag");
    assert!(t.false_alarms <= 4, "{} false alarms", t.false_alarms);
    assert!(t.gain_freed <= 10, "gain freed in {}", t.gain_freed);
}

/// Writes case `NLSDOF_CASE` as CSV to `NLSDOF_CASE_OUT` (for inspecting a
/// case with the CLI).
#[test]
#[ignore = "writes one case: NLSDOF_CASE=seed NLSDOF_CASE_OUT=file"]
fn write_case() {
    support::synthetic::write_case_from_env(unscreened_case);
}
