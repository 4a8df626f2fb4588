//! [`identify`]: the one entry point of a stepped-sine identification —
//! data in, a [`FitPlan`] (model family, what is fixed, sign, integer or
//! real exponents, gain, phase, jumps), a typed [`Identification`] out.
//! The CLI and the Python module only parse and render.
//!
//! ## Stages
//! 1. **Equation error, branch free** ([`super::equation_error`]): every
//!    measured point satisfies the first-order HB equations whichever branch
//!    it is on. With phase (used by default when every curve has it) the
//!    phase convention — lag or lead and a constant offset — is detected
//!    from the data through a complex gain; the equations are then linear
//!    least squares at fixed exponents.
//! 2. **Exponent landscape** ([`super::landscape`]): the equation-error cost
//!    profiled over a `(ρ, η)` grid of the free exponents (coefficients
//!    optimised at each node); its grid minima, best first, are the
//!    candidates. Integer exponents ([`ExponentChoice::Integer`]) use the
//!    integer nodes only. Profile-likelihood intervals of the exponents come
//!    from the same map.
//! 3. **Choices from the data.** The stiffness sign is the sign of the
//!    equation-error β of each candidate ([`SignChoice::Auto`]). The forcing
//!    gain (a point of a base-excited continuous structure sees `gain·γ`) is
//!    freed ([`GainChoice::Auto`]) when freeing it lowers the equation-error
//!    cost significantly: `F = (C₁ − C_G)/(C_G/(n − p)) > 10.83` (the χ²₁
//!    0.1 % point) at the best node and the estimate lies inside its
//!    bounds. Jump residuals ([`super::jumps`]) are added
//!    ([`JumpChoice::Auto`], λ = [`AUTO_JUMP_WEIGHT`]) when an up-sweep
//!    shows a measured jump.
//! 4. **Output error** (Eq 31, branch following, plus phase residuals
//!    when phase is used — [`super::objective::evaluate_with_phase`]): from
//!    each of the best `refine` candidates (in parallel) — its equation
//!    error solved again with the gain the test decided, then the
//!    branch-free output error ([`ResponseBranch::Nearest`]: each point
//!    against the model's nearest stable state, at most
//!    [`NEAREST_ITERATIONS`]), then Eq 31 with the jump residuals from that
//!    optimum, at most [`RACE_ITERATIONS`] LM iterations each. The lowest
//!    objective wins (a converged fit only breaks a near tie), and a winner
//!    stopped by its iteration limit is continued once; data longer than
//!    `refine_points` are then refined on all points
//!    ([`FitPlan::refine_points`]). Residuals are Eq 31's, or relative ones
//!    ([`Weighting`]). The result says whether it converged, which
//!    parameters sit at bounds and which the data cannot separate
//!    ([`super::FitResult::warning`]).
//!
//! ## Which branch a model point is compared with
//! The model's sweep follows its own branch in the measured direction and
//! jumps at its own fold ([`super::objective::model_amplitudes`]). Real
//! sweeps leave the upper branch *before* the fold (any disturbance near
//! the fold is enough); the measured points between the measured jump and
//! the model's fold are then compared with the model's upper branch, and
//! the misfit there pulls the model's fold down towards the measured jump.
//! The jump residual states that pull explicitly and continuously. Nothing
//! in the model family makes a sweep leave early, so on such data the model
//! fold ends up between the two, and the residuals show it (see the beam
//! tables in docs/identification.md).

use super::data::Dataset;
use super::equation_error::{
    solve_magnitude, solve_phase, wrap, EquationErrorError, EquationErrorFit, PhaseConvention,
    Prepared, Terms,
};
use super::landscape::{
    landscape_with_progress, Axis, Landscape, LandscapeError, LandscapePhase, ProfileInterval,
};
use super::levenberg_marquardt::{LmOptions, Termination};
use super::models::*;
use super::objective::{FitSpec, ResponseBranch, Sign, SpecError, Status};
use super::{fit_impl, FitError, FitOptions, FitResult};

/// Fraction of a curve's peak below which [`Weighting::Relative`] counts
/// an amplitude as this fraction of the peak.
pub const RELATIVE_FLOOR: f64 = 0.01;

/// λ of the automatic jump residuals ([`JumpChoice::Auto`]): a 1 % error
/// of a jump frequency costs as much as an error of 10 % of the curve's
/// peak at every step of it. A sweep places its jump to within one step
/// (0.03–0.1 % on the beam sets), far more precisely than a first-order
/// model matches real amplitudes (10–25 % of the peak on the beams).
/// Raised from 10 in the sixth session after measuring on the 24 °C clamped
/// beam (worst jump error +3.59 % at 10, +2.37 % at 100; synthetic suite 98
/// and 97 of 100): see docs/identification.md.
pub const AUTO_JUMP_WEIGHT: f64 = 100.0;

/// Most LM iterations of the all-point refinement that follows the
/// subsampled candidate refinement (see [`FitPlan::refine_points`]).
pub const POLISH_ITERATIONS: usize = 25;

/// Most LM iterations of the branch-free output-error stage
/// ([`ResponseBranch::Nearest`]) that seeds each candidate's Eq 31 fit: it
/// is a start, and on real data it can crawl.
pub const NEAREST_ITERATIONS: usize = 30;

/// Most LM iterations of each candidate's Eq 31 fit: the candidates race,
/// and only the winner, if stopped by this limit, continues (for up to
/// `2 × lm.max_iterations − RACE_ITERATIONS` more, so that its total
/// budget is the `2 × lm.max_iterations` of a candidate and its one
/// continuation before the race). On the 24 °C clamped beam the
/// losing candidates of the generalised fit ran 100 iterations each.
pub const RACE_ITERATIONS: usize = 30;

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

/// F threshold for freeing the gain (χ²₁ 0.1 % point).
pub const GAIN_F_THRESHOLD: f64 = 10.83;

/// Stiffness sign.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SignChoice {
    /// From the equation-error estimate of each candidate.
    #[default]
    Auto,
    Hardening,
    Softening,
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

/// Jump residuals.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum JumpChoice {
    /// λ = [`AUTO_JUMP_WEIGHT`] when an up-sweep has a measured jump.
    #[default]
    Auto,
    Off,
    Weight(f64),
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
    /// Weighting of the output-error residuals.
    pub weighting: Weighting,
    /// Landscape nodes `(n_ρ, n_η)` over the exponents' bounds.
    pub grid: (usize, usize),
    /// Candidates refined by output error.
    pub refine: usize,
    /// Extra global-search starts per refinement (1 = none).
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
            weighting: Weighting::Absolute,
            grid: (41, 41),
            refine: 3,
            starts: 1,
            seed: 1,
            lm: LmOptions::default(),
            landscape_points: 2000,
            refine_points: 1500,
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
}

/// The gain decision of [`GainChoice::Auto`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainTest {
    /// Equation-error gain estimate.
    pub gain: f64,
    /// F statistic of freeing it.
    pub f_statistic: f64,
    pub freed: bool,
}

/// One refined candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub rho: f64,
    pub eta: f64,
    /// Equation-error cost at the node.
    pub ee_cost: f64,
    /// Sign used for it.
    pub sign: Sign,
    /// Objective minimised by output error (incl. jump/phase terms), or the error.
    pub oe: Result<f64, String>,
}

/// Progress of [`identify`], for a progress bar: each stage announces
/// itself with the number of steps it will report, then reports them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdentifyProgress {
    /// A stage begins: `"landscape"` (one step per row of the exponent
    /// grid), `"output error"` (one step per refined start), `"judging on
    /// all points"` (one step).
    Stage { name: &'static str, steps: usize },
    /// One step of the current stage is done.
    Step,
}

/// The outcome of [`identify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// The final output-error fit.
    pub fit: FitResult,
    /// The structure it was fitted with (sign, gain status, phase weight).
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
    /// λ of the jump residuals (0 = none).
    pub jump_weight: f64,
    pub candidates: Vec<Candidate>,
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

/// Runs the whole identification (module docs).
pub fn identify(
    data: &Dataset,
    plan: &FitPlan,
    progress: &(dyn Fn(IdentifyProgress) + Sync),
) -> Result<Identification, IdentifyError> {
    let step = || progress(IdentifyProgress::Step);
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
    // the structure before any data-driven choice
    let configure = |sign: Sign| -> Result<FitSpec, IdentifyError> {
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
        Ok(s)
    };
    let spec0 = configure(Sign::Hardening)?;
    let scales = spec0.scales;
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
    let prep = Prepared::new(&sub, scales)?;
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
    let terms_free = Terms {
        stiffness: stiff,
        damping: damp,
        gain: gain_fixed,
    };
    // landscape with the gain free (Auto), falling back to gain = 1
    progress(IdentifyProgress::Stage {
        name: "landscape",
        steps: eta_axis.n.max(1),
    });
    let land =
        match landscape_with_progress(&prep, terms_free, rho_axis, eta_axis, phase_mode, &step) {
            Ok(l) => l,
            Err(e) if plan.gain == GainChoice::Auto => {
                let t = Terms {
                    gain: Some(1.0),
                    ..terms_free
                };
                progress(IdentifyProgress::Stage {
                    name: "landscape",
                    steps: eta_axis.n.max(1),
                });
                landscape_with_progress(&prep, t, rho_axis, eta_axis, phase_mode, &step)
                    .map_err(|_| e)?
            }
            Err(e) => return Err(e.into()),
        };
    let (bi, bj) = land
        .best()
        .ok_or_else(|| IdentifyError::NoCandidate("empty landscape".into()))?;
    let best_ee = land.fit_at(bi, bj).expect("best node solved").clone();
    // (nodes the data cannot separate are not in the landscape's minima)
    let phase_conv = best_ee.phase;
    // the equation error at node (ρ, η) with the gain held at `g`
    let solve_held_gain = |g: f64, rho: f64, eta: f64| {
        let terms = Terms {
            gain: Some(g),
            ..terms_free
        };
        match phase_mode {
            LandscapePhase::Ignore => solve_magnitude(&prep, terms, rho, eta, None).map(|x| x.0),
            _ => solve_phase(
                &prep,
                terms,
                rho,
                eta,
                phase_conv,
                phase_conv.map_or(0.0, |c| c.delay),
            ),
        }
    };
    // gain decision
    let mut gain_test = None;
    let gain_status = match plan.gain {
        GainChoice::Fixed(g) => Status::Fixed(g),
        GainChoice::Free => Status::Free,
        GainChoice::Auto => {
            let (rho, eta) = (land.rho[bi], land.eta[bj]);
            let fixed = solve_held_gain(1.0, rho, eta);
            let free_gain = best_ee.theta[GAIN];
            let (lo, hi) = spec0.bounds[GAIN];
            let dof = best_ee
                .n_residuals
                .saturating_sub(best_ee.n_unknowns)
                .max(1) as f64;
            let f = match (&fixed, land.fit_at(bi, bj)) {
                (Ok(fx), Some(fr)) if fr.n_unknowns > fx.n_unknowns => {
                    (fx.cost - fr.cost) / (fr.cost / dof).max(f64::MIN_POSITIVE)
                }
                _ => 0.0,
            };
            let freed = f > GAIN_F_THRESHOLD && free_gain > lo && free_gain < hi;
            gain_test = Some(GainTest {
                gain: free_gain,
                f_statistic: f,
                freed,
            });
            if freed {
                Status::Free
            } else {
                Status::Fixed(1.0)
            }
        }
    };
    // data as fitted
    let mut fit_data = data.clone();
    let use_phase = !matches!(phase_mode, LandscapePhase::Ignore);
    for c in &mut fit_data.curves {
        match (&mut c.phases, use_phase, phase_conv) {
            (Some(p), true, Some(conv)) => {
                for (k, v) in p.iter_mut().enumerate() {
                    *v = wrap(conv.lag(*v, c.omegas[k]));
                }
            }
            _ => c.phases = None,
        }
    }
    if plan.weighting == Weighting::Relative {
        relative_weights(&mut fit_data);
    }
    let jump_weight = match plan.jumps {
        JumpChoice::Off => 0.0,
        JumpChoice::Weight(w) => w,
        JumpChoice::Auto => {
            if super::jumps::jump_targets(&fit_data).is_empty() {
                0.0
            } else {
                AUTO_JUMP_WEIGHT
            }
        }
    };
    // refine the best candidates
    let opts = FitOptions {
        starts: plan.starts.max(1),
        seed: plan.seed,
        lm: plan.lm,
    };
    let refine_data = subsample(&fit_data, plan.refine_points);
    let polish = refine_data.len() < fit_data.len();
    // Each candidate is refined independently (in parallel); the winner is
    // chosen in candidate order, so the result does not depend on the
    // number of threads.
    use rayon::prelude::*;
    type Refined = (Candidate, Option<(FitResult, FitSpec, f64)>);
    let nodes = candidate_nodes(&land, plan.refine.max(1));
    // The landscape's nodes were solved with the gain free. When the gain
    // test held it (at 1, or the plan fixed it), each candidate's equation
    // error is solved again with that gain before it seeds the output
    // error: without phase, δ, κ and the gain trade along a ridge, and a
    // free-gain start (e.g. gain 43 with δ = 0) is far from the held-gain
    // optimum (measured on a synthetic softening case: the output error
    // from the free-gain start ended at ρ = 0 with α 79 % off).
    let with_gain_decided = |i: usize, j: usize, ee: &EquationErrorFit| -> EquationErrorFit {
        match gain_status {
            Status::Fixed(g) if (ee.theta[GAIN] - g).abs() > 1e-9 * g.abs() => {
                let held = solve_held_gain(g, land.rho[i], land.eta[j]);
                held.unwrap_or_else(|_| ee.clone())
            }
            _ => ee.clone(),
        }
    };
    progress(IdentifyProgress::Stage {
        name: "output error",
        steps: nodes.len() * opts.starts,
    });
    let refined: Vec<Result<Refined, IdentifyError>> = nodes
        .into_par_iter()
        .filter_map(|(i, j)| land.fit_at(i, j).map(|ee| (i, j, ee)))
        .map(|(i, j, ee)| (i, j, with_gain_decided(i, j, ee)))
        .map(|(i, j, ee)| {
            let ee = &ee;
            let sign = match plan.sign {
                SignChoice::Hardening => Sign::Hardening,
                SignChoice::Softening => Sign::Softening,
                SignChoice::Auto => {
                    if ee.theta[BETA] < 0.0 {
                        Sign::Softening
                    } else {
                        Sign::Hardening
                    }
                }
            };
            let mut spec = configure(sign)?;
            spec.status[GAIN] = gain_status;
            if let Status::Fixed(g) = gain_status {
                spec.start[GAIN] = g;
            }
            spec.phase_weight = use_phase.then_some(plan.phase_weight);
            // Softening: `|β_ref| < α` keeps the backbone frequency real at
            // A_ref. The default bound `0.95 α₀` uses the peak-based α₀,
            // which strong softening pulls below α (11 % on a synthetic
            // case, whose truth the bound then excluded); the candidate's
            // equation-error α (inside α's bounds) is the better estimate,
            // so the bound is raised to 0.95 of it when that is larger (not
            // when the plan sets β's bounds).
            let user_beta_bounds = plan.bounds.iter().any(|(n, _, _)| n == "beta");
            if sign == Sign::Softening && spec.status[BETA] == Status::Free && !user_beta_bounds {
                let alpha = ee.theta[ALPHA].min(spec.bounds[ALPHA].1);
                spec.bounds[BETA].1 = spec.bounds[BETA].1.max(0.95 * alpha);
            }
            start_from(&mut spec, ee, integer);
            // Branch-free output error first (each point against the
            // model's nearest stable state: continuous where Eq 31 jumps
            // when a model fold crosses a measured step), then Eq 31 with
            // the jump residuals from its optimum.
            let mut free_branch = spec.clone();
            free_branch.branch = ResponseBranch::Nearest;
            // (one start: it only seeds the Eq 31 fit, which runs the
            // plan's `starts`)
            let mut nearest_opts = FitOptions {
                starts: 1,
                ..opts.clone()
            };
            nearest_opts.lm.max_iterations = nearest_opts.lm.max_iterations.min(NEAREST_ITERATIONS);
            if let Ok(r) = fit_impl(&refine_data, &free_branch, &nearest_opts, None, &|| {}) {
                for j in spec.free_indices() {
                    spec.start[j] = r.theta[j];
                }
            }
            let mut race = opts.clone();
            race.lm.max_iterations = race.lm.max_iterations.min(RACE_ITERATIONS);
            let res = fit_impl(
                &refine_data,
                &spec,
                &race,
                (jump_weight > 0.0).then_some(jump_weight),
                &step,
            );
            let oe = match &res {
                Ok(r) => Ok(r.minima.first().map_or(r.cost, |m| m.cost)),
                Err(e) => Err(e.to_string()),
            };
            let cand = Candidate {
                rho: land.rho[i],
                eta: land.eta[j],
                ee_cost: land.at(i, j),
                sign,
                oe: oe.clone(),
            };
            let kept = match (res, oe) {
                (Ok(r), Ok(c)) => Some((r, spec, c)),
                _ => None,
            };
            Ok((cand, kept))
        })
        .collect();
    let mut candidates = Vec::new();
    let mut best: Option<(FitResult, FitSpec, f64)> = None;
    let mut last_err = String::new();
    for r in refined {
        let (cand, kept) = r?;
        if let Err(e) = &cand.oe {
            last_err = e.clone();
        }
        candidates.push(cand);
        if let Some((r, spec, c)) = kept {
            // the lower objective wins; a converged fit wins a near tie
            let better = match &best {
                None => true,
                Some((b, _, bc)) => {
                    let tie = (c - *bc).abs() <= 1e-6 * bc.abs().max(c.abs());
                    if tie {
                        r.converged && !b.converged
                    } else {
                        c < *bc
                    }
                }
            };
            if better {
                best = Some((r, spec, c));
            }
        }
    }
    // A winner that stopped on its iteration limit (the race's, or a long
    // flat valley, as an exponent the data barely determine) is continued
    // once from where it stopped; the continuation is kept when it is not
    // worse.
    if let Some((r, spec, c)) = &best {
        if !r.converged && (r.termination == Termination::MaxIterations || r.at_bounds.is_empty()) {
            let mut opts = opts.clone();
            let raced = opts.lm.max_iterations.min(RACE_ITERATIONS);
            opts.lm.max_iterations = 2 * opts.lm.max_iterations - raced;
            let mut spec2 = spec.clone();
            for j in spec2.free_indices() {
                spec2.start[j] = r.theta[j];
            }
            progress(IdentifyProgress::Stage {
                name: "output error, best candidate continued",
                steps: opts.starts,
            });
            if let Ok(r2) = fit_impl(
                &refine_data,
                &spec2,
                &opts,
                (jump_weight > 0.0).then_some(jump_weight),
                &step,
            ) {
                let c2 = r2.minima.first().map_or(r2.cost, |m| m.cost);
                if c2 <= *c {
                    best = Some((r2, spec2, c2));
                }
            }
        }
    }
    let (mut fit, spec, _) = best.ok_or(IdentifyError::NoCandidate(last_err))?;
    if polish {
        // The candidates were refined on a subsample (every `stride`-th
        // step) for speed. The winner is refined again on every point from
        // where it stopped (up to `POLISH_MAX_POINTS` points), at most
        // `POLISH_ITERATIONS` LM iterations, so
        // that the estimate uses all the data (on 400-step synthetic sweeps
        // the subsample alone left ρ up to 18 Cramér–Rao deviations off).
        // That refinement is kept when it converges; otherwise (real data
        // whose jumps lie between model folds make the all-point Eq 31
        // cost crawl) the subsample's optimum is judged on every point.
        progress(IdentifyProgress::Stage {
            name: "output error on all points",
            steps: 1,
        });
        let mut spec_all = spec.clone();
        for j in spec_all.free_indices() {
            spec_all.start[j] = fit.theta[j];
        }
        let mut single = FitOptions { starts: 1, ..opts };
        single.lm.max_iterations = single.lm.max_iterations.min(POLISH_ITERATIONS);
        single.lm.ftol = single.lm.ftol.max(POLISH_FTOL);
        let all = (fit_data.len() <= POLISH_MAX_POINTS)
            .then(|| {
                fit_impl(
                    &fit_data,
                    &spec_all,
                    &single,
                    (jump_weight > 0.0).then_some(jump_weight),
                    &|| {},
                )
                .ok()
            })
            .flatten();
        fit = match all {
            Some(r) if r.converged => r,
            _ => {
                let free = spec.free_indices();
                super::assess(
                    &fit_data,
                    &spec,
                    &free,
                    fit.theta,
                    fit.termination,
                    fit.iterations,
                    fit.minima.clone(),
                    fit.at_bounds.clone(),
                )?
            }
        };
        step();
    }
    Ok(Identification {
        fit,
        spec,
        data: fit_data,
        rho_profile: land.profile_interval(0),
        eta_profile: land.profile_interval(1),
        equation_error: best_ee,
        landscape: land,
        phase: if use_phase { phase_conv } else { None },
        gain_test,
        jump_weight,
        candidates,
    })
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
