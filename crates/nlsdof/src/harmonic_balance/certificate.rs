//! The one-root certificate of the stepped-sine fast path and of the fold
//! search: a cheap analytic proof that the response equation `P(x) = 1`
//! has exactly one root at every frequency of a cell, so the cell holds no
//! fold (used by [`super::sweep`] and [`super::folds`]).

use super::equation::{amplitude_bound, ResponseEquation};
use super::ForcedResponse;

/// Whether the fast-path certificate can apply at all to this response:
/// `ρ ≥ 0` (or no stiffness term) and `η ≥ −1` (or no damping term).
///
/// At `η = −1` (Coulomb friction) the damping part of `P` is
/// `x²D² = (d₀x + d₁)²`, still increasing in `x`, so a certified cell has
/// an increasing `P` as for `η > −1`; but `P(0⁺) = d₁²` is no longer 0, so
/// a certified cell has *at most* one root: none where `d₁ ≥ 1` (the
/// friction holds the mass). Every user of the certificate falls back to
/// exact root isolation when its Newton solve finds no root, and a cell
/// whose count goes from one root to none holds no fold.
pub(crate) fn fast_path_possible(r: &ForcedResponse) -> bool {
    (r.b == 0.0 || r.model.rho >= 0.0) && (r.c == 0.0 || r.model.eta >= -1.0)
}

/// Certificate that `P(x) = 1` has exactly one root for *every* frequency
/// between the two cell ends `a` and `b` (equations at the two ends); at
/// most one at `η = −1` (see [`fast_path_possible`]).
///
/// With `η ≥ −1`, `ρ ≥ 0`, all exponents of `P − 1` except 0 are positive
/// (at `η = −1` the `d₁²` term is a constant and its derivative vanishes) and
///
/// ```text
/// dP/dt = x² [ 2(s₀²+d₀²) + 2(2+ρ) s₀s₁ z + 2(1+ρ) s₁² z² + (≥ 0 damping terms) ],  z = x^ρ
/// ```
///
/// so `P` is increasing — one root, no fold — if `s₀s₁ ≥ 0`, or if the
/// quadratic in `z` has no positive root (`ρ² s₀² < 4(1+ρ) d₀²`), or if it
/// stays positive up to the root bound `x_hi`: with the cell's worst-case
/// lower bound `q(z) = (s₀² + d₀²)_min − (2+ρ)|s₀|_max|s₁| z + (1+ρ)s₁² z²`
/// of the bracket, `x_hi^ρ` below the smaller positive root of `q`; or if
/// the nonlinear-damping terms at their smallest over the zone where `q < 0`
/// exceed `−min q`.
/// `s₀`, `d₀`, `d₁` are monotone in Ω for both formulations, so their
/// extremes over the cell are at its ends and the test holds for the whole
/// cell.
// `!(x >= 0.0)` on purpose: a NaN takes the same branch as a negative value.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub(crate) fn certify_cell(a: &ResponseEquation, b: &ResponseEquation) -> bool {
    let s1 = a.s1;
    if s1 == 0.0 || a.rho == 0.0 {
        return true;
    }
    if a.s0 * s1 >= 0.0 && b.s0 * s1 >= 0.0 {
        return true;
    }
    let rho = a.rho;
    let s0_max = a.s0.abs().max(b.s0.abs());
    let s0sq_min = if (a.s0 > 0.0) != (b.s0 > 0.0) {
        0.0
    } else {
        (a.s0 * a.s0).min(b.s0 * b.s0)
    };
    let d0_min = a.d0.min(b.d0);
    if rho * rho * s0_max * s0_max < 4.0 * (1.0 + rho) * d0_min * d0_min {
        return true;
    }
    let rhs = s0sq_min + d0_min * d0_min;
    let lhs_factor = (2.0 + rho) * s0_max * s1.abs();
    // The bracket is at least q(z) = rhs − lhs_factor z + (1+ρ) s₁² z² over
    // the whole cell; q > 0 on [0, z_hi] iff z_hi is below its smaller
    // root z₁ = 2 rhs / (B + √(B² − 4AC)) (q has no positive root if the
    // discriminant is negative, handled above).
    let qa = (1.0 + rho) * s1 * s1;
    let disc = lhs_factor * lhs_factor - 4.0 * qa * rhs;
    if !(disc >= 0.0) {
        return disc < 0.0;
    }
    let z1 = 2.0 * rhs / (lhs_factor + disc.sqrt());
    // first with the cheap bound x_hi = 1/d₀, then with the tighter one
    if d0_min > 0.0 && (-rho * d0_min.ln()).exp() < z1 {
        return true;
    }
    let d1_min = a.d1.min(b.d1);
    let x_hi = amplitude_bound(d0_min, d1_min, a.eta);
    if x_hi.is_finite() && x_hi.powf(rho) < z1 {
        return true;
    }
    // The nonlinear-damping part of the bracket, (2+η)d₀d₁x^η + (1+η)d₁²x^{2η}
    // (≥ 0, dropped above), can make up for the dip of q: q < 0 only for
    // z ∈ (z₁, z₂) and q ≥ q_min = C − B²/(4A) there. The damping part is
    // monotone in x (increasing for η ≥ 0, decreasing for −1 < η < 0), so
    // over the part of that zone below x_hi it is smallest at x₁ = z₁^{1/ρ}
    // (η ≥ 0) or at min(z₂^{1/ρ}, x_hi) (η < 0), with the cell's smallest
    // d₀, d₁. If it exceeds −q_min there, P is increasing up to x_hi.
    if !(d1_min > 0.0) {
        return false;
    }
    let eta = a.eta;
    let q_min = rhs - lhs_factor * lhs_factor / (4.0 * qa);
    let t_w = if eta >= 0.0 {
        z1.ln() / rho
    } else {
        let z2 = (lhs_factor + disc.sqrt()) / (2.0 * qa);
        (z2.ln() / rho).min(x_hi.ln())
    };
    let w = (eta * t_w).exp();
    let damping = (2.0 + eta) * d0_min * d1_min * w + (1.0 + eta) * d1_min * d1_min * w * w;
    damping.is_finite() && damping > -q_min
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harmonic_balance::Formulation;
    use crate::model::NormalisedModel;

    /// Independent oracle for the one-root certificate: wherever
    /// [`certify_cell`] holds, exact root isolation finds exactly one root
    /// at every one of 40 frequencies across the cell.
    #[test]
    fn certified_cells_have_exactly_one_root() {
        let mut rnd = crate::harmonic_balance::test_uniform(0x1234_5678_9abc_def0u64);
        let (mut certified, mut checked, mut by_damping) = (0, 0, 0);
        let (mut coulomb, mut sticking) = (0, 0);
        for _ in 0..3000 {
            let wn = 10.0;
            let model = NormalisedModel {
                alpha: wn * wn,
                delta: 2.0 * wn * 10f64.powf(-3.0 + 2.5 * rnd()),
                beta: 10f64.powf(-2.0 + 6.0 * rnd()),
                rho: 0.3 + 6.0 * rnd(),
                kappa: if rnd() < 0.2 {
                    0.0
                } else {
                    10f64.powf(-4.0 + 5.0 * rnd())
                },
                // one case in ten at Coulomb friction (η = −1)
                eta: if rnd() < 0.1 {
                    -1.0
                } else {
                    -0.95 + 5.0 * rnd()
                },
            };
            let gamma = 10f64.powf(-1.0 + 2.0 * rnd());
            for formulation in [Formulation::HarmonicBalance, Formulation::Modulation] {
                let Ok(r) = ForcedResponse::from_normalised(&model, gamma, formulation) else {
                    continue;
                };
                let w0 = wn * (0.6 + 1.4 * rnd());
                let w1 = w0 * (1.0 + 0.2 * rnd());
                let (a, b) = (r.equation(w0), r.equation(w1));
                if !certify_cell(&a, &b) {
                    continue;
                }
                certified += 1;
                let no_damping = |e: &ResponseEquation| ResponseEquation { d1: 0.0, ..*e };
                if !certify_cell(&no_damping(&a), &no_damping(&b)) {
                    by_damping += 1;
                }
                for k in 0..40 {
                    let w = w0 + (w1 - w0) * k as f64 / 39.0;
                    let eq = r.equation(w);
                    if let Ok(roots) = eq.roots() {
                        // η = −1: none exactly when the friction holds the
                        // mass (P(0⁺) = d₁² ≥ 1), else one
                        let expected = if model.eta == -1.0 && model.kappa > 0.0 && eq.d1 >= 1.0 {
                            0
                        } else {
                            1
                        };
                        assert_eq!(
                            roots.len(),
                            expected,
                            "{model:?} γ={gamma} Ω={w}: {roots:?}"
                        );
                        checked += 1;
                        if model.eta == -1.0 && model.kappa > 0.0 {
                            coulomb += 1;
                            sticking += usize::from(expected == 0);
                        }
                    }
                }
            }
        }
        // the damping part of the certificate is exercised too
        eprintln!(
            "{certified} certified cells, {by_damping} by the damping part; \
             {coulomb} Coulomb frequencies checked, {sticking} sticking"
        );
        assert!(
            certified > 1000 && checked > 40_000 && by_damping > 100,
            "{certified} {checked} {by_damping}"
        );
        // Coulomb cells, with and without sticking, are exercised too
        assert!(coulomb > 2000 && sticking > 0, "{coulomb} {sticking}");
    }
}
