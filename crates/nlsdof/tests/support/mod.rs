//! Test support shared by every test file and bench of the core crate
//! (`mod support;`, benches through `#[path]`): the paper's wing and the
//! seeded generator ([`fixtures`]), and the seeded synthetic identification
//! cases ([`synthetic`]). Not every binary uses every item.
#![allow(dead_code)]

pub mod fixtures;
pub mod synthetic;
