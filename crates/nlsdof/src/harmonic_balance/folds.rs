//! Fold (saddle-node, jump) frequencies and the phase-quadrature point.
//!
//! A fold is a point of the response curve where two steady states merge:
//! `P(x, ν) = 1` and `∂P/∂x = 0`. As the frequency changes, roots of the
//! response equation appear and vanish in pairs only there, so the number of
//! roots `N(Ω)` (computed exactly by [`ResponseEquation::roots`]) is
//! piecewise constant with jumps of ±2 at the folds.
//!
//! Location: `N(Ω)` on a fixed log-spaced grid of [`GRID`] cells over the
//! requested range (independent of any sweep step), then bisection on `N` to
//! `|ΔΩ|/Ω ≤ 4ε`. `N` changes exactly where the value of `ln P` at the local
//! extremum between the merging roots changes sign, and that value is
//! computed with the unexpanded (accurate) formula, so the fold frequency is
//! found to ~1e-14 relative. Two folds inside one grid cell (a narrow
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

fn locate(
    r: &ForcedResponse,
    a: &Sample,
    b: &Sample,
    depth: u32,
    budget: &mut usize,
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
            locate(r, &prev, &s, depth + 1, budget, out)?;
            prev = s;
        }
        return Ok(());
    }
    // counts differ: bisect on the count
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
            locate(r, &s_lo, &s_mid, depth, budget, out)?;
            locate(r, &s_mid, &s_hi, depth, budget, out)?;
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
        locate(r, &a, &b, 0, &mut budget, &mut out)?;
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
