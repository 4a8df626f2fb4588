//! The studies behind the measured tables of `docs/`, as examples of this
//! crate (they read the shared data sets, so they are not part of the
//! tool):
//!
//! * `real_data_tables`: the default staged fit on the three clamped-beam
//!   sets, per level the measured and model jump, peak and RMS, and a
//!   cross-validation (docs/identification.md, "Real data");
//! * `beam_jumps`: the jump-weighted beam fits and the minimax check of the
//!   jump errors (docs/identification.md).
//!
//! ```text
//! cargo run --release -p nlsdof-studies --example real_data_tables -- [SHARED_DATA_DIR] [MODEL,..]
//! cargo run --release -p nlsdof-studies --example beam_jumps -- MODEL LAMBDA STARTS DECIMATE
//! ```
