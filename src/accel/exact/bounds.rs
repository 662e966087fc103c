//! Bounds on the summed ocean over a box of nominal positions, which the exact intersector
//! needs to skip the stretches of a ray that cannot meet the surface.
//!
//! The layers are periodic with unrelated extents, so no single pyramid covers their sum. Each
//! layer keeps its own min/max pyramid of h (Tevs, Ihrke & Seidel's maximum mipmaps, as in
//! Thonat et al. 2021), and a box's bound is the sum of the layers' bounds over it: the sum of
//! the minima is at most the minimum of the sum, so the bound is conservative, and it costs
//! one query per layer (at most four cells of one level). A bilinear read lies between the
//! smallest and largest of its four texels, so a box's bound covers the texels its reads touch.
//! Each layer also keeps what a read can never exceed anywhere: the largest |Dx|, |Dz| and the
//! steepest difference of h between neighbouring texels (the bilinear surface's slope bound).

use rayon::prelude::*;

use crate::ocean::{Layer, Sampler, field};

/// One layer's min/max pyramid of h: level `l` (from 1) holds, for each block of 2^l x 2^l
/// texels, the smallest and largest h in it.
struct Pyramid {
    n: usize,
    inv_dx: f64,
    origin: [f64; 2],
    /// `levels[l - 1]`: (n >> l)^2 cells, z-major.
    levels: Vec<Vec<[f32; 2]>>,
    /// The layer's smallest and largest h.
    global: [f32; 2],
}

/// What no read of one layer exceeds anywhere.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LayerLimits {
    /// Largest |Dx| and |Dz|, m.
    pub disp: [f64; 2],
    /// Largest |h|, m.
    pub height: f64,
    /// Steepest slope of the bilinear surface: the largest difference of h between
    /// neighbouring texels over dx.
    pub slope: f64,
    /// Largest |dDx/dx|, |dDz/dz| and |dDx/dz|, |dDz/dx| of the bilinear surface, from
    /// neighbour differences of the displacement.
    pub strain: [f64; 3],
}

/// The bounds of every layer of a surface, around one camera origin.
pub(super) struct SurfaceBounds {
    pyramids: Vec<Pyramid>,
    pub limits: Vec<LayerLimits>,
}

#[inline]
fn join(a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    [a[0].min(b[0]), a[1].max(b[1])]
}

impl Pyramid {
    fn new(layer: &Layer, origin: [f64; 2]) -> (Pyramid, LayerLimits) {
        let n = layer.n();
        let t = layer.fields();
        let h = |ix: usize, iz: usize| t[(iz % n) * n + ix % n][field::H];
        // level 1 straight from the texels, with the limits in the same pass
        let half = n / 2;
        let dx = layer.dx();
        let rows: Vec<(Vec<[f32; 2]>, LayerLimits)> = (0..half)
            .into_par_iter()
            .map(|jz| {
                let mut row = vec![[0.0f32; 2]; half];
                let mut lim = LayerLimits::default();
                for (jx, cell) in row.iter_mut().enumerate() {
                    let mut b = [f32::INFINITY, f32::NEG_INFINITY];
                    for (ix, iz) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (x, z) = (2 * jx + ix, 2 * jz + iz);
                        let v = h(x, z);
                        b = join(b, [v, v]);
                        let tx = &t[z * n + x];
                        let right = &t[z * n + (x + 1) % n];
                        let below = &t[((z + 1) % n) * n + x];
                        lim.height = lim.height.max(v.abs() as f64);
                        lim.disp[0] = lim.disp[0].max(tx[field::DX].abs() as f64);
                        lim.disp[1] = lim.disp[1].max(tx[field::DZ].abs() as f64);
                        let dh = (right[field::H] - v).abs().max((below[field::H] - v).abs());
                        lim.slope = lim.slope.max(dh as f64 / dx);
                        let strain = [
                            (right[field::DX] - tx[field::DX]).abs(),
                            (below[field::DZ] - tx[field::DZ]).abs(),
                            (below[field::DX] - tx[field::DX])
                                .abs()
                                .max((right[field::DZ] - tx[field::DZ]).abs()),
                        ];
                        for (m, s) in lim.strain.iter_mut().zip(strain) {
                            *m = m.max(s as f64 / dx);
                        }
                    }
                    *cell = b;
                }
                (row, lim)
            })
            .collect();
        let mut limits = LayerLimits::default();
        let mut level1 = Vec::with_capacity(half * half);
        for (row, l) in rows {
            level1.extend(row);
            limits.height = limits.height.max(l.height);
            limits.slope = limits.slope.max(l.slope);
            for k in 0..3 {
                limits.strain[k] = limits.strain[k].max(l.strain[k]);
            }
            for k in 0..2 {
                limits.disp[k] = limits.disp[k].max(l.disp[k]);
            }
        }
        let mut levels = vec![level1];
        while levels.last().map_or(0, |l| l.len()) > 1 {
            let prev = levels.last().expect("a level");
            let side = (prev.len() as f64).sqrt() as usize;
            let s = side / 2;
            let next: Vec<[f32; 2]> = (0..s * s)
                .into_par_iter()
                .map(|c| {
                    let (jx, jz) = (c % s, c / s);
                    let at = |x: usize, z: usize| prev[z * side + x];
                    join(
                        join(at(2 * jx, 2 * jz), at(2 * jx + 1, 2 * jz)),
                        join(at(2 * jx, 2 * jz + 1), at(2 * jx + 1, 2 * jz + 1)),
                    )
                })
                .collect();
            levels.push(next);
        }
        let global = levels.last().expect("a level")[0];
        (
            Pyramid {
                n,
                inv_dx: layer.inv_dx(),
                origin,
                levels,
                global,
            },
            limits,
        )
    }

    /// The smallest and largest h any bilinear read at nominal positions in
    /// `[x0, x1] x [z0, z1]` returns.
    #[inline]
    fn query(&self, x0: f64, x1: f64, z0: f64, z1: f64) -> [f32; 2] {
        // the texels the reads touch: floor(p0) ..= floor(p1) + 1 on each axis
        let ix0 = (self.origin[0] + x0 * self.inv_dx).floor();
        let ix1 = (self.origin[0] + x1 * self.inv_dx).floor() + 1.0;
        let iz0 = (self.origin[1] + z0 * self.inv_dx).floor();
        let iz1 = (self.origin[1] + z1 * self.inv_dx).floor() + 1.0;
        let span = (ix1 - ix0).max(iz1 - iz0) + 1.0;
        if span.is_nan() || span >= (self.n / 2) as f64 {
            return self.global;
        }
        // the smallest level whose blocks are at least `span` texels: the range then meets at
        // most two blocks on each axis
        let level = (span as u64).next_power_of_two().trailing_zeros().max(1) as usize;
        let cells = &self.levels[level - 1];
        let side = self.n >> level;
        let mask = side as i64 - 1;
        let (jx0, jx1) = ((ix0 as i64) >> level, (ix1 as i64) >> level);
        let (jz0, jz1) = ((iz0 as i64) >> level, (iz1 as i64) >> level);
        let at = |x: i64, z: i64| cells[(z & mask) as usize * side + (x & mask) as usize];
        let mut b = at(jx0, jz0);
        if jx1 != jx0 {
            b = join(b, at(jx1, jz0));
        }
        if jz1 != jz0 {
            b = join(b, at(jx0, jz1));
            if jx1 != jx0 {
                b = join(b, at(jx1, jz1));
            }
        }
        b
    }
}

impl SurfaceBounds {
    /// The pyramids of every layer `sampler` reads, around its camera origin. The sampler must
    /// read bilinearly (the only read whose values stay within their texels').
    pub fn new(sampler: &Sampler) -> SurfaceBounds {
        let (pyramids, limits) = sampler
            .layers()
            .iter()
            .zip(sampler.grid_origins())
            .map(|(l, &o)| Pyramid::new(l, o))
            .unzip();
        SurfaceBounds { pyramids, limits }
    }

    /// The smallest and largest summed h over nominal positions `[x0, x1] x [z0, z1]`, m.
    #[inline]
    pub fn height(&self, x0: f64, x1: f64, z0: f64, z1: f64) -> [f64; 2] {
        let (mut b, mut size) = ([0.0f64; 2], 1e-3);
        for p in &self.pyramids {
            let q = p.query(x0, x1, z0, z1);
            b[0] += q[0] as f64;
            b[1] += q[1] as f64;
            size += (q[0].abs().max(q[1].abs())) as f64;
        }
        // f32 texels blended and summed in f32 by the reads: a read can round past the exact
        // sum by a few ulps of each layer's value (layers can cancel, so not of the sum's)
        let slack = 1e-6 * size;
        [b[0] - slack, b[1] + slack]
    }

    /// Largest |Dx| and |Dz| of the summed surface, m.
    pub fn disp(&self) -> [f64; 2] {
        let mut d = [0.0; 2];
        for l in &self.limits {
            d[0] += l.disp[0];
            d[1] += l.disp[1];
        }
        d
    }

    /// Largest |h| of the summed surface, m.
    pub fn height_limit(&self) -> f64 {
        self.limits.iter().map(|l| l.height).sum()
    }

    /// The steepest slope of the summed surface as a height over arc position: the bilinear
    /// slope bound (per axis, so sqrt 2 for the gradient) over the least stretch of the
    /// horizontal map x -> x + D, 1 - |S| for its strain S = dD/dx, with |S| at most the
    /// largest diagonal bound plus the off-diagonal one (Gershgorin). `None` where that reaches
    /// 0.95 (the bound does not prove the surface is a height field).
    pub fn slope_limit(&self) -> Option<f64> {
        let slope: f64 = self.limits.iter().map(|l| l.slope).sum();
        let s: [f64; 3] = std::array::from_fn(|k| self.limits.iter().map(|l| l.strain[k]).sum());
        let norm = s[0].max(s[1]) + s[2];
        (norm < 0.95).then(|| std::f64::consts::SQRT_2 * slope / (1.0 - norm))
    }

    /// Bytes of the pyramids.
    pub fn bytes(&self) -> usize {
        self.pyramids
            .iter()
            .flat_map(|p| &p.levels)
            .map(|l| std::mem::size_of_val(l.as_slice()))
            .sum()
    }
}
