//! Readers of measured stepped-sine amplitude curves for the identification
//! (`nlsdof fit` / `nlsdof compare`).
//!
//! * **Long CSV**: header with `level,gamma,f_hz,amplitude` and optional
//!   `phase_deg`, `sweep` (`up`/`down`, default `up`) and `weight`
//!   (default 1) columns, any order, comma separated, one row per step.
//!   `gamma` is the input acceleration amplitude, `amplitude` the output
//!   amplitude; both zero-to-peak unless [`ReadOptions::peak_to_peak`].
//! * **Beam directory** (the layout of
//!   `clamped-beam-duffing-catarinaluz/cc_beam_*`): files `frf_<A>g.txt`,
//!   tab separated with decimal commas, two header lines, then rows
//!   `f [Hz] | v_up [m/s] | phase_up [deg] | v_down [m/s] | phase_down [deg]`
//!   (velocity amplitudes of the up and the down run side by side). The
//!   level `A` (g) is taken from the file name; displacement = v / Ω. The
//!   phases are relative to the vibrometer's reference channel, not a lag
//!   behind the base acceleration, so they are not used.
//! * **Universal file** (`.uff`/`.unv`, dataset 58/58b, [`read_uff`]): one
//!   complex FRF per level and sweep — every dataset 58 with complex values
//!   and function type 4 (FRF) or 5 (transmissibility); other functions
//!   (spectra, coherences, time responses) are skipped. Each is a response
//!   over the input (base) acceleration: the ordinate numerator (record 9)
//!   a displacement (specific data type 8 or units `m`: receptance,
//!   m/(m/s²)), velocity (11, `m/s`) or acceleration (12, `m/s^2`:
//!   accelerance or transmissibility), the denominator (record 10) an
//!   acceleration (12 or `m/s^2`); other quantities, units other than SI
//!   and a missing quantity are refused ([`crate::uff_convert::quantity`]).
//!   The abscissa must be a frequency in Hz (> 0). With `H` the FRF value
//!   and `γ` the level, the displacement phasor is `X = H γ` for a
//!   displacement, `V γ / (jΩ)` for a velocity and `−A γ / Ω²` for an
//!   acceleration, so the amplitude is `a = |H| γ`, `|H| γ / Ω` and
//!   `|H| γ / Ω²`. **Phase**: the model's convention `x = a cos(Ωt − φ)`
//!   under the input `γ cos(Ωt)` is `X = a e^{−jφ}` (time factor
//!   `e^{+jΩt}`, as FRFs are written), so the phase lag is
//!   `φ = −arg X` in (−180°, 180°], the `phase_deg` of the long CSV:
//!   `nlsdof frf --uff` writes `H = (a/γ) e^{−jφ}`.
//!   **Level** `γ` (m/s², zero-to-peak), first found of: the CLI's list
//!   (`--level-gamma`, one value a dataset in file order); a token
//!   `gamma=VALUE` (m/s²) in an ID line; the z-axis value (record 7 field 6)
//!   when the z axis (record 11) is an acceleration — units label `m/s^2`,
//!   or `g` (× 9.80665), or specific data type 12 without a units label. A
//!   dataset without a level is refused. **Sweep** direction: a token
//!   `sweep=up|down` in an ID line, default up. **Level name**: a token
//!   `level=NAME`, else the value of γ (so the up and down sweeps of one
//!   level form one level). Weights are 1.

use crate::csv_table::{
    column, lowercase, number, CsvOptions, CsvReadError, CsvRows, Row, Separator,
};
use nlsdof::identification::{DataError, Dataset, Record};
use nlsdof::SweepDirection;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Standard gravity, m/s² (used for levels given in g).
pub const STANDARD_GRAVITY: f64 = 9.80665;
const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// What the amplitude column measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AmplitudeKind {
    /// Displacement amplitude, m (default).
    #[default]
    Displacement,
    /// Velocity amplitude, m/s (divided by Ω).
    Velocity,
    /// Acceleration amplitude, m/s² (divided by Ω²).
    Acceleration,
}

/// Unit conversions applied while reading.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReadOptions {
    pub amplitude: AmplitudeKind,
    /// `gamma` column in g (× 9.80665).
    pub gamma_in_g: bool,
    /// Both `gamma` and `amplitude` are peak-to-peak (halved).
    pub peak_to_peak: bool,
}

/// Which runs of a beam file to read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Runs {
    Up,
    Down,
    Both,
}

/// Errors reading measured curves; each names the file and the offending item.
#[derive(Debug, Error)]
pub enum SteppedSineDataError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: missing column '{column}' (need level,gamma,f_hz,amplitude; optional phase_deg,sweep,weight)")]
    MissingColumn { path: PathBuf, column: &'static str },
    #[error("{path}: line {line}: {message}")]
    Line {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The file's format or layout is not what was expected: what it is
    /// and what to do.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    #[error("{path}: no file named frf_<A>g.txt in the directory")]
    NoBeamFiles { path: PathBuf },
    #[error("{path}: {source}")]
    Data { path: PathBuf, source: DataError },
    /// A universal file that holds no usable stepped-sine FRFs
    /// ([`read_uff`]).
    #[error("{path}: {message}")]
    Uff { path: PathBuf, message: String },
}

fn convert(opts: &ReadOptions, gamma: f64, omega: f64, amplitude: f64) -> (f64, f64) {
    let pp = if opts.peak_to_peak { 0.5 } else { 1.0 };
    let g = gamma
        * pp
        * if opts.gamma_in_g {
            STANDARD_GRAVITY
        } else {
            1.0
        };
    let a = amplitude
        * pp
        * match opts.amplitude {
            AmplitudeKind::Displacement => 1.0,
            AmplitudeKind::Velocity => 1.0 / omega,
            AmplitudeKind::Acceleration => 1.0 / (omega * omega),
        };
    (g, a)
}

/// One row of the long format, as read (before the [`ReadOptions`]).
#[derive(Debug, Clone, Copy)]
pub struct Columns<'a> {
    pub level: &'a str,
    /// Input level (unit per [`ReadOptions`]).
    pub gamma: f64,
    pub f_hz: f64,
    /// Amplitude (kind and unit per [`ReadOptions`]).
    pub amplitude: f64,
    /// Phase lag, degrees.
    pub phase_deg: Option<f64>,
    /// `up` or `down` (case-insensitive); empty or `None`: up.
    pub sweep: Option<&'a str>,
    pub weight: Option<f64>,
}

/// The record of one row: γ and the amplitude converted to zero-to-peak SI
/// displacement, Ω = 2π f, the phase in radians. The CSV reader and the
/// Python module (columns given as arrays) both build their records here.
pub fn record(opts: &ReadOptions, row: &Columns) -> Result<Record, String> {
    let omega = TWO_PI * row.f_hz;
    let (gamma, amplitude) = convert(opts, row.gamma, omega, row.amplitude);
    let direction = match row.sweep {
        None | Some("") => SweepDirection::Up,
        Some(s) if s.eq_ignore_ascii_case("up") => SweepDirection::Up,
        Some(s) if s.eq_ignore_ascii_case("down") => SweepDirection::Down,
        Some(s) => return Err(format!("sweep = '{s}' must be 'up' or 'down'")),
    };
    Ok(Record {
        level: row.level.to_string(),
        gamma,
        omega,
        amplitude,
        phase: row.phase_deg.map(f64::to_radians),
        direction,
        weight: row.weight.unwrap_or(1.0),
    })
}

/// Parses the long CSV format from text (`path` only names it in errors).
pub fn parse_csv(
    text: &str,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dataset, SteppedSineDataError> {
    // a European spreadsheet export: `;` or tab between fields, decimal
    // commas (then a comma is only ever a decimal comma)
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    let separator = if !first.contains(',') && first.contains(';') {
        Some(Separator::Semicolon)
    } else if !first.contains(',') && first.contains('\t') {
        Some(Separator::Tab)
    } else {
        None
    };
    let text: std::borrow::Cow<str> = match separator {
        Some(_) if text.contains(',') => text.replace(',', ".").into(),
        _ => text.into(),
    };
    let csv_opts = separator.map_or(CsvOptions::default(), |s| {
        CsvOptions::default().with_separator(s)
    });
    let mut rows = CsvRows::new(text.as_bytes(), csv_opts);
    let read_err = |e: CsvReadError| SteppedSineDataError::Read {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
    };
    let Some((_, header)) = rows.next_row().map_err(read_err)? else {
        return Err(SteppedSineDataError::Data {
            path: path.into(),
            source: DataError::Empty,
        });
    };
    let cols = lowercase(header);
    let find = |name: &'static str| column(&cols, name);
    let need = |name: &'static str| {
        find(name).ok_or_else(|| match crate::input::separator_hint(header) {
            // the separator explains the missing column: say so first
            Some(hint) => SteppedSineDataError::Format {
                path: path.into(),
                message: format!("missing column '{name}': {hint}"),
            },
            None => SteppedSineDataError::MissingColumn {
                path: path.into(),
                column: name,
            },
        })
    };
    let (cl, cg, cf, ca) = (
        need("level")?,
        need("gamma")?,
        need("f_hz")?,
        need("amplitude")?,
    );
    let (cp, cs, cw) = (find("phase_deg"), find("sweep"), find("weight"));
    let mut recs = Vec::new();
    while let Some((lineno, fields)) = rows.next_row().map_err(read_err)? {
        let err = |message: String| SteppedSineDataError::Line {
            path: path.into(),
            line: lineno as usize,
            message,
        };
        let row = Row::new(fields, cols.len()).map_err(err)?;
        let get = |c: usize, name: &str| row.field(c, name).map_err(err);
        let num = |c: usize, name: &str| row.number(c, name).map_err(err);
        let row = Columns {
            level: get(cl, "level")?,
            f_hz: num(cf, "f_hz")?,
            gamma: num(cg, "gamma")?,
            amplitude: num(ca, "amplitude")?,
            phase_deg: cp.map(|c| num(c, "phase_deg")).transpose()?,
            sweep: cs.map(|c| get(c, "sweep")).transpose()?,
            weight: cw.map(|c| num(c, "weight")).transpose()?,
        };
        recs.push(record(opts, &row).map_err(err)?);
    }
    Dataset::from_records(&recs).map_err(|source| SteppedSineDataError::Data {
        path: path.into(),
        source,
    })
}

/// Reads the long CSV format from a file.
pub fn read_csv(path: &Path, opts: &ReadOptions) -> Result<Dataset, SteppedSineDataError> {
    // UTF-8, or Latin-1/Windows-1252 (read, not refused); binary refused
    // naming what it is
    let text = crate::text::read_text(path).map_err(|e| match e {
        crate::text::TextFileError::Read(source) => SteppedSineDataError::Read {
            path: path.into(),
            source,
        },
        e => SteppedSineDataError::Format {
            path: path.into(),
            message: e.to_string(),
        },
    })?;
    parse_csv(&text, path, opts)
}

/// Reads stepped-sine FRFs from a universal file (see the module
/// documentation): one curve per complex FRF dataset. `level_gamma`, when
/// given, holds the level γ (m/s², zero-to-peak) of each such dataset in
/// file order and overrides the header.
pub fn read_uff(path: &Path, level_gamma: Option<&[f64]>) -> Result<Dataset, SteppedSineDataError> {
    use crate::uff58::{Uff58Data, Uff58Function};
    use crate::uff_convert::{check_frequency_axis, id_token, listing, quantity, Quantity};
    let uff = |message: String| SteppedSineDataError::Uff {
        path: path.into(),
        message,
    };
    let all = crate::uff58::read(path).map_err(|e| uff(e.to_string()))?;
    let frfs: Vec<&Uff58Function> = all
        .iter()
        .filter(|f| f.info.complex && matches!(f.dataset.header.function_type, 4 | 5))
        .collect();
    if frfs.is_empty() {
        return Err(uff(format!(
            "no complex FRF or transmissibility (function type 4 or 5) among the datasets ({})",
            if all.is_empty() {
                "none".to_string()
            } else {
                listing(&all, 0)
            }
        )));
    }
    if let Some(g) = level_gamma {
        if g.len() != frfs.len() {
            return Err(uff(format!(
                "--level-gamma gives {} level(s) but the file holds {} FRF dataset(s) (indices {})",
                g.len(),
                frfs.len(),
                frfs.iter()
                    .map(|f| f.info.index.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    let mut recs = Vec::new();
    for (n, f) in frfs.iter().enumerate() {
        let h = &f.dataset.header;
        let label = format!("dataset {} ({:?})", f.info.index, h.id1.trim());
        check_frequency_axis(&label, h).map_err(uff)?;
        let num = quantity(
            &format!("{label}: ordinate numerator (record 9)"),
            &h.ordinate_axis,
        )
        .map_err(uff)?;
        let den = quantity(
            &format!("{label}: ordinate denominator (record 10)"),
            &h.denominator_axis,
        )
        .map_err(uff)?;
        let power = match num {
            Some(Quantity::Displacement) => 0,
            Some(Quantity::Velocity) => 1,
            Some(Quantity::Acceleration) => 2,
            other => {
                return Err(uff(format!(
                    "{label}: the ordinate numerator (record 9) is {}: need a displacement (m), velocity (m/s) or acceleration (m/s^2) response",
                    other.map_or("not stated (specific data type 0/1, no units label)", |q| q.name())
                )))
            }
        };
        if den != Some(Quantity::Acceleration) {
            return Err(uff(format!(
                "{label}: the ordinate denominator (record 10) is {}: fit needs the response per input (base) acceleration (m/s^2)",
                den.map_or("not stated (specific data type 0/1, no units label)", |q| q.name())
            )));
        }
        let gamma = match level_gamma {
            Some(g) => g[n],
            None => level_of(h).map_err(|m| uff(format!("{label}: {m}")))?.ok_or_else(|| {
                uff(format!(
                    "{label} states no level: give gamma=VALUE (m/s^2) in an ID line, a z-axis value with an acceleration z axis (units m/s^2 or g), or the levels with --level-gamma"
                ))
            })?,
        };
        if !(gamma.is_finite() && gamma > 0.0) {
            return Err(uff(format!(
                "{label}: level gamma {gamma} m/s^2 must be finite and > 0"
            )));
        }
        let direction = match id_token(h, "sweep") {
            None => SweepDirection::Up,
            Some((_, v)) if v.eq_ignore_ascii_case("up") => SweepDirection::Up,
            Some((_, v)) if v.eq_ignore_ascii_case("down") => SweepDirection::Down,
            Some((line, v)) => {
                return Err(uff(format!(
                    "{label}: ID line {line}: sweep={v} must be up or down"
                )))
            }
        };
        let level = id_token(h, "level").map_or_else(|| format!("{gamma}"), |(_, v)| v);
        let Uff58Data::Complex(values) = &f.dataset.data else {
            continue; // filtered above: complex only
        };
        let f_hz = f.dataset.abscissa_values();
        for (k, (&fr, &(re, im))) in f_hz.iter().zip(values).enumerate() {
            if !(fr.is_finite() && fr > 0.0) {
                return Err(uff(format!(
                    "{label}: point {k}: frequency {fr} Hz must be finite and > 0"
                )));
            }
            if !(re.is_finite() && im.is_finite()) {
                return Err(uff(format!(
                    "{label}: point {k} ({fr} Hz): value ({re}, {im}) is not finite"
                )));
            }
            let omega = TWO_PI * fr;
            // displacement phasor X = H gamma / (j Omega)^power
            let (xr, xi) = match power {
                0 => (re * gamma, im * gamma),
                1 => (im * gamma / omega, -re * gamma / omega),
                _ => (-re * gamma / (omega * omega), -im * gamma / (omega * omega)),
            };
            recs.push(Record {
                level: level.clone(),
                gamma,
                omega,
                amplitude: xr.hypot(xi),
                phase: Some(-xi.atan2(xr)),
                direction,
                weight: 1.0,
            });
        }
    }
    Dataset::from_records(&recs).map_err(|source| SteppedSineDataError::Data {
        path: path.into(),
        source,
    })
}

/// The level γ (m/s²) a dataset's header states (see the module
/// documentation), `None` when it states none.
fn level_of(h: &crate::uff58::Uff58Header) -> Result<Option<f64>, String> {
    if let Some((line, v)) = crate::uff_convert::id_token(h, "gamma") {
        return match v.parse::<f64>() {
            Ok(g) => Ok(Some(g)),
            Err(_) => Err(format!("ID line {line}: gamma={v} is not a number (m/s^2)")),
        };
    }
    let z = &h.z_axis;
    let units: String = z.units.chars().filter(|c| !c.is_whitespace()).collect();
    let scale = match units.as_str() {
        "m/s^2" | "m/s2" | "m/s**2" | "m/s\u{b2}" => Some(1.0),
        "g" => Some(STANDARD_GRAVITY),
        "" | "NONE" | "none" if z.specific_data_type == 12 => Some(1.0),
        _ => None,
    };
    Ok(scale.map(|s| h.z_axis_value * s))
}

/// How a fit names beam-directory data (the model file's
/// `provenance.data`): `DIR (beam directory, runs R)`.
pub fn beam_source_name(dir: &Path, runs: Runs) -> String {
    let r = match runs {
        Runs::Up => "up",
        Runs::Down => "down",
        Runs::Both => "both",
    };
    format!("{} (beam directory, runs {r})", dir.display())
}

/// The level in g from a beam file name `frf_<A>g.txt`.
pub fn beam_level_g(file_name: &str) -> Option<f64> {
    let s = file_name
        .strip_prefix("frf_")?
        .strip_suffix(".txt")?
        .strip_suffix('g')?;
    s.replace(',', ".")
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && *v > 0.0)
}

/// Records of one beam file (velocity amplitudes converted to displacement;
/// phases in rad as measured, in the instrument's convention — see
/// `nlsdof::identification::equation_error` for how the convention is
/// detected).
pub fn parse_beam_file(
    text: &str,
    path: &Path,
    level_g: f64,
    runs: Runs,
) -> Result<Vec<Record>, SteppedSineDataError> {
    let label = format!("{level_g}g");
    let gamma = level_g * STANDARD_GRAVITY;
    let mut recs = Vec::new();
    let opts = CsvOptions::default()
        .with_separator(Separator::Tab)
        .with_decimal_comma();
    let mut rows = CsvRows::new(text.as_bytes(), opts);
    let read_err = |e: CsvReadError| SteppedSineDataError::Read {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
    };
    while let Some((line, fields)) = rows.next_row().map_err(read_err)? {
        // two header lines
        if line <= 2 {
            continue;
        }
        let lineno = line as usize;
        let num = |k: usize, name: &str| -> Result<f64, SteppedSineDataError> {
            let s = fields.get(k).ok_or_else(|| SteppedSineDataError::Line {
                path: path.into(),
                line: lineno,
                message: format!("missing column {} ({name})", k + 1),
            })?;
            number(s, opts).ok_or_else(|| SteppedSineDataError::Line {
                path: path.into(),
                line: lineno,
                message: format!("{name} = '{s}' is not a number"),
            })
        };
        let f = num(0, "frequency")?;
        let omega = TWO_PI * f;
        let mut push =
            |col: usize, dir: SweepDirection, name: &str| -> Result<(), SteppedSineDataError> {
                let v = num(col, name)?;
                // the phase as measured (the vibrometer's convention, velocity
                // against its reference channel): the identification detects
                // the sign and offset from the data
                let ph = num(col + 1, "phase")?;
                recs.push(Record {
                    level: label.clone(),
                    gamma,
                    omega,
                    amplitude: v / omega,
                    phase: Some(ph.to_radians()),
                    direction: dir,
                    weight: 1.0,
                });
                Ok(())
            };
        if matches!(runs, Runs::Up | Runs::Both) {
            push(1, SweepDirection::Up, "up-run velocity")?;
        }
        if matches!(runs, Runs::Down | Runs::Both) {
            push(3, SweepDirection::Down, "down-run velocity")?;
        }
    }
    Ok(recs)
}

/// Reads every `frf_<A>g.txt` of a beam directory (levels in increasing order).
pub fn read_beam_dir(dir: &Path, runs: Runs) -> Result<Dataset, SteppedSineDataError> {
    let rd = std::fs::read_dir(dir).map_err(|source| SteppedSineDataError::Read {
        path: dir.into(),
        source,
    })?;
    let mut files: Vec<(f64, PathBuf)> = Vec::new();
    for e in rd {
        let e = e.map_err(|source| SteppedSineDataError::Read {
            path: dir.into(),
            source,
        })?;
        let name = e.file_name().to_string_lossy().into_owned();
        if let Some(a) = beam_level_g(&name) {
            files.push((a, e.path()));
        }
    }
    if files.is_empty() {
        return Err(SteppedSineDataError::NoBeamFiles { path: dir.into() });
    }
    files.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut recs = Vec::new();
    for (a, p) in &files {
        let bytes = std::fs::read(p).map_err(|source| SteppedSineDataError::Read {
            path: p.clone(),
            source,
        })?;
        // latin-1/ASCII: map bytes to chars one to one
        let text: String = bytes.iter().map(|&b| b as char).collect();
        recs.extend(parse_beam_file(&text, p, *a, runs)?);
    }
    Dataset::from_records(&recs).map_err(|source| SteppedSineDataError::Data {
        path: dir.into(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_with_conversions_and_errors() {
        let text = "level,gamma,f_hz,amplitude,sweep\n1,0.1,10,2e-3,up\n1,0.1,11,3e-3,up\n1,0.1,12,2e-3,up\n2,0.2,10,4e-3,down\n2,0.2,11,6e-3,down\n2,0.2,12,4e-3,down\n";
        let p = Path::new("x.csv");
        let d = parse_csv(
            text,
            p,
            &ReadOptions {
                gamma_in_g: true,
                peak_to_peak: true,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(d.curves.len(), 2);
        assert!((d.curves[0].gamma - 0.05 * STANDARD_GRAVITY).abs() < 1e-15);
        assert!((d.curves[0].amplitudes[0] - 1e-3).abs() < 1e-18);
        assert_eq!(d.curves[1].direction, SweepDirection::Down);
        let v = parse_csv(
            text,
            p,
            &ReadOptions {
                amplitude: AmplitudeKind::Velocity,
                ..Default::default()
            },
        )
        .unwrap();
        assert!((v.curves[0].amplitudes[0] - 2e-3 / (TWO_PI * 10.0)).abs() < 1e-18);
        let bad = text.replace("3e-3", "abc");
        let e = parse_csv(&bad, p, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("abc"), "{e}");
        let e = parse_csv("level,gamma,f_hz\n", p, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("amplitude"), "{e}");
        let neg = text.replace("6e-3", "-6e-3");
        let e = parse_csv(&neg, p, &ReadOptions::default()).unwrap_err();
        assert!(matches!(
            e,
            SteppedSineDataError::Data {
                source: DataError::NegativeAmplitude { .. },
                ..
            }
        ));
    }

    #[test]
    fn uff_transmissibility_as_pyuff_reads_it() {
        // pyuff's oracle: function type 5, acceleration over acceleration,
        // no level in the header
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/uff58/ascii_single_complex_uneven_transmissibility.uff");
        let e = read_uff(&p, None).unwrap_err().to_string();
        assert!(e.contains("states no level"), "{e}");
        let text = std::fs::read_to_string(p.with_extension("uff.json")).unwrap();
        let j: serde_json::Value = serde_json::from_str(&text).unwrap();
        let num = |v: &serde_json::Value| v.as_str().unwrap().parse::<f64>().unwrap();
        let set = &j["sets"][0];
        let (x, data) = (
            set["x"].as_array().unwrap(),
            set["data"].as_array().unwrap(),
        );
        let gamma = 2.5;
        let d = read_uff(&p, Some(&[gamma])).unwrap();
        assert_eq!(d.curves.len(), 1);
        let c = &d.curves[0];
        assert_eq!((c.gamma, c.direction), (gamma, SweepDirection::Up));
        let phases = c.phases.as_ref().unwrap();
        for k in 0..x.len() {
            let (f, re, im) = (num(&x[k]), num(&data[k][0]), num(&data[k][1]));
            let w = TWO_PI * f;
            assert!((c.omegas[k] - w).abs() <= 1e-15 * w);
            let a = re.hypot(im) * gamma / (w * w);
            assert!((c.amplitudes[k] - a).abs() <= 1e-15 * a, "{k}");
            // X = -A gamma / w^2: the lag is -arg(-A)
            let lag = -((-im).atan2(-re));
            assert!((phases[k] - lag).abs() <= 1e-15, "{k}");
        }
    }

    #[test]
    fn uff_receptance_phase_level_and_sweep_tokens() {
        use crate::uff58::{write_binary_file, Abscissa, AxisInfo, Uff58Dataset};
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.uff");
        // a = 2e-3 m lagging 30 deg at 10, 11 and 12 Hz, gamma = 0.25 g in the z axis,
        // as a velocity per acceleration: V/gamma = j Omega a e^{-j phi} / gamma
        let (a, phi, gamma) = (2e-3, 30f64.to_radians(), 0.25 * STANDARD_GRAVITY);
        let h = [10.0, 11.0, 12.0]
            .iter()
            .map(|f| {
                let w = TWO_PI * f;
                (w * a * phi.sin() / gamma, w * a * phi.cos() / gamma)
            })
            .collect();
        let mut d = Uff58Dataset::frf(Abscissa::Uneven(vec![10.0, 11.0, 12.0]), h);
        d.header.id4 = "sweep=down level=L1".into();
        d.header.ordinate_axis = AxisInfo::new(0, "Velocity", "m/s");
        d.header.denominator_axis = AxisInfo::new(12, "Acceleration", "NONE");
        d.header.z_axis = AxisInfo::new(1, "Level", "g");
        d.header.z_axis_value = 0.25;
        write_binary_file(&p, &[d.clone()]).unwrap();
        let s = read_uff(&p, None).unwrap();
        let c = &s.curves[0];
        assert_eq!(
            (c.level.as_str(), c.direction),
            ("L1", SweepDirection::Down)
        );
        assert_eq!(c.gamma, gamma);
        for k in 0..3 {
            assert!((c.amplitudes[k] - a).abs() <= 1e-15 * a);
            assert!((c.phases.as_ref().unwrap()[k] - phi).abs() <= 1e-15);
        }
        d.header.id4 = "sweep=sideways".into();
        write_binary_file(&p, &[d.clone()]).unwrap();
        let e = read_uff(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("ID line 4: sweep=sideways must be up or down"),
            "{e}"
        );
        d.header.id4 = "gamma=abc".into();
        write_binary_file(&p, &[d]).unwrap();
        let e = read_uff(&p, None).unwrap_err().to_string();
        assert!(e.contains("ID line 4: gamma=abc is not a number"), "{e}");
    }

    #[test]
    fn beam_file_layout() {
        assert_eq!(beam_level_g("frf_0.04g.txt"), Some(0.04));
        assert_eq!(beam_level_g("frf_0.10g.txt"), Some(0.1));
        assert_eq!(beam_level_g("notes.txt"), None);
        let text = "X-Data [Hz]\tLaser\tPhase\tLaser\tPhase\t\r\n\t003\t\t004\t\r\n         120\t  0,00356758\t57,0\t  0,00322345\t57,3\r\n     120,088\t  0,00368738\t71,0\t   0,0033756\t58,1\r\n\r\n";
        let r = parse_beam_file(text, Path::new("f"), 0.04, Runs::Both).unwrap();
        assert_eq!(r.len(), 4);
        assert!((r[0].amplitude - 0.00356758 / (TWO_PI * 120.0)).abs() < 1e-18);
        assert_eq!(r[1].direction, SweepDirection::Down);
        assert!((r[2].omega - TWO_PI * 120.088).abs() < 1e-9);
    }
}
