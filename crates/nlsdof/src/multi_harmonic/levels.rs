//! Multi-harmonic stepped-sine sweeps of one model at several input
//! levels, with the settings a model needs and, for regularised models, the
//! regularisation check at each level's peak: what `nlsdof frf --harmonics`
//! computes.

use super::sweep::{sweep, MhbSweep};
use super::{
    harmonic_amplitude, regularisation_check, ContinuationOptions, HarmonicSettings, HbSystem,
    MhbError,
};
use crate::model::{AsNormalised, NormalisedModel};
use crate::SweepDirection;

/// The sweep of one level.
#[derive(Debug, Clone)]
pub struct LevelSweep {
    pub gamma: f64,
    pub sweep: MhbSweep,
    /// Regularised models only: the regularisation check (ε → ε/4) at the
    /// swept point of largest first-harmonic amplitude: (Ω rad/s, relative
    /// change of A₁).
    pub regularisation: Option<(f64, f64)>,
}

/// Sweeps `model` with `h` harmonics at each level of `gammas` (m/s²,
/// zero-to-peak) over `omegas` (rad/s) in `direction`, with
/// [`settings_for`] the model. A model without any damping is refused
/// ([`MhbError::Undamped`]): its response at resonance is unbounded.
pub fn level_sweeps(
    model: &(impl AsNormalised + ?Sized),
    gammas: &[f64],
    omegas: &[f64],
    direction: SweepDirection,
    h: usize,
) -> Result<Vec<LevelSweep>, MhbError> {
    let n = model.as_normalised()?;
    if n.delta == 0.0 && n.kappa == 0.0 {
        return Err(MhbError::Undamped);
    }
    crate::limits::MULTI_HARMONIC_WORK
        .check(omegas.len() as f64 * gammas.len() as f64 * (h as f64).powi(3))?;
    let mut out = Vec::with_capacity(gammas.len());
    for &gamma in gammas {
        let s = sweep(
            &n,
            gamma,
            h,
            omegas,
            direction,
            settings_for(&n),
            &ContinuationOptions::default(),
        )?;
        let mut regularisation = None;
        let mut sys = HbSystem::new(&n, gamma, h, settings_for(&n))?;
        if sys.is_regularised() {
            if let Some(p) = s.points.iter().max_by(|a, b| {
                harmonic_amplitude(&a.coefficients, 1)
                    .total_cmp(&harmonic_amplitude(&b.coefficients, 1))
            }) {
                sys.set_samples(s.samples)?;
                let chk = regularisation_check(&sys, p.omega, &p.coefficients)?;
                regularisation = Some((p.omega, chk.relative_change));
            }
        }
        out.push(LevelSweep {
            gamma,
            sweep: s,
            regularisation,
        });
    }
    Ok(out)
}

/// Numerical settings for a model: the defaults, except that a model with a
/// negative exponent (regularised, e.g. Coulomb friction) uses an aliasing
/// tolerance of 1e-6 (relative to γ): the truncation error of HB for a
/// friction jump decays only like 1/H (measured 7e-4 at H = 25, see
/// docs/multi-harmonic.md) and dominates anyway, while resolving the fixed
/// regularisation layer to 1e-11 near resonance (velocity ≫ ε) would need
/// more than the 2^18 samples allowed. For the same reason the
/// regularisation width is ε_rel = 1e-2 (library default 1e-3): the layer
/// is resolved with ~10 times fewer samples (a Coulomb sweep through
/// resonance: 41 s → see docs/multi-harmonic.md).
pub fn settings_for(model: &NormalisedModel) -> HarmonicSettings {
    // an absent term has exponent 0 in the normalised form
    let negative = model.rho < 0.0 || model.eta < 0.0;
    let mut s = HarmonicSettings::default();
    if negative {
        s.aliasing_tol = 1e-6;
        s.regularisation = 1e-2;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multi_harmonic::truncation::truncation_study;
    use crate::Model;

    #[test]
    fn an_undamped_model_is_refused_before_any_continuation() {
        let m = Model::linear(1.0, 3947.84, 0.0)
            .unwrap()
            .with_stiffness(1e6, 2.0)
            .unwrap();
        let w = [50.0, 60.0, 70.0];
        let e = level_sweeps(&m, &[1.0], &w, SweepDirection::Up, 3).unwrap_err();
        assert!(matches!(e, MhbError::Undamped), "{e}");
        let n = m.normalised().unwrap();
        let e = truncation_study(
            &m,
            1.0,
            50.0,
            70.0,
            &[1, 3],
            1e-6,
            settings_for(&n),
            &ContinuationOptions::default(),
        )
        .unwrap_err();
        assert!(matches!(e, MhbError::Undamped), "{e}");
        // any damping term is enough
        let damped = m.with_damping(1e-3, 1.0).unwrap();
        assert!(level_sweeps(&damped, &[1.0], &w, SweepDirection::Up, 3).is_ok());
    }
}
