//! The FRF estimate of `nlsdof frf-estimate` and of Python's
//! `frf_estimate`: H1 or H2 by Welch averaging (with coherence) or the
//! spectral ratio of one record, restricted to a band, without DC and
//! without the lines where the input has no power.
//!
//! One function ([`estimate_frf`]) for both front ends, so that the CLI and
//! Python give the same lines and the same summary.

use super::{spectral_ratio, welch_frf, SignalError, Symmetry, WelchOptions, Window};
use nalgebra::Complex;
use thiserror::Error;

type C64 = Complex<f64>;

/// Welch segment length used when none is given (or the record length if
/// the record is shorter), samples.
pub const DEFAULT_SEGMENT: usize = 4096;

/// The estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrfMethod {
    /// `H1 = G_xy/G_xx` (Welch; unbiased by output noise), with coherence.
    H1,
    /// `H2 = G_yy/G_yx` (Welch; unbiased by input noise), with coherence.
    H2,
    /// `Y/X` of the whole record (sine sweep or impact; no window, no
    /// averaging).
    Ratio,
}

impl FrfMethod {
    /// `"h1"`, `"h2"` or `"ratio"`.
    pub fn name(self) -> &'static str {
        match self {
            FrfMethod::H1 => "h1",
            FrfMethod::H2 => "h2",
            FrfMethod::Ratio => "ratio",
        }
    }

    /// The method named `s` (case-insensitive), or `None`.
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "h1" => Some(FrfMethod::H1),
            "h2" => Some(FrfMethod::H2),
            "ratio" => Some(FrfMethod::Ratio),
            _ => None,
        }
    }
}

/// `"hann"`, `"hamming"`, `"blackman"` or `"rectangular"`.
pub fn window_name(w: Window) -> &'static str {
    match w {
        Window::Hann => "hann",
        Window::Hamming => "hamming",
        Window::Blackman => "blackman",
        Window::Rectangular => "rectangular",
    }
}

/// The window named `s` (case-insensitive), or `None`.
pub fn parse_window(s: &str) -> Option<Window> {
    match s.trim().to_ascii_lowercase().as_str() {
        "hann" => Some(Window::Hann),
        "hamming" => Some(Window::Hamming),
        "blackman" => Some(Window::Blackman),
        "rectangular" => Some(Window::Rectangular),
        _ => None,
    }
}

/// Options of [`estimate_frf`]; the defaults are the CLI's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrfEstimateOptions {
    pub method: FrfMethod,
    /// Welch segment (FFT) length, samples (default [`DEFAULT_SEGMENT`], or
    /// the record length if shorter). Not used by the ratio.
    pub segment: Option<usize>,
    /// Fractional overlap of Welch segments, in `[0, 1)`.
    pub overlap: f64,
    pub window: Window,
    pub symmetry: Symmetry,
    /// Lines kept: `f_min <= f <= f_max`, Hz (default: all but DC).
    pub f_min: Option<f64>,
    pub f_max: Option<f64>,
}

impl Default for FrfEstimateOptions {
    fn default() -> Self {
        FrfEstimateOptions {
            method: FrfMethod::H1,
            segment: None,
            overlap: 0.5,
            window: Window::Hann,
            symmetry: Symmetry::Periodic,
            f_min: None,
            f_max: None,
        }
    }
}

/// Errors of [`estimate_frf`], each with the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrfEstimateError {
    #[error(transparent)]
    Signal(#[from] SignalError),
    #[error("f_min {f_min} / f_max {f_max}: need f_min < f_max")]
    Band { f_min: f64, f_max: f64 },
    #[error("fewer than 2 frequency lines with input power in [{f_min}, {f_max}] Hz")]
    TooFewLines { f_min: f64, f_max: f64 },
}

/// The estimated FRF on its kept lines, and what it was made from.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfLines {
    pub method: FrfMethod,
    /// Sampling frequency, Hz.
    pub fs: f64,
    /// Samples of each record.
    pub samples: usize,
    /// Segment length, samples (the record length for the ratio).
    pub segment: usize,
    /// Averaged segments (1 for the ratio).
    pub averages: usize,
    /// The window (`None` for the ratio) and its form.
    pub window: Option<Window>,
    pub symmetry: Symmetry,
    /// Frequencies of the kept lines, Hz (> 0, increasing).
    pub frequency_hz: Vec<f64>,
    /// The FRF at those lines (output unit / input unit).
    pub h: Vec<C64>,
    /// Ordinary coherence at those lines (Welch methods only).
    pub coherence: Option<Vec<f64>>,
}

impl FrfLines {
    /// Frequency resolution `fs / segment`, Hz.
    pub fn resolution_hz(&self) -> f64 {
        self.fs / self.segment as f64
    }

    /// Mean coherence over the kept lines (Welch methods only).
    pub fn mean_coherence(&self) -> Option<f64> {
        self.coherence
            .as_ref()
            .map(|c| c.iter().sum::<f64>() / c.len() as f64)
    }
}

/// The FRF of output `y` over input `x`, both sampled at `fs` Hz (see the
/// module documentation). Lines at DC, outside `[f_min, f_max]` and those
/// without input power (reported as exactly 0 by the estimators) are left
/// out; fewer than 2 remaining lines is an error.
pub fn estimate_frf(
    fs: f64,
    x: &[f64],
    y: &[f64],
    opts: &FrfEstimateOptions,
) -> Result<FrfLines, FrfEstimateError> {
    let f_lo = opts.f_min.unwrap_or(0.0);
    let f_hi = opts.f_max.unwrap_or(f64::INFINITY);
    if f_lo.is_nan() || f_hi.is_nan() || f_lo >= f_hi {
        return Err(FrfEstimateError::Band {
            f_min: f_lo,
            f_max: f_hi,
        });
    }
    if x.len() != y.len() {
        return Err(SignalError::LengthMismatch {
            input: x.len(),
            output: y.len(),
        }
        .into());
    }
    let (f, h, coh, averages, segment, window) = match opts.method {
        FrfMethod::Ratio => {
            let r = spectral_ratio(fs, x, y)?;
            (r.frequency_hz, r.h, None, 1, x.len(), None)
        }
        FrfMethod::H1 | FrfMethod::H2 => {
            let segment = opts.segment.unwrap_or(DEFAULT_SEGMENT.min(x.len()));
            let w = WelchOptions {
                segment,
                overlap: opts.overlap,
                window: opts.window,
                symmetry: opts.symmetry,
                detrend_mean: true,
            };
            let e = welch_frf(fs, x, y, &w)?;
            let h = if opts.method == FrfMethod::H1 {
                e.h1
            } else {
                e.h2
            };
            (
                e.frequency_hz,
                h,
                Some(e.coherence),
                e.averages,
                segment,
                Some(opts.window),
            )
        }
    };
    let keep: Vec<usize> = (0..f.len())
        .filter(|&i| f[i] > 0.0 && f[i] >= f_lo && f[i] <= f_hi && h[i].norm() > 0.0)
        .collect();
    if keep.len() < 2 {
        return Err(FrfEstimateError::TooFewLines {
            f_min: f_lo,
            f_max: f_hi,
        });
    }
    Ok(FrfLines {
        method: opts.method,
        fs,
        samples: x.len(),
        segment,
        averages,
        window,
        symmetry: opts.symmetry,
        frequency_hz: keep.iter().map(|&i| f[i]).collect(),
        h: keep.iter().map(|&i| h[i]).collect(),
        coherence: coh.map(|c| keep.iter().map(|&i| c[i]).collect()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn h1_of_a_gain_is_the_gain_on_every_line() {
        let fs = 1000.0;
        // a broadband input (deterministic pseudo-noise) and y = 2 x
        let mut s = 12345u64;
        let x: Vec<f64> = (0..8192)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let o = FrfEstimateOptions {
            segment: Some(1024),
            f_min: Some(10.0),
            f_max: Some(200.0),
            ..Default::default()
        };
        let e = estimate_frf(fs, &x, &y, &o).unwrap();
        assert_eq!(e.segment, 1024);
        assert!(e.averages > 1);
        assert!(e.frequency_hz[0] >= 10.0 && *e.frequency_hz.last().unwrap() <= 200.0);
        for v in &e.h {
            assert!((v.re - 2.0).abs() < 1e-9 && v.im.abs() < 1e-9, "{v}");
        }
        assert!((e.mean_coherence().unwrap() - 1.0).abs() < 1e-9);
        assert!((e.resolution_hz() - fs / 1024.0).abs() < 1e-12);
    }

    #[test]
    fn bad_band_and_lengths_are_errors_with_values() {
        let x = vec![1.0, 0.0, -1.0, 0.0];
        let o = FrfEstimateOptions {
            f_min: Some(5.0),
            f_max: Some(1.0),
            ..Default::default()
        };
        let e = estimate_frf(10.0, &x, &x, &o).unwrap_err();
        assert_eq!(e.to_string(), "f_min 5 / f_max 1: need f_min < f_max");
        let e = estimate_frf(10.0, &x, &x[..3], &Default::default()).unwrap_err();
        assert!(e.to_string().contains("4 samples but output has 3"), "{e}");
        assert_eq!(FrfMethod::parse("H2"), Some(FrfMethod::H2));
        assert_eq!(parse_window("nope"), None);
    }
}
