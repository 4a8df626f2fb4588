//! Stage 5: STFT spectrograms of the recorded and simulated stepped-sine
//! responses and their Eq 33 comparison (paper §4.5, Fig 8).

use super::compute::{stage_bar, Demo, FS_RECORD, SPECTROGRAM_LEVELS};
use crate::error::CliError;
use nlsdof::signal_processing::stft::{
    compare, spectrogram, Spectrogram, SpectrogramDifference, StftOptions,
};
use std::time::Instant;

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

fn stft_err(e: impl std::fmt::Display) -> CliError {
    CliError::Usage(format!("demo: spectrogram: {e}"))
}

pub fn stage_spectra(demo: &mut Demo) -> Result<(), CliError> {
    let total: usize = demo.runs.iter().map(|r| r.time.len()).sum();
    let pb = stage_bar(total as u64, "5/6 spectra");
    let t = Instant::now();
    for run in &mut demo.runs {
        pb.set_message(format!("{}: STFT, Eq 33", run.cfg.key));
        let mut out = Vec::new();
        for tl in &run.time {
            let opts = StftOptions::paper(tl.measured.len(), FS_RECORD);
            let sm = spectrogram(&tl.measured, &opts).map_err(stft_err)?;
            let sn = spectrogram(&tl.model, &opts).map_err(stft_err)?;
            let diff = compare(&sm, &sn, FLOOR_FRACTION).map_err(stft_err)?;
            let plot = SPECTROGRAM_LEVELS.contains(&tl.level).then(|| {
                (
                    sm.restrict(PLOT_BAND.0, PLOT_BAND.1),
                    sn.restrict(PLOT_BAND.0, PLOT_BAND.1),
                )
            });
            out.push(LevelSpectra {
                level: tl.level,
                segment_len: opts.segment_len,
                n_time: sm.n_time,
                n_freq: sm.n_freq,
                resolution_hz: if sm.frequencies.len() > 1 {
                    sm.frequencies[1] - sm.frequencies[0]
                } else {
                    f64::NAN
                },
                diff,
                plot,
            });
            pb.inc(1);
        }
        run.spectra = out;
    }
    super::compute::done(&pb, "spectrograms", t);
    Ok(())
}
