//! Linear identification of a single-degree-of-freedom system from a
//! measured FRF, as one call (paper Section 2.3, Table 3): the frequency
//! band, the mobility, the half-power and circle-fit estimates, vector
//! fitting (fixed or automatic order), the choice of the mode and the SDoF
//! linear part `α = k/m`, `δ = c/m` (and `m, k, c` where the mass is known
//! or identifiable). An amplitude-only FRF (no phase) falls back on the
//! half-power estimate.
//!
//! ```
//! use nlsdof::vector_fitting::{identify_sdof, MeasuredFrf, SdofIdOptions, C64};
//! // a linear SDoF with f_n = 10 Hz, ζ = 1 %, displacement per force, m = 2 kg
//! let (m, wn, zeta) = (2.0, std::f64::consts::TAU * 10.0, 0.01);
//! let omega: Vec<f64> = (0..400).map(|i| wn * (0.8 + 0.4 * i as f64 / 399.0)).collect();
//! let h: Vec<C64> = omega
//!     .iter()
//!     .map(|&w| C64::new(1.0, 0.0) / (m * C64::new(wn * wn - w * w, 2.0 * zeta * wn * w)))
//!     .collect();
//! let frf = MeasuredFrf::complex(omega, h);
//! let opts = SdofIdOptions {
//!     input: nlsdof::vector_fitting::InputKind::Force,
//!     ..SdofIdOptions::default()
//! };
//! let id = identify_sdof(&frf, &opts)?;
//! assert!((id.sdof.alpha.sqrt() / wn - 1.0).abs() < 1e-6);
//! assert!((id.sdof.mass.unwrap() / m - 1.0).abs() < 1e-6);
//! # Ok::<(), nlsdof::vector_fitting::SdofIdError>(())
//! ```

use super::{
    circle_fit, dominant_mode, fit_auto, half_power, modal_parameters, sdof_linear_part, CircleFit,
    HalfPower, InputKind, LinearPart, MassSource, ModalParameters, OutputKind, VectorFitError,
    VfFit, VfOptions, C64,
};
use thiserror::Error;

/// A measured FRF: angular frequencies (rad/s, strictly increasing), the
/// magnitude at each, and the complex values when the phase is known.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeasuredFrf {
    pub omega: Vec<f64>,
    pub magnitude: Vec<f64>,
    /// `None` for an amplitude-only FRF.
    pub values: Option<Vec<C64>>,
}

impl MeasuredFrf {
    /// A complex FRF; the magnitude is `|H|`.
    pub fn complex(omega: Vec<f64>, values: Vec<C64>) -> Self {
        Self {
            magnitude: values.iter().map(|z| z.norm()).collect(),
            omega,
            values: Some(values),
        }
    }
}

/// How many pole pairs vector fitting uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoleCount {
    /// Add pairs while the RMS error falls by more than 10 %, up to `max_pairs`.
    Auto { max_pairs: usize },
    /// Exactly this many pairs (>= 1).
    Fixed(usize),
}

/// Frequency weighting of the least-squares fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrfWeighting {
    /// All frequencies weigh the same.
    Uniform,
    /// Weight `1/|H|` (relative error).
    Inverse,
}

/// Options of [`identify_sdof`].
#[derive(Debug, Clone, PartialEq)]
pub struct SdofIdOptions {
    /// Frequency band `[low, high]`, rad/s, both ends included.
    pub band: (f64, f64),
    pub poles: PoleCount,
    pub input: InputKind,
    pub output: OutputKind,
    /// Known mass, kg.
    pub mass: Option<f64>,
    /// Mode taken as the SDoF, 1-based by natural frequency; `None`: the
    /// one with the highest peak.
    pub mode: Option<usize>,
    /// Fit the constant term `d`.
    pub constant: bool,
    /// Fit the proportional term `s e`.
    pub proportional: bool,
    pub weighting: FrfWeighting,
    /// Vector-fitting iteration limit.
    pub max_iterations: usize,
    /// Polled by the vector fitting ([`VfOptions::cancel`]): once set,
    /// [`identify_sdof`] ends with `SdofIdError::Fit(`
    /// [`VectorFitError::Interrupted`]`)` ([`crate::cancel`]).
    pub cancel: crate::cancel::Cancel,
}

impl Default for SdofIdOptions {
    fn default() -> Self {
        Self {
            band: (f64::NEG_INFINITY, f64::INFINITY),
            poles: PoleCount::Auto { max_pairs: 20 },
            input: InputKind::Acceleration,
            output: OutputKind::Displacement,
            mass: None,
            mode: None,
            constant: true,
            proportional: false,
            weighting: FrfWeighting::Uniform,
            max_iterations: 30,
            cancel: crate::cancel::Cancel::NEVER,
        }
    }
}

/// The SDoF linear part finally retained.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SdofLinear {
    /// α = k/m, 1/s².
    pub alpha: f64,
    /// δ = c/m, 1/s.
    pub delta: f64,
    pub mass: Option<f64>,
    pub mass_source: MassSource,
}

/// Everything [`identify_sdof`] computed.
#[derive(Debug, Clone)]
pub struct SdofIdentification {
    /// Indices of the input points inside the band.
    pub points: Vec<usize>,
    /// Frequencies, magnitudes and complex values inside the band.
    pub omega: Vec<f64>,
    pub magnitude: Vec<f64>,
    pub values: Option<Vec<C64>>,
    /// The vector fit (complex FRF only).
    pub fit: Option<VfFit>,
    /// `(pole pairs, RMS error)` of each order tried by [`PoleCount::Auto`].
    pub auto_history: Vec<(usize, f64)>,
    pub modes: Vec<ModalParameters>,
    /// Index (0-based) of the mode taken as the SDoF.
    pub chosen: Option<usize>,
    /// The linear part from vector fitting.
    pub linear: Option<LinearPart>,
    /// Half-power estimate on the mobility.
    pub half_power: Result<HalfPower, VectorFitError>,
    /// Circle fit of the mobility; `None` without the phase.
    pub circle: Option<Result<CircleFit, VectorFitError>>,
    /// From vector fitting, else from the half-power estimate.
    pub sdof: SdofLinear,
}

/// Errors of [`identify_sdof`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SdofIdError {
    #[error("no FRF point in [{low_hz}, {high_hz}] Hz ([{low}, {high}] rad/s)", low_hz = .low / std::f64::consts::TAU, high_hz = .high / std::f64::consts::TAU)]
    EmptyBand { low: f64, high: f64 },
    #[error(transparent)]
    Limit(#[from] crate::limits::LimitError),
    #[error("amplitude-only FRF and the half-power method failed: {0}")]
    HalfPowerFailed(VectorFitError),
    #[error(transparent)]
    Fit(#[from] VectorFitError),
}

/// The mobility `H (jω)^(1−p)` of an FRF of output kind `output`.
pub fn mobility(omega: f64, h: C64, output: OutputKind) -> C64 {
    h * C64::new(0.0, omega).powi(1 - output.power())
}

/// Identifies the SDoF linear part of `frf` (see the module documentation).
pub fn identify_sdof(
    frf: &MeasuredFrf,
    opts: &SdofIdOptions,
) -> Result<SdofIdentification, SdofIdError> {
    let (lo, hi) = opts.band;
    let points: Vec<usize> = (0..frf.omega.len())
        .filter(|&i| frf.omega[i] >= lo && frf.omega[i] <= hi)
        .collect();
    if points.is_empty() {
        return Err(SdofIdError::EmptyBand { low: lo, high: hi });
    }
    crate::limits::FRF_LINES.check(points.len() as f64)?;
    let omega: Vec<f64> = points.iter().map(|&i| frf.omega[i]).collect();
    let magnitude: Vec<f64> = points.iter().map(|&i| frf.magnitude[i]).collect();
    let values: Option<Vec<C64>> = frf
        .values
        .as_ref()
        .map(|v| points.iter().map(|&i| v[i]).collect());
    let output = opts.output;
    let mob_mag: Vec<f64> = omega
        .iter()
        .zip(&magnitude)
        .map(|(&w, &m)| m * w.powi(1 - output.power()))
        .collect();
    let mut id = SdofIdentification {
        points,
        half_power: half_power(&omega, &mob_mag),
        omega,
        magnitude,
        values,
        fit: None,
        auto_history: vec![],
        modes: vec![],
        chosen: None,
        linear: None,
        circle: None,
        sdof: SdofLinear {
            alpha: f64::NAN,
            delta: f64::NAN,
            mass: None,
            mass_source: MassSource::Unidentified,
        },
    };
    if let Some(h) = &id.values {
        let mob: Vec<C64> = id
            .omega
            .iter()
            .zip(h)
            .map(|(&w, &z)| mobility(w, z, output))
            .collect();
        id.circle = Some(circle_fit(&id.omega, &mob));
        let weights = match opts.weighting {
            FrfWeighting::Uniform => None,
            FrfWeighting::Inverse => Some(h.iter().map(|z| 1.0 / z.norm().max(1e-300)).collect()),
        };
        let vf = VfOptions {
            constant: opts.constant,
            proportional: opts.proportional,
            weights,
            max_iterations: opts.max_iterations,
            cancel: opts.cancel,
            ..Default::default()
        };
        let fitted = match opts.poles {
            PoleCount::Auto { max_pairs } => {
                let a = fit_auto(&id.omega, h, &vf, max_pairs, 0.9)?;
                id.auto_history = a.history;
                a.fit
            }
            PoleCount::Fixed(n) => super::vector_fit(
                &id.omega,
                h,
                &VfOptions {
                    pole_pairs: n,
                    ..vf
                },
            )?,
        };
        id.modes = modal_parameters(&fitted);
        let chosen = match opts.mode {
            Some(k) if k >= 1 && k <= id.modes.len() => k - 1,
            Some(k) => {
                return Err(VectorFitError::NoSuchMode {
                    index: k,
                    count: id.modes.len(),
                }
                .into())
            }
            None => dominant_mode(&id.modes)?,
        };
        id.linear = Some(sdof_linear_part(
            &id.modes[chosen],
            opts.input,
            output,
            opts.mass,
        )?);
        id.chosen = Some(chosen);
        id.fit = Some(fitted);
    }
    id.sdof = match (&id.linear, &id.half_power) {
        (Some(lp), _) => SdofLinear {
            alpha: lp.alpha,
            delta: lp.delta,
            mass: lp.mass,
            mass_source: lp.mass_source,
        },
        (None, Ok(hp)) => {
            let (mass, mass_source) = match opts.mass {
                Some(m) => (Some(m), MassSource::Given),
                None => (None, MassSource::Unidentified),
            };
            SdofLinear {
                alpha: hp.omega_n * hp.omega_n,
                delta: 2.0 * hp.zeta * hp.omega_n,
                mass,
                mass_source,
            }
        }
        (None, Err(e)) => return Err(SdofIdError::HalfPowerFailed(e.clone())),
    };
    Ok(id)
}
