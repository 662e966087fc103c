//! vastocean: FFT ocean layers, LOD doubling tessellation to the horizon on a curved earth,
//! ray tracing through Debian's Embree (or a pure-Rust BVH), and normal mapping as in
//! *Normal Maps for Rendering Vast Ocean Scenes*. See `DESIGN.md` in the shared folder for the
//! architecture; each module's own doc says which part of the paper it implements.
//!
//! Layers, each importing only those below it:
//! - [`app`]: one job per command (render, compare, crosscheck, mesh, ocean, sky, smoke, info);
//! - [`analysis`], [`render`]: the paper's statistics; cameras, the path tracer, the pipeline;
//! - [`sky`], [`accel`], [`lod`]: sky light; Embree, the Rust BVH and the f64 oracle; tessellation;
//! - [`ocean`], [`mesh`]: the FFT surface; triangle buffers;
//! - [`config`], [`fp`], [`equirect`], [`color`], [`rng`], [`image_io`]: the scene description
//!   and the conventions everything shares.

pub mod accel;
pub mod analysis;
pub mod app;
pub mod color;
pub mod config;
pub mod equirect;
pub mod fp;
pub mod image_io;
pub mod lod;
pub mod memory;
pub mod mesh;
pub mod objects;
pub mod ocean;
pub mod render;
pub mod rng;
pub mod sky;
