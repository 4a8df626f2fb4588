//! `nlsdof compare`: fit several models to one data set and tabulate cost,
//! RMS, AIC/BIC and parameters (paper Tables 5–7) and the phase-quadrature
//! comparison (Table 8).

use super::fit::{parse_model_kind, DataArgs};
use crate::error::CliError;
use nlsdof::identification::{Identification, Status, N_PARAMS, PARAM_NAMES};
use nlsdof_report::fit::pq_text;
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
    /// Extra global-search starts per refined candidate (1 = none).
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
    use super::sign::SignArg;
    use nlsdof::identification::compare::{compare_plans, CompareError, CompareOptions};
    use nlsdof::identification::SignChoice;
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
    let starts = args.starts.unwrap_or(1);
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    let mass = super::fit::resolve_mass(args.mass, None, None)?;
    // every model through the one pipeline (identify), as `fit`; the plans
    // are the library's, shared with Python's `compare`
    let opts = CompareOptions {
        free: args
            .free
            .as_deref()
            .map(|l| l.split(',').map(str::to_string).collect())
            .unwrap_or_default(),
        starts,
        seed: args.seed,
        sign: match sign {
            SignArg::Data => SignChoice::Auto,
            SignArg::Auto => SignChoice::Both,
            SignArg::Hardening => SignChoice::Hardening,
            SignArg::Softening => SignChoice::Softening,
        },
    };
    let plans = compare_plans(&data, &kinds, &opts).map_err(|e| match e {
        CompareError::Free(e) => CliError::Usage(format!("--free: {e}")),
        e => CliError::Usage(e.to_string()),
    })?;
    let mut results: Vec<Identification> = Vec::new();
    let n_plans = plans.len();
    for (i, plan) in plans.into_iter().enumerate() {
        let kind = plan.kind;
        // one bar per model, named with its place in the list
        let what = format!("model {}/{n_plans} {}", i + 1, kind.name());
        let (pb, on_progress) = super::progress::stage_bar(&what);
        let id = nlsdof::identification::identify(&data, &plan, &on_progress);
        pb.finish_and_clear();
        results.push(id.map_err(|e| CliError::Usage(format!("{kind}: {e}")))?);
    }
    if args.json {
        let v: Vec<_> = results
            .iter()
            .map(|id| nlsdof_report::fit::identification_document(id, mass))
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
        "{:<22} {:>4} {:>14} {:>12} {:>12} {:>12}  {:<15} parameters (mass-normalised)",
        "model", "p", "cost", "RMS a/gamma", "AIC", "BIC", "status"
    )
    .ok();
    for id in &results {
        let r = &id.fit;
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
            "{:<22} {:>4} {:>14.6e} {:>12.4e} {:>12.2} {:>12.2}  {:<15} {}",
            r.kind.name(),
            r.n_free,
            r.cost,
            r.rms_normalised(),
            r.aic(),
            r.bic(),
            status(id),
            params.join(" ")
        )
        .ok();
    }
    s.push_str("(* = held fixed; status as the fit's first line says)\n");
    for id in &results {
        if let Some(w) = id.warning() {
            writeln!(s, "{}: {w}", id.fit.kind).ok();
        }
        for n in id.fit.notes() {
            writeln!(s, "{}: note: {n}", id.fit.kind).ok();
        }
    }
    for id in &results {
        s.push_str(&pq_text(&id.data, &id.fit)?);
    }
    print!("{s}");
    Ok(())
}

/// The status column: the same judgement as the fit's first line.
fn status(id: &Identification) -> &'static str {
    let r = &id.fit;
    if !r.converged {
        "NOT CONVERGED"
    } else if !id.adequacy.adequate {
        "DOES NOT FIT"
    } else if !r.at_bounds.is_empty() {
        "AT BOUNDS"
    } else if !r.unidentifiable.is_empty() {
        "UNIDENTIFIABLE"
    } else if !r.ridges.is_empty() {
        "RIDGE"
    } else if !r.crossings.is_empty() {
        "INTERVAL CROSSES"
    } else {
        "ok"
    }
}
