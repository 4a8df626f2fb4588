//! `nlsdof signal`: make input accelerations (CSV `t,accel`) — sine, linear
//! or logarithmic chirp, open-loop stepped sine.

use super::simulate::Progress;
use crate::error::CliError;
use nlsdof::signal_generator::{build, GeneratedSignal, Param, SignalSpec, SignalSpecError};
use nlsdof_io::signal_file::CsvWriter;
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

/// The library's error with the parameters named by their flags.
fn usage(e: SignalSpecError) -> CliError {
    match e {
        SignalSpecError::Excitation(e) => CliError::Simulation(e),
        e => CliError::Usage(e.render(Param::flag)),
    }
}

fn write(g: &GeneratedSignal, c: &Common) -> Result<(), CliError> {
    let (n, fs, duration) = (g.samples, g.fs, g.duration);
    let mut w = CsvWriter::create(&c.out, &["t", "accel"])?;
    let progress = Progress::new(n, "writing signal");
    for k in 0..n {
        let (t, a) = g.sample(k);
        w.row(&[t, a])?;
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

/// The library's description of the signal `kind` and its common options.
fn spec(kind: Kind) -> (SignalSpec, Common) {
    match kind {
        Kind::Sine {
            common,
            freq,
            duration,
            phase_deg,
        } => (
            SignalSpec::Sine {
                amplitude: common.amplitude,
                freq,
                duration,
                phase_deg,
            },
            common,
        ),
        Kind::Chirp {
            common,
            kind,
            f0,
            f1,
            rate,
            duration,
        } => (
            SignalSpec::Chirp {
                amplitude: common.amplitude,
                kind: match kind {
                    ChirpKind::Linear => nlsdof::signal_generator::ChirpKind::Linear,
                    ChirpKind::Log => nlsdof::signal_generator::ChirpKind::Log,
                },
                f0,
                f1,
                rate,
                duration,
            },
            common,
        ),
        Kind::SteppedSine {
            common,
            f_min,
            f_max,
            steps,
            sweep,
            dwell_cycles,
            dwell,
        } => (
            SignalSpec::SteppedSine {
                amplitude: common.amplitude,
                f_min,
                f_max,
                steps,
                sweep: match sweep {
                    Direction::Up => nlsdof::SweepDirection::Up,
                    Direction::Down => nlsdof::SweepDirection::Down,
                },
                dwell_cycles,
                dwell,
            },
            common,
        ),
    }
}

pub fn run(a: Args) -> Result<(), CliError> {
    let (spec, common) = spec(a.kind);
    let g = build(&spec, common.fs).map_err(usage)?;
    write(&g, &common)
}
