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

mod markdown;
mod progress;
mod report;
mod table;

use crate::error::CliError;
use nlsdof::demo::{Demo, DemoSettings};
use std::path::{Path, PathBuf};
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
    check_out_dir(&args.out, args.force)?;
    let settings = DemoSettings::new(
        args.seed,
        args.quick,
        starts,
        args.noise,
        args.integer_radius,
    );
    let staging = Staging::create(&args.out)?;
    let mut demo = Demo::new(settings);
    demo.run_all(&progress::Bars::default())?;
    let t_report = Instant::now();
    let summary = report::write_all(&demo, staging.path(), &args.out)?;
    demo.timings.push((
        "figures and report".into(),
        t_report.elapsed().as_secs_f64(),
    ));
    let total = t_all.elapsed().as_secs_f64();
    // the timings are the only part that differs between runs with one seed:
    // they go into their own file and the summary's "timings_s"
    let summary = report::finish(&demo, staging.path(), summary, total)?;
    staging.commit(&args.out, args.force)?;
    eprintln!(
        "nlsdof demo: report written to {} in {:.1} s",
        args.out.join("report.md").display(),
        total
    );
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary).expect("json serialises")
        );
    } else {
        print!("{}", report::text_summary(&demo, &args.out));
    }
    Ok(())
}

fn check_out_dir(out: &Path, force: bool) -> Result<(), CliError> {
    match std::fs::metadata(out) {
        Err(_) => Ok(()),
        Ok(m) if !m.is_dir() => Err(CliError::Usage(format!(
            "--out {}: exists and is not a directory",
            out.display()
        ))),
        Ok(_) => {
            let non_empty = std::fs::read_dir(out)
                .map_err(|e| CliError::Usage(format!("--out {}: {e}", out.display())))?
                .next()
                .is_some();
            if non_empty && !force {
                Err(CliError::Usage(format!(
                    "--out {}: directory exists and is not empty (use --force to replace it)",
                    out.display()
                )))
            } else {
                Ok(())
            }
        }
    }
}

/// The report folder under construction: a hidden sibling of the target,
/// removed on drop unless committed.
struct Staging {
    dir: Option<PathBuf>,
}

impl Staging {
    fn create(out: &Path) -> Result<Self, CliError> {
        let parent = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let name = out
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| {
                CliError::Usage(format!("--out {}: not a folder name", out.display()))
            })?;
        if !parent.is_dir() {
            return Err(CliError::Usage(format!(
                "--out {}: parent folder {} does not exist",
                out.display(),
                parent.display()
            )));
        }
        let dir = parent.join(format!(".{name}.{}.partial", std::process::id()));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).ok();
        }
        nlsdof_io::atomic::register_partial_dir(&dir);
        std::fs::create_dir_all(dir.join("tables"))
            .map_err(|e| CliError::Usage(format!("cannot create {}: {e}", dir.display())))?;
        Ok(Self { dir: Some(dir) })
    }

    fn path(&self) -> &Path {
        self.dir.as_deref().expect("present until commit")
    }

    /// Renames the finished folder to `out` (replacing an existing one).
    fn commit(mut self, out: &Path, force: bool) -> Result<(), CliError> {
        let dir = self.dir.take().expect("present until commit");
        let fail = |e: std::io::Error, dir: &Path| {
            std::fs::remove_dir_all(dir).ok();
            CliError::Usage(format!("cannot create {}: {e}", out.display()))
        };
        if out.exists() {
            // checked at start: empty, or --force
            check_out_dir(out, force).inspect_err(|_| {
                std::fs::remove_dir_all(&dir).ok();
            })?;
            let old = dir.with_extension("old");
            std::fs::rename(out, &old).map_err(|e| fail(e, &dir))?;
            if let Err(e) = std::fs::rename(&dir, out) {
                std::fs::rename(&old, out).ok();
                return Err(fail(e, &dir));
            }
            std::fs::remove_dir_all(&old).ok();
        } else {
            std::fs::rename(&dir, out).map_err(|e| fail(e, &dir))?;
        }
        // Renamed (or removed on failure above, where a Ctrl-C cleanup of
        // the vanished path is harmless).
        nlsdof_io::atomic::unregister_partial_dir(&dir);
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if let Some(d) = self.dir.take() {
            std::fs::remove_dir_all(&d).ok();
            nlsdof_io::atomic::unregister_partial_dir(&d);
        }
    }
}
