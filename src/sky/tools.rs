//! Tools for equirectangular sky maps (convention of [`crate::equirect`]): statistics (solid-angle
//! weighted luminance, the sun found as a blurred luminance maximum, the share of energy near the
//! horizon), import of real HDR photographs with the ground below the horizon removed as the
//! paper did for its skies (section 5), rotation in azimuth, and a contact sheet of previews.

use glam::{DVec3, Vec3};
use serde::Serialize;

use crate::color::luminance;
use crate::equirect::{column_azimuth, direction64 as direction, row_elevation, texel_solid_angle};
use crate::image_io::{RgbImage, auto_exposure, tonemap};

/// What `sky info` reports.
#[derive(Clone, Debug, Serialize)]
pub struct SkyInfo {
    pub width: usize,
    pub height: usize,
    /// Solid-angle weighted mean luminance over the whole sphere.
    pub mean_radiance: f64,
    /// Largest texel luminance.
    pub peak_radiance: f64,
    /// Direction of the sun: the brightest region of the upper hemisphere, when it is a sun
    /// ([`find_sun`]); `None` (null in JSON) for a sky without one, such as an overcast sky.
    pub sun_elevation_deg: Option<f64>,
    pub sun_azimuth_deg: Option<f64>,
    /// The brightest region's peak luminance over the upper hemisphere's median luminance.
    pub sun_contrast: f64,
    /// Share of the sphere's solid-angle weighted luminance within 5 degrees above or below the
    /// horizon.
    pub horizon_energy_fraction: f64,
}

fn lum64(c: [f32; 3]) -> f64 {
    luminance(c) as f64
}

pub fn info(img: &RgbImage) -> SkyInfo {
    let (w, h) = (img.width, img.height);
    let (mut total, mut band, mut omega, mut peak) = (0.0, 0.0, 0.0, 0.0f64);
    for j in 0..h {
        let da = texel_solid_angle(j, w, h);
        let near = row_elevation(j, h).to_degrees().abs() <= 5.0;
        for i in 0..w {
            let l = lum64(img.get(i, j));
            peak = peak.max(l);
            total += l * da;
            omega += da;
            if near {
                band += l * da;
            }
        }
    }
    let region = brightest_region(img);
    let sun =
        (region.contrast >= SUN_CONTRAST).then_some((region.elevation_deg, region.azimuth_deg));
    SkyInfo {
        width: w,
        height: h,
        mean_radiance: total / omega,
        peak_radiance: peak,
        sun_elevation_deg: sun.map(|s| s.0),
        sun_azimuth_deg: sun.map(|s| s.1),
        sun_contrast: region.contrast,
        horizon_energy_fraction: if total > 0.0 { band / total } else { 0.0 },
    }
}

/// Circular box blur of one row with half-width `r`.
fn blur_row(row: &[f64], r: usize) -> Vec<f64> {
    let n = row.len();
    let r = r.min((n - 1) / 2);
    let mut out = vec![0.0; n];
    let mut sum: f64 = (0..=2 * r).map(|k| row[(k + n - r) % n]).sum();
    for (i, o) in out.iter_mut().enumerate() {
        *o = sum / (2 * r + 1) as f64;
        sum += row[(i + r + 1) % n] - row[(i + n - r) % n];
    }
    out
}

/// How much brighter than the median sky above the horizon the brightest region must peak to be
/// called a sun. A CIE overcast sky peaks at about 3x its median (zenith against horizon), a clear
/// sky's sun at thousands, and a photographed sun clipped as `study plan --clip-sun` does at its
/// factor (100 by default).
pub const SUN_CONTRAST: f64 = 10.0;

/// The brightest region of the upper hemisphere: where, and how much brighter than the median.
#[derive(Clone, Copy, Debug)]
pub struct BrightRegion {
    pub elevation_deg: f64,
    pub azimuth_deg: f64,
    /// Peak luminance in the region over the median luminance of the upper hemisphere's texels
    /// (infinite for a black sky with a bright spot, 1 for a uniform sky).
    pub contrast: f64,
}

/// (elevation, azimuth) in degrees of the sun, or `None` if the brightest region is not one (its
/// contrast is below [`SUN_CONTRAST`], as in an overcast or uniform sky).
pub fn find_sun(img: &RgbImage) -> Option<(f64, f64)> {
    let r = brightest_region(img);
    (r.contrast >= SUN_CONTRAST).then_some((r.elevation_deg, r.azimuth_deg))
}

/// The brightest region above the horizon: the maximum of the luminance blurred over about a
/// degree (a single hot texel does not win over the sun), refined by the luminance-weighted
/// centroid of the bright texels around it.
pub fn brightest_region(img: &RgbImage) -> BrightRegion {
    let (w, h) = (img.width, img.height);
    let rows = h / 2;
    let ry = (h / 180).max(1);
    let lum: Vec<Vec<f64>> = (0..rows)
        .map(|j| (0..w).map(|i| lum64(img.get(i, j))).collect())
        .collect();
    // Blur about equally in angle: rows near the zenith are narrower, so more texels.
    let hblur: Vec<Vec<f64>> = lum
        .iter()
        .enumerate()
        .map(|(j, row)| {
            let c = row_elevation(j, h).cos().max(1e-3);
            blur_row(row, ((ry as f64 / c).round() as usize).min(w / 2))
        })
        .collect();
    let (mut best, mut at) = (f64::NEG_INFINITY, (0, 0));
    for j in 0..rows {
        let (lo, hi) = (j.saturating_sub(ry), (j + ry).min(rows - 1));
        let mut column = vec![0.0; w];
        for row in &hblur[lo..=hi] {
            column.iter_mut().zip(row).for_each(|(c, v)| *c += v);
        }
        for (i, v) in column.into_iter().enumerate() {
            if v > best {
                best = v;
                at = (j, i);
            }
        }
    }
    let (jr, ir) = (3 * ry, 3 * ry * w / h.max(1));
    let window = |f: &mut dyn FnMut(usize, usize)| {
        for j in at.0.saturating_sub(jr)..=(at.0 + jr).min(rows - 1) {
            for di in 0..=2 * ir {
                f(j, (at.1 + w + di - ir) % w);
            }
        }
    };
    let mut max = 0.0f64;
    window(&mut |j, i| max = max.max(lum[j][i]));
    let mut sum = DVec3::ZERO;
    window(&mut |j, i| {
        if lum[j][i] >= 0.5 * max {
            let d = direction(row_elevation(j, h), column_azimuth(i, w));
            sum += d * lum[j][i] * texel_solid_angle(j, w, h);
        }
    });
    let d = sum
        .try_normalize()
        .unwrap_or_else(|| direction(row_elevation(at.0, h), column_azimuth(at.1, w)));
    let mut all: Vec<f64> = lum.iter().flatten().copied().collect();
    let mid = all.len() / 2;
    let median = *all.select_nth_unstable_by(mid, f64::total_cmp).1;
    BrightRegion {
        elevation_deg: d.y.clamp(-1.0, 1.0).asin().to_degrees(),
        azimuth_deg: d.z.atan2(d.x).to_degrees().rem_euclid(360.0),
        contrast: if max == median { 1.0 } else { max / median },
    }
}

/// How `sky import` treats the part of a photograph below the horizon.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Ground {
    /// A smooth continuation of the sky just above the horizon, darkening with depression.
    Fill,
    /// The sky reflected in the horizon.
    Mirror,
    /// Leave the photograph's ground.
    Keep,
}

crate::config::choice!(Ground { Fill => "fill", Mirror => "mirror", Keep => "keep" });

/// Replaces the lower half of the map (everything below the horizon) as `ground` says.
pub fn remove_ground(img: &mut RgbImage, ground: Ground) {
    let (w, h) = (img.width, img.height);
    let hr = h / 2;
    match ground {
        Ground::Keep => {}
        Ground::Mirror => {
            for k in 0..h - hr {
                for i in 0..w {
                    img.pixels[(hr + k) * w + i] = img.get(i, hr - 1 - k);
                }
            }
        }
        Ground::Fill => {
            // The few rows (about 3 degrees) above the horizon, per column, blurred in azimuth
            // (a 30 degree box three times: a Gaussian of about 15 degrees) so trees and
            // buildings on the horizon leave no streaks.
            let k = (h / 64).max(2).min(hr);
            let mut fill: [Vec<f64>; 3] = std::array::from_fn(|c| {
                (0..w)
                    .map(|i| (hr - k..hr).map(|j| img.get(i, j)[c] as f64).sum::<f64>() / k as f64)
                    .collect()
            });
            let r = (w / 24).max(1);
            for ch in fill.iter_mut() {
                *ch = blur_row(&blur_row(&blur_row(ch, r), r), r);
            }
            let horizon_mean = (0..w).map(|i| lum64(img.get(i, hr - 1))).sum::<f64>() / w as f64;
            for j in hr..h {
                let depression = -row_elevation(j, h).to_degrees();
                let fade = 0.3 + 0.7 * (-depression / 3.0).exp();
                for (i, px) in img.pixels[j * w..(j + 1) * w].iter_mut().enumerate() {
                    let mut c = [0, 1, 2].map(|ch| (fill[ch][i] * fade) as f32);
                    // The ground must never outshine the horizon: that would light the sea
                    // from below.
                    let l = lum64(c);
                    if l > horizon_mean {
                        let s = (horizon_mean / l) as f32;
                        c = c.map(|v| v * s);
                    }
                    *px = c;
                }
            }
        }
    }
}

/// The median texel luminance of the map's upper half (0 for a map of one row).
pub fn median_luminance_above_horizon(img: &RgbImage) -> f32 {
    let upper = img.width * (img.height / 2);
    let mut lum: Vec<f32> = img.pixels[..upper].iter().map(|&c| luminance(c)).collect();
    if lum.is_empty() {
        return 0.0;
    }
    let mid = lum.len() / 2;
    *lum.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// Clips the map as a photograph clips the sun: texels whose luminance exceeds `factor` times
/// the median luminance above the horizon are scaled down to that luminance (hue kept).
/// Returns the clip luminance and how many texels it touched.
pub fn clip_relative(img: &mut RgbImage, factor: f32) -> (f32, usize) {
    if img.height < 2 {
        return (0.0, 0);
    }
    let limit = factor * median_luminance_above_horizon(img);
    let mut clipped = 0;
    for p in &mut img.pixels {
        let l = luminance(*p);
        if l > limit && l > 0.0 {
            *p = p.map(|c| c * limit / l);
            clipped += 1;
        }
    }
    (limit, clipped)
}

/// Sets negative (finite) components to zero, as colour-space conversions leave in real HDR
/// photographs; returns how many there were and the most negative. NaN and infinity stay, for
/// validation to reject.
pub fn clamp_negative(img: &mut RgbImage) -> (usize, f32) {
    let (mut n, mut worst) = (0, 0.0f32);
    for v in img.pixels.iter_mut().flatten() {
        if *v < 0.0 {
            n += 1;
            worst = worst.min(*v);
            *v = 0.0;
        }
    }
    (n, worst)
}

/// Rotates the map in azimuth by a whole number of texels (lossless) as close to `degrees` as
/// possible; returns the rotation applied, degrees.
pub fn rotate_azimuth(img: &mut RgbImage, degrees: f64) -> f64 {
    let w = img.width;
    let shift = ((degrees / 360.0 * w as f64).round() as i64).rem_euclid(w as i64) as usize;
    for row in img.pixels.chunks_mut(w) {
        row.rotate_right(shift);
    }
    shift as f64 * 360.0 / w as f64
}

/// Rotates the map so that its sun ([`find_sun`]) lands at `azimuth_deg`; returns the rotation,
/// or `None` (the map untouched) if the map has no sun.
pub fn rotate_sun_to(img: &mut RgbImage, azimuth_deg: f64) -> Option<f64> {
    let (_, az) = find_sun(img)?;
    Some(rotate_azimuth(img, azimuth_deg - az))
}

/// An sRGB contact sheet: each map tone-mapped with its own auto exposure, scaled to
/// `thumb_width` (box filter), `columns` across with a gap. Returns (width, height, RGB8).
pub fn contact_sheet(maps: &[RgbImage], thumb_width: usize, columns: usize) -> (u32, u32, Vec<u8>) {
    let (tw, th, gap) = (thumb_width, thumb_width / 2, 6);
    let cols = columns.clamp(1, maps.len().max(1));
    let rows = maps.len().div_ceil(cols).max(1);
    let (sw, sh) = (cols * (tw + gap) + gap, rows * (th + gap) + gap);
    let mut buf = vec![40u8; sw * sh * 3];
    for (n, img) in maps.iter().enumerate() {
        let exposure = auto_exposure(img);
        let (ox, oy) = (gap + (n % cols) * (tw + gap), gap + (n / cols) * (th + gap));
        for y in 0..th {
            for x in 0..tw {
                let (x0, x1) = (
                    x * img.width / tw,
                    ((x + 1) * img.width / tw).max(x * img.width / tw + 1),
                );
                let (y0, y1) = (
                    y * img.height / th,
                    ((y + 1) * img.height / th).max(y * img.height / th + 1),
                );
                let mut s = Vec3::ZERO;
                for yy in y0..y1 {
                    for xx in x0..x1 {
                        s += Vec3::from(img.get(xx, yy));
                    }
                }
                let c = tonemap((s / ((x1 - x0) * (y1 - y0)) as f32).to_array(), exposure);
                let o = ((oy + y) * sw + ox + x) * 3;
                buf[o..o + 3].copy_from_slice(&c);
            }
        }
    }
    (sw as u32, sh as u32, buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_caps_the_sun_at_a_multiple_of_the_median_sky() {
        let mut img = RgbImage::new(8, 4);
        img.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
        img.pixels[3] = [5000.0, 4000.0, 3000.0];
        let (limit, n) = clip_relative(&mut img, 100.0);
        assert_eq!((limit, n), (100.0, 1));
        assert!((luminance(img.pixels[3]) - 100.0).abs() < 1e-3);
        // the hue stays: R > G > B
        assert!(img.pixels[3][0] > img.pixels[3][1] && img.pixels[3][1] > img.pixels[3][2]);
        assert_eq!(img.pixels[4], [1.0; 3]);
    }

    #[test]
    fn blur_row_keeps_the_mean_and_wraps() {
        let row = [0.0, 0.0, 0.0, 0.0, 0.0, 9.0];
        let b = blur_row(&row, 1);
        assert_eq!(b, vec![3.0, 0.0, 0.0, 0.0, 3.0, 3.0]);
    }

    #[test]
    fn rotation_by_whole_texels_is_lossless() {
        let mut img = RgbImage::new(8, 4);
        img.pixels[1] = [1.0; 3];
        let applied = rotate_azimuth(&mut img, 90.0);
        assert_eq!(applied, 90.0);
        assert_eq!(img.pixels[3], [1.0; 3]);
        rotate_azimuth(&mut img, -90.0);
        assert_eq!(img.pixels[1], [1.0; 3]);
    }

    #[test]
    fn only_a_sky_with_a_distinct_bright_region_has_a_sun() {
        use crate::sky::procedural::{SkyKind, SkyParams, generate};
        let mut uniform = RgbImage::new(64, 32);
        uniform.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
        assert_eq!(find_sun(&uniform), None);
        assert_eq!(brightest_region(&uniform).contrast, 1.0);
        let sky = |kind| {
            let p = SkyParams {
                kind,
                sun_elevation_deg: 30.0,
                sun_azimuth_deg: 90.0,
                ..SkyParams::default()
            };
            generate(&p, 256).unwrap()
        };
        let overcast = sky(SkyKind::Overcast);
        let r = brightest_region(&overcast);
        assert!(r.contrast > 1.0 && r.contrast < SUN_CONTRAST, "{r:?}");
        assert_eq!(find_sun(&overcast), None);
        let (el, az) = find_sun(&sky(SkyKind::Clear)).expect("a clear sky has a sun");
        assert!(
            (el - 30.0).abs() < 2.0 && (az - 90.0).abs() < 2.0,
            "{el} {az}"
        );
        let mut turned = overcast.clone();
        assert_eq!(rotate_sun_to(&mut turned, 10.0), None);
        assert_eq!(turned.pixels, overcast.pixels);
    }
}
