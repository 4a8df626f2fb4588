//! Linearised uncertainty at the optimum, with `J = ∂r/∂θ` over the free
//! natural parameters:
//!
//! * [`uncertainty`]: `cov = s² (JᵀJ)⁻¹`, `s² = cost / (n − p)` — every
//!   residual assumed to have the same variance;
//! * [`uncertainty_with_noise`]: the sandwich `cov = (JᵀJ)⁻¹ (Σ vᵢ JᵢᵀJᵢ)
//!   (JᵀJ)⁻¹` with a variance `vᵢ` per residual (the least-squares
//!   estimate's covariance when the noise is not of one size). Stepped-sine
//!   amplitudes carry noise that grows with the amplitude, and Eq 31 weighs
//!   every point alike: the first form then reads the large residuals of
//!   the peak as the noise of every point, and its exponent intervals
//!   missed the truth in about a fifth of random in-family sets
//!   (docs/identification.md).

use super::levenberg_marquardt::{cholesky_solve, normal_equations};
use super::models::{N_PARAMS, PARAM_NAMES};
use super::parameters::Parameters;

/// Standard errors, 95 % intervals and correlations of the free parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Uncertainty {
    /// Names of the free parameters, in θ order.
    #[serde(deserialize_with = "crate::interned::names")]
    pub names: Vec<&'static str>,
    pub values: Vec<f64>,
    pub std_errors: Vec<f64>,
    /// `value ± t₀.₉₇₅(dof) · std_error` (Student t quantile).
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Correlation matrix (row-major, p × p).
    pub correlation: Vec<Vec<f64>>,
    /// Residual variance s².
    pub s2: f64,
    pub dof: usize,
}

impl Uncertainty {
    /// Position of parameter `name` (e.g. `"rho"`) among the free
    /// parameters, `None` when it is not free.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| *n == name)
    }
}

/// z-value of a two-sided 95 % normal interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Two-sided 95 % Student-t quantile `t₀.₉₇₅(ν)` by the Cornish–Fisher
/// expansion about the normal quantile (error < 3e-3 for ν ≥ 5, < 2e-4 for ν ≥ 10).
pub fn t95(dof: usize) -> f64 {
    let z = Z95;
    let v = dof.max(1) as f64;
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * v)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v * v * v)
}

/// `None` if `JᵀJ` is singular (a parameter is not identifiable from the
/// data, e.g. ρ → 0 makes β a copy of α) or there are no residual degrees of freedom.
pub fn uncertainty(
    theta: &Parameters,
    free: &[usize],
    jacobian: &[[f64; N_PARAMS]],
    residuals: &[f64],
) -> Option<Uncertainty> {
    let p = free.len();
    let n = residuals.len();
    if n <= p {
        return None;
    }
    let j = free_columns(free, jacobian);
    let inv = normal_inverse(&j, residuals, p)?;
    let cost: f64 = residuals.iter().map(|r| r * r).sum();
    let dof = n - p;
    let s2 = cost / dof as f64;
    let cov: Vec<f64> = inv.iter().map(|x| s2 * x).collect();
    Some(summarise(theta, free, &cov, s2, dof))
}

/// The sandwich covariance with a variance per residual: `vᵢ = k σᵢ²`, the
/// shape `σᵢ` given (e.g. the noise model of [`super::noise`], in the
/// residuals' units), the scale `k` from the residuals,
/// `k = (Σ rᵢ²/(n − p)) / (Σ σᵢ²/n)`, so that a misfit above the noise
/// widens the intervals as in [`uncertainty`], to which this reduces when
/// every `σᵢ` is the same. Falls back to [`uncertainty`] when a `σᵢ` is not
/// positive and finite or the lengths differ.
pub fn uncertainty_with_noise(
    theta: &Parameters,
    free: &[usize],
    jacobian: &[[f64; N_PARAMS]],
    residuals: &[f64],
    sigma: &[f64],
) -> Option<Uncertainty> {
    let p = free.len();
    let n = residuals.len();
    if n <= p {
        return None;
    }
    if sigma.len() != n || sigma.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
        return uncertainty(theta, free, jacobian, residuals);
    }
    let j = free_columns(free, jacobian);
    let inv = normal_inverse(&j, residuals, p)?;
    let cost: f64 = residuals.iter().map(|r| r * r).sum();
    let dof = n - p;
    let s2 = cost / dof as f64;
    let mean_v = sigma.iter().map(|s| s * s).sum::<f64>() / n as f64;
    let k = s2 / mean_v;
    // B = Σ vᵢ JᵢᵀJᵢ
    let mut b = vec![0.0; p * p];
    for (row, &sg) in j.chunks_exact(p).zip(sigma) {
        let v = k * sg * sg;
        for r in 0..p {
            let x = v * row[r];
            for c in 0..=r {
                b[r * p + c] += x * row[c];
            }
        }
    }
    for r in 0..p {
        for c in 0..r {
            b[c * p + r] = b[r * p + c];
        }
    }
    // cov = A⁻¹ B A⁻¹
    let mut tmp = vec![0.0; p * p];
    for r in 0..p {
        for c in 0..p {
            tmp[r * p + c] = (0..p).map(|m| inv[r * p + m] * b[m * p + c]).sum();
        }
    }
    let mut cov = vec![0.0; p * p];
    for r in 0..p {
        for c in 0..p {
            cov[r * p + c] = (0..p).map(|m| tmp[r * p + m] * inv[m * p + c]).sum();
        }
    }
    if cov.iter().any(|x| !x.is_finite()) {
        return uncertainty(theta, free, jacobian, residuals);
    }
    Some(summarise(theta, free, &cov, s2, dof))
}

/// The Jacobian's free columns, row-major (n × p).
fn free_columns(free: &[usize], jacobian: &[[f64; N_PARAMS]]) -> Vec<f64> {
    jacobian
        .iter()
        .flat_map(|row| free.iter().map(move |&k| row[k]))
        .collect()
}

/// `(JᵀJ)⁻¹` (p × p), `None` when singular. Scaled to unit diagonal for a
/// well-conditioned inverse.
fn normal_inverse(j: &[f64], residuals: &[f64], p: usize) -> Option<Vec<f64>> {
    let (a, _) = normal_equations(j, residuals, p);
    let d: Vec<f64> = (0..p).map(|k| a[k * p + k].sqrt()).collect();
    if d.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
        return None;
    }
    let scaled: Vec<f64> = (0..p * p).map(|i| a[i] / (d[i / p] * d[i % p])).collect();
    let mut inv = vec![0.0; p * p];
    for c in 0..p {
        let mut e = vec![0.0; p];
        e[c] = 1.0;
        let col = cholesky_solve(&scaled, &e, p)?;
        for r in 0..p {
            inv[r * p + c] = col[r] / (d[r] * d[c]);
        }
    }
    Some(inv)
}

/// Standard errors, Student-t intervals and correlations of a covariance.
fn summarise(theta: &Parameters, free: &[usize], cov: &[f64], s2: f64, dof: usize) -> Uncertainty {
    let p = free.len();
    let se: Vec<f64> = (0..p).map(|k| cov[k * p + k].max(0.0).sqrt()).collect();
    let values: Vec<f64> = free.iter().map(|&k| theta[k]).collect();
    let t = t95(dof);
    let correlation = (0..p)
        .map(|r| {
            (0..p)
                .map(|c| cov[r * p + c] / (cov[r * p + r] * cov[c * p + c]).sqrt())
                .collect()
        })
        .collect();
    Uncertainty {
        names: free.iter().map(|&k| PARAM_NAMES[k]).collect(),
        lower: values.iter().zip(&se).map(|(v, s)| v - t * s).collect(),
        upper: values.iter().zip(&se).map(|(v, s)| v + t * s).collect(),
        values,
        std_errors: se,
        correlation,
        s2,
        dof,
    }
}

/// Names of the free parameters that the data cannot separate: the main
/// components (> 0.2 of the largest) of every eigenvector of the
/// column-scaled `JᵀJ` whose eigenvalue is below `1e-12` of the largest
/// (condition number above 1e12), or whose Jacobian column is zero.
/// Empty when `J` has full numerical rank.
pub fn null_directions(free: &[usize], jacobian: &[[f64; N_PARAMS]]) -> Vec<&'static str> {
    let p = free.len();
    let j: Vec<f64> = jacobian
        .iter()
        .flat_map(|row| free.iter().map(move |&k| row[k]))
        .collect();
    let zero = vec![0.0; jacobian.len()];
    let (a, _) = normal_equations(&j, &zero, p);
    let d: Vec<f64> = (0..p).map(|k| a[k * p + k].sqrt()).collect();
    let mut names: Vec<&'static str> = (0..p)
        .filter(|&k| !(d[k] > 0.0 && d[k].is_finite()))
        .map(|k| PARAM_NAMES[free[k]])
        .collect();
    if !names.is_empty() {
        return names;
    }
    let m = nalgebra::DMatrix::from_fn(p, p, |r, c| a[r * p + c] / (d[r] * d[c]));
    let eig = m.symmetric_eigen();
    let emax = eig.eigenvalues.iter().fold(0.0f64, |s, &e| s.max(e));
    for (i, &e) in eig.eigenvalues.iter().enumerate() {
        if e < 1e-12 * emax {
            let v = eig.eigenvectors.column(i);
            let vmax = v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
            for k in 0..p {
                if v[k].abs() > 0.2 * vmax && !names.contains(&PARAM_NAMES[free[k]]) {
                    names.push(PARAM_NAMES[free[k]]);
                }
            }
        }
    }
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Straight line `y = a + b x` as the Jacobian of θ = (α, δ) = (a, b).
    fn line(x: &[f64]) -> Vec<[f64; N_PARAMS]> {
        x.iter()
            .map(|&xi| {
                let mut row = [0.0; N_PARAMS];
                row[0] = 1.0;
                row[1] = xi;
                row
            })
            .collect()
    }

    /// With one noise size the sandwich is `s² (JᵀJ)⁻¹` (linear limit).
    #[test]
    fn equal_noise_reduces_to_the_plain_covariance() {
        let x: Vec<f64> = (0..40).map(|i| 1.0 + 0.25 * i as f64).collect();
        let jac = line(&x);
        let r: Vec<f64> = (0..40)
            .map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)
            .collect();
        let theta = Parameters::from([1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0]);
        let plain = uncertainty(&theta, &[0, 1], &jac, &r).unwrap();
        let sandwich = uncertainty_with_noise(&theta, &[0, 1], &jac, &r, &[0.3; 40]).unwrap();
        for k in 0..2 {
            let e = (sandwich.std_errors[k] / plain.std_errors[k] - 1.0).abs();
            assert!(e < 1e-12, "{k}: {e}");
        }
        assert!((sandwich.correlation[0][1] - plain.correlation[0][1]).abs() < 1e-12);
    }

    /// Noise proportional to x (as stepped-sine amplitude noise grows with
    /// the amplitude): over 4000 least-squares fits of a line, the spread
    /// of the slope is what the sandwich says (mean of its standard errors
    /// within 4 %), and the plain covariance is off by more than 10 % (a
    /// naive Monte-Carlo reference).
    #[test]
    fn sandwich_matches_the_spread_of_least_squares_under_unequal_noise() {
        let n = 60;
        let x: Vec<f64> = (0..n)
            .map(|i| 1.0 + 9.0 * i as f64 / (n - 1) as f64)
            .collect();
        let sigma: Vec<f64> = x.iter().map(|&xi| 0.01 * xi * xi).collect();
        let jac = line(&x);
        // least squares of a line in closed form
        let (sx, sxx) = (x.iter().sum::<f64>(), x.iter().map(|v| v * v).sum::<f64>());
        let nf = n as f64;
        let mut state = 12345u64;
        let mut normal = || {
            // Box–Muller on a 64-bit LCG
            let mut u = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
            };
            let (u1, u2) = (u(), u());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        };
        let (mut slopes, mut se_sandwich, mut se_plain) = (Vec::new(), 0.0, 0.0);
        let reps = 4000;
        for _ in 0..reps {
            let y: Vec<f64> = x
                .iter()
                .zip(&sigma)
                .map(|(&xi, &s)| 1.0 + 2.0 * xi + s * normal())
                .collect();
            let (sy, sxy) = (
                y.iter().sum::<f64>(),
                x.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>(),
            );
            let b = (nf * sxy - sx * sy) / (nf * sxx - sx * sx);
            let a = (sy - b * sx) / nf;
            let r: Vec<f64> = x.iter().zip(&y).map(|(&xi, &yi)| a + b * xi - yi).collect();
            let theta = Parameters::from([a, b, 0.0, 0.0, 0.0, 0.0, 1.0]);
            se_sandwich += uncertainty_with_noise(&theta, &[0, 1], &jac, &r, &sigma)
                .unwrap()
                .std_errors[1];
            se_plain += uncertainty(&theta, &[0, 1], &jac, &r).unwrap().std_errors[1];
            slopes.push(b);
        }
        let mean = slopes.iter().sum::<f64>() / reps as f64;
        let sd =
            (slopes.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (reps - 1) as f64).sqrt();
        let (se_sandwich, se_plain) = (se_sandwich / reps as f64, se_plain / reps as f64);
        println!("slope spread {sd:.4e}; mean standard error: sandwich {se_sandwich:.4e}, plain {se_plain:.4e}");
        assert!(
            (se_sandwich / sd - 1.0).abs() < 0.04,
            "sandwich {se_sandwich} vs spread {sd}"
        );
        assert!(
            (se_plain / sd - 1.0).abs() > 0.10,
            "plain {se_plain} vs spread {sd}"
        );
    }

    #[test]
    fn t_quantiles() {
        // tabulated t_0.975: ν = 5: 2.5706, 10: 2.2281, 30: 2.0423, 120: 1.9799
        for (v, t) in [(5, 2.5706), (10, 2.2281), (30, 2.0423), (120, 1.9799)] {
            assert!(
                (super::t95(v) - t).abs() < if v == 5 { 3e-3 } else { 2e-4 },
                "{v}: {}",
                super::t95(v)
            );
        }
    }
}
