//! `nlsdof fit-time`: output-error fit of Eq 32 to a recorded input and
//! output (library: `nlsdof::identification::time_domain`), validation on
//! test ranges, model file with the signal map, prediction CSV.

use crate::error::CliError;
use nlsdof::identification::time_domain::{
    check_ranges, fit_time_domain, predict_with, uniform_fs, InputInterpolation, Prediction,
    SampleRange, TimeFitOptions, TimeRecord, MAX_SUBSTEPS,
};
use nlsdof::identification::ModelKind;
use nlsdof_io::input::read_columns;
use nlsdof_io::model_file::{model_to_toml, signal_to_toml, SignalMap};
use nlsdof_io::signal_file::CsvWriter;
use nlsdof_report::time_fit as report;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    about = "Fit the power-law ODE (Eq 32) to a recorded input and output in the time domain (output error, exact RK4 gradients)",
    after_long_help = FIT_TIME_HELP
)]
pub struct Args {
    /// Table with the input and output columns (CSV; a header is optional, quoted names and a trailing comma are fine).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Input column: header name or 0-based index.
    #[arg(long, value_name = "C")]
    pub input_column: String,
    /// Output column: header name or 0-based index.
    #[arg(long, value_name = "C")]
    pub output_column: String,
    /// Sampling frequency, Hz (default: from the file's time column X_Value, t or time).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Time column (s); must be uniformly sampled. Instead of --fs (default: X_Value, t or time when present).
    #[arg(long, value_name = "C")]
    pub time_column: Option<String>,
    /// Estimation range A:B, 0-based half-open sample indices (default: the whole record,
    /// as Python's fit_time(fit_range=None)).
    #[arg(long, value_name = "A:B")]
    pub range: Option<String>,
    /// Model: linear, duffing (default, as Python's fit_time), generalised, quadratic,
    /// duffing-quadratic, duffing-generalised, generalised-damping, generalised-stiffness.
    #[arg(long, value_name = "KIND", default_value = "duffing")]
    pub model: String,
    /// Test range A:B (0-based half-open; may be repeated): predicted from its input and its first 50 output samples.
    #[arg(long, value_name = "A:B")]
    pub test: Vec<String>,
    /// Prediction CSV t,u,y_measured,y_model over the (single) --test range.
    #[arg(long, value_name = "PRED.csv")]
    pub predict: Option<PathBuf>,
    /// Fitted model file (TOML, per unit mass, with the [signal] gain and offsets).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Starts of the free-exponent stage (1 = from rho = 2, eta = 1; more add seeded random exponents).
    #[arg(long, default_value_t = 1)]
    pub starts: usize,
    /// Levenberg-Marquardt iteration limit of each stage.
    #[arg(long, value_name = "N", default_value_t = 400)]
    pub max_iterations: usize,
    /// Seed of the extra starts.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The input between samples, part of the model (written to the model file): cubic
    /// (through the 4 nearest samples), linear, or zoh (zero-order hold).
    #[arg(long, value_name = "cubic|linear|zoh", default_value = "cubic")]
    pub input_interpolation: String,
    /// RK4 substeps per sample (h = 1/(N fs)); default: chosen so that the integration
    /// error is at most --integration-tolerance of the RMS output error.
    #[arg(long, value_name = "N")]
    pub substeps: Option<usize>,
    /// Target of the automatic substeps: integration error / RMS output error.
    #[arg(
        long,
        value_name = "R",
        default_value_t = 0.01,
        allow_hyphen_values = true
    )]
    pub integration_tolerance: f64,
    /// Hold model parameters at values instead of fitting them: name=value,.. (alpha, delta,
    /// beta, rho, kappa, eta, gain, input_offset, output_offset; per unit mass, SI units),
    /// e.g. --fix delta=0 for pure power-law damping.
    #[arg(long, value_name = "NAME=VALUE,..", allow_hyphen_values = true)]
    pub fix: Option<String>,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

const FIT_TIME_HELP: &str = "MODEL (paper Eq 32, mass-normalised, recorded signals u, y):
  x'' + delta x' + alpha x + kappa x'|x'|^eta + beta x|x|^rho = gain (u + input_offset)
  y = x + output_offset
  Exponents are restricted to rho >= 0 and eta >= 0 (the sensitivity equations are
  singular at x = 0 / v = 0 otherwise). With --model linear the input offset is fixed at 0
  (only the sum of the two offsets is identifiable).

METHOD:
  The input between samples is reconstructed as --input-interpolation says (cubic
  through the 4 nearest samples by default; linear; zoh = zero-order hold): part of the
  model, written to the model file. RK4 with N substeps per sample (h = 1/(N fs)), exact
  discrete gradients by forward sensitivities, bounded Levenberg-Marquardt from an
  equation-error estimate; free exponents in a second stage (--starts, --seed). The
  initial state is fitted too.
  N is chosen so that the fit identifies the ODE, not the integrator: fitted at N = 2,
  the integration error (RMS change of the fitted output when N is doubled) is compared
  with the RMS output error; while above --integration-tolerance (1 %) of it, N is raised
  (RK4 is 4th order) and the fit rerun. --substeps N fixes N (a warning if the target
  is missed). The choice is reported (JSON: integration) and written to the model file.

TEST:
  Each --test range is simulated from its input; only its first 50 output samples are
  used, to fit the initial state. The score is the RMS error over the rest of the range
  (printed x1000: mV when the output is in volts).

OUTPUT:
  --out MODEL.toml: mass = 1 (per unit mass) and a [signal] table with input_gain,
  input_offset, output_offset, input_interpolation and substeps (simulate uses both);
  [provenance] has the step (integration_step) and the integration_error. `nlsdof simulate --model MODEL.toml --input PRED.csv
  --x0 X --v0 V --out sim.csv` reproduces y_model (column y) with the initial state that
  fit-time prints for the test range.
  --predict PRED.csv: t,u,y_measured,y_model over the --test range (one --test only).

EXAMPLE (Silverbox, ../shared/data/silverbox):
  nlsdof fit-time --input SNLS80mV.csv --input-column V1 --output-column V2 \\
      --fs 610.3515625 --range 40650:105712 --model duffing --test 100:40575 \\
      --predict arrow.csv --out silverbox.toml";

fn parse_range(flag: &str, s: &str) -> Result<SampleRange, CliError> {
    let bad = || {
        CliError::Usage(format!(
            "{flag} {s:?} is not a range A:B of 0-based sample indices (half-open, A < B)"
        ))
    };
    let (a, b) = s.split_once(':').ok_or_else(bad)?;
    let a: usize = a.trim().parse().map_err(|_| bad())?;
    let b: usize = b.trim().parse().map_err(|_| bad())?;
    Ok(SampleRange::new(a, b))
}

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    let kind = ModelKind::parse(&a.model).ok_or_else(|| {
        CliError::Usage(format!(
            "--model {:?} is not a model (linear, duffing, generalised, quadratic, duffing-quadratic, duffing-generalised, generalised-damping, generalised-stiffness)",
            a.model
        ))
    })?;
    if kind == ModelKind::Coulomb {
        return Err(CliError::Usage(
            "--model coulomb is not supported by fit-time (eta = -1 < 0: the sensitivity equations are singular at v = 0)".into(),
        ));
    }
    if a.max_iterations == 0 {
        return Err(CliError::Usage(
            "--max-iterations 0: give at least 1".into(),
        ));
    }
    if a.starts == 0 {
        return Err(CliError::Usage("--starts 0: give at least 1".into()));
    }
    let interpolation = InputInterpolation::parse(&a.input_interpolation).ok_or_else(|| {
        CliError::Usage(format!(
            "--input-interpolation {:?} is not an interpolation (cubic, linear, zoh)",
            a.input_interpolation
        ))
    })?;
    if let Some(n) = a.substeps {
        if !(1..=MAX_SUBSTEPS).contains(&n) {
            return Err(CliError::Usage(format!(
                "--substeps {n}: give 1 to {MAX_SUBSTEPS} RK4 steps per sample"
            )));
        }
    }
    if !(a.integration_tolerance.is_finite() && a.integration_tolerance > 0.0) {
        return Err(CliError::Usage(format!(
            "--integration-tolerance {}: give a finite ratio > 0 (e.g. 0.01)",
            a.integration_tolerance
        )));
    }
    let range_arg = a
        .range
        .as_deref()
        .map(|r| parse_range("--range", r))
        .transpose()?;
    let tests: Vec<SampleRange> = a
        .test
        .iter()
        .map(|s| parse_range("--test", s))
        .collect::<Result<_, _>>()?;
    if a.predict.is_some() && tests.len() != 1 {
        return Err(CliError::Usage(format!(
            "--predict needs exactly one --test range ({} given)",
            tests.len()
        )));
    }
    let mut targets: Vec<(&str, &std::path::Path)> = Vec::new();
    if let Some(p) = &a.out {
        targets.push(("--out", p));
    }
    if let Some(p) = &a.predict {
        targets.push(("--predict", p));
    }
    nlsdof_io::atomic::check_targets(&targets)?;
    if let Some(fs) = a.fs {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(CliError::Usage(format!(
                "--fs {fs} must be a finite sampling frequency > 0 Hz"
            )));
        }
    }
    let mut cols = vec![a.input_column.as_str(), a.output_column.as_str()];
    match (&a.fs, &a.time_column) {
        (Some(_), Some(_)) => {
            return Err(CliError::Usage(
                "give either --fs or --time-column, not both".into(),
            ))
        }
        (None, Some(t)) => cols.push(t.as_str()),
        _ => {}
    }
    // every format through the one reader; without --fs or --time-column
    // the file's own time column (LVM X_Value, CSV t or time)
    let auto_time = a.fs.is_none() && a.time_column.is_none();
    let table = read_columns(&a.input, &cols, auto_time)?;
    if auto_time && table.columns.len() < 3 {
        return Err(CliError::Usage(format!(
            "{}: the sampling frequency is needed and the file has no time column ({}): give --fs HZ or --time-column C",
            a.input.display(),
            nlsdof_io::input::TIME_COLUMNS.join(", ")
        )));
    }
    let (u, y) = (&table.columns[0], &table.columns[1]);
    let (fs, t0) = match a.fs {
        Some(fs) => (fs, 0.0),
        None => {
            let t = &table.columns[2];
            let fs = uniform_fs(t, 1e-3).map_err(|e| {
                CliError::Usage(format!(
                    "{}: column {:?}: {e}",
                    a.input.display(),
                    table.names[2]
                ))
            })?;
            (fs, t[0])
        }
    };
    let rec = TimeRecord::new(u, y, fs)?;
    let range = range_arg.unwrap_or(SampleRange::new(0, u.len()));
    if tests.is_empty() {
        check_ranges(u.len(), range, None)?;
    }
    for t in &tests {
        check_ranges(u.len(), range, Some(*t))?;
    }
    let mut opts = TimeFitOptions {
        starts: a.starts,
        seed: a.seed,
        interpolation,
        substeps: a.substeps,
        integration_tolerance: a.integration_tolerance,
        fixed: parse_fixed(a.fix.as_deref())?,
        ..TimeFitOptions::default()
    };
    opts.lm.max_iterations = a.max_iterations;
    opts.lm.max_evaluations = 3 * a.max_iterations;
    let t_fit = Instant::now();
    let res = crate::cmd::simulate::with_spinner("fitting", || {
        fit_time_domain(&rec, range, kind, &opts)
    })?;
    let fit_s = t_fit.elapsed().as_secs_f64();
    let tm = res.model();
    let preds: Vec<Prediction> = tests
        .iter()
        .map(|t| predict_with(&rec, *t, &tm, &res.discretisation))
        .collect::<Result<_, _>>()?;
    let signal = SignalMap {
        input_gain: tm.gain,
        input_offset: tm.input_offset,
        output_offset: tm.output_offset,
        input_interpolation: Some(res.discretisation.interpolation),
        substeps: Some(res.discretisation.substeps),
    };
    if let Some(p) = &a.out {
        let model = tm.model.to_physical(1.0)?;
        let provenance = nlsdof_io::model_file::Provenance {
            tool: Some("nlsdof fit-time".into()),
            version: Some(env!("CARGO_PKG_VERSION").into()),
            data: Some(a.input.display().to_string()),
            model: Some(kind.to_string()),
            objective: Some("RMS output error over the range, in the output's unit".into()),
            cost: Some(res.rms),
            converged: Some(res.termination.converged()),
            range: Some(format!("{}:{}", range.start, range.end)),
            integration_step: Some(res.integration.step),
            integration_error: Some(res.integration.integration_error),
        };
        let text = format!(
            "# fitted by `nlsdof fit-time`, model {kind}, range {}:{} of {}, RMS output error {:e}\n# m = 1 kg: all values are per unit mass; the [signal] table maps the recorded u, y\n{}{}{}",
            range.start,
            range.end,
            a.input.display(),
            res.rms,
            model_to_toml(&model),
            signal_to_toml(&signal),
            nlsdof_io::model_file::provenance_to_toml(&provenance)
        );
        nlsdof_io::atomic::write_atomic(p, text.as_bytes())?;
    }
    if let (Some(p), Some(pr)) = (&a.predict, preds.first()) {
        let mut w = CsvWriter::create(p, &["t", "u", "y_measured", "y_model"])?;
        for (k, ym) in pr.y_model.iter().enumerate() {
            let i = pr.range.start + k;
            w.row(&[t0 + i as f64 / fs, u[i], y[i], *ym])?;
        }
        w.commit()?;
    }
    let input = a.input.display().to_string();
    let run = report::TimeFitRun {
        input: &input,
        kind,
        fs,
        samples: u.len(),
        range,
        fit: &res,
        predictions: &preds,
        fit_s,
    };
    if a.json {
        let total_s = t_start.elapsed().as_secs_f64();
        println!("{}", report::json(&run, total_s));
    } else {
        print!("{}", report::text(&run));
    }
    Ok(())
}

/// `--fix name=value,..` as [`TimeFitOptions::fixed`] entries.
fn parse_fixed(list: Option<&str>) -> Result<Vec<(usize, f64)>, CliError> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for (name, v) in crate::cmd::fit::fix_items(list.unwrap_or(""))? {
        let p = nlsdof::identification::time_domain::fixable_parameter(&name).ok_or_else(|| {
            CliError::Usage(format!(
                "--fix {name}: not a parameter of fit-time (alpha, delta, beta, rho, kappa, eta, gain, input_offset, output_offset)"
            ))
        })?;
        if out.iter().any(|&(q, _)| q == p) {
            return Err(CliError::Usage(format!("--fix {name} is given twice")));
        }
        out.push((p, v));
    }
    Ok(out)
}
