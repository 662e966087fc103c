//! What a built ocean reports of itself ([`OceanSummary`]): per layer the spectrum's and the
//! realization's RMS and mean square slopes, per partition its height and share, and the
//! summed surface's statistics. Computed on first use and kept until the time changes; a render
//! reads only the cheap figures ([`Surface::folded_fraction`], [`Surface::realization_rms_m`]).

use rayon::prelude::*;
use serde::Serialize;

use super::Surface;
use super::{FIELD_COUNT, MAX_LAYERS, Sample, Texel, add_texel, field};
use crate::ocean::spectrum::Part;
use crate::ocean::{SpectrumKind, SpreadingKind};

/// Roughness length of the neutral log wind profile that takes the 10 m wind to Cox & Munk's
/// 12.5 m, m (a typical open-sea value).
pub const COX_MUNK_Z0_M: f64 = 1e-4;

/// Cox & Munk's clean-surface mean square slope for a wind of `u10` m/s at 10 m.
pub fn cox_munk_mss(u10: f64) -> f64 {
    let u12_5 = u10 * (12.5 / COX_MUNK_Z0_M).ln() / (10.0 / COX_MUNK_Z0_M).ln();
    0.003 + 5.12e-3 * u12_5
}

/// Side of the jittered grid that estimates the folded fraction and RMS of the summed surface
/// over the coarsest layer's period (stderr of a fraction p: sqrt(p / 512^2)).
const STATS_GRID: usize = 512;

/// What [`Surface::sampled`] measures of the summed surface as a render reads it, on a jittered
/// STATS_GRID^2 grid over the coarsest layer's period.
#[derive(Clone, Debug, Default)]
pub(super) struct Sampled {
    pub(super) folded_fraction: f64,
    rms_m: f64,
    /// Mean square slope |grad h|^2 of the summed surface (the surface's interpolation).
    mss: f64,
    /// Mean square slope of the summed bilinear height surface itself (its own gradient).
    surface_mss: f64,
    /// Per layer: its mean square slope as read between the grid points.
    lookup_mss: Vec<f64>,
    /// Per layer: the mean square slope of its bilinear height surface.
    surface_layer_mss: Vec<f64>,
}

/// |grad h|^2 of a texel (or of summed fields).
pub(super) fn slope2(t: &Texel) -> f64 {
    (t[field::DH_DX] as f64).powi(2) + (t[field::DH_DZ] as f64).powi(2)
}

/// Per-layer part of [`OceanSummary`].
#[derive(Clone, Debug, Serialize)]
pub struct LayerSummary {
    pub size_m: f64,
    pub n: usize,
    pub spacing_m: f64,
    /// Where the layer's share of the wavenumbers is non-zero, [k_min, k_max), rad/m.
    pub k_min: f64,
    pub k_max: f64,
    /// sqrt of the integral of the layer's share of the (scaled) spectrum, m.
    pub spectrum_rms_m: f64,
    pub realization_rms_m: f64,
    /// Mean square slope |grad h|^2: the integral of k^2 over the layer's share of the
    /// (scaled) spectrum; over the grid points (the realization's exact gradients; for
    /// prefiltered layers by Parseval from the coefficients before the prefilter, the sea's and
    /// not the texels'); and as the renderer reads it between them (the surface's
    /// interpolation, at random points).
    pub mss_spectrum: f64,
    pub mss_grid: f64,
    pub mss_lookup: f64,
    /// The mean square slope of the layer's bilinear height surface itself (its own gradient,
    /// what the exact surface's tangent plane sees), same points.
    pub mss_surface: f64,
    /// Where this layer alone folds, at its texels (for a prefiltered layer, of its
    /// prefiltered strains).
    pub folded_fraction: f64,
}

/// One partition of the sea state (the wind sea or a swell) as the layers carry it.
#[derive(Clone, Debug, Serialize)]
pub struct PartitionSummary {
    /// "wind sea", "swell 1", ...
    pub name: String,
    /// 4 x the RMS height of its share of the (scaled) spectrum over the layers' wavenumbers, m.
    pub hs_m: f64,
    /// Its share of that variance, 0-1.
    pub variance_share: f64,
    pub peak_period_s: f64,
    pub peak_wavelength_m: f64,
    /// Direction its waves travel towards, degrees from +x towards +z.
    pub direction_deg: f64,
}

/// What was generated, for the JSON sidecar.
#[derive(Clone, Debug, Serialize)]
pub struct OceanSummary {
    pub seed: u64,
    pub spectrum: Option<SpectrumKind>,
    pub spreading: Option<SpreadingKind>,
    pub alpha: f64,
    pub omega_p_rad_s: f64,
    pub peak_wavelength_m: f64,
    /// RMS of the whole model spectrum before any scaling to `rms_m`, m.
    pub model_rms_m: f64,
    /// sqrt of the integral of P over the union of the layers' bands, times the amplitude scale.
    pub spectrum_rms_m: f64,
    /// sqrt of the sum of the layers' grid variances at `time_s` (independent layers: the
    /// variance of their sum, in expectation).
    pub realization_rms_m: f64,
    /// RMS of the summed, interpolated surface on a jittered grid over the coarsest period.
    pub sampled_rms_m: f64,
    /// Mean square slope |grad h|^2 of the whole surface: the layers' spectrum and grid figures
    /// summed, and the summed surface as the renderer reads it (same jittered grid). Slopes of
    /// h over the undisplaced plane: the normal (eq. 7) adds the displacement's derivatives.
    pub mss_spectrum: f64,
    pub mss_grid: f64,
    pub mss_lookup: f64,
    /// The same of the summed bilinear height surface's own gradient: the slopes of the surface
    /// the exact intersector meets, which `compare --against truth` shades with its tangent
    /// plane (of the sea's own heights with bilinear reads, of the prefiltered ones with
    /// prefiltered reads).
    pub mss_surface: f64,
    /// The largest wavenumber any layer holds, rad/m: the spectrum's cut-off (shorter waves,
    /// the capillaries among them, are not in the surface).
    pub spectrum_cutoff_rad_m: f64,
    /// Cox & Munk's clean-surface fit of the mean square slope measured from sun glitter (1954):
    /// 0.003 + 5.12e-3 U12.5, with the wind at 12.5 m from the 10 m wind by a neutral log
    /// profile of roughness length [`COX_MUNK_Z0_M`] (x 1.019). None for a sea without a
    /// wind sea.
    pub cox_munk_mss: Option<f64>,
    /// Significant wave height 4 x realization RMS, m.
    pub hs_m: f64,
    /// The significant wave height asked for (`hs_m`, or 4 x `rms_m`), m; none without a target.
    pub hs_target_m: Option<f64>,
    /// Factor applied to the amplitudes to reach `rms_m` (1 without a target).
    pub amplitude_scale: f64,
    /// Fraction of the summed surface with J <= 0 (same jittered grid).
    pub folded_fraction: f64,
    /// Wall-clock generation time, s.
    pub seconds: f64,
    pub layers: Vec<LayerSummary>,
    /// The wind sea and each swell.
    pub partitions: Vec<PartitionSummary>,
}

impl Surface {
    /// Generation statistics (see [`OceanSummary`]), computed once per ocean time.
    pub fn summary(&self) -> &OceanSummary {
        self.summary.get_or_init(|| self.compute_summary())
    }

    fn compute_summary(&self) -> OceanSummary {
        let sampled = self.sampled();
        let partition = self.params.partition();
        let layers: Vec<LayerSummary> = self
            .layers
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let (k_min, k_max) = l.band();
                let band = |moment: i32| {
                    self.spectrum.as_ref().map_or(0.0, |s| {
                        s.weighted_variance(k_min, k_max, |k| {
                            k.powi(moment) * partition.weight(i, k)
                        })
                    })
                };
                let band_var = band(0);
                LayerSummary {
                    size_m: l.size_m(),
                    n: l.n(),
                    spacing_m: l.dx(),
                    k_min,
                    k_max,
                    spectrum_rms_m: band_var.sqrt() * self.amplitude_scale,
                    realization_rms_m: l.height_variance().sqrt(),
                    mss_spectrum: band(2) * self.amplitude_scale.powi(2),
                    mss_grid: l.grid_stats().mss,
                    mss_lookup: sampled.lookup_mss.get(i).copied().unwrap_or(0.0),
                    mss_surface: sampled.surface_layer_mss.get(i).copied().unwrap_or(0.0),
                    folded_fraction: l.folded_fraction(),
                }
            })
            .collect();
        let spectrum_var: f64 = layers.iter().map(|l| l.spectrum_rms_m.powi(2)).sum();
        let realization_var: f64 = layers.iter().map(|l| l.realization_rms_m.powi(2)).sum();
        let s = self.spectrum.as_ref();
        OceanSummary {
            seed: self.seed,
            spectrum: s.map(|s| s.kind),
            spreading: s.map(|s| s.spreading),
            alpha: s.map_or(0.0, |s| s.alpha),
            omega_p_rad_s: s.map_or(0.0, |s| s.omega_p),
            peak_wavelength_m: s.map_or(0.0, |s| std::f64::consts::TAU / s.peak_wavenumber()),
            model_rms_m: s.map_or(0.0, |s| s.total_variance().sqrt()),
            spectrum_rms_m: spectrum_var.sqrt(),
            realization_rms_m: realization_var.sqrt(),
            sampled_rms_m: sampled.rms_m,
            mss_spectrum: layers.iter().map(|l| l.mss_spectrum).sum(),
            mss_grid: layers.iter().map(|l| l.mss_grid).sum(),
            mss_lookup: sampled.mss,
            mss_surface: sampled.surface_mss,
            spectrum_cutoff_rad_m: layers.iter().map(|l| l.k_max).fold(0.0, f64::max),
            cox_munk_mss: s
                .filter(|_| self.params.wind_speed > 0.0)
                .map(|_| cox_munk_mss(self.params.wind_speed)),
            hs_m: 4.0 * realization_var.sqrt(),
            hs_target_m: self.params.rms_target().map(|rms| 4.0 * rms),
            amplitude_scale: self.amplitude_scale,
            folded_fraction: self.folded_fraction(),
            seconds: self.seconds,
            partitions: self.partitions(&layers),
            layers,
        }
    }

    /// Folded fraction, RMS and mean square slope of the summed surface, and each layer's mean
    /// square slope as read, on a jittered STATS_GRID^2 grid over the coarsest layer's period;
    /// rows are summed in order so the result is thread-count free.
    pub(super) fn sampled(&self) -> &Sampled {
        self.sampled.get_or_init(|| {
            let Some(l0) = self.layers.first() else {
                return Sampled::default();
            };
            let size = l0.size_m();
            let (layers, interp, m) = (&self.layers, self.params.interp, STATS_GRID);
            // Per row: folded points, sum of h^2, of |grad h|^2 as read, and of each layer's;
            // and of the bilinear height surface's own |grad h|^2, summed and each layer's.
            type Row = (usize, f64, f64, [f64; MAX_LAYERS], f64, [f64; MAX_LAYERS]);
            let rows: Vec<Row> = (0..m)
                .into_par_iter()
                .map(|r| {
                    let mut row: Row = (0, 0.0, 0.0, [0.0; MAX_LAYERS], 0.0, [0.0; MAX_LAYERS]);
                    for c in 0..m {
                        let h = crate::rng::splitmix64(((r * m + c) as u64) ^ self.seed);
                        let jx = (h & 0xFFFF_FFFF) as f64 / 4_294_967_296.0;
                        let jz = (h >> 32) as f64 / 4_294_967_296.0;
                        let u = ((c as f64 + jx) / m as f64 * size) as f32;
                        let v = ((r as f64 + jz) / m as f64 * size) as f32;
                        // What `Sampler::fields` sums for the origin (0, 0), layer by layer.
                        let mut sum = [0.0f32; FIELD_COUNT];
                        let mut grad = [0.0f64; 2];
                        for (i, l) in layers.iter().enumerate() {
                            let (px, pz) = (u as f64 * l.inv_dx(), v as f64 * l.inv_dx());
                            let t = l.read(px, pz, interp);
                            row.3[i] += slope2(&t);
                            add_texel(&mut sum, &t);
                            let g = l.surface_gradient(px, pz);
                            row.5[i] += g[0] * g[0] + g[1] * g[1];
                            grad = [grad[0] + g[0], grad[1] + g[1]];
                        }
                        row.4 += grad[0] * grad[0] + grad[1] * grad[1];
                        let s = Sample::from_fields(&sum);
                        row.0 += usize::from(s.jacobian <= 0.0);
                        row.1 += (s.height as f64).powi(2);
                        row.2 += slope2(&sum);
                    }
                    row
                })
                .collect();
            let total = (m * m) as f64;
            Sampled {
                folded_fraction: rows.iter().map(|r| r.0).sum::<usize>() as f64 / total,
                rms_m: (rows.iter().map(|r| r.1).sum::<f64>() / total).sqrt(),
                mss: rows.iter().map(|r| r.2).sum::<f64>() / total,
                surface_mss: rows.iter().map(|r| r.4).sum::<f64>() / total,
                lookup_mss: (0..layers.len())
                    .map(|i| rows.iter().map(|r| r.3[i]).sum::<f64>() / total)
                    .collect(),
                surface_layer_mss: (0..layers.len())
                    .map(|i| rows.iter().map(|r| r.5[i]).sum::<f64>() / total)
                    .collect(),
            }
        })
    }

    /// Each partition's expected share of the layers' variance (the wind sea first).
    fn partitions(&self, layers: &[LayerSummary]) -> Vec<PartitionSummary> {
        let Some(s) = self.spectrum.as_ref() else {
            return Vec::new();
        };
        let k_lo = layers.iter().map(|l| l.k_min).fold(f64::INFINITY, f64::min);
        let k_hi = layers.iter().map(|l| l.k_max).fold(0.0, f64::max);
        let parts = std::iter::once(Part::Wind).chain((0..s.swells.len()).map(Part::Swell));
        let var: Vec<(Part, f64)> = parts
            .map(|p| {
                (
                    p,
                    s.part_variance(p, k_lo, k_hi, |_| 1.0) * self.amplitude_scale.powi(2),
                )
            })
            .collect();
        let total: f64 = var.iter().map(|v| v.1).sum();
        var.into_iter()
            .map(|(part, v)| {
                let (name, omega_p, dir) = match part {
                    Part::Wind => ("wind sea".to_string(), s.omega_p, s.wind_dir_rad),
                    Part::Swell(i) => {
                        let w = &s.swells[i];
                        (format!("swell {}", i + 1), w.omega_p, w.dir_rad)
                    }
                };
                PartitionSummary {
                    name,
                    hs_m: 4.0 * v.sqrt(),
                    variance_share: if total > 0.0 { v / total } else { 0.0 },
                    peak_period_s: std::f64::consts::TAU / omega_p,
                    peak_wavelength_m: std::f64::consts::TAU
                        / crate::ocean::spectrum::wavenumber(omega_p, s.depth_m),
                    direction_deg: dir.to_degrees(),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cox_munk_takes_the_wind_to_12_5_m() {
        // U12.5 = 10 ln(125000) / ln(100000) = 10.194 m/s: 0.003 + 5.12e-3 x 10.194.
        assert!(
            (cox_munk_mss(10.0) - 0.055_19).abs() < 1e-5,
            "{}",
            cox_munk_mss(10.0)
        );
        assert!((cox_munk_mss(0.0) - 0.003).abs() < 1e-12);
    }
}
