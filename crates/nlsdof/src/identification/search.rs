//! Searches over the discrete choices of a model: the sign of the
//! nonlinear stiffness, and integer exponents.
//!
//! Both are the paper's way of choosing a structure (§4: Tables 4–7 fit
//! integer exponents and compare costs). Each candidate is a continuous fit
//! of Eq 31 (sweeps, [`super::fit`]) or of the phase-resonance residuals
//! ([`super::phase_resonance::fit_phase_resonance`]); the candidate with
//! the lowest cost is kept, and every candidate's cost (or error) is
//! returned, so a report can show how clear the choice was.
//!
//! ```
//! use nlsdof::identification::search::{fit_each_sign, signs_to_try};
//! use nlsdof::identification::{ModelKind, Sign};
//! // a model without stiffness term has one sign only
//! assert_eq!(signs_to_try(ModelKind::Quadratic, true, Sign::Softening), vec![Sign::Hardening]);
//! // toy fits: the softening one is cheaper and is kept
//! let (best, trials) = fit_each_sign(&[Sign::Hardening, Sign::Softening], &|s| {
//!     Ok::<_, String>((if s == Sign::Softening { 1.0 } else { 2.0 }, s))
//! })
//! .unwrap();
//! assert_eq!(best, Sign::Softening);
//! assert_eq!(trials.len(), 2);
//! ```

use super::models::{ModelKind, Term, ETA, RHO};
use super::phase_resonance::{integer_search_phase_resonance, PrDataset, PrFitOptions};
use super::phase_resonance::{PrFitResult, PrIntegerCandidate};
use super::{integer_search, Dataset, FitOptions, FitResult, FitSpec, IntegerCandidate};
use super::{Sign, Status, Termination};

/// One sign's outcome: the cost of its fit, or the fit's error message.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SignTrial {
    pub sign: Sign,
    pub cost: Result<f64, String>,
}

/// The signs to fit: both when `both` (hardening first), else `preferred`;
/// a model without a stiffness term has one (hardening, β = 0).
pub fn signs_to_try(kind: ModelKind, both: bool, preferred: Sign) -> Vec<Sign> {
    if kind.stiffness() == Term::Absent {
        return vec![Sign::Hardening];
    }
    if both {
        vec![Sign::Hardening, Sign::Softening]
    } else {
        vec![preferred]
    }
}

/// Fits each sign of `signs` with `fit_one` (which returns the fit's cost
/// and result) and keeps the lowest cost (the first on a tie). Every sign's
/// cost or error is returned. When every sign fails, the last error.
pub fn fit_each_sign<R, E: std::fmt::Display>(
    signs: &[Sign],
    fit_one: &dyn Fn(Sign) -> Result<(f64, R), E>,
) -> Result<(R, Vec<SignTrial>), E> {
    let mut best: Option<(f64, R)> = None;
    let mut trials = Vec::with_capacity(signs.len());
    let mut last_err = None;
    for &sign in signs {
        match fit_one(sign) {
            Ok((cost, r)) => {
                trials.push(SignTrial {
                    sign,
                    cost: Ok(cost),
                });
                if best.as_ref().map_or(true, |b| cost < b.0) {
                    best = Some((cost, r));
                }
            }
            Err(e) => {
                trials.push(SignTrial {
                    sign,
                    cost: Err(e.to_string()),
                });
                last_err = Some(e);
            }
        }
    }
    match (best, last_err) {
        (Some((_, r)), _) => Ok((r, trials)),
        (None, Some(e)) => Err(e),
        (None, None) => unreachable!("fit_each_sign needs at least one sign"),
    }
}

/// One integer exponent pair of an integer search: `None` for an exponent
/// the model does not leave free.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegerPair {
    pub rho: Option<i64>,
    pub eta: Option<i64>,
    /// `(cost, termination)` of the pair's fit, or its error message.
    pub outcome: Result<(f64, Termination), String>,
}

/// Errors of the integer searches.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegerSearchError {
    #[error("the {model} model has no free exponent")]
    NoFreeExponent { model: ModelKind },
    #[error("no integer exponent pair could be fitted")]
    NothingFitted,
}

/// Keeps the lowest-cost fit of the candidates (the first on a tie).
fn best_of<R: Clone, E: std::fmt::Display>(
    cands: impl IntoIterator<Item = (Option<i64>, Option<i64>, Result<R, E>)>,
    cost: impl Fn(&R) -> (f64, Termination),
) -> Result<(R, Vec<IntegerPair>), IntegerSearchError> {
    let mut best: Option<R> = None;
    let mut pairs = Vec::new();
    for (rho, eta, fit) in cands {
        let outcome = match fit {
            Ok(r) => {
                let c = cost(&r);
                if best.as_ref().map_or(true, |b| c.0 < cost(b).0) {
                    best = Some(r);
                }
                Ok(c)
            }
            Err(e) => Err(e.to_string()),
        };
        pairs.push(IntegerPair { rho, eta, outcome });
    }
    best.map(|b| (b, pairs))
        .ok_or(IntegerSearchError::NothingFitted)
}

fn check_free_exponent(spec: &FitSpec) -> Result<(), IntegerSearchError> {
    if spec.status[RHO] != Status::Free && spec.status[ETA] != Status::Free {
        return Err(IntegerSearchError::NoFreeExponent { model: spec.kind });
    }
    Ok(())
}

/// The best integer-exponent sweep fit ([`integer_search`]: every integer
/// value of each free exponent within its bounds), with every pair's cost.
pub fn best_integer_fit(
    data: &Dataset,
    spec: &FitSpec,
    opts: &FitOptions,
) -> Result<(FitResult, Vec<IntegerPair>), IntegerSearchError> {
    check_free_exponent(spec)?;
    best_of(
        integer_search(data, spec, opts)
            .into_iter()
            .map(|IntegerCandidate { rho, eta, fit }| (rho, eta, fit)),
        |r: &FitResult| (r.cost, r.termination),
    )
}

/// As [`best_integer_fit`], for phase-resonance points
/// ([`integer_search_phase_resonance`]).
pub fn best_integer_fit_phase_resonance(
    data: &PrDataset,
    spec: &FitSpec,
    opts: &PrFitOptions,
) -> Result<(PrFitResult, Vec<IntegerPair>), IntegerSearchError> {
    check_free_exponent(spec)?;
    best_of(
        integer_search_phase_resonance(data, spec, opts)
            .into_iter()
            .map(|PrIntegerCandidate { rho, eta, fit }| (rho, eta, fit)),
        |r: &PrFitResult| (r.cost, r.termination),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lowest_cost_wins_and_every_outcome_is_kept() {
        let (best, trials) = fit_each_sign(&[Sign::Hardening, Sign::Softening], &|s| match s {
            Sign::Hardening => Err("diverged".to_string()),
            Sign::Softening => Ok((3.0, 7)),
        })
        .unwrap();
        assert_eq!(best, 7);
        assert_eq!(trials[0].cost, Err("diverged".to_string()));
        assert_eq!(trials[1].cost, Ok(3.0));
        let all_fail: Result<((), _), String> =
            fit_each_sign(&[Sign::Hardening, Sign::Softening], &|s| {
                Err(format!("{} failed", s.name()))
            });
        assert_eq!(all_fail.unwrap_err(), "softening failed");
    }

    #[test]
    fn integer_best_is_the_lowest_cost_and_errors_are_listed() {
        let t = Termination::SmallStep;
        let cands: Vec<(Option<i64>, Option<i64>, Result<f64, String>)> = vec![
            (Some(1), None, Ok(2.0)),
            (Some(2), None, Err("no root".into())),
            (Some(3), None, Ok(0.5)),
            (Some(4), None, Ok(0.5)),
        ];
        let (best, pairs) = best_of(cands, |c: &f64| (*c, t)).unwrap();
        assert_eq!(best, 0.5);
        assert_eq!(pairs.len(), 4);
        assert_eq!(pairs[1].outcome, Err("no root".to_string()));
        assert_eq!(pairs[2].outcome, Ok((0.5, t)));
        let none: Vec<(Option<i64>, Option<i64>, Result<f64, String>)> =
            vec![(Some(1), None, Err("x".into()))];
        assert_eq!(
            best_of(none, |c: &f64| (*c, t)).unwrap_err(),
            IntegerSearchError::NothingFitted
        );
    }
}
