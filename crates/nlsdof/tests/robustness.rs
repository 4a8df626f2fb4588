//! Random valid parameters never panic and never produce NaN:
//! η ∈ [−1, 6], ρ ∈ [−1, 8], m ∈ [1e-12, 1e6] kg, f_n ∈ [0.1 Hz, 1 MHz],
//! hardening and softening, weak to strong nonlinearity.

use nlsdof::*;
use proptest::prelude::*;
use std::f64::consts::PI;

fn model(
    log_m: f64,
    log_fn: f64,
    log_zeta: f64,
    rho: f64,
    eta: f64,
    stiff_strength: f64,
    damp_strength: f64,
    gamma: f64,
) -> Model {
    let m = 10f64.powf(log_m);
    let wn = 2.0 * PI * 10f64.powf(log_fn);
    let zeta = 10f64.powf(log_zeta);
    let a_res = gamma / (wn * wn) / (2.0 * zeta);
    // k_eq(a_res)/k = stiff_strength, c_eq(a_res, ω_n)/c = damp_strength
    let kr = stiff_strength * m * wn * wn / (power_law::g(rho).unwrap() * a_res.powf(rho));
    let ce = damp_strength.abs() * 2.0 * zeta * m * wn
        / (power_law::g(eta).unwrap() * (wn * a_res).powf(eta));
    Model::linear(m, m * wn * wn, 2.0 * zeta * m * wn)
        .unwrap()
        .with_stiffness(kr, rho)
        .unwrap()
        .with_damping(ce, eta)
        .unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    #[test]
    fn never_panics_never_nan(
        log_m in -12.0f64..6.0,
        log_fn in -1.0f64..6.0,
        log_zeta in -4.0f64..-0.5,
        rho in -1.0f64..8.0,
        eta in -1.0f64..6.0,
        stiff in prop_oneof![-0.9f64..-1e-6, 1e-6f64..100.0],
        damp in 0.0f64..100.0,
        log_gamma in -3.0f64..3.0,
        nu in 0.2f64..3.0,
        modulation in any::<bool>(),
    ) {
        let gamma = 10f64.powf(log_gamma);
        let m = model(log_m, log_fn, log_zeta, rho, eta, stiff, damp, gamma);
        let form = if modulation { Formulation::Modulation } else { Formulation::HarmonicBalance };
        let r = ForcedResponse::new(&m, gamma, form).unwrap();
        let wn = m.omega_n();
        // The only admissible failure: a steady state whose amplitude is not
        // representable in f64 (e.g. ρ → −1 makes the stiffness force a
        // near-constant preload and the root lies below 1e-300 m).
        let out_of_range = |e: &SolveError| matches!(e, SolveError::Overflow { amplitude, .. }
            if !(amplitude.abs() > 1e-280 && amplitude.abs() < 1e280));
        let set = match r.steady_states(nu * wn) {
            Ok(set) => set,
            Err(e) => { prop_assert!(out_of_range(&e), "{e}"); return Ok(()); }
        };
        for s in &set.roots {
            prop_assert!(s.amplitude.is_finite() && s.amplitude > 0.0 && s.phase.is_finite());
        }
        prop_assert!(set.roots.windows(2).all(|w| w[0].amplitude < w[1].amplitude));
        if set.roots.is_empty() {
            prop_assert!(set.no_motion.is_some());
        }
        let omegas: Vec<f64> = (0..25).map(|i| wn * (0.5 + 1.5 * i as f64 / 24.0)).collect();
        for dir in [SweepDirection::Up, SweepDirection::Down] {
            let s = match r.sweep(&omegas, dir) {
                Ok(s) => s,
                Err(e) => { prop_assert!(out_of_range(&e), "{e}"); continue; }
            };
            prop_assert_eq!(s.points.len(), omegas.len());
            for p in &s.points {
                prop_assert!(p.amplitude.is_finite() && p.phase.is_finite());
            }
            for f in &s.folds {
                prop_assert!(f.omega.is_finite() && f.amplitude.is_finite());
            }
            for j in &s.jumps {
                prop_assert!(j.amplitude_before.is_finite() && j.amplitude_after.is_finite());
            }
        }
        if let Some(pq) = r.phase_quadrature().unwrap() {
            prop_assert!(pq.omega.is_finite() && pq.amplitude.is_finite());
        }
    }
}

#[test]
fn invalid_inputs_are_typed_errors() {
    let m = Model::linear(1.0, 100.0, 0.1).unwrap();
    let r = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance).unwrap();
    assert!(matches!(
        ForcedResponse::new(&m, f64::NAN, Formulation::HarmonicBalance),
        Err(SolveError::Parameter(ParameterError::NotFinite {
            name: "gamma",
            ..
        }))
    ));
    assert!(matches!(
        ForcedResponse::new(&m, -1.0, Formulation::HarmonicBalance),
        Err(SolveError::Parameter(ParameterError::NotPositive { name: "gamma", value })) if value == -1.0
    ));
    assert!(r.steady_states(0.0).is_err());
    assert!(r.steady_states(f64::NAN).is_err());
    assert!(matches!(
        r.sweep(&[1.0, 2.0, 2.0], SweepDirection::Up),
        Err(SolveError::Parameter(ParameterError::NotIncreasing {
            index: 2,
            ..
        }))
    ));
    assert!(matches!(
        r.sweep(&[], SweepDirection::Up),
        Err(SolveError::Parameter(ParameterError::Empty { .. }))
    ));
    assert!(matches!(
        r.folds(5.0, 1.0),
        Err(SolveError::Parameter(ParameterError::InvalidRange { .. }))
    ));
    let bad = Model { mass: -1.0, ..m };
    assert!(matches!(
        ForcedResponse::new(&bad, 1.0, Formulation::HarmonicBalance),
        Err(SolveError::Parameter(ParameterError::NotPositive {
            name: "mass",
            ..
        }))
    ));
}
