//! Classical fixed-step RK4 for Eq 32 (see the parent module for how the
//! input is read between samples).

use super::coulomb::{self, Mode};
use super::law::{dispatch, Dyn, Law, Visit};
use super::{is_coulomb, Options, Sample, SimulationError, State, Summary};
use crate::excitation::{Excitation, Grid, SampledInput};
use crate::model::NormalisedModel;

/// One classical RK4 step of size `h` from `(x, v)` with `a1 = u0 − f(x, v)`
/// already known, stage inputs `um` (t + h/2) and `u1` (t + h):
///
/// ```text
/// k1 = (v, a1)
/// k2 = f(t+h/2, y + h/2 k1),  k3 = f(t+h/2, y + h/2 k2),  k4 = f(t+h, y + h k3)
/// y₁ = y + h/6 (k1 + 2k2 + 2k3 + k4)
/// ```
#[inline(always)]
pub(crate) fn step<S: Law, D: Law>(d: &Dyn<S, D>, x: f64, v: f64, a1: f64, h: f64, um: f64, u1: f64) -> (f64, f64) {
    let hh = 0.5 * h;
    let x2 = x + hh * v;
    let v2 = v + hh * a1;
    let a2 = um - d.internal(x2, v2);
    let x3 = x + hh * v2;
    let v3 = v + hh * a2;
    let a3 = um - d.internal(x3, v3);
    let x4 = x + h * v3;
    let v4 = v + h * a3;
    let a4 = u1 - d.internal(x4, v4);
    let h6 = h * (1.0 / 6.0);
    (x + h6 * (v + 2.0 * (v2 + v3) + v4), v + h6 * (a1 + 2.0 * (a2 + a3) + a4))
}

#[cold]
fn diverged(t: f64, x: f64, v: f64) -> SimulationError {
    SimulationError::Diverged { t, x, v }
}

/// Emits every `decim`-th index with a countdown (no division per step).
struct Decimator {
    decim: usize,
    left: usize,
}

impl Decimator {
    fn new(decim: usize) -> Self {
        Self { decim, left: decim }
    }
    /// Called once per index after 0; true when this index is emitted.
    #[inline(always)]
    fn tick(&mut self) -> bool {
        self.left -= 1;
        if self.left == 0 {
            self.left = self.decim;
            true
        } else {
            false
        }
    }
}

struct SampledRun<'i, 'a, F> {
    input: &'i SampledInput<'a>,
    stride: usize,
    opts: Options,
    sink: F,
}

impl<F: FnMut(Sample)> Visit for SampledRun<'_, '_, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let SampledRun { input, stride, opts, mut sink } = self;
        match (input.grid(), stride) {
            (Grid::Uniform { t0, fs }, 2) => uniform2(&d, input.raw(), input.gain(), t0, fs, &opts, &mut sink),
            (Grid::Uniform { t0, fs }, _) => uniform1(&d, input.raw(), input.gain(), t0, fs, &opts, &mut sink),
            (Grid::Times(_), 2) => Err(SimulationError::StrideNeedsUniformSampling { samples_per_step: 2 }),
            (Grid::Times(ts), _) => times1(&d, input, ts, &opts, &mut sink),
        }
    }
}

fn uniform1<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    vals: &[f64],
    g: f64,
    t0: f64,
    fs: f64,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let h = 1.0 / fs;
    let n = vals.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = g * vals[0];
    sink(Sample { index: 0, t: t0, u: u0, x, v });
    let mut outputs = 1;
    let mut dec = Decimator::new(opts.decimation);
    for i in 1..n {
        let u1 = g * vals[i];
        let a1 = u0 - d.internal(x, v);
        (x, v) = step(d, x, v, a1, h, 0.5 * (u0 + u1), u1);
        if !(x.is_finite() && v.is_finite()) {
            return Err(diverged(t0 + i as f64 * h, x, v));
        }
        if dec.tick() {
            sink(Sample { index: i, t: t0 + i as f64 * h, u: u1, x, v });
            outputs += 1;
        }
        u0 = u1;
    }
    let steps = (n - 1) as u64;
    Ok(Summary {
        samples: n,
        outputs,
        steps,
        rejected_steps: 0,
        rhs_evaluations: 4 * steps,
        events: 0,
        samples_per_step: 1,
        final_state: State { x, v },
        final_time: t0 + (n - 1) as f64 * h,
    })
}

fn uniform2<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    vals: &[f64],
    g: f64,
    t0: f64,
    fs: f64,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let dt = 1.0 / fs;
    let h = 2.0 * dt;
    let h8 = 0.125 * h;
    let n = vals.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = g * vals[0];
    sink(Sample { index: 0, t: t0, u: u0, x, v });
    let mut outputs = 1;
    let mut dec = Decimator::new(opts.decimation);
    // a0 = acceleration at the current step start; the end acceleration of
    // one step is the first stage of the next (first same as last).
    let mut a0 = u0 - d.internal(x, v);
    let mut rhs: u64 = 1;
    let mut i = 0;
    while i + 2 < n {
        let um = g * vals[i + 1];
        let u1 = g * vals[i + 2];
        let (xn, vn) = step(d, x, v, a0, h, um, u1);
        let an = u1 - d.internal(xn, vn);
        if !(xn.is_finite() && vn.is_finite() && an.is_finite()) {
            return Err(diverged(t0 + (i + 2) as f64 * dt, xn, vn));
        }
        if dec.tick() {
            let xm = 0.5 * (x + xn) + h8 * (v - vn);
            let vm = 0.5 * (v + vn) + h8 * (a0 - an);
            sink(Sample { index: i + 1, t: t0 + (i + 1) as f64 * dt, u: um, x: xm, v: vm });
            outputs += 1;
        }
        if dec.tick() {
            sink(Sample { index: i + 2, t: t0 + (i + 2) as f64 * dt, u: u1, x: xn, v: vn });
            outputs += 1;
        }
        x = xn;
        v = vn;
        a0 = an;
        u0 = u1;
        i += 2;
    }
    let mut steps = (i / 2) as u64;
    rhs += 4 * steps;
    if i + 1 < n {
        // odd number of intervals: one last single-sample step
        let u1 = g * vals[i + 1];
        (x, v) = step(d, x, v, a0, dt, 0.5 * (u0 + u1), u1);
        if !(x.is_finite() && v.is_finite()) {
            return Err(diverged(t0 + (i + 1) as f64 * dt, x, v));
        }
        steps += 1;
        rhs += 3;
        if dec.tick() {
            sink(Sample { index: i + 1, t: t0 + (i + 1) as f64 * dt, u: u1, x, v });
            outputs += 1;
        }
    }
    Ok(Summary {
        samples: n,
        outputs,
        steps,
        rejected_steps: 0,
        rhs_evaluations: rhs,
        events: 0,
        samples_per_step: 2,
        final_state: State { x, v },
        final_time: t0 + (n - 1) as f64 * dt,
    })
}

fn times1<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    input: &SampledInput<'_>,
    ts: &[f64],
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let n = ts.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = input.value(0);
    sink(Sample { index: 0, t: ts[0], u: u0, x, v });
    let mut outputs = 1;
    let mut dec = Decimator::new(opts.decimation);
    for i in 1..n {
        let u1 = input.value(i);
        let h = ts[i] - ts[i - 1];
        let a1 = u0 - d.internal(x, v);
        (x, v) = step(d, x, v, a1, h, 0.5 * (u0 + u1), u1);
        if !(x.is_finite() && v.is_finite()) {
            return Err(diverged(ts[i], x, v));
        }
        if dec.tick() {
            sink(Sample { index: i, t: ts[i], u: u1, x, v });
            outputs += 1;
        }
        u0 = u1;
    }
    let steps = (n - 1) as u64;
    Ok(Summary {
        samples: n,
        outputs,
        steps,
        rejected_steps: 0,
        rhs_evaluations: 4 * steps,
        events: 0,
        samples_per_step: 1,
        final_state: State { x, v },
        final_time: ts[n - 1],
    })
}

/// Coulomb friction, one step per sample interval with event handling.
struct CoulombSampled<'i, 'a, F> {
    input: &'i SampledInput<'a>,
    kappa: f64,
    opts: Options,
    sink: F,
}

impl<F: FnMut(Sample)> Visit for CoulombSampled<'_, '_, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let CoulombSampled { input, kappa, opts, mut sink } = self;
        let n = input.len();
        let State { mut x, mut v } = opts.initial;
        let mut mode = coulomb::initial_mode(&d, kappa, x, v, input.value(0));
        sink(Sample { index: 0, t: input.time(0), u: input.value(0), x, v });
        let mut sum = Summary { samples: n, outputs: 1, samples_per_step: 1, ..Default::default() };
        let mut dec = Decimator::new(opts.decimation);
        for i in 1..n {
            let (ta, tb) = (input.time(i - 1), input.time(i));
            let (ua, ub) = (input.value(i - 1), input.value(i));
            let h = tb - ta;
            let slope = (ub - ua) / h;
            let u = |tau: f64| ua + slope * tau;
            coulomb::rk4_interval(&d, kappa, h, &u, ta, &mut x, &mut v, &mut mode, &mut sum)?;
            if !(x.is_finite() && v.is_finite()) {
                return Err(diverged(tb, x, v));
            }
            if dec.tick() {
                sink(Sample { index: i, t: tb, u: ub, x, v });
                sum.outputs += 1;
            }
        }
        sum.final_state = State { x, v };
        sum.final_time = input.time(n - 1);
        Ok(sum)
    }
}

pub(crate) fn simulate_sampled<F: FnMut(Sample)>(
    model: &NormalisedModel,
    input: &SampledInput<'_>,
    stride: usize,
    opts: &Options,
    sink: F,
) -> Result<Summary, SimulationError> {
    if is_coulomb(model) {
        dispatch(model, true, CoulombSampled { input, kappa: model.kappa, opts: *opts, sink })
    } else {
        dispatch(model, false, SampledRun { input, stride, opts: *opts, sink })
    }
}

struct ExcitationRun<'e, E: ?Sized, F> {
    exc: &'e E,
    t0: f64,
    dt: f64,
    n: usize,
    /// Some(κ) for Coulomb friction.
    coulomb: Option<f64>,
    opts: Options,
    sink: F,
}

impl<E: Excitation + ?Sized, F: FnMut(Sample)> Visit for ExcitationRun<'_, E, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let ExcitationRun { exc, t0, dt, n, coulomb, opts, mut sink } = self;
        let State { mut x, mut v } = opts.initial;
        let mut mode = coulomb.map(|k| coulomb::initial_mode(&d, k, x, v, exc.accel(t0))).unwrap_or(Mode::Stick);
        sink(Sample { index: 0, t: t0, u: exc.accel(t0), x, v });
        let mut sum = Summary { samples: n, outputs: 1, samples_per_step: 1, ..Default::default() };
        let mut dec = Decimator::new(opts.decimation);
        for i in 1..n {
            let ta = t0 + (i - 1) as f64 * dt;
            let tb = t0 + i as f64 * dt;
            let h = tb - ta;
            if let Some(kappa) = coulomb {
                let u = |tau: f64| exc.accel(ta + tau);
                coulomb::rk4_interval(&d, kappa, h, &u, ta, &mut x, &mut v, &mut mode, &mut sum)?;
            } else {
                let a1 = exc.accel(ta) - d.internal(x, v);
                (x, v) = step(&d, x, v, a1, h, exc.accel(ta + 0.5 * h), exc.accel(tb));
                sum.steps += 1;
                sum.rhs_evaluations += 4;
            }
            if !(x.is_finite() && v.is_finite()) {
                return Err(diverged(tb, x, v));
            }
            if dec.tick() {
                sink(Sample { index: i, t: tb, u: exc.accel(tb), x, v });
                sum.outputs += 1;
            }
        }
        sum.final_state = State { x, v };
        sum.final_time = t0 + (n - 1) as f64 * dt;
        Ok(sum)
    }
}

pub(crate) fn simulate_excitation<E: Excitation + ?Sized, F: FnMut(Sample)>(
    model: &NormalisedModel,
    exc: &E,
    t0: f64,
    dt: f64,
    n: usize,
    opts: &Options,
    sink: F,
) -> Result<Summary, SimulationError> {
    let coulomb = is_coulomb(model).then_some(model.kappa);
    dispatch(model, coulomb.is_some(), ExcitationRun { exc, t0, dt, n, coulomb, opts: *opts, sink })
}
