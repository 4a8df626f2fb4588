//! Fold (saddle-node, jump) frequencies and the phase-quadrature point.
//!
//! A fold is a point of the response curve where two steady states merge:
//! `P(x, ν) = 1` and `∂P/∂x = 0`. As the frequency changes, roots of the
//! response equation appear and vanish in pairs only there, so the number of
//! roots `N(Ω)` (computed exactly by [`ResponseEquation::roots`]) is
//! piecewise constant with jumps of ±2 at the folds.
//!
//! Location: `N(Ω)` on a fixed log-spaced grid of [`GRID`] cells over the
//! requested range ([`find_folds`]; a stepped sweep searches on its own
//! steps instead, at most two grid cells apart, and keeps the roots
//! isolated there: [`find_folds_on_steps`]). In a cell whose count
//! changes by two, the fold is the zero of the *critical value*
//! `h(Ω) = ln P(t_c(Ω), Ω)`, where `t_c(Ω)` is the local extremum of `ln P`
//! between the merging roots (`d ln P/dt = 0`; followed from the nearest
//! frequency already evaluated by bracketing the slope and Brent's method).
//! `N` changes exactly where `h` changes sign (at a fold `P = 1` and
//! `∂P/∂t = 0`), and `h` crosses zero transversally there, so Brent's
//! method on `h` finds the fold to `2ε` relative in about ten evaluations,
//! none of which isolates roots; the exact root count just either side
//! (±1e-9 relative) then confirms it. Where that does not apply (the count
//! changes by other than two, the extremum cannot be followed across the
//! cell, or the confirmation fails), the cell is bisected on `N` itself to
//! `|ΔΩ|/Ω ≤ 4ε` (about 45 root isolations per fold; kept as the oracle of
//! the critical-value location in the tests). `ln P` is computed with the
//! unexpanded (accurate) formula, so the fold frequency is found to ~1e-14
//! relative either way.
//!
//! Two folds inside one grid cell (a narrow hysteresis window near a cusp)
//! leave the counts at its ends equal. Such cells are found from the
//! critical values and their rates of change with `ln Ω` (envelope
//! theorem: the rate of `h` is `∂ ln P/∂ ln Ω` at fixed `t`, taken by a
//! central difference): a cell is refined (4-fold, up to 6 times: 1/4096 of
//! a cell) when a critical value changes sign across it with equal counts
//! (a second one must then cross too), when `|h|` turns inside it (rates
//! pointing inward) within 4× its change across the cell of zero, or when a
//! pair of critical points is born there near `ln P = 0` (their number
//! differs at the ends, or the slope at an inflection point turns or
//! changes sign, with the critical or inflection values within 4× their
//! change of zero; see [`suspicious`]). A critical value approaching zero
//! monotonically, as at every ordinary fold, needs no refinement: its
//! crossing changes the count. The refinement of one search is capped at
//! [`REFINE_BUDGET`] extra samples, taken in increasing frequency: at
//! extreme parameters (a response curve that is nearly vertical over a
//! wide band) a heuristic could otherwise refine almost every cell to full
//! depth.
//!
//! Each sample's exact isolation is warm started from the sample before
//! it ([`ResponseEquation::fold_indicators_warm`]): the roots of every
//! Rolle level of the previous sample, moved along their rates in `ln Ω`,
//! start a safeguarded Newton polish inside each verified bracket. Same
//! roots, critical and inflection points as the cold isolation to its
//! tolerance (test `warm_isolation_matches_the_cold_one`); on the 24 °C
//! beam's generalised fit 45 evaluations per isolation instead of 91.
//!
//! Measured (test `narrow_windows_just_above_the_cusp_are_found`): at 66
//! levels 1e-6 to 1e-4 above the cusp of random hardening and softening
//! models, every one of the 132 root-count changes of an exact-count grid
//! 5e-7 apart is found as a fold (windows narrower than the 2e-5 spacing
//! of the scan that brackets the level: under 1/300 of a grid cell). The earlier rule (refine where a critical value is
//! within 4× its change of zero, without rates) missed 32 of them and,
//! on the 24 °C beam fit, took 2.3 times as many samples (it refined
//! every cell around each ordinary fold to full depth).

use super::*;

/// Cells of the coarse fold-search grid over the requested frequency range.
pub const GRID: usize = 256;
const MAX_REFINE_DEPTH: u32 = 6;
/// Most extra samples the double-crossing refinement may take in one fold
/// search (4 per refined cell); deterministic, so results stay reproducible.
pub const REFINE_BUDGET: usize = 2 * GRID;

#[derive(Clone, Default)]
struct Sample {
    omega: f64,
    count: usize,
    /// The roots `t = ln x`, increasing (moved out by [`search`]).
    roots: Vec<f64>,
    /// (t, ln P) at each critical point.
    crit: Vec<(f64, f64)>,
    /// (t, slope) at each inflection point.
    infl: Vec<(f64, f64)>,
    /// d(ln P)/d(ln Ω) at each critical point, followed with Ω.
    crit_rate: Vec<f64>,
    /// d(slope)/d(ln Ω) at each inflection point, followed with Ω.
    infl_rate: Vec<f64>,
    /// `(ln P, ∂ ln P/∂ ln Ω)` at each inflection point (at fixed `t`).
    infl_ln_p: Vec<(f64, f64)>,
    /// The roots of every level of the isolation (`t`), the hints of the
    /// next sample's warm start.
    levels: Vec<Vec<f64>>,
    /// Their rates `dt/d ln Ω` per level, from the sample this one was
    /// warm started from (empty for a level whose count differed there):
    /// the next sample's hints are extrapolated linearly.
    velocity: Vec<Vec<f64>>,
    /// Working memory, kept for the next sample made in this one's place
    /// ([`sample_in`]).
    buffers: SampleBuffers,
}

/// Working memory of a sample: the warm start's hints, the isolation's
/// `ln P` at the inflection points and its own buffers.
#[derive(Clone, Default)]
struct SampleBuffers {
    hints: Vec<Vec<f64>>,
    inflection_ln_p: Vec<f64>,
    warm: super::equation::WarmBuffers,
}

/// Relative frequency step of the central difference in [`sample`].
const RATE_STEP: f64 = 1e-6;

/// The fold indicators at `omega` and their rates. With `warm` (a sample
/// at a nearby frequency), the isolation is warm started from its roots
/// per level ([`ResponseEquation::fold_indicators_warm`]: the same roots
/// to the isolation's tolerance, fewer evaluations).
fn sample(r: &ForcedResponse, omega: f64, warm: Option<&Sample>) -> Result<Sample, SolveError> {
    sample_in(r, omega, warm, Sample::default())
}

/// [`sample`] in the memory of `spare`, a sample no longer needed (its
/// contents are discarded): the same numbers, without allocating a
/// sample's dozen vectors afresh (a fit's fold searches take hundreds of
/// thousands of samples).
fn sample_in(
    r: &ForcedResponse,
    omega: f64,
    warm: Option<&Sample>,
    spare: Sample,
) -> Result<Sample, SolveError> {
    let Sample {
        roots,
        crit,
        infl,
        mut crit_rate,
        mut infl_rate,
        mut infl_ln_p,
        mut levels,
        mut velocity,
        mut buffers,
        ..
    } = spare;
    let eq = r.equation(omega);
    let warm = warm.filter(|_| !crate::power_sum::cold_requested());
    // hints: the warm sample's roots per level, moved by their rates
    let hints = &mut buffers.hints;
    match warm {
        None => hints.clear(),
        Some(s) => {
            let dw = (omega / s.omega).ln();
            crate::power_sum::clear_rows(hints, s.levels.len());
            for (k, (h, ts)) in hints.iter_mut().zip(&s.levels).enumerate() {
                match s.velocity.get(k) {
                    Some(v) if v.len() == ts.len() => {
                        h.extend(ts.iter().zip(v).map(|(t, v)| t + v * dw));
                    }
                    _ => h.extend_from_slice(ts),
                }
            }
        }
    }
    let mut ind = super::equation::FoldIndicators {
        roots,
        critical: crit,
        inflection: infl,
        inflection_ln_p: std::mem::take(&mut buffers.inflection_ln_p),
        e_min: 0.0,
    };
    eq.fold_indicators_warm_into(&buffers.hints, &mut levels, &mut ind, &mut buffers.warm)
        .map_err(|e| with_omega(e, omega))?;
    match warm {
        None => velocity.clear(),
        Some(s) => {
            let dw = (omega / s.omega).ln();
            crate::power_sum::clear_rows(&mut velocity, levels.len().min(s.levels.len()));
            for ((v, now), then) in velocity.iter_mut().zip(&levels).zip(&s.levels) {
                if now.len() == then.len() && dw != 0.0 {
                    v.extend(now.iter().zip(then).map(|(a, b)| (a - b) / dw));
                }
            }
        }
    }
    // Rates of change with ln Ω, by central differences in Ω at fixed t.
    // By the envelope theorem that is the total derivative of a critical
    // value (∂ ln P/∂t = 0 there, so the motion of t_c does not count). At
    // an inflection point the slope's own t-derivative is `e₁′ ×` the slope
    // (`e₁′` the lowest exponent of the level-1 sum), so the rate is exact
    // where the slope is zero — where it matters.
    let (lo, hi) = (
        r.equation(omega * (-RATE_STEP).exp()),
        r.equation(omega * RATE_STEP.exp()),
    );
    crit_rate.clear();
    crit_rate.extend(
        ind.critical
            .iter()
            .map(|&(t, _)| (hi.ln_p(t) - lo.ln_p(t)) / (2.0 * RATE_STEP)),
    );
    // (level1 and ln P of each side from one evaluation of its parts; ln P
    // at the point itself from the isolation)
    infl_rate.clear();
    infl_ln_p.clear();
    for (&(t, _), &lp) in ind.inflection.iter().zip(&ind.inflection_ln_p) {
        let (h1, hp) = hi.level1_and_ln_p(t, ind.e_min);
        let (l1, lp_lo) = lo.level1_and_ln_p(t, ind.e_min);
        infl_rate.push((h1 - l1) / (2.0 * RATE_STEP));
        infl_ln_p.push((lp, (hp - lp_lo) / (2.0 * RATE_STEP)));
    }
    buffers.inflection_ln_p = ind.inflection_ln_p;
    Ok(Sample {
        omega,
        count: ind.roots.len(),
        roots: ind.roots,
        crit: ind.critical,
        infl: ind.inflection,
        crit_rate,
        infl_rate,
        infl_ln_p,
        levels,
        velocity,
        buffers,
    })
}

impl Sample {
    /// The roots moved out (`locate` needs only counts), with the critical
    /// points.
    fn isolated(&mut self) -> Isolated {
        Isolated {
            roots: std::mem::take(&mut self.roots),
            crit: self.crit.iter().map(|c| c.0).collect(),
        }
    }
}

/// A value followed across a cell: `(value, d value/d ln Ω)` at each end.
type Tracked = ((f64, f64), (f64, f64));

/// `true` if `v` is within 4× `scale` of zero (or not a number).
// `!(x >= y)` on purpose: a NaN counts as near (the cell is refined).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn near_zero(v: f64, scale: f64) -> bool {
    !(v.abs() >= 4.0 * scale)
}

/// `true` if a value followed across a cell of width `w` (in ln Ω) may
/// cross zero twice inside it although its signs at the ends agree, or
/// crosses once (then another value crosses too, since the root counts at
/// the ends agree: a hysteresis window inside the cell). A double crossing
/// needs `|v|` to turn inside the cell: its rates at the ends point inward
/// (falling at the lower end, rising at the upper), and an end value within
/// 4× the change the rates or the values make across the cell. A value
/// that approaches zero monotonically, as at every ordinary fold, needs no
/// refinement (its crossing changes the root count).
fn may_cross_twice(((va, ra), (vb, rb)): Tracked, w: f64) -> bool {
    if (va > 0.0) != (vb > 0.0) {
        return true;
    }
    let sg = va.signum();
    let (ga, gb) = (sg * ra * w, sg * rb * w);
    if !(ga.is_finite() && gb.is_finite()) {
        return true;
    }
    let change = (va - vb).abs().max(ga.abs()).max(gb.abs());
    ga < 0.0 && gb > 0.0 && near_zero(va.abs().min(vb.abs()), change)
}

pub(crate) fn with_omega(e: SolveError, omega: f64) -> SolveError {
    match e {
        SolveError::Overflow { amplitude, .. } => SolveError::Overflow { amplitude, omega },
        other => other,
    }
}

/// A fold may hide in the cell (a, b) although the root counts agree
/// (module docs): a critical value `ln P` may cross zero twice (a narrow
/// hysteresis window), or a pair of critical points may be born (and die)
/// inside the cell near `ln P = 0`.
///
/// - Critical values present at both ends: [`may_cross_twice`].
/// - A pair of critical points born or dying inside the cell (their number
///   differs at the ends): refined when a critical value at either end is
///   within 4× its change across the cell of zero. The premise: a newborn
///   pair's values move apart from their birth value without turning
///   inside one cell, and a single crossing of zero changes the root
///   count, so far from zero no fold hides (the cusp test checks it).
/// - Inflection points (where pairs of critical points are born): their
///   slopes as the critical values, or their number differing, count only
///   where `ln P` at the inflection point — the value a newborn pair starts
///   from — is within 4× its change across the cell of zero.
fn suspicious(a: &Sample, b: &Sample) -> bool {
    let w = (b.omega / a.omega).ln();
    let crit = |s: &Sample, k: usize| (s.crit[k].1, s.crit_rate[k]);
    if a.crit.len() == b.crit.len() {
        if (0..a.crit.len()).any(|k| may_cross_twice((crit(a, k), crit(b, k)), w)) {
            return true;
        }
    } else if [a, b]
        .iter()
        .any(|s| (0..s.crit.len()).any(|k| near_zero(s.crit[k].1, s.crit_rate[k].abs() * w)))
    {
        return true;
    }
    // where a pair is born: ln P at the inflection points
    let lnp_near_zero = |k: Option<usize>| {
        let spread = |s: &Sample, k: usize| s.infl_ln_p[k].1.abs() * w;
        match k {
            Some(k) => {
                let (qa, qb) = (a.infl_ln_p[k].0, b.infl_ln_p[k].0);
                (qa > 0.0) != (qb > 0.0)
                    || near_zero(
                        qa.abs().min(qb.abs()),
                        (qa - qb).abs().max(spread(a, k)).max(spread(b, k)),
                    )
            }
            None => [a, b]
                .iter()
                .any(|s| (0..s.infl.len()).any(|k| near_zero(s.infl_ln_p[k].0, spread(s, k)))),
        }
    };
    let infl = |s: &Sample, k: usize| (s.infl[k].1, s.infl_rate[k]);
    if a.infl.len() == b.infl.len() {
        (0..a.infl.len())
            .any(|k| may_cross_twice((infl(a, k), infl(b, k)), w) && lnp_near_zero(Some(k)))
    } else {
        lnp_near_zero(None)
    }
}

/// How a fold is located inside a cell whose root count changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Locator {
    /// Brent on the critical value, bisection on the count where that
    /// does not apply (module docs).
    CriticalValue,
    /// Bisection on the count only (the test oracle).
    #[cfg_attr(not(test), allow(dead_code))]
    Count,
}

/// The local minimum (`minimum`) or maximum of `ln P` nearest `t0` in the
/// direction its slope points: the slope `d ln P/dt` is bracketed by
/// doubling steps from `t0` (a minimum has slope < 0 on its left and > 0
/// on its right) and its zero found by Brent's method to `2ε`. `None` if
/// no bracket is found within 40 doublings. (The extrema near a lightly
/// damped resonance are narrow dips, so Newton from the previous
/// frequency's extremum overshoots; the bracket does not.)
fn extremum_near(eq: &ResponseEquation, t0: f64, minimum: bool) -> Option<f64> {
    let slope = |t: f64| {
        let (_, s) = eq.ln_p_and_slope(t);
        if minimum {
            s
        } else {
            -s
        }
    };
    let s0 = slope(t0);
    if !s0.is_finite() {
        return None;
    }
    if s0 == 0.0 {
        return Some(t0);
    }
    // the extremum lies where the (signed) slope turns positive: to the
    // right of t0 if it is negative there, else to the left
    let dir = if s0 < 0.0 { 1.0 } else { -1.0 };
    let mut step = 1e-6 * (1.0 + t0.abs());
    let (mut near, mut s_near) = (t0, s0);
    for _ in 0..40 {
        let far = t0 + dir * step;
        let s_far = slope(far);
        if !s_far.is_finite() {
            return None;
        }
        if (s_far > 0.0) != (s_near > 0.0) {
            let (lo, flo, hi, fhi) = if near < far {
                (near, s_near, far, s_far)
            } else {
                (far, s_far, near, s_near)
            };
            return Some(crate::power_sum::brent(&slope, lo, hi, flo, fhi));
        }
        (near, s_near) = (far, s_far);
        step *= 2.0;
    }
    None
}

/// The fold in the cell `(a, b)` as the zero of the critical value
/// (module docs), or `None` where that method does not apply.
fn locate_by_critical_value(r: &ForcedResponse, a: &Sample, b: &Sample) -> Option<Fold> {
    if a.count.abs_diff(b.count) != 2 || a.crit.len() != b.crit.len() {
        return None;
    }
    // the one extremum whose value changes sign across the cell
    let mut changing = (0..a.crit.len()).filter(|&k| (a.crit[k].1 > 0.0) != (b.crit[k].1 > 0.0));
    let k = changing.next()?;
    if changing.next().is_some() {
        return None;
    }
    // between the merging roots ln P dips below zero (a minimum) or rises
    // above it (a maximum) on the side that has them
    let pair_side = if b.count > a.count { b } else { a };
    let minimum = pair_side.crit[k].1 < 0.0;
    let (eq_a, eq_b) = (r.equation(a.omega), r.equation(b.omega));
    let ta = extremum_near(&eq_a, a.crit[k].0, minimum)?;
    let tb = extremum_near(&eq_b, b.crit[k].0, minimum)?;
    let (ha, hb) = (eq_a.ln_p(ta), eq_b.ln_p(tb));
    if !(ha.is_finite() && hb.is_finite() && ha != 0.0 && hb != 0.0 && (ha > 0.0) != (hb > 0.0)) {
        return None;
    }
    // each evaluation follows the extremum from the one found at the
    // nearest frequency evaluated so far
    let seen = std::cell::RefCell::new(vec![(a.omega, ta), (b.omega, tb)]);
    let failed = std::cell::Cell::new(false);
    let start = |w: f64| {
        seen.borrow()
            .iter()
            .min_by(|p, q| (p.0 - w).abs().total_cmp(&(q.0 - w).abs()))
            .map_or(ta, |p| p.1)
    };
    let h = |w: f64| {
        let eq = r.equation(w);
        match extremum_near(&eq, start(w), minimum) {
            Some(t) => {
                seen.borrow_mut().push((w, t));
                eq.ln_p(t)
            }
            None => {
                failed.set(true);
                // ends the search
                0.0
            }
        }
    };
    let omega = crate::power_sum::brent(&h, a.omega, b.omega, ha, hb);
    if failed.get() || !(omega > a.omega && omega < b.omega) {
        return None;
    }
    let t = extremum_near(&r.equation(omega), start(omega), minimum)?;
    let amplitude = t.exp() * r.scale;
    if !amplitude.is_finite() {
        return None;
    }
    // Verification by the exact root count just either side: it rules out
    // a zero of h made by the followed extremum switching to another one
    // between evaluations (h then jumps). Two root isolations instead of
    // the ~45 of the bisection.
    let count = |w: f64| r.equation(w).roots_t().map(|v| v.len()).ok();
    let (below, above) = (omega * (1.0 - 1e-9), omega * (1.0 + 1e-9));
    if below <= a.omega || above >= b.omega {
        return None;
    }
    (count(below)? == a.count && count(above)? == b.count).then_some(Fold {
        omega,
        amplitude,
        pair_above: b.count > a.count,
    })
}

fn locate(
    r: &ForcedResponse,
    a: &Sample,
    b: &Sample,
    depth: u32,
    budget: &mut usize,
    locator: Locator,
    out: &mut Vec<Fold>,
) -> Result<(), SolveError> {
    if a.count == b.count {
        if depth >= MAX_REFINE_DEPTH || *budget < 4 || !suspicious(a, b) {
            return Ok(());
        }
        *budget -= 4;
        // refine: 4 sub-cells
        let mut prev = a.clone();
        for k in 1..=4 {
            let w = if k == 4 {
                b.omega
            } else {
                a.omega * (b.omega / a.omega).powf(k as f64 / 4.0)
            };
            let s = sample(r, w, Some(&prev))?;
            locate(r, &prev, &s, depth + 1, budget, locator, out)?;
            prev = s;
        }
        return Ok(());
    }
    // counts differ
    if locator == Locator::CriticalValue {
        if let Some(f) = locate_by_critical_value(r, a, b) {
            #[cfg(test)]
            tests::BY_VALUE.with(|c| c.set(c.get() + 1));
            out.push(f);
            return Ok(());
        }
    }
    // bisect on the count
    let (mut lo, mut hi) = (a.omega, b.omega);
    let (mut n_lo, n_hi) = (a.count, b.count);
    while (hi - lo) > 4.0 * f64::EPSILON * hi {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let n_mid = r
            .equation(mid)
            .roots_t()
            .map_err(|e| with_omega(e, mid))?
            .len();
        if n_mid == n_lo {
            lo = mid;
            n_lo = n_mid;
        } else if n_mid == n_hi {
            hi = mid;
        } else {
            // more than one fold in (lo, hi): split and recurse on both halves
            let s_lo = sample(r, lo, Some(a))?;
            let s_mid = sample(r, mid, Some(&s_lo))?;
            let s_hi = sample(r, hi, Some(&s_mid))?;
            locate(r, &s_lo, &s_mid, depth, budget, locator, out)?;
            locate(r, &s_mid, &s_hi, depth, budget, locator, out)?;
            return Ok(());
        }
    }
    let pair_above = n_hi > n_lo;
    let omega = 0.5 * (lo + hi);
    // amplitude: the critical point of the side that has the pair, closest to ln P = 0
    let side = if pair_above { hi } else { lo };
    let eq = r.equation(side);
    let t = eq
        .critical_points_t()
        .map_err(|e| with_omega(e, side))?
        .into_iter()
        .min_by(|x, y| eq.ln_p(*x).abs().total_cmp(&eq.ln_p(*y).abs()));
    if let Some(t) = t {
        out.push(Fold {
            omega,
            amplitude: t.exp() * r.scale,
            pair_above,
        });
    }
    Ok(())
}

pub(crate) fn find_folds(r: &ForcedResponse, lo: f64, hi: f64) -> Result<Vec<Fold>, SolveError> {
    find_folds_with(r, lo, hi, Locator::CriticalValue)
}

/// The lowest fold in `[lo, hi]` at which a pair of roots vanishes with
/// increasing frequency (`pair_above == false`: where a branch followed
/// upwards ends), or `None`: the fold [`find_folds`] would list first among
/// those, found by the same search stopped after the first grid cell that
/// holds one (the cells before it are searched as there, so it is the same
/// fold to the last bit; test `first_fold_ending_upwards_is_find_folds_first`).
pub(crate) fn first_fold_ending_upwards(
    r: &ForcedResponse,
    lo: f64,
    hi: f64,
) -> Result<Option<Fold>, SolveError> {
    let (grid, eqs) = fixed_grid(r, lo, hi)?;
    let (folds, _) = search_until(r, &grid, &eqs, Locator::CriticalValue, Some(false))?;
    Ok(folds.into_iter().find(|f| !f.pair_above))
}

/// The fixed log-spaced grid of [`GRID`] cells over `[lo, hi]` and its
/// equations.
fn fixed_grid(
    r: &ForcedResponse,
    lo: f64,
    hi: f64,
) -> Result<(Vec<f64>, Vec<ResponseEquation>), SolveError> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Err(ParameterError::InvalidRange { min: lo, max: hi }.into());
    }
    let grid: Vec<f64> = (0..=GRID)
        .map(|i| {
            if i == GRID {
                hi
            } else {
                lo * (hi / lo).powf(i as f64 / GRID as f64)
            }
        })
        .collect();
    let eqs: Vec<_> = grid.iter().map(|&w| r.equation(w)).collect();
    Ok((grid, eqs))
}

fn find_folds_with(
    r: &ForcedResponse,
    lo: f64,
    hi: f64,
    locator: Locator,
) -> Result<Vec<Fold>, SolveError> {
    let (grid, eqs) = fixed_grid(r, lo, hi)?;
    Ok(search(r, &grid, &eqs, locator)?.0)
}

/// The roots (`t = ln x`, increasing) at each step of a sweep where they
/// are known without another isolation.
pub(crate) type GridRoots = Vec<Option<Vec<f64>>>;

/// What the fold search isolated at a point of its grid: the roots and the
/// critical points separating them (`t = ln x`, increasing; no critical
/// points where Descartes' rule settled the count).
#[derive(Debug, Clone, Default)]
pub(crate) struct Isolated {
    roots: Vec<f64>,
    crit: Vec<f64>,
}

/// The folds of a stepped sweep over `[ω₀, ω_last]`, searched on the
/// sweep's own steps (`omegas`, increasing; `eqs` their equations) instead
/// of the fixed grid, at most two cells of the fixed grid
/// (`2 ln(ω_last/ω₀)/GRID`) apart: a step cell wider than that is split
/// evenly in `ln Ω` until it is not, and of denser steps only a subset is
/// sampled (the last step within that distance of the previous sample).
/// (The refinement finds every window of the cusp test on a grid of
/// `GRID/2` cells as well, on sparse and on dense steps alike; at four
/// grid cells it misses some.) Also returns the roots (`t = ln x`,
/// increasing) at every step where they are known without another
/// isolation, which the sweep then need not isolate again: at a sampled
/// step those the search isolated; at a step between two samples with
/// equal counts and no fold between them, those bracketed from the
/// samples' roots and critical points
/// ([`ResponseEquation::roots_bracketed`], which declines rather than
/// guesses). Measured on the 24 °C beam's generalised fit (6 × 1024
/// steps): the all-point refinement 4.5 s → 1.1 s, the whole fit 8.9 s →
/// 4.1 s. The folds are those of [`find_folds`] (located from other cell
/// ends, so equal to ~1e-14).
pub(crate) fn find_folds_on_steps(
    r: &ForcedResponse,
    omegas: &[f64],
    eqs: &[ResponseEquation],
) -> Result<(Vec<Fold>, GridRoots), SolveError> {
    let n = omegas.len();
    if n < 2 {
        return Ok((Vec::new(), vec![None; n]));
    }
    let widest = 2.0 * (omegas[n - 1] / omegas[0]).ln() / GRID as f64;
    let mut grid = vec![omegas[0]];
    let mut grid_eqs = vec![eqs[0]];
    // at[i]: the grid index of step i, if the search samples it
    let mut at: Vec<Option<usize>> = vec![None; n];
    at[0] = Some(0);
    let mut last = 0;
    for i in 1..n {
        // a step closer than `widest` to the last sample, and whose next
        // step is too, is left out of the search (its roots follow below)
        if i + 1 < n && (omegas[i + 1] / omegas[last]).ln() <= widest {
            continue;
        }
        let (a, b) = (omegas[last], omegas[i]);
        let parts = ((b / a).ln() / widest * (1.0 - 1e-12)).ceil().max(1.0) as usize;
        for k in 1..parts {
            let w = a * (b / a).powf(k as f64 / parts as f64);
            grid.push(w);
            grid_eqs.push(r.equation(w));
        }
        at[i] = Some(grid.len());
        grid.push(b);
        grid_eqs.push(eqs[i]);
        last = i;
    }
    let (folds, mut isolated) = search(r, &grid, &grid_eqs, Locator::CriticalValue)?;
    let mut roots: GridRoots = vec![None; n];
    // steps between two samples: the count there is the samples' (equal,
    // no fold between them), and their roots and critical points bracket
    // the roots (`roots_bracketed`); else the sweep isolates them itself
    let mut cell = (0, 0);
    // (the interpolated roots and critical points, and the hints, in the
    // same memory from step to step)
    let (mut rm, mut cm, mut hints) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        match at[i] {
            Some(g) => cell = (g, g),
            None => {
                if cell.0 == cell.1 {
                    // the cell's upper sample: the next sampled step (no
                    // points are inserted inside a cell with steps)
                    let g = at[i + 1..].iter().find_map(|&g| g).unwrap_or(cell.0);
                    cell = (cell.0, g);
                }
                let (ga, gb) = cell;
                let (Some(ia), Some(ib)) = (&isolated[ga], &isolated[gb]) else {
                    continue;
                };
                let (wa, wb) = (grid[ga], grid[gb]);
                if ia.roots.len() != ib.roots.len()
                    || folds.iter().any(|f| f.omega >= wa && f.omega <= wb)
                {
                    continue;
                }
                // the samples' roots and critical points, and the same
                // interpolated in ln Ω: a lightly damped resonance dips
                // below ln P = 0 over a width of t far smaller than it
                // moves across a cell
                let s = (omegas[i] / wa).ln() / (wb / wa).ln();
                let lerp = |to: &mut Vec<f64>, p: &[f64], q: &[f64]| {
                    to.clear();
                    if p.len() == q.len() {
                        to.extend(p.iter().zip(q).map(|(x, y)| x + s * (y - x)));
                    }
                };
                lerp(&mut rm, &ia.roots, &ib.roots);
                lerp(&mut cm, &ia.crit, &ib.crit);
                hints.clear();
                for part in [&ia.roots, &ia.crit, &ib.roots, &ib.crit, &rm, &cm] {
                    hints.extend_from_slice(part);
                }
                roots[i] = eqs[i].roots_bracketed(ia.roots.len(), &mut hints, &cm);
            }
        }
    }
    for (i, g) in at.iter().enumerate() {
        if let Some(g) = g {
            roots[i] = isolated[*g].take().map(|s| s.roots);
        }
    }
    Ok((folds, roots))
}

/// The fold search on `grid` (increasing frequencies, `eqs` their
/// equations; module docs): the folds, sorted, and the roots at each grid
/// point that was sampled.
fn search(
    r: &ForcedResponse,
    grid: &[f64],
    eqs: &[ResponseEquation],
    locator: Locator,
) -> Result<(Vec<Fold>, Vec<Option<Isolated>>), SolveError> {
    search_until(r, grid, eqs, locator, None)
}

/// [`search`], stopped after the first cell (with its refinement) that
/// holds a fold with `pair_above == stop` when `stop` is given (the grid
/// points beyond it are not sampled).
fn search_until(
    r: &ForcedResponse,
    grid: &[f64],
    eqs: &[ResponseEquation],
    locator: Locator,
    stop: Option<bool>,
) -> Result<(Vec<Fold>, Vec<Option<Isolated>>), SolveError> {
    let mut out = Vec::new();
    let mut roots: Vec<Option<Isolated>> = vec![None; grid.len()];
    // Cells where the analytic one-root certificate holds contain no fold:
    // skip them (no root isolation needed there).
    let fast = super::certificate::fast_path_possible(r);
    let mut budget = REFINE_BUDGET;
    let mut prev: Option<Sample> = None;
    // the last sample taken (warm start of the next one), wherever it was
    let mut last: Option<Sample> = None;
    // samples no longer needed, whose memory the next ones reuse
    let mut spare: Vec<Sample> = Vec::new();
    for i in 1..grid.len() {
        if fast && super::certificate::certify_cell(&eqs[i - 1], &eqs[i]) {
            if let Some(p) = prev.take() {
                spare.extend(last.replace(p));
            }
            continue;
        }
        // the roots move out of the samples (`locate` needs only counts)
        let a = match prev.take() {
            Some(s) => s,
            None => {
                let reuse = spare.pop().unwrap_or_default();
                let mut s = sample_in(r, grid[i - 1], last.as_ref(), reuse)?;
                roots[i - 1] = Some(s.isolated());
                s
            }
        };
        let reuse = spare.pop().unwrap_or_default();
        let mut b = sample_in(r, grid[i], Some(&a), reuse)?;
        roots[i] = Some(b.isolated());
        locate(r, &a, &b, 0, &mut budget, locator, &mut out)?;
        if stop.is_some_and(|p| out.iter().any(|f| f.pair_above == p)) {
            break;
        }
        spare.push(a);
        prev = Some(b);
    }
    out.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    out.dedup_by(|a, b| {
        (a.omega - b.omega).abs() <= 1e-13 * b.omega && a.pair_above == b.pair_above
    });
    Ok((out, roots))
}

/// Phase quadrature: `S = 0` (phase lag 90°) on the response curve, i.e. the
/// curve meets the backbone. Along the backbone `ν_bb(x)`
/// (exact: `ν² = 1 + b x^ρ`; modulation: `ν = 1 + b x^ρ/2`) solve
/// `h(t) = ln(x · D(x, ν_bb(x))) = 0`, `x = e^t`.
pub(crate) fn phase_quadrature(r: &ForcedResponse) -> Result<Option<PhaseQuadrature>, SolveError> {
    let m = r.model;
    let zeta = m.zeta();
    let (b, c, rho, eta) = (r.b, r.c, m.rho, m.eta);
    let exact = r.formulation == Formulation::HarmonicBalance;
    let nu_of = |t: f64| -> f64 {
        let k = if b == 0.0 { 0.0 } else { b * (rho * t).exp() };
        if exact {
            let v = 1.0 + k;
            if v > 0.0 {
                v.sqrt()
            } else {
                f64::NAN
            }
        } else {
            let v = 1.0 + 0.5 * k;
            if v > 0.0 {
                v
            } else {
                f64::NAN
            }
        }
    };
    let h = |t: f64| -> f64 {
        let nu = nu_of(t);
        if nu.is_nan() {
            // no positive backbone frequency at this amplitude
            return f64::NAN;
        }
        let xe = if c == 0.0 { 0.0 } else { c * (eta * t).exp() };
        let d = if exact {
            2.0 * zeta * nu + xe * nu.powf(1.0 + eta)
        } else {
            2.0 * zeta + xe
        };
        t + d.ln()
    };
    let finish = |t: f64| {
        let (omega, amplitude) = (nu_of(t) * r.omega_n, t.exp() * r.scale);
        (omega.is_finite() && amplitude.is_finite()).then_some(PhaseQuadrature { omega, amplitude })
    };
    let monotone = b >= 0.0 && rho >= 0.0 && (c == 0.0 || eta >= -1.0) && zeta > 0.0;
    if monotone {
        // h increasing: expand a bracket from t = 0, then Brent.
        let (mut a, mut fa) = (0.0, h(0.0));
        let mut step = if fa < 0.0 { 1.0 } else { -1.0 };
        for _ in 0..200 {
            let t = a + step;
            let ft = h(t);
            if !ft.is_finite() {
                return Ok(None);
            }
            if (ft > 0.0) != (fa > 0.0) {
                let (lo, flo, hi, fhi) = if a < t {
                    (a, fa, t, ft)
                } else {
                    (t, ft, a, fa)
                };
                return Ok(finish(crate::power_sum::brent(&h, lo, hi, flo, fhi)));
            }
            a = t;
            fa = ft;
            step *= 1.5;
        }
        return Ok(None);
    }
    // general case (softening, negative exponents): scan ln x upwards and
    // keep the first (smallest-amplitude) crossing — the resonance peak of
    // the branch that grows out of the linear resonance; later crossings lie
    // on detached or unbounded large-amplitude branches.
    let (t0, t1, n) = (-40.0, 40.0, 1600);
    let mut prev = (t0, h(t0));
    for i in 1..=n {
        let t = t0 + (t1 - t0) * i as f64 / n as f64;
        let ft = h(t);
        if ft.is_finite() && prev.1.is_finite() && (ft > 0.0) != (prev.1 > 0.0) {
            return Ok(finish(crate::power_sum::brent(&h, prev.0, t, prev.1, ft)));
        }
        prev = (t, ft);
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::NormalisedModel;

    thread_local! {
        /// Folds located by the critical value (not by the fallback).
        pub(super) static BY_VALUE: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
    }

    /// A random model of the fold tests: `ω_n = wn`, ζ 1e-3 … 3e-2,
    /// hardening (softening every fourth case), ρ 0.5 … 4.5, no nonlinear
    /// damping in 30 % of cases, η −0.9 … 3.1 (Coulomb friction every fifth).
    fn random_model(rnd: &mut impl FnMut() -> f64, case: usize, wn: f64) -> NormalisedModel {
        NormalisedModel {
            alpha: wn * wn,
            delta: 2.0 * wn * 10f64.powf(-3.0 + 1.5 * rnd()),
            beta: if case % 4 == 3 { -1.0 } else { 1.0 } * 10f64.powf(-1.0 + 3.0 * rnd()),
            rho: 0.5 + 4.0 * rnd(),
            kappa: if rnd() < 0.3 {
                0.0
            } else {
                10f64.powf(-4.0 + 3.0 * rnd())
            },
            eta: match case % 5 {
                0 => -1.0,
                _ => -0.9 + 4.0 * rnd(),
            },
        }
    }

    /// A random model of the fold tests ([`random_model`]) at a random
    /// forcing level γ (10^−0.5 … 10), with its forced response (`None`
    /// where the model admits none).
    fn random_response(
        rnd: &mut impl FnMut() -> f64,
        case: usize,
        wn: f64,
    ) -> Option<(NormalisedModel, f64, ForcedResponse)> {
        let model = random_model(rnd, case, wn);
        let gamma = 10f64.powf(-0.5 + 1.5 * rnd());
        let r =
            ForcedResponse::from_normalised(&model, gamma, Formulation::HarmonicBalance).ok()?;
        Some((model, gamma, r))
    }

    /// Narrow hysteresis windows just above the cusp, against an exact-count
    /// oracle: for random hardening and softening models (η down to Coulomb
    /// friction) the level where three roots first appear within ±3 % of
    /// the resonance is bracketed (a 3000-frequency exact-count scan per
    /// trial level), and at levels 1e-6, 1e-5 and 1e-4 above it the root
    /// count is taken on a 4000-frequency grid across the window (5e-7
    /// apart). Every count change there must be a fold the search finds
    /// over `[0.5, 3] ω_n` (256 grid cells of 0.7 %: the windows are under
    /// 1/300 of a cell), and that a sweep over `GRID/2 + 1` log-spaced steps
    /// finds on its own steps (cells two grid cells wide, the widest it
    /// searches on).
    #[test]
    fn narrow_windows_just_above_the_cusp_are_found() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x5eed_c05b_0000_0001u64);
        let (mut levels, mut changes, mut missed) = (0, 0, Vec::new());
        for case in 0..40 {
            let wn = 10.0;
            let model = random_model(&mut rnd, case, wn);
            let response = |g: f64| {
                ForcedResponse::from_normalised(&model, g, Formulation::HarmonicBalance).ok()
            };
            let count = |r: &ForcedResponse, w: f64| r.steady_states(w).map(|s| s.roots.len());
            // (first, last) scan frequency with three roots or more
            let window = |g: f64| -> Option<(f64, f64)> {
                let r = response(g)?;
                let centre = r.phase_quadrature().ok()??.omega;
                let n = 3000;
                let mut hit: Option<(f64, f64)> = None;
                for i in 0..=n {
                    let w = centre * (0.97 + 0.06 * i as f64 / n as f64);
                    if count(&r, w).ok()? >= 3 {
                        hit = Some(hit.map_or((w, w), |(f, _)| (f, w)));
                    }
                }
                hit
            };
            let (mut lo, mut hi) = (1e-4f64, 1e2f64);
            if window(hi).is_none() || window(lo).is_some() {
                continue;
            }
            for _ in 0..30 {
                let mid = (lo * hi).sqrt();
                if window(mid).is_some() {
                    hi = mid
                } else {
                    lo = mid
                }
            }
            for bump in [1e-6, 1e-5, 1e-4] {
                let g = hi * (1.0 + bump);
                let (Some((first, last)), Some(r)) = (window(g), response(g)) else {
                    continue;
                };
                let (a, b) = (first * (1.0 - 1e-3), last * (1.0 + 1e-3));
                let m = 4000;
                let mut expected = 0;
                let mut prev = None;
                for i in 0..=m {
                    let c = count(&r, a * (b / a).powf(i as f64 / m as f64)).unwrap();
                    expected += usize::from(prev.is_some_and(|p| p != c));
                    prev = Some(c);
                }
                let inside =
                    |f: &Vec<Fold>| f.iter().filter(|f| f.omega >= a && f.omega <= b).count();
                let found = inside(&find_folds(&r, 0.5 * wn, 3.0 * wn).unwrap());
                // a sweep of GRID/2 + 1 log-spaced steps: its cells are two
                // grid cells wide, the widest a sweep searches on
                let steps: Vec<f64> = (0..=GRID / 2)
                    .map(|i| 0.5 * wn * 6f64.powf(i as f64 / (GRID / 2) as f64))
                    .collect();
                let eqs: Vec<_> = steps.iter().map(|&w| r.equation(w)).collect();
                let on_steps = inside(&find_folds_on_steps(&r, &steps, &eqs).unwrap().0);
                // a dense sweep (8 steps per grid cell): the search samples
                // a subset of its steps, two grid cells apart
                let dense: Vec<f64> = (0..=8 * GRID)
                    .map(|i| 0.5 * wn * 6f64.powf(i as f64 / (8 * GRID) as f64))
                    .collect();
                let dense_eqs: Vec<_> = dense.iter().map(|&w| r.equation(w)).collect();
                let on_dense = inside(&find_folds_on_steps(&r, &dense, &dense_eqs).unwrap().0);
                levels += 1;
                changes += expected;
                if found != expected || on_steps != expected || on_dense != expected {
                    missed.push((
                        case,
                        bump,
                        (last - first) / first,
                        expected,
                        found,
                        on_steps,
                        on_dense,
                    ));
                }
            }
        }
        eprintln!("{levels} levels just above the cusp, {changes} count changes");
        assert!(levels >= 60 && changes >= 2 * levels, "{levels} {changes}");
        assert!(
            missed.is_empty(),
            "(case, bump, width, changes, folds found): {missed:?}"
        );
    }

    /// The search on a sweep's own steps against the fixed-grid search: on
    /// random hardening and softening models (η down to Coulomb friction),
    /// with steps uniform in Ω, coarse (40: cells split) and fine (600),
    /// both find the same folds to 1e-12 and the roots handed to the sweep
    /// are the exact isolation's, bit for bit.
    #[test]
    fn step_grid_search_matches_the_fixed_grid() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x57e9_9e1d_0000_0002u64);
        let (mut folds, mut shared, mut worst) = (0, 0, 0.0f64);
        for case in 0..200 {
            let wn = 10.0;
            let Some((model, gamma, r)) = random_response(&mut rnd, case, wn) else {
                continue;
            };
            let (lo, hi) = (0.5 * wn, 3.0 * wn);
            let Ok(fixed) = find_folds(&r, lo, hi) else {
                continue;
            };
            for n in [40, 600] {
                let omegas: Vec<f64> = (0..n)
                    .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                    .collect();
                let eqs: Vec<_> = omegas.iter().map(|&w| r.equation(w)).collect();
                let (on_steps, roots) = find_folds_on_steps(&r, &omegas, &eqs).unwrap();
                assert_eq!(fixed.len(), on_steps.len(), "{model:?} γ={gamma} n={n}");
                for (f, g) in fixed.iter().zip(&on_steps) {
                    assert_eq!(f.pair_above, g.pair_above);
                    assert!(
                        (f.omega - g.omega).abs() <= 1e-12 * f.omega,
                        "{f:?} vs {g:?}"
                    );
                    assert!((f.amplitude - g.amplitude).abs() <= 1e-7 * f.amplitude);
                }
                folds += fixed.len();
                for (eq, ts) in eqs.iter().zip(&roots) {
                    if let Some(ts) = ts {
                        let exact = eq.roots_t().unwrap();
                        assert_eq!(ts.len(), exact.len(), "{model:?} γ={gamma} n={n}");
                        for (t, e) in ts.iter().zip(&exact) {
                            let d = (t - e).abs() / (1.0 + e.abs());
                            worst = worst.max(d);
                            assert!(d <= 1e-14, "{t} vs {e}: {model:?} γ={gamma} n={n}");
                        }
                        shared += 1;
                    }
                }
            }
        }
        eprintln!(
            "{folds} folds; roots of {shared} steps shared with the sweep, \
             largest difference {worst:e} (relative to 1 + |t|)"
        );
        assert!(folds > 200 && shared > 10_000, "{folds} {shared}");
    }

    /// The search stopped at the first fold ending upwards (used for the
    /// fold beyond a measured up-sweep) against the full search's first
    /// such fold (the oracle), bit for bit, on random hardening and
    /// softening models (η down to Coulomb friction) over the range above
    /// the resonance and over a wide range; `None` exactly where the full
    /// search has no such fold.
    #[test]
    fn first_fold_ending_upwards_is_find_folds_first() {
        let mut rnd = crate::harmonic_balance::test_uniform(0xf1e5_7f01_0000_0003u64);
        let (mut found, mut none) = (0, 0);
        for case in 0..300 {
            let wn = 10.0;
            let Some((model, gamma, r)) = random_response(&mut rnd, case, wn) else {
                continue;
            };
            for (lo, hi) in [(wn, 2.0 * wn), (0.5 * wn, 3.0 * wn)] {
                let Ok(all) = find_folds(&r, lo, hi) else {
                    continue;
                };
                let oracle = all.into_iter().find(|f| !f.pair_above);
                let first = first_fold_ending_upwards(&r, lo, hi).unwrap();
                match (oracle, first) {
                    (Some(f), Some(g)) => {
                        assert_eq!(f.omega.to_bits(), g.omega.to_bits(), "{model:?} γ={gamma}");
                        assert_eq!(f.amplitude.to_bits(), g.amplitude.to_bits());
                        assert!(!g.pair_above);
                        found += 1;
                    }
                    (None, None) => none += 1,
                    (f, g) => panic!("{f:?} vs {g:?}: {model:?} γ={gamma}"),
                }
            }
        }
        eprintln!("{found} first folds equal bit for bit, {none} ranges without one");
        assert!(found > 150 && none > 50, "{found} {none}");
    }

    /// The warm-started isolation against the cold one (the oracle): on
    /// 240 random hardening and softening models (η down to Coulomb
    /// friction), along sweeps of 40, 206 and 600 steps uniform in Ω, each
    /// step warm started from the previous step's levels as they are and
    /// extrapolated linearly from the two steps before (as the fold search
    /// does), and every fifth step also from the step five before (a poor
    /// hint) and from none (then the result is the cold one bit for bit):
    /// the roots, critical and inflection points agree in number; roots and
    /// critical points (polished with the accurate evaluators) to
    /// `8ε (1 + |t|)` (measured: 4.6ε), inflection points to 8 × their
    /// rounding band, `ε (1 + |t|) + nε/|f′|` with `f` the expanded level-2
    /// sum scaled to a largest term of 1 (`n` terms; measured 3.9, up to
    /// 31ε (1 + |t|) where the band is wide); the values at the critical
    /// and inflection points to 1e-9.
    /// A sample made in the memory of a discarded one (`sample_in`, as the
    /// search recycles them) is the sample made afresh, bit for bit: the
    /// oracle is `sample` with new memory, warm started alike; the spares
    /// come from other frequencies, models and levels, with more or fewer
    /// roots and levels than the sample made in their place.
    #[test]
    fn a_sample_in_recycled_memory_is_the_fresh_sample() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x5a3e_11c0_0000_0016u64);
        let mut spare = Sample::default();
        let mut compared = 0;
        for case in 0..60 {
            let wn = 10.0;
            let Some((_, _, r)) = random_response(&mut rnd, case, wn) else {
                continue;
            };
            let mut warm: Option<Sample> = None;
            for k in 0..40 {
                let w = wn * (0.7 + 0.02 * k as f64);
                let Ok(fresh) = sample(&r, w, warm.as_ref()) else {
                    warm = None;
                    continue;
                };
                let reused = sample_in(&r, w, warm.as_ref(), std::mem::take(&mut spare))
                    .expect("the fresh sample succeeded");
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let pairs = |v: &[(f64, f64)]| {
                    v.iter()
                        .map(|(x, y)| (x.to_bits(), y.to_bits()))
                        .collect::<Vec<_>>()
                };
                let nested = |v: &[Vec<f64>]| v.iter().map(|l| bits(l)).collect::<Vec<_>>();
                let what = format!("case {case} step {k}");
                assert_eq!(fresh.omega.to_bits(), reused.omega.to_bits(), "{what}");
                assert_eq!(fresh.count, reused.count, "{what}");
                assert_eq!(bits(&fresh.roots), bits(&reused.roots), "{what}");
                assert_eq!(pairs(&fresh.crit), pairs(&reused.crit), "{what}");
                assert_eq!(pairs(&fresh.infl), pairs(&reused.infl), "{what}");
                assert_eq!(bits(&fresh.crit_rate), bits(&reused.crit_rate), "{what}");
                assert_eq!(bits(&fresh.infl_rate), bits(&reused.infl_rate), "{what}");
                assert_eq!(pairs(&fresh.infl_ln_p), pairs(&reused.infl_ln_p), "{what}");
                assert_eq!(nested(&fresh.levels), nested(&reused.levels), "{what}");
                assert_eq!(nested(&fresh.velocity), nested(&reused.velocity), "{what}");
                compared += 1;
                // the next spare: this step's sample or the previous one
                if let Some(old) = warm.replace(fresh) {
                    spare = old;
                }
                if k % 3 == 0 {
                    spare = reused;
                }
            }
        }
        assert!(compared > 1000, "{compared}");
    }

    #[test]
    fn warm_isolation_matches_the_cold_one() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x3a2d_57a2_7000_0003u64);
        let (mut steps, mut points, mut worst, mut worst_infl) = (0usize, 0usize, 0.0f64, 0.0f64);
        let mut models = 0;
        for case in 0..240 {
            let wn = 10.0;
            let model = random_model(&mut rnd, case, wn);
            let gamma = 10f64.powf(-0.5 + 1.5 * rnd());
            let Ok(r) =
                ForcedResponse::from_normalised(&model, gamma, Formulation::HarmonicBalance)
            else {
                continue;
            };
            models += 1;
            let (lo, hi) = (0.5 * wn, 3.0 * wn);
            for n in [40, 206, 600] {
                let omegas: Vec<f64> = (0..n)
                    .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                    .collect();
                // the levels of each step, warm started from the step before
                let mut history: Vec<Vec<Vec<f64>>> = Vec::new();
                for (i, &w) in omegas.iter().enumerate() {
                    let eq = r.equation(w);
                    let Ok(cold) = eq.fold_indicators() else {
                        history.push(Vec::new());
                        continue;
                    };
                    let (ps, u) = eq.scaled_power_sum();
                    let infl_sum = ps.reduced_derivative().reduced_derivative();
                    let previous = |k: usize| history.get(i.wrapping_sub(k)).cloned();
                    let mut starts = vec![previous(1)];
                    if let (Some(p1), Some(p2)) = (previous(1), previous(2)) {
                        // linear extrapolation (the steps are uniform)
                        let dw = (w / omegas[i - 1]).ln() / (omegas[i - 1] / omegas[i - 2]).ln();
                        starts.push(Some(
                            p1.iter()
                                .zip(&p2)
                                .map(|(a, b)| {
                                    if a.len() == b.len() {
                                        a.iter().zip(b).map(|(x, y)| x + (x - y) * dw).collect()
                                    } else {
                                        a.clone()
                                    }
                                })
                                .collect(),
                        ));
                    }
                    if i % 5 == 0 {
                        starts.push(previous(5));
                        starts.push(None);
                    }
                    for (s, start) in starts.iter().enumerate() {
                        let hints = start.as_deref().unwrap_or(&[]);
                        let mut levels = Vec::new();
                        let warm = eq.fold_indicators_warm(hints, &mut levels).unwrap();
                        let what = format!("{model:?} γ={gamma} n={n} Ω={w} start {s}");
                        if start.is_none() {
                            assert_eq!(warm, cold, "{what}");
                        }
                        assert_eq!(warm.roots.len(), cold.roots.len(), "{what}");
                        assert_eq!(warm.critical.len(), cold.critical.len(), "{what}");
                        assert_eq!(warm.inflection.len(), cold.inflection.len(), "{what}");
                        assert_eq!(warm.e_min, cold.e_min);
                        let as_pair = |t: &f64| (*t, 0.0);
                        let top = warm
                            .roots
                            .iter()
                            .map(as_pair)
                            .zip(cold.roots.iter().map(as_pair))
                            .chain(warm.critical.iter().copied().zip(cold.critical.clone()));
                        for ((ta, va), (tb, vb)) in top {
                            let d = (ta - tb).abs() / (1.0 + tb.abs()) / f64::EPSILON;
                            worst = worst.max(d);
                            assert!(d <= 8.0, "{ta} vs {tb} ({d} ε): {what}");
                            assert!((va - vb).abs() <= 1e-9, "{va} vs {vb}: {what}");
                            points += 1;
                        }
                        for (&(ta, va), &(tb, vb)) in warm.inflection.iter().zip(&cold.inflection) {
                            let (_, slope) = infl_sum.eval_scaled_with_slope(tb - u);
                            let band = (1.0 + tb.abs()) * f64::EPSILON
                                + infl_sum.len() as f64 * f64::EPSILON / slope.abs();
                            let d = (ta - tb).abs() / band;
                            worst_infl = worst_infl.max(d);
                            assert!(d <= 8.0, "{ta} vs {tb} ({d} bands): {what}");
                            assert!((va - vb).abs() <= 1e-9, "{va} vs {vb}: {what}");
                            points += 1;
                        }
                        if s == 0 {
                            history.push(levels);
                        }
                    }
                    steps += 1;
                }
            }
        }
        eprintln!(
            "{models} models, {steps} steps, {points} points: largest difference {worst:.2} ε \
             (relative to 1 + |t|), inflection points {worst_infl:.2} rounding bands"
        );
        assert!(models >= 200 && steps > 150_000, "{models} {steps}");
    }

    /// The Brent location on the critical value against its oracle, the
    /// bisection on the exact root count: on random hardening and softening
    /// models (η down to Coulomb friction, both formulations), every fold
    /// the count finds is found by the critical value at the same frequency
    /// (1e-12 relative) and amplitude (1e-7 relative), and directly from a
    /// cell of ±0.1 % around it.
    #[test]
    fn critical_value_location_matches_count_bisection() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x0dd_f01d_5eed_1234u64);
        let (mut folds, mut direct, mut coulomb) = (0, 0, 0);
        for case in 0..400 {
            let wn = 10.0;
            let softening = case % 4 == 3;
            let eta = match case % 5 {
                0 => -1.0,
                1 => 0.0,
                _ => -0.9 + 4.0 * rnd(),
            };
            let model = NormalisedModel {
                alpha: wn * wn,
                delta: 2.0 * wn * 10f64.powf(-3.0 + 1.5 * rnd()),
                beta: if softening { -1.0 } else { 1.0 } * 10f64.powf(-1.0 + 3.0 * rnd()),
                rho: 0.5 + 4.0 * rnd(),
                kappa: if rnd() < 0.3 {
                    0.0
                } else {
                    10f64.powf(-4.0 + 3.0 * rnd())
                },
                eta,
            };
            let gamma = 10f64.powf(-0.5 + 1.5 * rnd());
            let formulation = if case % 2 == 0 {
                Formulation::HarmonicBalance
            } else {
                Formulation::Modulation
            };
            let Ok(r) = ForcedResponse::from_normalised(&model, gamma, formulation) else {
                continue;
            };
            let (lo, hi) = (0.5 * wn, 3.0 * wn);
            let (Ok(by_count), Ok(by_value)) = (
                find_folds_with(&r, lo, hi, Locator::Count),
                find_folds_with(&r, lo, hi, Locator::CriticalValue),
            ) else {
                continue;
            };
            assert_eq!(by_count.len(), by_value.len(), "{model:?} γ={gamma}");
            for (c, v) in by_count.iter().zip(&by_value) {
                assert_eq!(c.pair_above, v.pair_above, "{model:?} γ={gamma}");
                assert!(
                    (c.omega - v.omega).abs() <= 1e-12 * c.omega,
                    "{model:?} γ={gamma}: {c:?} vs {v:?}"
                );
                assert!(
                    (c.amplitude - v.amplitude).abs() <= 1e-7 * c.amplitude,
                    "{model:?} γ={gamma}: {c:?} vs {v:?}"
                );
                folds += 1;
                coulomb += usize::from(model.eta == -1.0 && model.kappa > 0.0);
                // directly, from a cell of ±0.1 % around the fold
                let (Ok(a), Ok(b)) = (
                    sample(&r, c.omega * 0.999, None),
                    sample(&r, c.omega * 1.001, None),
                ) else {
                    continue;
                };
                if let Some(f) = locate_by_critical_value(&r, &a, &b) {
                    assert!((f.omega - c.omega).abs() <= 1e-12 * c.omega);
                    assert_eq!(f.pair_above, c.pair_above);
                    direct += 1;
                }
            }
        }
        let by_value = BY_VALUE.with(|c| c.get());
        eprintln!(
            "{folds} folds ({coulomb} with Coulomb friction): {by_value} located by the \
             critical value in the search, {direct} from a ±0.1 % cell"
        );
        assert!(
            folds > 200 && coulomb > 10 && by_value > folds * 9 / 10 && direct > folds / 2,
            "{folds} {coulomb} {by_value} {direct}"
        );
    }
}
