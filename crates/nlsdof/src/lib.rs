//! # nlsdof — nonlinear single-degree-of-freedom power-law models
//!
//! Pure mathematics, no I/O. Implements the generalised power-law SDoF model
//! of Civera et al. (2021), *Generalised power-law stiffness and damping for
//! nonlinear reduced-order models* (the "paper"; equation numbers in the docs
//! refer to it):
//!
//! ```text
//! m x'' + c x' + k x + c_e x'|x'|^η + k_r x|x|^ρ = m γ(t)          (Eq 29)
//! ```
//!
//! * [`power_law`] — the shape factor `g(μ)` (Eq 12/24), its integer closed
//!   forms (Eq 17, 25, 26) and the equivalent coefficients `k_eq`, `c_eq`,
//!   `ζ_eq` (Eq 9, 22, 23).
//! * [`model`] — physical and mass-normalised model with validation.
//! * [`power_sum`] — isolation of *all* positive roots of a sum of real
//!   powers (generalised Descartes rule + Rolle recursion); the engine that
//!   guarantees no steady state is missed near a fold.
//! * [`harmonic_balance`] — exact first-order harmonic balance (and the
//!   paper's near-resonance Eq 30): all steady states with phase and
//!   stability, folds, stepped-sine branch following, backbone, phase
//!   quadrature.
//!
//! * [`multi_harmonic`] — harmonic balance with H harmonics (AFT, analytic
//!   Jacobian), pseudo-arclength continuation with folds, Hill stability,
//!   backbone: measures the error of the first-order balance.
//! * [`vector_fitting`] — linear identification (Section 2.3, Table 3):
//!   fast relaxed vector fitting of a measured FRF, modal parameters, the
//!   SDoF linear part; half-power and circle fit for comparison.
//! * [`identification::time_domain`] — output-error fit of Eq 32 to a
//!   recorded input and output (exact discrete RK4 sensitivities,
//!   Levenberg–Marquardt, equation-error start), prediction on test ranges.
//! * [`signal_processing`] — FRF estimation from time histories (Welch
//!   H1/H2 and coherence, spectral ratio of a sweep), windows.
//!
//! Conventions: SI units; amplitudes and input levels are **zero-to-peak**
//! (the paper quotes peak-to-peak); frequencies are angular (rad/s) in the
//! library, Hz only at the CLI.

pub mod error;
pub mod excitation;
pub mod harmonic_balance;
pub mod identification;
pub mod model;
pub mod multi_harmonic;
pub mod power_law;
pub mod power_sum;
pub mod signal_processing;
pub mod simulation;
pub mod special;
pub mod stepped_sine;
pub mod vector_fitting;

pub use error::{ParameterError, SolveError};
pub use harmonic_balance::{
    backbone, sweep_levels, Fold, ForcedResponse, Formulation, Jump, NoMotion, PhaseQuadrature,
    RootSet, SteadyState, Sweep, SweepDirection, SweepPoint,
};
pub use model::{Model, NormalisedModel};
pub use power_law::PowerLaw;
