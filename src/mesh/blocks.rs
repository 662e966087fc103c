//! Blocks of whole grid cells that a tracer may read as grids instead of triangles: Embree's
//! grid geometry (`RTC_GEOMETRY_TYPE_GRID`) builds its BVH over 2 x 2-cell patches of a vertex
//! grid, an eighth as many primitives as the cells' triangles and no index buffer, so
//! paper-high's 22.3 M triangles build 8x faster in less memory (docs/performance.md,
//! "Grids").
//!
//! A block is `rows` rows of `cells` cells. Its top row of vertices (the largest z) is
//! `start, start + 1, ..., start + cells`, each row below it `stride` vertices further on. Cell
//! q of block row r has the two triangles `t + 2q`, the half holding the cell's lower-right
//! corner, and `t + 2q + 1`, the half holding its upper-left, where t is the row's entry in
//! the mesh's block-row table; both are split along the diagonal from the lower-left to the
//! upper-right corner, as Embree splits a grid's quads when the grid's rows run down in z.
//! [`Mesh::with_blocks`] checks every block's triangles against this layout.

use super::{Mesh, MeshError};

/// Cells along either side of a block, at most. Embree reports where on a grid a ray hit as two
/// f32 across the whole grid, so a block n cells wide loses log2(n) bits of the position within
/// its cell: at 64 cells the barycentrics are good to some 4e-6 of a cell, below the rounding
/// of the hit point's own coordinates that the renderer's offsets already cover.
pub const MAX_BLOCK_CELLS: u16 = 64;

/// Rows of whole cells, read as a grid of (rows + 1) x (cells + 1) vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    /// The top row's first vertex.
    pub start: u32,
    /// From a vertex to the one below it.
    pub stride: u32,
    /// Cells across, 1 to [`MAX_BLOCK_CELLS`].
    pub cells: u16,
    /// Rows of cells, 1 to [`MAX_BLOCK_CELLS`].
    pub rows: u16,
    /// Where the block's rows begin in the mesh's block-row table (its top row first).
    pub first_row: u32,
}

impl Block {
    /// The two triangles of cell q in block row r as the mesh must hold them: lower-right half
    /// (lower-left, upper-right, lower-right corner) and upper-left half (lower-left,
    /// upper-left, upper-right).
    fn triangles(&self, r: u32, q: u32) -> [[u32; 3]; 2] {
        let up = self.start + r * self.stride + q;
        let low = up + self.stride;
        [[low, up + 1, low + 1], [low, up, up + 1]]
    }
}

impl Mesh {
    /// The mesh, with `blocks` saying which of its triangles form grids and `rows` the first
    /// triangle of each block row (checked against the layout of [`Block`]).
    pub fn with_blocks(mut self, blocks: Vec<Block>, rows: Vec<u32>) -> Result<Mesh, MeshError> {
        use rayon::prelude::*;
        let (tris, verts) = (self.indices.len() as u64, self.positions.len() as u64);
        let indices = &self.indices;
        let fits = |b: &Block| {
            let (cells, nrows) = (u64::from(b.cells), u64::from(b.rows));
            if !(1..=MAX_BLOCK_CELLS).contains(&b.cells)
                || !(1..=MAX_BLOCK_CELLS).contains(&b.rows)
                || u64::from(b.stride) <= cells
                || u64::from(b.first_row) + nrows > rows.len() as u64
                || u64::from(b.start) + u64::from(b.stride) * nrows + cells >= verts
            {
                return false;
            }
            (0..u32::from(b.rows)).all(|r| {
                let first = u64::from(rows[(b.first_row + r) as usize]);
                first + 2 * cells <= tris
                    && (0..u32::from(b.cells)).all(|q| {
                        let t = (first + 2 * u64::from(q)) as usize;
                        indices[t..t + 2] == b.triangles(r, q)
                    })
            })
        };
        // (a paper-high mesh's 22 M triangles, read once, on every core)
        if let Some(i) = blocks.par_iter().position_first(|b| !fits(b)) {
            return Err(MeshError::BadBlock(i));
        }
        self.blocks = blocks;
        self.block_rows = rows;
        Ok(self)
    }

    /// The blocks of whole cells that may be traced as grids (none for most meshes).
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// The first triangle of each block row (see [`Block::first_row`]).
    pub fn block_rows(&self) -> &[u32] {
        &self.block_rows
    }

    /// A hit on block `block` reported as a grid's (u across its cells, v down its rows, each 0
    /// to 1 over the whole block) as the mesh's triangle and its barycentrics (those of the
    /// triangle's second and third vertex, as a triangle hit reports them).
    #[inline]
    pub fn block_hit(&self, block: u32, u: f32, v: f32) -> (u32, f32, f32) {
        let b = &self.blocks[block as usize];
        let (q, fx) = cell_of(u, b.cells);
        // v runs down the block, from its top row (the cells' larger z)
        let (r, fy) = cell_of(v, b.rows);
        let fz = 1.0 - fy;
        let first = self.block_rows[(b.first_row + r) as usize] + 2 * q;
        if fx >= fz {
            // lower-right half: (fx, fz) = b1 (1, 1) + b2 (1, 0)
            (first, fz, fx - fz)
        } else {
            // upper-left half: (fx, fz) = b1 (0, 1) + b2 (1, 1)
            (first + 1, fz - fx, fx)
        }
    }
}

/// The cell and the position within it (0 to 1) of `t` in [0, 1] across `n` cells.
#[inline]
fn cell_of(t: f32, n: u16) -> (u32, f32) {
    let n_f = f32::from(n);
    let x = (t * n_f).clamp(0.0, n_f);
    let i = (x as u32).min(u32::from(n) - 1);
    (i, (x - i as f32).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 x 4 grid of cells (x by z), rows numbered from the top, triangles as the doubling
    /// tessellation emits them row by row from the bottom, and blocks: the top two rows whole,
    /// then the bottom two rows' first two cells.
    fn grid() -> (Mesh, Vec<Block>, Vec<u32>) {
        let (nx, nz) = (3u32, 4u32);
        let mut positions = Vec::new();
        for z in (0..=nz).rev() {
            for x in 0..=nx {
                positions.push([x as f32, 0.1 * (x * z) as f32, z as f32]);
            }
        }
        let at = |x: u32, z: u32| (nz - z) * (nx + 1) + x;
        let mut indices = Vec::new();
        let mut row_first = Vec::new();
        for j in 0..nz {
            row_first.push(indices.len() as u32);
            for i in 0..nx {
                indices.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
                indices.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            }
        }
        let mesh = Mesh::new(positions, vec![], vec![], indices).unwrap();
        // the block-row table, each block's rows from its top
        let rows = vec![row_first[3], row_first[2], row_first[1], row_first[0]];
        let blocks = vec![
            Block {
                start: at(0, 4),
                stride: nx + 1,
                cells: 3,
                rows: 2,
                first_row: 0,
            },
            Block {
                start: at(0, 2),
                stride: nx + 1,
                cells: 2,
                rows: 2,
                first_row: 2,
            },
        ];
        (mesh, blocks, rows)
    }

    #[test]
    fn blocks_that_match_their_triangles_are_kept_and_others_refused() {
        let (mesh, blocks, rows) = grid();
        let m = mesh
            .clone()
            .with_blocks(blocks.clone(), rows.clone())
            .unwrap();
        assert_eq!(m.blocks(), &blocks[..]);
        let b = blocks[1];
        let broken = [
            Block { cells: 0, ..b },
            Block { rows: 0, ..b },
            Block {
                cells: MAX_BLOCK_CELLS + 1,
                ..b
            },
            Block { stride: 2, ..b },
            Block {
                start: b.start + 1,
                ..b
            },
            Block { first_row: 1, ..b },
            Block { first_row: 3, ..b },
            Block { rows: 3, ..b },
        ];
        for (k, broken) in broken.into_iter().enumerate() {
            assert_eq!(
                mesh.clone()
                    .with_blocks(vec![blocks[0], broken], rows.clone())
                    .err(),
                Some(MeshError::BadBlock(1)),
                "case {k}"
            );
        }
    }

    /// A point given by its place on a block, as Embree reports a grid hit, is the same point
    /// of the triangle and barycentrics the block's hit names.
    #[test]
    fn a_block_hit_names_the_triangle_and_barycentrics_of_the_same_point() {
        let (mesh, blocks, rows) = grid();
        let mesh = mesh.with_blocks(blocks, rows).unwrap();
        for (i, b) in mesh.blocks().iter().enumerate() {
            let top = mesh.positions()[b.start as usize][2];
            for k in 0..300 {
                let h = crate::rng::splitmix64(k);
                let (u, v) = ((h & 0xFFFF) as f32 / 65535.0, (h >> 48) as f32 / 65535.0);
                let (tri, b1, b2) = mesh.block_hit(i as u32, u, v);
                assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6, "{b1} {b2}");
                // the point on the block's own layout: x across, z down from its top row
                let want = [u * f32::from(b.cells), top - v * f32::from(b.rows)];
                let p = Mesh::interpolate(mesh.positions(), mesh.indices()[tri as usize], b1, b2);
                assert!(
                    (p[0] - want[0]).abs() < 1e-5 && (p[2] - want[1]).abs() < 1e-5,
                    "block {i} at ({u}, {v}): {p:?} against {want:?}"
                );
            }
        }
    }
}
