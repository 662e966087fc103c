//! Rows of whole grid cells that a tracer may read as grids instead of triangles: Embree's grid
//! geometry (`RTC_GEOMETRY_TYPE_GRID`) builds its BVH over patches of a vertex grid, a quarter
//! as many primitives as the cells' triangles and no index buffer, so paper-high's 22.3 M
//! triangles build in a fraction of the time and memory (docs/performance.md).
//!
//! A strip is `cells` cells of one row. Its upper row of vertices (the cells' larger z) is
//! `start, start + 1, ..., start + cells`, its lower row the same plus `stride`. Cell q's two
//! triangles are the mesh's `first_triangle + 2q`, the half holding the lower-right corner,
//! and `+ 1`, the half holding the upper-left; both are split along the diagonal from the
//! lower-left to the upper-right corner, as Embree splits a grid's quads when the grid's rows
//! run down in z. [`Mesh::with_strips`] checks every strip's triangles against this layout.

use super::{Mesh, MeshError};

/// Cells in one strip, at most. Embree reports where on a grid a ray hit as one f32 across the
/// whole grid, so a strip of n cells loses log2(n) bits of the position within its cell: at 64
/// cells the barycentrics are good to some 4e-6 of a cell, below the rounding of the hit
/// point's own coordinates that the renderer's offsets already cover.
pub const MAX_STRIP_CELLS: u16 = 64;

/// A row of whole cells, read as a grid of 2 x (cells + 1) vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strip {
    /// The upper row's first vertex.
    pub start: u32,
    /// From a vertex of the upper row to the one below it.
    pub stride: u32,
    /// Cells in the strip, 1 to [`MAX_STRIP_CELLS`].
    pub cells: u16,
    /// The triangle of the first cell's lower-right half.
    pub first_triangle: u32,
}

impl Strip {
    /// The two triangles of cell `q` as the mesh must hold them: lower-right half (lower-left,
    /// upper-right, lower-right corner) and upper-left half (lower-left, upper-left,
    /// upper-right).
    fn triangles(&self, q: u32) -> [[u32; 3]; 2] {
        let (up, low) = (self.start + q, self.start + self.stride + q);
        [[low, up + 1, low + 1], [low, up, up + 1]]
    }
}

impl Mesh {
    /// The mesh, with `strips` saying which of its triangles form grids (checked against the
    /// layout of [`Strip`]).
    pub fn with_strips(mut self, strips: Vec<Strip>) -> Result<Mesh, MeshError> {
        let (tris, verts) = (self.indices.len() as u64, self.positions.len() as u64);
        for (i, s) in strips.iter().enumerate() {
            let bad = || MeshError::BadStrip(i);
            let cells = u64::from(s.cells);
            if s.cells == 0 || s.cells > MAX_STRIP_CELLS || s.stride <= u32::from(s.cells) {
                return Err(bad());
            }
            if u64::from(s.first_triangle) + 2 * cells > tris
                || u64::from(s.start) + u64::from(s.stride) + cells >= verts
            {
                return Err(bad());
            }
            for q in 0..u32::from(s.cells) {
                let t = (s.first_triangle + 2 * q) as usize;
                if self.indices[t..t + 2] != s.triangles(q) {
                    return Err(bad());
                }
            }
        }
        self.strips = strips;
        Ok(self)
    }

    /// The strips of whole cells that may be traced as grids (none for most meshes).
    pub fn strips(&self) -> &[Strip] {
        &self.strips
    }

    /// A hit on strip `strip` reported as a grid's (u across its cells, v down its two rows,
    /// each 0 to 1 over the whole strip) as the mesh's triangle and its barycentrics (those of
    /// the triangle's second and third vertex, as a triangle hit reports them).
    #[inline]
    pub fn strip_hit(&self, strip: u32, u: f32, v: f32) -> (u32, f32, f32) {
        let s = &self.strips[strip as usize];
        let cells = f32::from(s.cells);
        let x = (u * cells).clamp(0.0, cells);
        let q = (x as u32).min(u32::from(s.cells) - 1);
        let fx = (x - q as f32).clamp(0.0, 1.0);
        // v runs down the strip, from the upper row (the cell's larger z)
        let fz = (1.0 - v).clamp(0.0, 1.0);
        let first = s.first_triangle + 2 * q;
        if fx >= fz {
            // lower-right half: (fx, fz) = b1 (1, 1) + b2 (1, 0)
            (first, fz, fx - fz)
        } else {
            // upper-left half: (fx, fz) = b1 (0, 1) + b2 (1, 1)
            (first + 1, fz - fx, fx)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 x 2 grid of cells, rows numbered from the top, triangles as the doubling
    /// tessellation emits them, one strip per cell row.
    fn grid() -> (Mesh, Vec<Strip>) {
        let (nx, nz) = (3u32, 2u32);
        let mut positions = Vec::new();
        for z in (0..=nz).rev() {
            for x in 0..=nx {
                positions.push([x as f32, 0.1 * (x * z) as f32, z as f32]);
            }
        }
        let at = |x: u32, z: u32| (nz - z) * (nx + 1) + x;
        let (mut indices, mut strips) = (Vec::new(), Vec::new());
        for j in 0..nz {
            strips.push(Strip {
                start: at(0, j + 1),
                stride: nx + 1,
                cells: nx as u16,
                first_triangle: indices.len() as u32,
            });
            for i in 0..nx {
                indices.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
                indices.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            }
        }
        let mesh = Mesh::new(positions, vec![], vec![], indices).unwrap();
        (mesh, strips)
    }

    #[test]
    fn strips_that_match_their_triangles_are_kept_and_others_refused() {
        let (mesh, strips) = grid();
        let m = mesh.clone().with_strips(strips.clone()).unwrap();
        assert_eq!(m.strips(), &strips[..]);
        let broken = [
            Strip {
                cells: 0,
                ..strips[0]
            },
            Strip {
                cells: MAX_STRIP_CELLS + 1,
                ..strips[0]
            },
            Strip {
                stride: 3,
                ..strips[0]
            },
            Strip {
                first_triangle: 1,
                ..strips[0]
            },
            Strip {
                start: strips[0].start + 1,
                ..strips[0]
            },
            Strip {
                first_triangle: 10,
                ..strips[1]
            },
        ];
        for (k, s) in broken.into_iter().enumerate() {
            assert_eq!(
                mesh.clone().with_strips(vec![strips[1], s]).err(),
                Some(MeshError::BadStrip(1)),
                "case {k}"
            );
        }
    }

    /// A point given by its place on a strip, as Embree reports a grid hit, is the same point
    /// of the triangle and barycentrics the strip's hit names.
    #[test]
    fn a_strip_hit_names_the_triangle_and_barycentrics_of_the_same_point() {
        let (mesh, strips) = grid();
        let mesh = mesh.with_strips(strips).unwrap();
        for (s, strip) in mesh.strips().iter().enumerate() {
            let cells = f32::from(strip.cells);
            for k in 0..200 {
                let h = crate::rng::splitmix64(k);
                let (u, v) = ((h & 0xFFFF) as f32 / 65535.0, (h >> 48) as f32 / 65535.0);
                let (tri, b1, b2) = mesh.strip_hit(s as u32, u, v);
                assert!(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6, "{b1} {b2}");
                // the point on the strip's own bilinear layout: x across, z from the upper row
                let z_upper = mesh.positions()[strip.start as usize][2];
                let want = [u * cells, z_upper - v];
                let p = Mesh::interpolate(mesh.positions(), mesh.indices()[tri as usize], b1, b2);
                assert!(
                    (p[0] - want[0]).abs() < 1e-5 && (p[2] - want[1]).abs() < 1e-5,
                    "strip {s} at ({u}, {v}): {p:?} against {want:?}"
                );
            }
        }
    }
}
