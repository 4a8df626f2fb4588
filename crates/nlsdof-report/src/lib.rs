//! # nlsdof-report
//!
//! The rendering layer of nlsdof. The core crate [`nlsdof`] computes; this
//! crate turns its typed results into what a person or a script reads:
//!
//! * **JSON values** (`serde_json::Value`): the documents of the CLI's
//!   `--json` and of the Python module's `to_dict()`, built in one place so
//!   that both give the same keys and the same numbers;
//! * **text** tables and summaries (SI units in every header);
//! * **markdown** (the demo's `report.md`);
//! * **figures** through [`nlsdof_figure`] (SVG, and PNG where a raster
//!   is the natural form).
//!
//! No argument parsing and no terminal: the CLI parses its arguments, calls
//! the library, and hands the result to the functions here.
//!
//! | module | renders |
//! |---|---|
//! | [`number`] | numbers in text and messages |
//! | [`rig`] | the virtual stepped-sine rig (`nlsdof stepped-sine`) |
//! | [`simulation`] | time simulation of a recorded input (`nlsdof simulate`) |
//! | [`spectrogram`] | STFT spectrograms and Eq 33 (`nlsdof spectrogram`) |
//! | [`steady_state`] | steady states and sweeps (`nlsdof roots`, `nlsdof frf`) |
//! | [`multi_harmonic`] | multi-harmonic sweeps (`nlsdof frf --harmonics H`) |
//! | [`time_fit`] | the time-domain fit (`nlsdof fit-time`) |
//! | [`truncation`] | truncation error of first-order HB (`nlsdof hb-error`) |
//! | [`fit`] | the stepped-sine fit (`nlsdof fit`, `compare`) |
//! | [`landscape`] | the exponent landscape (JSON grid, SVG/PNG heat map) |
//! | [`frf_plot`] | steady-state branches of `nlsdof frf` |
//! | [`linear_id`] | linear identification from an FRF (`nlsdof linear-id`) |
//! | [`decay`] | free-decay identification (`nlsdof decay`) |
//! | [`demo`] | the demo's figures, tables, `summary.json` and `report.md` |

pub mod decay;
pub mod demo;
pub mod figure_file;
pub mod fit;
pub mod frf_estimate;
pub mod frf_plot;
pub mod inspect;
pub mod intervals;
pub mod landscape;
pub mod linear_id;
pub mod multi_harmonic;
pub mod number;
pub mod rig;
pub mod simulation;
pub mod spectrogram;
pub mod steady_state;
pub mod time_fit;
pub mod truncation;

pub use number::{compact_numbers, num};

use thiserror::Error;

/// Why a document could not be rendered or written.
#[derive(Debug, Error)]
pub enum ReportError {
    #[error(transparent)]
    Io(#[from] nlsdof_io::IoError),
    #[error(transparent)]
    Figure(#[from] nlsdof_figure::FigureError),
    #[error(transparent)]
    Parameter(#[from] nlsdof::ParameterError),
    #[error(transparent)]
    Solve(#[from] nlsdof::SolveError),
    /// A request that cannot be rendered (a file name asking for a format
    /// this figure is not drawn in, a figure the backend could not draw):
    /// the offending value is in the message.
    #[error("{0}")]
    Invalid(String),
}
