//! `nlsdof decay`: free-decay identification (library:
//! `nlsdof::identification::decay`): Hilbert envelope and instantaneous
//! frequency, backbone, damping curve, averaged-equation fit, envelope
//! check, SVG figure.

use crate::error::CliError;
use nlsdof::identification::decay::{analyse, DecayOptions};
use nlsdof::identification::time_domain::uniform_fs;
use nlsdof_io::input::read_columns;
use nlsdof_report::decay as report;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    about = "Free-decay identification: Hilbert backbone f(a), damping curve, averaged power-law fit, envelope check",
    after_long_help = DECAY_HELP
)]
pub struct Args {
    /// Record: LabVIEW .lvm text (two header blocks) or CSV with a header.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Response column (header name or 0-based index).
    #[arg(long, value_name = "NAME")]
    pub column: String,
    /// Time column (s; default X_Value, t or time if present).
    #[arg(long, value_name = "C")]
    pub time_column: Option<String>,
    /// Sampling frequency, Hz (instead of a time column).
    #[arg(long, value_name = "HZ", allow_hyphen_values = true)]
    pub fs: Option<f64>,
    /// Start of the free decay, s from the first sample (default: where the envelope leaves its maximum).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_start: Option<f64>,
    /// Band-pass around the mode F1:F2 in Hz (default: 0.5 to 1.5 x the spectral peak).
    #[arg(long, value_name = "F1:F2")]
    pub band: Option<String>,
    /// Amplitude bins of the backbone.
    #[arg(long, default_value_t = 30)]
    pub bins: usize,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// Figure (SVG or PNG, from the file name): record with envelope, backbone, damping curve.
    #[arg(long, value_name = "FIG.svg|FIG.png")]
    pub plot: Option<PathBuf>,
    /// Unit of the response column, stated on the figure's axes (default: the LVM header's
    /// Y_Unit_Label of the column, else "unit as recorded").
    #[arg(long, value_name = "UNIT")]
    pub unit: Option<String>,
}

/// The unit of column `column` in a LabVIEW .lvm header (`Y_Unit_Label`,
/// one entry per channel after the X column), if the file is one and says.
fn lvm_unit(path: &std::path::Path, column: &str) -> Option<String> {
    use std::io::Read as _;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(256 * 1024)
        .read_to_end(&mut head)
        .ok()?;
    let text = String::from_utf8_lossy(&head);
    if !text.starts_with("LabVIEW Measurement") {
        return None;
    }
    let mut units: Option<Vec<String>> = None;
    for line in text.lines() {
        let fields: Vec<&str> = line.split('\t').collect();
        match fields.first().map(|f| f.trim()) {
            Some("Y_Unit_Label") => {
                units = Some(fields[1..].iter().map(|u| u.trim().to_string()).collect())
            }
            Some("X_Value") => {
                let k = match column.trim().parse::<usize>() {
                    Ok(k) => k,
                    Err(_) => fields.iter().position(|f| f.trim() == column.trim())?,
                };
                // channel k - 1: the X column comes first
                let u = units?.get(k.checked_sub(1)?)?.clone();
                return (!u.is_empty()).then_some(u);
            }
            _ => {}
        }
    }
    None
}

const DECAY_HELP: &str = "METHOD:
  Analytic signal by FFT (zero-padded to >= 2N, band-pass with raised-cosine edges; a
  record longer than 2^19 samples is filtered in overlapping blocks of 2^20 points, so
  memory stays near the record's own size), the instantaneous amplitude a(t) = |z| and
  frequency f(t); the ends are trimmed by max(3 cycles, 2/bandwidth). Backbone f(a) and decay rate lambda(a) = -d ln a/dt per
  amplitude bin. The averaged power-law equations
      omega^2 = alpha + g(rho) beta a^rho
      da/dt  = -a (delta + g(eta) kappa (omega a)^eta) / 2
  are fitted (grid over the exponent + Levenberg-Marquardt, 95 % intervals), and the
  fitted model's simulated free decay from (a0, 0) is compared with the measured
  envelope (RMS error relative to the largest amplitude).

EXAMPLE:
  nlsdof decay --input ../shared/data/magnetomechanical-sdof-decay-frid/decay_f_42p05_ampl_2p0_0.lvm \\
      --column Strain_0 --t-start 12 --json --plot decay.svg";

pub fn run(a: Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    let band = match &a.band {
        None => None,
        Some(b) => {
            let bad = || CliError::Usage(format!("--band {b:?} is not F1:F2 in Hz (e.g. 30:50)"));
            let (x, y) = b.split_once(':').ok_or_else(bad)?;
            Some((
                x.trim().parse::<f64>().map_err(|_| bad())?,
                y.trim().parse::<f64>().map_err(|_| bad())?,
            ))
        }
    };
    if a.bins < 4 {
        return Err(CliError::Usage(format!(
            "--bins {}: give at least 4",
            a.bins
        )));
    }
    nlsdof_report::figure_file::check_plot_name(a.plot.as_deref())?;
    if let Some(p) = &a.plot {
        nlsdof_io::atomic::check_targets(&[("--plot", p)])?;
    }
    if let Some(fs) = a.fs {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(CliError::Usage(format!(
                "--fs {fs} must be a finite sampling frequency > 0 Hz"
            )));
        }
        if a.time_column.is_some() {
            return Err(CliError::Usage(
                "give either --fs or --time-column, not both".into(),
            ));
        }
    }
    // every format (CSV, LVM, Polytec, MAT, UFF) through the one reader;
    // without --time-column the file's own time column (X_Value, t, time)
    let (x, fs, t0) = if let Some(fs) = a.fs {
        let t = read_columns(&a.input, &[a.column.as_str()], false)?;
        (t.columns.into_iter().next().unwrap_or_default(), fs, 0.0)
    } else {
        let t = match &a.time_column {
            Some(c) => read_columns(&a.input, &[a.column.as_str(), c.as_str()], false)?,
            None => read_columns(&a.input, &[a.column.as_str()], true)?,
        };
        if t.columns.len() < 2 {
            return Err(CliError::Usage(format!(
                "{}: no time column ({}): give --time-column C or --fs HZ",
                a.input.display(),
                nlsdof_io::input::TIME_COLUMNS.join(", ")
            )));
        }
        let mut cols = t.columns.into_iter();
        let x = cols.next().unwrap_or_default();
        let time = cols.next().unwrap_or_default();
        let fs = uniform_fs(&time, 1e-3).map_err(|e| {
            CliError::Usage(format!(
                "{}: column {:?}: {e}",
                a.input.display(),
                t.names[1]
            ))
        })?;
        (x, fs, time.first().copied().unwrap_or(0.0))
    };
    let opts = DecayOptions {
        t_start: a.t_start.map(|t| t - t0),
        band,
        bins: a.bins,
        // Ctrl-C ends the process (main's handler): nothing to poll here
        ..DecayOptions::default()
    };
    let t_an = Instant::now();
    let r = analyse(&x, fs, &opts)
        .map_err(|e| CliError::Usage(format!("{}: {e}", a.input.display())))?;
    let analyse_s = t_an.elapsed().as_secs_f64();
    if let Some(p) = &a.plot {
        let unit = a.unit.clone().or_else(|| lvm_unit(&a.input, &a.column));
        let format = nlsdof_report::figure_file::plot_format(p);
        let bytes = report::decay_figure(&x, fs, t0, &r, &a.column, unit.as_deref(), format)?;
        nlsdof_io::atomic::write_atomic(p, &bytes)?;
    }
    let input = a.input.display().to_string();
    let rec = report::DecayRecord {
        input: &input,
        column: &a.column,
        fs,
        t0,
    };
    if a.json {
        let total_s = t_start.elapsed().as_secs_f64();
        println!("{}", report::decay_json(&rec, &r, analyse_s, total_s));
    } else {
        print!("{}", report::decay_text(&rec, &r, analyse_s));
    }
    Ok(())
}
