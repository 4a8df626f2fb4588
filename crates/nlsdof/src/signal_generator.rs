//! The input accelerations of `nlsdof signal` and of Python's `signal`:
//! a sine, a linear or logarithmic chirp, or an open-loop stepped sine,
//! built from the verb's parameters (validated here, once for both front
//! ends) and sampled at `fs` from t = 0 to the duration, both ends
//! included.
//!
//! Errors name the offending parameter; [`SignalSpecError::render`] names it
//! as the caller spells it (Python argument or CLI flag, [`Param`]).

use crate::error::SimulationError;
use crate::excitation::{Dwell, Excitation, LinearChirp, LogChirp, Sine, SteppedSine};
use crate::SweepDirection;
use std::f64::consts::TAU;
use thiserror::Error;

/// Largest number of samples a signal may have (duration x fs + 1).
pub const MAX_SAMPLES: f64 = 1e10;

/// A parameter of a signal, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    Fs,
    Freq,
    Duration,
    /// The duration of a linear chirp given by f0, f1 and its rate.
    ChirpDuration,
    F0,
    F1,
    Rate,
    FMin,
    FMax,
    Steps,
    Dwell,
    DwellCycles,
}

impl Param {
    /// The Python argument's name.
    pub fn python(self) -> &'static str {
        match self {
            Param::Fs => "fs",
            Param::Freq => "freq",
            Param::Duration => "duration",
            Param::ChirpDuration => "duration (f1 - f0)/rate",
            Param::F0 => "f0",
            Param::F1 => "f1",
            Param::Rate => "rate",
            Param::FMin => "f_min",
            Param::FMax => "f_max",
            Param::Steps => "steps",
            Param::Dwell => "dwell",
            Param::DwellCycles => "dwell_cycles",
        }
    }

    /// The CLI flag (`nlsdof signal`).
    pub fn flag(self) -> &'static str {
        match self {
            Param::Fs => "--fs",
            Param::Freq => "--freq",
            Param::Duration => "--duration",
            Param::ChirpDuration => "duration (f1 - f0)/rate",
            Param::F0 => "--f0",
            Param::F1 => "--f1",
            Param::Rate => "--rate",
            Param::FMin => "--f-min",
            Param::FMax => "--f-max",
            Param::Steps => "--steps",
            Param::Dwell => "--dwell",
            Param::DwellCycles => "--dwell-cycles",
        }
    }
}

/// Why a signal cannot be made; each variant carries the offending values.
/// `Display` names parameters as Python does.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SignalSpecError {
    #[error("{}", self.render(Param::python))]
    NotPositive { param: Param, value: f64 },
    #[error("{}", self.render(Param::python))]
    TooManySamples {
        samples: f64,
        duration: f64,
        fs: f64,
    },
    #[error("{}", self.render(Param::python))]
    LinearChirpUnderdetermined,
    #[error("{}", self.render(Param::python))]
    RateNotFinite { rate: f64 },
    #[error("{}", self.render(Param::python))]
    ChirpEndsBelowZero { end_hz: f64 },
    #[error("{}", self.render(Param::python))]
    LogChirpUnderdetermined,
    #[error("{}", self.render(Param::python))]
    BadBand { f_min: f64, f_max: f64 },
    #[error("{}", self.render(Param::python))]
    BadSteps { steps: usize },
    #[error("{}", self.render(Param::python))]
    NoDwell,
    #[error("{}", self.render(Param::python))]
    Excitation(SimulationError),
}

impl SignalSpecError {
    /// The one-line message with parameters named by `name` (e.g.
    /// [`Param::flag`] for the CLI).
    pub fn render(&self, name: fn(Param) -> &'static str) -> String {
        use SignalSpecError::*;
        match self {
            NotPositive { param, value } => format!(
                "{} {value} is not allowed: must be a finite number > 0",
                name(*param)
            ),
            TooManySamples {
                samples,
                duration,
                fs,
            } => format!("{samples} samples is too many (duration {duration} s at {fs} Hz)"),
            LinearChirpUnderdetermined => {
                // the example as the caller writes it: `--f0 4.5` or `f0=4.5`
                let ex = |p: Param, v: &str| {
                    let n = name(p);
                    if n.starts_with("--") {
                        format!("{n} {v}")
                    } else {
                        format!("{n}={v}")
                    }
                };
                let sep = if name(Param::F0).starts_with("--") {
                    " "
                } else {
                    ", "
                };
                format!(
                    "a linear chirp needs two of {}, {}, {} (e.g. {})",
                    name(Param::F1),
                    name(Param::Rate),
                    name(Param::Duration),
                    [
                        ex(Param::F0, "4.5"),
                        ex(Param::Rate, "0.005"),
                        ex(Param::F1, "6")
                    ]
                    .join(sep)
                )
            }
            RateNotFinite { rate } => {
                format!("{} {rate} is not a finite number", name(Param::Rate))
            }
            ChirpEndsBelowZero { end_hz } => {
                format!("the chirp would reach {end_hz} Hz <= 0 before its end")
            }
            LogChirpUnderdetermined => format!(
                "a logarithmic chirp needs {} and {} (and no {})",
                name(Param::F1),
                name(Param::Duration),
                name(Param::Rate)
            ),
            BadBand { f_min, f_max } => format!(
                "{} {f_max} must be finite and > {} {f_min}",
                name(Param::FMax),
                name(Param::FMin)
            ),
            BadSteps { steps } => format!(
                "{} {steps}: need 2 to {}",
                name(Param::Steps),
                crate::stepped_sine::MAX_STEPS
            ),
            NoDwell => format!(
                "give the dwell per step: {} N or {} SECONDS",
                name(Param::DwellCycles),
                name(Param::Dwell)
            ),
            Excitation(e) => e.to_string(),
        }
    }
}

impl From<SimulationError> for SignalSpecError {
    fn from(e: SimulationError) -> Self {
        SignalSpecError::Excitation(e)
    }
}

/// `--kind` of a chirp.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChirpKind {
    /// `f(t) = f0 + rate t`.
    Linear,
    /// `f(t) = f0 (f1/f0)^(t/T)`.
    Log,
}

/// A signal as the verb describes it (frequencies Hz, durations s,
/// amplitude m/s^2 zero-to-peak, phase degrees).
#[derive(Debug, Clone, PartialEq)]
pub enum SignalSpec {
    /// `gamma = A sin(2 pi f t + phase)`.
    Sine {
        amplitude: f64,
        freq: f64,
        duration: f64,
        phase_deg: f64,
    },
    /// A linear chirp (two of `f1`, `rate`, `duration`) or a logarithmic
    /// one (`f1` and `duration`).
    Chirp {
        amplitude: f64,
        kind: ChirpKind,
        f0: f64,
        f1: Option<f64>,
        rate: Option<f64>,
        duration: Option<f64>,
    },
    /// Phase-continuous stepped sine, `steps` equally spaced frequencies
    /// from `f_min` to `f_max` (or back), a dwell per step in whole cycles
    /// or in seconds (exactly one of them).
    SteppedSine {
        amplitude: f64,
        f_min: f64,
        f_max: f64,
        steps: usize,
        sweep: SweepDirection,
        dwell_cycles: Option<u32>,
        dwell: Option<f64>,
    },
}

/// A validated signal: its excitation, duration (s), sampling (Hz) and
/// number of samples.
pub struct GeneratedSignal {
    excitation: Box<dyn Excitation>,
    pub duration: f64,
    pub fs: f64,
    pub samples: u64,
}

impl std::fmt::Debug for GeneratedSignal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeneratedSignal")
            .field("duration", &self.duration)
            .field("fs", &self.fs)
            .field("samples", &self.samples)
            .finish()
    }
}

impl GeneratedSignal {
    /// Time of sample `k`, s.
    pub fn time(&self, k: u64) -> f64 {
        k as f64 / self.fs
    }

    /// The acceleration at time `t`, m/s^2.
    pub fn accel(&self, t: f64) -> f64 {
        self.excitation.accel(t)
    }

    /// Sample `k`: `(t, accel)`.
    pub fn sample(&self, k: u64) -> (f64, f64) {
        let t = self.time(k);
        (t, self.accel(t))
    }
}

fn positive(param: Param, v: f64) -> Result<f64, SignalSpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SignalSpecError::NotPositive { param, value: v })
    }
}

/// Validates `spec` sampled at `fs` Hz and builds the signal.
pub fn build(spec: &SignalSpec, fs: f64) -> Result<GeneratedSignal, SignalSpecError> {
    positive(Param::Fs, fs)?;
    let (excitation, duration): (Box<dyn Excitation>, f64) = match *spec {
        SignalSpec::Sine {
            amplitude,
            freq,
            duration,
            phase_deg,
        } => {
            let s = Sine::new(
                amplitude,
                TAU * positive(Param::Freq, freq)?,
                phase_deg.to_radians(),
            )?;
            (Box::new(s), positive(Param::Duration, duration)?)
        }
        SignalSpec::Chirp {
            amplitude,
            kind,
            f0,
            f1,
            rate,
            duration,
        } => {
            positive(Param::F0, f0)?;
            match kind {
                ChirpKind::Linear => {
                    let (rate, duration) = match (f1, rate, duration) {
                        (Some(f1), None, Some(d)) => (
                            (positive(Param::F1, f1)? - f0) / positive(Param::Duration, d)?,
                            d,
                        ),
                        (None, Some(r), Some(d)) => (r, positive(Param::Duration, d)?),
                        (Some(f1), Some(r), None) => {
                            let d = (positive(Param::F1, f1)? - f0) / r;
                            (r, positive(Param::ChirpDuration, d)?)
                        }
                        _ => return Err(SignalSpecError::LinearChirpUnderdetermined),
                    };
                    if !rate.is_finite() {
                        return Err(SignalSpecError::RateNotFinite { rate });
                    }
                    let end = f0 + rate * duration;
                    if end <= 0.0 {
                        return Err(SignalSpecError::ChirpEndsBelowZero { end_hz: end });
                    }
                    let c = LinearChirp::from_rate(amplitude, TAU * f0, TAU * rate)?;
                    (Box::new(c), duration)
                }
                ChirpKind::Log => {
                    let (Some(f1), Some(d), None) = (f1, duration, rate) else {
                        return Err(SignalSpecError::LogChirpUnderdetermined);
                    };
                    let c = LogChirp::new(
                        amplitude,
                        TAU * f0,
                        TAU * positive(Param::F1, f1)?,
                        positive(Param::Duration, d)?,
                    )?;
                    (Box::new(c), d)
                }
            }
        }
        SignalSpec::SteppedSine {
            amplitude,
            f_min,
            f_max,
            steps,
            sweep,
            dwell_cycles,
            dwell,
        } => {
            positive(Param::FMin, f_min)?;
            if !(f_max.is_finite() && f_max > f_min) {
                return Err(SignalSpecError::BadBand { f_min, f_max });
            }
            if !(2..=crate::stepped_sine::MAX_STEPS).contains(&steps) {
                return Err(SignalSpecError::BadSteps { steps });
            }
            let dw = match (dwell_cycles, dwell) {
                (Some(c), None) => Dwell::Cycles(c),
                (None, Some(s)) => Dwell::Seconds(positive(Param::Dwell, s)?),
                _ => return Err(SignalSpecError::NoDwell),
            };
            let mut omegas: Vec<f64> = (0..steps)
                .map(|i| TAU * (f_min + (f_max - f_min) * i as f64 / (steps - 1) as f64))
                .collect();
            if sweep == SweepDirection::Down {
                omegas.reverse();
            }
            let s = SteppedSine::new(amplitude, omegas, dw)?;
            let d = s.duration();
            (Box::new(s), d)
        }
    };
    let n = (duration * fs).floor() + 1.0;
    if n > MAX_SAMPLES {
        return Err(SignalSpecError::TooManySamples {
            samples: n,
            duration,
            fs,
        });
    }
    Ok(GeneratedSignal {
        excitation,
        duration,
        fs,
        samples: n as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_samples_and_errors_named_per_front_end() {
        let spec = SignalSpec::Sine {
            amplitude: 2.0,
            freq: 5.0,
            duration: 1.0,
            phase_deg: 90.0,
        };
        let s = build(&spec, 100.0).unwrap();
        assert_eq!(s.samples, 101);
        let (t, a) = s.sample(10);
        assert!((t - 0.1).abs() < 1e-15);
        assert!((a - 2.0 * (TAU * 5.0 * 0.1 + std::f64::consts::FRAC_PI_2).sin()).abs() < 1e-12);
        let e = build(&spec, 0.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "fs 0 is not allowed: must be a finite number > 0"
        );
        assert_eq!(
            e.render(Param::flag),
            "--fs 0 is not allowed: must be a finite number > 0"
        );
        let spec = SignalSpec::SteppedSine {
            amplitude: 1.0,
            f_min: 1.0,
            f_max: 2.0,
            steps: 1,
            sweep: SweepDirection::Up,
            dwell_cycles: Some(1),
            dwell: None,
        };
        let e = build(&spec, 100.0).unwrap_err();
        assert!(
            e.render(Param::flag).starts_with("--steps 1: need 2 to"),
            "{e}"
        );
        let spec = SignalSpec::Chirp {
            amplitude: 1.0,
            kind: ChirpKind::Linear,
            f0: 4.5,
            f1: Some(6.0),
            rate: None,
            duration: None,
        };
        let e = build(&spec, 100.0).unwrap_err();
        assert_eq!(e, SignalSpecError::LinearChirpUnderdetermined);
        assert!(
            e.to_string().ends_with("(e.g. f0=4.5, rate=0.005, f1=6)"),
            "{e}"
        );
        assert!(
            e.render(Param::flag)
                .ends_with("(e.g. --f0 4.5 --rate 0.005 --f1 6)"),
            "{e}"
        );
    }
}
