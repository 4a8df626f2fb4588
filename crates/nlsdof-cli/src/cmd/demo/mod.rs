//! `nlsdof demo`: the paper's whole workflow (Civera et al. 2021, §2–§4) end
//! to end on a virtual high-aspect-ratio wing simulated inside the binary,
//! written to a report folder (`report.md`, figures, tables, `summary.json`).
//!
//! Stages (each timed):
//! 1. **rig** — the true unloaded and sensor-loaded wings (Table 3 linear
//!    part, Table 7 pre-estimated nonlinear part) tested by the virtual
//!    stepped-sine rig ([`nlsdof::stepped_sine`]) at the five levels of
//!    Table 2 over 5.3–5.5 Hz, plus seeded measurement noise;
//! 2. **linear** — linear identification from a simulated low-level chirp
//!    (4.5–6 Hz, +0.005 Hz/s): Welch H1, fast relaxed vector fitting;
//! 3. **fits** — Eq 31 fits of the classic, Duffing-generalised and
//!    generalised models (integer and real exponents) with the linear part
//!    fixed from stage 2, plus the generalised model with everything free;
//! 4. **time** — full-length time simulation of the stepped-sine test, true
//!    model + noise ("measured") vs the fitted generalised integer model;
//! 5. **spectrograms** — STFT and Eq 33 (and its robust variant), Fig 8;
//! 6. **report** — figures and `report.md`.
//!
//! Nothing is written under the target name until everything succeeded:
//! the folder is built as a hidden sibling and renamed at the end.

mod progress;

use crate::error::CliError;
use nlsdof::demo::{Demo, DemoSettings};
use nlsdof_io::atomic::{check_out_dir, StagedDir};
use nlsdof_report::demo as report;
use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    about = "The paper's whole workflow on a built-in virtual HAR wing: test, identify, simulate, compare; writes a report folder",
    after_long_help = LONG_HELP
)]
pub struct Args {
    /// Report folder to create (must not exist, or be empty, unless --force).
    #[arg(long, value_name = "DIR", default_value = "nlsdof-demo")]
    pub out: PathBuf,
    /// Replace an existing non-empty report folder.
    #[arg(long)]
    pub force: bool,
    /// Seed of the measurement noise and of the global search (same seed, same tables).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print a JSON summary on stdout (the same as DIR/summary.json).
    #[arg(long)]
    pub json: bool,
    /// Smaller, faster run (for tests): 100 frequency steps, 8 starts, dwell of the
    /// time simulation a quarter of the rig's.
    #[arg(long)]
    pub quick: bool,
    /// Global-search starts of each real-exponent fit [default: 32, 8 with --quick].
    #[arg(long, value_name = "N")]
    pub starts: Option<usize>,
    /// Relative standard deviation of the rig's amplitude noise (0.005 = 0.5 %).
    #[arg(long, value_name = "SIGMA", default_value_t = 0.005)]
    pub noise: f64,
    /// Integer exponents searched: every integer within R of the rounded real optimum.
    #[arg(long = "integer-radius", value_name = "R", default_value_t = 1)]
    pub integer_radius: u32,
}

const LONG_HELP: &str = "WHAT IT DOES:
  Reproduces Civera et al. (2021) end to end on data generated inside the binary:
  1. the unloaded and sensor-loaded wing (Table 3 + Table 7) tested by the virtual
     stepped-sine rig at gamma = 0.41, 0.62, 0.81, 1.00, 1.23 m/s^2 zero-to-peak
     (Table 2: 0.82 .. 2.46 m/s^2 peak-to-peak), 5.3-5.5 Hz, 200 steps, sweep up,
     with seeded amplitude and phase noise;
  2. linear identification from a 300 s chirp 4.5 -> 6 Hz (+0.005 Hz/s) at
     0.25 m/s^2: Welch H1 + fast relaxed vector fitting, vs the truth;
  3. fits (Eq 31) of duffing-quadratic (classic), duffing-generalised and generalised,
     integer and real exponents, linear part fixed from step 2 (as the paper);
     comparison table (cost, RMS, AIC/BIC, parameters with 95 % intervals) and the
     phase-quadrature table (Table 8);
  4. full-length stepped-sine time simulation of the fitted model vs the measured
     (true model + noise) output; STFT spectrograms and Eq 33 (Fig 8);
  5. figures (SVG line plots, PNG spectrograms) and DIR/report.md.

OUTPUT:
  DIR/report.md, DIR/summary.json, DIR/tables/*.csv, DIR/fig*.svg, DIR/fig8*.png.
  The folder appears only when complete (built as a hidden sibling, then renamed).

UNITS: SI; input levels gamma in m/s^2 and amplitudes in m are zero-to-peak.

EXAMPLES:
  nlsdof demo
  nlsdof demo --out /tmp/wing --seed 7 --json > summary.json
  nlsdof demo --quick --force";

pub fn run(args: Args) -> Result<(), CliError> {
    let t_all = Instant::now();
    if !(args.noise.is_finite() && (0.0..=0.2).contains(&args.noise)) {
        return Err(CliError::Usage(format!(
            "--noise {} is not allowed: use a relative standard deviation in [0, 0.2]",
            args.noise
        )));
    }
    let starts = args.starts.unwrap_or(if args.quick { 8 } else { 32 });
    if starts == 0 || starts > 4096 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=4096"
        )));
    }
    if args.integer_radius > 4 {
        return Err(CliError::Usage(format!(
            "--integer-radius {} is not allowed: use 0..=4",
            args.integer_radius
        )));
    }
    // a link to a folder is kept (the folder behind it is replaced); a link
    // that does not resolve is refused here, before any work
    let out = nlsdof_io::atomic::resolve_out_dir(&args.out)?;
    check_out_dir(&out, args.force)?;
    let settings = DemoSettings::new(
        args.seed,
        args.quick,
        starts,
        args.noise,
        args.integer_radius,
    );
    let staging = StagedDir::create(&out)?;
    let mut demo = Demo::new(settings);
    let bars = progress::Bars::default();
    demo.run_all(&bars)?;
    let t_report = Instant::now();
    let pb = progress::stage_bar(report::WRITE_STEPS, "6/6 report");
    pb.set_message("figures (SVG, PNG) and tables");
    let summary = report::write_all(&demo, staging.path(), &|| pb.inc(1))?;
    pb.finish_and_clear();
    demo.timings.push((
        "figures and report".into(),
        t_report.elapsed().as_secs_f64(),
    ));
    let total = t_all.elapsed().as_secs_f64();
    // the timings are the only part that differs between runs with one seed:
    // they go into their own file and the summary's "timings_s"
    let summary = report::finish(&demo, staging.path(), summary, total)?;
    // Standard output first, then the folder: if stdout fails (a full disk,
    // a closed pipe) the staged folder is removed and nothing is left.
    let text = if args.json {
        format!(
            "{}\n",
            serde_json::to_string_pretty(&summary).expect("json serialises")
        )
    } else {
        report::text_summary(&demo, &args.out)
    };
    {
        let mut so = std::io::stdout().lock();
        if let Err(e) = so.write_all(text.as_bytes()).and_then(|()| so.flush()) {
            // the one policy of every verb (exit 141 on a closed pipe, else
            // one line and exit 2); its cleanup removes the staged folder
            drop(staging);
            crate::stdout_failed(&e);
        }
    }
    staging.commit(&out, args.force)?;
    bars.print_stages();
    eprintln!(
        "nlsdof demo: report written to {} in {:.1} s",
        args.out.join("report.md").display(),
        total
    );
    Ok(())
}
