//! Short-time Fourier transform (STFT) spectrograms and their comparison
//! (paper section 4.5, Fig 8, Eq 33).
//!
//! ## Definition
//!
//! A record `x_0 … x_{N−1}` sampled at `f_s` Hz is cut into `M` segments of
//! `L` samples. Consecutive segments overlap by `n_ov = round(overlap · L)`
//! samples (clamped to `L − 1`), i.e. they start `H = L − n_ov` samples
//! apart (the *hop*), and
//!
//! ```text
//! M = 1 + floor((N − L) / H)          (trailing samples that do not fill a segment are dropped)
//! ```
//!
//! Segment `m` (`m = 0 … M−1`) starts at sample `m H`. Optionally its mean
//! `μ_m = (1/L) Σ_n x_{mH+n}` is removed ([`Detrend::Constant`]); it is then
//! multiplied by the window `w_n` ([`Window::coefficients`] with the chosen
//! [`Symmetry`]), zero-padded to `N_fft ≥ L` samples and transformed:
//!
//! ```text
//! X_m(k) = Σ_{n=0}^{L−1} w_n (x_{mH+n} − μ_m) e^{−2πj k n / N_fft},   k = 0 … ⌊N_fft/2⌋
//! f_k = k f_s / N_fft  [Hz],        t_m = (m H + L/2) / f_s  [s]  (segment centre,
//!                                    time measured from the first sample)
//! ```
//!
//! This is exactly `scipy.signal.spectrogram(x, fs, window=w, nperseg=L,
//! noverlap=n_ov, nfft=N_fft, detrend=False|'constant')` (and MATLAB's
//! `spectrogram(x, w, n_ov, N_fft, fs)`), up to the [`Scaling`].
//!
//! ## Scaling (one-sided)
//!
//! With `c_k = 1` at `k = 0` and (for even `N_fft`) at the Nyquist bin
//! `k = N_fft/2`, and `c_k = 2` otherwise (the energy of the negative
//! frequencies folded onto the positive ones):
//!
//! * [`Scaling::Amplitude`]: `s_m(k) = c_k |X_m(k)| / Σ_n w_n`. A sine
//!   `A sin(2π f t + φ)` with `f` on a bin centre reads `A` (zero-to-peak, in
//!   the signal's unit), up to the leakage of its mirror image at `−f`, which
//!   is negligible a few bins away from 0 and Nyquist. This is scipy's
//!   `mode='magnitude', scaling='spectrum'` times `c_k`.
//! * [`Scaling::Psd`]: `s_m(k) = c_k |X_m(k)|² / (f_s Σ_n w_n²)`, a power
//!   spectral density in unit²/Hz; identical to scipy's default
//!   `mode='psd', scaling='density'`. Parseval per segment:
//!   `Σ_k s_m(k) · f_s/N_fft = Σ_n (w_n (x_{mH+n} − μ_m))² / Σ_n w_n²`, which
//!   is the DFT identity `Σ_{k=0}^{N_fft−1} |X(k)|² = N_fft Σ_n (w_n x_n)²`
//!   folded onto the one-sided bins.
//!
//! Eq 33 differences are relative, so a common factor cancels, but not the
//! choice of *magnitude* vs *power*: with power (PSD) a relative magnitude
//! error `e` reads `(1 + e)² − 1 ≈ 2e`. The paper's defaults use
//! [`Scaling::Amplitude`] (differences in amplitude, like the amplitude
//! response functions of the rest of the paper).
//!
//! ## Paper defaults
//!
//! Section 4.5: "L-point symmetric Hamming windows (L being set to
//! one-fifteenth of the total data points in the recording) and 50 %
//! overlap": [`StftOptions::paper`] gives `L = ⌊N/15⌋`, symmetric Hamming,
//! `overlap = 0.5`, `N_fft = L`, no detrending, amplitude scaling.
//!
//! **Detrending.** scipy's `spectrogram` removes each segment's mean by
//! default (`detrend='constant'`); MATLAB's `spectrogram`, which the paper's
//! figures most likely come from, does not. The default here is
//! [`Detrend::None`]: the spectrogram is then a linear function of the
//! signal, a static offset of the response (e.g. gravity sag or a drift of
//! the simulated displacement) is a genuine difference between measurement
//! and model that Eq 33 should see, and the numbers agree with MATLAB's.
//! Use [`Detrend::Constant`] to reproduce scipy's default or to suppress a
//! sensor offset that only leaks into the lowest bins.
//!
//! ## Computation
//!
//! One real-to-complex FFT plan of length `N_fft` (the `realfft` crate on top
//! of `rustfft`) is built per call and shared by all segments; segments are
//! transformed in parallel (rayon), each with its own buffers, by the same
//! sequential code, so the result is bit-identical whatever the number of
//! threads. The default `N_fft = L` matches scipy (`nfft = nperseg`); for
//! `L = ⌊8 752 000 / 15⌋ = 583 466 = 2·13·22 441` realfft runs a complex
//! FFT of length `291 733 = 13 · 22 441`, whose large prime factor rustfft's
//! AVX planner handles with Bluestein's algorithm (inner FFTs of a smooth
//! `2^a 3^b` length; seen in a callgrind profile): about 2.5× the cost of a
//! smooth length, ~30 ms per segment on one core, well inside the 1 s budget
//! for the paper's 29 segments. Zero-padding to [`next_fast_len`] is
//! available (`nfft: Some(..)`, 588 000 here) but is not the default: it
//! interpolates the spectrum on a different, finer bin grid (not a higher
//! resolution), so the values no longer match scipy/MATLAB bin for bin.

use super::{Symmetry, Window};
use crate::cancel::Cancel;
use rayon::prelude::*;
use realfft::RealFftPlanner;
use thiserror::Error;

/// Segment mean removal before windowing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detrend {
    /// No detrending (MATLAB `spectrogram`; the default here, see the module docs).
    None,
    /// Subtract each segment's mean (scipy's default `detrend='constant'`).
    Constant,
}

/// What the spectrogram values are (one-sided, see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scaling {
    /// `s = c_k |X(k)| / Σw`: a sine of amplitude `A` (zero-to-peak) on a bin
    /// centre reads `A`, in the signal's unit.
    Amplitude,
    /// `s = c_k |X(k)|² / (f_s Σw²)`: power spectral density, unit²/Hz
    /// (scipy `scaling='density'`, `mode='psd'`).
    Psd,
}

impl Scaling {
    /// Name as used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Scaling::Amplitude => "amplitude",
            Scaling::Psd => "psd",
        }
    }

    /// Decibels of a value of this scaling: `20 log10 s` for an amplitude,
    /// `10 log10 s` for a power density (so both read the same dB change).
    pub fn to_db(self, s: f64) -> f64 {
        match self {
            Scaling::Amplitude => 20.0 * s.log10(),
            Scaling::Psd => 10.0 * s.log10(),
        }
    }
}

/// Errors of [`spectrogram`] and [`compare`]; each carries the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum StftError {
    #[error("the signal is empty: a spectrogram needs samples")]
    Empty,
    /// Cancelled through the flag of [`spectrogram_cancellable`]: no result.
    #[error(transparent)]
    Interrupted(#[from] crate::cancel::Interrupted),
    #[error("sample {index} of the signal is {value}: samples must be finite")]
    NotFinite { index: usize, value: f64 },
    #[error("sample rate {sample_rate} Hz must be finite and > 0")]
    BadSampleRate { sample_rate: f64 },
    #[error("segment length L = {segment_len} must be >= 2 (a record of N samples with S segments has L = N/S)")]
    SegmentTooShort { segment_len: usize },
    #[error("the signal has {samples} samples, fewer than one segment of L = {segment_len}")]
    TooShort { samples: usize, segment_len: usize },
    #[error("overlap {overlap} must be a fraction in [0, 1)")]
    BadOverlap { overlap: f64 },
    #[error("FFT length {nfft} must be >= the segment length {segment_len}")]
    BadNfft { nfft: usize, segment_len: usize },
    #[error("FFT length {nfft} is too large: at most {max} (2^24)")]
    NfftTooLarge { nfft: usize, max: usize },
    #[error("the spectrogram would have {n_segments} segments x {n_freq} bins = {cells} values, more than {max}: use fewer segments or a shorter FFT")]
    TooLarge {
        n_segments: usize,
        n_freq: usize,
        cells: u128,
        max: u128,
    },
    #[error("spectrograms have different shapes: measured {measured_time} segments x {measured_freq} bins, model {model_time} x {model_freq} (records of different length or options?)")]
    ShapeMismatch {
        measured_time: usize,
        measured_freq: usize,
        model_time: usize,
        model_freq: usize,
    },
    #[error("spectrograms are on different {axis} grids: measured {measured} vs model {model} at index {index}")]
    GridMismatch {
        axis: &'static str,
        index: usize,
        measured: f64,
        model: f64,
    },
    #[error("spectrograms have different scalings: measured {measured:?}, model {model:?}")]
    ScalingMismatch { measured: Scaling, model: Scaling },
    #[error("{which} spectrogram value at segment {t}, bin {k} is {value}: values must be finite and >= 0")]
    BadValue {
        which: &'static str,
        t: usize,
        k: usize,
        value: f64,
    },
    #[error("spectrogram has {len} values but n_time x n_freq = {n_time} x {n_freq}")]
    BadLayout {
        len: usize,
        n_time: usize,
        n_freq: usize,
    },
    #[error("floor fraction {floor_fraction} must be in [0, 1]")]
    BadFloor { floor_fraction: f64 },
    #[error("the measured spectrogram is zero everywhere: Eq 33 divides by it")]
    ZeroMeasured,
}

/// Largest FFT length (2^24; the FFT buffers are allocated up front).
pub const MAX_NFFT: usize = 1 << 24;
/// Largest spectrogram (segments x bins) values: 5e7, 400 MB of f64.
pub const MAX_CELLS: u128 = 50_000_000;

/// STFT options. Build with [`StftOptions::paper`] or
/// [`StftOptions::with_segments`] and adjust fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StftOptions {
    pub window: Window,
    pub symmetry: Symmetry,
    /// Segment length `L`, samples (≥ 2).
    pub segment_len: usize,
    /// Overlap of consecutive segments as a fraction of `L`, in `[0, 1)`;
    /// `n_ov = round(overlap · L)` samples, at most `L − 1`.
    pub overlap: f64,
    /// FFT length `N_fft ≥ L` (zero padding); `None` = `L` (scipy's default).
    pub nfft: Option<usize>,
    /// Sampling frequency `f_s`, Hz.
    pub sample_rate: f64,
    /// Segment mean removal; default [`Detrend::None`] (see the module docs).
    pub detrend: Detrend,
    /// Value scaling; default [`Scaling::Amplitude`].
    pub scaling: Scaling,
}

impl StftOptions {
    /// Paper defaults: symmetric Hamming, L = floor(N/15), 50 % overlap.
    /// Also `N_fft = L`, [`Detrend::None`], [`Scaling::Amplitude`].
    pub fn paper(n_samples: usize, sample_rate: f64) -> Self {
        Self::with_segments(n_samples, sample_rate, 15)
    }

    /// As [`StftOptions::paper`] with `L = ⌊N / segments⌋` (`segments = 0`
    /// gives `L = 0`, reported as [`StftError::SegmentTooShort`]).
    pub fn with_segments(n_samples: usize, sample_rate: f64, segments: usize) -> Self {
        Self {
            window: Window::Hamming,
            symmetry: Symmetry::Symmetric,
            segment_len: n_samples.checked_div(segments).unwrap_or(0),
            overlap: 0.5,
            nfft: None,
            sample_rate,
            detrend: Detrend::None,
            scaling: Scaling::Amplitude,
        }
    }

    /// Validates the options for a record of `n_samples` and returns the
    /// segment layout.
    pub fn layout(&self, n_samples: usize) -> Result<StftLayout, StftError> {
        let fs = self.sample_rate;
        if !(fs.is_finite() && fs > 0.0) {
            return Err(StftError::BadSampleRate { sample_rate: fs });
        }
        let l = self.segment_len;
        if l < 2 {
            return Err(StftError::SegmentTooShort { segment_len: l });
        }
        if !(self.overlap >= 0.0 && self.overlap < 1.0) {
            return Err(StftError::BadOverlap {
                overlap: self.overlap,
            });
        }
        let nfft = self.nfft.unwrap_or(l);
        if nfft < l {
            return Err(StftError::BadNfft {
                nfft,
                segment_len: l,
            });
        }
        if nfft > MAX_NFFT {
            return Err(StftError::NfftTooLarge {
                nfft,
                max: MAX_NFFT,
            });
        }
        if n_samples == 0 {
            return Err(StftError::Empty);
        }
        if n_samples < l {
            return Err(StftError::TooShort {
                samples: n_samples,
                segment_len: l,
            });
        }
        let noverlap = ((self.overlap * l as f64).round() as usize).min(l - 1);
        let hop = l - noverlap;
        let n_segments = 1 + (n_samples - l) / hop;
        let cells = n_segments as u128 * (nfft / 2 + 1) as u128;
        if cells > MAX_CELLS {
            return Err(StftError::TooLarge {
                n_segments,
                n_freq: nfft / 2 + 1,
                cells,
                max: MAX_CELLS,
            });
        }
        Ok(StftLayout {
            segment_len: l,
            noverlap,
            hop,
            n_segments,
            nfft,
            n_freq: nfft / 2 + 1,
            used_samples: (n_samples - l) / hop * hop + l,
        })
    }
}

/// Segment layout of an STFT (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StftLayout {
    /// `L`.
    pub segment_len: usize,
    /// `n_ov`, samples shared by consecutive segments.
    pub noverlap: usize,
    /// `H = L − n_ov`.
    pub hop: usize,
    /// `M`.
    pub n_segments: usize,
    /// `N_fft`.
    pub nfft: usize,
    /// `⌊N_fft/2⌋ + 1` one-sided bins.
    pub n_freq: usize,
    /// Samples covered by the segments (`(M−1) H + L ≤ N`).
    pub used_samples: usize,
}

/// A one-sided spectrogram `s(t_m, f_k)` (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Spectrogram {
    /// `f_k = k f_s / N_fft`, Hz, `k = 0 … ⌊N_fft/2⌋`.
    pub frequencies: Vec<f64>,
    /// Segment centres `t_m = (m H + L/2)/f_s`, s, from the first sample.
    pub times: Vec<f64>,
    /// Row-major: `magnitude[t * n_freq + k]` (values of [`Self::scaling`]).
    pub magnitude: Vec<f64>,
    pub n_freq: usize,
    pub n_time: usize,
    pub scaling: Scaling,
}

impl Spectrogram {
    /// `s(t_t, f_k)`.
    #[inline]
    pub fn at(&self, t: usize, k: usize) -> f64 {
        self.magnitude[t * self.n_freq + k]
    }

    /// The spectrum of segment `t` (all bins).
    pub fn row(&self, t: usize) -> &[f64] {
        &self.magnitude[t * self.n_freq..(t + 1) * self.n_freq]
    }

    /// Largest value (0 for an empty spectrogram).
    pub fn max(&self) -> f64 {
        self.magnitude.iter().fold(0.0, |m, &v| m.max(v))
    }

    /// Bin indices `k` with `f_min ≤ f_k ≤ f_max` (possibly empty).
    pub fn band(&self, f_min: f64, f_max: f64) -> std::ops::Range<usize> {
        let lo = self.frequencies.partition_point(|&f| f < f_min);
        let hi = self.frequencies.partition_point(|&f| f <= f_max);
        lo..hi.max(lo)
    }

    /// The spectrogram restricted to the bins with `f_min ≤ f ≤ f_max`.
    pub fn restrict(&self, f_min: f64, f_max: f64) -> Spectrogram {
        let r = self.band(f_min, f_max);
        let mut magnitude = Vec::with_capacity(self.n_time * r.len());
        for t in 0..self.n_time {
            magnitude.extend_from_slice(&self.row(t)[r.clone()]);
        }
        Spectrogram {
            frequencies: self.frequencies[r.clone()].to_vec(),
            times: self.times.clone(),
            magnitude,
            n_freq: r.len(),
            n_time: self.n_time,
            scaling: self.scaling,
        }
    }
}

/// The smallest `n' ≥ n` of the form `2^a 3^b 5^c 7^d` (like
/// `scipy.fft.next_fast_len`), a length rustfft transforms with its fastest
/// mixed-radix algorithms. `n = 0` gives 1.
pub fn next_fast_len(n: usize) -> usize {
    let n = n.max(1);
    let mut best = n.next_power_of_two();
    let mut p7 = 1usize;
    while p7 < best {
        let mut p5 = p7;
        while p5 < best {
            let mut p3 = p5;
            while p3 < best {
                let mut p = p3;
                while p < n {
                    p *= 2;
                }
                if p < best {
                    best = p;
                }
                p3 *= 3;
            }
            p5 *= 5;
        }
        p7 *= 7;
    }
    best
}

/// The STFT spectrogram of `x` (see the module docs for the definition and
/// the scaling). Errors: empty or non-finite signal, bad options, signal
/// shorter than one segment.
pub fn spectrogram(x: &[f64], opts: &StftOptions) -> Result<Spectrogram, StftError> {
    spectrogram_cancellable(x, opts, Cancel::NEVER)
}

/// As [`spectrogram`], polling `cancel` before each segment: once it is
/// set the remaining segments are skipped and the call ends with
/// [`StftError::Interrupted`] ([`crate::cancel`]).
pub fn spectrogram_cancellable(
    x: &[f64],
    opts: &StftOptions,
    cancel: Cancel,
) -> Result<Spectrogram, StftError> {
    let lay = opts.layout(x.len())?;
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(StftError::NotFinite { index, value });
    }
    let (l, nfft, n_freq, hop) = (lay.segment_len, lay.nfft, lay.n_freq, lay.hop);
    let fs = opts.sample_rate;
    let w = opts.window.coefficients(l, opts.symmetry);
    let sum_w: f64 = w.iter().sum();
    let sum_w2: f64 = w.iter().map(|v| v * v).sum();
    let nyquist = if nfft % 2 == 0 { Some(nfft / 2) } else { None };
    let fold = |k: usize| {
        if k == 0 || Some(k) == nyquist {
            1.0
        } else {
            2.0
        }
    };
    let plan = RealFftPlanner::<f64>::new().plan_fft_forward(nfft);
    let scaling = opts.scaling;
    let detrend = opts.detrend;
    let mut magnitude = vec![0.0; lay.n_segments * n_freq];
    magnitude.par_chunks_mut(n_freq).enumerate().for_each_init(
        || {
            (
                plan.make_input_vec(),
                plan.make_output_vec(),
                plan.make_scratch_vec(),
            )
        },
        |(input, output, scratch), (m, row)| {
            if cancel.is_cancelled() {
                return;
            }
            let seg = &x[m * hop..m * hop + l];
            let mean = match detrend {
                Detrend::None => 0.0,
                Detrend::Constant => seg.iter().sum::<f64>() / l as f64,
            };
            for ((d, &s), &wn) in input.iter_mut().zip(seg).zip(&w) {
                *d = (s - mean) * wn;
            }
            input[l..].iter_mut().for_each(|d| *d = 0.0);
            plan.process_with_scratch(input, output, scratch)
                .expect("buffer lengths come from the plan");
            for (k, (r, z)) in row.iter_mut().zip(output.iter()).enumerate() {
                let p = z.norm_sqr();
                *r = match scaling {
                    // sqrt(re² + im²), not hypot (3x the cost); hypot only
                    // where the square overflows
                    Scaling::Amplitude => {
                        fold(k) * if p.is_finite() { p.sqrt() } else { z.norm() } / sum_w
                    }
                    Scaling::Psd => fold(k) * p / (fs * sum_w2),
                };
            }
        },
    );
    cancel.check()?;
    Ok(Spectrogram {
        frequencies: (0..n_freq).map(|k| k as f64 * fs / nfft as f64).collect(),
        times: (0..lay.n_segments)
            .map(|m| (m as f64 * hop as f64 + l as f64 / 2.0) / fs)
            .collect(),
        magnitude,
        n_freq,
        n_time: lay.n_segments,
        scaling,
    })
}

/// Result of [`compare`] (paper Eq 33 and a robust variant).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrogramDifference {
    /// Eq 33: `max_{f,t} |s_exp − s_num| / s_exp · 100` over all bins, %
    /// (`+∞` if some bin has `s_exp = 0 ≠ s_num`).
    pub max_relative_percent: f64,
    /// Segment centre (s) and frequency (Hz) of that maximum.
    pub at_time: f64,
    pub at_frequency: f64,
    /// The same maximum over the bins with `s_exp ≥ floor_fraction · max s_exp` only, %.
    pub robust_max_relative_percent: f64,
    pub floor_fraction: f64,
    pub robust_at_time: f64,
    pub robust_at_frequency: f64,
    /// Bins in the robust maximum, and all bins.
    pub bins_compared: usize,
    pub bins_total: usize,
    /// Global relative difference `‖s_exp − s_num‖₂ / ‖s_exp‖₂ · 100` over all bins, %.
    pub global_relative_percent: f64,
}

fn check_values(which: &'static str, s: &Spectrogram) -> Result<(), StftError> {
    if s.magnitude.len() != s.n_time * s.n_freq
        || s.frequencies.len() != s.n_freq
        || s.times.len() != s.n_time
    {
        return Err(StftError::BadLayout {
            len: s.magnitude.len(),
            n_time: s.n_time,
            n_freq: s.n_freq,
        });
    }
    if let Some((i, &value)) = s
        .magnitude
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
    {
        return Err(StftError::BadValue {
            which,
            t: i / s.n_freq.max(1),
            k: i % s.n_freq.max(1),
            value,
        });
    }
    Ok(())
}

fn check_grid(axis: &'static str, a: &[f64], b: &[f64]) -> Result<(), StftError> {
    let scale = a.iter().chain(b).fold(0.0f64, |m, v| m.max(v.abs()));
    for (index, (&measured, &model)) in a.iter().zip(b).enumerate() {
        if (measured - model).abs() > 1e-9 * scale {
            return Err(StftError::GridMismatch {
                axis,
                index,
                measured,
                model,
            });
        }
    }
    Ok(())
}

/// Compares a measured spectrogram `s_exp` with a model one `s_num` on the
/// same grid (paper Eq 33):
///
/// ```text
/// Eq 33:   E    = max_{f,t} |s_exp(f,t) − s_num(f,t)| / s_exp(f,t) · 100  %
/// robust:  E_fl = the same maximum over {(f,t) : s_exp(f,t) ≥ floor_fraction · max s_exp}
/// ```
///
/// **Absolute value.** The paper prints Eq 33 without bars; without them
/// the maximum would only see bins where the model *under*-predicts
/// (`s_num < s_exp`) and ignore any over-prediction, however large, so the
/// absolute value is used: a "maximum difference" is symmetric in sign.
///
/// **Why the robust variant.** Eq 33 divides by `s_exp` bin by bin. A
/// spectrogram of a narrow-band response is near zero in most bins (far
/// from the excitation and its harmonics, only noise, leakage sidelobes and
/// round-off remain), where the ratio of two tiny, unrelated numbers can be
/// arbitrarily large (`+∞` when `s_exp = 0`): the maximum is then set by
/// the noise floor, not by the model's error where the response is.
/// Restricting to bins at least `floor_fraction` of the peak (e.g. 0.01 =
/// −40 dB in amplitude) measures the model where there is signal. With
/// `floor_fraction = 0` the robust value equals Eq 33. Bins with
/// `s_exp = s_num = 0` count as a 0 % difference.
///
/// Ties go to the first bin in row-major (time, then frequency) order.
/// Errors: different shapes, grids or scalings, negative or non-finite
/// values, `floor_fraction ∉ [0, 1]`, an all-zero `measured`.
pub fn compare(
    measured: &Spectrogram,
    model: &Spectrogram,
    floor_fraction: f64,
) -> Result<SpectrogramDifference, StftError> {
    if !(0.0..=1.0).contains(&floor_fraction) {
        return Err(StftError::BadFloor { floor_fraction });
    }
    if measured.n_time != model.n_time || measured.n_freq != model.n_freq {
        return Err(StftError::ShapeMismatch {
            measured_time: measured.n_time,
            measured_freq: measured.n_freq,
            model_time: model.n_time,
            model_freq: model.n_freq,
        });
    }
    if measured.scaling != model.scaling {
        return Err(StftError::ScalingMismatch {
            measured: measured.scaling,
            model: model.scaling,
        });
    }
    check_values("measured", measured)?;
    check_values("model", model)?;
    check_grid("frequency", &measured.frequencies, &model.frequencies)?;
    check_grid("time", &measured.times, &model.times)?;
    let peak = measured.max();
    if peak <= 0.0 {
        return Err(StftError::ZeroMeasured);
    }
    let threshold = floor_fraction * peak;
    let n_freq = measured.n_freq;
    let (mut best, mut best_i) = (f64::NEG_INFINITY, 0usize);
    let (mut rbest, mut rbest_i) = (f64::NEG_INFINITY, 0usize);
    let (mut compared, mut num2, mut den2) = (0usize, 0.0f64, 0.0f64);
    for (i, (&e, &s)) in measured.magnitude.iter().zip(&model.magnitude).enumerate() {
        let d = (e - s).abs();
        num2 += d * d;
        den2 += e * e;
        let r = if d == 0.0 { 0.0 } else { d / e * 100.0 };
        if r > best {
            best = r;
            best_i = i;
        }
        if e >= threshold {
            compared += 1;
            if r > rbest {
                rbest = r;
                rbest_i = i;
            }
        }
    }
    let at = |i: usize| (measured.times[i / n_freq], measured.frequencies[i % n_freq]);
    let (at_time, at_frequency) = at(best_i);
    let (robust_at_time, robust_at_frequency) = at(rbest_i);
    Ok(SpectrogramDifference {
        max_relative_percent: best,
        at_time,
        at_frequency,
        robust_max_relative_percent: rbest,
        floor_fraction,
        robust_at_time,
        robust_at_frequency,
        bins_compared: compared,
        bins_total: measured.magnitude.len(),
        global_relative_percent: (num2 / den2).sqrt() * 100.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_len() {
        assert_eq!(next_fast_len(0), 1);
        assert_eq!(next_fast_len(1), 1);
        assert_eq!(next_fast_len(11), 12);
        assert_eq!(next_fast_len(13), 14);
        assert_eq!(next_fast_len(1024), 1024);
        assert_eq!(next_fast_len(1025), 1029); // 3 * 7^3
                                               // brute-force oracle
        let smooth = |mut n: usize| {
            for p in [2, 3, 5, 7] {
                while n % p == 0 {
                    n /= p;
                }
            }
            n == 1
        };
        for n in 1..3000 {
            let f = next_fast_len(n);
            assert!(smooth(f) && f >= n);
            assert!((n..f).all(|m| !smooth(m)), "n = {n}");
        }
        let f = next_fast_len(583_466);
        assert!(smooth(f) && (583_466..f).all(|m| !smooth(m)));
    }
}
