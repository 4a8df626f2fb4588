//! Classical fixed-step RK4 for Eq 32 (see the parent module for how the
//! input is read between samples).

use super::coulomb::{self, Mode};
use super::law::{dispatch, Dyn, Law, MulAdd, NoFma, Visit};
use super::rk4_step::step;
use super::{is_coulomb, Options, Sample, SimulationError, State, Summary};
use crate::cancel::Cancel;
use crate::excitation::{Excitation, Grid, SampledInput};
use crate::model::NormalisedModel;

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
    cancel: Cancel,
    sink: F,
}

/// Samples between two polls of the cancel flag in an RK4 run over a
/// record (an atomic load; the results do not depend on it).
const CANCEL_EVERY: usize = 1 << 16;

/// A uniformly sampled record as the loops read it: the values, their gain,
/// the first sample time (s), the sampling rate (Hz), and the cancel flag
/// the run polls.
#[derive(Clone, Copy)]
struct Uniform<'v> {
    vals: &'v [f64],
    g: f64,
    t0: f64,
    fs: f64,
    cancel: Cancel,
}

impl<F: FnMut(Sample)> Visit for SampledRun<'_, '_, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let SampledRun {
            input,
            stride,
            opts,
            cancel,
            mut sink,
        } = self;
        let uniform = |t0, fs| Uniform {
            vals: input.raw(),
            g: input.gain(),
            t0,
            fs,
            cancel,
        };
        match (input.grid(), stride) {
            (Grid::Uniform { t0, fs }, 2) if S::SPECULATE || D::SPECULATE => {
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("fma")
                    && std::arch::is_x86_feature_detected!("avx2")
                {
                    // SAFETY: the CPU supports the features the function is compiled for.
                    return unsafe {
                        uniform2_predicted_fma(&d, uniform(t0, fs), &opts, &mut sink)
                    };
                }
                uniform2_predicted::<S, D, F, NoFma>(&d, uniform(t0, fs), &opts, &mut sink)
            }
            (Grid::Uniform { t0, fs }, 2) => uniform2(&d, uniform(t0, fs), &opts, &mut sink),
            (Grid::Uniform { t0, fs }, _) => uniform1(&d, uniform(t0, fs), &opts, &mut sink),
            (Grid::Times(_), 2) => Err(SimulationError::StrideNeedsUniformSampling {
                samples_per_step: 2,
            }),
            (Grid::Times(ts), _) => times1(&d, input, ts, &opts, cancel, &mut sink),
        }
    }
}

fn uniform1<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    rec: Uniform<'_>,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let Uniform {
        vals,
        g,
        t0,
        fs,
        cancel,
    } = rec;
    let h = 1.0 / fs;
    let n = vals.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = g * vals[0];
    sink(Sample {
        index: 0,
        t: t0,
        u: u0,
        x,
        v,
    });
    let mut outputs = 1;
    let mut dec = Decimator::new(opts.decimation);
    for (i, &ui) in vals.iter().enumerate().skip(1) {
        if i % CANCEL_EVERY == 0 {
            cancel.check()?;
        }
        let u1 = g * ui;
        let a1 = u0 - d.internal(x, v);
        (x, v) = step(d, x, v, a1, h, 0.5 * (u0 + u1), u1);
        if !(x.is_finite() && v.is_finite()) {
            return Err(diverged(t0 + i as f64 * h, x, v));
        }
        if dec.tick() {
            sink(Sample {
                index: i,
                t: t0 + i as f64 * h,
                u: u1,
                x,
                v,
            });
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

/// Output bookkeeping shared by the two-samples-per-step drivers
/// ([`uniform2`], [`uniform2_predicted`]): emission of the mid-step sample
/// (cubic Hermite interpolation at the half step) and of the step end, and
/// the final single-sample step when the number of intervals is odd.
struct TwoSampleOutput {
    dec: Decimator,
    outputs: usize,
    t0: f64,
    dt: f64,
}

impl TwoSampleOutput {
    /// The initial sample has been emitted by the caller.
    fn new(decimation: usize, t0: f64, dt: f64) -> Self {
        Self {
            dec: Decimator::new(decimation),
            outputs: 1,
            t0,
            dt,
        }
    }

    /// Emits samples `i + 1` (Hermite midpoint
    /// `x_m = (x + x_n)/2 + h/8 (v − v_n)`, `v_m = (v + v_n)/2 + h/8 (a − a_n)`)
    /// and `i + 2` (step end), subject to decimation.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn emit_pair<M: MulAdd, F: FnMut(Sample)>(
        &mut self,
        sink: &mut F,
        i: usize,
        (um, u1): (f64, f64),
        (x, v, a0): (f64, f64, f64),
        (xn, vn, an): (f64, f64, f64),
        h8: f64,
    ) {
        let (t0, dt) = (self.t0, self.dt);
        if self.dec.tick() {
            sink(Sample {
                index: i + 1,
                t: t0 + (i + 1) as f64 * dt,
                u: um,
                x: M::madd(0.5, x + xn, h8 * (v - vn)),
                v: M::madd(0.5, v + vn, h8 * (a0 - an)),
            });
            self.outputs += 1;
        }
        if self.dec.tick() {
            sink(Sample {
                index: i + 2,
                t: t0 + (i + 2) as f64 * dt,
                u: u1,
                x: xn,
                v: vn,
            });
            self.outputs += 1;
        }
    }

    /// After the paired steps ended at sample `i` (input `u0`, state
    /// `x, v, a0`): one last single-sample step if an interval is left
    /// (odd number of intervals), then the summary.
    #[allow(clippy::too_many_arguments)]
    fn finish<S: Law, D: Law, F: FnMut(Sample)>(
        mut self,
        d: &Dyn<S, D>,
        vals: &[f64],
        g: f64,
        (i, u0): (usize, f64),
        (mut x, mut v, a0): (f64, f64, f64),
        mut rhs: u64,
        sink: &mut F,
    ) -> Result<Summary, SimulationError> {
        let (t0, dt, n) = (self.t0, self.dt, vals.len());
        let mut steps = (i / 2) as u64;
        rhs += 4 * steps;
        if i + 1 < n {
            let u1 = g * vals[i + 1];
            (x, v) = step(d, x, v, a0, dt, 0.5 * (u0 + u1), u1);
            if !(x.is_finite() && v.is_finite()) {
                return Err(diverged(t0 + (i + 1) as f64 * dt, x, v));
            }
            steps += 1;
            rhs += 3;
            if self.dec.tick() {
                sink(Sample {
                    index: i + 1,
                    t: t0 + (i + 1) as f64 * dt,
                    u: u1,
                    x,
                    v,
                });
                self.outputs += 1;
            }
        }
        Ok(Summary {
            samples: n,
            outputs: self.outputs,
            steps,
            rejected_steps: 0,
            rhs_evaluations: rhs,
            events: 0,
            samples_per_step: 2,
            final_state: State { x, v },
            final_time: t0 + (n - 1) as f64 * dt,
        })
    }
}

fn uniform2<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    rec: Uniform<'_>,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let Uniform {
        vals,
        g,
        t0,
        fs,
        cancel,
    } = rec;
    let dt = 1.0 / fs;
    let h = 2.0 * dt;
    let h8 = 0.125 * h;
    let n = vals.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = g * vals[0];
    sink(Sample {
        index: 0,
        t: t0,
        u: u0,
        x,
        v,
    });
    let mut out = TwoSampleOutput::new(opts.decimation, t0, dt);
    // a0 = acceleration at the current step start; the end acceleration of
    // one step is the first stage of the next (first same as last).
    let mut a0 = u0 - d.internal(x, v);
    // one evaluation for the initial acceleration
    let rhs: u64 = 1;
    let mut i = 0;
    while i + 2 < n {
        if i % CANCEL_EVERY == 0 {
            cancel.check()?;
        }
        let um = g * vals[i + 1];
        let u1 = g * vals[i + 2];
        let (xn, vn) = step(d, x, v, a0, h, um, u1);
        let an = u1 - d.internal(xn, vn);
        if !(xn.is_finite() && vn.is_finite() && an.is_finite()) {
            return Err(diverged(t0 + (i + 2) as f64 * dt, xn, vn));
        }
        out.emit_pair::<NoFma, F>(sink, i, (um, u1), (x, v, a0), (xn, vn, an), h8);
        x = xn;
        v = vn;
        a0 = an;
        u0 = u1;
        i += 2;
    }
    out.finish(d, vals, g, (i, u0), (x, v, a0), rhs, sink)
}

/// Stage of [`uniform2_predicted`]: `u − f(x, v)` with the power laws
/// continued from references.
#[inline(always)]
fn accel_near<S: Law, D: Law, M: MulAdd>(
    d: &Dyn<S, D>,
    u: f64,
    x: f64,
    v: f64,
    rx: &S::Ref,
    rv: &D::Ref,
) -> f64 {
    u - d.internal_near::<M>(x, v, rx, rv)
}

/// [`uniform2_predicted`] compiled with fused multiply–add and AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn uniform2_predicted_fma<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    rec: Uniform<'_>,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    uniform2_predicted::<S, D, F, super::law::HwFma>(d, rec, opts, sink)
}

/// [`uniform2`] for real exponents, with the powers taken off the critical
/// path. Each RK4 step evaluates the right-hand side at three times (start,
/// middle, end); the powers at the middle and the end of the step after
/// next are evaluated *now* at values predicted by a Taylor extrapolation
/// of the new state (`x̂ = x + τv + τ²a/2 + τ³ȧ/6 + τ⁴ä/24`,
/// `v̂ = v + τa + τ²ȧ/2 + τ³ä/6`, τ = 3h/2 and 2h, with ȧ, ä from the
/// accelerations at the start, middle and end of the step just taken), so
/// their latency overlaps a whole step; the stage then
/// needs only the binomial continuation [`Law::f_near`] (`|ε| ≲ 1e-4` in
/// practice; exact evaluation otherwise). Results agree with [`uniform2`]
/// to rounding (tested).
#[inline(always)]
fn uniform2_predicted<S: Law, D: Law, F: FnMut(Sample), M: MulAdd>(
    d: &Dyn<S, D>,
    rec: Uniform<'_>,
    opts: &Options,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let Uniform {
        vals,
        g,
        t0,
        fs,
        cancel,
    } = rec;
    let dt = 1.0 / fs;
    let h = 2.0 * dt;
    let h8 = 0.125 * h;
    let State { mut x, mut v } = opts.initial;
    let mut u0 = g * vals[0];
    sink(Sample {
        index: 0,
        t: t0,
        u: u0,
        x,
        v,
    });
    let mut out = TwoSampleOutput::new(opts.decimation, t0, dt);
    let mut a0 = u0 - d.internal(x, v);
    // one evaluation for the initial acceleration
    let rhs: u64 = 1;
    // references for (middle, end) of the current step and of the next one
    let (mut cur_m, mut cur_e) = (
        (d.s.make_ref(x), d.d.make_ref(v)),
        (d.s.make_ref(x), d.d.make_ref(v)),
    );
    let (mut nxt_m, mut nxt_e) = (cur_m, cur_e);
    let mut i = 0;
    for pair in vals[1..].chunks_exact(2) {
        if i % CANCEL_EVERY == 0 {
            cancel.check()?;
        }
        let um = g * pair[0];
        let u1 = g * pair[1];
        // classical RK4 stages, powers continued from the references
        let hh = 0.5 * h;
        let x2 = M::madd(hh, v, x);
        let v2 = M::madd(hh, a0, v);
        let a2 = accel_near::<S, D, M>(d, um, x2, v2, &cur_m.0, &cur_m.1);
        let x3 = M::madd(hh, v2, x);
        let v3 = M::madd(hh, a2, v);
        let a3 = accel_near::<S, D, M>(d, um, x3, v3, &cur_m.0, &cur_m.1);
        let x4 = M::madd(h, v3, x);
        let v4 = M::madd(h, a3, v);
        let a4 = accel_near::<S, D, M>(d, u1, x4, v4, &cur_e.0, &cur_e.1);
        let h6 = h * (1.0 / 6.0);
        let xn = M::madd(h6, M::madd(2.0, v2 + v3, v + v4), x);
        let vn = M::madd(h6, M::madd(2.0, a2 + a3, a0 + a4), v);
        let an = accel_near::<S, D, M>(d, u1, xn, vn, &cur_e.0, &cur_e.1);
        if !(xn.is_finite() && vn.is_finite() && an.is_finite()) {
            return Err(diverged(t0 + (i + 2) as f64 * dt, xn, vn));
        }
        // predict the middle and end of the step after next (τ = 3h/2, 2h
        // from the new state) and evaluate their powers now
        let amid = 0.5 * (a2 + a3);
        let jerk = (3.0 * an - 4.0 * amid + a0) / h;
        let snap = 4.0 * (an - 2.0 * amid + a0) / (h * h);
        let predict = |tau: f64| {
            let t2 = tau * tau * 0.5;
            let t3 = t2 * tau * (1.0 / 3.0);
            let t4 = t3 * tau * 0.25;
            (
                M::madd(tau, vn, xn) + M::madd(t2, an, M::madd(t3, jerk, t4 * snap)),
                M::madd(tau, an, vn) + M::madd(t2, jerk, t3 * snap),
            )
        };
        let (xm, vm) = predict(1.5 * h);
        let (xe, ve) = predict(2.0 * h);
        cur_m = nxt_m;
        cur_e = nxt_e;
        (nxt_m, nxt_e) = d.make_refs::<M>(xm, xe, vm, ve);
        out.emit_pair::<M, F>(sink, i, (um, u1), (x, v, a0), (xn, vn, an), h8);
        x = xn;
        v = vn;
        a0 = an;
        u0 = u1;
        i += 2;
    }
    out.finish(d, vals, g, (i, u0), (x, v, a0), rhs, sink)
}

fn times1<S: Law, D: Law, F: FnMut(Sample)>(
    d: &Dyn<S, D>,
    input: &SampledInput<'_>,
    ts: &[f64],
    opts: &Options,
    cancel: Cancel,
    sink: &mut F,
) -> Result<Summary, SimulationError> {
    let n = ts.len();
    let State { mut x, mut v } = opts.initial;
    let mut u0 = input.value(0);
    sink(Sample {
        index: 0,
        t: ts[0],
        u: u0,
        x,
        v,
    });
    let mut outputs = 1;
    let mut dec = Decimator::new(opts.decimation);
    for i in 1..n {
        if i % CANCEL_EVERY == 0 {
            cancel.check()?;
        }
        let u1 = input.value(i);
        let h = ts[i] - ts[i - 1];
        let a1 = u0 - d.internal(x, v);
        (x, v) = step(d, x, v, a1, h, 0.5 * (u0 + u1), u1);
        if !(x.is_finite() && v.is_finite()) {
            return Err(diverged(ts[i], x, v));
        }
        if dec.tick() {
            sink(Sample {
                index: i,
                t: ts[i],
                u: u1,
                x,
                v,
            });
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
    cancel: Cancel,
    sink: F,
}

impl<F: FnMut(Sample)> Visit for CoulombSampled<'_, '_, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let CoulombSampled {
            input,
            kappa,
            opts,
            cancel,
            mut sink,
        } = self;
        let n = input.len();
        let State { mut x, mut v } = opts.initial;
        let mut mode = coulomb::initial_mode(&d, kappa, x, v, input.value(0));
        sink(Sample {
            index: 0,
            t: input.time(0),
            u: input.value(0),
            x,
            v,
        });
        let mut sum = Summary {
            samples: n,
            outputs: 1,
            samples_per_step: 1,
            ..Default::default()
        };
        let mut dec = Decimator::new(opts.decimation);
        for i in 1..n {
            if i % CANCEL_EVERY == 0 {
                cancel.check()?;
            }
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
                sink(Sample {
                    index: i,
                    t: tb,
                    u: ub,
                    x,
                    v,
                });
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
    cancel: Cancel,
    sink: F,
) -> Result<Summary, SimulationError> {
    if is_coulomb(model) {
        dispatch(
            model,
            true,
            CoulombSampled {
                input,
                kappa: model.kappa,
                opts: *opts,
                cancel,
                sink,
            },
        )
    } else {
        dispatch(
            model,
            false,
            SampledRun {
                input,
                stride,
                opts: *opts,
                cancel,
                sink,
            },
        )
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
        let ExcitationRun {
            exc,
            t0,
            dt,
            n,
            coulomb,
            opts,
            mut sink,
        } = self;
        let State { mut x, mut v } = opts.initial;
        let mut mode = coulomb
            .map(|k| coulomb::initial_mode(&d, k, x, v, exc.accel(t0)))
            .unwrap_or(Mode::Stick);
        sink(Sample {
            index: 0,
            t: t0,
            u: exc.accel(t0),
            x,
            v,
        });
        let mut sum = Summary {
            samples: n,
            outputs: 1,
            samples_per_step: 1,
            ..Default::default()
        };
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
                sink(Sample {
                    index: i,
                    t: tb,
                    u: exc.accel(tb),
                    x,
                    v,
                });
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
    dispatch(
        model,
        coulomb.is_some(),
        ExcitationRun {
            exc,
            t0,
            dt,
            n,
            coulomb,
            opts: *opts,
            sink,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::law::{Absent, IntLaw, RealLaw};

    fn run_both<S: Law, D: Law>(d: Dyn<S, D>, u: &[f64], fs: f64) {
        let opts = Options::default();
        let rec = Uniform {
            vals: u,
            g: 1.0,
            t0: 0.0,
            fs,
            cancel: Cancel::NEVER,
        };
        let (mut a, mut b, mut c) = (vec![], vec![], vec![]);
        uniform2(&d, rec, &opts, &mut |s: Sample| a.push((s.x, s.v))).unwrap();
        uniform2_predicted::<S, D, _, NoFma>(&d, rec, &opts, &mut |s: Sample| b.push((s.x, s.v)))
            .unwrap();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("fma") && std::arch::is_x86_feature_detected!("avx2")
        {
            unsafe { uniform2_predicted_fma(&d, rec, &opts, &mut |s: Sample| c.push((s.x, s.v))) }
                .unwrap();
        }
        let sx = a.iter().fold(0.0f64, |m, p| m.max(p.0.abs()));
        let sv = a.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
        for other in [&b, &c] {
            if other.is_empty() {
                continue;
            }
            assert_eq!(other.len(), a.len());
            let ex = a
                .iter()
                .zip(other.iter())
                .map(|(p, q)| (p.0 - q.0).abs())
                .fold(0.0, f64::max)
                / sx;
            let ev = a
                .iter()
                .zip(other.iter())
                .map(|(p, q)| (p.1 - q.1).abs())
                .fold(0.0, f64::max)
                / sv;
            assert!(
                ex < 1e-11 && ev < 1e-11,
                "predicted vs direct: {ex:e} {ev:e}"
            );
        }
    }

    /// The powers-off-the-critical-path loop reproduces the direct loop to
    /// rounding, for real exponents of both signs and sizes, through many
    /// zero crossings of x and v (where it falls back to direct powers),
    /// with and without fused multiply-add.
    #[test]
    fn predicted_powers_match_direct_evaluation() {
        let fs = 2048.0;
        let mut s: u64 = 99;
        let u: Vec<f64> = (0..60_000)
            .map(|k| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
                0.6 * (std::f64::consts::TAU * 5.4 * k as f64 / fs).sin() + 0.05 * noise
            })
            .collect();
        let (alpha, delta) = (306.7878 / 0.26699, 0.1164 / 0.26699);
        for &(rho, eta) in &[
            (4.0022, 3.03099),
            (0.37, 1.5),
            (7.25, 0.5),
            (-0.5, -0.5),
            (2.5, 25.3),
        ] {
            let beta = 85000.0 / 0.26699 * 0.04f64.powf(4.0 - rho);
            let kappa = 0.01591 / 0.26699;
            run_both(
                Dyn {
                    alpha,
                    delta,
                    s: RealLaw::new(beta, rho),
                    d: RealLaw::new(kappa, eta),
                },
                &u,
                fs,
            );
            run_both(
                Dyn {
                    alpha,
                    delta,
                    s: IntLaw { c: beta, n: 4 },
                    d: RealLaw::new(kappa, eta),
                },
                &u,
                fs,
            );
            run_both(
                Dyn {
                    alpha,
                    delta,
                    s: RealLaw::new(beta, rho),
                    d: Absent,
                },
                &u,
                fs,
            );
        }
    }
}
