//! A bounding volume hierarchy in safe Rust, the backend named "rust": a binned SAH build
//! (16 bins over centroid bounds, Wald 2007) parallelised with `rayon::join`, 32-byte nodes
//! with their two children adjacent, leaves of up to four triangles whose vertices are copied
//! into leaf order, and the watertight ray/triangle test of Woop, Benthin & Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2(1), 2013, with its f64 fallback for edge functions that
//! round to zero. Boxes are tested with the slab method made robust as in Ize, "Robust BVH Ray
//! Traversal", JCGT 2(2), 2013: far distances grow by `1 + 2·gamma(3)`, and a zero direction
//! component gives an infinite inverse whose NaN products are discarded, never propagated.
//! Hits use Embree's barycentric convention (`(1-u-v)·v0 + u·v1 + v·v2`) so the integrator
//! cannot tell this backend from Embree.

use std::sync::Arc;
use std::time::Instant;

use super::{Accel, Hit, Ray};
use crate::mesh::Mesh;

/// Most bins per axis in the SAH sweep; 16 is where more bins stop paying for themselves
/// (Wald 2007). Small nodes use fewer, as Embree does, since their sweep would dominate.
const BINS: usize = 16;
/// Most triangles in a leaf.
pub const MAX_LEAF: usize = 4;
/// Relative SAH costs of one node traversal and one triangle test.
const TRAVERSAL_COST: f32 = 1.0;
const TRIANGLE_COST: f32 = 1.0;
/// Subtrees smaller than this are built on one thread: below it, task overhead beats the gain.
const PARALLEL_MIN: usize = 4096;
/// Binning a node this large is itself split across threads; the top levels dominate otherwise.
const PARALLEL_BIN_MIN: usize = 1 << 16;
/// Traversal stack kept on the machine stack; deeper trees fall back to a heap stack.
const INLINE_STACK: usize = 64;

/// `gamma(n) = n·eps / (1 - n·eps)` with `eps` the unit roundoff (pbrt's bound on n roundings).
const fn gamma(n: f32) -> f32 {
    let eps = f32::EPSILON * 0.5;
    n * eps / (1.0 - n * eps)
}
/// Ize's factor: enough to cover the rounding in `(bound - org) · inv_dir` for the far plane.
const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3.0);

/// A node: bounds plus either two adjacent children at `index`, `index + 1` (`count == 0`) or
/// `count` triangles starting at `index` in leaf order.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    lo: [f32; 3],
    count: u32,
    hi: [f32; 3],
    index: u32,
}

const _: () = assert!(size_of::<Node>() == 32);

/// Two siblings, aligned so they share one 64-byte cache line: traversal tests both children
/// together, and a pair straddling two lines would cost a second miss per step.
#[repr(C, align(64))]
#[derive(Clone, Copy, Default)]
struct Pair([Node; 2]);

impl Node {
    fn new(b: &Aabb, index: usize, count: usize) -> Node {
        Node {
            lo: b.lo,
            count: count as u32,
            hi: b.hi,
            index: index as u32,
        }
    }
}

/// Minimum and maximum as single instructions: the build only sees finite coordinates (the
/// mesh is validated), so `f32::min`'s NaN handling would be paid for nothing.
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 3],
        hi: [f32::NEG_INFINITY; 3],
    };
    #[inline]
    fn grow(&mut self, p: [f32; 3]) {
        for ((lo, hi), c) in self.lo.iter_mut().zip(&mut self.hi).zip(p) {
            *lo = fmin(*lo, c);
            *hi = fmax(*hi, c);
        }
    }
    #[inline]
    fn join(&mut self, b: &Aabb) {
        for k in 0..3 {
            self.lo[k] = fmin(self.lo[k], b.lo[k]);
            self.hi[k] = fmax(self.hi[k], b.hi[k]);
        }
    }
    /// Half the surface area; zero for an empty box so empty bins cost nothing.
    #[inline]
    fn half_area(&self) -> f32 {
        let d: [f32; 3] = std::array::from_fn(|k| (self.hi[k] - self.lo[k]).max(0.0));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
    fn centroid(&self) -> [f32; 3] {
        std::array::from_fn(|k| 0.5 * (self.lo[k] + self.hi[k]))
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

type Bins = [[Bin; BINS]; 3];

/// Maps a centroid to its bin on each axis; axes with no centroid extent get scale 0.
struct BinMap {
    lo: [f32; 3],
    scale: [f32; 3],
    /// Bins in use, at most [`BINS`].
    count: usize,
}

impl BinMap {
    fn new(cb: &Aabb, n: usize) -> BinMap {
        let count = (4 + n / 20).min(BINS);
        BinMap {
            lo: cb.lo,
            scale: std::array::from_fn(|k| {
                let e = cb.hi[k] - cb.lo[k];
                if e > 0.0 { count as f32 / e } else { 0.0 }
            }),
            count,
        }
    }
    /// The float-to-int cast saturates, so rounding past either end stays in range.
    #[inline]
    fn bin(&self, c: [f32; 3], k: usize) -> usize {
        (((c[k] - self.lo[k]) * self.scale[k]) as usize).min(self.count - 1)
    }
}

/// A triangle as the build sees it. The build partitions these in place rather than an index
/// array, so binning and partitioning stream through memory instead of gathering from it.
#[derive(Clone, Copy)]
struct PrimRef {
    bounds: Aabb,
    id: u32,
}

impl PrimRef {
    #[inline]
    fn centroid(&self) -> [f32; 3] {
        self.bounds.centroid()
    }
}

enum Decision {
    Leaf,
    /// Split after `mid` ids, with each side's bounds and centroid bounds.
    Split {
        mid: usize,
        left: (Aabb, Aabb),
        right: (Aabb, Aabb),
    },
}

fn bin_slice(refs: &[PrimRef], map: &BinMap) -> Bins {
    let mut bins = [[EMPTY_BIN; BINS]; 3];
    for r in refs {
        let (c, b) = (r.centroid(), &r.bounds);
        for (k, axis) in bins.iter_mut().enumerate() {
            let bin = &mut axis[map.bin(c, k)];
            bin.count += 1;
            bin.bounds.join(b);
        }
    }
    bins
}

fn merge_bins(mut a: Bins, b: Bins) -> Bins {
    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        x.count += y.count;
        x.bounds.join(&y.bounds);
    }
    a
}

/// Chooses leaf or split for `ids` (bounds `b`, centroid bounds `cb`) and, for a split,
/// partitions `ids` in place.
fn decide(ids: &mut [PrimRef], b: &Aabb, cb: &Aabb) -> Decision {
    use rayon::prelude::*;
    let n = ids.len();
    if n == 1 {
        return Decision::Leaf;
    }
    let map = BinMap::new(cb, n);
    if map.scale == [0.0; 3] {
        // Every centroid coincides: SAH cannot separate them, so only size forces a split.
        if n <= MAX_LEAF {
            return Decision::Leaf;
        }
        return median_split(ids);
    }
    let bins = if n >= PARALLEL_BIN_MIN {
        ids.par_chunks(PARALLEL_BIN_MIN / 2)
            .map(|c| bin_slice(c, &map))
            .reduce(|| [[EMPTY_BIN; BINS]; 3], merge_bins)
    } else {
        bin_slice(ids, &map)
    };
    // Sweep each axis: suffix costs right to left, then prefix left to right.
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for (k, axis) in bins.iter().enumerate() {
        if map.scale[k] == 0.0 {
            continue;
        }
        let mut right_cost = [0f32; BINS];
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in (1..map.count).rev() {
            acc.join(&axis[i].bounds);
            cnt += axis[i].count;
            right_cost[i] = if cnt > 0 {
                acc.half_area() * cnt as f32
            } else {
                f32::INFINITY
            };
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in 1..map.count {
            acc.join(&axis[i - 1].bounds);
            cnt += axis[i - 1].count;
            if cnt == 0 {
                continue;
            }
            let cost = acc.half_area() * cnt as f32 + right_cost[i];
            if cost < best.0 {
                best = (cost, k, i);
            }
        }
    }
    let (cost, axis, split) = best;
    // Costs are compared multiplied through by the parent's area, so a flat box (area 0)
    // needs no division.
    let area = b.half_area();
    let split_cost = TRAVERSAL_COST * area + TRIANGLE_COST * cost;
    if n <= MAX_LEAF && TRIANGLE_COST * n as f32 * area <= split_cost {
        return Decision::Leaf;
    }
    if !cost.is_finite() {
        return median_split(ids);
    }
    let (mut lb, mut rb) = (Aabb::EMPTY, Aabb::EMPTY);
    for (i, bin) in bins[axis].iter().enumerate() {
        if i < split {
            lb.join(&bin.bounds);
        } else {
            rb.join(&bin.bounds);
        }
    }
    let (mut lcb, mut rcb) = (Aabb::EMPTY, Aabb::EMPTY);
    let (mut i, mut j) = (0, n);
    while i < j {
        let c = ids[i].centroid();
        if map.bin(c, axis) < split {
            lcb.grow(c);
            i += 1;
        } else {
            rcb.grow(c);
            j -= 1;
            ids.swap(i, j);
        }
    }
    Decision::Split {
        mid: i,
        left: (lb, lcb),
        right: (rb, rcb),
    }
}

fn median_split(ids: &[PrimRef]) -> Decision {
    let mid = ids.len() / 2;
    let side = |s: &[PrimRef]| {
        let (mut b, mut cb) = (Aabb::EMPTY, Aabb::EMPTY);
        for r in s {
            b.join(&r.bounds);
            cb.grow(r.centroid());
        }
        (b, cb)
    };
    Decision::Split {
        mid,
        left: side(&ids[..mid]),
        right: side(&ids[mid..]),
    }
}

/// Builds the subtree of `ids` (the leaf-order range starting at `offset`) into `nodes`, with
/// its root written at `slot`.
fn build_serial(
    ids: &mut [PrimRef],
    offset: usize,
    (b, cb): (Aabb, Aabb),
    nodes: &mut Vec<Node>,
    slot: usize,
) {
    match decide(ids, &b, &cb) {
        Decision::Leaf => nodes[slot] = Node::new(&b, offset, ids.len()),
        Decision::Split { mid, left, right } => {
            let c = nodes.len();
            nodes.extend([Node::default(); 2]);
            nodes[slot] = Node::new(&b, c, 0);
            let (l, r) = ids.split_at_mut(mid);
            build_serial(l, offset, left, nodes, c);
            build_serial(r, offset + mid, right, nodes, c + 1);
        }
    }
}

/// The parallel top of the tree; below [`PARALLEL_MIN`] triangles each task builds a flat
/// subtree whose root is its element 0.
enum Upper {
    Inner(Aabb, Box<Upper>, Box<Upper>),
    Subtree(Vec<Node>),
}

fn build_parallel(ids: &mut [PrimRef], offset: usize, bc: (Aabb, Aabb)) -> Upper {
    let n = ids.len();
    if n < PARALLEL_MIN {
        let mut nodes = Vec::with_capacity(n);
        nodes.push(Node::default());
        build_serial(ids, offset, bc, &mut nodes, 0);
        return Upper::Subtree(nodes);
    }
    match decide(ids, &bc.0, &bc.1) {
        Decision::Leaf => {
            let mut nodes = vec![Node::default()];
            nodes[0] = Node::new(&bc.0, offset, n);
            Upper::Subtree(nodes)
        }
        Decision::Split { mid, left, right } => {
            let (l, r) = ids.split_at_mut(mid);
            let (l, r) = rayon::join(
                || build_parallel(l, offset, left),
                || build_parallel(r, offset + mid, right),
            );
            Upper::Inner(bc.0, Box::new(l), Box::new(r))
        }
    }
}

/// Copies `up` into `nodes` in final layout, its root at `slot`.
fn flatten(up: Upper, nodes: &mut Vec<Node>, slot: usize) {
    match up {
        Upper::Subtree(sub) => {
            // Local child indices start at 1 (0 is the root, which goes to `slot`).
            let base = nodes.len() as u32;
            let relocate = |mut n: Node| {
                if n.count == 0 {
                    n.index = n.index - 1 + base;
                }
                n
            };
            nodes[slot] = relocate(sub[0]);
            nodes.extend(sub[1..].iter().map(|&n| relocate(n)));
        }
        Upper::Inner(b, l, r) => {
            let c = nodes.len();
            nodes.extend([Node::default(); 2]);
            nodes[slot] = Node::new(&b, c, 0);
            flatten(*l, nodes, c);
            flatten(*r, nodes, c + 1);
        }
    }
}

/// A ray prepared for traversal: inverse direction for the slabs and Woop et al.'s
/// permutation and shear into ray space.
struct Prepared {
    org: [f32; 3],
    inv: [f32; 3],
    tnear: f32,
    k: [usize; 3],
    shear: [f32; 3],
}

impl Prepared {
    /// `None` for a ray without a usable direction (zero or non-finite).
    fn new(ray: &Ray) -> Option<Prepared> {
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
            // Adding +0 turns -0 into +0: the inverse is then always +inf for a zero
            // component, so the NaN from `0 · inf` on a slab plane only ever appears where the
            // slab test below ignores it, never as a -inf far distance.
            inv: d.map(|c| 1.0 / (c + 0.0)),
            tnear: ray.tnear,
            k: [kx, ky, kz],
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        })
    }

    /// Entry distance into `n` if the ray meets it within `[tnear, tmax]`.
    #[inline(always)]
    fn slab(&self, n: &Node, tmax: f32) -> Option<f32> {
        let (mut t0, mut t1) = (self.tnear, tmax);
        for k in 0..3 {
            let mut near = (n.lo[k] - self.org[k]) * self.inv[k];
            let mut far = (n.hi[k] - self.org[k]) * self.inv[k];
            // A NaN compares false everywhere, so it is never swapped in as far, and the two
            // updates below keep the running value: the ray lies in that slab plane and the
            // axis imposes no constraint.
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            far *= FAR_SCALE;
            t0 = if near > t0 { near } else { t0 };
            t1 = if far < t1 { far } else { t1 };
        }
        (t0 <= t1).then_some(t0)
    }

    /// Woop et al.'s watertight test: `(t, u, v)` for a hit with `tnear <= t <= tmax`.
    #[inline(always)]
    fn triangle(&self, tri: &[[f32; 3]; 3], tmax: f32) -> Option<(f32, f32, f32)> {
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
        Some((t, e1 * inv, e2 * inv))
    }
}

/// Woop et al.'s watertight test of one ray against one triangle, outside any BVH: `(t, u, v)`
/// with Embree's barycentrics, or `None` for a miss, a parallel ray or a degenerate triangle.
pub fn intersect_triangle(ray: &Ray, tri: [[f32; 3]; 3]) -> Option<(f32, f32, f32)> {
    Prepared::new(ray)?.triangle(&tri, ray.tfar)
}

/// The Rust BVH over one mesh.
pub struct Bvh {
    mesh: Arc<Mesh>,
    /// Node `i` is `nodes[i / 2].0[i % 2]`; the root is node 0 and node 1 is padding, so every
    /// sibling pair starts at an even index.
    nodes: Vec<Pair>,
    /// Triangle corners in leaf order, so a leaf's triangles are contiguous in memory.
    tris: Vec<[[f32; 3]; 3]>,
    /// Original triangle index of each entry of `tris`.
    prims: Vec<u32>,
    depth: usize,
    build_seconds: f64,
}

impl Bvh {
    /// Builds the hierarchy on the current rayon pool.
    pub fn build(mesh: Arc<Mesh>) -> Bvh {
        use rayon::prelude::*;
        let start = Instant::now();
        let n = mesh.triangle_count();
        let mut refs: Vec<PrimRef> = (0..n as u32)
            .into_par_iter()
            .map(|id| {
                let mut bounds = Aabb::EMPTY;
                mesh.triangle(id).iter().for_each(|&v| bounds.grow(v));
                PrimRef { bounds, id }
            })
            .collect();
        let (b, cb) = refs
            .par_iter()
            .fold(
                || (Aabb::EMPTY, Aabb::EMPTY),
                |(mut b, mut cb), r| {
                    b.join(&r.bounds);
                    cb.grow(r.centroid());
                    (b, cb)
                },
            )
            .reduce(
                || (Aabb::EMPTY, Aabb::EMPTY),
                |(mut b, mut cb), (b2, cb2)| {
                    b.join(&b2);
                    cb.join(&cb2);
                    (b, cb)
                },
            );
        let upper = build_parallel(&mut refs, 0, (b, cb));
        let mut nodes = Vec::with_capacity(n.div_ceil(2) + 2);
        // Root and padding: from here on nodes are appended in pairs, at even indices.
        nodes.extend([Node::default(); 2]);
        flatten(upper, &mut nodes, 0);
        let ids: Vec<u32> = refs.par_iter().map(|r| r.id).collect();
        drop(refs);
        let tris: Vec<[[f32; 3]; 3]> = ids.par_iter().map(|&p| mesh.triangle(p)).collect();
        let depth = tree_depth(&nodes);
        let nodes = nodes.chunks_exact(2).map(|c| Pair([c[0], c[1]])).collect();
        Bvh {
            mesh,
            nodes,
            tris,
            prims: ids,
            depth,
            build_seconds: start.elapsed().as_secs_f64(),
        }
    }

    /// Wall-clock seconds [`Bvh::build`] took, from triangle bounds to leaf reordering.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    pub fn node_count(&self) -> usize {
        // Without the padding node.
        2 * self.nodes.len() - 1
    }

    /// Levels from the root to the deepest leaf (a lone leaf has depth 1).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Whether anything lies on the ray within `[tnear, tfar]`; stops at the first hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.traverse::<true>(ray).is_some()
    }

    /// Checks the structure: every triangle in exactly one leaf, leaves of 1 to
    /// [`MAX_LEAF`] triangles, every node's box enclosing its children or triangles. For tests.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = vec![false; self.tris.len()];
        let mut todo = vec![0usize];
        let inside = |outer: &Node, lo: [f32; 3], hi: [f32; 3]| {
            (0..3).all(|k| outer.lo[k] <= lo[k] && hi[k] <= outer.hi[k])
        };
        while let Some(i) = todo.pop() {
            let n = self.node(i);
            if n.count == 0 {
                let c = n.index as usize;
                if c <= i || !c.is_multiple_of(2) || c + 1 >= 2 * self.nodes.len() {
                    return Err(format!("node {i} has children at {c}"));
                }
                for ch in [c, c + 1] {
                    if !inside(n, self.node(ch).lo, self.node(ch).hi) {
                        return Err(format!("child {ch} sticks out of node {i}"));
                    }
                    todo.push(ch);
                }
            } else {
                if n.count as usize > MAX_LEAF {
                    return Err(format!("leaf {i} holds {} triangles", n.count));
                }
                for t in (n.index..n.index + n.count).map(|t| t as usize) {
                    if std::mem::replace(&mut seen[t], true) {
                        return Err(format!("triangle slot {t} is in two leaves"));
                    }
                    if self.tris[t] != self.mesh.triangle(self.prims[t]) {
                        return Err(format!("triangle slot {t} is not a copy of its prim"));
                    }
                    if self.tris[t].iter().any(|&v| !inside(n, v, v)) {
                        return Err(format!("triangle slot {t} sticks out of leaf {i}"));
                    }
                }
            }
        }
        let mut ids = self.prims.clone();
        ids.sort_unstable();
        if seen.iter().any(|s| !s) || ids.iter().enumerate().any(|(i, &p)| p as usize != i) {
            return Err("leaves do not hold each triangle exactly once".into());
        }
        Ok(())
    }

    #[inline(always)]
    fn node(&self, i: usize) -> &Node {
        &self.nodes[i / 2].0[i % 2]
    }

    /// Closest hit (or with `ANY`, the first hit found) within `[tnear, tfar]`.
    fn traverse<const ANY: bool>(&self, ray: &Ray) -> Option<Hit> {
        let p = Prepared::new(ray)?;
        let mut best_t = ray.tfar;
        let mut best: Option<(usize, f32, f32)> = None;
        let mut inline = [(0u32, 0f32); INLINE_STACK];
        let mut heap;
        // At most one entry per level is pushed, so the depth bounds the stack.
        let stack: &mut [(u32, f32)] = if self.depth < INLINE_STACK {
            &mut inline
        } else {
            heap = vec![(0u32, 0f32); self.depth + 1];
            &mut heap
        };
        let mut sp = 0usize;
        p.slab(self.node(0), best_t)?;
        let mut node = 0usize;
        'outer: loop {
            let n = self.node(node);
            if n.count > 0 {
                let first = n.index as usize;
                for (i, tri) in self.tris[first..first + n.count as usize]
                    .iter()
                    .enumerate()
                {
                    if let Some((t, u, v)) = p.triangle(tri, best_t) {
                        best_t = t;
                        best = Some((first + i, u, v));
                        if ANY {
                            break 'outer;
                        }
                    }
                }
            } else {
                let c = n.index as usize;
                let [n0, n1] = &self.nodes[c / 2].0;
                let d0 = p.slab(n0, best_t);
                let d1 = p.slab(n1, best_t);
                match (d0, d1) {
                    (Some(a), Some(b)) => {
                        let (near, far, t_far) = if a <= b { (c, c + 1, b) } else { (c + 1, c, a) };
                        stack[sp] = (far as u32, t_far);
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = c;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = c + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping subtrees that start beyond the closest hit found since the push.
            loop {
                if sp == 0 {
                    break 'outer;
                }
                sp -= 1;
                let (next, t_entry) = stack[sp];
                if t_entry <= best_t {
                    node = next as usize;
                    break;
                }
            }
        }
        best.map(|(i, u, v)| Hit {
            t: best_t,
            prim: self.prims[i],
            u,
            v,
        })
    }
}

/// Levels from the root to the deepest leaf.
fn tree_depth(nodes: &[Node]) -> usize {
    let mut deepest = 0;
    let mut todo = vec![(0usize, 1usize)];
    while let Some((i, d)) = todo.pop() {
        deepest = deepest.max(d);
        let n = &nodes[i];
        if n.count == 0 {
            todo.push((n.index as usize, d + 1));
            todo.push((n.index as usize + 1, d + 1));
        }
    }
    deepest
}

impl Accel for Bvh {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.traverse::<false>(ray)
    }

    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn name(&self) -> &'static str {
        "rust"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        Mesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
            ],
            vec![],
            vec![],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .unwrap()
    }

    #[test]
    fn known_hit_has_embree_barycentrics() {
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
        let (t, u, v) =
            intersect_triangle(&Ray::new([0.25, 2.0, 0.5], [0.0, -1.0, 0.0]), tri).expect("hit");
        assert_eq!((t, u, v), (2.0, 0.25, 0.5));
        // The same from below, and along a slanted direction with a negative dominant axis.
        let (t, u, v) =
            intersect_triangle(&Ray::new([0.25, -3.0, 0.5], [0.0, 1.0, 0.0]), tri).unwrap();
        assert_eq!((t, u, v), (3.0, 0.25, 0.5));
        let d = [0.36f32, 0.48, -0.8];
        let (t, u, v) =
            intersect_triangle(&Ray::new([0.1 - 0.36, -0.48, 0.3 + 0.8], d), tri).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (u - 0.1).abs() < 1e-6 && (v - 0.3).abs() < 1e-6);
        assert!(intersect_triangle(&Ray::new([0.75, 2.0, 0.5], [0.0, -1.0, 0.0]), tri).is_none());
    }

    #[test]
    fn tiny_mesh_is_one_leaf_and_traces() {
        let bvh = Bvh::build(Arc::new(quad()));
        assert_eq!(bvh.node_count(), 1);
        assert_eq!(bvh.depth(), 1);
        bvh.validate().unwrap();
        let h = bvh
            .intersect(&Ray::new([0.7, 3.0, 0.2], [0.0, -1.0, 0.0]))
            .unwrap();
        assert_eq!((h.prim, h.t), (0, 3.0));
        assert!(bvh.occluded(&Ray::new([0.2, 1.0, 0.7], [0.0, -1.0, 0.0])));
        assert!(!bvh.occluded(&Ray::new([0.2, 1.0, 0.7], [0.0, 1.0, 0.0])));
    }

    #[test]
    fn grid_tree_is_well_formed() {
        let bvh = Bvh::build(Arc::new(Mesh::grid(150, 100, 0.5)));
        bvh.validate().unwrap();
        // Leaves of up to 4 triangles over 30 000 triangles: at least 7 500 leaves.
        assert!(bvh.node_count() >= 2 * 7_500 - 1, "{}", bvh.node_count());
        assert!(bvh.depth() < 40, "depth {}", bvh.depth());
        assert!(bvh.build_seconds() > 0.0);
    }

    #[test]
    fn slab_ignores_nan_from_rays_in_a_slab_plane() {
        // A flat box in y = 0 and rays running exactly along its faces, with -0 components.
        let n = Node {
            lo: [0.0, 0.0, 0.0],
            count: 1,
            hi: [1.0, 0.0, 1.0],
            index: 0,
        };
        for (org, dir) in [
            ([0.0, 1.0, 0.5], [-0.0, -1.0, 0.0]),
            ([1.0, 1.0, 1.0], [0.0, -1.0, -0.0]),
            ([-1.0, 0.0, 0.0], [1.0, -0.0, 0.0]),
            ([0.5, 0.0, 2.0], [-0.0, 0.0, -1.0]),
        ] {
            let p = Prepared::new(&Ray::new(org, dir)).unwrap();
            assert!(p.slab(&n, f32::INFINITY).is_some(), "{org:?} {dir:?}");
        }
        let p = Prepared::new(&Ray::new([1.5, 1.0, 0.5], [0.0, -1.0, 0.0])).unwrap();
        assert!(p.slab(&n, f32::INFINITY).is_none());
    }
}
