//! Special functions needed by the identification code: the digamma
//! function `ψ(x) = d ln Γ(x) / dx` (for the exponent derivative of the
//! shape factor, `g'(μ) = g(μ) (ψ((3+μ)/2) − ψ(2+μ/2)) / 2`).

/// Digamma `ψ(x)` for `x > 0` (NaN otherwise).
///
/// Upward recurrence `ψ(x) = ψ(x+1) − 1/x` until `x ≥ 10`, then the
/// asymptotic series
/// `ψ(x) ~ ln x − 1/(2x) − Σ B_{2k} / (2k x^{2k})`
/// (`B₂ = 1/6, B₄ = −1/30, B₆ = 1/42, B₈ = −1/30, B₁₀ = 5/66, B₁₂ = −691/2730`),
/// truncation error below 1e-17 at `x = 10`.
pub fn digamma(x: f64) -> f64 {
    if !(x > 0.0) || !x.is_finite() {
        return f64::NAN;
    }
    let mut acc = 0.0;
    let mut x = x;
    while x < 10.0 {
        acc -= 1.0 / x;
        x += 1.0;
    }
    let r = 1.0 / (x * x);
    // − Σ B_{2k}/(2k) r^k
    let series = r
        * (1.0 / 12.0
            - r * (1.0 / 120.0
                - r * (1.0 / 252.0
                    - r * (1.0 / 240.0 - r * (1.0 / 132.0 - r * (691.0 / 32760.0))))));
    acc + x.ln() - 0.5 / x - series
}

/// Derivative of the shape factor `g(μ)` (Eq 12) with respect to `μ`:
/// `g'(μ) = g(μ) (ψ((3+μ)/2) − ψ(2+μ/2)) / 2`, `μ > −3`.
pub fn g_derivative(mu: f64) -> f64 {
    crate::power_law::g_unchecked(mu) * 0.5 * (digamma(0.5 * (3.0 + mu)) - digamma(2.0 + 0.5 * mu))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let euler = 0.577_215_664_901_532_9;
        assert!((digamma(1.0) + euler).abs() < 4e-15);
        assert!((digamma(0.5) - (-euler - 2.0 * std::f64::consts::LN_2)).abs() < 1e-14);
        // ψ(n+1) = H_n − γ
        let h10: f64 = (1..=10).map(|k| 1.0 / k as f64).sum();
        assert!((digamma(11.0) - (h10 - euler)).abs() < 1e-14);
        assert!(digamma(0.0).is_nan() && digamma(-1.0).is_nan());
    }

    #[test]
    fn matches_finite_differences_of_lgamma() {
        for k in 0..60 {
            let x = 0.05 + 0.37 * k as f64;
            let h = 1e-5 * (1.0 + x);
            let fd = (libm::lgamma(x + h) - libm::lgamma(x - h)) / (2.0 * h);
            let d = digamma(x);
            assert!(
                (fd - d).abs() < 1e-7 * (1.0 + d.abs()),
                "x={x}: {d} vs fd {fd}"
            );
        }
    }

    #[test]
    fn g_derivative_matches_finite_differences() {
        for k in 0..50 {
            let mu = -2.8 + 0.25 * k as f64;
            let h = 1e-6;
            let fd = (crate::power_law::g_unchecked(mu + h)
                - crate::power_law::g_unchecked(mu - h))
                / (2.0 * h);
            let d = g_derivative(mu);
            assert!(
                (fd - d).abs() < 1e-7 * (1.0 + d.abs()),
                "mu={mu}: {d} vs fd {fd}"
            );
        }
    }
}
