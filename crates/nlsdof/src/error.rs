//! Typed errors of the core library. Every variant carries the offending
//! value so a caller (e.g. the CLI) can print one precise line.

use thiserror::Error;

/// Invalid model or input parameter.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParameterError {
    #[error("{name} = {value} is not a finite number")]
    NotFinite { name: &'static str, value: f64 },
    #[error("{name} = {value} must be > 0")]
    NotPositive { name: &'static str, value: f64 },
    #[error("{name} = {value} must be >= 0")]
    Negative { name: &'static str, value: f64 },
    #[error(
        "exponent {name} = {value} must be > -3 (the equivalent coefficient, Eq 8, diverges at -3)"
    )]
    ExponentTooSmall { name: &'static str, value: f64 },
    #[error("exponent {value} is not an even integer > -3 (Eq 17)")]
    NotEvenExponent { value: i64 },
    #[error("exponent {value} is not an odd integer > -3 (Eq 25)")]
    NotOddExponent { value: i64 },
    #[error("frequency range [{min}, {max}] is invalid: need 0 < min < max, both finite")]
    InvalidRange { min: f64, max: f64 },
    #[error("frequencies must be strictly increasing: element {index} ({value_hz} Hz, {value} rad/s) does not exceed the previous one ({previous_hz} Hz, {previous} rad/s)", value_hz = .value / std::f64::consts::TAU, previous_hz = .previous / std::f64::consts::TAU)]
    NotIncreasing {
        index: usize,
        value: f64,
        previous: f64,
    },
    #[error("{name} is empty")]
    Empty { name: &'static str },
}

/// A numerical procedure could not produce a trustworthy answer.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SolveError {
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    #[error("harmonic-balance equation could not be evaluated (overflow) at amplitude {amplitude} m, frequency {omega_hz} Hz ({omega} rad/s): parameters out of representable range", omega_hz = .omega / std::f64::consts::TAU)]
    Overflow { amplitude: f64, omega: f64 },
    #[error("{what} did not converge after {iterations} iterations (last residual {residual:e})")]
    NoConvergence {
        what: &'static str,
        iterations: usize,
        residual: f64,
    },
}

/// Bad simulation input or options, or a simulation that cannot produce a
/// trustworthy answer: the error of [`crate::excitation`],
/// [`crate::simulation`] and the rig [`crate::stepped_sine`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimulationError {
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    #[error("input signal is empty")]
    EmptyInput,
    #[error("input signal has {len} sample(s); at least {min} are needed")]
    TooFewSamples { len: usize, min: usize },
    #[error("input sample {index} = {value} is not a finite number")]
    NonFiniteSample { index: usize, value: f64 },
    #[error("time t[{index}] = {value} is not a finite number")]
    NonFiniteTime { index: usize, value: f64 },
    #[error("time is not strictly increasing: t[{index}] = {t} s follows {previous} s")]
    NonMonotonicTime { index: usize, t: f64, previous: f64 },
    #[error("sampling frequency fs = {fs} Hz must be finite and > 0")]
    NonPositiveFs { fs: f64 },
    #[error("{times} time values but {samples} samples: the two columns must have equal length")]
    LengthMismatch { times: usize, samples: usize },
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("{samples_per_step} samples per RK4 step needs uniformly sampled input (use 1 for a time column with uneven steps)")]
    StrideNeedsUniformSampling { samples_per_step: usize },
    #[error("damping exponent eta = {eta} < -1: the force c_e v|v|^eta is unbounded at v = 0 (the mass would stick for ever); not simulated")]
    SingularDamping { eta: f64 },
    #[error("the response became non-finite at t = {t} s (x = {x}, v = {v}): the model diverges for this input")]
    Diverged { t: f64, x: f64, v: f64 },
    #[error("adaptive step size fell to {h:e} s at t = {t} s (tolerance too tight or non-smooth right-hand side)")]
    StepSizeUnderflow { t: f64, h: f64 },
    #[error("more than {limit} stick/slip events inside one step at t = {t} s (chattering)")]
    EventOverflow { t: f64, limit: usize },
    /// Cancelled through its [`crate::cancel::Cancel`] flag: no result.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}
