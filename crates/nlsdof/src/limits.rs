//! The size limits of every size argument, each with its reason: one place,
//! checked by the library entry points, so the CLI and Python refuse the
//! same inputs with the same line (issue 30: `decay --bins 1000000000` ran
//! until killed; `frf --harmonics 64 --steps 5000`, `fit --phase-resonance`
//! on 1e7 rows and `linear-id` on 1e7 rows ran for minutes without a word).
//!
//! | limit | value | reason |
//! |---|---|---|
//! | [`DECAY_BINS`] | 1,000 | amplitude bins of a free decay |
//! | [`MULTI_HARMONIC_WORK`] | 3e8 | steps × levels × H³ of a multi-harmonic sweep |
//! | [`PHASE_RESONANCE_POINTS`] | 10,000 | phase-resonance points (one per level) |
//! | [`FRF_LINES`] | 1,000,000 | FRF lines fitted by vector fitting |
//!
//! Other limits stay next to what they guard, with their reasons:
//! `stepped_sine::MAX_STEPS`, the signal generators' sample count, the
//! readers' file sizes.

use thiserror::Error;

/// A size limit: what is limited, the largest accepted value, and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    pub what: &'static str,
    pub max: f64,
    pub reason: &'static str,
}

/// A size beyond its [`Limit`].
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{what} = {value} is above the limit of {max}: {reason}")]
pub struct LimitError {
    pub what: &'static str,
    pub value: f64,
    pub max: f64,
    pub reason: &'static str,
}

impl Limit {
    /// `Ok` if `value` is within the limit.
    pub fn check(&self, value: f64) -> Result<(), LimitError> {
        if value <= self.max {
            Ok(())
        } else {
            Err(LimitError {
                what: self.what,
                value,
                max: self.max,
                reason: self.reason,
            })
        }
    }
}

/// Amplitude bins of a free-decay backbone.
pub const DECAY_BINS: Limit = Limit {
    what: "amplitude bins",
    max: 1000.0,
    reason: "each bin averages the cycles whose envelope falls in it; over two decades of amplitude 1,000 bins are 0.5 % apart, finer than any record's envelope",
};

/// Work of a multi-harmonic sweep: steps × levels × H³ (a Newton step
/// solves a dense system of 2H+1 unknowns per harmonic pair).
pub const MULTI_HARMONIC_WORK: Limit = Limit {
    what: "steps x levels x H^3",
    max: 3.0e8,
    reason: "about a minute of continuation on 2 cores (measured 1.7e-7 s per unit: 200 steps at H = 64 take 8.9 s); use fewer steps, levels or harmonics",
};

/// Phase-resonance points (one per level).
pub const PHASE_RESONANCE_POINTS: Limit = Limit {
    what: "phase-resonance points",
    max: 10_000.0,
    reason: "a phase-resonance test has one point per level, tens in practice; is this a swept curve (fit it without --phase-resonance)?",
};

/// FRF lines fitted by vector fitting.
pub const FRF_LINES: Limit = Limit {
    what: "FRF lines",
    max: 1.0e6,
    reason: "each iteration costs lines x poles^2 (1e6 lines of one mode take about 1 s); select the band of the mode (--f-min/--f-max) or decimate the FRF",
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_limit_admits_its_maximum_and_names_itself_beyond() {
        assert!(DECAY_BINS.check(1000.0).is_ok());
        let e = DECAY_BINS.check(1e9).unwrap_err();
        assert_eq!(e.value, 1e9);
        assert!(e
            .to_string()
            .starts_with("amplitude bins = 1000000000 is above the limit of 1000: "));
    }
}
