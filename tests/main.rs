//! Integration tests: one binary, one module per subsystem.

mod bvh;
mod common;
#[cfg(feature = "embree")]
mod embree;
mod lod;
#[cfg(feature = "embree")]
mod render;
mod sky;
