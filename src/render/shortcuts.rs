//! Bounds of a mesh that let the integrator skip rays that cannot meet it, the triangle test
//! that answers a camera ray on its pixel's predicted triangle, and the integrator's answers
//! to the rays it need not trace.

use glam::Vec3;

use super::counters::Counters;
use super::integrator::{CAMERA_BATCH, PathVertex, SceneRef, TraceSettings};
use crate::accel::{Hit, Ray};
use crate::mesh::Mesh;

/// The steepest slope (height change per horizontal metre) of any triangle of a mesh that is a
/// height field in y, or `None` when the shortcuts it enables would not be exact: some triangle
/// is wound facing sideways or down (an overhang, where choppy waves fold; meshes here are
/// wound counter-clockwise seen from above), has a vertex normal that disagrees with its
/// winding (the integrator takes the air side from the vertex normals), or has a slope of 1
/// or more. Over the mesh's footprint the surface then changes height by at most this much
/// per metre, so a ray under it that descends faster never meets it again, nor does a ray
/// above it that climbs faster: neither need be traced (see `SceneRef::skip_slope`). The
/// argument follows the ray's path over the footprint, which is convex for the default square
/// pattern up to the cell-sized steps of its cut edge (and of a frustum pattern's sides),
/// where a ray leaves the mesh for good in practice. Slopes under 1 also guarantee that a ray
/// origin offset below one triangle is below its neighbours too (two faces sloping opposite
/// ways would need gradients whose dot product is below -1 to put it above one of them).
pub fn max_slope(mesh: &Mesh) -> Option<f32> {
    use rayon::prelude::*;
    let normals = mesh.normals();
    // per triangle: Some(slope), or None for one facing sideways or down
    let worst = (0..mesh.triangle_count() as u32)
        .into_par_iter()
        .map(|prim| {
            let [a, b, c] = mesh.triangle(prim).map(Vec3::from);
            let n = (b - a).cross(c - a);
            if n == Vec3::ZERO {
                return Some(0.0); // degenerate: no area to hit
            }
            let agree = normals.is_empty()
                || mesh.indices()[prim as usize]
                    .iter()
                    .all(|&v| Vec3::from(normals[v as usize]).dot(n) > 0.0);
            (n.y > 0.0 && agree).then(|| (n.x * n.x + n.z * n.z).sqrt() / n.y)
        })
        .try_reduce(|| 0f32, |a, b| Some(a.max(b)))?;
    (worst < 1.0).then_some(worst)
}

/// The largest y of any vertex: a ray leaving upwards from above it never meets the mesh (every
/// point of a triangle is a mean of its vertices), so it need not be traced
/// (`SceneRef::skip_above_y`). `None` for an empty mesh.
pub fn highest_vertex_y(mesh: &Mesh) -> Option<f32> {
    use rayon::prelude::*;
    mesh.positions()
        .par_iter()
        .map(|p| p[1])
        .reduce_with(f32::max)
}

/// The hit of `ray` on triangle `tri` (primitive `prim`), with Embree's barycentrics, or `None`:
/// Möller and Trumbore's test (1997) in f32, for the predicted hits of camera rays
/// ([`SceneRef::predict_camera_prim`]). It is not watertight (a ray within rounding of an edge
/// may miss both triangles), which costs nothing there: a ray that misses goes to the BVH, and
/// a hit is within rounding of the triangle, so on the surface. The Rust BVH's watertight test
/// here (its slab set-up and its conservative bound against t = 0, which camera rays do not
/// need) left the default scene's trace 0.2-0.3 s slower.
#[inline]
pub fn hit_on_triangle(ray: &Ray, tri: [Vec3; 3], prim: u32) -> Option<Hit> {
    let (d, s) = (Vec3::from(ray.dir), Vec3::from(ray.org) - tri[0]);
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    let q = s.cross(e1);
    let inv = 1.0 / det;
    let (u, v, t) = (s.dot(p) * inv, d.dot(q) * inv, e2.dot(q) * inv);
    // Written so that a NaN (a ray parallel to the triangle) is a miss.
    let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
    (inside && t >= ray.tnear && t <= ray.tfar && t.is_finite()).then_some(Hit { t, prim, u, v })
}

impl SceneRef<'_> {
    /// Whether a ray in the air leaves upwards from above the highest vertex (`skip_above_y`),
    /// where nothing of the sea lies ahead of it. (A ray with a NaN or infinite component is
    /// left to the backend, which counts it.)
    #[inline]
    pub(super) fn rises_above_the_sea(&self, ray: &Ray) -> bool {
        ray.dir[1] >= 0.0
            && self.skip_above_y.is_some_and(|top| ray.org[1] > top)
            && ray.is_finite()
    }

    /// Whether a ray is answered without the BVH: cut at `max_segments`, or known to miss the
    /// surface (the skip shortcuts), which is counted, as is a ray that must be traced.
    /// `spawned`: the ray leaves a hit (on the side of the triangle it travels in).
    pub(super) fn answer_untraced(
        &self,
        ray: &Ray,
        in_water: bool,
        spawned: bool,
        segment: u32,
        settings: &TraceSettings,
        c: &mut Counters,
    ) -> Untraced {
        if segment >= settings.max_segments {
            c.truncated += 1;
            return Untraced::Known(Vec3::ZERO);
        }
        let d = Vec3::from(ray.dir);
        if in_water && self.descends_steeply(d) {
            c.skipped += 1;
            return Untraced::Known(Vec3::from(settings.upwelling));
        }
        if !in_water && self.rises_above_the_sea(ray) {
            c.skipped_above += 1;
            return Untraced::Sky;
        }
        // The same argument as in the water, mirrored: a ray leaving a hit into the air (so
        // starting on or above the surface) and rising more steeply than the surface ever
        // does stays above it. Only spawned rays, whose origins are offset to the air side of
        // the triangle they leave: a camera is checked to be above the ocean at its nadir, not
        // above the mesh there (and rising camera rays are mostly skipped above anyway).
        if !in_water
            && spawned
            && let Some(slope) = self.skip_slope
            && d.y > slope * (d.x * d.x + d.z * d.z).sqrt()
            && ray.is_finite()
        {
            c.skipped_rising += 1;
            return Untraced::Sky;
        }
        c.rays += 1;
        Untraced::Trace
    }

    /// The sky along the rays `entries[k]` for each `k` in `ks` (at most a batch), looked up
    /// together in the sky's lanes and weighed against the sun's samples, into `out[k]`.
    pub(super) fn sky_along(&self, entries: &[PathVertex], ks: &[u8], out: &mut [Vec3]) {
        let n = ks.len();
        let (mut orgs, mut dirs) = ([Vec3::ZERO; CAMERA_BATCH], [Vec3::ZERO; CAMERA_BATCH]);
        for (j, &k) in ks.iter().enumerate() {
            let ray = &entries[k as usize].ray;
            (orgs[j], dirs[j]) = (ray.org.into(), ray.dir.into());
        }
        let mut l = [Vec3::ZERO; CAMERA_BATCH];
        self.sky.radiance_many(&orgs[..n], &dirs[..n], &mut l[..n]);
        for (j, &k) in ks.iter().enumerate() {
            let sun_pdf = entries[k as usize].sun_pdf;
            out[k as usize] = self.weigh_sun(orgs[j], dirs[j], sun_pdf, l[j]);
        }
    }

    /// What a traced ray that met nothing sees in the water: the upwelling light; `None` in
    /// the air, where it sees the sky, which the caller looks up for all its misses together.
    pub(super) fn miss(
        &self,
        ray: &Ray,
        in_water: bool,
        segment: u32,
        settings: &TraceSettings,
        c: &mut Counters,
    ) -> Option<Vec3> {
        let d = Vec3::from(ray.dir);
        if segment == 0 && !in_water && d.y < settings.must_hit_below_y {
            c.escaped_below_horizon += 1;
        }
        in_water.then_some(Vec3::from(settings.upwelling))
    }
}

/// How [`SceneRef::answer_untraced`] answers a ray.
pub(super) enum Untraced {
    /// Its radiance, known without the BVH.
    Known(Vec3),
    /// It cannot meet the surface: the sky's radiance along it.
    Sky,
    /// The BVH must find its hit.
    Trace,
}
