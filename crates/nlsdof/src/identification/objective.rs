//! The Eq 31 objective and its analytic Jacobian.
//!
//! ```text
//! cost(θ) = Σ_levels Σ_steps w · ( a_model(Ω; θ, γ)/γ − a_meas/γ )²          (Eq 31)
//! ```
//!
//! `a_model` is the amplitude the model's stepped-sine sweep reaches at each
//! step, following the branch in the same direction as the measured sweep
//! ([`crate::ForcedResponse::sweep`]), so fits through jumps are consistent
//! with what the shaker saw. The model sees the input `gain · γ`.
//!
//! ## Jacobian by implicit differentiation
//! At each root `a` of the first-order harmonic-balance equation
//!
//! ```text
//! F(a, θ) = a² [ S² + Ω² D² ] − (gain γ)² = 0,
//! S = α + g(ρ) β a^ρ − Ω²,   D = δ + g(η) κ Ω^η a^η
//! ```
//!
//! `da/dθ = −(∂F/∂θ)/(∂F/∂a)` with (dividing both by 2a²)
//!
//! ```text
//! ∂F/∂a / (2a)  = S² + Ω²D² + ρ S g(ρ)β a^ρ + η Ω² D g(η) κ (Ωa)^η
//! ∂F/∂α /(2a²)  = S                ∂F/∂δ /(2a²) = Ω² D
//! ∂F/∂β /(2a²)  = S g(ρ) a^ρ       ∂F/∂κ /(2a²) = Ω² D g(η) (Ωa)^η
//! ∂F/∂ρ /(2a²)  = S β a^ρ (g'(ρ) + g(ρ) ln a)
//! ∂F/∂η /(2a²)  = Ω² D κ (Ωa)^η (g'(η) + g(η) ln(Ωa))
//! ∂F/∂gain/(2a²) = −gain γ² / a²
//! ```
//!
//! with `g'(μ) = g(μ)(ψ((3+μ)/2) − ψ(2+μ/2))/2` ([`crate::special`]).
//!
//! ## Optimisation variables
//! Coefficients are log-scaled. The nonlinear coefficients are further
//! expressed at a reference amplitude `A_ref` (the largest measured
//! amplitude) and frequency `Ω_ref` (where it was measured), which
//! decorrelates them from the exponents:
//!
//! ```text
//! u_α = ln α, u_δ = ln δ, u_gain = ln gain, u_ρ = ρ, u_η = η
//! u_β = ln β_ref,  β_ref = g(ρ) β A_ref^ρ           (k_eq/m at A_ref, 1/s²)
//! u_κ = ln κ_ref,  κ_ref = g(η) κ (Ω_ref A_ref)^η   (c_eq/m at A_ref, Ω_ref, 1/s)
//! ```
//!
//! The sign of β is not a variable: [`FitSpec::stiffness_sign`] chooses it
//! (`s = +1` hardening, the default; `s = −1` softening) and
//! `β = s · e^{u_β} / (g(ρ) A_ref^ρ)`, so `u_β = ln(s β_ref)` and the bounds
//! of β_ref are bounds of its magnitude `|β_ref|`. `∂β/∂u_β = β` for either sign.

use super::data::Dataset;
use super::models::*;
use super::parameters::Parameters;
use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use crate::model::NormalisedModel;
use crate::power_law::g_unchecked;
use crate::special::g_derivative;

/// Role of one parameter in a fit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Status {
    /// Not part of the model (value 0).
    Absent,
    /// Held at the given value (natural units).
    Fixed(f64),
    /// Estimated.
    Free,
}

/// Amplitude and frequency at which the nonlinear coefficients are scaled.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Scales {
    /// A_ref, m.
    pub a_ref: f64,
    /// Ω_ref, rad/s.
    pub omega_ref: f64,
}

/// The model structure of one fit: status of each parameter, box bounds
/// of the optimisation variables (in natural units, see the module docs:
/// for β and κ the bounds apply to β_ref and κ_ref), and the start.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitSpec {
    pub kind: ModelKind,
    pub status: [Status; N_PARAMS],
    pub bounds: [(f64, f64); N_PARAMS],
    /// Data-derived start, natural θ (β, κ as true coefficients).
    pub start: Parameters,
    pub scales: Scales,
    /// Sign of the fitted nonlinear stiffness β (when β is free).
    pub stiffness_sign: Sign,
    /// Weight `w_φ` of the phase residuals (`None`: amplitudes only, plain
    /// Eq 31). Used on the curves that carry phases, which must then be
    /// displacement phase **lags** in rad (see [`evaluate_with_phase`]).
    pub phase_weight: Option<f64>,
    /// Which model steady state each measured point is compared with
    /// (default [`ResponseBranch::Sweep`], Eq 31).
    pub branch: ResponseBranch,
    /// Per curve (data order): its measured jump is read as censored
    /// ([`super::output_error::JumpReading`]) under
    /// [`ResponseBranch::Measured`]; missing entries are exact.
    pub censored: Vec<bool>,
    /// Weight of the jump penalties of [`ResponseBranch::Measured`]
    /// (default 1: a fold one step on the wrong side of a measured point
    /// costs as much as the point's own amplitude).
    pub jump_weight: f64,
    /// [`ResponseBranch::Measured`]: the measured phases carry an unknown
    /// constant offset, profiled out ([`super::output_error`]).
    pub profile_phase_offset: bool,
}

/// Which steady state of the model a measured point `(Ω, a)` is compared
/// with in the output error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ResponseBranch {
    /// Eq 31 as published: the state the model's own sweep reaches at `Ω`
    /// (continuation in the measured direction, jumps at the model's folds).
    /// A model fold on the wrong side of a measured step puts that step on
    /// the other branch, so the cost is discontinuous in θ wherever a fold
    /// crosses a measured frequency.
    #[default]
    Sweep,
    /// Branch-free output error: the model's stable steady state at `Ω`
    /// nearest in `ln a` to the measured amplitude (the amplitude itself
    /// when it is 0), sticking (`a = 0`) when there is none. Every measured
    /// point lies on some branch, so at the true θ each is compared with its
    /// own branch whichever way the sweep went; the cost is continuous except
    /// where a fold crosses a measured step *and* that step's branch ends.
    Nearest,
    /// The state the measured sweep was on, continuous in θ
    /// ([`super::output_error`]): the sweep's own state, another stable
    /// state before the model's fold (free when the curve's jump is read as
    /// censored, [`FitSpec::censored`], else charged by its distance to the
    /// fold), or the end of the followed branch after the fold (charged).
    /// Equal to Eq 31 where every point is on the sweep's state, never
    /// above it. [`identify()`](crate::identification::identify()) minimises this.
    Measured,
}

/// Sign of the nonlinear stiffness coefficient β in a fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Sign {
    /// β > 0: the resonance bends to higher frequencies.
    #[default]
    Hardening,
    /// β < 0: the resonance bends to lower frequencies (`k + k_eq(a)`
    /// reaches zero at a finite amplitude: larger amplitudes escape).
    Softening,
}

impl Sign {
    /// `+1` or `−1`.
    pub fn factor(self) -> f64 {
        match self {
            Sign::Hardening => 1.0,
            Sign::Softening => -1.0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Sign::Hardening => "hardening",
            Sign::Softening => "softening",
        }
    }
}

/// Problem-specification errors.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    #[error("unknown parameter '{0}' (expected one of alpha, delta, beta, rho, kappa, eta, gain)")]
    UnknownParameter(String),
    #[error("parameter {name} is not part of the {model} model")]
    NotInModel {
        name: &'static str,
        model: ModelKind,
    },
    #[error("the mass m is not identifiable from acceleration-input data: only ratios to m (alpha = k/m, delta = c/m, beta = k_r/m, kappa = c_e/m) are; give a mass with --mass to convert")]
    MassNotIdentifiable,
    #[error("fixed value {name} = {value} is invalid: {why}")]
    BadFixedValue {
        name: &'static str,
        value: f64,
        why: &'static str,
    },
    #[error("bounds for {name}: [{min}, {max}] are invalid: need finite min < max{extra}")]
    BadBounds {
        name: &'static str,
        min: f64,
        max: f64,
        extra: &'static str,
    },
    #[error("no free parameter left to fit")]
    NothingFree,
    /// An exponent held at 0 with its coefficient free: the term is then a
    /// copy of the linear one (`x|x|^0 = x`, `x'|x'|^0 = x'`), and the
    /// two coefficients cannot be separated by any data.
    #[error("{exponent} held at 0 makes the {coefficient} term a copy of the linear {linear} term ({coefficient} and {linear} cannot be separated): free {exponent}, or {remedy}")]
    CopiesLinear {
        exponent: &'static str,
        coefficient: &'static str,
        linear: &'static str,
        remedy: &'static str,
    },
}

fn is_log(j: usize) -> bool {
    !(j == RHO || j == ETA)
}

impl FitSpec {
    /// Default structure and bounds for `kind`, derived from the data:
    ///
    /// * ω_n and ζ from the peak of the lowest level: `α₀ = Ω_peak²`,
    ///   `δ₀ = γ / (a_peak Ω_peak)` (linear resonance height `γ/(δΩ)`);
    /// * `β_ref,0 = Ω_peak,high² − α₀` from the peak shift up to the highest
    ///   level (at least `0.01 α₀`), `κ_ref,0 = δ₀/2`;
    /// * bounds: α ∈ [(Ω_min/2)², (1.5 Ω_max)²] over the data's frequencies;
    ///   δ ∈ [1e-4 δ₀, 1e2 δ₀]; β_ref ∈ [1e-6 α₀, 20 α₀];
    ///   κ_ref ∈ [1e-6 δ₀, 1e2 δ₀]; ρ ∈ [0, 10]; η ∈ [−1, 8];
    ///   gain ∈ [0.1, 10] (fixed at 1 unless freed).
    pub fn new(kind: ModelKind, data: &Dataset) -> Self {
        let low = lowest_curve(data, true);
        let high = lowest_curve(data, false);
        let (wp, ap, gl) = {
            let c = &data.curves[low];
            let i = c.peak_index();
            (c.omegas[i], c.amplitudes[i].max(f64::MIN_POSITIVE), c.gamma)
        };
        let (wh, _ah) = {
            let c = &data.curves[high];
            let i = c.peak_index();
            (c.omegas[i], c.amplitudes[i])
        };
        let (mut a_ref, mut omega_ref) = (0.0f64, wp);
        let (mut wmin, mut wmax) = (f64::INFINITY, 0.0f64);
        for c in &data.curves {
            for (&w, &a) in c.omegas.iter().zip(&c.amplitudes) {
                if a > a_ref {
                    a_ref = a;
                    omega_ref = w;
                }
                wmin = wmin.min(w);
                wmax = wmax.max(w);
            }
        }
        if !(a_ref > 0.0) {
            a_ref = 1.0;
        }
        let alpha0 = wp * wp;
        let delta0 = gl / (ap * wp);
        let beta_ref0 = (wh * wh - alpha0).max(0.01 * alpha0);
        let kappa_ref0 = 0.5 * delta0;
        let scales = Scales { a_ref, omega_ref };
        let mut status = [
            Status::Free,
            Status::Free,
            Status::Absent,
            Status::Absent,
            Status::Absent,
            Status::Absent,
            Status::Fixed(1.0),
        ];
        let mut start = Parameters {
            alpha: alpha0,
            delta: delta0,
            gain: 1.0,
            ..Parameters::default()
        };
        match kind.stiffness() {
            Term::Absent => {}
            Term::FixedExponent(r) => {
                status[BETA] = Status::Free;
                status[RHO] = Status::Fixed(r);
                start[RHO] = r;
            }
            Term::FreeExponent => {
                status[BETA] = Status::Free;
                status[RHO] = Status::Free;
                start[RHO] = 2.0;
            }
        }
        match kind.damping() {
            Term::Absent => {}
            Term::FixedExponent(e) => {
                status[KAPPA] = Status::Free;
                status[ETA] = Status::Fixed(e);
                start[ETA] = e;
            }
            Term::FreeExponent => {
                status[KAPPA] = Status::Free;
                status[ETA] = Status::Free;
                start[ETA] = 1.0;
            }
        }
        if status[KAPPA] != Status::Absent {
            start[DELTA] = 0.5 * delta0;
        }
        if status[BETA] != Status::Absent {
            start[BETA] = beta_ref0 / (g_unchecked(start[RHO]) * a_ref.powf(start[RHO]));
        }
        if status[KAPPA] != Status::Absent {
            start[KAPPA] =
                kappa_ref0 / (g_unchecked(start[ETA]) * (omega_ref * a_ref).powf(start[ETA]));
        }
        let bounds = [
            ((0.5 * wmin).powi(2), (1.5 * wmax).powi(2)),
            (1e-4 * delta0, 1e2 * delta0),
            (1e-6 * alpha0, 20.0 * alpha0),
            (0.0, 10.0),
            (1e-6 * delta0, 1e2 * delta0),
            (-1.0, 8.0),
            (0.1, 10.0),
        ];
        Self {
            kind,
            status,
            bounds,
            start,
            scales,
            stiffness_sign: Sign::Hardening,
            phase_weight: None,
            branch: ResponseBranch::Sweep,
            censored: Vec::new(),
            jump_weight: 1.0,
            profile_phase_offset: false,
        }
    }

    /// As [`FitSpec::new`] with the stiffness sign chosen. For
    /// [`Sign::Softening`] the start is `β_ref,0 = −clamp(α₀ − Ω_peak,high², 0.01 α₀, 0.5 α₀)`
    /// (the peak shift down to the highest level) and the upper bound of
    /// `|β_ref|` is `0.95 α₀` (at `|β_ref| ≥ α` the backbone
    /// `Ω² = α + g(ρ) β a^ρ` has no positive frequency at A_ref).
    pub fn new_signed(kind: ModelKind, data: &Dataset, sign: Sign) -> Self {
        let mut spec = Self::new(kind, data);
        if sign == Sign::Softening {
            spec.stiffness_sign = sign;
            if spec.status[BETA] != Status::Absent {
                let alpha0 = spec.start[ALPHA];
                let high = &data.curves[lowest_curve(data, false)];
                let wh = high.omegas[high.peak_index()];
                let beta_ref0 = (alpha0 - wh * wh).clamp(0.01 * alpha0, 0.5 * alpha0);
                spec.start[BETA] = -beta_ref0
                    / (g_unchecked(spec.start[RHO]) * spec.scales.a_ref.powf(spec.start[RHO]));
                let (lo, hi) = spec.bounds[BETA];
                spec.bounds[BETA] = (lo, hi.min(0.95 * alpha0));
            }
        }
        spec
    }

    /// Holds parameter `name` at `value` (natural units).
    pub fn fix(&mut self, name: &str, value: f64) -> Result<(), SpecError> {
        let j = self.index(name)?;
        let pname = PARAM_NAMES[j];
        if !value.is_finite() {
            return Err(SpecError::BadFixedValue {
                name: pname,
                value,
                why: "not finite",
            });
        }
        match j {
            ALPHA | GAIN if value <= 0.0 => {
                return Err(SpecError::BadFixedValue {
                    name: pname,
                    value,
                    why: "must be > 0",
                })
            }
            DELTA | KAPPA if value < 0.0 => {
                return Err(SpecError::BadFixedValue {
                    name: pname,
                    value,
                    why: "must be >= 0",
                })
            }
            RHO | ETA if value <= -3.0 => {
                return Err(SpecError::BadFixedValue {
                    name: pname,
                    value,
                    why: "exponent must be > -3",
                })
            }
            BETA if value == 0.0 => {
                return Err(SpecError::BadFixedValue {
                    name: pname,
                    value,
                    why: "must be non-zero (< 0 softening, > 0 hardening; use a model without nonlinear stiffness for 0)",
                })
            }
            _ => {}
        }
        self.status[j] = Status::Fixed(value);
        self.start[j] = value;
        Ok(())
    }

    /// Estimates parameter `name` (e.g. `gain`, or an exponent the model fixes).
    pub fn free(&mut self, name: &str) -> Result<(), SpecError> {
        let j = self.index(name)?;
        self.status[j] = Status::Free;
        Ok(())
    }

    /// Replaces the bounds of `name` (for β and κ: of β_ref and κ_ref; for
    /// β with [`Sign::Softening`]: of |β_ref|).
    pub fn set_bounds(&mut self, name: &str, min: f64, max: f64) -> Result<(), SpecError> {
        let j = self.index(name)?;
        let pname = PARAM_NAMES[j];
        if !(min.is_finite() && max.is_finite() && min < max) {
            return Err(SpecError::BadBounds {
                name: pname,
                min,
                max,
                extra: "",
            });
        }
        if is_log(j) && min <= 0.0 {
            return Err(SpecError::BadBounds {
                name: pname,
                min,
                max,
                extra: " and min > 0 (log-scaled coefficient)",
            });
        }
        if !is_log(j) && min <= -3.0 {
            return Err(SpecError::BadBounds {
                name: pname,
                min,
                max,
                extra: " and min > -3 (exponent)",
            });
        }
        self.bounds[j] = (min, max);
        Ok(())
    }

    fn index(&self, name: &str) -> Result<usize, SpecError> {
        let n = name.trim().to_ascii_lowercase();
        if n == "m" || n == "mass" {
            return Err(SpecError::MassNotIdentifiable);
        }
        let j = param_index(&n).ok_or_else(|| SpecError::UnknownParameter(name.to_string()))?;
        let absent = match j {
            BETA | RHO => self.kind.stiffness() == Term::Absent,
            KAPPA | ETA => self.kind.damping() == Term::Absent,
            _ => false,
        };
        if absent {
            return Err(SpecError::NotInModel {
                name: PARAM_NAMES[j],
                model: self.kind,
            });
        }
        Ok(j)
    }

    /// Indices of the free parameters, in θ order.
    pub fn free_indices(&self) -> Vec<usize> {
        (0..N_PARAMS)
            .filter(|&j| self.status[j] == Status::Free)
            .collect()
    }
}

/// Index of the curve with the lowest (`lowest = true`) or highest γ,
/// preferring up-sweeps.
fn lowest_curve(data: &Dataset, lowest: bool) -> usize {
    let key = |i: usize| {
        let c = &data.curves[i];
        let g = if lowest { c.gamma } else { -c.gamma };
        (
            g,
            if c.direction == SweepDirection::Up {
                0
            } else {
                1
            },
        )
    };
    (0..data.curves.len())
        .min_by(|&a, &b| key(a).partial_cmp(&key(b)).unwrap())
        .unwrap()
}

/// The model amplitudes, residuals and (optionally) the Jacobian with respect
/// to all seven natural parameters.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Model amplitude at each step, m, in data order (curve by curve, increasing Ω).
    pub model: Vec<f64>,
    /// `√w (a_model − a_meas)/γ`.
    pub residuals: Vec<f64>,
    /// `∂r/∂θ` per step for θ = (α, δ, β, ρ, κ, η, gain).
    pub jacobian: Option<Vec<[f64; N_PARAMS]>>,
}

impl Evaluation {
    pub fn cost(&self) -> f64 {
        self.residuals.iter().map(|r| r * r).sum()
    }
}

/// Mass-normalised model of θ ([`Parameters::normalised_model`]).
pub fn normalised_model(theta: &Parameters) -> NormalisedModel {
    theta.normalised_model()
}

/// `da/dθ` at a root `a` of the harmonic-balance equation (see module docs).
pub fn amplitude_derivatives(
    theta: &Parameters,
    gamma: f64,
    omega: f64,
    a: f64,
) -> [f64; N_PARAMS] {
    DerivativeConstants::new(theta).derivatives(gamma, omega, a)
}

/// The θ-only factors of [`amplitude_derivatives`] — `g(ρ)`, `g'(ρ)`,
/// `g(η)`, `g'(η)` (two Γ and two ψ evaluations each) — computed once per
/// objective evaluation instead of once per step.
#[derive(Debug, Clone, Copy)]
pub struct DerivativeConstants {
    theta: Parameters,
    g_rho: f64,
    dg_rho: f64,
    g_eta: f64,
    dg_eta: f64,
}

impl DerivativeConstants {
    pub fn new(theta: &Parameters) -> Self {
        let (g_rho, dg_rho) = if theta[BETA] != 0.0 {
            (g_unchecked(theta[RHO]), g_derivative(theta[RHO]))
        } else {
            (0.0, 0.0)
        };
        let (g_eta, dg_eta) = if theta[KAPPA] != 0.0 {
            (g_unchecked(theta[ETA]), g_derivative(theta[ETA]))
        } else {
            (0.0, 0.0)
        };
        Self {
            theta: *theta,
            g_rho,
            dg_rho,
            g_eta,
            dg_eta,
        }
    }

    /// `da/dθ` at the root `a` for input `gamma` at `omega` (module docs).
    pub fn derivatives(&self, gamma: f64, omega: f64, a: f64) -> [f64; N_PARAMS] {
        let theta = &self.theta;
        let (alpha, delta, beta, rho, kappa, eta, gain) = (
            theta[ALPHA],
            theta[DELTA],
            theta[BETA],
            theta[RHO],
            theta[KAPPA],
            theta[ETA],
            theta[GAIN],
        );
        let w2 = omega * omega;
        let la = a.ln();
        let lwa = (omega * a).ln();
        let (gr, ge) = (self.g_rho, self.g_eta);
        let ar = if beta != 0.0 { (rho * la).exp() } else { 0.0 };
        let wae = if kappa != 0.0 { (eta * lwa).exp() } else { 0.0 };
        let gbar = gr * beta * ar;
        let gkw = ge * kappa * wae;
        let s = alpha + gbar - w2;
        let d = delta + gkw;
        let fa = s * s + w2 * d * d + rho * s * gbar + eta * w2 * d * gkw;
        let mut h = [0.0; N_PARAMS];
        h[ALPHA] = s;
        h[DELTA] = w2 * d;
        if beta != 0.0 {
            h[BETA] = s * gr * ar;
            h[RHO] = s * beta * ar * (self.dg_rho + gr * la);
        }
        if kappa != 0.0 {
            h[KAPPA] = w2 * d * ge * wae;
            h[ETA] = w2 * d * kappa * wae * (self.dg_eta + ge * lwa);
        }
        h[GAIN] = -gain * gamma * gamma / (a * a);
        let mut out = [0.0; N_PARAMS];
        for j in 0..N_PARAMS {
            out[j] = -a * h[j] / fa;
        }
        out
    }

    /// `dφ/dθ` of the phase lag `φ = atan2(ΩD, S)` at the root `a`, given
    /// `da/dθ` ([`Self::derivatives`]); see [`evaluate_with_phase`].
    pub fn phase_derivatives(&self, omega: f64, a: f64, da: &[f64; N_PARAMS]) -> [f64; N_PARAMS] {
        let theta = &self.theta;
        let (alpha, delta, beta, rho, kappa, eta) = (
            theta[ALPHA],
            theta[DELTA],
            theta[BETA],
            theta[RHO],
            theta[KAPPA],
            theta[ETA],
        );
        let la = a.ln();
        let lwa = (omega * a).ln();
        let (gr, ge) = (self.g_rho, self.g_eta);
        let ar = if beta != 0.0 { (rho * la).exp() } else { 0.0 };
        let wae = if kappa != 0.0 { (eta * lwa).exp() } else { 0.0 };
        let gbar = gr * beta * ar;
        let gkw = ge * kappa * wae;
        let p = alpha + gbar - omega * omega;
        let q = omega * (delta + gkw);
        let den = p * p + q * q;
        // ∂S/∂θ and ∂(ΩD)/∂θ at fixed a
        let mut ds = [0.0; N_PARAMS];
        let mut dq = [0.0; N_PARAMS];
        ds[ALPHA] = 1.0;
        dq[DELTA] = omega;
        if beta != 0.0 {
            ds[BETA] = gr * ar;
            ds[RHO] = beta * ar * (self.dg_rho + gr * la);
        }
        if kappa != 0.0 {
            dq[KAPPA] = omega * ge * wae;
            dq[ETA] = omega * kappa * wae * (self.dg_eta + ge * lwa);
        }
        let ds_da = rho * gbar / a;
        let dq_da = omega * eta * gkw / a;
        let mut out = [0.0; N_PARAMS];
        for j in 0..N_PARAMS {
            let dsj = ds[j] + ds_da * da[j];
            let dqj = dq[j] + dq_da * da[j];
            out[j] = (p * dqj - q * dsj) / den;
        }
        out
    }
}

/// The measured amplitude at a curve's first step in sweep order (the
/// lowest frequency of an up-sweep, the highest of a down-sweep).
pub fn first_amplitude(c: &super::data::Curve) -> f64 {
    match c.direction {
        SweepDirection::Up => c.amplitudes[0],
        SweepDirection::Down => c.amplitudes[c.amplitudes.len() - 1],
    }
}

/// Model amplitudes of every curve at θ (branch-following sweeps), in
/// data order; sticking points give 0.
///
/// **First step.** Where several stable steady states coexist at a curve's
/// first step (in sweep order) the model starts on the one nearest (in
/// `ln a`) to the measured first amplitude
/// ([`crate::ForcedResponse::sweep_from`], sweep rule 1′): the measurement
/// says which state the structure was on, whereas the state reached "from
/// rest" depends on how the run was started (from rest, or continuing a
/// previous run), which the data do not record. This is the case for
/// down-sweeps starting inside the hysteresis window of a hardening level
/// (the upper branch reaches beyond the highest measured frequency), for
/// up-sweeps of softening systems starting inside theirs, and for many of
/// the extreme parameter sets a global search visits. It costs nothing
/// (no slow-flow integration); where the first step has one stable state
/// the rule changes nothing.
pub fn model_amplitudes(data: &Dataset, theta: &Parameters) -> Result<Vec<Vec<f64>>, SolveError> {
    Ok(model_response(data, theta)?
        .into_iter()
        .map(|c| c.into_iter().map(|(a, _)| a).collect())
        .collect())
}

/// The first-order HB response of `model` at curve `c`'s input `gain·γ`.
fn curve_response(
    model: &NormalisedModel,
    theta: &Parameters,
    c: &super::data::Curve,
) -> Result<ForcedResponse, SolveError> {
    ForcedResponse::from_normalised(model, theta[GAIN] * c.gamma, Formulation::HarmonicBalance)
}

/// The model's response at every measured step under `branch`: `(a, φ)`
/// per step in data order, sticking points `(0, 0)`
/// ([`ResponseBranch::Sweep`]: [`model_response`]).
pub fn branch_response(
    data: &Dataset,
    theta: &Parameters,
    branch: ResponseBranch,
) -> Result<Vec<Vec<(f64, f64)>>, SolveError> {
    if branch != ResponseBranch::Nearest {
        return model_response(data, theta);
    }
    let model = normalised_model(theta);
    data.map_curves(|_, c| {
        let r = curve_response(&model, theta, c)?;
        c.omegas
            .iter()
            .zip(&c.amplitudes)
            .map(|(&w, &a_meas)| {
                let set = r.steady_states_near(w, a_meas)?;
                let distance = |a: f64| {
                    if a_meas > 0.0 {
                        (a / a_meas).ln().abs()
                    } else {
                        a
                    }
                };
                let stable = set.roots.iter().any(|s| s.stable);
                Ok(set
                    .roots
                    .iter()
                    .filter(|s| s.stable || !stable)
                    .min_by(|x, y| distance(x.amplitude).total_cmp(&distance(y.amplitude)))
                    .map_or((0.0, 0.0), |s| (s.amplitude, s.phase)))
            })
            .collect()
    })
}

/// As [`model_amplitudes`], with the model's phase lag (rad) at each step:
/// `(a, φ)` per step; sticking points give `(0, 0)`.
pub fn model_response(
    data: &Dataset,
    theta: &Parameters,
) -> Result<Vec<Vec<(f64, f64)>>, SolveError> {
    Ok(model_sweeps(data, theta)?
        .into_iter()
        .map(|c| c.0)
        .collect())
}

/// The model's first jump on one curve's sweep: `(Ω, a before the jump)`.
pub type FirstJump = Option<(f64, f64)>;

/// [`model_response`] with each curve's first jump (in sweep order), from
/// the same sweeps (the jump residuals reuse them instead of sweeping again).
pub fn model_sweeps(
    data: &Dataset,
    theta: &Parameters,
) -> Result<Vec<(Vec<(f64, f64)>, FirstJump)>, SolveError> {
    let model = normalised_model(theta);
    data.map_curves(|_, c| {
        let r = curve_response(&model, theta, c)?;
        let sw = r.sweep_from(&c.omegas, c.direction, first_amplitude(c))?;
        let mut out: Vec<(f64, f64)> = sw
            .points
            .iter()
            .map(|p| {
                if p.sticking {
                    (0.0, 0.0)
                } else {
                    (p.amplitude, p.phase)
                }
            })
            .collect();
        if c.direction == SweepDirection::Down {
            out.reverse();
        }
        let jump = sw.jumps.first().map(|j| (j.omega, j.amplitude_before));
        Ok((out, jump))
    })
}

/// Wraps an angle to (−π, π] (kept here so that the objective does not
/// depend on the equation-error module, which depends on it).
fn wrap_angle(x: f64) -> f64 {
    let y = x.rem_euclid(std::f64::consts::TAU);
    if y > std::f64::consts::PI {
        y - std::f64::consts::TAU
    } else {
        y
    }
}

/// Evaluates Eq 31's residuals at θ, with the Jacobian if `jacobian`.
pub fn evaluate(
    data: &Dataset,
    theta: &Parameters,
    jacobian: bool,
) -> Result<Evaluation, SolveError> {
    evaluate_with_phase(data, theta, jacobian, None)
}

/// Eq 31's residuals, followed (when `phase_weight = Some(w_φ)`) by one
/// phase residual per step of every curve that carries phases:
///
/// ```text
/// r_φ = √(w_φ w) · a_meas · wrap(φ_model − φ_meas) / γ
/// ```
///
/// `a_meas Δφ/γ` is the size of the complex response error that a phase
/// error Δφ makes, so with `w_φ = 1` an amplitude error and a phase error of
/// the same complex size weigh the same. `φ` is the displacement phase lag
/// (rad); points where the model sticks have no phase residual (0).
/// `dφ/dθ` follows from `tan φ = Ω D / S` (module docs):
///
/// ```text
/// dφ = (S d(ΩD) − ΩD dS) / (S² + Ω² D²),
/// dS = ∂S/∂θ + (ρ g(ρ) β a^{ρ−1}) da,   d(ΩD) = Ω ∂D/∂θ + Ω (η g(η) κ Ω^η a^{η−1}) da.
/// ```
pub fn evaluate_with_phase(
    data: &Dataset,
    theta: &Parameters,
    jacobian: bool,
    phase_weight: Option<f64>,
) -> Result<Evaluation, SolveError> {
    evaluate_branch(data, theta, jacobian, phase_weight, ResponseBranch::Sweep)
}

/// [`evaluate_with_phase`] with the model's response taken on `branch`
/// ([`branch_response`]); the residuals and their derivatives are the same
/// functions of the compared state `(a, φ)`, whichever root it is.
pub fn evaluate_branch(
    data: &Dataset,
    theta: &Parameters,
    jacobian: bool,
    phase_weight: Option<f64>,
    branch: ResponseBranch,
) -> Result<Evaluation, SolveError> {
    if branch == ResponseBranch::Measured {
        let opts = super::output_error::MatchOptions {
            phase_weight,
            ..super::output_error::MatchOptions::amplitudes()
        };
        return Ok(super::output_error::evaluate_measured(data, theta, jacobian, &opts)?.0);
    }
    let resp = branch_response(data, theta, branch)?;
    Ok(evaluation_of(data, theta, &resp, jacobian, phase_weight))
}

/// The residuals of `spec`'s objective at θ (its response rule, phase
/// weight, jump readings and jump weight).
pub fn evaluate_spec(
    data: &Dataset,
    spec: &FitSpec,
    theta: &Parameters,
    jacobian: bool,
) -> Result<Evaluation, SolveError> {
    if spec.branch == ResponseBranch::Measured {
        return Ok(super::output_error::evaluate_measured(
            data,
            theta,
            jacobian,
            &super::output_error::MatchOptions::of(spec),
        )?
        .0);
    }
    let resp = branch_response(data, theta, spec.branch)?;
    Ok(evaluation_of(
        data,
        theta,
        &resp,
        jacobian,
        spec.phase_weight,
    ))
}

/// [`evaluate_with_phase`] with the curves' first model jumps (for the jump
/// residuals), from one sweep per curve.
pub fn evaluate_with_jumps(
    data: &Dataset,
    theta: &Parameters,
    jacobian: bool,
    phase_weight: Option<f64>,
) -> Result<(Evaluation, Vec<FirstJump>), SolveError> {
    let (resp, jumps): (Vec<_>, Vec<_>) = model_sweeps(data, theta)?.into_iter().unzip();
    Ok((
        evaluation_of(data, theta, &resp, jacobian, phase_weight),
        jumps,
    ))
}

fn evaluation_of(
    data: &Dataset,
    theta: &Parameters,
    resp: &[Vec<(f64, f64)>],
    jacobian: bool,
    phase_weight: Option<f64>,
) -> Evaluation {
    let n = data.len();
    let mut model = Vec::with_capacity(n);
    let mut residuals = Vec::with_capacity(n);
    let mut jac = jacobian.then(|| Vec::with_capacity(n));
    let dc = DerivativeConstants::new(theta);
    for (c, am) in data.curves.iter().zip(resp) {
        for i in 0..c.omegas.len() {
            let sw = c.weights[i].sqrt();
            let a = am[i].0;
            model.push(a);
            residuals.push(sw * (a - c.amplitudes[i]) / c.gamma);
            if let Some(j) = jac.as_mut() {
                let row = if a > 0.0 {
                    let mut d = dc.derivatives(c.gamma, c.omegas[i], a);
                    for v in d.iter_mut() {
                        *v *= sw / c.gamma;
                    }
                    d
                } else {
                    [0.0; N_PARAMS]
                };
                j.push(row);
            }
        }
    }
    if let Some(wp) = phase_weight {
        for (c, am) in data.curves.iter().zip(resp) {
            let Some(ph) = &c.phases else { continue };
            for i in 0..c.omegas.len() {
                let k = (wp * c.weights[i]).sqrt() * c.amplitudes[i] / c.gamma;
                let (a, phi) = am[i];
                if a > 0.0 {
                    residuals.push(k * wrap_angle(phi - ph[i]));
                } else {
                    residuals.push(0.0);
                }
                if let Some(j) = jac.as_mut() {
                    let row = if a > 0.0 {
                        let da = dc.derivatives(c.gamma, c.omegas[i], a);
                        let mut d = dc.phase_derivatives(c.omegas[i], a, &da);
                        for v in d.iter_mut() {
                            *v *= k;
                        }
                        d
                    } else {
                        [0.0; N_PARAMS]
                    };
                    j.push(row);
                }
            }
        }
    }
    Evaluation {
        model,
        residuals,
        jacobian: jac,
    }
}

/// The fit problem in optimisation variables `u` (module docs).
#[derive(Debug)]
pub struct Problem<'a> {
    pub data: &'a Dataset,
    pub spec: &'a FitSpec,
    pub free: Vec<usize>,
    /// The evaluation with the Jacobian of the lowest cost the solver has
    /// asked for, with its θ ([`Self::kept_evaluation`]).
    kept: std::sync::Mutex<Option<(Parameters, f64, Evaluation)>>,
}

impl Clone for Problem<'_> {
    /// The same problem; the kept evaluation is not copied.
    fn clone(&self) -> Self {
        Self {
            data: self.data,
            spec: self.spec,
            free: self.free.clone(),
            kept: std::sync::Mutex::new(None),
        }
    }
}

impl<'a> Problem<'a> {
    pub fn new(data: &'a Dataset, spec: &'a FitSpec) -> Result<Self, SpecError> {
        let free = spec.free_indices();
        if free.is_empty() {
            return Err(SpecError::NothingFree);
        }
        Ok(Self {
            data,
            spec,
            free,
            kept: std::sync::Mutex::new(None),
        })
    }

    /// [`evaluate_spec`] with the Jacobian at `th`, taken from the
    /// evaluation the solver kept when it was made at exactly this θ (the
    /// lowest-cost one it asked for: where a solve ends), else evaluated.
    /// The same numbers either way (`evaluate_spec` is a function of its
    /// arguments); the solve's result is assessed without sweeping every
    /// curve again (measured on the 24 °C beam's generalised fit: 12 of the
    /// 73 repeated sweeps of every curve of the all-points stage).
    pub fn evaluation_at(&self, th: &Parameters) -> Result<Evaluation, SolveError> {
        let kept = self.kept.lock().ok().and_then(|mut k| {
            k.take_if(|(t, _, _)| (0..N_PARAMS).all(|j| t[j].to_bits() == th[j].to_bits()))
        });
        match kept {
            Some((_, _, e)) => Ok(e),
            None => evaluate_spec(self.data, self.spec, th, true),
        }
    }

    /// Keeps `e` (at `th`, with the Jacobian) when it is the lowest cost
    /// seen so far (ties: the first).
    fn keep_if_lowest(&self, th: &Parameters, e: &Evaluation) {
        let cost = e.cost();
        if !cost.is_finite() {
            return;
        }
        if let Ok(mut k) = self.kept.lock() {
            if k.as_ref().is_none_or(|(_, c, _)| cost < *c) {
                *k = Some((*th, cost, e.clone()));
            }
        }
    }

    fn value_or(&self, j: usize, u: &[f64]) -> f64 {
        match self.spec.status[j] {
            Status::Absent => 0.0,
            Status::Fixed(v) => v,
            Status::Free => {
                let k = self.free.iter().position(|&f| f == j).unwrap();
                u[k]
            }
        }
    }

    fn beta_scale(&self, rho: f64) -> f64 {
        g_unchecked(rho) * self.spec.scales.a_ref.powf(rho)
    }

    fn kappa_scale(&self, eta: f64) -> f64 {
        g_unchecked(eta) * (self.spec.scales.omega_ref * self.spec.scales.a_ref).powf(eta)
    }

    /// θ from u.
    pub fn theta(&self, u: &[f64]) -> Parameters {
        let mut th = Parameters::default();
        for j in [ALPHA, DELTA, RHO, ETA, GAIN] {
            let v = self.value_or(j, u);
            th[j] = if self.spec.status[j] == Status::Free && is_log(j) {
                v.exp()
            } else {
                v
            };
        }
        for (j, e, sc) in [(BETA, RHO, 0), (KAPPA, ETA, 1)] {
            th[j] = match self.spec.status[j] {
                Status::Free => {
                    let mut v = self.value_or(j, u).exp();
                    if j == BETA {
                        v *= self.spec.stiffness_sign.factor();
                    }
                    v / if sc == 0 {
                        self.beta_scale(th[e])
                    } else {
                        self.kappa_scale(th[e])
                    }
                }
                _ => self.value_or(j, u),
            };
        }
        th
    }

    /// u from θ (inverse of [`Self::theta`] on the free entries).
    pub fn u_of(&self, th: &Parameters) -> Vec<f64> {
        self.free
            .iter()
            .map(|&j| match j {
                RHO | ETA => th[j],
                BETA => {
                    (self.spec.stiffness_sign.factor() * th[BETA] * self.beta_scale(th[RHO])).ln()
                }
                KAPPA => (th[KAPPA] * self.kappa_scale(th[ETA])).ln(),
                _ => th[j].ln(),
            })
            .collect()
    }

    /// Box bounds in u.
    pub fn u_bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.free
            .iter()
            .map(|&j| {
                let (lo, hi) = self.spec.bounds[j];
                if is_log(j) {
                    (lo.ln(), hi.ln())
                } else {
                    (lo, hi)
                }
            })
            .unzip()
    }

    /// `∂θ_j/∂u_k` (7 × n_free, row-major).
    pub fn dtheta_du(&self, th: &Parameters) -> Vec<[f64; N_PARAMS]> {
        // column k for each free k, stored as [f64; 7]
        let mut cols = vec![[0.0; N_PARAMS]; self.free.len()];
        let pos = |j: usize| self.free.iter().position(|&f| f == j);
        for (k, &j) in self.free.iter().enumerate() {
            cols[k][j] = if is_log(j) { th[j] } else { 1.0 };
        }
        if let (Some(_), Some(kr)) = (pos(BETA), pos(RHO)) {
            let rho = th[RHO];
            cols[kr][BETA] =
                -th[BETA] * (g_derivative(rho) / g_unchecked(rho) + self.spec.scales.a_ref.ln());
        }
        if let (Some(_), Some(ke)) = (pos(KAPPA), pos(ETA)) {
            let eta = th[ETA];
            cols[ke][KAPPA] = -th[KAPPA]
                * (g_derivative(eta) / g_unchecked(eta)
                    + (self.spec.scales.omega_ref * self.spec.scales.a_ref).ln());
        }
        cols
    }
}

/// Whether the first step of some curve (in sweep order) has more than one
/// stable steady state. (No longer used by the optimiser: such θ are
/// evaluated with the measured first amplitude selecting the state, see
/// [`model_amplitudes`].)
pub fn ambiguous_start(data: &Dataset, theta: &Parameters) -> bool {
    let model = normalised_model(theta);
    data.curves.iter().any(|c| {
        let w = match c.direction {
            SweepDirection::Up => c.omegas[0],
            SweepDirection::Down => c.omegas[c.omegas.len() - 1],
        };
        match ForcedResponse::from_normalised(
            &model,
            theta[GAIN] * c.gamma,
            Formulation::HarmonicBalance,
        )
        .and_then(|r| r.steady_states(w))
        {
            Ok(set) => set.roots.iter().filter(|s| s.stable).count() > 1,
            Err(_) => true,
        }
    })
}

impl Problem<'_> {
    /// Residuals and `∂r/∂u` (row-major) of an evaluation at `th = θ(u)`.
    pub(crate) fn residuals_and_jacobian_of(
        &self,
        th: &Parameters,
        e: Evaluation,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        use rayon::prelude::*;
        let cols = self.dtheta_du(th);
        let n = self.free.len();
        let jt = e.jacobian.as_ref()?;
        // (rows in parallel: thousands of rows on every point, between two
        // evaluations whose sweeps are parallel; each entry is the same sum)
        let mut j = vec![0.0; jt.len() * n];
        if n > 0 {
            j.par_chunks_mut(n)
                .zip(jt.par_iter())
                .with_min_len(256)
                .for_each(|(out, row)| {
                    for (o, col) in out.iter_mut().zip(&cols) {
                        let mut s = 0.0;
                        for p in 0..N_PARAMS {
                            if col[p] != 0.0 {
                                s += row[p] * col[p];
                            }
                        }
                        *o = if s.is_finite() { s } else { 0.0 };
                    }
                });
        }
        e.residuals
            .iter()
            .all(|r| r.is_finite())
            .then_some((e.residuals, j))
    }
}

impl super::levenberg_marquardt::LeastSquares for Problem<'_> {
    /// The sweeps dominate; the derivatives are analytic and cheap.
    fn jacobian_with_trials(&self) -> bool {
        true
    }

    fn n_params(&self) -> usize {
        self.free.len()
    }

    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        let th = self.theta(u);
        let e = evaluate_spec(self.data, self.spec, &th, false).ok()?;
        e.residuals
            .iter()
            .all(|r| r.is_finite())
            .then_some(e.residuals)
    }

    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let th = self.theta(u);
        let e = evaluate_spec(self.data, self.spec, &th, true).ok()?;
        self.keep_if_lowest(&th, &e);
        self.residuals_and_jacobian_of(&th, e)
    }
}
