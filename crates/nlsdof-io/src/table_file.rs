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

use crate::csv_table::{CsvOptions, CsvReadError, CsvRows, Encoding, Separator};
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
    #[error("{path}: the file has {bytes} bytes; a table is read up to {max} bytes (4 GiB: every selected value is kept in memory; split the record or keep only the columns needed)", max = MAX_FILE_BYTES)]
    TooLarge { path: PathBuf, bytes: u64 },
    /// A column found but unusable as asked (e.g. no time column), with
    /// what to do.
    #[error("{path}: {message}")]
    Column { path: PathBuf, message: String },
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

fn unquote(f: &str) -> &str {
    f.trim_matches('"').trim()
}

/// The selected fields `idx` of one row (`unq` applied to each) appended
/// to `columns`; errors name the line and the column.
fn push_row(
    columns: &mut [Vec<f64>],
    idx: &[usize],
    names: &[String],
    path: &Path,
    line: u64,
    fields: &[String],
    unq: fn(&str) -> &str,
    decimal_comma: bool,
) -> Result<(), TableError> {
    for (c, &i) in idx.iter().enumerate() {
        let Some(f) = fields.get(i).map(|f| unq(f)) else {
            return Err(TableError::ShortLine {
                path: path.into(),
                line,
                column: names[i].clone(),
                fields: fields.len(),
            });
        };
        match parse_num(f).or_else(|| decimal_comma.then(|| comma_num(f)).flatten()) {
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
    Ok(())
}

fn parse_num(s: &str) -> Option<f64> {
    s.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// A number written with a decimal comma (`-2,25`, `1,5E-3`): one comma,
/// no point. Only tried when the fields are not comma-separated.
fn comma_num(s: &str) -> Option<f64> {
    let s = s.trim();
    (s.matches(',').count() == 1 && !s.contains('.'))
        .then(|| parse_num(&s.replace(',', ".")))
        .flatten()
}

/// Reads the columns `wanted` (names or 0-based indices) of a table file.
///
/// A regular file is streamed, never held whole (issue 30, class 10: a
/// 1e7-row record of 240 MB was read into memory before 160 MB of numbers
/// were parsed out of it): one pass over its lines finds the LabVIEW header
/// blocks and counts the lines (the columns are reserved once, no doubling),
/// a short pass finds the header line, and a last pass parses the rows.
/// Anything that cannot be read twice (a pipe, a device) is read into
/// memory first, as before.
pub fn read_columns(path: &Path, wanted: &[&str]) -> Result<Table, TableError> {
    read_picked(path, &|names: &[String], header: bool| {
        pick_named(path, names, header, wanted)
    })
}

/// [`read_columns`] on bytes in memory (`path` names the data in errors).
pub fn parse_columns(bytes: &[u8], path: &Path, wanted: &[&str]) -> Result<Table, TableError> {
    parse_source(&|| Ok(bytes), path, &|names: &[String], header: bool| {
        pick_named(path, names, header, wanted)
    })
}

/// Chooses the columns to read from the header's `names` (indices as text
/// when the table has no header line, `header` false).
pub type Picker<'a> = dyn Fn(&[String], bool) -> Result<Vec<usize>, TableError> + 'a;

/// [`read_columns`] with the columns chosen by `pick` once the header is
/// known (e.g. a time column among several candidate names).
pub fn read_picked(path: &Path, pick: &Picker<'_>) -> Result<Table, TableError> {
    let read_err = |source| TableError::Read {
        path: path.into(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(read_err)?;
    if meta.is_file() {
        if meta.len() > MAX_FILE_BYTES {
            return Err(TableError::TooLarge {
                path: path.into(),
                bytes: meta.len(),
            });
        }
        parse_source(&|| std::fs::File::open(path), path, pick)
    } else {
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(
            &mut std::io::Read::take(
                std::fs::File::open(path).map_err(read_err)?,
                MAX_FILE_BYTES + 1,
            ),
            &mut bytes,
        )
        .map_err(read_err)?;
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(TableError::TooLarge {
                path: path.into(),
                bytes: bytes.len() as u64,
            });
        }
        parse_source(&|| Ok(&bytes[..]), path, pick)
    }
}

/// The header names of the table as a message lists them: `name (index)`.
pub fn listing(names: &[String], header: bool) -> String {
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
}

/// Index of the column `wanted`: a header name (case-insensitive) or a
/// 0-based index.
pub fn find_column(names: &[String], header: bool, wanted: &str) -> Option<usize> {
    let wt = wanted.trim();
    let by_name = names
        .iter()
        .position(|n| !n.is_empty() && n.eq_ignore_ascii_case(wt));
    let by_index = wt
        .parse::<usize>()
        .ok()
        .filter(|&i| i < names.len() && !(header && names[i].is_empty()));
    by_name.or(by_index)
}

fn pick_named(
    path: &Path,
    names: &[String],
    header: bool,
    wanted: &[&str],
) -> Result<Vec<usize>, TableError> {
    wanted
        .iter()
        .map(|w| {
            find_column(names, header, w).ok_or_else(|| TableError::MissingColumn {
                path: path.into(),
                wanted: w.trim().to_string(),
                found: listing(names, header),
            })
        })
        .collect()
}

/// Largest table file read: 4 GiB. The file is streamed (a line at a time),
/// but every row of the selected columns is kept as 8-byte numbers and
/// a larger text file means more than ~10^8 rows, beyond what the analyses
/// handle in reasonable time and memory.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

const END_OF_HEADER: &str = "***End_of_Header***";

/// Calls `f(index, line)` for the lines of `r` as `str::lines` splits the
/// lossily decoded text (a leading byte-order mark dropped), until `f`
/// returns `false`. `quick(bytes)` sees every line first and may say that
/// `f` has nothing to do with it, without decoding it (the full pass over
/// a large file).
fn for_each_line<R: std::io::Read>(
    r: R,
    mut quick: impl FnMut(&[u8]) -> bool,
    mut f: impl FnMut(usize, &str) -> bool,
) -> std::io::Result<()> {
    use std::io::BufRead;
    let mut r = std::io::BufReader::with_capacity(1 << 16, r);
    let mut buf = Vec::new();
    let mut lines = 0;
    loop {
        buf.clear();
        if r.read_until(b'\n', &mut buf)? == 0 {
            break;
        }
        let i = lines;
        lines += 1;
        let mut line = &buf[..];
        if let Some(l) = line.strip_suffix(b"\n") {
            line = l.strip_suffix(b"\r").unwrap_or(l);
        }
        if !quick(line) {
            continue;
        }
        let text = String::from_utf8_lossy(line);
        let text = if i == 0 {
            text.strip_prefix('\u{feff}').unwrap_or(&text)
        } else {
            &text
        };
        if !f(i, text) {
            break;
        }
    }
    Ok(())
}

/// The table from a source that can be opened again from its start: its
/// first 4 KiB, its lines and its rows are read in separate passes, so at
/// most a line and the parsed columns are in memory.
fn parse_source<R: std::io::Read>(
    open: &dyn Fn() -> std::io::Result<R>,
    path: &Path,
    pick: &Picker<'_>,
) -> Result<Table, TableError> {
    let read_err = |source| TableError::Read {
        path: path.into(),
        source,
    };
    let mut head = Vec::with_capacity(4096);
    std::io::Read::read_to_end(
        &mut std::io::Read::take(open().map_err(read_err)?, 4096),
        &mut head,
    )
    .map_err(read_err)?;
    if let Some(what) = crate::text::not_text(&head) {
        return Err(TableError::NotText {
            path: path.into(),
            what,
        });
    }
    drop(head);
    // LabVIEW .lvm: two header blocks, each ending with ***End_of_Header***
    // (this pass also counts the lines that are not blank or comments: at
    // most that many rows, the columns' capacity)
    let mut ends = 0;
    let mut skip = 0;
    let mut rows_max = 0usize;
    for_each_line(
        open().map_err(read_err)?,
        |l| {
            match l.iter().find(|b| !b.is_ascii_whitespace()) {
                Some(b'#') | None => {}
                Some(_) => rows_max += 1,
            }
            l.contains(&b'*')
        },
        |i, l| {
            if ends < 2 && l.trim_start().starts_with(END_OF_HEADER) {
                ends += 1;
                if ends == 2 {
                    skip = i + 1;
                }
            }
            true
        },
    )
    .map_err(read_err)?;
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
    let mut units = None;
    if skip == 0 {
        for_each_line(
            open().map_err(read_err)?,
            |_| true,
            |i, l| {
                if i < 64 && is_units(l) {
                    units = Some(i);
                }
                i < 63 && units.is_none()
            },
        )
        .map_err(read_err)?;
        units = units.filter(|&u| u > 0);
    }
    let skip = units.map_or(skip, |u| u - 1);
    // the first line that is not skipped decides the separator
    let mut first = None;
    for_each_line(
        open().map_err(read_err)?,
        |_| true,
        |i, l| {
            let l = l.trim_end_matches('\r');
            if i >= skip
                && Some(i) != units
                && !l.trim().is_empty()
                && !l.trim_start().starts_with('#')
            {
                first = Some((
                    i as u64 + 1,
                    l.contains('\t'),
                    l.contains(';'),
                    l.contains(','),
                ));
            }
            first.is_none()
        },
    )
    .map_err(read_err)?;
    let Some((first_no, tab, semicolon, comma)) = first else {
        return Err(TableError::Empty { path: path.into() });
    };
    let separator = if tab {
        Separator::Tab
    } else if semicolon && !comma {
        Separator::Semicolon
    } else {
        Separator::Comma
    };
    let opts = CsvOptions::default()
        .with_separator(separator)
        .with_encoding(Encoding::Utf8Lossy);
    let mut rows = CsvRows::new(open().map_err(read_err)?, opts);
    // the encoding is lossy: only the source can fail
    let row_err = |e: CsvReadError| match e {
        CsvReadError::Io(source) => read_err(source),
        e => read_err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            e.to_string(),
        )),
    };
    // the rows from the first one on (header or data), without the units line
    let data = |line: u64| line >= first_no && Some(line as usize - 1) != units;
    let mut head = None;
    while let Some((line, fields)) = rows.next_row().map_err(row_err)? {
        if data(line) {
            head = Some((
                line,
                fields
                    .iter()
                    .map(|f| unquote(f).to_string())
                    .collect::<Vec<_>>(),
            ));
            break;
        }
    }
    let Some((head_no, head)) = head else {
        return Err(TableError::Empty { path: path.into() });
    };
    let decimal_comma = separator != Separator::Comma;
    let header = head.iter().any(|f| {
        !f.is_empty() && parse_num(f).is_none() && !(decimal_comma && comma_num(f).is_some())
    });
    let names: Vec<String> = if header {
        head.clone()
    } else {
        (0..head.len()).map(|i| i.to_string()).collect()
    };
    let idx = pick(&names, header)?;
    // reserved once: a column never doubles its capacity (and copies
    // itself) while it grows
    let mut columns: Vec<Vec<f64>> = (0..idx.len())
        .map(|_| Vec::with_capacity(rows_max))
        .collect();
    if !header {
        push_row(
            &mut columns,
            &idx,
            &names,
            path,
            head_no,
            &head,
            |f| f,
            decimal_comma,
        )?;
    }
    // the fields are parsed where they are, not copied (1e7 rows)
    while let Some((line, fields)) = rows.next_row().map_err(row_err)? {
        if data(line) {
            push_row(
                &mut columns,
                &idx,
                &names,
                path,
                line,
                fields,
                unquote,
                decimal_comma,
            )?;
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
