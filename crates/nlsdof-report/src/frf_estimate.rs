//! The document of `nlsdof frf-estimate --json` (and of Python's
//! `frf_estimate`): method, sampling, Welch layout, lines kept, mean
//! coherence and the output file.

use nlsdof::signal_processing::frf_estimate::window_name;
use nlsdof::signal_processing::{FrfLines, Symmetry};
use serde_json::{json, Value};

/// The summary of an FRF estimate; `out` is the FRF CSV written, if any
/// (`null` otherwise).
pub fn json(e: &FrfLines, out: Option<&str>) -> Value {
    json!({
        "method": e.method.name(),
        "fs": e.fs,
        "samples": e.samples,
        "segment": e.segment,
        "averages": e.averages,
        "resolution_hz": e.resolution_hz(),
        "lines": e.frequency_hz.len(),
        "mean_coherence": e.mean_coherence(),
        "window": e.window.map_or("none", window_name),
        "window_form": match e.symmetry {
            Symmetry::Symmetric => "symmetric",
            Symmetry::Periodic => "periodic",
        },
        "out": out,
    })
}

/// The one-line text summary of the CLI.
pub fn text(e: &FrfLines) -> String {
    let f = &e.frequency_hz;
    format!(
        "{}: fs = {} Hz, {} samples, segment {} ({} averages), resolution {:.6} Hz, {} lines {:.6} .. {:.6} Hz{}",
        e.method.name(),
        e.fs,
        e.samples,
        e.segment,
        e.averages,
        e.resolution_hz(),
        f.len(),
        f[0],
        f[f.len() - 1],
        e.mean_coherence()
            .map(|c| format!(", mean coherence {c:.4}"))
            .unwrap_or_default()
    )
}
