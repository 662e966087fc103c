//! The first crossing of a ray segment with the implicit surface: interval bounds to skip, a
//! march with steps the surface's slope bound certifies, and a bracketed root.
//!
//! A segment [ta, tb] of the ray cannot meet the surface when the ray's altitude over it stays
//! above the largest surface altitude over the arc positions it passes (or below the
//! smallest): the ray's altitude is convex in t (a distance from the sphere's centre), so its
//! range is its end values and its closest approach; the surface's range is the layers'
//! pyramids over the nominal positions x = s - D(x) of the segment's arc positions s (the box
//! [`ExactSurface::nominal_box`]). Segments that are not cleared are halved until they are
//! shorter than [`ExactSurface::split_m`] (or, where neither the box's nor the sea's slope
//! bound holds, [`ExactSurface::split_rough_m`]), then marched: from a point where F = f, the
//! surface cannot be reached before |f| / K, K bounding dF/dt from the ray's speeds and the
//! directional slope bound ([`super::bounds::SlopeBound`]), so that step is taken when it is longer than the floor (half the finest texel), and the floor
//! otherwise. The floor is what the march does not certify: a crest the ray clips over less
//! than the floor (both crossings between two points) is not seen. A sign change brackets a
//! root, which the Illinois variant of false position narrows to [`TOL_F`].

use super::bounds::SlopeBound;
use super::implicit::{Eval, Implicit, Warm, sphere_coords};
use super::{ExactSurface, View};

/// |F| at which a root is accepted, m: part of the error the hit point carries into the
/// integrator's offset of the next ray's origin ([`super::ExactSurface::hit_error_m`]).
pub(super) const TOL_F: f64 = 2e-7;
/// Most halvings of one ray's segment before it is marched whatever its length.
const MAX_DEPTH: u32 = 40;
/// How often a segment's box of nominal positions is narrowed by the displacement's range
/// over it ([`ExactSurface::nominal_box`]).
const NARROWINGS: usize = 2;

/// One end of a segment: its t, arc position and altitude.
#[derive(Clone, Copy)]
struct End {
    t: f64,
    s: [f64; 2],
    a: f64,
}

/// A ray in f64 and what the search reuses along it.
struct RayPath<'a> {
    o: [f64; 3],
    d: [f64; 3],
    /// |d|
    len: f64,
    /// t of the ray's closest approach to the sphere's centre (where its altitude is least).
    t_low: f64,
    imp: Implicit<'a>,
    /// The surface searched.
    view: &'a View,
    warm: Option<Warm>,
    r: f64,
}

impl RayPath<'_> {
    #[inline]
    fn at(&self, t: f64) -> [f64; 3] {
        std::array::from_fn(|k| self.o[k] + t * self.d[k])
    }
    #[inline]
    fn end(&self, t: f64) -> End {
        let (s, a) = sphere_coords(self.at(t), self.r);
        End { t, s, a }
    }
    #[inline]
    fn eval(&mut self, t: f64) -> Eval {
        self.imp.eval(self.at(t), &mut self.warm)
    }
    /// [`Self::eval`] with the inversion started from the point's own arc position.
    fn eval_cold(&mut self, t: f64) -> Eval {
        self.warm = None;
        self.eval(t)
    }
}

impl ExactSurface {
    /// The first t in `[t0, t1]` where the ray `o + t d` crosses the surface (from either
    /// side), and the nominal position of the surface point there.
    pub(super) fn first_crossing(
        &self,
        view: &View,
        o: [f64; 3],
        d: [f64; 3],
        t0: f64,
        t1: f64,
    ) -> Option<(f64, [f64; 2])> {
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return None;
        }
        let r = self.earth_radius_m;
        let mut ray = self.ray_path(view, o, d);
        // the side the ray is on where its search starts, known after the first evaluation
        let mut side: Option<(f64, Eval)> = None;
        // depth first, nearer half on top: at most one entry per level waits, plus the top
        let mut stack = [(ray.end(t0), ray.end(t1), 0u32); MAX_DEPTH as usize + 2];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (a, b, depth) = stack[sp];
            let area = self.nominal_box(&ray, &a, &b);
            if self.clears(&ray, &a, &b, area) {
                continue;
            }
            // Halved down to the displacement's length, below which the box barely narrows;
            // further, down to eight of the finest texels, where no slope bound (the box's or
            // the sea's) certifies a march over it: only the bounds can skip ground there
            let ds = (b.s[0] - a.s[0]).hypot(b.s[1] - a.s[1]);
            let halve = depth < MAX_DEPTH && ds > view.split_rough_m;
            let slope = if halve && ds > view.split_m {
                None
            } else {
                let [x0, x1, z0, z1] = area;
                // (the box's and the sea's bounds both hold there: so do their smaller parts)
                let local = self.bounds.steepness(&view.lod, x0, x1, z0, z1);
                local.min(view.steep).slope_limit()
            };
            if halve && (ds > view.split_m || slope.is_none()) {
                let m = ray.end(0.5 * (a.t + b.t));
                stack[sp] = (m, b, depth + 1);
                stack[sp + 1] = (a, m, depth + 1);
                sp += 2;
                continue;
            }
            let (t_prev, e_prev) = match side {
                Some((t, e)) if t == a.t => (t, e),
                _ => (a.t, ray.eval(a.t)),
            };
            if e_prev.f == 0.0 {
                return Some((t_prev, e_prev.x));
            }
            let theta = a.s[0].hypot(a.s[1]).max(b.s[0].hypot(b.s[1])) / r;
            match self.march(&mut ray, t_prev, e_prev, b.t, theta, slope) {
                Ok(hit) => return Some(hit),
                // no crossing up to b: the next segment starts on the same side (evaluated
                // there afresh where the march did not reach b)
                Err(at_b) => side = at_b.map(|e| (b.t, e)),
            }
        }
        None
    }

    /// The ray `o + t d` as the search walks it.
    fn ray_path<'a>(&'a self, view: &'a View, o: [f64; 3], d: [f64; 3]) -> RayPath<'a> {
        let r = self.earth_radius_m;
        let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let rel = [o[0], o[1] + r, o[2]];
        RayPath {
            o,
            d,
            len: dd.sqrt(),
            t_low: -(rel[0] * d[0] + rel[1] * d[1] + rel[2] * d[2]) / dd,
            imp: self.implicit(view),
            view,
            warm: None,
            r,
        }
    }

    /// For tests: the box of nominal positions of the ray `o + t d` over `[t0, t1]`
    /// ([`Self::nominal_box`]), and the nominal positions of the surface points under `n + 1`
    /// points of that stretch, as F's inversion finds them to full accuracy.
    #[cfg(test)]
    pub(super) fn nominal_box_and_points(
        &self,
        o: [f64; 3],
        d: [f64; 3],
        [t0, t1]: [f64; 2],
        n: usize,
    ) -> ([f64; 4], Vec<super::implicit::Eval>) {
        let view = self.query(&crate::ocean::slopes::ALL_WAVES).view;
        let mut ray = self.ray_path(&view, o, d);
        ray.imp.lip = f64::INFINITY;
        let area = self.nominal_box(&ray, &ray.end(t0), &ray.end(t1));
        let points = (0..=n)
            .map(|i| ray.eval_cold(t0 + (t1 - t0) * i as f64 / n as f64))
            .collect();
        (area, points)
    }

    /// The nominal positions `[x0, x1, z0, z1]` whose surface points may lie over the arc
    /// positions the ray passes in `[a.t, b.t]`.
    #[inline]
    fn nominal_box(&self, ray: &RayPath, a: &End, b: &End) -> [f64; 4] {
        let len = (b.t - a.t) * ray.len;
        let far = a.s[0].hypot(a.s[1]).max(b.s[0].hypot(b.s[1])) + len;
        let theta = far / self.earth_radius_m;
        let [dx, dz] = ray.view.disp;
        // how far the arc positions of a straight segment stray from their chord, with room,
        // and how much the sphere stretches a displacement azimuthally (theta / sin theta - 1
        // < theta^2 / 5 below a radian)
        let slack = 1e-4
            + len * len * far / (self.earth_radius_m * self.earth_radius_m)
            + dx.max(dz) * theta * theta;
        let s = [
            a.s[0].min(b.s[0]) - slack,
            a.s[0].max(b.s[0]) + slack,
            a.s[1].min(b.s[1]) - slack,
            a.s[1].max(b.s[1]) + slack,
        ];
        // x = s - D(x): x lies within the largest displacement of s, and then within the
        // displacement's own range over that box, which is narrower wherever the longer
        // waves (most of the displacement) change little across it
        let mut area = [s[0] - dx, s[1] + dx, s[2] - dz, s[3] + dz];
        for _ in 0..NARROWINGS {
            let [x0, x1, z0, z1] = area;
            let d = self.bounds.displacement(&ray.view.lod, x0, x1, z0, z1);
            let narrowed = [
                x0.max(s[0] - d[1]),
                x1.min(s[1] - d[0]),
                z0.max(s[2] - d[3]),
                z1.min(s[3] - d[2]),
            ];
            // (an empty box would be rounding's doing: keep the one that holds x)
            if narrowed[0] > narrowed[1] || narrowed[2] > narrowed[3] {
                break;
            }
            area = narrowed;
        }
        area
    }

    /// Whether the ray's altitude over `[a.t, b.t]` stays clear of the surface's range over
    /// the nominal positions `area` ([`Self::nominal_box`]).
    #[inline]
    fn clears(&self, ray: &RayPath, a: &End, b: &End, [x0, x1, z0, z1]: [f64; 4]) -> bool {
        let [lo, hi] = self.bounds.height(&ray.view.lod, x0, x1, z0, z1);
        let hi = hi + ray.view.altitude_slack;
        let ray_hi = a.a.max(b.a);
        if ray_hi < lo {
            return true;
        }
        let ray_lo = if a.t < ray.t_low && ray.t_low < b.t {
            ray.end(ray.t_low).a
        } else {
            a.a.min(b.a)
        };
        ray_lo > hi
    }

    /// Marches from `t` (where F is `e`) to `t_end`, at most `theta` radians from the nadir,
    /// over a surface whose slope (height over arc position) is at most `slope` there: the
    /// first crossing, or F at `t_end`.
    fn march(
        &self,
        ray: &mut RayPath,
        mut t: f64,
        mut e: Eval,
        t_end: f64,
        theta: f64,
        slope: Option<SlopeBound>,
    ) -> Result<(f64, [f64; 2]), Option<Eval>> {
        let floor = ray.view.floor_m / ray.len;
        // |dF/dt| <= |da/dt| + |dH/dt|: the altitude and the arc position s move with the
        // ray's vertical and horizontal parts, each leaking into the other by the tilt from
        // the nadir (sin theta, with room for the segment's own reach and the sphere's
        // stretch of s), so |ds/dt| <= dh + leak dv and each of ds/dt's components is within
        // leak (dh + dv) of the ray's own along that axis
        let (dv, dh) = (ray.d[1].abs(), ray.d[0].hypot(ray.d[2]));
        let leak = 1.01 * theta + 1e-3;
        let spill = leak * (dh + dv);
        let (vx, vz) = (ray.d[0].abs() + spill, ray.d[2].abs() + spill);
        // how fast the surface's height can change along the ray
        let drift = slope.map(|s| 1.01 * s.rate(vx, vz, dh + leak * dv) + 1e-9);
        // The ray's vertical part away from the surface (up above it, down below it); F keeps
        // its sign until the crossing, so the march's side is e's throughout.
        let away = if e.f > 0.0 { ray.d[1] } else { -ray.d[1] };
        // Where the ray climbs away from the surface (or, below it, sinks) faster than the
        // surface's height can follow, F only moves away from zero over the segment: there
        // is no crossing in it, and nothing to evaluate (the altitude's rate is the ray's
        // vertical part, less the tilt's leak of both parts). Reflected rays rising steeply
        // and refracted ones sinking end here.
        if let Some(drift) = drift
            && e.converged
            && away - leak * (dh + dv) > drift
        {
            return Err(None);
        }
        // How fast F can move towards zero: a ray approaching the surface closes in by its
        // vertical part as well as the surface's drift; one moving away, by the drift less
        // its own climb (which the test above leaves below the drift)
        let k = drift.map(|drift| {
            if away < 0.0 {
                1.01 * (dv + leak * dh) + drift
            } else {
                drift + 1.01 * leak * (dh + dv) - 0.99 * away + 1e-9
            }
        });
        while t < t_end {
            // (F is known to a tenth of itself while it is far from zero; an inversion that did
            // not converge certifies nothing)
            let certified = match k {
                Some(k) if e.converged => 0.9 * e.f.abs() / k,
                _ => 0.0,
            };
            let tn = (t + certified.max(floor)).min(t_end);
            let mut en = ray.eval(tn);
            if !en.converged {
                // once more from scratch: a warm start across a steep patch can stall
                en = ray.eval_cold(tn);
            }
            if (en.f > 0.0) != (e.f > 0.0) || en.f == 0.0 {
                return Ok(self.root(ray, (t, e), (tn, en)));
            }
            (t, e) = (tn, en);
        }
        Err(Some(e))
    }

    /// The root of F between `a` and `b`, whose F differ in sign: false position with the
    /// Illinois halving, down to |F| <= [`TOL_F`] or a bracket of 1e-9 of t.
    fn root(&self, ray: &mut RayPath, a: (f64, Eval), b: (f64, Eval)) -> (f64, [f64; 2]) {
        let (mut ta, mut fa) = (a.0, a.1.f);
        let (mut tb, mut eb) = b;
        let mut fb = eb.f;
        if fb == 0.0 {
            return (tb, eb.x);
        }
        let mut kept = 0i8;
        for _ in 0..100 {
            let mut tm = tb - fb * (tb - ta) / (fb - fa);
            if !(tm > ta.min(tb) && tm < ta.max(tb)) {
                tm = 0.5 * (ta + tb);
            }
            let em = ray.eval(tm);
            if em.f.abs() <= TOL_F || (tb - ta).abs() * ray.len <= 1e-9 * (1.0 + tm * ray.len) {
                return (tm, em.x);
            }
            if (em.f > 0.0) == (fa > 0.0) {
                (ta, fa) = (tm, em.f);
                if kept == 1 {
                    fb *= 0.5;
                }
                kept = 1;
            } else {
                (tb, eb, fb) = (tm, em, em.f);
                if kept == -1 {
                    fa *= 0.5;
                }
                kept = -1;
            }
        }
        (tb, eb.x)
    }
}
