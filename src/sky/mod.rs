//! Image-based sky light (the paper lights every scene only with 360-degree sky maps, section 5;
//! Debevec 1998). A sky is an equirectangular map (the convention of [`crate::equirect`]) or a
//! built-in analytic sky ([`AnalyticSky`]), looked up
//! either at infinity or on a spherical dome at a given altitude above the curved earth (the
//! paper used 200 km), where rays leaving from far-away ocean points see the map with the
//! parallax a real dome gives.

mod analytic;
mod map;
mod map_sun;
pub mod procedural;
mod sampling;
pub mod tools;

use std::path::Path;

use glam::Vec3;

pub use crate::config::AnalyticSky;
use crate::image_io::{ImageError, RgbImage, read_exr};
pub use analytic::rasterize;
pub use analytic::{ClearLanes, Evaluator, HandMadeLanes};
use map::{Taps, read_taps, taps};
pub use map::{lookup, map_irradiance, validate_map};
pub use sampling::{SunLight, SunSample};

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

/// Whether `org` (camera-relative, the sky's convention) is the camera `h` metres up, which
/// sees the dome along its own directions.
#[inline]
pub(crate) fn at_camera(org: Vec3, h: f64) -> bool {
    org == Vec3::new(0.0, h as f32, 0.0)
}

/// `c` scaled down to luminance `limit` where it is brighter, hue kept (`c` unchanged, bit for
/// bit, below it or with an infinite limit).
#[inline(always)]
pub(crate) fn clip(c: [f32; 3], limit: f32) -> [f32; 3] {
    let l = crate::color::luminance(c);
    if l > limit {
        c.map(|v| v * (limit / l))
    } else {
        c
    }
}

/// The atmospheric turbidities the Preetham clear sky accepts: the range its coefficients were
/// fitted on (Preetham et al. 1999, about 2 to 10).
pub const TURBIDITY_RANGE: (f64, f64) = (1.7, 10.0);

/// Rays [`Sky::radiance_many`] evaluates side by side.
pub const SKY_LANES: usize = 16;

/// What [`Sky::radiance_many`] evaluates in lanes; the other analytic skies are cheap one by
/// one.
enum Lanes<'a> {
    Map(&'a RgbImage),
    Clear(&'a ClearLanes),
    HandMade(&'a HandMadeLanes),
}

/// Where sky radiance comes from.
#[derive(Clone, Debug)]
pub enum SkySource {
    Analytic {
        model: AnalyticSky,
        /// The model's constants, computed once.
        eval: Evaluator,
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
    /// An analytic sky's radiance is scaled down to this luminance where it is brighter (hue
    /// kept), as a photograph clips the sun ([`Sky::clip_relative`]); infinite = not clipped.
    /// A map is clipped in its texels instead.
    pub clip_luminance: f32,
}

impl Sky {
    pub fn analytic(sky: AnalyticSky) -> Sky {
        Sky {
            source: SkySource::Analytic {
                model: sky,
                eval: Evaluator::new(&sky),
            },
            dome_altitude_m: None,
            earth_radius_m: 6_371_000.0,
            camera_height_m: 2.0,
            scale: 1.0,
            clip_luminance: f32::INFINITY,
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
                SkySource::Analytic { eval, .. } => Vec3::from(clip(
                    eval.radiance(self.unit_direction(org, dir)).to_array(),
                    self.clip_luminance,
                )),
                SkySource::Map(img) => lookup(img, self.direction(org, dir)),
            }
    }

    /// [`Self::radiance`] of many rays, `out[i]` for `(orgs[i], dirs[i])`, bit for bit what
    /// each gets alone. A map and the analytic clear sky are evaluated up to [`SKY_LANES`] rays
    /// at a time, in loops the compiler vectorises: one ray's lookup is a chain of dependent square
    /// roots, divisions and polynomials (a map's two angles, the clear sky's angle to the sun
    /// and two exponentials); side by side they overlap.
    pub fn radiance_many(&self, orgs: &[Vec3], dirs: &[Vec3], out: &mut [Vec3]) {
        assert!(orgs.len() == dirs.len() && out.len() == dirs.len());
        let lanes = match &self.source {
            SkySource::Map(img) => Lanes::Map(img),
            SkySource::Analytic {
                eval: Evaluator::Clear(c),
                ..
            } => Lanes::Clear(c),
            SkySource::Analytic {
                eval: Evaluator::HandMade(h),
                ..
            } => Lanes::HandMade(h),
            SkySource::Analytic { .. } => {
                for ((o, d), l) in orgs.iter().zip(dirs).zip(out.iter_mut()) {
                    *l = self.radiance(*o, *d);
                }
                return;
            }
        };
        // Whole chunks of SKY_LANES rays, then the rest in the smallest chunk of 4, 8 or 16
        // that holds it: a batch's lookups hold four rays on average, and a chunk evaluates
        // every lane, used or not.
        let mut start = 0;
        while start < dirs.len() {
            let rest = dirs.len() - start;
            let len = rest.min(SKY_LANES);
            let (o, d) = (&orgs[start..start + len], &dirs[start..start + len]);
            let out = &mut out[start..start + len];
            match len {
                0..=4 => self.radiance_chunk::<4>(&lanes, o, d, out),
                5..=8 => self.radiance_chunk::<8>(&lanes, o, d, out),
                _ => self.radiance_chunk::<SKY_LANES>(&lanes, o, d, out),
            }
            start += len;
        }
    }

    /// [`Self::radiance_many`] for at most `L` rays, in `L` lanes (the unused ones look at the
    /// zenith), each step exactly what `radiance` does for one ray.
    #[inline(always)]
    fn radiance_chunk<const L: usize>(
        &self,
        lanes: &Lanes,
        o: &[Vec3],
        d: &[Vec3],
        out: &mut [Vec3],
    ) {
        let (mut x, mut y, mut z) = ([0f32; L], [1f32; L], [0f32; L]);
        let mut l = [[0f32; 3]; L];
        match *lanes {
            Lanes::Map(img) => {
                for (i, (o, d)) in o.iter().zip(d).enumerate() {
                    [x[i], y[i], z[i]] = self.direction(*o, *d).to_array();
                }
                let mut t = [Taps::default(); L];
                for i in 0..L {
                    t[i] = taps([x[i], y[i], z[i]], img.width, img.height);
                }
                for (l, t) in l.iter_mut().zip(&t[..o.len()]) {
                    *l = read_taps(img, t);
                }
            }
            Lanes::Clear(c) => {
                for (i, (o, d)) in o.iter().zip(d).enumerate() {
                    [x[i], y[i], z[i]] = self.unit_direction(*o, *d).to_array();
                }
                c.lanes(&x, &y, &z, &mut l);
                for l in &mut l {
                    *l = clip(*l, self.clip_luminance);
                }
            }
            Lanes::HandMade(h) => {
                for (i, (o, d)) in o.iter().zip(d).enumerate() {
                    [x[i], y[i], z[i]] = self.unit_direction(*o, *d).to_array();
                }
                for i in 0..L {
                    l[i] = clip(h.lane([x[i], y[i], z[i]]), self.clip_luminance);
                }
            }
        }
        for (out, l) in out.iter_mut().zip(l) {
            *out = self.scale * Vec3::from(l);
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
        at_camera(org, self.camera_height_m)
    }

    /// Downwelling irradiance on a horizontal surface: the radiance of the upper hemisphere
    /// weighted by the cosine to the zenith, per channel (the dome's parallax is ignored). Exact
    /// for a map (summed over its texels). An analytic sky's smooth part is sampled on a
    /// 1024 x 512 map; its sun disc, 1.5 texels across there, is integrated on its own.
    pub fn irradiance(&self) -> Vec3 {
        self.scale
            * match &self.source {
                SkySource::Map(m) => map_irradiance(m),
                SkySource::Analytic { eval, .. } => eval.irradiance(self.clip_luminance),
            }
    }

    /// Clips the sky as a photograph clips the sun: radiance brighter (in luminance) than
    /// `factor` times the median luminance above the horizon is scaled down to it, hue kept. A
    /// map's texels are clipped; an analytic sky's median is taken from a 1024 x 512 raster and
    /// its radiance clipped ray by ray. Returns the clip luminance.
    pub fn clip_relative(&mut self, factor: f32) -> f32 {
        match &mut self.source {
            SkySource::Map(img) => tools::clip_relative(img, factor).0,
            SkySource::Analytic { model, .. } => {
                let limit = factor * tools::median_luminance_above_horizon(&rasterize(model, 1024));
                self.clip_luminance = limit;
                limit
            }
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
        dome_offset(
            self.earth_radius_m,
            self.camera_height_m,
            altitude,
            org,
            dir,
        )
    }

    /// Direction from the camera to where the ray meets the dome.
    #[cfg(test)]
    fn dome_direction(&self, org: Vec3, dir: Vec3, altitude: f64) -> Vec3 {
        self.dome_offset(org, dir, altitude).normalize()
    }
}

/// [`Sky::dome_offset`] for an earth of radius `r`, a camera `h` above it and a dome at
/// `altitude`: where the ray from `org` along unit `dir` meets the dome, from the camera.
#[inline]
pub(crate) fn dome_offset(r: f64, h: f64, altitude: f64, org: Vec3, dir: Vec3) -> Vec3 {
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

#[cfg(test)]
mod tests;
