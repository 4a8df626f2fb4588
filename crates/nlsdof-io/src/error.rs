use std::path::PathBuf;
use thiserror::Error;

/// Errors reading or writing nlsdof files. Each names the file and the
/// offending item.
#[derive(Debug, Error)]
pub enum IoError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{path}: {source}")]
    Invalid {
        path: PathBuf,
        source: nlsdof::ParameterError,
    },
    /// An output folder that cannot be used or created.
    #[error("--out {path}: {message}")]
    OutputFolder { path: PathBuf, message: String },
    #[error("{path}: line {line}: {message}")]
    Data {
        path: PathBuf,
        line: usize,
        message: String,
    },
}
