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
//! [signal]                # optional (nlsdof fit-time): recorded signals <-> model
//! input_gain = 1.0        # gamma = input_gain * (u + input_offset)
//! input_offset = 0.0      # in the input's unit
//! output_offset = 0.0     # y = x + output_offset, in the output's unit
//! ```
//!
//! Unknown keys are rejected (a typo must not silently drop a term). A file
//! without `[signal]` means gain 1 and no offsets (backward compatible).

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
}

fn one() -> f64 {
    1.0
}

impl Default for SignalMap {
    fn default() -> Self {
        Self {
            input_gain: 1.0,
            input_offset: 0.0,
            output_offset: 0.0,
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

/// Parses model TOML text and its optional `[signal]` table (gain and
/// offsets must be finite, the gain non-zero).
pub fn parse_model_with_signal(
    text: &str,
    path: &Path,
) -> Result<(Model, Option<SignalMap>), IoError> {
    let file: ModelFile = toml::from_str(crate::strip_bom(text)).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        message: e.message().to_string(),
    })?;
    let model = file.to_model().map_err(|source| IoError::Invalid {
        path: path.to_path_buf(),
        source,
    })?;
    if let Some(s) = &file.signal {
        for (name, v) in [
            ("signal.input_gain", s.input_gain),
            ("signal.input_offset", s.input_offset),
            ("signal.output_offset", s.output_offset),
        ] {
            if !v.is_finite() {
                return Err(IoError::Invalid {
                    path: path.to_path_buf(),
                    source: nlsdof::ParameterError::NotFinite { name, value: v },
                });
            }
        }
        if s.input_gain == 0.0 {
            return Err(IoError::Parse {
                path: path.to_path_buf(),
                message: "signal.input_gain = 0 would disconnect the input".into(),
            });
        }
    }
    Ok((model, file.signal))
}

/// Reads a model file with its optional `[signal]` table.
pub fn read_model_with_signal(path: &Path) -> Result<(Model, Option<SignalMap>), IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_model_with_signal(&text, path)
}

/// The `[signal]` table as TOML text (appended to [`model_to_toml`]).
pub fn signal_to_toml(s: &SignalMap) -> String {
    format!(
        "\n[signal]                # recorded signals <-> model\ninput_gain = {:?}      # gamma = input_gain * (u + input_offset)\ninput_offset = {:?}    # input unit\noutput_offset = {:?}   # y = x + output_offset, output unit\n",
        s.input_gain, s.input_offset, s.output_offset
    )
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
