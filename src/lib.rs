//! vastocean: FFT ocean layers, LOD doubling tessellation to the horizon on a curved earth,
//! ray tracing through Debian's Embree (or a pure-Rust BVH), and normal mapping as in
//! *Normal Maps for Rendering Vast Ocean Scenes*. See `DESIGN.md` in the shared folder for the
//! architecture; each module's own doc says which part of the paper it implements.

pub mod accel;
pub mod analysis;
pub mod config;
pub mod image_io;
pub mod lod;
pub mod mesh;
pub mod ocean;
pub mod render;
pub mod rng;
