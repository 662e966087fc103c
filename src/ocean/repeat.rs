//! How much the summed surface repeats itself (the paper's reason for several layers, section 2:
//! one FFT patch is periodic and "prominent waves appear in a repeating pattern"), and the
//! surface sampled along a line so anyone can check it.
//!
//! The repeat correlation along a direction: the height h (at nominal positions, without the
//! horizontal displacement) is sampled every [`STEP_M`] along a line through the world origin,
//! and for every lag tau from [`MIN_LAG_M`] to [`MAX_LAG_M`] (in steps of [`STEP_M`]) the
//! Pearson correlation of h(x) and h(x + tau) over a window of [`WINDOW_M`] is computed; the
//! largest one, and its lag, is the metric. A periodic surface of period P gives ~1 at tau = P;
//! a sea that never repeats gives what two independent stretches of sea give (a few tenths at
//! most for a narrow spectrum, whose waves stay in phase for several wavelengths).

use serde::Serialize;

use super::Sampler;

/// Sample spacing along the line, m.
pub const STEP_M: f64 = 1.0;
/// Shortest and longest lag, m.
pub const MIN_LAG_M: f64 = 300.0;
pub const MAX_LAG_M: f64 = 10_000.0;
/// Window the correlation of each lag is taken over, m.
pub const WINDOW_M: f64 = 2_000.0;

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
    pub along_wind: RepeatPeak,
    pub across_wind: RepeatPeak,
}

/// The largest correlation of h over lags `MIN_LAG_M..=MAX_LAG_M` along the unit direction
/// (`dx`, `dz`) from the origin.
pub fn repeat_along(sampler: &Sampler, dx: f64, dz: f64) -> RepeatPeak {
    let n = ((MAX_LAG_M + WINDOW_M) / STEP_M) as usize + 1;
    let h: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * STEP_M;
            sampler.sample((t * dx) as f32, (t * dz) as f32).height as f64
        })
        .collect();
    let w = (WINDOW_M / STEP_M) as usize;
    let stats = |s: &[f64]| {
        let m = s.iter().sum::<f64>() / s.len() as f64;
        let v = s.iter().map(|x| (x - m).powi(2)).sum::<f64>();
        (m, v)
    };
    let (ma, va) = stats(&h[..w]);
    let first = (MIN_LAG_M / STEP_M) as usize;
    let last = (MAX_LAG_M / STEP_M) as usize;
    let peaks: Vec<RepeatPeak> = (first..=last)
        .map(|lag| {
            let b = &h[lag..lag + w];
            let (mb, vb) = stats(b);
            let cov: f64 = h[..w].iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
            RepeatPeak {
                correlation: cov / (va * vb).sqrt().max(1e-300),
                lag_m: lag as f64 * STEP_M,
            }
        })
        .collect();
    // A periodic surface correlates almost equally at every multiple of its period: name the
    // shortest lag within 0.005 of the largest correlation.
    let max = peaks
        .iter()
        .map(|p| p.correlation)
        .fold(f64::NEG_INFINITY, f64::max);
    *peaks
        .iter()
        .find(|p| p.correlation >= max - 0.005)
        .expect("at least one lag")
}

/// The repeat metric along the wind (blowing towards `wind_dir_deg`) and across it.
pub fn repeat_correlation(sampler: &Sampler, wind_dir_deg: f64) -> RepeatCorrelation {
    let a = wind_dir_deg.to_radians();
    let (along, across) = rayon::join(
        || repeat_along(sampler, a.cos(), a.sin()),
        || repeat_along(sampler, -a.sin(), a.cos()),
    );
    RepeatCorrelation {
        max: along.correlation.max(across.correlation),
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
        let r = repeat_correlation(&one.sampler([0.0, 0.0]), 0.0);
        assert!(r.max > 0.99, "{r:?}");
        assert_eq!(r.along_wind.lag_m, 400.0);
        assert_eq!(r.across_wind.lag_m, 400.0);
        // The default layers share the spectrum in disjoint bands: every wave longer than a few
        // metres lives in the 400 m layer alone, so the sum repeats every 400 m too.
        let default = Surface::new(&OceanParams::default(), 1).unwrap();
        let r = repeat_correlation(&default.sampler([0.0, 0.0]), 0.0);
        assert!(r.max > 0.95 && r.along_wind.lag_m == 400.0, "{r:?}");
        // The metric has teeth: a layer longer than every lag does not repeat within them.
        let long = surface(&[(16_384.0, 2048)]);
        let r = repeat_correlation(&long.sampler([0.0, 0.0]), 0.0);
        assert!(r.max < 0.6, "{r:?}");
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
    fn validity_warnings_flag_the_paper_cases_and_not_a_young_sea() {
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
        assert_eq!(s.validity_warnings().len(), 2);
        let young = OceanParams {
            wind_speed: 10.0,
            fetch_km: 10.0,
            ..OceanParams::default()
        };
        assert!(Spectrum::new(&young).validity_warnings().is_empty());
    }
}
