//! How much the summed surface repeats itself (the paper's reason for several layers, section 2:
//! one FFT patch is periodic and "prominent waves appear in a repeating pattern"), and the
//! surface sampled along a line so anyone can check it.
//!
//! The repeat correlation along a unit direction d: the height h (at nominal positions, without
//! the horizontal displacement) is sampled every [`STEP_M`] along [`LINES`] parallel lines in
//! direction d, [`LINE_SPACING_M`] apart across it (the first through the world origin), each
//! [`WINDOW_M`] + [`MAX_LAG_M`] long. With h' = h minus its mean over all samples and a_l(x),
//! x < [`WINDOW_M`], the start of line l, the correlation at lag tau is
//!
//!   r(tau) = sum_l sum_x a_l(x) h'_l(x + tau) / sqrt(sum_l sum_x a_l(x)^2 * sum_l sum_x h'_l(x + tau)^2)
//!
//! (the sums over x by FFT cross-correlation, exact up to rounding). The metric is the largest
//! r over tau from [`MIN_LAG_M`] to [`MAX_LAG_M`] and the shortest lag within 0.005 of it. A
//! periodic surface of period P gives ~1 at tau = P; a layer carrying the share f of the
//! variance adds about f at its period. Pooling 128 lines over 8 km x 32 km brings the floor
//! (what a sea that never repeats within 10 km reads, from chance alignments of a narrow
//! spectrum's waves) down to 0.02 (a 16 km layer; test
//! `the_default_does_not_repeat_and_the_metric_has_teeth`); one 2 km window on one line
//! read 0.3-0.55.

use rayon::prelude::*;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use serde::Serialize;

use super::Sampler;

/// Sample spacing along a line, m.
pub const STEP_M: f64 = 1.0;
/// Shortest and longest lag, m. The shortest is at least [`PEAKS_BEFORE_REPEAT`] of the sea's
/// longest peak wavelength: closer than that a long sea still correlates with itself (a 576 m
/// Douglas 9 sea reads 0.32 at 300 m, its own wave, not a repeat).
pub const MIN_LAG_M: f64 = 300.0;
pub const PEAKS_BEFORE_REPEAT: f64 = 4.0;
pub const MAX_LAG_M: f64 = 10_000.0;
/// Length of each line's start that is correlated with the shifted line, m.
pub const WINDOW_M: f64 = 8_000.0;
/// Number of parallel lines and their spacing, m.
pub const LINES: usize = 128;
pub const LINE_SPACING_M: f64 = 250.0;

/// The largest correlation along one direction (within 0.005: the shortest lag that comes that
/// close) and its lag.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RepeatPeak {
    pub correlation: f64,
    pub lag_m: f64,
}

/// The repeat metric along the wind and across it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RepeatCorrelation {
    /// The larger of the two.
    pub max: f64,
    /// The shortest lag looked at, m.
    pub min_lag_m: f64,
    pub along_wind: RepeatPeak,
    pub across_wind: RepeatPeak,
}

/// r(tau) of the module doc for tau = 0, STEP_M, ..., MAX_LAG_M along the unit direction
/// (`dx`, `dz`).
pub fn correlation_by_lag(sampler: &Sampler, dx: f64, dz: f64) -> Vec<f64> {
    let len = ((WINDOW_M + MAX_LAG_M) / STEP_M) as usize + 1;
    let w = (WINDOW_M / STEP_M) as usize;
    let lags = (MAX_LAG_M / STEP_M) as usize + 1;
    let n_fft = (len + w).next_power_of_two();
    let lines: Vec<Vec<f64>> = (0..LINES)
        .into_par_iter()
        .map(|l| {
            let (ox, oz) = (
                -dz * l as f64 * LINE_SPACING_M,
                dx * l as f64 * LINE_SPACING_M,
            );
            (0..len)
                .map(|i| {
                    let t = i as f64 * STEP_M;
                    sampler
                        .sample((ox + t * dx) as f32, (oz + t * dz) as f32)
                        .height as f64
                })
                .collect()
        })
        .collect();
    let mean = lines.iter().flatten().sum::<f64>() / (LINES * len) as f64;
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n_fft);
    let ifft = planner.plan_fft_inverse(n_fft);
    // sum over lines of conj(A) B, A the window's transform and B the line's
    let zero = || vec![Complex::<f64>::default(); n_fft];
    let cross = lines
        .par_iter()
        .map(|h| {
            let mut a = zero();
            let mut b = zero();
            for (i, v) in h.iter().enumerate() {
                b[i].re = v - mean;
                if i < w {
                    a[i].re = v - mean;
                }
            }
            fft.process(&mut a);
            fft.process(&mut b);
            a.iter()
                .zip(&b)
                .map(|(a, b)| a.conj() * b)
                .collect::<Vec<_>>()
        })
        .reduce(zero, |mut s, c| {
            s.iter_mut().zip(&c).for_each(|(s, c)| *s += c);
            s
        });
    let mut cross = cross;
    ifft.process(&mut cross);
    // sum_x h'(x + tau)^2 over the window, all lines, by prefix sums
    let mut window_energy = vec![0.0; lags];
    for h in &lines {
        let mut prefix = Vec::with_capacity(len + 1);
        prefix.push(0.0);
        for v in h {
            prefix.push(prefix.last().unwrap() + (v - mean) * (v - mean));
        }
        for (tau, e) in window_energy.iter_mut().enumerate() {
            *e += prefix[tau + w] - prefix[tau];
        }
    }
    let a_energy = window_energy[0];
    (0..lags)
        .map(|tau| {
            cross[tau].re / n_fft as f64 / (a_energy * window_energy[tau]).sqrt().max(1e-300)
        })
        .collect()
}

/// The largest correlation of h over lags `MIN_LAG_M..=MAX_LAG_M` along the unit direction
/// (`dx`, `dz`).
pub fn repeat_along(sampler: &Sampler, dx: f64, dz: f64, min_lag_m: f64) -> RepeatPeak {
    let r = correlation_by_lag(sampler, dx, dz);
    let lag = peak_lag(&r, (min_lag_m / STEP_M) as usize);
    RepeatPeak {
        correlation: r[lag],
        lag_m: lag as f64 * STEP_M,
    }
}

/// The index of r's largest value from `first` on (see [`repeat_along`]).
fn peak_lag(r: &[f64], first: usize) -> usize {
    let max = r[first..].iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // A periodic surface correlates almost equally at every multiple of its period: name the
    // shortest local maximum within 0.005 of the largest correlation. The range's ends count
    // as maxima on their open side (a long-wave sea still falls off at the shortest lag).
    (first..r.len())
        .find(|&i| {
            r[i] >= max - 0.005
                && (i == first || r[i] >= r[i - 1])
                && r.get(i + 1).is_none_or(|&next| r[i] >= next)
        })
        .unwrap_or(first)
}

/// The repeat metric along the wind (blowing towards `wind_dir_deg`) and across it.
/// `peak_wavelength_m` is the sea's longest peak wavelength (0 for the plain [`MIN_LAG_M`]).
pub fn repeat_correlation(
    sampler: &Sampler,
    wind_dir_deg: f64,
    peak_wavelength_m: f64,
) -> RepeatCorrelation {
    let four = PEAKS_BEFORE_REPEAT * peak_wavelength_m;
    let min_lag_m = if four.is_finite() {
        four.clamp(MIN_LAG_M, 0.5 * MAX_LAG_M)
    } else {
        MIN_LAG_M
    };
    let a = wind_dir_deg.to_radians();
    let along = repeat_along(sampler, a.cos(), a.sin(), min_lag_m);
    let across = repeat_along(sampler, -a.sin(), a.cos(), min_lag_m);
    RepeatCorrelation {
        max: along.correlation.max(across.correlation),
        min_lag_m,
        along_wind: along,
        across_wind: across,
    }
}

/// The surface at `n` points evenly spaced from (x0, z0) to (x1, z1), world metres, as CSV
/// rows `x,z,h,dx,dz,nx,ny,nz` (with a header).
pub fn profile_csv(sampler: &Sampler, from: [f64; 2], to: [f64; 2], n: usize) -> String {
    let mut out = String::from("x,z,h,dx,dz,nx,ny,nz\n");
    for i in 0..n {
        let t = if n > 1 {
            i as f64 / (n - 1) as f64
        } else {
            0.0
        };
        let (x, z) = (
            from[0] + t * (to[0] - from[0]),
            from[1] + t * (to[1] - from[1]),
        );
        let s = sampler.sample(x as f32, z as f32);
        out.push_str(&format!(
            "{x},{z},{},{},{},{},{},{}\n",
            s.height, s.disp[0], s.disp[1], s.normal[0], s.normal[1], s.normal[2]
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ocean::{LayerSpec, OceanParams, Surface};

    fn surface(layers: &[(f64, usize)]) -> Surface {
        let params = OceanParams {
            layers: layers
                .iter()
                .map(|&(size_m, n)| LayerSpec { size_m, n })
                .collect(),
            ..OceanParams::default()
        };
        Surface::new(&params, 1).unwrap()
    }

    #[test]
    fn a_single_layer_repeats_at_its_period_and_the_default_layers_at_the_coarsest() {
        let one = surface(&[(400.0, 256)]);
        let r = repeat_correlation(&one.sampler([0.0, 0.0]), 0.0, 0.0);
        assert!(r.max > 0.99, "{r:?}");
        assert_eq!(r.along_wind.lag_m, 400.0);
        assert_eq!(r.across_wind.lag_m, 400.0);
        // a long sea's lags start at 4 of its peak wavelengths: the next multiple is named
        let r = repeat_correlation(&one.sampler([0.0, 0.0]), 0.0, 250.0);
        assert_eq!((r.min_lag_m, r.along_wind.lag_m), (1000.0, 1200.0), "{r:?}");
        let r = repeat_correlation(&one.sampler([0.0, 0.0]), 0.0, f64::NAN);
        assert_eq!(r.min_lag_m, MIN_LAG_M);
        // The earlier default layers share the spectrum in disjoint bands: every wave longer
        // than a few metres lives in the 400 m layer alone, so the sum repeats every 400 m too.
        let before = Surface::new(&OceanParams::tiling_layers(), 1).unwrap();
        let r = repeat_correlation(&before.sampler([0.0, 0.0]), 0.0, 0.0);
        assert!(r.max > 0.95 && r.along_wind.lag_m == 400.0, "{r:?}");
    }

    #[test]
    fn the_default_does_not_repeat_and_the_metric_has_teeth() {
        // The default's overlapping layers put the peak in two layers longer than 10 km and
        // leave at most ~11 % of the variance to any shorter period.
        for seed in [1, 2] {
            let default = Surface::new(&OceanParams::default(), seed).unwrap();
            let r = repeat_correlation(&default.sampler([0.0, 0.0]), 0.0, 0.0);
            assert!(r.max < 0.2, "seed {seed}: {r:?}");
        }
        // A layer longer than every lag cannot repeat within them: what the metric reads then
        // is its floor.
        let long = surface(&[(16_384.0, 2048)]);
        let r = repeat_correlation(&long.sampler([0.0, 0.0]), 0.0, 0.0);
        assert!(r.max < 0.08, "{r:?}");
    }

    #[test]
    fn the_peak_may_sit_at_the_shortest_lag() {
        // a sea of long waves still decorrelating at the shortest lag (a Beaufort 9 sea)
        let falling: Vec<f64> = (0..100).map(|i| 1.0 - 0.01 * i as f64).collect();
        assert_eq!(peak_lag(&falling, 30), 30);
        // the shortest of two near-equal maxima
        let mut two = vec![0.0; 100];
        (two[40], two[80]) = (0.5, 0.503);
        assert_eq!(peak_lag(&two, 30), 40);
        assert_eq!(peak_lag(&[f64::NAN; 10], 3), 3);
    }

    #[test]
    fn the_profile_is_the_sampler_along_the_line() {
        let s = surface(&[(400.0, 128), (47.3, 128)]);
        let sampler = s.sampler([0.0, 0.0]);
        let csv = profile_csv(&sampler, [10.0, -5.0], [30.0, 15.0], 5);
        let rows: Vec<Vec<f64>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 5);
        for (i, r) in rows.iter().enumerate() {
            let (x, z) = (10.0 + 5.0 * i as f64, -5.0 + 5.0 * i as f64);
            assert_eq!((r[0], r[1]), (x, z));
            let p = sampler.sample(x as f32, z as f32);
            assert_eq!(r[2] as f32, p.height);
            assert_eq!([r[3] as f32, r[4] as f32], p.disp);
            assert_eq!([r[5] as f32, r[6] as f32, r[7] as f32], p.normal);
        }
    }

    #[test]
    fn range_notes_flag_the_paper_cases_and_not_a_young_sea() {
        use crate::ocean::Spectrum;
        // Table 1, case 87: g F / U^2 = 4.4e5, Mitsuyasu's s at the peak 254.
        let case87 = OceanParams {
            wind_speed: 1.78,
            fetch_km: 141.35,
            depth_m: 263.4,
            ..OceanParams::default()
        };
        let s = Spectrum::new(&case87);
        assert!((s.dimensionless_fetch().unwrap() / 4.376e5 - 1.0).abs() < 1e-3);
        assert!((s.peak_spreading_exponent().unwrap() - 254.0).abs() < 1.0);
        assert_eq!(s.range_notes().len(), 2);
        // the cap: the surface spreads as cos^2s with s = 75 at the peak, and only the fetch
        // warning stays
        let capped = Spectrum::new(&OceanParams {
            spreading_cap: Some(75.0),
            ..case87.clone()
        });
        let w = capped.omega_p;
        let (t, d) = (0.2, crate::ocean::spectrum::cos_2s);
        assert_eq!(capped.spreading_at(w, t), d(t, 75.0));
        assert!((s.spreading_at(w, t) - d(t, 254.0)).abs() < 0.05 * d(t, 254.0));
        assert!(capped.spreading_at(w, t) > 1.5 * s.spreading_at(w, t));
        assert_eq!(capped.range_notes().len(), 1);
        let young = OceanParams {
            wind_speed: 10.0,
            fetch_km: 10.0,
            ..OceanParams::default()
        };
        assert!(Spectrum::new(&young).range_notes().is_empty());
    }
}
