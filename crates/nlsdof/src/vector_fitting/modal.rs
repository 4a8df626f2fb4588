//! Modal parameters of a fitted pole pair and the SDoF linear part.
//!
//! A pole pair `a, ā` with `a = −ζω_n + jω_n√(1 − ζ²)` gives
//!
//! ```text
//! ω_n = |a|,   ζ = −Re a / |a|,   ω_d = Im a = ω_n √(1 − ζ²)
//! ```
//!
//! A single-degree-of-freedom displacement FRF
//! `X/U = G / (s² + δ s + α) = G / ((s − a)(s − ā))` has the residue
//! `r_x = G / (a − ā) = G / (2jω_d)` at `a`, hence the modal gain
//! `G = 2jω_d r_x` (real for a proportionally damped mode; its phase is
//! reported as the modal complexity). For a velocity or acceleration
//! output the residue of `s^p X/U` at `a` is `a^p r_x` (`p = 1, 2`), so
//! `r_x = r_out / a^p`.
//!
//! The linear part of the paper's model (Eq 29/32) follows from the poles
//! alone: `α = k/m = ω_n² = |a|²`, `δ = c/m = 2ζω_n = −2 Re a`.
//!
//! * **Force input** (`U = F`, N): `G = 1/m`, so `m = 1/|G|` (the modal
//!   mass at the measurement point), `k = m α`, `c = m δ`. A known mass
//!   (`known_mass`) overrides the residue value.
//! * **Acceleration input** (base excitation, `U = γ`, m/s²): `G` is the
//!   participation factor (1 for the ideal SDoF of Eq 29); the mass is **not
//!   identifiable** from the FRF: `m, k, c` are given only when a known mass
//!   is supplied, otherwise only `α` and `δ`.

use super::{VectorFitError, VfFit, C64};

/// Modal parameters of one pole pair (physical units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalParameters {
    /// Pole `a` with `Im a > 0`, rad/s.
    pub pole: C64,
    /// Residue at `a` of the fitted FRF (units of the FRF × rad/s).
    pub residue: C64,
    /// Natural frequency `ω_n = |a|`, rad/s.
    pub omega_n: f64,
    /// `f_n = ω_n / 2π`, Hz.
    pub frequency_hz: f64,
    /// Damping ratio `ζ = −Re a / |a|`.
    pub zeta: f64,
    /// Damped natural frequency `ω_d = Im a`, rad/s.
    pub omega_d: f64,
    /// Peak height of this mode's contribution, `|r| / |Re a|` (the
    /// magnitude of `r/(s − a)` at `s = j Im a`); used to pick the dominant mode.
    pub peak: f64,
}

/// Modal parameters of every complex pole pair, sorted by `ω_n`.
pub fn modal_parameters(fit: &VfFit) -> Vec<ModalParameters> {
    let mut v: Vec<ModalParameters> = fit
        .terms
        .iter()
        .filter(|t| t.is_pair())
        .map(|t| {
            let wn = t.pole.norm();
            ModalParameters {
                pole: t.pole,
                residue: t.residue,
                omega_n: wn,
                frequency_hz: wn / (2.0 * std::f64::consts::PI),
                zeta: -t.pole.re / wn,
                omega_d: t.pole.im,
                peak: t.residue.norm() / t.pole.re.abs().max(f64::MIN_POSITIVE),
            }
        })
        .collect();
    v.sort_by(|a, b| a.omega_n.partial_cmp(&b.omega_n).unwrap());
    v
}

/// Index (into [`modal_parameters`]) of the mode with the largest peak.
pub fn dominant_mode(modes: &[ModalParameters]) -> Result<usize, VectorFitError> {
    modes
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.peak.partial_cmp(&b.1.peak).unwrap())
        .map(|(i, _)| i)
        .ok_or(VectorFitError::NoMode)
}

/// The excitation quantity of the FRF.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// Force, N.
    Force,
    /// Base acceleration γ, m/s² (the paper's setting).
    Acceleration,
}

/// The response quantity of the FRF (relative to the base for base excitation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    Displacement,
    Velocity,
    Acceleration,
}

impl OutputKind {
    /// Power `p` of `s` relating the output to displacement.
    pub fn power(self) -> i32 {
        match self {
            OutputKind::Displacement => 0,
            OutputKind::Velocity => 1,
            OutputKind::Acceleration => 2,
        }
    }
}

/// Where the mass came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MassSource {
    /// `m = 1/|G|` from the residue (force input).
    Residue,
    /// Supplied by the caller.
    Given,
    /// Not identifiable (acceleration input without a known mass).
    Unidentified,
}

/// SDoF linear part `m x'' + c x' + k x` identified from one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearPart {
    pub mode: ModalParameters,
    /// α = k/m = ω_n², 1/s².
    pub alpha: f64,
    /// δ = c/m = 2ζω_n, 1/s.
    pub delta: f64,
    /// Modal gain `G = 2jω_d r_x` (force input: 1/m; acceleration input: participation factor).
    pub gain: C64,
    /// Phase of `G` relative to the real axis, rad, folded into (−π/2, π/2] (modal complexity; 0 for a real mode).
    pub complexity: f64,
    pub mass: Option<f64>,
    pub stiffness: Option<f64>,
    pub damping: Option<f64>,
    pub mass_source: MassSource,
    /// `1/|G|` for force input (reported even when a known mass overrides it).
    pub residue_mass: Option<f64>,
}

/// The SDoF linear part from one mode (see the module documentation).
pub fn sdof_linear_part(
    mode: &ModalParameters,
    input: InputKind,
    output: OutputKind,
    known_mass: Option<f64>,
) -> Result<LinearPart, VectorFitError> {
    if let Some(m) = known_mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(VectorFitError::BadOption {
                name: "mass",
                value: format!("{m}"),
                reason: "must be finite and > 0 kg",
            });
        }
    }
    let a = mode.pole;
    let rx = mode.residue / a.powi(output.power());
    let gain = C64::new(0.0, 2.0 * mode.omega_d) * rx;
    let mut complexity = gain.arg();
    if complexity > std::f64::consts::FRAC_PI_2 {
        complexity -= std::f64::consts::PI;
    } else if complexity <= -std::f64::consts::FRAC_PI_2 {
        complexity += std::f64::consts::PI;
    }
    let alpha = mode.omega_n * mode.omega_n;
    let delta = -2.0 * a.re;
    let residue_mass = match input {
        InputKind::Force if gain.norm() > 0.0 => Some(1.0 / gain.norm()),
        _ => None,
    };
    let (mass, source) = match (known_mass, residue_mass) {
        (Some(m), _) => (Some(m), MassSource::Given),
        (None, Some(m)) => (Some(m), MassSource::Residue),
        (None, None) => (None, MassSource::Unidentified),
    };
    Ok(LinearPart {
        mode: *mode,
        alpha,
        delta,
        gain,
        complexity,
        mass,
        stiffness: mass.map(|m| m * alpha),
        damping: mass.map(|m| m * delta),
        mass_source: source,
        residue_mass,
    })
}
