//! Alternating frequency/time (AFT) transforms between the real Fourier
//! coefficients of a truncated periodic signal and its samples over one
//! period (Cameron & Griffin 1989), with `realfft`.
//!
//! ## Conventions
//! A signal with `H` harmonics is stored as the `2H+1` real coefficients
//!
//! ```text
//! q = [a₀, a₁, b₁, a₂, b₂, …, a_H, b_H]
//! x(τ) = a₀ + Σ_{k=1}^{H} ( a_k cos kτ + b_k sin kτ ),   τ = Ω t
//! ```
//!
//! sampled at `τ_n = 2π n / N`, `n = 0 … N−1`. With the unnormalised DFT
//! `Y_m = Σ_n y_n e^{−i m τ_n}` and `ŷ_m = Y_m / N`, the projection of
//! samples `y_n` back onto the coefficients is
//!
//! ```text
//! a₀ = ŷ₀ = (1/N) Σ y_n,  a_k = 2 Re ŷ_k = (2/N) Σ y_n cos kτ_n,
//! b_k = −2 Im ŷ_k = (2/N) Σ y_n sin kτ_n.
//! ```
//!
//! This is the trapezoidal rule for the Fourier integrals; it is exact for
//! trigonometric polynomials of degree `< N − H` and otherwise carries the
//! aliasing error `Σ_{j≠0} ĉ_{m+jN}` (see [`super::system`] for how `N` is
//! chosen).
//!
//! ## Products for the Jacobian
//! The Jacobian needs the projection of `w(τ) u(τ)` for every basis function
//! `u ∈ {1, cos kτ, sin kτ}`. With the spectrum `W(m) = (1/N) Σ w_n e^{−i m τ_n}`
//! (`W(−m) = conj W(m)`) and the product-to-sum formulas,
//!
//! ```text
//! (2/N) Σ w cos jτ cos kτ = Re W(j−k) + Re W(j+k)
//! (2/N) Σ w sin jτ sin kτ = Re W(j−k) − Re W(j+k)
//! (2/N) Σ w cos jτ sin kτ = Im W(j−k) − Im W(j+k)
//! (2/N) Σ w sin jτ cos kτ = −Im W(j−k) − Im W(j+k)
//! ```
//!
//! and the row of the constant term (`j = 0`, weight `1/N`) is half of these.
//! So one FFT of `w` gives the whole `(2H+1)²` block in `O(H²)` — exact for
//! the sampled product, i.e. the Jacobian is the exact derivative of the
//! discrete (aliased) residual, as Newton needs.

use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use std::sync::Arc;

/// Number of real coefficients for `h` harmonics (constant included).
#[inline]
pub fn n_coefficients(h: usize) -> usize {
    2 * h + 1
}

/// FFT plans and scratch buffers for one `(H, N)`.
pub struct Aft {
    h: usize,
    n: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    spec: Vec<Complex<f64>>,
    time: Vec<f64>,
    scratch_f: Vec<Complex<f64>>,
    scratch_i: Vec<Complex<f64>>,
}

impl std::fmt::Debug for Aft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Aft")
            .field("harmonics", &self.h)
            .field("samples", &self.n)
            .finish()
    }
}

impl Clone for Aft {
    fn clone(&self) -> Self {
        Aft::new(self.h, self.n)
    }
}

impl Aft {
    /// Plans for `h` harmonics and `n` samples per period. Requires
    /// `n > 4h` (so that `W(m)` for `|m| ≤ 2h` is below the Nyquist index);
    /// callers validate this, a violating `n` is raised to the next even
    /// number above `4h`.
    pub fn new(h: usize, n: usize) -> Self {
        let mut n = n.max(4 * h + 2).max(4);
        if n % 2 == 1 {
            n += 1;
        }
        let mut planner = RealFftPlanner::<f64>::new();
        let r2c = planner.plan_fft_forward(n);
        let c2r = planner.plan_fft_inverse(n);
        let spec = r2c.make_output_vec();
        let time = r2c.make_input_vec();
        let scratch_f = r2c.make_scratch_vec();
        let scratch_i = c2r.make_scratch_vec();
        Self {
            h,
            n,
            r2c,
            c2r,
            spec,
            time,
            scratch_f,
            scratch_i,
        }
    }

    /// Harmonics H.
    pub fn harmonics(&self) -> usize {
        self.h
    }

    /// Samples per period N.
    pub fn samples(&self) -> usize {
        self.n
    }

    /// Samples `x(τ_n)` of the coefficients `q` (length `2H+1`) into `out`
    /// (length N). `derivative = true` gives `dx/dτ` instead.
    pub fn synthesize(&mut self, q: &[f64], derivative: bool, out: &mut [f64]) {
        debug_assert_eq!(q.len(), n_coefficients(self.h));
        debug_assert_eq!(out.len(), self.n);
        for c in self.spec.iter_mut() {
            *c = Complex::new(0.0, 0.0);
        }
        if !derivative {
            self.spec[0] = Complex::new(q[0], 0.0);
        }
        for k in 1..=self.h {
            let (a, b) = (q[2 * k - 1], q[2 * k]);
            // x = Σ a cos + b sin ⇒ X_k = (a − i b)/2; d/dτ: (a,b) → (k b, −k a)
            let (a, b) = if derivative {
                (k as f64 * b, -(k as f64) * a)
            } else {
                (a, b)
            };
            self.spec[k] = Complex::new(0.5 * a, -0.5 * b);
        }
        // realfft's inverse is unnormalised: x_n = Σ_m X_m e^{+i m τ_n} over
        // the full Hermitian spectrum, which is what we built.
        self.c2r
            .process_with_scratch(&mut self.spec, out, &mut self.scratch_i)
            .expect("spectrum length and DC/Nyquist imaginary parts are set by construction");
    }

    /// Projects samples `y` (length N) onto the `2H+1` coefficients (`out`).
    pub fn analyse(&mut self, y: &[f64], out: &mut [f64]) {
        self.spectrum(y);
        let inv = 1.0 / self.n as f64;
        out[0] = self.spec[0].re * inv;
        for k in 1..=self.h {
            out[2 * k - 1] = 2.0 * self.spec[k].re * inv;
            out[2 * k] = -2.0 * self.spec[k].im * inv;
        }
    }

    /// Normalised spectrum `W(m) = (1/N) Σ y_n e^{−i m τ_n}` for
    /// `m = 0 … 2H` into `out` (length ≥ 2H+1).
    pub fn spectrum_normalised(&mut self, y: &[f64], out: &mut [Complex<f64>]) {
        self.spectrum(y);
        let inv = 1.0 / self.n as f64;
        for (m, o) in out.iter_mut().enumerate().take(2 * self.h + 1) {
            *o = self.spec[m] * inv;
        }
    }

    fn spectrum(&mut self, y: &[f64]) {
        self.time.copy_from_slice(y);
        self.r2c
            .process_with_scratch(&mut self.time, &mut self.spec, &mut self.scratch_f)
            .expect("buffer lengths are set by construction");
    }
}

/// `W(m)` for any integer `m` from the stored `m ≥ 0` half.
#[inline]
fn w_at(w: &[Complex<f64>], m: i64) -> Complex<f64> {
    if m >= 0 {
        w[m as usize]
    } else {
        w[(-m) as usize].conj()
    }
}

/// Adds `scale ×` the matrix of "multiply by w(τ), project" acting on the
/// coefficient vector, `M[i][j] = ∂ proj_i(w · u) / ∂ q_j` with `u = Σ q_j φ_j`,
/// to `jac` (row-major, `n × n`, `n = 2H+1`). `w` is the normalised spectrum
/// `W(0 … 2H)` ([`Aft::spectrum_normalised`]). If `derivative` is set the
/// product is with `du/dτ` instead of `u` (for the velocity terms).
pub fn add_product_matrix(
    w: &[Complex<f64>],
    h: usize,
    scale: f64,
    derivative: bool,
    jac: &mut [f64],
) {
    let n = n_coefficients(h);
    // basis function j as (harmonic, is_sin) and its τ-derivative:
    // cos kτ → −k sin kτ, sin kτ → k cos kτ, 1 → 0.
    let basis = |j: usize| -> (i64, bool) {
        if j == 0 {
            (0, false)
        } else {
            (j.div_ceil(2) as i64, j % 2 == 0)
        }
    };
    for j in 0..n {
        let (k, ks) = basis(j);
        // u = coeff * (cos or sin)(kτ)
        let (coeff, u_sin) = if derivative {
            if k == 0 {
                continue;
            }
            if ks {
                (k as f64, false)
            } else {
                (-(k as f64), true)
            }
        } else {
            (1.0, ks)
        };
        let c = scale * coeff;
        for i in 0..n {
            let (l, ls) = basis(i);
            let wm = w_at(w, l - k);
            let wp = w_at(w, l + k);
            let v = match (ls, u_sin) {
                (false, false) => wm.re + wp.re,
                (true, true) => wm.re - wp.re,
                (false, true) => wm.im - wp.im,
                (true, false) => -wm.im - wp.im,
            };
            let v = if i == 0 { 0.5 * v } else { v };
            jac[i * n + j] += c * v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn synthesize_analyse_round_trip_and_derivative() {
        let h = 4;
        let mut aft = Aft::new(h, 32);
        let q = [0.3, 1.0, -0.5, 0.2, 0.7, -0.1, 0.05, 0.02, -0.03];
        let mut x = vec![0.0; 32];
        aft.synthesize(&q, false, &mut x);
        for (nn, xv) in x.iter().enumerate() {
            let t = std::f64::consts::TAU * nn as f64 / 32.0;
            let mut e = q[0];
            for k in 1..=h {
                e += q[2 * k - 1] * (k as f64 * t).cos() + q[2 * k] * (k as f64 * t).sin();
            }
            assert!((xv - e).abs() < 1e-14);
        }
        let mut back = vec![0.0; 9];
        aft.analyse(&x, &mut back);
        for (a, b) in q.iter().zip(&back) {
            assert!((a - b).abs() < 1e-15);
        }
        aft.synthesize(&q, true, &mut x);
        for (nn, xv) in x.iter().enumerate() {
            let t = std::f64::consts::TAU * nn as f64 / 32.0;
            let mut e = 0.0;
            for k in 1..=h {
                let kf = k as f64;
                e += kf * (-q[2 * k - 1] * (kf * t).sin() + q[2 * k] * (kf * t).cos());
            }
            assert!((xv - e).abs() < 1e-13);
        }
    }

    #[test]
    fn product_matrix_equals_direct_projection() {
        // oracle: the matrix applied to q equals analyse(w · synth(q)) and
        // analyse(w · synth'(q)) computed sample by sample.
        let h = 3;
        let nn = 32;
        let mut aft = Aft::new(h, nn);
        let w: Vec<f64> = (0..nn)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / nn as f64;
                1.0 + 0.4 * t.cos() - 0.3 * (2.0 * t).sin() + 0.1 * (5.0 * t).cos()
            })
            .collect();
        let mut ws = vec![Complex::new(0.0, 0.0); 2 * h + 1];
        aft.spectrum_normalised(&w, &mut ws);
        let q = [0.1, 1.0, -0.5, 0.2, 0.7, -0.1, 0.05];
        for der in [false, true] {
            let mut m = vec![0.0; 49];
            add_product_matrix(&ws, h, 2.0, der, &mut m);
            let mut u = vec![0.0; nn];
            aft.synthesize(&q, der, &mut u);
            let prod: Vec<f64> = u.iter().zip(&w).map(|(a, b)| 2.0 * a * b).collect();
            let mut direct = vec![0.0; 7];
            aft.analyse(&prod, &mut direct);
            for i in 0..7 {
                let mv: f64 = (0..7).map(|j| m[i * 7 + j] * q[j]).sum();
                assert!((mv - direct[i]).abs() < 1e-13, "der={der} row {i}");
            }
        }
    }
}
