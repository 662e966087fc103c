//! The parallel mesh build over the grids of `grid.rs`: vertex indices row by row, vertex
//! attributes (the ocean sampled at every nominal position, placed on the curved earth), the
//! triangles of every kept cell, and per-ring statistics.

use rayon::prelude::*;

use super::grid::{Geometry, Unit, V};
use super::{LodError, LodParams, MAX_TRIANGLES, RingStats, displace_into};
use crate::mesh::{Block, MAX_BLOCK_CELLS, Mesh, MeshError};
use crate::ocean::Sampler;

/// Vertex numbering: per ring, a dense array over its (2b+1)^2 grid points (`u32::MAX` where
/// no vertex is used), and the number of vertices in each (ring, row), in build order.
struct VertexIndex {
    index: Vec<Vec<u32>>,
    row_counts: Vec<usize>,
}

/// Per-vertex buffers.
struct Attributes {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
}

impl Geometry {
    /// Builds the mesh, sampling the ocean at every vertex (in parallel, by rows).
    pub(super) fn build(
        &self,
        params: &LodParams,
        sampler: &Sampler,
    ) -> Result<(Mesh, Vec<RingStats>), LodError> {
        let vi = self.vertex_index()?;
        let attrs = self.attributes(&vi, params.earth_radius_m, sampler);
        let (indices, tri_counts, runs) = self.triangles(&vi.index)?;
        let per_ring = self.ring_stats(&tri_counts);
        let (blocks, block_rows) = blocks(&runs);
        drop(vi);
        let mesh = Mesh::new(attrs.positions, attrs.normals, attrs.uvs, indices)?
            .with_blocks(blocks, block_rows)?;
        Ok((mesh, per_ring))
    }

    /// Numbers the used grid points in (ring, row) order, rows counted in parallel.
    fn vertex_index(&self) -> Result<VertexIndex, LodError> {
        // Zeroed (calloc) and mapped in on every core, each row set to u32::MAX (unused) by the
        // task that numbers it: filled on one thread, paper-high's 60 MB of index had taken
        // two thirds of a comparison's page faults.
        let mut index: Vec<Vec<u32>> = self
            .rings
            .iter()
            .map(|r| {
                let mut arr = vec![0u32; ((2 * r.b + 1) * (2 * r.b + 1)) as usize];
                crate::memory::prefault(&mut arr);
                arr
            })
            .collect();
        let mut row_counts: Vec<usize> = Vec::new();
        for (k, (r, arr)) in self.rings.iter().zip(index.iter_mut()).enumerate() {
            let side = (2 * r.b + 1) as usize;
            let mut counts: Vec<usize> = arr
                .par_chunks_mut(side)
                .enumerate()
                .map(|(row, out)| {
                    out.fill(u32::MAX);
                    let z = row as i64 - r.b;
                    let mut n = 0u32;
                    for (lo, hi) in self.point_spans(k, z) {
                        for x in lo..hi {
                            if self.point_used(k, (x, z)) {
                                out[(x + r.b) as usize] = n;
                                n += 1;
                            }
                        }
                    }
                    n as usize
                })
                .collect();
            // numbered from the ring's top row (largest z) down, as `point_rows` lists them:
            // a cell's upper row then comes first, the layout of Embree's grids
            counts.reverse();
            row_counts.extend(counts);
        }
        let vertices: usize = row_counts.iter().sum();
        if vertices > u32::MAX as usize - 1 {
            return Err(MeshError::TooManyVertices(vertices).into());
        }
        // Row-local numbers become global ones.
        let mut bases = Vec::with_capacity(row_counts.len());
        let mut acc = 0usize;
        for &c in &row_counts {
            bases.push(acc as u32);
            acc += c;
        }
        let mut at = 0;
        for (r, arr) in self.rings.iter().zip(index.iter_mut()) {
            let side = (2 * r.b + 1) as usize;
            let b = &bases[at..at + side];
            // (the array's rows run up in z, the bases down)
            arr.par_chunks_mut(side)
                .zip(b.par_iter().rev())
                .for_each(|(row, &base)| {
                    for v in row.iter_mut().filter(|v| **v != u32::MAX) {
                        *v += base;
                    }
                });
            at += side;
        }
        Ok(VertexIndex { index, row_counts })
    }

    /// The displaced point, normal and nominal position of every vertex, row by row in the
    /// order of the index.
    fn attributes(&self, vi: &VertexIndex, earth_r: f64, sampler: &Sampler) -> Attributes {
        let vertices: usize = vi.row_counts.iter().sum();
        // One spare element: Mesh pads these for Embree without reallocating. Zeroed
        // allocations (calloc), not cleared on one thread first; their pages are mapped in on
        // every core in one call each (`prefault`), not by a fault per page as rows are
        // written.
        let mut positions = vec![[0.0f32; 3]; vertices + 1];
        positions.truncate(vertices);
        let mut normals = vec![[0.0f32; 3]; vertices];
        let mut uvs = vec![[0.0f32; 2]; vertices + 1];
        uvs.truncate(vertices);
        crate::memory::prefault(&mut positions);
        crate::memory::prefault(&mut normals);
        crate::memory::prefault(&mut uvs);
        let pos_chunks = split_by(&mut positions, &vi.row_counts);
        let nrm_chunks = split_by(&mut normals, &vi.row_counts);
        let uv_chunks = split_by(&mut uvs, &vi.row_counts);
        self.point_rows()
            .par_iter()
            .zip(pos_chunks)
            .zip(nrm_chunks)
            .zip(uv_chunks)
            .for_each(|(((&(k, z), pos), nrm), uv)| {
                let r = &self.rings[k];
                let side = (2 * r.b + 1) as usize;
                let row = &vi.index[k][(z + r.b) as usize * side..][..side];
                let mut n = 0;
                for (xi, &v) in row.iter().enumerate() {
                    if v == u32::MAX {
                        continue;
                    }
                    let (x, zz) = ((xi as i64 - r.b) as f64 * r.size, z as f64 * r.size);
                    uv[n] = [x as f32, zz as f32];
                    n += 1;
                }
                displace_into(uv, sampler, earth_r, pos, nrm);
            });
        Attributes {
            positions,
            normals,
            uvs,
        }
    }

    /// The triangles of every kept cell, row by row, how many each cell row made, and each
    /// cell row's runs of whole cells (cells none of whose corners lies on the hole of its
    /// ring, whose two triangles have the layout of [`Block`]), at most [`MAX_BLOCK_CELLS`]
    /// to a run.
    #[allow(clippy::type_complexity)]
    fn triangles(
        &self,
        index: &[Vec<u32>],
    ) -> Result<(Vec<[u32; 3]>, Vec<usize>, Vec<Vec<Run>>), LodError> {
        let cell_rows = self.cell_rows();
        let tri_counts: Vec<usize> = cell_rows
            .par_iter()
            .map(|&(k, j)| {
                let mut n = 0;
                self.row_units(k, j, |u| n += Self::unit_tri_count(u));
                n
            })
            .collect();
        let triangles: usize = tri_counts.iter().sum();
        if triangles > MAX_TRIANGLES {
            return Err(LodError::TooLarge {
                triangles,
                limit: MAX_TRIANGLES,
            });
        }
        if triangles == 0 {
            return Err(LodError::Empty(self.reach));
        }
        let mut indices = vec![[0u32; 3]; triangles];
        crate::memory::prefault(&mut indices);
        // A point on a ring's hole edge is the finer ring's vertex.
        let lookup = |(k, x, z): V| -> u32 {
            let (k, x, z) = if k > 0 && x.abs().max(z.abs()) == self.rings[k].a {
                (k - 1, 2 * x, 2 * z)
            } else {
                (k, x, z)
            };
            let b = self.rings[k].b;
            let v = index[k][((z + b) * (2 * b + 1) + x + b) as usize];
            debug_assert!(v != u32::MAX, "ring {k} point ({x}, {z}) has no vertex");
            v
        };
        let mut bases = Vec::with_capacity(tri_counts.len());
        let mut acc = 0u32;
        for &c in &tri_counts {
            bases.push(acc);
            acc += c as u32;
        }
        let runs = cell_rows
            .par_iter()
            .zip(split_by(&mut indices, &tri_counts))
            .zip(&bases)
            .map(|((&(k, j), out), &base)| {
                let (a, b) = (self.rings[k].a, self.rings[k].b);
                let own = |x: i64, z: i64| k == 0 || x.abs().max(z.abs()) != a;
                // the ring's own vertices in the cell row's lower and upper point rows
                let side = (2 * b + 1) as usize;
                let lower = &index[k][(j + b) as usize * side..][..side];
                let upper = &index[k][(j + 1 + b) as usize * side..][..side];
                let mut runs: Vec<Run> = Vec::new();
                // the cell that would extend the last run
                let mut open: Option<i64> = None;
                let mut n = 0;
                self.row_units(k, j, |u| {
                    let here = n;
                    let whole = match u {
                        Unit::Cell((i, _))
                            if [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)]
                                .iter()
                                .all(|&(x, z)| own(x, z)) =>
                        {
                            Some(i)
                        }
                        _ => None,
                    };
                    let Some(i) = whole else {
                        self.unit_tris(k, u, |t| {
                            out[n] = t.map(lookup);
                            n += 1;
                        });
                        open = None;
                        return;
                    };
                    // What `unit_tris` and `lookup` give a cell whose corners are all its ring's
                    // (both triangles counter-clockwise as they stand), read straight from the
                    // two point rows (paper-high's triangle pass in half the time).
                    let x = (i + b) as usize;
                    let (l0, l1, u0, u1) = (lower[x], lower[x + 1], upper[x], upper[x + 1]);
                    out[n] = [l0, u1, l1];
                    out[n + 1] = [l0, u0, u1];
                    n += 2;
                    // the layout of `Block`: [low, up + 1, low + 1] and [low, up, up + 1]
                    let (up, low) = (out[here + 1][1], out[here][0]);
                    let laid = out[here] == [low, up + 1, low + 1]
                        && out[here + 1] == [low, up, up + 1]
                        && low > up;
                    if !laid {
                        open = None;
                        return;
                    }
                    match (open, runs.last_mut()) {
                        (Some(next), Some(run))
                            if next == i
                                && run.2 < MAX_BLOCK_CELLS
                                && up == run.0 + u32::from(run.2)
                                && low - up == run.1 =>
                        {
                            run.2 += 1
                        }
                        _ => runs.push((up, low - up, 1, base + here as u32)),
                    }
                    open = Some(i + 1);
                });
                runs
            })
            .collect();
        Ok((indices, tri_counts, runs))
    }

    /// Size, extent and triangle count of each ring, from the per-cell-row counts.
    fn ring_stats(&self, tri_counts: &[usize]) -> Vec<RingStats> {
        let mut per_ring: Vec<RingStats> = self
            .rings
            .iter()
            .map(|r| RingStats {
                size_m: r.size,
                inner_m: r.a as f64 * r.size,
                outer_m: r.b as f64 * r.size,
                triangles: 0,
            })
            .collect();
        for (&(k, _), &c) in self.cell_rows().iter().zip(tri_counts) {
            per_ring[k].triangles += c;
        }
        per_ring
    }
}

/// Splits `s` into consecutive chunks of the given lengths.
fn split_by<'a, T>(mut s: &'a mut [T], counts: &[usize]) -> Vec<&'a mut [T]> {
    let mut out = Vec::with_capacity(counts.len());
    for &c in counts {
        let (head, tail) = std::mem::take(&mut s).split_at_mut(c);
        out.push(head);
        s = tail;
    }
    out
}

/// A run of whole cells along a cell row: the first vertex of its upper row, the vertex stride
/// to the row below, its cells and the first cell's first triangle.
type Run = (u32, u32, u16, u32);

/// The blocks of whole cells ([`Block`]) from the runs of each cell row (in the order of
/// `cell_rows`): runs of the same cells and vertex stride in the rows below one another stack
/// into blocks, at most [`MAX_BLOCK_CELLS`] rows each. Returns the blocks and their rows' first
/// triangles.
fn blocks(runs: &[Vec<Run>]) -> (Vec<Block>, Vec<u32>) {
    // Stack the runs from each ring's top cell row down: a run continues the block whose
    // last row's lower vertices it starts on, with the same cells and stride.
    let (mut built, mut firsts): (Vec<Block>, Vec<Vec<u32>>) = (Vec::new(), Vec::new());
    let mut open: std::collections::HashMap<u32, usize> = Default::default();
    for row in runs.iter().rev() {
        let mut next = std::collections::HashMap::with_capacity(row.len());
        for &(start, stride, cells, first) in row {
            let b = match open.get(&start) {
                Some(&b)
                    if built[b].stride == stride
                        && built[b].cells == cells
                        && built[b].rows < MAX_BLOCK_CELLS =>
                {
                    built[b].rows += 1;
                    firsts[b].push(first);
                    b
                }
                _ => {
                    built.push(Block {
                        start,
                        stride,
                        cells,
                        rows: 1,
                        first_row: 0,
                    });
                    firsts.push(vec![first]);
                    built.len() - 1
                }
            };
            next.insert(start + stride, b);
        }
        open = next;
    }
    let mut table = Vec::with_capacity(firsts.iter().map(Vec::len).sum());
    for (b, rows) in built.iter_mut().zip(&firsts) {
        b.first_row = table.len() as u32;
        table.extend_from_slice(rows);
    }
    (built, table)
}
