//! Identification from phase-resonance points only: per input level γ the
//! frequency and amplitude where the response lags the input by 90°
//! (paper §4, Table 8's experimental columns `ā_PQ`, `f̄_PQ`).
//!
//! ## Model side: the phase-quadrature conditions
//! On the first-order harmonic-balance response (the algebraic equation
//! behind Eq 11 and Eq 30, [`crate::harmonic_balance`]) the phase lag is
//! `tan φ = Ω D / S`, so `φ = 90°` exactly where the stiffness bracket
//! vanishes. The model's phase-quadrature point `(a, Ω)` at input `gain·γ`
//! solves ([`ForcedResponse::phase_quadrature`])
//!
//! ```text
//! G₁ = S = α + g(ρ) β a^ρ − Ω² = 0                    (backbone, Eq 9)
//! G₂ = a Ω D − gain γ = 0,   D = δ + g(η) κ (Ω a)^η    (force balance, Eq 22)
//! ```
//!
//! (with `S = 0` the harmonic-balance equation `a²[S² + Ω²D²] = (gain γ)²`
//! reduces to `a Ω D = gain γ`).
//!
//! ## Residuals
//! For each measured point `i` (γᵢ, Ω̄ᵢ = 2π f̄ᵢ, āᵢ, weight wᵢ) two residuals:
//!
//! ```text
//! r_a,i = √wᵢ (a(γᵢ; θ) − āᵢ) / γᵢ                 (as in Eq 31, s²)
//! r_f,i = √wᵢ W (Ω(γᵢ; θ) − Ω̄ᵢ) / Ω̄ᵢ              (relative, scaled to s²)
//! W = w_f · √( mean_i (āᵢ/γᵢ)² ) / ζ₀,   ζ₀ = γ₀ / (2 ā₀ Ω̄₀²)
//! ```
//!
//! (ζ₀: the damping ratio of the lowest level's point read as a linear
//! resonance, `a = γ/(2ζω²)`; a fixed number of the data, so the objective
//! is a fixed weighted least squares.) Why this makes the two comparable: if
//! the measured complex response has a relative error ε, the amplitude is
//! off by ~ε (residual `(ā/γ)·ε`) while the 90° crossing moves by
//! `ΔΩ/Ω ≈ ζ ε`, because the phase slope at resonance is `dφ/dΩ = 1/(ζΩ)`.
//! So with the *relative frequency weight* `w_f = 1` (default) both kinds of
//! residual have the same size for the same measurement error. `w_f > 1`
//! trusts the frequencies more (e.g. a coarse amplitude calibration),
//! `w_f < 1` less (e.g. a frequency grid coarser than ζ ε). At an exact fit
//! the weighting does not matter.
//!
//! ## Jacobian by implicit differentiation
//! With `y = (a, Ω)`, `q = aΩ`, `E = δ + (1+η) g(η) κ q^η`:
//!
//! ```text
//! ∂G/∂y = [ ρ g(ρ) β a^(ρ−1)   −2Ω ]      det = E (ρ g(ρ) β a^ρ + 2Ω²)
//!         [ Ω E                 a E ]
//! ∂G₁/∂α = 1,  ∂G₁/∂β = g(ρ) a^ρ,  ∂G₁/∂ρ = β a^ρ (g'(ρ) + g(ρ) ln a)
//! ∂G₂/∂δ = q,  ∂G₂/∂κ = g(η) q^(1+η),  ∂G₂/∂η = κ q^(1+η) (g'(η) + g(η) ln q)
//! ∂G₂/∂gain = −γ
//! dy/dθ = −(∂G/∂y)⁻¹ ∂G/∂θ
//! ```
//!
//! (`g'` as in [`crate::special::g_derivative`]). The optimisation variables,
//! bounds, log scaling, stiffness sign and multistart are those of the sweep
//! fit ([`super::objective`], [`super::global`]).
//!
//! ## Identifiability
//! At an exact fit the conditions decouple: the N frequencies
//! determine the *stiffness* parameters (α, β, ρ) through the backbone
//! `Ω̄ᵢ² = α + g(ρ)β āᵢ^ρ`, the N amplitudes the *damping* parameters
//! (δ, κ, η, gain) through `gain γᵢ = q̄ᵢ (δ + g(η) κ q̄ᵢ^η)`. So each group
//! needs at least as many levels as it has free parameters, and `gain` is
//! never identifiable together with the free damping coefficients (scaling
//! gain, δ, κ by one factor leaves every point unchanged). These structural
//! checks run before the fit ([`check_identifiable`]); after it the
//! column-normalised Jacobian is checked for numerical rank deficiency
//! (smallest/largest singular value below [`RANK_TOLERANCE`]) and the
//! parameters of the null direction are named ([`PrFitError::RankDeficient`]).

use super::data::{Curve, Dataset};
use super::global;
use super::levenberg_marquardt::{LeastSquares, LmOptions, Termination};
use super::models::*;
use super::objective::{normalised_model, FitSpec, Problem, Sign, SpecError, Status};
use super::parameters::Parameters;
use super::uncertainty::{self, Uncertainty};
use super::Minimum;
use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use crate::power_law::g_unchecked;
use crate::special::g_derivative;
use thiserror::Error;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Smallest ratio of singular values of the column-normalised Jacobian at
/// the optimum below which the fit is reported as rank deficient.
pub const RANK_TOLERANCE: f64 = 1e-8;

/// One measured phase-resonance point (SI units, zero-to-peak).
#[derive(Debug, Clone, PartialEq)]
pub struct PrPoint {
    /// Level label.
    pub level: String,
    /// Input acceleration amplitude γ, m/s².
    pub gamma: f64,
    /// Frequency of 90° phase lag Ω̄, rad/s.
    pub omega: f64,
    /// Displacement amplitude there ā, m.
    pub amplitude: f64,
    /// Weight of both squared residuals of the point (default 1).
    pub weight: f64,
}

/// Validated phase-resonance points, sorted by increasing γ.
#[derive(Debug, Clone, PartialEq)]
pub struct PrDataset {
    pub points: Vec<PrPoint>,
}

/// Why a phase-resonance data set is invalid. Each variant names the
/// offending value.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PrDataError {
    #[error("no phase-resonance points")]
    Empty,
    #[error(transparent)]
    Limit(#[from] crate::limits::LimitError),
    #[error("level {level}: {what} = {value} is not a finite number")]
    NotFinite {
        level: String,
        what: &'static str,
        value: f64,
    },
    #[error("level {level}: {what} = {value} must be > 0")]
    NotPositive {
        level: String,
        what: &'static str,
        value: f64,
    },
    #[error("level {level}: weight = {value} must be finite and >= 0")]
    BadWeight { level: String, value: f64 },
    #[error("levels {first} and {second} have the same gamma = {gamma} m/s^2 (one phase-resonance point per input level)")]
    DuplicateGamma {
        first: String,
        second: String,
        gamma: f64,
    },
    #[error("every weight is 0: nothing to fit")]
    ZeroWeights,
}

impl PrDataset {
    /// Validates the points and sorts them by γ.
    pub fn new(mut points: Vec<PrPoint>) -> Result<Self, PrDataError> {
        if points.is_empty() {
            return Err(PrDataError::Empty);
        }
        crate::limits::PHASE_RESONANCE_POINTS.check(points.len() as f64)?;
        for p in &points {
            let f_hz = p.omega / TWO_PI;
            for (what, v) in [
                ("gamma", p.gamma),
                ("frequency [Hz]", f_hz),
                ("amplitude", p.amplitude),
            ] {
                if !v.is_finite() {
                    return Err(PrDataError::NotFinite {
                        level: p.level.clone(),
                        what,
                        value: v,
                    });
                }
                if v <= 0.0 {
                    return Err(PrDataError::NotPositive {
                        level: p.level.clone(),
                        what,
                        value: v,
                    });
                }
            }
            if !(p.weight.is_finite() && p.weight >= 0.0) {
                return Err(PrDataError::BadWeight {
                    level: p.level.clone(),
                    value: p.weight,
                });
            }
        }
        points.sort_by(|a, b| a.gamma.total_cmp(&b.gamma));
        for w in points.windows(2) {
            if w[0].gamma == w[1].gamma {
                return Err(PrDataError::DuplicateGamma {
                    first: w[0].level.clone(),
                    second: w[1].level.clone(),
                    gamma: w[0].gamma,
                });
            }
        }
        if points.iter().all(|p| p.weight == 0.0) {
            return Err(PrDataError::ZeroWeights);
        }
        Ok(Self { points })
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The points as one-step "curves" (what [`FitSpec::new`] and the
    /// variable mapping of [`Problem`] read: peaks, A_ref, Ω_ref, Ω range).
    pub fn as_curves(&self) -> Dataset {
        Dataset {
            curves: self
                .points
                .iter()
                .map(|p| Curve {
                    level: p.level.clone(),
                    gamma: p.gamma,
                    direction: SweepDirection::Up,
                    omegas: vec![p.omega],
                    amplitudes: vec![p.amplitude],
                    phases: None,
                    weights: vec![p.weight],
                })
                .collect(),
        }
    }

    /// `ζ₀ = γ₀/(2 ā₀ Ω̄₀²)` of the lowest level (module docs).
    pub fn zeta0(&self) -> f64 {
        let p = &self.points[0];
        p.gamma / (2.0 * p.amplitude * p.omega * p.omega)
    }

    /// The absolute frequency-residual scale `W = w_f √mean(ā/γ)² / ζ₀`, s².
    pub fn frequency_scale(&self, frequency_weight: f64) -> f64 {
        frequency_weight * self.amplitude_scale() / self.zeta0()
    }

    /// `√mean_i (āᵢ/γᵢ)²`, s² (the scale of the amplitude residuals).
    pub fn amplitude_scale(&self) -> f64 {
        let n = self.points.len() as f64;
        (self
            .points
            .iter()
            .map(|p| (p.amplitude / p.gamma).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
    }
}

/// Default structure, bounds and start for `kind` from phase-resonance
/// points: exactly [`FitSpec::new_signed`] applied to the points read as
/// one-step curves, i.e. `α₀ = Ω̄₀²`, `δ₀ = γ₀/(ā₀ Ω̄₀)` of the lowest
/// level, β_ref,0 from the backbone shift to the highest level, the same
/// bounds as the sweep fit (with A_ref the largest ā).
pub fn default_spec(kind: ModelKind, data: &PrDataset, sign: Sign) -> FitSpec {
    FitSpec::new_signed(kind, &data.as_curves(), sign)
}

/// Errors of a phase-resonance fit.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PrFitError {
    #[error(transparent)]
    Data(#[from] PrDataError),
    #[error(transparent)]
    Spec(#[from] SpecError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("the {model} fit has {free} free parameters but {points} phase-resonance point(s) give only {equations} equations")]
    TooFewPoints {
        model: ModelKind,
        points: usize,
        equations: usize,
        free: usize,
    },
    #[error("not identifiable from phase-resonance points: {parameters}: {reason}", parameters = .parameters.join(", "))]
    NotIdentifiable {
        parameters: Vec<&'static str>,
        reason: String,
    },
    #[error("not identifiable from these phase-resonance points: the Jacobian at the optimum is rank deficient (singular-value ratio {ratio:.3e}) along a direction of {parameters}; fix one of them", parameters = .parameters.join(", "))]
    RankDeficient {
        parameters: Vec<&'static str>,
        ratio: f64,
    },
    #[error("frequency weight {0} must be finite and > 0")]
    BadFrequencyWeight(f64),
    #[error("no start point of the {model} fit could be evaluated (no phase-quadrature point at some level)")]
    NoStartEvaluable { model: ModelKind },
    #[error(
        "the fitted model has no phase-quadrature point at level {level} (gamma = {gamma} m/s^2)"
    )]
    NoQuadrature { level: String, gamma: f64 },
}

/// Structural identifiability (module docs): equations vs free parameters,
/// per group (stiffness α, β, ρ from the frequencies; damping δ, κ, η, gain
/// from the amplitudes), and the gain–damping scale invariance.
pub fn check_identifiable(spec: &FitSpec, data: &PrDataset) -> Result<(), PrFitError> {
    let free = spec.free_indices();
    if free.is_empty() {
        return Err(SpecError::NothingFree.into());
    }
    let n = data.len();
    if 2 * n < free.len() {
        return Err(PrFitError::TooFewPoints {
            model: spec.kind,
            points: n,
            equations: 2 * n,
            free: free.len(),
        });
    }
    let is_free = |j: usize| spec.status[j] == Status::Free;
    if is_free(GAIN) {
        let damping: Vec<usize> = [DELTA, KAPPA]
            .into_iter()
            .filter(|&j| spec.status[j] != Status::Absent)
            .collect();
        if damping.iter().all(|&j| is_free(j)) {
            let mut parameters = vec![PARAM_NAMES[GAIN]];
            parameters.extend(damping.iter().map(|&j| PARAM_NAMES[j]));
            return Err(PrFitError::NotIdentifiable {
                parameters,
                reason: "scaling gain and the damping coefficients by one factor leaves every phase-resonance point unchanged (a Omega (delta + g(eta) kappa (a Omega)^eta) = gain gamma); fix gain (default 1) or a damping coefficient".into(),
            });
        }
    }
    for (group, what, eq) in [
        (
            &[ALPHA, BETA, RHO][..],
            "stiffness",
            "the backbone Omega^2 = alpha + g(rho) beta a^rho at each level's measured (a, Omega)",
        ),
        (
            &[DELTA, KAPPA, ETA, GAIN][..],
            "damping",
            "gain gamma = a Omega (delta + g(eta) kappa (a Omega)^eta) at each level",
        ),
    ] {
        let f: Vec<&'static str> = group
            .iter()
            .filter(|&&j| is_free(j))
            .map(|&j| PARAM_NAMES[j])
            .collect();
        if f.len() > n {
            return Err(PrFitError::NotIdentifiable {
                reason: format!(
                    "{} free {what} parameters but only {n} level(s): each level gives one equation for them ({eq}); give at least {} levels or fix {} of them",
                    f.len(),
                    f.len(),
                    f.len() - n
                ),
                parameters: f,
            });
        }
    }
    Ok(())
}

/// The model's phase-quadrature point `(Ω, a)` at each level (input
/// `gain·γᵢ`), `None` where the response curve never meets the backbone.
pub fn model_points(
    data: &PrDataset,
    theta: &Parameters,
) -> Result<Vec<Option<(f64, f64)>>, SolveError> {
    let model = normalised_model(theta);
    data.points
        .iter()
        .map(|p| {
            let r = ForcedResponse::from_normalised(
                &model,
                theta[GAIN] * p.gamma,
                Formulation::HarmonicBalance,
            )?;
            Ok(r.phase_quadrature()?.map(|q| (q.omega, q.amplitude)))
        })
        .collect()
}

/// `(da/dθ, dΩ/dθ)` at the phase-quadrature point `(Ω, a)` of the model
/// driven by `gain·γ` (`gamma` = γ, the measured level, before the gain), by implicit differentiation of `G₁ = G₂ = 0` (module
/// docs). `None` where `∂G/∂y` is singular (`E = 0` or
/// `ρ g(ρ) β a^ρ = −2Ω²`, a vertical backbone of a softening model).
pub fn quadrature_derivatives(
    theta: &Parameters,
    gamma: f64,
    omega: f64,
    a: f64,
) -> Option<([f64; N_PARAMS], [f64; N_PARAMS])> {
    let (beta, rho, delta, kappa, eta) = (
        theta[BETA],
        theta[RHO],
        theta[DELTA],
        theta[KAPPA],
        theta[ETA],
    );
    let la = a.ln();
    let q = a * omega;
    let lq = q.ln();
    let (gr, dgr, ar) = if beta != 0.0 {
        (g_unchecked(rho), g_derivative(rho), (rho * la).exp())
    } else {
        (0.0, 0.0, 0.0)
    };
    let (ge, dge, qe) = if kappa != 0.0 {
        (g_unchecked(eta), g_derivative(eta), (eta * lq).exp())
    } else {
        (0.0, 0.0, 0.0)
    };
    let e = delta + (1.0 + eta) * ge * kappa * qe;
    let a11 = rho * gr * beta * ar / a;
    let a12 = -2.0 * omega;
    let a21 = omega * e;
    let a22 = a * e;
    let det = a11 * a22 - a12 * a21;
    if !(det.is_finite() && det != 0.0) {
        return None;
    }
    let mut g1 = [0.0; N_PARAMS];
    let mut g2 = [0.0; N_PARAMS];
    g1[ALPHA] = 1.0;
    if beta != 0.0 {
        g1[BETA] = gr * ar;
        g1[RHO] = beta * ar * (dgr + gr * la);
    }
    g2[DELTA] = q;
    if kappa != 0.0 {
        g2[KAPPA] = ge * q * qe;
        g2[ETA] = kappa * q * qe * (dge + ge * lq);
    }
    g2[GAIN] = -gamma;
    let mut da = [0.0; N_PARAMS];
    let mut dw = [0.0; N_PARAMS];
    for j in 0..N_PARAMS {
        da[j] = -(a22 * g1[j] - a12 * g2[j]) / det;
        dw[j] = -(-a21 * g1[j] + a11 * g2[j]) / det;
    }
    (da.iter().chain(&dw).all(|v| v.is_finite())).then_some((da, dw))
}

/// Model points, residuals (interleaved per point: amplitude, frequency)
/// and optionally `∂r/∂θ` for all seven natural parameters.
#[derive(Debug, Clone)]
pub struct PrEvaluation {
    /// Model `(Ω, a)` per point.
    pub model: Vec<(f64, f64)>,
    pub residuals: Vec<f64>,
    pub jacobian: Option<Vec<[f64; N_PARAMS]>>,
}

impl PrEvaluation {
    pub fn cost(&self) -> f64 {
        self.residuals.iter().map(|r| r * r).sum()
    }
}

/// Evaluates the residuals at θ with the absolute frequency scale `w_abs`
/// (`W` of the module docs). `Ok(None)` if some level has no
/// phase-quadrature point (or a singular `∂G/∂y` when `jacobian`).
pub fn evaluate_phase_resonance(
    data: &PrDataset,
    theta: &Parameters,
    w_abs: f64,
    jacobian: bool,
) -> Result<Option<PrEvaluation>, SolveError> {
    let pts = model_points(data, theta)?;
    let n = data.len();
    let mut model = Vec::with_capacity(n);
    let mut residuals = Vec::with_capacity(2 * n);
    let mut jac = jacobian.then(|| Vec::with_capacity(2 * n));
    for (p, m) in data.points.iter().zip(pts) {
        let Some((w, a)) = m else {
            return Ok(None);
        };
        let sw = p.weight.sqrt();
        model.push((w, a));
        residuals.push(sw * (a - p.amplitude) / p.gamma);
        residuals.push(sw * w_abs * (w - p.omega) / p.omega);
        if let Some(j) = jac.as_mut() {
            let Some((da, dw)) = quadrature_derivatives(theta, p.gamma, w, a) else {
                return Ok(None);
            };
            j.push(da.map(|v| v * sw / p.gamma));
            j.push(dw.map(|v| v * sw * w_abs / p.omega));
        }
    }
    Ok(Some(PrEvaluation {
        model,
        residuals,
        jacobian: jac,
    }))
}

/// The least-squares problem in the optimisation variables of
/// [`Problem`] (log-scaled coefficients, β_ref, κ_ref, sign).
struct PrProblem<'a> {
    data: &'a PrDataset,
    map: Problem<'a>,
    w_abs: f64,
}

impl LeastSquares for PrProblem<'_> {
    fn n_params(&self) -> usize {
        self.map.free.len()
    }

    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        let th = self.map.theta(u);
        let e = evaluate_phase_resonance(self.data, &th, self.w_abs, false).ok()??;
        e.residuals
            .iter()
            .all(|r| r.is_finite())
            .then_some(e.residuals)
    }

    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let th = self.map.theta(u);
        let e = evaluate_phase_resonance(self.data, &th, self.w_abs, true).ok()??;
        let cols = self.map.dtheta_du(&th);
        let jt = e.jacobian.as_ref()?;
        let mut j = Vec::with_capacity(jt.len() * cols.len());
        for row in jt {
            for col in &cols {
                let s: f64 = (0..N_PARAMS)
                    .filter(|&p| col[p] != 0.0)
                    .map(|p| row[p] * col[p])
                    .sum();
                j.push(s);
            }
        }
        (e.residuals.iter().chain(&j).all(|r| r.is_finite())).then_some((e.residuals, j))
    }
}

/// Options of [`fit_phase_resonance`].
#[derive(Debug, Clone, PartialEq)]
pub struct PrFitOptions {
    /// Number of starts (1 = local fit from the data-derived start).
    pub starts: usize,
    pub seed: u64,
    pub lm: LmOptions,
    /// Relative frequency weight `w_f` (module docs), default 1.
    pub frequency_weight: f64,
}

impl Default for PrFitOptions {
    fn default() -> Self {
        Self {
            starts: 1,
            seed: 1,
            lm: LmOptions::default(),
            frequency_weight: 1.0,
        }
    }
}

/// Measured and model phase-resonance point of one level.
#[derive(Debug, Clone, PartialEq)]
pub struct PrRow {
    pub level: String,
    pub gamma: f64,
    /// Measured Ω̄ (rad/s) and ā (m).
    pub measured_omega: f64,
    pub measured_amplitude: f64,
    /// Model Ω and a at 90° phase.
    pub model_omega: f64,
    pub model_amplitude: f64,
}

impl PrRow {
    /// `(model − measured)/measured` in %: (frequency, amplitude).
    pub fn differences_percent(&self) -> (f64, f64) {
        (
            100.0 * (self.model_omega - self.measured_omega) / self.measured_omega,
            100.0 * (self.model_amplitude - self.measured_amplitude) / self.measured_amplitude,
        )
    }
}

/// Result of [`fit_phase_resonance`].
#[derive(Debug, Clone, PartialEq)]
pub struct PrFitResult {
    pub kind: ModelKind,
    pub status: [Status; N_PARAMS],
    pub stiffness_sign: Sign,
    /// Best θ = (α, δ, β, ρ, κ, η, gain).
    pub theta: Parameters,
    /// Σ (r_a² + r_f²).
    pub cost: f64,
    /// Levels (points); residuals are twice as many.
    pub n_points: usize,
    pub n_free: usize,
    /// The absolute frequency-residual scale `W` (s²).
    pub frequency_scale: f64,
    pub termination: Termination,
    pub iterations: usize,
    /// Distinct minima, best first.
    pub minima: Vec<Minimum>,
    /// `None` if there are no residual degrees of freedom (2N = p).
    pub uncertainty: Option<Uncertainty>,
    pub rows: Vec<PrRow>,
}

impl PrFitResult {
    fn n_res(&self) -> f64 {
        2.0 * self.n_points as f64
    }

    /// AIC over the 2N residuals, `2N ln(cost/2N) + 2p`.
    pub fn aic(&self) -> f64 {
        let n = self.n_res();
        n * (self.cost / n).ln() + 2.0 * self.n_free as f64
    }

    /// BIC over the 2N residuals, `2N ln(cost/2N) + p ln 2N`.
    pub fn bic(&self) -> f64 {
        let n = self.n_res();
        n * (self.cost / n).ln() + self.n_free as f64 * n.ln()
    }

    /// RMS of all residuals (s²).
    pub fn rms(&self) -> f64 {
        (self.cost / self.n_res()).sqrt()
    }

    /// Mass-normalised model of the best fit (γ must be scaled by `gain`).
    pub fn model(&self) -> crate::model::NormalisedModel {
        normalised_model(&self.theta)
    }
}

/// Fits `spec` to phase-resonance points: the same bounded LM
/// ([`super::levenberg_marquardt::minimise`]) and multistart
/// ([`global::multistart`]) as the sweep fit, analytic Jacobian (module
/// docs), structural and numerical identifiability checks, linearised
/// uncertainty. `progress` is called once per finished start.
pub fn fit_phase_resonance(
    data: &PrDataset,
    spec: &FitSpec,
    opts: &PrFitOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<PrFitResult, PrFitError> {
    if !(opts.frequency_weight.is_finite() && opts.frequency_weight > 0.0) {
        return Err(PrFitError::BadFrequencyWeight(opts.frequency_weight));
    }
    check_identifiable(spec, data)?;
    let curves = data.as_curves();
    let map = Problem::new(&curves, spec)?;
    let w_abs = data.frequency_scale(opts.frequency_weight);
    let problem = PrProblem { data, map, w_abs };
    let map = &problem.map;
    let (lo, hi) = map.u_bounds();
    let u0 = map.u_of(&spec.start);
    let mut lm = opts.lm;
    if lm.cost_floor == 0.0 {
        let scale: f64 = data
            .points
            .iter()
            .map(|p| p.weight * ((p.amplitude / p.gamma).powi(2) + w_abs * w_abs))
            .sum();
        lm.cost_floor = 1e-28 * scale;
    }
    let found = global::multistart(
        &problem,
        &u0,
        &lo,
        &hi,
        opts.starts.max(1),
        opts.seed,
        &lm,
        progress,
    );
    let best = found
        .first()
        .ok_or(PrFitError::NoStartEvaluable { model: spec.kind })?;
    let theta = map.theta(&best.result.u);
    let Some(e) = evaluate_phase_resonance(data, &theta, w_abs, true)? else {
        // name the first level without a 90° point (or a singular ∂G/∂y)
        let pts = model_points(data, &theta)?;
        let i = pts.iter().position(|p| p.is_none()).unwrap_or(0);
        let p = &data.points[i];
        return Err(PrFitError::NoQuadrature {
            level: p.level.clone(),
            gamma: p.gamma,
        });
    };
    if let Some((_, ju)) = problem.residuals_and_jacobian(&best.result.u) {
        if let Some((parameters, ratio)) = rank_deficiency(&ju, &map.free) {
            return Err(PrFitError::RankDeficient { parameters, ratio });
        }
    }
    let jac = e.jacobian.as_ref().expect("jacobian requested");
    let unc = uncertainty::uncertainty(&theta, &map.free, jac, &e.residuals);
    let minima = found
        .iter()
        .map(|m| Minimum {
            theta: map.theta(&m.result.u),
            cost: m.result.cost,
            termination: m.result.termination,
            iterations: m.result.iterations,
            count: m.count,
        })
        .collect();
    let rows = data
        .points
        .iter()
        .zip(&e.model)
        .map(|(p, &(w, a))| PrRow {
            level: p.level.clone(),
            gamma: p.gamma,
            measured_omega: p.omega,
            measured_amplitude: p.amplitude,
            model_omega: w,
            model_amplitude: a,
        })
        .collect();
    Ok(PrFitResult {
        kind: spec.kind,
        status: spec.status,
        stiffness_sign: spec.stiffness_sign,
        theta,
        cost: e.cost(),
        n_points: data.len(),
        n_free: map.free.len(),
        frequency_scale: w_abs,
        termination: best.result.termination,
        iterations: best.result.iterations,
        minima,
        uncertainty: unc,
        rows,
    })
}

/// Numerical rank check of the Jacobian `j` (row-major, `free.len()`
/// columns): columns scaled to unit norm, singular values by SVD. Returns
/// the parameters of the right singular vector of the smallest singular value
/// (entries with |v_k| ≥ 0.3, at least the largest) and the ratio
/// σ_min/σ_max if it is below [`RANK_TOLERANCE`] (or a column is zero).
pub fn rank_deficiency(j: &[f64], free: &[usize]) -> Option<(Vec<&'static str>, f64)> {
    let p = free.len();
    if p == 0 {
        return None;
    }
    let m = j.len() / p;
    let mut norms = vec![0.0f64; p];
    for r in 0..m {
        for k in 0..p {
            norms[k] += j[r * p + k] * j[r * p + k];
        }
    }
    let zero: Vec<&'static str> = (0..p)
        .filter(|&k| !(norms[k] > 0.0 && norms[k].is_finite()))
        .map(|k| PARAM_NAMES[free[k]])
        .collect();
    if !zero.is_empty() {
        return Some((zero, 0.0));
    }
    let mat = nalgebra::DMatrix::from_fn(m.max(p), p, |r, k| {
        if r < m {
            j[r * p + k] / norms[k].sqrt()
        } else {
            0.0
        }
    });
    let svd = nalgebra::SVD::new(mat, false, true);
    let v_t = svd.v_t.as_ref()?;
    let s = &svd.singular_values;
    let (mut imin, mut imax) = (0, 0);
    for i in 0..s.len() {
        if s[i] < s[imin] {
            imin = i;
        }
        if s[i] > s[imax] {
            imax = i;
        }
    }
    let ratio = s[imin] / s[imax];
    if ratio >= RANK_TOLERANCE {
        return None;
    }
    let v: Vec<f64> = (0..p).map(|k| v_t[(imin, k)]).collect();
    let kmax = (0..p)
        .max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))
        .unwrap_or(0);
    let names = (0..p)
        .filter(|&k| k == kmax || v[k].abs() >= 0.3)
        .map(|k| PARAM_NAMES[free[k]])
        .collect();
    Some((names, ratio))
}

/// One candidate of [`integer_search_phase_resonance`].
#[derive(Debug, Clone, PartialEq)]
pub struct PrIntegerCandidate {
    pub rho: Option<i64>,
    pub eta: Option<i64>,
    pub fit: Result<PrFitResult, PrFitError>,
}

/// Integer exponents (as `--integer` of the sweep fit,
/// [`super::integer_search`]): every integer value of each free exponent
/// within its bounds (not below −2) is held fixed and the coefficients are
/// fitted. The start of each coefficient keeps its equivalent value at the
/// reference amplitude: `β₀' g(ρ') A_ref^ρ' = β₀ g(ρ) A_ref^ρ` (and κ with
/// `Ω_ref A_ref`). Candidates in increasing (ρ, η) order.
pub fn integer_search_phase_resonance(
    data: &PrDataset,
    spec: &FitSpec,
    opts: &PrFitOptions,
) -> Vec<PrIntegerCandidate> {
    let range = |j: usize| -> Vec<Option<i64>> {
        if spec.status[j] != Status::Free {
            return vec![None];
        }
        let (lo, hi) = spec.bounds[j];
        ((lo.ceil() as i64).max(-2)..=hi.floor() as i64)
            .map(Some)
            .collect()
    };
    let sc = spec.scales;
    let rescale = |j: usize, old: f64, new: f64| {
        let base = if j == BETA {
            sc.a_ref
        } else {
            sc.a_ref * sc.omega_ref
        };
        spec.start[j] * g_unchecked(old) * base.powf(old) / (g_unchecked(new) * base.powf(new))
    };
    let mut out = Vec::new();
    for r in range(RHO) {
        for e in range(ETA) {
            let mut s = spec.clone();
            if let Some(r) = r {
                s.status[RHO] = Status::Fixed(r as f64);
                s.start[RHO] = r as f64;
                s.start[BETA] = rescale(BETA, spec.start[RHO], r as f64);
            }
            if let Some(e) = e {
                s.status[ETA] = Status::Fixed(e as f64);
                s.start[ETA] = e as f64;
                s.start[KAPPA] = rescale(KAPPA, spec.start[ETA], e as f64);
            }
            out.push(PrIntegerCandidate {
                rho: r,
                eta: e,
                fit: fit_phase_resonance(data, &s, opts, &|| {}),
            });
        }
    }
    out
}
