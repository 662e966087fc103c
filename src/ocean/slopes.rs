//! The slope covariance of a realization by wavenumber band: what `filtered` normals read
//! (DESIGN.md, Normal modes). For linear waves the slope (dh/dx, dh/dz) of the waves in a band
//! is Gaussian with covariance sum over the band of k k^T |h~(k, t)|^2 (Parseval, with the
//! layers' inverse transform h(x) = sum h~(k) e^(i k.x)), taken here from the realization's own
//! amplitudes at its time, layer by layer (each layer holds its share of the spectrum, so the
//! partition weights are in them).
//!
//! A ray's footprint is a Gaussian of std sigma over the surface ([`SurfaceSlopes::split`]): a
//! wave of wavenumber k seen through it keeps exp(-|k|^2 sigma^2) of its slope variance (the
//! squared transfer function of the filter), and the rest, the variance the wave's slope has
//! inside the footprint, becomes a Gaussian slope distribution: the summed covariance of every
//! layer's filtered-out part. Each layer's field is kept scaled by the square root of the share
//! of its slope variance the filter passes, so that the resolved slope and the unresolved
//! distribution together keep each layer's slope variance. A layer the footprint filters out
//! completely is not read at all. The filtered covariance is tabulated for footprints at
//! [`BINS_PER_OCTAVE`] steps an octave, from the realization binned at as many bins an octave
//! of |k|, and interpolated linearly in log sigma: the split moves smoothly with the footprint,
//! with no line where a layer switches off.
//!
//! The tables hold the slopes of the sea ([`SlopeSource::Spectrum`], what the `smith` lobe
//! models) or the slopes as the lookup reads them ([`SlopeSource::Read`]: each wave's term times
//! the power the read keeps of it, [`read_power_transfer`]), what the `mapped` lobe models: it
//! draws the normals the mapped normals of the pixel's own points would have, and bilinear reads
//! keep some 11 % less slope variance than the realization's on the default sea.

use rayon::prelude::*;

use super::layer::{Layer, read_power_transfer, signed_index};
use super::{Interp, MAX_LAYERS, Surface};

/// Whose slopes a [`SlopeBands`] table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlopeSource {
    /// The realization's own, sum k k^T |h~|^2.
    Spectrum,
    /// As a read with this interpolation returns them, on average over the positions between
    /// grid points.
    Read(Interp),
}

/// The smallest share of a layer's slope variance a footprint keeps as mapped normals; below
/// it the layer is wholly unresolved and not read (`Sampler::normals_weighted`).
pub const MIN_RESOLVED_SHARE: f64 = 1e-3;

/// Resolution of the tables.
pub const BINS_PER_OCTAVE: usize = 8;

/// A 2 x 2 slope covariance (xx, xz, zz), m^0.
pub type Cov = [f64; 3];

/// One layer's slope covariance, whole and as seen through Gaussian footprints of a range of
/// widths.
#[derive(Clone, Debug)]
pub struct SlopeBands {
    /// ln of the wavenumber whose reciprocal is the first node's footprint std, rad/m.
    ln_k0: f64,
    total: Cov,
    /// `resolved[i]`: the covariance of the slope averaged over a Gaussian footprint of std
    /// 1 / (k0 2^(i / BINS_PER_OCTAVE)) m, sum over the waves of exp(-|k|^2 s^2) k k^T |h~|^2.
    resolved: Vec<Cov>,
}

impl SlopeBands {
    /// The covariance of all the layer's waves.
    pub fn total(&self) -> Cov {
        self.total
    }

    /// The covariance of the slope averaged over a Gaussian footprint of std `sigma_m` (linear
    /// in log sigma between nodes; all of it below the table, none above).
    pub fn resolved(&self, sigma_m: f64) -> Cov {
        let x = (-sigma_m.ln() - self.ln_k0) * BINS_PER_OCTAVE as f64 / std::f64::consts::LN_2;
        let last = self.resolved.len() - 1;
        if x.is_nan() || x <= 0.0 {
            return [0.0; 3];
        }
        if x >= last as f64 {
            return self.total;
        }
        let (i, f) = (x.floor() as usize, x.fract());
        std::array::from_fn(|c| self.resolved[i][c] * (1.0 - f) + self.resolved[i + 1][c] * f)
    }
}

impl Layer {
    /// This layer's slope covariance by band, from its amplitudes at its time, of the sea or as
    /// read (`source`).
    pub fn slope_bands(&self, source: SlopeSource) -> SlopeBands {
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
        let (k_min, k_max) = self.band();
        // From the band's first wavenumber (or the grid's) past its last, so every wave is
        // counted in some bin and the last node is past all of them.
        let k0 = k_min.max(dk) * 0.999;
        let octaves = (k_max * std::f64::consts::SQRT_2 / k0).log2().max(1.0);
        let bins = (octaves * BINS_PER_OCTAVE as f64).ceil() as usize + 1;
        let ln_k0 = k0.ln();
        let t = self.time_s();
        // the cells outside the band's reach are zero
        let rows: Vec<usize> = self.band_indices().collect();
        let per_bin = rows
            .into_par_iter()
            .fold(
                || vec![[0.0f64; 3]; bins],
                |mut acc, ix| {
                    let kx = signed_index(ix, n) * dk;
                    for iz in self.band_indices() {
                        let h = self.h_tilde(ix, iz, t);
                        let p = h.norm_sqr() * gain[ix] * gain[iz];
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
        // The footprint table runs four octaves past the band either way, where the Gaussian
        // has passed everything or nothing.
        let pad = 4 * BINS_PER_OCTAVE as i64;
        let step = std::f64::consts::LN_2 / BINS_PER_OCTAVE as f64;
        let centre = |b: usize| (ln_k0 + (b as f64 + 0.5) * step).exp();
        let resolved = (-pad..bins as i64 + pad)
            .map(|i| {
                let sigma = 1.0 / (ln_k0 + i as f64 * step).exp();
                let mut r = [0.0f64; 3];
                for (b, cov) in per_bin.iter().enumerate() {
                    let g = (-(centre(b) * sigma).powi(2)).exp();
                    for c in 0..3 {
                        r[c] += g * cov[c];
                    }
                }
                r
            })
            .collect();
        let total = per_bin
            .iter()
            .fold([0.0; 3], |a, b| std::array::from_fn(|c| a[c] + b[c]));
        SlopeBands {
            ln_k0: ln_k0 - pad as f64 * step,
            total,
            resolved,
        }
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
    pub fn new(surface: &Surface, source: SlopeSource) -> SurfaceSlopes {
        SurfaceSlopes {
            layers: surface
                .layers()
                .par_iter()
                .map(|l| l.slope_bands(source))
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

    /// What a Gaussian footprint of std `sigma_m` resolves: each wave's slope seen through it
    /// keeps exp(-|k|^2 sigma^2) of its variance, and the rest is the unresolved covariance. A
    /// footprint of zero (or below) resolves every wave.
    pub fn split(&self, sigma_m: f32) -> Split {
        if sigma_m.is_nan() || sigma_m <= 0.0 {
            return Split::RESOLVED;
        }
        let sigma = sigma_m as f64;
        let mut s = Split::RESOLVED;
        let mut cov = [0.0f64; 3];
        for (w, l) in s.weights.iter_mut().zip(&self.layers) {
            let (total, mut resolved) = (l.total(), l.resolved(sigma));
            let t = total[0] + total[2];
            if t > 0.0 {
                let mut share = ((resolved[0] + resolved[2]) / t).clamp(0.0, 1.0);
                // A layer the filter passes less than this of is left out whole (its variance
                // all unresolved), so that it need not be read.
                if share < MIN_RESOLVED_SHARE {
                    (share, resolved) = (0.0, [0.0; 3]);
                }
                *w = share.sqrt() as f32;
            }
            for c in 0..3 {
                cov[c] += total[c] - resolved[c];
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

    /// The default sea with the texels holding its own samples, which Parseval's sums are
    /// (the prefiltered default scales them).
    fn surface() -> Surface {
        let p = OceanParams {
            interp: crate::ocean::Interp::Bilinear,
            ..OceanParams::default()
        };
        Surface::new(&p, 1).unwrap()
    }

    #[test]
    fn the_bands_sum_to_the_grid_slope_variance() {
        // Parseval: the mean of (dh/dx)^2 over a layer's grid is the sum of kx^2 |h~|^2.
        let s = surface();
        let slopes = SurfaceSlopes::new(&s, SlopeSource::Spectrum);
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
    fn the_read_tables_hold_the_slopes_the_lookup_reads() {
        // Each layer's table as read against its mean square slope as the surface reads it (a
        // jittered 512^2 grid of reads), bilinear and Catmull-Rom: within 1 % (measured: 0.14 %
        // at most for both), where the sea's own is 2 % to 22 % more than bilinear reads
        // (the finest layer's waves run to Nyquist, where a bilinear read keeps a third of the
        // power).
        for interp in [Interp::Bilinear, Interp::Bicubic] {
            let params = OceanParams {
                interp,
                ..OceanParams::default()
            };
            let s = Surface::new(&params, 1).unwrap();
            let read = SurfaceSlopes::new(&s, SlopeSource::Read(interp));
            let sea = SurfaceSlopes::new(&s, SlopeSource::Spectrum);
            let summary = s.summary();
            for (r, l) in read.layers().iter().zip(&summary.layers) {
                let r = r.total()[0] + r.total()[2];
                assert!(
                    (r / l.mss_lookup - 1.0).abs() < 0.01,
                    "{interp:?}, layer of {} m: table {r:.4e}, lookup {:.4e}",
                    l.size_m,
                    l.mss_lookup
                );
            }
            if interp == Interp::Bilinear {
                let (r, g) = (read.layers().last().unwrap(), sea.layers().last().unwrap());
                assert!(r.total()[0] + r.total()[2] < 0.95 * (g.total()[0] + g.total()[2]));
            }
        }
    }

    #[test]
    fn the_read_power_transfer_of_each_interpolation() {
        for i in 0..=16 {
            let theta = std::f64::consts::PI * i as f64 / 16.0;
            let bilinear = read_power_transfer(Interp::Bilinear, theta);
            assert!(
                (bilinear - (2.0 + theta.cos()) / 3.0).abs() < 1e-12,
                "{theta}"
            );
            let bicubic = read_power_transfer(Interp::Bicubic, theta);
            assert!(
                bicubic >= bilinear - 1e-6 && bicubic <= 1.0 + 1e-6,
                "{theta}"
            );
            assert_eq!(read_power_transfer(Interp::VariancePreserving, theta), 1.0);
        }
        assert!((read_power_transfer(Interp::Bicubic, 0.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_split_resolves_all_at_zero_width_and_nothing_at_a_huge_one() {
        for source in [SlopeSource::Spectrum, SlopeSource::Read(Interp::Bilinear)] {
            split_extremes(&SurfaceSlopes::new(&surface(), source));
        }
    }

    fn split_extremes(slopes: &SurfaceSlopes) {
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
        for source in [SlopeSource::Spectrum, SlopeSource::Read(Interp::Bilinear)] {
            split_moves_smoothly(&SurfaceSlopes::new(&surface(), source));
        }
    }

    fn split_moves_smoothly(slopes: &SurfaceSlopes) {
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
