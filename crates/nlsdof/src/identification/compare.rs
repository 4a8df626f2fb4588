//! Several models fitted to one data set (`nlsdof compare`, Python
//! `compare`; paper Tables 5–7): the fit plan of each model, built here
//! once for both front ends, each run by
//! [`identify`](super::identify::identify) as a single fit is (the front
//! ends add their progress bars and cancellation).

use super::identify::{FitPlan, GainChoice, IdentifyError, SignChoice};
use super::{Dataset, FitSpec, ModelKind, SpecError};
use thiserror::Error;

/// The models `nlsdof compare` fits by default, in its order.
pub const DEFAULT_MODELS: &str = "linear,duffing,duffing-quadratic,duffing-generalised,generalised";

/// What every model of a comparison shares.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareOptions {
    /// Parameters to estimate although a model holds them (e.g. `gain`,
    /// `rho`); a parameter a model does not have is not freed for it.
    pub free: Vec<String>,
    /// Extra global-search starts per refined candidate (1 = none).
    pub starts: usize,
    pub seed: u64,
    pub sign: SignChoice,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            free: Vec::new(),
            starts: 1,
            seed: 1,
            sign: SignChoice::Auto,
        }
    }
}

/// Why a comparison cannot run, with the offending value.
#[derive(Debug, Error)]
pub enum CompareError {
    #[error("unknown model '{name}' (expected one of {expected})")]
    UnknownModel { name: String, expected: String },
    #[error("no models to compare")]
    NoModels,
    #[error("free: {0}")]
    Free(SpecError),
    #[error("{kind}: {source}")]
    Fit {
        kind: ModelKind,
        source: IdentifyError,
    },
}

/// The models of a comma-separated list (blank entries ignored), or an
/// error naming an unknown one.
pub fn parse_models(list: &str) -> Result<Vec<ModelKind>, CompareError> {
    let kinds = list
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|name| {
            ModelKind::parse(name).ok_or_else(|| CompareError::UnknownModel {
                name: name.to_string(),
                expected: ModelKind::ALL
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    if kinds.is_empty() {
        return Err(CompareError::NoModels);
    }
    Ok(kinds)
}

/// The fit plan of each model in `kinds`, in order.
pub fn compare_plans(
    data: &Dataset,
    kinds: &[ModelKind],
    opts: &CompareOptions,
) -> Result<Vec<FitPlan>, CompareError> {
    if kinds.is_empty() {
        return Err(CompareError::NoModels);
    }
    let mut plans = Vec::with_capacity(kinds.len());
    for &kind in kinds {
        let mut plan = FitPlan::new(kind);
        plan.starts = opts.starts;
        plan.seed = opts.seed;
        plan.sign = opts.sign;
        for name in opts.free.iter().filter(|s| !s.trim().is_empty()) {
            let n = name.trim().to_ascii_lowercase();
            if n == "gain" {
                plan.gain = GainChoice::Free;
                continue;
            }
            let mut probe = FitSpec::new(kind, data);
            match probe.free(&n) {
                Ok(()) => plan.free.push(n),
                Err(SpecError::NotInModel { .. }) => {}
                Err(e) => return Err(CompareError::Free(e)),
            }
        }
        plans.push(plan);
    }
    Ok(plans)
}
