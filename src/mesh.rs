//! Triangle meshes as the tracers consume them: camera-relative positions, per-vertex normals,
//! texture coordinates (the nominal horizontal position of each vertex, paper section 2) and
//! u32 triangle indices.
//!
//! A [`Mesh`] is validated once, when it is made (finite positions, indices in range, at least
//! one triangle), and is immutable afterwards. Its position and texture-coordinate allocations
//! are padded past the last element, because Embree reads vertex buffers with 16-byte loads and
//! shares them with the caller instead of copying them.
//!
//! [`write_ply`] exports a mesh as binary PLY for Blender and MeshLab.

use thiserror::Error;

mod blocks;
pub use blocks::{Block, MAX_BLOCK_CELLS};

use crate::image_io::{WriteError, write_atomically};

#[derive(Debug, Error, PartialEq)]
pub enum MeshError {
    #[error("mesh has no triangles")]
    Empty,
    #[error("mesh has {positions} positions but {what} has {len} entries")]
    LengthMismatch {
        positions: usize,
        what: &'static str,
        len: usize,
    },
    #[error("vertex {index} has a non-finite position {value:?}")]
    NonFinite { index: usize, value: [f32; 3] },
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertices: usize,
    },
    #[error("mesh has {0} vertices; indices are u32, so at most 4294967295")]
    TooManyVertices(usize),
    #[error("block {0} does not match the mesh's triangles")]
    BadBlock(usize),
}

/// An immutable, validated triangle mesh. Fields are private so the padding and validation
/// invariants cannot be broken after construction.
#[derive(Debug, Clone)]
pub struct Mesh {
    positions: Padded<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Padded<[f32; 2]>,
    indices: Vec<[u32; 3]>,
    /// Blocks of whole cells that may be traced as grids ([`Block`]; empty for most meshes),
    /// and the first triangle of each of their rows.
    blocks: Vec<Block>,
    block_rows: Vec<u32>,
}

/// A buffer whose allocation holds at least one initialised element past its length, so a
/// 16-byte load of the last element (12-byte float3 or 8-byte float2) stays inside it. The
/// padding is a property of the type: it survives `Clone` (a plain `Vec` clone drops spare
/// capacity).
#[derive(Debug)]
struct Padded<T>(Vec<T>);

impl<T: Copy + Default> Padded<T> {
    fn new(mut v: Vec<T>) -> Padded<T> {
        v.reserve_exact(1);
        v.push(T::default());
        v.pop();
        Padded(v)
    }
}

impl<T: Copy + Default> Clone for Padded<T> {
    fn clone(&self) -> Padded<T> {
        let mut v = Vec::with_capacity(self.0.len() + 1);
        v.extend_from_slice(&self.0);
        Padded::new(v)
    }
}

impl<T> std::ops::Deref for Padded<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.0
    }
}

impl Mesh {
    /// Validates and takes ownership of the buffers. `normals` and `uvs` may be empty (no such
    /// attribute); otherwise they must have one entry per position.
    pub fn new(
        positions: Vec<[f32; 3]>,
        normals: Vec<[f32; 3]>,
        uvs: Vec<[f32; 2]>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Mesh, MeshError> {
        if indices.is_empty() {
            return Err(MeshError::Empty);
        }
        let n = positions.len();
        if n > u32::MAX as usize {
            return Err(MeshError::TooManyVertices(n));
        }
        for (what, len) in [("normals", normals.len()), ("uvs", uvs.len())] {
            if len != 0 && len != n {
                return Err(MeshError::LengthMismatch {
                    positions: n,
                    what,
                    len,
                });
            }
        }
        if let Some(index) = positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite {
                index,
                value: positions[index],
            });
        }
        for (triangle, tri) in indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: n,
                });
            }
        }
        Ok(Mesh {
            positions: Padded::new(positions),
            normals,
            uvs: Padded::new(uvs),
            indices,
            blocks: Vec::new(),
            block_rows: Vec::new(),
        })
    }

    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// Replaces the vertex positions in place (same count, same topology; the allocation and
    /// its padding stay, so a BVH sharing the buffer can be refitted). Checked first: on a
    /// wrong count or a non-finite position nothing changes.
    pub fn set_positions(&mut self, new: &[[f32; 3]]) -> Result<(), MeshError> {
        self.check_positions(new)?;
        self.positions.0.copy_from_slice(new);
        Ok(())
    }

    /// Replaces positions and vertex normals together (an animation frame); checked first as
    /// [`Mesh::set_positions`], and the normals must match in count.
    pub fn set_vertices(
        &mut self,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
    ) -> Result<(), MeshError> {
        self.check_positions(positions)?;
        if normals.len() != self.normals.len() {
            return Err(MeshError::LengthMismatch {
                positions: self.positions.len(),
                what: "new normals",
                len: normals.len(),
            });
        }
        self.positions.0.copy_from_slice(positions);
        self.normals.copy_from_slice(normals);
        Ok(())
    }

    fn check_positions(&self, new: &[[f32; 3]]) -> Result<(), MeshError> {
        if new.len() != self.positions.len() {
            return Err(MeshError::LengthMismatch {
                positions: self.positions.len(),
                what: "new positions",
                len: new.len(),
            });
        }
        if let Some(index) = new.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(MeshError::NonFinite {
                index,
                value: new[index],
            });
        }
        Ok(())
    }
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }
    pub fn uvs(&self) -> &[[f32; 2]] {
        &self.uvs
    }
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The three corner positions of triangle `prim`.
    #[inline]
    pub fn triangle(&self, prim: u32) -> [[f32; 3]; 3] {
        let [a, b, c] = self.indices[prim as usize];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// A flat regular grid in the y = 0 plane: `nx` x `nz` square cells of side `cell` metres,
    /// two triangles per cell, starting at the origin; texture coordinate = (x, z), normal +y.
    /// Winding is counter-clockwise seen from above, so Embree's geometric normal points up.
    pub fn grid(nx: u32, nz: u32, cell: f32) -> Mesh {
        let (vx, vz) = (nx + 1, nz + 1);
        let mut positions = Vec::with_capacity((vx * vz) as usize);
        let mut uvs = Vec::with_capacity((vx * vz) as usize);
        for j in 0..vz {
            for i in 0..vx {
                let (x, z) = (i as f32 * cell, j as f32 * cell);
                positions.push([x, 0.0, z]);
                uvs.push([x, z]);
            }
        }
        let mut indices = Vec::with_capacity(2 * (nx * nz) as usize);
        for j in 0..nz {
            for i in 0..nx {
                let a = j * vx + i;
                let (b, c, d) = (a + 1, a + vx + 1, a + vx);
                indices.push([a, c, b]);
                indices.push([a, d, c]);
            }
        }
        let normals = vec![[0.0, 1.0, 0.0]; positions.len()];
        Mesh::new(positions, normals, uvs, indices).expect("a grid is a valid mesh")
    }

    /// Bytes held by the buffers (what a tessellation costs in memory).
    pub fn bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(&*self.positions)
            + size_of_val(self.normals.as_slice())
            + size_of_val(&*self.uvs)
            + size_of_val(self.indices.as_slice())
            + size_of_val(self.blocks.as_slice())
            + size_of_val(self.block_rows.as_slice())
    }

    /// Whether the position and uv allocations extend past their last element (see module doc).
    pub fn is_padded(&self) -> bool {
        self.positions.0.capacity() > self.positions.len()
            && (self.uvs.is_empty() || self.uvs.0.capacity() > self.uvs.len())
    }

    /// Interpolates a per-vertex attribute with Embree's barycentric convention:
    /// value = (1-u-v)·a + u·b + v·c.
    #[inline]
    pub fn interpolate<const N: usize>(
        attr: &[[f32; N]],
        tri: [u32; 3],
        u: f32,
        v: f32,
    ) -> [f32; N] {
        let w = 1.0 - u - v;
        let (a, b, c) = (
            attr[tri[0] as usize],
            attr[tri[1] as usize],
            attr[tri[2] as usize],
        );
        std::array::from_fn(|i| w * a[i] + u * b[i] + v * c[i])
    }
}

/// Writes `mesh` as binary little-endian PLY (Blender and MeshLab read it): per vertex
/// `x y z`, then `nx ny nz` and the texture coordinate as `s t` when the mesh has them, and
/// faces as a `uchar` count plus `uint` indices. Written atomically.
pub fn write_ply(mesh: &Mesh, path: &std::path::Path) -> Result<(), WriteError> {
    use std::io::Write;
    write_atomically(path, |w| {
        let (normals, uvs) = (!mesh.normals.is_empty(), !mesh.uvs.is_empty());
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment vastocean mesh: x z relative to the \
             camera, y above mean sea level under it, y up; s t = nominal horizontal position \
             (x, z), m\nelement vertex {}\n\
             property float x\nproperty float y\nproperty float z\n",
            mesh.vertex_count()
        )?;
        if normals {
            w.write_all(b"property float nx\nproperty float ny\nproperty float nz\n")?;
        }
        if uvs {
            w.write_all(b"property float s\nproperty float t\n")?;
        }
        write!(
            w,
            "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            mesh.triangle_count()
        )?;
        for (i, p) in mesh.positions.iter().enumerate() {
            for c in p {
                w.write_all(&c.to_le_bytes())?;
            }
            if normals {
                for c in &mesh.normals[i] {
                    w.write_all(&c.to_le_bytes())?;
                }
            }
            if uvs {
                for c in &mesh.uvs[i] {
                    w.write_all(&c.to_le_bytes())?;
                }
            }
        }
        for t in &mesh.indices {
            w.write_all(&[3])?;
            for i in t {
                w.write_all(&i.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn rejects_bad_input_with_named_cause() {
        let (p, i) = quad();
        assert_eq!(
            Mesh::new(p.clone(), vec![], vec![], vec![]).unwrap_err(),
            MeshError::Empty
        );
        let mut bad = p.clone();
        bad[2][1] = f32::NAN;
        assert!(matches!(
            Mesh::new(bad, vec![], vec![], i.clone()),
            Err(MeshError::NonFinite { index: 2, .. })
        ));
        assert_eq!(
            Mesh::new(p.clone(), vec![], vec![], vec![[0, 1, 4]]).unwrap_err(),
            MeshError::IndexOutOfRange {
                triangle: 0,
                index: 4,
                vertices: 4
            }
        );
        assert!(matches!(
            Mesh::new(p, vec![], vec![[0.0; 2]; 3], i),
            Err(MeshError::LengthMismatch {
                what: "uvs",
                len: 3,
                ..
            })
        ));
    }

    #[test]
    fn buffers_are_padded_for_simd_loads() {
        let (p, i) = quad();
        let m = Mesh::new(p, vec![], vec![[0.0; 2]; 4], i).unwrap();
        assert!(m.is_padded());
        assert_eq!(m.vertex_count(), 4);
        assert!(m.clone().is_padded(), "padding survives Clone");
    }

    #[test]
    fn interpolation_matches_embree_convention() {
        let attr = [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(Mesh::interpolate(&attr, [0, 1, 2], 0.25, 0.5), [0.25, 0.5]);
    }
}
