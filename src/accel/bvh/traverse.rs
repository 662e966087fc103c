//! Traversal: the robust slab test of Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013 (far
//! distances grow by `1 + 2·gamma(3)`; a zero direction component gives an infinite inverse
//! whose NaN products are discarded, never propagated) on the four lanes of a wide node at
//! once, nearest child first with a short stack, and the watertight ray/triangle test of Woop,
//! Benthin & Wald, JCGT 2(1), 2013, with its f64 fallback for edge functions that round to zero
//! and pbrt-v4's conservative bound that refuses hits whose t rounding cannot tell from zero.
//! The stack (128 entries, zeroed per ray) measured no slower than one of 32 on `bench bvh
//! --quick`.

use super::Bvh;
use super::layout::{LANES, Wide};
use crate::accel::{Hit, Ray};
use crate::fp::gamma;

/// Traversal stack kept on the machine stack (enough for 42 wide levels); deeper trees fall
/// back to a heap stack.
const INLINE_STACK: usize = 128;
/// Ize's factor: enough to cover the rounding in `(bound - org) · inv_dir` for the far plane.
const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3.0);

/// A ray prepared for traversal: inverse direction for the slabs and Woop et al.'s
/// permutation and shear into ray space.
pub(super) struct Prepared {
    org: [f32; 3],
    dir: [f32; 3],
    inv: [f32; 3],
    /// Per axis, whether the direction is negative: the box's upper plane is then the near one.
    neg: [bool; 3],
    tnear: f32,
    k: [usize; 3],
    shear: [f32; 3],
}

impl Prepared {
    /// `None` for a ray without a usable direction (zero or non-finite).
    pub(super) fn new(ray: &Ray) -> Option<Prepared> {
        let d = ray.dir;
        if !d.iter().chain(&ray.org).all(|c| c.is_finite()) {
            return None;
        }
        let a = d.map(f32::abs);
        let kz = if a[0] > a[1] {
            if a[0] > a[2] { 0 } else { 2 }
        } else if a[1] > a[2] {
            1
        } else {
            2
        };
        if d[kz] == 0.0 {
            return None;
        }
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keeps the winding (the sign of det) independent of which axis was chosen.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Some(Prepared {
            org: ray.org,
            dir: d,
            // Adding +0 turns -0 into +0: the inverse is then always +inf for a zero
            // component, so the NaN from `0 · inf` on a slab plane only ever appears where the
            // slab test below ignores it, never as a -inf far distance.
            inv: d.map(|c| 1.0 / (c + 0.0)),
            // Matches the inverse: -0 counts as positive.
            neg: d.map(|c| c + 0.0 < 0.0),
            tnear: ray.tnear,
            k: [kx, ky, kz],
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        })
    }

    /// Entry distances into the four children of `n` and the mask of those the ray meets
    /// within `[tnear, tmax]` (bit `l` for lane `l`). The near plane of each axis is chosen by
    /// the direction's sign, so each lane is the same sequence of subtractions, products,
    /// minima and maxima, which LLVM turns into 4-wide vector instructions.
    #[inline(always)]
    pub(super) fn slabs(&self, n: &Wide, tmax: f32) -> ([f32; LANES], u32) {
        let (mut t0, mut t1) = ([self.tnear; LANES], [tmax; LANES]);
        for k in 0..3 {
            let (near, far) = if self.neg[k] {
                (&n.hi[k], &n.lo[k])
            } else {
                (&n.lo[k], &n.hi[k])
            };
            for l in 0..LANES {
                let a = (near[l] - self.org[k]) * self.inv[k];
                let b = (far[l] - self.org[k]) * self.inv[k] * FAR_SCALE;
                // A NaN (the ray lies in that slab plane: 0 times an infinite inverse) compares
                // false, so both updates keep the running value and the axis imposes no
                // constraint.
                t0[l] = if a > t0[l] { a } else { t0[l] };
                t1[l] = if b < t1[l] { b } else { t1[l] };
            }
        }
        let mut mask = 0;
        for l in 0..LANES {
            mask |= ((t0[l] <= t1[l]) as u32) << l;
        }
        (t0, mask)
    }

    /// Woop et al.'s watertight test: `(t, u, v)` for a hit with `tnear <= t <= tmax`.
    #[inline(always)]
    pub(super) fn triangle(&self, tri: &[[f32; 3]; 3], tmax: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let rel = |p: [f32; 3]| -> [f32; 3] { std::array::from_fn(|k| p[k] - self.org[k]) };
        let (a, b, c) = (rel(tri[0]), rel(tri[1]), rel(tri[2]));
        let (ax, ay) = (a[kx] - sx * a[kz], a[ky] - sy * a[kz]);
        let (bx, by) = (b[kx] - sx * b[kz], b[ky] - sy * b[kz]);
        let (cx, cy) = (c[kx] - sx * c[kz], c[ky] - sy * c[kz]);
        // Edge functions: e0 weighs v0, e1 v1, e2 v2. A shared edge is evaluated from the same
        // two transformed vertices by both triangles, so the sign is consistent across it.
        let mut e0 = cx * by - cy * bx;
        let mut e1 = ax * cy - ay * cx;
        let mut e2 = bx * ay - by * ax;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            // A zero may be cancellation rather than a true zero; the products of two f32
            // values are exact in f64, so this recovers the sign.
            let f = |x: f32| x as f64;
            e0 = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
            e1 = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
            e2 = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        if det == 0.0 {
            // Parallel to the ray, or degenerate: no single hit point.
            return None;
        }
        let t_scaled = e0 * (sz * a[kz]) + e1 * (sz * b[kz]) + e2 * (sz * c[kz]);
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        // Written so a NaN or infinite t is a miss.
        if !(t >= self.tnear && t <= tmax && t.is_finite()) {
            return None;
        }
        // pbrt-v4's conservative check (Triangle::Intersect): a t that rounding error cannot
        // tell from zero is refused, so a ray that leaves this very triangle never hits it.
        // Its f32 bound grows with the distance along the ray: for a grazing hit kilometres
        // away on a large triangle it can exceed t itself. Such inconclusive cases are settled
        // by the same bound in f64, whose rounding is 2^29 times smaller.
        if t <= self.zero_t_bound::<f32>(tri) && t <= self.zero_t_bound::<f64>(tri) {
            return None;
        }
        Some((t, e1 * inv, e2 * inv))
    }
}

/// The arithmetic the conservative t bound is evaluated in.
pub(super) trait Real:
    Copy
    + PartialOrd
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
{
    fn of(x: f32) -> Self;
    fn abs(self) -> Self;
    /// pbrt's gamma(n) for this type's unit roundoff.
    fn gamma(n: u8) -> Self;
    fn to_f32(self) -> f32;
}

impl Real for f32 {
    fn of(x: f32) -> f32 {
        x
    }
    fn abs(self) -> f32 {
        f32::abs(self)
    }
    fn gamma(n: u8) -> f32 {
        gamma(n as f32)
    }
    fn to_f32(self) -> f32 {
        self
    }
}

impl Real for f64 {
    fn of(x: f32) -> f64 {
        x as f64
    }
    fn abs(self) -> f64 {
        f64::abs(self)
    }
    fn gamma(n: u8) -> f64 {
        let u = f64::EPSILON * 0.5;
        n as f64 * u / (1.0 - n as f64 * u)
    }
    fn to_f32(self) -> f32 {
        // Rounded up, so the bound stays a bound.
        let f = self as f32;
        if (f as f64) < self { f.next_up() } else { f }
    }
}

impl Prepared {
    /// pbrt-v4's bound on the error of the intersection's t, computed in `R` from the
    /// triangle's corners relative to the ray origin (exact in f64): a computed t at or below it
    /// may stand for a true t of zero.
    #[inline(never)]
    fn zero_t_bound<R: Real>(&self, tri: &[[f32; 3]; 3]) -> f32 {
        let [kx, ky, kz] = self.k;
        let (sx, sy, sz) = (
            R::of(self.dir[kx]) / R::of(self.dir[kz]),
            R::of(self.dir[ky]) / R::of(self.dir[kz]),
            R::of(1.0) / R::of(self.dir[kz]),
        );
        let p = tri.map(|v| {
            let rel = |k: usize| R::of(v[k]) - R::of(self.org[k]);
            let (x, y, z) = (rel(kx), rel(ky), rel(kz));
            (x - sx * z, y - sy * z, sz * z)
        });
        let e = [
            p[2].0 * p[1].1 - p[2].1 * p[1].0,
            p[0].0 * p[2].1 - p[0].1 * p[2].0,
            p[1].0 * p[0].1 - p[1].1 * p[0].0,
        ];
        let max3 = |q: R, r: R, s: R| {
            let (q, r, s) = (q.abs(), r.abs(), s.abs());
            let m = if q > r { q } else { r };
            if m > s { m } else { s }
        };
        let max_xt = max3(p[0].0, p[1].0, p[2].0);
        let max_yt = max3(p[0].1, p[1].1, p[2].1);
        let max_zt = max3(p[0].2, p[1].2, p[2].2);
        let max_e = max3(e[0], e[1], e[2]);
        let det = (e[0] + e[1] + e[2]).abs();
        let two = R::of(2.0);
        let delta_z = R::gamma(3) * max_zt;
        let delta_x = R::gamma(5) * (max_xt + max_zt);
        let delta_y = R::gamma(5) * (max_yt + max_zt);
        let delta_e = two * (R::gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let bound =
            R::of(3.0) * (R::gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / det;
        bound.to_f32()
    }
}

/// Woop et al.'s watertight test of one ray against one triangle, outside any BVH: `(t, u, v)`
/// with Embree's barycentrics, or `None` for a miss, a parallel ray or a degenerate triangle.
pub fn intersect_triangle(ray: &Ray, tri: [[f32; 3]; 3]) -> Option<(f32, f32, f32)> {
    Prepared::new(ray)?.triangle(&tri, ray.tfar)
}

/// A child waiting on the traversal stack: a wide node (`count == 0`) or a leaf, and the
/// distance at which the ray enters its box.
#[derive(Clone, Copy, Default)]
struct Entry {
    index: u32,
    count: u32,
    t: f32,
}

impl Bvh {
    /// Closest hit (or with `ANY`, the first hit found) within `[tnear, tfar]`.
    pub(super) fn traverse<const ANY: bool>(&self, ray: &Ray) -> Option<Hit> {
        let p = Prepared::new(ray)?;
        let found = walk::<ANY>(
            &self.nodes,
            self.depth,
            &p,
            ray.tfar,
            |first, count, tmax| {
                let mut best = None;
                let mut tmax = tmax;
                for (i, tri) in self.tris[first..first + count].iter().enumerate() {
                    if let Some((t, u, v)) = p.triangle(tri, tmax) {
                        tmax = t;
                        best = Some((first + i, t, u, v));
                        if ANY {
                            break;
                        }
                    }
                }
                best
            },
        );
        found.map(|(i, t, u, v)| Hit {
            t,
            prim: self.prims[i],
            u,
            v,
        })
    }
}

/// The walk every tree of wide nodes shares: the four children's boxes at once, nearest child
/// first with a short stack. `leaf(first, count, tmax)` tests the primitives in leaf-order slots
/// `first..first + count` and returns the closest hit among them with `t <= tmax` as
/// `(slot, t, u, v)`; the walk returns the closest over all leaves (with `ANY`, the first found).
#[inline(always)]
pub(super) fn walk<const ANY: bool>(
    nodes: &[Wide],
    depth: usize,
    p: &Prepared,
    tfar: f32,
    mut leaf: impl FnMut(usize, usize, f32) -> Option<(usize, f32, f32, f32)>,
) -> Option<(usize, f32, f32, f32)> {
    let mut best_t = tfar;
    let mut best: Option<(usize, f32, f32, f32)> = None;
    let mut inline = [Entry::default(); INLINE_STACK];
    let mut heap;
    // A wide node pushes at most all its children but the one taken, once per level.
    let need = (LANES - 1) * depth + 1;
    let stack: &mut [Entry] = if need <= INLINE_STACK {
        &mut inline
    } else {
        heap = vec![Entry::default(); need];
        &mut heap
    };
    let mut sp = 0usize;
    // The root is a wide node, whose box is not stored: its lanes are tested first thing.
    let mut cur = Entry::default();
    'outer: loop {
        if cur.count == 0 {
            let n = &nodes[cur.index as usize];
            let (dist, mut mask) = p.slabs(n, best_t);
            if mask != 0 {
                let lane = |l: u32| Entry {
                    index: n.index[l as usize],
                    count: n.count[l as usize],
                    t: dist[l as usize],
                };
                let first = lane(mask.trailing_zeros());
                mask &= mask - 1;
                if mask == 0 {
                    cur = first;
                    continue;
                }
                // Two or more: push them all, sort the pushed run so the nearest is on top
                // (insertion sort of at most four), and take the nearest.
                let base = sp;
                stack[sp] = first;
                sp += 1;
                while mask != 0 {
                    stack[sp] = lane(mask.trailing_zeros());
                    sp += 1;
                    mask &= mask - 1;
                }
                for i in base + 1..sp {
                    let e = stack[i];
                    let mut j = i;
                    while j > base && stack[j - 1].t < e.t {
                        stack[j] = stack[j - 1];
                        j -= 1;
                    }
                    stack[j] = e;
                }
                sp -= 1;
                cur = stack[sp];
                continue;
            }
        } else if let Some(h) = leaf(cur.index as usize, cur.count as usize, best_t) {
            best_t = h.1;
            best = Some(h);
            if ANY {
                break 'outer;
            }
        }
        // Pop, skipping children that start beyond the closest hit found since the push.
        loop {
            if sp == 0 {
                break 'outer;
            }
            sp -= 1;
            if stack[sp].t <= best_t {
                cur = stack[sp];
                break;
            }
        }
    }
    best
}
