//! Power-law force kernels `c · y|y|^μ` (per unit mass) specialised by the
//! kind of exponent, and the monomorphising dispatch of a model onto them.
//!
//! The right-hand side of Eq 32 is evaluated four times per RK4 step, so
//! the exponent kind is resolved *once* (outside the time loop) and every
//! integrator is compiled for each combination:
//!
//! * [`Absent`] — coefficient 0: no work at all;
//! * [`IntLaw`] — integer exponent `n` (|n| ≤ 64): multiplications only
//!   (`y|y|^n = y^{n+1}` for even `n`, `|y| y^n` for odd `n`);
//! * [`RealLaw`] — real exponent: one `powf` per evaluation.
//!
//! `y = 0` returns 0 for every kind (for μ < 0 the product `0 · ∞` would
//! otherwise be NaN; for −1 < μ < 0 the force is continuous with value 0).

use crate::model::NormalisedModel;

/// A power-law force per unit mass, `f(y) = c · y|y|^μ`.
pub(crate) trait Law: Copy + Send + Sync + 'static {
    fn f(&self, y: f64) -> f64;
}

/// No term.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Absent;

impl Law for Absent {
    #[inline(always)]
    fn f(&self, _y: f64) -> f64 {
        0.0
    }
}

/// Integer exponent.
#[derive(Clone, Copy, Debug)]
pub(crate) struct IntLaw {
    pub c: f64,
    pub n: i32,
}

impl Law for IntLaw {
    #[inline(always)]
    fn f(&self, y: f64) -> f64 {
        let c = self.c;
        match self.n {
            0 => c * y,
            1 => c * y * y.abs(),
            2 => c * (y * y) * y,
            3 => {
                let y2 = y * y;
                c * (y2 * y) * y.abs()
            }
            4 => {
                let y2 = y * y;
                c * (y2 * y2) * y
            }
            n if n > 0 => c * y * y.abs().powi(n),
            n => {
                if y == 0.0 {
                    0.0
                } else {
                    c * y * y.abs().powi(n)
                }
            }
        }
    }
}

/// Real (non-integer) exponent.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RealLaw {
    pub c: f64,
    pub mu: f64,
}

impl Law for RealLaw {
    #[inline(always)]
    fn f(&self, y: f64) -> f64 {
        if y == 0.0 {
            0.0
        } else {
            self.c * y * y.abs().powf(self.mu)
        }
    }
}

/// How a term is evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LawKind {
    Absent,
    Int(f64, i32),
    Real(f64, f64),
}

impl LawKind {
    pub(crate) fn of(coefficient: f64, exponent: f64) -> Self {
        if coefficient == 0.0 {
            LawKind::Absent
        } else if exponent.fract() == 0.0 && exponent.abs() <= 64.0 {
            LawKind::Int(coefficient, exponent as i32)
        } else {
            LawKind::Real(coefficient, exponent)
        }
    }
}

/// Mass-normalised dynamics of Eq 32 with the two nonlinear terms as
/// specialised kernels: `x'' = u − (δ x' + α x + S(x) + D(x'))`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dyn<S, D> {
    pub alpha: f64,
    pub delta: f64,
    pub s: S,
    pub d: D,
}

impl<S: Law, D: Law> Dyn<S, D> {
    /// Internal (restoring + dissipative) acceleration
    /// `δ v + α x + β x|x|^ρ + κ v|v|^η`.
    #[inline(always)]
    pub fn internal(&self, x: f64, v: f64) -> f64 {
        (self.alpha * x + self.s.f(x)) + (self.delta * v + self.d.f(v))
    }

    /// Restoring part only, `α x + β x|x|^ρ`.
    #[inline(always)]
    pub fn restoring(&self, x: f64) -> f64 {
        self.alpha * x + self.s.f(x)
    }
}

/// A computation to run on the dynamics, compiled per kernel combination.
pub(crate) trait Visit {
    type Out;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out;
}

macro_rules! with_damping {
    ($alpha:expr, $delta:expr, $s:expr, $dk:expr, $vis:expr) => {
        match $dk {
            LawKind::Absent => $vis.go(Dyn { alpha: $alpha, delta: $delta, s: $s, d: Absent }),
            LawKind::Int(c, n) => $vis.go(Dyn { alpha: $alpha, delta: $delta, s: $s, d: IntLaw { c, n } }),
            LawKind::Real(c, mu) => $vis.go(Dyn { alpha: $alpha, delta: $delta, s: $s, d: RealLaw { c, mu } }),
        }
    };
}

/// Runs `vis` on the model's dynamics. With `drop_damping` the nonlinear
/// damping term is left out (the Coulomb integrators add friction as a
/// mode-dependent constant instead).
pub(crate) fn dispatch<V: Visit>(m: &NormalisedModel, drop_damping: bool, vis: V) -> V::Out {
    let sk = LawKind::of(m.beta, m.rho);
    let dk = if drop_damping { LawKind::Absent } else { LawKind::of(m.kappa, m.eta) };
    let (a, d) = (m.alpha, m.delta);
    match sk {
        LawKind::Absent => with_damping!(a, d, Absent, dk, vis),
        LawKind::Int(c, n) => with_damping!(a, d, IntLaw { c, n }, dk, vis),
        LawKind::Real(c, mu) => with_damping!(a, d, RealLaw { c, mu }, dk, vis),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_agree_with_the_definition() {
        for &y in &[-2.5, -1.0, -0.3, 0.0, 1e-3, 0.7, 3.0] {
            for n in -2..=9 {
                if n < 0 && y == 0.0 {
                    continue;
                }
                let exact = 1.7 * y * (y as f64).abs().powf(n as f64);
                let got = IntLaw { c: 1.7, n }.f(y);
                assert!((got - exact).abs() <= 1e-14 * exact.abs().max(1e-300), "n={n} y={y}");
            }
            let r = RealLaw { c: 0.3, mu: 3.03099 }.f(y);
            assert!((r - 0.3 * y * y.abs().powf(3.03099)).abs() <= 1e-15 * r.abs());
        }
        assert_eq!(RealLaw { c: 1.0, mu: -0.5 }.f(0.0), 0.0);
        assert_eq!(IntLaw { c: 1.0, n: -2 }.f(0.0), 0.0);
        assert_eq!(LawKind::of(0.0, 3.3), LawKind::Absent);
        assert_eq!(LawKind::of(2.0, 4.0), LawKind::Int(2.0, 4));
        assert_eq!(LawKind::of(2.0, 4.0022), LawKind::Real(2.0, 4.0022));
    }
}
