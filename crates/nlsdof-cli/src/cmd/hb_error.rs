//! `nlsdof hb-error`: how wrong is the first-order harmonic balance? The
//! truncation error in the resonance peak and the fold frequencies against
//! the number of harmonics H, until converged
//! ([`nlsdof::multi_harmonic::truncation`]).

use super::roots::{check_frequency, check_gamma, load_steady_model};
use crate::error::CliError;
use nlsdof::multi_harmonic::truncation::truncation_study;
use nlsdof::multi_harmonic::ContinuationOptions;
use nlsdof_report::truncation as report;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Harmonic counts tried, in order.
use nlsdof::multi_harmonic::truncation::HARMONIC_LADDER as LADDER;

#[derive(clap::Args)]
#[command(
    about = "Truncation error of the first-order harmonic balance (peak, folds) against the number of harmonics",
    after_long_help = "DESCRIPTION:
  For each input level, the response curve is continued (pseudo-arclength) over the band
  with H = 1, 3, 5, 7, 9, 11, 15, 21, 31, 41, 51, 63 harmonics (constant and even terms
  included) until the resonance peak (first-harmonic amplitude and frequency, located on
  the branch) and every fold frequency change by less than --tol (relative) from one H to
  the next. That H is the reference; the table gives each H's error against it. H = 1 is
  today's exact first-order balance (the paper's, Eq 11).

  If the ladder ends before convergence the study is reported as not converged, with the
  last change, and a warning on stderr (exit code 0).

OUTPUT:
  text (default): per level, one row per H: peak amplitude and frequency, max|x| at the
        peak, fold frequencies, error against the reference, samples per period
  --json: {\"levels\":[{\"gamma\":..,\"converged\":..,\"reference_harmonics\":..,\"rows\":[{\"harmonics\":..,
        \"peak\":{\"f_hz\":..,\"amplitude\":..,\"max_abs_x\":..},\"folds_hz\":[..],\"fold_amplitudes\":[..],
        \"peak_amplitude_error\":..,\"peak_frequency_error\":..,\"fold_frequency_errors\":[..],
        \"change\":..,\"samples_per_period\":..,\"points\":..}]}]}

EXAMPLES:
  nlsdof hb-error --model examples/duffing-strong.toml --gamma 0.5,2 --f-min 8 --f-max 16
  nlsdof hb-error --model examples/har-wing.toml --gamma 1.23 --f-min 5.2 --f-max 5.6 --json"
)]
pub struct Args {
    /// Model file (TOML, SI units).
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Input levels gamma, m/s^2 zero-to-peak, comma-separated.
    #[arg(long, value_name = "G1,G2,..", allow_hyphen_values = true)]
    pub gamma: String,
    /// Lowest frequency, Hz (default 0.8 f_n).
    #[arg(long = "f-min", value_name = "F0", allow_hyphen_values = true)]
    pub f_min: Option<f64>,
    /// Highest frequency, Hz (default 2 f_n).
    #[arg(long = "f-max", value_name = "F1", allow_hyphen_values = true)]
    pub f_max: Option<f64>,
    /// Convergence tolerance (relative change between successive H).
    #[arg(long, default_value_t = 1e-6)]
    pub tol: f64,
    /// Largest H of the ladder (1..=63).
    #[arg(long = "h-max", default_value_t = 63)]
    pub h_max: usize,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<(), CliError> {
    let mut gammas = Vec::new();
    for item in args.gamma.split(',') {
        let v: f64 = item.trim().parse().map_err(|_| {
            CliError::Usage(format!(
                "--gamma: '{}' is not a number: give input levels (m/s^2, zero-to-peak) as a comma-separated list",
                item.trim()
            ))
        })?;
        gammas.push(check_gamma(v)?);
    }
    if !(args.tol.is_finite() && args.tol > 0.0 && args.tol < 1.0) {
        return Err(CliError::Usage(format!(
            "--tol {:e} is not allowed: need 0 < tol < 1",
            args.tol
        )));
    }
    if args.h_max == 0 || args.h_max > 63 {
        return Err(CliError::Usage(format!(
            "--h-max {} is not allowed: need an integer from 1 to 63",
            args.h_max
        )));
    }
    let (model, gain) = load_steady_model(&args.model)?;
    if let Some(note) = super::roots::gain_note(gain) {
        eprintln!("nlsdof: {note}");
    }
    super::frf_mhb::check_damped(&model, "hb-error")?;
    let fn_hz = model.omega_n() / (2.0 * PI);
    let f_min = check_frequency("--f-min", args.f_min.unwrap_or(0.8 * fn_hz))?;
    let f_max = check_frequency("--f-max", args.f_max.unwrap_or(2.0 * fn_hz))?;
    if f_min >= f_max {
        return Err(CliError::Usage(format!(
            "--f-min {f_min} must be below --f-max {f_max} (Hz)"
        )));
    }
    let ladder: Vec<usize> = LADDER
        .iter()
        .copied()
        .filter(|&h| h <= args.h_max)
        .collect();
    let n = model.normalised()?;
    let mut studies = Vec::new();
    for &g in &gammas {
        // the model sees input_gain * gamma; the report gives gamma as given
        let st = crate::cmd::simulate::with_spinner("truncation study", || {
            truncation_study(
                &n,
                gain * g,
                2.0 * PI * f_min,
                2.0 * PI * f_max,
                &ladder,
                args.tol,
                nlsdof::multi_harmonic::settings_for(&n),
                &ContinuationOptions::default(),
            )
        })?;
        if !st.converged {
            // no NaN in a message: one H has no change to compare
            let last = match st.rows.last().map(|r| r.change) {
                Some(c) if c.is_finite() => format!("last change {c:.3e}"),
                _ => "one H only: nothing to compare; give --h-max 3 or more".into(),
            };
            eprintln!(
                "nlsdof: warning: gamma = {g}: not converged to --tol {:e} by H = {} ({last}); errors are against H = {}",
                args.tol,
                ladder.last().unwrap_or(&1),
                st.rows[st.reference].harmonics
            );
        }
        for r in &st.rows {
            if let Some(w) = &r.warning {
                eprintln!(
                    "nlsdof: warning: gamma = {g}, H = {}: continuation stopped early: {w}",
                    r.harmonics
                );
            }
        }
        studies.push((g, st));
    }
    let model_name = args.model.display().to_string();
    let request = report::StudyRequest {
        model_name: &model_name,
        f_min,
        f_max,
        tol: args.tol,
    };
    if args.json {
        println!("{}", report::study_json(&request, &model, &studies));
    } else {
        print!("{}", report::study_text(&request, &model, &studies));
    }
    Ok(())
}
