//! Identification from phase-resonance points (γ, f_PQ, a_PQ): the model
//! point against closed forms (linear limit, Duffing backbone), the two
//! 90° conditions and the steady states of the harmonic balance; the
//! analytic Jacobian against finite differences; noise-free recovery of
//! every model; identifiability and bad-data errors.

mod support;
use nlsdof::harmonic_balance::{ForcedResponse, Formulation};
use nlsdof::identification::models::*;
use nlsdof::identification::objective::normalised_model;
use nlsdof::identification::phase_resonance::*;
use nlsdof::identification::Parameters;
use nlsdof::identification::{ModelKind, Sign, SpecError, Status};
use nlsdof::power_law::g_unchecked;
use support::fixtures::Rng;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

/// f_n = 10 Hz, ζ = 1 %.
fn base() -> Parameters {
    let wn = TWO_PI * 10.0;
    Parameters::from([wn * wn, 2.0 * 0.01 * wn, 0.0, 0.0, 0.0, 0.0, 1.0])
}

/// True parameters of each model (4 % backbone shift and 80 % extra
/// damping at 1 cm; softening: −3 %).
fn truth(kind: ModelKind, sign: Sign) -> Parameters {
    let mut t = base();
    let a_ref: f64 = 0.01;
    let wn2 = t[ALPHA];
    let d = t[DELTA];
    let stiff = |t: &mut Parameters, rho: f64| {
        t[RHO] = rho;
        let k = if sign == Sign::Softening { -0.06 } else { 0.08 };
        t[BETA] = k * wn2 / (g_unchecked(rho) * a_ref.powf(rho));
    };
    match kind.stiffness() {
        Term::FixedExponent(r) => stiff(&mut t, r),
        Term::FreeExponent => stiff(&mut t, 2.6),
        Term::Absent => {}
    }
    let damp = |t: &mut Parameters, eta: f64| {
        t[ETA] = eta;
        t[KAPPA] = 0.8 * d / (g_unchecked(eta) * (TWO_PI * 10.0 * a_ref).powf(eta));
    };
    match kind.damping() {
        Term::FixedExponent(e) => damp(&mut t, e),
        Term::FreeExponent => damp(&mut t, 1.7),
        Term::Absent => {}
    }
    if kind == ModelKind::Coulomb {
        t[KAPPA] = 0.02;
    }
    t
}

const GAMMAS: [f64; 5] = [0.1, 0.2, 0.35, 0.5, 0.7];

/// Exact harmonic-balance phase-quadrature points of θ at `gammas`.
fn points(theta: &Parameters, gammas: &[f64]) -> PrDataset {
    let mut pts = Vec::new();
    for (i, &g) in gammas.iter().enumerate() {
        let r = ForcedResponse::from_normalised(
            &normalised_model(theta),
            theta[GAIN] * g,
            Formulation::HarmonicBalance,
        )
        .unwrap();
        let q = r.phase_quadrature().unwrap().expect("phase quadrature");
        pts.push(PrPoint {
            level: format!("L{i}"),
            gamma: g,
            omega: q.omega,
            amplitude: q.amplitude,
            weight: 1.0,
        });
    }
    PrDataset::new(pts).unwrap()
}

#[test]
fn model_point_linear_limit_closed_form() {
    // f_PQ = √α/2π, a_PQ = gain γ/(δ √α)
    let mut th = base();
    th[GAIN] = 1.7;
    let d = points(&th, &[0.3, 1.1]);
    for (p, m) in d.points.iter().zip(model_points(&d, &th).unwrap()) {
        let (w, a) = m.unwrap();
        let wn = th[ALPHA].sqrt();
        assert!(rel(w, wn) < 1e-13, "{w} vs {wn}");
        let a_ref = th[GAIN] * p.gamma / (th[DELTA] * wn);
        assert!(rel(a, a_ref) < 1e-12, "{a} vs {a_ref}");
    }
}

#[test]
fn model_point_duffing_backbone_closed_form() {
    // S = 0: Ω² = α + ¾ β a², and a Ω δ = gain γ ⇒
    // Ω² = (α + √(α² + 3 β (gain γ/δ)²)) / 2 for both signs of β
    // (softening: while α² + 3β(γ/δ)² > 0).
    for (beta, gain) in [(3.0e6, 1.0), (8.0e5, 2.5), (-6.0e5, 1.0)] {
        let mut th = base();
        th[BETA] = beta;
        th[RHO] = 2.0;
        th[GAIN] = gain;
        for &g in &[0.05, 0.2, 0.6] {
            let r = ForcedResponse::from_normalised(
                &normalised_model(&th),
                gain * g,
                Formulation::HarmonicBalance,
            )
            .unwrap();
            let q = r.phase_quadrature().unwrap().unwrap();
            let (al, de) = (th[ALPHA], th[DELTA]);
            let disc = al * al + 3.0 * beta * (gain * g / de).powi(2);
            assert!(disc > 0.0);
            let w = (0.5 * (al + disc.sqrt())).sqrt();
            let a = gain * g / (de * w);
            assert!(
                rel(q.omega, w) < 1e-12,
                "beta {beta} gamma {g}: {} vs {w}",
                q.omega
            );
            assert!(rel(q.amplitude, a) < 1e-11, "{} vs {a}", q.amplitude);
        }
    }
}

#[test]
fn model_point_satisfies_both_conditions_and_is_a_steady_state() {
    let th = truth(ModelKind::Generalised, Sign::Hardening);
    let d = points(&th, &GAMMAS);
    for p in &d.points {
        let (w, a) = (p.omega, p.amplitude);
        let s = th[ALPHA] + g_unchecked(th[RHO]) * th[BETA] * a.powf(th[RHO]) - w * w;
        let dd = th[DELTA] + g_unchecked(th[ETA]) * th[KAPPA] * (w * a).powf(th[ETA]);
        assert!(s.abs() < 1e-11 * th[ALPHA], "S = {s}");
        assert!(rel(a * w * dd, p.gamma) < 1e-12);
        // the response at Ω_PQ has a steady state at a_PQ with 90° phase lag
        let r = ForcedResponse::from_normalised(
            &normalised_model(&th),
            p.gamma,
            Formulation::HarmonicBalance,
        )
        .unwrap();
        let set = r.steady_states(w).unwrap();
        let hit = set
            .roots
            .iter()
            .find(|s| rel(s.amplitude, a) < 1e-9)
            .expect("root at a_PQ");
        assert!((hit.phase - std::f64::consts::FRAC_PI_2).abs() < 1e-8);
    }
}

#[test]
fn quadrature_derivatives_match_finite_differences() {
    let mut rng = Rng(11);
    let mut checked = 0;
    for trial in 0..40 {
        let wn = TWO_PI * (5.0 + 20.0 * rng.uniform());
        let softening = trial % 3 == 2;
        let mut th = Parameters::from([
            wn * wn,
            wn * (0.005 + 0.03 * rng.uniform()),
            0.0,
            0.5 + 4.0 * rng.uniform(),
            0.0,
            -0.8 + 3.0 * rng.uniform(),
            0.5 + rng.uniform(),
        ]);
        let gamma = 0.1 + rng.uniform();
        // coefficients sized at the linear resonance amplitude
        let a0 = th[GAIN] * gamma / (th[DELTA] * wn);
        let shift = if softening { -0.05 } else { 0.1 } * rng.uniform().max(0.1);
        th[BETA] = shift * th[ALPHA] / (g_unchecked(th[RHO]) * a0.powf(th[RHO]));
        th[KAPPA] =
            (0.2 + rng.uniform()) * th[DELTA] / (g_unchecked(th[ETA]) * (wn * a0).powf(th[ETA]));
        let d = PrDataset::new(vec![PrPoint {
            level: "x".into(),
            gamma,
            omega: 1.0,
            amplitude: 1.0,
            weight: 1.0,
        }])
        .unwrap();
        let Some((w, a)) = model_points(&d, &th).unwrap()[0] else {
            continue;
        };
        let (da, dw) = quadrature_derivatives(&th, gamma, w, a).unwrap();
        for j in 0..N_PARAMS {
            let h = 1e-6 * th[j].abs().max(1e-3);
            let mut tp = th;
            let mut tm = th;
            tp[j] += h;
            tm[j] -= h;
            let (wp, ap) = model_points(&d, &tp).unwrap()[0].unwrap();
            let (wm, am) = model_points(&d, &tm).unwrap()[0].unwrap();
            let fa = (ap - am) / (2.0 * h);
            let fw = (wp - wm) / (2.0 * h);
            // relative to the sensitivity scale of the output
            let sa = (a / th[j].abs().max(1e-3)).max(fa.abs());
            let sw = (w / th[j].abs().max(1e-3)).max(fw.abs());
            assert!(
                (da[j] - fa).abs() < 2e-6 * sa,
                "trial {trial} da/d{}: {} vs FD {fa}",
                PARAM_NAMES[j],
                da[j]
            );
            assert!(
                (dw[j] - fw).abs() < 2e-6 * sw,
                "trial {trial} dΩ/d{}: {} vs FD {fw}",
                PARAM_NAMES[j],
                dw[j]
            );
        }
        checked += 1;
    }
    assert!(checked >= 30, "only {checked} parameter sets checked");
}

fn check_recovery(kind: ModelKind, sign: Sign, starts: usize) {
    let th = truth(kind, sign);
    let d = points(&th, &GAMMAS);
    let spec = default_spec(kind, &d, sign);
    let opts = PrFitOptions {
        starts,
        ..Default::default()
    };
    let r = fit_phase_resonance(&d, &spec, &opts, &|| {})
        .unwrap_or_else(|e| panic!("{kind} ({sign:?}): {e}"));
    for j in spec.free_indices() {
        assert!(
            rel(r.theta[j], th[j]) < 1e-8,
            "{kind} ({sign:?}) {}: {} vs {} (cost {:e}, {})",
            PARAM_NAMES[j],
            r.theta[j],
            th[j],
            r.cost,
            r.termination
        );
    }
    for row in &r.rows {
        let (df, da) = row.differences_percent();
        assert!(df.abs() < 1e-8 && da.abs() < 1e-8);
    }
}

#[test]
fn noise_free_recovery_every_model() {
    for kind in ModelKind::ALL {
        check_recovery(kind, Sign::Hardening, 8);
    }
}

#[test]
fn noise_free_recovery_softening() {
    for kind in [
        ModelKind::Duffing,
        ModelKind::DuffingQuadratic,
        ModelKind::Generalised,
    ] {
        check_recovery(kind, Sign::Softening, 8);
    }
}

#[test]
fn gain_recovered_when_damping_is_fixed() {
    let mut th = truth(ModelKind::Duffing, Sign::Hardening);
    th[GAIN] = 2.3;
    let d = points(&th, &GAMMAS);
    let mut spec = default_spec(ModelKind::Duffing, &d, Sign::Hardening);
    spec.fix("delta", th[DELTA]).unwrap();
    spec.free("gain").unwrap();
    let r = fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}).unwrap();
    for j in [ALPHA, BETA, GAIN] {
        assert!(rel(r.theta[j], th[j]) < 1e-8, "{}", PARAM_NAMES[j]);
    }
}

#[test]
fn noisy_points_give_intervals() {
    // 1 % amplitude and 0.01 % (= ζ · 1 %) frequency noise on 8 levels: the
    // estimate is near the truth and the reported intervals are finite and ordered.
    let th = truth(ModelKind::DuffingQuadratic, Sign::Hardening);
    let gammas: Vec<f64> = (0..8).map(|i| 0.1 + 0.1 * i as f64).collect();
    let mut d = points(&th, &gammas);
    let mut rng = Rng(5);
    for p in &mut d.points {
        p.amplitude *= 1.0 + 0.01 * (2.0 * rng.uniform() - 1.0);
        p.omega *= 1.0 + 1e-4 * (2.0 * rng.uniform() - 1.0);
    }
    let spec = default_spec(ModelKind::DuffingQuadratic, &d, Sign::Hardening);
    let r = fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}).unwrap();
    let u = r.uncertainty.as_ref().expect("intervals");
    assert_eq!(u.names, vec!["alpha", "delta", "beta", "kappa"]);
    for k in 0..u.names.len() {
        assert!(u.std_errors[k] > 0.0 && u.lower[k] < u.values[k] && u.values[k] < u.upper[k]);
    }
    assert!(rel(r.theta[ALPHA], th[ALPHA]) < 1e-3);
    assert!(rel(r.theta[BETA], th[BETA]) < 0.2, "{}", r.theta[BETA]);
}

#[test]
fn identifiability_errors_name_the_parameters() {
    let th = truth(ModelKind::Duffing, Sign::Hardening);
    let d = points(&th, &GAMMAS);
    // gain and the free damping coefficients: scale invariance
    let mut spec = default_spec(ModelKind::DuffingQuadratic, &d, Sign::Hardening);
    spec.free("gain").unwrap();
    match fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}) {
        Err(PrFitError::NotIdentifiable { parameters, .. }) => {
            assert_eq!(parameters, vec!["gain", "delta", "kappa"])
        }
        other => panic!("{other:?}"),
    }
    // generalised stiffness (alpha, beta, rho) from 2 levels
    let d2 = points(&th, &[0.2, 0.5]);
    let spec = default_spec(ModelKind::GeneralisedStiffness, &d2, Sign::Hardening);
    let e = fit_phase_resonance(&d2, &spec, &PrFitOptions::default(), &|| {}).unwrap_err();
    match &e {
        PrFitError::NotIdentifiable { parameters, .. } => {
            assert_eq!(parameters, &vec!["alpha", "beta", "rho"])
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("at least 3 levels"), "{e}");
    // too few equations: generalised (6 free) from 2 levels
    let spec = default_spec(ModelKind::Generalised, &d2, Sign::Hardening);
    assert!(matches!(
        fit_phase_resonance(&d2, &spec, &PrFitOptions::default(), &|| {}),
        Err(PrFitError::TooFewPoints {
            points: 2,
            equations: 4,
            free: 6,
            ..
        })
    ));
    // numerical: kappa held at 0 leaves gain and delta in a scale
    // invariance the structural check cannot see
    let mut spec = default_spec(ModelKind::Quadratic, &d, Sign::Hardening);
    spec.fix("kappa", 0.0).unwrap();
    spec.free("gain").unwrap();
    match fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}) {
        Err(PrFitError::RankDeficient { parameters, ratio }) => {
            assert!(ratio < RANK_TOLERANCE);
            assert!(
                parameters.contains(&"gain") && parameters.contains(&"delta"),
                "{parameters:?}"
            );
        }
        other => panic!("{other:?}"),
    }
    // nothing free
    let mut spec = default_spec(ModelKind::Linear, &d, Sign::Hardening);
    spec.status[ALPHA] = Status::Fixed(th[ALPHA]);
    spec.status[DELTA] = Status::Fixed(th[DELTA]);
    assert!(matches!(
        fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}),
        Err(PrFitError::Spec(SpecError::NothingFree))
    ));
    // bad frequency weight
    let spec = default_spec(ModelKind::Linear, &d, Sign::Hardening);
    for w in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            fit_phase_resonance(
                &d,
                &spec,
                &PrFitOptions {
                    frequency_weight: w,
                    ..Default::default()
                },
                &|| {}
            ),
            Err(PrFitError::BadFrequencyWeight(_))
        ));
    }
}

#[test]
fn linear_model_from_one_level() {
    // 2 equations, 2 parameters: exactly determined, no intervals
    let th = base();
    let d = points(&th, &[0.4]);
    let spec = default_spec(ModelKind::Linear, &d, Sign::Hardening);
    let r = fit_phase_resonance(&d, &spec, &PrFitOptions::default(), &|| {}).unwrap();
    assert!(rel(r.theta[ALPHA], th[ALPHA]) < 1e-12);
    assert!(rel(r.theta[DELTA], th[DELTA]) < 1e-10);
    assert!(r.uncertainty.is_none());
}

fn pt(level: &str, gamma: f64, f_hz: f64, amplitude: f64) -> PrPoint {
    PrPoint {
        level: level.into(),
        gamma,
        omega: TWO_PI * f_hz,
        amplitude,
        weight: 1.0,
    }
}

#[test]
fn bad_data_errors() {
    assert_eq!(PrDataset::new(vec![]).unwrap_err(), PrDataError::Empty);
    let e = PrDataset::new(vec![
        pt("a", 0.1, 10.0, 1e-3),
        pt("b", f64::NAN, 10.0, 1e-3),
    ])
    .unwrap_err();
    assert!(matches!(e, PrDataError::NotFinite { ref level, what: "gamma", .. } if level == "b"));
    let e = PrDataset::new(vec![pt("a", 0.1, -10.0, 1e-3)]).unwrap_err();
    assert!(
        matches!(e, PrDataError::NotPositive { what: "frequency [Hz]", value, .. } if value == -10.0)
    );
    let e = PrDataset::new(vec![pt("a", 0.1, 10.0, 0.0)]).unwrap_err();
    assert!(matches!(
        e,
        PrDataError::NotPositive {
            what: "amplitude",
            ..
        }
    ));
    let e = PrDataset::new(vec![pt("a", 0.1, 10.0, 1e-3), pt("b", 0.1, 10.1, 2e-3)]).unwrap_err();
    assert_eq!(
        e,
        PrDataError::DuplicateGamma {
            first: "a".into(),
            second: "b".into(),
            gamma: 0.1
        }
    );
    assert!(e.to_string().contains("0.1"), "{e}");
    let mut p = pt("a", 0.1, 10.0, 1e-3);
    p.weight = -1.0;
    assert!(matches!(
        PrDataset::new(vec![p.clone()]).unwrap_err(),
        PrDataError::BadWeight { value, .. } if value == -1.0
    ));
    p.weight = 0.0;
    assert_eq!(
        PrDataset::new(vec![p]).unwrap_err(),
        PrDataError::ZeroWeights
    );
    // sorted by gamma
    let d = PrDataset::new(vec![pt("hi", 0.5, 10.2, 3e-3), pt("lo", 0.1, 10.0, 1e-3)]).unwrap();
    assert_eq!(d.points[0].level, "lo");
}
