//! Linear system identification: rational fitting of a measured complex
//! frequency response function (FRF) and its modal parameters.
//!
//! * [`frvf`] — **Fast Relaxed Vector Fitting** (Gustavsen & Semlyen 1999,
//!   *Rational approximation of frequency domain responses by vector
//!   fitting*, IEEE Trans. Power Deliv. 14, 1052–1059; relaxed
//!   normalisation of Gustavsen 2006, IEEE Trans. Power Deliv. 21,
//!   1587–1592; fast QR formulation of Deschrijver et al. 2008, IEEE MWCL 18,
//!   383–385; see also Grivet-Talocia & Gustavsen 2016, *Passive
//!   Macromodeling*, ch. 7). The model is the pole–residue form
//!
//!   ```text
//!   H(s) ≈ Σ_n r_n / (s − a_n) + d + s e,     s = jω              (Gustavsen & Semlyen 1999)
//!   ```
//!
//!   with complex poles in conjugate pairs, so that `H(−jω) = conj H(jω)`
//!   (a real system).
//! * [`modal`] — natural frequency, damping ratio and residue of each pole
//!   pair, and the single-degree-of-freedom linear part (`α = k/m`,
//!   `δ = c/m`, and `m, c, k` when the mass is identifiable) of the paper's
//!   model (Civera et al. 2021, Section 2.3, Table 3).
//! * [`simple`] — single-mode half-power bandwidth and circle (Nyquist)
//!   fit, for comparison and for amplitude-only data.
//! * [`sdof`] — the whole linear identification of an SDoF from a measured
//!   FRF in one call ([`identify_sdof`]): band, mobility, half-power
//!   fallback, vector fitting, mode choice, linear part.
//!
//! Frequencies are angular (rad/s) throughout.

pub mod frvf;
pub mod modal;
pub mod sdof;
pub mod simple;

pub use frvf::{
    fit_auto, vector_fit, AutoOrder, PoleTerm, Spacing, VectorFitTermination, VfFit, VfOptions,
};
pub use modal::{
    dominant_mode, modal_parameters, sdof_linear_part, InputKind, LinearPart, MassSource,
    ModalParameters, OutputKind,
};
pub use sdof::{
    identify_sdof, mobility, FrfWeighting, MeasuredFrf, PoleCount, SdofIdError, SdofIdOptions,
    SdofIdentification, SdofLinear,
};
pub use simple::{circle_fit, half_power, CircleFit, HalfPower};

/// Complex number type used for FRF values, poles and residues.
pub type C64 = nalgebra::Complex<f64>;

use thiserror::Error;

/// Errors of FRF fitting. Each carries the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum VectorFitError {
    #[error("{frequencies} frequencies but {values} FRF values: lengths must match")]
    LengthMismatch { frequencies: usize, values: usize },
    #[error("too few points: {points} complex samples give {equations} real equations, fewer than the {unknowns} unknowns of the requested model")]
    TooFewPoints {
        points: usize,
        equations: usize,
        unknowns: usize,
    },
    #[error("{what}[{index}] = {value} is not finite")]
    NotFinite {
        what: &'static str,
        index: usize,
        value: String,
    },
    #[error("frequencies must be strictly increasing: element {index} ({value_hz} Hz, {value} rad/s) does not exceed the previous one ({previous_hz} Hz, {previous} rad/s)", value_hz = .value / std::f64::consts::TAU, previous_hz = .previous / std::f64::consts::TAU)]
    NotIncreasing {
        index: usize,
        value: f64,
        previous: f64,
    },
    #[error("frequency[{index}] = {value_hz} Hz ({value} rad/s) is negative", value_hz = .value / std::f64::consts::TAU)]
    NegativeFrequency { index: usize, value: f64 },
    #[error("weight[{index}] = {value} must be finite and > 0")]
    BadWeight { index: usize, value: f64 },
    #[error("{name} = {value}: {reason}")]
    BadOption {
        name: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error("no complex pole pair in the fitted model: no mode to report")]
    NoMode,
    #[error("mode {index} requested but the fit has {count} pole pair(s)")]
    NoSuchMode { index: usize, count: usize },
    #[error("eigenvalue (real Schur) iteration for the relocated poles did not converge at iteration {iteration}")]
    Eigen { iteration: usize },
    #[error("least-squares problem is singular at iteration {iteration} ({what})")]
    Singular {
        iteration: usize,
        what: &'static str,
    },
    /// Cancelled through [`VfOptions::cancel`] (or
    /// [`SdofIdOptions::cancel`]): no result.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
}

/// Validates an FRF: equal lengths, finite values, frequencies `>= 0` and
/// strictly increasing.
pub(crate) fn validate_frf(omega: &[f64], h: &[C64]) -> Result<(), VectorFitError> {
    if omega.len() != h.len() {
        return Err(VectorFitError::LengthMismatch {
            frequencies: omega.len(),
            values: h.len(),
        });
    }
    for (i, &w) in omega.iter().enumerate() {
        if !w.is_finite() {
            return Err(VectorFitError::NotFinite {
                what: "frequency",
                index: i,
                value: format!("{w}"),
            });
        }
        if w < 0.0 {
            return Err(VectorFitError::NegativeFrequency { index: i, value: w });
        }
        if i > 0 && w <= omega[i - 1] {
            return Err(VectorFitError::NotIncreasing {
                index: i,
                value: w,
                previous: omega[i - 1],
            });
        }
    }
    for (i, z) in h.iter().enumerate() {
        if !(z.re.is_finite() && z.im.is_finite()) {
            return Err(VectorFitError::NotFinite {
                what: "frf",
                index: i,
                value: format!("{}{:+}j", z.re, z.im),
            });
        }
    }
    Ok(())
}
