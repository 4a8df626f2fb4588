//! `nlsdof compare`: fit several models to one data set and tabulate cost,
//! RMS, AIC/BIC and parameters (paper Tables 5–7) and the phase-quadrature
//! comparison (Table 8).

use super::fit::{parse_model_kind, DataArgs};
use crate::error::CliError;
use nlsdof::identification::{FitOptions, FitSpec, Status, N_PARAMS, PARAM_NAMES};
use nlsdof_report::fit::{pq_text, result_json};
use serde_json::json;
use std::fmt::Write as _;

#[derive(clap::Args)]
#[command(
    about = "Fit several models to one data set: cost, RMS, AIC/BIC, parameters and phase-quadrature tables"
)]
pub struct Args {
    #[command(flatten)]
    pub data: DataArgs,
    /// Models to compare, comma-separated.
    #[arg(
        long,
        default_value = "linear,duffing,duffing-quadratic,duffing-generalised,generalised"
    )]
    pub models: String,
    /// Estimate parameters the models hold (e.g. gain): name,..
    #[arg(long, value_name = "NAME,..")]
    pub free: Option<String>,
    /// Extra global-search starts per refined candidate (1 = none; with --sign
    /// hardening|softening|auto: starts of the classic multistart, 32 if not given).
    #[arg(long)]
    pub starts: Option<usize>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Mass m, kg (physical values in the JSON).
    #[arg(long, value_name = "M")]
    pub mass: Option<f64>,
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub pr: super::sign::PrArgs,
}

pub fn run(args: Args) -> Result<(), CliError> {
    // (`compare --phase-resonance` is dispatched to `phase_resonance::run_compare_args`)
    let sign = args.pr.sign.resolve(args.pr.softening)?;
    let data = args.data.load()?;
    let kinds = args
        .models
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(parse_model_kind)
        .collect::<Result<Vec<_>, _>>()?;
    if kinds.is_empty() {
        return Err(CliError::Usage("--models is empty".into()));
    }
    let staged = sign == super::sign::SignArg::Data;
    let starts = args.starts.unwrap_or(if staged { 1 } else { 32 });
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    let mass = super::fit::resolve_mass(args.mass, None, None)?;
    let opts = FitOptions {
        starts,
        seed: args.seed,
        ..FitOptions::default()
    };
    // (data as fitted, result) per model
    let mut results: Vec<(
        nlsdof::identification::Dataset,
        nlsdof::identification::FitResult,
    )> = Vec::new();
    for kind in kinds {
        if staged {
            // the default staged fit (equation error, landscape, output error)
            let mut plan = nlsdof::identification::FitPlan::new(kind);
            plan.starts = starts;
            plan.seed = args.seed;
            if let Some(list) = &args.free {
                for name in list.split(',').filter(|s| !s.trim().is_empty()) {
                    let n = name.trim().to_ascii_lowercase();
                    if n == "gain" {
                        plan.gain = nlsdof::identification::GainChoice::Free;
                        continue;
                    }
                    // a parameter a model does not have is simply not freed for it
                    let mut probe = FitSpec::new(kind, &data);
                    match probe.free(&n) {
                        Ok(()) => plan.free.push(n),
                        Err(nlsdof::identification::SpecError::NotInModel { .. }) => {}
                        Err(e) => return Err(CliError::Usage(format!("--free: {e}"))),
                    }
                }
            }
            let id = nlsdof::identification::identify(&data, &plan, &|_| {})
                .map_err(|e| CliError::Usage(format!("{kind}: {e}")))?;
            results.push((id.data, id.fit));
            continue;
        }
        let configure = |spec: &mut FitSpec| -> Result<(), CliError> {
            if let Some(list) = &args.free {
                for name in list.split(',').filter(|s| !s.trim().is_empty()) {
                    // a parameter a model does not have is simply not freed for it
                    match spec.free(name) {
                        Ok(()) | Err(nlsdof::identification::SpecError::NotInModel { .. }) => {}
                        Err(e) => return Err(CliError::Usage(format!("--free: {e}"))),
                    }
                }
            }
            Ok(())
        };
        let (r, _) = super::sign::fit_sweep_signed(&data, kind, sign, &configure, &opts)
            .map_err(|e| CliError::Usage(format!("{kind}: {e}")))?;
        results.push((data.clone(), r));
    }
    if args.json {
        let v: Vec<_> = results
            .iter()
            .map(|(d, r)| result_json(d, r, mass))
            .collect::<Result<_, _>>()?;
        println!(
            "{}",
            serde_json::to_string_pretty(&json!({"models": v})).expect("json")
        );
        return Ok(());
    }
    let mut s = String::new();
    writeln!(
        s,
        "{:<22} {:>4} {:>14} {:>12} {:>12} {:>12}  {:<14} parameters (mass-normalised)",
        "model", "p", "cost", "RMS a/gamma", "AIC", "BIC", "status"
    )
    .ok();
    for (_, r) in &results {
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
        let status = if !r.converged {
            "NOT CONVERGED"
        } else if !r.at_bounds.is_empty() {
            "AT BOUNDS"
        } else if !r.unidentifiable.is_empty() {
            "UNIDENTIFIABLE"
        } else {
            "ok"
        };
        writeln!(
            s,
            "{:<22} {:>4} {:>14.6e} {:>12.4e} {:>12.2} {:>12.2}  {:<14} {}",
            r.kind.name(),
            r.n_free,
            r.cost,
            r.rms_normalised(),
            r.aic(),
            r.bic(),
            status,
            params.join(" ")
        )
        .ok();
    }
    s.push_str("(* = held fixed)\n");
    for (_, r) in &results {
        if let Some(w) = r.warning() {
            writeln!(s, "{w}").ok();
        }
    }
    for (d, r) in &results {
        s.push_str(&pq_text(d, r)?);
    }
    print!("{s}");
    Ok(())
}
