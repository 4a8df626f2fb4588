//! Steady-state forced response by first-order harmonic balance (paper
//! §3.1–3.6) for `m x'' + c x' + k x + c_e x'|x'|^η + k_r x|x|^ρ = m γ cos Ωt`.
//!
//! ## Exact first-order harmonic balance (`Formulation::HarmonicBalance`)
//! With `x ≈ a cos(Ωt − φ)` and the equivalent coefficients of Eq 9 and
//! Eq 22, balancing the first harmonic gives (the algebraic equation behind
//! Eq 11 and Eq 30)
//!
//! ```text
//! a² [ (k + k_eq(a) − m Ω²)² + (Ω (c + c_eq(a, Ω)))² ] = (m γ)²
//! tan φ = Ω (c + c_eq) / (k + k_eq − m Ω²),   φ ∈ [0, π] (phase lag of x behind γ)
//! ```
//!
//! ## Near-resonance modulation form (`Formulation::Modulation`, Eq 30)
//! ```text
//! Ω/ω_n = 1 + k_eq/(2 m ω_n²) ± √( γ² / ((2ω_n²)² a²) − (ζ + ζ_eq)² )
//! ```
//! the first-order expansion of the exact form about `Ω = ω_n`
//! (`1 − Ω²/ω_n² ≈ 2(1 − Ω/ω_n)`, `Ω ≈ ω_n` in the damping terms, so
//! `ζ_eq` is evaluated at `Ω = ω_n`). It is an approximation: its error
//! grows with the distance from resonance and with the damping.
//!
//! Both are solved in the dimensionless form (`x = a ω_n² / γ`,
//! `ν = Ω / ω_n`)
//!
//! ```text
//! P(x) = x² [ (s₀ + s₁ x^ρ)² + (d₀ + d₁ x^η)² ] = 1
//! exact:      s₀ = 1 − ν²,   s₁ = b,  d₀ = 2ζν,  d₁ = c ν^{1+η}
//! modulation: s₀ = 2(1 − ν), s₁ = b,  d₀ = 2ζ,   d₁ = c
//! b = g(ρ) β (γ/ω_n²)^ρ / ω_n²,  c = g(η) κ (γ/ω_n)^η / ω_n
//! ```
//!
//! `P(x) − 1` expanded is a sum of at most six real powers of `x`, whose
//! positive roots are *all* isolated by [`crate::power_sum`] — no grid, so
//! two roots closer than any grid are still found.
//!
//! ## Stability (slow flow)
//! Averaging the complex amplitude `A` (`x = Re A e^{iΩt}`) gives
//! `2iΩ A' = γ − Z(|A|) A`, `Z = α_eff − Ω² + iΩ δ_eff`. Its Jacobian at a
//! steady state has `det ∝ d(a²|Z|²)/da` and `trace ∝ −(2 Im Z + a ∂Im Z/∂a)`,
//! so a steady state is stable iff
//!
//! ```text
//! dP/dx > 0   (saddle-node / fold criterion; the middle of three roots fails it)
//! 2 d₀ + (2 + η) d₁ x^η > 0   (no Hopf instability; always true for η > −2)
//! ```

pub mod branches;
mod certificate;
mod equation;
mod folds;
mod sweep;

pub use equation::ResponseEquation;

use crate::error::{ParameterError, SolveError};
use crate::model::AsNormalised;
use crate::model::NormalisedModel;

/// Which steady-state equation to solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Formulation {
    /// Exact first-order harmonic balance (default).
    #[default]
    HarmonicBalance,
    /// The paper's near-resonance form, Eq 30 (an approximation of the exact one).
    Modulation,
}

/// Direction of a stepped-sine sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum SweepDirection {
    Up,
    Down,
}

impl SweepDirection {
    /// `"up"` or `"down"`, as reports and data files name it.
    pub fn name(self) -> &'static str {
        match self {
            SweepDirection::Up => "up",
            SweepDirection::Down => "down",
        }
    }
}

/// One steady state (a root of the harmonic-balance equation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyState {
    /// Displacement amplitude a (m, zero-to-peak).
    pub amplitude: f64,
    /// Phase lag φ of x behind the input γ cos Ωt, rad, in [0, π].
    pub phase: f64,
    /// Slow-flow stability (saddle-node and Hopf criteria).
    pub stable: bool,
}

/// The stable steady states at every step of a sweep
/// ([`ForcedResponse::sweep_with_states`]), in sweep order, kept in one
/// allocation (a sweep of a thousand steps would otherwise allocate a
/// thousand small vectors).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepStates {
    states: Vec<SteadyState>,
    /// `states[ends[k − 1]..ends[k]]` are step `k`'s.
    ends: Vec<usize>,
}

impl StepStates {
    /// The stable states at step `k` (sweep order; the followed one among
    /// them; empty where the mass sticks or no stable state exists).
    pub fn at(&self, k: usize) -> &[SteadyState] {
        let start = if k == 0 { 0 } else { self.ends[k - 1] };
        &self.states[start..self.ends[k]]
    }

    /// Number of steps.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// `true` before the first step.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// Every step's states, in sweep order.
    pub fn iter(&self) -> impl Iterator<Item = &[SteadyState]> + '_ {
        (0..self.len()).map(|k| self.at(k))
    }

    pub(crate) fn with_capacity(steps: usize) -> Self {
        Self {
            states: Vec::with_capacity(steps + steps / 4),
            ends: Vec::with_capacity(steps),
        }
    }

    pub(crate) fn clear(&mut self) {
        self.states.clear();
        self.ends.clear();
    }

    /// Appends the next step's states.
    pub(crate) fn push_step(&mut self, states: impl IntoIterator<Item = SteadyState>) {
        self.states.extend(states);
        self.ends.push(self.states.len());
    }
}

/// Why no steady-state motion exists.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NoMotion {
    /// Coulomb friction (η = −1) holds the mass: the friction force
    /// `4 c_f / π` (its first-harmonic value) is at least the input force
    /// amplitude `m γ`. Both values are given per unit mass (m/s²).
    Sticking {
        friction_accel: f64,
        input_accel: f64,
    },
    /// No positive root for another reason (e.g. η < −1, where the damping
    /// force grows without bound as the amplitude goes to zero).
    NoRoot,
    /// No finite steady state: the restoring and damping forces never
    /// balance the input at any amplitude (`P(x) < 1` for all `x`), so the
    /// response grows without bound, e.g. an undamped linear model at its
    /// natural frequency. Not sticking: the mass moves.
    Unbounded,
}

/// All steady states at one (γ, Ω).
#[derive(Debug, Clone, PartialEq)]
pub struct RootSet {
    /// Input frequency Ω, rad/s.
    pub omega: f64,
    /// Roots sorted by increasing amplitude.
    pub roots: Vec<SteadyState>,
    /// Set when `roots` is empty.
    pub no_motion: Option<NoMotion>,
}

/// A fold (saddle-node, jump) point of the response curve of one level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fold {
    /// Frequency, rad/s.
    pub omega: f64,
    /// Amplitude where the two roots merge, m.
    pub amplitude: f64,
    /// `true` if the pair of roots exists just *above* `omega`
    /// (it is born as Ω increases), `false` if it exists just below.
    pub pair_above: bool,
}

/// A jump seen by a stepped-sine sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jump {
    /// Fold frequency where the followed branch ends, rad/s.
    pub omega: f64,
    /// Amplitude on the branch that ends (at the fold), m.
    pub amplitude_before: f64,
    /// Amplitude of the branch jumped to (at the fold frequency), m.
    pub amplitude_after: f64,
}

/// One step of a sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepPoint {
    /// Ω, rad/s.
    pub omega: f64,
    /// a, m (0 when `sticking` or `unbounded`: no finite amplitude).
    pub amplitude: f64,
    /// Phase lag, rad (0 when `sticking` or `unbounded`).
    pub phase: f64,
    /// The followed state is stable (false only where no stable root exists).
    pub stable: bool,
    /// No motion (Coulomb sticking, or no root for another reason).
    pub sticking: bool,
    /// No finite steady state ([`NoMotion::Unbounded`]): the response grows
    /// without bound; never set together with `sticking`.
    pub unbounded: bool,
}

/// Result of a stepped-sine sweep at one level.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    pub direction: SweepDirection,
    pub points: Vec<SweepPoint>,
    /// Jumps in sweep order.
    pub jumps: Vec<Jump>,
    /// All folds of this level between the first and last frequency, increasing.
    pub folds: Vec<Fold>,
}

/// Point where the phase lag is exactly 90° (Table 8 reports these).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseQuadrature {
    /// Ω, rad/s.
    pub omega: f64,
    /// a, m.
    pub amplitude: f64,
}

/// The forced response of one model at one input level γ.
#[derive(Debug, Clone, Copy)]
pub struct ForcedResponse {
    pub(crate) model: NormalisedModel,
    pub(crate) gamma: f64,
    pub(crate) formulation: Formulation,
    /// Amplitude scale γ/ω_n² (m): x = a / scale.
    pub(crate) scale: f64,
    pub(crate) omega_n: f64,
    /// g(ρ) β scale^ρ / ω_n²
    pub(crate) b: f64,
    /// g(η) κ (ω_n scale)^η / ω_n
    pub(crate) c: f64,
}

fn check_positive(name: &'static str, v: f64) -> Result<(), ParameterError> {
    if !v.is_finite() {
        return Err(ParameterError::NotFinite { name, value: v });
    }
    if v <= 0.0 {
        return Err(ParameterError::NotPositive { name, value: v });
    }
    Ok(())
}

impl ForcedResponse {
    /// Response of `model` to `γ cos Ωt` with `gamma` = γ (m/s², zero-to-peak, > 0).
    /// `model` is either form ([`crate::Model`] or [`NormalisedModel`], see
    /// [`AsNormalised`]).
    pub fn new(
        model: &(impl AsNormalised + ?Sized),
        gamma: f64,
        formulation: Formulation,
    ) -> Result<Self, SolveError> {
        Self::from_normalised(&model.as_normalised()?, gamma, formulation)
    }

    /// As [`ForcedResponse::new`] from mass-normalised parameters.
    pub fn from_normalised(
        model: &NormalisedModel,
        gamma: f64,
        formulation: Formulation,
    ) -> Result<Self, SolveError> {
        model.validate()?;
        check_positive("gamma", gamma)?;
        let omega_n = model.omega_n();
        let scale = gamma / model.alpha;
        let b = if model.beta == 0.0 {
            0.0
        } else {
            crate::power_law::g_unchecked(model.rho) * model.beta * scale.powf(model.rho)
                / model.alpha
        };
        let c = if model.kappa == 0.0 {
            0.0
        } else {
            crate::power_law::g_unchecked(model.eta)
                * model.kappa
                * (omega_n * scale).powf(model.eta)
                / omega_n
        };
        if !(b.is_finite() && c.is_finite() && scale.is_finite() && scale > 0.0) {
            return Err(SolveError::Overflow {
                amplitude: scale,
                omega: omega_n,
            });
        }
        Ok(Self {
            model: *model,
            gamma,
            formulation,
            scale,
            omega_n,
            b,
            c,
        })
    }

    /// Input level γ, m/s².
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The formulation in use.
    pub fn formulation(&self) -> Formulation {
        self.formulation
    }

    /// The dimensionless response equation at frequency `omega` (rad/s).
    pub fn equation(&self, omega: f64) -> ResponseEquation {
        let nu = omega / self.omega_n;
        let zeta = self.model.zeta();
        match self.formulation {
            Formulation::HarmonicBalance => ResponseEquation::new(
                1.0 - nu * nu,
                self.b,
                self.model.rho,
                2.0 * zeta * nu,
                if self.c == 0.0 {
                    0.0
                } else {
                    self.c * nu.powf(1.0 + self.model.eta)
                },
                self.model.eta,
            ),
            Formulation::Modulation => ResponseEquation::new(
                2.0 * (1.0 - nu),
                self.b,
                self.model.rho,
                2.0 * zeta,
                self.c,
                self.model.eta,
            ),
        }
    }

    fn no_motion_reason(&self, eq: &ResponseEquation) -> NoMotion {
        if self.model.kappa > 0.0 && self.model.eta == -1.0 && eq.d1 >= 1.0 {
            // P(x) >= (d1)^2 for all x > 0; in physical units 4 c_f/(π m) >= γ.
            NoMotion::Sticking {
                friction_accel: 4.0 / std::f64::consts::PI * self.model.kappa,
                input_accel: self.gamma,
            }
        } else if eq.grows_without_bound() {
            NoMotion::Unbounded
        } else {
            NoMotion::NoRoot
        }
    }

    /// All steady states at frequency `omega` (rad/s, > 0), sorted by
    /// amplitude, with phase and stability.
    pub fn steady_states(&self, omega: f64) -> Result<RootSet, SolveError> {
        check_positive("omega", omega)?;
        let eq = self.equation(omega);
        let ts = eq.roots_t().map_err(|e| folds::with_omega(e, omega))?;
        self.root_set(omega, &eq, &ts)
    }

    /// The steady states at `omega` from the roots `t = ln x` of its
    /// equation `eq` (increasing): amplitude, phase and stability of each.
    pub(crate) fn root_set(
        &self,
        omega: f64,
        eq: &ResponseEquation,
        ts: &[f64],
    ) -> Result<RootSet, SolveError> {
        let roots: Vec<SteadyState> = ts
            .iter()
            .map(|&t| {
                let x = t.exp();
                let (phase, stable) = eq.phase_and_stability(x);
                SteadyState {
                    amplitude: x * self.scale,
                    phase,
                    stable,
                }
            })
            .collect();
        if let Some(bad) = roots
            .iter()
            .find(|s| !(s.amplitude.is_finite() && s.amplitude > 0.0))
        {
            return Err(SolveError::Overflow {
                amplitude: bad.amplitude,
                omega,
            });
        }
        let no_motion = roots.is_empty().then(|| self.no_motion_reason(eq));
        Ok(RootSet {
            omega,
            roots,
            no_motion,
        })
    }

    /// As [`Self::steady_states`], faster where the one-root certificate of
    /// the stepped-sine fast path holds at `omega` (`ρ ≥ 0`, `η ≥ −1`, see
    /// [`sweep`](self)): the one root is then found by safeguarded Newton in
    /// `ln a` from `guess` (m; any positive value, e.g. a measured
    /// amplitude) instead of isolating every root. Falls back to
    /// [`Self::steady_states`] wherever the certificate does not hold or
    /// Newton fails (e.g. Coulomb friction that holds the mass).
    pub fn steady_states_near(&self, omega: f64, guess: f64) -> Result<RootSet, SolveError> {
        check_positive("omega", omega)?;
        let eq = self.equation(omega);
        if certificate::fast_path_possible(self) && certificate::certify_cell(&eq, &eq) {
            let t_guess = Some((guess / self.scale).ln()).filter(|t| t.is_finite());
            if let Some(u) = eq.solve_certified(t_guess) {
                let amplitude = u.t.exp() * self.scale;
                if amplitude.is_finite() && amplitude > 0.0 {
                    return Ok(RootSet {
                        omega,
                        roots: vec![SteadyState {
                            amplitude,
                            phase: u.phase,
                            stable: u.stable,
                        }],
                        no_motion: None,
                    });
                }
            }
        }
        self.steady_states(omega)
    }

    /// All folds (saddle-node points) with `omega_min <= Ω <= omega_max`
    /// (rad/s), sorted by frequency, located to ~1e-13 relative.
    pub fn folds(&self, omega_min: f64, omega_max: f64) -> Result<Vec<Fold>, SolveError> {
        folds::find_folds(self, omega_min, omega_max)
    }

    /// The lowest fold in `[omega_min, omega_max]` (rad/s) at which a
    /// branch followed with increasing frequency ends (a pair of roots
    /// vanishes upwards): the first such fold of [`Self::folds`], found
    /// without searching the range beyond it.
    pub fn first_fold_ending_upwards(
        &self,
        omega_min: f64,
        omega_max: f64,
    ) -> Result<Option<Fold>, SolveError> {
        folds::first_fold_ending_upwards(self, omega_min, omega_max)
    }

    /// Stepped-sine sweep over the strictly increasing frequencies `omegas`
    /// (rad/s), in `direction` (for `Down` the points are returned in sweep
    /// order, i.e. decreasing frequency). See [`sweep`](self) for the rules.
    pub fn sweep(&self, omegas: &[f64], direction: SweepDirection) -> Result<Sweep, SolveError> {
        sweep::sweep(self, omegas, direction, None, None)
    }

    /// As [`ForcedResponse::sweep`], but the state at the first step (in
    /// sweep order) is the stable steady state whose amplitude is nearest
    /// to `initial_amplitude` (m, compared in `ln a`) instead of the one
    /// reached from rest (sweep rule 1′). Used when the first state is
    /// known, e.g. measured: where several stable states coexist at the
    /// first frequency, the measurement tells which one the structure was
    /// on. Identical to `sweep` where the first step has one stable state.
    pub fn sweep_from(
        &self,
        omegas: &[f64],
        direction: SweepDirection,
        initial_amplitude: f64,
    ) -> Result<Sweep, SolveError> {
        sweep::sweep(self, omegas, direction, Some(initial_amplitude), None)
    }

    /// As [`ForcedResponse::sweep_from`], with every **stable** steady state
    /// at each step ([`StepStates::at`]: in sweep order, the followed one
    /// among them; empty where the mass sticks or no stable state exists). The sweep isolates
    /// these roots anyway wherever a fold is possible (at certified steps
    /// the one root is the state), so they come at no extra cost; the
    /// output error of the identification compares a measured point with
    /// them ([`crate::identification::objective`]).
    pub fn sweep_with_states(
        &self,
        omegas: &[f64],
        direction: SweepDirection,
        initial_amplitude: f64,
    ) -> Result<(Sweep, StepStates), SolveError> {
        let mut states = StepStates::with_capacity(omegas.len());
        let sw = sweep::sweep(
            self,
            omegas,
            direction,
            Some(initial_amplitude),
            Some(&mut states),
        )?;
        Ok((sw, states))
    }

    /// The point of the response curve where the phase lag is 90°
    /// (`k + k_eq(a) = m Ω²`, i.e. the curve meets the backbone). Unique for
    /// hardening with `η ≥ −1`; otherwise the smallest-amplitude crossing
    /// (the peak grown from the linear resonance) is returned. `None` if the
    /// curve never meets the backbone at a positive frequency.
    pub fn phase_quadrature(&self) -> Result<Option<PhaseQuadrature>, SolveError> {
        folds::phase_quadrature(self)
    }
}

/// Backbone curve: the undamped free-vibration frequency at amplitude `a`
/// (m), rad/s.
///
/// ```text
/// exact:      Ω_bb(a) = √( (k + k_eq(a)) / m ) = ω_n √(1 + k_eq/k)
/// modulation: Ω_bb(a) = ω_n (1 + k_eq / (2k))                        (Eq 30 with γ = 0)
/// ```
/// `None` where a softening term makes `k + k_eq <= 0` (exact form).
pub fn backbone(model: &NormalisedModel, amplitude: f64, formulation: Formulation) -> Option<f64> {
    let wn = model.omega_n();
    let keq_over_k = if model.beta == 0.0 || amplitude == 0.0 {
        0.0
    } else {
        crate::power_law::g_unchecked(model.rho) * model.beta * amplitude.abs().powf(model.rho)
            / model.alpha
    };
    match formulation {
        Formulation::HarmonicBalance => {
            let r = 1.0 + keq_over_k;
            (r > 0.0 && r.is_finite()).then(|| wn * r.sqrt())
        }
        Formulation::Modulation => {
            let r = 1.0 + 0.5 * keq_over_k;
            (r > 0.0 && r.is_finite()).then(|| wn * r)
        }
    }
}

/// The paper's Eq 30 read explicitly: the two frequencies (rad/s) at which
/// the near-resonance (modulation) response curve passes through amplitude
/// `amplitude` (m) at input level `gamma` (m/s²):
///
/// ```text
/// Ω±/ω_n = 1 + k_eq(a)/(2 m ω_n²) ± √( γ² / ((2ω_n²)² a²) − (ζ + ζ_eq(a))² )
/// ζ = c/(2mω_n),  ζ_eq = g(η) c_e |ω_n a|^η / (2 m ω_n)   (Eq 23 with Ω ≈ ω_n)
/// ```
///
/// `Ok(None)` where the square root is imaginary (the amplitude is above the
/// peak of the curve). This is an approximation of the exact harmonic
/// balance ([`Formulation::HarmonicBalance`]), valid near resonance for
/// light damping.
pub fn modulation_frequencies(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    amplitude: f64,
) -> Result<Option<(f64, f64)>, SolveError> {
    let n = model.as_normalised()?;
    check_positive("gamma", gamma)?;
    check_positive("amplitude", amplitude)?;
    let wn = n.omega_n();
    let keq_over_k = if n.beta == 0.0 {
        0.0
    } else {
        crate::power_law::g_unchecked(n.rho) * n.beta * amplitude.powf(n.rho) / n.alpha
    };
    let zeta_eq = if n.kappa == 0.0 {
        0.0
    } else {
        crate::power_law::g_unchecked(n.eta) * n.kappa * (wn * amplitude).powf(n.eta) / (2.0 * wn)
    };
    let disc = (gamma / (2.0 * wn * wn * amplitude)).powi(2) - (n.zeta() + zeta_eq).powi(2);
    if !(disc >= 0.0) {
        return Ok(None);
    }
    let centre = 1.0 + 0.5 * keq_over_k;
    let half = disc.sqrt();
    Ok(Some((wn * (centre - half), wn * (centre + half))))
}

/// One input level's forced response, its stepped-sine sweep and its
/// phase-quadrature point ([`level_responses`]).
#[derive(Debug, Clone)]
pub struct LevelResponse {
    /// γ, m/s² zero-to-peak.
    pub gamma: f64,
    pub response: ForcedResponse,
    pub sweep: Sweep,
    pub phase_quadrature: Option<PhaseQuadrature>,
}

/// The response of `model` at each level of `gammas` (m/s², zero-to-peak):
/// the sweep over the increasing `omegas` (rad/s) in `direction` and the
/// phase-quadrature point; levels computed in parallel (rayon), results in
/// the order of `gammas` (on failure, the first failing level's error).
pub fn level_responses(
    model: &(impl AsNormalised + ?Sized),
    gammas: &[f64],
    omegas: &[f64],
    direction: SweepDirection,
    formulation: Formulation,
) -> Result<Vec<LevelResponse>, SolveError> {
    use rayon::prelude::*;
    let model = &model.as_normalised()?;
    let levels: Vec<Result<LevelResponse, SolveError>> = gammas
        .par_iter()
        .map(|&gamma| {
            let response = ForcedResponse::new(model, gamma, formulation)?;
            let sweep = response.sweep(omegas, direction)?;
            let phase_quadrature = response.phase_quadrature()?;
            Ok(LevelResponse {
                gamma,
                response,
                sweep,
                phase_quadrature,
            })
        })
        .collect();
    levels.into_iter().collect()
}

/// Stepped-sine sweeps of one model at several input levels `gammas`
/// (m/s², zero-to-peak) over the same increasing frequencies `omegas`
/// (rad/s), levels computed in parallel (rayon). Results are identical to
/// calling [`ForcedResponse::sweep`] per level, in the order of `gammas`.
pub fn sweep_levels(
    model: &(impl AsNormalised + ?Sized),
    gammas: &[f64],
    omegas: &[f64],
    direction: SweepDirection,
    formulation: Formulation,
) -> Result<Vec<Sweep>, SolveError> {
    use rayon::prelude::*;
    let model = &model.as_normalised()?;
    let responses = gammas
        .iter()
        .map(|&g| ForcedResponse::new(model, g, formulation))
        .collect::<Result<Vec<_>, _>>()?;
    responses
        .par_iter()
        .map(|r| r.sweep(omegas, direction))
        .collect()
}

/// Uniform numbers in `[0, 1)` from a xorshift64 generator seeded with
/// `seed` (non-zero): the random models of this module's tests.
#[cfg(test)]
pub(crate) fn test_uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod step_states_tests {
    use super::*;

    /// The oracle is the cold root isolation at each frequency
    /// ([`ForcedResponse::steady_states`]): a sweep's states at a step are
    /// its stable roots, as many and the same to 1e-12, and the followed
    /// point is one of them. Up and down, through the jumps of a Duffing
    /// level, so that steps with one and with two stable states are read
    /// back from the one allocation.
    #[test]
    fn a_sweeps_states_are_the_stable_roots_at_each_step() {
        let m = NormalisedModel {
            alpha: 100.0,
            delta: 0.1,
            beta: 40.0,
            rho: 2.0,
            kappa: 0.0,
            eta: 0.0,
        };
        let r = ForcedResponse::from_normalised(&m, 1.0, Formulation::HarmonicBalance).unwrap();
        let omegas: Vec<f64> = (0..300).map(|i| 9.0 + 4.0 * i as f64 / 299.0).collect();
        for dir in [SweepDirection::Up, SweepDirection::Down] {
            let (sw, states) = r.sweep_with_states(&omegas, dir, 0.0).unwrap();
            assert!(
                !sw.jumps.is_empty(),
                "{dir:?}: a sweep with a jump is tested"
            );
            assert_eq!(states.len(), omegas.len());
            assert_eq!(states.iter().count(), omegas.len());
            let mut two = 0;
            for (k, p) in sw.points.iter().enumerate() {
                let cold: Vec<SteadyState> = r
                    .steady_states(p.omega)
                    .unwrap()
                    .roots
                    .into_iter()
                    .filter(|s| s.stable)
                    .collect();
                let at = states.at(k);
                assert_eq!(at.len(), cold.len(), "{dir:?} step {k}");
                for (a, b) in at.iter().zip(&cold) {
                    assert!((a.amplitude - b.amplitude).abs() <= 1e-12 * b.amplitude);
                }
                assert!(
                    at.iter().any(|s| s.amplitude == p.amplitude),
                    "{dir:?} step {k}"
                );
                two += usize::from(at.len() == 2);
            }
            assert!(two > 0, "{dir:?}: steps with two stable states are tested");
        }
    }
}
