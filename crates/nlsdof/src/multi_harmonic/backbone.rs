//! Backbone (nonlinear normal mode) by multi-harmonic balance: the periodic
//! orbits of the conservative system `x'' + α x + β x|x|^ρ = 0` as
//! frequency against amplitude.
//!
//! The restoring force is odd and the system conservative and reversible,
//! so an orbit through its turning point at `t = 0` is even in time:
//! `x(τ) = a₀ + Σ_{k=1}^H a_k cos kτ` (all `b_k = 0`). The cosine rows of the
//! balance of [`super::system`] with `δ = κ = γ = 0` give `H+1` equations;
//! fixing the first-harmonic amplitude `a₁ = A` leaves the `H+1` unknowns
//! `(a₀, a₂, …, a_H, Ω)`, solved by Newton with the analytic Jacobian
//! (columns of `∂R/∂q` and `∂R/∂Ω`). Amplitudes are followed in the given
//! order, each from the previous solution (the first from the first-order
//! backbone `Ω = √(α + g(ρ) β A^ρ)`).
//!
//! The independent oracle (tests): the exact period of the conservative
//! oscillator with turning point `X`,
//! `T(X) = 4 ∫₀^{π/2} X cos θ dθ / √(α X² cos²θ + 2β/(ρ+2) X^{ρ+2} (1 − sin^{ρ+2} θ))`,
//! against `2π/Ω` at `X = x(0) = Σ a_k`.

use super::system::{HarmonicSettings, HbSystem};
use super::MhbError;
use crate::model::AsNormalised;
use nalgebra::{DMatrix, DVector};

/// One point of the backbone.
#[derive(Debug, Clone, PartialEq)]
pub struct BackbonePoint {
    /// First-harmonic amplitude A (m).
    pub amplitude: f64,
    /// Turning point `x(0) = max x` (m).
    pub max_x: f64,
    /// Free-vibration frequency Ω (rad/s).
    pub omega: f64,
    /// Coefficients `[a₀, a₁, b₁ = 0, …]`.
    pub coefficients: Vec<f64>,
}

/// Backbone with `h` harmonics at the first-harmonic amplitudes
/// `amplitudes` (m, > 0).
pub fn multi_harmonic_backbone(
    model: &(impl AsNormalised + ?Sized),
    h: usize,
    amplitudes: &[f64],
    settings: HarmonicSettings,
) -> Result<Vec<BackbonePoint>, MhbError> {
    let model = &model.as_normalised()?;
    let mut cons = *model;
    cons.delta = 0.0;
    cons.kappa = 0.0;
    let a_max = amplitudes.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut sys = HbSystem::new(&cons, 1.0, h, settings)?;
    sys.set_gamma(0.0);
    sys.set_regularisation_widths(settings.regularisation * a_max, 0.0);
    let n = sys.dim();
    let mut out = Vec::with_capacity(amplitudes.len());
    let mut q = vec![0.0; n];
    let mut omega = f64::NAN;
    for &amp in amplitudes {
        if !(amp.is_finite() && amp > 0.0) {
            return Err(MhbError::InvalidValue {
                name: "amplitude",
                value: amp,
            });
        }
        if !omega.is_finite() {
            omega = crate::harmonic_balance::backbone(
                &cons,
                amp,
                crate::harmonic_balance::Formulation::HarmonicBalance,
            )
            .ok_or(MhbError::InvalidValue {
                name: "amplitude (no first-order backbone frequency)",
                value: amp,
            })?;
        }
        q[1] = amp;
        newton(&mut sys, &mut q, &mut omega, amp, settings)?;
        for _ in 0..12 {
            let n0 = sys.samples();
            sys.adapt_samples(&q, omega)?;
            if sys.samples() == n0 {
                break;
            }
            newton(&mut sys, &mut q, &mut omega, amp, settings)?;
        }
        let max_x = q[0] + (1..=h).map(|k| q[2 * k - 1]).sum::<f64>();
        out.push(BackbonePoint {
            amplitude: amp,
            max_x,
            omega,
            coefficients: q.clone(),
        });
    }
    Ok(out)
}

/// Newton on the cosine rows for `(a₀, a₂, …, a_H, Ω)` at fixed `a₁ = amp`.
fn newton(
    sys: &mut HbSystem,
    q: &mut [f64],
    omega: &mut f64,
    amp: f64,
    settings: HarmonicSettings,
) -> Result<(), MhbError> {
    let h = sys.harmonics();
    let n = sys.dim();
    let m = h + 1;
    let alpha = sys.model().alpha;
    let rows: Vec<usize> = std::iter::once(0)
        .chain((1..=h).map(|k| 2 * k - 1))
        .collect();
    let cols: Vec<usize> = std::iter::once(0)
        .chain((2..=h).map(|k| 2 * k - 1))
        .collect();
    let mut r = vec![0.0; n];
    let mut jac = vec![0.0; n * n];
    let mut dro = vec![0.0; n];
    let mut converged_once = false;
    for _ in 0..settings.max_iterations {
        let w = *omega;
        sys.residual_jacobian(q, w, &mut r, &mut jac, &mut dro);
        let rn = rows.iter().fold(0.0f64, |a, &i| a.max(r[i].abs()));
        if !rn.is_finite() {
            return Err(MhbError::NotFinite { omega: w });
        }
        // size of the largest term of the balance: (α + Ω²) a₁
        let scale = (alpha + w * w) * amp;
        if rn <= settings.tol * scale {
            if converged_once {
                return Ok(());
            }
            converged_once = true;
        }
        let mut a = DMatrix::zeros(m, m);
        let mut b = DVector::zeros(m);
        for (ii, &i) in rows.iter().enumerate() {
            for (jj, &j) in cols.iter().enumerate() {
                a[(ii, jj)] = jac[i * n + j];
            }
            a[(ii, m - 1)] = dro[i];
            b[ii] = r[i];
        }
        let d = a.lu().solve(&b).ok_or(MhbError::Singular {
            omega: w,
            gamma: 0.0,
        })?;
        for (jj, &j) in cols.iter().enumerate() {
            q[j] -= d[jj];
        }
        *omega = w - d[m - 1];
        if !(omega.is_finite() && *omega > 0.0) {
            return Err(MhbError::NotFinite { omega: *omega });
        }
    }
    Err(MhbError::NoConvergence {
        omega: *omega,
        iterations: settings.max_iterations,
        residual: f64::NAN,
    })
}
