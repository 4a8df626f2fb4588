//! `nlsdof linear-id`: linear system identification of a measured FRF by
//! fast relaxed vector fitting (paper Section 2.3, Table 3), with the
//! half-power and circle-fit estimates beside it, and the SDoF linear part
//! written as a model file.

use crate::error::CliError;
use nlsdof::vector_fitting::{
    identify_sdof, FrfWeighting, InputKind, MeasuredFrf, OutputKind, PoleCount, SdofIdError,
    SdofIdOptions, C64,
};
use nlsdof_report::linear_id as report;
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InputArg {
    /// Force, N (m, c, k identifiable).
    Force,
    /// Base acceleration, m/s^2 (only k/m and c/m unless --mass is given).
    Acceleration,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OutputArg {
    Displacement,
    Velocity,
    Acceleration,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WeightArg {
    /// All frequencies weigh the same.
    Uniform,
    /// Weight 1/|H| (relative error; stresses low-magnitude regions).
    Inverse,
}

#[derive(clap::Args)]
#[command(
    about = "Identify the linear part (m, c, k or k/m, c/m) from a measured FRF by fast relaxed vector fitting",
    after_long_help = LONG_HELP
)]
pub struct Args {
    /// FRF table (CSV: f_hz,re,im or f_hz,mag[,phase_deg]) or universal file (.uff/.unv,
    /// dataset 58, complex, abscissa in Hz); see FRF FILE below.
    #[arg(value_name = "FRF.csv|FRF.uff")]
    pub frf: PathBuf,
    /// Dataset of a universal file: INDEX among its dataset-58 functions (from 0) or TEXT
    /// contained in its ID line 1 (default: the file's only FRF, function type 4). Any
    /// complex function may be chosen; values are used in the file's units, frequencies in Hz.
    #[arg(long, value_name = "INDEX|TEXT")]
    pub dataset: Option<String>,
    /// Number of complex pole pairs, or `auto` (add pairs while the RMS error falls by > 10 %).
    #[arg(long, value_name = "N|auto", default_value = "auto")]
    pub poles: String,
    /// Largest number of pole pairs tried by --poles auto.
    #[arg(long = "max-poles", value_name = "N", default_value_t = 20)]
    pub max_poles: usize,
    /// Excitation quantity of the FRF.
    #[arg(long, value_enum, default_value_t = InputArg::Acceleration)]
    pub input: InputArg,
    /// Response quantity of the FRF (relative to the base for base excitation).
    #[arg(long, value_enum, default_value_t = OutputArg::Displacement)]
    pub output: OutputArg,
    /// Known mass, kg (> 0): gives m, k, c for acceleration input; overrides the residue mass for force input.
    #[arg(long, value_name = "KG", allow_hyphen_values = true)]
    pub mass: Option<f64>,
    /// Mode (1-based, by natural frequency) taken as the SDoF; default the one with the highest peak.
    #[arg(long, value_name = "K")]
    pub mode: Option<usize>,
    /// Use only frequencies >= F0 Hz.
    #[arg(long = "f-min", value_name = "F0", allow_hyphen_values = true)]
    pub f_min: Option<f64>,
    /// Use only frequencies <= F1 Hz.
    #[arg(long = "f-max", value_name = "F1", allow_hyphen_values = true)]
    pub f_max: Option<f64>,
    /// Fit without the constant term d.
    #[arg(long = "no-constant")]
    pub no_constant: bool,
    /// Also fit the proportional term s e.
    #[arg(long)]
    pub proportional: bool,
    /// Frequency weighting of the least-squares fit.
    #[arg(long, value_enum, default_value_t = WeightArg::Uniform)]
    pub weight: WeightArg,
    /// Iteration limit of the vector fitting (1 to 10000).
    #[arg(long = "max-iterations", value_name = "N", default_value_t = 30)]
    pub max_iterations: usize,
    /// Write the SDoF linear part as a model file (TOML) to FILE.
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Print JSON instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// Write a figure (SVG or PNG, from the file name): measured vs fitted magnitude and phase,
    /// and the Nyquist plot with the fitted circle.
    #[arg(long, value_name = "FIG.svg|FIG.png")]
    pub plot: Option<PathBuf>,
}

const LONG_HELP: &str = "DESCRIPTION:
  Fits H(s) = sum_n r_n/(s - a_n) + d [+ s e], s = j 2 pi f, to a measured complex FRF by
  fast relaxed vector fitting (Gustavsen & Semlyen 1999; relaxed: Gustavsen 2006; fast QR
  form: Deschrijver et al. 2008): complex starting poles spread over the band, relocated by
  linear least squares (QR) as the zeros of the weighting function sigma, unstable poles
  flipped, frequencies normalised by the highest one. It stops when the poles change by
  less than 1e-11 (relative), the RMS error stops changing (noise floor) or reaches
  round-off, or after --max-iterations; the text output lists the RMS error per iteration.

  Each complex pole pair a = -zeta w_n + j w_n sqrt(1 - zeta^2) gives the natural frequency
  f_n = |a|/(2 pi), the damping ratio zeta = -Re a/|a| and the residue r. The SDoF linear
  part of the model  m x'' + c x' + k x = m gamma  comes from the chosen mode:
    alpha = k/m = w_n^2,  delta = c/m = 2 zeta w_n          (poles only)
    --input force:         m = 1/|G|, G = 2 j w_d r_x (modal mass at the measurement point)
    --input acceleration:  m is NOT identifiable; only alpha and delta, unless --mass M
  where r_x = r / a^p is the displacement residue (p = 0, 1, 2 for --output displacement,
  velocity, acceleration). The half-power bandwidth and a circle (Nyquist) fit of the
  mobility are printed beside the vector-fitting result for comparison; an amplitude-only
  FRF (no phase) gets the half-power estimate only.

FRF FILE:
  CSV with a header: f_hz and either re,im or mag[,phase_deg] (coherence optional),
  frequencies in Hz strictly increasing; `nlsdof frf-estimate` writes this format.
  Universal file (.uff/.unv, dataset 58 or 58b): the file's only frequency response
  function (function type 4), or the dataset chosen with --dataset INDEX|TEXT (index from
  0, or text of ID line 1; any complex function). The abscissa must be a frequency in Hz
  (units label Hz, or specific data type 18); real functions are refused. State the
  FRF's quantities with --input/--output: the values are used as stored.

MODEL FILE (--out):
  mass, stiffness, damping of the chosen mode (no nonlinear terms). With acceleration input
  and no --mass the file holds mass = 1 kg, stiffness = alpha, damping = delta, and says so
  in a comment: every response to a base acceleration depends only on k/m and c/m.

EXAMPLES:
  nlsdof linear-id sweep.csv --input acceleration --out linear.toml
  nlsdof linear-id impact.csv --input force --output velocity --f-min 100 --f-max 200 \\
      --poles 1 --json --plot impact.svg

Errors are one line on stderr, exit code 2; no output file is left behind.";

fn usage(msg: String) -> CliError {
    CliError::Usage(msg)
}

pub fn run(args: Args) -> Result<(), CliError> {
    nlsdof_report::figure_file::check_plot_name(args.plot.as_deref())?;
    if args.max_iterations == 0 || args.max_iterations > 10_000 {
        return Err(usage(format!(
            "--max-iterations {}: need 1 to 10000 vector-fitting iterations",
            args.max_iterations
        )));
    }
    let table = nlsdof_io::frf_file::read_frf(&args.frf, args.dataset.as_deref())?;
    let f_lo = args.f_min.unwrap_or(f64::NEG_INFINITY);
    let f_hi = args.f_max.unwrap_or(f64::INFINITY);
    if f_lo.is_nan() || f_hi.is_nan() || f_lo >= f_hi {
        return Err(usage(format!(
            "--f-min {f_lo} / --f-max {f_hi}: need f-min < f-max"
        )));
    }
    if let Some(m) = args.mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(usage(format!("--mass {m}: must be finite and > 0 kg")));
        }
    }
    let in_band = |f: f64| f >= f_lo && f <= f_hi;
    // --poles matters (and is checked) only where vector fitting runs.
    let poles = match parse_poles(&args.poles, args.max_poles) {
        Ok(p) => p,
        Err(e) if table.values.is_some() && table.f_hz.iter().any(|&f| in_band(f)) => {
            return Err(e)
        }
        Err(_) => PoleCount::Fixed(1),
    };
    let output = match args.output {
        OutputArg::Displacement => OutputKind::Displacement,
        OutputArg::Velocity => OutputKind::Velocity,
        OutputArg::Acceleration => OutputKind::Acceleration,
    };
    let input = match args.input {
        InputArg::Force => InputKind::Force,
        InputArg::Acceleration => InputKind::Acceleration,
    };
    let frf = MeasuredFrf {
        omega: table.f_hz.iter().map(|f| 2.0 * PI * f).collect(),
        magnitude: table.magnitude.clone(),
        values: table
            .values
            .as_ref()
            .map(|v| v.iter().map(|&(re, im)| C64::new(re, im)).collect()),
    };
    let opts = SdofIdOptions {
        band: (2.0 * PI * f_lo, 2.0 * PI * f_hi),
        poles,
        input,
        output,
        mass: args.mass,
        mode: args.mode,
        constant: !args.no_constant,
        proportional: args.proportional,
        weighting: match args.weight {
            WeightArg::Uniform => FrfWeighting::Uniform,
            WeightArg::Inverse => FrfWeighting::Inverse,
        },
        max_iterations: args.max_iterations,
        // Ctrl-C ends the process (main's handler): nothing to poll here
        cancel: nlsdof::cancel::Cancel::NEVER,
    };
    let id = identify_sdof(&frf, &opts).map_err(|e| match e {
        SdofIdError::EmptyBand { .. } => usage(format!("no FRF point in [{f_lo}, {f_hi}] Hz")),
        SdofIdError::HalfPowerFailed(e) => usage(format!(
            "{}: amplitude-only FRF and the half-power method failed: {e}",
            args.frf.display()
        )),
        SdofIdError::Fit(e) => e.into(),
        SdofIdError::Limit(e) => usage(format!("{}: {e}", args.frf.display())),
    })?;
    let f_hz: Vec<f64> = id.points.iter().map(|&i| table.f_hz[i]).collect();
    // Build everything before writing anything.
    let name = args.frf.display().to_string();
    let model_text = match &args.out {
        Some(_) => Some(report::model_file_text(&id, &name)?),
        None => None,
    };
    let svg = match &args.plot {
        Some(p) => Some(report::figure_as(
            &id,
            &f_hz,
            input,
            output,
            nlsdof_report::figure_file::plot_format(p),
        )?),
        None => None,
    };
    let text = if args.json {
        format!("{}\n", report::json(&id, &f_hz))
    } else {
        let mut s = report::text(&id, &f_hz, &name);
        if let Some(p) = &args.out {
            s += &format!("model written to {}\n", p.display());
        }
        if let Some(p) = &args.plot {
            s += &format!("plot written to {}\n", p.display());
        }
        s
    };
    if let (Some(path), Some(s)) = (&args.out, &model_text) {
        nlsdof_io::atomic::write_atomic(path, s.as_bytes())?;
    }
    if let (Some(path), Some(s)) = (&args.plot, &svg) {
        // Committed together with --out at the end of the run (all or nothing).
        nlsdof_io::atomic::write_atomic(path, s)?;
    }
    print!("{text}");
    Ok(())
}

/// `--poles N|auto`.
fn parse_poles(s: &str, max_pairs: usize) -> Result<PoleCount, CliError> {
    if s.eq_ignore_ascii_case("auto") {
        if max_pairs == 0 {
            return Err(usage(
                "--max-poles 0 is not allowed: --poles auto needs at least 1 pole pair".into(),
            ));
        }
        return Ok(PoleCount::Auto { max_pairs });
    }
    let n: usize = s.parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
        usage(format!(
            "--poles {s:?}: expected a number of pole pairs >= 1 or `auto`"
        ))
    })?;
    Ok(PoleCount::Fixed(n))
}
