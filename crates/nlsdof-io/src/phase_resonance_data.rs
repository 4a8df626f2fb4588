//! Reader of phase-resonance points (`nlsdof fit --phase-resonance`): per
//! input level the frequency and amplitude where the response lags the
//! input by 90° (like the experimental columns of the paper's Table 8).
//!
//! CSV, comma separated, one row per level, header with `gamma,f_hz,amplitude`
//! and optional `level` (label; default: the gamma field as written) and
//! `weight` (default 1) columns, any order. Lines starting with `#` and
//! blank lines are ignored anywhere (comment header lines). `gamma` is the
//! input acceleration amplitude (m/s², or g with [`ReadOptions::gamma_in_g`]),
//! `amplitude` the output displacement amplitude (m; velocity or
//! acceleration amplitudes are divided by Ω or Ω², Ω = 2π f_hz); both
//! zero-to-peak unless [`ReadOptions::peak_to_peak`] halves both — the same
//! options as the sweep reader ([`crate::stepped_sine_data`]).

use crate::csv_table::{column, lowercase, CsvOptions, CsvReadError, CsvRows, Row};
use crate::stepped_sine_data::{AmplitudeKind, ReadOptions, STANDARD_GRAVITY};
use nlsdof::identification::phase_resonance::{PrDataError, PrDataset, PrPoint};
use std::path::{Path, PathBuf};
use thiserror::Error;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// Errors reading phase-resonance points; each names the file and the
/// offending item.
#[derive(Debug, Error)]
pub enum PhaseResonanceDataError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: missing column '{column}' (phase-resonance points need gamma,f_hz,amplitude; optional level,weight)")]
    MissingColumn { path: PathBuf, column: &'static str },
    #[error("{path}: line {line}: {message}")]
    Line {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: {source}")]
    Data { path: PathBuf, source: PrDataError },
}

/// Parses phase-resonance points from CSV text (`path` only names it in errors).
pub fn parse_csv(
    text: &str,
    path: &Path,
    opts: &ReadOptions,
) -> Result<PrDataset, PhaseResonanceDataError> {
    let mut rows = CsvRows::new(text.as_bytes(), CsvOptions::default());
    let read_err = |e: CsvReadError| PhaseResonanceDataError::Read {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
    };
    let Some((_, header)) = rows.next_row().map_err(read_err)? else {
        return Err(PhaseResonanceDataError::Data {
            path: path.into(),
            source: PrDataError::Empty,
        });
    };
    let cols = lowercase(header);
    let find = |name: &'static str| column(&cols, name);
    let need = |name: &'static str| {
        find(name).ok_or(PhaseResonanceDataError::MissingColumn {
            path: path.into(),
            column: name,
        })
    };
    let (cg, cf, ca) = (need("gamma")?, need("f_hz")?, need("amplitude")?);
    let (cl, cw) = (find("level"), find("weight"));
    let pp = if opts.peak_to_peak { 0.5 } else { 1.0 };
    let g_unit = if opts.gamma_in_g {
        STANDARD_GRAVITY
    } else {
        1.0
    };
    let mut points = Vec::new();
    while let Some((lineno, fields)) = rows.next_row().map_err(read_err)? {
        let err = |message: String| PhaseResonanceDataError::Line {
            path: path.into(),
            line: lineno as usize,
            message,
        };
        let row = Row::new(fields, cols.len()).map_err(err)?;
        let get = |c: usize, name: &str| row.field(c, name).map_err(err);
        let num = |c: usize, name: &str| row.number(c, name).map_err(err);
        let f = num(cf, "f_hz")?;
        let omega = TWO_PI * f;
        let gamma = num(cg, "gamma")? * pp * g_unit;
        let amplitude = num(ca, "amplitude")?
            * pp
            * match opts.amplitude {
                AmplitudeKind::Displacement => 1.0,
                AmplitudeKind::Velocity => 1.0 / omega,
                AmplitudeKind::Acceleration => 1.0 / (omega * omega),
            };
        let level = match cl {
            Some(c) => get(c, "level")?.to_string(),
            None => get(cg, "gamma")?.to_string(),
        };
        let weight = match cw {
            Some(c) => num(c, "weight")?,
            None => 1.0,
        };
        points.push(PrPoint {
            level,
            gamma,
            omega,
            amplitude,
            weight,
        });
    }
    PrDataset::new(points).map_err(|source| PhaseResonanceDataError::Data {
        path: path.into(),
        source,
    })
}

/// Reads phase-resonance points from a CSV file.
pub fn read_csv(path: &Path, opts: &ReadOptions) -> Result<PrDataset, PhaseResonanceDataError> {
    let text = crate::text::read_text(path).map_err(|e| match e {
        crate::text::TextFileError::Read(source) => PhaseResonanceDataError::Read {
            path: path.into(),
            source,
        },
        e => PhaseResonanceDataError::Read {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
        },
    })?;
    parse_csv(&text, path, opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str =
        "# comment\ngamma,f_hz,amplitude\n0.82,5.3950,0.02662\n\n# another\n1.24,5.3955,0.03558\n";

    #[test]
    fn reads_with_comments_and_conversions() {
        let p = Path::new("t.csv");
        let d = parse_csv(TEXT, p, &ReadOptions::default()).unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d.points[0].level, "0.82");
        assert!((d.points[1].omega - TWO_PI * 5.3955).abs() < 1e-12);
        assert_eq!(d.points[0].weight, 1.0);
        let h = parse_csv(
            TEXT,
            p,
            &ReadOptions {
                peak_to_peak: true,
                gamma_in_g: true,
                amplitude: AmplitudeKind::Velocity,
            },
        )
        .unwrap();
        assert!((h.points[0].gamma - 0.41 * STANDARD_GRAVITY).abs() < 1e-14);
        assert!((h.points[0].amplitude - 0.01331 / (TWO_PI * 5.395)).abs() < 1e-15);
        let a = parse_csv(
            TEXT,
            p,
            &ReadOptions {
                amplitude: AmplitudeKind::Acceleration,
                ..Default::default()
            },
        )
        .unwrap();
        assert!((a.points[0].amplitude - 0.02662 / (TWO_PI * 5.395f64).powi(2)).abs() < 1e-16);
        // level and weight columns in any order
        let t = "weight,amplitude,level,f_hz,gamma\n2,1e-3,low,10,0.1\n1,2e-3,high,10.1,0.2\n";
        let d = parse_csv(t, p, &ReadOptions::default()).unwrap();
        assert_eq!(d.points[0].level, "low");
        assert_eq!(d.points[0].weight, 2.0);
    }

    #[test]
    fn errors_name_the_file_line_and_value() {
        let p = Path::new("t.csv");
        let e = parse_csv("gamma,f_hz\n1,2\n", p, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("t.csv") && e.contains("'amplitude'"), "{e}");
        let e = parse_csv(&TEXT.replace("0.03558", "x"), p, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 6") && e.contains("'x'"), "{e}");
        let e = parse_csv(&TEXT.replace("1.24", "0.82"), p, &ReadOptions::default()).unwrap_err();
        assert!(matches!(
            e,
            PhaseResonanceDataError::Data {
                source: PrDataError::DuplicateGamma { .. },
                ..
            }
        ));
        let e = parse_csv(&TEXT.replace("0.03558", "-1"), p, &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("amplitude = -1"), "{e}");
        let e = parse_csv("# only a comment\n", p, &ReadOptions::default()).unwrap_err();
        assert!(matches!(
            e,
            PhaseResonanceDataError::Data {
                source: PrDataError::Empty,
                ..
            }
        ));
        let e = parse_csv("gamma,f_hz,amplitude\n", p, &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("no phase-resonance points"), "{e}");
    }
}
