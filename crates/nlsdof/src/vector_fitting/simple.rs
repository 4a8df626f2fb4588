//! Classical single-mode methods, for comparison with vector fitting.
//!
//! * [`half_power`] — needs only the magnitude. For a **mobility**
//!   (velocity/force) of a viscous SDoF, `|Y|² = 1/(c² + (mω − k/ω)²)`
//!   falls to half its peak exactly where `|mω − k/ω| = c`, whose positive
//!   roots satisfy `ω₂ − ω₁ = c/m = 2ζω_n` and `ω₁ω₂ = ω_n²`, so
//!   `ζ = (ω₂ − ω₁)/(2ω_n)` is exact. For a receptance or accelerance it is
//!   the usual approximation (error O(ζ²)). `ω₁, ω₂` are found by linear
//!   interpolation of `|H|` between samples; `ω_n = √(ω₁ω₂)`.
//! * [`circle_fit`] — Nyquist circle (Ewins 2000, §4.3) of a **mobility**
//!   `Y = 1/(c + jX)`, `X = mω − k/ω`: an exact circle of diameter `1/c`
//!   through the origin. The centre and radius come from the algebraic
//!   (Kåsa) least-squares fit `x² + y² + D x + E y + F = 0` of the points
//!   inside the half-power band. The resonance is the point diametrically
//!   opposite the origin (`X = 0`); by the inscribed-angle theorem a point at
//!   `ω` is seen from the centre at `θ` with `tan(θ/2) = |X|/c`, which gives
//!   for each pair `ω_b < ω_n < ω_a`
//!
//!   ```text
//!   ζ = (ω_a² − ω_b²) / (2ω_n (ω_a tan(θ_a/2) + ω_b tan(θ_b/2)))
//!   ```
//!
//!   (averaged over all pairs). The modal constant `1/c` is the diameter
//!   (`2R`): for a force input `c = 1/(2R)` and `m = c/(2ζω_n)`.

use super::{validate_frf, VectorFitError, C64};
use nalgebra::{DMatrix, DVector};

/// Result of [`half_power`] (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPower {
    /// Frequency of the largest sample.
    pub omega_peak: f64,
    pub peak: f64,
    /// Lower and upper half-power frequencies `|H| = peak/√2`.
    pub omega_low: f64,
    pub omega_high: f64,
    /// `√(ω₁ω₂)`.
    pub omega_n: f64,
    pub zeta: f64,
}

fn check_mag(omega: &[f64], mag: &[f64]) -> Result<(), VectorFitError> {
    let h: Vec<C64> = mag.iter().map(|&m| C64::new(m, 0.0)).collect();
    validate_frf(omega, &h)
}

/// Half-power bandwidth of the largest peak of `mag = |H(ω)|`.
pub fn half_power(omega: &[f64], mag: &[f64]) -> Result<HalfPower, VectorFitError> {
    check_mag(omega, mag)?;
    if omega.len() < 3 {
        return Err(VectorFitError::TooFewPoints {
            points: omega.len(),
            equations: omega.len(),
            unknowns: 3,
        });
    }
    let (ip, &peak) = mag
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.partial_cmp(b.1).unwrap())
        .unwrap();
    let level = peak / std::f64::consts::SQRT_2;
    let cross = |i: usize, j: usize| {
        // Linear interpolation of the level crossing between samples i and j.
        let t = (level - mag[i]) / (mag[j] - mag[i]);
        omega[i] + t * (omega[j] - omega[i])
    };
    let mut lo = None;
    for i in (0..ip).rev() {
        if mag[i] <= level {
            lo = Some(cross(i, i + 1));
            break;
        }
    }
    let mut hi = None;
    for i in ip + 1..mag.len() {
        if mag[i] <= level {
            hi = Some(cross(i - 1, i));
            break;
        }
    }
    let (Some(w1), Some(w2)) = (lo, hi) else {
        return Err(VectorFitError::BadOption {
            name: "frequency band",
            value: format!("[{}, {}] rad/s", omega[0], omega[omega.len() - 1]),
            reason: "does not contain both half-power points of the peak",
        });
    };
    let wn = (w1 * w2).sqrt();
    Ok(HalfPower {
        omega_peak: omega[ip],
        peak,
        omega_low: w1,
        omega_high: w2,
        omega_n: wn,
        zeta: (w2 - w1) / (2.0 * wn),
    })
}

/// Result of [`circle_fit`] (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircleFit {
    pub center: C64,
    pub radius: f64,
    pub omega_n: f64,
    pub zeta: f64,
    /// Points used (inside the half-power band).
    pub points: usize,
    /// RMS distance of the used points from the circle, relative to the radius.
    pub relative_residual: f64,
}

/// Circle fit of the dominant mode of a **mobility** FRF (see module docs).
pub fn circle_fit(omega: &[f64], mobility: &[C64]) -> Result<CircleFit, VectorFitError> {
    validate_frf(omega, mobility)?;
    let mag: Vec<f64> = mobility.iter().map(|z| z.norm()).collect();
    let hp = half_power(omega, &mag)?;
    let idx: Vec<usize> = (0..omega.len())
        .filter(|&i| omega[i] >= hp.omega_low && omega[i] <= hp.omega_high)
        .collect();
    if idx.len() < 5 {
        return Err(VectorFitError::TooFewPoints {
            points: idx.len(),
            equations: idx.len(),
            unknowns: 5,
        });
    }
    let mut a = DMatrix::<f64>::zeros(idx.len(), 3);
    let mut b = DVector::<f64>::zeros(idx.len());
    for (r, &i) in idx.iter().enumerate() {
        let z = mobility[i];
        a[(r, 0)] = z.re;
        a[(r, 1)] = z.im;
        a[(r, 2)] = 1.0;
        b[r] = -(z.re * z.re + z.im * z.im);
    }
    let qr = a.qr();
    let mut qtb = b.clone();
    qr.q_tr_mul(&mut qtb);
    let r = qr.r();
    let sol = r
        .solve_upper_triangular(&qtb.rows(0, 3).into_owned())
        .ok_or(VectorFitError::Singular {
            iteration: 0,
            what: "circle fit",
        })?;
    let center = C64::new(-sol[0] / 2.0, -sol[1] / 2.0);
    let radius = (center.norm_sqr() - sol[2]).max(0.0).sqrt();
    let resid = (idx
        .iter()
        .map(|&i| ((mobility[i] - center).norm() - radius).powi(2))
        .sum::<f64>()
        / idx.len() as f64)
        .sqrt();
    // Resonance: direction from the centre away from the origin.
    let dir = (-center).arg() + std::f64::consts::PI;
    let ang = |i: usize| {
        let mut t = (mobility[i] - center).arg() - dir;
        while t > std::f64::consts::PI {
            t -= 2.0 * std::f64::consts::PI;
        }
        while t <= -std::f64::consts::PI {
            t += 2.0 * std::f64::consts::PI;
        }
        t
    };
    // The angle decreases (clockwise) with frequency for a mobility; find the zero crossing.
    let th: Vec<f64> = idx.iter().map(|&i| ang(i)).collect();
    let mut wn = None;
    for j in 1..th.len() {
        if (th[j - 1] >= 0.0) != (th[j] >= 0.0) {
            let t = th[j - 1] / (th[j - 1] - th[j]);
            wn = Some(omega[idx[j - 1]] + t * (omega[idx[j]] - omega[idx[j - 1]]));
            break;
        }
    }
    let wn = wn.ok_or(VectorFitError::BadOption {
        name: "circle fit",
        value: format!("{} points", idx.len()),
        reason: "the resonance point is not inside the half-power band",
    })?;
    let mut sum = 0.0;
    let mut count = 0usize;
    for (ja, &ia) in idx.iter().enumerate() {
        if omega[ia] <= wn {
            continue;
        }
        for (jb, &ib) in idx.iter().enumerate() {
            if omega[ib] >= wn {
                continue;
            }
            let (wa, wb) = (omega[ia], omega[ib]);
            let (ta, tb) = ((th[ja].abs() / 2.0).tan(), (th[jb].abs() / 2.0).tan());
            let den = 2.0 * wn * (wa * ta + wb * tb);
            if den > 0.0 {
                sum += (wa * wa - wb * wb) / den;
                count += 1;
            }
        }
    }
    if count == 0 {
        return Err(VectorFitError::TooFewPoints {
            points: idx.len(),
            equations: 0,
            unknowns: 2,
        });
    }
    Ok(CircleFit {
        center,
        radius,
        omega_n: wn,
        zeta: sum / count as f64,
        points: idx.len(),
        relative_residual: resid / radius,
    })
}
