//! Identification of the power-law models from stepped-sine amplitude
//! curves at several input levels (paper §4, Eq 31).
//!
//! * [`data`] — validated measured curves ([`Dataset`]).
//! * [`models`] — the model family ([`ModelKind`]) and parameter names.
//! * [`parameters`] — θ as a struct ([`Parameters`]) with each entry's
//!   units, mass scaling and default bounds ([`Parameter::info`]).
//! * [`objective`] — Eq 31 with branch-following model sweeps, the analytic
//!   Jacobian by implicit differentiation, the optimisation variables.
//! * [`levenberg_marquardt`] — bounded LM (the local solver).
//! * [`global`] — seeded parallel multistart.
//! * [`recent_sweeps`] — the last model sweeps of the output error, so that
//!   an evaluation repeated at the same θ does not sweep again.
//! * [`uncertainty`] — standard errors, 95 % intervals, correlations.
//! * [`search`] — the stiffness sign and integer exponents, chosen by
//!   fitting each candidate and keeping the lowest cost.
//! * [`inspect`] — what stepped-sine data say before any fit: per-level
//!   resonance, damping and jumps, homogeneity against the noise, the
//!   backbone and damping power laws read model-free, a recommendation.
//! * [`time_domain`] — output-error fit of Eq 32 to a recorded input and
//!   output (its own parameter vector with gain, offsets, initial state).
//!
//! Everything is in mass-normalised parameters θ = (α, δ, β, ρ, κ, η, gain):
//! with acceleration input only ratios to m are identifiable. The model
//! sees the input `gain · γ` (a point on a continuous structure).

pub mod compare;
pub mod data;
pub mod decay;
pub mod equation_error;
pub mod flags;
pub mod global;
pub mod identify;
pub mod inspect;
pub mod jumps;
pub mod landscape;
pub mod levenberg_marquardt;
pub mod models;
pub mod noise;
pub mod objective;
pub mod output_error;
pub mod parameters;
pub mod phase_resonance;
pub mod profile;
pub mod recent_sweeps;
pub mod search;
pub mod time_domain;
pub mod uncertainty;

pub use data::{Curve, DataError, Dataset, Record};
pub use equation_error::{EquationErrorFit, PhaseConvention};
pub use identify::{
    identify, nearest_node, Adequacy, CurveReport, ExponentStart, FitPlan, GainChoice,
    Identification, IdentifyError, IdentifyProgress, JumpChoice, PhaseChoice, ReadingChoice,
    SignChoice, Weighting,
};
pub use landscape::{Axis, Landscape};
pub use levenberg_marquardt::{LmOptions, Termination};
pub use models::{ModelKind, N_PARAMS, PARAM_NAMES};
pub use objective::{FitSpec, ResponseBranch, Sign, SpecError, Status};
pub use parameters::{Parameter, Parameters};
pub use uncertainty::Uncertainty;

use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use objective::{evaluate_with_phase, normalised_model, Problem};

/// Errors of a fit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error(transparent)]
    Spec(#[from] SpecError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("no start point of the {model} fit could be evaluated (every model sweep failed)")]
    NoStartEvaluable { model: ModelKind },
    /// Cancelled through `opts.lm.cancel` ([`crate::cancel`]).
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}

/// Options of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Number of starts (1 = local fit from the data-derived start only).
    pub starts: usize,
    pub seed: u64,
    pub lm: LmOptions,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            starts: 1,
            seed: 1,
            lm: LmOptions::default(),
        }
    }
}

/// One distinct local minimum of the global search.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Minimum {
    pub theta: Parameters,
    pub cost: f64,
    pub termination: Termination,
    pub iterations: usize,
    /// Number of starts that converged here.
    pub count: usize,
}

/// Per-level residual summary.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LevelStats {
    pub level: String,
    pub gamma: f64,
    pub direction: SweepDirection,
    pub points: usize,
    /// RMS of `a_model − a_meas`, m.
    pub rms: f64,
    /// RMS of `(a_model − a_meas)/γ`, s².
    pub rms_normalised: f64,
}

/// Result of [`fit`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitResult {
    pub kind: ModelKind,
    pub status: [Status; N_PARAMS],
    /// Best θ = (α, δ, β, ρ, κ, η, gain).
    pub theta: Parameters,
    /// Eq 31 cost Σ w ((a_model − a_meas)/γ)² (amplitudes only; the phase
    /// residuals' part of the objective is `phase_cost`).
    pub cost: f64,
    pub n_points: usize,
    pub n_free: usize,
    pub termination: Termination,
    pub iterations: usize,
    /// Distinct minima, best first.
    pub minima: Vec<Minimum>,
    /// `None` if `JᵀJ` is singular at the optimum.
    pub uncertainty: Option<Uncertainty>,
    pub levels: Vec<LevelStats>,
    /// Model amplitudes at the data steps (curve by curve).
    pub model_amplitudes: Vec<f64>,
    /// The local solver met a convergence criterion (not max-iterations or
    /// stalled).
    pub converged: bool,
    /// Free parameters that ended at (within 1e-6 of the box width of) a bound.
    #[serde(deserialize_with = "crate::interned::names")]
    pub at_bounds: Vec<&'static str>,
    /// Free parameters along a (numerically) null direction of the
    /// Jacobian at the optimum: the data cannot separate them.
    #[serde(deserialize_with = "crate::interned::names")]
    pub unidentifiable: Vec<&'static str>,
    /// Sum of the squared phase residuals at the optimum (`None` when phase
    /// was not fitted).
    pub phase_cost: Option<f64>,
    /// The amplitude part of the objective minimised, with its jump
    /// penalties: Eq 31's `cost` for a fit of Eq 31, the measured-branch
    /// output error ([`output_error`]) for [`ResponseBranch::Measured`]
    /// (never above `cost`: the state of the model's own sweep is always
    /// one of the states a point is compared with; equal to it where every
    /// point is on that state).
    pub objective: f64,
    /// The model amplitude each point was compared with by the objective
    /// (data order): `model_amplitudes` for Eq 31.
    pub compared_amplitudes: Vec<f64>,
    /// Pairs of free parameters the data do not separate to first order
    /// (`|r| ≥ 0.999`, [`flags::ridges`]).
    pub ridges: Vec<flags::Ridge>,
    /// Free parameters whose 95 % interval crosses a physical bound.
    pub crossings: Vec<flags::BoundCrossing>,
    /// Parameters at a bound that is a result (η = −1: Coulomb friction),
    /// held there for the intervals of the others.
    pub natural: Vec<flags::NaturalBound>,
    /// Exponents without effect (their coefficient went to 0), held.
    pub inactive: Vec<flags::Inactive>,
    /// Set by the identification's self-check ([`identify::Adequacy`]) when
    /// the model does not fit its data: the residual in units of the noise
    /// that the first line quotes ([`identify::Adequacy::quoted_ratio`]; of
    /// the fit read exactly, when it fits only with early jumps:
    /// [`identify::Adequacy::needs_early_jumps`]). The intervals are then
    /// not valid: the linearised (and sandwich) intervals assume residuals
    /// that are noise, and a model far from its data has an optimum that
    /// moves with details no interval describes (measured on the 24 °C
    /// beam, residual 1268x the noise: ρ's Wald interval was ±0.007 while
    /// amplitudes scaled by 1 + k·1e-15 moved ρ between 1.267 and 1.912;
    /// docs/identification.md, example `rounding_sensitivity`).
    #[serde(default)]
    pub misfit: Option<f64>,
}

impl FitResult {
    /// Whether the linearised intervals mean anything: the fit converged,
    /// no parameter sits at a bound (natural bounds and vanished terms are
    /// held, not counted), the Jacobian has full rank, no two estimates lie
    /// on a ridge (`|r| ≥ 0.999`), no interval crosses a physical bound, and
    /// the model fits its noise ([`Self::misfit`]).
    pub fn intervals_valid(&self) -> bool {
        self.misfit.is_none()
            && self.converged
            && self.at_bounds.is_empty()
            && self.unidentifiable.is_empty()
            && self.uncertainty.is_some()
            && self.ridges.is_empty()
            && self.crossings.is_empty()
    }

    /// One line saying why the fit or its intervals are not to be trusted,
    /// `None` if they are. Natural bounds and vanished terms are results,
    /// not warnings ([`Self::notes`]).
    pub fn warning(&self) -> Option<String> {
        let mut why = Vec::new();
        if !self.converged {
            why.push(format!("did not converge ({})", self.termination));
        }
        if !self.at_bounds.is_empty() {
            why.push(format!("at bounds: {}", self.at_bounds.join(", ")));
        }
        if !self.unidentifiable.is_empty() {
            why.push(format!(
                "not identifiable from these data: {}",
                self.unidentifiable.join(", ")
            ));
        } else if self.uncertainty.is_none() {
            why.push("no intervals (J^T J singular or no residual degrees of freedom)".into());
        }
        for r in &self.ridges {
            why.push(r.describe());
        }
        for c in &self.crossings {
            why.push(c.describe());
        }
        (!why.is_empty()).then(|| {
            format!(
                "WARNING: the {} fit: {}; intervals are not valid",
                self.kind,
                why.join("; ")
            )
        })
    }

    /// Results worth a line that are not warnings: parameters at natural
    /// bounds ("eta = -1 (Coulomb friction)"), free exponents whose valid
    /// 95 % interval holds such a bound ([`flags::near_natural_bounds`]),
    /// vanished terms, and free exponents the data do not determine (95 %
    /// interval reaching −3, [`flags::undetermined_exponents`]).
    pub fn notes(&self) -> Vec<String> {
        let near = match &self.uncertainty {
            Some(u) if self.intervals_valid() => flags::near_natural_bounds(u),
            _ => Vec::new(),
        };
        self.natural
            .iter()
            .map(|n| n.describe())
            .chain(near.iter().map(|n| n.describe()))
            .chain(self.inactive.iter().map(|i| i.describe()))
            .chain(
                self.uncertainty
                    .as_ref()
                    .map_or(Vec::new(), flags::undetermined_exponents)
                    .iter()
                    .map(|u| u.describe()),
            )
            .collect()
    }

    /// Akaike information criterion `n ln(cost/n) + 2p`.
    pub fn aic(&self) -> f64 {
        let n = self.n_points as f64;
        n * (self.cost / n).ln() + 2.0 * self.n_free as f64
    }

    /// Bayesian information criterion `n ln(cost/n) + p ln n`.
    pub fn bic(&self) -> f64 {
        let n = self.n_points as f64;
        n * (self.cost / n).ln() + self.n_free as f64 * n.ln()
    }

    /// RMS of the normalised residuals over all steps.
    pub fn rms_normalised(&self) -> f64 {
        (self.cost / self.n_points as f64).sqrt()
    }

    /// Mass-normalised model of the best fit (γ must be scaled by `gain`).
    pub fn model(&self) -> crate::model::NormalisedModel {
        normalised_model(&self.theta)
    }
}

/// Fits `spec` to `data` (Eq 31): local LM from the data-derived start,
/// or a multistart global search when `opts.starts > 1`. `progress` is
/// called once per finished start.
pub fn fit(
    data: &Dataset,
    spec: &FitSpec,
    opts: &FitOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<FitResult, FitError> {
    fit_impl(data, spec, opts, None, progress)
}

/// As [`fit`], with the jump-frequency residuals of [`jumps`] (weight
/// `jump_weight` = λ ≥ 0) added to Eq 31 for every up-sweep with a measured
/// jump. The reported `cost`, RMS and uncertainty are those of Eq 31 alone
/// at the optimum; the costs in `minima` include the jump terms.
pub fn fit_with_jumps(
    data: &Dataset,
    spec: &FitSpec,
    opts: &FitOptions,
    jump_weight: f64,
    progress: &(dyn Fn() + Sync),
) -> Result<FitResult, FitError> {
    fit_impl(data, spec, opts, Some(jump_weight.max(0.0)), progress)
}

fn fit_impl(
    data: &Dataset,
    spec: &FitSpec,
    opts: &FitOptions,
    jump_weight: Option<f64>,
    progress: &(dyn Fn() + Sync),
) -> Result<FitResult, FitError> {
    let problem = Problem::new(data, spec)?;
    let (lo, hi) = problem.u_bounds();
    let u0 = problem.u_of(&spec.start);
    let mut lm = opts.lm;
    if lm.cost_floor == 0.0 {
        // an exact fit: residuals at rounding level of the data
        let scale: f64 = data
            .curves
            .iter()
            .flat_map(|c| c.amplitudes.iter().map(move |a| (a / c.gamma).powi(2)))
            .sum();
        lm.cost_floor = 1e-28 * scale;
    }
    // stage-2 score threshold of the global search: half the cost of the
    // zero model (global::multistart_below)
    let zero_model_cost: f64 = data
        .curves
        .iter()
        .flat_map(|c| {
            c.amplitudes
                .iter()
                .zip(&c.weights)
                .map(move |(a, w)| w * (a / c.gamma).powi(2))
        })
        .sum();
    let found = match jump_weight {
        None => global::multistart_below(
            &problem,
            &u0,
            &lo,
            &hi,
            opts.starts.max(1),
            opts.seed,
            &lm,
            0.5 * zero_model_cost,
            progress,
        ),
        Some(w) => global::multistart_below(
            &jumps::WithJumps::new(problem.clone(), w),
            &u0,
            &lo,
            &hi,
            opts.starts.max(1),
            opts.seed,
            &lm,
            0.5 * zero_model_cost,
            progress,
        ),
    };
    // a cancelled search returns no result (not its last iterates)
    lm.cancel.check()?;
    let best = found
        .first()
        .ok_or(FitError::NoStartEvaluable { model: spec.kind })?;
    let minima: Vec<Minimum> = found
        .iter()
        .map(|m| Minimum {
            theta: problem.theta(&m.result.u),
            cost: m.result.cost,
            termination: m.result.termination,
            iterations: m.result.iterations,
            count: m.count,
        })
        .collect();
    let theta = problem.theta(&best.result.u);
    // the solve's own evaluation at θ when it kept one (the same numbers)
    let e = problem.evaluation_at(&theta)?;
    assess_evaluated(
        data,
        spec,
        (theta, e),
        best.result.termination,
        best.result.iterations,
        minima,
    )
}

/// Free parameters of `spec` at θ that sit on a bound (within 1e-6 of the
/// box width of the optimisation variable): `(index, at the lower bound)`.
pub(crate) fn bound_hits(spec: &FitSpec, theta: &Parameters) -> Vec<(usize, bool)> {
    let empty = Dataset { curves: Vec::new() };
    let Ok(problem) = Problem::new(&empty, spec) else {
        return Vec::new();
    };
    let (lo, hi) = problem.u_bounds();
    let u = problem.u_of(theta);
    problem
        .free
        .iter()
        .enumerate()
        .filter_map(|(k, &j)| {
            let w = (hi[k] - lo[k]).abs().max(1e-300);
            if (u[k] - lo[k]).abs() <= 1e-6 * w {
                Some((j, true))
            } else if (hi[k] - u[k]).abs() <= 1e-6 * w {
                Some((j, false))
            } else {
                None
            }
        })
        .collect()
}

/// The statistics of a fit at θ on `data`: cost, per-level RMS, model
/// amplitudes, linearised intervals and null directions of the Jacobian.
/// (Used for the fit's own data, and to judge a fit made on a subsample on
/// all points.)
/// Per-curve RMS of `a_model − a_meas` (m) and of it over γ, for the model
/// amplitudes `model` in data order.
pub fn level_stats(data: &Dataset, model: &[f64]) -> Vec<LevelStats> {
    let mut levels = Vec::with_capacity(data.curves.len());
    let mut off = 0;
    for c in &data.curves {
        let n = c.omegas.len();
        let (mut s, mut sn) = (0.0, 0.0);
        for i in 0..n {
            let d = model[off + i] - c.amplitudes[i];
            s += d * d;
            sn += (d / c.gamma).powi(2);
        }
        levels.push(LevelStats {
            level: c.level.clone(),
            gamma: c.gamma,
            direction: c.direction,
            points: n,
            rms: (s / n as f64).sqrt(),
            rms_normalised: (sn / n as f64).sqrt(),
        });
        off += n;
    }
    levels
}

/// The statistics of a fit of `spec` at θ on `data`: Eq 31's cost and the
/// objective's, per-level RMS, model amplitudes, linearised intervals, null
/// directions, ridges, crossings and bounds (natural ones held for the
/// intervals of the others, [`flags`]).
pub(crate) fn assess(
    data: &Dataset,
    spec: &FitSpec,
    theta: Parameters,
    termination: Termination,
    iterations: usize,
    minima: Vec<Minimum>,
) -> Result<FitResult, FitError> {
    let e = objective::evaluate_spec(data, spec, &theta, true)?;
    assess_evaluated(data, spec, (theta, e), termination, iterations, minima)
}

/// [`assess`] with the evaluation (with the Jacobian) at θ already made.
fn assess_evaluated(
    data: &Dataset,
    spec: &FitSpec,
    (theta, e): (Parameters, objective::Evaluation),
    termination: Termination,
    iterations: usize,
    minima: Vec<Minimum>,
) -> Result<FitResult, FitError> {
    let n_amp = data.len();
    let n_phase = match spec.phase_weight {
        Some(_) => data
            .curves
            .iter()
            .filter(|c| c.phases.is_some())
            .map(|c| c.omegas.len())
            .sum(),
        None => 0,
    };
    // observations: amplitude and phase residuals (the jump penalties that
    // follow are constraints, zero at a consistent fit)
    let n_obs = (n_amp + n_phase).min(e.residuals.len());
    let jac = e.jacobian.as_ref().expect("jacobian requested");
    let mut natural = Vec::new();
    let mut at_bounds = Vec::new();
    for (j, lower) in bound_hits(spec, &theta) {
        match flags::natural_meaning(j, lower, theta[j]) {
            Some(meaning) => natural.push(flags::NaturalBound {
                name: PARAM_NAMES[j],
                value: theta[j],
                meaning,
            }),
            None => at_bounds.push(PARAM_NAMES[j]),
        }
    }
    let free: Vec<usize> = spec
        .free_indices()
        .into_iter()
        .filter(|&j| !natural.iter().any(|n| n.name == PARAM_NAMES[j]))
        .collect();
    // intervals by the sandwich with the noise model's per-point noise
    // (amplitude noise grows with the amplitude; Eq 31 weighs every point
    // alike), scaled to the residuals (`uncertainty_with_noise`)
    let with_phase = spec.phase_weight.is_some();
    let sigma = noise::noise_model(data, &e.residuals[..n_obs], with_phase).rows(data, with_phase);
    let unc = uncertainty::uncertainty_with_noise(
        &theta,
        &free,
        &jac[..n_obs],
        &e.residuals[..n_obs],
        &sigma,
    );
    let unidentifiable = uncertainty::null_directions(&free, &jac[..n_obs]);
    let crossings = unc.as_ref().map_or(Vec::new(), flags::crossings);
    // Ridges are judged in the optimisation variables (ln α, ln δ, ln β_ref,
    // ρ, ln κ_ref, η, ln gain): β and ρ themselves are tied by
    // β = β_ref/(g(ρ) A_ref^ρ) whatever the data, so their correlation is
    // near 1 on every fit and says nothing (it was reported as a ridge on
    // most good fits before this), while β_ref and ρ are separated by the
    // data or not.
    let ridges = {
        let problem = Problem::new(data, spec)?;
        let cols = problem.dtheta_du(&theta);
        let jac_u: Vec<[f64; N_PARAMS]> = jac[..n_obs]
            .iter()
            .map(|row| {
                let mut out = [0.0; N_PARAMS];
                for (k, &j) in problem.free.iter().enumerate() {
                    out[j] = (0..N_PARAMS).map(|p| row[p] * cols[k][p]).sum();
                }
                out
            })
            .collect();
        uncertainty::uncertainty(&theta, &free, &jac_u, &e.residuals[..n_obs])
            .map_or(Vec::new(), |u| flags::ridges(&u))
    };
    let phase_cost = spec
        .phase_weight
        .map(|_| e.residuals[n_amp..n_obs].iter().map(|r| r * r).sum::<f64>());
    let levels = level_stats(data, &e.model);
    let objective: f64 = e.residuals[..n_amp]
        .iter()
        .chain(&e.residuals[n_obs..])
        .map(|r| r * r)
        .sum();
    let (cost, model_amplitudes) = if spec.branch == ResponseBranch::Sweep {
        (objective, e.model.clone())
    } else {
        let s = evaluate_with_phase(data, &theta, false, None)?;
        (s.cost(), s.model)
    };
    Ok(FitResult {
        kind: spec.kind,
        status: spec.status,
        theta,
        cost,
        n_points: n_amp,
        n_free: spec.free_indices().len(),
        termination,
        iterations,
        minima,
        uncertainty: unc,
        levels,
        model_amplitudes,
        converged: termination.converged(),
        at_bounds,
        unidentifiable,
        phase_cost,
        objective,
        compared_amplitudes: e.model,
        ridges,
        crossings,
        natural,
        inactive: Vec::new(),
        misfit: None,
    })
}

/// Predicted first jump of each curve's model sweep (rad/s), `None` where
/// the model sweep does not jump. The sweep starts as in the objective
/// (state nearest to the measured first amplitude, see
/// [`objective::model_amplitudes`]).
pub fn predicted_jumps(data: &Dataset, theta: &Parameters) -> Result<Vec<Option<f64>>, SolveError> {
    let model = normalised_model(theta);
    data.curves
        .iter()
        .map(|c| {
            let r = ForcedResponse::from_normalised(
                &model,
                theta[models::GAIN] * c.gamma,
                Formulation::HarmonicBalance,
            )?;
            Ok(
                r.sweep_from(&c.omegas, c.direction, objective::first_amplitude(c))?
                    .jumps
                    .first()
                    .map(|j| j.omega),
            )
        })
        .collect()
}

/// The stepped-sine sweeps of `model` at the levels, frequencies and sweep
/// directions of `data`, exactly as a fit computes its model curves (Eq 31):
/// the model sees `input_gain · γ` (the forcing gain of a stepped-sine fit,
/// the `[signal] input_gain` of a model file), and each sweep starts on the
/// stable state nearest the curve's measured first amplitude (sweep rule 1′,
/// [`objective::model_amplitudes`]). One [`LevelResponse`](crate::LevelResponse) per curve, in data
/// order; its `gamma` is the measured level γ (not `input_gain · γ`) and its
/// points are in sweep order.
///
/// With `model` the physical model of a fit's θ at unit mass (as `nlsdof fit
/// --out` writes it) and `input_gain` its gain, the amplitudes equal the
/// fit's `model_amplitudes` bit for bit (test
/// `sweeps_at_the_data_reproduce_the_fit_bit_for_bit`).
pub fn sweeps_at_data(
    model: &(impl crate::model::AsNormalised + ?Sized),
    input_gain: f64,
    data: &Dataset,
) -> Result<Vec<crate::LevelResponse>, SolveError> {
    if !(input_gain.is_finite() && input_gain > 0.0) {
        return Err(crate::ParameterError::NotPositive {
            name: "input_gain",
            value: input_gain,
        }
        .into());
    }
    let model = model.as_normalised()?;
    data.map_curves(|_, c| {
        let response = ForcedResponse::from_normalised(
            &model,
            input_gain * c.gamma,
            Formulation::HarmonicBalance,
        )?;
        let sweep = response.sweep_from(&c.omegas, c.direction, objective::first_amplitude(c))?;
        let phase_quadrature = response.phase_quadrature()?;
        Ok(crate::LevelResponse {
            gamma: c.gamma,
            response,
            sweep,
            phase_quadrature,
        })
    })
}

/// One row of the phase-quadrature table (Table 8 analogue).
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseQuadratureRow {
    pub level: String,
    pub gamma: f64,
    /// Measured (Ω, a): the 90° phase-lag crossing if the curve has phases
    /// that cross 90°, else the amplitude peak.
    pub measured_omega: f64,
    pub measured_amplitude: f64,
    /// `"phase"` or `"peak"`.
    pub measured_from: &'static str,
    /// Model phase-quadrature point (None if the curve never meets the backbone).
    pub model_omega: Option<f64>,
    pub model_amplitude: Option<f64>,
}

impl PhaseQuadratureRow {
    /// `(model − measured)/measured` in %, frequency and amplitude.
    pub fn differences_percent(&self) -> (Option<f64>, Option<f64>) {
        (
            self.model_omega
                .map(|w| 100.0 * (w - self.measured_omega) / self.measured_omega),
            self.model_amplitude
                .map(|a| 100.0 * (a - self.measured_amplitude) / self.measured_amplitude),
        )
    }
}

/// Phase-quadrature table: one row per level (its up-sweep if present).
pub fn phase_quadrature_table(
    data: &Dataset,
    theta: &Parameters,
) -> Result<Vec<PhaseQuadratureRow>, SolveError> {
    let model = normalised_model(theta);
    let mut rows = Vec::new();
    for (level, gamma) in data.levels() {
        let c = data
            .curves
            .iter()
            .find(|c| c.level == level && c.direction == SweepDirection::Up)
            .or_else(|| data.curves.iter().find(|c| c.level == level))
            .expect("level has a curve");
        let (mw, ma, from) = measured_quadrature(c);
        let r = ForcedResponse::from_normalised(
            &model,
            theta[models::GAIN] * gamma,
            Formulation::HarmonicBalance,
        )?;
        let pq = r.phase_quadrature()?;
        rows.push(PhaseQuadratureRow {
            level,
            gamma,
            measured_omega: mw,
            measured_amplitude: ma,
            measured_from: from,
            model_omega: pq.map(|p| p.omega),
            model_amplitude: pq.map(|p| p.amplitude),
        });
    }
    Ok(rows)
}

fn measured_quadrature(c: &Curve) -> (f64, f64, &'static str) {
    let half_pi = std::f64::consts::FRAC_PI_2;
    if let Some(ph) = &c.phases {
        for i in 0..ph.len() - 1 {
            let (p0, p1) = (ph[i] - half_pi, ph[i + 1] - half_pi);
            if p0 == 0.0 {
                return (c.omegas[i], c.amplitudes[i], "phase");
            }
            if p0 * p1 < 0.0 && (ph[i + 1] - ph[i]).abs() < 2.0 {
                let t = p0 / (p0 - p1);
                return (
                    c.omegas[i] + t * (c.omegas[i + 1] - c.omegas[i]),
                    c.amplitudes[i] + t * (c.amplitudes[i + 1] - c.amplitudes[i]),
                    "phase",
                );
            }
        }
    }
    let i = c.peak_index();
    (c.omegas[i], c.amplitudes[i], "peak")
}

/// Result of the integer-exponent search.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegerCandidate {
    pub rho: Option<i64>,
    pub eta: Option<i64>,
    pub fit: Result<FitResult, FitError>,
}

/// `--integer`: for every integer value of each free exponent within its
/// bounds, fixes the exponent(s) and fits the coefficients (local fit, or
/// `opts.starts` multistart). Candidates in increasing (ρ, η) order; the
/// caller picks the lowest cost.
pub fn integer_search(data: &Dataset, spec: &FitSpec, opts: &FitOptions) -> Vec<IntegerCandidate> {
    use rayon::prelude::*;
    let range = |j: usize| -> Vec<Option<i64>> {
        if spec.status[j] != Status::Free {
            return vec![None];
        }
        let (lo, hi) = spec.bounds[j];
        let lo = (lo.ceil() as i64).max(-2);
        let hi = hi.floor() as i64;
        (lo..=hi).map(Some).collect()
    };
    let mut pairs = Vec::new();
    for r in range(models::RHO) {
        for e in range(models::ETA) {
            pairs.push((r, e));
        }
    }
    pairs
        .par_iter()
        .map(|&(r, e)| {
            let mut s = spec.clone();
            if let Some(r) = r {
                s.status[models::RHO] = Status::Fixed(r as f64);
                s.start[models::RHO] = r as f64;
                s.start[models::BETA] = rescale_start(spec, models::BETA, r as f64);
            }
            if let Some(e) = e {
                s.status[models::ETA] = Status::Fixed(e as f64);
                s.start[models::ETA] = e as f64;
                s.start[models::KAPPA] = rescale_start(spec, models::KAPPA, e as f64);
            }
            IntegerCandidate {
                rho: r,
                eta: e,
                fit: fit(data, &s, opts, &|| {}),
            }
        })
        .collect()
}

/// Start of a coefficient after its exponent changes, keeping its
/// equivalent value at the reference amplitude.
fn rescale_start(spec: &FitSpec, j: usize, new_exp: f64) -> f64 {
    use crate::power_law::g_unchecked;
    let sc = spec.scales;
    let (old_exp, base) = if j == models::BETA {
        (spec.start[models::RHO], sc.a_ref)
    } else {
        (spec.start[models::ETA], sc.a_ref * sc.omega_ref)
    };
    spec.start[j] * g_unchecked(old_exp) * base.powf(old_exp)
        / (g_unchecked(new_exp) * base.powf(new_exp))
}
