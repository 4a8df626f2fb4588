//! `nlsdof signal`: make input accelerations (CSV `t,accel`) — sine, linear
//! or logarithmic chirp, open-loop stepped sine.

use super::simulate::Progress;
use crate::error::CliError;
use nlsdof::excitation::{Dwell, Excitation, LinearChirp, LogChirp, Sine, SteppedSine};
use nlsdof_io::signal_file::CsvWriter;
use std::f64::consts::TAU;
use std::path::PathBuf;

#[derive(clap::Args)]
#[command(about = "Make an input acceleration signal (CSV t,accel): sine, chirp or stepped sine")]
pub struct Args {
    #[command(subcommand)]
    pub kind: Kind,
}

/// Sampling and output shared by every signal.
#[derive(clap::Args)]
pub struct Common {
    /// Amplitude, m/s^2 zero-to-peak.
    #[arg(long, allow_hyphen_values = true)]
    pub amplitude: f64,
    /// Sampling frequency, Hz (> 0); at most 1e10 samples in all (duration x fs).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: f64,
    /// Output CSV (t,accel); written atomically.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

/// `--kind` of chirp.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ChirpKind {
    /// f(t) = f0 + rate t.
    Linear,
    /// f(t) = f0 (f1/f0)^(t/T).
    Log,
}

/// `--sweep` of a stepped sine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Direction {
    Up,
    Down,
}

#[derive(clap::Subcommand)]
pub enum Kind {
    /// gamma = A sin(2 pi f t + phase).
    Sine {
        #[command(flatten)]
        common: Common,
        /// Frequency, Hz.
        #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
        freq: f64,
        /// Duration, s.
        #[arg(long, value_name = "S", allow_hyphen_values = true)]
        duration: f64,
        /// Initial phase, degrees.
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        phase_deg: f64,
    },
    /// Linear (f0 + rate t) or logarithmic chirp, gamma = A sin(theta(t)).
    Chirp {
        #[command(flatten)]
        common: Common,
        #[arg(long, value_enum, default_value_t = ChirpKind::Linear)]
        kind: ChirpKind,
        /// Start frequency, Hz.
        #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
        f0: f64,
        /// End frequency, Hz (with --duration, or with --rate for a linear chirp).
        #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
        f1: Option<f64>,
        /// Sweep rate of a linear chirp, Hz/s (the paper: +0.005 from 4.5 to 6 Hz).
        #[arg(long, value_name = "HZ_PER_S", allow_hyphen_values = true)]
        rate: Option<f64>,
        /// Duration, s.
        #[arg(long, value_name = "S", allow_hyphen_values = true)]
        duration: Option<f64>,
    },
    /// Phase-continuous stepped sine with a fixed dwell per step (open loop).
    SteppedSine {
        #[command(flatten)]
        common: Common,
        #[arg(long = "f-min", value_name = "HZ", allow_hyphen_values = true)]
        f_min: f64,
        #[arg(long = "f-max", value_name = "HZ", allow_hyphen_values = true)]
        f_max: f64,
        /// Number of steps (2 to 1000000), f-min and f-max included.
        #[arg(long)]
        steps: usize,
        #[arg(long, value_enum, default_value_t = Direction::Up)]
        sweep: Direction,
        /// Dwell per step in whole cycles.
        #[arg(long, value_name = "N", conflicts_with = "dwell")]
        dwell_cycles: Option<u32>,
        /// Dwell per step in seconds.
        #[arg(long, value_name = "S", allow_hyphen_values = true)]
        dwell: Option<f64>,
    },
}

fn positive(flag: &str, v: f64) -> Result<f64, CliError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(CliError::Usage(format!(
            "{flag} {v} is not allowed: must be a finite number > 0"
        )))
    }
}

/// Largest number of samples a signal may have.
const MAX_SAMPLES: f64 = 1e10;

fn write<E: Excitation>(e: &E, c: &Common, duration: f64) -> Result<(), CliError> {
    let fs = c.fs;
    let n = (duration * fs).floor() + 1.0;
    if n > MAX_SAMPLES {
        return Err(CliError::Usage(format!(
            "{n} samples is too many (duration {duration} s at {fs} Hz)"
        )));
    }
    let n = n as u64;
    let mut w = CsvWriter::create(&c.out, &["t", "accel"])?;
    let progress = Progress::new(n, "writing signal");
    for k in 0..n {
        let t = k as f64 / fs;
        w.row(&[t, e.accel(t)])?;
        if k & 0xffff == 0 {
            progress.set(k);
        }
    }
    w.commit()?;
    progress.finish();
    println!(
        "wrote {n} samples ({duration} s at {fs} Hz) to {}",
        c.out.display()
    );
    Ok(())
}

pub fn run(a: Args) -> Result<(), CliError> {
    match a.kind {
        Kind::Sine {
            common,
            freq,
            duration,
            phase_deg,
        } => {
            positive("--fs", common.fs)?;
            let s = Sine::new(
                common.amplitude,
                TAU * positive("--freq", freq)?,
                phase_deg.to_radians(),
            )?;
            write(&s, &common, positive("--duration", duration)?)
        }
        Kind::Chirp {
            common,
            kind,
            f0,
            f1,
            rate,
            duration,
        } => {
            positive("--fs", common.fs)?;
            positive("--f0", f0)?;
            match kind {
                ChirpKind::Linear => {
                    let (rate, duration) = match (f1, rate, duration) {
                        (Some(f1), None, Some(d)) => ((positive("--f1", f1)? - f0) / positive("--duration", d)?, d),
                        (None, Some(r), Some(d)) => (r, positive("--duration", d)?),
                        (Some(f1), Some(r), None) => {
                            let d = (positive("--f1", f1)? - f0) / r;
                            (r, positive("duration (f1 - f0)/rate", d)?)
                        }
                        _ => {
                            return Err(CliError::Usage(
                                "a linear chirp needs two of --f1, --rate, --duration (e.g. --f0 4.5 --rate 0.005 --f1 6)".into(),
                            ))
                        }
                    };
                    if !rate.is_finite() {
                        return Err(CliError::Usage(format!(
                            "--rate {rate} is not a finite number"
                        )));
                    }
                    let end = f0 + rate * duration;
                    if end <= 0.0 {
                        return Err(CliError::Usage(format!(
                            "the chirp would reach {end} Hz <= 0 before its end"
                        )));
                    }
                    let c = LinearChirp::from_rate(common.amplitude, TAU * f0, TAU * rate)?;
                    write(&c, &common, duration)
                }
                ChirpKind::Log => {
                    let (Some(f1), Some(d), None) = (f1, duration, rate) else {
                        return Err(CliError::Usage(
                            "a logarithmic chirp needs --f1 and --duration (and no --rate)".into(),
                        ));
                    };
                    let c = LogChirp::new(
                        common.amplitude,
                        TAU * f0,
                        TAU * positive("--f1", f1)?,
                        positive("--duration", d)?,
                    )?;
                    write(&c, &common, d)
                }
            }
        }
        Kind::SteppedSine {
            common,
            f_min,
            f_max,
            steps,
            sweep,
            dwell_cycles,
            dwell,
        } => {
            positive("--fs", common.fs)?;
            positive("--f-min", f_min)?;
            if !(f_max.is_finite() && f_max > f_min) {
                return Err(CliError::Usage(format!(
                    "--f-max {f_max} must be finite and > --f-min {f_min}"
                )));
            }
            if !(2..=nlsdof::stepped_sine::MAX_STEPS).contains(&steps) {
                return Err(CliError::Usage(format!(
                    "--steps {steps}: need 2 to {}",
                    nlsdof::stepped_sine::MAX_STEPS
                )));
            }
            let dw = match (dwell_cycles, dwell) {
                (Some(c), None) => Dwell::Cycles(c),
                (None, Some(s)) => Dwell::Seconds(positive("--dwell", s)?),
                _ => {
                    return Err(CliError::Usage(
                        "give the dwell per step: --dwell-cycles N or --dwell SECONDS".into(),
                    ))
                }
            };
            let mut omegas: Vec<f64> = (0..steps)
                .map(|i| TAU * (f_min + (f_max - f_min) * i as f64 / (steps - 1) as f64))
                .collect();
            if sweep == Direction::Down {
                omegas.reverse();
            }
            let s = SteppedSine::new(common.amplitude, omegas, dw)?;
            let d = s.duration();
            write(&s, &common, d)
        }
    }
}
