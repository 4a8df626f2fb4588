//! `nlsdof frf --harmonics H` (H ≥ 2): the stepped-sine curves by
//! multi-harmonic balance (constant and even harmonics included) with
//! pseudo-arclength continuation and Hill stability
//! ([`nlsdof::multi_harmonic`]). Output formats extend those of `frf`:
//! every point carries its harmonics and `max_abs_x`.

use crate::error::CliError;
use nlsdof::multi_harmonic::{level_sweeps, MAX_HARMONICS};
use nlsdof::{Model, SweepDirection};
use nlsdof_report::multi_harmonic as report;
use nlsdof_report::steady_state::sweep_name;
use std::fmt::Write as _;

/// Largest `--harmonics` accepted on the command line.
pub const CLI_MAX_HARMONICS: usize = if MAX_HARMONICS < 64 {
    MAX_HARMONICS
} else {
    64
};

/// Refuses a model without any damping: its forced response has no steady
/// state at resonance (the amplitude is unbounded) and every periodic
/// solution is only neutrally stable, so neither continuation nor Hill's
/// method has a defined answer.
pub fn check_damped(model: &Model, flag: &str) -> Result<(), CliError> {
    let c_e = model
        .nonlinear_damping
        .map(|d| d.coefficient)
        .unwrap_or(0.0);
    if model.damping == 0.0 && c_e == 0.0 {
        return Err(CliError::Usage(format!(
            "{flag}: the model has no damping (c = 0 and no c_e term): at resonance there is no forced steady state and every periodic solution is only neutrally stable; give c > 0 or a damping term"
        )));
    }
    Ok(())
}

/// What `frf --harmonics H` was asked for (the parsed `frf` arguments).
pub struct Request<'a> {
    /// The model file, as named.
    pub model: &'a std::path::Path,
    pub sweep: SweepDirection,
    pub steps: usize,
    pub harmonics: usize,
    pub json: bool,
    pub csv: bool,
    pub plot: Option<&'a std::path::Path>,
    /// The model file's `[signal] input_gain`: the model sees `gain * gamma`.
    pub input_gain: f64,
}

/// Checks `--harmonics`.
pub fn check_harmonics(h: usize) -> Result<usize, CliError> {
    if h == 0 || h > CLI_MAX_HARMONICS {
        return Err(CliError::Usage(format!(
            "--harmonics {h} is not allowed: need an integer from 1 (exact first-order balance) to {CLI_MAX_HARMONICS}"
        )));
    }
    Ok(h)
}

pub fn run(
    args: &Request,
    model: &Model,
    gammas: &[f64],
    omegas: &[f64],
    f_min: f64,
    f_max: f64,
) -> Result<(), CliError> {
    let h = args.harmonics;
    check_damped(model, "--harmonics")?;
    let gain = args.input_gain;
    let model_gammas: Vec<f64> = gammas.iter().map(|g| gain * g).collect();
    // a spinner after 1 s (the work is bounded by limits::MULTI_HARMONIC_WORK)
    let mut levels = crate::cmd::simulate::with_spinner("multi-harmonic continuation", || {
        level_sweeps(model, &model_gammas, omegas, args.sweep, h)
    })?;
    // the reports give the levels as given
    for (l, &g) in levels.iter_mut().zip(gammas) {
        l.gamma = g;
    }
    for (i, l) in levels.iter().enumerate() {
        if let Some(w) = &l.sweep.warning {
            eprintln!(
                "nlsdof: warning: level {} (gamma = {}): continuation stopped early, partial curve up to {:.6} Hz: {w}",
                i + 1,
                l.gamma,
                l.sweep.points.last().map(|p| p.omega / std::f64::consts::TAU).unwrap_or(f64::NAN)
            );
        }
    }
    let model_name = args.model.display().to_string();
    let request = report::HarmonicSweepRequest {
        model_name: &model_name,
        direction: args.sweep,
        steps: args.steps,
        harmonics: h,
    };
    let mut text = if args.json {
        let mut v = report::sweep_json(&request, model, &levels);
        v["input_gain"] = serde_json::json!(gain);
        format!("{v}\n")
    } else if args.csv {
        report::sweep_csv(&request, &levels)
    } else {
        super::roots::with_gain_note(
            report::sweep_text(&request, model, &levels, f_min, f_max),
            gain,
        )
    };
    if let Some(path) = args.plot {
        let title = format!(
            "{} - harmonic balance, H = {h}, sweep {}",
            args.model
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
            sweep_name(args.sweep)
        );
        let format = nlsdof_report::figure_file::plot_format(path);
        let bytes = report::sweep_figure(&title, &levels, f_min, f_max, format)?;
        nlsdof_io::atomic::write_atomic(path, &bytes)?;
        if !args.json && !args.csv {
            let _ = writeln!(text, "\nplot written to {}", path.display());
        }
    }
    print!("{text}");
    Ok(())
}
