//! `nlsdof simulate`: time-domain response of the model (Eq 32) to a
//! recorded input acceleration, streamed to CSV `t,accel,x,v`.

use crate::error::CliError;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nlsdof::identification::time_domain::{simulate_states, Discretisation, TimeModel};
use nlsdof::simulation::{
    simulate, simulate_record, Method, Options, RecordMethod, Sample, State, Summary,
};
use nlsdof::Model;
use nlsdof::NormalisedModel;
use nlsdof_io::signal_file::{read_signal, CsvWriter, SignalGrid};
use nlsdof_report::simulation as report;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Default RK4 on uniform sampling: the input upsampled this many times by
/// cubics and integrated with two fine samples per step, h = 2/(4 fs) =
/// 1/(2 fs).
const CUBIC_FACTOR: usize = nlsdof::simulation::DEFAULT_UPSAMPLING;

/// `--method` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Classical fixed-step RK4 driven by the samples (fast, streaming).
    Rk4,
    /// Adaptive Dormand-Prince 5(4), restarted at every sample (accuracy reference).
    Dopri,
}

#[derive(clap::Args)]
#[command(
    about = "Simulate the model's response to a recorded input acceleration (CSV or MAT), writing t,accel,x,v",
    after_long_help = SIMULATE_HELP
)]
pub struct Args {
    /// Model file (TOML, SI units).
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Input acceleration: CSV `t,accel` or one column (with --fs), or a MATLAB .mat file.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Sampling frequency of a one-column input, Hz (> 0).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Variable name in a .mat input (default: the only array, or `accel`), or the
    /// dataset of a .uff/.unv universal file (dataset 58/58b: its index from 0, or
    /// text of its ID line 1; default: the file's only time response).
    #[arg(long, value_name = "NAME")]
    pub var: Option<String>,
    /// Integrator.
    #[arg(long, value_enum, default_value_t = MethodArg::Rk4)]
    pub method: MethodArg,
    /// RK4 samples per step: 1 (piecewise-linear input; default for a non-uniform time column) or 2 (h = 2/fs, stage inputs at the samples). Default for uniform sampling: h = 1/(2 fs) with the input between samples interpolated by cubics through the samples.
    #[arg(long, value_name = "1|2")]
    pub samples_per_step: Option<usize>,
    /// Relative tolerance of --method dopri.
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    pub rtol: f64,
    /// Absolute tolerance of --method dopri (m; velocity uses atol * omega_n).
    #[arg(long, default_value_t = 1e-13, allow_hyphen_values = true)]
    pub atol: f64,
    /// The input is a base acceleration: simulate the relative coordinate with u = -input.
    #[arg(long)]
    pub base: bool,
    /// Initial displacement, m.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub x0: f64,
    /// Initial velocity, m/s.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub v0: f64,
    /// Write every N-th sample only.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub decimate: usize,
    /// Output CSV (t,accel,x,v), or a universal file when FILE ends in .uff/.unv (time
    /// responses accel m/s^2, x m, v m/s over time in s; see OUTPUT); written atomically,
    /// nothing on error or Ctrl-C.
    #[arg(long, value_name = "FILE.csv|FILE.uff")]
    pub out: PathBuf,
    /// Print the run summary as JSON.
    #[arg(long)]
    pub json: bool,
}

const SIMULATE_HELP: &str = "MODEL (paper Eq 32, mass-normalised):
  x'' = u(t) - (c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho) / m
  u = the input acceleration gamma(t) of Eq 29 (m gamma is the applied force). For a
  base-excited structure in relative coordinates u = -(base acceleration): use --base.

INPUT:
  CSV with two columns t,accel (s, m/s^2; header optional; t strictly increasing), or
  one column accel plus --fs HZ; or a MAT v5 file with an n x 2 [t accel] matrix or a
  vector plus fs (--fs, a scalar variable `fs`, or a vector `t` of the same length).
  NaN/Inf samples, non-increasing time, fs <= 0, an empty file or wrong columns are
  errors (one line on stderr, exit 2, no output file).

METHODS:
  rk4   classical RK4. Default for uniform sampling: h = 1/(2 fs), input between samples from
        cubics through the 4 nearest samples (4th order; within 1e-3 of the response at
        20 or more samples per cycle of the highest frequency present, for moderate
        damping). --samples-per-step 2: h = 2/fs, stage inputs exactly at the
        samples (4th order for any smooth input through the samples); mid-step outputs
        by cubic Hermite interpolation. --samples-per-step 1: h = 1/fs, input linear
        between samples. Coulomb friction (eta = -1) always uses 1, with stick-slip
        event location.
  dopri adaptive Dormand-Prince 5(4), input linear between samples, restarted at every
        sample (accuracy reference; about 1.5x the RHS evaluations of rk4 x1).

INTEGRATION ERROR:
  Every run on uniform sampling is checked by step doubling on the whole record: the
  default method is run again at h = 1/(4 fs) on the same cubic input, and the largest
  difference over max |x| is scaled by 2^p/(2^p - 1), p the order RK4 keeps on the law
  (4 for a smooth law; 2 + e for an exponent e that is not an even integer, so that
  laws not smooth at zero velocity or displacement, e in (-1, 2), and Coulomb friction
  are not underestimated). Another method adds its distance to that finer run (which
  includes reading the input as linear). The estimate of the error against the exact
  response to the cubic reading, relative to max |x|, is in the summary (JSON:
  integration_error); above 1e-3 a warning on stderr says what to do (the text Python's
  Model.simulate warns with). It costs about twice the run (three times for --method
  dopri or --samples-per-step).

SIGNAL MAP:
  A model file with a [signal] table (written by `nlsdof fit-time`) drives the model with
  gamma = input_gain * (input + input_offset) and adds a column y = x + output_offset.
  When the table states input_interpolation (cubic | linear | zoh) and/or substeps, the
  default RK4 integrates with that input reconstruction and h = 1/(substeps fs), as
  fit-time did (the error check then doubles the substeps); files without them: cubic, 2.

OUTPUT:
  --out FILE.csv: header t,accel,x,v (s, m/s^2 input as used, m, m/s), one row per
  (decimated) sample; t,accel,x,v,y with a [signal] table.
  --out FILE.uff (or .unv): a universal file instead (ASCII dataset 58, double precision,
  written atomically at the end): time responses (function type 1) with ID line 1 `accel`
  (m/s^2), `x` (m), `v` (m/s) [and `y` (m)], in that order (dataset indices 0..3); time in s,
  evenly spaced from t0 by decimate/fs (start and step keep 7 significant digits, the
  format's E13.5), or the sample times for non-uniform input. A one-line summary (or --json) goes to stdout.

EXAMPLE:
  nlsdof signal chirp --amplitude 0.25 --f0 4.5 --f1 6 --duration 300 --fs 2048 --out chirp.csv
  nlsdof simulate --model examples/har-wing.toml --input chirp.csv --out response.csv";

/// [`super::roots::load_document`]: the model and its optional `[signal]`
/// table (gain and offsets of `fit-time` models, gain of `fit` models).
/// The output rows `t,accel,x,v,y` as dataset-58 time responses (function
/// type 1): accel (m/s^2, input as used), x (m), v (m/s) and, with a
/// [signal] table, y (m); evenly spaced from the input's t0 every
/// decimate/fs s on uniform sampling, else at the sample times.
fn uff_datasets(
    rows: &[[f64; 5]],
    with_y: bool,
    grid: &SignalGrid,
    decimate: usize,
) -> Vec<nlsdof_io::uff58::Uff58Dataset> {
    use nlsdof_io::uff58::{Abscissa, AxisInfo, Uff58Dataset};
    let columns: &[(usize, &str, i32, &str, &str, &str)] = &[
        (
            1,
            "accel",
            12,
            "Acceleration",
            "m/s^2",
            "input acceleration as used",
        ),
        (2, "x", 8, "Displacement", "m", "displacement"),
        (3, "v", 11, "Velocity", "m/s", "velocity"),
        (
            4,
            "y",
            8,
            "Displacement",
            "m",
            "output y = x + output_offset",
        ),
    ];
    let (start, step) = match grid {
        SignalGrid::Uniform { t0, fs } => (*t0, decimate as f64 / fs),
        SignalGrid::Times(_) => (0.0, 0.0),
    };
    columns
        .iter()
        .filter(|c| with_y || c.0 != 4)
        .map(|&(col, name, kind, label, units, what)| {
            let mut d =
                Uff58Dataset::time_response(start, step, rows.iter().map(|r| r[col]).collect());
            if let SignalGrid::Times(_) = grid {
                d.abscissa = Abscissa::Uneven(rows.iter().map(|r| r[0]).collect());
            }
            d.header.id1 = name.to_string();
            d.header.id2 = format!("nlsdof simulate: {what} ({units})");
            d.header.function_id = col as i64;
            d.header.ordinate_axis = AxisInfo {
                length_exponent: 1,
                ..AxisInfo::new(kind, label, units)
            };
            d
        })
        .collect()
}

/// RK4 with the input reconstruction and substeps a model file states
/// (`time_domain::simulate_states`, the integrator of `fit-time`); `raw` is
/// the input before `gain`, `sink` gets `(k, gain · raw[k], x, v)`.
fn simulate_stated(
    nm: &NormalisedModel,
    raw: &[f64],
    gain: f64,
    (t0, fs): (f64, f64),
    d: &Discretisation,
    initial: State,
    sink: &mut dyn FnMut(usize, f64, f64, f64),
) -> Result<Summary, CliError> {
    let tm = TimeModel {
        model: *nm,
        gain,
        input_offset: 0.0,
        output_offset: 0.0,
    };
    let (xs, vs) = simulate_states(&tm, raw, fs, initial, d)?;
    for (k, (x, v)) in xs.iter().zip(&vs).enumerate() {
        sink(k, gain * raw[k], *x, *v);
    }
    let n = xs.len();
    let steps = (n.saturating_sub(1) * d.substeps) as u64;
    Ok(Summary {
        samples: n,
        outputs: n,
        steps,
        rhs_evaluations: 4 * steps,
        samples_per_step: 1,
        final_state: State {
            x: xs.last().copied().unwrap_or(initial.x),
            v: vs.last().copied().unwrap_or(initial.v),
        },
        final_time: t0 + n.saturating_sub(1) as f64 / fs,
        ..Summary::default()
    })
}

pub(crate) fn load_model_with_signal(
    path: &Path,
) -> Result<(Model, Option<nlsdof_io::model_file::SignalMap>), CliError> {
    let d = super::roots::load_document(path)?;
    Ok((d.model, d.signal))
}

/// A progress bar that appears only once an operation has run for more
/// than a second (and only on a terminal).
pub(crate) struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: AtomicBool,
}

impl Progress {
    pub(crate) fn new(total: u64, what: &str) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% ({eta} left)")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(what.to_string());
        Self {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
        }
    }

    #[inline]
    pub(crate) fn set(&self, pos: u64) {
        self.bar.set_position(pos);
        self.reveal();
    }

    #[inline]
    pub(crate) fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.reveal();
    }

    fn reveal(&self) {
        if !self.shown.load(Ordering::Relaxed) && self.start.elapsed() > Duration::from_secs(1) {
            self.shown.store(true, Ordering::Relaxed);
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A spinner shown on stderr only if `f` takes more than a second.
pub(crate) fn with_spinner<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    bar.set_message(what.to_string());
    let done = std::sync::Arc::new(AtomicBool::new(false));
    let (b2, d2) = (bar.clone(), done.clone());
    let timer = std::thread::spawn(move || {
        let t = Instant::now();
        while t.elapsed() < Duration::from_secs(1) {
            if d2.load(Ordering::Relaxed) {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        if !d2.load(Ordering::Relaxed) {
            b2.set_draw_target(ProgressDrawTarget::stderr());
            b2.enable_steady_tick(Duration::from_millis(120));
        }
    });
    let out = f();
    done.store(true, Ordering::Relaxed);
    let _ = timer.join();
    bar.finish_and_clear();
    out
}

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    if a.decimate == 0 {
        return Err(CliError::Usage(
            "--decimate 0 is not allowed: give N >= 1 (write every N-th sample)".into(),
        ));
    }
    let (model, signal_map) = load_model_with_signal(&a.model)?;
    let nm = model.normalised()?;
    nlsdof::simulation::check_model(&nm)?;
    let mut signal = with_spinner("reading input", || {
        read_signal(&a.input, a.fs, a.var.as_deref())
    })?;
    let map = signal_map.unwrap_or_default();
    if map.input_offset != 0.0 {
        for v in signal.values.iter_mut() {
            *v += map.input_offset;
        }
    }
    let gain = if a.base { -1.0 } else { 1.0 } * map.input_gain;
    let input = signal.as_input()?.with_gain(gain)?;
    let uniform = matches!(signal.grid, SignalGrid::Uniform { .. });
    // Default on uniform sampling: RK4 with h = 1/fs and cubic mid-step
    // inputs, run as RK4 with two samples per step on the input upsampled 2x.
    let cubic = uniform && a.method == MethodArg::Rk4 && a.samples_per_step.is_none();
    // A time-domain model file states its input reconstruction and RK4
    // substeps ([signal] input_interpolation, substeps): the default RK4
    // integrates that model as `fit-time` did.
    let stated = signal_map
        .filter(|_| cubic)
        .and_then(|m| m.stated_discretisation());
    let method = match a.method {
        MethodArg::Rk4 => {
            let sps = a.samples_per_step.unwrap_or(if uniform { 2 } else { 1 });
            Method::Rk4 {
                samples_per_step: sps,
            }
        }
        MethodArg::Dopri => {
            if a.samples_per_step.is_some() {
                return Err(CliError::Usage(
                    "--samples-per-step applies to --method rk4 only".into(),
                ));
            }
            Method::DormandPrince {
                rtol: a.rtol,
                atol: a.atol,
            }
        }
    };
    let initial = State { x: a.x0, v: a.v0 };
    let opts = Options {
        method,
        initial,
        decimation: 1,
    };
    let with_y = signal_map.is_some();
    let header: &[&str] = if with_y {
        &["t", "accel", "x", "v", "y"]
    } else {
        &["t", "accel", "x", "v"]
    };
    // --out FILE.uff: the rows are kept and written as a universal file at the end
    let to_uff = nlsdof_io::uff_convert::is_uff(&a.out);
    let mut out = if to_uff {
        None
    } else {
        Some(CsvWriter::create(&a.out, header)?)
    };
    let mut rows: Vec<[f64; 5]> = Vec::new();
    let n = input.len() as u64;
    let progress = Progress::new(n, "simulating");
    let mut write_err = None;
    let mut max_x = 0.0f64;
    let mut outputs = 0usize;
    // the integration error is checked on the whole of a uniform record
    let check_n = if uniform { input.len() } else { 0 };
    let mut xs: Vec<f64> = Vec::with_capacity(check_n);
    let t_sim = Instant::now();
    let mut sink = |k: usize, u: f64, x: f64, v: f64| {
        if k < check_n {
            xs.push(x);
        }
        if k % a.decimate == 0 {
            if let Some(out) = out.as_mut().filter(|_| write_err.is_none()) {
                let r = if with_y {
                    out.row(&[input.time(k), u, x, v, x + map.output_offset])
                } else {
                    out.row(&[input.time(k), u, x, v])
                };
                if let Err(e) = r {
                    write_err = Some(e);
                }
            } else if to_uff {
                rows.push([input.time(k), u, x, v, x + map.output_offset]);
            }
            outputs += 1;
        }
        max_x = max_x.max(x.abs());
        if k & 0xffff == 0 {
            progress.set(k as u64);
        }
    };
    let record = match method {
        _ if cubic => RecordMethod::Rk4Cubic,
        Method::Rk4 { samples_per_step } => RecordMethod::Rk4 { samples_per_step },
        Method::DormandPrince { rtol, atol } => RecordMethod::DormandPrince { rtol, atol },
    };
    let summary = match signal.grid {
        SignalGrid::Uniform { t0, fs } if stated.is_some() => {
            let d = stated.unwrap_or_default();
            simulate_stated(&nm, input.raw(), gain, (t0, fs), &d, initial, &mut sink)?
        }
        SignalGrid::Uniform { t0, fs } => {
            let mut each = |s: Sample| sink(s.index, s.u, s.x, s.v);
            simulate_record(&nm, input.raw(), (gain, t0, fs), record, initial, &mut each)?
        }
        SignalGrid::Times(_) => {
            simulate(&nm, &input, &opts, |s: Sample| sink(s.index, s.u, s.x, s.v))?
        }
    };
    drop(sink);
    if let Some(e) = write_err {
        return Err(e.into());
    }
    // Integration error estimate (one implementation with Python's
    // Model.simulate): step doubling on the whole record, scaled by the
    // Richardson factor of the law's order.
    let error_estimate = match signal.grid {
        SignalGrid::Uniform { fs, .. } if check_n >= 2 && stated.is_some() => {
            let d = stated.unwrap_or_default();
            let raw = &input.raw()[..check_n];
            let tm = TimeModel {
                model: nm,
                gain,
                input_offset: 0.0,
                output_offset: 0.0,
            };
            Some(
                nlsdof::identification::time_domain::stated_integration_error(
                    &tm, raw, fs, initial, &d, &xs,
                )?,
            )
        }
        SignalGrid::Uniform { t0, fs } if check_n >= 2 => {
            Some(nlsdof::simulation::record_error_estimate(
                &nm,
                input.raw(),
                (gain, t0, fs),
                record,
                initial,
                &xs,
            )?)
        }
        _ => None,
    };
    match out {
        Some(out) => out.commit()?,
        None => nlsdof_io::uff58::write_ascii_file(
            &a.out,
            &uff_datasets(&rows, with_y, &signal.grid, a.decimate),
        )?,
    }
    progress.finish();
    let elapsed = t_sim.elapsed().as_secs_f64();
    // the text Python's Model.simulate warns with
    if let Some(w) = error_estimate
        .as_ref()
        .and_then(|e| nlsdof::simulation::integration_warning(e, record))
    {
        eprintln!("nlsdof: warning: {w}");
    }
    let interpolation = match (a.method, cubic, summary.samples_per_step) {
        _ if stated.is_some() => stated.map_or("cubic", |d| d.interpolation.name()),
        (MethodArg::Dopri, _, _) => "linear",
        (_, true, _) => "cubic",
        (_, false, 2) => "samples",
        _ => "linear",
    };
    let input_name = a.input.display().to_string();
    let out_name = a.out.display().to_string();
    let run = report::SimulationRun {
        input: &input_name,
        out: &out_name,
        summary: &summary,
        outputs,
        fs: match &signal.grid {
            SignalGrid::Uniform { fs, .. } => Some(*fs),
            SignalGrid::Times(_) => None,
        },
        method: match method {
            Method::Rk4 { .. } => "rk4",
            Method::DormandPrince { .. } => "dopri",
        },
        // reported per input sample: 0.5 = two RK4 steps per sample
        samples_per_step: if let Some(d) = stated {
            1.0 / d.substeps as f64
        } else if cubic {
            2.0 / CUBIC_FACTOR as f64
        } else {
            summary.samples_per_step as f64
        },
        interpolation,
        integration_error: error_estimate.map(|e| (e.estimate, e.samples, e.is_warned())),
        max_abs_x: max_x,
        elapsed_s: elapsed,
    };
    if a.json {
        let total_s = t_start.elapsed().as_secs_f64();
        println!("{}", report::json(&run, total_s));
    } else {
        print!("{}", report::text(&run));
    }
    Ok(())
}
