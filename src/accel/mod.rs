//! Ray-tracing backends behind one interface (DESIGN.md, "Ray tracing contract").
//!
//! The integrator only sees [`Accel`]: closest hit of one ray, or of a batch, as
//! `Hit { t, prim, u, v }` with Embree's barycentric convention (the hit point is
//! `(1-u-v)·v0 + u·v1 + v·v2`), and the texture coordinate interpolated at a hit. Backends:
//! [`embree`] (Debian's Embree through the C shim in `wrapper/`) and [`brute`] (an exhaustive
//! f64 loop, the oracle the tests compare every other backend against).

pub mod brute;
pub mod bvh;
#[cfg(feature = "embree")]
pub mod crosscheck;
#[cfg(feature = "embree")]
pub mod embree;
pub mod exact;

use crate::mesh::Mesh;
use crate::ocean::slopes::LevelSet;

/// A rayon pool of `threads` workers (0 = all cores) for building and tracing. With Embree,
/// every worker sets flush-to-zero and denormals-are-zero first, as Embree asks of every thread
/// that traces (DESIGN.md, Parallelism); every pool that traces is made here.
pub fn tracing_pool(threads: usize) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| {
            #[cfg(feature = "embree")]
            embree::flush_denormals_on_this_thread();
        })
        .build()
}

/// A ray: points `org + t·dir` for `t` in `[tnear, tfar]`. The layout matches the C shim's
/// `vo_ray`, so batches are handed to Embree without copying.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub tfar: f32,
}

impl Ray {
    pub fn new(org: [f32; 3], dir: [f32; 3]) -> Ray {
        Ray {
            org,
            tnear: 0.0,
            dir,
            tfar: f32::INFINITY,
        }
    }
    pub fn at(&self, t: f32) -> [f32; 3] {
        std::array::from_fn(|i| self.org[i] + t * self.dir[i])
    }
    /// Origin and direction finite, the range not NaN: a ray a backend may trace.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.org.iter().chain(&self.dir).all(|c| c.is_finite())
            && !self.tnear.is_nan()
            && !self.tfar.is_nan()
    }
}

/// The closest hit of a ray on primitive `prim` at parameter `t`, barycentrics `(u, v)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// What every tracing backend offers the integrator.
pub trait Accel: Send + Sync {
    /// Closest hit of `ray`, if any.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// Closest hits of many rays; `hits.len()` must equal `rays.len()`. The default traces
    /// them one by one; a backend with a batch path (Embree's: one foreign call) overrides it, and must
    /// return exactly what [`Accel::intersect`] returns for each ray: the integrator's images
    /// must not depend on how its rays were batched (tested on every backend).
    fn intersect_many(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            *h = self.intersect(r);
        }
    }
    /// [`Accel::intersect_many`] with each ray meeting the surface of the layers' levels
    /// `lods[i]` ([`crate::ocean::slopes::LevelSet`]): the exact surface of a filtered render,
    /// where each path meets the waves its footprint resolves. A backend with one surface (a
    /// mesh, or the exact surface without levels) ignores `lods`.
    fn intersect_many_at(&self, rays: &[Ray], lods: &[LevelSet], hits: &mut [Option<Hit>]) {
        debug_assert_eq!(rays.len(), lods.len(), "one surface per ray");
        self.intersect_many(rays, hits)
    }
    /// The mesh being traced.
    fn mesh(&self) -> &Mesh;
    /// Texture coordinate (nominal horizontal position) interpolated at a hit.
    fn interpolate_uv(&self, hit: &Hit) -> [f32; 2] {
        let m = self.mesh();
        Mesh::interpolate(m.uvs(), m.indices()[hit.prim as usize], hit.u, hit.v)
    }
    /// Whether hits lie on the displaced ocean itself ([`exact`]), not on the mesh's
    /// triangles: a ray leaving a hit may meet the same prism again, and the mesh's slopes and
    /// heights bound nothing.
    fn exact_surface(&self) -> bool {
        false
    }
    /// For [`Accel::exact_surface`] backends: whether rays may meet the surfaces of the
    /// layers' low-passed levels (built for filtered normals); without them every ray meets
    /// the whole sea.
    fn exact_levels(&self) -> bool {
        false
    }
    /// For [`Accel::exact_surface`] backends: the unit geometric normal of the surface `lod`
    /// at a hit on it (the displaced surface's own tangent plane, air side up), in place of a
    /// triangle's, and how far from the surface the hit point may lie beyond its f32
    /// rounding, m.
    fn surface_normal(&self, _hit: &Hit, _lod: &LevelSet) -> Option<([f32; 3], f32)> {
        None
    }
    /// Short name for reports ("embree", "brute", ...).
    fn name(&self) -> &'static str;
    /// Rays refused so far because their origin or direction was NaN or infinite (answered as
    /// misses; such a ray never reaches the traversal).
    fn rejected_rays(&self) -> u64 {
        0
    }
    /// Bytes of the acceleration structure (not counting the mesh it shares).
    fn bytes(&self) -> u64;
    /// Moves the mesh's vertices and vertex normals (same topology: an animation frame) and
    /// updates the structure over them (Embree refits its BVH when built with refit quality;
    /// the Rust BVH refits its bounds). Returns the seconds the structure's update took. Fails,
    /// changing nothing, when the vertices are invalid or another owner shares the mesh.
    fn update_vertices(
        &mut self,
        _positions: &[[f32; 3]],
        _normals: &[[f32; 3]],
    ) -> Result<f64, String> {
        Err(format!(
            "the {} backend cannot move its vertices",
            self.name()
        ))
    }
    /// An error the backend reported while tracing, if any, clearing it (Embree's device
    /// errors are not checked per ray, only here and on setup calls).
    fn take_error(&self) -> Option<String> {
        None
    }
}
