//! The measured-branch output error (`ResponseBranch::Measured`,
//! `identification::output_error`): exact at the truth, censored readings of
//! early jumps, continuity where a model fold crosses a measured step (Eq 31
//! jumps there), and its Jacobian and the fold derivatives against finite
//! differences.

mod support;

use nlsdof::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use nlsdof::identification::jumps::fold_derivatives;
use nlsdof::identification::models::*;
use nlsdof::identification::objective::{evaluate_branch, Problem};
use nlsdof::identification::output_error::{evaluate_measured, Compared, MatchOptions};
use nlsdof::identification::{Dataset, FitSpec, ModelKind, Parameters, ResponseBranch};
use support::fixtures::{assert_jacobian_matches_fd, hb_sweeps, Rng};

/// Hardening Duffing with quadratic damping, f_n = 10 Hz, ζ = 1 %: its top
/// levels jump in both sweep directions between 8 and 14 Hz.
fn truth() -> Parameters {
    let wn = 2.0 * std::f64::consts::PI * 10.0;
    Parameters::from([wn * wn, 2.0 * 0.01 * wn, 4.0e6, 2.0, 0.3, 1.0, 1.0])
}

fn cost(data: &Dataset, th: &Parameters, censored: &[bool]) -> f64 {
    let (e, _) = evaluate_measured(
        data,
        th,
        false,
        &MatchOptions {
            censored,
            ..MatchOptions::amplitudes()
        },
    )
    .unwrap();
    e.residuals.iter().map(|r| r * r).sum()
}

fn eq31(data: &Dataset, th: &Parameters) -> f64 {
    let e = evaluate_branch(data, th, false, None, ResponseBranch::Sweep).unwrap();
    e.residuals.iter().map(|r| r * r).sum()
}

/// At the truth on noise-free data every point is compared with the state
/// of the model's own sweep (Eq 31's), both readings, and no penalty is
/// charged: the cost is zero, like Eq 31's.
#[test]
fn the_truth_matches_every_point_on_its_own_sweep_with_no_penalty() {
    let th = truth();
    let data = hb_sweeps(
        &th,
        &[0.5, 2.0, 4.0],
        (8.0, 14.0),
        181,
        &[SweepDirection::Up, SweepDirection::Down],
        Some((1.0, 0.0)),
    );
    let jumps = data
        .curves
        .iter()
        .filter(|c| {
            c.amplitudes
                .windows(2)
                .any(|w| (w[0] / w[1]).max(w[1] / w[0]) > 1.3)
        })
        .count();
    assert!(jumps >= 4, "{jumps} curves jump");
    for censored in [vec![], vec![true; data.curves.len()]] {
        let (e, matches) = evaluate_measured(
            &data,
            &th,
            true,
            &MatchOptions {
                phase_weight: Some(1.0),
                censored: &censored,
                ..MatchOptions::amplitudes()
            },
        )
        .unwrap();
        let c: f64 = e.residuals.iter().map(|r| r * r).sum();
        assert!(c < 1e-24, "cost at the truth {c:e}");
        for m in &matches {
            assert_eq!(m.penalty, 0.0);
            assert!(m.compared.iter().all(|&k| k == Compared::Sweep));
        }
    }
    assert!(eq31(&data, &th) < 1e-24);
}

/// An up-sweep that left the upper branch early (the down-sweep's points,
/// labelled as an up-sweep): the censored reading matches it exactly at the
/// truth and reports where it left; the exact reading charges it, and Eq 31
/// charges it more (every point past the departure on the wrong branch).
#[test]
fn an_early_jump_is_free_when_censored_and_charged_when_exact() {
    let th = truth();
    let top = 4.0;
    let mut data = hb_sweeps(&th, &[top], (8.0, 14.0), 241, &[SweepDirection::Down], None);
    data.curves[0].direction = SweepDirection::Up;
    let censored = cost(&data, &th, &[true]);
    let exact = cost(&data, &th, &[false]);
    let sweep = eq31(&data, &th);
    let peak = data.curves[0]
        .amplitudes
        .iter()
        .fold(0.0f64, |m, &a| m.max(a));
    let scale = (peak / top).powi(2);
    assert!(censored < 1e-20 * scale, "censored {censored:e}");
    assert!(exact > 1e-3 * scale, "exact {exact:e}");
    assert!(exact <= sweep, "exact {exact:e} vs Eq 31 {sweep:e}");
    let (_, m) = evaluate_measured(
        &data,
        &th,
        false,
        &MatchOptions {
            censored: &[true],
            ..MatchOptions::amplitudes()
        },
    )
    .unwrap();
    let c = &data.curves[0];
    let first = m[0].left_early(c).expect("left early");
    let (wf, _) = m[0].fold.expect("the model's up-sweep jumps");
    // the departure (the down-sweep's jump-up) lies below the model's fold
    assert!(c.omegas[first] < wf);
    let r =
        ForcedResponse::from_normalised(&th.normalised_model(), top, Formulation::HarmonicBalance)
            .unwrap();
    let down = r.sweep(&c.omegas, SweepDirection::Down).unwrap();
    let lower_fold = down.jumps[0].omega;
    // the first point compared with the other (upper) state... is the
    // first one above the down-sweep's jump
    assert!(
        c.omegas[first] >= lower_fold,
        "{} vs {lower_fold}",
        c.omegas[first]
    );
    assert!(first == 0 || c.omegas[first - 1] < lower_fold + 1e-9);
}

/// Moving the model fold across a measured step: Eq 31 jumps by the square
/// of the drop, the measured-branch cost changes continuously (its largest
/// change between neighbouring α is of the size of the others).
#[test]
fn the_cost_is_continuous_where_a_fold_crosses_a_step() {
    let th = truth();
    let data = hb_sweeps(&th, &[4.0], (8.0, 14.0), 61, &[SweepDirection::Up], None);
    let n = 400;
    let (mut prev_m, mut prev_e) = (f64::NAN, f64::NAN);
    let (mut max_dm, mut max_de) = (0.0f64, 0.0f64);
    for k in 0..=n {
        // α from −2 % to +2 %: the fold moves over several steps
        let mut t = th;
        t[ALPHA] *= 1.0 - 0.02 + 0.04 * k as f64 / n as f64;
        let (m, e) = (cost(&data, &t, &[]), eq31(&data, &t));
        if k > 0 {
            max_dm = max_dm.max((m - prev_m).abs());
            max_de = max_de.max((e - prev_e).abs());
        }
        prev_m = m;
        prev_e = e;
    }
    let c = &data.curves[0];
    let drop = c
        .amplitudes
        .windows(2)
        .map(|w| (w[0] - w[1]) / 4.0)
        .fold(0.0f64, f64::max);
    // Eq 31 jumps by about a drop² at each crossing
    assert!(
        max_de > 0.3 * drop * drop,
        "Eq 31 steps {max_de:e}, drop² {:e}",
        drop * drop
    );
    assert!(
        max_dm < 0.05 * max_de,
        "measured-branch steps {max_dm:e} vs Eq 31 {max_de:e}"
    );
}

/// The Jacobian of the measured-branch problem against central
/// differences, at parameter sets around the truth where points are
/// compared with other states and fold ends (both readings, with phase;
/// the phase offset profiled out on the censored pass).
#[test]
fn measured_branch_jacobian_matches_finite_differences() {
    let th = truth();
    let data = hb_sweeps(
        &th,
        &[1.0, 4.0],
        (8.0, 14.0),
        47,
        &[SweepDirection::Up, SweepDirection::Down],
        Some((1.0, 0.0)),
    );
    let mut rng = Rng(11);
    let mut kinds = [0usize; 3];
    for censored in [false, true] {
        let mut spec = FitSpec::new(ModelKind::Generalised, &data);
        spec.branch = ResponseBranch::Measured;
        spec.phase_weight = Some(1.0);
        spec.censored = vec![censored; data.curves.len()];
        // the phase offset profiled out on the censored pass
        spec.profile_phase_offset = censored;
        let p = Problem::new(&data, &spec).unwrap();
        let mut checked = 0;
        while checked < 8 {
            let mut t = th;
            for v in [ALPHA, DELTA, BETA, KAPPA] {
                t[v] *= 1.0 + 0.04 * (rng.uniform() - 0.5);
            }
            t[RHO] += 0.1 * (rng.uniform() - 0.5);
            t[ETA] += 0.1 * (rng.uniform() - 0.5);
            let (_, m) = evaluate_measured(&data, &t, false, &MatchOptions::of(&spec)).unwrap();
            // near a fold da/dθ ~ 1/√(distance), and the truncation error of
            // central differences with step h grows like (h/distance)²
            // (measured: 1.4e-4 relative at 5e-5 from a fold, 3e-5 at 2.7e-4):
            // draws with a step within 1e-3 of a fold are not judged
            let near_fold = m.iter().zip(&data.curves).any(|(cm, c)| {
                let r = ForcedResponse::from_normalised(
                    &t.normalised_model(),
                    c.gamma,
                    Formulation::HarmonicBalance,
                )
                .unwrap();
                let folds = r.folds(c.omegas[0], c.omegas[c.omegas.len() - 1]).unwrap();
                let _ = cm;
                folds
                    .iter()
                    .any(|f| c.omegas.iter().any(|&w| (w / f.omega - 1.0).abs() < 1e-3))
            });
            if near_fold {
                continue;
            }
            checked += 1;
            for cm in &m {
                for &k in &cm.compared {
                    kinds[k as usize] += 1;
                }
            }
            assert_jacobian_matches_fd(&p, &p.u_of(&t));
        }
    }
    // the random sets exercise every kind of comparison
    assert!(kinds[1] > 0 && kinds[2] > 0, "{kinds:?}");
}

/// `da_f/dθ`, `dΩ_f/dθ` and `dφ_f/dθ` at a fold against central differences
/// of the fold located by `ForcedResponse::folds`.
#[test]
fn fold_derivatives_match_finite_differences() {
    let th = truth();
    let gamma = 4.0;
    let two_pi = 2.0 * std::f64::consts::PI;
    let fold_of = |t: &Parameters| {
        let r = ForcedResponse::from_normalised(
            &t.normalised_model(),
            t[GAIN] * gamma,
            Formulation::HarmonicBalance,
        )
        .unwrap();
        let f = r.folds(two_pi * 8.0, two_pi * 16.0).unwrap();
        // the upper fold (end of the resonant branch)
        let f = *f.iter().find(|f| !f.pair_above).unwrap();
        let set = r.steady_states(f.omega * (1.0 - 1e-7)).unwrap();
        let _ = set;
        (f.omega, f.amplitude)
    };
    let (w, a) = fold_of(&th);
    let d = fold_derivatives(&th, gamma, w, a).unwrap();
    for j in [ALPHA, DELTA, BETA, RHO, KAPPA, ETA, GAIN] {
        let h = 1e-6 * th[j].abs().max(1e-3);
        let (mut tp, mut tm) = (th, th);
        tp[j] += h;
        tm[j] -= h;
        let ((wp, ap), (wm, am)) = (fold_of(&tp), fold_of(&tm));
        let fw = (wp - wm) / (2.0 * h);
        let fa = (ap - am) / (2.0 * h);
        assert!(
            (fw - d.omega[j]).abs() <= 1e-4 * fw.abs().max(1e-6 * w / th[j].abs().max(1e-3)),
            "dΩ/d{}: {} vs {fw}",
            PARAM_NAMES[j],
            d.omega[j]
        );
        assert!(
            (fa - d.amplitude[j]).abs() <= 1e-3 * fa.abs().max(1e-6 * a / th[j].abs().max(1e-3)),
            "da/d{}: {} vs {fa}",
            PARAM_NAMES[j],
            d.amplitude[j]
        );
    }
}
