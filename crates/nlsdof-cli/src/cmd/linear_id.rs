//! `nlsdof linear-id`: linear system identification of a measured FRF by
//! fast relaxed vector fitting (paper Section 2.3, Table 3), with the
//! half-power and circle-fit estimates beside it, and the SDoF linear part
//! written as a model file.

use crate::error::CliError;
use nlsdof::vector_fitting::{
    identify_sdof, mobility, CircleFit, FrfWeighting, InputKind, MassSource, MeasuredFrf,
    OutputKind, PoleCount, SdofIdError, SdofIdOptions, SdofIdentification, SdofLinear, C64,
};
use nlsdof::Model;
use nlsdof_figure::{self as figure, colour, Panel, Series, Style};
use serde_json::json;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InputArg {
    /// Force, N (m, c, k identifiable).
    Force,
    /// Base acceleration, m/s^2 (only k/m and c/m unless --mass is given).
    Acceleration,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OutputArg {
    Displacement,
    Velocity,
    Acceleration,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum WeightArg {
    /// All frequencies weigh the same.
    Uniform,
    /// Weight 1/|H| (relative error; stresses low-magnitude regions).
    Inverse,
}

#[derive(clap::Args)]
#[command(
    about = "Identify the linear part (m, c, k or k/m, c/m) from a measured FRF by fast relaxed vector fitting",
    after_long_help = LONG_HELP
)]
pub struct Args {
    /// FRF table (CSV: f_hz,re,im or f_hz,mag[,phase_deg]; see FRF FILE below).
    #[arg(value_name = "FRF.csv")]
    pub frf: PathBuf,
    /// Number of complex pole pairs, or `auto` (add pairs while the RMS error falls by > 10 %).
    #[arg(long, value_name = "N|auto", default_value = "auto")]
    pub poles: String,
    /// Largest number of pole pairs tried by --poles auto.
    #[arg(long = "max-poles", value_name = "N", default_value_t = 20)]
    pub max_poles: usize,
    /// Excitation quantity of the FRF.
    #[arg(long, value_enum, default_value_t = InputArg::Acceleration)]
    pub input: InputArg,
    /// Response quantity of the FRF (relative to the base for base excitation).
    #[arg(long, value_enum, default_value_t = OutputArg::Displacement)]
    pub output: OutputArg,
    /// Known mass, kg (> 0): gives m, k, c for acceleration input; overrides the residue mass for force input.
    #[arg(long, value_name = "KG", allow_hyphen_values = true)]
    pub mass: Option<f64>,
    /// Mode (1-based, by natural frequency) taken as the SDoF; default the one with the highest peak.
    #[arg(long, value_name = "K")]
    pub mode: Option<usize>,
    /// Use only frequencies >= F0 Hz.
    #[arg(long = "f-min", value_name = "F0", allow_hyphen_values = true)]
    pub f_min: Option<f64>,
    /// Use only frequencies <= F1 Hz.
    #[arg(long = "f-max", value_name = "F1", allow_hyphen_values = true)]
    pub f_max: Option<f64>,
    /// Fit without the constant term d.
    #[arg(long = "no-constant")]
    pub no_constant: bool,
    /// Also fit the proportional term s e.
    #[arg(long)]
    pub proportional: bool,
    /// Frequency weighting of the least-squares fit.
    #[arg(long, value_enum, default_value_t = WeightArg::Uniform)]
    pub weight: WeightArg,
    /// Iteration limit of the vector fitting (1 to 10000).
    #[arg(long = "max-iterations", value_name = "N", default_value_t = 30)]
    pub max_iterations: usize,
    /// Write the SDoF linear part as a model file (TOML) to FILE.
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Print JSON instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// Write an SVG plot: measured vs fitted magnitude and phase, and the Nyquist plot with the fitted circle.
    #[arg(long, value_name = "FIG.svg")]
    pub plot: Option<PathBuf>,
}

const LONG_HELP: &str = "DESCRIPTION:
  Fits H(s) = sum_n r_n/(s - a_n) + d [+ s e], s = j 2 pi f, to a measured complex FRF by
  fast relaxed vector fitting (Gustavsen & Semlyen 1999; relaxed: Gustavsen 2006; fast QR
  form: Deschrijver et al. 2008): complex starting poles spread over the band, relocated by
  linear least squares (QR) as the zeros of the weighting function sigma, unstable poles
  flipped, frequencies normalised by the highest one. It stops when the poles change by
  less than 1e-11 (relative), the RMS error stops changing (noise floor) or reaches
  round-off, or after --max-iterations; the text output lists the RMS error per iteration.

  Each complex pole pair a = -zeta w_n + j w_n sqrt(1 - zeta^2) gives the natural frequency
  f_n = |a|/(2 pi), the damping ratio zeta = -Re a/|a| and the residue r. The SDoF linear
  part of the model  m x'' + c x' + k x = m gamma  comes from the chosen mode:
    alpha = k/m = w_n^2,  delta = c/m = 2 zeta w_n          (poles only)
    --input force:         m = 1/|G|, G = 2 j w_d r_x (modal mass at the measurement point)
    --input acceleration:  m is NOT identifiable; only alpha and delta, unless --mass M
  where r_x = r / a^p is the displacement residue (p = 0, 1, 2 for --output displacement,
  velocity, acceleration). The half-power bandwidth and a circle (Nyquist) fit of the
  mobility are printed beside the vector-fitting result for comparison; an amplitude-only
  FRF (no phase) gets the half-power estimate only.

FRF FILE:
  CSV with a header: f_hz and either re,im or mag[,phase_deg] (coherence optional),
  frequencies in Hz strictly increasing; `nlsdof frf-estimate` writes this format.

MODEL FILE (--out):
  mass, stiffness, damping of the chosen mode (no nonlinear terms). With acceleration input
  and no --mass the file holds mass = 1 kg, stiffness = alpha, damping = delta, and says so
  in a comment: every response to a base acceleration depends only on k/m and c/m.

EXAMPLES:
  nlsdof linear-id sweep.csv --input acceleration --out linear.toml
  nlsdof linear-id impact.csv --input force --output velocity --f-min 100 --f-max 200 \\
      --poles 1 --json --plot impact.svg

Errors are one line on stderr, exit code 2; no output file is left behind.";

fn usage(msg: String) -> CliError {
    CliError::Usage(msg)
}

pub fn run(args: Args) -> Result<(), CliError> {
    crate::plot::check_svg_name(args.plot.as_deref())?;
    if args.max_iterations == 0 || args.max_iterations > 10_000 {
        return Err(usage(format!(
            "--max-iterations {}: need 1 to 10000 vector-fitting iterations",
            args.max_iterations
        )));
    }
    let table = nlsdof_io::frf_file::read_frf_csv(&args.frf)?;
    let f_lo = args.f_min.unwrap_or(f64::NEG_INFINITY);
    let f_hi = args.f_max.unwrap_or(f64::INFINITY);
    if f_lo.is_nan() || f_hi.is_nan() || f_lo >= f_hi {
        return Err(usage(format!(
            "--f-min {f_lo} / --f-max {f_hi}: need f-min < f-max"
        )));
    }
    if let Some(m) = args.mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(usage(format!("--mass {m}: must be finite and > 0 kg")));
        }
    }
    let in_band = |f: f64| f >= f_lo && f <= f_hi;
    // --poles matters (and is checked) only where vector fitting runs.
    let poles = match parse_poles(&args.poles, args.max_poles) {
        Ok(p) => p,
        Err(e) if table.values.is_some() && table.f_hz.iter().any(|&f| in_band(f)) => {
            return Err(e)
        }
        Err(_) => PoleCount::Fixed(1),
    };
    let output = match args.output {
        OutputArg::Displacement => OutputKind::Displacement,
        OutputArg::Velocity => OutputKind::Velocity,
        OutputArg::Acceleration => OutputKind::Acceleration,
    };
    let frf = MeasuredFrf {
        omega: table.f_hz.iter().map(|f| 2.0 * PI * f).collect(),
        magnitude: table.magnitude.clone(),
        values: table
            .values
            .as_ref()
            .map(|v| v.iter().map(|&(re, im)| C64::new(re, im)).collect()),
    };
    let opts = SdofIdOptions {
        band: (2.0 * PI * f_lo, 2.0 * PI * f_hi),
        poles,
        input: match args.input {
            InputArg::Force => InputKind::Force,
            InputArg::Acceleration => InputKind::Acceleration,
        },
        output,
        mass: args.mass,
        mode: args.mode,
        constant: !args.no_constant,
        proportional: args.proportional,
        weighting: match args.weight {
            WeightArg::Uniform => FrfWeighting::Uniform,
            WeightArg::Inverse => FrfWeighting::Inverse,
        },
        max_iterations: args.max_iterations,
    };
    let id = identify_sdof(&frf, &opts).map_err(|e| match e {
        SdofIdError::EmptyBand { .. } => usage(format!("no FRF point in [{f_lo}, {f_hi}] Hz")),
        SdofIdError::HalfPowerFailed(e) => usage(format!(
            "{}: amplitude-only FRF and the half-power method failed: {e}",
            args.frf.display()
        )),
        SdofIdError::Fit(e) => e.into(),
    })?;
    let f_hz: Vec<f64> = id.points.iter().map(|&i| table.f_hz[i]).collect();
    let SdofLinear {
        alpha,
        delta,
        mass,
        mass_source: source,
    } = id.sdof;

    // Build everything before writing anything.
    let model_text = if args.out.is_some() {
        let m = mass.unwrap_or(1.0);
        let model = Model::linear(m, m * alpha, m * delta)?;
        let mut s = format!(
            "# Linear part identified by `nlsdof linear-id` from {}\n# alpha = k/m = {alpha:?} 1/s^2, delta = c/m = {delta:?} 1/s\n",
            args.frf.display()
        );
        s += match source {
            MassSource::Residue => "# mass from the residue of the force-input FRF (modal mass at the measurement point)\n",
            MassSource::Given => "# mass given with --mass\n",
            MassSource::Unidentified => {
                "# mass NOT identifiable from a base-acceleration FRF: m = 1 kg placeholder, so stiffness = k/m and\n# damping = c/m; every response to a base acceleration depends only on these ratios.\n"
            }
        };
        s += &nlsdof_io::model_file::model_to_toml(&model);
        Some(s)
    } else {
        None
    };
    let svg = match &args.plot {
        Some(_) => Some(render(&id, &f_hz, output)?),
        None => None,
    };
    let text = if args.json {
        json_report(&id, &f_hz, alpha, delta, mass, source)
    } else {
        text_report(&id, &f_hz, &args, alpha, delta, mass, source)
    };
    if let (Some(path), Some(s)) = (&args.out, &model_text) {
        nlsdof_io::atomic::write_atomic(path, s.as_bytes())?;
    }
    if let (Some(path), Some(s)) = (&args.plot, &svg) {
        // Committed together with --out at the end of the run (all or nothing).
        nlsdof_io::atomic::write_atomic(path, s.as_bytes())?;
    }
    print!("{text}");
    Ok(())
}

/// The linear part as an `nlsdof fit --fix` value.
fn fix_argument(alpha: f64, delta: f64, mass: Option<f64>) -> String {
    let mut s = format!("alpha={alpha:?},delta={delta:?}");
    if let Some(m) = mass {
        s += &format!(",m={m:?}");
    }
    s
}

fn source_name(s: MassSource) -> &'static str {
    match s {
        MassSource::Residue => "residue",
        MassSource::Given => "given",
        MassSource::Unidentified => "not identifiable",
    }
}

fn c(z: C64) -> serde_json::Value {
    json!([z.re, z.im])
}

fn json_report(
    id: &SdofIdentification,
    f_hz: &[f64],
    alpha: f64,
    delta: f64,
    mass: Option<f64>,
    source: MassSource,
) -> String {
    let fit = id.fit.as_ref().map(|f| {
        json!({
            "pole_pairs": id.modes.len(),
            "order": f.order(),
            "iterations": f.iterations,
            "termination": f.termination.to_string(),
            "rms_history": f.rms_history,
            "rms_error": f.rms_error,
            "relative_rms_error": f.relative_rms_error,
            "constant": f.constant,
            "proportional": f.proportional,
            "auto_order_history": id.auto_history.iter().map(|(n, r)| json!({"pole_pairs": n, "rms_error": r})).collect::<Vec<_>>(),
            "real_poles": f.terms.iter().filter(|t| !t.is_pair()).map(|t| json!({"pole": t.pole.re, "residue": t.residue.re})).collect::<Vec<_>>(),
        })
    });
    let modes: Vec<_> = id
        .modes
        .iter()
        .map(|m| json!({"f_n_hz": m.frequency_hz, "zeta": m.zeta, "pole": c(m.pole), "residue": c(m.residue), "peak": m.peak}))
        .collect();
    let lp = id.linear.as_ref().map(|l| {
        json!({"mode": id.chosen.map(|i| i + 1), "gain": c(l.gain), "complexity_deg": l.complexity.to_degrees(), "residue_mass": l.residue_mass})
    });
    let hp = match &id.half_power {
        Ok(h) => {
            json!({"f_n_hz": h.omega_n / (2.0 * PI), "zeta": h.zeta, "f_low_hz": h.omega_low / (2.0 * PI), "f_high_hz": h.omega_high / (2.0 * PI)})
        }
        Err(e) => json!({"error": e.to_string()}),
    };
    let cf = match circle_result(id) {
        Ok(c) => {
            json!({"f_n_hz": c.omega_n / (2.0 * PI), "zeta": c.zeta, "diameter": 2.0 * c.radius, "points": c.points, "relative_residual": c.relative_residual})
        }
        Err(e) => json!({"error": e}),
    };
    let out = json!({
        "points": f_hz.len(),
        "vector_fitting": fit,
        "modes": modes,
        "sdof": {
            "alpha": alpha, "delta": delta,
            "f_n_hz": alpha.sqrt() / (2.0 * PI), "zeta": delta / (2.0 * alpha.sqrt()),
            "mass": mass, "stiffness": mass.map(|m| m * alpha), "damping": mass.map(|m| m * delta),
            "mass_source": source_name(source),
            "fix_argument": fix_argument(alpha, delta, mass),
            "from_vector_fitting": lp,
        },
        "half_power": hp,
        "circle_fit": cf,
    });
    format!("{out}\n")
}

fn text_report(
    id: &SdofIdentification,
    f_hz: &[f64],
    args: &Args,
    alpha: f64,
    delta: f64,
    mass: Option<f64>,
    source: MassSource,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "FRF {}: {} points, {:.6} .. {:.6} Hz",
        args.frf.display(),
        f_hz.len(),
        f_hz[0],
        f_hz[f_hz.len() - 1]
    );
    if let Some(f) = &id.fit {
        if !id.auto_history.is_empty() {
            let h: Vec<String> = id
                .auto_history
                .iter()
                .map(|(n, r)| format!("{n}:{r:.3e}"))
                .collect();
            let _ = writeln!(
                s,
                "model order (pole pairs: RMS error): {}  -> {} pair(s)",
                h.join("  "),
                id.modes.len()
            );
        }
        let _ = writeln!(
            s,
            "vector fitting: {} pole(s), {} iteration(s), {}",
            f.order(),
            f.iterations,
            f.termination
        );
        let h: Vec<String> = f.rms_history.iter().map(|r| format!("{r:.3e}")).collect();
        let _ = writeln!(s, "  RMS error per iteration: {}", h.join(" "));
        let _ = writeln!(
            s,
            "  final RMS error {:.4e} ({:.3e} of the RMS FRF)",
            f.rms_error, f.relative_rms_error
        );
        let _ = writeln!(
            s,
            "   #     f_n [Hz]         zeta       residue (rad/s units)"
        );
        for (i, m) in id.modes.iter().enumerate() {
            let mark = if Some(i) == id.chosen { "*" } else { " " };
            let _ = writeln!(
                s,
                "{mark}{:>3} {:>12.6} {:>12.6e}   {:+.6e} {:+.6e}j",
                i + 1,
                m.frequency_hz,
                m.zeta,
                m.residue.re,
                m.residue.im
            );
        }
        for t in f.terms.iter().filter(|t| !t.is_pair()) {
            let _ = writeln!(
                s,
                "  real pole {:.6e} rad/s, residue {:.6e}",
                t.pole.re, t.residue.re
            );
        }
    } else {
        let _ = writeln!(
            s,
            "amplitude-only FRF: vector fitting needs the phase; using the half-power estimate"
        );
    }
    let wn = alpha.sqrt();
    let _ = writeln!(
        s,
        "SDoF linear part{}:",
        id.chosen
            .map(|i| format!(" (mode {})", i + 1))
            .unwrap_or_default()
    );
    let _ = writeln!(
        s,
        "  f_n = {:.6} Hz, zeta = {:.6e}",
        wn / (2.0 * PI),
        delta / (2.0 * wn)
    );
    let _ = writeln!(
        s,
        "  alpha = k/m = {alpha:.6e} 1/s^2, delta = c/m = {delta:.6e} 1/s"
    );
    match mass {
        Some(m) => {
            let _ = writeln!(
                s,
                "  m = {m:.6e} kg ({}), k = {:.6e} N/m, c = {:.6e} N s/m",
                source_name(source),
                m * alpha,
                m * delta
            );
        }
        None => {
            let _ = writeln!(
                s,
                "  m, k, c: mass not identifiable from a base-acceleration FRF (give --mass)"
            );
        }
    }
    let _ = writeln!(
        s,
        "  for `nlsdof fit`: --fix {}",
        fix_argument(alpha, delta, mass)
    );
    if let Some(l) = &id.linear {
        let _ = writeln!(
            s,
            "  modal gain G = {:.6e} {:+.6e}j (complexity {:.2} deg)",
            l.gain.re,
            l.gain.im,
            l.complexity.to_degrees()
        );
    }
    match &id.half_power {
        Ok(h) => {
            let _ = writeln!(
                s,
                "half-power: f_n = {:.6} Hz, zeta = {:.6e} (mobility, band {:.6} .. {:.6} Hz)",
                h.omega_n / (2.0 * PI),
                h.zeta,
                h.omega_low / (2.0 * PI),
                h.omega_high / (2.0 * PI)
            );
        }
        Err(e) => {
            let _ = writeln!(s, "half-power: n/a ({e})");
        }
    }
    match circle_result(id) {
        Ok(c) => {
            let _ = writeln!(s, "circle fit: f_n = {:.6} Hz, zeta = {:.6e} ({} points, residual {:.2e} of the radius)", c.omega_n / (2.0 * PI), c.zeta, c.points, c.relative_residual);
        }
        Err(e) => {
            let _ = writeln!(s, "circle fit: n/a ({e})");
        }
    }
    if let Some(p) = &args.out {
        let _ = writeln!(s, "model written to {}", p.display());
    }
    if let Some(p) = &args.plot {
        let _ = writeln!(s, "plot written to {}", p.display());
    }
    s
}

/// The circle fit, or why there is none.
fn circle_result(id: &SdofIdentification) -> Result<&CircleFit, String> {
    match &id.circle {
        Some(Ok(c)) => Ok(c),
        Some(Err(e)) => Err(e.to_string()),
        None => Err("needs the phase (complex FRF)".into()),
    }
}

/// `--poles N|auto`.
fn parse_poles(s: &str, max_pairs: usize) -> Result<PoleCount, CliError> {
    if s.eq_ignore_ascii_case("auto") {
        return Ok(PoleCount::Auto { max_pairs });
    }
    let n: usize = s.parse().ok().filter(|&n| n >= 1).ok_or_else(|| {
        usage(format!(
            "--poles {s:?}: expected a number of pole pairs >= 1 or `auto`"
        ))
    })?;
    Ok(PoleCount::Fixed(n))
}

/// SVG: |H| (log) and phase vs frequency, measured points and fitted curve;
/// Nyquist plot of the mobility with the fitted model and the circle fit.
fn render(id: &SdofIdentification, f_hz: &[f64], output: OutputKind) -> Result<String, CliError> {
    let (blue, red, green) = (colour(0), colour(1), colour(2));
    let (f0, f1) = (f_hz[0], f_hz[f_hz.len() - 1]);
    let (f0, f1) = if f1 > f0 {
        (f0, f1)
    } else {
        (f0 - 0.5, f0 + 0.5)
    };
    let nf = 800;
    let fit_curve: Vec<(f64, C64)> = match &id.fit {
        Some(fit) => (0..=nf)
            .map(|i| f0 + (f1 - f0) * i as f64 / nf as f64)
            .map(|f| (f, fit.eval(2.0 * PI * f)))
            .collect(),
        None => vec![],
    };
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let mut mags: Vec<f64> = id.magnitude.iter().copied().filter(|&v| pos(v)).collect();
    mags.extend(fit_curve.iter().map(|p| p.1.norm()).filter(|&v| pos(v)));
    let lo = mags.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = mags.iter().copied().fold(0.0, f64::max);
    let (lo, hi) = if lo < hi {
        (lo / 1.5, hi * 1.5)
    } else {
        (1e-12, 1.0)
    };
    let mut mag = Panel::new(
        "Measured (points) and fitted (line) FRF",
        "Frequency [Hz]",
        "|H|",
    );
    mag.log_y = true;
    mag.x_range = Some((f0, f1));
    mag.y_range = Some((lo, hi));
    mag.series.push(
        Series::new(
            f_hz.iter()
                .copied()
                .zip(id.magnitude.iter().copied())
                .collect(),
            blue,
            Style::Dots(2),
        )
        .label("measured"),
    );
    let mut phase = Panel::new("Phase", "Frequency [Hz]", "Phase [deg]");
    phase.x_range = Some((f0, f1));
    phase.y_range = Some((-180.0, 180.0));
    if let Some(h) = &id.values {
        phase.series.push(Series::new(
            f_hz.iter()
                .zip(h)
                .map(|(&f, z)| (f, z.arg().to_degrees()))
                .collect(),
            blue,
            Style::Dots(2),
        ));
    }
    if !fit_curve.is_empty() {
        mag.series.push(
            Series::new(
                fit_curve
                    .iter()
                    .map(|&(f, z)| (f, z.norm().max(lo)))
                    .collect(),
                red,
                Style::Line(2),
            )
            .label("vector fit"),
        );
        phase.series.push(Series::new(
            fit_curve
                .iter()
                .map(|&(f, z)| (f, z.arg().to_degrees()))
                .collect(),
            red,
            Style::Filled(1),
        ));
    }
    // Nyquist of the mobility.
    let mob = |w: f64, z: C64| mobility(w, z, output);
    let meas: Vec<C64> = match &id.values {
        Some(h) => id.omega.iter().zip(h).map(|(&w, &z)| mob(w, z)).collect(),
        None => vec![],
    };
    let fitted: Vec<C64> = fit_curve
        .iter()
        .map(|&(f, z)| mob(2.0 * PI * f, z))
        .collect();
    let mut circle: Vec<C64> = vec![];
    if let Some(Ok(c)) = &id.circle {
        circle = (0..=200)
            .map(|i| c.center + C64::from_polar(c.radius, 2.0 * PI * i as f64 / 200.0))
            .collect();
    }
    let ext = meas
        .iter()
        .chain(&fitted)
        .chain(&circle)
        .map(|z| z.re.abs().max(z.im.abs()))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let ext = if ext > 0.0 { ext * 1.1 } else { 1.0 };
    let mut nyquist = Panel::new("Nyquist (mobility): data, fit, circle", "Re", "Im");
    nyquist.x_range = Some((-ext, ext));
    nyquist.y_range = Some((-ext, ext));
    let pts = |v: &[C64]| v.iter().map(|z| (z.re, z.im)).collect::<Vec<_>>();
    nyquist
        .series
        .push(Series::new(pts(&meas), blue, Style::Dots(2)).label("data"));
    if !fitted.is_empty() {
        nyquist
            .series
            .push(Series::new(pts(&fitted), red, Style::Line(2)).label("fit"));
    }
    if !circle.is_empty() {
        nyquist
            .series
            .push(Series::new(pts(&circle), green, Style::Line(1)).label("circle fit"));
    }
    Ok(figure::render(
        "Linear identification",
        &[mag, phase, nyquist],
        3,
        400,
        600,
    )?)
}
