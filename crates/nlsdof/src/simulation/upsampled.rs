//! RK4 on a uniformly sampled input upsampled by cubic interpolation: two
//! fine samples per step (`h = 2/(factor fs)`), processed in chunks so that
//! the upsampled input never takes more than a few MB; the state is
//! reported at every original sample. This is the default of
//! `nlsdof simulate` on uniform sampling (the input read as a smooth curve
//! through the samples, at a step below the sampling interval).

use super::{simulate, Method, Options, Sample, State, Summary};
use crate::error::SimulationError;
use crate::excitation::{upsample_cubic, SampledInput};
use crate::model::AsNormalised;

/// Options of [`simulate_upsampled`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Upsampling {
    /// Fine samples per original sample (>= 1).
    pub factor: usize,
    /// State at the first sample.
    pub initial: State,
}

/// Simulates Eq 32 driven by `gain · values` sampled at `fs` Hz from `t0`
/// s (`grid = (gain, t0, fs)`), the input upsampled `opts.factor` times by
/// cubics; `sink` gets the state at every original sample (index `k`,
/// time of that sample).
pub fn simulate_upsampled(
    model: &(impl AsNormalised + ?Sized),
    values: &[f64],
    grid: (f64, f64, f64),
    opts: &Upsampling,
    sink: &mut dyn FnMut(Sample),
) -> Result<Summary, SimulationError> {
    let model = &model.as_normalised()?;
    const CHUNK: usize = 1 << 16;
    let (gain, t0, fs) = grid;
    let factor = opts.factor;
    if factor == 0 {
        return Err(SimulationError::InvalidOption {
            name: "upsampling factor",
            value: 0.0,
            reason: "must be >= 1",
        });
    }
    if values.is_empty() {
        return Err(SimulationError::EmptyInput);
    }
    let n = values.len();
    let mut total = Summary::default();
    let mut state = opts.initial;
    sink(Sample {
        index: 0,
        t: t0,
        u: gain * values[0],
        x: state.x,
        v: state.v,
    });
    let mut start = 0;
    while start + 1 < n {
        let end = (start + CHUNK).min(n - 1);
        let (lo, hi) = (start.saturating_sub(1), (end + 2).min(n - 1));
        let fine = upsample_cubic(&values[lo..=hi], factor);
        let part = &fine[(start - lo) * factor..=(end - lo) * factor];
        let inp = SampledInput::uniform(part, factor as f64 * fs, t0 + start as f64 / fs)?
            .with_gain(gain)?;
        let o = Options {
            method: Method::Rk4 {
                samples_per_step: 2,
            },
            initial: state,
            decimation: factor,
        };
        let s = simulate(model, &inp, &o, |smp: Sample| {
            if smp.index > 0 {
                sink(Sample {
                    index: start + smp.index / factor,
                    ..smp
                });
            }
        })?;
        state = s.final_state;
        total.steps += s.steps;
        total.rhs_evaluations += s.rhs_evaluations;
        total.events += s.events;
        total.samples_per_step = s.samples_per_step;
        total.final_time = t0 + end as f64 / fs;
        start = end;
    }
    total.samples = n;
    total.final_state = state;
    if n == 1 {
        total.final_time = t0;
    }
    Ok(total)
}
