//! The slope covariance of a realization, layer by layer, and what a footprint leaves of it
//! unresolved: what `filtered` normals read (DESIGN.md, Normal modes). For linear waves the
//! slope (dh/dx, dh/dz) of a set of waves is Gaussian with covariance sum k k^T |h~(k, t)|^2
//! over them (Parseval, with the layers' inverse transform h(x) = sum h~(k) e^(i k.x)), taken
//! here from the realization's own amplitudes at its time (each layer holds its share of the
//! spectrum, so the partition weights are in them).
//!
//! A ray's footprint is a Gaussian of std sigma over the surface. Each layer's resolved waves
//! are read from its low-passed levels ([`crate::ocean::levels`]: level l is the layer's waves
//! times exp(-|k|^2 s^2 / 2), s = 2^l texels, on a grid of that spacing; level 0 the layer
//! itself): the level whose Gaussian is the footprint's, or a blend of the two that bracket it,
//! weighted by log2 sigma's place between them ([`LayerSlopes::level_coordinate`]), so that the
//! split moves smoothly with the footprint. A low-pass keeps the long waves whole and drops the
//! short ones, as the mean of the normals over the footprint does. Scaling a whole layer down
//! by its resolved share instead shrinks the long waves too, which the mesh's own triangles
//! follow, and the by-area lobe that takes their place loses the link between a normal and
//! where a grazing ray can land (measured: filtered normals half a per cent darker than mapped
//! ones near the horizon under `terminate`, docs/filtered.md). What a blend's read keeps of the slopes is
//! tabulated per layer from each level's own waves and read transfer, with the mean product of
//! two neighbouring levels' reads ([`read_cross_transfer`]); the rest of the layer's slopes,
//! the unresolved waves, is a Gaussian slope distribution added to the resolved normal's. Read
//! and unresolved together keep each layer's slope covariance exactly, at any footprint. Past
//! a layer's last level it is not read at all, and all of it is unresolved.
//!
//! The covariance is the sea's ([`SlopeSource::Spectrum`], what the `smith` lobe models) or the
//! slopes as the lookup reads them ([`SlopeSource::Read`]: each wave's term times the power the
//! read keeps of it, [`read_power_transfer`]), what the `mapped` lobe models: it draws the
//! normals the mapped normals of the pixel's own points would have (bilinear reads keep some
//! 11 % less slope variance than the realization's on the default sea; prefiltered ones keep
//! it). The levels' reads are tabulated the same way, with their own grids' transfer.

use rayon::prelude::*;

use rustfft::num_complex::Complex;

use super::layer::{Layer, h_tilde_of, read_cross_transfer, read_power_transfer, signed_index};
use super::{Interp, MAX_LAYERS, Surface};

/// Whose slopes a table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlopeSource {
    /// The realization's own, sum k k^T |h~|^2.
    Spectrum,
    /// As a read with this interpolation returns them, on average over the positions between
    /// grid points.
    Read(Interp),
}

/// The smallest share of a layer's mean square slope a level keeps; past the last level that
/// keeps more, the layer is wholly unresolved and not read.
pub const MIN_RESOLVED_SHARE: f64 = 1e-3;

/// A layer [`Split::levels`] leaves out.
pub const NOT_READ: u8 = u8::MAX;

/// One surface of the layers' levels: per layer, the level it is read from alone (0 its own
/// texels, l > 0 its l-th low-passed level, [`NOT_READ`] left out).
pub type LevelSet = [u8; MAX_LAYERS];

/// Every layer read from its own texels: the whole sea.
pub const ALL_WAVES: LevelSet = [0; MAX_LAYERS];

/// A 2 x 2 slope covariance (xx, xz, zz), m^0.
pub type Cov = [f64; 3];

// The separate passes over one grid that `LayerSlopes::of` makes in one: the tests' oracles.
impl Layer {
    /// This layer's slope covariance, from its amplitudes at its time, of the sea or as read
    /// (`source`).
    #[cfg(test)]
    pub fn slope_cov(&self, source: SlopeSource) -> Cov {
        let n = self.n();
        // The power a read keeps of a wave, per grid index along either axis: a wave of index s
        // advances 2 pi s / n a texel.
        let gain: Vec<f64> = (0..n)
            .map(|i| match source {
                SlopeSource::Spectrum => 1.0,
                SlopeSource::Read(interp) => read_power_transfer(
                    interp,
                    std::f64::consts::TAU * signed_index(i, n) / n as f64,
                ),
            })
            .collect();
        let dk = std::f64::consts::TAU / self.size_m();
        let t = self.time_s();
        // the cells outside the band's reach are zero
        let rows: Vec<usize> = self.band_indices().collect();
        rows.into_par_iter()
            .map(|ix| {
                let kx = signed_index(ix, n) * dk;
                let mut a = [0.0f64; 3];
                let h = self.h_tilde_row(ix, t);
                for iz in self.band_indices() {
                    let p = h(iz).norm_sqr() * gain[ix] * gain[iz];
                    let kz = signed_index(iz, n) * dk;
                    a[0] += kx * kx * p;
                    a[1] += kx * kz * p;
                    a[2] += kz * kz * p;
                }
                a
            })
            .reduce(|| [0.0; 3], |a, b| std::array::from_fn(|c| a[c] + b[c]))
    }
}

impl Layer {
    /// The mean over positions of the product of this layer's slopes and those of `coarser`,
    /// its next level (a grid twice as coarse over the same square, holding the same waves
    /// low-passed), both read with `interp`: the covariance term of a blend of the two
    /// ([`read_cross_transfer`]).
    #[cfg(test)]
    pub fn slope_cross(&self, coarser: &Layer, interp: Interp) -> Cov {
        let (n, m) = (self.n(), coarser.n());
        assert_eq!(n, 2 * m, "the next level's grid is twice as coarse");
        let dk = std::f64::consts::TAU / self.size_m();
        let cross: Vec<_> = (0..n)
            .map(|i| {
                read_cross_transfer(
                    interp,
                    std::f64::consts::TAU * signed_index(i, n) / n as f64,
                )
            })
            .collect();
        let fine = |i: usize| (signed_index(i, m) as i64).rem_euclid(n as i64) as usize;
        let (t, tc) = (self.time_s(), coarser.time_s());
        let rows: Vec<usize> = coarser.band_indices().collect();
        rows.into_par_iter()
            .map(|jx| {
                let kx = signed_index(jx, m) * dk;
                let ix = fine(jx);
                let mut a = [0.0f64; 3];
                let (h, h_coarse) = (self.h_tilde_row(ix, t), coarser.h_tilde_row(jx, tc));
                for jz in coarser.band_indices() {
                    let hc = h_coarse(jz);
                    if hc.norm_sqr() == 0.0 {
                        continue;
                    }
                    let iz = fine(jz);
                    let p = (h(iz) * hc.conj()).re * (cross[ix] * cross[iz]).re;
                    let kz = signed_index(jz, m) * dk;
                    a[0] += kx * kx * p;
                    a[1] += kx * kz * p;
                    a[2] += kz * kz * p;
                }
                a
            })
            .reduce(|| [0.0; 3], |a, b| std::array::from_fn(|c| a[c] + b[c]))
    }
}

/// What a footprint resolves: the levels each layer is read from and the covariance of the
/// slopes left unresolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Per layer, the finer of the two levels its resolved waves are read from: 0 its own
    /// texels, l > 0 its l-th low-passed level, [`NOT_READ`] none.
    pub levels: [u8; MAX_LAYERS],
    /// Per layer, the weight of the coarser of the two (the next level, or none past the
    /// last); the finer has one minus it.
    pub blend: [f32; MAX_LAYERS],
    /// Slope covariance of the unresolved waves (xx, xz, zz).
    pub cov: [f32; 3],
}

impl Split {
    /// Every wave resolved: the mapped normal.
    pub const RESOLVED: Split = Split {
        levels: [0; MAX_LAYERS],
        blend: [0.0; MAX_LAYERS],
        cov: [0.0; 3],
    };
}

/// One layer's slopes: whole, and as each of its levels and each blend of two neighbouring
/// levels reads them.
#[derive(Clone, Debug)]
pub struct LayerSlopes {
    total: Cov,
    /// `own[l]`: the covariance of level l's read (0 the layer's own texels).
    own: Vec<Cov>,
    /// `cross[l]`: the mean product of level l's read and level l + 1's.
    cross: Vec<Cov>,
    /// 2^(log2 dx + 1), dx the layer's grid spacing, m: the footprint that reads level 1 whole
    /// (level l's Gaussian has std 2^l dx), computed once, not at every split.
    level1_sigma_m: f32,
}

impl LayerSlopes {
    /// `layer`'s slopes of `source`, and as its levels (`levels[l - 1]` its level l) and each
    /// blend of two neighbours read them with `interp` (the levels' own grids' transfers), in one
    /// pass over the layer's cells: a level's amplitudes are the layer's times its Gaussian at
    /// the same wavevectors, so each cell reads every grid's pair of amplitudes and computes
    /// e^(i omega t) once. Each term is what a pass over that grid alone adds (the tests'
    /// `Layer::slope_cov` and `Layer::slope_cross`), in the same order along each row; the rows
    /// are summed in order. For the default ocean at rest the passes took 1.24 G instructions and
    /// this takes 1.09 G; at other times, where each turn of a phase costs a dispersion relation
    /// and a sine and cosine, about half the time.
    fn of(layer: &Layer, levels: &[&Layer], source: SlopeSource, interp: Interp) -> LayerSlopes {
        use std::f64::consts::TAU;
        use std::iter::once;
        let read = SlopeSource::Read(interp);
        let grids: Vec<&Layer> = once(layer).chain(levels.iter().copied()).collect();
        let count = levels.len();
        let phase_of = |g: &Layer, i: usize| TAU * signed_index(i, g.n()) / g.n() as f64;
        let gains = |g: &Layer, source: SlopeSource| -> Vec<f64> {
            (0..g.n())
                .map(|i| match source {
                    SlopeSource::Spectrum => 1.0,
                    SlopeSource::Read(interp) => read_power_transfer(interp, phase_of(g, i)),
                })
                .collect()
        };
        let source_gain = gains(layer, source);
        let read_gain: Vec<Vec<f64>> = grids.iter().map(|g| gains(g, read)).collect();
        let cross_gain: Vec<Vec<_>> = grids[..count]
            .iter()
            .map(|g| {
                (0..g.n())
                    .map(|i| read_cross_transfer(interp, phase_of(g, i)))
                    .collect()
            })
            .collect();
        // every signed index below a grid's reach (along either axis) is in its band
        let reach: Vec<i64> = grids.iter().map(|g| g.band_reach() as i64).collect();
        assert!(
            reach.windows(2).all(|r| r[1] <= r[0])
                && levels.iter().all(|g| g.time_s() == layer.time_s()),
            "a level reaches no further than the grid before it, at the layer's time"
        );
        let index = |g: usize, s: i64| s.rem_euclid(grids[g].n() as i64) as usize;
        let (n, dk, t) = (layer.n(), TAU / layer.size_m(), layer.time_s());
        let add = |a: &mut Cov, kx: f64, kz: f64, p: f64| {
            a[0] += kx * kx * p;
            a[1] += kx * kz * p;
            a[2] += kz * kz * p;
        };
        // per row: the total, own[0..=count], cross[0..count]
        let own_at = |g: usize| 1 + g;
        let cross_at = |g: usize| 2 + count + g;
        let rows: Vec<usize> = layer.band_indices().collect();
        // per grid, its index of each of the layer's band indices (the division of
        // `rem_euclid` per cell and grid cost more than the separate passes)
        let columns: Vec<Vec<usize>> = (0..grids.len())
            .map(|g| {
                rows.iter()
                    .map(|&i| index(g, signed_index(i, n) as i64))
                    .collect()
            })
            .collect();
        let signed: Vec<(i64, f64)> = rows
            .iter()
            .map(|&i| (signed_index(i, n) as i64, signed_index(i, n) * dk))
            .collect();
        let sums: Vec<Vec<Cov>> = rows
            .par_iter()
            .map(|&ix| {
                let mut acc = vec![[0.0f64; 3]; 2 + 2 * count];
                let sx = signed_index(ix, n) as i64;
                let kx = signed_index(ix, n) * dk;
                let pairs: Vec<_> = grids
                    .iter()
                    .enumerate()
                    .take_while(|&(g, _)| sx.abs() < reach[g])
                    .map(|(g, grid)| grid.h0_pair_row(index(g, sx)))
                    .collect();
                let row_of: Vec<usize> = (0..pairs.len()).map(|g| index(g, sx)).collect();
                let phase = layer.phase_row(ix, t);
                for (j, (&iz, &(sz, kz))) in rows.iter().zip(&signed).enumerate() {
                    let mut e = None;
                    let mut finer = Complex::<f64>::default();
                    for (g, pair) in pairs.iter().enumerate() {
                        if sz.abs() >= reach[g] {
                            break;
                        }
                        let (gx, gz) = (row_of[g], columns[g][j]);
                        let h = match pair(gz) {
                            Some((a, b)) => h_tilde_of(a, b, *e.get_or_insert_with(|| phase(iz))),
                            None => Complex::default(),
                        };
                        let power = h.norm_sqr();
                        if g == 0 {
                            add(
                                &mut acc[0],
                                kx,
                                kz,
                                power * source_gain[gx] * source_gain[gz],
                            );
                        }
                        if g > 0 || source != read {
                            let p = power * read_gain[g][gx] * read_gain[g][gz];
                            add(&mut acc[own_at(g)], kx, kz, p);
                        }
                        if g > 0 && power != 0.0 {
                            let c = &cross_gain[g - 1];
                            let (fx, fz) = (row_of[g - 1], columns[g - 1][j]);
                            let p = (finer * h.conj()).re * (c[fx] * c[fz]).re;
                            add(&mut acc[cross_at(g - 1)], kx, kz, p);
                        }
                        finer = h;
                    }
                }
                acc
            })
            .collect();
        let sum = |j: usize| -> Cov {
            sums.iter()
                .fold([0.0; 3], |a, r| std::array::from_fn(|c| a[c] + r[j][c]))
        };
        let total = sum(0);
        LayerSlopes {
            total,
            own: (0..=count)
                .map(|g| {
                    if g == 0 && source == read {
                        total
                    } else {
                        sum(own_at(g))
                    }
                })
                .collect(),
            cross: (0..count).map(|g| sum(cross_at(g))).collect(),
            level1_sigma_m: (layer.dx().log2() as f32 + 1.0).exp2(),
        }
    }

    /// The covariance of all the layer's waves.
    pub fn total(&self) -> Cov {
        self.total
    }

    /// How many levels past its own texels a footprint can read (then none).
    pub fn levels(&self) -> usize {
        self.own.len() - 1
    }

    /// The covariance a read of level `l` blended with the next (weight `t`; past the last
    /// level, with nothing) keeps: (1 - t)^2 own_l + 2 t (1 - t) cross_l + t^2 own_(l+1).
    pub fn resolved(&self, l: usize, t: f64) -> Cov {
        let last = self.levels();
        if l > last {
            return [0.0; 3];
        }
        let (a, b) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t));
        std::array::from_fn(|c| {
            let mut r = a * self.own[l][c];
            if l < last {
                r += b * self.cross[l][c] + t * t * self.own[l + 1][c];
            }
            r
        })
    }

    /// The covariance left unresolved where [`LayerSlopes::resolved`] is read.
    pub fn unresolved(&self, l: usize, t: f64) -> Cov {
        difference(self.total, self.resolved(l, t))
    }

    /// The level coordinate of a footprint of std `sigma_m`: level l >= 1 is read whole where
    /// its Gaussian is the footprint's (2^l grid spacings), and the coordinate is log2 of sigma
    /// from there (a fraction blends two levels); below level 1 it runs linearly in sigma from
    /// the layer's own texels at a footprint of zero, whose read leaves the short waves at one
    /// minus the fraction of their amplitude. At most one past the last level: not read.
    pub fn level_coordinate(&self, sigma_m: f32) -> f32 {
        let x = sigma_m / self.level1_sigma_m;
        let l = if x <= 1.0 { x.max(0.0) } else { 1.0 + x.log2() };
        l.min((self.levels() + 1) as f32)
    }
}

/// The slopes of every layer of a surface.
#[derive(Clone, Debug)]
pub struct SurfaceSlopes {
    layers: Vec<LayerSlopes>,
}

/// `a - b`, kept a covariance: rounding (and a read that keeps a little more of a wave than the
/// sea has, which Catmull-Rom's can) is not allowed to leave a negative variance.
fn difference(a: Cov, b: Cov) -> Cov {
    let (xx, zz) = ((a[0] - b[0]).max(0.0), (a[2] - b[2]).max(0.0));
    let bound = (xx * zz).sqrt();
    [xx, (a[1] - b[1]).clamp(-bound, bound), zz]
}

impl SurfaceSlopes {
    /// The surface's layers' slopes of `source` and as each of their levels and blends (as
    /// the surface reads them, `params.interp`) keeps them, for its time. Builds the levels
    /// ([`Surface::levels`]) if they are not yet.
    pub fn new(surface: &Surface, source: SlopeSource) -> SurfaceSlopes {
        let levels = surface.levels();
        let interp = surface.params().interp;
        let layers = surface
            .layers()
            .iter()
            .enumerate()
            .map(|(i, layer)| {
                let levels: Vec<&Layer> =
                    (1..=levels.count(i)).map(|l| levels.level(i, l)).collect();
                LayerSlopes::of(layer, &levels, source, interp)
            })
            .collect();
        SurfaceSlopes { layers }
    }

    pub fn layers(&self) -> &[LayerSlopes] {
        &self.layers
    }

    /// The total slope covariance of all layers (the mean square slope is xx + zz).
    pub fn total(&self) -> Cov {
        self.layers.iter().fold([0.0; 3], |a, l| {
            let t = l.total();
            std::array::from_fn(|c| a[c] + t[c])
        })
    }

    /// What a Gaussian footprint of std `sigma_m` resolves ([`LayerSlopes::level_coordinate`]
    /// per layer). A footprint of zero (or below) resolves every wave: the mapped normal.
    pub fn split(&self, sigma_m: f32) -> Split {
        if sigma_m.is_nan() || sigma_m <= 0.0 {
            return Split::RESOLVED;
        }
        let mut s = Split::RESOLVED;
        let mut cov = [0.0f64; 3];
        for ((level, blend), l) in s.levels.iter_mut().zip(&mut s.blend).zip(&self.layers) {
            let x = l.level_coordinate(sigma_m);
            // x is finite and at least 0: its floor by truncation (`floor` is a library call
            // on the baseline x86-64 target)
            let a = x as u32;
            let t = x - a as f32;
            let a = a as usize;
            (*level, *blend) = if a > l.levels() {
                (NOT_READ, 0.0)
            } else {
                (a as u8, t)
            };
            let u = l.unresolved(a, t as f64);
            for c in 0..3 {
                cov[c] += u[c];
            }
        }
        s.cov = cov.map(|v| v as f32);
        s
    }
}

impl SurfaceSlopes {
    /// One surface for a footprint of std `sigma_m`, where [`Self::split`] blends two levels
    /// of each layer: each layer read whole from one of them, the coarser where `u` (uniform
    /// in [0, 1), one number for every layer) falls below its blend weight, so that on average
    /// over `u` each level counts with the split's weight. The exact surface meets one surface
    /// per path ([`crate::accel::exact`]), which a blend of two is not.
    pub fn drawn_levels(&self, sigma_m: f32, u: f32) -> LevelSet {
        let mut levels = ALL_WAVES;
        if sigma_m.is_nan() || sigma_m <= 0.0 {
            return levels;
        }
        for (level, l) in levels.iter_mut().zip(&self.layers) {
            let x = l.level_coordinate(sigma_m);
            // (x is finite and at least 0: floored by truncation, as in `split`)
            let a = x as u32;
            let a = a as usize + usize::from(u < x - a as f32);
            *level = if a > l.levels() { NOT_READ } else { a as u8 };
        }
        levels
    }

    /// What the surface `levels` resolves, as a split without blends: those levels, and the
    /// slope covariance of the waves they leave out.
    pub fn split_of(&self, levels: &LevelSet) -> Split {
        let mut s = Split {
            levels: *levels,
            ..Split::RESOLVED
        };
        let mut cov = [0.0f64; 3];
        for (&level, l) in levels.iter().zip(&self.layers) {
            let a = if level == NOT_READ {
                l.levels() + 1
            } else {
                level as usize
            };
            let u = l.unresolved(a, 0.0);
            for c in 0..3 {
                cov[c] += u[c];
            }
        }
        s.cov = cov.map(|v| v as f32);
        s
    }
}

#[cfg(test)]
#[path = "slopes_tests.rs"]
mod tests;
