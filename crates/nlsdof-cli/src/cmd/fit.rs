//! `nlsdof fit`: identify a power-law model from stepped-sine amplitude
//! curves at several input levels (paper §4, Eq 31). Also home of the
//! helpers shared with `nlsdof compare` (data loading, options, reports).

use crate::error::CliError;
use nlsdof::identification::models::{ALPHA, BETA, DELTA, GAIN};
use nlsdof::identification::search::{best_integer_fit, IntegerPair};
use nlsdof::identification::{
    fit, identify, phase_quadrature_table, predicted_jumps, Dataset, FitOptions, FitPlan,
    FitResult, FitSpec, GainChoice, Identification, JumpChoice, ModelKind, PhaseChoice,
    PhaseConvention, SignChoice, Status, Weighting, N_PARAMS, PARAM_NAMES,
};
use nlsdof::identification::{Parameter, Parameters};
use nlsdof::{Model, SweepDirection};
use nlsdof_io::stepped_sine_data::{read_beam_dir, read_csv, AmplitudeKind, ReadOptions, Runs};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub use super::progress::progress_bar;

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
    /// Long-format CSV: level,gamma,f_hz,amplitude[,phase_deg][,sweep][,weight].
    #[arg(value_name = "DATA", required_unless_present = "beam_dir")]
    pub data: Option<PathBuf>,
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
            let runs = match self.runs {
                RunsArg::Up => Runs::Up,
                RunsArg::Down => Runs::Down,
                RunsArg::Both => Runs::Both,
            };
            return read_beam_dir(dir, runs).map_err(err);
        }
        let path = self
            .data
            .as_ref()
            .expect("clap requires DATA or --beam-dir");
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

    /// As [`Self::load`], with the phases dropped where they are not
    /// displacement lags (the beam files' raw instrument phases), for the
    /// fits that read phases as lags without detecting the convention.
    pub fn load_lag_phases(&self) -> Result<Dataset, CliError> {
        let mut d = self.load()?;
        if self.beam_dir.is_some() {
            for c in &mut d.curves {
                c.phases = None;
            }
        }
        Ok(d)
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
    #[arg(long, value_name = "NAME=VALUE,..", allow_hyphen_values = true)]
    pub fix: Option<String>,
    /// Estimate parameters the model holds (e.g. gain, or an exponent): name,..
    #[arg(long, value_name = "NAME,..")]
    pub free: Option<String>,
    /// Exponents restricted to integers: every integer pair in the bounds is fitted.
    #[arg(long)]
    pub integer: bool,
    /// Extra global-search starts (Latin hypercube) per refined landscape candidate
    /// (default 1 = none: the local fit from the equation-error start). With --integer or
    /// --sign auto: starts of the classic multistart (default 32).
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
    /// Landscape grid: N (N x N) or NxM (rho nodes x eta nodes), each 1..=512.
    #[arg(long, value_name = "N[xM]", default_value = "41")]
    pub grid: String,
    /// Landscape minima refined by output error (Eq 31).
    #[arg(long, value_name = "K", default_value_t = 3)]
    pub refine: usize,
    /// Seed of the Latin-hypercube starts.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Add a jump-frequency residual per up-sweep with a measured jump, weight LAMBDA >= 0
    /// (see JUMP FREQUENCIES below; 0 = plain Eq 31).
    #[arg(long = "jump-weight", value_name = "LAMBDA")]
    pub jump_weight: Option<f64>,
    /// TOML file of bounds: name = [min, max] (for beta/kappa: of beta_ref/kappa_ref, see --help).
    #[arg(long, value_name = "FILE")]
    pub bounds: Option<PathBuf>,
    /// Mass m, kg, for physical units and --out.
    #[arg(long, value_name = "M")]
    pub mass: Option<f64>,
    /// Take the mass from this model file.
    #[arg(long = "model-file", value_name = "FILE")]
    pub model_file: Option<PathBuf>,
    /// Write the fitted model (TOML model format).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Write an SVG of the data (dots) and the fitted model's sweeps (lines) per level.
    #[arg(long, value_name = "FIG.svg")]
    pub plot: Option<PathBuf>,
    /// JSON output.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub pr: super::sign::PrArgs,
}

/// Minimal SVG: measured amplitudes (dots) and the model's branch-following
/// amplitudes at the same steps (lines), one colour per curve.
pub fn fit_svg(data: &Dataset, res: &FitResult) -> String {
    const W: f64 = 900.0;
    const H: f64 = 560.0;
    const L: f64 = 80.0;
    const R: f64 = 170.0;
    const T: f64 = 30.0;
    const B: f64 = 50.0;
    const COLOURS: [&str; 9] = [
        "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#bcbd22",
        "#17becf",
    ];
    let (mut f0, mut f1, mut a1) = (f64::INFINITY, 0.0f64, 0.0f64);
    for c in &data.curves {
        for (&w, &a) in c.omegas.iter().zip(&c.amplitudes) {
            f0 = f0.min(hz(w));
            f1 = f1.max(hz(w));
            a1 = a1.max(a);
        }
    }
    a1 = a1.max(res.model_amplitudes.iter().cloned().fold(0.0, f64::max)) * 1.05;
    if !(a1 > 0.0) {
        a1 = 1.0;
    }
    let x = |f: f64| L + (f - f0) / (f1 - f0).max(1e-300) * (W - L - R);
    let y = |a: f64| H - B - a / a1 * (H - T - B);
    let mut s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n");
    let _ = writeln!(s, "<text x=\"{}\" y=\"18\" text-anchor=\"middle\">nlsdof fit: {} (dots: data, lines: model), cost {:.4e}</text>", W / 2.0, res.kind, res.cost);
    let _ = writeln!(
        s,
        "<rect x=\"{L}\" y=\"{T}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
        W - L - R,
        H - T - B
    );
    for k in 0..=5 {
        let f = f0 + (f1 - f0) * k as f64 / 5.0;
        let a = a1 * k as f64 / 5.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{f:.1}</text>",
            x(f),
            H - B + 18.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">{a:.2e}</text>",
            L - 6.0,
            y(a) + 4.0
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">frequency [Hz]</text>",
        L + (W - L - R) / 2.0,
        H - 12.0
    );
    let _ = writeln!(s, "<text x=\"16\" y=\"{}\" transform=\"rotate(-90 16 {})\" text-anchor=\"middle\">amplitude [m]</text>", H / 2.0, H / 2.0);
    let mut off = 0;
    for (i, c) in data.curves.iter().enumerate() {
        let col = COLOURS[i % COLOURS.len()];
        let n = c.omegas.len();
        let pts: Vec<String> = (0..n)
            .map(|k| {
                format!(
                    "{:.2},{:.2}",
                    x(hz(c.omegas[k])),
                    y(res.model_amplitudes[off + k])
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"{col}\" stroke-width=\"1.5\" points=\"{}\"/>",
            pts.join(" ")
        );
        let stride = (n / 300).max(1);
        for k in (0..n).step_by(stride) {
            let _ = writeln!(
                s,
                "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"1.8\" fill=\"{col}\"/>",
                x(hz(c.omegas[k])),
                y(c.amplitudes[k])
            );
        }
        let dir = if c.direction == SweepDirection::Up {
            "up"
        } else {
            "down"
        };
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" fill=\"{col}\">{} ({dir})</text>",
            W - R + 12.0,
            T + 16.0 * (i as f64 + 1.0),
            c.level
        );
        off += n;
    }
    s.push_str("</svg>\n");
    s
}

fn fit_long_help() -> String {
    "OBJECTIVE (Eq 31): sum over levels and steps of (a_model/gamma - a_meas/gamma)^2, the model amplitude \
following the measured sweep direction (branch following through jumps).\n\n\
PARAMETERS are mass-normalised (only ratios to m are identifiable with acceleration input): \
alpha = k/m, delta = c/m, beta = k_r/m, kappa = c_e/m, exponents rho, eta, and the forcing gain \
(the model sees gain*gamma; fixed at 1 unless --free gain).\n\n\
DEFAULT BOUNDS (derived from the data): alpha in [(Omega_min/2)^2, (1.5 Omega_max)^2]; delta in \
[1e-4, 1e2] x delta0 (delta0 from the lowest level's peak height); beta_ref = g(rho) beta A_ref^rho \
in [1e-6, 2] x alpha0; kappa_ref = g(eta) kappa (Omega_ref A_ref)^eta in [1e-6, 1e2] x delta0; \
rho in [0, 10]; eta in [-1, 8]; gain in [0.1, 10]. A_ref is the largest measured amplitude, \
Omega_ref its frequency. --bounds FILE overrides: lines `alpha = [min, max]`.\n\n\
JUMP FREQUENCIES (--jump-weight LAMBDA): Eq 31 is piecewise constant in the location of a jump (moving the predicted jump across one measured step changes the cost by a step), so a plain fit can put the jump-down several per cent away from the measured one. With LAMBDA > 0 each up-sweep with a measured jump adds the residual sqrt(LAMBDA n_c) (a_peak/gamma) (f_jump,model / f_jump,measured - 1), f_jump,model = the model's fold frequency (its 90-degree frequency where it has no fold), with analytic derivatives. The reported cost, RMS and intervals are those of Eq 31 alone at the optimum. Example (clamped beam): --free gain --jump-weight 100. Not with --integer, --sign auto or --phase-resonance.\n\n\
NONLINEAR STIFFNESS SIGN: hardening (beta > 0) by default; --softening (or --sign softening) fits \
beta < 0 (bounds then apply to |beta_ref|, whose upper default is 0.95 alpha0); --sign auto fits both \
and keeps the lower cost (both costs reported).\n\n\
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

/// Parses `--fix`; returns the mass if given there.
pub fn apply_fix_free(
    spec: &mut FitSpec,
    fix: Option<&str>,
    free: Option<&str>,
) -> Result<Option<f64>, CliError> {
    let mut mass = None;
    if let Some(list) = fix {
        for item in list.split(',').filter(|s| !s.trim().is_empty()) {
            let (name, value) = item
                .split_once('=')
                .ok_or_else(|| CliError::Usage(format!("--fix '{item}' is not name=value")))?;
            let v: f64 = value.trim().parse().map_err(|_| {
                CliError::Usage(format!("--fix {name}: '{}' is not a number", value.trim()))
            })?;
            let n = name.trim().to_ascii_lowercase();
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
    let sign = match parts[0].to_ascii_lowercase().as_str() {
        "lag" => 1.0,
        "lead" => -1.0,
        _ => return Err(bad("first field must be lag or lead")),
    };
    let offset: f64 = parts[1]
        .parse()
        .map_err(|_| bad("offset is not a number"))?;
    let delay: f64 = match parts.get(2) {
        Some(d) => d.parse().map_err(|_| bad("delay is not a number"))?,
        None => 0.0,
    };
    if !(offset.is_finite() && offset.abs() <= 360.0) {
        return Err(bad("offset must be finite, within [-360, 360] degrees"));
    }
    if !(delay.is_finite() && delay.abs() < 1.0) {
        return Err(bad("delay must be finite, |delay| < 1 s"));
    }
    Ok(PhaseConvention {
        sign,
        offset: offset.to_radians(),
        delay,
    })
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
        SignArg::Data | SignArg::Auto => SignChoice::Auto,
        SignArg::Hardening => SignChoice::Hardening,
        SignArg::Softening => SignChoice::Softening,
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

/// JSON of the stages of [`identify`] (equation error, landscape,
/// phase convention, gain decision, candidates).
pub fn identification_json(id: &Identification) -> Value {
    let l = &id.landscape;
    let minima: Vec<Value> = l
        .minima
        .iter()
        .take(20)
        .map(|&(i, j)| json!({"rho": l.rho[i], "eta": l.eta[j], "cost": l.at(i, j)}))
        .collect();
    let prof = |p: Option<nlsdof::identification::landscape::ProfileInterval>| {
        p.map(|p| json!([p.lower, p.upper]))
    };
    json!({
        "equation_error": {"theta": id.equation_error.theta.to_array(), "cost": id.equation_error.cost,
                            "residuals": id.equation_error.n_residuals},
        "landscape": {"rho": [l.rho.first(), l.rho.last(), l.rho.len()],
                      "eta": [l.eta.first(), l.eta.last(), l.eta.len()],
                      "with_phase": l.with_phase, "minima": minima},
        "profile_ci95": {"rho": prof(id.rho_profile), "eta": prof(id.eta_profile),
                         "note": "profile likelihood of the equation-error cost over the landscape grid; null bound = open at the grid edge"},
        "phase_convention": id.phase.map(|p| json!({
            "sign": if p.sign > 0.0 { "lag" } else { "lead" },
            "offset_deg": p.offset.to_degrees(), "delay_s": p.delay})),
        "gain_test": id.gain_test.map(|g| json!({"gain": g.gain, "f_statistic": g.f_statistic, "freed": g.freed})),
        "jump_weight": id.jump_weight,
        "candidates": id.candidates.iter().map(|c| json!({
            "rho": c.rho, "eta": c.eta, "ee_cost": c.ee_cost, "sign": c.sign.name(),
            "objective": c.oe.as_ref().ok(), "error": c.oe.as_ref().err()})).collect::<Vec<_>>(),
    })
}

/// Text lines of the stages of [`identify`].
pub fn identification_text(id: &Identification) -> String {
    let mut s = String::new();
    let l = &id.landscape;
    writeln!(
        s,
        "stages: equation error ({}) -> landscape {}x{} (rho {:.3}..{:.3}, eta {:.3}..{:.3}), {} grid minima -> output error from the best {}",
        if l.with_phase { "amplitude and phase" } else { "amplitude" },
        l.rho.len(),
        l.eta.len(),
        l.rho[0],
        l.rho[l.rho.len() - 1],
        l.eta[0],
        l.eta[l.eta.len() - 1],
        l.minima.len(),
        id.candidates.len()
    )
    .ok();
    if let Some(p) = id.phase {
        writeln!(
            s,
            "phase convention: {} {:+.2} deg{} (measured phase = {}displacement lag + offset)",
            if p.sign > 0.0 { "lag" } else { "lead" },
            p.offset.to_degrees(),
            if p.delay != 0.0 {
                format!(" + delay {:.3e} s", p.delay)
            } else {
                String::new()
            },
            if p.sign > 0.0 { "" } else { "-" }
        )
        .ok();
    }
    if let Some(g) = id.gain_test {
        writeln!(
            s,
            "gain: {} (equation-error gain {:.4}, F = {:.3e}, freed when F > {})",
            if g.freed { "free" } else { "held at 1" },
            g.gain,
            g.f_statistic,
            nlsdof::identification::identify::GAIN_F_THRESHOLD
        )
        .ok();
    }
    if id.jump_weight > 0.0 {
        writeln!(s, "jump residuals: lambda = {}", id.jump_weight).ok();
    }
    let f = |p: Option<nlsdof::identification::landscape::ProfileInterval>| {
        p.map(|p| {
            format!(
                "[{}, {}]",
                p.lower.map_or("open".into(), |v| format!("{v:.3}")),
                p.upper.map_or("open".into(), |v| format!("{v:.3}"))
            )
        })
    };
    if let Some(r) = f(id.rho_profile) {
        writeln!(s, "profile 95 % interval (equation error) rho: {r}").ok();
    }
    if let Some(e) = f(id.eta_profile) {
        writeln!(s, "profile 95 % interval (equation error) eta: {e}").ok();
    }
    s
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

fn hz(w: f64) -> f64 {
    w / (2.0 * PI)
}

fn status_name(s: Status) -> &'static str {
    match s {
        Status::Absent => "absent",
        Status::Fixed(_) => "fixed",
        Status::Free => "free",
    }
}

/// The `--out` model file of a fit: a header (model, cost, a note when the
/// fit is not trustworthy, the forcing gain, the mass convention) and the
/// physical model for `mass` (1 kg when not given).
pub fn model_file_text(res: &FitResult, mass: Option<f64>) -> Result<String, CliError> {
    let model = physical(res, mass.unwrap_or(1.0))?;
    let mut text = format!(
        "# fitted by `nlsdof fit`, model {}, cost {:.6e}{}\n# forcing gain = {} (the structure sees gain * gamma; not part of this file)\n",
        res.kind,
        res.cost,
        if res.warning().is_some() {
            " (NOT CONVERGED or not identifiable: see the fit report)"
        } else {
            ""
        },
        res.theta[GAIN]
    );
    if mass.is_none() {
        text.push_str("# no mass given: m = 1 kg, all values are per unit mass\n");
    }
    text.push_str(&nlsdof_io::model_file::model_to_toml(&model));
    Ok(text)
}

/// Physical model for mass `m` (β, κ scaled; gain is not part of it).
pub fn physical(res: &FitResult, m: f64) -> Result<Model, CliError> {
    Ok(res.model().to_physical(m)?)
}

/// JSON of one fit.
pub fn result_json(data: &Dataset, res: &FitResult, mass: Option<f64>) -> Result<Value, CliError> {
    let mut params = Vec::new();
    let valid = res.intervals_valid();
    for j in 0..N_PARAMS {
        if res.status[j] == Status::Absent {
            continue;
        }
        let unc = res.uncertainty.as_ref().filter(|_| valid).and_then(|u| {
            u.names
                .iter()
                .position(|n| *n == PARAM_NAMES[j])
                .map(|k| (u, k))
        });
        let mass_scaled = Parameter::ALL[j].mass_scaled();
        let m = mass.unwrap_or(1.0);
        let phys = |v: f64| if mass_scaled { v * m } else { v };
        params.push(json!({
            "name": PARAM_NAMES[j],
            "status": status_name(res.status[j]),
            "value": res.theta[j],
            "std_error": unc.map(|(u, k)| u.std_errors[k]),
            "ci95": unc.map(|(u, k)| [u.lower[k], u.upper[k]]),
            "physical": { "name": Parameter::ALL[j].info().physical_name, "unit": Parameter::ALL[j].info().physical_unit, "value": phys(res.theta[j]),
                          "ci95": unc.map(|(u, k)| [phys(u.lower[k]), phys(u.upper[k])]) },
        }));
    }
    let jumps = predicted_jumps(data, &res.theta)?;
    let levels: Vec<Value> = res
        .levels
        .iter()
        .zip(data.curves.iter().zip(&jumps))
        .map(|(l, (c, pj))| {
            json!({
                "level": l.level, "gamma": l.gamma,
                "sweep": if l.direction == SweepDirection::Up { "up" } else { "down" },
                "points": l.points, "rms": l.rms, "rms_normalised": l.rms_normalised,
                "measured_jump_f_hz": c.measured_jump(2.0).map(hz),
                "model_jump_f_hz": pj.map(hz),
            })
        })
        .collect();
    let pq: Vec<Value> = phase_quadrature_table(data, &res.theta)?
        .iter()
        .map(|r| {
            let (df, da) = r.differences_percent();
            json!({
                "level": r.level, "gamma": r.gamma, "measured_from": r.measured_from,
                "measured_f_hz": hz(r.measured_omega), "measured_amplitude": r.measured_amplitude,
                "model_f_hz": r.model_omega.map(hz), "model_amplitude": r.model_amplitude,
                "diff_f_percent": df, "diff_amplitude_percent": da,
            })
        })
        .collect();
    let minima: Vec<Value> = res
        .minima
        .iter()
        .map(|m| json!({"cost": m.cost, "count": m.count, "termination": m.termination.name(), "theta": m.theta.to_array()}))
        .collect();
    let stiffness_sign = (res.status[BETA] != Status::Absent).then(|| {
        if res.theta[BETA] < 0.0 {
            "softening"
        } else {
            "hardening"
        }
    });
    Ok(json!({
        "model": res.kind.name(),
        "stiffness_sign": stiffness_sign,
        "converged": res.converged,
        "at_bounds": res.at_bounds,
        "unidentifiable": res.unidentifiable,
        "intervals_valid": valid,
        "warning": res.warning(),
        "phase_cost": res.phase_cost,
        "parameters": params,
        "parameter_order": PARAM_NAMES,
        "theta": res.theta.to_array(),
        "mass": mass,
        "mass_note": if mass.is_none() { Some("no mass given: physical values are per unit mass (m = 1 kg)") } else { None },
        "cost": res.cost,
        "rms_normalised": res.rms_normalised(),
        "aic": res.aic(), "bic": res.bic(),
        "points": res.n_points, "free_parameters": res.n_free,
        "termination": res.termination.name(),
        "iterations": res.iterations,
        "correlation": res.uncertainty.as_ref().filter(|_| valid).map(|u| json!({"names": u.names, "matrix": u.correlation})),
        "minima": minima,
        "levels": levels,
        "phase_quadrature": pq,
    }))
}

/// The parameter block shared by the sweep and phase-resonance fit reports:
/// a note when no mass is given, one line per parameter (status, value,
/// standard error, 95 % interval, physical value) and `f_n`, `zeta`.
pub fn parameter_table_text(
    s: &mut String,
    theta: &Parameters,
    status: &[Status; N_PARAMS],
    unc: Option<&nlsdof::identification::uncertainty::Uncertainty>,
    mass: Option<f64>,
) {
    let m = mass.unwrap_or(1.0);
    if mass.is_none() {
        writeln!(
            s,
            "note: no mass given (--mass); physical values are per unit mass (m = 1 kg)"
        )
        .ok();
    }
    writeln!(
        s,
        "{:<6} {:>7} {:>15} {:>12} {:>33}   {}",
        "param", "status", "value", "std error", "95 % interval", "physical"
    )
    .ok();
    for j in 0..N_PARAMS {
        if status[j] == Status::Absent {
            continue;
        }
        let u_k = unc.and_then(|u| {
            u.names
                .iter()
                .position(|n| *n == PARAM_NAMES[j])
                .map(|k| (u, k))
        });
        let (se, ci) = match u_k {
            Some((u, k)) => (
                format!("{:.4e}", u.std_errors[k]),
                format!("[{:.6e}, {:.6e}]", u.lower[k], u.upper[k]),
            ),
            None => ("-".into(), "-".into()),
        };
        let phys = if Parameter::ALL[j].mass_scaled() {
            theta[j] * m
        } else {
            theta[j]
        };
        writeln!(
            s,
            "{:<6} {:>7} {:>15.8e} {:>12} {:>33}   {} = {:.8e} {}",
            PARAM_NAMES[j],
            status_name(status[j]),
            theta[j],
            se,
            ci,
            Parameter::ALL[j].info().physical_name,
            phys,
            Parameter::ALL[j].info().physical_unit
        )
        .ok();
    }
    let wn = theta[ALPHA].sqrt();
    writeln!(
        s,
        "f_n = {:.6} Hz, zeta = {:.6e}",
        hz(wn),
        theta[DELTA] / (2.0 * wn)
    )
    .ok();
}

/// Human-readable report of one fit.
pub fn result_text(data: &Dataset, res: &FitResult, mass: Option<f64>) -> Result<String, CliError> {
    let mut s = String::new();
    if let Some(w) = res.warning() {
        writeln!(s, "{w}").ok();
    }
    writeln!(s, "model {}: cost (Eq 31) = {:.6e}, RMS (a/gamma) = {:.6e} s^2, {} points, {} free parameters", res.kind, res.cost, res.rms_normalised(), res.n_points, res.n_free).ok();
    writeln!(
        s,
        "termination: {} after {} iterations",
        res.termination, res.iterations
    )
    .ok();
    parameter_table_text(
        &mut s,
        &res.theta,
        &res.status,
        res.uncertainty.as_ref().filter(|_| res.intervals_valid()),
        mass,
    );
    if res.uncertainty.is_some() && !res.intervals_valid() {
        writeln!(
            s,
            "intervals: not shown (the fit is not trustworthy, see the first line)"
        )
        .ok();
    } else if res.uncertainty.is_none() {
        writeln!(s, "intervals: not available (J^T J singular at the optimum: some parameter is not identifiable from these data)").ok();
    }
    let jumps = predicted_jumps(data, &res.theta)?;
    writeln!(
        s,
        "\nper level: {:<10} {:>10} {:>5} {:>12} {:>14} {:>14} {:>14}",
        "level", "gamma", "sweep", "RMS [m]", "RMS a/gamma", "jump meas [Hz]", "jump model [Hz]"
    )
    .ok();
    for (l, (c, pj)) in res.levels.iter().zip(data.curves.iter().zip(&jumps)) {
        let f = |v: Option<f64>| {
            v.map(|w| format!("{:.3}", hz(w)))
                .unwrap_or_else(|| "-".into())
        };
        writeln!(
            s,
            "           {:<10} {:>10.5} {:>5} {:>12.4e} {:>14.4e} {:>14} {:>14}",
            l.level,
            l.gamma,
            if l.direction == SweepDirection::Up {
                "up"
            } else {
                "down"
            },
            l.rms,
            l.rms_normalised,
            f(c.measured_jump(2.0)),
            f(*pj)
        )
        .ok();
    }
    s.push_str(&pq_text(data, res)?);
    if res.minima.len() > 1 || res.minima.first().map_or(false, |m| m.count > 1) {
        writeln!(s, "\ndistinct local minima ({}):", res.minima.len()).ok();
        for (i, mm) in res.minima.iter().enumerate().take(20) {
            let free: Vec<String> = (0..N_PARAMS)
                .filter(|&j| res.status[j] == Status::Free)
                .map(|j| format!("{}={:.5e}", PARAM_NAMES[j], mm.theta[j]))
                .collect();
            writeln!(
                s,
                "  #{:<3} cost {:.6e}  starts {:>4}  {}  {}",
                i + 1,
                mm.cost,
                mm.count,
                mm.termination,
                free.join(" ")
            )
            .ok();
        }
    }
    Ok(s)
}

/// Phase-quadrature table (Table 8 analogue) as text.
pub fn pq_text(data: &Dataset, res: &FitResult) -> Result<String, CliError> {
    let mut s = String::new();
    writeln!(s, "\nphase quadrature (model) vs measured ({}): {:<10} {:>12} {:>12} {:>9} {:>12} {:>12} {:>9}", res.kind, "level", "f_meas [Hz]", "f_model", "diff %", "a_meas [m]", "a_model", "diff %").ok();
    for r in phase_quadrature_table(data, &res.theta)? {
        let (df, da) = r.differences_percent();
        let o =
            |v: Option<f64>, p: usize| v.map(|x| format!("{x:.p$}")).unwrap_or_else(|| "-".into());
        writeln!(
            s,
            "  ({:<5})  {:<10} {:>12.4} {:>12} {:>9} {:>12.5e} {:>12} {:>9}",
            r.measured_from,
            r.level,
            hz(r.measured_omega),
            o(r.model_omega.map(hz), 4),
            o(df, 2),
            r.measured_amplitude,
            r.model_amplitude
                .map(|a| format!("{a:.5e}"))
                .unwrap_or_else(|| "-".into()),
            o(da, 2)
        )
        .ok();
    }
    Ok(s)
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

/// The default fit: [`identify`] (equation error, landscape, output error).
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
    if let Some(p) = &args.landscape {
        targets.push(("--landscape", p));
    }
    nlsdof_io::atomic::check_targets(&targets)?;
    let landscape_kind = match &args.landscape {
        None => None,
        Some(p) => Some(super::landscape_plot::kind_of(p)?),
    };
    let data = args.data.load()?;
    let (pb, on_progress) = super::progress::stage_bar(kind.name());
    let id = identify(&data, &plan, &on_progress);
    pb.finish_and_clear();
    let id = id.map_err(|e| CliError::Usage(e.to_string()))?;
    let res = &id.fit;
    // render everything first, then commit the files
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if let Some(out) = &args.out {
        files.push((out.clone(), model_file_text(res, mass)?.into_bytes()));
    }
    if let Some(p) = &args.plot {
        files.push((p.clone(), fit_svg(&id.data, res).into_bytes()));
    }
    if let (Some(p), Some(k)) = (&args.landscape, landscape_kind) {
        files.push((p.clone(), super::landscape_plot::render(&id, k)?));
    }
    for (p, bytes) in &files {
        nlsdof_io::atomic::write_atomic(p, bytes)?;
    }
    if args.json {
        let mut v = result_json(&id.data, res, mass)?;
        v["jump_weight"] = json!(id.jump_weight);
        v["identification"] = identification_json(&id);
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
    } else {
        // the fit report first (its first line is the warning, if any),
        // then the stages that led to it
        let mut s = result_text(&id.data, res, mass)?;
        s.push('\n');
        s.push_str(&identification_text(&id));
        print!("{s}");
    }
    Ok(())
}

pub fn run(args: Args) -> Result<(), CliError> {
    use super::sign::{fit_sweep_signed, sign_trials_json, sign_trials_text, SignArg};
    // (`fit --phase-resonance` is dispatched to `phase_resonance::run_fit_verb`)
    let sign = args.pr.sign.resolve(args.pr.softening)?;
    if let Some(l) = args.jump_weight {
        if !(l.is_finite() && l >= 0.0) {
            return Err(CliError::Usage(format!(
                "--jump-weight {l} is not allowed: use a finite value >= 0"
            )));
        }
        if args.integer || sign == SignArg::Auto {
            return Err(CliError::Usage(
                "--jump-weight is not available with --integer or --sign auto".into(),
            ));
        }
    }
    if sign == SignArg::Auto && args.integer {
        return Err(CliError::Usage(
            "--sign auto is not available with --integer: choose --sign hardening or softening"
                .into(),
        ));
    }
    let kind = parse_model_kind(&args.model)?;
    if !(args.integer || sign == SignArg::Auto) {
        return run_identify(&args, kind, sign);
    }
    if args.landscape.is_some()
        || args.no_phase
        || args.phase_convention.is_some()
        || args.weighting.is_some()
    {
        return Err(CliError::Usage(
            "--landscape, --no-phase, --phase-convention and --weighting belong to the default staged fit, not to --integer or --sign auto (which fit Eq 31, absolute)".into(),
        ));
    }
    // every output can be written, and no file is named twice, before any work
    let mut targets: Vec<(&str, &Path)> = Vec::new();
    if let Some(p) = &args.out {
        targets.push(("--out", p));
    }
    if let Some(p) = &args.plot {
        targets.push(("--plot", p));
    }
    nlsdof_io::atomic::check_targets(&targets)?;
    let data = args.data.load_lag_phases()?;
    let mut spec = FitSpec::new_signed(
        kind,
        &data,
        if sign == SignArg::Softening {
            nlsdof::identification::Sign::Softening
        } else {
            nlsdof::identification::Sign::Hardening
        },
    );
    if let Some(b) = &args.bounds {
        apply_bounds(&mut spec, b)?;
    }
    let fix_mass = apply_fix_free(&mut spec, args.fix.as_deref(), args.free.as_deref())?;
    let mass = resolve_mass(args.mass, fix_mass, args.model_file.as_deref())?;
    let starts = args.starts.unwrap_or(32);
    if starts == 0 || starts > 100_000 {
        return Err(CliError::Usage(format!(
            "--starts {starts} is not allowed: use 1..=100000"
        )));
    }
    let opts = FitOptions {
        starts,
        seed: args.seed,
        ..FitOptions::default()
    };
    let mut integer_table = Vec::new();
    let mut sign_trials = Vec::new();
    let res = if args.integer {
        let (best, pairs) = best_integer_fit(&data, &spec, &opts)
            .map_err(|e| CliError::Usage(format!("--integer: {e}")))?;
        integer_table = pairs;
        best
    } else if sign == SignArg::Auto {
        let configure = |s: &mut FitSpec| -> Result<(), CliError> {
            if let Some(b) = &args.bounds {
                apply_bounds(s, b)?;
            }
            apply_fix_free(s, args.fix.as_deref(), args.free.as_deref())?;
            Ok(())
        };
        let (r, t) = fit_sweep_signed(&data, kind, sign, &configure, &opts)?;
        sign_trials = t;
        r
    } else {
        let pb = progress_bar(opts.starts, kind.name());
        let r = match args.jump_weight {
            Some(l) if l > 0.0 => {
                nlsdof::identification::fit_with_jumps(&data, &spec, &opts, l, &|| pb.inc(1))
            }
            _ => fit(&data, &spec, &opts, &|| pb.inc(1)),
        };
        pb.finish_and_clear();
        r.map_err(|e| CliError::Usage(e.to_string()))?
    };
    // render everything first, then commit the files
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if let Some(out) = &args.out {
        files.push((out.clone(), model_file_text(&res, mass)?.into_bytes()));
    }
    if let Some(p) = &args.plot {
        files.push((p.clone(), fit_svg(&data, &res).into_bytes()));
    }
    for (p, bytes) in &files {
        nlsdof_io::atomic::write_atomic(p, bytes)?;
    }
    if args.json {
        let mut v = result_json(&data, &res, mass)?;
        if let Some(t) = sign_trials_json(&sign_trials) {
            v["sign_auto"] = t;
        }
        v["jump_weight"] = json!(args.jump_weight.unwrap_or(0.0));
        if args.integer {
            v["integer_pairs"] = integer_pairs_json(&integer_table);
        }
        println!("{}", serde_json::to_string_pretty(&v).expect("json"));
    } else {
        let mut s = sign_trials_text(
            &sign_trials,
            if res.theta[BETA] < 0.0 {
                nlsdof::identification::Sign::Softening
            } else {
                nlsdof::identification::Sign::Hardening
            },
        );
        s.push_str(&result_text(&data, &res, mass)?);
        if args.integer {
            s.push_str(&integer_pairs_text(&integer_table));
        }
        print!("{s}");
    }
    Ok(())
}

/// JSON of an integer search's pairs (`--integer`).
pub fn integer_pairs_json(pairs: &[IntegerPair]) -> Value {
    Value::Array(
        pairs
            .iter()
            .map(|p| match &p.outcome {
                Ok((cost, t)) => {
                    json!({"rho": p.rho, "eta": p.eta, "cost": cost, "termination": t.name()})
                }
                Err(e) => json!({"rho": p.rho, "eta": p.eta, "error": e}),
            })
            .collect(),
    )
}

/// Text of an integer search's pairs (`--integer`).
pub fn integer_pairs_text(pairs: &[IntegerPair]) -> String {
    let mut s = String::from("\ninteger exponent pairs (rho, eta): cost\n");
    let show = |v: Option<i64>| v.map_or_else(|| "null".to_string(), |v| v.to_string());
    for p in pairs {
        let outcome = match &p.outcome {
            Ok((cost, _)) => format!("{cost:.6e}"),
            Err(e) => Value::String(e.clone()).to_string(),
        };
        writeln!(s, "  ({}, {}): {outcome}", show(p.rho), show(p.eta)).ok();
    }
    s
}
