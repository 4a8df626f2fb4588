//! `nlsdof spectrogram`: STFT spectrogram of a recorded or simulated signal
//! (paper section 4.5), optionally compared with a second one by Eq 33 and
//! its robust variant; heat-map and waterfall PNGs, CSV, JSON.

use crate::cmd::simulate::with_spinner;
use crate::error::CliError;
use nlsdof::signal_processing::spectrogram_comparison::{
    compare_records, ComparisonError, ComparisonOptions, SpectrogramComparison,
};
use nlsdof::signal_processing::stft::{Detrend, Scaling, Spectrogram, StftOptions};
use nlsdof::signal_processing::{Symmetry, Window};
use nlsdof_io::signal_file::{read_signal, CsvWriter, SignalGrid, UNIFORM_TOLERANCE};
use nlsdof_report::spectrogram as report;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WindowArg {
    Hamming,
    Hann,
    Blackman,
    Rectangular,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DetrendArg {
    /// No mean removal (MATLAB spectrogram; the paper).
    None,
    /// Remove each segment's mean (scipy's default).
    Constant,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ScalingArg {
    /// c_k |X_k| / sum(w): a sine of amplitude A on a bin reads A (signal unit).
    Amplitude,
    /// c_k |X_k|^2 / (fs sum(w^2)): power spectral density, unit^2/Hz.
    Psd,
}

#[derive(clap::Args)]
#[command(
    about = "STFT spectrogram of a signal, optionally compared with another (Eq 33), with PNG heat map and waterfall",
    after_long_help = SPECTROGRAM_HELP
)]
pub struct Args {
    /// Signal file (the measurement): CSV or MAT, as read by `simulate --input`.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Column (CSV header name, e.g. x for `simulate` output), MAT variable, or the dataset of a
    /// .uff/.unv universal file (index from 0 or ID-line text); default: the accel column.
    #[arg(long, value_name = "NAME")]
    pub column: Option<String>,
    /// Sampling frequency of a one-column CSV, Hz.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Second signal (the model) to compare with --input by Eq 33; same length and sampling.
    #[arg(long, value_name = "FILE")]
    pub compare: Option<PathBuf>,
    /// Column of the --compare file (default: --column).
    #[arg(long, value_name = "NAME")]
    pub compare_column: Option<String>,
    /// Window shape.
    #[arg(long, value_enum, default_value_t = WindowArg::Hamming)]
    pub window: WindowArg,
    /// Periodic (DFT-even) window instead of the paper's symmetric one.
    #[arg(long)]
    pub periodic: bool,
    /// Segment length L = floor(N / SEGMENTS) samples (the paper: 15).
    #[arg(long, value_name = "N", default_value_t = 15)]
    pub segments: usize,
    /// Overlap of consecutive segments, fraction of L in [0, 1).
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub overlap: f64,
    /// FFT length (>= L, zero padding; at most 2^24 = 16777216, and at most 5e7 spectrogram values in all); default L.
    #[arg(long, value_name = "N")]
    pub nfft: Option<usize>,
    /// Segment mean removal.
    #[arg(long, value_enum, default_value_t = DetrendArg::None)]
    pub detrend: DetrendArg,
    /// Value scaling.
    #[arg(long, value_enum, default_value_t = ScalingArg::Amplitude)]
    pub scaling: ScalingArg,
    /// Robust Eq 33: only bins with s_exp >= FLOOR x max s_exp (0.01 = -40 dB in amplitude).
    #[arg(
        long,
        value_name = "FRACTION",
        default_value_t = 0.01,
        allow_hyphen_values = true
    )]
    pub floor: f64,
    /// Lowest frequency shown and compared, Hz.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fmin: Option<f64>,
    /// Highest frequency shown and compared, Hz.
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fmax: Option<f64>,
    /// Heat map PNG (time x frequency, dB colour scale; side by side with --compare).
    #[arg(long, value_name = "FIG.png")]
    pub plot: Option<PathBuf>,
    /// 3-D waterfall PNG (Fig 8: one spectrum per segment).
    #[arg(long, value_name = "FIG.png")]
    pub waterfall: Option<PathBuf>,
    /// CSV of the spectrogram(s) in the band, one row per cell: t_s,f_hz,s[,s_compare,rel_diff_percent].
    #[arg(long, value_name = "OUT.csv")]
    pub csv: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

const SPECTROGRAM_HELP: &str = "STFT (paper section 4.5):
  The record x_0..x_{N-1} (sampling fs) is cut into segments of L = floor(N/SEGMENTS)
  samples (paper: N/15) that overlap by round(OVERLAP*L) (paper: 50 %). Each segment is
  multiplied by the window w (paper: symmetric Hamming) and transformed:
    X_m(k) = sum_n w_n x_{mH+n} exp(-2 pi j k n / NFFT),  f_k = k fs / NFFT [Hz],
    t_m = start time + (m H + L/2)/fs [s] (segment centres), hop H = L - round(OVERLAP*L).
  Trailing samples that do not fill a segment are not used.

SCALING (one-sided, c_k = 2 except 1 at 0 Hz and Nyquist):
  amplitude  s = c_k |X_m(k)| / sum(w): a sine of amplitude A at a bin frequency reads A,
             in the signal's unit (m for x, m/s for v, m/s^2 for accel). Default.
  psd        s = c_k |X_m(k)|^2 / (fs sum(w^2)), unit^2/Hz (scipy's default 'density').
  Plots show dB: 20 log10(amplitude) or 10 log10(psd), over the top 80 dB.

COMPARISON (--compare, paper Eq 33), measured s_exp = --input, model s_num = --compare:
  Eq 33    max over (f,t) of |s_exp - s_num| / s_exp * 100 %
  robust   the same maximum over the bins with s_exp >= FLOOR * max(s_exp) only.
  Eq 33 divides by s_exp bin by bin: where the measured spectrogram is (near) zero -
  far from the excitation, only noise, leakage and round-off - the ratio of two tiny
  unrelated numbers is arbitrarily large, so Eq 33 then reports the noise floor, not
  the model. The robust value measures the model where there is signal. Also reported:
  the global relative difference ||s_exp - s_num|| / ||s_exp|| * 100 %.
  The absolute value is used (the paper prints no bars; without them over-predictions
  would be ignored). --fmin/--fmax restrict the comparison, the plots and the CSV.
  Both files must have the same length and sampling; use the same column, e.g. the
  recorded response and `nlsdof simulate` output driven by the recorded input.

INPUT:
  CSV t,value or one column with --fs, or a header with named columns (--column NAME,
  e.g. x, v or accel of `nlsdof simulate` output), a MAT v5 file (--column = variable),
  or a universal file .uff/.unv, dataset 58/58b (--column = dataset index or ID-line text).
  Sampling must be uniform. Errors: one line on stderr, exit 2, no output file.

EXAMPLE (a virtual measurement and a model with other parameters, same input):
  nlsdof signal stepped-sine --amplitude 0.62 --f-min 5 --f-max 5.8 --steps 40 --dwell 20 \\
      --fs 256 --out input.csv
  nlsdof simulate --model examples/har-wing.toml --input input.csv --out measured.csv
  nlsdof simulate --model my-model.toml --input input.csv --out model.csv
  nlsdof spectrogram --input measured.csv --column x --compare model.csv \\
      --fmin 4 --fmax 7 --plot spec.png --waterfall fig8.png";

/// A uniformly sampled signal.
struct Record {
    values: Vec<f64>,
    t0: f64,
    fs: f64,
    column: String,
}

fn load(path: &Path, column: Option<&str>, fs: Option<f64>) -> Result<Record, CliError> {
    if let Some(fs) = fs {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(CliError::Usage(format!(
                "--fs {fs} must be finite and > 0 Hz"
            )));
        }
    }
    // every format (CSV, LVM, Polytec, MAT, UFF) through the one reader
    let s = read_signal(path, fs, column)?;
    match s.grid {
        SignalGrid::Uniform { t0, fs } => Ok(Record {
            values: s.values,
            t0,
            fs,
            column: column.unwrap_or("accel").to_string(),
        }),
        SignalGrid::Times(_) => Err(non_uniform(path)),
    }
}

fn non_uniform(path: &Path) -> CliError {
    CliError::Usage(format!(
        "{}: the time column is not uniformly sampled (to within {UNIFORM_TOLERANCE} of a step): a spectrogram needs uniform sampling",
        path.display()
    ))
}

fn stft_err(e: nlsdof::signal_processing::stft::StftError) -> CliError {
    CliError::Usage(e.to_string())
}

fn label_of(path: &Path, column: &str) -> String {
    let stem = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!("{stem} [{column}]")
}

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    // --- validate the command line before any work
    if a.segments == 0 {
        return Err(CliError::Usage(
            "--segments 0 is not allowed: give S >= 1 (L = floor(N/S))".into(),
        ));
    }
    if !(a.overlap >= 0.0 && a.overlap < 1.0) {
        return Err(CliError::Usage(format!(
            "--overlap {} must be a fraction in [0, 1)",
            a.overlap
        )));
    }
    if !(0.0..=1.0).contains(&a.floor) {
        return Err(CliError::Usage(format!(
            "--floor {} must be a fraction in [0, 1] of the measured maximum",
            a.floor
        )));
    }
    for (name, v) in [("--fmin", a.fmin), ("--fmax", a.fmax)] {
        if let Some(v) = v {
            if !(v.is_finite() && v >= 0.0) {
                return Err(CliError::Usage(format!(
                    "{name} {v} must be finite and >= 0 Hz"
                )));
            }
        }
    }
    if let (Some(lo), Some(hi)) = (a.fmin, a.fmax) {
        if lo >= hi {
            return Err(CliError::Usage(format!(
                "--fmin {lo} must be below --fmax {hi}"
            )));
        }
    }
    if a.compare_column.is_some() && a.compare.is_none() {
        return Err(CliError::Usage(
            "--compare-column needs --compare FILE".into(),
        ));
    }
    {
        use nlsdof_report::figure_file::{check_figure, FigureFormat};
        check_figure("--plot", a.plot.as_deref(), &[FigureFormat::Png])?;
        check_figure("--waterfall", a.waterfall.as_deref(), &[FigureFormat::Png])?;
    }
    let outs: Vec<&PathBuf> = [&a.plot, &a.waterfall, &a.csv]
        .into_iter()
        .flatten()
        .collect();
    for (i, p) in outs.iter().enumerate() {
        if outs[..i].contains(p) {
            return Err(CliError::Usage(format!(
                "{} is given for two outputs",
                p.display()
            )));
        }
        for inp in std::iter::once(&a.input).chain(a.compare.as_ref()) {
            if *p == inp {
                return Err(CliError::Usage(format!(
                    "output {} would overwrite an input file",
                    p.display()
                )));
            }
        }
    }

    // --- read
    let measured = with_spinner("reading input", || {
        load(&a.input, a.column.as_deref(), a.fs)
    })?;
    let model = match &a.compare {
        Some(p) => {
            let col = a.compare_column.as_deref().or(a.column.as_deref());
            let r = with_spinner("reading comparison", || load(p, col, a.fs))?;
            if r.values.len() != measured.values.len() {
                return Err(CliError::Usage(format!(
                    "{} has {} samples but {} has {}: the comparison needs records of the same length",
                    a.input.display(),
                    measured.values.len(),
                    p.display(),
                    r.values.len()
                )));
            }
            if (r.fs - measured.fs).abs() > 1e-9 * measured.fs {
                return Err(CliError::Usage(format!(
                    "{} is sampled at {} Hz but {} at {} Hz: the comparison needs the same sampling",
                    a.input.display(),
                    measured.fs,
                    p.display(),
                    r.fs
                )));
            }
            Some(r)
        }
        None => None,
    };

    // --- compute
    let n = measured.values.len();
    let mut opts = StftOptions::with_segments(n, measured.fs, a.segments);
    opts.window = match a.window {
        WindowArg::Hamming => Window::Hamming,
        WindowArg::Hann => Window::Hann,
        WindowArg::Blackman => Window::Blackman,
        WindowArg::Rectangular => Window::Rectangular,
    };
    opts.symmetry = if a.periodic {
        Symmetry::Periodic
    } else {
        Symmetry::Symmetric
    };
    opts.overlap = a.overlap;
    opts.nfft = a.nfft;
    opts.detrend = match a.detrend {
        DetrendArg::None => Detrend::None,
        DetrendArg::Constant => Detrend::Constant,
    };
    opts.scaling = match a.scaling {
        ScalingArg::Amplitude => Scaling::Amplitude,
        ScalingArg::Psd => Scaling::Psd,
    };
    let layout = opts.layout(n).map_err(|e| {
        CliError::Usage(format!(
            "{} ({} samples, --segments {}): {e}",
            a.input.display(),
            n,
            a.segments
        ))
    })?;
    let t_stft = Instant::now();
    let cmp_opts = ComparisonOptions {
        stft: opts,
        band: (a.fmin, a.fmax),
        time_offset: measured.t0,
        floor_fraction: a.floor,
        // Ctrl-C ends the process (main's handler): nothing to poll here
        cancel: nlsdof::cancel::Cancel::NEVER,
    };
    let cmp = with_spinner("computing spectrograms", || {
        compare_records(
            &measured.values,
            model.as_ref().map(|m| m.values.as_slice()),
            &cmp_opts,
        )
    })
    .map_err(|e| match e {
        ComparisonError::EmptyBand { low, high, last } => CliError::Usage(format!(
            "no frequency bin in {low}..{high} Hz (bins every {} Hz up to {last} Hz)",
            measured.fs / layout.nfft as f64,
        )),
        ComparisonError::Stft(e) => stft_err(e),
    })?;
    let stft_s = t_stft.elapsed().as_secs_f64();
    drop(model);
    let SpectrogramComparison {
        measured: sm,
        model: sn,
        difference: diff,
        band: f_range,
    } = cmp;

    // --- render everything in memory, then write all files atomically
    let label_m = label_of(&a.input, &measured.column);
    let label_n = a
        .compare
        .as_ref()
        .map(|p| label_of(p, a.compare_column.as_deref().unwrap_or(&measured.column)));
    let mut panels: Vec<(&str, &Spectrogram)> = vec![(label_m.as_str(), &sm)];
    if let (Some(l), Some(s)) = (&label_n, &sn) {
        panels.push((l.as_str(), s));
    }
    let input = a.input.display().to_string();
    let compare = a.compare.as_ref().map(|p| p.display().to_string());
    let compare_column = a.compare_column.as_deref().unwrap_or(&measured.column);
    let run = report::SpectrogramRun {
        label: &label_m,
        input: &input,
        column: &measured.column,
        compare: compare.as_deref().map(|f| (f, compare_column)),
        fs: measured.fs,
        t0: measured.t0,
        samples: n,
        options: &cmp_opts.stft,
        layout: &layout,
        measured: &sm,
        difference: diff.as_ref(),
        floor: a.floor,
    };
    let title = report::title(&run);
    let t_plot = Instant::now();
    let heat = match &a.plot {
        Some(_) => Some(with_spinner("drawing heat map", || {
            nlsdof_figure::heatmap_png(&panels, f_range, &title)
        })?),
        None => None,
    };
    let fall = match &a.waterfall {
        Some(_) => Some(with_spinner("drawing waterfall", || {
            nlsdof_figure::waterfall_png(&panels, f_range, &title)
        })?),
        None => None,
    };
    let plot_s = t_plot.elapsed().as_secs_f64();
    let mut pending: Vec<nlsdof_io::atomic::AtomicFile> = Vec::new();
    for (path, bytes) in [(&a.plot, &heat), (&a.waterfall, &fall)] {
        if let (Some(p), Some(b)) = (path, bytes) {
            let mut f = nlsdof_io::atomic::AtomicFile::create(p)?;
            std::io::Write::write_all(&mut f, b).map_err(|source| {
                CliError::Io(nlsdof_io::IoError::Write {
                    path: p.clone(),
                    source,
                })
            })?;
            pending.push(f);
        }
    }
    let csv = match &a.csv {
        Some(p) => Some(with_spinner("writing CSV", || {
            write_csv(p, &sm, sn.as_ref())
        })?),
        None => None,
    };
    if let Some(w) = csv {
        w.commit()?;
    }
    for f in pending {
        f.commit()?;
    }

    // --- report
    if a.json {
        let outputs = json!({"plot": a.plot, "waterfall": a.waterfall, "csv": a.csv});
        let timings = (stft_s, plot_s, t_start.elapsed().as_secs_f64());
        println!("{}", report::json(&run, outputs, timings));
    } else {
        print!("{}", report::text(&run, stft_s));
        for (what, p) in [
            ("heat map", &a.plot),
            ("waterfall", &a.waterfall),
            ("CSV", &a.csv),
        ] {
            if let Some(p) = p {
                println!("wrote {what} {}", p.display());
            }
        }
    }
    Ok(())
}

fn write_csv(
    path: &Path,
    sm: &Spectrogram,
    sn: Option<&Spectrogram>,
) -> Result<CsvWriter, CliError> {
    let header: &[&str] = if sn.is_some() {
        &["t_s", "f_hz", "s", "s_compare", "rel_diff_percent"]
    } else {
        &["t_s", "f_hz", "s"]
    };
    let mut w = CsvWriter::create(path, header)?;
    for t in 0..sm.n_time {
        for k in 0..sm.n_freq {
            let e = sm.at(t, k);
            match sn {
                Some(sn) => {
                    let s = sn.at(t, k);
                    let d = (e - s).abs();
                    let r = if d == 0.0 { 0.0 } else { d / e * 100.0 };
                    w.row(&[sm.times[t], sm.frequencies[k], e, s, r])?;
                }
                None => w.row(&[sm.times[t], sm.frequencies[k], e])?,
            }
        }
    }
    Ok(w)
}
