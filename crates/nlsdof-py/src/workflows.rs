//! The CLI's workflows `frf-estimate`, `compare` and `signal` as Python
//! functions with the same options, defaults and documents; each calls the
//! library function the verb calls.

use crate::arrays::{f64_array, values};
use crate::convert::{to_py, value_error};
use nlsdof::identification::compare::{
    compare_plans, parse_models, CompareError, CompareOptions, DEFAULT_MODELS,
};
use nlsdof::identification::{identify, Identification, SignChoice};
use nlsdof::signal_generator::{build, ChirpKind, SignalSpec};
use nlsdof::signal_processing::frf_estimate::parse_window;
use nlsdof::signal_processing::{estimate_frf, FrfEstimateOptions, FrfMethod, Symmetry};
use numpy::{Complex64, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A channel given as a path (read) or as an array of samples.
enum Channel {
    File(PathBuf),
    Samples(Vec<f64>),
}

fn channel(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Channel> {
    if obj.is_instance_of::<pyo3::types::PyString>() || obj.hasattr("__fspath__")? {
        return Ok(Channel::File(obj.extract::<PathBuf>()?));
    }
    let a = f64_array(obj, name)?;
    Ok(Channel::Samples(values(&a).into_owned()))
}

/// A list of names from a comma-separated string or a sequence of strings.
fn names(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<String>> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(s.split(',').map(str::to_string).collect());
    }
    obj.extract::<Vec<String>>().map_err(|_| {
        value_error(format!(
            "{what}: expected a comma-separated string or a list of names"
        ))
    })
}

/// Estimates an FRF from an input and an output time history (as
/// `nlsdof frf-estimate --json`): Welch H1 (default) or H2 with coherence,
/// or the spectral ratio ``"ratio"`` of one record (sine sweep, impact).
///
/// `input` and `output` are either arrays of samples (then `fs`, Hz, is
/// required) or files, read as the CLI reads them: CSV with a time column
/// or `fs`, Polytec ASCII export, MAT v5 or universal file, the channel
/// chosen by `input_channel` / `output_channel` (name or 1-based number;
/// the output defaults to channel 1 of `output`, or channel 2 of `input`
/// when `output` is None). `segment` (samples, default min(4096, N)),
/// `overlap`, `window` ("hann", "hamming", "blackman", "rectangular") and
/// `symmetric_window` set the Welch averaging; only lines with input power
/// in [`f_min`, `f_max`] Hz (DC left out) are kept. `out` writes the FRF
/// CSV (`f_hz,re,im,mag,phase_deg[,coherence]`) that `linear-id` reads.
///
/// Returns the CLI's document (`method`, `fs`, `samples`, `segment`,
/// `averages`, `resolution_hz`, `lines`, `mean_coherence`, `window`,
/// `window_form`, `out`) and the estimate as numpy arrays: `f_hz` (Hz),
/// `frf` (complex, output unit per input unit) and `coherence` (None for
/// the ratio).
///
/// >>> import numpy as np, nlsdof
/// >>> rng = np.random.default_rng(1)
/// >>> x = rng.standard_normal(8192)
/// >>> r = nlsdof.frf_estimate(x, 2.0 * x, fs=1000.0, segment=1024, f_max=200.0)
/// >>> r["method"], r["averages"], r["lines"], bool(np.allclose(r["frf"], 2.0))
/// ('h1', 15, 204, True)
#[pyfunction]
#[pyo3(signature = (input, output=None, *, fs=None, input_channel="1", output_channel=None, method="h1", segment=None, overlap=0.5, window="hann", symmetric_window=false, f_min=None, f_max=None, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn frf_estimate<'py>(
    py: Python<'py>,
    input: &Bound<'py, PyAny>,
    output: Option<&Bound<'py, PyAny>>,
    fs: Option<f64>,
    input_channel: &str,
    output_channel: Option<&str>,
    method: &str,
    segment: Option<usize>,
    overlap: f64,
    window: &str,
    symmetric_window: bool,
    f_min: Option<f64>,
    f_max: Option<f64>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let method = FrfMethod::parse(method).ok_or_else(|| {
        value_error(format!(
            "method {method:?} is not allowed: use \"h1\", \"h2\" or \"ratio\""
        ))
    })?;
    let window_kind = parse_window(window).ok_or_else(|| {
        value_error(format!(
            "window {window:?} is not allowed: use hann, hamming, blackman or rectangular"
        ))
    })?;
    let input = channel(input, "input")?;
    let output = output.map(|o| channel(o, "output")).transpose()?;
    let (fs, x, y) = match (input, output) {
        (Channel::Samples(x), Some(Channel::Samples(y))) => {
            let Some(fs) = fs else {
                return Err(value_error(
                    "fs: the sampling frequency (Hz) is needed with arrays of samples",
                ));
            };
            (fs, x, y)
        }
        (Channel::File(p), o) => {
            let of = match o {
                None => None,
                Some(Channel::File(q)) => Some(q),
                Some(Channel::Samples(_)) => {
                    return Err(value_error(
                        "output: give a file when input is a file (or arrays for both)",
                    ))
                }
            };
            py.detach(|| {
                nlsdof_io::frf_file::read_channel_pair(
                    &p,
                    input_channel,
                    of.as_deref(),
                    output_channel,
                    fs,
                )
            })
            .map_err(value_error)?
        }
        (Channel::Samples(_), _) => {
            return Err(value_error(
                "output: give the output samples (an array) with input samples",
            ))
        }
    };
    let opts = FrfEstimateOptions {
        method,
        segment,
        overlap,
        window: window_kind,
        symmetry: if symmetric_window {
            Symmetry::Symmetric
        } else {
            Symmetry::Periodic
        },
        f_min,
        f_max,
    };
    let e = py
        .detach(|| estimate_frf(fs, &x, &y, &opts))
        .map_err(value_error)?;
    if let Some(p) = &out {
        let hk: Vec<(f64, f64)> = e.h.iter().map(|h| (h.re, h.im)).collect();
        nlsdof_io::frf_file::write_frf_csv(p, &e.frequency_hz, &hk, e.coherence.as_deref())
            .map_err(value_error)?;
    }
    let out_s = out.as_ref().map(|p| p.display().to_string());
    let doc = to_py(py, &nlsdof_report::frf_estimate::json(&e, out_s.as_deref()))?;
    let d = doc.cast::<PyDict>()?;
    d.set_item("f_hz", PyArray1::from_vec(py, e.frequency_hz.clone()))?;
    let h: Vec<Complex64> = e.h.iter().map(|h| Complex64::new(h.re, h.im)).collect();
    d.set_item("frf", PyArray1::from_vec(py, h))?;
    match e.coherence {
        Some(c) => d.set_item("coherence", PyArray1::from_vec(py, c))?,
        None => d.set_item("coherence", py.None())?,
    }
    crate::document::report(doc, "frf_estimate")
}

/// Fits several models to one stepped-sine data set (as `nlsdof compare
/// --json`, paper Tables 5–7): each model through the pipeline of `fit`.
/// `models`: comma-separated names or a list (None: the CLI's default,
/// linear, duffing, duffing-quadratic, duffing-generalised, generalised);
/// `free`: parameters to estimate although a model holds them (e.g.
/// "gain"; one a model does not have is not freed for it); `starts`,
/// `seed`, `sign` and `mass` (kg, physical values in the document) as
/// `fit`. Returns ``{"models": [document, ...]}``, each the document of
/// `fit(...).to_dict()`. Ctrl-C stops it; `progress` as `fit`.
///
/// >>> import numpy as np, nlsdof
/// >>> wing = nlsdof.Model.from_toml("examples/har-wing.toml")
/// >>> f = np.linspace(5.3, 5.5, 25)
/// >>> data = {"level": ["1"] * 25, "gamma": [0.41] * 25, "f_hz": f,
/// ...         "amplitude": wing.sweep(0.41, f).amplitude}
/// >>> r = nlsdof.compare(data, models="linear,duffing")
/// >>> [(m["model"], m["converged"]) for m in r["models"]]
/// [('linear', True), ('duffing', True)]
#[pyfunction]
#[pyo3(signature = (data, models=None, *, free=None, starts=None, seed=1, mass=None, sign="data", progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn compare<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    models: Option<&Bound<'py, PyAny>>,
    free: Option<&Bound<'py, PyAny>>,
    starts: Option<usize>,
    seed: u64,
    mass: Option<f64>,
    sign: &str,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let list = match models {
        None => DEFAULT_MODELS.to_string(),
        Some(m) => names(m, "models")?.join(","),
    };
    let kinds = parse_models(&list).map_err(value_error)?;
    let starts = starts.unwrap_or(1);
    if starts == 0 || starts > 100_000 {
        return Err(value_error(format!(
            "starts {starts} is not allowed: use 1..=100000"
        )));
    }
    if let Some(m) = mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(value_error(format!(
                "mass {m} is not allowed: the mass must be finite and > 0 (kg)"
            )));
        }
    }
    let sign = match sign.to_ascii_lowercase().as_str() {
        // one to one with the CLI's --sign data|hardening|softening|auto
        "data" => SignChoice::Auto,
        "auto" => SignChoice::Both,
        "hardening" => SignChoice::Hardening,
        "softening" => SignChoice::Softening,
        _ => {
            return Err(value_error(format!(
                "sign {sign:?} is not allowed: use \"data\", \"hardening\", \"softening\" or \"auto\" (both signs)"
            )))
        }
    };
    let (data, _) = crate::fit::dataset(data)?;
    let opts = CompareOptions {
        free: free
            .map(|f| names(f, "free"))
            .transpose()?
            .unwrap_or_default(),
        starts,
        seed,
        sign,
    };
    let plans = compare_plans(&data, &kinds, &opts).map_err(value_error)?;
    let ids: Vec<Identification> =
        crate::interrupt::run(py, progress, "compare", |cancel, rep| {
            plans
                .into_iter()
                .map(|mut plan| {
                    plan.lm.cancel = cancel;
                    let kind = plan.kind;
                    identify(&data, &plan, &|p| rep.identify(p))
                        .map_err(|source| CompareError::Fit { kind, source })
                })
                .collect::<Result<Vec<_>, _>>()
        })?
        .map_err(value_error)?;
    let docs = ids
        .iter()
        .map(|id| nlsdof_report::fit::identification_document(id, mass))
        .collect::<Result<Vec<_>, _>>()
        .map_err(value_error)?;
    crate::document::report(
        to_py(py, &serde_json::json!({ "models": docs }))?,
        "compare",
    )
}

/// Most samples `signal` returns (two float64 arrays of 0.8 GB each); the
/// CLI streams up to 1e10 to a file.
const MAX_PY_SAMPLES: u64 = 100_000_000;

/// Makes an input acceleration (as `nlsdof signal KIND`): `kind` "sine"
/// (`freq`, `duration`, `phase_deg`), "chirp" (`chirp_kind` "linear" with
/// two of `f1`, `rate`, `duration`, or "log" with `f1` and `duration`;
/// the CLI's `chirp --kind`) or "stepped-sine" (`f_min`, `f_max`, `steps`,
/// `sweep`, and `dwell_cycles` or `dwell` s). `amplitude` m/s^2
/// zero-to-peak, frequencies Hz, `fs` Hz; samples at t = k/fs from 0 to
/// the duration, both ends included (at most 1e8 samples here). `out`
/// writes the CLI's CSV `t,accel`. Returns ``{"t": ..., "accel": ...}``
/// (numpy arrays, s and m/s^2).
///
/// >>> import nlsdof
/// >>> s = nlsdof.signal("sine", amplitude=2.0, fs=100.0, freq=5.0, duration=1.0)
/// >>> len(s["t"]), round(float(s["accel"][5]), 12)
/// (101, 2.0)
#[pyfunction]
#[pyo3(signature = (kind, *, amplitude, fs, freq=None, duration=None, phase_deg=0.0, chirp_kind="linear", f0=None, f1=None, rate=None, f_min=None, f_max=None, steps=None, sweep="up", dwell_cycles=None, dwell=None, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn signal<'py>(
    py: Python<'py>,
    kind: &str,
    amplitude: f64,
    fs: f64,
    freq: Option<f64>,
    duration: Option<f64>,
    phase_deg: f64,
    chirp_kind: &str,
    f0: Option<f64>,
    f1: Option<f64>,
    rate: Option<f64>,
    f_min: Option<f64>,
    f_max: Option<f64>,
    steps: Option<usize>,
    sweep: &str,
    dwell_cycles: Option<u32>,
    dwell: Option<f64>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let need = |v: Option<f64>, name: &str| {
        v.ok_or_else(|| value_error(format!("signal {kind:?} needs {name}")))
    };
    let spec = match kind.to_ascii_lowercase().replace('_', "-").as_str() {
        "sine" => SignalSpec::Sine {
            amplitude,
            freq: need(freq, "freq (Hz)")?,
            duration: need(duration, "duration (s)")?,
            phase_deg,
        },
        "chirp" => SignalSpec::Chirp {
            amplitude,
            kind: match chirp_kind.to_ascii_lowercase().as_str() {
                "linear" => ChirpKind::Linear,
                "log" => ChirpKind::Log,
                _ => {
                    return Err(value_error(format!(
                        "chirp_kind {chirp_kind:?} is not allowed: use \"linear\" or \"log\""
                    )))
                }
            },
            f0: need(f0, "f0 (Hz)")?,
            f1,
            rate,
            duration,
        },
        "stepped-sine" => SignalSpec::SteppedSine {
            amplitude,
            f_min: need(f_min, "f_min (Hz)")?,
            f_max: need(f_max, "f_max (Hz)")?,
            steps: steps.ok_or_else(|| value_error(format!("signal {kind:?} needs steps")))?,
            sweep: crate::convert::direction(sweep)?,
            dwell_cycles,
            dwell,
        },
        _ => {
            return Err(value_error(format!(
                "kind {kind:?} is not allowed: use \"sine\", \"chirp\" or \"stepped-sine\""
            )))
        }
    };
    let g = build(&spec, fs).map_err(value_error)?;
    if g.samples > MAX_PY_SAMPLES {
        return Err(value_error(format!(
            "{} samples is too many for arrays (duration {} s at {} Hz; at most {MAX_PY_SAMPLES}): write it with the CLI's `nlsdof signal`",
            g.samples, g.duration, g.fs
        )));
    }
    let (t, a): (Vec<f64>, Vec<f64>) = py.detach(|| (0..g.samples).map(|k| g.sample(k)).unzip());
    if let Some(p) = &out {
        py.detach(|| {
            let mut w = nlsdof_io::signal_file::CsvWriter::create(p, &["t", "accel"])?;
            for (t, a) in t.iter().zip(&a) {
                w.row(&[*t, *a])?;
            }
            w.commit()
        })
        .map_err(value_error)?;
    }
    let d = PyDict::new(py);
    d.set_item("t", PyArray1::from_vec(py, t))?;
    d.set_item("accel", PyArray1::from_vec(py, a))?;
    Ok(d)
}
