//! The 95 % intervals of a fit's parameters (`nlsdof fit`, Python
//! `FitResult.report()`): **one per parameter by default**, labelled with
//! its method — the output-error profile where it was computed (`fit
//! --profile`) and may be reported, else the linearised (Wald) interval.
//! The others appear on request (`--intervals all`, Python
//! `intervals="all"`), each labelled with what it leaves out.
//!
//! An interval that leaves out its own estimate is not an interval of it:
//! such a profile is refused, with the reason
//! ([`OutputErrorProfile::refusal`]), and the Wald interval is shown.

use nlsdof::identification::profile::OutputErrorProfile;
use nlsdof::identification::{FitResult, Identification, Status, N_PARAMS, PARAM_NAMES};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// Which 95 % intervals a report shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IntervalView {
    /// One per parameter ([`chosen`]).
    #[default]
    One,
    /// Every interval computed, each with what it leaves out.
    All,
}

impl IntervalView {
    /// `"one"` or `"all"` (any case).
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "one" => Some(Self::One),
            "all" => Some(Self::All),
            _ => None,
        }
    }
}

/// Method names, as the reports and the JSON (`"method"`) give them.
pub const WALD: &str = "Wald";
pub const OE_PROFILE: &str = "output-error profile";
pub const EE_PROFILE: &str = "equation-error profile";

/// What each method leaves out (the `--intervals all` labels).
pub const WALD_LEAVES_OUT: &str = "linearised at the optimum (with the per-curve noise model): leaves out the curvature of the objective, so it is symmetric and can cross a bound";
pub const OE_PROFILE_LEAVES_OUT: &str = "the objective the fit minimised (measured-branch output error with its jump penalties, phase residuals when fitted), refitted with the exponent held: leaves out the per-curve noise model (the noise read as of one size, sigma^2 = P*/(m - p)) and the uncertainty of the jump readings";
pub const EE_PROFILE_LEAVES_OUT: &str = "the branch-free equation error on the landscape grid, an interval of the equation-error estimate, not of the fit's: leaves out the model's branches and jumps and the noise in the measured amplitudes (errors in variables bias it)";

/// One 95 % interval; `None` bounds are open.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub method: &'static str,
}

impl Interval {
    /// `[lower, upper]` with "open" for a missing bound.
    pub fn bounds_text(&self) -> String {
        let f = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.6e}"));
        format!("[{}, {}]", f(self.lower), f(self.upper))
    }

    pub fn json(&self) -> Value {
        json!({"ci95": [self.lower, self.upper], "method": self.method})
    }
}

/// The Wald (linearised) interval of parameter `j`, when the fit's
/// intervals are to be trusted ([`FitResult::intervals_valid`]).
pub fn wald(res: &FitResult, j: usize) -> Option<Interval> {
    let u = res.uncertainty.as_ref().filter(|_| res.intervals_valid())?;
    let k = u.index(PARAM_NAMES[j])?;
    Some(Interval {
        lower: Some(u.lower[k]),
        upper: Some(u.upper[k]),
        method: WALD,
    })
}

/// The one interval shown per parameter (θ order; `None`: none): the
/// output-error profile of `profiles` where computed and not refused, else
/// the Wald interval.
pub fn chosen(res: &FitResult, profiles: &[OutputErrorProfile]) -> [Option<Interval>; N_PARAMS] {
    std::array::from_fn(|j| {
        // (a model that does not fit its noise has no valid interval of
        // any method: each assumes residuals that are noise)
        if res.status[j] == Status::Absent || res.misfit.is_some() {
            return None;
        }
        profiles
            .iter()
            .find(|p| p.parameter as usize == j && p.refusal().is_none())
            .map(|p| Interval {
                lower: p.lower,
                upper: p.upper,
                method: OE_PROFILE,
            })
            .or_else(|| wald(res, j))
    })
}

/// Adds the chosen interval to each entry of `doc["parameters"]` (the
/// JSON of `nlsdof fit`) as `"interval": {"ci95": [lower, upper],
/// "method": ...}` (`null` when none), and to `doc["interval_methods"]` what
/// each method leaves out. The other fields are kept.
pub fn add_chosen_json(doc: &mut Value, res: &FitResult, profiles: &[OutputErrorProfile]) {
    let chosen = chosen(res, profiles);
    if let Some(params) = doc.get_mut("parameters").and_then(Value::as_array_mut) {
        for p in params {
            let j = p
                .get("name")
                .and_then(Value::as_str)
                .and_then(|n| PARAM_NAMES.iter().position(|m| *m == n));
            if let Some(j) = j {
                p["interval"] = chosen[j].map_or(Value::Null, |i| i.json());
            }
        }
    }
    doc["interval_methods"] = json!({
        WALD: WALD_LEAVES_OUT, OE_PROFILE: OE_PROFILE_LEAVES_OUT, EE_PROFILE: EE_PROFILE_LEAVES_OUT,
        "note": "parameters[].interval is the one 95 % interval reported: the output-error profile where computed (fit --profile) and not refused, else Wald; ci95 keeps the Wald interval"
    });
}

/// The lines under the parameter table of the default view: the profiles
/// refused and why, and where the other intervals are.
pub fn default_text(id: &Identification, profiles: &[OutputErrorProfile]) -> String {
    let mut s = String::new();
    for p in profiles {
        if let Some(why) = p.refusal() {
            let name = p.parameter.info().name;
            let instead = if wald(&id.fit, p.parameter as usize).is_some() {
                "the Wald interval is shown"
            } else {
                "no interval is shown"
            };
            writeln!(
                s,
                "{name}: output-error profile interval not shown ({instead}): {why}"
            )
            .ok();
        }
    }
    let others = id.rho_profile.is_some() || id.eta_profile.is_some() || !profiles.is_empty();
    if others && id.fit.misfit.is_none() {
        writeln!(
            s,
            "intervals: one 95 % interval per parameter, its method named; the others (each with what it leaves out): --intervals all (Python: intervals=\"all\")"
        )
        .ok();
    }
    s
}

/// The `--intervals all` section: every interval computed for every free
/// parameter, each labelled with what it leaves out.
pub fn all_text(id: &Identification, profiles: &[OutputErrorProfile]) -> String {
    let res = &id.fit;
    let mut s = String::new();
    writeln!(
        s,
        "\n95 % intervals, every method (each leaves something out):"
    )
    .ok();
    if let Some(r) = res.misfit {
        writeln!(
            s,
            "  NONE IS VALID: the model does not fit its noise (residual {r:.1}x); every interval below assumes residuals that are noise"
        )
        .ok();
    }
    let mut methods = Vec::new();
    for j in 0..N_PARAMS {
        if res.status[j] != Status::Free {
            continue;
        }
        let name = PARAM_NAMES[j];
        match wald(res, j) {
            Some(w) => writeln!(s, "  {name:<6} {WALD:<24} {}", w.bounds_text()),
            None => writeln!(
                s,
                "  {name:<6} {WALD:<24} not shown (the fit's intervals are not to be trusted, see above)"
            ),
        }
        .ok();
        methods.push(WALD);
        if let Some(p) = profiles.iter().find(|p| p.parameter as usize == j) {
            let i = Interval {
                lower: p.lower,
                upper: p.upper,
                method: OE_PROFILE,
            };
            let refused = p
                .refusal()
                .map_or(String::new(), |why| format!("; REFUSED: {why}"));
            writeln!(
                s,
                "  {name:<6} {OE_PROFILE:<24} {} around {:.4} ({} local fits){refused}",
                i.bounds_text(),
                p.estimate,
                p.fits
            )
            .ok();
            methods.push(OE_PROFILE);
        }
        let ee = match name {
            "rho" => id.rho_profile,
            "eta" => id.eta_profile,
            _ => None,
        };
        if let Some(e) = ee {
            let i = Interval {
                lower: e.lower,
                upper: e.upper,
                method: EE_PROFILE,
            };
            writeln!(
                s,
                "  {name:<6} {EE_PROFILE:<24} {} of the equation-error estimate {:.4}",
                i.bounds_text(),
                id.equation_error.theta[j]
            )
            .ok();
            methods.push(EE_PROFILE);
        }
    }
    for (m, what) in [
        (WALD, WALD_LEAVES_OUT),
        (OE_PROFILE, OE_PROFILE_LEAVES_OUT),
        (EE_PROFILE, EE_PROFILE_LEAVES_OUT),
    ] {
        if methods.contains(&m) {
            writeln!(s, "  {m}: {what}").ok();
        }
    }
    s
}
