//! `nlsdof stepped-sine`: the virtual stepped-sine test rig — time-domain
//! simulation of what the paper's shaker controller did, with a settling
//! rule that is right for light damping.

use super::simulate::Progress;
use crate::error::CliError;
use nlsdof::stepped_sine::{run_sweeps, RigOptions, RigSweep};
use nlsdof::SweepDirection;
use nlsdof_io::signal_file::CsvWriter;
use nlsdof_report::rig as report;
use nlsdof_report::steady_state::sweep_name as name;
use std::f64::consts::TAU;
use std::path::PathBuf;
use std::time::Instant;

/// `--sweep` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepArg {
    Up,
    Down,
    /// Up, then (separately, from rest) down.
    Both,
}

#[derive(clap::Args)]
#[command(
    about = "Virtual stepped-sine test: simulate the shaker dwell at each frequency until steady, record amplitude and phase",
    after_long_help = RIG_HELP
)]
pub struct Args {
    /// Model file (TOML, SI units).
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Input levels gamma, m/s^2 zero-to-peak, comma-separated (each > 0).
    #[arg(long, value_name = "G1,G2,..", allow_hyphen_values = true)]
    pub gamma: String,
    /// Lowest frequency, Hz.
    #[arg(long = "f-min", value_name = "HZ", allow_hyphen_values = true)]
    pub f_min: f64,
    /// Highest frequency, Hz.
    #[arg(long = "f-max", value_name = "HZ", allow_hyphen_values = true)]
    pub f_max: f64,
    /// Number of frequency steps, linearly spaced, f-min and f-max included (2 to 1000000).
    #[arg(long, value_name = "N")]
    pub steps: usize,
    /// Sweep direction.
    #[arg(long, value_enum, default_value_t = SweepArg::Up)]
    pub sweep: SweepArg,
    /// Output CSV: level,gamma,f_hz,amplitude,phase_deg,sweep.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
    /// Also write per-step details (peak-to-peak, 2nd/3rd harmonics, dwell, settled flag).
    #[arg(long, value_name = "FILE.csv")]
    pub details: Option<PathBuf>,
    /// Also write the simulated time history (level,gamma,sweep,t,accel,x,v).
    #[arg(long, value_name = "FILE.csv")]
    pub history: Option<PathBuf>,
    /// Keep every N-th simulated sample in --history.
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub history_decimate: usize,
    /// RK4 steps per input cycle (16 to 100000).
    #[arg(long, value_name = "N", default_value_t = 64)]
    pub samples_per_cycle: usize,
    /// Settled when the estimated remaining transient is below this fraction of the amplitude.
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Minimum dwell per step in effective decay times 1/sigma_eff.
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub min_decay_times: f64,
    /// Give up on a step after this many cycles (flagged settled=false).
    #[arg(long, default_value_t = 5000)]
    pub max_cycles: usize,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

const RIG_HELP: &str = "WHAT IT DOES:
  At each frequency the input is a phase-continuous sine gamma*cos(theta) (gamma
  zero-to-peak, m/s^2); the model (Eq 32) is integrated by RK4 with N steps per cycle
  from the state left by the previous step; the rig dwells until the response is
  steady, then records the first harmonic of x over the last cycle.

SETTLING RULE:
  The shaker rule 'two consecutive cycle amplitudes within 1 %' stops ~20 % short of
  steady state on a lightly damped structure. Here a step is settled when (1) the dwell
  is at least --min-decay-times effective decay times 1/sigma_eff, sigma_eff =
  (delta + delta_eq(a, Omega))/2 (Eq 22-23), and (2) the geometric tail bound of the
  remaining transient of the complex first harmonic, |D_n| q/(1-q) with D_n = X_n -
  X_{n-1} and q = max(exp(-sigma_eff T), observed |D_n|/|D_{n-1}|), is below
  --tolerance * |X_n| on 3 consecutive cycles.

OUTPUT (SI, amplitudes zero-to-peak):
  --out: level,gamma,f_hz,amplitude,phase_deg,sweep — level is the 1-based index in
         --gamma, amplitude the first-harmonic displacement amplitude (m), phase_deg
         the lag of x behind the input (0..180), rows in sweep order.
  --details: level,gamma,f_hz,amplitude,phase_deg,sweep,peak_to_peak,harmonic2,
         harmonic3,cycles,settled,residual
  --history: level,gamma,sweep,t,accel,x,v (every --history-decimate-th sample)

EXAMPLE (the paper's test: 5 levels x 200 steps of 1 mHz):
  nlsdof stepped-sine --model examples/har-wing.toml --gamma 0.41,0.62,0.81,1.00,1.23 \\
      --f-min 5.3 --f-max 5.499 --steps 200 --sweep up --out rig.csv";

fn parse_gammas(text: &str) -> Result<Vec<f64>, CliError> {
    text.split(',')
        .map(|item| {
            let item = item.trim();
            match item.parse::<f64>() {
                Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
                _ => Err(CliError::Usage(format!(
                    "--gamma: '{item}' is not allowed: give input levels (m/s^2, zero-to-peak) as comma-separated finite numbers > 0"
                ))),
            }
        })
        .collect()
}

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    let gammas = parse_gammas(&a.gamma)?;
    if !(a.f_min.is_finite() && a.f_min > 0.0 && a.f_max.is_finite() && a.f_max > a.f_min) {
        return Err(CliError::Usage(format!(
            "--f-min {} --f-max {}: need 0 < f-min < f-max, both finite (Hz)",
            a.f_min, a.f_max
        )));
    }
    if a.steps < 2 || a.steps > nlsdof::stepped_sine::MAX_STEPS {
        return Err(CliError::Usage(format!(
            "--steps {}: need 2 to {} frequency steps",
            a.steps,
            nlsdof::stepped_sine::MAX_STEPS
        )));
    }
    if a.history_decimate == 0 {
        return Err(CliError::Usage(
            "--history-decimate 0 is not allowed: give N >= 1".into(),
        ));
    }
    let (model, gain) = super::roots::load_steady_model(&a.model)?;
    if let Some(note) = super::roots::gain_note(gain) {
        eprintln!("nlsdof: {note}");
    }
    let nm = model.normalised()?;
    // the model sees input_gain * gamma; every output gives the levels as given
    let model_gammas: Vec<f64> = gammas.iter().map(|g| gain * g).collect();
    let n = a.steps;
    let omegas: Vec<f64> = (0..n)
        .map(|i| {
            TAU * if i == n - 1 {
                a.f_max
            } else {
                a.f_min + (a.f_max - a.f_min) * i as f64 / (n - 1) as f64
            }
        })
        .collect();
    let opts = RigOptions {
        samples_per_cycle: a.samples_per_cycle,
        tolerance: a.tolerance,
        min_decay_times: a.min_decay_times,
        max_cycles: a.max_cycles,
        history_decimation: a.history.as_ref().map(|_| a.history_decimate),
        ..RigOptions::default()
    };
    let dirs: Vec<SweepDirection> = match a.sweep {
        SweepArg::Up => vec![SweepDirection::Up],
        SweepArg::Down => vec![SweepDirection::Down],
        SweepArg::Both => vec![SweepDirection::Up, SweepDirection::Down],
    };
    // create the outputs first: a bad path fails before the simulation
    let mut out = CsvWriter::create(
        &a.out,
        &["level", "gamma", "f_hz", "amplitude", "phase_deg", "sweep"],
    )?;
    let mut details = match &a.details {
        Some(p) => Some(CsvWriter::create(
            p,
            &[
                "level",
                "gamma",
                "f_hz",
                "amplitude",
                "phase_deg",
                "sweep",
                "peak_to_peak",
                "harmonic2",
                "harmonic3",
                "cycles",
                "settled",
                "residual",
            ],
        )?),
        None => None,
    };
    let mut history = match &a.history {
        Some(p) => Some(CsvWriter::create(
            p,
            &["level", "gamma", "sweep", "t", "accel", "x", "v"],
        )?),
        None => None,
    };
    let progress = Progress::new((gammas.len() * n * dirs.len()) as u64, "stepped sine");
    let t_sim = Instant::now();
    let sweeps: Vec<(usize, RigSweep)> =
        run_sweeps(&nm, &model_gammas, &omegas, &dirs, &opts, &|| {
            progress.inc(1)
        })?
        .into_iter()
        .enumerate()
        .map(|(i, mut sw)| {
            let k = i % gammas.len();
            sw.gamma = gammas[k];
            if gain != 1.0 {
                for h in &mut sw.history {
                    h.u /= gain;
                }
            }
            (k, sw)
        })
        .collect();
    let sim_s = t_sim.elapsed().as_secs_f64();
    progress.finish();
    let mut unsettled = 0usize;
    for (k, sw) in &sweeps {
        let level = (k + 1).to_string();
        for p in &sw.points {
            let row = [sw.gamma, p.omega / TAU, p.amplitude, p.phase.to_degrees()];
            out.text(&level)?;
            for v in row {
                out.num(v)?;
            }
            out.text(name(sw.direction))?;
            out.end_row()?;
            if let Some(d) = details.as_mut() {
                d.text(&level)?;
                for v in row {
                    d.num(v)?;
                }
                d.text(name(sw.direction))?;
                for v in [p.peak_to_peak, p.harmonic2, p.harmonic3] {
                    d.num(v)?;
                }
                d.text(&p.cycles.to_string())?;
                d.text(if p.settled { "true" } else { "false" })?;
                d.num(p.residual)?;
                d.end_row()?;
            }
            unsettled += usize::from(!p.settled);
        }
        if let Some(h) = history.as_mut() {
            for s in &sw.history {
                h.text(&level)?;
                h.num(sw.gamma)?;
                h.text(name(sw.direction))?;
                h.row(&[s.t, s.u, s.x, s.v])?;
            }
        }
    }
    out.commit()?;
    if let Some(d) = details {
        d.commit()?;
    }
    if let Some(h) = history {
        h.commit()?;
    }
    if unsettled > 0 {
        eprintln!(
            "nlsdof: warning: {unsettled} step(s) did not settle within --max-cycles {} (see settled=false in --details)",
            a.max_cycles
        );
    }
    let (integration_error, integration_warning) =
        report::integration_error(&sweeps, a.samples_per_cycle);
    if let Some(w) = &integration_warning {
        eprintln!("nlsdof: warning: {w}");
    }
    let out_name = a.out.display().to_string();
    let run = report::RigRun {
        sweeps: &sweeps,
        steps: n,
        wall_s: sim_s,
        out: &out_name,
    };
    if a.json {
        let total_s = t_start.elapsed().as_secs_f64();
        let integration = (integration_error, integration_warning);
        println!("{}", report::json(&run, integration, total_s));
    } else {
        print!("{}", report::text(&run));
    }
    Ok(())
}
