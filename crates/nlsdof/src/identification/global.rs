//! Global search: seeded multistart of the bounded local solver (like
//! MATLAB's MultiStart). Start points are a Latin hypercube in the box of
//! the optimisation variables (plus the data-derived start), run in parallel
//! with rayon; each local run is deterministic, so the result for a given
//! seed does not depend on the number of threads. Minima are de-duplicated
//! (same point to 1e-4 of the box width in every variable, or same cost to
//! 1e-9 relative) and sorted by cost.

use super::levenberg_marquardt::{minimise, LeastSquares, LmOptions, LmResult};
use rayon::prelude::*;

/// SplitMix64: a small, well-mixed deterministic generator.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// `n` points of a Latin hypercube in `[0,1)^dims`.
pub fn latin_hypercube(n: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = SplitMix64(seed);
    let mut pts = vec![vec![0.0; dims]; n];
    for d in 0..dims {
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            perm.swap(i, j);
        }
        for i in 0..n {
            pts[i][d] = (perm[i] as f64 + rng.next_f64()) / n as f64;
        }
    }
    pts
}

/// One distinct local minimum.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMinimum {
    pub result: LmResult,
    /// How many starts ended here.
    pub count: usize,
    /// Index of the first start that found it (0 = data-derived start).
    pub first_start: usize,
}

/// Runs `starts` local fits (the first from `u0`, the rest from a Latin
/// hypercube with `seed`) and returns the distinct minima, best first.
/// `progress` is called once per finished start. Starts whose objective
/// cannot be evaluated are skipped; empty result if none could be.
pub fn multistart<P: LeastSquares>(
    problem: &P,
    u0: &[f64],
    lo: &[f64],
    hi: &[f64],
    starts: usize,
    seed: u64,
    opts: &LmOptions,
    progress: &(dyn Fn() + Sync),
) -> Vec<LocalMinimum> {
    let n = problem.n_params();
    let mut points = vec![u0.to_vec()];
    if starts > 1 {
        for p in latin_hypercube(starts - 1, n, seed) {
            points.push((0..n).map(|k| lo[k] + p[k] * (hi[k] - lo[k])).collect());
        }
    }
    let results: Vec<Option<LmResult>> = points
        .par_iter()
        .map(|u| {
            let r = minimise(problem, u, lo, hi, opts).ok();
            progress();
            r
        })
        .collect();
    dedupe(results, lo, hi)
}

fn dedupe(results: Vec<Option<LmResult>>, lo: &[f64], hi: &[f64]) -> Vec<LocalMinimum> {
    let mut found: Vec<(usize, LmResult)> = results
        .into_iter()
        .enumerate()
        .filter_map(|(i, r)| r.filter(|r| r.cost.is_finite()).map(|r| (i, r)))
        .collect();
    found.sort_by(|a, b| a.1.cost.total_cmp(&b.1.cost).then(a.0.cmp(&b.0)));
    let mut out: Vec<LocalMinimum> = Vec::new();
    for (i, r) in found {
        let same = out.iter_mut().find(|m| {
            let close = m.result.u.iter().zip(&r.u).enumerate().all(|(k, (a, b))| {
                let w = (hi[k] - lo[k]).abs();
                let w = if w.is_finite() && w > 0.0 { w } else { 1.0 };
                (a - b).abs() <= 1e-4 * w
            });
            let same_cost = (m.result.cost - r.cost).abs() <= 1e-9 * m.result.cost.max(r.cost);
            close || same_cost
        });
        match same {
            Some(m) => {
                m.count += 1;
                m.first_start = m.first_start.min(i);
            }
            None => out.push(LocalMinimum {
                result: r,
                count: 1,
                first_start: i,
            }),
        }
    }
    out
}

/// Convenience: default LM options.
pub fn default_options() -> LmOptions {
    LmOptions::default()
}
