//! What a render may refuse, and why: its errors, the memory it needs before anything is
//! allocated, and the folding it tolerates.

use thiserror::Error;

use super::Camera;
#[cfg(feature = "embree")]
use crate::accel::embree::EmbreeError;
use crate::config::{Backend, ConfigError, NormalMode, SceneConfig, SurfaceKind};
use crate::image_io::ImageError;
use crate::lod::LodError;
use crate::ocean::OceanError;

/// Filtered normals on the exact surface need the surfaces of the layers' levels, which a scene
/// prepared with other normals did not build: a render asking for them is refused, where its
/// paths would meet the whole sea and shade as if they met their drawn levels.
pub(super) fn check_exact_levels(
    accel: &dyn crate::accel::Accel,
    normals: crate::config::NormalMode,
) -> Result<(), RenderError> {
    if normals == crate::config::NormalMode::Filtered
        && accel.exact_surface()
        && !accel.exact_levels()
    {
        return Err(RenderError::Exact(
            "filtered normals need the levels' surfaces, and this scene was prepared without \
             them: prepare it with render.normals = \"filtered\""
                .into(),
        ));
    }
    Ok(())
}

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
        "this render needs about {} ({} for the {pixels}-pixel film, {} for the ocean, {} for {triangles} triangles and their BVH), more than the {} this process can still allocate; lower the width, the tessellation or the ocean's layers",
        crate::memory::gigabytes(*need), crate::memory::gigabytes(*film), crate::memory::gigabytes(*ocean), crate::memory::gigabytes(*mesh), crate::memory::gigabytes(*available)
    )]
    OutOfMemory {
        need: u64,
        film: u64,
        ocean: u64,
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

/// Bytes a triangle of the tessellation takes with its share of the vertices and of the
/// acceleration structure that traces it, from the peak memory of paper-high's 22.3 M triangles
/// in a whole render less paper-low's (docs/performance.md, "Memory"), rounded up by some 5 %:
/// Embree's grids 35 B (39 B not compact), Embree's triangles 60 B (123 B not compact), the
/// Rust BVH 128 B.
pub fn bytes_per_triangle(backend: Backend, grids: bool, compact: bool) -> u64 {
    match (backend, grids, compact) {
        (Backend::Rust, ..) => 135,
        (Backend::Embree, true, true) => 37,
        (Backend::Embree, true, false) => 41,
        (Backend::Embree, false, true) => 64,
        (Backend::Embree, false, false) => 130,
    }
}

/// Bytes the ocean of `cfg` takes once built, from above: each layer's texels (eight f32
/// fields, 32 B a cell) and amplitudes (at most a complex f32 a cell), the transforms' planes,
/// sized for the largest layer (four complex f32 planes over at most half its rows, 16 B a
/// cell). The default sea: 0.42 GB counted, 0.37 GB at the peak of `vastocean ocean`
/// (docs/performance.md, "Memory"). What the normals or the surface add is [`ocean_extra_bytes`].
pub fn ocean_bytes(cfg: &SceneConfig) -> u64 {
    let layers = &cfg.ocean.layers;
    let texels = texel_bytes(cfg);
    let amplitudes: u64 = layers.iter().map(|l| 8 * cells(l.n)).sum();
    let planes = layers.iter().map(|l| 16 * cells(l.n)).max().unwrap_or(0);
    texels + amplitudes + planes
}

/// What a render of `cfg` adds to its ocean, as far as it is not built already: filtered
/// normals' levels (a third of the texels, built on an ocean's first filtered render and kept
/// with it) or the exact surface's pyramids (under half of them, built with every scene that
/// traces the exact surface).
pub fn ocean_extra_bytes(cfg: &SceneConfig, levels_built: bool, pyramids_built: bool) -> u64 {
    match (cfg.render.normals, cfg.render.surface) {
        (NormalMode::Filtered, _) if !levels_built => texel_bytes(cfg) / 3,
        (NormalMode::Filtered, _) => 0,
        (_, SurfaceKind::Exact) if !pyramids_built => texel_bytes(cfg) / 2,
        _ => 0,
    }
}

fn cells(n: usize) -> u64 {
    (n * n) as u64
}

fn texel_bytes(cfg: &SceneConfig) -> u64 {
    cfg.ocean.layers.iter().map(|l| 32 * cells(l.n)).sum()
}

/// What of a render's ocean is built when its memory is checked.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum OceanAtHand {
    /// Nothing: a scene that builds its own ocean.
    None,
    /// The ocean, built already (shared by another scene, or by a mounted camera's placing),
    /// and filtered normals' levels if `levels`; the scene's exact-surface pyramids are still
    /// to build.
    Shared { levels: bool },
    /// A prepared scene's: all but filtered normals' levels unless `levels`.
    Prepared { levels: bool },
}

/// What a render of `cfg` over `triangles` needs before anything is allocated: its pixels, and
/// the bytes of its film, of its ocean (what is not built already) and of its mesh with what
/// traces it.
fn memory_needed(
    cfg: &SceneConfig,
    triangles: usize,
    batches: usize,
    keep_states: bool,
    ocean: OceanAtHand,
) -> (u64, u64, u64, u64) {
    let pixels = pixels(cfg);
    let film = super::film::film_bytes(pixels, batches, keep_states);
    let ocean = match ocean {
        OceanAtHand::None => ocean_bytes(cfg) + ocean_extra_bytes(cfg, false, false),
        OceanAtHand::Shared { levels } => ocean_extra_bytes(cfg, levels, false),
        OceanAtHand::Prepared { levels } => ocean_extra_bytes(cfg, levels, true),
    };
    let r = &cfg.render;
    let grids = embree_grids(cfg, triangles);
    let mesh = triangles as u64 * bytes_per_triangle(r.backend, grids, r.compact_bvh);
    (pixels, film, ocean, mesh)
}

/// The pixels of a render of `cfg`.
fn pixels(cfg: &SceneConfig) -> u64 {
    let c = &cfg.camera;
    let camera = Camera::new(c.aimed(), c.width, c.aspect);
    (camera.width * camera.height) as u64
}

/// Whether Embree takes the `triangles` of a render of `cfg` as grids (its
/// `render.embree_geometry`, `auto` deciding by the camera samples): what the BVH is built as
/// and what the memory check counts. Never for the exact surface, whose coarse triangles bound
/// user geometry.
pub(super) fn embree_grids(cfg: &SceneConfig, triangles: usize) -> bool {
    cfg.render.surface == SurfaceKind::Mesh
        && cfg
            .render
            .embree_geometry
            .grids_for(triangles, pixels(cfg) * u64::from(cfg.render.spp))
}

/// Refuses a render that cannot fit in memory, before anything is allocated (the ocean's share
/// as far as `ocean` is not built already).
pub(super) fn check_memory(
    cfg: &SceneConfig,
    triangles: usize,
    batches: usize,
    keep_states: bool,
    ocean: OceanAtHand,
) -> Result<(), RenderError> {
    let (pixels, film, ocean, mesh) = memory_needed(cfg, triangles, batches, keep_states, ocean);
    let need = film + ocean + mesh;
    match crate::memory::available_bytes() {
        Some(available) if need > available => Err(RenderError::OutOfMemory {
            need,
            film,
            ocean,
            mesh,
            pixels,
            triangles: triangles as u64,
            available,
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::EmbreeGeometry;

    /// A shared ocean, without filtered normals' levels.
    const SHARED: OceanAtHand = OceanAtHand::Shared { levels: false };

    #[test]
    fn the_memory_check_counts_what_traces_the_mesh() {
        // paper-high's 22.3 M triangles at 1024 px: grids under `auto` at 16 spp, triangles
        // past 400 spp; the check's mesh figure follows, within the measured peaks (+ 10 %)
        let tris = 22_341_600;
        let mut cfg = SceneConfig::default();
        cfg.camera.width = 1024;
        // (the default backend is the Rust BVH in a build without Embree)
        cfg.render.backend = Backend::Embree;
        let mesh_gb = |cfg: &SceneConfig| memory_needed(cfg, tris, 8, false, SHARED).3 as f64 / 1e9;
        cfg.render.spp = 16;
        let grids = mesh_gb(&cfg);
        assert!((0.77..0.85).contains(&grids), "{grids}");
        cfg.render.spp = 1024;
        let triangles = mesh_gb(&cfg);
        assert!((1.35..1.49).contains(&triangles), "{triangles}");
        cfg.render.embree_geometry = EmbreeGeometry::Grids;
        assert_eq!(mesh_gb(&cfg), grids);
        cfg.render.backend = Backend::Rust;
        let rust = mesh_gb(&cfg);
        assert!((2.8..3.1).contains(&rust), "{rust}");
    }

    #[test]
    fn the_memory_check_counts_the_ocean_unless_it_is_built() {
        // the default sea: 0.37 GB at the peak of `vastocean ocean`, counted from above
        let mut cfg = SceneConfig::default();
        let ocean = |cfg: &SceneConfig, at_hand| memory_needed(cfg, 0, 8, false, at_hand).2;
        let gb = ocean_bytes(&cfg) as f64 / 1e9;
        assert!((0.37..0.45).contains(&gb), "{gb}");
        assert_eq!(ocean(&cfg, SHARED), 0);
        assert_eq!(ocean(&cfg, OceanAtHand::None), ocean_bytes(&cfg));
        // filtered normals' levels add a third of the texels, unless a shared ocean has them
        cfg.render.normals = NormalMode::Filtered;
        let levels = ocean(&cfg, OceanAtHand::None) - ocean_bytes(&cfg);
        assert!(levels as f64 / 1e9 > 0.08, "{levels}");
        assert_eq!(ocean(&cfg, SHARED), levels);
        assert_eq!(ocean(&cfg, OceanAtHand::Shared { levels: true }), 0);
        assert_eq!(ocean(&cfg, OceanAtHand::Prepared { levels: false }), levels);
        assert_eq!(ocean(&cfg, OceanAtHand::Prepared { levels: true }), 0);
        // the exact surface's pyramids are every render's own, shared ocean or not
        cfg.render.normals = NormalMode::Mapped;
        cfg.render.surface = SurfaceKind::Exact;
        let pyramids = ocean(&cfg, SHARED);
        assert!(pyramids as f64 / 1e9 > 0.11, "{pyramids}");
        assert_eq!(ocean(&cfg, OceanAtHand::None), ocean_bytes(&cfg) + pyramids);
        assert_eq!(ocean(&cfg, OceanAtHand::Shared { levels: true }), pyramids);
        assert_eq!(ocean(&cfg, OceanAtHand::Prepared { levels: false }), 0);
        // a 4096-texel layer more: half a gigabyte of texels alone
        cfg.render.surface = SurfaceKind::Mesh;
        let n = cfg.ocean.layers[0];
        cfg.ocean
            .layers
            .push(crate::ocean::LayerSpec { n: 4096, ..n });
        assert!(ocean_bytes(&cfg) as f64 / 1e9 > gb + 0.5 + 0.13);
    }

    #[test]
    fn embree_takes_grids_by_the_cameras_samples_and_never_for_the_exact_surface() {
        // `auto`: paper-high at 1024 px takes grids at 16 spp (8.4 M camera samples) and
        // triangles at 1024 spp; the exact surface's coarse triangles are never grids
        let mut cfg = SceneConfig::default();
        cfg.camera.width = 1024;
        cfg.render.spp = 16;
        assert!(embree_grids(&cfg, 22_341_600));
        cfg.render.spp = 1024;
        assert!(!embree_grids(&cfg, 22_341_600));
        cfg.render.embree_geometry = EmbreeGeometry::Grids;
        assert!(embree_grids(&cfg, 25_520));
        cfg.render.surface = SurfaceKind::Exact;
        assert!(!embree_grids(&cfg, 25_520));
    }
}
