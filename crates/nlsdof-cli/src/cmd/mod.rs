//! One module per CLI verb.
pub mod equiv;
pub mod frf;
pub mod roots;
