//! File formats for nlsdof. All values SI, amplitudes zero-to-peak.
//!
//! * [`model_file`] — the model TOML (`mass`, `stiffness`, `damping`,
//!   optional `[nonlinear_stiffness]` / `[nonlinear_damping]` tables with
//!   `coefficient` and `exponent`).
//! * [`atomic`] — write-to-temporary-then-rename output files so a failure or
//!   Ctrl-C never leaves a partial file behind.
//! * [`signal_file`] — recorded input signals (CSV `t,accel` or one column
//!   plus fs; MATLAB MAT v5 numeric arrays) and streamed numeric CSV output.

pub mod atomic;
pub mod error;
pub mod model_file;
pub mod signal_file;

pub use error::IoError;
