//! Stage 5: STFT spectrograms of the recorded and simulated stepped-sine
//! responses and their Eq 33 comparison (paper §4.5, Fig 8).

use super::DemoError;
use crate::signal_processing::spectrogram_comparison::{compare_records, ComparisonOptions};
use crate::signal_processing::stft::{Spectrogram, SpectrogramDifference, StftOptions};

/// Bins below this fraction of the measured maximum are left out of the
/// robust Eq 33 (0.01 = −40 dB in amplitude).
pub const FLOOR_FRACTION: f64 = 0.01;
/// Band kept for the figures, Hz.
pub const PLOT_BAND: (f64, f64) = (5.15, 5.65);

/// One level's comparison.
#[derive(Debug, Clone)]
pub struct LevelSpectra {
    pub level: usize,
    pub segment_len: usize,
    pub n_time: usize,
    pub n_freq: usize,
    pub resolution_hz: f64,
    pub diff: SpectrogramDifference,
    /// Spectrograms restricted to [`PLOT_BAND`] (levels of the figure only).
    pub plot: Option<(Spectrogram, Spectrogram)>,
}

fn stft_err(e: impl std::fmt::Display) -> DemoError {
    DemoError::Failed(format!("demo: spectrogram: {e}"))
}

/// The spectrograms of one level's recorded and simulated responses
/// (sampled at `fs`, Hz) and their Eq 33 difference; with `plot`, the
/// spectrograms in [`PLOT_BAND`] for the figure.
pub(crate) fn level_spectra(
    level: usize,
    measured: &[f64],
    model: &[f64],
    fs: f64,
    plot: bool,
) -> Result<LevelSpectra, DemoError> {
    let opts = ComparisonOptions {
        floor_fraction: FLOOR_FRACTION,
        ..ComparisonOptions::new(StftOptions::paper(measured.len(), fs))
    };
    let c = compare_records(measured, Some(model), &opts).map_err(stft_err)?;
    let (sm, sn) = (&c.measured, c.model.as_ref().expect("a model record"));
    Ok(LevelSpectra {
        level,
        segment_len: opts.stft.segment_len,
        n_time: sm.n_time,
        n_freq: sm.n_freq,
        resolution_hz: if sm.frequencies.len() > 1 {
            sm.frequencies[1] - sm.frequencies[0]
        } else {
            f64::NAN
        },
        plot: plot.then(|| {
            (
                sm.restrict(PLOT_BAND.0, PLOT_BAND.1),
                sn.restrict(PLOT_BAND.0, PLOT_BAND.1),
            )
        }),
        diff: c.difference.expect("a model record"),
    })
}
