//! The nested grids of the doubling method (paper Figure 1) as integer cells, how neighbouring
//! rings are stitched, and which cells a pattern keeps; `build.rs` turns them into a mesh.
//!
//! Ring k is a square annulus of square cells of side `size`, in its own integer grid centred on
//! the camera's nadir: cells whose Chebyshev index lies in [a, b) (half-widths a and b in cells;
//! b is even when a coarser ring follows, whose hole is then b / 2 of its cells). Each cell is
//! two triangles, except the cells of a coarser ring lying along its hole: their inner edge
//! carries the finer ring's midpoint vertex, so they are fanned into three triangles and the
//! shared edge has the same vertices on both sides (no T-junction, so displacing the vertices
//! opens no crack). That adds one triangle per boundary cell, which is what makes the paper's
//! counts come out exactly (see the module doc of `lod`). Cells are culled by distance and, for
//! the frustum pattern, by angle; every cell's triangles span only that cell, so any set of kept
//! cells is conforming. Vertices get indices in (ring, row) order, each ring's rows from the top
//! (largest z) down; rows are built in parallel.

use rayon::prelude::*;

use super::{LodError, LodParams, MAX_TRIANGLES, Pattern};

type P = (i64, i64);

pub(super) struct Ring {
    pub(super) size: f64,
    /// Hole half-width, cells (0 for the innermost ring).
    pub(super) a: i64,
    /// Outer half-width, cells.
    pub(super) b: i64,
    /// No coarser ring follows.
    last: bool,
    /// Every cell of the ring with Chebyshev index below this survives culling.
    fast: i64,
}

struct Wedge {
    yaw: f64,
    half: f64,
}

pub(super) struct Geometry {
    pub(super) rings: Vec<Ring>,
    /// Cells whose nearest point is farther are culled (infinite when the last ring is whole).
    cut: f64,
    /// How far the tessellation reaches (for the statistics).
    pub(super) reach: f64,
    wedge: Option<Wedge>,
    /// Cells nearer than this are kept by the frustum pattern whatever their direction.
    near_keep: f64,
    /// Per ring, row-major over its (2b)^2 cells: whether the cell survives culling (filled
    /// once, in parallel, since every cell is asked about several times).
    mask: Vec<Vec<bool>>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Unit {
    Cell(P),
    /// A cell along the hole of its ring, fanned to the finer ring's midpoint vertex: the
    /// canonical cell (i, a), above the hole's top side, rotated `r` quarter turns.
    Split {
        r: u8,
        i: i64,
    },
}

/// A grid point of a ring: (ring, x, z) in that ring's integer grid.
pub(super) type V = (usize, i64, i64);

/// Chebyshev index of cell `i` (covering [i, i+1]): distance in cells from the centre to its
/// nearest side.
#[inline]
fn cheb(i: i64) -> i64 {
    if i >= 0 { i } else { -i - 1 }
}

#[inline]
fn rot(r: u8, p: P) -> P {
    let (mut x, mut z) = p;
    for _ in 0..r {
        (x, z) = (-z, x);
    }
    (x, z)
}

/// Lower corner of the rectangle [p, q] rotated `r` quarter turns.
#[inline]
fn rot_rect(r: u8, p: P, q: P) -> P {
    let (p, q) = (rot(r, p), rot(r, q));
    (p.0.min(q.0), p.1.min(q.1))
}

#[inline]
fn rot_cell(r: u8, c: P) -> P {
    rot_rect(r, c, (c.0 + 1, c.1 + 1))
}

impl Wedge {
    /// Whether the angular extent of the rectangle [x0, x1] x [z0, z1] (not containing the
    /// origin) meets the wedge.
    fn meets(&self, x0: f64, x1: f64, z0: f64, z1: f64) -> bool {
        use std::f64::consts::{PI, TAU};
        let wrap = |a: f64| (a + PI).rem_euclid(TAU) - PI;
        let (xc, zc) = (0.5 * (x0 + x1), 0.5 * (z0 + z1));
        let centre = zc.atan2(xc);
        // The rectangle lies within its circumscribed circle's angular radius of the centre's
        // direction; only cells near the wedge's edges need their corners.
        let off = wrap(self.yaw - centre).abs();
        let spread = (0.5 * (x1 - x0).hypot(z1 - z0) / xc.hypot(zc))
            .min(1.0)
            .asin();
        if off <= self.half {
            return true;
        }
        if off > self.half + spread {
            return false;
        }
        let (mut lo, mut hi) = (0.0f64, 0.0f64);
        for (x, z) in [(x0, z0), (x1, z0), (x0, z1), (x1, z1)] {
            let d = wrap(z.atan2(x) - centre);
            lo = lo.min(d);
            hi = hi.max(d);
        }
        let delta = wrap(self.yaw - centre);
        delta + self.half >= lo && delta - self.half <= hi
    }
}

impl Geometry {
    pub(super) fn new(params: &LodParams) -> Result<Geometry, LodError> {
        let (s, d) = (params.near_size_m, params.double_distance_m);
        let max = params.max_distance();
        let widths = params.reading.widths();
        let cap_ends = params.reading.cap_ends_tessellation();
        let whole = params.reading.whole_last_ring();
        let cut = if whole { f64::INFINITY } else { max };
        let wedge = match params.pattern {
            Pattern::Square => None,
            Pattern::Frustum { yaw_deg, hfov_deg } => Some(Wedge {
                yaw: yaw_deg.to_radians(),
                half: (0.5 * hfov_deg + super::FRUSTUM_MARGIN_DEG).to_radians(),
            }),
        };
        let mut rings: Vec<Ring> = Vec::new();
        let mut estimate = 0.0f64;
        for k in 0..=64u32 {
            let size = s * 2f64.powi(k as i32);
            let scale = 2f64.powi(k as i32);
            let nominal = if widths {
                d * (2.0 * scale - 1.0)
            } else {
                d * scale
            };
            let capped = params.generations == Some(k);
            let (outer, last) = if nominal >= max {
                (if whole { nominal } else { max }, true)
            } else if capped && !cap_ends {
                (max, true)
            } else {
                (nominal, capped)
            };
            let a = rings.last().map_or(0, |r| r.b / 2);
            let b = if last {
                ((outer / size).ceil() as i64).max(a + 1)
            } else {
                // Snapped to whole cells of the next (coarser) ring, at least one of them wide.
                let q = 2 * (outer / (2.0 * size)).round() as i64;
                q.max(a + 2 + a % 2)
            };
            let fast = if wedge.is_some() {
                0
            } else if whole {
                i64::MAX
            } else {
                (max / (size * std::f64::consts::SQRT_2)).floor() as i64 + 1
            };
            estimate += 2.0 * (2.0 * b as f64).powi(2);
            if estimate > 4.0 * MAX_TRIANGLES as f64 {
                return Err(LodError::TooLarge {
                    triangles: estimate as usize,
                    limit: MAX_TRIANGLES,
                });
            }
            rings.push(Ring {
                size,
                a,
                b,
                last,
                fast,
            });
            if last {
                break;
            }
        }
        let Some(outer) = rings.last().filter(|r| r.last) else {
            return Err(LodError::Empty(max));
        };
        let reach = if whole {
            outer.b as f64 * outer.size
        } else {
            max
        };
        let mut geo = Geometry {
            rings,
            cut,
            reach,
            wedge,
            near_keep: params.camera_height_m,
            mask: Vec::new(),
        };
        geo.mask = (0..geo.rings.len())
            .map(|k| {
                let b = geo.rings[k].b;
                let side = (2 * b) as usize;
                let mut m = vec![false; side * side];
                m.par_chunks_mut(side).enumerate().for_each(|(row, out)| {
                    let j = row as i64 - b;
                    for (x, o) in out.iter_mut().enumerate() {
                        *o = geo.survives(k, (x as i64 - b, j));
                    }
                });
                m
            })
            .collect();
        Ok(geo)
    }

    pub(super) fn max_distance(&self) -> f64 {
        self.reach
    }

    pub(super) fn ring_extents(&self) -> Vec<(f64, f64, f64)> {
        self.rings
            .iter()
            .map(|r| (r.size, r.a as f64 * r.size, r.b as f64 * r.size))
            .collect()
    }

    /// Whether cell (i, j) of ring k is in the ring and survives culling on its own.
    #[inline]
    fn pred(&self, k: usize, (i, j): P) -> bool {
        let b = self.rings[k].b;
        self.in_annulus(k, (i, j)) && self.mask[k][((j + b) * 2 * b + i + b) as usize]
    }

    /// [`Geometry::pred`] from scratch.
    fn survives(&self, k: usize, (i, j): P) -> bool {
        let r = &self.rings[k];
        let (ci, cj) = (cheb(i), cheb(j));
        let c = ci.max(cj);
        if c < r.a || c >= r.b {
            return false;
        }
        if c < r.fast {
            return true;
        }
        let near = r.size * (ci as f64).hypot(cj as f64);
        if near > self.cut {
            return false;
        }
        match &self.wedge {
            None => true,
            Some(w) => {
                near < self.near_keep
                    || (ci == 0 && cj == 0)
                    || w.meets(
                        i as f64 * r.size,
                        (i + 1) as f64 * r.size,
                        j as f64 * r.size,
                        (j + 1) as f64 * r.size,
                    )
            }
        }
    }

    fn in_annulus(&self, k: usize, (i, j): P) -> bool {
        let r = &self.rings[k];
        let c = cheb(i).max(cheb(j));
        c >= r.a && c < r.b
    }

    fn unit_of(&self, k: usize, c: P) -> Unit {
        let a = self.rings[k].a;
        if k == 0 || cheb(c.0).max(cheb(c.1)) != a {
            return Unit::Cell(c);
        }
        for r in 0..4u8 {
            let (ci, cj) = rot_cell((4 - r) % 4, c);
            if cj == a && (-a..a).contains(&ci) {
                return Unit::Split { r, i: ci };
            }
        }
        // Diagonal to a corner of the hole: it meets the finer ring in one coarse vertex.
        Unit::Cell(c)
    }

    fn keep_cell(&self, k: usize, c: P) -> bool {
        self.pred(k, c)
    }

    /// Calls `f` with each triangle of the unit, wound like [`Mesh::grid`] (counter-clockwise
    /// seen from above).
    pub(super) fn unit_tris(&self, k: usize, u: Unit, mut f: impl FnMut([V; 3])) {
        let mut emit = |r: u8, t: [V; 3]| {
            let t = t.map(|(kk, x, z)| {
                let (x, z) = rot(r, (x, z));
                (kk, x, z)
            });
            // Orientation in the finer grid's units, where every point is on the lattice.
            let fine = t.map(|(kk, x, z)| {
                if kk == k && k > 0 {
                    (2 * x, 2 * z)
                } else {
                    (x, z)
                }
            });
            let [p0, p1, p2] = fine;
            let cross = (p1.0 - p0.0) * (p2.1 - p0.1) - (p1.1 - p0.1) * (p2.0 - p0.0);
            f(if cross < 0 { t } else { [t[0], t[2], t[1]] });
        };
        match u {
            Unit::Cell((i, j)) => {
                emit(0, [(k, i, j), (k, i + 1, j + 1), (k, i + 1, j)]);
                emit(0, [(k, i, j), (k, i, j + 1), (k, i + 1, j + 1)]);
            }
            Unit::Split { r, i } => {
                let a = self.rings[k].a;
                let (p0, p2) = ((k, i, a), (k, i + 1, a));
                let (q0, q2) = ((k, i, a + 1), (k, i + 1, a + 1));
                let m = (k - 1, 2 * i + 1, 2 * a);
                emit(r, [p0, m, q0]);
                emit(r, [m, q2, q0]);
                emit(r, [m, p2, q2]);
            }
        }
    }

    pub(super) fn unit_tri_count(u: Unit) -> usize {
        match u {
            Unit::Cell(_) => 2,
            Unit::Split { .. } => 3,
        }
    }

    /// Calls `f` with every kept unit in cell row j of ring k.
    pub(super) fn row_units(&self, k: usize, j: i64, mut f: impl FnMut(Unit)) {
        let r = &self.rings[k];
        let mut span = |lo: i64, hi: i64| {
            for i in lo..hi {
                let c = (i, j);
                if self.pred(k, c) {
                    f(self.unit_of(k, c));
                }
            }
        };
        if cheb(j) >= r.a {
            span(-r.b, r.b);
        } else {
            span(-r.b, -r.a);
            span(r.a, r.b);
        }
    }

    /// Whether grid point p of ring k is a vertex of the mesh owned by ring k (points on a
    /// ring's hole belong to the finer ring inside it).
    pub(super) fn point_used(&self, k: usize, (x, z): P) -> bool {
        let r = &self.rings[k];
        let c = x.abs().max(z.abs());
        if c > r.b || c < r.a || (k > 0 && c == r.a) {
            return false;
        }
        // The cell outward of the point is in the ring and survives.
        if c < r.b && c < r.fast {
            return true;
        }
        let cells = [(x - 1, z - 1), (x, z - 1), (x - 1, z), (x, z)];
        if cells.iter().any(|&cell| self.keep_cell(k, cell)) {
            return true;
        }
        if !r.last && c == r.b {
            // Coarse cells whose closed square holds the point (an odd point is the midpoint
            // of a coarse edge); every kept one uses it.
            let span = |v: i64| (v - 1).div_euclid(2)..=v.div_euclid(2);
            return span(z)
                .flat_map(|cz| span(x).map(move |cx| (cx, cz)))
                .any(|cell| self.keep_cell(k + 1, cell));
        }
        false
    }

    /// Grid points of row z of ring k that might be vertices, as x ranges.
    pub(super) fn point_spans(&self, k: usize, z: i64) -> [(i64, i64); 2] {
        let r = &self.rings[k];
        if z.abs() >= r.a {
            [(-r.b, r.b + 1), (0, 0)]
        } else {
            [(-r.b, -r.a + 1), (r.a, r.b + 1)]
        }
    }

    /// (triangles, vertices) the build makes.
    pub(super) fn count(&self) -> (usize, usize) {
        let rows: Vec<(usize, i64)> = self.cell_rows();
        let tris = rows
            .par_iter()
            .map(|&(k, j)| {
                let mut n = 0;
                self.row_units(k, j, |u| n += Self::unit_tri_count(u));
                n
            })
            .sum();
        let verts = self
            .point_rows()
            .par_iter()
            .map(|&(k, z)| {
                self.point_spans(k, z)
                    .iter()
                    .flat_map(|&(lo, hi)| lo..hi)
                    .filter(|&x| self.point_used(k, (x, z)))
                    .count()
            })
            .sum();
        (tris, verts)
    }

    pub(super) fn cell_rows(&self) -> Vec<(usize, i64)> {
        self.rings
            .iter()
            .enumerate()
            .flat_map(|(k, r)| (-r.b..r.b).map(move |j| (k, j)))
            .collect()
    }

    /// The rows of grid points in the order their vertices are numbered: ring by ring, each
    /// from its top row (largest z) down.
    pub(super) fn point_rows(&self) -> Vec<(usize, i64)> {
        self.rings
            .iter()
            .enumerate()
            .flat_map(|(k, r)| (-r.b..=r.b).rev().map(move |z| (k, z)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotations_are_quarter_turns() {
        assert_eq!(rot(1, (3, 1)), (-1, 3));
        assert_eq!(rot(4 % 4, (3, 1)), (3, 1));
        // Cell (0, 0) = [0,1]^2 turns into [-1,0] x [0,1].
        assert_eq!(rot_cell(1, (0, 0)), (-1, 0));
        for r in 0..4 {
            assert_eq!(rot_cell((4 - r) % 4, rot_cell(r, (5, -2))), (5, -2));
        }
    }

    #[test]
    fn cells_along_each_hole_are_split() {
        let params = LodParams {
            near_size_m: 1.0,
            double_distance_m: 8.0,
            generations: Some(2),
            ..crate::lod::Preset::PaperLow.params(2.0)
        };
        let geo = Geometry::new(&params).unwrap();
        for (k, r) in geo.rings.iter().enumerate() {
            let mut split = std::collections::HashSet::new();
            for j in -r.b..r.b {
                for i in -r.b..r.b {
                    if let Unit::Split { r: rr, i: ci } = geo.unit_of(k, (i, j)) {
                        assert_eq!(rot_cell(rr, (ci, r.a)), (i, j));
                        split.insert((i, j));
                    }
                }
            }
            // Every side of the hole, 2a cells each.
            assert_eq!(split.len() as i64, 8 * r.a, "ring {k}");
        }
    }
}
