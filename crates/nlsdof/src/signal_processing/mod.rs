//! FRF estimation from input/output time histories.
//!
//! * [`window`] — data windows, symmetric or periodic (stated explicitly).
//! * [`welch`] — Welch-averaged auto/cross spectra, the H1 and H2 FRF
//!   estimators, ordinary coherence, and the spectral ratio `Y/X` of a
//!   single record (sine sweep or impact).
//! * [`stft`] — STFT spectrograms and the Eq 33 difference of two.
//! * [`frf_estimate`] — the FRF of `nlsdof frf-estimate` (H1, H2 or ratio
//!   on a band, lines without input power left out).
//! * [`spectrogram_comparison`] — a measured record against the model's in
//!   one call ([`compare_records`]): spectrograms, band, Eq 33.
//!
//! Pure mathematics: samples in, spectra out (frequencies in Hz here,
//! since they come from a sampling frequency in Hz).

pub mod frf_estimate;
pub mod spectrogram_comparison;
pub mod stft;
pub mod welch;
pub mod window;

pub use frf_estimate::{estimate_frf, FrfEstimateError, FrfEstimateOptions, FrfLines, FrfMethod};
pub use spectrogram_comparison::{
    compare_records, ComparisonError, ComparisonOptions, SpectrogramComparison,
};
pub use welch::{spectral_ratio, welch_frf, FrfEstimate, SpectralRatio, WelchOptions};
pub use window::{Symmetry, Window};

use thiserror::Error;

/// Errors of FRF estimation. Each carries the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SignalError {
    #[error("input has {input} samples but output has {output}: lengths must match")]
    LengthMismatch { input: usize, output: usize },
    #[error("{channel}[{index}] = {value} is not finite")]
    NotFinite {
        channel: &'static str,
        index: usize,
        value: f64,
    },
    #[error("sampling frequency {fs} Hz must be finite and > 0")]
    BadSamplingFrequency { fs: f64 },
    #[error("segment length {segment} must be >= 2 and <= the record length {samples}")]
    BadSegment { segment: usize, samples: usize },
    #[error("overlap {overlap} must be in [0, 1)")]
    BadOverlap { overlap: f64 },
    #[error("the input has no power at any frequency (all-zero or constant input)")]
    NoInputPower,
}

fn check_pair(fs: f64, x: &[f64], y: &[f64]) -> Result<(), SignalError> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(SignalError::BadSamplingFrequency { fs });
    }
    if x.len() != y.len() {
        return Err(SignalError::LengthMismatch {
            input: x.len(),
            output: y.len(),
        });
    }
    for (name, v) in [("input", x), ("output", y)] {
        if let Some((i, &val)) = v.iter().enumerate().find(|(_, a)| !a.is_finite()) {
            return Err(SignalError::NotFinite {
                channel: name,
                index: i,
                value: val,
            });
        }
    }
    Ok(())
}
