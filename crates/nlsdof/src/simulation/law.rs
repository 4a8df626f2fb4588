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
    pub pow: FastPow,
}

impl RealLaw {
    pub(crate) fn new(c: f64, mu: f64) -> Self {
        Self { c, pow: FastPow::new(mu) }
    }
}

impl Law for RealLaw {
    #[inline(always)]
    fn f(&self, y: f64) -> f64 {
        if y == 0.0 {
            0.0
        } else {
            self.c * y * self.pow.pow(y.abs())
        }
    }
}

/// `y^μ` for a fixed real μ and `y > 0`, inlined and table driven:
///
/// ```text
/// y = 2^k z,  z ∈ [0.6875, 1.375),  z = c_i (1 + r),  |r| < 2^-8
/// log2 y = k + log2 c_i + log2(1 + r)         (128-entry table, degree-6 series)
/// y^μ = 2^{μ log2 y} = 2^{n/128} 2^{r'}       (128-entry table, degree-5 series, |r'| ≤ 1/256)
/// ```
///
/// Relative error below `2e-16 (|μ log2 y| + 8)` (≤ 5e-15 for the physical
/// range |μ log2 y| ≤ 16, e.g. y ∈ [0.06, 16] at μ = 4; checked against
/// `powf` in the tests) for results within 2^±1000; zero, subnormal, non-finite arguments and results
/// outside that range fall back to `powf`. About twice the speed of the C
/// library's correctly rounded `pow`, which dominates the right-hand side
/// of Eq 32 for real exponents.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FastPow {
    pub mu: f64,
    tab: &'static PowTables,
}

struct PowTables {
    /// (1/c_i, log2 c_i)
    log: [(f64, f64); 128],
    /// bits of 2^(j/128)
    exp: [u64; 128],
}

impl std::fmt::Debug for PowTables {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PowTables")
    }
}

const LOG_OFF: u64 = 0x3fe6_0000_0000_0000; // 0.6875
const EXP_SHIFT: f64 = 6755399441055744.0; // 1.5 * 2^52

fn tables() -> &'static PowTables {
    static T: std::sync::OnceLock<PowTables> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let mut log = [(0.0, 0.0); 128];
        for (i, e) in log.iter_mut().enumerate() {
            let lo = f64::from_bits(LOG_OFF + ((i as u64) << 45));
            let hi = f64::from_bits(LOG_OFF + ((i as u64 + 1) << 45));
            let invc = 1.0 / (0.5 * (lo + hi));
            *e = (invc, -invc.log2());
        }
        let mut exp = [0u64; 128];
        for (j, e) in exp.iter_mut().enumerate() {
            *e = (j as f64 / 128.0).exp2().to_bits();
        }
        PowTables { log, exp }
    })
}

impl FastPow {
    pub(crate) fn new(mu: f64) -> Self {
        Self { mu, tab: tables() }
    }

    #[inline(always)]
    pub(crate) fn pow(&self, y: f64) -> f64 {
        // log2(1 + r) = r/ln2 (1 − r/2 + r²/3 − …)
        const A1: f64 = std::f64::consts::LOG2_E;
        const A2: f64 = -std::f64::consts::LOG2_E / 2.0;
        const A3: f64 = std::f64::consts::LOG2_E / 3.0;
        const A4: f64 = -std::f64::consts::LOG2_E / 4.0;
        const A5: f64 = std::f64::consts::LOG2_E / 5.0;
        const A6: f64 = -std::f64::consts::LOG2_E / 6.0;
        const LN2: f64 = std::f64::consts::LN_2;
        let ix = y.to_bits();
        // not a positive normal number
        if ix.wrapping_sub(0x0010_0000_0000_0000) >= 0x7fe0_0000_0000_0000 {
            return y.powf(self.mu);
        }
        let tmp = ix.wrapping_sub(LOG_OFF);
        let i = ((tmp >> 45) & 127) as usize;
        let k = ((tmp as i64) >> 52) as f64;
        let z = f64::from_bits(ix.wrapping_sub(tmp & (0xfffu64 << 52)));
        let (invc, logc) = self.tab.log[i];
        let r = z * invc - 1.0;
        let r2 = r * r;
        let p = r * A1 + r2 * ((A2 + r * A3) + r2 * ((A4 + r * A5) + r2 * A6));
        let l = (k + logc) + p;
        let e = self.mu * l;
        if !(e.abs() < 1000.0) {
            return y.powf(self.mu);
        }
        let kd = e * 128.0 + EXP_SHIFT;
        let n = (kd.to_bits() as i64).wrapping_sub(EXP_SHIFT.to_bits() as i64);
        let kd = kd - EXP_SHIFT;
        let t = (e - kd * (1.0 / 128.0)) * LN2; // |t| ≤ ln2/256
        let j = (n & 127) as usize;
        let scale = f64::from_bits(self.tab.exp[j].wrapping_add(((n >> 7) as u64) << 52));
        let t2 = t * t;
        let q = t + t2 * ((0.5 + t * (1.0 / 6.0)) + t2 * ((1.0 / 24.0) + t * (1.0 / 120.0)));
        scale + scale * q
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
            LawKind::Real(c, mu) => $vis.go(Dyn { alpha: $alpha, delta: $delta, s: $s, d: RealLaw::new(c, mu) }),
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
        LawKind::Real(c, mu) => with_damping!(a, d, RealLaw::new(c, mu), dk, vis),
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
            let r = RealLaw::new(0.3, 3.03099).f(y);
            assert!((r - 0.3 * y * y.abs().powf(3.03099)).abs() <= 1e-14 * r.abs());
        }
        assert_eq!(RealLaw::new(1.0, -0.5).f(0.0), 0.0);
        assert_eq!(IntLaw { c: 1.0, n: -2 }.f(0.0), 0.0);
        assert_eq!(LawKind::of(0.0, 3.3), LawKind::Absent);
        assert_eq!(LawKind::of(2.0, 4.0), LawKind::Int(2.0, 4));
        assert_eq!(LawKind::of(2.0, 4.0022), LawKind::Real(2.0, 4.0022));
    }

    /// Independent oracle: the C library's `pow`. Random arguments over 40
    /// decades and exponents over the admissible range (μ > −3).
    #[test]
    fn fast_pow_matches_powf() {
        let mut s: u64 = 12345;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst = 0.0f64;
        for &mu in &[4.0022, 3.03099, -0.5, -2.9, 0.37, 1.5, 7.25, 25.3, -1.0, 2.0] {
            let p = FastPow::new(mu);
            for _ in 0..200_000 {
                let y = 10f64.powf(40.0 * rnd() - 20.0);
                let exact = y.powf(mu);
                let got = p.pow(y);
                if exact.is_finite() && exact > 1e-290 && exact < 1e290 {
                    let rel = ((got - exact) / exact).abs();
                    let bound = 2e-16 * ((mu * y.log2()).abs() + 8.0);
                    worst = worst.max(rel / bound);
                    assert!(rel < bound, "mu={mu} y={y}: {got} vs {exact} ({rel:e} > {bound:e})");
                } else {
                    assert!(got == exact || (got - exact).abs() <= 1e-14 * exact.abs(), "mu={mu} y={y}");
                }
            }
            // table boundaries and exact powers of two
            for e in -60..60 {
                for &m in &[1.0, 0.6875, 1.375, 0.9999999999, 1.0000000001, 0.75] {
                    let y = m * 2f64.powi(e);
                    let rel = ((p.pow(y) - y.powf(mu)) / y.powf(mu)).abs();
                    assert!(rel < 2e-16 * ((mu * y.log2()).abs() + 8.0), "mu={mu} y={y}: {rel:e}");
                }
            }
        }
        for y in [0.0, f64::MIN_POSITIVE / 4.0, f64::INFINITY, f64::NAN, 1e300] {
            let (a, b) = (FastPow::new(3.3).pow(y), y.powf(3.3));
            assert!(a == b || (a.is_nan() && b.is_nan()), "y={y}: {a} vs {b}");
        }
        println!("fast pow worst error / bound = {worst}");
    }
}
