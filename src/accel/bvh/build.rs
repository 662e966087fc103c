//! The build: binned SAH (up to 16 bins over centroid bounds, Wald 2007) on 32-byte primitive
//! references (4-wide boxes, Embree's layout) partitioned in place without branches, the top
//! levels split across threads with `rayon::join` (and binning of the largest nodes across
//! chunks), each thread's subtree collapsed into 4-wide nodes as soon as it is built, and the
//! top of the tree collapsed over them.

use std::sync::Arc;

use rayon::prelude::*;

use super::collapse::{collapse, widen};
use super::layout::{Aabb, LANES, Node, Wide};
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

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    count: 0,
};

/// Bins of all three axes; `N` is [`BINS`] or, for small nodes, 4 or 8 (the smallest that holds
/// the bins in use, see [`decide`]). The sweep always stopped at the bins in use; what a smaller
/// `N` saves is clearing 16 bins per axis and joining them into the two sides, which for a node
/// of a few triangles cost more than the triangles did.
type Bins<const N: usize> = [[Bin; N]; 3];

/// Maps a centroid to its bin on each axis; axes with no centroid extent get scale 0. Centroids
/// are kept doubled (`lo + hi`, see [`PrimRef::centroid2`]) throughout the build, and so are
/// the centroid bounds it is made from.
struct BinMap {
    lo: [f32; 4],
    scale: [f32; 4],
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
                if k < 3 && e > 0.0 {
                    count as f32 / e
                } else {
                    0.0
                }
            }),
            count,
        }
    }
    /// The bin of `r` on axis `k`. The float-to-int cast saturates, so rounding past either
    /// end stays in range.
    #[inline]
    fn bin(&self, r: &PrimRef, k: usize) -> usize {
        let c = r.centroid2();
        (((c[k] - self.lo[k]) * self.scale[k]) as usize).min(self.count - 1)
    }
    /// [`Self::bin`] on the three axes.
    #[inline]
    fn bins(&self, r: &PrimRef) -> [usize; 3] {
        std::array::from_fn(|k| self.bin(r, k))
    }
}

/// A triangle as the build sees it: its box, with the triangle's id in the lower corner's unused
/// fourth lane (bit-cast, as Embree's `PrimRef` does), so a reference is one aligned 32-byte
/// record. The build partitions these in place rather than an index array, so binning and
/// partitioning stream through memory instead of gathering from it.
#[derive(Clone, Copy)]
struct PrimRef(Aabb);

impl PrimRef {
    fn new(mut bounds: Aabb, id: u32) -> PrimRef {
        bounds.lo[3] = f32::from_bits(id);
        bounds.hi[3] = f32::from_bits(id);
        PrimRef(bounds)
    }
    #[inline]
    fn id(&self) -> u32 {
        self.0.lo[3].to_bits()
    }
    /// Twice the centroid, `lo + hi` (the fourth lane is meaningless).
    #[inline]
    fn centroid2(&self) -> [f32; 4] {
        std::array::from_fn(|k| self.0.lo[k] + self.0.hi[k])
    }
}

/// Grows centroid bounds (doubled, see [`BinMap`]) by a reference's centroid.
#[inline]
fn grow_centroid(cb: &mut Aabb, r: &PrimRef) {
    let c = r.centroid2();
    cb.grow([c[0], c[1], c[2]]);
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

fn bin_slice<const N: usize>(refs: &[PrimRef], map: &BinMap) -> Bins<N> {
    let mut bins = [[EMPTY_BIN; N]; 3];
    for r in refs {
        let idx = map.bins(r);
        for (axis, &i) in bins.iter_mut().zip(&idx) {
            let bin = &mut axis[i];
            bin.count += 1;
            bin.bounds.join(&r.0);
        }
    }
    bins
}

fn merge_bins<const N: usize>(mut a: Bins<N>, b: Bins<N>) -> Bins<N> {
    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        x.count += y.count;
        x.bounds.join(&y.bounds);
    }
    a
}

/// Chooses leaf or split for `ids` (bounds `b`, centroid bounds `cb`) and, for a split,
/// partitions `ids` in place.
fn decide(ids: &mut [PrimRef], b: &Aabb, cb: &Aabb) -> Decision {
    let n = ids.len();
    if n == 1 {
        return Decision::Leaf;
    }
    let map = BinMap::new(cb, n);
    if map.scale == [0.0; 4] {
        // Every centroid coincides: SAH cannot separate them, so only size forces a split.
        if n <= MAX_LEAF {
            return Decision::Leaf;
        }
        return median_split(ids);
    }
    match map.count {
        0..=4 => decide_binned::<4>(ids, b, &map),
        5..=8 => decide_binned::<8>(ids, b, &map),
        _ => decide_binned::<BINS>(ids, b, &map),
    }
}

/// [`decide`] with `N >= map.count` bins per axis.
fn decide_binned<const N: usize>(ids: &mut [PrimRef], b: &Aabb, map: &BinMap) -> Decision {
    let n = ids.len();
    let bins: Bins<N> = if n >= PARALLEL_BIN_MIN {
        ids.par_chunks(PARALLEL_BIN_MIN / 2)
            .map(|c| bin_slice(c, map))
            .reduce(|| [[EMPTY_BIN; N]; 3], merge_bins)
    } else {
        bin_slice(ids, map)
    };
    // Sweep each axis: suffix costs right to left, then prefix left to right.
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for (k, axis) in bins.iter().enumerate() {
        if map.scale[k] == 0.0 {
            continue;
        }
        let mut right_cost = [0f32; N];
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
    // Branch-free Lomuto partition: every reference is swapped with the first right-hand one
    // and the boundary advances by the comparison. Which side a triangle goes is a coin toss to
    // the branch predictor, and a branching partition paid a misprediction on half of them.
    let mut mid = 0;
    for i in 0..n {
        let left = map.bin(&ids[i], axis) < split;
        ids.swap(i, mid);
        mid += left as usize;
    }
    let centroid_bounds = |s: &[PrimRef]| {
        let mut cb = Aabb::EMPTY;
        s.iter().for_each(|r| grow_centroid(&mut cb, r));
        cb
    };
    Decision::Split {
        mid,
        left: (lb, centroid_bounds(&ids[..mid])),
        right: (rb, centroid_bounds(&ids[mid..])),
    }
}

fn median_split(ids: &[PrimRef]) -> Decision {
    let mid = ids.len() / 2;
    let side = |s: &[PrimRef]| {
        let (mut b, mut cb) = (Aabb::EMPTY, Aabb::EMPTY);
        for r in s {
            b.join(&r.0);
            grow_centroid(&mut cb, r);
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

/// The parallel top of the tree. Below [`PARALLEL_MIN`] triangles each task builds a binary
/// subtree (root at element 0, siblings in pairs from element 1) and collapses it into wide
/// nodes while it is still in cache.
enum Upper {
    Inner(Aabb, Box<Upper>, Box<Upper>),
    /// A side of at most [`MAX_LEAF`] triangles that stayed a leaf.
    Leaf(Node),
    /// Wide nodes indexed from their own root at 0, and their depth.
    Wide {
        bounds: Aabb,
        nodes: Vec<Wide>,
        depth: usize,
    },
}

impl Upper {
    /// At least as many wide nodes as the assembled tree has (an inner node becomes at most one).
    fn wide_nodes(&self) -> usize {
        match self {
            Upper::Inner(_, l, r) => 1 + l.wide_nodes() + r.wide_nodes(),
            Upper::Leaf(_) => 0,
            Upper::Wide { nodes, .. } => nodes.len(),
        }
    }
}

fn build_parallel(ids: &mut [PrimRef], offset: usize, bc: (Aabb, Aabb)) -> Upper {
    let n = ids.len();
    if n < PARALLEL_MIN {
        // A binary tree over n triangles has fewer than 2n nodes.
        let mut nodes = Vec::with_capacity(2 * n);
        nodes.push(Node::default());
        build_serial(ids, offset, bc, &mut nodes, 0);
        if nodes[0].count > 0 {
            return Upper::Leaf(nodes[0]);
        }
        let (nodes, depth) = collapse(&nodes);
        return Upper::Wide {
            bounds: bc.0,
            nodes,
            depth,
        };
    }
    match decide(ids, &bc.0, &bc.1) {
        // Unreachable above PARALLEL_MIN (`decide` makes leaves of at most MAX_LEAF triangles);
        // handled rather than asserted so that `decide` alone owns the leaf rule.
        Decision::Leaf => Upper::Leaf(Node::new(&bc.0, offset, n)),
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

/// Writes the wide node for `up` (an [`Upper::Inner`]) at `slot` of `out`, appending its
/// descendants after it (the collapsed subtrees relocated by their offset); returns its depth.
fn assemble(up: &Upper, out: &mut Vec<Wide>, slot: usize) -> usize {
    let Upper::Inner(_, l, r) = up else {
        unreachable!("only inner nodes are assembled")
    };
    let (kids, n) = widen(
        [&**l, &**r],
        |u| match u {
            Upper::Inner(b, ..) => Some(b.half_area()),
            _ => None,
        },
        |u| match u {
            Upper::Inner(_, l, r) => [&**l, &**r],
            _ => unreachable!("`widen` opens only the children it has an area for"),
        },
    );
    let mut below = 0;
    for (lane, kid) in kids[..n].iter().enumerate() {
        match kid {
            Upper::Leaf(leaf) => out[slot].set(lane, (leaf.lo, leaf.hi), leaf.index, leaf.count),
            Upper::Wide {
                bounds,
                nodes,
                depth,
            } => {
                let base = out.len() as u32;
                out[slot].set(lane, bounds.corners(), base, 0);
                out.extend(nodes.iter().map(|w| {
                    let mut w = *w;
                    for l in 0..LANES {
                        if w.count[l] == 0 && w.index[l] != Wide::NONE {
                            w.index[l] += base;
                        }
                    }
                    w
                }));
                below = below.max(*depth);
            }
            Upper::Inner(b, ..) => {
                let s = out.len();
                out.push(Wide::EMPTY);
                out[slot].set(lane, b.corners(), s as u32, 0);
                below = below.max(assemble(kid, out, s));
            }
        }
    }
    1 + below
}

/// The built tree: 4-wide nodes (root first, every node's children after it), the triangle ids
/// in leaf order, and the depth in wide nodes from the root to the deepest leaf.
pub(super) struct Built {
    pub(super) nodes: Vec<Wide>,
    pub(super) ids: Vec<u32>,
    pub(super) depth: usize,
}

/// Builds the tree over `mesh` on the current rayon pool.
pub(super) fn build_nodes(mesh: &Arc<Mesh>) -> Built {
    build_over((0..mesh.triangle_count() as u32).into_par_iter().map(|id| {
        let mut bounds = Aabb::EMPTY;
        mesh.triangle(id).iter().for_each(|&v| bounds.grow(v));
        bounds
    }))
}

/// Builds the tree over primitives with boxes `bounds` (primitive `i` the `i`-th box), on the
/// current rayon pool.
pub(super) fn build_over(bounds: impl IndexedParallelIterator<Item = Aabb>) -> Built {
    let mut refs: Vec<PrimRef> = bounds
        .enumerate()
        .map(|(id, b)| PrimRef::new(b, id as u32))
        .collect();
    let (b, cb) = refs
        .par_iter()
        .fold(
            || (Aabb::EMPTY, Aabb::EMPTY),
            |(mut b, mut cb), r| {
                b.join(&r.0);
                grow_centroid(&mut cb, r);
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
    let (nodes, depth) = match build_parallel(&mut refs, 0, (b, cb)) {
        Upper::Leaf(leaf) => {
            let mut root = Wide::EMPTY;
            root.set(0, (leaf.lo, leaf.hi), leaf.index, leaf.count);
            (vec![root], 1)
        }
        Upper::Wide { nodes, depth, .. } => (nodes, depth),
        inner => {
            let mut nodes = Vec::with_capacity(inner.wide_nodes());
            nodes.push(Wide::EMPTY);
            let depth = assemble(&inner, &mut nodes, 0);
            (nodes, depth)
        }
    };
    let ids = refs.par_iter().map(PrimRef::id).collect();
    Built { nodes, ids, depth }
}
