//! Jump-frequency residuals: an optional term added to Eq 31 so that a fit
//! can be asked to put the up-sweep jumps where they were measured.
//!
//! The Eq 31 cost is piecewise constant in the location of a model jump
//! (moving the jump inside one step interval changes no residual), so a
//! gradient-based solver cannot move it. This term is continuous and
//! differentiable: for each up-sweep curve c with a measured jump-down
//! (the last step on the upper branch, [`super::Curve::measured_jump`]
//! with ratio 2) it adds
//!
//! ```text
//! r_J,c = √(λ n_c) · (a_peak,c/γ_c) · dist(Ω_J,c(θ), [Ω_J,c, Ω_J,c⁺]) / Ω_J,c
//! ```
//!
//! where `[Ω_J, Ω_J⁺]` is the measured step interval across which the
//! amplitude dropped: the data place the fold anywhere inside it, so the
//! residual is the distance of the predicted fold outside the interval
//! (zero inside: noise-free data of the model have zero residual).
//!
//! * `Ω_J,c(θ)` predicted: the first jump of the model's sweep of curve c
//!   (its fold frequency `Ω_f`, differentiable in θ, see
//!   [`fold_frequency_derivatives`]); where the model sweep does not jump,
//!   its phase-quadrature frequency `Ω_pq` (where the response curve meets
//!   the backbone, `S = 0`; a hardening up-sweep's upper branch ends at the
//!   fold just past it, `O(ζ)` apart, so the two nearly agree where the
//!   fold appears), so the term exists and is continuous enough for LM
//!   where a fold is born or dies;
//! * `(a_peak/γ)` (largest measured normalised amplitude of the curve) puts
//!   the term in the units of the Eq 31 residuals, and `n_c` is the number
//!   of steps of the curve: with `λ = 1` a 1 % jump error costs as much as a
//!   1 %-of-peak error at every step of the curve.
//!
//! ## Derivative of the phase-quadrature frequency
//! At the phase-quadrature point
//!
//! ```text
//! G₁ = α + g(ρ)β a^ρ − Ω² = 0,     G₂ = a Ω D − gain γ = 0,
//! D  = δ + g(η) κ (Ω a)^η
//! ```
//!
//! so `[∂G/∂(a, Ω)] (da, dΩ)ᵀ = −∂G/∂θ` (implicit differentiation) with
//!
//! ```text
//! ∂G₁/∂a = ρ g(ρ)β a^{ρ−1}      ∂G₁/∂Ω = −2Ω
//! ∂G₂/∂a = Ω (D + η k)          ∂G₂/∂Ω = a (D + η k),   k = g(η)κ(Ωa)^η
//! ∂G₁/∂α = 1, ∂G₁/∂β = g(ρ)a^ρ, ∂G₁/∂ρ = β a^ρ (g'(ρ) + g(ρ) ln a)
//! ∂G₂/∂δ = aΩ, ∂G₂/∂κ = aΩ g(η)(Ωa)^η,
//! ∂G₂/∂η = aΩ κ (Ωa)^η (g'(η) + g(η) ln(Ωa)),  ∂G₂/∂gain = −γ
//! ```
//!
//! solved by Cramer's rule for `dΩ/dθ`.

use super::data::Dataset;
use super::levenberg_marquardt::LeastSquares;
use super::models::*;
use super::objective::{evaluate, evaluate_with_jumps, normalised_model, FirstJump, Problem};
use super::parameters::Parameters;
use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use crate::power_law::g_unchecked;
use crate::special::g_derivative;

/// Measured jump of one curve and the scale of its residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JumpTarget {
    /// Index of the curve in the data set.
    pub curve: usize,
    /// Measured jump-down frequency Ω_J (rad/s): the last step on the
    /// upper branch.
    pub omega: f64,
    /// The next step (the first one after the jump), rad/s: the fold lies
    /// somewhere in `[omega, omega_next]`.
    pub omega_next: f64,
    /// `√(n_c) · a_peak/γ` (s²).
    pub scale: f64,
}

/// The jump targets of `data`: every up-sweep curve with a measured jump
/// (an amplitude ratio above 2 between consecutive steps).
pub fn jump_targets(data: &Dataset) -> Vec<JumpTarget> {
    data.curves
        .iter()
        .enumerate()
        .filter(|(_, c)| c.direction == SweepDirection::Up)
        .filter_map(|(i, c)| {
            let omega = c.measured_jump(2.0)?;
            let k = c.omegas.iter().position(|&w| w == omega)?;
            let omega_next = *c.omegas.get(k + 1)?;
            let peak = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a)) / c.gamma;
            Some(JumpTarget {
                curve: i,
                omega,
                omega_next,
                scale: (c.omegas.len() as f64).sqrt() * peak,
            })
        })
        .collect()
}

/// The power-law terms of the response equation at `(Ω, a)` that the
/// derivatives of this module share (notation of [`super::objective`]):
/// `B = g(ρ)βa^ρ`, `K = g(η)κ(Ωa)^η`, with their factors kept for the
/// derivatives in β, ρ, κ, η (zero when the term is absent).
struct PowerTerms {
    /// `ln a`, `ln Ωa`.
    la: f64,
    lwa: f64,
    /// `g(ρ)`, `a^ρ`.
    gr: f64,
    ar: f64,
    /// `g(η)`, `(Ωa)^η`.
    ge: f64,
    wae: f64,
    /// `B`, `K`.
    b: f64,
    k: f64,
}

impl PowerTerms {
    fn at(theta: &Parameters, omega: f64, a: f64) -> Self {
        let (beta, rho, kappa, eta) = (theta[BETA], theta[RHO], theta[KAPPA], theta[ETA]);
        let la = a.ln();
        let lwa = (omega * a).ln();
        let (gr, ar) = if beta != 0.0 {
            (g_unchecked(rho), (rho * la).exp())
        } else {
            (0.0, 0.0)
        };
        let (ge, wae) = if kappa != 0.0 {
            (g_unchecked(eta), (eta * lwa).exp())
        } else {
            (0.0, 0.0)
        };
        Self {
            la,
            lwa,
            gr,
            ar,
            ge,
            wae,
            b: gr * beta * ar,
            k: ge * kappa * wae,
        }
    }
}

/// Phase-quadrature frequency `Ω_pq` (rad/s) of the model θ at input
/// `gain·gamma`, and `dΩ_pq/dθ` (module docs). `None` if the curve never
/// meets the backbone or the 2 × 2 system is singular.
pub fn quadrature_frequency(
    theta: &Parameters,
    gamma: f64,
) -> Result<Option<(f64, [f64; N_PARAMS])>, SolveError> {
    let r = ForcedResponse::from_normalised(
        &normalised_model(theta),
        theta[GAIN] * gamma,
        Formulation::HarmonicBalance,
    )?;
    let Some(pq) = r.phase_quadrature()? else {
        return Ok(None);
    };
    let (w, a) = (pq.omega, pq.amplitude);
    let (beta, rho, kappa, eta, gain) = (
        theta[BETA],
        theta[RHO],
        theta[KAPPA],
        theta[ETA],
        theta[GAIN],
    );
    let PowerTerms {
        la,
        lwa,
        gr,
        ar,
        ge,
        wae,
        k,
        ..
    } = PowerTerms::at(theta, w, a);
    let d = theta[DELTA] + k;
    // ∂G/∂(a, Ω)
    let g1a = if beta != 0.0 {
        rho * gr * beta * ar / a
    } else {
        0.0
    };
    let g1w = -2.0 * w;
    let g2a = w * (d + eta * k);
    let g2w = a * (d + eta * k);
    let det = g1a * g2w - g1w * g2a;
    if !(det.is_finite() && det != 0.0) {
        return Ok(None);
    }
    let mut g1 = [0.0; N_PARAMS];
    let mut g2 = [0.0; N_PARAMS];
    g1[ALPHA] = 1.0;
    if beta != 0.0 {
        g1[BETA] = gr * ar;
        g1[RHO] = beta * ar * (g_derivative(rho) + gr * la);
    }
    g2[DELTA] = a * w;
    if kappa != 0.0 {
        g2[KAPPA] = a * w * ge * wae;
        g2[ETA] = a * w * kappa * wae * (g_derivative(eta) + ge * lwa);
    }
    g2[GAIN] = -gamma;
    let _ = gain;
    // [g1a g1w; g2a g2w] (da, dΩ) = −(g1, g2)  ⇒  dΩ = −(g1a g2 − g2a g1)/det
    let mut dw = [0.0; N_PARAMS];
    for j in 0..N_PARAMS {
        dw[j] = -(g1a * g2[j] - g2a * g1[j]) / det;
    }
    Ok(Some((w, dw)))
}

/// `dΩ_f/dθ` at a fold `(a_f, Ω_f)` of the response curve at input
/// `gain·gamma`: there `F = 0` and `∂F/∂a = 0`, so
/// `dΩ_f/dθ = −(∂F/∂θ)/(∂F/∂Ω)` with (both divided by `2a²`, notation of
/// [`super::objective`])
///
/// ```text
/// ∂F/∂Ω /(2a²) = Ω (D² + η D k − 2S),   k = g(η)κ(Ωa)^η
/// ```
///
/// and `∂F/∂θ /(2a²)` as in the amplitude derivatives. `None` if
/// `∂F/∂Ω = 0`.
pub fn fold_frequency_derivatives(
    theta: &Parameters,
    gamma: f64,
    omega: f64,
    a: f64,
) -> Option<[f64; N_PARAMS]> {
    frequency_derivatives_at(theta, &PowerTerms::at(theta, omega, a), gamma, omega, a)
}

/// [`fold_frequency_derivatives`] with the power-law terms at the fold given.
fn frequency_derivatives_at(
    theta: &Parameters,
    t: &PowerTerms,
    gamma: f64,
    omega: f64,
    a: f64,
) -> Option<[f64; N_PARAMS]> {
    let (alpha, delta, beta, rho, kappa, eta, gain) = (
        theta[ALPHA],
        theta[DELTA],
        theta[BETA],
        theta[RHO],
        theta[KAPPA],
        theta[ETA],
        theta[GAIN],
    );
    let &PowerTerms {
        la,
        lwa,
        gr,
        ar,
        ge,
        wae,
        b,
        k,
    } = t;
    let w2 = omega * omega;
    let s = alpha + b - w2;
    let d = delta + k;
    let fw = omega * (d * d + eta * d * k - 2.0 * s);
    if !(fw.is_finite() && fw != 0.0) {
        return None;
    }
    let mut h = [0.0; N_PARAMS];
    h[ALPHA] = s;
    h[DELTA] = w2 * d;
    if beta != 0.0 {
        h[BETA] = s * gr * ar;
        h[RHO] = s * beta * ar * (g_derivative(rho) + gr * la);
    }
    if kappa != 0.0 {
        h[KAPPA] = w2 * d * ge * wae;
        h[ETA] = w2 * d * kappa * wae * (g_derivative(eta) + ge * lwa);
    }
    h[GAIN] = -gain * gamma * gamma / (a * a);
    let mut out = [0.0; N_PARAMS];
    for j in 0..N_PARAMS {
        out[j] = -h[j] / fw;
    }
    Some(out)
}

/// Derivatives of a fold `(a_f, Ω_f)` of the response curve at input
/// `gain·γ` with respect to θ, and the phase lag there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FoldDerivatives {
    /// `dΩ_f/dθ` (rad/s per unit of each parameter).
    pub omega: [f64; N_PARAMS],
    /// `da_f/dθ` (m per unit of each parameter).
    pub amplitude: [f64; N_PARAMS],
    /// Phase lag at the fold, rad, `atan2(Ω D, S)`.
    pub phase: f64,
    /// `dφ_f/dθ`.
    pub phase_derivative: [f64; N_PARAMS],
}

/// [`FoldDerivatives`] at the fold `(omega, a)` of the response at input
/// `gain·gamma`. A fold satisfies `F = 0` and `∂F/∂a = 2a Q = 0` with
/// (notation of [`super::objective`], `B = g(ρ)βa^ρ`, `K = g(η)κ(Ωa)^η`)
///
/// ```text
/// Q = S² + ρ S B + Ω² D² + η Ω² D K
/// ```
///
/// so `dΩ_f = −F_θ/F_Ω` ([`fold_frequency_derivatives`]) and
/// `da_f = −(Q_θ + Q_Ω dΩ_f)/Q_a` with
///
/// ```text
/// a Q_a = 2ρSB + ρ²B² + ρ²SB + 2ηΩ²DK + η²Ω²K² + η²Ω²DK
/// Ω Q_Ω = −4Ω²S − 2ρΩ²B + 2Ω²D² + 4ηΩ²DK + η²Ω²K² + η²Ω²DK
/// Q_α = 2S + ρB,   Q_δ = Ω²(2D + ηK)
/// Q_β = b_β (2S + ρB + ρS),              b_β = g(ρ) a^ρ
/// Q_ρ = b_ρ (2S + ρB + ρS) + S B,        b_ρ = β a^ρ (g'(ρ) + g(ρ) ln a)
/// Q_κ = Ω² k_κ (2D + ηK + ηD),           k_κ = g(η)(Ωa)^η
/// Q_η = Ω² k_η (2D + ηK + ηD) + Ω² D K,  k_η = κ(Ωa)^η (g'(η) + g(η) ln Ωa)
/// Q_gain = 0
/// ```
///
/// The phase `φ = atan2(ΩD, S)` moves with θ directly and through
/// `(a_f, Ω_f)`: `dS = S_θ + (ρB/a) da − 2Ω dΩ`,
/// `d(ΩD) = Ω D_θ + (ηΩK/a) da + (D + ηK) dΩ`. `None` where `F_Ω` or `Q_a`
/// vanishes (a cusp).
pub fn fold_derivatives(
    theta: &Parameters,
    gamma: f64,
    omega: f64,
    a: f64,
) -> Option<FoldDerivatives> {
    let terms = PowerTerms::at(theta, omega, a);
    let domega = frequency_derivatives_at(theta, &terms, gamma, omega, a)?;
    let (alpha, delta, beta, rho, kappa, eta) = (
        theta[ALPHA],
        theta[DELTA],
        theta[BETA],
        theta[RHO],
        theta[KAPPA],
        theta[ETA],
    );
    let PowerTerms {
        la,
        lwa,
        gr,
        ar,
        ge,
        wae,
        b,
        k,
    } = terms;
    let w = omega;
    let w2 = w * w;
    let s = alpha + b - w2;
    let d = delta + k;
    let qa = (2.0 * rho * s * b
        + rho * rho * b * b
        + rho * rho * s * b
        + 2.0 * eta * w2 * d * k
        + eta * eta * w2 * k * k
        + eta * eta * w2 * d * k)
        / a;
    let qw = (-4.0 * w2 * s - 2.0 * rho * w2 * b
        + 2.0 * w2 * d * d
        + 4.0 * eta * w2 * d * k
        + eta * eta * w2 * k * k
        + eta * eta * w2 * d * k)
        / w;
    if !(qa.is_finite() && qa != 0.0 && qw.is_finite()) {
        return None;
    }
    let mut q = [0.0; N_PARAMS];
    let mut ds = [0.0; N_PARAMS];
    let mut dd = [0.0; N_PARAMS];
    q[ALPHA] = 2.0 * s + rho * b;
    ds[ALPHA] = 1.0;
    q[DELTA] = w2 * (2.0 * d + eta * k);
    dd[DELTA] = 1.0;
    if beta != 0.0 {
        let b_beta = gr * ar;
        let b_rho = beta * ar * (g_derivative(rho) + gr * la);
        q[BETA] = b_beta * (2.0 * s + rho * b + rho * s);
        q[RHO] = b_rho * (2.0 * s + rho * b + rho * s) + s * b;
        ds[BETA] = b_beta;
        ds[RHO] = b_rho;
    }
    if kappa != 0.0 {
        let k_kappa = ge * wae;
        let k_eta = kappa * wae * (g_derivative(eta) + ge * lwa);
        q[KAPPA] = w2 * k_kappa * (2.0 * d + eta * k + eta * d);
        q[ETA] = w2 * k_eta * (2.0 * d + eta * k + eta * d) + w2 * d * k;
        dd[KAPPA] = k_kappa;
        dd[ETA] = k_eta;
    }
    let mut da = [0.0; N_PARAMS];
    let mut dphi = [0.0; N_PARAMS];
    let den = s * s + w2 * d * d;
    for j in 0..N_PARAMS {
        da[j] = -(q[j] + qw * domega[j]) / qa;
        let dsj = ds[j] + rho * b / a * da[j] - 2.0 * w * domega[j];
        let dqj = w * dd[j] + eta * w * k / a * da[j] + (d + eta * k) * domega[j];
        dphi[j] = (s * dqj - w * d * dsj) / den;
    }
    Some(FoldDerivatives {
        omega: domega,
        amplitude: da,
        phase: (w * d).atan2(s),
        phase_derivative: dphi,
    })
}

/// Eq 31 plus the jump residuals (module docs), weight `λ`, in the
/// optimisation variables of [`Problem`]. A curve whose model never meets
/// the backbone makes θ not evaluable.
#[derive(Debug, Clone)]
pub struct WithJumps<'a> {
    pub problem: Problem<'a>,
    pub targets: Vec<JumpTarget>,
    /// λ ≥ 0.
    pub weight: f64,
}

impl<'a> WithJumps<'a> {
    pub fn new(problem: Problem<'a>, weight: f64) -> Self {
        let targets = jump_targets(problem.data);
        Self {
            problem,
            targets,
            weight,
        }
    }

    /// The model's predicted jump of target `t` at θ: the first jump of the
    /// curve's model sweep (its fold frequency) with `dΩ_f/dθ`, or, where
    /// the model sweep does not jump, the phase-quadrature frequency with
    /// its derivative (module docs).
    pub fn predicted(&self, theta: &Parameters, t: &JumpTarget) -> Option<(f64, [f64; N_PARAMS])> {
        let c = &self.problem.data.curves[t.curve];
        let r = ForcedResponse::from_normalised(
            &normalised_model(theta),
            theta[GAIN] * c.gamma,
            Formulation::HarmonicBalance,
        )
        .ok()?;
        let sw = r
            .sweep_from(&c.omegas, c.direction, super::objective::first_amplitude(c))
            .ok()?;
        self.predicted_from(
            theta,
            t,
            sw.jumps.first().map(|j| (j.omega, j.amplitude_before)),
        )
    }

    /// [`Self::predicted`] from the curve's first model jump `(Ω, a before)`
    /// already found by its sweep.
    fn predicted_from(
        &self,
        theta: &Parameters,
        t: &JumpTarget,
        jump: FirstJump,
    ) -> Option<(f64, [f64; N_PARAMS])> {
        let c = &self.problem.data.curves[t.curve];
        match jump {
            Some((w, a)) => fold_frequency_derivatives(theta, c.gamma, w, a).map(|d| (w, d)),
            None => quadrature_frequency(theta, c.gamma).ok()?,
        }
    }

    /// Jump residuals and (if `jacobian`) their rows `∂r/∂θ` at θ.
    pub fn jump_residuals(
        &self,
        theta: &Parameters,
        jacobian: bool,
    ) -> Option<(Vec<f64>, Vec<[f64; N_PARAMS]>)> {
        use rayon::prelude::*;
        // one model sweep per target, in parallel (collected in order)
        let predicted: Vec<Option<(f64, [f64; N_PARAMS])>> = self
            .targets
            .par_iter()
            .map(|t| self.predicted(theta, t))
            .collect();
        self.jump_residuals_of(predicted, jacobian)
    }

    /// The jump residuals from the first model jump of every curve (data
    /// order), as [`super::objective::evaluate_with_jumps`] returns them.
    fn jump_residuals_from(
        &self,
        theta: &Parameters,
        jumps: &[FirstJump],
        jacobian: bool,
    ) -> Option<(Vec<f64>, Vec<[f64; N_PARAMS]>)> {
        use rayon::prelude::*;
        let predicted: Vec<Option<(f64, [f64; N_PARAMS])>> = self
            .targets
            .par_iter()
            .map(|t| self.predicted_from(theta, t, *jumps.get(t.curve)?))
            .collect();
        self.jump_residuals_of(predicted, jacobian)
    }

    fn jump_residuals_of(
        &self,
        predicted: Vec<Option<(f64, [f64; N_PARAMS])>>,
        jacobian: bool,
    ) -> Option<(Vec<f64>, Vec<[f64; N_PARAMS]>)> {
        let sw = self.weight.sqrt();
        let mut r = Vec::with_capacity(self.targets.len());
        let mut j = Vec::new();
        for (t, p) in self.targets.iter().zip(predicted) {
            let (w, dw) = p?;
            let f = sw * t.scale / t.omega;
            // dead zone: a model fold anywhere inside the measured step
            // interval [Ω_J, Ω_J,next] agrees with the data (the sweep
            // cannot resolve it further), so the residual is the distance
            // outside that interval
            let (d, inside) = if w < t.omega {
                (w - t.omega, false)
            } else if w > t.omega_next {
                (w - t.omega_next, false)
            } else {
                (0.0, true)
            };
            r.push(f * d);
            if jacobian {
                let mut row = if inside { [0.0; N_PARAMS] } else { dw };
                for v in row.iter_mut() {
                    *v *= f;
                }
                j.push(row);
            }
        }
        Some((r, j))
    }

    /// Predicted/measured − 1 per target (for reports).
    pub fn relative_errors(&self, theta: &Parameters) -> Vec<Option<f64>> {
        self.targets
            .iter()
            .map(|t| self.predicted(theta, t).map(|(w, _)| w / t.omega - 1.0))
            .collect()
    }
}

impl LeastSquares for WithJumps<'_> {
    /// The sweeps dominate; the derivatives are analytic and cheap.
    fn jacobian_with_trials(&self) -> bool {
        true
    }

    fn n_params(&self) -> usize {
        self.problem.free.len()
    }

    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        let th = self.problem.theta(u);
        // one sweep per curve serves Eq 31 and the jump residuals
        let (e, jumps) = evaluate_with_jumps(
            self.problem.data,
            &th,
            false,
            self.problem.spec.phase_weight,
        )
        .ok()?;
        let mut r = e.residuals;
        let (rj, _) = self.jump_residuals_from(&th, &jumps, false)?;
        r.extend(rj);
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let th = self.problem.theta(u);
        let (e, jumps) =
            evaluate_with_jumps(self.problem.data, &th, true, self.problem.spec.phase_weight)
                .ok()?;
        let (mut r, mut j) = self.problem.residuals_and_jacobian_of(&th, e)?;
        let (rj, jj) = self.jump_residuals_from(&th, &jumps, true)?;
        let cols = self.problem.dtheta_du(&th);
        for row in &jj {
            for col in &cols {
                let s: f64 = (0..N_PARAMS)
                    .filter(|&p| col[p] != 0.0)
                    .map(|p| row[p] * col[p])
                    .sum();
                j.push(if s.is_finite() { s } else { 0.0 });
            }
        }
        r.extend(rj);
        r.iter().all(|v| v.is_finite()).then_some((r, j))
    }
}

/// Eq 31 cost alone at θ (for reporting a jump-weighted fit).
pub fn eq31_cost(data: &Dataset, theta: &Parameters) -> Result<f64, SolveError> {
    Ok(evaluate(data, theta, false)?.cost())
}
