//! Exhaustive ray-triangle intersection in f64: every ray against every triangle. Far too slow
//! to render with, and meant to be: it is the independent witness that the tests compare
//! Embree and the Rust BVH against, with no acceleration structure of its own to get wrong.

use glam::DVec3;

use super::{Accel, Hit, Ray};
use crate::mesh::Mesh;

/// Where the ray's line meets the triangle's plane, in f64 (Möller–Trumbore without any
/// inside or range test): `(t, u, v)` with Embree's barycentric convention, or `None` when the
/// line is parallel to the plane or the triangle is degenerate. Shared by the oracle and by the
/// cross-checks that ask how far a ray passes from a triangle's edges.
pub fn line_hit(ray: &Ray, tri: [[f32; 3]; 3]) -> Option<(f64, f64, f64)> {
    let f = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (o, d, p0) = (f(ray.org), f(ray.dir), f(tri[0]));
    let (e1, e2) = (f(tri[1]) - p0, f(tri[2]) - p0);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - p0;
    let qv = tv.cross(e1);
    Some((e2.dot(qv) * inv, tv.dot(pv) * inv, d.dot(qv) * inv))
}

/// Möller–Trumbore in f64 without backface culling. Returns `(t, u, v)` with Embree's
/// barycentric convention, or `None` for a miss or a ray parallel to the triangle.
pub fn intersect_triangle(ray: &Ray, tri: [[f32; 3]; 3]) -> Option<(f64, f64, f64)> {
    let (t, u, v) = line_hit(ray, tri)?;
    let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
    (inside && t >= ray.tnear as f64 && t <= ray.tfar as f64).then_some((t, u, v))
}

/// A triangle as the oracle's loop wants it: first corner and the two edges from it, in f64.
struct Tri64 {
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
}

/// The brute-force backend: owns its mesh, loops over all triangles per ray.
pub struct BruteForce {
    mesh: Mesh,
    tris: Vec<Tri64>,
}

impl BruteForce {
    pub fn new(mesh: Mesh) -> BruteForce {
        let f = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let tris = (0..mesh.triangle_count() as u32)
            .map(|p| {
                let [a, b, c] = mesh.triangle(p).map(f);
                Tri64 {
                    p0: a,
                    e1: b - a,
                    e2: c - a,
                }
            })
            .collect();
        BruteForce { mesh, tris }
    }

    /// Every hit of `ray`: `(t, prim, u, v)`, unordered. The arithmetic is [`line_hit`]'s and
    /// the acceptance [`intersect_triangle`]'s, with early exits on the barycentrics.
    fn hits<'a>(&'a self, ray: &Ray) -> impl Iterator<Item = (f64, u32, f64, f64)> + 'a {
        let f = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let (o, d) = (f(ray.org), f(ray.dir));
        let (tnear, tfar) = (ray.tnear as f64, ray.tfar as f64);
        self.tris.iter().enumerate().filter_map(move |(p, tri)| {
            let pv = d.cross(tri.e2);
            let det = tri.e1.dot(pv);
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let inv = 1.0 / det;
            let tv = o - tri.p0;
            let u = tv.dot(pv) * inv;
            // (NaN fails too.)
            if u.is_nan() || u < 0.0 {
                return None;
            }
            let qv = tv.cross(tri.e1);
            let v = d.dot(qv) * inv;
            if !(v >= 0.0 && u + v <= 1.0) {
                return None;
            }
            let t = tri.e2.dot(qv) * inv;
            (t >= tnear && t <= tfar).then_some((t, p as u32, u, v))
        })
    }

    /// All triangles the ray hits, as `(t, prim)` in f64, nearest first.
    pub fn all_hits(&self, ray: &Ray) -> Vec<(f64, u32)> {
        let mut hits: Vec<(f64, u32)> = self.hits(ray).map(|(t, p, _, _)| (t, p)).collect();
        hits.sort_by(|a, b| a.0.total_cmp(&b.0));
        hits
    }

    /// The nearest hit in f64: `(t, prim, u, v)` (the first triangle of equal distances).
    pub fn nearest(&self, ray: &Ray) -> Option<(f64, u32, f64, f64)> {
        self.hits(ray)
            .fold(None, |best: Option<(f64, u32, f64, f64)>, h| {
                if best.is_none_or(|b| h.0 < b.0) {
                    Some(h)
                } else {
                    best
                }
            })
    }
}

impl Accel for BruteForce {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.nearest(ray).map(|(t, prim, u, v)| Hit {
            t: t as f32,
            prim,
            u: u as f32,
            v: v as f32,
        })
    }

    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn name(&self) -> &'static str {
        "brute"
    }

    fn bytes(&self) -> u64 {
        std::mem::size_of_val(self.tris.as_slice()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_quad_with_embree_barycentrics() {
        let m = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
            vec![],
            vec![],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let b = BruteForce::new(m);
        let h = b
            .intersect(&Ray::new([0.25, 2.0, 0.5], [0.0, -1.0, 0.0]))
            .unwrap();
        assert_eq!((h.t, h.prim, h.u, h.v), (2.0, 0, 0.25, 0.5));
        assert!(
            b.intersect(&Ray::new([0.75, 2.0, 0.5], [0.0, -1.0, 0.0]))
                .is_none()
        );
        // parallel ray in the triangle's plane: a miss, not a NaN
        assert!(
            b.intersect(&Ray::new([-1.0, 0.0, 0.1], [1.0, 0.0, 0.0]))
                .is_none()
        );
    }
}
