//! Time–frequency validation in one call (paper §4.5, Fig 8): the STFT
//! spectrograms of a measured record and, optionally, of the model's
//! response to the same input, restricted to a frequency band, and their
//! Eq 33 difference with its robust variant ([`stft::compare`]).
//!
//! ```
//! use nlsdof::signal_processing::spectrogram_comparison::{compare_records, ComparisonOptions};
//! use nlsdof::signal_processing::stft::StftOptions;
//! let fs = 64.0;
//! let measured: Vec<f64> = (0..4096).map(|i| (std::f64::consts::TAU * 5.0 * i as f64 / fs).sin()).collect();
//! let model: Vec<f64> = measured.iter().map(|v| 1.02 * v).collect();
//! let opts = ComparisonOptions {
//!     band: (Some(4.0), Some(6.0)),
//!     ..ComparisonOptions::new(StftOptions::paper(measured.len(), fs))
//! };
//! let c = compare_records(&measured, Some(&model), &opts)?;
//! let d = c.difference.unwrap();
//! assert!((d.max_relative_percent - 100.0 * 0.02 / 1.0).abs() < 1e-6 * 100.0);
//! # Ok::<(), nlsdof::signal_processing::spectrogram_comparison::ComparisonError>(())
//! ```

use super::stft::{
    self, compare, spectrogram_cancellable, Spectrogram, SpectrogramDifference, StftOptions,
};
use crate::cancel::Cancel;
use thiserror::Error;

/// Options of [`compare_records`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComparisonOptions {
    pub stft: StftOptions,
    /// Band kept, Hz: `(f_min, f_max)`; a missing end is the first or last
    /// bin. `(None, None)` keeps every bin.
    pub band: (Option<f64>, Option<f64>),
    /// Added to the segment times (the record's start time), s.
    pub time_offset: f64,
    /// Bins below this fraction of the measured maximum are left out of the
    /// robust Eq 33 (see [`stft::compare`]).
    pub floor_fraction: f64,
    /// Polled before each STFT segment: once set, [`compare_records`] ends
    /// with [`stft::StftError::Interrupted`] ([`crate::cancel`]).
    pub cancel: Cancel,
}

impl ComparisonOptions {
    /// Every bin, times from the first sample, floor 1 % (−40 dB).
    pub fn new(stft: StftOptions) -> Self {
        Self {
            stft,
            band: (None, None),
            time_offset: 0.0,
            floor_fraction: 0.01,
            cancel: Cancel::NEVER,
        }
    }
}

/// What [`compare_records`] computed.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrogramComparison {
    /// Spectrogram of the measured record, in the band.
    pub measured: Spectrogram,
    /// Spectrogram of the model's record, in the band.
    pub model: Option<Spectrogram>,
    /// Eq 33 and its robust variant (with a model record).
    pub difference: Option<SpectrogramDifference>,
    /// The band applied, Hz (`None`: every bin kept).
    pub band: Option<(f64, f64)>,
}

/// Errors of [`compare_records`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ComparisonError {
    #[error(transparent)]
    Stft(#[from] stft::StftError),
    /// No bin of the spectrogram lies in the band.
    #[error("no frequency bin in {low}..{high} Hz (bins up to {last} Hz)")]
    EmptyBand { low: f64, high: f64, last: f64 },
}

/// Spectrograms of `measured` and `model` (same length and sampling) in
/// the band, and their Eq 33 difference.
pub fn compare_records(
    measured: &[f64],
    model: Option<&[f64]>,
    opts: &ComparisonOptions,
) -> Result<SpectrogramComparison, ComparisonError> {
    let s_meas = spectrogram_cancellable(measured, &opts.stft, opts.cancel)?;
    let s_model = match model {
        Some(m) => Some(spectrogram_cancellable(m, &opts.stft, opts.cancel)?),
        None => None,
    };
    let last = *s_meas.frequencies.last().unwrap_or(&0.0);
    let (f_min, f_max) = opts.band;
    let band = (f_min.unwrap_or(0.0), f_max.unwrap_or(last));
    let restrict = f_min.is_some() || f_max.is_some();
    let shape = |s: Spectrogram| {
        let mut r = if restrict {
            s.restrict(band.0, band.1)
        } else {
            s
        };
        r.times.iter_mut().for_each(|t| *t += opts.time_offset);
        r
    };
    let measured = shape(s_meas);
    if measured.n_freq == 0 {
        return Err(ComparisonError::EmptyBand {
            low: band.0,
            high: band.1,
            last,
        });
    }
    let model = s_model.map(shape);
    let difference = match &model {
        Some(m) => Some(compare(&measured, m, opts.floor_fraction)?),
        None => None,
    };
    Ok(SpectrogramComparison {
        measured,
        model,
        difference,
        band: restrict.then_some(band),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cancel::Interrupted;

    /// A set flag ends the comparison with the typed error (issue 27:
    /// Ctrl-C); without it the same records are compared.
    #[test]
    fn a_cancelled_comparison_ends_with_interrupted() {
        use std::sync::atomic::AtomicBool;
        static STOP: AtomicBool = AtomicBool::new(true);
        let fs = 64.0;
        let x: Vec<f64> = (0..4096)
            .map(|i| (std::f64::consts::TAU * 5.0 * i as f64 / fs).sin())
            .collect();
        let opts = ComparisonOptions {
            cancel: Cancel::new(&STOP),
            ..ComparisonOptions::new(StftOptions::paper(x.len(), fs))
        };
        assert_eq!(
            compare_records(&x, Some(&x), &opts),
            Err(ComparisonError::Stft(stft::StftError::Interrupted(
                Interrupted
            )))
        );
        assert_eq!(
            stft::spectrogram_cancellable(&x, &opts.stft, opts.cancel),
            Err(stft::StftError::Interrupted(Interrupted))
        );
        let free = ComparisonOptions::new(StftOptions::paper(x.len(), fs));
        assert!(compare_records(&x, Some(&x), &free).is_ok());
    }
}
