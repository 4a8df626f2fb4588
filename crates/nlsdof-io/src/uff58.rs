//! Universal File Format dataset 58 ("function at nodal DOF"), ASCII and
//! binary 58b: the measured functions (time responses, spectra, FRFs,
//! coherences) that vibration test systems (Siemens Testlab, m+p, B&K,
//! Polytec, Data Physics) exchange.
//!
//! Written by hand because no Rust crate reads or writes dataset 58; the
//! layout follows the SDRC/I-DEAS dataset description and the UC-SDRL note
//! on binary 58b, and is checked against files written and read by pyuff.
//!
//! ## A universal file
//!
//! A file is a sequence of datasets, each opened and closed by a line
//! `    -1` and starting with its dataset number (`    58`). Datasets of
//! other types (151 header, 164 units, 15/2411 nodes, ...) are skipped,
//! ASCII ones up to their closing `-1`, binary ones (`NNNNb` identifier) by
//! their declared byte count.
//!
//! ## Dataset 58
//!
//! | record | content | fields here |
//! |---|---|---|
//! | identifier | `    58`, or `    58b` + byte ordering (1 little, 2 big endian), floating point format (2 IEEE 754; DEC VMS and IBM 370 are refused), number of ASCII header lines (11), number of binary data bytes | [`Encoding`] |
//! | 1–5 | ID lines 1–5 (80 characters, `NONE` if unused) | [`Uff58Header::id1`] … `id5` |
//! | 6 | function type, function id, version/sequence number, load case, response entity name, node, direction, reference entity name, node, direction | [`Uff58Header`] |
//! | 7 | ordinate data type, number of points, abscissa spacing (1 even, 0 uneven), abscissa minimum, increment, z-axis value | [`Uff58Info`], [`Abscissa`], [`Uff58Header::z_axis_value`] |
//! | 8–11 | axis data characteristics of abscissa, ordinate numerator, ordinate denominator, z axis: specific data type, length, force and temperature unit exponents, axis label, units label | [`AxisInfo`] |
//! | 12 | data values | [`Uff58Data`], [`Abscissa::Uneven`] |
//!
//! **Ordinate data types** (record 7 field 1): 2 real single precision, 4
//! real double, 5 complex single, 6 complex double. Complex values are
//! stored as real–imaginary pairs; dataset 58 has no magnitude–phase
//! ordinate type. A program that exports magnitude or phase writes it as a
//! real function (type 2 or 4, with an axis label such as "Magnitude" or
//! "Phase"), which is read as [`Uff58Data::Real`]; any other code is an
//! error. Values are kept as written: an ASCII single precision value is the
//! decimal number of its field (not rounded to `f32`), a binary single
//! precision value the exact `f32` widened to `f64`.
//!
//! **Abscissa**: even spacing stores only the minimum and increment
//! (record 7, E13.5 fields); uneven spacing stores `x, y` (or `x, re, im`)
//! for each point in record 12, the abscissa in E13.5 fields too.
//!
//! **Units** are not converted: the unit exponents and labels of records
//! 8–11 are kept as read. For the SI unit system (the project's
//! convention) a file has the labels `s`, `Hz`, `m`, `m/s`, `m/s^2`, `N`.
//! Function types: [`function_type_name`]; specific data types:
//! [`specific_data_type_name`].
//!
//! ## Reading
//!
//! [`read`] (every function), [`read_selected`] (by index or header fields,
//! [`Uff58Select`]), [`read_headers`] (records 1–11 only, data skipped);
//! `parse*` do the same on bytes in memory. ASCII data fields are read in
//! the columns of the format (6E13.5, 4E20.12, 2(E13.5,E20.12),
//! E13.5,2E20.12), and a line whose fields do not fit those columns is
//! read as blank-separated numbers. Fortran `D` exponents are accepted.
//! ID lines, names and labels are trimmed; lines that are not UTF-8 are read
//! as Latin-1 (Windows programs write `µ`, `°`, `²` so).
//!
//! In binary 58b the data follow the 11 header lines directly, in the
//! precision of the ordinate type (an uneven abscissa in that precision too,
//! as pyuff writes it, or as 4-byte floats when the declared byte count says
//! so). The byte count of the data is the one record 7 implies; the one
//! declared in the identifier is not trusted (pyuff 2.5.8 declares 8 bytes
//! a point even for complex or uneven data), and a line end between the
//! data and the closing `-1` (written by some programs) is accepted.
//!
//! Errors ([`Uff58Error`], which converts into [`IoError`]) name the
//! file, the line, the dataset (index among the file's dataset 58 functions
//! and block number among all its datasets, both from 0 as
//! [`read_selected`] and pyuff count them), the record and the offending
//! text (escaped, at most 60 characters: binary bytes are never copied into
//! a message). A declared number of points is checked against the bytes
//! present before anything is allocated, and a file is limited to
//! [`MAX_FILE_BYTES`] and [`MAX_VALUES`].
//!
//! ## Writing
//!
//! [`write_ascii`] / [`write_ascii_file`]: ASCII dataset 58, double
//! precision (ordinate type 4 or 6), in the fixed columns of the format
//! (records 8–11 `I10,3I5,2(1X,20A1)`, data 4E20.12 / 2(E13.5,E20.12) /
//! E13.5,2E20.12) so that pyuff and commercial programs read it. Each field
//! holds the shortest decimal that reads back as the same `f64` when it
//! fits, and the value rounded to as many digits as fit otherwise:
//!
//! * a 20-column data field (with its leading blank) holds 12 to 14
//!   significant digits, by sign and exponent: values of up to 12 digits
//!   (everything read from an ASCII file: E20.12 holds 12) are written
//!   exactly, others within a relative 5e-13 (5e-12 for magnitudes beyond
//!   1e±99; 1e-11 next to the largest double, where the digits are cut
//!   lest they round to infinity);
//! * a 13-column field (record 7: even abscissa minimum and increment,
//!   z-axis value; an uneven abscissa) holds 5 to 7: values of up to 6
//!   digits (E13.5) exactly, others within 5e-6. A time step of 1/3000 s
//!   is kept to 7 digits.
//!
//! An exact copy of any double needs up to 17 digits, more than the 20
//! columns of the format: [`write_binary`] / [`write_binary_file`] write
//! 58b (little endian IEEE doubles), whose data are bit-exact (record 7
//! stays ASCII). A dataset the format cannot hold is refused before
//! anything is written ([`Uff58WriteError`], see [`write_ascii`]).

use crate::error::IoError;
use crate::text::{not_text, shown};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Largest file read: the whole file is held in memory while it is parsed,
/// so larger files are refused rather than risk exhausting memory.
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// Largest number of values (abscissa and ordinate numbers, 8 bytes each in
/// memory) of all functions of one file: 2^27, 1 GiB.
pub const MAX_VALUES: usize = 1 << 27;

// ------------------------------------------------------------------ types

/// How a dataset 58 is stored (identifier record).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// ASCII dataset 58: data values in fixed-width text fields.
    Ascii,
    /// Binary 58b: data values as IEEE 754 numbers after the ASCII header.
    Binary {
        /// Byte ordering field 2 (big endian) rather than 1 (little).
        big_endian: bool,
        /// Number of binary data bytes as declared in the identifier
        /// record (not trusted; see the module documentation).
        declared_bytes: u64,
    },
}

/// Precision of the stored values (record 7 field 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// Ordinate data type 2 or 5.
    Single,
    /// Ordinate data type 4 or 6.
    Double,
}

/// Axis data characteristics: one of records 8 (abscissa), 9 (ordinate or
/// ordinate numerator), 10 (ordinate denominator), 11 (z axis), format
/// `I10,3I5,2(1X,20A1)`. Exponents and labels are kept as in the file (no
/// unit conversion).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AxisInfo {
    /// Field 1: specific data type ([`specific_data_type_name`]: 0 unknown,
    /// 1 general, 8 displacement, 11 velocity, 12 acceleration, 13
    /// excitation force, 17 time, 18 frequency, ...).
    pub specific_data_type: i32,
    /// Field 2: length units exponent.
    pub length_exponent: i32,
    /// Field 3: force units exponent.
    pub force_exponent: i32,
    /// Field 4: temperature units exponent.
    pub temperature_exponent: i32,
    /// Field 5: axis label (`NONE` if unused), at most 20 characters.
    pub label: String,
    /// Field 6: axis units label (`NONE` if unused), at most 20 characters,
    /// e.g. `Hz`, `s`, `m/s^2`, `N`.
    pub units: String,
}

impl Default for AxisInfo {
    /// Specific data type 0 (unknown), exponents 0, labels `NONE`.
    fn default() -> Self {
        Self {
            specific_data_type: 0,
            length_exponent: 0,
            force_exponent: 0,
            temperature_exponent: 0,
            label: "NONE".into(),
            units: "NONE".into(),
        }
    }
}

impl AxisInfo {
    /// An axis of specific data type `specific_data_type` with a label and
    /// units label, exponents 0.
    pub fn new(specific_data_type: i32, label: &str, units: &str) -> Self {
        Self {
            specific_data_type,
            label: label.into(),
            units: units.into(),
            ..Self::default()
        }
    }
}

/// The descriptive fields of a dataset 58 (records 1–11, without the data
/// form of record 7 fields 1–5, which follows from the data).
#[derive(Debug, Clone, PartialEq)]
pub struct Uff58Header {
    /// Record 1: ID line 1, the function description (at most 80
    /// characters; `NONE` if unused).
    pub id1: String,
    /// Record 2: ID line 2 (run identification).
    pub id2: String,
    /// Record 3: ID line 3 (creation date and time).
    pub id3: String,
    /// Record 4: ID line 4 (load case name).
    pub id4: String,
    /// Record 5: ID line 5.
    pub id5: String,
    /// Record 6 field 1: function type ([`function_type_name`]: 1 time
    /// response, 2 auto spectrum, 3 cross spectrum, 4 FRF, 5
    /// transmissibility, 6 coherence, ...).
    pub function_type: i32,
    /// Record 6 field 2: function identification number.
    pub function_id: i64,
    /// Record 6 field 3: version number, or sequence number.
    pub version: i64,
    /// Record 6 field 4: load case identification number (0: single point
    /// excitation).
    pub load_case: i64,
    /// Record 6 field 5: response entity name (`NONE` if unused), at most
    /// 10 characters.
    pub response_entity: String,
    /// Record 6 field 6: response node.
    pub response_node: i64,
    /// Record 6 field 7: response direction (0 scalar, ±1..±3 X/Y/Z
    /// translation, ±4..±6 X/Y/Z rotation).
    pub response_direction: i32,
    /// Record 6 field 8: reference entity name (`NONE` if unused).
    pub reference_entity: String,
    /// Record 6 field 9: reference node.
    pub reference_node: i64,
    /// Record 6 field 10: reference direction (as the response direction).
    pub reference_direction: i32,
    /// Record 7 field 6: z-axis value (0 if unused).
    pub z_axis_value: f64,
    /// Record 8: abscissa data characteristics.
    pub abscissa_axis: AxisInfo,
    /// Record 9: ordinate (or ordinate numerator) data characteristics.
    pub ordinate_axis: AxisInfo,
    /// Record 10: ordinate denominator data characteristics.
    pub denominator_axis: AxisInfo,
    /// Record 11: z-axis data characteristics.
    pub z_axis: AxisInfo,
}

impl Default for Uff58Header {
    /// ID lines and entity names `NONE`, function type 0 (general), every
    /// number 0, axes [`AxisInfo::default`].
    fn default() -> Self {
        Self {
            id1: "NONE".into(),
            id2: "NONE".into(),
            id3: "NONE".into(),
            id4: "NONE".into(),
            id5: "NONE".into(),
            function_type: 0,
            function_id: 0,
            version: 0,
            load_case: 0,
            response_entity: "NONE".into(),
            response_node: 0,
            response_direction: 0,
            reference_entity: "NONE".into(),
            reference_node: 0,
            reference_direction: 0,
            z_axis_value: 0.0,
            abscissa_axis: AxisInfo::default(),
            ordinate_axis: AxisInfo::default(),
            denominator_axis: AxisInfo::default(),
            z_axis: AxisInfo::default(),
        }
    }
}

impl Uff58Header {
    /// The name of the function type (record 6 field 1).
    pub fn function_type_name(&self) -> &'static str {
        function_type_name(self.function_type)
    }
}

/// The abscissa (x values) of a function.
#[derive(Debug, Clone, PartialEq)]
pub enum Abscissa {
    /// Even spacing (record 7 field 3 = 1): `x_k = start + k * step`, from
    /// record 7 fields 4 (abscissa minimum) and 5 (increment).
    Even { start: f64, step: f64 },
    /// Uneven spacing (record 7 field 3 = 0): one x value a point, stored in
    /// record 12 before each ordinate value.
    Uneven(Vec<f64>),
}

/// The ordinate values of a function (record 12).
#[derive(Debug, Clone, PartialEq)]
pub enum Uff58Data {
    /// Ordinate data type 2 (single) or 4 (double precision).
    Real(Vec<f64>),
    /// Ordinate data type 5 or 6: `(re, im)` pairs.
    Complex(Vec<(f64, f64)>),
}

impl Uff58Data {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            Uff58Data::Real(v) => v.len(),
            Uff58Data::Complex(v) => v.len(),
        }
    }

    /// No point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One function: what [`write_ascii`] writes and [`read`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Uff58Dataset {
    /// Records 1–11 (descriptive fields).
    pub header: Uff58Header,
    /// Record 7 fields 3–5, or the x values of record 12.
    pub abscissa: Abscissa,
    /// Record 12 ordinate values.
    pub data: Uff58Data,
}

impl Uff58Dataset {
    /// A time response (function type 1) sampled evenly from `start` every
    /// `step` seconds: abscissa axis "Time" in `s` (specific data type 17).
    /// Set the ordinate axis ([`Uff58Header::ordinate_axis`]) and the
    /// response node and direction for the measured quantity.
    pub fn time_response(start: f64, step: f64, values: Vec<f64>) -> Self {
        Self {
            header: Uff58Header {
                function_type: 1,
                abscissa_axis: AxisInfo::new(17, "Time", "s"),
                ..Uff58Header::default()
            },
            abscissa: Abscissa::Even { start, step },
            data: Uff58Data::Real(values),
        }
    }

    /// A frequency response function (function type 4) of complex values
    /// `(re, im)` at the frequencies of `abscissa` (Hz): abscissa axis
    /// "Frequency" in `Hz` (specific data type 18). Set the ordinate
    /// numerator and denominator axes (e.g. 12 acceleration `m/s^2` over
    /// 13 excitation force `N`) and the nodes and directions.
    pub fn frf(abscissa: Abscissa, values: Vec<(f64, f64)>) -> Self {
        Self {
            header: Uff58Header {
                function_type: 4,
                abscissa_axis: AxisInfo::new(18, "Frequency", "Hz"),
                ..Uff58Header::default()
            },
            abscissa,
            data: Uff58Data::Complex(values),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// No point.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// The x value of every point (`start + k * step` for an even
    /// abscissa).
    pub fn abscissa_values(&self) -> Vec<f64> {
        match &self.abscissa {
            Abscissa::Even { start, step } => {
                (0..self.len()).map(|k| start + k as f64 * step).collect()
            }
            Abscissa::Uneven(x) => x.clone(),
        }
    }
}

/// Where and how a function is stored in its file (identifier record and
/// record 7 as read).
#[derive(Debug, Clone, PartialEq)]
pub struct Uff58Info {
    /// Position among the file's dataset 58 functions, from 0.
    pub index: usize,
    /// Position among all datasets of the file (other types included), from
    /// 0: pyuff's set number.
    pub block: usize,
    /// Line of the `-1` that opens the dataset, from 1.
    pub line: usize,
    /// ASCII 58 or binary 58b (identifier record).
    pub encoding: Encoding,
    /// Record 7 field 1: ordinate data type (2, 4, 5 or 6).
    pub ordinate_type: i32,
    /// Single or double precision, from the ordinate data type.
    pub precision: Precision,
    /// Complex ordinate (type 5 or 6), from the ordinate data type.
    pub complex: bool,
    /// Record 7 field 2: number of points (data values for an even
    /// abscissa, data pairs for an uneven one).
    pub points: usize,
    /// Record 7 field 3: abscissa spacing, 1 even, 0 uneven.
    pub abscissa_spacing: i32,
    /// Record 7 field 4: abscissa minimum (0 for an uneven abscissa).
    pub abscissa_min: f64,
    /// Record 7 field 5: abscissa increment (0 for an uneven abscissa).
    pub abscissa_increment: f64,
}

/// A function read from a file: how it was stored, and its content.
#[derive(Debug, Clone, PartialEq)]
pub struct Uff58Function {
    /// Storage (identifier record, record 7).
    pub info: Uff58Info,
    /// Header, abscissa and data.
    pub dataset: Uff58Dataset,
}

/// A function's header without its data ([`read_headers`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Uff58Entry {
    /// Storage (identifier record, record 7).
    pub info: Uff58Info,
    /// Records 1–11.
    pub header: Uff58Header,
}

/// Which functions [`read_selected`] returns: those matching every field
/// that is set (all of them when none is).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Uff58Select {
    /// Position among the file's dataset 58 functions, from 0.
    pub index: Option<usize>,
    /// Record 6 field 1.
    pub function_type: Option<i32>,
    /// Record 6 field 6.
    pub response_node: Option<i64>,
    /// Record 6 field 7.
    pub response_direction: Option<i32>,
    /// Record 6 field 9.
    pub reference_node: Option<i64>,
    /// Record 6 field 10.
    pub reference_direction: Option<i32>,
    /// Text contained in ID line 1 (record 1), case-sensitive.
    pub id1_contains: Option<String>,
}

impl Uff58Select {
    /// Whether the function at `index` with `header` is selected.
    pub fn matches(&self, index: usize, header: &Uff58Header) -> bool {
        fn ok<T: PartialEq>(want: &Option<T>, have: &T) -> bool {
            match want {
                None => true,
                Some(w) => w == have,
            }
        }
        ok(&self.index, &index)
            && ok(&self.function_type, &header.function_type)
            && ok(&self.response_node, &header.response_node)
            && ok(&self.response_direction, &header.response_direction)
            && ok(&self.reference_node, &header.reference_node)
            && ok(&self.reference_direction, &header.reference_direction)
            && match &self.id1_contains {
                None => true,
                Some(s) => header.id1.contains(s.as_str()),
            }
    }
}

/// The name of a function type code (record 6 field 1); `"unknown"` for a
/// code the format does not define.
pub fn function_type_name(code: i32) -> &'static str {
    match code {
        0 => "general or unknown",
        1 => "time response",
        2 => "auto spectrum",
        3 => "cross spectrum",
        4 => "frequency response function",
        5 => "transmissibility",
        6 => "coherence",
        7 => "auto correlation",
        8 => "cross correlation",
        9 => "power spectral density",
        10 => "energy spectral density",
        11 => "probability density function",
        12 => "spectrum",
        13 => "cumulative frequency distribution",
        14 => "peaks valley",
        15 => "stress/cycles",
        16 => "strain/cycles",
        17 => "orbit",
        18 => "mode indicator function",
        19 => "force pattern",
        20 => "partial power",
        21 => "partial coherence",
        22 => "eigenvalue",
        23 => "eigenvector",
        24 => "shock response spectrum",
        25 => "finite impulse response filter",
        26 => "multiple coherence",
        27 => "order function",
        _ => "unknown",
    }
}

/// The name of a specific data type code (records 8–11 field 1);
/// `"unknown"` for a code the format does not define.
pub fn specific_data_type_name(code: i32) -> &'static str {
    match code {
        1 => "general",
        2 => "stress",
        3 => "strain",
        5 => "temperature",
        6 => "heat flux",
        8 => "displacement",
        9 => "reaction force",
        11 => "velocity",
        12 => "acceleration",
        13 => "excitation force",
        15 => "pressure",
        16 => "mass",
        17 => "time",
        18 => "frequency",
        19 => "rpm",
        20 => "order",
        _ => "unknown",
    }
}

// ------------------------------------------------------------------ errors

/// Why a universal file cannot be read.
#[derive(Debug, Error)]
pub enum Uff58Error {
    /// The file cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file as a whole: empty, too large, not a universal file.
    #[error("{path}: {message}")]
    File { path: PathBuf, message: String },
    /// A dataset of another type, or the structure between datasets.
    #[error("{path}: line {line}: block {block}: {message}")]
    Block {
        path: PathBuf,
        line: usize,
        /// Position among all datasets of the file, from 0.
        block: usize,
        message: String,
    },
    /// A record of a dataset 58.
    #[error("{path}: line {line}: dataset 58 index {index} (block {block}), {record}: {message}")]
    Dataset {
        path: PathBuf,
        line: usize,
        /// Position among the file's dataset 58 functions, from 0.
        index: usize,
        /// Position among all datasets of the file, from 0.
        block: usize,
        /// The record, e.g. `record 7 (data form)`.
        record: &'static str,
        message: String,
    },
}

/// Why a dataset given to a writer cannot be written (before anything is
/// written): the dataset's position in the slice given, and the field.
#[derive(Debug, Clone, Error, PartialEq, Eq)]
#[error("cannot write dataset 58 index {index}: {message}")]
pub struct Uff58WriteError {
    /// Position of the dataset in the slice given to the writer, from 0.
    pub index: usize,
    /// The field and why, e.g. `response direction (record 6 field 7) 7 is
    /// not one of -6..6`.
    pub message: String,
}

impl From<Uff58Error> for IoError {
    fn from(e: Uff58Error) -> Self {
        match e {
            Uff58Error::Read { path, source } => IoError::Read { path, source },
            Uff58Error::File { path, message } => IoError::Parse { path, message },
            Uff58Error::Block {
                path,
                line,
                block,
                message,
            } => IoError::Data {
                path,
                line,
                message: format!("block {block}: {message}"),
            },
            Uff58Error::Dataset {
                path,
                line,
                index,
                block,
                record,
                message,
            } => IoError::Data {
                path,
                line,
                message: format!("dataset 58 index {index} (block {block}), {record}: {message}"),
            },
        }
    }
}

const R_ID: &str = "identifier record";
const R_IDS: [&str; 5] = [
    "record 1 (ID line 1)",
    "record 2 (ID line 2)",
    "record 3 (ID line 3)",
    "record 4 (ID line 4)",
    "record 5 (ID line 5)",
];
const R6: &str = "record 6 (DOF identification)";
const R7: &str = "record 7 (data form)";
const R_AXES: [&str; 4] = [
    "record 8 (abscissa data characteristics)",
    "record 9 (ordinate numerator data characteristics)",
    "record 10 (ordinate denominator data characteristics)",
    "record 11 (z-axis data characteristics)",
];
const R12: &str = "record 12 (data values)";
const R_END: &str = "closing -1";
const NO_CLOSING: &str = "the dataset opened here has no closing '    -1' (the file is cut off)";

/// `s` quoted for a message: escaped, at most 60 characters.
fn q(s: &str) -> String {
    format!("'{}'", shown(s.trim()))
}

/// Bytes of the file quoted for a message (never raw binary).
fn qb(b: &[u8]) -> String {
    q(&String::from_utf8_lossy(b))
}

// ------------------------------------------------------------------ reading

/// Reads every dataset 58 of a universal file (ASCII and binary, other
/// dataset types skipped), in file order.
pub fn read(path: &Path) -> Result<Vec<Uff58Function>, Uff58Error> {
    parse(&load(path)?, path)
}

/// Reads the dataset 58 functions of a universal file that `select`
/// matches; the data of the others are skipped without being parsed.
pub fn read_selected(path: &Path, select: &Uff58Select) -> Result<Vec<Uff58Function>, Uff58Error> {
    parse_selected(&load(path)?, path, select)
}

/// Reads records 1–11 of every dataset 58 of a universal file, skipping
/// the data (for listing a large file).
pub fn read_headers(path: &Path) -> Result<Vec<Uff58Entry>, Uff58Error> {
    parse_headers(&load(path)?, path)
}

/// [`read`] of a file held in memory (`path` only names it in errors).
pub fn parse(bytes: &[u8], path: &Path) -> Result<Vec<Uff58Function>, Uff58Error> {
    parse_selected(bytes, path, &Uff58Select::default())
}

/// [`read_selected`] of a file held in memory.
pub fn parse_selected(
    bytes: &[u8],
    path: &Path,
    select: &Uff58Select,
) -> Result<Vec<Uff58Function>, Uff58Error> {
    Ok(scan(bytes, path, Want::Select(select))?
        .into_iter()
        .filter_map(|(info, header, body)| {
            body.map(|(abscissa, data)| Uff58Function {
                info,
                dataset: Uff58Dataset {
                    header,
                    abscissa,
                    data,
                },
            })
        })
        .collect())
}

/// [`read_headers`] of a file held in memory.
pub fn parse_headers(bytes: &[u8], path: &Path) -> Result<Vec<Uff58Entry>, Uff58Error> {
    Ok(scan(bytes, path, Want::Headers)?
        .into_iter()
        .map(|(info, header, _)| Uff58Entry { info, header })
        .collect())
}

fn load(path: &Path) -> Result<Vec<u8>, Uff58Error> {
    let read_err = |source| Uff58Error::Read {
        path: path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(path).map_err(read_err)?.len();
    if len > MAX_FILE_BYTES {
        return Err(Uff58Error::File {
            path: path.to_path_buf(),
            message: format!(
                "the file has {len} bytes; at most {MAX_FILE_BYTES} (1 GiB) are read, because the \
                 whole file is held in memory while it is parsed (split it into smaller files)"
            ),
        });
    }
    std::fs::read(path).map_err(read_err)
}

enum Want<'a> {
    Headers,
    Select(&'a Uff58Select),
}

type Body = (Abscissa, Uff58Data);
type Parsed = (Uff58Info, Uff58Header, Option<Body>);

/// A line of the file, without its line end (`\n` or `\r\n`).
#[derive(Clone, Copy)]
struct Line<'a> {
    no: usize,
    text: &'a [u8],
}

#[derive(Clone)]
struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
    /// Number of the line that starts at `pos`, from 1.
    line: usize,
}

impl<'a> Cursor<'a> {
    fn next_line(&mut self) -> Option<Line<'a>> {
        let rest = self.b.get(self.pos..).filter(|r| !r.is_empty())?;
        let (text, adv) = match rest.iter().position(|&c| c == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        let text = text.strip_suffix(b"\r").unwrap_or(text);
        self.pos += adv;
        let no = self.line;
        self.line += 1;
        Some(Line { no, text })
    }

    /// Skips `n` bytes (binary data), counting the line feeds in them.
    fn skip(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let data = self.b.get(self.pos..end)?;
        self.line += data.iter().filter(|&&c| c == b'\n').count();
        self.pos = end;
        Some(data)
    }

    fn remaining(&self) -> usize {
        self.b.len().saturating_sub(self.pos)
    }
}

fn trim_bytes(b: &[u8]) -> &[u8] {
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    let end = b
        .iter()
        .rposition(|c| !c.is_ascii_whitespace())
        .map_or(start, |e| e + 1);
    &b[start..end.max(start)]
}

/// The dataset delimiter: `-1` right-justified in columns 1–6 (also
/// accepted with fewer leading blanks).
fn is_delimiter(text: &[u8]) -> bool {
    let end = text
        .iter()
        .rposition(|c| !c.is_ascii_whitespace())
        .map_or(0, |e| e + 1);
    end <= 6 && trim_bytes(text) == b"-1"
}

fn is_blank(text: &[u8]) -> bool {
    trim_bytes(text).is_empty()
}

/// Text of a header line: UTF-8, or Latin-1 when it is not UTF-8.
fn decode(b: &[u8]) -> String {
    match std::str::from_utf8(b) {
        Ok(s) => s.to_string(),
        Err(_) => b.iter().map(|&c| c as char).collect(),
    }
}

/// The identifier record: dataset number and, for a binary dataset
/// (`NNNNb`), its byte ordering, floating point format, number of ASCII
/// header lines and number of binary bytes.
struct Ident {
    number: i64,
    binary: Option<BinaryHead>,
}

struct BinaryHead {
    big_endian: bool,
    fp_format: i64,
    ascii_lines: usize,
    bytes: u64,
}

fn parse_ident(text: &[u8]) -> Result<Ident, String> {
    let t = trim_bytes(text);
    let digits = t.iter().take_while(|c| c.is_ascii_digit()).count();
    let number = std::str::from_utf8(&t[..digits])
        .ok()
        .and_then(|s| s.parse::<i64>().ok())
        .ok_or_else(|| {
            format!(
                "{} is not a dataset number (a line after -1 starts a dataset with its number, e.g. '    58')",
                qb(text)
            )
        })?;
    let rest = &t[digits..];
    let Some(fields) = rest.strip_prefix(b"b").or_else(|| rest.strip_prefix(b"B")) else {
        if !is_blank(rest) {
            return Err(format!(
                "{} is not a dataset number (unexpected text after {number})",
                qb(text)
            ));
        }
        return Ok(Ident {
            number,
            binary: None,
        });
    };
    let fields = std::str::from_utf8(fields).map_err(|_| {
        format!(
            "binary dataset {number}: {} is not text (byte ordering, floating point format, number of ASCII lines, number of bytes)",
            qb(text)
        )
    })?;
    let toks: Vec<&str> = fields.split_whitespace().take(8).collect();
    if toks.len() < 4 {
        return Err(format!(
            "binary dataset {number}: {} lacks the byte ordering, floating point format, number of ASCII lines and number of bytes",
            qb(text)
        ));
    }
    let int = |k: usize, what: &str| -> Result<i64, String> {
        toks[k].parse::<i64>().map_err(|_| {
            format!(
                "binary dataset {number}: {what} {} is not an integer",
                q(toks[k])
            )
        })
    };
    let order = int(0, "byte ordering")?;
    let fp_format = int(1, "floating point format")?;
    let ascii_lines = int(2, "number of ASCII lines")?;
    let bytes = int(3, "number of binary bytes")?;
    let big_endian = match order {
        1 => false,
        2 => true,
        o => {
            return Err(format!(
                "binary dataset {number}: byte ordering {o} is neither 1 (little endian) nor 2 (big endian)"
            ))
        }
    };
    let ascii_lines = usize::try_from(ascii_lines)
        .ok()
        .filter(|&n| n <= 1000)
        .ok_or_else(|| {
            format!("binary dataset {number}: number of ASCII lines {ascii_lines} is out of range (0..1000)")
        })?;
    let bytes = u64::try_from(bytes)
        .map_err(|_| format!("binary dataset {number}: number of binary bytes {bytes} < 0"))?;
    Ok(Ident {
        number,
        binary: Some(BinaryHead {
            big_endian,
            fp_format,
            ascii_lines,
            bytes,
        }),
    })
}

fn scan(bytes: &[u8], path: &Path, want: Want<'_>) -> Result<Vec<Parsed>, Uff58Error> {
    let file_err = |message: String| Uff58Error::File {
        path: path.to_path_buf(),
        message,
    };
    if bytes.is_empty() {
        return Err(file_err("the file is empty".into()));
    }
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(file_err(format!(
            "{} bytes; at most {MAX_FILE_BYTES} (1 GiB) are read, because the whole file is held in memory while it is parsed",
            bytes.len()
        )));
    }
    let mut c = Cursor {
        b: bytes,
        pos: 0,
        line: 1,
    };
    let mut out = Vec::new();
    let mut block = 0usize;
    let mut index = 0usize;
    let mut budget = MAX_VALUES;
    let mut open: Option<Line> = None;
    while let Some(l) = c.next_line() {
        let Some(opened) = open else {
            if is_blank(l.text) {
                continue;
            }
            if is_delimiter(l.text) {
                open = Some(l);
                continue;
            }
            if block == 0 {
                let what = match not_text(bytes) {
                    Some(d) => d,
                    None => format!(
                        "line {} is {}, but a universal file starts with a '    -1' line",
                        l.no,
                        qb(l.text)
                    ),
                };
                return Err(file_err(format!("not a universal file: {what}")));
            }
            return Err(Uff58Error::Block {
                path: path.to_path_buf(),
                line: l.no,
                block,
                message: format!(
                    "{} between datasets; expected '    -1' (the line that opens a dataset)",
                    qb(l.text)
                ),
            });
        };
        // `l` is the identifier record of the block opened by `opened`.
        if is_delimiter(l.text) {
            // a stray -1 (an empty block): this one opens the next dataset
            open = Some(l);
            continue;
        }
        let block_err = |line: usize, message: String| Uff58Error::Block {
            path: path.to_path_buf(),
            line,
            block,
            message,
        };
        let ident = parse_ident(l.text).map_err(|m| block_err(l.no, m))?;
        if ident.number == 58 {
            let ctx = Ctx { path, index, block };
            out.push(dataset58(
                &mut c,
                &ctx,
                opened.no,
                &ident,
                &want,
                &mut budget,
            )?);
            index += 1;
        } else if let Some(bin) = &ident.binary {
            // another binary dataset: its ASCII lines, its bytes, the -1
            for _ in 0..bin.ascii_lines {
                c.next_line().ok_or_else(|| {
                    block_err(
                        l.no,
                        format!(
                            "binary dataset {} ends before its {} ASCII lines",
                            ident.number, bin.ascii_lines
                        ),
                    )
                })?;
            }
            let n = usize::try_from(bin.bytes).unwrap_or(usize::MAX);
            let left = c.remaining();
            if c.skip(n).is_none() {
                return Err(block_err(
                    l.no,
                    format!(
                        "binary dataset {} declares {} bytes of data but only {left} remain",
                        ident.number, bin.bytes
                    ),
                ));
            }
            closing(&mut c).map_err(|(line, m)| {
                block_err(line, format!("binary dataset {}: {m}", ident.number))
            })?;
        } else {
            // another ASCII dataset: up to its closing -1
            loop {
                match c.next_line() {
                    Some(x) if is_delimiter(x.text) => break,
                    Some(_) => {}
                    None => {
                        return Err(block_err(
                            opened.no,
                            format!(
                            "dataset {} opened here has no closing '    -1' (the file is cut off)",
                            ident.number
                        ),
                        ))
                    }
                }
            }
        }
        block += 1;
        open = None;
    }
    if block == 0 {
        let what = not_text(bytes).unwrap_or_else(|| {
            "no dataset (a '    -1' line followed by a dataset number such as '    58')".into()
        });
        return Err(file_err(format!("not a universal file: {what}")));
    }
    Ok(out)
}

/// After binary data: an optional line end, then the closing `-1` line.
/// On failure, the line number and a message.
fn closing(c: &mut Cursor) -> Result<(), (usize, String)> {
    let rest = c.b.get(c.pos..).unwrap_or(&[]);
    if rest.starts_with(b"\r\n") {
        c.skip(2);
    } else if rest.starts_with(b"\n") || rest.starts_with(b"\r") {
        c.skip(1);
    }
    match c.next_line() {
        Some(l) if is_delimiter(l.text) => Ok(()),
        Some(l) => Err((
            l.no,
            format!(
                "after the binary data comes {} where the closing '    -1' should be",
                qb(&l.text[..l.text.len().min(16)])
            ),
        )),
        None => Err((c.line, "the file ends without the closing '    -1'".into())),
    }
}

struct Ctx<'a> {
    path: &'a Path,
    index: usize,
    block: usize,
}

impl Ctx<'_> {
    fn err(&self, line: usize, record: &'static str, message: String) -> Uff58Error {
        Uff58Error::Dataset {
            path: self.path.to_path_buf(),
            line,
            index: self.index,
            block: self.block,
            record,
            message,
        }
    }
}

/// `width` characters of `s` from character `start` (fewer at its end).
fn cols(s: &str, start: usize, width: usize) -> String {
    s.chars().skip(start).take(width).collect()
}

/// An integer field: blank is 0 (Fortran); `None` when not an integer.
fn int_field(s: &str) -> Option<i64> {
    let t = s.trim();
    if t.is_empty() {
        return Some(0);
    }
    t.parse::<i64>().ok()
}

/// A real field in any Fortran form: `1.5`, `1.5E-3`, `1.5D-3`, `.15E+01`,
/// `0.15-100` (exponent without its letter); `None` when blank or not a
/// number.
fn real_field(s: &str) -> Option<f64> {
    let t = s.trim();
    if t.is_empty() || t.len() > 80 {
        return None;
    }
    if let Ok(v) = t.parse::<f64>() {
        return Some(v);
    }
    let mut u: String = t.replace(['D', 'd'], "E");
    if let Ok(v) = u.parse::<f64>() {
        return Some(v);
    }
    if !u.contains(['E', 'e']) {
        let at = u
            .bytes()
            .enumerate()
            .skip(1)
            .find(|&(_, ch)| ch == b'+' || ch == b'-')
            .map(|(i, _)| i)?;
        u.insert(at, 'E');
        return u.parse::<f64>().ok();
    }
    None
}

fn int_in<T: TryFrom<i64>>(v: i64, field: &str) -> Result<T, String> {
    T::try_from(v).map_err(|_| format!("{field}: {v} is out of range"))
}

fn field_int(s: &str, start: usize, width: usize, field: &str) -> Result<i64, String> {
    let f = cols(s, start, width);
    int_field(&f).ok_or_else(|| format!("{field}: {} is not an integer", q(&f)))
}

fn record6(s: &str, h: &mut Uff58Header) -> Result<(), String> {
    h.function_type = int_in(field_int(s, 0, 5, "field 1 (function type)")?, "field 1")?;
    h.function_id = field_int(s, 5, 10, "field 2 (function identification number)")?;
    h.version = field_int(s, 15, 5, "field 3 (version or sequence number)")?;
    h.load_case = field_int(s, 20, 10, "field 4 (load case)")?;
    h.response_entity = cols(s, 30, 11).trim().to_string();
    h.response_node = field_int(s, 41, 10, "field 6 (response node)")?;
    h.response_direction = int_in(
        field_int(s, 51, 4, "field 7 (response direction)")?,
        "field 7",
    )?;
    h.reference_entity = cols(s, 55, 11).trim().to_string();
    h.reference_node = field_int(s, 66, 10, "field 9 (reference node)")?;
    h.reference_direction = int_in(
        field_int(s, 76, 4, "field 10 (reference direction)")?,
        "field 10",
    )?;
    Ok(())
}

/// Record 7 as written: ordinate type, points, spacing, min, increment, z.
type Form = (i64, i64, i64, f64, f64, f64);

fn record7(s: &str) -> Result<Form, String> {
    const NAMES: [&str; 6] = [
        "field 1 (ordinate data type)",
        "field 2 (number of points)",
        "field 3 (abscissa spacing)",
        "field 4 (abscissa minimum)",
        "field 5 (abscissa increment)",
        "field 6 (z-axis value)",
    ];
    let real = |t: &str| {
        if t.trim().is_empty() {
            Some(0.0)
        } else {
            real_field(t)
        }
    };
    // the columns of the format, 3I10,3E13.5
    let f: Vec<String> = [(0, 10), (10, 10), (20, 10), (30, 13), (43, 13), (56, 13)]
        .iter()
        .map(|&(a, w)| cols(s, a, w))
        .collect();
    let tail_blank = cols(s, 69, usize::MAX).trim().is_empty();
    let fixed = (|| {
        Some((
            int_field(&f[0])?,
            int_field(&f[1])?,
            int_field(&f[2])?,
            real(&f[3])?,
            real(&f[4])?,
            real(&f[5])?,
        ))
    })();
    if let (Some(v), true) = (fixed, tail_blank) {
        return Ok(v);
    }
    // fields not in those columns: blank-separated
    let toks: Vec<&str> = s.split_whitespace().take(7).collect();
    if toks.len() == 6 {
        let spaced = (|| {
            Some((
                toks[0].parse().ok()?,
                toks[1].parse().ok()?,
                toks[2].parse().ok()?,
                real_field(toks[3])?,
                real_field(toks[4])?,
                real_field(toks[5])?,
            ))
        })();
        if let Some(v) = spaced {
            return Ok(v);
        }
    }
    for (k, t) in f.iter().enumerate() {
        let ok = if k < 3 {
            int_field(t).is_some()
        } else {
            real(t).is_some()
        };
        if !ok {
            let kind = if k < 3 { "an integer" } else { "a number" };
            return Err(format!("{}: {} is not {kind}", NAMES[k], q(t)));
        }
    }
    Err(format!(
        "{} has text after column 69 and is not 6 blank-separated numbers",
        q(s)
    ))
}

fn axis_record(s: &str) -> Result<AxisInfo, String> {
    let i32_field = |a, w, name| -> Result<i32, String> { int_in(field_int(s, a, w, name)?, name) };
    Ok(AxisInfo {
        specific_data_type: i32_field(0, 10, "field 1 (specific data type)")?,
        length_exponent: i32_field(10, 5, "field 2 (length units exponent)")?,
        force_exponent: i32_field(15, 5, "field 3 (force units exponent)")?,
        temperature_exponent: i32_field(20, 5, "field 4 (temperature units exponent)")?,
        label: cols(s, 25, 21).trim().to_string(),
        units: cols(s, 46, 21).trim().to_string(),
    })
}

/// Numbers of one stored point: x (uneven), y or re, im.
fn per_point(complex: bool, uneven: bool) -> usize {
    (if complex { 2 } else { 1 }) + usize::from(uneven)
}

/// Column widths of an ASCII data line (record 12, Addendum B cases 1–8).
fn data_widths(precision: Precision, complex: bool, uneven: bool) -> &'static [usize] {
    match (precision, complex, uneven) {
        (Precision::Single, _, _) => &[13; 6],
        (Precision::Double, _, false) => &[20; 4],
        (Precision::Double, false, true) => &[13, 20, 13, 20],
        (Precision::Double, true, true) => &[13, 20, 20],
    }
}

/// The numbers of one ASCII data line, in the columns of `widths` or else
/// blank-separated; stops once `out` holds more than `max` numbers.
fn data_line(text: &[u8], widths: &[usize], out: &mut Vec<f64>, max: usize) -> Result<(), String> {
    let Ok(s) = std::str::from_utf8(text) else {
        return Err(format!("{} is not text", qb(text)));
    };
    if !s.is_ascii() {
        return Err(format!("{} holds non-ASCII characters", q(s)));
    }
    let mut fixed = [0.0f64; 6];
    let mut n = 0;
    let mut pos = 0;
    let mut ok = true;
    let mut blank = false;
    for &w in widths {
        if pos >= s.len() {
            break;
        }
        let f = &s[pos..(pos + w).min(s.len())];
        pos += w;
        if f.trim().is_empty() {
            blank = true;
            continue;
        }
        match real_field(f) {
            Some(v) if !blank => {
                fixed[n] = v;
                n += 1;
            }
            _ => {
                ok = false;
                break;
            }
        }
    }
    if ok && pos < s.len() && !s[pos..].trim().is_empty() {
        ok = false;
    }
    if ok {
        out.extend_from_slice(&fixed[..n]);
        return Ok(());
    }
    for tok in s.split_whitespace() {
        if out.len() > max {
            break;
        }
        let v = real_field(tok).ok_or_else(|| format!("{} is not a number", q(tok)))?;
        out.push(v);
    }
    Ok(())
}

fn dataset58(
    c: &mut Cursor,
    ctx: &Ctx,
    open_line: usize,
    ident: &Ident,
    want: &Want,
    budget: &mut usize,
) -> Result<Parsed, Uff58Error> {
    let encoding = match &ident.binary {
        None => Encoding::Ascii,
        Some(b) => {
            if b.fp_format != 2 {
                let what = match b.fp_format {
                    1 => "1 (DEC VMS)",
                    3 => "3 (IBM 5/370)",
                    _ => "not 2 (IEEE 754)",
                };
                return Err(ctx.err(
                    open_line + 1,
                    R_ID,
                    format!(
                        "floating point format {} is {what}; only IEEE 754 (2) binary data are read",
                        b.fp_format
                    ),
                ));
            }
            if b.ascii_lines != 11 {
                return Err(ctx.err(
                    open_line + 1,
                    R_ID,
                    format!(
                        "{} ASCII header lines declared; a dataset 58b has 11 (records 1-11)",
                        b.ascii_lines
                    ),
                ));
            }
            Encoding::Binary {
                big_endian: b.big_endian,
                declared_bytes: b.bytes,
            }
        }
    };
    // records 1-11
    let mut lines: Vec<(usize, String)> = Vec::with_capacity(11);
    for k in 0..11 {
        let record = match k {
            0..=4 => R_IDS[k],
            5 => R6,
            6 => R7,
            _ => R_AXES[k - 7],
        };
        let l = c.next_line().ok_or_else(|| {
            ctx.err(
                c.line,
                record,
                "the file ends before this record (a dataset 58 has 11 header records)".into(),
            )
        })?;
        if is_delimiter(l.text) {
            return Err(ctx.err(
                l.no,
                record,
                "the dataset closes ('    -1') before this record (a dataset 58 has 11 header records)"
                    .into(),
            ));
        }
        lines.push((l.no, decode(l.text)));
    }
    let mut h = Uff58Header::default();
    for (k, id) in [&mut h.id1, &mut h.id2, &mut h.id3, &mut h.id4, &mut h.id5]
        .into_iter()
        .enumerate()
    {
        *id = lines[k].1.trim().to_string();
    }
    record6(&lines[5].1, &mut h).map_err(|m| ctx.err(lines[5].0, R6, m))?;
    let l7 = lines[6].0;
    let (ord, points, spacing, xmin, dx, z) =
        record7(&lines[6].1).map_err(|m| ctx.err(l7, R7, m))?;
    h.z_axis_value = z;
    for (k, axis) in [
        &mut h.abscissa_axis,
        &mut h.ordinate_axis,
        &mut h.denominator_axis,
        &mut h.z_axis,
    ]
    .into_iter()
    .enumerate()
    {
        *axis = axis_record(&lines[7 + k].1).map_err(|m| ctx.err(lines[7 + k].0, R_AXES[k], m))?;
    }
    let (precision, complex) = match ord {
        2 => (Precision::Single, false),
        4 => (Precision::Double, false),
        5 => (Precision::Single, true),
        6 => (Precision::Double, true),
        o => {
            return Err(ctx.err(
                l7,
                R7,
                format!(
                    "field 1 (ordinate data type): {o} is not 2, 4, 5 or 6 (real or complex, single or \
                     double precision; dataset 58 has no magnitude-phase type)"
                ),
            ))
        }
    };
    let points = usize::try_from(points)
        .map_err(|_| ctx.err(l7, R7, format!("field 2 (number of points): {points} < 0")))?;
    let uneven = match spacing {
        0 => true,
        1 => false,
        s => {
            return Err(ctx.err(
                l7,
                R7,
                format!("field 3 (abscissa spacing): {s} is neither 0 (uneven) nor 1 (even)"),
            ))
        }
    };
    let finite = xmin.is_finite() && dx.is_finite();
    if !uneven && !finite {
        return Err(ctx.err(
            l7,
            R7,
            format!("fields 4-5: even abscissa minimum {xmin} and increment {dx} must be finite"),
        ));
    }
    let info = Uff58Info {
        index: ctx.index,
        block: ctx.block,
        line: open_line,
        encoding,
        ordinate_type: ord as i32,
        precision,
        complex,
        points,
        abscissa_spacing: spacing as i32,
        abscissa_min: xmin,
        abscissa_increment: dx,
    };
    let parse_data = match want {
        Want::Headers => false,
        Want::Select(s) => s.matches(ctx.index, &h),
    };
    let k = per_point(complex, uneven);
    let too_many = || {
        ctx.err(
            l7,
            R7,
            format!(
                "field 2 (number of points): {points} points; a file may hold at most \
                 {MAX_VALUES} numbers, because they are all held in memory (8 bytes each)"
            ),
        )
    };
    let values_needed = points.checked_mul(k).ok_or_else(too_many)?;
    let values = match encoding {
        Encoding::Binary {
            big_endian,
            declared_bytes,
        } => {
            let size = if precision == Precision::Single { 4 } else { 8 };
            // the layout of one point: x (uneven), then y or re, im
            let mut layout = vec![size; k];
            let std_bytes = points.checked_mul(size * k);
            if uneven && precision == Precision::Double {
                // the abscissa as 4-byte floats (Addendum B: "the abscissa is
                // always real single precision"), when the count says so
                let alt = points.checked_mul(4 + size * (k - 1));
                if alt.is_some_and(|a| a as u64 == declared_bytes) && std_bytes != alt {
                    layout[0] = 4;
                }
            }
            let need = points
                .checked_mul(layout.iter().sum::<usize>())
                .filter(|&n| n <= c.remaining())
                .ok_or_else(|| {
                    ctx.err(
                        l7,
                        R7,
                        format!(
                            "field 2 (number of points): {points} points of {} bytes, but only {} bytes \
                             remain in the file (declared: {declared_bytes})",
                            layout.iter().sum::<usize>(),
                            c.remaining()
                        ),
                    )
                })?;
            let data_line = c.line;
            let data = c.skip(need).unwrap_or(&[]);
            let mut values = Vec::new();
            if parse_data {
                if values_needed > *budget {
                    return Err(too_many());
                }
                *budget -= values_needed;
                values.reserve_exact(values_needed);
                let mut at = 0;
                for _ in 0..points {
                    for &sz in &layout {
                        let b = data.get(at..at + sz).unwrap_or(&[]);
                        at += sz;
                        values.push(float_at(b, big_endian));
                    }
                }
            }
            // the closing -1: after the data, or after the declared count
            let after = c.clone();
            if let Err((line, m)) = closing(c) {
                let declared = usize::try_from(declared_bytes)
                    .ok()
                    .filter(|&d| d > need)
                    .and_then(|d| {
                        let mut alt = after.clone();
                        alt.skip(d - need)?;
                        closing(&mut alt).ok()?;
                        Some(alt)
                    });
                match declared {
                    Some(alt) => *c = alt,
                    None => {
                        return Err(ctx.err(
                            line,
                            R_END,
                            format!(
                                "{m} (record 7: {points} points, {need} bytes of data from line \
                                 {data_line}; declared: {declared_bytes} bytes)"
                            ),
                        ))
                    }
                }
            }
            values
        }
        Encoding::Ascii => {
            // find the closing -1 first: the data lines and their size
            let start = c.clone();
            let mut data_bytes = 0usize;
            let close_line = loop {
                match c.next_line() {
                    Some(l) if is_delimiter(l.text) => break l.no,
                    Some(l) => data_bytes += l.text.len() + 1,
                    None => return Err(ctx.err(open_line, R_END, NO_CLOSING.into())),
                }
            };
            let mut values = Vec::new();
            if parse_data {
                // every number takes at least 2 bytes (a digit and a blank or line end)
                if values_needed > data_bytes / 2 + 1 {
                    return Err(ctx.err(
                        l7,
                        R7,
                        format!(
                            "field 2 (number of points): {points} points ({values_needed} numbers), \
                             but the {} bytes of data up to the closing -1 at line {close_line} cannot hold them",
                            data_bytes
                        ),
                    ));
                }
                if values_needed > *budget {
                    return Err(too_many());
                }
                *budget -= values_needed;
                values.reserve_exact(values_needed);
                let widths = data_widths(precision, complex, uneven);
                let mut d = start;
                while let Some(l) = d.next_line() {
                    if l.no >= close_line {
                        break;
                    }
                    data_line(l.text, widths, &mut values, values_needed)
                        .map_err(|m| ctx.err(l.no, R12, m))?;
                    if values.len() > values_needed {
                        return Err(ctx.err(
                            l.no,
                            R12,
                            format!(
                                "more numbers than record 7 declares ({points} points of {k} numbers: {values_needed})"
                            ),
                        ));
                    }
                }
                if values.len() != values_needed {
                    return Err(ctx.err(
                        close_line,
                        R12,
                        format!(
                            "{} numbers, but record 7 declares {points} points of {k} numbers ({values_needed})",
                            values.len()
                        ),
                    ));
                }
            }
            values
        }
    };
    let body = parse_data.then(|| split_values(&values, complex, uneven, xmin, dx));
    Ok((info, h, body))
}

fn float_at(b: &[u8], big_endian: bool) -> f64 {
    match b.len() {
        4 => {
            let a = [b[0], b[1], b[2], b[3]];
            (if big_endian {
                f32::from_be_bytes(a)
            } else {
                f32::from_le_bytes(a)
            }) as f64
        }
        8 => {
            let a = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
            if big_endian {
                f64::from_be_bytes(a)
            } else {
                f64::from_le_bytes(a)
            }
        }
        _ => f64::NAN,
    }
}

fn split_values(v: &[f64], complex: bool, uneven: bool, xmin: f64, dx: f64) -> Body {
    let k = per_point(complex, uneven);
    let abscissa = if uneven {
        Abscissa::Uneven(v.chunks_exact(k).map(|p| p[0]).collect())
    } else {
        Abscissa::Even {
            start: xmin,
            step: dx,
        }
    };
    let o = usize::from(uneven);
    let data = if complex {
        Uff58Data::Complex(v.chunks_exact(k).map(|p| (p[o], p[o + 1])).collect())
    } else {
        Uff58Data::Real(v.chunks_exact(k).map(|p| p[o]).collect())
    };
    (abscissa, data)
}

// ------------------------------------------------------------------ writing

/// Writes `datasets` as ASCII dataset 58 in double precision (ordinate type
/// 4 real or 6 complex), each field in the columns of the format (see the
/// module documentation for the digits written).
///
/// Refused (naming the dataset and field): text that is not printable ASCII
/// or longer than its field (ID lines 80, entity names 10, axis labels 20
/// characters; fixed-width columns are counted in bytes by most readers, so
/// write `m/s^2`, `deg`), integers wider than their field, directions
/// outside -6..6, non-finite values, and an uneven abscissa whose length
/// differs from the data's.
pub fn write_ascii(datasets: &[Uff58Dataset]) -> Result<String, Uff58WriteError> {
    let mut out = String::new();
    for (index, d) in datasets.iter().enumerate() {
        check(index, d)?;
        out.push_str("    -1\n    58\n");
        header_text(&mut out, d);
        let uneven = matches!(d.abscissa, Abscissa::Uneven(_));
        let x = match &d.abscissa {
            Abscissa::Uneven(x) => x.as_slice(),
            Abscissa::Even { .. } => &[],
        };
        let mut line = String::new();
        let mut fields = 0;
        let mut push = |line: &mut String, s: String, per_line: usize, out: &mut String| {
            line.push_str(&s);
            fields += 1;
            if fields == per_line {
                out.push_str(line);
                out.push('\n');
                line.clear();
                fields = 0;
            }
        };
        match (&d.data, uneven) {
            (Uff58Data::Real(y), false) => {
                for &v in y {
                    push(&mut line, fit(v, 20), 4, &mut out);
                }
            }
            (Uff58Data::Complex(y), false) => {
                for &(re, im) in y {
                    push(&mut line, fit(re, 20), 4, &mut out);
                    push(&mut line, fit(im, 20), 4, &mut out);
                }
            }
            (Uff58Data::Real(y), true) => {
                for (&xv, &v) in x.iter().zip(y) {
                    push(&mut line, fit(xv, 13), 4, &mut out);
                    push(&mut line, fit(v, 20), 4, &mut out);
                }
            }
            (Uff58Data::Complex(y), true) => {
                for (&xv, &(re, im)) in x.iter().zip(y) {
                    push(&mut line, fit(xv, 13), 3, &mut out);
                    push(&mut line, fit(re, 20), 3, &mut out);
                    push(&mut line, fit(im, 20), 3, &mut out);
                }
            }
        }
        if !line.is_empty() {
            out.push_str(&line);
            out.push('\n');
        }
        out.push_str("    -1\n");
    }
    Ok(out)
}

/// Writes `datasets` as binary dataset 58b: little endian IEEE 754 doubles
/// (ordinate type 4 or 6), an uneven abscissa as doubles before each
/// ordinate value (as pyuff writes and reads it), the exact byte count in
/// the identifier record, and the closing `-1` right after the data. The
/// data are bit-exact; the header is as [`write_ascii`] writes it.
pub fn write_binary(datasets: &[Uff58Dataset]) -> Result<Vec<u8>, Uff58WriteError> {
    let mut out = Vec::new();
    for (index, d) in datasets.iter().enumerate() {
        check(index, d)?;
        let mut values: Vec<f64> = Vec::new();
        let x = match &d.abscissa {
            Abscissa::Uneven(x) => Some(x),
            Abscissa::Even { .. } => None,
        };
        for k in 0..d.len() {
            if let Some(x) = x {
                values.push(x[k]);
            }
            match &d.data {
                Uff58Data::Real(y) => values.push(y[k]),
                Uff58Data::Complex(y) => {
                    values.push(y[k].0);
                    values.push(y[k].1);
                }
            }
        }
        let mut head = format!(
            "    -1\n    58b{:6}{:6}{:12}{:12}{:6}{:6}{:12}{:12}\n",
            1,
            2,
            11,
            values.len() * 8,
            0,
            0,
            0,
            0
        );
        header_text(&mut head, d);
        out.extend_from_slice(head.as_bytes());
        for v in values {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(b"    -1\n");
    }
    Ok(out)
}

/// [`write_ascii`] to a file, atomically (no partial file on failure).
pub fn write_ascii_file(path: &Path, datasets: &[Uff58Dataset]) -> Result<(), IoError> {
    let text = write_ascii(datasets).map_err(|e| invalid(path, e))?;
    crate::atomic::write_atomic(path, text.as_bytes())
}

/// [`write_binary`] to a file, atomically (no partial file on failure).
pub fn write_binary_file(path: &Path, datasets: &[Uff58Dataset]) -> Result<(), IoError> {
    let bytes = write_binary(datasets).map_err(|e| invalid(path, e))?;
    crate::atomic::write_atomic(path, &bytes)
}

fn invalid(path: &Path, e: Uff58WriteError) -> IoError {
    IoError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, e.to_string()),
    }
}

/// Records 1-11 (identifier and -1 excluded) in the columns of the format.
fn header_text(out: &mut String, d: &Uff58Dataset) {
    use std::fmt::Write;
    let h = &d.header;
    let none = |s: &str| {
        if s.trim().is_empty() {
            "NONE".to_string()
        } else {
            s.to_string()
        }
    };
    for id in [&h.id1, &h.id2, &h.id3, &h.id4, &h.id5] {
        let _ = writeln!(out, "{:<80}", none(id));
    }
    let _ = writeln!(
        out,
        "{:5}{:10}{:5}{:10} {:>10}{:10}{:4} {:>10}{:10}{:4}",
        h.function_type,
        h.function_id,
        h.version,
        h.load_case,
        none(&h.response_entity),
        h.response_node,
        h.response_direction,
        none(&h.reference_entity),
        h.reference_node,
        h.reference_direction
    );
    let (ord, spacing, xmin, dx) = match (&d.data, &d.abscissa) {
        (Uff58Data::Real(_), Abscissa::Even { start, step }) => (4, 1, *start, *step),
        (Uff58Data::Complex(_), Abscissa::Even { start, step }) => (6, 1, *start, *step),
        (Uff58Data::Real(_), Abscissa::Uneven(_)) => (4, 0, 0.0, 0.0),
        (Uff58Data::Complex(_), Abscissa::Uneven(_)) => (6, 0, 0.0, 0.0),
    };
    let _ = writeln!(
        out,
        "{:10}{:10}{:10}{}{}{}",
        ord,
        d.len(),
        spacing,
        fit(xmin, 13),
        fit(dx, 13),
        fit(h.z_axis_value, 13)
    );
    for a in [
        &h.abscissa_axis,
        &h.ordinate_axis,
        &h.denominator_axis,
        &h.z_axis,
    ] {
        let _ = writeln!(
            out,
            "{:10}{:5}{:5}{:5} {:<20} {:<20}",
            a.specific_data_type,
            a.length_exponent,
            a.force_exponent,
            a.temperature_exponent,
            none(&a.label),
            none(&a.units)
        );
    }
}

/// Fortran-style scientific notation of Rust's `{:e}` output: `1.5e-7`
/// becomes `1.5E-07`.
fn sci(s: &str) -> String {
    let (m, e) = s.split_once('e').unwrap_or((s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    let m = if m.contains('.') {
        m.to_string()
    } else {
        format!("{m}.0")
    };
    let sign = if e < 0 { '-' } else { '+' };
    format!("{m}E{sign}{:02}", e.unsigned_abs())
}

/// `v` (finite) right-justified in `width` columns with at least one
/// leading blank: the shortest decimal that reads back as `v` when it
/// fits, else `v` rounded to the most significant digits that fit (toward
/// zero where rounding would overflow to infinity), written as the
/// shortest decimal of that rounded value, so that writing what was read
/// gives the same text.
fn fit(v: f64, width: usize) -> String {
    let room = width - 1;
    let shortest = sci(&format!("{v:e}"));
    let s = if shortest.len() <= room {
        shortest
    } else {
        let plain = format!("{v}");
        if plain.len() <= room {
            plain
        } else {
            (0..17)
                .rev()
                .find_map(|p| {
                    let s = sci(&format!("{v:.p$e}"));
                    if s.len() > room {
                        return None;
                    }
                    let w = match s.parse::<f64>() {
                        Ok(w) if w.is_finite() => w,
                        // rounded up past f64::MAX: cut the digits instead
                        _ => truncated(v, p)?,
                    };
                    let t = sci(&format!("{w:e}"));
                    Some(if t.len() <= room { t } else { s })
                })
                .unwrap_or_else(|| sci(&format!("{v:.0e}")))
        }
    };
    format!("{s:>width$}")
}

/// `v` with `p` digits after the point of its mantissa, cut (not rounded).
fn truncated(v: f64, p: usize) -> Option<f64> {
    let full = format!("{v:.20e}");
    let (m, e) = full.split_once('e')?;
    let keep = m.find('.')? + 1 + p;
    format!("{}e{e}", m.get(..keep)?).parse().ok()
}

fn check(index: usize, d: &Uff58Dataset) -> Result<(), Uff58WriteError> {
    let bad = |message: String| Uff58WriteError { index, message };
    let h = &d.header;
    let text = |value: &str, max: usize, what: &str| -> Result<(), Uff58WriteError> {
        if let Some(c) = value.chars().find(|c| !(' '..='~').contains(c)) {
            return Err(bad(format!(
                "{what} {} holds {}, which is not printable ASCII (fixed-width columns are counted in \
                 bytes by most readers: write e.g. m/s^2, deg)",
                q(value),
                q(&c.to_string())
            )));
        }
        if value.len() > max {
            return Err(bad(format!(
                "{what} {} has {} characters; the field holds {max}",
                q(value),
                value.len()
            )));
        }
        Ok(())
    };
    for (k, id) in [&h.id1, &h.id2, &h.id3, &h.id4, &h.id5].iter().enumerate() {
        text(id, 80, &format!("ID line {} (record {})", k + 1, k + 1))?;
    }
    text(
        &h.response_entity,
        10,
        "response entity name (record 6 field 5)",
    )?;
    text(
        &h.reference_entity,
        10,
        "reference entity name (record 6 field 8)",
    )?;
    let int = |v: i64, digits: usize, what: &str| -> Result<(), Uff58WriteError> {
        let max = 10i64.pow(digits as u32) - 1;
        let min = -(10i64.pow(digits as u32 - 1) - 1);
        if v < min || v > max {
            return Err(bad(format!(
                "{what} {v} does not fit its {digits}-column field ({min}..{max})"
            )));
        }
        Ok(())
    };
    int(
        h.function_type.into(),
        5,
        "function type (record 6 field 1)",
    )?;
    int(h.function_id, 10, "function id (record 6 field 2)")?;
    int(h.version, 5, "version number (record 6 field 3)")?;
    int(h.load_case, 10, "load case (record 6 field 4)")?;
    int(h.response_node, 10, "response node (record 6 field 6)")?;
    int(h.reference_node, 10, "reference node (record 6 field 9)")?;
    for (dir, what) in [
        (
            h.response_direction,
            "response direction (record 6 field 7)",
        ),
        (
            h.reference_direction,
            "reference direction (record 6 field 10)",
        ),
    ] {
        if !(-6..=6).contains(&dir) {
            return Err(bad(format!("{what} {dir} is not one of -6..6")));
        }
    }
    for (k, a) in [
        &h.abscissa_axis,
        &h.ordinate_axis,
        &h.denominator_axis,
        &h.z_axis,
    ]
    .iter()
    .enumerate()
    {
        let r = k + 8;
        int(
            a.specific_data_type.into(),
            10,
            &format!("specific data type (record {r} field 1)"),
        )?;
        for (v, f) in [
            (a.length_exponent, 2),
            (a.force_exponent, 3),
            (a.temperature_exponent, 4),
        ] {
            int(
                v.into(),
                5,
                &format!("unit exponent (record {r} field {f})"),
            )?;
        }
        text(&a.label, 20, &format!("axis label (record {r} field 5)"))?;
        text(&a.units, 20, &format!("units label (record {r} field 6)"))?;
    }
    int(d.len() as i64, 10, "number of points (record 7 field 2)")?;
    if !h.z_axis_value.is_finite() {
        return Err(bad(format!(
            "z-axis value (record 7 field 6) {} is not finite",
            h.z_axis_value
        )));
    }
    match &d.abscissa {
        Abscissa::Even { start, step } => {
            if !(start.is_finite() && step.is_finite()) {
                return Err(bad(format!(
                    "even abscissa start {start} and step {step} (record 7 fields 4-5) must be finite"
                )));
            }
        }
        Abscissa::Uneven(x) => {
            if x.len() != d.len() {
                return Err(bad(format!(
                    "uneven abscissa of {} values for {} data points",
                    x.len(),
                    d.len()
                )));
            }
            if let Some(k) = x.iter().position(|v| !v.is_finite()) {
                return Err(bad(format!("abscissa value {k} is {}", x[k])));
            }
        }
    }
    let bad_point = match &d.data {
        Uff58Data::Real(y) => y.iter().position(|v| !v.is_finite()),
        Uff58Data::Complex(y) => y
            .iter()
            .position(|(re, im)| !(re.is_finite() && im.is_finite())),
    };
    if let Some(k) = bad_point {
        return Err(bad(format!(
            "data value {k} is not finite (NaN or infinite)"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_hold_the_shortest_exact_decimal_when_it_fits() {
        assert_eq!(fit(0.5, 20), format!("{:>20}", "5.0E-01"));
        assert_eq!(fit(-1.0 / 3.0, 20).len(), 20);
        assert_eq!(fit(0.1220703125, 13), " 0.1220703125");
        assert_eq!(fit(1.0 / 1024.0, 13), " 9.765625E-04");
        for v in [
            0.1,
            -2.5e-300,
            1e300,
            123.456,
            -0.0,
            5e-324,
            1.0 / 3.0,
            f64::MAX,
            -f64::MAX,
        ] {
            let s = fit(v, 20);
            assert_eq!(s.len(), 20, "{s}");
            assert!(s.starts_with(' '), "{s}");
            let back: f64 = s.trim().parse().unwrap();
            let tol = if v.abs() >= 1e99 { 1e-11 } else { 5e-13 };
            assert!((back - v).abs() <= v.abs() * tol, "{v} {s}");
        }
        for v in [f64::MAX, -f64::MAX, 1.7976931348623157e308 * 0.9999999] {
            let s = fit(v, 13);
            assert_eq!(s.len(), 13, "{s}");
            let back: f64 = s.trim().parse().unwrap();
            assert!(
                back.is_finite() && (back - v).abs() <= v.abs() * 1e-4,
                "{v} {s}"
            );
            assert_eq!(fit(back, 13), s);
        }
        assert_eq!(
            fit(-0.0, 20).trim().parse::<f64>().unwrap().to_bits(),
            (-0.0f64).to_bits()
        );
    }

    #[test]
    fn fortran_reals() {
        assert_eq!(real_field(" 1.5D+02 "), Some(150.0));
        assert_eq!(real_field("0.15-100"), Some(0.15e-100));
        assert_eq!(real_field("-.5E1"), Some(-5.0));
        assert_eq!(real_field("abc"), None);
        assert_eq!(real_field(""), None);
    }

    #[test]
    fn delimiters() {
        assert!(is_delimiter(b"    -1"));
        assert!(is_delimiter(b"    -1     "));
        assert!(is_delimiter(b"-1"));
        assert!(!is_delimiter(b"        -1"));
        assert!(!is_delimiter(b"    -12"));
    }
}
