//! The most recent model sweeps of the measured-branch output error, kept
//! so that an evaluation repeated at the same parameters does not sweep
//! again.
//!
//! A fit evaluates the output error ([`super::output_error`]) at the same
//! θ more than once: a solver's last point is assessed again, a stage
//! starts where the previous one stopped, the readings are compared at a
//! common start, and a judgement re-evaluates the result. The model sweep
//! of a curve (its followed branch, folds, jumps and stable states at
//! every step: [`ForcedResponse::sweep_with_states`]) is a function of the
//! model, the input level, the formulation, the curve's frequencies, its
//! direction and its first amplitude only: not of the jump reading, the
//! weights, the phases or whether a Jacobian is wanted. So a repeated sweep
//! can be returned from memory, and the result is the same bit for bit.
//!
//! Measured on the default generalised fit of `cc_beam_no_magnet_24C`
//! (2026-11-28): of 1.67 million swept points, 8.4 % (140,000) repeated an
//! earlier sweep of the same key; 64 % of those repeats came within 6
//! sweeps of the first, 88 % within 30. Hence a small least-recently-used
//! memo ([`CAPACITY`] sweeps, at most [`MAX_STEPS`] steps in all) and not
//! a table of every sweep. It serves 103,000 of those points (48 sweeps
//! and the same step budget: 87,000; 128 sweeps and twice the steps:
//! 104,000), and the fit takes 4 % less time, with the same result.
//!
//! The key is compared exactly (the bits of every model parameter, the
//! level, the first amplitude and every frequency), never by a hash alone,
//! so a hit is the sweep that would have been computed. Failed sweeps are
//! not kept. The memo is shared by every fit in the process (fits running
//! in parallel only share its capacity: a key names one sweep whichever
//! fit asks); it holds at most a few megabytes.
//!
//! Written by hand: a dozen lines of a bounded list; an LRU crate would
//! still need the exact key and the step budget.

use super::data::Curve;
use super::objective::first_amplitude;
use crate::error::SolveError;
use crate::harmonic_balance::{ForcedResponse, StepStates, Sweep, SweepDirection};
use std::sync::{Arc, Mutex};

/// A sweep with the stable steady states at each step
/// ([`ForcedResponse::sweep_with_states`]).
pub type SweepWithStates = (Sweep, StepStates);

/// Most sweeps kept.
pub const CAPACITY: usize = 96;

/// Most steps kept over all sweeps (about 100 bytes each); a sweep of more
/// than a quarter of this is not kept.
pub const MAX_STEPS: usize = 1 << 16;

/// What a sweep is a function of, by bits.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Key {
    /// α, δ, β, ρ, κ, η, γ (the input level the model sees), the first
    /// amplitude.
    numbers: [u64; 8],
    formulation: crate::harmonic_balance::Formulation,
    up: bool,
    omegas: Vec<u64>,
}

impl Key {
    fn of(r: &ForcedResponse, c: &Curve) -> Self {
        let m = &r.model;
        Self {
            numbers: [
                m.alpha,
                m.delta,
                m.beta,
                m.rho,
                m.kappa,
                m.eta,
                r.gamma,
                first_amplitude(c),
            ]
            .map(f64::to_bits),
            formulation: r.formulation,
            up: c.direction == SweepDirection::Up,
            omegas: c.omegas.iter().map(|w| w.to_bits()).collect(),
        }
    }
}

/// Most recently used first.
static RECENT: Mutex<Vec<(Key, Arc<SweepWithStates>)>> = Mutex::new(Vec::new());

/// The sweep of curve `c` with the model and level of `r`, with its stable
/// states: `r.sweep_with_states(&c.omegas, c.direction, first_amplitude(c))`,
/// from memory when that sweep was one of the recent ones (module docs).
pub fn sweep_with_states(
    r: &ForcedResponse,
    c: &Curve,
) -> Result<Arc<SweepWithStates>, SolveError> {
    let steps = c.omegas.len();
    let keep = steps <= MAX_STEPS / 4;
    let key = keep.then(|| Key::of(r, c));
    if let Some(k) = &key {
        let mut recent = RECENT.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = recent.iter().position(|(rk, _)| rk == k) {
            let entry = recent.remove(i);
            let found = entry.1.clone();
            recent.insert(0, entry);
            return Ok(found);
        }
    }
    // (swept outside the lock: the sweeps of other curves go on meanwhile)
    let swept = Arc::new(r.sweep_with_states(&c.omegas, c.direction, first_amplitude(c))?);
    if let Some(k) = key {
        let mut recent = RECENT.lock().unwrap_or_else(|e| e.into_inner());
        // (another thread may have swept the same key meanwhile)
        if !recent.iter().any(|(rk, _)| *rk == k) {
            recent.insert(0, (k, swept.clone()));
            let mut total = 0;
            let kept = recent
                .iter()
                .take(CAPACITY)
                .take_while(|(rk, _)| {
                    total += rk.omegas.len();
                    total <= MAX_STEPS
                })
                .count();
            recent.truncate(kept);
        }
    }
    Ok(swept)
}

/// Empties the memo (its memory is freed). Results never depend on it; a
/// benchmark of one fit calls this first, so that it does not reuse the
/// sweeps of the fit it ran before.
pub fn forget() {
    RECENT.lock().unwrap_or_else(|e| e.into_inner()).clear();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harmonic_balance::Formulation;
    use crate::model::NormalisedModel;

    fn curve(direction: SweepDirection, n: usize) -> Curve {
        let omegas: Vec<f64> = (0..n).map(|i| 9.0 + 4.0 * i as f64 / n as f64).collect();
        Curve {
            level: "1".into(),
            gamma: 1.0,
            omegas,
            amplitudes: vec![0.01; n],
            phases: None,
            direction,
            weights: vec![1.0; n],
        }
    }

    fn response(beta: f64) -> ForcedResponse {
        let m = NormalisedModel {
            alpha: 100.0,
            delta: 0.1,
            beta,
            rho: 2.0,
            kappa: 0.0,
            eta: 0.0,
        };
        ForcedResponse::from_normalised(&m, 1.0, Formulation::HarmonicBalance).unwrap()
    }

    fn same(a: &SweepWithStates, b: &SweepWithStates) -> bool {
        let bits = |s: &Sweep| -> Vec<u64> {
            s.points
                .iter()
                .flat_map(|p| [p.omega, p.amplitude, p.phase])
                .chain(s.folds.iter().map(|f| f.omega))
                .chain(s.jumps.iter().map(|j| j.omega))
                .map(f64::to_bits)
                .collect()
        };
        let states = |s: &StepStates| -> Vec<u64> {
            s.iter()
                .flatten()
                .flat_map(|s| [s.amplitude, s.phase])
                .map(f64::to_bits)
                .collect()
        };
        bits(&a.0) == bits(&b.0) && states(&a.1) == states(&b.1)
    }

    /// The oracle is the sweep itself: a repeated key returns the stored
    /// sweep (the same allocation), equal bit for bit to a fresh one; a
    /// change of one bit of the model, of the direction or of one
    /// frequency is another sweep.
    #[test]
    fn a_repeated_sweep_is_the_fresh_one() {
        let c = curve(SweepDirection::Up, 200);
        let r = response(40.0);
        let first = sweep_with_states(&r, &c).unwrap();
        let again = sweep_with_states(&r, &c).unwrap();
        let fresh = r
            .sweep_with_states(&c.omegas, c.direction, first_amplitude(&c))
            .unwrap();
        assert!(Arc::ptr_eq(&first, &again) || same(&first, &again));
        assert!(same(&again, &fresh));
        assert!(!fresh.0.jumps.is_empty(), "a sweep with a jump is tested");

        let nudged = response(f64::from_bits(40f64.to_bits() + 1));
        let other = sweep_with_states(&nudged, &c).unwrap();
        assert!(!Arc::ptr_eq(&first, &other));
        let fresh = nudged
            .sweep_with_states(&c.omegas, c.direction, first_amplitude(&c))
            .unwrap();
        assert!(same(&other, &fresh));

        let mut moved = c.clone();
        moved.omegas[100] = f64::from_bits(moved.omegas[100].to_bits() + 1);
        let other = sweep_with_states(&r, &moved).unwrap();
        assert!(!Arc::ptr_eq(&first, &other));

        let down = curve(SweepDirection::Down, 200);
        let other = sweep_with_states(&r, &down).unwrap();
        let fresh = r
            .sweep_with_states(&down.omegas, down.direction, first_amplitude(&down))
            .unwrap();
        assert!(same(&other, &fresh));
    }

    /// The memo stays within its budget of sweeps and steps.
    #[test]
    fn the_memo_stays_within_its_budget() {
        let c = curve(SweepDirection::Up, MAX_STEPS / 8);
        for k in 0..12 {
            let r = response(10.0 * (1.0 + k as f64));
            sweep_with_states(&r, &c).unwrap();
            let recent = RECENT.lock().unwrap();
            assert!(recent.len() <= CAPACITY);
            let steps: usize = recent.iter().map(|(k, _)| k.omegas.len()).sum();
            assert!(steps <= MAX_STEPS, "{steps} steps kept");
        }
        // a sweep too long to keep is still swept
        let long = curve(SweepDirection::Up, MAX_STEPS / 4 + 1);
        let r = response(20.0);
        let s = sweep_with_states(&r, &long).unwrap();
        assert_eq!(s.0.points.len(), long.omegas.len());
        let recent = RECENT.lock().unwrap();
        assert!(recent.iter().all(|(k, _)| k.omegas.len() <= MAX_STEPS / 4));
    }
}
