//! Stability of a periodic HB solution by Hill's method (von Groll & Ewins
//! 2001; Lazarus & Thomas 2010; the method of NLvib).
//!
//! ## Hill's eigenvalue problem
//! A perturbation `u` of the periodic solution obeys the linear periodic
//! equation `u'' + (δ + f_v(τ)) u' + (α + f_x(τ)) u = 0`
//! (`f_x = ∂f/∂x`, `f_v = ∂f/∂v` along the orbit). Floquet's ansatz
//! `u = e^{λt} p(τ)`, `p` a trigonometric polynomial with coefficients `c`
//! in the HB basis, `u' = e^{λt}(λ p + Ω p_τ)`,
//! `u'' = e^{λt}(λ² p + 2λΩ p_τ + Ω² p_ττ)`, projected like the residual:
//!
//! ```text
//! ( λ² I + λ Δ₁ + J ) c = 0,     Δ₁ = 2Ω∇ + δ I + W_v
//! ```
//!
//! with `J = ∂R/∂q` the HB Jacobian (it equals `Ω²∇² + δΩ∇ + α + W_x + Ω W_v ∇`),
//! `∇` the τ-derivative on the coefficients (`(a_k, b_k) → (k b_k, −k a_k)`)
//! and `W_v` the matrix of "multiply by `f_v`, project". It is solved as the
//! standard eigenproblem of the companion matrix `[[0, I], [−J, −Δ₁]]`
//! (size `2(2H+1)`, real Schur of nalgebra).
//!
//! ## Selection of the meaningful exponents
//! The `2(2H+1)` eigenvalues approximate the 2 Floquet exponents of the
//! second-order scalar equation, each repeated as `λ + i kΩ` (`k` integer,
//! the exponent is defined modulo `iΩ`). The copies with large `|k|` are
//! polluted by the truncation; the accurate ones are those whose
//! eigenvectors are concentrated on the low harmonics, which for the
//! exact problem are the representatives with `|Im λ| ≤ Ω/2`. We sort the
//! eigenvalues by `|Im λ|` and keep the **two with the smallest
//! `|Im λ|`** (ties — a real pair, or a complex pair at `±Ω/2` — are kept
//! together). This is checked in the tests against the Floquet multipliers
//! `μ = e^{λT}`, `T = 2π/Ω`, of the monodromy matrix computed by time
//! integration (Dormand–Prince) and against Liouville's formula
//! `λ₁ + λ₂ = −(δ + mean f_v)` (mod `iΩ`). The solution is stable iff both
//! selected exponents have `Re λ < 0` (multipliers inside the unit circle).

use super::system::HbSystem;
use super::MhbError;
use nalgebra::DMatrix;
use realfft::num_complex::Complex;

/// The two selected Floquet exponents and multipliers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloquetExponents {
    /// λ (1/s), sorted by decreasing real part.
    pub exponents: [Complex<f64>; 2],
    /// μ = e^{λT}.
    pub multipliers: [Complex<f64>; 2],
    /// Both `Re λ < 0`.
    pub stable: bool,
}

/// Hill's method at the converged solution `(q, Ω)` of `system`.
pub fn hill_floquet_exponents(
    system: &mut HbSystem,
    q: &[f64],
    omega: f64,
) -> Result<FloquetExponents, MhbError> {
    let n = system.dim();
    let h = system.harmonics();
    let (jac, wv) = system.hill_matrices(q, omega);
    let delta = system.model().delta;
    let mut a = DMatrix::<f64>::zeros(2 * n, 2 * n);
    for i in 0..n {
        a[(i, n + i)] = 1.0;
        for j in 0..n {
            a[(n + i, j)] = -jac[i * n + j];
            a[(n + i, n + j)] = -wv[i * n + j];
        }
        a[(n + i, n + i)] -= delta;
    }
    for k in 1..=h {
        let (ia, ib) = (2 * k - 1, 2 * k);
        let kf = k as f64;
        // −2Ω∇: ∇[ia][ib] = k, ∇[ib][ia] = −k
        a[(n + ia, n + ib)] -= 2.0 * omega * kf;
        a[(n + ib, n + ia)] += 2.0 * omega * kf;
    }
    if a.iter().any(|v| !v.is_finite()) {
        return Err(MhbError::NotFinite { omega });
    }
    let schur = nalgebra::linalg::Schur::try_new(a, f64::EPSILON, 100_000)
        .ok_or(MhbError::Eigenvalues { omega })?;
    let mut ev: Vec<Complex<f64>> = schur
        .complex_eigenvalues()
        .iter()
        .map(|c| Complex::new(c.re, c.im))
        .collect();
    ev.sort_by(|x, y| x.im.abs().total_cmp(&y.im.abs()));
    let mut sel = [ev[0], ev[1]];
    sel.sort_by(|x, y| y.re.total_cmp(&x.re));
    let period = std::f64::consts::TAU / omega;
    let mult = sel.map(|l| (l * period).exp());
    Ok(FloquetExponents {
        exponents: sel,
        multipliers: mult,
        stable: sel.iter().all(|l| l.re < 0.0),
    })
}
