//! `nlsdof frf`: amplitude–frequency curves at several input levels, as a
//! stepped-sine sweep sees them (jumps, folds, phase quadrature), as text,
//! JSON or CSV, optionally plotted to SVG.

use super::roots::{
    check_frequency, check_gamma, conventions_help, load_steady_model, with_gain_note,
    FormulationArg,
};
use crate::error::CliError;
use nlsdof::{level_responses, SweepDirection};
use nlsdof_report::frf_plot as plot;
use nlsdof_report::steady_state as report;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Largest accepted `--steps` (keeps memory and output size sane).
const MAX_STEPS: usize = 10_000_000;

/// `--sweep` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepArg {
    /// Increasing frequency (default).
    Up,
    /// Decreasing frequency.
    Down,
}

impl SweepArg {
    pub fn to_core(self) -> SweepDirection {
        match self {
            SweepArg::Up => SweepDirection::Up,
            SweepArg::Down => SweepDirection::Down,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            SweepArg::Up => "up",
            SweepArg::Down => "down",
        }
    }
}

#[derive(clap::Args)]
#[command(
    about = "Amplitude-frequency curves at several input levels, as a stepped-sine sweep sees them",
    after_long_help = frf_long_help()
)]
pub struct Args {
    /// Model file (TOML, SI units; see MODEL FILE below).
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Input levels gamma, m/s^2 zero-to-peak, comma-separated (each finite and > 0).
    #[arg(
        long,
        value_name = "G1,G2,..",
        allow_hyphen_values = true,
        required_unless_present = "at"
    )]
    pub gamma: Option<String>,
    /// Lowest frequency, Hz (> 0).
    #[arg(
        long = "f-min",
        value_name = "F0",
        allow_hyphen_values = true,
        required_unless_present = "at"
    )]
    pub f_min: Option<f64>,
    /// Highest frequency, Hz (> f-min).
    #[arg(
        long = "f-max",
        value_name = "F1",
        allow_hyphen_values = true,
        required_unless_present = "at"
    )]
    pub f_max: Option<f64>,
    /// Number of frequencies, linearly spaced from f-min to f-max inclusive (>= 2).
    #[arg(long, value_name = "N", required_unless_present = "at")]
    pub steps: Option<usize>,
    /// Sweep direction of the stepped-sine test.
    #[arg(long, value_enum, default_value_t = SweepArg::Up)]
    pub sweep: SweepArg,
    /// Sweep at the levels, frequencies and sweep directions of a stepped-sine data file
    /// (long CSV level,gamma,f_hz,amplitude[,sweep], SI zero-to-peak, as `fit` reads it or
    /// `fit --predict` writes it), each sweep starting on the state nearest its measured first
    /// amplitude: the curves a fit compares with the data (see PREDICTING DATA below).
    #[arg(long, value_name = "DATA.csv", conflicts_with_all = ["gamma", "f_min", "f_max", "steps", "sweep", "harmonics", "formulation"])]
    pub at: Option<PathBuf>,
    /// Steady-state equation: exact harmonic balance or the paper's Eq 30.
    #[arg(long, value_enum, default_value_t = FormulationArg::Hb)]
    pub formulation: FormulationArg,
    /// Print JSON instead of the text summary.
    #[arg(long, conflicts_with = "csv")]
    pub json: bool,
    /// Print CSV (level,gamma,f_hz,amplitude,phase_deg,sweep,stable,sticking) instead of the text summary.
    #[arg(long)]
    pub csv: bool,
    /// Also write a plot of amplitude vs frequency to FILE (SVG or PNG, from the name).
    #[arg(long, value_name = "FILE.svg|FILE.png")]
    pub plot: Option<PathBuf>,
    /// Also write the curves as a universal file (ASCII dataset 58, double precision): one
    /// complex FRF per level, receptance H = (a/gamma) e^(-j phi) in m/(m/s^2) over the
    /// frequency in Hz, level in the z axis (m/s^2) and `gamma=G sweep=up|down level=K` in ID
    /// line 2 (what `fit` reads). Frequencies keep 7 significant digits (the format's E13.5).
    #[arg(long, value_name = "FILE.uff")]
    pub uff: Option<PathBuf>,
    /// Harmonics H of the balance: 1 = exact first order (default); 2..64 = multi-harmonic
    /// balance (constant and even terms included) with continuation and Hill stability.
    #[arg(long, value_name = "H", default_value_t = 1)]
    pub harmonics: usize,
}

fn frf_long_help() -> String {
    format!(
        "DESCRIPTION:
  Amplitude-frequency response curves at one or more input levels, computed as a
  stepped-sine test sees them: at each of N linearly spaced frequencies the structure
  settles on a stable steady state, following its branch from the previous step (the
  first step starts from rest). Where the followed branch ends at a fold the response
  jumps to another stable branch, so sweeping up and down gives different curves
  (hysteresis) for a hardening or softening model.

  For each level the verb reports the swept points, the jumps, all folds (saddle-node
  points) in the band, and the phase-quadrature point (phase lag 90 deg, where the
  curve crosses the backbone; the paper's Table 8 reports these).

{}

OUTPUT:
  text (default): a summary per level - peak amplitude and its frequency, jumps, folds,
        phase quadrature; amplitudes in m (zero-to-peak), frequencies in Hz
  --json: {{\"levels\":[{{\"gamma\":..,\"sweep\":\"up\",\"points\":[{{\"f_hz\":..,\"amplitude\":..,\"phase_deg\":..,
        \"stable\":..,\"sticking\":..}}],\"jumps\":[{{\"f_hz\":..,\"amplitude_before\":..,\"amplitude_after\":..}}],
        \"folds_hz\":[..],\"phase_quadrature\":{{\"f_hz\":..,\"amplitude\":..}} or null}}]}}
        points are in sweep order (decreasing frequency for --sweep down)
  --csv: header `level,gamma,f_hz,amplitude,phase_deg,sweep,stable,sticking`, then one row
        per swept point (level = 1-based index in the --gamma list), points in sweep order;
        a sticking point (Coulomb friction holds the mass) has amplitude 0 and an empty phase
  --plot FILE.svg|FILE.png: amplitude vs frequency, one colour per level; stable branches solid,
        unstable dashed, backbone dotted grey, swept points as markers, jumps as arrows.
        The plot is written atomically: on any error no file is created.
  --uff FILE.uff: universal file, ASCII dataset 58 (double precision), one complex FRF
        per level: receptance H = (a/gamma) e^(-j phi), m/(m/s^2) (ordinate displacement
        over denominator acceleration), frequencies increasing in Hz, gamma as the z-axis
        value (m/s^2) and `gamma=G sweep=up|down level=K` in ID line 2, so that
        `nlsdof fit FILE.uff` reads it back. Abscissa values keep 7 significant digits
        (E13.5 fields of the format). Written atomically; first-order curves only.

MODEL FILE [signal] TABLE:
  A model file written by `nlsdof fit --out` holds the fit's forcing gain as
  [signal] input_gain: the model sees input_gain * gamma, and the levels you give
  (and report) are the measured ones. A non-zero input_offset (a static force) or a
  negative input_gain is refused with one line naming the key.

PREDICTING DATA (--at DATA.csv):
  Instead of --gamma/--f-min/--f-max/--steps/--sweep, sweep at exactly the levels,
  frequencies and directions of a data file, each sweep starting on the stable state
  nearest its measured first amplitude (as `nlsdof fit` computes its model curves, Eq 31).
  With the model file of a fit, the amplitudes equal the fit's model curves bit for bit:
    nlsdof fit data.csv --out fitted.toml --predict fitted.csv
    nlsdof frf --model fitted.toml --at data.csv --csv
  Points are listed in sweep order per level, levels in the data's order.

EXAMPLES:
  nlsdof frf --model examples/har-wing.toml --gamma 0.41,0.62,0.81,1.00,1.23 \\
      --f-min 5.2 --f-max 5.6 --steps 200 --plot wing.svg
  nlsdof frf --model examples/duffing-strong.toml --gamma 0.5,1,2 --f-min 8 --f-max 16 \\
      --steps 400 --sweep down --csv > down.csv",
        conventions_help()
    )
}

/// Parses the comma-separated `--gamma` list.
fn parse_gammas(text: &str) -> Result<Vec<f64>, CliError> {
    let mut out = Vec::new();
    for item in text.split(',') {
        let item = item.trim();
        let v: f64 = item.parse().map_err(|_| {
            CliError::Usage(format!(
                "--gamma: '{item}' is not a number: give input levels (m/s^2, zero-to-peak) as a comma-separated list of finite numbers > 0, e.g. 0.5,1,2"
            ))
        })?;
        out.push(check_gamma(v)?);
    }
    Ok(out)
}

/// `steps` frequencies (Hz) from `f_min` to `f_max` inclusive.
fn linspace(f_min: f64, f_max: f64, steps: usize) -> Vec<f64> {
    let n = steps - 1;
    (0..steps)
        .map(|i| {
            if i == n {
                f_max
            } else {
                f_min + (f_max - f_min) * (i as f64 / n as f64)
            }
        })
        .collect()
}

pub fn run(args: Args) -> Result<(), CliError> {
    if args.at.is_some() {
        return run_at(&args);
    }
    // All checks first, all computation in memory; files are written last
    // and atomically, so an error never leaves a file behind.
    nlsdof_report::figure_file::check_plot_name(args.plot.as_deref())?;
    // clap requires these without --at
    let (Some(gamma_list), Some(f_min), Some(f_max), Some(steps)) =
        (&args.gamma, args.f_min, args.f_max, args.steps)
    else {
        return Err(CliError::Usage(
            "give --gamma, --f-min, --f-max and --steps, or --at DATA.csv".into(),
        ));
    };
    let gammas = parse_gammas(gamma_list)?;
    let f_min = check_frequency("--f-min", f_min)?;
    let f_max = check_frequency("--f-max", f_max)?;
    if f_min >= f_max {
        return Err(CliError::Usage(format!(
            "--f-min {f_min} must be below --f-max {f_max} (Hz)"
        )));
    }
    if steps < 2 || steps > MAX_STEPS {
        return Err(CliError::Usage(format!(
            "--steps {steps} is not allowed: need an integer from 2 to {MAX_STEPS}"
        )));
    }
    let (model, gain) = load_steady_model(&args.model)?;
    let formulation = args.formulation.to_core();
    let freqs = linspace(f_min, f_max, steps);
    let omegas: Vec<f64> = freqs.iter().map(|f| 2.0 * PI * f).collect();
    if omegas.windows(2).any(|w| w[1] <= w[0]) {
        return Err(CliError::Usage(format!(
            "--steps {steps} is too many for --f-min {f_min} .. --f-max {f_max} Hz: neighbouring frequencies coincide in floating point; use fewer steps or a wider range"
        )));
    }

    super::frf_mhb::check_harmonics(args.harmonics)?;
    if args.harmonics > 1 && args.uff.is_some() {
        return Err(CliError::Usage(format!(
            "--uff writes first-order curves; --harmonics {} is not supported with it",
            args.harmonics
        )));
    }
    if args.harmonics > 1 {
        if args.formulation != FormulationArg::Hb {
            return Err(CliError::Usage(format!(
                "--harmonics {} needs --formulation hb (Eq 30 is a first-order approximation)",
                args.harmonics
            )));
        }
        let request = super::frf_mhb::Request {
            model: &args.model,
            sweep: args.sweep.to_core(),
            steps,
            harmonics: args.harmonics,
            json: args.json,
            csv: args.csv,
            plot: args.plot.as_deref(),
            input_gain: gain,
        };
        return super::frf_mhb::run(&request, &model, &gammas, &omegas, f_min, f_max);
    }

    // the model sees input_gain * gamma; the reports give the levels as given
    let model_gammas: Vec<f64> = gammas.iter().map(|g| gain * g).collect();
    let mut levels = level_responses(
        &model,
        &model_gammas,
        &omegas,
        args.sweep.to_core(),
        formulation,
    )?;
    for (l, &g) in levels.iter_mut().zip(&gammas) {
        l.gamma = g;
    }
    let request = report::SweepRequest {
        model_name: &args.model.display().to_string(),
        direction: args.sweep.to_core(),
        formulation,
        steps,
        f_min,
        f_max,
        at: None,
    };
    let title = format!(
        "{} - {}, sweep {}",
        args.model
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        args.formulation.description(),
        args.sweep.name()
    );
    emit(&args, &request, &model, gain, &levels, title)
}

/// `--at DATA.csv`: the sweeps of the data's levels, frequencies and
/// directions ([`nlsdof::identification::sweeps_at_data`]).
fn run_at(args: &Args) -> Result<(), CliError> {
    nlsdof_report::figure_file::check_plot_name(args.plot.as_deref())?;
    let at = args.at.as_ref().expect("run_at needs --at");
    let (model, gain) = load_steady_model(&args.model)?;
    let data = nlsdof_io::stepped_sine_data::read_csv(at, &Default::default())
        .map_err(|e| CliError::Usage(e.to_string()))?;
    let levels = nlsdof::identification::sweeps_at_data(&model, gain, &data)?;
    let (mut f_min, mut f_max) = (f64::INFINITY, 0.0f64);
    for c in &data.curves {
        f_min = f_min.min(c.omegas[0] / (2.0 * PI));
        f_max = f_max.max(c.omegas[c.omegas.len() - 1] / (2.0 * PI));
    }
    let at_name = at.display().to_string();
    let request = report::SweepRequest {
        model_name: &args.model.display().to_string(),
        direction: data.curves[0].direction,
        formulation: nlsdof::Formulation::HarmonicBalance,
        steps: data
            .curves
            .iter()
            .map(|c| c.omegas.len())
            .max()
            .unwrap_or(0),
        f_min,
        f_max,
        at: Some(&at_name),
    };
    let title = format!(
        "{} at the data of {}",
        args.model
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        at.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
    );
    emit(args, &request, &model, gain, &levels, title)
}

/// Prints the sweeps (text, JSON or CSV) and writes the plot.
fn emit(
    args: &Args,
    request: &report::SweepRequest,
    model: &nlsdof::Model,
    gain: f64,
    levels: &[nlsdof::LevelResponse],
    title: String,
) -> Result<(), CliError> {
    let formulation = request.formulation;
    let (f_min, f_max) = (request.f_min, request.f_max);
    let mut stdout_text = if args.json {
        let mut v = report::sweep_json(request, model, levels);
        v["input_gain"] = serde_json::json!(gain);
        format!("{v}\n")
    } else if args.csv {
        report::sweep_csv(levels)
    } else {
        let text = nlsdof_report::compact_numbers(&report::sweep_text(request, model, levels));
        with_gain_note(text, gain)
    };

    let uff = match &args.uff {
        Some(_) => Some(uff_datasets(levels, formulation)?),
        None => None,
    };
    if let Some(path) = &args.plot {
        let input = plot::FrfPlot {
            title,
            model: model.normalised()?,
            formulation,
            direction: request.direction,
            f_min,
            f_max,
            levels,
        };
        let format = nlsdof_report::figure_file::plot_format(path);
        let bytes = plot::render_frf_as(&input, format)?;
        nlsdof_io::atomic::write_atomic(path, &bytes)?;
        if !args.json && !args.csv {
            let _ = writeln!(stdout_text, "\nplot written to {}", path.display());
        }
    }
    if let (Some(path), Some(datasets)) = (&args.uff, &uff) {
        nlsdof_io::uff58::write_ascii_file(path, datasets)?;
        if !args.json && !args.csv {
            let _ = writeln!(stdout_text, "universal file written to {}", path.display());
        }
    }
    print!("{stdout_text}");
    Ok(())
}

/// The swept curves as dataset-58 receptances `H = (a/gamma) e^(-j phi)`
/// (m/(m/s^2)), one per level, frequencies increasing; level K (from 1),
/// gamma and sweep direction in ID line 2 and gamma as the z-axis value.
fn uff_datasets(
    levels: &[nlsdof::LevelResponse],
    formulation: nlsdof::Formulation,
) -> Result<Vec<nlsdof_io::uff58::Uff58Dataset>, CliError> {
    use nlsdof_io::uff58::{Abscissa, AxisInfo, Uff58Dataset};
    let mut out = Vec::new();
    for (i, l) in levels.iter().enumerate() {
        let mut points: Vec<&nlsdof::SweepPoint> = l.sweep.points.iter().collect();
        if let Some(p) = points.iter().find(|p| p.unbounded) {
            return Err(CliError::Usage(format!(
                "--uff: the response at level {} (gamma {} m/s^2) is unbounded at {} Hz: a universal file holds finite values only",
                i + 1,
                l.gamma,
                p.omega / (2.0 * PI)
            )));
        }
        points.sort_by(|a, b| a.omega.total_cmp(&b.omega));
        let f: Vec<f64> = points.iter().map(|p| p.omega / (2.0 * PI)).collect();
        let h: Vec<(f64, f64)> = points
            .iter()
            .map(|p| {
                let r = p.amplitude / l.gamma;
                (r * p.phase.cos(), -r * p.phase.sin())
            })
            .collect();
        let sweep = match l.sweep.direction {
            SweepDirection::Up => "up",
            SweepDirection::Down => "down",
        };
        let mut d = Uff58Dataset::frf(Abscissa::Uneven(f), h);
        d.header.id1 = format!("nlsdof frf receptance level {}", i + 1);
        d.header.id2 = format!("gamma={} sweep={sweep} level={}", l.gamma, i + 1);
        d.header.id3 = format!("formulation {formulation:?}");
        d.header.ordinate_axis = AxisInfo {
            length_exponent: 1,
            ..AxisInfo::new(8, "Displacement", "m")
        };
        d.header.denominator_axis = AxisInfo {
            length_exponent: 1,
            ..AxisInfo::new(12, "Acceleration", "m/s^2")
        };
        d.header.z_axis = AxisInfo {
            length_exponent: 1,
            ..AxisInfo::new(12, "Level", "m/s^2")
        };
        d.header.z_axis_value = l.gamma;
        out.push(d);
    }
    Ok(out)
}
