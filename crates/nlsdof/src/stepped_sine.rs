//! Virtual stepped-sine test rig — what the paper's shaker controller did
//! (§2.1, §2.3, Fig. 2): at each frequency step the input is a
//! phase-continuous sine `γ cos θ(t)` (zero-to-peak γ, m/s²); the rig dwells
//! until the response is steady, then records the first-harmonic amplitude
//! and phase lag of the displacement (plus peak-to-peak and the 2nd/3rd
//! harmonic levels), carries the state to the next step and sweeps up or
//! down. The simulated plant is Eq 32 integrated by classical RK4 with
//! exactly `N` steps per input cycle (so every cycle is sampled at the same
//! phases and the per-cycle DFT is exact for harmonics below N/2); Coulomb
//! friction uses the event-handling stepper of [`crate::simulation`].
//!
//! ## Settling rule
//!
//! The real controller's rule — "two consecutive cycle amplitudes within
//! 1 %" — is badly wrong for a lightly damped structure: the transient
//! decays by only `e^{−2πζ}` per cycle (≈ 4 % for the wing, ζ ≈ 0.64 %), so
//! consecutive amplitudes differ by < 1 % while the response is still
//! 30 % away from steady state; and a beating envelope is flat at its turns.
//! The rig instead works with the complex first harmonic `X_n` of cycle n
//! (a beating transient rotates `X_n` even where `|X_n|` is stationary) and
//! its differences `D_n = X_n − X_{n−1}`. Near a steady state the transient
//! in the rotating frame is a sum of modes `c λ^n`, so the distance to the
//! steady state is bounded by the geometric tail
//!
//! ```text
//! |X_n − X_∞| ≤ |D_n| q / (1 − q),      q ≥ |λ|
//! q = max( e^{−σ_eff T},  |D_n|/|D_{n−1}|,  |D_{n−1}|/|D_{n−2}| )
//! σ_eff = (δ + δ_eq(a, Ω)) / 2,   δ_eq = g(η) κ |Ω a|^η        (Eq 22–23)
//! ```
//!
//! (the model bound `e^{−σ_eff T}` is the decay per cycle of the
//! linearised transient; the observed ratios take over where the decay is
//! slower, e.g. near a fold where one slow-flow eigenvalue tends to zero).
//! A step is **settled** when
//!
//! 1. the dwell is at least `min_decay_times` effective decay times
//!    `1/σ_eff` (and `min_cycles` cycles), and
//! 2. the relative tail bound `|D_n| q/(1−q) / |X_n|` is below
//!    `tolerance` on `consecutive` successive cycles.
//!
//! A step that hits `max_cycles` is recorded with `settled = false`.
//!
//! ## Integration error
//!
//! RK4 with `N` steps per input cycle is accurate for the input, but not
//! necessarily for the response: a structure stepped far below its natural
//! frequency, or a strongly nonlinear one with high harmonics, has motion
//! faster than the input. So at each step, once the dwell ends, the last
//! state is integrated for one more cycle twice, with `N` and with `2N`
//! steps (without moving the sweep on), and the first harmonics `X_N`,
//! `X_2N` of those cycles give the Richardson estimate of the error of the
//! recorded one (RK4 is of order 4):
//!
//! ```text
//! ε ≈ |X_N − X_2N| · 16/15 / |X_2N|
//! ```
//!
//! This costs three cycles per step, against the tens to thousands of the
//! dwell. Above [`INTEGRATION_WARNING`] the remedy is a larger
//! `samples_per_cycle`.

use crate::harmonic_balance::SweepDirection;
use crate::model::AsNormalised;
use crate::model::NormalisedModel;
use crate::simulation::coulomb::{self, Mode};
use crate::simulation::law::{dispatch, Dyn, Law, Visit};
use crate::simulation::rk4_step::step;
use crate::simulation::{check_model, Sample, SimulationError, State, Summary};
use std::f64::consts::{PI, TAU};

/// Largest accepted `samples_per_cycle` (the per-cycle tables are allocated
/// up front).
pub const MAX_SAMPLES_PER_CYCLE: usize = 100_000;
/// Largest number of frequency steps of one sweep.
pub use crate::excitation::MAX_STEPS;

/// Relative integration error above which a rig result is not trustworthy
/// to the accuracy a user expects from it (the CLI warns).
pub const INTEGRATION_WARNING: f64 = 1e-3;

/// Rig settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigOptions {
    /// RK4 steps (samples) per input cycle, ≥ 16.
    pub samples_per_cycle: usize,
    /// Settled when the estimated remaining transient of the first harmonic
    /// is below this fraction of its amplitude.
    pub tolerance: f64,
    /// Minimum dwell in effective decay times `1/σ_eff`.
    pub min_decay_times: f64,
    /// Minimum dwell in cycles (≥ 4).
    pub min_cycles: usize,
    /// Give up (settled = false) after this many cycles at one frequency.
    pub max_cycles: usize,
    /// Number of successive cycles that must pass the tail test.
    pub consecutive: usize,
    /// Keep every `d`-th simulated sample as time history (`None`: none).
    pub history_decimation: Option<usize>,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            samples_per_cycle: 64,
            tolerance: 1e-4,
            min_decay_times: 2.0,
            min_cycles: 8,
            max_cycles: 5000,
            consecutive: 3,
            history_decimation: None,
        }
    }
}

/// One recorded frequency step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigPoint {
    /// Ω, rad/s.
    pub omega: f64,
    /// First-harmonic displacement amplitude |X₁| of the last cycle, m (zero-to-peak).
    pub amplitude: f64,
    /// Phase lag of the first harmonic of x behind the input `γ cos Ωt`,
    /// rad (in [0, π] for a dissipative steady state).
    pub phase: f64,
    /// max x − min x over the last cycle, m.
    pub peak_to_peak: f64,
    /// Amplitude of the 2nd harmonic of x, m.
    pub harmonic2: f64,
    /// Amplitude of the 3rd harmonic of x, m.
    pub harmonic3: f64,
    /// Cycles dwelt at this frequency.
    pub cycles: usize,
    /// Passed the settling rule (false: hit `max_cycles`).
    pub settled: bool,
    /// Final relative tail bound of the remaining transient.
    pub residual: f64,
    /// Estimated relative integration error of `amplitude` (see the module
    /// docs, "Integration error").
    pub integration_error: f64,
}

/// A sweep at one level.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSweep {
    /// γ, m/s² zero-to-peak.
    pub gamma: f64,
    pub direction: SweepDirection,
    /// In sweep order.
    pub points: Vec<RigPoint>,
    /// Time history (t, input, x, v), if requested.
    pub history: Vec<Sample>,
    pub final_state: State,
    /// Total simulated time, s.
    pub duration: f64,
}

fn check_options(o: &RigOptions) -> Result<(), SimulationError> {
    let bad = |name, value: f64, reason| {
        Err(SimulationError::InvalidOption {
            name,
            value,
            reason,
        })
    };
    if o.samples_per_cycle < 16 {
        return bad(
            "samples per cycle",
            o.samples_per_cycle as f64,
            "must be >= 16",
        );
    }
    if o.samples_per_cycle > MAX_SAMPLES_PER_CYCLE {
        return bad(
            "samples per cycle",
            o.samples_per_cycle as f64,
            "must be <= 100000",
        );
    }
    if !(o.tolerance.is_finite() && o.tolerance > 0.0) {
        return bad("settling tolerance", o.tolerance, "must be > 0");
    }
    if !(o.min_decay_times.is_finite() && o.min_decay_times >= 0.0) {
        return bad(
            "minimum dwell (decay times)",
            o.min_decay_times,
            "must be >= 0",
        );
    }
    if o.min_cycles < 4 {
        return bad("minimum cycles", o.min_cycles as f64, "must be >= 4");
    }
    if o.max_cycles < o.min_cycles {
        return bad(
            "maximum cycles",
            o.max_cycles as f64,
            "must be >= minimum cycles",
        );
    }
    if o.consecutive == 0 {
        return bad("consecutive cycles", 0.0, "must be >= 1");
    }
    if o.history_decimation == Some(0) {
        return bad("history decimation", 0.0, "must be >= 1");
    }
    Ok(())
}

fn check_omegas(omegas: &[f64]) -> Result<(), SimulationError> {
    if omegas.is_empty() {
        return Err(SimulationError::EmptyInput);
    }
    for (i, &w) in omegas.iter().enumerate() {
        if !(w.is_finite() && w > 0.0) {
            return Err(SimulationError::InvalidOption {
                name: "omega",
                value: w,
                reason: "must be finite and > 0",
            });
        }
        if i > 0 && w <= omegas[i - 1] {
            return Err(SimulationError::Parameter(
                crate::error::ParameterError::NotIncreasing {
                    index: i,
                    value: w,
                    previous: omegas[i - 1],
                },
            ));
        }
    }
    Ok(())
}

/// Effective decay rate σ_eff = (δ + δ_eq)/2 of the transient at amplitude
/// `a` and frequency `omega` (Eq 22–23, per unit mass).
pub fn effective_decay_rate(model: &NormalisedModel, a: f64, omega: f64) -> f64 {
    let mut d = model.delta;
    if model.kappa > 0.0 && a > 0.0 {
        let deq = crate::power_law::g_unchecked(model.eta)
            * model.kappa
            * (omega * a).abs().powf(model.eta);
        if deq.is_finite() {
            d += deq;
        }
    }
    0.5 * d
}

/// Runs the rig at one level `gamma` over the strictly increasing
/// frequencies `omegas` (rad/s) in `direction`, from state `initial`.
pub fn run(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    omegas: &[f64],
    direction: SweepDirection,
    options: &RigOptions,
    initial: State,
) -> Result<RigSweep, SimulationError> {
    let model = &model.as_normalised()?;
    run_with_progress(model, gamma, omegas, direction, options, initial, &|| {})
}

/// [`run`] calling `progress` after every frequency step.
#[allow(clippy::too_many_arguments)]
pub fn run_with_progress(
    model: &(impl AsNormalised + ?Sized),
    gamma: f64,
    omegas: &[f64],
    direction: SweepDirection,
    options: &RigOptions,
    initial: State,
    progress: &(dyn Fn() + Sync),
) -> Result<RigSweep, SimulationError> {
    let model = &model.as_normalised()?;
    check_model(model)?;
    check_options(options)?;
    check_omegas(omegas)?;
    if !(gamma.is_finite() && gamma > 0.0) {
        return Err(SimulationError::InvalidOption {
            name: "gamma",
            value: gamma,
            reason: "must be finite and > 0",
        });
    }
    if !(initial.x.is_finite() && initial.v.is_finite()) {
        return Err(SimulationError::InvalidOption {
            name: "initial state",
            value: f64::NAN,
            reason: "not finite",
        });
    }
    let order: Vec<f64> = match direction {
        SweepDirection::Up => omegas.to_vec(),
        SweepDirection::Down => omegas.iter().rev().copied().collect(),
    };
    let coulomb = crate::simulation::is_coulomb(model);
    dispatch(
        model,
        coulomb,
        Rig {
            model: *model,
            gamma,
            omegas: &order,
            direction,
            o: *options,
            initial,
            coulomb,
            progress,
        },
    )
}

/// Runs several levels (in parallel on the rayon pool), each from rest.
/// Results in the order of `gammas`, identical whatever the number of
/// threads; on failure, the error of the first failing level.
pub fn run_levels(
    model: &(impl AsNormalised + ?Sized),
    gammas: &[f64],
    omegas: &[f64],
    direction: SweepDirection,
    options: &RigOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<RigSweep>, SimulationError> {
    let model = &model.as_normalised()?;
    run_sweeps(model, gammas, omegas, &[direction], options, progress)
}

/// The rig's whole test: every level swept in every direction, each sweep
/// from rest, all sweeps in parallel on the rayon pool. Results in the
/// order direction by direction, then level by level (`result[d *
/// gammas.len() + k]` is level `k` swept in `directions[d]`), identical
/// whatever the number of threads; on failure, the error of the first
/// failing sweep in that order.
pub fn run_sweeps(
    model: &(impl AsNormalised + ?Sized),
    gammas: &[f64],
    omegas: &[f64],
    directions: &[SweepDirection],
    options: &RigOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<RigSweep>, SimulationError> {
    let model = &model.as_normalised()?;
    use rayon::prelude::*;
    let jobs: Vec<(SweepDirection, f64)> = directions
        .iter()
        .flat_map(|&d| gammas.iter().map(move |&g| (d, g)))
        .collect();
    let results: Vec<Result<RigSweep, SimulationError>> = jobs
        .par_iter()
        .map(|&(direction, gamma)| {
            run_with_progress(
                model,
                gamma,
                omegas,
                direction,
                options,
                State::default(),
                progress,
            )
        })
        .collect();
    results.into_iter().collect()
}

struct Rig<'a> {
    model: NormalisedModel,
    gamma: f64,
    omegas: &'a [f64],
    direction: SweepDirection,
    o: RigOptions,
    initial: State,
    coulomb: bool,
    progress: &'a (dyn Fn() + Sync),
}

/// Per-cycle accumulators.
#[derive(Default, Clone, Copy)]
struct CycleStats {
    re: [f64; 3],
    im: [f64; 3],
    max: f64,
    min: f64,
}

impl Visit for Rig<'_> {
    type Out = Result<RigSweep, SimulationError>;

    fn go<S: Law, D: Law>(self, d: Dyn<S, D>) -> Self::Out {
        let Rig {
            model,
            gamma,
            omegas,
            direction,
            o,
            initial,
            coulomb,
            progress,
        } = self;
        let n = o.samples_per_cycle;
        // cos(π j / N), j = 0 .. 2N: input at whole and half samples; DFT weights
        let table: Vec<f64> = (0..=2 * n)
            .map(|j| (PI * j as f64 / n as f64).cos())
            .collect();
        let sin_table: Vec<f64> = (0..2 * n)
            .map(|j| (PI * j as f64 / n as f64).sin())
            .collect();
        let mut st = initial;
        let mut mode = if coulomb {
            coulomb::initial_mode(&d, model.kappa, st.x, st.v, gamma)
        } else {
            Mode::Stick
        };
        let mut counters = Summary::default();
        let mut t = 0.0;
        let mut points = Vec::with_capacity(omegas.len());
        let mut history = Vec::new();
        let mut hist_left = o.history_decimation.unwrap_or(0);
        for &omega in omegas {
            let period = TAU / omega;
            let h = period / n as f64;
            let mut prev: Option<(f64, f64)> = None;
            let mut diffs: [f64; 3] = [f64::NAN; 3]; // |D_n|, |D_{n-1}|, |D_{n-2}|
            let mut passes = 0usize;
            let mut cycles = 0usize;
            let mut last = CycleStats::default();
            let mut residual = f64::INFINITY;
            let mut settled = false;
            while cycles < o.max_cycles {
                let mut cs = CycleStats {
                    max: st.x,
                    min: st.x,
                    ..Default::default()
                };
                for j in 0..n {
                    let (x0, v0) = (st.x, st.v);
                    // DFT of x at phases θ_j = 2π j / N for harmonics 1..3
                    for (k, (re, im)) in cs.re.iter_mut().zip(cs.im.iter_mut()).enumerate() {
                        let idx = (2 * (k + 1) * j) % (2 * n);
                        *re += x0 * table[idx];
                        *im -= x0 * sin_table[idx];
                    }
                    let u0 = gamma * table[2 * j];
                    let um = gamma * table[2 * j + 1];
                    let u1 = gamma * table[2 * j + 2];
                    if coulomb {
                        let th0 = TAU * j as f64 / n as f64;
                        let u = |tau: f64| gamma * (th0 + omega * tau).cos();
                        let (mut x1, mut v1) = (x0, v0);
                        coulomb::rk4_interval(
                            &d,
                            model.kappa,
                            h,
                            &u,
                            t,
                            &mut x1,
                            &mut v1,
                            &mut mode,
                            &mut counters,
                        )?;
                        st = State { x: x1, v: v1 };
                    } else {
                        let a1 = u0 - d.internal(x0, v0);
                        let (x1, v1) = step(&d, x0, v0, a1, h, um, u1);
                        st = State { x: x1, v: v1 };
                    }
                    if !(st.x.is_finite() && st.v.is_finite()) {
                        return Err(SimulationError::Diverged {
                            t: t + h,
                            x: st.x,
                            v: st.v,
                        });
                    }
                    // extremum inside the step: cubic Hermite at the linear v-zero
                    if (v0 > 0.0) != (st.v > 0.0) && v0 != st.v {
                        let s = (v0 / (v0 - st.v)).clamp(0.0, 1.0);
                        let (h00, h10, h01, h11) = hermite(s);
                        let xe = h00 * x0 + h10 * h * v0 + h01 * st.x + h11 * h * st.v;
                        cs.max = cs.max.max(xe);
                        cs.min = cs.min.min(xe);
                    }
                    cs.max = cs.max.max(st.x);
                    cs.min = cs.min.min(st.x);
                    t += h;
                    if let Some(dec) = o.history_decimation {
                        hist_left -= 1;
                        if hist_left == 0 {
                            hist_left = dec;
                            history.push(Sample {
                                index: history.len(),
                                t,
                                u: u1,
                                x: st.x,
                                v: st.v,
                            });
                        }
                    }
                }
                let scale = 2.0 / n as f64;
                for k in 0..3 {
                    cs.re[k] *= scale;
                    cs.im[k] *= scale;
                }
                cycles += 1;
                last = cs;
                let amp = cs.re[0].hypot(cs.im[0]);
                if let Some((pr, pi)) = prev {
                    diffs = [(cs.re[0] - pr).hypot(cs.im[0] - pi), diffs[0], diffs[1]];
                }
                prev = Some((cs.re[0], cs.im[0]));
                if cycles < 4 || !diffs[2].is_finite() {
                    continue;
                }
                let sigma = effective_decay_rate(&model, amp, omega);
                let q_model = (-sigma * period).exp();
                let q_obs = (diffs[0] / diffs[1]).max(diffs[1] / diffs[2]);
                let noise = 1e-12 * amp.max(f64::MIN_POSITIVE);
                residual = if diffs[0] <= noise {
                    diffs[0] / amp.max(f64::MIN_POSITIVE)
                } else {
                    let q = q_model.max(if q_obs.is_finite() { q_obs } else { 1.0 });
                    if q < 1.0 {
                        diffs[0] * q / (1.0 - q) / amp.max(f64::MIN_POSITIVE)
                    } else {
                        f64::INFINITY
                    }
                };
                passes = if residual < o.tolerance {
                    passes + 1
                } else {
                    0
                };
                let min_dwell = if sigma > 0.0 {
                    (o.min_decay_times / (sigma * period))
                        .ceil()
                        .min(o.max_cycles as f64) as usize
                } else {
                    o.max_cycles
                };
                if passes >= o.consecutive && cycles >= o.min_cycles.max(min_dwell) {
                    settled = true;
                    break;
                }
            }
            let integration_error = {
                let mut scratch = counters;
                let mut harmonic = |m: usize| {
                    cycle_harmonic(
                        &d,
                        model.kappa,
                        coulomb,
                        mode,
                        gamma,
                        omega,
                        st,
                        m,
                        t,
                        &mut scratch,
                    )
                };
                let coarse = harmonic(n)?;
                let fine = harmonic(2 * n)?;
                let size = fine.0.hypot(fine.1);
                if size > 0.0 {
                    (coarse.0 - fine.0).hypot(coarse.1 - fine.1) * 16.0 / 15.0 / size
                } else {
                    0.0
                }
            };
            let amplitude = last.re[0].hypot(last.im[0]);
            // x ≈ Re(X₁ e^{iθ}) = |X₁| cos(θ + arg X₁): lag φ = −arg X₁
            let phase = if amplitude > 0.0 {
                -last.im[0].atan2(last.re[0])
            } else {
                0.0
            };
            let phase = if phase < -0.5 * PI {
                phase + TAU
            } else {
                phase
            };
            points.push(RigPoint {
                omega,
                amplitude,
                phase,
                peak_to_peak: last.max - last.min,
                harmonic2: last.re[1].hypot(last.im[1]),
                harmonic3: last.re[2].hypot(last.im[2]),
                cycles,
                settled,
                residual,
                integration_error,
            });
            progress();
        }
        Ok(RigSweep {
            gamma,
            direction,
            points,
            history,
            final_state: st,
            duration: t,
        })
    }
}

/// First harmonic `(Re, Im)` of x over one input cycle `γ cos(Ωτ)` from
/// `st` at phase 0, integrated with `m` RK4 steps (for the Richardson
/// estimate of the integration error; the caller's state is not moved).
#[allow(clippy::too_many_arguments)]
fn cycle_harmonic<S: Law, D: Law>(
    d: &Dyn<S, D>,
    kappa: f64,
    coulomb: bool,
    mut mode: Mode,
    gamma: f64,
    omega: f64,
    st: State,
    m: usize,
    t: f64,
    counters: &mut Summary,
) -> Result<(f64, f64), SimulationError> {
    let h = TAU / omega / m as f64;
    let (mut x, mut v) = (st.x, st.v);
    let (mut re, mut im) = (0.0, 0.0);
    for j in 0..m {
        let th = TAU * j as f64 / m as f64;
        re += x * th.cos();
        im -= x * th.sin();
        if coulomb {
            let u = |tau: f64| gamma * (th + omega * tau).cos();
            coulomb::rk4_interval(d, kappa, h, &u, t, &mut x, &mut v, &mut mode, counters)?;
        } else {
            let u0 = gamma * th.cos();
            let um = gamma * (th + 0.5 * omega * h).cos();
            let u1 = gamma * (th + omega * h).cos();
            let a1 = u0 - d.internal(x, v);
            (x, v) = step(d, x, v, a1, h, um, u1);
        }
    }
    let scale = 2.0 / m as f64;
    Ok((re * scale, im * scale))
}

/// Cubic Hermite basis at s ∈ [0, 1].
#[inline]
fn hermite(s: f64) -> (f64, f64, f64, f64) {
    let s2 = s * s;
    let s3 = s2 * s;
    (
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    )
}
