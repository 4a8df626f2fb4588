//! Linear identification from an FRF (paper §2.3, Table 3) and STFT
//! spectrograms with their comparison (paper §4.5, Eq 33).

use crate::arrays::{f64_array, values};
use crate::convert::{to_py, value_error};
use nlsdof::signal_processing::stft::{Detrend, Scaling, StftOptions};
use nlsdof::signal_processing::{compare_records, ComparisonOptions, Symmetry, Window};
use nlsdof::vector_fitting::{
    identify_sdof, FrfWeighting, InputKind, MeasuredFrf, OutputKind, PoleCount, SdofIdOptions, C64,
};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use std::f64::consts::TAU;

/// Identifies the linear part of an SDoF from a measured FRF by fast
/// relaxed vector fitting, with the half-power and circle-fit estimates
/// (as `nlsdof linear-id --json`). `f_hz`: frequencies (Hz); `frf`: the
/// complex FRF (or its magnitude only: then the half-power method);
/// `input`: "acceleration" (base, m/s^2: only k/m and c/m unless `mass`)
/// or "force" (N); `output`: "displacement", "velocity" or "acceleration";
/// `poles`: number of complex pole pairs or "auto". Returns the document
/// (dict): `sdof` holds alpha = k/m (1/s^2), delta = c/m (1/s), f_n_hz,
/// zeta and, when the mass is known, m, k, c.
///
/// >>> import numpy as np, nlsdof
/// >>> f = np.linspace(5.0, 15.0, 201); w = 2 * np.pi * f
/// >>> h = 1 / ((2 * np.pi * 10) ** 2 - w**2 + 2j * w)  # f_n 10 Hz, delta 2 1/s
/// >>> r = nlsdof.linear_id(f, h)
/// >>> round(r["sdof"]["f_n_hz"], 6), round(r["sdof"]["delta"], 6)
/// (10.0, 2.0)
#[pyfunction]
#[pyo3(signature = (f_hz, frf, input="acceleration", output="displacement", mass=None, poles=None, max_poles=20, f_min=None, f_max=None, mode=None, constant=true, proportional=false, weight="uniform", max_iterations=30))]
#[allow(clippy::too_many_arguments)]
pub fn linear_id<'py>(
    py: Python<'py>,
    f_hz: &Bound<'py, PyAny>,
    frf: &Bound<'py, PyAny>,
    input: &str,
    output: &str,
    mass: Option<f64>,
    poles: Option<&Bound<'py, PyAny>>,
    max_poles: usize,
    f_min: Option<f64>,
    f_max: Option<f64>,
    mode: Option<usize>,
    constant: bool,
    proportional: bool,
    weight: &str,
    max_iterations: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let f = f64_array(f_hz, "f_hz")?;
    let f: Vec<f64> = values(&f).into_owned();
    let np = py.import("numpy")?;
    let complex: bool = np.call_method1("iscomplexobj", (frf,))?.extract()?;
    let measured = if complex {
        let re = f64_array(&np.call_method1("real", (frf,))?, "frf")?;
        let im = f64_array(&np.call_method1("imag", (frf,))?, "frf")?;
        let h: Vec<C64> = values(&re)
            .iter()
            .zip(values(&im).iter())
            .map(|(&a, &b)| C64::new(a, b))
            .collect();
        MeasuredFrf::complex(f.iter().map(|f| TAU * f).collect(), h)
    } else {
        let m = f64_array(frf, "frf")?;
        MeasuredFrf {
            omega: f.iter().map(|f| TAU * f).collect(),
            magnitude: values(&m).into_owned(),
            values: None,
        }
    };
    if measured.magnitude.len() != f.len() {
        return Err(value_error(format!(
            "frf has {} values but f_hz has {}",
            measured.magnitude.len(),
            f.len()
        )));
    }
    let poles = match poles {
        None => PoleCount::Auto {
            max_pairs: max_poles,
        },
        Some(p) => match p.extract::<usize>() {
            Ok(n) if n >= 1 => PoleCount::Fixed(n),
            _ => match p.extract::<String>() {
                Ok(s) if s.eq_ignore_ascii_case("auto") => PoleCount::Auto {
                    max_pairs: max_poles,
                },
                _ => {
                    return Err(value_error(
                        "poles: expected a number of pole pairs >= 1 or \"auto\"",
                    ))
                }
            },
        },
    };
    let (lo, hi) = (
        f_min.unwrap_or(f64::NEG_INFINITY),
        f_max.unwrap_or(f64::INFINITY),
    );
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return Err(value_error(format!(
            "f_min {lo} / f_max {hi}: need f_min < f_max"
        )));
    }
    if max_iterations == 0 || max_iterations > 10_000 {
        return Err(value_error(format!(
            "max_iterations {max_iterations}: need 1 to 10000 vector-fitting iterations"
        )));
    }
    let opts = SdofIdOptions {
        band: (TAU * lo, TAU * hi),
        poles,
        input: match input.to_ascii_lowercase().as_str() {
            "force" => InputKind::Force,
            "acceleration" => InputKind::Acceleration,
            _ => {
                return Err(value_error(format!(
                    "input {input:?} is not allowed: use \"force\" or \"acceleration\""
                )))
            }
        },
        output: match output.to_ascii_lowercase().as_str() {
            "displacement" => OutputKind::Displacement,
            "velocity" => OutputKind::Velocity,
            "acceleration" => OutputKind::Acceleration,
            _ => {
                return Err(value_error(format!(
                    "output {output:?} is not allowed: use \"displacement\", \"velocity\" or \"acceleration\""
                )))
            }
        },
        mass,
        mode,
        constant,
        proportional,
        weighting: match weight.to_ascii_lowercase().as_str() {
            "uniform" => FrfWeighting::Uniform,
            "inverse" => FrfWeighting::Inverse,
            _ => {
                return Err(value_error(format!(
                    "weight {weight:?} is not allowed: use \"uniform\" or \"inverse\""
                )))
            }
        },
        max_iterations,
        cancel: nlsdof::cancel::Cancel::NEVER,
    };
    if let Some(m) = mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(value_error(format!("mass {m}: must be finite and > 0 kg")));
        }
    }
    // Ctrl-C stops it (KeyboardInterrupt): the flag is polled before each
    // vector-fitting relocation and residue solve
    let id = crate::interrupt::run(py, None, "linear_id", |cancel, _| {
        let opts = SdofIdOptions {
            cancel,
            ..opts.clone()
        };
        identify_sdof(&measured, &opts)
    })?
    .map_err(value_error)?;
    let used: Vec<f64> = id.points.iter().map(|&i| f[i]).collect();
    let out = to_py(py, &nlsdof_report::linear_id::json(&id, &used))?;
    // beyond the CLI's document: what its figure draws (nlsdof.plot.linear_id)
    let d = out.cast::<pyo3::types::PyDict>()?;
    d.set_item(
        "frf_unit",
        nlsdof_report::linear_id::frf_unit(opts.input, opts.output),
    )?;
    d.set_item(
        "mobility_unit",
        nlsdof_report::linear_id::frf_unit(opts.input, OutputKind::Velocity),
    )?;
    d.set_item("output_power", opts.output.power())?;
    d.set_item("f_hz", PyArray1::from_vec(py, used.clone()))?;
    let h: Vec<numpy::Complex64> = match &id.values {
        Some(v) => v
            .iter()
            .map(|z| numpy::Complex64::new(z.re, z.im))
            .collect(),
        None => id
            .magnitude
            .iter()
            .map(|&m| numpy::Complex64::new(m, f64::NAN))
            .collect(),
    };
    d.set_item("frf", PyArray1::from_vec(py, h))?;
    if let (Some(fit), Some(&f0), Some(&f1)) = (&id.fit, used.first(), used.last()) {
        let grid: Vec<f64> = (0..=800)
            .map(|i| f0 + (f1 - f0) * i as f64 / 800.0)
            .collect();
        let curve: Vec<numpy::Complex64> = grid
            .iter()
            .map(|&f| {
                let z = fit.eval(TAU * f);
                numpy::Complex64::new(z.re, z.im)
            })
            .collect();
        d.set_item("fit_f_hz", PyArray1::from_vec(py, grid))?;
        d.set_item("fit_frf", PyArray1::from_vec(py, curve))?;
    }
    crate::document::report(out, "linear_id")
}

/// An STFT spectrogram: `times` (s, segment centres), `frequencies` (Hz)
/// and `magnitude`, a numpy array of shape (len(times), len(frequencies)).
#[pyclass(frozen, name = "Spectrogram", module = "nlsdof")]
pub struct Spectrogram {
    #[pyo3(get)]
    times: Py<PyArray1<f64>>,
    #[pyo3(get)]
    frequencies: Py<PyArray1<f64>>,
    #[pyo3(get)]
    magnitude: Py<PyAny>,
    shape: (usize, usize),
}

#[pymethods]
impl Spectrogram {
    /// Jupyter: the time and frequency ranges (s, Hz) and the largest
    /// magnitude.
    fn _repr_html_(&self, py: Python<'_>) -> PyResult<String> {
        use numpy::PyArrayMethods;
        let range = |a: &Py<PyArray1<f64>>| -> PyResult<String> {
            let r = a.bind(py).readonly();
            let v = r.as_array();
            Ok(match (v.first(), v.last()) {
                (Some(a), Some(b)) => format!("{a} .. {b}"),
                _ => "&mdash;".into(),
            })
        };
        let peak: f64 = self
            .magnitude
            .bind(py)
            .call_method0("max")
            .and_then(|m| m.extract())
            .unwrap_or(f64::NAN);
        Ok(format!(
            "<div><b>nlsdof Spectrogram</b> &mdash; {} times x {} frequencies<table>\
             <tr><th>quantity</th><th>value</th><th>unit</th></tr>\
             <tr><td>times (segment centres)</td><td>{}</td><td>s</td></tr>\
             <tr><td>frequencies</td><td>{}</td><td>Hz</td></tr>\
             <tr><td>max magnitude</td><td>{peak:.6e}</td><td>input unit</td></tr>\
             </table></div>",
            self.shape.0,
            self.shape.1,
            range(&self.times)?,
            range(&self.frequencies)?
        ))
    }

    /// The magnitude in dB over time (s) and frequency (Hz) as the CLI's
    /// `spectrogram --plot` draws it (matplotlib; `nlsdof.plot.spectrogram`):
    /// `ax=None` draws a new figure. Returns the Axes.
    #[pyo3(signature = (ax=None))]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        slf.py()
            .import("nlsdof.plot")?
            .call_method1("spectrogram", (slf, ax))
    }
    fn __repr__(&self) -> String {
        format!(
            "Spectrogram({} times x {} frequencies)",
            self.shape.0, self.shape.1
        )
    }
}

#[allow(clippy::too_many_arguments)]
fn stft_options(
    n: usize,
    fs: f64,
    segments: usize,
    overlap: f64,
    window: &str,
    periodic: bool,
    nfft: Option<usize>,
    detrend: &str,
    scaling: &str,
) -> PyResult<StftOptions> {
    if segments == 0 {
        return Err(value_error(
            "segments 0 is not allowed: give S >= 1 (L = floor(N/S))",
        ));
    }
    let mut o = StftOptions::with_segments(n, fs, segments);
    o.window = match window.to_ascii_lowercase().as_str() {
        "hamming" => Window::Hamming,
        "hann" => Window::Hann,
        "blackman" => Window::Blackman,
        "rectangular" => Window::Rectangular,
        _ => {
            return Err(value_error(format!(
                "window {window:?} is not allowed: use hamming, hann, blackman or rectangular"
            )))
        }
    };
    o.symmetry = if periodic {
        Symmetry::Periodic
    } else {
        Symmetry::Symmetric
    };
    o.overlap = overlap;
    o.nfft = nfft;
    o.detrend = match detrend.to_ascii_lowercase().as_str() {
        "none" => Detrend::None,
        "constant" => Detrend::Constant,
        _ => {
            return Err(value_error(format!(
                "detrend {detrend:?} is not allowed: use \"none\" or \"constant\""
            )))
        }
    };
    o.scaling = match scaling.to_ascii_lowercase().as_str() {
        "amplitude" => Scaling::Amplitude,
        "psd" => Scaling::Psd,
        _ => {
            return Err(value_error(format!(
                "scaling {scaling:?} is not allowed: use \"amplitude\" or \"psd\""
            )))
        }
    };
    Ok(o)
}

/// The STFT spectrogram of `x` sampled at `fs` Hz (as `nlsdof
/// spectrogram`): segments of L = floor(N / `segments`) samples with
/// `overlap` (fraction of L), a symmetric Hamming window by default (the
/// paper's), `scaling` "amplitude" (a sine of amplitude A on a bin reads A)
/// or "psd"; restricted to [`f_min`, `f_max`] Hz when given.
///
/// >>> import numpy as np, nlsdof
/// >>> t = np.arange(3000) / 100.0
/// >>> s = nlsdof.spectrogram(2.0 * np.sin(2 * np.pi * 5.0 * t), fs=100.0, segments=10, window="hann", periodic=True)
/// >>> s, round(float(s.magnitude.max()), 3)
/// (Spectrogram(19 times x 151 frequencies), 2.0)
#[pyfunction]
#[pyo3(signature = (x, fs, segments=15, overlap=0.5, window="hamming", periodic=false, nfft=None, detrend="none", scaling="amplitude", f_min=None, f_max=None))]
#[allow(clippy::too_many_arguments)]
pub fn spectrogram<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    fs: f64,
    segments: usize,
    overlap: f64,
    window: &str,
    periodic: bool,
    nfft: Option<usize>,
    detrend: &str,
    scaling: &str,
    f_min: Option<f64>,
    f_max: Option<f64>,
) -> PyResult<Spectrogram> {
    let a = f64_array(x, "x")?;
    let x = values(&a);
    let stft = stft_options(
        x.len(),
        fs,
        segments,
        overlap,
        window,
        periodic,
        nfft,
        detrend,
        scaling,
    )?;
    let mut opts = ComparisonOptions {
        band: (f_min, f_max),
        ..ComparisonOptions::new(stft)
    };
    // Ctrl-C stops it (KeyboardInterrupt): the flag is polled before each
    // segment
    let cmp = crate::interrupt::run(py, None, "spectrogram", |cancel, _| {
        opts.cancel = cancel;
        compare_records(&x, None, &opts)
    })?
    .map_err(value_error)?;
    let s = cmp.measured;
    let (nt, nf) = (s.n_time, s.n_freq);
    let magnitude = PyArray1::from_vec(py, s.magnitude).reshape([nt, nf])?;
    Ok(Spectrogram {
        times: PyArray1::from_vec(py, s.times).unbind(),
        frequencies: PyArray1::from_vec(py, s.frequencies).unbind(),
        magnitude: magnitude.into_any().unbind(),
        shape: (nt, nf),
    })
}

/// Compares the spectrograms of `measured` and `model` (same length and
/// sampling `fs` Hz) by the paper's Eq 33, `max |s_exp - s_num| / s_exp`
/// in %, and its robust variant over the bins with `s_exp >= floor x max`;
/// returns the `compare` block of `nlsdof spectrogram --compare --json`.
///
/// >>> import numpy as np, nlsdof
/// >>> x = np.sin(2 * np.pi * 5.0 * np.arange(3000) / 100.0)
/// >>> c = nlsdof.compare_spectrograms(x, 1.01 * x, fs=100.0)
/// >>> round(c["eq33_max_relative_percent"], 6)
/// 1.0
#[pyfunction]
#[pyo3(signature = (measured, model, fs, segments=15, overlap=0.5, window="hamming", periodic=false, nfft=None, detrend="none", scaling="amplitude", f_min=None, f_max=None, floor=0.01))]
#[allow(clippy::too_many_arguments)]
pub fn compare_spectrograms<'py>(
    py: Python<'py>,
    measured: &Bound<'py, PyAny>,
    model: &Bound<'py, PyAny>,
    fs: f64,
    segments: usize,
    overlap: f64,
    window: &str,
    periodic: bool,
    nfft: Option<usize>,
    detrend: &str,
    scaling: &str,
    f_min: Option<f64>,
    f_max: Option<f64>,
    floor: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let a = f64_array(measured, "measured")?;
    let b = f64_array(model, "model")?;
    let (x, y) = (values(&a), values(&b));
    if x.len() != y.len() {
        return Err(value_error(format!(
            "measured has {} samples but model has {}: the comparison needs records of the same length",
            x.len(),
            y.len()
        )));
    }
    if !(0.0..=1.0).contains(&floor) {
        return Err(value_error(format!(
            "floor {floor} must be a fraction in [0, 1] of the measured maximum"
        )));
    }
    let stft = stft_options(
        x.len(),
        fs,
        segments,
        overlap,
        window,
        periodic,
        nfft,
        detrend,
        scaling,
    )?;
    let layout = stft.layout(x.len()).map_err(value_error)?;
    let mut opts = ComparisonOptions {
        band: (f_min, f_max),
        floor_fraction: floor,
        ..ComparisonOptions::new(stft)
    };
    // Ctrl-C stops it (KeyboardInterrupt), as `spectrogram`
    let cmp = crate::interrupt::run(py, None, "compare_spectrograms", |cancel, _| {
        opts.cancel = cancel;
        compare_records(&x, Some(&y), &opts)
    })?
    .map_err(value_error)?;
    let run = nlsdof_report::spectrogram::SpectrogramRun {
        label: "measured",
        input: "measured",
        column: "measured",
        compare: Some(("model", "model")),
        fs,
        t0: 0.0,
        samples: x.len(),
        options: &opts.stft,
        layout: &layout,
        measured: &cmp.measured,
        difference: cmp.difference.as_ref(),
        floor,
    };
    let doc = nlsdof_report::spectrogram::json(&run, serde_json::Value::Null, (0.0, 0.0, 0.0));
    to_py(py, &doc["compare"])
}
