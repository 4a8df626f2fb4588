//! `nlsdof` — identify and simulate nonlinear single-degree-of-freedom
//! power-law models of vibrating structures. See `nlsdof --help`.

mod cmd;
mod error;

use clap::{Parser, Subcommand};
use error::CliError;

/// Nonlinear SDoF power-law models: m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma(t).
///
/// All quantities are SI. Input levels (gamma, m/s^2) and amplitudes (m) are
/// zero-to-peak; frequencies on the command line are in Hz.
#[derive(Parser)]
#[command(name = "nlsdof", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Shape factor g(mu) of the equivalent coefficient (Eq 12/24) and its integer closed form.
    Equiv(cmd::equiv::Args),
    /// All steady-state amplitudes at one input level and frequency, with phase and stability.
    Roots(cmd::roots::Args),
    /// Amplitude-frequency curves at several input levels, as a stepped-sine sweep sees them.
    Frf(cmd::frf::Args),
}

fn main() {
    ctrlc::set_handler(|| {
        nlsdof_io::atomic::cleanup_all();
        eprintln!("nlsdof: interrupted; no output written");
        std::process::exit(130);
    })
    .ok();
    let cli = Cli::parse();
    let result: Result<(), CliError> = match cli.command {
        Command::Equiv(a) => cmd::equiv::run(a),
        Command::Roots(a) => cmd::roots::run(a),
        Command::Frf(a) => cmd::frf::run(a),
    };
    if let Err(e) = result {
        eprintln!("nlsdof: error: {e}");
        std::process::exit(2);
    }
}
