//! What stepped-sine data say before any model is fitted (`nlsdof
//! inspect`): per-level resonance, damping and jumps, the homogeneity of
//! the levels against their noise, and the stiffness and damping laws read
//! model-free from the resonance points, with a recommendation of the model
//! family. Pure mathematics on a [`Dataset`]; no model is fitted to the
//! curves, no harmonic balance is solved.
//!
//! Notation (mass-normalised, SI): `α = k/m` (rad²/s²), `δ = c/m` (1/s),
//! `β = k_r/m`, `κ = c_e/m`, input level `γ` (m/s², zero-to-peak), response
//! amplitude `a` (m, zero-to-peak), frequency `Ω` (rad/s; Hz in messages).
//!
//! # The first-order harmonic balance at resonance
//!
//! With the equivalent coefficients of the paper (Eq 9, Eq 22, shape factor
//! `g(μ)` of Eq 12/24) the steady state of Eq 29 obeys
//!
//! ```text
//! a² [ (α_eff(a) − Ω²)² + Ω² δ_eff(a, Ω)² ] = γ²                  (the algebraic form of Eq 30)
//! α_eff(a)    = α + g(ρ) β |a|^ρ                                   (Eq 9 / m)
//! δ_eff(a, Ω) = δ + g(η) κ |Ω a|^η                                 (Eq 22 / m)
//! ```
//!
//! At **phase quadrature** (lag 90°) the stiffness term vanishes,
//! `α_eff(a_q) = Ω_q²`: the point lies on the backbone (Eq 30 with γ = 0),
//! and `a_q Ω_q δ_eff = γ`. Hence, one point per level,
//!
//! ```text
//! backbone:  Ω_r² − ω₀² = g(ρ) β a_r^ρ                  (ω₀² = α)
//! damping:   δ_eq ≡ γ / (a_r Ω_r) = δ + g(η) κ (Ω_r a_r)^η
//! ```
//!
//! two power laws in the measured resonance amplitude `a_r` and velocity
//! amplitude `V = Ω_r a_r` (m/s), fitted across the levels (see *The
//! regressions*). Coulomb friction (Eq 27–28, η = −1) shows as
//! `δ_eq − δ ∝ 1/V`.
//!
//! At the **amplitude peak** (`∂a/∂Ω = 0` along the curve) differentiating
//! the balance at fixed `a` gives
//!
//! ```text
//! α_eff(a_p) − Ω_p² = δ_eff (δ + (1 + η) c_eq) / 2,     c_eq = g(η) κ (Ω_p a_p)^η,
//! ```
//!
//! (for a linear SDoF the familiar `Ω_p² = ω_n² − δ²/2`). A level without
//! phase therefore enters the backbone at `Ω_p² + δ_eq (δ₀ + (1 + η)(δ_eq −
//! δ₀))/2`: first with `η = 0`, `δ₀ = δ_eq` (i.e. `+ δ_eq²/2`), then again
//! with the fitted damping law. `γ/(a_p Ω_p)` differs from `δ_eff` by
//! `O(ζ²)` only, so the damping estimator is the same for peaks and
//! quadrature points. On a curve whose sweep jumps down, the peak is the
//! last point before the jump (the top of the branch that ends, within one
//! step of the fold, right of the backbone by `(ζΩ)²/(2 Ω a dΩ_bb/da)` in
//! the near-resonance form): it is used as measured.
//!
//! # Per level
//!
//! * **Peak**: the largest amplitude (on a curve that jumps down, of the
//!   branch before the jump), refined by a local fit of `1/a²` against
//!   `Ω²` — exact for a linear SDoF, whose `γ²/a² = (α − Ω²)² + δ² Ω²` is a
//!   parabola in `Ω²`. On exact data the fit is the parabola through the
//!   top three points; with noise its window is widened to where the curve
//!   is [`PEAK_WINDOW_SIGMAS`] local noise standard deviations below its
//!   top, at most to [`PEAK_WINDOW_FLOOR`] of it (with 1 % noise, windows
//!   only 4 standard deviations deep made the vertex frequency scatter
//!   2.8–4.6 times its propagated noise over 100 seeds), and then
//!   recentred twice on the fitted vertex (a window cut by one noisy point
//!   no longer moves it). The fit is a cubic in the sheared coordinate
//!   `Ω² − B a^p` of the first pass's backbone law (second pass, jump-free
//!   curves): a nonlinear stiffness with linear damping is then exactly a
//!   parabola again, `γ²/a² = (α_eff(a_ref) − u′)² + δ²Ω²`, and the cubic
//!   term takes up what lean is left. (A parabola without the shear over
//!   the wide window put the vertex of a leaning peak 22 noise standard
//!   deviations low on average; with the shear and the cubic the damping
//!   points of the noisy coverage sets err by 1.07–1.18 times their
//!   propagated noise, RMS per level.)
//! * **Phase quadrature** (where phases are given): the 90° crossing of the
//!   lag, interpolated in the exact linear-SDoF coordinates
//!   `−Ω cot φ = (Ω² − α)/δ` (a straight line in `Ω²`) through the points
//!   within [`QUADRATURE_WINDOW_SIGMAS`] phase-noise standard deviations of 90°
//!   (at least the two around it, at most [`QUADRATURE_WINDOW_DEG`], never
//!   across a jump).
//! * **Damping**: half-power width where the curve has no jump and both
//!   `a_p/√2` points lie in the band (interpolated in `(Ω², 1/a²)`); for a
//!   linear SDoF they satisfy `(Ω₂² − Ω₁²)²/4 = δ² (Ω_p² + δ²/4)`, solved
//!   for `δ` (→ `δ ≈ Ω₂ − Ω₁`, `ζ ≈ (Ω₂ − Ω₁)/(2Ω_r)` for light damping).
//!   Otherwise the **phase slope** at quadrature: from
//!   `tan φ = δΩ/(α − Ω²)`, `dφ/dΩ = [δ(α − Ω²) + 2δΩ²]/[(α − Ω²)² + δ²Ω²]`,
//!   which at `Ω = ω_n` is `2/δ = 1/(ζ ω_n)`; it is read as the slope `1/δ`
//!   of `−Ω cot φ` against `Ω²` over the points within
//!   [`SLOPE_WINDOW_DEG`] of 90° (exact for a linear SDoF).
//! * **Jumps**: [`Curve::measured_jump`] with ratio
//!   [`InspectOptions::min_jump_ratio`]; a drop ends the followed branch
//!   (the peak is before it), a rise lands on the upper branch at a fold
//!   (that curve's maximum is not a resonance and is not used).
//! * **Noise**: [`noise::local_noise`] applied to the amplitudes
//!   themselves: its pseudo-residuals are the residuals of the local linear
//!   smoother through each step's two neighbours, so the data alone give
//!   the noise `σ_i² = c (a_i² + b)` (relative part and floor). Where a
//!   peak is only a few steps wide its curvature adds to them (noise.rs
//!   caps such steps; what remains overestimates the noise, which makes the
//!   homogeneity test conservative). Measured on 1 % relative noise, 400
//!   steps: 0.0089–0.0104 per curve, linear or not; 60–100 steps across a
//!   peak of ζ = 0.3 %: 0.0088–0.0140. (A global parabola of `1/a²` in `Ω²`
//!   per branch, exact for a linear SDoF, was tried first: on nonlinear
//!   curves its misfit made the estimate 0.0057–0.0099.) The phase noise
//!   is the same estimator on the lag (constant scale). The noise is
//!   propagated (linearised, steps independent) into every peak,
//!   quadrature point and damping value.
//!
//! # Homogeneity
//!
//! Per level the resonance point (quadrature where a curve of the level
//! has one, else the peak; a level with both sweep directions at a regular
//! peak averages them by inverse variance). The **linearity index** is
//!
//! ```text
//! I = √( (χ²_h + χ²_Ω) / (2 (L − 1)) ),   χ²_h = Σ_l (h_l − h̄)² / σ_h,l²,  h = a_r/γ,
//!                                         χ²_Ω = Σ_l (Ω_l − Ω̄)² / σ_Ω,l²
//! ```
//!
//! (weighted means, `L` levels): the spread of the normalised peaks and of
//! the resonance frequencies in units of what the noise allows; `I ≈ 1`
//! when the curves are homogeneous (linear) within the noise. It is
//! compared with its 99.9 % point under that hypothesis (exact χ² quantile,
//! [`chi2_upper`]). The same test on `Ω_r` alone says whether the
//! stiffness changes, on `δ_eq` alone whether the damping does (`a/γ`
//! alone mixes both: it is `1/(Ω δ_eq)`).
//!
//! # The regressions
//!
//! Both laws are `y = c + B x^p` (backbone: `x = a_r`, `y = Ω_r²`,
//! `c = ω₀² ≥ 0`, `B = g(ρ) β` of either sign; damping: `x = V`, `y = δ_eq`,
//! `c = δ₀ ≥ 0`, `B = g(η) κ ≥ 0`). Each point's variance is the effective
//! variance `var y − 2 f′ cov(x, y) + f′² var x` of its residual (errors in
//! both coordinates: for the damping `y = γ/x` exactly, so a velocity error
//! moves the point along the hyperbola). At a fixed exponent the law is
//! linear in `c` and `B`, so the exponent is found by its profile: the
//! weighted linear fit (with `c` held at its bound when it would cross it)
//! on a grid of 0.05 over [`EXPONENT_RANGE`], refined by golden section,
//! the weights updated from `f′` four times — the 1-D scan with the fit
//! inside, on the original scale rather than log–log (the log of `y − c`
//! needs `c` below every point, and the scan over `c` then has to
//! bracket the points' own noise). With `s² = χ²_min/(L − 3)`:
//!
//! * the standard errors are `√(s² (JᵀWJ)⁻¹)` in `(c, B, p)`;
//! * the 95 % interval of the exponent is its **profile-t** interval
//!   `{p : χ²(p) − χ²_min ≤ t₀.₉₇₅(L − 3)² s²}` (Bates & Watts 1988, §6.1):
//!   the covariance interval `p ± t·se` for a model linear in its
//!   parameters, and still right when the intercept sits at its bound or
//!   the law bends (a noisy set whose fit held `δ₀ = 0` gave η = 0.19 with
//!   the covariance interval [0.174, 0.210] against the truth 0.567; its
//!   profile-t interval holds the truth).
//!   Student t quantiles are tabulated exactly up to 30 degrees of freedom.
//!   With three levels the exponent is given without an interval, with
//!   fewer not at all; an interval that reaches an end of the range says
//!   so ([`LawFit::interval_open`]).
//!
//! # Recommendation
//!
//! The stiffness is nonlinear when `Ω_r` changes beyond the noise or a
//! curve jumps (folds need a bent backbone); its sign is the fitted law's
//! (without a law: the jumps', or the trend of `Ω_r` with `a_r`). The
//! exponent is *pinned* when its 95 % interval is at most
//! ±[`PINNED_HALF_WIDTH`] wide; `ρ ≈ 2` (Duffing-like) when the interval
//! holds 2, `η ≈ 1` (quadratic) or `η ≈ −1` (Coulomb-like) likewise. A
//! sweep **left its branch early** when the last point before a drop jump
//! lies before the backbone (in sweep direction; the backbone fitted to
//! the other levels when four or more remain) by more than three standard
//! deviations of the point's frequency and of the backbone's scatter about
//! its points, plus one step: a sweep that reached its peak leaves from the
//! far side of the backbone (lag past 90°, between the peak and the fold),
//! so a drop from the near side means it never got there. With phases the
//! same reads directly: the lag before the jump had not reached 90° (less
//! [`EARLY_LAG_TOLERANCE_DEG`]). Such
//! levels are left out of the laws.

use super::data::{Curve, Dataset};
use super::equation_error::PhaseConvention;
use super::noise;
use crate::harmonic_balance::SweepDirection;
use crate::power_law::g_unchecked;
use serde::{Deserialize, Serialize};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;
const HALF_PI: f64 = std::f64::consts::FRAC_PI_2;

/// Default smallest step-to-step amplitude ratio of a jump. Lower than the
/// fit's 2: a jump up onto the upper branch can be small (ratio 1.44 on a
/// ρ = 3 down-sweep, 1.5 on softening up-sweeps), and a jump that is not
/// seen puts the peak's parabola across it. [`Curve::measured_jump`] also
/// requires the step to stand out from the steps the other way, which
/// keeps the coarse flanks of a sharp peak from counting.
pub const DEFAULT_JUMP_RATIO: f64 = 1.2;

/// The peak parabola's top points reach at most down to this fraction of
/// the maximum amplitude.
pub const PEAK_WINDOW_FLOOR: f64 = 0.8;

/// The peak parabola's window is widened on each side until its end point
/// is this many local noise standard deviations below the maximum.
pub const PEAK_WINDOW_SIGMAS: f64 = 20.0;

/// Points of a sweep on the branch a jump ends (the first step of a
/// sweep that jumps is a start transient; measured on the cantilever beam,
/// whose up-runs rise by 1.2 between their first two steps).
pub const MIN_POINTS_BEFORE_JUMP: usize = 3;

/// Largest half-width (degrees of lag around 90°) of the points that place
/// the quadrature crossing: the window is [`QUADRATURE_WINDOW_SIGMAS`]
/// phase-noise standard deviations wide, at least the two points around the
/// crossing, at most this (a line through a window that bends biases the
/// crossing).
pub const QUADRATURE_WINDOW_DEG: f64 = 10.0;

/// Half-width of the quadrature window in phase-noise standard deviations.
pub const QUADRATURE_WINDOW_SIGMAS: f64 = 4.0;

/// Half-width (degrees of lag around 90°) of the points of the phase-slope
/// damping estimate.
pub const SLOPE_WINDOW_DEG: f64 = 30.0;

/// A sweep that jumps down with its lag short of 90° by more than this
/// (or three phase-noise standard deviations) left its branch early.
pub const EARLY_LAG_TOLERANCE_DEG: f64 = 5.0;

/// Significance of the homogeneity tests (the χ² point of 1 − this).
pub const SIGNIFICANCE: f64 = 0.001;

/// An exponent is *pinned* when its 95 % interval is within ± this.
pub const PINNED_HALF_WIDTH: f64 = 0.25;

/// Range searched for the exponents ρ and η (the shape factor needs > −3).
pub const EXPONENT_RANGE: (f64, f64) = (-2.9, 15.0);

/// A detected phase offset within this many degrees of a multiple of 90°
/// is taken as that multiple.
pub const OFFSET_SNAP_DEG: f64 = 10.0;

/// How the phase columns are read.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PhaseUse {
    /// Detect the convention (lag or lead, constant offset) from the data
    /// ([`detect_convention`]).
    #[default]
    Auto,
    /// The convention is known.
    Known(PhaseConvention),
    /// Do not use phases.
    Ignore,
}

/// Options of [`inspect`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InspectOptions {
    pub phase: PhaseUse,
    /// Smallest step-to-step amplitude ratio of a jump (> 1).
    pub min_jump_ratio: f64,
}

impl Default for InspectOptions {
    fn default() -> Self {
        Self {
            phase: PhaseUse::Auto,
            min_jump_ratio: DEFAULT_JUMP_RATIO,
        }
    }
}

/// Why the data cannot be inspected. Each variant names the offending
/// level, sweep and value (frequencies in Hz).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InspectError {
    #[error("no curves in the data")]
    Empty,
    #[error(
        "level {level} ({direction} sweep): {what} = {value} at {f_hz:.4} Hz is not a finite number"
    )]
    NotFinite {
        level: String,
        direction: &'static str,
        what: &'static str,
        value: f64,
        f_hz: f64,
    },
    #[error("level {level} ({direction} sweep): {count} points; at least 3 are needed")]
    TooFewPoints {
        level: String,
        direction: &'static str,
        count: usize,
    },
    #[error("level {level} ({direction} sweep): the frequencies must increase strictly and be > 0 (at {f_hz:.4} Hz)")]
    NotIncreasing {
        level: String,
        direction: &'static str,
        f_hz: f64,
    },
    #[error("level {level} ({direction} sweep): the columns have different lengths ({omegas} frequencies, {amplitudes} amplitudes, {phases} phases)")]
    Lengths {
        level: String,
        direction: &'static str,
        omegas: usize,
        amplitudes: usize,
        phases: usize,
    },
    #[error("level {level}: gamma = {value} m/s^2 must be finite and > 0")]
    BadGamma { level: String, value: f64 },
    #[error(
        "level {level} ({direction} sweep): amplitude = {value} m at {f_hz:.4} Hz is negative"
    )]
    NegativeAmplitude {
        level: String,
        direction: &'static str,
        value: f64,
        f_hz: f64,
    },
    #[error("level {level} ({direction} sweep): the amplitude is constant ({value} m) from {f_min_hz:.4} to {f_max_hz:.4} Hz: no resonance to inspect")]
    ConstantAmplitude {
        level: String,
        direction: &'static str,
        value: f64,
        f_min_hz: f64,
        f_max_hz: f64,
    },
    #[error("--min-jump-ratio {0} must be finite and > 1")]
    BadJumpRatio(f64),
    #[error("no level has its resonance inside the band: {detail}")]
    NoResonance { detail: String },
}

// ---------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------

/// What a curve's largest amplitude is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PeakKind {
    /// Interior maximum, refined by the parabola.
    Refined,
    /// The last point before a drop jump (the top of the branch that ends).
    BeforeJump,
    /// The maximum right after a jump up: a fold, not a resonance.
    AfterJump,
    /// The maximum is at the first or last frequency: the band misses the
    /// resonance.
    BandEdge,
    /// Interior maximum whose parabola failed (flat or noisy top): the
    /// measured point.
    Sampled,
}

/// A curve's amplitude peak.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    pub kind: PeakKind,
    /// rad/s
    pub omega: f64,
    pub f_hz: f64,
    /// m
    pub amplitude: f64,
    /// `a/γ`, s²
    pub normalised: f64,
    /// Nearest measured step (index in increasing frequency).
    pub index: usize,
    /// Points in the parabola (0 when not refined).
    pub window: usize,
    /// Standard errors from the noise, rad/s and m.
    pub sigma_omega: f64,
    pub sigma_amplitude: f64,
}

/// The 90° point of a curve's lag.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Quadrature {
    pub omega: f64,
    pub f_hz: f64,
    pub amplitude: f64,
    pub normalised: f64,
    /// Lag slope at the crossing, rad per rad/s (`2/δ` for a linear SDoF).
    pub phase_slope: f64,
    pub sigma_omega: f64,
    pub sigma_amplitude: f64,
}

/// How a curve's damping was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DampingMethod {
    HalfPower,
    PhaseSlope,
}

/// A curve's damping as a linear SDoF would have it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DampingEstimate {
    pub method: DampingMethod,
    /// Damping ratio ζ.
    pub zeta: f64,
    /// `δ = 2ζω_n`, 1/s.
    pub delta: f64,
    /// Natural frequency of the equivalent linear SDoF, rad/s and Hz.
    pub omega_n: f64,
    pub f_n_hz: f64,
    /// Half-power frequencies, Hz (half-power method only).
    pub f_low_hz: Option<f64>,
    pub f_high_hz: Option<f64>,
    /// Standard error of δ from the noise, 1/s.
    pub sigma_delta: f64,
}

/// Whether a jump drops to a lower branch or rises to a higher one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JumpKind {
    Drop,
    Rise,
}

/// A measured jump ([`Curve::measured_jump`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JumpReport {
    pub kind: JumpKind,
    /// Last step on the branch that ends and first step after, in sweep
    /// order: rad/s and Hz.
    pub omega_before: f64,
    pub f_before_hz: f64,
    pub omega_after: f64,
    pub f_after_hz: f64,
    /// m
    pub amplitude_before: f64,
    pub amplitude_after: f64,
    /// `max/min` of the two amplitudes (> 1).
    pub ratio: f64,
    /// The sweep left its branch before the backbone says its fold would
    /// be (module docs); `None` where this could not be judged.
    pub early: Option<bool>,
    /// How early: backbone frequency at the amplitude before the jump minus
    /// the jump frequency, in sweep direction, Hz.
    pub early_by_hz: Option<f64>,
}

/// One curve (one level, one sweep direction).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveReport {
    pub level: String,
    /// m/s², zero-to-peak
    pub gamma: f64,
    pub direction: SweepDirection,
    pub points: usize,
    pub f_min_hz: f64,
    pub f_max_hz: f64,
    pub peak: Peak,
    pub quadrature: Option<Quadrature>,
    pub damping: Option<DampingEstimate>,
    pub jump: Option<JumpReport>,
    /// Median local noise of the amplitude relative to the amplitude.
    pub noise_relative: f64,
    /// Phase noise, rad (curves with phases).
    pub noise_phase: Option<f64>,
    /// What could not be read from this curve, and why.
    pub notes: Vec<String>,
}

/// Where a level's resonance point comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResonanceSource {
    /// 90° lag (on the backbone).
    Quadrature,
    /// Amplitude peak (refined, or the last point before a drop jump).
    Peak,
}

/// One level's resonance point: the data of the homogeneity test and the
/// two laws.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelPoint {
    pub level: String,
    pub gamma: f64,
    pub source: ResonanceSource,
    /// Indices of the curves averaged into the point.
    pub curves: Vec<usize>,
    /// Resonance frequency Ω_r (rad/s, Hz) and amplitude a_r (m).
    pub omega: f64,
    pub f_hz: f64,
    pub amplitude: f64,
    /// `a_r/γ`, s²
    pub normalised: f64,
    /// `V = Ω_r a_r`, m/s
    pub velocity: f64,
    /// `δ_eq = γ/(a_r Ω_r)`, 1/s, and `ζ_eq = δ_eq/(2Ω_r)`.
    pub delta_eq: f64,
    pub zeta_eq: f64,
    /// The backbone frequency of the point, rad/s: `Ω_r` at quadrature, the
    /// peak corrected to the backbone otherwise (module docs).
    pub omega_backbone: f64,
    /// `omega_backbone` is a refined peak corrected to the backbone.
    pub corrected: bool,
    pub sigma_omega: f64,
    pub sigma_amplitude: f64,
    pub sigma_delta_eq: f64,
    /// The point entered the stiffness and damping laws (false: its sweep
    /// left its branch early).
    pub used: bool,
}

/// The spread of the levels against the noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Homogeneity {
    pub levels: usize,
    /// Linearity index `I` (module docs): about 1 when linear within the noise.
    pub index: f64,
    /// The same for the normalised peaks `a_r/γ` alone and for `Ω_r` alone.
    pub index_normalised_peak: f64,
    pub index_frequency: f64,
    /// `√(χ²/(L−1))` of `δ_eq` alone.
    pub index_damping: f64,
    /// 99.9 % point of `I` (and of each single index) under homogeneity.
    pub threshold: f64,
    pub threshold_single: f64,
    /// `I ≤ threshold`.
    pub linear_within_noise: bool,
    /// `(max − min)/min` over the levels, %.
    pub frequency_shift_percent: f64,
    pub normalised_peak_change_percent: f64,
    pub damping_change_percent: f64,
}

/// A power-law regression (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawFit {
    /// ρ or η.
    pub exponent: f64,
    pub exponent_se: Option<f64>,
    pub exponent_ci95: Option<[f64; 2]>,
    /// ω₀² (rad²/s²) or δ₀ (1/s).
    pub intercept: f64,
    pub intercept_se: Option<f64>,
    pub intercept_ci95: Option<[f64; 2]>,
    /// β or κ, mass-normalised (SI: 1/(s² m^ρ), or (s/m)^η / s), signed.
    pub coefficient: f64,
    /// The equivalent prefactor `g(μ)·coefficient`.
    pub prefactor: f64,
    /// Degrees of freedom `L − 3` (`L − 2` with the intercept held) and
    /// the t quantile used.
    pub dof: usize,
    pub t95: Option<f64>,
    /// `√(χ²/dof)` with the noise weights: ~1 when the law and the noise
    /// model explain the scatter.
    pub scatter: Option<f64>,
    /// The intercept sits at its bound (δ₀ = 0) and was held there.
    pub intercept_held: bool,
    /// The exponent ended at the end of [`EXPONENT_RANGE`].
    pub exponent_at_bound: bool,
    /// The 95 % interval reaches an end of [`EXPONENT_RANGE`] (the levels
    /// do not bound the exponent on that side).
    pub interval_open: bool,
    pub levels: Vec<String>,
    /// Why there is no interval, if there is none.
    pub interval_note: Option<String>,
}

impl LawFit {
    /// Half-width of the exponent's 95 % interval.
    pub fn half_width(&self) -> Option<f64> {
        self.exponent_ci95.map(|[a, b]| 0.5 * (b - a))
    }
    /// The exponent's interval holds `v`.
    pub fn holds(&self, v: f64) -> bool {
        self.exponent_ci95.is_some_and(|[a, b]| a <= v && v <= b)
    }
    /// The data determine the exponent: not at the end of the search
    /// range, its interval (if any) bounded on both sides.
    pub fn determined(&self) -> bool {
        !self.exponent_at_bound && !self.interval_open
    }
    /// The model at `x` (`a` or `V`).
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.prefactor * x.powf(self.exponent)
    }
}

/// The stiffness law `Ω_r² − ω₀² = g(ρ) β a_r^ρ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StiffnessLaw {
    /// `Ω_r` changes beyond the noise (χ² test) or a curve jumps.
    pub nonlinear: bool,
    /// χ² of `Ω_r` about its mean and its degrees of freedom.
    pub chi2: Option<f64>,
    pub hardening: Option<bool>,
    pub fit: Option<LawFit>,
    /// `ω₀/2π` of the fit, Hz.
    pub f0_hz: Option<f64>,
    pub note: Option<String>,
}

/// The damping law `δ_eq − δ₀ = g(η) κ V^η`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DampingLaw {
    /// `δ_eq` changes beyond the noise (χ² test).
    pub nonlinear: bool,
    pub chi2: Option<f64>,
    pub fit: Option<LawFit>,
    pub note: Option<String>,
}

/// How the phases were read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseReport {
    pub used: bool,
    pub convention: Option<PhaseConvention>,
    pub detected: bool,
    pub note: String,
}

/// The model family the data point to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    Linear,
    DuffingLike,
    Generalised,
}

/// What the data say, with the evidence for each point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recommendation {
    /// One line: the verdict.
    pub headline: String,
    pub family: Family,
    /// `"linear"`, `"hardening"` or `"softening"`.
    pub stiffness: String,
    /// `"linear"`, `"coulomb-like"`, `"quadratic"`, `"power-law"`, or
    /// `"nonlinear"` (the damping changes, its exponent is not determined).
    pub damping: String,
    /// `nlsdof fit --model` to start from.
    pub model: String,
    pub evidence: Vec<String>,
    /// The exponents the data pin, with their precision.
    pub pinned: Vec<String>,
    /// Levels whose resonance departs from the lowest level's beyond 3σ, or
    /// that jump.
    pub nonlinear_levels: Vec<String>,
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// The result of [`inspect`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inspection {
    pub curves: Vec<CurveReport>,
    pub levels: Vec<LevelPoint>,
    pub phase: PhaseReport,
    /// `None` with fewer than two levels.
    pub homogeneity: Option<Homogeneity>,
    pub stiffness: StiffnessLaw,
    pub damping: DampingLaw,
    pub recommendation: Recommendation,
}

impl Inspection {
    /// The exponents the laws determined (not at the end of the search
    /// range), as a start of the fit ([`super::FitPlan::start_exponents`],
    /// `nlsdof fit --from-inspect`).
    pub fn exponent_start(&self) -> super::ExponentStart {
        let pick = |f: &Option<LawFit>| {
            f.as_ref()
                .filter(|f| !f.exponent_at_bound && f.exponent.is_finite())
                .map(|f| f.exponent)
        };
        super::ExponentStart {
            rho: pick(&self.stiffness.fit),
            eta: pick(&self.damping.fit),
        }
    }
}

// ---------------------------------------------------------------------------
// Entry point
// ---------------------------------------------------------------------------

/// Inspects stepped-sine curves before any fit (module docs). Errors name
/// the offending level and value; a data set that supports only part of
/// the analysis (one level, a band that misses some resonances, too few
/// levels for a law) gives a reduced report that says what is missing.
pub fn inspect(data: &Dataset, options: &InspectOptions) -> Result<Inspection, InspectError> {
    if !(options.min_jump_ratio.is_finite() && options.min_jump_ratio > 1.0) {
        return Err(InspectError::BadJumpRatio(options.min_jump_ratio));
    }
    validate(data)?;
    let (lags, phase) = phase_lags(data, options.phase);
    let noises: Vec<CurveNoise> = data
        .curves
        .iter()
        .zip(&lags)
        .map(|(c, l)| curve_noise(c, l.as_deref()))
        .collect();
    let analyse = |shear: Option<Shear>| -> Vec<CurveWork> {
        data.curves
            .iter()
            .zip(&lags)
            .zip(&noises)
            .map(|((c, l), nz)| analyse_curve(c, l.as_deref(), nz, options.min_jump_ratio, shear))
            .collect()
    };
    let mut works = analyse(None);
    let mut levels = level_points(data, &works);
    if levels.is_empty() {
        let detail: Vec<String> = works
            .iter()
            .map(|w| {
                format!(
                    "{} ({}): {}",
                    w.report.level,
                    w.report.direction.name(),
                    match w.report.peak.kind {
                        PeakKind::BandEdge => format!(
                            "largest amplitude at the band edge, {} Hz (band {}-{} Hz)",
                            fmt_hz(w.report.peak.f_hz),
                            fmt_hz(w.report.f_min_hz),
                            fmt_hz(w.report.f_max_hz)
                        ),
                        PeakKind::AfterJump => format!(
                            "largest amplitude right after a jump up at {} Hz (a fold)",
                            fmt_hz(w.report.peak.f_hz)
                        ),
                        _ => "no resonance point".into(),
                    }
                )
            })
            .collect();
        return Err(InspectError::NoResonance {
            detail: detail.join("; "),
        });
    }
    let any_jump = works.iter().any(|w| w.report.jump.is_some());
    let (mut stiffness, mut damping, shear) = laws(&mut levels, &mut works, any_jump);
    // second pass: the peaks refitted with the backbone's lean taken out
    if shear.is_some() {
        works = analyse(shear);
        levels = level_points(data, &works);
        (stiffness, damping, _) = laws(&mut levels, &mut works, any_jump);
    }
    let homogeneity = homogeneity(&levels);
    let curves: Vec<CurveReport> = works.into_iter().map(|w| w.report).collect();
    let recommendation = recommend(
        data,
        &curves,
        &levels,
        &homogeneity,
        &stiffness,
        &damping,
        &phase,
    );
    Ok(Inspection {
        curves,
        levels,
        phase,
        homogeneity,
        stiffness,
        damping,
        recommendation,
    })
}

fn fmt_hz(f: f64) -> String {
    crate_fmt(f, 5)
}

/// A number with `sig` significant digits, without trailing zeros.
fn crate_fmt(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..=6).contains(&mag) {
        return format!("{:.*e}", sig.saturating_sub(1), v);
    }
    let decimals = (sig as i32 - 1 - mag).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn validate(data: &Dataset) -> Result<(), InspectError> {
    if data.curves.is_empty() {
        return Err(InspectError::Empty);
    }
    for c in &data.curves {
        let dir = c.direction.name();
        let lvl = || c.level.clone();
        if !(c.gamma.is_finite() && c.gamma > 0.0) {
            return Err(InspectError::BadGamma {
                level: lvl(),
                value: c.gamma,
            });
        }
        let n = c.omegas.len();
        let np = c.phases.as_ref().map_or(n, Vec::len);
        if c.amplitudes.len() != n || np != n {
            return Err(InspectError::Lengths {
                level: lvl(),
                direction: dir,
                omegas: n,
                amplitudes: c.amplitudes.len(),
                phases: np,
            });
        }
        if n < 3 {
            return Err(InspectError::TooFewPoints {
                level: lvl(),
                direction: dir,
                count: n,
            });
        }
        for i in 0..n {
            let f_hz = c.omegas[i] / TWO_PI;
            let check = |what: &'static str, v: f64| {
                if v.is_finite() {
                    Ok(())
                } else {
                    Err(InspectError::NotFinite {
                        level: lvl(),
                        direction: dir,
                        what,
                        value: v,
                        f_hz,
                    })
                }
            };
            check("frequency", c.omegas[i])?;
            check("amplitude", c.amplitudes[i])?;
            if let Some(p) = &c.phases {
                check("phase", p[i])?;
            }
            if c.omegas[i] <= 0.0 || (i > 0 && c.omegas[i] <= c.omegas[i - 1]) {
                return Err(InspectError::NotIncreasing {
                    level: lvl(),
                    direction: dir,
                    f_hz,
                });
            }
            if c.amplitudes[i] < 0.0 {
                return Err(InspectError::NegativeAmplitude {
                    level: lvl(),
                    direction: dir,
                    value: c.amplitudes[i],
                    f_hz,
                });
            }
        }
        let (lo, hi) = c
            .amplitudes
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        if hi <= 0.0 || hi - lo <= 1e-12 * hi {
            return Err(InspectError::ConstantAmplitude {
                level: lvl(),
                direction: dir,
                value: hi,
                f_min_hz: c.omegas[0] / TWO_PI,
                f_max_hz: c.omegas[n - 1] / TWO_PI,
            });
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Phase
// ---------------------------------------------------------------------------

/// Unwraps a phase sequence (steps of more than π are taken as wraps).
fn unwrap(p: &[f64]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(p.len());
    let mut shift = 0.0f64;
    for (i, &v) in p.iter().enumerate() {
        if i > 0 {
            let d = v + shift - out[i - 1];
            shift -= TWO_PI * (d / TWO_PI).round();
        }
        out.push(v + shift);
    }
    out
}

fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return 0.0;
    }
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The phase convention detected from the data. Across a resonance the lag
/// grows (by up to π), so the sign of the change of the unwrapped phase
/// from the first to the last 5 % of a curve (medians, at least 3 points)
/// is the convention's sign. The offset comes from where the lag is 90°:
///
/// * on curves without a jump, at the amplitude peak (a linear SDoF's lag
///   there is `90° − ζ` rad; a nonlinear curve meets its backbone near its
///   peak), read at the vertex of the parabola of `1/a²` in `Ω²` through
///   the top three points: `offset = ψ(peak) − sign·π/2`;
/// * else (every curve jumps: the top of a branch that ends lies past its
///   90° point, by about 10° on the clamped beams) from the ends of the
///   curves whose phase turns by 90°–270°: their mean sits at the 90° lag,
///   `offset = (ψ_low + ψ_high)/2 − sign·π/2` (biased by half the
///   asymmetry of the ends);
/// * else from the peaks of the curves that jump.
///
/// Median over the curves used; an offset within [`OFFSET_SNAP_DEG`] of a
/// multiple of 90° is taken as that multiple. `None` when no curve can be
/// read or the curves disagree on the sign.
pub fn detect_convention(data: &Dataset) -> Option<PhaseConvention> {
    // per curve: (jump-free, sign, offset from the peak, offset from the ends)
    let mut cands: Vec<(bool, f64, Option<f64>, Option<f64>)> = Vec::new();
    for c in &data.curves {
        let Some(p) = &c.phases else { continue };
        let u = unwrap(p);
        let n = u.len();
        let k = (n / 20).max(3).min(n);
        let (lo, hi) = (median(&u[..k]), median(&u[n - k..]));
        let d = hi - lo;
        if d == 0.0 {
            continue;
        }
        let s = d.signum();
        let ends = (d.abs() >= HALF_PI && d.abs() <= 3.0 * HALF_PI)
            .then_some(0.5 * (lo + hi) - s * HALF_PI);
        let jump_free = c.measured_jump(DEFAULT_JUMP_RATIO).is_none();
        let imax = (0..n).max_by(|&i, &j| c.amplitudes[i].total_cmp(&c.amplitudes[j]))?;
        let peak = (imax > 0 && imax + 1 < n).then(|| {
            // the phase at the vertex of the parabola of 1/a² in Ω² through
            // the top three points (exact for a linear SDoF), interpolated
            let (u0, u1, u2) = (
                c.omegas[imax - 1].powi(2),
                c.omegas[imax].powi(2),
                c.omegas[imax + 1].powi(2),
            );
            let y = |i: usize| c.amplitudes[i].max(f64::MIN_POSITIVE).powi(-2);
            let (y0, y1, y2) = (y(imax - 1), y(imax), y(imax + 1));
            let den = (u0 - u1) * (u0 - u2) * (u1 - u2);
            let a2 = (u2 * (y1 - y0) + u1 * (y0 - y2) + u0 * (y2 - y1)) / den;
            let b2 = (u2 * u2 * (y0 - y1) + u1 * u1 * (y2 - y0) + u0 * u0 * (y1 - y2)) / den;
            let uv = -b2 / (2.0 * a2);
            let psi = if a2 > 0.0 && uv >= u0 && uv <= u2 {
                let (i, j) = if uv <= u1 {
                    (imax - 1, imax)
                } else {
                    (imax, imax + 1)
                };
                let t = (uv.sqrt() - c.omegas[i]) / (c.omegas[j] - c.omegas[i]);
                u[i] + t * (u[j] - u[i])
            } else {
                u[imax]
            };
            psi - s * HALF_PI
        });
        cands.push((jump_free, s, peak, ends));
    }
    let free: Vec<(f64, f64)> = cands
        .iter()
        .filter(|c| c.0)
        .filter_map(|c| c.2.map(|o| (c.1, o)))
        .collect();
    let ends: Vec<(f64, f64)> = cands.iter().filter_map(|c| c.3.map(|o| (c.1, o))).collect();
    let peaks: Vec<(f64, f64)> = cands.iter().filter_map(|c| c.2.map(|o| (c.1, o))).collect();
    let used = if !free.is_empty() {
        free
    } else if !ends.is_empty() {
        ends
    } else {
        peaks
    };
    let &(sign, first) = used.first()?;
    if used.iter().any(|c| c.0 != sign) {
        return None;
    }
    // offsets compared modulo 2π about the first
    let aligned: Vec<f64> = used
        .iter()
        .map(|c| c.1 - TWO_PI * ((c.1 - first) / TWO_PI).round())
        .collect();
    let mut offset = median(&aligned);
    offset -= TWO_PI * (offset / TWO_PI).round();
    let quarter = (offset / HALF_PI).round() * HALF_PI;
    if (offset - quarter).abs() <= OFFSET_SNAP_DEG.to_radians() {
        offset = quarter + 0.0; // (not −0)
    }
    Some(PhaseConvention {
        sign,
        offset,
        delay: 0.0,
    })
}

/// The lag of each curve (unwrapped, shifted so its median is nearest 90°)
/// under the chosen convention.
fn phase_lags(data: &Dataset, use_: PhaseUse) -> (Vec<Option<Vec<f64>>>, PhaseReport) {
    let none = || vec![None; data.curves.len()];
    let with_phase = data.curves.iter().filter(|c| c.phases.is_some()).count();
    if with_phase == 0 {
        return (
            none(),
            PhaseReport {
                used: false,
                convention: None,
                detected: false,
                note: "no phase columns: resonance points are amplitude peaks".into(),
            },
        );
    }
    let (conv, detected) = match use_ {
        PhaseUse::Ignore => {
            return (
                none(),
                PhaseReport {
                    used: false,
                    convention: None,
                    detected: false,
                    note: "phases ignored (as asked): resonance points are amplitude peaks".into(),
                },
            )
        }
        PhaseUse::Known(c) => (c, false),
        PhaseUse::Auto => match detect_convention(data) {
            Some(c) => (c, true),
            None => {
                return (
                    none(),
                    PhaseReport {
                        used: false,
                        convention: None,
                        detected: false,
                        note: "phases not used: their convention cannot be told (no curve has its peak inside the band, or the curves disagree on the direction of the phase change; give it with --phase-convention)".into(),
                    },
                )
            }
        },
    };
    let lags = data
        .curves
        .iter()
        .map(|c| {
            c.phases.as_ref().map(|p| {
                let raw: Vec<f64> = p
                    .iter()
                    .zip(&c.omegas)
                    .map(|(&psi, &w)| conv.lag(psi, w))
                    .collect();
                let mut u = unwrap(&raw);
                let m = median(&u);
                let k = ((m - HALF_PI) / TWO_PI).round();
                for v in &mut u {
                    *v -= k * TWO_PI;
                }
                u
            })
        })
        .collect();
    let note = format!(
        "phases used as a {} with offset {:.1} deg{}",
        if conv.sign > 0.0 { "lag" } else { "lead" },
        conv.offset.to_degrees(),
        if detected {
            " (detected: the lag grows through resonance and is 90 deg at the peak, or midway between the ends of curves that jump)"
        } else {
            " (as given)"
        }
    );
    (
        lags,
        PhaseReport {
            used: true,
            convention: Some(conv),
            detected,
            note,
        },
    )
}

// ---------------------------------------------------------------------------
// Per curve
// ---------------------------------------------------------------------------

/// A curve's resonance candidate (internal).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    source: ResonanceSource,
    omega: f64,
    amplitude: f64,
    sigma_omega: f64,
    sigma_amplitude: f64,
    /// Peak refined on a jump-free curve (its backbone correction applies).
    refined: bool,
    /// The curve has no jump.
    jump_free: bool,
}

struct CurveWork {
    report: CurveReport,
    quadrature: Option<Candidate>,
    peak: Option<Candidate>,
    /// Before a drop jump: (Ω, a, lag there).
    before_drop: Option<(f64, f64, Option<f64>)>,
    /// With phases and a drop jump: the lag never reached 90° before it.
    missed_quadrature: bool,
}

/// Weighted least squares of `y` on the first `p ≤ N` columns of the rows
/// `x` with weights `w`: coefficients and `(XᵀWX)⁻¹`.
#[allow(clippy::type_complexity)]
fn wls<const N: usize>(
    x: &[[f64; N]],
    p: usize,
    y: &[f64],
    w: &[f64],
) -> Option<([f64; N], [[f64; N]; N])> {
    let mut a = [[0.0; N]; N];
    let mut r = [0.0; N];
    for ((row, &yi), &wi) in x.iter().zip(y).zip(w) {
        for j in 0..p {
            r[j] += wi * row[j] * yi;
            for k in 0..p {
                a[j][k] += wi * row[j] * row[k];
            }
        }
    }
    let inv = invert(&a, p)?;
    let mut c = [0.0; N];
    for j in 0..p {
        c[j] = (0..p).map(|k| inv[j][k] * r[k]).sum();
    }
    c.iter().all(|v| v.is_finite()).then_some((c, inv))
}

/// Inverse of the leading `p × p` block (Gauss–Jordan with pivoting, on
/// the matrix scaled to unit diagonal); `None` when singular.
fn invert<const N: usize>(a: &[[f64; N]; N], p: usize) -> Option<[[f64; N]; N]> {
    let mut d = [1.0; N];
    for j in 0..p {
        if !(a[j][j] > 0.0 && a[j][j].is_finite()) {
            return None;
        }
        d[j] = 1.0 / a[j][j].sqrt();
    }
    let mut m = vec![vec![0.0; 2 * p]; p];
    for j in 0..p {
        for k in 0..p {
            m[j][k] = a[j][k] * d[j] * d[k];
        }
        m[j][p + j] = 1.0;
    }
    for col in 0..p {
        let piv = (col..p).max_by(|&i, &k| m[i][col].abs().total_cmp(&m[k][col].abs()))?;
        if m[piv][col].abs() < 1e-13 {
            return None;
        }
        m.swap(col, piv);
        let v = m[col][col];
        for x in m[col].iter_mut() {
            *x /= v;
        }
        let pivot_row = m[col].clone();
        for (i, row) in m.iter_mut().enumerate() {
            if i != col {
                let f = row[col];
                if f != 0.0 {
                    for (x, &pv) in row.iter_mut().zip(&pivot_row) {
                        *x -= f * pv;
                    }
                }
            }
        }
    }
    let mut inv = [[0.0; N]; N];
    for j in 0..p {
        for k in 0..p {
            inv[j][k] = m[j][p + k] * d[j] * d[k];
        }
    }
    Some(inv)
}

/// A curve's noise (module docs), computed once for both passes.
#[derive(Debug, Clone)]
struct CurveNoise {
    /// σ of each amplitude, m.
    sigma: Vec<f64>,
    /// Median of σ/a.
    relative: f64,
    /// σ of the lag, rad.
    phase: Option<f64>,
}

/// The noise of curve `c` from the data alone: the pseudo-residuals of
/// its amplitudes and of its lag ([`noise::local_noise_scaled`]), floored
/// at 1e-9 relative.
fn curve_noise(c: &Curve, lags: Option<&[f64]>) -> CurveNoise {
    let n = c.omegas.len();
    let peak_amp = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
    let floor = 1e-9 * peak_amp.max(f64::MIN_POSITIVE);
    let sigma: Vec<f64> = noise::local_noise(c, &c.amplitudes)
        .into_iter()
        .zip(&c.amplitudes)
        .map(|(s, &a)| {
            let s = if s.is_finite() { s } else { 0.0 };
            s.max(1e-9 * a.max(0.01 * peak_amp)).max(floor)
        })
        .collect();
    let relative = median(
        &sigma
            .iter()
            .zip(&c.amplitudes)
            .map(|(s, &a)| s / a.max(0.01 * peak_amp))
            .collect::<Vec<_>>(),
    );
    let phase = lags.map(|l| {
        let m = median(&noise::local_noise_scaled(&c.omegas, l, &vec![1.0; n]));
        if m.is_finite() {
            m.max(1e-9)
        } else {
            1e-9
        }
    });
    CurveNoise {
        sigma,
        relative,
        phase,
    }
}

fn analyse_curve(
    c: &Curve,
    lags: Option<&[f64]>,
    noise: &CurveNoise,
    min_ratio: f64,
    shear: Option<Shear>,
) -> CurveWork {
    let n = c.omegas.len();
    let mut notes = Vec::new();
    // the jump: `from` its last step on the branch that ends, `to` the next
    // (a step out of the first two of a sweep is a start transient, not
    // the end of a branch: at least three points precede a jump)
    let jump = c.measured_jump(min_ratio).and_then(|w| {
        let from = c.omegas.iter().position(|&o| o == w)?;
        let (to, before) = match c.direction {
            SweepDirection::Up => (from + 1, from),
            SweepDirection::Down => (from.checked_sub(1)?, n - 1 - from),
        };
        (to < n && before >= MIN_POINTS_BEFORE_JUMP - 1).then_some((from, to))
    });
    let split = jump.map(|(f, t)| f.min(t));
    let CurveNoise {
        sigma,
        relative: noise_relative,
        phase: sigma_phase,
    } = noise.clone();
    // the jump report and the range of the branch that holds the peak
    let mut jump_report = None;
    let mut range = (0, n - 1);
    let mut kind_rise = false;
    if let Some((from, to)) = jump {
        let (a0, a1) = (c.amplitudes[from], c.amplitudes[to]);
        let kind = if a1 < a0 {
            JumpKind::Drop
        } else {
            JumpKind::Rise
        };
        if kind == JumpKind::Drop {
            range = match c.direction {
                SweepDirection::Up => (0, from),
                SweepDirection::Down => (from, n - 1),
            };
        } else {
            kind_rise = true;
        }
        jump_report = Some(JumpReport {
            kind,
            omega_before: c.omegas[from],
            f_before_hz: c.omegas[from] / TWO_PI,
            omega_after: c.omegas[to],
            f_after_hz: c.omegas[to] / TWO_PI,
            amplitude_before: a0,
            amplitude_after: a1,
            ratio: a0.max(a1) / a0.min(a1).max(f64::MIN_POSITIVE),
            early: None,
            early_by_hz: None,
        });
    }
    // the peak
    let (lo, hi) = range;
    let imax = (lo..=hi)
        .max_by(|&i, &k| c.amplitudes[i].total_cmp(&c.amplitudes[k]))
        .unwrap_or(lo);
    let step = |i: usize| {
        let l = if i > 0 {
            c.omegas[i] - c.omegas[i - 1]
        } else {
            0.0
        };
        let r = if i + 1 < n {
            c.omegas[i + 1] - c.omegas[i]
        } else {
            0.0
        };
        l.max(r)
    };
    let sampled = |kind: PeakKind| Peak {
        kind,
        omega: c.omegas[imax],
        f_hz: c.omegas[imax] / TWO_PI,
        amplitude: c.amplitudes[imax],
        normalised: c.amplitudes[imax] / c.gamma,
        index: imax,
        window: 0,
        sigma_omega: step(imax) / 12f64.sqrt(),
        sigma_amplitude: sigma[imax],
    };
    let drop_from = jump
        .filter(|_| {
            jump_report
                .as_ref()
                .is_some_and(|j| j.kind == JumpKind::Drop)
        })
        .map(|(f, _)| f);
    let peak = if kind_rise {
        notes.push(format!(
            "the largest amplitude follows a jump up at {} Hz: a fold, not a resonance",
            fmt_hz(c.omegas[jump.map_or(imax, |j| j.0)] / TWO_PI)
        ));
        sampled(PeakKind::AfterJump)
    } else if Some(imax) == drop_from {
        sampled(PeakKind::BeforeJump)
    } else if imax == 0 || imax == n - 1 || imax == lo || imax == hi {
        notes.push(format!(
            "largest amplitude at the band edge ({} Hz): the band misses the resonance",
            fmt_hz(c.omegas[imax] / TWO_PI)
        ));
        sampled(PeakKind::BandEdge)
    } else {
        // the lean is taken out of jump-free curves only: near a fold the
        // sheared coordinate folds back on itself
        let sh = if jump.is_none() { shear } else { None };
        match refine_peak(c, &sigma, imax, lo, hi, sh) {
            Some(p) => p,
            None => {
                notes.push(
                    "the peak's local fit failed (flat or noisy top): the measured maximum is used"
                        .into(),
                );
                sampled(PeakKind::Sampled)
            }
        }
    };
    let peak_candidate = matches!(
        peak.kind,
        PeakKind::Refined | PeakKind::BeforeJump | PeakKind::Sampled
    )
    .then_some(Candidate {
        source: ResonanceSource::Peak,
        omega: peak.omega,
        amplitude: peak.amplitude,
        sigma_omega: peak.sigma_omega,
        sigma_amplitude: peak.sigma_amplitude,
        refined: peak.kind == PeakKind::Refined && jump.is_none(),
        jump_free: jump.is_none(),
    });
    // quadrature
    let mut quadrature = None;
    let mut quad_candidate = None;
    let mut missed_quadrature = false;
    if let (Some(l), Some(sp)) = (lags, sigma_phase) {
        match find_quadrature(c, l, sp, &sigma, split, (lo, hi), imax) {
            Some(q) => {
                quad_candidate = Some(Candidate {
                    source: ResonanceSource::Quadrature,
                    omega: q.omega,
                    amplitude: q.amplitude,
                    sigma_omega: q.sigma_omega,
                    sigma_amplitude: q.sigma_amplitude,
                    refined: false,
                    jump_free: jump.is_none(),
                });
                quadrature = Some(q);
            }
            None => {
                if let Some(f) = drop_from {
                    let lag = l[f];
                    // a few degrees of tolerance: the detected offset is
                    // biased by half the asymmetry of the curve's ends
                    let tol = (3.0 * sp).max(EARLY_LAG_TOLERANCE_DEG.to_radians());
                    let reached = match c.direction {
                        SweepDirection::Up => lag >= HALF_PI - tol,
                        SweepDirection::Down => lag <= HALF_PI + tol,
                    };
                    if !reached {
                        missed_quadrature = true;
                    }
                    notes.push(format!(
                        "no 90 deg crossing before the jump (lag {:.1} deg at {} Hz)",
                        lag.to_degrees(),
                        fmt_hz(c.omegas[f] / TWO_PI)
                    ));
                } else {
                    notes.push("the lag does not cross 90 deg on a branch of this curve".into());
                }
            }
        }
    }
    // damping
    let damping = half_power(c, &sigma, &peak, jump.is_some(), shear).or_else(|| {
        let (l, sp) = (lags?, sigma_phase?);
        let q = quadrature.as_ref()?;
        phase_slope(c, l, sp, split, q.omega, shear)
    });
    if let (Some(d), Some(q)) = (&damping, &quadrature) {
        let d_eq = c.gamma / (q.amplitude * q.omega);
        let ratio = d.delta / d_eq;
        if d.method == DampingMethod::PhaseSlope && !(0.5..=2.0).contains(&ratio) {
            notes.push(format!(
                "the phase slope reads delta = {:.4} 1/s, {:.1} times delta_eq = gamma/(a Omega) = {:.4} 1/s at 90 deg: the curve is too distorted for a linear-SDoF reading; delta_eq is the damping at resonance",
                d.delta, ratio, d_eq
            ));
        }
    }
    if damping.is_none() {
        notes.push(
            if jump.is_some() && lags.is_none() {
                "no damping estimate: the curve jumps (no half-power width) and has no phase"
            } else if lags.is_none() {
                "no damping estimate: a half-power point lies outside the band and there is no phase"
            } else {
                "no damping estimate: no half-power width and no phase slope at 90 deg"
            }
            .to_string(),
        );
    }
    let before_drop = drop_from.map(|f| (c.omegas[f], c.amplitudes[f], lags.map(|l| l[f])));
    CurveWork {
        report: CurveReport {
            level: c.level.clone(),
            gamma: c.gamma,
            direction: c.direction,
            points: n,
            f_min_hz: c.omegas[0] / TWO_PI,
            f_max_hz: c.omegas[n - 1] / TWO_PI,
            peak,
            quadrature,
            damping,
            jump: jump_report,
            noise_relative,
            noise_phase: sigma_phase,
            notes,
        },
        quadrature: quad_candidate,
        peak: peak_candidate,
        before_drop,
        missed_quadrature,
    }
}

/// The lean of the backbone, `Ω_bb²(a) − ω₀² = B a^p` (the first pass's
/// backbone law), taken out of a peak before its local fit.
#[derive(Debug, Clone, Copy)]
struct Shear {
    b: f64,
    p: f64,
}

impl Shear {
    fn at(s: Option<Shear>, a: f64) -> f64 {
        s.map_or(0.0, |s| s.b * a.powf(s.p))
    }
}

/// The weighted cubic of `1/a²` in the sheared `u′ = Ω² − B a^p` over
/// `idx` (amplitudes `amps`): its minimum `(Ω_p, a_p)` (back in `Ω`) and
/// half its second derivative in `u′`; `None` if it has no minimum inside
/// the window. A linear SDoF's `1/a²` is a parabola in `Ω²` (the cubic
/// term vanishes), and so is that of a nonlinear stiffness with linear
/// damping in the sheared coordinate, `γ²/a² = (α_eff(a_ref) − u′)² + δ²u`;
/// the cubic term takes up what lean is left.
fn parabola_vertex(
    c: &Curve,
    sigma: &[f64],
    idx: &[usize],
    amps: &[f64],
    shear: Option<Shear>,
) -> Option<(f64, f64, f64)> {
    let mid = idx.len() / 2;
    let f_ref = Shear::at(shear, amps[mid]);
    let us: Vec<f64> = idx
        .iter()
        .zip(amps)
        .map(|(&i, &a)| c.omegas[i].powi(2) - Shear::at(shear, a) + f_ref)
        .collect();
    let u_c = us[mid];
    let (umin, umax) = us
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &u| {
            (l.min(u), h.max(u))
        });
    let span = (umax - umin).max(f64::MIN_POSITIVE);
    let yscale = amps[mid].powi(-2);
    let mut rows = Vec::with_capacity(idx.len());
    let mut y = Vec::with_capacity(idx.len());
    let mut w = Vec::with_capacity(idx.len());
    for (k, &i) in idx.iter().enumerate() {
        let t = (us[k] - u_c) / span;
        rows.push([1.0, t, t * t, t * t * t]);
        let a = amps[k];
        y.push(a.powi(-2) / yscale);
        // var(1/a²) = 4σ²/a⁶
        let s = sigma[i];
        w.push(a.powi(6) / (4.0 * s * s) * yscale * yscale);
    }
    let p = if idx.len() >= 6 { 4 } else { 3 };
    let (coef, _) = wls(&rows, p, &y, &w)?;
    let t_lo = (umin - u_c) / span;
    let t_hi = (umax - u_c) / span;
    // stationary points: c1 + 2 c2 t + 3 c3 t² = 0, the minimum (y'' > 0)
    let (c1, c2, c3) = (coef[1], coef[2], coef[3]);
    let t_v = if c3.abs() < 1e-12 * c2.abs().max(1e-300) {
        -c1 / (2.0 * c2)
    } else {
        let disc = c2 * c2 - 3.0 * c1 * c3;
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        // the root with y'' = 2 c2 + 6 c3 t = 2√disc > 0 (stable form)
        let q = -(c2 + c2.signum() * disc.sqrt());
        let (r1, r2) = (q / (3.0 * c3), c1 / q);
        if 2.0 * c2 + 6.0 * c3 * r1 > 0.0 {
            r1
        } else {
            r2
        }
    };
    let curv_t = c2 + 3.0 * c3 * t_v;
    if !(curv_t > 0.0 && t_v >= t_lo && t_v <= t_hi) {
        return None;
    }
    let y_v = (coef[0] + t_v * (c1 + t_v * (c2 + t_v * c3))) * yscale;
    if y_v.is_nan() || y_v <= 0.0 {
        return None;
    }
    let a_v = y_v.powf(-0.5);
    let u_v = u_c + t_v * span + Shear::at(shear, a_v) - f_ref;
    let curv = curv_t * yscale / (span * span);
    (u_v > 0.0).then(|| (u_v.sqrt(), a_v, curv))
}

fn refine_peak(
    c: &Curve,
    sigma: &[f64],
    imax: usize,
    lo: usize,
    hi: usize,
    shear: Option<Shear>,
) -> Option<Peak> {
    let amax = c.amplitudes[imax];
    // first window: contiguous run around the maximum above the threshold
    let rel = sigma[imax] / amax;
    let level = (1.0 - PEAK_WINDOW_SIGMAS * rel).max(PEAK_WINDOW_FLOOR);
    let thresh = level * amax;
    let mut l = imax - 1;
    while l > lo && c.amplitudes[l] > thresh && c.amplitudes[l - 1] > 0.0 {
        l -= 1;
    }
    let mut r = imax + 1;
    while r < hi && c.amplitudes[r] > thresh {
        r += 1;
    }
    if c.amplitudes[l] <= 0.0 || c.amplitudes[r] <= 0.0 {
        return None;
    }
    let mut idx: Vec<usize> = (l..=r).collect();
    let mut amps: Vec<f64> = idx.iter().map(|&i| c.amplitudes[i]).collect();
    let (mut w, mut a, mut curv) = parabola_vertex(c, sigma, &idx, &amps, shear)?;
    // then the window where the fitted curve is above the same level of its
    // vertex (in the sheared coordinate): its ends no longer hang on single
    // noisy points
    let sheared = |i: usize| c.omegas[i].powi(2) - Shear::at(shear, c.amplitudes[i]);
    for _ in 0..3 {
        let du = (a.powi(-2) * (1.0 / (level * level) - 1.0) / curv).sqrt();
        let u_v = w * w - Shear::at(shear, a);
        let mut next: Vec<usize> = (lo..=hi)
            .filter(|&i| c.amplitudes[i] > 0.0 && (sheared(i) - u_v).abs() <= du)
            .collect();
        if next.len() < 3 {
            let near = (lo..=hi)
                .min_by(|&i, &k| (c.omegas[i] - w).abs().total_cmp(&(c.omegas[k] - w).abs()))
                .unwrap_or(imax);
            let m = near.clamp(lo + 1, hi - 1);
            next = vec![m - 1, m, m + 1];
        }
        if next == idx {
            break;
        }
        let nx: Vec<f64> = next.iter().map(|&i| c.amplitudes[i]).collect();
        match parabola_vertex(c, sigma, &next, &nx, shear) {
            Some((w2, a2, c2)) => {
                idx = next;
                amps = nx;
                (w, a, curv) = (w2, a2, c2);
            }
            None => break,
        }
    }
    // a vertex well above the top points is an extrapolation, not a peak
    if !(a.is_finite() && a > 0.0 && a <= amax * 1.02 + 5.0 * sigma[imax]) {
        return None;
    }
    // noise propagated by finite differences in each amplitude
    let (mut vw, mut va) = (0.0, 0.0);
    for k in 0..idx.len() {
        let h = 1e-4 * sigma[idx[k]].max(1e-12 * amps[k]);
        let mut p = amps.clone();
        p[k] += h;
        let (w2, a2, _) = parabola_vertex(c, sigma, &idx, &p, shear).unwrap_or((w, a, curv));
        let s = sigma[idx[k]];
        vw += ((w2 - w) / h * s).powi(2);
        va += ((a2 - a) / h * s).powi(2);
    }
    let near = idx
        .iter()
        .copied()
        .min_by(|&i, &k| (c.omegas[i] - w).abs().total_cmp(&(c.omegas[k] - w).abs()))
        .unwrap_or(imax);
    Some(Peak {
        kind: PeakKind::Refined,
        omega: w,
        f_hz: w / TWO_PI,
        amplitude: a,
        normalised: a / c.gamma,
        index: near,
        window: idx.len(),
        sigma_omega: vw.sqrt(),
        sigma_amplitude: va.sqrt(),
    })
}

/// Weighted line of `q = −Ω cot φ` against `u = Ω²` over `idx`:
/// `(u_q, δ, σ_u, σ_δ)` with `u_q` where `q = 0`, `δ = 1/slope`.
fn cot_line(
    c: &Curve,
    lags: &[f64],
    sp: f64,
    idx: &[usize],
    shear: Option<Shear>,
) -> Option<(f64, f64, f64, f64)> {
    // in the sheared `u′ = Ω² − B a^p` a nonlinear stiffness with linear
    // damping has `−Ω cot φ = (u′ − α_eff(a_ref))/δ` exactly
    let a_ref = c.amplitudes[idx[idx.len() / 2]];
    let us: Vec<f64> = idx
        .iter()
        .map(|&i| c.omegas[i].powi(2) - Shear::at(shear, c.amplitudes[i]) + Shear::at(shear, a_ref))
        .collect();
    let u_c = us[0];
    let (umin, umax) = us
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &u| {
            (l.min(u), h.max(u))
        });
    let span = (umax - umin).max(f64::MIN_POSITIVE);
    let mut rows = Vec::new();
    let mut y = Vec::new();
    let mut w = Vec::new();
    for (k, &i) in idx.iter().enumerate() {
        let (om, ph) = (c.omegas[i], lags[i]);
        let s = ph.sin();
        if s.abs() < 1e-3 {
            return None;
        }
        rows.push([1.0, (us[k] - u_c) / span, 0.0]);
        y.push(-om * ph.cos() / s);
        // var q = Ω² σ_φ² / sin⁴φ
        w.push(s.powi(4) / (om * om * sp * sp));
    }
    let (coef, cov) = wls(&rows, 2, &y, &w)?;
    let (a0, b0) = (coef[0], coef[1]);
    if b0.is_nan() || b0 <= 0.0 {
        return None;
    }
    let t_q = -a0 / b0;
    let u_q = u_c + t_q * span;
    let delta = span / b0;
    // gradients: t_q wrt (a0, b0) = (−1/b0, a0/b0²); δ wrt b0 = −span/b0²
    let (ga, gb) = (-1.0 / b0, a0 / (b0 * b0));
    let var_t = ga * ga * cov[0][0] + 2.0 * ga * gb * cov[0][1] + gb * gb * cov[1][1];
    let var_d = (span / (b0 * b0)).powi(2) * cov[1][1];
    (u_q > 0.0 && delta > 0.0).then(|| {
        (
            u_q,
            delta,
            var_t.max(0.0).sqrt() * span,
            var_d.max(0.0).sqrt(),
        )
    })
}

/// Points of the branch `seg` whose lag is within `half` of 90°, as a
/// contiguous run around the crossing step `(i, i + 1)`, at least those two.
fn window_around(lags: &[f64], i: usize, seg: (usize, usize), half: f64) -> Vec<usize> {
    let mut l = i;
    while l > seg.0 && (lags[l - 1] - HALF_PI).abs() <= half {
        l -= 1;
    }
    let mut r = i + 1;
    while r < seg.1 && (lags[r + 1] - HALF_PI).abs() <= half {
        r += 1;
    }
    (l..=r).collect()
}

fn find_quadrature(
    c: &Curve,
    lags: &[f64],
    sp: f64,
    sigma: &[f64],
    split: Option<usize>,
    range: (usize, usize),
    imax: usize,
) -> Option<Quadrature> {
    let n = c.omegas.len();
    // the branch the crossing must lie on (not across the jump step)
    let seg_of = |i: usize| match split {
        Some(s) if i <= s => (0, s),
        Some(s) => (s + 1, n - 1),
        None => (0, n - 1),
    };
    let crossing = (range.0..range.1)
        .filter(|&i| Some(i) != split)
        .filter(|&i| (lags[i] - HALF_PI) * (lags[i + 1] - HALF_PI) <= 0.0 && lags[i] != lags[i + 1])
        .min_by_key(|&i| i.abs_diff(imax))?;
    let seg = seg_of(crossing);
    let seg = (seg.0.max(range.0), seg.1.min(range.1));
    let half = (QUADRATURE_WINDOW_SIGMAS * sp).min(QUADRATURE_WINDOW_DEG.to_radians());
    let idx = window_around(lags, crossing, seg, half);
    let (u_q, _, s_u, _) = cot_line(c, lags, sp, &idx, None)?;
    let w = u_q.sqrt();
    let (w0, w1) = (c.omegas[crossing], c.omegas[crossing + 1]);
    // the crossing must stay within its bracketing step (a line fitted to
    // a window that bends could move it out)
    let w = w.clamp(w0, w1);
    let t = (w - w0) / (w1 - w0);
    let (a0, a1) = (c.amplitudes[crossing], c.amplitudes[crossing + 1]);
    // the amplitude there: the parabola in the lag through the pair and the
    // next point on the branch (the lag, not the frequency: near a fold the
    // amplitude has a square-root singularity in Ω but none in φ), else
    // linear
    let below = crossing.checked_sub(1).filter(|&k| k >= seg.0);
    let above = Some(crossing + 2).filter(|&k| k <= seg.1);
    let third = if t < 0.5 {
        below.or(above)
    } else {
        above.or(below)
    };
    let lin = a0 + t * (a1 - a0);
    let a = third
        .and_then(|k| {
            let pts = [crossing, crossing + 1, k];
            let mut y = 0.0;
            for &i in &pts {
                let mut l = 1.0;
                for &j in pts.iter().filter(|&&j| j != i) {
                    let d = lags[i] - lags[j];
                    if d.abs() < 1e-12 {
                        return None;
                    }
                    l *= (HALF_PI - lags[j]) / d;
                }
                y += l * c.amplitudes[i];
            }
            Some(y)
        })
        .filter(|a| a.is_finite() && (a - lin).abs() <= 0.1 * lin)
        .unwrap_or(lin);
    let s_w = s_u / (2.0 * w);
    let slope_a = (a1 - a0) / (w1 - w0);
    let s_a = (((1.0 - t) * sigma[crossing]).powi(2)
        + (t * sigma[crossing + 1]).powi(2)
        + (slope_a * s_w).powi(2))
    .sqrt();
    let phase_slope = (lags[crossing + 1] - lags[crossing]) / (w1 - w0);
    Some(Quadrature {
        omega: w,
        f_hz: w / TWO_PI,
        amplitude: a,
        normalised: a / c.gamma,
        phase_slope,
        sigma_omega: s_w,
        sigma_amplitude: s_a,
    })
}

fn phase_slope(
    c: &Curve,
    lags: &[f64],
    sp: f64,
    split: Option<usize>,
    omega_q: f64,
    shear: Option<Shear>,
) -> Option<DampingEstimate> {
    let n = c.omegas.len();
    let i = c
        .omegas
        .iter()
        .position(|&w| w >= omega_q)?
        .checked_sub(1)?;
    if Some(i) == split || i + 1 >= n {
        return None;
    }
    let seg = match split {
        Some(s) if i <= s => (0, s),
        Some(s) => (s + 1, n - 1),
        None => (0, n - 1),
    };
    let idx = window_around(lags, i, seg, SLOPE_WINDOW_DEG.to_radians());
    let (_, delta, _, s_d) = cot_line(c, lags, sp, &idx, shear)?;
    let wn = omega_q;
    Some(DampingEstimate {
        method: DampingMethod::PhaseSlope,
        zeta: delta / (2.0 * wn),
        delta,
        omega_n: wn,
        f_n_hz: wn / TWO_PI,
        f_low_hz: None,
        f_high_hz: None,
        sigma_delta: s_d,
    })
}

/// Half-power damping (module docs) of a jump-free curve with a refined
/// peak.
fn half_power(
    c: &Curve,
    sigma: &[f64],
    peak: &Peak,
    has_jump: bool,
    shear: Option<Shear>,
) -> Option<DampingEstimate> {
    if has_jump || peak.kind != PeakKind::Refined {
        return None;
    }
    let n = c.omegas.len();
    let level = peak.amplitude / 2f64.sqrt();
    let y_half = level.powi(-2);
    // the crossing on each side, interpolated in (Ω², 1/a²)
    let cross = |i: usize, j: usize| -> Option<(f64, f64)> {
        let (ai, aj) = (c.amplitudes[i], c.amplitudes[j]);
        if !(ai > 0.0 && aj > 0.0) {
            return None;
        }
        let (yi, yj) = (ai.powi(-2), aj.powi(-2));
        // sheared `u′ = Ω² − B a^p + B a_p^p`: the half-power points of a
        // nonlinear stiffness with linear damping are then those of a
        // linear SDoF (module docs)
        let f_p = Shear::at(shear, peak.amplitude);
        let (ui, uj) = (
            c.omegas[i].powi(2) - Shear::at(shear, ai) + f_p,
            c.omegas[j].powi(2) - Shear::at(shear, aj) + f_p,
        );
        let t = (y_half - yi) / (yj - yi);
        let u = ui + t * (uj - ui);
        // σ of u from the noise of the two amplitudes
        let dy_da = |a: f64| -2.0 * a.powi(-3);
        let du_dyi = -(uj - ui) * (1.0 - t) / (yj - yi);
        let du_dyj = -(uj - ui) * t / (yj - yi);
        let var = (du_dyi * dy_da(ai) * sigma[i]).powi(2) + (du_dyj * dy_da(aj) * sigma[j]).powi(2);
        Some((u, var))
    };
    let mut left = None;
    let mut i = peak.index;
    while i > 0 {
        if c.amplitudes[i - 1] <= level && c.amplitudes[i] > level {
            left = cross(i - 1, i);
            break;
        }
        i -= 1;
    }
    let mut right = None;
    let mut i = peak.index;
    while i + 1 < n {
        if c.amplitudes[i + 1] <= level && c.amplitudes[i] > level {
            right = cross(i, i + 1);
            break;
        }
        i += 1;
    }
    let ((u1, v1), (u2, v2)) = (left?, right?);
    let up = peak.omega * peak.omega;
    let d = 0.5 * (u2 - u1);
    if d.is_nan() || d <= 0.0 {
        return None;
    }
    // δ² = 2(−u_p + √(u_p² + D²))  (exact for a linear SDoF)
    let root = (up * up + d * d).sqrt();
    let d2 = 2.0 * (d * d / (root + up));
    let delta = d2.sqrt();
    let wn = (up + 0.5 * d2).sqrt();
    // dδ/dD = 2D / (δ · root) (from δ² = 2(root − u_p))
    let dd_dd = 2.0 * d / (delta * root);
    let sigma_delta = dd_dd * 0.5 * (v1 + v2).sqrt();
    Some(DampingEstimate {
        method: DampingMethod::HalfPower,
        zeta: delta / (2.0 * wn),
        delta,
        omega_n: wn,
        f_n_hz: wn / TWO_PI,
        f_low_hz: Some(u1.max(0.0).sqrt() / TWO_PI),
        f_high_hz: Some(u2.max(0.0).sqrt() / TWO_PI),
        sigma_delta,
    })
}

// ---------------------------------------------------------------------------
// Levels
// ---------------------------------------------------------------------------

fn combine(cands: &[(usize, Candidate)]) -> (Vec<usize>, Candidate) {
    // inverse-variance mean of jump-free candidates of one source
    let wsum_w: f64 = cands.iter().map(|(_, c)| c.sigma_omega.powi(-2)).sum();
    let wsum_a: f64 = cands.iter().map(|(_, c)| c.sigma_amplitude.powi(-2)).sum();
    let omega = cands
        .iter()
        .map(|(_, c)| c.omega * c.sigma_omega.powi(-2))
        .sum::<f64>()
        / wsum_w;
    let amplitude = cands
        .iter()
        .map(|(_, c)| c.amplitude * c.sigma_amplitude.powi(-2))
        .sum::<f64>()
        / wsum_a;
    let first = cands[0].1;
    (
        cands.iter().map(|(i, _)| *i).collect(),
        Candidate {
            omega,
            amplitude,
            sigma_omega: wsum_w.powf(-0.5),
            sigma_amplitude: wsum_a.powf(-0.5),
            refined: cands.iter().all(|(_, c)| c.refined),
            ..first
        },
    )
}

fn level_points(data: &Dataset, works: &[CurveWork]) -> Vec<LevelPoint> {
    let mut out = Vec::new();
    for (level, gamma) in data.levels() {
        let of_level: Vec<usize> = (0..works.len())
            .filter(|&k| data.curves[k].level == level)
            .collect();
        let quads: Vec<(usize, Candidate)> = of_level
            .iter()
            .filter_map(|&k| works[k].quadrature.map(|c| (k, c)))
            .collect();
        let peaks: Vec<(usize, Candidate)> = of_level
            .iter()
            .filter_map(|&k| works[k].peak.map(|c| (k, c)))
            .collect();
        let chosen = if !quads.is_empty() {
            Some(pick(&quads))
        } else if !peaks.is_empty() {
            Some(pick(&peaks))
        } else {
            None
        };
        let Some((curves, c)) = chosen else { continue };
        let delta_eq = gamma / (c.amplitude * c.omega);
        let rel =
            ((c.sigma_amplitude / c.amplitude).powi(2) + (c.sigma_omega / c.omega).powi(2)).sqrt();
        let correction = if c.refined {
            0.5 * delta_eq * delta_eq
        } else {
            0.0
        };
        out.push(LevelPoint {
            level,
            gamma,
            source: c.source,
            curves,
            omega: c.omega,
            f_hz: c.omega / TWO_PI,
            amplitude: c.amplitude,
            normalised: c.amplitude / gamma,
            velocity: c.omega * c.amplitude,
            delta_eq,
            zeta_eq: delta_eq / (2.0 * c.omega),
            omega_backbone: (c.omega * c.omega + correction).sqrt(),
            corrected: c.refined,
            sigma_omega: c.sigma_omega,
            sigma_amplitude: c.sigma_amplitude,
            sigma_delta_eq: delta_eq * rel,
            used: true,
        });
    }
    out
}

/// One level's candidates: all jump-free ones averaged, else the one of
/// the highest amplitude (the branch that went furthest up).
fn pick(cands: &[(usize, Candidate)]) -> (Vec<usize>, Candidate) {
    if cands.iter().all(|(_, c)| c.jump_free) {
        return combine(cands);
    }
    let best = cands
        .iter()
        .max_by(|a, b| a.1.amplitude.total_cmp(&b.1.amplitude))
        .copied()
        .unwrap_or(cands[0]);
    (vec![best.0], best.1)
}

// ---------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------

/// Two-sided 95 % Student t quantile `t₀.₉₇₅(ν)`: tabulated to 8 digits
/// for ν ≤ 30, [`super::uncertainty::t95`] (error < 2e-4) beyond.
pub fn t975(dof: usize) -> Option<f64> {
    const T: [f64; 30] = [
        12.706_204_7,
        4.302_652_7,
        3.182_446_3,
        2.776_445_1,
        2.570_581_8,
        2.446_911_9,
        2.364_624_3,
        2.306_004_1,
        2.262_157_2,
        2.228_138_9,
        2.200_985_2,
        2.178_812_8,
        2.160_368_7,
        2.144_786_7,
        2.131_449_5,
        2.119_905_3,
        2.109_815_6,
        2.100_922_0,
        2.093_024_1,
        2.085_963_4,
        2.079_613_8,
        2.073_873_1,
        2.068_657_6,
        2.063_898_6,
        2.059_538_6,
        2.055_529_4,
        2.051_830_5,
        2.048_407_1,
        2.045_229_6,
        2.042_272_5,
    ];
    match dof {
        0 => None,
        1..=30 => Some(T[dof - 1]),
        _ => Some(super::uncertainty::t95(dof)),
    }
}

/// Upper tail `Q(k/2, x/2) = P(χ²_k > x)` of the χ² distribution: the
/// regularised incomplete gamma function by its series below `a + 1` and
/// its continued fraction (modified Lentz) above (Numerical Recipes §6.2).
pub fn chi2_sf(k: usize, x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return 1.0;
    }
    let a = 0.5 * k as f64;
    let x = 0.5 * x;
    let ln_pre = a * x.ln() - x - libm::lgamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * ln_pre.exp()).clamp(0.0, 1.0)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (ln_pre.exp() * h).clamp(0.0, 1.0)
    }
}

/// The χ²_k quantile at upper tail probability [`SIGNIFICANCE`] (bisection
/// of [`chi2_sf`]).
pub fn chi2_upper(k: usize) -> f64 {
    let k = k.max(1);
    let (mut lo, mut hi) = (0.0, 10.0 * k as f64 + 100.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_sf(k, mid) > SIGNIFICANCE {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// χ² of values about their weighted mean.
fn chi2_about_mean(v: &[(f64, f64)]) -> f64 {
    let w: f64 = v.iter().map(|(_, s)| s.powi(-2)).sum();
    let mean = v.iter().map(|(x, s)| x * s.powi(-2)).sum::<f64>() / w;
    v.iter().map(|(x, s)| ((x - mean) / s).powi(2)).sum()
}

fn change_percent(v: impl Iterator<Item = f64>) -> f64 {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if lo > 0.0 && hi.is_finite() {
        100.0 * (hi - lo) / lo
    } else {
        0.0
    }
}

fn homogeneity(levels: &[LevelPoint]) -> Option<Homogeneity> {
    let l = levels.len();
    if l < 2 {
        return None;
    }
    let k = (l - 1) as f64;
    let h: Vec<(f64, f64)> = levels
        .iter()
        .map(|p| (p.normalised, p.sigma_amplitude / p.gamma))
        .collect();
    let w: Vec<(f64, f64)> = levels
        .iter()
        .map(|p| (p.omega_backbone, p.sigma_omega))
        .collect();
    let d: Vec<(f64, f64)> = levels
        .iter()
        .map(|p| (p.delta_eq, p.sigma_delta_eq))
        .collect();
    let (ch, cw, cd) = (
        chi2_about_mean(&h),
        chi2_about_mean(&w),
        chi2_about_mean(&d),
    );
    let index = ((ch + cw) / (2.0 * k)).sqrt();
    let threshold = (chi2_upper(2 * (l - 1)) / (2.0 * k)).sqrt();
    let threshold_single = (chi2_upper(l - 1) / k).sqrt();
    Some(Homogeneity {
        levels: l,
        index,
        index_normalised_peak: (ch / k).sqrt(),
        index_frequency: (cw / k).sqrt(),
        index_damping: (cd / k).sqrt(),
        threshold,
        threshold_single,
        linear_within_noise: index <= threshold,
        frequency_shift_percent: change_percent(levels.iter().map(|p| p.omega)),
        normalised_peak_change_percent: change_percent(levels.iter().map(|p| p.normalised)),
        damping_change_percent: change_percent(levels.iter().map(|p| p.delta_eq)),
    })
}

// ---------------------------------------------------------------------------
// Power-law regression
// ---------------------------------------------------------------------------

/// One point of a regression: value, variances and covariance of its errors.
#[derive(Debug, Clone, Copy)]
struct Obs {
    x: f64,
    y: f64,
    var_x: f64,
    var_y: f64,
    cov: f64,
}

/// A fit of `y = c + B x^p` (internal).
#[derive(Debug, Clone, Copy)]
struct RawFit {
    c: f64,
    /// The signed prefactor `B = s e^b`.
    big_b: f64,
    p: f64,
    chi2: f64,
    /// `(JᵀWJ)⁻¹` in (c, B, p) (the c row and column zero when held).
    cov: [[f64; 3]; 3],
    c_held: bool,
    p_at_bound: bool,
    n: usize,
    /// Profile-t interval of `p` (module docs); the flags say where it
    /// reached the end of [`EXPONENT_RANGE`].
    interval: Option<[f64; 2]>,
    open: (bool, bool),
}

impl RawFit {
    fn f(&self, x: f64) -> f64 {
        self.c + self.big_b * x.powf(self.p)
    }
    fn dof(&self) -> usize {
        self.n.saturating_sub(3)
    }
}

fn eff_var(o: &Obs, fp: f64) -> f64 {
    let v = o.var_y - 2.0 * fp * o.cov + fp * fp * o.var_x;
    v.max(1e-30 * o.y.abs().max(1e-300).powi(2))
        .max(f64::MIN_POSITIVE)
}

/// The weighted linear fit of `y = c + B x^p` at fixed `p` (the model is
/// linear in `c` and `B`) with `c ≥ c_min` and, for `sign = Some(s)`,
/// `s B ≥ 0`: `(χ², c, B, c held)`.
fn fixed_exponent(
    obs: &[Obs],
    v: &[f64],
    p: f64,
    c_min: f64,
    sign: Option<f64>,
) -> (f64, f64, f64, bool) {
    let xs: Vec<f64> = obs.iter().map(|o| o.x.powf(p)).collect();
    let chi2 = |c: f64, bb: f64| -> f64 {
        obs.iter()
            .zip(&xs)
            .zip(v)
            .map(|((o, &x), &vi)| (o.y - c - bb * x).powi(2) / vi)
            .sum()
    };
    // a constant (B = 0) at its weighted mean, at least c_min
    let constant = || {
        let w: f64 = v.iter().map(|vi| 1.0 / vi).sum();
        let c = (obs.iter().zip(v).map(|(o, vi)| o.y / vi).sum::<f64>() / w).max(c_min);
        (chi2(c, 0.0), c, 0.0, false)
    };
    // unconstrained, with x^p scaled for conditioning
    let scale = xs
        .iter()
        .fold(0.0f64, |m, &x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    let rows: Vec<[f64; 2]> = xs.iter().map(|&x| [1.0, x / scale]).collect();
    let y: Vec<f64> = obs.iter().map(|o| o.y).collect();
    let w: Vec<f64> = v.iter().map(|vi| 1.0 / vi).collect();
    let mut best = match wls(&rows, 2, &y, &w) {
        Some((coef, _)) => {
            let (c, bb) = (coef[0], coef[1] / scale);
            if c >= c_min {
                (chi2(c, bb), c, bb, false)
            } else {
                // c held at its bound: B alone
                let num: f64 = obs
                    .iter()
                    .zip(&xs)
                    .zip(v)
                    .map(|((o, &x), &vi)| x * (o.y - c_min) / vi)
                    .sum();
                let den: f64 = xs.iter().zip(v).map(|(&x, &vi)| x * x / vi).sum();
                let bb = if den > 0.0 { num / den } else { 0.0 };
                (chi2(c_min, bb), c_min, bb, true)
            }
        }
        None => constant(),
    };
    if let Some(s) = sign {
        if best.2 * s < 0.0 {
            best = constant();
        }
    }
    if !best.0.is_finite() {
        best = constant();
    }
    best
}

/// The profile `χ²(p)` minimised over a grid of [`EXPONENT_RANGE`] (steps of
/// 0.05) and refined by golden section: `(p, χ², c, B, held)`.
fn profile_min(
    obs: &[Obs],
    v: &[f64],
    c_min: f64,
    sign: Option<f64>,
) -> (f64, f64, f64, f64, bool) {
    let (lo, hi) = EXPONENT_RANGE;
    let n = ((hi - lo) / 0.05).round() as usize;
    let at = |p: f64| fixed_exponent(obs, v, p, c_min, sign);
    let mut best = (lo, f64::INFINITY);
    let mut k_best = 0;
    for k in 0..=n {
        let p = lo + (hi - lo) * k as f64 / n as f64;
        let f = at(p).0;
        if f < best.1 {
            best = (p, f);
            k_best = k;
        }
    }
    let step = (hi - lo) / n as f64;
    let (mut a, mut b) = (
        (lo + step * k_best as f64 - step).max(lo),
        (lo + step * k_best as f64 + step).min(hi),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (at(x1).0, at(x2).0);
    for _ in 0..80 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = at(x1).0;
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = at(x2).0;
        }
    }
    let p = if f1 < f2 { x1 } else { x2 };
    let p = if at(p).0 <= best.1 { p } else { best.0 };
    let (chi2, c, bb, held) = at(p);
    (p, chi2, c, bb, held)
}

/// Fits `y = c + B x^p` (module docs): the exponent by its profile (the
/// model is linear in `c` and `B` at fixed `p`), the effective-variance
/// weights updated from `f′` four times; the covariance `(JᵀWJ)⁻¹` and the
/// profile-t interval `{p : χ²(p) − χ²_min ≤ t² χ²_min/(L − 3)}`.
fn fit_law(obs: &[Obs], c_min: f64, sign: Option<f64>) -> Option<RawFit> {
    let l = obs.len();
    if l < 3 {
        return None;
    }
    let mut v: Vec<f64> = obs.iter().map(|o| eff_var(o, 0.0)).collect();
    let mut est = profile_min(obs, &v, c_min, sign);
    for _ in 0..4 {
        let (p, _, _, bb, _) = est;
        v = obs
            .iter()
            .map(|o| eff_var(o, bb * p * o.x.powf(p - 1.0)))
            .collect();
        est = profile_min(obs, &v, c_min, sign);
    }
    let (p, chi2, c, bb, held) = est;
    if !(p.is_finite() && chi2.is_finite() && c.is_finite() && bb.is_finite()) {
        return None;
    }
    // covariance in (c, B, p)
    let free: Vec<usize> = if held { vec![1, 2] } else { vec![0, 1, 2] };
    let m = free.len();
    let mut a = [[0.0; 3]; 3];
    for (o, &vi) in obs.iter().zip(&v) {
        let xp = o.x.powf(p);
        let j = [1.0, xp, bb * xp * o.x.ln()];
        for (r, &fr) in free.iter().enumerate() {
            for (q, &fq) in free.iter().enumerate() {
                a[r][q] += j[fr] * j[fq] / vi;
            }
        }
    }
    let mut cov = [[f64::INFINITY; 3]; 3];
    if let Some(inv) = invert(&a, m) {
        cov = [[0.0; 3]; 3];
        for (r, &fr) in free.iter().enumerate() {
            for (q, &fq) in free.iter().enumerate() {
                cov[fr][fq] = inv[r][q];
            }
        }
    }
    let (lo, hi) = EXPONENT_RANGE;
    let p_at_bound = p <= lo + 0.01 || p >= hi - 0.01;
    // profile-t interval
    let dof = l - 3;
    let mut interval = None;
    let mut open = (false, false);
    if let Some(t) = t975(dof) {
        let s2 = chi2 / dof as f64;
        let limit = chi2 + t * t * s2;
        let prof = |q: f64| fixed_exponent(obs, &v, q, c_min, sign).0;
        let edge = |toward: f64| -> (f64, bool) {
            // walk out in steps of 0.05 until the profile crosses, then bisect
            let mut inner = p;
            let mut k = 0;
            loop {
                k += 1;
                let q = (p + toward * 0.05 * k as f64).clamp(lo, hi);
                if prof(q) > limit {
                    let mut outer = q;
                    for _ in 0..60 {
                        let mid = 0.5 * (inner + outer);
                        if prof(mid) > limit {
                            outer = mid;
                        } else {
                            inner = mid;
                        }
                    }
                    return (0.5 * (inner + outer), false);
                }
                inner = q;
                if q <= lo || q >= hi {
                    return (q, true);
                }
            }
        };
        let (l_end, l_open) = edge(-1.0);
        let (h_end, h_open) = edge(1.0);
        interval = Some([l_end, h_end]);
        open = (l_open, h_open);
    }
    Some(RawFit {
        c,
        big_b: bb,
        p,
        chi2,
        cov,
        c_held: held,
        p_at_bound,
        n: l,
        interval,
        open,
    })
}

fn law_fit(raw: &RawFit, levels: Vec<String>) -> LawFit {
    let dof = raw.dof();
    let s2 = if dof > 0 {
        raw.chi2 / dof as f64
    } else {
        f64::NAN
    };
    let t = t975(dof);
    let se = |k: usize| -> Option<f64> {
        let v = raw.cov[k][k] * s2;
        (dof > 0 && v.is_finite() && v >= 0.0).then(|| v.sqrt())
    };
    let (se_p, se_c) = (se(2), if raw.c_held { None } else { se(0) });
    let ci_c = match (t, se_c) {
        (Some(t), Some(se)) => Some([raw.c - t * se, raw.c + t * se]),
        _ => None,
    };
    let interval_note = if dof == 0 {
        Some(format!(
            "no interval: {} levels for 3 parameters (a fourth level gives one)",
            raw.n
        ))
    } else if raw.open.0 || raw.open.1 {
        Some(format!(
            "the 95 % interval reaches the end of the exponent range [{}, {}]: these levels do not bound it",
            EXPONENT_RANGE.0, EXPONENT_RANGE.1
        ))
    } else {
        None
    };
    LawFit {
        exponent: raw.p,
        exponent_se: se_p,
        exponent_ci95: raw.interval,
        intercept: raw.c,
        intercept_se: se_c,
        intercept_ci95: ci_c,
        coefficient: raw.big_b / g_unchecked(raw.p),
        prefactor: raw.big_b,
        dof,
        t95: t,
        scatter: (dof > 0).then(|| s2.sqrt()),
        intercept_held: raw.c_held,
        exponent_at_bound: raw.p_at_bound,
        interval_open: raw.open.0 || raw.open.1,
        levels,
        interval_note,
    }
}

fn backbone_obs(levels: &[&LevelPoint]) -> Vec<Obs> {
    levels
        .iter()
        .map(|p| {
            let w = p.omega_backbone;
            Obs {
                x: p.amplitude,
                y: w * w,
                var_x: p.sigma_amplitude.powi(2),
                var_y: (2.0 * w * p.sigma_omega).powi(2),
                cov: 0.0,
            }
        })
        .collect()
}

fn damping_obs(levels: &[&LevelPoint]) -> Vec<Obs> {
    levels
        .iter()
        .map(|p| {
            // V = Ω a; δ_eq = γ/V: a velocity error moves the point along
            // the hyperbola (cov = −(δ/V) var V)
            let var_v = p.velocity.powi(2)
                * ((p.sigma_amplitude / p.amplitude).powi(2) + (p.sigma_omega / p.omega).powi(2));
            Obs {
                x: p.velocity,
                y: p.delta_eq,
                var_x: var_v,
                var_y: (p.delta_eq / p.velocity).powi(2) * var_v,
                cov: -(p.delta_eq / p.velocity) * var_v,
            }
        })
        .collect()
}

/// The backbone (either sign of `g(ρ) β`, `ω₀² ≥ 0`).
fn fit_backbone(levels: &[&LevelPoint]) -> Option<RawFit> {
    fit_law(&backbone_obs(levels), 0.0, None)
}

/// The damping law (`κ ≥ 0`, `δ₀ ≥ 0`).
fn fit_damping(levels: &[&LevelPoint]) -> Option<RawFit> {
    fit_law(&damping_obs(levels), 0.0, Some(1.0))
}

/// The stiffness and damping laws, the early-jump check, the peak
/// correction's second pass.
fn laws(
    levels: &mut [LevelPoint],
    works: &mut [CurveWork],
    any_jump: bool,
) -> (StiffnessLaw, DampingLaw, Option<Shear>) {
    let l = levels.len();
    let chi2_w = (l >= 2).then(|| {
        chi2_about_mean(
            &levels
                .iter()
                .map(|p| (p.omega_backbone, p.sigma_omega))
                .collect::<Vec<_>>(),
        )
    });
    let chi2_d = (l >= 2).then(|| {
        chi2_about_mean(
            &levels
                .iter()
                .map(|p| (p.delta_eq, p.sigma_delta_eq))
                .collect::<Vec<_>>(),
        )
    });
    let crit = (l >= 2).then(|| chi2_upper(l - 1));
    let w_changes = matches!((chi2_w, crit), (Some(c), Some(q)) if c > q);
    let d_changes = matches!((chi2_d, crit), (Some(c), Some(q)) if c > q);
    let mut s_note = None;
    let mut d_note = None;
    let names = |v: &[&LevelPoint]| v.iter().map(|p| p.level.clone()).collect::<Vec<_>>();
    // early jumps: phases that never reached 90° first
    for p in levels.iter_mut() {
        if p.curves.iter().any(|&k| works[k].missed_quadrature) && p.source == ResonanceSource::Peak
        {
            p.used = false;
            for &k in &p.curves {
                if let Some(j) = works[k].report.jump.as_mut() {
                    j.early = Some(true);
                }
            }
        }
    }
    let fit_all = |levels: &[LevelPoint]| -> (Option<RawFit>, Option<RawFit>) {
        let used: Vec<&LevelPoint> = levels.iter().filter(|p| p.used).collect();
        if used.len() < 3 {
            return (None, None);
        }
        (fit_backbone(&used), fit_damping(&used))
    };
    let (mut bb, mut dm) = fit_all(levels);
    // the backbone test of each drop jump (leave-one-level-out with four or
    // more levels in the fit)
    let mut flagged = false;
    if bb.is_some() {
        for i in 0..levels.len() {
            let p = &levels[i];
            if !p.used || p.source != ResonanceSource::Peak {
                continue;
            }
            let Some(&k) = p.curves.first() else { continue };
            let Some((wj, aj, _)) = works[k].before_drop else {
                continue;
            };
            let others: Vec<&LevelPoint> = levels
                .iter()
                .enumerate()
                .filter(|(m, q)| *m != i && q.used)
                .map(|(_, q)| q)
                .collect();
            let (fit, pts) = if others.len() >= 3 {
                (fit_backbone(&others), others)
            } else {
                (bb, levels.iter().filter(|q| q.used).collect())
            };
            let Some(f) = fit else { continue };
            let w2 = f.f(aj);
            if w2.is_nan() || w2 <= 0.0 {
                continue;
            }
            let wbb = w2.sqrt();
            let dir = if works[k].report.direction == SweepDirection::Up {
                1.0
            } else {
                -1.0
            };
            let ahead = dir * (wbb - wj);
            // the backbone's own scatter about its points, in frequency
            let rms = (pts
                .iter()
                .map(|q| (q.omega_backbone - f.f(q.amplitude).max(0.0).sqrt()).powi(2))
                .sum::<f64>()
                / pts.len() as f64)
                .sqrt();
            let step = works[k]
                .report
                .jump
                .as_ref()
                .map_or(0.0, |j| (j.omega_after - j.omega_before).abs());
            let tol = 3.0 * (p.sigma_omega.powi(2) + rms * rms).sqrt() + step;
            let early = ahead > tol;
            if let Some(j) = works[k].report.jump.as_mut() {
                j.early = Some(early);
                j.early_by_hz = Some(ahead / TWO_PI);
            }
            if early {
                levels[i].used = false;
                flagged = true;
            }
        }
    }
    if flagged || levels.iter().any(|p| !p.used) {
        (bb, dm) = fit_all(levels);
    }
    // second pass of the peak correction with the damping law
    if let Some(d) = dm {
        let changed = levels.iter().any(|p| p.refined_free());
        if changed {
            let eta = d.p;
            for p in levels.iter_mut().filter(|p| p.refined_free()) {
                let ceq = (p.delta_eq - d.c).max(0.0);
                let corr = (0.5 * p.delta_eq * (d.c + (1.0 + eta) * ceq))
                    .clamp(0.0, 2.0 * p.delta_eq * p.delta_eq);
                p.omega_backbone = (p.omega * p.omega + corr).sqrt();
            }
            let used: Vec<&LevelPoint> = levels.iter().filter(|p| p.used).collect();
            if used.len() >= 3 {
                bb = fit_backbone(&used);
            }
        }
    }
    let used: Vec<&LevelPoint> = levels.iter().filter(|p| p.used).collect();
    let n_used = used.len();
    if n_used < 3 {
        let why = format!(
            "{} level{} with a usable resonance point: the laws need three (intercept, coefficient, exponent) and four for an interval",
            n_used,
            if n_used == 1 { "" } else { "s" }
        );
        s_note = Some(why.clone());
        d_note = Some(why);
    }
    let shear = bb.map(|f| Shear { b: f.big_b, p: f.p });
    let stiffness_fit = bb.map(|f| law_fit(&f, names(&used)));
    let damping_fit = dm.map(|f| law_fit(&f, names(&used)));
    // the sign: the law's, else the jumps', else the trend
    let jump_sign = works.iter().find_map(|w| {
        let j = w.report.jump.as_ref()?;
        Some(matches!(
            (j.kind, w.report.direction),
            (JumpKind::Drop, SweepDirection::Up) | (JumpKind::Rise, SweepDirection::Down)
        ))
    });
    let trend_sign = (l >= 2).then(|| {
        let lo = levels
            .iter()
            .min_by(|a, b| a.amplitude.total_cmp(&b.amplitude))
            .map(|p| p.omega_backbone);
        let hi = levels
            .iter()
            .max_by(|a, b| a.amplitude.total_cmp(&b.amplitude))
            .map(|p| p.omega_backbone);
        matches!((lo, hi), (Some(a), Some(b)) if b > a)
    });
    let nonlinear = w_changes || any_jump;
    let hardening = if !nonlinear {
        None
    } else if let Some(f) = &stiffness_fit {
        Some(f.prefactor > 0.0)
    } else {
        jump_sign.or(trend_sign)
    };
    let f0_hz = stiffness_fit
        .as_ref()
        .filter(|f| f.intercept > 0.0)
        .map(|f| f.intercept.sqrt() / TWO_PI);
    if l < 2 {
        s_note = Some(
            "one level: whether the resonance moves with the level needs two levels or more".into(),
        );
        d_note = Some(
            "one level: whether the damping changes with the level needs two levels or more".into(),
        );
    }
    (
        StiffnessLaw {
            nonlinear,
            chi2: chi2_w,
            hardening,
            fit: stiffness_fit,
            f0_hz,
            note: s_note,
        },
        DampingLaw {
            nonlinear: d_changes,
            chi2: chi2_d,
            fit: damping_fit,
            note: d_note,
        },
        shear,
    )
}

impl LevelPoint {
    /// A refined, jump-free peak: its backbone frequency is corrected.
    fn refined_free(&self) -> bool {
        self.source == ResonanceSource::Peak && self.corrected
    }
}

// ---------------------------------------------------------------------------
// Recommendation
// ---------------------------------------------------------------------------

fn fmt_ci(f: &LawFit) -> String {
    match f.exponent_ci95 {
        Some([a, b]) => format!("{:.3} [{:.3}, {:.3}]", f.exponent, a, b),
        None => format!("{:.3} (no interval)", f.exponent),
    }
}

fn recommend(
    data: &Dataset,
    curves: &[CurveReport],
    levels: &[LevelPoint],
    hom: &Option<Homogeneity>,
    st: &StiffnessLaw,
    dm: &DampingLaw,
    phase: &PhaseReport,
) -> Recommendation {
    let mut evidence = Vec::new();
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let mut pinned = Vec::new();
    let n_levels = data.levels().len();
    let n_used = levels.iter().filter(|p| p.used).count();
    // evidence: homogeneity
    if let Some(h) = hom {
        evidence.push(format!(
            "linearity index {:.2} (threshold {:.2} at 99.9 %): normalised peaks {:.2}, resonance frequencies {:.2}, damping {:.2} in units of the noise; resonance moves {:.3} % and a/gamma changes {:.1} % across {} levels",
            h.index,
            h.threshold,
            h.index_normalised_peak,
            h.index_frequency,
            h.index_damping,
            h.frequency_shift_percent,
            h.normalised_peak_change_percent,
            h.levels
        ));
    } else {
        notes.push("homogeneity needs two levels or more: one level gives its own peak, damping and jumps only".into());
    }
    let jumps: Vec<String> = curves
        .iter()
        .filter_map(|c| {
            let j = c.jump.as_ref()?;
            Some(format!(
                "{} ({}) {} {} -> {} Hz (ratio {:.2})",
                c.level,
                c.direction.name(),
                if j.kind == JumpKind::Drop {
                    "drops"
                } else {
                    "rises"
                },
                fmt_hz(j.f_before_hz),
                fmt_hz(j.f_after_hz),
                j.ratio
            ))
        })
        .collect();
    if !jumps.is_empty() {
        evidence.push(format!(
            "jumps (folds need a nonlinear stiffness): {}",
            jumps.join("; ")
        ));
    }
    // stiffness
    let stiff_word = match (st.nonlinear, st.hardening) {
        (false, _) => "linear",
        (true, Some(true)) => "hardening",
        (true, Some(false)) => "softening",
        (true, None) => "nonlinear",
    };
    let mut stiff_class = "none";
    if st.nonlinear {
        if let Some(f) = &st.fit {
            evidence.push(format!(
                "backbone Omega_r^2 - omega_0^2 = g(rho) beta a^rho: rho = {}, beta = {:.4e} (mass-normalised), f_0 = {} Hz, scatter {} x the noise, levels {}",
                fmt_ci(f),
                f.coefficient,
                st.f0_hz.map_or("-".into(), fmt_hz),
                f.scatter.map_or("-".into(), |s| format!("{s:.2}")),
                f.levels.join(", ")
            ));
            if f.exponent_at_bound {
                warnings.push(format!(
                    "rho ended at the end of its search range [{}, {}]: the stiffness law is not determined by these levels",
                    EXPONENT_RANGE.0, EXPONENT_RANGE.1
                ));
            }
            let duffing = (f.holds(2.0) && f.half_width().is_some_and(|h| h <= 1.0))
                || (f.exponent_ci95.is_none() && (f.exponent - 2.0).abs() < 0.25);
            stiff_class = if duffing { "duffing" } else { "generalised" };
            match f.half_width() {
                Some(h) if h <= PINNED_HALF_WIDTH => pinned.push(format!(
                    "rho = {:.3} +- {:.3} (95 %)",
                    f.exponent, h
                )),
                Some(h) => notes.push(format!(
                    "rho is not pinned: 95 % interval +- {h:.2} (more levels, or levels further apart, narrow it)"
                )),
                None => {}
            }
        } else {
            stiff_class = "generalised";
        }
        evidence.push(format!(
            "stiffness {stiff_word}: {}",
            match (st.chi2, levels.len()) {
                (Some(c), l) if l >= 2 => format!(
                    "chi2 of the resonance frequencies {:.1} for {} degrees of freedom (99.9 % point {:.1}){}",
                    c,
                    l - 1,
                    chi2_upper(l - 1),
                    if jumps.is_empty() { "" } else { ", and the curves jump" }
                ),
                _ => "the curves jump".into(),
            }
        ));
    } else if let Some(c) = st.chi2 {
        evidence.push(format!(
            "stiffness linear: chi2 of the resonance frequencies {:.1} for {} degrees of freedom is below its 99.9 % point {:.1}, no jumps",
            c,
            levels.len() - 1,
            chi2_upper(levels.len() - 1)
        ));
    }
    // damping
    let mut damp_class = "linear";
    if dm.nonlinear {
        damp_class = "power-law";
        if dm.fit.as_ref().is_some_and(|f| !f.determined()) {
            damp_class = "nonlinear";
        }
        if let Some(f) = &dm.fit {
            evidence.push(format!(
                "damping delta_eq - delta_0 = g(eta) kappa V^eta: eta = {}, delta_0 = {:.4e} 1/s{}, kappa = {:.4e} (mass-normalised), scatter {} x the noise",
                fmt_ci(f),
                f.intercept,
                if f.intercept_held { " (held at 0)" } else { "" },
                f.coefficient,
                f.scatter.map_or("-".into(), |s| format!("{s:.2}"))
            ));
            if f.exponent_at_bound {
                warnings.push(format!(
                    "eta ended at the end of its search range [{}, {}]: the damping law is not determined by these levels",
                    EXPONENT_RANGE.0, EXPONENT_RANGE.1
                ));
            }
            let narrow = f.half_width().is_some_and(|h| h <= 1.0);
            if f.holds(-1.0) && narrow && !f.holds(1.0) {
                damp_class = "coulomb-like";
            } else if f.holds(1.0) && narrow && !f.holds(-1.0) {
                damp_class = "quadratic";
            } else if f.exponent_ci95.is_none() {
                if (f.exponent + 1.0).abs() < 0.25 {
                    damp_class = "coulomb-like";
                } else if (f.exponent - 1.0).abs() < 0.25 {
                    damp_class = "quadratic";
                }
            }
            match f.half_width() {
                Some(h) if h <= PINNED_HALF_WIDTH => pinned.push(format!(
                    "eta = {:.3} +- {:.3} (95 %)",
                    f.exponent, h
                )),
                Some(h) => notes.push(format!(
                    "eta is not pinned: 95 % interval +- {h:.2} (more levels, or levels further apart, narrow it)"
                )),
                None => {}
            }
        }
        if let Some(c) = dm.chi2 {
            evidence.push(format!(
                "damping changes: chi2 of delta_eq = gamma/(a_r Omega_r) {:.1} for {} degrees of freedom (99.9 % point {:.1})",
                c,
                levels.len() - 1,
                chi2_upper(levels.len() - 1)
            ));
        }
    } else if let Some(c) = dm.chi2 {
        evidence.push(format!(
            "damping linear: chi2 of delta_eq = gamma/(a_r Omega_r) {:.1} for {} degrees of freedom is below its 99.9 % point {:.1}",
            c,
            levels.len() - 1,
            chi2_upper(levels.len() - 1)
        ));
    }
    let family = match (st.nonlinear, stiff_class, dm.nonlinear) {
        (false, _, false) => Family::Linear,
        (true, "duffing", _) => Family::DuffingLike,
        (false, _, true) if damp_class == "quadratic" || damp_class == "coulomb-like" => {
            Family::DuffingLike
        }
        _ => Family::Generalised,
    };
    let model = match (stiff_class, damp_class) {
        ("none", "linear") => "linear",
        ("duffing", "linear") => "duffing",
        ("none", "quadratic") => "quadratic",
        ("duffing", "quadratic") => "duffing-quadratic",
        ("duffing", _) => "duffing-generalised",
        ("none", "coulomb-like") => "coulomb",
        ("none", _) => "generalised-damping",
        (_, "linear") => "generalised-stiffness",
        _ => "generalised",
    }
    .to_string();
    // the levels that carry the nonlinearity: beyond 3σ from the lowest
    // level's resonance, or jumping
    let mut nonlinear_levels = Vec::new();
    if let Some(base) = levels.iter().min_by(|a, b| a.gamma.total_cmp(&b.gamma)) {
        for p in levels {
            let dw = (p.omega_backbone - base.omega_backbone).abs()
                / (p.sigma_omega.powi(2) + base.sigma_omega.powi(2)).sqrt();
            let dd = (p.delta_eq - base.delta_eq).abs()
                / (p.sigma_delta_eq.powi(2) + base.sigma_delta_eq.powi(2)).sqrt();
            let jumps = curves
                .iter()
                .any(|c| c.level == p.level && c.jump.is_some());
            if dw > 3.0 || dd > 3.0 || jumps {
                nonlinear_levels.push(p.level.clone());
            }
        }
    }
    // warnings
    if n_levels < 3 {
        warnings.push(format!(
            "too few levels ({n_levels}): the stiffness and damping exponents need three levels, their intervals four; five or more spread over a factor 3 or more in gamma are advisable"
        ));
    } else if n_used == 3 {
        warnings.push(
            "three usable levels: the exponents have no interval (a fourth level gives one)".into(),
        );
    }
    for c in curves {
        if c.peak.kind == PeakKind::BandEdge {
            warnings.push(format!(
                "level {} ({}): largest amplitude at the band edge ({} Hz of {}-{} Hz): the band misses the resonance; the level is not used",
                c.level,
                c.direction.name(),
                fmt_hz(c.peak.f_hz),
                fmt_hz(c.f_min_hz),
                fmt_hz(c.f_max_hz)
            ));
        }
        if let Some(j) = &c.jump {
            if j.early == Some(true) {
                warnings.push(format!(
                    "level {} ({}): the sweep left its branch early, at {} Hz{}; the level is left out of the laws",
                    c.level,
                    c.direction.name(),
                    fmt_hz(j.f_before_hz),
                    match j.early_by_hz {
                        Some(d) => format!(", {} Hz before the backbone at its amplitude", fmt_hz(d)),
                        None => " (its lag had not reached 90 deg)".into(),
                    }
                ));
            }
        }
    }
    if let Some(h) = hom {
        if h.linear_within_noise && (st.nonlinear || dm.nonlinear) {
            warnings.push(format!(
                "the linearity index {:.2} is at the noise (threshold {:.2}): the nonlinearity rests on {}",
                h.index,
                h.threshold,
                if st.nonlinear && !jumps.is_empty() {
                    "the jumps"
                } else {
                    "one of the two quantities alone"
                }
            ));
        }
        if h.linear_within_noise && !st.nonlinear && !dm.nonlinear && !jumps.is_empty() {
            warnings
                .push("curves jump although the levels are homogeneous within the noise".into());
        }
    }
    notes.push(phase.note.clone());
    // headline
    let headline = match family {
        Family::Linear => format!(
            "linear within the noise{}: suggested `nlsdof fit --model {model}`",
            hom.as_ref().map_or(String::new(), |h| format!(
                " (linearity index {:.2} <= {:.2})",
                h.index, h.threshold
            ))
        ),
        _ => {
            let mut parts = Vec::new();
            if st.nonlinear {
                parts.push(match st.fit.as_ref().filter(|f| f.determined()) {
                    Some(f) => format!(
                        "{stiff_word} stiffness, rho = {}{}",
                        fmt_ci(f),
                        if stiff_class == "duffing" {
                            " (Duffing-like)"
                        } else {
                            ""
                        }
                    ),
                    None => format!("{stiff_word} stiffness (rho not determined by these levels)"),
                });
            }
            if dm.nonlinear {
                parts.push(match dm.fit.as_ref().filter(|f| f.determined()) {
                    Some(f) => format!(
                        "{} damping, eta = {}",
                        match damp_class {
                            "coulomb-like" => "Coulomb-like",
                            "quadratic" => "quadratic",
                            _ => "power-law",
                        },
                        fmt_ci(f)
                    ),
                    None => "nonlinear damping (eta not determined by these levels)".into(),
                });
            }
            format!(
                "nonlinear: {}: suggested `nlsdof fit --model {model}`",
                parts.join("; ")
            )
        }
    };
    Recommendation {
        headline,
        family,
        stiffness: if st.nonlinear {
            stiff_word.to_string()
        } else {
            "linear".into()
        },
        damping: damp_class.into(),
        model,
        evidence,
        pinned,
        nonlinear_levels,
        warnings,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The tabulated t quantiles against independent values: the closed
    /// forms of the t CDF for 1 and 2 degrees of freedom, and Simpson
    /// integration of the density for the others.
    #[test]
    fn t_quantiles_are_the_975_points() {
        let t1 = t975(1).unwrap();
        assert!((0.5 + t1.atan() / PI - 0.975).abs() < 1e-8);
        let t2 = t975(2).unwrap();
        assert!((0.5 + t2 / (2.0 * (2.0 + t2 * t2).sqrt()) - 0.975).abs() < 1e-8);
        for nu in [3usize, 5, 10, 20, 30] {
            let v = nu as f64;
            let lnc = libm::lgamma(0.5 * (v + 1.0)) - libm::lgamma(0.5 * v) - 0.5 * (v * PI).ln();
            let pdf = |x: f64| (lnc - 0.5 * (v + 1.0) * (1.0 + x * x / v).ln()).exp();
            let t = t975(nu).unwrap();
            let m = 20_000;
            let h = t / m as f64;
            let mut s = pdf(0.0) + pdf(t);
            for k in 1..m {
                s += if k % 2 == 1 { 4.0 } else { 2.0 } * pdf(k as f64 * h);
            }
            let cdf = 0.5 + s * h / 3.0;
            assert!((cdf - 0.975).abs() < 1e-7, "nu {nu}: {cdf}");
        }
        assert!(t975(0).is_none());
        assert!((t975(120).unwrap() - 1.9799).abs() < 2e-4);
    }

    /// χ² 0.999 points against tables (Abramowitz & Stegun 26.4), the
    /// closed form `−2 ln p` of two degrees of freedom, and the tail of one
    /// degree of freedom against `erfc(√(x/2))`.
    #[test]
    fn chi2_points() {
        for (k, q) in [
            (1, 10.828),
            (3, 16.266),
            (5, 20.515),
            (10, 29.588),
            (20, 45.315),
            (30, 59.703),
        ] {
            assert!((chi2_upper(k) - q).abs() < 1.5e-3, "{k}: {}", chi2_upper(k));
        }
        assert!((chi2_upper(2) + 2.0 * SIGNIFICANCE.ln()).abs() < 1e-9);
        for x in [0.1f64, 1.0, 3.84, 10.0, 25.0] {
            let q = libm::erfc((0.5 * x).sqrt());
            assert!((chi2_sf(1, x) - q).abs() < 1e-12 * q.max(1e-3), "{x}");
        }
    }

    /// The power-law regression recovers an exact law, with either sign and
    /// a negative exponent, and its intercept held at 0 when the data have
    /// none.
    #[test]
    fn regression_recovers_exact_laws() {
        let make = |c: f64, k: f64, p: f64, xs: &[f64]| -> Vec<Obs> {
            xs.iter()
                .map(|&x| {
                    let y = c + k * x.powf(p);
                    Obs {
                        x,
                        y,
                        var_x: 0.0,
                        var_y: (1e-3 * y).powi(2),
                        cov: 0.0,
                    }
                })
                .collect()
        };
        let xs = [1e-3, 2e-3, 3e-3, 5e-3, 8e-3];
        for (c, k, p, s) in [
            (4e5, 3e9, 2.0, 1.0),
            (4e5, -3e9, 2.0, -1.0),
            (4e5, 2e4, 0.5, 1.0),
            (4e5, 1e15, 4.0, 1.0),
        ] {
            let f = fit_law(&make(c, k, p, &xs), 0.0, None).unwrap();
            assert_eq!(f.big_b.signum(), s);
            assert!((f.p - p).abs() < 1e-6, "{p}: {}", f.p);
            assert!((f.c / c - 1.0).abs() < 1e-8);
        }
        // Coulomb-like: δ = 0.5 + 0.02/V
        let vs = [0.01, 0.02, 0.05, 0.1, 0.2];
        let f = fit_law(&make(0.5, 0.02, -1.0, &vs), 0.0, Some(1.0)).unwrap();
        assert!(
            (f.p + 1.0).abs() < 1e-6 && (f.c - 0.5).abs() < 1e-8,
            "{f:?}"
        );
        // no intercept: held at 0
        let f = fit_law(&make(0.0, 3.0, 1.5, &vs), 0.0, Some(1.0)).unwrap();
        assert!(f.c_held && f.c == 0.0 && (f.p - 1.5).abs() < 1e-6, "{f:?}");
    }

    /// The convention detection on a linear SDoF's lag written as a lead
    /// with an offset of 57° and wrapped into (−π, π]: sign and offset come
    /// back.
    #[test]
    fn phase_convention_from_the_curve_ends() {
        let n = 200;
        let (wn, zeta) = (100.0, 0.01);
        let omegas: Vec<f64> = (0..n)
            .map(|i| wn * (0.9 + 0.2 * i as f64 / (n - 1) as f64))
            .collect();
        let lag: Vec<f64> = omegas
            .iter()
            .map(|&w| (2.0 * zeta * wn * w).atan2(wn * wn - w * w))
            .collect();
        let off = 57f64.to_radians();
        let wrap = |x: f64| x - TWO_PI * ((x + PI) / TWO_PI).floor();
        let psi: Vec<f64> = lag.iter().map(|&l| wrap(-l + off)).collect();
        let c = Curve {
            level: "1".into(),
            gamma: 1.0,
            direction: SweepDirection::Up,
            omegas: omegas.clone(),
            amplitudes: omegas
                .iter()
                .map(|&w| 1.0 / ((wn * wn - w * w).powi(2) + (2.0 * zeta * wn * w).powi(2)).sqrt())
                .collect(),
            phases: Some(psi),
            weights: vec![1.0; n],
        };
        let conv = detect_convention(&Dataset { curves: vec![c] }).unwrap();
        assert_eq!(conv.sign, -1.0);
        // the lag at the peak is 90° − ζ rad (0.57°) and the sampled
        // maximum is within half a step of it
        assert!(
            (conv.offset - off).abs() < 1f64.to_radians(),
            "{}",
            conv.offset.to_degrees()
        );
    }

    /// The regression's 95 % profile-t interval against its nominal rate,
    /// on per-level points drawn from a known law with known Gaussian
    /// errors (400 draws each: in y alone, and along the hyperbola
    /// `δ = γ/V` as the damping points err): the oracle is the truth.
    #[test]
    fn regression_intervals_have_their_nominal_rate() {
        let mut st = 12345u64;
        let mut unif = move || {
            st ^= st << 13;
            st ^= st >> 7;
            st ^= st << 17;
            (st >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut normal = move || {
            let u1: f64 = unif().max(1e-300);
            let u2 = unif();
            (-2.0 * u1.ln()).sqrt() * (TWO_PI * u2).cos()
        };
        for hyperbola in [false, true] {
            let (d0, k, eta) = (7.49, 11.0, 1.825);
            let (mut n, mut hit) = (0, 0);
            for _ in 0..400 {
                let obs: Vec<Obs> = (0..6)
                    .map(|l| {
                        let v = 0.13 * 3.6f64.powf(l as f64 / 5.0);
                        let y = d0 + k * v.powf(eta);
                        let rel = 0.007;
                        if hyperbola {
                            let v2 = v * (1.0 + rel * normal());
                            let y2 = y * v / v2;
                            let var_v = (rel * v2).powi(2);
                            Obs {
                                x: v2,
                                y: y2,
                                var_x: var_v,
                                var_y: (y2 / v2).powi(2) * var_v,
                                cov: -(y2 / v2) * var_v,
                            }
                        } else {
                            Obs {
                                x: v,
                                y: y * (1.0 + rel * normal()),
                                var_x: 0.0,
                                var_y: (rel * y).powi(2),
                                cov: 0.0,
                            }
                        }
                    })
                    .collect();
                let f = fit_law(&obs, 0.0, Some(1.0)).unwrap();
                let [a, b] = f.interval.unwrap();
                n += 1;
                hit += usize::from(a <= eta && eta <= b);
            }
            let rate = hit as f64 / n as f64;
            assert!((rate - 0.95).abs() < 0.03, "hyperbola {hyperbola}: {rate}");
        }
    }
}
