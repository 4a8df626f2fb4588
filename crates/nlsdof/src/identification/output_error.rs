//! The output error of the final identification stage: each measured point
//! against the model state the measured sweep was on, continuous in θ
//! ([`super::objective::ResponseBranch::Measured`]).
//!
//! ## Why not Eq 31 as it stands
//! Eq 31 compares every measured point with the state the model's *own*
//! sweep reaches at its frequency. Where a model fold crosses a measured
//! step, that step changes branch and the cost jumps: Eq 31 is piecewise
//! constant in the fold locations, and a gradient solver cannot move a
//! model jump across a step (measured: a hardening case whose top-level
//! fold sat 0.2 step before the measured jump ended at 500× the cost of
//! the truth, "converged").
//!
//! ## The comparison
//! Per curve, the model's sweep (in the measured direction, from the state
//! nearest the first measured amplitude) gives the followed state at every
//! step and its first jump, at the fold `(Ω_f, a_f)`. A measured point at
//! `Ω_k` is compared with the cheapest of
//!
//! 1. the state the model's sweep is on at `Ω_k` (Eq 31's state);
//! 2. **before the fold** (in sweep order): every other *stable* state at
//!    `Ω_k`, plus a penalty in the exact reading and none in the censored
//!    one;
//! 3. **after the fold**: the end of the branch the sweep was on, `a_f` at
//!    its fold, plus the same penalty in both readings,
//!
//! the penalty being `(s_k (d_k + μ h_k)/h_k)²`, where `d_k = |Ω_k − Ω_f|`,
//! `h_k` is the measured step from `Ω_k` towards the fold, `s_k` the
//! measured amplitude (at least 1 % of the curve's peak) and `μ =`
//! [`BARRIER`], all over `γ` as in Eq 31. "Cheapest" is the point's whole
//! contribution (amplitude, phase and penalty residuals squared), so the
//! cost is the minimum of functions each continuous in θ: continuous, but
//! for a step of at most `μ² s²` where a fold crosses a measured point —
//! a barrier that a solver on the right side does not cross, and whose
//! slope pulls one on the wrong side back. It equals Eq 31 wherever every
//! point is compared with the sweep's own state — at the truth on
//! noise-free data, and wherever the model's folds lie in the measured step
//! intervals of the jumps — and a penalised comparison is chosen only where
//! it is cheaper than Eq 31's, within about a step of the fold. (Comparing
//! every point with its nearest state in amplitude instead, so that the
//! penalty pulls a fold from any distance, made the cost landscape so steep
//! far from the folds that the unscreened suite's optimum found dropped
//! from 199 to 181 of 200.)
//!
//! Where the model's sweep does not jump inside the measured range but a
//! point prefers another state (exact reading), `Ω_f` is the first fold
//! beyond the range in the sweep direction where the followed branch ends;
//! if there is none, only the sweep's state is compared (Eq 31).
//!
//! ## Phase offset
//! When the phase convention was detected from the data, its constant
//! offset is a nuisance parameter of the output error too: the equation
//! error that detected it is biased by the noise in its regressors (4°
//! measured on a strongly hardening set, which left the phase residuals at
//! 14× their noise). With [`MatchOptions::profile_phase_offset`] the offset
//! is profiled out in closed form (variable projection: the best constant
//! for the model's phases, and its derivative in the Jacobian), within
//! [`MAX_OFFSET_CORRECTION`] of the detected one.
//!
//! ## Residuals and Jacobian
//! Amplitude residuals `√w (a − a_meas)/γ` (data order), phase residuals
//! `√(w_φ w) a_meas wrap(φ − φ_meas)/γ` (curves with phases), then one
//! penalty residual per curve, `√(Σ_k p_k)`. `da/dθ` at a root by implicit
//! differentiation ([`super::objective::DerivativeConstants`]); at the fold
//! end `da_f/dθ`, `dφ_f/dθ` and `dΩ_f/dθ` from the fold conditions
//! ([`super::jumps::fold_derivatives`]). Checked against finite differences
//! in the tests.

use super::data::{Curve, Dataset};
use super::jumps::{fold_derivatives, fold_frequency_derivatives};
use super::models::*;
use super::objective::{DerivativeConstants, Evaluation};
use super::parameters::Parameters;
use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};

/// Offset of the penalty, in measured steps: a point charged by its
/// distance `d` to the fold pays `(s (d + μh)/h)²`, so crossing to the wrong
/// side of a fold costs at least `μ² s²` (module docs, "Barrier").
pub const BARRIER: f64 = 0.1;

/// How a measured jump is read (module docs).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize, serde::Deserialize,
)]
pub enum JumpReading {
    /// A perfect sweep: it leaves its branch at the fold, within a step.
    #[default]
    Exact,
    /// The jump bounds the fold from one side: the sweep may have left its
    /// branch earlier, never later.
    Censored,
}

impl JumpReading {
    pub fn name(self) -> &'static str {
        match self {
            JumpReading::Exact => "exact",
            JumpReading::Censored => "censored",
        }
    }
}

/// Which state a measured point was compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compared {
    /// The state of the model's own sweep (Eq 31).
    Sweep,
    /// Another stable state at the point's frequency, before the model's fold.
    Other,
    /// The end (fold) of the branch the model's sweep was on, after the fold.
    FoldEnd,
}

/// What the comparison found on one curve.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveMatch {
    /// The model's first jump in sweep order: fold frequency (rad/s) and the
    /// amplitude on the branch that ends there (m).
    pub fold: Option<(f64, f64)>,
    /// The state each measured point was compared with (data order).
    pub compared: Vec<Compared>,
    /// Sum of the squared penalty terms of the curve (in the units of the
    /// residuals).
    pub penalty: f64,
    /// The penalty charged to each point, in the units of the squared
    /// residuals (data order; 0 where none), for the noise-scaled
    /// statistics ([`super::noise::z2_per_curve`]).
    pub penalties: Vec<f64>,
}

impl CurveMatch {
    /// The measured sweep left the model's branch before the model's fold:
    /// the first step (data index, in sweep order) compared with another
    /// state before the fold, if any.
    pub fn left_early(&self, c: &Curve) -> Option<usize> {
        let n = c.omegas.len();
        let order: Vec<usize> = match c.direction {
            SweepDirection::Up => (0..n).collect(),
            SweepDirection::Down => (0..n).rev().collect(),
        };
        order
            .into_iter()
            .find(|&i| self.compared[i] == Compared::Other)
    }
}

/// One candidate state of a measured point.
struct Candidate {
    a: f64,
    phase: f64,
    kind: Compared,
    /// Squared penalty (already over γ², weighted) and its `d`, `scale` for
    /// the derivative: `p = coef · d²`.
    coef: f64,
    d: f64,
    /// Sign of `∂d/∂Ω_f`.
    sign: f64,
}

/// The fold a penalty measures the distance to, with `dΩ_f/dθ`.
#[derive(Clone, Copy)]
struct PenaltyFold {
    omega: f64,
    domega: [f64; N_PARAMS],
}

/// The settings of the measured-branch comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchOptions<'a> {
    /// Weight `w_φ` of the phase residuals (`None`: amplitudes only).
    pub phase_weight: Option<f64>,
    /// Per curve: its jump is read as censored (missing entries: exact).
    pub censored: &'a [bool],
    /// Multiplies every penalty (≥ 0, default 1).
    pub jump_weight: f64,
    /// The measured phases carry an unknown constant offset: it is
    /// profiled out (module docs, "Phase offset").
    pub profile_phase_offset: bool,
}

impl<'a> MatchOptions<'a> {
    /// Amplitudes only, every jump exact, weight 1.
    pub fn amplitudes() -> Self {
        Self {
            phase_weight: None,
            censored: &[],
            jump_weight: 1.0,
            profile_phase_offset: false,
        }
    }

    /// The settings of a fit structure.
    pub fn of(spec: &'a super::objective::FitSpec) -> Self {
        Self {
            phase_weight: spec.phase_weight,
            censored: &spec.censored,
            jump_weight: spec.jump_weight,
            profile_phase_offset: spec.profile_phase_offset,
        }
    }
}

/// Residuals (and the Jacobian with respect to the seven natural
/// parameters) of the measured-branch output error (module docs), and what
/// each curve's comparison found.
pub fn evaluate_measured(
    data: &Dataset,
    theta: &Parameters,
    jacobian: bool,
    opts: &MatchOptions,
) -> Result<(Evaluation, Vec<CurveMatch>), SolveError> {
    let MatchOptions {
        phase_weight,
        censored,
        jump_weight,
        profile_phase_offset,
    } = *opts;
    let model = theta.normalised_model();
    let dc = DerivativeConstants::new(theta);
    let per_curve: Vec<CurveOutput> = data.map_curves(|ci, c| {
        let reading = if censored.get(ci).copied().unwrap_or(false) {
            JumpReading::Censored
        } else {
            JumpReading::Exact
        };
        let r = ForcedResponse::from_normalised(
            &model,
            theta[GAIN] * c.gamma,
            Formulation::HarmonicBalance,
        )?;
        curve_output(
            &r,
            theta,
            &dc,
            c,
            reading,
            jump_weight,
            jacobian,
            phase_weight,
        )
    })?;
    let n = data.len();
    let mut model_a = Vec::with_capacity(n);
    let mut residuals = Vec::with_capacity(n + data.curves.len());
    let mut jac: Option<Vec<[f64; N_PARAMS]>> = jacobian.then(|| Vec::with_capacity(n));
    for o in &per_curve {
        model_a.extend(&o.model);
        residuals.extend(&o.amp);
        if let Some(j) = jac.as_mut() {
            j.extend(&o.amp_jac);
        }
    }
    if let Some(wp) = phase_weight {
        let start = residuals.len();
        let mut ks: Vec<f64> = Vec::new();
        for (o, c) in per_curve.iter().zip(&data.curves) {
            if c.phases.is_some() {
                residuals.extend(&o.phase);
                if let Some(j) = jac.as_mut() {
                    j.extend(&o.phase_jac);
                }
                // the residual weights k = √(w_φ w) a/γ (0 where the model sticks)
                ks.extend((0..c.omegas.len()).map(|i| {
                    if o.model[i] > 0.0 {
                        (wp * c.weights[i]).sqrt() * c.amplitudes[i] / c.gamma
                    } else {
                        0.0
                    }
                }));
            }
        }
        if profile_phase_offset {
            profile_offset(
                &mut residuals[start..],
                jac.as_mut().map(|j| &mut j[start..]),
                &ks,
            );
        }
    }
    for o in &per_curve {
        residuals.push(o.penalty);
        if let Some(j) = jac.as_mut() {
            j.push(o.penalty_jac);
        }
    }
    let matches = per_curve.into_iter().map(|o| o.matched).collect();
    Ok((
        Evaluation {
            model: model_a,
            residuals,
            jacobian: jac,
        },
        matches,
    ))
}

/// Largest correction (rad, 15°) of a detected phase offset that the
/// output error makes: the equation error that detected it is biased by a
/// few degrees on data of the model (4° measured); a larger correction
/// would mean that the model does not follow the measured phases, and the
/// offset would then absorb misfit (on the clamped beam it moved 140°).
pub const MAX_OFFSET_CORRECTION: f64 = 15.0 * std::f64::consts::PI / 180.0;

/// Profiles a constant offset `c` out of the phase residuals
/// `r_i = k_i (φ_i − ψ_i)`: `c* = Σ k_i r_i / Σ k_i²` minimises
/// `Σ (r_i − k_i c)²`, and its derivative `Σ k_i ∂r_i/∂θ / Σ k_i²` enters
/// the Jacobian (variable projection: the projected residuals
/// `r_i − k_i c*(θ)` and their exact derivatives).
fn profile_offset(residuals: &mut [f64], jacobian: Option<&mut [[f64; N_PARAMS]]>, k: &[f64]) {
    let den: f64 = k.iter().map(|x| x * x).sum();
    if !(den > 0.0) {
        return;
    }
    let c: f64 = k
        .iter()
        .zip(residuals.iter())
        .map(|(k, r)| k * r)
        .sum::<f64>()
        / den;
    // kept within MAX_OFFSET_CORRECTION of the detected offset (there the
    // correction is held and has no derivative)
    let clamped = c.clamp(-MAX_OFFSET_CORRECTION, MAX_OFFSET_CORRECTION);
    for (r, &ki) in residuals.iter_mut().zip(k) {
        *r -= ki * clamped;
    }
    if clamped != c {
        return;
    }
    if let Some(j) = jacobian {
        let mut dc = [0.0; N_PARAMS];
        for (row, &ki) in j.iter().zip(k) {
            for p in 0..N_PARAMS {
                dc[p] += ki * row[p] / den;
            }
        }
        for (row, &ki) in j.iter_mut().zip(k) {
            for p in 0..N_PARAMS {
                row[p] -= ki * dc[p];
            }
        }
    }
}

/// The phase offset profiled out of the phase residuals of an evaluation
/// of `data` (`residuals` as [`evaluate_measured`] returns them with
/// [`MatchOptions::profile_phase_offset`] off): the constant to add to every
/// measured phase lag, rad.
pub fn phase_offset(data: &Dataset, residuals: &[f64], phase_weight: f64, model: &[f64]) -> f64 {
    let mut off = data.len();
    let (mut num, mut den) = (0.0, 0.0);
    let mut m = 0;
    for c in &data.curves {
        let n = c.omegas.len();
        if c.phases.is_some() {
            for i in 0..n {
                if model[m + i] > 0.0 {
                    let k = (phase_weight * c.weights[i]).sqrt() * c.amplitudes[i] / c.gamma;
                    num += k * residuals[off + i];
                    den += k * k;
                }
            }
            off += n;
        }
        m += n;
    }
    if den > 0.0 {
        (num / den).clamp(-MAX_OFFSET_CORRECTION, MAX_OFFSET_CORRECTION)
    } else {
        0.0
    }
}

struct CurveOutput {
    model: Vec<f64>,
    amp: Vec<f64>,
    amp_jac: Vec<[f64; N_PARAMS]>,
    phase: Vec<f64>,
    phase_jac: Vec<[f64; N_PARAMS]>,
    penalty: f64,
    penalty_jac: [f64; N_PARAMS],
    matched: CurveMatch,
}

fn wrap_angle(x: f64) -> f64 {
    let y = x.rem_euclid(std::f64::consts::TAU);
    if y > std::f64::consts::PI {
        y - std::f64::consts::TAU
    } else {
        y
    }
}

/// The first fold beyond the measured range, in the sweep direction, at
/// which the branch the sweep follows can end (a pair of roots dies in the
/// sweep direction).
fn fold_beyond(r: &ForcedResponse, c: &Curve) -> Result<Option<(f64, f64)>, SolveError> {
    let (lo, hi) = (c.omegas[0], c.omegas[c.omegas.len() - 1]);
    let span = (hi - lo).max(0.1 * hi);
    Ok(match c.direction {
        // (the search stops at the first such fold: the same fold as the
        // first of `folds(hi, hi + span)` ending upwards)
        SweepDirection::Up => r
            .first_fold_ending_upwards(hi, hi + span)?
            .map(|f| (f.omega, f.amplitude)),
        SweepDirection::Down => r
            .folds((lo - span).max(0.5 * lo), lo)?
            .into_iter()
            .rev()
            .find(|f| f.pair_above)
            .map(|f| (f.omega, f.amplitude)),
    })
}

#[allow(clippy::too_many_arguments)]
fn curve_output(
    r: &ForcedResponse,
    theta: &Parameters,
    dc: &DerivativeConstants,
    c: &Curve,
    reading: JumpReading,
    jump_weight: f64,
    jacobian: bool,
    phase_weight: Option<f64>,
) -> Result<CurveOutput, SolveError> {
    let n = c.omegas.len();
    // (from memory when this sweep was one of the recent ones: a function
    // of the model, the level and the curve only)
    let swept = super::recent_sweeps::sweep_with_states(r, c)?;
    let (sw, states) = (&swept.0, &swept.1);
    let sgn = match c.direction {
        SweepDirection::Up => 1.0,
        SweepDirection::Down => -1.0,
    };
    let data_index = |k: usize| match c.direction {
        SweepDirection::Up => k,
        SweepDirection::Down => n - 1 - k,
    };
    // the first jump, when it is at a fold (not a loss of stability at a step)
    let jump = sw
        .jumps
        .first()
        .filter(|j| sw.folds.iter().any(|f| f.omega == j.omega))
        .map(|j| (j.omega, j.amplitude_before));
    let fold_d = match jump {
        Some((w, a)) => fold_derivatives(theta, c.gamma, w, a),
        None => None,
    };
    let peak = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
    let use_phase = phase_weight.is_some() && c.phases.is_some();
    let wp = phase_weight.unwrap_or(0.0);
    // the local step from data index i towards frequency `towards`
    let step_towards = |i: usize, towards: f64| -> f64 {
        let w = c.omegas[i];
        let up = towards > w;
        let h = if up {
            c.omegas.get(i + 1).map(|&x| x - w)
        } else {
            i.checked_sub(1).map(|p| w - c.omegas[p])
        };
        h.or_else(|| {
            if up {
                i.checked_sub(1).map(|p| w - c.omegas[p])
            } else {
                c.omegas.get(i + 1).map(|&x| x - w)
            }
        })
        .unwrap_or(w)
        .abs()
        .max(f64::MIN_POSITIVE)
    };
    // the fold the exact reading measures pre-fold alternatives against:
    // the sweep's own jump, else (lazily) the first fold beyond the range
    let mut beyond: Option<Option<PenaltyFold>> = None;
    let mut out = CurveOutput {
        model: vec![0.0; n],
        amp: vec![0.0; n],
        amp_jac: if jacobian {
            vec![[0.0; N_PARAMS]; n]
        } else {
            Vec::new()
        },
        phase: if use_phase { vec![0.0; n] } else { Vec::new() },
        phase_jac: if use_phase && jacobian {
            vec![[0.0; N_PARAMS]; n]
        } else {
            Vec::new()
        },
        penalty: 0.0,
        penalty_jac: [0.0; N_PARAMS],
        matched: CurveMatch {
            fold: jump,
            compared: vec![Compared::Sweep; n],
            penalty: 0.0,
            penalties: vec![0.0; n],
        },
    };
    let mut pen_sum = 0.0;
    let mut pen_grad = [0.0; N_PARAMS];
    for (k, p) in sw.points.iter().enumerate() {
        let i = data_index(k);
        let w = c.omegas[i];
        let a_meas = c.amplitudes[i];
        let wt = c.weights[i];
        let g = c.gamma;
        let phi_meas = c.phases.as_ref().map(|ph| ph[i]);
        let cost_of = |a: f64, phi: f64| -> f64 {
            let mut s = wt * ((a - a_meas) / g).powi(2);
            if let (true, Some(pm)) = (use_phase && a > 0.0, phi_meas) {
                s += wp * wt * (a_meas * wrap_angle(phi - pm) / g).powi(2);
            }
            s
        };
        let scale = a_meas.max(0.01 * peak);
        let (sweep_a, sweep_phi) = if p.sticking || p.unbounded {
            (0.0, 0.0)
        } else {
            (p.amplitude, p.phase)
        };
        let mut best = Candidate {
            a: sweep_a,
            phase: sweep_phi,
            kind: Compared::Sweep,
            coef: 0.0,
            d: 0.0,
            sign: 0.0,
        };
        let mut best_cost = cost_of(sweep_a, sweep_phi);
        let after_fold = jump.is_some_and(|(wf, _)| sgn * (w - wf) >= 0.0);
        if after_fold {
            // case 3: the end of the branch the sweep was on
            if let (Some((wf, af)), Some(fd)) = (jump, fold_d.as_ref()) {
                let h = step_towards(i, wf);
                let coef = jump_weight * wt * (scale / (h * g)).powi(2);
                let d = (w - wf).abs() + BARRIER * h;
                let cst = cost_of(af, fd.phase) + coef * d * d;
                if cst < best_cost {
                    best_cost = cst;
                    best = Candidate {
                        a: af,
                        phase: fd.phase,
                        kind: Compared::FoldEnd,
                        coef,
                        d,
                        sign: if wf > w { 1.0 } else { -1.0 },
                    };
                }
            }
        } else {
            // case 2: another stable state before the fold
            for s in states.at(k) {
                if (s.amplitude - sweep_a).abs() <= 1e-12 * sweep_a.max(f64::MIN_POSITIVE) {
                    continue;
                }
                let base = cost_of(s.amplitude, s.phase);
                if base >= best_cost {
                    continue;
                }
                let (coef, d, sign) = match reading {
                    JumpReading::Censored => (0.0, 0.0, 0.0),
                    JumpReading::Exact => {
                        let pf = match jump {
                            Some((wf, _)) => fold_d.as_ref().map(|fd| PenaltyFold {
                                omega: wf,
                                domega: fd.omega,
                            }),
                            None => *beyond.get_or_insert_with(|| {
                                fold_beyond(r, c).ok().flatten().and_then(|(wf, af)| {
                                    fold_frequency_derivatives(theta, c.gamma, wf, af)
                                        .map(|domega| PenaltyFold { omega: wf, domega })
                                })
                            }),
                        };
                        let Some(pf) = pf else { continue };
                        let h = step_towards(i, pf.omega);
                        let coef = jump_weight * wt * (scale / (h * g)).powi(2);
                        let d = (w - pf.omega).abs() + BARRIER * h;
                        (coef, d, if pf.omega > w { 1.0 } else { -1.0 })
                    }
                };
                let cst = base + coef * d * d;
                if cst < best_cost {
                    best_cost = cst;
                    best = Candidate {
                        a: s.amplitude,
                        phase: s.phase,
                        kind: Compared::Other,
                        coef,
                        d,
                        sign,
                    };
                }
            }
        }
        let sw_w = wt.sqrt();
        out.model[i] = best.a;
        out.amp[i] = sw_w * (best.a - a_meas) / g;
        out.matched.compared[i] = best.kind;
        if use_phase {
            let pm = phi_meas.unwrap_or(0.0);
            let kph = (wp * wt).sqrt() * a_meas / g;
            out.phase[i] = if best.a > 0.0 {
                kph * wrap_angle(best.phase - pm)
            } else {
                0.0
            };
        }
        let p_k = best.coef * best.d * best.d;
        pen_sum += p_k;
        out.matched.penalties[i] = p_k;
        // the fold this point's penalty is measured against
        let penalty_domega = match best.kind {
            Compared::Sweep => None,
            Compared::FoldEnd => fold_d.as_ref().map(|fd| fd.omega),
            Compared::Other => match (jump, fold_d.as_ref()) {
                (Some(_), Some(fd)) => Some(fd.omega),
                _ => beyond.flatten().map(|pf| pf.domega),
            },
        };
        if jacobian {
            let (da, dphi) = match best.kind {
                _ if best.a <= 0.0 => ([0.0; N_PARAMS], [0.0; N_PARAMS]),
                Compared::FoldEnd => match fold_d.as_ref() {
                    Some(fd) => (fd.amplitude, fd.phase_derivative),
                    None => ([0.0; N_PARAMS], [0.0; N_PARAMS]),
                },
                _ => {
                    let da = dc.derivatives(c.gamma, w, best.a);
                    let dphi = if use_phase {
                        dc.phase_derivatives(w, best.a, &da)
                    } else {
                        [0.0; N_PARAMS]
                    };
                    (da, dphi)
                }
            };
            for j in 0..N_PARAMS {
                out.amp_jac[i][j] = sw_w * da[j] / g;
            }
            if use_phase && best.a > 0.0 {
                let kph = (wp * wt).sqrt() * a_meas / g;
                for j in 0..N_PARAMS {
                    out.phase_jac[i][j] = kph * dphi[j];
                }
            }
            if p_k > 0.0 {
                if let Some(dw) = penalty_domega {
                    // ∂p/∂θ = 2 coef d ∂d/∂θ,  ∂d/∂θ = sign · ∂Ω_f/∂θ
                    for j in 0..N_PARAMS {
                        pen_grad[j] += 2.0 * best.coef * best.d * best.sign * dw[j];
                    }
                }
            }
        }
    }
    out.penalty = pen_sum.sqrt();
    out.matched.penalty = pen_sum;
    if jacobian && out.penalty > 0.0 {
        for j in 0..N_PARAMS {
            out.penalty_jac[j] = 0.5 * pen_grad[j] / out.penalty;
        }
    }
    Ok(out)
}
