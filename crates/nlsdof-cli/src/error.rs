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
    VectorFit(#[from] nlsdof::vector_fitting::VectorFitError),
    #[error(transparent)]
    SignalProcessing(#[from] nlsdof::signal_processing::SignalError),
    #[error(transparent)]
    FrfFile(#[from] nlsdof_io::frf_file::FrfFileError),
    #[error(transparent)]
    Demo(#[from] nlsdof::demo::DemoError),
    #[error(transparent)]
    Table(#[from] nlsdof_io::table_file::TableError),
    #[error(transparent)]
    TimeFit(#[from] nlsdof::identification::time_domain::TimeFitError),
    #[error(transparent)]
    Figure(#[from] nlsdof_figure::FigureError),
    #[error(transparent)]
    Report(#[from] nlsdof_report::ReportError),
    /// A bad command-line value: what was given and what is allowed.
    #[error("{0}")]
    Usage(String),
}
