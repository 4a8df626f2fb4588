//! Softening stiffness (β < 0) in the sweep fit (Eq 31): the sign choice of
//! `FitSpec::new_signed`, noise-free recovery of a softening Duffing whose
//! down-sweeps jump on the low-frequency side, and clean failure for
//! parameter sets whose backbone has no positive frequency.

mod support;
use nlsdof::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use nlsdof::identification::models::*;
use nlsdof::identification::objective::{model_amplitudes, normalised_model};
use nlsdof::identification::phase_resonance::{model_points, PrDataset, PrPoint};
use nlsdof::identification::*;
use support::fixtures::Rng;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// f_n = 10 Hz, ζ = 1 %, k_eq/k = −6 % at 1 cm (softening Duffing).
fn truth() -> Parameters {
    let wn = TWO_PI * 10.0;
    let alpha = wn * wn;
    Parameters::from([
        alpha,
        2.0 * 0.01 * wn,
        -0.06 * alpha / (0.75 * 1e-4),
        2.0,
        0.0,
        0.0,
        1.0,
    ])
}

fn synthetic(theta: &Parameters, gammas: &[f64], steps: usize) -> Dataset {
    let omegas: Vec<f64> = (0..steps)
        .map(|i| TWO_PI * (8.8 + 2.2 * i as f64 / (steps - 1) as f64))
        .collect();
    let mut recs = Vec::new();
    for (l, &g) in gammas.iter().enumerate() {
        for d in [SweepDirection::Up, SweepDirection::Down] {
            for &w in &omegas {
                recs.push(Record {
                    level: format!("L{l}"),
                    gamma: g,
                    omega: w,
                    amplitude: 1.0,
                    phase: None,
                    direction: d,
                    weight: 1.0,
                });
            }
        }
    }
    let mut data = Dataset::from_records(&recs).unwrap();
    let amps = model_amplitudes(&data, theta).unwrap();
    for (c, a) in data.curves.iter_mut().zip(amps) {
        c.amplitudes = a;
    }
    data
}

#[test]
fn softening_down_sweep_jumps_below_the_up_sweep_jump() {
    // hysteresis on the low-frequency side: the down-sweep stays on the
    // large-amplitude branch down to the lower fold, the up-sweep jumps up
    // at the upper fold — both below f_n
    let th = truth();
    let r =
        ForcedResponse::from_normalised(&normalised_model(&th), 0.6, Formulation::HarmonicBalance)
            .unwrap();
    let omegas: Vec<f64> = (0..400)
        .map(|i| TWO_PI * (8.8 + 2.2 * i as f64 / 399.0))
        .collect();
    let up = r.sweep(&omegas, SweepDirection::Up).unwrap();
    let down = r.sweep(&omegas, SweepDirection::Down).unwrap();
    let (ju, jd) = (up.jumps[0], down.jumps[0]);
    assert!(
        ju.amplitude_after > ju.amplitude_before,
        "up-sweep jumps up"
    );
    assert!(
        jd.amplitude_after < jd.amplitude_before,
        "down-sweep jumps down"
    );
    assert!(
        jd.omega < ju.omega,
        "down jump {} below up jump {}",
        jd.omega,
        ju.omega
    );
    assert!(ju.omega < th[ALPHA].sqrt());
}

#[test]
fn softening_duffing_recovered_from_noise_free_sweeps() {
    let th = truth();
    let data = synthetic(&th, &[0.1, 0.35, 0.6], 60);
    // the top level jumps in both directions
    let top: Vec<_> = data.curves.iter().filter(|c| c.level == "L2").collect();
    for c in &top {
        assert!(
            c.measured_jump(1.5).is_some(),
            "{:?} sweep has a jump",
            c.direction
        );
    }
    let spec = FitSpec::new_signed(ModelKind::Duffing, &data, Sign::Softening);
    assert_eq!(spec.stiffness_sign, Sign::Softening);
    assert!(spec.start[BETA] < 0.0);
    let r = fit(
        &data,
        &spec,
        &FitOptions {
            starts: 4,
            ..Default::default()
        },
        &|| {},
    )
    .unwrap();
    for j in [ALPHA, DELTA, BETA] {
        assert!(
            ((r.theta[j] - th[j]) / th[j]).abs() < 1e-8,
            "{}: {} vs {} ({}, cost {:e})",
            PARAM_NAMES[j],
            r.theta[j],
            th[j],
            r.termination,
            r.cost
        );
    }
    // the hardening fit of the same data is clearly worse
    let hard = fit(
        &data,
        &FitSpec::new_signed(ModelKind::Duffing, &data, Sign::Hardening),
        &FitOptions::default(),
        &|| {},
    )
    .unwrap();
    assert!(hard.theta[BETA] > 0.0);
    assert!(
        hard.cost > 1e6 * r.cost.max(1e-30),
        "{} vs {}",
        hard.cost,
        r.cost
    );
}

#[test]
fn softening_spec_fix_and_bounds() {
    let data = synthetic(&truth(), &[0.1, 0.35], 20);
    let spec = FitSpec::new_signed(ModelKind::Duffing, &data, Sign::Softening);
    // |beta_ref| bounded below alpha0: the backbone keeps a positive frequency at A_ref
    assert!(spec.bounds[BETA].1 <= 0.95 * spec.start[ALPHA] * (1.0 + 1e-15));
    let mut s = spec.clone();
    s.fix("beta", -1.0e6).unwrap();
    assert_eq!(s.status[BETA], Status::Fixed(-1.0e6));
    assert!(matches!(
        s.fix("beta", 0.0),
        Err(SpecError::BadFixedValue { name: "beta", .. })
    ));
    // models without stiffness ignore the sign
    let lin = FitSpec::new_signed(ModelKind::Linear, &data, Sign::Softening);
    assert_eq!(lin.start[BETA], 0.0);
}

#[test]
fn strongly_softening_parameter_sets_fail_cleanly() {
    // |k_eq| > k already at small amplitudes: no backbone frequency, escape
    // branches. Every evaluation returns a value or a typed error, no panic,
    // and the fit from such a start still returns a typed result.
    let data = synthetic(&truth(), &[0.1, 0.35, 0.6], 30);
    let mut th = truth();
    for factor in [10.0, 1e3, 1e6] {
        th[BETA] = truth()[BETA] * factor;
        match model_amplitudes(&data, &th) {
            Ok(a) => assert!(a.iter().flatten().all(|v| v.is_finite() && *v >= 0.0)),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
        let pts = PrDataset::new(vec![PrPoint {
            level: "x".into(),
            gamma: 0.6,
            omega: 60.0,
            amplitude: 1e-2,
            weight: 1.0,
        }])
        .unwrap();
        // no 90° point: on the backbone Ω² = α(1 − 0.6 factor (a/1 cm)²)
        // the force a Ω δ stays below γ = 0.6 (at factor 10 its maximum is
        // ≈ 0.0091 · 62.8 · √0.5 · 1.257 ≈ 0.51), the response escapes
        assert_eq!(model_points(&pts, &th).unwrap()[0], None);
    }
    let mut spec = FitSpec::new_signed(ModelKind::Duffing, &data, Sign::Softening);
    spec.start[BETA] *= 50.0;
    spec.bounds[BETA].1 *= 1e3;
    match fit(&data, &spec, &FitOptions::default(), &|| {}) {
        Ok(r) => assert!(r.cost.is_finite()),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

#[test]
fn softening_jacobian_in_optimisation_variables_matches_finite_differences() {
    // generalised softening model: u_β = ln(−β_ref), the ρ column carries
    // ∂β/∂ρ of the reparametrisation; levels low enough for no jumps
    use nlsdof::identification::objective::Problem;
    let mut th = truth();
    th[RHO] = 2.4;
    th[BETA] = -0.06 * th[ALPHA] / (nlsdof::power_law::g_unchecked(2.4) * 0.01f64.powf(2.4));
    let data = synthetic(&th, &[0.05, 0.15], 25);
    let spec = FitSpec::new_signed(ModelKind::GeneralisedStiffness, &data, Sign::Softening);
    let p = Problem::new(&data, &spec).unwrap();
    let u_true = p.u_of(&th);
    let back = p.theta(&u_true);
    for j in [ALPHA, DELTA, BETA, RHO] {
        assert!(
            ((back[j] - th[j]) / th[j]).abs() < 1e-13,
            "round trip {}",
            PARAM_NAMES[j]
        );
    }
    let mut rng = Rng(9);
    for _ in 0..4 {
        let u: Vec<f64> = u_true
            .iter()
            .map(|v| v + 0.05 * (rng.uniform() - 0.5))
            .collect();
        assert!(p.theta(&u)[BETA] < 0.0);
        support::fixtures::assert_jacobian_matches_fd(&p, &u);
    }
}
