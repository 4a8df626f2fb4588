//! Multi-harmonic balance against independent oracles:
//! finite-difference Jacobians, the exact first-order balance (H = 1),
//! periodic orbits found by shooting with the Dormand–Prince integrator
//! (their harmonics and the Floquet multipliers of the monodromy matrix),
//! the exact period of the conservative oscillator (backbone), the exact
//! first-order folds, and convergence in H.

mod support;
use nlsdof::excitation::Sine;
use nlsdof::multi_harmonic::backbone::multi_harmonic_backbone;
use nlsdof::multi_harmonic::*;
use nlsdof::simulation::{simulate_excitation, Method, Options, State};
use nlsdof::*;
use std::f64::consts::{PI, TAU};
use support::fixtures::wing_normalised as wing;

fn duffing_strong() -> NormalisedModel {
    Model::linear(1.0, 3947.84, 1.2566)
        .unwrap()
        .with_stiffness(1.2e7, 2.0)
        .unwrap()
        .normalised()
        .unwrap()
}

fn power(rho: f64, beta: f64) -> NormalisedModel {
    NormalisedModel {
        alpha: 3947.84,
        delta: 1.2566,
        beta,
        rho,
        kappa: 0.0,
        eta: 0.0,
    }
}

fn coulomb() -> NormalisedModel {
    Model::linear(1.0, 1000.0, 0.5)
        .unwrap()
        .with_damping(2.0, -1.0)
        .unwrap()
        .normalised()
        .unwrap()
}

// ---------------------------------------------------------------- Jacobian

#[test]
fn jacobian_matches_central_differences() {
    let models = [
        ("duffing", duffing_strong(), 1e-2),
        ("wing", wing(), 5e-3),
        (
            "rho0.5_eta1.5",
            NormalisedModel {
                alpha: 3947.84,
                delta: 1.0,
                beta: 1e4,
                rho: 0.5,
                kappa: 30.0,
                eta: 1.5,
            },
            1e-2,
        ),
        ("coulomb", coulomb(), 2e-2),
        ("rho-0.5", power(-0.5, 50.0), 1e-2),
    ];
    for (name, m, amp) in models {
        let h = 5;
        let mut sys = HbSystem::new(
            &m,
            1.0,
            h,
            HarmonicSettings {
                samples: Some(512),
                regularisation: 0.05,
                ..HarmonicSettings::default()
            },
        )
        .unwrap();
        let nq = sys.dim();
        // a state with all harmonics, constant and even ones included
        let q: Vec<f64> = (0..nq)
            .map(|i| amp * (0.7 * (i as f64 + 1.0)).sin() / (1.0 + i as f64))
            .collect();
        let omega = 0.9 * m.omega_n();
        let mut r = vec![0.0; nq];
        let mut jac = vec![0.0; nq * nq];
        let mut dro = vec![0.0; nq];
        sys.residual_jacobian(&q, omega, &mut r, &mut jac, &mut dro);
        let scale = sys.residual_scale(&q, omega) / amp;
        let mut rp = vec![0.0; nq];
        let mut rm = vec![0.0; nq];
        let mut worst: f64 = 0.0;
        // fourth-order central differences (truncation O(h^4))
        let mut r2p = vec![0.0; nq];
        let mut r2m = vec![0.0; nq];
        for j in 0..nq {
            let hstep = 1e-5 * amp;
            let shifted = |d: f64| {
                let mut v = q.clone();
                v[j] += d;
                v
            };
            sys.residual(&shifted(hstep), omega, &mut rp);
            sys.residual(&shifted(-hstep), omega, &mut rm);
            sys.residual(&shifted(2.0 * hstep), omega, &mut r2p);
            sys.residual(&shifted(-2.0 * hstep), omega, &mut r2m);
            for i in 0..nq {
                let fd = (8.0 * (rp[i] - rm[i]) - (r2p[i] - r2m[i])) / (12.0 * hstep);
                worst = worst.max((fd - jac[i * nq + j]).abs() / scale);
            }
        }
        let ho = 1e-5 * omega;
        sys.residual(&q, omega + ho, &mut rp);
        sys.residual(&q, omega - ho, &mut rm);
        sys.residual(&q, omega + 2.0 * ho, &mut r2p);
        sys.residual(&q, omega - 2.0 * ho, &mut r2m);
        let dscale = sys.residual_scale(&q, omega) / omega;
        let mut worst_o: f64 = 0.0;
        for i in 0..nq {
            let fd = (8.0 * (rp[i] - rm[i]) - (r2p[i] - r2m[i])) / (12.0 * ho);
            worst_o = worst_o.max((fd - dro[i]).abs() / dscale);
        }
        eprintln!("{name}: Jacobian vs 4th-order FD: dR/dq {worst:.1e}, dR/dOmega {worst_o:.1e}");
        assert!(worst < 1e-7, "{name}: dR/dq error {worst:e}");
        assert!(worst_o < 1e-7, "{name}: dR/dOmega error {worst_o:e}");
    }
}

// ------------------------------------------------------- H = 1 vs first order

#[test]
fn one_harmonic_equals_exact_first_order() {
    // (model, gamma, frequencies in units of f_n, fixed N or adaptive)
    let cases: Vec<(&str, NormalisedModel, f64, Vec<f64>, Option<usize>)> = vec![
        (
            "duffing (exact projection)",
            duffing_strong(),
            2.0,
            vec![0.8, 1.0, 1.1, 1.25, 1.3, 1.5],
            None,
        ),
        (
            "rho=0.5",
            power(0.5, 1e4),
            1.0,
            vec![0.7, 1.0, 1.02, 1.3],
            Some(1 << 17),
        ),
        (
            "rho=5.5",
            power(5.5, 1e14),
            2.0,
            vec![0.9, 1.0, 1.05, 1.2],
            Some(1 << 14),
        ),
        (
            "wing",
            wing(),
            1.23,
            vec![0.95, 1.0, 1.01, 1.05],
            Some(1 << 16),
        ),
    ];
    for (name, m, gamma, nus, samples) in cases {
        let settings = HarmonicSettings {
            samples,
            ..HarmonicSettings::default()
        };
        let fr = ForcedResponse::from_normalised(&m, gamma, Formulation::HarmonicBalance).unwrap();
        let mut checked = 0;
        for nu in nus {
            let omega = nu * m.omega_n();
            let set = fr.steady_states(omega).unwrap();
            for root in &set.roots {
                let mut sys = HbSystem::new(&m, gamma, 1, settings).unwrap();
                // start 1e-4 off the exact root
                let mut q = from_first_order(1, (1.0 + 1e-4) * root.amplitude, root.phase + 1e-4);
                let sol = solve_from(&mut sys, omega, &mut q).unwrap();
                let a = harmonic_amplitude(&sol.coefficients, 1);
                let ph = harmonic_phase(&sol.coefficients, 1);
                let rel = (a - root.amplitude).abs() / root.amplitude;
                assert!(rel < 1e-12, "{name} nu={nu}: amplitude rel error {rel:e}");
                assert!(
                    (ph - root.phase).abs() < 1e-12,
                    "{name} nu={nu}: phase {ph} vs {}",
                    root.phase
                );
                assert!(sol.coefficients[0].abs() < 1e-14 * root.amplitude);
                checked += 1;
            }
        }
        assert!(checked >= 4, "{name}");
    }
}

// ------------------------------------------- shooting oracle (time integration)

/// One period of the forced oscillator from `s0` with Dormand–Prince
/// (rtol 1e-12); returns the samples x(t_k), t_k = kT/m, k = 0..=m, and the
/// end state.
fn period(
    model: &NormalisedModel,
    gamma: f64,
    omega: f64,
    s0: State,
    m: usize,
) -> (Vec<f64>, State) {
    let exc = Sine::new(gamma, omega, PI / 2.0).unwrap(); // γ cos Ωt
    let opts = Options {
        method: Method::DormandPrince {
            rtol: 1e-12,
            atol: 1e-15,
        },
        initial: s0,
        decimation: 1,
    };
    let dt = TAU / omega / m as f64;
    let mut xs = Vec::with_capacity(m + 1);
    let mut last = s0;
    simulate_excitation(model, &exc, 0.0, dt, m + 1, &opts, |s| {
        xs.push(s.x);
        last = State { x: s.x, v: s.v };
    })
    .unwrap();
    (xs, last)
}

/// Periodic orbit by shooting (Newton on s(T) − s0 with a central-difference
/// monodromy matrix). Returns the initial state, the monodromy matrix and
/// the harmonics (a_k, b_k) of x from a DFT of one period.
fn shoot(
    model: &NormalisedModel,
    gamma: f64,
    omega: f64,
    mut s0: State,
    m: usize,
) -> (State, [[f64; 2]; 2], Vec<(f64, f64)>) {
    let mut mono = [[0.0; 2]; 2];
    for _ in 0..20 {
        let (_, s1) = period(model, gamma, omega, s0, m);
        let g = [s1.x - s0.x, s1.v - s0.v];
        let hx = 1e-7 * s0.x.abs().max(1e-9);
        let hv = 1e-7 * s0.v.abs().max(1e-9);
        for (j, h) in [(0, hx), (1, hv)] {
            let mut p = s0;
            let mut q = s0;
            if j == 0 {
                p.x += h;
                q.x -= h;
            } else {
                p.v += h;
                q.v -= h;
            }
            let (_, sp) = period(model, gamma, omega, p, m);
            let (_, sq) = period(model, gamma, omega, q, m);
            mono[0][j] = (sp.x - sq.x) / (2.0 * h);
            mono[1][j] = (sp.v - sq.v) / (2.0 * h);
        }
        // Newton: (M − I) d = −g
        let a = [
            [mono[0][0] - 1.0, mono[0][1]],
            [mono[1][0], mono[1][1] - 1.0],
        ];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let dx = (-g[0] * a[1][1] + g[1] * a[0][1]) / det;
        let dv = (-a[0][0] * g[1] + a[1][0] * g[0]) / det;
        s0.x += dx;
        s0.v += dv;
        if dx.abs() < 1e-14 * s0.x.abs().max(1e-12) && dv.abs() < 1e-14 * s0.v.abs().max(1e-12) {
            break;
        }
    }
    let (xs, _) = period(model, gamma, omega, s0, m);
    let harmonics = (0..=7)
        .map(|k| {
            let (mut a, mut b) = (0.0, 0.0);
            for (i, x) in xs[..m].iter().enumerate() {
                let t = TAU * (k * i) as f64 / m as f64;
                a += x * t.cos();
                b += x * t.sin();
            }
            let f = if k == 0 { 1.0 } else { 2.0 } / m as f64;
            (a * f, b * f)
        })
        .collect();
    (s0, mono, harmonics)
}

fn hb_solution(
    m: &NormalisedModel,
    gamma: f64,
    omega: f64,
    h: usize,
    settings: HarmonicSettings,
) -> (HbSystem, Vec<f64>) {
    let mut sys = HbSystem::new(m, gamma, h, settings).unwrap();
    let sol = solve_at(&mut sys, omega, StartRoot::Smallest).unwrap();
    (sys, sol.coefficients)
}

fn compare_with_shooting(
    name: &str,
    m: &NormalisedModel,
    gamma: f64,
    omega: f64,
    h: usize,
    settings: HarmonicSettings,
    samples: usize,
) -> (f64, f64, f64, f64) {
    let (sys, q) = hb_solution(m, gamma, omega, h, settings);
    let s0 = State {
        x: displacement_at(&q, omega, 0.0),
        v: velocity_at(&q, omega, 0.0),
    };
    let (_, _, harm) = shoot(m, gamma, omega, s0, samples);
    let a1_ref = harm[1].0.hypot(harm[1].1);
    let a3_ref = harm[3].0.hypot(harm[3].1);
    let a1 = harmonic_amplitude(&q, 1);
    let a3 = harmonic_amplitude(&q, 3);
    let e1 = (a1 - a1_ref).abs() / a1_ref;
    let e3 = (a3 - a3_ref).abs() / a3_ref;
    // first order error
    let fr = ForcedResponse::from_normalised(m, gamma, Formulation::HarmonicBalance).unwrap();
    let a_fo = fr.steady_states(omega).unwrap().roots[0].amplitude;
    let e_fo = (a_fo - a1_ref).abs() / a1_ref;
    eprintln!(
        "{name}: H={h} N={} a1={a1:.12e} ref={a1_ref:.12e} rel {e1:.2e}; a3/a1={:.3e} a3 rel {e3:.2e}; first-order rel error {e_fo:.2e}",
        sys.samples(),
        a3_ref / a1_ref
    );
    (e1, e3, e_fo, a3_ref / a1_ref)
}

#[test]
fn large_h_matches_periodic_orbit_of_time_integration() {
    let d = duffing_strong();
    // hard Duffing at a third of its linear resonance (superharmonic region)
    let (e1, e3, e_fo, r3) = compare_with_shooting(
        "duffing f_n/3",
        &d,
        40.0,
        d.omega_n() / 3.0,
        25,
        HarmonicSettings::default(),
        1024,
    );
    assert!(e1 < 1e-6 && e3 < 1e-4, "duffing {e1:e} {e3:e}");
    assert!(
        e_fo > 1e-3 && r3 > 1e-2,
        "first order should be visibly wrong here: {e_fo:e} {r3:e}"
    );
    // rho = 0.5 (softly hardening), near resonance
    let m = power(0.5, 1e4);
    let (e1, e3, _, _) = compare_with_shooting(
        "rho=0.5",
        &m,
        1.0,
        1.05 * m.omega_n(),
        25,
        HarmonicSettings::default(),
        1024,
    );
    assert!(e1 < 1e-6 && e3 < 1e-4, "rho=0.5 {e1:e} {e3:e}");
    // rho = 5.5
    let m = power(5.5, 1e14);
    let (e1, e3, _, _) = compare_with_shooting(
        "rho=5.5",
        &m,
        2.0,
        0.9 * m.omega_n(),
        25,
        HarmonicSettings::default(),
        1024,
    );
    assert!(e1 < 1e-6 && e3 < 1e-4, "rho=5.5 {e1:e} {e3:e}");
}

/// Coulomb friction (η = −1, regularised): HB converges only like 1/H for
/// the first harmonic (the truncated velocity misplaces the velocity
/// reversals where the friction force jumps by O(1/H)), so the 1e-6 target
/// is out of reach of any H; what is asserted is the measured order: the
/// error halves when H doubles, toward the periodic orbit of the
/// event-handling integrator, and the third harmonic is within 1e-4.
#[test]
fn coulomb_with_regularisation_converges_to_time_integration() {
    let m = coulomb();
    let settings = HarmonicSettings {
        regularisation: 1e-3,
        aliasing_tol: 1e-9,
        ..HarmonicSettings::default()
    };
    let omega = 0.8 * m.omega_n();
    let mut e = Vec::new();
    for h in [25usize, 50, 100] {
        let (e1, e3, e_fo, _) = compare_with_shooting(
            &format!("coulomb H={h}"),
            &m,
            10.0,
            omega,
            h,
            settings,
            4096,
        );
        assert!(e3 < 1e-4, "H={h}: third harmonic {e3:e}");
        assert!(
            e1 < 0.1 * e_fo,
            "H={h}: {e1:e} not well below first order {e_fo:e}"
        );
        e.push(e1);
    }
    assert!(e[1] < 0.55 * e[0] && e[2] < 0.55 * e[1], "{e:?}");
    assert!(e[2] < 2.5e-4, "{e:?}");
    // regularisation convergence check reported by the library
    let (sys, q) = hb_solution(&m, 10.0, omega, 25, settings);
    let chk = regularisation_check(&sys, omega, &q).unwrap();
    eprintln!(
        "coulomb: regularisation check eps -> eps/4: rel change {:.2e}",
        chk.relative_change
    );
    assert!(chk.relative_change < 1e-5);
}

/// Coulomb friction: the balance converges like 1/n (n = odd harmonics
/// here), so no affordable H reaches 1e-6 (7.4e-4 at H = 25, 1.9e-4 at
/// H = 100, test above); Richardson extrapolation in n from H and 2H
/// (`extrapolation::first_harmonic_extrapolated`) removes the 1/n term and
/// matches the periodic orbit of the time integration to 1e-6.
#[test]
fn coulomb_first_harmonic_extrapolated_in_h_matches_time_integration() {
    use nlsdof::multi_harmonic::extrapolation::first_harmonic_extrapolated;
    let m = coulomb();
    let gamma = 10.0;
    let settings = HarmonicSettings {
        regularisation: 1e-4,
        aliasing_tol: 1e-9,
        ..HarmonicSettings::default()
    };
    let omega = 0.8 * m.omega_n();
    // the periodic orbit by shooting (Dormand–Prince, rtol 1e-12), started
    // from the H = 100 balance
    let (_, q) = hb_solution(&m, gamma, omega, 100, settings);
    let s0 = State {
        x: displacement_at(&q, omega, 0.0),
        v: velocity_at(&q, omega, 0.0),
    };
    let (_, _, harm) = shoot(&m, gamma, omega, s0, 8192);
    let a_ref = harm[1].0.hypot(harm[1].1);
    let rel = |a: f64| (a - a_ref).abs() / a_ref;
    for h in [25usize, 50] {
        let e = first_harmonic_extrapolated(&m, gamma, omega, h, settings, StartRoot::Smallest)
            .unwrap();
        eprintln!(
            "coulomb H = {h} and {}: a1 rel errors {:.2e} and {:.2e}, extrapolated {:.2e} (n = {}, {})",
            2 * h,
            rel(e.coarse.2),
            rel(e.fine.2),
            rel(e.amplitude),
            e.coarse.1,
            e.fine.1
        );
        // half-wave symmetry recognised: n = odd harmonics
        assert_eq!((e.coarse.1, e.fine.1), (h.div_ceil(2), h));
        assert!(rel(e.amplitude) < 1e-6, "H = {h}: {:e}", rel(e.amplitude));
        assert!(rel(e.amplitude) < 1e-2 * rel(e.fine.2));
    }
}

/// `truncation_study` (what `nlsdof hb-error` runs) with Coulomb friction:
/// the rows converge like 1/n, so the study extrapolates consecutive rows
/// in n and measures the errors against the extrapolation. Its peak
/// amplitude (from H = 3 and 5) agrees to 1e-6 with the extrapolation of
/// single-frequency balances with H = 15 and 30 at the same frequency (the
/// peak is flat, so the frequency's own error does not matter), while the
/// plain H = 5 row is further off than the study's tolerance.
#[test]
fn coulomb_truncation_study_extrapolates_in_h() {
    use nlsdof::multi_harmonic::extrapolation::first_harmonic_extrapolated;
    use nlsdof::multi_harmonic::truncation::truncation_study;
    let m = coulomb();
    let gamma = 10.0;
    let settings = settings_for(&m);
    let opts = ContinuationOptions {
        max_dp: 1.0 / 50.0,
        ..ContinuationOptions::default()
    };
    let st = truncation_study(
        &m,
        gamma,
        TAU * 4.9,
        TAU * 5.2,
        &[1, 3, 5, 7],
        1e-6,
        settings,
        &opts,
    )
    .unwrap();
    let x = st.extrapolated.as_ref().expect("Coulomb: extrapolated");
    let (w_peak, a_peak, _) = x.peak.unwrap();
    let fine =
        first_harmonic_extrapolated(&m, gamma, w_peak, 15, settings, StartRoot::Largest).unwrap();
    let rel = |a: f64| (a - fine.amplitude).abs() / fine.amplitude;
    let raw = st.rows[st.reference].peak.unwrap().1;
    eprintln!(
        "coulomb study: converged {} at H = {}; extrapolated peak a1 {a_peak:.9e} at {:.7} Hz, rel {:.2e} to H = 15/30 extrapolated; plain H = {}: {:.2e}",
        st.converged,
        st.rows[st.reference].harmonics,
        w_peak / TAU,
        rel(a_peak),
        st.rows[st.reference].harmonics,
        rel(raw)
    );
    assert!(st.converged);
    assert!(rel(a_peak) < 1e-6, "{:e}", rel(a_peak));
    assert!(rel(raw) > 1e-6 && rel(a_peak) < 0.2 * rel(raw));
    // the change of a Coulomb row is that of the extrapolations
    assert!(st.rows[1].change.is_nan() && st.rows[st.reference].change <= 1e-6);
}

// ------------------------------------------------------------ convergence in H

#[test]
fn convergence_in_harmonics() {
    let d = duffing_strong();
    let gamma = 40.0;
    let omega = d.omega_n() / 3.0;
    let reference = hb_solution(&d, gamma, omega, 31, HarmonicSettings::default()).1;
    let a_ref = harmonic_amplitude(&reference, 1);
    let mut errs = Vec::new();
    for h in [1usize, 3, 5, 7, 9, 11, 13, 15] {
        let (_, q) = hb_solution(&d, gamma, omega, h, HarmonicSettings::default());
        let e = (harmonic_amplitude(&q, 1) - a_ref).abs() / a_ref;
        eprintln!("H = {h:2}: first-harmonic rel error {e:.3e}");
        errs.push(e);
    }
    // geometric (not monotone) convergence: four more harmonics gain at
    // least a factor 100 (until rounding), and H = 15 is at least 1e6
    // times better than H = 1.
    for i in 0..errs.len() - 2 {
        assert!(
            errs[i + 2] < 1e-2 * errs[i] || errs[i + 2] < 1e-12,
            "{errs:?}"
        );
    }
    assert!(errs[errs.len() - 1] < 1e-6 * errs[0], "{errs:?}");
}

// ---------------------------------------------------- Hill vs monodromy matrix

fn eig2(m: [[f64; 2]; 2]) -> [(f64, f64); 2] {
    let tr = m[0][0] + m[1][1];
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let disc = tr * tr / 4.0 - det;
    if disc >= 0.0 {
        let s = disc.sqrt();
        [(tr / 2.0 + s, 0.0), (tr / 2.0 - s, 0.0)]
    } else {
        let s = (-disc).sqrt();
        [(tr / 2.0, s), (tr / 2.0, -s)]
    }
}

#[test]
fn hill_multipliers_match_monodromy() {
    let d = duffing_strong();
    let gamma = 2.0;
    let omega = 2.0 * PI * 12.5; // three coexisting states
    let fr = ForcedResponse::from_normalised(&d, gamma, Formulation::HarmonicBalance).unwrap();
    let roots = fr.steady_states(omega).unwrap().roots;
    assert_eq!(roots.len(), 3);
    let mut cases: Vec<(NormalisedModel, f64, f64, Vec<f64>)> = Vec::new();
    for r in &roots {
        cases.push((d, gamma, omega, from_first_order(15, r.amplitude, r.phase)));
    }
    // a model with nonlinear damping (velocity-dependent f_v term of Hill)
    let w = wing();
    let fw = ForcedResponse::from_normalised(&w, 1.23, Formulation::HarmonicBalance).unwrap();
    let ow = 1.005 * w.omega_n();
    let rw = fw.steady_states(ow).unwrap().roots[0];
    cases.push((w, 1.23, ow, from_first_order(15, rw.amplitude, rw.phase)));
    let mut unstable_seen = false;
    for (model, g, om, mut q) in cases {
        let mut sys = HbSystem::new(&model, g, 15, HarmonicSettings::default()).unwrap();
        solve_from(&mut sys, om, &mut q).unwrap();
        let fl = hill_floquet_exponents(&mut sys, &q, om).unwrap();
        let s0 = State {
            x: displacement_at(&q, om, 0.0),
            v: velocity_at(&q, om, 0.0),
        };
        let (_, mono, _) = shoot(&model, g, om, s0, 256);
        let mut mu = eig2(mono);
        mu.sort_by(|a, b| {
            b.0.hypot(b.1)
                .total_cmp(&a.0.hypot(a.1))
                .then(b.1.total_cmp(&a.1))
        });
        let mut hill: Vec<(f64, f64)> = fl.multipliers.iter().map(|c| (c.re, c.im)).collect();
        hill.sort_by(|a, b| {
            b.0.hypot(b.1)
                .total_cmp(&a.0.hypot(a.1))
                .then(b.1.total_cmp(&a.1))
        });
        let max_mod = mu[0].0.hypot(mu[0].1);
        for (a, b) in mu.iter().zip(&hill) {
            let err = (a.0 - b.0).hypot(a.1 - b.1);
            eprintln!("Hill multiplier {b:?} vs monodromy {a:?}: |diff| {err:.2e}");
            assert!(err < 1e-6 * max_mod.max(1.0), "{b:?} vs {a:?}");
        }
        let stable_mono = max_mod < 1.0;
        assert_eq!(fl.stable, stable_mono);
        unstable_seen |= !stable_mono;
        // Liouville: λ₁ + λ₂ = −(δ + mean f_v) (real part; mod iΩ)
        let mean_fv = if model.kappa == 0.0 {
            0.0
        } else {
            let n = 4096;
            (0..n)
                .map(|i| {
                    let t = TAU / om * i as f64 / n as f64;
                    let v = velocity_at(&q, om, t);
                    model.kappa * (model.eta + 1.0) * v.abs().powf(model.eta)
                })
                .sum::<f64>()
                / n as f64
        };
        let sum = fl.exponents[0].re + fl.exponents[1].re;
        let want = -(model.delta + mean_fv);
        eprintln!("Liouville: sum Re(lambda) {sum:.12e}, -(delta + mean f_v) {want:.12e}");
        assert!((sum - want).abs() < 1e-8 * want.abs(), "{sum} vs {want}");
    }
    assert!(unstable_seen, "the middle Duffing root must be unstable");
}

// ------------------------------------------------------------- continuation

#[test]
fn continuation_h1_folds_equal_exact_first_order_folds() {
    let d = duffing_strong();
    let gamma = 2.0;
    let (w0, w1) = (2.0 * PI * 8.0, 2.0 * PI * 16.0);
    let br = continue_in_omega(
        &d,
        gamma,
        1,
        w0,
        w1,
        HarmonicSettings::default(),
        &ContinuationOptions {
            stability: true,
            ..ContinuationOptions::default()
        },
    )
    .unwrap();
    assert!(br.warning.is_none(), "{:?}", br.warning);
    assert!(br.points.len() >= 500, "{}", br.points.len());
    let last = br.points.last().unwrap();
    assert!((last.omega - w1).abs() < 1e-9 * w1);
    let fr = ForcedResponse::from_normalised(&d, gamma, Formulation::HarmonicBalance).unwrap();
    let folds = fr.folds(w0, w1).unwrap();
    assert_eq!(folds.len(), 2);
    assert_eq!(br.limit_points.len(), 2);
    // along the branch the folds come in the order upper (pair ends), lower
    let mut hb_folds: Vec<_> = br
        .limit_points
        .iter()
        .map(|l| (l.point.omega, l.point.amplitude(1)))
        .collect();
    hb_folds.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (f, (om, a)) in folds.iter().zip(&hb_folds) {
        eprintln!(
            "fold exact {:.12} rad/s a={:.10e}; continuation {:.12} a={:.10e}",
            f.omega, f.amplitude, om, a
        );
        assert!((f.omega - om).abs() < 1e-9 * f.omega);
        assert!((f.amplitude - a).abs() < 1e-6 * f.amplitude);
    }
    // every point agrees with an exact first-order root at its frequency
    for p in br.points.iter().step_by(7) {
        let roots = fr.steady_states(p.omega).unwrap().roots;
        let a = p.amplitude(1);
        let best = roots
            .iter()
            .map(|r| (r.amplitude - a).abs() / a)
            .fold(f64::INFINITY, f64::min);
        assert!(best < 1e-9, "omega {} a {a} best {best:e}", p.omega);
    }
    // stability: unstable exactly between the folds (middle branch)
    let i0 = br.limit_points[0].index;
    let i1 = br.limit_points[1].index;
    for (i, p) in br.points.iter().enumerate() {
        if i + 1 < i0.min(i1) || i > i0.max(i1) + 1 {
            assert_eq!(p.stable(), Some(true), "point {i} at {}", p.omega);
        } else if i > i0.min(i1) + 1 && i + 1 < i0.max(i1) {
            assert_eq!(p.stable(), Some(false), "point {i} at {}", p.omega);
        }
    }
}

#[test]
fn continuation_many_harmonics_and_in_gamma() {
    let d = duffing_strong();
    let (w0, w1) = (2.0 * PI * 8.0, 2.0 * PI * 16.0);
    let br = continue_in_omega(
        &d,
        2.0,
        9,
        w0,
        w1,
        HarmonicSettings::default(),
        &ContinuationOptions::default(),
    )
    .unwrap();
    assert!(br.warning.is_none());
    assert_eq!(br.limit_points.len(), 2);
    // each fold: the Jacobian dR/dq is singular there (and not at a regular point)
    let sv_ratio = |p: &BranchPoint| {
        let mut sys = HbSystem::new(&d, 2.0, 9, HarmonicSettings::default()).unwrap();
        let n = sys.dim();
        let mut r = vec![0.0; n];
        let mut jac = vec![0.0; n * n];
        let mut dro = vec![0.0; n];
        sys.residual_jacobian(&p.coefficients, p.omega, &mut r, &mut jac, &mut dro);
        let sv = nalgebra::DMatrix::from_row_slice(n, n, &jac).singular_values();
        sv.min() / sv.max()
    };
    for lp in &br.limit_points {
        let ratio = sv_ratio(&lp.point);
        eprintln!(
            "H=9 fold at {:.9} Hz: smallest/largest singular value {ratio:.2e}",
            lp.point.omega / TAU
        );
        assert!(ratio < 1e-8);
    }
    let regular = &br.points[br.limit_points[0].index / 2];
    assert!(sv_ratio(regular) > 1e-4);
    // continuation in gamma at fixed frequency from a small level: passes a fold pair
    let om = 2.0 * PI * 12.0;
    let bg = continue_in_gamma(
        &d,
        om,
        5,
        0.2,
        4.0,
        HarmonicSettings::default(),
        &ContinuationOptions::default(),
    )
    .unwrap();
    assert!(bg.warning.is_none(), "{:?}", bg.warning);
    let last = bg.points.last().unwrap();
    assert!((last.gamma - 4.0).abs() < 1e-9);
    // the end state solves the balance at gamma = 4
    let mut sys = HbSystem::new(&d, 4.0, 5, HarmonicSettings::default()).unwrap();
    let mut r = vec![0.0; sys.dim()];
    sys.residual(&last.coefficients, om, &mut r);
    assert!(r
        .iter()
        .all(|v| v.abs() < 1e-9 * sys.residual_scale(&last.coefficients, om)));
}

// -------------------------------------------------------------- backbone

fn exact_period(m: &NormalisedModel, x: f64) -> f64 {
    // T = 4 ∫_0^{π/2} X cos θ / sqrt(α X² cos²θ + 2β/(ρ+2) X^{ρ+2}(1 − sin^{ρ+2}θ)) dθ, composite Simpson
    let n = 20000;
    let hstep = PI / 2.0 / n as f64;
    let f = |th: f64| {
        let u = PI / 2.0 - th;
        if u <= 0.0 {
            // θ = π/2 limit: X cos θ / sqrt(den) → 1/sqrt(α + β X^ρ)
            return 1.0 / (m.alpha + m.beta * x.powf(m.rho)).sqrt();
        }
        let c = u.sin();
        // 1 − sin^{ρ+2}θ without cancellation: sin θ = 1 − 2 sin²(u/2)
        let one_minus_s = 2.0 * (0.5 * u).sin().powi(2);
        let one_minus_sp = -((m.rho + 2.0) * (-one_minus_s).ln_1p()).exp_m1();
        let den = m.alpha * x * x * c * c
            + 2.0 * m.beta / (m.rho + 2.0) * x.powf(m.rho + 2.0) * one_minus_sp;
        x * c / den.sqrt()
    };
    let mut s = f(0.0) + f(PI / 2.0);
    for i in 1..n {
        s += f(i as f64 * hstep) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    4.0 * s * hstep / 3.0
}

#[test]
fn backbone_matches_exact_period() {
    // polynomial (Duffing): exact to rounding at H = 21; ρ = 5.5: the
    // truncation error of H = 21 (Fourier coefficients of x|x|^5.5 decay
    // algebraically) is measured at 1e-11 at the largest amplitude.
    for (m, amps, tol) in [
        (duffing_strong(), vec![1e-3, 5e-3, 1e-2, 2e-2], 1e-12),
        (power(5.5, 1e14), vec![1e-3, 5e-3, 1e-2], 1e-10),
    ] {
        let bb = multi_harmonic_backbone(&m, 21, &amps, HarmonicSettings::default()).unwrap();
        for p in &bb {
            let om = TAU / exact_period(&m, p.max_x);
            let rel = (p.omega - om).abs() / om;
            eprintln!(
                "rho={} A={:.1e}: HB {:.12} exact {:.12} rel {rel:.1e}",
                m.rho, p.amplitude, p.omega, om
            );
            assert!(rel < tol, "rho={} A={} rel {rel:e}", m.rho, p.amplitude);
        }
    }
    // ρ = 0.5: x|x|^0.5 is singular at x = 0, algebraic convergence in H
    // (measured ≈ H^-3.5): H = 81 is > 50 times better than H = 21 and < 1e-9.
    let m = power(0.5, 1e4);
    let amps = [1e-3, 1e-2, 5e-2];
    let errs = |h| -> Vec<f64> {
        multi_harmonic_backbone(&m, h, &amps, HarmonicSettings::default())
            .unwrap()
            .iter()
            .map(|p| {
                let om = TAU / exact_period(&m, p.max_x);
                (p.omega - om).abs() / om
            })
            .collect()
    };
    let (e21, e81) = (errs(21), errs(81));
    eprintln!("rho=0.5 backbone rel errors H=21 {e21:?}, H=81 {e81:?}");
    for (a, b) in e21.iter().zip(&e81) {
        assert!(*b < a / 50.0 && *b < 1e-9, "{a:e} {b:e}");
    }
}

// -------------------------------------------------------------- bad input

#[test]
fn bad_input_is_a_typed_error() {
    let d = duffing_strong();
    assert!(matches!(
        HbSystem::new(&d, 1.0, 0, HarmonicSettings::default()),
        Err(MhbError::Harmonics { value: 0, .. })
    ));
    assert!(matches!(
        HbSystem::new(&d, 1.0, MAX_HARMONICS + 1, HarmonicSettings::default()),
        Err(MhbError::Harmonics { .. })
    ));
    assert!(matches!(
        HbSystem::new(&d, -1.0, 3, HarmonicSettings::default()),
        Err(MhbError::InvalidValue { name: "gamma", .. })
    ));
    assert!(matches!(
        HbSystem::new(&d, f64::NAN, 3, HarmonicSettings::default()),
        Err(MhbError::InvalidValue { .. })
    ));
    assert!(HbSystem::new(
        &d,
        1.0,
        3,
        HarmonicSettings {
            samples: Some(8),
            ..HarmonicSettings::default()
        }
    )
    .is_err());
    assert!(continue_in_omega(
        &d,
        1.0,
        3,
        10.0,
        10.0,
        HarmonicSettings::default(),
        &ContinuationOptions::default()
    )
    .is_err());
    assert!(continue_in_omega(
        &d,
        1.0,
        3,
        f64::NAN,
        10.0,
        HarmonicSettings::default(),
        &ContinuationOptions::default()
    )
    .is_err());
    // Coulomb sticking: no first-order state to start from
    let c = coulomb();
    let mut sys = HbSystem::new(&c, 2.0, 3, HarmonicSettings::default()).unwrap();
    assert!(matches!(
        solve_at(&mut sys, 30.0, StartRoot::Smallest),
        Err(MhbError::NoStart { .. })
    ));
    // an impossible tolerance: a stated partial branch or an error, never a hang
    let br = continue_in_omega(
        &d,
        2.0,
        3,
        2.0 * PI * 8.0,
        2.0 * PI * 16.0,
        HarmonicSettings {
            tol: 1e-300,
            max_iterations: 5,
            ..HarmonicSettings::default()
        },
        &ContinuationOptions::default(),
    );
    match br {
        Ok(b) => assert!(b.warning.is_some()),
        Err(e) => assert!(matches!(e, MhbError::NoConvergence { .. })),
    }
    // undamped oscillator at resonance: singular, typed error
    let und = NormalisedModel {
        alpha: 100.0,
        delta: 0.0,
        beta: 0.0,
        rho: 0.0,
        kappa: 0.0,
        eta: 0.0,
    };
    let mut sys = HbSystem::new(&und, 1.0, 3, HarmonicSettings::default()).unwrap();
    let mut q = from_first_order(3, 1.0, 0.0);
    assert!(sys.solve(&mut q, 10.0).is_err());
}

#[test]
#[ignore]
fn coulomb_convergence_experiment() {
    let m = coulomb();
    let omega = 0.8 * m.omega_n();
    for reg in [1e-3, 1e-4] {
        for h in [25usize, 50, 100] {
            let settings = HarmonicSettings {
                regularisation: reg,
                aliasing_tol: 1e-9,
                ..HarmonicSettings::default()
            };
            let t = std::time::Instant::now();
            compare_with_shooting(
                &format!("coulomb reg {reg:e}"),
                &m,
                10.0,
                omega,
                h,
                settings,
                4096,
            );
            eprintln!("  {:?}", t.elapsed());
        }
    }
}

#[test]
#[ignore]
fn backbone_experiment() {
    let m = power(0.5, 1e4);
    for h in [11usize, 21, 41, 81] {
        let t = std::time::Instant::now();
        let bb = multi_harmonic_backbone(&m, h, &[1e-3, 1e-2, 5e-2], HarmonicSettings::default())
            .unwrap();
        for p in &bb {
            let om = TAU / exact_period(&m, p.max_x);
            eprintln!(
                "H={h} A={:.0e}: rel {:.2e}",
                p.amplitude,
                (p.omega - om).abs() / om
            );
        }
        eprintln!("  {:?}", t.elapsed());
    }
}

// ------------------------------------------------------------ sweep

/// With H = 1 the sweep read off the continued branch equals today's exact
/// first-order stepped-sine sweep: same amplitudes, same jumps.
#[test]
fn sweep_h1_equals_first_order_sweep() {
    use nlsdof::multi_harmonic::sweep::sweep;
    let d = duffing_strong();
    let omegas: Vec<f64> = (0..200)
        .map(|i| TAU * (8.0 + 8.0 * i as f64 / 199.0))
        .collect();
    let fr = ForcedResponse::from_normalised(&d, 2.0, Formulation::HarmonicBalance).unwrap();
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let exact = fr.sweep(&omegas, dir).unwrap();
        let mhb = sweep(
            &d,
            2.0,
            1,
            &omegas,
            dir,
            HarmonicSettings::default(),
            &ContinuationOptions::default(),
        )
        .unwrap();
        assert_eq!(exact.points.len(), mhb.points.len());
        for (e, m) in exact.points.iter().zip(&mhb.points) {
            assert!((e.omega - m.omega).abs() < 1e-12 * e.omega);
            let a = harmonic_amplitude(&m.coefficients, 1);
            assert!(
                (e.amplitude - a).abs() < 1e-9 * e.amplitude,
                "{dir:?} {} {} {a}",
                e.omega,
                e.amplitude
            );
            assert_eq!(e.stable, m.stable);
        }
        assert_eq!(exact.jumps.len(), 1);
        assert_eq!(mhb.jumps.len(), 1);
        let (je, jm) = (exact.jumps[0], mhb.jumps[0]);
        assert!(
            (je.omega - jm.omega).abs() < 1e-9 * je.omega,
            "{je:?} {jm:?}"
        );
        assert!((je.amplitude_before - jm.amplitude_before).abs() < 1e-6 * je.amplitude_before);
        assert!(
            (je.amplitude_after - jm.amplitude_after).abs() < 1e-6 * je.amplitude_after,
            "{je:?} {jm:?}"
        );
    }
}

// ------------------------------------------------------ peak and truncation study

/// The located first-order peak satisfies the analytic peak condition of the
/// first-order balance: ∂P/∂Ω = 0 with P = a²[(α + g(2)βa² − Ω²)² + (δΩ)²]
/// ⇒ α + ¾βa² − Ω² = δ²/2 (no nonlinear damping).
#[test]
fn located_peak_satisfies_first_order_peak_condition_and_study_converges() {
    use nlsdof::multi_harmonic::truncation::truncation_study;
    let d = duffing_strong();
    let (w0, w1) = (TAU * 8.0, TAU * 16.0);
    let br = continue_in_omega(
        &d,
        2.0,
        1,
        w0,
        w1,
        HarmonicSettings::default(),
        &ContinuationOptions::default(),
    )
    .unwrap();
    assert_eq!(br.peaks.len(), 1);
    let p = &br.peaks[0];
    let a = p.amplitude(1);
    let lhs = d.alpha + 0.75 * d.beta * a * a - p.omega * p.omega;
    let rhs = d.delta * d.delta / 2.0;
    eprintln!("peak condition: {lhs:e} vs {rhs:e} (alpha = {})", d.alpha);
    assert!((lhs - rhs).abs() < 1e-9 * d.alpha, "{lhs} {rhs}");
    // truncation study: converges, and first order is off by more than 1e-3
    let st = truncation_study(
        &d,
        2.0,
        w0,
        w1,
        &[1, 3, 5, 7, 9, 11, 15, 21],
        1e-6,
        HarmonicSettings::default(),
        &ContinuationOptions::default(),
    )
    .unwrap();
    assert!(
        st.converged,
        "{:?}",
        st.rows.iter().map(|r| r.change).collect::<Vec<_>>()
    );
    let r = &st.rows[st.reference];
    let fo = &st.rows[0];
    let e_peak = (fo.peak.unwrap().1 - r.peak.unwrap().1).abs() / r.peak.unwrap().1;
    let e_fold = (fo.folds[1].0 - r.folds[1].0).abs() / r.folds[1].0;
    eprintln!("strong Duffing gamma=2: converged at H={}, first-order peak error {e_peak:.2e}, upper fold {e_fold:.2e}", r.harmonics);
    assert!(e_peak > 1e-3 && e_fold > 1e-3);
}

// ------------------------------------------------ folds vs the stepped-sine rig

/// The upper (jump-down) fold of a strong Duffing oscillator against the
/// virtual stepped-sine rig (RK4 time integration, settling rule): with
/// steps finer than the first-order truncation error of the fold, the
/// rig's jump brackets the H = 9 fold within one step and excludes the
/// first-order (H = 1) fold.
#[test]
fn upper_fold_matches_stepped_sine_rig_and_first_order_does_not() {
    use nlsdof::stepped_sine::{run, RigOptions};
    let model = Model::linear(1.0, 1.0, 0.02)
        .unwrap()
        .with_stiffness(0.5, 2.0)
        .unwrap();
    let m = model.normalised().unwrap();
    let gamma = 0.02;
    let fold_of = |h: usize| {
        let br = continue_in_omega(
            &m,
            gamma,
            h,
            0.9,
            1.3,
            HarmonicSettings::default(),
            &ContinuationOptions::default(),
        )
        .unwrap();
        assert_eq!(br.limit_points.len(), 2);
        br.limit_points
            .iter()
            .map(|l| l.point.omega)
            .fold(0.0f64, f64::max)
    };
    let (f1, f9) = (fold_of(1), fold_of(9));
    let gap = f9 - f1;
    assert!(gap > 0.0);
    // window: start 4 gaps below the H = 9 fold on the resonant branch
    let step = gap / 6.0;
    let omegas: Vec<f64> = (0..40).map(|i| f9 - 4.0 * gap + i as f64 * step).collect();
    let w0 = omegas[0];
    let mut sys = HbSystem::new(&m, gamma, 9, HarmonicSettings::default()).unwrap();
    let sol = solve_at(&mut sys, w0, StartRoot::Largest).unwrap();
    let q = sol.coefficients;
    let start = State {
        x: displacement_at(&q, w0, 0.0),
        v: velocity_at(&q, w0, 0.0),
    };
    let sw = run(
        &m,
        gamma,
        &omegas,
        SweepDirection::Up,
        &RigOptions::default(),
        start,
    )
    .unwrap();
    let pts = &sw.points;
    let (k, ratio) = (0..pts.len() - 1)
        .map(|k| (k, (pts[k].amplitude / pts[k + 1].amplitude).ln()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    let (lo, hi) = (pts[k].omega, pts[k + 1].omega);
    eprintln!(
        "rig jump between {lo:.6} and {hi:.6} rad/s (x{:.2}), fold H=9 {f9:.6}, H=1 {f1:.6}, step {step:.2e}",
        ratio.exp()
    );
    assert!(ratio > 1.5f64.ln());
    assert!(
        lo - step <= f9 && f9 <= hi + step,
        "H=9 fold {f9} outside [{lo}, {hi}] ± {step}"
    );
    assert!(
        f1 < lo - step,
        "first-order fold {f1} not excluded by the rig jump [{lo}, {hi}]"
    );
}
