//! The staged identification (issue 10): equation-error estimator with and
//! without phase (exact on noise-free data, phase convention detected),
//! phase Jacobian against finite differences, the exponent landscape, the
//! `identify` entry point on the cases that defeated the plain Eq 31 fit,
//! honest convergence reports and typed errors for bad input.

mod support;

use nlsdof::harmonic_balance::SweepDirection;
use nlsdof::identification::equation_error::{
    solve_magnitude, solve_magnitude_lifted, solve_phase, PhaseConvention, Prepared, Terms,
};
use nlsdof::identification::landscape::{landscape, Axis, LandscapePhase};
use nlsdof::identification::models::*;
use nlsdof::identification::objective::{evaluate_with_phase, FitSpec};
use nlsdof::identification::output_error::JumpReading;
use nlsdof::identification::*;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

use support::fixtures::hb_sweeps as data;

/// Duffing + quadratic damping with jumps (f_n = 10 Hz, ζ = 1 %).
fn duffing_quadratic() -> Parameters {
    let wn = TWO_PI * 10.0;
    Parameters::from([wn * wn, 2.0 * 0.01 * wn, 4.0e6, 2.0, 0.05, 1.0, 1.0])
}

/// The Duffing + quadratic damping set: 3 levels, up and down
/// sweeps with jumps, 120 steps over 8–14 Hz, noise free.
fn duffing_quadratic_data(t: &Parameters) -> Dataset {
    data(
        t,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        120,
        &[SweepDirection::Up, SweepDirection::Down],
        None,
    )
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn equation_error_with_phase_is_exact_and_detects_the_convention() {
    let t = duffing_quadratic();
    // a lead convention with an offset of 120 degrees and a free gain of 1.7
    let mut tg = t;
    tg[GAIN] = 1.7;
    let d = data(
        &tg,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        120,
        &[SweepDirection::Up, SweepDirection::Down],
        Some((-1.0, 120f64.to_radians())),
    );
    let spec = FitSpec::new(ModelKind::DuffingQuadratic, &d);
    let prep = Prepared::new(&d, spec.scales).unwrap();
    let terms = Terms {
        stiffness: true,
        damping: true,
        gain: None,
    };
    let f = solve_phase(&prep, terms, 2.0, 1.0, None, 0.0).unwrap();
    let conv = f.phase.unwrap();
    assert_eq!(conv.sign, -1.0);
    assert!((conv.offset - 120f64.to_radians()).abs() < 1e-9, "{conv:?}");
    for j in [ALPHA, DELTA, BETA, KAPPA, GAIN] {
        assert!(
            rel(f.theta[j], tg[j]) < 1e-8,
            "{j}: {} vs {}",
            f.theta[j],
            tg[j]
        );
    }
    // known convention, gain held: same coefficients
    let held = Terms {
        gain: Some(1.7),
        ..terms
    };
    let f2 = solve_phase(
        &prep,
        held,
        2.0,
        1.0,
        Some(PhaseConvention {
            sign: -1.0,
            offset: 120f64.to_radians(),
            delay: 0.0,
        }),
        0.0,
    )
    .unwrap();
    for j in [ALPHA, DELTA, BETA, KAPPA] {
        assert!(rel(f2.theta[j], tg[j]) < 1e-8, "{j}");
    }
}

#[test]
fn equation_error_without_phase_is_exact() {
    for (t, kind) in [
        (duffing_quadratic(), ModelKind::DuffingQuadratic),
        // Coulomb friction + softening stiffness rho = 1.5
        (
            {
                let wn = TWO_PI * 10.0;
                Parameters::from([wn * wn, 2.0 * 0.01 * wn, -2.0e4, 1.5, 0.1, -1.0, 1.0])
            },
            ModelKind::Generalised,
        ),
    ] {
        let d = data(
            &t,
            &[1.0, 2.0, 3.0],
            (8.0, 12.0),
            100,
            &[SweepDirection::Up],
            None,
        );
        let spec = FitSpec::new(kind, &d);
        let prep = Prepared::new(&d, spec.scales).unwrap();
        let terms = Terms {
            stiffness: true,
            damping: true,
            gain: None,
        };
        // the lifted closed form alone is exact on exact data
        let l = solve_magnitude_lifted(&prep, terms, t[RHO], t[ETA]).unwrap();
        for j in [ALPHA, DELTA, BETA, KAPPA, GAIN] {
            assert!(
                rel(l[j], t[j]) < 1e-7,
                "{kind}: lifted {j}: {} vs {}",
                l[j],
                t[j]
            );
        }
        let (f, _) = solve_magnitude(&prep, terms, t[RHO], t[ETA], None).unwrap();
        for j in [ALPHA, DELTA, BETA, KAPPA, GAIN] {
            assert!(
                rel(f.theta[j], t[j]) < 1e-6,
                "{kind}: {j}: {} vs {}",
                f.theta[j],
                t[j]
            );
        }
    }
}

#[test]
fn phase_jacobian_matches_finite_differences() {
    let t = Parameters::from([3900.0, 1.2, 3.0e6, 2.3, 0.04, 0.7, 1.1]);
    let mut d = data(
        &t,
        &[1.0, 2.5],
        (8.0, 13.0),
        60,
        &[SweepDirection::Up],
        Some((1.0, 0.0)),
    );
    // perturb the data so that residuals are not zero
    for c in &mut d.curves {
        for (k, a) in c.amplitudes.iter_mut().enumerate() {
            *a *= 1.0 + 0.01 * ((k as f64) * 0.7).sin();
        }
    }
    let at = |th: &Parameters| evaluate_with_phase(&d, th, true, Some(1.0)).unwrap();
    let e = at(&t);
    let jac = e.jacobian.unwrap();
    let n = d.len();
    for j in 0..N_PARAMS {
        let h = 1e-6 * t[j].abs().max(1e-3);
        let (mut tp, mut tm) = (t, t);
        tp[j] += h;
        tm[j] -= h;
        let (rp, rm) = (at(&tp).residuals, at(&tm).residuals);
        // phase residuals only (after the n amplitude residuals)
        for i in n..rp.len() {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            let an = jac[i][j];
            let scale = jac[i]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs() * t[j].abs().max(1e-3)))
                / t[j].abs().max(1e-3);
            assert!(
                (fd - an).abs() <= 1e-5 * scale.max(1e-12) + 1e-9,
                "param {j} row {i}: fd {fd} analytic {an}"
            );
        }
    }
}

#[test]
fn landscape_minimum_is_at_the_truth_and_profile_covers_it() {
    let t = duffing_quadratic();
    let d = data(
        &t,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        100,
        &[SweepDirection::Up],
        Some((1.0, 0.0)),
    );
    let spec = FitSpec::new(ModelKind::Generalised, &d);
    let prep = Prepared::new(&d, spec.scales).unwrap();
    let terms = Terms {
        stiffness: true,
        damping: true,
        gain: Some(1.0),
    };
    let rho = Axis {
        min: 0.0,
        max: 5.0,
        n: 21,
    }; // 2.0 is a node
    let eta = Axis {
        min: -1.0,
        max: 4.0,
        n: 21,
    }; // 1.0 is a node
    let l = landscape(
        &prep,
        terms,
        rho,
        eta,
        LandscapePhase::Detect { delay: 0.0 },
    )
    .unwrap();
    let (i, j) = l.best().unwrap();
    assert!(
        (l.rho[i] - 2.0).abs() < 1e-12 && (l.eta[j] - 1.0).abs() < 1e-12,
        "{:?}",
        (l.rho[i], l.eta[j])
    );
    let p = l.profile_interval(0).unwrap();
    assert!(p.lower.unwrap() <= 2.0 && 2.0 <= p.upper.unwrap());
    // zero-size grid
    let z = Axis {
        min: 0.0,
        max: 5.0,
        n: 0,
    };
    assert!(matches!(
        landscape(&prep, terms, z, eta, LandscapePhase::Ignore),
        Err(landscape::LandscapeError::EmptyGrid { n_rho: 0, .. })
    ));
    assert!(FitPlan::new(ModelKind::Generalised)
        .with_grid(0, 4)
        .is_err());
}

/// The landscape computes each node's columns and the phases' sin/cos once
/// per axis value and shares them between nodes (`NodeColumns`); the
/// oracle is the single-node solve, which computes them itself: every
/// node's cost and θ must be the same bit for bit, with the convention
/// detected or known, the gain free or held.
#[test]
fn landscape_nodes_equal_single_node_solves_bit_for_bit() {
    let mut t = duffing_quadratic();
    t[GAIN] = 1.3;
    let d = data(
        &t,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        60,
        &[SweepDirection::Up, SweepDirection::Down],
        Some((-1.0, 0.4)),
    );
    let spec = FitSpec::new(ModelKind::Generalised, &d);
    let prep = Prepared::new(&d, spec.scales).unwrap();
    let rho = Axis {
        min: 0.5,
        max: 4.5,
        n: 5,
    };
    let eta = Axis {
        min: -1.0,
        max: 3.0,
        n: 4,
    };
    let known = PhaseConvention {
        sign: -1.0,
        offset: 0.4,
        delay: 1e-4,
    };
    for gain in [None, Some(1.3)] {
        let terms = Terms {
            stiffness: true,
            damping: true,
            gain,
        };
        for (phase, conv, delay) in [
            (LandscapePhase::Detect { delay: 2e-4 }, None, 2e-4),
            (LandscapePhase::Known(known), Some(known), known.delay),
        ] {
            let l = landscape(&prep, terms, rho, eta, phase).unwrap();
            for (i, &r) in l.rho.iter().enumerate() {
                for (j, &e) in l.eta.iter().enumerate() {
                    let node = l.fit_at(i, j).expect("every node solves");
                    let single = solve_phase(&prep, terms, r, e, conv, delay).unwrap();
                    assert_eq!(node.cost.to_bits(), single.cost.to_bits(), "{r} {e}");
                    assert_eq!(node.theta, single.theta, "{r} {e}");
                    assert_eq!(node.phase, single.phase, "{r} {e}");
                }
            }
        }
    }
}

/// The first example: Duffing + quadratic damping with jumps, up and
/// down sweeps at 3 levels, where the plain Eq 31 multistart ended 2,700×
/// above the truth. Noise free here: the default staged fit must recover
/// the parameters.
#[test]
fn default_fit_recovers_duffing_quadratic_with_jumps() {
    let t = duffing_quadratic();
    let d = duffing_quadratic_data(&t);
    let r = identify(&d, &FitPlan::new(ModelKind::DuffingQuadratic), &|_| {}).unwrap();
    assert!(!r.fit.levels.is_empty());
    for j in [ALPHA, DELTA, BETA, KAPPA] {
        assert!(
            rel(r.fit.theta[j], t[j]) < 1e-6,
            "{j}: {} vs {}",
            r.fit.theta[j],
            t[j]
        );
    }
    // and the generalised model finds the exponents
    let r = identify(&d, &FitPlan::new(ModelKind::Generalised), &|_| {}).unwrap();
    assert!((r.fit.theta[RHO] - 2.0).abs() < 1e-4, "{:?}", r.fit.theta);
    assert!((r.fit.theta[ETA] - 1.0).abs() < 1e-4, "{:?}", r.fit.theta);
}

/// Softening stiffness (ρ = 1, β < 0), up and down sweeps: the default
/// chooses the sign from the data.
#[test]
fn default_fit_chooses_softening_from_the_data() {
    let wn = TWO_PI * 10.0;
    let t = Parameters::from([wn * wn, 2.0 * 0.01 * wn, -3.0e5, 1.0, 0.0, 0.0, 1.0]);
    let d = data(
        &t,
        &[0.5, 1.0, 1.5],
        (8.5, 11.0),
        120,
        &[SweepDirection::Up, SweepDirection::Down],
        None,
    );
    let r = identify(&d, &FitPlan::new(ModelKind::GeneralisedStiffness), &|_| {}).unwrap();
    assert!(r.fit.theta[BETA] < 0.0);
    assert!((r.fit.theta[RHO] - 1.0).abs() < 1e-4, "{:?}", r.fit.theta);
    assert!(rel(r.fit.theta[ALPHA], t[ALPHA]) < 1e-6);
}

#[test]
fn a_fit_stopped_early_says_so() {
    let t = duffing_quadratic();
    let d = data(
        &t,
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        80,
        &[SweepDirection::Up],
        None,
    );
    let mut plan = FitPlan::new(ModelKind::Generalised);
    plan.lm.max_iterations = 1;
    plan.grid = (5, 5); // coarse: the start is far from the optimum
    let r = identify(&d, &plan, &|_| {}).unwrap();
    assert!(!r.fit.converged);
    assert!(!r.fit.intervals_valid());
    let w = r.fit.warning().unwrap();
    assert!(w.contains("did not converge"), "{w}");
}

#[test]
fn bad_input_is_a_typed_error() {
    let t = duffing_quadratic();
    // one level, constant amplitude: nothing separable
    let recs: Vec<Record> = (0..10)
        .map(|i| Record {
            level: "a".into(),
            gamma: 1.0,
            omega: 60.0 + i as f64,
            amplitude: 1e-3,
            phase: None,
            direction: SweepDirection::Up,
            weight: 1.0,
        })
        .collect();
    let d = Dataset::from_records(&recs).unwrap();
    let e = identify(&d, &FitPlan::new(ModelKind::Duffing), &|_| {}).unwrap_err();
    assert!(e.to_string().contains("cannot separate"), "{e}");
    // phase outside [-2 pi, 2 pi]
    let mut d = data(
        &t,
        &[1.0, 2.0],
        (8.0, 12.0),
        30,
        &[SweepDirection::Up],
        Some((1.0, 0.0)),
    );
    d.curves[0].phases.as_mut().unwrap()[3] = 10.0;
    let e = identify(&d, &FitPlan::new(ModelKind::Duffing), &|_| {}).unwrap_err();
    assert!(e.to_string().contains("phase"), "{e}");
    // NaN phase is rejected when the data are built
    let recs = vec![Record {
        level: "a".into(),
        gamma: 1.0,
        omega: 60.0,
        amplitude: 1e-3,
        phase: Some(f64::NAN),
        direction: SweepDirection::Up,
        weight: 1.0,
    }];
    assert!(matches!(
        Dataset::from_records(&recs),
        Err(DataError::NotFinite { what: "phase", .. })
    ));
    // weights of the plan
    let mut plan = FitPlan::new(ModelKind::Duffing);
    plan.phase_weight = f64::NAN;
    assert!(matches!(
        identify(&d, &plan, &|_| {}),
        Err(IdentifyError::BadPhaseWeight(_))
    ));
}

/// Synthetic in-family case with phase from the suite's generator, as a
/// smoke test of the generator and the entry point together.
#[test]
fn suite_generator_case_with_phase_fits() {
    let c = support::synthetic::case(7);
    let r = identify(&c.data, &FitPlan::new(ModelKind::Generalised), &|_| {}).unwrap();
    assert!(r.phase.is_some());
    assert!(rel(r.fit.theta[ALPHA], c.truth[ALPHA]) < 5e-3);
}

/// The Duffing + quadratic damping model, 3 levels swept up and
/// down, 60 steps, noise free: the data of the progress tests.
fn progress_data() -> Dataset {
    data(
        &duffing_quadratic(),
        &[0.5, 1.0, 2.0],
        (8.0, 14.0),
        60,
        &[SweepDirection::Up, SweepDirection::Down],
        None,
    )
}

/// The stages `identify` reports for `plan` on `d`, in order: (name,
/// steps announced, steps reported).
fn reported_stages(d: &Dataset, plan: &FitPlan) -> Vec<(&'static str, usize, usize)> {
    use std::sync::Mutex;
    let events = Mutex::new(Vec::new());
    identify(d, plan, &|p| events.lock().unwrap().push(p)).unwrap();
    let mut stages: Vec<(&'static str, usize, usize)> = Vec::new();
    for e in events.into_inner().unwrap() {
        match e {
            IdentifyProgress::Stage { name, steps } => stages.push((name, steps, 0)),
            IdentifyProgress::Step => stages.last_mut().expect("a step before any stage").2 += 1,
        }
    }
    stages
}

/// The staged fit reports its stages in order, each announcing how many
/// steps it reports: one per landscape row, one per output-error start.
#[test]
fn identify_reports_its_stages() {
    let plan = FitPlan::new(ModelKind::Generalised)
        .with_grid(9, 7)
        .unwrap();
    let stages = reported_stages(&progress_data(), &plan);
    assert_eq!(stages[0], ("landscape", 7, 7), "{stages:?}");
    assert_eq!(stages[1].0, "output error", "{stages:?}");
    assert!(stages[1].2 >= 1 && stages[1].2 <= stages[1].1, "{stages:?}");
    for (name, announced, reported) in &stages[2..] {
        assert!(reported <= announced, "{name}: {reported} of {announced}");
    }
}

/// `FitPlan::starts` reaches the race: each candidate's output-error fit
/// is a global search of that many trial points (its own start and
/// Latin-hypercube ones), each reported as a step. The oracle is the same
/// fit with one start: the race announces and reports four times its steps
/// with four (the option was ignored, silently, before the sixteenth
/// session: the steps were the same).
#[test]
fn the_plans_starts_reach_every_race_candidate() {
    let d = progress_data();
    let race = |starts: usize| {
        let mut plan = FitPlan::new(ModelKind::Generalised)
            .with_grid(9, 7)
            .unwrap();
        plan.starts = starts;
        let stages = reported_stages(&d, &plan);
        let first = stages
            .iter()
            .find(|s| s.0 == "output error")
            .copied()
            .expect("a race");
        (first.1, first.2)
    };
    let (announced, reported) = race(1);
    assert!(reported >= 1, "{reported}");
    assert_eq!(race(4), (4 * announced, 4 * reported));
}

/// With phases, the first line says which part does not fit. Duffing data
/// (two levels up, 1 % amplitude noise, 0.3° phase noise) whose phases
/// carry a ramp of 0 → 6° across the band that no model phase follows:
/// the amplitudes fit their noise and the phases do not. The two ratios
/// recombine to the statistic the decision uses (the oracle: the mean of
/// z² over both parts, equal counts), and the message quotes them.
#[test]
fn a_fit_with_phases_says_whether_amplitudes_or_phases_do_not_fit() {
    let wn = TWO_PI * 10.0;
    let t = Parameters::from([wn * wn, 2.0 * 0.02 * wn, 1.0e6, 2.0, 0.0, 0.0, 1.0]);
    let mut d = data(
        &t,
        &[0.5, 1.0],
        (8.0, 13.0),
        150,
        &[SweepDirection::Up],
        Some((1.0, 0.0)),
    );
    let mut rng = support::fixtures::Rng(0x5eed_0025);
    for c in &mut d.curves {
        let n = c.omegas.len();
        for a in &mut c.amplitudes {
            *a *= 1.0 + 0.01 * rng.normal();
        }
        let ph = c.phases.as_mut().expect("phases");
        for (i, p) in ph.iter_mut().enumerate() {
            *p += (6.0 * i as f64 / (n - 1) as f64 + 0.3 * rng.normal()).to_radians();
        }
    }
    let id = identify(&d, &FitPlan::new(ModelKind::Duffing), &|_| {}).unwrap();
    assert!(id.phase.is_some());
    let split = id.adequacy.split.expect("a split with phases");
    let (amp, phase) = split.ratios();
    assert!(amp < 1.5, "amplitudes {amp}x the noise");
    assert!(phase > 3.0, "phases {phase}x the noise");
    // equal counts (every point has both): the mean of the two means
    let mean = 0.5 * (split.amplitude_mean_z2 + split.phase_mean_z2);
    assert!(
        rel(id.adequacy.ratio.powi(2), mean) < 1e-9,
        "{} vs {mean}",
        id.adequacy.ratio.powi(2)
    );
    for c in &id.curves {
        let s = c.noise.split.expect("per curve");
        let m = 0.5 * (s.amplitude_mean_z2 + s.phase_mean_z2);
        assert!(rel(c.noise.mean_z2, m) < 1e-9, "{} vs {m}", c.noise.mean_z2);
    }
    assert!(!id.adequacy.adequate);
    let msg = id.adequacy_message().unwrap();
    let worst = id
        .adequacy
        .failing
        .iter()
        .map(|&i| id.curves[i].noise)
        .max_by(|a, b| a.ratio().total_cmp(&b.ratio()));
    let (a, p) = worst
        .and_then(|n| n.split)
        .map_or((amp, phase), |s| s.ratios());
    assert!(
        msg.contains(&format!("(amplitudes {a:.1}x, phases {p:.1}x)")),
        "{msg}"
    );
    // without phases there is no split, and the line has none
    let mut bare = d.clone();
    for c in &mut bare.curves {
        c.phases = None;
    }
    let id = identify(&bare, &FitPlan::new(ModelKind::Linear), &|_| {}).unwrap();
    assert!(id.adequacy.split.is_none());
    assert!(id.curves.iter().all(|c| c.noise.split.is_none()));
    if let Some(msg) = id.adequacy_message() {
        assert!(!msg.contains("phases"), "{msg}");
    }
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2402129818, case h016-mixed: three up-sweeps with jumps, exact
/// first-order HB by the independent oracle, 1 % amplitude noise) on which
/// no stage reaches the truth's basin: the exact reading is stuck at 111×
/// the noise, and the censored reading fits the noise at 621× the truth's
/// Eq 31 cost. Whatever the pipeline finds, it must not be a miss without a
/// flag: either the optimum (Eq 31 cost at most 1.05× the truth's) or
/// `adequate: false` — here because the fit rests on sweeps that left their
/// branch early.
#[test]
fn a_fit_that_fits_only_with_early_jumps_says_so() {
    let (data, truth) = blind_h016();
    let id = identify(&data, &FitPlan::new(ModelKind::Generalised), &|_| {}).unwrap();
    let eq31 = |th: &Parameters| objective::evaluate(&data, th, false).unwrap().cost();
    let (fit, truth) = (eq31(&id.fit.theta), eq31(&truth));
    let optimum = fit <= 1.05 * truth;
    assert!(
        optimum || !id.adequacy.adequate || !id.fit.converged,
        "cost/truth {} with no flag",
        fit / truth
    );
    if !optimum && id.spec.censored.iter().any(|&c| c) {
        assert!(id.adequacy.needs_early_jumps.is_some());
        let msg = id.adequacy_message().unwrap();
        assert!(msg.contains("fits only if the sweep"), "{msg}");
    }
}

/// The same blind set with η held at 3.5 (truth 3.48): without phase the
/// landscape's warm chain left every node degenerate, and the fit failed
/// with "no node of the exponent landscape could be solved"; each node
/// solved on its own, it reaches the truth's cost.
#[test]
fn a_held_exponent_is_fitted_when_the_warm_chain_degenerates() {
    let (data, truth) = blind_h016();
    let plan = FitPlan::new(ModelKind::Generalised).with_fixed("eta", 3.5);
    let id = identify(&data, &plan, &|_| {}).expect("a fit with eta held");
    let eq31 = |th: &Parameters| objective::evaluate(&data, th, false).unwrap().cost();
    assert!(
        eq31(&id.fit.theta) <= 1.05 * eq31(&truth),
        "cost/truth {}",
        eq31(&id.fit.theta) / eq31(&truth)
    );
}

/// A blind suite's CSV (`level,gamma,f_hz,amplitude[,phase_deg],sweep`,
/// as `../shared/tools/blind_suite.py` writes it) as a data set.
fn blind_set(text: &str) -> Dataset {
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name);
    let (phase, sweep) = (col("phase_deg"), col("sweep").unwrap());
    let recs: Vec<Record> = lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            Record {
                level: f[0].to_string(),
                gamma: f[1].parse().unwrap(),
                omega: std::f64::consts::TAU * f[2].parse::<f64>().unwrap(),
                amplitude: f[3].parse().unwrap(),
                phase: phase.map(|k| f[k].parse::<f64>().unwrap().to_radians()),
                direction: if f[sweep] == "down" {
                    SweepDirection::Down
                } else {
                    SweepDirection::Up
                },
                weight: 1.0,
            }
        })
        .collect();
    Dataset::from_records(&recs).unwrap()
}

/// The default generalised fit of `data`, asserted to find the optimum:
/// its Eq 31 cost at most 1.05× the truth's on the same data.
fn default_fit_finds_the_optimum(data: &Dataset, truth: &Parameters) -> Identification {
    finds_the_optimum(data, truth, FitPlan::new(ModelKind::Generalised))
}

/// [`default_fit_finds_the_optimum`] with the fit as `blind_suite.py` runs
/// it (seed 7, default settings otherwise).
fn suite_fit_finds_the_optimum(data: &Dataset, truth: &Parameters) -> Identification {
    let mut plan = FitPlan::new(ModelKind::Generalised);
    plan.seed = 7;
    finds_the_optimum(data, truth, plan)
}

/// The fit of `data` under `plan`, after checking that its Eq 31 cost is at
/// most 1.05x the truth's on the same data.
fn finds_the_optimum(data: &Dataset, truth: &Parameters, plan: FitPlan) -> Identification {
    let id = identify(data, &plan, &|_| {}).unwrap();
    let eq31 = |th: &Parameters| objective::evaluate(data, th, false).unwrap().cost();
    let (fit, truth) = (eq31(&id.fit.theta), eq31(truth));
    assert!(fit <= 1.05 * truth, "cost/truth {}", fit / truth);
    id
}

/// The mass-normalised truth (gain 1) of a blind set from its physical
/// parameters as `blind_suite.py` draws them: mass `m` (kg), `[k, c, k_r]`
/// (N/m, N s/m, N/m^(ρ+1)) and `[ρ, c_e, η]`.
fn physical_truth(m: f64, [k, c, k_r]: [f64; 3], [rho, c_e, eta]: [f64; 3]) -> Parameters {
    Parameters::from([k / m, c / m, k_r / m, rho, c_e / m, eta, 1.0])
}

/// The escalation tried a step whose entry contains `what`.
fn assert_tried(id: &Identification, what: &str) {
    assert!(
        id.adequacy.escalation.iter().any(|t| t.contains(what)),
        "{what}: {:?}",
        id.adequacy.escalation
    );
}

/// The fit says nothing alarming: converged, and adequate to its noise.
fn assert_trusted(id: &Identification) {
    assert!(
        id.fit.converged && id.adequacy.adequate,
        "{:?} {:?}",
        id.fit.termination,
        id.adequacy
    );
}

/// Blind set g3 h016-mixed and its truth (mass-normalised).
fn blind_h016() -> (Dataset, Parameters) {
    let data = blind_set(include_str!("data/blind_h016_mixed.csv"));
    let truth = Parameters::from([
        2108.328697240462,
        0.10752970059097348,
        463665.1970380751,
        2.7896647200728246,
        6.603705854036738e-05,
        3.483383476279982,
        1.0,
    ]);
    (data, truth)
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 783382638, case h032-mixed: five levels swept up and down with jumps,
/// phase given, exact first-order HB by the independent oracle, 1 %
/// amplitude and 0.3° phase noise). The fit of the previous pipeline had
/// every parameter within 6 % of the truth but the top up-sweep's fold a
/// hair (2 % of a step) after the measured jump: the one point between
/// them sat on the wrong branch in Eq 31 (149× the truth's cost) while the
/// measured-branch output error charged it only a small penalty, and no
/// gradient crossed back. Read exactly, a late fold is not a solution:
/// `pull_late_folds` moves it into the measured jump's step.
#[test]
fn a_late_fold_is_pulled_into_its_measured_jump() {
    let (data, truth) = blind_h032();
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// Blind set h032-mixed (seed 783382638) and its truth (mass-normalised).
fn blind_h032() -> (Dataset, Parameters) {
    let data = blind_set(include_str!("data/blind_h032_mixed.csv"));
    let truth = Parameters::from([
        4942968.377441952,
        6.370792300585375,
        2743155808787.139,
        1.5943730428063314,
        3079.8106344855505,
        3.193849256712001,
        1.0,
    ]);
    (data, truth)
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 305790139, case h047-mixed: three levels swept up and down, no phase,
/// ρ = 5.36, η = 1.09). The race candidates from the nodes next to the
/// truth stopped at 17× the truth's objective with every parameter within
/// 30 % of it: the top up-sweep's model fold one step before the measured
/// jump, where no gradient crosses. The winner came from another basin (η
/// = 1.51, 1.14× the truth's Eq 31 cost, adequate by the noise test: a
/// miss without a flag). `relocate_folds` in the race moves such a fold
/// into its measured step.
#[test]
fn a_race_candidate_with_a_misplaced_fold_is_relocated() {
    let data = blind_set(include_str!("data/blind_h047_mixed.csv"));
    let truth = Parameters::from([
        3048.2682500907176,
        2.0811596444451395,
        5733816331930936.0,
        5.364276432908587,
        6.770609142380112,
        1.0917198557101981,
        1.0,
    ]);
    default_fit_finds_the_optimum(&data, &truth);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 577215664, case h015-mixed: two levels swept up only, 300 steps, no
/// phase, ρ = 3.92, η = 2.78). The race candidates of the truth's basin all
/// stopped with the lower level's model fold a step before the measured
/// jump; the least-misfit move of `relocate_folds` (which follows the
/// directions these weakly informative data see least) lost the fold or
/// moved it the wrong way, so none was relocated, and the winner from
/// another basin ended at 1.12× the truth's Eq 31 cost, converged and
/// adequate (residual 1.25× the noise): a miss without a flag. The move by
/// the least change in the optimisation variables, tried when the
/// least-misfit one fails, places the fold.
#[test]
fn a_fold_the_least_misfit_move_cannot_place_is_moved_by_the_least_change() {
    let data = blind_set(include_str!("data/blind_h015_mixed.csv"));
    let truth = Parameters::from([
        9391.130862463033,
        3.1706642595263776,
        410254540551116.94,
        3.9200151599516606,
        259.6666389702413,
        2.779637785268596,
        1.0,
    ]);
    default_fit_finds_the_optimum(&data, &truth);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 577215664, case h024-hardening: one level swept up, 120 steps, phase
/// given, ρ = 5.22, no nonlinear damping). The fit is at the optimum (its
/// Eq 31 cost below the truth's), but it gets there along a ridge where the
/// power-law damping turns into a copy of the linear one (η → −0.05, δ →
/// 0): three rounds of 25 iterations ended it "not converged
/// (max-iterations)", a false alarm. The rounds' budget is one of work
/// (`polish_rounds`: more rounds on small data), and the fit converges.
#[test]
fn a_crawl_on_small_data_is_given_rounds_to_converge() {
    let data = blind_set(include_str!("data/blind_h024_hardening.csv"));
    let truth = Parameters::from([
        260.8780883995088,
        0.037418938192490474,
        0.3992952437784263,
        5.220089893064354,
        0.0,
        0.0,
        1.0,
    ]);
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2611270014, case h033-mixed: one level swept up and down, 120 steps, no
/// phase, ρ = 5.62, η = 1.69 with a weak nonlinear damping). The race ended
/// at η = 0.04 (the power-law damping a near copy of the linear one), 2.11×
/// the truth's Eq 31 cost with a residual 1.23× the noise: adequate, so
/// nothing searched further, a miss without a flag. A single forcing level
/// pins the exponents weakly; such data now get the escalation's wider
/// search whatever their residual, which reaches 0.97×.
#[test]
fn a_single_level_is_searched_as_widely_as_a_misfit() {
    let data = blind_set(include_str!("data/blind_h033_mixed.csv"));
    let truth = Parameters::from([
        129.36096843945995,
        0.07789207136769802,
        89.78850427625011,
        5.616753437827994,
        0.0011437022604019289,
        1.6901687504748963,
        1.0,
    ]);
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert!(!id.adequacy.escalation.is_empty(), "{:?}", id.adequacy);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2611270019, case h027-mixed: one level swept up and down, 120 steps, no
/// phase, ρ = 2.38, η = 0.64). Eq 31 is nearly flat in η here (held at 0.35
/// the default pipeline's objective is below the truth's), and for three
/// sessions the fit ended elsewhere on that flat valley, 1.13–1.33× the
/// truth's cost and within the noise: a miss without a flag. Found since the
/// exponent profile also starts from the landscape (0.998×, η 0.35, δ and κ
/// named as a ridge, intervals not valid); since the profile also holds η
/// half a unit either side of the fit, lower still (Eq 31 3.235e-14 against
/// 3.378e-14) at η 3.35, which is named as not determined by the data (its
/// 95 % interval [−39.9, 46.6]). Either way the flat direction is named.
#[test]
fn a_single_level_flat_in_eta_reaches_the_optimum_and_names_the_ridge() {
    let data = blind_set(include_str!("data/blind_h027_mixed.csv"));
    let truth = physical_truth(
        0.07311876677744167,
        [932597.8521311749, 2.828484891012489, 5.564766255374733e18],
        [2.3754726025068047, 67.8373517200117, 0.6382314100844745],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    let eta_undetermined = id.fit.uncertainty.as_ref().is_some_and(|u| {
        nlsdof::identification::flags::undetermined_exponents(u)
            .iter()
            .any(|x| x.name == "eta")
    });
    assert!(
        !id.fit.intervals_valid() || eta_undetermined,
        "{:?} {:?}",
        id.fit.warning(),
        id.fit.notes()
    );
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2711270131, case h038-hardening: four levels swept down, 120 steps, no
/// phase, ρ = 2.80, no nonlinear damping). The fit reached 0.954× the
/// truth's Eq 31 cost but was flagged "does not fit the resonance peaks:
/// 1.8× the noise there" — as was the truth itself: the noise estimate of
/// the top level put its noise into the absolute floor, and at that
/// level's peak its σ̂ was 0.38× the true 1 %. The peaks' own
/// pseudo-residuals show it (`noise::pseudo_residual_chi2`), and the peak
/// test now uses the noise they support: trusted.
#[test]
fn a_noise_floor_fitted_to_the_low_amplitudes_does_not_flag_the_peaks() {
    let data = blind_set(include_str!("data/blind_h038_hardening.csv"));
    let truth = physical_truth(
        2.315820315356214,
        [2238.1025676264094, 0.563779266614056, 22370.042109657945],
        [2.79739395210785, 0.0, 0.0],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2711270203, case h023-hardening: one level swept up, 120 steps, no
/// phase, ρ = 1.22, no nonlinear damping). The fit reached 0.78× the
/// truth's Eq 31 cost but was flagged "does not fit the data: residual
/// 1.6× the noise": the noise estimate took the grid's largest absolute
/// floor (capped likelihood 5.9 lower than without one), and σ̂ at the peak
/// was 0.36× the true 1 %. A floor is now fitted only when significant
/// (χ²₁ 0.1 %): trusted.
#[test]
fn a_noise_floor_the_data_do_not_need_is_not_fitted() {
    let data = blind_set(include_str!("data/blind_h023_hardening.csv"));
    let truth = physical_truth(
        96.1559954412813,
        [7429.682026139289, 19.641767225988808, 2955.8083695041605],
        [1.217118297207809, 0.0, 0.0],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2711270212, case h003-mixed: three levels swept up and down, 200 steps,
/// no phase, ρ = 2.46, η = 0.92). The fit ended in a neighbouring basin of
/// η (0.41, δ a quarter of the truth's on a δ–κ ridge), within its noise
/// (1.03×) at 1.065× the truth's Eq 31 cost: a miss without a flag. The
/// gain test had freed the gain there (0.995, F = 64) to take up the
/// misfit. A fit whose gain the decisions freed now gets the exponent
/// profile, which also holds each exponent half a unit either side of the
/// fit (the coarse values, 1.35 apart on η, stepped over this basin).
#[test]
fn a_freed_gain_sends_the_fit_to_the_exponent_profile() {
    let data = blind_set(include_str!("data/blind_h003_mixed.csv"));
    let truth = physical_truth(
        0.10239173251517239,
        [43.58053148748426, 0.037304709346788874, 17319.03119370524],
        [2.455712812502284, 0.03108748269496654, 0.9230419731508293],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// A blind in-family set of one level swept up and down without phase
/// (`../shared/tools/blind_suite.py`: h036-mixed of seed 2711270401, 120
/// steps, ρ = 1.82, η = 1.44). Its escalation profiled the race's winner
/// (ρ 2.67, η −0.72) and ended 4.8× above the truth's objective; the
/// decided fit (ρ 2.37, η 0.99) sat within its noise (1.39×) at 1.52× the
/// truth's Eq 31 cost: a miss without a flag. A fit within its noise but
/// near its top is now profiled from where the decisions left it at one
/// level too: held half a unit below its ρ it reaches the optimum.
#[test]
fn one_level_near_its_noise_is_profiled_from_the_decided_fit() {
    let data = blind_set(include_str!("data/blind_h036_mixed_one_level.csv"));
    let truth = physical_truth(
        0.09920351478428957,
        [180.1407711766082, 0.22997980951404431, 1524592.73621671],
        [1.8233108416753956, 3.1773726215060702, 1.443171882445813],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// A blind in-family set of six levels swept up without phase and without
/// nonlinear damping (`../shared/tools/blind_suite.py`: h001-hardening of
/// seed 2711270322, 300 steps, ρ = 3.94). The top level's fold ended pinned
/// at the measured step before its jump, one step early, and the fit was
/// flagged at 49.6× the truth's Eq 31 cost. The jump reassignment saw it,
/// but moving that fold by itself took level 5's out of its measured
/// interval, and the refit could not bring it back. The folds are now also
/// moved jointly, every other one held in its step cell.
#[test]
fn a_fold_moved_a_step_holds_the_other_levels_folds() {
    let data = blind_set(include_str!("data/blind_h001_hardening_early_fold.csv"));
    let truth = physical_truth(
        2.4571216434026995,
        [77401092.827797, 192.26977732538347, 2.326334105127967e29],
        [3.9353526715539497, 0.0, 0.0],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// Two blind in-family sets of two levels without phase
/// (`../shared/tools/blind_suite.py`: h002-mixed of seed 2711270143, swept
/// up, 200 steps, ρ = 2.01, η = 3.00; h036-mixed of seed 2711270407, swept
/// up and down, 300 steps, ρ = 1.23, η = 3.66), flagged misses after the
/// escalation. The escalation profiles the race's winner when that is
/// within 20× its noise: h002's was not, and its candidates and multistart
/// ended at η 6.14, 1.88× the truth's Eq 31 cost; h036's was, and it ended
/// at η 7.5 with a sweep read as censored, 118×. A fit still within 20× its
/// noise after the escalation now gets the exponent profile from where it
/// ended.
#[test]
fn a_misfit_near_its_noise_is_profiled_from_where_the_escalation_ended() {
    for (csv, truth) in [
        (
            include_str!("data/blind_h002_mixed_unprofiled.csv"),
            physical_truth(
                0.7751266586322141,
                [1176038.1932142891, 4.3784849996335335, 66086676778735.68],
                [2.006918374904716, 2222.380342891835, 3.004347934512829],
            ),
        ),
        (
            include_str!("data/blind_h036_mixed_two_levels_censored.csv"),
            physical_truth(
                1.5184005238495453,
                [70272.47701017749, 1.1097784012671568, 6731659.871104796],
                [1.2262484398999258, 1.7441491737391257, 3.6614531951465756],
            ),
        ),
    ] {
        let data = blind_set(csv);
        let id = default_fit_finds_the_optimum(&data, &truth);
        assert_trusted(&id);
    }
}

/// Two blind in-family sets without phase (`../shared/tools/blind_suite.py`:
/// h036-mixed of seed 2711270501, three levels up, 300 steps, ρ = 5.72,
/// η = 2.32; h012-mixed of seed 2711270322, four levels up and down, 300
/// steps, ρ = 5.07, η = 1.13), each fitted within its noise (1.006×,
/// 1.012×) at 1.055× and 1.10× the truth's Eq 31 cost with one fold pinned
/// against a measured step after the unpin refit: misses without a flag,
/// below the near-noise profile's trigger. A fold still pinned is a
/// constrained optimum, and such a fit is now profiled from the decided fit.
#[test]
fn a_fold_still_pinned_within_the_noise_is_profiled() {
    for (csv, truth) in [
        (
            include_str!("data/blind_h036_mixed_pinned_fold.csv"),
            physical_truth(
                3.686790554067276,
                [
                    3135630.389665155,
                    10.916968564669062,
                    2.0158915332336057e+27,
                ],
                [5.718304934023328, 224.3693410216537, 2.3238837646230843],
            ),
        ),
        (
            include_str!("data/blind_h012_mixed_pinned_fold.csv"),
            physical_truth(
                0.30244981659166004,
                [27.944927721872272, 0.01984313472219946, 129.40329367524177],
                [5.07376715602204, 0.0018963554723037152, 1.1335274624271274],
            ),
        ),
    ] {
        let data = blind_set(csv);
        let id = default_fit_finds_the_optimum(&data, &truth);
        assert_trusted(&id);
        assert_tried(&id, "exponent held");
    }
}

/// Blind h032-mixed of random seed 3339137987 (`blind_suite.py`: six
/// levels swept up and down, 300 steps, no phase, ρ = 3.63, η = 0.68):
/// the gain freed, the refit from folds moved past the points still on
/// their branch lowered the objective 24.5x in its one round of 25
/// iterations on every point and stopped at that limit, and the fit ended
/// "did not converge (max-iterations)" although it had found the optimum
/// (0.936x the truth's Eq 31 cost): a false alarm. That refit is now
/// continued as the polish is; three more iterations converge.
#[test]
fn a_refit_from_moved_folds_is_continued_to_convergence() {
    let data = blind_set(include_str!("data/blind_h032_mixed_reassigned.csv"));
    let truth = physical_truth(
        0.048487700356699796,
        [
            1695397.1696819619,
            1.705044086978183,
            1.9683512853328485e+26,
        ],
        [3.625637591959259, 34.866928848323774, 0.6813014299711411],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
}

/// Blind h001-mixed of fresh seed 2711280107 (`blind_suite.py`: six
/// levels swept down, 300 steps, no phase, ρ 2.05, η 1.51): the race's
/// winner, at η 0.029 with κ beside δ, lost its damping term on the
/// 906-point subsample (statistic 5.88 against 5.99), and every point then
/// refined without it to 1.262x the truth's Eq 31 cost, within the noise:
/// a miss without a flag. The removed term is now tested again on every
/// point (`retest_removed_terms`), which needs it.
#[test]
fn a_term_removed_on_the_subsample_is_tested_again_on_every_point() {
    let data = blind_set(include_str!("data/blind_h001_mixed_term_retested.csv"));
    let truth = physical_truth(
        0.010668979579794501,
        [33.67161945426202, 0.002348468961608824, 608.521289872339],
        [
            2.0462819672639094,
            0.00014283476857762298,
            1.5119719664993934,
        ],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_eq!(id.fit.status[KAPPA], Status::Free, "{:?}", id.fit.inactive);
}

/// Blind h008-mixed of random seed 4120673301 (`blind_suite.py`: five
/// levels swept up and down, 200 steps, no phase, ρ 5.04, η 2.19): the fit
/// converged within the noise at 1.128x the truth's Eq 31 cost, level 5's
/// up-sweep fold 2e-5 Hz below the step after it. On the straight line to
/// the truth the objective falls monotonically while that fold moves into
/// its cell, but LM stops at the step: every trial step crosses it. The
/// unpin refit holds each pinned fold at the middle of its cell
/// (`refit_with_folds_held`), then frees it: 1.063x, at η 1.50, a miss
/// without a flag. The near profile then held η at 2.0 on the race's
/// subsample, 12 % lower there, but carried through the decisions its
/// refit on every point stopped at once above the standing fit; held at
/// 2.0 on every point, the rest refit 6.3 % below the standing fit, which
/// the noise-scaled test alone (`Σ z²` 9.2 lower) did not keep. Now the
/// profile's exponent is held on every point too, and a drop of 1 % of the
/// objective is kept: 0.997x.
#[test]
fn a_profiled_exponent_is_held_on_every_point() {
    let data = blind_set(include_str!("data/blind_h008_mixed_folds_held.csv"));
    let truth = physical_truth(
        2.039966084528128,
        [107733.03817396067, 1.139606804415167, 3944906094849427.5],
        [5.035237196513762, 0.17301609916581145, 2.190173402958884],
    );
    let id = suite_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_tried(&id, "held on every point");
}

/// Blind h025-mixed of seed 2711280113 (`blind_suite.py`: one level swept
/// up and down, 200 steps, no phase, ρ 4.12, η 2.85): the screen freed the
/// gain at 1.35, and the free race and its escalation ended at η 7.1 with
/// the gain 1.041, 1.685x the truth's Eq 31 cost (flagged: 2.3x the
/// noise). The held race's winner (η 5.84), carried through the stages,
/// ended 1.9x the noise. With the gain fixed at 1 the default stages reach
/// 1.006x: a fit whose freed gain is near 1 and that does not fit its
/// noise now gets the escalation again with the gain held.
#[test]
fn a_freed_gain_near_one_that_does_not_fit_escalates_again_held() {
    let data = blind_set(include_str!(
        "data/blind_h025_mixed_gain_held_escalation.csv"
    ));
    let truth = physical_truth(
        5.396514112285732,
        [131943.20718700276, 15.61597133037484, 1.1240352348987875e17],
        [4.123112017482026, 1818.3112226310125, 2.8534786347824617],
    );
    let id = suite_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_tried(&id, "with the gain held at 1");
}

/// Blind h018-mixed of seed 2811280612 (`blind_suite.py`: one level swept
/// up, 200 steps, no phase, ρ 5.64, η 2.67): the equation-error screen
/// freed the gain at 282 (F = 3.6e4), so its landscape's minima were those
/// of a free gain and no held race ran; the fit ended at ρ 10 (its bound),
/// κ removed, gain 0.72, 1715x the noise and 2202x the truth's Eq 31 cost
/// (flagged). The escalation again with the gain held, from the same
/// landscape's nodes, stayed in that basin (ρ 10, 2.11e-6 against the
/// truth's 9.6e-10). With the gain fixed at 1 the default stages reach
/// 0.996x. Now a held race that runs only for this escalation takes its
/// nodes from the landscape with the gain held at 1, and its winner goes
/// through the stages when the escalation finds nothing lower; a misfit
/// beyond 20x the noise gets it too (without the exponent profile).
#[test]
fn a_held_gain_escalation_races_the_held_landscape() {
    let data = blind_set(include_str!(
        "data/blind_h018_mixed_gain_held_landscape.csv"
    ));
    let truth = physical_truth(
        0.10891047792170103,
        [66816.48215061713, 0.2550193349466572, 1.1388602645733163e24],
        [5.6426726065696, 2.465969611475018, 2.667934792959242],
    );
    let id = suite_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_tried(&id, "with the gain held at 1");
}

/// Blind h008-hardening of random seed 233097205 (`blind_suite.py`: one
/// level swept up, 300 steps, no phase, ρ = 4.92, no nonlinear damping):
/// the fit converged within the noise at ρ 4.772 ± 0.049, 1.056x the
/// truth's Eq 31 cost, with its fold pinned above the last step on its
/// branch after the unpin refit, and neither profile moved it (held half a
/// unit away the others refit 1.6x and 2.8x above the fit): a miss without
/// a flag. With ρ held two standard errors away they refit lower; a fold
/// still pinned after the profiles now gets that step
/// (`ProfileScope::Fine`).
#[test]
fn an_exponent_held_two_standard_errors_away_frees_a_pinned_fit() {
    let data = blind_set(include_str!(
        "data/blind_h008_hardening_pinned_one_level.csv"
    ));
    let truth = physical_truth(
        5.123796599901752,
        [
            244.82127129463433,
            0.10641733613465416,
            0.007029734583853076,
        ],
        [4.921691505259032, 0.0, 0.0],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_tried(&id, "two standard errors");
}

/// Blind h047-mixed of seed 2711280110 (`blind_suite.py`: four levels
/// swept up, 300 steps, no phase, ρ 4.63, η 3.83): the fit (seed 7, as the
/// suite runs it) left level 1's fold 2.1e-12 relative past the last step
/// of a sweep without a jump, where no step cell holds it; the suite's
/// oracle placed that fold 3.9e-11 before the step, read the last point off
/// the branch, and scored the fit at 39.9x the truth's Eq 31 cost, without
/// a flag. A fold past the end of a sweep is now kept off the last step
/// too: the root count at every sweep's end equals the count one margin
/// past it.
#[test]
fn a_fold_just_past_the_end_of_a_sweep_is_moved_off_its_last_step() {
    use nlsdof::harmonic_balance::{ForcedResponse, Formulation};
    let data = blind_set(include_str!("data/blind_h047_mixed_fold_past_the_end.csv"));
    let truth = physical_truth(
        0.43986830154423456,
        [1452195.5482030655, 2.914052971922669, 9.584473827767231e+26],
        [4.629509928211734, 17292.8274974654, 3.833273761423978],
    );
    let id = suite_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    let th = id.fit.theta;
    for c in &data.curves {
        let r = ForcedResponse::from_normalised(
            &th.normalised_model(),
            th[GAIN] * c.gamma,
            Formulation::HarmonicBalance,
        )
        .unwrap();
        let end = match c.direction {
            SweepDirection::Up => *c.omegas.last().unwrap(),
            SweepDirection::Down => c.omegas[0],
        };
        let sign = if c.direction == SweepDirection::Up {
            1.0
        } else {
            -1.0
        };
        let count = |w: f64| r.equation(w).roots_t().unwrap().len();
        let past = end * (1.0 + sign * nlsdof::identification::identify::FOLD_MARGIN);
        assert_eq!(count(end), count(past), "level {}", c.level);
    }
}

/// Two blind in-family sets of one level swept up with phase
/// (`../shared/tools/blind_suite.py`: h016-mixed of seed 2711270301, 300
/// steps, ρ = 5.29, η = 2.17; h013-mixed of seed 2711270232, 120 steps,
/// ρ = 5.41, η = 3.80), measured as displacement lags without an offset.
/// The landscape's best node detected the phase offset at −47° (h016) and
/// −85° (h013): with one level the complex gain that carries it trades with
/// the laws. Read so, every candidate went elsewhere, the gain was freed
/// (4.96, 8.30) and the fits ended flagged at 35.5× and 578× the truth's
/// Eq 31 cost. Each node's candidate now reads the phases with its own
/// node's offset when the output error's correction cannot reach it: the
/// optimum, the gain held, the offset found near its true 0.
#[test]
fn one_level_with_phase_reads_the_phases_with_each_nodes_own_offset() {
    for (csv, truth) in [
        (
            include_str!("data/blind_h016_mixed_one_level_phase.csv"),
            physical_truth(
                23.178209981562564,
                [11760.700616243375, 26.88254798358362, 20375260452442.938],
                [5.286228602293731, 159.03020682386972, 2.168292407284458],
            ),
        ),
        (
            include_str!("data/blind_h013_mixed_one_level_phase.csv"),
            physical_truth(
                0.3723486039544407,
                [567127.2840505483, 7.733704859948478, 2.1524830602510995e32],
                [5.414518863676374, 3760399.2371841758, 3.79569125054283],
            ),
        ),
    ] {
        let data = blind_set(csv);
        let id = default_fit_finds_the_optimum(&data, &truth);
        assert_trusted(&id);
        assert_eq!(id.fit.theta.gain, 1.0);
        let conv = id.phase.expect("phases used");
        assert_eq!(conv.sign, 1.0);
        assert!(conv.offset.to_degrees().abs() < 3.0, "{conv:?}");
    }
}

/// Two blind in-family sets swept up without phase whose equation-error
/// screen freed the gain (`../shared/tools/blind_suite.py`: h040-mixed of
/// seed 2711270312, three levels, 200 steps, ρ = 2.75, η = 1.41, screen
/// F = 66; h053-mixed of seed 2711270143, five levels, 120 steps, ρ = 3.11,
/// η = 3.85, F = 194). The candidates raced with the gain free only: h040
/// ended at gain 1.41 and 14.7× the truth's Eq 31 cost (the held refit of
/// the gain decision stuck 1360× above the truth's objective, so the test
/// freed the gain), h053 at 422× with the gain held at 1. Both were flagged
/// misses. The candidates now race with the gain held too, and a held
/// winner that loses the race is carried through the decisions as well.
#[test]
fn a_gain_the_screen_freed_is_raced_held_too() {
    for (csv, truth) in [
        (
            include_str!("data/blind_h040_mixed_gain_screen.csv"),
            physical_truth(
                9.548774242137835,
                [450034.64915461227, 5.2176959651000745, 2786321626596.05],
                [2.748584504580691, 8.891980580248005, 1.4147192527568022],
            ),
        ),
        (
            include_str!("data/blind_h053_mixed_gain_screen.csv"),
            physical_truth(
                0.36012318960294004,
                [27619.406760155955, 0.23920636085460928, 3939740551069.461],
                [3.1123122153530054, 0.2894450530572031, 3.8460588489954297],
            ),
        ),
    ] {
        let data = blind_set(csv);
        let id = default_fit_finds_the_optimum(&data, &truth);
        assert_trusted(&id);
        let test = id.gain_test.expect("the gain decided by the data");
        assert!(test.f_statistic > identify::GAIN_F_THRESHOLD, "{test:?}");
        assert!(!test.freed, "{test:?}");
        assert_eq!(id.fit.theta.gain, 1.0);
    }
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2711270143, case h000-mixed: two levels swept up and down, 300 steps,
/// no phase, ρ = 3.43, η = 0.55). The race ended at η = −1 (its natural
/// bound), 4.9× the truth's objective; stage 5 removed the damping term
/// there, the gain was freed (1.013) to stand in for it, and the fit ended
/// 1.074× the truth's Eq 31 cost within the noise (1.32×): a miss without a
/// flag. The near-noise profile held only ρ. A term stage 5 removed is now
/// profiled along its exponent too, from the fit with half its linear
/// damping moved into the term: the optimum, and a residual at the noise.
#[test]
fn a_damping_term_removed_in_a_wrong_basin_is_tried_again_along_its_exponent() {
    let data = blind_set(include_str!("data/blind_h000_mixed.csv"));
    let truth = physical_truth(
        9.136545136669797,
        [28741.846378463797, 1.6343895202915546, 4504757488.302594],
        [3.426069105528884, 2.50076863229789, 0.5523968551668148],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert!(id.fit.theta.kappa > 0.0, "{:?}", id.fit.theta);
}

/// Blind set h013-mixed (`../shared/tools/blind_suite.py`, seed
/// 110808810: four levels swept up and down, 200 steps, no phase, ρ = 4.70,
/// η = 1.24) and its truth (mass-normalised).
fn blind_h013() -> (Dataset, Parameters) {
    let data = blind_set(include_str!("data/blind_h013_mixed.csv"));
    let truth = physical_truth(
        97.39835864801628,
        [3938760.6748232045, 61.01291873096872, 1.712547736914544e17],
        [4.704604063014635, 41.418214912737916, 1.2426352980194202],
    );
    (data, truth)
}

/// Blind h013-mixed without the escalation, η held at 2.95: the fit has
/// level 3's up-sweep leave the model's branch a step before the model's
/// fold; the measured-branch output error charges the point between them a
/// small penalty, but the model's own sweep (Eq 31) is still on the upper
/// branch there, at 91x the truth's Eq 31 cost, while every curve's own
/// residual is within the noise. Read exactly that is not a
/// solution: the self-check names the curve (`late_folds`) and the fit is
/// not adequate. (Until the landscape solved its collapsed rows cold, the
/// default race itself ended there, at η 2.87 and 92x; it now ends in
/// another basin, flagged by its residual, and η is held to keep the case.)
#[test]
fn a_sweep_that_leaves_before_the_model_fold_read_exactly_is_flagged() {
    let (data, truth) = blind_h013();
    let mut plan = FitPlan::new(ModelKind::Generalised).with_fixed("eta", 2.95);
    plan.escalate = false;
    let id = identify(&data, &plan, &|_| {}).unwrap();
    let eq31 = |th: &Parameters| objective::evaluate(&data, th, false).unwrap().cost();
    // the miss this flag is for (else the test tests nothing)
    assert!(eq31(&id.fit.theta) > 10.0 * eq31(&truth));
    assert!(!id.adequacy.adequate, "{:?}", id.adequacy);
    assert!(!id.adequacy.late_folds.is_empty());
    for &(ci, ratio) in &id.adequacy.late_folds {
        let c = &id.curves[ci];
        assert_eq!(c.reading, JumpReading::Exact);
        assert!(c.left_early_by.is_some());
        // the model's own sweep is far from the data there
        assert!(ratio > 10.0, "{ratio}");
    }
    let msg = id.adequacy_message().unwrap();
    assert!(msg.contains("own sweep does not follow"), "{msg}");
    assert_eq!(id.fit.misfit, Some(id.adequacy.quoted_ratio(&id.curves)));
}

/// Blind h013-mixed, default fit: the race's fit does not fit (first a
/// late fold at η 2.87; since the landscape's collapsed rows are solved, a
/// residual 2.8x the noise at η 0.40, 84x the truth's Eq 31 cost) and
/// escalates, and the escalation's exponent profile (η held across its
/// range, from the fit and from the landscape, the other parameters
/// refitted, the best freed) finds the truth's basin, which no landscape
/// candidate and no random start reached.
#[test]
fn an_exponent_profile_finds_the_basin_no_candidate_reached() {
    let (data, truth) = blind_h013();
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert!(id.adequacy.adequate, "{:?}", id.adequacy);
    assert_tried(&id, "exponent held");
}

/// Blind set h031-hardening (`../shared/tools/blind_suite.py`, seed
/// 218726641: three levels swept up and down, 300 steps, no phase,
/// ρ = 5.43, no nonlinear damping) and its truth (mass-normalised).
fn blind_h031() -> (Dataset, Parameters) {
    let data = blind_set(include_str!("data/blind_h031_hardening.csv"));
    let truth = physical_truth(
        0.02066530084515362,
        [1178.1400536536416, 0.015736389581954034, 935439530939493.8],
        [5.434594024455927, 0.0, 0.0],
    );
    (data, truth)
}

/// Blind h031-hardening, default fit: the late-fold pull carried η to the
/// end of its range (8) with a vanishing κ, converged and within the noise
/// at 1.084x the truth's Eq 31 cost, after the terms had been settled on
/// the race's data. The terms are settled again when an exponent ends at
/// its range end: κ is removed and the rest refits to the optimum.
#[test]
fn an_exponent_the_pull_carries_to_its_range_end_has_its_term_settled_again() {
    let (data, truth) = blind_h031();
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert_eq!(id.spec.status[KAPPA], Status::Absent);
    assert!(
        id.fit.inactive.iter().any(|i| i.coefficient == "kappa"),
        "{:?}",
        id.fit.inactive
    );
}

/// Blind h031-hardening with the family of its truth: a power-law
/// stiffness, no nonlinear damping (the model `generalised-stiffness`, and
/// the generalised model with κ held at 0, which is the same model). The
/// equation-error landscape is then a single chained row from ρ = 0; its
/// best node was ρ 0.25 at gain 5.23, the race from it stuck 69.9x the
/// noise and freed the gain. The row is also solved cold node by node:
/// both fits reach the optimum with the gain held at 1, and say nothing
/// alarming.
#[test]
fn a_power_law_stiffness_alone_finds_the_optimum_with_the_gain_held() {
    let (data, truth) = blind_h031();
    let eq31 = |th: &Parameters| objective::evaluate(&data, th, false).unwrap().cost();
    let mut held = FitPlan::new(ModelKind::Generalised);
    held.fix = vec![("kappa".into(), 0.0), ("eta".into(), 1.0)];
    for plan in [FitPlan::new(ModelKind::GeneralisedStiffness), held] {
        let id = identify(&data, &plan, &|_| {}).unwrap();
        let ratio = eq31(&id.fit.theta) / eq31(&truth);
        assert!(ratio <= 1.05, "cost/truth {ratio}");
        assert_trusted(&id);
        assert_eq!(id.spec.status[KAPPA], Status::Absent);
        assert_eq!(id.spec.status[GAIN], Status::Fixed(1.0));
        assert!(!id.gain_test.unwrap().freed);
    }
}

/// Blind h008-hardening (`../shared/tools/blind_suite.py`, seed 2711270031:
/// four levels swept up and down, 200 steps, no phase, ρ = 3.80, no
/// nonlinear damping). The fit converged within the noise at 1.071x the
/// truth's Eq 31 cost with level 4's up-sweep fold pinned 1.3e-7 Hz above
/// the last measured step on its branch (the truth's fold lies inside the
/// step cell, β and ρ elsewhere along their ridge). The fold moved into
/// its cell and refitted behind the barrier (`unpin_folds`) reaches the
/// optimum, and the fit stays trusted.
#[test]
fn a_fold_pinned_at_a_measured_step_is_moved_into_its_cell() {
    let data = blind_set(include_str!("data/blind_h008_hardening.csv"));
    let truth = physical_truth(
        38.541409525194645,
        [149792.94065675922, 52.055476853796534, 1154730223455.5867],
        [3.8042661431729616, 0.0, 0.0],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    // the fold of level 4's up-sweep is inside its step cell, not at a step
    let (ci, c) = id
        .data
        .curves
        .iter()
        .enumerate()
        .find(|(_, c)| c.level == "4" && c.direction == SweepDirection::Up)
        .unwrap();
    let wf = id.curves[ci].model_jump.expect("a model jump");
    let k = c.omegas.partition_point(|&w| w < wf);
    let (lo, hi) = (c.omegas[k - 1], c.omegas[k]);
    assert!((wf - lo).min(hi - wf) > 0.05 * (hi - lo), "{lo} {wf} {hi}");
}

/// Blind h002-mixed (`../shared/tools/blind_suite.py`, seed 2711270052:
/// four levels swept up, 200 steps, no phase, ρ = 3.14, η = 0.41). The
/// equation-error landscape's chained rows collapsed to δ = κ = 0 (rank
/// deficient, not candidates) for every η from 0.35 to 4.4, and the fit
/// ended at η 3.43 within its noise at 1.215x the truth's Eq 31 cost, a
/// miss without a flag. Rows the chain left wholly degenerate are solved
/// cold: the row through the truth's η is solved, and the default fit
/// reaches the optimum and stays trusted.
#[test]
fn landscape_rows_the_chain_collapsed_are_solved_cold() {
    let data = blind_set(include_str!("data/blind_h002_mixed.csv"));
    let truth = physical_truth(
        0.09144455052795457,
        [156670.19308948045, 0.6364599795444507, 3.406744299389431e17],
        [3.1446761608647855, 0.5231784648906079, 0.41035792066712706],
    );
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    let land = &id.landscape;
    let j = land
        .eta
        .iter()
        .position(|&e| (e - 0.35).abs() < 1e-9)
        .expect("a row at eta 0.35");
    let solved = (0..land.rho.len())
        .filter(|&i| land.at(i, j).is_finite())
        .count();
    assert!(
        solved > land.rho.len() / 2,
        "{solved} of {}",
        land.rho.len()
    );
}

/// An exponent held at 0 with its coefficient free makes the term a copy
/// of the linear one: a typed error naming both, not a landscape whose
/// every node is rank-deficient (which named the wrong pair for η).
#[test]
fn an_exponent_held_at_zero_with_its_coefficient_free_is_refused() {
    let (data, _) = blind_h031();
    for (exp, coef, linear) in [("rho", "beta", "alpha"), ("eta", "kappa", "delta")] {
        let mut plan = FitPlan::new(ModelKind::Generalised);
        plan.fix = vec![(exp.into(), 0.0)];
        match identify(&data, &plan, &|_| {}) {
            Err(IdentifyError::Spec(SpecError::CopiesLinear {
                exponent,
                coefficient,
                linear: l,
                ..
            })) => assert_eq!((exponent, coefficient, l), (exp, coef, linear)),
            Err(e) => panic!("{exp}: {e}"),
            Ok(_) => panic!("{exp}: fitted"),
        }
    }
}

/// A blind in-family set (`../shared/tools/blind_suite.py`, seed
/// 2711270013, case h037-friction: two levels swept up, 300 steps, no
/// phase, ρ = 2.86, Coulomb friction η = −1). The fit reached 0.89× the
/// truth's Eq 31 cost with η at its natural bound −1, then crawled along ρ
/// and β for twelve rounds of 25 iterations and ended "did not converge
/// (max-iterations)": a false alarm. Holding the parameter at its natural
/// bound while the rest converges (`hold_natural_bounds`) ends it
/// converged, at a lower cost, and still reported as Coulomb friction.
/// That fit (without the escalation's searches) ended with level 2's fold
/// pinned at a measured step, and the default fit profiled it lower. Since
/// the eleventh session the unpin refit also holds a pinned fold inside its
/// cell (`refit_with_folds_held`), and the fit without the escalation
/// reaches that lower optimum itself, before any crawl (η −0.998, 0.870×
/// the truth's Eq 31 cost), so this set no longer reaches
/// `hold_natural_bounds`; either way the fit must end converged, at the
/// optimum, and as Coulomb friction or consistent with it. The default fit
/// ends no higher, with η −0.998 ± 0.007: inside its range, its interval
/// reaching −1, and noted as consistent with Coulomb friction
/// ([`flags::near_natural_bounds`]).
#[test]
fn a_crawl_beside_a_natural_bound_converges_with_the_bound_held() {
    let data = blind_set(include_str!("data/blind_h037_friction.csv"));
    let truth = physical_truth(
        16.020598116319658,
        [936602.8233285932, 14.95301896593451, 719278983068.4012],
        [2.8619136641205873, 2.8807696121868873, -1.0],
    );
    let mut plan = FitPlan::new(ModelKind::Generalised);
    plan.escalate = false;
    let held = identify(&data, &plan, &|_| {}).unwrap();
    let eq31 = |th: &Parameters| objective::evaluate(&data, th, false).unwrap().cost();
    assert!(eq31(&held.fit.theta) <= 1.05 * eq31(&truth));
    assert_trusted(&held);
    let at_bound = held
        .fit
        .natural
        .iter()
        .any(|n| n.name == "eta" && n.value == -1.0);
    let consistent = held.fit.notes().iter().any(|n| {
        n.starts_with("eta = -0.99") && n.contains("consistent with -1 (Coulomb friction)")
    });
    assert!(at_bound || consistent, "{:?}", held.fit.notes());
    assert_eq!(held.fit.status[ETA], Status::Free);
    let id = default_fit_finds_the_optimum(&data, &truth);
    assert_trusted(&id);
    assert!(id.fit.objective <= held.fit.objective);
    let u = id.fit.uncertainty.as_ref().unwrap();
    let k = u.index("eta").unwrap();
    assert!(
        u.lower[k] <= -1.0 && -1.0 <= u.upper[k],
        "{} {}",
        u.lower[k],
        u.upper[k]
    );
    assert!(id.fit.theta[ETA] > -1.0);
    // the free fit says what the held one said, as consistent with it
    assert!(
        id.fit
            .notes()
            .iter()
            .any(|n| n.starts_with("eta = -0.99")
                && n.contains("consistent with -1 (Coulomb friction)")),
        "{:?}",
        id.fit.notes()
    );
}

/// A fitted model, as its file holds it (θ at unit mass, the gain as the
/// input gain), swept at the data's levels, frequencies and directions,
/// gives the fit's model curves bit for bit (issue 25: a model file
/// reproduces the fit).
#[test]
fn sweeps_at_the_data_reproduce_the_fit_bit_for_bit() {
    let t = duffing_quadratic();
    let d = duffing_quadratic_data(&t);
    let mut plan = FitPlan::new(ModelKind::DuffingQuadratic);
    // a gain other than 1, so that its product with the level is exercised
    plan.gain = GainChoice::Fixed(1.7);
    let r = identify(&d, &plan, &|_| {}).unwrap();
    let th = r.fit.theta;
    assert_eq!(th[GAIN], 1.7);
    let law = |c: f64, e: f64| {
        (c != 0.0).then_some(nlsdof::PowerLaw {
            coefficient: c,
            exponent: e,
        })
    };
    let model = nlsdof::Model {
        mass: 1.0,
        stiffness: th[ALPHA],
        damping: th[DELTA],
        nonlinear_stiffness: law(th[BETA], th[RHO]),
        nonlinear_damping: law(th[KAPPA], th[ETA]),
    };
    let sweeps = sweeps_at_data(&model, th[GAIN], &r.data).unwrap();
    let mut got = Vec::new();
    for (s, c) in sweeps.iter().zip(&r.data.curves) {
        assert_eq!(s.gamma, c.gamma);
        let mut a: Vec<f64> = s
            .sweep
            .points
            .iter()
            .map(|p| if p.sticking { 0.0 } else { p.amplitude })
            .collect();
        if c.direction == SweepDirection::Down {
            a.reverse();
        }
        got.extend(a);
    }
    assert_eq!(got.len(), r.fit.model_amplitudes.len());
    for (k, (a, b)) in got.iter().zip(&r.fit.model_amplitudes).enumerate() {
        assert_eq!(a.to_bits(), b.to_bits(), "point {k}: {a:e} vs {b:e}");
    }
    // a gain that is not a positive number is refused, naming it
    let e = sweeps_at_data(&model, -1.0, &r.data).unwrap_err();
    assert!(e.to_string().contains("input_gain"), "{e}");
}

/// Unit hints (issue 28): levels given in g fit with a free gain of
/// 9.80665 and say so first; amplitudes given in mm (1000x) do not fit and
/// say they may be mm; the same data in SI get no hint.
#[test]
fn likely_unit_mistakes_are_named_first() {
    let t = duffing_quadratic();
    let si = duffing_quadratic_data(&t);
    let fit =
        |d: &Dataset| identify(d, &FitPlan::new(ModelKind::DuffingQuadratic), &|_| {}).unwrap();
    assert_eq!(fit(&si).unit_hint(), None);
    let mut in_g = si.clone();
    for c in &mut in_g.curves {
        c.gamma /= identify::G_STANDARD;
    }
    let r = fit(&in_g);
    let hint = r.unit_hint().expect("a hint for levels in g");
    assert!(hint.contains("look like they are in g"), "{hint}");
    assert!(
        r.warning().unwrap().starts_with("HINT"),
        "{:?}",
        r.warning()
    );
    let mut in_mm = si.clone();
    for c in &mut in_mm.curves {
        for a in &mut c.amplitudes {
            *a *= 1000.0;
        }
    }
    let r = fit(&in_mm);
    let hint = r.unit_hint().expect("a hint for amplitudes in mm");
    assert!(hint.contains("in mm"), "{hint}");
}

/// A model that does not fit its noise has no valid intervals
/// (`FitResult::misfit`): a linear model fitted to hardening Duffing data
/// with 1 % amplitude noise is far above the noise, so `intervals_valid()`
/// is false and `misfit` carries the residual over the noise; the Duffing
/// model on the same data fits its noise and keeps its intervals.
#[test]
fn a_model_that_does_not_fit_its_noise_has_no_valid_intervals() {
    let wn = TWO_PI * 10.0;
    let t = Parameters::from([wn * wn, 2.0 * 0.02 * wn, 1.0e6, 2.0, 0.0, 0.0, 1.0]);
    let mut d = data(
        &t,
        &[0.5, 1.0, 2.0],
        (8.0, 13.0),
        150,
        &[SweepDirection::Up],
        None,
    );
    let mut rng = support::fixtures::Rng(0x5eed_0024);
    for c in &mut d.curves {
        for a in &mut c.amplitudes {
            *a *= 1.0 + 0.01 * rng.normal();
        }
    }
    let lin = identify(&d, &FitPlan::new(ModelKind::Linear), &|_| {}).unwrap();
    assert!(!lin.adequacy.adequate);
    let r = lin.fit.misfit.expect("a misfit is recorded on the fit");
    assert!(
        r > nlsdof::identification::identify::ADEQUACY_CURVE.sqrt(),
        "residual/noise {r}"
    );
    assert!(lin.fit.uncertainty.is_some() && !lin.fit.intervals_valid());
    // the number the first line quotes
    let msg = lin.adequacy_message().unwrap();
    assert!(msg.contains(&format!("residual {r:.1}x")), "{msg} vs {r}");
    let duf = identify(&d, &FitPlan::new(ModelKind::Duffing), &|_| {}).unwrap();
    assert!(duf.adequacy.adequate, "{:?}", duf.adequacy_message());
    assert_eq!(duf.fit.misfit, None);
    assert!(duf.fit.intervals_valid(), "{:?}", duf.fit.warning());
}
