//! The one reader layer of measured data: what a file is, decided from its
//! content (magic bytes and first lines; the extension only breaks ties),
//! and the time history or the columns it holds, read the same way by
//! every verb.
//!
//! | format | recognised by | a column is | time |
//! |---|---|---|---|
//! | CSV / delimited text | anything else that is text | header name or 0-based index | `t`, `time`, `t_s`, or `--fs` |
//! | LabVIEW `.lvm` | first line `LabVIEW Measurement` | header name after the 2nd `***End_of_Header***` | `X_Value` |
//! | Polytec ASCII export | a line `Source File Name` / a `[ unit ]` line | header name (`Time Signal`) | `Time` |
//! | MATLAB MAT v5 | `MATLAB 5.0 MAT-file` header | variable name | a vector `t`/`time`, a scalar `fs`, or `--fs` |
//! | Universal file, dataset 58/58b | `-1` line then `58`/`58b` (or `.uff`/`.unv`) | dataset index from 0 or ID-line-1 text | the abscissa |
//!
//! A file that is not text and none of these (gzip, zip, UTF-16, binary)
//! is refused with what it is and what to do; its bytes are never quoted.
//!
//! Size limits (each refused with the reason): text tables
//! [`crate::table_file::MAX_FILE_BYTES`] (streamed, only the selected
//! columns kept), MAT files [`crate::mat5::MAX_INFLATED_BYTES`] (held
//! whole while parsed), universal files [`crate::uff58::MAX_FILE_BYTES`]
//! (held whole while parsed).

pub use crate::format::{detect, detect_file, not_text_format, Format, HEAD_BYTES};
use crate::signal_file::{Signal, SignalFileError, SignalGrid, UNIFORM_TOLERANCE};
use crate::table_file::{find_column, listing, Table, TableError};
use nlsdof::excitation::SampledInput;
use std::path::Path;

/// Whether `path` is a universal file: named `.uff`/`.unv`, or starting
/// like one (whatever its name).
pub fn is_uff_file(path: &Path) -> bool {
    crate::uff_convert::is_uff(path) || detect_file(path).is_ok_and(|f| f == Format::Uff)
}

/// Names of a time column, tried in this order when the caller names none:
/// LabVIEW's `X_Value`, the CSV `t`, `time`, `t_s`, Polytec's `Time`.
pub const TIME_COLUMNS: [&str; 4] = ["X_Value", "t", "time", "t_s"];

/// Names of an input-acceleration column, used when no column is named.
pub const ACCEL_COLUMNS: [&str; 5] = ["accel", "acceleration", "gamma", "u", "accel_m_s2"];

fn time_index(names: &[String], header: bool, skip: &[usize]) -> Option<usize> {
    if !header {
        return None;
    }
    TIME_COLUMNS
        .iter()
        .find_map(|t| find_column(names, true, t))
        .filter(|i| !skip.contains(i))
}

/// Reads the columns `wanted` (names or 0-based indices; MAT variable
/// names; universal-file dataset indices or ID-line-1 text) of any format,
/// and after them the time column if `time` is true and the file has one
/// (the last column of the table is then the time, named as in the file;
/// `t` for MAT and universal files). See the module documentation.
pub fn read_columns(path: &Path, wanted: &[&str], time: bool) -> Result<Table, TableError> {
    let format = detect_file(path).map_err(|source| TableError::Read {
        path: path.into(),
        source,
    })?;
    match format {
        Format::Mat => mat_columns(path, wanted, time),
        Format::Uff => uff_columns(path, wanted, time),
        Format::Other(what) => Err(TableError::NotText {
            path: path.into(),
            what: format!("this is {what}"),
        }),
        _ => crate::table_file::read_picked(path, &|names: &[String], header: bool| {
            let mut idx = Vec::with_capacity(wanted.len() + 1);
            for w in wanted {
                idx.push(
                    find_column(names, header, w)
                        .ok_or_else(|| missing_column(path, w, names, header))?,
                );
            }
            if time {
                if let Some(t) = time_index(names, header, &idx) {
                    idx.push(t);
                }
            }
            Ok(idx)
        }),
    }
}

/// A missing column, with the separator or decimal-comma mistake that
/// explains it named first when the header suggests one.
fn missing_column(path: &Path, wanted: &str, names: &[String], header: bool) -> TableError {
    let found = listing(names, header);
    if let Some(hint) = separator_hint(names) {
        return TableError::Column {
            path: path.into(),
            message: format!(
                "no column \"{}\": {hint} (columns read: {})",
                crate::text::shown(wanted.trim()),
                crate::text::shown(&found)
            ),
        };
    }
    TableError::MissingColumn {
        path: path.into(),
        wanted: wanted.trim().to_string(),
        found,
    }
}

/// When a header read with the separator chosen holds fields that another
/// separator would split (a one-field header with `;` or tabs in it),
/// what happened and how to fix it.
pub fn separator_hint(names: &[String]) -> Option<String> {
    let joined: Vec<&String> = names.iter().filter(|n| !n.is_empty()).collect();
    if joined.len() != 1 {
        return None;
    }
    let h = joined[0];
    for (sep, what) in [(';', "semicolons"), ('\t', "tabs"), ('|', "bars")] {
        if h.split(sep).filter(|f| !f.trim().is_empty()).count() >= 2 {
            return Some(format!(
                "the header is one field \"{}\" with {what} in it: the file looks separated by {what} (a decimal-comma export?); save it comma-separated with decimal points",
                crate::text::shown(h)
            ));
        }
    }
    None
}

fn mat_columns(path: &Path, wanted: &[&str], time: bool) -> Result<Table, TableError> {
    let content = |message: String| TableError::Column {
        path: path.into(),
        message,
    };
    let arrays = crate::mat5::read(path)
        .map_err(|source| TableError::Read {
            path: path.into(),
            source,
        })?
        .map_err(|e| content(format!("this is a MATLAB MAT-file: {e}")))?;
    let vars = || {
        arrays
            .iter()
            .map(|a| format!("{}{:?}", a.name, a.dims))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let vector = |a: &crate::mat5::MatArray| -> Result<Vec<f64>, TableError> {
        if a.complex {
            return Err(content(format!(
                "MAT variable {:?} is complex; a real vector is needed",
                a.name
            )));
        }
        if a.dims.iter().filter(|&&d| d != 1).count() > 1 {
            return Err(content(format!(
                "MAT variable {:?} has size {:?}; a column is a vector",
                a.name, a.dims
            )));
        }
        Ok(a.real.clone())
    };
    let mut names = Vec::new();
    let mut columns = Vec::new();
    for w in wanted {
        let a = arrays.iter().find(|a| a.name == w.trim()).ok_or_else(|| {
            content(format!(
                "this is a MAT-file with no numeric variable {:?}: give a variable name with --column (variables: {})",
                crate::text::shown(w.trim()),
                vars()
            ))
        })?;
        names.push(a.name.clone());
        columns.push(vector(a)?);
    }
    if time {
        if let Some(a) = ["t", "time"]
            .iter()
            .filter_map(|n| arrays.iter().find(|a| a.name == *n))
            .find(|a| !names.contains(&a.name))
        {
            names.push(a.name.clone());
            columns.push(vector(a)?);
        }
    }
    equal_lengths(path, &names, &columns)?;
    Ok(Table { names, columns })
}

fn uff_columns(path: &Path, wanted: &[&str], time: bool) -> Result<Table, TableError> {
    use crate::uff58::Uff58Data;
    let content = |message: String| TableError::Column {
        path: path.into(),
        message,
    };
    let all = crate::uff58::read(path).map_err(|e| content(e.to_string()))?;
    let mut names = Vec::new();
    let mut columns = Vec::new();
    let mut abscissa = None;
    for w in wanted {
        let f = crate::uff_convert::select(&all, Some(w), 0, "--column", "", |_| false)
            .map_err(|m| content(format!("this is a universal file: {m}")))?;
        let Uff58Data::Real(values) = &f.dataset.data else {
            return Err(content(format!(
                "dataset {} is complex ({}): a column is a real function",
                f.info.index,
                crate::uff58::function_type_name(f.dataset.header.function_type)
            )));
        };
        names.push(format!("{}", f.info.index));
        columns.push(values.clone());
        abscissa.get_or_insert_with(|| f.dataset.abscissa_values());
    }
    if time {
        if let Some(t) = abscissa {
            names.push("t".into());
            columns.push(t);
        }
    }
    equal_lengths(path, &names, &columns)?;
    Ok(Table { names, columns })
}

fn equal_lengths(path: &Path, names: &[String], columns: &[Vec<f64>]) -> Result<(), TableError> {
    if columns.first().is_none_or(|c| c.is_empty()) {
        return Err(TableError::Empty { path: path.into() });
    }
    for (n, c) in names.iter().zip(columns) {
        if c.len() != columns[0].len() {
            return Err(TableError::Column {
                path: path.into(),
                message: format!(
                    "{:?} has {} values but {:?} has {}: columns must have equal lengths",
                    n,
                    c.len(),
                    names[0],
                    columns[0].len()
                ),
            });
        }
        if let Some((k, v)) = c.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(TableError::Column {
                path: path.into(),
                message: format!("{n:?}: value {k} is {v}, not a finite number"),
            });
        }
    }
    Ok(())
}

/// One time history of any format (see the module documentation): the
/// column `column` (CSV/LVM/Polytec header name or index, MAT variable,
/// universal-file dataset), or without one the file's only signal or its
/// acceleration column (`accel`, `gamma`, `u`, ...). The time column is
/// used where the file has one (then `fs` is refused); without one `fs`
/// (Hz) gives the sampling from t = 0.
pub fn read_signal(
    path: &Path,
    column: Option<&str>,
    fs: Option<f64>,
) -> Result<Signal, SignalFileError> {
    let format = detect_file(path).map_err(|source| SignalFileError::Read {
        path: path.into(),
        source,
    })?;
    match format {
        Format::Mat => crate::signal_file::read_mat(path, fs, column),
        Format::Uff => crate::signal_file::read_uff(path, fs, column),
        Format::Other(what) => Err(SignalFileError::Column {
            path: path.into(),
            message: format!("this is {what}"),
        }),
        Format::Csv if column.is_none() => crate::signal_file::read_csv(path, fs),
        Format::Csv | Format::Lvm | Format::Polytec => text_signal(path, column, fs, &format),
    }
}

/// A signal from a text table with a header (LVM, Polytec, CSV with a
/// named column).
fn text_signal(
    path: &Path,
    column: Option<&str>,
    fs: Option<f64>,
    format: &Format,
) -> Result<Signal, SignalFileError> {
    if let Some(f) = fs {
        if !(f.is_finite() && f > 0.0) {
            return Err(SignalFileError::Signal {
                path: path.into(),
                source: nlsdof::simulation::SimulationError::NonPositiveFs { fs: f },
            });
        }
    }
    let table_err = |e: TableError| SignalFileError::Column {
        path: path.into(),
        message: strip_path(path, &e.to_string()),
    };
    let polytec_time = |names: &[String]| {
        (*format == Format::Polytec)
            .then(|| find_column(names, true, "Time"))
            .flatten()
    };
    let table = crate::table_file::read_picked(path, &|names: &[String], header: bool| {
        let err = |message: String| TableError::Column {
            path: path.into(),
            message,
        };
        let t = time_index(names, header, &[]).or_else(|| polytec_time(names));
        let c = match column {
            Some(c) => find_column(names, header, c)
                .ok_or_else(|| missing_column(path, c, names, header))?,
            None => {
                let named = ACCEL_COLUMNS
                    .iter()
                    .find_map(|a| find_column(names, header, a));
                let others: Vec<usize> = (0..names.len())
                    .filter(|&i| Some(i) != t && !names[i].is_empty())
                    .collect();
                match (named, others.as_slice()) {
                    (Some(i), _) => i,
                    (None, [i]) => *i,
                    _ => {
                        return Err(err(format!(
                            "{} with several columns: choose one with --column NAME (columns: {})",
                            format.name(),
                            listing(names, header)
                        )))
                    }
                }
            }
        };
        if Some(c) == t {
            return Err(err(format!(
                "column {:?} is the time column; choose a signal column (columns: {})",
                names[c],
                listing(names, header)
            )));
        }
        match (t, fs) {
            (Some(t), Some(f)) => Err(err(format!(
                "the file has a time column ({}); --fs {f} would contradict it (drop --fs)",
                names[t]
            ))),
            (None, None) => Err(err(format!(
                "no time column ({}) in the header: give the sampling frequency with --fs HZ",
                TIME_COLUMNS.join(", ")
            ))),
            (Some(t), None) => Ok(vec![c, t]),
            (None, Some(_)) => Ok(vec![c]),
        }
    })
    .map_err(table_err)?;
    let mut cols = table.columns.into_iter();
    let values = cols.next().unwrap_or_default();
    let grid = match (cols.next(), fs) {
        (Some(times), _) => {
            if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
                return Err(SignalFileError::Column {
                    path: path.into(),
                    message: format!(
                        "time column {:?}: sample {}: time {} does not increase (previous {})",
                        table.names[1],
                        k + 1,
                        times[k + 1],
                        times[k]
                    ),
                });
            }
            match SampledInput::detect_uniform(&times, UNIFORM_TOLERANCE) {
                Some((t0, fs)) => SignalGrid::Uniform { t0, fs },
                None if times.len() < 2 => {
                    return Err(SignalFileError::Column {
                        path: path.into(),
                        message: "one sample cannot define a sampling frequency".into(),
                    })
                }
                None => SignalGrid::Times(times),
            }
        }
        (None, Some(fs)) => SignalGrid::Uniform { t0: 0.0, fs },
        (None, None) => return Err(SignalFileError::MissingFs { path: path.into() }),
    };
    Ok(Signal { values, grid })
}

/// `message` without a leading `PATH: ` (the caller adds the path once).
fn strip_path(path: &Path, message: &str) -> String {
    let p = format!("{}: ", path.display());
    message.strip_prefix(&p).unwrap_or(message).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_are_told_by_content() {
        let p = Path::new("x.dat");
        assert_eq!(detect(b"MATLAB 5.0 MAT-file, Platform", p), Format::Mat);
        assert_eq!(detect(b"    -1\n    58\nid1\n", p), Format::Uff);
        assert_eq!(detect(b"    -1\n    58b     2   1\n", p), Format::Uff);
        assert_eq!(detect(b"LabVIEW Measurement\t\r\nWriter", p), Format::Lvm);
        assert_eq!(
            detect("\u{feff}Source File Name:\tt3\n".as_bytes(), p),
            Format::Polytec
        );
        assert_eq!(detect(b"t,x\n0,1\n", p), Format::Csv);
        assert_eq!(detect(b"-1,2\n3,4\n", p), Format::Csv);
        assert!(matches!(detect(&[0x1f, 0x8b, 8, 0], p), Format::Other(w) if w.contains("gzip")));
        assert_eq!(
            detect(&[1, 0, 0, 0, 9, 9], Path::new("v4.mat")),
            Format::Mat
        );
        assert_eq!(detect(b"", p), Format::Csv);
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    const LVM: &[u8] = b"LabVIEW Measurement\t\r\nWriter_Version\t2\r\nX_Columns\tOne\r\n***End_of_Header***\t\r\n\t\r\nChannels\t2\t\t\r\n***End_of_Header***\t\t\t\r\nX_Value\tVoltage\tStrain_0\tComment\r\n0.000000\t1.211061\t0.000211\t\r\n0.001000\t1.208510\t0.000219\t\r\n0.002000\t1.211061\t2.1E-4\t\r\n";

    #[test]
    fn lvm_signal_uses_x_value_as_time() {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "a.lvm", LVM);
        let s = read_signal(&p, Some("Strain_0"), None).unwrap();
        // values and sampling as written in the fixture text
        assert_eq!(s.values, vec![0.000211, 0.000219, 2.1e-4]);
        match s.grid {
            SignalGrid::Uniform { t0, fs } => {
                assert_eq!(t0, 0.0);
                assert!((fs - 1000.0).abs() < 1e-9, "{fs}");
            }
            g => panic!("{g:?}"),
        }
        let e = read_signal(&p, None, None).unwrap_err().to_string();
        assert!(
            e.contains("several columns") && e.contains("Strain_0 (2)"),
            "{e}"
        );
        let e = read_signal(&p, Some("Strain_0"), Some(10.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("X_Value") && e.contains("drop --fs"), "{e}");
        let t = read_columns(&p, &["Voltage"], true).unwrap();
        assert_eq!(t.names, ["Voltage", "X_Value"]);
        assert_eq!(t.columns[1], vec![0.0, 0.001, 0.002]);
    }

    #[test]
    fn polytec_signal_uses_time() {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "v.txt", b"Source File Name:\tt3\nPoint Index:\t1\nSignal:\tTime - Vib Velocity - Samples\n\nTime\tTime Signal\n[ s ]\t[ m/s ]\n0\t0.001976648\n0.0001\t-0.005674316\n0.0002\t1e-3\n");
        let s = read_signal(&p, None, None).unwrap();
        assert_eq!(s.values, vec![0.001976648, -0.005674316, 1e-3]);
        assert!(matches!(s.grid, SignalGrid::Uniform { fs, .. } if (fs - 1e4).abs() < 1e-6));
    }

    #[test]
    fn mat_columns_by_variable_name() {
        let d = tempfile::tempdir().unwrap();
        let bytes = crate::signal_file::tests::mat_bytes(&[
            ("V1", 3, 1, &[1.0, 2.0, 3.0]),
            ("V2", 3, 1, &[4.0, 5.0, 6.0]),
        ]);
        let p = write(d.path(), "s.mat", &bytes);
        let t = read_columns(&p, &["V2"], true).unwrap();
        assert_eq!(t.columns, vec![vec![4.0, 5.0, 6.0]]);
        let e = read_columns(&p, &["V3"], false).unwrap_err().to_string();
        assert!(
            e.contains("this is a MAT-file") && e.contains("--column"),
            "{e}"
        );
        // no binary in the message
        assert!(!e.contains('\0'));
        // the same file under a .csv name is still read as MAT
        let p = write(d.path(), "s.csv", &bytes);
        assert_eq!(
            read_columns(&p, &["V1"], false).unwrap().columns[0],
            [1.0, 2.0, 3.0]
        );
    }

    #[test]
    fn semicolon_header_is_named() {
        let d = tempfile::tempdir().unwrap();
        let h = separator_hint(&["level;gamma;f_hz;amplitude".to_string()]).unwrap();
        assert!(h.contains("semicolons"), "{h}");
        assert!(separator_hint(&["t".into(), "x".into()]).is_none());
        assert!(separator_hint(&["time history".into()]).is_none());
        // a semicolon table with decimal commas is read
        let p = write(d.path(), "a.csv", b"t;x\n0;1,5\n0,5;-2,25\n");
        let t = read_columns(&p, &["x"], true).unwrap();
        assert_eq!(t.columns, vec![vec![1.5, -2.25], vec![0.0, 0.5]]);
    }
}
