//! One error type for the CLI: every failure becomes one line on stderr and
//! exit code 2 (see `main`).

use thiserror::Error;

#[derive(Debug, Error)]
pub enum CliError {
    #[error(transparent)]
    Io(#[from] nlsdof_io::IoError),
    #[error(transparent)]
    Parameter(#[from] nlsdof::ParameterError),
    #[error(transparent)]
    Solve(#[from] nlsdof::SolveError),
    #[error(transparent)]
    MultiHarmonic(#[from] nlsdof::multi_harmonic::MhbError),
    #[error(transparent)]
    Simulation(#[from] nlsdof::simulation::SimulationError),
    #[error(transparent)]
    Signal(#[from] nlsdof_io::signal_file::SignalFileError),
    #[error(transparent)]
    Identification(#[from] nlsdof::vector_fitting::IdentificationError),
    #[error(transparent)]
    SignalProcessing(#[from] nlsdof::signal_processing::SignalError),
    #[error(transparent)]
    FrfFile(#[from] nlsdof_io::frf_file::FrfFileError),
    /// A bad command-line value: what was given and what is allowed.
    #[error("{0}")]
    Usage(String),
}
