//! Profile-likelihood intervals of the exponents from the **output-error**
//! objective the fit minimised (Eq 31, or the measured-branch output error
//! of [`super::identify()`] with its jump penalties, plus the phase
//! residuals when phase is fitted): the
//! interval of ρ (or η) over which
//!
//! ```text
//! (P(ρ) − P*) / σ̂²  ≤  χ²₁(0.95) = 3.8415,   σ̂² = P* / (m − p),
//! ```
//!
//! where `P(ρ)` is the objective minimised over every other free parameter
//! with ρ held, `P*` its overall minimum, `m` the number of residuals and
//! `p` of free parameters. Unlike the linearised interval
//! ([`super::uncertainty`]) it follows the curvature of the objective, and
//! unlike the landscape's profile ([`super::landscape`]) it uses the
//! output error of the final fit rather than the equation error.
//!
//! The profile is walked outwards from the optimum in steps, each a local
//! Levenberg–Marquardt fit warm-started from the previous one (the
//! objective is piecewise smooth in the jump locations, so a cold start
//! could land in another basin); the crossing of the threshold is located
//! by linear interpolation of `√((P − P*)/σ̂²)`, exact for a quadratic
//! profile. A side that reaches the parameter's bound or the step limit
//! without crossing is open (`None`).

use super::{fit, Dataset, FitError, FitOptions, FitSpec, Parameter, Status};

/// χ²₁ quantile of the 95 % interval.
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// The output-error profile interval of one exponent.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputErrorProfile {
    pub parameter: Parameter,
    /// The optimum the profile starts from.
    pub estimate: f64,
    /// 95 % bounds; `None`: open on that side (bound or step limit reached).
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    /// The profile as walked: (value, (P − P*)/σ̂²), increasing value.
    pub points: Vec<(f64, f64)>,
    /// Local fits run.
    pub fits: usize,
    /// The value the profile started from (the reported optimum; the
    /// first refit moves it to `estimate`).
    pub start: f64,
    /// The lowest `(P − P*)/σ̂²` met on the walk, before the statistic is
    /// clipped at 0 (`points`), and where: `(estimate, 0)` when no held fit
    /// went below `P*`.
    pub lowest: (f64, f64),
}

impl OutputErrorProfile {
    /// Why this interval must not be reported as the interval of the
    /// estimate, `None` when it may. An interval that leaves out its own
    /// estimate is not an interval of it. It happens when the estimate is
    /// not at the minimum of the objective along the parameter (a fit that
    /// stopped on a flat ridge, or at its iteration limit):
    ///
    /// * a held fit lowered the objective below `P*` by at least
    ///   χ²₁(0.95) σ̂²: against that lower minimum the estimate itself would
    ///   be outside its 95 % region;
    /// * the first refit moved the exponent away from the reported optimum
    ///   (`start`), and the interval around the refit leaves `start` out.
    pub fn refusal(&self) -> Option<String> {
        let name = self.parameter.info().name;
        let show = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4}"));
        if self.lowest.1 <= -CHI2_1_95 {
            return Some(format!(
                "a refit with {name} held at {:.4} lowers the objective by {:.3} sigma^2 below its value at the optimum {:.4} (more than chi2_1(0.95) = 3.84): the fit did not reach the minimum of its objective along {name}, so no profile interval of its estimate exists",
                self.lowest.0, -self.lowest.1, self.estimate
            ));
        }
        let inside = self.lower.map_or(true, |l| l <= self.start)
            && self.upper.map_or(true, |u| self.start <= u);
        if !inside {
            return Some(format!(
                "the refit from the reported optimum moved {name} from {:.4} to {:.4} and the profile around it, [{}, {}], leaves the reported estimate out: the fit did not reach the minimum of its objective along {name}",
                self.start,
                self.estimate,
                show(self.lower),
                show(self.upper)
            ));
        }
        None
    }
}

/// Why a profile could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProfileError {
    #[error("{name} is not a free parameter of this fit: only a free exponent (rho, eta) can be profiled")]
    NotFree { name: &'static str },
    #[error("only the exponents rho and eta are profiled, not {name}")]
    NotAnExponent { name: &'static str },
    #[error("no residual degrees of freedom ({residuals} residuals, {free} free parameters)")]
    NoDegreesOfFreedom { residuals: usize, free: usize },
    #[error("step {step} is not allowed: use a finite value > 0")]
    BadStep { step: f64 },
    #[error(transparent)]
    Fit(#[from] FitError),
    /// Cancelled ([`output_error_profile_with`]): no interval.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}

/// A step for [`output_error_profile`]: half the linearised standard error
/// of `parameter` in `fit` (a quadratic profile then crosses the 95 %
/// threshold at the fourth step), 0.05 when there is none.
pub fn default_step(fit: &super::FitResult, parameter: Parameter) -> f64 {
    let name = parameter.info().name;
    fit.uncertainty
        .as_ref()
        .and_then(|u| u.index(name).map(|k| u.std_errors[k]))
        .filter(|s| s.is_finite() && *s > 0.0)
        .map_or(0.05, |s| 0.5 * s)
}

/// The objective the fit minimised, and its number of residuals.
fn objective(res: &super::FitResult, data: &Dataset, spec: &FitSpec) -> (f64, usize) {
    let phase_points: usize = match spec.phase_weight {
        Some(_) => data
            .curves
            .iter()
            .filter_map(|c| c.phases.as_ref().map(Vec::len))
            .sum(),
        None => 0,
    };
    // (`objective`, not Eq 31's `cost`: a fit of the measured-branch output
    // error minimises the former, and the profile must compare minima of
    // what was minimised)
    (
        res.objective + res.phase_cost.unwrap_or(0.0),
        res.n_points + phase_points,
    )
}

/// The output-error profile interval of `parameter` (ρ or η, free in
/// `spec`) for `data`, from the optimum `start` (e.g. the final fit of
/// [`super::identify()`]): first a local refit with everything free (the
/// profile's minimum `P*`), then up to `max_steps` steps of `step` on each
/// side. `step` of the order of the linearised standard error resolves the
/// crossing in a few fits.
pub fn output_error_profile(
    data: &Dataset,
    spec: &FitSpec,
    start: &super::Parameters,
    parameter: Parameter,
    step: f64,
    max_steps: usize,
) -> Result<OutputErrorProfile, ProfileError> {
    output_error_profile_with(
        data,
        spec,
        start,
        parameter,
        step,
        max_steps,
        crate::cancel::Cancel::NEVER,
        &|_, _| {},
    )
}

/// As [`output_error_profile`], polling `cancel` in every local fit
/// ([`crate::cancel`]: a cancelled profile returns
/// [`ProfileError::Interrupted`], never a partial interval) and calling
/// `progress(fits_done, most_fits)` after each local fit (`most_fits =
/// 1 + 2 max_steps`: a side ends early when it crosses the threshold).
#[allow(clippy::too_many_arguments)]
pub fn output_error_profile_with(
    data: &Dataset,
    spec: &FitSpec,
    start: &super::Parameters,
    parameter: Parameter,
    step: f64,
    max_steps: usize,
    cancel: crate::cancel::Cancel,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<OutputErrorProfile, ProfileError> {
    let name = parameter.info().name;
    if !matches!(parameter, Parameter::Rho | Parameter::Eta) {
        return Err(ProfileError::NotAnExponent { name });
    }
    let j = parameter as usize;
    if spec.status[j] != Status::Free {
        return Err(ProfileError::NotFree { name });
    }
    if !(step.is_finite() && step > 0.0) {
        return Err(ProfileError::BadStep { step });
    }
    let mut opts = FitOptions {
        starts: 1,
        ..FitOptions::default()
    };
    opts.lm.cancel = cancel;
    let most = 1 + 2 * max_steps;
    let mut free = spec.clone();
    free.start = *start;
    let best = fit(data, &free, &opts, &|| {})?;
    progress(1, most);
    let (p_star, m) = objective(&best, data, &free);
    let p = best.n_free;
    if m <= p {
        return Err(ProfileError::NoDegreesOfFreedom {
            residuals: m,
            free: p,
        });
    }
    let sigma2 = (p_star / (m - p) as f64).max(f64::MIN_POSITIVE);
    let estimate = best.theta[j];
    let (lo_bound, hi_bound) = spec.bounds[j];
    let mut points = vec![(estimate, 0.0)];
    let mut lowest = (estimate, 0.0f64);
    let mut fits = 1;
    let mut ends = [None, None];
    for (side, dir) in [(0usize, -1.0f64), (1, 1.0)] {
        let mut theta = best.theta;
        let mut prev = (estimate, 0.0f64);
        for k in 1..=max_steps {
            let v = estimate + dir * step * k as f64;
            if v <= lo_bound || v >= hi_bound {
                break;
            }
            let mut held = spec.clone();
            theta[j] = v;
            held.start = theta;
            held.status[j] = Status::Fixed(v);
            let r = match fit(data, &held, &opts, &|| {}) {
                Ok(r) => r,
                Err(_) => break,
            };
            fits += 1;
            progress(fits, most);
            theta = r.theta;
            let (pv, _) = objective(&r, data, &held);
            let raw = (pv - p_star) / sigma2;
            if raw < lowest.1 {
                lowest = (v, raw);
            }
            let stat = raw.max(0.0);
            points.push((v, stat));
            if stat >= CHI2_1_95 {
                // √stat is linear in v for a quadratic profile
                let (a, b) = (prev.1.sqrt(), stat.sqrt());
                let c = CHI2_1_95.sqrt();
                let frac = if b > a { (c - a) / (b - a) } else { 1.0 };
                ends[side] = Some(prev.0 + frac * (v - prev.0));
                break;
            }
            prev = (v, stat);
        }
    }
    cancel.check()?;
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(OutputErrorProfile {
        parameter,
        estimate,
        lower: ends[0],
        upper: ends[1],
        points,
        fits,
        start: start[j],
        lowest,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::{Dataset, FitSpec, ModelKind, Parameters, Record};
    use crate::{ForcedResponse, Formulation, SweepDirection};

    /// Noisy data of a generalised-stiffness model, no jumps: the profile
    /// of ρ against the linearised interval (the objective is close to
    /// quadratic there, so the two must agree) and against the truth. Both
    /// read the noise as of one size (`σ̂² = P*/(m − p)`), so the
    /// comparison is with the plain linearised interval
    /// ([`crate::identification::uncertainty::uncertainty`]); the fit's own
    /// intervals are the sandwich with the noise model, which for this
    /// proportional noise is a different (and the right) statement.
    #[test]
    fn rho_profile_agrees_with_the_linearised_interval_near_quadratic() {
        let wn = std::f64::consts::TAU * 10.0;
        let (rho, a_ref) = (2.6f64, 0.01f64);
        let beta = 0.05 * wn * wn / (crate::power_law::g_unchecked(rho) * a_ref.powf(rho));
        let theta = Parameters::from([wn * wn, 2.0 * 0.02 * wn, beta, rho, 0.0, 0.0, 1.0]);
        let model = theta.normalised_model();
        let omegas: Vec<f64> = (0..40)
            .map(|i| std::f64::consts::TAU * (8.0 + 5.0 * i as f64 / 39.0))
            .collect();
        // SplitMix64 + Box-Muller: 1 % relative amplitude noise, fixed seed
        let mut rng = crate::identification::global::SplitMix64(11);
        let mut uniform = || rng.next_f64();
        let mut recs = Vec::new();
        for (l, &g) in [0.3, 0.6, 0.9].iter().enumerate() {
            let r =
                ForcedResponse::from_normalised(&model, g, Formulation::HarmonicBalance).unwrap();
            for p in r.sweep(&omegas, SweepDirection::Up).unwrap().points {
                let (u1, u2) = (uniform().max(1e-300), uniform());
                let n = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                recs.push(Record {
                    level: format!("L{l}"),
                    gamma: g,
                    omega: p.omega,
                    amplitude: p.amplitude * (1.0 + 0.01 * n),
                    phase: None,
                    direction: SweepDirection::Up,
                    weight: 1.0,
                });
            }
        }
        let data = Dataset::from_records(&recs).unwrap();
        let spec = FitSpec::new(ModelKind::GeneralisedStiffness, &data);
        let mut start_spec = spec.clone();
        start_spec.start = theta;
        let best = fit(&data, &start_spec, &FitOptions::default(), &|| {}).unwrap();
        // the plain linearised interval at the fit (one noise size)
        let e = crate::identification::objective::evaluate_spec(&data, &spec, &best.theta, true)
            .unwrap();
        let jac = e.jacobian.as_ref().unwrap();
        let n = data.len();
        let u = &crate::identification::uncertainty::uncertainty(
            &best.theta,
            &spec.free_indices(),
            &jac[..n],
            &e.residuals[..n],
        )
        .expect("intervals");
        let k = u.index("rho").unwrap();
        let (lin_lo, lin_hi, se) = (u.lower[k], u.upper[k], u.std_errors[k]);
        let prof =
            output_error_profile(&data, &spec, &best.theta, Parameter::Rho, 0.5 * se, 20).unwrap();
        let (lo, hi) = (prof.lower.unwrap(), prof.upper.unwrap());
        eprintln!(
            "rho {:.6}: linearised [{lin_lo:.6}, {lin_hi:.6}], profile [{lo:.6}, {hi:.6}], {} fits",
            prof.estimate, prof.fits
        );
        // both ends within 15 % of the half-width of the linearised ones
        let half = 0.5 * (lin_hi - lin_lo);
        assert!(
            (lo - lin_lo).abs() < 0.15 * half,
            "{lo} vs {lin_lo} (half {half})"
        );
        assert!(
            (hi - lin_hi).abs() < 0.15 * half,
            "{hi} vs {lin_hi} (half {half})"
        );
        assert!(lo < prof.estimate && prof.estimate < hi);
        // the statistic is 0 at the optimum and grows both ways
        assert!(prof.points.iter().all(|p| p.1 >= 0.0));
        // a held or non-exponent parameter is refused
        assert!(matches!(
            output_error_profile(&data, &spec, &best.theta, Parameter::Alpha, 0.1, 5),
            Err(ProfileError::NotAnExponent { .. })
        ));
        assert!(matches!(
            output_error_profile(&data, &spec, &best.theta, Parameter::Eta, 0.1, 5),
            Err(ProfileError::NotFree { .. })
        ));
    }
}
