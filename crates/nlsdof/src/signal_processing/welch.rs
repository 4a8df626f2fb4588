//! Welch-averaged spectra and FRF estimators (Bendat & Piersol,
//! *Random Data*, 4th ed., ch. 9).
//!
//! The record is cut into `n_d` segments of `L` samples overlapping by
//! `overlap × L` (rounded); each segment has its mean removed (optional),
//! is multiplied by the window `w` ([`Symmetry::Periodic`] by default; see
//! [`super::window`]) and transformed, `X_i(f_k) = Σ_n w_n x_n e^{−2πjkn/L}`.
//! One-sided spectral densities, `f_k = k f_s/L`, `k = 0..=L/2`:
//!
//! ```text
//! G_xx = (2 / (f_s Σw² n_d)) Σ_i |X_i|²,   G_yy likewise,
//! G_xy = (2 / (f_s Σw² n_d)) Σ_i conj(X_i) Y_i        (factor 1 at k = 0 and k = L/2)
//! H1 = G_xy / G_xx      (unbiased by output noise)
//! H2 = G_yy / G_yx = G_yy / conj(G_xy)   (unbiased by input noise)
//! γ² = |G_xy|² / (G_xx G_yy)            (ordinary coherence, H1/H2 = γ²)
//! ```
//!
//! Normalised random error of `|H1|` (Bendat & Piersol Eq 9.90):
//! `ε ≈ √(1 − γ²) / (|γ| √(2 n_d))` (independent segments).
//!
//! Both real channels go through one complex FFT of `z = x + j y`:
//! `X_k = (Z_k + conj Z_{L−k})/2`, `Y_k = (Z_k − conj Z_{L−k})/(2j)`.

use super::{check_pair, SignalError, Symmetry, Window};
use nalgebra::Complex;
use rustfft::FftPlanner;

type C64 = Complex<f64>;

/// Options of [`welch_frf`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WelchOptions {
    /// Segment (and FFT) length `L`, samples.
    pub segment: usize,
    /// Fractional overlap of consecutive segments, in `[0, 1)`.
    pub overlap: f64,
    pub window: Window,
    pub symmetry: Symmetry,
    /// Remove each segment's mean before windowing.
    pub detrend_mean: bool,
}

impl Default for WelchOptions {
    fn default() -> Self {
        Self {
            segment: 4096,
            overlap: 0.5,
            window: Window::Hann,
            symmetry: Symmetry::Periodic,
            detrend_mean: true,
        }
    }
}

/// Welch FRF estimate on `f_k = k f_s / L`, `k = 0..=L/2`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfEstimate {
    pub frequency_hz: Vec<f64>,
    pub h1: Vec<C64>,
    pub h2: Vec<C64>,
    pub coherence: Vec<f64>,
    pub gxx: Vec<f64>,
    pub gyy: Vec<f64>,
    pub gxy: Vec<C64>,
    /// Number of averaged segments `n_d`.
    pub averages: usize,
}

impl FrfEstimate {
    /// Normalised random error of `|H1|` at bin `k`: `√(1−γ²)/(|γ|√(2 n_d))`.
    pub fn h1_random_error(&self, k: usize) -> f64 {
        let g2 = self.coherence[k];
        if g2 <= 0.0 {
            return f64::INFINITY;
        }
        ((1.0 - g2).max(0.0)).sqrt() / (g2.sqrt() * (2.0 * self.averages as f64).sqrt())
    }
}

/// Splits the DFT `z` of `x + j y` into the DFTs of `x` and `y` at bin `k`.
#[inline]
fn split(z: &[C64], k: usize) -> (C64, C64) {
    let l = z.len();
    let a = z[k];
    let b = z[(l - k) % l].conj();
    let x = (a + b) * 0.5;
    let y = (a - b) * C64::new(0.0, -0.5);
    (x, y)
}

/// H1, H2 and coherence by Welch averaging (see the module documentation).
///
/// Errors: mismatched lengths, non-finite samples, bad `fs`, segment
/// longer than the record or shorter than 2, overlap outside `[0, 1)`, and
/// an input without power.
pub fn welch_frf(
    fs: f64,
    x: &[f64],
    y: &[f64],
    opts: &WelchOptions,
) -> Result<FrfEstimate, SignalError> {
    check_pair(fs, x, y)?;
    let l = opts.segment;
    if l < 2 || l > x.len() {
        return Err(SignalError::BadSegment {
            segment: l,
            samples: x.len(),
        });
    }
    if !(opts.overlap >= 0.0 && opts.overlap < 1.0) {
        return Err(SignalError::BadOverlap {
            overlap: opts.overlap,
        });
    }
    let step = (l - ((opts.overlap * l as f64).round() as usize).min(l - 1)).max(1);
    let nseg = 1 + (x.len() - l) / step;
    let w = opts.window.coefficients(l, opts.symmetry);
    let sw2: f64 = w.iter().map(|v| v * v).sum();
    let fft = FftPlanner::<f64>::new().plan_fft_forward(l);
    let mut scratch = vec![C64::new(0.0, 0.0); fft.get_inplace_scratch_len()];
    let nb = l / 2 + 1;
    let mut sxx = vec![0.0; nb];
    let mut syy = vec![0.0; nb];
    let mut sxy = vec![C64::new(0.0, 0.0); nb];
    let mut buf = vec![C64::new(0.0, 0.0); l];
    // Input energy after windowing and mean removal, and before mean removal:
    // X and Y share one complex FFT, so an input without power still gets
    // round-off from Y in its bins (|X|^2 ~ 1e-32 |Y|^2); decide in the time
    // domain instead.
    let (mut ex, mut raw) = (0.0f64, 0.0f64);
    for i in 0..nseg {
        let xs = &x[i * step..i * step + l];
        let ys = &y[i * step..i * step + l];
        let (mx, my) = if opts.detrend_mean {
            (
                xs.iter().sum::<f64>() / l as f64,
                ys.iter().sum::<f64>() / l as f64,
            )
        } else {
            (0.0, 0.0)
        };
        for n in 0..l {
            buf[n] = C64::new(w[n] * (xs[n] - mx), w[n] * (ys[n] - my));
            ex += buf[n].re * buf[n].re;
            raw += (w[n] * xs[n]) * (w[n] * xs[n]);
        }
        fft.process_with_scratch(&mut buf, &mut scratch);
        for k in 0..nb {
            let (xk, yk) = split(&buf, k);
            sxx[k] += xk.norm_sqr();
            syy[k] += yk.norm_sqr();
            sxy[k] += xk.conj() * yk;
        }
    }
    let base = 1.0 / (fs * sw2 * nseg as f64);
    let mut est = FrfEstimate {
        frequency_hz: (0..nb).map(|k| k as f64 * fs / l as f64).collect(),
        h1: Vec::with_capacity(nb),
        h2: Vec::with_capacity(nb),
        coherence: Vec::with_capacity(nb),
        gxx: Vec::with_capacity(nb),
        gyy: Vec::with_capacity(nb),
        gxy: Vec::with_capacity(nb),
        averages: nseg,
    };
    if sxx.iter().all(|&v| v == 0.0) || ex <= (64.0 * f64::EPSILON).powi(2) * raw {
        return Err(SignalError::NoInputPower);
    }
    for k in 0..nb {
        let f = if k == 0 || 2 * k == l {
            base
        } else {
            2.0 * base
        };
        let (gxx, gyy, gxy) = (sxx[k] * f, syy[k] * f, sxy[k] * f);
        est.h1.push(if gxx > 0.0 {
            gxy / gxx
        } else {
            C64::new(0.0, 0.0)
        });
        est.h2.push(if gxy.norm_sqr() > 0.0 {
            C64::new(gyy, 0.0) / gxy.conj()
        } else {
            C64::new(0.0, 0.0)
        });
        est.coherence.push(if gxx > 0.0 && gyy > 0.0 {
            (gxy.norm_sqr() / (gxx * gyy)).min(1.0)
        } else {
            0.0
        });
        est.gxx.push(gxx);
        est.gyy.push(gyy);
        est.gxy.push(gxy);
    }
    Ok(est)
}

/// Result of [`spectral_ratio`].
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralRatio {
    pub frequency_hz: Vec<f64>,
    /// `Y/X` (0 where the input has no power).
    pub h: Vec<C64>,
    /// `|X(f_k)|`, to judge where the input has energy.
    pub input_magnitude: Vec<f64>,
}

/// Spectral ratio of one record, `H(f_k) = Y(f_k) / X(f_k)` on
/// `f_k = k f_s / N`, `k = 0..=N/2`, without window (rectangular; the right
/// choice for a sine sweep or an impact that decays within the record).
/// Bins where `|X|` is below `1e-12 max|X|` are reported as 0.
pub fn spectral_ratio(fs: f64, x: &[f64], y: &[f64]) -> Result<SpectralRatio, SignalError> {
    check_pair(fs, x, y)?;
    let n = x.len();
    if n < 2 {
        return Err(SignalError::BadSegment {
            segment: n,
            samples: n,
        });
    }
    let mut buf: Vec<C64> = x.iter().zip(y).map(|(&a, &b)| C64::new(a, b)).collect();
    FftPlanner::<f64>::new()
        .plan_fft_forward(n)
        .process(&mut buf);
    let nb = n / 2 + 1;
    let mut xs = Vec::with_capacity(nb);
    let mut ys = Vec::with_capacity(nb);
    for k in 0..nb {
        let (a, b) = split(&buf, k);
        xs.push(a);
        ys.push(b);
    }
    let xmax = xs.iter().map(|v| v.norm()).fold(0.0, f64::max);
    // All-zero input: |X| is only round-off leaked from Y by the shared FFT.
    if xmax == 0.0 || x.iter().all(|&v| v == 0.0) {
        return Err(SignalError::NoInputPower);
    }
    let h = xs
        .iter()
        .zip(&ys)
        .map(|(a, b)| {
            if a.norm() > 1e-12 * xmax {
                b / a
            } else {
                C64::new(0.0, 0.0)
            }
        })
        .collect();
    let f = (0..nb).map(|k| k as f64 * fs / n as f64).collect();
    Ok(SpectralRatio {
        frequency_hz: f,
        h,
        input_magnitude: xs.iter().map(|v| v.norm()).collect(),
    })
}
