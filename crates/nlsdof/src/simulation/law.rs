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

/// How `a·b + c` is evaluated in the hot loops: two roundings ([`NoFma`]),
/// or one fused instruction ([`HwFma`], only inside functions compiled
/// with the `fma` target feature after a run-time CPU check).
pub(crate) trait MulAdd: Copy {
    fn madd(a: f64, b: f64, c: f64) -> f64;
}

#[derive(Clone, Copy)]
pub(crate) struct NoFma;

impl MulAdd for NoFma {
    #[inline(always)]
    fn madd(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

#[derive(Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct HwFma;

impl MulAdd for HwFma {
    #[inline(always)]
    fn madd(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

/// A power-law force per unit mass, `f(y) = c · y|y|^μ`.
///
/// `make_ref`/`f_near` let an integrator take the power off its critical
/// path: `make_ref(ŷ)` evaluates the power at a *predicted* argument ŷ
/// early (its latency overlaps other work), and `f_near(y, r)` then gets
/// `f(y)` for the actual `y ≈ ŷ` from a short binomial series
/// `|y|^μ = |ŷ|^μ (1 + ε)^μ`, `ε = y/ŷ − 1` — or directly when `y` is not
/// close enough. Kernels without a transcendental have `SPECULATE = false`.
pub(crate) trait Law: Copy + Send + Sync + 'static {
    /// Whether `f_near` is cheaper than `f` (real exponents).
    const SPECULATE: bool = false;
    type Ref: Copy + Default;
    fn f(&self, y: f64) -> f64;
    #[inline(always)]
    fn make_ref(&self, _y: f64) -> Self::Ref {
        Self::Ref::default()
    }
    #[inline(always)]
    fn f_near<M: MulAdd>(&self, y: f64, _r: &Self::Ref) -> f64 {
        self.f(y)
    }
    /// Two references at once (lane-wise for real exponents).
    #[inline(always)]
    fn make_ref2<M: MulAdd>(&self, y: [f64; 2]) -> [Self::Ref; 2] {
        [self.make_ref(y[0]), self.make_ref(y[1])]
    }
    /// The real exponent and its power evaluator (real kernels only).
    #[inline(always)]
    fn fast_pow(&self) -> Option<FastPow> {
        None
    }
    /// Reference from a power `|y|^μ` and `1/y` computed elsewhere.
    #[inline(always)]
    fn ref_from(&self, y: f64, _pow: f64, _inv: f64) -> Self::Ref {
        self.make_ref(y)
    }
}

/// No term.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Absent;

impl Law for Absent {
    type Ref = ();
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
    type Ref = ();
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
    /// binomial coefficients C(μ, k), k = 2..4, of (1 + ε)^μ
    binom: [f64; 3],
    /// |ε| up to which the degree-4 series is exact to ~1e-16
    eps_max: f64,
}

/// A pre-evaluated power at a predicted argument: `(ŷ, 1/ŷ, c |ŷ|^μ)`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PowRef {
    inv: f64,
    cp: f64,
}

impl RealLaw {
    pub(crate) fn new(c: f64, mu: f64) -> Self {
        let mut binom = [0.0; 3];
        let mut b = mu; // C(μ, 1)
        for (k, slot) in (2..=4).zip(binom.iter_mut()) {
            b *= (mu - (k - 1) as f64) / k as f64;
            *slot = b;
        }
        let c5 = (b * (mu - 4.0) / 5.0).abs();
        let c6 = (c5 * (mu - 5.0) / 6.0).abs();
        // truncation error ≈ |C(μ,5)| ε⁵ + |C(μ,6)| ε⁶ ≤ 2e-17
        let mut eps_max: f64 = 0.02;
        while c5 * eps_max.powi(5) + c6 * eps_max.powi(6) > 2e-17 {
            eps_max *= 0.9;
        }
        Self {
            c,
            pow: FastPow::new(mu),
            binom,
            eps_max,
        }
    }
}

impl Law for RealLaw {
    const SPECULATE: bool = true;
    type Ref = PowRef;

    #[inline(always)]
    fn f(&self, y: f64) -> f64 {
        if y == 0.0 {
            0.0
        } else {
            self.c * y * self.pow.pow(y.abs())
        }
    }

    #[inline(always)]
    fn make_ref(&self, y: f64) -> PowRef {
        // y = 0 or non-finite: inv is ±inf/NaN and f_near falls back
        PowRef {
            inv: 1.0 / y,
            cp: self.c * self.pow.pow(y.abs()),
        }
    }

    #[inline(always)]
    fn f_near<M: MulAdd>(&self, y: f64, r: &PowRef) -> f64 {
        let e = M::madd(y, r.inv, -1.0);
        if e.abs() <= self.eps_max {
            let [c2, c3, c4] = self.binom;
            let e2 = e * e;
            let q = M::madd(
                e2,
                M::madd(e2, c4, M::madd(e, c3, c2)),
                M::madd(e, self.pow.mu, 1.0),
            );
            y * r.cp * q
        } else {
            self.f_cold(y)
        }
    }

    #[inline(always)]
    fn fast_pow(&self) -> Option<FastPow> {
        Some(self.pow)
    }

    #[inline(always)]
    fn ref_from(&self, _y: f64, pow: f64, inv: f64) -> PowRef {
        PowRef {
            inv,
            cp: self.c * pow,
        }
    }

    #[inline(always)]
    fn make_ref2<M: MulAdd>(&self, y: [f64; 2]) -> [PowRef; 2] {
        let p = self.pow.pow2::<M>([y[0].abs(), y[1].abs()]);
        [
            PowRef {
                inv: 1.0 / y[0],
                cp: self.c * p[0],
            },
            PowRef {
                inv: 1.0 / y[1],
                cp: self.c * p[1],
            },
        ]
    }
}

impl RealLaw {
    /// Direct evaluation kept out of line so the hot loops stay compact.
    #[cold]
    #[inline(never)]
    fn f_cold(&self, y: f64) -> f64 {
        self.f(y)
    }
}

/// `y^μ` for a fixed real μ and `y > 0`, inlined and table driven:
///
/// ```text
/// y = 2^k z,  z ∈ [0.6875, 1.375),  z = c_i (1 + r),  |r| < 2^-7.9
/// log2 y = k + log2 c_i + log2(1 + r)         (128-entry table, degree-6 series)
/// y^μ = 2^{μ log2 y} = 2^{n/128} 2^{r'}       (128-entry table, degree-5 series, |r'| ≤ 1/256)
/// ```
///
/// Relative error below `3e-16 (|μ log2 y| + 8)` (≤ 7e-15 for the physical
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
    /// (c_i, 1/c_i, log2 c_i); c_i has few significant bits so that
    /// `z − c_i` is exact (Sterbenz) and `r = (z − c_i)/c_i` carries only a
    /// relative rounding error
    log: [(f64, f64, f64); 128],
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
        let mut log = [(0.0, 0.0, 0.0); 128];
        for (i, e) in log.iter_mut().enumerate() {
            let lo = f64::from_bits(LOG_OFF + ((i as u64) << 45));
            let hi = f64::from_bits(LOG_OFF + ((i as u64 + 1) << 45));
            // centre of the sub-interval, rounded to 20 significant bits
            let c = f64::from_bits((0.5 * (lo + hi)).to_bits() & !((1u64 << 32) - 1));
            *e = (c, 1.0 / c, c.log2());
        }
        let mut exp = [0u64; 128];
        for (j, e) in exp.iter_mut().enumerate() {
            *e = (j as f64 / 128.0).exp2().to_bits();
        }
        PowTables { log, exp }
    })
}

/// `[y0^a, y1^a, y2^b, y3^b]` for the exponents of `pa` and `pb`, written
/// lane-wise (4-wide SIMD where available); identical to [`FastPow::pow`].
#[inline(always)]
pub(crate) fn pow4<M: MulAdd>(pa: &FastPow, pb: &FastPow, y: [f64; 4]) -> [f64; 4] {
    const A1: f64 = std::f64::consts::LOG2_E;
    const A2: f64 = -std::f64::consts::LOG2_E / 2.0;
    const A3: f64 = std::f64::consts::LOG2_E / 3.0;
    const A4: f64 = -std::f64::consts::LOG2_E / 4.0;
    const A5: f64 = std::f64::consts::LOG2_E / 5.0;
    const A6: f64 = -std::f64::consts::LOG2_E / 6.0;
    const LN2: f64 = std::f64::consts::LN_2;
    let tab = pa.tab;
    let mu = [pa.mu, pa.mu, pb.mu, pb.mu];
    let ix = y.map(f64::to_bits);
    let bad = ix.iter().fold(false, |b, &i| {
        b | (i.wrapping_sub(0x0010_0000_0000_0000) >= 0x7fe0_0000_0000_0000)
    });
    if bad {
        return pow4_cold(pa, pb, y);
    }
    let tmp = ix.map(|i| i.wrapping_sub(LOG_OFF));
    let lt = tmp.map(|t| tab.log[((t >> 45) & 127) as usize]);
    let mut e = [0.0; 4];
    for l in 0..4 {
        let k = ((tmp[l] as i64) >> 52) as f64;
        let z = f64::from_bits(ix[l].wrapping_sub(tmp[l] & (0xfffu64 << 52)));
        let r = (z - lt[l].0) * lt[l].1;
        let r2 = r * r;
        let p = M::madd(
            r,
            A1,
            r2 * (M::madd(r, A3, A2) + r2 * (M::madd(r, A5, A4) + r2 * A6)),
        );
        e[l] = mu[l] * ((k + lt[l].2) + p);
    }
    if !e.iter().all(|v| v.abs() < 1000.0) {
        return pow4_cold(pa, pb, y);
    }
    let mut out = [0.0; 4];
    for l in 0..4 {
        let s = e[l] * 128.0 + EXP_SHIFT;
        let n = (s.to_bits() as i64).wrapping_sub(EXP_SHIFT.to_bits() as i64);
        let kd = s - EXP_SHIFT;
        let scale =
            f64::from_bits(tab.exp[(n & 127) as usize].wrapping_add(((n >> 7) as u64) << 52));
        let t = (e[l] - kd * (1.0 / 128.0)) * LN2;
        let t2 = t * t;
        let q = M::madd(
            t2,
            M::madd(t, 1.0 / 6.0, 0.5) + t2 * M::madd(t, 1.0 / 120.0, 1.0 / 24.0),
            t,
        );
        out[l] = M::madd(scale, q, scale);
    }
    out
}

#[cold]
#[inline(never)]
fn pow4_cold(pa: &FastPow, pb: &FastPow, y: [f64; 4]) -> [f64; 4] {
    [pa.pow(y[0]), pa.pow(y[1]), pb.pow(y[2]), pb.pow(y[3])]
}

#[cold]
#[inline(never)]
fn powf_cold(y: f64, mu: f64) -> f64 {
    y.powf(mu)
}

impl FastPow {
    pub(crate) fn new(mu: f64) -> Self {
        Self { mu, tab: tables() }
    }

    /// [`FastPow::pow`] of two arguments, written lane-wise so that the
    /// arithmetic runs as 2-wide SIMD (SSE2); identical results.
    #[inline(always)]
    pub(crate) fn pow2<M: MulAdd>(&self, y: [f64; 2]) -> [f64; 2] {
        const A1: f64 = std::f64::consts::LOG2_E;
        const A2: f64 = -std::f64::consts::LOG2_E / 2.0;
        const A3: f64 = std::f64::consts::LOG2_E / 3.0;
        const A4: f64 = -std::f64::consts::LOG2_E / 4.0;
        const A5: f64 = std::f64::consts::LOG2_E / 5.0;
        const A6: f64 = -std::f64::consts::LOG2_E / 6.0;
        const LN2: f64 = std::f64::consts::LN_2;
        let ix = [y[0].to_bits(), y[1].to_bits()];
        if ix[0].wrapping_sub(0x0010_0000_0000_0000) >= 0x7fe0_0000_0000_0000
            || ix[1].wrapping_sub(0x0010_0000_0000_0000) >= 0x7fe0_0000_0000_0000
        {
            return [self.pow(y[0]), self.pow(y[1])];
        }
        let tmp = [ix[0].wrapping_sub(LOG_OFF), ix[1].wrapping_sub(LOG_OFF)];
        let t0 = self.tab.log[((tmp[0] >> 45) & 127) as usize];
        let t1 = self.tab.log[((tmp[1] >> 45) & 127) as usize];
        let cc = [t0.0, t1.0];
        let invc = [t0.1, t1.1];
        let logc = [t0.2, t1.2];
        let k = [
            ((tmp[0] as i64) >> 52) as f64,
            ((tmp[1] as i64) >> 52) as f64,
        ];
        let z = [
            f64::from_bits(ix[0].wrapping_sub(tmp[0] & (0xfffu64 << 52))),
            f64::from_bits(ix[1].wrapping_sub(tmp[1] & (0xfffu64 << 52))),
        ];
        let mut e = [0.0; 2];
        for l in 0..2 {
            let r = (z[l] - cc[l]) * invc[l];
            let r2 = r * r;
            let p = M::madd(
                r,
                A1,
                r2 * (M::madd(r, A3, A2) + r2 * (M::madd(r, A5, A4) + r2 * A6)),
            );
            e[l] = self.mu * ((k[l] + logc[l]) + p);
        }
        if !(e[0].abs() < 1000.0 && e[1].abs() < 1000.0) {
            return [self.pow(y[0]), self.pow(y[1])];
        }
        let mut out = [0.0; 2];
        let mut kd = [0.0; 2];
        let mut nn = [0i64; 2];
        for l in 0..2 {
            let s = e[l] * 128.0 + EXP_SHIFT;
            nn[l] = (s.to_bits() as i64).wrapping_sub(EXP_SHIFT.to_bits() as i64);
            kd[l] = s - EXP_SHIFT;
        }
        let scale = [
            f64::from_bits(
                self.tab.exp[(nn[0] & 127) as usize].wrapping_add(((nn[0] >> 7) as u64) << 52),
            ),
            f64::from_bits(
                self.tab.exp[(nn[1] & 127) as usize].wrapping_add(((nn[1] >> 7) as u64) << 52),
            ),
        ];
        for l in 0..2 {
            let t = (e[l] - kd[l] * (1.0 / 128.0)) * LN2;
            let t2 = t * t;
            let q = M::madd(
                t2,
                M::madd(t, 1.0 / 6.0, 0.5) + t2 * M::madd(t, 1.0 / 120.0, 1.0 / 24.0),
                t,
            );
            out[l] = M::madd(scale[l], q, scale[l]);
        }
        out
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
            return powf_cold(y, self.mu);
        }
        let tmp = ix.wrapping_sub(LOG_OFF);
        let i = ((tmp >> 45) & 127) as usize;
        let k = ((tmp as i64) >> 52) as f64;
        let z = f64::from_bits(ix.wrapping_sub(tmp & (0xfffu64 << 52)));
        let (c, invc, logc) = self.tab.log[i];
        let r = (z - c) * invc;
        let r2 = r * r;
        let p = r * A1 + r2 * ((A2 + r * A3) + r2 * ((A4 + r * A5) + r2 * A6));
        let l = (k + logc) + p;
        let e = self.mu * l;
        if e.abs() >= 1000.0 || e.is_nan() {
            return powf_cold(y, self.mu);
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

    /// [`Dyn::internal`] with the power laws evaluated near pre-evaluated
    /// references (see [`Law::make_ref`]).
    #[inline(always)]
    pub fn internal_near<M: MulAdd>(&self, x: f64, v: f64, rx: &S::Ref, rv: &D::Ref) -> f64 {
        M::madd(self.alpha, x, self.s.f_near::<M>(x, rx))
            + M::madd(self.delta, v, self.d.f_near::<M>(v, rv))
    }

    /// References at two predicted states (middle, end): four powers
    /// evaluated lane-wise in one go when both laws are real.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    pub fn make_refs<M: MulAdd>(
        &self,
        xm: f64,
        xe: f64,
        vm: f64,
        ve: f64,
    ) -> ((S::Ref, D::Ref), (S::Ref, D::Ref)) {
        if let (Some(ps), Some(pd)) = (self.s.fast_pow(), self.d.fast_pow()) {
            let y = [xm, xe, vm, ve];
            let p = pow4::<M>(&ps, &pd, y.map(f64::abs));
            let inv = y.map(|v| 1.0 / v);
            (
                (
                    self.s.ref_from(xm, p[0], inv[0]),
                    self.d.ref_from(vm, p[2], inv[2]),
                ),
                (
                    self.s.ref_from(xe, p[1], inv[1]),
                    self.d.ref_from(ve, p[3], inv[3]),
                ),
            )
        } else {
            let [sm, se] = self.s.make_ref2::<M>([xm, xe]);
            let [dm, de] = self.d.make_ref2::<M>([vm, ve]);
            ((sm, dm), (se, de))
        }
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
            LawKind::Absent => $vis.go(Dyn {
                alpha: $alpha,
                delta: $delta,
                s: $s,
                d: Absent,
            }),
            LawKind::Int(c, n) => $vis.go(Dyn {
                alpha: $alpha,
                delta: $delta,
                s: $s,
                d: IntLaw { c, n },
            }),
            LawKind::Real(c, mu) => $vis.go(Dyn {
                alpha: $alpha,
                delta: $delta,
                s: $s,
                d: RealLaw::new(c, mu),
            }),
        }
    };
}

/// Runs `vis` on the model's dynamics. With `drop_damping` the nonlinear
/// damping term is left out (the Coulomb integrators add friction as a
/// mode-dependent constant instead).
pub(crate) fn dispatch<V: Visit>(m: &NormalisedModel, drop_damping: bool, vis: V) -> V::Out {
    let sk = LawKind::of(m.beta, m.rho);
    let dk = if drop_damping {
        LawKind::Absent
    } else {
        LawKind::of(m.kappa, m.eta)
    };
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
        for &y in &[-2.5f64, -1.0, -0.3, 0.0, 1e-3, 0.7, 3.0] {
            for n in -2..=9 {
                if n < 0 && y == 0.0 {
                    continue;
                }
                let exact = 1.7 * y * y.abs().powf(n as f64);
                let got = IntLaw { c: 1.7, n }.f(y);
                assert!(
                    (got - exact).abs() <= 1e-14 * exact.abs().max(1e-300),
                    "n={n} y={y}"
                );
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

    /// The series continuation `f_near` equals the direct evaluation near the
    /// reference and falls back far from it, at zero and at non-finite refs.
    #[test]
    fn near_evaluation_matches_direct() {
        for &mu in &[4.0022, 3.03099, -0.5, 0.37, 7.25, 25.3] {
            let l = RealLaw::new(1.7, mu);
            for &y0 in &[-3.0, -0.02, 1e-5, 0.4, 12.0] {
                let r = l.make_ref(y0);
                for &e in &[0.0, 1e-6, -3e-4, 2e-3, 0.019, -0.05, 0.3, -1.5] {
                    let y = y0 * (1.0 + e);
                    let (a, b) = (l.f_near::<NoFma>(y, &r), 1.7 * y * y.abs().powf(mu));
                    assert!(
                        (a - b).abs() <= 3e-15 * b.abs() * (1.0 + (mu * y.abs().log2()).abs()),
                        "mu={mu} y0={y0} e={e}: {a} vs {b}"
                    );
                }
            }
            assert_eq!(l.f_near::<NoFma>(0.0, &l.make_ref(0.0)), 0.0);
            assert_eq!(l.f_near::<NoFma>(0.5, &l.make_ref(0.0)), l.f(0.5));
            assert_eq!(l.f_near::<NoFma>(0.5, &l.make_ref(f64::NAN)), l.f(0.5));
        }
    }

    /// Independent oracle: the C library's `pow`. Random arguments over 40
    /// decades and exponents over the admissible range (μ > −3).
    #[test]
    fn fast_pow_matches_powf() {
        let mut s: u64 = 12345;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst = 0.0f64;
        for &mu in &[
            4.0022, 3.03099, -0.5, -2.9, 0.37, 1.5, 7.25, 25.3, -1.0, 2.0,
        ] {
            let p = FastPow::new(mu);
            for _ in 0..200_000 {
                let y = 10f64.powf(40.0 * rnd() - 20.0);
                let exact = y.powf(mu);
                let got = p.pow(y);
                if exact.is_finite() && exact > 1e-290 && exact < 1e290 {
                    let rel = ((got - exact) / exact).abs();
                    let bound = 3e-16 * ((mu * y.log2()).abs() + 8.0);
                    worst = worst.max(rel / bound);
                    assert!(
                        rel < bound,
                        "mu={mu} y={y}: {got} vs {exact} ({rel:e} > {bound:e})"
                    );
                } else {
                    let bound = 3e-16 * ((mu * y.log2()).abs() + 8.0);
                    assert!(
                        got == exact || (got - exact).abs() <= bound * exact.abs(),
                        "mu={mu} y={y}: {got} vs {exact}"
                    );
                }
            }
            // table boundaries and exact powers of two
            for e in -60..60 {
                for &m in &[1.0, 0.6875, 1.375, 0.9999999999, 1.0000000001, 0.75] {
                    let y = m * 2f64.powi(e);
                    if !y.powf(mu).is_normal() {
                        assert_eq!(p.pow(y), y.powf(mu));
                        continue;
                    }
                    let rel = ((p.pow(y) - y.powf(mu)) / y.powf(mu)).abs();
                    assert!(
                        rel < 3e-16 * ((mu * y.log2()).abs() + 8.0),
                        "mu={mu} y={y}: {rel:e}"
                    );
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
