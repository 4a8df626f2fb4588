//! Universal File Format dataset 58/58b (`nlsdof_io::uff58`): `read_uff`
//! and `write_uff`, one dict per function.
//!
//! A dict holds the header fields under the names of
//! `nlsdof_io::uff58::Uff58Header` (`id1`..`id5`, `function_type`,
//! `function_id`, `version`, `load_case`, `response_entity`,
//! `response_node`, `response_direction`, `reference_entity`,
//! `reference_node`, `reference_direction`, `z_axis_value`) and the four
//! axes `abscissa_axis`, `ordinate_axis`, `denominator_axis`, `z_axis`
//! (dicts of `specific_data_type`, `length_exponent`, `force_exponent`,
//! `temperature_exponent`, `label`, `units`); the abscissa as
//! `abscissa_spacing` (1 even, 0 uneven), `abscissa_min`,
//! `abscissa_increment` and the numpy array `x` of every abscissa value;
//! the ordinate as the numpy array `y` (float64, or complex128 for a
//! complex function). `read_uff` adds what it read about the storage:
//! `index` (among the file's dataset-58 functions, from 0), `block` (among
//! all its datasets), `binary`, `ordinate_type`, `precision`, `complex`,
//! `points` and `function_type_name`; `write_uff` accepts and ignores
//! those, so a dict read can be written back.

use crate::arrays::{f64_array, values};
use crate::convert::value_error;
use nlsdof_io::uff58::{
    function_type_name, read, read_headers, write_ascii_file, write_binary_file, Abscissa,
    AxisInfo, Encoding, Precision, Uff58Data, Uff58Dataset, Uff58Header, Uff58Info,
};
use numpy::{Complex64, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

const AXES: [&str; 4] = [
    "abscissa_axis",
    "ordinate_axis",
    "denominator_axis",
    "z_axis",
];
const AXIS_KEYS: [&str; 6] = [
    "specific_data_type",
    "length_exponent",
    "force_exponent",
    "temperature_exponent",
    "label",
    "units",
];
/// Keys `read_uff` adds that `write_uff` ignores.
const READ_ONLY: [&str; 8] = [
    "index",
    "block",
    "binary",
    "ordinate_type",
    "precision",
    "complex",
    "points",
    "function_type_name",
];
const TEXT_KEYS: [&str; 7] = [
    "id1",
    "id2",
    "id3",
    "id4",
    "id5",
    "response_entity",
    "reference_entity",
];
const INT_KEYS: [&str; 8] = [
    "function_type",
    "function_id",
    "version",
    "load_case",
    "response_node",
    "response_direction",
    "reference_node",
    "reference_direction",
];

fn axis_dict<'py>(py: Python<'py>, a: &AxisInfo) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("specific_data_type", a.specific_data_type)?;
    d.set_item("length_exponent", a.length_exponent)?;
    d.set_item("force_exponent", a.force_exponent)?;
    d.set_item("temperature_exponent", a.temperature_exponent)?;
    d.set_item("label", &a.label)?;
    d.set_item("units", &a.units)?;
    Ok(d)
}

fn header_dict<'py>(
    py: Python<'py>,
    info: &Uff58Info,
    h: &Uff58Header,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("index", info.index)?;
    d.set_item("block", info.block)?;
    d.set_item("binary", matches!(info.encoding, Encoding::Binary { .. }))?;
    d.set_item("ordinate_type", info.ordinate_type)?;
    d.set_item(
        "precision",
        match info.precision {
            Precision::Single => "single",
            Precision::Double => "double",
        },
    )?;
    d.set_item("complex", info.complex)?;
    d.set_item("points", info.points)?;
    for (k, v) in [
        ("id1", &h.id1),
        ("id2", &h.id2),
        ("id3", &h.id3),
        ("id4", &h.id4),
        ("id5", &h.id5),
    ] {
        d.set_item(k, v)?;
    }
    d.set_item("function_type", h.function_type)?;
    d.set_item("function_type_name", function_type_name(h.function_type))?;
    d.set_item("function_id", h.function_id)?;
    d.set_item("version", h.version)?;
    d.set_item("load_case", h.load_case)?;
    d.set_item("response_entity", &h.response_entity)?;
    d.set_item("response_node", h.response_node)?;
    d.set_item("response_direction", h.response_direction)?;
    d.set_item("reference_entity", &h.reference_entity)?;
    d.set_item("reference_node", h.reference_node)?;
    d.set_item("reference_direction", h.reference_direction)?;
    d.set_item("z_axis_value", h.z_axis_value)?;
    for (k, a) in AXES.iter().zip([
        &h.abscissa_axis,
        &h.ordinate_axis,
        &h.denominator_axis,
        &h.z_axis,
    ]) {
        d.set_item(*k, axis_dict(py, a)?)?;
    }
    d.set_item("abscissa_spacing", info.abscissa_spacing)?;
    d.set_item("abscissa_min", info.abscissa_min)?;
    d.set_item("abscissa_increment", info.abscissa_increment)?;
    Ok(d)
}

/// Whether the function at `index` with `header` is chosen by `dataset`:
/// None every one, an int its index (from 0), a str text of ID line 1.
enum Choice {
    All,
    Index(usize),
    Text(String),
}

impl Choice {
    fn of(dataset: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let Some(d) = dataset else {
            return Ok(Choice::All);
        };
        if let Ok(i) = d.extract::<usize>() {
            return Ok(Choice::Index(i));
        }
        if let Ok(s) = d.extract::<String>() {
            return Ok(Choice::Text(s));
        }
        Err(value_error(format!(
            "dataset {}: give an index (int, from 0) or text of ID line 1 (str)",
            d.repr().map(|r| r.to_string()).unwrap_or_default()
        )))
    }

    fn matches(&self, index: usize, h: &Uff58Header) -> bool {
        match self {
            Choice::All => true,
            Choice::Index(i) => *i == index,
            Choice::Text(s) => h.id1.contains(s.as_str()),
        }
    }
}

/// Reads the dataset-58 functions (ASCII 58 and binary 58b) of a universal
/// file as a list of dicts (see the module documentation): header fields,
/// `x` (abscissa values, float64 array) and `y` (float64 or complex128
/// array). `dataset`: None (every function), an index among the file's
/// dataset-58 functions (from 0) or text contained in ID line 1 (every
/// match). `headers_only=True` skips the data (no `x`, `y`). Values are as
/// stored: no unit conversion. Raises ValueError for an unreadable file.
#[pyfunction]
#[pyo3(signature = (path, dataset=None, headers_only=false))]
pub fn read_uff<'py>(
    py: Python<'py>,
    path: PathBuf,
    dataset: Option<&Bound<'py, PyAny>>,
    headers_only: bool,
) -> PyResult<Bound<'py, PyList>> {
    let choice = Choice::of(dataset)?;
    let out = PyList::empty(py);
    if headers_only {
        let entries = py.detach(|| read_headers(&path)).map_err(value_error)?;
        for e in entries
            .iter()
            .filter(|e| choice.matches(e.info.index, &e.header))
        {
            out.append(header_dict(py, &e.info, &e.header)?)?;
        }
        return Ok(out);
    }
    let all = py.detach(|| read(&path)).map_err(value_error)?;
    for f in all
        .iter()
        .filter(|f| choice.matches(f.info.index, &f.dataset.header))
    {
        let d = header_dict(py, &f.info, &f.dataset.header)?;
        d.set_item("x", PyArray1::from_vec(py, f.dataset.abscissa_values()))?;
        match &f.dataset.data {
            Uff58Data::Real(v) => d.set_item("y", PyArray1::from_vec(py, v.clone()))?,
            Uff58Data::Complex(v) => d.set_item(
                "y",
                PyArray1::from_vec(
                    py,
                    v.iter().map(|&(re, im)| Complex64::new(re, im)).collect(),
                ),
            )?,
        }
        out.append(d)?;
    }
    Ok(out)
}

fn get<'py>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
    Ok(d.get_item(key)?.filter(|v| !v.is_none()))
}

fn extract<'py, T: for<'a> FromPyObject<'a, 'py>>(
    n: usize,
    key: &str,
    v: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<T> {
    v.extract::<T>().map_err(|_| {
        value_error(format!(
            "datasets[{n}]: {key} = {} is not {what}",
            v.repr().map(|r| r.to_string()).unwrap_or_default()
        ))
    })
}

fn axis_of(n: usize, key: &str, v: &Bound<'_, PyAny>) -> PyResult<AxisInfo> {
    let d = v
        .cast::<PyDict>()
        .map_err(|_| value_error(format!("datasets[{n}]: {key} must be a dict")))?;
    let mut a = AxisInfo::default();
    for (k, item) in d.iter() {
        let k: String = k
            .extract()
            .map_err(|_| value_error(format!("datasets[{n}]: {key}: keys must be str")))?;
        let name = format!("{key}['{k}']");
        match k.as_str() {
            "specific_data_type" => a.specific_data_type = extract(n, &name, &item, "an int")?,
            "length_exponent" => a.length_exponent = extract(n, &name, &item, "an int")?,
            "force_exponent" => a.force_exponent = extract(n, &name, &item, "an int")?,
            "temperature_exponent" => a.temperature_exponent = extract(n, &name, &item, "an int")?,
            "label" => a.label = extract(n, &name, &item, "a str")?,
            "units" => a.units = extract(n, &name, &item, "a str")?,
            _ => {
                return Err(value_error(format!(
                    "datasets[{n}]: {key}: unknown key '{k}' (keys: {})",
                    AXIS_KEYS.join(", ")
                )))
            }
        }
    }
    Ok(a)
}

fn dataset_of(n: usize, obj: &Bound<'_, PyAny>) -> PyResult<Uff58Dataset> {
    let d = obj
        .cast::<PyDict>()
        .map_err(|_| value_error(format!("datasets[{n}] must be a dict")))?;
    let mut h = Uff58Header::default();
    let known = |k: &str| {
        TEXT_KEYS.contains(&k)
            || INT_KEYS.contains(&k)
            || AXES.contains(&k)
            || READ_ONLY.contains(&k)
            || [
                "z_axis_value",
                "abscissa_spacing",
                "abscissa_min",
                "abscissa_increment",
                "x",
                "y",
            ]
            .contains(&k)
    };
    for (k, v) in d.iter() {
        let k: String = k
            .extract()
            .map_err(|_| value_error(format!("datasets[{n}]: keys must be str")))?;
        if !known(&k) {
            return Err(value_error(format!(
                "datasets[{n}]: unknown key '{k}' (header fields as read_uff returns them, x, y)"
            )));
        }
        if v.is_none() {
            continue;
        }
        match k.as_str() {
            "id1" => h.id1 = extract(n, &k, &v, "a str")?,
            "id2" => h.id2 = extract(n, &k, &v, "a str")?,
            "id3" => h.id3 = extract(n, &k, &v, "a str")?,
            "id4" => h.id4 = extract(n, &k, &v, "a str")?,
            "id5" => h.id5 = extract(n, &k, &v, "a str")?,
            "response_entity" => h.response_entity = extract(n, &k, &v, "a str")?,
            "reference_entity" => h.reference_entity = extract(n, &k, &v, "a str")?,
            "function_type" => h.function_type = extract(n, &k, &v, "an int")?,
            "function_id" => h.function_id = extract(n, &k, &v, "an int")?,
            "version" => h.version = extract(n, &k, &v, "an int")?,
            "load_case" => h.load_case = extract(n, &k, &v, "an int")?,
            "response_node" => h.response_node = extract(n, &k, &v, "an int")?,
            "response_direction" => h.response_direction = extract(n, &k, &v, "an int")?,
            "reference_node" => h.reference_node = extract(n, &k, &v, "an int")?,
            "reference_direction" => h.reference_direction = extract(n, &k, &v, "an int")?,
            "z_axis_value" => h.z_axis_value = extract(n, &k, &v, "a number")?,
            "abscissa_axis" => h.abscissa_axis = axis_of(n, &k, &v)?,
            "ordinate_axis" => h.ordinate_axis = axis_of(n, &k, &v)?,
            "denominator_axis" => h.denominator_axis = axis_of(n, &k, &v)?,
            "z_axis" => h.z_axis = axis_of(n, &k, &v)?,
            _ => {}
        }
    }
    let y = get(d, "y")?
        .ok_or_else(|| value_error(format!("datasets[{n}]: no 'y' (ordinate values)")))?;
    let np = d.py().import("numpy")?;
    let complex: bool = np.call_method1("iscomplexobj", (&y,))?.extract()?;
    let name = format!("datasets[{n}]['y']");
    let data = if complex {
        let re = f64_array(&np.call_method1("real", (&y,))?, &name)?;
        let im = f64_array(&np.call_method1("imag", (&y,))?, &name)?;
        Uff58Data::Complex(
            values(&re)
                .iter()
                .copied()
                .zip(values(&im).iter().copied())
                .collect(),
        )
    } else {
        let v = f64_array(&y, &name)?;
        Uff58Data::Real(values(&v).into_owned())
    };
    let spacing: Option<i32> = match get(d, "abscissa_spacing")? {
        Some(v) => Some(extract(
            n,
            "abscissa_spacing",
            &v,
            "0 (uneven) or 1 (even)",
        )?),
        None => None,
    };
    let x = get(d, "x")?;
    let even = |d: &Bound<'_, PyDict>| -> PyResult<Abscissa> {
        let num = |k: &str| -> PyResult<f64> {
            let v = get(d, k)?.ok_or_else(|| {
                value_error(format!(
                    "datasets[{n}]: an even abscissa needs abscissa_min and abscissa_increment"
                ))
            })?;
            extract(n, k, &v, "a number")
        };
        Ok(Abscissa::Even {
            start: num("abscissa_min")?,
            step: num("abscissa_increment")?,
        })
    };
    let abscissa = match (spacing, &x) {
        (Some(1), _) => even(d)?,
        (Some(0), Some(x)) | (None, Some(x)) => {
            let xa = f64_array(x, &format!("datasets[{n}]['x']"))?;
            Abscissa::Uneven(values(&xa).into_owned())
        }
        (Some(0), None) => {
            return Err(value_error(format!(
                "datasets[{n}]: abscissa_spacing 0 (uneven) needs 'x'"
            )))
        }
        (None, None) => even(d)?,
        (Some(s), _) => {
            return Err(value_error(format!(
                "datasets[{n}]: abscissa_spacing {s} must be 0 (uneven) or 1 (even)"
            )))
        }
    };
    if let Abscissa::Uneven(xs) = &abscissa {
        if xs.len() != data.len() {
            return Err(value_error(format!(
                "datasets[{n}]: x has {} values but y has {}",
                xs.len(),
                data.len()
            )));
        }
    }
    Ok(Uff58Dataset {
        header: h,
        abscissa,
        data,
    })
}

/// Writes `datasets` (dicts as `read_uff` returns them; see the module
/// documentation) to a universal file: ASCII dataset 58 in double precision
/// (`binary=False`, fields of 12 to 14 significant digits, abscissa
/// minimum, increment and uneven x values of 7) or binary 58b (bit-exact
/// little endian doubles). Missing header fields take their defaults
/// (`NONE`, 0); `y` real or complex; the abscissa even from
/// `abscissa_min`/`abscissa_increment` when `abscissa_spacing` is 1 or there
/// is no `x`, else uneven from `x`. Written atomically; raises ValueError
/// (naming the dataset and field) before anything is written.
#[pyfunction]
#[pyo3(signature = (path, datasets, binary=false))]
pub fn write_uff(
    py: Python<'_>,
    path: PathBuf,
    datasets: &Bound<'_, PyAny>,
    binary: bool,
) -> PyResult<()> {
    let items: Vec<Bound<'_, PyAny>> = if let Ok(d) = datasets.cast::<PyDict>() {
        vec![d.clone().into_any()]
    } else {
        datasets
            .try_iter()
            .map_err(|_| value_error("datasets must be a list of dicts"))?
            .collect::<PyResult<_>>()?
    };
    let sets = items
        .iter()
        .enumerate()
        .map(|(n, o)| dataset_of(n, o))
        .collect::<PyResult<Vec<_>>>()?;
    py.detach(|| {
        if binary {
            write_binary_file(&path, &sets)
        } else {
            write_ascii_file(&path, &sets)
        }
    })
    .map_err(value_error)
}
