//! Stub (being implemented).
