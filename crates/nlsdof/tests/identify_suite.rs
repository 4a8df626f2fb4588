//! The seeded synthetic identification suite of issue 10: in-family cases
//! (generator in `support/synthetic.rs`, not fixed files), identified with
//! the default plan (`FitPlan::new(ModelKind::Generalised)`, no tuning).
//!
//! A case passes when
//! * both exponents are within 0.1 of the truth,
//! * α is within 0.5 %,
//! * δ is within 10 % or inside its reported 95 % interval,
//! * every fitted curve is within 1.5 % of the noise-free truth curve
//!   (RMS of `a_model − a_true` over the curve, relative to its peak).
//!
//! At 1 % noise the data of many cases do not carry the information to pin
//! an exponent to 0.1: the Cramér–Rao bound (`support::synthetic::exponent_crlb`,
//! the smallest spread of any unbiased estimator) is wider. Each case's
//! bound is printed, and a second criterion, *efficient*, accepts an
//! exponent within `max(0.1, 2.58 σ_CRLB)` (where 99 % of the estimates of
//! an ideal estimator fall), the other criteria unchanged.
//!
//! CI runs the first 24 cases; the full 100 run with
//! `cargo test --release -p nlsdof --test identify_suite -- --ignored`.

mod support;

use nlsdof::identification::models::*;
use nlsdof::identification::{identify, FitPlan, ModelKind, Weighting};
use support::synthetic::{case, exponent_crlb, Case};

struct Outcome {
    /// The criterion (exponents within 0.1).
    pass: bool,
    /// Exponents within 0.1 *or* inside their reported 95 % interval (the
    /// other criteria unchanged): the estimate is consistent with the truth
    /// even where 1 % data do not pin an exponent to 0.1.
    consistent: bool,
    /// α, δ and the curves within their limits (the fit found the data's
    /// optimum; exponents not judged).
    fitted: bool,
    /// Exponents within `max(0.1, 2.58 σ_CRLB)`, the rest as `pass`.
    efficient: bool,
    /// The data allow the criterion: `1.96 σ_CRLB ≤ 0.1` for both.
    informative: bool,
    line: String,
}

fn run(c: &Case, weighting: Weighting) -> Outcome {
    let plan = FitPlan::new(ModelKind::Generalised).with_weighting(weighting);
    let t = &c.truth;
    let (sd_rho, sd_eta) = exponent_crlb(c).unwrap_or((f64::INFINITY, f64::INFINITY));
    let informative = 1.96 * sd_rho <= 0.1 && 1.96 * sd_eta <= 0.1;
    let res = match identify(&c.data, &plan, &|_| {}) {
        Ok(r) => r,
        Err(e) => {
            return Outcome {
                pass: false,
                consistent: false,
                fitted: false,
                efficient: false,
                informative,
                line: format!("{}: ERROR {e}", c.description),
            }
        }
    };
    let th = &res.fit.theta;
    let d_rho = (th[RHO] - t[RHO]).abs();
    let d_eta = (th[ETA] - t[ETA]).abs();
    let e_alpha = (th[ALPHA] / t[ALPHA] - 1.0).abs();
    let e_delta = (th[DELTA] / t[DELTA] - 1.0).abs();
    let in_ci = |name: &str, j: usize| {
        res.fit.intervals_valid()
            && res.fit.uncertainty.as_ref().is_some_and(|u| {
                u.names
                    .iter()
                    .position(|n| *n == name)
                    .is_some_and(|k| u.lower[k] <= t[j] && t[j] <= u.upper[k])
            })
    };
    let delta_in_ci = in_ci("delta", DELTA);
    // curves vs the noise-free truth
    let mut worst_curve = 0.0f64;
    let mut off = 0;
    for (ci, cur) in res.data.curves.iter().enumerate() {
        let n = cur.omegas.len();
        let clean = &c.clean[ci];
        let peak = clean.iter().fold(0.0f64, |m, &a| m.max(a)).max(1e-300);
        let ms: f64 = (0..n)
            .map(|k| (res.fit.model_amplitudes[off + k] - clean[k]).powi(2))
            .sum::<f64>()
            / n as f64;
        worst_curve = worst_curve.max(ms.sqrt() / peak);
        off += n;
    }
    let rest = e_alpha <= 0.005 && (e_delta <= 0.10 || delta_in_ci) && worst_curve <= 0.015;
    let pass = d_rho <= 0.1 && d_eta <= 0.1 && rest;
    let consistent =
        (d_rho <= 0.1 || in_ci("rho", RHO)) && (d_eta <= 0.1 || in_ci("eta", ETA)) && rest;
    let efficient =
        d_rho <= 0.1f64.max(2.58 * sd_rho) && d_eta <= 0.1f64.max(2.58 * sd_eta) && rest;
    let line = format!(
        "{}: {} | rho {:.3} (d {:.3}, CRLB sd {:.3}) eta {:.3} (d {:.3}, CRLB sd {:.3}) alpha {:+.3}% delta {:+.2}%{} curves {:.3}% | gain {} phase {} {}",
        c.description,
        if pass {
            "pass"
        } else if efficient {
            "FAIL (exponent within 2.58 CRLB sd)"
        } else if consistent {
            "FAIL (exponent within its 95 % interval)"
        } else {
            "FAIL"
        },
        th[RHO],
        d_rho,
        sd_rho,
        th[ETA],
        d_eta,
        sd_eta,
        100.0 * (th[ALPHA] / t[ALPHA] - 1.0),
        100.0 * (th[DELTA] / t[DELTA] - 1.0),
        if delta_in_ci { " (in CI)" } else { "" },
        100.0 * worst_curve,
        match res.spec.status[GAIN] {
            nlsdof::identification::Status::Free => format!("free {:.4}", th[GAIN]),
            _ => "fixed".into(),
        },
        res.phase
            .map(|p| format!("s{:+} c{:.3}", p.sign, p.offset))
            .unwrap_or_else(|| "-".into()),
        res.fit.warning().unwrap_or_default(),
    );
    Outcome {
        pass,
        consistent,
        fitted: rest,
        efficient,
        informative,
        line,
    }
}

/// Counts of a suite run.
struct Tally {
    n: usize,
    passed: usize,
    consistent: usize,
    fitted: usize,
    efficient: usize,
    informative: usize,
    passed_informative: usize,
}

fn suite(seeds: std::ops::Range<u64>, weighting: Weighting) -> Tally {
    use rayon::prelude::*;
    let n = seeds.end - seeds.start;
    let outcomes: Vec<Outcome> = seeds
        .clone()
        .into_par_iter()
        .map(|s| run(&case(s), weighting))
        .collect();
    let mut passed = 0;
    let mut consistent = 0;
    let mut fitted = 0;
    let mut efficient = 0;
    let mut informative = 0;
    let mut passed_informative = 0;
    for o in &outcomes {
        println!("{}", o.line);
        passed += usize::from(o.pass);
        consistent += usize::from(o.consistent);
        fitted += usize::from(o.fitted);
        efficient += usize::from(o.efficient);
        informative += usize::from(o.informative);
        passed_informative += usize::from(o.informative && o.pass);
    }
    let failed: Vec<&String> = outcomes
        .iter()
        .filter(|o| !o.pass)
        .map(|o| &o.line)
        .collect();
    println!("\nsynthetic suite: {passed} of {n} cases pass (exponents within 0.1); {consistent} of {n} with exponents within 0.1 or inside their 95 % interval; {efficient} of {n} within max(0.1, 2.58 CRLB sd); {fitted} of {n} with alpha, delta and the curves within their limits");
    println!("the data allow exponents within 0.1 (1.96 CRLB sd <= 0.1 for both) in {informative} of {n} cases; {passed_informative} of those pass");
    if !failed.is_empty() {
        println!("failures:");
        for f in failed {
            println!("  {f}");
        }
    }
    Tally {
        n: n as usize,
        passed,
        consistent,
        fitted,
        efficient,
        informative,
        passed_informative,
    }
}

/// Runs the first 24 cases with `weighting` and asserts the floors
/// `(efficient, consistent, strict)`; every case must be fitted.
fn ci_subset(weighting: Weighting, floors: (usize, usize, usize)) {
    let t = suite(0..24, weighting);
    let n = t.n;
    println!(
        "{weighting:?}: strict {}/{n}, consistent {}/{n}, efficient {}/{n}, fitted {}/{n}",
        t.passed, t.consistent, t.efficient, t.fitted
    );
    assert_eq!(t.fitted, n, "{} of {n} fitted", t.fitted);
    assert!(t.efficient >= floors.0, "{} of {n} efficient", t.efficient);
    assert!(
        t.consistent >= floors.1,
        "{} of {n} consistent",
        t.consistent
    );
    assert!(t.passed >= floors.2, "{} of {n} strict", t.passed);
    // every case whose data allow the 0.1 passes it
    assert_eq!(
        t.passed_informative, t.informative,
        "{} of the {} cases whose data allow exponents within 0.1 pass",
        t.passed_informative, t.informative
    );
}

/// Measured (docs/identification.md), default (absolute, Eq 31) weights:
/// the fit reaches the data's optimum (alpha, delta, curves) on all 24 and
/// is within 2.58 CRLB sd of the true exponents on 23; the exponent
/// criterion (within 0.1) holds on 6, since at 1 % noise the data of 22 of
/// these 24 cases do not pin both exponents to 0.1 (1.96 CRLB sd > 0.1).
/// The floors guard against regressions; the 97 % is asserted by
/// the full suites.
#[test]
fn synthetic_suite_ci_subset() {
    ci_subset(Weighting::default(), (23, 19, 6));
}

/// Relative weights, the maximum-likelihood choice for the generator's
/// proportional noise: the reported intervals cover the truth (measured
/// 23 of 24 consistent, against 19 with the default weights).
#[test]
fn synthetic_suite_ci_subset_relative() {
    ci_subset(Weighting::Relative, (23, 22, 8));
}

#[test]
#[ignore = "full suite (100 cases): cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full() {
    let t = suite(0..100, Weighting::default());
    assert!(t.passed >= 97, "{} of {} passed", t.passed, t.n);
}

#[test]
#[ignore = "full suite (100 cases), efficiency criterion: cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full_efficiency() {
    let t = suite(0..100, Weighting::default());
    assert!(t.efficient >= 97, "{} of {} efficient", t.efficient, t.n);
}

/// The same with relative weights (`--weighting relative`), the
/// maximum-likelihood choice for the generator's proportional noise.
#[test]
#[ignore = "full suite (100 cases), relative weights: cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full_relative() {
    let t = suite(0..100, Weighting::Relative);
    assert!(t.efficient >= 97, "{} of {} efficient", t.efficient, t.n);
    assert!(t.consistent >= 90, "{} of {} consistent", t.consistent, t.n);
}
