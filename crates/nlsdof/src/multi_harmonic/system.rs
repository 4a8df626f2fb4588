//! The multi-harmonic balance equations of the forced oscillator (Eq 32 per
//! unit mass), their residual and analytic Jacobian by AFT.
//!
//! ## Equations
//! With `τ = Ωt` and `x(τ) = a₀ + Σ_{k=1}^H (a_k cos kτ + b_k sin kτ)`
//! (layout in [`super::aft`]), `v = Ω dx/dτ`, the nonlinear force per unit
//! mass `f(τ) = β x|x|^ρ + κ v|v|^η` and its projection `F = P f`
//! (AFT), Galerkin projection of
//! `x'' + δ x' + α x + f = γ cos Ωt` on `{1, cos kτ, sin kτ}` gives
//!
//! ```text
//! R₀    = α a₀ + F₀
//! R_a,k = (α − k²Ω²) a_k + δ k Ω b_k + F_a,k − γ [k = 1]
//! R_b,k = (α − k²Ω²) b_k − δ k Ω a_k + F_b,k
//! ```
//!
//! The constant and the even harmonics are unknowns too, so asymmetric
//! (symmetry-broken) responses are representable. For the symmetric
//! power laws of Eq 32 and symmetric starting guesses they stay zero (to
//! rounding) unless a symmetry-breaking bifurcation is followed.
//!
//! ## Jacobian (analytic, by AFT)
//! `∂F/∂q = P[f_x(τ) φ_j(τ)] + Ω P[f_v(τ) φ_j'(τ)]` with
//! `f_x = β (ρ+1)|x|^ρ`, `f_v = κ (η+1)|v|^η`: one FFT each of `f_x` and
//! `f_v`, then the product-to-sum formulas of [`super::aft`].
//! `∂F/∂Ω = P[f_v · dx/dτ]`, `∂R/∂γ = −e_{a,1}`.
//!
//! ## Number of time samples N
//! The projection is the trapezoidal rule, exact for polynomial terms
//! (`ρ` or `η` an even integer ≥ 0: `y|y|^μ = y^{μ+1}`) when
//! `N > (μ+2)H`. For real exponents `y|y|^μ` has a `|y|^{μ+1}`-type
//! singularity at each zero of `x` (or `v`), its Fourier coefficients decay
//! only like `m^{−(μ+2)}`, and the projection carries an aliasing error of
//! that order in `N`. `N` is therefore chosen at run time
//! ([`HbSystem::adapt_samples`]): starting from the smallest power of two
//! above the polynomial bound (at least `4H+2`, at least 16), `N` is
//! doubled until the change of the force coefficients between `N` and `2N`
//! — an estimate of the aliasing error at `N`, since the error at `2N` is
//! `2^{μ+2}` times smaller — is below `aliasing_tol · γ`, up to
//! [`MAX_SAMPLES`] (else [`MhbError::Aliasing`]).
//!
//! ## Negative exponents (Coulomb friction, η = −1) — regularisation
//! For `μ < 0` the derivative `(μ+1)|y|^μ` is unbounded at `y = 0` (and for
//! `μ = −1` the force `κ sgn v` jumps), so Newton on the sampled equations
//! is ill-posed. Such a term is replaced by
//!
//! ```text
//! y |y|^μ  ≈  y (y² + ε²)^{μ/2}         (μ = −1: κ v / √(v² + ε²))
//! d/dy     =  (y² + ε²)^{μ/2 − 1} ((1+μ) y² + ε²)
//! ```
//!
//! smooth, odd, equal to the original for `|y| ≫ ε`. The width is fixed per
//! system (so a continuation follows the branch of one fixed equation):
//! `ε_v = ε_rel γ/ω_n` for the velocity and `ε_x = ε_rel γ/α` for the
//! displacement (the velocity and displacement of the static response),
//! `ε_rel` = [`HarmonicSettings::regularisation`]. The regularisation error must be
//! checked, not assumed: [`regularisation_check`](super::regularisation_check)
//! re-solves with `ε/4` and reports the change. The adaptive `N` resolves
//! the layer of width `ε` automatically.

use super::aft::{add_product_matrix, n_coefficients, Aft};
use super::MhbError;
use crate::model::NormalisedModel;
use realfft::num_complex::Complex;

/// Largest number of harmonics accepted.
pub const MAX_HARMONICS: usize = 128;
/// Largest number of time samples per period.
pub const MAX_SAMPLES: usize = 1 << 18;

/// Numerical settings of the multi-harmonic balance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarmonicSettings {
    /// Newton converges when `‖R‖∞ ≤ tol · (γ + max_k (α + k²Ω²)|q_k|)` (the
    /// size of the largest linear term); one more Newton step is then taken.
    pub tol: f64,
    /// Newton iteration cap.
    pub max_iterations: usize,
    /// Aliasing tolerance relative to γ (see the module docs).
    pub aliasing_tol: f64,
    /// Fixed number of samples instead of the adaptive rule (`None`: adaptive).
    pub samples: Option<usize>,
    /// Relative width ε_rel of the regularisation of negative exponents.
    pub regularisation: f64,
}

impl Default for HarmonicSettings {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            max_iterations: 40,
            aliasing_tol: 1e-11,
            samples: None,
            regularisation: 1e-3,
        }
    }
}

/// Nonlinear force `c y|y|^μ` and derivative, with the regularisation for
/// `μ < 0` (`eps` > 0).
#[inline]
fn power_force(c: f64, mu: f64, eps: f64, y: f64) -> (f64, f64) {
    if mu < 0.0 {
        let s = y * y + eps * eps;
        let p = s.powf(0.5 * mu);
        (c * y * p, c * p * ((1.0 + mu) * y * y + eps * eps) / s)
    } else if mu == 2.0 {
        (c * y * y * y, 3.0 * c * y * y)
    } else if mu == 1.0 {
        (c * y * y.abs(), 2.0 * c * y.abs())
    } else if mu == 0.0 {
        (c * y, c)
    } else {
        let p = y.abs().powf(mu);
        (c * y * p, c * (mu + 1.0) * p)
    }
}

/// Smallest N for which a polynomial term is exactly projected, or the
/// starting N for a real exponent.
fn minimal_samples(h: usize, model: &NormalisedModel) -> usize {
    let mut deg = 1.0f64;
    for (c, mu) in [(model.beta, model.rho), (model.kappa, model.eta)] {
        if c != 0.0 {
            let d = if mu >= 0.0 { mu + 1.0 } else { 3.0 };
            deg = deg.max(d);
        }
    }
    let need = ((deg + 1.0) * h as f64).ceil() as usize + 2;
    need.max(4 * h + 2).max(16).next_power_of_two()
}

fn is_polynomial(mu: f64) -> bool {
    mu >= 0.0 && mu.fract() == 0.0 && (mu as i64) % 2 == 0
}

/// Multi-harmonic balance equations of one model at one input level.
#[derive(Debug, Clone)]
pub struct HbSystem {
    pub(crate) model: NormalisedModel,
    pub(crate) gamma: f64,
    pub(crate) h: usize,
    pub(crate) settings: HarmonicSettings,
    eps_x: f64,
    eps_v: f64,
    aft: Aft,
    x: Vec<f64>,
    dx: Vec<f64>,
    f: Vec<f64>,
    fx: Vec<f64>,
    fv: Vec<f64>,
    wx: Vec<Complex<f64>>,
    wv: Vec<Complex<f64>>,
}

impl HbSystem {
    /// `h` harmonics (1 ≤ h ≤ [`MAX_HARMONICS`]) for `model` at level
    /// `gamma` (m/s², > 0).
    pub fn new(
        model: &NormalisedModel,
        gamma: f64,
        h: usize,
        settings: HarmonicSettings,
    ) -> Result<Self, MhbError> {
        model.validate()?;
        if h == 0 {
            return Err(MhbError::Harmonics {
                value: h,
                max: MAX_HARMONICS,
            });
        }
        if h > MAX_HARMONICS {
            return Err(MhbError::Harmonics {
                value: h,
                max: MAX_HARMONICS,
            });
        }
        if !(gamma.is_finite() && gamma > 0.0) {
            return Err(MhbError::InvalidValue {
                name: "gamma",
                value: gamma,
            });
        }
        for (name, v) in [
            ("tol", settings.tol),
            ("aliasing_tol", settings.aliasing_tol),
            ("regularisation", settings.regularisation),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(MhbError::InvalidValue { name, value: v });
            }
        }
        let n = match settings.samples {
            Some(n) if n <= 4 * h || n > MAX_SAMPLES => {
                return Err(MhbError::InvalidValue {
                    name: "samples",
                    value: n as f64,
                })
            }
            Some(n) => n,
            None => minimal_samples(h, model),
        };
        let eps_v = settings.regularisation * gamma / model.omega_n();
        let eps_x = settings.regularisation * gamma / model.alpha;
        let mut s = Self {
            model: *model,
            gamma,
            h,
            settings,
            eps_x,
            eps_v,
            aft: Aft::new(h, n),
            x: Vec::new(),
            dx: Vec::new(),
            f: Vec::new(),
            fx: Vec::new(),
            fv: Vec::new(),
            wx: vec![Complex::new(0.0, 0.0); 2 * h + 1],
            wv: vec![Complex::new(0.0, 0.0); 2 * h + 1],
        };
        s.resize();
        Ok(s)
    }

    fn resize(&mut self) {
        let n = self.aft.samples();
        for b in [
            &mut self.x,
            &mut self.dx,
            &mut self.f,
            &mut self.fx,
            &mut self.fv,
        ] {
            b.clear();
            b.resize(n, 0.0);
        }
    }

    /// Number of harmonics H.
    pub fn harmonics(&self) -> usize {
        self.h
    }

    /// Unknowns per solution, `2H+1`.
    pub fn dim(&self) -> usize {
        n_coefficients(self.h)
    }

    /// Samples per period N in use.
    pub fn samples(&self) -> usize {
        self.aft.samples()
    }

    /// Input level γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Changes the input level (for continuation in γ).
    pub fn set_gamma(&mut self, gamma: f64) {
        self.gamma = gamma;
    }

    /// The model.
    pub fn model(&self) -> &NormalisedModel {
        &self.model
    }

    /// Regularisation widths (ε_x, ε_v), used only for negative exponents.
    pub fn regularisation_widths(&self) -> (f64, f64) {
        (self.eps_x, self.eps_v)
    }

    /// Sets the regularisation widths (absolute, m and m/s).
    pub fn set_regularisation_widths(&mut self, eps_x: f64, eps_v: f64) {
        self.eps_x = eps_x;
        self.eps_v = eps_v;
    }

    /// `true` if a term with a negative exponent is present (regularised).
    pub fn is_regularised(&self) -> bool {
        (self.model.beta != 0.0 && self.model.rho < 0.0)
            || (self.model.kappa != 0.0 && self.model.eta < 0.0)
    }

    /// `true` if every nonlinear term is projected exactly (even integer
    /// exponents ≥ 0) for the current N.
    pub fn is_exact(&self) -> bool {
        (self.model.beta == 0.0 || is_polynomial(self.model.rho))
            && (self.model.kappa == 0.0 || is_polynomial(self.model.eta))
    }

    /// Samples x, dx/dτ and the nonlinear force (and its partial derivatives
    /// if `derivs`) at the current N.
    fn evaluate_time(&mut self, q: &[f64], omega: f64, derivs: bool) {
        self.aft.synthesize(q, false, &mut self.x);
        self.aft.synthesize(q, true, &mut self.dx);
        let m = &self.model;
        for i in 0..self.x.len() {
            let (fs, dfs) = if m.beta != 0.0 {
                power_force(m.beta, m.rho, self.eps_x, self.x[i])
            } else {
                (0.0, 0.0)
            };
            let (fd, dfd) = if m.kappa != 0.0 {
                power_force(m.kappa, m.eta, self.eps_v, omega * self.dx[i])
            } else {
                (0.0, 0.0)
            };
            self.f[i] = fs + fd;
            if derivs {
                self.fx[i] = dfs;
                self.fv[i] = dfd;
            }
        }
    }

    /// Nonlinear force coefficients `F = P f` (length 2H+1) into `out`.
    pub fn nonlinear_force(&mut self, q: &[f64], omega: f64, out: &mut [f64]) {
        self.evaluate_time(q, omega, false);
        let f = std::mem::take(&mut self.f);
        self.aft.analyse(&f, out);
        self.f = f;
    }

    fn add_linear(&self, q: &[f64], omega: f64, r: &mut [f64]) {
        let m = &self.model;
        r[0] += m.alpha * q[0];
        for k in 1..=self.h {
            let kf = k as f64;
            let (a, b) = (q[2 * k - 1], q[2 * k]);
            let s = m.alpha - kf * kf * omega * omega;
            let d = m.delta * kf * omega;
            r[2 * k - 1] += s * a + d * b;
            r[2 * k] += s * b - d * a;
        }
        r[1] -= self.gamma;
    }

    /// Residual `R(q, Ω)` into `r`.
    pub fn residual(&mut self, q: &[f64], omega: f64, r: &mut [f64]) {
        self.nonlinear_force(q, omega, r);
        self.add_linear(q, omega, r);
    }

    /// Residual, Jacobian `∂R/∂q` (row-major `n×n`) and `∂R/∂Ω`.
    pub fn residual_jacobian(
        &mut self,
        q: &[f64],
        omega: f64,
        r: &mut [f64],
        jac: &mut [f64],
        dr_domega: &mut [f64],
    ) {
        let n = self.dim();
        self.evaluate_time(q, omega, true);
        let f = std::mem::take(&mut self.f);
        self.aft.analyse(&f, r);
        self.f = f;
        self.add_linear(q, omega, r);
        jac.iter_mut().for_each(|v| *v = 0.0);
        let m = self.model;
        let fx = std::mem::take(&mut self.fx);
        let fv = std::mem::take(&mut self.fv);
        if m.beta != 0.0 {
            let mut w = std::mem::take(&mut self.wx);
            self.aft.spectrum_normalised(&fx, &mut w);
            add_product_matrix(&w, self.h, 1.0, false, jac);
            self.wx = w;
        }
        dr_domega.iter_mut().for_each(|v| *v = 0.0);
        if m.kappa != 0.0 {
            let mut w = std::mem::take(&mut self.wv);
            self.aft.spectrum_normalised(&fv, &mut w);
            add_product_matrix(&w, self.h, omega, true, jac);
            self.wv = w;
            // ∂F/∂Ω = P[f_v dx/dτ]
            let mut prod = std::mem::take(&mut self.f);
            for i in 0..prod.len() {
                prod[i] = fv[i] * self.dx[i];
            }
            self.aft.analyse(&prod, dr_domega);
            self.f = prod;
        }
        self.fx = fx;
        self.fv = fv;
        jac[0] += m.alpha;
        for k in 1..=self.h {
            let kf = k as f64;
            let (ia, ib) = (2 * k - 1, 2 * k);
            let s = m.alpha - kf * kf * omega * omega;
            let d = m.delta * kf * omega;
            jac[ia * n + ia] += s;
            jac[ia * n + ib] += d;
            jac[ib * n + ia] -= d;
            jac[ib * n + ib] += s;
            let (a, b) = (q[ia], q[ib]);
            dr_domega[ia] += -2.0 * kf * kf * omega * a + m.delta * kf * b;
            dr_domega[ib] += -2.0 * kf * kf * omega * b - m.delta * kf * a;
        }
    }

    /// Residual scale `γ + max_k (α + k²Ω²) |q_k|` (the largest linear term
    /// of the balance) used by the convergence test.
    pub fn residual_scale(&self, q: &[f64], omega: f64) -> f64 {
        let mut s = self.model.alpha * q[0].abs();
        for k in 1..=self.h {
            let kf = k as f64;
            let c = self.model.alpha + kf * kf * omega * omega;
            s = s.max(c * q[2 * k - 1].abs()).max(c * q[2 * k].abs());
        }
        self.gamma + s
    }

    /// Aliasing estimate at state `(q, Ω)`: `max |F_N − F_2N| / γ`
    /// (`/ (α‖q‖∞)` when γ = 0).
    pub fn aliasing_estimate(&mut self, q: &[f64], omega: f64) -> f64 {
        if self.is_exact() {
            return 0.0;
        }
        let n = self.dim();
        let mut f1 = vec![0.0; n];
        self.nonlinear_force(q, omega, &mut f1);
        let mut twice = self.clone_with_samples(2 * self.samples());
        let mut f2 = vec![0.0; n];
        twice.nonlinear_force(q, omega, &mut f2);
        // relative to γ (forced response), or to the linear restoring force
        // α‖q‖∞ when γ = 0 (backbone)
        let reference = if self.gamma > 0.0 {
            self.gamma
        } else {
            self.model.alpha * q.iter().fold(0.0f64, |a, v| a.max(v.abs()))
        };
        f1.iter()
            .zip(&f2)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
            / reference
    }

    fn clone_with_samples(&self, n: usize) -> Self {
        let mut s = self.clone();
        s.aft = Aft::new(self.h, n);
        s.resize();
        s
    }

    /// Sets the number of samples N (> 4H, ≤ [`MAX_SAMPLES`]).
    pub fn set_samples(&mut self, n: usize) -> Result<(), MhbError> {
        if n <= 4 * self.h || n > MAX_SAMPLES {
            return Err(MhbError::InvalidValue {
                name: "samples",
                value: n as f64,
            });
        }
        if n != self.samples() {
            self.aft = Aft::new(self.h, n);
            self.resize();
        }
        Ok(())
    }

    /// Doubles N until the aliasing estimate at `(q, Ω)` is below
    /// `aliasing_tol` (no-op with fixed samples or exact projection).
    /// Returns the estimate at the final N.
    pub fn adapt_samples(&mut self, q: &[f64], omega: f64) -> Result<f64, MhbError> {
        if self.settings.samples.is_some() || self.is_exact() {
            return Ok(0.0);
        }
        loop {
            let est = self.aliasing_estimate(q, omega);
            if !est.is_finite() {
                return Err(MhbError::NotFinite { omega });
            }
            if est <= self.settings.aliasing_tol {
                return Ok(est);
            }
            let n = self.samples();
            if 2 * n > MAX_SAMPLES {
                return Err(MhbError::Aliasing {
                    samples: n,
                    estimate: est,
                    tolerance: self.settings.aliasing_tol,
                });
            }
            self.aft = Aft::new(self.h, 2 * n);
            self.resize();
        }
    }

    /// Newton's method at fixed Ω from `q` (updated in place). Returns the
    /// number of iterations. Step halving (up to 20 times) when the
    /// residual norm does not decrease.
    pub fn solve(&mut self, q: &mut [f64], omega: f64) -> Result<usize, MhbError> {
        let n = self.dim();
        let mut r = vec![0.0; n];
        let mut jac = vec![0.0; n * n];
        let mut dro = vec![0.0; n];
        let mut trial = vec![0.0; n];
        let mut rt = vec![0.0; n];
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let mut converged_once = false;
        for it in 0..self.settings.max_iterations {
            self.residual_jacobian(q, omega, &mut r, &mut jac, &mut dro);
            let rn = norm(&r);
            if !rn.is_finite() {
                return Err(MhbError::NotFinite { omega });
            }
            if rn <= self.settings.tol * self.residual_scale(q, omega) {
                if converged_once {
                    return Ok(it);
                }
                converged_once = true;
            }
            let a = nalgebra::DMatrix::from_row_slice(n, n, &jac);
            let b = nalgebra::DVector::from_column_slice(&r);
            let dx = a.lu().solve(&b).ok_or(MhbError::Singular {
                omega,
                gamma: self.gamma,
            })?;
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..20 {
                for i in 0..n {
                    trial[i] = q[i] - lambda * dx[i];
                }
                self.residual(&trial, omega, &mut rt);
                let tn = norm(&rt);
                if tn.is_finite() && (tn < rn || converged_once || tn <= 1e-300) {
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                return Err(MhbError::NoConvergence {
                    omega,
                    iterations: it + 1,
                    residual: rn / self.gamma,
                });
            }
            q.copy_from_slice(&trial);
            if converged_once {
                return Ok(it + 1);
            }
        }
        self.residual(q, omega, &mut r);
        Err(MhbError::NoConvergence {
            omega,
            iterations: self.settings.max_iterations,
            residual: norm(&r) / self.gamma,
        })
    }
}

impl HbSystem {
    /// The matrices of Hill's method at `(q, Ω)`: the HB Jacobian `∂R/∂q`
    /// and `W_v`, the matrix of "multiply by `f_v(τ)` and project" (both
    /// row-major `n × n`). See [`super::stability`].
    pub fn hill_matrices(&mut self, q: &[f64], omega: f64) -> (Vec<f64>, Vec<f64>) {
        let n = self.dim();
        let mut r = vec![0.0; n];
        let mut jac = vec![0.0; n * n];
        let mut dro = vec![0.0; n];
        self.residual_jacobian(q, omega, &mut r, &mut jac, &mut dro);
        let mut wv = vec![0.0; n * n];
        if self.model.kappa != 0.0 {
            add_product_matrix(&self.wv, self.h, 1.0, false, &mut wv);
        }
        (jac, wv)
    }
}
