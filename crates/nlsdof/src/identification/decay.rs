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
//!    `max(3 cycles, 2/(f2 − f1))` are trimmed at both ends. A record
//!    longer than 2^19 samples is filtered the same way in overlapping
//!    blocks (overlap-save, [`ANALYTIC_BLOCK`]), so memory stays near the
//!    record's own size (issue 30, class 10).
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
use super::time_domain::{simulate_states, Discretisation, TimeModel};
use super::uncertainty::t95;
use crate::cancel::{Cancel, Interrupted};
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
    /// Cancelled through [`DecayOptions::cancel`]: no result.
    #[error(transparent)]
    Interrupted(#[from] Interrupted),
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
    /// Polled between the FFT blocks, the amplitude bins and the pieces of
    /// the model's free decay: once set, [`analyse`] ends with
    /// [`DecayError::Interrupted`] ([`crate::cancel`]).
    pub cancel: Cancel,
}

impl Default for DecayOptions {
    fn default() -> Self {
        Self {
            t_start: None,
            band: None,
            bins: 30,
            cancel: Cancel::NEVER,
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

/// Largest FFT of the analytic signal computed in one piece: 2^20 points
/// (16 MiB, and as much scratch). A longer record is filtered in
/// overlapping blocks (issue 30, class 10: the one FFT of a 1e7-sample
/// record, zero-padded to 2^25 points, took 512 MiB, twice over with its
/// scratch).
pub const ANALYTIC_BLOCK: usize = 1 << 20;

/// The one-sided band-pass weight of bin `k` of a `len`-point FFT (bin
/// width `df` Hz): 1 inside `band` (Hz) more than `edge` from its ends, a
/// raised-cosine taper over `edge`, 0 outside, at DC and at and above
/// Nyquist (the analytic signal keeps positive frequencies only).
fn band_weight(k: usize, len: usize, df: f64, band: (f64, f64), edge: f64) -> f64 {
    let f = k as f64 * df;
    if k == 0 || k >= len / 2 || f < band.0 || f > band.1 {
        return 0.0;
    }
    let d = (f - band.0).min(band.1 - f);
    if d >= edge {
        1.0
    } else {
        0.5 - 0.5 * (std::f64::consts::PI * d / edge).cos()
    }
}

/// The analytic signal of `x` (mean removed) restricted to the band
/// `[f1, f2]` Hz, handed to `out` in consecutive pieces that cover the
/// record in order.
///
/// A record with `(2N).next_power_of_two() <= `[`ANALYTIC_BLOCK`] (N up to
/// 2^19) is one piece: the whole record zero-padded to a power of two
/// >= 2N, as always. A longer one is filtered block by block (overlap-save)
/// with the same mask on a grid of `L >= ANALYTIC_BLOCK` points: each block
/// keeps its middle half and reads a quarter block (`L/4 >= 100 fs/edge`,
/// a hundred time scales of the raised-cosine edge) either side. The
/// filter's impulse response falls off as `1/t³` beyond `fs/edge`, so the
/// blocks differ from the single FFT only by that tail (relative 1e-6 or
/// less of the envelope).
/// `cancel` is polled before each block.
fn analytic_pieces(
    x: &[f64],
    fs: f64,
    band: (f64, f64),
    cancel: Cancel,
    out: &mut dyn FnMut(&[Complex<f64>]),
) -> Result<(), Interrupted> {
    let n = x.len();
    let zero = Complex::new(0.0, 0.0);
    let mean = x.iter().sum::<f64>() / n.max(1) as f64;
    let m = (2 * n).next_power_of_two();
    // raised-cosine edges (10 % of the band each side, inside the band):
    // a brick-wall mask would ring for the whole record (sinc tails ~1/t)
    let edge = 0.1 * (band.1 - band.0);
    let reach = 4.0 * 100.0 * fs / edge;
    let block = if reach.is_finite() && reach > 0.0 && reach < (1u64 << 40) as f64 {
        (reach.ceil() as usize)
            .next_power_of_two()
            .max(ANALYTIC_BLOCK)
    } else {
        usize::MAX
    };
    // (FFT length, samples read before the kept part, samples kept)
    let (len, lead, keep) = if m <= block {
        (m, 0, n)
    } else {
        (block, block / 4, block / 2)
    };
    let mut planner = FftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(len);
    let inverse = planner.plan_fft_inverse(len);
    let mut scratch = vec![
        zero;
        forward
            .get_inplace_scratch_len()
            .max(inverse.get_inplace_scratch_len())
    ];
    let mut buf = vec![zero; len];
    let df = fs / len as f64;
    let mut s = 0;
    while s < n {
        cancel.check()?;
        // samples s - lead .. s - lead + len, zero outside the record
        for (j, c) in buf.iter_mut().enumerate() {
            *c = match (s + j).checked_sub(lead) {
                Some(t) if t < n => Complex::new(x[t] - mean, 0.0),
                _ => zero,
            };
        }
        forward.process_with_scratch(&mut buf, &mut scratch);
        for (k, c) in buf.iter_mut().enumerate() {
            *c *= 2.0 * band_weight(k, len, df, band, edge) / len as f64;
        }
        inverse.process_with_scratch(&mut buf, &mut scratch);
        out(&buf[lead..lead + keep.min(n - s)]);
        s += keep;
    }
    Ok(())
}

/// Analytic signal of `x` (mean removed) restricted to the band `[f1, f2]` Hz
/// (see `analytic_pieces` for records longer than 2^19 samples).
pub fn analytic_signal(x: &[f64], fs: f64, band: (f64, f64)) -> Vec<Complex<f64>> {
    let mut z = Vec::with_capacity(x.len());
    analytic_pieces(x, fs, band, Cancel::NEVER, &mut |p| z.extend_from_slice(p))
        .expect("never cancelled");
    z
}

/// The frequency of the largest bin of the spectrum of `x` (mean removed,
/// zero-padded to a power of two `M`).
///
/// Computed in `O(M/2)` memory rather than three times that (issue 30,
/// class 10: one complex FFT of 2^24 points at 1e7 samples took 256 MiB,
/// as much scratch and as many twiddle factors). The record is real, so its
/// spectrum comes from the `h = M/2`-point FFT `Z` of the even and odd
/// samples packed as real and imaginary parts; that FFT is done in four
/// steps (`h = n1 n2`: `n2` FFTs of `n1` points over strided samples,
/// twiddles, `n1` FFTs of `n2` points), which needs one `h`-point
/// intermediate and small plans; the last FFTs give `Z` column by column,
/// and each bin's power is taken there, never stored.
/// `cancel` is polled every 64 of the small FFTs.
fn peak_frequency(x: &[f64], fs: f64, cancel: Cancel) -> Result<f64, Interrupted> {
    let n = x.len();
    let m = n.next_power_of_two().max(4);
    let h = m / 2;
    let mean = x.iter().sum::<f64>() / n as f64;
    let at = |t: usize| if t < n { x[t] - mean } else { 0.0 };
    let zero = Complex::new(0.0, 0.0);
    let n1 = 1usize << (h.trailing_zeros() / 2);
    let n2 = h / n1;
    let mut planner = FftPlanner::<f64>::new();
    let (f1, f2) = (planner.plan_fft_forward(n1), planner.plan_fft_forward(n2));
    let mut scratch = vec![
        zero;
        f1.get_inplace_scratch_len()
            .max(f2.get_inplace_scratch_len())
    ];
    let twiddle = |j: usize, k: usize| {
        let (sin, cos) = (-TWO_PI * ((j * k) % h) as f64 / h as f64).sin_cos();
        Complex::new(cos, sin)
    };
    // step 1: a[j2 n1 + k1] = w_h^(j2 k1) FFT_n1(p[n2 j1 + j2] over j1)[k1]
    let mut a = vec![zero; h];
    for j2 in 0..n2 {
        if j2 % 64 == 0 {
            cancel.check()?;
        }
        let row = &mut a[j2 * n1..(j2 + 1) * n1];
        for (j1, c) in row.iter_mut().enumerate() {
            let j = n2 * j1 + j2;
            *c = Complex::new(at(2 * j), at(2 * j + 1));
        }
        f1.process_with_scratch(row, &mut scratch);
        for (k1, c) in row.iter_mut().enumerate() {
            *c *= twiddle(j2, k1);
        }
    }
    // step 2: Z[k1 + n1 k2] = FFT_n2(a[j2 n1 + k1] over j2)[k2], for the
    // columns k1 and n1 - k1 together: X[k] needs Z[k] and Z[h - k]
    let column = |k1: usize, out: &mut Vec<Complex<f64>>, scratch: &mut Vec<Complex<f64>>| {
        out.clear();
        out.extend((0..n2).map(|j2| a[j2 * n1 + k1]));
        f2.process_with_scratch(out, scratch);
    };
    let (mut c, mut d) = (Vec::with_capacity(n2), Vec::with_capacity(n2));
    let mut best = (1, f64::NEG_INFINITY);
    for k1 in 0..=n1 / 2 {
        if k1 % 32 == 0 {
            cancel.check()?;
        }
        let k1r = (n1 - k1) % n1;
        column(k1, &mut c, &mut scratch);
        column(k1r, &mut d, &mut scratch);
        for (col, other, kk1) in [(&c, &d, k1), (&d, &c, k1r)] {
            for k2 in 0..n2 {
                let k = kk1 + n1 * k2;
                if k == 0 || k >= h {
                    continue;
                }
                // Z[h - k] is in the other column
                let r = h - k;
                let zr = other[r / n1];
                debug_assert_eq!(r % n1, (n1 - kk1) % n1);
                // X[k] = E[k] + e^(-2πik/M) O[k], the spectra of the even and odd
                // samples E = (Z[k] + conj Z[h-k]) / 2, O = (Z[k] - conj Z[h-k]) / 2i
                let (za, zb) = (col[k2], zr.conj());
                let even = (za + zb) * 0.5;
                let odd = (za - zb) * Complex::new(0.0, -0.5);
                let (sin, cos) = (-TWO_PI * k as f64 / m as f64).sin_cos();
                let p = (even + Complex::new(cos, sin) * odd).norm_sqr();
                // the last of equal maxima, as `max_by` over k
                if p > best.1 || (p == best.1 && k > best.0) {
                    best = (k, p);
                }
            }
        }
    }
    Ok(best.0 as f64 * fs / m as f64)
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

/// Envelope `|z|` of the analytic signal (no complex copy of the record).
fn envelope(x: &[f64], fs: f64, band: (f64, f64), cancel: Cancel) -> Result<Vec<f64>, Interrupted> {
    let mut env = Vec::with_capacity(x.len());
    analytic_pieces(x, fs, band, cancel, &mut |p| {
        env.extend(p.iter().map(|c| c.norm()))
    })?;
    Ok(env)
}

/// The model's simulated free decay from `(x0, 0)`: `n` samples of
/// [`simulate_states`] with zero input, computed in pieces of 2^16 samples,
/// each started from the state the previous one ended in. The steps are
/// those of one call (the input is zero throughout and the state carries
/// over exactly), without an `n`-sample zero input and its upsampled copy
/// in memory (issue 30, class 10). `None` if the simulation fails;
/// `cancel` is polled before each piece.
fn free_decay(
    tm: &TimeModel,
    n: usize,
    fs: f64,
    x0: f64,
    cancel: Cancel,
) -> Result<Option<Vec<f64>>, Interrupted> {
    const PIECE: usize = 1 << 16;
    let zeros = vec![0.0; PIECE + 1];
    let mut y = Vec::with_capacity(n);
    let mut state = State { x: x0, v: 0.0 };
    while y.len() < n {
        cancel.check()?;
        let k = (n - y.len()).min(PIECE);
        // one sample more than kept, except at the end: the next start
        let steps = if y.len() + k < n { k + 1 } else { k };
        let Ok((ys, vs)) =
            simulate_states(tm, &zeros[..steps], fs, state, &Discretisation::default())
        else {
            return Ok(None);
        };
        y.extend_from_slice(&ys[..k]);
        if steps > k {
            state = State {
                x: ys[k] - tm.output_offset,
                v: vs[k],
            };
        }
    }
    Ok(Some(y))
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
            let fp = peak_frequency(seg0, fs, opts.cancel)?;
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
            let env = envelope(x, fs, band, opts.cancel)?;
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
        let env = envelope(x, fs, band, opts.cancel)?;
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
    // envelope and phase of the analytic signal: two real vectors, filled
    // piece by piece, no complex copy of the record (issue 30, class 10)
    let mut amp_all = Vec::with_capacity(seg.len());
    let mut phase = Vec::with_capacity(seg.len());
    analytic_pieces(seg, fs, band, opts.cancel, &mut |p| {
        amp_all.extend(p.iter().map(|c| c.norm()));
        phase.extend(p.iter().map(|c| c.arg()));
    })?;
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
    // the analysed range of both, cut in place (shrinking returns the rest)
    let mut amplitude = amp_all;
    amplitude.truncate(stop);
    amplitude.drain(..trim);
    amplitude.shrink_to_fit();
    phase.truncate(stop + 1);
    phase.drain(..trim.saturating_sub(1));
    // unwrapped in place
    let mut off = 0.0;
    let mut prev = 0.0;
    for (i, p) in phase.iter_mut().enumerate() {
        let raw = *p;
        if i > 0 {
            let d = raw - prev;
            if d > std::f64::consts::PI {
                off -= TWO_PI;
            } else if d < -std::f64::consts::PI {
                off += TWO_PI;
            }
        }
        prev = raw;
        *p = raw + off;
    }
    // instantaneous frequency in place: f[k] needs the phase at k and k + 2
    // only (trim >= 1, so the phase has two samples more than the
    // amplitude and k + 2 is never overwritten before it is read)
    let mut f_hz = phase;
    let last_phase = f_hz.len() - 1;
    for k in 0..amplitude.len() {
        let (a, b) = (k, (k + 2).min(last_phase));
        f_hz[k] = (f_hz[b] - f_hz[a]) * fs / ((b - a) as f64 * TWO_PI);
    }
    f_hz.truncate(amplitude.len());
    f_hz.shrink_to_fit();
    // amplitude bins
    let amax = amplitude.iter().cloned().fold(0.0, f64::max);
    let amin = amplitude.iter().cloned().fold(f64::INFINITY, f64::min);
    let nb = opts.bins.max(4);
    let (la, lb) = (amin.ln(), amax.ln());
    let mut backbone = Vec::new();
    for b in 0..nb {
        opts.cancel.check()?;
        let lo = (la + (lb - la) * b as f64 / nb as f64).exp();
        let hi = (la + (lb - la) * (b + 1) as f64 / nb as f64).exp();
        // the bin's samples, in order, in two passes (means, then the
        // slope) rather than a list of their indices (up to the record)
        let bin = || {
            (0..amplitude.len())
                .filter(|&k| amplitude[k] >= lo && (amplitude[k] < hi || (b == nb - 1)))
        };
        let (mut count, mut first, mut last) = (0usize, 0usize, 0usize);
        let (mut st, mut sl, mut sf) = (0.0, 0.0, 0.0);
        for k in bin() {
            if count == 0 {
                first = k;
            }
            last = k;
            count += 1;
            st += k as f64 / fs;
            sl += amplitude[k].ln();
            sf += f_hz[k];
        }
        // at least two cycles in the bin
        let span = last - first;
        if count < 8 || (span as f64) < 2.0 * fs / fc {
            continue;
        }
        let m = count as f64;
        let tm = st / m;
        let lm = sl / m;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for k in bin() {
            let dt = k as f64 / fs - tm;
            sxy += dt * (amplitude[k].ln() - lm);
            sxx += dt * dt;
        }
        backbone.push(DecayPoint {
            amplitude: lm.exp(),
            f_hz: sf / m,
            decay_rate: -sxy / sxx,
            samples: count,
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
        if let Some(sim) = free_decay(&tm, len + 2 * trim, fs, res.amplitude[0], opts.cancel)? {
            // pad before the start with the same oscillation backwards is
            // not available: analyse the simulated decay from its start and
            // compare from sample 0 (the simulated decay starts at a0);
            // only the first `len` samples of its envelope are kept
            let mut m = Vec::with_capacity(len);
            analytic_pieces(&sim, fs, band, opts.cancel, &mut |p| {
                let k = (len - m.len()).min(p.len());
                m.extend(p[..k].iter().map(|c| c.norm()));
            })?;
            drop(sim);
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

    /// The analytic signal as one FFT of the whole record zero-padded to
    /// `(2N).next_power_of_two()` points: the computation before issue 30's
    /// class 10, the reference of the block-wise one.
    fn one_fft_analytic(x: &[f64], fs: f64, band: (f64, f64)) -> Vec<Complex<f64>> {
        let n = x.len();
        let mean = x.iter().sum::<f64>() / n as f64;
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
        let edge = 0.1 * (band.1 - band.0);
        for (k, c) in buf.iter_mut().enumerate() {
            *c *= 2.0 * band_weight(k, m, df, band, edge) / m as f64;
        }
        planner.plan_fft_inverse(m).process(&mut buf);
        buf.truncate(n);
        buf
    }

    fn decaying_sine(n: usize, fs: f64, f: f64, rate: f64) -> Vec<f64> {
        (0..n)
            .map(|k| {
                let t = k as f64 / fs;
                (-rate * t).exp() * (TWO_PI * f * t).sin() + 0.01 * (TWO_PI * 3.1 * f * t).sin()
            })
            .collect()
    }

    #[test]
    fn short_records_are_one_fft_bit_for_bit() {
        // up to 2^19 samples nothing changed (issue 30, class 10)
        for n in [64, 1000, 4097, 1 << 19] {
            let x = decaying_sine(n, 1000.0, 37.0, 0.5);
            assert_eq!(
                analytic_signal(&x, 1000.0, (18.0, 55.0)),
                one_fft_analytic(&x, 1000.0, (18.0, 55.0)),
                "{n}"
            );
        }
    }

    #[test]
    fn blocks_match_the_one_fft() {
        // 2^19 + 1 samples: (2N).next_power_of_two() = 2^21 > ANALYTIC_BLOCK
        let (fs, n) = (2000.0, (1 << 19) + 1);
        let x = decaying_sine(n, fs, 37.0, 0.02);
        let band = (18.5, 55.5);
        let reference = one_fft_analytic(&x, fs, band);
        let mut pieces = 0;
        let mut z = Vec::new();
        analytic_pieces(&x, fs, band, Cancel::NEVER, &mut |p| {
            pieces += 1;
            z.extend_from_slice(p)
        })
        .unwrap();
        assert!(pieces > 1, "{pieces} piece(s)");
        assert_eq!(z.len(), n);
        let scale = reference.iter().fold(0.0f64, |a, c| a.max(c.norm()));
        let worst = z
            .iter()
            .zip(&reference)
            .fold(0.0f64, |a, (u, v)| a.max((u - v).norm()));
        assert!(worst < 1e-9 * scale, "{worst:e} of {scale}");
    }

    #[test]
    fn peak_frequency_is_the_largest_bin_of_the_full_spectrum() {
        for (n, fs, f) in [
            (100, 100.0, 7.3),
            (5000, 1000.0, 37.0),
            (300_001, 10_000.0, 123.4),
        ] {
            let x = decaying_sine(n, fs, f, 0.3);
            let m = n.next_power_of_two();
            let mean = x.iter().sum::<f64>() / n as f64;
            let mut buf: Vec<Complex<f64>> = (0..m)
                .map(|t| Complex::new(if t < n { x[t] - mean } else { 0.0 }, 0.0))
                .collect();
            FftPlanner::<f64>::new()
                .plan_fft_forward(m)
                .process(&mut buf);
            let k = (1..m / 2)
                .max_by(|&a, &b| buf[a].norm_sqr().total_cmp(&buf[b].norm_sqr()))
                .unwrap();
            assert_eq!(
                peak_frequency(&x, fs, Cancel::NEVER).unwrap(),
                k as f64 * fs / m as f64,
                "{n}"
            );
        }
    }

    #[test]
    fn the_free_decay_in_pieces_is_one_simulation() {
        let tm = TimeModel {
            model: NormalisedModel {
                alpha: (TWO_PI * 37.0).powi(2),
                beta: 1e4,
                rho: 2.0,
                delta: 0.5,
                kappa: 0.3,
                eta: 1.0,
            },
            gain: 0.0,
            input_offset: 0.0,
            output_offset: 0.0,
        };
        let (fs, n) = (1000.0, 3 * (1 << 16) + 5);
        let one = super::super::time_domain::simulate_output(
            &tm,
            &vec![0.0; n],
            fs,
            State { x: 0.8, v: 0.0 },
        )
        .unwrap();
        let pieces = free_decay(&tm, n, fs, 0.8, Cancel::NEVER).unwrap();
        assert_eq!(pieces.unwrap(), one);
    }

    /// A set flag ends the analysis with the typed error, not a result
    /// (issue 27: Ctrl-C); the same record without it is analysed.
    #[test]
    fn a_cancelled_analysis_ends_with_interrupted() {
        use std::sync::atomic::AtomicBool;
        static STOP: AtomicBool = AtomicBool::new(true);
        let x = decaying_sine(20_000, 1000.0, 20.0, 0.3);
        let opts = DecayOptions {
            cancel: Cancel::new(&STOP),
            ..DecayOptions::default()
        };
        assert!(matches!(
            analyse(&x, 1000.0, &opts),
            Err(DecayError::Interrupted(Interrupted))
        ));
        let given = DecayOptions {
            t_start: Some(0.0),
            band: Some((10.0, 30.0)),
            ..opts
        };
        assert!(matches!(
            analyse(&x, 1000.0, &given),
            Err(DecayError::Interrupted(Interrupted))
        ));
        assert!(analyse(&x, 1000.0, &DecayOptions::default()).is_ok());
    }

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
