//! Fast Relaxed Vector Fitting (FRVF) of one complex FRF.
//!
//! ## Model
//!
//! ```text
//! H(s) ≈ Σ_{n=1}^{N} r_n/(s − a_n) + d + s e                      (Gustavsen & Semlyen 1999)
//! ```
//!
//! Complex poles come in conjugate pairs `(a, ā)` with residues `(r, r̄)`;
//! real poles have real residues. `N = 2 × pole_pairs`.
//!
//! ## Frequency normalisation
//!
//! All computations use `ŝ = jω/ω₀` with `ω₀ = max ω`, so the basis
//! columns are O(1); results are scaled back: `a = â ω₀`, `r = r̂ ω₀`,
//! `e = ê/ω₀`, `d = d̂`.
//!
//! ## One iteration (pole relocation)
//!
//! With the current poles `â_n` and an unknown weighting function
//!
//! ```text
//! σ(s) = Σ_n c̃_n/(s − â_n) + d̃                                     (Gustavsen & Semlyen 1999, relaxed: d̃ free)
//! ```
//!
//! the linearised problem `(σH)_fit(s_k) − σ(s_k) H(s_k) ≈ 0`, i.e.
//!
//! ```text
//! Σ_n c_n φ_n(s_k) + d + s_k e − H_k (Σ_n c̃_n φ_n(s_k) + d̃) ≈ 0     (Gustavsen & Semlyen 1999)
//! ```
//!
//! is solved for all unknowns by linear least squares, each equation
//! multiplied by the weight `w_k`, real and imaginary parts stacked. The
//! real basis of a complex pair is `φ' = 1/(s−a) + 1/(s−ā)`,
//! `φ'' = j/(s−a) − j/(s−ā)` (coefficients `c = c' + j c''`), which keeps
//! all unknowns real (Gustavsen & Semlyen 1999). The **fast** formulation
//! (Deschrijver et al. 2008) takes the QR factorisation `[A₁ A₂] = Q R` of
//! the matrix of the `(c, d, e)` columns `A₁` and the `(c̃, d̃)` columns
//! `A₂`; since the right-hand side is zero, `c̃, d̃` solve the small system
//! `R₂₂ [c̃; d̃] = 0` together with the **relaxation** row (Gustavsen 2006)
//!
//! ```text
//! Re Σ_k σ(s_k) = N_s            (prevents the trivial solution σ ≡ 0)
//! ```
//!
//! scaled by `‖w H‖₂ / N_s`. If `|d̃| < 10⁻⁸` it is fixed to `±10⁻⁸` and
//! the system re-solved. All least-squares problems are solved by
//! Householder QR (nalgebra) with columns scaled to unit norm.
//!
//! The new poles are the zeros of `σ` (Gustavsen & Semlyen 1999: `H = (σH)_fit/σ_fit`,
//! so the poles of `H` are the zeros of `σ`), the eigenvalues of
//! `Â − b̂ c̃ᵀ/d̃` with `Â` the real block-diagonal realisation of the poles
//! (`[â]` for a real pole with `b̂ = 1`; `[[a', a''], [−a'', a']]` with
//! `b̂ = [2, 0]ᵀ` for a pair `a' + j a''`), computed by a bounded real Schur
//! iteration. Unstable poles (`Re a > 0`) are flipped to `−|Re a| + j Im a`.
//!
//! Starting poles (Gustavsen & Semlyen 1999): `a = −β/100 ± jβ`, `β` spread linearly
//! (or logarithmically) over the band; the damping fraction `1/100` is
//! [`VfOptions::starting_damping`].
//!
//! After each relocation the residues `r_n, d, e` are found for the new
//! poles by weighted linear least squares (the same QR solver), and the RMS
//! error `sqrt(Σ_k |H_k − H_fit(s_k)|² / N_s)` (unweighted) is recorded.
//!
//! ## Stopping rule
//!
//! After iteration `i` the fit stops with
//! * [`VectorFitTermination::PolesConverged`] if `max_n |a_n⁽ⁱ⁾ − a_n⁽ⁱ⁻¹⁾| / |a_n⁽ⁱ⁾| ≤ pole_tolerance`,
//! * [`VectorFitTermination::ErrorFloor`] if the relative RMS error `≤ 10⁻¹³`
//!   (exact rational data),
//! * [`VectorFitTermination::Stagnated`] if `i ≥ 3` and the RMS error changed by
//!   less than `rms_tolerance` (relative) in each of the last two iterations
//!   (noisy data: the error has reached the noise floor),
//! * [`VectorFitTermination::MaxIterations`] after `max_iterations`.

use super::{validate_frf, VectorFitError, C64};
use nalgebra::{DMatrix, DVector};

/// Spacing of the starting poles' imaginary parts over the band.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    Linear,
    Logarithmic,
}

/// Options of [`vector_fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct VfOptions {
    /// Number of complex pole pairs `N/2` (>= 1).
    pub pole_pairs: usize,
    /// Include the constant term `d`.
    pub constant: bool,
    /// Include the proportional term `s e`.
    pub proportional: bool,
    /// Optional weight per sample (finite, > 0); `None` = uniform.
    pub weights: Option<Vec<f64>>,
    /// Iteration limit (>= 1).
    pub max_iterations: usize,
    /// Relative pole change that ends the iteration.
    pub pole_tolerance: f64,
    /// Relative RMS change below which the error counts as stagnated.
    pub rms_tolerance: f64,
    /// Spacing of the starting poles.
    pub spacing: Spacing,
    /// `α/β` of the starting poles `−αβ ± jβ` (G&S 1999: 0.01).
    pub starting_damping: f64,
    /// Flip unstable poles into the left half plane.
    pub flip_unstable: bool,
    /// Polled before each pole relocation and each residue solve: once
    /// set, the fit ends with [`VectorFitError::Interrupted`]
    /// ([`crate::cancel`]).
    pub cancel: crate::cancel::Cancel,
}

impl Default for VfOptions {
    fn default() -> Self {
        Self {
            pole_pairs: 1,
            constant: true,
            proportional: false,
            weights: None,
            max_iterations: 30,
            pole_tolerance: 1e-11,
            rms_tolerance: 1e-6,
            spacing: Spacing::Linear,
            starting_damping: 0.01,
            flip_unstable: true,
            cancel: crate::cancel::Cancel::NEVER,
        }
    }
}

/// One pole of the fitted model with its residue, physical units (rad/s).
/// `pole.im > 0`: a complex pair (the conjugate term `r̄/(s − ā)` is
/// implied); `pole.im == 0`: a real pole with real residue.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoleTerm {
    pub pole: C64,
    pub residue: C64,
}

impl PoleTerm {
    pub fn is_pair(&self) -> bool {
        self.pole.im > 0.0
    }
}

/// Why the iteration stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VectorFitTermination {
    /// Largest relative pole change fell to `change <= pole_tolerance`.
    PolesConverged { change: f64 },
    /// Relative RMS error below 1e-13 (exact rational data).
    ErrorFloor,
    /// RMS error stopped changing (noise floor); `change` = last relative change.
    Stagnated { change: f64 },
    /// `max_iterations` reached; `change` = last relative pole change.
    MaxIterations { change: f64 },
}

impl std::fmt::Display for VectorFitTermination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VectorFitTermination::PolesConverged { change } => {
                write!(f, "poles converged (relative change {change:.2e})")
            }
            VectorFitTermination::ErrorFloor => {
                write!(f, "error at round-off floor (exact rational data)")
            }
            VectorFitTermination::Stagnated { change } => {
                write!(f, "RMS error stagnated (relative change {change:.2e})")
            }
            VectorFitTermination::MaxIterations { change } => {
                write!(
                    f,
                    "iteration limit reached (last relative pole change {change:.2e})"
                )
            }
        }
    }
}

/// Result of [`vector_fit`] (physical units: poles and residues in rad/s).
#[derive(Debug, Clone, PartialEq)]
pub struct VfFit {
    /// Poles and residues, sorted by `|Im a|` then `Re a`.
    pub terms: Vec<PoleTerm>,
    /// `d` (0 when not fitted).
    pub constant: f64,
    /// `e`, in 1/(rad/s) (0 when not fitted).
    pub proportional: f64,
    /// Iterations performed.
    pub iterations: usize,
    /// RMS error after each iteration.
    pub rms_history: Vec<f64>,
    /// Final RMS error `sqrt(Σ|H_k − H_fit,k|²/N_s)`.
    pub rms_error: f64,
    /// `rms_error / sqrt(Σ|H_k|²/N_s)`.
    pub relative_rms_error: f64,
    pub termination: VectorFitTermination,
    /// Normalisation frequency `ω₀ = max ω`, rad/s.
    pub omega_scale: f64,
}

impl VfFit {
    /// Model value at angular frequency `omega` (rad/s).
    pub fn eval(&self, omega: f64) -> C64 {
        eval_terms(
            &self.terms,
            self.constant,
            self.proportional,
            C64::new(0.0, omega),
        )
    }

    /// Number of poles `N` (a pair counts twice).
    pub fn order(&self) -> usize {
        self.terms
            .iter()
            .map(|t| if t.is_pair() { 2 } else { 1 })
            .sum()
    }
}

fn eval_terms(terms: &[PoleTerm], d: f64, e: f64, s: C64) -> C64 {
    let mut v = C64::new(d, 0.0) + s * e;
    for t in terms {
        v += t.residue / (s - t.pole);
        if t.is_pair() {
            v += t.residue.conj() / (s - t.pole.conj());
        }
    }
    v
}

/// Number of real unknowns of the relocation problem for `opts`.
fn unknowns(opts: &VfOptions) -> usize {
    let n = 2 * opts.pole_pairs;
    n + opts.constant as usize + opts.proportional as usize + n + 1
}

fn check_options(omega: &[f64], h: &[C64], opts: &VfOptions) -> Result<(), VectorFitError> {
    validate_frf(omega, h)?;
    let bad = |name, value: String, reason| {
        Err(VectorFitError::BadOption {
            name,
            value,
            reason,
        })
    };
    if opts.pole_pairs == 0 {
        return bad("pole_pairs", "0".into(), "at least one pole pair is needed");
    }
    if opts.max_iterations == 0 {
        return bad(
            "max_iterations",
            "0".into(),
            "at least one iteration is needed",
        );
    }
    if !(opts.starting_damping.is_finite() && opts.starting_damping > 0.0) {
        return bad(
            "starting_damping",
            format!("{}", opts.starting_damping),
            "must be finite and > 0",
        );
    }
    if !(opts.pole_tolerance >= 0.0 && opts.rms_tolerance >= 0.0) {
        return bad(
            "tolerance",
            format!("{} / {}", opts.pole_tolerance, opts.rms_tolerance),
            "must be >= 0",
        );
    }
    let needed = unknowns(opts);
    if 2 * omega.len() < needed {
        return Err(VectorFitError::TooFewPoints {
            points: omega.len(),
            equations: 2 * omega.len(),
            unknowns: needed,
        });
    }
    if let Some(w) = &opts.weights {
        if w.len() != omega.len() {
            return bad(
                "weights",
                format!("{} values", w.len()),
                "need one weight per frequency",
            );
        }
        for (i, &x) in w.iter().enumerate() {
            if !(x.is_finite() && x > 0.0) {
                return Err(VectorFitError::BadWeight { index: i, value: x });
            }
        }
    }
    if omega[omega.len() - 1] <= 0.0 {
        return bad(
            "frequency range",
            format!("max {}", omega[omega.len() - 1]),
            "need a positive frequency",
        );
    }
    Ok(())
}

/// Starting poles (normalised): `−α β + j β`, pairs only.
fn starting_poles(wmin: f64, wmax: f64, pairs: usize, spacing: Spacing, alpha: f64) -> Vec<C64> {
    let betas: Vec<f64> = match spacing {
        Spacing::Linear => {
            if pairs == 1 {
                vec![0.5 * (wmin + wmax)]
            } else {
                (0..pairs)
                    .map(|i| wmin + (wmax - wmin) * i as f64 / (pairs - 1) as f64)
                    .collect()
            }
        }
        Spacing::Logarithmic => {
            let lo = wmin.max(wmax * 1e-3).ln();
            let hi = wmax.ln();
            if pairs == 1 {
                vec![(0.5 * (lo + hi)).exp()]
            } else {
                (0..pairs)
                    .map(|i| (lo + (hi - lo) * i as f64 / (pairs - 1) as f64).exp())
                    .collect()
            }
        }
    };
    betas
        .into_iter()
        .map(|b| C64::new(-alpha * b.max(1e-6), b.max(1e-6)))
        .collect()
}

/// Complex basis columns, column-major `ns × n_poles`, for poles stored with
/// `im >= 0` (`im == 0` real pole: one column; `im > 0` pair: two).
fn basis(s: &[C64], poles: &[C64]) -> (Vec<C64>, usize) {
    let n: usize = poles.iter().map(|p| if p.im > 0.0 { 2 } else { 1 }).sum();
    let ns = s.len();
    let mut phi = vec![C64::new(0.0, 0.0); ns * n];
    let mut col = 0;
    for &a in poles {
        if a.im > 0.0 {
            for (k, &sk) in s.iter().enumerate() {
                let p = 1.0 / (sk - a);
                let q = 1.0 / (sk - a.conj());
                phi[col * ns + k] = p + q;
                phi[(col + 1) * ns + k] = C64::new(0.0, 1.0) * (p - q);
            }
            col += 2;
        } else {
            for (k, &sk) in s.iter().enumerate() {
                phi[col * ns + k] = 1.0 / (sk - a);
            }
            col += 1;
        }
    }
    (phi, n)
}

/// Least squares `min ‖A x − b‖₂` by Householder QR with unit-norm column
/// scaling; directions with `|R_ii| <= 1e-14 max|R_jj|` are set to zero
/// (basic solution of a rank-deficient problem).
fn lstsq(mut a: DMatrix<f64>, mut b: DVector<f64>) -> Option<DVector<f64>> {
    let n = a.ncols();
    if a.nrows() < n {
        return None;
    }
    let mut scale = vec![1.0; n];
    for j in 0..n {
        let nrm = a.column(j).norm();
        if nrm > 0.0 && nrm.is_finite() {
            scale[j] = 1.0 / nrm;
            a.column_mut(j).scale_mut(1.0 / nrm);
        }
    }
    let qr = a.qr();
    qr.q_tr_mul(&mut b);
    let r = qr.r();
    let rmax = (0..n).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    if !(rmax > 0.0 && rmax.is_finite()) {
        return None;
    }
    let mut x = DVector::zeros(n);
    for i in (0..n).rev() {
        let rii = r[(i, i)];
        if rii.abs() <= 1e-14 * rmax {
            continue;
        }
        let mut acc = b[i];
        for j in i + 1..n {
            acc -= r[(i, j)] * x[j];
        }
        x[i] = acc / rii;
    }
    for j in 0..n {
        x[j] *= scale[j];
    }
    if x.iter().all(|v| v.is_finite()) {
        Some(x)
    } else {
        None
    }
}

struct Problem<'a> {
    s: Vec<C64>,
    f: &'a [C64],
    w: Vec<f64>,
    constant: bool,
    proportional: bool,
}

impl Problem<'_> {
    fn ns(&self) -> usize {
        self.s.len()
    }

    /// Columns `n`, `n + 1` of the weighted least-squares matrix (real parts
    /// in rows `0..ns`, imaginary parts in rows `ns..2ns`): the constant term
    /// `d·w_k` and the proportional term `e·s_k·w_k`, when fitted.
    fn fill_direct_terms(&self, a: &mut DMatrix<f64>, n: usize) {
        let ns = self.ns();
        let mut col = n;
        if self.constant {
            for k in 0..ns {
                a[(k, col)] = self.w[k];
            }
            col += 1;
        }
        if self.proportional {
            for k in 0..ns {
                let v = self.s[k] * self.w[k];
                a[(k, col)] = v.re;
                a[(ns + k, col)] = v.im;
            }
        }
    }

    /// One pole relocation; returns the new poles (im >= 0 storage).
    fn relocate(
        &self,
        poles: &[C64],
        iteration: usize,
        flip: bool,
    ) -> Result<Vec<C64>, VectorFitError> {
        let ns = self.ns();
        let (phi, n) = basis(&self.s, poles);
        let n1 = n + self.constant as usize + self.proportional as usize;
        let n2 = n + 1;
        let mut a = DMatrix::<f64>::zeros(2 * ns, n1 + n2);
        for j in 0..n {
            for k in 0..ns {
                let v = phi[j * ns + k] * self.w[k];
                a[(k, j)] = v.re;
                a[(ns + k, j)] = v.im;
                let g = -v * self.f[k];
                a[(k, n1 + j)] = g.re;
                a[(ns + k, n1 + j)] = g.im;
            }
        }
        self.fill_direct_terms(&mut a, n);
        for k in 0..ns {
            let g = -self.f[k] * self.w[k];
            a[(k, n1 + n)] = g.re;
            a[(ns + k, n1 + n)] = g.im;
        }
        // Fast VF: only the trailing block R₂₂ of the QR factor is needed.
        let r = a.qr().r();
        let r22 = r.view((n1, n1), (n2, n2)).into_owned();
        // Relaxation row: Re Σ_k σ(s_k) = N_s, scaled by ‖wH‖/N_s.
        let wf_norm = self
            .f
            .iter()
            .zip(&self.w)
            .map(|(f, w)| (f * *w).norm_sqr())
            .sum::<f64>()
            .sqrt();
        let scale = wf_norm / ns as f64;
        let mut m = DMatrix::<f64>::zeros(n2 + 1, n2);
        m.view_mut((0, 0), (n2, n2)).copy_from(&r22);
        for j in 0..n {
            let sum: f64 = (0..ns).map(|k| phi[j * ns + k].re).sum();
            m[(n2, j)] = scale * sum;
        }
        m[(n2, n)] = scale * ns as f64;
        let mut rhs = DVector::<f64>::zeros(n2 + 1);
        rhs[n2] = scale * ns as f64;
        let x = lstsq(m, rhs).ok_or(VectorFitError::Singular {
            iteration,
            what: "pole relocation",
        })?;
        let mut ct: Vec<f64> = x.iter().take(n).copied().collect();
        let mut dt = x[n];
        if dt.abs() < 1e-8 {
            // Relaxed d̃ degenerate: fix it and solve R₂₂ [c̃; d̃] = 0 for c̃.
            dt = if dt < 0.0 { -1e-8 } else { 1e-8 };
            let m2 = r22.view((0, 0), (n2, n)).into_owned();
            let b2 = -r22.column(n) * dt;
            let c2 = lstsq(m2, b2).ok_or(VectorFitError::Singular {
                iteration,
                what: "pole relocation (fixed d̃)",
            })?;
            ct = c2.iter().copied().collect();
        }
        // Zeros of σ: eig(Â − b̂ c̃ᵀ / d̃).
        let mut z = DMatrix::<f64>::zeros(n, n);
        let mut bvec = vec![0.0; n];
        let mut col = 0;
        for &p in poles {
            if p.im > 0.0 {
                z[(col, col)] = p.re;
                z[(col, col + 1)] = p.im;
                z[(col + 1, col)] = -p.im;
                z[(col + 1, col + 1)] = p.re;
                bvec[col] = 2.0;
                col += 2;
            } else {
                z[(col, col)] = p.re;
                bvec[col] = 1.0;
                col += 1;
            }
        }
        for i in 0..n {
            if bvec[i] != 0.0 {
                for j in 0..n {
                    z[(i, j)] -= bvec[i] * ct[j] / dt;
                }
            }
        }
        if !z.iter().all(|v| v.is_finite()) {
            return Err(VectorFitError::Singular {
                iteration,
                what: "zeros of sigma",
            });
        }
        let schur = nalgebra::linalg::Schur::try_new(z, f64::EPSILON, 10_000)
            .ok_or(VectorFitError::Eigen { iteration })?;
        let eig = schur.complex_eigenvalues();
        let mut out: Vec<C64> = Vec::with_capacity(n);
        let mut count = 0;
        for e in eig.iter() {
            if e.im > 0.0 {
                count += 2;
                out.push(*e);
            } else if e.im == 0.0 {
                count += 1;
                out.push(*e);
            }
        }
        if count != n || out.iter().any(|p| !(p.re.is_finite() && p.im.is_finite())) {
            return Err(VectorFitError::Eigen { iteration });
        }
        if flip {
            for p in out.iter_mut() {
                if p.re > 0.0 {
                    p.re = -p.re;
                }
            }
        }
        sort_poles(&mut out);
        Ok(out)
    }

    /// Residues, d, e for fixed poles; returns (terms, d, e, rms).
    fn residues(
        &self,
        poles: &[C64],
        iteration: usize,
    ) -> Result<(Vec<PoleTerm>, f64, f64, f64), VectorFitError> {
        let ns = self.ns();
        let (phi, n) = basis(&self.s, poles);
        let n1 = n + self.constant as usize + self.proportional as usize;
        let mut a = DMatrix::<f64>::zeros(2 * ns, n1);
        let mut b = DVector::<f64>::zeros(2 * ns);
        for j in 0..n {
            for k in 0..ns {
                let v = phi[j * ns + k] * self.w[k];
                a[(k, j)] = v.re;
                a[(ns + k, j)] = v.im;
            }
        }
        self.fill_direct_terms(&mut a, n);
        for k in 0..ns {
            let v = self.f[k] * self.w[k];
            b[k] = v.re;
            b[ns + k] = v.im;
        }
        let x = lstsq(a, b).ok_or(VectorFitError::Singular {
            iteration,
            what: "residue identification",
        })?;
        let mut terms = Vec::with_capacity(poles.len());
        let mut j = 0;
        for &p in poles {
            if p.im > 0.0 {
                terms.push(PoleTerm {
                    pole: p,
                    residue: C64::new(x[j], x[j + 1]),
                });
                j += 2;
            } else {
                terms.push(PoleTerm {
                    pole: p,
                    residue: C64::new(x[j], 0.0),
                });
                j += 1;
            }
        }
        let d = if self.constant { x[n] } else { 0.0 };
        let e = if self.proportional { x[n1 - 1] } else { 0.0 };
        let mut sum = 0.0;
        for k in 0..ns {
            let v = eval_terms(&terms, d, e, self.s[k]);
            sum += (self.f[k] - v).norm_sqr();
        }
        Ok((terms, d, e, (sum / ns as f64).sqrt()))
    }
}

fn sort_poles(p: &mut [C64]) {
    p.sort_by(|a, b| {
        a.im.partial_cmp(&b.im)
            .unwrap()
            .then(a.re.partial_cmp(&b.re).unwrap())
    });
}

fn pole_change(old: &[C64], new: &[C64]) -> f64 {
    if old.len() != new.len()
        || old
            .iter()
            .zip(new)
            .any(|(a, b)| (a.im > 0.0) != (b.im > 0.0))
    {
        return f64::INFINITY;
    }
    old.iter()
        .zip(new)
        .map(|(a, b)| (a - b).norm() / b.norm().max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}

/// Fits `H(jω_k) ≈ h_k` (see the module documentation for the algorithm,
/// the stopping rule and the reported termination).
///
/// Errors: mismatched lengths, non-finite values, negative or
/// non-increasing frequencies, bad weights or options, and fewer real
/// equations (`2 × points`) than unknowns (`2N + [d] + [e] + N + 1`).
pub fn vector_fit(omega: &[f64], h: &[C64], opts: &VfOptions) -> Result<VfFit, VectorFitError> {
    check_options(omega, h, opts)?;
    let ns = omega.len();
    let w0 = omega[ns - 1];
    let prob = Problem {
        s: omega.iter().map(|&w| C64::new(0.0, w / w0)).collect(),
        f: h,
        w: opts.weights.clone().unwrap_or_else(|| vec![1.0; ns]),
        constant: opts.constant,
        proportional: opts.proportional,
    };
    let href = (h.iter().map(|z| z.norm_sqr()).sum::<f64>() / ns as f64).sqrt();
    let mut poles = starting_poles(
        omega[0] / w0,
        1.0,
        opts.pole_pairs,
        opts.spacing,
        opts.starting_damping,
    );
    let mut history = Vec::new();
    let mut best: Option<(Vec<PoleTerm>, f64, f64, f64)> = None;
    let mut termination = VectorFitTermination::MaxIterations {
        change: f64::INFINITY,
    };
    let mut iterations = 0;
    for it in 1..=opts.max_iterations {
        iterations = it;
        opts.cancel.check()?;
        let new = prob.relocate(&poles, it, opts.flip_unstable)?;
        let change = pole_change(&poles, &new);
        poles = new;
        opts.cancel.check()?;
        let (terms, d, e, rms) = prob.residues(&poles, it)?;
        history.push(rms);
        best = Some((terms, d, e, rms));
        termination = VectorFitTermination::MaxIterations { change };
        if change <= opts.pole_tolerance {
            termination = VectorFitTermination::PolesConverged { change };
            break;
        }
        if rms <= 1e-13 * href {
            termination = VectorFitTermination::ErrorFloor;
            break;
        }
        if it >= 3 {
            let r = |i: usize| {
                (history[i] - history[i - 1]).abs() / history[i - 1].max(f64::MIN_POSITIVE)
            };
            let (c1, c2) = (r(it - 1), r(it - 2));
            if c1 <= opts.rms_tolerance && c2 <= opts.rms_tolerance {
                termination = VectorFitTermination::Stagnated { change: c1 };
                break;
            }
        }
    }
    let (terms, d, e, rms) = best.expect("at least one iteration");
    let terms = terms
        .into_iter()
        .map(|t| PoleTerm {
            pole: t.pole * w0,
            residue: t.residue * w0,
        })
        .collect();
    Ok(VfFit {
        terms,
        constant: d,
        proportional: e / w0,
        iterations,
        rms_history: history,
        rms_error: rms,
        relative_rms_error: if href > 0.0 { rms / href } else { rms },
        termination,
        omega_scale: w0,
    })
}

/// Result of [`fit_auto`]: the chosen fit and the RMS error of every order
/// tried, as `(pole_pairs, rms_error)`.
#[derive(Debug, Clone, PartialEq)]
pub struct AutoOrder {
    pub fit: VfFit,
    pub pole_pairs: usize,
    pub history: Vec<(usize, f64)>,
}

/// Model-order selection: fits with 1, 2, … pole pairs and keeps adding a
/// pair while the RMS error falls. Order `n + 1` (or `n + 2`: one order of
/// look-ahead, since an odd intermediate order can be a poor fit) is
/// accepted when its error is below `improvement × rms(n)` (the CLI uses
/// 0.9: the error must fall by more than 10 %; a value like 0.5 stops too
/// early on FRFs with many modes, where each added pair removes only a
/// fraction of the error); otherwise `n` is returned. The search
/// also stops at `max_pairs`, when the relative error reaches 1e-12, or
/// when there are too few points for a higher order.
pub fn fit_auto(
    omega: &[f64],
    h: &[C64],
    opts: &VfOptions,
    max_pairs: usize,
    improvement: f64,
) -> Result<AutoOrder, VectorFitError> {
    if !(improvement > 0.0 && improvement < 1.0) {
        return Err(VectorFitError::BadOption {
            name: "improvement",
            value: format!("{improvement}"),
            reason: "must be in (0, 1)",
        });
    }
    if max_pairs == 0 {
        return Err(VectorFitError::BadOption {
            name: "max_pairs",
            value: "0".into(),
            reason: "at least one pole pair is needed",
        });
    }
    let run = |n: usize| {
        let mut o = opts.clone();
        o.pole_pairs = n;
        vector_fit(omega, h, &o)
    };
    let mut history = Vec::new();
    let mut cur = run(1)?;
    let mut cur_n = 1;
    history.push((1, cur.rms_error));
    loop {
        if cur.relative_rms_error <= 1e-12 || cur_n >= max_pairs {
            break;
        }
        let mut accepted = None;
        for step in 1..=2 {
            let n = cur_n + step;
            if n > max_pairs {
                break;
            }
            let mut o = opts.clone();
            o.pole_pairs = n;
            if 2 * omega.len() < unknowns(&o) {
                break;
            }
            let f = match run(n) {
                Ok(f) => f,
                Err(VectorFitError::Eigen { .. }) | Err(VectorFitError::Singular { .. }) => {
                    continue
                }
                Err(e) => return Err(e),
            };
            history.push((n, f.rms_error));
            if f.rms_error < improvement * cur.rms_error {
                accepted = Some((n, f));
                break;
            }
        }
        match accepted {
            Some((n, f)) => {
                cur = f;
                cur_n = n;
            }
            None => break,
        }
    }
    Ok(AutoOrder {
        fit: cur,
        pole_pairs: cur_n,
        history,
    })
}
