//! The one font of every plot: DejaVu Sans, embedded in the binary
//! (`assets/fonts/` of this crate, Bitstream Vera licence in
//! `LICENSE-DejaVu.txt`).
//!
//! plotters is built with its `ab_glyph` text backend so that PNG figures
//! can rasterise text without system fonts (CI machines and containers have
//! none). With that backend every text element — in SVG too, where it is
//! used to measure text for layout — needs a registered font, so
//! [`register`] is called before any drawing (every function of this crate
//! does; the CLI also calls it at the start of `main`).

use std::sync::Once;

/// The embedded TrueType font.
pub const DEJAVU_SANS: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers [`DEJAVU_SANS`] under the family names plotters' styles use
/// (`sans-serif`, and `serif`/`monospace` as fallbacks). Idempotent.
pub fn register() {
    static INIT: Once = Once::new();
    INIT.call_once(|| {
        for family in ["sans-serif", "serif", "monospace"] {
            // Cannot fail for a valid embedded font; a failure would surface
            // as a one-line plot error ("font unavailable") later.
            let _ = plotters::style::register_font(
                family,
                plotters::style::FontStyle::Normal,
                DEJAVU_SANS,
            );
        }
    });
}
