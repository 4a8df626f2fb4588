//! Pseudo-arclength continuation of the multi-harmonic balance in the
//! input frequency Ω (or in the level γ at fixed Ω), with step control and
//! location of limit points (folds).
//!
//! ## Method (Keller's pseudo-arclength)
//! Unknowns `y = (q̃, p̃)`, scaled `q̃ = q / q_s`, `p̃ = p / p_s` (`q_s = γ/α`
//! the static deflection, `p_s = ω_n` for Ω, `p_s = γ_max` for γ) so that
//! both parts are O(1) in the arclength norm. At an accepted point with unit
//! tangent `t` (the null vector of `[∂R/∂q̃  ∂R/∂p̃]`, from the bordered
//! system `[J̃; t_prevᵀ] t = [0; 1]`, normalised and oriented along
//! `t_prev`), the predictor is `y_p = y + s t` and the corrector is Newton
//! on
//!
//! ```text
//! R(q, p) = 0,     tᵀ (y − y_p) = 0
//! ```
//!
//! whose bordered Jacobian is regular at simple folds (where `∂R/∂q` is
//! singular), so folds are passed without special treatment.
//!
//! **Step control.** A step is accepted when Newton converges within
//! `max_corrector` iterations *and* the new tangent turns by less than
//! `max_angle` (which also prevents jumping between close branches near a
//! fold); the next step is `s·1.5` after ≤ 2 iterations, `s` after 3–4, `s·0.7`
//! otherwise, capped at `ds_max`. A rejected step is halved; below `ds_min`
//! the continuation stops and returns the partial branch with the reason in
//! [`Branch::warning`] (never a hang: at most `max_points` steps and
//! `max_points·4` rejections).
//!
//! **Limit points.** A fold in `p` is where the `p` component of the tangent
//! changes sign between two accepted points. It is located by the secant
//! (Illinois) method on `s ↦ t_p(y(s))`, `y(s)` the corrected point at
//! arclength `s` from the earlier point, to `|t_p| ≤ 1e-10` or 60
//! iterations. The maxima of the first-harmonic amplitude along the branch
//! (the resonance peaks) are located the same way on `d(a₁² + b₁²)/ds`.

use super::aft::n_coefficients;
use super::stability::{hill_floquet_exponents, FloquetExponents};
use super::system::{HarmonicSettings, HbSystem};
use super::{from_first_order, harmonic_amplitude, max_abs_displacement, MhbError};
use crate::harmonic_balance::{ForcedResponse, Formulation};
use crate::model::AsNormalised;
use nalgebra::{DMatrix, DVector};

/// Options of the continuation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuationOptions {
    /// First step (scaled arclength).
    pub ds0: f64,
    /// Smallest step before giving up.
    pub ds_min: f64,
    /// Largest step.
    pub ds_max: f64,
    /// Largest parameter step per accepted point, as a fraction of the
    /// parameter range (guarantees a resolution of at least `1/max_dp` points).
    pub max_dp: f64,
    /// Corrector iteration cap.
    pub max_corrector: usize,
    /// Largest turn of the tangent per step (rad).
    pub max_angle: f64,
    /// Cap on accepted points.
    pub max_points: usize,
    /// Compute Hill stability at every point.
    pub stability: bool,
}

impl Default for ContinuationOptions {
    fn default() -> Self {
        Self {
            ds0: 1e-3,
            ds_min: 1e-9,
            ds_max: 0.5,
            max_dp: 1.0 / 500.0,
            max_corrector: 8,
            max_angle: 0.3,
            max_points: 20_000,
            stability: false,
        }
    }
}

/// One point of a branch.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchPoint {
    /// Ω, rad/s.
    pub omega: f64,
    /// γ, m/s².
    pub gamma: f64,
    /// Coefficients `[a₀, a₁, b₁, …, a_H, b_H]` (m).
    pub coefficients: Vec<f64>,
    /// Hill stability (`None` unless requested).
    pub floquet: Option<FloquetExponents>,
}

impl BranchPoint {
    /// Amplitude of harmonic `k` (m).
    pub fn amplitude(&self, k: usize) -> f64 {
        harmonic_amplitude(&self.coefficients, k)
    }
    /// Phase lag of harmonic `k` (rad).
    pub fn phase(&self, k: usize) -> f64 {
        super::harmonic_phase(&self.coefficients, k)
    }
    /// `max |x(t)|` over a period (m).
    pub fn max_abs_x(&self) -> f64 {
        max_abs_displacement(&self.coefficients)
    }
    /// `x(t)` (m) at time `t` (s).
    pub fn displacement(&self, t: f64) -> f64 {
        super::displacement_at(&self.coefficients, self.omega, t)
    }
    /// Stable by Hill's method (`None` if not computed).
    pub fn stable(&self) -> Option<bool> {
        self.floquet.as_ref().map(|f| f.stable)
    }
}

/// A located limit point (fold) of the branch.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitPoint {
    /// The point.
    pub point: BranchPoint,
    /// Index in [`Branch::points`] where it was inserted.
    pub index: usize,
}

/// Continuation parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    Omega,
    Gamma,
}

/// A computed branch (ordered along the arclength).
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    pub parameter: Parameter,
    pub harmonics: usize,
    pub points: Vec<BranchPoint>,
    /// Folds in branch order (their points are also in `points`).
    pub limit_points: Vec<LimitPoint>,
    /// Local maxima of the first-harmonic amplitude along the branch,
    /// located like the folds (secant on `d(a₁²+b₁²)/ds = 0`), in branch
    /// order (not inserted in `points`).
    pub peaks: Vec<BranchPoint>,
    /// Samples per period at the end.
    pub samples: usize,
    /// Set when the branch stopped early: the reason (the branch up to
    /// there is valid).
    pub warning: Option<MhbError>,
    /// Newton iterations in total (corrector + fold location).
    pub newton_iterations: usize,
}

struct Cont<'a> {
    sys: &'a mut HbSystem,
    param: Parameter,
    /// fixed other parameter (Ω when continuing in γ)
    fixed: f64,
    qs: f64,
    ps: f64,
    n: usize,
    iterations: usize,
    /// `[J̃ | R̃_p]` at the point returned by the last corrector, reused
    /// for the tangent there.
    last_m: Option<DMatrix<f64>>,
    q_buf: Vec<f64>,
    r_buf: Vec<f64>,
    jac_buf: Vec<f64>,
    dro_buf: Vec<f64>,
}

impl Cont<'_> {
    fn pq(&self, y: &[f64]) -> (Vec<f64>, f64) {
        let q: Vec<f64> = y[..self.n].iter().map(|v| v * self.qs).collect();
        (q, y[self.n] * self.ps)
    }

    /// Evaluates at `y`: the residual goes to `self.r`; returns
    /// `(‖R‖∞, residual scale, A)` with `A` the `(n+1)×(n+1)` matrix whose
    /// first `n` rows are `[J̃ | R̃_p]` and whose last row is zero (for the
    /// caller's bordering row). Buffers are reused (no allocation but `A`).
    fn eval(&mut self, y: &[f64]) -> (f64, f64, DMatrix<f64>) {
        let n = self.n;
        for (qv, yv) in self.q_buf.iter_mut().zip(&y[..n]) {
            *qv = yv * self.qs;
        }
        let p = y[n] * self.ps;
        let (omega, gamma) = match self.param {
            Parameter::Omega => (p, self.sys.gamma()),
            Parameter::Gamma => (self.fixed, p),
        };
        self.sys.set_gamma(gamma);
        self.sys.residual_jacobian(
            &self.q_buf,
            omega,
            &mut self.r_buf,
            &mut self.jac_buf,
            &mut self.dro_buf,
        );
        let mut m = DMatrix::zeros(n + 1, n + 1);
        for i in 0..n {
            for j in 0..n {
                m[(i, j)] = self.jac_buf[i * n + j] * self.qs;
            }
            m[(i, n)] = match self.param {
                Parameter::Omega => self.dro_buf[i] * self.ps,
                Parameter::Gamma => {
                    if i == 1 {
                        -self.ps
                    } else {
                        0.0
                    }
                }
            };
        }
        let rn = self.r_buf.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let scale = self.sys.residual_scale(&self.q_buf, omega);
        (rn, scale, m)
    }

    fn tangent(&mut self, y: &[f64], t_prev: &[f64]) -> Option<Vec<f64>> {
        let (_, _, m) = self.eval(y);
        self.tangent_of(m, t_prev)
    }

    /// Tangent at the point just returned by [`Cont::correct`].
    fn tangent_after_correct(&mut self, y: &[f64], t_prev: &[f64]) -> Option<Vec<f64>> {
        match self.last_m.take() {
            Some(m) => self.tangent_of(m, t_prev),
            None => self.tangent(y, t_prev),
        }
    }

    /// Solves `[J̃ R̃_p; t_prevᵀ] t = e_{n+1}` (`a` holds the first n rows).
    fn tangent_of(&self, mut a: DMatrix<f64>, t_prev: &[f64]) -> Option<Vec<f64>> {
        let n = self.n;
        for j in 0..=n {
            a[(n, j)] = t_prev[j];
        }
        let mut b = DVector::zeros(n + 1);
        b[n] = 1.0;
        let t = a.lu().solve(&b)?;
        let norm = t.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        let mut t: Vec<f64> = t.iter().map(|v| v / norm).collect();
        let dot: f64 = t.iter().zip(t_prev).map(|(a, b)| a * b).sum();
        if dot < 0.0 {
            t.iter_mut().for_each(|v| *v = -*v);
        }
        Some(t)
    }

    /// Newton on `R = 0, c·(y − y_c) = 0` from `y` (in place), where the
    /// constraint row is `c` (for a fixed parameter: the unit vector of p).
    /// Converged when `‖R‖∞ ≤ tol · scale` and `|c·(y − y_c)| ≤ 1e-12`; the
    /// bordered Jacobian at the returned point is kept for the tangent.
    fn correct(&mut self, y: &mut [f64], c: &[f64], yc: &[f64], max_it: usize) -> Option<usize> {
        let n = self.n;
        let tol = self.sys.settings.tol;
        self.last_m = None;
        for it in 0..=max_it {
            let (rn, scale, mut a) = self.eval(y);
            let g: f64 = c
                .iter()
                .zip(y.iter().zip(yc))
                .map(|(c, (a, b))| c * (a - b))
                .sum();
            if !rn.is_finite() {
                return None;
            }
            self.iterations += 1;
            if rn <= tol * scale && g.abs() <= 1e-12 {
                self.last_m = Some(a);
                return Some(it);
            }
            if it == max_it {
                break;
            }
            for j in 0..=n {
                a[(n, j)] = c[j];
            }
            let mut b = DVector::zeros(n + 1);
            for i in 0..n {
                b[i] = self.r_buf[i];
            }
            b[n] = g;
            let d = a.lu().solve(&b)?;
            for i in 0..=n {
                y[i] -= d[i];
            }
        }
        None
    }

    fn point(&mut self, y: &[f64], stability: bool) -> Result<BranchPoint, MhbError> {
        let (q, p) = self.pq(y);
        let (omega, gamma) = match self.param {
            Parameter::Omega => (p, self.sys.gamma()),
            Parameter::Gamma => (self.fixed, p),
        };
        self.sys.set_gamma(gamma);
        let floquet = if stability {
            Some(hill_floquet_exponents(self.sys, &q, omega)?)
        } else {
            None
        };
        Ok(BranchPoint {
            omega,
            gamma,
            coefficients: q,
            floquet,
        })
    }
}

/// Continuation in Ω from `omega_start` to `omega_end` (either order) at
/// level `gamma`, starting from the smallest-amplitude first-order steady
/// state at `omega_start`, with `h` harmonics.
pub fn continue_in_omega(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    h: usize,
    omega_start: f64,
    omega_end: f64,
    settings: HarmonicSettings,
    opts: &ContinuationOptions,
) -> Result<Branch, MhbError> {
    let model = &model.as_normalised()?;
    for (name, v) in [("omega_start", omega_start), ("omega_end", omega_end)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MhbError::InvalidValue { name, value: v });
        }
    }
    if omega_start == omega_end {
        return Err(MhbError::InvalidValue {
            name: "omega_end",
            value: omega_end,
        });
    }
    let mut sys = HbSystem::new(model, gamma, h, settings)?;
    let fr = ForcedResponse::from_normalised(model, gamma, Formulation::HarmonicBalance)?;
    let set = fr.steady_states(omega_start)?;
    let root = set
        .roots
        .first()
        .ok_or(MhbError::NoStart { omega: omega_start })?;
    let q0 = from_first_order(h, root.amplitude, root.phase);
    let ps = model.omega_n();
    run(
        &mut sys,
        Parameter::Omega,
        gamma,
        q0,
        omega_start,
        omega_end,
        ps,
        opts,
    )
}

/// Continuation in γ from `gamma_start` to `gamma_end` at fixed `omega`,
/// from the smallest-amplitude first-order steady state at `gamma_start`.
pub fn continue_in_gamma(
    model: &(impl AsNormalised + ?Sized),
    omega: f64,
    h: usize,
    gamma_start: f64,
    gamma_end: f64,
    settings: HarmonicSettings,
    opts: &ContinuationOptions,
) -> Result<Branch, MhbError> {
    let model = &model.as_normalised()?;
    if !(omega.is_finite() && omega > 0.0) {
        return Err(MhbError::InvalidValue {
            name: "omega",
            value: omega,
        });
    }
    for (name, v) in [("gamma_start", gamma_start), ("gamma_end", gamma_end)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MhbError::InvalidValue { name, value: v });
        }
    }
    if gamma_start == gamma_end {
        return Err(MhbError::InvalidValue {
            name: "gamma_end",
            value: gamma_end,
        });
    }
    let gmax = gamma_start.max(gamma_end);
    let mut sys = HbSystem::new(model, gmax, h, settings)?;
    sys.set_gamma(gamma_start);
    let fr = ForcedResponse::from_normalised(model, gamma_start, Formulation::HarmonicBalance)?;
    let set = fr.steady_states(omega)?;
    let root = set.roots.first().ok_or(MhbError::NoStart { omega })?;
    let q0 = from_first_order(h, root.amplitude, root.phase);
    run(
        &mut sys,
        Parameter::Gamma,
        omega,
        q0,
        gamma_start,
        gamma_end,
        gmax,
        opts,
    )
}

#[allow(clippy::too_many_arguments)]
fn run(
    sys: &mut HbSystem,
    param: Parameter,
    fixed: f64,
    q0: Vec<f64>,
    p_start: f64,
    p_end: f64,
    ps: f64,
    opts: &ContinuationOptions,
) -> Result<Branch, MhbError> {
    for (name, v) in [
        ("ds0", opts.ds0),
        ("ds_min", opts.ds_min),
        ("ds_max", opts.ds_max),
        ("max_dp", opts.max_dp),
        ("max_angle", opts.max_angle),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MhbError::InvalidValue { name, value: v });
        }
    }
    let h = sys.harmonics();
    let n = n_coefficients(h);
    let qs = sys.gamma() / sys.model().alpha;
    // first point: damped Newton at fixed p with N adaptation (the solver
    // of `solve_at`; the undamped corrector of the continuation diverged from
    // the first-order start of a friction oscillator far below resonance,
    // issue 30: Coulomb from 2 Hz)
    let om0 = if param == Parameter::Omega {
        p_start
    } else {
        fixed
    };
    let mut q0 = q0;
    super::solve_from(sys, om0, &mut q0)?;
    let mut c = Cont {
        sys,
        param,
        fixed,
        qs,
        ps,
        n,
        iterations: 0,
        last_m: None,
        q_buf: vec![0.0; n],
        r_buf: vec![0.0; n],
        jac_buf: vec![0.0; n * n],
        dro_buf: vec![0.0; n],
    };
    let dir = (p_end - p_start).signum();
    let p_lo = p_start.min(p_end);
    let p_hi = p_start.max(p_end);
    let dp_max = opts.max_dp * (p_hi - p_lo) / ps;

    let mut y: Vec<f64> = q0.iter().map(|v| v / qs).collect();
    y.push(p_start / ps);
    let mut ep = vec![0.0; n + 1];
    ep[n] = 1.0;
    let mut t_prev = vec![0.0; n + 1];
    t_prev[n] = dir;
    let mut t = c.tangent(&y, &t_prev).ok_or(MhbError::Singular {
        omega: if param == Parameter::Omega {
            p_start
        } else {
            fixed
        },
        gamma: c.sys.gamma(),
    })?;
    let mut points = vec![c.point(&y, opts.stability)?];
    let mut limit_points = Vec::new();
    let mut peaks = Vec::new();
    let mut ds = opts.ds0.min(opts.ds_max);
    let mut rejections = 0usize;
    let mut warning = None;
    let mut finished = false;
    while points.len() < opts.max_points && !finished {
        // cap the parameter step
        let step = if t[n].abs() * ds > dp_max {
            dp_max / t[n].abs()
        } else {
            ds
        };
        let yp: Vec<f64> = y.iter().zip(&t).map(|(a, b)| a + step * b).collect();
        let mut yn = yp.clone();
        let res = c.correct(&mut yn, &t, &yp, opts.max_corrector);
        let mut ok = false;
        let mut its = 0;
        let mut tn = Vec::new();
        if let Some(k) = res {
            its = k;
            if let Some(tt) = c.tangent_after_correct(&yn, &t) {
                let dot: f64 = tt.iter().zip(&t).map(|(a, b)| a * b).sum();
                if dot.clamp(-1.0, 1.0).acos() <= opts.max_angle {
                    ok = true;
                    tn = tt;
                }
            }
        }
        if !ok {
            rejections += 1;
            ds = 0.5 * step;
            if ds < opts.ds_min || rejections > 4 * opts.max_points {
                let (_, p) = c.pq(&y);
                warning = Some(MhbError::NoConvergence {
                    omega: if param == Parameter::Omega { p } else { fixed },
                    iterations: opts.max_corrector,
                    residual: f64::NAN,
                });
                break;
            }
            continue;
        }
        // aliasing control at the new point
        {
            let (q, p) = c.pq(&yn);
            let om = if param == Parameter::Omega { p } else { fixed };
            let n0 = c.sys.samples();
            if let Err(e) = c.sys.adapt_samples(&q, om) {
                warning = Some(e);
                break;
            }
            if c.sys.samples() != n0 {
                let ypp = yp.clone();
                if c.correct(&mut yn, &t, &ypp, opts.max_corrector).is_none() {
                    ds = 0.5 * step;
                    continue;
                }
                tn = match c.tangent_after_correct(&yn, &t) {
                    Some(v) => v,
                    None => {
                        ds = 0.5 * step;
                        continue;
                    }
                };
            }
        }
        // crossing the end of the range: solve at p_end exactly and stop
        let p_new = yn[n] * ps;
        if (p_new - p_end) * dir >= 0.0 {
            let frac = (p_end / ps - y[n]) / (yn[n] - y[n]);
            let mut ye: Vec<f64> = y.iter().zip(&yn).map(|(a, b)| a + frac * (b - a)).collect();
            ye[n] = p_end / ps;
            let yfix = ye.clone();
            if c.correct(&mut ye, &ep, &yfix, opts.max_corrector * 2)
                .is_some()
            {
                // only if the branch reaches the end without folding back
                if t[n] * dir > 0.0 && tn[n] * dir > 0.0 {
                    points.push(c.point(&ye, opts.stability)?);
                    finished = true;
                    continue;
                }
            }
        }
        // fold between y and yn?
        if t[n] * tn[n] < 0.0 {
            if let Some((yf, its_f)) = locate_fold(&mut c, &y, &t, step) {
                let _ = its_f;
                let pt = c.point(&yf, opts.stability)?;
                limit_points.push(LimitPoint {
                    point: pt.clone(),
                    index: points.len(),
                });
                points.push(pt);
            }
        }
        // first-harmonic amplitude maximum between y and yn?
        let (g0, g1) = (amplitude_slope(&y, &t), amplitude_slope(&yn, &tn));
        if g0 > 0.0 && g1 <= 0.0 {
            let tol = 1e-13 * (y[1].abs() + y[2].abs());
            if let Some((yp, _)) = locate_zero(&mut c, &y, &t, step, tol, amplitude_slope) {
                peaks.push(c.point(&yp, false)?);
            }
        }
        points.push(c.point(&yn, opts.stability)?);
        y = yn;
        t = tn;
        ds = if its <= 2 {
            step * 1.5
        } else if its <= 4 {
            step
        } else {
            step * 0.7
        }
        .min(opts.ds_max);
        if p_new < 0.0 {
            break;
        }
    }
    if !finished && warning.is_none() {
        let (_, p) = c.pq(&y);
        warning = Some(MhbError::InvalidValue {
            name: "max_points reached before the end of the range at parameter",
            value: p,
        });
    }
    Ok(Branch {
        parameter: param,
        harmonics: h,
        points,
        limit_points,
        peaks,
        samples: c.sys.samples(),
        warning,
        newton_iterations: c.iterations,
    })
}

/// Secant (Illinois) on `s ↦ t_p(y(s))` in `(0, s1)`.
fn locate_fold(c: &mut Cont<'_>, y0: &[f64], t0: &[f64], s1: f64) -> Option<(Vec<f64>, usize)> {
    let n = c.n;
    locate_zero(c, y0, t0, s1, 1e-10, move |_, t| t[n])
}

/// `½ d(a₁² + b₁²)/ds` in scaled coordinates (zero at a first-harmonic
/// amplitude extremum along the branch).
fn amplitude_slope(y: &[f64], t: &[f64]) -> f64 {
    y[1] * t[1] + y[2] * t[2]
}

/// Secant (Illinois) on `s ↦ g(y(s), t(s))` in `(0, s1)`, `y(s)` the
/// corrected point at arclength `s` from `y0` along `t0`; stops at
/// `|g| ≤ tol` or a bracket below 1e-14·s1 (60 iterations at most).
fn locate_zero(
    c: &mut Cont<'_>,
    y0: &[f64],
    t0: &[f64],
    s1: f64,
    tol: f64,
    g: impl Fn(&[f64], &[f64]) -> f64,
) -> Option<(Vec<f64>, usize)> {
    let eval = |c: &mut Cont<'_>, s: f64| -> Option<(f64, Vec<f64>)> {
        let yp: Vec<f64> = y0.iter().zip(t0).map(|(a, b)| a + s * b).collect();
        let mut y = yp.clone();
        c.correct(&mut y, t0, &yp, 12)?;
        let t = c.tangent_after_correct(&y, t0)?;
        Some((g(&y, &t), y))
    };
    let (mut a, mut fa) = (0.0, g(y0, t0));
    let (mut b, (mut fb, mut yb)) = (s1, eval(c, s1)?);
    if fa * fb > 0.0 {
        return None;
    }
    for it in 0..60 {
        let s = (a * fb - b * fa) / (fb - fa);
        let (fs, ys) = eval(c, s)?;
        if fs.abs() <= tol || (b - a).abs() <= 1e-14 * s1.max(1e-300) {
            return Some((ys, it));
        }
        if fs * fb < 0.0 {
            a = b;
            fa = fb;
        } else {
            fa *= 0.5;
        }
        b = s;
        fb = fs;
        yb = ys;
    }
    Some((yb, 60))
}
