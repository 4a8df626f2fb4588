//! Multi-harmonic balance (HB with `H` harmonics, constant and even terms
//! included) of
//!
//! ```text
//! x'' + δ x' + α x + κ x'|x'|^η + β x|x|^ρ = γ cos Ωt               (Eq 32)
//! ```
//!
//! the generalisation of the paper's first-order balance (§3, Eq 9–11,
//! 22, 30) that keeps the higher harmonics the power laws generate, so the
//! error of first order can be measured.
//!
//! * [`aft`] — alternating frequency/time transforms (realfft), the
//!   coefficient layout and the product-to-sum Jacobian blocks;
//! * [`system`] — residual and analytic Jacobian, choice of the number of
//!   time samples (aliasing control), regularisation of negative exponents
//!   (Coulomb friction), Newton at one frequency;
//! * [`continuation`] — pseudo-arclength continuation in Ω (or in γ) with
//!   step control and limit-point (fold) location;
//! * [`stability`] — Hill's method: Floquet exponents from the HB Jacobian;
//! * [`sweep`] — a stepped-sine sweep (jumps at folds) read off a branch;
//! * [`truncation`] — error of the truncation (first order included) in
//!   the peak and the folds against H, until convergence;
//! * [`extrapolation`] — Richardson extrapolation in the number of
//!   harmonics, for Coulomb friction, where the balance converges only
//!   like `1/H`;
//! * [`backbone`] — periodic orbits of the conservative system (nonlinear
//!   normal mode) as amplitude against frequency.
//!
//! With `H = 1` the balance reduces to the exact first-order equation of
//! [`crate::harmonic_balance`] (the first Fourier coefficient of
//! `x|x|^ρ` for `x = a cos θ` is `g(ρ) a^{ρ+1}`, Eq 9–12): tested to 1e-12.

pub mod aft;
pub mod backbone;
pub mod continuation;
pub mod extrapolation;
pub mod levels;
pub mod stability;
pub mod sweep;
pub mod system;
pub mod truncation;

pub use continuation::{
    continue_in_gamma, continue_in_omega, Branch, BranchPoint, ContinuationOptions, LimitPoint,
};
pub use levels::{level_sweeps, settings_for, LevelSweep};
pub use stability::{hill_floquet_exponents, FloquetExponents};
pub use system::{HarmonicSettings, HbSystem, MAX_HARMONICS, MAX_SAMPLES};

use crate::error::{ParameterError, SolveError};
use crate::harmonic_balance::{ForcedResponse, Formulation};
use thiserror::Error;

/// Errors of the multi-harmonic balance; each carries the offending value.
/// ` (residual/gamma R)` when the residual is known (finite), else nothing:
/// no NaN in a message (issue 30).
fn residual_note(residual: f64) -> String {
    if residual.is_finite() {
        format!(" (residual/gamma {residual:e})")
    } else {
        String::new()
    }
}

#[derive(Debug, Clone, PartialEq, Error)]
pub enum MhbError {
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    #[error(transparent)]
    Limit(#[from] crate::limits::LimitError),
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// No damping at all (c = 0 and no c_e term): no forced steady state at
    /// resonance, every periodic solution only neutrally stable.
    #[error("the model has no damping (c = 0 and no c_e term): at resonance there is no forced steady state and every periodic solution is only neutrally stable; give c > 0 or a damping term")]
    Undamped,
    #[error("number of harmonics {value} must be between 1 and {max}")]
    Harmonics { value: usize, max: usize },
    #[error("{name} = {value} is invalid")]
    InvalidValue { name: &'static str, value: f64 },
    #[error("aliasing estimate {estimate:e} (relative to gamma) still above the tolerance {tolerance:e} at the largest sample count {samples}")]
    Aliasing {
        samples: usize,
        estimate: f64,
        tolerance: f64,
    },
    #[error("Newton did not converge at {omega_hz} Hz ({omega} rad/s) after {iterations} iterations{residual_note}", omega_hz = .omega / std::f64::consts::TAU, residual_note = residual_note(*.residual))]
    NoConvergence {
        omega: f64,
        iterations: usize,
        residual: f64,
    },
    #[error("harmonic-balance Jacobian is singular at {omega_hz} Hz ({omega} rad/s), gamma = {gamma}", omega_hz = .omega / std::f64::consts::TAU)]
    Singular { omega: f64, gamma: f64 },
    #[error("non-finite value in the harmonic-balance equations at {omega_hz} Hz ({omega} rad/s) (overflow)", omega_hz = .omega / std::f64::consts::TAU)]
    NotFinite { omega: f64 },
    #[error("no first-order steady state to start from at {omega_hz} Hz ({omega} rad/s) (e.g. Coulomb sticking)", omega_hz = .omega / std::f64::consts::TAU)]
    NoStart { omega: f64 },
    #[error("the Hill eigenvalue problem failed to converge at {omega_hz} Hz ({omega} rad/s)", omega_hz = .omega / std::f64::consts::TAU)]
    Eigenvalues { omega: f64 },
}

/// Amplitude `√(a_k² + b_k²)` of harmonic `k` (for `k = 0`: `|a₀|`).
pub fn harmonic_amplitude(q: &[f64], k: usize) -> f64 {
    if k == 0 {
        q[0].abs()
    } else {
        q[2 * k - 1].hypot(q[2 * k])
    }
}

/// Phase lag `φ_k = atan2(b_k, a_k)` of harmonic `k` (rad), so that the
/// harmonic is `A_k cos(kΩt − φ_k)`; for `k = 1` the same convention as
/// [`crate::SteadyState::phase`]. For `k = 0` 0 or π by the sign of `a₀`.
pub fn harmonic_phase(q: &[f64], k: usize) -> f64 {
    if k == 0 {
        if q[0] < 0.0 {
            std::f64::consts::PI
        } else {
            0.0
        }
    } else {
        q[2 * k].atan2(q[2 * k - 1])
    }
}

/// Displacement `x(t)` of the periodic solution `q` at time `t` (s) for
/// input frequency `omega` (rad/s).
pub fn displacement_at(q: &[f64], omega: f64, t: f64) -> f64 {
    let tau = omega * t;
    let h = (q.len() - 1) / 2;
    let mut x = q[0];
    for k in 1..=h {
        let (s, c) = (k as f64 * tau).sin_cos();
        x += q[2 * k - 1] * c + q[2 * k] * s;
    }
    x
}

/// Velocity `x'(t)` of the periodic solution `q` at time `t`.
pub fn velocity_at(q: &[f64], omega: f64, t: f64) -> f64 {
    let tau = omega * t;
    let h = (q.len() - 1) / 2;
    let mut v = 0.0;
    for k in 1..=h {
        let kf = k as f64;
        let (s, c) = (kf * tau).sin_cos();
        v += kf * omega * (-q[2 * k - 1] * s + q[2 * k] * c);
    }
    v
}

/// `max_t |x(t)|` of the periodic solution, on a grid of `16·(2H+1)`
/// points refined by golden-section search around the best one.
pub fn max_abs_displacement(q: &[f64]) -> f64 {
    let h = (q.len() - 1) / 2;
    let m = 16 * (2 * h + 1);
    let f = |tau: f64| displacement_at(q, 1.0, tau).abs();
    let (mut best, mut tb) = (0.0, 0.0);
    for i in 0..m {
        let t = std::f64::consts::TAU * i as f64 / m as f64;
        let v = f(t);
        if v > best {
            best = v;
            tb = t;
        }
    }
    let d = std::f64::consts::TAU / m as f64;
    let (mut a, mut b) = (tb - d, tb + d);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let c = b - g * (b - a);
        let e = a + g * (b - a);
        if f(c) > f(e) {
            b = e;
        } else {
            a = c;
        }
    }
    best.max(f(0.5 * (a + b)))
}

/// Coefficients (H harmonics) of a first-order steady state
/// `a cos(Ωt − φ)`: `a₁ = a cos φ`, `b₁ = a sin φ`, the rest zero.
pub fn from_first_order(h: usize, amplitude: f64, phase: f64) -> Vec<f64> {
    let mut q = vec![0.0; aft::n_coefficients(h)];
    q[1] = amplitude * phase.cos();
    q[2] = amplitude * phase.sin();
    q
}

/// Which first-order root starts a solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StartRoot {
    /// Smallest amplitude.
    Smallest,
    /// Largest amplitude.
    Largest,
}

/// A converged periodic solution at one frequency.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Ω, rad/s.
    pub omega: f64,
    /// Coefficients `[a₀, a₁, b₁, …]`.
    pub coefficients: Vec<f64>,
    /// Newton iterations.
    pub iterations: usize,
    /// Samples per period used.
    pub samples: usize,
}

/// Solves the H-harmonic balance at `omega` starting from the exact
/// first-order steady state selected by `start` (the first-order root set
/// of [`crate::harmonic_balance`]); N is adapted to the aliasing tolerance
/// at the converged state (and the state re-solved if N changed).
pub fn solve_at(system: &mut HbSystem, omega: f64, start: StartRoot) -> Result<Solution, MhbError> {
    if !(omega.is_finite() && omega > 0.0) {
        return Err(MhbError::InvalidValue {
            name: "omega",
            value: omega,
        });
    }
    let fr = ForcedResponse::from_normalised(
        system.model(),
        system.gamma(),
        Formulation::HarmonicBalance,
    )?;
    let set = fr.steady_states(omega)?;
    let root = match start {
        StartRoot::Smallest => set.roots.first(),
        StartRoot::Largest => set.roots.last(),
    }
    .ok_or(MhbError::NoStart { omega })?;
    let mut q = from_first_order(system.harmonics(), root.amplitude, root.phase);
    solve_from(system, omega, &mut q)
}

/// Newton from `q` at `omega`, then N adaptation and re-solve.
pub fn solve_from(system: &mut HbSystem, omega: f64, q: &mut [f64]) -> Result<Solution, MhbError> {
    let mut iterations = system.solve(q, omega)?;
    for _ in 0..12 {
        let n0 = system.samples();
        system.adapt_samples(q, omega)?;
        if system.samples() == n0 {
            break;
        }
        iterations += system.solve(q, omega)?;
    }
    Ok(Solution {
        omega,
        coefficients: q.to_vec(),
        iterations,
        samples: system.samples(),
    })
}

/// Result of [`regularisation_check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegularisationCheck {
    /// First-harmonic amplitude at the system's ε.
    pub amplitude: f64,
    /// First-harmonic amplitude at ε/4.
    pub amplitude_refined: f64,
    /// `|A(ε) − A(ε/4)| / A(ε/4)`.
    pub relative_change: f64,
}

/// Convergence check of the regularisation of negative exponents: re-solves
/// the converged solution `q` at `omega` with both widths divided by 4 and
/// reports the change of the first-harmonic amplitude.
pub fn regularisation_check(
    system: &HbSystem,
    omega: f64,
    q: &[f64],
) -> Result<RegularisationCheck, MhbError> {
    let mut fine = system.clone();
    let (ex, ev) = system.regularisation_widths();
    fine.set_regularisation_widths(0.25 * ex, 0.25 * ev);
    let mut qf = q.to_vec();
    let sol = solve_from(&mut fine, omega, &mut qf)?;
    let a = harmonic_amplitude(q, 1);
    let af = harmonic_amplitude(&sol.coefficients, 1);
    Ok(RegularisationCheck {
        amplitude: a,
        amplitude_refined: af,
        relative_change: (a - af).abs() / af,
    })
}
