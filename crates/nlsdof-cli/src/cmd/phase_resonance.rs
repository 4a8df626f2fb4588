//! `nlsdof fit --phase-resonance` and `nlsdof compare --phase-resonance`:
//! fit the power-law models to phase-resonance points (`gamma,f_hz,amplitude`
//! at 90° phase per level; `nlsdof::identification::phase_resonance`), and
//! the `--sign` choice (hardening / softening / auto) shared with sweep fits.

use super::fit::{apply_bounds, apply_fix_free, parse_model_kind, resolve_mass, DataArgs};
use super::sign::{fit_pr_signed, SignArg};
use crate::error::CliError;
use nlsdof::identification::models::GAIN;
use nlsdof::identification::phase_resonance::{default_spec, PrDataset, PrFitOptions};
use nlsdof::identification::search::best_integer_fit_phase_resonance;
use nlsdof::identification::{FitSpec, ModelKind, Sign, Status, N_PARAMS, PARAM_NAMES};
use nlsdof_io::phase_resonance_data::read_csv;
use nlsdof_io::stepped_sine_data::{AmplitudeKind, ReadOptions};
use nlsdof_report::fit::{
    integer_pairs_json, integer_pairs_text, pr_json, pr_table_text, pr_text, sign_trials_json,
    sign_trials_text,
};
use serde_json::{json, Value};
use std::fmt::Write as _;

impl DataArgs {
    /// Reads DATA as phase-resonance points (`--phase-resonance`).
    pub fn load_phase_resonance(&self) -> Result<PrDataset, CliError> {
        if self.beam_dir.is_some() {
            return Err(CliError::Usage(
                "--phase-resonance reads a CSV file of gamma,f_hz,amplitude points, not --beam-dir"
                    .into(),
            ));
        }
        let path = self
            .data
            .as_ref()
            .ok_or_else(|| CliError::Usage("--phase-resonance needs a DATA file".into()))?;
        let opts = ReadOptions {
            amplitude: if self.velocity {
                AmplitudeKind::Velocity
            } else if self.acceleration {
                AmplitudeKind::Acceleration
            } else {
                AmplitudeKind::Displacement
            },
            gamma_in_g: self.gamma_in_g,
            peak_to_peak: self.peak_to_peak,
        };
        read_csv(path, &opts).map_err(|e| CliError::Usage(e.to_string()))
    }
}

/// Checks `--frequency-weight`.
pub fn check_frequency_weight(w: f64) -> Result<(), CliError> {
    if !(w.is_finite() && w > 0.0) {
        return Err(CliError::Usage(format!(
            "--frequency-weight {w} is not allowed: it must be finite and > 0"
        )));
    }
    Ok(())
}

/// `nlsdof fit DATA --phase-resonance ...`.
/// `nlsdof fit --phase-resonance`.
pub fn run_fit_verb(args: &super::fit::Args) -> Result<(), CliError> {
    let sign = args.pr.sign.resolve(args.pr.softening)?;
    sweep_only_refused(args)?;
    run_fit(args, sign)
}

/// The `fit` options that act on sweep data only, refused in one line with
/// `--phase-resonance` (issue 30: `--landscape` and `--profile` were
/// accepted and did nothing). Options with a default value (`--grid`,
/// `--refine`, `--phase-weight`) cannot be told apart from their default
/// here and are documented as sweep options in `fit --help`.
fn sweep_only_refused(args: &super::fit::Args) -> Result<(), CliError> {
    let given: Vec<&str> = [
        (args.landscape.is_some(), "--landscape"),
        (args.profile, "--profile"),
        (args.jump_weight.is_some(), "--jump-weight"),
        (args.jump_reading.is_some(), "--jump-reading"),
        (args.plot.is_some(), "--plot"),
        (args.no_phase, "--no-phase"),
        (args.phase_convention.is_some(), "--phase-convention"),
        (args.weighting.is_some(), "--weighting"),
    ]
    .into_iter()
    .filter_map(|(set, name)| set.then_some(name))
    .collect();
    if given.is_empty() {
        return Ok(());
    }
    Err(CliError::Usage(format!(
        "{} appl{} to sweep data, not to --phase-resonance points (one row per level: the \
         frequency and amplitude where the phase lag is 90 deg)",
        given.join(", "),
        if given.len() == 1 { "ies" } else { "y" }
    )))
}

pub fn run_fit(args: &super::fit::Args, sign: SignArg) -> Result<(), CliError> {
    if args.integer && sign == SignArg::Auto {
        return Err(CliError::Usage(
            "--sign auto is not available with --integer: choose --sign hardening or softening"
                .into(),
        ));
    }
    check_frequency_weight(args.pr.frequency_weight)?;
    let starts = args.starts.unwrap_or(32);
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    let data = args.data.load_phase_resonance()?;
    let kind = parse_model_kind(&args.model)?;
    // resolve the mass before fitting (and check --fix once)
    let mut probe = default_spec(kind, &data, Sign::Hardening);
    let fix_mass = apply_fix_free(&mut probe, args.fix.as_deref(), args.free.as_deref())?;
    let mass = resolve_mass(args.mass, fix_mass, args.model_file.as_deref())?;
    let configure = |spec: &mut FitSpec| -> Result<(), CliError> {
        if let Some(b) = &args.bounds {
            apply_bounds(spec, b)?;
        }
        apply_fix_free(spec, args.fix.as_deref(), args.free.as_deref())?;
        Ok(())
    };
    let opts = PrFitOptions {
        starts,
        seed: args.seed,
        frequency_weight: args.pr.frequency_weight,
        ..PrFitOptions::default()
    };
    let mut integer_table = Vec::new();
    let (res, trials) = if args.integer {
        let mut spec = default_spec(
            kind,
            &data,
            if sign == SignArg::Softening {
                Sign::Softening
            } else {
                Sign::Hardening
            },
        );
        configure(&mut spec)?;
        let (best, pairs) = best_integer_fit_phase_resonance(&data, &spec, &opts)
            .map_err(|e| CliError::Usage(format!("--integer: {e}")))?;
        integer_table = pairs;
        (best, Vec::new())
    } else {
        fit_pr_signed(&data, kind, sign, &configure, &opts)?
    };
    if let Some(out) = &args.out {
        let m = mass.unwrap_or(1.0);
        let model = res.model().to_physical(m)?;
        let mut text = format!(
            "# fitted by `nlsdof fit --phase-resonance`, model {}, cost {:.6e}\n# forcing gain = {} (the structure sees gain * gamma; not part of this file)\n",
            res.kind, res.cost, res.theta[GAIN]
        );
        if mass.is_none() {
            text.push_str("# no mass given: m = 1 kg, all values are per unit mass\n");
        }
        text.push_str(&nlsdof_io::model_file::model_to_toml(&model));
        nlsdof_io::atomic::write_atomic(out, text.as_bytes())?;
    }
    if args.json {
        let mut v = pr_json(&res, mass, args.pr.frequency_weight);
        if let Some(t) = sign_trials_json(&trials) {
            v["sign_auto"] = t;
        }
        if args.integer {
            v["integer_pairs"] = integer_pairs_json(&integer_table);
        }
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
    } else {
        let mut s = sign_trials_text(&trials, res.stiffness_sign);
        s.push_str(&pr_text(&res, mass, args.pr.frequency_weight));
        if args.integer {
            s.push_str(&integer_pairs_text(&integer_table));
        }
        print!("{s}");
    }
    Ok(())
}

/// `nlsdof compare DATA --phase-resonance ...` from the parsed arguments.
pub fn run_compare_args(args: &super::compare::Args) -> Result<(), CliError> {
    let sign = args.pr.sign.resolve(args.pr.softening)?;
    let kinds = args
        .models
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(parse_model_kind)
        .collect::<Result<Vec<_>, _>>()?;
    if kinds.is_empty() {
        return Err(CliError::Usage("--models is empty".into()));
    }
    let starts = args.starts.unwrap_or(32);
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    let mass = resolve_mass(args.mass, None, None)?;
    let opts = PrFitOptions {
        starts,
        seed: args.seed,
        frequency_weight: args.pr.frequency_weight,
        ..PrFitOptions::default()
    };
    run_compare(
        &args.data,
        &kinds,
        args.free.as_deref(),
        sign,
        &opts,
        mass,
        args.json,
    )
}

/// `nlsdof compare DATA --phase-resonance ...`: one fit per model.
pub fn run_compare(
    data_args: &DataArgs,
    kinds: &[ModelKind],
    free: Option<&str>,
    sign: SignArg,
    opts: &PrFitOptions,
    mass: Option<f64>,
    as_json: bool,
) -> Result<(), CliError> {
    check_frequency_weight(opts.frequency_weight)?;
    let data = data_args.load_phase_resonance()?;
    let mut results = Vec::new();
    for &kind in kinds {
        let configure = |spec: &mut FitSpec| -> Result<(), CliError> {
            if let Some(list) = free {
                for name in list.split(',').filter(|s| !s.trim().is_empty()) {
                    match spec.free(name) {
                        Ok(()) | Err(nlsdof::identification::SpecError::NotInModel { .. }) => {}
                        Err(e) => return Err(CliError::Usage(format!("--free: {e}"))),
                    }
                }
            }
            Ok(())
        };
        let (r, _) = fit_pr_signed(&data, kind, sign, &configure, opts)
            .map_err(|e| CliError::Usage(format!("{kind}: {e}")))?;
        results.push(r);
    }
    if as_json {
        let v: Vec<Value> = results
            .iter()
            .map(|r| pr_json(r, mass, opts.frequency_weight))
            .collect();
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({"models": v})).expect("json")
        );
        return Ok(());
    }
    let mut s = String::new();
    writeln!(
        s,
        "{:<22} {:>4} {:>14} {:>12} {:>12} {:>12}  parameters (mass-normalised)",
        "model", "p", "cost", "RMS", "AIC", "BIC"
    )
    .ok();
    for r in &results {
        let params: Vec<String> = (0..N_PARAMS)
            .filter(|&j| r.status[j] != Status::Absent)
            .map(|j| {
                format!(
                    "{}={:.5e}{}",
                    PARAM_NAMES[j],
                    r.theta[j],
                    if r.status[j] == Status::Free { "" } else { "*" }
                )
            })
            .collect();
        writeln!(
            s,
            "{:<22} {:>4} {:>14.6e} {:>12.4e} {:>12.2} {:>12.2}  {}",
            r.kind.name(),
            r.n_free,
            r.cost,
            r.rms(),
            r.aic(),
            r.bic(),
            params.join(" ")
        )
        .ok();
    }
    s.push_str("(* = held fixed; phase-resonance points, 2 residuals per level)\n");
    for r in &results {
        s.push_str(&pr_table_text(r));
    }
    print!("{s}");
    Ok(())
}
