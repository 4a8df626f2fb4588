//! All positive roots of a sum of real powers
//!
//! ```text
//! f(x) = Σᵢ cᵢ x^{eᵢ},   x > 0,  eᵢ ∈ ℝ distinct
//! ```
//!
//! (a "generalised polynomial"). With `t = ln x` it is the exponential sum
//! `F(t) = Σ cᵢ e^{eᵢ t}`. Two classical facts make root isolation exact,
//! with no sampling grid:
//!
//! 1. **Descartes' rule for generalised polynomials** (Laguerre): with the
//!    terms sorted by exponent, the number of positive roots (with
//!    multiplicity) is at most the number of sign changes of the coefficient
//!    sequence. Zero sign changes ⇒ no root; one ⇒ exactly one root.
//! 2. **Rolle recursion**: `e^{−e₁t} F(t)` has the same roots as `F`, and its
//!    derivative `F₁(t) = Σ_{i≥2} cᵢ (eᵢ − e₁) e^{(eᵢ−e₁)t}` has one term
//!    fewer. Between consecutive roots of `F₁`, `e^{−e₁t}F` is monotone, so
//!    each such interval holds at most one root of `F`, found by a sign test
//!    and a bracketing solver. Recursing until Descartes' rule settles the
//!    count isolates every root, however close two roots are.
//!
//! All roots lie in `[T_lo, T_hi]`: beyond `T_hi` the term with the largest
//! exponent exceeds the sum of all others (`|c_n| e^{e_n t} > (n−1)|cᵢ| e^{eᵢ t}`
//! for every `i`), and symmetrically below `T_lo`.
//!
//! Written by hand because no maintained crate isolates roots of sums of
//! *real* powers (polynomial root finders need integer exponents).
//!
//! Evaluation is done in a sign-preserving scaled form
//! `F(t) e^{−M(t)}` with `M(t) = maxᵢ (ln|cᵢ| + eᵢ t)`, so no term overflows.
//! Callers that know a more accurate (unexpanded) formula for the top levels
//! pass it in: expanding a product can cancel digits near a root.
//!
//! **Warm start** ([`PowerSum::roots_warm_in`]): along a sweep the roots of
//! every level move little from one frequency to the next. Given the
//! previous frequency's roots per level as hints, each level is isolated
//! exactly as above (the next level's roots split the range into monotone
//! intervals, a sign change at the ends of one proves a single root in
//! it), and only the polishing changes: safeguarded Newton from the hint
//! inside the bracket (the derivative is analytic), with Brent's method on
//! the shrunk bracket when a step leaves it or stops converging
//! quadratically, and Brent from the bracket ends where no hint lies in
//! it. The bracket is verified either way, so the roots are those of the
//! cold isolation to its tolerance.

/// A sum of real powers, terms sorted by increasing exponent, equal exponents
/// merged, zero coefficients dropped.
#[derive(Debug, Clone, PartialEq)]
pub struct PowerSum {
    exponents: Terms,
    coefficients: Terms,
    log_abs: Terms,
}

/// The terms' numbers, inline up to [`INLINE_TERMS`] (the response
/// equation has at most 6 terms; its fold search builds and drops several
/// sums, and their reduced derivatives, at every step of a sweep).
type Terms = smallvec::SmallVec<[f64; INLINE_TERMS]>;

/// Terms a [`PowerSum`] holds without a heap allocation.
const INLINE_TERMS: usize = 8;

/// A function used for sign tests and root polishing in place of the
/// expanded sum (same sign as the sum for every `t`).
pub type Evaluator<'a> = &'a dyn Fn(f64) -> f64;

/// An [`Evaluator`] with its derivative in `t`: `(f(t), f′(t))`, where
/// `f(t)` is bit for bit the value of the plain evaluator it goes with
/// (so the warm isolation takes the same sign decisions as the cold one).
pub type EvaluatorWithSlope<'a> = &'a dyn Fn(f64) -> (f64, f64);

/// Counts one evaluation of kind `k` of the isolation, in builds with
/// `RUSTFLAGS="--cfg nlsdof_count"` only (nothing in ordinary builds):
/// `0` top level, `1` level 1, `2` deeper levels (scaled sums), `3` an
/// isolation; per Rolle level `l` (0 = roots) at `4 + 3l`: polishes from a
/// hint, polishes without one (Brent), Newton runs that fell back to
/// Brent; `22`–`24` why Newton fell back (step out of the bracket, at the
/// rounding floor, slow). Printed to stderr at process exit.
#[inline(always)]
#[allow(unused_variables, unexpected_cfgs)]
pub(crate) fn count(k: usize) {
    #[cfg(nlsdof_count)]
    {
        use std::sync::atomic::{AtomicU64, Ordering};
        #[allow(clippy::declare_interior_mutable_const)]
        const ZERO: AtomicU64 = AtomicU64::new(0);
        static COUNTS: [AtomicU64; 26] = [ZERO; 26];
        extern "C" fn dump() {
            let c: Vec<u64> = COUNTS.iter().map(|c| c.load(Ordering::Relaxed)).collect();
            eprintln!(
                "nlsdof_count: isolations {} evaluations top {} level1 {} deeper {} \
                 (per isolation {:.1})",
                c[3],
                c[0],
                c[1],
                c[2],
                (c[0] + c[1] + c[2]) as f64 / c[3].max(1) as f64
            );
            eprintln!(
                "nlsdof_count: fallbacks: out of bracket {}, at floor {}, slow {}",
                c[22], c[23], c[24]
            );
            for l in 0..5 {
                eprintln!(
                    "nlsdof_count: level {l}: polished from a hint {}, without {}, fell back {}",
                    c[4 + 3 * l],
                    c[5 + 3 * l],
                    c[6 + 3 * l]
                );
            }
        }
        #[used]
        #[link_section = ".fini_array"]
        static DUMP: extern "C" fn() = dump;
        COUNTS[k].fetch_add(1, Ordering::Relaxed);
    }
}

/// `true` in counting builds (see [`count`]) run with `NLSDOF_COLD` set:
/// the fold search then isolates cold, to measure the warm start against.
#[inline(always)]
#[allow(unexpected_cfgs)]
pub(crate) fn cold_requested() -> bool {
    #[cfg(nlsdof_count)]
    {
        std::env::var_os("NLSDOF_COLD").is_some()
    }
    #[cfg(not(nlsdof_count))]
    {
        false
    }
}

/// `rows` made `n` empty rows, keeping the memory of those it had (the
/// fold search refills the same rows at every sample).
pub(crate) fn clear_rows(rows: &mut Vec<Vec<f64>>, n: usize) {
    rows.resize_with(n, Vec::new);
    rows.iter_mut().for_each(Vec::clear);
}

impl PowerSum {
    /// Builds `Σ c x^e` from `(exponent, coefficient)` pairs. Non-finite
    /// entries are the caller's responsibility (checked in debug builds).
    pub fn new(terms: impl IntoIterator<Item = (f64, f64)>) -> Self {
        let mut v: Vec<(f64, f64)> = terms.into_iter().collect();
        debug_assert!(v.iter().all(|(e, c)| e.is_finite() && c.is_finite()));
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let n = v.len();
        Self::from_sorted(v, n)
    }

    /// From terms sorted by exponent: equal exponents merged in order, zero
    /// coefficients dropped.
    fn from_sorted(terms: impl IntoIterator<Item = (f64, f64)>, capacity: usize) -> Self {
        let mut exponents = Terms::with_capacity(capacity);
        let mut coefficients = Terms::with_capacity(capacity);
        for (e, c) in terms {
            if exponents.last() == Some(&e) {
                *coefficients.last_mut().unwrap() += c;
                continue;
            }
            exponents.push(e);
            coefficients.push(c);
        }
        let mut i = 0;
        while i < exponents.len() {
            if coefficients[i] == 0.0 {
                exponents.remove(i);
                coefficients.remove(i);
            } else {
                i += 1;
            }
        }
        let log_abs = coefficients.iter().map(|c| c.abs().ln()).collect();
        Self {
            exponents,
            coefficients,
            log_abs,
        }
    }

    /// Number of (non-zero) terms.
    pub fn len(&self) -> usize {
        self.exponents.len()
    }

    /// `true` if every coefficient is zero.
    pub fn is_empty(&self) -> bool {
        self.exponents.is_empty()
    }

    /// Sorted exponents.
    pub fn exponents(&self) -> &[f64] {
        &self.exponents
    }

    /// Coefficients in exponent order.
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// Sign changes of the coefficient sequence: an upper bound on the
    /// number of positive roots (generalised Descartes rule).
    pub(crate) fn sign_changes(&self) -> usize {
        self.coefficients
            .windows(2)
            .filter(|w| (w[0] > 0.0) != (w[1] > 0.0))
            .count()
    }

    /// Sign of `f` as `x → 0⁺` (`t → −∞`) and as `x → ∞`.
    pub(crate) fn asymptotic_signs(&self) -> (f64, f64) {
        match (self.coefficients.first(), self.coefficients.last()) {
            (Some(a), Some(b)) => (a.signum(), b.signum()),
            _ => (0.0, 0.0),
        }
    }

    /// `f(e^t) · e^{−M(t)}`, `M(t) = maxᵢ(ln|cᵢ| + eᵢt)`: same sign as `f`,
    /// magnitude in `[…, n]`, never overflows.
    pub(crate) fn eval_scaled(&self, t: f64) -> f64 {
        let mut m = f64::NEG_INFINITY;
        for (l, e) in self.log_abs.iter().zip(&self.exponents) {
            m = m.max(l + e * t);
        }
        let mut s = 0.0;
        for ((l, e), c) in self
            .log_abs
            .iter()
            .zip(&self.exponents)
            .zip(&self.coefficients)
        {
            s += c.signum() * (l + e * t - m).exp();
        }
        s
    }

    /// [`Self::eval_scaled`] (the same value, bit for bit) and its
    /// derivative in `t`: `d/dt [F e^{−M}] = Σ cᵢ (eᵢ − e_k) e^{ln|cᵢ| + eᵢt − M}`,
    /// `e_k` the exponent of the largest term (the slope of `M`).
    pub(crate) fn eval_scaled_with_slope(&self, t: f64) -> (f64, f64) {
        let mut m = f64::NEG_INFINITY;
        let mut e_k = 0.0;
        for (l, e) in self.log_abs.iter().zip(&self.exponents) {
            let v = l + e * t;
            if v > m {
                e_k = *e;
            }
            m = m.max(v);
        }
        let (mut s, mut ds) = (0.0, 0.0);
        for ((l, e), c) in self
            .log_abs
            .iter()
            .zip(&self.exponents)
            .zip(&self.coefficients)
        {
            let term = c.signum() * (l + e * t - m).exp();
            s += term;
            ds += (e - e_k) * term;
        }
        (s, ds)
    }

    /// Plain evaluation `Σ cᵢ x^{eᵢ}` (may overflow for extreme `x`).
    pub fn eval(&self, x: f64) -> f64 {
        self.exponents
            .iter()
            .zip(&self.coefficients)
            .map(|(e, c)| c * x.powf(*e))
            .sum()
    }

    /// `d/dt [e^{−e₁ t} F(t)]` as a power sum in `x` (exponents shifted by
    /// `−e₁`): one term fewer, roots interlace those of `F` (Rolle).
    pub(crate) fn reduced_derivative(&self) -> PowerSum {
        if self.exponents.is_empty() {
            return self.clone();
        }
        // As `PowerSum::new` of the shifted terms, without its sort: the
        // exponents are sorted, and `e − e₁` rounds monotonically, so they
        // stay sorted (equal ones merged in order, as there).
        let e1 = self.exponents[0];
        Self::from_sorted(
            self.exponents
                .iter()
                .zip(&self.coefficients)
                .skip(1)
                .map(|(e, c)| (e - e1, c * (e - e1))),
            self.len() - 1,
        )
    }

    /// An interval `[T_lo, T_hi]` of `t = ln x` that contains every root
    /// (`None` if there are fewer than two terms, i.e. no root at all).
    pub(crate) fn root_bounds(&self) -> Option<(f64, f64)> {
        let n = self.len();
        if n < 2 {
            return None;
        }
        let k = (n - 1) as f64;
        let (e_n, l_n) = (self.exponents[n - 1], self.log_abs[n - 1]);
        let (e_1, l_1) = (self.exponents[0], self.log_abs[0]);
        let mut hi = f64::NEG_INFINITY;
        for i in 0..n - 1 {
            hi = hi.max((k.ln() + self.log_abs[i] - l_n) / (e_n - self.exponents[i]));
        }
        let mut lo = f64::INFINITY;
        for i in 1..n {
            lo = lo.min((l_1 - k.ln() - self.log_abs[i]) / (self.exponents[i] - e_1));
        }
        Some((lo, hi))
    }

    /// All roots `t = ln x` with `lo <= t <= hi`, increasing.
    ///
    /// `top` (and `second`) optionally replace the expanded sum (and its
    /// reduced derivative) for sign tests and polishing: they must have the
    /// same sign as the respective sum for all `t`. Deeper levels of the
    /// recursion use the scaled expanded form.
    pub fn roots_in(
        &self,
        lo: f64,
        hi: f64,
        top: Option<Evaluator<'_>>,
        second: Option<Evaluator<'_>>,
    ) -> Vec<f64> {
        let mut out = Vec::new();
        self.roots_rec(lo, hi, top, second, &mut out, None);
        out
    }

    /// As [`Self::roots_in`], also returning the roots of the reduced
    /// derivative used to separate them (the critical points of
    /// `e^{−e₁t}F` in `(lo, hi)`; empty when Descartes' rule already settled
    /// the count, i.e. fewer than two sign changes).
    pub fn roots_and_critical_points_in(
        &self,
        lo: f64,
        hi: f64,
        top: Option<Evaluator<'_>>,
        second: Option<Evaluator<'_>>,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut out = Vec::new();
        let mut levels = [Vec::new()];
        self.roots_rec(lo, hi, top, second, &mut out, Some(&mut levels));
        let [crit] = levels;
        (out, crit)
    }

    /// As [`Self::roots_in`], also returning the separating roots of the
    /// next `levels.len()` reduced derivatives (level 1: critical points,
    /// level 2: inflection points of `e^{−e₁t}F`, …), as far as the
    /// recursion needed them.
    pub fn roots_with_levels_in(
        &self,
        lo: f64,
        hi: f64,
        top: Option<Evaluator<'_>>,
        second: Option<Evaluator<'_>>,
        levels: &mut [Vec<f64>],
    ) -> Vec<f64> {
        let mut out = Vec::new();
        self.roots_rec(lo, hi, top, second, &mut out, Some(levels));
        out
    }

    /// As [`Self::roots_with_levels_in`], warm started: `hints[k]` are
    /// points near which the roots of level `k` are expected (level 0: the
    /// roots, 1: critical points, …; typically the previous frequency's
    /// `levels`), `levels` receives the roots of every level the recursion
    /// went through (level 0 the roots; `levels[k]` the separating points
    /// of level `k − 1`, empty below the deepest level). Evaluators come
    /// with their slopes (see [`EvaluatorWithSlope`]), the plain one for the
    /// sign tests. The isolation is the exact one; only the polishing of a
    /// root whose bracket holds a hint starts there (module docs).
    pub fn roots_warm_in(
        &self,
        lo: f64,
        hi: f64,
        evaluators: &[(Evaluator<'_>, EvaluatorWithSlope<'_>)],
        hints: &[Vec<f64>],
        levels: &mut Vec<Vec<f64>>,
    ) {
        // the bracket ends and their values of every level, one allocation
        let mut scratch = Vec::with_capacity(4 * self.len() + 8);
        self.roots_warm_in_with(lo, hi, evaluators, hints, levels, &mut scratch);
    }

    /// [`Self::roots_warm_in`] with the bracket stack in `scratch` (its
    /// contents are discarded; its memory is reused).
    pub(crate) fn roots_warm_in_with(
        &self,
        lo: f64,
        hi: f64,
        evaluators: &[(Evaluator<'_>, EvaluatorWithSlope<'_>)],
        hints: &[Vec<f64>],
        levels: &mut Vec<Vec<f64>>,
        scratch: &mut Vec<f64>,
    ) {
        clear_rows(levels, self.len().max(1));
        scratch.clear();
        self.roots_rec_warm(lo, hi, evaluators, hints, levels, scratch);
    }

    fn roots_rec_warm(
        &self,
        lo: f64,
        hi: f64,
        evaluators: &[(Evaluator<'_>, EvaluatorWithSlope<'_>)],
        hints: &[Vec<f64>],
        levels: &mut [Vec<f64>],
        scratch: &mut Vec<f64>,
    ) {
        if self.len() < 2 || lo >= hi || self.sign_changes() == 0 {
            return;
        }
        let (here, deeper) = levels.split_at_mut(1);
        let out = &mut here[0];
        let scaled = |t: f64| {
            count(2);
            self.eval_scaled(t)
        };
        let scaled_d = |t: f64| {
            count(2);
            self.eval_scaled_with_slope(t)
        };
        let (f, fd): (Evaluator<'_>, EvaluatorWithSlope<'_>) = match evaluators.first() {
            Some(&(f, fd)) => (f, fd),
            None => (&scaled, &scaled_d),
        };
        if self.sign_changes() >= 2 {
            let d = self.reduced_derivative();
            d.roots_rec_warm(
                lo,
                hi,
                evaluators.get(1..).unwrap_or(&[]),
                hints.get(1..).unwrap_or(&[]),
                deeper,
                scratch,
            );
            deeper[0].retain(|&c| c > lo && c < hi);
        }
        // points (lo, the next level's roots, hi) and their values, on the
        // scratch stack above the deeper levels' (which are done)
        let base = scratch.len();
        scratch.push(lo);
        if self.sign_changes() >= 2 {
            scratch.extend(deeper[0].iter().copied());
        }
        scratch.push(hi);
        let n = scratch.len() - base;
        for i in 0..n {
            let v = f(scratch[base + i]);
            scratch.push(v);
        }
        let (points, vals) = scratch[base..].split_at(n);
        for i in 1..n - 1 {
            if vals[i] == 0.0 {
                out.push(points[i]);
            }
        }
        let hint = hints.first().map_or(&[][..], |h| &h[..]);
        for i in 0..n - 1 {
            let (a, b) = (points[i], points[i + 1]);
            let (fa, fb) = (vals[i], vals[i + 1]);
            if fa == 0.0 || fb == 0.0 {
                continue;
            }
            if (fa < 0.0) != (fb < 0.0) {
                let start = hint.iter().copied().find(|&h| h > a && h < b);
                let depth = 6usize.saturating_sub(self.len()).min(5);
                out.push(match start {
                    Some(h) => {
                        count(4 + 3 * depth);
                        newton_from(fd, f, a, b, fa, fb, h, 6 + 3 * depth)
                    }
                    None => {
                        count(5 + 3 * depth);
                        brent(f, a, b, fa, fb)
                    }
                });
            }
        }
        scratch.truncate(base);
        out.sort_by(f64::total_cmp);
    }

    fn roots_rec(
        &self,
        lo: f64,
        hi: f64,
        top: Option<Evaluator<'_>>,
        second: Option<Evaluator<'_>>,
        out: &mut Vec<f64>,
        levels: Option<&mut [Vec<f64>]>,
    ) {
        if self.len() < 2 || lo >= hi || self.sign_changes() == 0 {
            return;
        }
        let f = |t: f64| match top {
            Some(g) => g(t),
            None => {
                count(2);
                self.eval_scaled(t)
            }
        };
        let mut points = vec![lo];
        if self.sign_changes() >= 2 {
            let d = self.reduced_derivative();
            let mut crit = Vec::new();
            match levels {
                Some(lv) if !lv.is_empty() => {
                    let (here, deeper) = lv.split_at_mut(1);
                    d.roots_rec(lo, hi, second, None, &mut crit, Some(deeper));
                    crit.retain(|&c| c > lo && c < hi);
                    here[0] = crit.clone();
                }
                _ => {
                    d.roots_rec(lo, hi, second, None, &mut crit, None);
                    crit.retain(|&c| c > lo && c < hi);
                }
            }
            points.extend(crit.iter().copied());
        }
        points.push(hi);
        let mut vals: Vec<f64> = points.iter().map(|&t| f(t)).collect();
        // A critical point where f is exactly zero is a double root.
        for i in 1..points.len() - 1 {
            if vals[i] == 0.0 {
                out.push(points[i]);
            }
        }
        for i in 0..points.len() - 1 {
            let (a, b) = (points[i], points[i + 1]);
            let (fa, fb) = (vals[i], vals[i + 1]);
            if fa == 0.0 || fb == 0.0 {
                continue;
            }
            if (fa < 0.0) != (fb < 0.0) {
                out.push(brent(&f, a, b, fa, fb));
            }
        }
        vals.clear();
        out.sort_by(f64::total_cmp);
    }
}

/// The root of `f` in the bracket `[a, b]` (`f(a) = fa` and `f(b) = fb`
/// of opposite signs), by Newton's method from `t0 ∈ (a, b)` (`fd` gives
/// `f` and its slope), each step shrinking the bracket; where a step would
/// leave the bracket or does not at least halve the previous one (not yet
/// or no longer quadratic: far from the root, or at the rounding floor),
/// [`brent`] on the shrunk bracket. Converged when a step is within
/// Brent's tolerance (`2ε|t|`). `counter`: see [`count`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn newton_from(
    fd: &dyn Fn(f64) -> (f64, f64),
    f: &dyn Fn(f64) -> f64,
    a: f64,
    b: f64,
    fa: f64,
    fb: f64,
    t0: f64,
    counter: usize,
) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    let neg_at_a = fa < 0.0;
    let mut t = t0;
    let mut last_step = f64::INFINITY;
    for _ in 0..12 {
        let (v, dv) = fd(t);
        if v == 0.0 {
            return t;
        }
        if !v.is_finite() {
            break;
        }
        if (v < 0.0) == neg_at_a {
            a = t;
            fa = v;
        } else {
            b = t;
            fb = v;
        }
        let next = t - v / dv;
        let step = (next - t).abs();
        if step <= 2.0 * f64::EPSILON * t.abs() + 1e-300 {
            // converged (`t` is an end of the shrunk bracket: the step may
            // round onto it)
            return next.clamp(a, b);
        }
        if !(next.is_finite() && next > a && next < b) {
            count(22);
            break;
        }
        if step > 0.5 * last_step {
            if step < 64.0 * f64::EPSILON * (1.0 + t.abs()) {
                count(23);
            } else {
                count(24);
            }
            break;
        }
        last_step = step;
        t = next;
    }
    count(counter);
    brent(f, a, b, fa, fb)
}

/// Brent's bracketing root finder on `[a, b]` with `f(a) f(b) < 0`, to
/// machine precision in `t` (tolerance `2 ε |t| + 1e-300`).
///
/// Inverse quadratic interpolation / secant with bisection safeguard
/// (Brent 1973, *Algorithms for Minimization without Derivatives*, ch. 4).
pub(crate) fn brent(f: &dyn Fn(f64) -> f64, a: f64, b: f64, fa: f64, fb: f64) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (a, b, fa, fb);
    let mut c = a;
    let mut fc = fa;
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 1e-300;
        let m = 0.5 * (c - b);
        if m.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * m * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * m * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * m * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = m;
                e = m;
            }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(m) };
        fb = f(b);
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn roots_x(p: &PowerSum) -> Vec<f64> {
        let (lo, hi) = match p.root_bounds() {
            Some(b) => b,
            None => return vec![],
        };
        p.roots_in(lo - 1.0, hi + 1.0, None, None)
            .into_iter()
            .map(f64::exp)
            .collect()
    }

    #[test]
    fn merges_and_drops() {
        let p = PowerSum::new([(2.0, 1.0), (0.0, -1.0), (2.0, 2.0), (1.0, 0.0)]);
        assert_eq!(p.exponents(), &[0.0, 2.0]);
        assert_eq!(p.coefficients(), &[-1.0, 3.0]);
        assert_eq!(p.sign_changes(), 1);
    }

    #[test]
    fn polynomial_with_known_roots() {
        // (x-1)(x-2)(x-3) = x^3 - 6x^2 + 11x - 6
        let p = PowerSum::new([(3.0, 1.0), (2.0, -6.0), (1.0, 11.0), (0.0, -6.0)]);
        let r = roots_x(&p);
        assert_eq!(r.len(), 3);
        for (a, b) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((a - b).abs() < 1e-13, "{r:?}");
        }
    }

    #[test]
    fn nearly_double_root_is_split() {
        // (x - 1)(x - (1 + 1e-7)) = x^2 - (2 + 1e-7) x + (1 + 1e-7): two roots 1e-7 apart
        let d = 1e-7;
        let p = PowerSum::new([(2.0, 1.0), (1.0, -(2.0 + d)), (0.0, 1.0 + d)]);
        // The expanded coefficients are rounded, which moves the roots by
        // ~√ε ≈ 1e-8; the unexpanded forms are passed for sign tests, as
        // the harmonic-balance solver does.
        let top = |t: f64| {
            let x = t.exp();
            (x - 1.0) * (x - 1.0 - d)
        };
        // d/dt [x^0 (f)] = x f'(x) has the sign of 2x − 2 − d
        let second = |t: f64| 2.0 * t.exp() - 2.0 - d;
        let (lo, hi) = p.root_bounds().unwrap();
        let r: Vec<f64> = p
            .roots_in(lo - 1.0, hi + 1.0, Some(&top), Some(&second))
            .into_iter()
            .map(f64::exp)
            .collect();
        assert_eq!(r.len(), 2, "{r:?}");
        assert!(
            (r[0] - 1.0).abs() < 1e-12 && (r[1] - 1.0 - d).abs() < 1e-12,
            "{r:?}"
        );
    }

    #[test]
    fn real_exponents() {
        // x^0.5 - 2 = 0  ->  x = 4 ;  x^{-1.5} + x^{2.5} - 3 has roots by construction check
        let p = PowerSum::new([(0.5, 1.0), (0.0, -2.0)]);
        let r = roots_x(&p);
        assert_eq!(r.len(), 1);
        assert!((r[0] - 4.0).abs() < 1e-13);
        let q = PowerSum::new([(-1.5, 1.0), (2.5, 1.0), (0.0, -3.0)]);
        let r = roots_x(&q);
        assert_eq!(r.len(), 2);
        for x in r {
            assert!(q.eval(x).abs() < 1e-12);
        }
    }

    #[test]
    fn brent_solves_cubic() {
        let f = |t: f64| t * t * t - 2.0;
        let r = brent(&f, 0.0, 2.0, f(0.0), f(2.0));
        assert!((r - 2f64.cbrt()).abs() < 1e-15);
    }

    proptest! {
        /// Oracle: a product of (x - r_k) with distinct positive roots, expanded;
        /// every root is found, count exact.
        #[test]
        fn finds_all_roots_of_products(mut rs in proptest::collection::vec(0.05f64..20.0, 1..6)) {
            rs.sort_by(f64::total_cmp);
            rs.dedup_by(|a, b| (*a - *b).abs() < 1e-3 * b.abs());
            let mut coeffs = vec![1.0];
            for r in &rs {
                let mut next = vec![0.0; coeffs.len() + 1];
                for (i, c) in coeffs.iter().enumerate() {
                    next[i + 1] += c;
                    next[i] -= r * c;
                }
                coeffs = next;
            }
            let p = PowerSum::new(coeffs.iter().enumerate().map(|(i, c)| (i as f64, *c)));
            let found = roots_x(&p);
            prop_assert_eq!(found.len(), rs.len(), "{:?} vs {:?}", found, rs);
            for (a, b) in found.iter().zip(&rs) {
                prop_assert!((a - b).abs() < 1e-6 * b.max(1.0), "{} vs {}", a, b);
            }
        }
    }
}
