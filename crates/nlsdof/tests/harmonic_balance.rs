//! Harmonic-balance steady state against independent oracles:
//! the exact linear FRF, companion-matrix roots of the squared polynomial
//! (integer exponents), the classical Duffing fold conditions, Coulomb
//! sticking, and step-size independence of branch following.

mod support;
use nlsdof::harmonic_balance::modulation_frequencies;
use nlsdof::power_law::g;
use nlsdof::*;
use std::f64::consts::PI;
use support::fixtures::Rng;

fn linear_frf(m: &Model, gamma: f64, w: f64) -> (f64, f64) {
    let re = m.stiffness - m.mass * w * w;
    let im = m.damping * w;
    (m.mass * gamma / re.hypot(im), im.atan2(re))
}

#[test]
fn linear_limit_equals_exact_sdof_frf() {
    let m = Model::linear(0.26699, 306.7878, 0.1164).unwrap();
    let gamma = 0.41;
    let r = ForcedResponse::new(&m, gamma, Formulation::HarmonicBalance).unwrap();
    let omegas: Vec<f64> = (0..400)
        .map(|i| 2.0 * PI * (0.5 + 0.025 * i as f64))
        .collect();
    for &w in &omegas {
        let set = r.steady_states(w).unwrap();
        assert_eq!(set.roots.len(), 1);
        let (a, ph) = linear_frf(&m, gamma, w);
        assert!((set.roots[0].amplitude - a).abs() <= 1e-12 * a, "w={w}");
        assert!((set.roots[0].phase - ph).abs() <= 1e-12, "w={w}");
        assert!(set.roots[0].stable);
    }
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let s = r.sweep(&omegas, dir).unwrap();
        assert!(s.jumps.is_empty() && s.folds.is_empty());
        for p in &s.points {
            let (a, ph) = linear_frf(&m, gamma, p.omega);
            assert!((p.amplitude - a).abs() <= 1e-12 * a);
            assert!((p.phase - ph).abs() <= 1e-12);
        }
    }
    // zero-coefficient nonlinear terms are the linear model too
    let m0 = m
        .with_stiffness(0.0, 2.0)
        .unwrap()
        .with_damping(0.0, 1.0)
        .unwrap();
    let r0 = ForcedResponse::new(&m0, gamma, Formulation::HarmonicBalance).unwrap();
    let w = 2.0 * PI * 5.3;
    let (a, _) = linear_frf(&m, gamma, w);
    assert!((r0.steady_states(w).unwrap().roots[0].amplitude - a).abs() <= 1e-12 * a);
    // phase quadrature of a linear system: Ω = ω_n, a = γ/(δ ω_n)
    let pq = r.phase_quadrature().unwrap().unwrap();
    assert!((pq.omega - m.omega_n()).abs() < 1e-12 * m.omega_n());
    let a_pq = gamma * m.mass / (m.damping * m.omega_n());
    assert!((pq.amplitude - a_pq).abs() < 1e-12 * a_pq);
}

/// Polynomial coefficients (index = power of y, a = a0 y) of
/// a²[(k + g(ρ)k_r a^ρ − mΩ²)² + (Ω(c + g(η)c_e Ω^η a^η))²] − (mγ)²,
/// built directly from the physical parameters.
fn squared_polynomial(m: &Model, gamma: f64, w: f64, a0: f64) -> Vec<f64> {
    let (kr, rho) = m
        .nonlinear_stiffness
        .map(|t| (t.coefficient, t.exponent as usize))
        .unwrap();
    let (ce, eta) = m
        .nonlinear_damping
        .map(|t| (t.coefficient, t.exponent as usize))
        .unwrap();
    let deg = 2 + 2 * rho.max(eta);
    let mut p = vec![0.0; deg + 1];
    // S(y) = s0 + s1 y^rho ; D(y) = d0 + d1 y^eta (in units of force / a)
    let s0 = m.stiffness - m.mass * w * w;
    let s1 = g(rho as f64).unwrap() * kr * a0.powi(rho as i32);
    let d0 = w * m.damping;
    let d1 = w * g(eta as f64).unwrap() * ce * w.powi(eta as i32) * a0.powi(eta as i32);
    let mut add = |pow: usize, c: f64| p[pow] += c;
    // a^2 S^2 = a0^2 y^2 (s0^2 + 2 s0 s1 y^rho + s1^2 y^2rho)
    add(2, a0 * a0 * (s0 * s0 + d0 * d0));
    add(2 + rho, a0 * a0 * 2.0 * s0 * s1);
    add(2 + 2 * rho, a0 * a0 * s1 * s1);
    add(2 + eta, a0 * a0 * 2.0 * d0 * d1);
    add(2 + 2 * eta, a0 * a0 * d1 * d1);
    add(0, -(m.mass * gamma).powi(2));
    p
}

/// Positive real roots via companion-matrix eigenvalues (nalgebra), or
/// `None` when an eigenvalue is too close to the real axis to classify.
fn companion_positive_roots(p: &[f64]) -> Option<Vec<f64>> {
    let big = p.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    let mut p: Vec<f64> = p.iter().map(|c| c / big).collect();
    while p.last() == Some(&0.0) {
        p.pop();
    }
    let n = p.len() - 1;
    let lead = p[n];
    let mut c = nalgebra::DMatrix::<f64>::zeros(n, n);
    for i in 1..n {
        c[(i, i - 1)] = 1.0;
    }
    for i in 0..n {
        c[(i, n - 1)] = -p[i] / lead;
    }
    // bounded iteration: the default unbounded Schur loop can spin forever
    let eig = nalgebra::linalg::Schur::try_new(c, 1e-15, 100_000)?.complex_eigenvalues();
    let mut out = Vec::new();
    for z in eig.iter() {
        let rel = z.im.abs() / z.norm().max(1e-300);
        if rel < 1e-9 {
            if z.re > 0.0 {
                out.push(z.re);
            }
        } else if rel < 1e-3 && z.re > 0.0 {
            return None; // ambiguous: nearly a double root, the oracle cannot tell
        }
    }
    out.sort_by(f64::total_cmp);
    Some(out)
}

#[test]
fn integer_exponents_match_companion_matrix_roots_of_squared_polynomial() {
    let mut rng = Rng(20211);
    let (mut tested, mut multi) = (0, 0);
    for _ in 0..400 {
        let mass = 10f64.powf(rng.range(-2.0, 2.0));
        let wn = 2.0 * PI * 10f64.powf(rng.range(-0.5, 2.0));
        let zeta = 10f64.powf(rng.range(-3.0, -1.0));
        let rho = (rng.uniform() * 5.0) as usize; // 0..4
        let eta = (rng.uniform() * 4.0) as usize; // 0..3
        let gamma = 10f64.powf(rng.range(-1.0, 1.0));
        let a0 = gamma / (wn * wn);
        let a_res = a0 / (2.0 * zeta);
        // nonlinear stiffness giving k_eq/k in (-0.5, 2) at the linear resonance amplitude
        let kr_strength = rng.range(-0.5, 2.0);
        let kr = kr_strength * mass * wn * wn / (g(rho as f64).unwrap() * a_res.powi(rho as i32));
        let ce_strength = rng.range(0.0, 3.0);
        let ce = ce_strength * 2.0 * zeta * mass * wn
            / (g(eta as f64).unwrap() * (wn * a_res).powi(eta as i32));
        let model = Model::linear(mass, mass * wn * wn, 2.0 * zeta * mass * wn)
            .unwrap()
            .with_stiffness(kr, rho as f64)
            .unwrap()
            .with_damping(ce, eta as f64)
            .unwrap();
        let w = wn * rng.range(0.5, 1.6);
        let ours = ForcedResponse::new(&model, gamma, Formulation::HarmonicBalance)
            .unwrap()
            .steady_states(w)
            .unwrap();
        // scale by the linear resonance amplitude so the coefficients are O(1)
        // (the companion-matrix eigenvalues are meaningless otherwise)
        let poly = squared_polynomial(&model, gamma, w, a_res);
        let Some(oracle) = companion_positive_roots(&poly) else {
            continue;
        };
        tested += 1;
        assert_eq!(
            ours.roots.len(),
            oracle.len(),
            "rho={rho} eta={eta} ours={:?} oracle={:?}",
            ours.roots
                .iter()
                .map(|r| r.amplitude / a_res)
                .collect::<Vec<_>>(),
            oracle
        );
        if oracle.len() > 1 {
            multi += 1;
        }
        for (r, y) in ours.roots.iter().zip(&oracle) {
            let a = y * a_res;
            assert!(
                (r.amplitude - a).abs() <= 1e-7 * a,
                "{} vs {} (rho {rho} eta {eta} poly {poly:?})",
                r.amplitude,
                a
            );
        }
    }
    assert!(tested >= 200, "only {tested} unambiguous cases");
    assert!(
        multi >= 10,
        "only {multi} cases with several roots: the test is not probing folds"
    );
}

/// Strong hardening Duffing, exact HB: f_n = 10 Hz, ζ = 0.01.
fn duffing() -> Model {
    let m = 1.0;
    let wn = 2.0 * PI * 10.0;
    Model::linear(m, wn * wn, 2.0 * 0.01 * wn)
        .unwrap()
        .with_stiffness(4.0e7, 2.0)
        .unwrap()
}

/// Classical fold condition of the exact first-order HB Duffing equation,
/// derived by eliminating Ω from P = 1, ∂P/∂a = 0 (Y = x², b = ¾β a0²/α):
/// 16ζ²b³Y⁵ + 16ζ²b²Y⁴ − 4b²Y³ + 8ζ²bY² + 1 = 0,  ν² = 1 + bY + 1/(2bY²).
fn duffing_exact_folds(m: &Model, gamma: f64) -> Vec<f64> {
    let wn = m.omega_n();
    let zeta = m.zeta();
    let a0 = gamma / (wn * wn);
    let b = 0.75 * m.nonlinear_stiffness.unwrap().coefficient / m.mass * a0 * a0 / (wn * wn);
    let z2 = zeta * zeta;
    let q = |y: f64| {
        16.0 * z2 * b.powi(3) * y.powi(5) + 16.0 * z2 * b * b * y.powi(4) - 4.0 * b * b * y.powi(3)
            + 8.0 * z2 * b * y * y
            + 1.0
    };
    bisect_all(&q, 1e-3, 1e9)
        .into_iter()
        .map(|y| wn * (1.0 + b * y + 1.0 / (2.0 * b * y * y)).sqrt())
        .collect()
}

/// Nayfeh–Mook fold condition of the modulation equations (Eq 30 form):
/// u = 2(ν−1) = 2bY ± √(b²Y² − 4ζ²) and (bY − u)² + 4ζ² = 1/Y.
fn duffing_modulation_folds(m: &Model, gamma: f64) -> Vec<f64> {
    let wn = m.omega_n();
    let zeta = m.zeta();
    let a0 = gamma / (wn * wn);
    let b = 0.75 * m.nonlinear_stiffness.unwrap().coefficient / m.mass * a0 * a0 / (wn * wn);
    let mut out = Vec::new();
    for sgn in [1.0, -1.0] {
        let h = |y: f64| {
            let disc = b * b * y * y - 4.0 * zeta * zeta;
            if disc < 0.0 {
                return f64::NAN;
            }
            let u = 2.0 * b * y + sgn * disc.sqrt();
            (b * y - u).powi(2) + 4.0 * zeta * zeta - 1.0 / y
        };
        for y in bisect_all(&h, 2.0 * zeta / b * (1.0 + 1e-12), 1e9) {
            let disc = (b * b * y * y - 4.0 * zeta * zeta).sqrt();
            out.push(wn * (1.0 + 0.5 * (2.0 * b * y + sgn * disc)));
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

fn bisect_all(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64) -> Vec<f64> {
    let n = 200_000;
    let mut out = Vec::new();
    let (l0, l1) = (lo.ln(), hi.ln());
    let mut prev = (lo, f(lo));
    for i in 1..=n {
        let y = (l0 + (l1 - l0) * i as f64 / n as f64).exp();
        let fy = f(y);
        if fy.is_finite() && prev.1.is_finite() && (fy > 0.0) != (prev.1 > 0.0) {
            let (mut a, mut b, fa) = (prev.0, y, prev.1);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if (f(m) > 0.0) == (fa > 0.0) {
                    a = m
                } else {
                    b = m
                }
            }
            out.push(0.5 * (a + b));
        }
        prev = (y, fy);
    }
    out
}

#[test]
fn duffing_folds_match_closed_forms_and_sweeps_show_hysteresis() {
    let m = duffing();
    for &gamma in &[0.5, 1.0, 2.0] {
        let (lo, hi) = (2.0 * PI * 8.0, 2.0 * PI * 22.0);
        let exact = duffing_exact_folds(&m, gamma);
        let r = ForcedResponse::new(&m, gamma, Formulation::HarmonicBalance).unwrap();
        let folds = r.folds(lo, hi).unwrap();
        let inside: Vec<f64> = exact
            .iter()
            .copied()
            .filter(|w| *w > lo && *w < hi)
            .collect();
        assert_eq!(
            folds.len(),
            inside.len(),
            "gamma={gamma}: {folds:?} vs {exact:?}"
        );
        assert_eq!(
            inside.len(),
            2,
            "gamma={gamma}: test case must have hysteresis in band"
        );
        for (f, w) in folds.iter().zip(&inside) {
            assert!(
                (f.omega - w).abs() <= 1e-10 * w,
                "gamma={gamma}: fold {} vs closed form {}",
                f.omega,
                w
            );
        }
        // lower fold: pair born above it; upper fold: pair dies above it
        assert!(folds[0].pair_above && !folds[1].pair_above);

        let modf = ForcedResponse::new(&m, gamma, Formulation::Modulation)
            .unwrap()
            .folds(lo, hi)
            .unwrap();
        let nm: Vec<f64> = duffing_modulation_folds(&m, gamma)
            .into_iter()
            .filter(|w| *w > lo && *w < hi)
            .collect();
        assert_eq!(modf.len(), nm.len(), "{modf:?} vs {nm:?}");
        for (f, w) in modf.iter().zip(&nm) {
            assert!(
                (f.omega - w).abs() <= 1e-10 * w,
                "modulation fold {} vs Nayfeh–Mook {}",
                f.omega,
                w
            );
        }

        let omegas: Vec<f64> = (0..200)
            .map(|i| lo + (hi - lo) * i as f64 / 199.0)
            .collect();
        let up = r.sweep(&omegas, SweepDirection::Up).unwrap();
        let down = r.sweep(&omegas, SweepDirection::Down).unwrap();
        assert_eq!(up.jumps.len(), 1, "sweep up: {:?}", up.jumps);
        assert_eq!(down.jumps.len(), 1, "sweep down: {:?}", down.jumps);
        assert!(
            up.jumps[0].amplitude_after < up.jumps[0].amplitude_before,
            "sweep up jumps down"
        );
        assert!(
            down.jumps[0].amplitude_after > down.jumps[0].amplitude_before,
            "sweep down jumps up"
        );
        assert!((up.jumps[0].omega - inside[1]).abs() <= 1e-10 * inside[1]);
        assert!((down.jumps[0].omega - inside[0]).abs() <= 1e-10 * inside[0]);
        assert!(up.points.iter().all(|p| p.stable) && down.points.iter().all(|p| p.stable));
        // hysteresis: inside the fold band the two sweeps sit on different branches
        let differ = up
            .points
            .iter()
            .zip(down.points.iter().rev())
            .filter(|(a, b)| (a.amplitude - b.amplitude).abs() > 0.1 * a.amplitude)
            .count();
        assert!(differ > 0);
    }
}

#[test]
fn branch_following_does_not_depend_on_step_size() {
    let m = duffing();
    let r = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance).unwrap();
    let (lo, hi) = (2.0 * PI * 8.0, 2.0 * PI * 16.0);
    let grid = |n: usize| -> Vec<f64> {
        (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
            .collect()
    };
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let coarse = r.sweep(&grid(11), dir).unwrap();
        let fine = r.sweep(&grid(1001), dir).unwrap();
        // the same jumps; a sweep searches its folds on its own steps, so
        // they are located from different brackets: equal to the fold
        // location's precision (~1e-14), not bit for bit
        assert_eq!(coarse.jumps.len(), fine.jumps.len());
        for (c, f) in coarse.jumps.iter().zip(&fine.jumps) {
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * a.abs();
            assert!(
                close(c.omega, f.omega)
                    && close(c.amplitude_before, f.amplitude_before)
                    && close(c.amplitude_after, f.amplitude_after),
                "{c:?} vs {f:?}"
            );
        }
        for p in &coarse.points {
            let q = fine
                .points
                .iter()
                .find(|q| (q.omega - p.omega).abs() < 1e-9 * p.omega)
                .unwrap();
            assert!(
                (p.amplitude - q.amplitude).abs() <= 1e-12 * p.amplitude,
                "{p:?} vs {q:?}"
            );
        }
    }
}

#[test]
fn sweep_starting_inside_hysteresis_settles_from_rest() {
    let m = duffing();
    let r = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance).unwrap();
    let folds = r.folds(2.0 * PI * 8.0, 2.0 * PI * 16.0).unwrap();
    let mid = 0.5 * (folds[0].omega + folds[1].omega);
    let set = r.steady_states(mid).unwrap();
    assert_eq!(set.roots.len(), 3);
    // starting from rest inside the window (beyond the linear resonance) the
    // slow flow goes to the small-amplitude branch
    let s = r.sweep(&[mid, mid * 1.0001], SweepDirection::Up).unwrap();
    assert!(
        (s.points[0].amplitude - set.roots[0].amplitude).abs() < 1e-12 * set.roots[0].amplitude
    );
}

#[test]
fn coulomb_friction_sticks_exactly_when_theory_says() {
    // friction force c_f; sticking iff 4 c_f / π >= m γ
    let (mass, cf) = (2.0, 3.0);
    let m = Model::linear(mass, 5000.0, 0.8)
        .unwrap()
        .with_damping(cf, -1.0)
        .unwrap();
    let gamma_crit = 4.0 * cf / (PI * mass);
    let w = 0.9 * m.omega_n();
    let stuck = ForcedResponse::new(&m, gamma_crit * (1.0 - 1e-9), Formulation::HarmonicBalance)
        .unwrap()
        .steady_states(w)
        .unwrap();
    assert!(stuck.roots.is_empty());
    match stuck.no_motion {
        Some(NoMotion::Sticking {
            friction_accel,
            input_accel,
        }) => {
            assert!((friction_accel - gamma_crit).abs() < 1e-12 * gamma_crit);
            assert!(input_accel < friction_accel);
        }
        other => panic!("expected sticking, got {other:?}"),
    }
    let gamma = 3.0 * gamma_crit;
    let moving = ForcedResponse::new(&m, gamma, Formulation::HarmonicBalance)
        .unwrap()
        .steady_states(w)
        .unwrap();
    assert_eq!(moving.roots.len(), 1);
    // check against the closed form with c_eq = 4 c_f / (π Ω a):
    // a²(k − mΩ²)² + (cΩa + 4c_f/π)² = (mγ)²
    let a = moving.roots[0].amplitude;
    let lhs =
        (a * (m.stiffness - mass * w * w)).powi(2) + (m.damping * w * a + 4.0 * cf / PI).powi(2);
    assert!((lhs - (mass * gamma).powi(2)).abs() < 1e-12 * (mass * gamma).powi(2));
    // In first-order HB the sticking condition does not depend on Ω
    // (c_eq Ω a = 4c_f/π): a sweep either sticks everywhere or nowhere.
    let omegas: Vec<f64> = (1..300).map(|i| m.omega_n() * (0.01 * i as f64)).collect();
    let below = ForcedResponse::new(&m, 0.95 * gamma_crit, Formulation::HarmonicBalance).unwrap();
    let s = below.sweep(&omegas, SweepDirection::Up).unwrap();
    assert!(s.points.iter().all(|p| p.sticking && p.amplitude == 0.0));
    let above = ForcedResponse::new(&m, 1.05 * gamma_crit, Formulation::HarmonicBalance).unwrap();
    for dir in [SweepDirection::Up, SweepDirection::Down] {
        let s = above.sweep(&omegas, dir).unwrap();
        assert!(s
            .points
            .iter()
            .all(|p| !p.sticking && p.amplitude > 0.0 && p.phase.is_finite()));
    }
}

#[test]
fn phase_quadrature_is_at_ninety_degrees_on_the_backbone() {
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .with_stiffness(85000.0, 4.00220)
        .unwrap()
        .with_damping(0.01591, 3.03099)
        .unwrap();
    for &gamma in &[0.41, 1.23] {
        for form in [Formulation::HarmonicBalance, Formulation::Modulation] {
            let r = ForcedResponse::new(&m, gamma, form).unwrap();
            let pq = r.phase_quadrature().unwrap().unwrap();
            let set = r.steady_states(pq.omega).unwrap();
            let root = set
                .roots
                .iter()
                .find(|s| (s.amplitude - pq.amplitude).abs() < 1e-9 * pq.amplitude);
            let root = root.expect("PQ amplitude is a steady state at the PQ frequency");
            assert!(
                (root.phase - PI / 2.0).abs() < 1e-9,
                "{form:?}: phase {}",
                root.phase
            );
            let bb = backbone(&m.normalised().unwrap(), pq.amplitude, form).unwrap();
            assert!((bb - pq.omega).abs() < 1e-12 * bb);
        }
    }
}

#[test]
fn backbone_closed_forms() {
    let m = duffing();
    let n = m.normalised().unwrap();
    let a = 2e-3;
    let exact = (n.alpha + 0.75 * n.beta * a * a).sqrt();
    assert!((backbone(&n, a, Formulation::HarmonicBalance).unwrap() - exact).abs() < 1e-12 * exact);
    let approx = n.omega_n() * (1.0 + 0.75 * n.beta * a * a / (2.0 * n.alpha));
    assert!((backbone(&n, a, Formulation::Modulation).unwrap() - approx).abs() < 1e-12 * approx);
    let soft = Model::linear(1.0, 100.0, 0.1)
        .unwrap()
        .with_stiffness(-100.0, 2.0)
        .unwrap()
        .normalised()
        .unwrap();
    assert!(backbone(&soft, 2.0, Formulation::HarmonicBalance).is_none());
}

#[test]
fn modulation_form_is_eq30_explicitly() {
    // Ω±(a) from Eq 30 must be steady states of the Modulation formulation at a.
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .with_stiffness(85000.0, 4.0)
        .unwrap()
        .with_damping(0.01591, 3.0)
        .unwrap();
    let gamma = 0.81;
    let r = ForcedResponse::new(&m, gamma, Formulation::Modulation).unwrap();
    let pq = r.phase_quadrature().unwrap().unwrap();
    for frac in [0.2, 0.5, 0.9, 0.999] {
        let a = frac * pq.amplitude;
        let (lo, hi) = modulation_frequencies(&m, gamma, a).unwrap().unwrap();
        assert!(lo < pq.omega && hi > pq.omega);
        for w in [lo, hi] {
            let set = r.steady_states(w).unwrap();
            assert!(
                set.roots.iter().any(|s| (s.amplitude - a).abs() < 1e-9 * a),
                "a={a} w={w} {set:?}"
            );
        }
    }
    assert!(modulation_frequencies(&m, gamma, 1.01 * pq.amplitude)
        .unwrap()
        .is_none());
    // near resonance and weak damping the approximation is close to the exact form
    let exact = ForcedResponse::new(&m, gamma, Formulation::HarmonicBalance)
        .unwrap()
        .phase_quadrature()
        .unwrap()
        .unwrap();
    assert!((exact.amplitude - pq.amplitude).abs() < 0.02 * exact.amplitude);
    assert!((exact.omega - pq.omega).abs() < 1e-3 * exact.omega);
}

#[test]
fn sweep_leaves_a_state_that_loses_stability_without_a_fold() {
    // η = −2.5 < −2: the Hopf (trace) criterion can fail with no fold.
    let m = Model::linear(1.0, 1000.0, 0.5)
        .unwrap()
        .with_damping(0.05, -2.5)
        .unwrap();
    let r = ForcedResponse::new(&m, 5.0, Formulation::HarmonicBalance).unwrap();
    let omegas: Vec<f64> = (0..50)
        .map(|i| 2.0 * PI * (3.0 + 4.0 * i as f64 / 49.0))
        .collect();
    let s = r.sweep(&omegas, SweepDirection::Up).unwrap();
    for p in &s.points {
        let set = r.steady_states(p.omega).unwrap();
        if set.roots.iter().any(|q| q.stable) && !p.sticking {
            assert!(
                p.stable,
                "at {} rad/s a stable state exists but the sweep reports {p:?}",
                p.omega
            );
        }
    }
}

#[test]
fn softening_phase_quadrature_is_the_resonance_peak() {
    let wn = 2.0 * PI * 10.0;
    let m = Model::linear(1.0, wn * wn, 2.0 * 0.01 * wn)
        .unwrap()
        .with_stiffness(-1.2e7, 2.0)
        .unwrap();
    let r = ForcedResponse::new(&m, 0.5, Formulation::HarmonicBalance).unwrap();
    let pq = r.phase_quadrature().unwrap().unwrap();
    // softening: the peak leans below f_n, but stays near it at this level
    let f = pq.omega / (2.0 * PI);
    assert!(f > 9.0 && f < 10.0, "PQ at {f} Hz");
    // it is the largest amplitude of the swept curve (the resonance peak)
    let omegas: Vec<f64> = (0..2001)
        .map(|i| 2.0 * PI * (8.0 + 4.0 * i as f64 / 2000.0))
        .collect();
    let peak = omegas
        .iter()
        .flat_map(|&w| r.steady_states(w).unwrap().roots)
        .map(|s| s.amplitude)
        .fold(0.0, f64::max);
    assert!(
        (pq.amplitude - peak).abs() < 1e-3 * peak,
        "{} vs peak {}",
        pq.amplitude,
        peak
    );
}

/// Documents (does not hide) the paper's internal inconsistency: Table 7's
/// unloaded, pre-estimated, non-integer model at the Table 2 levels
/// converted to zero-to-peak (γ = γ_pp/2). Table 8 lists the model's a_PQ as
/// 0.02630, 0.03620, 0.04341, 0.04845, 0.05363 m "peak-to-peak".
/// Standard conventions give a zero-to-peak a_PQ within 2 % *below those
/// numbers*, i.e. about twice the stated peak-to-peak amplitude /2: the
/// paper's amplitudes and input levels cannot both be peak-to-peak.
#[test]
fn table8_discrepancy_is_what_we_document() {
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .with_stiffness(85000.0, 4.00220)
        .unwrap()
        .with_damping(0.01591, 3.03099)
        .unwrap();
    let gamma_pp = [0.82, 1.24, 1.62, 2.00, 2.46];
    let table8_model_a = [0.02630, 0.03620, 0.04341, 0.04845, 0.05363];
    let table8_model_f = [5.3955, 5.3985, 5.4005, 5.4035, 5.4075];
    for i in 0..5 {
        let pq = ForcedResponse::new(&m, gamma_pp[i] / 2.0, Formulation::HarmonicBalance)
            .unwrap()
            .phase_quadrature()
            .unwrap()
            .unwrap();
        let ratio = pq.amplitude / table8_model_a[i];
        assert!(
            ratio > 0.98 && ratio < 1.0,
            "level {i}: a_PQ {} m, ratio to Table 8 {ratio}",
            pq.amplitude
        );
        let df = pq.omega / (2.0 * PI) / table8_model_f[i] - 1.0;
        assert!(
            df < 0.0 && df > -0.002,
            "level {i}: f_PQ {} Hz ({df:+e})",
            pq.omega / (2.0 * PI)
        );
    }
}

#[test]
fn parallel_levels_equal_sequential() {
    let m = duffing();
    let gammas = [0.25, 0.5, 1.0, 2.0];
    let omegas: Vec<f64> = (0..300)
        .map(|i| 2.0 * PI * (8.0 + 12.0 * i as f64 / 299.0))
        .collect();
    let par = sweep_levels(
        &m,
        &gammas,
        &omegas,
        SweepDirection::Down,
        Formulation::HarmonicBalance,
    )
    .unwrap();
    for (g, p) in gammas.iter().zip(&par) {
        let seq = ForcedResponse::new(&m, *g, Formulation::HarmonicBalance)
            .unwrap()
            .sweep(&omegas, SweepDirection::Down)
            .unwrap();
        assert_eq!(&seq, p);
    }
}

#[test]
fn narrow_hysteresis_window_near_the_cusp_is_found() {
    // Increase γ until the closed-form fold pair appears, then take a level
    // whose window is far narrower than one cell of the fold-search grid
    // (0.4 % over 8–22 Hz with 256 cells).
    let m = duffing();
    let (mut lo_g, mut hi_g) = (1e-3, 0.5);
    assert!(duffing_exact_folds(&m, lo_g).is_empty() && duffing_exact_folds(&m, hi_g).len() == 2);
    for _ in 0..200 {
        let mid = 0.5 * (lo_g + hi_g);
        let f = duffing_exact_folds(&m, mid);
        if f.len() == 2 && (f[1] - f[0]) / f[0] < 3e-5 {
            hi_g = mid;
            break;
        }
        if f.len() == 2 {
            hi_g = mid
        } else {
            lo_g = mid
        }
    }
    let gamma = hi_g;
    let exact = duffing_exact_folds(&m, gamma);
    assert_eq!(exact.len(), 2);
    let width = (exact[1] - exact[0]) / exact[0];
    assert!(width < 3e-5 && width > 0.0, "window {width}");
    let r = ForcedResponse::new(&m, gamma, Formulation::HarmonicBalance).unwrap();
    let folds = r.folds(2.0 * PI * 8.0, 2.0 * PI * 22.0).unwrap();
    assert_eq!(folds.len(), 2, "window {width:e}: {folds:?} vs {exact:?}");
    for (f, w) in folds.iter().zip(&exact) {
        assert!((f.omega - w).abs() <= 1e-10 * w, "{} vs {}", f.omega, w);
    }
}

/// Independent oracle for the stability flags: integrate the averaged
/// (slow-flow) equations dX/dτ = −i(1 − Z(|X|)X), Z = S + iD, from a small
/// perturbation of each steady state (X* = x e^{−iφ}) and see whether it
/// returns (stable) or leaves (unstable).
fn slow_flow_returns(
    eq: &nlsdof::harmonic_balance::ResponseEquation,
    x: f64,
    phase: f64,
    kick: (f64, f64),
) -> bool {
    let z = |re: f64, im: f64| {
        let a = re.hypot(im);
        (
            eq.s0 + eq.s1 * a.powf(eq.rho),
            eq.d0 + eq.d1 * a.powf(eq.eta),
        )
    };
    let f = |re: f64, im: f64| {
        let (s, d) = z(re, im);
        let (ur, ui) = (1.0 - (s * re - d * im), -(s * im + d * re));
        (ui, -ur)
    };
    let (x0r, x0i) = (x * phase.cos(), -x * phase.sin());
    let (mut re, mut im) = (x0r * (1.0 + kick.0), x0i * (1.0 + kick.0) + x * kick.1);
    let d0 = ((re - x0r).hypot(im - x0i)) / x;
    // time scale: 1/|Z|, decay ~ D; integrate many decay times
    let (s, d) = z(re, im);
    let h = 0.02 / s.hypot(d).max(1.0).max(1.0 / x);
    let steps = ((200.0 / d.abs().max(1e-3)) / h).min(2e6) as usize;
    for _ in 0..steps {
        let (k1r, k1i) = f(re, im);
        let (k2r, k2i) = f(re + 0.5 * h * k1r, im + 0.5 * h * k1i);
        let (k3r, k3i) = f(re + 0.5 * h * k2r, im + 0.5 * h * k2i);
        let (k4r, k4i) = f(re + h * k3r, im + h * k3i);
        re += h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
        im += h / 6.0 * (k1i + 2.0 * k2i + 2.0 * k3i + k4i);
        if ((re - x0r).hypot(im - x0i)) / x > 0.5 {
            return false;
        }
    }
    ((re - x0r).hypot(im - x0i)) / x < 0.1 * d0
}

#[test]
fn stability_flags_agree_with_slow_flow_integration() {
    let mut checked = (0, 0);
    // hardening Duffing inside the hysteresis band: stable, unstable, stable
    let m = duffing();
    let r = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance).unwrap();
    let folds = r.folds(2.0 * PI * 8.0, 2.0 * PI * 22.0).unwrap();
    for frac in [0.2, 0.5, 0.8] {
        let w = folds[0].omega + frac * (folds[1].omega - folds[0].omega);
        let eq = r.equation(w);
        let set = r.steady_states(w).unwrap();
        assert_eq!(set.roots.len(), 3);
        for s in &set.roots {
            let x = s.amplitude / (1.0 / m.omega_n().powi(2));
            let back = slow_flow_returns(&eq, x, s.phase, (1e-3, 1e-3))
                && slow_flow_returns(&eq, x, s.phase, (-1e-3, 0.0));
            assert_eq!(back, s.stable, "Duffing w={w} root {s:?}");
            if s.stable {
                checked.0 += 1
            } else {
                checked.1 += 1
            }
        }
    }
    // η = −2.5: Hopf instability without a fold
    let m = Model::linear(1.0, 1000.0, 0.5)
        .unwrap()
        .with_damping(0.05, -2.5)
        .unwrap();
    let r = ForcedResponse::new(&m, 5.0, Formulation::HarmonicBalance).unwrap();
    for f_hz in [4.0, 5.0, 6.0] {
        let w = 2.0 * PI * f_hz;
        let eq = r.equation(w);
        for s in &r.steady_states(w).unwrap().roots {
            let x = s.amplitude / (5.0 / m.omega_n().powi(2));
            let back = slow_flow_returns(&eq, x, s.phase, (1e-3, 1e-3))
                && slow_flow_returns(&eq, x, s.phase, (-1e-3, 0.0));
            assert_eq!(back, s.stable, "eta=-2.5 f={f_hz} root {s:?}");
            if s.stable {
                checked.0 += 1
            } else {
                checked.1 += 1
            }
        }
    }
    assert!(checked.0 >= 6 && checked.1 >= 4, "{checked:?}");
}

/// Issue 11: `roots` said "no positive root" for k_r beyond ~1e150 because
/// the squared coefficient s₁² of the expanded equation overflowed. For a
/// huge k_r the root is x = (4 m γ / (3 k_r))^{1/3} (stiffness-dominated
/// cubic term, g(2) = 3/4); the sweep (Newton path) agrees.
#[test]
fn extreme_stiffness_coefficient_keeps_its_root() {
    let w = 2.0 * PI * 10.0;
    for &kr in &[1e100, 1e150, 1e170, 1e200, 1e250, 1e300] {
        let m = Model::linear(1.0, 3947.84, 1.2566)
            .unwrap()
            .with_stiffness(kr, 2.0)
            .unwrap();
        let r = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance).unwrap();
        let set = r.steady_states(w).unwrap();
        assert_eq!(set.roots.len(), 1, "k_r = {kr:e}: {set:?}");
        let x = set.roots[0].amplitude;
        let want = (4.0 / (3.0 * kr)).powf(1.0 / 3.0);
        assert!(
            ((x - want) / want).abs() < 1e-9,
            "k_r = {kr:e}: {x:e} vs {want:e}"
        );
        let sw = r.sweep(&[w], SweepDirection::Up).unwrap();
        assert!(
            ((sw.points[0].amplitude - x) / x).abs() < 1e-9,
            "k_r = {kr:e}"
        );
    }
    // 1e300 is the case: 1.1006424163e-100 m
    let m = Model::linear(1.0, 3947.84, 1.2566)
        .unwrap()
        .with_stiffness(1e300, 2.0)
        .unwrap();
    let set = ForcedResponse::new(&m, 1.0, Formulation::HarmonicBalance)
        .unwrap()
        .steady_states(w)
        .unwrap();
    assert!((set.roots[0].amplitude / 1.1006424163e-100 - 1.0).abs() < 1e-10);
}

/// `steady_states_near` (Newton where the one-root certificate holds)
/// against its oracle `steady_states` (exact isolation of every root): the
/// same set at every frequency of random hardening models (η down to
/// Coulomb friction, sticking included), from guesses a factor 1e-3 … 1e3
/// off: amplitude to 1e-12 relative, phase to 1e-12 rad, same stability.
#[test]
fn steady_states_near_equals_exact_isolation() {
    let mut rng = Rng(0x5eed_5afe_0123_4567);
    let (mut compared, mut single) = (0, 0);
    for case in 0..300 {
        let wn = 10.0;
        let model = NormalisedModel {
            alpha: wn * wn,
            delta: 2.0 * wn * 10f64.powf(rng.range(-3.0, -1.0)),
            beta: 10f64.powf(rng.range(-2.0, 3.0)),
            rho: rng.range(0.0, 5.0),
            kappa: if case % 3 == 0 {
                0.0
            } else {
                10f64.powf(rng.range(-3.0, 0.5))
            },
            eta: if case % 4 == 0 {
                -1.0
            } else {
                rng.range(-0.9, 3.0)
            },
        };
        let gamma = 10f64.powf(rng.range(-1.0, 1.0));
        for formulation in [Formulation::HarmonicBalance, Formulation::Modulation] {
            let Ok(r) = ForcedResponse::from_normalised(&model, gamma, formulation) else {
                continue;
            };
            for k in 0..20 {
                let w = wn * (0.5 + 2.0 * k as f64 / 19.0);
                let Ok(exact) = r.steady_states(w) else {
                    continue;
                };
                let guess = exact.roots.first().map_or(1e-3, |s| s.amplitude)
                    * 10f64.powf(rng.range(-3.0, 3.0));
                let near = r.steady_states_near(w, guess).unwrap();
                assert_eq!(
                    near.roots.len(),
                    exact.roots.len(),
                    "{model:?} γ={gamma} Ω={w}"
                );
                assert_eq!(near.no_motion, exact.no_motion);
                for (a, b) in near.roots.iter().zip(&exact.roots) {
                    assert!(
                        (a.amplitude - b.amplitude).abs() <= 1e-12 * b.amplitude
                            && (a.phase - b.phase).abs() <= 1e-12
                            && a.stable == b.stable,
                        "{model:?} γ={gamma} Ω={w}: {a:?} vs {b:?}"
                    );
                }
                compared += 1;
                single += usize::from(exact.roots.len() == 1);
            }
        }
    }
    eprintln!("{compared} frequencies compared, {single} with one root");
    assert!(compared > 8000 && single > 5000, "{compared} {single}");
}
