//! A bounding volume hierarchy in safe Rust, the backend named "rust": a binned SAH build
//! (up to 16 bins over centroid bounds, Wald 2007) parallelised with `rayon::join` into a binary
//! tree, collapsed into 4-wide nodes whose four child boxes a ray meets in one set of vector
//! instructions, leaves of up to four triangles whose vertices are copied into leaf order, and
//! the watertight ray/triangle test of Woop, Benthin & Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2(1), 2013, with its f64 fallback for edge functions that
//! round to zero. Boxes are tested with the slab method made robust as in Ize, "Robust BVH Ray
//! Traversal", JCGT 2(2), 2013: far distances grow by `1 + 2·gamma(3)`, and a zero direction
//! component gives an infinite inverse whose NaN products are discarded, never propagated.
//! Hits use Embree's barycentric convention (`(1-u-v)·v0 + u·v1 + v·v2`) so the integrator
//! cannot tell this backend from Embree.
//!
//! [`build`] makes the tree (binary, then collapsed into 4-wide nodes by [`collapse`]),
//! [`layout`] is its memory layout, [`traverse`] walks it.

mod build;
mod collapse;
mod layout;
mod traverse;

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use super::{Accel, Hit, Ray};
use crate::mesh::Mesh;
pub use build::MAX_LEAF;
use layout::{LANES, Wide};
pub use traverse::intersect_triangle;

/// The Rust BVH over one mesh.
pub struct Bvh {
    mesh: Arc<Mesh>,
    /// 4-wide nodes, the root first and every node's children after it.
    nodes: Vec<Wide>,
    /// Triangle corners in leaf order, so a leaf's triangles are contiguous in memory.
    tris: Vec<[[f32; 3]; 3]>,
    /// Original triangle index of each entry of `tris`.
    prims: Vec<u32>,
    depth: usize,
    build_seconds: f64,
    /// Rays with a NaN or infinite origin or direction, answered as misses without traversal.
    rejected: AtomicU64,
}

impl Bvh {
    /// Builds the hierarchy on the current rayon pool. Panics for meshes of 2^32 - 1 triangles
    /// or more (leaf offsets are 32-bit, and all ones marks an empty lane).
    pub fn build(mesh: Arc<Mesh>) -> Bvh {
        use rayon::prelude::*;
        assert!(
            mesh.triangle_count() < Wide::NONE as usize,
            "the Rust BVH holds fewer than 2^32 - 1 triangles"
        );
        let start = Instant::now();
        let build::Built { nodes, ids, depth } = build::build_nodes(&mesh);
        let tris: Vec<[[f32; 3]; 3]> = ids.par_iter().map(|&p| mesh.triangle(p)).collect();
        Bvh {
            mesh,
            nodes,
            tris,
            prims: ids,
            depth,
            build_seconds: start.elapsed().as_secs_f64(),
            rejected: AtomicU64::new(0),
        }
    }

    /// Wall-clock seconds [`Bvh::build`] took, from triangle bounds to leaf reordering.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// Moves the mesh's vertices and normals (same topology: an animation frame) and refits
    /// the bounds bottom-up, keeping the tree: the leaves' triangle copies are refreshed and
    /// every node's box becomes the union of its children's. Returns the seconds the refit
    /// took (not the vertex copy). The tree's quality degrades as the vertices wander from
    /// where the SAH placed them; an ocean's vertices move by metres on a tree whose boxes
    /// span kilometres near the top, so it stays good. Fails, changing nothing, when another
    /// owner shares the mesh or the vertices are invalid.
    pub fn refit(&mut self, positions: &[[f32; 3]], normals: &[[f32; 3]]) -> Result<f64, String> {
        use rayon::prelude::*;
        let mesh = Arc::get_mut(&mut self.mesh)
            .ok_or("the mesh is shared with another owner; it cannot move")?;
        mesh.set_vertices(positions, normals)
            .map_err(|e| e.to_string())?;
        let start = Instant::now();
        let mesh = &self.mesh;
        self.tris
            .par_iter_mut()
            .zip(&self.prims)
            .for_each(|(t, &p)| *t = mesh.triangle(p));
        refit_wide(&mut self.nodes, &self.tris, 0);
        Ok(start.elapsed().as_secs_f64())
    }

    /// Bytes of the built structure: nodes, triangles copied into leaf order, and their ids.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice())
            + std::mem::size_of_val(self.tris.as_slice())
            + std::mem::size_of_val(self.prims.as_slice())
    }

    /// Wide nodes (each with up to four children).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Wide nodes on the longest path from the root to a leaf (a lone leaf has depth 1).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Whether anything lies on the ray within `[tnear, tfar]`; stops at the first hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.admit(ray) && self.traverse::<true>(ray).is_some()
    }

    /// Whether `ray` can be traversed; counts the ones that cannot.
    #[inline]
    fn admit(&self, ray: &Ray) -> bool {
        let ok = ray.is_finite();
        if !ok {
            self.rejected.fetch_add(1, Ordering::Relaxed);
        }
        ok
    }

    /// Checks the structure: every triangle in exactly one leaf, leaves of 1 to [`MAX_LEAF`]
    /// triangles, every lane's box enclosing its child's boxes or triangles and an empty lane's
    /// box empty, children stored after their parents, the depth recorded (which sizes the
    /// traversal stack) the tree's. For tests.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = vec![false; self.tris.len()];
        let mut todo = vec![(0usize, 1usize)];
        let (mut deepest, mut visited) = (0, 0);
        let inside = |(lo, hi): ([f32; 3], [f32; 3]), p: [f32; 3], q: [f32; 3]| {
            (0..3).all(|k| lo[k] <= p[k] && q[k] <= hi[k])
        };
        while let Some((i, depth)) = todo.pop() {
            deepest = deepest.max(depth);
            visited += 1;
            let w = &self.nodes[i];
            for l in 0..LANES {
                let (index, count, lane) = (w.index[l], w.count[l], w.lane(l));
                if index == Wide::NONE {
                    if count != 0 || lane != Wide::EMPTY.lane(0) {
                        return Err(format!("empty lane {l} of node {i} is not empty"));
                    }
                } else if count == 0 {
                    let c = index as usize;
                    if c <= i || c >= self.nodes.len() {
                        return Err(format!("node {i} has a child at {c}"));
                    }
                    let child = &self.nodes[c];
                    if child.index.iter().all(|&m| m == Wide::NONE) {
                        return Err(format!("node {c} has no children"));
                    }
                    for m in (0..LANES).filter(|&m| child.index[m] != Wide::NONE) {
                        let (lo, hi) = child.lane(m);
                        if !inside(lane, lo, hi) {
                            return Err(format!("lane {m} of node {c} sticks out of node {i}"));
                        }
                    }
                    todo.push((c, depth + 1));
                } else {
                    if count as usize > MAX_LEAF {
                        return Err(format!("a leaf of node {i} holds {count} triangles"));
                    }
                    for t in (index as usize..).take(count as usize) {
                        if t >= self.tris.len() || std::mem::replace(&mut seen[t], true) {
                            return Err(format!("triangle slot {t} is in two leaves or none"));
                        }
                        if self.tris[t] != self.mesh.triangle(self.prims[t]) {
                            return Err(format!("triangle slot {t} is not a copy of its prim"));
                        }
                        if self.tris[t].iter().any(|&v| !inside(lane, v, v)) {
                            return Err(format!("triangle slot {t} sticks out of node {i}"));
                        }
                    }
                }
            }
        }
        let mut ids = self.prims.clone();
        ids.sort_unstable();
        if seen.iter().any(|s| !s) || ids.iter().enumerate().any(|(i, &p)| p as usize != i) {
            return Err("leaves do not hold each triangle exactly once".into());
        }
        if deepest != self.depth {
            return Err(format!("depth {} recorded, {deepest} walked", self.depth));
        }
        // Children are stored after their parents (checked above), so a node reached twice
        // would need two parents; one never reached is garbage.
        if visited != self.nodes.len() {
            return Err(format!("{visited} of {} nodes reachable", self.nodes.len()));
        }
        Ok(())
    }
}

/// Recomputes the lanes' boxes of wide node `i` and everything under it; returns their union.
fn refit_wide(nodes: &mut [Wide], tris: &[[[f32; 3]; 3]], i: usize) -> layout::Aabb {
    let mut all = layout::Aabb::EMPTY;
    for l in 0..LANES {
        let (index, count) = (nodes[i].index[l], nodes[i].count[l]);
        if index == Wide::NONE {
            continue;
        }
        let b = if count == 0 {
            refit_wide(nodes, tris, index as usize)
        } else {
            let mut b = layout::Aabb::EMPTY;
            for t in &tris[index as usize..index as usize + count as usize] {
                t.iter().for_each(|&v| b.grow(v));
            }
            b
        };
        nodes[i].set(l, b.corners(), index, count);
        all.join(&b);
    }
    all
}

impl Accel for Bvh {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.admit(ray) {
            return None;
        }
        self.traverse::<false>(ray)
    }

    fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    fn name(&self) -> &'static str {
        "rust"
    }

    fn rejected_rays(&self) -> u64 {
        self.rejected.load(Ordering::Relaxed)
    }

    fn bytes(&self) -> u64 {
        Bvh::bytes(self) as u64
    }

    fn update_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<f64, String> {
        self.refit(positions, normals)
    }
}

/// A tree over boxes whose primitives the caller tests: the same build and walk as [`Bvh`]'s,
/// for primitives that are not triangles (the exact surface's prisms).
pub struct BoxTree {
    nodes: Vec<Wide>,
    /// Primitive index of each leaf-order slot.
    ids: Vec<u32>,
    depth: usize,
}

impl BoxTree {
    /// Builds the tree over `boxes` (primitive `i` is `boxes[i]`, lower and upper corner) on
    /// the current rayon pool.
    pub fn build(boxes: &[([f32; 3], [f32; 3])]) -> BoxTree {
        use rayon::prelude::*;
        assert!(
            !boxes.is_empty() && boxes.len() < Wide::NONE as usize,
            "a box tree holds 1 to 2^32 - 2 boxes"
        );
        let build::Built { nodes, ids, depth } = build::build_over(boxes.par_iter().map(|b| {
            let mut a = layout::Aabb::EMPTY;
            a.grow(b.0);
            a.grow(b.1);
            a
        }));
        BoxTree { nodes, ids, depth }
    }

    /// The closest hit along `ray` within `[tnear, tfar]`: `test(prim, tmax)` answers for one
    /// primitive whose box the ray meets, with `(t, u, v)` for a hit at `t <= tmax`.
    pub fn closest(
        &self,
        ray: &Ray,
        mut test: impl FnMut(u32, f32) -> Option<(f32, f32, f32)>,
    ) -> Option<Hit> {
        let p = traverse::Prepared::new(ray)?;
        let found = traverse::walk::<false>(
            &self.nodes,
            self.depth,
            &p,
            ray.tfar,
            |first, count, tmax| {
                let mut best = None;
                let mut tmax = tmax;
                for slot in first..first + count {
                    if let Some((t, u, v)) = test(self.ids[slot], tmax) {
                        tmax = t;
                        best = Some((slot, t, u, v));
                    }
                }
                best
            },
        );
        found.map(|(slot, t, u, v)| Hit {
            t,
            prim: self.ids[slot],
            u,
            v,
        })
    }

    /// Bytes of the nodes and ids.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes.as_slice()) + std::mem::size_of_val(self.ids.as_slice())
    }
}

#[cfg(test)]
mod tests {
    use super::layout::Wide;
    use super::traverse::Prepared;
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
        // Leaves of up to 4 triangles over 30 000 triangles: at least 7 500 leaves, which take
        // (7 500 - 1) / 3 nodes of four children at least.
        assert!(bvh.node_count() >= 2_500, "{}", bvh.node_count());
        // The collapse fills the lanes: without it every node would hold two children.
        let lanes = bvh
            .nodes
            .iter()
            .flat_map(|w| w.index)
            .filter(|&i| i != Wide::NONE);
        let per_node = lanes.count() as f64 / bvh.node_count() as f64;
        assert!(per_node > 2.5, "{per_node} children per node");
        assert!(bvh.depth() < 20, "depth {}", bvh.depth());
        assert!(bvh.build_seconds() > 0.0);
    }

    #[test]
    fn refit_moves_the_boxes_with_the_vertices() {
        let mut bvh = Bvh::build(Arc::new(Mesh::grid(40, 30, 0.5)));
        let lift = |p: &[f32; 3]| [p[0], p[1] + 3.0 + 0.1 * p[0], p[2]];
        let moved: Vec<[f32; 3]> = bvh.mesh.positions().iter().map(lift).collect();
        let normals = bvh.mesh.normals().to_vec();
        bvh.refit(&moved, &normals).unwrap();
        bvh.validate().unwrap();
        // A ray down through the raised sheet meets it where it now is.
        let ray = Ray::new([5.3, 20.0, 4.1], [0.0, -1.0, 0.0]);
        let h = bvh.intersect(&ray).expect("hit");
        assert!((h.t - (20.0 - (3.0 + 0.53))).abs() < 1e-4, "{h:?}");
    }

    #[test]
    fn slab_ignores_nan_from_rays_in_a_slab_plane() {
        // A flat box in y = 0 in lane 1 and rays running exactly along its faces, with -0
        // components; the other lanes are empty and must never be entered.
        let mut n = Wide::EMPTY;
        n.set(1, ([0.0, 0.0, 0.0], [1.0, 0.0, 1.0]), 0, 1);
        for (org, dir) in [
            ([0.0, 1.0, 0.5], [-0.0, -1.0, 0.0]),
            ([1.0, 1.0, 1.0], [0.0, -1.0, -0.0]),
            ([-1.0, 0.0, 0.0], [1.0, -0.0, 0.0]),
            ([0.5, 0.0, 2.0], [-0.0, 0.0, -1.0]),
            ([0.5, 0.0, 2.0], [-0.0, -0.0, -1.0]),
        ] {
            let p = Prepared::new(&Ray::new(org, dir)).unwrap();
            assert_eq!(p.slabs(&n, f32::INFINITY).1, 0b10, "{org:?} {dir:?}");
        }
        let p = Prepared::new(&Ray::new([1.5, 1.0, 0.5], [0.0, -1.0, 0.0])).unwrap();
        assert_eq!(p.slabs(&n, f32::INFINITY).1, 0);
        // Stopping short of the box misses it too.
        let p = Prepared::new(&Ray::new([0.5, 1.0, 0.5], [0.0, -1.0, 0.0])).unwrap();
        assert_eq!(p.slabs(&n, 0.5).1, 0);
        assert_eq!(p.slabs(&n, 1.0).1, 0b10);
    }
}
