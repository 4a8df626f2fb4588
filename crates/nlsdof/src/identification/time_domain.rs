//! Output-error identification of the power-law ODE (paper §4.5, Eq 32)
//! from a recorded input `u` and output `y`.
//!
//! ## Model
//!
//! The recorded signals are mapped to the mass-normalised model of Eq 32 by
//! an input gain `g`, an input offset `b_u` and an output offset `b_y`:
//!
//! ```text
//! x'' + δ x' + α x + κ x'|x'|^η + β x|x|^ρ = g (u(t) + b_u)          (Eq 32, γ = g (u + b_u))
//! ŷ(t) = x(t) + b_y
//! ```
//!
//! θ = (α, δ, β, ρ, κ, η, g, b_u, b_y, x₀, v₀) ([`TIME_PARAM_NAMES`]);
//! which entries are free follows the [`ModelKind`] (ρ = 2 for Duffing,
//! …). With the linear model `b_u` is fixed at 0: a constant input only
//! shifts the output by `g b_u / α`, exactly what `b_y` does, so the two are
//! not separately identifiable. The nonlinear terms separate them (the
//! asymmetry of the Silverbox circuit is such an offset).
//!
//! ## Discretisation: the continuous-time model, to a controlled error
//!
//! The input between samples is reconstructed as the model states
//! ([`InputInterpolation`]: the cubic through the four nearest samples by
//! default, or linear, or a zero-order hold) and the ODE is advanced by
//! classical RK4 with `n` substeps per sample, `h = 1/(n f_s)`, whose stage
//! inputs are that reconstruction at the step's start, middle and end
//! ([`Discretisation`]; with a hold, the end stage of the last substep of an
//! interval uses the held value, the left limit). `n = 2` with cubic input
//! is the default of `nlsdof simulate`.
//!
//! The fitted parameters must belong to the ODE, not to the integrator, so
//! [`fit_time_domain`] chooses `n` (unless [`TimeFitOptions::substeps`]
//! fixes it): it fits at `n = 2`, then measures the integration error at the
//! fitted θ as the RMS change of ŷ when `n` is doubled, `e_n = RMS(ŷ_n −
//! ŷ_2n)`. While `e_n` exceeds [`TimeFitOptions::integration_tolerance`]
//! (1 %) of the RMS output error, `n` is raised to the value that RK4's
//! fourth order predicts meets it (`n (e_n / (tol · rms))^{1/4}`, 10 %
//! margin) and the fit is rerun from the current θ; the check is repeated at
//! the end ([`IntegrationCheck`] reports the final `n`, `h`, `e_n` and the
//! RMS output error). The model file records both the reconstruction and
//! `n`, so `nlsdof simulate` reproduces the fit's predictions to rounding.
//!
//! ## Output error and exact discrete gradients
//!
//! The fit minimises `Σ_k (ŷ_k(θ) − y_k)²` over the estimation range by the
//! bounded Levenberg–Marquardt of [`super::levenberg_marquardt`]. The
//! Jacobian `∂ŷ_k/∂θ` comes from the forward sensitivity equations of the
//! **discrete** RK4 map (forward-mode differentiation of every stage):
//! with the right-hand side `f(s, θ) = (v, γ − α x − δ v − β x|x|^ρ − κ v|v|^η)`,
//! `S = ∂s/∂θ` and stage `K_i = f(s + c_i h K_{i−1})`,
//!
//! ```text
//! ∂K_i/∂θ = f_s(s_i) (S + c_i h ∂K_{i−1}/∂θ) + f_θ(s_i),
//! S_{n+1} = S_n + h/6 (∂K_1 + 2 ∂K_2 + 2 ∂K_3 + ∂K_4)/∂θ,     S_0 = ∂(x₀, v₀)/∂θ
//! ```
//!
//! so the gradient is that of the computed ŷ to rounding (tested against
//! finite differences). The partial derivatives of the acceleration
//! `a = γ − α x − δ v − β x|x|^ρ − κ v|v|^η` are
//! `∂a/∂x = −α − (ρ+1) β |x|^ρ`, `∂a/∂v = −δ − (η+1) κ |v|^η`,
//! `∂a/∂ρ = −β x|x|^ρ ln|x|`, `∂a/∂η = −κ v|v|^η ln|v|` (0 at x = 0,
//! v = 0), `∂a/∂g = u + b_u`, `∂a/∂b_u = g`.
//!
//! **Exponents are restricted to ρ ≥ 0 and η ≥ 0 here** (the model allows
//! exponents above −3): for ρ < 0 the stiffness slope `(ρ+1) β |x|^ρ` of the sensitivity
//! equations is infinite at x = 0, which every oscillation crosses, and the
//! same holds for η < 0 at each velocity reversal; the discrete map is then
//! not differentiable and the sensitivities are meaningless. With ρ, η ≥ 0
//! all of `x|x|^ρ`, its slope and `x|x|^ρ ln|x|` are continuous at 0.
//!
//! ## Start and local minima
//!
//! The start is an **equation-error** estimate: Eq 32 is linear in
//! (g, g b_u, α, δ, β, κ) once the exponents are fixed, so with `x'` and
//! `x''` from fifth-order central differences of y it is a linear least
//! squares problem. Output-error fits of lightly damped oscillators have
//! local minima when the start's natural frequency is off by more than
//! about the half-power bandwidth; the equation-error start is within a
//! fraction of a per cent of the natural frequency for sampled records with
//! moderate noise. Free exponents are fitted in a second stage from the fit
//! with the exponents fixed at (ρ, η) = (2, 1), plus `starts − 1` seeded
//! random exponent starts (SplitMix64, uniform in [0.5, 4]): the result is
//! deterministic for a given seed and independent of the thread count.
//!
//! With a free damping exponent, the start from η = 1 is raced against a
//! second one with the damping moved into the power-law term at η₀ = 0.05
//! (δ₀ = 1 % of the equivalent linear damping at the RMS velocity, κ₀ the
//! rest; `damping_moved_start`): near η = 0 the terms `δ v` and `κ v|v|^η`
//! nearly coincide, and the cost has a long curved valley (`δ + κ v^η` and
//! `κ η` nearly constant) that LM crawls along from η = 1 (Silverbox: 201
//! iterations down to η = 0.017, δ = 0), or leaves for a local minimum at
//! η = 0, κ = 0. Both starts get 10 LM iterations; the lower cost (the
//! first on a tie) is continued from where it stopped, with its LM state,
//! so that its iterates are those of an uninterrupted run
//! ([`super::levenberg_marquardt::minimise_resumable`]).
//! [`TimeFitOptions::fixed`] holds entries of θ at given values (e.g.
//! δ = 0).
//!
//! ## Validation
//!
//! [`predict`] simulates a test range from its input alone; only the first
//! [`INIT_WINDOW`] output samples are used, to estimate the initial state
//! (a two-parameter output-error fit with the model fixed).

use super::global::SplitMix64;
use super::levenberg_marquardt::{
    cholesky_solve, minimise_resumable, normal_equations, LeastSquares, LmOptions, LmState,
    Termination,
};
use super::models::{ModelKind, Term};
use super::uncertainty::t95;
pub use crate::excitation::InputInterpolation;
use crate::model::NormalisedModel;
use crate::simulation::State;
use rayon::prelude::*;
use thiserror::Error;

/// Interpolation points per sample interval of the default
/// [`Discretisation`] (cubic input, 2 RK4 substeps per sample); RK4 step
/// `h = 2/(UPSAMPLE f_s)` (the default of `nlsdof simulate`).
pub const UPSAMPLE: usize = 4;

/// Most RK4 substeps per sample the automatic choice of [`fit_time_domain`]
/// (and [`Discretisation::new`]) takes.
pub const MAX_SUBSTEPS: usize = 256;

/// How the continuous-time model is integrated on a sampled input: the
/// input reconstruction between samples (a part of the model) and the RK4
/// substeps per sample, `h = 1/(substeps · f_s)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Discretisation {
    pub interpolation: InputInterpolation,
    /// RK4 steps per sample interval (1..=[`MAX_SUBSTEPS`]).
    pub substeps: usize,
}

impl Default for Discretisation {
    /// Cubic input, 2 substeps (`h = 1/(2 f_s)`): the default of
    /// `nlsdof simulate` and of model files that state neither.
    fn default() -> Self {
        Self {
            interpolation: InputInterpolation::Cubic,
            substeps: UPSAMPLE / 2,
        }
    }
}

impl Discretisation {
    /// Checked: `substeps` in 1..=[`MAX_SUBSTEPS`].
    pub fn new(interpolation: InputInterpolation, substeps: usize) -> Result<Self, TimeFitError> {
        if !(1..=MAX_SUBSTEPS).contains(&substeps) {
            return Err(TimeFitError::InvalidOption {
                name: "substeps",
                value: substeps as f64,
                reason: "must be between 1 and 256",
            });
        }
        Ok(Self {
            interpolation,
            substeps,
        })
    }
    /// The reconstructed input at the RK4 stage times: `2 · substeps`
    /// points per sample interval.
    fn fine(&self, u: &[f64]) -> Vec<f64> {
        self.interpolation.upsample(u, 2 * self.substeps)
    }
    /// The same reconstruction with twice the substeps.
    fn doubled(&self) -> Self {
        Self {
            substeps: 2 * self.substeps,
            ..*self
        }
    }
}

/// The integration-error check of a fit ([`fit_time_domain`]): the scheme
/// used and the RMS change of ŷ at the fitted θ when its substeps are
/// doubled, against the RMS output error being fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegrationCheck {
    /// RK4 substeps per sample of the final fit.
    pub substeps: usize,
    /// The RK4 step, s (`1/(substeps · f_s)`).
    pub step: f64,
    /// `RMS(ŷ_n − ŷ_2n)` over the estimation range at the fitted θ (an
    /// estimate of the integration error of ŷ_n, in the output's unit).
    pub integration_error: f64,
    /// The RMS output error of the fit.
    pub output_error: f64,
    /// The tolerance: `integration_error <= tolerance · output_error` is
    /// the target.
    pub tolerance: f64,
    /// Whether the target was met (false when [`MAX_SUBSTEPS`] or a fixed
    /// [`TimeFitOptions::substeps`] did not suffice).
    pub met: bool,
    /// Whether `substeps` was chosen automatically.
    pub automatic: bool,
    /// Fits run (1 = the first choice met the target).
    pub refits: usize,
}

/// Output samples at the start of a test range that [`predict`] may use (to
/// estimate the initial state), as in the Silverbox benchmark.
pub const INIT_WINDOW: usize = 50;

/// Index of each entry of θ.
/// (The first seven are those of the steady-state fits' θ.)
pub use super::models::{ALPHA, BETA, DELTA, ETA, GAIN, KAPPA, RHO};
pub const INPUT_OFFSET: usize = 7;
pub const OUTPUT_OFFSET: usize = 8;
pub const X0: usize = 9;
pub const V0: usize = 10;
/// Length of θ.
pub const N_TIME_PARAMS: usize = 11;
/// Names of θ's entries.
pub const TIME_PARAM_NAMES: [&str; N_TIME_PARAMS] = [
    "alpha",
    "delta",
    "beta",
    "rho",
    "kappa",
    "eta",
    "gain",
    "input_offset",
    "output_offset",
    "x0",
    "v0",
];

/// The index in θ of a model parameter that [`TimeFitOptions::fixed`] may
/// hold, by its name in [`TIME_PARAM_NAMES`] (`alpha` … `output_offset`;
/// not the initial state). `None` for any other name.
pub fn fixable_parameter(name: &str) -> Option<usize> {
    TIME_PARAM_NAMES[..=OUTPUT_OFFSET]
        .iter()
        .position(|n| *n == name)
}

/// Upper bound of the exponents in the fit.
pub const MAX_EXPONENT: f64 = 20.0;

/// Bad data, ranges or options of a time-domain fit. Each variant carries
/// the offending value.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TimeFitError {
    #[error("sampling frequency fs = {fs} Hz must be finite and > 0")]
    NonPositiveFs { fs: f64 },
    #[error("input has {input} samples but output has {output}: they must be equally long")]
    LengthMismatch { input: usize, output: usize },
    #[error("{signal} sample {index} = {value} is not a finite number")]
    NonFinite {
        signal: &'static str,
        index: usize,
        value: f64,
    },
    #[error("{what} range {start}:{end} is empty or reversed (ranges are 0-based, half-open A:B with A < B)")]
    EmptyRange {
        what: &'static str,
        start: usize,
        end: usize,
    },
    #[error("{what} range {start}:{end} is outside the record of {len} samples (valid: 0:{len})")]
    RangeOutside {
        what: &'static str,
        start: usize,
        end: usize,
        len: usize,
    },
    #[error("{what} range {start}:{end} has {len} samples; at least {min} are needed")]
    RangeTooShort {
        what: &'static str,
        start: usize,
        end: usize,
        len: usize,
        min: usize,
    },
    #[error(
        "estimation range {est_start}:{est_end} and test range {test_start}:{test_end} overlap"
    )]
    Overlap {
        est_start: usize,
        est_end: usize,
        test_start: usize,
        test_end: usize,
    },
    #[error("sampling is not uniform: step {index} is {dt} s, the first step is {expected} s (relative tolerance {tolerance})")]
    NonUniformSampling {
        index: usize,
        dt: f64,
        expected: f64,
        tolerance: f64,
    },
    #[error("model {kind} has an exponent {value} < 0 (time-domain fits need rho >= 0 and eta >= 0: the sensitivity equations are singular at x = 0 or v = 0 otherwise)")]
    UnsupportedModel { kind: ModelKind, value: f64 },
    #[error("the equation-error start is singular (the estimation range does not excite the model: constant or zero output?)")]
    SingularStart,
    #[error(
        "the model cannot be simulated from the start point (it diverges on the estimation input)"
    )]
    StartNotEvaluable,
    #[error("the model diverges on the test input (non-finite response)")]
    Diverged,
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// Cancelled through `opts.lm.cancel` ([`crate::cancel`]): no result.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}

/// A half-open sample range `[start, end)`, 0-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleRange {
    pub start: usize,
    pub end: usize,
}

impl SampleRange {
    pub fn new(start: usize, end: usize) -> Self {
        Self { start, end }
    }
    pub fn len(&self) -> usize {
        self.end.saturating_sub(self.start)
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Checks the range against a record of `len` samples.
    pub fn check(&self, what: &'static str, len: usize, min: usize) -> Result<(), TimeFitError> {
        if self.end <= self.start {
            return Err(TimeFitError::EmptyRange {
                what,
                start: self.start,
                end: self.end,
            });
        }
        if self.end > len {
            return Err(TimeFitError::RangeOutside {
                what,
                start: self.start,
                end: self.end,
                len,
            });
        }
        if self.len() < min {
            return Err(TimeFitError::RangeTooShort {
                what,
                start: self.start,
                end: self.end,
                len: self.len(),
                min,
            });
        }
        Ok(())
    }
    fn overlaps(&self, other: &SampleRange) -> bool {
        self.start < other.end && other.start < self.end
    }
}

/// Minimum number of samples of an estimation range.
pub const MIN_ESTIMATION_SAMPLES: usize = 64;

/// Checks an estimation and an optional test range against a record of
/// `len` samples: inside, long enough (the test range needs more than
/// [`INIT_WINDOW`] samples), not overlapping.
pub fn check_ranges(
    len: usize,
    estimation: SampleRange,
    test: Option<SampleRange>,
) -> Result<(), TimeFitError> {
    estimation.check("estimation", len, MIN_ESTIMATION_SAMPLES)?;
    if let Some(t) = test {
        t.check("test", len, INIT_WINDOW + 1)?;
        if t.overlaps(&estimation) {
            return Err(TimeFitError::Overlap {
                est_start: estimation.start,
                est_end: estimation.end,
                test_start: t.start,
                test_end: t.end,
            });
        }
    }
    Ok(())
}

/// The sampling frequency of a time column that is uniform to within
/// `tolerance` of its first step, else [`TimeFitError::NonUniformSampling`].
pub fn uniform_fs(t: &[f64], tolerance: f64) -> Result<f64, TimeFitError> {
    if t.len() < 2 {
        return Err(TimeFitError::RangeTooShort {
            what: "time",
            start: 0,
            end: t.len(),
            len: t.len(),
            min: 2,
        });
    }
    let dt0 = t[1] - t[0];
    for (i, w) in t.windows(2).enumerate() {
        let dt = w[1] - w[0];
        if !(dt.is_finite() && dt > 0.0 && (dt - dt0).abs() <= tolerance * dt0.abs()) {
            return Err(TimeFitError::NonUniformSampling {
                index: i,
                dt,
                expected: dt0,
                tolerance,
            });
        }
    }
    let fs = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
    Ok(fs)
}

/// A validated, uniformly sampled input/output record.
#[derive(Debug, Clone, Copy)]
pub struct TimeRecord<'a> {
    pub u: &'a [f64],
    pub y: &'a [f64],
    /// Sampling frequency, Hz.
    pub fs: f64,
}

impl<'a> TimeRecord<'a> {
    /// Checks equal lengths, finite samples and `fs > 0`.
    pub fn new(u: &'a [f64], y: &'a [f64], fs: f64) -> Result<Self, TimeFitError> {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(TimeFitError::NonPositiveFs { fs });
        }
        if u.len() != y.len() {
            return Err(TimeFitError::LengthMismatch {
                input: u.len(),
                output: y.len(),
            });
        }
        for (signal, s) in [("input", u), ("output", y)] {
            if let Some((index, &value)) = s.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(TimeFitError::NonFinite {
                    signal,
                    index,
                    value,
                });
            }
        }
        Ok(Self { u, y, fs })
    }
}

/// The identified map from the recorded input to the recorded output:
/// `x'' + … = g (u + b_u)`, `ŷ = x + b_y`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeModel {
    pub model: NormalisedModel,
    pub gain: f64,
    pub input_offset: f64,
    pub output_offset: f64,
}

impl TimeModel {
    fn from_theta(th: &[f64; N_TIME_PARAMS]) -> Self {
        Self {
            model: NormalisedModel {
                alpha: th[ALPHA],
                delta: th[DELTA],
                beta: th[BETA],
                rho: th[RHO],
                kappa: th[KAPPA],
                eta: th[ETA],
            },
            gain: th[GAIN],
            input_offset: th[INPUT_OFFSET],
            output_offset: th[OUTPUT_OFFSET],
        }
    }

    fn theta(&self, initial: State) -> [f64; N_TIME_PARAMS] {
        let m = &self.model;
        [
            m.alpha,
            m.delta,
            m.beta,
            m.rho,
            m.kappa,
            m.eta,
            self.gain,
            self.input_offset,
            self.output_offset,
            initial.x,
            initial.v,
        ]
    }
}

/// `c · s|s|^μ`, its slope `c (μ+1) |s|^μ` and `s|s|^μ`, `s|s|^μ ln|s|`
/// (μ ≥ 0; every term is 0 at s = 0 except the slope for μ = 0).
#[inline(always)]
fn power_terms(s: f64, mu: f64, want_log: bool) -> (f64, f64, f64) {
    if s == 0.0 {
        return (0.0, if mu == 0.0 { 1.0 } else { 0.0 }, 0.0);
    }
    let a = s.abs();
    let p = if mu == 2.0 {
        a * a
    } else if mu == 1.0 {
        a
    } else if mu == 0.0 {
        1.0
    } else {
        a.powf(mu)
    };
    let sp = s * p;
    let lg = if want_log { sp * a.ln() } else { 0.0 };
    (sp, (mu + 1.0) * p, lg)
}

/// Simulation of θ on a fine input (`disc.fine`); `ys` gets ŷ at every
/// record sample and, with `jac = Some`, the rows `∂ŷ_k/∂θ` (all
/// [`N_TIME_PARAMS`] columns); `vs = Some` gets the velocity at every
/// sample. `logs = (ρ, η)` columns needed. Returns `false` on a non-finite
/// state. ([`trajectory`], then [`sensitivities_split`].)
#[allow(clippy::too_many_arguments)]
fn run(
    th: &[f64; N_TIME_PARAMS],
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
    ys: &mut Vec<f64>,
    jac: Option<&mut Vec<[f64; N_TIME_PARAMS]>>,
    logs: (bool, bool),
    vs: Option<&mut Vec<f64>>,
) -> bool {
    let Some(jac) = jac else {
        return trajectory(th, fine, fs, disc, logs, ys, vs, None);
    };
    jac.clear();
    let mut stages = Vec::new();
    if !trajectory(th, fine, fs, disc, logs, ys, vs, Some(&mut stages)) {
        return false;
    }
    let cols: Vec<usize> = (0..N_TIME_PARAMS).collect();
    let flat = sensitivities_split(th, fine, fs, disc, logs, &stages, &cols);
    jac.extend(
        flat.chunks_exact(N_TIME_PARAMS)
            .map(|r| <[f64; N_TIME_PARAMS]>::try_from(r).expect("row length")),
    );
    true
}

/// One RK4 stage of a simulated trajectory, recorded by [`trajectory`] for
/// [`sensitivities`]: the stage state and the power-law factors `|x|^ρ`,
/// `|v|^η` with `ln|x|`, `ln|v|` (as [`power_parts`] returns them).
#[derive(Debug, Clone, Copy, Default)]
struct Stage {
    x: f64,
    v: f64,
    px: f64,
    pv: f64,
    lnx: f64,
    lnv: f64,
}

/// `|s|^μ` and `ln|s|` (μ ≥ 0) for the simulation: `|s|^μ = exp(μ ln|s|)`,
/// one logarithm shared by the power and the exponent's sensitivity
/// (`s|s|^μ ln|s|`); exact products for μ = 0, 1, 2 (the log then only
/// when `want_log`). At s = 0: `(1 if μ = 0 else 0, 0)`, so that
/// `s|s|^μ = 0`, its slope `(μ+1)|s|^μ` and `s|s|^μ ln|s| = 0` (as
/// [`power_terms`]).
#[inline(always)]
fn power_parts(s: f64, mu: f64, want_log: bool) -> (f64, f64) {
    if s == 0.0 {
        return (if mu == 0.0 { 1.0 } else { 0.0 }, 0.0);
    }
    let a = s.abs();
    let special = if mu == 2.0 {
        Some(a * a)
    } else if mu == 1.0 {
        Some(a)
    } else if mu == 0.0 {
        Some(1.0)
    } else {
        None
    };
    match special {
        Some(p) => (p, if want_log { a.ln() } else { 0.0 }),
        None => {
            let l = a.ln();
            ((mu * l).exp(), l)
        }
    }
}

/// The state recurrence of [`run`] (RK4 on the fine input): ŷ at every
/// sample into `ys`, the velocity into `vs`, every stage into `stages`
/// (`1 + 4 · steps` entries: the first stage of each step, then its
/// stages 2–4; the last entry is the first stage after the last step).
/// `logs`: record `ln|x|`, `ln|v|` for the exponents' sensitivities.
/// `false` on a non-finite state.
#[allow(clippy::too_many_arguments)]
fn trajectory(
    th: &[f64; N_TIME_PARAMS],
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
    logs: (bool, bool),
    ys: &mut Vec<f64>,
    mut vs: Option<&mut Vec<f64>>,
    mut stages: Option<&mut Vec<Stage>>,
) -> bool {
    let (alpha, delta, beta, rho, kappa, eta) =
        (th[ALPHA], th[DELTA], th[BETA], th[RHO], th[KAPPA], th[ETA]);
    let (g, bu, by) = (th[GAIN], th[INPUT_OFFSET], th[OUTPUT_OFFSET]);
    let per_sample = 2 * disc.substeps;
    let zoh = disc.interpolation == InputInterpolation::Zoh;
    let h = 1.0 / (disc.substeps as f64 * fs);
    let hh = 0.5 * h;
    let h6 = h * (1.0 / 6.0);
    let has_s = beta != 0.0 || logs.0;
    let has_d = kappa != 0.0 || logs.1;
    // acceleration at one stage, and the stage's record
    let accel = |x: f64, v: f64, ut: f64| {
        let (px, lnx) = if has_s {
            power_parts(x, rho, logs.0)
        } else {
            (0.0, 0.0)
        };
        let (pv, lnv) = if has_d {
            power_parts(v, eta, logs.1)
        } else {
            (0.0, 0.0)
        };
        let fx = if has_s { x * px } else { 0.0 };
        let fv = if has_d { v * pv } else { 0.0 };
        let a = g * (ut + bu) - ((alpha * x + beta * fx) + (delta * v + kappa * fv));
        (
            a,
            Stage {
                x,
                v,
                px,
                pv,
                lnx,
                lnv,
            },
        )
    };
    ys.clear();
    let (mut x, mut v) = (th[X0], th[V0]);
    ys.push(x + by);
    if let Some(w) = vs.as_deref_mut() {
        w.clear();
        w.push(v);
    }
    let (mut a1, st1) = accel(x, v, fine[0]);
    if let Some(s) = stages.as_deref_mut() {
        s.clear();
        s.reserve(2 * fine.len() + 1);
        s.push(st1);
    }
    let mut i = 0;
    let n_fine = fine.len();
    while i + 2 < n_fine {
        let boundary = (i + 2) % per_sample == 0;
        // a hold keeps u_k up to the end of its interval (the left limit)
        let (um, u1) = (
            fine[i + 1],
            if zoh && boundary {
                fine[i + 1]
            } else {
                fine[i + 2]
            },
        );
        let x2 = x + hh * v;
        let v2 = v + hh * a1;
        let (a2, st2) = accel(x2, v2, um);
        let x3 = x + hh * v2;
        let v3 = v + hh * a2;
        let (a3, st3) = accel(x3, v3, um);
        let x4 = x + h * v3;
        let v4 = v + h * a3;
        let (a4, st4) = accel(x4, v4, u1);
        let xn = x + h6 * (v + 2.0 * (v2 + v3) + v4);
        let vn = v + h6 * (a1 + 2.0 * (a2 + a3) + a4);
        x = xn;
        v = vn;
        if !(x.is_finite() && v.is_finite()) {
            return false;
        }
        let (na1, st1) = accel(x, v, fine[i + 2]);
        a1 = na1;
        if let Some(s) = stages.as_deref_mut() {
            s.extend_from_slice(&[st2, st3, st4, st1]);
        }
        i += 2;
        if boundary {
            ys.push(x + by);
            if let Some(w) = vs.as_deref_mut() {
                w.push(v);
            }
        }
    }
    true
}

/// The forward sensitivities (module docs) of a trajectory recorded by
/// [`trajectory`] with the same θ, input, discretisation and `logs`, for
/// the entries `cols` of θ: `out` gets one row of `cols.len()` values
/// `∂ŷ_k/∂θ_c` per sample. Each column's recurrence involves only that
/// column, so any grouping of the columns gives the same values (those of
/// the joint recurrence: the same operations in the same order).
#[allow(clippy::too_many_arguments)]
fn sensitivities(
    th: &[f64; N_TIME_PARAMS],
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
    logs: (bool, bool),
    stages: &[Stage],
    cols: &[usize],
    out: &mut Vec<f64>,
) {
    // a fixed width (the loops unrolled and vectorised), padded with
    // columns that stay 0 and are not written
    match cols.len() {
        0..=2 => sensitivities_w::<2>(th, fine, fs, disc, logs, stages, cols, out),
        3..=4 => sensitivities_w::<4>(th, fine, fs, disc, logs, stages, cols, out),
        5..=6 => sensitivities_w::<6>(th, fine, fs, disc, logs, stages, cols, out),
        7..=8 => sensitivities_w::<8>(th, fine, fs, disc, logs, stages, cols, out),
        _ => sensitivities_w::<N_TIME_PARAMS>(th, fine, fs, disc, logs, stages, cols, out),
    }
}

/// [`sensitivities`] with `W >= cols.len()` lanes.
#[allow(clippy::too_many_arguments)]
fn sensitivities_w<const W: usize>(
    th: &[f64; N_TIME_PARAMS],
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
    logs: (bool, bool),
    stages: &[Stage],
    cols: &[usize],
    out: &mut Vec<f64>,
) {
    const P: usize = N_TIME_PARAMS;
    let c = cols.len();
    assert!(c <= W && W <= P, "at most {W} columns");
    let (alpha, delta, beta, rho, kappa, eta) =
        (th[ALPHA], th[DELTA], th[BETA], th[RHO], th[KAPPA], th[ETA]);
    let (g, bu) = (th[GAIN], th[INPUT_OFFSET]);
    let per_sample = 2 * disc.substeps;
    let zoh = disc.interpolation == InputInterpolation::Zoh;
    let h = 1.0 / (disc.substeps as f64 * fs);
    let hh = 0.5 * h;
    let h6 = h * (1.0 / 6.0);
    let has_s = beta != 0.0 || logs.0;
    let has_d = kappa != 0.0 || logs.1;
    // padding lanes read the forcing slot P, always 0
    let mut col = [P; W];
    let mut sx = [0.0; W];
    let mut sv = [0.0; W];
    for (k, &p) in cols.iter().enumerate() {
        assert!(p < P, "column {p}");
        col[k] = p;
        sx[k] = if p == X0 { 1.0 } else { 0.0 };
        sv[k] = if p == V0 { 1.0 } else { 0.0 };
    }
    // ∂a/∂θ at one stage: f_s · (S_x, S_v) + f_θ
    let slope = |s: &Stage, ut: f64, sx: &[f64; W], sv: &[f64; W], da: &mut [f64; W]| {
        let (fx, dfx, lx) = if has_s {
            let fx = s.x * s.px;
            (
                fx,
                (rho + 1.0) * s.px,
                if logs.0 { fx * s.lnx } else { 0.0 },
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        let (fv, dfv, lv) = if has_d {
            let fv = s.v * s.pv;
            (
                fv,
                (eta + 1.0) * s.pv,
                if logs.1 { fv * s.lnv } else { 0.0 },
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        let ax = -alpha - beta * dfx;
        let av = -delta - kappa * dfv;
        let mut f = [0.0; P + 1];
        f[ALPHA] = -s.x;
        f[DELTA] = -s.v;
        f[BETA] = -fx;
        f[RHO] = -(beta * lx);
        f[KAPPA] = -fv;
        f[ETA] = -(kappa * lv);
        f[GAIN] = ut + bu;
        f[INPUT_OFFSET] = g;
        let mut fk = [0.0; W];
        for k in 0..W {
            fk[k] = f[col[k]];
        }
        for k in 0..W {
            da[k] = ax * sx[k] + av * sv[k] + fk[k];
        }
    };
    let emit = |sx: &[f64; W], out: &mut Vec<f64>| {
        for k in 0..c {
            out.push(if col[k] == OUTPUT_OFFSET {
                sx[k] + 1.0
            } else {
                sx[k]
            });
        }
    };
    out.clear();
    out.reserve(c * (fine.len() / per_sample + 1));
    emit(&sx, out);
    let mut da1 = [0.0; W];
    let mut da2 = [0.0; W];
    let mut da3 = [0.0; W];
    let mut da4 = [0.0; W];
    let (mut s2x, mut s2v) = ([0.0; W], [0.0; W]);
    let (mut s3x, mut s3v) = ([0.0; W], [0.0; W]);
    let (mut s4x, mut s4v) = ([0.0; W], [0.0; W]);
    slope(&stages[0], fine[0], &sx, &sv, &mut da1);
    let mut i = 0;
    for st in stages[1..].chunks_exact(4) {
        let boundary = (i + 2) % per_sample == 0;
        let (um, u1) = (
            fine[i + 1],
            if zoh && boundary {
                fine[i + 1]
            } else {
                fine[i + 2]
            },
        );
        for k in 0..W {
            s2x[k] = sx[k] + hh * sv[k];
            s2v[k] = sv[k] + hh * da1[k];
        }
        slope(&st[0], um, &s2x, &s2v, &mut da2);
        for k in 0..W {
            s3x[k] = sx[k] + hh * s2v[k];
            s3v[k] = sv[k] + hh * da2[k];
        }
        slope(&st[1], um, &s3x, &s3v, &mut da3);
        for k in 0..W {
            s4x[k] = sx[k] + h * s3v[k];
            s4v[k] = sv[k] + h * da3[k];
        }
        slope(&st[2], u1, &s4x, &s4v, &mut da4);
        for k in 0..W {
            sx[k] += h6 * (sv[k] + 2.0 * (s2v[k] + s3v[k]) + s4v[k]);
            sv[k] += h6 * (da1[k] + 2.0 * (da2[k] + da3[k]) + da4[k]);
        }
        slope(&st[3], fine[i + 2], &sx, &sv, &mut da1);
        i += 2;
        if boundary {
            emit(&sx, out);
        }
    }
}

/// Steps (RK4 stages / 4) from which [`sensitivities_split`] shares the
/// columns between two threads.
const SPLIT_MIN_STAGES: usize = 4096;

/// [`sensitivities`] of `cols` into a row-major matrix (one row of
/// `cols.len()` per sample), the columns shared between two rayon tasks on
/// long records (the same values: the columns are independent).
#[allow(clippy::too_many_arguments)]
fn sensitivities_split(
    th: &[f64; N_TIME_PARAMS],
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
    logs: (bool, bool),
    stages: &[Stage],
    cols: &[usize],
) -> Vec<f64> {
    let c = cols.len();
    let mut out = Vec::new();
    if c < 4 || stages.len() < SPLIT_MIN_STAGES {
        sensitivities(th, fine, fs, disc, logs, stages, cols, &mut out);
        return out;
    }
    let (left, right) = cols.split_at(c / 2);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    rayon::join(
        || sensitivities(th, fine, fs, disc, logs, stages, left, &mut a),
        || sensitivities(th, fine, fs, disc, logs, stages, right, &mut b),
    );
    let (nl, nr) = (left.len(), right.len());
    out.reserve(a.len() + b.len());
    for (ra, rb) in a.chunks_exact(nl).zip(b.chunks_exact(nr)) {
        out.extend_from_slice(ra);
        out.extend_from_slice(rb);
    }
    out
}

/// ŷ of a model on a range's input from an initial state (the prediction of
/// [`predict`] once the initial state is known), with the default
/// [`Discretisation`] (cubic input, `h = 1/(2 f_s)`).
pub fn simulate_output(
    tm: &TimeModel,
    u: &[f64],
    fs: f64,
    initial: State,
) -> Result<Vec<f64>, TimeFitError> {
    simulate_output_with(tm, u, fs, initial, &Discretisation::default())
}

/// [`simulate_output`] with a given input reconstruction and substeps.
pub fn simulate_output_with(
    tm: &TimeModel,
    u: &[f64],
    fs: f64,
    initial: State,
    disc: &Discretisation,
) -> Result<Vec<f64>, TimeFitError> {
    Ok(simulate_states(tm, u, fs, initial, disc)?.0)
}

/// ŷ and the velocity `x'` at every sample of `u` (see
/// [`simulate_output_with`]); `x = ŷ − output_offset`.
pub fn simulate_states(
    tm: &TimeModel,
    u: &[f64],
    fs: f64,
    initial: State,
    disc: &Discretisation,
) -> Result<(Vec<f64>, Vec<f64>), TimeFitError> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(TimeFitError::NonPositiveFs { fs });
    }
    let disc = Discretisation::new(disc.interpolation, disc.substeps)?;
    let th = tm.theta(initial);
    let mut ys = Vec::with_capacity(u.len());
    let mut vs = Vec::with_capacity(u.len());
    if !run(
        &th,
        &disc.fine(u),
        fs,
        &disc,
        &mut ys,
        None,
        (false, false),
        Some(&mut vs),
    ) {
        return Err(TimeFitError::Diverged);
    }
    Ok((ys, vs))
}

/// Step doubling of a stated discretisation (the integration check of
/// `nlsdof simulate` and Python's `Model.simulate` on a model file that
/// states its input reconstruction and substeps): `x`, the displacement
/// simulated from `u` with `disc`, against the same record at twice the
/// substeps, `max |x − x₂| / max |x₂|`, scaled by the law's Richardson
/// factor ([`crate::simulation::step_doubling_error`]).
pub fn stated_integration_error(
    tm: &TimeModel,
    u: &[f64],
    fs: f64,
    initial: State,
    disc: &Discretisation,
    x: &[f64],
) -> Result<crate::simulation::IntegrationError, TimeFitError> {
    let n = x.len().min(u.len());
    let fine = Discretisation {
        substeps: (2 * disc.substeps).min(MAX_SUBSTEPS),
        ..*disc
    };
    let (x2, _) = simulate_states(tm, &u[..n], fs, initial, &fine)?;
    let (mut diff, mut scale) = (0.0f64, 0.0f64);
    for (a, b) in x.iter().zip(&x2) {
        diff = diff.max((a - b).abs());
        scale = scale.max(b.abs());
    }
    let diff = if scale > 0.0 { diff / scale } else { 0.0 };
    Ok(crate::simulation::step_doubling_error(&tm.model, diff, n))
}

/// ŷ and its exact discrete Jacobian (one row of [`N_TIME_PARAMS`] per
/// sample) for θ on the input `u` — the sensitivities of the fit, exposed
/// for tests.
pub fn output_and_sensitivities(
    theta: &[f64; N_TIME_PARAMS],
    u: &[f64],
    fs: f64,
) -> Option<(Vec<f64>, Vec<[f64; N_TIME_PARAMS]>)> {
    let mut ys = Vec::new();
    let mut jac = Vec::new();
    let disc = Discretisation::default();
    run(
        theta,
        &disc.fine(u),
        fs,
        &disc,
        &mut ys,
        Some(&mut jac),
        (true, true),
        None,
    )
    .then_some((ys, jac))
}

/// The least-squares problem over the free entries of θ, scaled:
/// `θ_p = scale_p z_p`.
struct OutputError<'a> {
    fine: &'a [f64],
    y: &'a [f64],
    fs: f64,
    disc: Discretisation,
    base: [f64; N_TIME_PARAMS],
    free: &'a [usize],
    scale: Vec<f64>,
    logs: (bool, bool),
    /// The trajectory of the last [`LeastSquares::residuals`] call: LM
    /// asks for the Jacobian at the trial point it has just accepted, whose
    /// trajectory (with its powers and logs) is then reused as it is.
    last: std::sync::Mutex<LastTrajectory>,
    /// Ctrl-C: once set, evaluations return `None` (before the trajectory
    /// and between it and the sensitivities), so a stop waits for at most
    /// one of the two passes; LM then ends and the fit reports `Interrupted`.
    cancel: crate::cancel::Cancel,
}

/// See [`OutputError::last`].
#[derive(Default)]
struct LastTrajectory {
    /// The z of the trajectory (empty: none).
    z: Vec<f64>,
    ys: Vec<f64>,
    stages: Vec<Stage>,
}

impl OutputError<'_> {
    fn theta(&self, z: &[f64]) -> [f64; N_TIME_PARAMS] {
        let mut th = self.base;
        for (k, &p) in self.free.iter().enumerate() {
            th[p] = z[k] * self.scale[k];
        }
        th
    }
}

impl LeastSquares for OutputError<'_> {
    fn n_params(&self) -> usize {
        self.free.len()
    }
    fn residuals(&self, z: &[f64]) -> Option<Vec<f64>> {
        if self.cancel.is_cancelled() {
            return None;
        }
        let th = self.theta(z);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let last = &mut *last;
        last.z.clear();
        let mut ys = Vec::with_capacity(self.y.len());
        if !trajectory(
            &th,
            self.fine,
            self.fs,
            &self.disc,
            self.logs,
            &mut ys,
            None,
            Some(&mut last.stages),
        ) {
            return None;
        }
        last.z.extend_from_slice(z);
        last.ys.clone_from(&ys);
        for (a, b) in ys.iter_mut().zip(self.y) {
            *a -= b;
        }
        Some(ys)
    }
    fn residuals_and_jacobian(&self, z: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        if self.cancel.is_cancelled() {
            return None;
        }
        let th = self.theta(z);
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        let last = &mut *last;
        let same = !last.z.is_empty()
            && last.z.len() == z.len()
            && last
                .z
                .iter()
                .zip(z)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        let mut ys = Vec::with_capacity(self.y.len());
        if same {
            ys.clone_from(&last.ys);
        } else {
            last.z.clear();
            if !trajectory(
                &th,
                self.fine,
                self.fs,
                &self.disc,
                self.logs,
                &mut ys,
                None,
                Some(&mut last.stages),
            ) {
                return None;
            }
        }
        if self.cancel.is_cancelled() {
            return None;
        }
        let flat = sensitivities_split(
            &th,
            self.fine,
            self.fs,
            &self.disc,
            self.logs,
            &last.stages,
            self.free,
        );
        for (a, b) in ys.iter_mut().zip(self.y) {
            *a -= b;
        }
        let mut j = flat;
        for row in j.chunks_exact_mut(self.free.len()) {
            for (v, s) in row.iter_mut().zip(&self.scale) {
                *v *= s;
            }
        }
        if j.iter().any(|v| !v.is_finite()) {
            return None;
        }
        Some((ys, j))
    }
}

/// Standard errors and 95 % intervals of the free parameters
/// (`cov = s² (JᵀJ)⁻¹`, `s² = cost/(n − p)`, Student t quantile).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeUncertainty {
    pub names: Vec<&'static str>,
    pub values: Vec<f64>,
    pub std_errors: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    pub s2: f64,
    pub dof: usize,
}

fn uncertainty_of(
    theta: &[f64; N_TIME_PARAMS],
    free: &[usize],
    j: &[f64],
    r: &[f64],
) -> Option<TimeUncertainty> {
    let p = free.len();
    let n = r.len();
    if n <= p {
        return None;
    }
    let (a, _) = normal_equations(j, r, p);
    let d: Vec<f64> = (0..p).map(|k| a[k * p + k].sqrt()).collect();
    if d.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        return None;
    }
    let scaled: Vec<f64> = (0..p * p).map(|i| a[i] / (d[i / p] * d[i % p])).collect();
    let mut diag = vec![0.0; p];
    for c in 0..p {
        let mut e = vec![0.0; p];
        e[c] = 1.0;
        let col = cholesky_solve(&scaled, &e, p)?;
        diag[c] = col[c] / (d[c] * d[c]);
    }
    let cost: f64 = r.iter().map(|x| x * x).sum();
    let dof = n - p;
    let s2 = cost / dof as f64;
    let t = t95(dof);
    let values: Vec<f64> = free.iter().map(|&k| theta[k]).collect();
    let se: Vec<f64> = diag.iter().map(|&v| (s2 * v).max(0.0).sqrt()).collect();
    Some(TimeUncertainty {
        names: free.iter().map(|&k| TIME_PARAM_NAMES[k]).collect(),
        lower: values.iter().zip(&se).map(|(v, s)| v - t * s).collect(),
        upper: values.iter().zip(&se).map(|(v, s)| v + t * s).collect(),
        values,
        std_errors: se,
        s2,
        dof,
    })
}

/// Options of [`fit_time_domain`].
#[derive(Debug, Clone, PartialEq)]
pub struct TimeFitOptions {
    pub lm: LmOptions,
    /// Starts of the free-exponent stage: 1 = from (ρ, η) = (2, 1) only;
    /// more add seeded random exponents.
    pub starts: usize,
    pub seed: u64,
    /// The input reconstruction between samples (part of the model).
    pub interpolation: InputInterpolation,
    /// RK4 substeps per sample: `None` chooses them so that the
    /// integration error is at most `integration_tolerance` of the RMS
    /// output error (see the module docs); `Some(n)` fixes them.
    pub substeps: Option<usize>,
    /// Target of the automatic choice: integration error (RMS change of ŷ
    /// when the substeps are doubled) over RMS output error.
    pub integration_tolerance: f64,
    /// Entries of θ held at a value instead of fitted, `(index, value)`
    /// (indices as [`TIME_PARAM_NAMES`]; model parameters α … b_y whose
    /// value is inside the fit's bounds), e.g. `(DELTA, 0.0)`. Empty by
    /// default.
    pub fixed: Vec<(usize, f64)>,
}

impl Default for TimeFitOptions {
    fn default() -> Self {
        Self {
            lm: LmOptions {
                max_iterations: 400,
                max_evaluations: 1200,
                xtol: 1e-10,
                ftol: 1e-12,
                gtol: 1e-10,
                cost_floor: 0.0,
                decrement_tol: 0.0,
                cancel: crate::cancel::Cancel::NEVER,
            },
            starts: 1,
            seed: 1,
            interpolation: InputInterpolation::Cubic,
            substeps: None,
            integration_tolerance: 0.01,
            fixed: Vec::new(),
        }
    }
}

/// Result of [`fit_time_domain`].
#[derive(Debug, Clone, PartialEq)]
pub struct TimeFit {
    pub kind: ModelKind,
    pub range: SampleRange,
    /// θ at the optimum (see [`TIME_PARAM_NAMES`]); x₀, v₀ at `range.start`.
    pub theta: [f64; N_TIME_PARAMS],
    /// Indices of the free entries of θ.
    pub free: Vec<usize>,
    /// The equation-error start.
    pub start: [f64; N_TIME_PARAMS],
    /// RMS output error of the start and of the fit over the range.
    pub start_rms: f64,
    pub rms: f64,
    pub cost: f64,
    /// How the local fit that produced θ ended, and its LM iterations: the
    /// last local fit (the free-exponent stage's winner, or its refit at
    /// more substeps when the integration check asked for one:
    /// [`IntegrationCheck::refits`]), not the sum over the stages.
    pub termination: Termination,
    pub iterations: usize,
    /// `None` when `JᵀJ` is singular at the optimum.
    pub uncertainty: Option<TimeUncertainty>,
    /// ŷ over the estimation range.
    pub y_model: Vec<f64>,
    /// The input reconstruction and RK4 substeps the fit integrated with.
    pub discretisation: Discretisation,
    /// The integration-error check at the optimum.
    pub integration: IntegrationCheck,
}

impl TimeFit {
    pub fn model(&self) -> TimeModel {
        TimeModel::from_theta(&self.theta)
    }
    pub fn initial(&self) -> State {
        State {
            x: self.theta[X0],
            v: self.theta[V0],
        }
    }
}

/// Exponents of a kind (ρ, η): fixed value or `None` = free; `Err` for
/// negative fixed exponents (Coulomb).
fn exponents(kind: ModelKind) -> Result<(Term, Term), TimeFitError> {
    let (s, d) = (kind.stiffness(), kind.damping());
    for t in [s, d] {
        if let Term::FixedExponent(e) = t {
            if e < 0.0 {
                return Err(TimeFitError::UnsupportedModel { kind, value: e });
            }
        }
    }
    Ok((s, d))
}

/// Equation-error estimate with fixed exponents: Eq 32 at every sample
/// with `x = y − ȳ` and `x'`, `x''` from fifth-order central differences,
/// `x'' = g u + c − α x − δ x' − β x|x|^ρ − κ x'|x'|^η`, solved by linear
/// least squares (columns scaled to unit norm). Returns θ with `b_y = ȳ`,
/// `b_u = c/g` (nonlinear) or `b_u = 0`, `b_y = ȳ + c/α` (linear), and
/// x₀, v₀ from the first samples.
fn equation_error(
    u: &[f64],
    y: &[f64],
    fs: f64,
    stiff: Option<f64>,
    damp: Option<f64>,
) -> Result<[f64; N_TIME_PARAMS], TimeFitError> {
    let n = y.len();
    let ybar = y.iter().sum::<f64>() / n as f64;
    let h = 1.0 / fs;
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut rhs = Vec::with_capacity(n);
    let ncol = 4 + stiff.is_some() as usize + damp.is_some() as usize;
    for _ in 0..ncol {
        cols.push(Vec::with_capacity(n));
    }
    for k in 2..n - 2 {
        let (ym2, ym1, y0, y1, y2) = (y[k - 2], y[k - 1], y[k], y[k + 1], y[k + 2]);
        let d1 = (-y2 + 8.0 * y1 - 8.0 * ym1 + ym2) / (12.0 * h);
        let d2 = (-y2 + 16.0 * y1 - 30.0 * y0 + 16.0 * ym1 - ym2) / (12.0 * h * h);
        let x = y0 - ybar;
        let mut c = 0;
        let mut push = |v: f64| {
            cols[c].push(v);
            c += 1;
        };
        push(u[k]);
        push(1.0);
        push(-x);
        push(-d1);
        if let Some(r) = stiff {
            push(-power_terms(x, r, false).0);
        }
        if let Some(e) = damp {
            push(-power_terms(d1, e, false).0);
        }
        rhs.push(d2);
    }
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    if norms.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
        return Err(TimeFitError::SingularStart);
    }
    let m = rhs.len();
    let mut j = Vec::with_capacity(m * ncol);
    for i in 0..m {
        j.extend(cols.iter().zip(&norms).map(|(col, nc)| col[i] / nc));
    }
    let (a, g) = normal_equations(&j, &rhs, ncol);
    let sol = cholesky_solve(&a, &g, ncol).ok_or(TimeFitError::SingularStart)?;
    let p: Vec<f64> = sol.iter().zip(&norms).map(|(s, n)| s / n).collect();
    let mut th = [0.0; N_TIME_PARAMS];
    th[GAIN] = p[0];
    th[ALPHA] = p[2];
    th[DELTA] = p[3];
    let mut c = 4;
    if let Some(r) = stiff {
        th[BETA] = p[c];
        th[RHO] = r;
        c += 1;
    } else {
        th[RHO] = 0.0;
    }
    if let Some(e) = damp {
        th[KAPPA] = p[c].max(0.0);
        th[ETA] = e;
    }
    if !(th[ALPHA] > 0.0 && th[GAIN] != 0.0) {
        return Err(TimeFitError::SingularStart);
    }
    if !(th[DELTA] > 0.0) {
        // at least a little damping: 0.1 % of critical
        th[DELTA] = 2e-3 * th[ALPHA].sqrt();
    }
    if stiff.is_some() {
        th[INPUT_OFFSET] = p[1] / p[0];
        th[OUTPUT_OFFSET] = ybar;
    } else {
        th[INPUT_OFFSET] = 0.0;
        th[OUTPUT_OFFSET] = ybar + p[1] / p[2];
    }
    th[X0] = y[0] - th[OUTPUT_OFFSET];
    th[V0] = (-3.0 * y[0] + 4.0 * y[1] - y[2]) / (2.0 * h);
    Ok(th)
}

fn bounds(p: usize) -> (f64, f64) {
    match p {
        ALPHA => (f64::MIN_POSITIVE, f64::INFINITY),
        DELTA | KAPPA => (0.0, f64::INFINITY),
        RHO | ETA => (0.0, MAX_EXPONENT),
        _ => (f64::NEG_INFINITY, f64::INFINITY),
    }
}

struct Local {
    theta: [f64; N_TIME_PARAMS],
    cost: f64,
    termination: Termination,
    iterations: usize,
    evaluations: usize,
}

/// One bounded LM run over `free` from `start`.
fn local_fit(
    fine: &[f64],
    disc: &Discretisation,
    y: &[f64],
    fs: f64,
    start: &[f64; N_TIME_PARAMS],
    free: &[usize],
    lm: &LmOptions,
) -> Result<Local, TimeFitError> {
    local_fit_resumable(fine, disc, y, fs, start, free, lm, None).map(|(l, _)| l)
}

/// Where an LM run of [`local_fit_resumable`] stopped: its scaling of θ and
/// its [`LmState`], to continue it.
struct Resume {
    scale: Vec<f64>,
    /// The scaled point `z` it stopped at.
    z: Vec<f64>,
    state: LmState,
}

/// [`local_fit`], or the continuation of a run stopped at its iteration
/// limit (`resume`: its scaling and state; `start` = its θ): the iterates of
/// the run that did not stop.
#[allow(clippy::too_many_arguments)]
fn local_fit_resumable(
    fine: &[f64],
    disc: &Discretisation,
    y: &[f64],
    fs: f64,
    start: &[f64; N_TIME_PARAMS],
    free: &[usize],
    lm: &LmOptions,
    resume: Option<Resume>,
) -> Result<(Local, Resume), TimeFitError> {
    let (scale, z0, state) = match resume {
        Some(r) => (r.scale, r.z, r.state),
        None => {
            let scale = scale_of(start, free, y, fs);
            let z0 = free
                .iter()
                .zip(&scale)
                .map(|(&p, s)| start[p] / s)
                .collect();
            (scale, z0, LmState::default())
        }
    };
    local_fit_scaled(fine, disc, y, fs, start, free, lm, scale, z0, state)
}

/// The scaling `θ_p = scale_p z_p` of an LM run from `start`.
fn scale_of(start: &[f64; N_TIME_PARAMS], free: &[usize], y: &[f64], fs: f64) -> Vec<f64> {
    free.iter()
        .map(|&p| {
            let s = start[p].abs();
            match p {
                RHO | ETA => 1.0,
                X0 | V0 | INPUT_OFFSET | OUTPUT_OFFSET => {
                    // offsets and states on the scale of the output's spread
                    let spread = y.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
                    match p {
                        V0 => spread * fs,
                        INPUT_OFFSET => (spread * start[ALPHA] / start[GAIN].abs()).max(s),
                        _ => spread.max(s),
                    }
                }
                _ if s > 0.0 => s,
                _ => 1.0,
            }
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn local_fit_scaled(
    fine: &[f64],
    disc: &Discretisation,
    y: &[f64],
    fs: f64,
    start: &[f64; N_TIME_PARAMS],
    free: &[usize],
    lm: &LmOptions,
    scale: Vec<f64>,
    z0: Vec<f64>,
    state: LmState,
) -> Result<(Local, Resume), TimeFitError> {
    let problem = OutputError {
        fine,
        y,
        fs,
        disc: *disc,
        base: *start,
        free,
        scale: scale.clone(),
        logs: (free.contains(&RHO), free.contains(&ETA)),
        last: Default::default(),
        cancel: lm.cancel,
    };
    let (lo, hi): (Vec<f64>, Vec<f64>) = free
        .iter()
        .zip(&scale)
        .map(|(&p, s)| {
            let (l, h) = bounds(p);
            (l / s, h / s)
        })
        .unzip();
    let (r, state) =
        minimise_resumable(&problem, &z0, &lo, &hi, lm, state).map_err(|_| {
            match lm.cancel.check() {
                Err(i) => TimeFitError::Interrupted(i),
                Ok(()) => TimeFitError::StartNotEvaluable,
            }
        })?;
    let local = Local {
        theta: problem.theta(&r.u),
        cost: r.cost,
        termination: r.termination,
        iterations: r.iterations,
        evaluations: r.evaluations,
    };
    Ok((
        local,
        Resume {
            scale,
            z: r.u,
            state,
        },
    ))
}

/// Share of the equivalent linear damping left in δ by
/// [`damping_moved_start`].
const MOVED_DELTA_SHARE: f64 = 0.01;
/// The damping exponent of [`damping_moved_start`].
const MOVED_ETA: f64 = 0.05;
/// LM iterations each start of [`race`] gets before the lower cost is
/// continued.
const RACE_ITERATIONS: usize = 10;

/// The second start of the free-exponent stage: the fit `th` (exponents
/// fixed) with its damping `δ v + κ v|v|^η` moved into the power-law term
/// at a small exponent, `η₀ =` [`MOVED_ETA`], `δ₀ =` [`MOVED_DELTA_SHARE`]
/// `· c`, `κ₀ = (1 −` [`MOVED_DELTA_SHARE`]`) c v_rms^−η₀`, with
/// `c = δ + κ v_rms^η` the equivalent linear damping at the RMS velocity
/// `v_rms` of `th`'s response. Near η = 0 the two damping terms nearly
/// coincide and the cost has a long curved valley (`δ + κ v_rms^η` and
/// `κ η` nearly constant) that LM crawls along from η = 1; this start
/// is at its low-η end. `None` when the response has no velocity.
fn damping_moved_start(
    th: &[f64; N_TIME_PARAMS],
    delta_free: bool,
    fine: &[f64],
    fs: f64,
    disc: &Discretisation,
) -> Option<[f64; N_TIME_PARAMS]> {
    let mut ys = Vec::new();
    let mut vs = Vec::new();
    if !trajectory(
        th,
        fine,
        fs,
        disc,
        (false, false),
        &mut ys,
        Some(&mut vs),
        None,
    ) {
        return None;
    }
    let vrms = (vs.iter().map(|v| v * v).sum::<f64>() / vs.len() as f64).sqrt();
    let c = th[DELTA] + th[KAPPA] * vrms.powf(th[ETA]);
    let (delta, kappa) = if delta_free {
        (
            MOVED_DELTA_SHARE * c,
            (1.0 - MOVED_DELTA_SHARE) * c * vrms.powf(-MOVED_ETA),
        )
    } else {
        // δ held: all of the rest of the damping
        (th[DELTA], (c - th[DELTA]) * vrms.powf(-MOVED_ETA))
    };
    if !(vrms > 0.0 && c > 0.0 && kappa > 0.0 && kappa.is_finite()) {
        return None;
    }
    let mut moved = *th;
    moved[DELTA] = delta;
    moved[KAPPA] = kappa;
    moved[ETA] = MOVED_ETA;
    Some(moved)
}

/// LM from each of `starts` (in parallel) for at most [`RACE_ITERATIONS`]
/// iterations; the lowest cost (the first on a tie) is continued to
/// convergence with the rest of the budget `lm`. Deterministic and
/// independent of the thread count. Errors only when no start is
/// evaluable.
fn race(
    fine: &[f64],
    disc: &Discretisation,
    y: &[f64],
    fs: f64,
    starts: &[[f64; N_TIME_PARAMS]],
    free: &[usize],
    lm: &LmOptions,
) -> Result<Local, TimeFitError> {
    let short = LmOptions {
        max_iterations: RACE_ITERATIONS.min(lm.max_iterations),
        ..*lm
    };
    let mut winner: Option<(Local, Resume)> = None;
    let mut error = None;
    let screened: Vec<Result<(Local, Resume), TimeFitError>> = starts
        .par_iter()
        .map(|th| local_fit_resumable(fine, disc, y, fs, th, free, &short, None))
        .collect();
    for r in screened {
        match r {
            Ok(r) => {
                let lower = match &winner {
                    Some(w) => r.0.cost < w.0.cost,
                    None => true,
                };
                if lower {
                    winner = Some(r);
                }
            }
            Err(e) => error = error.or(Some(e)),
        }
    }
    let Some((w, resume)) = winner else {
        return Err(error.unwrap_or(TimeFitError::StartNotEvaluable));
    };
    if w.termination != Termination::MaxIterations || w.iterations < short.max_iterations {
        return Ok(w);
    }
    // the winner continued as if it had not stopped
    let rest = LmOptions {
        max_iterations: lm.max_iterations - w.iterations,
        max_evaluations: lm.max_evaluations.saturating_sub(w.evaluations),
        ..*lm
    };
    let (c, _) = local_fit_resumable(fine, disc, y, fs, &w.theta, free, &rest, Some(resume))?;
    Ok(Local {
        iterations: w.iterations + c.iterations,
        evaluations: w.evaluations + c.evaluations,
        ..c
    })
}

/// Output-error fit of `kind` to the record over `range` (see the module
/// docs). Kinds with negative fixed exponents (Coulomb) are refused.
pub fn fit_time_domain(
    record: &TimeRecord<'_>,
    range: SampleRange,
    kind: ModelKind,
    opts: &TimeFitOptions,
) -> Result<TimeFit, TimeFitError> {
    range.check("estimation", record.u.len(), MIN_ESTIMATION_SAMPLES)?;
    if opts.starts == 0 {
        return Err(TimeFitError::InvalidOption {
            name: "starts",
            value: 0.0,
            reason: "must be >= 1",
        });
    }
    let (s, d) = exponents(kind)?;
    let u = &record.u[range.start..range.end];
    let y = &record.y[range.start..range.end];
    let fs = record.fs;
    let fixed_or = |t: Term, free_start: f64| match t {
        Term::Absent => None,
        Term::FixedExponent(e) => Some(e),
        Term::FreeExponent => Some(free_start),
    };
    let stiff = fixed_or(s, 2.0);
    let damp = fixed_or(d, 1.0);
    let tol = opts.integration_tolerance;
    if !(tol.is_finite() && tol > 0.0) {
        return Err(TimeFitError::InvalidOption {
            name: "integration_tolerance",
            value: tol,
            reason: "must be finite and > 0",
        });
    }
    let mut disc = Discretisation::new(
        opts.interpolation,
        opts.substeps.unwrap_or(Discretisation::default().substeps),
    )?;
    for &(p, v) in &opts.fixed {
        let (lo, hi) = bounds(p.min(N_TIME_PARAMS - 1));
        if !(p <= OUTPUT_OFFSET && v.is_finite() && lo <= v && v <= hi) {
            return Err(TimeFitError::InvalidOption {
                name: "fixed",
                value: v,
                reason: "must hold a model parameter (alpha ... output_offset) at a finite value inside its bounds",
            });
        }
    }
    let held = |p: &usize| opts.fixed.iter().any(|&(q, _)| q == *p);
    let mut start = equation_error(u, y, fs, stiff, damp)?;
    for &(p, v) in &opts.fixed {
        start[p] = v;
    }
    let mut fine = disc.fine(u);
    let simulate = |th: &[f64; N_TIME_PARAMS], fine: &[f64], disc: &Discretisation| {
        let mut ys = Vec::new();
        run(th, fine, fs, disc, &mut ys, None, (false, false), None).then_some(ys)
    };
    let rms_between = |a: &[f64], b: &[f64]| {
        (a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>() / b.len() as f64).sqrt()
    };
    let start_rms = simulate(&start, &fine, &disc)
        .map(|ys| rms_between(&ys, y))
        .unwrap_or(f64::INFINITY);
    // stage 1: exponents fixed
    let mut free: Vec<usize> = vec![ALPHA, DELTA, GAIN, OUTPUT_OFFSET, X0, V0];
    if stiff.is_some() {
        free.push(BETA);
        free.push(INPUT_OFFSET);
    }
    if damp.is_some() {
        free.push(KAPPA);
    }
    free.retain(|p| !held(p));
    free.sort_unstable();
    let stage1 = local_fit(&fine, &disc, y, fs, &start, &free, &opts.lm)?;
    let mut best = stage1;
    // stage 2: free exponents
    let mut free2 = free.clone();
    if matches!(s, Term::FreeExponent) {
        free2.push(RHO);
    }
    if matches!(d, Term::FreeExponent) {
        free2.push(ETA);
    }
    free2.retain(|p| !held(p));
    free2.sort_unstable();
    if free2.len() > free.len() {
        let mut starts = vec![best.theta];
        let mut rng = SplitMix64(opts.seed);
        for _ in 1..opts.starts {
            let mut th = best.theta;
            if free2.contains(&RHO) {
                th[RHO] = 0.5 + 3.5 * rng.next_f64();
            }
            if free2.contains(&ETA) {
                th[ETA] = 0.5 + 3.5 * rng.next_f64();
            }
            starts.push(th);
        }
        for th in starts.iter_mut() {
            // a small positive κ so that η has a gradient
            if free2.contains(&ETA) && free2.contains(&KAPPA) && th[KAPPA] <= 0.0 {
                th[KAPPA] = 1e-3 * th[DELTA].max(1e-12);
            }
        }
        // the start with the linear damping moved into the power law, raced
        // against the first: both screened, the lower cost continued
        let moved = (free2.contains(&ETA) && free2.contains(&KAPPA))
            .then(|| damping_moved_start(&best.theta, free2.contains(&DELTA), &fine, fs, &disc))
            .flatten();
        let full = |ths: &[[f64; N_TIME_PARAMS]]| -> Vec<Result<Local, TimeFitError>> {
            ths.par_iter()
                .map(|th| local_fit(&fine, &disc, y, fs, th, &free2, &opts.lm))
                .collect()
        };
        let results: Vec<Result<Local, TimeFitError>> = match moved {
            Some(moved) => {
                let pair = [starts[0], moved];
                let (raced, mut others) = rayon::join(
                    || race(&fine, &disc, y, fs, &pair, &free2, &opts.lm),
                    || full(&starts[1..]),
                );
                others.insert(0, raced);
                others
            }
            None => full(&starts),
        };
        for r in results.into_iter().flatten() {
            if r.cost < best.cost {
                best = r;
            }
        }
        free = free2;
    }
    // integration error at the optimum: ŷ at twice the substeps; refit at
    // more substeps while it exceeds tol · RMS output error
    let spread = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut refits = 1;
    let integration = loop {
        opts.lm.cancel.check()?;
        let yn = simulate(&best.theta, &fine, &disc).ok_or(TimeFitError::StartNotEvaluable)?;
        let d2 = disc.doubled();
        let e = simulate(&best.theta, &d2.fine(u), &d2)
            .map(|y2| rms_between(&yn, &y2))
            .unwrap_or(f64::INFINITY);
        let out = rms_between(&yn, y);
        // a floor for noise-free records: rounding of the output's scale
        let target = tol * out.max(1e-12 * spread);
        let met = e <= target;
        let check = IntegrationCheck {
            substeps: disc.substeps,
            step: 1.0 / (disc.substeps as f64 * fs),
            integration_error: e,
            output_error: out,
            tolerance: tol,
            met,
            automatic: opts.substeps.is_none(),
            refits,
        };
        if met || opts.substeps.is_some() || disc.substeps >= MAX_SUBSTEPS || refits >= 6 {
            break check;
        }
        // RK4: the error falls as n⁻⁴; 10 % margin, at least one more step
        let ratio = if e.is_finite() { e / target } else { 16.0 };
        let n = ((disc.substeps as f64 * ratio.powf(0.25) * 1.1).ceil() as usize)
            .max(disc.substeps + 1)
            .min(MAX_SUBSTEPS);
        disc = Discretisation::new(disc.interpolation, n)?;
        fine = disc.fine(u);
        best = local_fit(&fine, &disc, y, fs, &best.theta, &free, &opts.lm)?;
        refits += 1;
    };
    let mut ys = Vec::new();
    let mut jac = Vec::new();
    let ok = run(
        &best.theta,
        &fine,
        fs,
        &disc,
        &mut ys,
        Some(&mut jac),
        (free.contains(&RHO), free.contains(&ETA)),
        None,
    );
    if !ok {
        return Err(TimeFitError::StartNotEvaluable);
    }
    let r: Vec<f64> = ys.iter().zip(y).map(|(a, b)| a - b).collect();
    let j: Vec<f64> = jac
        .iter()
        .flat_map(|row| free.iter().map(move |&p| row[p]))
        .collect();
    let cost: f64 = r.iter().map(|v| v * v).sum();
    let uncertainty = uncertainty_of(&best.theta, &free, &j, &r);
    // a cancelled fit (its LM runs stopped early) returns no result
    opts.lm.cancel.check()?;
    Ok(TimeFit {
        kind,
        range,
        theta: best.theta,
        free,
        start,
        start_rms,
        rms: (cost / y.len() as f64).sqrt(),
        cost,
        termination: best.termination,
        iterations: best.iterations,
        uncertainty,
        y_model: ys,
        discretisation: disc,
        integration,
    })
}

/// A prediction over a test range.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    pub range: SampleRange,
    /// Initial state at `range.start`, estimated from the first
    /// [`INIT_WINDOW`] output samples.
    pub initial: State,
    /// ŷ at every sample of the range.
    pub y_model: Vec<f64>,
    /// RMS of `ŷ − y` over the range without its first [`INIT_WINDOW`]
    /// samples (the benchmark score, in the output's unit).
    pub rms: f64,
}

/// Predicts the output over `range` from the input alone; the output is
/// read only at the first [`INIT_WINDOW`] samples, to fit the initial state
/// (LM over x₀, v₀ with the model fixed). Integrates with the default
/// [`Discretisation`]; [`predict_with`] takes the fit's.
pub fn predict(
    record: &TimeRecord<'_>,
    range: SampleRange,
    tm: &TimeModel,
) -> Result<Prediction, TimeFitError> {
    predict_with(record, range, tm, &Discretisation::default())
}

/// [`predict`] with a given input reconstruction and substeps (those of the
/// fit: [`TimeFit::discretisation`]).
pub fn predict_with(
    record: &TimeRecord<'_>,
    range: SampleRange,
    tm: &TimeModel,
    disc: &Discretisation,
) -> Result<Prediction, TimeFitError> {
    let disc = &Discretisation::new(disc.interpolation, disc.substeps)?;
    range.check("test", record.u.len(), INIT_WINDOW + 1)?;
    let u = &record.u[range.start..range.end];
    let fs = record.fs;
    let y0 = &record.y[range.start..range.start + INIT_WINDOW];
    let h = 1.0 / fs;
    let mut th = tm.theta(State {
        x: y0[0] - tm.output_offset,
        v: (-3.0 * y0[0] + 4.0 * y0[1] - y0[2]) / (2.0 * h),
    });
    // the initial state from the first INIT_WINDOW samples (input included)
    let fine_init = disc.fine(&u[..INIT_WINDOW]);
    let lm = LmOptions {
        max_iterations: 100,
        max_evaluations: 300,
        ..TimeFitOptions::default().lm
    };
    let loc = local_fit(&fine_init, disc, y0, fs, &th, &[X0, V0], &lm)?;
    th[X0] = loc.theta[X0];
    th[V0] = loc.theta[V0];
    let initial = State {
        x: th[X0],
        v: th[V0],
    };
    let y_model = simulate_output_with(tm, u, fs, initial, disc)?;
    let y = &record.y[range.start..range.end];
    let m = range.len() - INIT_WINDOW;
    let rms = (y_model[INIT_WINDOW..]
        .iter()
        .zip(&y[INIT_WINDOW..])
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / m as f64)
        .sqrt();
    Ok(Prediction {
        range,
        initial,
        y_model,
        rms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_checked() {
        let r = SampleRange::new;
        assert!(check_ranges(1000, r(0, 500), Some(r(500, 1000))).is_ok());
        assert!(matches!(
            check_ranges(1000, r(0, 500), Some(r(400, 1000))),
            Err(TimeFitError::Overlap { .. })
        ));
        assert!(matches!(
            check_ranges(1000, r(0, 1001), None),
            Err(TimeFitError::RangeOutside { end: 1001, .. })
        ));
        assert!(matches!(
            check_ranges(1000, r(10, 10), None),
            Err(TimeFitError::EmptyRange { .. })
        ));
        assert!(matches!(
            check_ranges(1000, r(0, 500), Some(r(500, 520))),
            Err(TimeFitError::RangeTooShort { .. })
        ));
        assert!(matches!(
            uniform_fs(&[0.0, 0.1, 0.2, 0.31], 1e-3),
            Err(TimeFitError::NonUniformSampling { index: 2, .. })
        ));
        assert!((uniform_fs(&[0.0, 0.1, 0.2, 0.3], 1e-3).unwrap() - 10.0).abs() < 1e-9);
    }

    /// The simulation with sensitivities as it was before [`trajectory`] and
    /// [`sensitivities`] (one joint recurrence over all columns, `powf`):
    /// the reference of the fast path. Simulation of θ on a fine input (`disc.fine`); `ys` gets ŷ at every
    /// record sample and, with `jac = Some`, the rows `∂ŷ_k/∂θ` (all
    /// [`N_TIME_PARAMS`] columns); `vs = Some` gets the velocity at every
    /// sample. `logs = (ρ, η)` columns needed. Returns `false` on a non-finite
    /// state.
    #[allow(clippy::too_many_arguments)]
    fn run_reference(
        th: &[f64; N_TIME_PARAMS],
        fine: &[f64],
        fs: f64,
        disc: &Discretisation,
        ys: &mut Vec<f64>,
        mut jac: Option<&mut Vec<[f64; N_TIME_PARAMS]>>,
        logs: (bool, bool),
        mut vs: Option<&mut Vec<f64>>,
    ) -> bool {
        const P: usize = N_TIME_PARAMS;
        let (alpha, delta, beta, rho, kappa, eta) =
            (th[ALPHA], th[DELTA], th[BETA], th[RHO], th[KAPPA], th[ETA]);
        let (g, bu, by) = (th[GAIN], th[INPUT_OFFSET], th[OUTPUT_OFFSET]);
        let per_sample = 2 * disc.substeps;
        let zoh = disc.interpolation == InputInterpolation::Zoh;
        let h = 1.0 / (disc.substeps as f64 * fs);
        let hh = 0.5 * h;
        let h6 = h * (1.0 / 6.0);
        let sens = jac.is_some();
        ys.clear();
        if let Some(j) = jac.as_deref_mut() {
            j.clear();
        }
        let (mut x, mut v) = (th[X0], th[V0]);
        let mut sx = [0.0; P];
        let mut sv = [0.0; P];
        sx[X0] = 1.0;
        sv[V0] = 1.0;
        let has_s = beta != 0.0 || logs.0;
        let has_d = kappa != 0.0 || logs.1;
        // acceleration and its sensitivity at one stage
        let accel = |x: f64, v: f64, sx: &[f64; P], sv: &[f64; P], ut: f64, da: &mut [f64; P]| {
            let (fx, dfx, lx) = if has_s {
                power_terms(x, rho, logs.0)
            } else {
                (0.0, 0.0, 0.0)
            };
            let (fv, dfv, lv) = if has_d {
                power_terms(v, eta, logs.1)
            } else {
                (0.0, 0.0, 0.0)
            };
            let a = g * (ut + bu) - ((alpha * x + beta * fx) + (delta * v + kappa * fv));
            if sens {
                let ax = -alpha - beta * dfx;
                let av = -delta - kappa * dfv;
                for p in 0..P {
                    da[p] = ax * sx[p] + av * sv[p];
                }
                da[ALPHA] -= x;
                da[DELTA] -= v;
                da[BETA] -= fx;
                da[RHO] -= beta * lx;
                da[KAPPA] -= fv;
                da[ETA] -= kappa * lv;
                da[GAIN] += ut + bu;
                da[INPUT_OFFSET] += g;
            }
            a
        };
        let emit =
            |x: f64, sx: &[f64; P], ys: &mut Vec<f64>, jac: &mut Option<&mut Vec<[f64; P]>>| {
                ys.push(x + by);
                if let Some(j) = jac.as_deref_mut() {
                    let mut row = *sx;
                    row[OUTPUT_OFFSET] += 1.0;
                    j.push(row);
                }
            };
        emit(x, &sx, ys, &mut jac);
        if let Some(w) = vs.as_deref_mut() {
            w.clear();
            w.push(v);
        }
        let mut da1 = [0.0; P];
        let mut da2 = [0.0; P];
        let mut da3 = [0.0; P];
        let mut da4 = [0.0; P];
        let mut s2x = [0.0; P];
        let mut s2v = [0.0; P];
        let mut a1 = accel(x, v, &sx, &sv, fine[0], &mut da1);
        let mut i = 0;
        let n_fine = fine.len();
        while i + 2 < n_fine {
            let boundary = (i + 2) % per_sample == 0;
            // a hold keeps u_k up to the end of its interval (the left limit)
            let (um, u1) = (
                fine[i + 1],
                if zoh && boundary {
                    fine[i + 1]
                } else {
                    fine[i + 2]
                },
            );
            let x2 = x + hh * v;
            let v2 = v + hh * a1;
            if sens {
                for p in 0..P {
                    s2x[p] = sx[p] + hh * sv[p];
                    s2v[p] = sv[p] + hh * da1[p];
                }
            }
            let a2 = accel(x2, v2, &s2x, &s2v, um, &mut da2);
            let x3 = x + hh * v2;
            let v3 = v + hh * a2;
            let mut s3x = [0.0; P];
            let mut s3v = [0.0; P];
            if sens {
                for p in 0..P {
                    s3x[p] = sx[p] + hh * s2v[p];
                    s3v[p] = sv[p] + hh * da2[p];
                }
            }
            let a3 = accel(x3, v3, &s3x, &s3v, um, &mut da3);
            let x4 = x + h * v3;
            let v4 = v + h * a3;
            let mut s4x = [0.0; P];
            let mut s4v = [0.0; P];
            if sens {
                for p in 0..P {
                    s4x[p] = sx[p] + h * s3v[p];
                    s4v[p] = sv[p] + h * da3[p];
                }
            }
            let a4 = accel(x4, v4, &s4x, &s4v, u1, &mut da4);
            let xn = x + h6 * (v + 2.0 * (v2 + v3) + v4);
            let vn = v + h6 * (a1 + 2.0 * (a2 + a3) + a4);
            if sens {
                for p in 0..P {
                    sx[p] += h6 * (sv[p] + 2.0 * (s2v[p] + s3v[p]) + s4v[p]);
                    sv[p] += h6 * (da1[p] + 2.0 * (da2[p] + da3[p]) + da4[p]);
                }
            }
            x = xn;
            v = vn;
            if !(x.is_finite() && v.is_finite()) {
                return false;
            }
            a1 = accel(x, v, &sx, &sv, fine[i + 2], &mut da1);
            i += 2;
            if boundary {
                emit(x, &sx, ys, &mut jac);
                if let Some(w) = vs.as_deref_mut() {
                    w.push(v);
                }
            }
        }
        true
    }

    fn theta_for_tests(rho: f64, eta: f64, kappa: f64) -> [f64; N_TIME_PARAMS] {
        let mut th = [0.0; N_TIME_PARAMS];
        th[ALPHA] = 1.8e5;
        th[DELTA] = 20.0;
        th[BETA] = 7e5;
        th[RHO] = rho;
        th[KAPPA] = kappa;
        th[ETA] = eta;
        th[GAIN] = 1.9e5;
        th[INPUT_OFFSET] = -0.008;
        th[OUTPUT_OFFSET] = 0.003;
        th[X0] = 0.03;
        th[V0] = -40.0;
        th
    }

    fn input_for_tests(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 / 610.0;
                0.1 * (2.0 * std::f64::consts::PI * 60.0 * t).sin()
                    + 0.05 * (2.0 * std::f64::consts::PI * 13.0 * t + 0.3).sin()
            })
            .collect()
    }

    /// The fast path (trajectory, then the sensitivities column by column,
    /// split between threads, powers by exp(μ ln|s|)) against the joint
    /// recurrence with powf: identical for the exact exponents 0, 1, 2,
    /// equal to rounding otherwise.
    #[test]
    fn fast_path_matches_the_reference() {
        let fs = 610.0;
        let u = input_for_tests(3000);
        for (rho, eta, kappa, exact) in [
            (2.0, 0.0, 0.0, true),
            (2.0, 1.0, 0.5, true),
            (1.98, 0.0166, 39.5, false),
            (2.7, 0.4, 3.0, false),
        ] {
            let th = theta_for_tests(rho, eta, kappa);
            for disc in [
                Discretisation::new(InputInterpolation::Cubic, 2).unwrap(),
                Discretisation::new(InputInterpolation::Zoh, 3).unwrap(),
            ] {
                let fine = disc.fine(&u);
                for logs in [(false, false), (true, true)] {
                    let (mut y0, mut j0, mut v0) = (Vec::new(), Vec::new(), Vec::new());
                    assert!(run_reference(
                        &th,
                        &fine,
                        fs,
                        &disc,
                        &mut y0,
                        Some(&mut j0),
                        logs,
                        Some(&mut v0)
                    ));
                    let (mut y1, mut j1, mut v1) = (Vec::new(), Vec::new(), Vec::new());
                    assert!(run(
                        &th,
                        &fine,
                        fs,
                        &disc,
                        &mut y1,
                        Some(&mut j1),
                        logs,
                        Some(&mut v1)
                    ));
                    assert_eq!(y0.len(), u.len());
                    assert_eq!((y1.len(), j1.len(), v1.len()), (u.len(), u.len(), u.len()));
                    let close = |a: &[f64], b: &[f64]| {
                        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
                        let err = a
                            .iter()
                            .zip(b)
                            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                        if exact {
                            assert!(err == 0.0, "{rho} {eta}: {err:e}");
                        } else {
                            assert!(err <= 1e-11 * scale, "{rho} {eta}: {err:e} of {scale:e}");
                        }
                    };
                    close(&y1, &y0);
                    close(&v1, &v0);
                    for p in 0..N_TIME_PARAMS {
                        let c0: Vec<f64> = j0.iter().map(|r| r[p]).collect();
                        let c1: Vec<f64> = j1.iter().map(|r| r[p]).collect();
                        close(&c1, &c0);
                    }
                    // any grouping of the columns gives the same values
                    let mut ys = Vec::new();
                    let mut st = Vec::new();
                    assert!(trajectory(
                        &th,
                        &fine,
                        fs,
                        &disc,
                        logs,
                        &mut ys,
                        None,
                        Some(&mut st)
                    ));
                    let cols = [KAPPA, X0, ALPHA, ETA, OUTPUT_OFFSET];
                    let mut part = Vec::new();
                    sensitivities(&th, &fine, fs, &disc, logs, &st, &cols, &mut part);
                    for (k, row) in part.chunks_exact(cols.len()).enumerate() {
                        for (q, &p) in cols.iter().enumerate() {
                            assert_eq!(row[q].to_bits(), j1[k][p].to_bits());
                        }
                    }
                }
            }
        }
    }

    /// The Jacobian of the least-squares problem from the trajectory kept by
    /// the last residual evaluation is the one computed afresh, bit for bit.
    #[test]
    fn reused_trajectory_gives_the_same_jacobian() {
        let fs = 610.0;
        let u = input_for_tests(10_000);
        let disc = Discretisation::new(InputInterpolation::Cubic, 2).unwrap();
        let fine = disc.fine(&u);
        let th = theta_for_tests(1.98, 0.0166, 39.5);
        let mut y = Vec::new();
        assert!(run(
            &th,
            &fine,
            fs,
            &disc,
            &mut y,
            None,
            (false, false),
            None
        ));
        for (k, v) in y.iter_mut().enumerate() {
            *v += 1e-4 * ((k as f64) * 0.37).sin();
        }
        let free: Vec<usize> = (0..N_TIME_PARAMS).collect();
        let scale: Vec<f64> = th.iter().map(|v| v.abs().max(1.0)).collect();
        let problem = || OutputError {
            fine: &fine,
            y: &y,
            fs,
            disc,
            base: th,
            free: &free,
            scale: scale.clone(),
            logs: (true, true),
            last: Default::default(),
            cancel: crate::cancel::Cancel::NEVER,
        };
        let z: Vec<f64> = th.iter().zip(&scale).map(|(t, s)| t / s * 1.0001).collect();
        let z2: Vec<f64> = z.iter().map(|v| v * 0.9999).collect();
        let fresh = problem().residuals_and_jacobian(&z).unwrap();
        let p = problem();
        let r = p.residuals(&z2).unwrap();
        assert_ne!(r, fresh.0);
        let r = p.residuals(&z).unwrap();
        let reused = p.residuals_and_jacobian(&z).unwrap();
        assert_eq!(r, fresh.0);
        assert_eq!(reused, fresh);
        // a different point after it: computed afresh
        let again = p.residuals_and_jacobian(&z2).unwrap();
        assert_eq!(again, problem().residuals_and_jacobian(&z2).unwrap());
    }

    #[test]
    fn power_terms_are_safe_at_zero() {
        for mu in [0.0, 0.5, 1.0, 2.0, 3.7] {
            let (f, df, l) = power_terms(0.0, mu, true);
            assert_eq!(f, 0.0);
            assert_eq!(l, 0.0);
            assert_eq!(df, if mu == 0.0 { 1.0 } else { 0.0 });
            let (f, df, l) = power_terms(-0.5, mu, true);
            assert!((f + 0.5f64.powf(mu + 1.0)).abs() < 1e-15);
            assert!((df - (mu + 1.0) * 0.5f64.powf(mu)).abs() < 1e-15);
            assert!((l - f * 0.5f64.ln()).abs() < 1e-15);
        }
    }
}
