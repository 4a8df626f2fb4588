//! `nlsdof.Model` and what it computes: steady states and sweeps of the
//! first-order harmonic balance (paper Eq 12-30), time simulation (Eq 32)
//! and the virtual stepped-sine rig.

use crate::arrays::{f64_array, values};
use crate::convert::{to_py, value_error};
use crate::simulation::Simulation;
use nlsdof::identification::time_domain::{
    simulate_states, stated_integration_error, InputInterpolation, TimeModel, MAX_SUBSTEPS,
};
use nlsdof::simulation::{simulate_record_cancellable, RecordMethod, Sample, State};
use nlsdof::stepped_sine::{run_sweeps, RigOptions};
use nlsdof::{level_responses, AsNormalised, ForcedResponse};
use nlsdof_io::model_file::{ModelDocument, Provenance, SignalMap};
use nlsdof_report::steady_state::{sweep_json, SweepRequest};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use std::f64::consts::TAU;
use std::path::PathBuf;

/// A power-law SDoF model (SI units):
///
///     m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma(t)
///
/// `Model(mass, stiffness, damping, nonlinear_stiffness=(k_r, rho),
/// nonlinear_damping=(c_e, eta))`: mass in kg, stiffness k in N/m, damping
/// c in N s/m, k_r in N/m^(1+rho), c_e in N (s/m)^(1+eta); exponents > -3.
/// Input levels gamma are accelerations in m/s^2 and amplitudes are in m,
/// both zero-to-peak; frequencies are in Hz.
///
/// `signal` (optional, a dict as the model file's `[signal]` table):
/// `input_gain` (default 1), `input_offset`, `output_offset` (default 0);
/// a time-domain fit's `input_interpolation` ("cubic", "linear", "zoh") and
/// RK4 `substeps` per sample, which `simulate` then follows.
/// The model sees `gamma = input_gain * (u + input_offset)`: the forcing
/// gain of a stepped-sine fit (`FitResult.model` carries it), the signal
/// map of a time-domain fit. `sweep`, `steady_states`, `harmonic_sweep`,
/// `hb_error` and `stepped_sine` apply `input_gain` to the levels given
/// (and refuse a non-zero `input_offset` or a negative gain, as the CLI);
/// `simulate` applies gain and input offset (the recorded output is
/// `x + output_offset`). Models pickle, deep-copy and compare by value.
///
/// >>> import nlsdof
/// >>> m = nlsdof.Model(1.0, 100.0, 0.5, nonlinear_stiffness=(1e3, 3.0))
/// >>> [round(s.amplitude, 6) for s in m.steady_states(1.0, 1.5)]  # gamma m/s^2, f Hz -> m
/// [0.080312]
#[pyclass(frozen, eq, name = "Model", module = "nlsdof")]
#[derive(Clone, PartialEq)]
pub struct Model {
    pub inner: nlsdof::Model,
    pub signal: Option<SignalMap>,
    pub provenance: Option<Provenance>,
}

impl Model {
    /// A model without signal map or provenance.
    pub fn plain(inner: nlsdof::Model) -> Self {
        Self {
            inner,
            signal: None,
            provenance: None,
        }
    }

    fn document(&self) -> ModelDocument {
        ModelDocument {
            model: self.inner,
            signal: self.signal,
            provenance: self.provenance.clone(),
        }
    }

    /// The input gain a steady-state computation applies to its levels;
    /// refuses what a harmonic balance about zero cannot apply (the CLI's
    /// rule, `nlsdof frf --help`).
    fn steady_gain(&self) -> PyResult<f64> {
        self.signal
            .unwrap_or_default()
            .steady_state_gain()
            .map_err(value_error)
    }
}

/// The `[signal]` table from a dict.
fn signal_from(d: &Bound<'_, pyo3::types::PyDict>) -> PyResult<SignalMap> {
    let mut s = SignalMap::default();
    for (k, v) in d.iter() {
        let key: String = k.extract()?;
        // the integration a time-domain fit states (issue 26)
        if key == "input_interpolation" {
            let name: String = v.extract().map_err(|_| {
                value_error(
                    "signal[\"input_interpolation\"] must be a string: cubic, linear or zoh",
                )
            })?;
            s.input_interpolation = Some(InputInterpolation::parse(&name).ok_or_else(|| {
                value_error(format!(
                    "signal[\"input_interpolation\"] = {name:?} is not an interpolation (cubic, linear, zoh)"
                ))
            })?);
            continue;
        }
        if key == "substeps" {
            let n: usize = v
                .extract()
                .ok()
                .filter(|n| (1..=MAX_SUBSTEPS).contains(n))
                .ok_or_else(|| {
                    value_error(format!(
                        "signal[\"substeps\"] must be an integer from 1 to {MAX_SUBSTEPS}"
                    ))
                })?;
            s.substeps = Some(n);
            continue;
        }
        let val: f64 = v
            .extract()
            .map_err(|_| value_error(format!("signal[{key:?}] must be a number")))?;
        match key.as_str() {
            "input_gain" => s.input_gain = val,
            "input_offset" => s.input_offset = val,
            "output_offset" => s.output_offset = val,
            other => {
                return Err(value_error(format!(
                    "signal has no key {other:?}: use input_gain, input_offset, output_offset, input_interpolation, substeps"
                )))
            }
        }
    }
    // the model file's rule, in its words
    s.check().map_err(|(_, m)| value_error(m))?;
    Ok(s)
}

#[pymethods]
impl Model {
    #[new]
    #[pyo3(signature = (mass, stiffness, damping, nonlinear_stiffness=None, nonlinear_damping=None, signal=None))]
    fn new(
        mass: f64,
        stiffness: f64,
        damping: f64,
        nonlinear_stiffness: Option<Vec<f64>>,
        nonlinear_damping: Option<Vec<f64>>,
        signal: Option<&Bound<'_, pyo3::types::PyDict>>,
    ) -> PyResult<Self> {
        let mut m = nlsdof::Model::linear(mass, stiffness, damping).map_err(value_error)?;
        if let Some((k_r, rho)) = crate::convert::pair(nonlinear_stiffness, "nonlinear_stiffness")?
        {
            m = m.with_stiffness(k_r, rho).map_err(value_error)?;
        }
        if let Some((c_e, eta)) = crate::convert::pair(nonlinear_damping, "nonlinear_damping")? {
            m = m.with_damping(c_e, eta).map_err(value_error)?;
        }
        Ok(Self {
            inner: m,
            signal: signal.map(signal_from).transpose()?,
            provenance: None,
        })
    }

    /// Reads a model file (TOML, SI units; the format of `nlsdof --help`)
    /// with its `[signal]` and `[provenance]` tables.
    #[staticmethod]
    fn from_toml(path: PathBuf) -> PyResult<Self> {
        let d = nlsdof_io::model_file::read_document(&path).map_err(value_error)?;
        Ok(Self {
            inner: d.model,
            signal: d.signal,
            provenance: d.provenance,
        })
    }

    /// Parses model-file text (as `to_toml()` writes it).
    #[staticmethod]
    fn from_toml_str(text: &str) -> PyResult<Self> {
        let d = nlsdof_io::model_file::parse_document(text, std::path::Path::new("<string>"))
            .map_err(value_error)?;
        Ok(Self {
            inner: d.model,
            signal: d.signal,
            provenance: d.provenance,
        })
    }

    /// The model file (TOML) of this model, with its `[signal]` and
    /// `[provenance]` tables; `from_toml_str` reads it back to an equal model.
    fn to_toml(&self) -> String {
        self.document().to_toml()
    }

    /// Pickling and `copy.deepcopy`: the model file text, which round-trips
    /// every number exactly.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let ctor = slf.get_type().getattr("from_toml_str")?;
        Ok((ctor, (slf.get().to_toml(),)))
    }

    /// The `[signal]` table as a dict (`input_gain`, `input_offset`,
    /// `output_offset`; `input_interpolation` and `substeps` where the file
    /// states them), or None.
    #[getter]
    fn signal<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, pyo3::types::PyDict>>> {
        self.signal
            .map(|s| {
                let d = pyo3::types::PyDict::new(py);
                d.set_item("input_gain", s.input_gain)?;
                d.set_item("input_offset", s.input_offset)?;
                d.set_item("output_offset", s.output_offset)?;
                if let Some(i) = s.input_interpolation {
                    d.set_item("input_interpolation", i.name())?;
                }
                if let Some(n) = s.substeps {
                    d.set_item("substeps", n)?;
                }
                Ok(d)
            })
            .transpose()
    }
    /// The input gain the model applies to every level and input (1 without
    /// a `[signal]` table).
    #[getter]
    fn input_gain(&self) -> f64 {
        self.signal.unwrap_or_default().input_gain
    }
    /// The `[provenance]` table (tool, version, data, model, objective,
    /// cost, converged, range) as a dict, or None.
    #[getter]
    fn provenance<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.provenance
            .as_ref()
            .map(|p| {
                let v = serde_json::to_value(p).map_err(value_error)?;
                to_py(py, &v)
            })
            .transpose()
    }

    /// Mass m, kg.
    #[getter]
    fn mass(&self) -> f64 {
        self.inner.mass
    }
    /// Linear stiffness k, N/m.
    #[getter]
    fn stiffness(&self) -> f64 {
        self.inner.stiffness
    }
    /// Linear damping c, N s/m.
    #[getter]
    fn damping(&self) -> f64 {
        self.inner.damping
    }
    /// (k_r, rho) or None.
    #[getter]
    fn nonlinear_stiffness(&self) -> Option<(f64, f64)> {
        self.inner
            .nonlinear_stiffness
            .map(|p| (p.coefficient, p.exponent))
    }
    /// (c_e, eta) or None.
    #[getter]
    fn nonlinear_damping(&self) -> Option<(f64, f64)> {
        self.inner
            .nonlinear_damping
            .map(|p| (p.coefficient, p.exponent))
    }
    /// Linear natural frequency sqrt(k/m) / (2 pi), Hz.
    #[getter]
    fn f_n_hz(&self) -> f64 {
        self.inner.omega_n() / TAU
    }
    /// Linear damping ratio c / (2 m omega_n).
    #[getter]
    fn zeta(&self) -> f64 {
        self.inner.zeta()
    }

    /// The parameters with their SI units (and the signal map when set),
    /// e.g. `Model(mass=0.26699 kg, stiffness=306.7878 N/m, damping=0.1164
    /// N s/m, nonlinear_stiffness=(85000.0 N/m^5.0022, rho=4.0022))`.
    fn __repr__(&self) -> String {
        let m = &self.inner;
        let mut s = format!(
            "Model(mass={:?} kg, stiffness={:?} N/m, damping={:?} N s/m",
            m.mass, m.stiffness, m.damping
        );
        if let Some(p) = m.nonlinear_stiffness {
            s += &format!(
                ", nonlinear_stiffness=({:?} N/m^{:?}, rho={:?})",
                p.coefficient,
                p.exponent + 1.0,
                p.exponent
            );
        }
        if let Some(p) = m.nonlinear_damping {
            s += &format!(
                ", nonlinear_damping=({:?} N (s/m)^{:?}, eta={:?})",
                p.coefficient,
                p.exponent + 1.0,
                p.exponent
            );
        }
        if let Some(g) = self.signal {
            s += &format!(
                ", signal={{'input_gain': {:?}, 'input_offset': {:?}, 'output_offset': {:?}}}",
                g.input_gain, g.input_offset, g.output_offset
            );
        }
        s + ")"
    }

    /// Every steady state at input level `gamma` (m/s^2, zero-to-peak) and
    /// frequency `f_hz` (Hz): first-order harmonic balance (Eq 12-30), with
    /// phase lag (deg) and stability, ordered by amplitude. An empty list
    /// when there is no steady motion (Coulomb friction sticks).
    #[pyo3(signature = (gamma, f_hz, formulation="hb"))]
    fn steady_states(
        &self,
        py: Python<'_>,
        gamma: f64,
        f_hz: f64,
        formulation: &str,
    ) -> PyResult<Vec<SteadyState>> {
        let form = crate::convert::formulation(formulation)?;
        let model = &self.inner;
        let gain = self.steady_gain()?;
        let set = py
            .detach(|| {
                let r = ForcedResponse::new(model, gain * gamma, form)?;
                r.steady_states(TAU * f_hz)
            })
            .map_err(value_error)?;
        Ok(set
            .roots
            .iter()
            .map(|r| SteadyState {
                amplitude: r.amplitude,
                phase_deg: r.phase.to_degrees(),
                stable: r.stable,
            })
            .collect())
    }

    /// A stepped-sine sweep at level `gamma` (m/s^2, zero-to-peak) over the
    /// frequencies `f_hz` (Hz; increasing, or decreasing for a sweep down as it is
    /// written), `direction` "up" or "down": the
    /// branch a sweep follows, with its jumps and folds (as `nlsdof frf`).
    /// With a sequence of levels, one `Sweep` per level (computed in
    /// parallel).
    #[pyo3(signature = (gamma, f_hz, direction="up", formulation="hb"))]
    fn sweep<'py>(
        &self,
        py: Python<'py>,
        gamma: &Bound<'py, PyAny>,
        f_hz: &Bound<'py, PyAny>,
        direction: &str,
        formulation: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let dir = crate::convert::direction(direction)?;
        let form = crate::convert::formulation(formulation)?;
        let req = SweepArgs::new(gamma, f_hz, dir)?;
        let model = &self.inner;
        let gain = self.steady_gain()?;
        let model_gammas: Vec<f64> = req.gammas.iter().map(|g| gain * g).collect();
        let levels = py
            .detach(|| level_responses(model, &model_gammas, &req.omegas, dir, form))
            .map_err(value_error)?;
        let out: Vec<Sweep> = levels
            .into_iter()
            .zip(&req.gammas)
            .map(|(mut level, &g)| {
                // the level as given; the model saw gain * gamma
                level.gamma = g;
                level
            })
            .map(|level| Sweep {
                model: self.inner,
                level,
                formulation: form,
                band: req.band,
            })
            .collect();
        req.one_or_list(py, out)
    }

    /// Multi-harmonic balance with `harmonics` harmonics (the constant and
    /// even terms included; alternating frequency/time forces, analytic
    /// Jacobian, pseudo-arclength continuation through the folds, Hill
    /// stability), as `nlsdof frf --harmonics H`: the branch a stepped-sine
    /// sweep at level `gamma` (m/s^2, zero-to-peak) follows over `f_hz` (Hz).
    /// With a sequence of levels, one `HarmonicSweep` per level.
    #[pyo3(signature = (gamma, f_hz, harmonics, direction="up"))]
    fn harmonic_sweep<'py>(
        &self,
        py: Python<'py>,
        gamma: &Bound<'py, PyAny>,
        f_hz: &Bound<'py, PyAny>,
        harmonics: usize,
        direction: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let dir = crate::convert::direction(direction)?;
        let req = SweepArgs::new(gamma, f_hz, dir)?;
        let model = &self.inner;
        let gain = self.steady_gain()?;
        let model_gammas: Vec<f64> = req.gammas.iter().map(|g| gain * g).collect();
        let levels = py
            .detach(|| {
                nlsdof::multi_harmonic::level_sweeps(
                    model,
                    &model_gammas,
                    &req.omegas,
                    dir,
                    harmonics,
                )
            })
            .map_err(value_error)?;
        let out: Vec<HarmonicSweep> = levels
            .into_iter()
            .zip(&req.gammas)
            .map(|(mut level, &g)| {
                level.gamma = g;
                level
            })
            .map(|level| HarmonicSweep {
                model: self.inner,
                level,
                harmonics,
                steps: req.band.2,
            })
            .collect();
        req.one_or_list(py, out)
    }

    /// How wrong the first-order balance is (`nlsdof hb-error`): the
    /// resonance peak and the folds over [`f_min`, `f_max`] Hz (default 0.8
    /// to 2 f_n) at level `gamma` for H = 1, 3, 5, ... up to `h_max`, until
    /// successive H agree to `tol`; errors relative to the converged H.
    /// Returns the level's entry of `nlsdof hb-error --json`.
    #[pyo3(signature = (gamma, f_min=None, f_max=None, tol=1e-6, h_max=63))]
    fn hb_error<'py>(
        &self,
        py: Python<'py>,
        gamma: f64,
        f_min: Option<f64>,
        f_max: Option<f64>,
        tol: f64,
        h_max: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        use nlsdof::multi_harmonic::truncation::{truncation_study, HARMONIC_LADDER};
        let fn_hz = self.inner.omega_n() / TAU;
        let (f0, f1) = (f_min.unwrap_or(0.8 * fn_hz), f_max.unwrap_or(2.0 * fn_hz));
        if !(f0.is_finite() && f1.is_finite() && 0.0 < f0 && f0 < f1) {
            return Err(value_error(format!(
                "f_min {f0} / f_max {f1}: need 0 < f_min < f_max (Hz)"
            )));
        }
        if h_max == 0 || h_max > 63 {
            return Err(value_error(format!(
                "h_max {h_max} is not allowed: need an integer from 1 to 63"
            )));
        }
        let ladder: Vec<usize> = HARMONIC_LADDER
            .iter()
            .copied()
            .filter(|&h| h <= h_max)
            .collect();
        let n = self.inner.normalised().map_err(value_error)?;
        let gain = self.steady_gain()?;
        let study = py
            .detach(|| {
                truncation_study(
                    &n,
                    gain * gamma,
                    TAU * f0,
                    TAU * f1,
                    &ladder,
                    tol,
                    nlsdof::multi_harmonic::settings_for(&n),
                    &nlsdof::multi_harmonic::ContinuationOptions::default(),
                )
            })
            .map_err(value_error)?;
        let req = nlsdof_report::truncation::StudyRequest {
            model_name: "",
            f_min: f0,
            f_max: f1,
            tol,
        };
        let doc = nlsdof_report::truncation::study_json(&req, &self.inner, &[(gamma, study)]);
        to_py(py, &doc["levels"][0])
    }

    /// Simulates Eq 32 driven by the input acceleration `u` (m/s^2) sampled
    /// at `fs` Hz, from `x0` (m), `v0` (m/s). `method`: "rk4" (default: RK4
    /// with h = 1/(2 fs) on the input read as cubics through the samples;
    /// `samples_per_step=1|2` drives RK4 by the samples themselves) or
    /// "dopri" (adaptive Dormand-Prince 5(4), `rtol`, `atol`). `base=True`:
    /// `u` is a base acceleration and x the relative displacement (the
    /// structure sees -u). With a `signal` map the model sees
    /// `input_gain * (u + input_offset)` (as `nlsdof simulate`; the recorded
    /// output is `x + signal["output_offset"]`). Returns a `Simulation` that
    /// unpacks as numpy arrays `x, v` at every sample, in m and m/s; the same
    /// numbers as `nlsdof simulate`. `check=True` (default, as the CLI): the
    /// integration error is estimated as the CLI does (step doubling on the
    /// whole record, the Richardson factor of the law's order; for a method
    /// other than the default, also its distance to the default reading of
    /// the input) into `Simulation.integration_error`, and above 1e-3 of
    /// max |x| a `RuntimeWarning` is given with the CLI's warning text (also
    /// `Simulation.warning`). It costs about twice the work of the default
    /// run itself; `check=False` skips it (many calls on a known-good
    /// sampling).
    #[pyo3(signature = (u, fs, method="rk4", base=false, x0=0.0, v0=0.0, samples_per_step=None, rtol=1e-10, atol=1e-13, check=true))]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        fs: f64,
        method: &str,
        base: bool,
        x0: f64,
        v0: f64,
        samples_per_step: Option<usize>,
        rtol: f64,
        atol: f64,
        check: bool,
    ) -> PyResult<Simulation> {
        let record = match (method.to_ascii_lowercase().as_str(), samples_per_step) {
            ("rk4", None) => RecordMethod::Rk4Cubic,
            ("rk4", Some(s)) => RecordMethod::Rk4 {
                samples_per_step: s,
            },
            ("dopri", None) => RecordMethod::DormandPrince { rtol, atol },
            ("dopri", Some(_)) => {
                return Err(value_error(
                    "samples_per_step applies to method=\"rk4\" only",
                ))
            }
            _ => {
                return Err(value_error(format!(
                    "method {method:?} is not allowed: use \"rk4\" or \"dopri\""
                )))
            }
        };
        let arr = f64_array(u, "u")?;
        let mut u = values(&arr);
        let map = self.signal.unwrap_or_default();
        let gain = if base { -1.0 } else { 1.0 } * map.input_gain;
        if map.input_offset != 0.0 {
            // as `nlsdof simulate`: the offset is added to the samples
            for v in u.to_mut().iter_mut() {
                *v += map.input_offset;
            }
        }
        let model = &self.inner;
        // a model file that states its input reconstruction and RK4
        // substeps ([signal] input_interpolation, substeps, written by
        // fit-time) is integrated as fit-time did, as `nlsdof simulate` does
        let stated = self
            .signal
            .filter(|_| matches!(record, RecordMethod::Rk4Cubic))
            .and_then(|m| m.stated_discretisation());
        if let Some(d) = stated {
            let nm = model.as_normalised().map_err(value_error)?;
            let tm = TimeModel {
                model: nm,
                gain,
                input_offset: 0.0,
                output_offset: 0.0,
            };
            let initial = State { x: x0, v: v0 };
            let (x, v, error) = py
                .detach(|| {
                    let (x, v) = simulate_states(&tm, &u, fs, initial, &d)?;
                    let error = if check && x.len() >= 2 {
                        Some(stated_integration_error(&tm, &u, fs, initial, &d, &x)?)
                    } else {
                        None
                    };
                    Ok::<_, nlsdof::identification::time_domain::TimeFitError>((x, v, error))
                })
                .map_err(value_error)?;
            return self.simulation(py, x, v, error, record);
        }
        // Ctrl-C stops it (KeyboardInterrupt): the default method and the
        // check poll the flag every 2^16 samples, "dopri" every 4096
        let (x, v, error) = crate::interrupt::run(py, None, "simulate", |cancel, _| {
            let mut x = Vec::with_capacity(u.len());
            let mut v = Vec::with_capacity(u.len());
            let mut sink = |s: Sample| {
                x.push(s.x);
                v.push(s.v);
            };
            let initial = State { x: x0, v: v0 };
            let grid = (gain, 0.0, fs);
            simulate_record_cancellable(model, &u, grid, record, initial, &mut sink, cancel)?;
            // the CLI's check (one implementation in the core): step
            // doubling on the whole record, for every method
            let error = if check {
                Some(nlsdof::simulation::record_error_estimate_cancellable(
                    model, &u, grid, record, initial, &x, cancel,
                )?)
            } else {
                None
            };
            Ok::<_, nlsdof::simulation::SimulationError>((x, v, error))
        })?
        .map_err(value_error)?;
        self.simulation(py, x, v, error, record)
    }

    /// The virtual stepped-sine rig: simulates the shaker dwell at each
    /// frequency `f_hz` (Hz) at level `gamma` (m/s^2, zero-to-peak) until
    /// the response is steady, and records the first-harmonic amplitude (m)
    /// and phase lag (deg), as `nlsdof stepped-sine`.
    #[pyo3(signature = (gamma, f_hz, direction="up", samples_per_cycle=64, tolerance=1e-4, max_cycles=5000))]
    #[allow(clippy::too_many_arguments)]
    fn stepped_sine(
        &self,
        py: Python<'_>,
        gamma: f64,
        f_hz: &Bound<'_, PyAny>,
        direction: &str,
        samples_per_cycle: usize,
        tolerance: f64,
        max_cycles: usize,
    ) -> PyResult<RigSweep> {
        let dir = crate::convert::direction(direction)?;
        let f = f64_array(f_hz, "f_hz")?;
        let omegas = sweep_omegas(&values(&f), dir)?;
        let opts = RigOptions {
            samples_per_cycle,
            tolerance,
            max_cycles,
            ..RigOptions::default()
        };
        let model = &self.inner;
        let gain = self.steady_gain()?;
        let sweeps = py
            .detach(|| run_sweeps(model, &[gain * gamma], &omegas, &[dir], &opts, &|| {}))
            .map_err(value_error)?;
        let Some(s) = sweeps.into_iter().next() else {
            return Err(value_error("the rig returned no sweep"));
        };
        let pts = &s.points;
        Ok(RigSweep {
            gamma,
            f_hz: PyArray1::from_vec(py, pts.iter().map(|p| p.omega / TAU).collect()).unbind(),
            amplitude: PyArray1::from_vec(py, pts.iter().map(|p| p.amplitude).collect()).unbind(),
            phase_deg: PyArray1::from_vec(py, pts.iter().map(|p| p.phase.to_degrees()).collect())
                .unbind(),
            settled: PyArray1::from_vec(py, pts.iter().map(|p| p.settled).collect::<Vec<bool>>())
                .unbind(),
            cycles: PyArray1::from_vec(
                py,
                pts.iter().map(|p| p.cycles as u64).collect::<Vec<u64>>(),
            )
            .unbind(),
            integration_error: pts.iter().map(|p| p.integration_error).fold(0.0, f64::max),
            simulated_s: s.duration,
            n: pts.len(),
        })
    }
}

/// The levels and frequencies of a sweep call: `gamma` a number (one
/// result) or a sequence (a list of results), `f_hz` in Hz.
struct SweepArgs {
    gammas: Vec<f64>,
    one: bool,
    omegas: Vec<f64>,
    /// f_min, f_max (Hz), steps.
    band: (f64, f64, usize),
}

/// The frequencies of a sweep (Hz) as increasing angular frequencies:
/// finite, > 0 and strictly increasing, or, for a down-sweep, strictly
/// decreasing as a sweep down is written (then reversed: the sweep runs
/// down either way). Every message is in Hz, as given.
fn sweep_omegas(f: &[f64], dir: nlsdof::SweepDirection) -> PyResult<Vec<f64>> {
    if f.is_empty() {
        return Err(value_error("f_hz is empty: give at least one frequency"));
    }
    for (i, &x) in f.iter().enumerate() {
        if !(x.is_finite() && x > 0.0) {
            return Err(value_error(format!(
                "f_hz[{i}] = {x} Hz: every frequency must be finite and > 0"
            )));
        }
    }
    let increasing = f.windows(2).all(|w| w[1] > w[0]);
    let decreasing = f.windows(2).all(|w| w[1] < w[0]);
    let mut f = f.to_vec();
    if !increasing {
        if decreasing && dir == nlsdof::SweepDirection::Down {
            f.reverse();
        } else {
            let i = (1..f.len())
                .find(|&i| {
                    if dir == nlsdof::SweepDirection::Down && f[1] < f[0] {
                        f[i] >= f[i - 1]
                    } else {
                        f[i] <= f[i - 1]
                    }
                })
                .unwrap_or(1);
            let want = if dir == nlsdof::SweepDirection::Down {
                "strictly increasing or strictly decreasing"
            } else {
                "strictly increasing (for a sweep down, pass direction=\"down\")"
            };
            return Err(value_error(format!(
                "f_hz[{i}] = {} Hz after f_hz[{}] = {} Hz: the frequencies must be {want}",
                f[i],
                i - 1,
                f[i - 1]
            )));
        }
    }
    Ok(f.iter().map(|x| TAU * x).collect())
}

impl SweepArgs {
    fn new(
        gamma: &Bound<'_, PyAny>,
        f_hz: &Bound<'_, PyAny>,
        dir: nlsdof::SweepDirection,
    ) -> PyResult<Self> {
        let (gammas, one) = match gamma.extract::<f64>() {
            Ok(g) => (vec![g], true),
            Err(_) => (values(&f64_array(gamma, "gamma")?).into_owned(), false),
        };
        let f = f64_array(f_hz, "f_hz")?;
        let omegas = sweep_omegas(&values(&f), dir)?;
        let n = omegas.len();
        Ok(Self {
            gammas,
            one,
            band: (omegas[0] / TAU, omegas[n - 1] / TAU, n),
            omegas,
        })
    }

    /// One object for one level, else the list.
    fn one_or_list<'py, T>(&self, py: Python<'py>, out: Vec<T>) -> PyResult<Bound<'py, PyAny>>
    where
        T: pyo3::PyClass + Into<pyo3::PyClassInitializer<T>>,
    {
        let mut items = Vec::with_capacity(out.len());
        for t in out {
            items.push(Bound::new(py, t)?.into_any());
        }
        if self.one && items.len() == 1 {
            Ok(items.remove(0))
        } else {
            Ok(pyo3::types::PyList::new(py, items)?.into_any())
        }
    }
}

/// The jumps of a sweep for Python (frequencies in Hz).
fn jumps_of(jumps: &[nlsdof::Jump]) -> Vec<Jump> {
    jumps
        .iter()
        .map(|j| Jump {
            f_hz: j.omega / TAU,
            amplitude_before: j.amplitude_before,
            amplitude_after: j.amplitude_after,
        })
        .collect()
}

/// One steady state: amplitude (m, zero-to-peak), phase lag of x behind
/// the input (deg), and whether it is stable.
#[pyclass(frozen, name = "SteadyState", module = "nlsdof")]
pub struct SteadyState {
    #[pyo3(get)]
    amplitude: f64,
    #[pyo3(get)]
    phase_deg: f64,
    #[pyo3(get)]
    stable: bool,
}

#[pymethods]
impl SteadyState {
    fn __repr__(&self) -> String {
        format!(
            "SteadyState(amplitude={:?}, phase_deg={:?}, stable={})",
            self.amplitude,
            self.phase_deg,
            if self.stable { "True" } else { "False" }
        )
    }
}

/// A jump of a sweep: frequency (Hz) and the amplitudes (m) before and after.
#[pyclass(frozen, name = "Jump", module = "nlsdof")]
pub struct Jump {
    #[pyo3(get)]
    f_hz: f64,
    #[pyo3(get)]
    amplitude_before: f64,
    #[pyo3(get)]
    amplitude_after: f64,
}

#[pymethods]
impl Jump {
    fn __repr__(&self) -> String {
        format!(
            "Jump(f_hz={:?}, amplitude_before={:?}, amplitude_after={:?})",
            self.f_hz, self.amplitude_before, self.amplitude_after
        )
    }
}

/// A stepped-sine sweep of the first-order balance: numpy `f_hz`,
/// `amplitude` (m; NaN where the response is unbounded), `phase_deg` (NaN
/// where there is no motion) and `stable`; the `jumps`, the `folds_hz` and
/// the `phase_quadrature` point `(f_hz, amplitude)`. Built on access.
#[pyclass(frozen, name = "Sweep", module = "nlsdof")]
pub struct Sweep {
    model: nlsdof::Model,
    level: nlsdof::LevelResponse,
    formulation: nlsdof::Formulation,
    /// f_min, f_max (Hz), steps.
    band: (f64, f64, usize),
}

impl Sweep {
    fn column<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        f: impl Fn(&nlsdof::SweepPoint) -> T,
    ) -> Bound<'py, PyArray1<T>> {
        PyArray1::from_vec(py, self.level.sweep.points.iter().map(f).collect())
    }
}

#[pymethods]
impl Sweep {
    /// Input level, m/s^2 zero-to-peak.
    #[getter]
    fn gamma(&self) -> f64 {
        self.level.gamma
    }
    /// Frequencies, Hz.
    #[getter]
    fn f_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.omega / TAU)
    }
    /// Amplitudes followed by the sweep, m zero-to-peak (NaN: unbounded).
    #[getter]
    fn amplitude<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| if p.unbounded { f64::NAN } else { p.amplitude })
    }
    /// Phase lag of x behind the input, deg (NaN: no motion or unbounded).
    #[getter]
    fn phase_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| {
            if p.unbounded || p.sticking {
                f64::NAN
            } else {
                p.phase.to_degrees()
            }
        })
    }
    /// Whether the followed state is stable.
    #[getter]
    fn stable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.column(py, |p| p.stable)
    }
    /// The jumps of the sweep (list of `Jump`).
    #[getter]
    fn jumps(&self) -> Vec<Jump> {
        jumps_of(&self.level.sweep.jumps)
    }
    /// Fold (limit-point) frequencies in the band, Hz.
    #[getter]
    fn folds_hz(&self) -> Vec<f64> {
        self.level
            .sweep
            .folds
            .iter()
            .map(|f| f.omega / TAU)
            .collect()
    }
    /// The phase-quadrature (90 deg) point `(f_hz, amplitude)`, or None.
    #[getter]
    fn phase_quadrature(&self) -> Option<(f64, f64)> {
        self.level
            .phase_quadrature
            .map(|q| (q.omega / TAU, q.amplitude))
    }
    /// The level's entry of `nlsdof frf --json` (same keys and numbers).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let req = SweepRequest {
            model_name: "",
            direction: self.level.sweep.direction,
            formulation: self.formulation,
            steps: self.band.2,
            f_min: self.band.0,
            f_max: self.band.1,
            at: None,
        };
        let doc = sweep_json(&req, &self.model, std::slice::from_ref(&self.level));
        to_py(py, &doc["levels"][0])
    }

    fn __len__(&self) -> usize {
        self.level.sweep.points.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Sweep(gamma={:?}, {} points, {} jump(s), folds_hz={:?})",
            self.level.gamma,
            self.level.sweep.points.len(),
            self.level.sweep.jumps.len(),
            self.folds_hz()
        )
    }
}

/// A run of the virtual stepped-sine rig: numpy `f_hz`, `amplitude` (m),
/// `phase_deg`, `settled`, `cycles`; the largest estimated
/// `integration_error` (relative) and the `simulated_s` seconds.
#[pyclass(frozen, name = "RigSweep", module = "nlsdof")]
pub struct RigSweep {
    #[pyo3(get)]
    gamma: f64,
    #[pyo3(get)]
    f_hz: Py<PyArray1<f64>>,
    #[pyo3(get)]
    amplitude: Py<PyArray1<f64>>,
    #[pyo3(get)]
    phase_deg: Py<PyArray1<f64>>,
    #[pyo3(get)]
    settled: Py<PyArray1<bool>>,
    #[pyo3(get)]
    cycles: Py<PyArray1<u64>>,
    #[pyo3(get)]
    integration_error: f64,
    #[pyo3(get)]
    simulated_s: f64,
    n: usize,
}

#[pymethods]
impl RigSweep {
    fn __repr__(&self) -> String {
        format!(
            "RigSweep(gamma={:?}, {} steps, {:.1} s simulated)",
            self.gamma, self.n, self.simulated_s
        )
    }
}

/// A multi-harmonic sweep: numpy `f_hz`, `amplitude` (first harmonic, m),
/// `phase_deg` (first harmonic), `stable` (Hill), `max_abs_x` (m),
/// `harmonic_amplitudes` (points x (H+1): orders 0..H, m); the `jumps`, the
/// `folds_hz`, a `warning` when the continuation stopped early, and
/// `to_dict()` (the level of `nlsdof frf --harmonics H --json`).
#[pyclass(frozen, name = "HarmonicSweep", module = "nlsdof")]
pub struct HarmonicSweep {
    model: nlsdof::Model,
    level: nlsdof::multi_harmonic::LevelSweep,
    harmonics: usize,
    steps: usize,
}

impl HarmonicSweep {
    fn column<'py, T: numpy::Element>(
        &self,
        py: Python<'py>,
        f: impl Fn(&nlsdof::multi_harmonic::sweep::MhbSweepPoint) -> T,
    ) -> Bound<'py, PyArray1<T>> {
        PyArray1::from_vec(py, self.level.sweep.points.iter().map(f).collect())
    }
}

#[pymethods]
impl HarmonicSweep {
    /// Input level, m/s^2 zero-to-peak.
    #[getter]
    fn gamma(&self) -> f64 {
        self.level.gamma
    }
    /// Number of harmonics H.
    #[getter]
    fn harmonics(&self) -> usize {
        self.harmonics
    }
    /// Frequencies, Hz.
    #[getter]
    fn f_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.omega / TAU)
    }
    /// First-harmonic amplitude, m.
    #[getter]
    fn amplitude<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| {
            nlsdof::multi_harmonic::harmonic_amplitude(&p.coefficients, 1)
        })
    }
    /// First-harmonic phase lag, deg.
    #[getter]
    fn phase_deg<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| {
            nlsdof::multi_harmonic::harmonic_phase(&p.coefficients, 1).to_degrees()
        })
    }
    /// Hill stability of each point.
    #[getter]
    fn stable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        self.column(py, |p| p.stable)
    }
    /// max |x(t)| over a period, m.
    #[getter]
    fn max_abs_x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| {
            nlsdof::multi_harmonic::max_abs_displacement(&p.coefficients)
        })
    }
    /// Amplitudes of the harmonics 0..H at every point, m: shape (points, H+1).
    #[getter]
    fn harmonic_amplitudes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let h = self.harmonics;
        let pts = &self.level.sweep.points;
        let v: Vec<f64> = pts
            .iter()
            .flat_map(|p| {
                (0..=h).map(move |k| nlsdof::multi_harmonic::harmonic_amplitude(&p.coefficients, k))
            })
            .collect();
        Ok(PyArray1::from_vec(py, v)
            .reshape([pts.len(), h + 1])?
            .into_any())
    }
    /// The jumps (first-harmonic amplitudes before and after).
    #[getter]
    fn jumps(&self) -> Vec<Jump> {
        jumps_of(&self.level.sweep.jumps)
    }
    /// Limit points of the branch, Hz.
    #[getter]
    fn folds_hz(&self) -> Vec<f64> {
        self.level.sweep.folds.iter().map(|f| f.0 / TAU).collect()
    }
    /// Why the continuation stopped early (the curve is then partial), or None.
    #[getter]
    fn warning(&self) -> Option<String> {
        self.level.sweep.warning.as_ref().map(|w| w.to_string())
    }
    /// The level's entry of `nlsdof frf --harmonics H --json`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let req = nlsdof_report::multi_harmonic::HarmonicSweepRequest {
            model_name: "",
            direction: self.level.sweep.direction,
            steps: self.steps,
            harmonics: self.harmonics,
        };
        let doc = nlsdof_report::multi_harmonic::sweep_json(
            &req,
            &self.model,
            std::slice::from_ref(&self.level),
        );
        to_py(py, &doc["levels"][0])
    }
    fn __len__(&self) -> usize {
        self.level.sweep.points.len()
    }
    fn __repr__(&self) -> String {
        format!(
            "HarmonicSweep(gamma={:?}, H={}, {} points, {} jump(s))",
            self.level.gamma,
            self.harmonics,
            self.level.sweep.points.len(),
            self.level.sweep.jumps.len()
        )
    }
}

impl Model {
    /// The `Simulation` of `simulate`, with the CLI's warning (the same
    /// text) given as a RuntimeWarning at the caller's line (level 1: the
    /// method has no Python frame of its own).
    fn simulation(
        &self,
        py: Python<'_>,
        x: Vec<f64>,
        v: Vec<f64>,
        error: Option<nlsdof::simulation::IntegrationError>,
        record: RecordMethod,
    ) -> PyResult<Simulation> {
        let warning = error
            .as_ref()
            .and_then(|e| nlsdof::simulation::integration_warning(e, record));
        if let Some(msg) = &warning {
            let warn = py.import("warnings")?;
            let cat = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
            warn.call_method1("warn", (msg.as_str(), cat, 1))?;
        }
        Ok(Simulation::new(
            x.len(),
            PyArray1::from_vec(py, x).unbind(),
            PyArray1::from_vec(py, v).unbind(),
            error.map(|e| e.estimate),
            warning,
        ))
    }
}
