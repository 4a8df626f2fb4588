//! `nlsdof inspect`: what stepped-sine data say before any model is fitted
//! (library: `nlsdof::identification::inspect`). Reads every stepped-sine
//! input `fit` reads (`fit`'s [`DataArgs`]).

use super::fit::{parse_phase_convention, DataArgs};
use crate::error::CliError;
use nlsdof::identification::inspect::{inspect, InspectOptions, PhaseUse, DEFAULT_JUMP_RATIO};
use nlsdof_report::figure_file::figure_format;
use nlsdof_report::inspect::{inspect_figure, inspect_json, inspect_text, PLOT_FORMATS};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    about = "What stepped-sine curves say before any fit: resonance, damping and jumps per level, homogeneity against the noise, model-free stiffness and damping laws, the model to fit",
    after_long_help = INSPECT_HELP
)]
pub struct Args {
    #[command(flatten)]
    pub data: DataArgs,
    /// Print the result as JSON (SI units; frequencies in rad/s and Hz).
    #[arg(long)]
    pub json: bool,
    /// Write the one-page figure: FILE.svg or FILE.png (normalised curves, backbone with its
    /// fit, damping against velocity amplitude with its fit).
    #[arg(long, value_name = "FILE.svg|png")]
    pub plot: Option<PathBuf>,
    /// Do not use the phase columns (resonance points are then amplitude peaks).
    #[arg(long = "no-phase", conflicts_with = "phase_convention")]
    pub no_phase: bool,
    /// State the phase convention instead of detecting it: lag|lead,OFFSET_DEG[,DELAY_S]
    /// (measured phase = +-lag + offset + 2 pi f delay), as for `fit`.
    #[arg(
        long = "phase-convention",
        value_name = "lag|lead,OFFSET_DEG[,DELAY_S]",
        allow_hyphen_values = true
    )]
    pub phase_convention: Option<String>,
    /// Smallest step-to-step amplitude ratio read as a jump (> 1; the step must also stand
    /// out from the steps the other way along the curve).
    #[arg(long = "min-jump-ratio", value_name = "R", default_value_t = DEFAULT_JUMP_RATIO)]
    pub min_jump_ratio: f64,
}

const INSPECT_HELP: &str = "WHAT IT DOES
  Reads the stepped-sine curves as `nlsdof fit` does (long CSV or --beam-dir) and, without
  fitting any model to them, reports what they say. SI units: gamma in m/s^2 and amplitudes
  in m, both zero-to-peak; frequencies in Hz (rad/s in JSON beside them). Notation is
  mass-normalised: alpha = k/m, delta = c/m, beta = k_r/m, kappa = c_e/m.

THE FIRST LINE is the verdict: linear within the noise, or the nonlinear terms with their
  exponents and 95 % intervals, and the `nlsdof fit --model` to start from.

PER CURVE
  peak       the largest amplitude, refined by a local fit of 1/a^2 against Omega^2 (a
             parabola for a linear SDoF: gamma^2/a^2 = (alpha - Omega^2)^2 + delta^2 Omega^2),
             with the backbone's lean taken out; on a sweep that jumps down, the last point
             before the jump; after a jump up, a fold (not used); at the band edge, the band
             misses the resonance (not used).
  f_90       where the phase lag crosses 90 deg (with phases): the curve meets the backbone.
             The phase convention is detected from the ends of the curves (the lag turns by
             180 deg across a resonance), or given with --phase-convention.
  damping    zeta and delta = 2 zeta omega_n from the half-power width (no jump, both -3 dB
             points in the band; exact for a linear SDoF), else from the phase slope at
             90 deg, d phi/d Omega = 2/delta = 1/(zeta omega_n).
  jump       a step whose amplitude ratio stands out (drop: the branch ended; rise: landed
             on the upper branch); EARLY marks a sweep that left its branch before the
             backbone says its fold would be (its level is left out of the laws).
  noise      the local noise of the amplitudes from the data alone (pseudo-residuals).

RESONANCE POINT PER LEVEL
  the 90 deg point where a curve of the level has one, else the peak (peaks are moved to the
  backbone: Omega_bb^2 = Omega_p^2 + delta_eq (delta_0 + (1 + eta) c_eq)/2). At resonance the
  first-order harmonic balance gives
      delta_eq = gamma / (a_r Omega_r) = delta + g(eta) kappa (Omega_r a_r)^eta   (Eq 22)
      Omega_r^2 = alpha + g(rho) beta a_r^rho                                  (Eq 9, 30)
  with g(mu) = 2 Gamma((3+mu)/2) / (sqrt(pi) Gamma(2+mu/2)) (Eq 12/24).

HOMOGENEITY
  linearity index = sqrt((chi2(a_r/gamma) + chi2(Omega_r)) / (2 (L - 1))): the spread of the
  normalised peaks and of the resonance frequencies across the L levels in units of what the
  noise allows. About 1: linear within the noise; compared with its 99.9 % point.

STIFFNESS AND DAMPING LAWS
  Omega_r^2 - omega_0^2 = g(rho) beta a_r^rho and delta_eq - delta_0 = g(eta) kappa V^eta
  (V = Omega_r a_r, m/s) fitted across the levels with the noise of each point (errors in
  both coordinates), omega_0 and delta_0 extrapolated to zero amplitude. 95 % intervals of
  rho and eta by profile likelihood with the Student t quantile of L - 3 degrees of
  freedom: three levels give the exponents without an interval, four or more with one.
  Coulomb friction shows as eta = -1 (Eq 27-28); quadratic damping as eta = 1; Duffing as
  rho = 2. An exponent is pinned when its interval is within +-0.25.

RECOMMENDATION
  model family (linear, Duffing-like, generalised), stiffness sign, damping kind, the
  evidence for each, the pinned exponents, the levels that carry the nonlinearity, and
  warnings: too few levels, a band that misses the resonance, sweeps that left their branch
  early, a linearity index at the noise.

EXAMPLES
  nlsdof inspect --beam-dir ../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C
  nlsdof inspect data.csv --gamma-in-g --json --plot inspect.svg";

pub fn run(a: Args) -> Result<(), CliError> {
    if !(a.min_jump_ratio.is_finite() && a.min_jump_ratio > 1.0) {
        return Err(CliError::Usage(format!(
            "--min-jump-ratio {} is not allowed: use a finite ratio > 1",
            a.min_jump_ratio
        )));
    }
    let plot = match &a.plot {
        Some(p) => {
            let f = figure_format("--plot", p, &PLOT_FORMATS)?;
            nlsdof_io::atomic::check_targets(&[("--plot", p)])?;
            Some((p.clone(), f))
        }
        None => None,
    };
    let phase = if a.no_phase {
        PhaseUse::Ignore
    } else if let Some(c) = &a.phase_convention {
        PhaseUse::Known(parse_phase_convention(c)?)
    } else {
        PhaseUse::Auto
    };
    let data = a.data.load()?;
    let source = a.data.source_name();
    let t_an = Instant::now();
    let opts = InspectOptions {
        phase,
        min_jump_ratio: a.min_jump_ratio,
    };
    let r = inspect(&data, &opts).map_err(|e| CliError::Usage(format!("{source}: {e}")))?;
    let seconds = t_an.elapsed().as_secs_f64();
    if let Some((p, f)) = &plot {
        nlsdof_io::atomic::write_atomic(p, &inspect_figure(&data, &r, *f)?)?;
    }
    if a.json {
        let v = inspect_json(&source, &r, seconds)?;
        println!(
            "{}",
            serde_json::to_string_pretty(&v).map_err(|e| CliError::Usage(e.to_string()))?
        );
    } else {
        print!("{}", inspect_text(&source, &r));
    }
    Ok(())
}
