//! Free-decay identification (issue 15; the paper's Fig 3, a log-Hilbert
//! view of the nonlinearity).
//!
//! 1. **Analytic signal** `z = x + i H[x]` by FFT: the segment (mean
//!    removed) is zero-padded to a power of two ≥ 2N (no circular
//!    wrap-around), the bins inside the band `[f1, f2]` are kept (doubled
//!    for positive frequencies), all others zeroed — a band-pass and the
//!    Hilbert transform in one step. The band is chosen from the data
//!    (`[0.5, 1.5] × f_peak`, f_peak = the spectrum's largest bin, which
//!    excludes the odd harmonics of a Duffing-type response) or given. End
//!    effects: the filter's transient lasts about `1/(f2 − f1)`, so
//!    `max(3 cycles, 2/(f2 − f1))` are trimmed at both ends.
//! 2. **Instantaneous amplitude and frequency** `a = |z|`,
//!    `f = (1/2π) dφ/dt` (central differences of the unwrapped phase).
//! 3. **Backbone and damping curve**: amplitude bins (log-spaced between the
//!    largest and the smallest analysed amplitude); per bin the mean
//!    frequency and the decay rate `λ = −d ln a/dt` (least-squares slope of
//!    ln a over the bin's samples).
//! 4. **Averaged equations of the power-law model** (first-order averaging
//!    of Eq 32 with Eq 9 and Eq 22):
//!
//!    ```text
//!    ω² = α + g(ρ) β a^ρ                                  (backbone, Eq 9)
//!    da/dt = −a (δ + g(η) κ (ω a)^η) / 2   ⇔   2 λ = δ + g(η) κ (ω a)^η   (Eq 22/23)
//!    ```
//!
//!    each fitted by a grid over the exponent with linear least squares for
//!    the coefficients, refined by Levenberg–Marquardt over all three;
//!    95 % intervals from `s² (JᵀJ)⁻¹`. The exponents range over
//!    [`EXPONENT_RANGE`] = [−1, 10] (η = −1: Coulomb friction, a result
//!    reported as such; ρ likewise from −1): a fit at 10 is flagged
//!    ([`Fitted::at_bounds`]). δ and κ are ≥ 0 (a decay cannot be fed by
//!    damping): their intervals are taken on `ln` of the value (delta
//!    method) so they stay positive, and a coefficient at 0 gets `[0, upper]`
//!    and is named (its exponent is then without effect).
//! 3′. **A free decay only falls**: every bin's decay rate must be > 0
//!    (a record whose envelope rises in more than a fifth of the bins, e.g.
//!    a chirp response, is refused as [`DecayError::NotADecay`]; the few
//!    rising bins a noisy tail may have are dropped and counted), and the
//!    backbone must give `α > 0`.
//! 5. **Check**: the fitted model's free decay from `(x, v) = (a₀, 0)` is
//!    simulated (the time-domain RK4 of [`super::time_domain`]) and its
//!    envelope, computed the same way, compared with the measured one.

use super::levenberg_marquardt::{
    cholesky_solve, minimise, normal_equations, LeastSquares, LmOptions,
};
use super::time_domain::{simulate_output, TimeModel};
use super::uncertainty::t95;
use crate::model::NormalisedModel;
use crate::power_law::g_unchecked;
use crate::simulation::State;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use thiserror::Error;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Bad records or options of a free-decay analysis (each carries the
/// offending value).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DecayError {
    #[error("sampling frequency fs = {fs} Hz must be finite and > 0")]
    NonPositiveFs { fs: f64 },
    #[error("sample {index} = {value} is not a finite number")]
    NonFinite { index: usize, value: f64 },
    #[error("the decay has {len} samples; at least {min} are needed")]
    TooShort { len: usize, min: usize },
    #[error("start time {t_start} s is outside the record (0 to {duration} s)")]
    StartOutside { t_start: f64, duration: f64 },
    #[error("band {f1}:{f2} Hz is outside 0 < f1 < f2 <= Nyquist = {nyquist} Hz")]
    BandOutsideNyquist { f1: f64, f2: f64, nyquist: f64 },
    #[error("no decay: the envelope falls only from {start} to {end} (needs to halve at least); is this a free decay?")]
    NoDecay { start: f64, end: f64 },
    #[error("the {what} fit failed (too few distinct amplitude bins: {bins})")]
    FitFailed { what: &'static str, bins: usize },
    #[error(transparent)]
    Limit(#[from] crate::limits::LimitError),
    #[error("not a free decay: the envelope rises in {rising} of {bins} amplitude bins (a free decay only falls); give --t-start where the excitation stops")]
    NotADecay { rising: usize, bins: usize },
    #[error("not a free decay of an oscillator: the backbone fit gives omega^2 = alpha = {alpha} 1/s^2 at zero amplitude (must be > 0)")]
    NoOscillator { alpha: f64 },
}

/// Range of both exponents (ρ of the backbone, η of the damping curve):
/// from Coulomb friction (η = −1) to the steepest law the fit accepts.
pub const EXPONENT_RANGE: (f64, f64) = (-1.0, 10.0);

/// The analysed decay ends where the envelope falls below this fraction of
/// its start (or 3× the noise floor): two decades of amplitude.
pub const MIN_RELATIVE_AMPLITUDE: f64 = 0.01;

/// Options of [`analyse`].
#[derive(Debug, Clone, PartialEq)]
pub struct DecayOptions {
    /// Start of the free decay, s from the first sample (default: the last
    /// time the envelope is within 5 % of its maximum).
    pub t_start: Option<f64>,
    /// Band-pass around the mode, Hz (default from the spectrum).
    pub band: Option<(f64, f64)>,
    /// Amplitude bins of the backbone.
    pub bins: usize,
}

impl Default for DecayOptions {
    fn default() -> Self {
        Self {
            t_start: None,
            band: None,
            bins: 30,
        }
    }
}

/// One backbone / damping-curve point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecayPoint {
    pub amplitude: f64,
    pub f_hz: f64,
    /// `λ = −d ln a / dt`, 1/s.
    pub decay_rate: f64,
    pub samples: usize,
}

/// A fitted averaged equation: `value ± half_width` (95 %).
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    pub names: [&'static str; 3],
    pub values: [f64; 3],
    pub lower: [f64; 3],
    pub upper: [f64; 3],
    /// RMS residual.
    pub rms: f64,
    /// Parameters that ended at a bound that is not a result: an exponent
    /// at the top of [`EXPONENT_RANGE`], a coefficient at 0 (then its
    /// exponent has no effect and is named too).
    pub at_bounds: Vec<&'static str>,
}

/// Result of [`analyse`].
#[derive(Debug, Clone, PartialEq)]
pub struct DecayAnalysis {
    pub fs: f64,
    pub band: (f64, f64),
    /// Sample index where the analysed decay starts and ends (exclusive).
    pub start: usize,
    pub end: usize,
    /// Envelope and instantaneous frequency over `start..end`.
    pub amplitude: Vec<f64>,
    pub f_hz: Vec<f64>,
    pub backbone: Vec<DecayPoint>,
    /// `(α, β, ρ)` of `ω² = α + g(ρ) β a^ρ`.
    pub stiffness: Fitted,
    /// `(δ, κ, η)` of `2λ = δ + g(η) κ (ω a)^η`.
    pub damping: Fitted,
    /// Envelope of the fitted model's simulated free decay over `start..end`.
    pub model_amplitude: Vec<f64>,
    /// RMS of (model − measured envelope) / max measured envelope (`None`
    /// when the model's decay could not be simulated).
    pub envelope_error: Option<f64>,
    /// Amplitude bins whose envelope rose (a noisy tail), dropped.
    pub rising_bins: usize,
}

impl DecayAnalysis {
    pub fn model(&self) -> NormalisedModel {
        NormalisedModel {
            alpha: self.stiffness.values[0],
            beta: self.stiffness.values[1],
            rho: self.stiffness.values[2],
            delta: self.damping.values[0],
            kappa: self.damping.values[1],
            eta: self.damping.values[2],
        }
    }
}

/// Analytic signal of `x` (mean removed) restricted to the band `[f1, f2]` Hz.
pub fn analytic_signal(x: &[f64], fs: f64, band: (f64, f64)) -> Vec<Complex<f64>> {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n.max(1) as f64;
    let m = (2 * n).next_power_of_two();
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .map(|&v| Complex::new(v - mean, 0.0))
        .chain(std::iter::repeat(Complex::new(0.0, 0.0)))
        .take(m)
        .collect();
    let mut planner = FftPlanner::<f64>::new();
    planner.plan_fft_forward(m).process(&mut buf);
    let df = fs / m as f64;
    // raised-cosine edges (10 % of the band each side, inside the band):
    // a brick-wall mask would ring for the whole record (sinc tails ~1/t)
    let edge = 0.1 * (band.1 - band.0);
    for (k, c) in buf.iter_mut().enumerate() {
        let f = k as f64 * df;
        let w = if k == 0 || k >= m / 2 || f < band.0 || f > band.1 {
            0.0
        } else {
            let d = (f - band.0).min(band.1 - f);
            if d >= edge {
                1.0
            } else {
                0.5 - 0.5 * (std::f64::consts::PI * d / edge).cos()
            }
        };
        *c *= 2.0 * w / m as f64;
    }
    planner.plan_fft_inverse(m).process(&mut buf);
    buf.truncate(n);
    buf
}

fn peak_frequency(x: &[f64], fs: f64) -> f64 {
    let n = x.len();
    let m = n.next_power_of_two();
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .map(|&v| Complex::new(v - mean, 0.0))
        .chain(std::iter::repeat(Complex::new(0.0, 0.0)))
        .take(m)
        .collect();
    FftPlanner::<f64>::new()
        .plan_fft_forward(m)
        .process(&mut buf);
    let k = (1..m / 2)
        .max_by(|&a, &b| buf[a].norm_sqr().total_cmp(&buf[b].norm_sqr()))
        .unwrap_or(1);
    k as f64 * fs / m as f64
}

/// `y = c0 + c1 · φ(a)` over a grid of the exponent `p` with `φ = g(p) s^p`,
/// then LM over (c0, c1, p); returns the fit with intervals.
struct PowerFit<'a> {
    s: &'a [f64],
    y: &'a [f64],
}

impl PowerFit<'_> {
    fn basis(p: f64, s: f64) -> f64 {
        g_unchecked(p) * s.powf(p)
    }
}

impl LeastSquares for PowerFit<'_> {
    fn n_params(&self) -> usize {
        3
    }
    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        let r: Vec<f64> = self
            .s
            .iter()
            .zip(self.y)
            .map(|(&s, &y)| u[0] + u[1] * Self::basis(u[2], s) - y)
            .collect();
        r.iter().all(|v| v.is_finite()).then_some(r)
    }
    fn residuals_and_jacobian(&self, u: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let r = self.residuals(u)?;
        let dp = 1e-6;
        let (g, gp, gm) = (
            g_unchecked(u[2]),
            g_unchecked(u[2] + dp),
            g_unchecked(u[2] - dp),
        );
        let dg = (gp - gm) / (2.0 * dp);
        let mut j = Vec::with_capacity(3 * r.len());
        for &s in self.s {
            let sp = s.powf(u[2]);
            j.push(1.0);
            j.push(g * sp);
            j.push(u[1] * (dg * sp + g * sp * s.ln()));
        }
        j.iter().all(|v| v.is_finite()).then_some((r, j))
    }
}

fn fit_power(
    s: &[f64],
    y: &[f64],
    names: [&'static str; 3],
    nonneg_c0: bool,
    what: &'static str,
) -> Result<Fitted, DecayError> {
    let n = s.len();
    if n < 4 {
        return Err(DecayError::FitFailed { what, bins: n });
    }
    let fail = || DecayError::FitFailed { what, bins: n };
    let (p_lo, p_hi) = EXPONENT_RANGE;
    // grid over the exponent, steps of 0.05
    let steps = ((p_hi - p_lo) / 0.05).round() as usize;
    let mut best: Option<(f64, [f64; 3])> = None;
    for i in 0..=steps {
        let p = p_lo + 0.05 * i as f64;
        let j: Vec<f64> = s
            .iter()
            .flat_map(|&si| [1.0, PowerFit::basis(p, si)])
            .collect();
        let (a, b) = normal_equations(&j, y, 2);
        let Some(c) = cholesky_solve(&a, &b, 2) else {
            continue;
        };
        let (mut c0, mut c1) = (c[0], c[1]);
        if c1 < 0.0 && nonneg_c0 {
            continue;
        }
        if nonneg_c0 && c0 < 0.0 {
            c0 = 0.0;
            let num: f64 = s
                .iter()
                .zip(y)
                .map(|(&si, &yi)| PowerFit::basis(p, si) * yi)
                .sum();
            let den: f64 = s.iter().map(|&si| PowerFit::basis(p, si).powi(2)).sum();
            c1 = num / den;
        }
        let cost: f64 = s
            .iter()
            .zip(y)
            .map(|(&si, &yi)| (c0 + c1 * PowerFit::basis(p, si) - yi).powi(2))
            .sum();
        if cost.is_finite() && best.map(|b| cost < b.0).unwrap_or(true) {
            best = Some((cost, [c0, c1, p]));
        }
    }
    let (_, start) = best.ok_or_else(fail)?;
    let problem = PowerFit { s, y };
    let lo = [
        if nonneg_c0 { 0.0 } else { f64::NEG_INFINITY },
        if nonneg_c0 { 0.0 } else { f64::NEG_INFINITY },
        p_lo,
    ];
    let hi = [f64::INFINITY, f64::INFINITY, p_hi];
    let r = minimise(&problem, &start, &lo, &hi, &LmOptions::default()).map_err(|_| fail())?;
    let (res, j) = problem.residuals_and_jacobian(&r.u).ok_or_else(fail)?;
    let cost: f64 = res.iter().map(|v| v * v).sum();
    let (a, _) = normal_equations(&j, &res, 3);
    let dof = n.saturating_sub(3).max(1);
    let s2 = cost / dof as f64;
    let t = t95(dof);
    let d: Vec<f64> = (0..3).map(|k| a[k * 3 + k].sqrt().max(1e-300)).collect();
    let scaled: Vec<f64> = (0..9).map(|i| a[i] / (d[i / 3] * d[i % 3])).collect();
    let mut lower = [f64::NAN; 3];
    let mut upper = [f64::NAN; 3];
    for c in 0..3 {
        let mut e = [0.0; 3];
        e[c] = 1.0;
        if let Some(col) = cholesky_solve(&scaled, &e, 3) {
            let se = (s2 * col[c] / (d[c] * d[c])).max(0.0).sqrt();
            let v = r.u[c];
            if nonneg_c0 && c < 2 {
                // a coefficient >= 0: the interval of ln v (delta method,
                // se(ln v) = se/v), so it stays inside the physical range
                if v > 0.0 {
                    let k = (t * se / v).exp();
                    lower[c] = v / k;
                    upper[c] = v * k;
                } else {
                    lower[c] = 0.0;
                    upper[c] = t * se;
                }
            } else {
                lower[c] = v - t * se;
                upper[c] = v + t * se;
            }
        }
    }
    let mut at_bounds = Vec::new();
    if nonneg_c0 {
        if r.u[0] <= 0.0 {
            at_bounds.push(names[0]);
        }
        if r.u[1] <= 0.0 {
            // no nonlinear term: its exponent has no effect either
            at_bounds.push(names[1]);
            at_bounds.push(names[2]);
        }
    }
    if r.u[2] >= p_hi - 1e-6 * (p_hi - p_lo) && !at_bounds.contains(&names[2]) {
        at_bounds.push(names[2]);
    }
    Ok(Fitted {
        names,
        values: [r.u[0], r.u[1], r.u[2]],
        lower,
        upper,
        rms: (cost / n as f64).sqrt(),
        at_bounds,
    })
}

/// Envelope with the trimmed ends of the analytic signal.
fn envelope(x: &[f64], fs: f64, band: (f64, f64)) -> Vec<f64> {
    analytic_signal(x, fs, band)
        .iter()
        .map(|c| c.norm())
        .collect()
}

/// The free-decay analysis of a record `x` sampled at `fs` (see the module
/// docs).
pub fn analyse(x: &[f64], fs: f64, opts: &DecayOptions) -> Result<DecayAnalysis, DecayError> {
    if !(fs.is_finite() && fs > 0.0) {
        return Err(DecayError::NonPositiveFs { fs });
    }
    crate::limits::DECAY_BINS.check(opts.bins as f64)?;
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DecayError::NonFinite { index, value });
    }
    let n = x.len();
    let nyquist = fs / 2.0;
    if let Some((f1, f2)) = opts.band {
        if !(f1 > 0.0 && f2 > f1 && f2 <= nyquist) {
            return Err(DecayError::BandOutsideNyquist { f1, f2, nyquist });
        }
    }
    if n < 64 {
        return Err(DecayError::TooShort { len: n, min: 64 });
    }
    let duration = (n - 1) as f64 / fs;
    let given_start = match opts.t_start {
        Some(t) if !(t >= 0.0 && t < duration) => {
            return Err(DecayError::StartOutside {
                t_start: t,
                duration,
            })
        }
        Some(t) => Some((t * fs).round() as usize),
        None => None,
    };
    // band from the spectrum of the (candidate) decay
    let seg0 = &x[given_start.unwrap_or(0)..];
    let band = match opts.band {
        Some(b) => b,
        None => {
            let fp = peak_frequency(seg0, fs);
            (0.5 * fp, (1.5 * fp).min(nyquist))
        }
    };
    // start: given, or the last time the full-record envelope is within 5 % of its maximum
    let start = match given_start {
        Some(s) => s,
        None => {
            let trim = ((3.0 / band.1.max(1e-300)).max(2.0 / (band.1 - band.0)) * fs) as usize;
            // the band-pass transients at both ends leave nothing between
            // them on a record this short (issue 30: 64–200 samples panicked)
            if n < 2 * trim + 64 {
                return Err(DecayError::TooShort {
                    len: n,
                    min: 2 * trim + 64,
                });
            }
            let env = envelope(x, fs, band);
            let inner = &env[trim..n - trim];
            let max = inner.iter().cloned().fold(0.0, f64::max);
            trim + inner.iter().rposition(|&a| a >= 0.95 * max).unwrap_or(0)
        }
    };
    let seg = &x[start..];
    let fc = 0.5 * (band.0 + band.1);
    let trim = ((3.0 / fc).max(2.0 / (band.1 - band.0)) * fs).ceil() as usize;
    if seg.len() < 2 * trim + 64 && given_start.is_none() {
        // the envelope is near its maximum until the end: no decay
        let env = envelope(x, fs, band);
        return Err(DecayError::NoDecay {
            start: env[n / 2],
            end: env[n - 1 - trim.min(n / 4)],
        });
    }
    if seg.len() < 2 * trim + 64 {
        return Err(DecayError::TooShort {
            len: seg.len(),
            min: 2 * trim + 64,
        });
    }
    let z = analytic_signal(seg, fs, band);
    let amp_all: Vec<f64> = z.iter().map(|c| c.norm()).collect();
    // analysed range: after the leading trim, until the envelope reaches
    // 3x the noise floor (median of the last 10 %) or the trailing trim
    let tail = &amp_all[amp_all.len() - amp_all.len() / 10..];
    let mut sorted = tail.to_vec();
    sorted.sort_by(f64::total_cmp);
    let floor = sorted[sorted.len() / 2];
    let a0 = amp_all[trim];
    let last = amp_all.len() - trim;
    let stop = (trim..last)
        .find(|&k| amp_all[k] < (3.0 * floor).max(MIN_RELATIVE_AMPLITUDE * a0))
        .unwrap_or(last);
    let end_amp = amp_all[stop.saturating_sub(1).max(trim)];
    if !(end_amp <= 0.5 * a0) || stop < trim + 64 {
        return Err(DecayError::NoDecay {
            start: a0,
            end: end_amp,
        });
    }
    let amplitude: Vec<f64> = amp_all[trim..stop].to_vec();
    let phase: Vec<f64> = z[trim.saturating_sub(1)..(stop + 1).min(z.len())]
        .iter()
        .map(|c| c.arg())
        .collect();
    let mut unwrapped = Vec::with_capacity(phase.len());
    let mut off = 0.0;
    for (i, &p) in phase.iter().enumerate() {
        if i > 0 {
            let d = p - phase[i - 1];
            if d > std::f64::consts::PI {
                off -= TWO_PI;
            } else if d < -std::f64::consts::PI {
                off += TWO_PI;
            }
        }
        unwrapped.push(p + off);
    }
    let f_hz: Vec<f64> = (0..amplitude.len())
        .map(|k| {
            let (a, b) = (k, (k + 2).min(unwrapped.len() - 1));
            (unwrapped[b] - unwrapped[a]) * fs / ((b - a) as f64 * TWO_PI)
        })
        .collect();
    // amplitude bins
    let amax = amplitude.iter().cloned().fold(0.0, f64::max);
    let amin = amplitude.iter().cloned().fold(f64::INFINITY, f64::min);
    let nb = opts.bins.max(4);
    let (la, lb) = (amin.ln(), amax.ln());
    let mut backbone = Vec::new();
    for b in 0..nb {
        let lo = (la + (lb - la) * b as f64 / nb as f64).exp();
        let hi = (la + (lb - la) * (b + 1) as f64 / nb as f64).exp();
        let idx: Vec<usize> = (0..amplitude.len())
            .filter(|&k| amplitude[k] >= lo && (amplitude[k] < hi || (b == nb - 1)))
            .collect();
        // at least two cycles in the bin
        let span = idx.last().zip(idx.first()).map(|(l, f)| l - f).unwrap_or(0);
        if idx.len() < 8 || (span as f64) < 2.0 * fs / fc {
            continue;
        }
        let m = idx.len() as f64;
        let tm = idx.iter().map(|&k| k as f64 / fs).sum::<f64>() / m;
        let lm = idx.iter().map(|&k| amplitude[k].ln()).sum::<f64>() / m;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for &k in &idx {
            let dt = k as f64 / fs - tm;
            sxy += dt * (amplitude[k].ln() - lm);
            sxx += dt * dt;
        }
        backbone.push(DecayPoint {
            amplitude: lm.exp(),
            f_hz: idx.iter().map(|&k| f_hz[k]).sum::<f64>() / m,
            decay_rate: -sxy / sxx,
            samples: idx.len(),
        });
    }
    // a free decay only falls: drop the few bins a noisy tail may raise,
    // refuse a record whose envelope rises in more than a fifth of them
    let bins = backbone.len();
    let rising = backbone.iter().filter(|p| !(p.decay_rate > 0.0)).count();
    if bins > 0 && rising * 5 > bins {
        return Err(DecayError::NotADecay { rising, bins });
    }
    backbone.retain(|p| p.decay_rate > 0.0);
    let a: Vec<f64> = backbone.iter().map(|p| p.amplitude).collect();
    let w2: Vec<f64> = backbone.iter().map(|p| (TWO_PI * p.f_hz).powi(2)).collect();
    let stiffness = fit_power(&a, &w2, ["alpha", "beta", "rho"], false, "backbone")?;
    if !(stiffness.values[0] > 0.0) {
        return Err(DecayError::NoOscillator {
            alpha: stiffness.values[0],
        });
    }
    let wa: Vec<f64> = backbone
        .iter()
        .map(|p| TWO_PI * p.f_hz * p.amplitude)
        .collect();
    let two_l: Vec<f64> = backbone.iter().map(|p| 2.0 * p.decay_rate).collect();
    let damping = fit_power(&wa, &two_l, ["delta", "kappa", "eta"], true, "damping")?;
    // envelope check: simulate the free decay from (a0, 0)
    let mut res = DecayAnalysis {
        fs,
        band,
        start: start + trim,
        end: start + stop,
        amplitude,
        f_hz,
        backbone,
        stiffness,
        damping,
        model_amplitude: Vec::new(),
        envelope_error: None,
        rising_bins: rising,
    };
    let model = res.model();
    if model.alpha > 0.0 {
        let len = stop - trim;
        let tm = TimeModel {
            model,
            gain: 0.0,
            input_offset: 0.0,
            output_offset: 0.0,
        };
        let zeros = vec![0.0; len + 2 * trim];
        if let Ok(sim) = simulate_output(
            &tm,
            &zeros,
            fs,
            State {
                x: res.amplitude[0],
                v: 0.0,
            },
        ) {
            // pad before the start with the same oscillation backwards is
            // not available: analyse the simulated decay from its start and
            // compare from sample 0 (the simulated decay starts at a0)
            let env = envelope(&sim, fs, band);
            let m = env[..len].to_vec();
            let scale = res.amplitude.iter().cloned().fold(0.0, f64::max);
            let skip = trim.min(len / 4);
            let err = (m[skip..]
                .iter()
                .zip(&res.amplitude[skip..])
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                / (len - skip) as f64)
                .sqrt()
                / scale;
            res.model_amplitude = m;
            res.envelope_error = err.is_finite().then_some(err);
        }
    }
    Ok(res)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn analytic_signal_of_a_sine() {
        let fs = 1000.0;
        let x: Vec<f64> = (0..4000)
            .map(|k| 2.0 * (TWO_PI * 37.0 * k as f64 / fs).sin())
            .collect();
        let z = analytic_signal(&x, fs, (20.0, 60.0));
        for c in &z[500..3500] {
            assert!((c.norm() - 2.0).abs() < 1e-2, "{}", c.norm());
        }
    }
}
