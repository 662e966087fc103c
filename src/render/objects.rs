//! Objects in the path tracer ([`crate::objects`]): their hits beside the ocean's, their
//! shading (Lambertian, or a GGX conductor, [`super::ggx`]: the sun sampled by next-event
//! estimation and weighed by the power heuristic against the BSDF's own bounce, which carries
//! its density so that the sun it finds itself gets the complementary weight), and shadow rays
//! that both the sea and the objects block.
//!
//! Every ray the integrator would answer without the ocean's BVH (the skip shortcuts: a ray
//! that cannot meet the sea) is still tested against the objects first, so a ship above the
//! highest wave or under the water is seen by rays the sea's shortcuts skip. Where the
//! objects' bounds are missed nothing is traced.

use glam::Vec3;

use super::counters::Counters;
use super::dielectric::RoughDielectric;
use super::ggx::{Frame, Ggx};
use super::integrator::{CAMERA_BATCH, SceneRef, TraceSettings};
use super::interface::{SurfacePoint, surface_point_on};
use super::microfacet::power_heuristic;
use crate::accel::{Hit, Ray};
use crate::config::Material;
use crate::ocean::slopes::{ALL_WAVES, LevelSet};
use crate::rng::Rng;
use std::f32::consts::FRAC_1_PI;

/// What an object hit does to a path.
#[derive(Clone, Copy)]
pub(super) struct ObjectScatter {
    pub(super) sp: SurfacePoint,
    /// The diffuse reflectance times the attenuation of the segment that reached the hit.
    pub(super) weight: Vec3,
    /// The water's attenuation of that segment alone (for the sun's direct light, which the
    /// hit reflects with its albedo already in it).
    pub(super) attenuation: Vec3,
    pub(super) width_m: f32,
    /// The bounce; `None` where a metal's or glass's sample left on the wrong side of the
    /// surface.
    pub(super) bounce: Option<Bounce>,
    /// The sun's sampled direct light: the shadow ray and the radiance it brings if clear.
    pub(super) sun: Option<(Ray, Vec3)>,
}

/// The ray an object hit sends on.
#[derive(Clone, Copy)]
pub(super) struct Bounce {
    pub(super) dir: Vec3,
    /// The density the sun it finds is weighed with (0: full weight).
    pub(super) sun_pdf: f32,
    /// The medium it travels in: the water, or inside a glass object (which the sea does not
    /// enter).
    pub(super) in_water: bool,
    pub(super) in_object: bool,
}

/// An object's surface at a hit.
enum Surface {
    Diffuse,
    Metal(Ggx),
    /// With whether a ray refracted out of it goes into the water.
    Glass(RoughDielectric, bool),
}

impl SceneRef<'_> {
    /// The object hits of `rays` into `hits` (all `None` without objects); rays whose `skip`
    /// is set, and rays that miss the objects' bounds, are not traced.
    pub(super) fn object_hits(
        &self,
        rays: &[Ray],
        skip: &[bool],
        hits: &mut [Option<Hit>],
        c: &mut Counters,
    ) {
        hits.iter_mut().for_each(|h| *h = None);
        let Some(objects) = self.objects else {
            return;
        };
        let mut traced = [Ray::new([0.0; 3], [0.0, 1.0, 0.0]); CAMERA_BATCH];
        let mut of = [0u8; CAMERA_BATCH];
        let mut n = 0;
        for (i, (ray, &skip)) in rays.iter().zip(skip).enumerate() {
            if !skip && ray.is_finite() && objects.may_hit(ray) {
                traced[n] = *ray;
                of[n] = i as u8;
                n += 1;
            }
        }
        if n == 0 {
            return;
        }
        c.object_rays += n as u64;
        let mut found = [None; CAMERA_BATCH];
        objects.intersect_many(&traced[..n], &mut found[..n]);
        for (&i, h) in of[..n].iter().zip(found) {
            hits[i as usize] = h;
        }
    }

    /// Shading at an object hit of `ray` (travelling in the water when `in_water`, inside glass
    /// when `in_object`, which an opaque object's bounce keeps): in the air
    /// the sun sampled (two numbers, drawn first), then the bounce: cosine-weighted for a
    /// diffuse object, by GGX's visible normals for a metal one (two numbers), and for glass
    /// reflected or refracted by the microfacet's Fresnel (three).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn scatter_object(
        &self,
        ray: &Ray,
        hit: &Hit,
        in_water: bool,
        in_object: bool,
        width_m: f32,
        settings: &TraceSettings,
        rng: &mut Rng,
        c: &mut Counters,
    ) -> ObjectScatter {
        let objects = self.objects.expect("object hits come from the objects");
        c.object_hits += 1;
        let sp = surface_point_on(
            objects.triangle(hit.prim),
            hit,
            objects.error_scale(hit.prim),
        );
        let d = Vec3::from(ray.dir);
        // the side the ray came from (both sides of an object's triangle are its surface; a
        // glass mesh is wound outward, so its ray comes from outside where it meets the
        // winding's normal, `sp.ng`, head on)
        // (edge-on, or NaN, counts as outside, as the side an opaque object was shaded on)
        let from_outside = d.dot(sp.ng).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater);
        let n = if from_outside { sp.ng } else { -sp.ng };
        let albedo = objects.albedo(hit.prim);
        let object = objects.object(hit.prim);
        let surface = match object.material {
            Material::Diffuse => Surface::Diffuse,
            Material::Metal => Surface::Metal(Ggx {
                alpha: object.roughness,
                f0: albedo,
            }),
            Material::Glass => {
                // the medium outside: the ray's own when it arrives from outside; where it
                // leaves, the water below the sea's surface and the air above it
                let exit_in_water = !from_outside && self.below_sea(sp.p);
                let outside = if (from_outside && in_water) || exit_in_water {
                    settings.water.ior
                } else {
                    1.0
                };
                let eta = if from_outside {
                    object.ior / outside
                } else {
                    outside / object.ior
                };
                Surface::Glass(
                    RoughDielectric {
                        alpha: object.roughness,
                        eta,
                    },
                    exit_in_water,
                )
            }
        };
        let frame = Frame::new(n);
        let wo = frame.to_local(-d);
        // the BSDF times the cosine, and the density the bounce gives direction w (on the
        // ray's side of the surface)
        let reflect = |w: Vec3| -> (Vec3, f32) {
            let wi = frame.to_local(w);
            match &surface {
                Surface::Diffuse => {
                    let cos = wi.z.max(0.0);
                    (albedo * cos * FRAC_1_PI, cos * FRAC_1_PI)
                }
                Surface::Metal(g) => (g.f(wo, wi) * wi.z.max(0.0), g.pdf(wo, wi)),
                Surface::Glass(b, _) => {
                    let (f, pdf) = b.eval(wo, wi);
                    (Vec3::splat(f * wi.z.max(0.0)), pdf)
                }
            }
        };
        let attenuation = if in_water {
            settings.water.transmittance(hit.t)
        } else {
            Vec3::ONE
        };
        let mut sun = None;
        // (from inside glass the sun is behind its surface; an opaque object's either side
        // may face it)
        let glass = matches!(surface, Surface::Glass(..));
        let sun_sampled = !in_water && (from_outside || !glass) && self.sun.is_some();
        if let (Some(light), true) = (&self.sun, sun_sampled) {
            let s = light.sample(sp.p, rng.f32(), rng.f32());
            if n.dot(s.d) > 0.0 && s.pdf > 0.0 {
                let (f_cos, bounce_pdf) = reflect(s.d);
                let w = power_heuristic(s.pdf, bounce_pdf);
                sun = Some((sp.spawn(s.d), f_cos * light.radiance(&s) * (w / s.pdf)));
            }
        }
        // the bounce's direction, the density the sun it finds is weighed with, its medium
        // (in the water, inside the object) and its weight
        let (bounce, weight) = match &surface {
            Surface::Diffuse => {
                let (w, cos) = cosine_direction(&frame, rng.f32(), rng.f32());
                (Some((w, cos * FRAC_1_PI, in_water, in_object)), albedo)
            }
            Surface::Metal(g) => match g.sample(wo, rng.f32(), rng.f32()) {
                Some((wi, weight)) => (
                    Some((frame.from_local(wi), g.pdf(wo, wi), in_water, in_object)),
                    weight,
                ),
                // it leaves below the surface: masked, its light lost
                None => (None, Vec3::ZERO),
            },
            Surface::Glass(b, exit_in_water) => {
                let (u1, u2, u3) = (rng.f32(), rng.f32(), rng.f32());
                match b.sample(wo, u1, u2, u3) {
                    // refracted: into the object, or out of it into the water or the air; the
                    // sun beyond is not sampled from here (full weight)
                    Some(s) if s.refracted => (
                        Some((frame.from_local(s.wi), 0.0, *exit_in_water, from_outside)),
                        albedo * s.weight,
                    ),
                    Some(s) => (
                        Some((frame.from_local(s.wi), s.pdf, in_water, !from_outside)),
                        Vec3::splat(s.weight),
                    ),
                    None => (None, Vec3::ZERO),
                }
            }
        };
        ObjectScatter {
            sp,
            weight: attenuation * weight,
            attenuation,
            width_m,
            // the sun the bounce finds is weighed against the sun's own samples
            bounce: bounce.map(|(w, pdf, water, object)| Bounce {
                dir: w,
                sun_pdf: if sun_sampled { pdf } else { 0.0 },
                in_water: water,
                in_object: object,
            }),
            sun,
        }
    }

    /// Whether scene point `p` lies below the sea's surface (its height where the displaced
    /// surface stands over p, lowered by the earth's curvature).
    fn below_sea(&self, p: Vec3) -> bool {
        let Some(sampler) = &self.ocean else {
            return p.y < 0.0;
        };
        let (x, z) = (p.x as f64, p.z as f64);
        let drop = (x * x + z * z) / (2.0 * self.earth_radius_m);
        (p.y as f64) < crate::objects::surface_height_at(sampler, p.x, p.z) - drop
    }

    /// The sun light sampled at up to [`CAMERA_BATCH`] hits, `suns[j]` = (shadow ray, light):
    /// the shadow rays traced together against the sea (those rising clear of its mesh are
    /// not), each meeting the surface `lods[j]` (its path's), and the objects, each blocked
    /// one dark.
    pub(super) fn sun_through(
        &self,
        suns: &[Option<(Ray, Vec3)>],
        lods: &[LevelSet],
        c: &mut Counters,
    ) -> [Vec3; CAMERA_BATCH] {
        let mut direct = [Vec3::ZERO; CAMERA_BATCH];
        let mut rays = [Ray::new([0.0; 3], [0.0, 1.0, 0.0]); CAMERA_BATCH];
        let mut ray_lods = [ALL_WAVES; CAMERA_BATCH];
        let mut of = [0u8; CAMERA_BATCH];
        let mut n = 0;
        let mut all = [Ray::new([0.0; 3], [0.0, 1.0, 0.0]); CAMERA_BATCH];
        let mut none = [true; CAMERA_BATCH];
        for (j, sun) in suns.iter().enumerate() {
            if let Some((ray, light)) = *sun {
                direct[j] = light;
                (all[j], none[j]) = (ray, false);
                let d = Vec3::from(ray.dir);
                // (an object's deck stands above the sea's highest vertex: a sun just below
                // the horizon must still be looked for through the sea)
                let clear = ray.is_finite()
                    && (self
                        .skip_above_y
                        .is_some_and(|top| ray.org[1] > top && d.y >= 0.0)
                        || self
                            .skip_slope
                            .is_some_and(|k| d.y > k * (d.x * d.x + d.z * d.z).sqrt()));
                if !clear {
                    rays[n] = ray;
                    ray_lods[n] = lods[j];
                    of[n] = j as u8;
                    n += 1;
                }
            }
        }
        if n > 0 {
            c.sun_rays += n as u64;
            let mut hits = [None; CAMERA_BATCH];
            // (a sun ray leaves its hit's surface, which is its path's)
            self.accel
                .intersect_many_at(&rays[..n], &ray_lods[..n], &mut hits[..n]);
            for (&j, h) in of[..n].iter().zip(&hits[..n]) {
                if h.is_some() {
                    c.sun_occluded += 1;
                    direct[j as usize] = Vec3::ZERO;
                    none[j as usize] = true;
                }
            }
        }
        let m = suns.len();
        if self.objects.is_some() && none[..m].contains(&false) {
            let mut hits = [None; CAMERA_BATCH];
            self.object_hits(&all[..m], &none[..m], &mut hits[..m], c);
            for (j, h) in hits[..m].iter().enumerate() {
                if h.is_some() {
                    c.sun_object_occluded += 1;
                    direct[j] = Vec3::ZERO;
                }
            }
        }
        direct
    }
}

/// A direction about `frame`'s normal with density cos / pi, from two uniform numbers, and its
/// cosine.
fn cosine_direction(frame: &Frame, u1: f32, u2: f32) -> (Vec3, f32) {
    let r = u1.sqrt();
    let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
    let cos = (1.0 - u1).max(0.0).sqrt();
    let local = Vec3::new(r * c, r * s, cos);
    (frame.from_local(local).normalize(), cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cosine-weighted directions: on n's side, with E[cos] = 2/3 and no mean sideways.
    #[test]
    fn cosine_directions_have_the_cosine_density() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        let mut rng = Rng::keyed(&[7]);
        let count = 200_000;
        let (mut sum_cos, mut side) = (0.0f64, Vec3::ZERO);
        for _ in 0..count {
            let (w, cos) = cosine_direction(&Frame::new(n), rng.f32(), rng.f32());
            assert!((w.dot(n) - cos).abs() < 1e-5 && cos >= 0.0);
            sum_cos += cos as f64;
            side += w - w.dot(n) * n;
        }
        let mean = sum_cos / count as f64;
        // std of cos under this density is sqrt(1/2 - 4/9) = 0.236
        assert!(
            (mean - 2.0 / 3.0).abs() < 5.0 * 0.236 / (count as f64).sqrt(),
            "{mean}"
        );
        assert!(side.length() / (count as f32) < 0.01, "{side}");
    }
}
