//! The `--sign` choice (hardening / softening / auto) and the options of
//! `fit` and `compare` for phase-resonance data, shared by the sweep fits
//! (`fit`, `compare`) and the phase-resonance fits (`phase_resonance`).

use super::progress::progress_bar;
use crate::error::CliError;
use nlsdof::identification::phase_resonance::{
    default_spec, fit_phase_resonance, PrDataset, PrFitOptions, PrFitResult,
};
use nlsdof::identification::search::{fit_each_sign, signs_to_try, SignTrial};
use nlsdof::identification::{FitSpec, ModelKind, Sign};

/// Options of `fit` and `compare` added for phase-resonance data and the
/// stiffness sign.
#[derive(clap::Args, Debug, Clone)]
pub struct PrArgs {
    /// DATA holds phase-resonance points, one row per level: gamma,f_hz,amplitude[,level][,weight]
    /// (frequency and amplitude where the phase lag is 90 deg, like Table 8's experimental
    /// columns); '#' lines are comments. Unit options (--peak-to-peak, --gamma-in-g,
    /// --velocity, --acceleration) apply as for sweeps. Not auto-detected.
    #[arg(long = "phase-resonance")]
    pub phase_resonance: bool,
    /// Relative weight w_f of the frequency residuals of --phase-resonance fits. 1 (default):
    /// a relative frequency error zeta0*e costs as much as a relative amplitude error e
    /// (zeta0 = damping ratio of the lowest level), as a relative error e of the measured
    /// response does to the two. > 1 trusts the frequencies more.
    #[arg(
        long = "frequency-weight",
        value_name = "W",
        default_value_t = 1.0,
        requires = "phase_resonance"
    )]
    pub frequency_weight: f64,
    /// Sign of the nonlinear stiffness beta: data (default: sweeps take the sign of the
    /// branch-free equation-error estimate; phase-resonance points are fitted hardening),
    /// hardening (beta > 0), softening (beta < 0), or auto (fit both, keep the lower cost,
    /// report both).
    #[arg(long, value_enum, default_value = "data")]
    pub sign: SignArg,
    /// Short for --sign softening.
    #[arg(long)]
    pub softening: bool,
}

/// `--sign`: sign of the fitted nonlinear stiffness.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum SignArg {
    /// From the data (sweeps: sign of the equation-error estimate; phase-resonance
    /// points: hardening).
    #[default]
    Data,
    /// beta > 0.
    Hardening,
    /// beta < 0.
    Softening,
    /// Fit both signs, keep the lower cost (both costs are reported).
    Auto,
}

impl SignArg {
    /// `--softening` is short for `--sign softening`.
    pub fn resolve(self, softening: bool) -> Result<SignArg, CliError> {
        match (softening, self) {
            (false, s) => Ok(s),
            (true, SignArg::Data | SignArg::Hardening | SignArg::Softening) => {
                Ok(SignArg::Softening)
            }
            (true, SignArg::Auto) => Err(CliError::Usage(
                "--softening conflicts with --sign auto".into(),
            )),
        }
    }

    /// The signs to fit for `kind` (one sign if the model has no stiffness term).
    pub fn signs(self, kind: ModelKind) -> Vec<Sign> {
        let preferred = if self == SignArg::Softening {
            Sign::Softening
        } else {
            Sign::Hardening
        };
        signs_to_try(kind, self == SignArg::Auto, preferred)
    }
}

/// Phase-resonance fit with the stiffness sign chosen by `sign`.
pub fn fit_pr_signed(
    data: &PrDataset,
    kind: ModelKind,
    sign: SignArg,
    configure: &dyn Fn(&mut FitSpec) -> Result<(), CliError>,
    opts: &PrFitOptions,
) -> Result<(PrFitResult, Vec<SignTrial>), CliError> {
    each_sign(kind, sign, opts.starts, &|s, tick| {
        let mut spec = default_spec(kind, data, s);
        configure(&mut spec)?;
        Ok(fit_phase_resonance(data, &spec, opts, tick).map(|r| (r.cost, r)))
    })
}

/// One sign's fit for [`each_sign`]: `Err` for a bad configuration, else
/// the fit's `(cost, result)` or its error.
type SignRun<'a, R, E> =
    dyn Fn(Sign, &(dyn Fn() + Sync)) -> Result<Result<(f64, R), E>, CliError> + 'a;

/// [`fit_each_sign`] over the signs of `sign`, with one progress bar of
/// `starts` per sign. A bad configuration (`run` returning `Err`) fails the
/// whole call; a failed fit is recorded and the other sign may win.
fn each_sign<R, E: std::fmt::Display>(
    kind: ModelKind,
    sign: SignArg,
    starts: usize,
    run: &SignRun<'_, R, E>,
) -> Result<(R, Vec<SignTrial>), CliError> {
    let config_error = std::cell::RefCell::new(None);
    let found = fit_each_sign(&sign.signs(kind), &|s| {
        let pb = progress_bar(starts, &format!("{} ({})", kind.name(), s.name()));
        let r = run(s, &|| pb.inc(1));
        pb.finish_and_clear();
        match r {
            Ok(fit) => fit.map_err(|e| e.to_string()),
            Err(e) => {
                let msg = e.to_string();
                config_error.borrow_mut().get_or_insert(e);
                Err(msg)
            }
        }
    });
    if let Some(e) = config_error.into_inner() {
        return Err(e);
    }
    found.map_err(CliError::Usage)
}
