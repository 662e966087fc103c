//! Integration tests: one binary, one module per subsystem.

mod common;
#[cfg(feature = "embree")]
mod embree;
#[cfg(feature = "embree")]
mod render;
