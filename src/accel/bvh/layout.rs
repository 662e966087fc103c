//! The BVH's memory layout: the build's binary nodes, the 4-wide nodes traversal walks, and the
//! axis-aligned boxes the build works with.

/// A node: bounds plus either two adjacent children at `index`, `index + 1` (`count == 0`) or
/// `count` triangles starting at `index` in leaf order.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Node {
    pub(super) lo: [f32; 3],
    pub(super) count: u32,
    pub(super) hi: [f32; 3],
    pub(super) index: u32,
}

const _: () = assert!(size_of::<Node>() == 32);

impl Node {
    pub(super) fn new(b: &Aabb, index: usize, count: usize) -> Node {
        let (lo, hi) = b.corners();
        Node {
            lo,
            count: count as u32,
            hi,
            index: index as u32,
        }
    }
}

/// A 4-wide node (Wald, Benthin & Boulos, "Getting rid of packets", 2008; the BVH4 of Embree
/// and psychopath): the boxes of up to four children stored lane by lane, so one ray meets all
/// four in the same few vector instructions, and the children's links. 128 bytes, two cache
/// lines. A child is another wide node (`count == 0`), a leaf of `count` triangles starting at
/// `index` in leaf order, or an empty lane ([`Wide::NONE`], with an empty box no ray enters).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub(super) struct Wide {
    /// `lo[axis][lane]`: lower corners of the four children's boxes.
    pub(super) lo: [[f32; LANES]; 3],
    /// `hi[axis][lane]`: upper corners.
    pub(super) hi: [[f32; LANES]; 3],
    pub(super) index: [u32; LANES],
    pub(super) count: [u32; LANES],
}

/// Children per wide node. Eight (Embree's BVH8) was measured with `vastocean bench bvh --quick`:
/// random rays on the 1 M-triangle mesh 1.67 against 1.48-1.57 Mrays/s with four, but 22 % more
/// memory (89.8 against 73.7 MB: wide nodes are less full) and a slower build at 10^5
/// triangles; the camera and secondary rays did not change.
pub(super) const LANES: usize = 4;

const _: () = assert!(size_of::<Wide>() == 32 * LANES);

impl Wide {
    /// The index of an empty lane.
    pub(super) const NONE: u32 = u32::MAX;
    /// Four empty lanes: boxes from +inf to -inf, which every slab test rejects.
    pub(super) const EMPTY: Wide = Wide {
        lo: [[f32::INFINITY; LANES]; 3],
        hi: [[f32::NEG_INFINITY; LANES]; 3],
        index: [Wide::NONE; LANES],
        count: [0; LANES],
    };
    /// Sets lane `l` to a child with box `(lo, hi)`.
    pub(super) fn set(&mut self, l: usize, (lo, hi): ([f32; 3], [f32; 3]), index: u32, count: u32) {
        for k in 0..3 {
            self.lo[k][l] = lo[k];
            self.hi[k][l] = hi[k];
        }
        self.index[l] = index;
        self.count[l] = count;
    }
    /// Lane `l`'s box.
    pub(super) fn lane(&self, l: usize) -> ([f32; 3], [f32; 3]) {
        (
            std::array::from_fn(|k| self.lo[k][l]),
            std::array::from_fn(|k| self.hi[k][l]),
        )
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

/// A box with a fourth lane on each corner, so that joining two boxes is one 4-wide min and max
/// (LLVM vectorises the fixed-size loop): the build does little else. A primitive reference
/// keeps its triangle's id in its own box's fourth lane (see `PrimRef`); in boxes joined from
/// others the lane holds whatever min and max made of it, and nothing reads it.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Aabb {
    pub(super) lo: [f32; 4],
    pub(super) hi: [f32; 4],
}

impl Aabb {
    pub(super) const EMPTY: Aabb = Aabb {
        lo: [f32::INFINITY; 4],
        hi: [f32::NEG_INFINITY; 4],
    };
    #[inline]
    pub(super) fn grow(&mut self, p: [f32; 3]) {
        for (k, c) in p.into_iter().enumerate() {
            self.lo[k] = fmin(self.lo[k], c);
            self.hi[k] = fmax(self.hi[k], c);
        }
    }
    #[inline]
    pub(super) fn join(&mut self, b: &Aabb) {
        for k in 0..4 {
            self.lo[k] = fmin(self.lo[k], b.lo[k]);
            self.hi[k] = fmax(self.hi[k], b.hi[k]);
        }
    }
    /// Half the surface area; zero for an empty box so empty bins cost nothing.
    #[inline]
    pub(super) fn half_area(&self) -> f32 {
        let d: [f32; 3] = std::array::from_fn(|k| (self.hi[k] - self.lo[k]).max(0.0));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
    /// The lower and upper corners' first three lanes.
    #[inline]
    pub(super) fn corners(&self) -> ([f32; 3], [f32; 3]) {
        (
            [self.lo[0], self.lo[1], self.lo[2]],
            [self.hi[0], self.hi[1], self.hi[2]],
        )
    }
}
