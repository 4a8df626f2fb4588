//! Event handling for Coulomb friction (η = −1): the friction force per
//! unit mass is `κ sgn(x')` while slipping and anything in `[−κ, κ]` while
//! stuck (Filippov's set-valued extension, static = kinetic friction).
//!
//! * Slip with sign `s`: `x'' = (u − κ s) − (δ x' + α x + β x|x|^ρ)`, a
//!   smooth right-hand side (friction is a constant offset of the input).
//! * `x'` reaches 0 at the event time `t*` (located by Illinois regula
//!   falsi). With `F = u(t*) − α x − β x|x|^ρ` (force per unit mass other
//!   than friction), the mass sticks if `|F| ≤ κ`, else slips with
//!   `s = sgn F`.
//! * Stuck: `x` frozen, `x' = 0`, until `|F(t)| = κ` (breakaway, located the
//!   same way); then slip with `s = sgn F`.

use super::law::{Dyn, Law};
use super::rk4_step::step;
use super::{SimulationError, Summary};

/// Friction state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Mode {
    /// Slipping with velocity sign ±1.
    Slip(f64),
    Stick,
}

/// Maximum events inside one sample interval before giving up.
pub(crate) const EVENT_LIMIT: usize = 64;

/// Mode at velocity `v` with input `u` (used at the start and after every
/// velocity reversal).
pub(crate) fn initial_mode<S: Law, D: Law>(
    d: &Dyn<S, D>,
    kappa: f64,
    x: f64,
    v: f64,
    u: f64,
) -> Mode {
    if v > 0.0 {
        Mode::Slip(1.0)
    } else if v < 0.0 {
        Mode::Slip(-1.0)
    } else {
        rest_mode(d, kappa, x, u)
    }
}

/// Mode of a mass at rest at `x` under input `u`.
#[inline]
pub(crate) fn rest_mode<S: Law, D: Law>(d: &Dyn<S, D>, kappa: f64, x: f64, u: f64) -> Mode {
    let f = u - d.restoring(x);
    if f.abs() <= kappa {
        Mode::Stick
    } else {
        Mode::Slip(f.signum())
    }
}

/// Illinois (modified regula falsi) root of `g` in `[a, b]` with
/// `g(a) > 0 ≥ g(b)`. Returns the end of the final bracket where `g ≤ 0`
/// (the event has happened), after at most 200 evaluations or when the
/// bracket is shorter than `tol`.
pub(crate) fn illinois<G: FnMut(f64) -> f64>(
    mut g: G,
    mut a: f64,
    mut fa: f64,
    mut b: f64,
    mut fb: f64,
    tol: f64,
) -> f64 {
    // invariant: fa > 0 >= fb
    let mut side = 0i8;
    for _ in 0..200 {
        if b - a <= tol {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a && c < b) {
            c = 0.5 * (a + b);
        }
        let fc = g(c);
        if fc > 0.0 {
            a = c;
            fa = fc;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            b = c;
            fb = fc;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
            if fc == 0.0 {
                break;
            }
        }
    }
    b
}

/// First time in `[lo, hi]` at which a stuck mass breaks away, i.e.
/// `|F(τ)| > κ` with `F(τ) = u(τ) − restoring`; `None` if it stays stuck
/// (checked at the mid point and the end of the interval).
pub(crate) fn breakaway<U: Fn(f64) -> f64>(
    u: &U,
    restoring: f64,
    kappa: f64,
    lo: f64,
    hi: f64,
) -> Option<(f64, f64)> {
    let excess = |tau: f64| (u(tau) - restoring).abs() - kappa;
    let mid = 0.5 * (lo + hi);
    let probe = if excess(mid) > 0.0 {
        mid
    } else if excess(hi) > 0.0 {
        hi
    } else {
        return None;
    };
    // g > 0 while stuck, <= 0 once broken away
    let g = |tau: f64| -excess(tau);
    let g_lo = g(lo);
    let tb = if g_lo > 0.0 {
        illinois(
            g,
            lo,
            g_lo,
            probe,
            g(probe),
            1e-14 * (hi - lo).max(f64::MIN_POSITIVE),
        )
    } else {
        lo
    };
    let s = (u(tb) - restoring).signum();
    Some((tb, s))
}

/// Advances `(x, v)` over one interval of length `h` (input `u(τ)`,
/// `τ ∈ [0, h]`) with RK4 sub-steps between friction events. `d` holds
/// the dynamics *without* the damping power law.
#[allow(clippy::too_many_arguments)]
pub(crate) fn rk4_interval<S: Law, D: Law, U: Fn(f64) -> f64>(
    d: &Dyn<S, D>,
    kappa: f64,
    h: f64,
    u: &U,
    t_abs: f64,
    x: &mut f64,
    v: &mut f64,
    mode: &mut Mode,
    sum: &mut Summary,
) -> Result<(), SimulationError> {
    let mut tau = 0.0;
    for _ in 0..EVENT_LIMIT {
        let rem = h - tau;
        if rem <= 0.0 {
            return Ok(());
        }
        match *mode {
            Mode::Stick => {
                let r = d.restoring(*x);
                sum.rhs_evaluations += 2;
                match breakaway(u, r, kappa, tau, h) {
                    None => {
                        *v = 0.0;
                        return Ok(());
                    }
                    Some((tb, s)) => {
                        sum.events += 1;
                        tau = tb;
                        *mode = Mode::Slip(s);
                    }
                }
            }
            Mode::Slip(s) => {
                let fr = kappa * s;
                let (x0, v0) = (*x, *v);
                let a1 = u(tau) - fr - d.internal(x0, v0);
                let take = |len: f64| {
                    step(
                        d,
                        x0,
                        v0,
                        a1,
                        len,
                        u(tau + 0.5 * len) - fr,
                        u(tau + len) - fr,
                    )
                };
                let (xn, vn) = take(rem);
                sum.steps += 1;
                sum.rhs_evaluations += 4;
                if s * vn > 0.0 {
                    *x = xn;
                    *v = vn;
                    return Ok(());
                }
                // velocity reversal inside the step: g(σ) = s·v(σ) > 0 before it
                let mut evals = 0u64;
                let mut g = |len: f64| {
                    evals += 1;
                    s * take(len).1
                };
                let (mut a, mut ga) = (0.0, s * v0);
                if ga <= 0.0 {
                    // just broke away (v0 = 0): find a small σ with s·v > 0
                    let mut p = 0.5 * rem;
                    ga = 0.0;
                    for _ in 0..60 {
                        let gp = g(p);
                        if gp > 0.0 {
                            a = p;
                            ga = gp;
                            break;
                        }
                        p *= 0.5;
                    }
                }
                let sigma = if ga > 0.0 {
                    illinois(&mut g, a, ga, rem, s * vn, 1e-14 * h)
                } else {
                    rem.min(1e-14 * h)
                };
                sum.rhs_evaluations += 3 * evals;
                let (xe, _) = take(sigma);
                *x = xe;
                *v = 0.0;
                tau += sigma;
                sum.events += 1;
                *mode = rest_mode(d, kappa, xe, u(tau.min(h)));
                if *mode == Mode::Slip(s) {
                    // cannot keep slipping the same way after stopping (would
                    // need |F| > κ along s, contradicting the reversal):
                    // numerical tie, stay put for this instant
                    *mode = Mode::Stick;
                }
            }
        }
    }
    Err(SimulationError::EventOverflow {
        t: t_abs + tau,
        limit: EVENT_LIMIT,
    })
}
