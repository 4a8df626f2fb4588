//! [`identify`]: the one entry point of a stepped-sine identification —
//! data in, a [`FitPlan`] (model family, what is fixed, sign, integer or
//! real exponents, gain, phase, jumps), a typed [`Identification`] out.
//! The CLI and the Python module only parse and render; every option
//! (`--sign auto`, `--integer`, the expert flags) goes through here.
//!
//! ## Stages (one function each)
//! 1. **Equation error, branch free** ([`super::equation_error`]): every
//!    measured point satisfies the first-order HB equations whichever branch
//!    it is on. With phase (used by default when every curve has it) the
//!    phase convention — lag or lead and a constant offset — is detected
//!    from the data through a complex gain; the equations are then linear
//!    least squares at fixed exponents.
//! 2. **Exponent landscape** ([`super::landscape`], `explore`): the
//!    equation-error cost profiled over a `(ρ, η)` grid of the free
//!    exponents (coefficients optimised at each node); its grid minima,
//!    best first, are the candidates. Integer exponents
//!    ([`ExponentChoice::Integer`]) use the integer nodes only.
//!    Profile-likelihood intervals of the exponents come from the same map.
//!    A single-row landscape (no nonlinear damping, or η held) is also
//!    solved node by node cold (its one warm-started chain starts at the
//!    degenerate ρ = 0), and so is, with several levels, a row the chain
//!    left wholly degenerate. κ held at 0 is the model without the term; an
//!    exponent held at 0 with its coefficient free is refused
//!    ([`SpecError::CopiesLinear`]).
//! 3. **Gain screen** (`screen_gain`): the forcing gain (a point of a
//!    base-excited continuous structure sees `gain·γ`) is provisionally
//!    freed when freeing it lowers the equation-error cost significantly
//!    (`F > 10.83`, the χ²₁ 0.1 % point) and the estimate lies inside its
//!    bounds. The noisy amplitudes sit inside the equation error's
//!    regressors (errors in variables), which biases this test: it only
//!    chooses the starts; stage 5 decides.
//! 4. **Candidates race** (`race`): from each of the best `refine`
//!    candidates (and the best node of each third of each exponent's range,
//!    and the node nearest to [`FitPlan::start_exponents`] when given),
//!    its equation error solved again with the provisional gain, the output
//!    error of [`ResponseBranch::Measured`] ([`super::output_error`]: each
//!    point against the model state the measured sweep was on, continuous
//!    in θ, jump penalties in the exact reading) for at most
//!    [`RACE_ITERATIONS`] LM iterations; the sign is the equation error's
//!    ([`SignChoice::Auto`]), or both are fitted ([`SignChoice::Both`]).
//!    The candidates the limit stopped near the lead continue; those far
//!    above it (a race on every point only) have folds on the wrong side of
//!    a measured step moved into it (`relocate_folds`: the least-misfit
//!    change, else the least change in the optimisation variables) and
//!    refitted; the lowest objective wins. With one forcing level and a
//!    detected convention, a node whose own phase offset lies beyond the
//!    output error's correction from the best node's reads the phases with
//!    its own (`node_phase_shift`; the winner's reading becomes the
//!    stages'). When the screen freed the gain with an estimate within
//!    [`HELD_RACE_GAIN`] of 1, the candidates also race with it held; a
//!    held winner that loses goes through stages 5–7 too, and is kept if
//!    lower on every point.
//! 5. **Decisions, on the race's data** (`finish`): the terms
//!    (`settle_terms`, below), the gain (`decide_gain`), the terms again
//!    (a refitted gain can leave a term near a copy of the linear one).
//!    Tests need hundreds of points, not thousands: a subsample suffices.
//!    * **Gain decision** ([`GainChoice::Auto`]): the output error is
//!      refitted with the gain the screen did not choose; the gain is free
//!      when that lowers the objective significantly by the nested
//!      statistic (`nested_statistic`: the drop over its expectation under
//!      the pooled noise model of [`super::noise`], χ²₁, above its 0.1 %
//!      point 10.83). The output error attributes the noise to the
//!      amplitudes only, so this test is not biased by the errors in
//!      variables of stage 3.
//!    * **Terms that vanished** (`settle_terms`): a nonlinear term whose
//!      coefficient went to its lower bound, whose exponent is near 0 or at
//!      a bound, whose coefficient trades off with its linear counterpart
//!      (a near copy of the linear term), or that left the fit unconverged,
//!      is removed when removing it does not raise the objective
//!      significantly (nested statistic, χ² 5 % point: a weak term the data
//!      do see is kept, with its wide interval, rather than declared
//!      absent); the fit says so and names the exponent that had no effect
//!      ([`super::flags::Inactive`]).
//! 6. **All points** (`refine_all_points`): data longer than
//!    `refine_points` were raced on a subsample; the winner is judged and
//!    refined on every point (at most `polish_rounds` rounds of
//!    [`POLISH_ITERATIONS`] while a round ends at its limit), its folds
//!    moved past the points still on their branch (`reassign_jumps`), and
//!    the lowest objective kept. A result that still did not converge has
//!    its terms settled again on those data (a refinement can end on a
//!    ridge where a term has no effect that the race's data had not shown:
//!    κ → 0 with η wandering, measured on an unscreened case that ended at
//!    max-iterations at the truth's cost before this rule). A term that
//!    stage 5 removed on the subsample is tested again on every point
//!    (`retest_removed_terms`): refitted there from the race's winner, it
//!    is restored when the same nested test on every point needs it.
//! 7. **Folds off the steps** (`keep_folds_off_steps`): a fitted fold that
//!    lies within 1e-9 (relative) of a measured frequency is moved to 1e-9
//!    away from it (a minimum-norm change of the parameters), so that which
//!    branch the model's sweep is on at every measured step does not depend
//!    on the last digits of the parameters or of the solver that
//!    re-evaluates them; so is a fold within that margin past the last step
//!    of a sweep without a jump (`fold_past_the_end`). A fit whose late-fold pull left an exponent
//!    within 1 % of an end of its range has its terms settled again there.
//! 8. **Self-check against the noise** (`judge`, `escalate`): each curve's
//!    noise is estimated from the fit's residuals ([`super::noise`]); where
//!    the residual is well above it ([`ADEQUACY_CURVE`], [`ADEQUACY_ALL`],
//!    [`ADEQUACY_PEAKS`] over the resonance peaks, set from the in-family
//!    suites), or where a sweep read exactly leaves the model's branch a
//!    step or more before the model's fold ([`Adequacy::late_folds`]: the
//!    model's own sweep does not follow it), or whatever the residual when
//!    the data have a single forcing level (which pins the exponents
//!    weakly), the escalation tries more candidates (every landscape
//!    minimum, both signs), other jump assignments (folds moved past the
//!    points still on their branch; again with every other fold held in
//!    its step cell when that refit is not lower), a multistart of
//!    [`ESCALATION_STARTS`], then each exponent held across its range
//!    (`profile_exponents`, started from the fit and from the landscape;
//!    a term stage 5 removed is restored and profiled too);
//!    a lower objective goes through stages 5–7 again. A fit whose gain
//!    was freed near 1 ([`HELD_RACE_GAIN`]) and that still does not fit
//!    gets the escalation again with the gain held at 1, from the held
//!    race (raced then, on the landscape with the gain held, if the
//!    screen's free gain was far from 1). If it still does
//!    not fit, the result says so ([`Adequacy`],
//!    [`Identification::warning`]). A fit within its noise but above
//!    [`PROFILE_NEAR_NOISE`] of it, or whose gain the decisions freed (a
//!    free gain can take up the misfit of a neighbouring basin), gets the
//!    exponent profile from the decided fit (its miss would be silent; a
//!    single level a second time), and so does a fit still within
//!    [`PROFILE_MAX_RATIO`] of its noise after the escalation (which
//!    profiled the race's winner, not the fit it ended at). A fit within its noise with a fold
//!    pinned against a measured step has it moved into its step cell and
//!    refitted (`unpin_folds`): behind a barrier, and held at the middle
//!    of its cell then freed (`refit_with_folds_held`, holding in turn a
//!    fold that the refit pins), kept when lower and still within the noise;
//!    a fold still pinned after that (a constrained optimum) has each
//!    exponent held half a unit either side (`profile_decided`,
//!    `ProfileScope::Near`), a lower fit kept only when significantly
//!    lower (`significantly_lower`); a fold pinned still after the profiles
//!    has each exponent held two standard errors either side
//!    (`ProfileScope::Fine`), kept on the same test.
//! 9. **Jump readings** (`decide_readings`, [`ReadingChoice::Auto`], only
//!    when the fit still does not fit its noise after the escalation): a
//!    stepped sine can leave its branch before the fold, never after. The
//!    fit is repeated with every jump read as censored; curves whose
//!    measured sweep then leaves the model's branch a step or more before
//!    the model's fold are read as censored when that lowers the objective
//!    by more than the χ² 0.1 % point for that many curves (in units of
//!    the residual variance). On data of the model family the exact
//!    reading fits, and is kept. A censored fit whose θ read exactly fits
//!    its noise is reported read exactly (`read_exactly_if_it_fits`).
//! 10. **Phase offset** (`bake_phase_offset`): the output error's profiled
//!    correction of a detected phase offset is folded into the reported
//!    convention and the data as fitted.
//!
//! The reported `cost` is Eq 31 (amplitudes, branch following) at the
//! final θ, the paper's cost; `objective` is the measured-branch output
//! error that was minimised (equal to Eq 31 where every point is compared
//! with the model sweep's own state). Residuals are Eq 31's, or relative
//! ones ([`Weighting`]). The result says whether it converged, which
//! parameters sit at bounds, which the data cannot separate, which trade
//! off along a ridge ([`super::FitResult::warning`]).

use super::data::{Curve, Dataset};
use super::equation_error::{
    solve_magnitude, solve_phase, wrap, EquationErrorError, EquationErrorFit, PhaseConvention,
    Prepared, Terms,
};
use super::flags::Inactive;
use super::landscape::{
    landscape_cancellable, Axis, Landscape, LandscapeError, LandscapePhase, ProfileInterval,
};
use super::levenberg_marquardt::{LmOptions, Termination};
use super::models::*;
use super::noise::{
    noise_model, pseudo_residual_chi2, z2_per_curve, z2_split_per_curve, CurveNoise, NoiseModel,
    NoiseSplit,
};
use super::objective::{Evaluation, FitSpec, ResponseBranch, Sign, SpecError, Status};
use super::output_error::{evaluate_measured, Compared, CurveMatch, JumpReading, MatchOptions};
use super::search::SignTrial;
use super::{fit_impl, FitError, FitOptions, FitResult};
use crate::harmonic_balance::SweepDirection;

/// Fraction of a curve's peak below which [`Weighting::Relative`] counts
/// an amplitude as this fraction of the peak.
pub const RELATIVE_FLOOR: f64 = 0.01;

/// Most LM iterations of the all-point refinement that follows the
/// subsampled candidate refinement (see [`FitPlan::refine_points`]).
pub const POLISH_ITERATIONS: usize = 25;

/// Rounds of [`POLISH_ITERATIONS`] a polish on all points may take while
/// it still ends at its iteration limit: at least this many.
const POLISH_ROUNDS: usize = 3;

/// At most this many rounds ([`polish_rounds`]).
const POLISH_ROUNDS_MAX: usize = 12;

/// The rounds' budget in points × rounds ([`polish_rounds`]): twelve rounds
/// on 1500 points.
const POLISH_POINT_ROUNDS: usize = 18_000;

/// Rounds of [`POLISH_ITERATIONS`] a fit on `n` points may take while it
/// still ends at its iteration limit: [`POLISH_POINT_ROUNDS`]` / n`, between
/// [`POLISH_ROUNDS`] and [`POLISH_ROUNDS_MAX`], so that the budget is one of
/// work (an iteration costs about `n`), not of iterations. A fit still
/// ending at its limit is still lowering the objective by more than the
/// statistical resolution ([`DECREMENT_TOL`]'s progress test); on small data
/// a crawl along a ridge where a term turns into a copy of the linear one (η
/// → 0, δ → 0) takes more than the three rounds of the large sets, and ended
/// "not converged" at the optimum (measured on blind sets: 120 points, ρ
/// 5.0, η → −0.05, δ → 0, converged within the larger budget; 1800 points,
/// η → 0.01, still moving after 4 rounds, converged within 8).
fn polish_rounds(n: usize) -> usize {
    POLISH_POINT_ROUNDS
        .div_ceil(n.max(1))
        .clamp(POLISH_ROUNDS, POLISH_ROUNDS_MAX)
}

/// Most LM iterations of each candidate's output-error fit: the candidates
/// race, and those stopped by this limit near the lead
/// ([`CONTINUE_FACTOR`], [`CONTINUE_CANDIDATES`]) continue (for up to
/// `2 × lm.max_iterations − RACE_ITERATIONS` more, so that the total budget
/// of each is the `2 × lm.max_iterations` of a candidate and its one
/// continuation).
pub const RACE_ITERATIONS: usize = 30;

/// Candidates stopped by the race's limit within this factor of the best
/// objective continue (`race`).
pub const CONTINUE_FACTOR: f64 = 30.0;

/// At most this many stopped candidates continue.
pub const CONTINUE_CANDIDATES: usize = 2;

/// Most LM iterations of each refit that decides something (the gain, the
/// jump readings, a vanished term): each starts at the current optimum.
pub const DECISION_ITERATIONS: usize = 40;

/// Largest data set (points) refined on all points: beyond it the
/// subsample's optimum is only judged on every point (a refinement of
/// 1,000,000 rows would take minutes, and 1500 points already pin the
/// parameters far below the model error of real data).
pub const POLISH_MAX_POINTS: usize = 50_000;

/// Relative cost reduction below which the all-point refinement stops.
/// A parameter change of one standard deviation changes the cost by about
/// `1/n` relative (n residuals, thousands here), so this stops far inside
/// the statistical resolution of the estimate.
pub const POLISH_FTOL: f64 = 1e-7;

/// The output-error fits stop when the Gauss–Newton step would lower the
/// objective by less than this fraction of the residual variance: the
/// optimum is then within 0.01 standard error in every direction
/// ([`LmOptions::decrement_tol`]). Before this criterion, fits whose
/// nonlinear term had vanished crept along the flat direction until their
/// iteration limit and reported "did not converge".
pub const DECREMENT_TOL: f64 = 1e-4;

/// F threshold for freeing the gain (χ²₁ 0.1 % point).
pub const GAIN_F_THRESHOLD: f64 = 10.83;

/// When the equation-error screen frees the gain, the candidates also race
/// with it held at 1 if the screen's free gain is within this factor of 1.
/// The screen's estimate is biased by errors in variables: on the 18 of
/// 347 blind in-family sets (gain 1; six seeds) whose screen freed it, it
/// was 0.92 to 1.25. On
/// the beam sets, whose forcing gain is a real unknown, it is 2.3–3.1 or
/// 0.13, and the output error frees it there with F from 3e4 to 8e6.
pub const HELD_RACE_GAIN: f64 = 1.5;

/// A race candidate whose objective exceeds the lead's by this factor has
/// its folds relocated (`race`, [`relocate_folds`]).
const RELOCATE_FACTOR: f64 = 1.5;

/// Standard gravity, m/s² (the unit hint of a gain near it).
pub const G_STANDARD: f64 = 9.80665;

/// Relative distance of a free gain from [`G_STANDARD`] within which
/// [`Identification::unit_hint`] says the levels look like g.
pub const G_HINT_TOLERANCE: f64 = 0.03;

/// Resonance amplification `a Ω²/γ` above which a fit that does not fit
/// gets the hint that the amplitudes may be in mm: a damping ratio under
/// 5e-5 (lightly damped structures in air reach 1e3; the factor 1000 of
/// mm read as m puts them far above).
pub const AMPLIFICATION_HINT: f64 = 1e4;

/// A curve does not fit when the mean of its squared noise-scaled
/// residuals exceeds this (residual `√4 = 2×` the noise). Set from the
/// in-family suites (docs/identification.md): fits at the truth's cost
/// reach at most about 2.
pub const ADEQUACY_CURVE: f64 = 6.25;

/// The data set does not fit when the mean squared noise-scaled residual
/// over all points exceeds this (`√2.25 = 1.5×` the noise).
pub const ADEQUACY_ALL: f64 = 2.25;

/// The resonance peaks do not fit when the mean squared noise-scaled
/// residual over their points (amplitudes at least half the curve's peak)
/// exceeds this (`√3 = 1.7×` the noise). Over the 200 unscreened cases the
/// peaks of fits that found the optimum reached 1.39² = 1.9 (99th
/// percentile 1.34²); a blind mixed case whose fit missed a weak
/// amplitude-dependent damping (2.2× the truth's cost, 1.1× the noise on
/// average) had 5.9 there. The noise there is the estimate's, unless the
/// peaks' own pseudo-residuals reject it (their `Σ e²/V` above its χ² 0.1 %
/// point, [`super::noise::pseudo_residual_chi2`]): then it is scaled by
/// their mean `e²/V`. A floor fitted to the many low amplitudes can leave
/// the estimate at a peak far too small (blind h038-hardening: 0.38× the
/// true noise, the truth itself flagged at 1.9×), and second differences do
/// not see a smooth miss of the peaks, which this test is for.
pub const ADEQUACY_PEAKS: f64 = 3.0;

/// Starts of the multistart tried when the fit does not fit the noise.
pub const ESCALATION_STARTS: usize = 16;

/// A fitted fold is kept at least this far (relative frequency) from every
/// measured frequency (stage 7): a thousand times the precision to which
/// folds are located here and by an independent bisection (1e-11), so that
/// the branch a sweep is on at every step does not depend on the solver.
/// Near a fold the branch moves like the square root of the distance, so
/// the move changes the nearest step's model amplitude by about `√(1e-9
/// Ω/h)` of its change over one step (measured: a tenth of that point's
/// noise variance in the objective, at most).
pub const FOLD_MARGIN: f64 = 1e-9;

/// Stiffness sign.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SignChoice {
    /// From the equation-error estimate of each candidate (CLI `--sign
    /// data`, the default).
    #[default]
    Auto,
    Hardening,
    Softening,
    /// Every candidate fitted with both signs; the lower objective wins
    /// (CLI `--sign auto`). Both signs' best objectives are reported
    /// ([`Identification::sign_trials`]).
    Both,
}

/// Forcing gain.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum GainChoice {
    /// Freed when the data demand it (module docs), else held at 1.
    #[default]
    Auto,
    Fixed(f64),
    Free,
}

/// Phase use.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PhaseChoice {
    /// Used when every curve has phases, convention detected.
    #[default]
    Auto,
    /// Not used (and dropped from the data).
    Ignore,
    /// Used, with this convention.
    Known(PhaseConvention),
}

/// Weight of the jump penalties of the output error
/// ([`super::output_error`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum JumpChoice {
    /// Weight 1: a model fold one measured step on the wrong side of a point
    /// costs as much as the point's own amplitude (the continuous form of
    /// Eq 31's charge for a point on the wrong branch).
    #[default]
    Auto,
    /// No penalty: every point against the nearest of the model's stable
    /// states or the end of the followed branch.
    Off,
    /// This weight (≥ 0).
    Weight(f64),
}

impl JumpChoice {
    /// The penalty weight.
    pub fn weight(self) -> f64 {
        match self {
            JumpChoice::Auto => 1.0,
            JumpChoice::Off => 0.0,
            JumpChoice::Weight(w) => w,
        }
    }
}

/// How measured jumps are read ([`JumpReading`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReadingChoice {
    /// Exact, except for the curves whose data show that the sweep left its
    /// branch early: those are read as censored when that lowers the
    /// noise-scaled misfit significantly (module docs, stage 9).
    #[default]
    Auto,
    /// Every jump at the model's fold, within a step.
    Exact,
    /// Every jump a bound: the sweep may have left its branch earlier.
    Censored,
}

/// How the output-error amplitude residuals are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Weighting {
    /// Eq 31 as in the paper: `(a_model − a_meas)/γ` at every point, the
    /// maximum-likelihood choice when the amplitude noise of a level is of
    /// one size at every point (and grows with γ). The default: on the
    /// beam sets every relative weighting tried (floors of 1 % and 25 % of
    /// the peak, and a variance function estimated from the Eq 31
    /// residuals) gave up the resonance peaks for the low-amplitude points
    /// (peaks 50–80 % low, docs/identification.md).
    #[default]
    Absolute,
    /// Relative errors `K (a_model − a_meas)/a_meas` (phase errors `K Δφ`),
    /// the maximum-likelihood choice when the noise is a fixed fraction of
    /// the amplitude (as in the synthetic suite, where it makes the
    /// exponent intervals honest). `K = max_c a_peak,c/γ_c` keeps the
    /// residuals in the units of Eq 31, so the jump residuals and the phase
    /// weight mean the same under both weightings. Amplitudes below
    /// [`RELATIVE_FLOOR`] of their curve's peak count as that fraction of
    /// it (stuck Coulomb points have amplitude 0).
    Relative,
}

/// Real or integer exponents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExponentChoice {
    #[default]
    Real,
    Integer,
}

/// What to fit and how. [`FitPlan::new`] gives the defaults that work
/// without tuning; the `with_*` setters change one thing each.
///
/// ```
/// use nlsdof::identification::{FitPlan, ModelKind, GainChoice};
/// let plan = FitPlan::new(ModelKind::Duffing)
///     .with_gain(GainChoice::Fixed(1.0))
///     .with_grid(32, 32)
///     .unwrap();
/// assert_eq!(plan.grid, (32, 32));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FitPlan {
    pub kind: ModelKind,
    /// Held parameters `(name, value)` (natural units).
    pub fix: Vec<(String, f64)>,
    /// Freed parameters (e.g. an exponent the model fixes).
    pub free: Vec<String>,
    /// Bounds `(name, min, max)` (for β, κ: of β_ref, κ_ref).
    pub bounds: Vec<(String, f64, f64)>,
    pub sign: SignChoice,
    pub exponents: ExponentChoice,
    pub gain: GainChoice,
    pub phase: PhaseChoice,
    /// Weight `w_φ` of the phase residuals.
    pub phase_weight: f64,
    pub jumps: JumpChoice,
    /// How measured jumps are read.
    pub reading: ReadingChoice,
    /// When the fit's residual stays well above the noise, try more
    /// candidates and a multistart before reporting (module docs, stage 8).
    pub escalate: bool,
    /// Weighting of the output-error residuals.
    pub weighting: Weighting,
    /// Landscape nodes `(n_ρ, n_η)` over the exponents' bounds.
    pub grid: (usize, usize),
    /// Candidates refined by output error.
    pub refine: usize,
    /// Trial points of each race candidate's output-error fit: its own
    /// start and `starts − 1` Latin-hypercube ones, of which at most
    /// [`super::global::local_run_budget`] are run to a minimum (1 = the
    /// local fit only, the default).
    pub starts: usize,
    pub seed: u64,
    pub lm: LmOptions,
    /// Largest number of points used for the landscape (a regular subsample
    /// of longer data; with more than `landscape_points /`
    /// [`SUBSAMPLE_POINTS_PER_LEVEL`] levels, that many levels first).
    pub landscape_points: usize,
    /// Largest number of points of the candidates' output-error fits (a
    /// regular subsample of longer data, every curve's end points kept,
    /// thinned by level first as for `landscape_points`); the
    /// winner is then refined on all points (data of at most
    /// [`POLISH_MAX_POINTS`], at most [`POLISH_ITERATIONS`] LM iterations,
    /// kept when that converges) and judged (cost, residuals, intervals) on
    /// all points.
    pub refine_points: usize,
    /// Exponents from elsewhere (e.g. the model-free backbone and damping
    /// laws of [`super::inspect`]) to start from: the landscape node
    /// nearest to them joins the candidates of the race (module docs,
    /// stage 4) beside the landscape's own minima. `None` (default): the
    /// landscape's candidates only.
    pub start_exponents: Option<ExponentStart>,
}

/// Exponents to start the output error from ([`FitPlan::start_exponents`]);
/// an exponent left `None` is taken at the landscape's best node along the
/// other.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ExponentStart {
    pub rho: Option<f64>,
    pub eta: Option<f64>,
}

/// The landscape node nearest to `start`: on each axis the node nearest to
/// the given exponent; an exponent not given, the lowest-cost node along
/// that axis at the other's node. `None` if neither is given or the
/// landscape has no solved node there.
pub fn nearest_node(land: &Landscape, start: &ExponentStart) -> Option<(usize, usize)> {
    let nearest = nearest_index;
    let (i, j) = match (start.rho, start.eta) {
        (None, None) => return None,
        (Some(r), Some(e)) => (nearest(&land.rho, r)?, nearest(&land.eta, e)?),
        (Some(r), None) => {
            let i = nearest(&land.rho, r)?;
            let j = (0..land.eta.len())
                .filter(|&j| land.at(i, j).is_finite())
                .min_by(|&a, &b| land.at(i, a).total_cmp(&land.at(i, b)))?;
            (i, j)
        }
        (None, Some(e)) => {
            let j = nearest(&land.eta, e)?;
            let i = (0..land.rho.len())
                .filter(|&i| land.at(i, j).is_finite())
                .min_by(|&a, &b| land.at(a, j).total_cmp(&land.at(b, j)))?;
            (i, j)
        }
    };
    land.at(i, j).is_finite().then_some((i, j))
}

impl FitPlan {
    pub fn new(kind: ModelKind) -> Self {
        Self {
            kind,
            fix: Vec::new(),
            free: Vec::new(),
            bounds: Vec::new(),
            sign: SignChoice::Auto,
            exponents: ExponentChoice::Real,
            gain: GainChoice::Auto,
            phase: PhaseChoice::Auto,
            phase_weight: 1.0,
            jumps: JumpChoice::Auto,
            reading: ReadingChoice::Auto,
            escalate: true,
            weighting: Weighting::Absolute,
            grid: (41, 41),
            refine: 3,
            starts: 1,
            seed: 1,
            lm: LmOptions {
                decrement_tol: DECREMENT_TOL,
                ..LmOptions::default()
            },
            landscape_points: 2000,
            refine_points: 1500,
            start_exponents: None,
        }
    }

    /// Landscape size; both at least 1.
    pub fn with_grid(mut self, n_rho: usize, n_eta: usize) -> Result<Self, IdentifyError> {
        if n_rho == 0 || n_eta == 0 {
            return Err(IdentifyError::Landscape(LandscapeError::EmptyGrid {
                n_rho,
                n_eta,
            }));
        }
        self.grid = (n_rho, n_eta);
        Ok(self)
    }

    pub fn with_gain(mut self, g: GainChoice) -> Self {
        self.gain = g;
        self
    }

    pub fn with_sign(mut self, s: SignChoice) -> Self {
        self.sign = s;
        self
    }

    pub fn with_phase(mut self, p: PhaseChoice) -> Self {
        self.phase = p;
        self
    }

    pub fn with_jumps(mut self, j: JumpChoice) -> Self {
        self.jumps = j;
        self
    }

    pub fn with_reading(mut self, r: ReadingChoice) -> Self {
        self.reading = r;
        self
    }

    pub fn with_weighting(mut self, w: Weighting) -> Self {
        self.weighting = w;
        self
    }

    pub fn with_exponents(mut self, e: ExponentChoice) -> Self {
        self.exponents = e;
        self
    }

    pub fn with_fixed(mut self, name: &str, value: f64) -> Self {
        self.fix.push((name.to_string(), value));
        self
    }
}

/// Errors of [`identify`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    #[error(transparent)]
    Spec(#[from] SpecError),
    #[error(transparent)]
    EquationError(#[from] EquationErrorError),
    #[error(transparent)]
    Landscape(#[from] LandscapeError),
    #[error(transparent)]
    Fit(#[from] FitError),
    #[error("phase weight {0} must be finite and > 0")]
    BadPhaseWeight(f64),
    #[error("jump weight {0} must be finite and >= 0")]
    BadJumpWeight(f64),
    #[error("no candidate of the landscape could be refined: {0}")]
    NoCandidate(String),
    /// Cancelled through `plan.lm.cancel` ([`crate::cancel`]): no result.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}

/// The gain decision of [`GainChoice::Auto`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GainTest {
    /// Equation-error gain estimate (stage 3).
    pub gain: f64,
    /// F statistic of freeing it in the equation error (the screen).
    pub f_statistic: f64,
    /// The final decision.
    pub freed: bool,
    /// The output-error test that decided (stage 5), when it ran.
    pub output_error: Option<OutputErrorGainTest>,
}

/// The output-error comparison of the held and the free gain.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OutputErrorGainTest {
    /// Objective with the gain held at 1, and free.
    pub held: f64,
    pub free: f64,
    /// The free gain's estimate.
    pub gain: f64,
    /// The drop of the objective when the gain is freed, scaled by its
    /// expected size under the noise: χ²₁ when the gain is 1.
    pub f_statistic: f64,
    /// The free estimate sits at a bound of the gain (reported as such
    /// when freed).
    pub at_bound: bool,
}

/// One refined candidate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Candidate {
    pub rho: f64,
    pub eta: f64,
    /// Equation-error cost at the node.
    pub ee_cost: f64,
    /// Sign used for it.
    pub sign: Sign,
    /// Objective minimised by output error (incl. jump/phase terms), or the error.
    pub oe: Result<f64, String>,
    /// The forcing gain this candidate was fitted with held (`None`: free).
    /// When the equation-error screen frees the gain, each node is raced
    /// with it free and held at 1, and appears once for each.
    #[serde(default)]
    pub gain: Option<f64>,
}

/// Progress of [`identify`], for a progress bar: each stage announces
/// itself with the number of steps it will report, then reports them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdentifyProgress {
    /// A stage begins: `"landscape"` (one step per row of the exponent
    /// grid), `"output error"` (one step per refined start), `"output error
    /// on all points"`, `"decisions"`, `"escalation"`.
    Stage { name: &'static str, steps: usize },
    /// One step of the current stage is done.
    Step,
}

/// What the fit says about one measured curve.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurveReport {
    pub level: String,
    pub gamma: f64,
    pub direction: SweepDirection,
    /// How its jump was read.
    pub reading: JumpReading,
    /// The last measured step (rad/s) on the branch the model's sweep
    /// starts on, before the sweep measured the other branch: the measured
    /// jump. `None` when the curve does not leave its first branch.
    pub measured_jump: Option<f64>,
    /// The measured step after it (rad/s): the jump lies between the two.
    pub measured_jump_next: Option<f64>,
    /// The model's first jump (fold), rad/s.
    pub model_jump: Option<f64>,
    /// How far before the model's fold the measured sweep left its branch
    /// (rad/s, > 0), when by a step or more.
    pub left_early_by: Option<f64>,
    /// The residual against the noise.
    pub noise: CurveNoise,
    /// RMS of `a_model − a_meas` over the steps before the measured jump
    /// (m), where there is one.
    pub upper_branch_rms: Option<f64>,
    /// Largest measured amplitude and the model's amplitude there (m).
    pub peak: (f64, f64),
}

/// The self-check of a fit against the noise of its data (stage 8).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adequacy {
    /// The model fits every curve to within the noise thresholds.
    pub adequate: bool,
    /// `√(mean z²)` over all points: the residual in units of the noise.
    pub ratio: f64,
    /// `√(mean z²)` over the points of the resonance peaks (at least half
    /// their curve's peak amplitude), where Eq 31's cost lies: a fit that
    /// misses the peaks by a few noise levels can look fine on average.
    /// (Against the noise the peaks' pseudo-residuals support where they
    /// reject the estimate: [`ADEQUACY_PEAKS`].)
    pub peak_ratio: f64,
    /// Indices (into [`Identification::curves`]) of the curves that do not
    /// fit (`mean z² >` [`ADEQUACY_CURVE`]).
    pub failing: Vec<usize>,
    /// What was tried because the first fit did not fit, or because the
    /// data have a single forcing level (searched as widely whatever the
    /// residual).
    pub escalation: Vec<String>,
    /// Set when the fit fits only with some jumps read as censored by
    /// [`ReadingChoice::Auto`]: the worst residual over noise of the fit
    /// read exactly. Such a fit is not adequate: it rests on sweeps having
    /// left their branch early, which the data alone cannot confirm, and on
    /// data of the model family it means the exact optimum was missed
    /// (measured: a blind three-level set whose exact fit was stuck at
    /// 111x the noise fitted the noise censored, at 621x the truth's Eq 31
    /// cost).
    pub needs_early_jumps: Option<f64>,
    /// Curves read exactly whose measured sweep left the model's branch a
    /// step or more before the model's fold ([`CurveReport::left_early_by`]),
    /// with the residual over the noise of the model's own sweep there
    /// (Eq 31: those points compared with the branch the sweep had not yet
    /// left). Read exactly, a sweep jumps at its fold, so such a fit is not
    /// a solution of its own reading however small its output error: the
    /// measured-branch output error charges the points between the jumps a
    /// penalty scaled by their distance to the fold, which a noisy fit can
    /// absorb (measured: a blind in-family set, four levels both ways, whose
    /// fit left one up-sweep 0.057 Hz — 1.1 steps — early at a residual
    /// 1.16x the noise over all points, while its Eq 31 cost was 92x the
    /// truth's). Not adequate.
    #[serde(default)]
    pub late_folds: Vec<(usize, f64)>,
    /// For a fit with phases: the mean `z²` over all points of the
    /// amplitude residuals (with the penalty terms) and of the phase
    /// residuals, apart (the first line names the part that does not fit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub split: Option<NoiseSplit>,
}

impl Adequacy {
    /// The residual over the noise that the first line quotes: the worst
    /// failing curve's; the resonance peaks' when only they fail; else the
    /// whole set's. (For a fit that fits only with early jumps, the line
    /// quotes [`Self::needs_early_jumps`] instead.)
    pub fn quoted_ratio(&self, curves: &[CurveReport]) -> f64 {
        if !self.failing.is_empty() {
            self.failing
                .iter()
                .filter_map(|&i| curves.get(i))
                .map(|c| c.noise.ratio())
                .fold(0.0f64, f64::max)
        } else if self.only_late_folds() {
            self.late_folds.iter().map(|l| l.1).fold(0.0f64, f64::max)
        } else if self.only_peaks_fail() {
            self.peak_ratio
        } else {
            self.ratio
        }
    }

    /// No curve and not the whole set fails, only the resonance peaks.
    fn only_peaks_fail(&self) -> bool {
        self.failing.is_empty()
            && !(self.peak_ratio.powi(2) <= ADEQUACY_PEAKS)
            && self.ratio.powi(2) <= ADEQUACY_ALL
    }

    /// The residual fits the noise everywhere; only some sweeps left the
    /// model's branch before its fold ([`Self::late_folds`]).
    fn only_late_folds(&self) -> bool {
        !self.late_folds.is_empty()
            && self.failing.is_empty()
            && self.peak_ratio.powi(2) <= ADEQUACY_PEAKS
            && self.ratio.powi(2) <= ADEQUACY_ALL
    }
}

/// The outcome of [`identify`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Identification {
    /// The final output-error fit.
    pub fit: FitResult,
    /// The structure it was fitted with (sign, gain status, phase weight,
    /// jump readings).
    pub spec: FitSpec,
    /// The data as fitted (phases converted to displacement lags, or
    /// dropped when phase is not used).
    pub data: Dataset,
    /// Equation-error fit at the best landscape node.
    pub equation_error: EquationErrorFit,
    pub landscape: Landscape,
    /// Profile-likelihood 95 % intervals (equation error) of ρ and η.
    pub rho_profile: Option<ProfileInterval>,
    pub eta_profile: Option<ProfileInterval>,
    /// The phase convention used (detected or given).
    pub phase: Option<PhaseConvention>,
    pub gain_test: Option<GainTest>,
    /// Weight of the jump penalties.
    pub jump_weight: f64,
    pub candidates: Vec<Candidate>,
    /// Per curve (data order): readings, jumps, residual against the noise.
    pub curves: Vec<CurveReport>,
    pub adequacy: Adequacy,
    /// With [`SignChoice::Both`]: the best objective of each sign.
    pub sign_trials: Vec<SignTrial>,
    /// The landscape node `(ρ, η)` that joined the race from
    /// [`FitPlan::start_exponents`], if any.
    pub start_node: Option<(f64, f64)>,
}

impl Identification {
    /// The first line a user must read, `None` when the fit is fine: that
    /// the model does not fit (naming the curves and by how much), then the
    /// fit's own warning.
    pub fn warning(&self) -> Option<String> {
        let mut parts = Vec::new();
        if let Some(h) = self.unit_hint() {
            parts.push(h);
        }
        if let Some(m) = self.adequacy_message() {
            parts.push(m);
        }
        if let Some(w) = self.fit.warning() {
            parts.push(w);
        }
        (!parts.is_empty()).then(|| parts.join("\n"))
    }

    /// A likely unit mistake in the data, with its fix (issue 28), or
    /// `None`:
    /// * a free forcing gain within [`G_HINT_TOLERANCE`] of g = 9.80665:
    ///   the levels were given in g;
    /// * a fit that does not fit, on data whose resonance amplification
    ///   `a Ω²/(gain γ)` exceeds [`AMPLIFICATION_HINT`] (a damping ratio
    ///   under 5e-5): amplitudes 1000x too large read that way, so they may
    ///   be in mm.
    pub fn unit_hint(&self) -> Option<String> {
        let gain = self.fit.theta[GAIN];
        // a free gain stopped by its bound (10 by default: within 3 % of
        // g) measures nothing but the bound: amplitudes in mm push it
        // there, and it must not read as "levels in g"
        let (lo, hi) = self.spec.bounds[GAIN];
        let at_bound = (gain - hi).abs() <= 1e-6 * hi.abs().max(1.0)
            || (gain - lo).abs() <= 1e-6 * lo.abs().max(1.0);
        if matches!(self.fit.status[GAIN], Status::Free)
            && !at_bound
            && (gain / G_STANDARD - 1.0).abs() <= G_HINT_TOLERANCE
        {
            return Some(format!(
                "HINT: the fitted forcing gain is {gain:.4}, within {:.0} % of g = {G_STANDARD} m/s^2: the levels \
                 look like they are in g; give gamma in m/s^2 (CLI: --gamma-in-g; Python: gamma_in_g=True)",
                100.0 * G_HINT_TOLERANCE
            ));
        }
        if self.adequacy.adequate {
            return None;
        }
        let amplification = self
            .data
            .curves
            .iter()
            .filter_map(|c| {
                let k = c.peak_index();
                let g = c.gamma * if at_bound { 1.0 } else { gain };
                (g > 0.0).then(|| c.amplitudes[k] * c.omegas[k] * c.omegas[k] / g)
            })
            .fold(0.0f64, f64::max);
        (amplification > AMPLIFICATION_HINT).then(|| {
            format!(
                "HINT: at the resonance peak the response is {amplification:.3e} times the input (a Omega^2 / gamma, \
                 a damping ratio near {:.1e}); if the amplitudes are in mm, give them in m (zero-to-peak)",
                0.5 / amplification
            )
        })
    }

    /// "WARNING: the model does not fit levels 0.08g, 0.10g: residual 6.2x
    /// the noise", or `None` when it fits.
    pub fn adequacy_message(&self) -> Option<String> {
        if self.adequacy.adequate {
            return None;
        }
        let mut names: Vec<String> = Vec::new();
        for &i in &self.adequacy.failing {
            let c = &self.curves[i];
            let dir = c.direction.name();
            let both = self.curves.iter().filter(|o| o.level == c.level).count() > 1;
            let name = if both {
                format!("{} ({dir})", c.level)
            } else {
                c.level.clone()
            };
            if !names.contains(&name) {
                names.push(name);
            }
        }
        let tried = if self.adequacy.escalation.is_empty() {
            String::new()
        } else {
            format!(" (also tried: {})", self.adequacy.escalation.join(", "))
        };
        if let Some(exact) = self.adequacy.needs_early_jumps {
            let early: Vec<String> = self
                .curves
                .iter()
                .filter(|c| c.reading == JumpReading::Censored)
                .map(|c| format!("{} ({})", c.level, c.direction.name()))
                .collect();
            return Some(format!(
                "WARNING: the model fits only if the sweep{} of level{} {} left {} branch before the model's fold; \
                 read exactly (a sweep jumps at its fold) it does not fit: residual {exact:.1}x the noise{tried}. \
                 On data of the model family this means the fit missed its optimum; if those sweeps did leave early, \
                 state it with --jump-reading censored",
                if early.len() > 1 { "s" } else { "" },
                if early.len() > 1 { "s" } else { "" },
                early.join(", "),
                if early.len() > 1 { "their" } else { "its" },
            ));
        }
        // the number quoted is `FitResult::misfit`
        let r = self.adequacy.quoted_ratio(&self.curves);
        Some(if self.adequacy.only_late_folds() {
            let late: Vec<String> = self
                .adequacy
                .late_folds
                .iter()
                .filter_map(|&(i, _)| self.curves.get(i))
                .map(|c| {
                    format!(
                        "{} ({}) {:.3} Hz",
                        c.level,
                        c.direction.name(),
                        c.left_early_by.unwrap_or(f64::NAN) / std::f64::consts::TAU
                    )
                })
                .collect();
            format!(
                "WARNING: the model's own sweep does not follow the data: the measured sweep{} left {} branch before \
                 the model's fold (level{} {}), where the model's sweep is still on it: residual {r:.1}x the noise there \
                 (Eq 31){tried}. On data of the model family this means the fit missed its optimum; if those sweeps \
                 did leave early, state it with --jump-reading censored",
                if late.len() > 1 { "s" } else { "" },
                if late.len() > 1 { "their" } else { "its" },
                if late.len() > 1 { "s" } else { "" },
                late.join(", "),
            )
        } else if self.adequacy.only_peaks_fail() {
            format!(
                "WARNING: the model does not fit the resonance peaks: residual {r:.1}x the noise there \
                 ({:.1}x over all points){tried}",
                self.adequacy.ratio
            )
        } else if names.is_empty() {
            let parts = split_text(self.adequacy.split.as_ref());
            format!("WARNING: the model does not fit the data: residual {r:.1}x the noise{parts}{tried}")
        } else {
            // the split of the curve whose ratio is quoted
            let worst = self
                .adequacy
                .failing
                .iter()
                .filter_map(|&i| self.curves.get(i))
                .max_by(|a, b| a.noise.ratio().total_cmp(&b.noise.ratio()));
            let parts = split_text(worst.and_then(|c| c.noise.split.as_ref()));
            format!(
                "WARNING: the model does not fit level{} {}: residual {r:.1}x the noise{parts}{tried}",
                if names.len() > 1 { "s" } else { "" },
                names.join(", "),
            )
        })
    }
}

/// " (amplitudes 1.0x, phases 2.1x)": which part of a fit with phases
/// does not fit its noise (empty without phases).
fn split_text(split: Option<&NoiseSplit>) -> String {
    split.map_or_else(String::new, |s| {
        let (a, p) = s.ratios();
        format!(" (amplitudes {a:.1}x, phases {p:.1}x)")
    })
}

/// One fit on its way through the stages.
#[derive(Debug, Clone)]
struct Fitted {
    fit: FitResult,
    spec: FitSpec,
    /// The LM objective (amplitude, phase and penalty residuals squared)
    /// on the data it was fitted to.
    objective: f64,
    /// Added to every measured phase lag of the stages' data to give the
    /// data this fit was made on (rad; [`node_phase_shift`]): 0 except for
    /// a fit from a landscape node whose own detected phase offset the
    /// output error's correction cannot reach from the stages'.
    phase_shift: f64,
}

impl Fitted {
    fn from_result(fit: FitResult, spec: FitSpec) -> Self {
        let objective = fit
            .minima
            .first()
            .map_or(fit.objective + fit.phase_cost.unwrap_or(0.0), |m| m.cost);
        Self {
            fit,
            spec,
            objective,
            phase_shift: 0.0,
        }
    }

    /// `spec` at θ assessed on `data` (objective, Jacobian, flags) as the
    /// end of the fit `of` (its termination, iterations and minima); the
    /// objective is the assessed one.
    fn assessed(
        data: &Dataset,
        spec: FitSpec,
        theta: super::Parameters,
        of: &FitResult,
    ) -> Result<Self, FitError> {
        let r = super::assess(
            data,
            &spec,
            theta,
            of.termination,
            of.iterations,
            of.minima.clone(),
        )?;
        let mut out = Self::from_result(r, spec);
        out.objective = out.fit.objective + out.fit.phase_cost.unwrap_or(0.0);
        Ok(out)
    }

    /// `self` as a fit made on the stages' data shifted by `shift`
    /// ([`Fitted::phase_shift`]).
    fn read_shifted(self, shift: f64) -> Self {
        Self {
            phase_shift: shift,
            ..self
        }
    }

    /// `spec` fitted on `data` with `opts` (no progress reports); `None`
    /// when the fit fails.
    fn fitted(data: &Dataset, spec: FitSpec, opts: &FitOptions) -> Option<Self> {
        fit_impl(data, &spec, opts, None, &|| {})
            .ok()
            .map(|r| Self::from_result(r, spec))
    }
}

/// Everything fixed before the data decide anything.
struct Setup<'a> {
    data: &'a Dataset,
    plan: &'a FitPlan,
    spec0: FitSpec,
    phase_mode: LandscapePhase,
    prep: Prepared,
    terms_free: Terms,
    rho_axis: Axis,
    eta_axis: Axis,
    integer: bool,
}

impl Setup<'_> {
    /// `FitSpec` of the plan (bounds, fixes, frees, gain choice) for `sign`.
    fn configure(&self, sign: Sign) -> Result<FitSpec, IdentifyError> {
        configure(self.plan, self.data, sign)
    }
}

fn configure(plan: &FitPlan, data: &Dataset, sign: Sign) -> Result<FitSpec, IdentifyError> {
    let mut s = FitSpec::new_signed(plan.kind, data, sign);
    for (n, lo, hi) in &plan.bounds {
        s.set_bounds(n, *lo, *hi)?;
    }
    for (n, v) in &plan.fix {
        s.fix(n, *v)?;
    }
    for n in &plan.free {
        s.free(n)?;
    }
    match plan.gain {
        GainChoice::Fixed(g) => s.fix("gain", g)?,
        GainChoice::Free => s.free("gain")?,
        GainChoice::Auto => {}
    }
    // κ held at 0 is the model without nonlinear damping: the term is
    // absent (its exponent means nothing), so that no stage fits it (the
    // equation-error landscape has no held coefficients: measured on a
    // blind three-level set, κ = 0 and η = 1 held ended at gain 1.55, a
    // linear model 64.8x the noise; κ absent fits at 0.988x the truth's
    // Eq 31 cost)
    if s.status[KAPPA] == Status::Fixed(0.0) {
        for j in [KAPPA, ETA] {
            s.status[j] = Status::Absent;
            s.start[j] = 0.0;
        }
    }
    for (exp, coef, linear, remedy) in [
        (RHO, BETA, ALPHA, "use a model without nonlinear stiffness"),
        (ETA, KAPPA, DELTA, "hold kappa at 0 (no nonlinear damping)"),
    ] {
        if s.status[exp] == Status::Fixed(0.0) && s.status[coef] == Status::Free {
            return Err(SpecError::CopiesLinear {
                exponent: PARAM_NAMES[exp],
                coefficient: PARAM_NAMES[coef],
                linear: PARAM_NAMES[linear],
                remedy,
            }
            .into());
        }
    }
    Ok(s)
}

/// The result of stages 1–2.
struct Exploration {
    land: Landscape,
    best_ee: EquationErrorFit,
    phase_conv: Option<PhaseConvention>,
}

/// Runs the whole identification (module docs).
pub fn identify(
    data: &Dataset,
    plan: &FitPlan,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Identification, IdentifyError> {
    match stages(data, plan, progress) {
        // a run cancelled inside a stage can surface as that stage's own
        // failure (a race whose every candidate was interrupted read "no
        // candidate of the landscape could be refined: interrupted"): the
        // flag decides, so a cancelled run always ends with `Interrupted`
        Err(e) if plan.lm.cancel.is_cancelled() && !matches!(e, IdentifyError::Interrupted(_)) => {
            Err(crate::cancel::Interrupted.into())
        }
        r => r,
    }
}

/// The stages of [`identify`], in order.
fn stages(
    data: &Dataset,
    plan: &FitPlan,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Identification, IdentifyError> {
    validate(plan)?;
    let setup = prepare(data, plan)?;
    let mut ex = explore(&setup, progress)?;
    // (cancellation: every fit polls `plan.lm.cancel`; the stages are
    // checked here so that a cancelled run returns no partial result)
    let cancel = plan.lm.cancel;
    cancel.check()?;
    let (gain_test, gain_status) = screen_gain(&setup, &ex);
    let mut fit_data = data_as_fitted(&setup, &ex);
    let mut refine_data = subsample(&fit_data, plan.refine_points);
    let mut nodes = candidate_nodes(&ex.land, plan.refine.max(1));
    // (a single-node landscape: the model holds both exponents, no start)
    let start_node = plan
        .start_exponents
        .as_ref()
        .filter(|_| ex.land.rho.len() * ex.land.eta.len() > 1)
        .and_then(|s| nearest_node(&ex.land, s));
    if let Some(n) = start_node {
        if !nodes.contains(&n) {
            nodes.push(n);
        }
    }
    let signs = |ee: &EquationErrorFit| -> Vec<Sign> {
        match plan.sign {
            SignChoice::Hardening => vec![Sign::Hardening],
            SignChoice::Softening => vec![Sign::Softening],
            SignChoice::Both if setup.spec0.status[BETA] != Status::Absent => {
                vec![Sign::Hardening, Sign::Softening]
            }
            _ => vec![if ee.theta[BETA] < 0.0 {
                Sign::Softening
            } else {
                Sign::Hardening
            }],
        }
    };
    let race_with = |gain: Status| {
        let data = &refine_data;
        race(&setup, &ex, data, &nodes, gain, &signs, &[], true, progress)
    };
    let (mut candidates, mut winner, mut sign_trials, raced) = race_with(gain_status)?;
    cancel.check()?;
    // The equation-error screen freed the gain (it only chooses the starts;
    // stage 5 decides): the candidates also race with the gain held at 1,
    // and that race's winner goes through stages 5–7 beside the free one
    // (`finish_alternative`: kept if it fits its noise where the other does
    // not, or lower on every point). From a free-gain winner in another
    // basin the held refit of stage 5 stays stuck there, and the
    // output-error test then frees the gain against a held fit far above the
    // held optimum. Measured on blind h040-mixed of seed 2711270312 (three
    // levels up, no phase, screen F = 66): the free race ended at gain 1.41,
    // the held refit 1360× above the truth's objective, the gain freed with
    // F = 1.4e6, the fit flagged at 14.7× the truth's Eq 31 cost; now
    // 0.977×. Blind h053-mixed of 2711270143 (five levels up, F = 194):
    // 422×, flagged, now 0.946×. The held winner does not replace the free
    // one outright, although it is often lower on the race's data: on blind
    // h013-mixed of 110808810 (test
    // `an_exponent_profile_finds_the_basin_no_candidate_reached`) it was,
    // and its fit ended with a late fold, its objective below the truth's
    // and 69× its Eq 31 cost, which no later stage could leave.
    // (only when the screen's own free gain is within HELD_RACE_GAIN of 1:
    // on the beams, whose gain is not 1, it is 2.3–3.1 or 0.13, and the held
    // race there only costs time, up to 1.5 s)
    let mut held_alt = None;
    // (the held race's list of raced nodes, for an escalation of its own)
    let mut held_raced: Option<Vec<(usize, usize, Sign)>> = None;
    let screened_near_one = gain_test
        .as_ref()
        .is_some_and(|t| t.gain.is_finite() && t.gain.ln().abs() <= HELD_RACE_GAIN.ln());
    if plan.gain == GainChoice::Auto && gain_status == Status::Free && screened_near_one {
        let (more, held_winner, trials, list) = race_with(Status::Fixed(1.0))?;
        cancel.check()?;
        candidates.extend(more);
        merge_sign_trials(&mut sign_trials, trials);
        held_alt = Some(held_winner);
        held_raced = Some(list);
    }
    // a winner that read the phases with its own node's offset makes that
    // reading the stages' (`node_phase_shift`)
    let winner_shift = winner.phase_shift;
    let datas = [&mut fit_data, &mut refine_data];
    adopt_phase_shift(&mut winner, &mut ex.phase_conv, datas);
    if let Some(h) = held_alt.as_mut() {
        h.phase_shift -= winner_shift;
    }
    let race_winner = winner.clone();
    // the held race's winner as it stands here: an escalation of its own
    // starts from it, while the stages still read the data as the race did
    // (`conv_at_race`)
    let held_winner = held_alt.clone();
    let conv_at_race = ex.phase_conv;
    let mut gain_test = gain_test;
    let race_objective = winner.objective;
    let mut best = finish(
        &setup,
        winner,
        &fit_data,
        &refine_data,
        &mut gain_test,
        progress,
    )?;
    cancel.check()?;
    let (mut curves, mut adequacy) = judge(&fit_data, &best);
    if let Some(h) = held_alt {
        let datas = (&mut fit_data, &mut refine_data, &mut ex.phase_conv);
        let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
        finish_alternative(&setup, h, datas, result, progress)?;
        cancel.check()?;
    }
    // A single forcing level pins the exponents weakly (the damping is seen
    // at one amplitude only), and a fit from another basin can sit within
    // the noise: such data are searched as widely as data that do not fit
    // (measured: a blind set, one level swept up and down, no phase, ρ 5.6,
    // η 1.7, whose race ended at η 0.04 and 2.11x the truth's Eq 31 cost
    // with a residual 1.23x the noise; the escalation reaches 0.97x).
    let single_level = fit_data.levels().len() == 1;
    if (!adequacy.adequate || single_level) && plan.escalate {
        let (alt, tried, more) = escalate(
            &setup,
            &ex,
            &refine_data,
            gain_status,
            (&race_winner, adequacy.ratio <= PROFILE_MAX_RATIO),
            &raced,
            progress,
        )?;
        candidates.extend(more.0);
        merge_sign_trials(&mut sign_trials, more.1);
        adequacy.escalation = tried;
        // an escalation that found no lower objective than the race (on the
        // same data, same reading) is not carried through the decisions
        if let Some(alt) = alt.filter(|a| a.objective < race_objective * (1.0 - 1e-6)) {
            let datas = (&mut fit_data, &mut refine_data, &mut ex.phase_conv);
            let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
            finish_alternative(&setup, alt, datas, result, progress)?;
        }
    }
    // A gain freed near 1 (`HELD_RACE_GAIN`) on a fit that still does not
    // fit its noise after the escalation: the escalation again (with the
    // exponent profile within `PROFILE_MAX_RATIO` of the noise), from the
    // race with the gain held at 1, and its result through the stages
    // beside the standing fit (`finish_alternative`). When the screen's free
    // gain was far from 1 that race has not run: it runs now, on the nodes
    // of the landscape with the gain held (`explore_held`; the screen's
    // landscape has the minima of its free gain), and its winner goes
    // through the stages when the escalation finds nothing lower (measured:
    // blind h018-mixed of seed 2811280612, one level up, no phase, ρ 5.64,
    // η 2.67: the screen freed the gain at 282, the fit ended at ρ 10, its
    // bound, gain 0.72, 1715x the noise and 2202x the truth's Eq 31 cost,
    // flagged; a held race on the screen's nodes stayed at ρ 10; now
    // 0.996x). A free gain absorbs the misfit of another
    // basin, and the held race's winner alone, carried through the stages,
    // can stay in one (measured: blind h025-mixed of seed 2711280113, one
    // level up and down, no phase, ρ 4.12, η 2.85: the screen freed the
    // gain at 1.35; the free race and its escalation ended at η 7.1 with
    // the gain 1.041, 2.3x the noise and 1.685x the truth's Eq 31 cost,
    // flagged; the held race's winner, η 5.84, ended 1.9x the noise and
    // above it; the default stages with the gain fixed at 1 reach 1.006x.)
    // (Beams leave this out: their freed gains are 2.3–3.1 or 0.13; the six
    // beam fits are byte-identical with and without this step.)
    let gain_near_one = best.spec.status[GAIN] == Status::Free
        && best.fit.theta[GAIN].ln().abs() <= HELD_RACE_GAIN.ln();
    if plan.escalate
        && plan.gain == GainChoice::Auto
        && gain_near_one
        && !adequacy.adequate
        && ex.phase_conv == conv_at_race
    {
        // (`finished`: the held race's winner went through the stages
        // beside the free one already)
        let (first, list, held_ex, finished) = match (held_winner, held_raced) {
            (Some(w), Some(l)) => (w, l, None, true),
            _ => {
                // (the screen's landscape when the held one cannot be had)
                let held_ex = explore_held(&setup, &ex, progress)?;
                cancel.check()?;
                let (race_ex, held_nodes) = match &held_ex {
                    Some(h) => (h, candidate_nodes(&h.land, plan.refine.max(1))),
                    None => (&ex, nodes.clone()),
                };
                let (more, w, trials, l) = race(
                    &setup,
                    race_ex,
                    &refine_data,
                    &held_nodes,
                    Status::Fixed(1.0),
                    &signs,
                    &[],
                    true,
                    progress,
                )?;
                cancel.check()?;
                candidates.extend(more);
                merge_sign_trials(&mut sign_trials, trials);
                (w, l, held_ex, false)
            }
        };
        let held = Status::Fixed(1.0);
        let profile = adequacy.ratio <= PROFILE_MAX_RATIO;
        let (alt, tried, more) = escalate(
            &setup,
            held_ex.as_ref().unwrap_or(&ex),
            &refine_data,
            held,
            (&first, profile),
            &list,
            progress,
        )?;
        cancel.check()?;
        candidates.extend(more.0);
        merge_sign_trials(&mut sign_trials, more.1);
        let n = tried.len();
        adequacy.escalation.push(format!(
            "the same {n} steps with the gain held at 1 (the free gain's fit did not fit)"
        ));
        // the escalation's result, or the held race's winner when that has
        // not been through the stages yet
        let first_objective = first.objective;
        let alt = match alt.filter(|a| a.objective < first_objective * (1.0 - 1e-6)) {
            Some(a) => Some(a),
            None => (!finished).then_some(first),
        };
        if let Some(alt) = alt {
            let datas = (&mut fit_data, &mut refine_data, &mut ex.phase_conv);
            let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
            finish_alternative(&setup, alt, datas, result, progress)?;
            cancel.check()?;
        }
    }
    // A fit within its noise but near its top can sit in
    // another basin of an exponent, silently (`PROFILE_NEAR_NOISE`), and so
    // can one whose gain the decisions freed (in-family data have gain 1:
    // measured, blind h003-mixed of seed 2711270212, gain 0.995 freed with
    // F = 64 in a basin of η 0.41 against the truth's 0.92, 1.03× the noise
    // and 1.065× the truth's Eq 31 cost; the profile reaches 1.003×): the
    // escalation's exponent profile, from the fit on the race's data; a
    // freed fit with a lower objective there goes through the decisions and
    // is kept if its objective on every point is lower. A single level
    // gets it too, although its escalation already profiled the race's
    // winner: from the decided fit the local values lie elsewhere (measured:
    // blind h036-mixed of seed 2711270401, one level up and down, no phase,
    // ρ 1.82, η 1.44: the escalation's profile from the race winner at ρ
    // 2.67, η −0.72 ended 4.8× the truth's objective, the decided fit at
    // ρ 2.37, η 0.99 was 1.52× the truth's Eq 31 cost within its noise
    // (1.39×); held at ρ 1.87 from there it reaches 0.962×). And so does a
    // fit that does not fit its noise but is within `PROFILE_MAX_RATIO` of
    // it after the escalation, which profiled the race's winner only if
    // that was as near, not the fit it ended at (measured: blind h002-mixed
    // of seed 2711270143, two levels up, no phase, ρ 2.01, η 3.00: the race
    // winner too far to profile, the escalation's candidates and multistart
    // ended at η 6.14, 1.99× the noise and 1.88× the truth's Eq 31 cost,
    // flagged, now 0.980×; h036-mixed of 2711270407, two levels up and down,
    // ρ 1.23, η 3.66: profiled from the race winner, ended at η 7.5 with a
    // sweep read as censored, flagged at 118×, now 0.989×).
    let gain_freed = gain_test.as_ref().is_some_and(|t| t.freed);
    let near_top = adequacy.adequate && (adequacy.ratio > PROFILE_NEAR_NOISE || gain_freed);
    let misfit_near_noise = !adequacy.adequate && adequacy.ratio <= PROFILE_MAX_RATIO;
    let profile_now = plan.escalate && (near_top || misfit_near_noise);
    if profile_now {
        let datas = (&fit_data, &refine_data);
        let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
        profile_decided(&setup, &ex, datas, result, ProfileScope::Across, progress)?;
    }
    // A fit within its noise whose fold is pinned at a measured step can
    // still miss the optimum (`unpin_folds`); it is kept only if it stays
    // within the noise. (Only such fits: a fit that does not fit is flagged
    // whatever its folds, and on the 24 °C beam, 1268x the noise, the
    // unpinned fit led the censored stage to a higher Eq 31 cost, 3.77e-4
    // against 3.37e-4.)
    // (data fitted on every point: a subsample's fit is judged, not refined,
    // on all points)
    // (a fit with no fold pinned is left as it is, and is not looked at again)
    let pinned = if adequacy.adequate && fit_data.len() <= POLISH_MAX_POINTS {
        pinned_folds(&fit_data, &best)?
    } else {
        Vec::new()
    };
    if !pinned.is_empty() {
        let un = unpin_folds(&setup, best.clone(), &fit_data, &pinned)?;
        let mut still_pinned = true;
        if un.fit.cost < best.fit.cost {
            let un = keep_folds_off_steps(un, &fit_data)?;
            let judged = judge(&fit_data, &un);
            if judged.1.adequate {
                adopt((&mut best, &mut curves, &mut adequacy), un, judged);
                still_pinned = !pinned_folds(&fit_data, &best)?.is_empty();
            }
        }
        // A fold still pinned against a measured step after that is a
        // constrained optimum: the fit wants the fold across the step, and
        // another basin of the exponents, with the fold inside its cell, can
        // be lower. Such a fit within its noise is profiled too (measured:
        // blind h036-mixed of seed 2711270501, three levels up, no phase,
        // rho 5.72, eta 2.32: level 2's fold 2e-6 Hz below a step after the
        // unpin refit, 1.006x the noise and 1.055x the truth's Eq 31 cost,
        // now 0.995x; h012-mixed of 2711270322, four levels up and down,
        // rho 5.07, eta 1.13: level 3's up-sweep fold on a step, 1.012x the
        // noise, 1.10x, now 0.996x). (The fit is adequate here: the unpin
        // refit is adopted only so.)
        if plan.escalate && !profile_now && still_pinned {
            let datas = (&fit_data, &refine_data);
            let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
            if profile_decided(&setup, &ex, datas, result, ProfileScope::Near, progress)? {
                still_pinned = !pinned_folds(&fit_data, &best)?.is_empty();
            }
        }
        // A fold pinned still after the profiles: the fit stopped against
        // that constraint is no stationary point, and with an exponent held
        // two of its standard errors away the other parameters can refit
        // lower, where half a unit away lies far higher (measured: blind
        // h008-hardening of seed 233097205, one level up, rho 4.92: the fit
        // converged within the noise at rho 4.772 +- 0.049, 1.056x the
        // truth's Eq 31 cost, its fold pinned above the last step on its
        // branch after the unpin refit and both profiles; with rho held at
        // 4.80 or 4.85 the others refit from the fit to 0.995x and 0.979x,
        // while at 5.27 and 4.27 they end 1.6x and 2.8x above the fit; now
        // 0.980x). A step of its
        // own, after the others: tried among the near profile's values, the
        // best freed fit of the two steps was chosen before its decisions,
        // and blind h036-hardening of 2711280106 ended at 1.111x instead of
        // 0.994x (its finer fit lost its damping term there).
        if plan.escalate && still_pinned {
            let datas = (&fit_data, &refine_data);
            let result = (&mut best, &mut curves, &mut adequacy, &mut gain_test);
            profile_decided(&setup, &ex, datas, result, ProfileScope::Fine, progress)?;
        }
    }
    // Early jumps: only a fit that does not fit the noise with every jump
    // read exactly (after the escalation) is asked whether some sweeps left
    // their branch early. On data of the model family the exact reading
    // fits, and a stuck fit must not be "explained" by early departures
    // (measured: a blind in-family set whose exact fit had a fold 22 steps
    // off was censored at two levels and ended at 1000x the truth's cost).
    cancel.check()?;
    if !adequacy.adequate && plan.reading == ReadingChoice::Auto {
        let start = restarted(&best.spec, &best.fit.theta);
        let on_sub = Fitted {
            spec: carry_readings(&start, &fit_data, &refine_data),
            ..best.clone()
        };
        let on_sub = refit_on(&setup, on_sub, &refine_data)?;
        let censored = decide_readings(&setup, on_sub, &refine_data)?;
        if censored.spec.censored.iter().any(|&c| c) {
            let alt = refine_all_points(&setup, censored, &fit_data, &refine_data, progress)?;
            let alt = keep_folds_off_steps(alt, fit_data_or_sub(&fit_data, &refine_data))?;
            let alt = judged_on_all(alt, &fit_data, &refine_data)?;
            // decided by the significance test of decide_readings; on every
            // point a censored reading cannot cost more than the exact one
            // at the same θ, so a higher objective means the refinement on
            // every point failed, and the exact fit is kept
            if alt.objective <= best.objective {
                let (alt, (alt_curves, mut alt_adequacy)) =
                    read_exactly_if_it_fits(alt, &fit_data, best.objective)?;
                if alt_adequacy.adequate && alt.spec.censored.iter().any(|&c| c) {
                    let exact_worst = adequacy
                        .failing
                        .iter()
                        .map(|&i| curves[i].noise.ratio())
                        .fold(adequacy.ratio, f64::max);
                    alt_adequacy.adequate = false;
                    alt_adequacy.needs_early_jumps = Some(exact_worst);
                }
                adopt(
                    (&mut best, &mut curves, &mut adequacy),
                    alt,
                    (alt_curves, alt_adequacy),
                );
            }
        }
    }
    let mut phase_conv = ex.phase_conv;
    if let Some(conv) = phase_conv.as_mut() {
        best = bake_phase_offset(best, &mut fit_data, &mut refine_data, conv)?;
    }
    cancel.check()?;
    let Fitted { mut fit, spec, .. } = best;
    // a fit that does not fit its noise has no valid intervals
    // (`FitResult::misfit`)
    fit.misfit = (!adequacy.adequate).then(|| {
        adequacy
            .needs_early_jumps
            .unwrap_or_else(|| adequacy.quoted_ratio(&curves))
    });
    let start_node = start_node.map(|(i, j)| (ex.land.rho[i], ex.land.eta[j]));
    Ok(Identification {
        fit,
        jump_weight: spec.jump_weight,
        spec,
        data: fit_data,
        rho_profile: ex.land.profile_interval(0),
        eta_profile: ex.land.profile_interval(1),
        equation_error: ex.best_ee,
        landscape: ex.land,
        phase: if matches!(setup.phase_mode, LandscapePhase::Ignore) {
            None
        } else {
            phase_conv
        },
        gain_test,
        candidates,
        curves,
        adequacy,
        sign_trials,
        start_node,
    })
}

/// The standing result of the stages, which an alternative may replace:
/// the fit, its per-curve reports, its adequacy and its gain test.
type Standing<'a> = (
    &'a mut Fitted,
    &'a mut Vec<CurveReport>,
    &'a mut Adequacy,
    &'a mut Option<GainTest>,
);

/// The exponent profile ([`profile_exponents`]) from the decided fit `best`
/// on the race's data (`refine_data`), with the fit's readings carried
/// there; a profiled fit with a lower objective there goes through the
/// decisions and replaces `best` by [`finish_and_adopt_if_better`]
/// (`true` when it did). The escalation list names it (a second profile,
/// after the escalation's, says where from). A fit the race's data cannot
/// assess is left as it is.
fn profile_decided(
    setup: &Setup,
    ex: &Exploration,
    (fit_data, refine_data): (&Dataset, &Dataset),
    (best, curves, adequacy, gain_test): Standing<'_>,
    scope: ProfileScope,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<bool, IdentifyError> {
    let start = restarted(&best.spec, &best.fit.theta);
    let spec = carry_readings(&start, fit_data, refine_data);
    let Ok(here) = Fitted::assessed(refine_data, spec, best.fit.theta, &best.fit) else {
        return Ok(false);
    };
    let Some((p, held)) = profile_exponents(setup, ex, refine_data, &here, scope, progress) else {
        return Ok(false);
    };
    let again = adequacy
        .escalation
        .iter()
        .any(|t| t.contains("exponent held"));
    adequacy.escalation.push(match (scope, again) {
        (ProfileScope::Near, _) => {
            format!("{held} fits with an exponent held half a unit either side of the fit (a fold pinned at a step)")
        }
        (ProfileScope::Fine, _) => {
            format!("{held} fits with an exponent held two standard errors either side of the fit (a fold still pinned at a step)")
        }
        (ProfileScope::Across, true) => {
            format!("{held} more with an exponent held, from the fit the escalation ended at")
        }
        (ProfileScope::Across, false) => held_across(held),
    });
    if p.objective < here.objective * (1.0 - 1e-6) {
        let lower = match scope {
            ProfileScope::Across => Lower::Any,
            ProfileScope::Near | ProfileScope::Fine => Lower::Significantly,
        };
        let result = (&mut *best, &mut *curves, &mut *adequacy, &mut *gain_test);
        let datas = (fit_data, refine_data);
        if finish_and_adopt_if_better(setup, p.clone(), datas, result, lower, progress)? {
            return Ok(true);
        }
        // (not adopted: `best` is as it was)
        if let Some(h) = held_on_every_point(setup, best, &p, datas)? {
            let kept = adopt_if_better((best, curves, adequacy), h, fit_data, lower)?;
            if kept {
                adequacy
                    .escalation
                    .push("the profile's exponent held on every point, then freed".to_string());
            }
            return Ok(kept);
        }
    }
    Ok(false)
}

/// The exponent values of a profiled fit `p` (found on the race's
/// subsample) carried to every point: each exponent `p` moved, held there
/// on every point and the rest refitted, from the standing fit `best` with
/// that exponent moved and from `p`, then freed; the lowest, its folds
/// treated as stage 9 treats them, or `None` (data not refined on every
/// point, no exponent moved, no fit). The subsample's optimum can lie
/// elsewhere than every point's, and a refit on every point from it stops
/// wherever a fold meets a measured step, as the freed fits do here too:
/// held, the exponent cannot follow the fold back (measured: blind
/// h008-mixed of random seed 4120673301, five levels up and down, no
/// phase, ρ 5.04, η 2.19: the fit at η 1.50, within the noise at 1.063x
/// the truth's Eq 31 cost; the profile held η at 2.0 and reached 0.88x
/// the standing fit's objective on the subsample, but carried through
/// the decisions its refit on every point stopped at once, 1.015x the
/// standing fit's objective there; η held at 2.0 on every point from the
/// standing fit, the rest refit to 0.937x of it).
fn held_on_every_point(
    setup: &Setup,
    best: &Fitted,
    p: &Fitted,
    (fit_data, refine_data): (&Dataset, &Dataset),
) -> Result<Option<Fitted>, IdentifyError> {
    if !refined_on_every_point(fit_data, refine_data) {
        return Ok(None);
    }
    let plan = setup.plan;
    let opts = limited(&plan.lm, plan.seed, RACE_ITERATIONS);
    let mut out: Option<Fitted> = None;
    for j in [RHO, ETA] {
        let v = p.fit.theta[j];
        let moved = best.spec.status[j] == Status::Free
            && p.spec.status[j] == Status::Free
            && (v - best.fit.theta[j]).abs() > PROFILE_FINE_MIN;
        if !moved {
            continue;
        }
        for from in [&best.fit.theta, &p.fit.theta] {
            let mut t = *from;
            t[j] = v;
            let mut spec = restarted(&best.spec, &t);
            spec.status[j] = Status::Fixed(v);
            let Some(held) = Fitted::fitted(fit_data, spec, &opts) else {
                continue;
            };
            let spec = restarted(&best.spec, &held.fit.theta);
            let Some(freed) = Fitted::fitted(fit_data, spec, &opts) else {
                continue;
            };
            let mut freed = continue_unfinished(setup, freed, fit_data)?;
            freed.fit.inactive = best.fit.inactive.clone();
            if better(&freed, out.as_ref()) {
                out = Some(freed);
            }
        }
    }
    let Some(f) = out else {
        return Ok(None);
    };
    let f = pull_late_folds(setup, f, fit_data)?;
    Ok(Some(keep_folds_off_steps(f, fit_data)?))
}

/// `alt`, a fit on every point, replaces the standing fit when it fits its
/// noise and the standing fit does not (never the other way round), or,
/// alike, when its objective is lower as `lower` asks ([`lower_enough`]);
/// the terms the standing fit found
/// inactive that `alt` still lacks stay named. Returns whether it replaced
/// the standing fit.
fn adopt_if_better(
    (best, curves, adequacy): (&mut Fitted, &mut Vec<CurveReport>, &mut Adequacy),
    mut alt: Fitted,
    fit_data: &Dataset,
    lower: Lower,
) -> Result<bool, IdentifyError> {
    let judged = judge(fit_data, &alt);
    let kept = match (judged.1.adequate, adequacy.adequate) {
        (true, false) => true,
        (false, true) => false,
        _ => lower_enough(lower, fit_data, &alt, best)?,
    };
    if !kept {
        return Ok(false);
    }
    // terms `best` found inactive that `alt` still lacks stay named (at
    // `alt`'s value of their exponent)
    let index = |name: &str| PARAM_NAMES.iter().position(|n| *n == name);
    for i in &best.fit.inactive {
        let (Some(coef), Some(exp)) = (index(i.coefficient), index(i.exponent)) else {
            continue;
        };
        let named = alt
            .fit
            .inactive
            .iter()
            .any(|a| a.coefficient == i.coefficient);
        if alt.spec.status[coef] == Status::Absent && !named {
            alt.fit.inactive.push(Inactive {
                held_at: alt.fit.theta[exp],
                ..*i
            });
        }
    }
    adopt((best, curves, adequacy), alt, judged);
    Ok(true)
}

fn validate(plan: &FitPlan) -> Result<(), IdentifyError> {
    if !(plan.phase_weight.is_finite() && plan.phase_weight > 0.0) {
        return Err(IdentifyError::BadPhaseWeight(plan.phase_weight));
    }
    if let JumpChoice::Weight(w) = plan.jumps {
        if !(w.is_finite() && w >= 0.0) {
            return Err(IdentifyError::BadJumpWeight(w));
        }
    }
    if plan.grid.0 == 0 || plan.grid.1 == 0 {
        return Err(LandscapeError::EmptyGrid {
            n_rho: plan.grid.0,
            n_eta: plan.grid.1,
        }
        .into());
    }
    Ok(())
}

/// The structure before any data-driven choice, the phase mode and the
/// equation error's data.
fn prepare<'a>(data: &'a Dataset, plan: &'a FitPlan) -> Result<Setup<'a>, IdentifyError> {
    let spec0 = configure(plan, data, Sign::Hardening)?;
    let has_phase = data.curves.iter().all(|c| c.phases.is_some());
    let phase_mode = match plan.phase {
        PhaseChoice::Ignore => LandscapePhase::Ignore,
        PhaseChoice::Known(c) => LandscapePhase::Known(c),
        PhaseChoice::Auto if has_phase => LandscapePhase::Detect { delay: 0.0 },
        PhaseChoice::Auto => LandscapePhase::Ignore,
    };
    if let LandscapePhase::Known(_) = phase_mode {
        if let Some(c) = data.curves.iter().find(|c| c.phases.is_none()) {
            return Err(EquationErrorError::MissingPhase {
                level: c.level.clone(),
            }
            .into());
        }
    }
    let sub = subsample(data, plan.landscape_points);
    let prep = Prepared::new(&sub, spec0.scales)?;
    let stiff = spec0.status[BETA] != Status::Absent;
    let damp = spec0.status[KAPPA] != Status::Absent;
    let gain_fixed = match spec0.status[GAIN] {
        Status::Fixed(g) if plan.gain != GainChoice::Auto => Some(g),
        _ => None,
    };
    let integer = plan.exponents == ExponentChoice::Integer;
    let rho_axis = exponent_axis(
        spec0.status[RHO],
        spec0.bounds[RHO],
        plan.grid.0,
        integer,
        stiff,
    );
    let eta_axis = exponent_axis(
        spec0.status[ETA],
        spec0.bounds[ETA],
        plan.grid.1,
        integer,
        damp,
    );
    Ok(Setup {
        data,
        plan,
        spec0,
        phase_mode,
        prep,
        terms_free: Terms {
            stiffness: stiff,
            damping: damp,
            gain: gain_fixed,
        },
        rho_axis,
        eta_axis,
        integer,
    })
}

/// Stages 1–2: the landscape (gain free under [`GainChoice::Auto`],
/// falling back to gain = 1) and its best node.
fn explore(
    setup: &Setup,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Exploration, IdentifyError> {
    let step = || progress(IdentifyProgress::Step);
    let (rho_axis, eta_axis) = (setup.rho_axis, setup.eta_axis);
    progress(IdentifyProgress::Stage {
        name: "landscape",
        steps: eta_axis.n.max(1),
    });
    let cancel = setup.plan.lm.cancel;
    let land = match landscape_cancellable(
        &setup.prep,
        setup.terms_free,
        rho_axis,
        eta_axis,
        setup.phase_mode,
        &step,
        cancel,
    ) {
        Ok(l) => l,
        Err(LandscapeError::Interrupted(i)) => return Err(i.into()),
        Err(e) if setup.plan.gain == GainChoice::Auto => {
            held_landscape(setup, "landscape", progress).map_err(|e2| match e2 {
                LandscapeError::Interrupted(i) => i.into(),
                _ => IdentifyError::from(e),
            })?
        }
        Err(e) => return Err(e.into()),
    };
    let best_ee = best_node(&land)?;
    let phase_conv = best_ee.phase;
    Ok(Exploration {
        land,
        best_ee,
        phase_conv,
    })
}

/// The landscape with the gain held at 1 (stage `name` in the progress).
fn held_landscape(
    setup: &Setup,
    name: &'static str,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Landscape, LandscapeError> {
    let step = || progress(IdentifyProgress::Step);
    let (rho_axis, eta_axis) = (setup.rho_axis, setup.eta_axis);
    progress(IdentifyProgress::Stage {
        name,
        steps: eta_axis.n.max(1),
    });
    let t = Terms {
        gain: Some(1.0),
        ..setup.terms_free
    };
    let (phase, cancel) = (setup.phase_mode, setup.plan.lm.cancel);
    landscape_cancellable(&setup.prep, t, rho_axis, eta_axis, phase, &step, cancel)
}

/// The equation-error fit at the landscape's best node.
fn best_node(land: &Landscape) -> Result<EquationErrorFit, IdentifyError> {
    let (bi, bj) = land
        .best()
        .ok_or_else(|| IdentifyError::NoCandidate("empty landscape".into()))?;
    Ok(land.fit_at(bi, bj).expect("best node solved").clone())
}

/// The landscape with the gain held at 1 (`--fix gain=1`'s), read with
/// `ex`'s phase convention: the nodes of a held race when the screen's
/// free gain was far from 1 and its landscape's minima are those of that
/// gain (`stages`, the held escalation). `None` when that landscape cannot
/// be solved or is empty (the step is then an extra try, not a reason to
/// fail the fit); an interruption is returned.
fn explore_held(
    setup: &Setup,
    ex: &Exploration,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Option<Exploration>, IdentifyError> {
    let land = match held_landscape(setup, "landscape, gain held at 1", progress) {
        Ok(l) => l,
        Err(LandscapeError::Interrupted(i)) => return Err(i.into()),
        Err(_) => return Ok(None),
    };
    let Ok(best_ee) = best_node(&land) else {
        return Ok(None);
    };
    Ok(Some(Exploration {
        land,
        best_ee,
        phase_conv: ex.phase_conv,
    }))
}

/// The equation error at node `(ρ, η)` with the gain held at `g`.
fn solve_held_gain(
    setup: &Setup,
    ex: &Exploration,
    g: f64,
    rho: f64,
    eta: f64,
) -> Result<EquationErrorFit, EquationErrorError> {
    solve_held_gain_with(setup, ex.phase_conv, g, rho, eta)
}

/// [`solve_held_gain`] with the phases read with `conv` (the stages'
/// convention, or a landscape node's own).
fn solve_held_gain_with(
    setup: &Setup,
    conv: Option<PhaseConvention>,
    g: f64,
    rho: f64,
    eta: f64,
) -> Result<EquationErrorFit, EquationErrorError> {
    let terms = Terms {
        gain: Some(g),
        ..setup.terms_free
    };
    match setup.phase_mode {
        LandscapePhase::Ignore => solve_magnitude(&setup.prep, terms, rho, eta, None).map(|x| x.0),
        _ => solve_phase(
            &setup.prep,
            terms,
            rho,
            eta,
            conv,
            conv.map_or(0.0, |c| c.delay),
        ),
    }
}

/// The shift (rad) that turns the measured lags of the stages' data (read
/// with the convention `base`) into those read with a landscape node's own
/// detected convention `node`, when the output error's correction of the
/// offset ([`super::output_error::MAX_OFFSET_CORRECTION`] either side of
/// `base`'s) cannot reach it and the data have one forcing level; else 0,
/// and 0 whenever the convention was not detected (the user stated it) or
/// the two differ in sign or delay.
///
/// Each node's equation error detects the offset with its own exponents.
/// With one forcing level the complex gain that carries the offset is one
/// constant complex force, which trades with the damping and stiffness
/// laws: the offset can differ by tens of degrees between nodes, and the
/// best node's is then wrong for the others. Measured on blind sets of one
/// level up with phase (no true offset), each a flagged miss before: h016-mixed of
/// seed 2711270301 (ρ 5.29, η 2.17): the best node (ρ 5.5, η −0.55)
/// detected −47°, the node nearest the truth −5°; read with −47° every
/// candidate went elsewhere (gain freed to 4.96, 35.5× the truth's Eq 31
/// cost), with each node's own offset 0.997×. Likewise h003-mixed and
/// h052-mixed of 2711270213 (node shifts of 81° and 20°; 1094× → 0.94×,
/// 1.80× → 0.996×) and h013-mixed of 2711270232 (85°; 578× → 0.987×).
/// Several levels share one complex gain across forces, which pins it:
/// there the shift is not made (measured: on the six-level 24 °C beam, a
/// node 15.4° off won the race, and over the six rounding rolls of
/// docs/identification.md the fit ended at objectives 3.2e-5 to 6.1e-5
/// instead of 5.6e-6 to 4.0e-5, and took up to 4.7 s; no in-family
/// multi-level case of the suites or the blind runs moved).
fn node_phase_shift(
    setup: &Setup,
    base: Option<PhaseConvention>,
    node: Option<PhaseConvention>,
) -> f64 {
    if !matches!(setup.phase_mode, LandscapePhase::Detect { .. }) || setup.data.levels().len() != 1
    {
        return 0.0;
    }
    match (base, node) {
        (Some(b), Some(n)) if b.sign == n.sign && b.delay == n.delay => {
            // lag = s (ψ − c − Ωτ): read with c_n instead of c_b, every
            // lag grows by s (c_b − c_n)
            let shift = wrap(b.sign * (b.offset - n.offset));
            if shift.abs() > super::output_error::MAX_OFFSET_CORRECTION {
                shift
            } else {
                0.0
            }
        }
        _ => 0.0,
    }
}

/// `data` with every measured phase lag shifted by `shift` rad (borrowed
/// as it is when the shift is 0).
fn phases_shifted(data: &Dataset, shift: f64) -> std::borrow::Cow<'_, Dataset> {
    if shift == 0.0 {
        return std::borrow::Cow::Borrowed(data);
    }
    let mut out = data.clone();
    shift_phases(&mut out, shift);
    std::borrow::Cow::Owned(out)
}

/// Every measured phase lag of `data` shifted by `shift` rad.
fn shift_phases(data: &mut Dataset, shift: f64) {
    for c in &mut data.curves {
        if let Some(p) = &mut c.phases {
            for v in p.iter_mut() {
                *v = wrap(*v + shift);
            }
        }
    }
}

/// The phase shift of `f` ([`Fitted::phase_shift`]) made the stages':
/// their data (`datas`) shifted by it and their convention `conv` changed
/// to match ([`reread_phases`]), so that `f`'s data are theirs (its shift
/// then 0).
fn adopt_phase_shift(f: &mut Fitted, conv: &mut Option<PhaseConvention>, datas: [&mut Dataset; 2]) {
    let shift = std::mem::take(&mut f.phase_shift);
    if shift != 0.0 {
        reread_phases(datas, conv.as_mut(), shift);
    }
}

/// Every measured phase lag of `datas` shifted by `shift` rad, and the
/// convention they were read with changed to match.
fn reread_phases(datas: [&mut Dataset; 2], conv: Option<&mut PhaseConvention>, shift: f64) {
    for d in datas {
        shift_phases(d, shift);
    }
    if let Some(c) = conv {
        // lag = s (ψ − c − Ωτ): adding `shift` to every lag is c → c − s·shift
        c.offset = wrap(c.offset - c.sign * shift);
    }
}

/// Stage 3: the provisional gain status (the screen of the equation
/// error; stage 5 decides under [`GainChoice::Auto`]).
fn screen_gain(setup: &Setup, ex: &Exploration) -> (Option<GainTest>, Status) {
    match setup.plan.gain {
        GainChoice::Fixed(g) => (None, Status::Fixed(g)),
        GainChoice::Free => (None, Status::Free),
        GainChoice::Auto => {
            let land = &ex.land;
            let (bi, bj) = land.best().expect("best node");
            let (rho, eta) = (land.rho[bi], land.eta[bj]);
            let fixed = solve_held_gain(setup, ex, 1.0, rho, eta);
            let free_gain = ex.best_ee.theta[GAIN];
            let (lo, hi) = setup.spec0.bounds[GAIN];
            let dof = ex
                .best_ee
                .n_residuals
                .saturating_sub(ex.best_ee.n_unknowns)
                .max(1) as f64;
            let f = match (&fixed, land.fit_at(bi, bj)) {
                (Ok(fx), Some(fr)) if fr.n_unknowns > fx.n_unknowns => {
                    (fx.cost - fr.cost) / (fr.cost / dof).max(f64::MIN_POSITIVE)
                }
                _ => 0.0,
            };
            let freed = f > GAIN_F_THRESHOLD && free_gain > lo && free_gain < hi;
            (
                Some(GainTest {
                    gain: free_gain,
                    f_statistic: f,
                    freed,
                    output_error: None,
                }),
                if freed {
                    Status::Free
                } else {
                    Status::Fixed(1.0)
                },
            )
        }
    }
}

/// The data as fitted: phases converted to displacement lags with the
/// detected convention (dropped when phase is not used), relative weights.
fn data_as_fitted(setup: &Setup, ex: &Exploration) -> Dataset {
    let mut fit_data = setup.data.clone();
    let use_phase = !matches!(setup.phase_mode, LandscapePhase::Ignore);
    for c in &mut fit_data.curves {
        match (&mut c.phases, use_phase, ex.phase_conv) {
            (Some(p), true, Some(conv)) => {
                for (k, v) in p.iter_mut().enumerate() {
                    *v = wrap(conv.lag(*v, c.omegas[k]));
                }
            }
            _ => c.phases = None,
        }
    }
    if setup.plan.weighting == Weighting::Relative {
        relative_weights(&mut fit_data);
    }
    fit_data
}

/// The output-error structure of a candidate: the plan's spec for `sign`,
/// the gain status, the measured-branch objective with the plan's reading
/// and jump weight, the softening bound, the start from `ee`.
fn candidate_spec(
    setup: &Setup,
    data: &Dataset,
    ee: &EquationErrorFit,
    sign: Sign,
    gain_status: Status,
) -> Result<FitSpec, IdentifyError> {
    let plan = setup.plan;
    let mut spec = setup.configure(sign)?;
    spec.status[GAIN] = gain_status;
    if let Status::Fixed(g) = gain_status {
        spec.start[GAIN] = g;
    }
    let use_phase = !matches!(setup.phase_mode, LandscapePhase::Ignore);
    spec.phase_weight = use_phase.then_some(plan.phase_weight);
    spec.branch = ResponseBranch::Measured;
    spec.jump_weight = plan.jumps.weight();
    // a detected phase convention's offset is refined by the output error
    spec.profile_phase_offset =
        use_phase && matches!(setup.phase_mode, LandscapePhase::Detect { .. });
    spec.censored = vec![plan.reading == ReadingChoice::Censored; data.curves.len()];
    // Softening: `|β_ref| < α` keeps the backbone frequency real at A_ref.
    // The default bound `0.95 α₀` uses the peak-based α₀, which strong
    // softening pulls below α (11 % on a synthetic case, whose truth the
    // bound then excluded); the candidate's equation-error α (inside α's
    // bounds) is the better estimate, so the bound is raised to 0.95 of it
    // when that is larger (not when the plan sets β's bounds).
    let user_beta_bounds = plan.bounds.iter().any(|(n, _, _)| n == "beta");
    if sign == Sign::Softening && spec.status[BETA] == Status::Free && !user_beta_bounds {
        let alpha = ee.theta[ALPHA].min(spec.bounds[ALPHA].1);
        spec.bounds[BETA].1 = spec.bounds[BETA].1.max(0.95 * alpha);
    }
    start_from(&mut spec, ee, setup.integer);
    Ok(spec)
}

/// The phase offset the output error profiled out of the measured phases
/// ([`FitSpec::profile_phase_offset`], phase convention detected) made part
/// of the data and of the reported convention: the measured lags are
/// shifted by it and the profiling turned off, so that the final fit, its
/// residuals and its convention describe the same data (the objective does
/// not change: the shift is the profiled constant).
fn bake_phase_offset(
    best: Fitted,
    fit_data: &mut Dataset,
    refine_data: &mut Dataset,
    conv: &mut PhaseConvention,
) -> Result<Fitted, IdentifyError> {
    let mut best = best;
    let Some(wp) = best
        .spec
        .phase_weight
        .filter(|_| best.spec.profile_phase_offset)
    else {
        return Ok(best);
    };
    let mut plain = best.spec.clone();
    plain.profile_phase_offset = false;
    let e = super::objective::evaluate_spec(fit_data, &plain, &best.fit.theta, false)
        .map_err(|e| IdentifyError::Fit(FitError::Solve(e)))?;
    // residual k (φ_model − ψ): the offset to add to every measured lag
    let delta = super::output_error::phase_offset(fit_data, &e.residuals, wp, &e.model);
    if delta.is_finite() {
        reread_phases([&mut *fit_data, &mut *refine_data], Some(&mut *conv), delta);
    }
    best.spec.profile_phase_offset = false;
    Ok(best)
}

/// A nonlinear coefficient whose start (from the equation error) is below
/// this fraction of the default start of [`FitSpec::new`] has vanished.
const VANISHED_START: f64 = 1e-3;

/// Revives the nonlinear coefficients of `spec` whose start vanished: the
/// equation error, which the noise in its regressors biases, often puts a
/// weak term at zero, and from there the output error cannot grow it (its
/// derivative, and its exponent's, vanish with it: measured on a blind
/// mixed case whose damping exponent of 0.38 was never found, 2.2× the
/// truth's cost). Their reference values are set to the data-derived
/// defaults (`β_ref = Ω_peak,high² − α₀`, `κ_ref = δ₀/2`). Returns whether
/// any was revived.
fn revive_coefficients(spec: &mut FitSpec) -> bool {
    use crate::power_law::g_unchecked;
    let sc = spec.scales;
    let mut revived = false;
    for (coef, exp) in [(BETA, RHO), (KAPPA, ETA)] {
        if spec.status[coef] != Status::Free {
            continue;
        }
        let e = spec.start[exp];
        let base = if coef == BETA {
            sc.a_ref
        } else {
            sc.omega_ref * sc.a_ref
        };
        let scale = g_unchecked(e) * base.powf(e);
        let reference = (spec.start[coef] * scale).abs();
        let default_ref = if coef == BETA {
            // |β_ref,0| of FitSpec::new: the peak shift (at least 0.01 α₀)
            spec.bounds[BETA].0 / 1e-6 * 0.01
        } else {
            // κ_ref,0 = δ₀/2, δ₀ = (lower bound of δ)/1e-4
            0.5 * spec.bounds[DELTA].0 / 1e-4
        };
        if reference < VANISHED_START * default_ref {
            let sign = if coef == BETA {
                spec.stiffness_sign.factor()
            } else {
                1.0
            };
            spec.start[coef] = sign * default_ref / scale;
            revived = true;
        }
    }
    revived
}

/// LM options limited to `iterations`, one start.
fn limited(lm: &LmOptions, seed: u64, iterations: usize) -> FitOptions {
    let mut o = FitOptions {
        starts: 1,
        seed,
        lm: *lm,
    };
    o.lm.max_iterations = o.lm.max_iterations.min(iterations);
    o
}

/// `spec` started at θ of `fit`.
fn restarted(spec: &FitSpec, theta: &super::Parameters) -> FitSpec {
    let mut s = spec.clone();
    for j in s.free_indices() {
        s.start[j] = theta[j];
    }
    s
}

type Raced = (
    Vec<Candidate>,
    Fitted,
    Vec<SignTrial>,
    Vec<(usize, usize, Sign)>,
);

/// Stage 4: the candidates race on `refine_data`; the winner continues
/// if its iteration limit stopped it.
#[allow(clippy::too_many_arguments)]
fn race(
    setup: &Setup,
    ex: &Exploration,
    refine_data: &Dataset,
    nodes: &[(usize, usize)],
    gain_status: Status,
    signs: &(dyn Fn(&EquationErrorFit) -> Vec<Sign> + Sync),
    exclude: &[(usize, usize, Sign)],
    continue_winner: bool,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Raced, IdentifyError> {
    use rayon::prelude::*;
    let plan = setup.plan;
    let step = || progress(IdentifyProgress::Step);
    let land = &ex.land;
    // The landscape's nodes were solved with the gain free. When the gain
    // test held it (at 1, or the plan fixed it), each candidate's equation
    // error is solved again with that gain before it seeds the output
    // error: without phase, δ, κ and the gain trade along a ridge, and a
    // free-gain start (e.g. gain 43 with δ = 0) is far from the held-gain
    // optimum (measured on a synthetic softening case: the output error
    // from the free-gain start ended at ρ = 0 with α 79 % off).
    // A node whose own detected phase offset the output error cannot reach
    // from the stages' reads the phases with it (`node_phase_shift`): its
    // equation error (with the gain held) and its fit see the data shifted.
    // (`shift`: the node's, from `node_phase_shift`)
    let with_gain_decided = |i: usize, j: usize, ee: &EquationErrorFit, shift: f64| {
        let conv = if shift != 0.0 {
            ee.phase
        } else {
            ex.phase_conv
        };
        match gain_status {
            Status::Fixed(g) if (ee.theta[GAIN] - g).abs() > 1e-9 * g.abs() => {
                solve_held_gain_with(setup, conv, g, land.rho[i], land.eta[j])
                    .unwrap_or_else(|_| ee.clone())
            }
            _ => ee.clone(),
        }
    };
    // each job: node, its equation error, sign, and whether its vanished
    // nonlinear coefficients are revived (first race, best node only)
    let first_node = nodes.first().copied().unwrap_or((usize::MAX, usize::MAX));
    let jobs: Vec<(usize, usize, EquationErrorFit, Sign, bool, f64)> = nodes
        .iter()
        .filter_map(|&(i, j)| {
            land.fit_at(i, j).map(|ee| {
                let shift = node_phase_shift(setup, ex.phase_conv, ee.phase);
                (i, j, with_gain_decided(i, j, ee, shift), shift)
            })
        })
        .flat_map(|(i, j, ee, shift)| {
            signs(&ee)
                .into_iter()
                .filter(|&s| !exclude.contains(&(i, j, s)))
                .flat_map(move |s| {
                    // (the best node only: revived starts are a second look,
                    // not a search)
                    let revive = exclude.is_empty() && (i, j) == first_node;
                    [
                        (i, j, ee.clone(), s, false, shift),
                        (i, j, ee.clone(), s, true, shift),
                    ]
                    .into_iter()
                    .take(if revive { 2 } else { 1 })
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let mut raced: Vec<(usize, usize, Sign)> =
        jobs.iter().map(|(i, j, _, s, _, _)| (*i, *j, *s)).collect();
    raced.dedup();
    // each candidate with the plan's global-search starts (`FitPlan::starts`:
    // its own start and `starts − 1` Latin-hypercube ones; one step each)
    let mut opts = limited(&plan.lm, plan.seed, RACE_ITERATIONS);
    opts.starts = plan.starts.max(1);
    progress(IdentifyProgress::Stage {
        name: "output error",
        steps: jobs.len() * opts.starts,
    });
    let outcomes: Vec<Result<Option<(Candidate, Option<Fitted>)>, IdentifyError>> = jobs
        .into_par_iter()
        .map(|(i, j, ee, sign, revive, shift)| {
            let mut spec = candidate_spec(setup, refine_data, &ee, sign, gain_status)?;
            if revive && !revive_coefficients(&mut spec) {
                // nothing vanished: the plain job covers this node
                return Ok(None);
            }
            let data = phases_shifted(refine_data, shift);
            let res = fit_impl(&data, &spec, &opts, None, &step);
            let oe = match &res {
                Ok(r) => Ok(r.minima.first().map_or(r.cost, |m| m.cost)),
                Err(e) => Err(e.to_string()),
            };
            let cand = Candidate {
                rho: land.rho[i],
                eta: land.eta[j],
                ee_cost: land.at(i, j),
                sign,
                oe,
                gain: match gain_status {
                    Status::Fixed(g) => Some(g),
                    _ => None,
                },
            };
            let kept = res
                .ok()
                .map(|r| Fitted::from_result(r, spec).read_shifted(shift));
            Ok(Some((cand, kept)))
        })
        .collect();
    let mut candidates = Vec::new();
    let mut finalists: Vec<Fitted> = Vec::new();
    let mut last_err = String::new();
    let mut trials: Vec<SignTrial> = Vec::new();
    for o in outcomes {
        let Some((cand, kept)) = o? else {
            continue;
        };
        if let Err(e) = &cand.oe {
            last_err = e.clone();
        }
        if plan.sign == SignChoice::Both {
            note_sign_trial(&mut trials, cand.sign, cand.oe.clone());
        }
        candidates.push(cand);
        if let Some(f) = kept {
            finalists.push(f);
        }
    }
    if finalists.is_empty() {
        return Err(IdentifyError::NoCandidate(last_err));
    }
    // The race's limit stops slow candidates that would end lower than a
    // fast one (measured on a blind in-family set: the winner after 30
    // iterations ended at 5x the truth's cost, a candidate 10x above it at
    // that point reached below the truth with more). Every candidate the
    // limit stopped within CONTINUE_FACTOR of the best objective (at most
    // CONTINUE_CANDIDATES, best first) continues from where it stopped
    // (for up to `2 × lm.max_iterations − RACE_ITERATIONS` more, the
    // budget of a candidate and its continuation).
    let lead = finalists
        .iter()
        .map(|f| f.objective)
        .fold(f64::INFINITY, f64::min);
    let mut order: Vec<usize> = (0..finalists.len()).collect();
    order.sort_by(|&a, &b| finalists[a].objective.total_cmp(&finalists[b].objective));
    let stopped: Vec<usize> = order
        .into_iter()
        .filter(|&k| {
            let f = &finalists[k];
            !f.fit.converged
                && (f.fit.termination == Termination::MaxIterations || f.fit.at_bounds.is_empty())
                && f.objective <= CONTINUE_FACTOR * lead
        })
        .take(CONTINUE_CANDIDATES)
        .collect();
    if continue_winner && !stopped.is_empty() {
        let raced = plan.lm.max_iterations.min(RACE_ITERATIONS);
        let more = 2 * plan.lm.max_iterations - raced;
        progress(IdentifyProgress::Stage {
            name: "output error, best candidates continued",
            steps: stopped.len(),
        });
        let continued: Vec<Option<Fitted>> = stopped
            .par_iter()
            .map(|&k| {
                let spec2 = restarted(&finalists[k].spec, &finalists[k].fit.theta);
                let shift = finalists[k].phase_shift;
                fit_impl(
                    &phases_shifted(refine_data, shift),
                    &spec2,
                    &limited(&plan.lm, plan.seed, more),
                    None,
                    &step,
                )
                .ok()
                .map(|r| Fitted::from_result(r, spec2).read_shifted(shift))
            })
            .collect();
        for (&k, c) in stopped.iter().zip(continued) {
            if let Some(c) = c.filter(|c| c.objective <= finalists[k].objective) {
                finalists[k] = c;
            }
        }
    }
    // A candidate far above the lead may be the right basin with a fold on
    // the wrong side of a measured step, where no gradient crosses: its
    // folds are relocated ([`relocate_folds`]) and it is kept so when that
    // lowers its objective.
    let lead = finalists
        .iter()
        .map(|f| f.objective)
        .fold(f64::INFINITY, f64::min);
    let full = refine_data.len() >= setup.data.len();
    let relocated: Vec<Option<Fitted>> = finalists
        .par_iter()
        .map(|f| {
            // on a subsample the measured steps are coarser than the data's:
            // a fold placed in one of them is not placed in the data's (the
            // stages on every point relocate folds there)
            (full && f.objective > RELOCATE_FACTOR * lead)
                .then(|| {
                    let data = phases_shifted(refine_data, f.phase_shift);
                    relocate_folds(setup, f.clone(), &data, RACE_ITERATIONS, true).ok()
                })
                .flatten()
                .filter(|g| g.objective < f.objective)
                .map(|g| g.read_shifted(f.phase_shift))
        })
        .collect();
    for (f, r) in finalists.iter_mut().zip(relocated) {
        if let Some(r) = r {
            *f = r;
        }
    }
    let mut best: Option<Fitted> = None;
    for f in finalists {
        if better(&f, best.as_ref()) {
            best = Some(f);
        }
    }
    let best = best.expect("a finalist");
    Ok((candidates, best, trials, raced))
}

/// The lower objective wins; a converged fit wins a near tie.
fn better(f: &Fitted, best: Option<&Fitted>) -> bool {
    match best {
        None => true,
        Some(b) => {
            let tie = (f.objective - b.objective).abs()
                <= 1e-6 * b.objective.abs().max(f.objective.abs());
            if tie {
                f.fit.converged && !b.fit.converged
            } else {
                f.objective < b.objective
            }
        }
    }
}

fn note_sign_trial(trials: &mut Vec<SignTrial>, sign: Sign, cost: Result<f64, String>) {
    match trials.iter_mut().find(|t| t.sign == sign) {
        Some(t) => {
            if let Ok(c) = cost {
                t.cost = match &t.cost {
                    Ok(old) => Ok(old.min(c)),
                    Err(_) => Ok(c),
                };
            }
        }
        None => trials.push(SignTrial { sign, cost }),
    }
}

fn merge_sign_trials(into: &mut Vec<SignTrial>, more: Vec<SignTrial>) {
    for t in more {
        note_sign_trial(into, t.sign, t.cost);
    }
}

/// Stages 5–9 on a race winner: the decisions (terms settled before the
/// gain and the readings are decided, so that those tests compare
/// converged fits), then every point, then the folds kept off the steps.
fn finish(
    setup: &Setup,
    winner: Fitted,
    fit_data: &Dataset,
    refine_data: &Dataset,
    gain_test: &mut Option<GainTest>,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Fitted, IdentifyError> {
    // the decisions on the race's data (a subsample of long data: the
    // tests need hundreds of points, not thousands), then every point
    progress(IdentifyProgress::Stage {
        name: "decisions",
        steps: 3,
    });
    let step = || progress(IdentifyProgress::Step);
    let raced = winner.clone();
    let mut best = settle_terms(setup, winner, refine_data)?;
    step();
    best = decide_gain(setup, best, refine_data, gain_test)?;
    step();
    // the refit of the gain can leave a term near a copy of the linear one
    // (a free gain trades with δ, and κ with both)
    best = settle_terms(setup, best, refine_data)?;
    step();
    best = refine_all_points(setup, best, fit_data, refine_data, progress)?;
    if !best.fit.converged {
        // the refinement on every point can end on a ridge where a term
        // has no effect (the race's data had not shown it): the terms are
        // settled again on the data of the result
        best = settle_terms(setup, best, fit_data_or_sub(fit_data, refine_data))?;
    }
    best = retest_removed_terms(setup, &raced, best, (fit_data, refine_data), progress)?;
    let work = fit_data_or_sub(fit_data, refine_data);
    best = pull_late_folds(setup, best, work)?;
    best = keep_folds_off_steps(best, work)?;
    // the pull can carry an exponent to the end of its range after the
    // terms were settled on the race's data (measured: a blind three-level
    // hardening set without nonlinear damping, up and down, whose pull
    // moved η from 7.9991 to the bound 8 with κ 1.2e-4, converged and
    // within the noise at 1.084x the truth's Eq 31 cost; the term removed
    // there, the rest refits to 0.988x)
    if [RHO, ETA]
        .into_iter()
        .any(|j| exponent_near_range_end(&best.spec, &best.fit.theta, j))
    {
        let settled = settle_terms(setup, best.clone(), work)?;
        if settled.fit.inactive.len() > best.fit.inactive.len() {
            best = keep_folds_off_steps(settled, work)?;
        }
    }
    judged_on_all(best, fit_data, refine_data)
}

/// A power-law term that stage 5 removed on the race's subsample
/// ([`settle_terms`]) is tested again on every point, where the result is
/// judged: refitted there with the term restored from the race's winner
/// (`raced`, the fit before the decisions), it is kept when the same test
/// as stage 5's, on every point, says the data need it ([`nested_statistic`]
/// above the χ² 5 % point). A subsample has fewer points to see a weak
/// term, and the refinement on every point moves the other parameters
/// without it (measured: blind h001-mixed of seed 2711280107, six levels
/// swept down, no phase, ρ 2.05, η 1.51: the race's winner at η 0.029,
/// κ 0.150 beside δ 0.079, was 29 % below its refit without the term on
/// the 906-point subsample, statistic 5.88 against the 5.99 of two degrees
/// of freedom; the term removed, every point refined to ρ 2.119 at 1.262×
/// the truth's Eq 31 cost, within the noise, unflagged; with η held at
/// 0.03 and κ free the same points refine to 0.963×). Only data refined
/// on every point after a subsampled race (`refine_all_points`): elsewhere
/// stage 5 decided on the data the result is judged on.
fn retest_removed_terms(
    setup: &Setup,
    raced: &Fitted,
    best: Fitted,
    (fit_data, refine_data): (&Dataset, &Dataset),
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Fitted, IdentifyError> {
    if !refined_on_every_point(fit_data, refine_data) {
        return Ok(best);
    }
    let plan = setup.plan;
    let mut best = best;
    for (coef, exp) in [(KAPPA, ETA), (BETA, RHO)] {
        // removed by the decisions: in the race's winner, absent now
        let was_fitted = raced.spec.status[coef] == Status::Free
            && raced.spec.status[exp] == Status::Free
            && raced.fit.theta[coef] != 0.0;
        if !(was_fitted && removed_term(setup, &best, coef, exp)) {
            continue;
        }
        // the result's decisions (gain, the other term, readings) with the
        // term free again, from the race's winner
        let mut spec = carry_readings(&best.spec, fit_data, refine_data);
        for j in [coef, exp] {
            spec.status[j] = Status::Free;
        }
        let spec = restarted(&spec, &raced.fit.theta);
        let opts = limited(&plan.lm, plan.seed, DECISION_ITERATIONS);
        let Some(sub) = Fitted::fitted(refine_data, spec, &opts) else {
            continue;
        };
        let sub = continue_unfinished(setup, sub, refine_data)?;
        let mut full = refine_all_points(setup, sub, fit_data, refine_data, progress)?;
        let rise = best.objective - full.objective;
        if !rise.is_finite() || rise <= 0.0 || full.spec.status[coef] != Status::Free {
            continue;
        }
        let tested: Vec<usize> = [coef, exp]
            .into_iter()
            .filter(|&j| full.spec.status[j] == Status::Free)
            .collect();
        let stat = nested_statistic(fit_data, &full, &tested, rise)?;
        if stat > chi2_95(tested.len()) {
            full.fit.inactive = best
                .fit
                .inactive
                .iter()
                .filter(|i| i.coefficient != PARAM_NAMES[coef])
                .cloned()
                .collect();
            best = full;
        }
    }
    Ok(best)
}

/// `alt` carried through the decisions and every point on the data as it
/// read them ([`Fitted::phase_shift`]) and kept as
/// [`finish_and_adopt_if_better`] decides; its reading of the phases then
/// becomes the stages' (`datas`: their data and convention).
fn finish_alternative(
    setup: &Setup,
    mut alt: Fitted,
    (fit_data, refine_data, conv): (&mut Dataset, &mut Dataset, &mut Option<PhaseConvention>),
    result: Standing<'_>,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<(), IdentifyError> {
    if alt.phase_shift == 0.0 {
        finish_and_adopt_if_better(
            setup,
            alt,
            (fit_data, refine_data),
            result,
            Lower::Any,
            progress,
        )?;
        return Ok(());
    }
    let (mut alt_fit, mut alt_refine, mut alt_conv) =
        (fit_data.clone(), refine_data.clone(), *conv);
    adopt_phase_shift(&mut alt, &mut alt_conv, [&mut alt_fit, &mut alt_refine]);
    let datas = (&alt_fit, &alt_refine);
    if finish_and_adopt_if_better(setup, alt, datas, result, Lower::Any, progress)? {
        (*fit_data, *refine_data, *conv) = (alt_fit, alt_refine, alt_conv);
    }
    Ok(())
}

/// How much lower an alternative's objective must be for
/// [`finish_and_adopt_if_better`] to keep it (both fits alike adequate or
/// not).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Lower {
    /// Any lower objective.
    Any,
    /// Lower by more than the noise explains ([`significantly_lower`]).
    Significantly,
}

/// Whether `alt` fits `data` better than `best` by more than the noise
/// explains: its `Σ z²` against `best`'s noise model ([`noise_scaled`]) is
/// lower by more than the χ²₁ 0.1 % point (10.83). Two optima of one model
/// within that of each other are one result to the resolution of the data
/// (on in-family data at most 10.83 of the truth's expected `Σ z²` of one
/// per point: 1.8 % of the cost at 600 points).
fn significantly_lower(data: &Dataset, alt: &Fitted, best: &Fitted) -> Result<bool, IdentifyError> {
    let (z_best, noise) = noise_scaled(data, best, None)?;
    let (z_alt, _) = noise_scaled(data, alt, Some(&noise))?;
    Ok(z_best - z_alt > chi2_999(1))
}

/// A lower objective than the standing fit's by at least this share is
/// kept under [`Lower::Significantly`] whatever the noise says
/// ([`lower_enough`]).
const MATERIAL_DROP: f64 = 0.01;

/// Whether `alt`'s objective on `data` is lower than `best`'s as `lower`
/// asks: any drop, or ([`Lower::Significantly`]) one the noise does not
/// explain ([`significantly_lower`]) or of at least [`MATERIAL_DROP`] of
/// the objective. The test keeps a fit from being replaced by a copy of
/// itself a rounding away (its notes lost with it); it must not keep a
/// fit above a lower optimum of its own objective, which is what the fit
/// reports: under noise proportional to the amplitude a lower optimum at
/// the resonance peaks, where the noise is largest, changes `Σ z²` little
/// (measured: blind h008-mixed of random seed 4120673301, five levels up
/// and down, no phase, 2000 points: with η held at 2.0 on every point and
/// then freed, the fit went 6.3 % below the standing fit's objective, to
/// 0.997x the truth's Eq 31 cost against the standing fit's 1.063x, and
/// lowered `Σ z²` by 9.2 only).
fn lower_enough(
    lower: Lower,
    data: &Dataset,
    alt: &Fitted,
    best: &Fitted,
) -> Result<bool, IdentifyError> {
    if alt.objective >= best.objective {
        return Ok(false);
    }
    Ok(match lower {
        Lower::Any => true,
        Lower::Significantly => {
            alt.objective <= best.objective * (1.0 - MATERIAL_DROP)
                || significantly_lower(data, alt, best)?
        }
    })
}

/// `alt` (a lower objective found on the race's data, or the held-gain
/// race's winner) carried through the decisions and every point
/// (`finish`), with its own gain test; it replaces the result `(best,
/// curves, adequacy, gain_test)` ([`adopt`]) when it fits its noise and the
/// result does not, or, both fitting or both not, when its objective there
/// is lower (both read exactly, on every point). A lower objective that
/// does not fit its noise where the result does is not kept: with a fold
/// late by a fraction of a step the measured-branch objective can sit
/// below the truth's at many times its Eq 31 cost, and only the self-check
/// sees it (`late_folds`). Returns whether it replaced the result.
fn finish_and_adopt_if_better(
    setup: &Setup,
    alt: Fitted,
    (fit_data, refine_data): (&Dataset, &Dataset),
    (best, curves, adequacy, gain_test): Standing<'_>,
    lower: Lower,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<bool, IdentifyError> {
    let mut alt_gain = *gain_test;
    let alt = finish(setup, alt, fit_data, refine_data, &mut alt_gain, progress)?;
    let kept = adopt_if_better((best, curves, adequacy), alt, fit_data, lower)?;
    if kept {
        *gain_test = alt_gain;
    }
    Ok(kept)
}

/// `alt`, with its judgement (`judge`), replaces the result `(best,
/// curves, adequacy)`; the escalation tried so far stays listed.
fn adopt(
    (best, curves, adequacy): (&mut Fitted, &mut Vec<CurveReport>, &mut Adequacy),
    alt: Fitted,
    (alt_curves, mut alt_adequacy): (Vec<CurveReport>, Adequacy),
) {
    alt_adequacy.escalation = std::mem::take(&mut adequacy.escalation);
    *best = alt;
    *curves = alt_curves;
    *adequacy = alt_adequacy;
}

/// `alt` (a fit with some curves read as censored) read exactly at its θ
/// when that fits the noise, with its judgement: the censored reading was
/// then only the search's way to the optimum, and no sweep needs an early
/// departure (measured: a blind three-level hardening set, κ held at 0,
/// whose exact fit stuck 69.9x the noise with one fold off; censoring
/// that curve reached 0.987x the truth's Eq 31 cost, where the exact
/// reading fits too). Otherwise (or when the exact reading costs more than
/// `exact_before`, the exact fit it would replace) `alt` as it was.
fn read_exactly_if_it_fits(
    alt: Fitted,
    data: &Dataset,
    exact_before: f64,
) -> Result<(Fitted, (Vec<CurveReport>, Adequacy)), IdentifyError> {
    let judged = judge(data, &alt);
    if !judged.1.adequate {
        return Ok((alt, judged));
    }
    let mut spec = alt.spec.clone();
    spec.censored = vec![false; data.curves.len()];
    let exact = Fitted::assessed(data, spec, alt.fit.theta, &alt.fit)?;
    if exact.objective > exact_before {
        return Ok((alt, judged));
    }
    let exact_judged = judge(data, &exact);
    if exact_judged.1.adequate {
        let mut exact = exact;
        exact.fit.inactive = alt.fit.inactive.clone();
        return Ok((exact, exact_judged));
    }
    Ok((alt, judged))
}

/// The data the last stages run on: every point, or the subsample of data
/// longer than [`POLISH_MAX_POINTS`].
fn fit_data_or_sub<'a>(fit_data: &'a Dataset, refine_data: &'a Dataset) -> &'a Dataset {
    if fit_data.len() <= POLISH_MAX_POINTS {
        fit_data
    } else {
        refine_data
    }
}

/// `best` (fitted on [`fit_data_or_sub`]) judged on every point.
fn judged_on_all(
    mut best: Fitted,
    fit_data: &Dataset,
    refine_data: &Dataset,
) -> Result<Fitted, IdentifyError> {
    let work = fit_data_or_sub(fit_data, refine_data);
    if work.len() < fit_data.len() {
        let theta = best.fit.theta;
        let (t, it, minima) = (
            best.fit.termination,
            best.fit.iterations,
            best.fit.minima.clone(),
        );
        let inactive = best.fit.inactive.clone();
        best.spec = carry_readings(&best.spec, work, fit_data);
        best.fit = super::assess(fit_data, &best.spec, theta, t, it, minima)?;
        best.fit.inactive = inactive;
        best.objective = best.fit.objective + best.fit.phase_cost.unwrap_or(0.0);
    }
    Ok(best)
}

/// `f`'s structure and θ refitted on `data` (a few LM iterations: its
/// objective there, for comparisons on one data set).
fn refit_on(setup: &Setup, f: Fitted, data: &Dataset) -> Result<Fitted, IdentifyError> {
    let plan = setup.plan;
    let spec = restarted(&f.spec, &f.fit.theta);
    let inactive = f.fit.inactive.clone();
    match Fitted::fitted(
        data,
        spec,
        &limited(&plan.lm, plan.seed, DECISION_ITERATIONS),
    ) {
        Some(mut out) => {
            out.fit.inactive = inactive;
            Ok(out)
        }
        None => Ok(f),
    }
}

/// `spec` with its per-curve jump readings carried from the curves of
/// `from` to those of `to` (matched by level and direction; a subsample
/// may keep fewer curves).
fn carry_readings(spec: &FitSpec, from: &Dataset, to: &Dataset) -> FitSpec {
    let mut s = spec.clone();
    s.censored = to
        .curves
        .iter()
        .map(|c| {
            from.curves
                .iter()
                .position(|f| f.level == c.level && f.direction == c.direction)
                .and_then(|k| spec.censored.get(k).copied())
                .unwrap_or(spec.censored.first().copied().unwrap_or(false))
        })
        .collect();
    s
}

/// Whether [`refine_all_points`] refines on every point: the race ran on
/// a subsample, and every point is at most [`POLISH_MAX_POINTS`].
fn refined_on_every_point(fit_data: &Dataset, refine_data: &Dataset) -> bool {
    refine_data.len() < fit_data.len() && fit_data.len() <= POLISH_MAX_POINTS
}

/// Stage 5: the winner of a subsampled race refined on every point (data
/// of at most [`POLISH_MAX_POINTS`]; kept when that converges, else the
/// subsample's optimum is judged on every point).
fn refine_all_points(
    setup: &Setup,
    winner: Fitted,
    fit_data: &Dataset,
    refine_data: &Dataset,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Fitted, IdentifyError> {
    if !refined_on_every_point(fit_data, refine_data) {
        // nothing to refine, or too many points: the decisions ran on the
        // data the result is judged on (every point, or the subsample, then
        // judged on every point at the end); a decision's refit that its
        // iteration limit stopped is continued there
        let work = fit_data_or_sub(fit_data, refine_data);
        return continue_unfinished(setup, winner, work);
    }
    progress(IdentifyProgress::Stage {
        name: "output error on all points",
        steps: 1,
    });
    let plan = setup.plan;
    let spec_all = carry_readings(
        &restarted(&winner.spec, &winner.fit.theta),
        refine_data,
        fit_data,
    );
    let mut single = limited(&plan.lm, plan.seed, POLISH_ITERATIONS);
    single.lm.ftol = single.lm.ftol.max(POLISH_FTOL);
    // the subsample's optimum judged on every point, and refined there;
    // the lower objective is kept
    let f = &winner.fit;
    let mut out = Fitted::assessed(fit_data, spec_all.clone(), f.theta, f)?;
    out.fit.inactive = winner.fit.inactive.clone();
    if let Some(polished) = Fitted::fitted(fit_data, spec_all, &single) {
        let mut polished = continue_unfinished(setup, polished, fit_data)?;
        polished.fit.inactive = winner.fit.inactive.clone();
        if polished.objective <= out.objective {
            out = polished;
        }
    }
    // a fold that sat inside a step of the subsample can sit a full step
    // early on every point, where no gradient reaches it
    if let Some(r) = reassign_jumps(setup, &out, fit_data, POLISH_ITERATIONS)? {
        if r.objective < out.objective {
            // the refit from the moved folds is continued as the polish
            // was (measured: blind h032-mixed of seed 3339137987, six
            // levels up and down, gain free: the move lowered the
            // objective 24.5x in one round of 25 iterations, which ended at
            // its limit, "did not converge (max-iterations)", while three
            // more iterations converged)
            let mut r = continue_unfinished(setup, r, fit_data)?;
            r.fit.inactive = out.fit.inactive.clone();
            out = r;
        }
    }
    progress(IdentifyProgress::Step);
    Ok(out)
}

/// `f` continued on `data` while its last fit ended at its iteration limit
/// (at most [`polish_rounds`] − 1 more rounds of [`POLISH_ITERATIONS`]): a
/// fit still moving when its budget ran out (a crawl along a ridge, a
/// decision's refit) does not end as "not converged" at a point that is
/// still improving. The lower objective is kept.
fn continue_unfinished(setup: &Setup, f: Fitted, data: &Dataset) -> Result<Fitted, IdentifyError> {
    let plan = setup.plan;
    let mut single = limited(&plan.lm, plan.seed, POLISH_ITERATIONS);
    single.lm.ftol = single.lm.ftol.max(POLISH_FTOL);
    // (a plan whose iteration limit is below one round asked for an early
    // stop: it keeps the base rounds)
    let rounds = if plan.lm.max_iterations >= POLISH_ITERATIONS {
        polish_rounds(data.len())
    } else {
        POLISH_ROUNDS
    };
    let mut f = more_rounds(f, data, &single, rounds);
    if f.fit.termination == Termination::MaxIterations && !f.fit.natural.is_empty() {
        f = hold_natural_bounds(f, data, &single, rounds)?;
    }
    Ok(f)
}

/// `f` refitted from where it stopped while its fit ends at its iteration
/// limit, `f` counting as the first of at most `rounds` fits of `opts`; a
/// round that fails or raises the objective ends it. The terms `f` had
/// found inactive stay so.
fn more_rounds(f: Fitted, data: &Dataset, opts: &FitOptions, rounds: usize) -> Fitted {
    let inactive = f.fit.inactive.clone();
    let mut f = f;
    for _ in 1..rounds {
        if f.fit.termination != Termination::MaxIterations {
            break;
        }
        let spec = restarted(&f.spec, &f.fit.theta);
        match Fitted::fitted(data, spec, opts) {
            Some(next) if next.objective <= f.objective => {
                f = next;
                f.fit.inactive = inactive.clone();
            }
            _ => break,
        }
    }
    f
}

/// `f`, still moving at its iteration limit with parameters at natural
/// bounds (η = −1, δ = 0: [`super::flags::natural_meaning`]), refitted with
/// those held where they are, and assessed with them free again at the
/// result (the held fit's termination; kept when its objective is not
/// higher). The bound-constrained steps crawl: measured on a blind
/// two-level up-sweep with Coulomb friction (η = −1), twelve rounds of 25
/// iterations lowered the objective from 1.4164e-8 to 1.3449e-8 along ρ
/// and β and ended "did not converge (max-iterations)" at 0.89x the
/// truth's Eq 31 cost; with η held the rest converges (small-decrement) at
/// 1.3399e-8. A free parameter at its bound whose refit could leave it
/// would have left it in those rounds.
fn hold_natural_bounds(
    f: Fitted,
    data: &Dataset,
    opts: &FitOptions,
    rounds: usize,
) -> Result<Fitted, IdentifyError> {
    let mut held = restarted(&f.spec, &f.fit.theta);
    for n in &f.fit.natural {
        if let Some(j) = PARAM_NAMES.iter().position(|&p| p == n.name) {
            held.status[j] = Status::Fixed(f.fit.theta[j]);
        }
    }
    // (the same budget of rounds as the free continuation)
    let Some(h) = Fitted::fitted(data, held, opts) else {
        return Ok(f);
    };
    let h = more_rounds(h, data, opts, rounds);
    if h.objective > f.objective || h.fit.termination == Termination::MaxIterations {
        return Ok(f);
    }
    let spec = restarted(&f.spec, &h.fit.theta);
    let mut out = Fitted::assessed(data, spec, h.fit.theta, &h.fit)?;
    out.fit.inactive = f.fit.inactive.clone();
    Ok(out)
}

/// Stage 5 ([`GainChoice::Auto`]): the output error decides the gain, by
/// the drop of its objective when the gain is freed, scaled by the noise
/// ([`nested_statistic`]: a χ²₁ variable when the gain is 1; freed above
/// its 0.1 % point).
fn decide_gain(
    setup: &Setup,
    best: Fitted,
    work: &Dataset,
    gain_test: &mut Option<GainTest>,
) -> Result<Fitted, IdentifyError> {
    let Some(test) = gain_test.as_mut() else {
        return Ok(best);
    };
    let plan = setup.plan;
    // (the terms settled before stay named, whichever fit is kept)
    let inactive = best.fit.inactive.clone();
    let held_now = best.spec.status[GAIN] != Status::Free;
    let mut alt = restarted(&best.spec, &best.fit.theta);
    if held_now {
        alt.status[GAIN] = Status::Free;
        alt.start[GAIN] = 1.0;
    } else {
        alt.status[GAIN] = Status::Fixed(1.0);
        alt.start[GAIN] = 1.0;
    }
    let opts = limited(&plan.lm, plan.seed, DECISION_ITERATIONS);
    let Some(alt) = Fitted::fitted(work, alt, &opts) else {
        return Ok(best);
    };
    let (held, mut free) = if held_now { (best, alt) } else { (alt, best) };
    // the free gain includes the held one: a free fit above the held one
    // did not reach its optimum, and is continued from the held one
    if free.objective > held.objective {
        let mut spec = restarted(&free.spec, &held.fit.theta);
        spec.start[GAIN] = 1.0;
        if let Some(f2) = Fitted::fitted(work, spec, &opts) {
            if f2.objective < free.objective {
                free = f2;
            }
        }
    }
    let drop = (held.objective - free.objective).max(0.0);
    let f = nested_statistic(work, &free, &[GAIN], drop)?;
    let gain = free.fit.theta[GAIN];
    let at_bound = free.fit.at_bounds.contains(&"gain");
    // a free gain at its bound that still lowers the objective significantly
    // is kept, and reported at its bound: holding it at 1 would hide a
    // misfit the data demonstrate
    let freed = f > GAIN_F_THRESHOLD;
    test.output_error = Some(OutputErrorGainTest {
        held: held.objective,
        free: free.objective,
        gain,
        f_statistic: f,
        at_bound,
    });
    test.freed = freed;
    let mut out = if freed { free } else { held };
    out.fit.inactive = inactive;
    Ok(out)
}

/// The measured-branch evaluation of `f` on `data` (objective units) and
/// what each curve's comparison found.
fn comparison(data: &Dataset, f: &Fitted) -> Result<(Evaluation, Vec<CurveMatch>), IdentifyError> {
    evaluate_measured(data, &f.fit.theta, false, &MatchOptions::of(&f.spec))
        .map_err(|e| IdentifyError::Fit(FitError::Solve(e)))
}

/// `Σ z²` of `f` on `data` ([`super::noise`]): its residuals (and jump
/// penalties) against the local noise `noise`, or against their own noise
/// when `None`; the noise model used is returned. Two fits are compared
/// against one noise model, that of the larger one: a χ² difference that
/// holds where the noise is not of one size along a curve (proportional
/// noise: the residual variance a term can absorb at the resonance peaks
/// is many times the average one, which made an F test on the raw
/// objective keep near-copies of the linear terms).
fn noise_scaled(
    data: &Dataset,
    f: &Fitted,
    noise: Option<&NoiseModel>,
) -> Result<(f64, NoiseModel), IdentifyError> {
    let (e, m) = comparison(data, f)?;
    let wp = f.spec.phase_weight.is_some();
    let nm = match noise {
        Some(n) => n.clone(),
        None => noise_model(data, &e.residuals, wp),
    };
    let pens: Vec<Vec<f64>> = m.into_iter().map(|c| c.penalties).collect();
    let z = z2_per_curve(data, &e.residuals, wp, &pens, &nm);
    Ok((z.iter().map(|x| x.0).sum(), nm))
}

/// The statistic of a nested comparison: the objective drops by
/// `delta_objective` when the parameters `tested` are freed, `larger` being
/// the fit with them free. Under the smaller model, with noise of local
/// standard deviation `σ_i` (estimated from `larger`'s residuals,
/// [`super::noise`]), the drop is `εᵀ Q (QᵀQ)⁻¹ Qᵀ ε` (`Q` the tested
/// columns of the Jacobian with the other columns projected out), of mean
/// `E = tr((QᵀQ)⁻¹ Qᵀ Σ Q)`, `Σ = diag(σ_i²)`; the statistic
/// `k · drop / E` is χ²_k for Gaussian noise whatever its size along the
/// curves. (The objective weighs every amplitude alike, Eq 31, while the
/// noise grows with the amplitude: an F test with one residual variance,
/// or a difference of noise-scaled costs, disagreed with the objective
/// the fits minimise — a free gain was "significant" on a fit whose held
/// gain had the lower objective.)
fn nested_statistic(
    work: &Dataset,
    larger: &Fitted,
    tested: &[usize],
    delta_objective: f64,
) -> Result<f64, IdentifyError> {
    use super::levenberg_marquardt::LeastSquares;
    use super::objective::Problem;
    let problem = Problem::new(work, &larger.spec)?;
    let u = problem.u_of(&larger.fit.theta);
    let Some((r, j)) = problem.residuals_and_jacobian(&u) else {
        return Ok(f64::NAN);
    };
    let p = problem.free.len();
    let with_phase = larger.spec.phase_weight.is_some();
    let nm = noise_model(work, &r, with_phase);
    let sigma = nm.rows(work, with_phase);
    let rows = sigma.len().min(r.len());
    let t: Vec<usize> = (0..p)
        .filter(|&k| tested.contains(&problem.free[k]))
        .collect();
    let o: Vec<usize> = (0..p).filter(|k| !t.contains(k)).collect();
    let k = t.len();
    if k == 0 {
        return Ok(f64::NAN);
    }
    let col = |row: usize, c: usize| j[row * p + c];
    // Q = J_T − J_O (J_Oᵀ J_O)⁻¹ J_Oᵀ J_T
    let no = o.len();
    let mut q = vec![0.0; rows * k];
    let mut ooa = vec![0.0; no * no];
    let mut otb = vec![0.0; no * k];
    for i in 0..rows {
        for (a, &oa) in o.iter().enumerate() {
            for (b, &ob) in o.iter().enumerate() {
                ooa[a * no + b] += col(i, oa) * col(i, ob);
            }
            for (b, &tb) in t.iter().enumerate() {
                otb[a * k + b] += col(i, oa) * col(i, tb);
            }
        }
    }
    // the projection coefficients, one tested column at a time (unit
    // diagonal scaling for the solve)
    let d: Vec<f64> = (0..no)
        .map(|a| ooa[a * no + a].sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let scaled: Vec<f64> = (0..no * no)
        .map(|x| ooa[x] / (d[x / no] * d[x % no]))
        .collect();
    let mut coef = vec![0.0; no * k];
    for b in 0..k {
        let rhs: Vec<f64> = (0..no).map(|a| otb[a * k + b] / d[a]).collect();
        if no > 0 {
            let Some(x) = super::levenberg_marquardt::cholesky_solve(&scaled, &rhs, no) else {
                return Ok(f64::NAN);
            };
            for a in 0..no {
                coef[a * k + b] = x[a] / d[a];
            }
        }
    }
    for i in 0..rows {
        for (b, &tb) in t.iter().enumerate() {
            let mut v = col(i, tb);
            for (a, &oa) in o.iter().enumerate() {
                v -= col(i, oa) * coef[a * k + b];
            }
            q[i * k + b] = v;
        }
    }
    // E = tr(M⁻¹ S), M = QᵀQ, S = Qᵀ Σ Q
    let mut m = vec![0.0; k * k];
    let mut sm = vec![0.0; k * k];
    for i in 0..rows {
        let s2 = sigma[i] * sigma[i];
        for a in 0..k {
            for b in 0..k {
                let x = q[i * k + a] * q[i * k + b];
                m[a * k + b] += x;
                sm[a * k + b] += s2 * x;
            }
        }
    }
    let mut e = 0.0;
    for b in 0..k {
        let rhs: Vec<f64> = (0..k).map(|a| sm[a * k + b]).collect();
        let Some(x) = super::levenberg_marquardt::cholesky_solve(&m, &rhs, k) else {
            return Ok(f64::NAN);
        };
        e += x[b];
    }
    Ok(if e > 0.0 {
        k as f64 * delta_objective / e
    } else {
        f64::NAN
    })
}

/// The χ² quantile `q` with `P(χ²_k > q) = 0.001` (Wilson–Hilferty; 11.2
/// for k = 1 against the exact 10.83, 22.5 for k = 6 against 22.46).
pub fn chi2_999(k: usize) -> f64 {
    chi2_quantile(k, 3.090_232)
}

/// The χ² quantile `q` with `P(χ²_k > q) = 0.05` (Wilson–Hilferty; 3.85
/// for k = 1 against 3.84, 5.99 for k = 2).
pub fn chi2_95(k: usize) -> f64 {
    chi2_quantile(k, 1.644_854)
}

/// Wilson–Hilferty: the χ²_k quantile at the standard normal quantile `z`.
fn chi2_quantile(k: usize, z: f64) -> f64 {
    let k = k.max(1) as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Stage 9 ([`ReadingChoice::Auto`]): censor the curves whose measured
/// sweep left its branch early, when the data demand it. The fit with every
/// jump censored says which curves can leave early (a step or more before
/// the model's fold); those are censored when that lowers the noise-scaled
/// misfit by more than the χ² 0.1 % point for that many curves; the new fit
/// is then asked again about its curves still read exactly (at most three
/// rounds: censoring one curve moves the folds of the others).
fn decide_readings(setup: &Setup, best: Fitted, work: &Dataset) -> Result<Fitted, IdentifyError> {
    let plan = setup.plan;
    if plan.reading != ReadingChoice::Auto || plan.jumps.weight() == 0.0 {
        return Ok(best);
    }
    // only where a curve could have jumped: a model fold in its range
    let (_, m_exact) = comparison(work, &best)?;
    if !m_exact.iter().any(|m| m.fold.is_some()) {
        return Ok(best);
    }
    let mut all = restarted(&best.spec, &best.fit.theta);
    all.censored = vec![true; work.curves.len()];
    let opts = limited(&plan.lm, plan.seed, DECISION_ITERATIONS);
    let Some(cens) = Fitted::fitted(work, all, &opts) else {
        return Ok(best);
    };
    let (_, m_cens) = comparison(work, &cens)?;
    let early = |m: &[CurveMatch], spec: &FitSpec| -> Vec<usize> {
        (0..work.curves.len())
            .filter(|&ci| !spec.censored.get(ci).copied().unwrap_or(false))
            .filter(|&ci| early_by(&work.curves[ci], &m[ci]).is_some())
            .collect()
    };
    let mut candidates = early(&m_cens, &best.spec);
    let mut start = cens.fit.theta;
    let mut best = best;
    for _ in 0..3 {
        if candidates.is_empty() {
            break;
        }
        let mut spec = restarted(&best.spec, &start);
        for &ci in &candidates {
            spec.censored[ci] = true;
        }
        let Some(trial) = Fitted::fitted(work, spec, &opts) else {
            break;
        };
        // the drop of the objective against its residual variance: on real
        // data the model's misfit, not the instrument noise, is what the
        // readings are compared by (a noise-scaled comparison was ruled by
        // the few points of the tiniest noise)
        let n = work.len();
        let p = trial.spec.free_indices().len();
        let s2 = trial.objective / n.saturating_sub(p).max(1) as f64;
        let f = (best.objective - trial.objective) / s2.max(f64::MIN_POSITIVE);
        if !(f > chi2_999(candidates.len())) {
            break;
        }
        best = trial;
        let (_, m) = comparison(work, &best)?;
        candidates = early(&m, &best.spec);
        start = best.fit.theta;
    }
    Ok(best)
}

/// How far before the model's fold the measured sweep of `c` left its
/// branch (rad/s), when by at least one step: from the last step compared
/// with the followed state before the first one compared with another
/// state, to the fold.
fn early_by(c: &Curve, m: &CurveMatch) -> Option<f64> {
    let (wf, _) = m.fold?;
    let first = m.left_early(c)?;
    let n = c.omegas.len();
    let (last_on, h) = match c.direction {
        SweepDirection::Up => {
            let k = first.checked_sub(1)?;
            (c.omegas[k], c.omegas[first] - c.omegas[k])
        }
        SweepDirection::Down => {
            let k = (first + 1 < n).then_some(first + 1)?;
            (c.omegas[k], c.omegas[k] - c.omegas[first])
        }
    };
    let d = (wf - last_on).abs();
    (d >= h).then_some(d)
}

/// An exponent within this of 0 makes its power-law term a near copy of
/// the linear one (stage 5 then tests whether the term matters; the
/// synthetic suites draw no exponent within 0.5 of 0 for the same reason).
pub const NEAR_LINEAR: f64 = 0.5;

/// Share of an exponent's range within which it counts as at an end of
/// the range ([`exponent_near_range_end`]).
const RANGE_END: f64 = 0.01;

/// `true` when the free exponent `j` of `spec` is within [`RANGE_END`] of
/// its range at θ (for ρ and η no end of the range is a natural bound: an
/// exponent there is carried by a term the data may not need; measured on
/// blind sets without nonlinear damping, fits ended with κ vanishing and
/// η at 8.0 and at 7.9997).
fn exponent_near_range_end(spec: &FitSpec, theta: &super::Parameters, j: usize) -> bool {
    let (lo, hi) = spec.bounds[j];
    spec.status[j] == Status::Free && (theta[j] - lo).min(hi - theta[j]) <= RANGE_END * (hi - lo)
}

/// Stage 5: remove the nonlinear terms that do not matter, naming the
/// exponent that had no effect.
fn settle_terms(setup: &Setup, best: Fitted, work: &Dataset) -> Result<Fitted, IdentifyError> {
    let plan = setup.plan;
    let mut best = best;
    for (coef, exp) in [(KAPPA, ETA), (BETA, RHO)] {
        if best.spec.status[coef] == Status::Absent {
            continue;
        }
        let hits = super::bound_hits(&best.spec, &best.fit.theta);
        let at_lower = |j: usize| hits.contains(&(j, true));
        let exponent_zero = best.spec.status[exp] == Status::Free
            && at_lower(exp)
            && best.spec.bounds[exp].0 == 0.0;
        // an exponent near 0 makes the term a near copy of the linear one
        let near_linear =
            best.spec.status[exp] == Status::Free && best.fit.theta[exp].abs() <= NEAR_LINEAR;
        // the coefficient trades off with its linear counterpart (κ with δ,
        // β with α): the term acts as a copy of the linear one
        let linear = if coef == KAPPA { "delta" } else { "alpha" };
        let copies_linear = best.fit.ridges.iter().any(|r| {
            (r.first == PARAM_NAMES[coef] && r.second == linear)
                || (r.second == PARAM_NAMES[coef] && r.first == linear)
        });
        // (a weak term the data see but cannot pin — a ridge with its own
        // exponent, a wide interval — is kept and reported as such)
        // an exponent at a bound of its range: the term may not be needed
        // (within 1 % of an end: a bound hit is one)
        let exponent_at_bound = exponent_near_range_end(&best.spec, &best.fit.theta, exp);
        if !(at_lower(coef)
            || exponent_zero
            || exponent_at_bound
            || near_linear
            || copies_linear
            || !best.fit.converged)
        {
            continue;
        }
        let mut reduced = restarted(&best.spec, &best.fit.theta);
        reduced.status[coef] = Status::Absent;
        reduced.status[exp] = Status::Absent;
        reduced.start[coef] = 0.0;
        reduced.start[exp] = 0.0;
        let removed = [coef, exp]
            .iter()
            .filter(|&&j| best.spec.status[j] == Status::Free)
            .count();
        if reduced.free_indices().is_empty() {
            continue;
        }
        let opts = limited(&plan.lm, plan.seed, DECISION_ITERATIONS);
        let Some(cand) = Fitted::fitted(work, reduced, &opts) else {
            continue;
        };
        let cand = continue_unfinished(setup, cand, work)?;
        let tested: Vec<usize> = [coef, exp]
            .into_iter()
            .filter(|&j| best.spec.status[j] == Status::Free)
            .collect();
        let rise = (cand.objective - best.objective).max(0.0);
        // (NaN: the tested directions are degenerate, no evidence for them)
        let stat = if tested.is_empty() {
            0.0
        } else {
            nested_statistic(work, &best, &tested, rise)?
        };
        let stat = if stat.is_nan() { 0.0 } else { stat };
        if cand.objective <= best.objective || stat <= chi2_95(removed.max(1)) {
            let held_at = best.fit.theta[exp];
            let mut inactive = best.fit.inactive.clone();
            inactive.push(Inactive {
                exponent: PARAM_NAMES[exp],
                coefficient: PARAM_NAMES[coef],
                held_at,
            });
            best = cand;
            best.fit.inactive = inactive;
        }
    }
    Ok(best)
}

/// θ of `f` changed (least change in the optimisation variables, a few
/// Newton steps on the fold frequency) so that the first fold of curve `ci`
/// lies at `target` (rad/s); `None` when that curve's model has no fold or
/// it cannot be moved there.
fn move_fold(
    work: &Dataset,
    f: &Fitted,
    ci: usize,
    target: f64,
    tolerance: f64,
) -> Result<Option<super::Parameters>, IdentifyError> {
    move_fold_in(work, f, ci, target, tolerance, false)
}

/// [`move_fold`]; with `least_misfit`, the change is the one that moves
/// the fold at least first-order change of the residuals on every curve
/// (`du ∝ M⁻¹g`, `M = JᵀJ` of the whole fit in the optimisation
/// variables, `g = ∂Ω_f/∂u`) instead of the least change in `u`: a fold
/// moved by the least change in `u` shifts every curve (measured: the
/// noise-scaled cost of a five-level fit grew from 4.2e3 to 1.3e6 for a
/// one-step move).
fn move_fold_in(
    work: &Dataset,
    f: &Fitted,
    ci: usize,
    target: f64,
    tolerance: f64,
    least_misfit: bool,
) -> Result<Option<super::Parameters>, IdentifyError> {
    use super::objective::Problem;
    let problem = Problem::new(work, &f.spec)?;
    let (ulo, uhi) = problem.u_bounds();
    let mut th = f.fit.theta;
    for _ in 0..8 {
        let Some((wf, af)) = first_fold(work, f, ci, &th) else {
            return Ok(None);
        };
        if (wf - target).abs() <= tolerance {
            return Ok(Some(th));
        }
        let cols = problem.dtheta_du(&th);
        let Some(g) = fold_gradient(&cols, work.curves[ci].gamma, &th, (wf, af)) else {
            return Ok(None);
        };
        // the direction of the move, `d`, with `g·d` its effect on Ω_f
        let d: Vec<f64> = if least_misfit {
            match least_misfit_direction(work, f, &th, &cols, &g) {
                Some(d) => d,
                None => return Ok(None),
            }
        } else {
            g.clone()
        };
        let gd: f64 = g.iter().zip(&d).map(|(a, b)| a * b).sum();
        if !(gd.abs() > 0.0 && gd.is_finite()) {
            return Ok(None);
        }
        let mut u = problem.u_of(&th);
        for k in 0..u.len() {
            u[k] = (u[k] + (target - wf) * d[k] / gd).clamp(ulo[k], uhi[k]);
        }
        th = problem.theta(&u);
    }
    Ok(None)
}

/// The first fold `(Ω_f, a_f)` of curve `ci`'s sweep under `f`'s reading
/// at `th` (`None` when it has none or cannot be evaluated).
fn first_fold(work: &Dataset, f: &Fitted, ci: usize, th: &super::Parameters) -> Option<(f64, f64)> {
    let one = Dataset {
        curves: vec![work.curves[ci].clone()],
    };
    let (_, m) = evaluate_measured(&one, th, false, &MatchOptions::of(&f.spec)).ok()?;
    m.first().and_then(|m| m.fold)
}

/// `∂Ω_f/∂u_k` of the fold `(Ω_f, a_f)` of a curve at forcing `gamma`,
/// `cols` the columns `∂θ/∂u_k` at `th`.
fn fold_gradient(
    cols: &[[f64; N_PARAMS]],
    gamma: f64,
    th: &super::Parameters,
    (wf, af): (f64, f64),
) -> Option<Vec<f64>> {
    let dw = super::jumps::fold_frequency_derivatives(th, gamma, wf, af)?;
    Some(
        cols.iter()
            .map(|col| (0..N_PARAMS).map(|p| dw[p] * col[p]).sum())
            .collect(),
    )
}

/// `f`'s θ moved so that each listed curve's first fold lies within its
/// tolerance of its target, `(ci, target, tolerance)`, all at once, by the
/// least change in `u` that moves them so to first order (`du = Gᵀ(GGᵀ)⁻¹Δ`,
/// `G` the rows `∂Ω_f/∂u` of the listed folds), Newton-iterated; `None`
/// when a listed fold vanishes, there are more folds than free parameters,
/// the rows are dependent, or eight steps do not place them.
/// [`reassign_jumps`] holds every other fold in its step cell so: the move
/// of one fold by itself shifts every curve's fold, and
/// a fold pushed out of its measured jump interval is piecewise constant
/// there, so the refit cannot bring it back (measured: blind h001-hardening
/// of seed 2711270322, six levels up, ρ 3.94: the top level's fold moved a
/// step later took level 5's 1.46 Hz later, out of its measured interval,
/// and the refit ended 28 % above the fit it came from).
fn move_folds_jointly(
    work: &Dataset,
    f: &Fitted,
    targets: &[(usize, f64, f64)],
) -> Result<Option<super::Parameters>, IdentifyError> {
    use super::levenberg_marquardt::cholesky_solve;
    use super::objective::Problem;
    let k = targets.len();
    let problem = Problem::new(work, &f.spec)?;
    let (ulo, uhi) = problem.u_bounds();
    if k == 0 || k > ulo.len() {
        return Ok(None);
    }
    let mut th = f.fit.theta;
    for _ in 0..8 {
        let cols = problem.dtheta_du(&th);
        let (mut rows, mut miss) = (Vec::with_capacity(k), Vec::with_capacity(k));
        let mut placed = true;
        for &(ci, target, tolerance) in targets {
            let Some((wf, af)) = first_fold(work, f, ci, &th) else {
                return Ok(None);
            };
            placed &= (wf - target).abs() <= tolerance;
            let Some(g) = fold_gradient(&cols, work.curves[ci].gamma, &th, (wf, af)) else {
                return Ok(None);
            };
            rows.push(g);
            miss.push(target - wf);
        }
        if placed {
            return Ok(Some(th));
        }
        // GGᵀ y = Δ, du = Gᵀy
        let mut ggt = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..k {
                ggt[i * k + j] = rows[i].iter().zip(&rows[j]).map(|(a, b)| a * b).sum();
            }
        }
        let Some(y) = cholesky_solve(&ggt, &miss, k) else {
            return Ok(None);
        };
        if !y.iter().all(|v| v.is_finite()) {
            return Ok(None);
        }
        let mut u = problem.u_of(&th);
        for (q, uq) in u.iter_mut().enumerate() {
            let du: f64 = (0..k).map(|i| rows[i][q] * y[i]).sum();
            *uq = (*uq + du).clamp(ulo[q], uhi[q]);
        }
        th = problem.theta(&u);
    }
    Ok(None)
}

/// Stage 7, exact readings: a model fold that lies after measured points
/// the sweep had already left it at. Read exactly, a measured jump says the
/// fold lies in the step interval of the jump; the measured-branch output
/// error compares the points between the measured jump and a late model
/// fold with the other stable state at a penalty scaled by their (small)
/// amplitude, so its pull is weak and a fit can end with the model's jump a
/// step late — indistinguishable in the output error, but Eq 31 charges
/// those points the whole distance between the branches (measured: a blind
/// in-family set, five levels both ways, whose top up-sweep's fold sat one
/// step late ended at 149x the truth's Eq 31 cost with every parameter
/// within 6 % of the truth). Each such fold is moved into the measured
/// step interval (halfway), the fit restarted from there, and the move kept
/// when the noise-scaled cost does not grow by more than one point's noise
/// variance.
fn pull_late_folds(setup: &Setup, best: Fitted, work: &Dataset) -> Result<Fitted, IdentifyError> {
    // a relocation that cannot be evaluated (a solve failing at a moved θ)
    // leaves the fit as it was rather than failing it
    Ok(relocate_folds(setup, best.clone(), work, POLISH_ITERATIONS, false).unwrap_or(best))
}

/// The folds of `best` that sit on the wrong side of a measured step moved
/// into the measured jump's step, by the least-misfit change
/// ([`move_fold_in`]), and refitted (at most `iterations`) behind a barrier
/// that keeps them there; the result replaces `best` when its Eq 31 cost
/// is lower. Two cases, per curve:
/// * **late** (exact reading only): points just before the model's fold
///   compared with another stable state — the measured sweep had already
///   left the branch ([`pull_late_folds`]);
/// * **early**: points just after the model's fold nearer (in amplitude)
///   to the end of the branch the model left than to the state they are
///   compared with — the measured sweep stayed on it ([`reassign_jumps`]
///   moves these by the least change in `u` and refits without a barrier,
///   which can slide back: measured on a blind three-level set, a race
///   candidate with every parameter within 30 % of the truth stopped at 17x
///   the truth's objective with the top up-sweep's fold one step early).
///
/// With `least_change_too` (the race), a fold the least-misfit move cannot
/// place is moved by the least change in `u` instead (below). The late-fold
/// pull on every point does without it: there no measured case needed it,
/// and on the 24 °C beam it cost a quarter of the Duffing fit's time
/// (0.84–0.96 s → 1.08–1.17 s, same result) for refits that were not kept.
fn relocate_folds(
    setup: &Setup,
    best: Fitted,
    work: &Dataset,
    iterations: usize,
    least_change_too: bool,
) -> Result<Fitted, IdentifyError> {
    let (e, matches) = comparison(work, &best)?;
    let mut moved = best.clone();
    let mut any = false;
    let mut off = 0;
    for (ci, c) in work.curves.iter().enumerate() {
        let n = c.omegas.len();
        let model = &e.model[off..off + n];
        off += n;
        let m = &matches[ci];
        let Some((wf, af)) = m.fold else {
            continue;
        };
        // late: the points before the fold, nearest the fold first
        let before: Vec<usize> = match c.direction {
            SweepDirection::Up => (0..n).rev().filter(|&i| c.omegas[i] < wf).collect(),
            SweepDirection::Down => (0..n).filter(|&i| c.omegas[i] > wf).collect(),
        };
        let late = if best.spec.censored.get(ci).copied().unwrap_or(false) {
            0
        } else {
            before
                .iter()
                .take_while(|&&i| m.compared[i] == Compared::Other)
                .count()
        };
        let (a, b) = if late > 0 && late < before.len() {
            (before[late - 1], before[late])
        } else if let Some(pair) = stayed_on_branch(c, m, model, (wf, af), true) {
            pair
        } else {
            continue;
        };
        // the least-misfit move follows the directions the data see least,
        // which can lose the fold or move it the wrong way; in the race the
        // least change in `u` is tried then (measured: a blind two-level
        // up-sweep set, ρ 3.9, η 2.8, whose race candidates of the truth's
        // basin all kept their folds a step early because the least-misfit
        // move failed, ended at 1.12x the truth's cost; with this move four
        // of them reached 0.98x)
        any |= move_fold_between(work, &mut moved, ci, (a, b), true)?
            || (least_change_too && move_fold_between(work, &mut moved, ci, (a, b), false)?);
    }
    if !any {
        return Ok(best);
    }
    refit_behind_barrier(setup, best, moved, work, iterations)
}

/// `moved` (`best` with folds moved into measured step cells) refitted
/// behind a barrier the folds do not cross, then assessed as `best` is
/// read; kept when its Eq 31 cost is lower than `best`'s.
fn refit_behind_barrier(
    setup: &Setup,
    best: Fitted,
    moved: Fitted,
    work: &Dataset,
    iterations: usize,
) -> Result<Fitted, IdentifyError> {
    // refitted behind a barrier the fold does not cross (every penalty
    // ×[`PULL_BARRIER`]: in the exact reading a fit whose folds lie in the
    // measured jump intervals pays none), then assessed as fitted
    let plan = setup.plan;
    let mut spec = restarted(&moved.spec, &moved.fit.theta);
    spec.jump_weight *= PULL_BARRIER;
    let Some(held) = Fitted::fitted(work, spec, &limited(&plan.lm, plan.seed, iterations)) else {
        return Ok(best);
    };
    let spec = restarted(&best.spec, &held.fit.theta);
    let cand = Fitted::assessed(work, spec, held.fit.theta, &held.fit)?;
    // a refit its budget stopped continues without the barrier (the
    // fold's own barrier holds it), so it does not end "not converged"
    let mut cand = continue_unfinished(setup, cand, work)?;
    // read exactly, a late fold is not a solution: the fit that keeps
    // the folds in their measured intervals replaces it when its Eq 31
    // cost is lower (the judge then says whether it fits the noise)
    if cand.fit.cost < best.fit.cost {
        cand.fit.inactive = best.fit.inactive.clone();
        Ok(cand)
    } else {
        Ok(best)
    }
}

/// Share of a step cell within which a fold counts as pinned at its edge.
const PINNED: f64 = 0.01;

/// Folds that end pinned against a measured step (`pinned`, by
/// [`pinned_folds`]: within [`PINNED`] of the cell's width, curves read
/// exactly) moved to the middle of their cell
/// and refitted behind the barrier ([`refit_behind_barrier`]). A fold at
/// the edge of its cell is a constrained optimum: the fit wants it across
/// the step, where that point would change branch, and the sqrt-singular
/// branch end gives LM no usable gradient along it; a basin with the fold
/// inside the cell can be lower (measured: blind h008-hardening, seed
/// 2711270031, four levels up and down, ρ 3.80: level 4's up-sweep fold
/// 1.3e-7 Hz above the last measured step on its branch, converged and
/// within the noise at 1.071x the truth's Eq 31 cost; moved into its cell
/// and refitted, 0.995x).
fn unpin_folds(
    setup: &Setup,
    best: Fitted,
    work: &Dataset,
    pinned: &[(usize, usize)],
) -> Result<Fitted, IdentifyError> {
    let mut moved = best.clone();
    let mut any = false;
    for &(ci, k) in pinned {
        any |= move_fold_between(work, &mut moved, ci, (k - 1, k), true)?
            || move_fold_between(work, &mut moved, ci, (k - 1, k), false)?;
    }
    if !any {
        return Ok(best);
    }
    let held = refit_with_folds_held(setup, &moved, work, pinned)?;
    let barrier = refit_behind_barrier(setup, best, moved, work, POLISH_ITERATIONS)?;
    Ok(match held {
        Some(h) if h.fit.cost < barrier.fit.cost => h,
        _ => barrier,
    })
}

/// Weight of the held folds in [`refit_with_folds_held`]: a fold a tenth
/// of its cell off its target costs as much as the whole objective at the
/// start.
const FOLD_HELD_WEIGHT: f64 = 10.0;

/// [`unpin_folds`]' second refit: `moved` (the pinned folds moved to the
/// middle of their cells) refitted with those folds *held* there (an
/// equality, a heavily weighted residual of each fold frequency,
/// [`FoldsHeld`]), then freed from that fit and continued; `None` when it
/// cannot be fitted. Inside its cell a fold is free behind the barrier of
/// [`refit_behind_barrier`], and LM carries it back to the step: the
/// smooth part of the objective wants it across, every trial step that
/// crosses is rejected, and the solver stops at the kink with a small step
/// although the objective still falls along the step (measured: blind
/// h008-mixed of random seed 4120673301, five levels up and down, no
/// phase, ρ 5.04, η 2.19: level 5's up-sweep fold 2e-5 Hz below the step
/// after it, the fit converged within the noise at 1.128x the truth's
/// Eq 31 cost; on the straight line to the truth the objective falls
/// monotonically while the fold moves into its cell, and LM from the
/// line's midpoint returns to the step). Held at the middle, the others
/// refit on a smooth objective; freed there, the fit only descends.
fn refit_with_folds_held(
    setup: &Setup,
    moved: &Fitted,
    work: &Dataset,
    pinned: &[(usize, usize)],
) -> Result<Option<Fitted>, IdentifyError> {
    use super::levenberg_marquardt::{minimise, LeastSquares};
    use super::objective::Problem;
    // (the held objective is the measured-branch output error)
    if moved.spec.branch != super::objective::ResponseBranch::Measured {
        return Ok(None);
    }
    let plan = setup.plan;
    let problem = Problem::new(work, &moved.spec)?;
    let (lo, hi) = problem.u_bounds();
    let opts = limited(&plan.lm, plan.seed, POLISH_ITERATIONS);
    let mut held_cells: Vec<(usize, usize)> = pinned.to_vec();
    let mut start = moved.fit.theta;
    let mut out: Option<Fitted> = None;
    for _ in 0..FOLD_HELD_ROUNDS {
        let u0 = problem.u_of(&start);
        let Some(r0) = problem.residuals(&u0) else {
            break;
        };
        let scale = FOLD_HELD_WEIGHT * r0.iter().map(|r| r * r).sum::<f64>().sqrt();
        let folds = held_cells
            .iter()
            .map(|&(ci, k)| {
                let w = &work.curves[ci].omegas;
                (ci, 0.5 * (w[k - 1] + w[k]), (w[k - 1] - w[k]).abs())
            })
            .collect();
        let held = FoldsHeld {
            problem: &problem,
            folds,
            scale,
        };
        let Ok(r) = minimise(&held, &u0, &lo, &hi, &opts.lm) else {
            break;
        };
        let th = problem.theta(&r.u);
        let Some(freed) = Fitted::fitted(work, restarted(&moved.spec, &th), &opts) else {
            break;
        };
        let mut freed = continue_unfinished(setup, freed, work)?;
        freed.fit.inactive = moved.fit.inactive.clone();
        // freed, another fold can end pinned in its turn: it is held too,
        // from there
        let more: Vec<(usize, usize)> = pinned_folds(work, &freed)?
            .into_iter()
            .filter(|p| !held_cells.contains(p))
            .collect();
        start = freed.fit.theta;
        if out.as_ref().is_none_or(|o| freed.fit.cost < o.fit.cost) {
            out = Some(freed);
        }
        if more.is_empty() {
            break;
        }
        held_cells.extend(more);
    }
    Ok(out)
}

/// Rounds of [`refit_with_folds_held`]: each holds the folds pinned so far.
const FOLD_HELD_ROUNDS: usize = 3;

/// The output error of [`Problem`] plus one residual per held fold,
/// `scale · (Ω_f − target)/width` (its first fold `Ω_f` on curve `ci`, the
/// target and the width of its step cell), for [`refit_with_folds_held`].
struct FoldsHeld<'a> {
    problem: &'a super::objective::Problem<'a>,
    /// `(curve, target, width)`, rad/s.
    folds: Vec<(usize, f64, f64)>,
    scale: f64,
}

impl FoldsHeld<'_> {
    fn evaluate(&self, u: &[f64], jacobian: bool) -> Option<(Vec<f64>, Vec<f64>)> {
        let th = self.problem.theta(u);
        let work = self.problem.data;
        let (e, matches) =
            evaluate_measured(work, &th, jacobian, &MatchOptions::of(self.problem.spec)).ok()?;
        let (mut r, mut j) = if jacobian {
            self.problem.residuals_and_jacobian_of(&th, e)?
        } else {
            (e.residuals, Vec::new())
        };
        let cols = self.problem.dtheta_du(&th);
        for &(ci, target, width) in &self.folds {
            let (wf, af) = matches.get(ci)?.fold?;
            r.push(self.scale * (wf - target) / width);
            if jacobian {
                let g = fold_gradient(&cols, work.curves[ci].gamma, &th, (wf, af))?;
                j.extend(g.iter().map(|v| self.scale * v / width));
            }
        }
        r.iter().all(|v| v.is_finite()).then_some((r, j))
    }
}

impl super::levenberg_marquardt::LeastSquares for FoldsHeld<'_> {
    fn jacobian_with_trials(&self) -> bool {
        true
    }

    fn n_params(&self) -> usize {
        self.problem.free.len()
    }

    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        self.evaluate(u, false).map(|(r, _)| r)
    }

    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        self.evaluate(u, true)
    }
}

/// The first folds of `f` on `work` pinned against a measured step (within
/// [`PINNED`] of their cell's width, curves read exactly): `(curve, k)`
/// with the fold in the cell of steps `k − 1`, `k` ([`step_cell`]).
fn pinned_folds(work: &Dataset, f: &Fitted) -> Result<Vec<(usize, usize)>, IdentifyError> {
    let (_, matches) = comparison(work, f)?;
    Ok(work
        .curves
        .iter()
        .enumerate()
        .filter(|&(ci, _)| !f.spec.censored.get(ci).copied().unwrap_or(false))
        .filter_map(|(ci, c)| {
            let (wf, _) = matches[ci].fold?;
            let (k, lo, hi) = step_cell(c, wf)?;
            ((wf - lo).min(hi - wf) <= PINNED * (hi - lo)).then_some((ci, k))
        })
        .collect())
}

/// `f`'s θ (and its start) moved so that the first fold of curve `ci` lies
/// halfway between the measured steps `a` and `b` (within a tenth of that
/// step), by [`move_fold_in`]; `false`, and `f` unchanged, when it cannot
/// be moved there.
fn move_fold_between(
    work: &Dataset,
    f: &mut Fitted,
    ci: usize,
    (a, b): (usize, usize),
    least_misfit: bool,
) -> Result<bool, IdentifyError> {
    let w = &work.curves[ci].omegas;
    let target = 0.5 * (w[a] + w[b]);
    let tol = 0.1 * (w[a] - w[b]).abs();
    let Some(th) = move_fold_in(work, f, ci, target, tol, least_misfit)? else {
        return Ok(false);
    };
    f.spec = restarted(&f.spec, &th);
    f.fit.theta = th;
    Ok(true)
}

/// `M⁻¹g` for [`move_fold_in`]: `M = J_uᵀJ_u` of `f`'s residuals on `work`
/// at `th` (Jacobian in θ times `cols`, the columns `∂θ/∂u_k`), with a
/// relative ridge of 1e-10 of its largest diagonal entry so a direction
/// the data do not see stays finite.
fn least_misfit_direction(
    work: &Dataset,
    f: &Fitted,
    th: &super::Parameters,
    cols: &[[f64; N_PARAMS]],
    g: &[f64],
) -> Option<Vec<f64>> {
    let (e, _) = evaluate_measured(work, th, true, &MatchOptions::of(&f.spec)).ok()?;
    let jac = e.jacobian?;
    let n = cols.len();
    let mut m = nalgebra::DMatrix::<f64>::zeros(n, n);
    for row in &jac {
        let ju: Vec<f64> = cols
            .iter()
            .map(|col| (0..N_PARAMS).map(|p| row[p] * col[p]).sum())
            .collect();
        for a in 0..n {
            for b in 0..n {
                m[(a, b)] += ju[a] * ju[b];
            }
        }
    }
    let top = (0..n).map(|k| m[(k, k)]).fold(0.0, f64::max);
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    for k in 0..n {
        m[(k, k)] += 1e-10 * top;
    }
    let d = m
        .cholesky()?
        .solve(&nalgebra::DVector::from_column_slice(g));
    d.iter()
        .all(|x| x.is_finite())
        .then(|| d.iter().copied().collect())
}

/// Multiplies the jump penalties while [`pull_late_folds`] refits.
const PULL_BARRIER: f64 = 1e4;

/// The measured step cell of curve `c` around frequency `wf` (rad/s):
/// `(k, ω_{k−1}, ω_k)` with `ω_{k−1} < wf ≤ ω_k`; `None` outside the
/// measured range.
fn step_cell(c: &Curve, wf: f64) -> Option<(usize, f64, f64)> {
    let k = c.omegas.partition_point(|&w| w < wf);
    (k > 0 && k < c.omegas.len()).then(|| (k, c.omegas[k - 1], c.omegas[k]))
}

/// When the model's branch at the end of curve `ci`'s sweep (which has no
/// jump) ends within [`FOLD_MARGIN`] past the last step (an up-sweep's
/// highest frequency, a down-sweep's lowest): the data with that curve
/// extended by one step past the fold, where the sweep sees it, and the
/// target twice the margin past the last step. The root count at the last
/// step and one margin past it differ there. Such a fold is the sweep's
/// last step read by the last digits: an independent evaluation of the
/// same model can place it before that step, and the step then on the
/// other branch (measured: blind h047-mixed of seed 2711280110, four levels
/// up, its fit's level-1 fold 2.1e-12 relative past the last step; the
/// oracle of `blind_suite.py` placed it 3.9e-11 before, read the last
/// point off the branch and scored the fit at 39.9x the truth's Eq 31
/// cost, where nlsdof's own cost of it is 0.98x the truth's).
fn fold_past_the_end(work: &Dataset, ci: usize, th: &super::Parameters) -> Option<(Dataset, f64)> {
    let c = &work.curves[ci];
    let (end, sign) = match c.direction {
        SweepDirection::Up => (*c.omegas.last()?, 1.0),
        SweepDirection::Down => (*c.omegas.first()?, -1.0),
    };
    let r = crate::harmonic_balance::ForcedResponse::from_normalised(
        &th.normalised_model(),
        th[GAIN] * c.gamma,
        crate::harmonic_balance::Formulation::HarmonicBalance,
    )
    .ok()?;
    let count = |w: f64| r.equation(w).roots_t().ok().map(|v| v.len());
    let past = end * (1.0 + sign * FOLD_MARGIN);
    if count(end)? == count(past)? {
        return None;
    }
    let mut ext = work.clone();
    let e = &mut ext.curves[ci];
    let beyond = end * (1.0 + sign * 4.0 * FOLD_MARGIN);
    let at = if sign > 0.0 { e.omegas.len() } else { 0 };
    let k = if sign > 0.0 { e.omegas.len() - 1 } else { 0 };
    let (a, wt) = (e.amplitudes[k], e.weights[k]);
    e.omegas.insert(at, beyond);
    e.amplitudes.insert(at, a);
    e.weights.insert(at, wt);
    if let Some(p) = e.phases.as_mut() {
        let v = p[k];
        p.insert(at, v);
    }
    Some((ext, end * (1.0 + sign * 2.0 * FOLD_MARGIN)))
}

/// Stage 7: no fitted fold within [`FOLD_MARGIN`] of a step of a measured
/// frequency, or past the last step of a sweep by less than that
/// ([`fold_past_the_end`]).
fn keep_folds_off_steps(best: Fitted, work: &Dataset) -> Result<Fitted, IdentifyError> {
    let mut best = best;
    // the noise-scaled cost of `best` and its noise model, while it stands
    let mut now: Option<(f64, NoiseModel)> = None;
    for _round in 0..3 {
        let (_, matches) = comparison(work, &best)?;
        let mut moved = false;
        for (ci, c) in work.curves.iter().enumerate() {
            // a fold just past the end of a sweep without a jump: moved
            // out on the extended curve (`fold_past_the_end`)
            let (on, target, margin) = match matches[ci].fold {
                Some((wf, _)) => {
                    // the measured step interval around the fold
                    let Some((_, lo, hi)) = step_cell(c, wf) else {
                        continue;
                    };
                    let margin = FOLD_MARGIN * wf;
                    // aim at twice the margin, so that rounding cannot leave
                    // it short
                    let target = if wf - lo < margin {
                        lo + 2.0 * margin
                    } else if hi - wf < margin {
                        hi - 2.0 * margin
                    } else {
                        continue;
                    };
                    (std::borrow::Cow::Borrowed(work), target, margin)
                }
                None => match fold_past_the_end(work, ci, &best.fit.theta) {
                    Some((ext, target)) => {
                        (std::borrow::Cow::Owned(ext), target, FOLD_MARGIN * target)
                    }
                    None => continue,
                },
            };
            let Some(theta) = move_fold(&on, &best, ci, target, 0.5 * margin)? else {
                continue;
            };
            let spec = restarted(&best.spec, &theta);
            // a moved θ that cannot be evaluated is not taken (measured on
            // the 24 °C beam, with a variant of the late-fold pull: a fold
            // moved by 1e-9 took η from −1 to −1 + 2e-9, where the friction
            // that held the mass at 120 Hz left an amplitude of 1e-300, the
            // solve overflowed, and the error ended the identification)
            let Ok(mut moved_fit) = Fitted::assessed(work, spec, theta, &best.fit) else {
                continue;
            };
            // accepted when it costs nothing measurable: less than a tenth
            // of one point's noise variance (the current fit's cost and
            // noise model are computed once per accepted fit)
            let (z_now, nm) = match now.take() {
                Some(v) => v,
                None => noise_scaled(work, &best, None)?,
            };
            let z_moved = noise_scaled(work, &moved_fit, Some(&nm)).ok().map(|v| v.0);
            if z_moved.is_some_and(|z| z <= z_now + 0.1) {
                moved_fit.fit.inactive = best.fit.inactive.clone();
                moved_fit.fit.termination = best.fit.termination;
                moved_fit.fit.converged = best.fit.converged;
                moved_fit.objective = moved_fit.objective.max(0.0);
                best = moved_fit;
                moved = true;
            } else {
                now = Some((z_now, nm));
            }
        }
        if !moved {
            break;
        }
    }
    Ok(best)
}

/// The points just after the model's fold (`(Ω_f, a_f)`) in sweep order
/// that are nearer, in amplitude, to the end of the branch the model left
/// than to the model state (`model`) — the measured sweep stayed on that
/// branch — as the data indices of the last of them and the next point;
/// `None` when there is none or every point after the fold is one. Points
/// compared with another state never count; those compared with the
/// branch end count when `fold_end_counts`.
fn stayed_on_branch(
    c: &Curve,
    m: &CurveMatch,
    model: &[f64],
    (wf, af): (f64, f64),
    fold_end_counts: bool,
) -> Option<(usize, usize)> {
    let n = c.omegas.len();
    let after: Vec<usize> = match c.direction {
        SweepDirection::Up => (0..n).filter(|&i| c.omegas[i] >= wf).collect(),
        SweepDirection::Down => (0..n).rev().filter(|&i| c.omegas[i] <= wf).collect(),
    };
    let run = after
        .iter()
        .take_while(|&&i| {
            (m.compared[i] == Compared::Sweep
                || (fold_end_counts && m.compared[i] == Compared::FoldEnd))
                && (c.amplitudes[i] - af).abs() < (c.amplitudes[i] - model[i]).abs()
        })
        .count();
    (run > 0 && run < after.len()).then(|| (after[run - 1], after[run]))
}

/// Stage 8, escalation: other jump assignments. A point measured after the
/// model's fold but nearer (in amplitude) to the end of the branch the
/// model left than to the state it is compared with says that the sweep
/// stayed on that branch; when the fold sits more than a step before such
/// points, the penalty that would pull it is dearer than Eq 31's charge
/// and no gradient reaches it (measured: a top level whose fold sat 1.6
/// steps early, 80x the truth's cost). Each such fold is moved past the
/// run of those points (halfway to the next one), and the fit restarted
/// from there; when that refit is not lower than `f`, the same moves are
/// made again with every other fold held in its step cell
/// ([`move_folds_jointly`]) and refitted, and the lower of the two refits is
/// returned. `None` when no curve shows it.
fn reassign_jumps(
    setup: &Setup,
    f: &Fitted,
    work: &Dataset,
    iterations: usize,
) -> Result<Option<Fitted>, IdentifyError> {
    let (e, matches) = comparison(work, f)?;
    let mut moved = f.clone();
    let mut any = false;
    // (curve, its move's target and tolerance) of every fold moved
    let mut targets: Vec<(usize, f64, f64)> = Vec::new();
    let mut off = 0;
    for (ci, c) in work.curves.iter().enumerate() {
        let n = c.omegas.len();
        let model = &e.model[off..off + n];
        off += n;
        let Some((wf, af)) = matches[ci].fold else {
            continue;
        };
        let Some((last, next)) = stayed_on_branch(c, &matches[ci], model, (wf, af), false) else {
            continue;
        };
        let w = &c.omegas;
        targets.push((
            ci,
            0.5 * (w[last] + w[next]),
            0.1 * (w[last] - w[next]).abs(),
        ));
        any |= move_fold_between(work, &mut moved, ci, (last, next), false)?;
    }
    if !any {
        return Ok(None);
    }
    let plan = setup.plan;
    let opts = limited(&plan.lm, plan.seed, iterations);
    let refit = |th: &super::Parameters| Fitted::fitted(work, restarted(&f.spec, th), &opts);
    let r = refit(&moved.fit.theta);
    if r.as_ref().is_some_and(|r| r.objective < f.objective) {
        return Ok(r);
    }
    // the moves shifted the other folds too: the same moves with every
    // other fold held inside its step cell (`move_folds_jointly`)
    for (ci, c) in work.curves.iter().enumerate() {
        if targets.iter().any(|t| t.0 == ci) {
            continue;
        }
        let Some((wf, _)) = matches[ci].fold else {
            continue;
        };
        if let Some((_, lo, hi)) = step_cell(c, wf) {
            targets.push((ci, wf, 0.5 * (wf - lo).min(hi - wf)));
        }
    }
    let joint = move_folds_jointly(work, f, &targets)?.and_then(|th| refit(&th));
    Ok(match (r, joint) {
        (Some(r), Some(j)) => Some(if j.objective < r.objective { j } else { r }),
        (r, j) => r.or(j),
    })
}

/// Stage 8: per-curve reports and the adequacy of `f` on `data`.
fn judge(data: &Dataset, f: &Fitted) -> (Vec<CurveReport>, Adequacy) {
    let failed = || {
        (
            Vec::new(),
            Adequacy {
                adequate: false,
                ratio: f64::NAN,
                peak_ratio: f64::NAN,
                failing: Vec::new(),
                escalation: Vec::new(),
                needs_early_jumps: None,
                late_folds: Vec::new(),
                split: None,
            },
        )
    };
    let Ok((e, matches)) = comparison(data, f) else {
        return failed();
    };
    // the model's own sweep (Eq 31), evaluated when a curve read exactly
    // left early (NaN residuals if it cannot be)
    let mut sweep: Option<Vec<f64>> = None;
    let mut late_folds = Vec::new();
    let wp = f.spec.phase_weight.is_some();
    let nm = noise_model(data, &e.residuals, wp).with_precision_floor(data);
    let pens: Vec<Vec<f64>> = matches.iter().map(|c| c.penalties.clone()).collect();
    let z = z2_per_curve(data, &e.residuals, wp, &pens, &nm);
    let zs = z2_split_per_curve(data, &e.residuals, wp, &pens, &nm);
    // (the split over all points: amplitude, then phase `(Σ z², count)`)
    let mut split_all: Option<[(f64, usize); 2]> = None;
    let mut curves = Vec::with_capacity(data.curves.len());
    let mut off = 0;
    let (mut z_all, mut n_all) = (0.0, 0usize);
    let (mut z_peak, mut n_peak) = (0.0, 0usize);
    // the peaks' pseudo-residuals against the noise estimate there
    // (`ADEQUACY_PEAKS`)
    let mut peak_check = (0.0, 0usize);
    let mut failing = Vec::new();
    let rms = |v: &mut dyn Iterator<Item = f64>| {
        let (s, k) = v.fold((0.0, 0usize), |(s, k), x| (s + x * x, k + 1));
        (s / k.max(1) as f64).sqrt()
    };
    for (ci, c) in data.curves.iter().enumerate() {
        let n = c.omegas.len();
        // residuals and noise in m
        let r: Vec<f64> = (0..n).map(|i| e.model[off + i] - c.amplitudes[i]).collect();
        let to_m = |i: usize| c.gamma / c.weights[i].sqrt().max(f64::MIN_POSITIVE);
        let m = &matches[ci];
        let (z2, count) = z[ci];
        let top = c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
        let at_peak = |i: usize| c.amplitudes[i] >= 0.5 * top;
        for i in 0..n {
            let sg = nm.amplitude[ci][i];
            if at_peak(i) && sg > 0.0 && sg.is_finite() {
                z_peak += (e.residuals[off + i].powi(2) + m.penalties[i]) / (sg * sg);
                n_peak += 1;
            }
        }
        let (t, k) = pseudo_residual_chi2(
            &c.omegas,
            &e.residuals[off..off + n],
            &nm.amplitude[ci],
            at_peak,
        );
        peak_check.0 += t;
        peak_check.1 += k;
        let mean_z2 = if count > 0 {
            z2 / count as f64
        } else {
            f64::NAN
        };
        let (amp, phase) = zs[ci];
        let split = phase.and_then(|phase| NoiseSplit::of(amp, phase));
        if let (Some(_), Some((zp, np))) = (split, phase) {
            let all = split_all.get_or_insert([(0.0, 0); 2]);
            all[0] = (all[0].0 + amp.0, all[0].1 + amp.1);
            all[1] = (all[1].0 + zp, all[1].1 + np);
        }
        let noise = CurveNoise {
            mean_z2,
            noise_rms: rms(&mut (0..n).map(|i| nm.amplitude[ci][i] * to_m(i))),
            residual_rms: rms(&mut r.iter().copied()),
            split,
        };
        if mean_z2.is_finite() {
            z_all += z2;
            n_all += count;
        }
        if !(mean_z2 <= ADEQUACY_CURVE) {
            failing.push(ci);
        }
        let reading = if f.spec.censored.get(ci).copied().unwrap_or(false) {
            JumpReading::Censored
        } else {
            JumpReading::Exact
        };
        let left_early_by = early_by(c, m);
        if reading == JumpReading::Exact && left_early_by.is_some() {
            let sweep = sweep.get_or_insert_with(|| {
                super::objective::evaluate(data, &f.fit.theta, false)
                    .map_or_else(|_| vec![f64::NAN; data.len()], |e| e.residuals)
            });
            let mut z2 = 0.0;
            let mut count = 0usize;
            for i in 0..n {
                let sg = nm.amplitude[ci][i];
                if sg > 0.0 && sg.is_finite() {
                    z2 += (sweep[off + i] / sg).powi(2);
                    count += 1;
                }
            }
            late_folds.push((ci, (z2 / count.max(1) as f64).sqrt()));
        }
        let (mj, mj_next) = measured_jump(c, m);
        let upper = mj.map(|w| {
            let idx: Vec<usize> = (0..n)
                .filter(|&i| match c.direction {
                    SweepDirection::Up => c.omegas[i] <= w,
                    SweepDirection::Down => c.omegas[i] >= w,
                })
                .collect();
            (idx.iter().map(|&i| r[i] * r[i]).sum::<f64>() / idx.len().max(1) as f64).sqrt()
        });
        let pk = c.peak_index();
        curves.push(CurveReport {
            level: c.level.clone(),
            gamma: c.gamma,
            direction: c.direction,
            reading,
            measured_jump: mj,
            measured_jump_next: mj_next,
            model_jump: m.fold.map(|f| f.0),
            left_early_by,
            noise,
            upper_branch_rms: upper,
            peak: (c.amplitudes[pk], c.amplitudes[pk] + r[pk]),
        });
        off += n;
    }
    let mean = if n_all > 0 {
        z_all / n_all as f64
    } else {
        f64::NAN
    };
    // a noise estimate too small at the peaks (its floor fitted to the
    // low amplitudes) is scaled to what the peaks' own pseudo-residuals say
    let (t, k) = peak_check;
    let peak_scale = if k > 0 && t > chi2_999(k) {
        t / k as f64
    } else {
        1.0
    };
    let peak = if n_peak > 0 {
        z_peak / n_peak as f64 / peak_scale
    } else {
        0.0
    };
    let adequate = mean <= ADEQUACY_ALL
        && peak <= ADEQUACY_PEAKS
        && failing.is_empty()
        && late_folds.is_empty();
    (
        curves,
        Adequacy {
            adequate,
            ratio: mean.max(0.0).sqrt(),
            peak_ratio: peak.max(0.0).sqrt(),
            failing,
            escalation: Vec::new(),
            needs_early_jumps: None,
            late_folds,
            split: split_all.and_then(|[amp, phase]| NoiseSplit::of(amp, phase)),
        },
    )
}

/// The measured jump of `c` as the fit saw it: the last step compared with
/// the branch the model's sweep started on, and the next step, when the
/// measured sweep leaves that branch (before the model's fold, or at it);
/// `None` when it stays on it.
fn measured_jump(c: &Curve, m: &CurveMatch) -> (Option<f64>, Option<f64>) {
    let n = c.omegas.len();
    let order: Vec<usize> = match c.direction {
        SweepDirection::Up => (0..n).collect(),
        SweepDirection::Down => (0..n).rev().collect(),
    };
    let after_fold = |i: usize| {
        m.fold.is_some_and(|(wf, _)| match c.direction {
            SweepDirection::Up => c.omegas[i] >= wf,
            SweepDirection::Down => c.omegas[i] <= wf,
        })
    };
    // the first step (sweep order) not on the followed branch: compared
    // with another state before the fold, or with the sweep's state after it
    let off = order.iter().position(|&i| {
        (m.compared[i] == Compared::Other && !after_fold(i))
            || (m.compared[i] == Compared::Sweep && after_fold(i))
    });
    match off {
        Some(k) if k > 0 => (Some(c.omegas[order[k - 1]]), Some(c.omegas[order[k]])),
        _ => (None, None),
    }
}

/// Stage 8, when the fit does not fit: the landscape minima (up to 12)
/// and the other stiffness sign not raced yet, then a multistart of
/// [`ESCALATION_STARTS`] from the better of that race's winner and the
/// first race's, then (with `profile`: the fit within
/// [`PROFILE_MAX_RATIO`] of the noise) each exponent held across its range
/// from the best so far ([`profile_exponents`]). Returns the best fit found on the race's data (compared
/// with the first race's objective by the caller), what was tried, and the
/// candidates and sign trials of the extra race.
#[allow(clippy::type_complexity)]
fn escalate(
    setup: &Setup,
    ex: &Exploration,
    refine_data: &Dataset,
    gain_status: Status,
    (first, profile): (&Fitted, bool),
    raced: &[(usize, usize, Sign)],
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<
    (
        Option<Fitted>,
        Vec<String>,
        (Vec<Candidate>, Vec<SignTrial>),
    ),
    IdentifyError,
> {
    let plan = setup.plan;
    let mut tried = Vec::new();
    let mut nodes = candidate_nodes(&ex.land, ex.land.minima.len().max(plan.refine));
    nodes.truncate(12);
    let both = setup.spec0.status[BETA] != Status::Absent
        && matches!(plan.sign, SignChoice::Auto | SignChoice::Both);
    let signs = |ee: &EquationErrorFit| -> Vec<Sign> {
        if both {
            vec![Sign::Hardening, Sign::Softening]
        } else if plan.sign == SignChoice::Softening {
            vec![Sign::Softening]
        } else if plan.sign == SignChoice::Hardening {
            vec![Sign::Hardening]
        } else if ee.theta[BETA] < 0.0 {
            vec![Sign::Softening]
        } else {
            vec![Sign::Hardening]
        }
    };
    let mut start = first.clone();
    let mut cands = Vec::new();
    let mut trials = Vec::new();
    // (a race with nothing new to try fails, and is skipped)
    if let Ok((c, winner, t, new)) = race(
        setup,
        ex,
        refine_data,
        &nodes,
        gain_status,
        &signs,
        raced,
        false,
        progress,
    ) {
        tried.push(format!(
            "{} more landscape candidate{}{}",
            new.len(),
            if new.len() == 1 { "" } else { "s" },
            if both { " (both signs)" } else { "" }
        ));
        cands = c;
        trials = t;
        if winner.objective < start.objective {
            start = winner;
        }
    }
    // other jump assignments, from the first race's winner and the wider
    // race's (each on the data as it read them, `Fitted::phase_shift`)
    for from in [first.clone(), start.clone()] {
        let data = phases_shifted(refine_data, from.phase_shift);
        let moved = reassign_jumps(setup, &from, &data, plan.lm.max_iterations)?;
        if let Some(r) = moved.map(|r| r.read_shifted(from.phase_shift)) {
            if !tried.iter().any(|t| t.starts_with("folds moved")) {
                tried.push("folds moved past the points still on their branch".into());
            }
            if r.objective < start.objective {
                start = r;
            }
        }
    }
    progress(IdentifyProgress::Stage {
        name: "escalation: multistart",
        steps: ESCALATION_STARTS,
    });
    tried.push(format!("a multistart of {ESCALATION_STARTS}"));
    let mut spec = restarted(&start.spec, &start.fit.theta);
    spec.censored = vec![plan.reading == ReadingChoice::Censored; refine_data.curves.len()];
    let mut opts = limited(&plan.lm, plan.seed, RACE_ITERATIONS);
    opts.starts = ESCALATION_STARTS;
    let step = || progress(IdentifyProgress::Step);
    let shift = start.phase_shift;
    if let Ok(r) = fit_impl(
        &phases_shifted(refine_data, shift),
        &spec,
        &opts,
        None,
        &step,
    ) {
        let m = Fitted::from_result(r, spec).read_shifted(shift);
        if m.objective < start.objective {
            start = m;
        }
    }
    let shift = start.phase_shift;
    let profiled = profile
        .then(|| {
            let data = phases_shifted(refine_data, shift);
            profile_exponents(setup, ex, &data, &start, ProfileScope::Across, progress)
        })
        .flatten()
        .map(|(p, held)| (p.read_shifted(shift), held));
    if let Some((p, held)) = profiled {
        tried.push(held_across(held));
        if p.objective < start.objective {
            start = p;
        }
    }
    Ok((Some(start), tried, (cands, trials)))
}

/// The escalation list's entry for `held` fits of the whole exponent
/// profile ([`ProfileScope::Across`]).
fn held_across(held: usize) -> String {
    format!("{held} fits with an exponent held across its range")
}

/// Which values [`profile_exponents`] holds each exponent at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ProfileScope {
    /// Across its landscape axis, and [`PROFILE_LOCAL`] either side of the
    /// fit; a removed term restored along its exponent.
    Across,
    /// Only [`PROFILE_LOCAL`] either side of the fit.
    Near,
    /// Only two standard errors either side of the fit.
    Fine,
}

/// Most values of each exponent that `profile_exponents` holds across
/// its axis.
pub const PROFILE_VALUES: usize = 8;

/// `profile_exponents` also holds each exponent this far either side of
/// the fit's value (the axis values, 1.35 apart on η's default axis, can
/// step over a neighbouring basin: blind h003-mixed of seed 2711270212,
/// fit at η 0.41, truth 0.92). The best of these held fits is freed beside
/// the two best across the axis, not instead of them: held near the fit
/// they start in its basin and end low, and crowded out the held fit that
/// leads blind h000-mixed of seed 2711270143 to its optimum (1.293× the
/// truth's cost instead of 1.003×).
pub const PROFILE_LOCAL: f64 = 0.5;

/// The index of the axis value nearest `v` (`None` for an empty axis or a
/// `v` that is not finite).
fn nearest_index(axis: &[f64], v: f64) -> Option<usize> {
    if !v.is_finite() {
        return None;
    }
    (0..axis.len()).min_by(|&a, &b| (axis[a] - v).abs().total_cmp(&(axis[b] - v).abs()))
}

/// Held fits of [`profile_exponents`] freed again: the best across the
/// axis, and the best near the fit ([`PROFILE_LOCAL`]).
const PROFILE_FREED_ACROSS: usize = 2;
const PROFILE_FREED_NEAR: usize = 1;
const PROFILE_FREED_FINE: usize = 1;

/// Smallest two-standard-error step `profile_exponents` holds an exponent
/// at beside the fit (below it the held fit is the fit).
const PROFILE_FINE_MIN: f64 = 1e-3;

/// The groups of `profile_exponents`' held fits; each group's best are
/// freed, so that no group crowds out another.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Held {
    /// At values across the landscape's axis.
    Across,
    /// Half a unit ([`PROFILE_LOCAL`]) either side of the fit.
    Near,
    /// Two standard errors either side of the fit.
    Fine,
}

/// The escalation's exponent profile runs when the fit's residual over all
/// points is at most this many times the noise ([`Adequacy::ratio`]). A fit
/// near the noise (or one that fits but for a fold, or a single level) can
/// be one exponent away from a basin that fits; a fit tens to hundreds of
/// times the noise is a model whose form misses its data, which no exponent
/// repairs (measured: the three beam sets, 37x, 59x and 628x the noise,
/// whose generalised fits the profile left unchanged at 1.2–1.5 s each;
/// the blind in-family misses it found were 1.16x and 8.9x). Either way the
/// flag is the self-check's: this only decides how far the search goes.
pub const PROFILE_MAX_RATIO: f64 = 20.0;

/// A fit of several levels that fits its noise but whose residual over all
/// points is above this ratio ([`Adequacy::ratio`]) gets the exponent
/// profile too (`profile_exponents`): its miss would be silent, the
/// self-check cannot tell 1.2x the truth's Eq 31 cost from noise (measured:
/// blind h046-mixed, seed 2711270093, two levels up without phase, ρ 5.80,
/// η 0.84: the fit ended at η 1.70, residual 1.19x the noise, 1.227x the
/// truth's cost; the profile's start from the landscape at η 0.35 reaches
/// its optimum). Set from 120 blind in-family fits that found their
/// optimum (seeds 2711270071/72): residual over the noise median 1.02, 90th
/// percentile 1.11; about 8 in 100 of those of several levels lie above
/// 1.1, and take the profile's time.
pub const PROFILE_NEAR_NOISE: f64 = 1.1;

/// Stage 8, escalation: each free exponent of `from` held in turn at up to
/// [`PROFILE_VALUES`] values across the landscape's axis (its coefficient
/// kept at its reference value, `β_ref` or `κ_ref`, so the held fit starts
/// with the same equivalent stiffness or damping at the largest amplitude;
/// and a second start from the landscape there, [`held_from_landscape`])
/// and the other parameters refitted; the two best held fits are then
/// refitted with the exponent free (and the best held [`PROFILE_LOCAL`]
/// from the fit; [`ProfileScope::Fine`]: the best held two standard errors
/// from it). A basin of the other exponent that no
/// landscape node reached and no random start found is one exponent away
/// from the fit: measured on a blind four-level set swept both ways
/// without phase, whose landscape pointed at η −0.78 and whose fit ended at
/// η 2.87 with one up-sweep's fold a step late (92x the truth's Eq 31
/// cost); held at η 1.24 every stage reaches the truth's cost. A term
/// that stage 5 removed from `from` (`removed_term`) is profiled too,
/// restored: from the landscape, and for the damping from `from` with half
/// its linear damping moved into the term (equal equivalent damping at the
/// reference amplitude); its freed fits keep the term. Measured on blind
/// h000-mixed (seed 2711270143: two levels up and down, no phase, η 0.55):
/// the race ended at η −1, stage 5 removed the term there and a freed gain
/// stood in for it, 1.074x the truth's Eq 31 cost within the noise; the
/// split start at η 0.35 reaches 1.003x (the landscape's ended 500x above
/// the fit: its equation-error starts had κ near 0). Returns the best freed
/// fit and the number of held fits.
fn profile_exponents(
    setup: &Setup,
    ex: &Exploration,
    work: &Dataset,
    from: &Fitted,
    scope: ProfileScope,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Option<(Fitted, usize)> {
    use rayon::prelude::*;
    let plan = setup.plan;
    let th = from.fit.theta;
    let sc = from.spec.scales;
    // (spec, its group: held fits compete for the freed refits within
    // their group, across the axis, half a unit from the fit, or two
    // standard errors from it)
    let mut jobs: Vec<(FitSpec, Held)> = Vec::new();
    for (coef, exp, axis, r) in [
        (KAPPA, ETA, &ex.land.eta, reference(ETA, &sc)),
        (BETA, RHO, &ex.land.rho, reference(RHO, &sc)),
    ] {
        if axis.len() < 2 {
            continue;
        }
        let every = axis.len().div_ceil(PROFILE_VALUES);
        // a term stage 5 removed (its exponent at a bound, or a copy of the
        // linear one, in the fit's basin) is tried again along its exponent:
        // from the landscape, where it is present, and for the damping from
        // the fit with half its linear damping moved into the term (the
        // equivalent damping at the reference amplitude kept)
        if removed_term(setup, from, coef, exp) {
            if scope != ProfileScope::Across {
                continue;
            }
            for (k, &v) in axis.iter().enumerate().step_by(every) {
                if coef == KAPPA && from.spec.status[DELTA] == Status::Free && th[DELTA] > 0.0 {
                    let mut t = th;
                    t[KAPPA] = equivalent_at_reference(0.5 * th[DELTA], 0.0, v, r);
                    t[DELTA] = 0.5 * th[DELTA];
                    t[ETA] = v;
                    if t[KAPPA].is_finite() && t[KAPPA] > 0.0 {
                        let mut spec = restarted(&from.spec, &t);
                        spec.status[KAPPA] = Status::Free;
                        spec.start[KAPPA] = t[KAPPA];
                        spec.status[ETA] = Status::Fixed(v);
                        spec.start[ETA] = v;
                        jobs.push((spec, Held::Across));
                    }
                }
                if let Some(spec) = held_from_landscape(setup, ex, work, from, exp, k) {
                    jobs.push((spec, Held::Across));
                }
            }
            continue;
        }
        if from.spec.status[exp] != Status::Free || th[coef] == 0.0 {
            continue;
        }
        // the axis in PROFILE_VALUES steps, and half a unit either side of
        // the fit (a neighbouring basin the coarse values step over)
        let (lo, hi) = (axis[0], axis[axis.len() - 1]);
        let coarse = axis
            .iter()
            .copied()
            .enumerate()
            .step_by(every)
            .filter(|_| scope == ProfileScope::Across)
            .map(|(k, v)| (k, v, Held::Across));
        let local = [th[exp] - PROFILE_LOCAL, th[exp] + PROFILE_LOCAL]
            .into_iter()
            .filter(|_| scope != ProfileScope::Fine)
            .filter(|v| *v >= lo && *v <= hi)
            .filter_map(|v| Some((nearest_index(axis, v)?, v, Held::Near)));
        for (k, v, group) in coarse.chain(local) {
            if (v - th[exp]).abs() < 0.25 {
                continue;
            }
            let mut t = th;
            t[coef] = equivalent_at_reference(th[coef], th[exp], v, r);
            t[exp] = v;
            if t[coef].is_finite() && t[coef] != 0.0 {
                let mut spec = restarted(&from.spec, &t);
                spec.status[exp] = Status::Fixed(v);
                jobs.push((spec, group));
            }
            if let Some(spec) = held_from_landscape(setup, ex, work, from, exp, k) {
                jobs.push((spec, group));
            }
        }
        // two standard errors either side of the fit (`ProfileScope::Fine`),
        // from the fit only (the landscape's nearest node is the fit's own)
        let sd = from
            .fit
            .uncertainty
            .as_ref()
            .filter(|_| scope == ProfileScope::Fine)
            .and_then(|u| u.index(PARAM_NAMES[exp]).map(|k| u.std_errors[k]));
        if let Some(sd) = sd.filter(|sd| 2.0 * sd > PROFILE_FINE_MIN && 2.0 * sd < 0.25) {
            for v in [th[exp] - 2.0 * sd, th[exp] + 2.0 * sd] {
                if v < lo || v > hi {
                    continue;
                }
                // from the equivalent coefficient at the reference
                // amplitude, and from the fit's own coefficient
                for scaled in [true, false] {
                    let mut t = th;
                    if scaled {
                        t[coef] = equivalent_at_reference(th[coef], th[exp], v, r);
                    }
                    t[exp] = v;
                    if t[coef].is_finite() && t[coef] != 0.0 {
                        let mut spec = restarted(&from.spec, &t);
                        spec.status[exp] = Status::Fixed(v);
                        jobs.push((spec, Held::Fine));
                    }
                }
            }
        }
    }
    if jobs.is_empty() {
        return None;
    }
    let held = jobs.len();
    let in_group = |g: Held| jobs.iter().filter(|j| j.1 == g).count();
    let to_free = in_group(Held::Across).min(PROFILE_FREED_ACROSS)
        + in_group(Held::Near).min(PROFILE_FREED_NEAR)
        + in_group(Held::Fine).min(PROFILE_FREED_FINE);
    progress(IdentifyProgress::Stage {
        name: "escalation: exponents held",
        steps: held + to_free,
    });
    let step = || progress(IdentifyProgress::Step);
    let opts = limited(&plan.lm, plan.seed, RACE_ITERATIONS);
    let mut fits: Vec<(Fitted, Held)> = jobs
        .into_par_iter()
        .filter_map(|(spec, group)| {
            let r = fit_impl(work, &spec, &opts, None, &step).ok()?;
            Some((Fitted::from_result(r, spec), group))
        })
        .collect();
    fits.sort_by(|a, b| a.0.objective.total_cmp(&b.0.objective));
    // the two best held across the axis, the best held half a unit from the
    // fit, and the best held two standard errors from it
    let best_of = |g: Held, n: usize| {
        fits.iter()
            .filter(move |f| f.1 == g)
            .take(n)
            .map(|f| f.0.clone())
    };
    let fits: Vec<Fitted> = best_of(Held::Across, PROFILE_FREED_ACROSS)
        .chain(best_of(Held::Near, PROFILE_FREED_NEAR))
        .chain(best_of(Held::Fine, PROFILE_FREED_FINE))
        .collect();
    let freed: Vec<Fitted> = fits
        .into_par_iter()
        .filter_map(|f| {
            let mut spec = restarted(&from.spec, &f.fit.theta);
            // a removed term its held fit restored stays, its exponent freed
            for (coef, exp) in [(KAPPA, ETA), (BETA, RHO)] {
                if removed_term(setup, from, coef, exp) && f.spec.status[coef] == Status::Free {
                    for j in [coef, exp] {
                        spec.status[j] = Status::Free;
                        spec.start[j] = f.fit.theta[j];
                    }
                }
            }
            let r = fit_impl(work, &spec, &opts, None, &step).ok()?;
            Some(Fitted::from_result(r, spec))
        })
        .collect();
    let mut best: Option<Fitted> = None;
    for f in freed {
        if better(&f, best.as_ref()) {
            best = Some(f);
        }
    }
    best.map(|b| (b, held))
}

/// `true` when `from` lacks the power-law term `(coef, exp)` that the plan
/// fits with both free: stage 5 removed it (`settle_terms`).
fn removed_term(setup: &Setup, from: &Fitted, coef: usize, exp: usize) -> bool {
    let plan = &setup.spec0.status;
    from.spec.status[exp] == Status::Absent
        && plan[exp] == Status::Free
        && plan[coef] == Status::Free
}

/// The second start of [`profile_exponents`] at the held value `axis[k]`
/// of exponent `exp`: the landscape's equation-error fit at the lowest node
/// of that line of the held axis (or of the nearest line with a solved
/// node, its coefficient rescaled to keep the equivalent stiffness or
/// damping at the reference amplitude), with the fit's sign, gain status
/// and readings. The start scaled from the fit keeps the fit's linear part
/// and folds, which can hold the held fit in the fit's basin: measured on
/// blind h013-mixed (seed 110808810) once the landscape's collapsed rows
/// were solved (stage 2), the race ended at η 0.40, 84x the truth's Eq 31
/// cost, and no start scaled from it reached the basin; from the
/// landscape's nodes the profile reaches 0.982x.
fn held_from_landscape(
    setup: &Setup,
    ex: &Exploration,
    work: &Dataset,
    from: &Fitted,
    exp: usize,
    k: usize,
) -> Option<FitSpec> {
    let land = &ex.land;
    let along_rho = exp == ETA;
    let (n_other, n_axis) = if along_rho {
        (land.rho.len(), land.eta.len())
    } else {
        (land.eta.len(), land.rho.len())
    };
    let lowest = |kk: usize| {
        (0..n_other)
            .map(|o| if along_rho { (o, kk) } else { (kk, o) })
            .filter(|&(i, j)| land.at(i, j).is_finite() && land.fit_at(i, j).is_some())
            .min_by(|&(a, b), &(c, d)| land.at(a, b).total_cmp(&land.at(c, d)))
    };
    let (i, j) = (0..n_axis)
        .flat_map(|d| [k.checked_sub(d), (d > 0).then_some(k + d)])
        .flatten()
        .filter(|&kk| kk < n_axis)
        .find_map(lowest)?;
    let mut ee = land.fit_at(i, j)?.clone();
    let gain = from.spec.status[GAIN];
    if let Status::Fixed(g) = gain {
        if (ee.theta[GAIN] - g).abs() > 1e-9 * g.abs() {
            ee = solve_held_gain(setup, ex, g, land.rho[i], land.eta[j]).ok()?;
        }
    }
    let sign = if from.fit.theta[BETA] < 0.0 {
        Sign::Softening
    } else {
        Sign::Hardening
    };
    let mut spec = candidate_spec(setup, work, &ee, sign, gain).ok()?;
    spec.censored = from.spec.censored.clone();
    let (v, coef) = if exp == ETA {
        (land.eta[k], KAPPA)
    } else {
        (land.rho[k], BETA)
    };
    let r = reference(exp, &spec.scales);
    let (e0, c0) = (spec.start[exp], spec.start[coef]);
    if e0 != v {
        let c = equivalent_at_reference(c0, e0, v, r);
        if !(c.is_finite() && c != 0.0) {
            return None;
        }
        spec.start[coef] = c;
    }
    spec.status[exp] = Status::Fixed(v);
    spec.start[exp] = v;
    Some(spec)
}

/// The reference of exponent `exp`'s power law: the largest measured
/// amplitude `A_ref` for ρ, `Ω_ref A_ref` for η.
fn reference(exp: usize, sc: &super::objective::Scales) -> f64 {
    if exp == ETA {
        sc.a_ref * sc.omega_ref
    } else {
        sc.a_ref
    }
}

/// The coefficient that, with exponent `to`, has the equivalent (first
/// harmonic) coefficient `c` has with exponent `from` at the reference `r`:
/// `c g(from) r^from / (g(to) r^to)`.
fn equivalent_at_reference(c: f64, from: f64, to: f64, r: f64) -> f64 {
    use crate::power_law::g_unchecked;
    c * g_unchecked(from) * r.powf(from) / (g_unchecked(to) * r.powf(to))
}

/// Fewest points per level a subsample aims to keep: data with more levels
/// than `max / SUBSAMPLE_POINTS_PER_LEVEL` are thinned by level first.
pub const SUBSAMPLE_POINTS_PER_LEVEL: usize = 20;

/// Regular subsample of at most `max` points per data set (all if smaller),
/// keeping every curve's first and last point. Data with more levels than
/// `max / SUBSAMPLE_POINTS_PER_LEVEL` (at least 2) keep that many levels,
/// evenly spaced in the order the levels first appear (the first and last
/// kept; every curve of a kept level, up and down alike), so that each kept
/// curve still has points between its ends: without it, 5000 levels of 200
/// steps kept only their two end points each, more than 10,000 points whose
/// every curve still needed a fold search at each evaluation (a nonlinear
/// set of that shape did not finish in 7 min). Sets of up to 75 levels (the
/// default 1500 points) are not thinned by level.
fn subsample(data: &Dataset, max: usize) -> Dataset {
    let n = data.len();
    if n <= max || max == 0 {
        return data.clone();
    }
    let mut seen = std::collections::HashSet::new();
    let levels: Vec<&str> = data
        .curves
        .iter()
        .map(|c| c.level.as_str())
        .filter(|l| seen.insert(*l))
        .collect();
    let cap = (max / SUBSAMPLE_POINTS_PER_LEVEL).max(2);
    let mut out = if levels.len() > cap {
        let kept: std::collections::HashSet<&str> = (0..cap)
            .map(|k| levels[(k * (levels.len() - 1) + (cap - 1) / 2) / (cap - 1)])
            .collect();
        Dataset {
            curves: data
                .curves
                .iter()
                .filter(|c| kept.contains(c.level.as_str()))
                .cloned()
                .collect(),
        }
    } else {
        data.clone()
    };
    let n = out.len();
    if n <= max {
        return out;
    }
    let stride = n.div_ceil(max);
    for c in &mut out.curves {
        let m = c.omegas.len();
        let keep: Vec<usize> = (0..m).filter(|&i| i % stride == 0 || i + 1 == m).collect();
        let pick = |v: &Vec<f64>| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        c.omegas = pick(&c.omegas);
        c.amplitudes = pick(&c.amplitudes);
        c.weights = pick(&c.weights);
        if let Some(p) = &c.phases {
            c.phases = Some(pick(p));
        }
    }
    out
}

fn exponent_axis(
    status: Status,
    bounds: (f64, f64),
    n: usize,
    integer: bool,
    present: bool,
) -> Axis {
    if !present {
        return Axis::single(0.0);
    }
    match status {
        Status::Fixed(v) => Axis::single(v),
        Status::Absent => Axis::single(0.0),
        Status::Free => {
            if integer {
                let lo = bounds.0.ceil().max(-2.0);
                let hi = bounds.1.floor().max(lo);
                Axis {
                    min: lo,
                    max: hi,
                    n: (hi - lo) as usize + 1,
                }
            } else {
                Axis {
                    min: bounds.0,
                    max: bounds.1,
                    n,
                }
            }
        }
    }
}

/// Multiplies every weight by `(K γ_c / max(a, a_peak,c/100))²`,
/// `K = max_c a_peak,c/γ_c` ([`Weighting::Relative`]).
fn relative_weights(data: &mut Dataset) {
    let peak = |c: &super::data::Curve| c.amplitudes.iter().fold(0.0f64, |m, &a| m.max(a));
    let k = data
        .curves
        .iter()
        .map(|c| peak(c) / c.gamma)
        .fold(0.0f64, f64::max);
    if !(k.is_finite() && k > 0.0) {
        return;
    }
    for c in &mut data.curves {
        let floor = RELATIVE_FLOOR * peak(c);
        if !(floor > 0.0) {
            continue;
        }
        for (w, &a) in c.weights.iter_mut().zip(&c.amplitudes) {
            *w *= (k * c.gamma / a.max(floor)).powi(2);
        }
    }
}

/// The landscape nodes refined by output error: the best `refine` grid
/// minima, then (diversity) the best node of each third of every free
/// exponent's range that is not yet a candidate. Where the landscape is
/// flat along an exponent (the data barely constrain it, as the damping
/// exponent of the clamped beam) its grid minima all lie in one place, and
/// the output error can then run into a degenerate corner (e.g. Coulomb
/// friction that holds the mass); starts spread over the range let it
/// compare.
fn candidate_nodes(land: &Landscape, refine: usize) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = land.minima.iter().take(refine).copied().collect();
    let (nr, ne) = (land.rho.len(), land.eta.len());
    for axis in 0..2 {
        let n = if axis == 0 { nr } else { ne };
        if n < 3 {
            continue;
        }
        for band in 0..3 {
            let (lo, hi) = (band * n / 3, ((band + 1) * n / 3).max(band * n / 3 + 1));
            let mut best: Option<((usize, usize), f64)> = None;
            for k in lo..hi {
                for o in 0..if axis == 0 { ne } else { nr } {
                    let (i, j) = if axis == 0 { (k, o) } else { (o, k) };
                    let c = land.at(i, j);
                    if c.is_finite() && best.map_or(true, |(_, b)| c < b) {
                        best = Some(((i, j), c));
                    }
                }
            }
            if let Some((node, _)) = best {
                if !out.contains(&node) {
                    out.push(node);
                }
            }
        }
    }
    out
}

/// Sets the output-error start from an equation-error fit (clamped into the
/// bounds; exponents fixed at integer nodes when `integer`).
fn start_from(spec: &mut FitSpec, ee: &EquationErrorFit, integer: bool) {
    let sc = spec.scales;
    for j in 0..N_PARAMS {
        if spec.status[j] != Status::Free {
            continue;
        }
        let v = ee.theta[j];
        let (lo, hi) = spec.bounds[j];
        spec.start[j] = match j {
            BETA => {
                let s = spec.stiffness_sign.factor();
                let rho = ee.theta[RHO];
                let g = crate::power_law::g_unchecked(rho) * sc.a_ref.powf(rho);
                let mag = (v * g).abs().clamp(lo * 1.0001, hi * 0.9999);
                // β_ref magnitude with the plan's sign
                s * mag / g
            }
            KAPPA => {
                let eta = ee.theta[ETA];
                let g = crate::power_law::g_unchecked(eta) * (sc.omega_ref * sc.a_ref).powf(eta);
                (v * g).clamp(lo * 1.0001, hi * 0.9999) / g
            }
            _ => v.clamp(
                if lo > 0.0 { lo * 1.0001 } else { lo },
                if hi > 0.0 { hi * 0.9999 } else { hi },
            ),
        };
    }
    if integer {
        for j in [RHO, ETA] {
            if spec.status[j] == Status::Free {
                spec.status[j] = Status::Fixed(ee.theta[j]);
                spec.start[j] = ee.theta[j];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Oracle: a hand-made 3 x 3 landscape, the nearest node on each axis
    /// by inspection, the lowest-cost node along the axis not given.
    #[test]
    fn nearest_node_picks_the_closest_and_the_best_along() {
        let land = Landscape {
            rho: vec![0.0, 1.0, 2.0],
            eta: vec![-1.0, 0.0, 1.0],
            // cost[j * 3 + i] at (rho[i], eta[j])
            cost: vec![5.0, 4.0, 3.0, 6.0, 1.0, f64::NAN, 7.0, 2.0, 0.5],
            fits: vec![None; 9],
            minima: vec![(2, 2)],
            with_phase: false,
        };
        let at = |rho, eta| nearest_node(&land, &ExponentStart { rho, eta });
        assert_eq!(at(Some(1.4), Some(-0.6)), Some((1, 0)));
        assert_eq!(at(Some(-3.0), Some(9.0)), Some((0, 2)));
        // rho 1 given: along eta the lowest cost at i = 1 is 1.0 (j = 1)
        assert_eq!(at(Some(0.9), None), Some((1, 1)));
        // eta 0 given: along rho at j = 1, rho = 2 is unsolved, rho = 1 wins
        assert_eq!(at(None, Some(0.2)), Some((1, 1)));
        // the nearest node unsolved: no start
        assert_eq!(at(Some(2.0), Some(0.0)), None);
        assert_eq!(at(None, None), None);
        assert_eq!(at(Some(f64::NAN), Some(0.0)), None);
    }
    use crate::identification::Curve;
    use crate::SweepDirection;

    fn levels(n_levels: usize, steps: usize) -> Dataset {
        let mut curves = Vec::new();
        for l in 0..n_levels {
            for direction in [SweepDirection::Up, SweepDirection::Down] {
                curves.push(Curve {
                    level: format!("L{l}"),
                    gamma: 0.1 + l as f64,
                    direction,
                    omegas: (0..steps).map(|i| 50.0 + i as f64).collect(),
                    amplitudes: vec![1e-3; steps],
                    phases: None,
                    weights: vec![1.0; steps],
                });
            }
        }
        Dataset { curves }
    }

    /// Oracle: central differences. The Jacobian of [`FoldsHeld`] (the
    /// output error's rows and the held fold's row, `fold_gradient`) in the
    /// optimisation variables, on one hardening up-sweep of the model
    /// itself with a jump.
    #[test]
    fn held_fold_jacobian_matches_differences() {
        use super::super::levenberg_marquardt::LeastSquares;
        use super::super::objective::{model_amplitudes, Problem};
        let wn = 2.0 * std::f64::consts::PI * 10.0;
        let (rho, eta, a_ref): (f64, f64, f64) = (2.6, 1.7, 0.01);
        let beta = 0.08 * wn * wn / (crate::power_law::g_unchecked(rho) * a_ref.powf(rho));
        let kappa = 0.8 * 0.02 * wn / (crate::power_law::g_unchecked(eta) * (wn * a_ref).powf(eta));
        let theta =
            super::super::Parameters::from([wn * wn, 0.02 * wn, beta, rho, kappa, eta, 1.0]);
        let n = 120;
        let omegas: Vec<f64> = (0..n)
            .map(|i| 2.0 * std::f64::consts::PI * (8.0 + 10.0 * i as f64 / (n - 1) as f64))
            .collect();
        let mut data = Dataset {
            curves: vec![Curve {
                level: "L".into(),
                gamma: 3.0,
                direction: SweepDirection::Up,
                omegas,
                amplitudes: vec![1.0; n],
                phases: None,
                weights: vec![1.0; n],
            }],
        };
        let model = model_amplitudes(&data, &theta).unwrap();
        // measured 1 % off the model, so the residuals are not zero
        data.curves[0].amplitudes = model[0]
            .iter()
            .enumerate()
            .map(|(i, a)| a * (1.0 + 0.01 * ((i % 7) as f64 - 3.0) / 3.0))
            .collect();
        let spec = FitSpec::new(ModelKind::Generalised, &data);
        let problem = Problem::new(&data, &spec).unwrap();
        let (_, m) = evaluate_measured(&data, &theta, false, &MatchOptions::of(&spec)).unwrap();
        let (wf, _) = m[0].fold.expect("the up-sweep jumps");
        let held = FoldsHeld {
            problem: &problem,
            folds: vec![(0, wf * 0.999, 0.01 * wf)],
            scale: 3.0,
        };
        let u = problem.u_of(&theta);
        let (r, j) = held.residuals_and_jacobian(&u).unwrap();
        let p = u.len();
        assert_eq!(j.len(), r.len() * p);
        let fold_row = r.len() - 1;
        assert!(r[fold_row] != 0.0);
        for k in 0..p {
            let h = 1e-6 * u[k].abs().max(1e-3);
            let (mut up, mut dn) = (u.clone(), u.clone());
            up[k] += h;
            dn[k] -= h;
            let (rp, rm) = (held.residuals(&up).unwrap(), held.residuals(&dn).unwrap());
            for row in [fold_row, 0, n / 2] {
                let fd = (rp[row] - rm[row]) / (2.0 * h);
                let an = j[row * p + k];
                let tol = 1e-4 * an.abs().max(fd.abs()) + 1e-9 * r[row].abs().max(1.0);
                assert!(
                    (fd - an).abs() <= tol,
                    "row {row} column {k}: fd {fd} analytic {an}"
                );
            }
        }
    }

    /// Many levels are thinned by level (evenly, the extreme levels and
    /// both directions of each kept level kept), so that every kept curve
    /// keeps points between its ends; few levels are only thinned by point.
    #[test]
    fn subsample_thins_many_levels_by_level_first() {
        let data = levels(2500, 200);
        let sub = subsample(&data, 1500);
        let cap = 1500 / SUBSAMPLE_POINTS_PER_LEVEL;
        assert_eq!(sub.curves.len(), 2 * cap);
        assert!(sub.len() <= 1500 + 2 * sub.curves.len(), "{}", sub.len());
        assert_eq!(sub.curves[0].level, "L0");
        assert_eq!(sub.curves[sub.curves.len() - 1].level, "L2499");
        for pair in sub.curves.chunks(2) {
            assert_eq!(pair[0].level, pair[1].level);
            assert_ne!(pair[0].direction, pair[1].direction);
        }
        for c in &sub.curves {
            assert!(c.omegas.len() >= 10, "{} points", c.omegas.len());
            assert_eq!(c.omegas[0], 50.0);
            assert_eq!(c.omegas[c.omegas.len() - 1], 249.0);
        }
        // 18 levels (the cantilever's count): every level kept
        let data = levels(18, 1024);
        let sub = subsample(&data, 1500);
        assert_eq!(sub.curves.len(), 36);
        assert!(sub.len() <= 1500 + 36);
    }
}
