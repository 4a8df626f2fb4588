//! `nlsdof` — identify and simulate nonlinear single-degree-of-freedom
//! power-law models of vibrating structures. See `nlsdof --help`.

mod cmd;
mod error;

use clap::{Parser, Subcommand};
use error::CliError;
use std::io::Write;

/// Nonlinear SDoF power-law models: m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma(t).
///
/// All quantities are SI. Input levels (gamma, m/s^2) and amplitudes (m) are
/// zero-to-peak; frequencies on the command line are in Hz.
#[derive(Parser)]
#[command(name = "nlsdof", version, about, long_about = None, propagate_version = true)]
#[command(after_long_help = cmd::roots::top_level_help())]
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
    /// Truncation error of the first-order harmonic balance (peak, folds) against the number of harmonics.
    #[command(name = "hb-error")]
    HbError(cmd::hb_error::Args),
    /// Simulate the response to a recorded input acceleration (CSV or MAT), writing t,accel,x,v.
    Simulate(cmd::simulate::Args),
    /// Virtual stepped-sine test rig: dwell until steady at each frequency, record amplitude and phase.
    #[command(name = "stepped-sine")]
    SteppedSine(cmd::stepped_sine::Args),
    /// Make an input signal (CSV t,accel): sine, chirp or stepped sine.
    Signal(cmd::signal::Args),
    /// Fit a power-law model to stepped-sine amplitude curves at several input levels (Eq 31).
    Fit(cmd::fit::Args),
    /// Fit the power-law ODE to a recorded input and output in the time domain (output error, RK4 sensitivities).
    #[command(name = "fit-time")]
    FitTime(cmd::fit_time::Args),
    /// Free-decay identification: Hilbert backbone, damping curve, averaged power-law fit.
    Decay(cmd::decay::Args),
    /// What stepped-sine curves say before any fit: homogeneity, model-free stiffness and damping laws, the model to fit.
    Inspect(cmd::inspect::Args),
    /// Fit several models to one data set and compare them (Tables 5-8 analogue).
    Compare(cmd::compare::Args),
    /// Estimate an FRF (H1, H2 with coherence, or spectral ratio) from input/output time histories.
    #[command(name = "frf-estimate")]
    FrfEstimate(cmd::frf_estimate::Args),
    /// Identify the linear part (m, c, k or k/m, c/m) from a measured FRF by fast relaxed vector fitting.
    #[command(name = "linear-id")]
    LinearId(cmd::linear_id::Args),
    /// STFT spectrogram of a recorded signal, optionally compared with another (Eq 33), with PNG heat map and waterfall.
    Spectrogram(cmd::spectrogram::Args),
    /// The paper's whole workflow on a built-in virtual HAR wing: test, identify, simulate, compare; writes a report folder.
    Demo(cmd::demo::Args),
}

/// Whether standard output (file descriptor 1) was closed when the process
/// started (`nlsdof equiv --mu 2 >&-`). Rust's runtime reopens a closed
/// standard descriptor on /dev/null before `main`, after which every write
/// "succeeds" and the output is lost without a word; a constructor in
/// `.init_array` runs before that and records it. (Hand-written because the
/// runtime's reopening cannot be turned off; `fcntl` is declared here to
/// avoid a dependency for one call.)
#[cfg(target_os = "linux")]
mod closed_stdout {
    use std::sync::atomic::{AtomicBool, Ordering};

    static CLOSED: AtomicBool = AtomicBool::new(false);

    extern "C" {
        fn fcntl(fd: i32, cmd: i32, ...) -> i32;
    }
    const F_GETFD: i32 = 1;

    extern "C" fn check() {
        // SAFETY: F_GETFD only queries the descriptor flags.
        if unsafe { fcntl(1, F_GETFD) } == -1 {
            CLOSED.store(true, Ordering::Relaxed);
        }
    }

    #[used]
    #[link_section = ".init_array"]
    static INIT: extern "C" fn() = check;

    pub fn was_closed() -> bool {
        CLOSED.load(Ordering::Relaxed)
    }
}

#[cfg(not(target_os = "linux"))]
mod closed_stdout {
    pub fn was_closed() -> bool {
        false
    }
}

/// Standard output failed: a closed pipe ends quietly as Unix tools do (exit
/// 141, what a shell reports for SIGPIPE), any other error is one line and
/// exit 2. No output file is committed in either case.
fn stdout_failed(e: &std::io::Error) -> ! {
    nlsdof_io::atomic::cleanup_all();
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(141);
    }
    let _ = writeln!(
        std::io::stderr(),
        "nlsdof: error: cannot write to standard output: {e}; no output file written"
    );
    std::process::exit(2);
}

/// `print!` panics when standard output fails (closed pipe, full disk):
/// turn that into [`stdout_failed`]; any other panic removes the temporary
/// files before the default report.
fn install_panic_hook() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(rest) = msg.strip_prefix("failed printing to stdout: ") {
            let kind = if rest.contains("Broken pipe") || rest.contains("os error 32") {
                std::io::ErrorKind::BrokenPipe
            } else {
                std::io::ErrorKind::Other
            };
            stdout_failed(&std::io::Error::new(kind, rest.to_string()));
        }
        if msg.starts_with("failed printing to stderr") {
            nlsdof_io::atomic::cleanup_all();
            std::process::exit(2);
        }
        nlsdof_io::atomic::cleanup_all();
        default(info);
    }));
}

fn main() {
    nlsdof_figure::fonts::register();
    install_panic_hook();
    // SIGINT, SIGTERM and SIGHUP (ctrlc "termination" feature).
    ctrlc::set_handler(|| {
        nlsdof_io::atomic::cleanup_all();
        eprintln!("nlsdof: interrupted; no output written");
        std::process::exit(130);
    })
    .ok();
    // every verb writes to standard output: a closed one is an error before
    // any work, as any later write error would be
    if closed_stdout::was_closed() {
        stdout_failed(&std::io::Error::new(
            std::io::ErrorKind::Other,
            "it is closed (file descriptor 1)",
        ));
    }
    let cli = Cli::try_parse().unwrap_or_else(|e| {
        use clap::error::ErrorKind as K;
        if !e.use_stderr()
            || matches!(
                e.kind(),
                K::DisplayHelp | K::DisplayVersion | K::DisplayHelpOnMissingArgumentOrSubcommand
            )
        {
            e.exit();
        }
        // Usage errors too are one line on stderr and exit code 2.
        let text = e.render().to_string();
        let parts: Vec<&str> = text
            .lines()
            .map(|l| l.trim().trim_start_matches("error: "))
            .filter(|l| {
                !l.is_empty() && !l.starts_with("For more information") && !l.starts_with("Usage:")
            })
            .collect();
        let mut msg = String::new();
        for p in parts {
            if !msg.is_empty() {
                msg.push_str(if msg.ends_with(':') { " " } else { "; " });
            }
            msg.push_str(p);
        }
        eprintln!(
            "nlsdof: error: {} (see --help)",
            nlsdof_report::compact_numbers(&msg)
        );
        std::process::exit(2);
    });
    // All output files of a command are committed together at the end, after
    // standard output is flushed (all or nothing). `demo` stages its own
    // folder and renames it.
    if !matches!(cli.command, Command::Demo(_)) {
        nlsdof_io::atomic::defer_commits();
    }
    // `fit --plot` writes SVG or PNG (checked here, before any work).
    if let Command::Fit(a) = &cli.command {
        if let Err(e) = nlsdof_report::figure_file::check_plot_name(a.plot.as_deref()) {
            eprintln!("nlsdof: error: {e}");
            std::process::exit(2);
        }
    }
    let result: Result<(), CliError> = match cli.command {
        Command::Equiv(a) => cmd::equiv::run(a),
        Command::Roots(a) => cmd::roots::run(a),
        Command::Frf(a) => cmd::frf::run(a),
        Command::HbError(a) => cmd::hb_error::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::SteppedSine(a) => cmd::stepped_sine::run(a),
        Command::Signal(a) => cmd::signal::run(a),
        Command::Fit(a) if a.pr.phase_resonance => cmd::phase_resonance::run_fit_verb(&a),
        Command::Fit(a) => cmd::fit::run(a),
        Command::FitTime(a) => cmd::fit_time::run(a),
        Command::Decay(a) => cmd::decay::run(a),
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Compare(a) if a.pr.phase_resonance => cmd::phase_resonance::run_compare_args(&a),
        Command::Compare(a) => cmd::compare::run(a),
        Command::FrfEstimate(a) => cmd::frf_estimate::run(a),
        Command::LinearId(a) => cmd::linear_id::run(a),
        Command::Spectrogram(a) => cmd::spectrogram::run(a),
        Command::Demo(a) => cmd::demo::run(a),
    };
    let result = result.and_then(|()| {
        if let Err(e) = std::io::stdout().flush() {
            stdout_failed(&e);
        }
        nlsdof_io::atomic::commit_deferred().map_err(CliError::from)
    });
    if let Err(e) = result {
        nlsdof_io::atomic::cleanup_all();
        eprintln!(
            "nlsdof: error: {}",
            nlsdof_report::compact_numbers(&e.to_string())
        );
        std::process::exit(2);
    }
}
