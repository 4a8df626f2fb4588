//! The mass-normalised parameters θ of the steady-state identification, with
//! their metadata (name, units, mass scaling, default bounds).
//!
//! Dividing the model (paper Eq 1) by the mass `m`,
//!
//! ```text
//! x'' + δ x' + α x + κ x'|x'|^η + β x|x|^ρ = gain · γ(t)
//! α = k/m,  δ = c/m,  β = k_r/m,  κ = c_e/m
//! ```
//!
//! With base-acceleration amplitude data only these ratios are identifiable;
//! `gain` scales the measured input γ to what the structure sees (a point on
//! a continuous structure). Physical values follow from a known mass:
//! `k = m α`, `c = m δ`, `k_r = m β`, `c_e = m κ` ([`Parameter::mass_scaled`]).
//!
//! ```
//! use nlsdof::identification::parameters::{Parameter, Parameters};
//! let p = Parameters { alpha: 4.0e4, delta: 2.0, ..Parameters::default() };
//! assert_eq!(p[Parameter::Alpha], 4.0e4);
//! assert_eq!(Parameter::Beta.info().physical_unit, "N/m^(rho+1)");
//! // k = m α for m = 0.5 kg
//! assert_eq!(p.physical(Parameter::Alpha, 0.5), 2.0e4);
//! ```

use super::models::N_PARAMS;
use crate::model::NormalisedModel;
use std::ops::{Index, IndexMut};

/// θ = (α, δ, β, ρ, κ, η, gain), mass-normalised (module docs).
///
/// Also indexable by position (`theta[RHO]`, with the index constants of
/// [`super::models`]) for the optimisers, which work on vectors.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Parameters {
    /// α = k/m, 1/s².
    pub alpha: f64,
    /// δ = c/m, 1/s.
    pub delta: f64,
    /// β = k_r/m, 1/(s² m^ρ) (negative: softening).
    pub beta: f64,
    /// ρ, stiffness exponent (> −3).
    pub rho: f64,
    /// κ = c_e/m, s^(η−1)/m^η.
    pub kappa: f64,
    /// η, damping exponent (> −3; −1 is Coulomb friction).
    pub eta: f64,
    /// Forcing gain (dimensionless; the structure sees `gain · γ`).
    pub gain: f64,
}

/// One entry of θ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Parameter {
    Alpha,
    Delta,
    Beta,
    Rho,
    Kappa,
    Eta,
    Gain,
}

/// Default bounds of a parameter in the fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DefaultBounds {
    /// The same for every data set.
    Fixed(f64, f64),
    /// Scaled from the data (the rule, in words).
    FromData(&'static str),
}

/// What is known of a parameter without data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParameterInfo {
    /// Name used by `--fix`, `--free`, bounds files and reports.
    pub name: &'static str,
    /// Symbol in the paper's notation.
    pub symbol: &'static str,
    /// SI unit of the mass-normalised value.
    pub unit: &'static str,
    /// Name of the physical parameter (`k`, `c`, `k_r`, `c_e`, or the same).
    pub physical_name: &'static str,
    /// SI unit of the physical value.
    pub physical_unit: &'static str,
    /// Whether the physical value is `m ×` the normalised one.
    pub mass_scaled: bool,
    pub default_bounds: DefaultBounds,
}

impl Parameter {
    /// In θ order.
    pub const ALL: [Parameter; N_PARAMS] = [
        Parameter::Alpha,
        Parameter::Delta,
        Parameter::Beta,
        Parameter::Rho,
        Parameter::Kappa,
        Parameter::Eta,
        Parameter::Gain,
    ];

    /// Position in θ (the index constants of [`super::models`]).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The parameter of a name (`alpha`, …, `gain`; case-insensitive).
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase();
        Self::ALL.into_iter().find(|p| p.info().name == n)
    }

    /// Whether the physical value is `m ×` the normalised one.
    pub fn mass_scaled(self) -> bool {
        self.info().mass_scaled
    }

    /// Name, units, mass scaling and default bounds.
    pub fn info(self) -> ParameterInfo {
        use DefaultBounds::{Fixed, FromData};
        let i = |name, symbol, unit, physical_name, physical_unit, mass_scaled, default_bounds| {
            ParameterInfo {
                name,
                symbol,
                unit,
                physical_name,
                physical_unit,
                mass_scaled,
                default_bounds,
            }
        };
        match self {
            Parameter::Alpha => i(
                "alpha",
                "α",
                "1/s^2",
                "k",
                "N/m",
                true,
                FromData("[(Ω_min/2)², (1.5 Ω_max)²] over the data's frequencies"),
            ),
            Parameter::Delta => i(
                "delta",
                "δ",
                "1/s",
                "c",
                "N s/m",
                true,
                FromData("[1e-4 δ₀, 1e2 δ₀], δ₀ = γ/(a_peak Ω_peak) of the lowest level"),
            ),
            Parameter::Beta => i(
                "beta",
                "β",
                "1/(s^2 m^rho)",
                "k_r",
                "N/m^(rho+1)",
                true,
                FromData("β_ref = g(ρ) β A_ref^ρ in [1e-6 α₀, 20 α₀]"),
            ),
            Parameter::Rho => i("rho", "ρ", "-", "rho", "-", false, Fixed(0.0, 10.0)),
            Parameter::Kappa => i(
                "kappa",
                "κ",
                "s^(eta-1)/m^eta",
                "c_e",
                "N (s/m)^(eta+1)",
                true,
                FromData("κ_ref = g(η) κ (Ω_ref A_ref)^η in [1e-6 δ₀, 1e2 δ₀]"),
            ),
            Parameter::Eta => i("eta", "η", "-", "eta", "-", false, Fixed(-1.0, 8.0)),
            Parameter::Gain => i("gain", "gain", "-", "gain", "-", false, Fixed(0.1, 10.0)),
        }
    }
}

impl Parameters {
    /// From θ in vector order.
    pub fn from_array(a: [f64; N_PARAMS]) -> Self {
        Self {
            alpha: a[0],
            delta: a[1],
            beta: a[2],
            rho: a[3],
            kappa: a[4],
            eta: a[5],
            gain: a[6],
        }
    }

    /// θ in vector order.
    pub fn to_array(self) -> [f64; N_PARAMS] {
        [
            self.alpha, self.delta, self.beta, self.rho, self.kappa, self.eta, self.gain,
        ]
    }

    /// The values in θ order.
    pub fn iter(&self) -> impl Iterator<Item = f64> {
        self.to_array().into_iter()
    }

    /// The mass-normalised model of θ (every entry but the gain, which
    /// scales the input: the model sees `gain · γ`).
    pub fn normalised_model(&self) -> NormalisedModel {
        NormalisedModel {
            alpha: self.alpha,
            delta: self.delta,
            beta: self.beta,
            rho: self.rho,
            kappa: self.kappa,
            eta: self.eta,
        }
    }

    /// θ of a mass-normalised model and a forcing gain.
    pub fn from_normalised(m: &NormalisedModel, gain: f64) -> Self {
        Self {
            alpha: m.alpha,
            delta: m.delta,
            beta: m.beta,
            rho: m.rho,
            kappa: m.kappa,
            eta: m.eta,
            gain,
        }
    }

    /// Physical value for mass `m` (kg): `m ×` the normalised value for α,
    /// δ, β and κ, the value itself otherwise.
    pub fn physical(&self, p: Parameter, m: f64) -> f64 {
        if p.mass_scaled() {
            m * self[p]
        } else {
            self[p]
        }
    }
}

impl From<[f64; N_PARAMS]> for Parameters {
    fn from(a: [f64; N_PARAMS]) -> Self {
        Self::from_array(a)
    }
}

impl From<Parameters> for [f64; N_PARAMS] {
    fn from(p: Parameters) -> Self {
        p.to_array()
    }
}

impl Index<Parameter> for Parameters {
    type Output = f64;
    fn index(&self, p: Parameter) -> &f64 {
        match p {
            Parameter::Alpha => &self.alpha,
            Parameter::Delta => &self.delta,
            Parameter::Beta => &self.beta,
            Parameter::Rho => &self.rho,
            Parameter::Kappa => &self.kappa,
            Parameter::Eta => &self.eta,
            Parameter::Gain => &self.gain,
        }
    }
}

impl IndexMut<Parameter> for Parameters {
    fn index_mut(&mut self, p: Parameter) -> &mut f64 {
        match p {
            Parameter::Alpha => &mut self.alpha,
            Parameter::Delta => &mut self.delta,
            Parameter::Beta => &mut self.beta,
            Parameter::Rho => &mut self.rho,
            Parameter::Kappa => &mut self.kappa,
            Parameter::Eta => &mut self.eta,
            Parameter::Gain => &mut self.gain,
        }
    }
}

/// Position in θ; panics beyond [`N_PARAMS`] as an array would.
impl Index<usize> for Parameters {
    type Output = f64;
    fn index(&self, j: usize) -> &f64 {
        &self[Parameter::ALL[j]]
    }
}

impl IndexMut<usize> for Parameters {
    fn index_mut(&mut self, j: usize) -> &mut f64 {
        &mut self[Parameter::ALL[j]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::models::{ALPHA, BETA, DELTA, ETA, GAIN, KAPPA, PARAM_NAMES, RHO};

    #[test]
    fn order_names_and_indices_agree() {
        let p = Parameters::from_array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        assert_eq!(p.to_array(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        for (j, q) in Parameter::ALL.into_iter().enumerate() {
            assert_eq!(q.index(), j);
            assert_eq!(p[j], p[q]);
            assert_eq!(q.info().name, PARAM_NAMES[j]);
            assert_eq!(Parameter::parse(&q.info().name.to_uppercase()), Some(q));
        }
        assert_eq!(
            [p.alpha, p.delta, p.beta, p.rho, p.kappa, p.eta, p.gain],
            [p[ALPHA], p[DELTA], p[BETA], p[RHO], p[KAPPA], p[ETA], p[GAIN]]
        );
        let mut q = p;
        q[RHO] = 9.0;
        q[Parameter::Eta] = -1.0;
        assert_eq!((q.rho, q.eta), (9.0, -1.0));
        assert_eq!(Parameter::parse("mass"), None);
    }

    #[test]
    fn mass_scaling() {
        let p = Parameters::from_array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        let m = 0.25;
        let phys: Vec<f64> = Parameter::ALL.iter().map(|&q| p.physical(q, m)).collect();
        assert_eq!(phys, vec![0.25, 0.5, 0.75, 4.0, 1.25, 6.0, 7.0]);
        // the model keeps every entry but the gain
        let back = Parameters::from_normalised(&p.normalised_model(), p.gain);
        assert_eq!(back, p);
    }
}
