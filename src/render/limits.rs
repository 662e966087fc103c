//! What a render may refuse, and why: its errors, the memory it needs before anything is
//! allocated, and the folding it tolerates.

use thiserror::Error;

use super::Camera;
#[cfg(feature = "embree")]
use crate::accel::embree::EmbreeError;
use crate::config::{ConfigError, SceneConfig};
use crate::image_io::ImageError;
use crate::lod::LodError;
use crate::ocean::OceanError;

#[derive(Debug, Error)]
pub enum RenderError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error(transparent)]
    Ocean(#[from] OceanError),
    #[error(transparent)]
    Lod(#[from] LodError),
    #[error(transparent)]
    #[cfg(feature = "embree")]
    Embree(#[from] EmbreeError),
    #[error(
        "this build has no Embree (built without the `embree` feature): use render.backend = \"rust\" (--backend rust)"
    )]
    NoEmbree,
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error(transparent)]
    Objects(#[from] crate::objects::ObjectError),
    #[error("cannot start the worker threads")]
    Threads(#[from] rayon::ThreadPoolBuildError),
    #[error(
        "the camera (camera.height_m = {camera_m} m) is not above the sea: the surface under it stands at {surface_m:.3} m (waves with their horizontal displacement); raise the camera or calm the sea"
    )]
    CameraUnderwater { camera_m: f64, surface_m: f64 },
    #[error(
        "{:.1}% of the sea surface folds over itself (Jacobian <= 0; ocean.choppiness = {choppiness}): above {:.0}% it is a tangle of overlapping triangles, not a sea; lower ocean.choppiness",
        100.0 * folded, 100.0 * MAX_FOLDED_FRACTION
    )]
    Folded { folded: f64, choppiness: f64 },
    #[error(
        "this render needs about {} ({} for the {pixels}-pixel film, {} for {triangles} triangles and their BVH), more than the {} this process can still allocate; lower the width or the tessellation",
        crate::memory::gigabytes(*need), crate::memory::gigabytes(*film), crate::memory::gigabytes(*mesh), crate::memory::gigabytes(*available)
    )]
    OutOfMemory {
        need: u64,
        film: u64,
        mesh: u64,
        pixels: u64,
        triangles: u64,
        available: u64,
    },
    #[error("the exact surface: {0}")]
    Exact(String),
    #[error("the {backend} backend could not move the mesh to the next frame: {message}")]
    Refit {
        backend: &'static str,
        message: String,
    },
    #[error("the {backend} backend reported an error while tracing: {message}")]
    Trace {
        backend: &'static str,
        message: String,
    },
    /// A shared ocean ([`Setup::ocean`]) used where it cannot be: a programming error.
    #[error("a shared ocean {0}")]
    SharedOcean(&'static str),
}

/// Largest share of the sea surface that may fold over itself (Jacobian <= 0); more is refused.
/// Any fold warns.
pub const MAX_FOLDED_FRACTION: f64 = 0.10;

/// Bytes a triangle of the tessellation takes with its share of the vertices and the BVH
/// (paper-high's 22.3 M triangles peak at 2.7 GB in a whole render: 120 bytes each).
pub const BYTES_PER_TRIANGLE: u64 = 120;

/// Refuses a render that cannot fit in memory, before anything is allocated.
pub(super) fn check_memory(
    cfg: &SceneConfig,
    triangles: usize,
    batches: usize,
    keep_states: bool,
) -> Result<(), RenderError> {
    let camera = Camera::new(cfg.camera.aimed(), cfg.camera.width, cfg.camera.aspect);
    let pixels = (camera.width * camera.height) as u64;
    let film = super::film::film_bytes(pixels, batches, keep_states);
    let mesh = triangles as u64 * BYTES_PER_TRIANGLE;
    let need = film + mesh;
    match crate::memory::available_bytes() {
        Some(available) if need > available => Err(RenderError::OutOfMemory {
            need,
            film,
            mesh,
            pixels,
            triangles: triangles as u64,
            available,
        }),
        _ => Ok(()),
    }
}
