//! Time-domain simulation (Eq 32) against independent oracles: closed-form
//! linear responses, convergence order, energy balance, the exact Coulomb
//! free decay, and error handling.

mod support;
use nlsdof::excitation::{Excitation, SampledInput, Sine};
use nlsdof::simulation::{
    dissipated_power, energy, simulate, simulate_excitation, simulate_to_vec, Method, Options,
    Sample, SimulationError, State,
};
use nlsdof::{Model, NormalisedModel};
use std::f64::consts::{PI, TAU};
use support::fixtures::wing;

struct Zero;
impl Excitation for Zero {
    fn accel(&self, _t: f64) -> f64 {
        0.0
    }
}

fn collect(
    model: &NormalisedModel,
    input: &SampledInput<'_>,
    method: Method,
    init: State,
) -> Vec<Sample> {
    let mut out = vec![];
    simulate(
        model,
        input,
        &Options {
            method,
            initial: init,
            decimation: 1,
        },
        |s| out.push(s),
    )
    .unwrap();
    out
}

fn collect_exc<E: Excitation>(
    model: &NormalisedModel,
    e: &E,
    dt: f64,
    n: usize,
    method: Method,
    init: State,
) -> Vec<Sample> {
    let mut out = vec![];
    simulate_excitation(
        model,
        e,
        0.0,
        dt,
        n,
        &Options {
            method,
            initial: init,
            decimation: 1,
        },
        |s| out.push(s),
    )
    .unwrap();
    out
}

/// Linear SDoF `x'' + δx' + αx = A sin(Ωt + φ0)`, closed form from (x0, v0).
struct LinearSine {
    alpha: f64,
    delta: f64,
    a: f64,
    w: f64,
    p: f64,
    x0: f64,
    v0: f64,
}

impl LinearSine {
    fn eval(&self, t: f64) -> (f64, f64) {
        // particular: Im(A H e^{i(Ωt+φ)}), H = 1/(α − Ω² + iδΩ)
        let (re, im) = (self.alpha - self.w * self.w, self.delta * self.w);
        let den = re * re + im * im;
        let (hr, hi) = (re / den, -im / den);
        let xp = |t: f64| {
            let th = self.w * t + self.p;
            self.a * (hr * th.sin() + hi * th.cos())
        };
        let vp = |t: f64| {
            let th = self.w * t + self.p;
            self.a * self.w * (hr * th.cos() - hi * th.sin())
        };
        let sigma = 0.5 * self.delta;
        let wd = (self.alpha - sigma * sigma).sqrt();
        let c1 = self.x0 - xp(0.0);
        let c2 = (self.v0 - vp(0.0) + sigma * c1) / wd;
        let e = (-sigma * t).exp();
        let (c, s) = ((wd * t).cos(), (wd * t).sin());
        let xh = e * (c1 * c + c2 * s);
        let vh = e * (-sigma * (c1 * c + c2 * s) + wd * (-c1 * s + c2 * c));
        (xp(t) + xh, vp(t) + vh)
    }
}

fn max_rel_err(out: &[Sample], exact: impl Fn(f64) -> (f64, f64)) -> (f64, f64) {
    let (mut ex, mut ev, mut sx, mut sv) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for s in out {
        let (x, v) = exact(s.t);
        ex = ex.max((s.x - x).abs());
        ev = ev.max((s.v - v).abs());
        sx = sx.max(x.abs());
        sv = sv.max(v.abs());
    }
    (ex / sx, ev / sv)
}

/// RK4 (both input modes) and Dormand–Prince against the closed-form
/// response of a linear oscillator to a sine, including the transient.
/// 20 s (108 cycles) at 3 % below resonance of the wing's linear part
/// (ζ = 0.64 %), fs = 2048 Hz. Bound on the relative max-norm error:
/// ≤ 2e-6 for RK4 with two samples per step (h = 1/1024 s, ω_n h = 0.033),
/// ≤ 2e-7 for RK4 with one step per 1/fs on the analytic input, ≤ 1e-8 for
/// DOPRI (rtol 1e-10). (The phase error of the lightly damped transient
/// dominates: it grows with the number of cycles.)
#[test]
fn linear_sine_response_matches_closed_form() {
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .normalised()
        .unwrap();
    let w = 0.97 * m.omega_n();
    let cf = LinearSine {
        alpha: m.alpha,
        delta: m.delta,
        a: 0.5,
        w,
        p: 0.3,
        x0: 0.01,
        v0: -0.2,
    };
    let sine = Sine::new(0.5, w, 0.3).unwrap();
    let fs = 2048.0;
    let n = (20.0 * fs) as usize + 1;
    let samples: Vec<f64> = (0..n).map(|k| sine.accel(k as f64 / fs)).collect();
    let input = SampledInput::uniform(&samples, fs, 0.0).unwrap();
    let init = State { x: 0.01, v: -0.2 };
    // two samples per step: stage inputs are exact samples of the smooth sine
    let (ex, ev) = max_rel_err(
        &collect(
            &m,
            &input,
            Method::Rk4 {
                samples_per_step: 2,
            },
            init,
        ),
        |t| cf.eval(t),
    );
    assert!(ex < 2e-6 && ev < 2e-6, "rk4 x2: {ex:e} {ev:e}");
    // analytic input, one RK4 step per 1/fs
    let (ex1, ev1) = max_rel_err(
        &collect_exc(
            &m,
            &sine,
            1.0 / fs,
            n,
            Method::Rk4 {
                samples_per_step: 1,
            },
            init,
        ),
        |t| cf.eval(t),
    );
    assert!(ex1 < 2e-7 && ev1 < 2e-7, "rk4 analytic: {ex1:e} {ev1:e}");
    let (ed, edv) = max_rel_err(
        &collect_exc(&m, &sine, 1.0 / fs, n, Method::reference(), init),
        |t| cf.eval(t),
    );
    assert!(ed < 1e-8 && edv < 1e-8, "dopri: {ed:e} {edv:e}");
    println!("sine: rk4x2 {ex:e}/{ev:e} rk4 {ex1:e}/{ev1:e} dopri {ed:e}/{edv:e}");
}

/// Exact response of the linear oscillator to a piecewise-linear input:
/// on each interval `u = u_k + s τ`, particular solution
/// `x_p = (u_k + s τ)/α − s δ/α²`, `v_p = s/α`, homogeneous part through
/// the exact transition matrix.
fn linear_pl_exact(
    alpha: f64,
    delta: f64,
    t: &[f64],
    u: &[f64],
    x0: f64,
    v0: f64,
) -> Vec<(f64, f64)> {
    let sigma = 0.5 * delta;
    let wd = (alpha - sigma * sigma).sqrt();
    let mut out = vec![(x0, v0)];
    let (mut x, mut v) = (x0, v0);
    for k in 0..t.len() - 1 {
        let h = t[k + 1] - t[k];
        let s = (u[k + 1] - u[k]) / h;
        let xp = |tau: f64| (u[k] + s * tau) / alpha - s * delta / (alpha * alpha);
        let vp = s / alpha;
        let (yh, vh) = (x - xp(0.0), v - vp);
        let e = (-sigma * h).exp();
        let (c, sn) = ((wd * h).cos(), (wd * h).sin());
        let xh1 = e * (yh * (c + sigma / wd * sn) + vh * sn / wd);
        let vh1 = e * (-yh * alpha / wd * sn + vh * (c - sigma / wd * sn));
        x = xp(h) + xh1;
        v = vp + vh1;
        out.push((x, v));
    }
    out
}

/// Pseudo-random numbers in [−1, 1) (64-bit LCG; deterministic).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// RK4 with one step per sample and Dormand–Prince (restarted at every
/// sample) against the exact response to a piecewise-linear input — a
/// broadband random signal, uniform and non-uniform time grids.
/// fs = 2048 Hz, 20 000 samples. Bound on the relative max-norm error:
/// ≤ 1e-7 (RK4), ≤ 1e-8 (DOPRI).
#[test]
fn linear_piecewise_linear_response_matches_closed_form() {
    let m = Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .normalised()
        .unwrap();
    let mut rnd = lcg(7);
    let n = 20_000;
    let fs = 2048.0;
    let u: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let t: Vec<f64> = (0..n).map(|k| k as f64 / fs).collect();
    let init = State { x: 0.002, v: 0.05 };
    let exact = linear_pl_exact(m.alpha, m.delta, &t, &u, init.x, init.v);
    let check = |out: &[Sample], tol: f64, what: &str| {
        let (mut ex, mut sx, mut ev, mut sv) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (s, &(x, v)) in out.iter().zip(&exact) {
            ex = ex.max((s.x - x).abs());
            ev = ev.max((s.v - v).abs());
            sx = sx.max(x.abs());
            sv = sv.max(v.abs());
        }
        assert_eq!(out.len(), exact.len());
        println!("{what}: {:e} {:e}", ex / sx, ev / sv);
        assert!(
            ex / sx < tol && ev / sv < tol,
            "{what}: {:e} {:e}",
            ex / sx,
            ev / sv
        );
    };
    let uni = SampledInput::uniform(&u, fs, 0.0).unwrap();
    check(
        &collect(
            &m,
            &uni,
            Method::Rk4 {
                samples_per_step: 1,
            },
            init,
        ),
        1e-7,
        "rk4 uniform",
    );
    check(
        &collect(&m, &uni, Method::reference(), init),
        1e-8,
        "dopri uniform",
    );
    // non-uniform grid: jittered times
    let mut rnd = lcg(11);
    let tj: Vec<f64> = (0..n).map(|k| (k as f64 + 0.3 * rnd()) / fs).collect();
    let exact_j = linear_pl_exact(m.alpha, m.delta, &tj, &u, init.x, init.v);
    let nonuni = SampledInput::with_times(&tj, &u).unwrap();
    let out = collect(
        &m,
        &nonuni,
        Method::Rk4 {
            samples_per_step: 1,
        },
        init,
    );
    let err = out
        .iter()
        .zip(&exact_j)
        .map(|(s, &(x, _))| (s.x - x).abs())
        .fold(0.0, f64::max);
    let scale = exact_j.iter().map(|p| p.0.abs()).fold(0.0, f64::max);
    assert!(err / scale < 1e-7, "rk4 non-uniform: {:e}", err / scale);
    assert!(matches!(
        simulate(&m, &nonuni, &Options::default(), |_| {}),
        Err(SimulationError::StrideNeedsUniformSampling {
            samples_per_step: 2
        })
    ));
}

/// Smooth nonlinear case (ρ = 2, η = 2: the RHS is a polynomial): the RK4
/// error at a fixed time falls ~16× per halving of the step. Oracle: DOPRI
/// at rtol 1e-13.
#[test]
fn rk4_convergence_order_is_four() {
    let m = Model::linear(1.0, 100.0, 0.4)
        .unwrap()
        .with_stiffness(2.0e4, 2.0)
        .unwrap()
        .with_damping(5.0, 2.0)
        .unwrap();
    let m = m.normalised().unwrap();
    let sine = Sine::new(30.0, 11.0, 0.0).unwrap();
    let t_end = 4.0;
    let init = State { x: 0.01, v: 0.0 };
    let reference = collect_exc(
        &m,
        &sine,
        t_end / 64.0,
        65,
        Method::DormandPrince {
            rtol: 1e-13,
            atol: 1e-16,
        },
        init,
    );
    let end = reference.last().unwrap();
    let mut errs = vec![];
    for k in 0..4 {
        let steps = 400usize << k;
        let out = collect_exc(
            &m,
            &sine,
            t_end / steps as f64,
            steps + 1,
            Method::Rk4 {
                samples_per_step: 1,
            },
            init,
        );
        let last = out.last().unwrap();
        assert!((last.t - t_end).abs() < 1e-12);
        errs.push((last.x - end.x).abs().max((last.v - end.v).abs() / 10.0));
    }
    for w in errs.windows(2) {
        let r = w[0] / w[1];
        assert!(
            (13.0..19.5).contains(&r),
            "error ratio {r} (errors {errs:?})"
        );
    }
    // the same through sampled input, two samples per step (fs doubles)
    let mut errs2 = vec![];
    for k in 0..3 {
        let fs = 200.0 * (1 << k) as f64;
        let n = (t_end * fs) as usize + 1;
        let s: Vec<f64> = (0..n).map(|i| sine.accel(i as f64 / fs)).collect();
        let inp = SampledInput::uniform(&s, fs, 0.0).unwrap();
        let out = collect(
            &m,
            &inp,
            Method::Rk4 {
                samples_per_step: 2,
            },
            init,
        );
        let last = out.last().unwrap();
        errs2.push((last.x - end.x).abs().max((last.v - end.v).abs() / 10.0));
    }
    for w in errs2.windows(2) {
        let r = w[0] / w[1];
        assert!(
            (13.0..19.5).contains(&r),
            "sampled x2 error ratio {r} (errors {errs2:?})"
        );
    }
    println!("rk4 errors {errs:?} sampled {errs2:?}");
}

/// 5-point Gauss–Legendre integral of `f(v(τ))` over every output interval,
/// with v(τ) the cubic Hermite interpolant of (v, a) at the ends.
fn integrate_along<F: Fn(f64, f64) -> f64>(
    m: &NormalisedModel,
    out: &[Sample],
    exc: &dyn Fn(f64) -> f64,
    f: F,
) -> f64 {
    const X: [f64; 5] = [
        0.0,
        -0.538_469_310_105_683_1,
        0.538_469_310_105_683_1,
        -0.906_179_845_938_664,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
        0.236_926_885_056_189_1,
    ];
    let acc = |s: &Sample| s.u - m.internal_acceleration(s.x, s.v);
    let mut total = 0.0;
    for w in out.windows(2) {
        let (p, q) = (&w[0], &w[1]);
        let h = q.t - p.t;
        let (a0, a1) = (acc(p), acc(q));
        let mut sum = 0.0;
        for (xi, wi) in X.iter().zip(W) {
            let s = 0.5 * (xi + 1.0);
            let s2 = s * s;
            let s3 = s2 * s;
            let v = (2.0 * s3 - 3.0 * s2 + 1.0) * p.v
                + (s3 - 2.0 * s2 + s) * h * a0
                + (-2.0 * s3 + 3.0 * s2) * q.v
                + (s3 - s2) * h * a1;
            sum += wi * f(p.t + s * h, v);
        }
        total += 0.5 * h * sum;
    }
    let _ = exc;
    total
}

/// Energy balance `E(T) − E(0) = ∫ u v dt − ∫ (δ v² + κ|v|^{η+2}) dt` with
/// `E = v²/2 + αx²/2 + β|x|^{ρ+2}/(ρ+2)`, for the wing model (real
/// exponents) in free decay and under a sine, to 1e-6 of the energy
/// throughput. Oracle: the potentials of the force laws, integrated
/// independently of the integrator (Gauss–Legendre on Hermite output).
#[test]
fn energy_balance_free_decay_and_forced() {
    let m = wing().normalised().unwrap();
    let dt = 1.0 / 2048.0;
    // free decay
    let init = State { x: 0.05, v: 0.0 };
    let out = collect_exc(
        &m,
        &Zero,
        dt,
        8 * 2048,
        Method::Rk4 {
            samples_per_step: 1,
        },
        init,
    );
    let e0 = energy(&m, init);
    let last = out.last().unwrap();
    let e1 = energy(
        &m,
        State {
            x: last.x,
            v: last.v,
        },
    );
    let wd = integrate_along(&m, &out, &|_| 0.0, |_, v| dissipated_power(&m, v));
    let rel = ((e0 - e1) - wd).abs() / (e0 - e1);
    println!("free decay: E0 {e0:e} E1 {e1:e} dissipated {wd:e} rel {rel:e}");
    assert!(e1 < 0.5 * e0, "decay too small to be a test");
    assert!(rel < 1e-6, "free-decay energy balance {rel:e}");
    // forced
    let sine = Sine::new(1.0, 0.995 * m.omega_n(), 0.0).unwrap();
    let out = collect_exc(
        &m,
        &sine,
        dt,
        8 * 2048,
        Method::Rk4 {
            samples_per_step: 1,
        },
        State::default(),
    );
    let last = out.last().unwrap();
    let e1 = energy(
        &m,
        State {
            x: last.x,
            v: last.v,
        },
    );
    let win = integrate_along(&m, &out, &|t| sine.accel(t), |t, v| sine.accel(t) * v);
    let wd = integrate_along(&m, &out, &|_| 0.0, |_, v| dissipated_power(&m, v));
    let rel = ((e1 - 0.0) - (win - wd)).abs() / win.abs().max(wd);
    println!("forced: E1 {e1:e} input {win:e} dissipated {wd:e} rel {rel:e}");
    assert!(rel < 1e-6, "forced energy balance {rel:e}");
}

/// Exact piecewise solution of Coulomb free decay `x'' + αx + κ sgn(x') = 0`
/// from (x0, 0): half-cycle n starts at t_n = nπ/ω at
/// `x_n = (−1)^n (x0 − 2nκ/α)`, oscillating about `(−1)^n κ/α`; the motion
/// stops at the first turning point with `|x_n| ≤ κ/α`.
fn coulomb_exact(alpha: f64, kappa: f64, x0: f64, t: f64) -> (f64, f64) {
    let w = alpha.sqrt();
    let xf = kappa / alpha;
    let half = PI / w;
    let mut n = 0usize;
    loop {
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        let xn = sign * (x0 - 2.0 * n as f64 * xf);
        if xn.abs() <= xf {
            return (xn, 0.0); // stuck for ever
        }
        let tn = n as f64 * half;
        if t < tn + half || (xn.abs() - 2.0 * xf).abs() < 0.0 {
            let xe = sign * xf;
            let tau = t - tn;
            return (
                xe + (xn - xe) * (w * tau).cos(),
                -(xn - xe) * w * (w * tau).sin(),
            );
        }
        n += 1;
    }
}

/// Coulomb friction (η = −1) free decay: the amplitude falls linearly by
/// `4 c_f / k` per cycle and the mass sticks at the first turning point
/// inside `|x| ≤ c_f/k` — checked sample by sample against the exact
/// piecewise-harmonic solution, for RK4 and Dormand–Prince.
#[test]
fn coulomb_free_decay_is_linear_with_4cf_over_k_per_cycle() {
    let (mass, k, cf) = (2.0, 2.0 * TAU * TAU, 1.0); // f_n = 1 Hz
    let model = Model::linear(mass, k, 0.0)
        .unwrap()
        .with_damping(cf, -1.0)
        .unwrap();
    let m = model.normalised().unwrap();
    let x0 = 0.3;
    let dt = 1e-3;
    let n = 12_001; // 12 s: decays to rest after ~2.96 cycles
    for method in [
        Method::Rk4 {
            samples_per_step: 1,
        },
        Method::reference(),
    ] {
        let out = collect_exc(&m, &Zero, dt, n, method, State { x: x0, v: 0.0 });
        let mut err = 0.0f64;
        for s in &out {
            let (x, v) = coulomb_exact(m.alpha, m.kappa, x0, s.t);
            err = err.max((s.x - x).abs()).max((s.v - v).abs() / m.omega_n());
        }
        assert!(
            err < 1e-8 * x0,
            "{method:?}: max deviation from exact Coulomb decay {err:e}"
        );
        // turning points at t = n/2 s (ω = 2π): |x| falls by 2 c_f/k per half cycle
        let at = |t: f64| out[(t / dt).round() as usize].x;
        let per_cycle = 4.0 * cf / k;
        for c in 0..2 {
            let drop = at(c as f64).abs() - at(c as f64 + 1.0).abs();
            assert!(
                (drop - per_cycle).abs() < 1e-8,
                "cycle {c}: drop {drop} vs 4cf/k = {per_cycle}"
            );
        }
        let rest = out.last().unwrap();
        let exact_rest = coulomb_exact(m.alpha, m.kappa, x0, 1e9).0;
        assert!(
            (rest.x - exact_rest).abs() < 1e-8 && rest.v == 0.0,
            "rest at {} vs {exact_rest}",
            rest.x
        );
    }
}

/// Forced Coulomb oscillator: below the breakaway force the mass never
/// moves (exact); above it, stick–slip motion with RK4 and DOPRI agreeing,
/// and the energy balance (input work = friction work + viscous work + ΔE,
/// friction work κ∫|v|dt) closing to 1e-6.
#[test]
fn forced_coulomb_sticks_and_slips_consistently() {
    let model = Model::linear(1.0, TAU * TAU, 0.05)
        .unwrap()
        .with_damping(0.8, -1.0)
        .unwrap();
    let m = model.normalised().unwrap();
    let weak = Sine::new(0.79, 3.0, 0.0).unwrap();
    let out = collect_exc(
        &m,
        &weak,
        1e-3,
        5001,
        Method::Rk4 {
            samples_per_step: 1,
        },
        State::default(),
    );
    assert!(
        out.iter().all(|s| s.x == 0.0 && s.v == 0.0),
        "mass moved below the friction force"
    );
    let strong = Sine::new(1.5, 0.6 * TAU, 0.0).unwrap();
    let dt = 1.0 / 1024.0;
    let n = 10 * 1024 + 1;
    let a = collect_exc(
        &m,
        &strong,
        dt,
        n,
        Method::Rk4 {
            samples_per_step: 1,
        },
        State::default(),
    );
    let b = collect_exc(&m, &strong, dt, n, Method::reference(), State::default());
    let scale = a.iter().map(|s| s.x.abs()).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (p.x - q.x).abs())
        .fold(0.0, f64::max);
    assert!(
        diff < 1e-6 * scale,
        "rk4 vs dopri with stick-slip: {:e}",
        diff / scale
    );
    let stuck = a.iter().filter(|s| s.v == 0.0).count();
    assert!(
        stuck > 100,
        "expected stick phases, found {stuck} stuck samples"
    );
    let last = b.last().unwrap();
    let e1 = energy(
        &m,
        State {
            x: last.x,
            v: last.v,
        },
    );
    let win = integrate_along(&m, &b, &|t| strong.accel(t), |t, v| strong.accel(t) * v);
    let wv = integrate_along(&m, &b, &|_| 0.0, |_, v| m.delta * v * v);
    let wf = integrate_along(&m, &b, &|_| 0.0, |_, v| m.kappa * v.abs());
    let rel = (e1 - (win - wv - wf)).abs() / win;
    println!("coulomb forced: E1 {e1:e} win {win:e} viscous {wv:e} friction {wf:e} rel {rel:e} stuck {stuck}");
    // Hermite quadrature across the kinks at events limits this check
    assert!(rel < 1e-4, "friction energy balance {rel:e}");
}

/// −1 < η < 0: continuous but non-Lipschitz damping at v = 0, integrated
/// directly; the error still falls when the step is halved (order is lost
/// only in the steps containing a velocity reversal).
#[test]
fn sub_linear_damping_converges() {
    let model = Model::linear(1.0, 100.0, 0.0)
        .unwrap()
        .with_damping(0.5, -0.5)
        .unwrap();
    let m = model.normalised().unwrap();
    let sine = Sine::new(3.0, 9.0, 0.0).unwrap();
    let reference = collect_exc(
        &m,
        &sine,
        0.01,
        301,
        Method::DormandPrince {
            rtol: 1e-12,
            atol: 1e-15,
        },
        State::default(),
    );
    let end = reference.last().unwrap().x;
    let mut errs = vec![];
    for k in 0..3 {
        let steps = 3000usize << k;
        let out = collect_exc(
            &m,
            &sine,
            3.0 / steps as f64,
            steps + 1,
            Method::Rk4 {
                samples_per_step: 1,
            },
            State::default(),
        );
        errs.push((out.last().unwrap().x - end).abs());
    }
    assert!(
        errs[0] / errs[1] > 2.5 && errs[1] / errs[2] > 2.5,
        "errors {errs:?}"
    );
    let scale = reference.iter().map(|s| s.x.abs()).fold(0.0, f64::max);
    assert!(errs[2] < 1e-6 * scale, "errors {errs:?} (scale {scale})");
    // η < −1 is rejected, not silently integrated
    let bad = Model::linear(1.0, 1.0, 0.0)
        .unwrap()
        .with_damping(0.1, -1.5)
        .unwrap()
        .normalised()
        .unwrap();
    let z = [0.0; 4];
    let inp = SampledInput::uniform(&z, 10.0, 0.0).unwrap();
    assert_eq!(
        simulate(&bad, &inp, &Options::default(), |_| {}),
        Err(SimulationError::SingularDamping { eta: -1.5 })
    );
}

/// Efficiency snapshot: Dormand–Prince cost on a reference problem (wing
/// model, 10 s of near-resonant sine, analytic input with 64 outputs/s,
/// rtol 1e-9). A regression of more than 2 % fails; an improvement asks
/// for the snapshot to be lowered.
#[test]
fn dopri_cost_snapshot() {
    const SNAPSHOT_RHS: u64 = 41_827;
    let m = wing().normalised().unwrap();
    let sine = Sine::new(1.0, m.omega_n(), 0.0).unwrap();
    let s = simulate_excitation(
        &m,
        &sine,
        0.0,
        1.0 / 64.0,
        641,
        &Options {
            method: Method::DormandPrince {
                rtol: 1e-9,
                atol: 1e-12,
            },
            ..Default::default()
        },
        |_| {},
    )
    .unwrap();
    println!(
        "dopri cost: {} RHS, {} steps, {} rejected",
        s.rhs_evaluations, s.steps, s.rejected_steps
    );
    if SNAPSHOT_RHS > 0 {
        assert!(
            s.rhs_evaluations as f64 <= 1.02 * SNAPSHOT_RHS as f64,
            "cost regression: {} > {SNAPSHOT_RHS}",
            s.rhs_evaluations
        );
        assert!(
            s.rhs_evaluations as f64 >= 0.9 * SNAPSHOT_RHS as f64,
            "cost improved: lower SNAPSHOT_RHS to {}",
            s.rhs_evaluations
        );
    }
    // sampled input: exactly one step per sample at 2048 Hz (6 RHS + 1)
    let fs = 2048.0;
    let u: Vec<f64> = (0..2049).map(|k| sine.accel(k as f64 / fs)).collect();
    let inp = SampledInput::uniform(&u, fs, 0.0).unwrap();
    let s = simulate(
        &m,
        &inp,
        &Options {
            method: Method::reference(),
            ..Default::default()
        },
        |_| {},
    )
    .unwrap();
    assert_eq!(s.steps, 2048);
    assert_eq!(s.rejected_steps, 0);
    assert_eq!(s.rhs_evaluations, 6 * 2048 + 1);
}

/// Bad inputs give typed errors carrying the offending value, never numbers.
#[test]
fn bad_input_is_rejected_with_the_offending_value() {
    let m = wing().normalised().unwrap();
    let o = Options::default();
    let nan = [0.0, 1.0, f64::NAN, 2.0];
    assert!(matches!(
        SampledInput::uniform(&nan, 100.0, 0.0),
        Err(SimulationError::NonFiniteSample { index: 2, .. })
    ));
    let inf = [0.0, f64::INFINITY];
    assert!(
        matches!(SampledInput::uniform(&inf, 100.0, 0.0), Err(SimulationError::NonFiniteSample { index: 1, value }) if value.is_infinite())
    );
    assert_eq!(
        SampledInput::uniform(&[1.0, 2.0], 0.0, 0.0),
        Err(SimulationError::NonPositiveFs { fs: 0.0 })
    );
    assert_eq!(
        SampledInput::uniform(&[1.0, 2.0], -2048.0, 0.0),
        Err(SimulationError::NonPositiveFs { fs: -2048.0 })
    );
    assert_eq!(
        SampledInput::uniform(&[], 1.0, 0.0),
        Err(SimulationError::EmptyInput)
    );
    assert_eq!(
        SampledInput::uniform(&[1.0], 1.0, 0.0),
        Err(SimulationError::TooFewSamples { len: 1, min: 2 })
    );
    assert_eq!(
        SampledInput::with_times(&[0.0, 1.0, 1.0], &[0.0; 3]),
        Err(SimulationError::NonMonotonicTime {
            index: 2,
            t: 1.0,
            previous: 1.0
        })
    );
    assert_eq!(
        SampledInput::with_times(&[0.0, 1.0], &[0.0; 3]),
        Err(SimulationError::LengthMismatch {
            times: 2,
            samples: 3
        })
    );
    let z = [0.0; 8];
    let inp = SampledInput::uniform(&z, 100.0, 0.0).unwrap();
    let bad = |o: Options| simulate(&m, &inp, &o, |_| {}).unwrap_err();
    assert!(matches!(
        bad(Options { decimation: 0, ..o }),
        SimulationError::InvalidOption {
            name: "decimation",
            ..
        }
    ));
    assert!(
        matches!(bad(Options { method: Method::Rk4 { samples_per_step: 3 }, ..o }), SimulationError::InvalidOption { value, .. } if value == 3.0)
    );
    assert!(matches!(
        bad(Options {
            method: Method::DormandPrince {
                rtol: 0.0,
                atol: 1e-9
            },
            ..o
        }),
        SimulationError::InvalidOption { name: "rtol", .. }
    ));
    assert!(matches!(
        bad(Options {
            initial: State {
                x: f64::NAN,
                v: 0.0
            },
            ..o
        }),
        SimulationError::InvalidOption { .. }
    ));
}

/// A softening model driven out of its potential well stops with
/// `Diverged` instead of streaming infinities.
#[test]
fn divergence_is_an_error() {
    let m = Model::linear(1.0, 1.0, 0.0)
        .unwrap()
        .with_stiffness(-1.0, 2.0)
        .unwrap()
        .normalised()
        .unwrap();
    let u = vec![5.0; 4000];
    let inp = SampledInput::uniform(&u, 10.0, 0.0).unwrap();
    for method in [
        Method::Rk4 {
            samples_per_step: 2,
        },
        Method::Rk4 {
            samples_per_step: 1,
        },
        Method::reference(),
    ] {
        let r = simulate(
            &m,
            &inp,
            &Options {
                method,
                ..Default::default()
            },
            |_| {},
        );
        assert!(
            matches!(
                r,
                Err(SimulationError::Diverged { .. })
                    | Err(SimulationError::StepSizeUnderflow { .. })
            ),
            "{method:?}: {r:?}"
        );
    }
}

/// Decimation keeps indices 0, d, 2d, … and the same states as the full run;
/// every output of the two-samples-per-step mode, including the mid-step
/// (Hermite) ones, agrees with RK4 on the exact analytic input at h = 1/fs
/// to 1e-6 (2 s at resonance, fs = 2048 Hz).
#[test]
fn decimation_and_mid_step_outputs() {
    let m = wing().normalised().unwrap();
    let fs = 2048.0;
    let sine = Sine::new(0.6, m.omega_n(), 0.0).unwrap();
    let u: Vec<f64> = (0..4097).map(|k| sine.accel(k as f64 / fs)).collect();
    let inp = SampledInput::uniform(&u, fs, 0.5).unwrap();
    let (full, s) = simulate_to_vec(&m, &inp, &Options::default()).unwrap();
    assert_eq!(s.samples_per_step, 2);
    assert_eq!(full.x.len(), 4097);
    assert!((full.t[4096] - (0.5 + 2.0)).abs() < 1e-12);
    let (dec, _) = simulate_to_vec(
        &m,
        &inp,
        &Options {
            decimation: 7,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(dec.index, (0..4097).step_by(7).collect::<Vec<_>>());
    for (k, &i) in dec.index.iter().enumerate() {
        assert_eq!(dec.x[k], full.x[i]);
    }
    // the same signal on its own clock (the sampled one starts at t0 = 0.5)
    let one = collect_exc(
        &m,
        &sine,
        1.0 / fs,
        4097,
        Method::Rk4 {
            samples_per_step: 1,
        },
        State::default(),
    );
    let scale = full.x.iter().map(|x| x.abs()).fold(0.0, f64::max);
    let diff = full
        .x
        .iter()
        .zip(&one)
        .map(|(a, b)| (a - b.x).abs())
        .fold(0.0, f64::max);
    let diff_mid = full
        .x
        .iter()
        .zip(&one)
        .skip(1)
        .step_by(2)
        .map(|(a, b)| (a - b.x).abs())
        .fold(0.0, f64::max);
    let diff_end = full
        .x
        .iter()
        .zip(&one)
        .step_by(2)
        .map(|(a, b)| (a - b.x).abs())
        .fold(0.0, f64::max);
    // RK4 error of h = 2/fs over 2 s at resonance; the interpolated mid-step
    // outputs are no worse than the step ends
    assert!(diff < 1e-6 * scale, "x2 vs analytic: {:e}", diff / scale);
    assert!(
        diff_mid <= 1.5 * diff_end,
        "mid {:e} vs ends {:e}",
        diff_mid / scale,
        diff_end / scale
    );
}
