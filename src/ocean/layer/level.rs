//! A layer low-passed: the same waves, each times a Gaussian exp(-|k|^2 s^2 / 2) of std s, on a
//! coarser grid over the same square. What filtered normals read for the waves a footprint
//! resolves ([`crate::ocean::levels`]): a low-pass keeps the long waves whole (they are the
//! ones the mesh's own triangles follow, and where a grazing ray lands depends on them) and
//! drops the short ones, where scaling a whole layer down would shrink both alike.

use std::f64::consts::TAU;

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
        let mut h0 = vec![C32::default(); cells.width * cells.width];
        let mut power = 0.0f64;
        for cx in 0..cells.width {
            let sx = signed_index(cells.grid_index(cx), n);
            for cz in 0..cells.width {
                let sz = signed_index(cells.grid_index(cz), n);
                let h = self.h0_signed(sx, sz);
                if h == C32::default() {
                    continue;
                }
                let k2 = (sx * sx + sz * sz) * dk * dk;
                let g = (-0.5 * k2 * s * s).exp() as f32;
                let h = h * g;
                power += h.norm_sqr() as f64;
                h0[cx * cells.width + cz] = h;
            }
        }
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

    /// h0 of the cell of signed indices (sx, sz), zero outside the band's reach.
    fn h0_signed(&self, sx: f64, sz: f64) -> C32 {
        let (n, c) = (self.n as i64, &self.cells);
        let index = |s: f64| (s as i64).rem_euclid(n) as usize;
        let (ix, iz) = (index(sx), index(sz));
        if (sx.abs() as i64) < n / 2 && (sz.abs() as i64) < n / 2 && c.inside(ix) && c.inside(iz) {
            self.h0[c.compact_index(ix) * c.width + c.compact_index(iz)]
        } else {
            C32::default()
        }
    }
}
