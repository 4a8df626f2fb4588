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
    #[error("frequencies must be strictly increasing: element {index} ({value} rad/s) does not exceed the previous one ({previous} rad/s)")]
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
    #[error("harmonic-balance equation could not be evaluated (overflow) at amplitude {amplitude} m, frequency {omega} rad/s: parameters out of representable range")]
    Overflow { amplitude: f64, omega: f64 },
    #[error("{what} did not converge after {iterations} iterations (last residual {residual:e})")]
    NoConvergence {
        what: &'static str,
        iterations: usize,
        residual: f64,
    },
}
