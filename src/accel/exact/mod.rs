//! Exact hits on the displaced ocean, found inside the coarse tessellation's triangles instead
//! of on them: wave hiding without a fine mesh.
//!
//! Each coarse triangle bounds a prism: the box that provably holds the displaced surface X(x)
//! for every nominal position x of the triangle (the sphere under its corners, widened by the
//! layers' h bounds over the triangle from their pyramids, the largest horizontal displacement
//! and the curved frame's tilt of it). A ray that meets a prism searches its stretch inside it
//! for the first crossing of the whole surface ([`search`]: interval bounds, a certified march,
//! a bracketed root on the implicit function of [`implicit`]). Prisms overlap by the
//! displacement, so a crossing may be found from more than one; each reports the same first
//! crossing of its stretch, so the closest over all prisms is the ray's. The hit names the
//! prism's triangle and the barycentrics, relative to its corners' texture coordinates, of the
//! nominal position of the surface point hit (outside the triangle where the crossing lies in
//! a neighbour's part of the overlap): the texture coordinate interpolated at the hit is that
//! nominal position, so normal mapping reads the surface's own normal there.
//!
//! Only bilinear reads are supported: a bilinear value lies between its texels', which the
//! pyramids bound; a Catmull-Rom read overshoots them.

mod bounds;
mod implicit;
mod pyramid;
mod search;

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use super::bvh::BoxTree;
use super::{Accel, Hit, Ray};
use crate::mesh::Mesh;
use crate::ocean::slopes::{ALL_WAVES, LevelSet};
use crate::ocean::{Interp, Surface};
use bounds::{Steepness, SurfaceBounds};
use implicit::Implicit;

/// The displaced surface of an ocean around one camera origin, with the bounds the intersector
/// needs; with filtered normals, also the surfaces of the layers' low-passed levels, one of
/// which each path meets ([`View`]).
pub struct ExactSurface {
    ocean: Arc<Surface>,
    origin: [f64; 2],
    earth_radius_m: f64,
    bounds: SurfaceBounds,
    /// The largest |Dx| and |Dz| of any surface a ray may meet, m.
    prism_disp: [f64; 2],
    /// The largest |(Dx, h, Dz)| of any of them, m.
    prism_disp_norm: f64,
    /// The whole sea's view.
    all: View,
    /// Whether rays may meet the levels' surfaces (filtered normals).
    levels: bool,
}

/// What the search needs of one surface of the layers' levels ([`LevelSet`]: each layer read
/// from one of its levels, or left out): its bounds' whole-sea figures and the lengths the
/// search works at, which grow with the finest texel the surface reads.
#[derive(Clone, Copy, Debug)]
pub(super) struct View {
    lod: LevelSet,
    /// The surface's largest |Dx| and |Dz|, m.
    disp: [f64; 2],
    /// How far above h a surface point's altitude can be: |D|^2 / 2R (the displacement is
    /// tangent to the sphere at its base), m.
    altitude_slack: f64,
    /// The whole sea's slope and strain bounds.
    steep: Steepness,
    /// Its steepest slope in any direction (height over arc position, [`bounds::SlopeBound::norm`]),
    /// if the strain bound proves one.
    slope: Option<f64>,
    /// Segments are halved down to this length (arc), m: below the widening by the
    /// displacement, the bounds narrow slowly.
    split_m: f64,
    /// ... and, where no slope bound certifies a march, down to this: eight of the finest
    /// texels read.
    split_rough_m: f64,
    /// The shortest step of the march, m: half the finest texel read.
    floor_m: f64,
    /// The surface's largest |h|, m.
    height_limit: f64,
}

impl View {
    fn new(bounds: &SurfaceBounds, lod: &LevelSet, earth_radius_m: f64) -> View {
        let steep = bounds.sea_steepness(lod);
        let disp = bounds.disp(lod);
        // (a surface that reads no layer is the flat sea: any finite lengths do)
        let finest = bounds.finest_texel(lod).min(1e3);
        View {
            lod: *lod,
            altitude_slack: (disp[0] * disp[0] + disp[1] * disp[1]) / earth_radius_m + 1e-6,
            steep,
            slope: steep.slope_limit().map(|s| s.norm),
            split_m: disp[0].max(disp[1]).max(8.0 * finest),
            split_rough_m: 8.0 * finest,
            floor_m: 0.5 * finest,
            disp,
            height_limit: bounds.height_limit(lod),
        }
    }
}

/// One ray's search: the surface it meets and the stretch of it already searched. Embree's
/// callbacks receive it through the query context.
#[derive(Clone, Copy, Debug)]
pub struct Query {
    searched: Searched,
    view: View,
}

impl ExactSurface {
    /// The surface of `ocean` as a camera at world position `origin` (x, z) sees it, on an
    /// earth of radius `earth_radius_m`; with `levels`, also the surfaces of the ocean's
    /// low-passed levels ([`crate::ocean::levels::Levels`], built here if they are not yet),
    /// which filtered normals' paths meet.
    pub fn new(
        ocean: Arc<Surface>,
        origin: [f64; 2],
        earth_radius_m: f64,
        levels: bool,
    ) -> Result<ExactSurface, String> {
        if !matches!(
            ocean.params().interp,
            Interp::Bilinear | Interp::Prefiltered
        ) {
            return Err(format!(
                "the exact surface reads the layers bilinearly; ocean.interp is {}",
                ocean.params().interp
            ));
        }
        let bounds = SurfaceBounds::new(&ocean.sampler(origin), levels.then(|| ocean.levels()));
        let (prism_disp, h) = bounds.limits_any();
        let all = View::new(&bounds, &ALL_WAVES, earth_radius_m);
        Ok(ExactSurface {
            prism_disp,
            prism_disp_norm: (prism_disp[0] * prism_disp[0]
                + prism_disp[1] * prism_disp[1]
                + h * h)
                .sqrt(),
            all,
            levels,
            ocean,
            origin,
            earth_radius_m,
            bounds,
        })
    }

    /// Whether rays may meet the levels' surfaces (built for filtered normals).
    pub fn levels(&self) -> bool {
        self.levels
    }

    /// A ray's search of the surface `lod` (every layer whole, [`ALL_WAVES`], without levels).
    pub fn query(&self, lod: &LevelSet) -> Query {
        let view = if *lod == ALL_WAVES || !self.levels {
            self.all
        } else {
            View::new(&self.bounds, lod, self.earth_radius_m)
        };
        Query {
            searched: Searched::default(),
            view,
        }
    }

    fn sampler(&self) -> crate::ocean::Sampler<'_> {
        let s = self.ocean.sampler(self.origin);
        if self.levels {
            s.with_levels(self.ocean.levels())
        } else {
            s
        }
    }

    fn implicit(&self, view: &View) -> Implicit<'_> {
        Implicit {
            sampler: self.sampler(),
            lod: view.lod,
            earth_radius_m: self.earth_radius_m,
            lip: view.slope.map_or(f64::INFINITY, |s| 1.0 + s),
        }
    }

    /// How far an exact hit point on the surface `lod` may lie from it, m, beyond its f32
    /// rounding: the root's tolerance on F, what the inversion's residual can add to it (the
    /// slope bound, or 10 without one, times its tolerance), and the f32 rounding of the
    /// summed heights; doubled for room. The integrator offsets rays leaving an exact hit by
    /// this much more than a triangle hit's.
    pub fn hit_error_m(&self, lod: &LevelSet) -> f32 {
        let view = self.query(lod).view;
        let lip = 1.0 + view.slope.unwrap_or(10.0);
        (2.0 * (search::TOL_F + lip * implicit::TOL_S + 1e-6 * view.height_limit)) as f32
    }

    /// The box that holds the surface over the triangle of nominal corners `uv`.
    pub fn prism(&self, uv: [[f32; 2]; 3]) -> ([f32; 3], [f32; 3]) {
        let r = self.earth_radius_m;
        let uv = uv.map(|c| c.map(f64::from));
        let (x0, x1) = (
            uv.iter().map(|c| c[0]).fold(f64::INFINITY, f64::min),
            uv.iter().map(|c| c[0]).fold(f64::NEG_INFINITY, f64::max),
        );
        let (z0, z1) = (
            uv.iter().map(|c| c[1]).fold(f64::INFINITY, f64::min),
            uv.iter().map(|c| c[1]).fold(f64::NEG_INFINITY, f64::max),
        );
        let [hlo, hhi] = self.bounds.height_any(x0, x1, z0, z1);
        // the sphere under the corners, and how far the patch between them can bulge past
        // their box (a chord's sagitta d^2 / 8R, with room)
        let base = uv.map(|c| crate::lod::curved_frame_position(c[0], c[1], [0.0; 3], r));
        let d = (x1 - x0).hypot(z1 - z0);
        let bulge = d * d / r + 1e-3;
        let far = uv.iter().map(|c| c[0].hypot(c[1])).fold(0.0, f64::max) + d;
        // the tilt of the displacement away from the nadir's axes: a rotation by at most
        // theta moves a vector by at most theta times its length
        let tilt = self.prism_disp_norm * (far / r);
        let lo = std::array::from_fn(|k| base.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min));
        let hi =
            std::array::from_fn(|k| base.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max));
        let (lo, hi): ([f64; 3], [f64; 3]) = (lo, hi);
        let widen_lo = [-self.prism_disp[0], hlo, -self.prism_disp[1]];
        let widen_hi = [self.prism_disp[0], hhi, self.prism_disp[1]];
        // f32 corners rounded outwards
        let out = |v: f64, up: bool| -> f32 {
            let m = v.abs() * 1e-6 + 1e-4;
            (if up { v + m } else { v - m }) as f32
        };
        (
            std::array::from_fn(|k| out(lo[k] + widen_lo[k] - bulge - tilt, false)),
            std::array::from_fn(|k| out(hi[k] + widen_hi[k] + bulge + tilt, true)),
        )
    }

    /// The first crossing of the surface by `ray` inside `prism` with t at most `tmax`, as
    /// `(t, u, v)`: (u, v) the barycentrics of the nominal position hit relative to the
    /// triangle's texture coordinates `uv`.
    pub fn intersect_prism(
        &self,
        ray: &Ray,
        uv: [[f32; 2]; 3],
        prism: &([f32; 3], [f32; 3]),
        tmax: f32,
        query: &mut Query,
    ) -> Option<(f32, f32, f32)> {
        let o = ray.org.map(f64::from);
        let d = ray.dir.map(f64::from);
        let (mut t0, mut t1) = (ray.tnear.max(0.0) as f64, tmax as f64);
        for k in 0..3 {
            let (lo, hi) = (prism.0[k] as f64, prism.1[k] as f64);
            if d[k] == 0.0 {
                if o[k] < lo || o[k] > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - o[k]) / d[k], (hi - o[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        let view = &query.view;
        let (t, x) = query
            .searched
            .search(t0, t1, |a, b| self.first_crossing(view, o, d, a, b))?;
        let t32 = t as f32;
        if !(t32 >= ray.tnear && t32 <= tmax) {
            return None;
        }
        let uv = uv.map(|c| c.map(f64::from));
        let (e1, e2) = (
            [uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]],
            [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]],
        );
        let q = [x[0] - uv[0][0], x[1] - uv[0][1]];
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        let u = (q[0] * e2[1] - q[1] * e2[0]) / det;
        let v = (e1[0] * q[1] - e1[1] * q[0]) / det;
        Some((t32, u as f32, v as f32))
    }

    /// The unit normal of the surface `lod`'s own tangent plane at nominal position `x`
    /// (air side up), by central differences of X over 1 mm: the bilinear blend of the heights
    /// that the rays meet, where the mapped normal interpolates the layers' FFT derivatives
    /// instead (the two differ by up to a few degrees between texels).
    pub fn normal_at(&self, x: [f64; 2], lod: &LevelSet) -> [f32; 3] {
        const H: f64 = 1e-3;
        let sampler = self.sampler();
        // (without levels every ray meets the whole sea)
        let lod = if self.levels { lod } else { &ALL_WAVES };
        let at = |u: f64, v: f64| {
            let f = sampler.fields_f64_at(u, v, lod);
            let d = [
                f[crate::ocean::field::DX] as f64,
                f[crate::ocean::field::H] as f64,
                f[crate::ocean::field::DZ] as f64,
            ];
            crate::lod::curved_frame_position(u, v, d, self.earth_radius_m)
        };
        let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dx = sub(at(x[0] + H, x[1]), at(x[0] - H, x[1]));
        let dz = sub(at(x[0], x[1] + H), at(x[0], x[1] - H));
        // dX/dz x dX/dx points up on a flat sea (as the ocean's normals)
        let n = [
            dz[1] * dx[2] - dz[2] * dx[1],
            dz[2] * dx[0] - dz[0] * dx[2],
            dz[0] * dx[1] - dz[1] * dx[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len > 0.0 && len.is_finite() {
            n.map(|c| (c / len) as f32)
        } else {
            [0.0, 1.0, 0.0]
        }
    }

    /// Bytes of the bounds (the layers are the ocean's).
    pub fn bytes(&self) -> usize {
        self.bounds.bytes()
    }
}

/// The stretch of one ray already searched: prisms overlap, and a stretch searched from one
/// need not be searched again from the next (a camera ray near the camera crosses some 17
/// prism boxes over one stretch of sea).
#[derive(Clone, Copy, Debug)]
struct Searched {
    a: f64,
    b: f64,
}

impl Default for Searched {
    fn default() -> Self {
        Searched {
            a: f64::INFINITY,
            b: f64::NEG_INFINITY,
        }
    }
}

impl Searched {
    /// The first crossing in `[t0, t1]` by `search` over the parts not searched before; the
    /// searched stretch grows to cover `[t0, t1]` (up to the crossing, if one is found), or is
    /// replaced by it when the two are apart.
    fn search(
        &mut self,
        t0: f64,
        t1: f64,
        mut search: impl FnMut(f64, f64) -> Option<(f64, [f64; 2])>,
    ) -> Option<(f64, [f64; 2])> {
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return None;
        }
        if t1 < self.a || t0 > self.b {
            let hit = search(t0, t1);
            *self = Searched {
                a: t0,
                b: hit.map_or(t1, |h| h.0),
            };
            return hit;
        }
        if t0 < self.a {
            let hit = search(t0, self.a);
            self.a = t0;
            if let Some(h) = hit {
                self.b = h.0;
                return hit;
            }
        }
        if t1 > self.b {
            let hit = search(self.b, t1);
            self.b = hit.map_or(t1, |h| h.0);
            return hit;
        }
        None
    }
}

/// The exact surface behind the Rust backend's tree of prisms (backend name "rust-exact").
pub struct Exact {
    mesh: Arc<Mesh>,
    surface: ExactSurface,
    prisms: Vec<([f32; 3], [f32; 3])>,
    tree: BoxTree,
    top_y: f32,
    build_seconds: f64,
    rejected: AtomicU64,
}

impl Exact {
    /// The prisms of every triangle of the coarse `mesh` and the tree over them, on the
    /// current rayon pool.
    pub fn build(mesh: Arc<Mesh>, surface: ExactSurface) -> Exact {
        let start = Instant::now();
        let prisms = prisms_of(&mesh, &surface);
        let tree = BoxTree::build(&prisms);
        let top_y = top_of(&prisms);
        Exact {
            mesh,
            surface,
            prisms,
            tree,
            top_y,
            build_seconds: start.elapsed().as_secs_f64(),
            rejected: AtomicU64::new(0),
        }
    }

    /// Seconds the prisms and their tree took.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// The highest point of any prism: nothing of the surface lies above it.
    pub fn top_y(&self) -> f32 {
        self.top_y
    }

    /// The surface searched.
    pub fn surface(&self) -> &ExactSurface {
        &self.surface
    }
}

/// Each ray's closest hit on its own surface by `at`: both exact backends'
/// [`Accel::intersect_many_at`] (a ray's search is one call each, Embree's too).
pub fn intersect_each(
    rays: &[Ray],
    lods: &[LevelSet],
    hits: &mut [Option<Hit>],
    at: impl Fn(&Ray, &LevelSet) -> Option<Hit>,
) {
    assert!(rays.len() == hits.len() && lods.len() == rays.len());
    for ((r, lod), h) in rays.iter().zip(lods).zip(hits.iter_mut()) {
        *h = at(r, lod);
    }
}

/// The highest point of any of `prisms`: nothing of the surface lies above it.
pub fn top_of(prisms: &[([f32; 3], [f32; 3])]) -> f32 {
    prisms
        .iter()
        .map(|p| p.1[1])
        .fold(f32::NEG_INFINITY, f32::max)
}

/// The prism of every triangle of `mesh`, in triangle order.
pub fn prisms_of(mesh: &Mesh, surface: &ExactSurface) -> Vec<([f32; 3], [f32; 3])> {
    use rayon::prelude::*;
    let (uvs, idx) = (mesh.uvs(), mesh.indices());
    idx.par_iter()
        .map(|t| surface.prism(t.map(|v| uvs[v as usize])))
        .collect()
}

impl Exact {
    /// The closest hit of `ray` on the surface `lod`.
    pub fn intersect_at(&self, ray: &Ray, lod: &LevelSet) -> Option<Hit> {
        if !ray.is_finite() {
            self.rejected.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        let (uvs, idx) = (self.mesh.uvs(), self.mesh.indices());
        let mut query = self.surface.query(lod);
        self.tree.closest(ray, |prim, tmax| {
            let uv = idx[prim as usize].map(|v| uvs[v as usize]);
            let prism = &self.prisms[prim as usize];
            self.surface
                .intersect_prism(ray, uv, prism, tmax, &mut query)
        })
    }
}

impl Accel for Exact {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.intersect_at(ray, &ALL_WAVES)
    }
    fn intersect_many_at(&self, rays: &[Ray], lods: &[LevelSet], hits: &mut [Option<Hit>]) {
        intersect_each(rays, lods, hits, |r, lod| self.intersect_at(r, lod));
    }
    fn mesh(&self) -> &Mesh {
        &self.mesh
    }
    fn name(&self) -> &'static str {
        "rust-exact"
    }
    fn exact_surface(&self) -> bool {
        true
    }

    fn exact_levels(&self) -> bool {
        self.surface.levels
    }
    fn surface_normal(&self, hit: &Hit, lod: &LevelSet) -> Option<([f32; 3], f32)> {
        let n = self
            .surface
            .normal_at(self.interpolate_uv(hit).map(f64::from), lod);
        Some((n, self.surface.hit_error_m(lod)))
    }
    fn rejected_rays(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }
    fn bytes(&self) -> u64 {
        (self.tree.bytes() + std::mem::size_of_val(self.prisms.as_slice()) + self.surface.bytes())
            as u64
    }
}

#[cfg(test)]
mod tests;
