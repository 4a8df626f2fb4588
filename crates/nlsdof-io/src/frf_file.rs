//! FRF tables and measured time histories for linear identification.
//!
//! ## FRF CSV (read by `nlsdof linear-id`, written by `nlsdof frf-estimate`)
//!
//! Comma-separated, `#` comments, one header line naming the columns
//! (case-insensitive):
//! * frequency: `f_hz` (also `f`, `freq`, `frequency`), Hz, strictly increasing;
//! * complex value: `re`, `im` (also `real`, `imag`); or
//! * `mag` (also `magnitude`, `abs`) with optional `phase_deg` (also `phase`,
//!   degrees) — without a phase the table is amplitude-only;
//! * optional `coherence`.
//!
//! Without a header, 3 columns are `f_hz,re,im` and 2 columns `f_hz,mag`.
//! Written files have `f_hz,re,im,mag,phase_deg[,coherence]`.
//!
//! ## FRF in a universal file (`.uff`/`.unv`, read by `nlsdof linear-id`)
//!
//! [`read_frf`] reads a dataset 58/58b ([`crate::uff58`]) with complex
//! values: by default the file's only frequency response function
//! (function type 4), else the dataset chosen by a selector — its index
//! among the file's dataset-58 functions (from 0) or text of its ID line 1
//! — which may be any complex function. A real function (coherence,
//! magnitude) is refused. The abscissa must be a frequency in Hz
//! (units label `Hz`, or specific data type 18 without a units label; see
//! [`crate::uff_convert`]), non-negative and strictly increasing, the
//! values finite. The values are used as stored (no unit conversion).
//!
//! ## Time histories (read by `nlsdof frf-estimate`)
//!
//! * **Polytec ASCII export** (`.txt` whose first line starts
//!   `Source File Name`): header lines, then rows `time<TAB>value`, decimal
//!   point; one channel per file, named by its `Signal:` line (e.g. the
//!   impact tests in `shared/data/clamped-beam-duffing-catarinaluz`).
//! * **CSV** with a header: a time column `t`/`time` (or `--fs`) and any
//!   number of named channels; separators comma, semicolon, tab or spaces.
//! * **MAT v5**: one variable per channel (read with
//!   [`crate::signal_file::read_signal`]).
//! * **Universal file** (`.uff`/`.unv`, dataset 58/58b): one real function
//!   a channel, chosen by its number among the file's dataset-58 functions
//!   counted from 1 (dataset index + 1, like the CSV channel numbers) or by
//!   text of its ID line 1; its abscissa must be a time in s, evenly
//!   spaced (or uneven but uniform). A complex function is refused.
//!
//! The sampling must be uniform (time steps equal within 1e-3 of a step).
//!
//! ## Polytec swept-sine FRF (`frf_<A>g.txt` of the beam data)
//!
//! [`read_polytec_sweep`]: tab-separated, decimal comma, two header lines,
//! columns frequency (Hz), amplitude and phase (deg) of run 1 and run 2.

use crate::atomic::AtomicFile;
use crate::csv_table::{CsvOptions, CsvReadError, CsvRows, Encoding, Separator};
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors reading FRF tables and time histories; each names the file and,
/// where there is one, the line and the offending value.
#[derive(Debug, Error)]
pub enum FrfFileError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no data rows")]
    Empty { path: PathBuf },
    #[error("{path}: line {line}: {message}")]
    Line {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: {message}")]
    Content { path: PathBuf, message: String },
    /// A MAT channel (read as a signal).
    #[error(transparent)]
    Signal(#[from] crate::signal_file::SignalFileError),
}

/// One channel of a time history and its sampling frequency, Hz: a MAT
/// variable (by name; a number picks the file's only array) or a channel
/// of a CSV or Polytec time history ([`read_time_history`],
/// [`TimeHistory::channel`]: by name or 1-based number). `fs` is the
/// sampling frequency of a file without a time column.
pub fn read_channel(
    path: &Path,
    key: &str,
    fs: Option<f64>,
) -> Result<(f64, Vec<f64>), FrfFileError> {
    use crate::input::Format;
    // the format from the content (the one reader layer, crate::input)
    let format = crate::input::detect_file(path).map_err(|source| FrfFileError::Read {
        path: path.into(),
        source,
    })?;
    match format {
        Format::Uff => return read_uff_channel(path, key, fs),
        Format::Lvm => return read_lvm_channel(path, key, fs),
        Format::Other(what) => {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: format!("this is {what}"),
            })
        }
        _ => {}
    }
    if format == Format::Mat {
        let var = if key.parse::<usize>().is_ok() {
            None
        } else {
            Some(key)
        };
        let s = crate::signal_file::read_signal(path, fs, var)?;
        return match s.grid {
            crate::signal_file::SignalGrid::Uniform { fs, .. } => Ok((fs, s.values)),
            crate::signal_file::SignalGrid::Times(_) => Err(FrfFileError::Content {
                path: path.into(),
                message: format!("sampling of {key:?} is not uniform"),
            }),
        };
    }
    let th = read_time_history(path, fs)?;
    let v = th.channel(key, path)?.to_vec();
    Ok((th.fs, v))
}

/// A channel of a LabVIEW `.lvm` file: the column named `key`
/// (case-insensitive) or the `key`-th channel from 1 (the columns after
/// `X_Value`, which is the time), sampled at the rate of `X_Value` (or at
/// `fs` when the file has no `X_Value`).
fn read_lvm_channel(
    path: &Path,
    key: &str,
    fs: Option<f64>,
) -> Result<(f64, Vec<f64>), FrfFileError> {
    use crate::table_file::{find_column, listing, read_picked, TableError};
    let table = read_picked(path, &|names: &[String], header: bool| {
        let t = crate::input::TIME_COLUMNS
            .iter()
            .find_map(|n| find_column(names, header, n).filter(|_| header));
        let channels: Vec<usize> = (0..names.len())
            .filter(|&i| Some(i) != t && !names[i].is_empty())
            .collect();
        let by_name = names
            .iter()
            .position(|n| !n.is_empty() && n.eq_ignore_ascii_case(key.trim()));
        let by_number = key
            .trim()
            .parse::<usize>()
            .ok()
            .and_then(|k| k.checked_sub(1))
            .and_then(|k| channels.get(k).copied());
        let c = by_name.or(by_number).ok_or_else(|| TableError::Column {
            path: path.into(),
            message: format!(
                "no channel {:?} (channels by name or number from 1: {})",
                crate::text::shown(key),
                channels
                    .iter()
                    .enumerate()
                    .map(|(k, &i)| format!("{} {}", k + 1, names[i]))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?;
        match (t, fs) {
            (Some(t), None) => Ok(vec![c, t]),
            (None, Some(_)) => Ok(vec![c]),
            (Some(_), Some(f)) => Err(TableError::Column {
                path: path.into(),
                message: format!("the file has a time column (X_Value); --fs {f} would contradict it (drop --fs)"),
            }),
            (None, None) => Err(TableError::Column {
                path: path.into(),
                message: format!(
                    "no time column (X_Value) among {}: give the sampling frequency (--fs HZ)",
                    listing(names, header)
                ),
            }),
        }
    })
    .map_err(|e| FrfFileError::Content {
        path: path.into(),
        message: {
            let m = e.to_string();
            let p = format!("{}: ", path.display());
            m.strip_prefix(&p).unwrap_or(&m).to_string()
        },
    })?;
    let mut cols = table.columns.into_iter();
    let values = cols.next().unwrap_or_default();
    let rate = match (cols.next(), fs) {
        (Some(t), _) => {
            let lines = vec![0; t.len()];
            uniform_fs(path, &t, &lines)?
        }
        (None, Some(f)) => f,
        (None, None) => {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: "no sampling frequency: give --fs HZ".into(),
            })
        }
    };
    Ok((rate, values))
}

/// A channel of a universal file (see the module documentation): the real
/// function chosen by `key` (number from 1, or ID-line-1 text), with its
/// sampling frequency, Hz. `fs` is refused (the file states its sampling).
pub fn read_uff_channel(
    path: &Path,
    key: &str,
    fs: Option<f64>,
) -> Result<(f64, Vec<f64>), FrfFileError> {
    use crate::uff58::{function_type_name, Abscissa, Uff58Data};
    let content = |message: String| FrfFileError::Content {
        path: path.into(),
        message,
    };
    let all = crate::uff58::read(path).map_err(|e| content(e.to_string()))?;
    let f = crate::uff_convert::select(&all, Some(key), 1, "the channel option", "", |_| false)
        .map_err(|m| content(format!("channel {key:?}: {m}")))?;
    let label = format!(
        "channel {} ({:?})",
        f.info.index + 1,
        f.dataset.header.id1.trim()
    );
    let Uff58Data::Real(values) = &f.dataset.data else {
        return Err(content(format!(
            "{label} is complex ({}): a time history is a real function",
            function_type_name(f.dataset.header.function_type)
        )));
    };
    crate::uff_convert::check_time_axis(&label, &f.dataset.header).map_err(content)?;
    if let Some(g) = fs {
        return Err(content(format!(
            "the file states its sampling; --fs {g} would contradict it (drop --fs)"
        )));
    }
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(content(format!(
            "{label}: sample {k} is {} (not finite)",
            values[k]
        )));
    }
    let rate = match &f.dataset.abscissa {
        Abscissa::Even { step, .. } => {
            if !(step.is_finite() && *step > 0.0) {
                return Err(content(format!(
                    "{label}: time increment {step} s must be > 0"
                )));
            }
            1.0 / step
        }
        Abscissa::Uneven(t) => {
            let lines = vec![0; t.len()];
            uniform_fs(path, t, &lines).map_err(|e| {
                content(format!(
                    "{label}: {}",
                    match e {
                        FrfFileError::Line { message, .. }
                        | FrfFileError::Content { message, .. } => message,
                        other => other.to_string(),
                    }
                ))
            })?
        }
    };
    if values.len() < 2 {
        return Err(content(format!(
            "{label}: {} sample(s): need at least 2",
            values.len()
        )));
    }
    Ok((rate, values.clone()))
}

/// Reads an FRF: a universal file (`.uff`/`.unv`, dataset chosen by
/// `dataset`, see the module documentation) or else an FRF CSV table
/// ([`read_frf_csv`], where `dataset` must be `None`).
pub fn read_frf(path: &Path, dataset: Option<&str>) -> Result<FrfTable, FrfFileError> {
    if crate::input::is_uff_file(path) {
        return read_frf_uff(path, dataset);
    }
    if let Some(d) = dataset {
        return Err(FrfFileError::Content {
            path: path.into(),
            message: format!(
                "--dataset {d:?} chooses a dataset of a universal file (.uff/.unv); this is read as a CSV table"
            ),
        });
    }
    read_frf_csv(path)
}

/// The FRF of a universal file (see the module documentation).
pub fn read_frf_uff(path: &Path, dataset: Option<&str>) -> Result<FrfTable, FrfFileError> {
    use crate::uff58::{function_type_name, Uff58Data};
    let content = |message: String| FrfFileError::Content {
        path: path.into(),
        message,
    };
    let all = crate::uff58::read(path).map_err(|e| content(e.to_string()))?;
    let f = crate::uff_convert::select(
        &all,
        dataset,
        0,
        "--dataset",
        "is a complex frequency response function (function type 4)",
        |f| f.info.complex && f.dataset.header.function_type == 4,
    )
    .map_err(content)?;
    let label = format!(
        "dataset {} ({:?})",
        f.info.index,
        f.dataset.header.id1.trim()
    );
    let Uff58Data::Complex(values) = &f.dataset.data else {
        return Err(content(format!(
            "{label} is real ({}): an FRF is a complex function",
            function_type_name(f.dataset.header.function_type)
        )));
    };
    crate::uff_convert::check_frequency_axis(&label, &f.dataset.header).map_err(content)?;
    if values.is_empty() {
        return Err(FrfFileError::Empty { path: path.into() });
    }
    let f_hz = f.dataset.abscissa_values();
    for (k, (&fr, &(re, im))) in f_hz.iter().zip(values).enumerate() {
        if !(fr.is_finite() && re.is_finite() && im.is_finite()) {
            return Err(content(format!(
                "{label}: point {k}: frequency {fr} Hz, value ({re}, {im}) is not finite"
            )));
        }
        if k == 0 && fr < 0.0 {
            return Err(content(format!("{label}: negative frequency {fr} Hz")));
        }
        if k > 0 && fr <= f_hz[k - 1] {
            return Err(content(format!(
                "{label}: point {k}: frequency {fr} Hz does not exceed the previous one ({} Hz): frequencies must be strictly increasing",
                f_hz[k - 1]
            )));
        }
    }
    let magnitude = values.iter().map(|(a, b)| a.hypot(*b)).collect();
    Ok(FrfTable {
        f_hz,
        values: Some(values.clone()),
        magnitude,
        coherence: None,
    })
}

/// An FRF table read from CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfTable {
    pub f_hz: Vec<f64>,
    /// Complex values `(re, im)`, or `None` for amplitude-only data.
    pub values: Option<Vec<(f64, f64)>>,
    /// `|H|` (always present).
    pub magnitude: Vec<f64>,
    pub coherence: Option<Vec<f64>>,
}

fn find(names: &[String], wanted: &[&str]) -> Option<usize> {
    names.iter().position(|n| wanted.contains(&n.as_str()))
}

/// A row that could not be read (I/O or encoding), as a content error.
fn csv_error(path: &Path, e: CsvReadError) -> FrfFileError {
    FrfFileError::Content {
        path: path.into(),
        message: e.to_string(),
    }
}

fn parse_num(path: &Path, line: usize, field: &str) -> Result<f64, FrfFileError> {
    let v: f64 = field.trim().parse().map_err(|_| FrfFileError::Line {
        path: path.into(),
        line,
        message: format!("{:?} is not a number", field.trim()),
    })?;
    if !v.is_finite() {
        return Err(FrfFileError::Line {
            path: path.into(),
            line,
            message: format!("value {v} is not finite"),
        });
    }
    Ok(v)
}

/// The file's text (UTF-8, or Latin-1/Windows-1252), at most
/// [`crate::text::MAX_TEXT_BYTES`]; a binary file is refused naming what
/// it is.
fn read_text(path: &Path) -> Result<String, FrfFileError> {
    crate::text::read_text(path).map_err(|e| match e {
        crate::text::TextFileError::Read(source) => FrfFileError::Read {
            path: path.into(),
            source,
        },
        e => FrfFileError::Content {
            path: path.into(),
            message: e.to_string(),
        },
    })
}

/// Reads an FRF CSV table (see the module documentation).
pub fn read_frf_csv(path: &Path) -> Result<FrfTable, FrfFileError> {
    let text = read_text(path)?;
    parse_frf_csv(&text, path)
}

/// Parses an FRF table from CSV text (`path` only names it in errors).
pub fn parse_frf_csv(text: &str, path: &Path) -> Result<FrfTable, FrfFileError> {
    let mut csv = CsvRows::new(text.as_bytes(), CsvOptions::default());
    let mut header: Option<Vec<String>> = None;
    let mut rows: Vec<(usize, Vec<f64>)> = Vec::new();
    while let Some((line, fields)) = csv.next_row().map_err(|e| FrfFileError::Read {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.to_string()),
    })? {
        let line = line as usize;
        if header.is_none() && rows.is_empty() && fields.iter().any(|f| f.parse::<f64>().is_err()) {
            header = Some(fields.iter().map(|f| f.to_ascii_lowercase()).collect());
            continue;
        }
        let vals = fields
            .iter()
            .map(|f| parse_num(path, line, f))
            .collect::<Result<Vec<_>, _>>()?;
        rows.push((line, vals));
    }
    if rows.is_empty() {
        return Err(FrfFileError::Empty { path: path.into() });
    }
    let ncol = header.as_ref().map(|h| h.len()).unwrap_or(rows[0].1.len());
    for (line, r) in &rows {
        if r.len() != ncol {
            return Err(FrfFileError::Line {
                path: path.into(),
                line: *line,
                message: format!("expected {ncol} columns, found {}", r.len()),
            });
        }
    }
    let names = header.unwrap_or_else(|| match ncol {
        2 => vec!["f_hz".into(), "mag".into()],
        3 => vec!["f_hz".into(), "re".into(), "im".into()],
        _ => vec![],
    });
    let content = |message: String| FrfFileError::Content {
        path: path.into(),
        message,
    };
    let fcol =
        find(&names, &["f_hz", "f", "freq", "frequency", "frequency_hz"]).ok_or_else(|| {
            content(format!(
                "no frequency column (f_hz) among [{}]",
                names.join(", ")
            ))
        })?;
    let re = find(&names, &["re", "real"]);
    let im = find(&names, &["im", "imag"]);
    let mag = find(&names, &["mag", "magnitude", "abs"]);
    let ph = find(&names, &["phase_deg", "phase"]);
    let coh = find(&names, &["coherence"]);
    let col = |c: usize| rows.iter().map(|r| r.1[c]).collect::<Vec<f64>>();
    let f_hz = col(fcol);
    for i in 1..f_hz.len() {
        if f_hz[i] <= f_hz[i - 1] {
            return Err(FrfFileError::Line {
                path: path.into(),
                line: rows[i].0,
                message: format!("frequency {} Hz does not exceed the previous one ({} Hz): frequencies must be strictly increasing", f_hz[i], f_hz[i - 1]),
            });
        }
    }
    if f_hz[0] < 0.0 {
        return Err(FrfFileError::Line {
            path: path.into(),
            line: rows[0].0,
            message: format!("negative frequency {} Hz", f_hz[0]),
        });
    }
    let (values, magnitude) = match (re, im, mag, ph) {
        (Some(r), Some(i), _, _) => {
            let v: Vec<(f64, f64)> = col(r).into_iter().zip(col(i)).collect();
            let m = v.iter().map(|(a, b)| a.hypot(*b)).collect();
            (Some(v), m)
        }
        (_, _, Some(m), Some(p)) => {
            let m = col(m);
            let v = m
                .iter()
                .zip(col(p))
                .map(|(a, d)| (a * d.to_radians().cos(), a * d.to_radians().sin()))
                .collect();
            (Some(v), m)
        }
        (_, _, Some(m), None) => (None, col(m)),
        _ => {
            return Err(content(format!(
                "need columns re,im or mag[,phase_deg]; found [{}]",
                names.join(", ")
            )))
        }
    };
    Ok(FrfTable {
        f_hz,
        values,
        magnitude,
        coherence: coh.map(col),
    })
}

/// Writes `f_hz,re,im,mag,phase_deg[,coherence]` atomically.
pub fn write_frf_csv(
    path: &Path,
    f_hz: &[f64],
    values: &[(f64, f64)],
    coherence: Option<&[f64]>,
) -> Result<(), FrfFileError> {
    let werr = |source| FrfFileError::Write {
        path: path.into(),
        source,
    };
    let mut f = AtomicFile::create(path).map_err(|e| FrfFileError::Content {
        path: path.into(),
        message: e.to_string(),
    })?;
    let mut s = String::from(if coherence.is_some() {
        "f_hz,re,im,mag,phase_deg,coherence\n"
    } else {
        "f_hz,re,im,mag,phase_deg\n"
    });
    for (i, (&fr, &(re, im))) in f_hz.iter().zip(values).enumerate() {
        s += &format!(
            "{fr:?},{re:?},{im:?},{:?},{:?}",
            re.hypot(im),
            im.atan2(re).to_degrees()
        );
        if let Some(c) = coherence {
            s += &format!(",{:?}", c[i]);
        }
        s.push('\n');
    }
    f.write_all(s.as_bytes()).map_err(werr)?;
    f.commit().map_err(|e| FrfFileError::Content {
        path: path.into(),
        message: e.to_string(),
    })
}

/// Uniformly sampled channels read from one file.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeHistory {
    pub fs: f64,
    pub channels: Vec<(String, Vec<f64>)>,
}

impl TimeHistory {
    /// A channel by name (case-insensitive) or by 1-based index among the channels.
    pub fn channel(&self, key: &str, path: &Path) -> Result<&[f64], FrfFileError> {
        if let Some(c) = self.channels.iter().find(|c| c.0.eq_ignore_ascii_case(key)) {
            return Ok(&c.1);
        }
        if let Ok(i) = key.parse::<usize>() {
            if i >= 1 && i <= self.channels.len() {
                return Ok(&self.channels[i - 1].1);
            }
        }
        let names: Vec<&str> = self.channels.iter().map(|c| c.0.as_str()).collect();
        Err(FrfFileError::Content {
            path: path.into(),
            message: format!("no channel {key:?} (channels: {})", names.join(", ")),
        })
    }
}

fn uniform_fs(path: &Path, t: &[f64], lines: &[usize]) -> Result<f64, FrfFileError> {
    if t.len() < 2 {
        return Err(FrfFileError::Content {
            path: path.into(),
            message: format!("{} sample(s): need at least 2", t.len()),
        });
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    for i in 1..t.len() {
        let step = t[i] - t[i - 1];
        if step.is_nan() || step <= 0.0 || (step - dt).abs() > 1e-3 * dt.abs() {
            return Err(FrfFileError::Line {
                path: path.into(),
                line: lines[i],
                message: format!(
                    "time {} s after {} s: sampling must be uniform with step {dt} s",
                    t[i],
                    t[i - 1]
                ),
            });
        }
    }
    Ok(1.0 / dt)
}

/// Reads a Polytec ASCII time export (one channel) or a multi-channel CSV
/// (see the module documentation). `fs` is needed for a CSV without a time
/// column and must not contradict one.
pub fn read_time_history(path: &Path, fs: Option<f64>) -> Result<TimeHistory, FrfFileError> {
    if let Some(f) = fs {
        if !(f.is_finite() && f > 0.0) {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: format!("sampling frequency {f} Hz must be > 0"),
            });
        }
    }
    let text = read_text(path)?;
    parse_time_history(&text, path, fs)
}

/// Parses time histories (CSV or Polytec ASCII export) from text (`path`
/// only names it in errors).
pub fn parse_time_history(
    text: &str,
    path: &Path,
    fs: Option<f64>,
) -> Result<TimeHistory, FrfFileError> {
    if let Some(f) = fs {
        if !(f.is_finite() && f > 0.0) {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: format!("sampling frequency {f} Hz must be > 0"),
            });
        }
    }
    let text = crate::strip_bom(text);
    if text.starts_with("Source File Name") {
        return read_polytec_time(path, &text, fs);
    }
    let mut header: Option<Vec<String>> = None;
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut lines = Vec::new();
    let opts = CsvOptions::default().with_separator(Separator::PerLine);
    let mut rows = CsvRows::new(text.as_bytes(), opts);
    while let Some((line, fields)) = rows.next_row().map_err(|e| csv_error(path, e))? {
        let line = line as usize;
        if header.is_none() && cols.is_empty() && fields.iter().any(|f| f.parse::<f64>().is_err()) {
            header = Some(fields.to_vec());
            continue;
        }
        if cols.is_empty() {
            cols = vec![Vec::new(); fields.len()];
        }
        if fields.len() != cols.len() {
            return Err(FrfFileError::Line {
                path: path.into(),
                line,
                message: format!("expected {} columns, found {}", cols.len(), fields.len()),
            });
        }
        for (c, f) in fields.iter().enumerate() {
            cols[c].push(parse_num(path, line, f)?);
        }
        lines.push(line);
    }
    if cols.is_empty() {
        return Err(FrfFileError::Empty { path: path.into() });
    }
    let names = header.unwrap_or_else(|| (1..=cols.len()).map(|i| format!("ch{i}")).collect());
    if names.len() != cols.len() {
        return Err(FrfFileError::Content {
            path: path.into(),
            message: format!(
                "header has {} names but rows have {} columns",
                names.len(),
                cols.len()
            ),
        });
    }
    let tcol = names
        .iter()
        .position(|n| n.eq_ignore_ascii_case("t") || n.eq_ignore_ascii_case("time"));
    let fs = match (tcol, fs) {
        (Some(_), Some(f)) => {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: format!("the file has a time column; --fs {f} would contradict it"),
            })
        }
        (Some(c), None) => uniform_fs(path, &cols[c], &lines)?,
        (None, Some(f)) => f,
        (None, None) => {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: "no time column (t/time): give the sampling frequency (--fs HZ)".into(),
            })
        }
    };
    let channels = names
        .into_iter()
        .zip(cols)
        .enumerate()
        .filter(|(i, _)| Some(*i) != tcol)
        .map(|(_, c)| c)
        .collect();
    Ok(TimeHistory { fs, channels })
}

fn read_polytec_time(
    path: &Path,
    text: &str,
    fs: Option<f64>,
) -> Result<TimeHistory, FrfFileError> {
    let mut name = String::from("signal");
    let mut t = Vec::new();
    let mut v = Vec::new();
    let mut lines = Vec::new();
    let opts = CsvOptions::default().with_separator(Separator::Tab);
    let mut rows = CsvRows::new(text.as_bytes(), opts);
    while let Some((line, fields)) = rows.next_row().map_err(|e| csv_error(path, e))? {
        let line = line as usize;
        let joined = fields.join("\t");
        if let Some(rest) = joined.strip_prefix("Signal:") {
            // "Time - Ref1 Force - Samples" -> "Ref1 Force"
            let parts: Vec<&str> = rest.split(" - ").map(str::trim).collect();
            name = parts.get(1).unwrap_or(&parts[0]).to_string();
            continue;
        }
        if fields.len() != 2 {
            if t.is_empty() {
                continue;
            }
            return Err(FrfFileError::Line {
                path: path.into(),
                line,
                message: format!("expected 'time<TAB>value', found {joined:?}"),
            });
        }
        match (fields[0].parse::<f64>(), fields[1].parse::<f64>()) {
            (Ok(a), Ok(b)) => {
                if !(a.is_finite() && b.is_finite()) {
                    return Err(FrfFileError::Line {
                        path: path.into(),
                        line,
                        message: format!("non-finite sample {a}, {b}"),
                    });
                }
                t.push(a);
                v.push(b);
                lines.push(line);
            }
            _ if t.is_empty() => continue,
            _ => {
                return Err(FrfFileError::Line {
                    path: path.into(),
                    line,
                    message: format!("{joined:?} is not 'time<TAB>value'"),
                })
            }
        }
    }
    if t.is_empty() {
        return Err(FrfFileError::Empty { path: path.into() });
    }
    let f = uniform_fs(path, &t, &lines)?;
    if let Some(g) = fs {
        if (g - f).abs() > 1e-6 * f {
            return Err(FrfFileError::Content {
                path: path.into(),
                message: format!(
                    "the file has a time column (fs = {f} Hz); --fs {g} would contradict it"
                ),
            });
        }
    }
    Ok(TimeHistory {
        fs: f,
        channels: vec![(name, v)],
    })
}

/// One run of a Polytec swept-sine FRF export.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRun {
    pub f_hz: Vec<f64>,
    pub amplitude: Vec<f64>,
    pub phase_deg: Vec<f64>,
}

/// Reads a Polytec swept-sine export with decimal commas (the beam
/// `frf_<A>g.txt` files): returns run 1 and, if present, run 2.
pub fn read_polytec_sweep(path: &Path) -> Result<Vec<SweepRun>, FrfFileError> {
    let bytes = std::fs::read(path).map_err(|source| FrfFileError::Read {
        path: path.into(),
        source,
    })?;
    parse_polytec_sweep(&bytes, path)
}

/// Parses a Polytec swept-sine export held in `bytes` (latin-1; `path` only
/// names it in errors).
pub fn parse_polytec_sweep(bytes: &[u8], path: &Path) -> Result<Vec<SweepRun>, FrfFileError> {
    let opts = CsvOptions::default()
        .with_separator(Separator::Tab)
        .with_encoding(Encoding::Latin1)
        .with_decimal_comma();
    let mut rows = CsvRows::new(bytes, opts);
    let mut runs: Vec<SweepRun> = Vec::new();
    while let Some((line, fields)) = rows.next_row().map_err(|e| csv_error(path, e))? {
        // two header lines
        if line <= 2 {
            continue;
        }
        let i = line as usize - 1;
        let vals = fields
            .iter()
            .map(|f| parse_num(path, i + 1, &f.replace(',', ".")))
            .collect::<Result<Vec<f64>, _>>()?;
        if vals.len() < 3 || (vals.len() - 1) % 2 != 0 {
            return Err(FrfFileError::Line {
                path: path.into(),
                line: i + 1,
                message: format!("expected 1 + 2k columns, found {}", vals.len()),
            });
        }
        let k = (vals.len() - 1) / 2;
        if runs.is_empty() {
            runs = vec![
                SweepRun {
                    f_hz: vec![],
                    amplitude: vec![],
                    phase_deg: vec![]
                };
                k
            ];
        }
        if k != runs.len() {
            return Err(FrfFileError::Line {
                path: path.into(),
                line: i + 1,
                message: format!("expected {} runs, found {k}", runs.len()),
            });
        }
        for (j, r) in runs.iter_mut().enumerate() {
            r.f_hz.push(vals[0]);
            r.amplitude.push(vals[1 + 2 * j]);
            r.phase_deg.push(vals[2 + 2 * j]);
        }
    }
    if runs.is_empty() {
        return Err(FrfFileError::Empty { path: path.into() });
    }
    Ok(runs)
}

/// The input and output channels of an FRF estimate (`nlsdof
/// frf-estimate`, Python `frf_estimate`) with their common sampling
/// frequency, Hz: `input_key` of `input` and `output_key` of `output`
/// (another file, e.g. a Polytec export per channel) or of `input`. The
/// output channel defaults to 1 in another file, else 2. Sampling
/// frequencies that differ (by more than 1e-9 relative) are an error
/// naming both.
pub fn read_channel_pair(
    input: &Path,
    input_key: &str,
    output: Option<&Path>,
    output_key: Option<&str>,
    fs: Option<f64>,
) -> Result<(f64, Vec<f64>, Vec<f64>), FrfFileError> {
    let (fs_in, x) = read_channel(input, input_key, fs)?;
    let out_path = output.unwrap_or(input);
    let out_key = output_key.unwrap_or(if output.is_some() { "1" } else { "2" });
    let (fs_out, y) = read_channel(out_path, out_key, fs)?;
    if (fs_in - fs_out).abs() > 1e-9 * fs_in {
        return Err(FrfFileError::Content {
            path: out_path.into(),
            message: format!("sampling frequencies differ: input {fs_in} Hz, output {fs_out} Hz"),
        });
    }
    Ok((fs_in, x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frf_csv_round_trip_and_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("h.csv");
        write_frf_csv(
            &p,
            &[1.0, 2.0],
            &[(1.0, -1.0), (0.5, 0.25)],
            Some(&[0.9, 1.0]),
        )
        .unwrap();
        let t = read_frf_csv(&p).unwrap();
        assert_eq!(t.values.unwrap(), vec![(1.0, -1.0), (0.5, 0.25)]);
        assert_eq!(t.coherence.unwrap(), vec![0.9, 1.0]);
        std::fs::write(&p, "f_hz,mag,phase_deg\n1,2,90\n2,1,0\n").unwrap();
        let t = read_frf_csv(&p).unwrap();
        let v = t.values.unwrap();
        assert!(v[0].0.abs() < 1e-15 && (v[0].1 - 2.0).abs() < 1e-15);
        std::fs::write(&p, "f_hz,re,im\n1,2,3\n1,2,3\n").unwrap();
        let e = read_frf_csv(&p).unwrap_err().to_string();
        assert!(
            e.contains("line 3") && e.contains("strictly increasing"),
            "{e}"
        );
        std::fs::write(&p, "f_hz,re,im\n1,2,nan\n").unwrap();
        assert!(read_frf_csv(&p)
            .unwrap_err()
            .to_string()
            .contains("not finite"));
        std::fs::write(&p, "f_hz,re,im\n1,2\n").unwrap();
        assert!(read_frf_csv(&p)
            .unwrap_err()
            .to_string()
            .contains("expected 3 columns"));
    }

    fn oracle(name: &str) -> (PathBuf, serde_json::Value) {
        let p = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/uff58")
            .join(name);
        let text = std::fs::read_to_string(p.with_file_name(format!("{name}.json"))).unwrap();
        (p, serde_json::from_str(&text).unwrap())
    }

    fn num(v: &serde_json::Value) -> f64 {
        v.as_str().unwrap().parse().unwrap()
    }

    #[test]
    fn uff_frfs_read_as_pyuff_reads_them() {
        for name in [
            "ascii_double_complex_even_frf.uff",
            "binary_double_complex_uneven_frf_be.uff",
            "crlf_ascii_double_complex_even_frf.uff",
        ] {
            let (p, j) = oracle(name);
            let t = read_frf(&p, None).unwrap();
            let set = &j["sets"][0];
            let x = set["x"].as_array().unwrap();
            let data = set["data"].as_array().unwrap();
            let v = t.values.as_ref().unwrap();
            assert_eq!(t.f_hz.len(), x.len(), "{name}");
            for k in 0..x.len() {
                let (re, im) = (num(&data[k][0]), num(&data[k][1]));
                let f = num(&x[k]);
                // pyuff's x of an even abscissa is min + k inc: round-off only
                assert!((t.f_hz[k] - f).abs() <= 1e-12 * f.abs(), "{name} {k}");
                assert_eq!(v[k], (re, im), "{name} {k}");
                assert_eq!(t.magnitude[k], re.hypot(im));
            }
            assert_eq!(read_frf(&p, Some("0")).unwrap(), t);
        }
        // a real function chosen, a file without an FRF, a time abscissa
        let (p, _) = oracle("ascii_single_real_even_coherence.uff");
        let e = read_frf(&p, Some("0")).unwrap_err().to_string();
        assert!(
            e.contains("is real (coherence): an FRF is a complex function"),
            "{e}"
        );
        let e = read_frf(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("no dataset is a complex frequency response function"),
            "{e}"
        );
        // any complex function may be chosen explicitly (a cross spectrum)
        let (p, _) = oracle("ascii_single_complex_even_crossspectrum.uff");
        assert!(read_frf(&p, None).is_err());
        assert!(read_frf(&p, Some("Cross")).is_ok());
        let (p, _) = oracle("ascii_double_real_even_time.uff");
        let e = read_uff_channel(&p, "1", None).unwrap();
        assert!(e.1.len() > 2);
        let e = read_frf(&p, Some("0")).unwrap_err().to_string();
        assert!(e.contains("is real (time response)"), "{e}");
        let (p, _) = oracle("ascii_double_complex_even_frf.uff");
        let e = read_uff_channel(&p, "1", None).unwrap_err().to_string();
        assert!(
            e.contains("is complex (frequency response function)"),
            "{e}"
        );
    }

    #[test]
    fn time_history_csv_and_polytec() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("th.csv");
        std::fs::write(&p, "t,force,vel\n0,1,2\n0.1,3,4\n0.2,5,6\n").unwrap();
        let th = read_time_history(&p, None).unwrap();
        assert!((th.fs - 10.0).abs() < 1e-9);
        assert_eq!(th.channel("vel", &p).unwrap(), &[2.0, 4.0, 6.0]);
        assert_eq!(th.channel("1", &p).unwrap(), &[1.0, 3.0, 5.0]);
        assert!(th.channel("acc", &p).is_err());
        let q = dir.path().join("p.txt");
        std::fs::write(&q, "Source File Name:\tt3\r\nSignal:\tTime - Ref1 Force - Samples\r\n\r\nTime\tTime Signal\r\n[ s ]\t[ N ]\r\n0\t1.5\r\n0.0001\t2.5\r\n0.0002\t3\r\n").unwrap();
        let th = read_time_history(&q, None).unwrap();
        assert_eq!(th.channels[0].0, "Ref1 Force");
        assert!((th.fs - 1e4).abs() < 1e-6);
        std::fs::write(&p, "t,x\n0,1\n0.1,2\n0.3,3\n").unwrap();
        assert!(read_time_history(&p, None)
            .unwrap_err()
            .to_string()
            .contains("uniform"));
    }
}
