//! The film: rows rendered in parallel, `spp` samples per pixel on a low-discrepancy pattern
//! (the R2 sequence of Roberts 2018, rotated per pixel by a hashed offset: Cranley-Patterson),
//! summed in f64 and averaged. Every random number is a hash of (seed, pixel, sample), so an
//! image does not depend on the thread count (DESIGN.md, Determinism). A guard drops any
//! sample that is NaN or infinite and counts it.
//!
//! Besides the image the film keeps what it takes to say how noisy it is:
//! - per pixel, the sample variance of the luminance (Welford's update in f64), from which the
//!   variance of the pixel's mean follows (`var_y`, written to the EXR as `Y.variance`);
//! - two half images, the means of the even- and of the odd-numbered samples. They are two
//!   independent renders of the same scene with half the samples each, and they measure the
//!   noise of anything computed from images that share sample seeds: the difference of two
//!   scenarios rendered with the same seed is correlated pixel by pixel, which per-image
//!   variances cannot account for, but its two half differences are independent estimates of
//!   the same thing (see `crate::analysis::error`).

use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use super::camera::Camera;
use super::integrator::{Counters, SceneRef, TraceSettings};
use crate::accel::Ray;
use crate::color::luminance;
use crate::image_io::RgbImage;
use crate::rng::Rng;

/// R2 generator constants: 1/phi2 and 1/phi2^2 for the plastic number phi2.
const R2: (f64, f64) = (0.754_877_666_246_692_7, 0.569_840_290_998_053_3);

/// A rendered image with its noise estimates.
#[derive(Clone, Debug)]
pub struct Film {
    /// Mean radiance of each pixel.
    pub image: RgbImage,
    /// Means of the even-numbered (`[0]`) and odd-numbered (`[1]`) samples of each pixel.
    pub halves: [RgbImage; 2],
    /// Samples each half holds per pixel (before NaN samples are dropped): ceil(spp / 2) and
    /// floor(spp / 2).
    pub half_spp: [u32; 2],
    /// Variance of each pixel's mean luminance (its squared standard error); 0 with one sample.
    pub var_y: Vec<f32>,
}

impl Film {
    /// RMS over the image of the standard error of the pixel luminance, or `None` with fewer
    /// than two samples per pixel.
    pub fn noise_rms(&self) -> Option<f64> {
        if self.half_spp[1] == 0 {
            return None;
        }
        let sum: f64 = self.var_y.iter().map(|&v| v as f64).sum();
        Some((sum / self.var_y.len().max(1) as f64).sqrt())
    }
}

/// What one pixel accumulates.
#[derive(Clone, Copy, Default)]
struct PixelSums {
    sum: [f64; 3],
    half: [[f64; 3]; 2],
    half_n: [u32; 2],
    /// Welford's running mean and sum of squared deviations of the luminance.
    n: u32,
    mean_y: f64,
    m2_y: f64,
}

impl PixelSums {
    fn add(&mut self, s: u32, l: Vec3) {
        let h = (s % 2) as usize;
        for k in 0..3 {
            self.sum[k] += l[k] as f64;
            self.half[h][k] += l[k] as f64;
        }
        self.half_n[h] += 1;
        self.n += 1;
        let y = luminance(l.to_array()) as f64;
        let delta = y - self.mean_y;
        self.mean_y += delta / self.n as f64;
        self.m2_y += delta * (y - self.mean_y);
    }

    fn mean(sum: &[f64; 3], n: u32) -> [f32; 3] {
        let n = n.max(1) as f64;
        [
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        ]
    }

    /// Variance of the mean luminance: s^2 / n with s^2 = M2 / (n - 1).
    fn var_of_mean(&self) -> f32 {
        if self.n < 2 {
            0.0
        } else {
            (self.m2_y / (self.n - 1) as f64 / self.n as f64) as f32
        }
    }
}

/// Renders the camera's image. `camera_height_m` places the camera above the mean sea level
/// at its nadir. Shows a progress bar on stderr when `progress` is set.
pub fn render_image(
    scene: &SceneRef,
    camera: &Camera,
    camera_height_m: f32,
    spp: u32,
    seed: u64,
    settings: &TraceSettings,
    progress: bool,
) -> (Film, Counters) {
    let (w, h) = (camera.width, camera.height);
    let bar = if progress {
        ProgressBar::new(h as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("render {bar:40} {pos}/{len} rows  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let origin = [0.0, camera_height_m, 0.0];
    let rows: Vec<(Vec<PixelSums>, Counters)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut c = Counters::default();
            let row = (0..w)
                .map(|x| {
                    let pixel = (y * w + x) as u64;
                    let mut acc = PixelSums::default();
                    let mut rot = Rng::keyed(&[seed, pixel, u64::MAX]);
                    let (ox, oy) = (rot.f64(), rot.f64());
                    for s in 0..spp {
                        let jx = (ox + s as f64 * R2.0).fract() as f32;
                        let jy = (oy + s as f64 * R2.1).fract() as f32;
                        let dir = camera.direction(x as f32 + jx, y as f32 + jy);
                        let mut rng = Rng::keyed(&[seed, pixel, s as u64]);
                        let l: Vec3 = scene.radiance(
                            &Ray::new(origin, dir.to_array()),
                            false,
                            0,
                            settings,
                            &mut rng,
                            &mut c,
                        );
                        if l.is_finite() {
                            acc.add(s, l);
                        } else {
                            c.nan += 1;
                        }
                    }
                    acc
                })
                .collect();
            bar.inc(1);
            (row, c)
        })
        .collect();
    bar.finish_and_clear();
    let mut film = Film {
        image: RgbImage::new(w, h),
        halves: [RgbImage::new(w, h), RgbImage::new(w, h)],
        half_spp: [spp.div_ceil(2), spp / 2],
        var_y: vec![0.0; w * h],
    };
    let mut counters = Counters::default();
    for (y, (row, c)) in rows.into_iter().enumerate() {
        for (x, p) in row.iter().enumerate() {
            let i = y * w + x;
            film.image.pixels[i] = PixelSums::mean(&p.sum, p.n);
            for k in 0..2 {
                film.halves[k].pixels[i] = PixelSums::mean(&p.half[k], p.half_n[k]);
            }
            film.var_y[i] = p.var_of_mean();
        }
        counters += c;
    }
    (film, counters)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_and_halves_match_direct_formulas() {
        let samples = [0.5f32, 2.0, 1.25, 7.0, 0.0];
        let mut p = PixelSums::default();
        for (s, &v) in samples.iter().enumerate() {
            p.add(s as u32, Vec3::splat(v));
        }
        let n = samples.len() as f64;
        let mean = samples.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = samples
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        assert!((p.var_of_mean() as f64 - var / n).abs() < 1e-6 * var);
        assert_eq!(p.half_n, [3, 2]);
        let even = (0.5 + 1.25 + 0.0) / 3.0;
        assert!((PixelSums::mean(&p.half[0], p.half_n[0])[0] - even).abs() < 1e-6);
        assert!((PixelSums::mean(&p.half[1], p.half_n[1])[1] - 4.5).abs() < 1e-6);
        let one = {
            let mut q = PixelSums::default();
            q.add(0, Vec3::ONE);
            q
        };
        assert_eq!(one.var_of_mean(), 0.0);
    }
}
