//! One module per CLI verb.
pub mod equiv;
pub mod frf;
pub mod roots;
pub mod signal;
pub mod simulate;
pub mod stepped_sine;
