//! The surface at a hit as shading needs it (point, geometric normal, rounding bound, the ray
//! leaving it) and the wrong-side policy: what happens when a shading normal disagrees with
//! the triangle it shades.

use glam::Vec3;

use super::counters::Counters;
use crate::accel::{Hit, Ray};
use crate::config::WrongSide;
use crate::fp;
use crate::mesh::Mesh;

/// The surface at a hit, as shading needs it.
#[derive(Clone, Copy)]
pub(super) struct SurfacePoint {
    pub p: Vec3,
    /// Geometric normal, oriented to the air side (agreeing with the vertex normals).
    pub ng: Vec3,
    /// Bound on the rounding error of `p`, per component.
    pub err: Vec3,
    /// The triangle hit: rays spawned here must never meet it again.
    pub prim: u32,
}

/// The point of `hit` on an object's triangle `tri` (corners in the scene, placed by its
/// instance's transform in f32), its geometric normal the winding's (v1 - v0) x (v2 - v0):
/// outward on a mesh wound outward. `scale`: the size of the coordinates the backend
/// intersected in (its instance's translation plus its prototype's extent).
pub(super) fn surface_point_on(tri: [Vec3; 3], hit: &Hit, scale: f32) -> SurfacePoint {
    let [p0, p1, p2] = tri;
    let (b1, b2) = (hit.u, hit.v);
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    // As for the sea's, plus the rounding of the transform between the prototype's frame, in
    // which the backend intersects, and the scene's: a few ulps of the larger coordinates of
    // either (the point's, or the translation's and the prototype's).
    let err = fp::barycentric_error([b0, b1, b2], [p0, p1, p2])
        + Vec3::splat(fp::gamma(8.0) * (p.abs().max_element() + scale));
    let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y);
    SurfacePoint {
        p,
        ng,
        err,
        prim: hit.prim,
    }
}

pub(super) fn surface_point(mesh: &Mesh, hit: &Hit) -> SurfacePoint {
    let tri = mesh.indices()[hit.prim as usize];
    let [p0, p1, p2] = mesh.triangle(hit.prim).map(Vec3::from);
    let (b1, b2) = (hit.u, hit.v);
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    // The interpolated point's own error bound, plus the error of the backend evaluating the
    // triangle's plane at the ray origin in f32, which scales with the coordinates' magnitude
    // in every direction (a flat sea has no error in y from interpolation, yet Embree, which
    // has no conservative t check like pbrt's, can find t = 0 on its own plane).
    let err = fp::barycentric_error([b0, b1, b2], [p0, p1, p2])
        + Vec3::splat(fp::gamma(3.0) * p.abs().max_element());
    let mut ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    let nv = if mesh.normals().is_empty() {
        Vec3::Y
    } else {
        Vec3::from(Mesh::interpolate(mesh.normals(), tri, b1, b2))
    };
    if ng.dot(nv) < 0.0 {
        ng = -ng;
    }
    if ng == Vec3::ZERO {
        ng = nv.normalize_or(Vec3::Y);
    }
    SurfacePoint {
        p,
        ng,
        err,
        prim: hit.prim,
    }
}

/// The surface at a hit on the exact displaced surface ([`crate::accel::exact`]): the point on
/// the ray, the surface's own tangent plane's normal `normal` as the geometric normal, and a
/// rounding bound that adds the root finder's distance from the surface, `root_error_m`.
pub(super) fn exact_surface_point(
    ray: &Ray,
    hit: &Hit,
    normal: Vec3,
    root_error_m: f32,
) -> SurfacePoint {
    let (o, d) = (Vec3::from(ray.org), Vec3::from(ray.dir));
    let p = o + hit.t * d;
    let err = fp::gamma(3.0) * (o.abs() + (hit.t * d).abs()) + Vec3::splat(root_error_m);
    SurfacePoint {
        p,
        ng: normal.normalize_or(Vec3::Y),
        // The normal comes from the hit's nominal position in f32 texture coordinates
        // (centimetres off at tens of kilometres, across the bilinear surface's kinks), so
        // the offset does not rely on its orientation: the error's whole length on every
        // axis, at least that length along the normal, a margin rather than pbrt's
        // projection. (With the projection, rays leaving hits 45 km from a camera 10 km up met
        // the surface again; half a millimetre more cleared them.)
        err: Vec3::splat(err.length()),
        prim: hit.prim,
    }
}

impl SurfacePoint {
    /// The ray leaving the surface along `w`, its origin moved just far enough to `w`'s side
    /// to clear the hit's rounding error (pbrt-v4's OffsetRayOrigin), so it cannot meet its own
    /// triangle again.
    pub fn spawn(&self, w: Vec3) -> Ray {
        let o = fp::offset_ray_origin(self.p, self.err, self.ng, w);
        Ray::new(o.to_array(), w.to_array())
    }
}

/// The ray leaving the surface of `mesh` at `hit` along `w`, as the integrator spawns its
/// secondary rays (for tests and cross-checks).
pub fn spawn_ray(mesh: &Mesh, hit: &Hit, w: Vec3) -> Ray {
    surface_point(mesh, hit).spawn(w)
}

/// A new direction `w` on its proper side of the triangle (normal `ng`, facing the incoming
/// ray), as the policy wants it: unchanged when it is on its side; otherwise mirrored back
/// across the triangle's plane, keeping its weight, or (`Terminate`) no direction at all.
/// Wrong-side directions are counted.
pub(super) fn keep_side(
    w: Vec3,
    ng: Vec3,
    want_same_side_as_ng: bool,
    policy: WrongSide,
    c: &mut Counters,
) -> Option<Vec3> {
    let s = w.dot(ng);
    if (s > 0.0) == want_same_side_as_ng {
        return Some(w);
    }
    c.wrong_side += 1;
    if policy == WrongSide::Terminate {
        c.terminated += 1;
        return None;
    }
    let m = w - 2.0 * s * ng;
    Some(if m.dot(ng) == 0.0 {
        if want_same_side_as_ng { ng } else { -ng }
    } else {
        m
    })
}

/// Cycles' `ensure_valid_reflection` (after Keller et al. 2017, "The Iray Light Transport
/// Simulation and Rendering System"): the shading normal `n` bent, in the plane of `n` and the
/// geometric normal `ng`, just enough that the mirror reflection of `i` (towards the viewer,
/// on `ng`'s side) leaves at least as steeply as 90 % of the incoming ray's elevation (at most
/// 0.01). Unchanged when the reflection is valid already.
pub fn bend_normal(ng: Vec3, i: Vec3, n: Vec3) -> Vec3 {
    let ni = n.dot(i);
    let (r, threshold) = if ni > 0.0 {
        let r = 2.0 * ni * n - i;
        let threshold = bend_threshold(ng, i);
        if ng.dot(r) >= threshold {
            return n;
        }
        (r, threshold)
    } else {
        (-i, 0.01)
    };
    let r = r + ng * (threshold - ng.dot(r));
    (i * r.length() + r * i.length()).normalize_or(ng)
}

/// The lowest elevation on `ng` (as a dot product) a reflection of `i` may leave at under the
/// `bend` policy: 90 % of the incoming ray's, at most 0.01.
pub fn bend_threshold(ng: Vec3, i: Vec3) -> f32 {
    (0.9 * ng.dot(i)).min(0.01)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bending_lifts_the_reflection_just_above_the_surface() {
        let ng = Vec3::Y;
        // Grazing view (i towards the viewer) of a normal tilted away: the mirror reflection
        // would go below the surface.
        let i = Vec3::new(-0.99, 0.02, 0.0).normalize();
        let n = Vec3::new(0.3, 0.95, 0.0).normalize();
        assert!((2.0 * n.dot(i) * n - i).dot(ng) < 0.0);
        let b = bend_normal(ng, i, n);
        let r = 2.0 * b.dot(i) * b - i;
        let threshold = (0.9 * ng.dot(i)).min(0.01);
        assert!((r.dot(ng) - threshold).abs() < 1e-4, "{r}");
        assert!((b.length() - 1.0).abs() < 1e-5);
        // A normal whose reflection is valid is left alone.
        assert_eq!(bend_normal(ng, Vec3::new(-0.6, 0.8, 0.0), n), n);
        // A normal facing away from the viewer is turned towards it.
        let away = bend_normal(ng, i, Vec3::new(0.999, 0.04, 0.0).normalize());
        assert!(away.dot(i) > 0.0 && (2.0 * away.dot(i) * away - i).dot(ng) > 0.0);
    }
}
