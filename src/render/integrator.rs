//! The Monte Carlo path tracer of paper section 5: camera rays meet the tessellated ocean, and
//! every hit splits into a Fresnel reflection and a refraction (weights F and 1 - F), up to a
//! branching depth past which one of the two is chosen at random with probability F (the
//! estimator stays unbiased). Paths end after `max_segments` segments (the paper: 10). The
//! paths of one pixel's samples are traced together, a stage at a time
//! ([`SceneRef::radiance_batch`]), and each comes out bit for bit as it would alone.
//!
//! The shading normal is the interpolated vertex normal (`vertex`, the paper's "without
//! normal mapping") or, for `mapped` (paper section 4), the ocean normal of eq. 7 recomputed
//! from the layers at the texture coordinate interpolated at the hit and tilted into the
//! curved-earth frame there. A shading normal can disagree with the triangle it shades: face
//! away from the incoming ray, or send the reflected or refracted ray to the wrong side of the
//! geometric surface. [`WrongSide`] chooses what happens then (mirror the direction back, flip
//! the normal, bend it as Cycles and Iray do, or end the branch), and each case is counted.
//!
//! Secondary rays leave the surface offset along the geometric normal by a bound on the hit
//! point's floating-point error, rounded away from the surface (pbrt-v4, section 6.8.6;
//! [`crate::fp::offset_ray_origin`]), not by a fixed epsilon.

use glam::Vec3;
use serde::Serialize;

use super::water::{fresnel, reflect, refract};
use crate::accel::{Accel, Hit, Ray};
use crate::config::{NormalMode, SceneConfig, Water, WrongSide};
use crate::fp;
use crate::mesh::Mesh;
use crate::ocean::Sampler;
use crate::rng::Rng;
use crate::sky::Sky;

/// Path-tracing settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TraceSettings {
    pub normals: NormalMode,
    /// Most segments (rays) in one path.
    pub max_segments: u32,
    /// Hits up to this depth branch into both reflection and refraction; deeper ones choose one.
    pub branch_depth: u32,
    pub water: Water,
    pub wrong_side: WrongSide,
    /// Radiance a downward ray that never meets the surface again returns: the water's R_rs
    /// times the sky's irradiance (see [`Water::upwelling`]), resolved once per render.
    pub upwelling: [f32; 3],
    /// A camera ray with a direction's y below this must meet the sea (it dips under the
    /// horizon of the deepest troughs); one that escapes counts as a hole. -1 = never counted.
    pub must_hit_below_y: f32,
}

impl Default for TraceSettings {
    /// The default scene's settings under a sky of irradiance pi (radiance ~1).
    fn default() -> Self {
        TraceSettings::new(&SceneConfig::default(), Vec3::splat(std::f32::consts::PI))
    }
}

impl TraceSettings {
    /// The settings of `scene` under a sky of downwelling irradiance `sky_irradiance`.
    pub fn new(scene: &SceneConfig, sky_irradiance: Vec3) -> TraceSettings {
        TraceSettings {
            normals: scene.render.normals,
            max_segments: scene.render.max_segments,
            branch_depth: scene.render.branch_depth,
            water: scene.water,
            wrong_side: scene.render.wrong_side,
            upwelling: scene.water.upwelling(sky_irradiance).to_array(),
            must_hit_below_y: -1.0,
        }
    }
}

/// Per-render counts, summed over threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Counters {
    /// Rays whose closest hit was searched for: by the BVH, or for `predicted` of them on
    /// their pixel's predicted triangle.
    pub rays: u64,
    /// Ocean hits shaded.
    pub hits: u64,
    /// Samples whose radiance was NaN or infinite (dropped by the guard).
    pub nan: u64,
    /// Camera rays below the horizon that met no water (see [`TraceSettings::must_hit_below_y`]).
    pub escaped_below_horizon: u64,
    /// Rays spawned at a hit that met their own triangle again (self-intersection). Should be 0.
    pub self_hits: u64,
    /// Reflected or refracted rays the shading normal sent to the wrong side of the triangle.
    pub wrong_side: u64,
    /// Hits where the shading normal faced away from the incoming ray.
    pub backfacing_shading: u64,
    /// Shading normals bent by the `bend` policy.
    pub bent: u64,
    /// Branches (or, at a normal facing away, whole hits) ended by the `terminate` policy.
    pub terminated: u64,
    /// Paths cut at `max_segments` while still bouncing.
    pub truncated: u64,
    /// Rays in the water known not to meet the surface again, so not traced.
    pub skipped: u64,
    /// Rays in the air leaving a hit upwards more steeply than any slope of the mesh, so
    /// never meeting it again: not traced. Absent from pass files written before it.
    #[serde(default)]
    pub skipped_rising: u64,
    /// Rays leaving upwards from above the mesh's highest vertex, so never meeting it: not
    /// traced (the camera's upper half, for one). Absent from pass files written before it.
    #[serde(default)]
    pub skipped_above: u64,
    /// Camera rays whose hit was found on their pixel's predicted triangle, without the BVH
    /// (counted in `rays` too; see [`SceneRef::predict_camera_prim`]). Absent from pass files
    /// written before it.
    #[serde(default)]
    pub predicted: u64,
    /// Rays traced through the pixels' centres to predict those triangles (not in `rays`;
    /// every pass traces its pixels' again, so merged passes sum them). Absent from pass files
    /// written before it.
    #[serde(default)]
    pub prediction_rays: u64,
    /// Mapped normals evaluated (`normal_evals`), in `normal_batches` calls, each a batch of
    /// hits. Of every 64 calls, one is timed alone (`normal_timed` intervals, `normal_timed_ns`
    /// in all, over `normal_timed_points` normals) and one is timed followed by a second,
    /// discarded evaluation of the same normals (`normal_timed_twice`, `..._ns`, `..._points`).
    /// See [`Counters::normal_map_thread_seconds`] (applied to a render's own counters: a
    /// merge adds up the passes' estimates). Absent from pass files written before the
    /// batches: `normal_batches` and the `_points`.
    pub normal_evals: u64,
    #[serde(default)]
    pub normal_batches: u64,
    pub normal_timed: u64,
    pub normal_timed_ns: u64,
    #[serde(default)]
    pub normal_timed_points: u64,
    #[serde(default)]
    pub normal_timed_twice: u64,
    #[serde(default)]
    pub normal_timed_twice_ns: u64,
    #[serde(default)]
    pub normal_timed_twice_points: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.nan += o.nan;
        self.escaped_below_horizon += o.escaped_below_horizon;
        self.self_hits += o.self_hits;
        self.wrong_side += o.wrong_side;
        self.backfacing_shading += o.backfacing_shading;
        self.bent += o.bent;
        self.terminated += o.terminated;
        self.truncated += o.truncated;
        self.skipped += o.skipped;
        self.skipped_rising += o.skipped_rising;
        self.skipped_above += o.skipped_above;
        self.predicted += o.predicted;
        self.prediction_rays += o.prediction_rays;
        self.normal_evals += o.normal_evals;
        self.normal_batches += o.normal_batches;
        self.normal_timed += o.normal_timed;
        self.normal_timed_ns += o.normal_timed_ns;
        self.normal_timed_points += o.normal_timed_points;
        self.normal_timed_twice += o.normal_timed_twice;
        self.normal_timed_twice_ns += o.normal_timed_twice_ns;
        self.normal_timed_twice_points += o.normal_timed_twice_points;
    }
}

impl Counters {
    /// Estimated thread-seconds that mapped normals add to the trace: the number of normals
    /// times what one more normal adds to a timed interval. Each interval is modelled as
    /// `clock + k x normals` (k doubled where the batch is evaluated twice); the sums of the
    /// two kinds of intervals give the two unknowns, and k is the cost of a normal.
    ///
    /// An interval with one evaluation overstates its cost: reading the clock waits for the work
    /// in flight before it to finish, so the interval also holds the overlap with neighbouring
    /// work that an untimed evaluation enjoys. The second evaluation cancels that and the
    /// clock's own cost. Checked against rendering the default scene with every batch's normals
    /// evaluated twice: 0.10-0.32 s more trace (four interleaved pairs) where this reads
    /// 0.26 s. The intercept, about 200 ns an interval against the clock's 24, is left out: the
    /// second evaluation finds the texels in cache and the pipeline busy, so what a batch costs
    /// beyond its normals' marginal cost is not separable from the clock's (perf, which
    /// attributes stalls to the instructions waiting, gives the normal path 14.5 % of the
    /// trace's samples where this reads 9 %). Renders too small to have timed a pair fall back
    /// to the single intervals less [`clock_overhead_ns`].
    pub fn normal_map_thread_seconds(&self) -> f64 {
        let (n1, s1) = (self.normal_timed as f64, self.normal_timed_points as f64);
        let (n2, s2) = (
            self.normal_timed_twice as f64,
            self.normal_timed_twice_points as f64,
        );
        let (t1, t2) = (
            self.normal_timed_ns as f64,
            self.normal_timed_twice_ns as f64,
        );
        // t1 = clock n1 + k s1 and t2 = clock n2 + 2 k s2. The denominator is n1 n2 (2 m2 - m1)
        // for mean batch sizes m1, m2: solved only while the paired batches are not much
        // smaller than the single ones, where noise would swamp it.
        let denominator = 2.0 * s2 * n1 - s1 * n2;
        let per_normal_ns = if n2 > 0.0 && denominator > 0.5 * s2 * n1 {
            (t2 * n1 - t1 * n2) / denominator
        } else if s1 > 0.0 {
            (t1 - clock_overhead_ns() * n1) / s1
        } else {
            return 0.0;
        };
        per_normal_ns.max(0.0) * 1e-9 * self.normal_evals as f64
    }
}

/// What an empty timed interval reads, ns: the clock's own cost inside every interval it
/// times. Measured once per process as the median of 1001 empty intervals timed exactly as the
/// mapped normals are (about 24 ns here); only renders too small to have timed a pair of
/// evaluations use it ([`Counters::normal_map_thread_seconds`]).
pub(crate) fn clock_overhead_ns() -> f64 {
    static OVERHEAD: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        let mut v: Vec<u64> = (0..1001)
            .map(|_| {
                let t0 = std::time::Instant::now();
                t0.elapsed().as_nanos() as u64
            })
            .collect();
        v.sort_unstable();
        v[500] as f64
    })
}

/// Rotates a vector given in the flat-sea frame at camera-relative nominal position (u, v) into
/// the curved-earth frame there: the local vertical at horizontal distance r is tilted by
/// r / R away from the camera's nadir (DESIGN.md, Curved earth).
#[inline]
pub fn tilt_to_earth(u: f32, v: f32, earth_radius_m: f64, n: Vec3) -> Vec3 {
    let r = (u * u + v * v).sqrt();
    if r == 0.0 || !earth_radius_m.is_finite() {
        return n;
    }
    let theta = (r as f64 / earth_radius_m) as f32;
    let (s, c) = if theta < TILT_SERIES_MAX {
        tilt_series(theta)
    } else {
        theta.sin_cos()
    };
    Vec3::from(rotate_tilt(u, v, r, s, c, n.to_array()))
}

/// Angles below this take two Taylor terms, exact in f32 there and much cheaper than sin_cos
/// (this runs at every mapped hit); out to the horizon theta stays under 1e-3 rad.
const TILT_SERIES_MAX: f32 = 1e-2;

/// (sin theta, cos theta) for theta < [`TILT_SERIES_MAX`].
#[inline]
fn tilt_series(theta: f32) -> (f32, f32) {
    let t2 = theta * theta;
    (theta * (1.0 - t2 / 6.0), 1.0 - 0.5 * t2 * (1.0 - t2 / 12.0))
}

/// Rotation of `n` by the angle with sine `s` and cosine `c` about the horizontal axis
/// a = (v, 0, -u) / r (Rodrigues' formula): n c + (a x n) s + a (a . n) (1 - c), written out
/// in glam's order of operations (the renders stayed bit for bit the same) so that lanes of it
/// compile to vector code.
#[inline]
fn rotate_tilt(u: f32, v: f32, r: f32, s: f32, c: f32, n: [f32; 3]) -> [f32; 3] {
    let (ax, ay, az) = (v / r, 0.0f32, -u / r);
    let [nx, ny, nz] = n;
    let cross = [ay * nz - ny * az, az * nx - nz * ax, ax * ny - nx * ay];
    let dot = ax * nx + ay * ny + az * nz;
    let k = 1.0 - c;
    [
        nx * c + cross[0] * s + ax * dot * k,
        ny * c + cross[1] * s + ay * dot * k,
        nz * c + cross[2] * s + az * dot * k,
    ]
}

/// [`tilt_to_earth`] of every `n[i]` at `uv[i]`, bit for bit: points out to the series' reach
/// are rotated together, branch-free, in vector code; the rest (the nadir, a flat earth,
/// beyond the series) one at a time.
pub fn tilt_to_earth_many(uv: &[[f32; 2]], earth_radius_m: f64, n: &mut [Vec3]) {
    const LANES: usize = 8;
    assert_eq!(uv.len(), n.len(), "one position per vector");
    let finite = earth_radius_m.is_finite();
    for (uv, n) in uv.chunks(LANES).zip(n.chunks_mut(LANES)) {
        // Lanes past the chunk rotate +y at the origin, and are not written back. Components
        // are kept apart (one array per coordinate): the layout vector code wants.
        let (mut u, mut v) = ([0.0f32; LANES], [0.0f32; LANES]);
        let mut flat = [[0.0f32; LANES], [1.0; LANES], [0.0; LANES]];
        for (l, (p, n)) in uv.iter().zip(&*n).enumerate() {
            (u[l], v[l]) = (p[0], p[1]);
            (flat[0][l], flat[1][l], flat[2][l]) = (n.x, n.y, n.z);
        }
        let mut series = [false; LANES];
        let mut tilted = [[0.0f32; LANES]; 3];
        for l in 0..LANES {
            let r = (u[l] * u[l] + v[l] * v[l]).sqrt();
            let theta = (r as f64 / earth_radius_m) as f32;
            // (A NaN radius fails the `theta <` test: the scalar path returns its rotation.)
            series[l] = r != 0.0 && theta < TILT_SERIES_MAX;
            let (s, c) = tilt_series(theta);
            let t = rotate_tilt(u[l], v[l], r, s, c, [flat[0][l], flat[1][l], flat[2][l]]);
            (tilted[0][l], tilted[1][l], tilted[2][l]) = (t[0], t[1], t[2]);
        }
        for (l, n) in n.iter_mut().enumerate() {
            *n = if series[l] && finite {
                Vec3::new(tilted[0][l], tilted[1][l], tilted[2][l])
            } else {
                tilt_to_earth(u[l], v[l], earth_radius_m, *n)
            };
        }
    }
}

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

/// Most camera rays [`SceneRef::radiance_camera_batch`] takes at once (one pixel's samples go
/// to the BVH together). It bounds every batch of [`SceneRef::radiance_batch`] (a batch holds a
/// sample at most once).
pub const CAMERA_BATCH: usize = 16;

/// What the integrator traces against.
pub struct SceneRef<'a> {
    pub accel: &'a dyn Accel,
    /// From [`max_slope`]: rays in the water descending more steeply than this are not
    /// traced (they cannot hit the surface) and return the upwelling radiance directly; nor are
    /// rays leaving a hit into the air rising more steeply, which see the sky directly; and
    /// camera rays descending more steeply may take a predicted hit (`predict_camera_hits`).
    /// `None` traces every ray.
    pub skip_slope: Option<f32>,
    /// From [`highest_vertex_y`]: rays in the air leaving upwards from above this height are
    /// not traced (nothing lies above it) and see the sky directly. `None` traces every ray.
    pub skip_above_y: Option<f32>,
    /// Camera rays take their hit from their pixel's predicted triangle where that triangle
    /// holds their closest hit ([`SceneRef::predict_camera_prim`]; needs `skip_slope`). The
    /// hits differ from the BVH's by rounding.
    pub predict_camera_hits: bool,
    /// The ocean, for mapped normals (required for `NormalMode::Mapped`).
    pub ocean: Option<Sampler<'a>>,
    pub earth_radius_m: f64,
    pub sky: &'a Sky,
}

/// The surface at a hit, as shading needs it.
#[derive(Clone, Copy)]
struct SurfacePoint {
    p: Vec3,
    /// Geometric normal, oriented to the air side (agreeing with the vertex normals).
    ng: Vec3,
    /// Bound on the rounding error of `p`, per component.
    err: Vec3,
    /// The triangle hit: rays spawned here must never meet it again.
    prim: u32,
}

fn surface_point(mesh: &Mesh, hit: &Hit) -> SurfacePoint {
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

impl SurfacePoint {
    /// The ray leaving the surface along `w`, its origin moved just far enough to `w`'s side
    /// to clear the hit's rounding error (pbrt-v4's OffsetRayOrigin), so it cannot meet its own
    /// triangle again.
    fn spawn(&self, w: Vec3) -> Ray {
        let o = fp::offset_ray_origin(self.p, self.err, self.ng, w);
        Ray::new(o.to_array(), w.to_array())
    }
}

/// The ray leaving the surface of `mesh` at `hit` along `w`, as the integrator spawns its
/// secondary rays (for tests and cross-checks).
pub fn spawn_ray(mesh: &Mesh, hit: &Hit, w: Vec3) -> Ray {
    surface_point(mesh, hit).spawn(w)
}

/// What one hit does to a path: where it is, which way the medium changes, the attenuation of
/// the segment that reached it, and the two directions leaving it with the Fresnel weight.
#[derive(Clone, Copy)]
struct Scatter {
    sp: SurfacePoint,
    from_below: bool,
    attenuation: Vec3,
    fresnel: f32,
    /// `None`: the wrong-side policy ended this branch.
    reflected: Option<Vec3>,
    /// `None` on total internal reflection; `Some(None)` when the policy ended the branch.
    refracted: Option<Option<Vec3>>,
}

impl Scatter {
    /// A placeholder for the unused slots of a batch's array.
    const NONE: Scatter = Scatter {
        sp: SurfacePoint {
            p: Vec3::ZERO,
            ng: Vec3::Y,
            err: Vec3::ZERO,
            prim: 0,
        },
        from_below: false,
        attenuation: Vec3::ZERO,
        fresnel: 0.0,
        reflected: None,
        refracted: None,
    };
}

/// A new direction `w` on its proper side of the triangle (normal `ng`, facing the incoming
/// ray), as the policy wants it: unchanged when it is on its side; otherwise mirrored back
/// across the triangle's plane, keeping its weight, or (`Terminate`) no direction at all.
/// Wrong-side directions are counted.
fn keep_side(
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
        let threshold = (0.9 * ng.dot(i)).min(0.01);
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

impl SceneRef<'_> {
    /// The shading normal `mode` gives at a hit (air side up), for tests and cross-checks.
    pub fn normal_at(&self, hit: &Hit, mode: NormalMode) -> Vec3 {
        let settings = TraceSettings {
            normals: mode,
            ..TraceSettings::default()
        };
        let mut n = [Vec3::Y];
        self.shading_normals(&[Some(*hit)], &settings, &mut Counters::default(), &mut n);
        n[0]
    }

    /// The shading normals (air side up) at a batch of hits into `out` (a miss's entry is
    /// not used: left as it is, or +y).
    /// Mapped normals: each hit's texture coordinate, the ocean's normals there computed
    /// together ([`Sampler::normals`], bit for bit one at a time), tilted to the curved earth.
    /// One call in 64 is timed alone, one timed with a second evaluation of the same normals
    /// (see [`Counters::normal_map_thread_seconds`]).
    fn shading_normals(
        &self,
        hits: &[Option<Hit>],
        settings: &TraceSettings,
        c: &mut Counters,
        out: &mut [Vec3],
    ) {
        debug_assert!(hits.len() <= CAMERA_BATCH && out.len() == hits.len());
        let mesh = self.accel.mesh();
        match (settings.normals, &self.ocean) {
            (NormalMode::Mapped, Some(ocean)) => {
                let mut uv = [[0.0f32; 2]; CAMERA_BATCH];
                let mut at = [0u8; CAMERA_BATCH];
                let mut n = 0;
                for (i, h) in hits.iter().enumerate() {
                    if let Some(h) = h {
                        (uv[n], at[n]) = (self.accel.interpolate_uv(h), i as u8);
                        n += 1;
                    }
                }
                if n == 0 {
                    return;
                }
                let mapped = |normals: &mut [Vec3]| {
                    let mut flat = [[0.0f32; 3]; CAMERA_BATCH];
                    ocean.normals(&uv[..n], &mut flat[..n]);
                    for (o, f) in normals.iter_mut().zip(&flat) {
                        *o = Vec3::from(*f);
                    }
                    tilt_to_earth_many(&uv[..n], self.earth_radius_m, normals);
                };
                // Neither timed call is a row's first (counters start afresh with every row),
                // whose cold caches would bias the single intervals up and the estimate down.
                let slot = c.normal_batches % 64;
                let t0 = (slot == 31 || slot == 63).then(std::time::Instant::now);
                let mut normals = [Vec3::Y; CAMERA_BATCH];
                mapped(&mut normals[..n]);
                if slot == 63 {
                    let mut again = [Vec3::Y; CAMERA_BATCH];
                    std::hint::black_box(&uv);
                    mapped(&mut again[..n]);
                    std::hint::black_box(&again);
                }
                if let Some(t0) = t0 {
                    let ns = t0.elapsed().as_nanos() as u64;
                    if slot == 31 {
                        c.normal_timed += 1;
                        c.normal_timed_ns += ns;
                        c.normal_timed_points += n as u64;
                    } else {
                        c.normal_timed_twice += 1;
                        c.normal_timed_twice_ns += ns;
                        c.normal_timed_twice_points += n as u64;
                    }
                }
                c.normal_batches += 1;
                c.normal_evals += n as u64;
                for (&i, nm) in at[..n].iter().zip(normals) {
                    out[i as usize] = nm;
                }
            }
            _ => {
                for (o, h) in out.iter_mut().zip(hits) {
                    *o = match h {
                        Some(h) if !mesh.normals().is_empty() => {
                            let tri = mesh.indices()[h.prim as usize];
                            Vec3::from(Mesh::interpolate(mesh.normals(), tri, h.u, h.v))
                                .normalize_or(Vec3::Y)
                        }
                        _ => Vec3::Y,
                    };
                }
            }
        }
    }

    /// Radiance arriving at `ray.org` along `-ray.dir`. `in_water`: the ray travels in the sea.
    /// (A batch of one: see [`Self::radiance_batch`].)
    pub fn radiance(
        &self,
        ray: &Ray,
        in_water: bool,
        segment: u32,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
    ) -> Vec3 {
        let vertex = PathVertex {
            ray: *ray,
            sample: 0,
            parent: None,
            in_water,
        };
        let mut out = [Vec3::ZERO];
        self.radiance_batch(
            &[vertex],
            None,
            segment,
            settings,
            std::slice::from_mut(rng),
            c,
            &mut out,
        );
        out[0]
    }

    /// Whether a ray descends more steeply than any slope of the mesh ([`max_slope`]): along
    /// it the height above the surface only falls, so it crosses the surface at most once.
    #[inline]
    pub fn descends_steeply(&self, d: Vec3) -> bool {
        self.skip_slope
            .is_some_and(|slope| d.y < 0.0 && -d.y > slope * (d.x * d.x + d.z * d.z).sqrt())
    }

    /// The triangle a pixel's camera rays are predicted to hit: the one its centre ray `ray`
    /// hits, when that ray descends more steeply than the mesh ever slopes (`None` otherwise,
    /// for a miss, and when `predict_camera_hits` is off). A camera ray that descends as
    /// steeply crosses the surface at most once, so a hit on this triangle is its closest hit
    /// (up to rounding): the BVH need not be searched ([`Self::radiance_camera_batch`]). The
    /// centre ray depends on the pixel alone, so a sample's hit does not depend on which other
    /// samples a render or a pass takes.
    pub fn predict_camera_prim(&self, ray: &Ray, c: &mut Counters) -> Option<u32> {
        if !self.predict_camera_hits
            || !self.descends_steeply(Vec3::from(ray.dir))
            || !ray.is_finite()
        {
            return None;
        }
        c.prediction_rays += 1;
        self.accel.intersect(ray).map(|h| h.prim)
    }

    /// Radiance along camera rays (in the air, first segment), computed together: see
    /// [`Self::radiance_batch`]. At most [`CAMERA_BATCH`] rays; `rngs[i]` is ray i's generator
    /// and `out[i]` receives its radiance. `predicted`: the pixel's triangle from
    /// [`Self::predict_camera_prim`]; a ray that descends more steeply than the mesh slopes and
    /// meets it takes that hit ([`hit_on_triangle`]) instead of the BVH's. Each ray's result is
    /// bit for bit what it gets in a batch of one with the same prediction; with `None`, what
    /// [`Self::radiance`] gives it (with a prediction, that up to the rounding of the hit).
    pub fn radiance_camera_batch(
        &self,
        rays: &[Ray],
        predicted: Option<u32>,
        settings: &TraceSettings,
        rngs: &mut [Rng],
        c: &mut Counters,
        out: &mut [Vec3],
    ) {
        let n = rays.len();
        assert!(n <= CAMERA_BATCH && rngs.len() == n && out.len() == n);
        let mut entries = [PathVertex::NONE; CAMERA_BATCH];
        for (i, (e, ray)) in entries.iter_mut().zip(rays).enumerate() {
            *e = PathVertex {
                ray: *ray,
                sample: i as u8,
                parent: None,
                in_water: false,
            };
        }
        self.radiance_batch(&entries[..n], predicted, 0, settings, rngs, c, out);
    }

    /// The radiance of up to [`CAMERA_BATCH`] rays at `segment`, each from a different sample
    /// (`rngs[entry.sample]` is its generator), into `out`: the path tracer itself, a stage at a
    /// time over the whole batch, each ray's result bit for bit what it gets in a batch of one.
    ///
    /// The rays the BVH must see are traced together (one call into the backend), every hit is
    /// shaded, and the rays leaving the hits form two
    /// batches of their own: the first branch of every hit (its reflection, or the branch chosen
    /// past `branch_depth`), then the second (its refraction, while both are followed). One
    /// sample's path is a chain of dependent long-latency steps (square roots, divisions, texel
    /// reads); a stage over 16 independent samples lets the processor overlap them. A sample's
    /// subtrees are still finished depth first, first branch before second, whatever else the
    /// batch holds, so its random numbers are drawn in the same order as in a batch of one
    /// (`--pass` renders merge into the single render bit for bit because of this).
    #[allow(clippy::too_many_arguments)]
    fn radiance_batch(
        &self,
        entries: &[PathVertex],
        predicted: Option<u32>,
        segment: u32,
        settings: &TraceSettings,
        rngs: &mut [Rng],
        c: &mut Counters,
        out: &mut [Vec3],
    ) {
        debug_assert!(entries.len() <= CAMERA_BATCH && out.len() == entries.len());
        // Answered without the BVH, from the sky (all together), or traced together.
        let mut traced = [PathVertex::NONE.ray; CAMERA_BATCH];
        let mut traced_entry = [0u8; CAMERA_BATCH];
        let mut m = 0;
        let (mut sky_org, mut sky_dir) = ([Vec3::ZERO; CAMERA_BATCH], [Vec3::ZERO; CAMERA_BATCH]);
        let mut sky_entry = [0u8; CAMERA_BATCH];
        let mut n_sky = 0;
        for (k, e) in entries.iter().enumerate() {
            match self.answer_untraced(&e.ray, e.in_water, e.parent.is_some(), segment, settings, c)
            {
                Untraced::Known(l) => out[k] = l,
                Untraced::Sky => {
                    (sky_org[n_sky], sky_dir[n_sky]) = (e.ray.org.into(), e.ray.dir.into());
                    sky_entry[n_sky] = k as u8;
                    n_sky += 1;
                }
                Untraced::Trace => {
                    traced[m] = e.ray;
                    traced_entry[m] = k as u8;
                    m += 1;
                }
            }
        }
        if n_sky > 0 {
            let mut l = [Vec3::ZERO; CAMERA_BATCH];
            let (orgs, dirs) = (&sky_org[..n_sky], &sky_dir[..n_sky]);
            self.sky.radiance_many(orgs, dirs, &mut l[..n_sky]);
            for (&k, l) in sky_entry[..n_sky].iter().zip(l) {
                out[k as usize] = l;
            }
        }
        if m == 0 {
            return;
        }
        let mut hits = [None; CAMERA_BATCH];
        match predicted {
            None => self.accel.intersect_many(&traced[..m], &mut hits[..m]),
            Some(prim) => {
                // Rays that meet the predicted triangle steeply enough have their hit; the
                // rest go to the BVH together.
                let tri = self.accel.mesh().triangle(prim).map(Vec3::from);
                let mut rest = [PathVertex::NONE.ray; CAMERA_BATCH];
                let mut rest_of = [0u8; CAMERA_BATCH];
                let mut r = 0;
                for (i, ray) in traced[..m].iter().enumerate() {
                    let on_prim = if self.descends_steeply(Vec3::from(ray.dir)) {
                        hit_on_triangle(ray, tri, prim)
                    } else {
                        None
                    };
                    match on_prim {
                        Some(hit) => {
                            c.predicted += 1;
                            hits[i] = Some(hit);
                        }
                        None => {
                            rest[r] = *ray;
                            rest_of[r] = i as u8;
                            r += 1;
                        }
                    }
                }
                let mut rest_hits = [None; CAMERA_BATCH];
                self.accel.intersect_many(&rest[..r], &mut rest_hits[..r]);
                for (&i, h) in rest_of[..r].iter().zip(rest_hits) {
                    hits[i as usize] = h;
                }
            }
        }

        // Shading at every hit, its normal computed with the others'; what a miss sees.
        let mut normals = [Vec3::Y; CAMERA_BATCH];
        self.shading_normals(&hits[..m], settings, c, &mut normals[..m]);
        let mut shaded = [(0u8, Scatter::NONE); CAMERA_BATCH];
        let mut n_shaded = 0;
        for ((&k, hit), ns) in traced_entry[..m].iter().zip(&hits[..m]).zip(normals) {
            let e = &entries[k as usize];
            match hit {
                None => out[k as usize] = self.miss(&e.ray, e.in_water, segment, settings, c),
                Some(hit) => {
                    c.hits += 1;
                    // A planar triangle cannot meet a ray leaving it twice: this is rounding.
                    c.self_hits += u64::from(e.parent == Some(hit.prim));
                    let d = Vec3::from(e.ray.dir);
                    shaded[n_shaded] = (k, self.scatter(d, hit, ns, settings, c));
                    n_shaded += 1;
                }
            }
        }
        let shaded = &shaded[..n_shaded];

        // The branches: which each hit follows (drawing a sample's random choice here, before
        // its subtrees), then each batch of branches in turn.
        let mut first = [None; CAMERA_BATCH];
        let mut second = [None; CAMERA_BATCH];
        let mut both = [false; CAMERA_BATCH];
        for (j, (k, s)) in shaded.iter().enumerate() {
            let rng = &mut rngs[entries[*k as usize].sample as usize];
            (first[j], second[j], both[j]) = branches(s, segment, settings, rng);
        }
        let mut l_first = [Vec3::ZERO; CAMERA_BATCH];
        let mut l_second = [Vec3::ZERO; CAMERA_BATCH];
        for (dirs, l) in [(&first, &mut l_first), (&second, &mut l_second)] {
            let mut batch = [PathVertex::NONE; CAMERA_BATCH];
            let mut of = [0u8; CAMERA_BATCH];
            let mut b = 0;
            for (j, (k, s)) in shaded.iter().enumerate() {
                if let Some((w, in_water)) = dirs[j] {
                    batch[b] = PathVertex {
                        ray: s.sp.spawn(w),
                        sample: entries[*k as usize].sample,
                        parent: Some(s.sp.prim),
                        in_water,
                    };
                    of[b] = j as u8;
                    b += 1;
                }
            }
            if b > 0 {
                let mut lb = [Vec3::ZERO; CAMERA_BATCH];
                self.radiance_batch(
                    &batch[..b],
                    None,
                    segment + 1,
                    settings,
                    rngs,
                    c,
                    &mut lb[..b],
                );
                for (&j, lb) in of[..b].iter().zip(lb) {
                    l[j as usize] = lb;
                }
            }
        }
        for (j, (k, s)) in shaded.iter().enumerate() {
            let l = if both[j] {
                s.fresnel * l_first[j] + (1.0 - s.fresnel) * l_second[j]
            } else {
                l_first[j]
            };
            out[*k as usize] = s.attenuation * l;
        }
    }

    /// Whether a ray is answered without the BVH: cut at `max_segments`, or known to miss the
    /// surface (the skip shortcuts), which is counted, as is a ray that must be traced.
    /// `spawned`: the ray leaves a hit (on the side of the triangle it travels in).
    fn answer_untraced(
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
        // (A ray with a NaN or infinite component is left to the backend, which counts it.)
        if !in_water
            && d.y >= 0.0
            && let Some(top) = self.skip_above_y
            && ray.org[1] > top
            && ray.is_finite()
        {
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

    /// What a traced ray that met nothing sees: the sky, or in the water the upwelling light.
    fn miss(
        &self,
        ray: &Ray,
        in_water: bool,
        segment: u32,
        settings: &TraceSettings,
        c: &mut Counters,
    ) -> Vec3 {
        let d = Vec3::from(ray.dir);
        if segment == 0 && !in_water && d.y < settings.must_hit_below_y {
            c.escaped_below_horizon += 1;
        }
        if in_water {
            Vec3::from(settings.upwelling)
        } else {
            self.sky.radiance(Vec3::from(ray.org), d)
        }
    }

    /// Shading at a hit of a ray travelling along `d`, whose shading normal (air side up) is
    /// `shading` ([`Self::shading_normals`]): the interface's normals, the Fresnel weight and
    /// the reflected and refracted directions.
    fn scatter(
        &self,
        d: Vec3,
        hit: &Hit,
        shading: Vec3,
        settings: &TraceSettings,
        c: &mut Counters,
    ) -> Scatter {
        let sp = surface_point(self.accel.mesh(), hit);
        let from_below = d.dot(sp.ng) > 0.0;
        let attenuation = if from_below {
            settings.water.transmittance(hit.t)
        } else {
            Vec3::ONE
        };

        // Shading normal facing the incoming ray, and the geometric one likewise.
        let mut ns = shading;
        let (ng, eta_i, eta_t) = if from_below {
            (-sp.ng, settings.water.ior, 1.0)
        } else {
            (sp.ng, 1.0, settings.water.ior)
        };
        if from_below {
            ns = -ns;
        }
        let policy = settings.wrong_side;
        let mut dead = false;
        if d.dot(ns) >= 0.0 {
            c.backfacing_shading += 1;
            match policy {
                WrongSide::Mirror => ns = ng,
                WrongSide::Flip => ns = -ns,
                // Bent below, as every other normal is.
                WrongSide::Bend => {}
                WrongSide::Terminate => dead = true,
            }
        }
        if policy == WrongSide::Bend {
            let bent = bend_normal(ng, -d, ns);
            c.bent += u64::from(bent != ns);
            ns = bent;
        }
        let cos_i = -d.dot(ns);
        let fresnel = fresnel(cos_i, eta_i, eta_t);
        let (reflected, refracted) = if dead {
            c.terminated += 1;
            (None, Some(None))
        } else {
            (
                keep_side(reflect(d, ns), ng, true, policy, c),
                refract(d, ns, eta_i / eta_t).map(|t| keep_side(t, ng, false, policy, c)),
            )
        };
        Scatter {
            sp,
            from_below,
            attenuation,
            fresnel,
            reflected,
            refracted,
        }
    }
}

/// How [`SceneRef::answer_untraced`] answers a ray.
enum Untraced {
    /// Its radiance, known without the BVH.
    Known(Vec3),
    /// It cannot meet the surface: the sky's radiance along it.
    Sky,
    /// The BVH must find its hit.
    Trace,
}

/// One ray of a batch in [`SceneRef::radiance_batch`]: sample `sample`'s ray, spawned on
/// triangle `parent` (none for a camera ray), travelling in the water or the air.
#[derive(Clone, Copy)]
struct PathVertex {
    ray: Ray,
    sample: u8,
    parent: Option<u32>,
    in_water: bool,
}

impl PathVertex {
    const NONE: PathVertex = PathVertex {
        ray: Ray {
            org: [0.0; 3],
            tnear: 0.0,
            dir: [0.0, 1.0, 0.0],
            tfar: f32::INFINITY,
        },
        sample: 0,
        parent: None,
        in_water: false,
    };
}

/// A branch leaving a hit: its direction and whether it travels in the water (`None`: not
/// followed, radiance zero).
type Branch = Option<(Vec3, bool)>;

/// The branches a hit at `segment` follows, first then second, and whether both are (then F
/// and 1 - F weigh them; otherwise the first carries the whole radiance): the reflection alone
/// on total internal reflection; both, up to `branch_depth`; past it one, chosen with
/// probability F (drawn from `rng`: the estimator stays unbiased). The reflected ray stays in
/// the medium it came from, the refracted one changes it.
fn branches(
    s: &Scatter,
    segment: u32,
    settings: &TraceSettings,
    rng: &mut Rng,
) -> (Branch, Branch, bool) {
    let reflected = s.reflected.map(|w| (w, s.from_below));
    let refracted = |t: Option<Vec3>| t.map(|w| (w, !s.from_below));
    match s.refracted {
        None => (reflected, None, false),
        Some(t) if segment < settings.branch_depth => (reflected, refracted(t), true),
        Some(t) => {
            if rng.f32() < s.fresnel {
                (reflected, None, false)
            } else {
                (refracted(t), None, false)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cost_is_solved_from_single_and_paired_intervals() {
        let c = Counters {
            normal_evals: 6400,
            normal_timed: 100,
            normal_timed_points: 100,
            normal_timed_ns: 12_000,
            normal_timed_twice: 100,
            normal_timed_twice_points: 100,
            normal_timed_twice_ns: 18_000,
            ..Counters::default()
        };
        // One normal an interval: 180 - 120 ns per evaluation, whatever the clock costs.
        assert!((c.normal_map_thread_seconds() - 6400.0 * 60e-9).abs() < 1e-12);
        // A second evaluation that seems free counts as free, not negative.
        let free = Counters {
            normal_timed_twice_ns: 11_000,
            ..c
        };
        assert_eq!(free.normal_map_thread_seconds(), 0.0);
        // Without pairs, or with paired batches under half the size of the single ones (too
        // noisy to solve), the single intervals less the clock's cost.
        let expected = (120.0 - clock_overhead_ns()).max(0.0) * 1e-9 * 6400.0;
        for single in [
            Counters {
                normal_timed_twice: 0,
                normal_timed_twice_ns: 0,
                normal_timed_twice_points: 0,
                ..c
            },
            Counters {
                normal_timed_twice_points: 60,
                ..c
            },
        ] {
            assert!((single.normal_map_thread_seconds() - expected).abs() < 1e-12);
        }
        assert_eq!(Counters::default().normal_map_thread_seconds(), 0.0);
        // Batches of different sizes: a 30 ns clock and 20 ns a normal, 10 normals an interval
        // alone and 14 in a pair's; the estimate recovers the 20 ns.
        let batches = Counters {
            normal_evals: 6400,
            normal_timed: 100,
            normal_timed_points: 1000,
            normal_timed_ns: 100 * 30 + 20 * 1000,
            normal_timed_twice: 50,
            normal_timed_twice_points: 700,
            normal_timed_twice_ns: 50 * 30 + 2 * 20 * 700,
            ..Counters::default()
        };
        assert!((batches.normal_map_thread_seconds() - 6400.0 * 20e-9).abs() < 1e-12);
    }

    #[test]
    fn earth_tilt_turns_up_towards_the_local_vertical() {
        let r = 6_371_000.0;
        let n = tilt_to_earth(5000.0, 0.0, r, Vec3::Y);
        // 5 km along +x the local vertical leans 5000/R radians towards +x
        assert!((n.x - (5000.0 / r) as f32).abs() < 1e-7 && (n.length() - 1.0).abs() < 1e-6);
        assert_eq!(tilt_to_earth(0.0, 0.0, r, Vec3::Y), Vec3::Y);
        let n = tilt_to_earth(0.0, -3000.0, r, Vec3::Y);
        assert!(n.z < 0.0 && n.x.abs() < 1e-9);
    }

    #[test]
    fn earth_tilt_in_lanes_is_the_tilt_one_at_a_time() {
        let mut uv = Vec::new();
        let mut n = Vec::new();
        for i in 0..37u64 {
            let h = crate::rng::splitmix64(i);
            let f = |k: u32| ((h >> k) & 0xFFFF) as f32 / 65536.0 - 0.5;
            // out to 150 km: past the series' reach (63.7 km on the earth; 10 m on a planet
            // of 1 km, where the series would be wrong at the 300 m scale)
            let scale = [3.0e5, 600.0, 30.0][i as usize % 3];
            uv.push([f(0) * scale, f(16) * scale]);
            n.push(Vec3::new(f(32), 1.0, f(48)).normalize());
        }
        uv.extend([
            [0.0, 0.0],
            [1.0e-30, 0.0],
            [f32::NAN, 2.0],
            [f32::INFINITY, 0.0],
        ]);
        n.extend([Vec3::Y, Vec3::X, Vec3::Y, Vec3::Z]);
        for r in [6_371_000.0, 1000.0, f64::INFINITY] {
            let mut lanes = n.clone();
            tilt_to_earth_many(&uv, r, &mut lanes);
            for ((&[u, v], &n), t) in uv.iter().zip(&n).zip(lanes) {
                let one = tilt_to_earth(u, v, r, n);
                let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                assert_eq!(bits(t), bits(one), "R {r} at ({u}, {v})");
            }
        }
    }

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
