//! A sky map's sun as a light: the part of the map above a cap in a window of texels around
//! its brightest, sampled in proportion to its bilinear lookup.
//!
//! The split is exact texel by texel: each texel of the window brighter than the cap gives its
//! luminance above the cap (hue kept) to the sun's part and keeps the cap, and since the
//! bilinear lookup is linear in the texels, every lookup is the capped map's plus the part's.
//! The cap is the larger of [`SUN_CONTRAST`] times the median sky and a thousandth of the
//! peak: what stays in the window is at most that, which the BSDF's own samples find without
//! much noise. A map whose peak is under [`SUN_CONTRAST`] times its median has no sun.
//!
//! Sampling: a texel of the part with probability in proportion to its luminance, then a point
//! of its bilinear footprint by a tent in each axis of the map. The density in map coordinates
//! is then the part's own bilinear lookup over the sum of the texels' luminances, so a
//! sample's radiance over density varies only with its texel's solid angle (the cosine of its
//! elevation) and hue: by a few per cent over the few texels of a sun.

use glam::Vec3;

use super::map::{read_taps_by, taps};
use super::tools::{SUN_CONTRAST, median_luminance_above_horizon};
use crate::color::luminance;
use crate::equirect;
use crate::image_io::RgbImage;

/// The angle from the brightest texel within which texels may hold the sun, rad.
const WINDOW_RAD: f64 = 0.05;

/// The part of a map above its cap near its sun.
#[derive(Clone, Debug)]
pub(super) struct MapSun {
    /// The map's size.
    w: usize,
    h: usize,
    /// The window: its first row and column (columns wrap round) and its size.
    row0: usize,
    col0: usize,
    rows: usize,
    cols: usize,
    /// The part's texels in the window, row by row (zero where a texel is under the cap).
    part: Vec<[f32; 3]>,
    /// The window's texels with a part, and the running sum of their luminances.
    lit: Vec<u32>,
    cumulative: Vec<f64>,
    /// The brightest texel's direction.
    pub(super) peak: Vec3,
}

impl MapSun {
    /// The map's sun, or `None` for a map without one (or whose sun is within the window of a
    /// pole, where the map's rows meet).
    pub(super) fn new(img: &RgbImage) -> Option<MapSun> {
        let (w, h) = (img.width, img.height);
        let upper = &img.pixels[..w * (h / 2)];
        let (peak_at, peak) = upper
            .iter()
            .map(|&c| luminance(c))
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        let median = median_luminance_above_horizon(img);
        if !(peak >= SUN_CONTRAST as f32 * median && peak > 0.0) {
            return None;
        }
        let cap = (SUN_CONTRAST as f32 * median).max(1e-3 * peak);
        let (pj, pi) = (peak_at / w, peak_at % w);
        let centre = equirect::direction64(
            equirect::row_elevation(pj, h),
            equirect::column_azimuth(pi, w),
        );
        // A box of rows within the window's angle of the peak's and columns within it at the
        // box's row farthest from the equator; of it, the texels within the window's angle.
        let reach = (WINDOW_RAD * h as f64 / std::f64::consts::PI).ceil() as usize;
        if pj < reach + 1 || pj + reach + 2 > h {
            return None;
        }
        let (row0, rows) = (pj - reach, 2 * reach + 1);
        let narrowest = [row0, row0 + rows - 1]
            .map(|j| equirect::row_elevation(j, h).cos())
            .into_iter()
            .fold(1.0, f64::min);
        let half = (WINDOW_RAD / (narrowest * std::f64::consts::TAU / w as f64)).ceil() as usize;
        let (col0, cols) = if 2 * half + 1 >= w {
            (0, w)
        } else {
            ((pi + w - half) % w, 2 * half + 1)
        };
        let mut part = vec![[0.0; 3]; rows * cols];
        let (mut lit, mut cumulative, mut sum) = (Vec::new(), Vec::new(), 0.0f64);
        for r in 0..rows {
            for c in 0..cols {
                let (i, j) = ((col0 + c) % w, row0 + r);
                let texel = img.get(i, j);
                let l = luminance(texel);
                let at = equirect::direction64(
                    equirect::row_elevation(j, h),
                    equirect::column_azimuth(i, w),
                );
                if l > cap && at.angle_between(centre) <= WINDOW_RAD {
                    let k = r * cols + c;
                    part[k] = texel.map(|v| v * (1.0 - cap / l));
                    sum += luminance(part[k]) as f64;
                    lit.push(k as u32);
                    cumulative.push(sum);
                }
            }
        }
        if lit.is_empty() {
            return None;
        }
        Some(MapSun {
            w,
            h,
            row0,
            col0,
            rows,
            cols,
            part,
            lit,
            cumulative,
            peak: centre.as_vec3(),
        })
    }

    /// How far from the brightest texel (as the camera sees it) a direction may still read
    /// the part: the window plus a lookup's reach, sqrt 2 texel pitches.
    pub(super) fn reach_rad(&self) -> f32 {
        (WINDOW_RAD + std::f64::consts::SQRT_2 * std::f64::consts::PI / self.h as f64) as f32
    }

    /// The part's texel at map column `i`, row `j` (zero outside the window).
    #[inline]
    fn texel(&self, i: u32, j: u32) -> [f32; 3] {
        let r = (j as usize).wrapping_sub(self.row0);
        let c = (i as usize + self.w - self.col0) % self.w;
        if r < self.rows && c < self.cols {
            self.part[r * self.cols + c]
        } else {
            [0.0; 3]
        }
    }

    /// The part's radiance along `d` (the map's bilinear lookup of the part).
    pub(super) fn radiance(&self, d: Vec3) -> Vec3 {
        let t = taps(d.to_array(), self.w, self.h);
        Vec3::from(read_taps_by(&t, |i, j| self.texel(i, j)))
    }

    /// The density per steradian of [`MapSun::sample`] at `d`, given the part's radiance
    /// there: the lookup's luminance over the texels' sum, over the map's steradians per
    /// texel at `d`'s elevation.
    pub(super) fn pdf(&self, d: Vec3, radiance: Vec3) -> f32 {
        let total = *self.cumulative.last().unwrap_or(&0.0);
        let cos = (1.0 - d.y * d.y).max(0.0).sqrt();
        let texel_sr = equirect::texel_solid_angle_at(cos as f64, self.w, self.h);
        if total == 0.0 || texel_sr == 0.0 {
            return 0.0;
        }
        (luminance(radiance.to_array()) as f64 / (total * texel_sr)) as f32
    }

    /// A direction from two uniform numbers: a texel by its luminance (`u1`), then a tent
    /// about its centre in each axis (what is left of `u1`, and `u2`).
    pub(super) fn sample(&self, u1: f32, u2: f32) -> Vec3 {
        let total = *self.cumulative.last().unwrap_or(&0.0);
        let target = u1 as f64 * total;
        let k = self
            .cumulative
            .partition_point(|&c| c <= target)
            .min(self.lit.len() - 1);
        let below = if k == 0 { 0.0 } else { self.cumulative[k - 1] };
        let reuse = ((target - below) / (self.cumulative[k] - below)).clamp(0.0, 1.0) as f32;
        let at = self.lit[k] as usize;
        let (r, c) = (at / self.cols, at % self.cols);
        let x = ((self.col0 + c) % self.w) as f32 + 0.5 + tent(reuse);
        let y = (self.row0 + r) as f32 + 0.5 + tent(u2);
        let x = x.rem_euclid(self.w as f32);
        equirect::pixel_direction(x, y, self.w as f32, self.h as f32)
    }
}

/// The inverse of the tent distribution on (-1, 1): a bilinear lookup's weight of a texel.
#[inline]
fn tent(u: f32) -> f32 {
    if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 * (1.0 - u)).sqrt()
    }
}
