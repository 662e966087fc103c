//! A committed Embree scene over one triangle mesh: build, refit, and the [`Accel`] queries.

use std::ffi::c_void;
use std::ptr::NonNull;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use super::grids::{self, Split};
use super::{BuildOptions, Device, EmbreeError, error_name, ffi};
use crate::accel::{Accel, Hit, Ray};
use crate::mesh::Mesh;

/// A committed Embree scene holding one triangle mesh.
pub struct Scene {
    raw: NonNull<c_void>,
    geometry: NonNull<c_void>,
    /// Grids and triangles: the mesh's blocks as one geometry, its other triangles as another.
    split: Option<Split>,
    mesh: Arc<Mesh>,
    build_seconds: f64,
    options: BuildOptions,
    device: Arc<Device>,
    /// Rays with a NaN or infinite origin or direction, answered as misses without Embree.
    rejected: AtomicU64,
    /// What the device's memory monitor saw the build allocate (the BVH and Embree's own
    /// per-geometry data; the shared mesh buffers are not copied).
    bytes: u64,
}

// SAFETY: a committed scene is only read (rtcIntersect*, rtcOccluded*, rtcInterpolate), which
// Embree allows from any number of threads at once; `Scene` has no method that modifies it,
// and the shared mesh buffers are immutable behind the Arc.
unsafe impl Send for Scene {}
unsafe impl Sync for Scene {}

/// A new, empty scene on `device` (the caller releases it, and holds `device.building`).
pub(super) fn new_scene(
    device: &Device,
    options: BuildOptions,
    flags: u32,
) -> Result<NonNull<c_void>, EmbreeError> {
    // SAFETY: the device is live; the caller releases the scene.
    let scene = unsafe { ffi::vo_scene_new(device.raw.as_ptr(), options.quality.raw(), flags) };
    device.check("rtcNewScene")?;
    NonNull::new(scene).ok_or(EmbreeError::Call {
        call: "rtcNewScene",
        code: 1,
        name: error_name(1),
        message: "no scene returned".into(),
    })
}

/// Attaches the triangles `indices` over `mesh`'s vertices (and their texture coordinates
/// `uvs`, or null) to `scene` and returns the geometry and its id.
///
/// # Safety
/// `indices` must name vertices of `mesh`, whose positions are padded, and both (and `uvs`)
/// must outlive the scene unchanged.
pub(super) unsafe fn attach_triangles(
    device: &Device,
    scene: NonNull<c_void>,
    options: BuildOptions,
    mesh: &Mesh,
    indices: &[[u32; 3]],
    uvs: *const f32,
) -> Result<(NonNull<c_void>, u32), EmbreeError> {
    let mut geom_id = 0u32;
    // SAFETY: the caller's.
    let g = unsafe {
        ffi::vo_scene_attach_triangles(
            device.raw.as_ptr(),
            scene.as_ptr(),
            options.quality.raw(),
            mesh.positions().as_ptr() as *const f32,
            mesh.vertex_count(),
            indices.as_ptr() as *const u32,
            indices.len(),
            uvs,
            &mut geom_id,
        )
    };
    device.check("rtcAttachGeometry")?;
    Ok((returned(g)?, geom_id))
}

/// A geometry handle Embree returned, or the error of its absence.
pub(super) fn returned(g: *mut c_void) -> Result<NonNull<c_void>, EmbreeError> {
    NonNull::new(g).ok_or_else(|| EmbreeError::Call {
        call: "rtcNewGeometry",
        code: 1,
        name: error_name(1),
        message: "no geometry returned".into(),
    })
}

impl Scene {
    /// Attaches `mesh`, builds the BVH and returns the committed scene.
    pub fn new(
        device: &Arc<Device>,
        mesh: Arc<Mesh>,
        options: BuildOptions,
    ) -> Result<Scene, EmbreeError> {
        if !mesh.is_padded() {
            return Err(EmbreeError::Unpadded);
        }
        if mesh.triangle_count() >= u32::MAX as usize {
            return Err(EmbreeError::TooLarge(mesh.triangle_count()));
        }
        // Held from attach to commit: errors drained below are this build's.
        let _building = device.building.lock().unwrap_or_else(|e| e.into_inner());
        let flags = if options.compact {
            ffi::VO_SCENE_COMPACT
        } else {
            0
        } | if options.robust {
            ffi::VO_SCENE_ROBUST
        } else {
            0
        };
        let scene = new_scene(device, options, flags)?;
        let release = |e| {
            // SAFETY: scene is live and not yet owned by a Scene value.
            unsafe { ffi::vo_scene_release(scene.as_ptr()) };
            e
        };
        let uvs = if mesh.uvs().is_empty() {
            std::ptr::null()
        } else {
            mesh.uvs().as_ptr() as *const f32
        };
        let attached = if options.grids && !mesh.blocks().is_empty() {
            grids::attach(device, scene, options, &mesh)
        } else {
            // SAFETY: the mesh's index buffer is validated (in range), its positions and uvs
            // padded (checked above), all kept alive and unmodified by the Arc<Mesh> stored in
            // the returned Scene.
            unsafe { attach_triangles(device, scene, options, &mesh, mesh.indices(), uvs) }
                .map(|(g, _)| (g, None))
        };
        let (geometry, split) = attached.map_err(release)?;
        let before = device.memory().0;
        let start = Instant::now();
        // SAFETY: scene is live and complete.
        unsafe { ffi::vo_scene_commit(scene.as_ptr()) };
        let build_seconds = start.elapsed().as_secs_f64();
        let bytes = device.memory().0.saturating_sub(before);
        device.check("rtcCommitScene").map_err(release)?;
        Ok(Scene {
            raw: scene,
            geometry,
            split,
            mesh,
            build_seconds,
            options,
            device: device.clone(),
            rejected: AtomicU64::new(0),
            bytes,
        })
    }

    /// The Embree version of the device this scene was built on.
    pub fn device_version(&self) -> String {
        self.device.version()
    }

    /// Wall-clock seconds the BVH build (rtcCommitScene) took.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    pub fn options(&self) -> BuildOptions {
        self.options
    }

    /// Moves the mesh's vertices to `positions` in place (the topology stays) and updates the
    /// BVH: a refit of its bounds when the scene was built with [`Quality::Refit`], a rebuild
    /// otherwise. Returns the seconds Embree took. Fails without touching anything when
    /// something else still holds the scene's mesh or the positions are invalid.
    pub fn refit(&mut self, positions: &[[f32; 3]]) -> Result<f64, EmbreeError> {
        self.refit_with(|m| m.set_positions(positions))
    }

    /// As [`Scene::refit`], moving the vertex normals too (an animation frame).
    pub fn refit_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<f64, EmbreeError> {
        self.refit_with(|m| m.set_vertices(positions, normals))
    }

    fn refit_with(
        &mut self,
        update: impl FnOnce(&mut Mesh) -> Result<(), crate::mesh::MeshError>,
    ) -> Result<f64, EmbreeError> {
        let mesh = Arc::get_mut(&mut self.mesh).ok_or(EmbreeError::Shared)?;
        update(mesh).map_err(|e| EmbreeError::Mesh(e.to_string()))?;
        let _building = self
            .device
            .building
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let start = Instant::now();
        // SAFETY: the scene and geometry are live; the vertex buffer is the one attached (the
        // Vec was changed in place, never reallocated) and nothing traces while `&mut self`.
        let second = self
            .split
            .as_ref()
            .and_then(|s| s.rest)
            .map_or(std::ptr::null_mut(), |(g, _)| g.as_ptr());
        unsafe { ffi::vo_scene_refit(self.raw.as_ptr(), self.geometry.as_ptr(), second) };
        let seconds = start.elapsed().as_secs_f64();
        self.device.check("rtcCommitScene (refit)")?;
        Ok(seconds)
    }

    /// Axis-aligned bounds of the scene as Embree sees it: (lower, upper).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (mut lo, mut hi) = ([0f32; 3], [0f32; 3]);
        // SAFETY: scene is committed; the arrays have three elements each.
        unsafe { ffi::vo_scene_bounds(self.raw.as_ptr(), lo.as_mut_ptr(), hi.as_mut_ptr()) };
        (lo, hi)
    }

    /// Whether anything lies on the ray within `[tnear, tfar]`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !self.admit(ray) {
            return false;
        }
        // SAFETY: Ray has vo_ray's layout (checked at compile time); scene is committed.
        unsafe {
            ffi::vo_occluded1(self.raw.as_ptr(), ray as *const Ray as *const ffi::vo_ray) != 0
        }
    }
}

impl Scene {
    /// The committed scene's handle (for an instance that places it).
    pub(super) fn raw(&self) -> NonNull<c_void> {
        self.raw
    }

    /// Whether `ray` may be handed to Embree; counts the ones that may not.
    #[inline]
    fn admit(&self, ray: &Ray) -> bool {
        let ok = ray.is_finite();
        if !ok {
            self.rejected.fetch_add(1, Ordering::Relaxed);
        }
        ok
    }
}

impl Scene {
    /// Embree's hit as the mesh's: a grid's hit becomes its cell's triangle and barycentrics,
    /// a remaining triangle's its own.
    #[inline]
    fn to_hit(&self, h: &ffi::vo_hit) -> Option<Hit> {
        if h.prim == ffi::VO_INVALID_ID {
            return None;
        }
        let (prim, u, v) = match &self.split {
            None => (h.prim, h.u, h.v),
            Some(s) => s.hit(&self.mesh, h.geom, h.prim, h.u, h.v),
        };
        Some(Hit { t: h.t, prim, u, v })
    }
}

impl Accel for Scene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.admit(ray) {
            return None;
        }
        let mut h = ffi::vo_hit::default();
        // SAFETY: as in `occluded`; `h` is a valid out-parameter.
        unsafe {
            ffi::vo_intersect1(
                self.raw.as_ptr(),
                ray as *const Ray as *const ffi::vo_ray,
                &mut h,
            )
        };
        self.to_hit(&h)
    }

    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        // Fixed-size chunks keep the shim's output on the stack: no allocation per batch. Left
        // uninitialised: the shim writes every field of each ray's hit, and zeroing 64 hits
        // for batches of a few rays was a memset of 2.3 kB per call.
        const CHUNK: usize = 64;
        let mut out = [std::mem::MaybeUninit::<ffi::vo_hit>::uninit(); CHUNK];
        for (rs, hs) in rays.chunks(CHUNK).zip(hits.chunks_mut(CHUNK)) {
            if !rs.iter().all(Ray::is_finite) {
                // Rare: trace this chunk ray by ray, so the bad rays are answered (and counted)
                // without reaching Embree.
                for (r, h) in rs.iter().zip(hs.iter_mut()) {
                    *h = self.intersect(r);
                }
                continue;
            }
            // SAFETY: `rs` is a slice of vo_ray-layout rays; `out` has room for rs.len() hits,
            // and the shim writes all of each one (`vo_intersect_context`, hit or miss).
            unsafe {
                ffi::vo_intersect_batch(
                    self.raw.as_ptr(),
                    rs.as_ptr() as *const ffi::vo_ray,
                    out.as_mut_ptr().cast::<ffi::vo_hit>(),
                    rs.len(),
                )
            };
            for (h, o) in hs.iter_mut().zip(&out[..rs.len()]) {
                // SAFETY: written by the shim above.
                *h = self.to_hit(unsafe { o.assume_init_ref() });
            }
        }
    }

    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn interpolate_uv(&self, hit: &Hit) -> [f32; 2] {
        // In Rust from the barycentrics: rtcInterpolate through the shim cost ~157
        // instructions a hit (measured with callgrind), this a dozen. A foreign `Hit` must not
        // index outside the buffers.
        let m = &self.mesh;
        match m.indices().get(hit.prim as usize) {
            Some(&tri) if !m.uvs().is_empty() => Mesh::interpolate(m.uvs(), tri, hit.u, hit.v),
            _ => [0.0; 2],
        }
    }

    fn name(&self) -> &'static str {
        "embree"
    }

    fn rejected_rays(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }

    fn bytes(&self) -> u64 {
        self.bytes
    }

    fn update_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<f64, String> {
        self.refit_vertices(positions, normals)
            .map_err(|e| e.to_string())
    }

    fn take_error(&self) -> Option<String> {
        self.device.check("tracing").err().map(|e| e.to_string())
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: the scene (and the geometry it owns) is released once; the device outlives it
        // through `device`.
        unsafe { ffi::vo_scene_release(self.raw.as_ptr()) }
    }
}
