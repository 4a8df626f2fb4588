//! The generalised power-law SDoF model, Eq 29 (physical units) and its
//! mass-normalised form (Eq 1–3, Eq 32):
//!
//! ```text
//! m x'' + c x' + k x + c_e x'|x'|^η + k_r x|x|^ρ = m γ(t)            (Eq 29)
//!   x'' + δ x' + α x + κ x'|x'|^η + β x|x|^ρ   = γ(t)               (Eq 32)
//! α = k/m,  δ = c/m,  β = k_r/m,  κ = c_e/m,  ω_n = √α,  ζ = δ/(2 ω_n)
//! ```
//!
//! `γ(t)` is the input acceleration (m/s²). With acceleration input only the
//! ratios to `m` are identifiable, so every response routine works on
//! [`NormalisedModel`]; [`Model`] keeps the physical values a user enters.

use crate::error::ParameterError;
use crate::power_law::{check_exponent, PowerLaw};

/// Physical model (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Model {
    /// m, kg (> 0).
    pub mass: f64,
    /// k, N/m (> 0).
    pub stiffness: f64,
    /// c, N s/m (>= 0).
    pub damping: f64,
    /// `k_r x|x|^ρ`: k_r in N/m^{ρ+1} (any sign: < 0 is softening), ρ > −3.
    pub nonlinear_stiffness: Option<PowerLaw>,
    /// `c_e x'|x'|^η`: c_e in N (s/m)^{η+1} (>= 0), η > −3. η = −1 is
    /// Coulomb friction with friction force c_e.
    pub nonlinear_damping: Option<PowerLaw>,
}

fn finite(name: &'static str, v: f64) -> Result<(), ParameterError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(ParameterError::NotFinite { name, value: v })
    }
}

impl Model {
    /// Linear model `m x'' + c x' + k x = m γ`.
    pub fn linear(mass: f64, stiffness: f64, damping: f64) -> Result<Self, ParameterError> {
        let m = Self {
            mass,
            stiffness,
            damping,
            nonlinear_stiffness: None,
            nonlinear_damping: None,
        };
        m.validate()?;
        Ok(m)
    }

    /// Adds (or replaces) the nonlinear stiffness term `k_r x|x|^ρ`.
    pub fn with_stiffness(mut self, k_r: f64, rho: f64) -> Result<Self, ParameterError> {
        self.nonlinear_stiffness = Some(PowerLaw {
            coefficient: k_r,
            exponent: rho,
        });
        self.validate()?;
        Ok(self)
    }

    /// Adds (or replaces) the nonlinear damping term `c_e x'|x'|^η`.
    pub fn with_damping(mut self, c_e: f64, eta: f64) -> Result<Self, ParameterError> {
        self.nonlinear_damping = Some(PowerLaw {
            coefficient: c_e,
            exponent: eta,
        });
        self.validate()?;
        Ok(self)
    }

    /// Checks every parameter: finite; m > 0; k > 0; c >= 0; c_e >= 0;
    /// exponents finite and > −3. The first violation is returned.
    pub fn validate(&self) -> Result<(), ParameterError> {
        finite("mass", self.mass)?;
        finite("stiffness", self.stiffness)?;
        finite("damping", self.damping)?;
        if self.mass <= 0.0 {
            return Err(ParameterError::NotPositive {
                name: "mass",
                value: self.mass,
            });
        }
        if self.stiffness <= 0.0 {
            return Err(ParameterError::NotPositive {
                name: "stiffness",
                value: self.stiffness,
            });
        }
        if self.damping < 0.0 {
            return Err(ParameterError::Negative {
                name: "damping",
                value: self.damping,
            });
        }
        if let Some(t) = self.nonlinear_stiffness {
            finite("nonlinear_stiffness.coefficient", t.coefficient)?;
            check_exponent("nonlinear_stiffness.exponent", t.exponent)?;
        }
        if let Some(t) = self.nonlinear_damping {
            finite("nonlinear_damping.coefficient", t.coefficient)?;
            check_exponent("nonlinear_damping.exponent", t.exponent)?;
            if t.coefficient < 0.0 {
                return Err(ParameterError::Negative {
                    name: "nonlinear_damping.coefficient",
                    value: t.coefficient,
                });
            }
        }
        Ok(())
    }

    /// Linear natural frequency ω_n = √(k/m), rad/s.
    pub fn omega_n(&self) -> f64 {
        (self.stiffness / self.mass).sqrt()
    }

    /// Linear damping ratio ζ = c / (2 m ω_n) = c / (2√k √m): the square
    /// roots taken apart, so that `k m` cannot overflow or underflow at
    /// extreme (but valid) scalings (test `zeta_survives_extreme_scalings`).
    pub fn zeta(&self) -> f64 {
        self.damping / (2.0 * self.stiffness.sqrt() * self.mass.sqrt())
    }

    /// Mass-normalised parameters (α, δ, β, ρ, κ, η). Validates first.
    pub fn normalised(&self) -> Result<NormalisedModel, ParameterError> {
        self.validate()?;
        Ok(self.normalised_unchecked())
    }

    pub(crate) fn normalised_unchecked(&self) -> NormalisedModel {
        let m = self.mass;
        let (beta, rho) = self
            .nonlinear_stiffness
            .map(|t| (t.coefficient / m, t.exponent))
            .unwrap_or((0.0, 0.0));
        let (kappa, eta) = self
            .nonlinear_damping
            .map(|t| (t.coefficient / m, t.exponent))
            .unwrap_or((0.0, 0.0));
        NormalisedModel {
            alpha: self.stiffness / m,
            delta: self.damping / m,
            beta,
            rho,
            kappa,
            eta,
        }
    }
}

/// Mass-normalised model, Eq 32:
/// `x'' + δ x' + α x + κ x'|x'|^η + β x|x|^ρ = γ(t)`.
///
/// A missing nonlinear term is represented by a zero coefficient (its
/// exponent is then irrelevant and set to 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalisedModel {
    /// α = k/m, 1/s².
    pub alpha: f64,
    /// δ = c/m, 1/s.
    pub delta: f64,
    /// β = k_r/m, 1/(s² m^ρ).
    pub beta: f64,
    /// ρ, stiffness exponent.
    pub rho: f64,
    /// κ = c_e/m, (s/m)^η / s.
    pub kappa: f64,
    /// η, damping exponent.
    pub eta: f64,
}

impl NormalisedModel {
    /// Validates: α > 0, δ ≥ 0, κ ≥ 0, all finite, exponents > −3.
    pub fn validate(&self) -> Result<(), ParameterError> {
        finite("alpha", self.alpha)?;
        finite("delta", self.delta)?;
        finite("beta", self.beta)?;
        finite("kappa", self.kappa)?;
        check_exponent("rho", self.rho)?;
        check_exponent("eta", self.eta)?;
        if self.alpha <= 0.0 {
            return Err(ParameterError::NotPositive {
                name: "alpha",
                value: self.alpha,
            });
        }
        if self.delta < 0.0 {
            return Err(ParameterError::Negative {
                name: "delta",
                value: self.delta,
            });
        }
        if self.kappa < 0.0 {
            return Err(ParameterError::Negative {
                name: "kappa",
                value: self.kappa,
            });
        }
        Ok(())
    }

    /// ω_n = √α, rad/s.
    pub fn omega_n(&self) -> f64 {
        self.alpha.sqrt()
    }

    /// ζ = δ / (2 ω_n).
    pub fn zeta(&self) -> f64 {
        self.delta / (2.0 * self.omega_n())
    }

    /// Physical model for a given mass (the inverse of [`Model::normalised`]).
    pub fn to_physical(&self, mass: f64) -> Result<Model, ParameterError> {
        let m = Model {
            mass,
            stiffness: self.alpha * mass,
            damping: self.delta * mass,
            nonlinear_stiffness: (self.beta != 0.0).then_some(PowerLaw {
                coefficient: self.beta * mass,
                exponent: self.rho,
            }),
            nonlinear_damping: (self.kappa != 0.0).then_some(PowerLaw {
                coefficient: self.kappa * mass,
                exponent: self.eta,
            }),
        };
        m.validate()?;
        Ok(m)
    }

    /// Restoring plus dissipative acceleration
    /// `δ v + α x + κ v|v|^η + β x|x|^ρ` (the left side of Eq 32 minus x'').
    /// At `v = 0` with `η ≤ −1` the damping term is taken as 0 (the
    /// set-valued friction force is resolved by the integrator, not here).
    #[inline]
    pub fn internal_acceleration(&self, x: f64, v: f64) -> f64 {
        let mut f = self.delta * v + self.alpha * x;
        if self.beta != 0.0 && x != 0.0 {
            f += self.beta * x * x.abs().powf(self.rho);
        }
        if self.kappa != 0.0 && v != 0.0 {
            f += self.kappa * v * v.abs().powf(self.eta);
        }
        f
    }
}

#[cfg(test)]
mod tests {

    /// Issue 30: mass 1e-300 gave zeta = inf and 1e300 zeta = 0 (k m out of
    /// range); the ratio is scale-free, so every scaling gives 1 %.
    #[test]
    fn zeta_survives_extreme_scalings() {
        for m in [1e-300, 1e-150, 1.0, 1e150, 1e300] {
            let model = Model::linear(m, m * 3947.84, m * 1.256_637).unwrap();
            let z = model.zeta();
            assert!((z - 0.01).abs() < 1e-6, "mass {m:e}: zeta {z:e}");
        }
    }

    use super::*;

    #[test]
    fn validation_reports_offending_value() {
        assert_eq!(
            Model::linear(-1.0, 1.0, 0.0).unwrap_err(),
            ParameterError::NotPositive {
                name: "mass",
                value: -1.0
            }
        );
        assert_eq!(
            Model::linear(1.0, 0.0, 0.0).unwrap_err(),
            ParameterError::NotPositive {
                name: "stiffness",
                value: 0.0
            }
        );
        assert_eq!(
            Model::linear(1.0, 1.0, -0.5).unwrap_err(),
            ParameterError::Negative {
                name: "damping",
                value: -0.5
            }
        );
        assert!(matches!(
            Model::linear(f64::NAN, 1.0, 0.0).unwrap_err(),
            ParameterError::NotFinite { name: "mass", .. }
        ));
        let m = Model::linear(1.0, 1.0, 0.1).unwrap();
        assert!(matches!(
            m.with_stiffness(1.0, -3.0).unwrap_err(),
            ParameterError::ExponentTooSmall { value, .. } if value == -3.0
        ));
        assert!(matches!(
            m.with_damping(-0.1, 1.0).unwrap_err(),
            ParameterError::Negative { value, .. } if value == -0.1
        ));
        assert!(m.with_damping(0.1, f64::INFINITY).is_err());
        assert!(m.with_stiffness(f64::NAN, 2.0).is_err());
        // softening is allowed
        assert!(m.with_stiffness(-5.0, 2.0).is_ok());
    }

    #[test]
    fn normalisation_round_trip() {
        let m = Model::linear(0.26699, 306.7878, 0.1164)
            .unwrap()
            .with_stiffness(85000.0, 4.0022)
            .unwrap()
            .with_damping(0.01591, 3.03099)
            .unwrap();
        let n = m.normalised().unwrap();
        assert!((n.alpha - 306.7878 / 0.26699).abs() < 1e-12);
        assert!((n.omega_n() - m.omega_n()).abs() < 1e-12);
        assert!((n.zeta() - m.zeta()).abs() < 1e-15);
        let back = n.to_physical(0.26699).unwrap();
        assert!((back.stiffness - m.stiffness).abs() < 1e-10);
        assert!((back.nonlinear_damping.unwrap().coefficient - 0.01591).abs() < 1e-15);
    }
}

/// Either form of the model: every computation of the crate (harmonic
/// balance, simulation, the rig, multi-harmonic balance) accepts the
/// physical [`Model`] or its mass-normalised form [`NormalisedModel`]
/// through this trait, so one model value serves every entry point.
///
/// ```
/// use nlsdof::{simulation::{simulate_to_vec, Options}, excitation::SampledInput, Model};
/// let m = Model::linear(2.0, 800.0, 1.0)?; // physical
/// let u = vec![1.0; 64];
/// let input = SampledInput::uniform(&u, 100.0, 0.0)?;
/// let (a, _) = simulate_to_vec(&m, &input, &Options::default())?;
/// let (b, _) = simulate_to_vec(&m.normalised()?, &input, &Options::default())?;
/// assert_eq!(a.x, b.x);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait AsNormalised {
    /// The mass-normalised model (for [`Model`]: validated, then divided
    /// by the mass; for [`NormalisedModel`]: itself, each computation
    /// checks what it needs).
    fn as_normalised(&self) -> Result<NormalisedModel, ParameterError>;
}

impl AsNormalised for Model {
    fn as_normalised(&self) -> Result<NormalisedModel, ParameterError> {
        self.normalised()
    }
}

impl AsNormalised for NormalisedModel {
    fn as_normalised(&self) -> Result<NormalisedModel, ParameterError> {
        Ok(*self)
    }
}
