//! `nlsdof roots`: every steady state at one input level and frequency.
//!
//! Also home of the small helpers shared by the response verbs (`roots`,
//! `frf`): the `--formulation` flag, model loading, value checks and the
//! conventions paragraph of the long help.

use crate::error::CliError;
use nlsdof::{ForcedResponse, Formulation, Model};
use nlsdof_report::steady_state as report;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// `--formulation` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormulationArg {
    /// Exact first-order harmonic balance (default).
    Hb,
    /// The paper's near-resonance form, Eq 30 (an approximation of `hb`).
    Modulation,
}

impl FormulationArg {
    pub fn to_core(self) -> Formulation {
        match self {
            FormulationArg::Hb => Formulation::HarmonicBalance,
            FormulationArg::Modulation => Formulation::Modulation,
        }
    }
    pub fn description(self) -> &'static str {
        report::formulation_description(self.to_core())
    }
}

/// The model equation and the unit conventions, for the long help of the
/// response verbs.
pub fn conventions_help() -> &'static str {
    "MODEL (SI units):
    m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma cos(2 pi f t)
  m     mass, kg
  k     linear stiffness, N/m
  c     viscous damping, N s/m
  k_r   power-law stiffness coefficient, N/m^(rho+1); exponent rho > -3
        (rho = 2 is Duffing; k_r < 0 is softening)
  c_e   power-law damping coefficient, N (s/m)^(eta+1), >= 0; exponent eta > -3
        (eta = 1 quadratic damping; eta = -1 Coulomb friction of force c_e, N)
  Steady states x = a cos(2 pi f t - phi) come from first-order harmonic balance with
  the equivalent coefficients k_eq = g(rho) k_r a^rho (Eq 9) and
  c_eq = g(eta) c_e (2 pi f a)^eta (Eq 22); see `nlsdof equiv`.

MODEL FILE (TOML):
  mass = 1.0
  stiffness = 3947.84
  damping = 1.2566
  [nonlinear_stiffness]      # optional
  coefficient = 1.2e7        # k_r
  exponent = 2.0             # rho
  [nonlinear_damping]        # optional
  coefficient = 0.01591      # c_e
  exponent = 3.0             # eta

UNITS AND CONVENTIONS:
  gamma    input acceleration amplitude, m/s^2, ZERO-TO-PEAK
           (the paper quotes peak-to-peak levels = 2 gamma)
  a        displacement amplitude, m, zero-to-peak
  f        frequency, Hz (the library works with Omega = 2 pi f in rad/s)
  phase    lag of x behind the input, degrees in [0, 180]; 90 at phase
           quadrature, where the response curve crosses the backbone
  stable   slow-flow stability of the steady state; a stepped-sine test can
           only settle on stable states

FORMULATIONS (--formulation):
  hb           exact first-order harmonic balance (default)
  modulation   the paper's near-resonance form, Eq 30: an approximation of hb
               whose error grows away from resonance and with damping"
}

/// After-help of `nlsdof --help`: conventions and a first example per verb.
pub fn top_level_help() -> String {
    format!(
        "{}

EXAMPLES:
  nlsdof equiv --mu 2
  nlsdof roots --model examples/duffing-strong.toml --gamma 2 --f-hz 12.5
  nlsdof frf --model examples/har-wing.toml --gamma 0.41,0.62,0.81,1.00,1.23 \\
      --f-min 5.2 --f-max 5.6 --steps 200 --plot wing.svg

Every error is one line on stderr starting `nlsdof: error:`, exit code 2, and no output
file is left behind. `nlsdof <COMMAND> --help` explains each command.",
        conventions_help()
    )
}

/// Reads and validates a model file (the model alone: for its mass, or
/// where no level is involved). The message always fits on one line.
pub fn load_model(path: &Path) -> Result<Model, CliError> {
    Ok(load_document(path)?.model)
}

/// Reads and validates a whole model file: model, `[signal]`, `[provenance]`.
pub fn load_document(path: &Path) -> Result<nlsdof_io::model_file::ModelDocument, CliError> {
    nlsdof_io::model_file::read_document(path).map_err(|e| {
        let msg = e.to_string();
        if msg.contains('\n') {
            CliError::Usage(msg.split_whitespace().collect::<Vec<_>>().join(" "))
        } else {
            CliError::Io(e)
        }
    })
}

/// A model file for a steady-state command: the model and the input gain
/// its `[signal]` table applies to the levels (1 without one). Refuses, in
/// one line naming the key, what a harmonic balance about zero cannot apply:
/// a non-zero `input_offset` (a static force) or a negative `input_gain`.
pub fn load_steady_model(path: &Path) -> Result<(Model, f64), CliError> {
    let doc = load_document(path)?;
    let gain = doc
        .signal_or_identity()
        .steady_state_gain()
        .map_err(|why| CliError::Usage(format!("{}: {why}", path.display())))?;
    Ok((doc.model, gain))
}

/// The note a steady-state command prints when the model file's gain is
/// not 1: the levels it reports are the user's, the model sees them scaled.
pub fn gain_note(gain: f64) -> Option<String> {
    (gain != 1.0).then(|| {
        format!("model file [signal] input_gain = {gain}: the model sees input_gain * gamma; levels below are as given")
    })
}

/// A text report with [`gain_note`] as its second line (after the model line).
pub fn with_gain_note(text: String, gain: f64) -> String {
    match gain_note(gain) {
        Some(note) => {
            let (first, rest) = text.split_once('\n').unwrap_or((&text, ""));
            format!("{first}\n{note}\n{rest}")
        }
        None => text,
    }
}

/// An input level: finite and > 0.
pub fn check_gamma(gamma: f64) -> Result<f64, CliError> {
    if gamma.is_finite() && gamma > 0.0 {
        Ok(gamma)
    } else {
        Err(CliError::Usage(format!(
            "--gamma {gamma} is not allowed: the input level gamma (m/s^2, zero-to-peak) must be a finite number > 0"
        )))
    }
}

/// A frequency option (`flag`, Hz): finite and > 0.
pub fn check_frequency(flag: &str, f: f64) -> Result<f64, CliError> {
    if f.is_finite() && f > 0.0 {
        Ok(f)
    } else {
        Err(CliError::Usage(format!(
            "{flag} {f} is not allowed: frequencies are in Hz and must be finite and > 0"
        )))
    }
}

#[derive(clap::Args)]
#[command(
    about = "All steady-state amplitudes at one input level and frequency, with phase and stability",
    after_long_help = roots_long_help()
)]
pub struct Args {
    /// Model file (TOML, SI units; see MODEL FILE below).
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// Input acceleration amplitude gamma, m/s^2 zero-to-peak (> 0).
    #[arg(long, value_name = "G", allow_hyphen_values = true)]
    pub gamma: f64,
    /// Input frequency, Hz (> 0).
    #[arg(long = "f-hz", value_name = "F", allow_hyphen_values = true)]
    pub f_hz: f64,
    /// Steady-state equation: exact harmonic balance or the paper's Eq 30.
    #[arg(long, value_enum, default_value_t = FormulationArg::Hb)]
    pub formulation: FormulationArg,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

fn roots_long_help() -> String {
    format!(
        "DESCRIPTION:
  All steady states (roots of the harmonic-balance equation) at one input level gamma
  and one frequency f, sorted by amplitude, each with its phase lag and stability.
  Near a fold of a hardening or softening response there are three: the lower and
  upper ones are stable, the middle one is unstable. When there is none (e.g. Coulomb
  friction that holds the mass: 4 c_e/pi >= m gamma) the output says so explicitly.

{}

OUTPUT:
  text (default): one line per root, amplitude in m, phase lag in degrees, stability
  --json: {{\"f_hz\":..,\"gamma\":..,\"formulation\":\"hb\",\"roots\":[{{\"amplitude\":..,\"phase_deg\":..,\"stable\":true}},..],\"no_motion\":null}}
          with no root: \"no_motion\":\"sticking\" (plus friction/input accelerations and forces) or \"no_root\"

EXAMPLE:
  nlsdof roots --model examples/duffing-strong.toml --gamma 2 --f-hz 12.5
  nlsdof roots --model examples/coulomb.toml --gamma 1 --f-hz 5 --json",
        conventions_help()
    )
}

pub fn run(args: Args) -> Result<(), CliError> {
    let gamma = check_gamma(args.gamma)?;
    let f_hz = check_frequency("--f-hz", args.f_hz)?;
    let (model, gain) = load_steady_model(&args.model)?;
    let response = ForcedResponse::new(&model, gain * gamma, args.formulation.to_core())?;
    let set = response.steady_states(2.0 * PI * f_hz)?;

    let name = args.model.display().to_string();
    let formulation = args.formulation.to_core();
    if args.json {
        let mut v = report::roots_json(&name, &model, f_hz, gamma, formulation, &set);
        v["input_gain"] = serde_json::json!(gain);
        println!("{v}");
    } else {
        let text = report::roots_text(&name, &model, f_hz, gamma, formulation, &set);
        print!("{}", with_gain_note(text, gain));
    }
    Ok(())
}
