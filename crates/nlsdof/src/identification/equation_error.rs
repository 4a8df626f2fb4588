//! Branch-free equation-error estimator: the first stage of every sweep fit.
//!
//! ## Why
//! Eq 31 compares amplitudes on the branch the model's sweep follows. It is
//! piecewise constant in the jump locations and has many basins, so a local
//! solver on it needs a start that is already right. The first-order
//! harmonic-balance equations give one: **every** measured point
//! `(Ω, a, γ[, φ])` satisfies them, whichever branch (upper, lower, or even
//! an unstable one) it lies on, so no branch has to be followed.
//!
//! ## The equations (paper Eq 9, 22, 29 under `x = a cos(Ωt − φ)`)
//! With `S = α + g(ρ) β |a|^ρ − Ω²` and `D = δ + g(η) κ |Ω a|^η`:
//!
//! ```text
//! with phase:     S a = G γ cos φ,        Ω D a = G γ sin φ
//! without phase:  a² [ S² + Ω² D² ] = (G γ)²
//! ```
//!
//! For fixed exponents `(ρ, η)` the phase form is **linear** least squares
//! in `(α, β, δ, κ, G)`, solved in closed form ([`solve_phase`]). Without
//! phase the residual `r = a √(S² + Ω² D²) / (G γ) − 1` (relative, square
//! rooted so that a 1 % amplitude error is a residual of 0.01 everywhere on
//! the curve) is minimised by bounded Levenberg–Marquardt from the trivial
//! start (β = 0, damping from the peak height; [`solve_magnitude`]); for fixed
//! exponents it is small and well conditioned.
//!
//! ## Phase conventions
//! Instruments report phase differently: lag or lead, relative to force or
//! base acceleration, of displacement or velocity (+90°), absolute or
//! relative motion (+180°), plus a constant sensor delay `τ` (a lag `Ωτ`).
//! With the measured phase `ψ` modelled as `ψ = s φ + c + Ω τ`
//! (`s = ±1`, constant offset `c`), the phase equations become
//!
//! ```text
//! (S + i Ω D) a = G̃ γ e^{i s (ψ − Ω τ)},   G̃ = G e^{−i s c}
//! ```
//!
//! still linear, with a **complex** gain `G̃` that absorbs the unknown offset.
//! [`PhaseConvention`] states `s`, `c`, `τ`; with
//! [`PhaseMode::Detect`] the estimator tries `s = ±1` (τ as given, default 0),
//! keeps the sign with the smaller cost and reads `c = −arg(G̃)/s` from the
//! fitted complex gain. A sweep through resonance changes the lag by ≈ 180°:
//! `s` is the sign of that change; the offset is the phase where the
//! displacement lag is 0 (the quasi-static end).
//!
//! ## Errors-in-variables bias
//! Equation error puts the measured `a` (and `φ`) inside the regressors: with
//! amplitude noise `a = a₀(1 + ε)` the residual is
//! `≈ ε (S a + ρ g(ρ) β a^{ρ+1}) / γ` plus a term in `ε²`, and the regressors
//! are correlated with it. The least-squares estimate is therefore biased by
//! `O(σ²)` (σ the relative noise), and near resonance, where `S ≈ 0` and the
//! regressors are most sensitive, the bias is largest. At 1 % noise it is
//! small but not negligible for δ and the exponents; the output-error fit
//! (Eq 31, branch following included), which attributes the noise to the
//! measured output only, is unbiased to first order and is run from the
//! equation-error estimate. The equation-error stage provides the *basin*,
//! the output-error stage the *estimate*.
//!
//! Scaling: coefficients are solved as `α/Ω_ref²`, `β_ref/Ω_ref²`
//! (`β_ref = g(ρ) β A_ref^ρ`), `δ/Ω_ref`, `κ_ref/Ω_ref`
//! (`κ_ref = g(η) κ (Ω_ref A_ref)^η`) with `A_ref` the largest measured
//! amplitude and `Ω_ref` its frequency, so that all unknowns are O(1).

use super::data::Dataset;
use super::levenberg_marquardt::{minimise, LeastSquares, LmOptions};
use super::models::{ALPHA, BETA, DELTA, ETA, GAIN, KAPPA, PARAM_NAMES, RHO};
use super::objective::Scales;
use super::parameters::Parameters;
use crate::power_law::g_unchecked;

/// How the measured phase relates to the model's displacement phase lag φ:
/// `ψ = sign · φ + offset + Ω · delay` (rad, s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseConvention {
    /// `+1`: the file's phase is a lag (grows through resonance); `−1`: a lead.
    pub sign: f64,
    /// Constant offset `c`, rad (e.g. π/2 for velocity, π for relative motion
    /// against base acceleration).
    pub offset: f64,
    /// Constant delay τ, s (a lag `Ω τ` added by the instrument chain).
    pub delay: f64,
}

impl Default for PhaseConvention {
    /// Displacement phase lag behind the input, no offset, no delay (the
    /// convention of nlsdof's own outputs).
    fn default() -> Self {
        Self {
            sign: 1.0,
            offset: 0.0,
            delay: 0.0,
        }
    }
}

impl PhaseConvention {
    /// A convention as a user states it: `lag` (the measured phase grows
    /// through resonance; `false`: a lead), the offset in degrees (within
    /// ±360) and the delay in seconds (|τ| < 1). The error says which value
    /// is out of range.
    ///
    /// ```
    /// use nlsdof::identification::PhaseConvention;
    /// let velocity = PhaseConvention::from_degrees(true, 90.0, 0.0).unwrap();
    /// assert!((velocity.offset - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    /// assert!(PhaseConvention::from_degrees(true, 400.0, 0.0).is_err());
    /// ```
    pub fn from_degrees(lag: bool, offset_deg: f64, delay_s: f64) -> Result<Self, String> {
        if !(offset_deg.is_finite() && offset_deg.abs() <= 360.0) {
            return Err(format!(
                "offset {offset_deg} must be finite, within [-360, 360] degrees"
            ));
        }
        if !(delay_s.is_finite() && delay_s.abs() < 1.0) {
            return Err(format!("delay {delay_s} must be finite, |delay| < 1 s"));
        }
        Ok(Self {
            sign: if lag { 1.0 } else { -1.0 },
            offset: offset_deg.to_radians(),
            delay: delay_s,
        })
    }

    /// The model phase lag φ of a measured phase ψ at Ω.
    pub fn lag(&self, psi: f64, omega: f64) -> f64 {
        self.sign * (psi - self.offset - omega * self.delay)
    }
}

/// How the equation-error stage uses phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PhaseMode {
    /// Phase not used (magnitude equation only).
    Ignore,
    /// The convention is known.
    Known(PhaseConvention),
    /// Sign and offset detected from the data (the delay, if any, is given).
    Detect { delay: f64 },
}

/// Which terms the equation-error model contains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terms {
    pub stiffness: bool,
    pub damping: bool,
    /// `None`: gain estimated; `Some(g)`: held at `g`.
    pub gain: Option<f64>,
}

/// Result of an equation-error fit at fixed exponents.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EquationErrorFit {
    /// θ = (α, δ, β, ρ, κ, η, gain), natural units (β signed).
    pub theta: Parameters,
    /// Sum of squared residuals (see the module docs for their scaling).
    pub cost: f64,
    /// Number of residuals (2 per point with phase, 1 without).
    pub n_residuals: usize,
    /// Number of estimated coefficients.
    pub n_unknowns: usize,
    /// The convention used or detected (None without phase).
    pub phase: Option<PhaseConvention>,
    /// Names of parameters the data cannot separate (empty if well posed).
    #[serde(deserialize_with = "crate::interned::names")]
    pub unidentifiable: Vec<&'static str>,
}

/// Errors of the equation-error stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EquationErrorError {
    #[error("the data cannot separate {names}: the equation-error system is rank-deficient (need more levels, frequencies, or amplitude variation)", names = .names.join(", "))]
    RankDeficient { names: Vec<&'static str> },
    #[error("phase = {value} rad at {f_hz} Hz (level {level}) is not finite or outside [-2 pi, 2 pi] (360 degrees)")]
    BadPhase {
        level: String,
        value: f64,
        f_hz: f64,
    },
    #[error("phase mode needs phases on every curve, but level {level} has none")]
    MissingPhase { level: String },
    #[error("the equation-error fit did not converge for rho = {rho}, eta = {eta}")]
    NotConverged { rho: f64, eta: f64 },
}

/// One measured point, pre-processed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Point {
    pub omega: f64,
    pub a: f64,
    pub gamma: f64,
    pub sw: f64,
    pub psi: f64,
    /// ln a, ln(Ω a) (for the powers).
    pub la: f64,
    pub lwa: f64,
    /// The phase form's entries of this point that no exponent changes
    /// ([`coefficient_rows`]; scaled as in the module docs): `k a` (α),
    /// `k Ω a/Ω_ref` (δ), with `k = √w/γ`, and the right-hand side
    /// `√w Ω² a/(γ Ω_ref²)`.
    pub row_alpha: f64,
    pub row_delta: f64,
    pub rhs: f64,
}

impl Point {
    /// `√w/γ`, the factor of every coefficient entry of the point's rows.
    fn k(&self) -> f64 {
        self.sw / self.gamma
    }
}

/// The data prepared once for many equation-error solves.
#[derive(Debug, Clone)]
pub struct Prepared {
    pub(crate) points: Vec<Point>,
    pub(crate) scales: Scales,
    pub(crate) has_phase: bool,
    /// Start values (scaled): α̃₀, δ̃₀ (from the lowest level's peak).
    pub(crate) alpha0: f64,
    pub(crate) delta0: f64,
    pub(crate) beta0: f64,
}

impl Prepared {
    /// Prepares `data` (validated phases; every point with `a > 0` used).
    pub fn new(data: &Dataset, scales: Scales) -> Result<Self, EquationErrorError> {
        let mut points = Vec::with_capacity(data.len());
        let has_phase = data.curves.iter().all(|c| c.phases.is_some());
        for c in &data.curves {
            for i in 0..c.omegas.len() {
                let (w, a) = (c.omegas[i], c.amplitudes[i]);
                let psi = c.phases.as_ref().map_or(0.0, |p| p[i]);
                if c.phases.is_some()
                    && !(psi.is_finite() && psi.abs() <= 2.0 * std::f64::consts::PI + 1e-9)
                {
                    return Err(EquationErrorError::BadPhase {
                        level: c.level.clone(),
                        value: psi,
                        f_hz: w / (2.0 * std::f64::consts::PI),
                    });
                }
                if !(a > 0.0) || c.weights[i] == 0.0 {
                    continue;
                }
                let (sw, gamma, wr) = (c.weights[i].sqrt(), c.gamma, scales.omega_ref);
                let k = sw / gamma;
                points.push(Point {
                    omega: w,
                    a,
                    gamma,
                    sw,
                    psi,
                    la: a.ln(),
                    lwa: (w * a).ln(),
                    row_alpha: k * a,
                    row_delta: k * w * a / wr,
                    rhs: sw / gamma * w * w * a / (wr * wr),
                });
            }
        }
        // start: lowest level's peak
        let low = data
            .curves
            .iter()
            .min_by(|x, y| x.gamma.total_cmp(&y.gamma))
            .expect("dataset has curves");
        let k = low.peak_index();
        let (wp, ap) = (low.omegas[k], low.amplitudes[k].max(f64::MIN_POSITIVE));
        let high = data
            .curves
            .iter()
            .max_by(|x, y| x.gamma.total_cmp(&y.gamma))
            .expect("dataset has curves");
        let wh = high.omegas[high.peak_index()];
        let wr2 = scales.omega_ref * scales.omega_ref;
        Ok(Self {
            points,
            scales,
            has_phase,
            alpha0: wp * wp / wr2,
            delta0: low.gamma / (ap * wp) / scales.omega_ref,
            beta0: (wh * wh - wp * wp) / wr2,
        })
    }

    /// Whether every curve carries phase.
    pub fn has_phase(&self) -> bool {
        self.has_phase
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// Per-point regressors at fixed exponents: `fa = g(ρ) a^{ρ+1} / (A_ref^ρ)`
/// (so that its coefficient is β_ref), `fd = g(η) Ω a (Ωa)^η / (Ω_ref A_ref)^η`.
fn regressors(p: &Point, rho: f64, eta: f64, sc: &Scales) -> (f64, f64) {
    (
        stiffness_regressor(p, rho, sc),
        damping_regressor(p, eta, sc),
    )
}

/// `fa` of [`regressors`].
fn stiffness_regressor(p: &Point, rho: f64, sc: &Scales) -> f64 {
    p.a * ((p.la - sc.a_ref.ln()) * rho).exp()
}

/// `fd` of [`regressors`].
fn damping_regressor(p: &Point, eta: f64, sc: &Scales) -> f64 {
    p.omega * p.a * ((p.lwa - (sc.omega_ref * sc.a_ref).ln()) * eta).exp()
}

/// The per-point quantities of the phase form at one node that do not
/// depend on the unknowns, computed once and shared by the nodes that
/// need them (the landscape: every node of a row has its `η` columns,
/// every row the `ρ` columns of every node, and every node the phases'
/// `sin`/`cos`). Each entry is computed by the same expression as the
/// per-point loop computed it, so a node's solution is the same bit for
/// bit; the table only saves the repeated `exp`, `ln` and `sin_cos`
/// (measured on the 24 °C beam's default generalised fit, 41 × 41 nodes,
/// phase detected: the landscape stage went from 0.197 s to 0.124 s, its
/// CPU time from 0.36 s to 0.24 s).
#[derive(Debug, Clone, Copy)]
pub(crate) struct NodeColumns<'a> {
    /// The β entry `k fa` of each point's real row ([`stiffness_regressor`]
    /// at the node's ρ; `k` of [`Point::k`]).
    pub beta: &'a [f64],
    /// The κ entry `k fd/Ω_ref` of each point's imaginary row
    /// ([`damping_regressor`] at the node's η).
    pub kappa: &'a [f64],
    /// `exp(η ln Ωa)` per point ([`damping_positive`] at the node's η).
    pub damping_power: &'a [f64],
}

/// Owned [`NodeColumns`] of one node or one axis value.
#[derive(Debug, Clone, Default)]
pub(crate) struct Columns {
    pub beta: Vec<f64>,
    pub kappa: Vec<f64>,
    pub damping_power: Vec<f64>,
}

impl Columns {
    /// The β entries of every point at `rho`.
    pub fn stiffness(prep: &Prepared, rho: f64) -> Vec<f64> {
        let sc = &prep.scales;
        prep.points
            .iter()
            .map(|p| p.k() * stiffness_regressor(p, rho, sc))
            .collect()
    }

    /// The κ entries and the sign test's powers of every point at `eta`.
    pub fn damping(prep: &Prepared, eta: f64) -> (Vec<f64>, Vec<f64>) {
        let sc = &prep.scales;
        let wr = sc.omega_ref;
        let fd = prep
            .points
            .iter()
            .map(|p| p.k() * damping_regressor(p, eta, sc) / wr)
            .collect();
        let power = prep.points.iter().map(|p| (p.lwa * eta).exp()).collect();
        (fd, power)
    }

    /// Every column of one node.
    pub fn node(prep: &Prepared, rho: f64, eta: f64) -> Self {
        let (kappa, damping_power) = Self::damping(prep, eta);
        Self {
            beta: Self::stiffness(prep, rho),
            kappa,
            damping_power,
        }
    }

    pub fn borrowed(&self) -> NodeColumns<'_> {
        NodeColumns {
            beta: &self.beta,
            kappa: &self.kappa,
            damping_power: &self.damping_power,
        }
    }
}

/// `(sin φ, cos φ)` per point of the phase angle each phase-form solve
/// rotates by: `sign·(ψ − Ω·delay)` for the two signs of a detection, or
/// a known convention's lag (same expressions as the solves', see
/// [`NodeColumns`]).
#[derive(Debug, Clone)]
pub(crate) enum PhaseTrig {
    /// `[sign +1, sign −1]` of [`solve_phase`] with `conv = None`: the
    /// point's gain entries of each row, `[re Gr, re Gi, im Gr, im Gi]`
    /// (`−√w cos, √w sin, −√w sin, −√w cos` over `Ω_ref²`).
    Detect([Vec<[f64; 4]>; 2]),
    /// A known convention ([`PhaseConvention::lag`]).
    Known(Vec<(f64, f64)>),
}

impl PhaseTrig {
    pub fn new(prep: &Prepared, conv: Option<PhaseConvention>, delay: f64) -> Self {
        match conv {
            Some(c) => PhaseTrig::Known(
                prep.points
                    .iter()
                    .map(|p| c.lag(p.psi, p.omega).sin_cos())
                    .collect(),
            ),
            None => PhaseTrig::Detect([1.0, -1.0].map(|sign: f64| {
                let wr = prep.scales.omega_ref;
                prep.points
                    .iter()
                    .map(|p| complex_gain_entries(p, sign, delay, wr))
                    .collect()
            })),
        }
    }
}

/// Natural θ from scaled coefficients.
fn natural(
    sc: &Scales,
    rho: f64,
    eta: f64,
    alpha_s: f64,
    beta_s: f64,
    delta_s: f64,
    kappa_s: f64,
    gain: f64,
) -> Parameters {
    let wr = sc.omega_ref;
    let mut th = Parameters::default();
    th[ALPHA] = alpha_s * wr * wr;
    th[DELTA] = delta_s * wr;
    th[RHO] = rho;
    th[ETA] = eta;
    th[BETA] = beta_s * wr * wr / (g_unchecked(rho) * sc.a_ref.powf(rho));
    th[KAPPA] = kappa_s * wr / (g_unchecked(eta) * (sc.omega_ref * sc.a_ref).powf(eta));
    th[GAIN] = gain;
    th
}

/// Small dense least squares `min ‖A x − b‖²` by column-scaled normal
/// equations (at most 6 unknowns), with a rank check by the eigenvalues of
/// the scaled normal matrix (nalgebra's symmetric eigen-decomposition).
struct SmallLs {
    n: usize,
    ata: [[f64; 8]; 8],
    atb: [f64; 8],
}

impl SmallLs {
    fn new(n: usize) -> Self {
        Self {
            n,
            ata: [[0.0; 8]; 8],
            atb: [0.0; 8],
        }
    }

    fn add(&mut self, row: &[f64], b: f64) {
        for p in 0..self.n {
            if row[p] == 0.0 {
                continue;
            }
            self.atb[p] += row[p] * b;
            for q in 0..=p {
                self.ata[p][q] += row[p] * row[q];
            }
        }
    }

    /// Solution, and the indices of a null direction's main components if
    /// the scaled normal matrix has condition number above 1e12.
    fn solve(&self) -> (Option<Vec<f64>>, Vec<usize>) {
        let n = self.n;
        let d: Vec<f64> = (0..n).map(|k| self.ata[k][k].sqrt()).collect();
        let dead: Vec<usize> = (0..n)
            .filter(|&k| !(d[k] > 0.0 && d[k].is_finite()))
            .collect();
        if !dead.is_empty() {
            return (None, dead);
        }
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| {
            let v = if i >= j {
                self.ata[i][j]
            } else {
                self.ata[j][i]
            };
            v / (d[i] * d[j])
        });
        let eig = m.clone().symmetric_eigen();
        let (mut imin, mut emin, mut emax) = (0, f64::INFINITY, 0.0f64);
        for (i, &e) in eig.eigenvalues.iter().enumerate() {
            if e < emin {
                emin = e;
                imin = i;
            }
            emax = emax.max(e);
        }
        if !(emin > 1e-12 * emax) {
            let v = eig.eigenvectors.column(imin);
            let vmax = v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
            let names = (0..n).filter(|&k| v[k].abs() > 0.2 * vmax).collect();
            return (None, names);
        }
        let b = nalgebra::DVector::from_fn(n, |i, _| self.atb[i] / d[i]);
        match m.cholesky() {
            Some(ch) => {
                let y = ch.solve(&b);
                (Some((0..n).map(|i| y[i] / d[i]).collect()), Vec::new())
            }
            None => (None, (0..n).collect()),
        }
    }
}

/// Equation-error fit **with phase** at fixed exponents (linear least
/// squares, closed form). `conv = None` detects sign and offset.
pub fn solve_phase(
    prep: &Prepared,
    terms: Terms,
    rho: f64,
    eta: f64,
    conv: Option<PhaseConvention>,
    delay: f64,
) -> Result<EquationErrorFit, EquationErrorError> {
    let cols = Columns::node(prep, rho, eta);
    let trig = PhaseTrig::new(prep, conv, delay);
    solve_phase_with(prep, terms, (rho, eta), conv, delay, cols.borrowed(), &trig)
}

/// [`solve_phase`] with the node's columns and the phases' `sin`/`cos`
/// given (`trig` made by [`PhaseTrig::new`] with the same `conv` and
/// `delay`): the same result bit for bit.
pub(crate) fn solve_phase_with(
    prep: &Prepared,
    terms: Terms,
    (rho, eta): (f64, f64),
    conv: Option<PhaseConvention>,
    delay: f64,
    cols: NodeColumns<'_>,
    trig: &PhaseTrig,
) -> Result<EquationErrorFit, EquationErrorError> {
    match conv {
        Some(c) => {
            let known = match trig {
                PhaseTrig::Known(t) => Some(&t[..]),
                PhaseTrig::Detect(_) => None,
            };
            solve_phase_known(prep, terms, (rho, eta), c, cols, known)
        }
        None => {
            let mut best: Option<EquationErrorFit> = None;
            let mut last_err = None;
            for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                let detect = match trig {
                    PhaseTrig::Detect(t) => Some(&t[k][..]),
                    PhaseTrig::Known(_) => None,
                };
                // complex gain free: offset from its argument
                match solve_phase_complex(prep, terms, (rho, eta), sign, delay, cols, detect) {
                    Ok((fit, offset)) => {
                        let conv = PhaseConvention {
                            sign,
                            offset,
                            delay,
                        };
                        let fit = if terms.gain.is_some() {
                            // re-solve with the offset known and the gain held
                            // (its angles are this offset's: computed there)
                            solve_phase_known(prep, terms, (rho, eta), conv, cols, None)?
                        } else {
                            EquationErrorFit {
                                phase: Some(conv),
                                ..fit
                            }
                        };
                        // The two signs are mirror images (φ → −φ with
                        // D → −D) of equal cost when the damping is free:
                        // the physical one has positive damping at the
                        // points; the cost decides otherwise.
                        let key = |f: &EquationErrorFit| {
                            let positive = damping_positive(prep, f, eta, cols.damping_power);
                            (std::cmp::Reverse(positive as u8), f.cost)
                        };
                        if best.as_ref().map_or(true, |b| {
                            key(&fit).partial_cmp(&key(b)) == Some(std::cmp::Ordering::Less)
                        }) {
                            best = Some(fit);
                        }
                    }
                    Err(e) => last_err = Some(e),
                }
            }
            best.ok_or_else(|| last_err.expect("an error when no sign worked"))
        }
    }
}

/// Whether the fitted damping force `Ω D a` is positive on average over
/// the points (the physical sign of the phase convention). `power` holds
/// `exp(η ln Ωa)` per point at the node's `eta` ([`NodeColumns`]), used
/// when the fit has that exponent.
fn damping_positive(prep: &Prepared, f: &EquationErrorFit, eta: f64, power: &[f64]) -> bool {
    let th = &f.theta;
    let ge = if th[KAPPA] != 0.0 {
        g_unchecked(th[ETA])
    } else {
        0.0
    };
    let tabled = th[ETA].to_bits() == eta.to_bits() && power.len() == prep.points.len();
    let s: f64 = prep
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let e = if tabled {
                power[i]
            } else {
                (p.lwa * th[ETA]).exp()
            };
            let d = th[DELTA] + ge * th[KAPPA] * e;
            p.omega * d * p.a / p.gamma
        })
        .sum();
    s > 0.0
}

/// The gain entries of a point's rows in the complex-gain form
/// ([`PhaseTrig::Detect`]).
fn complex_gain_entries(p: &Point, sign: f64, delay: f64, wr: f64) -> [f64; 4] {
    let th = sign * (p.psi - p.omega * delay);
    let (s, c) = th.sin_cos();
    [
        -p.sw * c / (wr * wr),
        p.sw * s / (wr * wr),
        -p.sw * s / (wr * wr),
        -p.sw * c / (wr * wr),
    ]
}

/// The coefficient part of point `i`'s two phase-form rows (real: α, β;
/// imaginary: δ, κ; scaled as in the module docs) and the index of the
/// first gain column; the β and κ entries from the node's columns.
fn coefficient_rows(
    p: &Point,
    (beta, kappa): (f64, f64),
    terms: Terms,
) -> ([f64; 6], [f64; 6], usize) {
    let mut re = [0.0; 6];
    let mut im = [0.0; 6];
    let mut q = 0;
    re[q] = p.row_alpha;
    q += 1;
    if terms.stiffness {
        re[q] = beta;
        q += 1;
    }
    im[q] = p.row_delta;
    q += 1;
    if terms.damping {
        im[q] = kappa;
        q += 1;
    }
    (re, im, q)
}

/// Column layout of the phase system: α, β?, δ, κ?, then gain columns.
fn layout(terms: Terms) -> (Vec<usize>, usize) {
    let mut cols = vec![ALPHA];
    if terms.stiffness {
        cols.push(BETA);
    }
    cols.push(DELTA);
    if terms.damping {
        cols.push(KAPPA);
    }
    let n = cols.len();
    (cols, n)
}

fn names_of(cols: &[usize], idx: &[usize]) -> Vec<&'static str> {
    idx.iter()
        .map(|&k| cols.get(k).map_or("gain", |&j| PARAM_NAMES[j]))
        .collect()
}

fn solve_phase_complex(
    prep: &Prepared,
    terms: Terms,
    (rho, eta): (f64, f64),
    sign: f64,
    delay: f64,
    node: NodeColumns<'_>,
    trig: Option<&[[f64; 4]]>,
) -> Result<(EquationErrorFit, f64), EquationErrorError> {
    let sc = &prep.scales;
    let (cols, nc) = layout(terms);
    let n = nc + 2;
    let wr = sc.omega_ref;
    let mut ls = SmallLs::new(n);
    let mut rows: Vec<([f64; 6], f64, [f64; 6], f64)> = Vec::with_capacity(prep.points.len());
    for (i, p) in prep.points.iter().enumerate() {
        let [gr_re, gi_re, gr_im, gi_im] = match trig {
            Some(t) => t[i],
            None => complex_gain_entries(p, sign, delay, wr),
        };
        let (mut re, mut im, q) = coefficient_rows(p, (node.beta[i], node.kappa[i]), terms);
        // G̃ = Gr + i Gi (unknowns scaled by 1/Ω_ref²: the rows are divided by Ω_ref²)
        re[q] = gr_re;
        re[q + 1] = gi_re;
        im[q] = gr_im;
        im[q + 1] = gi_im;
        let bre = p.rhs;
        ls.add(&re[..n], bre);
        ls.add(&im[..n], 0.0);
        rows.push((re, bre, im, 0.0));
    }
    let (x, null) = ls.solve();
    let Some(x) = x else {
        return Err(EquationErrorError::RankDeficient {
            names: names_of(&cols, &null),
        });
    };
    let cost = residual_cost(&rows, &x);
    let (gr, gi) = (x[nc], x[nc + 1]);
    let gain = gr.hypot(gi);
    let offset = -gi.atan2(gr) / sign;
    let theta = unpack(sc, &cols, &x, rho, eta, gain, terms);
    Ok((
        EquationErrorFit {
            theta,
            cost,
            n_residuals: 2 * prep.points.len(),
            n_unknowns: n,
            phase: None,
            unidentifiable: Vec::new(),
        },
        wrap(offset),
    ))
}

/// Wraps an angle to (−π, π].
pub fn wrap(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut y = x.rem_euclid(t);
    if y > std::f64::consts::PI {
        y -= t;
    }
    y
}

fn residual_cost(rows: &[([f64; 6], f64, [f64; 6], f64)], x: &[f64]) -> f64 {
    let mut cost = 0.0;
    for (re, bre, im, bim) in rows {
        let mut r1 = -bre;
        let mut r2 = -bim;
        for k in 0..x.len() {
            r1 += re[k] * x[k];
            r2 += im[k] * x[k];
        }
        cost += r1 * r1 + r2 * r2;
    }
    cost
}

fn unpack(
    sc: &Scales,
    cols: &[usize],
    x: &[f64],
    rho: f64,
    eta: f64,
    gain: f64,
    terms: Terms,
) -> Parameters {
    let get = |j: usize| cols.iter().position(|&c| c == j).map_or(0.0, |k| x[k]);
    let mut th = natural(
        sc,
        if terms.stiffness { rho } else { 0.0 },
        if terms.damping { eta } else { 0.0 },
        get(ALPHA),
        get(BETA),
        get(DELTA),
        get(KAPPA),
        gain,
    );
    if !terms.stiffness {
        th[BETA] = 0.0;
        th[RHO] = 0.0;
    }
    if !terms.damping {
        th[KAPPA] = 0.0;
        th[ETA] = 0.0;
    }
    th
}

fn solve_phase_known(
    prep: &Prepared,
    terms: Terms,
    (rho, eta): (f64, f64),
    conv: PhaseConvention,
    node: NodeColumns<'_>,
    trig: Option<&[(f64, f64)]>,
) -> Result<EquationErrorFit, EquationErrorError> {
    let sc = &prep.scales;
    let (cols, nc) = layout(terms);
    let n = nc + usize::from(terms.gain.is_none());
    let wr = sc.omega_ref;
    let mut ls = SmallLs::new(n);
    let mut rows = Vec::with_capacity(prep.points.len());
    for (i, p) in prep.points.iter().enumerate() {
        let (s, c) = match trig {
            Some(t) => t[i],
            None => conv.lag(p.psi, p.omega).sin_cos(),
        };
        let (mut re, mut im, q) = coefficient_rows(p, (node.beta[i], node.kappa[i]), terms);
        let mut bre = p.rhs;
        let mut bim = 0.0;
        match terms.gain {
            None => {
                re[q] = -p.sw * c / (wr * wr);
                im[q] = -p.sw * s / (wr * wr);
            }
            Some(g) => {
                bre += g * p.sw * c / (wr * wr);
                bim += g * p.sw * s / (wr * wr);
            }
        }
        ls.add(&re[..n], bre);
        ls.add(&im[..n], bim);
        rows.push((re, bre, im, bim));
    }
    let (x, null) = ls.solve();
    let Some(x) = x else {
        return Err(EquationErrorError::RankDeficient {
            names: names_of(&cols, &null),
        });
    };
    let cost = residual_cost(&rows, &x);
    let gain = terms.gain.unwrap_or_else(|| x[nc]);
    Ok(EquationErrorFit {
        theta: unpack(sc, &cols, &x, rho, eta, gain, terms),
        cost,
        n_residuals: 2 * prep.points.len(),
        n_unknowns: n,
        phase: Some(conv),
        unidentifiable: Vec::new(),
    })
}

/// The magnitude-only problem at fixed exponents, in scaled unknowns
/// `x = (α̃, β̃?, δ̃, κ̃?, G?)`.
///
/// Per point, with `u = f_a/a`, `w = Ω̃²`, `ω̃ = Ω/Ω_ref`, `v = f_d/(Ω_ref a)`
/// and `s = γ/(Ω_ref² a)` (dimensionless, precomputed once per node so an
/// evaluation is a few multiplications):
///
/// ```text
/// S̃ = α̃ + β̃ u − w,   D̃ = δ̃ ω̃ + κ̃ v,   r = √w_i (√(S̃² + D̃²) / (G s) − 1)
/// ```
struct Magnitude {
    terms: Terms,
    /// Per point: (fa, fd) regressors, scaled by Ω_ref as in the phase form.
    reg: Vec<(f64, f64)>,
    /// Per point: `[u, w, ω̃, v, s, √weight]`.
    rows: Vec<[f64; 6]>,
}

impl Magnitude {
    fn new(prep: &Prepared, terms: Terms, rho: f64, eta: f64) -> Self {
        let sc = prep.scales;
        let reg: Vec<(f64, f64)> = prep
            .points
            .iter()
            .map(|p| regressors(p, rho, eta, &sc))
            .collect();
        let wr = sc.omega_ref;
        let rows = prep
            .points
            .iter()
            .zip(&reg)
            .map(|(p, &(fa, fd))| {
                let ow = p.omega / wr;
                [
                    fa / p.a,
                    ow * ow,
                    ow,
                    fd / (wr * p.a),
                    p.gamma / (wr * wr * p.a),
                    p.sw,
                ]
            })
            .collect();
        Self { terms, reg, rows }
    }

    fn unpack(&self, x: &[f64]) -> (f64, f64, f64, f64, f64) {
        let mut q = 0;
        let mut next = |present: bool| {
            if present {
                q += 1;
                x[q - 1]
            } else {
                0.0
            }
        };
        let al = next(true);
        let be = next(self.terms.stiffness);
        let de = next(true);
        let ka = next(self.terms.damping);
        let g = match self.terms.gain {
            Some(g) => g,
            None => next(true),
        };
        (al, be, de, ka, g)
    }

    /// Residual of point `i` at the unpacked unknowns `c = (α̃, β̃, δ̃, κ̃, G)`,
    /// and its gradient row if asked.
    #[inline]
    fn point(&self, i: usize, c: (f64, f64, f64, f64, f64), row: Option<&mut [f64]>) -> f64 {
        let [u, w, ow, v, sg, sw] = self.rows[i];
        let (al, be, de, ka, g) = c;
        let s = al + be * u - w;
        let od = de * ow + ka * v;
        // scaled quantities are O(1): the plain root does not overflow where
        // hypot would be needed, and is several times faster
        let mut m = (s * s + od * od).sqrt();
        if !m.is_finite() {
            m = s.hypot(od);
        }
        let gs = g * sg;
        let r = sw * (m / gs - 1.0);
        if let Some(row) = row {
            let inv = if m > 0.0 { sw / (m * gs) } else { 0.0 };
            let mut q = 0;
            row[q] = inv * s;
            q += 1;
            if self.terms.stiffness {
                row[q] = inv * s * u;
                q += 1;
            }
            row[q] = inv * od * ow;
            q += 1;
            if self.terms.damping {
                row[q] = inv * od * v;
                q += 1;
            }
            if self.terms.gain.is_none() {
                row[q] = -sw * m / (gs * g);
            }
        }
        r
    }
}

impl LeastSquares for Magnitude {
    fn n_params(&self) -> usize {
        2 + usize::from(self.terms.stiffness)
            + usize::from(self.terms.damping)
            + usize::from(self.terms.gain.is_none())
    }

    fn residuals(&self, x: &[f64]) -> Option<Vec<f64>> {
        let c = self.unpack(x);
        let r: Vec<f64> = (0..self.rows.len())
            .map(|i| self.point(i, c, None))
            .collect();
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn residuals_and_jacobian(&self, x: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let n = self.n_params();
        let c = self.unpack(x);
        let mut j = vec![0.0; self.rows.len() * n];
        let r: Vec<f64> = j
            .chunks_exact_mut(n)
            .enumerate()
            .map(|(i, row)| self.point(i, c, Some(row)))
            .collect();
        (r.iter().all(|v| v.is_finite()) && j.iter().all(|v| v.is_finite())).then_some((r, j))
    }
}

/// Scaled start vector of the magnitude problem, or `warm` if given.
fn magnitude_start(prep: &Prepared, terms: Terms, sign_hint: f64) -> Vec<f64> {
    let mut x = vec![prep.alpha0];
    if terms.stiffness {
        x.push(sign_hint * prep.beta0.abs().max(1e-3 * prep.alpha0));
    }
    let d0 = prep.delta0;
    x.push(if terms.damping { 0.5 * d0 } else { d0 });
    if terms.damping {
        x.push(0.5 * d0);
    }
    if terms.gain.is_none() {
        x.push(1.0);
    }
    x
}

/// Scaled unknowns of [`solve_magnitude_lifted`] (the math is there).
fn magnitude_lifted_start(prep: &Prepared, terms: Terms, reg: &[(f64, f64)]) -> Option<Vec<f64>> {
    let wr = prep.scales.omega_ref;
    let stiff = terms.stiffness;
    let damp = terms.damping;
    let free_gain = terms.gain.is_none();
    let g0 = terms.gain.unwrap_or(1.0);
    let n = 2 + 3 * usize::from(stiff) + 2 * usize::from(damp) + usize::from(free_gain);
    // rows kept for an SVD solve: the normal equations would square the
    // condition number, and δ̃² = z₄ + 2α̃ already cancels ~4 digits
    let m = prep.points.len();
    let mut a_mat = nalgebra::DMatrix::<f64>::zeros(m, n);
    let mut b_vec = nalgebra::DVector::<f64>::zeros(m);
    let mut row = [0.0; 8];
    for (i, (p, &(fa, fd))) in prep.points.iter().zip(reg).enumerate() {
        let u = fa / p.a;
        let w = p.omega * p.omega / (wr * wr);
        let v = fd / (wr * p.a);
        let sg = p.gamma / (wr * wr * p.a);
        let k = p.sw / (g0 * g0 * sg * sg);
        let mut q = 0;
        let mut put = |x: f64, q: &mut usize| {
            row[*q] = k * x;
            *q += 1;
        };
        put(1.0, &mut q);
        if stiff {
            put(2.0 * u, &mut q);
            put(u * u, &mut q);
        }
        put(w, &mut q);
        if stiff {
            put(-2.0 * u * w, &mut q);
        }
        if damp {
            put(2.0 * w.sqrt() * v, &mut q);
            put(v * v, &mut q);
        }
        let mut b = -w * w;
        if free_gain {
            put(-sg * sg, &mut q);
        } else {
            b += g0 * g0 * sg * sg;
        }
        for (c, &v) in row[..n].iter().enumerate() {
            a_mat[(i, c)] = v;
        }
        b_vec[i] = k * b;
    }
    // unit column norms, then the SVD least-squares solution
    let norms: Vec<f64> = (0..n).map(|c| a_mat.column(c).norm()).collect();
    if norms.iter().any(|&v| !(v > 0.0 && v.is_finite())) {
        return None;
    }
    for (c, &v) in norms.iter().enumerate() {
        a_mat.column_mut(c).scale_mut(1.0 / v);
    }
    let svd = a_mat.svd(true, true);
    let smax = svd.singular_values.max();
    if !(svd.singular_values.min() > 1e-12 * smax) {
        return None;
    }
    let y = svd.solve(&b_vec, 0.0).ok()?;
    let z: Vec<f64> = (0..n).map(|c| y[c] / norms[c]).collect();
    let mut q = 0;
    let mut next = || {
        q += 1;
        z[q - 1]
    };
    let a2 = next();
    let (_ab, _b2) = if stiff { (next(), next()) } else { (0.0, 0.0) };
    let c = next();
    let be = if stiff { next() } else { 0.0 };
    let (_dk, k2) = if damp { (next(), next()) } else { (0.0, 0.0) };
    let g2 = if free_gain { next() } else { g0 * g0 };
    if !(a2 > 0.0 && g2 > 0.0) {
        return None;
    }
    let al = a2.sqrt();
    let d2 = c + 2.0 * al;
    let mut x = vec![al];
    if stiff {
        x.push(be);
    }
    // damping shared out as the data say; a square estimated ≤ 0 starts
    // from a small positive value (the bound is 0)
    let tiny = 1e-3 * prep.delta0.max(f64::MIN_POSITIVE);
    x.push(if d2 > 0.0 { d2.sqrt() } else { tiny });
    if damp {
        x.push(if k2 > 0.0 { k2.sqrt() } else { tiny });
    }
    if free_gain {
        x.push(g2.sqrt());
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Closed-form estimate of the magnitude problem by *lifting*, as a
/// natural θ (no iteration): squared, the
/// no-phase equation of every point is linear in products of the unknowns.
/// In the scaled unknowns of the magnitude problem (`solve_magnitude`), with `u = f_a/a`, `w = Ω̃²`,
/// `v = f_d/(Ω_ref a)` and `s = γ/(Ω_ref² a)`,
///
/// ```text
/// S̃² + (Ω̃D̃)² = G² s²,   S̃ = α̃ + β̃ u − w,   Ω̃D̃ = δ̃ √w + κ̃ v
/// ⇔ α̃² + 2α̃β̃ u + β̃² u² + (δ̃² − 2α̃) w − 2β̃ u w + 2δ̃κ̃ √w v + κ̃² v² − G² s² = −w²
/// ```
///
/// which is linear least squares in `z = (α̃², α̃β̃, β̃², δ̃² − 2α̃, β̃, δ̃κ̃, κ̃², G²)`
/// (rows divided by `G₀² s²` so that each measures a relative error, as the
/// residual of `solve_magnitude` does). The products are then split: `α̃ = √z₁`,
/// `β̃ = z₅`, `δ̃ = √(z₄ + 2α̃)`, `κ̃ = √z₇`, `G = √z₈`. Exact for exact data;
/// with noise a biased but close start, from which LM needs a few steps.
/// `None` when the lifted system is rank deficient or a square is negative.
pub fn solve_magnitude_lifted(
    prep: &Prepared,
    terms: Terms,
    rho: f64,
    eta: f64,
) -> Option<Parameters> {
    let prob = Magnitude::new(prep, terms, rho, eta);
    let x = magnitude_lifted_start(prep, terms, &prob.reg)?;
    let (al, be, de, ka, g) = prob.unpack(&x);
    Some(natural(&prep.scales, rho, eta, al, be, de, ka, g))
}

/// Equation-error fit **without phase** at fixed exponents (bounded LM on
/// the relative magnitude residual). `warm` is a scaled start (e.g. from a
/// neighbouring landscape node); otherwise the lifted closed-form start
/// ([`solve_magnitude_lifted`]) is used, and the trivial starts (β̃ of
/// either sign, damping from the peak height) are tried as well when LM
/// from it does not converge.
pub fn solve_magnitude(
    prep: &Prepared,
    terms: Terms,
    rho: f64,
    eta: f64,
    warm: Option<&[f64]>,
) -> Result<(EquationErrorFit, Vec<f64>), EquationErrorError> {
    solve_magnitude_to(prep, terms, rho, eta, warm, 1e-13, 1e-15)
}

/// [`solve_magnitude`] to the step and cost tolerances `xtol`, `ftol` of
/// the LM (the landscape maps the cost to ~1e-10, not to the last digit).
pub(crate) fn solve_magnitude_to(
    prep: &Prepared,
    terms: Terms,
    rho: f64,
    eta: f64,
    warm: Option<&[f64]>,
    xtol: f64,
    ftol: f64,
) -> Result<(EquationErrorFit, Vec<f64>), EquationErrorError> {
    let sc = prep.scales;
    let prob = Magnitude::new(prep, terms, rho, eta);
    let n = prob.n_params();
    let inf = f64::INFINITY;
    let mut lo = vec![1e-12; n];
    let mut hi = vec![inf; n];
    if terms.stiffness {
        lo[1] = -inf;
        hi[1] = inf;
    }
    // damping coefficients may reach 0
    let kd = if terms.stiffness { 2 } else { 1 };
    lo[kd] = 0.0;
    if terms.damping {
        lo[kd + 1] = 0.0;
    }
    let opts = LmOptions {
        max_iterations: 200,
        max_evaluations: 600,
        xtol,
        ftol,
        gtol: xtol,
        cost_floor: 1e-28 * prep.points.len() as f64,
        decrement_tol: 0.0,
        cancel: crate::cancel::Cancel::NEVER,
    };
    let mut best: Option<super::levenberg_marquardt::LmResult> = None;
    let run = |s: &[f64], best: &mut Option<super::levenberg_marquardt::LmResult>| {
        if let Ok(r) = minimise(&prob, s, &lo, &hi, &opts) {
            if best.as_ref().map_or(true, |b| r.cost < b.cost) {
                *best = Some(r);
            }
        }
    };
    if let Some(w) = warm {
        run(w, &mut best);
    } else {
        if let Some(s) = magnitude_lifted_start(prep, terms, &prob.reg) {
            run(&s, &mut best);
        }
        use super::levenberg_marquardt::Termination as T;
        let settled = best.as_ref().is_some_and(|b| {
            matches!(
                b.termination,
                T::ZeroResidual | T::SmallStep | T::SmallCostReduction | T::SmallGradient
            )
        });
        if !settled {
            run(&magnitude_start(prep, terms, 1.0), &mut best);
            if terms.stiffness {
                run(&magnitude_start(prep, terms, -1.0), &mut best);
                run(&magnitude_start(prep, terms, 0.0), &mut best);
            }
        }
    }
    let best = best.ok_or(EquationErrorError::NotConverged { rho, eta })?;
    let (al, be, de, ka, g) = prob.unpack(&best.u);
    let mut theta = natural(&sc, rho, eta, al, be, de, ka, g);
    if !terms.stiffness {
        theta[BETA] = 0.0;
        theta[RHO] = 0.0;
    }
    if !terms.damping {
        theta[KAPPA] = 0.0;
        theta[ETA] = 0.0;
    }
    // rank check at the optimum
    let mut unid = Vec::new();
    if let Some((_, j)) = prob.residuals_and_jacobian(&best.u) {
        let mut ls = SmallLs::new(n);
        for row in j.chunks_exact(n) {
            ls.add(row, 0.0);
        }
        let (x, null) = ls.solve();
        if x.is_none() {
            unid = names_of(&layout(terms).0, &null);
        }
    }
    Ok((
        EquationErrorFit {
            theta,
            cost: best.cost,
            n_residuals: prep.points.len(),
            n_unknowns: n,
            phase: None,
            unidentifiable: unid,
        },
        best.u,
    ))
}

/// Scaled unknowns of a natural θ (for warm starts of [`solve_magnitude`]).
pub fn scaled_of(prep: &Prepared, terms: Terms, theta: &Parameters) -> Vec<f64> {
    let sc = &prep.scales;
    let wr = sc.omega_ref;
    let mut x = vec![theta[ALPHA] / (wr * wr)];
    if terms.stiffness {
        x.push(theta[BETA] * g_unchecked(theta[RHO]) * sc.a_ref.powf(theta[RHO]) / (wr * wr));
    }
    x.push(theta[DELTA] / wr);
    if terms.damping {
        x.push(
            theta[KAPPA] * g_unchecked(theta[ETA]) * (sc.omega_ref * sc.a_ref).powf(theta[ETA])
                / wr,
        );
    }
    if terms.gain.is_none() {
        x.push(theta[GAIN]);
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harmonic_balance::SweepDirection;
    use crate::identification::data::Record;

    /// Three levels of made-up (not in-family) amplitudes: the Jacobian is
    /// checked away from any optimum, where every term contributes.
    fn prepared() -> Prepared {
        let mut recs = Vec::new();
        for (l, g) in [0.5, 1.0, 2.0].into_iter().enumerate() {
            for i in 0..15 {
                let f = 8.0 + 0.3 * i as f64;
                recs.push(Record {
                    level: format!("L{l}"),
                    gamma: g,
                    omega: 2.0 * std::f64::consts::PI * f,
                    amplitude: 1e-3 * g * (1.0 + 0.1 * (i as f64).sin()),
                    phase: None,
                    direction: SweepDirection::Up,
                    weight: 1.0 + 0.05 * i as f64,
                });
            }
        }
        let data = Dataset::from_records(&recs).unwrap();
        let scales = Scales {
            a_ref: 1.5e-3,
            omega_ref: 2.0 * std::f64::consts::PI * 10.0,
        };
        Prepared::new(&data, scales).unwrap()
    }

    /// The analytic Jacobian of the magnitude residual against central
    /// differences, for every combination of terms.
    #[test]
    fn magnitude_jacobian_matches_finite_differences() {
        let prep = prepared();
        for (stiffness, damping, gain) in [
            (true, true, None),
            (true, false, Some(1.3)),
            (false, true, None),
            (false, false, Some(0.7)),
        ] {
            let terms = Terms {
                stiffness,
                damping,
                gain,
            };
            let prob = Magnitude::new(&prep, terms, 1.7, 0.6);
            let n = prob.n_params();
            let x: Vec<f64> = [1.1, 0.3, 0.02, 0.015, 0.9][..n].to_vec();
            let (r0, j) = prob.residuals_and_jacobian(&x).unwrap();
            assert_eq!(r0, prob.residuals(&x).unwrap());
            for k in 0..n {
                let h = 1e-6 * x[k].abs().max(1e-3);
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[k] += h;
                xm[k] -= h;
                let (rp, rm) = (prob.residuals(&xp).unwrap(), prob.residuals(&xm).unwrap());
                for i in 0..r0.len() {
                    let fd = (rp[i] - rm[i]) / (2.0 * h);
                    let an = j[i * n + k];
                    assert!(
                        (fd - an).abs() <= 1e-6 * an.abs().max(1e-3),
                        "terms ({stiffness}, {damping}, {gain:?}), point {i}, unknown {k}: analytic {an}, finite difference {fd}"
                    );
                }
            }
        }
    }
}
