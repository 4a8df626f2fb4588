//! Stepped-sine branch following, as a sweep on a shaker sees it.
//!
//! Rules (independent of the step size by construction):
//!
//! 1. **Start from rest.** At the first frequency the structure starts at
//!    `x = 0`. If one stable steady state exists it is taken; if several do,
//!    the slow flow `dX/dτ = −i(1 − Z(|X|) X)`, `Z = S + iD` (module docs of
//!    [`super`]) is integrated from `X = 0` and the stable state it settles
//!    on is taken.
//! 2. **Follow the branch.** Between folds the roots of the response equation
//!    are smooth in Ω and cannot cross, so a steady state keeps its *rank*
//!    (index in the amplitude-sorted list). All folds between the first and
//!    last frequency are located first ([`super::folds`]); crossing one
//!    where a new pair of roots is born below the followed one shifts the
//!    rank by +2, a pair dying below shifts it by −2.
//! 3. **Jump at the end of the branch.** When the followed root is one of the
//!    pair that dies at a fold, the state leaves: where `P(x_fold) > 1` just
//!    past the fold the amplitude decreases to the nearest stable root below,
//!    otherwise it increases to the nearest stable root above. The jump is
//!    reported at the fold frequency.
//! 4. **Loss of stability without a fold** (Hopf, possible only for
//!    η < −2): the state moves to the nearest stable root, reported as a
//!    jump at that step.
//! 5. **Sticking** (no root, e.g. Coulomb friction stronger than the input):
//!    the point is reported with `sticking = true`, and motion restarts from
//!    rest (rule 1) where roots exist again.
//!
//! Fast path: where a cheap analytic certificate proves that every frequency
//! between consecutive steps has exactly one root (see [`certify_cell`]),
//! there are no folds, and each step is a safeguarded Newton solve warm
//! started from the previous step.

use super::equation::{amplitude_bound, ResponseEquation, UniqueState};
use super::folds::{find_folds, with_omega};
use super::*;

fn validate_omegas(omegas: &[f64]) -> Result<(), ParameterError> {
    if omegas.is_empty() {
        return Err(ParameterError::Empty {
            name: "frequencies",
        });
    }
    for (i, &w) in omegas.iter().enumerate() {
        if !w.is_finite() {
            return Err(ParameterError::NotFinite {
                name: "frequency",
                value: w,
            });
        }
        if w <= 0.0 {
            return Err(ParameterError::NotPositive {
                name: "frequency",
                value: w,
            });
        }
        if i > 0 && w <= omegas[i - 1] {
            return Err(ParameterError::NotIncreasing {
                index: i,
                value: w,
                previous: omegas[i - 1],
            });
        }
    }
    Ok(())
}

/// Whether the fast-path certificate can apply at all to this response:
/// `ρ ≥ 0` (or no stiffness term) and `η > −1` (or no damping term).
pub(crate) fn fast_path_possible(r: &ForcedResponse) -> bool {
    (r.b == 0.0 || r.model.rho >= 0.0) && (r.c == 0.0 || r.model.eta > -1.0)
}

/// Certificate that `P(x) = 1` has exactly one root for *every* frequency
/// between the two cell ends `a` and `b` (equations at the two ends).
///
/// With `η > −1`, `ρ ≥ 0`, all exponents of `P − 1` except 0 are positive and
///
/// ```text
/// dP/dt = x² [ 2(s₀²+d₀²) + 2(2+ρ) s₀s₁ z + 2(1+ρ) s₁² z² + (≥ 0 damping terms) ],  z = x^ρ
/// ```
///
/// so `P` is increasing — one root, no fold — if `s₀s₁ ≥ 0`, or if the
/// quadratic in `z` has no positive root (`ρ² s₀² < 4(1+ρ) d₀²`), or if it
/// stays positive up to the root bound `x_hi` (`(2+ρ)|s₀s₁| x_hi^ρ < s₀² + d₀²`).
/// `s₀`, `d₀`, `d₁` are monotone in Ω for both formulations, so their
/// extremes over the cell are at its ends and the test holds for the whole
/// cell.
pub(crate) fn certify_cell(a: &ResponseEquation, b: &ResponseEquation) -> bool {
    let s1 = a.s1;
    if s1 == 0.0 || a.rho == 0.0 {
        return true;
    }
    if a.s0 * s1 >= 0.0 && b.s0 * s1 >= 0.0 {
        return true;
    }
    let rho = a.rho;
    let s0_max = a.s0.abs().max(b.s0.abs());
    let s0sq_min = if (a.s0 > 0.0) != (b.s0 > 0.0) {
        0.0
    } else {
        (a.s0 * a.s0).min(b.s0 * b.s0)
    };
    let d0_min = a.d0.min(b.d0);
    if rho * rho * s0_max * s0_max < 4.0 * (1.0 + rho) * d0_min * d0_min {
        return true;
    }
    let rhs = s0sq_min + d0_min * d0_min;
    let lhs_factor = (2.0 + rho) * s0_max * s1.abs();
    // first with the cheap bound x_hi = 1/d₀, then with the tighter one
    if d0_min > 0.0 && lhs_factor * (-rho * d0_min.ln()).exp() < rhs {
        return true;
    }
    let x_hi = amplitude_bound(d0_min, a.d1.min(b.d1), a.eta);
    x_hi.is_finite() && lhs_factor * x_hi.powf(rho) < rhs
}

fn point(r: &ForcedResponse, omega: f64, s: &SteadyState) -> SweepPoint {
    let _ = r;
    SweepPoint {
        omega,
        amplitude: s.amplitude,
        phase: s.phase,
        stable: s.stable,
        sticking: false,
    }
}

fn sticking_point(omega: f64) -> SweepPoint {
    SweepPoint {
        omega,
        amplitude: 0.0,
        phase: 0.0,
        stable: true,
        sticking: true,
    }
}

pub(crate) fn sweep(
    r: &ForcedResponse,
    omegas: &[f64],
    dir: SweepDirection,
) -> Result<Sweep, SolveError> {
    validate_omegas(omegas)?;
    let order: Vec<usize> = match dir {
        SweepDirection::Up => (0..omegas.len()).collect(),
        SweepDirection::Down => (0..omegas.len()).rev().collect(),
    };
    let eqs: Vec<ResponseEquation> = omegas.iter().map(|&w| r.equation(w)).collect();
    let certified = fast_path_possible(r)
        && eqs.windows(2).all(|w| certify_cell(&w[0], &w[1]))
        && (eqs.len() > 1 || certify_cell(&eqs[0], &eqs[0]));
    if certified {
        if let Some(points) = fast_sweep(r, omegas, &eqs, &order) {
            return Ok(Sweep {
                direction: dir,
                points,
                jumps: Vec::new(),
                folds: Vec::new(),
            });
        }
    }
    general_sweep(r, omegas, &order, dir)
}

fn fast_sweep(
    r: &ForcedResponse,
    omegas: &[f64],
    eqs: &[ResponseEquation],
    order: &[usize],
) -> Option<Vec<SweepPoint>> {
    let mut points = Vec::with_capacity(order.len());
    // (omega, t) of the last three steps, newest first
    let mut hist: [(f64, f64); 3] = [(f64::NAN, f64::NAN); 3];
    for (k, &i) in order.iter().enumerate() {
        let eq = &eqs[i];
        let w = omegas[i];
        // any valid upper bound on the root works; 1/d₀ is the cheapest
        let t_max = if eq.d0 > 0.0 {
            -eq.d0.ln()
        } else {
            eq.amplitude_bound().ln()
        };
        let guess = match k {
            0 => -0.5 * (eq.s0 * eq.s0 + eq.d0 * eq.d0).ln(),
            1 => hist[0].1,
            2 => {
                let [(w1, t1), (w0, t0), _] = hist;
                t1 + (t1 - t0) * (w - w1) / (w1 - w0)
            }
            _ => {
                // quadratic (Lagrange) extrapolation through the last three steps
                let [(w2, t2), (w1, t1), (w0, t0)] = hist;
                t2 * (w - w1) * (w - w0) / ((w2 - w1) * (w2 - w0))
                    + t1 * (w - w2) * (w - w0) / ((w1 - w2) * (w1 - w0))
                    + t0 * (w - w2) * (w - w1) / ((w0 - w2) * (w0 - w1))
            }
        };
        let guess = if guess.is_finite() {
            guess.min(t_max)
        } else {
            0.0f64.min(t_max)
        };
        let UniqueState { t, phase, stable } = eq.solve_unique_state(guess, t_max)?;
        points.push(SweepPoint {
            omega: w,
            amplitude: t.exp() * r.scale,
            phase,
            stable,
            sticking: false,
        });
        hist = [(w, t), hist[0], hist[1]];
    }
    Some(points)
}

fn roots_at(r: &ForcedResponse, omega: f64) -> Result<Vec<SteadyState>, SolveError> {
    Ok(r.steady_states(omega)?.roots)
}

/// Rule 1: the stable state reached from rest.
fn from_rest(r: &ForcedResponse, omega: f64, roots: &[SteadyState]) -> usize {
    let stable: Vec<usize> = (0..roots.len()).filter(|&k| roots[k].stable).collect();
    match stable.len() {
        0 => return 0,
        1 => return stable[0],
        _ => {}
    }
    let eq = r.equation(omega);
    if eq.eta <= -1.0 && eq.d1 != 0.0 {
        return stable[0];
    }
    let x = slow_flow_from_rest(&eq);
    let target = x / 1.0;
    *stable
        .iter()
        .min_by(|&&p, &&q| {
            let dp = ((roots[p].amplitude / r.scale) / target).ln().abs();
            let dq = ((roots[q].amplitude / r.scale) / target).ln().abs();
            dp.total_cmp(&dq)
        })
        .unwrap()
}

/// Integrates the averaged (slow-flow) equation `dX/dτ = −i (1 − Z(|X|) X)`
/// from `X = 0` with classical RK4 until `|dX/dτ| < 1e-9 |X|` and returns
/// the final `|X|` (dimensionless amplitude).
fn slow_flow_from_rest(eq: &ResponseEquation) -> f64 {
    let rhs = |re: f64, im: f64| -> (f64, f64) {
        let a = re.hypot(im);
        let (s, d) = if a > 0.0 {
            let t = a.ln();
            let sr = if eq.s1 == 0.0 {
                0.0
            } else {
                eq.s1 * (eq.rho * t).exp()
            };
            let de = if eq.d1 == 0.0 {
                0.0
            } else {
                eq.d1 * (eq.eta * t).exp()
            };
            (eq.s0 + sr, eq.d0 + de)
        } else {
            (eq.s0, eq.d0)
        };
        // 1 − (s + i d)(re + i im) = (1 − s re + d im) − i (s im + d re)
        let (ur, ui) = (1.0 - s * re + d * im, -(s * im + d * re));
        // −i (ur + i ui) = ui − i ur
        (ui, -ur)
    };
    let (mut re, mut im) = (0.0f64, 0.0f64);
    let mut h = 0.1;
    for _ in 0..4_000_000 {
        let (k1r, k1i) = rhs(re, im);
        let scale = 1.0 + (k1r.hypot(k1i) / (1e-300 + re.hypot(im))).min(1e6);
        h = (0.2 / scale).min(h * 1.5).max(1e-6);
        let (k2r, k2i) = rhs(re + 0.5 * h * k1r, im + 0.5 * h * k1i);
        let (k3r, k3i) = rhs(re + 0.5 * h * k2r, im + 0.5 * h * k2i);
        let (k4r, k4i) = rhs(re + h * k3r, im + h * k3i);
        re += h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
        im += h / 6.0 * (k1i + 2.0 * k2i + 2.0 * k3i + k4i);
        let a = re.hypot(im);
        if a > 0.0 && k1r.hypot(k1i) < 1e-9 * a {
            break;
        }
    }
    re.hypot(im)
}

fn general_sweep(
    r: &ForcedResponse,
    omegas: &[f64],
    order: &[usize],
    dir: SweepDirection,
) -> Result<Sweep, SolveError> {
    let folds = if omegas.len() > 1 {
        find_folds(r, omegas[0], omegas[omegas.len() - 1])?
    } else {
        Vec::new()
    };
    let sgn = match dir {
        SweepDirection::Up => 1.0,
        SweepDirection::Down => -1.0,
    };
    let mut points = Vec::with_capacity(order.len());
    let mut jumps = Vec::new();
    let mut rank: Option<usize> = None;
    let mut prev_omega = f64::NAN;
    for (step, &i) in order.iter().enumerate() {
        let w = omegas[i];
        if step > 0 {
            let (a, b) = (prev_omega.min(w), prev_omega.max(w));
            let mut events: Vec<&Fold> = folds
                .iter()
                .filter(|f| f.omega > a && f.omega <= b)
                .collect();
            if sgn < 0.0 {
                events = folds
                    .iter()
                    .filter(|f| f.omega >= a && f.omega < b)
                    .collect();
                events.reverse();
            }
            for f in events {
                let Some(j) = rank else { continue };
                let before_w = f.omega * (1.0 - sgn * 1e-9);
                let after_w = f.omega * (1.0 + sgn * 1e-9);
                let appears = f.pair_above == (sgn > 0.0);
                let before = roots_at(r, before_w)?;
                if appears {
                    if j < before.len() && f.amplitude < before[j].amplitude {
                        rank = Some(j + 2);
                    }
                    continue;
                }
                if before.len() < 2 {
                    continue;
                }
                let lf = f.amplitude.ln();
                let k = (0..before.len() - 1)
                    .min_by(|&p, &q| {
                        let cp = (before[p].amplitude.ln() - lf).abs()
                            + (before[p + 1].amplitude.ln() - lf).abs();
                        let cq = (before[q].amplitude.ln() - lf).abs()
                            + (before[q + 1].amplitude.ln() - lf).abs();
                        cp.total_cmp(&cq)
                    })
                    .unwrap();
                if j == k || j == k + 1 {
                    let after = roots_at(r, after_w)?;
                    let eq_after = r.equation(after_w);
                    let down = eq_after.ln_p((f.amplitude / r.scale).ln()) > 0.0;
                    let target = if down {
                        (0..after.len())
                            .rev()
                            .find(|&q| after[q].stable && after[q].amplitude < f.amplitude)
                    } else {
                        (0..after.len())
                            .find(|&q| after[q].stable && after[q].amplitude > f.amplitude)
                    }
                    .or_else(|| {
                        (0..after.len())
                            .filter(|&q| after[q].stable)
                            .min_by(|&p, &q| {
                                (after[p].amplitude.ln() - lf)
                                    .abs()
                                    .total_cmp(&(after[q].amplitude.ln() - lf).abs())
                            })
                    });
                    match target {
                        Some(q) => {
                            jumps.push(Jump {
                                omega: f.omega,
                                amplitude_before: f.amplitude,
                                amplitude_after: after[q].amplitude,
                            });
                            rank = Some(q);
                        }
                        None => rank = None,
                    }
                } else if j > k + 1 {
                    rank = Some(j - 2);
                }
            }
        }
        let set = r.steady_states(w).map_err(|e| with_omega(e, w))?;
        let roots = set.roots;
        if roots.is_empty() {
            points.push(sticking_point(w));
            rank = None;
        } else {
            let j = match rank {
                Some(j) if j < roots.len() => j,
                Some(_) => {
                    // inconsistent count (a fold below resolution): nearest stable root
                    let last = points
                        .last()
                        .map(|p: &SweepPoint| p.amplitude)
                        .unwrap_or(0.0);
                    (0..roots.len())
                        .min_by(|&p, &q| {
                            let dp = (roots[p].amplitude - last).abs()
                                + if roots[p].stable { 0.0 } else { f64::MAX / 4.0 };
                            let dq = (roots[q].amplitude - last).abs()
                                + if roots[q].stable { 0.0 } else { f64::MAX / 4.0 };
                            dp.total_cmp(&dq)
                        })
                        .unwrap()
                }
                None => from_rest(r, w, &roots),
            };
            let mut j = j;
            if !roots[j].stable {
                // The followed state lost stability without a fold (Hopf,
                // only possible for η < −2) or no fold was resolvable: the
                // motion leaves it for the nearest stable state, if any.
                let a = roots[j].amplitude.ln();
                if let Some(q) = (0..roots.len())
                    .filter(|&q| roots[q].stable)
                    .min_by(|&p, &q| {
                        (roots[p].amplitude.ln() - a)
                            .abs()
                            .total_cmp(&(roots[q].amplitude.ln() - a).abs())
                    })
                {
                    if rank.is_some() {
                        jumps.push(Jump {
                            omega: w,
                            amplitude_before: roots[j].amplitude,
                            amplitude_after: roots[q].amplitude,
                        });
                    }
                    j = q;
                }
            }
            rank = Some(j);
            points.push(point(r, w, &roots[j]));
        }
        prev_omega = w;
    }
    Ok(Sweep {
        direction: dir,
        points,
        jumps,
        folds,
    })
}
