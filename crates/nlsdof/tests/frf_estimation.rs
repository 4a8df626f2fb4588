//! FRF estimation from time histories of a simulated linear SDoF.
//!
//! The system `x'' + 2ζω_n x' + ω_n² x = u(t)` is driven by a
//! zero-order-hold input; its sampled response obeys exactly
//! `q_{k+1} = Φ q_k + Γ u_k`, `Φ = e^{AT}`, `Γ = A⁻¹(Φ − I)B` (closed form
//! below), so the true FRF from `u_k` to `x_k` is the discrete-time
//! `H_d(e^{jθ}) = C (e^{jθ} I − Φ)⁻¹ Γ`, `θ = 2πf/f_s` — no simulation
//! error at all.

mod support;
use nlsdof::signal_processing::{
    spectral_ratio, welch_frf, SignalError, Symmetry, WelchOptions, Window,
};
use nlsdof::vector_fitting::C64;
use std::f64::consts::PI;
use support::fixtures::Rng;

struct Sdof {
    phi: [[f64; 2]; 2],
    gam: [f64; 2],
}

impl Sdof {
    fn new(fn_hz: f64, zeta: f64, fs: f64) -> Self {
        let wn = 2.0 * PI * fn_hz;
        let sg = zeta * wn;
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        let t = 1.0 / fs;
        let (c, s, e) = ((wd * t).cos(), (wd * t).sin(), (-sg * t).exp());
        let phi = [
            [e * (c + sg / wd * s), e * s / wd],
            [-e * wn * wn * s / wd, e * (c - sg / wd * s)],
        ];
        // Γ = A⁻¹ (Φ − I) B with A⁻¹ = [[−2ζ/ω_n, −1/ω_n²], [1, 0]], B = [0, 1].
        let (p01, p11) = (phi[0][1], phi[1][1] - 1.0);
        let gam = [-2.0 * zeta / wn * p01 - p11 / (wn * wn), p01];
        Self { phi, gam }
    }

    fn simulate(&self, u: &[f64]) -> Vec<f64> {
        let mut q = [0.0, 0.0];
        u.iter()
            .map(|&uk| {
                let y = q[0];
                q = [
                    self.phi[0][0] * q[0] + self.phi[0][1] * q[1] + self.gam[0] * uk,
                    self.phi[1][0] * q[0] + self.phi[1][1] * q[1] + self.gam[1] * uk,
                ];
                y
            })
            .collect()
    }

    fn frf(&self, f: f64, fs: f64) -> C64 {
        let z = C64::from_polar(1.0, 2.0 * PI * f / fs);
        let (a, b, c, d) = (
            z - self.phi[0][0],
            C64::new(-self.phi[0][1], 0.0),
            C64::new(-self.phi[1][0], 0.0),
            z - self.phi[1][1],
        );
        let det = a * d - b * c;
        // First row of the inverse times Γ.
        (d * self.gam[0] - b * self.gam[1]) / det
    }
}

#[test]
fn discrete_model_matches_its_frf_at_steady_state() {
    // Sanity check of the closed-form Φ, Γ: steady sine response amplitude.
    let fs = 1000.0;
    let sys = Sdof::new(50.0, 0.02, fs);
    let f = 40.0;
    let u: Vec<f64> = (0..20000)
        .map(|k| (2.0 * PI * f * k as f64 / fs).cos())
        .collect();
    let y = sys.simulate(&u);
    let h = sys.frf(f, fs);
    for k in 19000..19010 {
        let expect = (h * C64::from_polar(1.0, 2.0 * PI * f * k as f64 / fs)).re;
        assert!(
            (y[k] - expect).abs() < 1e-9 * h.norm(),
            "{} vs {}",
            y[k],
            expect
        );
    }
    // And the continuous receptance at low frequency: 1/ω_n².
    let wn = 2.0 * PI * 50.0;
    assert!((sys.frf(0.0, fs).re * wn * wn - 1.0).abs() < 1e-9);
}

/// H1 of white-noise input with white output noise equals the true FRF
/// within its theoretical random error `ε = √(1−γ²)/(|γ|√(2n_d))`
/// (Bendat & Piersol Eq 9.90): the normalised complex error
/// `|Ĥ1 − H|/(|H| ε)` behaves like a Rayleigh variable with
/// `E[(·)²] ≈ 2` (magnitude and phase errors each of standard deviation ε),
/// so fewer than 1 % of the bins may exceed 4ε (Rayleigh tail `e^{-8}`,
/// widened for the correlation of 50 %-overlapped segments); the
/// coherence matches its true value `|H|²G_uu/(|H|²G_uu + G_nn)` to 0.15
/// (about 5 standard deviations `√(2/n_d) γ (1 − γ²)` at γ² ≈ 0.5).
#[test]
fn h1_of_simulated_sdof_within_theoretical_variance() {
    let fs = 1000.0;
    let sys = Sdof::new(50.0, 0.02, fs);
    let n = 1 << 19;
    let mut rng = Rng(3);
    let u: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
    let x = sys.simulate(&u);
    let xrms = (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let y: Vec<f64> = x.iter().map(|v| v + 0.05 * xrms * rng.normal()).collect();
    let opts = WelchOptions {
        segment: 4096,
        overlap: 0.5,
        ..Default::default()
    };
    let est = welch_frf(fs, &u, &y, &opts).unwrap();
    assert_eq!(est.averages, 255);
    let mut sum = 0.0;
    let mut count = 0;
    let mut outliers = 0;
    let mut worst_coh: f64 = 0.0;
    for k in 1..est.frequency_hz.len() - 1 {
        let f = est.frequency_hz[k];
        if !(5.0..=400.0).contains(&f) || est.coherence[k] < 0.3 {
            continue;
        }
        let h = sys.frf(f, fs);
        let eps = est.h1_random_error(k);
        let r = (est.h1[k] - h).norm() / (h.norm() * eps);
        sum += r * r;
        count += 1;
        if r > 4.0 {
            outliers += 1;
        }
        // H1/H2 = γ².
        assert!(((est.h1[k] / est.h2[k]).re - est.coherence[k]).abs() < 1e-9);
        // Coherence against its true value |H|²G_uu/(|H|²G_uu + G_nn).
        let guu = 2.0 / fs;
        let gnn = 2.0 * (0.05 * xrms).powi(2) / fs;
        let g_true = h.norm_sqr() * guu / (h.norm_sqr() * guu + gnn);
        worst_coh = worst_coh.max((est.coherence[k] - g_true).abs());
    }
    let mean = sum / count as f64;
    eprintln!("H1: {count} bins, mean (|e|/eps)^2 = {mean:.3}, {outliers} beyond 4 eps, worst coherence error {worst_coh:.3}");
    assert!(count > 500, "{count} bins used");
    assert!(
        mean > 1.0 && mean < 3.0,
        "mean normalised squared error {mean} (expected about 2)"
    );
    assert!(
        (outliers as f64) < 0.01 * count as f64,
        "{outliers} of {count} bins beyond 4 eps"
    );
    assert!(worst_coh < 0.15, "coherence error {worst_coh}");
}

/// Without noise the ratio of output and input spectra of a sine sweep
/// (followed by enough silence for the response to decay) is the FRF.
#[test]
fn spectral_ratio_of_a_sweep_is_the_frf() {
    let fs = 1000.0;
    let sys = Sdof::new(50.0, 0.02, fs);
    let (n_sweep, n) = (20000, 1 << 15);
    let (f0, f1) = (10.0, 200.0);
    let dur = n_sweep as f64 / fs;
    let u: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 / fs;
            if k < n_sweep {
                (2.0 * PI * (f0 * t + 0.5 * (f1 - f0) / dur * t * t)).sin()
            } else {
                0.0
            }
        })
        .collect();
    let y = sys.simulate(&u);
    let r = spectral_ratio(fs, &u, &y).unwrap();
    let (f, h, xmag) = (r.frequency_hz, r.h, r.input_magnitude);
    let xmax = xmag.iter().cloned().fold(0.0, f64::max);
    let mut checked = 0;
    for k in 0..f.len() {
        if f[k] < 20.0 || f[k] > 190.0 || xmag[k] < 0.1 * xmax {
            continue;
        }
        let ht = sys.frf(f[k], fs);
        assert!(
            (h[k] - ht).norm() / ht.norm() < 1e-6,
            "f = {}: {} vs {}",
            f[k],
            h[k],
            ht
        );
        checked += 1;
    }
    assert!(checked > 5000);
}

#[test]
fn bad_signals_give_typed_errors() {
    let x = vec![0.0, 1.0, 2.0, f64::NAN, 1.0];
    let y = vec![0.0; 5];
    let o = WelchOptions {
        segment: 4,
        ..Default::default()
    };
    let e = welch_frf(100.0, &x, &y, &o).unwrap_err();
    assert!(
        matches!(e, SignalError::NotFinite { channel: "input", index: 3, value } if value.is_nan()),
        "{e}"
    );
    assert_eq!(
        welch_frf(100.0, &x[..4], &y, &o).unwrap_err(),
        SignalError::LengthMismatch {
            input: 4,
            output: 5
        }
    );
    let x = vec![1.0; 5];
    assert_eq!(
        welch_frf(0.0, &x, &y, &o).unwrap_err(),
        SignalError::BadSamplingFrequency { fs: 0.0 }
    );
    assert_eq!(
        welch_frf(
            1.0,
            &x,
            &y,
            &WelchOptions {
                segment: 8,
                ..Default::default()
            }
        )
        .unwrap_err(),
        SignalError::BadSegment {
            segment: 8,
            samples: 5
        }
    );
    assert_eq!(
        welch_frf(
            1.0,
            &x,
            &y,
            &WelchOptions {
                segment: 4,
                overlap: 1.0,
                ..Default::default()
            }
        )
        .unwrap_err(),
        SignalError::BadOverlap { overlap: 1.0 }
    );
    // Constant input: no power after mean removal.
    assert_eq!(
        welch_frf(1.0, &x, &y, &o).unwrap_err(),
        SignalError::NoInputPower
    );
    // Rectangular symmetric window is accepted too.
    let xr: Vec<f64> = (0..64).map(|k| (k as f64 * 0.7).sin()).collect();
    let o = WelchOptions {
        segment: 16,
        window: Window::Rectangular,
        symmetry: Symmetry::Symmetric,
        ..Default::default()
    };
    let e = welch_frf(1.0, &xr, &xr, &o).unwrap();
    assert!(e
        .h1
        .iter()
        .zip(&e.gxx)
        .all(|(h, &g)| g == 0.0 || (h - C64::new(1.0, 0.0)).norm() < 1e-12));
}

/// Issue 11: an all-zero (or constant, with mean removal) input channel with
/// a live output gave |H1| ~ 1e16 at coherence 0.98, because X and Y share
/// one complex FFT and round-off from Y leaks into X. It is an error.
#[test]
fn silent_input_with_live_output_is_no_input_power() {
    let n = 4096;
    let y: Vec<f64> = (0..n)
        .map(|k| (k as f64 * 0.37).sin() + 0.3 * (k as f64 * 1.91).cos())
        .collect();
    let o = WelchOptions {
        segment: 512,
        ..Default::default()
    };
    for x in [vec![0.0; n], vec![2.5; n]] {
        assert_eq!(
            welch_frf(1000.0, &x, &y, &o).unwrap_err(),
            SignalError::NoInputPower
        );
    }
    assert_eq!(
        spectral_ratio(1000.0, &vec![0.0; n], &y).unwrap_err(),
        SignalError::NoInputPower
    );
    // A weak but real input is still accepted.
    let x: Vec<f64> = (0..n).map(|k| 1e-9 * (k as f64 * 0.37).sin()).collect();
    let e = welch_frf(1000.0, &x, &y, &o).unwrap();
    assert!(e.h1.iter().all(|h| h.re.is_finite() && h.im.is_finite()));
}
