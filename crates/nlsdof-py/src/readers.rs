//! Readers of measured data (`nlsdof_io`): LabVIEW `.lvm` text, Polytec
//! ASCII exports (time histories and swept-sine FRFs) and MAT v5 files, as
//! dicts of numpy arrays. The same functions read these files for the
//! CLI's verbs (`decay`, `fit-time`, `frf-estimate`, `fit --beam-dir`), so
//! Python sees the numbers the CLI uses.

use crate::convert::value_error;
use nlsdof_io::frf_file::{parse_time_history, read_polytec_sweep as io_read_polytec_sweep};
use nlsdof_io::signal_file::SignalFileError;
use nlsdof_io::table_file::{parse_columns, read_columns, read_picked, TableError};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyList};
use std::path::{Path, PathBuf};

/// The columns of a table file, all (`columns` None: every named column
/// that has a number on every row) or those named (names or 0-based
/// indices, as `--column` of `nlsdof decay`).
fn table_columns(
    path: &Path,
    columns: Option<Vec<String>>,
) -> Result<nlsdof_io::table_file::Table, TableError> {
    if let Some(c) = columns {
        let wanted: Vec<&str> = c.iter().map(String::as_str).collect();
        if wanted.is_empty() {
            // an empty list reads every column, as None does
            return table_columns(path, None);
        }
        return read_columns(path, &wanted);
    }
    // every named column, less those found to end early
    let mut dropped: Vec<String> = Vec::new();
    loop {
        let pick = |names: &[String], _header: bool| {
            Ok((0..names.len())
                .filter(|&i| !names[i].is_empty() && !dropped.contains(&names[i]))
                .collect())
        };
        match read_picked(path, &pick) {
            // a column that ends early (LabVIEW's shorter channels, a
            // `Comment` column) is left out; a field that is not a number
            // stays an error
            Err(e) => {
                let gap = match &e {
                    TableError::ShortLine { column, .. } => Some(column.clone()),
                    TableError::NotANumber { column, field, .. } if field.trim().is_empty() => {
                        Some(column.clone())
                    }
                    _ => None,
                };
                match gap {
                    Some(c) if !dropped.contains(&c) => dropped.push(c),
                    _ => return Err(e),
                }
            }
            Ok(t) => return Ok(t),
        }
    }
}

fn columns_dict<'py>(
    py: Python<'py>,
    t: nlsdof_io::table_file::Table,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (n, c) in t.names.into_iter().zip(t.columns) {
        d.set_item(n, PyArray1::from_vec(py, c))?;
    }
    Ok(d)
}

/// Reads a LabVIEW measurement file (`.lvm`, text): everything up to the
/// second `***End_of_Header***` line is skipped, then the tab-separated
/// column names and rows. Returns a dict of float64 numpy arrays keyed by
/// column name, in file order; `X_Value` is the time column (s).
///
/// `columns`: names (case-insensitive) or 0-based indices of the columns
/// to read (as `nlsdof decay --column`); by default every named column
/// with a number on every row — channels that end early (LabVIEW's
/// one-sample channels) and an empty `Comment` column are left out. A
/// field that is not a number is a ``ValueError`` naming the file, line
/// and column. Any delimited text table (CSV, Polytec ASCII) reads the
/// same way.
///
/// >>> import nlsdof
/// >>> d = nlsdof.read_lvm("../shared/data/magnetomechanical-sdof-decay-frid/decay_f_42p05_ampl_2p0_0.lvm", columns=["X_Value", "Strain_0"])
/// >>> sorted(d), len(d["X_Value"]), float(d["X_Value"][1])
/// (['Strain_0', 'X_Value'], 29000, 0.001)
#[pyfunction]
#[pyo3(signature = (path, columns=None))]
pub fn read_lvm<'py>(
    py: Python<'py>,
    path: PathBuf,
    columns: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let t = py
        .detach(|| table_columns(&path, columns))
        .map_err(value_error)?;
    columns_dict(py, t)
}

/// Reads a Polytec ASCII time export (`.txt` starting `Source File
/// Name`, one channel per file; the beam impact records): returns a dict
/// with the time column ``"t"`` (s) and the channel under the name of its
/// `Signal:` line (e.g. ``"Ref1 Force"``, N, or ``"Vib Velocity"``, m/s),
/// the name `frf_estimate` accepts as `input_channel`. The sampling must
/// be uniform (steps equal within 1e-3 of a step); ``fs = 1 /
/// (t[1] - t[0])``.
///
/// >>> import nlsdof
/// >>> d = nlsdof.read_polytec("../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_impact/mec-t1-force.txt")
/// >>> list(d), len(d["t"]), round(float(d["Ref1 Force"][1]), 5)
/// (['t', 'Ref1 Force'], 100000, 24.79215)
#[pyfunction]
pub fn read_polytec<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let is_polytec = std::fs::File::open(&path)
        .and_then(|f| {
            let mut head = [0u8; 19];
            let n = std::io::Read::read(&mut std::io::Read::take(f, 19), &mut head)?;
            Ok(head[..n]
                .strip_prefix(b"\xef\xbb\xbf")
                .unwrap_or(&head[..n])
                .starts_with(b"Source File Name"))
        })
        .map_err(|source| {
            value_error(nlsdof_io::frf_file::FrfFileError::Read {
                path: path.clone(),
                source,
            })
        })?;
    if !is_polytec {
        return Err(value_error(format!(
            "{}: not a Polytec ASCII export (the first line does not start with \"Source File Name\"); read tables with read_lvm",
            path.display()
        )));
    }
    // the file is read once: the channel and the time column are parsed
    // from the same text (read_time_history and read_columns each read it)
    let (th, t) = py.detach(|| {
        let text = nlsdof_io::text::read_text(&path).map_err(|e| {
            value_error(match e {
                nlsdof_io::text::TextFileError::Read(source) => {
                    nlsdof_io::frf_file::FrfFileError::Read {
                        path: path.clone(),
                        source,
                    }
                }
                e => nlsdof_io::frf_file::FrfFileError::Content {
                    path: path.clone(),
                    message: e.to_string(),
                },
            })
        })?;
        let th = parse_time_history(&text, &path, None).map_err(value_error)?;
        let t = parse_columns(text.as_bytes(), &path, &["0"]).map_err(value_error)?;
        Ok::<_, PyErr>((th, t))
    })?;
    let d = PyDict::new(py);
    let t = t.columns.into_iter().next().unwrap_or_default();
    let (name, v) = th.channels.into_iter().next().unwrap_or_default();
    if t.len() != v.len() {
        return Err(value_error(format!(
            "{}: {} times but {} samples",
            path.display(),
            t.len(),
            v.len()
        )));
    }
    d.set_item("t", PyArray1::from_vec(py, t))?;
    d.set_item(name, PyArray1::from_vec(py, v))?;
    Ok(d)
}

/// Reads a Polytec swept-sine FRF export (tab-separated, decimal comma;
/// the beam `frf_<A>g.txt` files, as `nlsdof fit --beam-dir` does): a list
/// of runs (run 1, and run 2 if present), each a dict of numpy arrays
/// ``f_hz`` (Hz), ``amplitude`` (as exported: the header names the unit,
/// m/s for the beam's laser velocity) and ``phase_deg`` (degrees).
///
/// >>> import nlsdof
/// >>> runs = nlsdof.read_polytec_sweep("../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C/frf_0.04g.txt")
/// >>> len(runs), sorted(runs[0])
/// (2, ['amplitude', 'f_hz', 'phase_deg'])
#[pyfunction]
pub fn read_polytec_sweep<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyList>> {
    let runs = py
        .detach(|| io_read_polytec_sweep(&path))
        .map_err(value_error)?;
    let l = PyList::empty(py);
    for r in runs {
        let d = PyDict::new(py);
        d.set_item("f_hz", PyArray1::from_vec(py, r.f_hz))?;
        d.set_item("amplitude", PyArray1::from_vec(py, r.amplitude))?;
        d.set_item("phase_deg", PyArray1::from_vec(py, r.phase_deg))?;
        l.append(d)?;
    }
    Ok(l)
}

/// Reads the numeric arrays of a MATLAB MAT v5 file (as saved by
/// ``save(FILE, ..., '-v7')``; compressed or not): a dict of numpy arrays
/// keyed by variable name, float64 whatever the stored class, each with its MATLAB shape (at least 2-D,
/// as ``scipy.io.loadmat`` gives). `variables` chooses some by name
/// (missing ones are a ``ValueError`` listing the file's). Complex arrays
/// are a ``ValueError`` when asked for and left out otherwise; non-numeric
/// variables (cells, structs, strings) are skipped. MAT v4 and v7.3 (HDF5)
/// files are refused with a hint.
///
/// >>> import nlsdof
/// >>> d = nlsdof.read_mat("../shared/data/silverbox/SNLS80mV.mat")
/// >>> sorted(d), d["V1"].shape, d["V1"].dtype
/// (['Ovld1', 'Ovld2', 'V1', 'V2'], (1, 131072), dtype('float64'))
#[pyfunction]
#[pyo3(signature = (path, variables=None))]
pub fn read_mat<'py>(
    py: Python<'py>,
    path: PathBuf,
    variables: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let arrays = py
        .detach(|| {
            nlsdof_io::mat5::read(&path)
                .map_err(|source| SignalFileError::Read {
                    path: path.clone(),
                    source,
                })?
                .map_err(|source| SignalFileError::Mat {
                    path: path.clone(),
                    source,
                })
        })
        .map_err(value_error)?;
    let chosen: Vec<&nlsdof_io::mat5::MatArray> = match &variables {
        None => arrays.iter().filter(|a| !a.complex).collect(),
        Some(names) => {
            let mut v = Vec::with_capacity(names.len());
            for n in names {
                let Some(a) = arrays.iter().find(|a| &a.name == n) else {
                    let found: Vec<String> = arrays
                        .iter()
                        .map(|a| format!("{}{:?}", a.name, a.dims))
                        .collect();
                    return Err(value_error(format!(
                        "{}: no numeric variable {n:?} (variables: {})",
                        path.display(),
                        found.join(", ")
                    )));
                };
                if a.complex {
                    return Err(value_error(format!(
                        "{}: variable {n:?} is complex: only real arrays are read",
                        path.display()
                    )));
                }
                v.push(a);
            }
            v
        }
    };
    let np = py.import("numpy")?;
    let d = PyDict::new(py);
    for a in chosen {
        let flat = PyArray1::from_vec(py, a.real.clone());
        let dims: Vec<usize> = if a.dims.is_empty() {
            vec![1, 1]
        } else {
            a.dims.clone()
        };
        // MATLAB stores column-major
        let shaped = np.call_method(
            "reshape",
            (flat, dims),
            Some(&[("order", "F")].into_py_dict(py)?),
        )?;
        d.set_item(&a.name, shaped)?;
    }
    Ok(d)
}
