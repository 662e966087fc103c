//! Safe layer over Debian's Embree (3.13 or 4.x) through the C shim in `wrapper/`.
//!
//! Ownership: a [`Device`] is shared (`Arc`) by the scenes built on it and released last. A
//! [`Scene`] exists only committed: [`Scene::new`] attaches the mesh, commits (timing the BVH
//! build) and returns a value with no mutating methods, so nothing can change it while it is
//! traced. The scene holds the `Arc<Mesh>` whose buffers Embree shares, which keeps them alive
//! and unmodified for exactly as long as Embree may read them.
//!
//! Errors: Embree reports device errors through a callback into a per-device sink; setup calls
//! (device, attach, commit) check it and turn anything there into an [`EmbreeError`]. Ray
//! queries are never checked per ray, as Embree's documentation advises.

mod describe;
mod device;
mod grids;
mod instances;
mod scene;
mod user;

pub use describe::{EmbreeInfo, describe, versions};
pub use device::{Device, flush_denormals_on_this_thread};
pub use instances::Instances;
pub use scene::Scene;
pub use user::ExactScene;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::Ray;

#[allow(non_camel_case_types, non_upper_case_globals, dead_code, clippy::all)]
mod ffi {
    include!(concat!(env!("OUT_DIR"), "/embree_shim.rs"));
}

// `Ray` is handed to the shim as `vo_ray` without copying; these prove the layouts agree.
const _: () = {
    assert!(size_of::<Ray>() == size_of::<ffi::vo_ray>());
    assert!(align_of::<Ray>() == align_of::<ffi::vo_ray>());
    assert!(std::mem::offset_of!(Ray, tnear) == std::mem::offset_of!(ffi::vo_ray, tnear));
    assert!(std::mem::offset_of!(Ray, dir) == std::mem::offset_of!(ffi::vo_ray, dir));
    assert!(std::mem::offset_of!(Ray, tfar) == std::mem::offset_of!(ffi::vo_ray, tfar));
};

#[derive(Debug, Error)]
pub enum EmbreeError {
    #[error("could not create an Embree device with config {config:?}: {message}")]
    Device { config: String, message: String },
    #[error("Embree reported {name} (code {code}) during {call}: {message}")]
    Call {
        call: &'static str,
        code: i32,
        name: &'static str,
        message: String,
    },
    #[error("the mesh's buffers are not padded for Embree's 16-byte vertex loads")]
    Unpadded,
    #[error("the mesh has {0} triangles; Embree's index buffer holds at most 2^32-1")]
    TooLarge(usize),
    #[error("the scene's mesh is shared, so its vertices cannot move")]
    Shared,
    #[error("the moved mesh is invalid: {0}")]
    Mesh(String),
}

fn error_name(code: i32) -> &'static str {
    match code {
        0 => "RTC_ERROR_NONE",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU",
        6 => "RTC_ERROR_CANCELLED",
        _ => "RTC_ERROR_UNKNOWN",
    }
}

/// BVH build quality (Embree's RTCBuildQuality). `Refit` applies to the geometry: the scene is
/// then built at low quality, as the two-level structure in which Embree honours a geometry's
/// own quality, and [`Scene::refit`] refits the geometry's BVH instead of rebuilding it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    Low,
    #[default]
    Medium,
    High,
    Refit,
}

crate::config::choice!(Quality { Low => "low", Medium => "medium", High => "high", Refit => "refit" });

impl Quality {
    fn raw(self) -> ffi::vo_quality {
        match self {
            Quality::Low => ffi::VO_QUALITY_LOW,
            Quality::Medium => ffi::VO_QUALITY_MEDIUM,
            Quality::High => ffi::VO_QUALITY_HIGH,
            Quality::Refit => ffi::VO_QUALITY_REFIT,
        }
    }
}

/// How a scene is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildOptions {
    pub quality: Quality,
    /// Smaller BVH nodes, somewhat slower traversal (`RTC_SCENE_FLAG_COMPACT`; the default:
    /// paper-high's render peak 3.15 -> 2.22 GB and its build 6.1 -> 4.6 s for 3-5 % slower
    /// tracing, docs/performance.md).
    pub compact: bool,
    /// Watertight traversal: a ray through a shared edge hits exactly one triangle.
    pub robust: bool,
    /// Hand a mesh's blocks of whole cells ([`crate::mesh::Block`]) to Embree as grids
    /// (`RTC_GEOMETRY_TYPE_GRID`) and only its other triangles as triangles: the same
    /// triangles, a BVH over far fewer primitives (docs/performance.md, "Grids"). Meshes
    /// without blocks are triangles whatever this says.
    pub grids: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            quality: Quality::Medium,
            compact: true,
            robust: true,
            grids: true,
        }
    }
}
