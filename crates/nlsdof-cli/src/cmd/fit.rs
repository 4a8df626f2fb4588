//! `nlsdof fit`: identify a power-law model from stepped-sine amplitude
//! curves at several input levels (paper §4, Eq 31). Also home of the
//! helpers shared with `nlsdof compare` (data loading, options, reports).

use crate::error::CliError;
use nlsdof::identification::inspect::{inspect, InspectOptions, Inspection, LawFit};
use nlsdof::identification::models::{ETA, RHO};
use nlsdof::identification::profile::{
    default_step, output_error_profile_with, OutputErrorProfile,
};
use nlsdof::identification::Status;
use nlsdof::identification::{
    identify, Dataset, FitPlan, FitSpec, GainChoice, JumpChoice, ModelKind, PhaseChoice,
    PhaseConvention, ReadingChoice, SignChoice, Weighting,
};
use nlsdof::identification::{Identification, Parameter};
use nlsdof::SweepDirection;
use nlsdof_io::stepped_sine_data::{read_beam_dir, read_csv, AmplitudeKind, ReadOptions, Runs};
use std::path::{Path, PathBuf};

use nlsdof_report::fit::model_file_text;

/// `--weighting` (see [`Weighting`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WeightingArg {
    Absolute,
    Relative,
}

/// `--runs` values for `--beam-dir`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RunsArg {
    Up,
    Down,
    Both,
}

/// Data options shared by `fit` and `compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct DataArgs {
    /// Long-format CSV: level,gamma,f_hz,amplitude[,phase_deg][,sweep][,weight]; or a
    /// universal file (.uff/.unv): one complex FRF dataset 58 per level and sweep, response
    /// (m, m/s or m/s^2) per input acceleration (m/s^2), abscissa in Hz (see the README).
    #[arg(value_name = "DATA", required_unless_present = "beam_dir")]
    pub data: Option<PathBuf>,
    /// Levels gamma, m/s^2 zero-to-peak, of the FRF datasets of a universal-file DATA, one per
    /// complex FRF dataset in file order (overrides the header's gamma=VALUE token or
    /// acceleration z-axis value; needed when the file states no level).
    #[arg(
        long = "level-gamma",
        value_name = "G1,G2,..",
        allow_hyphen_values = true
    )]
    pub level_gamma: Option<String>,
    /// Read a directory of frf_<A>g.txt files (tab-separated, decimal comma,
    /// velocity amplitudes of up and down runs side by side) instead of DATA.
    #[arg(long = "beam-dir", value_name = "DIR", conflicts_with = "data")]
    pub beam_dir: Option<PathBuf>,
    /// Runs of --beam-dir files to use.
    #[arg(long, value_enum, default_value = "up")]
    pub runs: RunsArg,
    /// The amplitude column is a velocity amplitude (m/s), converted by Omega.
    #[arg(long, conflicts_with = "acceleration")]
    pub velocity: bool,
    /// The amplitude column is an acceleration amplitude (m/s^2), converted by Omega^2.
    #[arg(long)]
    pub acceleration: bool,
    /// The gamma column is in g (9.80665 m/s^2).
    #[arg(long = "gamma-in-g")]
    pub gamma_in_g: bool,
    /// Both gamma and amplitude columns are peak-to-peak (halved on reading).
    #[arg(long = "peak-to-peak")]
    pub peak_to_peak: bool,
}

impl DataArgs {
    /// The data as the user named them (a file, or `DIR (beam directory, runs R)`).
    pub fn source_name(&self) -> String {
        match (&self.beam_dir, &self.data) {
            (Some(dir), _) => nlsdof_io::stepped_sine_data::beam_source_name(dir, self.runs()),
            (None, Some(p)) => p.display().to_string(),
            (None, None) => String::new(),
        }
    }

    fn runs(&self) -> Runs {
        match self.runs {
            RunsArg::Up => Runs::Up,
            RunsArg::Down => Runs::Down,
            RunsArg::Both => Runs::Both,
        }
    }

    pub fn load(&self) -> Result<Dataset, CliError> {
        let err = |e: nlsdof_io::stepped_sine_data::SteppedSineDataError| {
            use nlsdof_io::stepped_sine_data::SteppedSineDataError as E;
            // one point per level looks like phase-resonance data
            let hint = match &e {
                E::MissingColumn {
                    column: "level", ..
                }
                | E::Data {
                    source: nlsdof::identification::DataError::TooFewFrequencies { count: 1, .. },
                    ..
                } => " (phase-resonance points, one row per level? add --phase-resonance)",
                _ => "",
            };
            CliError::Usage(format!("{e}{hint}"))
        };
        if let Some(dir) = &self.beam_dir {
            if self.level_gamma.is_some() {
                return Err(CliError::Usage(
                    "--level-gamma gives the levels of a universal file (.uff/.unv); --beam-dir takes them from the file names".into(),
                ));
            }
            return read_beam_dir(dir, self.runs()).map_err(err);
        }
        let path = self
            .data
            .as_ref()
            .expect("clap requires DATA or --beam-dir");
        if nlsdof_io::input::is_uff_file(path) {
            return self.load_uff(path).map_err(err);
        }
        if self.level_gamma.is_some() {
            return Err(CliError::Usage(format!(
                "--level-gamma gives the levels of a universal file (.uff/.unv); {} is read as CSV (put the levels in its gamma column)",
                path.display()
            )));
        }
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
        read_csv(path, &opts).map_err(err)
    }

    /// A universal file of stepped-sine FRFs: the quantities come from its
    /// header, so the CSV unit flags do not apply.
    fn load_uff(
        &self,
        path: &Path,
    ) -> Result<Dataset, nlsdof_io::stepped_sine_data::SteppedSineDataError> {
        let uff = |message: String| nlsdof_io::stepped_sine_data::SteppedSineDataError::Uff {
            path: path.into(),
            message,
        };
        for (set, flag) in [
            (self.velocity, "--velocity"),
            (self.acceleration, "--acceleration"),
            (self.gamma_in_g, "--gamma-in-g"),
            (self.peak_to_peak, "--peak-to-peak"),
        ] {
            if set {
                return Err(uff(format!(
                    "{flag} applies to CSV data; a universal file states its quantities in its header"
                )));
            }
        }
        let gammas = match &self.level_gamma {
            None => None,
            Some(text) => Some(
                text.split(',')
                    .map(|item| {
                        let item = item.trim();
                        item.parse::<f64>()
                            .ok()
                            .filter(|g| g.is_finite() && *g > 0.0)
                            .ok_or_else(|| {
                                uff(format!(
                                    "--level-gamma: '{item}' is not a level: give input levels (m/s^2, zero-to-peak) as a comma-separated list of finite numbers > 0"
                                ))
                            })
                    })
                    .collect::<Result<Vec<f64>, _>>()?,
            ),
        };
        nlsdof_io::stepped_sine_data::read_uff(path, gammas.as_deref())
    }
}

#[derive(clap::Args)]
#[command(
    about = "Fit a power-law model to stepped-sine amplitude curves at several input levels (Eq 31)",
    after_long_help = fit_long_help()
)]
pub struct Args {
    #[command(flatten)]
    pub data: DataArgs,
    /// Model: linear, duffing, quadratic, duffing-quadratic (classic),
    /// duffing-generalised, generalised, generalised-damping, generalised-stiffness, coulomb.
    #[arg(long, default_value = "generalised")]
    pub model: String,
    /// Hold parameters: name=value,.. (alpha, delta, beta, rho, kappa, eta, gain; m or mass sets the mass for conversion).
    /// kappa=0 is the model without nonlinear damping (as --model generalised-stiffness; eta then means nothing).
    /// rho=0 or eta=0 with its coefficient free is refused: x|x|^0 = x, so the term would copy the linear one.
    #[arg(long, value_name = "NAME=VALUE,..", allow_hyphen_values = true)]
    pub fix: Option<String>,
    /// Estimate parameters the model holds (e.g. gain, or an exponent): name,..
    #[arg(long, value_name = "NAME,..")]
    pub free: Option<String>,
    /// Exponents restricted to integers: the landscape's integer nodes only; the best
    /// --refine of them (and the best of each third of each exponent's range) are fitted
    /// with the exponents held, and the table of every integer pair's equation-error cost
    /// (and objective where fitted) is reported.
    #[arg(long)]
    pub integer: bool,
    /// Extra global-search starts (Latin hypercube) per refined landscape candidate
    /// (default 1 = none: the local fit from the equation-error start).
    #[arg(long)]
    pub starts: Option<usize>,
    /// Do not use the phase columns (default: used when every curve has phases, with
    /// the phase convention detected from the data).
    #[arg(long = "no-phase")]
    pub no_phase: bool,
    /// State the phase convention instead of detecting it: lag|lead,OFFSET_DEG[,DELAY_S]
    /// (measured phase = +-lag + offset + 2 pi f delay).
    #[arg(
        long = "phase-convention",
        value_name = "lag|lead,OFFSET_DEG[,DELAY_S]",
        allow_hyphen_values = true
    )]
    pub phase_convention: Option<String>,
    /// Weight of the phase residuals relative to the amplitude residuals.
    #[arg(long = "phase-weight", value_name = "W", default_value_t = 1.0)]
    pub phase_weight: f64,
    /// Amplitude residuals of the output-error fit. absolute (default): the paper's
    /// Eq 31, (a_model - a)/gamma, for noise of one size along a level; relative:
    /// (a_model - a)/a, the maximum-likelihood choice when the noise is a fixed fraction
    /// of the amplitude (amplitudes below 1 % of their curve's peak counted as 1 %).
    /// Relative weights trade the resonance peaks for the low-amplitude points when the
    /// model cannot follow the data everywhere (the clamped beams: peaks 50-80 % low).
    /// The reported cost is that of the weighting used.
    #[arg(long, value_enum, value_name = "absolute|relative")]
    pub weighting: Option<WeightingArg>,
    /// Write the exponent landscape: FILE.json (grid), FILE.svg or FILE.png (heat map).
    #[arg(long, value_name = "FILE")]
    pub landscape: Option<PathBuf>,
    /// Also compute output-error profile-likelihood 95 % intervals of the free
    /// exponents (rho, eta): refits with the exponent held, walked out from
    /// the optimum until (P - P*)/sigma^2 crosses chi2_1(0.95) = 3.84.
    /// Costs a few to a few tens of local fits (a progress bar each). They
    /// replace the Wald interval of the exponents in the table; a profile
    /// that leaves out its own estimate (the fit did not reach the minimum
    /// of its objective) is refused, with the reason.
    #[arg(long)]
    pub profile: bool,
    /// Intervals shown: one (default: one 95 % interval per parameter, named by
    /// its method: the output-error profile where --profile computed it, else
    /// Wald, the linearised one) or all (also every other interval computed:
    /// Wald, output-error profile, equation-error profile of the landscape,
    /// each labelled with what it leaves out). The JSON always has them all,
    /// and parameters[].interval the one shown.
    #[arg(long, value_enum, default_value = "one", value_name = "one|all")]
    pub intervals: IntervalsArg,
    /// Landscape grid: N (N x N) or NxM (rho nodes x eta nodes), each 1..=512.
    #[arg(long, value_name = "N[xM]", default_value = "41")]
    pub grid: String,
    /// Landscape minima refined by output error (Eq 31).
    #[arg(long, value_name = "K", default_value_t = 3)]
    pub refine: usize,
    /// Seed of the Latin-hypercube starts.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Weight W >= 0 of the jump penalties (default 1: a model fold one measured step on
    /// the wrong side of a point costs as much as the point's own amplitude; 0 = none, each
    /// point against the nearest stable model state). See JUMPS below.
    #[arg(long = "jump-weight", value_name = "W")]
    pub jump_weight: Option<f64>,
    /// How measured jumps are read: auto (default: exact, except curves whose sweep
    /// demonstrably left its branch before the model's fold), exact (every jump at the
    /// model's fold, within a step), censored (every jump only bounds the fold: a sweep may
    /// leave its branch early, never late). See JUMPS below.
    #[arg(long = "jump-reading", value_enum, value_name = "auto|exact|censored")]
    pub jump_reading: Option<ReadingArg>,
    /// TOML file of bounds: name = [min, max] (for beta/kappa: of beta_ref/kappa_ref, see --help).
    #[arg(long, value_name = "FILE")]
    pub bounds: Option<PathBuf>,
    /// Mass m, kg, for physical units and --out.
    #[arg(long, value_name = "M")]
    pub mass: Option<f64>,
    /// Take the mass from this model file.
    #[arg(long = "model-file", value_name = "FILE")]
    pub model_file: Option<PathBuf>,
    /// Write the fitted model (TOML model format, with the forcing gain as [signal]
    /// input_gain and a [provenance] table): `frf --model` reproduces the fit's curves.
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Write every measured point with the model's amplitude and phase there (CSV:
    /// level,gamma,f_hz,amplitude,sweep,model_amplitude,model_phase_deg[,phase_deg]; SI,
    /// zero-to-peak; the fit's own model curves, Eq 31).
    #[arg(long, value_name = "CURVES.csv")]
    pub predict: Option<PathBuf>,
    /// Write a figure (SVG or PNG, from the file name) of the data (markers) and the fitted
    /// model's sweeps (lines) per level; up-sweeps solid, down-sweeps dashed.
    #[arg(long, value_name = "FIG.svg|FIG.png")]
    pub plot: Option<PathBuf>,
    /// JSON output.
    #[arg(long)]
    pub json: bool,
    /// Run `nlsdof inspect` on the data first (model-free backbone and damping laws, tens of
    /// ms) and start the fit also from its exponents: the landscape node nearest to inspect's
    /// rho and eta joins the race beside the landscape's own candidates. Inspect's estimates
    /// and 95 % intervals are printed beside the fit's (JSON: "from_inspect").
    #[arg(long = "from-inspect")]
    pub from_inspect: bool,
    #[command(flatten)]
    pub pr: super::sign::PrArgs,
}

fn fit_long_help() -> String {
    "DEFAULT FIT (stages, one library call: identification::identify): branch-free equation error \
-> exponent landscape over (rho, eta) -> gain screen -> the best --refine landscape candidates race \
(output error, at most 30 iterations each; those stopped near the lead continue) -> the gain and \
the terms that do not matter decided by the objective's noise-scaled drop -> the winner refined on \
all points (data of at most 50,000 points; a 1500-point subsample before) -> SELF-CHECK: each \
curve's residual against its noise, estimated from the data; a fit well above it, or any fit of a \
single forcing level, escalates (more candidates, both signs, folds moved, a multistart of 16, each \
exponent held across its range; a fit within its noise whose fold ends pinned at a measured step \
holds each exponent half a unit either side) and, if it still does not fit, says so on \
the first line (\"the model does not fit levels ...: residual N x the noise\"; with phases also \
\"(amplitudes A x, phases P x)\", each against its own noise) and in JSON under \
\"adequacy\". A fit whose measured sweep leaves the model's branch a step or more before the model's \
fold (read exactly) does not fit either: the model's own sweep does not follow the data there. Details: docs/identification.md.\n\n\
OBJECTIVE: each measured point against the model state the measured sweep was on (the state the \
model's own sweep follows; before the model's fold another stable state; after it the fold's end), \
continuous in the parameters, plus the jump penalties below. The reported `cost` is the paper's \
Eq 31 (sum over levels and steps of (a_model/gamma - a_meas/gamma)^2, the model's own sweep) at the \
result; `objective` is what was minimised; both are equal where every point is on the model \
sweep's state.\n\n\
PARAMETERS are mass-normalised (only ratios to m are identifiable with acceleration input): \
alpha = k/m, delta = c/m, beta = k_r/m, kappa = c_e/m, exponents rho, eta, and the forcing gain \
(the model sees gain*gamma; held at 1 unless the data demand it, or --free gain / --fix gain=G).\n\n\
DEFAULT BOUNDS (derived from the data): alpha in [(Omega_min/2)^2, (1.5 Omega_max)^2]; delta in \
[1e-4, 1e2] x delta0 (delta0 from the lowest level's peak height); beta_ref = g(rho) beta A_ref^rho \
in [1e-6, 20] x alpha0; kappa_ref = g(eta) kappa (Omega_ref A_ref)^eta in [1e-6, 1e2] x delta0; \
rho in [0, 10]; eta in [-1, 8]; gain in [0.1, 10]. A_ref is the largest measured amplitude, \
Omega_ref its frequency. --bounds FILE overrides: lines `alpha = [min, max]`.\n\n\
JUMPS: a stepped sine can leave its branch before the fold (noise, a disturbance, the controller), \
never after it. --jump-reading exact: a measured jump sits at the model's fold within one measured \
step; a model fold on the wrong side of a point costs (s (d + 0.1 h)/h)^2 x W (d its distance, h \
the measured step, s the point's amplitude; --jump-weight W, default 1). censored: a measured \
jump only bounds the fold (a fold after the jump is free, one before it is penalised). auto \
(default): exact, except the curves that demonstrably left their branch early (tested only when \
the exact fit does not fit its noise); the text and JSON say per level whether the sweep left \
early and by how many Hz. A fit that fits its noise only because auto read some jumps as \
censored is flagged (adequacy.needs_early_jumps): it rests on sweeps having left early, which \
the data alone cannot confirm, and on data of the model family it means the optimum was missed; \
--jump-reading censored states the assumption instead.\n\n\
FLAGS: not converged; parameters at bounds; parameters the data cannot separate; pairs that trade \
off along a ridge (|r| >= 0.999: named, with what would separate them); 95 % intervals that cross \
a physical bound (delta < 0, gain < 0); natural bounds reported as results (eta = -1: Coulomb \
friction); terms that vanished (eta when kappa goes to 0, rho when beta goes to 0). Any of these \
sets intervals_valid false, and so does a model that does not fit its noise (JSON misfit: the \
residual over the noise quoted on the first line; every interval assumes residuals that are noise). A fit that is fine says nothing alarming.\n\n\
NONLINEAR STIFFNESS SIGN: from the data by default (--sign data: each candidate takes the sign of its \
equation-error beta); --sign hardening|softening holds it (softening: bounds apply to |beta_ref|, \
whose upper default is 0.95 alpha0); --sign auto races both signs through the same stages (both \
objectives reported). The self-check's escalation tries both signs either way.\n\n\
PHASE-RESONANCE DATA (--phase-resonance): DATA is a CSV gamma,f_hz,amplitude[,level][,weight], one row \
per level: the frequency and amplitude where the phase lag is 90 deg. Not auto-detected: without the \
flag DATA is read as sweeps. Residuals per level: (a_model - a_meas)/gamma and \
W (f_model - f_meas)/f_meas, W = w_f * RMS(a_meas/gamma) / zeta0 (--frequency-weight w_f, default 1; \
zeta0 = gamma/(2 a Omega^2) of the lowest level: a relative error e of the measured response moves the \
amplitude by ~e and the 90 deg frequency by ~zeta e); the \
model point is the 90 deg point of the harmonic balance. Parameters that these points cannot separate \
(e.g. gain with the free damping coefficients, more free stiffness or damping parameters than levels, \
or a rank-deficient Jacobian at the optimum) are reported as an error naming them."
        .to_string()
}

/// The items of a `--fix name=value,..` list (`fit`, `phase-resonance`,
/// `fit-time`): names trimmed and lowercased, values parsed.
pub fn fix_items(list: &str) -> Result<Vec<(String, f64)>, CliError> {
    list.split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|item| {
            let (name, value) = item
                .split_once('=')
                .ok_or_else(|| CliError::Usage(format!("--fix '{item}' is not name=value")))?;
            let v: f64 = value.trim().parse().map_err(|_| {
                CliError::Usage(format!("--fix {name}: '{}' is not a number", value.trim()))
            })?;
            Ok((name.trim().to_ascii_lowercase(), v))
        })
        .collect()
}

/// Parses `--fix`; returns the mass if given there.
pub fn apply_fix_free(
    spec: &mut FitSpec,
    fix: Option<&str>,
    free: Option<&str>,
) -> Result<Option<f64>, CliError> {
    let mut mass = None;
    if let Some(list) = fix {
        for (n, v) in fix_items(list)? {
            if n == "m" || n == "mass" {
                if !(v.is_finite() && v > 0.0) {
                    return Err(CliError::Usage(format!(
                        "--fix m={v}: the mass must be finite and > 0"
                    )));
                }
                mass = Some(v);
                continue;
            }
            spec.fix(&n, v)
                .map_err(|e| CliError::Usage(format!("--fix: {e}")))?;
        }
    }
    if let Some(list) = free {
        for name in list.split(',').filter(|s| !s.trim().is_empty()) {
            spec.free(name)
                .map_err(|e| CliError::Usage(format!("--free: {e}")))?;
        }
    }
    Ok(mass)
}

/// Reads a bounds TOML file (`name = [min, max]`) with nlsdof-io's reader
/// (the fuzzed one).
pub fn parse_bounds(path: &Path) -> Result<Vec<(String, f64, f64)>, CliError> {
    Ok(nlsdof_io::bounds_file::read_bounds(path)?)
}

/// Applies a bounds TOML file (`name = [min, max]`).
pub fn apply_bounds(spec: &mut FitSpec, path: &Path) -> Result<(), CliError> {
    for (name, lo, hi) in parse_bounds(path)? {
        spec.set_bounds(&name, lo, hi)
            .map_err(|e| CliError::Usage(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// `--grid N` or `--grid NxM`.
pub fn parse_grid(s: &str) -> Result<(usize, usize), CliError> {
    let bad = || {
        CliError::Usage(format!(
            "--grid '{s}' is not allowed: use N or NxM with 1 <= N, M <= 512 (landscape nodes of rho x eta)"
        ))
    };
    let (a, b) = match s.split_once(['x', 'X']) {
        Some((a, b)) => (a, b),
        None => (s, s),
    };
    let n: usize = a.trim().parse().map_err(|_| bad())?;
    let m: usize = b.trim().parse().map_err(|_| bad())?;
    if n == 0 || m == 0 || n > 512 || m > 512 {
        return Err(bad());
    }
    Ok((n, m))
}

/// `--phase-convention lag|lead,OFFSET_DEG[,DELAY_S]`.
pub fn parse_phase_convention(s: &str) -> Result<PhaseConvention, CliError> {
    let bad = |why: &str| {
        CliError::Usage(format!(
            "--phase-convention '{s}': {why} (expected lag|lead,OFFSET_DEG[,DELAY_S])"
        ))
    };
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() < 2 || parts.len() > 3 {
        return Err(bad("need 2 or 3 fields"));
    }
    let lag = match parts[0].to_ascii_lowercase().as_str() {
        "lag" => true,
        "lead" => false,
        _ => return Err(bad("first field must be lag or lead")),
    };
    let offset: f64 = parts[1]
        .parse()
        .map_err(|_| bad("offset is not a number"))?;
    let delay: f64 = match parts.get(2) {
        Some(d) => d.parse().map_err(|_| bad("delay is not a number"))?,
        None => 0.0,
    };
    PhaseConvention::from_degrees(lag, offset, delay).map_err(|why| bad(&why))
}

/// The fit plan of the CLI options (`--fix`, `--free`, `--bounds`, sign,
/// phase, jumps, landscape grid); returns the mass given with `--fix m=..`.
pub fn plan_from_args(
    args: &Args,
    kind: ModelKind,
    sign: super::sign::SignArg,
) -> Result<(FitPlan, Option<f64>), CliError> {
    use super::sign::SignArg;
    let mut plan = FitPlan::new(kind);
    // validate names and values exactly as the spec does
    let mut probe = FitSpec::new(kind, &dummy_dataset());
    let mass = apply_fix_free(&mut probe, args.fix.as_deref(), args.free.as_deref())?;
    if let Some(list) = &args.fix {
        for item in list.split(',').filter(|s| !s.trim().is_empty()) {
            let (name, value) = item.split_once('=').expect("checked");
            let n = name.trim().to_ascii_lowercase();
            let v: f64 = value.trim().parse().expect("checked");
            match n.as_str() {
                "m" | "mass" => {}
                "gain" => plan.gain = GainChoice::Fixed(v),
                _ => plan.fix.push((n, v)),
            }
        }
    }
    if let Some(list) = &args.free {
        for name in list.split(',').filter(|s| !s.trim().is_empty()) {
            let n = name.trim().to_ascii_lowercase();
            if n == "gain" {
                plan.gain = GainChoice::Free;
            } else {
                plan.free.push(n);
            }
        }
    }
    if let Some(b) = &args.bounds {
        apply_bounds(&mut probe, b)?;
        plan.bounds = parse_bounds(b)?;
    }
    plan.sign = match sign {
        SignArg::Data => SignChoice::Auto,
        SignArg::Auto => SignChoice::Both,
        SignArg::Hardening => SignChoice::Hardening,
        SignArg::Softening => SignChoice::Softening,
    };
    if args.integer {
        if kind.stiffness() != nlsdof::identification::models::Term::FreeExponent
            && kind.damping() != nlsdof::identification::models::Term::FreeExponent
            && !plan.free.iter().any(|n| n == "rho" || n == "eta")
        {
            return Err(CliError::Usage(format!(
                "--integer: the {kind} model has no free exponent"
            )));
        }
        plan.exponents = nlsdof::identification::identify::ExponentChoice::Integer;
    }
    plan.reading = match args.jump_reading {
        None | Some(ReadingArg::Auto) => ReadingChoice::Auto,
        Some(ReadingArg::Exact) => ReadingChoice::Exact,
        Some(ReadingArg::Censored) => ReadingChoice::Censored,
    };
    if args.no_phase && args.phase_convention.is_some() {
        return Err(CliError::Usage(
            "--no-phase conflicts with --phase-convention".into(),
        ));
    }
    plan.phase = if args.no_phase {
        PhaseChoice::Ignore
    } else if let Some(c) = &args.phase_convention {
        PhaseChoice::Known(parse_phase_convention(c)?)
    } else {
        PhaseChoice::Auto
    };
    if !(args.phase_weight.is_finite() && args.phase_weight > 0.0) {
        return Err(CliError::Usage(format!(
            "--phase-weight {} is not allowed: use a finite value > 0",
            args.phase_weight
        )));
    }
    plan.phase_weight = args.phase_weight;
    plan.weighting = match args.weighting {
        None | Some(WeightingArg::Absolute) => Weighting::Absolute,
        Some(WeightingArg::Relative) => Weighting::Relative,
    };
    plan.jumps = match args.jump_weight {
        None => JumpChoice::Auto,
        Some(l) if l == 0.0 => JumpChoice::Off,
        Some(l) => JumpChoice::Weight(l),
    };
    plan.grid = parse_grid(&args.grid)?;
    if args.refine == 0 || args.refine > 100 {
        return Err(CliError::Usage(format!(
            "--refine {} is not allowed: use 1..=100",
            args.refine
        )));
    }
    plan.refine = args.refine;
    let starts = args.starts.unwrap_or(1);
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    plan.starts = starts;
    plan.seed = args.seed;
    Ok((plan, mass))
}

/// A tiny valid data set, only to validate `--fix`/`--free`/`--bounds`
/// names and values before the real data are read.
fn dummy_dataset() -> Dataset {
    let recs: Vec<nlsdof::identification::Record> = (0..3)
        .map(|i| nlsdof::identification::Record {
            level: "1".into(),
            gamma: 1.0,
            omega: 1.0 + i as f64,
            amplitude: 1.0,
            phase: None,
            direction: SweepDirection::Up,
            weight: 1.0,
        })
        .collect();
    Dataset::from_records(&recs).expect("valid dummy data")
}

pub fn parse_model_kind(name: &str) -> Result<ModelKind, CliError> {
    ModelKind::parse(name).ok_or_else(|| {
        let all: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
        CliError::Usage(format!(
            "unknown model '{name}' (expected one of {})",
            all.join(", ")
        ))
    })
}

pub fn resolve_mass(
    flag: Option<f64>,
    from_fix: Option<f64>,
    model_file: Option<&Path>,
) -> Result<Option<f64>, CliError> {
    if let Some(m) = flag {
        if !(m.is_finite() && m > 0.0) {
            return Err(CliError::Usage(format!(
                "--mass {m} is not allowed: the mass must be finite and > 0 (kg)"
            )));
        }
        return Ok(Some(m));
    }
    if from_fix.is_some() {
        return Ok(from_fix);
    }
    if let Some(p) = model_file {
        return Ok(Some(super::roots::load_model(p)?.mass));
    }
    Ok(None)
}

/// The output-error profile intervals of the free exponents of the final
/// fit, in steps of half their linearised standard error (0.05 without one),
/// each with a progress bar of its local fits (on a terminal).
fn oe_profiles(id: &Identification) -> Result<Vec<OutputErrorProfile>, CliError> {
    let mut out = Vec::new();
    let free: Vec<Parameter> = [Parameter::Rho, Parameter::Eta]
        .into_iter()
        .filter(|&p| id.spec.status[p as usize] == nlsdof::identification::Status::Free)
        .collect();
    for (i, &p) in free.iter().enumerate() {
        let step = default_step(&id.fit, p);
        let what = format!("profile {} ({}/{})", p.info().name, i + 1, free.len());
        let (pb, on_progress) = super::progress::fits_bar(&what);
        let prof = output_error_profile_with(
            &id.data,
            &id.spec,
            &id.fit.theta,
            p,
            step,
            24,
            nlsdof::cancel::Cancel::NEVER,
            &on_progress,
        );
        pb.finish_and_clear();
        out.push(prof.map_err(|e| CliError::Usage(format!("--profile: {e}")))?);
    }
    Ok(out)
}

/// `--intervals`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IntervalsArg {
    One,
    All,
}

/// `--jump-reading`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReadingArg {
    Auto,
    Exact,
    Censored,
}

/// The fit: [`identify`] (equation error, landscape, output error, decisions, self-check).
fn run_identify(args: &Args, kind: ModelKind, sign: super::sign::SignArg) -> Result<(), CliError> {
    let (plan, fix_mass) = plan_from_args(args, kind, sign)?;
    let mass = resolve_mass(args.mass, fix_mass, args.model_file.as_deref())?;
    // every output can be written, and no file is named twice, before any work
    let mut targets: Vec<(&str, &Path)> = Vec::new();
    if let Some(p) = &args.out {
        targets.push(("--out", p));
    }
    if let Some(p) = &args.plot {
        targets.push(("--plot", p));
    }
    if let Some(p) = &args.predict {
        targets.push(("--predict", p));
    }
    if let Some(p) = &args.landscape {
        targets.push(("--landscape", p));
    }
    nlsdof_io::atomic::check_targets(&targets)?;
    let landscape_kind = match &args.landscape {
        None => None,
        Some(p) => Some(nlsdof_report::landscape::kind_of(p)?),
    };
    // a model without a free exponent has a one-node landscape: nothing to
    // draw, refused before the fit (its JSON still gives the node's cost)
    if let (
        Some(p),
        Some(nlsdof_report::landscape::Kind::Svg | nlsdof_report::landscape::Kind::Png),
    ) = (&args.landscape, landscape_kind)
    {
        use nlsdof::identification::models::Term;
        let fixed = |n: &str| plan.fix.iter().any(|(f, _)| f == n);
        let free = |n: &str, t: Term| {
            !fixed(n) && (t == Term::FreeExponent || plan.free.iter().any(|f| f == n))
        };
        if !free("rho", kind.stiffness()) && !free("eta", kind.damping()) {
            return Err(CliError::Usage(format!(
                "--landscape {}: the {kind} model has no free exponent, so its landscape is a single node and there is nothing to draw; write FILE.json for its cost, or free an exponent (--model generalised, or --free rho)",
                p.display()
            )));
        }
    }
    let data = args.data.load()?;
    let mut plan = plan;
    let inspected = if args.from_inspect {
        let r = inspect(&data, &InspectOptions::default()).map_err(|e| {
            CliError::Usage(format!("--from-inspect: {}: {e}", args.data.source_name()))
        })?;
        plan.start_exponents = Some(r.exponent_start());
        Some(r)
    } else {
        None
    };
    let (pb, on_progress) = super::progress::stage_bar(kind.name());
    let id = identify(&data, &plan, &on_progress);
    pb.finish_and_clear();
    let id = id.map_err(|e| CliError::Usage(e.to_string()))?;
    let res = &id.fit;
    // render everything first, then commit the files
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if let Some(out) = &args.out {
        let source = args.data.source_name();
        files.push((
            out.clone(),
            model_file_text(res, mass, Some(&source))?.into_bytes(),
        ));
    }
    if let Some(p) = &args.predict {
        files.push((
            p.clone(),
            nlsdof_report::fit::predict_csv(&id)?.into_bytes(),
        ));
    }
    if let Some(p) = &args.plot {
        let format = nlsdof_report::figure_file::plot_format(p);
        files.push((
            p.clone(),
            nlsdof_report::fit::fit_figure(&id.data, res, format)?,
        ));
    }
    if let (Some(p), Some(k)) = (&args.landscape, landscape_kind) {
        files.push((p.clone(), nlsdof_report::landscape::render(&id, k)?));
    }
    for (p, bytes) in &files {
        nlsdof_io::atomic::write_atomic(p, bytes)?;
    }
    let profiles = if args.profile {
        // refits with the exponent held: seconds to minutes, a bar per exponent
        oe_profiles(&id)?
    } else {
        Vec::new()
    };
    if args.json {
        let mut v = nlsdof_report::fit::identification_document(&id, mass)?;
        if args.profile {
            v["identification"]["profile_oe_ci95"] = nlsdof_report::fit::profiles_json(&profiles);
        }
        // the one interval per parameter, with its method (ci95 stays Wald)
        nlsdof_report::intervals::add_chosen_json(&mut v, &id.fit, &profiles);
        if args.integer {
            v["integer_pairs"] = nlsdof_report::fit::integer_nodes_json(&id);
        }
        if let Some(r) = &inspected {
            v["from_inspect"] = from_inspect_json(r, &id);
        }
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
    } else {
        let view = match args.intervals {
            IntervalsArg::One => nlsdof_report::intervals::IntervalView::One,
            IntervalsArg::All => nlsdof_report::intervals::IntervalView::All,
        };
        print!(
            "{}",
            nlsdof_report::fit::identification_report_with(&id, mass, &profiles, view)?
        );
        if let Some(r) = &inspected {
            print!("{}", from_inspect_text(r, &id));
        }
        if args.integer {
            print!("{}", nlsdof_report::fit::integer_nodes_text(&id));
        }
    }
    Ok(())
}

/// Per exponent: inspect's estimate and interval beside the fit's value and
/// status.
fn exponent_rows(
    r: &Inspection,
    id: &Identification,
) -> Vec<(&'static str, Option<LawFit>, f64, Status)> {
    vec![
        (
            "rho",
            r.stiffness.fit.clone(),
            id.fit.theta[RHO],
            id.spec.status[RHO],
        ),
        (
            "eta",
            r.damping.fit.clone(),
            id.fit.theta[ETA],
            id.spec.status[ETA],
        ),
    ]
}

fn from_inspect_text(r: &Inspection, id: &Identification) -> String {
    let mut out = String::from("\nFrom inspect (model-free laws, --from-inspect):\n");
    for (name, law, value, status) in exponent_rows(r, id) {
        let ins = match &law {
            Some(f) => {
                let ci = match f.exponent_ci95 {
                    Some([a, b]) => format!(
                        "95 % [{a:.3}, {b:.3}]{}",
                        if f.interval_open { " (open)" } else { "" }
                    ),
                    None => "no interval".to_string(),
                };
                format!(
                    "{:.3}  {ci}{}",
                    f.exponent,
                    if f.exponent_at_bound {
                        ", at the end of its range: not used"
                    } else {
                        ""
                    }
                )
            }
            None => "not estimated".to_string(),
        };
        let fit = match status {
            Status::Free => format!("{value:.4}"),
            _ => format!("{value:.4} (held)"),
        };
        out.push_str(&format!("  {name:<4} inspect {ins};  fit {fit}\n"));
    }
    match id.start_node {
        Some((rho, eta)) => out.push_str(&format!(
            "  the race also started from the landscape node rho = {rho:.3}, eta = {eta:.3}\n"
        )),
        None => out.push_str(
            "  no extra start: the model holds both exponents, or inspect determined neither\n",
        ),
    }
    out
}

fn from_inspect_json(r: &Inspection, id: &Identification) -> serde_json::Value {
    let mut v = serde_json::Map::new();
    for (name, law, value, status) in exponent_rows(r, id) {
        v.insert(
            name.to_string(),
            serde_json::json!({
                "inspect": law.as_ref().map(|f| f.exponent),
                "inspect_ci95": law.as_ref().and_then(|f| f.exponent_ci95),
                "inspect_interval_open": law.as_ref().map(|f| f.interval_open),
                "inspect_at_bound": law.as_ref().map(|f| f.exponent_at_bound),
                "fit": value,
                "fit_free": status == Status::Free,
            }),
        );
    }
    v.insert(
        "start_node".to_string(),
        match id.start_node {
            Some((rho, eta)) => serde_json::json!({ "rho": rho, "eta": eta }),
            None => serde_json::Value::Null,
        },
    );
    serde_json::Value::Object(v)
}

pub fn run(args: Args) -> Result<(), CliError> {
    // (`fit --phase-resonance` is dispatched to `phase_resonance::run_fit_verb`)
    let sign = args.pr.sign.resolve(args.pr.softening)?;
    if let Some(l) = args.jump_weight {
        if !(l.is_finite() && l >= 0.0) {
            return Err(CliError::Usage(format!(
                "--jump-weight {l} is not allowed: use a finite value >= 0"
            )));
        }
    }
    let kind = parse_model_kind(&args.model)?;
    // one pipeline: --sign auto, --integer and every expert flag go
    // through identify
    run_identify(&args, kind, sign)
}
