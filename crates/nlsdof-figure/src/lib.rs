//! # nlsdof-figure — the figure layer of nlsdof
//!
//! One way to draw every figure of the tool, so that the commands, the
//! demo report and any other front end look alike and state their units:
//!
//! * [`render`] / [`render_png`] — line figures: a grid of [`Panel`]s, each
//!   with its own axes (linear or logarithmic), [`Series`] of lines, dashed
//!   lines or markers in the shared [`COLOURS`] palette, and a legend laid
//!   out by hand in a [`Corner`]. SVG and PNG come from the same drawing
//!   code (plotters' SVG and bitmap backends).
//! * [`heatmap_png`] / [`waterfall_png`] — STFT spectrograms (the paper's
//!   Fig 8) as PNG: 10⁶–10⁷ cells are too many for SVG.
//! * [`viridis`] and [`encode_png`] for figures drawn by their callers.
//!
//! Text is rasterised from DejaVu Sans embedded in the crate
//! ([`fonts::register`]), so no system font is needed anywhere. Nothing here
//! writes a file: every function returns the document (SVG text or PNG
//! bytes), and the caller decides where and how to write it (the CLI writes
//! atomically). Errors are [`FigureError`].
//!
//! ```
//! use nlsdof_figure::{colour, render, Panel, Series, Style};
//! let mut p = Panel::new("Response", "frequency [Hz]", "amplitude [mm]");
//! let points = (0..50).map(|i| (10.0 + 0.1 * i as f64, (i as f64 * 0.2).sin().abs()));
//! p.series.push(Series::new(points.collect(), colour(0), Style::Line(2)).label("0.1 g"));
//! let svg = render("Stepped sine", &[p], 1, 640, 420).unwrap();
//! assert!(svg.starts_with("<svg") && svg.contains("frequency [Hz]"));
//! ```

pub mod fonts;
mod grid_map;
mod panel;
mod spectrogram;

pub use grid_map::{grid_map_png, grid_map_svg, GridMap};
pub use panel::*;
/// Colours of series (the palette is [`COLOURS`]).
pub use plotters::style::RGBColor;
pub use spectrogram::{encode_png, heatmap_png, viridis, waterfall_png, DYNAMIC_RANGE_DB};

/// Why a figure could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FigureError {
    /// The drawing backend failed (e.g. a font could not be used).
    #[error("cannot draw {figure}: {detail}")]
    Draw {
        figure: &'static str,
        detail: String,
    },
    #[error("cannot encode PNG: {0}")]
    Encode(String),
    #[error("no spectrogram to plot")]
    NoSpectrogram,
    #[error("frequency range {min}..{max} Hz must be finite and increasing")]
    BadFrequencyRange { min: f64, max: f64 },
    #[error(
        "spectrogram {label:?} is empty or malformed ({n_time} x {n_freq} cells, {values} values)"
    )]
    MalformedSpectrogram {
        label: String,
        n_time: usize,
        n_freq: usize,
        values: usize,
    },
    #[error(
        "spectrogram {label:?} has no frequency bin in {min}..{max} Hz (bins {first} .. {last} Hz)"
    )]
    NoBinInRange {
        label: String,
        min: f64,
        max: f64,
        first: f64,
        last: f64,
    },
}
