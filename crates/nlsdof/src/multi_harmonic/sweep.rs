//! A stepped-sine sweep read off a continued branch (the multi-harmonic
//! counterpart of [`crate::harmonic_balance::ForcedResponse::sweep`]).
//!
//! The branch, continued from the first swept frequency in the sweep
//! direction, is cut at its limit points into segments
//! on which Ω is monotone. The sweep starts on the first segment and stays
//! on its segment while that covers the next frequency with a stable
//! state; otherwise (the segment ended at a fold, or lost stability) it
//! jumps to the stable state of another segment at that frequency whose
//! first-harmonic amplitude is nearest (in `ln a`) to the last one, and the
//! jump is recorded at the fold frequency. The state at each requested
//! frequency is the linear interpolation of the coefficients between the
//! two bracketing branch points, polished by Newton at the exact frequency;
//! its stability is Hill's ([`super::stability`]) at that state.
//! Only the branch connected to the starting state is known: an isolated
//! branch (isola) is not seen, as in a real sweep from that start.

use super::continuation::{continue_in_omega, BranchPoint, ContinuationOptions};
use super::stability::hill_floquet_exponents;
use super::system::{HarmonicSettings, HbSystem};
use super::{harmonic_amplitude, MhbError};
use crate::harmonic_balance::{Jump, SweepDirection};
use crate::model::AsNormalised;

/// One swept point.
#[derive(Debug, Clone, PartialEq)]
pub struct MhbSweepPoint {
    /// Ω, rad/s.
    pub omega: f64,
    /// Coefficients `[a₀, a₁, b₁, …]`, m.
    pub coefficients: Vec<f64>,
    /// Hill-stable.
    pub stable: bool,
}

/// A sweep at one level.
#[derive(Debug, Clone, PartialEq)]
pub struct MhbSweep {
    pub direction: SweepDirection,
    /// In sweep order.
    pub points: Vec<MhbSweepPoint>,
    /// Jumps in sweep order (`amplitude_*` are first-harmonic amplitudes).
    pub jumps: Vec<Jump>,
    /// Limit points of the branch (Ω rad/s, first-harmonic amplitude m), increasing Ω.
    pub folds: Vec<(f64, f64)>,
    /// The continued branch.
    pub branch: Vec<BranchPoint>,
    /// Set if the continuation stopped early (the sweep then ends where
    /// the branch ends).
    pub warning: Option<MhbError>,
    /// Samples per period used.
    pub samples: usize,
}

struct Segment {
    lo: usize,
    hi: usize, // inclusive indices into the branch
}

fn covers(b: &[BranchPoint], s: &Segment, omega: f64) -> Option<usize> {
    // index i with omega between b[i] and b[i+1]
    for i in s.lo..s.hi {
        let (a, c) = (b[i].omega, b[i + 1].omega);
        if (a <= omega && omega <= c) || (c <= omega && omega <= a) {
            return Some(i);
        }
    }
    None
}

fn interpolate(b: &[BranchPoint], i: usize, omega: f64) -> Vec<f64> {
    let (p, q) = (&b[i], &b[i + 1]);
    let d = q.omega - p.omega;
    let t = if d == 0.0 { 0.0 } else { (omega - p.omega) / d };
    p.coefficients
        .iter()
        .zip(&q.coefficients)
        .map(|(a, c)| a + t * (c - a))
        .collect()
}

/// Stepped-sine sweep over the strictly increasing `omegas` (rad/s) in
/// `direction`, with `h` harmonics (points returned in sweep order).
pub fn sweep(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    h: usize,
    omegas: &[f64],
    direction: SweepDirection,
    settings: HarmonicSettings,
    opts: &ContinuationOptions,
) -> Result<MhbSweep, MhbError> {
    let model = &model.as_normalised()?;
    if omegas.len() < 2 {
        return Err(MhbError::InvalidValue {
            name: "number of sweep frequencies",
            value: omegas.len() as f64,
        });
    }
    let ordered: Vec<f64> = match direction {
        SweepDirection::Up => omegas.to_vec(),
        SweepDirection::Down => omegas.iter().rev().copied().collect(),
    };
    let (w0, w1) = (ordered[0], *ordered.last().unwrap());
    let opts = ContinuationOptions {
        stability: false,
        ..*opts
    };
    let br = continue_in_omega(model, gamma, h, w0, w1, settings, &opts)?;
    let b = &br.points;
    let mut cuts: Vec<usize> = vec![0];
    cuts.extend(br.limit_points.iter().map(|l| l.index));
    cuts.push(b.len() - 1);
    cuts.dedup();
    let segs: Vec<Segment> = cuts
        .windows(2)
        .map(|w| Segment { lo: w[0], hi: w[1] })
        .collect();
    let mut sys = HbSystem::new(model, gamma, h, settings)?;
    sys.set_samples(br.samples.max(sys.samples()))?;
    // state at `om` on branch interval `i`: interpolated, polished, Hill
    let mut state = |i: usize, om: f64| -> Result<(Vec<f64>, bool), MhbError> {
        let mut q = interpolate(b, i, om);
        sys.solve(&mut q, om)?;
        let fl = hill_floquet_exponents(&mut sys, &q, om)?;
        Ok((q, fl.stable))
    };
    let mut cur = 0usize;
    let mut points = Vec::with_capacity(ordered.len());
    let mut jumps = Vec::new();
    let mut last_amp = f64::NAN;
    for &om in &ordered {
        let here = segs.get(cur).and_then(|s| covers(b, s, om));
        let mut chosen: Option<(usize, Vec<f64>, bool)> = None;
        let mut here_state = None;
        if let Some(i) = here {
            let (q, st) = state(i, om)?;
            if st {
                chosen = Some((cur, q, true));
            } else {
                here_state = Some(q);
            }
        }
        if chosen.is_none() {
            // jump: the stable state of another segment nearest in ln a
            let mut best: Option<(usize, Vec<f64>, f64)> = None;
            for (k, s) in segs.iter().enumerate() {
                if Some(k) == here.map(|_| cur) {
                    continue;
                }
                if let Some(i) = covers(b, s, om) {
                    let (q, st) = state(i, om)?;
                    if st {
                        let a = harmonic_amplitude(&q, 1);
                        let dist = if last_amp.is_finite() {
                            (a.ln() - last_amp.ln()).abs()
                        } else {
                            0.0
                        };
                        if best.as_ref().is_none_or(|(_, _, d)| dist < *d) {
                            best = Some((k, q, dist));
                        }
                    }
                }
            }
            if let Some((k, q, _)) = best {
                if k != cur && !points.is_empty() {
                    // the fold where the followed segment ended (or the
                    // last point if it lost stability inside)
                    let end = if here.is_none() {
                        let e = &b[segs[cur].hi];
                        (e.omega, e.amplitude(1))
                    } else {
                        (om, last_amp)
                    };
                    let after = match covers(b, &segs[k], end.0) {
                        Some(j) => harmonic_amplitude(&state(j, end.0)?.0, 1),
                        None => harmonic_amplitude(&q, 1),
                    };
                    jumps.push(Jump {
                        omega: end.0,
                        amplitude_before: end.1,
                        amplitude_after: after,
                    });
                }
                chosen = Some((k, q, true));
            } else if let Some(q) = here_state {
                chosen = Some((cur, q, false));
            } else if let Some((k, i)) = segs
                .iter()
                .enumerate()
                .find_map(|(k, s)| covers(b, s, om).map(|i| (k, i)))
            {
                let (q, st) = state(i, om)?;
                chosen = Some((k, q, st));
            }
        }
        let Some((seg, q, stable)) = chosen else {
            break; // beyond the computed branch (continuation stopped early)
        };
        cur = seg;
        last_amp = harmonic_amplitude(&q, 1);
        points.push(MhbSweepPoint {
            omega: om,
            coefficients: q,
            stable,
        });
    }
    let mut folds: Vec<(f64, f64)> = br
        .limit_points
        .iter()
        .map(|l| (l.point.omega, l.point.amplitude(1)))
        .collect();
    folds.sort_by(|a, c| a.0.total_cmp(&c.0));
    Ok(MhbSweep {
        direction,
        points,
        jumps,
        folds,
        samples: br.samples,
        warning: br.warning.clone(),
        branch: br.points,
    })
}
