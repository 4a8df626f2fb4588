//! One classical RK4 step of the state-space model, shared by the
//! fixed-step integrator ([`super::rk4`]), the friction event handling
//! ([`super::coulomb`]) and the stepped-sine rig ([`crate::stepped_sine`]).

use super::law::{Dyn, Law};

/// One classical RK4 step of size `h` from `(x, v)` with `a1 = u0 − f(x, v)`
/// already known, stage inputs `um` (t + h/2) and `u1` (t + h):
///
/// ```text
/// k1 = (v, a1)
/// k2 = f(t+h/2, y + h/2 k1),  k3 = f(t+h/2, y + h/2 k2),  k4 = f(t+h, y + h k3)
/// y₁ = y + h/6 (k1 + 2k2 + 2k3 + k4)
/// ```
#[inline(always)]
pub(crate) fn step<S: Law, D: Law>(
    d: &Dyn<S, D>,
    x: f64,
    v: f64,
    a1: f64,
    h: f64,
    um: f64,
    u1: f64,
) -> (f64, f64) {
    let hh = 0.5 * h;
    let x2 = x + hh * v;
    let v2 = v + hh * a1;
    let a2 = um - d.internal(x2, v2);
    let x3 = x + hh * v2;
    let v3 = v + hh * a2;
    let a3 = um - d.internal(x3, v3);
    let x4 = x + h * v3;
    let v4 = v + h * a3;
    let a4 = u1 - d.internal(x4, v4);
    let h6 = h * (1.0 / 6.0);
    (
        x + h6 * (v + 2.0 * (v2 + v3) + v4),
        v + h6 * (a1 + 2.0 * (a2 + a3) + a4),
    )
}
