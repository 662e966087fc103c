//! The exact ocean surface on Embree: the coarse triangles' prisms as user geometry, whose
//! bounds and intersect callbacks (through the shim) are [`crate::accel::exact`]'s. Embree
//! builds its BVH over the prisms' boxes and calls the intersect callback for each prism a ray
//! meets; the ray's search ([`Query`]: the surface it meets, the stretch searched) rides in
//! the query context, so overlapping prisms do not search one stretch twice.

use std::ffi::{c_int, c_void};
use std::ptr::NonNull;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use super::{BuildOptions, Device, EmbreeError, error_name, ffi};
use crate::accel::exact::{ExactSurface, Query, intersect_each, prisms_of, top_of};
use crate::accel::{Accel, Hit, Ray};
use crate::mesh::Mesh;
use crate::ocean::slopes::{ALL_WAVES, LevelSet};

/// What the callbacks read: the surface, the prisms and the triangles' texture coordinates.
struct Prisms {
    surface: ExactSurface,
    prisms: Vec<([f32; 3], [f32; 3])>,
    mesh: Arc<Mesh>,
}

/// A committed Embree scene whose one geometry is the exact surface's prisms (backend name
/// "embree-exact").
pub struct ExactScene {
    raw: NonNull<c_void>,
    device: Arc<Device>,
    /// Read by Embree's threads through the callbacks' user pointer until the scene is
    /// released (in `Drop`, before these are).
    data: Box<Prisms>,
    _callbacks: Box<ffi::vo_user_geometry>,
    top_y: f32,
    build_seconds: f64,
    bytes: u64,
    rejected: AtomicU64,
}

// SAFETY: as for `Scene`: a committed scene is only traced; the callbacks' data is immutable
// (`ExactSurface` and the prisms are `Sync`), and per-ray state lives in each query's context.
unsafe impl Send for ExactScene {}
unsafe impl Sync for ExactScene {}

unsafe extern "C" fn bounds(user: *mut c_void, prim: u32, lower: *mut f32, upper: *mut f32) {
    // SAFETY: `user` is the `Prisms` this geometry was attached with, alive while Embree builds;
    // Embree asks for prim < the primitive count, and lower / upper point to 3 floats.
    unsafe {
        let d = &*(user as *const Prisms);
        let (lo, hi) = d.prisms[prim as usize];
        std::ptr::copy_nonoverlapping(lo.as_ptr(), lower, 3);
        std::ptr::copy_nonoverlapping(hi.as_ptr(), upper, 3);
    }
}

unsafe extern "C" fn intersect(
    user: *mut c_void,
    query: *mut c_void,
    prim: u32,
    ray: *const ffi::vo_ray,
    t: *mut f32,
    u: *mut f32,
    v: *mut f32,
) -> c_int {
    // SAFETY: as in `bounds`; `ray` has `Ray`'s layout (checked in the parent module); `query`
    // is null or the `Query` of this ray, owned by the thread tracing it; t, u, v are
    // writable floats.
    unsafe {
        let d = &*(user as *const Prisms);
        let ray = &*(ray as *const Ray);
        let mut fresh;
        let query = match (query as *mut Query).as_mut() {
            Some(q) => q,
            None => {
                fresh = d.surface.query(&ALL_WAVES);
                &mut fresh
            }
        };
        let (uvs, idx) = (d.mesh.uvs(), d.mesh.indices());
        let tri = idx[prim as usize].map(|k| uvs[k as usize]);
        match d
            .surface
            .intersect_prism(ray, tri, &d.prisms[prim as usize], ray.tfar, query)
        {
            Some((th, uh, vh)) => {
                (*t, *u, *v) = (th, uh, vh);
                1
            }
            None => 0,
        }
    }
}

impl ExactScene {
    /// The prisms of every triangle of the coarse `mesh` attached to a new scene on `device`
    /// and committed (Embree builds its BVH over their boxes).
    pub fn new(
        device: &Arc<Device>,
        mesh: Arc<Mesh>,
        surface: ExactSurface,
        options: BuildOptions,
    ) -> Result<ExactScene, EmbreeError> {
        if mesh.triangle_count() >= u32::MAX as usize {
            return Err(EmbreeError::TooLarge(mesh.triangle_count()));
        }
        let start = Instant::now();
        let prisms = prisms_of(&mesh, &surface);
        let top_y = top_of(&prisms);
        let count = prisms.len();
        let data = Box::new(Prisms {
            surface,
            prisms,
            mesh,
        });
        let callbacks = Box::new(ffi::vo_user_geometry {
            bounds: Some(bounds),
            intersect: Some(intersect),
            user: &*data as *const Prisms as *mut c_void,
        });
        let dev = device.raw.as_ptr();
        let _building = device.building.lock().unwrap_or_else(|e| e.into_inner());
        // released in Drop or on the error paths below
        let scene = super::scene::new_scene(device, options, 0)?;
        let release = |e| {
            // SAFETY: scene is live and not yet owned by an ExactScene value.
            unsafe { ffi::vo_scene_release(scene.as_ptr()) };
            e
        };
        let mut geom_id = 0u32;
        // SAFETY: `callbacks` and `data` are boxed (stable addresses) and kept in the returned
        // value, which releases the scene before dropping them.
        let geometry = unsafe {
            ffi::vo_scene_attach_user(
                dev,
                scene.as_ptr(),
                options.quality.raw(),
                count,
                &*callbacks,
                &mut geom_id,
            )
        };
        device.check("rtcAttachGeometry").map_err(release)?;
        if geometry.is_null() {
            return Err(release(EmbreeError::Call {
                call: "rtcNewGeometry",
                code: 1,
                name: error_name(1),
                message: "no geometry returned".into(),
            }));
        }
        let before = device.memory().0;
        // SAFETY: scene is live and complete.
        unsafe { ffi::vo_scene_commit(scene.as_ptr()) };
        let bytes = device.memory().0.saturating_sub(before);
        device.check("rtcCommitScene").map_err(release)?;
        Ok(ExactScene {
            raw: scene,
            device: device.clone(),
            data,
            _callbacks: callbacks,
            top_y,
            build_seconds: start.elapsed().as_secs_f64(),
            bytes,
            rejected: AtomicU64::new(0),
        })
    }

    /// Seconds the prisms and Embree's BVH over them took.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// The highest point of any prism: nothing of the surface lies above it.
    pub fn top_y(&self) -> f32 {
        self.top_y
    }
}

impl ExactScene {
    /// The closest hit of `ray` on the surface `lod`.
    fn intersect_at(&self, ray: &Ray, lod: &LevelSet) -> Option<Hit> {
        if !ray.is_finite() {
            self.rejected.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        let mut h = ffi::vo_hit::default();
        let mut query = self.data.surface.query(lod);
        // SAFETY: Ray has vo_ray's layout; the scene is committed; `query` outlives the call,
        // which hands it to this thread's callbacks only.
        unsafe {
            ffi::vo_intersect1_query(
                self.raw.as_ptr(),
                ray as *const Ray as *const ffi::vo_ray,
                &mut h,
                &mut query as *mut Query as *mut c_void,
            )
        };
        (h.prim != ffi::VO_INVALID_ID).then_some(Hit {
            t: h.t,
            prim: h.prim,
            u: h.u,
            v: h.v,
        })
    }
}

impl Accel for ExactScene {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.intersect_at(ray, &ALL_WAVES)
    }

    fn intersect_many_at(&self, rays: &[Ray], lods: &[LevelSet], hits: &mut [Option<Hit>]) {
        intersect_each(rays, lods, hits, |r, lod| self.intersect_at(r, lod));
    }

    fn mesh(&self) -> &Mesh {
        &self.data.mesh
    }

    fn name(&self) -> &'static str {
        "embree-exact"
    }

    fn exact_surface(&self) -> bool {
        true
    }

    fn exact_levels(&self) -> bool {
        self.data.surface.levels()
    }

    fn surface_normal(&self, hit: &Hit, lod: &LevelSet) -> Option<([f32; 3], f32)> {
        let s = &self.data.surface;
        let n = s.normal_at(self.interpolate_uv(hit).map(f64::from), lod);
        Some((n, s.hit_error_m(lod)))
    }

    fn rejected_rays(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }

    fn bytes(&self) -> u64 {
        self.bytes
            + (std::mem::size_of_val(self.data.prisms.as_slice()) + self.data.surface.bytes())
                as u64
    }

    fn take_error(&self) -> Option<String> {
        self.device.check("tracing").err().map(|e| e.to_string())
    }
}

impl Drop for ExactScene {
    fn drop(&mut self) {
        // SAFETY: released once, before the callbacks' data (dropped after this) goes.
        unsafe { ffi::vo_scene_release(self.raw.as_ptr()) }
    }
}
