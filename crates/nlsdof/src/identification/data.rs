//! Measured stepped-sine amplitude curves (the data of Eq 31), validated.

use crate::harmonic_balance::SweepDirection;
use thiserror::Error;

/// One measured step, in SI units and rad/s (long format, one row per step).
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Level label (e.g. "0.04g" or "1").
    pub level: String,
    /// Input acceleration amplitude γ, m/s², zero-to-peak.
    pub gamma: f64,
    /// Excitation frequency Ω, rad/s.
    pub omega: f64,
    /// Output displacement amplitude a, m, zero-to-peak.
    pub amplitude: f64,
    /// Phase lag, rad (optional).
    pub phase: Option<f64>,
    /// Sweep direction of the run this step belongs to.
    pub direction: SweepDirection,
    /// Weight of the squared residual (default 1).
    pub weight: f64,
}

/// One sweep at one level: frequencies strictly increasing, whatever the
/// sweep direction (the direction tells the branch follower which way the
/// shaker went).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Curve {
    pub level: String,
    pub gamma: f64,
    pub direction: SweepDirection,
    pub omegas: Vec<f64>,
    pub amplitudes: Vec<f64>,
    pub phases: Option<Vec<f64>>,
    pub weights: Vec<f64>,
}

/// A validated data set: at least one level, each curve at least three
/// distinct frequencies.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dataset {
    pub curves: Vec<Curve>,
}

/// Why a data set cannot be fitted. Each variant names the offending value.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DataError {
    #[error("no data rows")]
    Empty,
    #[error("only one input level ({level}, gamma = {gamma} m/s^2): the identification needs at least two levels to separate linear and nonlinear terms")]
    SingleLevel { level: String, gamma: f64 },
    #[error(
        "level {level} ({direction} sweep) has {count} distinct frequencies; at least 3 are needed"
    )]
    TooFewFrequencies {
        level: String,
        direction: &'static str,
        count: usize,
    },
    #[error("level {level}: {what} = {value} at {f_hz} Hz is not a finite number")]
    NotFinite {
        level: String,
        what: &'static str,
        value: f64,
        f_hz: f64,
    },
    #[error("level {level}: {what} = {value} at {f_hz} Hz must be > 0")]
    NotPositive {
        level: String,
        what: &'static str,
        value: f64,
        f_hz: f64,
    },
    #[error("level {level}: amplitude = {value} at {f_hz} Hz is negative")]
    NegativeAmplitude {
        level: String,
        value: f64,
        f_hz: f64,
    },
    #[error("level {level} ({direction} sweep): frequency {f_hz} Hz appears more than once")]
    DuplicateFrequency {
        level: String,
        direction: &'static str,
        f_hz: f64,
    },
    #[error("level {level}: gamma = {value} m/s^2 differs from the level's first value {first} m/s^2 (gamma must be constant within a level)")]
    GammaNotConstant {
        level: String,
        first: f64,
        value: f64,
    },
    #[error("level {level}: weight = {value} at {f_hz} Hz must be finite and >= 0")]
    BadWeight {
        level: String,
        value: f64,
        f_hz: f64,
    },
}

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// How many times `ln` of the largest step-to-step amplitude ratio of a
/// curve must exceed `ln` of every ratio of the opposite direction (rise
/// against drop) to count as a measured jump ([`Curve::measured_jump`]).
pub const DISTINCT_JUMP: f64 = 1.5;

impl Dataset {
    /// Groups long-format records into curves (by level and direction, in
    /// order of first appearance) and validates them.
    pub fn from_records(records: &[Record]) -> Result<Self, DataError> {
        if records.is_empty() {
            return Err(DataError::Empty);
        }
        use std::collections::HashMap;
        // first γ of each level, and the rows of each (level, direction) in
        // order of first appearance; looked up by hash (a linear search made
        // 1,000,000 rows of 5000 levels take 9 s here)
        let mut level_gamma: HashMap<&str, f64> = HashMap::new();
        let mut group_of: HashMap<(&str, SweepDirection), usize> = HashMap::new();
        let mut groups: Vec<(String, SweepDirection, Vec<&Record>)> = Vec::new();
        for r in records {
            let f_hz = r.omega / TWO_PI;
            let lvl = || r.level.clone();
            for (what, v) in [
                ("gamma", r.gamma),
                ("frequency", r.omega),
                ("amplitude", r.amplitude),
            ] {
                if !v.is_finite() {
                    return Err(DataError::NotFinite {
                        level: lvl(),
                        what,
                        value: v,
                        f_hz,
                    });
                }
            }
            if let Some(p) = r.phase {
                if !p.is_finite() {
                    return Err(DataError::NotFinite {
                        level: lvl(),
                        what: "phase",
                        value: p,
                        f_hz,
                    });
                }
            }
            if r.gamma <= 0.0 {
                return Err(DataError::NotPositive {
                    level: lvl(),
                    what: "gamma",
                    value: r.gamma,
                    f_hz,
                });
            }
            if r.omega <= 0.0 {
                return Err(DataError::NotPositive {
                    level: lvl(),
                    what: "frequency",
                    value: f_hz,
                    f_hz,
                });
            }
            if r.amplitude < 0.0 {
                return Err(DataError::NegativeAmplitude {
                    level: lvl(),
                    value: r.amplitude,
                    f_hz,
                });
            }
            if !(r.weight.is_finite() && r.weight >= 0.0) {
                return Err(DataError::BadWeight {
                    level: lvl(),
                    value: r.weight,
                    f_hz,
                });
            }
            let g = *level_gamma.entry(r.level.as_str()).or_insert(r.gamma);
            if (g - r.gamma).abs() > 1e-9 * g {
                return Err(DataError::GammaNotConstant {
                    level: lvl(),
                    first: g,
                    value: r.gamma,
                });
            }
            let k = *group_of
                .entry((r.level.as_str(), r.direction))
                .or_insert_with(|| {
                    groups.push((r.level.clone(), r.direction, Vec::new()));
                    groups.len() - 1
                });
            groups[k].2.push(r);
        }
        // One level is accepted: the amplitude variation along one curve
        // can separate the terms. Whether it does is checked by the
        // equation-error stage, which names what cannot be separated.
        let mut curves = Vec::with_capacity(groups.len());
        for (level, direction, mut rows) in groups {
            rows.sort_by(|a, b| a.omega.total_cmp(&b.omega));
            for w in rows.windows(2) {
                if w[0].omega == w[1].omega {
                    return Err(DataError::DuplicateFrequency {
                        level,
                        direction: direction.name(),
                        f_hz: w[0].omega / TWO_PI,
                    });
                }
            }
            if rows.len() < 3 {
                return Err(DataError::TooFewFrequencies {
                    level,
                    direction: direction.name(),
                    count: rows.len(),
                });
            }
            let phases = rows
                .iter()
                .all(|r| r.phase.is_some())
                .then(|| rows.iter().map(|r| r.phase.unwrap()).collect());
            curves.push(Curve {
                gamma: rows[0].gamma,
                direction,
                omegas: rows.iter().map(|r| r.omega).collect(),
                amplitudes: rows.iter().map(|r| r.amplitude).collect(),
                phases,
                weights: rows.iter().map(|r| r.weight).collect(),
                level,
            });
        }
        Ok(Self { curves })
    }

    /// Total number of measured steps.
    pub fn len(&self) -> usize {
        self.curves.iter().map(|c| c.omegas.len()).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `f(index, curve)` for every curve, in parallel on the rayon pool,
    /// the results in data order. The curves wait in one queue, costliest
    /// first (most steps, then highest level: the folds and their searches
    /// are at the top levels), and each of the pool's threads takes the
    /// next one when it is free (greedy list scheduling), so that two cores
    /// finish together. rayon's own split of a list hands each core a
    /// contiguous half of it: with the costliest first, one core took
    /// every top level (measured on the 24 °C beam's generalised fit, 6 ×
    /// 1024 steps: the evaluations on every point used 1.67–1.69 of 2
    /// cores in data order, the same when sorted and split, 1.81–1.88 from
    /// the queue). Each result is a function of its curve alone, so the
    /// order changes no digit. The error returned is the one of the first
    /// failing curve in data order (as a sequential map's).
    pub(crate) fn map_curves<T, E, F>(&self, f: F) -> Result<Vec<T>, E>
    where
        T: Send,
        E: Send,
        F: Fn(usize, &Curve) -> Result<T, E> + Sync,
    {
        use rayon::prelude::*;
        let mut order: Vec<usize> = (0..self.curves.len()).collect();
        order.sort_by(|&i, &j| {
            let (a, b) = (&self.curves[i], &self.curves[j]);
            (b.omegas.len(), b.gamma)
                .partial_cmp(&(a.omegas.len(), a.gamma))
                .unwrap_or(std::cmp::Ordering::Equal)
                .then(i.cmp(&j))
        });
        // A shared queue in that order (greedy list scheduling: each task
        // takes the costliest curve not yet started). rayon's own split of
        // `order` would hand one core the first half, the top levels.
        let next = std::sync::atomic::AtomicUsize::new(0);
        let workers = rayon::current_num_threads().min(order.len()).max(1);
        let mut done: Vec<(usize, Result<T, E>)> = (0..workers)
            .into_par_iter()
            .with_max_len(1)
            .flat_map_iter(|_| {
                let mut mine = Vec::new();
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&i) = order.get(k) else { break };
                    mine.push((i, f(i, &self.curves[i])));
                }
                mine
            })
            .collect();
        done.sort_by_key(|(i, _)| *i);
        done.into_iter().map(|(_, r)| r).collect()
    }

    /// Distinct levels `(label, gamma)` in order of first appearance.
    pub fn levels(&self) -> Vec<(String, f64)> {
        let mut out: Vec<(String, f64)> = Vec::new();
        for c in &self.curves {
            if !out.iter().any(|(l, _)| *l == c.level) {
                out.push((c.level.clone(), c.gamma));
            }
        }
        out
    }
}

impl Curve {
    /// Index of the largest measured amplitude.
    pub fn peak_index(&self) -> usize {
        (0..self.amplitudes.len())
            .max_by(|&a, &b| self.amplitudes[a].total_cmp(&self.amplitudes[b]))
            .unwrap_or(0)
    }

    /// Measured jump frequency (rad/s): the step before the largest
    /// amplitude ratio between consecutive steps in sweep order (the last
    /// point on the branch that ends). `None` if no ratio exceeds
    /// `min_ratio`, or if `ln` of that ratio is less than [`DISTINCT_JUMP`]
    /// times `ln` of every step ratio of the opposite direction along the
    /// curve: on steps too coarse for the resonance (0.25 Hz at f_n = 10 Hz,
    /// ζ = 1 %) the rise into the peak and the fall after it are alike
    /// (ratios 2.24 up, 2.21 down on consecutive steps), the jump cannot be
    /// placed within a step, and a target one step off pulled exact data's
    /// fit to ρ = 1.963, η = 2.59 (truth 2, 3); the amplitudes alone then
    /// carry the fit.
    pub fn measured_jump(&self, min_ratio: f64) -> Option<f64> {
        let n = self.omegas.len();
        // every step in sweep order: (index it starts from, rises, ratio)
        let steps: Vec<(usize, bool, f64)> = (0..n - 1)
            .filter_map(|i| {
                let (from, to) = match self.direction {
                    SweepDirection::Up => (i, i + 1),
                    SweepDirection::Down => (i + 1, i),
                };
                let (a, b) = (self.amplitudes[from], self.amplitudes[to]);
                (a > 0.0 && b > 0.0).then(|| (from, b > a, (a / b).max(b / a)))
            })
            .collect();
        let mut best: Option<(f64, usize, bool)> = None;
        for &(from, rises, ratio) in &steps {
            if ratio > min_ratio && best.map_or(true, |(r, _, _)| ratio > r) {
                best = Some((ratio, from, rises));
            }
        }
        let (ratio, from, jump_rises) = best?;
        // A jump stands out from the changes the other way along the curve
        // (the rise into a jump-down, the fall after a jump-up), compared
        // in ln(ratio). On steps too coarse for the resonance the rise into
        // the peak and the fall after it are alike, and no step can be told
        // apart as the jump; the steep approach to a fold runs the same way
        // as the jump and does not count against it.
        let other_way = steps
            .iter()
            .filter(|&&(_, rises, _)| rises != jump_rises)
            .map(|&(_, _, r)| r)
            .fold(1.0f64, f64::max);
        (ratio.ln() >= DISTINCT_JUMP * other_way.ln()).then(|| self.omegas[from])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve(direction: SweepDirection, amplitudes: &[f64]) -> Curve {
        let n = amplitudes.len();
        Curve {
            level: "L".into(),
            gamma: 1.0,
            direction,
            omegas: (0..n).map(|i| 60.0 + i as f64).collect(),
            amplitudes: amplitudes.to_vec(),
            phases: None,
            weights: vec![1.0; n],
        }
    }

    /// `map_curves` starts the curves in another order than the data's; its
    /// results are a sequential map's (the oracle), in data order, and its
    /// error is that of the first failing curve in data order, whatever the
    /// thread count.
    #[test]
    fn map_curves_is_a_sequential_map_in_data_order() {
        let curves: Vec<Curve> = (0..9)
            .map(|k| {
                let mut c = curve(SweepDirection::Up, &vec![1.0; 3 + (k * 7) % 5]);
                c.gamma = 1.0 + (k * 4 % 9) as f64;
                c.level = format!("L{k}");
                c
            })
            .collect();
        let data = Dataset { curves };
        let f = |i: usize, c: &Curve| -> Result<(usize, String, usize), usize> {
            if c.gamma > 7.5 || c.gamma == 5.0 {
                Err(i)
            } else {
                Ok((i, c.level.clone(), c.omegas.len()))
            }
        };
        let sequential: Result<Vec<_>, usize> = data
            .curves
            .iter()
            .enumerate()
            .map(|(i, c)| f(i, c))
            .collect();
        for threads in [1, 2, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let got = pool.install(|| data.map_curves(f));
            assert_eq!(got, sequential, "{threads} threads");
            // (the first failing curve in data order is curve 1, γ 5)
            assert_eq!(got, Err(1));
            let ok = pool.install(|| data.map_curves(|i, c| Ok::<_, ()>((i, c.gamma))));
            let expect: Vec<(usize, f64)> = data
                .curves
                .iter()
                .enumerate()
                .map(|(i, c)| (i, c.gamma))
                .collect();
            assert_eq!(ok, Ok(expect));
        }
    }

    /// The queue of `map_curves` starts the costliest curve first: most
    /// steps, then the highest level, then data order (the oracle: that
    /// order sorted by hand). One thread takes the whole queue in turn; two
    /// threads start the first two and take the rest as they finish.
    #[test]
    fn map_curves_starts_the_costliest_curves_first() {
        let steps = [3, 5, 5, 4, 5, 3];
        let gammas = [1.0, 2.0, 7.0, 9.0, 2.0, 4.0];
        let curves: Vec<Curve> = (0..6)
            .map(|k| {
                let mut c = curve(SweepDirection::Up, &vec![1.0; steps[k]]);
                c.gamma = gammas[k];
                c
            })
            .collect();
        let data = Dataset { curves };
        // most steps (5: curves 1, 2, 4 by level 7, 2, 2, so 2, 1, 4), then
        // 4 steps (3), then 3 steps by level (5 then 0)
        let costliest_first = vec![2, 1, 4, 3, 5, 0];
        // the curves in the order they started on a pool of `threads`, each
        // taking `pause` once started
        let started_on = |threads: usize, pause: std::time::Duration| {
            let started = std::sync::Mutex::new(Vec::new());
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let got = pool.install(|| {
                data.map_curves(|i, _| {
                    started.lock().unwrap().push(i);
                    std::thread::sleep(pause);
                    Ok::<_, ()>(i)
                })
            });
            assert_eq!(got, Ok((0..6).collect::<Vec<_>>()), "{threads} threads");
            started.into_inner().unwrap()
        };
        assert_eq!(started_on(1, std::time::Duration::ZERO), costliest_first);
        // two threads: every curve once, the first two started before any
        // other (rayon's split of that order started 2 and 3; a thread
        // would have to stall 30 ms between taking a curve and starting it
        // for this to fail by chance)
        let order = started_on(2, std::time::Duration::from_millis(30));
        let mut sorted = order.clone();
        sorted.sort();
        assert_eq!(sorted, (0..6).collect::<Vec<_>>());
        let mut first_two = order[..2].to_vec();
        first_two.sort();
        assert_eq!(first_two, vec![1, 2]);
    }

    /// A clear drop (ratio 6 against rises of at most 1.3) is the jump, in
    /// either sweep direction, and so is a small jump-up approached by a
    /// steep rise (the approach runs the same way); a coarsely sampled peak
    /// whose rise into it matches the fall after it (the measured case:
    /// 2.24 up, 2.21 down) is not.
    #[test]
    fn measured_jump_must_stand_out_from_the_other_steps() {
        let up = [1.0, 1.2, 1.5, 1.9, 2.4, 0.4, 0.35, 0.3];
        let c = curve(SweepDirection::Up, &up);
        assert_eq!(c.measured_jump(2.0), Some(64.0));
        let mut down = up;
        down.reverse();
        let c = curve(SweepDirection::Down, &down);
        assert_eq!(c.measured_jump(2.0), Some(63.0));
        let coarse = [0.65, 1.18, 2.64, 1.20, 0.60, 0.40];
        let c = curve(SweepDirection::Up, &coarse);
        assert_eq!(c.measured_jump(2.0), None);
        // softening up-sweep: a steepening rise, a small jump up (1.53),
        // then a slow fall on the upper branch
        let soft = [1.0, 1.1, 1.25, 1.5, 2.1, 3.2, 3.0, 2.85, 2.7];
        let c = curve(SweepDirection::Up, &soft);
        assert_eq!(c.measured_jump(1.5), Some(64.0));
        // the same peak with one clear drop added stands out again
        let jump = [0.65, 1.18, 2.64, 0.20, 0.19, 0.18];
        let c = curve(SweepDirection::Up, &jump);
        assert_eq!(c.measured_jump(2.0), Some(62.0));
    }
}
