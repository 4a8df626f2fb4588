//! The dimensionless steady-state equation at one frequency,
//!
//! ```text
//! P(x) = x² [ S(x)² + D(x)² ] = 1,   S = s₀ + s₁ x^ρ,   D = d₀ + d₁ x^η
//! ```
//!
//! (see the module docs of [`super`] for the coefficients of each
//! formulation). Expanded, `P(x) − 1` is the sum of real powers
//!
//! ```text
//! −1 + (s₀² + d₀²) x² + 2 s₀ s₁ x^{2+ρ} + s₁² x^{2+2ρ} + 2 d₀ d₁ x^{2+η} + d₁² x^{2+2η}
//! ```
//!
//! whose roots [`crate::power_sum`] isolates exactly. Sign tests at the top
//! two levels use the unexpanded (accurate) forms
//! `ln P(t) = 2t + ln(S² + D²)` and `d/dt[e^{−e_min t}(P − 1)]`, `t = ln x`,
//! because the expansion cancels digits near resonance (`s₀ ≈ −s₁x^ρ`).

use crate::error::SolveError;
use crate::power_sum::PowerSum;

/// Dimensionless response equation `x²[(s₀ + s₁x^ρ)² + (d₀ + d₁x^η)²] = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResponseEquation {
    pub s0: f64,
    pub s1: f64,
    pub rho: f64,
    pub d0: f64,
    pub d1: f64,
    pub eta: f64,
}

/// Largest `|ln|term||` allowed in the accurate evaluators (e^700 < f64::MAX).
const LN_SAFE: f64 = 690.0;

impl ResponseEquation {
    pub fn new(s0: f64, s1: f64, rho: f64, d0: f64, d1: f64, eta: f64) -> Self {
        Self {
            s0,
            s1,
            rho,
            d0,
            d1,
            eta,
        }
    }

    /// `P(x) − 1` as a sum of real powers of `x`.
    pub fn power_sum(&self) -> PowerSum {
        let (s0, s1, d0, d1, r, e) = (self.s0, self.s1, self.d0, self.d1, self.rho, self.eta);
        PowerSum::new([
            (0.0, -1.0),
            (2.0, s0 * s0 + d0 * d0),
            (2.0 + r, 2.0 * s0 * s1),
            (2.0 + 2.0 * r, s1 * s1),
            (2.0 + e, 2.0 * d0 * d1),
            (2.0 + 2.0 * e, d1 * d1),
        ])
    }

    /// `P(x) − 1` in the scaled variable `y = x e^{−u}`, with `u` chosen so
    /// that no coefficient overflows or underflows: `(power sum in y, u)`.
    /// `u = 0` (the plain [`Self::power_sum`]) whenever its coefficients are
    /// representable, which is every physically sensible case; extreme
    /// parameters (e.g. `k_r = 1e300`, whose `s₁²` overflows) are scaled.
    pub fn scaled_power_sum(&self) -> (PowerSum, f64) {
        let (s0, s1, d0, d1, r, e) = (self.s0, self.s1, self.d0, self.d1, self.rho, self.eta);
        let ln = |v: f64| v.abs().ln();
        // (exponent, sign, ln|coefficient|) of each nonzero term
        let mut terms: Vec<(f64, f64, f64)> = vec![(0.0, -1.0, 0.0)];
        if s0 != 0.0 || d0 != 0.0 {
            terms.push((2.0, 1.0, ln_sum_sq(s0, d0)));
        }
        if s0 != 0.0 && s1 != 0.0 {
            terms.push((2.0 + r, (s0 * s1).signum(), 2f64.ln() + ln(s0) + ln(s1)));
        }
        if s1 != 0.0 {
            terms.push((2.0 + 2.0 * r, 1.0, 2.0 * ln(s1)));
        }
        if d0 != 0.0 && d1 != 0.0 {
            terms.push((2.0 + e, (d0 * d1).signum(), 2f64.ln() + ln(d0) + ln(d1)));
        }
        if d1 != 0.0 {
            terms.push((2.0 + 2.0 * e, 1.0, 2.0 * ln(d1)));
        }
        let worst = |u: f64| {
            terms
                .iter()
                .map(|&(ex, _, l)| (l + ex * u).abs())
                .fold(0.0, f64::max)
        };
        let u = if worst(0.0) < 600.0 || terms.iter().any(|t| !t.2.is_finite()) {
            0.0
        } else {
            // worst(u) is convex (max of |affine|): golden-section search
            let (mut a, mut b) = (-1500.0f64, 1500.0f64);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            for _ in 0..200 {
                let (c, d) = (b - g * (b - a), a + g * (b - a));
                if worst(c) <= worst(d) {
                    b = d;
                } else {
                    a = c;
                }
            }
            0.5 * (a + b)
        };
        if u == 0.0 {
            return (self.power_sum(), 0.0);
        }
        (
            PowerSum::new(
                terms
                    .iter()
                    .map(|&(ex, sign, l)| (ex, sign * (l + ex * u).exp())),
            ),
            u,
        )
    }

    /// `(S, D, ρ s₁ x^ρ, η d₁ x^η)` at `t = ln x`.
    #[inline]
    fn parts(&self, t: f64) -> (f64, f64, f64, f64) {
        let sr = if self.s1 == 0.0 {
            0.0
        } else {
            self.s1 * (self.rho * t).exp()
        };
        let de = if self.d1 == 0.0 {
            0.0
        } else {
            self.d1 * (self.eta * t).exp()
        };
        (self.s0 + sr, self.d0 + de, self.rho * sr, self.eta * de)
    }

    /// `ln P(e^t) = 2t + ln(S² + D²)`: negative below, positive above the
    /// forcing level, zero at a steady state.
    #[inline]
    pub fn ln_p(&self, t: f64) -> f64 {
        let (s, d, _, _) = self.parts(t);
        2.0 * t + ln_sum_sq(s, d)
    }

    /// `(ln P, d ln P/dt)` at `t = ln x`:
    /// `d ln P/dt = 2 + 2 (S·ρs₁x^ρ + D·ηd₁x^η) / (S² + D²)`.
    #[inline]
    pub fn ln_p_and_slope(&self, t: f64) -> (f64, f64) {
        let (s, d, st, dt) = self.parts(t);
        if s.abs() < 1e150 && d.abs() < 1e150 {
            let q = s * s + d * d;
            (2.0 * t + q.ln(), 2.0 + 2.0 * (s * st + d * dt) / q)
        } else {
            let h = s.hypot(d);
            (
                2.0 * t + 2.0 * h.ln(),
                2.0 + 2.0 * ((s / h) * (st / h) + (d / h) * (dt / h)),
            )
        }
    }

    /// `(phase, stable)` at a root `x` from one evaluation (see
    /// [`Self::phase`], [`Self::is_stable`]).
    #[inline]
    pub fn phase_and_stability(&self, x: f64) -> (f64, bool) {
        self.phase_and_stability_t(x.ln())
    }

    /// As [`Self::phase_and_stability`] at `t = ln x`.
    #[inline]
    pub fn phase_and_stability_t(&self, t: f64) -> (f64, bool) {
        let (s, d, st, dt) = self.parts(t);
        let q = s * s + d * d;
        // sign of d ln P/dt = 2 + 2(S st + D dt)/q, scaled by q/2 > 0
        let slope_sign = q + s * st + d * dt;
        (d.atan2(s), slope_sign > 0.0 && 2.0 * d + dt > 0.0)
    }

    /// `P(x)`.
    pub fn p(&self, x: f64) -> f64 {
        let (s, d, _, _) = self.parts(x.ln());
        x * x * (s * s + d * d)
    }

    /// Sign-equivalent of `d/dt [e^{−e_min t}(P − 1)] ∝ P′(t) − e_min (P − 1)`,
    /// divided by `max(P, 1)` so it never overflows.
    pub(crate) fn level1(&self, t: f64, e_min: f64) -> f64 {
        self.level1_and_ln_p(t, e_min).0
    }

    /// `(level1, ln P)` at `t` from one evaluation of the parts, each bit
    /// for bit as [`Self::level1`] and [`Self::ln_p`] compute it.
    #[inline]
    pub(crate) fn level1_and_ln_p(&self, t: f64, e_min: f64) -> (f64, f64) {
        let (lp, slope) = self.ln_p_and_slope(t);
        let v = if lp > 0.0 {
            slope + e_min * ((-lp).exp() - 1.0)
        } else {
            let p = lp.exp();
            p * slope - e_min * (p - 1.0)
        };
        (v, lp)
    }

    /// `(ln P, d ln P/dt, d² ln P/dt²)` at `t = ln x`, the first two
    /// exactly as [`Self::ln_p_and_slope`] computes them (bit for bit).
    /// With `A = S S′ + D D′` (`′` = d/dt: `S′ = ρs₁x^ρ`, `S″ = ρS′`, same
    /// for `D` with η) and `Q = S² + D²`:
    /// `d² ln P/dt² = 2 (S′² + S S″ + D′² + D D″)/Q − 4 (A/Q)²`.
    #[inline]
    fn ln_p_slope_curvature(&self, t: f64) -> (f64, f64, f64) {
        let (s, d, st, dt) = self.parts(t);
        let (lp, slope) = if s.abs() < 1e150 && d.abs() < 1e150 {
            let q = s * s + d * d;
            (2.0 * t + q.ln(), 2.0 + 2.0 * (s * st + d * dt) / q)
        } else {
            let h = s.hypot(d);
            (
                2.0 * t + 2.0 * h.ln(),
                2.0 + 2.0 * ((s / h) * (st / h) + (d / h) * (dt / h)),
            )
        };
        let h = s.hypot(d);
        let (sn, dn, stn, dtn) = (s / h, d / h, st / h, dt / h);
        let a = sn * stn + dn * dtn;
        let a1 = stn * stn + sn * self.rho * stn + dtn * dtn + dn * self.eta * dtn;
        (lp, slope, 2.0 * a1 - 4.0 * a * a)
    }

    /// [`Self::level1`] (the same value, bit for bit) and its derivative
    /// in `t` (with `s`, `s′` the first two derivatives of `ln P`):
    /// `s′ − e_min e^{−ln P} s` where `P > 1`, `P (s² + s′ − e_min s)`
    /// elsewhere.
    pub(crate) fn level1_with_slope(&self, t: f64, e_min: f64) -> (f64, f64) {
        let (lp, slope, curv) = self.ln_p_slope_curvature(t);
        if lp > 0.0 {
            let q = (-lp).exp();
            (slope + e_min * (q - 1.0), curv - e_min * q * slope)
        } else {
            let p = lp.exp();
            (
                p * slope - e_min * (p - 1.0),
                p * (slope * slope + curv - e_min * slope),
            )
        }
    }

    /// Range of `t` in which the accurate evaluators cannot overflow.
    fn safe_range(&self) -> (f64, f64) {
        // ln P = 2t + ln(S² + D²) never forms x², so only x itself and the
        // terms of S and D must be representable.
        let (mut lo, mut hi) = (-LN_SAFE, LN_SAFE);
        for (c, e) in [(self.s1, self.rho), (self.d1, self.eta)] {
            if c == 0.0 || e == 0.0 {
                continue;
            }
            let lim = (LN_SAFE - c.abs().ln()) / e;
            if e > 0.0 {
                hi = hi.min(lim);
            } else {
                lo = lo.max(lim);
            }
        }
        (lo, hi)
    }

    /// `P(x) < 1` at the largest representable amplitude: with no root,
    /// the response has no finite steady state (it grows without bound).
    pub fn grows_without_bound(&self) -> bool {
        let (_, hi) = self.safe_range();
        !(self.ln_p(hi) >= 0.0)
    }

    /// Every positive root `x` of `P(x) = 1`, increasing. Exact isolation
    /// (no grid); each root polished to machine precision in `ln x`.
    ///
    /// Errors only if a root lies beyond the range where `P` is representable
    /// in `f64` (absurd parameters), never silently.
    pub fn roots(&self) -> Result<Vec<f64>, SolveError> {
        Ok(self.roots_t()?.into_iter().map(f64::exp).collect())
    }

    /// As [`Self::roots`] in `t = ln x`.
    pub fn roots_t(&self) -> Result<Vec<f64>, SolveError> {
        Ok(self.roots_and_critical_points_t()?.0)
    }

    /// Roots and the critical points separating them (see
    /// [`Self::critical_points_t`]; empty when the root count is settled by
    /// Descartes' rule, in which case no fold can be near), in `t = ln x`.
    pub fn roots_and_critical_points_t(&self) -> Result<(Vec<f64>, Vec<f64>), SolveError> {
        let (ps, u) = self.scaled_power_sum();
        if ps.sign_changes() == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let (lo, hi) = self.search_range(&ps, u)?;
        let e_min = ps.exponents()[0];
        let top = |t: f64| self.ln_p(t + u);
        let second = |t: f64| self.level1(t + u, e_min);
        let (mut roots, mut crit) =
            ps.roots_and_critical_points_in(lo, hi, Some(&top), Some(&second));
        if u != 0.0 {
            roots
                .iter_mut()
                .chain(crit.iter_mut())
                .for_each(|t| *t += u);
        }
        Ok((roots, crit))
    }

    /// Roots, critical points and inflection points (all in `t = ln x`, as
    /// far as the isolation needed them) with the values of `ln P` at the
    /// critical points and of the (scaled) slope `d/dt[e^{−e_min t}(P−1)]`
    /// at the inflection points. A fold is a critical point where
    /// `ln P = 0`; a pair of critical points is born where the slope at an
    /// inflection point touches zero. Used by the fold search.
    pub fn fold_indicators(&self) -> Result<FoldIndicators, SolveError> {
        crate::power_sum::count(3);
        let (ps, u) = self.scaled_power_sum();
        if ps.sign_changes() == 0 {
            return Ok(FoldIndicators::default());
        }
        let (lo, hi) = self.search_range(&ps, u)?;
        let e_min = ps.exponents()[0];
        let top = |t: f64| {
            crate::power_sum::count(0);
            self.ln_p(t + u)
        };
        let second = |t: f64| {
            crate::power_sum::count(1);
            self.level1(t + u, e_min)
        };
        let mut levels = [Vec::new(), Vec::new()];
        let roots = ps.roots_with_levels_in(lo, hi, Some(&top), Some(&second), &mut levels);
        let [crit, infl] = levels;
        Ok(FoldIndicators {
            e_min,
            roots: roots.into_iter().map(|t| t + u).collect(),
            critical: crit
                .into_iter()
                .map(|t| (t + u, self.ln_p(t + u)))
                .collect(),
            inflection_ln_p: infl.iter().map(|&t| self.ln_p(t + u)).collect(),
            inflection: infl
                .into_iter()
                .map(|t| (t + u, self.level1(t + u, e_min)))
                .collect(),
        })
    }

    /// As [`Self::fold_indicators`], warm started from `hints`: the roots
    /// of every level of the isolation at a nearby frequency (`t = ln x`;
    /// the `levels` of a previous call, or empty). The isolation is the
    /// exact one (every bracket verified by a sign change on a monotone
    /// interval); only the polishing of each root starts at the hint in
    /// its bracket, by safeguarded Newton ([`PowerSum::roots_warm_in`]).
    /// `levels` receives this frequency's roots per level, for the next
    /// call. The results equal the cold isolation's to its tolerance
    /// (`2ε|t|`; test `warm_isolation_matches_the_cold_one`).
    #[cfg(test)]
    pub(crate) fn fold_indicators_warm(
        &self,
        hints: &[Vec<f64>],
        levels: &mut Vec<Vec<f64>>,
    ) -> Result<FoldIndicators, SolveError> {
        let mut out = FoldIndicators::default();
        self.fold_indicators_warm_into(hints, levels, &mut out, &mut WarmBuffers::default())?;
        Ok(out)
    }

    /// [`Self::fold_indicators_warm`] into `out`, with the working memory
    /// of `buffers`: the same numbers, in the memory of an earlier call
    /// (the fold search of a sweep isolates at a hundred or more
    /// frequencies, a fit's at hundreds of thousands).
    pub(crate) fn fold_indicators_warm_into(
        &self,
        hints: &[Vec<f64>],
        levels: &mut Vec<Vec<f64>>,
        out: &mut FoldIndicators,
        buffers: &mut WarmBuffers,
    ) -> Result<(), SolveError> {
        crate::power_sum::count(3);
        out.roots.clear();
        out.critical.clear();
        out.inflection.clear();
        out.inflection_ln_p.clear();
        out.e_min = 0.0;
        let (ps, u) = self.scaled_power_sum();
        if ps.sign_changes() == 0 {
            levels.clear();
            return Ok(());
        }
        let (lo, hi) = self.search_range(&ps, u)?;
        let e_min = ps.exponents()[0];
        let top = |t: f64| {
            crate::power_sum::count(0);
            self.ln_p(t + u)
        };
        let top_d = |t: f64| {
            crate::power_sum::count(0);
            self.ln_p_and_slope(t + u)
        };
        let second = |t: f64| {
            crate::power_sum::count(1);
            self.level1(t + u, e_min)
        };
        let second_d = |t: f64| {
            crate::power_sum::count(1);
            self.level1_with_slope(t + u, e_min)
        };
        let evaluators: [(
            crate::power_sum::Evaluator<'_>,
            crate::power_sum::EvaluatorWithSlope<'_>,
        ); 2] = [(&top, &top_d), (&second, &second_d)];
        let WarmBuffers { shifted, scratch } = buffers;
        let hints = if u == 0.0 {
            hints
        } else {
            crate::power_sum::clear_rows(shifted, hints.len());
            for (to, h) in shifted.iter_mut().zip(hints) {
                to.extend(h.iter().map(|t| t - u));
            }
            &shifted[..]
        };
        ps.roots_warm_in_with(lo, hi, &evaluators, hints, levels, scratch);
        if u != 0.0 {
            levels.iter_mut().flatten().for_each(|t| *t += u);
        }
        let level = |k: usize| levels.get(k).map_or(&[][..], |v| &v[..]);
        out.e_min = e_min;
        out.roots.extend_from_slice(level(0));
        out.critical
            .extend(level(1).iter().map(|&t| (t, self.ln_p(t))));
        for &t in level(2) {
            let (v, lp) = self.level1_and_ln_p(t, e_min);
            out.inflection_ln_p.push(lp);
            out.inflection.push((t, v));
        }
        Ok(())
    }

    /// Critical points of `e^{−e_min t}(P − 1)` (in `t`) inside the root
    /// search range: the local extrema between which roots appear and vanish
    /// in pairs. A fold is a critical point where `P = 1`.
    pub fn critical_points_t(&self) -> Result<Vec<f64>, SolveError> {
        let (ps, u) = self.scaled_power_sum();
        if ps.sign_changes() < 2 {
            return Ok(Vec::new());
        }
        let (lo, hi) = self.search_range(&ps, u)?;
        let e_min = ps.exponents()[0];
        let second = |t: f64| self.level1(t + u, e_min);
        Ok(ps
            .reduced_derivative()
            .roots_in(lo, hi, Some(&second), None)
            .into_iter()
            .map(|t| t + u)
            .collect())
    }

    /// Root search range in `t_y = ln y = ln x − u` of the scaled power sum.
    fn search_range(&self, ps: &PowerSum, u: f64) -> Result<(f64, f64), SolveError> {
        let (blo, bhi) = ps.root_bounds().unwrap_or((0.0, 0.0));
        let (blo, bhi) = (blo - 0.5, bhi + 0.5);
        let (slo, shi) = self.safe_range();
        let (slo, shi) = (slo - u, shi - u);
        let (sgn_lo, sgn_hi) = ps.asymptotic_signs();
        let (mut lo, mut hi) = (blo, bhi);
        if bhi > shi {
            hi = shi;
            if self.ln_p(hi + u).signum() != sgn_hi {
                return Err(SolveError::Overflow {
                    amplitude: (hi + u).exp(),
                    omega: f64::NAN,
                });
            }
        }
        if blo < slo {
            lo = slo;
            if self.ln_p(lo + u).signum() != sgn_lo {
                return Err(SolveError::Overflow {
                    amplitude: (lo + u).exp(),
                    omega: f64::NAN,
                });
            }
        }
        Ok((lo, hi.max(lo)))
    }

    /// The roots (`t = ln x`, increasing) when the equation is known to have
    /// exactly `n` of them, from `hints`: points of `t` near which they lie
    /// (the roots and critical points of a nearby frequency). `ln P` is
    /// evaluated at the sorted hints and one unit of `t` beyond them; with
    /// `n` sign changes found, each of the `n` disjoint brackets holds an
    /// odd number of roots and together they hold at most `n`, so each holds
    /// exactly one, polished by [`Self::root_in`]. `None` (the caller
    /// isolates the roots exactly) with any other number of sign changes, a
    /// hint where `ln P` is zero or not a number, or `n = 0`.
    ///
    /// `separators` (hints expected between the roots: the critical points
    /// of the nearby frequency) let most calls evaluate `ln P` at a few of
    /// the hints only ([`Self::roots_by_anchors`]: the same roots, bit for
    /// bit). About 2n evaluations of `ln P` and a few Newton steps per root,
    /// against several hundred for the exact isolation: the stepped sweep
    /// uses it between the samples of its fold search, where the count is
    /// known ([`super::folds`]).
    pub(crate) fn roots_bracketed(
        &self,
        n: usize,
        hints: &mut Vec<f64>,
        separators: &[f64],
    ) -> Option<Vec<f64>> {
        if n == 0 {
            return None;
        }
        hints.retain(|t| t.is_finite());
        if hints.is_empty() {
            return None;
        }
        hints.sort_by(f64::total_cmp);
        hints.dedup();
        let (first, last) = (hints[0], hints[hints.len() - 1]);
        hints.insert(0, first - 1.0);
        hints.push(last + 1.0);
        self.roots_by_anchors(n, hints, separators)
            .or_else(|| self.roots_at_every_hint(n, hints))
    }

    /// The roots from `ln P` at every one of the sorted `hints` (the outer
    /// ones included): the bracketing [`Self::roots_by_anchors`] reproduces
    /// with fewer evaluations, and its fallback.
    fn roots_at_every_hint(&self, n: usize, hints: &[f64]) -> Option<Vec<f64>> {
        let mut prev = (hints[0], self.ln_p(hints[0]));
        let mut roots = Vec::with_capacity(n);
        for &t in &hints[1..] {
            let v = self.ln_p(t);
            if !(v.is_finite() && v != 0.0 && prev.1.is_finite() && prev.1 != 0.0) {
                return None;
            }
            if (v > 0.0) != (prev.1 > 0.0) {
                if roots.len() == n {
                    return None;
                }
                roots.push(self.root_in(prev.0, t, prev.1, v));
            }
            prev = (t, v);
        }
        (roots.len() == n).then_some(roots)
    }

    /// The roots of [`Self::roots_bracketed`] from fewer evaluations:
    /// `ln P` at the ends of the sorted `hints` and at those of the
    /// `separators` (hints expected between the roots: the critical points)
    /// first; when exactly `n` of these anchor intervals change sign, each
    /// holds the one pair of adjacent hints across which `ln P` changes
    /// sign (the `n` roots allow no more than `n` sign changes in all), found
    /// by bisection on the hints' indices, and the root is polished there by
    /// [`Self::root_in`] exactly as the evaluation of every hint would have
    /// it (same bracket, same values: the same roots to the last bit).
    /// `None` (every hint is then evaluated) with another count, or a value
    /// that is zero or not a number. About `n + 1 + n log₂(hints/n)`
    /// evaluations of `ln P` instead of one per hint.
    fn roots_by_anchors(&self, n: usize, hints: &[f64], separators: &[f64]) -> Option<Vec<f64>> {
        let m = hints.len();
        let mut anchors: Vec<usize> = Vec::with_capacity(separators.len() + 2);
        anchors.push(0);
        for s in separators {
            if let Ok(i) = hints.binary_search_by(|h| h.total_cmp(s)) {
                anchors.push(i);
            }
        }
        anchors.push(m - 1);
        anchors.sort_unstable();
        anchors.dedup();
        let value = |i: usize| {
            let v = self.ln_p(hints[i]);
            (v.is_finite() && v != 0.0).then_some(v)
        };
        let values: Vec<f64> = anchors.iter().map(|&i| value(i)).collect::<Option<_>>()?;
        let changing: Vec<usize> = (1..anchors.len())
            .filter(|&k| (values[k] > 0.0) != (values[k - 1] > 0.0))
            .collect();
        if changing.len() != n {
            return None;
        }
        let mut roots = Vec::with_capacity(n);
        for k in changing {
            let (mut a, mut va) = (anchors[k - 1], values[k - 1]);
            let (mut b, mut vb) = (anchors[k], values[k]);
            while b - a > 1 {
                let mid = a + (b - a) / 2;
                let v = value(mid)?;
                if (v > 0.0) == (va > 0.0) {
                    (a, va) = (mid, v);
                } else {
                    (b, vb) = (mid, v);
                }
            }
            roots.push(self.root_in(hints[a], hints[b], va, vb));
        }
        Some(roots)
    }

    /// The root of `ln P` in `(a, b)`, where `ln P(a)` = `fa` and
    /// `ln P(b)` = `fb` have opposite signs: Newton's method on `ln P(t)`
    /// (analytic slope) kept inside the shrinking bracket, bisection where a
    /// step would leave it; to the tolerance of [`crate::power_sum`]'s
    /// Brent solver (`2ε|t|`).
    pub(crate) fn root_in(&self, a: f64, b: f64, fa: f64, fb: f64) -> f64 {
        let (mut a, mut b) = (a, b);
        let neg_at_a = fa < 0.0;
        // regula falsi start
        let mut t = a - fa * (b - a) / (fb - fa);
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
        for _ in 0..200 {
            let (f, fp) = self.ln_p_and_slope(t);
            if f == 0.0 {
                return t;
            }
            if f.is_finite() {
                if (f < 0.0) == neg_at_a {
                    a = t;
                } else {
                    b = t;
                }
            }
            let tol = 2.0 * f64::EPSILON * t.abs() + 1e-300;
            let next = t - f / fp;
            if next.is_finite() && next > a && next < b {
                if (next - t).abs() <= tol {
                    return next;
                }
                t = next;
            } else {
                let mid = 0.5 * (a + b);
                if mid <= a || mid >= b || b - a <= tol {
                    return mid.clamp(a, b);
                }
                t = mid;
            }
        }
        t
    }

    /// Phase lag `φ = atan2(D, S) ∈ [0, π]` at amplitude `x`.
    pub fn phase(&self, x: f64) -> f64 {
        let (s, d, _, _) = self.parts(x.ln());
        d.atan2(s)
    }

    /// Slow-flow stability at a root `x`: `dP/dx > 0` (saddle-node) and
    /// `2d₀ + (2+η) d₁ x^η > 0` (Hopf).
    pub fn is_stable(&self, x: f64) -> bool {
        let t = x.ln();
        let (_, slope) = self.ln_p_and_slope(t);
        let (_, d, _, dt) = self.parts(t);
        // 2 d0 + (2+η) d1 x^η = 2 D + η d1 x^η
        slope > 0.0 && 2.0 * d + dt > 0.0
    }

    /// As [`Self::solve_unique`], also returning phase and stability at the
    /// root. When the last Newton step `δ` is accepted without another
    /// evaluation (|δ| < 1e-9), the power terms of that last evaluation are
    /// carried to the root by `e^{−ρδ} ≈ 1 − ρδ + (ρδ)²/2` (relative error
    /// < (ρδ)³/6 ≈ 1e-27), so no further transcendental calls are needed.
    pub fn solve_unique_state(&self, t0: f64, t_max: f64) -> Option<UniqueState> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, t_max);
        let mut t = t0.min(t_max);
        for _ in 0..60 {
            let sr = if self.s1 == 0.0 {
                0.0
            } else {
                self.s1 * (self.rho * t).exp()
            };
            let de = if self.d1 == 0.0 {
                0.0
            } else {
                self.d1 * (self.eta * t).exp()
            };
            let (s, d) = (self.s0 + sr, self.d0 + de);
            let (st, dt) = (self.rho * sr, self.eta * de);
            let q = s * s + d * d;
            let (f, fp) = if s.abs() < 1e150 && d.abs() < 1e150 {
                (2.0 * t + q.ln(), 2.0 + 2.0 * (s * st + d * dt) / q)
            } else {
                let h = s.hypot(d);
                (
                    2.0 * t + 2.0 * h.ln(),
                    2.0 + 2.0 * ((s / h) * (st / h) + (d / h) * (dt / h)),
                )
            };
            if f == 0.0 {
                return Some(self.state_from_terms(t, sr, de));
            }
            if f < 0.0 {
                lo = lo.max(t);
            } else {
                hi = hi.min(t);
            }
            let step = f / fp;
            let mut next = t - step;
            if fp > 0.0 && step.abs() < 1e-9 && next > lo && next < hi {
                let shift = |e: f64| {
                    let u = e * step;
                    1.0 - u + 0.5 * u * u
                };
                return Some(self.state_from_terms(
                    next,
                    sr * shift(self.rho),
                    de * shift(self.eta),
                ));
            }
            if !(fp > 0.0) || !next.is_finite() || next <= lo || next >= hi {
                next = if lo.is_finite() && hi.is_finite() {
                    0.5 * (lo + hi)
                } else if lo.is_finite() {
                    lo + 1.0
                } else {
                    hi - 1.0
                };
            }
            if (next - t).abs() <= 4.0 * f64::EPSILON * (1.0 + t.abs()) {
                let (phase, stable) = self.phase_and_stability_t(next);
                return Some(UniqueState {
                    t: next,
                    phase,
                    stable,
                });
            }
            t = next;
        }
        None
    }

    #[inline]
    fn state_from_terms(&self, t: f64, sr: f64, de: f64) -> UniqueState {
        let (s, d) = (self.s0 + sr, self.d0 + de);
        let (st, dt) = (self.rho * sr, self.eta * de);
        let slope_sign = s * s + d * d + s * st + d * dt;
        UniqueState {
            t,
            phase: d.atan2(s),
            stable: slope_sign > 0.0 && 2.0 * d + dt > 0.0,
        }
    }

    /// Upper bound on every root: `P ≥ x² d₀²` and `P ≥ x^{2+2η} d₁²`
    /// (valid when `d₀, d₁ ≥ 0`), so roots satisfy `x ≤ 1/d₀` and
    /// `x ≤ d₁^{−1/(1+η)}` (η > −1). `∞` if neither applies.
    pub fn amplitude_bound(&self) -> f64 {
        amplitude_bound(self.d0, self.d1, self.eta)
    }

    /// The one root where it is known to be unique (the one-root
    /// certificate of the stepped-sine fast path):
    /// [`Self::solve_unique_state`] up to the root bound `ln(1/d₀)` (or
    /// [`Self::amplitude_bound`] without linear damping; any valid bound
    /// works, this is the cheapest), from `t_guess` (`ln x`) or, without
    /// one, from the linear estimate `−½ ln(s₀² + d₀²)`; a start that is
    /// not finite is replaced by `t = 0`.
    pub fn solve_certified(&self, t_guess: Option<f64>) -> Option<UniqueState> {
        let t_max = if self.d0 > 0.0 {
            -self.d0.ln()
        } else {
            self.amplitude_bound().ln()
        };
        let guess = t_guess.unwrap_or_else(|| -0.5 * (self.s0 * self.s0 + self.d0 * self.d0).ln());
        let guess = if guess.is_finite() {
            guess.min(t_max)
        } else {
            0.0f64.min(t_max)
        };
        self.solve_unique_state(guess, t_max)
    }

    /// Safeguarded Newton on `ln P(t) = 0` from `t0`, for use where the root
    /// is known to be unique and `ln P` increasing up to `t_max` (with
    /// `ln P > 0` beyond). Returns `None` if it fails to converge.
    pub fn solve_unique(&self, t0: f64, t_max: f64) -> Option<f64> {
        self.solve_unique_state(t0, t_max).map(|s| s.t)
    }
}

/// Steady state from [`ResponseEquation::solve_unique_state`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniqueState {
    /// `t = ln x` of the root.
    pub t: f64,
    /// Phase lag (rad).
    pub phase: f64,
    /// Slow-flow stability.
    pub stable: bool,
}

/// Working memory of [`ResponseEquation::fold_indicators_warm_into`]:
/// the hints shifted to the scaled variable, and the isolation's bracket
/// stack ([`PowerSum::roots_warm_in_with`]).
#[derive(Debug, Clone, Default)]
pub(crate) struct WarmBuffers {
    shifted: Vec<Vec<f64>>,
    scratch: Vec<f64>,
}

/// See [`ResponseEquation::fold_indicators`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FoldIndicators {
    /// Roots `t = ln x`.
    pub roots: Vec<f64>,
    /// `(t, ln P)` at each critical point.
    pub critical: Vec<(f64, f64)>,
    /// `(t, slope)` at each inflection point.
    pub inflection: Vec<(f64, f64)>,
    /// `ln P` at each inflection point.
    pub inflection_ln_p: Vec<f64>,
    /// The smallest exponent `e_min` of the expanded `P − 1`: the slope at
    /// an inflection point is that of `e^{−e_min t}(P − 1)`.
    pub e_min: f64,
}

/// `ln(s² + d²)` without overflow.
#[inline]
fn ln_sum_sq(s: f64, d: f64) -> f64 {
    if s.abs() < 1e150 && d.abs() < 1e150 {
        (s * s + d * d).ln()
    } else {
        2.0 * s.hypot(d).ln()
    }
}

/// See [`ResponseEquation::amplitude_bound`].
pub(crate) fn amplitude_bound(d0: f64, d1: f64, eta: f64) -> f64 {
    let mut b = f64::INFINITY;
    if d0 > 0.0 {
        b = b.min(1.0 / d0);
    }
    if d1 > 0.0 && eta > -1.0 {
        b = b.min(d1.powf(-1.0 / (1.0 + eta)));
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Newton in the bracket against Brent's method (the oracle) on the
    /// same brackets, and `roots_bracketed` against the exact isolation:
    /// random hardening and softening equations (η down to −1) with one to
    /// three roots, hints perturbed from the exact roots and critical
    /// points. Every root agrees to 1e-14 relative; a bracketing that
    /// does not find the count returns `None`, never wrong roots; the
    /// anchored bracketing (`roots_by_anchors`) returns the roots of the
    /// evaluation at every hint bit for bit.
    #[test]
    fn newton_in_bracket_matches_brent() {
        let mut rnd = crate::harmonic_balance::test_uniform(0xb7ac_4e7e_d000_0001u64);
        let (mut checked, mut bracketed, mut declined, mut same_bits) = (0, 0, 0, 0);
        for case in 0..4000 {
            let nu = 0.8 + 0.5 * rnd();
            let s0 = 1.0 - nu * nu;
            let sign = if case % 3 == 2 { -1.0 } else { 1.0 };
            let s1 = sign * 10f64.powf(-3.0 + 4.0 * rnd());
            let rho = 0.3 + 3.0 * rnd();
            let d0 = 10f64.powf(-3.5 + 2.0 * rnd());
            let eta = -1.0 + 3.0 * rnd();
            let d1 = 10f64.powf(-4.0 + 3.0 * rnd());
            let eq = ResponseEquation::new(s0, s1, rho, d0, d1, eta);
            let Ok((roots, crit)) = eq.roots_and_critical_points_t() else {
                continue;
            };
            // each root against Brent on a bracket around it
            for (k, &t) in roots.iter().enumerate() {
                let lo = if k == 0 { t - 2.0 } else { crit[k - 1] };
                let hi = if k + 1 == roots.len() {
                    t + 2.0
                } else {
                    crit[k]
                };
                let (fa, fb) = (eq.ln_p(lo), eq.ln_p(hi));
                if !((fa > 0.0) != (fb > 0.0) && fa != 0.0 && fb != 0.0) {
                    continue;
                }
                let f = |x: f64| eq.ln_p(x);
                let b = crate::power_sum::brent(&f, lo, hi, fa, fb);
                let n = eq.root_in(lo, hi, fa, fb);
                assert!(
                    (n - b).abs() <= 1e-14 * (1.0 + b.abs()),
                    "{n} vs {b} in [{lo}, {hi}]: {eq:?}"
                );
                checked += 1;
            }
            // the roots from perturbed hints, knowing the count
            let jitter = 1e-3 * (rnd() - 0.5);
            let mut hints: Vec<f64> = roots.iter().chain(&crit).map(|t| t + jitter).collect();
            let crit_hints: Vec<f64> = crit.iter().map(|t| t + jitter).collect();
            match eq.roots_bracketed(roots.len(), &mut hints, &crit_hints) {
                Some(ts) => {
                    // (hints now sorted, with the outer points): the
                    // anchored bracketing against every hint, bit for bit
                    let every = eq.roots_at_every_hint(roots.len(), &hints);
                    let anchored = eq.roots_by_anchors(roots.len(), &hints, &crit_hints);
                    if let (Some(a), Some(e)) = (&anchored, &every) {
                        assert!(a.iter().zip(e).all(|(x, y)| x.to_bits() == y.to_bits()));
                        same_bits += 1;
                    }
                    assert_eq!(ts.len(), roots.len());
                    for (t, e) in ts.iter().zip(&roots) {
                        assert!(
                            (t - e).abs() <= 1e-14 * (1.0 + e.abs()),
                            "{t} vs {e}: {eq:?}"
                        );
                    }
                    bracketed += 1;
                }
                None => declined += 1,
            }
            // a wrong count is declined, never answered
            if !roots.is_empty() {
                let mut hints: Vec<f64> = roots.iter().chain(&crit).copied().collect();
                assert!(eq
                    .roots_bracketed(roots.len() + 2, &mut hints, &crit)
                    .is_none());
            }
        }
        eprintln!(
            "{checked} roots against Brent; {bracketed} root sets bracketed, {declined} declined; \
             {same_bits} from anchors bit for bit as from every hint"
        );
        assert!(checked > 4000 && bracketed > 3000, "{checked} {bracketed}");
        assert!(same_bits > 3000, "{same_bits}");
    }

    /// The slopes of the warm isolation's evaluators against central
    /// differences, and their values bit for bit those of the plain ones.
    #[test]
    fn evaluator_slopes_match_differences() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x51_0be5_0000_0004u64);
        let mut checked = 0;
        for case in 0..2000 {
            let nu = 0.8 + 0.5 * rnd();
            let sign = if case % 3 == 2 { -1.0 } else { 1.0 };
            let eq = ResponseEquation::new(
                1.0 - nu * nu,
                sign * 10f64.powf(-3.0 + 4.0 * rnd()),
                0.3 + 3.0 * rnd(),
                10f64.powf(-3.5 + 2.0 * rnd()),
                10f64.powf(-4.0 + 3.0 * rnd()),
                -1.0 + 3.0 * rnd(),
            );
            let (ps, _) = eq.scaled_power_sum();
            let e_min = ps.exponents()[0];
            let sums = [
                ps.reduced_derivative(),
                ps.reduced_derivative().reduced_derivative(),
            ];
            for _ in 0..5 {
                let t = -6.0 + 12.0 * rnd();
                let h = 1e-5;
                let (v, dv) = eq.level1_with_slope(t, e_min);
                assert_eq!(v.to_bits(), eq.level1(t, e_min).to_bits());
                let fd = (eq.level1(t + h, e_min) - eq.level1(t - h, e_min)) / (2.0 * h);
                assert!(
                    (dv - fd).abs() <= 1e-5 * (1.0 + fd.abs()),
                    "level 1 at {t}: {dv} vs {fd}: {eq:?}"
                );
                for p in &sums {
                    let (v, dv) = p.eval_scaled_with_slope(t);
                    assert_eq!(v.to_bits(), p.eval_scaled(t).to_bits());
                    let fd = (p.eval_scaled(t + h) - p.eval_scaled(t - h)) / (2.0 * h);
                    assert!(
                        (dv - fd).abs() <= 1e-5 * (1.0 + fd.abs()),
                        "scaled sum at {t}: {dv} vs {fd}: {p:?}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 9000);
    }

    #[test]
    fn linear_root_is_closed_form() {
        let eq = ResponseEquation::new(0.3, 0.0, 0.0, 0.05, 0.0, 0.0);
        let r = eq.roots().unwrap();
        assert_eq!(r.len(), 1);
        let exact = 1.0 / (0.3f64 * 0.3 + 0.05 * 0.05).sqrt();
        assert!((r[0] - exact).abs() < 1e-14 * exact);
        assert!(eq.is_stable(r[0]));
        assert!((eq.phase(r[0]) - 0.05f64.atan2(0.3)).abs() < 1e-15);
    }

    #[test]
    fn duffing_three_roots_middle_unstable() {
        // strongly detuned above resonance, hardening: three roots
        let eq = ResponseEquation::new(1.0 - 1.3f64.powi(2), 0.01, 2.0, 2.0 * 0.01 * 1.3, 0.0, 0.0);
        let r = eq.roots().unwrap();
        assert_eq!(r.len(), 3, "{r:?}");
        assert!(eq.is_stable(r[0]) && !eq.is_stable(r[1]) && eq.is_stable(r[2]));
        for x in &r {
            assert_eq!(eq.phase_and_stability(*x), (eq.phase(*x), eq.is_stable(*x)));
        }
        for x in &r {
            assert!((eq.p(*x) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn coulomb_sticking_has_no_root() {
        // eta = -1: P >= d1^2; d1 >= 1 means friction beats forcing
        let eq = ResponseEquation::new(0.5, 0.0, 0.0, 0.1, 1.2, -1.0);
        assert!(eq.roots().unwrap().is_empty());
        let eq = ResponseEquation::new(0.5, 0.0, 0.0, 0.1, 0.8, -1.0);
        assert_eq!(eq.roots().unwrap().len(), 1);
    }

    #[test]
    fn unique_state_matches_direct_evaluation() {
        let eq = ResponseEquation::new(-0.02, 3e-4, 4.0022, 0.0129, 2e-6, 3.03099);
        for t0 in [-3.0, 0.0, 2.0, 4.0] {
            let st = eq
                .solve_unique_state(t0, eq.amplitude_bound().ln())
                .unwrap();
            // independent oracle: exact root isolation
            let iso = eq.roots_t().unwrap();
            assert_eq!(iso.len(), 1);
            assert!((st.t - iso[0]).abs() < 1e-14);
            let (ph, stable) = eq.phase_and_stability_t(st.t);
            assert!((st.phase - ph).abs() < 1e-15, "{} vs {}", st.phase, ph);
            assert_eq!(st.stable, stable);
        }
    }

    #[test]
    fn unique_newton_matches_isolation() {
        let eq = ResponseEquation::new(-0.01, 1e-4, 4.0, 0.013, 1e-6, 3.0);
        let iso = eq.roots_t().unwrap();
        assert_eq!(iso.len(), 1);
        let t = eq.solve_unique(0.0, eq.amplitude_bound().ln()).unwrap();
        assert!((t - iso[0]).abs() < 1e-14);
    }
}
