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
    #[error("{path}: no file named frf_<A>g.txt in the directory")]
    NoBeamFiles { path: PathBuf },
    #[error("{path}: {source}")]
    Data { path: PathBuf, source: DataError },
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
    let mut rows = CsvRows::new(text.as_bytes(), CsvOptions::default());
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
        find(name).ok_or(SteppedSineDataError::MissingColumn {
            path: path.into(),
            column: name,
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
    let text = std::fs::read_to_string(path).map_err(|source| SteppedSineDataError::Read {
        path: path.into(),
        source,
    })?;
    parse_csv(&text, path, opts)
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
