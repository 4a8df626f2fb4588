//! Numeric columns of a delimited text table, chosen by name or index
//! (recorded input/output pairs for `nlsdof fit-time`).
//!
//! * Comma-separated (tab or semicolon also detected from the first line);
//!   a header line is detected when one of its fields is not a number, and
//!   quoted names are unquoted (`"V1","V2",` — the Silverbox files — has
//!   columns `V1`, `V2` and an empty trailing field, which is ignored).
//! * A column is named by its header name (case-insensitive) or by its
//!   0-based index.
//! * LabVIEW `.lvm` text: everything up to the second `***End_of_Header***`
//!   line is skipped, then the tab-separated column names and rows.
//! * Polytec ASCII export (the beam impact records): a preamble of
//!   `Key:\tvalue` lines, a tab-separated header (`Time\tTime Signal`) and a
//!   line of bracketed units (`[ s ]\t[ m/s ]`); the header is the line
//!   before the units line, and the units line is skipped.
//! * Blank lines and lines starting with `#` are skipped. Every selected
//!   field must be a finite number; errors name the file, the line and the
//!   field. Unselected columns are not parsed (they may be empty).

use crate::csv_table::{CsvOptions, CsvRows, Encoding, Separator};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors reading a table.
#[derive(Debug, Error)]
pub enum TableError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no data rows")]
    Empty { path: PathBuf },
    #[error("{path}: {what}")]
    NotText { path: PathBuf, what: String },
    #[error(
        "{path}: no column \"{wanted}\" (columns: {found}; give a header name or a 0-based index)", wanted = crate::text::shown(.wanted), found = crate::text::shown(.found)
    )]
    MissingColumn {
        path: PathBuf,
        wanted: String,
        found: String,
    },
    #[error("{path}: line {line}: column \"{column}\" is missing (the line has {fields} field(s))", column = crate::text::shown(.column))]
    ShortLine {
        path: PathBuf,
        line: u64,
        column: String,
        fields: usize,
    },
    #[error("{path}: line {line}: column \"{column}\": \"{field}\" is not a finite number", column = crate::text::shown(.column), field = crate::text::shown(.field))]
    NotANumber {
        path: PathBuf,
        line: u64,
        column: String,
        field: String,
    },
}

/// Selected columns, in the order asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Header names of the selected columns (or their indices as text).
    pub names: Vec<String>,
    pub columns: Vec<Vec<f64>>,
}

fn parse_num(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Reads the columns `wanted` (names or 0-based indices) of a table file.
pub fn read_columns(path: &Path, wanted: &[&str]) -> Result<Table, TableError> {
    let text = std::fs::read(path).map_err(|source| TableError::Read {
        path: path.into(),
        source,
    })?;
    parse_columns(&text, path, wanted)
}

/// [`read_columns`] on bytes in memory (`path` names the data in errors).
pub fn parse_columns(bytes: &[u8], path: &Path, wanted: &[&str]) -> Result<Table, TableError> {
    if let Some(what) = crate::text::not_text(bytes) {
        return Err(TableError::NotText {
            path: path.into(),
            what,
        });
    }
    let text = String::from_utf8_lossy(bytes);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    // LabVIEW .lvm: two header blocks, each ending with ***End_of_Header***
    let skip = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with("***End_of_Header***"))
        .nth(1)
        .map(|(i, _)| i + 1)
        .unwrap_or(0);
    // Polytec ASCII: the header is the line before a line of `[ unit ]` fields
    let is_units = |l: &str| {
        let f: Vec<&str> = l
            .trim_end_matches('\r')
            .split('\t')
            .map(str::trim)
            .collect();
        f.len() >= 2
            && f.iter()
                .filter(|x| !x.is_empty())
                .all(|x| x.starts_with('[') && x.ends_with(']'))
            && f.iter().any(|x| !x.is_empty())
    };
    let units = if skip == 0 {
        text.lines().take(64).position(is_units).filter(|&u| u > 0)
    } else {
        None
    };
    let skip = units.map_or(skip, |u| u - 1);
    // the first line that is not skipped decides the separator
    let Some((first_no, first)) = text
        .lines()
        .enumerate()
        .skip(skip)
        .filter(|(i, _)| Some(*i) != units)
        .map(|(i, l)| (i as u64 + 1, l.trim_end_matches('\r')))
        .find(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
    else {
        return Err(TableError::Empty { path: path.into() });
    };
    let separator = if first.contains('\t') {
        Separator::Tab
    } else if first.contains(';') && !first.contains(',') {
        Separator::Semicolon
    } else {
        Separator::Comma
    };
    let opts = CsvOptions::default()
        .with_separator(separator)
        .with_encoding(Encoding::Utf8Lossy);
    let mut rows = CsvRows::new(bytes, opts);
    let unquote = |f: &str| f.trim_matches('"').trim().to_string();
    // the rows from the first one on (header or data), without the units line
    let mut next = || -> Option<(u64, Vec<String>)> {
        loop {
            // a byte slice cannot fail to read, and the encoding is lossy
            let (line, fields) = rows.next_row().ok()??;
            if line < first_no || Some(line as usize - 1) == units {
                continue;
            }
            return Some((line, fields.iter().map(|f| unquote(f)).collect()));
        }
    };
    let Some((_, head)) = next() else {
        return Err(TableError::Empty { path: path.into() });
    };
    let header = head.iter().any(|f| !f.is_empty() && parse_num(f).is_none());
    let mut pending = None;
    let names: Vec<String> = if header {
        head.clone()
    } else {
        pending = Some((first_no, head.clone()));
        (0..head.len()).map(|i| i.to_string()).collect()
    };
    let shown = || {
        names
            .iter()
            .enumerate()
            .filter(|(_, n)| !n.is_empty())
            .map(|(i, n)| {
                if header {
                    format!("{n} ({i})")
                } else {
                    n.clone()
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut idx = Vec::with_capacity(wanted.len());
    for w in wanted {
        let wt = w.trim();
        let by_name = names
            .iter()
            .position(|n| !n.is_empty() && n.eq_ignore_ascii_case(wt));
        let by_index = wt
            .parse::<usize>()
            .ok()
            .filter(|&i| i < names.len() && !(header && names[i].is_empty()));
        match by_name.or(by_index) {
            Some(i) => idx.push(i),
            None => {
                return Err(TableError::MissingColumn {
                    path: path.into(),
                    wanted: wt.to_string(),
                    found: shown(),
                })
            }
        }
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); wanted.len()];
    while let Some((line, fields)) = pending.take().or_else(&mut next) {
        for (c, &i) in idx.iter().enumerate() {
            let Some(f) = fields.get(i) else {
                return Err(TableError::ShortLine {
                    path: path.into(),
                    line,
                    column: names[i].clone(),
                    fields: fields.len(),
                });
            };
            match parse_num(f) {
                Some(v) => columns[c].push(v),
                None => {
                    return Err(TableError::NotANumber {
                        path: path.into(),
                        line,
                        column: names[i].clone(),
                        field: f.to_string(),
                    })
                }
            }
        }
    }
    if columns.first().map(|c| c.is_empty()).unwrap_or(true) {
        return Err(TableError::Empty { path: path.into() });
    }
    Ok(Table {
        names: idx.iter().map(|&i| names[i].clone()).collect(),
        columns,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn silverbox_header_with_trailing_comma() {
        let text = b"\"V1\",\"V2\",\n0.0057756,0.0093978,\n0.0066102,0.012971,\n\n";
        let t = parse_columns(text, Path::new("s.csv"), &["V1", "v2"]).unwrap();
        assert_eq!(t.names, ["V1", "V2"]);
        assert_eq!(t.columns[0], [0.0057756, 0.0066102]);
        assert_eq!(t.columns[1], [0.0093978, 0.012971]);
        let t = parse_columns(text, Path::new("s.csv"), &["1"]).unwrap();
        assert_eq!(t.columns[0], [0.0093978, 0.012971]);
        let e = parse_columns(text, Path::new("s.csv"), &["V3"]).unwrap_err();
        assert!(e.to_string().contains("no column \"V3\""), "{e}");
        assert!(e.to_string().contains("V1 (0), V2 (1)"), "{e}");
        // index of the empty trailing field is not a column
        assert!(parse_columns(text, Path::new("s.csv"), &["2"]).is_err());
    }

    #[test]
    fn lvm_two_header_blocks() {
        let text = b"LabVIEW Measurement\t\nX_Columns\tOne\n***End_of_Header***\t\n\nChannels\t2\n***End_of_Header***\t\t\nX_Value\tStrain_0\tComment\r\n0.000\t0.000211\t\r\n0.001\t2.1E-4\t\r\n";
        let t = parse_columns(text, Path::new("a.lvm"), &["X_Value", "Strain_0"]).unwrap();
        assert_eq!(t.columns, vec![vec![0.0, 0.001], vec![0.000211, 2.1e-4]]);
    }

    #[test]
    fn polytec_ascii_preamble_and_units() {
        let text = b"Source File Name:\tt3\nPoint Index:\t1\t[x = 0.03\ty = 0.02\tz = -1.23]\nComponent:\tRoot\nSignal:\tTime - Vib Velocity - Samples\n\nTime\tTime Signal\n[ s ]\t[ m/s ]\n0\t0.001976648\n0.0001\t-0.005674316\n";
        let t = parse_columns(text, Path::new("v.txt"), &["Time", "Time Signal"]).unwrap();
        assert_eq!(t.names, vec!["Time", "Time Signal"]);
        assert_eq!(t.columns[0], vec![0.0, 0.0001]);
        assert_eq!(t.columns[1], vec![0.001976648, -0.005674316]);
    }

    #[test]
    fn headerless_and_bad_fields() {
        let t = parse_columns(b"1,2\n3,4\n", Path::new("a.csv"), &["1", "0"]).unwrap();
        assert_eq!(t.columns, vec![vec![2.0, 4.0], vec![1.0, 3.0]]);
        let e = parse_columns(b"a,b\n1,2\n3,x\n", Path::new("a.csv"), &["b"]).unwrap_err();
        assert!(matches!(e, TableError::NotANumber { line: 3, .. }), "{e}");
        let e = parse_columns(b"a,b\n1,2\n3\n", Path::new("a.csv"), &["b"]).unwrap_err();
        assert!(matches!(e, TableError::ShortLine { line: 3, .. }), "{e}");
        let e = parse_columns(b"a,b\n1,nan\n", Path::new("a.csv"), &["b"]).unwrap_err();
        assert!(matches!(e, TableError::NotANumber { .. }), "{e}");
        assert!(matches!(
            parse_columns(b"a,b\n", Path::new("a.csv"), &["a"]),
            Err(TableError::Empty { .. })
        ));
    }
}
