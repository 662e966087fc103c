//! The built-in analytic skies: their radiance one ray at a time and in lanes, and their
//! irradiance.

use glam::Vec3;

use super::{AnalyticSky, SUN_RADIUS_RAD, map_irradiance};
use crate::equirect;
use crate::image_io::RgbImage;

/// The analytic sun's colour, scaled by its radiance.
pub(super) const SUN_COLOUR: Vec3 = Vec3::new(1.0, 0.93, 0.82);

impl AnalyticSky {
    /// Downwelling irradiance on a horizontal surface (see [`Sky::irradiance`]).
    pub fn irradiance(&self) -> Vec3 {
        let AnalyticSky::Clear {
            sun_elevation_deg,
            sun_azimuth_deg,
            sun_radiance,
            sky_scale,
        } = *self
        else {
            return map_irradiance(&rasterize(self, 1024));
        };
        let without_sun = AnalyticSky::Clear {
            sun_elevation_deg,
            sun_azimuth_deg,
            sun_radiance: 0.0,
            sky_scale,
        };
        // The disc: sin(elevation) over a 64 x 64 grid across it, points below the horizon
        // left out.
        let (el, az) = (sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians());
        let sun = equirect::direction(el, az);
        let (u, v) = (
            Vec3::new(-az.sin(), 0.0, az.cos()),
            equirect::direction(el + std::f32::consts::FRAC_PI_2, az),
        );
        const K: usize = 64;
        let mut cos_sum = 0.0f64;
        let mut inside = 0usize;
        for i in 0..K {
            for j in 0..K {
                let (a, b) = (
                    (2.0 * (i as f32 + 0.5) / K as f32 - 1.0),
                    (2.0 * (j as f32 + 0.5) / K as f32 - 1.0),
                );
                if a * a + b * b > 1.0 {
                    continue;
                }
                inside += 1;
                let d = (sun + SUN_RADIUS_RAD * (a * u + b * v)).normalize();
                cos_sum += d.y.max(0.0) as f64;
            }
        }
        let solid_angle = std::f64::consts::TAU * (1.0 - (SUN_RADIUS_RAD as f64).cos());
        let disc = (solid_angle * cos_sum / inside.max(1) as f64) as f32;
        map_irradiance(&rasterize(&without_sun, 1024))
            + Vec3::splat(sun_radiance) * SUN_COLOUR * disc
    }

    /// Direction towards the sun (+y up); `Vec3::Y` for the skies without one.
    pub fn sun_direction(&self) -> Vec3 {
        match *self {
            AnalyticSky::Clear {
                sun_elevation_deg,
                sun_azimuth_deg,
                ..
            } => equirect::direction(sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians()),
            _ => Vec3::Y,
        }
    }

    /// Radiance arriving from direction `d`.
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.radiance_with_sun(d, self.sun_direction())
    }

    /// [`Self::radiance`] with the sun's direction computed once ([`Self::sun_direction`]):
    /// its two sine-cosine pairs were a tenth of a clear sky's cost per ray.
    #[inline]
    pub fn radiance_with_sun(&self, d: Vec3, sun: Vec3) -> Vec3 {
        match *self {
            AnalyticSky::Uniform { radiance } => Vec3::from(radiance),
            AnalyticSky::Gradient { zenith, horizon } => {
                let s = d.y.clamp(0.0, 1.0);
                Vec3::from(horizon).lerp(Vec3::from(zenith), s)
            }
            AnalyticSky::Clear {
                sun_radiance,
                sky_scale,
                ..
            } => Vec3::from(clear_lane(
                d.to_array(),
                sun.to_array(),
                sun_radiance,
                sky_scale,
            )),
        }
    }
}

/// The clear sky's radiance along unit direction `d` with the sun towards `sun`: one lane of a
/// batch. [`AnalyticSky::radiance_with_sun`] and [`Sky::radiance_many`] both evaluate it, so a
/// direction gets the same bits alone as in a batch; it is branch-free, its acos and exp
/// inline, so a loop over lanes vectorises (libm's `acosf` and `expf` calls and the branch at
/// the sun's disc made the sky a quarter of the default render's trace, latency-bound).
#[inline(always)]
pub(super) fn clear_lane(
    d: [f32; 3],
    sun: [f32; 3],
    sun_radiance: f32,
    sky_scale: f32,
) -> [f32; 3] {
    const ZENITH: [f32; 3] = [0.25, 0.45, 0.95];
    const HORIZON: [f32; 3] = [0.95, 0.9, 0.85];
    const GLOW: [f32; 3] = [1.0, 0.75, 0.45];
    let cos_g = (d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]).clamp(-1.0, 1.0);
    let gamma = acos(cos_g);
    let up = d[1].max(0.0);
    let s = 1.0 - exp(-up * (1.0 / 0.12));
    // Forward-scattering glow around the sun, stronger for a low sun.
    // exp(-gamma / 0.12) is the fifth power of exp(-gamma / 0.6): one exp, not two.
    let e = exp(-gamma * (1.0 / 0.6));
    let e2 = e * e;
    // Light low in the sky drops towards the horizon below a low sun (reddened).
    let glow = (3.0 * (e2 * e2 * e) + 0.6 * e) * (1.0 - 0.7 * sun[1].max(0.0));
    let in_disc = gamma < SUN_RADIUS_RAD;
    std::array::from_fn(|k| {
        let sky = sky_scale * ((HORIZON[k] + (ZENITH[k] - HORIZON[k]) * s) + GLOW[k] * glow);
        if in_disc {
            sun_radiance * SUN_COLOUR.to_array()[k]
        } else {
            sky
        }
    })
}

/// acos(x) for x in [-1, 1], within 3e-7 rad of the true angle (an f32 ulp is 2.4e-7 near
/// pi), branch-free for [`clear_lane`]: Cephes' `acosf` (S. L. Moshier), pi/2 - asin(x) in the
/// middle, 2 asin(sqrt((1 - x) / 2)) towards 1 and pi minus that of -x towards -1, asin an odd
/// polynomial of degree 11 on [0, 1/2].
#[inline(always)]
pub(super) fn acos(x: f32) -> f32 {
    let a = x.abs();
    let outer = a > 0.5;
    let z_outer = 0.5 * (1.0 - a);
    let s = if outer { z_outer.sqrt() } else { x };
    let z = if outer { z_outer } else { x * x };
    let p = (((4.216_32e-2 * z + 2.418_131e-2) * z + 4.547_002_6e-2) * z + 7.495_300_3e-2) * z
        + 1.666_675_2e-1;
    let asin = p * z * s + s;
    if outer {
        // acos(x) = 2 asin(sqrt((1 - x) / 2)) for x > 1/2, pi minus that of -x below -1/2
        let t = 2.0 * asin;
        if x > 0.0 { t } else { std::f32::consts::PI - t }
    } else {
        std::f32::consts::FRAC_PI_2 - asin
    }
}

/// e^x for x in [-87, 0] (the clear sky's arguments; clamped to it), within 2 ulp: Cephes'
/// `expf` (S. L. Moshier), x = n ln 2 + r with |r| <= ln 2 / 2, a polynomial of degree 7 in r,
/// and 2^n from its exponent bits; branch-free for [`clear_lane`].
#[inline(always)]
pub(super) fn exp(x: f32) -> f32 {
    let x = x.clamp(-87.0, 0.0);
    // n = round(x / ln 2) by the 1.5 x 2^23 trick (no rounding instruction on baseline x86-64)
    const MAGIC: f32 = 12_582_912.0;
    let shifted = x * std::f32::consts::LOG2_E + MAGIC;
    let n = shifted - MAGIC;
    let ni = shifted.to_bits() as i32 - MAGIC.to_bits() as i32;
    let r = x - n * 0.693_359_4 - n * -2.121_944_4e-4;
    let p = ((((1.987_569_2e-4 * r + 1.398_2e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 0.5;
    let e = p * r * r + r + 1.0;
    e * f32::from_bits(((ni + 127) << 23) as u32)
}

/// Samples an analytic sky at the texel centres of a `width` x `width / 2` equirectangular map.
pub fn rasterize(sky: &AnalyticSky, width: usize) -> RgbImage {
    let mut img = RgbImage::new(width, width / 2);
    let (w, h) = (width as f32, img.height as f32);
    for y in 0..img.height {
        for x in 0..width {
            let d = equirect::pixel_direction(x as f32 + 0.5, y as f32 + 0.5, w, h);
            img.pixels[y * width + x] = sky.radiance(d).to_array();
        }
    }
    img
}
