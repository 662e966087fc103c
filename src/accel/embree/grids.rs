//! A tessellation's blocks of whole cells handed to Embree as grids (`RTC_GEOMETRY_TYPE_GRID`,
//! [`BuildOptions::grids`]), the triangles outside them as triangles, and grid hits turned back
//! into the mesh's triangle hits.

use std::ffi::c_void;
use std::ptr::NonNull;

use super::scene::{attach_triangles, returned};
use super::{BuildOptions, Device, EmbreeError, ffi};
use crate::mesh::Mesh;

/// A mesh handed to Embree as grids and the triangles outside them.
pub(super) struct Split {
    /// The grid geometry's id (the scene's `geometry` is its handle).
    pub(super) grids: u32,
    /// The other triangles' geometry, if any: its handle and id.
    pub(super) rest: Option<(NonNull<c_void>, u32)>,
    /// Each of the other geometry's primitives' triangle in the mesh.
    pub(super) rest_prims: Vec<u32>,
    /// That geometry's index buffer (theirs in that order), kept alive for Embree, which
    /// shares it.
    _rest_indices: Vec<[u32; 3]>,
}

/// Attaches `mesh`'s blocks as one grid geometry and its other triangles as a triangle geometry
/// to `scene`: the grid geometry's handle, and the [`Split`] that maps their hits back.
pub(super) fn attach(
    device: &Device,
    scene: NonNull<c_void>,
    options: BuildOptions,
    mesh: &Mesh,
) -> Result<(NonNull<c_void>, Option<Split>), EmbreeError> {
    let (rest_prims, rest_indices) = outside_blocks(mesh);
    let rest = if rest_prims.is_empty() {
        None
    } else {
        // SAFETY: the indices are the mesh's own (validated), its positions padded; the mesh
        // outlives the scene in the Scene's Arc, and `rest_indices` moves into the Split with
        // its heap buffer unchanged.
        Some(unsafe {
            attach_triangles(
                device,
                scene,
                options,
                mesh,
                &rest_indices,
                std::ptr::null(),
            )
        }?)
    };
    let grids: Vec<ffi::vo_grid> = mesh
        .blocks()
        .iter()
        .map(|b| ffi::vo_grid {
            start: b.start,
            stride: b.stride,
            width: b.cells + 1,
            height: b.rows + 1,
        })
        .collect();
    let mut geom_id = 0u32;
    // SAFETY: the blocks were checked against the mesh (every vertex they name exists); its
    // positions are padded and outlive the scene; the grids are copied.
    let g = unsafe {
        ffi::vo_scene_attach_grids(
            device.raw.as_ptr(),
            scene.as_ptr(),
            options.quality.raw(),
            mesh.positions().as_ptr() as *const f32,
            mesh.vertex_count(),
            grids.as_ptr(),
            grids.len(),
            &mut geom_id,
        )
    };
    device.check("rtcAttachGeometry (grids)")?;
    let split = Split {
        grids: geom_id,
        rest,
        rest_prims,
        _rest_indices: rest_indices,
    };
    Ok((returned(g)?, Some(split)))
}

impl Split {
    /// The mesh's (triangle, u, v) for Embree's hit on geometry `geom`, primitive `prim`.
    #[inline]
    pub(super) fn hit(&self, mesh: &Mesh, geom: u32, prim: u32, u: f32, v: f32) -> (u32, f32, f32) {
        if geom == self.grids {
            mesh.block_hit(prim, u, v)
        } else {
            (self.rest_prims[prim as usize], u, v)
        }
    }
}

/// The triangles of `mesh` in none of its blocks: their indices in the mesh, and their
/// vertices.
fn outside_blocks(mesh: &Mesh) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut covered = vec![false; mesh.triangle_count()];
    for b in mesh.blocks() {
        let rows = &mesh.block_rows()[b.first_row as usize..][..usize::from(b.rows)];
        for &first in rows {
            let first = first as usize;
            covered[first..first + 2 * usize::from(b.cells)].fill(true);
        }
    }
    let prims: Vec<u32> = (0..mesh.triangle_count() as u32)
        .filter(|&t| !covered[t as usize])
        .collect();
    let indices = prims.iter().map(|&t| mesh.indices()[t as usize]).collect();
    (prims, indices)
}
