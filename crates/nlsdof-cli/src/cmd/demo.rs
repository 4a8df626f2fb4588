//! `nlsdof demo` (placeholder while being written; replaced in this session).
use crate::error::CliError;

#[derive(clap::Args)]
pub struct Args {}

pub fn run(_a: Args) -> Result<(), CliError> {
    Err(CliError::Usage("`demo` is not implemented yet".into()))
}
