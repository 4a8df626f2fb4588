//! The fixtures shared by the tests and the benches: the paper's wing and
//! one seeded random generator.

use nlsdof::harmonic_balance::{ForcedResponse, Formulation, SweepDirection};
use nlsdof::identification::{Dataset, Parameters, Record};
use nlsdof::{Model, NormalisedModel};

/// The paper's wing, unloaded: Table 3 (m, k, c) with Table 7's
/// pre-estimated nonlinear terms (k_r = 85000 N/m^5.0022, ρ = 4.0022;
/// c_e = 0.01591, η = 3.03099).
pub fn wing() -> Model {
    wing_with_exponents(4.00220, 3.03099)
}

/// [`wing`] with other exponents (e.g. the integer pair 4, 3 of Table 6).
pub fn wing_with_exponents(rho: f64, eta: f64) -> Model {
    Model::linear(0.26699, 306.7878, 0.1164)
        .unwrap()
        .with_stiffness(85000.0, rho)
        .unwrap()
        .with_damping(0.01591, eta)
        .unwrap()
}

/// [`wing`], mass-normalised.
pub fn wing_normalised() -> NormalisedModel {
    wing().normalised().unwrap()
}

/// Noise-free stepped-sine data of θ: the exact first-order harmonic-balance
/// sweeps (branch following, jumps included) at each level `gammas`
/// (m/s², the model sees `gain · γ`), `steps` frequencies evenly from `f.0`
/// to `f.1` Hz, in each direction of `dirs`; phases written as
/// `ψ = sign·φ + offset` for `phase = Some((sign, offset))`, none for `None`.
pub fn hb_sweeps(
    theta: &Parameters,
    gammas: &[f64],
    f: (f64, f64),
    steps: usize,
    dirs: &[SweepDirection],
    phase: Option<(f64, f64)>,
) -> Dataset {
    let two_pi = 2.0 * std::f64::consts::PI;
    let model = theta.normalised_model();
    let omegas: Vec<f64> = (0..steps)
        .map(|i| two_pi * (f.0 + (f.1 - f.0) * i as f64 / (steps - 1) as f64))
        .collect();
    let mut recs = Vec::new();
    for (l, &g) in gammas.iter().enumerate() {
        let r =
            ForcedResponse::from_normalised(&model, theta.gain * g, Formulation::HarmonicBalance)
                .unwrap();
        for &d in dirs {
            let sw = r.sweep(&omegas, d).unwrap();
            for p in &sw.points {
                recs.push(Record {
                    level: format!("L{l}"),
                    gamma: g,
                    omega: p.omega,
                    amplitude: p.amplitude,
                    phase: phase.map(|(s, c)| s * p.phase + c),
                    direction: d,
                    weight: 1.0,
                });
            }
        }
    }
    Dataset::from_records(&recs).unwrap()
}

/// SplitMix64 (Steele, Lea & Flood 2014): the one seeded generator of the
/// tests, with uniform and standard normal deviates. Written here so the
/// tests need no random-number crate; the sequence of a seed never changes.
/// The Silverbox record SNLS80mV (u, y in volts) from `SILVERBOX_DIR` or
/// `../shared/data/silverbox` beside the repository; panics when absent
/// (the tests that read it are ignored by default).
pub fn silverbox_record() -> (Vec<f64>, Vec<f64>) {
    let dir = std::env::var_os("SILVERBOX_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/data/silverbox")
        });
    let text = std::fs::read_to_string(dir.join("SNLS80mV.csv")).expect("Silverbox data");
    let (mut u, mut y) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1).filter(|l| !l.trim().is_empty()) {
        let mut f = line.split(',');
        u.push(f.next().unwrap().trim().parse::<f64>().unwrap());
        y.push(f.next().unwrap().trim().parse::<f64>().unwrap());
    }
    (u, y)
}

/// A random-phase multisine sampled at `fs` Hz: 30 lines at 0.5, 1, …,
/// 15 Hz, RMS about 1 (seeded); the input of the time-domain tests.
pub fn multisine(n: usize, fs: f64, seed: u64) -> Vec<f64> {
    let mut rng = Rng(seed);
    let lines: Vec<(f64, f64)> = (1..=30)
        .map(|k| (0.5 * k as f64, 2.0 * std::f64::consts::PI * rng.uniform()))
        .collect();
    let amp = (2.0 / lines.len() as f64).sqrt();
    (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            lines
                .iter()
                .map(|(f, p)| amp * (2.0 * std::f64::consts::PI * f * t + p).sin())
                .sum()
        })
        .collect()
}

#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [a, b).
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }

    /// Standard normal deviate (Box–Muller, cosine branch; `u₁` kept
    /// away from 0).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform().max(1e-300);
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[test]
fn rng_is_uniform_and_normal() {
    let mut a = Rng(7);
    let u: Vec<f64> = (0..100_000).map(|_| a.uniform()).collect();
    assert!(u.iter().all(|&v| (0.0..1.0).contains(&v)));
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    assert!(
        (mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / u.len() as f64).sqrt(),
        "{mean}"
    );
    let n = 200_000;
    let mut r = Rng(1);
    let x: Vec<f64> = (0..n).map(|_| r.normal()).collect();
    let mean = x.iter().sum::<f64>() / n as f64;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
    // 5 standard errors
    assert!(mean.abs() < 5.0 / (n as f64).sqrt(), "{mean}");
    assert!((var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(), "{var}");
}

/// Checks the analytic Jacobian of `p` at `u` against central differences
/// (step `1e-6 (1 + |u_k|)`): every entry within `1e-5` of its column's norm.
pub fn assert_jacobian_matches_fd(
    p: &impl nlsdof::identification::levenberg_marquardt::LeastSquares,
    u: &[f64],
) {
    let (r, j) = p.residuals_and_jacobian(u).unwrap();
    let n = u.len();
    for k in 0..n {
        let h = 1e-6 * (1.0 + u[k].abs());
        let (mut up, mut um) = (u.to_vec(), u.to_vec());
        up[k] += h;
        um[k] -= h;
        let (rp, rm) = (p.residuals(&up).unwrap(), p.residuals(&um).unwrap());
        let colnorm: f64 = (0..r.len())
            .map(|i| j[i * n + k].powi(2))
            .sum::<f64>()
            .sqrt();
        for i in 0..r.len() {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            assert!(
                (fd - j[i * n + k]).abs() <= 1e-5 * colnorm,
                "u[{k}] residual {i}: analytic {} vs fd {fd}",
                j[i * n + k]
            );
        }
    }
}
