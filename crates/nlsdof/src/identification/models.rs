//! The model family of the identification (paper §4): which power-law terms
//! are present and which exponents are fixed by the model's definition.

use std::fmt;

/// Index of each mass-normalised parameter in the parameter vector θ.
pub const ALPHA: usize = 0;
pub const DELTA: usize = 1;
pub const BETA: usize = 2;
pub const RHO: usize = 3;
pub const KAPPA: usize = 4;
pub const ETA: usize = 5;
pub const GAIN: usize = 6;
/// Number of parameters in θ = (α, δ, β, ρ, κ, η, gain).
pub const N_PARAMS: usize = 7;
/// Names of θ's entries, as used by `--fix` and in reports.
pub const PARAM_NAMES: [&str; N_PARAMS] = ["alpha", "delta", "beta", "rho", "kappa", "eta", "gain"];

/// Index of a parameter name (`alpha`, `delta`, `beta`, `rho`, `kappa`, `eta`, `gain`).
pub fn param_index(name: &str) -> Option<usize> {
    PARAM_NAMES.iter().position(|n| *n == name)
}

/// A model of the identification family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum ModelKind {
    /// `x'' + δx' + αx = γ`.
    Linear,
    /// Cubic stiffness (ρ = 2), linear damping.
    Duffing,
    /// Quadratic damping (η = 1), linear stiffness.
    Quadratic,
    /// ρ = 2 and η = 1 (the paper's "classic" model).
    DuffingQuadratic,
    /// ρ = 2, η free (Table 6).
    DuffingGeneralised,
    /// ρ and η free (Table 7).
    Generalised,
    /// Linear stiffness, power-law damping with free η.
    GeneralisedDamping,
    /// Power-law stiffness with free ρ, linear damping.
    GeneralisedStiffness,
    /// Coulomb friction (η = −1), linear stiffness.
    Coulomb,
}

/// Role of one power-law term in a model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Term {
    Absent,
    /// Present with the exponent fixed by the model.
    FixedExponent(f64),
    /// Present with a free exponent.
    FreeExponent,
}

impl ModelKind {
    pub const ALL: [ModelKind; 9] = [
        ModelKind::Linear,
        ModelKind::Duffing,
        ModelKind::Quadratic,
        ModelKind::DuffingQuadratic,
        ModelKind::DuffingGeneralised,
        ModelKind::Generalised,
        ModelKind::GeneralisedDamping,
        ModelKind::GeneralisedStiffness,
        ModelKind::Coulomb,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Linear => "linear",
            ModelKind::Duffing => "duffing",
            ModelKind::Quadratic => "quadratic",
            ModelKind::DuffingQuadratic => "duffing-quadratic",
            ModelKind::DuffingGeneralised => "duffing-generalised",
            ModelKind::Generalised => "generalised",
            ModelKind::GeneralisedDamping => "generalised-damping",
            ModelKind::GeneralisedStiffness => "generalised-stiffness",
            ModelKind::Coulomb => "coulomb",
        }
    }

    /// Parses a model name (also accepts `classic` for duffing-quadratic).
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase().replace('_', "-");
        if n == "classic" {
            return Some(ModelKind::DuffingQuadratic);
        }
        Self::ALL.into_iter().find(|k| k.name() == n)
    }

    /// The stiffness term `β x|x|^ρ`.
    pub fn stiffness(self) -> Term {
        match self {
            ModelKind::Duffing | ModelKind::DuffingQuadratic | ModelKind::DuffingGeneralised => {
                Term::FixedExponent(2.0)
            }
            ModelKind::Generalised | ModelKind::GeneralisedStiffness => Term::FreeExponent,
            _ => Term::Absent,
        }
    }

    /// The damping term `κ x'|x'|^η`.
    pub fn damping(self) -> Term {
        match self {
            ModelKind::Quadratic | ModelKind::DuffingQuadratic => Term::FixedExponent(1.0),
            ModelKind::Coulomb => Term::FixedExponent(-1.0),
            ModelKind::DuffingGeneralised
            | ModelKind::Generalised
            | ModelKind::GeneralisedDamping => Term::FreeExponent,
            _ => Term::Absent,
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
