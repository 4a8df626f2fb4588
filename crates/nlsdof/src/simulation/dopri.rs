//! Adaptive Dormand–Prince 5(4) with the 4th-order continuous extension,
//! the accuracy reference. Restarted at every sample (or output) time: no
//! step crosses one, so the kink of a piecewise-linear input never sits
//! inside a step (the error estimator would not see it).

use super::coulomb::{self, breakaway, illinois, Mode};
use super::law::{dispatch, Dyn, Law, Visit};
use super::{is_coulomb, Options, Sample, SimulationError, State, Summary};
use crate::cancel::Cancel;
use crate::excitation::{Excitation, SampledInput};
use crate::model::NormalisedModel;

// Butcher tableau (Dormand & Prince 1980).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// error coefficients b − b̂ (5th minus embedded 4th order)
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// continuous extension (Hairer, Nørsett & Wanner, dense output of DOPRI5)
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Result of one trial step: 5th-order solution, error estimate, stages.
struct Trial {
    x: f64,
    v: f64,
    ex: f64,
    ev: f64,
    /// stage derivatives (x' = v stage, v' = a stage)
    #[cfg_attr(not(test), allow(dead_code))]
    kx: [f64; 7],
    ka: [f64; 7],
}

/// One Dormand–Prince step of size `h` from `(t, x, v)`; `a1` is the
/// acceleration at the start; `fr` a constant friction offset.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trial<S: Law, D: Law, U: Fn(f64) -> f64>(
    d: &Dyn<S, D>,
    u: &U,
    fr: f64,
    t: f64,
    x: f64,
    v: f64,
    a1: f64,
    h: f64,
) -> Trial {
    let f = |tt: f64, xx: f64, vv: f64| u(tt) - fr - d.internal(xx, vv);
    let (k1x, k1a) = (v, a1);
    let (x2, v2) = (x + h * A21 * k1x, v + h * A21 * k1a);
    let (k2x, k2a) = (v2, f(t + C2 * h, x2, v2));
    let (x3, v3) = (
        x + h * (A31 * k1x + A32 * k2x),
        v + h * (A31 * k1a + A32 * k2a),
    );
    let (k3x, k3a) = (v3, f(t + C3 * h, x3, v3));
    let (x4, v4) = (
        x + h * (A41 * k1x + A42 * k2x + A43 * k3x),
        v + h * (A41 * k1a + A42 * k2a + A43 * k3a),
    );
    let (k4x, k4a) = (v4, f(t + C4 * h, x4, v4));
    let x5s = x + h * (A51 * k1x + A52 * k2x + A53 * k3x + A54 * k4x);
    let v5s = v + h * (A51 * k1a + A52 * k2a + A53 * k3a + A54 * k4a);
    let (k5x, k5a) = (v5s, f(t + C5 * h, x5s, v5s));
    let x6 = x + h * (A61 * k1x + A62 * k2x + A63 * k3x + A64 * k4x + A65 * k5x);
    let v6 = v + h * (A61 * k1a + A62 * k2a + A63 * k3a + A64 * k4a + A65 * k5a);
    let (k6x, k6a) = (v6, f(t + h, x6, v6));
    let xn = x + h * (B1 * k1x + B3 * k3x + B4 * k4x + B5 * k5x + B6 * k6x);
    let vn = v + h * (B1 * k1a + B3 * k3a + B4 * k4a + B5 * k5a + B6 * k6a);
    let (k7x, k7a) = (vn, f(t + h, xn, vn));
    let ex = h * (E1 * k1x + E3 * k3x + E4 * k4x + E5 * k5x + E6 * k6x + E7 * k7x);
    let ev = h * (E1 * k1a + E3 * k3a + E4 * k4a + E5 * k5a + E6 * k6a + E7 * k7a);
    Trial {
        x: xn,
        v: vn,
        ex,
        ev,
        kx: [k1x, k2x, k3x, k4x, k5x, k6x, k7x],
        ka: [k1a, k2a, k3a, k4a, k5a, k6a, k7a],
    }
}

/// Dense output of one component at `θ ∈ [0, 1]` of an accepted step.
fn dense(y0: f64, y1: f64, k: &[f64; 7], h: f64, theta: f64) -> f64 {
    let ydiff = y1 - y0;
    let bspl = h * k[0] - ydiff;
    let r4 = ydiff - h * k[6] - bspl;
    let r5 = h * (D1 * k[0] + D3 * k[2] + D4 * k[3] + D5 * k[4] + D6 * k[5] + D7 * k[6]);
    let t1 = 1.0 - theta;
    y0 + theta * (ydiff + t1 * (bspl + theta * (r4 + t1 * r5)))
}

/// Integrator state carried across restarts.
struct Dp<'d, S, D> {
    d: &'d Dyn<S, D>,
    rtol: f64,
    atol_x: f64,
    atol_v: f64,
    t: f64,
    x: f64,
    v: f64,
    /// acceleration at (t, x, v) for the current friction offset
    a: f64,
    /// proposed next step
    h: f64,
    /// Some(κ) for Coulomb friction
    kappa: Option<f64>,
    mode: Mode,
}

impl<S: Law, D: Law> Dp<'_, S, D> {
    fn fr(&self) -> f64 {
        match (self.kappa, self.mode) {
            (Some(k), Mode::Slip(s)) => k * s,
            _ => 0.0,
        }
    }

    fn refresh_accel<U: Fn(f64) -> f64>(&mut self, u: &U, sum: &mut Summary) {
        self.a = u(self.t) - self.fr() - self.d.internal(self.x, self.v);
        sum.rhs_evaluations += 1;
    }

    /// Integrates to `t_end` (input `u` smooth on `[t, t_end]`).
    fn advance<U: Fn(f64) -> f64>(
        &mut self,
        t_end: f64,
        u: &U,
        sum: &mut Summary,
    ) -> Result<(), SimulationError> {
        let mut rejected_last = false;
        let mut events = 0usize;
        while self.t < t_end {
            if let (Some(kappa), Mode::Stick) = (self.kappa, self.mode) {
                let r = self.d.restoring(self.x);
                sum.rhs_evaluations += 2;
                match breakaway(u, r, kappa, self.t, t_end) {
                    None => {
                        self.t = t_end;
                        self.v = 0.0;
                        return Ok(());
                    }
                    Some((tb, s)) => {
                        self.t = tb;
                        self.mode = Mode::Slip(s);
                        self.refresh_accel(u, sum);
                        sum.events += 1;
                        events += 1;
                        if events > coulomb::EVENT_LIMIT {
                            return Err(SimulationError::EventOverflow {
                                t: self.t,
                                limit: coulomb::EVENT_LIMIT,
                            });
                        }
                        continue;
                    }
                }
            }
            let rem = t_end - self.t;
            let (h, clipped) = if self.h >= rem {
                (rem, true)
            } else if self.h > 0.5 * rem {
                (0.5 * rem, true)
            } else {
                (self.h, false)
            };
            let tr = trial(self.d, u, self.fr(), self.t, self.x, self.v, self.a, h);
            sum.rhs_evaluations += 6;
            let sx = self.atol_x + self.rtol * self.x.abs().max(tr.x.abs());
            let sv = self.atol_v + self.rtol * self.v.abs().max(tr.v.abs());
            let err = (0.5 * ((tr.ex / sx).powi(2) + (tr.ev / sv).powi(2))).sqrt();
            if !err.is_finite() {
                if !(tr.x.is_finite() && tr.v.is_finite()) && h < 1e-12 * (1.0 + self.t.abs()) {
                    return Err(SimulationError::Diverged {
                        t: self.t + h,
                        x: tr.x,
                        v: tr.v,
                    });
                }
                self.h = 0.2 * h;
                sum.rejected_steps += 1;
                rejected_last = true;
                continue;
            }
            if err <= 1.0 {
                if let (Some(kappa), Mode::Slip(s)) = (self.kappa, self.mode) {
                    if s * tr.v <= 0.0 {
                        // velocity reversal: locate on the dense output, cut the step there
                        let g = |th: f64| s * dense(self.v, tr.v, &tr.ka, h, th);
                        let g0 = s * self.v;
                        let theta = if g0 > 0.0 {
                            illinois(g, 0.0, g0, 1.0, s * tr.v, 1e-14)
                        } else {
                            1e-14
                        };
                        let hs = (theta * h).max(f64::MIN_POSITIVE);
                        let cut = trial(self.d, u, kappa * s, self.t, self.x, self.v, self.a, hs);
                        sum.rhs_evaluations += 6;
                        sum.steps += 1;
                        sum.events += 1;
                        events += 1;
                        if events > coulomb::EVENT_LIMIT {
                            return Err(SimulationError::EventOverflow {
                                t: self.t,
                                limit: coulomb::EVENT_LIMIT,
                            });
                        }
                        self.t = if hs >= rem { t_end } else { self.t + hs };
                        self.x = cut.x;
                        self.v = 0.0;
                        self.mode = coulomb::rest_mode(self.d, kappa, self.x, u(self.t));
                        if self.mode == Mode::Slip(s) {
                            self.mode = Mode::Stick;
                        }
                        self.refresh_accel(u, sum);
                        continue;
                    }
                }
                sum.steps += 1;
                self.t = if clipped && h == rem {
                    t_end
                } else {
                    self.t + h
                };
                self.x = tr.x;
                self.v = tr.v;
                self.a = tr.ka[6];
                let mut fac = (0.9 * err.powf(-0.2)).clamp(0.2, 5.0);
                if rejected_last {
                    fac = fac.min(1.0);
                }
                rejected_last = false;
                let hn = h * fac;
                self.h = if clipped { self.h.max(hn) } else { hn };
                if !(self.x.is_finite() && self.v.is_finite()) {
                    return Err(SimulationError::Diverged {
                        t: self.t,
                        x: self.x,
                        v: self.v,
                    });
                }
            } else {
                sum.rejected_steps += 1;
                rejected_last = true;
                self.h = h * (0.9 * err.powf(-0.2)).clamp(0.2, 1.0);
                if self.h < 1e-14 * (1.0 + self.t.abs()) {
                    return Err(SimulationError::StepSizeUnderflow {
                        t: self.t,
                        h: self.h,
                    });
                }
            }
        }
        Ok(())
    }
}

#[allow(clippy::too_many_arguments)]
fn new_dp<'d, S: Law, D: Law>(
    d: &'d Dyn<S, D>,
    kappa: Option<f64>,
    rtol: f64,
    atol: f64,
    t0: f64,
    u0: f64,
    init: State,
    h0: f64,
    sum: &mut Summary,
) -> Dp<'d, S, D> {
    let omega_n = d.alpha.sqrt();
    let mode = kappa
        .map(|k| coulomb::initial_mode(d, k, init.x, init.v, u0))
        .unwrap_or(Mode::Stick);
    let mut dp = Dp {
        d,
        rtol,
        atol_x: atol,
        atol_v: atol * omega_n,
        t: t0,
        x: init.x,
        v: init.v,
        a: 0.0,
        h: h0,
        kappa,
        mode,
    };
    dp.refresh_accel(&|_| u0, sum);
    dp
}

struct SampledRun<'i, 'a, F> {
    input: &'i SampledInput<'a>,
    kappa: Option<f64>,
    rtol: f64,
    atol: f64,
    opts: Options,
    cancel: Cancel,
    sink: F,
}

/// Samples between two polls of the cancel flag in a Dormand–Prince run
/// (a few ms of work at the reference tolerances).
const CANCEL_EVERY: usize = 1 << 12;

impl<F: FnMut(Sample)> Visit for SampledRun<'_, '_, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let SampledRun {
            input,
            kappa,
            rtol,
            atol,
            opts,
            cancel,
            mut sink,
        } = self;
        let n = input.len();
        let mut sum = Summary {
            samples: n,
            outputs: 1,
            ..Default::default()
        };
        let h0 = 0.05 / d.alpha.sqrt();
        let mut dp = new_dp(
            &d,
            kappa,
            rtol,
            atol,
            input.time(0),
            input.value(0),
            opts.initial,
            h0,
            &mut sum,
        );
        sink(Sample {
            index: 0,
            t: input.time(0),
            u: input.value(0),
            x: dp.x,
            v: dp.v,
        });
        let mut left = opts.decimation;
        for i in 1..n {
            if i % CANCEL_EVERY == 0 {
                cancel.check()?;
            }
            let (ta, tb) = (input.time(i - 1), input.time(i));
            let (ua, ub) = (input.value(i - 1), input.value(i));
            let slope = (ub - ua) / (tb - ta);
            let u = move |t: f64| ua + slope * (t - ta);
            dp.advance(tb, &u, &mut sum)?;
            dp.t = tb;
            left -= 1;
            if left == 0 {
                left = opts.decimation;
                sink(Sample {
                    index: i,
                    t: tb,
                    u: ub,
                    x: dp.x,
                    v: dp.v,
                });
                sum.outputs += 1;
            }
        }
        sum.final_state = State { x: dp.x, v: dp.v };
        sum.final_time = input.time(n - 1);
        Ok(sum)
    }
}

/// Polls `cancel` every [`CANCEL_EVERY`] samples
/// ([`SimulationError::Interrupted`] once it is set).
pub(crate) fn simulate_sampled<F: FnMut(Sample)>(
    model: &NormalisedModel,
    input: &SampledInput<'_>,
    rtol: f64,
    atol: f64,
    opts: &Options,
    cancel: Cancel,
    sink: F,
) -> Result<Summary, SimulationError> {
    let kappa = is_coulomb(model).then_some(model.kappa);
    dispatch(
        model,
        kappa.is_some(),
        SampledRun {
            input,
            kappa,
            rtol,
            atol,
            opts: *opts,
            cancel,
            sink,
        },
    )
}

struct ExcRun<'e, E: ?Sized, F> {
    exc: &'e E,
    t0: f64,
    dt: f64,
    n: usize,
    kappa: Option<f64>,
    rtol: f64,
    atol: f64,
    opts: Options,
    sink: F,
}

impl<E: Excitation + ?Sized, F: FnMut(Sample)> Visit for ExcRun<'_, E, F> {
    type Out = Result<Summary, SimulationError>;
    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let ExcRun {
            exc,
            t0,
            dt,
            n,
            kappa,
            rtol,
            atol,
            opts,
            mut sink,
        } = self;
        let mut sum = Summary {
            samples: n,
            outputs: 1,
            ..Default::default()
        };
        let h0 = (0.05 / d.alpha.sqrt()).min(dt);
        let u = |t: f64| exc.accel(t);
        let mut dp = new_dp(&d, kappa, rtol, atol, t0, u(t0), opts.initial, h0, &mut sum);
        sink(Sample {
            index: 0,
            t: t0,
            u: u(t0),
            x: dp.x,
            v: dp.v,
        });
        let mut left = opts.decimation;
        for i in 1..n {
            let tb = t0 + i as f64 * dt;
            dp.advance(tb, &u, &mut sum)?;
            dp.t = tb;
            left -= 1;
            if left == 0 {
                left = opts.decimation;
                sink(Sample {
                    index: i,
                    t: tb,
                    u: u(tb),
                    x: dp.x,
                    v: dp.v,
                });
                sum.outputs += 1;
            }
        }
        sum.final_state = State { x: dp.x, v: dp.v };
        sum.final_time = t0 + (n - 1) as f64 * dt;
        Ok(sum)
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate_excitation<E: Excitation + ?Sized, F: FnMut(Sample)>(
    model: &NormalisedModel,
    exc: &E,
    t0: f64,
    dt: f64,
    n: usize,
    rtol: f64,
    atol: f64,
    opts: &Options,
    sink: F,
) -> Result<Summary, SimulationError> {
    let kappa = is_coulomb(model).then_some(model.kappa);
    dispatch(
        model,
        kappa.is_some(),
        ExcRun {
            exc,
            t0,
            dt,
            n,
            kappa,
            rtol,
            atol,
            opts: *opts,
            sink,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::law::Absent;

    /// The continuous extension reproduces the step ends and is 4th-order
    /// accurate inside the step (oracle: the harmonic oscillator's closed form).
    #[test]
    fn dense_output_matches_closed_form() {
        let d = Dyn {
            alpha: 4.0,
            delta: 0.0,
            s: Absent,
            d: Absent,
        };
        let u = |_t: f64| 0.0;
        let mut errs = vec![];
        for &h in &[0.2, 0.1] {
            let tr = trial(&d, &u, 0.0, 0.0, 1.0, 0.0, -4.0, h);
            assert_eq!(dense(1.0, tr.x, &tr.kx, h, 0.0), 1.0);
            assert!((dense(1.0, tr.x, &tr.kx, h, 1.0) - tr.x).abs() < 1e-15);
            let th = 0.37;
            let e = (dense(1.0, tr.x, &tr.kx, h, th) - (2.0 * th * h).cos()).abs();
            let ev = (dense(0.0, tr.v, &tr.ka, h, th) + 2.0 * (2.0 * th * h).sin()).abs();
            errs.push(e.max(ev));
        }
        // local error of a 4th-order interpolant: O(h^5) → ratio ≈ 32
        let ratio = errs[0] / errs[1];
        assert!(
            ratio > 20.0,
            "dense output order: ratio {ratio}, errors {errs:?}"
        );
        assert!(errs[0] < 1e-4, "errors {errs:?}"); // ω h = 0.4
    }
}
