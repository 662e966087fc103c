//! The sun of a sky as a light to sample (next-event estimation at rough water hits, combined
//! with the BSDF's own samples by multiple importance sampling). The sky's radiance splits
//! exactly into a smooth sky plus the sun's part, which [`SunLight::seen`] gives and the cone
//! it is sampled over covers:
//! - an analytic sky: the sky minus the same sky without its disc (both clipped as the sky is,
//!   so a clipped sun stays clipped);
//! - a map: in a window of texels around its brightest, the luminance each has above a cap,
//!   sampled in proportion to its lookup (`map_sun.rs`).
//!
//! On a dome (the paper's 200 km) the sky is looked up where a ray meets the dome, seen from
//! the camera, so from a point of the sea kilometres away the disc sits a little elsewhere
//! (at a 3 degree sun the ray runs some 1,600 km to the dome: the parallax of a point 5 km out
//! is ~3 mrad, most of the disc's 4.6 mrad radius). The sun is then sampled where it is on the
//! dome: a direction in the disc as the camera sees it, the dome point along it, and the
//! direction from the shaded point to that dome point, whose density per steradian there is
//! the camera's times the ratio of the two solid angles the same patch of dome subtends
//! (cos / r^2 at each end).

use std::sync::Arc;

use glam::Vec3;

use super::analytic::Evaluator;
use super::map_sun::MapSun;
use super::{SUN_RADIUS_RAD, Sky, SkySource, at_camera, clip, dome_offset};

/// How far from the sun's centre a direction may see the sun through the dome's parallax,
/// beyond where the camera sees it: see [`SunLight::near`].
const PARALLAX_RAD: f32 = 0.095;

/// A direction towards the sun from [`SunLight::sample`].
#[derive(Clone, Copy, Debug)]
pub struct SunSample {
    /// The direction, from the point sampled for.
    pub d: Vec3,
    /// Its density per steradian there.
    pub pdf: f32,
    /// Where the camera sees the dome point it looks at (the sky's lookup direction).
    seen_as: Vec3,
    /// The sun's radiance there, when sampling needed it.
    known: Option<Vec3>,
}

impl SunSample {
    /// The sun's radiance along the sample where sampling needed it (a map's sun, whose
    /// density follows its radiance), `None` for the analytic disc, which is uniform but for
    /// the sky's smooth part beneath it.
    pub fn known_radiance(&self) -> Option<Vec3> {
        self.known
    }
}

/// The sun's part of the sky's radiance, and how it is sampled.
#[derive(Clone, Debug)]
enum Part {
    Analytic(Box<AnalyticSun>),
    /// A map's texels above its cap near its sun.
    Map(Arc<MapSun>),
}

/// An analytic sky's sun: the sky minus the same sky without its disc, both clipped at
/// `clip_luminance`, sampled uniformly over the cone about the disc's centre with axes `u`,
/// `v` across it.
#[derive(Clone, Debug)]
struct AnalyticSun {
    full: Evaluator,
    smooth: Evaluator,
    clip_luminance: f32,
    u: Vec3,
    v: Vec3,
    /// 1 - cos of the cone's half-angle.
    one_minus_cos: f32,
    /// sin^2 of a hair more than that angle: where the density is non-zero (tested with the
    /// cross product, exact near the axis where 1 - cos is not in f32).
    sin2_support: f32,
}

impl AnalyticSun {
    /// The cone's density per steradian.
    fn pdf(&self) -> f32 {
        1.0 / (std::f32::consts::TAU * self.one_minus_cos)
    }
}

/// The sun of a sky, to sample.
#[derive(Clone, Debug)]
pub struct SunLight {
    /// The sun's centre (a map's brightest texel) as the camera sees it.
    dir: Vec3,
    /// The cosine of the widest angle from `dir` at which a direction may see the sun.
    near_cos: f32,
    /// How far from `dir` the camera may see the sun: the disc's radius, or a map's window.
    reach_rad: f32,
    part: Part,
    scale: f32,
    /// Earth radius, camera height and dome altitude, m, when the sky is on a dome.
    dome: Option<(f64, f64, f64)>,
}

impl Sky {
    /// The sun to sample: an analytic sky's whose disc is (partly) above the horizon, or a
    /// map's (see the module doc); `None` for a sky without one. Rays that find the sun by
    /// themselves still see it: sampling only changes the noise.
    pub fn sun_light(&self) -> Option<SunLight> {
        let (dir, reach, part) = match &self.source {
            SkySource::Analytic { eval, .. } => {
                let (dir, _) = eval.disc()?;
                if dir.y < -SUN_RADIUS_RAD {
                    return None;
                }
                // A hair wider than the disc, so the evaluator's own disc test (its acos is
                // good to 3e-7 rad) never finds sun outside the sampled cone.
                let radius = SUN_RADIUS_RAD * 1.001;
                let u = Vec3::Y.cross(dir).try_normalize().unwrap_or(Vec3::X);
                let part = Part::Analytic(Box::new(AnalyticSun {
                    full: *eval,
                    smooth: eval.without_disc(),
                    clip_luminance: self.clip_luminance,
                    u,
                    v: dir.cross(u),
                    one_minus_cos: 2.0 * (0.5 * radius).sin().powi(2),
                    sin2_support: (radius * 1.0005).sin().powi(2),
                }));
                (dir, radius, part)
            }
            SkySource::Map(img) => {
                let sun = MapSun::new(img)?;
                (sun.peak, sun.reach_rad(), Part::Map(Arc::new(sun)))
            }
        };
        Some(SunLight {
            dir,
            near_cos: (reach + PARALLAX_RAD).min(std::f32::consts::PI).cos(),
            reach_rad: reach,
            part,
            scale: self.scale,
            dome: self
                .dome_altitude_m
                .map(|alt| (self.earth_radius_m, self.camera_height_m, alt)),
        })
    }
}

impl SunLight {
    /// The sun's centre as the camera sees it.
    pub fn direction(&self) -> Vec3 {
        self.dir
    }

    /// How far from [`Self::direction`] the camera may see the sun, radians: the disc's radius
    /// (a hair more), or a map's window.
    pub fn reach_rad(&self) -> f32 {
        self.reach_rad
    }

    /// The sun's centre seen from `org`: where the camera sees it, moved by the dome's
    /// parallax when the sky is on a dome.
    pub fn centre_from(&self, org: Vec3) -> Vec3 {
        match self.dome {
            Some((r, h, alt)) if !at_camera(org, h) => {
                let camera = Vec3::new(0.0, h as f32, 0.0);
                let q = dome_offset(r, h, alt, camera, self.dir);
                (q - Vec3::new(org.x, org.y - h as f32, org.z)).normalize()
            }
            _ => self.dir,
        }
    }

    /// A camera direction towards the sun from two uniform numbers.
    fn sample_camera(&self, u1: f32, u2: f32) -> Vec3 {
        match &self.part {
            Part::Analytic(a) => {
                // Uniform in solid angle over the cone.
                let k = u1 * a.one_minus_cos;
                let cos = 1.0 - k;
                let sin = (k * (2.0 - k)).max(0.0).sqrt();
                let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
                (cos * self.dir + sin * (c * a.u + s * a.v)).normalize()
            }
            Part::Map(sun) => sun.sample(u1, u2),
        }
    }

    /// The density of [`Self::sample_camera`] at camera direction `s`, per steradian, and the
    /// sun's part of the sky's radiance there (both zero where the sun has no part; for the
    /// analytic cone the support is wider than it by rounding's reach, where the disc has no
    /// radiance).
    fn camera_pdf_and_radiance(&self, s: Vec3) -> (f32, Vec3) {
        match &self.part {
            Part::Analytic(a) => {
                if !(s.dot(self.dir) > 0.0 && s.cross(self.dir).length_squared() <= a.sin2_support)
                {
                    return (0.0, Vec3::ZERO);
                }
                let full = clip(a.full.radiance(s).to_array(), a.clip_luminance);
                let smooth = clip(a.smooth.radiance(s).to_array(), a.clip_luminance);
                let radiance = (Vec3::from(full) - Vec3::from(smooth)).max(Vec3::ZERO);
                (a.pdf(), self.scale * radiance)
            }
            Part::Map(sun) => {
                let radiance = sun.radiance(s);
                (sun.pdf(s, radiance), self.scale * radiance)
            }
        }
    }

    /// For a ray from `org` along unit `d` meeting the dome at `q` (from the camera): the
    /// ratio of the ray's solid angle to the camera's for the same patch of dome.
    fn dome_jacobian(org: Vec3, d: Vec3, q: Vec3, r: f64, h: f64) -> f32 {
        let normal = (q + Vec3::new(0.0, (r + h) as f32, 0.0)).normalize();
        let from_org = q - Vec3::new(org.x, org.y - h as f32, org.z);
        let s = q.normalize();
        let (r_cam2, r_org2) = (q.length_squared(), from_org.length_squared());
        (s.dot(normal).abs() / r_cam2) * (r_org2 / d.dot(normal).abs().max(1e-12))
    }

    /// Whether direction `d` (from anywhere in the scene) may see the sun: within the sun's
    /// reach as the camera sees it (the disc, or a map's window) plus 0.095 rad of parallax,
    /// which holds points of the sea out to 100 km (the dome is over 1,000 km away along rays
    /// near the horizon for the paper's 200 km; lower domes make the reach shorter, not the
    /// bound wrong: only the ratio of distances matters). Directions farther off are
    /// answered without the dome's geometry; a direction that does see the sun must be near,
    /// or its multiple-importance weight would not be asked and the sun counted twice.
    #[inline]
    pub fn near(&self, d: Vec3) -> bool {
        d.dot(self.dir) > self.near_cos * d.length()
    }

    /// A direction from `org` towards the sun, from two uniform numbers: the direction, its
    /// density per steradian, and where the camera sees it (for [`Self::radiance`]).
    pub fn sample(&self, org: Vec3, u1: f32, u2: f32) -> SunSample {
        let s = self.sample_camera(u1, u2);
        // The analytic sun's density is the cone's wherever it lands and its radiance is asked
        // only where the sample is used (two evaluations of the sky); a map's density is its
        // radiance's.
        let (pdf, known) = match &self.part {
            Part::Analytic(a) => (a.pdf(), None),
            Part::Map(_) => {
                let (pdf, radiance) = self.camera_pdf_and_radiance(s);
                (pdf, Some(radiance))
            }
        };
        let (d, pdf) = match self.dome {
            Some((r, h, alt)) if !at_camera(org, h) => {
                let camera = Vec3::new(0.0, h as f32, 0.0);
                let q = dome_offset(r, h, alt, camera, s);
                let d = (q - Vec3::new(org.x, org.y - h as f32, org.z)).normalize();
                (d, pdf * Self::dome_jacobian(org, d, q, r, h))
            }
            _ => (s, pdf),
        };
        SunSample {
            d,
            pdf,
            seen_as: s,
            known,
        }
    }

    /// The sun's radiance along a sample.
    pub fn radiance(&self, sample: &SunSample) -> Vec3 {
        sample
            .known
            .unwrap_or_else(|| self.camera_pdf_and_radiance(sample.seen_as).1)
    }

    /// The density [`Self::sample`] gives direction `d` from `org`, and the sun's radiance
    /// along it (both zero where the ray does not see the sun).
    pub fn seen(&self, org: Vec3, d: Vec3) -> (f32, Vec3) {
        if !self.near(d) {
            return (0.0, Vec3::ZERO);
        }
        let (s, jacobian) = match self.dome {
            Some((r, h, alt)) if !at_camera(org, h) => {
                let q = dome_offset(r, h, alt, org, d);
                (q.normalize(), Self::dome_jacobian(org, d, q, r, h))
            }
            _ => (d, 1.0),
        };
        let (pdf, radiance) = self.camera_pdf_and_radiance(s);
        if pdf == 0.0 {
            return (0.0, Vec3::ZERO);
        }
        (pdf * jacobian, radiance)
    }
}

#[cfg(test)]
mod tests {
    use super::super::lookup;
    use super::*;
    use crate::color::luminance;
    use crate::config::AnalyticSky;
    use crate::rng::Rng;

    fn sky() -> Sky {
        Sky::analytic(AnalyticSky::Clear {
            sun_elevation_deg: 20.0,
            sun_azimuth_deg: 180.0,
            turbidity: 2.5,
        })
    }

    #[test]
    fn samples_stay_in_the_cone_and_its_pdf_integrates_the_disc() {
        // The disc's radiance integrated by sampling the cone is its radiance times its solid
        // angle (the disc is uniform), and every sample lands where the pdf is non-zero.
        // From the camera, and on a dome from a point of the sea 5 km out, where the density
        // [`SunLight::seen`] reports for the sampled direction is the sampler's own.
        for (dome, org) in [
            (None, Vec3::new(0.0, 2.0, 0.0)),
            (Some(200e3), Vec3::new(-4000.0, 0.3, 3000.0)),
        ] {
            let mut sky = sky();
            sky.dome_altitude_m = dome;
            let sun = sky.sun_light().unwrap();
            let mut rng = Rng::keyed(&[1]);
            let n = 20_000;
            let (mut sum, mut edge) = (Vec3::ZERO, 0);
            for _ in 0..n {
                let sample = sun.sample(org, rng.f32(), rng.f32());
                let (d, pdf, l) = (sample.d, sample.pdf, sun.radiance(&sample));
                let (seen_pdf, seen_l) = sun.seen(org, d);
                assert!(
                    pdf > 0.0 && (seen_pdf / pdf - 1.0).abs() < 1e-3,
                    "{pdf} {seen_pdf}"
                );
                // (Through the dome and back a direction moves by rounding: at the disc's
                // very edge it may fall on the other side.)
                edge += usize::from((seen_l - l).abs().max_element() > 1e-6 * l.max_element());
                sum += l / pdf;
            }
            assert!(
                edge < n / 200,
                "{edge} of {n} samples changed radiance on the way back"
            );
            let disc = sun.seen(Vec3::new(0.0, 2.0, 0.0), sun.direction()).1;
            let solid = std::f64::consts::TAU * (1.0 - (SUN_RADIUS_RAD as f64).cos());
            let got = sum / n as f32;
            // From the sea the dome's disc subtends the camera's solid angle over the ratio of
            // densities (2 % here: the sea point is nearer the sun's patch of dome).
            let centre_pdf = sun.sample(org, 0.0, 0.0).pdf;
            let cone_pdf = sun.seen(Vec3::new(0.0, 2.0, 0.0), sun.direction()).0;
            let expect = disc * (solid as f32 * cone_pdf / centre_pdf);
            assert!(
                ((got - expect) / expect).abs().max_element() < 0.02,
                "{got} vs {expect}"
            );
        }
    }

    #[test]
    fn the_sky_is_the_smooth_sky_plus_the_suns_part() {
        let sky = sky();
        let sun = sky.sun_light().unwrap();
        let SkySource::Analytic { eval, .. } = &sky.source else {
            unreachable!()
        };
        let smooth = eval.without_disc();
        for d in [
            sun.direction(),
            (sun.direction() + 0.003 * Vec3::Y).normalize(),
            (sun.direction() + 0.01 * Vec3::Y).normalize(),
            Vec3::Y,
        ] {
            let whole = sky.radiance(Vec3::new(0.0, sky.camera_height_m as f32, 0.0), d);
            let parts = smooth.radiance(d) + sun.seen(Vec3::new(0.0, 2.0, 0.0), d).1;
            assert!(
                (whole - parts).abs().max_element() <= 1e-6 * whole.max_element(),
                "{d}"
            );
        }
    }

    /// The clear sky of [`sky`] as a 2048-wide map, whose disc covers a few texels.
    fn map_sky() -> Sky {
        let SkySource::Analytic { model, .. } = sky().source else {
            unreachable!()
        };
        map_of(model)
    }

    /// `model` rasterized into a 2048-wide map.
    fn map_of(model: AnalyticSky) -> Sky {
        Sky {
            source: SkySource::Map(super::super::rasterize(&model, 2048)),
            ..sky()
        }
    }

    #[test]
    fn a_maps_sun_reaches_no_farther_than_near_says_for_a_low_and_a_high_sun() {
        // A glow 50 times the sky out to 0.2 rad round a small bright sun puts texels above
        // the cap far beyond the disc: the part stops at the window, within what `near` lets a
        // ray see (outside it a ray's MIS weight would not be asked, and the sun would be
        // counted twice), for a sun near the equator and one near the zenith, where the
        // window's columns are widest.
        for elevation in [20.0f64, 80.0] {
            let sun_dir = crate::equirect::direction64(elevation.to_radians(), 0.5);
            let (w, h) = (2048, 1024);
            let mut img = crate::image_io::RgbImage::new(w, h);
            for j in 0..h {
                for i in 0..w {
                    let d = crate::equirect::direction64(
                        crate::equirect::row_elevation(j, h),
                        crate::equirect::column_azimuth(i, w),
                    );
                    let g = d.angle_between(sun_dir);
                    let l = 1.0 + 50.0 * f32::from(g < 0.2) + 1e4 * f32::from(g < 0.005);
                    img.pixels[j * w + i] = [l; 3];
                }
            }
            let sky = Sky {
                source: SkySource::Map(img),
                ..sky()
            };
            let sun = sky.sun_light().unwrap();
            let u = Vec3::Y.cross(sun.direction()).normalize();
            let v = sun.direction().cross(u);
            let mut far = 0.0f32;
            for a in -100..=100 {
                for b in -100..=100 {
                    let d = (sun.direction() + 1.5e-3 * (a as f32 * u + b as f32 * v)).normalize();
                    if sun.camera_pdf_and_radiance(d).1.max_element() > 0.0 {
                        assert!(sun.near(d), "{elevation}: {d} has sun but is not near");
                        far = far.max(d.angle_between(sun.direction()));
                    }
                }
            }
            // The glow fills the window: the part reaches out to it, and no farther than it
            // and a lookup's reach.
            assert!(far > 0.045 && far < 0.056, "{elevation}: {far}");
        }
    }

    #[test]
    fn a_map_is_its_capped_self_plus_the_suns_part_where_samples_land() {
        let sky = map_sky();
        let sun = sky.sun_light().unwrap();
        let SkySource::Map(img) = &sky.source else {
            unreachable!()
        };
        // Every direction within 0.06 rad of the sun, on a grid finer than the texels: the
        // part is non-negative and under the lookup, the rest is at most a thousandth of the
        // peak (the cap here: the map's median is far below), and the density is the part's.
        let peak = img.pixels.iter().map(|&c| luminance(c)).fold(0.0, f32::max);
        let u = Vec3::Y.cross(sun.direction()).normalize();
        let v = sun.direction().cross(u);
        let (mut with_part, mut with_rest) = (0, 0);
        for a in -120..=120 {
            for b in -120..=120 {
                let d = (sun.direction() + 5e-4 * (a as f32 * u + b as f32 * v)).normalize();
                let whole = lookup(img, d);
                let (pdf, part) = sun.seen(Vec3::new(0.0, 2.0, 0.0), d);
                assert!(part.min_element() >= 0.0 && (whole - part).min_element() >= -1e-6);
                let rest = luminance((whole - part).to_array());
                assert!(rest <= 1e-3 * peak * 1.0001, "{d}: {rest} over the cap");
                assert_eq!(pdf > 0.0, part.max_element() > 0.0, "{d}");
                with_part += usize::from(part.max_element() > 0.0);
                with_rest += usize::from(rest > 0.5e-3 * peak);
            }
        }
        assert!(
            with_part > 100 && with_rest > 100,
            "{with_part} {with_rest}"
        );
        // Every sample lands where the sun has radiance, and carries radiance over density
        // within a few per cent of the mean (the map's texel size varies with elevation).
        let mut rng = Rng::keyed(&[3]);
        let org = Vec3::new(0.0, 2.0, 0.0);
        let ratios: Vec<f32> = (0..2000)
            .map(|_| {
                let s = sun.sample(org, rng.f32(), rng.f32());
                luminance(sun.radiance(&s).to_array()) / s.pdf
            })
            .collect();
        let mean = ratios.iter().sum::<f32>() / ratios.len() as f32;
        assert!(
            ratios.iter().all(|r| (r / mean - 1.0).abs() < 0.02),
            "{:?}",
            ratios
                .iter()
                .fold((f32::MAX, 0.0f32), |(a, b), &r| (a.min(r), b.max(r)))
        );
    }

    #[test]
    fn a_maps_sun_on_a_dome_is_seen_where_it_is_sampled() {
        // From a point of the sea 5 km out, under the paper's dome: every sample is near, and
        // the density `seen` reports for its direction is the sampler's own.
        let mut sky = map_sky();
        sky.dome_altitude_m = Some(200e3);
        let sun = sky.sun_light().unwrap();
        let org = Vec3::new(-4000.0, 0.3, 3000.0);
        let mut rng = Rng::keyed(&[4]);
        let mut off = 0;
        for _ in 0..5000 {
            let s = sun.sample(org, rng.f32(), rng.f32());
            assert!(sun.near(s.d), "{:?}", s.d);
            let (pdf, l) = sun.seen(org, s.d);
            off += usize::from((pdf / s.pdf - 1.0).abs() > 1e-2 || l == Vec3::ZERO);
        }
        // (Through the dome and back a direction moves by rounding, which the part's density
        // follows where it falls steeply at the sun's edge.)
        assert!(off < 50, "{off} of 5000 samples seen elsewhere");
    }

    #[test]
    fn a_maps_sun_sampled_integrates_its_part() {
        // Sampling the cone integrates the part as a quadrature over it does.
        let sky = map_sky();
        let sun = sky.sun_light().unwrap();
        let org = Vec3::new(0.0, 2.0, 0.0);
        let mut rng = Rng::keyed(&[2]);
        let n = 100_000;
        let mut sampled = Vec3::ZERO;
        for _ in 0..n {
            let s = sun.sample(org, rng.f32(), rng.f32());
            sampled += sun.radiance(&s) / s.pdf / n as f32;
        }
        let u = Vec3::Y.cross(sun.direction()).normalize();
        let v = sun.direction().cross(u);
        let (step, mut quadrature) = (2e-4f32, Vec3::ZERO);
        for a in -100..=100 {
            for b in -100..=100 {
                let d = sun.direction() + step * (a as f32 * u + b as f32 * v);
                // d is off the unit sphere by under 2e-4: its solid angle per cell is
                // step^2 / |d|^3.
                let l = d.length();
                quadrature += sun.seen(org, d / l).1 * step * step / (l * l * l);
            }
        }
        assert!(
            ((sampled - quadrature) / quadrature).abs().max_element() < 0.01,
            "{sampled} vs {quadrature}"
        );
    }

    #[test]
    fn maps_without_a_sun_have_none_to_sample() {
        let sky = Sky {
            source: SkySource::Map(super::super::rasterize(
                &AnalyticSky::Gradient {
                    zenith: [0.3, 0.5, 1.0],
                    horizon: [1.0, 1.0, 1.0],
                },
                256,
            )),
            ..sky()
        };
        assert!(sky.sun_light().is_none());
    }

    #[test]
    fn sunless_skies_have_no_sun_to_sample() {
        assert!(
            Sky::analytic(AnalyticSky::Uniform { radiance: [1.0; 3] })
                .sun_light()
                .is_none()
        );
    }
}
