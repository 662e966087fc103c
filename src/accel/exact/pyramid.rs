//! One layer's pyramids (Tevs, Ihrke & Seidel's maximum mipmaps, as in Thonat et al. 2021):
//! each block's smallest and largest h, its steepest neighbour differences of h and of the
//! displacement, and its smallest and largest Dx and Dz, with the layer's limits (what no read
//! exceeds anywhere). A bilinear read lies between the smallest and largest of its four texels,
//! so a box's blocks bound every read inside it.

use rayon::prelude::*;

use crate::fp::floor_i64;
use crate::ocean::{Layer, field};

/// What a pyramid keeps per block of texels, and how two blocks join.
pub(super) trait Block: Copy + Send + Sync {
    fn join(self, o: Self) -> Self;
}

/// The smallest and largest h of a block.
impl Block for [f32; 2] {
    #[inline]
    fn join(self, o: Self) -> Self {
        [self[0].min(o[0]), self[1].max(o[1])]
    }
}

/// The largest neighbour differences over dx that start at a block's texels: of h along x and
/// along z, and of the displacement on the strain's diagonal (dDx/dx, dDz/dz) and off it
/// (dDx/dz, dDz/dx).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Steep {
    pub slope: [f32; 2],
    pub strain: [f32; 2],
}

impl Block for Steep {
    #[inline]
    fn join(self, o: Self) -> Self {
        Steep {
            slope: [self.slope[0].max(o.slope[0]), self.slope[1].max(o.slope[1])],
            strain: [
                self.strain[0].max(o.strain[0]),
                self.strain[1].max(o.strain[1]),
            ],
        }
    }
}

/// The smallest and largest Dx and Dz of a block: `[Dx min, Dx max, Dz min, Dz max]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Disp(pub [f32; 4]);

impl Block for Disp {
    #[inline]
    fn join(self, o: Self) -> Self {
        let (a, b) = (self.0, o.0);
        Disp([
            a[0].min(b[0]),
            a[1].max(b[1]),
            a[2].min(b[2]),
            a[3].max(b[3]),
        ])
    }
}

/// A max-mipmap of one layer's blocks: level `l` (from 1) holds, for each block of 2^l x 2^l
/// texels, the join of its texels.
pub(super) struct Levels<T> {
    /// `levels[l - 1]`: (n >> l)^2 cells, z-major.
    levels: Vec<Vec<T>>,
    /// n >> 1, the side of level 1 in blocks.
    side1: usize,
    /// The whole layer's.
    global: T,
}

impl<T: Block> Levels<T> {
    fn new(level1: Vec<T>) -> Levels<T> {
        let side1 = (level1.len() as f64).sqrt() as usize;
        let mut levels = vec![level1];
        while levels.last().map_or(0, |l| l.len()) > 1 {
            let prev = levels.last().expect("a level");
            let side = (prev.len() as f64).sqrt() as usize;
            let s = side / 2;
            let next: Vec<T> = (0..s * s)
                .into_par_iter()
                .map(|c| {
                    let (jx, jz) = (c % s, c / s);
                    let at = |x: usize, z: usize| prev[z * side + x];
                    (at(2 * jx, 2 * jz).join(at(2 * jx + 1, 2 * jz)))
                        .join(at(2 * jx, 2 * jz + 1).join(at(2 * jx + 1, 2 * jz + 1)))
                })
                .collect();
            levels.push(next);
        }
        let global = levels.last().expect("a level")[0];
        Levels {
            levels,
            side1,
            global,
        }
    }

    /// The join over the blocks of `level` from (jx0, jz0) to (jx1, jz1) (at most two on each
    /// axis, wrapping), or the whole layer's for level 0.
    #[inline]
    pub fn get(&self, (level, [jx0, jx1], [jz0, jz1]): Blocks) -> T {
        if level == 0 {
            return self.global;
        }
        let cells = &self.levels[level - 1];
        let side = self.side1 >> (level - 1);
        let mask = side as i64 - 1;
        let at = |x: i64, z: i64| cells[(z & mask) as usize * side + (x & mask) as usize];
        let mut b = at(jx0, jz0);
        if jx1 != jx0 {
            b = b.join(at(jx1, jz0));
        }
        if jz1 != jz0 {
            b = b.join(at(jx0, jz1));
            if jx1 != jx0 {
                b = b.join(at(jx1, jz1));
            }
        }
        b
    }

    pub fn bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| std::mem::size_of_val(l.as_slice()))
            .sum()
    }
}

/// A level and the first and last block on each axis.
pub(super) type Blocks = (usize, [i64; 2], [i64; 2]);

/// One layer's pyramids: h's range, the steepest differences, and the displacement's range.
pub(super) struct Pyramid {
    n: usize,
    /// The layer's (level 0's) 1 / dx and grid origin, and its texels' scale to this grid's:
    /// a nominal position x is at this grid's coordinate (origin + x inv_dx) scale, as the
    /// sampler reads a level.
    inv_dx: f64,
    origin: [f64; 2],
    scale: f64,
    pub heights: Levels<[f32; 2]>,
    pub steep: Levels<Steep>,
    pub disp: Levels<Disp>,
}

/// What no read of one layer exceeds anywhere.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LayerLimits {
    /// Largest |Dx| and |Dz|, m.
    pub disp: [f64; 2],
    /// Largest |h|, m.
    pub height: f64,
    /// Steepest slopes of the bilinear surface along x and z: the largest difference of h
    /// between neighbouring texels along each axis, over dx.
    pub slope: [f64; 2],
    /// Largest |dDx/dx|, |dDz/dz| and |dDx/dz|, |dDz/dx| of the bilinear surface, from
    /// neighbour differences of the displacement.
    pub strain: [f64; 3],
}

impl Pyramid {
    /// The pyramids of `layer`, whose grid coordinate at nominal position x is
    /// (`origin` + x `inv_dx`) `scale`: a layer's own (`scale` 1) or one of its levels (`origin`
    /// and `inv_dx` its layer's, `scale` 2^-l).
    pub fn new(layer: &Layer, origin: [f64; 2], inv_dx: f64, scale: f64) -> (Pyramid, LayerLimits) {
        let n = layer.n();
        let t = layer.fields();
        // (a layer's side is a power of two: neighbours wrap with a mask)
        let mask = n - 1;
        // level 1 straight from the texels, with the limits in the same pass; the differences
        // are taken in f32 as the texels hold them and divided by dx once per block (the
        // division and the rounding up are monotone, so the largest quotient is the quotient
        // of the largest difference)
        let half = n / 2;
        let dx = layer.dx();
        // rounded up, so that the f32 block still bounds the f64 figure
        let up = |v: f32| (v as f64 / dx * (1.0 + 1e-6)) as f32;
        // max and min as one compare each (f32::max's NaN rules cost several instructions;
        // the fields hold no NaN, and a NaN difference would be dropped, not kept)
        let mx = |m: f32, v: f32| if v > m { v } else { m };
        let mn = |m: f32, v: f32| if v < m { v } else { m };
        type Row = (Vec<[f32; 2]>, Vec<Steep>, Vec<Disp>, [f32; 8]);
        let rows: Vec<Row> = (0..half)
            .into_par_iter()
            .map(|jz| {
                let mut row = Vec::with_capacity(half);
                let mut steep_row = Vec::with_capacity(half);
                let mut disp_row = Vec::with_capacity(half);
                // the row's largest |h|, |Dx|, |Dz|, h differences along x and z, dDx/dx,
                // dDz/dz and off-diagonal difference
                let mut lim = [0.0f32; 8];
                for jx in 0..half {
                    let (inf, ninf) = (f32::INFINITY, f32::NEG_INFINITY);
                    let (mut hr, mut dr) = ([inf, ninf], [inf, ninf, inf, ninf]);
                    // steepest h difference along x and z, dDx/dx, dDz/dz, off-diagonal
                    let mut s = [0.0f32; 5];
                    for (ix, iz) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (x, z) = (2 * jx + ix, 2 * jz + iz);
                        let c = &t[z * n + x];
                        let r = &t[z * n + ((x + 1) & mask)];
                        let b = &t[((z + 1) & mask) * n + x];
                        let v = c[field::H];
                        let (ddx, ddz) = (c[field::DX], c[field::DZ]);
                        hr = [mn(hr[0], v), mx(hr[1], v)];
                        dr = [
                            mn(dr[0], ddx),
                            mx(dr[1], ddx),
                            mn(dr[2], ddz),
                            mx(dr[3], ddz),
                        ];
                        let diff = [
                            (r[field::H] - v).abs(),
                            (b[field::H] - v).abs(),
                            (r[field::DX] - ddx).abs(),
                            (b[field::DZ] - ddz).abs(),
                            mx((b[field::DX] - ddx).abs(), (r[field::DZ] - ddz).abs()),
                        ];
                        for (m, d) in s.iter_mut().zip(diff) {
                            *m = mx(*m, d);
                        }
                    }
                    row.push(hr);
                    disp_row.push(Disp(dr));
                    steep_row.push(Steep {
                        slope: [up(s[0]), up(s[1])],
                        strain: [up(mx(s[2], s[3])), up(s[4])],
                    });
                    let block = [
                        mx(hr[0].abs(), hr[1].abs()),
                        mx(dr[0].abs(), dr[1].abs()),
                        mx(dr[2].abs(), dr[3].abs()),
                        s[0],
                        s[1],
                        s[2],
                        s[3],
                        s[4],
                    ];
                    for (m, b) in lim.iter_mut().zip(block) {
                        *m = mx(*m, b);
                    }
                }
                (row, steep_row, disp_row, lim)
            })
            .collect();
        let mut lim = [0.0f32; 8];
        let mut level1 = Vec::with_capacity(half * half);
        let mut steep1 = Vec::with_capacity(half * half);
        let mut disp1 = Vec::with_capacity(half * half);
        for (row, steep_row, disp_row, l) in rows {
            level1.extend(row);
            steep1.extend(steep_row);
            disp1.extend(disp_row);
            for (m, v) in lim.iter_mut().zip(l) {
                *m = m.max(v);
            }
        }
        let limits = LayerLimits {
            disp: [lim[1] as f64, lim[2] as f64],
            height: lim[0] as f64,
            slope: [lim[3] as f64 / dx, lim[4] as f64 / dx],
            strain: [lim[5] as f64 / dx, lim[6] as f64 / dx, lim[7] as f64 / dx],
        };
        (
            Pyramid {
                n,
                inv_dx,
                origin,
                scale,
                heights: Levels::new(level1),
                steep: Levels::new(steep1),
                disp: Levels::new(disp1),
            },
            limits,
        )
    }

    /// The grid's texel, m.
    pub fn dx(&self) -> f64 {
        1.0 / (self.inv_dx * self.scale)
    }

    /// The blocks holding every texel a bilinear read at nominal positions in
    /// `[x0, x1] x [z0, z1]` touches (level 0: the whole layer).
    #[inline]
    pub fn blocks(&self, x0: f64, x1: f64, z0: f64, z1: f64) -> Blocks {
        let p = [
            (self.origin[0] + x0 * self.inv_dx) * self.scale,
            (self.origin[0] + x1 * self.inv_dx) * self.scale,
            (self.origin[1] + z0 * self.inv_dx) * self.scale,
            (self.origin[1] + z1 * self.inv_dx) * self.scale,
        ];
        // (NaN fails the test too)
        if !p.iter().all(|v| v.abs() < 1e15) {
            return (0, [0; 2], [0; 2]);
        }
        // the texels the reads touch: floor(p0) ..= floor(p1) + 1 on each axis
        let [ix0, ix1, iz0, iz1] = p.map(floor_i64);
        let (ix1, iz1) = (ix1 + 1, iz1 + 1);
        let span = (ix1 - ix0).max(iz1 - iz0) + 1;
        if span >= (self.n / 2) as i64 {
            return (0, [0; 2], [0; 2]);
        }
        // the smallest level whose blocks are at least `span` texels: the range then meets at
        // most two blocks on each axis
        let level = (span.max(1) as u64)
            .next_power_of_two()
            .trailing_zeros()
            .max(1) as usize;
        (
            level,
            [ix0 >> level, ix1 >> level],
            [iz0 >> level, iz1 >> level],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Each layer's and each of its levels' pyramid queries against the texels a box's reads
    /// touch, counted one by one: every block value holds them (h's and D's ranges, the
    /// steepest differences that start at them), and is no looser than the texels of the
    /// blocks it joins.
    #[test]
    fn every_query_holds_the_texels_of_its_box_one_by_one() {
        let ocean = crate::accel::exact::tests::sea(1.0);
        let sampler = ocean.sampler([321.0, -45.5]);
        let mut rng = Rng::keyed(&[6]);
        // each layer's own texels, and each of its low-passed levels (a grid 2^l times coarser
        // over the same square, read at the layer's coordinates times 2^-l)
        let levels = ocean.levels();
        let grids = sampler
            .layers()
            .iter()
            .zip(sampler.grid_origins())
            .enumerate()
            .flat_map(|(i, (layer, &origin))| {
                (0..=levels.count(i)).map(move |l| {
                    let grid = if l == 0 { layer } else { levels.level(i, l) };
                    (layer, grid, origin, 0.5f64.powi(l as i32))
                })
            });
        for (layer, grid, origin, scale) in grids {
            let (pyramid, _) = Pyramid::new(grid, origin, layer.inv_dx(), scale);
            let (n, t, dx) = (grid.n() as i64, grid.fields(), grid.dx());
            let at = |x: i64, z: i64| &t[(z.rem_euclid(n) * n + x.rem_euclid(n)) as usize];
            for _ in 0..300 {
                let size = grid.dx() * 0.3 * 40f64.powf(rng.f64());
                let (x0, z0) = (rng.f64() * 400.0 - 200.0, rng.f64() * 400.0 - 200.0);
                let (x1, z1) = (x0 + size, z0 + size * rng.f64());
                let texel = |v: f64, o: f64| ((o + v * layer.inv_dx()) * scale).floor() as i64;
                let (ix0, ix1) = (texel(x0, origin[0]), texel(x1, origin[0]) + 1);
                let (iz0, iz1) = (texel(z0, origin[1]), texel(z1, origin[1]) + 1);
                let blocks = pyramid.blocks(x0, x1, z0, z1);
                let (h, steep, disp) = (
                    pyramid.heights.get(blocks),
                    pyramid.steep.get(blocks),
                    pyramid.disp.get(blocks).0,
                );
                for z in iz0..=iz1 {
                    for x in ix0..=ix1 {
                        let (c, r, b) = (at(x, z), at(x + 1, z), at(x, z + 1));
                        let v = c[field::H];
                        assert!(h[0] <= v && v <= h[1], "h {v} outside {h:?}");
                        let d = |a: &[f32; 8], k: usize| ((a[k] - c[k]).abs() as f64 / dx) as f32;
                        let slope = [d(r, field::H), d(b, field::H)];
                        let diag = d(r, field::DX).max(d(b, field::DZ));
                        let off = d(b, field::DX).max(d(r, field::DZ));
                        assert!(
                            slope[0] <= steep.slope[0] && slope[1] <= steep.slope[1],
                            "{slope:?} > {steep:?}"
                        );
                        assert!(
                            diag <= steep.strain[0] && off <= steep.strain[1],
                            "{steep:?}"
                        );
                        let (ddx, ddz) = (c[field::DX], c[field::DZ]);
                        assert!(disp[0] <= ddx && ddx <= disp[1], "Dx {ddx} {disp:?}");
                        assert!(disp[2] <= ddz && ddz <= disp[3], "Dz {ddz} {disp:?}");
                    }
                }
                // no looser than the blocks' own texels: at most four blocks of the level
                // (or the whole layer), whose join the values must equal
                let (level, [jx0, jx1], [jz0, jz1]) = blocks;
                if level > 0 {
                    let side = 1i64 << level;
                    let mut hi = f32::NEG_INFINITY;
                    for jz in [jz0, jz1] {
                        for jx in [jx0, jx1] {
                            for z in jz * side..(jz + 1) * side {
                                for x in jx * side..(jx + 1) * side {
                                    hi = hi.max(at(x, z)[field::H]);
                                }
                            }
                        }
                    }
                    assert_eq!(h[1], hi);
                }
            }
        }
    }
}
