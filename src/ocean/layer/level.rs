//! A layer low-passed: the same waves, each times a Gaussian exp(-|k|^2 s^2 / 2) of std s, on a
//! coarser grid over the same square. What filtered normals read for the waves a footprint
//! resolves ([`crate::ocean::levels`]): a low-pass keeps the long waves whole (they are the
//! ones the mesh's own triangles follow, and where a grazing ray lands depends on them) and
//! drops the short ones, where scaling a whole layer down would shrink both alike.

use std::f64::consts::TAU;

use rayon::prelude::*;
use rustfft::FftPlanner;

use super::amplitudes::BandCells;
use super::fields::FieldPlanes;
use super::{C32, GridStats, Layer, signed_index};

impl Layer {
    /// Level `l` >= 1 of this layer: its amplitudes times exp(-|k|^2 s^2 / 2), s = 2^l times
    /// its grid spacing, on an n / 2^l grid (whose spacing is s) over the same square, read
    /// as this layer is (prefiltered or not), with its fields computed at this layer's time in
    /// `planes`, its transform planned by `planner` (one for all levels). The Gaussian is
    /// 0.007 at the coarser grid's Nyquist wavenumber, where the waves it cannot hold are
    /// dropped.
    pub(crate) fn low_passed_in(
        &self,
        l: u32,
        planes: &mut FieldPlanes,
        planner: &mut FftPlanner<f32>,
    ) -> Layer {
        let n = self.n >> l;
        assert!(l >= 1 && n >= 4, "level {l} of a {}-texel layer", self.n);
        let dk = TAU / self.size_m;
        let s = self.dx() * (1u64 << l) as f64;
        let k_max = self.k_max.min(0.5 * n as f64 * dk);
        let cells = BandCells::new(n, dk, k_max);
        // exp(-|k|^2 s^2 / 2) is the product of one Gaussian per axis, tabulated once per
        // axis: an exp per cell made this loop most of a filtered render's set-up.
        let gauss: Vec<f64> = (0..cells.width)
            .map(|c| {
                let k = signed_index(cells.grid_index(c), n) * dk;
                (-0.5 * k * k * s * s).exp()
            })
            .collect();
        // The level reaches no further than the layer (its k_max is at most the layer's), so
        // each of its rows is the layer's row of the same signed index, cut to the level's
        // columns: the layer's compact index of each of the level's, per axis.
        let (width, layer_width) = (cells.width, self.cells.width);
        assert!(
            cells.reach() <= self.cells.reach(),
            "a level reaches no further than its layer"
        );
        let of_layer: Vec<usize> = (0..width)
            .map(|c| {
                let s = signed_index(cells.grid_index(c), n) as i64;
                let i = s.rem_euclid(self.n as i64) as usize;
                self.cells.compact_index(i)
            })
            .collect();
        // each row on its own core; the power summed after, in cell order
        let mut h0 = vec![C32::default(); width * width];
        h0.par_chunks_mut(width).enumerate().for_each(|(cx, row)| {
            let layer_row = &self.h0[of_layer[cx] * layer_width..][..layer_width];
            for (cz, cell) in row.iter_mut().enumerate() {
                *cell = layer_row[of_layer[cz]] * (gauss[cx] * gauss[cz]) as f32;
            }
        });
        let power: f64 = h0.iter().map(|h| h.norm_sqr() as f64).sum();
        let mut level = Layer {
            size_m: self.size_m,
            n,
            k_min: self.k_min,
            k_max,
            choppiness: self.choppiness,
            time_s: self.time_s,
            h0,
            cells,
            depth_m: self.depth_m,
            // E|h0|^2 is half a cell's integral of P: this is the level's own realization's
            expected_variance: 2.0 * power,
            fields: Vec::new(),
            grid: GridStats::default(),
            lag_correlations: std::sync::OnceLock::new(),
            prefilter: self.prefilter,
            fft: planner.plan_fft_inverse(n),
            inv_dx: n as f64 / self.size_m,
        };
        level.compute_fields_in(self.time_s, planes);
        level
    }
}
