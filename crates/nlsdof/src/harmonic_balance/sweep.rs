//! Stepped-sine branch following, as a sweep on a shaker sees it.
//!
//! Rules (independent of the step size by construction; the fold
//! frequencies, located from the step cells, to their ~1e-14 precision):
//!
//! 1. **Start from rest.** At the first frequency the structure starts at
//!    `x = 0`. If one stable steady state exists it is taken; if several do,
//!    the slow flow `dX/dτ = −i(1 − Z(|X|) X)`, `Z = S + iD` (module docs of
//!    [`super`]) is integrated from `X = 0` and the stable state it settles
//!    on is taken.
//!    Variant (rule 1′, [`ForcedResponse::sweep_from`]): when the state at
//!    the first step is known to be near a given amplitude `a₀` (e.g. the
//!    measured one, when fitting data), the stable root nearest to `a₀` in
//!    `ln a` is taken instead, with no slow-flow integration.
//! 2. **Follow the branch.** Between folds the roots of the response equation
//!    are smooth in Ω and cannot cross, so a steady state keeps its *rank*
//!    (index in the amplitude-sorted list). All folds between the first and
//!    last frequency are located first ([`super::folds`], searched on the
//!    sweep's own steps, with step cells wider than two cells of the fixed
//!    fold grid split; the roots isolated there serve the steps, so a step
//!    is isolated once); crossing one
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
//! between consecutive steps has exactly one root (see [`super::certificate`]),
//! there are no folds, and each step is a safeguarded Newton solve warm
//! started from the previous step.

use super::certificate::{certify_cell, fast_path_possible};
use super::equation::{ResponseEquation, UniqueState};
use super::folds::{find_folds_on_steps, with_omega};
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

fn point(r: &ForcedResponse, omega: f64, s: &SteadyState) -> SweepPoint {
    let _ = r;
    SweepPoint {
        omega,
        amplitude: s.amplitude,
        phase: s.phase,
        stable: s.stable,
        sticking: false,
        unbounded: false,
    }
}

/// A step without a steady state: sticking (no motion), or no finite
/// steady state (`unbounded`, unstable) when the response grows without bound.
fn sticking_point(omega: f64, reason: Option<NoMotion>) -> SweepPoint {
    let unbounded = reason == Some(NoMotion::Unbounded);
    SweepPoint {
        omega,
        amplitude: 0.0,
        phase: 0.0,
        stable: !unbounded,
        sticking: !unbounded,
        unbounded,
    }
}

pub(crate) fn sweep(
    r: &ForcedResponse,
    omegas: &[f64],
    dir: SweepDirection,
    initial: Option<f64>,
    states: Option<&mut StepStates>,
) -> Result<Sweep, SolveError> {
    validate_omegas(omegas)?;
    if let Some(a) = initial {
        let name = "initial amplitude";
        if !a.is_finite() {
            return Err(ParameterError::NotFinite { name, value: a }.into());
        }
        if a < 0.0 {
            return Err(ParameterError::Negative { name, value: a }.into());
        }
    }
    let order: Vec<usize> = match dir {
        SweepDirection::Up => (0..omegas.len()).collect(),
        SweepDirection::Down => (0..omegas.len()).rev().collect(),
    };
    let eqs: Vec<ResponseEquation> = omegas.iter().map(|&w| r.equation(w)).collect();
    // unique[i]: the one-root certificate holds on a cell touching step i
    let unique: Vec<bool> = if fast_path_possible(r) {
        let cells: Vec<bool> = eqs.windows(2).map(|w| certify_cell(&w[0], &w[1])).collect();
        (0..eqs.len())
            .map(|i| {
                (i > 0 && cells[i - 1])
                    || cells.get(i).copied().unwrap_or(false)
                    || (eqs.len() == 1 && certify_cell(&eqs[0], &eqs[0]))
            })
            .collect()
    } else {
        vec![false; eqs.len()]
    };
    let certified = unique.iter().all(|&u| u)
        && (eqs.len() == 1 || eqs.windows(2).all(|w| certify_cell(&w[0], &w[1])));
    if certified {
        if let Some(points) = fast_sweep(r, omegas, &eqs, &order) {
            if let Some(st) = states {
                // one root per step (certified)
                st.clear();
                for p in &points {
                    st.push_step([SteadyState {
                        amplitude: p.amplitude,
                        phase: p.phase,
                        stable: p.stable,
                    }]);
                }
            }
            return Ok(Sweep {
                direction: dir,
                points,
                jumps: Vec::new(),
                folds: Vec::new(),
            });
        }
    }
    general_sweep(r, omegas, &order, dir, &eqs, &unique, initial, states)
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
        let guess = match k {
            // the linear estimate
            0 => None,
            1 => Some(hist[0].1),
            2 => {
                let [(w1, t1), (w0, t0), _] = hist;
                Some(t1 + (t1 - t0) * (w - w1) / (w1 - w0))
            }
            _ => {
                // quadratic (Lagrange) extrapolation through the last three steps
                let [(w2, t2), (w1, t1), (w0, t0)] = hist;
                Some(
                    t2 * (w - w1) * (w - w0) / ((w2 - w1) * (w2 - w0))
                        + t1 * (w - w2) * (w - w0) / ((w1 - w2) * (w1 - w0))
                        + t0 * (w - w2) * (w - w1) / ((w0 - w2) * (w0 - w1)),
                )
            }
        };
        let UniqueState { t, phase, stable } = eq.solve_certified(guess)?;
        points.push(SweepPoint {
            omega: w,
            amplitude: t.exp() * r.scale,
            phase,
            stable,
            sticking: false,
            unbounded: false,
        });
        hist = [(w, t), hist[0], hist[1]];
    }
    Some(points)
}

fn roots_at(r: &ForcedResponse, omega: f64) -> Result<Vec<SteadyState>, SolveError> {
    Ok(r.steady_states(omega)?.roots)
}

/// Rule 1′: the stable root nearest to `a0` in `ln a` (ties: the smaller
/// root); the only root if none is stable.
fn nearest_stable(roots: &[SteadyState], a0: f64) -> usize {
    let la = a0.max(f64::MIN_POSITIVE).ln();
    (0..roots.len())
        .filter(|&k| roots[k].stable)
        .min_by(|&p, &q| {
            (roots[p].amplitude.ln() - la)
                .abs()
                .total_cmp(&(roots[q].amplitude.ln() - la).abs())
        })
        .unwrap_or(0)
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

/// The root at a step where the one-root certificate holds (`unique`):
/// safeguarded Newton from `prev_x` (the previous step's dimensionless
/// amplitude) or from the linear estimate. `None` if Newton fails or the
/// state is not stable (then the caller isolates all roots).
fn unique_root(
    r: &ForcedResponse,
    eq: &ResponseEquation,
    omega: f64,
    prev_x: Option<f64>,
) -> Option<SweepPoint> {
    let guess = prev_x.filter(|&x| x > 0.0).map(f64::ln);
    let UniqueState { t, phase, stable } = eq.solve_certified(guess)?;
    let amplitude = t.exp() * r.scale;
    (stable && amplitude.is_finite() && amplitude > 0.0).then_some(SweepPoint {
        omega,
        amplitude,
        phase,
        stable,
        sticking: false,
        unbounded: false,
    })
}

#[allow(clippy::too_many_arguments)]
fn general_sweep(
    r: &ForcedResponse,
    omegas: &[f64],
    order: &[usize],
    dir: SweepDirection,
    eqs: &[ResponseEquation],
    unique: &[bool],
    initial: Option<f64>,
    mut states: Option<&mut StepStates>,
) -> Result<Sweep, SolveError> {
    if let Some(st) = states.as_deref_mut() {
        st.clear();
    }
    // the folds, and the roots at the steps where the search isolated them
    let (folds, mut step_roots) = find_folds_on_steps(r, omegas, eqs)?;
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
        if unique[i] {
            // exactly one root here (certified): it is the state, whatever
            // the rank bookkeeping says; no root isolation needed
            let prev_x = points
                .last()
                .filter(|p: &&SweepPoint| !p.sticking)
                .map(|p| p.amplitude / r.scale);
            if let Some(p) = unique_root(r, &eqs[i], w, prev_x) {
                rank = Some(0);
                if let Some(st) = states.as_deref_mut() {
                    st.push_step([SteadyState {
                        amplitude: p.amplitude,
                        phase: p.phase,
                        stable: p.stable,
                    }]);
                }
                points.push(p);
                prev_omega = w;
                continue;
            }
        }
        let set = match step_roots[i].take() {
            Some(ts) => r.root_set(w, &eqs[i], &ts)?,
            None => r.steady_states(w).map_err(|e| with_omega(e, w))?,
        };
        let roots = set.roots;
        if let Some(st) = states.as_deref_mut() {
            st.push_step(roots.iter().filter(|s| s.stable).copied());
        }
        if roots.is_empty() {
            points.push(sticking_point(w, set.no_motion));
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
                None => match initial {
                    // rule 1′: the first step's state is the stable root
                    // nearest (in ln a) to the given amplitude
                    Some(a0) if step == 0 => nearest_stable(&roots, a0),
                    _ => from_rest(r, w, &roots),
                },
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
