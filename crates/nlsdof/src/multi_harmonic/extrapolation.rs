//! Richardson extrapolation in the number of harmonics, for forces that
//! are not smooth (Coulomb friction).
//!
//! With smooth power laws the harmonic balance converges geometrically in
//! `H` ([`super::truncation`]). With Coulomb friction (`η = −1`) the
//! friction force jumps where the velocity changes sign, and the balance
//! converges only like `1/n`: the truncated velocity places the reversals
//! wrong by about the tail of its own series (coefficients `∝ 1/k²` for a
//! velocity with kinks, tail `∝ 1/n`), and the first harmonic of the force
//! moves with the reversals. Regularising the sign does not help (the error
//! does not depend on the width ε once ε is small). Measured on
//! `examples/coulomb.toml` at `0.8 f_n`, `γ = 10` (sliding throughout),
//! against the periodic orbit of a Dormand–Prince shooting at rtol 1e-12:
//! first-harmonic errors 7.43e-4, 3.86e-4, 1.93e-4 at `H = 25, 50, 100`.
//!
//! `n` is the number of harmonics that carry the response: all `H`, or
//! only the odd ones, `⌈H/2⌉`, when the response has half-wave symmetry
//! (odd forces, no constant or even harmonic; [`effective_harmonics`]). The
//! errors above fall by 1.92 and 1.99 per doubling of `H`, the ratios of
//! 13, 25 and 50 odd harmonics, not 2.
//!
//! If a quantity behaves as `Q(n) = Q∞ + c/n + O(n⁻²)`, two balances give
//!
//! ```text
//! Q∞ = (n₂ Q(n₂) − n₁ Q(n₁)) / (n₂ − n₁) + O(n⁻²)
//! ```
//!
//! ([`richardson`]). On the case above the extrapolated first harmonic
//! matches the periodic orbit to about 1e-8 from `H = 50, 100` (tests in
//! `tests/multi_harmonic.rs`). For smooth forces extrapolation is neither
//! needed nor right (their error is not `∝ 1/n`).

use super::system::{HarmonicSettings, HbSystem};
use super::{harmonic_amplitude, solve_at, MhbError, StartRoot};
use crate::model::NormalisedModel;

/// Richardson extrapolation of `Q(n) = Q∞ + c/n + O(n⁻²)` from two values
/// (module docs): `(n₂ q₂ − n₁ q₁)/(n₂ − n₁)`.
///
/// ```
/// use nlsdof::multi_harmonic::extrapolation::richardson;
/// // Q(n) = 2 + 3/n exactly
/// let q = |n: usize| 2.0 + 3.0 / n as f64;
/// assert!((richardson(10, q(10), 20, q(20)).unwrap() - 2.0).abs() < 1e-14);
/// ```
pub fn richardson(n1: usize, q1: f64, n2: usize, q2: f64) -> Result<f64, MhbError> {
    for (name, n) in [("n1", n1), ("n2", n2)] {
        if n == 0 {
            return Err(MhbError::InvalidValue {
                name,
                value: n as f64,
            });
        }
    }
    if n1 == n2 {
        return Err(MhbError::InvalidValue {
            name: "n2 (must differ from n1)",
            value: n2 as f64,
        });
    }
    for (name, q) in [("q1", q1), ("q2", q2)] {
        if !q.is_finite() {
            return Err(MhbError::InvalidValue { name, value: q });
        }
    }
    let (n1, n2) = (n1 as f64, n2 as f64);
    Ok((n2 * q2 - n1 * q1) / (n2 - n1))
}

/// Number of harmonics that carry the solution `q` of `h` harmonics
/// (`[a₀, a₁, b₁, a₂, b₂, …]`): `⌈h/2⌉` (the odd ones) when the constant
/// and every even harmonic are at most `1e-9` of the first harmonic
/// (half-wave symmetry), else `h`.
pub fn effective_harmonics(q: &[f64], h: usize) -> usize {
    let a1 = harmonic_amplitude(q, 1);
    let even_small = q[0].abs() <= 1e-9 * a1
        && (2..=h)
            .step_by(2)
            .all(|k| harmonic_amplitude(q, k) <= 1e-9 * a1);
    if even_small {
        h.div_ceil(2)
    } else {
        h
    }
}

/// First-harmonic amplitude extrapolated from `H` and `2H` harmonics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtrapolatedAmplitude {
    /// Extrapolated first-harmonic amplitude (m).
    pub amplitude: f64,
    /// `(H, n, a₁)` of the coarse balance (`n` effective harmonics).
    pub coarse: (usize, usize, f64),
    /// `(2H, n, a₁)` of the fine balance.
    pub fine: (usize, usize, f64),
    /// `|amplitude − a₁(2H)| / amplitude`: the correction the
    /// extrapolation made (an upper estimate of the fine balance's error,
    /// not of the extrapolated one's).
    pub correction: f64,
}

/// Solves the balance with `h` and `2h` harmonics at `omega` (each from the
/// first-order root `start`, [`solve_at`]) and extrapolates the first
/// harmonic with [`richardson`] in the effective harmonic counts. Errors:
/// those of [`HbSystem::new`] (e.g. `2h` above
/// [`super::MAX_HARMONICS`]) and of the solves, and
/// [`MhbError::InvalidValue`] if the two balances do not agree on the
/// symmetry of the response.
pub fn first_harmonic_extrapolated(
    model: &NormalisedModel,
    gamma: f64,
    omega: f64,
    h: usize,
    settings: HarmonicSettings,
    start: StartRoot,
) -> Result<ExtrapolatedAmplitude, MhbError> {
    let solve = |h: usize| -> Result<(usize, usize, f64), MhbError> {
        let mut sys = HbSystem::new(model, gamma, h, settings)?;
        let q = solve_at(&mut sys, omega, start)?.coefficients;
        Ok((h, effective_harmonics(&q, h), harmonic_amplitude(&q, 1)))
    };
    let coarse = solve(h)?;
    let fine = solve(2 * h)?;
    let odd = |(h, n, _): (usize, usize, f64)| n != h || h == 1;
    if odd(coarse) != odd(fine) {
        return Err(MhbError::InvalidValue {
            name: "effective harmonics of the fine balance (symmetry differs)",
            value: fine.1 as f64,
        });
    }
    let amplitude = richardson(coarse.1, coarse.2, fine.1, fine.2)?;
    Ok(ExtrapolatedAmplitude {
        amplitude,
        coarse,
        fine,
        correction: (amplitude - fine.2).abs() / amplitude.abs().max(f64::MIN_POSITIVE),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed form: `Q(n) = Q∞ + c/n + d/n²` is extrapolated with an error
    /// of exactly `d/(n₁ n₂)` (the `O(n⁻²)` term).
    #[test]
    fn richardson_removes_the_first_order_term() {
        let (q_inf, c, d) = (0.026870357, -5.3e-4, 2.0e-3);
        let q = |n: usize| q_inf + c / n as f64 + d / (n * n) as f64;
        for (n1, n2) in [(13, 25), (25, 50), (7, 8)] {
            let r = richardson(n1, q(n1), n2, q(n2)).unwrap();
            let expected = q_inf - d / (n1 * n2) as f64;
            assert!((r - expected).abs() < 1e-15, "{n1} {n2}: {r} vs {expected}");
        }
    }

    #[test]
    fn bad_counts_are_typed_errors() {
        assert!(matches!(
            richardson(0, 1.0, 2, 1.0),
            Err(MhbError::InvalidValue { name: "n1", .. })
        ));
        assert!(matches!(
            richardson(3, 1.0, 3, 1.0),
            Err(MhbError::InvalidValue { .. })
        ));
        assert!(matches!(
            richardson(3, f64::NAN, 5, 1.0),
            Err(MhbError::InvalidValue { name: "q1", .. })
        ));
    }

    /// Half-wave symmetry is recognised from the coefficients.
    #[test]
    fn effective_harmonics_counts_odd_ones_of_symmetric_responses() {
        // h = 5: [a0, a1, b1, a2, b2, a3, b3, a4, b4, a5, b5]
        let mut q = vec![0.0; 11];
        q[1] = 1.0;
        q[6] = 0.1;
        assert_eq!(effective_harmonics(&q, 5), 3);
        q[4] = 1e-6; // an even harmonic
        assert_eq!(effective_harmonics(&q, 5), 5);
        q[4] = 0.0;
        q[0] = 1e-3; // a constant
        assert_eq!(effective_harmonics(&q, 5), 5);
    }
}
