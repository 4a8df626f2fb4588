//! `nlsdof.fit` (the staged identification of paper §4, Eq 31, with the
//! equation-error start and the exponent landscape) and the stepped-sine
//! data it reads.

use crate::arrays::{f64_array, values};
use crate::convert::{to_py, value_error};
use nlsdof::identification::profile::OutputErrorProfile;
use nlsdof::identification::{
    identify, Dataset, FitPlan, GainChoice, Identification, JumpChoice, ModelKind, PhaseChoice,
    PhaseConvention, SignChoice, Status, Weighting, PARAM_NAMES,
};
use nlsdof::identification::{Parameter, Record};
use nlsdof_io::stepped_sine_data::{self as data_io, AmplitudeKind, Columns, ReadOptions, Runs};
use nlsdof_report::intervals::IntervalView;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use pyo3::PyTypeInfo;
use std::collections::HashMap;
use std::f64::consts::TAU;
use std::path::PathBuf;

/// Stepped-sine amplitude curves at several levels, as the fit reads them:
/// zero-to-peak SI displacement amplitudes (m), levels gamma (m/s^2),
/// frequencies (Hz), phase lags (deg) where measured. Made by
/// `read_stepped_sine`, `read_beam_dir`, or from columns by `fit`.
#[pyclass(frozen, name = "SteppedSineData", module = "nlsdof")]
#[derive(Clone)]
pub struct SteppedSineData {
    pub inner: Dataset,
    /// Where the data came from, as a fit's model file names it (None for
    /// columns).
    pub source: Option<String>,
}

impl SteppedSineData {
    fn column(&self, f: impl Fn(&nlsdof::identification::Curve, usize) -> f64) -> Vec<f64> {
        let mut v = Vec::new();
        for c in &self.inner.curves {
            for k in 0..c.omegas.len() {
                v.push(f(c, k));
            }
        }
        v
    }
}

#[pymethods]
impl SteppedSineData {
    /// Level label of every point.
    #[getter]
    fn level(&self) -> Vec<String> {
        let mut v = Vec::new();
        for c in &self.inner.curves {
            v.extend(std::iter::repeat_n(c.level.clone(), c.omegas.len()));
        }
        v
    }
    /// gamma of every point, m/s^2 zero-to-peak.
    #[getter]
    fn gamma<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.column(|c, _| c.gamma))
    }
    /// Frequency of every point, Hz.
    #[getter]
    fn f_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.column(|c, k| c.omegas[k] / TAU))
    }
    /// Displacement amplitude of every point, m zero-to-peak.
    #[getter]
    fn amplitude<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.column(|c, k| c.amplitudes[k]))
    }
    /// Phase lag of every point, deg (NaN where not measured).
    #[getter]
    fn phase_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(
            py,
            self.column(|c, k| c.phases.as_ref().map_or(f64::NAN, |p| p[k].to_degrees())),
        )
    }
    /// "up" or "down" for every point.
    #[getter]
    fn sweep(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        for c in &self.inner.curves {
            let d = nlsdof_report::steady_state::sweep_name(c.direction);
            v.extend(std::iter::repeat_n(d, c.omegas.len()));
        }
        v
    }
    /// Weight of every point (1 unless the data gave one).
    #[getter]
    fn weight<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.column(|c, k| c.weights[k]))
    }
    /// Where the data came from (the path read), or None for columns.
    #[getter]
    fn source(&self) -> Option<String> {
        self.source.clone()
    }
    /// Builds the data from a mapping of columns (`level`, `gamma` m/s^2,
    /// `f_hz` Hz, `amplitude` m zero-to-peak, optional `phase_deg`, `sweep`,
    /// `weight`), e.g. a dict, a pandas DataFrame or `to_dict()` of another.
    #[new]
    fn new(columns: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (inner, source) = dataset(columns)?;
        Ok(Self { inner, source })
    }
    /// The columns as a dict of lists and numpy arrays (`pandas.DataFrame(d.to_dict())`);
    /// `SteppedSineData(d.to_dict())` reads them back.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("level", self.level())?;
        d.set_item("gamma", self.gamma(py))?;
        d.set_item("f_hz", self.f_hz(py))?;
        d.set_item("amplitude", self.amplitude(py))?;
        if self.inner.curves.iter().any(|c| c.phases.is_some()) {
            d.set_item("phase_deg", self.phase_deg(py))?;
        }
        d.set_item("sweep", self.sweep())?;
        d.set_item("weight", self.weight(py))?;
        Ok(d)
    }
    /// The curves: a list of `(level, gamma, sweep)`, one per curve, in data
    /// order (gamma in m/s^2).
    #[getter]
    fn curves(&self) -> Vec<(String, f64, &'static str)> {
        self.inner
            .curves
            .iter()
            .map(|c| (c.level.clone(), c.gamma, c.direction.name()))
            .collect()
    }
    /// The curves of one level and/or one sweep direction ("up", "down"), as
    /// new data; a selection that leaves nothing is a `ValueError` naming
    /// what there is.
    #[pyo3(signature = (level=None, sweep=None))]
    fn select(&self, level: Option<&str>, sweep: Option<&str>) -> PyResult<Self> {
        let dir = sweep.map(crate::convert::direction).transpose()?;
        let curves: Vec<_> = self
            .inner
            .curves
            .iter()
            .filter(|c| level.is_none_or(|l| c.level == l) && dir.is_none_or(|d| c.direction == d))
            .cloned()
            .collect();
        if curves.is_empty() {
            let have: Vec<String> = self
                .curves()
                .iter()
                .map(|(l, _, s)| format!("{l} ({s})"))
                .collect();
            return Err(value_error(format!(
                "no curve of level {} and sweep {}: the data have {}",
                level.unwrap_or("any"),
                sweep.unwrap_or("any"),
                have.join(", ")
            )));
        }
        Ok(Self {
            inner: Dataset { curves },
            source: self.source.clone(),
        })
    }
    /// `data["0.04g"]` is `data.select(level="0.04g")`, `data["0.04g", "down"]`
    /// `data.select(level="0.04g", sweep="down")`.
    fn __getitem__(&self, key: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(level) = key.extract::<String>() {
            return self.select(Some(&level), None);
        }
        let (level, sweep): (String, String) = key
            .extract()
            .map_err(|_| value_error("index the data by a level label, or by (level, sweep)"))?;
        self.select(Some(&level), Some(&sweep))
    }
    /// The columns as a pandas DataFrame (long format, one row per point;
    /// needs pandas).
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        dataframe(py, self.to_dict(py)?)
    }
    /// Pickling and `copy.deepcopy`: every curve exactly as held (angular
    /// frequencies and phases in rad, no conversion).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (CurveStates, Option<String>))> {
        let me = slf.get();
        let curves = me
            .inner
            .curves
            .iter()
            .map(|c| {
                (
                    c.level.clone(),
                    c.gamma,
                    c.direction.name().to_string(),
                    c.omegas.clone(),
                    c.amplitudes.clone(),
                    c.phases.clone(),
                    c.weights.clone(),
                )
            })
            .collect();
        Ok((
            slf.get_type().getattr("_from_state")?,
            (curves, me.source.clone()),
        ))
    }
    /// Rebuilds pickled data (see `__reduce__`).
    #[staticmethod]
    fn _from_state(curves: CurveStates, source: Option<String>) -> PyResult<Self> {
        let curves = curves
            .into_iter()
            .map(|(level, gamma, dir, omegas, amplitudes, phases, weights)| {
                let direction = crate::convert::direction(&dir)?;
                Ok(nlsdof::identification::Curve {
                    level,
                    gamma,
                    direction,
                    omegas,
                    amplitudes,
                    phases,
                    weights,
                })
            })
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Self {
            inner: Dataset { curves },
            source,
        })
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<SteppedSineData>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }
    fn __len__(&self) -> usize {
        self.inner.len()
    }
    fn __repr__(&self) -> String {
        let levels: Vec<String> = self
            .inner
            .curves
            .iter()
            .map(|c| format!("{} ({} m/s^2, {})", c.level, c.gamma, c.direction.name()))
            .collect();
        format!(
            "SteppedSineData({} points, {} curves: {})",
            self.inner.len(),
            self.inner.curves.len(),
            levels.join(", ")
        )
    }
}

/// A pandas DataFrame of `columns`; a clear error when pandas is missing.
fn dataframe<'py>(py: Python<'py>, columns: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyAny>> {
    let pd = py.import("pandas").map_err(|_| {
        pyo3::exceptions::PyImportError::new_err(
            "to_dataframe() needs pandas (pip install pandas); to_dict()/fitted_curves() give the same columns without it",
        )
    })?;
    pd.getattr("DataFrame")?.call1((columns,))
}

/// The pickled state of a [`FitResult`].
#[derive(serde::Serialize, serde::Deserialize)]
struct FitState {
    id: Identification,
    mass: Option<f64>,
    source: Option<String>,
    integer: bool,
    /// `intervals="all"` (absent in states pickled before it: one).
    #[serde(default)]
    all_intervals: bool,
    /// The output-error profiles `profile()` computed (absent in states
    /// pickled before they were kept: none).
    #[serde(default)]
    profiles: Vec<ProfileState>,
}

/// An [`OutputErrorProfile`] as pickled (the library's type is not serde).
#[derive(serde::Serialize, serde::Deserialize)]
struct ProfileState {
    /// Index into `Parameter::ALL`.
    parameter: usize,
    estimate: f64,
    lower: Option<f64>,
    upper: Option<f64>,
    points: Vec<(f64, f64)>,
    fits: usize,
    start: f64,
    lowest: (f64, f64),
}

impl ProfileState {
    fn of(p: &OutputErrorProfile) -> Self {
        ProfileState {
            parameter: p.parameter as usize,
            estimate: p.estimate,
            lower: p.lower,
            upper: p.upper,
            points: p.points.clone(),
            fits: p.fits,
            start: p.start,
            lowest: p.lowest,
        }
    }

    fn profile(self) -> Option<OutputErrorProfile> {
        Some(OutputErrorProfile {
            parameter: *Parameter::ALL.get(self.parameter)?,
            estimate: self.estimate,
            lower: self.lower,
            upper: self.upper,
            points: self.points,
            fits: self.fits,
            start: self.start,
            lowest: self.lowest,
        })
    }
}

/// The pickled state of each curve: level, gamma, direction, omegas (rad/s),
/// amplitudes, phases (rad), weights.
type CurveStates = Vec<(
    String,
    f64,
    String,
    Vec<f64>,
    Vec<f64>,
    Option<Vec<f64>>,
    Vec<f64>,
)>;

/// Reads the long CSV format `level,gamma,f_hz,amplitude[,phase_deg,sweep,weight]`
/// (as `nlsdof fit DATA`). `velocity`/`acceleration`: the amplitudes are of
/// velocity (m/s) or acceleration (m/s^2), converted to displacement;
/// `gamma_in_g`: levels in g; `peak_to_peak`: levels and amplitudes are
/// peak-to-peak (the paper's tables).
///
/// >>> import os, tempfile, nlsdof
/// >>> p = os.path.join(tempfile.mkdtemp(), "d.csv")
/// >>> _ = open(p, "w").write("level,gamma,f_hz,amplitude\n1,0.5,5.0,0.01\n1,0.5,5.1,0.02\n1,0.5,5.2,0.015\n")
/// >>> nlsdof.read_stepped_sine(p).curves  # (level, gamma m/s^2, sweep)
/// [('1', 0.5, 'up')]
#[pyfunction]
#[pyo3(signature = (path, velocity=false, acceleration=false, gamma_in_g=false, peak_to_peak=false))]
pub fn read_stepped_sine(
    path: PathBuf,
    velocity: bool,
    acceleration: bool,
    gamma_in_g: bool,
    peak_to_peak: bool,
) -> PyResult<SteppedSineData> {
    let opts = read_options(velocity, acceleration, gamma_in_g, peak_to_peak)?;
    let inner = data_io::read_csv(&path, &opts).map_err(value_error)?;
    Ok(SteppedSineData {
        inner,
        source: Some(path.display().to_string()),
    })
}

/// Reads a beam directory of Polytec `frf_<A>g.txt` exports (as `nlsdof fit
/// --beam-dir`); `runs`: "up" (default, as the CLI's `--runs`), "down" or
/// "both".
///
/// >>> import nlsdof
/// >>> d = nlsdof.read_beam_dir("../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C")
/// >>> d.curves[:2]
/// [('0.04g', 0.392266, 'up'), ('0.06g', 0.5883989999999999, 'up')]
#[pyfunction]
#[pyo3(signature = (path, runs="up"))]
pub fn read_beam_dir(path: PathBuf, runs: &str) -> PyResult<SteppedSineData> {
    let runs = match runs.to_ascii_lowercase().as_str() {
        "up" => Runs::Up,
        "down" => Runs::Down,
        "both" => Runs::Both,
        _ => {
            return Err(value_error(format!(
                "runs {runs:?} is not allowed: use \"up\", \"down\" or \"both\""
            )))
        }
    };
    let inner = data_io::read_beam_dir(&path, runs).map_err(value_error)?;
    Ok(SteppedSineData {
        inner,
        source: Some(data_io::beam_source_name(&path, runs)),
    })
}

fn read_options(
    velocity: bool,
    acceleration: bool,
    gamma_in_g: bool,
    peak_to_peak: bool,
) -> PyResult<ReadOptions> {
    let amplitude = match (velocity, acceleration) {
        (false, false) => AmplitudeKind::Displacement,
        (true, false) => AmplitudeKind::Velocity,
        (false, true) => AmplitudeKind::Acceleration,
        (true, true) => {
            return Err(value_error(
                "give velocity=True or acceleration=True, not both",
            ))
        }
    };
    Ok(ReadOptions {
        amplitude,
        gamma_in_g,
        peak_to_peak,
    })
}

/// The data argument of `fit`: `SteppedSineData`, a path, or a mapping of
/// columns (`level`, `gamma`, `f_hz`, `amplitude`, optional `phase_deg`,
/// `sweep`, `weight`), each a sequence or numpy array of one length.
pub(crate) fn dataset(obj: &Bound<'_, PyAny>) -> PyResult<(Dataset, Option<String>)> {
    if let Ok(d) = obj.cast::<SteppedSineData>() {
        return Ok((d.get().inner.clone(), d.get().source.clone()));
    }
    if let Ok(p) = obj.extract::<PathBuf>() {
        let inner = data_io::read_csv(&p, &ReadOptions::default()).map_err(value_error)?;
        return Ok((inner, Some(p.display().to_string())));
    }
    // a dict, a pandas DataFrame, or anything with `name in obj` and `obj[name]`
    let columns = obj.hasattr("__contains__")? && obj.hasattr("__getitem__")?;
    if !columns || obj.is_instance_of::<pyo3::types::PyString>() {
        return Err(value_error("data must be SteppedSineData, a CSV path, or a mapping of columns (level, gamma, f_hz, amplitude[, phase_deg, sweep, weight]) such as a dict or a pandas DataFrame"));
    }
    let get = |name: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        if obj.contains(name)? {
            Ok(Some(obj.get_item(name)?))
        } else {
            Ok(None)
        }
    };
    let need = |name: &str| -> PyResult<Bound<'_, PyAny>> {
        get(name)?.ok_or_else(|| value_error(format!("data: missing column '{name}' (need level, gamma, f_hz, amplitude; optional phase_deg, sweep, weight)")))
    };
    let num = |name: &str, v: &Bound<'_, PyAny>| -> PyResult<Vec<f64>> {
        let a = f64_array(v, name)?;
        Ok(values(&a).into_owned())
    };
    let strings = |name: &str, v: &Bound<'_, PyAny>| -> PyResult<Vec<String>> {
        let list = PyList::type_object(v.py()).call1((v,))?;
        list.try_iter()?
            .map(|x| {
                let x = x?;
                match x.extract::<String>() {
                    Ok(s) => Ok(s),
                    Err(_) => Ok(x.str()?.to_string()),
                }
            })
            .collect::<PyResult<Vec<String>>>()
            .map_err(|e| value_error(format!("{name}: {e}")))
    };
    let level = strings("level", &need("level")?)?;
    let gamma = num("gamma", &need("gamma")?)?;
    let f_hz = num("f_hz", &need("f_hz")?)?;
    let amplitude = num("amplitude", &need("amplitude")?)?;
    let phase = get("phase_deg")?
        .map(|v| num("phase_deg", &v))
        .transpose()?;
    let sweep = get("sweep")?.map(|v| strings("sweep", &v)).transpose()?;
    let weight = get("weight")?.map(|v| num("weight", &v)).transpose()?;
    let n = level.len();
    let lens = [
        ("gamma", Some(gamma.len())),
        ("f_hz", Some(f_hz.len())),
        ("amplitude", Some(amplitude.len())),
        ("phase_deg", phase.as_ref().map(Vec::len)),
        ("sweep", sweep.as_ref().map(Vec::len)),
        ("weight", weight.as_ref().map(Vec::len)),
    ];
    for (name, len) in lens {
        if let Some(len) = len {
            if len != n {
                return Err(value_error(format!(
                    "data: column '{name}' has {len} values but 'level' has {n}"
                )));
            }
        }
    }
    let opts = ReadOptions::default();
    let mut recs: Vec<Record> = Vec::with_capacity(n);
    for i in 0..n {
        let row = Columns {
            level: &level[i],
            gamma: gamma[i],
            f_hz: f_hz[i],
            amplitude: amplitude[i],
            phase_deg: phase.as_ref().map(|p| p[i]),
            sweep: sweep.as_ref().map(|s| s[i].as_str()),
            weight: weight.as_ref().map(|w| w[i]),
        };
        recs.push(
            data_io::record(&opts, &row).map_err(|e| value_error(format!("data: row {i}: {e}")))?,
        );
    }
    Dataset::from_records(&recs)
        .map(|d| (d, None))
        .map_err(|e| value_error(format!("data: {e}")))
}

/// Fits a power-law model to stepped-sine amplitude curves at several
/// levels (paper §4, Eq 31), the staged way of `nlsdof fit`: a branch-free
/// equation-error estimate, the exponent landscape, output-error refinement
/// of the best candidates, and judging on all points.
///
/// `data`: `SteppedSineData`, a CSV path, or a mapping of columns (`level`,
/// `gamma` m/s^2, `f_hz` Hz, `amplitude` m zero-to-peak, optional
/// `phase_deg`, `sweep` "up"/"down", `weight`). `model`: linear, duffing,
/// quadratic, duffing-quadratic, duffing-generalised, generalised-stiffness,
/// generalised-damping, generalised, coulomb. `mass` (kg) scales the
/// physical values (only ratios to m are identifiable from base
/// acceleration). `fix`: {name: value} (alpha, delta, beta, kappa, rho,
/// eta, gain; m or mass); `free`: [names]; `bounds`: {name: (lo, hi)};
/// `sign`: as the CLI's `--sign`: "data" (default: the sign of the
/// branch-free equation-error estimate), "hardening", "softening", or
/// "auto" (fit both signs, keep the lower objective); `phase`: "auto", "ignore" or
/// (lag|lead, offset_deg, delay_s); `weighting`: "absolute" (Eq 31) or
/// "relative"; `jump_weight`: None (auto), 0 (off) or lambda;
/// `jump_reading`: "auto", "exact" or "censored" (`--jump-reading`);
/// `integer`: also fit the integer exponent pairs around the optimum
/// (`--integer`); `intervals`: "one" (default: one 95 % interval per
/// parameter in `report()`, named by its method) or "all" (`--intervals
/// all`: also every other interval, with what it leaves out);
/// `from_inspect`: as `--from-inspect`, start also from the exponents of
/// `nlsdof.inspect` on the same data (the landscape node nearest to them
/// joins the race).
///
/// Long work: Ctrl-C raises `KeyboardInterrupt` within a fraction of a
/// second (nothing is returned). `progress`: None (default: quiet), True (a
/// tqdm bar per stage when tqdm is installed, else one line on stderr), or
/// a callable `progress(stage, done, total)` called on this thread at most
/// every 20 ms and at each stage's start (stages "landscape", "output
/// error", "output error on all points", "decisions", "escalation"); an
/// exception it raises stops the fit and propagates.
///
/// >>> import numpy as np, nlsdof
/// >>> wing = nlsdof.Model.from_toml("examples/har-wing.toml")
/// >>> f = np.linspace(5.3, 5.5, 25)
/// >>> data = {"level": ["1"] * 25, "gamma": [0.41] * 25, "f_hz": f,
/// ...         "amplitude": wing.sweep(0.41, f).amplitude}
/// >>> r = nlsdof.fit(data, model="duffing")
/// >>> r.converged, r.parameters["alpha"]["unit"]
/// (True, '1/s^2')
#[pyfunction]
#[pyo3(signature = (data, model="generalised", *, mass=None, fix=None, free=None, bounds=None, sign="data", phase=None, phase_weight=None, weighting="absolute", jump_weight=None, jump_reading="auto", integer=false, grid=None, refine=None, starts=1, seed=1, intervals="one", progress=None, from_inspect=false))]
#[allow(clippy::too_many_arguments)]
pub fn fit(
    py: Python<'_>,
    data: &Bound<'_, PyAny>,
    model: &str,
    mass: Option<f64>,
    fix: Option<HashMap<String, f64>>,
    free: Option<Vec<String>>,
    bounds: Option<HashMap<String, Vec<f64>>>,
    sign: &str,
    phase: Option<&Bound<'_, PyAny>>,
    phase_weight: Option<f64>,
    weighting: &str,
    jump_weight: Option<f64>,
    jump_reading: &str,
    integer: bool,
    grid: Option<Vec<usize>>,
    refine: Option<usize>,
    starts: usize,
    seed: u64,
    intervals: &str,
    progress: Option<&Bound<'_, PyAny>>,
    from_inspect: bool,
) -> PyResult<FitResult> {
    let all_intervals = interval_view(intervals)? == IntervalView::All;
    let kind = ModelKind::parse(model).ok_or_else(|| {
        let all: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
        value_error(format!(
            "unknown model '{model}' (expected one of {})",
            all.join(", ")
        ))
    })?;
    let (data, source) = dataset(data)?;
    let mut plan = FitPlan::new(kind);
    let mut mass = mass;
    let mut fixes: Vec<(String, f64)> = fix.unwrap_or_default().into_iter().collect();
    fixes.sort_by(|a, b| a.0.cmp(&b.0));
    for (name, v) in fixes {
        match name.to_ascii_lowercase().as_str() {
            "m" | "mass" => mass = Some(v),
            "gain" => plan.gain = GainChoice::Fixed(v),
            n => plan.fix.push((n.to_string(), v)),
        }
    }
    if let Some(m) = mass {
        if !(m.is_finite() && m > 0.0) {
            return Err(value_error(format!(
                "mass {m} is not allowed: the mass must be finite and > 0 (kg)"
            )));
        }
    }
    for name in free.unwrap_or_default() {
        match name.to_ascii_lowercase().as_str() {
            "gain" => plan.gain = GainChoice::Free,
            n => plan.free.push(n.to_string()),
        }
    }
    let mut bounds: Vec<(String, (f64, f64))> = bounds
        .unwrap_or_default()
        .into_iter()
        .map(|(k, v)| {
            let b = crate::convert::pair(Some(v), &format!("bounds[{k:?}]"))?
                .expect("a pair was given");
            Ok((k, b))
        })
        .collect::<PyResult<_>>()?;
    bounds.sort_by(|a, b| a.0.cmp(&b.0));
    plan.bounds = bounds
        .into_iter()
        .map(|(n, (lo, hi))| (n.to_ascii_lowercase(), lo, hi))
        .collect();
    plan.sign = match sign.to_ascii_lowercase().as_str() {
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
    plan.phase = phase_choice(phase)?;
    // as the CLI's --jump-reading and --integer
    plan.reading = match jump_reading.to_ascii_lowercase().as_str() {
        "auto" => nlsdof::identification::ReadingChoice::Auto,
        "exact" => nlsdof::identification::ReadingChoice::Exact,
        "censored" => nlsdof::identification::ReadingChoice::Censored,
        _ => {
            return Err(value_error(format!(
            "jump_reading {jump_reading:?} is not allowed: use \"auto\", \"exact\" or \"censored\""
        )))
        }
    };
    if integer {
        use nlsdof::identification::models::Term;
        if kind.stiffness() != Term::FreeExponent
            && kind.damping() != Term::FreeExponent
            && !plan.free.iter().any(|n| n == "rho" || n == "eta")
        {
            return Err(value_error(format!(
                "integer: the {kind} model has no free exponent"
            )));
        }
        plan.exponents = nlsdof::identification::identify::ExponentChoice::Integer;
    }
    if let Some(w) = phase_weight {
        if !(w.is_finite() && w > 0.0) {
            return Err(value_error(format!(
                "phase_weight {w} is not allowed: use a finite value > 0"
            )));
        }
        plan.phase_weight = w;
    }
    plan.weighting = match weighting.to_ascii_lowercase().as_str() {
        "absolute" => Weighting::Absolute,
        "relative" => Weighting::Relative,
        _ => {
            return Err(value_error(format!(
                "weighting {weighting:?} is not allowed: use \"absolute\" or \"relative\""
            )))
        }
    };
    plan.jumps = match jump_weight {
        None => JumpChoice::Auto,
        Some(0.0) => JumpChoice::Off,
        Some(l) => JumpChoice::Weight(l),
    };
    if let Some((a, b)) = crate::convert::pair(grid, "grid")? {
        plan = plan.with_grid(a, b).map_err(value_error)?;
    }
    if let Some(r) = refine {
        if r == 0 || r > 100 {
            return Err(value_error(format!(
                "refine {r} is not allowed: use 1..=100"
            )));
        }
        plan.refine = r;
    }
    if starts == 0 || starts > 100_000 {
        return Err(value_error(format!(
            "starts {starts} is not allowed: use 1..=100000"
        )));
    }
    plan.starts = starts;
    plan.seed = seed;
    if from_inspect {
        // as `fit --from-inspect`: inspect's exponents join the race
        let r = nlsdof::identification::inspect::inspect(&data, &Default::default())
            .map_err(|e| value_error(format!("from_inspect: {e}")))?;
        plan.start_exponents = Some(r.exponent_start());
    }
    // Ctrl-C stops it (KeyboardInterrupt), progress= follows the stages
    let id = crate::interrupt::run(py, progress, kind.name(), |cancel, rep| {
        plan.lm.cancel = cancel;
        identify(&data, &plan, &|p| rep.identify(p))
    })?
    .map_err(value_error)?;
    // checked here so that `model` cannot fail later
    let physical = id
        .fit
        .model()
        .to_physical(mass.unwrap_or(1.0))
        .map_err(value_error)?;
    Ok(FitResult {
        id,
        mass,
        physical,
        source,
        integer,
        all_intervals,
        profiles: std::sync::Mutex::new(Vec::new()),
    })
}

/// `intervals=`: "one" or "all" (`fit --intervals`).
fn interval_view(intervals: &str) -> PyResult<IntervalView> {
    IntervalView::parse(intervals).ok_or_else(|| {
        value_error(format!(
            "intervals {intervals:?} is not allowed: use \"one\" (one 95 % interval per parameter) or \"all\""
        ))
    })
}

/// `phase=`: None/"auto", "ignore", or (lag|lead, offset_deg[, delay_s]).
fn phase_choice(phase: Option<&Bound<'_, PyAny>>) -> PyResult<PhaseChoice> {
    let Some(p) = phase else {
        return Ok(PhaseChoice::Auto);
    };
    if let Ok(s) = p.extract::<String>() {
        return match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(PhaseChoice::Auto),
            "ignore" => Ok(PhaseChoice::Ignore),
            _ => Err(value_error(format!(
                "phase {s:?} is not allowed: use \"auto\", \"ignore\" or (\"lag\"|\"lead\", offset_deg, delay_s)"
            ))),
        };
    }
    let (dir, offset, delay): (String, f64, f64) = match p.extract::<(String, f64, f64)>() {
        Ok(t) => t,
        Err(_) => {
            let (d, o): (String, f64) = p.extract().map_err(|_| {
                value_error(
                    "phase must be \"auto\", \"ignore\" or (\"lag\"|\"lead\", offset_deg, delay_s)",
                )
            })?;
            (d, o, 0.0)
        }
    };
    let lag = match dir.to_ascii_lowercase().as_str() {
        "lag" => true,
        "lead" => false,
        _ => {
            return Err(value_error(format!(
                "phase convention {dir:?}: use \"lag\" or \"lead\""
            )))
        }
    };
    PhaseConvention::from_degrees(lag, offset, delay)
        .map(PhaseChoice::Known)
        .map_err(|why| value_error(format!("phase: {why}")))
}

/// The outcome of `fit`: `parameters` (name -> {value, interval, unit,
/// status, physical}), `cost` (Eq 31), `converged`, `warning`, `notes`, `minima`
/// (the distinct local minima found), `model` (the physical `Model` for
/// `mass`, 1 kg if not given), `to_dict()` (the document of `nlsdof fit
/// --json`) and `to_toml()` (its `--out` model file).
#[pyclass(frozen, name = "FitResult", module = "nlsdof")]
pub struct FitResult {
    id: Identification,
    mass: Option<f64>,
    physical: nlsdof::Model,
    /// The data's source, as the model file's provenance names it.
    source: Option<String>,
    /// Fitted with `integer=True` (the documents add the integer nodes).
    integer: bool,
    /// `intervals="all"`: `report()` shows every interval computed.
    all_intervals: bool,
    /// The output-error profiles `profile()` computed, one per exponent
    /// (the latest): `report()` and `to_dict()` show them as the one
    /// interval of that exponent, as `nlsdof fit --profile` does.
    profiles: std::sync::Mutex<Vec<OutputErrorProfile>>,
}

impl FitResult {
    /// The profiles computed so far (a copy).
    fn computed_profiles(&self) -> Vec<OutputErrorProfile> {
        self.profiles.lock().map(|p| p.clone()).unwrap_or_default()
    }
}

#[pymethods]
impl FitResult {
    /// name -> {"value", "interval" (95 %, or None), "unit", "status",
    /// "physical" {name, value, unit}}; mass-normalised values (per kg) as
    /// fitted, physical values for the given mass.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let res = &self.id.fit;
        let valid = res.intervals_valid();
        let m = self.mass.unwrap_or(1.0);
        let out = PyDict::new(py);
        for (j, p) in Parameter::ALL.iter().enumerate() {
            if res.status[j] == Status::Absent {
                continue;
            }
            let info = p.info();
            let interval = res.uncertainty.as_ref().filter(|_| valid).and_then(|u| {
                u.index(nlsdof::identification::PARAM_NAMES[j])
                    .map(|k| (u.lower[k], u.upper[k]))
            });
            let d = PyDict::new(py);
            d.set_item("value", res.theta[j])?;
            d.set_item("interval", interval)?;
            // the method of `interval` (the linearised one; `profile()`
            // gives the output-error profile)
            d.set_item(
                "interval_method",
                interval.map(|_| nlsdof_report::intervals::WALD),
            )?;
            d.set_item("unit", info.unit)?;
            d.set_item(
                "status",
                match res.status[j] {
                    Status::Free => "free",
                    Status::Fixed(_) => "fixed",
                    Status::Absent => "absent",
                },
            )?;
            let phys = PyDict::new(py);
            phys.set_item("name", info.physical_name)?;
            phys.set_item(
                "value",
                if p.mass_scaled() {
                    res.theta[j] * m
                } else {
                    res.theta[j]
                },
            )?;
            phys.set_item("unit", info.physical_unit)?;
            d.set_item("physical", phys)?;
            out.set_item(PARAM_NAMES[j], d)?;
        }
        Ok(out)
    }
    /// The Eq 31 cost at the optimum.
    #[getter]
    fn cost(&self) -> f64 {
        self.id.fit.cost
    }
    /// Whether the local solver converged (a fit that did not says so).
    #[getter]
    fn converged(&self) -> bool {
        self.id.fit.converged
    }
    /// Why the fit is not to be trusted (the model does not fit the noise,
    /// not converged, at a bound, not identifiable, a ridge), or None: the
    /// first lines of the CLI's report.
    #[getter]
    fn warning(&self) -> Option<String> {
        self.id.warning()
    }
    /// Results worth a line that are not warnings, as the CLI prints them
    /// after "note:": a natural bound ("eta = -1 (Coulomb friction)"), an
    /// exponent whose interval holds one, a term the data do not need, an
    /// exponent the data do not determine. Empty when there are none.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.id.fit.notes()
    }
    /// Whether the model fits every curve to within its noise (the
    /// self-check; `to_dict()["adequacy"]` has the details).
    #[getter]
    fn adequate(&self) -> bool {
        self.id.adequacy.adequate
    }
    /// The distinct local minima: list of {"cost", "count", "termination",
    /// "theta"}.
    #[getter]
    fn minima<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &nlsdof_report::fit::minima_json(&self.id.fit.minima))
    }
    /// The fitted physical model for the given mass (1 kg if none).
    #[getter]
    fn model(&self) -> crate::model::Model {
        crate::model::Model {
            inner: self.physical,
            // the fit's forcing gain: model.sweep(gamma) reproduces the fit's curves
            signal: Some(nlsdof_io::model_file::SignalMap {
                input_gain: self.id.fit.theta[nlsdof::identification::models::GAIN],
                ..Default::default()
            }),
            provenance: Some(nlsdof_report::fit::provenance(
                &self.id.fit,
                self.source.as_deref(),
            )),
        }
    }
    /// The document of `nlsdof fit --json` (same keys and numbers).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut doc = nlsdof_report::fit::identification_document(&self.id, self.mass)
            .map_err(value_error)?;
        // parameters[].interval: the one interval reported, with its method
        // (the output-error profile where `profile()` computed it, as
        // `nlsdof fit --profile --json`)
        let profiles = self.computed_profiles();
        nlsdof_report::intervals::add_chosen_json(&mut doc, &self.id.fit, &profiles);
        if self.integer {
            doc["integer_pairs"] = nlsdof_report::fit::integer_nodes_json(&self.id);
        }
        to_py(py, &doc)
    }
    /// The model file of `nlsdof fit --out` (TOML, with its header).
    fn to_toml(&self) -> PyResult<String> {
        nlsdof_report::fit::model_file_text(&self.id.fit, self.mass, self.source.as_deref())
            .map_err(value_error)
    }
    /// Output-error profile-likelihood 95 % interval of a free exponent
    /// (`"rho"` or `"eta"`): refits with the exponent held, walked out from
    /// the optimum in `step`s (default half its linearised standard error)
    /// until `(P - P*)/sigma^2` crosses chi2_1(0.95) = 3.84. Returns the
    /// entry of `nlsdof fit --profile --json`: `estimate`, `ci95` (None:
    /// open), `fits`, `points`. The profile is kept (also when pickled):
    /// `report()` and `to_dict()` then give it as this exponent's one 95 %
    /// interval ("output-error profile"), as `nlsdof fit --profile`.
    #[pyo3(signature = (parameter="rho", step=None, max_steps=24, *, progress=None))]
    fn profile<'py>(
        &self,
        py: Python<'py>,
        parameter: &str,
        step: Option<f64>,
        max_steps: usize,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        use nlsdof::identification::profile::{default_step, output_error_profile_with};
        let p = match parameter.to_ascii_lowercase().as_str() {
            "rho" => Parameter::Rho,
            "eta" => Parameter::Eta,
            _ => {
                return Err(value_error(format!(
                    "parameter {parameter:?}: only the exponents \"rho\" and \"eta\" are profiled"
                )))
            }
        };
        let id = &self.id;
        let step = step.unwrap_or_else(|| default_step(&id.fit, p));
        let what = format!("profile {}", p.info().name);
        let prof = crate::interrupt::run(py, progress, &what, |cancel, rep| {
            rep.stage("local fits", 1 + 2 * max_steps);
            output_error_profile_with(
                &id.data,
                &id.spec,
                &id.fit.theta,
                p,
                step,
                max_steps,
                cancel,
                &|done, total| rep.at(done, total),
            )
        })?
        .map_err(value_error)?;
        let doc = nlsdof_report::fit::profiles_json(std::slice::from_ref(&prof));
        // kept: report() and to_dict() show it as this exponent's interval
        if let Ok(mut kept) = self.profiles.lock() {
            kept.retain(|q| q.parameter != prof.parameter);
            kept.push(prof);
            kept.sort_by_key(|q| q.parameter as usize);
        }
        to_py(py, &doc[p.info().name])
    }
    /// The text report of `nlsdof fit`: one 95 % interval per parameter,
    /// named by its method: the output-error profile of an exponent once
    /// `profile()` computed it (and did not refuse it), else Wald, as
    /// `nlsdof fit --profile --intervals one`; `intervals="all"` (default: as
    /// given to `fit`) adds every other interval with what it leaves out, as
    /// `nlsdof fit --intervals all`.
    #[pyo3(signature = (intervals=None))]
    fn report(&self, intervals: Option<&str>) -> PyResult<String> {
        let view = match intervals {
            Some(v) => interval_view(v)?,
            None if self.all_intervals => IntervalView::All,
            None => IntervalView::One,
        };
        let profiles = self.computed_profiles();
        let mut text =
            nlsdof_report::fit::identification_report_with(&self.id, self.mass, &profiles, view)
                .map_err(value_error)?;
        if self.integer {
            text.push_str(&nlsdof_report::fit::integer_nodes_text(&self.id));
        }
        Ok(text)
    }
    /// Every measured point with the fit's model there, as columns (a dict of
    /// lists and numpy arrays): `level`, `gamma` (m/s^2), `f_hz`, `amplitude`
    /// (m, measured), `sweep`, `model_amplitude` (m) and `model_phase_deg`
    /// (deg), plus `phase_deg` when the data have phases — the fit's own model
    /// curves (Eq 31; the table of `nlsdof fit --predict`, same numbers).
    fn fitted_curves<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let pts = nlsdof_report::fit::predicted_points(&self.id).map_err(value_error)?;
        let d = PyDict::new(py);
        let col = |f: &dyn Fn(&nlsdof_report::fit::PredictedPoint) -> f64| {
            PyArray1::from_vec(py, pts.iter().map(f).collect())
        };
        d.set_item("level", pts.iter().map(|p| p.level).collect::<Vec<_>>())?;
        d.set_item("gamma", col(&|p| p.gamma))?;
        d.set_item("f_hz", col(&|p| p.f_hz))?;
        d.set_item("amplitude", col(&|p| p.amplitude))?;
        d.set_item("sweep", pts.iter().map(|p| p.sweep).collect::<Vec<_>>())?;
        d.set_item("model_amplitude", col(&|p| p.model_amplitude))?;
        d.set_item("model_phase_deg", col(&|p| p.model_phase_deg))?;
        if pts.iter().any(|p| p.phase_deg.is_some()) {
            d.set_item("phase_deg", col(&|p| p.phase_deg.unwrap_or(f64::NAN)))?;
        }
        Ok(d)
    }
    /// The measured points and the fit's model curves per level and sweep
    /// (matplotlib; `nlsdof.plot.fit`): `ax=None` draws a new figure. Returns
    /// the Axes.
    #[pyo3(signature = (ax=None))]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        slf.py()
            .import("nlsdof.plot")?
            .call_method1("fit", (slf, ax))
    }
    /// The exponent landscape (the document of `nlsdof fit --landscape
    /// FILE.json`): `rho`, `eta` (nodes), `cost` (`cost[j][i]` at
    /// `(rho[i], eta[j])`, None where not solvable), `minima`, `fitted`,
    /// `with_phase`.
    fn landscape<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let bytes =
            nlsdof_report::landscape::render(&self.id, nlsdof_report::landscape::Kind::Json)
                .map_err(value_error)?;
        let doc: serde_json::Value = serde_json::from_slice(&bytes).map_err(value_error)?;
        to_py(py, &doc)
    }
    /// The exponent landscape as the CLI's `--landscape FILE.png` draws it
    /// (matplotlib; `nlsdof.plot.landscape`): a map over (rho, eta), a 1-D
    /// profile when one exponent is fixed; ValueError for a single node.
    /// Returns the Axes.
    #[pyo3(signature = (ax=None))]
    fn plot_landscape<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        slf.py()
            .import("nlsdof.plot")?
            .call_method1("landscape", (slf, ax))
    }
    /// `fitted_curves()` as a pandas DataFrame (long format, one row per
    /// measured point; needs pandas).
    fn to_dataframe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        dataframe(py, self.fitted_curves(py)?)
    }
    /// The fitted model's stepped-sine sweeps at levels `gamma` (m/s^2, as
    /// measured: the fitted forcing gain is applied) over `f_hz` (Hz), in
    /// `direction`: `self.model.sweep(gamma, f_hz, direction)`.
    #[pyo3(signature = (gamma, f_hz, direction="up"))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        gamma: &Bound<'py, PyAny>,
        f_hz: &Bound<'py, PyAny>,
        direction: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        Bound::new(py, self.model())?
            .into_any()
            .call_method1("sweep", (gamma, f_hz, direction))
    }
    /// Pickling and `copy.deepcopy`: the whole identification (every stage,
    /// so `to_dict()`, `report()` and `profile()` work on the copy as on the
    /// original) as CBOR bytes, with the mass and the data's source.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyBytes>,))> {
        let me = slf.get();
        let state = FitState {
            id: me.id.clone(),
            mass: me.mass,
            source: me.source.clone(),
            integer: me.integer,
            all_intervals: me.all_intervals,
            profiles: me
                .computed_profiles()
                .iter()
                .map(ProfileState::of)
                .collect(),
        };
        let mut bytes = Vec::new();
        ciborium::into_writer(&state, &mut bytes).map_err(value_error)?;
        Ok((
            slf.get_type().getattr("_from_state")?,
            (pyo3::types::PyBytes::new(slf.py(), &bytes),),
        ))
    }
    /// Rebuilds a pickled result (see `__reduce__`).
    #[staticmethod]
    fn _from_state(state: &[u8]) -> PyResult<Self> {
        let s: FitState = ciborium::from_reader(state)
            .map_err(|e| value_error(format!("not a pickled FitResult: {e}")))?;
        let physical =
            s.id.fit
                .model()
                .to_physical(s.mass.unwrap_or(1.0))
                .map_err(value_error)?;
        Ok(Self {
            id: s.id,
            mass: s.mass,
            physical,
            source: s.source,
            integer: s.integer,
            all_intervals: s.all_intervals,
            profiles: std::sync::Mutex::new(
                s.profiles
                    .into_iter()
                    .filter_map(ProfileState::profile)
                    .collect(),
            ),
        })
    }
    /// Equal when the two identifications are the same bit for bit (data,
    /// every stage, result; NaN cells included) with the same mass.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> PyResult<bool> {
        let Ok(o) = other.cast::<FitResult>() else {
            return Ok(false);
        };
        let bytes = |r: &FitResult| -> PyResult<Vec<u8>> {
            let mut b = Vec::new();
            ciborium::into_writer(&(&r.id, r.mass), &mut b).map_err(value_error)?;
            Ok(b)
        };
        Ok(bytes(self)? == bytes(o.get())?)
    }
    /// Jupyter: the verdict, then a table of every parameter present with
    /// its value, unit, status and 95 % interval (when the intervals are
    /// valid), and the cost.
    fn _repr_html_(&self) -> String {
        let fit = &self.id.fit;
        let esc = |t: &str| {
            t.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
        };
        let ci = fit.uncertainty.as_ref().filter(|_| fit.warning().is_none());
        let mut h = format!(
            "<div><b>nlsdof fit: {}</b> &mdash; cost (Eq 31) {:.6e}, {}",
            fit.kind.name(),
            fit.cost,
            if fit.converged {
                "converged"
            } else {
                "<b>not converged</b>"
            }
        );
        if let Some(w) = self.id.warning() {
            h += &format!("<br><b>WARNING:</b> {}", esc(&w));
        }
        h += "<table><tr><th>parameter</th><th>value</th><th>unit</th><th>status</th><th>95 % interval</th></tr>";
        for j in 0..nlsdof::identification::N_PARAMS {
            if fit.status[j] == Status::Absent {
                continue;
            }
            let info = Parameter::ALL[j].info();
            let status = match fit.status[j] {
                Status::Free => "free",
                Status::Fixed(_) => "held",
                Status::Absent => "",
            };
            let interval = ci
                .and_then(|u| {
                    u.index(nlsdof::identification::PARAM_NAMES[j])
                        .map(|k| (u, k))
                })
                .map(|(u, k)| format!("[{:.4e}, {:.4e}]", u.lower[k], u.upper[k]))
                .unwrap_or_else(|| "&mdash;".into());
            h += &format!(
                "<tr><td>{}</td><td>{:.6e}</td><td>{}</td><td>{status}</td><td>{interval}</td></tr>",
                info.name,
                fit.theta[j],
                esc(info.unit)
            );
        }
        h + "</table></div>"
    }
    /// The model, every parameter present with its unit (and 95 % interval
    /// when valid), the cost and the verdict.
    fn __repr__(&self) -> String {
        let fit = &self.id.fit;
        let ci = fit.uncertainty.as_ref().filter(|_| fit.warning().is_none());
        let params: Vec<String> = (0..nlsdof::identification::N_PARAMS)
            .filter(|&j| fit.status[j] != Status::Absent)
            .map(|j| {
                let info = Parameter::ALL[j].info();
                let v = fit.theta[j];
                let unit = if info.unit == "-" || info.unit.is_empty() {
                    String::new()
                } else {
                    format!(" {}", info.unit)
                };
                let interval = ci
                    .and_then(|u| {
                        u.index(nlsdof::identification::PARAM_NAMES[j])
                            .map(|k| (u, k))
                    })
                    .map(|(u, k)| format!(" [{:.4e}, {:.4e}]", u.lower[k], u.upper[k]))
                    .unwrap_or_default();
                let held = if fit.status[j] == Status::Free {
                    ""
                } else {
                    " (held)"
                };
                format!("{} = {v:.6e}{unit}{interval}{held}", info.name)
            })
            .collect();
        format!(
            "FitResult(model={}: {}; cost (Eq 31) = {:.6e}; converged={}, adequate={})",
            fit.kind.name(),
            params.join(", "),
            fit.cost,
            if fit.converged { "True" } else { "False" },
            if self.id.adequacy.adequate {
                "True"
            } else {
                "False"
            }
        )
    }
}
