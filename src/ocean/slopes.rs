//! The slope covariance of a realization by wavenumber band: what `filtered` normals read
//! (DESIGN.md, Normal modes). For linear waves the slope (dh/dx, dh/dz) of the waves in a band
//! is Gaussian with covariance sum over the band of k k^T |h~(k, t)|^2 (Parseval, with the
//! layers' inverse transform h(x) = sum h~(k) e^(i k.x)), taken here from the realization's own
//! amplitudes at its time, layer by layer (each layer holds its share of the spectrum, so the
//! partition weights are in them).
//!
//! A ray's footprint of width w resolves the waves longer than two footprints, |k| < pi / w
//! ([`SurfaceSlopes::split`]): the waves above that cut-off become a Gaussian slope
//! distribution of the summed covariance of every layer's part above it; each layer's field
//! is kept scaled by the square root of the share of its slope variance below the cut-off, so
//! that the resolved slope and the unresolved distribution together keep each layer's slope
//! variance. A layer whose waves all lie above the cut-off is not read at all. The cumulative
//! covariance is tabulated at [`BINS_PER_OCTAVE`] bins an octave and interpolated linearly in
//! log k, so the split moves smoothly with the footprint: no line where a layer switches off.

use rayon::prelude::*;

use super::layer::{Layer, signed_index};
use super::{MAX_LAYERS, Surface};

/// Resolution of the cumulative tables.
pub const BINS_PER_OCTAVE: usize = 8;

/// A 2 x 2 slope covariance (xx, xz, zz), m^0.
pub type Cov = [f64; 3];

/// One layer's slope covariance above each wavenumber of a log-spaced table.
#[derive(Clone, Debug)]
pub struct SlopeBands {
    /// ln of the table's first wavenumber, rad/m.
    ln_k0: f64,
    /// `above[i]`: the covariance of the waves with |k| >= k0 2^(i / BINS_PER_OCTAVE); the last
    /// entry is zero (past every wave of the layer).
    above: Vec<Cov>,
}

impl SlopeBands {
    /// The covariance of all the layer's waves.
    pub fn total(&self) -> Cov {
        self.above[0]
    }

    /// The covariance of the layer's waves with |k| >= `k` (linear in log k between nodes).
    pub fn above(&self, k: f64) -> Cov {
        let x = (k.ln() - self.ln_k0) * BINS_PER_OCTAVE as f64 / std::f64::consts::LN_2;
        if x.is_nan() || x <= 0.0 {
            return self.above[0];
        }
        let last = self.above.len() - 1;
        if x >= last as f64 {
            return [0.0; 3];
        }
        let (i, f) = (x.floor() as usize, x.fract());
        std::array::from_fn(|c| self.above[i][c] * (1.0 - f) + self.above[i + 1][c] * f)
    }
}

impl Layer {
    /// This layer's slope covariance by band, from its amplitudes at its time.
    pub fn slope_bands(&self) -> SlopeBands {
        let n = self.n();
        let dk = std::f64::consts::TAU / self.size_m();
        let (k_min, k_max) = self.band();
        // From the band's first wavenumber (or the grid's) past its last, so every wave is
        // counted in some bin and the last node is past all of them.
        let k0 = k_min.max(dk) * 0.999;
        let octaves = (k_max * std::f64::consts::SQRT_2 / k0).log2().max(1.0);
        let bins = (octaves * BINS_PER_OCTAVE as f64).ceil() as usize + 1;
        let ln_k0 = k0.ln();
        let t = self.time_s();
        let per_bin = (0..n)
            .into_par_iter()
            .fold(
                || vec![[0.0f64; 3]; bins],
                |mut acc, ix| {
                    let kx = signed_index(ix, n) * dk;
                    for iz in 0..n {
                        let h = self.h_tilde(ix, iz, t);
                        let p = h.norm_sqr();
                        if p == 0.0 {
                            continue;
                        }
                        let kz = signed_index(iz, n) * dk;
                        let k = kx.hypot(kz);
                        let b = ((k.ln() - ln_k0) * BINS_PER_OCTAVE as f64 / std::f64::consts::LN_2)
                            .floor()
                            .clamp(0.0, (bins - 2) as f64) as usize;
                        let a = &mut acc[b];
                        a[0] += kx * kx * p;
                        a[1] += kx * kz * p;
                        a[2] += kz * kz * p;
                    }
                    acc
                },
            )
            .reduce(
                || vec![[0.0f64; 3]; bins],
                |mut a, b| {
                    for (a, b) in a.iter_mut().zip(b) {
                        for c in 0..3 {
                            a[c] += b[c];
                        }
                    }
                    a
                },
            );
        // Bin b holds the waves between nodes b and b + 1: the covariance above node i is the
        // sum of bins i.. (the interpolation between nodes spreads each bin over its width).
        let mut above = vec![[0.0f64; 3]; bins];
        for i in (0..bins - 1).rev() {
            above[i] = std::array::from_fn(|c| above[i + 1][c] + per_bin[i][c]);
        }
        SlopeBands { ln_k0, above }
    }
}

/// What a footprint resolves: each layer's weight on its mapped fields and the covariance of
/// the slopes left unresolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    /// Per layer, in [0, 1]: the square root of the share of its slope variance resolved.
    pub weights: [f32; MAX_LAYERS],
    /// Slope covariance of the unresolved waves (xx, xz, zz).
    pub cov: [f32; 3],
}

impl Split {
    /// Every wave resolved: the mapped normal.
    pub const RESOLVED: Split = Split {
        weights: [1.0; MAX_LAYERS],
        cov: [0.0; 3],
    };
}

/// The slope bands of every layer of a surface.
#[derive(Clone, Debug)]
pub struct SurfaceSlopes {
    layers: Vec<SlopeBands>,
}

impl SurfaceSlopes {
    /// The surface's layers' tables (in parallel); for its time.
    pub fn new(surface: &Surface) -> SurfaceSlopes {
        SurfaceSlopes {
            layers: surface
                .layers()
                .par_iter()
                .map(Layer::slope_bands)
                .collect(),
        }
    }

    pub fn layers(&self) -> &[SlopeBands] {
        &self.layers
    }

    /// The total slope covariance of all layers (the mean square slope is xx + zz).
    pub fn total(&self) -> Cov {
        self.layers.iter().fold([0.0; 3], |a, l| {
            let t = l.total();
            std::array::from_fn(|c| a[c] + t[c])
        })
    }

    /// What a footprint `width_m` wide resolves: waves with |k| < pi / width_m (twice the
    /// width per wavelength). A width of zero (or below) resolves every wave.
    pub fn split(&self, width_m: f32) -> Split {
        if width_m.is_nan() || width_m <= 0.0 {
            return Split::RESOLVED;
        }
        let k_cut = std::f64::consts::PI / width_m as f64;
        let mut s = Split::RESOLVED;
        let mut cov = [0.0f64; 3];
        for (w, l) in s.weights.iter_mut().zip(&self.layers) {
            let (total, above) = (l.total(), l.above(k_cut));
            let t = total[0] + total[2];
            if t > 0.0 {
                let resolved = (1.0 - (above[0] + above[2]) / t).clamp(0.0, 1.0);
                *w = resolved.sqrt() as f32;
            }
            for c in 0..3 {
                cov[c] += above[c];
            }
        }
        s.cov = cov.map(|v| v as f32);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ocean::OceanParams;

    fn surface() -> Surface {
        Surface::new(&OceanParams::default(), 1).unwrap()
    }

    #[test]
    fn the_bands_sum_to_the_grid_slope_variance() {
        // Parseval: the mean of (dh/dx)^2 over a layer's grid is the sum of kx^2 |h~|^2.
        let s = surface();
        let slopes = SurfaceSlopes::new(&s);
        for (layer, bands) in s.layers().iter().zip(slopes.layers()) {
            let f = layer.fields();
            let mean = |i: usize, j: usize| {
                f.iter().map(|t| t[i] as f64 * t[j] as f64).sum::<f64>() / f.len() as f64
            };
            use crate::ocean::field::{DH_DX, DH_DZ};
            let grid = [mean(DH_DX, DH_DX), mean(DH_DX, DH_DZ), mean(DH_DZ, DH_DZ)];
            let total = bands.total();
            let scale = grid[0] + grid[2];
            for c in 0..3 {
                assert!(
                    (total[c] - grid[c]).abs() < 1e-4 * scale,
                    "layer of {} m: {total:?} vs grid {grid:?}",
                    layer.size_m()
                );
            }
        }
    }

    #[test]
    fn the_split_resolves_all_at_zero_width_and_nothing_at_a_huge_one() {
        let slopes = SurfaceSlopes::new(&surface());
        assert_eq!(slopes.split(0.0), Split::RESOLVED);
        let far = slopes.split(1e6);
        let total = slopes.total();
        for (w, _) in far.weights.iter().zip(slopes.layers()) {
            assert_eq!(*w, 0.0);
        }
        for c in 0..3 {
            assert!((far.cov[c] as f64 - total[c]).abs() <= 1e-6 * (total[0] + total[2]));
        }
    }

    #[test]
    fn the_split_moves_smoothly_and_keeps_each_layers_variance() {
        // Resolved (weight^2 x the layer's total) plus unresolved is the layer's total, at any
        // width; the unresolved part only grows with the width, without a jump.
        let slopes = SurfaceSlopes::new(&surface());
        let mut last = 0.0f64;
        let total = slopes.total();
        let tr = total[0] + total[2];
        for i in 0..400 {
            let w = 1e-3 * 1.03f32.powi(i);
            let s = slopes.split(w);
            let resolved: f64 = s
                .weights
                .iter()
                .zip(slopes.layers())
                .map(|(w, l)| (*w as f64).powi(2) * (l.total()[0] + l.total()[2]))
                .sum();
            let unresolved = (s.cov[0] + s.cov[2]) as f64;
            assert!((resolved + unresolved - tr).abs() < 1e-5 * tr, "width {w}");
            assert!(unresolved >= last - 1e-7 * tr, "width {w}");
            assert!(
                unresolved - last < 0.05 * tr,
                "a jump of the split at width {w}"
            );
            last = unresolved;
        }
    }
}
