//! `nlsdof equiv`: the shape factor g(mu) of the equivalent coefficients.

use crate::error::CliError;
use nlsdof::power_law::{g, g_integer};
use serde_json::json;

#[derive(clap::Args)]
#[command(
    about = "Shape factor g(mu) of the equivalent coefficient (Eq 12/24) and its integer closed form",
    after_long_help = equiv_long_help()
)]
pub struct Args {
    /// Power-law exponent mu (rho for stiffness, eta for damping), real, > -3.
    #[arg(long, value_name = "MU", allow_hyphen_values = true)]
    pub mu: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

fn equiv_long_help() -> String {
    "DESCRIPTION:
  Shape factor g(mu) of the first-order harmonic-balance (describing-function)
  equivalent coefficient of a power-law term of the model (SI units)

    m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma cos(2 pi f t).

  A power-law stiffness force k_r x|x|^rho (Eq 4) or damping force c_e x'|x'|^eta
  (Eq 18), under the motion x = a cos(Omega t), has the equivalent linear coefficients

    k_eq = g(rho) k_r a^rho              N/m      (Eq 9)
    c_eq = g(eta) c_e (Omega a)^eta      N s/m    (Eq 22)

  (a zero-to-peak amplitude in m, Omega = 2 pi f in rad/s), with the shape factor

    g(mu) = 2 Gamma((3+mu)/2) / (sqrt(pi) Gamma(2+mu/2)),   mu > -3   (Eq 12 = Eq 24)

  For integer mu the paper gives closed forms with double factorials (Eq 26): Eq 17
  for even and Eq 25 for odd mu; both are printed for comparison.

  Special cases: mu = 0 linear (g = 1), mu = 2 Duffing cubic stiffness (g = 3/4),
  mu = 1 quadratic damping (g = 8/(3 pi)), mu = -1 Coulomb friction (g = 4/pi).

OUTPUT:
  text (default), or --json:
  {\"mu\":2.0,\"g\":0.75,\"integer\":true,\"closed_form\":0.75,\"closed_form_formula\":\"Eq 17 even\",\"name\":\"Duffing (cubic stiffness)\"}
  closed_form/closed_form_formula/name are null when they do not apply.

EXAMPLES:
  nlsdof equiv --mu 2
  nlsdof equiv --mu 4.0022 --json
  nlsdof equiv --mu -1"
        .to_string()
}

/// Names of the classical special cases.
fn special_name(mu: f64) -> Option<&'static str> {
    const NAMES: [(f64, &str); 4] = [
        (0.0, "linear (viscous damping / linear stiffness)"),
        (1.0, "quadratic damping"),
        (2.0, "Duffing (cubic stiffness)"),
        (-1.0, "Coulomb friction"),
    ];
    NAMES.iter().find(|(m, _)| *m == mu).map(|(_, n)| *n)
}

/// Eq 26 for integer mu, `None` where the factorials overflow f64 (mu > ~290).
fn closed_form(mu: f64) -> Option<(f64, &'static str)> {
    if mu.fract() != 0.0 || mu.abs() > 1e4 {
        return None;
    }
    let n = mu as i64;
    let v = g_integer(n).ok()?;
    v.is_finite().then_some((
        v,
        if n % 2 == 0 {
            "Eq 17 even"
        } else {
            "Eq 25 odd"
        },
    ))
}

pub fn run(args: Args) -> Result<(), CliError> {
    let mu = args.mu;
    let value = g(mu).map_err(|e| {
        CliError::Usage(format!(
            "--mu {mu} is not allowed (need a finite real number > -3): {e}"
        ))
    })?;
    let closed = closed_form(mu);
    let name = special_name(mu);
    if args.json {
        let out = json!({
            "mu": mu,
            "g": value,
            "integer": mu.fract() == 0.0,
            "closed_form": closed.map(|c| c.0),
            "closed_form_formula": closed.map(|c| c.1),
            "name": name,
        });
        println!("{out}");
        return Ok(());
    }
    println!("mu = {mu}");
    println!("g(mu) = {value}   (Eq 12/24, Gamma-function form)");
    match closed {
        Some((v, formula)) => println!(
            "closed form, Eq 26 ({formula}) = {v}   (difference {:.1e})",
            (v - value).abs()
        ),
        None if mu.fract() == 0.0 => {
            println!("closed form: its factorials overflow f64 at this mu")
        }
        None => println!("closed form: none (mu is not an integer)"),
    }
    if let Some(n) = name {
        println!("special case: {n}");
    }
    println!("as stiffness: k_eq = {value} * k_r * a^{mu}   (N/m, a zero-to-peak in m)");
    println!("as damping:   c_eq = {value} * c_e * (Omega a)^{mu}   (N s/m, Omega in rad/s)");
    Ok(())
}
