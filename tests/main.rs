//! Integration tests: one binary, one module per subsystem.

mod app;
mod bvh;
mod cli;
mod common;
mod defects;
mod docs;
#[cfg(feature = "embree")]
mod embree;
mod estimator;
mod exact;
mod far_field_glint;
mod filtered;
mod frames;
mod glass;
mod lod;
mod mount;
mod objects;
mod passes;
mod render;
mod render_batches;
mod sea_state;
mod sky;
mod stress;
mod study;
