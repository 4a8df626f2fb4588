//! Linearised uncertainty at the optimum: `cov = s² (JᵀJ)⁻¹`,
//! `s² = cost / (n − p)`, with `J = ∂r/∂θ` over the free natural parameters.

use super::levenberg_marquardt::{cholesky_solve, normal_equations};
use super::models::{N_PARAMS, PARAM_NAMES};
use super::parameters::Parameters;

/// Standard errors, 95 % intervals and correlations of the free parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Uncertainty {
    /// Names of the free parameters, in θ order.
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
    let j: Vec<f64> = jacobian
        .iter()
        .flat_map(|row| free.iter().map(move |&k| row[k]))
        .collect();
    let (a, _) = normal_equations(&j, residuals, p);
    // scale to unit diagonal for a well-conditioned inverse
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
    let cost: f64 = residuals.iter().map(|r| r * r).sum();
    let dof = n - p;
    let s2 = cost / dof as f64;
    let se: Vec<f64> = (0..p)
        .map(|k| (s2 * inv[k * p + k]).max(0.0).sqrt())
        .collect();
    let values: Vec<f64> = free.iter().map(|&k| theta[k]).collect();
    let t = t95(dof);
    let correlation = (0..p)
        .map(|r| {
            (0..p)
                .map(|c| inv[r * p + c] / (inv[r * p + r] * inv[c * p + c]).sqrt())
                .collect()
        })
        .collect();
    Some(Uncertainty {
        names: free.iter().map(|&k| PARAM_NAMES[k]).collect(),
        lower: values.iter().zip(&se).map(|(v, s)| v - t * s).collect(),
        upper: values.iter().zip(&se).map(|(v, s)| v + t * s).collect(),
        values,
        std_errors: se,
        correlation,
        s2,
        dof,
    })
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
