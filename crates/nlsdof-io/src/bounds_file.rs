//! Parameter bounds for `nlsdof fit --bounds FILE`: a TOML table of
//! `name = [min, max]` (numbers, integers accepted).
//!
//! The same rules as `apply_bounds` in the CLI's `fit` command, as a parser
//! of its own so that it can be tested and fuzzed without the CLI.

use crate::error::IoError;
use std::path::Path;

/// `(name, min, max)` in file order.
pub fn parse_bounds(text: &str, path: &Path) -> Result<Vec<(String, f64, f64)>, IoError> {
    let parse = |message: String| IoError::Parse {
        path: path.to_path_buf(),
        message,
    };
    let table: toml::Table =
        toml::from_str(crate::strip_bom(text)).map_err(|e| parse(e.message().to_string()))?;
    let mut out = Vec::with_capacity(table.len());
    for (name, v) in table {
        let arr = v
            .as_array()
            .filter(|a| a.len() == 2)
            .ok_or_else(|| parse(format!("{name} must be [min, max]")))?;
        let num = |x: &toml::Value| x.as_float().or_else(|| x.as_integer().map(|i| i as f64));
        match (num(&arr[0]), num(&arr[1])) {
            (Some(lo), Some(hi)) => out.push((name, lo, hi)),
            _ => return Err(parse(format!("{name} bounds must be numbers"))),
        }
    }
    Ok(out)
}

/// Reads a bounds file.
pub fn read_bounds(path: &Path) -> Result<Vec<(String, f64, f64)>, IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_bounds(&text, path)
}
