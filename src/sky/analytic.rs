//! The built-in analytic skies: their radiance one ray at a time and in lanes, and their
//! irradiance. An [`Evaluator`] holds a sky's per-sky constants (the sun's direction, the
//! Preetham model's coefficients), computed once; [`Sky`](super::Sky) evaluates rays with it.

use glam::Vec3;

use super::procedural::{KCD_PER_UNIT, Preetham};
use super::{AnalyticSky, SUN_RADIUS_RAD, map_irradiance};
use crate::equirect;
use crate::image_io::RgbImage;

/// The hand-made sky's sun colour, scaled by its radiance.
pub(super) const SUN_COLOUR: Vec3 = Vec3::new(1.0, 0.93, 0.82);

impl AnalyticSky {
    /// Direction towards the sun (+y up); `Vec3::Y` for the skies without one.
    pub fn sun_direction(&self) -> Vec3 {
        match *self {
            AnalyticSky::Clear {
                sun_elevation_deg,
                sun_azimuth_deg,
                ..
            }
            | AnalyticSky::HandMadeClear {
                sun_elevation_deg,
                sun_azimuth_deg,
                ..
            } => equirect::direction(sun_elevation_deg.to_radians(), sun_azimuth_deg.to_radians()),
            _ => Vec3::Y,
        }
    }

    /// Radiance arriving from direction `d` (unit length). Prepares the sky on every call: for
    /// many rays, make one [`Evaluator`].
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        Evaluator::new(self).radiance(d)
    }

    /// Downwelling irradiance on a horizontal surface (see [`Sky::irradiance`](super::Sky::irradiance)).
    pub fn irradiance(&self) -> Vec3 {
        Evaluator::new(self).irradiance(f32::INFINITY)
    }
}

/// An analytic sky ready to be evaluated: what depends only on the sky computed once.
#[derive(Clone, Copy, Debug)]
pub enum Evaluator {
    Uniform([f32; 3]),
    Gradient { zenith: [f32; 3], horizon: [f32; 3] },
    Clear(ClearLanes),
    HandMade(HandMadeLanes),
}

impl Evaluator {
    pub fn new(sky: &AnalyticSky) -> Evaluator {
        match *sky {
            AnalyticSky::Uniform { radiance } => Evaluator::Uniform(radiance),
            AnalyticSky::Gradient { zenith, horizon } => Evaluator::Gradient { zenith, horizon },
            AnalyticSky::Clear {
                sun_elevation_deg,
                sun_azimuth_deg,
                turbidity,
            } => Evaluator::Clear(ClearLanes::new(&Preetham::new(
                sun_elevation_deg as f64,
                sun_azimuth_deg as f64,
                turbidity as f64,
            ))),
            AnalyticSky::HandMadeClear {
                sun_radiance,
                sky_scale,
                ..
            } => Evaluator::HandMade(HandMadeLanes {
                sun: sky.sun_direction().to_array(),
                sun_radiance,
                sky_scale,
            }),
        }
    }

    /// Radiance arriving from unit direction `d`: the same bits as a lane of a batch.
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match self {
            Evaluator::Uniform(radiance) => Vec3::from(*radiance),
            Evaluator::Gradient { zenith, horizon } => {
                let s = d.y.clamp(0.0, 1.0);
                Vec3::from(*horizon).lerp(Vec3::from(*zenith), s)
            }
            Evaluator::Clear(c) => Vec3::from(c.lane(d.to_array())),
            Evaluator::HandMade(h) => Vec3::from(h.lane(d.to_array())),
        }
    }

    /// The sun's direction and its disc's radiance, for the skies with a sun.
    pub(super) fn disc(&self) -> Option<(Vec3, Vec3)> {
        match self {
            Evaluator::Clear(c) => Some((Vec3::from(c.sun), Vec3::from(c.sun_rgb))),
            Evaluator::HandMade(h) => Some((Vec3::from(h.sun), h.sun_radiance * SUN_COLOUR)),
            _ => None,
        }
    }

    /// The same sky without its sun's disc.
    pub(super) fn without_disc(&self) -> Evaluator {
        let mut e = *self;
        match &mut e {
            Evaluator::Clear(c) => c.sun_rgb = [0.0; 3],
            Evaluator::HandMade(h) => h.sun_radiance = 0.0,
            _ => {}
        }
        e
    }

    /// Downwelling irradiance on a horizontal surface of the sky clipped to luminance `clip`
    /// (see [`super::Sky::clip_luminance`]): the sky without the disc sampled on a 1024 x 512
    /// map (exact for the smooth part to the map's resolution), plus the disc, 1.5 texels
    /// across there, integrated on its own.
    pub fn irradiance(&self, clip: f32) -> Vec3 {
        let mut smooth = rasterize_with(&self.without_disc(), 1024);
        for p in &mut smooth.pixels {
            *p = super::clip(*p, clip);
        }
        let smooth = map_irradiance(&smooth);
        match self.disc() {
            Some((sun, rgb)) => {
                smooth
                    + Vec3::from(super::clip(rgb.to_array(), clip)) * disc_cosine_solid_angle(sun)
            }
            None => smooth,
        }
    }
}

/// The sun disc's solid angle weighted by the cosine to the zenith: sin(elevation) over a
/// 64 x 64 grid across it, points below the horizon left out.
fn disc_cosine_solid_angle(sun: Vec3) -> f32 {
    let u = Vec3::Y.cross(sun).try_normalize().unwrap_or(Vec3::X);
    let v = sun.cross(u);
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
    (solid_angle * cos_sum / inside.max(1) as f64) as f32
}

/// The Preetham clear sky's constants in f32, for [`ClearLanes::lane`].
#[derive(Clone, Copy, Debug)]
pub struct ClearLanes {
    sun: [f32; 3],
    /// Perez et al.'s coefficients A..E, each for luminance Y and chromaticities x and y.
    a: [f32; 3],
    b: [f32; 3],
    c: [f32; 3],
    d: [f32; 3],
    e: [f32; 3],
    /// Zenith luminance (map units), x and y, each over the Perez function at the zenith.
    zenith: [f32; 3],
    /// The sun disc's linear sRGB, map units.
    sun_rgb: [f32; 3],
}

impl ClearLanes {
    pub fn new(p: &Preetham) -> ClearLanes {
        let (coeffs, zenith) = (p.perez_coefficients(), p.scaled_zenith());
        let col = |i: usize| std::array::from_fn(|k| coeffs[k][i] as f32);
        let (b, d): ([f32; 3], [f32; 3]) = (col(1), col(3));
        // exp's arguments B / cos(theta) and D gamma stay <= 0 (its domain) for the model's
        // turbidities, 1.7..=10: B and D are negative there.
        debug_assert!(b.iter().chain(&d).all(|&v| v < 0.0), "{b:?} {d:?}");
        ClearLanes {
            sun: p.sun().as_vec3().to_array(),
            a: col(0),
            b,
            c: col(2),
            d,
            e: col(4),
            zenith: [
                (zenith[0] / KCD_PER_UNIT) as f32,
                zenith[1] as f32,
                zenith[2] as f32,
            ],
            sun_rgb: p.sun_rgb().as_vec3().to_array(),
        }
    }

    /// The radiance along unit direction `d`: [`Self::lanes`] for one ray.
    #[inline]
    pub(super) fn lane(&self, d: [f32; 3]) -> [f32; 3] {
        let mut out = [[0.0; 3]];
        self.lanes(&[d[0]], &[d[1]], &[d[2]], &mut out);
        out[0]
    }

    /// The radiance along N unit directions (x, y, z): what [`Preetham::sky`] gives in f64
    /// (within 1e-4 relative, test) and the sun's disc inside its radius; below the horizon the
    /// horizon's sky at that azimuth, as in the model `sky generate` renders. Branch-free and
    /// written stage by stage over the lanes, so each stage vectorises across rays (one ray's
    /// stages in a row vectorised across the three channels instead, at 5x the cost); a ray
    /// gets the same bits alone (N = 1) as in a batch.
    #[inline(always)]
    pub(super) fn lanes<const N: usize>(
        &self,
        x: &[f32; N],
        y: &[f32; N],
        z: &[f32; N],
        out: &mut [[f32; 3]; N],
    ) {
        let sun = self.sun;
        let (mut gamma, mut cos2, mut over_cos_theta) = ([0f32; N], [0f32; N], [0f32; N]);
        let mut in_disc = [false; N];
        for i in 0..N {
            let below = y[i] < 0.0;
            let across = 1.0 / (x[i] * x[i] + z[i] * z[i]).sqrt().max(1e-20);
            let s = if below { across } else { 1.0 };
            let (dx, dy, dz) = (x[i] * s, y[i].max(0.0), z[i] * s);
            let cos_g = (dx * sun[0] + dy * sun[1] + dz * sun[2]).clamp(-1.0, 1.0);
            gamma[i] = acos(cos_g);
            cos2[i] = cos_g * cos_g;
            over_cos_theta[i] = 1.0 / dy.max(1e-4);
            in_disc[i] = !below && gamma[i] < SUN_RADIUS_RAD;
        }
        // Perez: F = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma), times the
        // zenith's value over F at the zenith: luminance Y (map units) and chromaticities x, y.
        let mut f = [[0f32; N]; 3];
        for (k, f) in f.iter_mut().enumerate() {
            let (a, b, c, d, e, zen) = (
                self.a[k],
                self.b[k],
                self.c[k],
                self.d[k],
                self.e[k],
                self.zenith[k],
            );
            for i in 0..N {
                f[i] = zen
                    * ((1.0 + a * exp(b * over_cos_theta[i]))
                        * (1.0 + c * exp(d * gamma[i]) + e * cos2[i]));
            }
        }
        let sun_rgb = self.sun_rgb;
        for i in 0..N {
            let (lum, cx, cy) = (f[0][i].max(0.0), f[1][i], f[2][i]);
            // xyY -> XYZ -> linear sRGB (D65)
            let per_y = lum / cy;
            let (big_x, big_z) = (cx * per_y, (1.0 - cx - cy) * per_y);
            let r = 3.2406 * big_x - 1.5372 * lum - 0.4986 * big_z;
            let g = -0.9689 * big_x + 1.8758 * lum + 0.0415 * big_z;
            let b = 0.0557 * big_x - 0.2040 * lum + 1.0570 * big_z;
            out[i] = if in_disc[i] {
                sun_rgb
            } else {
                [r.max(0.0), g.max(0.0), b.max(0.0)]
            };
        }
    }
}

/// The hand-made clear sky's constants.
#[derive(Clone, Copy, Debug)]
pub struct HandMadeLanes {
    sun: [f32; 3],
    sun_radiance: f32,
    sky_scale: f32,
}

impl HandMadeLanes {
    /// The hand-made clear sky's radiance along unit direction `d`: one lane of a batch,
    /// branch-free, its acos and exp inline, so a loop over lanes vectorises (libm's `acosf` and
    /// `expf` calls and the branch at the sun's disc made the sky a quarter of the default
    /// render's trace, latency-bound).
    #[inline(always)]
    pub(super) fn lane(&self, d: [f32; 3]) -> [f32; 3] {
        const ZENITH: [f32; 3] = [0.25, 0.45, 0.95];
        const HORIZON: [f32; 3] = [0.95, 0.9, 0.85];
        const GLOW: [f32; 3] = [1.0, 0.75, 0.45];
        let (sun, sun_radiance, sky_scale) = (self.sun, self.sun_radiance, self.sky_scale);
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
}

/// acos(x) for x in [-1, 1], within 3e-7 rad of the true angle (an f32 ulp is 2.4e-7 near
/// pi), branch-free for the lanes: Cephes' `acosf` (S. L. Moshier), pi/2 - asin(x) in the
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
/// and 2^n from its exponent bits; branch-free for the lanes.
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
    rasterize_with(&Evaluator::new(sky), width)
}

/// [`rasterize`] with the sky prepared: rows in parallel, the Preetham sky 16 texels at a time
/// (the same bits as one at a time). Every render rasterizes its sky once for the irradiance.
fn rasterize_with(sky: &Evaluator, width: usize) -> RgbImage {
    use rayon::prelude::*;
    const LANES: usize = super::SKY_LANES;
    let mut img = RgbImage::new(width, width / 2);
    let (w, h) = (width as f32, img.height as f32);
    img.pixels
        .par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (chunk, out) in row.chunks_mut(LANES).enumerate() {
                let (mut dx, mut dy, mut dz) = ([0f32; LANES], [1f32; LANES], [0f32; LANES]);
                for (i, _) in out.iter().enumerate() {
                    let x = (chunk * LANES + i) as f32 + 0.5;
                    let d = equirect::pixel_direction(x, y as f32 + 0.5, w, h);
                    [dx[i], dy[i], dz[i]] = d.to_array();
                }
                match sky {
                    Evaluator::Clear(c) => {
                        let mut l = [[0f32; 3]; LANES];
                        c.lanes(&dx, &dy, &dz, &mut l);
                        out.copy_from_slice(&l[..out.len()]);
                    }
                    _ => {
                        for (i, p) in out.iter_mut().enumerate() {
                            *p = sky.radiance(Vec3::new(dx[i], dy[i], dz[i])).to_array();
                        }
                    }
                }
            }
        });
    img
}
