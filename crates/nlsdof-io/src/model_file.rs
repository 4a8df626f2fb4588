//! Model file (TOML, SI units):
//!
//! ```toml
//! mass = 0.26699          # kg
//! stiffness = 306.7878    # k, N/m
//! damping = 0.1164        # c, N s/m
//! [nonlinear_stiffness]   # optional: k_r x|x|^rho
//! coefficient = 85000.0   # k_r, N/m^(rho+1)
//! exponent = 4.0          # rho
//! [nonlinear_damping]     # optional: c_e x'|x'|^eta
//! coefficient = 0.0159    # c_e, N (s/m)^(eta+1)
//! exponent = 3.0          # eta
//! [signal]                # optional: recorded signals <-> model
//! input_gain = 1.0        # the model sees gamma = input_gain * (u + input_offset)
//! input_offset = 0.0      # in the input's unit
//! output_offset = 0.0     # y = x + output_offset, in the output's unit
//! input_interpolation = "cubic"  # optional: u between samples, cubic | linear | zoh
//! substeps = 8            # optional: RK4 steps per sample (h = 1/(substeps fs))
//! [provenance]            # optional: where the model came from (information only)
//! tool = "nlsdof fit"
//! version = "0.1.0"
//! data = "levels.csv"
//! model = "generalised"
//! objective = "Eq 31 output error, m^2"
//! cost = 1.25e-9
//! converged = true
//! ```
//!
//! ## The tables and who uses them
//!
//! - The model (`mass`, `stiffness`, `damping`, `[nonlinear_stiffness]`,
//!   `[nonlinear_damping]`): every command that takes `--model`, and Python
//!   `Model.from_toml`.
//! - `[signal]`: how a recorded input `u` drives the model and how its
//!   output is recorded. `nlsdof fit --out` writes the forcing gain of a
//!   stepped-sine fit here (`input_gain`; the model sees `gain * gamma`, the
//!   levels `gamma` being the measured ones), `nlsdof fit-time --out` the
//!   gain and both offsets of a time-domain fit. `simulate` applies all three
//!   (`gamma = input_gain (u + input_offset)`, column `y = x + output_offset`).
//!   `input_interpolation` states how the recorded input is reconstructed
//!   between samples — part of a time-domain model — and `substeps` the RK4
//!   steps per sample the fit integrated with (chosen to make the
//!   integration error negligible); `simulate`'s default RK4 uses both.
//!   Without them: cubic input and 2 substeps (`h = 1/(2 fs)`), the
//!   behaviour of files written before they existed.
//!   The steady-state commands (`roots`, `frf`, `hb-error`, `stepped-sine`)
//!   and Python's `sweep`, `steady_states`, `hb_error` and `stepped_sine`
//!   apply `input_gain` to the levels given and refuse a file with a
//!   non-zero `input_offset` (a static force shifts the equilibrium of a
//!   nonlinear model, which a harmonic balance about zero cannot represent)
//!   or a negative `input_gain` (an inverted input: the amplitudes of
//!   `|gain|` but phases shifted by 180°), each with one line naming the
//!   key. A DC `output_offset` does not change an amplitude.
//! - `[provenance]`: written by the fitting commands, read back by Python
//!   (`Model.provenance`) and ignored by every computation.
//!
//! Unknown keys are rejected (a typo must not silently drop a term). A file
//! without `[signal]` means gain 1 and no offsets (backward compatible).
//! `input_gain` must be finite and non-zero (negative: an inverted input,
//! which a time-domain fit may find), the offsets finite.

use crate::error::IoError;
use nlsdof::{Model, PowerLaw};
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TermFile {
    pub coefficient: f64,
    pub exponent: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    pub mass: f64,
    pub stiffness: f64,
    pub damping: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlinear_stiffness: Option<TermFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlinear_damping: Option<TermFile>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signal: Option<SignalMap>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub provenance: Option<Provenance>,
}

/// Where a fitted model came from (the `[provenance]` table): information
/// only, no computation reads it. Every field is optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    /// The command that wrote the file, e.g. `nlsdof fit`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool: Option<String>,
    /// nlsdof's version.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub version: Option<String>,
    /// The data the model was fitted to, as the user named it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<String>,
    /// The model family fitted (`generalised`, `duffing`, ...).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// What `cost` measures, with its unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objective: Option<String>,
    /// The fit's cost (see `objective`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost: Option<f64>,
    /// Whether the fit met its convergence criterion.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub converged: Option<bool>,
    /// The sample range fitted (`start:end`, time-domain fits).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<String>,
    /// Time-domain fits: the RK4 step, s (`1/(substeps fs)`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration_step: Option<f64>,
    /// Time-domain fits: the estimated integration error of the fitted
    /// output (RMS change when the substeps are doubled), output unit; to
    /// compare with `cost`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration_error: Option<f64>,
}

/// Everything a model file holds: the model, the optional signal map and
/// provenance.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelDocument {
    pub model: Model,
    pub signal: Option<SignalMap>,
    pub provenance: Option<Provenance>,
}

impl ModelDocument {
    /// The model alone (no signal map, no provenance).
    pub fn new(model: Model) -> Self {
        Self {
            model,
            signal: None,
            provenance: None,
        }
    }

    /// The signal map, or the identity (gain 1, no offsets) without one.
    pub fn signal_or_identity(&self) -> SignalMap {
        self.signal.unwrap_or_default()
    }

    /// The model file text: the model with unit comments, then `[signal]`
    /// and `[provenance]` when present. [`parse_document`] reads it back to
    /// an equal document.
    pub fn to_toml(&self) -> String {
        let mut s = model_to_toml(&self.model);
        if let Some(sig) = &self.signal {
            s += &signal_to_toml(sig);
        }
        if let Some(p) = &self.provenance {
            s += &provenance_to_toml(p);
        }
        s
    }
}

/// How recorded signals map to the model (time-domain fits): the model is
/// driven by `gamma = input_gain * (u + input_offset)` and its output is
/// `y = x + output_offset`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignalMap {
    #[serde(default = "one")]
    pub input_gain: f64,
    #[serde(default)]
    pub input_offset: f64,
    #[serde(default)]
    pub output_offset: f64,
    /// How `u` is reconstructed between samples (`None`: cubic, the
    /// default of files that do not state it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_interpolation: Option<nlsdof::excitation::InputInterpolation>,
    /// RK4 steps per sample interval the model was fitted with (`None`:
    /// 2, `h = 1/(2 fs)`); 1..=256.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub substeps: Option<usize>,
}

fn one() -> f64 {
    1.0
}

impl SignalMap {
    /// The integration the table states (`input_interpolation` and/or
    /// `substeps`, written by `fit-time`), the missing one at its default;
    /// `None` when it states neither (the simulator's own default applies).
    pub fn stated_discretisation(
        &self,
    ) -> Option<nlsdof::identification::time_domain::Discretisation> {
        use nlsdof::identification::time_domain::Discretisation;
        (self.input_interpolation.is_some() || self.substeps.is_some()).then(|| Discretisation {
            interpolation: self.input_interpolation.unwrap_or_default(),
            substeps: self.substeps.unwrap_or(Discretisation::default().substeps),
        })
    }

    /// The gain finite and non-zero, the offsets finite: `Err` names the key
    /// (`signal.input_gain`, ...) and says what is wrong.
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        for (name, v) in [
            ("signal.input_gain", self.input_gain),
            ("signal.input_offset", self.input_offset),
            ("signal.output_offset", self.output_offset),
        ] {
            if !v.is_finite() {
                return Err((name, format!("{name} = {v} is not a finite number")));
            }
        }
        if self.input_gain == 0.0 {
            return Err((
                "signal.input_gain",
                "signal.input_gain = 0 would disconnect the input".into(),
            ));
        }
        if let Some(n) = self.substeps {
            if !(1..=256).contains(&n) {
                return Err((
                    "signal.substeps",
                    format!(
                        "signal.substeps = {n} must be between 1 and 256 (RK4 steps per sample)"
                    ),
                ));
            }
        }
        Ok(())
    }
}

impl SignalMap {
    /// The gain a steady-state (harmonic-balance) computation applies to its
    /// levels, or why it cannot apply this map: a non-zero `input_offset` is
    /// a static force, which shifts the equilibrium of a nonlinear model (a
    /// balance about zero cannot represent it); a negative gain inverts the
    /// input. One rule for the CLI's steady-state commands and Python's
    /// `Model` methods.
    pub fn steady_state_gain(&self) -> Result<f64, String> {
        if self.input_offset != 0.0 {
            return Err(format!(
                "[signal] input_offset = {:?} is a static force, which shifts the equilibrium of a nonlinear model; the steady-state (harmonic balance) computations cannot apply it: simulate the time response instead, or remove the offset to see the response without it",
                self.input_offset
            ));
        }
        if self.input_gain < 0.0 {
            return Err(format!(
                "[signal] input_gain = {:?} < 0 inverts the input; the steady-state computations need a gain > 0 (the amplitudes are those of |input_gain|, the phases shifted by 180 deg)",
                self.input_gain
            ));
        }
        Ok(self.input_gain)
    }
}

impl Default for SignalMap {
    fn default() -> Self {
        Self {
            input_gain: 1.0,
            input_offset: 0.0,
            output_offset: 0.0,
            input_interpolation: None,
            substeps: None,
        }
    }
}

impl From<&Model> for ModelFile {
    fn from(m: &Model) -> Self {
        let t = |p: Option<PowerLaw>| {
            p.map(|p| TermFile {
                coefficient: p.coefficient,
                exponent: p.exponent,
            })
        };
        ModelFile {
            mass: m.mass,
            stiffness: m.stiffness,
            damping: m.damping,
            nonlinear_stiffness: t(m.nonlinear_stiffness),
            nonlinear_damping: t(m.nonlinear_damping),
            signal: None,
            provenance: None,
        }
    }
}

impl ModelFile {
    /// Converts to a validated [`Model`].
    pub fn to_model(&self) -> Result<Model, nlsdof::ParameterError> {
        let t = |p: &Option<TermFile>| {
            p.as_ref().map(|p| PowerLaw {
                coefficient: p.coefficient,
                exponent: p.exponent,
            })
        };
        let m = Model {
            mass: self.mass,
            stiffness: self.stiffness,
            damping: self.damping,
            nonlinear_stiffness: t(&self.nonlinear_stiffness),
            nonlinear_damping: t(&self.nonlinear_damping),
        };
        m.validate()?;
        Ok(m)
    }
}

/// Parses model TOML text; `path` is used in error messages only.
pub fn parse_model(text: &str, path: &Path) -> Result<Model, IoError> {
    let file: ModelFile = toml::from_str(crate::strip_bom(text)).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        message: e.message().to_string(),
    })?;
    file.to_model().map_err(|source| IoError::Invalid {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads and validates a model file.
pub fn read_model(path: &Path) -> Result<Model, IoError> {
    Ok(read_model_with_signal(path)?.0)
}

/// Parses a whole model file: the model, `[signal]` (gain finite and
/// non-zero, offsets finite) and `[provenance]`.
pub fn parse_document(text: &str, path: &Path) -> Result<ModelDocument, IoError> {
    let file: ModelFile = toml::from_str(crate::strip_bom(text)).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        message: e.message().to_string(),
    })?;
    let model = file.to_model().map_err(|source| IoError::Invalid {
        path: path.to_path_buf(),
        source,
    })?;
    if let Some(s) = &file.signal {
        s.check().map_err(|(_, message)| IoError::Parse {
            path: path.to_path_buf(),
            message,
        })?;
    }
    if let Some(c) = file.provenance.as_ref().and_then(|p| p.cost) {
        if !(c.is_finite() && c >= 0.0) {
            return Err(IoError::Parse {
                path: path.to_path_buf(),
                message: format!("provenance.cost = {c} is not a cost (a finite number >= 0)"),
            });
        }
    }
    Ok(ModelDocument {
        model,
        signal: file.signal,
        provenance: file.provenance,
    })
}

/// Reads a whole model file ([`parse_document`]).
pub fn read_document(path: &Path) -> Result<ModelDocument, IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_document(&text, path)
}

/// Parses model TOML text and its optional `[signal]` table (gain and
/// offsets must be finite, the gain non-zero).
pub fn parse_model_with_signal(
    text: &str,
    path: &Path,
) -> Result<(Model, Option<SignalMap>), IoError> {
    let d = parse_document(text, path)?;
    Ok((d.model, d.signal))
}

/// Reads a model file with its optional `[signal]` table.
pub fn read_model_with_signal(path: &Path) -> Result<(Model, Option<SignalMap>), IoError> {
    let d = read_document(path)?;
    Ok((d.model, d.signal))
}

/// The `[signal]` table as TOML text (appended to [`model_to_toml`]).
pub fn signal_to_toml(s: &SignalMap) -> String {
    let mut t = format!(
        "\n[signal]                # recorded signals <-> model\ninput_gain = {:?}      # gamma = input_gain * (u + input_offset)\ninput_offset = {:?}    # input unit\noutput_offset = {:?}   # y = x + output_offset, output unit\n",
        s.input_gain, s.input_offset, s.output_offset
    );
    if let Some(i) = s.input_interpolation {
        t += &format!(
            "input_interpolation = \"{}\"   # u between samples (part of the model): cubic | linear | zoh\n",
            i.name()
        );
    }
    if let Some(n) = s.substeps {
        t += &format!("substeps = {n}          # RK4 steps per sample, h = 1/(substeps fs)\n");
    }
    t
}

/// The `[signal]` table of a stepped-sine fit: its forcing gain only.
pub fn forcing_gain_to_toml(gain: f64) -> String {
    format!(
        "\n[signal]                # the fit's forcing gain: the model sees input_gain * gamma\ninput_gain = {gain:?}\n"
    )
}

/// The `[provenance]` table as TOML text (strings escaped by the TOML
/// serialiser).
pub fn provenance_to_toml(p: &Provenance) -> String {
    #[derive(Serialize)]
    struct Wrap<'a> {
        provenance: &'a Provenance,
    }
    let body = toml::to_string(&Wrap { provenance: p }).expect("a provenance serialises");
    format!("\n# where this model came from (information only; no computation reads it)\n{body}")
}

/// Model as TOML text, with unit comments.
pub fn model_to_toml(m: &Model) -> String {
    let mut s = format!(
        "mass = {:?}          # kg\nstiffness = {:?}     # k, N/m\ndamping = {:?}       # c, N s/m\n",
        m.mass, m.stiffness, m.damping
    );
    if let Some(t) = m.nonlinear_stiffness {
        s += &format!(
            "\n[nonlinear_stiffness]   # k_r x|x|^rho\ncoefficient = {:?}   # k_r, N/m^(rho+1)\nexponent = {:?}      # rho\n",
            t.coefficient, t.exponent
        );
    }
    if let Some(t) = m.nonlinear_damping {
        s += &format!(
            "\n[nonlinear_damping]     # c_e x'|x'|^eta\ncoefficient = {:?}   # c_e, N (s/m)^(eta+1)\nexponent = {:?}      # eta\n",
            t.coefficient, t.exponent
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_full_and_round_trips() {
        let text = "mass = 0.26699\nstiffness = 306.7878\ndamping = 0.1164\n[nonlinear_stiffness]\ncoefficient = 85000.0\nexponent = 4.0\n[nonlinear_damping]\ncoefficient = 0.0159\nexponent = 3.0\n";
        let m = parse_model(text, Path::new("x.toml")).unwrap();
        assert_eq!(m.nonlinear_stiffness.unwrap().exponent, 4.0);
        let again = parse_model(&model_to_toml(&m), Path::new("y.toml")).unwrap();
        assert_eq!(m, again);
    }

    #[test]
    fn signal_table_round_trips_and_is_optional() {
        let text = "mass = 1.0\nstiffness = 4.0\ndamping = 0.1\n";
        let (m, s) = parse_model_with_signal(text, Path::new("a.toml")).unwrap();
        assert!(s.is_none());
        let map = SignalMap {
            input_gain: 2.5,
            input_offset: -0.003,
            output_offset: 0.0008,
            ..SignalMap::default()
        };
        let full = model_to_toml(&m) + &signal_to_toml(&map);
        let (m2, s2) = parse_model_with_signal(&full, Path::new("b.toml")).unwrap();
        assert_eq!(m, m2);
        assert_eq!(s2, Some(map));
        // the plain reader still accepts it
        assert_eq!(parse_model(&full, Path::new("c.toml")).unwrap(), m);
        assert!(parse_model_with_signal(
            &(text.to_string() + "[signal]\ninput_gain = 0.0\n"),
            Path::new("d.toml")
        )
        .is_err());
        assert!(parse_model_with_signal(
            &(text.to_string() + "[signal]\ngain = 1.0\n"),
            Path::new("e.toml")
        )
        .is_err());
    }

    #[test]
    fn every_table_round_trips() {
        let model = Model::linear(0.3, 1234.5, 0.07)
            .unwrap()
            .with_stiffness(-8.5e7, 2.4)
            .unwrap()
            .with_damping(0.013, -0.6)
            .unwrap();
        let doc = ModelDocument {
            model,
            signal: Some(SignalMap {
                input_gain: -1.77,
                input_offset: 3.1e-4,
                output_offset: -2.0e-5,
                input_interpolation: Some(nlsdof::excitation::InputInterpolation::Zoh),
                substeps: Some(8),
            }),
            provenance: Some(Provenance {
                tool: Some("nlsdof fit".into()),
                version: Some("0.1.0".into()),
                data: Some("dir with \"quotes\" and \\ back\nslash".into()),
                model: Some("generalised".into()),
                objective: Some("Eq 31 output error, m^2".into()),
                cost: Some(1.234_567_890_123_4e-9),
                converged: Some(false),
                range: Some("40650:105712".into()),
                integration_step: Some(1.0 / 4882.8125),
                integration_error: Some(2.5e-6),
            }),
        };
        let again = parse_document(&doc.to_toml(), Path::new("r.toml")).unwrap();
        assert_eq!(again, doc);
        // each table alone, and the stepped-sine gain table
        for d in [
            ModelDocument::new(model),
            ModelDocument {
                provenance: None,
                ..doc.clone()
            },
            ModelDocument {
                signal: None,
                ..doc.clone()
            },
        ] {
            assert_eq!(
                parse_document(&d.to_toml(), Path::new("r.toml")).unwrap(),
                d
            );
        }
        let text = model_to_toml(&model) + &forcing_gain_to_toml(1.7712345678901234);
        let d = parse_document(&text, Path::new("g.toml")).unwrap();
        assert_eq!(
            d.signal,
            Some(SignalMap {
                input_gain: 1.7712345678901234,
                ..SignalMap::default()
            })
        );
    }

    #[test]
    fn bad_tables_name_the_key() {
        let base = "mass = 1.0\nstiffness = 4.0\ndamping = 0.1\n";
        for (table, key) in [
            ("[signal]\ninput_gain = nan\n", "signal.input_gain"),
            ("[signal]\ninput_gain = inf\n", "signal.input_gain"),
            ("[signal]\ninput_offset = -inf\n", "signal.input_offset"),
            ("[signal]\noutput_offset = nan\n", "signal.output_offset"),
            ("[signal]\ninput_gain = 0.0\n", "signal.input_gain"),
            ("[signal]\nsubsteps = 0\n", "signal.substeps"),
            ("[signal]\ninput_interpolation = \"spline\"\n", "spline"),
            ("[provenance]\ncost = -1.0\n", "provenance.cost"),
            ("[provenance]\ncost = nan\n", "provenance.cost"),
            ("[provenance]\nwho = \"me\"\n", "who"),
        ] {
            let e = parse_document(&format!("{base}{table}"), Path::new("b.toml")).unwrap_err();
            assert!(e.to_string().contains(key), "{table}: {e}");
        }
    }

    #[test]
    fn rejects_bad_models() {
        let p = Path::new("bad.toml");
        assert!(matches!(
            parse_model("mass = -1.0\nstiffness = 1.0\ndamping = 0.0", p),
            Err(IoError::Invalid { .. })
        ));
        assert!(matches!(
            parse_model("mass = 1.0\nstiffness = 1.0", p),
            Err(IoError::Parse { .. })
        ));
        assert!(matches!(
            parse_model(
                "mass = 1.0\nstiffness = 1.0\ndamping = 0.0\nstifness = 2.0",
                p
            ),
            Err(IoError::Parse { .. })
        ));
        assert!(matches!(
            parse_model("mass = 1.0\nstiffness = 1.0\ndamping = 0.0\n[nonlinear_damping]\ncoefficient = 1.0\nexponent = -3.0", p),
            Err(IoError::Invalid { .. })
        ));
        assert!(matches!(
            parse_model("mass = nan\nstiffness = 1.0\ndamping = 0.0", p),
            Err(IoError::Invalid { .. })
        ));
    }
}
