//! Time-domain simulation of the state-space model, paper §4.5, Eq 32:
//!
//! ```text
//! x' = y
//! y' = −δ y − α x − (k_{ρ+1}/m) x|x|^ρ − (c_{η+1}/m) y|y|^η + γ(t)       (Eq 32)
//!    = u(t) − (c x' + k x + c_e x'|x'|^η + k_r x|x|^ρ) / m,   u ≡ γ
//! ```
//!
//! `u(t) = γ(t)` is the input acceleration of Eq 29 (m γ is the applied
//! force). For base excitation in relative coordinates `u = −ÿ_base` (see
//! [`crate::excitation`] and [`SampledInput::with_gain`]).
//!
//! The paper (§4.1) could not afford this: its longest record, 8 752 000
//! samples at 2048 Hz, had to be subsampled to 64 Hz and still took over
//! 40 minutes per simulation. Here one pass is a fraction of a second.
//!
//! ## Integrators
//!
//! * **Classical RK4, fixed step, driven by the samples** ([`Method::Rk4`]),
//!   streaming: the state (x, v) is the only memory besides the input and
//!   whatever the output sink keeps; optional output decimation.
//!   - `samples_per_step = 1`: step `h = t_{k+1} − t_k`; the stage inputs
//!     are `u_k`, the linear-interpolation mid value `(u_k + u_{k+1})/2`
//!     (stages 2 and 3) and `u_{k+1}`. The input is therefore treated as
//!     **piecewise linear**, and RK4 is 4th-order accurate for that input
//!     (the kink at each sample lies on a step boundary). Works with
//!     non-uniform time columns.
//!   - `samples_per_step = 2` (default for uniform sampling): `h = 2/fs`,
//!     stage inputs `u_k`, `u_{k+1}` (exactly at the half step), `u_{k+2}`.
//!     No interpolation at all: RK4 is 4th-order accurate for *any smooth
//!     input through the samples* (the natural reading of a band-limited
//!     record), at half the cost per sample. The output at the odd
//!     (mid-step) sample is the cubic Hermite interpolant of
//!     `(x, v, a)` at the step ends (`x_mid = (x₀+x₁)/2 + h (v₀−v₁)/8`,
//!     `v_mid = (v₀+v₁)/2 + h (a₀−a₁)/8`), O(h⁴) like the method.
//! * **RK4 on a cubic-upsampled input** ([`simulate_upsampled`]): a
//!   uniformly sampled record upsampled by cubics, two fine samples per
//!   step, in chunks; the state at every original sample.
//! * **Dormand–Prince 5(4)** with embedded error control and the 4th-order
//!   continuous extension ([`Method::DormandPrince`]), the accuracy
//!   reference. It treats the input as piecewise linear and **restarts at
//!   every sample**: no step crosses a sample time, because the kink of the
//!   interpolated input at a sample is invisible to the error estimator
//!   (the first-same-as-last stage is still valid across the boundary since
//!   the input is continuous there). Error norm
//!   `sqrt(½ Σ (e_i / (atol_i + rtol·max|y_i|))²)` with `atol_x = atol`,
//!   `atol_v = atol · ω_n`.
//!
//! ## Integration error
//!
//! [`record_error_estimate`] estimates the error of a simulated record by
//! step doubling on the whole record, scaled by the Richardson factor of
//! the order RK4 keeps on the law ([`convergence_order`]: below 4 for laws
//! not smooth at zero); `nlsdof simulate` and Python's `Model.simulate`
//! both report it and warn above [`INTEGRATION_WARN`] with
//! [`integration_warning`]'s text.
//!
//! ## Friction and non-smooth damping (η < 0)
//!
//! * `η = −1` (Coulomb friction `c_f sgn(x')`, Eq 27): **event handling**,
//!   no regularisation. In *slip* with sign `s` the friction force per unit
//!   mass is the constant `κ s`, so the right-hand side is smooth and the
//!   integrator runs unchanged. When `x'` changes sign inside a step the
//!   zero crossing is located (Illinois regula falsi on the RK4 step length,
//!   or on the DOPRI dense output) and the step is cut there. At `x' = 0`
//!   the mass *sticks* if the remaining force `|u − α x − β x|x|^ρ| ≤ κ`
//!   (static = kinetic friction), otherwise it slips in the direction of
//!   that force. While stuck the state is frozen and the breakaway time
//!   (where `|u − restoring| = κ`) is located the same way. Friction
//!   models always use one RK4 step per sample (the sub-steps between
//!   events need the interpolated input).
//! * `−1 < η < 0`: the force `κ sgn(x')|x'|^{1+η}` is continuous (zero at
//!   rest, so no sticking) but not Lipschitz at `x' = 0`; it is integrated
//!   directly. The local error is larger in the step containing a velocity
//!   reversal (order is lost there only); convergence is still observed.
//! * `η < −1`: the damping force is unbounded as `x' → 0`; a mass at rest
//!   could never move again. Rejected with
//!   [`SimulationError::SingularDamping`].
//!
//! ## Speed
//!
//! The exponent kind of each term is resolved once and every loop is
//! compiled per combination (integer exponents: multiplications only; real
//! exponents: a table-driven power `law`). With real exponents the power
//! of the *velocity* sits on the critical dependency chain of every RK4
//! stage, so the default loop (uniform input, two samples per step)
//! evaluates the powers at the middle and end of the step after next at
//! Taylor-predicted states, where their latency overlaps a whole step, and
//! each stage only continues them with a 4-term binomial series
//! (`|y|^μ = |ŷ|^μ (1+ε)^μ`, `|ε| ≲ 1e-4`, exact evaluation when `ε` is
//! not small, e.g. near a velocity reversal). On x86-64 CPUs with FMA/AVX2
//! that loop is compiled a second time with fused multiply–add and chosen
//! at run time. Results agree with direct evaluation to rounding (tested).
//!
//! A non-finite state (e.g. a softening model escaping its potential well)
//! stops the run with [`SimulationError::Diverged`]: numbers are never
//! silently produced.

pub(crate) mod coulomb;
mod dopri;
mod error_estimate;
pub(crate) mod law;
pub(crate) mod rk4;
pub(crate) mod rk4_step;
mod upsampled;

pub use crate::error::SimulationError;
pub use error_estimate::{
    convergence_order, integration_warning, record_error_estimate,
    record_error_estimate_cancellable, step_doubling_error, IntegrationError, INTEGRATION_WARN,
};
pub use upsampled::{
    rk4_cubic_error_estimate, simulate_record, simulate_record_cancellable, simulate_upsampled,
    RecordMethod, Upsampling, DEFAULT_UPSAMPLING,
};

use crate::excitation::{Excitation, SampledInput};
use crate::model::AsNormalised;
use crate::model::NormalisedModel;

/// Displacement (m) and velocity (m/s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct State {
    pub x: f64,
    pub v: f64,
}

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Classical fixed-step RK4; `samples_per_step` is 1 or 2 (see the
    /// module docs).
    Rk4 { samples_per_step: usize },
    /// Adaptive Dormand–Prince 5(4), restarted at every sample.
    DormandPrince { rtol: f64, atol: f64 },
}

impl Default for Method {
    fn default() -> Self {
        Method::Rk4 {
            samples_per_step: 2,
        }
    }
}

impl Method {
    /// Dormand–Prince with the reference tolerances `rtol = 1e-10`,
    /// `atol = 1e-13` (m; m/s scaled by ω_n).
    pub fn reference() -> Self {
        Method::DormandPrince {
            rtol: 1e-10,
            atol: 1e-13,
        }
    }
}

/// Simulation options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    pub method: Method,
    /// State at the first sample time.
    pub initial: State,
    /// Emit every `decimation`-th sample (indices 0, d, 2d, …); ≥ 1.
    pub decimation: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            method: Method::default(),
            initial: State::default(),
            decimation: 1,
        }
    }
}

/// One output sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Index of the input sample (or output time) this state belongs to.
    pub index: usize,
    /// Time, s.
    pub t: f64,
    /// Input acceleration u(t) = γ(t), m/s².
    pub u: f64,
    /// Displacement, m.
    pub x: f64,
    /// Velocity, m/s.
    pub v: f64,
}

/// Cost and end state of a run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Summary {
    /// Input samples (or output times) covered.
    pub samples: usize,
    /// Samples passed to the sink.
    pub outputs: usize,
    /// Accepted integration steps.
    pub steps: u64,
    /// Rejected steps (adaptive method).
    pub rejected_steps: u64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Stick/slip events (Coulomb friction).
    pub events: u64,
    /// RK4 samples per step actually used (0 for Dormand–Prince).
    pub samples_per_step: usize,
    pub final_state: State,
    pub final_time: f64,
}

/// Checks the model for simulation: valid parameters and η ≥ −1 when a
/// damping term is present.
pub fn check_model(model: &NormalisedModel) -> Result<(), SimulationError> {
    model.validate()?;
    if model.kappa != 0.0 && model.eta < -1.0 {
        return Err(SimulationError::SingularDamping { eta: model.eta });
    }
    Ok(())
}

/// `true` when the damping term is Coulomb friction (κ > 0, η = −1).
pub(crate) fn is_coulomb(model: &NormalisedModel) -> bool {
    model.kappa != 0.0 && model.eta == -1.0
}

fn check_options(opts: &Options) -> Result<(), SimulationError> {
    if opts.decimation == 0 {
        return Err(SimulationError::InvalidOption {
            name: "decimation",
            value: 0.0,
            reason: "must be >= 1",
        });
    }
    for (name, v) in [("initial x", opts.initial.x), ("initial v", opts.initial.v)] {
        if !v.is_finite() {
            return Err(SimulationError::InvalidOption {
                name,
                value: v,
                reason: "not a finite number",
            });
        }
    }
    match opts.method {
        Method::Rk4 { samples_per_step } if !(1..=2).contains(&samples_per_step) => {
            Err(SimulationError::InvalidOption {
                name: "samples per step",
                value: samples_per_step as f64,
                reason: "must be 1 or 2",
            })
        }
        Method::DormandPrince { rtol, atol } => {
            if !(rtol.is_finite() && rtol > 0.0) {
                return Err(SimulationError::InvalidOption {
                    name: "rtol",
                    value: rtol,
                    reason: "must be > 0",
                });
            }
            if !(atol.is_finite() && atol > 0.0) {
                return Err(SimulationError::InvalidOption {
                    name: "atol",
                    value: atol,
                    reason: "must be > 0",
                });
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// Simulates Eq 32 driven by a recorded input, streaming every
/// `opts.decimation`-th state to `sink` (the state at sample 0 is the
/// initial state). Memory is O(1) besides the input and what `sink` keeps.
pub fn simulate<F: FnMut(Sample)>(
    model: &(impl AsNormalised + ?Sized),
    input: &SampledInput<'_>,
    opts: &Options,
    sink: F,
) -> Result<Summary, SimulationError> {
    simulate_cancellable(model, input, opts, crate::cancel::Cancel::NEVER, sink)
}

/// As [`simulate`], polling `cancel` ([`Method::DormandPrince`] every 4096
/// samples, [`Method::Rk4`] every 65,536) and then ending with
/// [`SimulationError::Interrupted`] ([`crate::cancel`]); the samples
/// already given to `sink` are those of the run so far. The results of a
/// run that is not cancelled do not depend on it.
pub fn simulate_cancellable<F: FnMut(Sample)>(
    model: &(impl AsNormalised + ?Sized),
    input: &SampledInput<'_>,
    opts: &Options,
    cancel: crate::cancel::Cancel,
    sink: F,
) -> Result<Summary, SimulationError> {
    let model = &model.as_normalised()?;
    check_model(model)?;
    check_options(opts)?;
    let summary = match opts.method {
        Method::Rk4 { samples_per_step } => {
            rk4::simulate_sampled(model, input, samples_per_step, opts, cancel, sink)
        }
        Method::DormandPrince { rtol, atol } => {
            dopri::simulate_sampled(model, input, rtol, atol, opts, cancel, sink)
        }
    }?;
    cancel.check()?;
    Ok(summary)
}

/// Output arrays of [`simulate_to_vec`]: state at sample indices
/// `0, d, 2d, …` (d = decimation).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    pub index: Vec<usize>,
    pub t: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
}

/// [`simulate`] collecting x and v (and their times) into vectors sized
/// exactly once.
pub fn simulate_to_vec(
    model: &(impl AsNormalised + ?Sized),
    input: &SampledInput<'_>,
    opts: &Options,
) -> Result<(Trajectory, Summary), SimulationError> {
    let model = &model.as_normalised()?;
    let n = input.len().div_ceil(opts.decimation.max(1));
    let mut tr = Trajectory {
        index: Vec::with_capacity(n),
        t: Vec::with_capacity(n),
        x: Vec::with_capacity(n),
        v: Vec::with_capacity(n),
    };
    let s = simulate(model, input, opts, |s| {
        tr.index.push(s.index);
        tr.t.push(s.t);
        tr.x.push(s.x);
        tr.v.push(s.v);
    })?;
    Ok((tr, s))
}

/// Only x and v into caller-provided vectors (cleared first): the
/// smallest-memory way to keep a whole response.
pub fn simulate_into(
    model: &(impl AsNormalised + ?Sized),
    input: &SampledInput<'_>,
    opts: &Options,
    x: &mut Vec<f64>,
    v: &mut Vec<f64>,
) -> Result<Summary, SimulationError> {
    let model = &model.as_normalised()?;
    x.clear();
    v.clear();
    let n = input.len().div_ceil(opts.decimation.max(1));
    x.reserve_exact(n);
    v.reserve_exact(n);
    simulate(model, input, opts, |s| {
        x.push(s.x);
        v.push(s.v);
    })
}

/// Simulates Eq 32 driven by an analytic input `exc`, with output times
/// `t_k = t0 + k·dt`, `k = 0 .. n−1`. RK4 takes one step of `dt` per
/// output interval and evaluates `exc` exactly at the stage times;
/// Dormand–Prince restarts at each output time. `samples_per_step` is
/// ignored.
pub fn simulate_excitation<E: Excitation + ?Sized, F: FnMut(Sample)>(
    model: &NormalisedModel,
    exc: &E,
    t0: f64,
    dt: f64,
    n: usize,
    opts: &Options,
    sink: F,
) -> Result<Summary, SimulationError> {
    check_model(model)?;
    check_options(opts)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SimulationError::InvalidOption {
            name: "dt",
            value: dt,
            reason: "must be > 0",
        });
    }
    if !t0.is_finite() {
        return Err(SimulationError::NonFiniteTime {
            index: 0,
            value: t0,
        });
    }
    if n < 2 {
        return Err(SimulationError::TooFewSamples { len: n, min: 2 });
    }
    match opts.method {
        Method::Rk4 { .. } => rk4::simulate_excitation(model, exc, t0, dt, n, opts, sink),
        Method::DormandPrince { rtol, atol } => {
            dopri::simulate_excitation(model, exc, t0, dt, n, rtol, atol, opts, sink)
        }
    }
}

/// Mechanical energy per unit mass,
/// `E = v²/2 + α x²/2 + β |x|^{ρ+2}/(ρ+2)` (the potential of the
/// restoring force `α x + β x|x|^ρ`; needs ρ ≠ −2).
pub fn energy(model: &NormalisedModel, s: State) -> f64 {
    let mut e = 0.5 * s.v * s.v + 0.5 * model.alpha * s.x * s.x;
    if model.beta != 0.0 && s.x != 0.0 {
        e += model.beta * s.x.abs().powf(model.rho + 2.0) / (model.rho + 2.0);
    }
    e
}

/// Dissipated power per unit mass `δ v² + κ |v|^{η+2}`.
pub fn dissipated_power(model: &NormalisedModel, v: f64) -> f64 {
    let mut p = model.delta * v * v;
    if model.kappa != 0.0 && v != 0.0 {
        p += model.kappa * v.abs().powf(model.eta + 2.0);
    }
    p
}
