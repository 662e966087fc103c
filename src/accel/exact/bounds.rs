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
//! A second pyramid holds each block's steepest neighbour differences of h and of the
//! displacement, so a box also has its own slope bound: the march's steps are certified by the
//! slopes where the ray is, not by the steepest texel of the whole sea. A third holds each
//! block's smallest and largest Dx and Dz, which narrow the box of nominal positions a stretch
//! of the ray can meet (x = s - D(x)) from the sea's largest displacement to the box's own.

use super::pyramid::{LayerLimits, Pyramid};
use crate::ocean::Sampler;
use crate::ocean::levels::Levels;
use crate::ocean::slopes::{LevelSet, NOT_READ};

/// Slope and strain bounds of the summed surface over a box of nominal positions (or the whole
/// sea).
#[derive(Clone, Copy, Debug)]
pub(super) struct Steepness {
    /// Bounds on |dh/dx| and |dh/dz| of the bilinear surface: the sum of the layers' steepest
    /// neighbour differences of h over dx along each axis.
    pub slope: [f64; 2],
    /// A bound on the strain S = dD/dx's norm (S is symmetric, so its largest row sum bounds
    /// it, Gershgorin): summed per layer over a box, the sea's own for the whole sea.
    pub strain: f64,
}

impl Steepness {
    /// The tighter of two bounds on the same surface: each holds, so their smaller parts do.
    pub fn min(self, o: Steepness) -> Steepness {
        Steepness {
            slope: [self.slope[0].min(o.slope[0]), self.slope[1].min(o.slope[1])],
            strain: self.strain.min(o.strain),
        }
    }

    /// How fast the surface's height can change with arc position over the box; `None` where
    /// the strain bound reaches 0.95. The box is to hold every nominal position whose surface
    /// point lies over the arc positions in question (the search's `nominal_box`), and there
    /// the map x -> x + D is one to one (its strain is below 1 on a convex set).
    pub fn slope_limit(&self) -> Option<SlopeBound> {
        let [gx, gz] = self.slope;
        let s = self.strain;
        (s < 0.95).then(|| {
            let g = gx.hypot(gz);
            SlopeBound {
                axis: self.slope,
                skew: g * s / (1.0 - s),
                norm: g / (1.0 - s),
            }
        })
    }
}

/// How fast the summed surface's height H(s) = h(x(s)) can change with arc position s, where
/// s = x + D(x). Along an arc velocity v, dH = grad h . w with w = (I + S)^-1 v, so w = v - S w,
/// |w| <= |v| / (1 - |S|) and |w - v| <= |S| |v| / (1 - |S|): hence
/// |dH| <= gx |vx| + gz |vz| + |g| |S| / (1 - |S|) |v|, never more than |g| |v| / (1 - |S|).
/// Along the waves' crests (long-crested seas) the first term is what the slope across them
/// leaves out.
#[derive(Clone, Copy, Debug)]
pub(super) struct SlopeBound {
    /// Bounds on |dh/dx| and |dh/dz|.
    pub axis: [f64; 2],
    /// |g| |S| / (1 - |S|): what the map from nominal to arc position adds per unit of speed.
    pub skew: f64,
    /// The steepest slope in any direction, |g| / (1 - |S|).
    pub norm: f64,
}

impl SlopeBound {
    /// A bound on |dH/dt| for an arc velocity whose components are at most `vx` and `vz` and
    /// whose length is at most `v`.
    #[inline]
    pub fn rate(&self, vx: f64, vz: f64, v: f64) -> f64 {
        self.axis[0] * vx + self.axis[1] * vz + self.skew * v
    }
}

/// Of each layer's `per_level` entries, the one of the level `lod` reads it at (none for a layer
/// it leaves out).
#[inline]
fn at_levels<'a, T>(
    per_level: &'a [Vec<T>],
    lod: &'a LevelSet,
) -> impl Iterator<Item = &'a T> + 'a {
    per_level
        .iter()
        .zip(lod)
        .filter(|(_, l)| **l != NOT_READ)
        .map(|(p, &l)| &p[l as usize])
}

/// The bounds of every layer of a surface, and of each of its levels, around one camera origin.
pub(super) struct SurfaceBounds {
    /// `pyramids[i][l]`: layer i's level l (0 the layer's own texels).
    pyramids: Vec<Vec<Pyramid>>,
    /// Their limits, likewise.
    limits: Vec<Vec<LayerLimits>>,
    /// Whether a surface may leave a layer out (its levels are held: a footprint past the
    /// last of them reads none).
    levels: bool,
}

impl SurfaceBounds {
    /// The pyramids of every layer `sampler` reads, around its camera origin, and of each of
    /// its `levels` if given. The sampler must read bilinearly (the only read whose values stay
    /// within their texels').
    pub fn new(sampler: &Sampler, levels: Option<&Levels>) -> SurfaceBounds {
        let (pyramids, limits) = sampler
            .layers()
            .iter()
            .zip(sampler.grid_origins())
            .enumerate()
            .map(|(i, (layer, &o))| {
                let count = levels.map_or(0, |ls| ls.count(i));
                (0..=count)
                    .map(|l| {
                        let grid = if l == 0 {
                            layer
                        } else {
                            levels.expect("levels").level(i, l)
                        };
                        Pyramid::new(grid, o, layer.inv_dx(), 0.5f64.powi(l as i32))
                    })
                    .unzip()
            })
            .unzip();
        SurfaceBounds {
            pyramids,
            limits,
            levels: levels.is_some(),
        }
    }

    /// The pyramids of the grids the surface `lod` reads.
    #[inline]
    fn read<'a>(&'a self, lod: &'a LevelSet) -> impl Iterator<Item = &'a Pyramid> + 'a {
        at_levels(&self.pyramids, lod)
    }

    /// The limits of the grids the surface `lod` reads.
    fn read_limits<'a>(&'a self, lod: &'a LevelSet) -> impl Iterator<Item = &'a LayerLimits> + 'a {
        at_levels(&self.limits, lod)
    }

    /// The smallest and largest summed h of the surface `lod` over nominal positions
    /// `[x0, x1] x [z0, z1]`, m.
    #[inline]
    pub fn height(&self, lod: &LevelSet, x0: f64, x1: f64, z0: f64, z1: f64) -> [f64; 2] {
        let (mut b, mut size) = ([0.0f64; 2], 1e-3);
        for p in self.read(lod) {
            let q = p.heights.get(p.blocks(x0, x1, z0, z1));
            b[0] += q[0] as f64;
            b[1] += q[1] as f64;
            size += (q[0].abs().max(q[1].abs())) as f64;
        }
        // f32 texels blended and summed in f32 by the reads: a read can round past the exact
        // sum by a few ulps of each layer's value (layers can cancel, so not of the sum's)
        let slack = 1e-6 * size;
        [b[0] - slack, b[1] + slack]
    }

    /// [`Self::height`] over every surface of the levels held: each layer's range joined over
    /// its levels (and 0, where a layer may be left out).
    pub fn height_any(&self, x0: f64, x1: f64, z0: f64, z1: f64) -> [f64; 2] {
        let (mut b, mut size) = ([0.0f64; 2], 1e-3);
        for levels in &self.pyramids {
            let (mut lo, mut hi) = if self.levels {
                (0.0f32, 0.0f32)
            } else {
                (f32::INFINITY, f32::NEG_INFINITY)
            };
            for p in levels {
                let q = p.heights.get(p.blocks(x0, x1, z0, z1));
                (lo, hi) = (lo.min(q[0]), hi.max(q[1]));
            }
            b[0] += lo as f64;
            b[1] += hi as f64;
            size += (lo.abs().max(hi.abs())) as f64;
        }
        let slack = 1e-6 * size;
        [b[0] - slack, b[1] + slack]
    }

    /// The summed slope and strain bounds of the surface `lod` over nominal positions
    /// `[x0, x1] x [z0, z1]`.
    #[inline]
    pub fn steepness(&self, lod: &LevelSet, x0: f64, x1: f64, z0: f64, z1: f64) -> Steepness {
        let (mut slope, mut strain) = ([0.0; 2], 0.0);
        for p in self.read(lod) {
            let q = p.steep.get(p.blocks(x0, x1, z0, z1));
            // each layer's Gershgorin norm; their sum bounds the summed strain's
            slope[0] += q.slope[0] as f64;
            slope[1] += q.slope[1] as f64;
            strain += q.strain[0] as f64 + q.strain[1] as f64;
        }
        Steepness { slope, strain }
    }

    /// The smallest and largest summed Dx and Dz of the surface `lod` over nominal positions
    /// `[x0, x1] x [z0, z1]`, m: `[Dx min, Dx max, Dz min, Dz max]`.
    #[inline]
    pub fn displacement(&self, lod: &LevelSet, x0: f64, x1: f64, z0: f64, z1: f64) -> [f64; 4] {
        let (mut b, mut size) = ([0.0f64; 4], 1e-3);
        for p in self.read(lod) {
            let q = p.disp.get(p.blocks(x0, x1, z0, z1)).0;
            for (s, v) in b.iter_mut().zip(q) {
                *s += v as f64;
            }
            size += q.iter().fold(0.0f32, |m, v| m.max(v.abs())) as f64;
        }
        // (the reads' f32 rounding, as for h)
        let slack = 1e-6 * size;
        [b[0] - slack, b[1] + slack, b[2] - slack, b[3] + slack]
    }

    /// Largest |Dx| and |Dz| of the surface `lod`, m.
    pub fn disp(&self, lod: &LevelSet) -> [f64; 2] {
        let mut d = [0.0; 2];
        for l in self.read_limits(lod) {
            d[0] += l.disp[0];
            d[1] += l.disp[1];
        }
        d
    }

    /// Largest |h| of the surface `lod`, m.
    pub fn height_limit(&self, lod: &LevelSet) -> f64 {
        self.read_limits(lod).map(|l| l.height).sum()
    }

    /// Largest |Dx|, |Dz| and |h| of any surface of the levels held, m.
    pub fn limits_any(&self) -> ([f64; 2], f64) {
        let mut d = ([0.0; 2], 0.0);
        for levels in &self.limits {
            let most = |f: &dyn Fn(&LayerLimits) -> f64| levels.iter().map(f).fold(0.0, f64::max);
            d.0[0] += most(&|l| l.disp[0]);
            d.0[1] += most(&|l| l.disp[1]);
            d.1 += most(&|l| l.height);
        }
        d
    }

    /// The whole sea's slope and strain bounds for the surface `lod`: each axis's bilinear
    /// slope bound summed over the grids read, and the summed strain's Gershgorin bound (the
    /// largest summed diagonal bound plus the summed off-diagonal one), which is tighter than a
    /// sum of the layers' norms. Its [`Steepness::slope_limit`] is `None` where the strain
    /// bound reaches 0.95 (the bound does not prove the surface is a height field).
    pub fn sea_steepness(&self, lod: &LevelSet) -> Steepness {
        let slope = std::array::from_fn(|k| self.read_limits(lod).map(|l| l.slope[k]).sum());
        let s: [f64; 3] = std::array::from_fn(|k| self.read_limits(lod).map(|l| l.strain[k]).sum());
        Steepness {
            slope,
            strain: s[0].max(s[1]) + s[2],
        }
    }

    /// The finest texel the surface `lod` reads, m (infinite if it reads none).
    pub fn finest_texel(&self, lod: &LevelSet) -> f64 {
        self.read(lod).map(|p| p.dx()).fold(f64::INFINITY, f64::min)
    }

    /// Bytes of the pyramids.
    pub fn bytes(&self) -> usize {
        self.pyramids
            .iter()
            .flatten()
            .map(|p| p.heights.bytes() + p.steep.bytes() + p.disp.bytes())
            .sum()
    }
}
