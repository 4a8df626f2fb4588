//! File formats for nlsdof. All values SI, amplitudes zero-to-peak.
//!
//! * [`model_file`] — the model TOML (`mass`, `stiffness`, `damping`,
//!   optional `[nonlinear_stiffness]` / `[nonlinear_damping]` tables with
//!   `coefficient` and `exponent`).
//! * [`csv_table`] — the CSV reader of the table formats (csv crate,
//!   header-indexed, BOM tolerant, optional decimal comma): stepped-sine
//!   and phase-resonance data, FRF tables, named signal columns.
//! * [`atomic`] — write-to-temporary-then-rename output files so a failure or
//!   Ctrl-C never leaves a partial file behind.
//! * [`signal_file`] — recorded input signals (CSV `t,accel` or one column
//!   plus fs; MATLAB MAT v5 numeric arrays) and streamed numeric CSV output.
//! * [`frf_file`] — FRF tables (CSV `f_hz,re,im` or `f_hz,mag[,phase_deg]`),
//!   multi-channel time histories (CSV, Polytec ASCII exports) and Polytec
//!   swept-sine FRF exports, for linear identification.
//! * [`phase_resonance_data`] — phase-resonance points (`gamma,f_hz,amplitude`
//!   at 90° phase per level) for `nlsdof fit --phase-resonance`.
//! * [`table_file`] — numeric columns of a delimited table chosen by name or
//!   index (recorded input/output pairs for `nlsdof fit-time`).
//! * [`input`] — the one reader layer: the format of a data file from its
//!   content (CSV, LabVIEW `.lvm`, Polytec ASCII, MAT v5, UFF 58), and a
//!   time history or named columns read from any of them.
//! * [`uff58`] — Universal File Format dataset 58 / 58b (measured functions
//!   of vibration test systems: time responses, spectra, FRFs, coherences):
//!   reader of ASCII and binary files, ASCII and binary writer.

pub mod atomic;
pub mod bounds_file;
pub mod csv_table;
pub mod error;
pub mod format;
pub mod frf_file;
pub mod input;
pub mod mat5;
pub mod model_file;
pub mod phase_resonance_data;
pub mod signal_file;
pub mod stepped_sine_data;
pub mod table_file;
pub mod text;
pub mod uff58;
pub mod uff_convert;

pub use error::IoError;

/// `text` without a leading UTF-8 byte-order mark (Excel writes one).
pub(crate) fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}
