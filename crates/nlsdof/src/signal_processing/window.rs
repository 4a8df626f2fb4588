//! Data windows for spectral estimation.
//!
//! **Symmetric vs periodic.** A window of length `L` can be defined with
//! denominator `L − 1` (*symmetric*: `w[0] = w[L−1]`, the form used for
//! FIR filter design) or with denominator `L` (*periodic* or *DFT-even*:
//! the first `L` samples of a symmetric window of length `L + 1`). For
//! spectral analysis with an `L`-point DFT the **periodic** form is the
//! correct one: its DFT has the exact sidelobe/bin structure (e.g. the Hann
//! window's DFT has only three non-zero bins) and 50 % overlapped periodic
//! Hann windows sum to a constant. Using the symmetric form in Welch
//! averaging is a classic bug (slight scalloping and leakage errors).
//! [`Window::coefficients`] therefore takes the [`Symmetry`] explicitly;
//! the Welch estimator uses [`Symmetry::Periodic`].
//!
//! Generalised cosine windows `w[n] = Σ_k (−1)^k a_k cos(2πkn/D)`,
//! `D = L` (periodic) or `L − 1` (symmetric):
//! Hann `a = (0.5, 0.5)`, Hamming `(0.54, 0.46)`,
//! Blackman `(0.42, 0.5, 0.08)`; rectangular `w = 1`.

use std::f64::consts::PI;

/// Window shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    Rectangular,
    Hann,
    Hamming,
    Blackman,
}

/// Symmetric (`D = L − 1`) or periodic (`D = L`, DFT-even) definition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    Symmetric,
    Periodic,
}

impl Window {
    fn coeffs(self) -> &'static [f64] {
        match self {
            Window::Rectangular => &[1.0],
            Window::Hann => &[0.5, 0.5],
            Window::Hamming => &[0.54, 0.46],
            Window::Blackman => &[0.42, 0.5, 0.08],
        }
    }

    /// Name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Window::Rectangular => "rectangular",
            Window::Hann => "hann",
            Window::Hamming => "hamming",
            Window::Blackman => "blackman",
        }
    }

    /// The `len` window coefficients (`len >= 1`; a length-1 window is `[1]`).
    pub fn coefficients(self, len: usize, symmetry: Symmetry) -> Vec<f64> {
        if len <= 1 {
            return vec![1.0; len];
        }
        let d = match symmetry {
            Symmetry::Symmetric => (len - 1) as f64,
            Symmetry::Periodic => len as f64,
        };
        let a = self.coeffs();
        (0..len)
            .map(|n| {
                a.iter()
                    .enumerate()
                    .map(|(k, &ak)| {
                        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                        sign * ak * (2.0 * PI * k as f64 * n as f64 / d).cos()
                    })
                    .sum()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_and_symmetric_hann() {
        let p = Window::Hann.coefficients(8, Symmetry::Periodic);
        let s = Window::Hann.coefficients(9, Symmetry::Symmetric);
        for i in 0..8 {
            assert!((p[i] - s[i]).abs() < 1e-15);
        }
        assert!(p[0].abs() < 1e-15 && (p[4] - 1.0).abs() < 1e-15);
        let s8 = Window::Hann.coefficients(8, Symmetry::Symmetric);
        assert!((s8[0] - s8[7]).abs() < 1e-15);
        // 50 % overlapped periodic Hann windows sum to 1.
        for n in 0..4 {
            assert!((p[n] + p[n + 4] - 1.0).abs() < 1e-15);
        }
    }
}
