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
//! The core is pure mathematics (no I/O): models, steady states, time
//! simulation, identification and signal processing. File formats live in
//! `nlsdof-io`, the command line in `nlsdof-cli`.
//!
//! # Guided tour
//!
//! One entry point per task, each with a runnable example below. The model
//! is a [`Model`] (physical: kg, N/m, …) or its mass-normalised form
//! [`NormalisedModel`] (Eq 32); every computation takes either
//! ([`AsNormalised`]). Identified parameters are [`identification::Parameters`],
//! with each entry's units and mass scaling in [`identification::Parameter`].
//!
//! | task | entry point | result |
//! | --- | --- | --- |
//! | [steady state](#steady-state) at one level and frequency | [`ForcedResponse::steady_states`] | [`RootSet`] |
//! | [stepped-sine sweep](#sweep) of the first-order balance | [`ForcedResponse::sweep`], [`sweep_levels`], [`level_responses`] | [`Sweep`], [`LevelResponse`] |
//! | branch tracing for response curves | [`harmonic_balance::branches::trace_branches`] | [`harmonic_balance::branches::TracedBranch`] |
//! | multi-harmonic balance | [`multi_harmonic`] | |
//! | [time simulation](#simulate) from a recorded or analytic input | [`simulation::simulate`], [`simulation::simulate_to_vec`], [`simulation::simulate_excitation`] | [`simulation::Trajectory`] |
//! | [virtual stepped-sine rig](#rig) | [`stepped_sine::run`], [`stepped_sine::run_sweeps`] | [`stepped_sine::RigSweep`] |
//! | [fit](#fit) of a power-law model to stepped-sine curves | [`identification::identify()`] (staged), [`identification::fit`] (Eq 31) | [`identification::Identification`] |
//! | an estimator of your own on the Eq 31 objective (e.g. minimax jump errors, `nlsdof-studies`), or on the branch-free output error ([`identification::ResponseBranch`]) | [`identification::objective::Problem`] with [`identification::levenberg_marquardt::minimise`] and [`identification::jumps::WithJumps`] | [`identification::levenberg_marquardt::LmResult`] |
//! | [linear identification](#linear-identification) of an SDoF from an FRF | [`vector_fitting::identify_sdof`] | [`vector_fitting::SdofIdentification`] |
//! | FRF estimation from time histories | [`signal_processing::welch_frf`], [`signal_processing::spectral_ratio`] | [`signal_processing::FrfEstimate`] |
//! | [spectrogram comparison](#spectrogram) (Eq 33) | [`signal_processing::compare_records`] | [`signal_processing::SpectrogramComparison`] |
//!
//! The modules:
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
//!   stability, folds, stepped-sine branch following, branch tracing,
//!   backbone, phase quadrature.
//! * [`multi_harmonic`] — harmonic balance with H harmonics (AFT, analytic
//!   Jacobian), pseudo-arclength continuation with folds, Hill stability,
//!   backbone: measures the error of the first-order balance.
//! * [`excitation`] — analytic inputs (sine, chirps, stepped sine) and
//!   sampled records.
//! * [`simulation`] — time integration of Eq 32 (RK4, Dormand–Prince,
//!   Coulomb friction by event handling).
//! * [`stepped_sine`] — the virtual stepped-sine test rig.
//! * [`identification`] — fits of the power-law models to stepped-sine
//!   curves or phase-resonance points (Eq 31), staged identification,
//!   intervals.
//! * [`vector_fitting`] — linear identification (Section 2.3, Table 3):
//!   fast relaxed vector fitting of a measured FRF, modal parameters, the
//!   SDoF linear part; half-power and circle fit for comparison.
//! * [`identification::time_domain`] — output-error fit of Eq 32 to a
//!   recorded input and output (exact discrete RK4 sensitivities,
//!   Levenberg–Marquardt, equation-error start), prediction on test ranges.
//! * [`signal_processing`] — FRF estimation from time histories (Welch
//!   H1/H2 and coherence, spectral ratio of a sweep), windows, STFT
//!   spectrograms and their comparison.
//! * [`demo`] — the paper's whole workflow on a virtual HAR wing in one
//!   call (test, identify, simulate, compare), for the `nlsdof demo` report.
//! * [`special`] — special functions; [`error`] — the shared error types.
//!
//! Conventions: SI units; amplitudes and input levels are **zero-to-peak**
//! (the paper quotes peak-to-peak); frequencies are angular (rad/s) in the
//! library, Hz only at the CLI and in signal processing.
//!
//! ## Steady state
//!
//! All steady states of a hardening Duffing oscillator (f_n = 10 Hz,
//! ζ = 1 %) above resonance: two stable states and an unstable one.
//!
//! ```
//! use nlsdof::{ForcedResponse, Formulation, Model};
//! let duffing = Model::linear(1.0, 3947.84, 1.2566)?.with_stiffness(1.2e7, 2.0)?;
//! let r = ForcedResponse::new(&duffing, 2.0, Formulation::HarmonicBalance)?;
//! let set = r.steady_states(std::f64::consts::TAU * 12.5)?;
//! assert_eq!(set.roots.len(), 3);
//! assert_eq!(set.roots.iter().filter(|s| s.stable).count(), 2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Sweep
//!
//! A stepped-sine sweep up follows the resonant branch and jumps down at
//! the upper fold.
//!
//! ```
//! use nlsdof::{ForcedResponse, Formulation, Model, SweepDirection};
//! let duffing = Model::linear(1.0, 3947.84, 1.2566)?.with_stiffness(1.2e7, 2.0)?;
//! let r = ForcedResponse::new(&duffing, 2.0, Formulation::HarmonicBalance)?;
//! let omegas: Vec<f64> = (0..200).map(|i| 50.0 + 50.0 * i as f64 / 199.0).collect();
//! let up = r.sweep(&omegas, SweepDirection::Up)?;
//! assert_eq!(up.folds.len(), 2);
//! assert_eq!(up.jumps.len(), 1);
//! assert!(up.jumps[0].amplitude_after < up.jumps[0].amplitude_before);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Simulate
//!
//! The response of the linear oscillator to a sampled sine settles on the
//! harmonic-balance amplitude `γ / |ω_n² − Ω² + 2iζω_nΩ|`.
//!
//! ```
//! use nlsdof::excitation::SampledInput;
//! use nlsdof::simulation::{simulate_to_vec, Options};
//! use nlsdof::Model;
//! let m = Model::linear(1.0, 3947.84, 12.566)?.normalised()?; // ζ = 10 %
//! let (fs, w) = (1000.0, std::f64::consts::TAU * 8.0);
//! let u: Vec<f64> = (0..20_000).map(|i| (w * i as f64 / fs).cos()).collect();
//! let input = SampledInput::uniform(&u, fs, 0.0)?;
//! let (tr, _summary) = simulate_to_vec(&m, &input, &Options::default())?;
//! let peak = tr.x[10_000..].iter().fold(0.0f64, |a, x| a.max(x.abs()));
//! let exact = 1.0 / ((m.alpha - w * w).powi(2) + (m.delta * w).powi(2)).sqrt();
//! assert!((peak / exact - 1.0).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Rig
//!
//! The virtual stepped-sine rig measures the first-harmonic amplitude at
//! each step; on a weakly nonlinear model it agrees with the harmonic
//! balance.
//!
//! ```
//! use nlsdof::stepped_sine::{run, RigOptions};
//! use nlsdof::{ForcedResponse, Formulation, Model, SweepDirection};
//! let model = Model::linear(1.0, 3947.84, 6.283)?.with_stiffness(1.0e5, 2.0)?;
//! let omegas: Vec<f64> = (0..5).map(|i| 55.0 + 3.0 * i as f64).collect();
//! let rig = run(&model.normalised()?, 1.0, &omegas, SweepDirection::Up, &RigOptions::default(), Default::default())?;
//! let hb = ForcedResponse::new(&model, 1.0, Formulation::HarmonicBalance)?;
//! for p in &rig.points {
//!     let a = hb.steady_states(p.omega)?.roots[0].amplitude;
//!     assert!(p.settled && (p.amplitude / a - 1.0).abs() < 5e-3);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Fit
//!
//! The staged identification recovers a Duffing model with quadratic
//! damping from noise-free sweeps at three levels.
//!
//! ```
//! use nlsdof::identification::{identify, Dataset, FitPlan, ModelKind, Record};
//! use nlsdof::{ForcedResponse, Formulation, Model, SweepDirection};
//! let truth = Model::linear(1.0, 3947.84, 1.2566)?
//!     .with_stiffness(4.0e6, 2.0)?
//!     .with_damping(0.05, 1.0)?;
//! let omegas: Vec<f64> = (0..60).map(|i| 50.0 + 40.0 * i as f64 / 59.0).collect();
//! let mut records = Vec::new();
//! for (l, gamma) in [0.5, 1.0, 2.0].into_iter().enumerate() {
//!     let r = ForcedResponse::new(&truth, gamma, Formulation::HarmonicBalance)?;
//!     for p in r.sweep(&omegas, SweepDirection::Up)?.points {
//!         records.push(Record {
//!             level: format!("{l}"),
//!             gamma,
//!             omega: p.omega,
//!             amplitude: p.amplitude,
//!             phase: None,
//!             direction: SweepDirection::Up,
//!             weight: 1.0,
//!         });
//!     }
//! }
//! let data = Dataset::from_records(&records)?;
//! let id = identify(&data, &FitPlan::new(ModelKind::DuffingQuadratic), &|_| {})?;
//! let fitted = id.fit.model();
//! assert!((fitted.beta / truth.normalised()?.beta - 1.0).abs() < 1e-3);
//! // θ has named fields, and each entry its units and mass scaling
//! use nlsdof::identification::Parameter;
//! assert_eq!(id.fit.theta.rho, 2.0); // fixed by the model
//! let k = id.fit.theta.physical(Parameter::Alpha, truth.mass);
//! assert_eq!(Parameter::Alpha.info().physical_unit, "N/m");
//! assert!((k / truth.stiffness - 1.0).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Linear identification
//!
//! See [`vector_fitting::sdof`] for the whole pipeline in one call; here
//! the linear part of a displacement-per-base-acceleration FRF.
//!
//! ```
//! use nlsdof::vector_fitting::{identify_sdof, MeasuredFrf, SdofIdOptions, C64};
//! let (wn, zeta) = (std::f64::consts::TAU * 5.4, 0.006);
//! let omega: Vec<f64> = (0..300).map(|i| wn * (0.9 + 0.2 * i as f64 / 299.0)).collect();
//! let h: Vec<C64> = omega
//!     .iter()
//!     .map(|&w| C64::new(1.0, 0.0) / C64::new(wn * wn - w * w, 2.0 * zeta * wn * w))
//!     .collect();
//! let id = identify_sdof(&MeasuredFrf::complex(omega, h), &SdofIdOptions::default())?;
//! assert!((id.sdof.alpha / (wn * wn) - 1.0).abs() < 1e-8);
//! assert!((id.sdof.delta / (2.0 * zeta * wn) - 1.0).abs() < 1e-6);
//! assert!(id.sdof.mass.is_none()); // not identifiable from a base acceleration
//! # Ok::<(), nlsdof::vector_fitting::SdofIdError>(())
//! ```
//!
//! ## Spectrogram
//!
//! The spectrograms of a measured record and of a model that is 5 % off
//! in amplitude differ by 5 % (Eq 33).
//!
//! ```
//! use nlsdof::signal_processing::stft::StftOptions;
//! use nlsdof::signal_processing::{compare_records, ComparisonOptions};
//! let fs = 64.0;
//! let x: Vec<f64> = (0..8192).map(|i| (std::f64::consts::TAU * 5.4 * i as f64 / fs).sin()).collect();
//! let model: Vec<f64> = x.iter().map(|v| 1.05 * v).collect();
//! let opts = ComparisonOptions::new(StftOptions::paper(x.len(), fs));
//! let c = compare_records(&x, Some(&model), &opts)?;
//! assert!((c.difference.unwrap().max_relative_percent - 5.0).abs() < 1e-6);
//! # Ok::<(), nlsdof::signal_processing::ComparisonError>(())
//! ```

pub mod cancel;
pub mod demo;
pub mod error;
pub mod excitation;
pub mod harmonic_balance;
pub mod identification;
pub mod interned;
pub mod limits;
pub mod model;
pub mod multi_harmonic;
pub mod power_law;
pub mod power_sum;
pub mod signal_generator;
pub mod signal_processing;
pub mod simulation;
pub mod special;
pub mod stepped_sine;
pub mod vector_fitting;

pub use error::{ParameterError, SolveError};
pub use harmonic_balance::{
    backbone, level_responses, sweep_levels, Fold, ForcedResponse, Formulation, Jump,
    LevelResponse, NoMotion, PhaseQuadrature, RootSet, SteadyState, Sweep, SweepDirection,
    SweepPoint,
};
pub use model::{AsNormalised, Model, NormalisedModel};
pub use power_law::PowerLaw;
