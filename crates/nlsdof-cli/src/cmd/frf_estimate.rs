//! `nlsdof frf-estimate`: FRF from measured input/output time histories
//! (Welch H1/H2 with coherence, or the spectral ratio of one record),
//! written as the FRF CSV that `nlsdof linear-id` reads.

use crate::error::CliError;
use nlsdof::signal_processing::{Symmetry, Window};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// H1 = G_xy/G_xx (Welch; unbiased by output noise), with coherence.
    H1,
    /// H2 = G_yy/G_yx (Welch; unbiased by input noise), with coherence.
    H2,
    /// Y/X of the whole record (sine sweep or impact; no window, no averaging).
    Ratio,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowArg {
    Hann,
    Hamming,
    Blackman,
    Rectangular,
}

#[derive(clap::Args)]
#[command(about = "Estimate an FRF (H1, H2 or spectral ratio) from input/output time histories", after_long_help = LONG_HELP)]
pub struct Args {
    /// Time-history file holding the input channel (CSV with header, Polytec ASCII .txt, MAT v5,
    /// or universal file .uff/.unv: one real dataset 58 per channel, abscissa time in s).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// File holding the output channel, if not the --input file (e.g. Polytec exports: one channel per file).
    #[arg(long = "output-file", value_name = "FILE")]
    pub output_file: Option<PathBuf>,
    /// Input channel: column/variable name or 1-based index among the channels (default 1);
    /// in a universal file K is the dataset's position among its dataset-58 functions from 1
    /// (index + 1) and NAME text contained in its ID line 1 (one dataset must match).
    #[arg(long = "input-channel", value_name = "NAME|K", default_value = "1")]
    pub input_channel: String,
    /// Output channel: name or 1-based index (default 2, or 1 with --output-file); universal
    /// files as --input-channel.
    #[arg(long = "output-channel", value_name = "NAME|K")]
    pub output_channel: Option<String>,
    /// Sampling frequency, Hz, for files without a time column.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Estimator.
    #[arg(long, value_enum, default_value_t = MethodArg::H1)]
    pub method: MethodArg,
    /// Welch segment (FFT) length, samples (default 4096, or the record length if shorter).
    #[arg(long, value_name = "N")]
    pub segment: Option<usize>,
    /// Fractional overlap of Welch segments, in [0, 1).
    #[arg(
        long,
        value_name = "FRAC",
        default_value_t = 0.5,
        allow_hyphen_values = true
    )]
    pub overlap: f64,
    /// Welch window (periodic/DFT-even form unless --symmetric-window).
    #[arg(long, value_enum, default_value_t = WindowArg::Hann)]
    pub window: WindowArg,
    /// Use the symmetric window definition (filter-design form; not recommended for spectra).
    #[arg(long = "symmetric-window")]
    pub symmetric_window: bool,
    /// Write only frequencies >= F0 Hz.
    #[arg(long = "f-min", value_name = "F0", allow_hyphen_values = true)]
    pub f_min: Option<f64>,
    /// Write only frequencies <= F1 Hz.
    #[arg(long = "f-max", value_name = "F1", allow_hyphen_values = true)]
    pub f_max: Option<f64>,
    /// Output FRF CSV (f_hz,re,im,mag,phase_deg[,coherence]).
    #[arg(long, value_name = "FRF.csv")]
    pub out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

const LONG_HELP: &str = "DESCRIPTION:
  H1 and H2 use Welch averaging: segments of --segment samples overlapping by --overlap,
  each with its mean removed and multiplied by the window, one-sided spectral densities
  G_xx, G_yy, G_xy averaged over the segments; H1 = G_xy/G_xx, H2 = G_yy/G_yx and the
  coherence gamma^2 = |G_xy|^2/(G_xx G_yy) (= H1/H2). Windows are PERIODIC (DFT-even,
  denominator N), the correct form for spectral analysis; --symmetric-window selects the
  filter-design form (denominator N-1) for comparison. The random error of |H1| is about
  sqrt(1 - gamma^2)/(|gamma| sqrt(2 n_d)) with n_d averages.
  --method ratio divides the spectra of the whole record, Y(f)/X(f), without window: the
  right estimate for one sine sweep or one impact whose response decays within the record.

INPUT FILES:
  CSV with a header (a time column t/time, or --fs) and named channels; Polytec ASCII time
  exports (.txt starting `Source File Name`, one channel per file: use --output-file);
  MAT v5 (one variable per channel, named with --input-channel/--output-channel; fs from a
  scalar `fs`, a `t` vector or --fs). Sampling must be uniform.
  Universal file (.uff/.unv, dataset 58/58b): each channel is a real dataset (time
  response) with a time abscissa in s, chosen by its position K from 1 among the file's
  dataset-58 functions (dataset index + 1; default 1 and 2, as for CSV columns) or by text
  of its ID line 1; the sampling comes from the file (--fs is refused). Complex functions
  (FRFs, spectra) are refused.

EXAMPLES:
  nlsdof frf-estimate --input test.csv --input-channel force --output-channel vel --out h1.csv
  nlsdof frf-estimate --input mec-t1-force.txt --output-file mec-t1-velocity.txt \\
      --method ratio --f-min 50 --f-max 400 --out impact.csv

Errors are one line on stderr, exit code 2; no output file is left behind.";

pub fn run(args: Args) -> Result<(), CliError> {
    use nlsdof::signal_processing::{estimate_frf, FrfEstimateOptions, FrfMethod};
    let (fs, x, y) = nlsdof_io::frf_file::read_channel_pair(
        &args.input,
        &args.input_channel,
        args.output_file.as_deref(),
        args.output_channel.as_deref(),
        args.fs,
    )?;
    if x.len() != y.len() {
        return Err(CliError::Usage(format!(
            "input has {} samples but output has {}: lengths must match",
            x.len(),
            y.len()
        )));
    }
    let f_lo = args.f_min.unwrap_or(0.0);
    let f_hi = args.f_max.unwrap_or(f64::INFINITY);
    if f_lo.is_nan() || f_hi.is_nan() || f_lo >= f_hi {
        return Err(CliError::Usage(format!(
            "--f-min {f_lo} / --f-max {f_hi}: need f-min < f-max"
        )));
    }
    let opts = FrfEstimateOptions {
        method: match args.method {
            MethodArg::H1 => FrfMethod::H1,
            MethodArg::H2 => FrfMethod::H2,
            MethodArg::Ratio => FrfMethod::Ratio,
        },
        segment: args.segment,
        overlap: args.overlap,
        window: match args.window {
            WindowArg::Hann => Window::Hann,
            WindowArg::Hamming => Window::Hamming,
            WindowArg::Blackman => Window::Blackman,
            WindowArg::Rectangular => Window::Rectangular,
        },
        symmetry: if args.symmetric_window {
            Symmetry::Symmetric
        } else {
            Symmetry::Periodic
        },
        f_min: args.f_min,
        f_max: args.f_max,
    };
    let e = estimate_frf(fs, &x, &y, &opts).map_err(|e| match e {
        nlsdof::signal_processing::FrfEstimateError::Signal(s) => CliError::SignalProcessing(s),
        e => CliError::Usage(e.to_string()),
    })?;
    let hk: Vec<(f64, f64)> = e.h.iter().map(|h| (h.re, h.im)).collect();
    nlsdof_io::frf_file::write_frf_csv(&args.out, &e.frequency_hz, &hk, e.coherence.as_deref())?;
    let out = args.out.display().to_string();
    if args.json {
        println!("{}", nlsdof_report::frf_estimate::json(&e, Some(&out)));
    } else {
        println!("{}", nlsdof_report::frf_estimate::text(&e));
        println!("FRF written to {out}");
    }
    Ok(())
}
