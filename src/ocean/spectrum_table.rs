//! P(k) with everything that depends only on |k| tabulated: each partition's
//! S(omega(k)) Q(s(k)) (d omega / d k) / k times a layer's weight(|k|), and Mitsuyasu's exponent
//! s(k), on nodes evenly spaced in sqrt(|k|) (omega is nearly proportional to it, so the
//! spectral peak gets as many nodes whatever the layer). A point then costs one interpolation
//! and one power per partition, |cos(theta / 2)|^(2 s) = ((1 + cos theta) / 2)^s, instead of
//! some twenty transcendental functions: a 2048-texel layer draws its amplitudes ~3x faster.
//! The exact [`Spectrum::p_k`] stays the reference; the layers' tests bound the difference.

use super::{Spectrum, SpreadingKind};

/// Nodes of a table. With them a layer's amplitudes and fields stay within 2e-5 of their RMS of
/// the exact formulas' (test `table_matches_exact_spectrum` of the layers).
const NODES: usize = 8192;

/// One partition's radial factors and direction.
struct TablePart {
    /// Unit vector it travels towards, (cos, sin).
    dir: (f64, f64),
    /// S(omega) Q(s) (d omega / d k) / k weight(|k|) at each node.
    radial: Vec<f64>,
    /// The cos-2s exponent at each node.
    s: Vec<f64>,
}

/// P(k) times a weight, tabulated radially for `|k| <= k_max` (see the module doc).
pub struct RadialTable {
    inv_du: f64,
    parts: Vec<TablePart>,
    /// [`Spectrum::spreading_width`] at each node.
    width: Vec<f64>,
}

impl RadialTable {
    /// The table of `spectrum` times `weight` up to `k_max`, or `None` where the wind sea's
    /// spreading is not cos-2s (Mitsuyasu): the others stay on the exact path.
    pub fn new(
        spectrum: &Spectrum,
        weight: &(dyn Fn(f64) -> f64 + Sync),
        k_max: f64,
    ) -> Option<RadialTable> {
        if spectrum.spreading != SpreadingKind::Mitsuyasu || k_max.is_nan() || k_max <= 0.0 {
            return None;
        }
        let du = k_max.sqrt() / (NODES - 1) as f64;
        let k_at = |i: usize| (i as f64 * du).powi(2);
        let nodes = |f: &(dyn Fn(f64) -> f64 + Sync)| -> Vec<f64> {
            use rayon::prelude::*;
            (0..NODES).into_par_iter().map(|i| f(k_at(i))).collect()
        };
        let depth = spectrum.depth_m;
        // d omega / d k / k times the weight; 0 at k = 0, where P vanishes
        let jacobian = |k: f64| {
            if k > 0.0 {
                super::group_velocity(k, depth) / k * weight(k)
            } else {
                0.0
            }
        };
        let wind_s = |k: f64| {
            let omega = spectrum.omega(k);
            super::mitsuyasu_s_from_peak(omega, spectrum.omega_p, spectrum.mitsuyasu_peak)
                .min(spectrum.spreading_cap)
        };
        let mut parts = vec![TablePart {
            dir: (spectrum.wind_dir_rad.cos(), spectrum.wind_dir_rad.sin()),
            radial: nodes(&|k| {
                let j = jacobian(k);
                if j == 0.0 {
                    return 0.0;
                }
                let omega = spectrum.omega(k);
                // Q(s) is cos-2s at theta = 0
                spectrum.wind_s_omega(omega) * super::cos_2s(0.0, wind_s(k)) * j
            }),
            s: nodes(&wind_s),
        }];
        for (i, sw) in spectrum.swells.iter().enumerate() {
            let q = sw.spreading_at(sw.dir_rad);
            parts.push(TablePart {
                dir: (sw.dir_rad.cos(), sw.dir_rad.sin()),
                radial: nodes(&|k| {
                    let j = jacobian(k);
                    if j == 0.0 {
                        return 0.0;
                    }
                    spectrum.swell_s_omega(i, spectrum.omega(k)) * q * j
                }),
                s: vec![sw.s; NODES],
            });
        }
        Some(RadialTable {
            inv_du: 1.0 / du,
            parts,
            width: nodes(&|k| spectrum.spreading_width(spectrum.omega(k))),
        })
    }

    /// The node below `k` and the fraction of the way to the next.
    #[inline]
    fn locate(&self, k: f64) -> (usize, f64) {
        let x = k.sqrt() * self.inv_du;
        let i = (x as usize).min(NODES - 2);
        (i, x - i as f64)
    }

    /// weight(|k|) P(kx, kz) where |k| = `k` > 0 (at most the table's `k_max`).
    #[inline]
    pub fn p_k_at(&self, kx: f64, kz: f64, k: f64) -> f64 {
        let (i, f) = self.locate(k);
        let lerp = |v: &[f64]| v[i] + f * (v[i + 1] - v[i]);
        let mut p = 0.0;
        for part in &self.parts {
            let r = lerp(&part.radial);
            if r == 0.0 {
                continue;
            }
            // cos^2(theta / 2) = (1 + cos theta) / 2 of the angle from the partition's direction
            let c = 0.5 * (1.0 + (kx * part.dir.0 + kz * part.dir.1) / k);
            if c > 0.0 {
                p += r * c.powf(lerp(&part.s));
            }
        }
        p
    }

    /// [`Spectrum::spreading_width`] at |k| = `k`.
    #[inline]
    pub fn spreading_width(&self, k: f64) -> f64 {
        let (i, f) = self.locate(k);
        self.width[i] + f * (self.width[i + 1] - self.width[i])
    }
}
