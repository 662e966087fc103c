//! Every layer low-passed at octave steps: level l of a layer holds its waves times a Gaussian
//! of std 2^l texels, on a grid of that spacing (`Layer::low_passed_in`), a third of the
//! layer's memory in all. Filtered normals read the waves a footprint resolves from the two
//! levels whose Gaussians bracket the footprint's, blended
//! ([`crate::ocean::slopes::SurfaceSlopes::split`] says which and how), so that a resolved
//! normal keeps the long waves whole and leaves out the short ones, as the average of the
//! normals over the footprint does.

use rustfft::FftPlanner;

use super::Interp;
use super::layer::{FIELD_COUNT, FieldPlanes, Layer, Texel, add_texel, slopes};
use super::slopes::{LevelSet, MIN_RESOLVED_SHARE, NOT_READ, Split};
use super::surface::{Sampler, normal_from_slopes};

/// The coarsest level's grid, texels a side.
const MIN_LEVEL_N: usize = 4;

/// Each layer's low-passed levels (level 0, the layer itself, is not held here).
pub struct Levels {
    layers: Vec<Vec<Layer>>,
}

impl Levels {
    /// The levels of each of `layers`, down to the first that keeps less than
    /// [`MIN_RESOLVED_SHARE`] of its layer's mean square slope (not kept: past the last level
    /// a layer is not read at all) or a grid of [`MIN_LEVEL_N`] texels.
    pub fn new(layers: &[Layer]) -> Levels {
        let mut planes = FieldPlanes::default();
        let mut planner = FftPlanner::new();
        let layers = layers
            .iter()
            .map(|layer| {
                let mss = layer.grid_stats().mss;
                let mut levels = Vec::new();
                for l in 1u32.. {
                    if layer.n() >> l < MIN_LEVEL_N {
                        break;
                    }
                    let level = layer.low_passed_in(l, &mut planes, &mut planner);
                    // (a NaN slope ends the levels too)
                    let keeps = level.grid_stats().mss;
                    if keeps.is_nan() || keeps < MIN_RESOLVED_SHARE * mss {
                        break;
                    }
                    levels.push(level);
                }
                levels
            })
            .collect();
        Levels { layers }
    }

    /// How many levels layer `i` has past itself.
    pub fn count(&self, i: usize) -> usize {
        self.layers[i].len()
    }

    /// Level `l` >= 1 of layer `i`.
    pub fn level(&self, i: usize, l: usize) -> &Layer {
        &self.layers[i][l - 1]
    }

    /// Bytes of the levels' gridded fields.
    pub fn bytes(&self) -> usize {
        self.layers
            .iter()
            .flatten()
            .map(|l| std::mem::size_of_val(l.fields()))
            .sum()
    }
}

impl<'a> Sampler<'a> {
    /// This sampler, reading `levels` where a split asks for them ([`Sampler::normals_split`]).
    pub fn with_levels(mut self, levels: &'a Levels) -> Sampler<'a> {
        self.levels = Some(levels);
        self
    }

    /// The levels a split past a layer's own texels reads: a sampler without them cannot
    /// blend, and reading the layer alone would leave the tables' resolved share wrong.
    fn levels_of(&self) -> &'a Levels {
        self.levels
            .expect("a split past a layer's own texels needs a sampler with_levels")
    }

    /// [`Sampler::fields_f64`] of the surface `levels`: layer i read from its level
    /// `levels[i]` alone (at the grid coordinates [`Sampler::normals_split`] reads it at), or
    /// left out; with every level 0 ([`super::slopes::ALL_WAVES`]), [`Sampler::fields_f64`].
    /// A level past 0 needs a sampler [`Sampler::with_levels`].
    #[inline]
    pub fn fields_f64_at(&self, u: f64, v: f64, levels: &LevelSet) -> Texel {
        let mut f = [0.0f32; FIELD_COUNT];
        for (i, (layer, o)) in self.layers.iter().zip(&self.origin).enumerate() {
            let l = levels[i];
            if l == NOT_READ {
                continue;
            }
            let inv = layer.inv_dx();
            let (px, pz) = (o[0] + u * inv, o[1] + v * inv);
            if l == 0 {
                add_texel(&mut f, &layer.read(px, pz, self.interp));
            } else {
                let scale = 0.5f64.powi(l as i32);
                let level = self.levels_of().level(i, l as usize);
                add_texel(&mut f, &level.read(px * scale, pz * scale, self.interp));
            }
        }
        f
    }

    /// The unit normals at the points `uv` with each layer read as `split[i]` says for point
    /// i: from its level `levels` (0: the layer itself, [`NOT_READ`]: left out) with weight one
    /// minus `blend`, and from the next with weight `blend` (past the last level: nothing). With
    /// every split [`Split::RESOLVED`], bit for bit [`Sampler::normals`]. A level past 0 needs
    /// a sampler [`Sampler::with_levels`].
    pub fn normals_split(&self, uv: &[[f32; 2]], split: &[Split], out: &mut [[f32; 3]]) {
        assert!(
            uv.len() == out.len() && split.len() == uv.len(),
            "one normal per point"
        );
        for ((uv, split), out) in uv.chunks(8).zip(split.chunks(8)).zip(out.chunks_mut(8)) {
            let count = uv.len();
            // (lanes past `count` at (0, 0))
            let uv: [[f32; 2]; 8] = std::array::from_fn(|p| uv.get(p).copied().unwrap_or_default());
            let mut sum = [[0.0f32; FIELD_COUNT]; 8];
            for (i, (layer, o)) in self.layers.iter().zip(&self.origin).enumerate() {
                // The points' texel coordinates in the layer itself, once for all its levels.
                let inv = layer.inv_dx();
                let own: [[f64; 8]; 2] =
                    std::array::from_fn(|c| std::array::from_fn(|p| o[c] + uv[p][c] as f64 * inv));
                // Each point's reads: (level, weight), the finer and the coarser.
                let reads = |p: usize| -> [(usize, f32); 2] {
                    let (l, t) = (split[p].levels[i], split[p].blend[i]);
                    if l == NOT_READ {
                        return [(usize::MAX, 0.0); 2];
                    }
                    let l = l as usize;
                    let coarser = if t > 0.0 && l < self.levels_of().count(i) {
                        l + 1
                    } else {
                        usize::MAX
                    };
                    [(l, 1.0 - t), (coarser, t)]
                };
                // each level read once for every point that reads it (rarely more than three)
                let mut todo: [[(usize, f32); 2]; 8] = std::array::from_fn(|p| {
                    if p < count {
                        reads(p)
                    } else {
                        [(usize::MAX, 0.0); 2]
                    }
                });
                while let Some(l) = todo[..count]
                    .iter()
                    .flatten()
                    .map(|r| r.0)
                    .find(|&l| l != usize::MAX)
                {
                    let level = if l == 0 {
                        layer
                    } else {
                        self.levels_of().level(i, l)
                    };
                    // Level l's grid is 2^l times coarser over the same square: its texel
                    // coordinates are the layer's divided by 2^l, exactly.
                    let scale = 0.5f64.powi(l as i32);
                    let at = |p: usize, c: usize| own[c][p] * scale;
                    let mut t = [[0.0f32; FIELD_COUNT]; 8];
                    if self.interp == Interp::Bicubic {
                        for (p, t) in t.iter_mut().enumerate().take(count) {
                            *t = level.read(at(p, 0), at(p, 1), self.interp);
                        }
                    } else {
                        let px = std::array::from_fn(|p| at(p, 0));
                        let pz = std::array::from_fn(|p| at(p, 1));
                        let preserve = self.interp == Interp::VariancePreserving;
                        level.add_bilinear_lanes::<8>(&px, &pz, count, preserve, &mut t);
                    }
                    for (p, reads) in todo[..count].iter_mut().enumerate() {
                        for r in reads.iter_mut().filter(|r| r.0 == l) {
                            if r.1 == 1.0 {
                                add_texel(&mut sum[p], &t[p]);
                            } else {
                                add_texel(&mut sum[p], &t[p].map(|v| v * r.1));
                            }
                            r.0 = usize::MAX;
                        }
                    }
                }
            }
            for (n, s) in out.iter_mut().zip(&sum) {
                *n = normal_from_slopes(slopes(s as &Texel)).0;
            }
        }
    }
}
