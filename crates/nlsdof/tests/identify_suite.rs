//! The seeded synthetic identification suite of issue 10: in-family cases
//! (generator in `support/synthetic.rs`, not fixed files), identified with
//! the default plan (`FitPlan::new(ModelKind::Generalised)`, no tuning).
//!
//! A case passes when
//! * both exponents are within 0.1 of the truth,
//! * α is within 0.5 %,
//! * δ is within 10 % or inside its reported 95 % interval,
//! * every fitted curve is within 1.5 % of the noise-free truth curve: RMS
//!   over the curve, relative to its peak, of the distance from each true
//!   point to the fitted model's nearest steady state within one frequency
//!   step, with at most one step per true jump on another branch (see
//!   `run`: the vertical error of the fitted sweep is ill-conditioned at a
//!   fold and is printed beside it).
//!
//! **The suite's cases** (`synthetic_suite_full`, and the first 24 in CI)
//! come from `Design::informative()` through `informative_case`: a draw is
//! kept when its Cramér–Rao bound (`exponent_crlb`, from the truth and the
//! noise, never from a fit) allows both exponents within 0.1 with 99 %
//! probability (`2.58 σ_CRLB ≤ 0.1`) and a softening case stays inside its
//! potential well. The rejected draws are counted in the output.
//!
//! **The legacy design** (`case`: 120 steps, strengths set at the linear
//! peak amplitude, no screen) is kept as a second suite: there most cases
//! cannot pin an exponent to 0.1 at 1 % noise, and a second criterion,
//! *efficient*, accepts an exponent within `max(0.1, 2.58 σ_CRLB)`.
//!
//! `cargo test --release -p nlsdof --test identify_suite -- --ignored` runs
//! the full suites (100 cases each).

mod support;

use nlsdof::harmonic_balance::{ForcedResponse, Formulation};
use nlsdof::identification::models::*;
use nlsdof::identification::{identify, FitPlan, ModelKind, Weighting};
use support::synthetic::{case, exponent_crlb, informative_case, Case, Design, SCREEN_Z};

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
    let informative = SCREEN_Z * sd_rho <= 0.1 && SCREEN_Z * sd_eta <= 0.1;
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
                u.index(name)
                    .is_some_and(|k| u.lower[k] <= t[j] && t[j] <= u.upper[k])
            })
    };
    let delta_in_ci = in_ci("delta", DELTA);
    // curves vs the noise-free truth, two ways:
    // * `worst_sweep` (printed only): RMS of the fitted sweep (the branch
    //   the model's sweep follows) minus the truth, relative to the peak.
    //   Near a fold dA/dΩ is infinite, so this vertical error is
    //   ill-conditioned there: one frequency step of disagreement on a jump
    //   costs (drop)/sqrt(n) of the peak, e.g. 3.5 % for a 70 % drop on
    //   400 steps, however well the rest of the curve fits.
    // * `worst_curve` (judged): the same with each true point compared with
    //   the nearest steady state of the fitted model within one frequency
    //   step (the data's resolution) of its frequency, on any branch; plus
    //   `misplaced`: points where the fitted sweep is on another branch
    //   than the truth (more than 10 % of the peak apart), allowed one per
    //   true jump (a jump placed one step early or late).
    let model = res.fit.model();
    let mut worst_sweep = 0.0f64;
    let mut worst_curve = 0.0f64;
    let mut misplaced_ok = true;
    let mut off = 0;
    for (ci, cur) in res.data.curves.iter().enumerate() {
        let n = cur.omegas.len();
        let clean = &c.clean[ci];
        let peak = clean.iter().fold(0.0f64, |m, &a| m.max(a)).max(1e-300);
        let fr = ForcedResponse::from_normalised(
            &model,
            th[GAIN] * cur.gamma,
            Formulation::HarmonicBalance,
        )
        .ok();
        let (mut ss_sweep, mut ss_curve, mut misplaced) = (0.0, 0.0, 0usize);
        for k in 0..n {
            let a_sweep = res.fit.model_amplitudes[off + k];
            ss_sweep += (a_sweep - clean[k]).powi(2);
            let step = if k + 1 < n {
                cur.omegas[k + 1] - cur.omegas[k]
            } else {
                cur.omegas[k] - cur.omegas[k - 1]
            }
            .abs();
            let nearest = (-4..=4)
                .filter_map(|j| {
                    let w = cur.omegas[k] + step * j as f64 / 4.0;
                    let set = fr.as_ref()?.steady_states(w).ok()?;
                    // no root: the mass sticks (Coulomb), amplitude 0
                    let first = if set.roots.is_empty() {
                        0.0
                    } else {
                        f64::INFINITY
                    };
                    Some(set.roots.iter().map(|r| r.amplitude).fold(first, |m, a| {
                        if (a - clean[k]).abs() < (m - clean[k]).abs() {
                            a
                        } else {
                            m
                        }
                    }))
                })
                .fold(f64::INFINITY, |m, a| {
                    if (a - clean[k]).abs() < (m - clean[k]).abs() {
                        a
                    } else {
                        m
                    }
                });
            ss_curve += (nearest - clean[k]).powi(2);
            misplaced += usize::from((a_sweep - clean[k]).abs() > 0.1 * peak);
        }
        worst_sweep = worst_sweep.max((ss_sweep / n as f64).sqrt() / peak);
        worst_curve = worst_curve.max((ss_curve / n as f64).sqrt() / peak);
        misplaced_ok &= misplaced <= c.clean_jumps[ci];
        off += n;
    }
    let rest = e_alpha <= 0.005
        && (e_delta <= 0.10 || delta_in_ci)
        && worst_curve <= 0.015
        && misplaced_ok;
    let pass = d_rho <= 0.1 && d_eta <= 0.1 && rest;
    let consistent =
        (d_rho <= 0.1 || in_ci("rho", RHO)) && (d_eta <= 0.1 || in_ci("eta", ETA)) && rest;
    let efficient =
        d_rho <= 0.1f64.max(2.58 * sd_rho) && d_eta <= 0.1f64.max(2.58 * sd_eta) && rest;
    let line = format!(
        "{}: {} | rho {:.3} (d {:.3}, CRLB sd {:.3}) eta {:.3} (d {:.3}, CRLB sd {:.3}) alpha {:+.3}% delta {:+.2}%{} curves {:.3}% (sweep {:.3}%{}) | gain {} phase {} {}",
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
        100.0 * worst_sweep,
        if misplaced_ok { "" } else { ", a jump misplaced" },
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
    suite_of(seeds, weighting, &|s| (case(s), 0))
}

/// The suite on the informative design: every case can pin its exponents
/// to 0.1 (`informative_case`).
fn informative_suite(seeds: std::ops::Range<u64>, weighting: Weighting) -> Tally {
    let design = Design::informative();
    suite_of(seeds, weighting, &|s| {
        informative_case(s, &design).expect("an informative draw within MAX_DRAWS")
    })
}

fn suite_of(
    seeds: std::ops::Range<u64>,
    weighting: Weighting,
    generate: &(dyn Fn(u64) -> (Case, u64) + Sync),
) -> Tally {
    use rayon::prelude::*;
    let n = seeds.end - seeds.start;
    let drawn: Vec<(Case, u64)> = seeds.clone().into_par_iter().map(generate).collect();
    let redraws: u64 = drawn.iter().map(|d| d.1).sum();
    let outcomes: Vec<Outcome> = drawn.par_iter().map(|(c, _)| run(c, weighting)).collect();
    let mut passed = 0;
    let mut consistent = 0;
    let mut fitted = 0;
    let mut efficient = 0;
    let mut informative = 0;
    let mut passed_informative = 0;
    if redraws > 0 {
        println!("{redraws} uninformative draws rejected before these {n} cases");
    }
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
    println!("the data allow exponents within 0.1 (2.58 CRLB sd <= 0.1 for both) in {informative} of {n} cases; {passed_informative} of those pass");
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

/// Runs the first 24 cases (of the informative design, or of the legacy
/// one without a screen) with `weighting` and asserts the floors
/// `(fitted, efficient, consistent, strict)`, measured values that guard
/// against regressions (the 97 % is asserted by the full suite).
fn ci_subset(informative: bool, weighting: Weighting, floors: (usize, usize, usize, usize)) {
    let t = if informative {
        informative_suite(0..24, weighting)
    } else {
        suite(0..24, weighting)
    };
    let n = t.n;
    println!(
        "{weighting:?}: strict {}/{n}, consistent {}/{n}, efficient {}/{n}, fitted {}/{n}",
        t.passed, t.consistent, t.efficient, t.fitted
    );
    assert!(t.fitted >= floors.0, "{} of {n} fitted", t.fitted);
    assert!(t.efficient >= floors.1, "{} of {n} efficient", t.efficient);
    assert!(
        t.consistent >= floors.2,
        "{} of {n} consistent",
        t.consistent
    );
    assert!(t.passed >= floors.3, "{} of {n} strict", t.passed);
    if !informative {
        // every case whose data allow the 0.1 passes it
        assert_eq!(
            t.passed_informative, t.informative,
            "{} of the {} cases whose data allow exponents within 0.1 pass",
            t.passed_informative, t.informative
        );
    }
}

/// The criterion on the first 24 informative cases (default plan,
/// default weights). Measured: 22 of 24 pass; the two failures are listed
/// in docs/identification.md (seed 16: a model fold on the wrong side of a
/// measured step, ρ 4 σ_CRLB off; draw 5000019: one level, the Eq 31
/// optimum itself lies 8 σ_CRLB from the truth).
#[test]
fn synthetic_suite_ci_subset() {
    ci_subset(true, Weighting::default(), (23, 22, 22, 22));
}

/// The legacy design (no screen, 120 steps, strengths at `A`), default
/// weights. Most of these cases do not pin both exponents to 0.1 at 1 %
/// noise (2 of 24 do), so the floors are mostly of the fitted and
/// efficient criteria. Measured: 24 fitted, 23 efficient, 19 consistent,
/// 6 strict.
#[test]
fn synthetic_suite_ci_subset_legacy() {
    ci_subset(false, Weighting::default(), (24, 23, 19, 6));
}

/// The legacy design with relative weights, the maximum-likelihood choice
/// for the generator's proportional noise. Measured: 24 fitted,
/// 23 efficient, 23 consistent, 9 strict.
#[test]
fn synthetic_suite_ci_subset_legacy_relative() {
    ci_subset(false, Weighting::Relative, (24, 23, 23, 9));
}

/// The suite: 100 informative cases, default plan, at least 97 pass.
#[test]
#[ignore = "full suite (100 cases): cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full() {
    let t = informative_suite(0..100, Weighting::default());
    assert!(t.passed >= 97, "{} of {} passed", t.passed, t.n);
}

/// The legacy design, 100 cases, efficiency criterion.
#[test]
#[ignore = "full suite (100 cases), legacy design: cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full_legacy() {
    let t = suite(0..100, Weighting::default());
    assert!(t.efficient >= 97, "{} of {} efficient", t.efficient, t.n);
}

/// The legacy design with relative weights (`--weighting relative`).
#[test]
#[ignore = "full suite (100 cases), legacy design, relative weights: cargo test --release -p nlsdof --test identify_suite -- --ignored"]
fn synthetic_suite_full_legacy_relative() {
    let t = suite(0..100, Weighting::Relative);
    assert!(t.efficient >= 97, "{} of {} efficient", t.efficient, t.n);
    assert!(t.consistent >= 90, "{} of {} consistent", t.consistent, t.n);
}

/// Writes case `NLSDOF_CASE` of the legacy design (`NLSDOF_DESIGN=legacy`)
/// or the informative one as CSV to `NLSDOF_CASE_OUT`.
#[test]
#[ignore = "writes one case: NLSDOF_CASE=seed NLSDOF_CASE_OUT=file [NLSDOF_DESIGN=legacy]"]
fn write_case() {
    support::synthetic::write_case_from_env(|seed| {
        if std::env::var("NLSDOF_DESIGN").as_deref() == Ok("legacy") {
            case(seed)
        } else {
            informative_case(seed, &Design::informative()).unwrap().0
        }
    });
}
