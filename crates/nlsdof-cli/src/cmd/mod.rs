//! One module per CLI verb.
pub mod compare;
pub mod demo;
pub mod equiv;
pub mod fit;
pub mod fit_time;
pub mod frf;
pub mod frf_estimate;
pub mod frf_mhb;
pub mod hb_error;
pub mod landscape_plot;
pub mod linear_id;
pub mod phase_resonance;
pub mod roots;
pub mod signal;
pub mod simulate;
pub mod spectrogram;
pub mod stepped_sine;
