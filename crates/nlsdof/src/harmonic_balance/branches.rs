//! Branch tracing: every steady-state branch of a forced response across a
//! band, as polylines of one stability each (what a response-curve plot
//! draws). `steady_states` is solved on a grid of frequencies plus the
//! folds; roots of equal rank (index in the amplitude-sorted list) are
//! connected between consecutive samples with equal root count, and across
//! a fold the two roots born or dying there are joined to the fold point.
//!
//! ```
//! use nlsdof::harmonic_balance::branches::{trace_branches, BranchOptions};
//! use nlsdof::{ForcedResponse, Formulation, Model, SweepDirection};
//! let duffing = Model::linear(1.0, 3947.84, 1.2566)?.with_stiffness(1.2e7, 2.0)?;
//! let r = ForcedResponse::new(&duffing, 2.0, Formulation::HarmonicBalance)?;
//! let omegas: Vec<f64> = (0..50).map(|i| 50.0 + 50.0 * i as f64 / 49.0).collect();
//! let sweep = r.sweep(&omegas, SweepDirection::Up)?;
//! let lines = trace_branches(&r, &sweep.folds, 50.0, 100.0, &BranchOptions::default())?;
//! // two stable branches and the unstable one between the folds
//! assert_eq!(lines.iter().filter(|b| !b.stable).count(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::{Fold, ForcedResponse, SteadyState};
use crate::error::SolveError;
use std::collections::HashMap;

/// A piece of one branch: points (frequency in the caller's unit, m) with
/// one stability.
#[derive(Debug, Clone, PartialEq)]
pub struct TracedBranch {
    pub points: Vec<(f64, f64)>,
    pub stable: bool,
}

type Segment = ((f64, f64), (f64, f64), bool);

fn key(p: (f64, f64), stable: bool) -> (u64, u64, bool) {
    (p.0.to_bits(), p.1.to_bits(), stable)
}

/// Joins segments (generated in increasing frequency) into polylines.
fn merge(segments: Vec<Segment>) -> Vec<TracedBranch> {
    let mut lines: Vec<TracedBranch> = Vec::new();
    let mut open: HashMap<(u64, u64, bool), usize> = HashMap::new();
    for (p0, p1, stable) in segments {
        if let Some(idx) = open.remove(&key(p0, stable)) {
            lines[idx].points.push(p1);
            open.insert(key(p1, stable), idx);
        } else {
            lines.push(TracedBranch {
                points: vec![p0, p1],
                stable,
            });
            open.insert(key(p1, stable), lines.len() - 1);
        }
    }
    lines
}

fn connect_rankwise(
    fa: f64,
    a: &[SteadyState],
    fb: f64,
    b: &[SteadyState],
    out: &mut Vec<Segment>,
) {
    for (ra, rb) in a.iter().zip(b) {
        out.push((
            (fa, ra.amplitude),
            (fb, rb.amplitude),
            ra.stable && rb.stable,
        ));
    }
}

/// Options of [`trace_branches`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchOptions {
    /// Frequencies sampled across the band (plus the folds), >= 2.
    pub samples: usize,
    /// Radians per second per unit of the frequency axis: 1 for rad/s,
    /// `2π` for Hz.
    pub radians_per_unit: f64,
}

impl Default for BranchOptions {
    fn default() -> Self {
        Self {
            samples: 600,
            radians_per_unit: 1.0,
        }
    }
}

/// All steady-state branches of `response` across `[f_min, f_max]` (in the
/// unit of [`BranchOptions::radians_per_unit`]), with `folds` the folds of
/// the band (e.g. [`crate::Sweep::folds`]).
pub fn trace_branches(
    response: &ForcedResponse,
    folds: &[Fold],
    f_min: f64,
    f_max: f64,
    opts: &BranchOptions,
) -> Result<Vec<TracedBranch>, SolveError> {
    let unit = opts.radians_per_unit;
    let n = opts.samples.max(2);
    let fold_hz: Vec<f64> = folds.iter().map(|f| f.omega / unit).collect();
    let tol = 1e-9 * (f_max - f_min);
    let mut samples: Vec<(f64, Vec<SteadyState>)> = Vec::with_capacity(n);
    for i in 0..n {
        let f = f_min + (f_max - f_min) * i as f64 / (n - 1) as f64;
        // A sample exactly at a fold would hold a double root: skip it.
        if fold_hz.iter().any(|&ff| (ff - f).abs() <= tol) {
            continue;
        }
        let set = response.steady_states(unit * f)?;
        samples.push((f, set.roots));
    }
    let mut segments: Vec<Segment> = Vec::new();
    for w in samples.windows(2) {
        let (fa, ra) = (&w[0].0, &w[0].1);
        let (fb, rb) = (&w[1].0, &w[1].1);
        let inside: Vec<usize> = (0..folds.len())
            .filter(|&k| fold_hz[k] > *fa && fold_hz[k] < *fb)
            .collect();
        match inside.len() {
            0 if ra.len() == rb.len() => connect_rankwise(*fa, ra, *fb, rb, &mut segments),
            1 if ra.len().abs_diff(rb.len()) == 2 => {
                let fold = folds[inside[0]];
                let fp = (fold_hz[inside[0]], fold.amplitude);
                // The side holding the pair born/dying at the fold.
                let pair_after = rb.len() > ra.len();
                let (pair_side, other) = if pair_after { (rb, ra) } else { (ra, rb) };
                let j = (0..pair_side.len() - 1)
                    .min_by(|&x, &y| {
                        let dx = (pair_side[x].amplitude - fold.amplitude).abs()
                            + (pair_side[x + 1].amplitude - fold.amplitude).abs();
                        let dy = (pair_side[y].amplitude - fold.amplitude).abs()
                            + (pair_side[y + 1].amplitude - fold.amplitude).abs();
                        dx.total_cmp(&dy)
                    })
                    .unwrap_or(0);
                let rest: Vec<SteadyState> = pair_side
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != j && *k != j + 1)
                    .map(|(_, r)| *r)
                    .collect();
                if pair_after {
                    connect_rankwise(*fa, other, *fb, &rest, &mut segments);
                    for r in &pair_side[j..=j + 1] {
                        segments.push((fp, (*fb, r.amplitude), r.stable));
                    }
                } else {
                    connect_rankwise(*fa, &rest, *fb, other, &mut segments);
                    for r in &pair_side[j..=j + 1] {
                        segments.push(((*fa, r.amplitude), fp, r.stable));
                    }
                }
            }
            // Root count changes without one identified fold (sticking
            // boundary, two folds within one sample step): leave a gap.
            _ => {}
        }
    }
    Ok(merge(segments))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Formulation, Model, Sweep, SweepDirection};
    use std::f64::consts::PI;

    fn duffing() -> Model {
        Model::linear(1.0, 3947.84, 1.2566)
            .unwrap()
            .with_stiffness(1.2e7, 2.0)
            .unwrap()
    }

    fn level(
        model: &Model,
        gamma: f64,
        f_min: f64,
        f_max: f64,
        steps: usize,
    ) -> (ForcedResponse, Sweep) {
        let omegas: Vec<f64> = (0..steps)
            .map(|i| 2.0 * PI * (f_min + (f_max - f_min) * i as f64 / (steps - 1) as f64))
            .collect();
        let hb = Formulation::HarmonicBalance;
        let l = crate::level_responses(model, &[gamma], &omegas, SweepDirection::Up, hb)
            .unwrap()
            .remove(0);
        (l.response, l.sweep)
    }

    #[test]
    fn branches_of_a_hardening_duffing_meet_at_the_folds() {
        let l = level(&duffing(), 2.0, 8.0, 16.0, 50);
        assert_eq!(l.1.folds.len(), 2);
        let opts = BranchOptions {
            samples: 600,
            radians_per_unit: 2.0 * PI,
        };
        let lines = trace_branches(&l.0, &l.1.folds, 8.0, 16.0, &opts).unwrap();
        // resonant branch 8 Hz -> upper fold, low branch lower fold -> 16 Hz,
        // and the unstable middle branch from fold to fold
        assert_eq!(lines.iter().filter(|p| p.stable).count(), 2, "{lines:?}");
        assert_eq!(lines.iter().filter(|p| !p.stable).count(), 1);
        for fold in &l.1.folds {
            let fp = (fold.omega / (2.0 * PI), fold.amplitude);
            let touching: Vec<&TracedBranch> = lines
                .iter()
                .filter(|p| p.points.first() == Some(&fp) || p.points.last() == Some(&fp))
                .collect();
            assert_eq!(touching.len(), 2, "fold {fp:?}");
            assert!(touching.iter().any(|p| p.stable) && touching.iter().any(|p| !p.stable));
        }
        for p in &lines {
            assert!(
                p.points.windows(2).all(|w| w[1].0 > w[0].0),
                "increasing frequency"
            );
            assert!(p
                .points
                .iter()
                .all(|&(f, a)| (8.0..=16.0).contains(&f) && a > 0.0));
        }
    }
}
