//! Procedural sky maps: the clear sky of Preetham, Shirley & Smits 1999 ("A Practical Analytic
//! Model for Daylight": the Perez et al. 1993 luminance distribution with turbidity-dependent
//! coefficients, their zenith luminance and chromaticity fits, xyY -> linear sRGB, and the sun's
//! transmittance of their appendix), the CIE standard overcast sky (Moon & Spencer 1942:
//! L(theta) = Lz (1 + 2 cos theta) / 3), and a partly cloudy sky (the clear sky under a seeded
//! fBm cloud layer at a fixed altitude, lit by the sun), rendered into equirectangular maps in
//! the convention of [`crate::equirect`] (y up, horizon at the middle row, azimuth 0 = +x at the
//! left edge, 90 degrees = +z).
//!
//! Units: one map unit is 1e5 cd/m^2 (100 kcd/m^2), luminance-weighted linear sRGB. Preetham's
//! zenith fit is in kcd/m^2; the sun is 1.96e9 cd/m^2 outside the atmosphere (133 klx over its
//! 6.8e-5 sr) times the model's transmittance. That unit keeps the physical sun/sky ratio
//! (about 1e5) inside half-float range: the sun stays below 65504 and the darkest sky well above
//! half's smallest normal number, so shipped maps can be half-float EXR.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use thiserror::Error;

use super::tools::{Ground, remove_ground};
use crate::equirect::{column_azimuth, direction64 as direction, row_elevation};
use crate::image_io::RgbImage;

/// kcd/m^2 per map unit.
pub const KCD_PER_UNIT: f64 = 100.0;
/// Luminance of the sun's disc above the atmosphere, cd/m^2.
pub const SUN_LUMINANCE_EXTRATERRESTRIAL: f64 = 1.96e9;
/// Angular radius of the sun's disc (0.53 degrees across), radians.
pub const SUN_RADIUS: f64 = 0.53 / 2.0 * PI / 180.0;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyKind {
    /// Preetham clear sky with the sun.
    Clear,
    /// CIE standard overcast sky (no sun).
    Overcast,
    /// The clear sky under a seeded cloud layer.
    PartlyCloudy,
}

crate::config::choice!(SkyKind { Clear => "clear", Overcast => "overcast", PartlyCloudy => "partly-cloudy" });

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SkyParams {
    pub kind: SkyKind,
    pub sun_elevation_deg: f64,
    pub sun_azimuth_deg: f64,
    /// Atmospheric turbidity (Preetham: 2 very clear ... 6 hazy).
    pub turbidity: f64,
    /// Fraction of the cloud layer covered (partly cloudy only).
    pub cloud_cover: f64,
    pub seed: u64,
}

impl Default for SkyParams {
    fn default() -> Self {
        SkyParams {
            kind: SkyKind::Clear,
            sun_elevation_deg: 20.0,
            sun_azimuth_deg: 180.0,
            turbidity: 2.5,
            cloud_cover: 0.4,
            seed: 1,
        }
    }
}

#[derive(Debug, Error)]
pub enum SkyGenError {
    #[error("{field}: {message}")]
    Invalid {
        field: &'static str,
        message: String,
    },
}

impl SkyParams {
    pub fn validate(&self) -> Result<(), SkyGenError> {
        let bad = |field, message: String| Err(SkyGenError::Invalid { field, message });
        if let Err(rule) = super::check_sun_elevation(self.sun_elevation_deg) {
            return bad(
                "sun elevation",
                format!("{} degrees; it must be {rule}", self.sun_elevation_deg),
            );
        }
        if !self.sun_azimuth_deg.is_finite() {
            return bad(
                "sun azimuth",
                format!("{} is not finite", self.sun_azimuth_deg),
            );
        }
        // Preetham et al. fitted their coefficients for turbidities of about 2 to 10.
        let (lo, hi) = super::TURBIDITY_RANGE;
        if !(lo..=hi).contains(&self.turbidity) {
            return bad(
                "turbidity",
                format!(
                    "{} is outside the model's range {lo}..={hi}",
                    self.turbidity
                ),
            );
        }
        if !(0.0..=1.0).contains(&self.cloud_cover) {
            return bad(
                "cloud cover",
                format!("{} is outside 0..=1", self.cloud_cover),
            );
        }
        Ok(())
    }
}

/// CIE XYZ -> linear sRGB (D65).
fn xyz_to_rgb(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(
        3.2406 * x - 1.5372 * y - 0.4986 * z,
        -0.9689 * x + 1.8758 * y + 0.0415 * z,
        0.0557 * x - 0.2040 * y + 1.0570 * z,
    )
    .max(DVec3::ZERO)
}

/// Perez et al. 1993: F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma).
fn perez(c: &[f64; 5], cos_theta: f64, gamma: f64, cos_gamma: f64) -> f64 {
    // At and below the horizon B / cos theta -> -inf, so the first factor tends to 1.
    (1.0 + c[0] * (c[1] / cos_theta.max(1e-4)).exp())
        * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * cos_gamma * cos_gamma)
}

/// The Preetham clear sky for one sun position and turbidity.
#[derive(Clone, Debug)]
pub struct Preetham {
    sun: DVec3,
    /// Perez coefficients for Y, x, y.
    coeffs: [[f64; 5]; 3],
    /// Zenith Y (kcd/m^2), x, y, each divided by F(0, theta_s).
    scaled_zenith: [f64; 3],
    sun_rgb: DVec3,
}

impl Preetham {
    pub fn new(sun_elevation_deg: f64, sun_azimuth_deg: f64, turbidity: f64) -> Preetham {
        let t = turbidity;
        let sun = direction(sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians());
        let theta_s = FRAC_PI_2 - sun_elevation_deg.to_radians();
        let coeffs = [
            [
                0.1787 * t - 1.4630,
                -0.3554 * t + 0.4275,
                -0.0227 * t + 5.3251,
                0.1206 * t - 2.5771,
                -0.0670 * t + 0.3703,
            ],
            [
                -0.0193 * t - 0.2592,
                -0.0665 * t + 0.0008,
                -0.0004 * t + 0.2125,
                -0.0641 * t - 0.8989,
                -0.0033 * t + 0.0452,
            ],
            [
                -0.0167 * t - 0.2608,
                -0.0950 * t + 0.0092,
                -0.0079 * t + 0.2102,
                -0.0441 * t - 1.6537,
                -0.0109 * t + 0.0529,
            ],
        ];
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let yz = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
        let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
        let tt = [t * t, t, 1.0];
        let fit = |m: [[f64; 4]; 3]| -> f64 {
            (0..3)
                .map(|r| tt[r] * (0..4).map(|c| m[r][c] * th[c]).sum::<f64>())
                .sum()
        };
        let xz = fit([
            [0.00166, -0.00375, 0.00209, 0.0],
            [-0.02903, 0.06377, -0.03202, 0.00394],
            [0.11693, -0.21196, 0.06052, 0.25886],
        ]);
        let yz_chroma = fit([
            [0.00275, -0.00610, 0.00317, 0.0],
            [-0.04214, 0.08970, -0.04153, 0.00516],
            [0.15346, -0.26756, 0.06670, 0.26688],
        ]);
        let zen = [yz, xz, yz_chroma];
        let scaled_zenith =
            std::array::from_fn(|k| zen[k] / perez(&coeffs[k], 1.0, theta_s, theta_s.cos()));
        Preetham {
            sun,
            coeffs,
            scaled_zenith,
            sun_rgb: sun_radiance(theta_s, turbidity),
        }
    }

    pub fn sun(&self) -> DVec3 {
        self.sun
    }

    /// Perez et al.'s coefficients A..E for luminance Y and chromaticities x and y.
    pub fn perez_coefficients(&self) -> [[f64; 5]; 3] {
        self.coeffs
    }

    /// Zenith luminance Y (kcd/m^2) and chromaticities x and y, each divided by the Perez
    /// function at the zenith.
    pub fn scaled_zenith(&self) -> [f64; 3] {
        self.scaled_zenith
    }

    /// Linear sRGB of the sun's disc, map units.
    pub fn sun_rgb(&self) -> DVec3 {
        self.sun_rgb
    }

    /// Sky radiance without the sun's disc along `d` (upper hemisphere; the horizon's value
    /// below it), map units.
    pub fn sky(&self, d: DVec3) -> DVec3 {
        let cos_g = d.dot(self.sun).clamp(-1.0, 1.0);
        let gamma = cos_g.acos();
        let [y, x, yc] = std::array::from_fn(|k| {
            self.scaled_zenith[k] * perez(&self.coeffs[k], d.y, gamma, cos_g)
        });
        let y = y.max(0.0) / KCD_PER_UNIT;
        xyz_to_rgb(x / yc * y, y, (1.0 - x - yc) / yc * y)
    }
}

/// Sun radiance after the atmosphere (Preetham appendix: Rayleigh and Angstrom aerosol
/// transmittance with Kasten's relative air mass; ozone and water vapour bands left out) at
/// three wavelengths standing for sRGB's R, G and B, scaled so that the unattenuated sun has the
/// extraterrestrial luminance.
/// A sun below the horizon (Kasten's air mass has no value past 93.9 degrees from the zenith)
/// sends no direct light.
fn sun_radiance(theta_s: f64, turbidity: f64) -> DVec3 {
    let deg = theta_s.to_degrees();
    if deg >= 90.0 {
        return DVec3::ZERO;
    }
    let m = 1.0 / (theta_s.cos() + 0.15 * (93.885 - deg).powf(-1.253));
    let beta = 0.04608 * turbidity - 0.04586;
    let tau = |lambda_um: f64| {
        (-m * (0.008735 * lambda_um.powf(-4.08) + beta * lambda_um.powf(-1.3))).exp()
    };
    DVec3::new(tau(0.610), tau(0.550), tau(0.465))
        * (SUN_LUMINANCE_EXTRATERRESTRIAL / 1e3 / KCD_PER_UNIT)
}

/// CIE overcast zenith luminance in map units: horizontal illuminance 300 + 21000 sin(h) lx
/// (Krochmann's fit adopted by the CIE) over the overcast sky's 7 pi / 9. With the sun below
/// the horizon the fit goes negative; twilight illuminance falls about a decade per 3 degrees
/// (3 lx at -6 degrees, the end of civil twilight), so it continues as 300 x 10^(h / 3) lx.
pub fn overcast_zenith(sun_elevation_deg: f64) -> f64 {
    let e_h = if sun_elevation_deg >= 0.0 {
        300.0 + 21_000.0 * sun_elevation_deg.to_radians().sin()
    } else {
        300.0 * 10f64.powf(sun_elevation_deg / 3.0)
    };
    9.0 * e_h / (7.0 * PI) / 1e3 / KCD_PER_UNIT
}

/// Value noise on an integer lattice, hashed from the seed: smooth and seamless everywhere.
fn lattice(seed: u64, x: i64, y: i64) -> f64 {
    let mut h = seed ^ 0x9e37_79b9_7f4a_7c15;
    for v in [x as u64, y as u64] {
        h = (h ^ v).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 31;
    }
    h = h.wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 29;
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn value_noise(seed: u64, p: DVec2) -> f64 {
    let f = p.floor();
    let t = p - f;
    // Quintic fade: continuous slope, so no lattice creases in the clouds.
    let s = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (x, y) = (f.x as i64, f.y as i64);
    let a = lattice(seed, x, y);
    let b = lattice(seed, x + 1, y);
    let c = lattice(seed, x, y + 1);
    let d = lattice(seed, x + 1, y + 1);
    let ab = a + (b - a) * s.x;
    let cd = c + (d - c) * s.x;
    ab + (cd - ab) * s.y
}

/// Fractal Brownian motion of value noise, in [0, 1].
fn fbm(seed: u64, p: DVec2) -> f64 {
    let (mut sum, mut amp, mut norm, mut q) = (0.0, 0.5, 0.0, p);
    // Rotating each octave keeps the lattice axes from lining up into visible streaks.
    let rot = DVec2::new(0.8, 0.6);
    for o in 0..6u64 {
        sum += amp * value_noise(seed.wrapping_add(o * 7919), q);
        norm += amp;
        amp *= 0.5;
        q = rot.rotate(q) * 2.03 + DVec2::splat(17.0);
    }
    sum / norm
}

/// A cloud layer at a fixed altitude above a curved earth.
#[derive(Clone, Debug)]
struct Clouds {
    seed: u64,
    threshold: f64,
    sun_h: DVec2,
}

const EARTH_RADIUS_M: f64 = 6.371e6;
const CLOUD_ALTITUDE_M: f64 = 2000.0;
const CLOUD_FEATURE_M: f64 = 3000.0;
/// Beyond this distance clouds fade into the sky's haze (aerial perspective).
const CLOUD_HAZE_M: f64 = 50_000.0;

impl Clouds {
    fn new(seed: u64, cover: f64, sun: DVec3) -> Clouds {
        // The threshold is the noise's (1 - cover) quantile, so `cover` is the covered fraction.
        let mut samples: Vec<f64> = (0..4096)
            .map(|i| {
                let p = DVec2::new(
                    lattice(seed ^ 0xc10d, i, 0) * 64.0,
                    lattice(seed ^ 0xc10d, i, 1) * 64.0,
                );
                fbm(seed, p)
            })
            .collect();
        samples.sort_by(f64::total_cmp);
        let threshold = if cover <= 0.0 {
            f64::INFINITY
        } else {
            samples[((1.0 - cover) * (samples.len() - 1) as f64).round() as usize]
        };
        let sun_h = DVec2::new(sun.x, sun.z).try_normalize().unwrap_or(DVec2::X);
        Clouds {
            seed,
            threshold,
            sun_h,
        }
    }

    fn density(&self, p: DVec2) -> f64 {
        ((fbm(self.seed, p / CLOUD_FEATURE_M) - self.threshold) / 0.12).clamp(0.0, 1.0)
    }

    /// Where `d` (d.y > 0) meets the layer, and how far away.
    fn hit(d: DVec3) -> (DVec2, f64) {
        let (r, h) = (EARTH_RADIUS_M, CLOUD_ALTITUDE_M);
        let b = r * d.y;
        let t = -b + (b * b + 2.0 * r * h + h * h).sqrt();
        (DVec2::new(d.x, d.z) * t, t)
    }
}

/// A sky model that can be evaluated in any direction.
#[derive(Clone, Debug)]
pub struct SkyModel {
    params: SkyParams,
    clear: Preetham,
    clouds: Option<Clouds>,
}

impl SkyModel {
    pub fn new(params: &SkyParams) -> Result<SkyModel, SkyGenError> {
        params.validate()?;
        let clear = Preetham::new(
            params.sun_elevation_deg,
            params.sun_azimuth_deg,
            params.turbidity,
        );
        let clouds = (params.kind == SkyKind::PartlyCloudy)
            .then(|| Clouds::new(params.seed, params.cloud_cover, clear.sun));
        Ok(SkyModel {
            params: *params,
            clear,
            clouds,
        })
    }

    pub fn sun(&self) -> DVec3 {
        self.clear.sun
    }

    /// Whether the map shows a sun disc.
    pub fn has_sun(&self) -> bool {
        self.params.kind != SkyKind::Overcast
    }

    /// Radiance along `d`, map units. Below the horizon the models say nothing; this gives the
    /// horizon's sky there (without the sun), and [`render_map`] replaces it with the same
    /// darkening fill that `sky import` uses.
    pub fn radiance(&self, d: DVec3) -> DVec3 {
        if d.y < 0.0 {
            let h = DVec3::new(d.x, 0.0, d.z)
                .try_normalize()
                .unwrap_or(DVec3::X);
            return self.above(h, false);
        }
        self.above(d, true)
    }

    fn above(&self, d: DVec3, with_sun: bool) -> DVec3 {
        if self.params.kind == SkyKind::Overcast {
            let lz = overcast_zenith(self.params.sun_elevation_deg);
            return DVec3::splat(lz * (1.0 + 2.0 * d.y.max(0.0)) / 3.0);
        }
        let mut sky = self.clear.sky(d);
        if with_sun && d.dot(self.clear.sun) >= SUN_RADIUS.cos() {
            sky = self.clear.sun_rgb;
        }
        match &self.clouds {
            Some(c) if d.y > 0.0 => {
                let (alpha, cloud) = self.cloud(c, d);
                sky * (1.0 - alpha) + cloud * alpha
            }
            _ => sky,
        }
    }

    /// Opacity and radiance of the cloud layer along `d`.
    fn cloud(&self, c: &Clouds, d: DVec3) -> (f64, DVec3) {
        let (p, dist) = Clouds::hit(d);
        let dens = c.density(p);
        if dens <= 0.0 {
            return (0.0, DVec3::ZERO);
        }
        // Cloud towards the sun shadows this point; the lit side is brighter.
        let shadow = c.density(p + c.sun_h * 350.0) + c.density(p + c.sun_h * 900.0);
        let lit = (-1.2 * shadow).exp();
        let sun = self.clear.sun;
        let e_sun = self.clear.sun_rgb * (PI * SUN_RADIUS * SUN_RADIUS);
        // Henyey-Greenstein forward scattering (g = 0.6), relative to isotropic: thin edges near
        // the sun glow (silver lining); thick cores only pass light diffused many times.
        let g = 0.6;
        let cos_t = d.dot(sun);
        let hg = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_t).powf(1.5);
        let thin = 1.0 - dens;
        let sun_term =
            e_sun / PI * lit * (0.9 * (-1.3 * dens).exp() + 0.5 * thin * (hg - 1.0).max(0.0));
        // Skylight from above, mostly blocked by the cloud's own bulk at its base.
        let ambient = self.clear.sky(DVec3::Y) * (0.5 + 0.5 * thin) * 1.5;
        let haze = (-dist / CLOUD_HAZE_M).exp();
        let alpha = dens.powf(0.7) * haze;
        (alpha, sun_term + ambient)
    }
}

/// Renders a model into an equirectangular map `width` texels wide (width = 2 x height).
/// Texels near the sun are supersampled so the disc keeps its solid angle (and energy) at any
/// resolution; cloudy skies are supersampled 2 x 2 everywhere against aliasing. Below the
/// horizon (which a raised camera sees a little of) the map continues the sky just above it,
/// smoothed in azimuth and darkening with depression ([`Ground::Fill`]): copying the horizon row
/// straight down would paint a bright column under a low sun's aureole.
pub fn render_map(model: &SkyModel, width: usize) -> RgbImage {
    let (w, h) = (width, width / 2);
    let base = if model.clouds.is_some() { 2 } else { 1 };
    let texel = TAU / w as f64;
    let near_sun = SUN_RADIUS + 2.0 * texel;
    let mut img = RgbImage::new(w, h);
    img.pixels[..w * (h / 2)]
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, px) in row.iter_mut().enumerate() {
                let centre = direction(row_elevation(j, h), column_azimuth(i, w));
                let n = if model.has_sun() && centre.angle_between(model.sun()) < near_sun {
                    16
                } else {
                    base
                };
                let mut sum = DVec3::ZERO;
                for a in 0..n {
                    for b in 0..n {
                        let u = (i as f64 + (a as f64 + 0.5) / n as f64) / w as f64;
                        let v = (j as f64 + (b as f64 + 0.5) / n as f64) / h as f64;
                        sum += model.radiance(direction(FRAC_PI_2 - v * PI, u * TAU));
                    }
                }
                *px = (sum / (n * n) as f64).as_vec3().to_array();
            }
        });
    remove_ground(&mut img, Ground::Fill);
    img
}

/// Validates `params` and renders the map.
pub fn generate(params: &SkyParams, width: usize) -> Result<RgbImage, SkyGenError> {
    if width < 4 || !width.is_multiple_of(2) {
        return Err(SkyGenError::Invalid {
            field: "width",
            message: format!("{width} must be even and at least 4 (the map is width x width/2)"),
        });
    }
    Ok(render_map(&SkyModel::new(params)?, width))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zenith_luminance_follows_the_preetham_fit() {
        // Preetham et al.'s zenith luminance fit at T = 2, sun 30 degrees up, by hand:
        // chi = (4/9 - 2/120)(pi - 2 * 60deg), Yz = (4.0453*2 - 4.971) tan(chi) - 0.431 + 2.4192.
        let chi: f64 = (4.0 / 9.0 - 2.0 / 120.0) * (PI - 2.0 * 60f64.to_radians());
        let expect = (4.0453 * 2.0 - 4.9710) * chi.tan() - 0.2155 * 2.0 + 2.4192;
        let p = Preetham::new(30.0, 0.0, 2.0);
        let zen = p.sky(DVec3::Y);
        let y = 0.2126 * zen.x + 0.7152 * zen.y + 0.0722 * zen.z;
        assert!(
            (y * KCD_PER_UNIT / expect - 1.0).abs() < 0.03,
            "{y} vs {expect}"
        );
        // A clear zenith is blue.
        assert!(zen.z > zen.x, "{zen}");
    }

    #[test]
    fn noise_is_seeded() {
        let p = DVec2::new(3.3, 7.1);
        assert_eq!(fbm(4, p), fbm(4, p));
        assert_ne!(fbm(4, p), fbm(5, p));
        assert!((0.0..=1.0).contains(&fbm(4, p)));
    }

    #[test]
    fn bad_parameters_are_named() {
        let p = SkyParams {
            turbidity: 0.5,
            ..Default::default()
        };
        assert!(p.validate().unwrap_err().to_string().contains("turbidity"));
        let p = SkyParams {
            sun_elevation_deg: 95.0,
            ..Default::default()
        };
        assert!(
            p.validate()
                .unwrap_err()
                .to_string()
                .contains("sun elevation")
        );
    }
}
