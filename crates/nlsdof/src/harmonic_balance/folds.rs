//! Fold (saddle-node, jump) frequencies and the phase-quadrature point.
//!
//! A fold is a point of the response curve where two steady states merge:
//! `P(x, ν) = 1` and `∂P/∂x = 0`. As the frequency changes, roots of the
//! response equation appear and vanish in pairs only there, so the number of
//! roots `N(Ω)` (computed exactly by [`ResponseEquation::roots`]) is
//! piecewise constant with jumps of ±2 at the folds.
//!
//! Location: `N(Ω)` on a fixed log-spaced grid of [`GRID`] cells over the
//! requested range (independent of any sweep step). In a cell whose count
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
//! relative either way. Two folds inside one grid cell (a narrow
//! hysteresis window near a cusp) are caught by refining every cell where
//! a local extremum of `ln P` — or, where no extremum exists at the cell
//! ends, the slope of `ln P` at an inflection point — is closer to zero
//! than 4× its change across the cell (refined 4-fold, up to 6 times:
//! 1/4096 of a cell). The refinement of one search is capped at
//! [`REFINE_BUDGET`] extra samples, taken in increasing frequency: at
//! extreme parameters (a response curve that is nearly vertical over a wide
//! band, so that critical values stay near zero everywhere) the heuristic
//! would otherwise refine almost every cell to full depth — thousands of
//! root isolations per sweep for no fold.
//!
//! Limitation (measured in the sixth session with an exact-count grid of
//! 1000 frequencies, 2e-5 apart, around the peak of random models at levels
//! just above their cusp): windows a few 1e-5 wide are missed in about a
//! third of such cases; the test of a 3e-5 Duffing window
//! (`narrow_hysteresis_window_near_the_cusp_is_found`) passes. Such windows
//! lie far inside any measured frequency step.

use super::*;

/// Cells of the coarse fold-search grid over the requested frequency range.
pub const GRID: usize = 256;
const MAX_REFINE_DEPTH: u32 = 6;
/// Most extra samples the double-crossing refinement may take in one fold
/// search (4 per refined cell); deterministic, so results stay reproducible.
pub const REFINE_BUDGET: usize = 2 * GRID;

#[derive(Clone)]
struct Sample {
    omega: f64,
    count: usize,
    /// (t, ln P) at each critical point.
    crit: Vec<(f64, f64)>,
    /// (t, slope) at each inflection point.
    infl: Vec<(f64, f64)>,
}

fn sample(r: &ForcedResponse, omega: f64) -> Result<Sample, SolveError> {
    let ind = r
        .equation(omega)
        .fold_indicators()
        .map_err(|e| with_omega(e, omega))?;
    Ok(Sample {
        omega,
        count: ind.roots.len(),
        crit: ind.critical,
        infl: ind.inflection,
    })
}

/// `true` if one of the paired values may cross zero twice inside the cell:
/// it is closer to zero at an end than 4× its change across the cell.
fn near_double_crossing(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    if a.len() != b.len() {
        return !(a.is_empty() && b.is_empty());
    }
    a.iter().zip(b).any(|(ca, cb)| {
        let change = (ca.1 - cb.1).abs();
        ca.1.abs().min(cb.1.abs()) < 4.0 * change && (ca.1 > 0.0) == (cb.1 > 0.0)
    })
}

pub(crate) fn with_omega(e: SolveError, omega: f64) -> SolveError {
    match e {
        SolveError::Overflow { amplitude, .. } => SolveError::Overflow { amplitude, omega },
        other => other,
    }
}

/// A fold may hide in the cell (a, b) although the root counts agree: a
/// critical value `ln P` may cross zero twice (a narrow hysteresis window),
/// or a pair of critical points may be born and die inside the cell (the
/// slope at an inflection point touching zero, near a cusp).
fn suspicious(a: &Sample, b: &Sample) -> bool {
    near_double_crossing(&a.crit, &b.crit) || near_double_crossing(&a.infl, &b.infl)
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
            let s = sample(r, w)?;
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
            let s_lo = sample(r, lo)?;
            let s_mid = sample(r, mid)?;
            let s_hi = sample(r, hi)?;
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

fn find_folds_with(
    r: &ForcedResponse,
    lo: f64,
    hi: f64,
    locator: Locator,
) -> Result<Vec<Fold>, SolveError> {
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Err(ParameterError::InvalidRange { min: lo, max: hi }.into());
    }
    let mut out = Vec::new();
    let grid: Vec<f64> = (0..=GRID)
        .map(|i| {
            if i == GRID {
                hi
            } else {
                lo * (hi / lo).powf(i as f64 / GRID as f64)
            }
        })
        .collect();
    // Cells where the analytic one-root certificate holds contain no fold:
    // skip them (no root isolation needed there).
    let fast = super::certificate::fast_path_possible(r);
    let eqs: Vec<_> = grid.iter().map(|&w| r.equation(w)).collect();
    let mut budget = REFINE_BUDGET;
    let mut prev: Option<Sample> = None;
    for i in 1..=GRID {
        if fast && super::certificate::certify_cell(&eqs[i - 1], &eqs[i]) {
            prev = None;
            continue;
        }
        let a = match prev.take() {
            Some(s) => s,
            None => sample(r, grid[i - 1])?,
        };
        let b = sample(r, grid[i])?;
        locate(r, &a, &b, 0, &mut budget, locator, &mut out)?;
        prev = Some(b);
    }
    out.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    out.dedup_by(|a, b| {
        (a.omega - b.omega).abs() <= 1e-13 * b.omega && a.pair_above == b.pair_above
    });
    Ok(out)
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
                let (Ok(a), Ok(b)) = (sample(&r, c.omega * 0.999), sample(&r, c.omega * 1.001))
                else {
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
