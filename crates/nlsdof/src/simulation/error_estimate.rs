//! Integration-error estimate of a simulated record, by step doubling on
//! the whole record (issue 26, item 4). One implementation for
//! `nlsdof simulate` and Python's `Model.simulate`.
//!
//! ## What is estimated
//!
//! The error of the simulated displacement against the exact solution of
//! Eq 32 driven by the record read as cubics through the samples (the
//! reading of [`RecordMethod::Rk4Cubic`], 4th-order accurate for a smooth
//! input), as `max_k |x_k − x(t_k)| / max_k |x(t_k)|` over every sample.
//!
//! ## Why step doubling, and why on the whole record
//!
//! The earlier check compared the run with RK4 at half the step on the
//! first 4 Mi samples and reported the difference as the error. That
//! difference is `(1 − 2^{−p})` of the error when the scheme converges
//! with order `p`: 15/16 for RK4 on a smooth law, but only about half for
//! a law that is not smooth where the state crosses zero — damping
//! `c_e x'|x'|^η` with η ∈ (−1, 0) (force `∝ |x'|^{1+η}`, not Lipschitz at
//! a velocity reversal), stiffness `k_r x|x|^ρ` with ρ ∈ (−1, 0), and
//! Coulomb friction (η = −1). There RK4 loses order in the step that holds
//! the reversal or zero crossing: the local error of that step is
//! `O(h^{2+e})` for the exponent `e`, and with a bounded number of
//! crossings per unit time the global error is `O(h^{2+e})`, not `O(h⁴)`.
//! A local smoothness assumption (a Taylor or embedded-pair error model)
//! does not see this; the difference between two whole runs does, because
//! each run crosses zero on its own grid. The difference is scaled by the
//! Richardson factor `2^p/(2^p − 1)` with the order `p` the law allows
//! ([`convergence_order`]), so that it bounds the error of the coarser run
//! rather than measuring `(1 − 2^{−p})` of it. A later error in a long
//! record (a sweep that reaches resonance late) is seen because every
//! sample is compared.
//!
//! ## Other methods
//!
//! For a method other than the default (RK4 driven by the samples, or
//! Dormand–Prince on the input read as linear between samples) the
//! estimate is `max|x − y| + max|x_c − y| / (2^p − 1)`, relative to
//! `max |y|`, where `x_c` is the default run (`h = 1/(2 f_s)`) and `y` the
//! same at half the step: by the triangle inequality the error of `x` is
//! at most its distance to `y` plus the error of `y`, and the latter is
//! the step-doubling estimate of the finer run. So the estimate includes
//! what reading the input as linear (or as "the samples" of RK4 with two
//! samples per step) costs against the cubic reading, as well as the step
//! error of the method itself. For the default method `x = x_c` and the
//! two terms add up to `2^p/(2^p − 1) · max|x − y|`.
//!
//! ## Cost
//!
//! One run at half the default step: about twice the work of the default
//! run; three times for another method (the default run as well).

use super::{simulate_upsampled, RecordMethod, Sample, State, Upsampling, DEFAULT_UPSAMPLING};
use crate::cancel::Cancel;
use crate::error::SimulationError;
use crate::model::{AsNormalised, NormalisedModel};

/// Estimated integration error (relative to `max |x|`) above which
/// `nlsdof simulate` and Python's `Model.simulate` warn.
pub const INTEGRATION_WARN: f64 = 1e-3;

/// An integration-error estimate of a simulated record
/// ([`record_error_estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegrationError {
    /// Estimated `max |x − x_exact| / max |x_exact|` over the record.
    pub estimate: f64,
    /// Samples compared: the whole record.
    pub samples: usize,
    /// Convergence order `p` assumed for the Richardson factor
    /// ([`convergence_order`]).
    pub order: f64,
}

impl IntegrationError {
    /// `true` when the estimate is above [`INTEGRATION_WARN`] (or not a
    /// number).
    pub fn is_warned(&self) -> bool {
        !(self.estimate <= INTEGRATION_WARN)
    }
}

/// The order `p` with which RK4 converges on the model's law: 4 when every
/// nonlinear term is smooth (absent, or an exponent that is an even integer:
/// `x|x|^0 = x`, `x|x|² = x³`), else `2 + e` for the smallest such exponent
/// `e` (clamped to [1, 4]): the term `x|x|^e` (or `x'|x'|^e`) has a
/// `(1 + e)`-th power singularity at the zero crossing, and the step that
/// holds the crossing makes a local error `O(h^{2+e})`. Coulomb friction
/// (η = −1, events located but the input linear between the fine samples)
/// gets 1, the most conservative value.
pub fn convergence_order(model: &NormalisedModel) -> f64 {
    let smooth = |e: f64| e >= 0.0 && e.fract() == 0.0 && (e as u64) % 2 == 0;
    let mut p: f64 = 4.0;
    for (coefficient, e) in [(model.beta, model.rho), (model.kappa, model.eta)] {
        if coefficient != 0.0 && !smooth(e) {
            p = p.min((2.0 + e).clamp(1.0, 4.0));
        }
    }
    p
}

/// The step-doubling estimate from a relative difference already measured
/// (`max |x_h − x_{h/2}| / max |x_{h/2}|` over `samples` samples, by a
/// caller with its own scheme): the difference times the Richardson factor
/// `2^p/(2^p − 1)` of the law's order ([`convergence_order`]).
pub fn step_doubling_error(
    model: &NormalisedModel,
    relative_difference: f64,
    samples: usize,
) -> IntegrationError {
    let order = convergence_order(model);
    IntegrationError {
        estimate: relative_difference * order.exp2() / (order.exp2() - 1.0),
        samples,
        order,
    }
}

/// Estimates the integration error of `x`, the displacement at every sample
/// of a record simulated by [`super::simulate_record`] with `method` (the
/// same `values`, `grid = (gain, t0, fs)` and `initial`), by step doubling
/// on the whole record (see the module docs). `x` may be shorter than the
/// record (its first samples are checked); fewer than 2 samples give 0.
pub fn record_error_estimate(
    model: &(impl AsNormalised + ?Sized),
    values: &[f64],
    grid: (f64, f64, f64),
    method: RecordMethod,
    initial: State,
    x: &[f64],
) -> Result<IntegrationError, SimulationError> {
    record_error_estimate_cancellable(model, values, grid, method, initial, x, Cancel::NEVER)
}

/// As [`record_error_estimate`], polling `cancel` every 2^16 samples of its
/// runs ([`SimulationError::Interrupted`] once it is set, [`crate::cancel`]).
pub fn record_error_estimate_cancellable(
    model: &(impl AsNormalised + ?Sized),
    values: &[f64],
    grid: (f64, f64, f64),
    method: RecordMethod,
    initial: State,
    x: &[f64],
    cancel: Cancel,
) -> Result<IntegrationError, SimulationError> {
    let model = &model.as_normalised()?;
    let order = convergence_order(model);
    let n = x.len().min(values.len());
    let mut result = IntegrationError {
        estimate: 0.0,
        samples: n,
        order,
    };
    if n < 2 {
        return Ok(result);
    }
    let values = &values[..n];
    // the default run x_c (the run itself for the default method)
    let own;
    let xc: &[f64] = if method == RecordMethod::Rk4Cubic {
        &x[..n]
    } else {
        let mut v = Vec::with_capacity(n);
        let opts = Upsampling {
            factor: DEFAULT_UPSAMPLING,
            initial,
            cancel,
        };
        simulate_upsampled(model, values, grid, &opts, &mut |s: Sample| v.push(s.x))?;
        own = v;
        &own
    };
    // y: the default reading at half the step, compared as it streams
    let (mut d_run, mut d_default, mut scale) = (0.0f64, 0.0f64, 0.0f64);
    let opts = Upsampling {
        factor: 2 * DEFAULT_UPSAMPLING,
        initial,
        cancel,
    };
    simulate_upsampled(model, values, grid, &opts, &mut |s: Sample| {
        if s.index < n {
            d_run = d_run.max((x[s.index] - s.x).abs());
            d_default = d_default.max((xc[s.index] - s.x).abs());
            scale = scale.max(s.x.abs());
        }
    })?;
    let diff = d_run + d_default / (order.exp2() - 1.0);
    result.estimate = if scale > 0.0 {
        diff / scale
    } else if diff > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    Ok(result)
}

/// The warning of `nlsdof simulate` (after `nlsdof: warning: `) and of
/// Python's `Model.simulate` (a `RuntimeWarning`), the same text for both,
/// when the estimate is above [`INTEGRATION_WARN`]; `None` otherwise. The
/// advice depends on how `method` reads the input between samples.
pub fn integration_warning(error: &IntegrationError, method: RecordMethod) -> Option<String> {
    if !error.is_warned() {
        return None;
    }
    let what = match method {
        RecordMethod::DormandPrince { .. } | RecordMethod::Rk4 { samples_per_step: 1 } => {
            "the input is taken as linear between samples: use the default method (rk4 with cubic input, no samples per step given), or sample the input faster"
        }
        RecordMethod::Rk4 { .. } => {
            "use the default method (rk4 with h = 1/(2 fs) and cubic input, no samples per step given), or sample the input faster"
        }
        RecordMethod::Rk4Cubic => {
            "sample the input faster (at least 20 samples per cycle of the highest frequency, more for very light damping or for a law that is not smooth at zero: exponents below 2, Coulomb friction)"
        }
    };
    Some(format!(
        "estimated integration error {:.1e} of max |x| is above {INTEGRATION_WARN:e}: {what}",
        error.estimate
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(rho: f64, eta: f64) -> NormalisedModel {
        NormalisedModel {
            alpha: 1.0,
            delta: 0.1,
            beta: 1.0,
            rho,
            kappa: 1.0,
            eta,
        }
    }

    #[test]
    fn the_order_follows_the_smoothness_of_the_law() {
        assert_eq!(convergence_order(&model(2.0, 0.0)), 4.0);
        assert_eq!(convergence_order(&model(2.0, 4.0)), 4.0);
        assert_eq!(convergence_order(&model(1.0, 0.0)), 3.0);
        assert_eq!(convergence_order(&model(2.0, -0.133)), 2.0 - 0.133);
        assert_eq!(convergence_order(&model(-0.5, 2.0)), 1.5);
        assert_eq!(convergence_order(&model(2.0, -1.0)), 1.0);
        assert_eq!(convergence_order(&model(3.5, 2.5)), 4.0);
        // an absent term does not count
        let linear = NormalisedModel {
            beta: 0.0,
            kappa: 0.0,
            ..model(-0.5, -1.0)
        };
        assert_eq!(convergence_order(&linear), 4.0);
    }

    #[test]
    fn the_warning_is_given_above_the_level_only() {
        let e = |estimate| IntegrationError {
            estimate,
            samples: 10,
            order: 4.0,
        };
        assert!(integration_warning(&e(9e-4), RecordMethod::Rk4Cubic).is_none());
        let w = integration_warning(&e(2.1e-3), RecordMethod::Rk4Cubic).unwrap();
        assert!(w.starts_with("estimated integration error 2.1e-3 of max |x| is above 1e-3"));
        assert!(integration_warning(&e(f64::NAN), RecordMethod::Rk4Cubic).is_some());
    }
}
