//! The film: rows rendered in parallel, `spp` samples per pixel on a low-discrepancy pattern
//! (the R2 sequence of Roberts 2018, rotated per pixel by a hashed offset: Cranley-Patterson;
//! one sequence for the even samples and one for the odd ones), summed in f64 and averaged. Every random number is a hash of (seed, pixel, sample), so an
//! image does not depend on the thread count (DESIGN.md, Determinism). A guard drops any
//! sample that is NaN or infinite and counts it.
//!
//! Besides the image the film keeps what it takes to say how noisy it is:
//! - per pixel, the sample variance of the luminance (Welford's update in f64), from which the
//!   variance of the pixel's mean follows (`var_y`, written to the EXR as `Y.variance`);
//! - on request, batch means: the samples of each pixel dealt round-robin into `k` batches
//!   (sample s into batch s mod k), each batch on its own rotated R2 sequence with its own
//!   random streams, and the mean luminance of each. The batches are `k` independent renders of
//!   the same scene, and they measure the noise of anything computed from images that share
//!   sample seeds: the difference of two scenarios rendered with the same seed is correlated
//!   pixel by pixel, which per-image variances cannot account for, but its `k` batch
//!   differences are independent estimates of the same thing (see `crate::analysis::error`).

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

/// Most batches a film keeps per pixel.
pub const MAX_BATCHES: usize = 8;

/// The mean luminance of each batch of each pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Batches {
    /// Batches per pixel.
    pub k: usize,
    /// Samples in each batch (before NaN samples are dropped, which are counted apart).
    pub spp: Vec<u32>,
    /// `luminance[pixel * k + b]`: the mean luminance of batch b of a pixel.
    pub luminance: Vec<f32>,
}

/// A rendered image with its noise estimates.
#[derive(Clone, Debug)]
pub struct Film {
    /// Mean radiance of each pixel.
    pub image: RgbImage,
    /// Variance of each pixel's mean luminance (its squared standard error); 0 with one sample.
    pub var_y: Vec<f32>,
    pub spp: u32,
    /// When asked for: batch means (see the module doc).
    pub batches: Option<Batches>,
}

impl Film {
    /// RMS over the image of the standard error of the pixel luminance, or `None` with fewer
    /// than two samples per pixel.
    pub fn noise_rms(&self) -> Option<f64> {
        if self.spp < 2 {
            return None;
        }
        let sum: f64 = self.var_y.iter().map(|&v| v as f64).sum();
        Some((sum / self.var_y.len().max(1) as f64).sqrt())
    }
}

/// Bytes a film of `pixels` pixels takes while it renders and is written: the per-pixel sums,
/// the image, its variance, `batches` batch means, and the copies the EXR and PNG writers make.
pub fn film_bytes(pixels: u64, batches: usize) -> u64 {
    let per_pixel = std::mem::size_of::<PixelSums>() // sums while rendering
        + 12 + 4 + 4 * batches // image, variance, batch means
        + 16 + 3; // EXR channels (R, G, B, Y.variance), PNG bytes
    pixels * per_pixel as u64
}

/// What one pixel accumulates.
#[derive(Clone, Copy, Default)]
struct PixelSums {
    sum: [f64; 3],
    /// Luminance sums and sample counts of the batches.
    batch: [f64; MAX_BATCHES],
    batch_n: [u32; MAX_BATCHES],
    /// Welford's running mean and sum of squared deviations of the luminance.
    n: u32,
    mean_y: f64,
    m2_y: f64,
}

impl PixelSums {
    fn add(&mut self, batch: usize, l: Vec3) {
        for k in 0..3 {
            self.sum[k] += l[k] as f64;
        }
        self.n += 1;
        let y = luminance(l.to_array()) as f64;
        self.batch[batch] += y;
        self.batch_n[batch] += 1;
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
/// at its nadir. Keeps `batches` batch means per pixel when that is 2 or more (at most
/// [`MAX_BATCHES`], and at most `spp`). Shows a progress bar on stderr when `progress` is set.
#[allow(clippy::too_many_arguments)]
pub fn render_image(
    scene: &SceneRef,
    camera: &Camera,
    camera_height_m: f32,
    spp: u32,
    seed: u64,
    settings: &TraceSettings,
    batches: usize,
    progress: bool,
) -> (Film, Counters) {
    // Samples are dealt into k sequences whatever is kept, so an image does not depend on
    // whether batch means were asked for.
    let k = MAX_BATCHES;
    let keep = batches.clamp(0, k).min(spp as usize);
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
                    // Each sequence runs its own rotated R2 pattern, so batches are independent
                    // renders (their noise estimate is unbiased).
                    let offsets: [(f64, f64); MAX_BATCHES] = std::array::from_fn(|b| {
                        let mut rot = Rng::keyed(&[seed, pixel, u64::MAX - b as u64]);
                        (rot.f64(), rot.f64())
                    });
                    for s in 0..spp {
                        let b = s as usize % k;
                        let ((ox, oy), j) = (offsets[b], (s as usize / k) as f64);
                        let jx = (ox + j * R2.0).fract() as f32;
                        let jy = (oy + j * R2.1).fract() as f32;
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
                            // With fewer batches kept, the k sequences fold onto them.
                            acc.add(b % keep.max(1), l);
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
        var_y: vec![0.0; w * h],
        spp,
        batches: (keep >= 2).then(|| Batches {
            k: keep,
            // Sequence s mod k feeds batch (s mod k) mod keep.
            spp: (0..keep)
                .map(|b| (0..spp as usize).filter(|s| (s % k) % keep == b).count() as u32)
                .collect(),
            luminance: vec![0.0; w * h * keep],
        }),
    };
    let mut counters = Counters::default();
    for (y, (row, c)) in rows.into_iter().enumerate() {
        for (x, p) in row.iter().enumerate() {
            let i = y * w + x;
            film.image.pixels[i] = PixelSums::mean(&p.sum, p.n);
            film.var_y[i] = p.var_of_mean();
            if let Some(b) = &mut film.batches {
                for j in 0..keep {
                    b.luminance[i * keep + j] = (p.batch[j] / p.batch_n[j].max(1) as f64) as f32;
                }
            }
        }
        counters += c;
    }
    (film, counters)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_and_batches_match_direct_formulas() {
        let samples = [0.5f32, 2.0, 1.25, 7.0, 0.0];
        let mut p = PixelSums::default();
        for (s, &v) in samples.iter().enumerate() {
            p.add(s % 2, Vec3::splat(v));
        }
        let n = samples.len() as f64;
        let mean = samples.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = samples
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        assert!((p.var_of_mean() as f64 - var / n).abs() < 1e-6 * var);
        assert_eq!(&p.batch_n[..2], &[3, 2]);
        let even = (0.5 + 1.25 + 0.0) / 3.0;
        assert!((p.batch[0] / 3.0 - even).abs() < 1e-6);
        assert!((p.batch[1] / 2.0 - 4.5).abs() < 1e-6);
        let one = {
            let mut q = PixelSums::default();
            q.add(0, Vec3::ONE);
            q
        };
        assert_eq!(one.var_of_mean(), 0.0);
    }
}
