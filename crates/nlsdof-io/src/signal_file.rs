//! Recorded input signals (input acceleration γ(t), m/s²) and streamed
//! numeric CSV output.
//!
//! ## Reading
//!
//! * **CSV** — either two columns `t,accel` (time in s, strictly
//!   increasing) or one column `accel` plus a sampling frequency (`fs`, Hz,
//!   given by the caller). A header line is optional (detected when its
//!   fields are not numbers); with a header and more than two columns the
//!   columns named `t`/`time` and `accel`/`acceleration`/`gamma`/`u` are used
//!   (so the output of `nlsdof simulate` can be read back). Lines starting
//!   with `#` are comments. A time column that is uniform to within 1e-3 of
//!   a step is stored as `(t0, fs)`.
//! * **MATLAB MAT v5** (`.mat`, read by [`crate::mat5`]): a numeric array,
//!   either an `n×2` (or `2×n`) matrix `[t accel]` or a vector plus `fs`
//!   (from the caller, or a scalar variable `fs` in the file, or a vector
//!   `t`/`time` of the same length). With several arrays in the file the
//!   variable is chosen by name.
//!
//! Every sample is checked while reading: a non-finite value, a
//! non-increasing time, a wrong column count or an unparsable field is an
//! error naming the file and line ([`SignalFileError`]); nothing is
//! returned half-read.

use crate::atomic::AtomicFile;
use crate::csv_table::{column, CsvOptions, CsvReadError, CsvRows};
use crate::error::IoError;
use nlsdof::excitation::SampledInput;
use nlsdof::simulation::SimulationError;
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors reading a signal file. Each names the file and, where there is
/// one, the line and the offending value.
#[derive(Debug, Error)]
pub enum SignalFileError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no samples (empty file)")]
    Empty { path: PathBuf },
    #[error("{path}: line {line}: expected {expected}, found {found} column(s)")]
    WrongColumns {
        path: PathBuf,
        line: u64,
        expected: String,
        found: usize,
    },
    #[error("{path}: line {line}: column {column}: {field:?} is not a number")]
    NotANumber {
        path: PathBuf,
        line: u64,
        column: usize,
        field: String,
    },
    #[error("{path}: line {line}: {source}")]
    Invalid {
        path: PathBuf,
        line: u64,
        source: SimulationError,
    },
    #[error("{path}: {source}")]
    Signal {
        path: PathBuf,
        source: SimulationError,
    },
    #[error("{path}: a one-column signal needs the sampling frequency (--fs HZ)")]
    MissingFs { path: PathBuf },
    #[error("{path}: the file has a time column; --fs {fs} would contradict it (drop --fs)")]
    FsWithTimeColumn { path: PathBuf, fs: f64 },
    #[error("{path}: header names no {wanted} column (columns: {found})")]
    MissingColumn {
        path: PathBuf,
        wanted: &'static str,
        found: String,
    },
    #[error("{path}: {source}")]
    Mat {
        path: PathBuf,
        source: crate::mat5::MatError,
    },
    #[error("{path}: {message}")]
    MatContent { path: PathBuf, message: String },
    /// A universal file that holds no usable time history ([`read_uff`]).
    #[error("{path}: {message}")]
    Uff { path: PathBuf, message: String },
    /// A named CSV column that cannot be read ([`read_csv_column`]).
    #[error("{path}: {message}")]
    Column { path: PathBuf, message: String },
}

/// Sampling of a signal read from a file.
#[derive(Debug, Clone, PartialEq)]
pub enum SignalGrid {
    Uniform { t0: f64, fs: f64 },
    Times(Vec<f64>),
}

/// A validated recorded signal.
#[derive(Debug, Clone, PartialEq)]
pub struct Signal {
    pub values: Vec<f64>,
    pub grid: SignalGrid,
}

impl Signal {
    /// The signal as the core library's input (gain 1).
    pub fn as_input(&self) -> Result<SampledInput<'_>, SimulationError> {
        match &self.grid {
            SignalGrid::Uniform { t0, fs } => SampledInput::uniform(&self.values, *fs, *t0),
            SignalGrid::Times(t) => SampledInput::with_times(t, &self.values),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Bytes held by the sample arrays.
    pub fn bytes(&self) -> usize {
        8 * (self.values.len()
            + if let SignalGrid::Times(t) = &self.grid {
                t.len()
            } else {
                0
            })
    }
}

/// Relative tolerance (fraction of one step) for treating a time column as
/// uniformly sampled.
pub const UNIFORM_TOLERANCE: f64 = 1e-3;

/// Reads the column named `name` (case-insensitive) of a CSV with a header
/// line, and its time column (`t`, `time` or `t_s`) if it has one; without
/// a time column `fs` (Hz, checked by the caller) gives the sampling,
/// starting at t = 0. Every row has as many fields as the header; values
/// are finite, times strictly increasing. A uniform time column (to within
/// [`UNIFORM_TOLERANCE`] of a step) is stored as `(t0, fs)`.
pub fn read_csv_column(
    path: &Path,
    name: &str,
    fs: Option<f64>,
) -> Result<Signal, SignalFileError> {
    let err = |message: String| SignalFileError::Column {
        path: path.into(),
        message,
    };
    let file = std::fs::File::open(path).map_err(|source| SignalFileError::Read {
        path: path.into(),
        source,
    })?;
    let mut rows = CsvRows::new(file, CsvOptions::default());
    let read_err = |e: CsvReadError| match e {
        CsvReadError::Io(source) => SignalFileError::Read {
            path: path.into(),
            source,
        },
        e => SignalFileError::Read {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
        },
    };
    let Some((_, header)) = rows.next_row().map_err(read_err)? else {
        return Err(SignalFileError::Empty { path: path.into() });
    };
    let names: Vec<String> = header.iter().map(|f| f.to_ascii_lowercase()).collect();
    if names.iter().all(|n| n.parse::<f64>().is_ok()) {
        return Err(err(format!(
            "--column {name} needs a header line naming the columns (the first line is numbers)"
        )));
    }
    let col = column(&names, name).ok_or_else(|| {
        err(format!(
            "no column named {name:?} (columns: {})",
            names.join(",")
        ))
    })?;
    let tcol = names
        .iter()
        .position(|n| ["t", "time", "t_s"].contains(&n.as_str()))
        .filter(|&i| i != col);
    match (tcol, fs) {
        (Some(_), Some(fs)) => {
            return Err(SignalFileError::FsWithTimeColumn {
                path: path.into(),
                fs,
            })
        }
        (None, None) => {
            return Err(err(
                "no time column (t) in the header: give the sampling frequency with --fs HZ".into(),
            ))
        }
        _ => {}
    }
    let mut values = Vec::new();
    let mut times = Vec::new();
    let parse = |line: u64, field: &str, what: &str| -> Result<f64, SignalFileError> {
        let v: f64 = field
            .parse()
            .map_err(|_| err(format!("line {line}: {what} {field:?} is not a number")))?;
        if !v.is_finite() {
            return Err(err(format!("line {line}: {what} {v} is not finite")));
        }
        Ok(v)
    };
    while let Some((line, fields)) = rows.next_row().map_err(read_err)? {
        if fields.len() != names.len() {
            return Err(err(format!(
                "line {line}: expected {} columns like the header, found {}",
                names.len(),
                fields.len()
            )));
        }
        values.push(parse(line, &fields[col], name)?);
        if let Some(tc) = tcol {
            let t = parse(line, &fields[tc], "time")?;
            if let Some(&prev) = times.last() {
                if t <= prev {
                    return Err(err(format!(
                        "line {line}: time {t} does not increase (previous {prev})"
                    )));
                }
            }
            times.push(t);
        }
    }
    if values.is_empty() {
        return Err(err("no samples after the header".into()));
    }
    let grid = match fs {
        Some(fs) => SignalGrid::Uniform { t0: 0.0, fs },
        None => match SampledInput::detect_uniform(&times, UNIFORM_TOLERANCE) {
            Some((t0, fs)) => SignalGrid::Uniform { t0, fs },
            None if times.len() < 2 => {
                return Err(err("one sample cannot define a sampling frequency".into()))
            }
            None => SignalGrid::Times(times),
        },
    };
    Ok(Signal { values, grid })
}

fn check_fs(path: &Path, fs: Option<f64>) -> Result<(), SignalFileError> {
    if let Some(fs) = fs {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(SignalFileError::Signal {
                path: path.into(),
                source: SimulationError::NonPositiveFs { fs },
            });
        }
    }
    Ok(())
}

/// Reads a signal of any format, decided from the file's content
/// ([`crate::input::read_signal`]: CSV, LabVIEW `.lvm`, Polytec ASCII, MAT
/// v5, universal file). `fs` is the sampling frequency for a signal
/// without a time column; `var` the column (CSV/LVM/Polytec header name),
/// the MAT variable name, or the UFF dataset ([`read_uff`]).
pub fn read_signal(
    path: &Path,
    fs: Option<f64>,
    var: Option<&str>,
) -> Result<Signal, SignalFileError> {
    crate::input::read_signal(path, var, fs)
}

/// A time history from a universal file (dataset 58 or 58b, read by
/// [`crate::uff58`]): the real function chosen by `dataset` — its index
/// among the file's dataset-58 functions (from 0), or text contained in
/// its ID line 1 — or, when `None`, the file's only time response
/// (function type 1), else its only function. The abscissa is the time in
/// s: an even one gives `(t0, fs)`, an uneven one the times. `fs` is
/// refused (the file states its sampling). Complex functions (FRFs,
/// spectra) are refused naming the dataset.
pub fn read_uff(
    path: &Path,
    fs: Option<f64>,
    dataset: Option<&str>,
) -> Result<Signal, SignalFileError> {
    use crate::uff58::{function_type_name, read, Abscissa, Uff58Data};
    let uff = |message: String| SignalFileError::Uff {
        path: path.into(),
        message,
    };
    let all = read(path).map_err(|e| uff(e.to_string()))?;
    if all.is_empty() {
        return Err(uff("the universal file holds no dataset 58".into()));
    }
    let listing = || {
        all.iter()
            .map(|f| {
                format!(
                    "{}: {} '{}'",
                    f.info.index,
                    function_type_name(f.dataset.header.function_type),
                    f.dataset.header.id1.trim()
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let chosen: Vec<&crate::uff58::Uff58Function> = match dataset {
        Some(sel) => match sel.trim().parse::<usize>() {
            Ok(i) => all.iter().filter(|f| f.info.index == i).collect(),
            Err(_) => all
                .iter()
                .filter(|f| f.dataset.header.id1.contains(sel))
                .collect(),
        },
        None => {
            let times: Vec<_> = all
                .iter()
                .filter(|f| f.dataset.header.function_type == 1)
                .collect();
            if times.is_empty() && all.len() == 1 {
                all.iter().collect()
            } else {
                times
            }
        }
    };
    let f = match chosen.as_slice() {
        [f] => *f,
        [] => {
            return Err(uff(format!(
                "no dataset {} (datasets: {})",
                dataset.map_or("is a time response".to_string(), |d| format!(
                    "matches '{d}'"
                )),
                listing()
            )))
        }
        _ => {
            return Err(uff(format!(
                "{} datasets match; choose one by index or ID-line text with --var (datasets: {})",
                chosen.len(),
                listing()
            )))
        }
    };
    let Uff58Data::Real(values) = &f.dataset.data else {
        return Err(uff(format!(
            "dataset {} is complex ({}): a time history is a real function",
            f.info.index,
            function_type_name(f.dataset.header.function_type)
        )));
    };
    if let Some(fs) = fs {
        return Err(SignalFileError::FsWithTimeColumn {
            path: path.into(),
            fs,
        });
    }
    let (times, rate) = match &f.dataset.abscissa {
        Abscissa::Even { start, step } => {
            if !(step.is_finite() && *step > 0.0 && start.is_finite()) {
                return Err(uff(format!(
                    "dataset {}: abscissa start {start}, increment {step}: not a sampling in time",
                    f.info.index
                )));
            }
            (None, Some(1.0 / step))
        }
        Abscissa::Uneven(t) => (Some(t.clone()), None),
    };
    let mut s = finish(path, values.clone(), times, rate)?;
    if let (Abscissa::Even { start, .. }, SignalGrid::Uniform { t0, .. }) =
        (&f.dataset.abscissa, &mut s.grid)
    {
        *t0 = *start;
    }
    Ok(s)
}

fn finish(
    path: &Path,
    values: Vec<f64>,
    times: Option<Vec<f64>>,
    fs: Option<f64>,
) -> Result<Signal, SignalFileError> {
    if values.is_empty() {
        return Err(SignalFileError::Empty { path: path.into() });
    }
    let grid = match (times, fs) {
        (Some(_), Some(fs)) => {
            return Err(SignalFileError::FsWithTimeColumn {
                path: path.into(),
                fs,
            })
        }
        (Some(t), None) => match SampledInput::detect_uniform(&t, UNIFORM_TOLERANCE) {
            Some((t0, fs)) => SignalGrid::Uniform { t0, fs },
            None => SignalGrid::Times(t),
        },
        (None, Some(fs)) => SignalGrid::Uniform { t0: 0.0, fs },
        (None, None) => return Err(SignalFileError::MissingFs { path: path.into() }),
    };
    let s = Signal { values, grid };
    s.as_input().map_err(|source| SignalFileError::Signal {
        path: path.into(),
        source,
    })?;
    Ok(s)
}

fn parse_field(path: &Path, line: u64, column: usize, raw: &[u8]) -> Result<f64, SignalFileError> {
    std::str::from_utf8(raw)
        .ok()
        .map(str::trim)
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| SignalFileError::NotANumber {
            path: path.into(),
            line,
            column: column + 1,
            field: String::from_utf8_lossy(raw).into_owned(),
        })
}

/// Reads a CSV signal (see the module docs).
pub fn read_csv(path: &Path, fs: Option<f64>) -> Result<Signal, SignalFileError> {
    check_fs(path, fs)?;
    let file = std::fs::File::open(path).map_err(|source| SignalFileError::Read {
        path: path.into(),
        source,
    })?;
    parse_csv(std::io::BufReader::with_capacity(1 << 20, file), path, fs)
}

/// Parses a CSV signal from `reader` (`path` only names it in errors).
pub fn parse_csv<R: std::io::Read>(
    reader: R,
    path: &Path,
    fs: Option<f64>,
) -> Result<Signal, SignalFileError> {
    check_fs(path, fs)?;
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .buffer_capacity(1 << 20)
        .from_reader(reader);
    let mut rec = csv::ByteRecord::new();
    let csv_err = |e: csv::Error| match e.into_kind() {
        csv::ErrorKind::Io(source) => SignalFileError::Read {
            path: path.into(),
            source,
        },
        other => SignalFileError::Read {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{other:?}")),
        },
    };
    // first non-empty record: header or data
    let first_line;
    loop {
        if !rdr.read_byte_record(&mut rec).map_err(csv_err)? {
            return Err(SignalFileError::Empty { path: path.into() });
        }
        if !(rec.len() == 1 && rec[0].is_empty()) {
            first_line = rec.position().map(|p| p.line()).unwrap_or(1);
            break;
        }
    }
    let numeric = rec.iter().all(|f| {
        std::str::from_utf8(f)
            .ok()
            .and_then(|s| s.trim().parse::<f64>().ok())
            .is_some()
    });
    let ncols = rec.len();
    // (time column, accel column) indices
    let (tcol, acol): (Option<usize>, usize) = if numeric {
        match ncols {
            1 => (None, 0),
            2 => (Some(0), 1),
            n => {
                return Err(SignalFileError::WrongColumns {
                    path: path.into(),
                    line: first_line,
                    expected: "1 column (accel, with --fs) or 2 columns (t,accel)".into(),
                    found: n,
                })
            }
        }
    } else {
        let names: Vec<String> = rec
            .iter()
            .map(|f| String::from_utf8_lossy(f).trim().to_ascii_lowercase())
            .collect();
        match ncols {
            1 => (None, 0),
            2 => (Some(0), 1),
            _ => {
                let find = |cands: &[&str]| names.iter().position(|n| cands.contains(&n.as_str()));
                let t = find(&["t", "time", "t_s"]);
                let a = find(&["accel", "acceleration", "gamma", "u", "accel_m_s2"]).ok_or_else(
                    || SignalFileError::MissingColumn {
                        path: path.into(),
                        wanted: "accel",
                        found: names.join(","),
                    },
                )?;
                (t, a)
            }
        }
    };
    if tcol.is_some() && fs.is_some() {
        return Err(SignalFileError::FsWithTimeColumn {
            path: path.into(),
            fs: fs.unwrap_or(0.0),
        });
    }
    let mut values = Vec::new();
    let mut times = tcol.map(|_| Vec::new());
    let push = |rec: &csv::ByteRecord,
                line: u64,
                values: &mut Vec<f64>,
                times: &mut Option<Vec<f64>>|
     -> Result<(), SignalFileError> {
        if rec.len() != ncols {
            return Err(SignalFileError::WrongColumns {
                path: path.into(),
                line,
                expected: format!("{ncols} column(s) like the first line"),
                found: rec.len(),
            });
        }
        let index = values.len();
        let a = parse_field(path, line, acol, &rec[acol])?;
        if !a.is_finite() {
            return Err(SignalFileError::Invalid {
                path: path.into(),
                line,
                source: SimulationError::NonFiniteSample { index, value: a },
            });
        }
        if let (Some(tc), Some(ts)) = (tcol, times.as_mut()) {
            let t = parse_field(path, line, tc, &rec[tc])?;
            if !t.is_finite() {
                return Err(SignalFileError::Invalid {
                    path: path.into(),
                    line,
                    source: SimulationError::NonFiniteTime { index, value: t },
                });
            }
            if let Some(&previous) = ts.last() {
                if t <= previous {
                    return Err(SignalFileError::Invalid {
                        path: path.into(),
                        line,
                        source: SimulationError::NonMonotonicTime { index, t, previous },
                    });
                }
            }
            ts.push(t);
        }
        values.push(a);
        Ok(())
    };
    if numeric {
        push(&rec, first_line, &mut values, &mut times)?;
    }
    while rdr.read_byte_record(&mut rec).map_err(csv_err)? {
        if rec.len() == 1 && rec[0].is_empty() {
            continue;
        }
        let line = rec.position().map(|p| p.line()).unwrap_or(0);
        push(&rec, line, &mut values, &mut times)?;
    }
    values.shrink_to_fit();
    if let Some(t) = times.as_mut() {
        t.shrink_to_fit();
    }
    finish(path, values, times, fs)
}

/// Reads a MAT v5 signal (see the module docs).
pub fn read_mat(
    path: &Path,
    fs: Option<f64>,
    var: Option<&str>,
) -> Result<Signal, SignalFileError> {
    check_fs(path, fs)?;
    let arrays = crate::mat5::read(path)
        .map_err(|source| SignalFileError::Read {
            path: path.into(),
            source,
        })?
        .map_err(|source| SignalFileError::Mat {
            path: path.into(),
            source,
        })?;
    mat_signal(arrays, path, fs, var)
}

/// Parses a MAT v5 signal held in `bytes` (`path` only names it in errors).
pub fn parse_mat(
    bytes: &[u8],
    path: &Path,
    fs: Option<f64>,
    var: Option<&str>,
) -> Result<Signal, SignalFileError> {
    check_fs(path, fs)?;
    let arrays = crate::mat5::parse(bytes).map_err(|source| SignalFileError::Mat {
        path: path.into(),
        source,
    })?;
    mat_signal(arrays, path, fs, var)
}

fn mat_signal(
    arrays: Vec<crate::mat5::MatArray>,
    path: &Path,
    fs: Option<f64>,
    var: Option<&str>,
) -> Result<Signal, SignalFileError> {
    let find = |name: &str| arrays.iter().find(|a| a.name == name);
    let real = |a: &crate::mat5::MatArray| (!a.complex).then(|| a.real.clone());
    let content = |message: String| SignalFileError::MatContent {
        path: path.into(),
        message,
    };
    let names: Vec<String> = arrays
        .iter()
        .map(|a| format!("{}{:?}", a.name, a.dims))
        .collect();
    let numel = |a: &crate::mat5::MatArray| a.numel();
    let array = match var {
        Some(v) => find(v).ok_or_else(|| {
            content(format!(
                "no numeric variable {v:?} (variables: {})",
                names.join(", ")
            ))
        })?,
        None => {
            let big: Vec<&crate::mat5::MatArray> = arrays.iter().filter(|a| numel(a) > 1).collect();
            let named = big
                .iter()
                .find(|a| ["accel", "acceleration", "gamma", "u"].contains(&a.name.as_str()));
            match (big.len(), named) {
                (0, _) => return Err(SignalFileError::Empty { path: path.into() }),
                (1, _) => big[0],
                (_, Some(a)) => a,
                _ => {
                    return Err(content(format!(
                        "several arrays ({}); choose one with --var",
                        names.join(", ")
                    )))
                }
            }
        }
    };
    let size = array.dims.clone();
    let data = real(array).ok_or_else(|| {
        content(format!(
            "variable {:?} is complex; a real signal is needed",
            array.name
        ))
    })?;
    if data.is_empty() {
        return Err(SignalFileError::Empty { path: path.into() });
    }
    let dims: Vec<usize> = size.iter().copied().filter(|&d| d != 1).collect();
    let check_values = |values: &[f64]| -> Result<(), SignalFileError> {
        if let Some((index, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SignalFileError::Signal {
                path: path.into(),
                source: SimulationError::NonFiniteSample { index, value },
            });
        }
        Ok(())
    };
    let check_times = |t: &[f64]| -> Result<(), SignalFileError> {
        for (index, w) in t.windows(2).enumerate() {
            if !w[1].is_finite() || !w[0].is_finite() {
                let (index, value) = if w[0].is_finite() {
                    (index + 1, w[1])
                } else {
                    (index, w[0])
                };
                return Err(SignalFileError::Signal {
                    path: path.into(),
                    source: SimulationError::NonFiniteTime { index, value },
                });
            }
            if w[1] <= w[0] {
                return Err(SignalFileError::Signal {
                    path: path.into(),
                    source: SimulationError::NonMonotonicTime {
                        index: index + 1,
                        t: w[1],
                        previous: w[0],
                    },
                });
            }
        }
        Ok(())
    };
    if dims.len() <= 1 {
        // vector: fs from caller, a scalar `fs`, or a same-length `t` vector
        let values = data;
        check_values(&values)?;
        if let Some(fs) = fs {
            return finish(path, values, None, Some(fs));
        }
        if let Some(a) = find("fs").filter(|a| numel(a) == 1) {
            let f = real(a).and_then(|v| v.first().copied()).unwrap_or(f64::NAN);
            check_fs(path, Some(f))?;
            return finish(path, values, None, Some(f));
        }
        if let Some(t) = ["t", "time"]
            .iter()
            .filter_map(|n| find(n))
            .find(|a| numel(a) == values.len() && a.name != array.name)
        {
            let t = real(t).ok_or_else(|| content("time vector is complex".into()))?;
            check_times(&t)?;
            return finish(path, values, Some(t), None);
        }
        return Err(SignalFileError::MissingFs { path: path.into() });
    }
    if dims.len() == 2 && (size[0] == 2 || size[1] == 2) {
        // column-major storage: n×2 → columns t, accel; 2×n → rows t, accel
        let (t, a): (Vec<f64>, Vec<f64>) = if size[1] == 2 && size[0] != 2 {
            let n = size[0];
            (data[..n].to_vec(), data[n..].to_vec())
        } else {
            data.chunks_exact(2).map(|c| (c[0], c[1])).unzip()
        };
        check_times(&t)?;
        check_values(&a)?;
        if let Some(fs) = fs {
            return Err(SignalFileError::FsWithTimeColumn {
                path: path.into(),
                fs,
            });
        }
        return finish(path, a, Some(t), None);
    }
    Err(content(format!(
        "variable {:?} has size {:?}; expected a vector (with fs) or an n×2 [t accel] matrix",
        array.name, size
    )))
}

/// Streams numeric CSV rows to an [`AtomicFile`] (visible only after
/// [`CsvWriter::commit`]); numbers are written in the shortest form that
/// reads back exactly.
pub struct CsvWriter {
    file: AtomicFile,
    path: PathBuf,
    num: ryu::Buffer,
    first: bool,
}

impl CsvWriter {
    /// Creates the (hidden) file and writes the header.
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, IoError> {
        let mut w = Self {
            file: AtomicFile::create(path)?,
            path: path.into(),
            num: ryu::Buffer::new(),
            first: true,
        };
        for h in header {
            w.text(h)?;
        }
        w.end_row()?;
        Ok(w)
    }

    fn err(&self, source: std::io::Error) -> IoError {
        IoError::Write {
            path: self.path.clone(),
            source,
        }
    }

    fn sep(&mut self) -> Result<(), IoError> {
        if !self.first {
            self.file.write_all(b",").map_err(|e| self.err(e))?;
        }
        self.first = false;
        Ok(())
    }

    /// One numeric field (non-finite values are written as `nan`/`inf`).
    #[inline]
    pub fn num(&mut self, v: f64) -> Result<(), IoError> {
        self.sep()?;
        let s = if v.is_finite() {
            self.num.format_finite(v)
        } else if v.is_nan() {
            "nan"
        } else if v > 0.0 {
            "inf"
        } else {
            "-inf"
        };
        let bytes = s.as_bytes();
        // ryu writes integers as "1.0": keep it (reads back as a float)
        self.file
            .writer()
            .write_all(bytes)
            .map_err(|e| IoError::Write {
                path: self.path.clone(),
                source: e,
            })
    }

    /// One text field (must not contain commas, quotes or newlines).
    pub fn text(&mut self, s: &str) -> Result<(), IoError> {
        self.sep()?;
        self.file.write_all(s.as_bytes()).map_err(|e| self.err(e))
    }

    /// A whole numeric row.
    #[inline]
    pub fn row(&mut self, vals: &[f64]) -> Result<(), IoError> {
        for &v in vals {
            self.num(v)?;
        }
        self.end_row()
    }

    pub fn end_row(&mut self) -> Result<(), IoError> {
        self.first = true;
        self.file.write_all(b"\n").map_err(|e| self.err(e))
    }

    /// Renames the finished file into place.
    pub fn commit(self) -> Result<(), IoError> {
        self.file.commit()
    }
}

/// Writes a signal as CSV `t,accel` atomically.
pub fn write_signal_csv(path: &Path, t0: f64, fs: f64, values: &[f64]) -> Result<(), IoError> {
    let mut w = CsvWriter::create(path, &["t", "accel"])?;
    for (k, &v) in values.iter().enumerate() {
        w.row(&[t0 + k as f64 / fs, v])?;
    }
    w.commit()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn reads_two_columns_one_column_and_named_columns() {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), "a.csv", "t,accel\n0,1\n0.5,2\n1.0,3\n");
        let s = read_csv(&p, None).unwrap();
        assert_eq!(s.values, vec![1.0, 2.0, 3.0]);
        assert_eq!(s.grid, SignalGrid::Uniform { t0: 0.0, fs: 2.0 });
        let p = write(d.path(), "b.csv", "# comment\n1\n2\n\n3\n");
        let s = read_csv(&p, Some(100.0)).unwrap();
        assert_eq!(s.values.len(), 3);
        assert!(matches!(
            read_csv(&p, None),
            Err(SignalFileError::MissingFs { .. })
        ));
        let p = write(
            d.path(),
            "c.csv",
            "t,accel,x,v\n0,1,0,0\n0.1,2,0,0\n0.3,3,0,0\n",
        );
        let s = read_csv(&p, None).unwrap();
        assert_eq!(s.grid, SignalGrid::Times(vec![0.0, 0.1, 0.3]));
        let p = write(d.path(), "d.csv", "0 , 1\n1e-3, 2\n2e-3,-3.5\n");
        assert_eq!(read_csv(&p, None).unwrap().values, vec![1.0, 2.0, -3.5]);
    }

    #[test]
    fn bad_csv_is_a_clear_error() {
        let d = tempfile::tempdir().unwrap();
        let e = read_csv(&write(d.path(), "e.csv", ""), Some(1.0)).unwrap_err();
        assert!(matches!(e, SignalFileError::Empty { .. }), "{e}");
        let e = read_csv(&write(d.path(), "h.csv", "t,accel\n"), None).unwrap_err();
        assert!(matches!(e, SignalFileError::Empty { .. }), "{e}");
        let e = read_csv(&write(d.path(), "n.csv", "t,accel\n0,1\n1,nan\n"), None).unwrap_err();
        assert!(
            matches!(
                e,
                SignalFileError::Invalid {
                    line: 3,
                    source: SimulationError::NonFiniteSample { index: 1, .. },
                    ..
                }
            ),
            "{e}"
        );
        let e = read_csv(&write(d.path(), "m.csv", "0,1\n1,2\n0.5,3\n"), None).unwrap_err();
        assert!(
            matches!(e, SignalFileError::Invalid { line: 3, source: SimulationError::NonMonotonicTime { index: 2, t, previous }, .. } if t == 0.5 && previous == 1.0),
            "{e}"
        );
        let e = read_csv(&write(d.path(), "w.csv", "0,1,2\n"), None).unwrap_err();
        assert!(
            matches!(e, SignalFileError::WrongColumns { found: 3, .. }),
            "{e}"
        );
        let e = read_csv(&write(d.path(), "r.csv", "0,1\n1\n"), None).unwrap_err();
        assert!(
            matches!(
                e,
                SignalFileError::WrongColumns {
                    line: 2,
                    found: 1,
                    ..
                }
            ),
            "{e}"
        );
        let e = read_csv(&write(d.path(), "x.csv", "0,1\n1,abc\n"), None).unwrap_err();
        assert!(
            matches!(
                e,
                SignalFileError::NotANumber {
                    line: 2,
                    column: 2,
                    ..
                }
            ),
            "{e}"
        );
        let p = write(d.path(), "f.csv", "1\n2\n");
        let e = read_csv(&p, Some(0.0)).unwrap_err();
        assert!(
            matches!(e, SignalFileError::Signal { source: SimulationError::NonPositiveFs { fs }, .. } if fs == 0.0),
            "{e}"
        );
        let e = read_csv(&write(d.path(), "g.csv", "0,1\n1,2\n"), Some(5.0)).unwrap_err();
        assert!(matches!(e, SignalFileError::FsWithTimeColumn { .. }), "{e}");
        let e = read_csv(&write(d.path(), "k.csv", "a,b,c\n1,2,3\n"), None).unwrap_err();
        assert!(matches!(e, SignalFileError::MissingColumn { .. }), "{e}");
        assert!(matches!(
            read_csv(&d.path().join("missing.csv"), None),
            Err(SignalFileError::Read { .. })
        ));
    }

    /// Minimal MAT v5 writer for tests: one uncompressed double matrix per
    /// variable (header, miMATRIX element with flags, dims, name, real part).
    pub(crate) fn mat_bytes(vars: &[(&str, usize, usize, &[f64])]) -> Vec<u8> {
        fn pad(b: &mut Vec<u8>) {
            while b.len() % 8 != 0 {
                b.push(0);
            }
        }
        fn tag(b: &mut Vec<u8>, ty: u32, len: u32) {
            b.extend_from_slice(&ty.to_le_bytes());
            b.extend_from_slice(&len.to_le_bytes());
        }
        let mut out = vec![b' '; 116];
        out[..22].copy_from_slice(b"MATLAB 5.0 MAT-file, t");
        out.extend_from_slice(&[0u8; 8]);
        out.extend_from_slice(&0x0100u16.to_le_bytes());
        out.extend_from_slice(b"IM");
        for (name, rows, cols, data) in vars {
            let mut el = vec![];
            tag(&mut el, 6, 8); // miUINT32 array flags
            el.extend_from_slice(&6u32.to_le_bytes()); // mxDOUBLE_CLASS
            el.extend_from_slice(&0u32.to_le_bytes());
            tag(&mut el, 5, 8); // miINT32 dims
            el.extend_from_slice(&(*rows as i32).to_le_bytes());
            el.extend_from_slice(&(*cols as i32).to_le_bytes());
            tag(&mut el, 1, name.len() as u32); // miINT8 name
            el.extend_from_slice(name.as_bytes());
            pad(&mut el);
            tag(&mut el, 9, (8 * data.len()) as u32); // miDOUBLE
            for v in data.iter() {
                el.extend_from_slice(&v.to_le_bytes());
            }
            pad(&mut el);
            tag(&mut out, 14, el.len() as u32); // miMATRIX
            out.extend_from_slice(&el);
        }
        out
    }

    #[test]
    fn reads_mat_v5_vectors_and_matrices() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("v.mat");
        std::fs::write(
            &p,
            mat_bytes(&[
                ("accel", 4, 1, &[1.0, 2.0, 3.0, 4.0]),
                ("fs", 1, 1, &[2048.0]),
            ]),
        )
        .unwrap();
        let s = read_signal(&p, None, None).unwrap();
        assert_eq!(s.values, vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
            s.grid,
            SignalGrid::Uniform {
                t0: 0.0,
                fs: 2048.0
            }
        );
        // n×2 [t accel], column-major
        let p = d.path().join("m.mat");
        std::fs::write(
            &p,
            mat_bytes(&[("rec", 3, 2, &[0.0, 0.1, 0.3, 5.0, 6.0, 7.0])]),
        )
        .unwrap();
        let s = read_signal(&p, None, None).unwrap();
        assert_eq!(s.values, vec![5.0, 6.0, 7.0]);
        assert_eq!(s.grid, SignalGrid::Times(vec![0.0, 0.1, 0.3]));
        // several arrays: choose by name
        let p = d.path().join("s.mat");
        std::fs::write(
            &p,
            mat_bytes(&[("a", 1, 3, &[1.0, 2.0, 3.0]), ("b", 1, 3, &[4.0, 5.0, 6.0])]),
        )
        .unwrap();
        assert!(matches!(
            read_signal(&p, Some(10.0), None),
            Err(SignalFileError::MatContent { .. })
        ));
        assert_eq!(
            read_signal(&p, Some(10.0), Some("b")).unwrap().values,
            vec![4.0, 5.0, 6.0]
        );
        assert!(matches!(
            read_signal(&p, Some(10.0), Some("zz")),
            Err(SignalFileError::MatContent { .. })
        ));
        // NaN in a MAT vector
        let p = d.path().join("nan.mat");
        std::fs::write(&p, mat_bytes(&[("accel", 3, 1, &[1.0, f64::NAN, 3.0])])).unwrap();
        assert!(matches!(
            read_signal(&p, Some(10.0), None),
            Err(SignalFileError::Signal {
                source: SimulationError::NonFiniteSample { index: 1, .. },
                ..
            })
        ));
        // not a MAT file
        let p = d.path().join("bad.mat");
        std::fs::write(&p, b"hello").unwrap();
        assert!(matches!(
            read_signal(&p, Some(10.0), None),
            Err(SignalFileError::Mat { .. })
        ));
    }

    #[test]
    fn csv_writer_round_trips() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("o.csv");
        let vals = [0.1, -2.5e-7, 3.0, 1.0 / 3.0];
        write_signal_csv(&p, 0.0, 4.0, &vals).unwrap();
        let s = read_csv(&p, None).unwrap();
        assert_eq!(s.values, vals.to_vec());
        assert_eq!(s.grid, SignalGrid::Uniform { t0: 0.0, fs: 4.0 });
    }
}
