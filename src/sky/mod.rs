//! Image-based sky light (the paper lights every scene only with 360-degree sky maps, section 5;
//! Debevec 1998). A sky is an equirectangular map (the convention of [`crate::equirect`]) or a
//! built-in analytic sky ([`AnalyticSky`]), looked up
//! either at infinity or on a spherical dome at a given altitude above the curved earth (the
//! paper used 200 km), where rays leaving from far-away ocean points see the map with the
//! parallax a real dome gives.

pub mod procedural;
pub mod tools;

use std::path::Path;

use glam::{DVec3, Vec3};

pub use crate::config::AnalyticSky;
use crate::equirect;
use crate::image_io::{ImageError, RgbImage, read_exr};

/// Angular radius of the analytic sky's sun, radians (0.53 degree diameter).
pub const SUN_RADIUS_RAD: f32 = 0.004_625;

impl AnalyticSky {
    /// Radiance arriving from direction `d`.
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match *self {
            AnalyticSky::Uniform { radiance } => Vec3::from(radiance),
            AnalyticSky::Gradient { zenith, horizon } => {
                let s = d.y.clamp(0.0, 1.0);
                Vec3::from(horizon).lerp(Vec3::from(zenith), s)
            }
            AnalyticSky::Clear {
                sun_elevation_deg,
                sun_azimuth_deg,
                sun_radiance,
                sky_scale,
            } => {
                let (el, az) = (sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians());
                let sun = equirect::direction(el, az);
                let cos_g = d.dot(sun).clamp(-1.0, 1.0);
                let gamma = cos_g.acos();
                if gamma < SUN_RADIUS_RAD {
                    return Vec3::splat(sun_radiance) * Vec3::new(1.0, 0.93, 0.82);
                }
                let up = d.y.max(0.0);
                let zenith = Vec3::new(0.25, 0.45, 0.95);
                let horizon = Vec3::new(0.95, 0.9, 0.85);
                let base = horizon.lerp(zenith, 1.0 - (-up / 0.12).exp());
                // Forward-scattering glow around the sun, stronger for a low sun.
                let glow = Vec3::new(1.0, 0.75, 0.45)
                    * (3.0 * (-gamma / 0.12).exp() + 0.6 * (-gamma / 0.6).exp());
                // Light low in the sky drops towards the horizon below a low sun (reddened).
                sky_scale * (base + glow * (1.0 - 0.7 * sun.y.max(0.0)))
            }
        }
    }
}

/// Where sky radiance comes from.
#[derive(Clone, Debug)]
pub enum SkySource {
    Analytic(AnalyticSky),
    Map(RgbImage),
}

/// The sky as the integrator sees it.
#[derive(Clone, Debug)]
pub struct Sky {
    pub source: SkySource,
    /// Altitude of the sky dome above sea level, m; `None` = at infinity.
    pub dome_altitude_m: Option<f64>,
    pub earth_radius_m: f64,
    pub camera_height_m: f64,
    /// Multiplies the map or analytic radiance.
    pub scale: f32,
}

impl Sky {
    pub fn analytic(sky: AnalyticSky) -> Sky {
        Sky {
            source: SkySource::Analytic(sky),
            dome_altitude_m: None,
            earth_radius_m: 6_371_000.0,
            camera_height_m: 2.0,
            scale: 1.0,
        }
    }

    /// Loads an equirectangular EXR (width = 2 x height, finite non-negative texels).
    pub fn load(path: &Path) -> Result<Sky, ImageError> {
        let img = read_exr(path)?;
        validate_map(path, &img)?;
        Ok(Sky {
            source: SkySource::Map(img),
            ..Sky::analytic(AnalyticSky::default())
        })
    }

    /// Radiance arriving along `-dir` at a ray that left `org` (camera-relative metres, y above
    /// the sea level at the camera's nadir) and hit nothing.
    pub fn radiance(&self, org: Vec3, dir: Vec3) -> Vec3 {
        let d = match self.dome_altitude_m {
            None => dir,
            Some(alt) => self.dome_direction(org, dir, alt),
        };
        self.scale
            * match &self.source {
                SkySource::Analytic(a) => a.radiance(d),
                SkySource::Map(img) => lookup(img, d),
            }
    }

    /// Downwelling irradiance on a horizontal surface: the radiance of the upper hemisphere
    /// weighted by the cosine to the zenith, per channel (the dome's parallax is ignored). Exact
    /// for a map (summed over its texels); an analytic sky is first sampled on a 1024 x 512 map.
    pub fn irradiance(&self) -> Vec3 {
        let raster;
        let img = match &self.source {
            SkySource::Map(m) => m,
            SkySource::Analytic(a) => {
                raster = rasterize(a, 1024);
                &raster
            }
        };
        self.scale * map_irradiance(img)
    }

    /// Direction from the camera to where the ray meets the dome: a sphere about the earth's
    /// centre `altitude` above the sea. f64, because the earth's radius leaves f32 a metre of
    /// precision.
    fn dome_direction(&self, org: Vec3, dir: Vec3, altitude: f64) -> Vec3 {
        let r = self.earth_radius_m;
        let centre = DVec3::new(0.0, -r, 0.0);
        let o = org.as_dvec3() - centre;
        let d = dir.as_dvec3();
        let big_r = r + altitude;
        // |o + t d|^2 = R^2 with |d| = 1: t = -b + sqrt(b^2 - c), the far root (we are inside).
        let b = o.dot(d);
        let c = o.length_squared() - big_r * big_r;
        let t = -b + (b * b - c).max(0.0).sqrt();
        let q = o + t * d;
        let cam = DVec3::new(0.0, self.camera_height_m + r, 0.0);
        (q - cam).normalize().as_vec3()
    }
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

/// Cosine-weighted integral of an equirectangular map over the upper hemisphere: each texel
/// contributes L sin(elevation) times its solid angle cos(elevation) dphi dtheta.
pub fn map_irradiance(img: &RgbImage) -> Vec3 {
    let (dphi, dtheta) = (
        std::f64::consts::TAU / img.width as f64,
        std::f64::consts::PI / img.height as f64,
    );
    let mut e = [0f64; 3];
    for y in 0..img.height / 2 {
        let el = std::f64::consts::FRAC_PI_2 - (y as f64 + 0.5) * dtheta;
        let w = el.sin() * el.cos() * dphi * dtheta;
        for x in 0..img.width {
            let p = img.get(x, y);
            for k in 0..3 {
                e[k] += p[k] as f64 * w;
            }
        }
    }
    Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32)
}

/// Checks that an image can serve as an equirectangular sky map.
pub fn validate_map(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    let invalid = |message: String| ImageError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    if img.width != 2 * img.height || img.height < 2 {
        return Err(invalid(format!(
            "a sky map must be equirectangular (width = 2 x height), got {} x {}",
            img.width, img.height
        )));
    }
    if let Some(i) = img
        .pixels
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
    {
        return Err(invalid(format!(
            "texel ({}, {}) is {:?}: sky radiance must be finite and >= 0",
            i % img.width,
            i / img.width,
            img.pixels[i]
        )));
    }
    Ok(())
}

/// Bilinear lookup of an equirectangular map, wrapping in azimuth and clamping at the poles.
pub fn lookup(img: &RgbImage, d: Vec3) -> Vec3 {
    let (w, h) = (img.width as f32, img.height as f32);
    // Continuous pixel coordinates; texel centres sit at +0.5.
    let (x, y) = equirect::direction_pixel(d, w, h);
    let x = x - 0.5;
    let y = (y - 0.5).clamp(0.0, h - 1.0);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let xi = |x: f32| (x as i64).rem_euclid(img.width as i64) as usize;
    let (xa, xb) = (xi(x0), xi(x0 + 1.0));
    let (ya, yb) = (y0 as usize, (y0 as usize + 1).min(img.height - 1));
    let p = |x, y| Vec3::from(img.get(x, y));
    (p(xa, ya) * (1.0 - fx) + p(xb, ya) * fx) * (1.0 - fy)
        + (p(xa, yb) * (1.0 - fx) + p(xb, yb) * fx) * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dome_direction_from_the_camera_is_the_ray_direction() {
        let mut sky = Sky::analytic(AnalyticSky::default());
        sky.dome_altitude_m = Some(200_000.0);
        let d = Vec3::new(0.6, 0.0, 0.8);
        let got = sky.dome_direction(Vec3::new(0.0, 2.0, 0.0), d, 200_000.0);
        assert!((got - d).length() < 1e-6);
        // From 5 km away, a horizontal ray meets the dome at a point the camera sees slightly
        // off the ray direction: parallax.
        let got = sky.dome_direction(Vec3::new(0.0, 0.0, 5000.0), Vec3::X, 200_000.0);
        assert!(got.z > 0.0 && (got - Vec3::X).length() < 0.01);
    }

    #[test]
    fn map_lookup_follows_the_camera_convention() {
        let mut img = RgbImage::new(8, 4);
        img.pixels[4] = [1.0, 0.0, 0.0]; // row 0 (top), column 4 (azimuth 180 degrees, +x is column 0)
        img.pixels[8 * 2 + 2] = [0.0, 1.0, 0.0]; // row 2 (just below the horizon), azimuth 90 = +z
        let up_back = Vec3::new(-0.3, 0.95, 0.0).normalize();
        let c = lookup(&img, up_back);
        assert!(c.x > 0.2, "{c}");
        let below_z = Vec3::new(0.0, -0.3, 1.0).normalize();
        assert!(lookup(&img, below_z).y > 0.3);
    }

    #[test]
    fn clear_sky_sun_disc_has_the_right_size() {
        let s = AnalyticSky::default();
        let AnalyticSky::Clear {
            sun_elevation_deg,
            sun_azimuth_deg,
            sun_radiance,
            ..
        } = s
        else {
            unreachable!()
        };
        let (el, az) = (sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians());
        // step away from the sun centre in elevation
        let at = |off: f32| {
            s.radiance(Vec3::new(
                (el + off).cos() * az.cos(),
                (el + off).sin(),
                (el + off).cos() * az.sin(),
            ))
            .x
        };
        assert!(at(0.0) >= 0.99 * sun_radiance);
        assert!(at(0.9 * SUN_RADIUS_RAD) >= 0.99 * sun_radiance);
        assert!(at(1.1 * SUN_RADIUS_RAD) < 0.01 * sun_radiance);
        // 0.53 degrees across: the disc ends at the same angle on the other side
        assert!(
            at(-0.9 * SUN_RADIUS_RAD) >= 0.99 * sun_radiance
                && at(-1.1 * SUN_RADIUS_RAD) < 0.01 * sun_radiance
        );
        assert!((2.0 * SUN_RADIUS_RAD.to_degrees() - 0.53).abs() < 0.001);
    }

    #[test]
    fn irradiance_of_a_uniform_sky_is_pi_times_its_radiance() {
        let sky = Sky::analytic(AnalyticSky::Uniform {
            radiance: [0.5, 1.0, 2.0],
        });
        let e = sky.irradiance();
        for (got, l) in e.to_array().into_iter().zip([0.5f32, 1.0, 2.0]) {
            assert!(
                (got / (std::f32::consts::PI * l) - 1.0).abs() < 1e-4,
                "{got}"
            );
        }
        // A sky bright only below the horizon gives no irradiance.
        let mut img = RgbImage::new(64, 32);
        for p in &mut img.pixels[16 * 64..] {
            *p = [1.0; 3];
        }
        assert_eq!(map_irradiance(&img), Vec3::ZERO);
    }

    #[test]
    fn bad_maps_are_rejected_with_the_reason() {
        let p = Path::new("sky.exr");
        assert!(
            validate_map(p, &RgbImage::new(10, 10))
                .unwrap_err()
                .to_string()
                .contains("equirectangular")
        );
        let mut img = RgbImage::new(8, 4);
        img.pixels[3] = [f32::NAN, 0.0, 0.0];
        assert!(
            validate_map(p, &img)
                .unwrap_err()
                .to_string()
                .contains("texel (3, 0)")
        );
    }
}
