//! Image-based sky light (the paper lights every scene only with 360-degree sky maps, section 5;
//! Debevec 1998). A sky is an equirectangular map (the convention of [`crate::equirect`]) or a
//! built-in analytic sky ([`AnalyticSky`]), looked up
//! either at infinity or on a spherical dome at a given altitude above the curved earth (the
//! paper used 200 km), where rays leaving from far-away ocean points see the map with the
//! parallax a real dome gives.

pub mod procedural;
pub mod tools;

use std::path::Path;

use glam::Vec3;

pub use crate::config::AnalyticSky;
use crate::equirect;
use crate::image_io::{ImageError, RgbImage, read_exr};

/// Angular radius of the analytic sky's sun, radians (0.53 degree diameter).
pub const SUN_RADIUS_RAD: f32 = 0.004_625;

/// The sun elevations every sky accepts, degrees: the analytic sky of a scene and the generated
/// ones alike. 90 is the zenith; down to -10 covers civil twilight (the disc below the horizon,
/// the sky still lit); lower is night, which none of the models describes.
pub const SUN_ELEVATION_RANGE_DEG: (f64, f64) = (-10.0, 90.0);

/// Checks a sun elevation against [`SUN_ELEVATION_RANGE_DEG`]; the error says the rule.
pub fn check_sun_elevation(deg: f64) -> Result<(), String> {
    let (lo, hi) = SUN_ELEVATION_RANGE_DEG;
    if (lo..=hi).contains(&deg) {
        Ok(())
    } else {
        Err(format!(
            "in [{lo}, {hi}] degrees (90 is the zenith; below {lo} is night, which no sky model here describes)"
        ))
    }
}
/// The analytic sun's colour, scaled by its radiance.
const SUN_COLOUR: Vec3 = Vec3::new(1.0, 0.93, 0.82);

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
fn clear_lane(d: [f32; 3], sun: [f32; 3], sun_radiance: f32, sky_scale: f32) -> [f32; 3] {
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
fn acos(x: f32) -> f32 {
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
fn exp(x: f32) -> f32 {
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

/// Rays [`Sky::radiance_many`] evaluates side by side.
pub const SKY_LANES: usize = 16;

/// Where sky radiance comes from.
#[derive(Clone, Debug)]
pub enum SkySource {
    Analytic {
        model: AnalyticSky,
        /// `model.sun_direction()`, computed once.
        sun: Vec3,
    },
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
            source: SkySource::Analytic {
                model: sky,
                sun: sky.sun_direction(),
            },
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
        self.scale
            * match &self.source {
                SkySource::Analytic { model, sun } => {
                    model.radiance_with_sun(self.unit_direction(org, dir), *sun)
                }
                SkySource::Map(img) => lookup(img, self.direction(org, dir)),
            }
    }

    /// [`Self::radiance`] of many rays, `out[i]` for `(orgs[i], dirs[i])`, bit for bit what
    /// each gets alone. A map and the analytic clear sky are evaluated [`SKY_LANES`] rays at a
    /// time, in loops the compiler vectorises: one ray's lookup is a chain of dependent square
    /// roots, divisions and polynomials (a map's two angles, the clear sky's angle to the sun
    /// and two exponentials); side by side they overlap.
    pub fn radiance_many(&self, orgs: &[Vec3], dirs: &[Vec3], out: &mut [Vec3]) {
        assert!(orgs.len() == dirs.len() && out.len() == dirs.len());
        // What the lanes evaluate; the other analytic skies are cheap one by one.
        enum Lanes<'a> {
            Map(&'a RgbImage),
            Clear([f32; 3], f32, f32),
        }
        let lanes = match &self.source {
            SkySource::Map(img) => Lanes::Map(img),
            SkySource::Analytic {
                model:
                    AnalyticSky::Clear {
                        sun_radiance,
                        sky_scale,
                        ..
                    },
                sun,
            } => Lanes::Clear(sun.to_array(), *sun_radiance, *sky_scale),
            SkySource::Analytic { .. } => {
                for ((o, d), l) in orgs.iter().zip(dirs).zip(out.iter_mut()) {
                    *l = self.radiance(*o, *d);
                }
                return;
            }
        };
        for ((o, d), out) in orgs
            .chunks(SKY_LANES)
            .zip(dirs.chunks(SKY_LANES))
            .zip(out.chunks_mut(SKY_LANES))
        {
            // The directions in lanes (the unused ones look at the zenith), then every lane's
            // sky: each step exactly what `radiance` does for one ray.
            let (mut x, mut y, mut z) = ([0f32; SKY_LANES], [1f32; SKY_LANES], [0f32; SKY_LANES]);
            let mut l = [[0f32; 3]; SKY_LANES];
            match lanes {
                Lanes::Map(img) => {
                    for (i, (o, d)) in o.iter().zip(d).enumerate() {
                        [x[i], y[i], z[i]] = self.direction(*o, *d).to_array();
                    }
                    let mut t = [Taps::default(); SKY_LANES];
                    for i in 0..SKY_LANES {
                        t[i] = taps([x[i], y[i], z[i]], img.width, img.height);
                    }
                    for (l, t) in l.iter_mut().zip(&t[..o.len()]) {
                        *l = read_taps(img, t);
                    }
                }
                Lanes::Clear(sun, sun_radiance, sky_scale) => {
                    for (i, (o, d)) in o.iter().zip(d).enumerate() {
                        [x[i], y[i], z[i]] = self.unit_direction(*o, *d).to_array();
                    }
                    for i in 0..SKY_LANES {
                        l[i] = clear_lane([x[i], y[i], z[i]], sun, sun_radiance, sky_scale);
                    }
                }
            }
            for (out, l) in out.iter_mut().zip(l) {
                *out = self.scale * Vec3::from(l);
            }
        }
    }

    /// Towards where the ray meets the sky, seen from the camera (see [`Self::direction`]):
    /// the dome's offset normalised, or the ray's own direction (unit already).
    #[inline]
    fn unit_direction(&self, org: Vec3, dir: Vec3) -> Vec3 {
        match self.dome_altitude_m {
            Some(alt) if !self.at_camera(org) => self.dome_offset(org, dir, alt).normalize(),
            _ => dir,
        }
    }

    /// Towards where the ray meets the sky, seen from the camera: along the ray at infinity and
    /// from the camera itself (which needs no intersection: half of every image looks at the
    /// sky), else towards where it meets the dome, not normalised (a map lookup does not need
    /// it, and its square root and division were on every escaped ray's critical path).
    #[inline]
    fn direction(&self, org: Vec3, dir: Vec3) -> Vec3 {
        match self.dome_altitude_m {
            Some(alt) if !self.at_camera(org) => self.dome_offset(org, dir, alt),
            _ => dir,
        }
    }

    /// Whether a ray leaves from the camera itself.
    #[inline]
    fn at_camera(&self, org: Vec3) -> bool {
        org == Vec3::new(0.0, self.camera_height_m as f32, 0.0)
    }

    /// Downwelling irradiance on a horizontal surface: the radiance of the upper hemisphere
    /// weighted by the cosine to the zenith, per channel (the dome's parallax is ignored). Exact
    /// for a map (summed over its texels). An analytic sky's smooth part is sampled on a
    /// 1024 x 512 map; its sun disc, 1.5 texels across there, is integrated on its own.
    pub fn irradiance(&self) -> Vec3 {
        self.scale
            * match &self.source {
                SkySource::Map(m) => map_irradiance(m),
                SkySource::Analytic { model, .. } => model.irradiance(),
            }
    }

    /// From the camera to where the ray meets the dome, a sphere about the earth's centre
    /// `altitude` above the sea (not normalised: [`Self::dome_direction`] is its direction).
    ///
    /// In f32, relative to the camera: with o = p + (0, rc, 0) (p the origin relative to the
    /// camera, rc the camera's distance from the earth's centre), b = o.d = p.d + rc d_y and
    /// c = |o|^2 - R'^2 = |p|^2 + 2 rc p_y + c0, where only c0 = rc^2 - R'^2 needs f64, and t
    /// comes from the root formula that does not cancel. The direction is within about 1e-7
    /// rad of the f64 intersection at the default 200 km, ~1e-6 rad for a dome 1 km up (test);
    /// the f64 formula this replaced was 8 % of the default render's trace.
    fn dome_offset(&self, org: Vec3, dir: Vec3, altitude: f64) -> Vec3 {
        let (r, h) = (self.earth_radius_m, self.camera_height_m);
        // the camera's distance from the earth's centre, and |camera - centre|^2 - R'^2
        let rc = (r + h) as f32;
        let c0 = ((h - altitude) * (2.0 * r + h + altitude)) as f32;
        let p = Vec3::new(org.x, org.y - h as f32, org.z);
        // |o + t d|^2 = R'^2 with o = p + (0, rc, 0) and |d| = 1: t^2 + 2 b t + c = 0
        let b = p.dot(dir) + rc * dir.y;
        let c = p.length_squared() + 2.0 * rc * p.y + c0;
        let s = (b * b - c).max(0.0).sqrt();
        // the far root (we are inside): -b + s, written without cancellation when b > 0
        let t = if b > 0.0 { -c / (b + s) } else { s - b };
        p + t * dir
    }

    /// Direction from the camera to where the ray meets the dome.
    #[cfg(test)]
    fn dome_direction(&self, org: Vec3, dir: Vec3, altitude: f64) -> Vec3 {
        self.dome_offset(org, dir, altitude).normalize()
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

/// Bilinear lookup of an equirectangular map along `d` (any non-zero length), wrapping in
/// azimuth and clamping at the poles.
pub fn lookup(img: &RgbImage, d: Vec3) -> Vec3 {
    Vec3::from(read_taps(img, &taps(d.to_array(), img.width, img.height)))
}

/// Where a bilinear lookup reads: columns `xa`, `xb` (wrapped), rows `ya`, `yb` (clamped) and
/// the weights of `xb` and `yb`.
#[derive(Clone, Copy, Default)]
struct Taps {
    xa: u32,
    xb: u32,
    ya: u32,
    yb: u32,
    fx: f32,
    fy: f32,
}

/// The taps of a `w` x `h` map along `d`: one lane of a batch ([`Sky::radiance_many`] runs it
/// over many directions in a loop the compiler vectorises; [`lookup`] runs it alone, so a
/// direction reads the same texels with the same weights either way). The floors are written
/// as truncations, which vectorise without SSE4.1 (a lane of NaN reads columns 0 and 1 of row
/// 0, weighted NaN).
#[inline(always)]
fn taps(d: [f32; 3], w: usize, h: usize) -> Taps {
    let (wf, hf) = (w as f32, h as f32);
    // Continuous pixel coordinates; texel centres sit at +0.5.
    let (x, y) = equirect::direction_pixel(Vec3::from(d), wf, hf);
    let x = x - 0.5;
    let y = (y - 0.5).clamp(0.0, hf - 1.0);
    // floor(x) for x in [-0.5, w - 0.5]; y >= 0 truncates to its floor
    let t = x as i32;
    let x0 = t - i32::from(x < t as f32);
    let y0 = y as i32;
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let (wi, hi) = (w as i32, h as i32);
    let xa = if x0 < 0 { x0 + wi } else { x0 };
    let xb = if x0 + 1 >= wi { x0 + 1 - wi } else { x0 + 1 };
    let clamp = |i: i32, n: i32| i.clamp(0, n - 1) as u32;
    Taps {
        xa: clamp(xa, wi),
        xb: clamp(xb, wi),
        ya: clamp(y0, hi),
        yb: clamp(y0 + 1, hi),
        fx,
        fy,
    }
}

/// The bilinear blend of a lookup's four texels.
#[inline(always)]
fn read_taps(img: &RgbImage, t: &Taps) -> [f32; 3] {
    let p = |x: u32, y: u32| img.get(x as usize, y as usize);
    let (a, b, c, d) = (p(t.xa, t.ya), p(t.xb, t.ya), p(t.xa, t.yb), p(t.xb, t.yb));
    let (fx, fy) = (t.fx, t.fy);
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn inline_acos_and_exp_agree_with_libm() {
        let (mut worst_acos, mut worst_exp) = (0f64, 0f64);
        let n = 200_000;
        for i in 0..=n {
            for x in [-1.0 + 2.0 * i as f32 / n as f32, 1.0 - i as f32 * 1e-7] {
                worst_acos = worst_acos.max((acos(x) as f64 - (x as f64).acos()).abs());
            }
            let x = -87.0 * i as f32 / n as f32;
            let want = (x as f64).exp();
            worst_exp = worst_exp.max((exp(x) as f64 - want).abs() / want);
        }
        assert!(worst_acos < 3e-7, "{worst_acos}");
        // 2 ulp: f32's epsilon is 1.19e-7
        assert!(worst_exp < 2.4e-7, "{worst_exp}");
        assert_eq!((acos(1.0), exp(0.0)), (0.0, 1.0));
        assert_eq!(acos(-1.0), std::f32::consts::PI);
        assert!((acos(0.0) - std::f32::consts::FRAC_PI_2).abs() < 1e-7);
        assert!(exp(-1000.0) > 0.0 && exp(-1000.0) < 1e-37);
    }

    #[test]
    fn sky_lookups_in_batches_equal_single_lookups() {
        let model = AnalyticSky::Clear {
            sun_elevation_deg: 3.0,
            sun_azimuth_deg: 40.0,
            sun_radiance: 5e4,
            sky_scale: 1.0,
        };
        let mut sky = Sky::analytic(model);
        sky.dome_altitude_m = Some(200_000.0);
        let sun = sky_sun(&sky);
        let mut rng = crate::rng::Rng::keyed(&[11]);
        let camera = Vec3::new(0.0, sky.camera_height_m as f32, 0.0);
        // From the camera and from far hits; some through the sun's disc.
        let rays: Vec<(Vec3, Vec3)> = (0..37)
            .map(|i| {
                let org = if i % 3 == 0 {
                    camera
                } else {
                    Vec3::new(
                        rng.range(-5e3, 5e3),
                        rng.range(-1.0, 1.0),
                        rng.range(-5e3, 5e3),
                    )
                };
                let d = if i % 4 == 0 {
                    sun + 1e-3 * Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0))
                } else {
                    Vec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(0.0, 1.0),
                        rng.range(-1.0, 1.0),
                    )
                };
                (org, d.normalize())
            })
            .collect();
        let (orgs, dirs): (Vec<Vec3>, Vec<Vec3>) = rays.iter().copied().unzip();
        // The same sky as a map: its lanes compute where to read instead.
        let mut map = sky.clone();
        map.source = SkySource::Map(rasterize(&model, 256));
        for sky in [sky, map] {
            let mut many = vec![Vec3::ZERO; rays.len()];
            sky.radiance_many(&orgs, &dirs, &mut many);
            let mut bright = 0;
            for ((o, d), l) in rays.iter().zip(&many) {
                let alone = sky.radiance(*o, *d);
                assert_eq!(
                    alone.to_array().map(f32::to_bits),
                    l.to_array().map(f32::to_bits)
                );
                bright += usize::from(alone.x > 1e2);
            }
            // (the analytic sun's disc is met; the map's texels are wider than it)
            let analytic = matches!(sky.source, SkySource::Analytic { .. });
            assert!(!analytic || (bright > 2 && bright < rays.len()), "{bright}");
            // The lanes see the dome: a far origin looks elsewhere than the camera does.
            let far = Vec3::new(0.0, 0.5, 150e3);
            let mut l = [Vec3::ZERO; 2];
            let up = Vec3::new(0.0, 0.05, 1.0).normalize();
            sky.radiance_many(&[camera, far], &[up, up], &mut l);
            assert_ne!(l[0], l[1]);
        }
    }

    fn sky_sun(sky: &Sky) -> Vec3 {
        match sky.source {
            SkySource::Analytic { sun, .. } => sun,
            SkySource::Map(_) => unreachable!(),
        }
    }

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
    fn dome_direction_in_f32_matches_the_f64_intersection() {
        let mut sky = Sky::analytic(AnalyticSky::default());
        // The sphere intersection in f64 about the earth's centre.
        let reference = |org: Vec3, dir: Vec3, alt: f64| {
            let r = sky.earth_radius_m;
            let o = org.as_dvec3() + DVec3::new(0.0, r, 0.0);
            let d = dir.as_dvec3();
            let (b, c) = (o.dot(d), o.length_squared() - (r + alt) * (r + alt));
            let q = o + (-b + (b * b - c).sqrt()) * d;
            (q - DVec3::new(0.0, sky.camera_height_m + r, 0.0)).normalize()
        };
        for (alt, bound) in [(200_000.0, 5e-7), (1_000.0, 5e-6)] {
            sky.dome_altitude_m = Some(alt);
            let mut rng = crate::rng::Rng::keyed(&[7]);
            let mut worst = 0f64;
            for _ in 0..20_000 {
                let mut u = || 2.0 * rng.f32() - 1.0;
                let org = Vec3::new(8000.0 * u(), 0.5 * u(), 8000.0 * u());
                // upwards, from grazing to the zenith, and a few downwards (they meet the dome
                // through the earth: still a well-defined far root)
                let dir = Vec3::new(u(), 0.3 * u() + 0.05, u()).normalize();
                let got = sky.dome_direction(org, dir, alt).as_dvec3();
                worst = worst.max(got.angle_between(reference(org, dir, alt)));
            }
            assert!(worst < bound, "{alt} m: {worst}");
        }
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
    fn map_lookup_wraps_at_the_seam() {
        // Column 0 is bright, the last column dark: along +x (azimuth 0, the seam) the lookup
        // sits halfway between them; a little either side it leans to its own side.
        let mut img = RgbImage::new(8, 4);
        for y in 0..4 {
            img.pixels[y * 8] = [1.0; 3];
        }
        let at = |az: f32| lookup(&img, Vec3::new(az.cos(), 0.0, az.sin())).x;
        assert!((at(0.0) - 0.5).abs() < 1e-6, "{}", at(0.0));
        let quarter_texel = std::f32::consts::TAU / 32.0;
        assert!(
            (at(quarter_texel) - 0.75).abs() < 1e-5,
            "{}",
            at(quarter_texel)
        );
        assert!(
            (at(-quarter_texel) - 0.25).abs() < 1e-5,
            "{}",
            at(-quarter_texel)
        );
        // Halfway round, far from the seam, nothing bright.
        assert_eq!(at(std::f32::consts::PI), 0.0);
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
    fn the_sun_disc_adds_its_exact_irradiance() {
        let sun = |el: f32| AnalyticSky::Clear {
            sun_elevation_deg: el,
            sun_azimuth_deg: 70.0,
            sun_radiance: 1000.0,
            sky_scale: 0.0,
        };
        // (1 - cos R) cancels badly in f32.
        let omega = (std::f64::consts::TAU * (1.0 - (SUN_RADIUS_RAD as f64).cos())) as f32;
        // Well up: L x solid angle x sin(elevation) (exact to second order in the radius).
        let e = sun(30.0).irradiance();
        let want = 1000.0 * SUN_COLOUR * omega * 0.5;
        assert!(
            ((e - want) / want).abs().max_element() < 1e-3,
            "{e} vs {want}"
        );
        // A sun 0.1 degrees up, its disc 0.265 degrees in radius: part of it is below the
        // horizon and adds nothing.
        let low = sun(0.1).irradiance().x;
        let full = 1000.0 * omega * 0.1f32.to_radians().sin();
        assert!(low > 0.0 && low < 1.5 * full, "{low} vs {full}");
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
