//! The film: rows rendered in parallel, `spp` samples per pixel on a low-discrepancy pattern
//! (each batch of a pixel's samples, below, takes consecutive points of its own scrambled
//! Sobol' sequence over the pixel and the first rough hit's draw: `super::strata`), summed in
//! fixed point and averaged. Every random number is a hash of (seed, pixel, sample), so an
//! image does not depend on the thread count (DESIGN.md, Determinism). A guard drops any
//! sample that is NaN or infinite and counts it.
//!
//! A pixel's radiance sums are kept in 128-bit fixed point (2^-47 resolution, about 7e-15):
//! integer sums do not depend on the order of their terms, so sample passes rendered apart
//! ([`Samples`]) merge into exactly the image a single render makes (`vastocean merge`).
//!
//! Besides the image the film keeps what it takes to say how noisy it is:
//! - per pixel, the sample variance of the luminance (from exact fixed-point sums), from which the
//!   variance of the pixel's mean follows (`var_y`, written to the EXR as `Y.variance`);
//! - on request, batch means: the samples of each pixel dealt round-robin into `k` batches
//!   (sample s into batch s mod k), each batch on its own scrambled sequence with its own
//!   random streams, and the mean luminance of each. The batches are `k` independent renders of
//!   the same scene, and they measure the noise of anything computed from images that share
//!   sample seeds: the difference of two scenarios rendered with the same seed is correlated
//!   pixel by pixel, which per-image variances cannot account for, but its `k` batch
//!   differences are independent estimates of the same thing (see `crate::analysis::error`).

use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use super::camera::Camera;
use super::integrator::{CAMERA_BATCH, Counters, SceneRef, TraceSettings};
pub use super::pixel_state::PixelState;
use super::strata::Strata;
use crate::accel::Ray;
use crate::color::luminance;
use crate::image_io::RgbImage;
use crate::rng::Rng;

/// Most batches a film keeps per pixel.
pub const MAX_BATCHES: usize = 8;

/// The mean luminance of each batch of each pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Batches {
    /// Batches per pixel.
    pub k: usize,
    /// Samples in each batch (before NaN samples are dropped, which are counted apart); a
    /// boosted pixel's batches hold its boost times these.
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
    /// Image rows `first..first + rows` of the film (a band of a panorama), batches and all.
    pub fn rows(&self, first: usize, rows: usize) -> Film {
        let w = self.image.width;
        let (a, b) = (first * w, (first + rows) * w);
        Film {
            image: RgbImage {
                width: w,
                height: rows,
                pixels: self.image.pixels[a..b].to_vec(),
            },
            var_y: self.var_y[a..b].to_vec(),
            spp: self.spp,
            batches: self.batches.as_ref().map(|bt| Batches {
                k: bt.k,
                spp: bt.spp.clone(),
                luminance: bt.luminance[a * bt.k..b * bt.k].to_vec(),
            }),
        }
    }

    /// Per pixel, the variance of its mean luminance from the spread of its batch means:
    /// sum_b n_b (Y_b - Y)^2 / ((k - 1) n), n_b the batch's samples, n the pixel's. Unlike
    /// `var_y` (the samples' variance over n, which takes them as independent), it holds for
    /// samples on a low-discrepancy pattern, whose mean varies less than independent samples'
    /// would. `None` without batches.
    pub fn batch_variance_of_mean(&self) -> Option<Vec<f64>> {
        let b = self.batches.as_ref()?;
        let k = b.k;
        let n: f64 = b.spp.iter().map(|&c| c as f64).sum();
        Some(
            b.luminance
                .chunks(k)
                .map(|y| {
                    let mean = y
                        .iter()
                        .zip(&b.spp)
                        .map(|(&v, &c)| v as f64 * c as f64)
                        .sum::<f64>()
                        / n;
                    let ss: f64 = y
                        .iter()
                        .zip(&b.spp)
                        .map(|(&v, &c)| c as f64 * (v as f64 - mean).powi(2))
                        .sum();
                    ss / ((k - 1) as f64 * n)
                })
                .collect(),
        )
    }

    /// For each of `rows`, the mean over its pixels of the variance of the pixel mean (from the
    /// batches when the film has them, [`Film::batch_variance_of_mean`], else `var_y`).
    pub fn row_noise(&self, rows: &[usize]) -> Vec<f64> {
        let w = self.image.width;
        let var = self
            .batch_variance_of_mean()
            .unwrap_or_else(|| self.var_y.iter().map(|&v| v as f64).collect());
        rows.iter()
            .map(|&y| var[y * w..(y + 1) * w].iter().sum::<f64>() / w as f64)
            .collect()
    }

    /// [`Film::noise_rms`] over the pixels whose centre looks below the horizon (the sea), and
    /// that over the sea's mean luminance; `None` with fewer than two samples per pixel or no
    /// such pixel.
    pub fn noise_rms_sea(&self, camera: &Camera) -> Option<(f64, f64)> {
        if self.spp < 2 {
            return None;
        }
        let w = self.image.width.max(1);
        // row sums side by side, added in row order (the same figure for any thread count)
        let rows: Vec<(f64, f64, usize)> = self
            .var_y
            .par_chunks(w)
            .zip(self.image.pixels.par_chunks(w))
            .enumerate()
            .map(|(y, (var_y, pixels))| {
                let (mut var, mut lum, mut n) = (0.0f64, 0.0f64, 0usize);
                for (x, (&v, &p)) in var_y.iter().zip(pixels).enumerate() {
                    if camera.direction(x as f32 + 0.5, y as f32 + 0.5).y < 0.0 {
                        var += v as f64;
                        lum += crate::color::luminance(p) as f64;
                        n += 1;
                    }
                }
                (var, lum, n)
            })
            .collect();
        let (var, lum, n) = rows
            .iter()
            .fold((0.0, 0.0, 0), |(a, b, c), r| (a + r.0, b + r.1, c + r.2));
        (n > 0).then(|| {
            let rms = (var / n as f64).sqrt();
            (rms, rms / (lum / n as f64).max(1e-30))
        })
    }

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
pub fn film_bytes(pixels: u64, batches: usize, keep_states: bool) -> u64 {
    let states = if keep_states {
        2 * std::mem::size_of::<PixelState>() // the rows' states, then the pass file's
    } else {
        0
    };
    let per_pixel = states
        + 2 * (12 + 4 + 4 * batches) // image, variance, batch means: the rows', then the film's
        + 16 + 3; // EXR channels (R, G, B, Y.variance), PNG bytes
    pixels * per_pixel as u64
}

/// Which of a pixel's samples a render takes: those with index s = `pass` mod `passes` (all of
/// them for pass 0 of 1). The samples of passes 0..passes are disjoint and together are
/// exactly those of one render. A pixel takes `spp` samples, or `spp * boost[pixel]` when a
/// boost map is given (row-major, one factor a pixel): its further samples continue its
/// sequences, so its batches stay independent and equally filled. A boost of 0 leaves a pixel
/// unsampled (black, variance 0), so a pilot of which only some rows are read traces no other.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Samples<'a> {
    pub pass: usize,
    pub passes: usize,
    pub boost: Option<&'a [u16]>,
}

impl Samples<'_> {
    pub const ALL: Samples<'static> = Samples {
        pass: 0,
        passes: 1,
        boost: None,
    };

    /// Samples of pixel `pixel` at `spp` samples per pixel before any boost.
    fn of_pixel(&self, pixel: usize, spp: u32) -> u32 {
        self.boost.map_or(spp, |b| spp * u32::from(b[pixel]))
    }
}

/// What one pixel accumulates: its state and the luminance sums of its batches.
#[derive(Clone, Copy, Default)]
struct PixelSums {
    state: PixelState,
    batch: [f64; MAX_BATCHES],
    batch_n: [u32; MAX_BATCHES],
}

impl PixelSums {
    fn add(&mut self, batch: usize, l: Vec3) {
        let y = luminance(l.to_array());
        self.state.add_with_luminance(l, y);
        self.batch[batch] += y as f64;
        self.batch_n[batch] += 1;
    }
}

impl Film {
    /// The film of `w` x `h` pixel states (row-major) rendered at `spp` samples per pixel.
    pub fn from_states(w: usize, h: usize, spp: u32, states: &[PixelState]) -> Film {
        let mut image = RgbImage::new(w, h);
        for (p, s) in image.pixels.iter_mut().zip(states) {
            *p = s.mean();
        }
        Film {
            image,
            var_y: states.iter().map(PixelState::var_of_mean).collect(),
            spp,
            batches: None,
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
    let (film, _, c) = render_image_samples(
        scene,
        camera,
        camera_height_m,
        spp,
        seed,
        settings,
        batches,
        Samples::ALL,
        false,
        progress,
    );
    (film, c)
}

/// [`render_image`] taking only the `samples` of `spp` (all, or one pass, and boosted pixels
/// more); also returns each pixel's state, which merges exactly with other passes'.
#[allow(clippy::too_many_arguments)]
pub fn render_image_samples(
    scene: &SceneRef,
    camera: &Camera,
    camera_height_m: f32,
    spp: u32,
    seed: u64,
    settings: &TraceSettings,
    batches: usize,
    samples: Samples,
    keep_states: bool,
    progress: bool,
) -> (Film, Vec<PixelState>, Counters) {
    // Footprints spread from the camera's pixels.
    let settings = &TraceSettings {
        pixel_spread_rad: camera.pixel_spread_rad(),
        ..*settings
    };
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
    type Row = (Vec<PixelState>, Vec<[f32; 3]>, Vec<f32>, Vec<f32>, Counters);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        // one row per job: rows near the horizon and the sun cost many times the rest, and a
        // leaf of many rows left for last kept one core idle at the end of the trace
        .with_max_len(1)
        .map(|y| {
            let mut c = Counters::default();
            let row = (0..w)
                .map(|x| {
                    let pixel = (y * w + x) as u64;
                    let mut acc = PixelSums::default();
                    let pixel_spp = samples.of_pixel(pixel as usize, spp);
                    if samples.pass as u32 >= pixel_spp {
                        // no sample of this pixel in this pass (a boost of 0 leaves it out)
                        return acc;
                    }
                    // Each batch runs its own scrambled sequence, so batches are independent
                    // renders (their noise estimate is unbiased).
                    // (the keys [seed, pixel] every stream of the pixel starts with, hashed once)
                    let keys = Rng::keyed(&[seed, pixel]);
                    let strata: [Strata; MAX_BATCHES] = std::array::from_fn(|b| {
                        Strata::new(keys.then(u64::MAX - b as u64).next_u64())
                    });
                    // The triangle the pixel's centre ray hits, which its camera rays take
                    // without the BVH where they can (see `SceneRef::predict_camera_prim`).
                    let pixel_rays = camera.pixel_rays(x, y);
                    let centre = pixel_rays.direction(0.5, 0.5);
                    let predicted =
                        scene.predict_camera_prim(&Ray::new(origin, centre.to_array()), &mut c);
                    // The pixel's samples go to the integrator CAMERA_BATCH at a time, so that
                    // their paths go through each stage together.
                    let mut sample_ids = (samples.pass as u32..pixel_spp).step_by(samples.passes);
                    loop {
                        let mut ids = [0u32; CAMERA_BATCH];
                        let mut n = 0;
                        for s in sample_ids.by_ref().take(CAMERA_BATCH) {
                            ids[n] = s;
                            n += 1;
                        }
                        if n == 0 {
                            break;
                        }
                        let chunk = &ids[..n];
                        let mut rays = [Ray::new(origin, [0.0, 1.0, 0.0]); CAMERA_BATCH];
                        let mut draws = [[0.0f32; 2]; CAMERA_BATCH];
                        let mut rngs: [Rng; CAMERA_BATCH] =
                            std::array::from_fn(|_| Rng::keyed(&[]));
                        for (((&s, ray), rng), draw) in
                            chunk.iter().zip(&mut rays).zip(&mut rngs).zip(&mut draws)
                        {
                            let [u1, u2, jx, jy] = strata[s as usize % k].point(s / k as u32);
                            *draw = [u1, u2];
                            let dir = pixel_rays.direction(jx, jy);
                            *ray = Ray::new(origin, dir.to_array());
                            *rng = keys.then(s as u64);
                        }
                        let mut ls = [Vec3::ZERO; CAMERA_BATCH];
                        scene.radiance_camera_batch(
                            &rays[..n],
                            Some(&draws[..n]),
                            predicted,
                            settings,
                            &mut rngs[..n],
                            &mut c,
                            &mut ls[..n],
                        );
                        for (&s, &l) in chunk.iter().zip(&ls) {
                            if l.is_finite() {
                                // With fewer batches kept, the k sequences fold onto them.
                                acc.add(s as usize % k % keep.max(1), l);
                            } else {
                                c.nan += 1;
                            }
                        }
                    }
                    acc
                })
                .collect::<Vec<PixelSums>>();
            bar.inc(1);
            // Each row keeps the image, the variance and the batch means (not the sums of every
            // batch), and the exact states only for a pass file (112 bytes a pixel).
            let means = row
                .iter()
                .flat_map(|p| (0..keep).map(|j| (p.batch[j] / p.batch_n[j].max(1) as f64) as f32))
                .collect();
            let states = if keep_states {
                row.iter().map(|p| p.state).collect()
            } else {
                Vec::new()
            };
            let pixels = row.iter().map(|p| p.state.mean()).collect();
            let var_y = row.iter().map(|p| p.state.var_of_mean()).collect();
            (states, pixels, var_y, means, c)
        })
        .collect();
    bar.finish_and_clear();
    let mut states = Vec::with_capacity(if keep_states { w * h } else { 0 });
    let mut image = RgbImage::new(w, h);
    let mut var_y = Vec::with_capacity(w * h);
    let mut batch_means = (keep >= 2).then(|| Batches {
        k: keep,
        // Sequence s mod k feeds batch (s mod k) mod keep.
        spp: (0..keep)
            .map(|b| (0..spp as usize).filter(|s| (s % k) % keep == b).count() as u32)
            .collect(),
        luminance: Vec::with_capacity(w * h * keep),
    });
    let mut counters = Counters::default();
    // Rows are freed as they are moved into the film.
    for (y, (row, pixels, v, means, c)) in rows.into_iter().enumerate() {
        states.extend_from_slice(&row);
        image.pixels[y * w..(y + 1) * w].copy_from_slice(&pixels);
        var_y.extend_from_slice(&v);
        if let Some(b) = &mut batch_means {
            b.luminance.extend_from_slice(&means);
        }
        counters += c;
    }
    let film = Film {
        image,
        var_y,
        spp,
        batches: batch_means,
    };
    (film, states, counters)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variance_and_batches_match_direct_formulas() {
        let samples = [0.5f32, 2.0, 1.25, 7.0, 0.0];
        let mut sums = PixelSums::default();
        for (s, &v) in samples.iter().enumerate() {
            sums.add(s % 2, Vec3::splat(v));
        }
        let p = sums.state;
        let n = samples.len() as f64;
        let mean = samples.iter().map(|&v| v as f64).sum::<f64>() / n;
        let var = samples
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / (n - 1.0);
        assert!((p.var_of_mean() as f64 - var / n).abs() < 1e-6 * var);
        assert_eq!(&sums.batch_n[..2], &[3, 2]);
        let even = (0.5 + 1.25 + 0.0) / 3.0;
        assert!((sums.batch[0] / 3.0 - even).abs() < 1e-6);
        assert!((sums.batch[1] / 2.0 - 4.5).abs() < 1e-6);
        let one = {
            let mut q = PixelState::default();
            q.add(Vec3::ONE);
            q
        };
        assert_eq!(one.var_of_mean(), 0.0);
    }

    #[test]
    fn variance_of_the_mean_from_batches() {
        // Two pixels, four batches of two samples: the spread of the batch means over k - 1,
        // over k (the mean of k equal batches).
        let means = [1.0f32, 2.0, 3.0, 6.0, 5.0, 5.0, 5.0, 5.0];
        let film = Film {
            image: RgbImage::new(2, 1),
            var_y: vec![0.0; 2],
            spp: 8,
            batches: Some(Batches {
                k: 4,
                spp: vec![2; 4],
                luminance: means.to_vec(),
            }),
        };
        let v = film.batch_variance_of_mean().unwrap();
        // Batch means 1, 2, 3, 6: mean 3, squares 4 + 1 + 0 + 9 = 14; 14 / 3 / 4.
        assert!((v[0] - 14.0 / 12.0).abs() < 1e-12, "{v:?}");
        assert_eq!(v[1], 0.0);
        assert!(
            Film {
                batches: None,
                ..film
            }
            .batch_variance_of_mean()
            .is_none()
        );
    }

    #[test]
    fn the_sea_noise_is_the_rms_over_the_pixels_below_the_horizon() {
        // a panorama's lower half looks down; rows summed side by side agree with one pass
        let panorama = crate::config::Projection::Equirect { band_deg: None };
        let camera = Camera::new(panorama, 64, 2.0);
        let (w, h) = (camera.width, camera.height);
        let mut rng = crate::rng::Rng::keyed(&[5]);
        let film = Film {
            image: RgbImage {
                width: w,
                height: h,
                pixels: (0..w * h).map(|_| [rng.f64() as f32; 3]).collect(),
            },
            var_y: (0..w * h).map(|_| rng.f64() as f32).collect(),
            spp: 4,
            batches: None,
        };
        let (mut var, mut lum, mut n) = (0.0f64, 0.0f64, 0usize);
        for i in 0..w * h {
            if camera
                .direction((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)
                .y
                < 0.0
            {
                var += film.var_y[i] as f64;
                lum += crate::color::luminance(film.image.pixels[i]) as f64;
                n += 1;
            }
        }
        assert_eq!(n, w * h / 2);
        let (rms, relative) = film.noise_rms_sea(&camera).unwrap();
        let want = (var / n as f64).sqrt();
        assert!((rms / want - 1.0).abs() < 1e-12, "{rms} {want}");
        assert!((relative / (want / (lum / n as f64)) - 1.0).abs() < 1e-12);
        // the same bits on one thread and on several
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads);
            pool.build()
                .unwrap()
                .install(|| film.noise_rms_sea(&camera))
        };
        assert_eq!(on(1), on(4));
        assert_eq!(on(1), Some((rms, relative)));
    }

    #[test]
    fn states_merge_exactly_in_any_order_and_round_trip_through_bytes() {
        let values = [0.3f32, 1e-9, 2000.0, 0.07, 5.5, 1e6, 0.0, 0.123_456_7];
        let mut whole = PixelState::default();
        values
            .iter()
            .for_each(|&v| whole.add(Vec3::new(v, 0.5 * v, 2.0 * v)));
        // Split three ways (s mod 3), merged in a scrambled order.
        let mut parts = [PixelState::default(); 3];
        for (s, &v) in values.iter().enumerate() {
            parts[s % 3].add(Vec3::new(v, 0.5 * v, 2.0 * v));
        }
        let mut merged = parts[2];
        merged.merge(&parts[0]);
        merged.merge(&parts[1]);
        assert_eq!(merged, whole);
        assert_eq!(merged.mean(), whole.mean());
        assert_eq!(merged.var_of_mean(), whole.var_of_mean());
        let mut bytes = Vec::new();
        merged.to_bytes(&mut bytes);
        assert_eq!(bytes.len(), PixelState::BYTES);
        assert_eq!(PixelState::from_bytes(&bytes), merged);
    }
}
