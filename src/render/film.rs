//! The film: rows rendered in parallel, `spp` samples per pixel on a low-discrepancy pattern
//! (the R2 sequence of Roberts 2018, rotated per pixel by a hashed offset: Cranley-Patterson),
//! summed in f64 and averaged. Every random number is a hash of (seed, pixel, sample), so an
//! image does not depend on the thread count (DESIGN.md, Determinism). A guard drops any
//! sample that is NaN or infinite and counts it.

use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

use super::camera::Camera;
use super::integrator::{Counters, SceneRef, TraceSettings};
use crate::accel::Ray;
use crate::image_io::RgbImage;
use crate::rng::Rng;

/// R2 generator constants: 1/phi2 and 1/phi2^2 for the plastic number phi2.
const R2: (f64, f64) = (0.754_877_666_246_692_7, 0.569_840_290_998_053_3);

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
) -> (RgbImage, Counters) {
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
    let rows: Vec<(Vec<[f32; 3]>, Counters)> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut c = Counters::default();
            let row = (0..w)
                .map(|x| {
                    let pixel = (y * w + x) as u64;
                    let mut sum = [0f64; 3];
                    let mut good = 0u32;
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
                            for k in 0..3 {
                                sum[k] += l[k] as f64;
                            }
                            good += 1;
                        } else {
                            c.nan += 1;
                        }
                    }
                    let n = good.max(1) as f64;
                    [
                        (sum[0] / n) as f32,
                        (sum[1] / n) as f32,
                        (sum[2] / n) as f32,
                    ]
                })
                .collect();
            bar.inc(1);
            (row, c)
        })
        .collect();
    bar.finish_and_clear();
    let mut img = RgbImage::new(w, h);
    let mut counters = Counters::default();
    for (y, (row, c)) in rows.into_iter().enumerate() {
        img.pixels[y * w..(y + 1) * w].copy_from_slice(&row);
        counters += c;
    }
    (img, counters)
}
