//! Collapsing a binary tree into 4-wide nodes, as Embree's BVH4 and psychopath's bvh4 do: a
//! wide node starts from a binary node's two children and keeps opening the child with the
//! largest surface area (the one a ray is likeliest to enter) until it holds four or only
//! leaves are left. Wide nodes are written depth first, a node's children after it.
//!
//! The build collapses each subtree it made on one thread right away, while its binary nodes
//! are still in cache ([`collapse`]); collapsing the whole binary tree afterwards cost a cache
//! miss per node and took 2.2 s for paper-high's 22 M triangles. The few nodes above those
//! subtrees are collapsed the same way by [`super::build`].

use super::layout::{Aabb, LANES, Node, Wide};

/// The wide nodes (root first, indices relative to it) of the binary tree `nodes` (root 0, an
/// inner node's children at `index` and `index + 1`), and their depth: wide nodes on the
/// longest path from the root to a leaf. The root must be an inner node.
pub(super) fn collapse(nodes: &[Node]) -> (Vec<Wide>, usize) {
    debug_assert!(nodes[0].count == 0, "a leaf has nothing to collapse");
    // m inner nodes (nodes.len() = 2m + 1) become at most m wide ones, about m / 2 on ocean
    // meshes; the upper bound, since this is a subtree's small scratch vector.
    let mut wide = Vec::with_capacity(nodes.len() / 2 + 1);
    wide.push(Wide::EMPTY);
    let depth = fill(nodes, 0, &mut wide, 0);
    (wide, depth)
}

/// Up to four children for a wide node, starting from `first` and opening, while there is room,
/// the inner child whose box has the largest area. `area` is `None` for a child that cannot
/// be opened (a leaf), `open` gives an inner child's two children.
pub(super) fn widen<T: Copy>(
    first: [T; 2],
    area: impl Fn(T) -> Option<f32>,
    open: impl Fn(T) -> [T; 2],
) -> ([T; LANES], usize) {
    let mut kids = [first[0]; LANES];
    kids[1] = first[1];
    let mut n = 2;
    while n < LANES {
        let largest = (0..n)
            .filter_map(|j| area(kids[j]).map(|a| (j, a)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((j, _)) = largest else { break };
        [kids[j], kids[n]] = open(kids[j]);
        n += 1;
    }
    (kids, n)
}

fn half_area(n: &Node) -> f32 {
    let mut b = Aabb::EMPTY;
    b.grow(n.lo);
    b.grow(n.hi);
    b.half_area()
}

/// Fills wide node `slot` from binary inner node `i`; returns the depth of the wide subtree.
fn fill(nodes: &[Node], i: usize, wide: &mut Vec<Wide>, slot: usize) -> usize {
    let c = nodes[i].index as usize;
    let (kids, n) = widen(
        [c, c + 1],
        |k| (nodes[k].count == 0).then(|| half_area(&nodes[k])),
        |k| {
            let g = nodes[k].index as usize;
            [g, g + 1]
        },
    );
    let mut below = 0;
    for (lane, &k) in kids[..n].iter().enumerate() {
        let child = &nodes[k];
        if child.count > 0 {
            wide[slot].set(lane, (child.lo, child.hi), child.index, child.count);
        } else {
            let s = wide.len();
            wide.push(Wide::EMPTY);
            wide[slot].set(lane, (child.lo, child.hi), s as u32, 0);
            below = below.max(fill(nodes, k, wide, s));
        }
    }
    1 + below
}
